//! `cargo run --release -p fires-sim --example sim -- --scenario NAME --seed N --duration SECONDS --out DIR
//! [--no-images] [--no-truth] [--object sphere|cylinder|box|blob]`: the same arguments the host CLI's
//! `fires sim` will take. Prints a summary and the wall time.

use fires_sim::objects::ObjectKind;
use fires_sim::{run_scenario, SimOptions, SCENARIOS};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

fn usage() -> String {
    let mut s = String::from(
        "usage: sim --scenario NAME --seed N --duration SECONDS --out DIR [--no-images] [--no-truth] [--object KIND]\nscenarios:\n",
    );
    for (name, desc) in SCENARIOS {
        s.push_str(&format!("  {name:10} {desc}\n"));
    }
    s
}

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let (mut name, mut seed, mut duration, mut out) = (None, 0u64, 10.0f64, None);
    let mut opts = SimOptions::default();
    while let Some(a) = args.next() {
        let mut val = || args.next().unwrap_or_default();
        match a.as_str() {
            "--scenario" => name = Some(val()),
            "--seed" => match val().parse() {
                Ok(v) => seed = v,
                Err(_) => return fail("--seed needs an unsigned integer"),
            },
            "--duration" => match val().parse() {
                Ok(v) => duration = v,
                Err(_) => return fail("--duration needs a number of seconds"),
            },
            "--out" => out = Some(PathBuf::from(val())),
            "--no-images" => opts.images = false,
            "--no-truth" => opts.truth = false,
            "--object" => match ObjectKind::parse(&val()) {
                Some(k) => opts.object = Some(k),
                None => return fail("--object must be sphere, cylinder, box or blob"),
            },
            _ => return fail(&usage()),
        }
    }
    let (Some(name), Some(out)) = (name, out) else {
        return fail(&usage());
    };
    let start = Instant::now();
    match run_scenario(&name, seed, duration, &out, opts) {
        Ok(s) => {
            println!("{s:#?}");
            println!("wall time: {:.3} s", start.elapsed().as_secs_f64());
            ExitCode::SUCCESS
        }
        Err(e) => fail(&format!("error: {e}")),
    }
}

fn fail(msg: &str) -> ExitCode {
    eprintln!("{msg}");
    ExitCode::FAILURE
}
