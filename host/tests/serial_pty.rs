//! The serial link over a real pseudo-terminal pair carrying pen bytes, including an unplug and a replug of the
//! device behind a stable path (as a udev symlink such as /dev/rfcomm0 behaves).
#![cfg(unix)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use fires_host::clock::HostClock;
use fires_host::link::{LinkEvent, SerialConfig, SerialLink};
use fires_protocol::{Command, CommandParser, SensorPacket, StreamDecoder};
use serialport::{SerialPort, TTYPort};

/// A fresh pty whose slave end is reachable at `link`; returns the master (the "pen" side).
fn plug(link: &Path) -> TTYPort {
    let (master, slave) = TTYPort::pair().expect("pty pair");
    let name = slave.name().expect("slave path");
    let _ = std::fs::remove_file(link);
    std::os::unix::fs::symlink(name, link).expect("symlink");
    master
}

fn packets(range: std::ops::Range<u32>) -> Vec<u8> {
    range
        .flat_map(|i| {
            SensorPacket {
                counter: i as u8,
                accel: [i as i16, 0, 1024],
                ..Default::default()
            }
            .encode()
        })
        .collect()
}

/// Polls until `want` bytes arrived or a deadline; returns the bytes and the events seen.
fn read_bytes(link: &mut SerialLink, want: usize) -> (Vec<u8>, Vec<LinkEvent>) {
    let mut got = Vec::new();
    let mut events = Vec::new();
    let mut buf = [0u8; 4096];
    let deadline = Instant::now() + Duration::from_secs(10);
    while got.len() < want && Instant::now() < deadline {
        match link.poll(&mut buf) {
            LinkEvent::Bytes { len, .. } => got.extend_from_slice(&buf[..len]),
            LinkEvent::Idle => {}
            other => events.push(other),
        }
    }
    (got, events)
}

fn wait_for(link: &mut SerialLink, pred: impl Fn(&LinkEvent) -> bool) -> Vec<LinkEvent> {
    let mut buf = [0u8; 4096];
    let mut seen = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(10);
    while Instant::now() < deadline {
        let e = link.poll(&mut buf);
        let done = pred(&e);
        seen.push(e);
        if done {
            return seen;
        }
    }
    panic!("event did not come; saw {seen:?}");
}

fn temp_link(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fires-pty-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join("rfcomm")
}

#[test]
fn bytes_cross_a_pty_and_survive_unplug_and_replug() {
    let path = temp_link("replug");
    let mut pen = plug(&path);
    let mut link = SerialLink::open(SerialConfig::pen(&path), HostClock::new()).expect("open");

    let first = packets(0..50);
    pen.write_all(&first).expect("pen writes");
    let (got, events) = read_bytes(&mut link, first.len());
    assert_eq!(got, first);
    assert!(events.is_empty(), "{events:?}");

    // Unplug: the pen side goes away.
    drop(pen);
    let seen = wait_for(&mut link, |e| matches!(e, LinkEvent::Disconnected { .. }));
    assert!(matches!(seen.last(), Some(LinkEvent::Disconnected { .. })));
    assert!(!link.is_connected());

    // Replug: a new device appears behind the same path.
    let mut pen = plug(&path);
    wait_for(&mut link, |e| matches!(e, LinkEvent::Reconnected { .. }));
    let second = packets(60..120);
    pen.write_all(&second).expect("pen writes again");
    let (got2, _) = read_bytes(&mut link, second.len());
    assert_eq!(got2, second);

    // Everything read decodes: 50 + 60 packets, 10 lost across the unplug.
    let mut decoder = StreamDecoder::new();
    let mut n = 0;
    decoder.feed(&got, |_| n += 1);
    decoder.feed(&got2, |_| n += 1);
    n += usize::from(decoder.finish().is_some());
    assert_eq!(n, 110);
    assert_eq!(decoder.stats().lost, 10);
    let _ = std::fs::remove_dir_all(path.parent().expect("dir"));
}

#[test]
fn commands_reach_the_pen_intact() {
    let path = temp_link("commands");
    let mut pen = plug(&path);
    pen.set_timeout(Duration::from_secs(2)).expect("timeout");
    let mut link = SerialLink::open(SerialConfig::pen(&path), HostClock::new()).expect("open");
    let sent = [
        Command::Start,
        Command::Vibrate { duration_ms: 250 },
        Command::IrLeds { on: true },
        Command::Stop,
    ];
    for c in sent {
        link.send(c).expect("send");
    }
    let mut parser = CommandParser::new();
    let mut got = Vec::new();
    let mut buf = [0u8; 64];
    let deadline = Instant::now() + Duration::from_secs(5);
    while got.len() < sent.len() && Instant::now() < deadline {
        if let Ok(n) = std::io::Read::read(&mut pen, &mut buf) {
            got.extend(buf[..n].iter().filter_map(|&b| parser.push(b)));
        }
    }
    assert_eq!(got, sent);
    let _ = std::fs::remove_dir_all(path.parent().expect("dir"));
}

#[test]
fn a_missing_device_is_a_clear_error() {
    let err = SerialLink::open(
        SerialConfig::pen("/dev/fires-no-such-pen"),
        HostClock::new(),
    )
    .err()
    .expect("no device");
    let msg = err.to_string();
    assert!(msg.contains("/dev/fires-no-such-pen"), "{msg}");
}
