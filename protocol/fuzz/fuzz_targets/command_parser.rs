//! Arbitrary bytes into the pen-side command parser: no panic, and every extended command it accepts re-encodes
//! to exactly the bytes that ended at that position.
#![no_main]

use fires_protocol::{Command, CommandParser};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut p = CommandParser::new();
    for (i, &b) in data.iter().enumerate() {
        if let Some(cmd) = p.push(b) {
            let enc = cmd.encode();
            let bytes = enc.as_bytes();
            if !matches!(cmd, Command::Start | Command::Stop) {
                assert!(i + 1 >= bytes.len());
                assert_eq!(&data[i + 1 - bytes.len()..=i], bytes);
            } else {
                assert_eq!(bytes, &[b]);
            }
        }
    }
});
