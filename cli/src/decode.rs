//! `fires decode [PATH|-]`: raw link bytes in, one JSON line per packet out, then a summary line.

use std::fs::File;
use std::io::{self, BufWriter, Read, Write};
use std::path::PathBuf;

use anyhow::Context;
use fires_host::link::{PacketLine, SummaryLine};
use fires_protocol::{Decoded, StreamDecoder};

/// Arguments of `fires decode`.
#[derive(Debug, clap::Args)]
pub struct DecodeArgs {
    /// File of raw bytes as received from the pen (a serial capture or a recording's link payload);
    /// `-` or nothing reads standard input.
    pub path: Option<PathBuf>,
}

/// Opens the input: a file, or standard input for `-` / no path.
fn open_input(path: &Option<PathBuf>) -> anyhow::Result<Box<dyn Read>> {
    match path {
        Some(p) if p.as_os_str() != "-" => {
            let f = File::open(p).with_context(|| format!("cannot open {}", p.display()))?;
            Ok(Box::new(f))
        }
        _ => Ok(Box::new(io::stdin().lock())),
    }
}

/// Decodes the input and prints the packets and the summary.
pub fn run(args: &DecodeArgs) -> anyhow::Result<()> {
    let mut input = open_input(&args.path)?;
    let mut out = BufWriter::new(io::stdout().lock());
    let mut decoder = StreamDecoder::new();
    let mut buf = vec![0u8; 1 << 16];
    let mut bytes = 0u64;
    let mut write_err = None;
    let mut print = |d: Decoded, out: &mut BufWriter<_>| {
        if write_err.is_none() {
            if let Err(e) = write_line(out, &PacketLine::from(&d)) {
                write_err = Some(e);
            }
        }
    };
    loop {
        let n = match input.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e).context("cannot read the input"),
        };
        bytes += n as u64;
        decoder.feed(&buf[..n], |d| print(d, &mut out));
    }
    if let Some(d) = decoder.finish() {
        print(d, &mut out);
    }
    if let Some(e) = write_err {
        return Err(e);
    }
    write_line(&mut out, &SummaryLine::new(bytes, decoder.stats()))?;
    out.flush().context("cannot write to standard output")
}

fn write_line(out: &mut impl Write, value: &impl serde::Serialize) -> anyhow::Result<()> {
    serde_json::to_writer(&mut *out, value)
        .map_err(io::Error::from)
        .and_then(|()| out.write_all(b"\n"))
        .context("cannot write to standard output")
}
