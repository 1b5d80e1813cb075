//! Rule 3 of hardware-docs/protocol.md §1.4 when garbage follows a locked frame: what it lets out, what it holds
//! back, and its false-frame bounds, each counted exactly over every value of the byte that decides.

use fires_protocol::{Frame, SensorPacket, StatusPacket, StreamDecoder, FRAME_LEN};

/// Sensor packet `counter` with payload bytes that differ from each other and from the sync bytes, so that a
/// frame shifted by one byte never equals the original.
fn sensor(counter: u8) -> [u8; FRAME_LEN] {
    let b = |i: u8| i16::from_le_bytes([0x30 + 2 * i, 0x31 + 2 * i]) ^ i16::from(counter);
    SensorPacket {
        counter,
        accel: [b(0), b(1), b(2)],
        gyro: [b(3), b(4), b(5)],
        mag: [b(6), b(7), b(8)],
    }
    .encode()
}

fn decode(bytes: &[u8]) -> (Vec<[u8; FRAME_LEN]>, StreamDecoder) {
    let mut d = StreamDecoder::new();
    let mut out = Vec::new();
    d.feed(bytes, |f| out.push(f.frame.encode()));
    out.extend(d.finish().map(|f| f.frame.encode()));
    (out, d)
}

/// Frames 0..=3 intact, then `middle`, then frames 5..=8 intact.
fn stream(middle: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    for c in 0..4 {
        out.extend_from_slice(&sensor(c));
    }
    out.extend_from_slice(middle);
    for c in 5..9 {
        out.extend_from_slice(&sensor(c));
    }
    out
}

/// Decoded frames that are none of the sent ones.
fn false_frames(got: &[[u8; FRAME_LEN]]) -> usize {
    let sent: Vec<[u8; FRAME_LEN]> = (0..9).map(sensor).collect();
    got.iter().filter(|g| !sent.contains(g)).count()
}

#[test]
fn garbage_after_a_frame_lets_it_out() {
    for g in [
        &[0x55u8][..],
        b"READY.\r\n",
        &[0x20, 0x20, 0x0A],
        &[0x0B, 0x20],
    ] {
        let mut middle = sensor(4).to_vec();
        middle.extend_from_slice(g);
        let (got, d) = decode(&stream(&middle));
        assert_eq!(
            got,
            (0..9).map(sensor).collect::<Vec<_>>(),
            "garbage {g:02X?}"
        );
        assert_eq!(d.stats().lost, 0);
    }
}

#[test]
fn a_frame_that_lost_a_byte_and_is_followed_by_garbage_passes_for_one_garbage_value_in_256() {
    let f = sensor(4);
    for at in 0..FRAME_LEN {
        let mut lost = f.to_vec();
        lost.remove(at);
        // Followed by the next frame: never a false frame (its sync pair comes one byte early).
        assert_eq!(false_frames(&decode(&stream(&lost)).0), 0, "lost byte {at}");
        // Followed by garbage: a false frame exactly when the first garbage byte completes the checksum, i.e.
        // equals the lost byte, and the counter survived (the window continues frame 3).
        let passing: Vec<u8> = (0..=255u8)
            .filter(|&g| {
                let mut middle = lost.clone();
                middle.extend_from_slice(&[g, 0x55, 0x55]);
                false_frames(&decode(&stream(&middle)).0) > 0
            })
            .collect();
        // (Losing the checksum byte and gaining it back from the garbage rebuilds the frame itself.)
        if (3..FRAME_LEN - 1).contains(&at) {
            assert_eq!(passing, vec![f[at]], "lost byte {at}");
        } else {
            assert!(passing.is_empty(), "lost byte {at}: {passing:02X?}");
        }
    }
}

#[test]
fn a_frame_that_gained_a_byte_passes_for_one_inserted_value_in_256() {
    // The inserted byte completes the checksum when it equals the frame's checksum; the frame's own last byte is
    // then the garbage that follows the 22-byte window. (Inserted at 21, the window is the frame itself.)
    let f = sensor(4);
    for at in 3..FRAME_LEN - 1 {
        let passing: Vec<u8> = (0..=255u8)
            .filter(|&x| {
                let mut middle = f.to_vec();
                middle.insert(at, x);
                false_frames(&decode(&stream(&middle)).0) > 0
            })
            .collect();
        assert_eq!(passing, vec![f[FRAME_LEN - 1]], "byte inserted at {at}");
    }
}

#[test]
fn an_intact_frame_ending_in_0x20_is_held_back_only_by_garbage_starting_with_a_second_sync_byte() {
    // Frame 4 with its checksum 0x20: the "next sync pair one byte early" sign when 0x0A or 0x0B follows.
    let f = (0..=u16::MAX)
        .map(|v| {
            SensorPacket {
                counter: 4,
                accel: [v as i16, 1, 2],
                ..Default::default()
            }
            .encode()
        })
        .find(|f| f[FRAME_LEN - 1] == 0x20)
        .expect("some payload has checksum 0x20");
    let held_back: Vec<u8> = (0..=255u8)
        .filter(|&g| {
            let mut middle = f.to_vec();
            middle.extend_from_slice(&[g, 0x55]);
            !decode(&stream(&middle)).0.contains(&f)
        })
        .collect();
    assert_eq!(held_back, vec![0x0A, 0x0B]);
}

#[test]
fn a_frame_that_garbage_follows_comes_out_only_if_it_continues_the_frame_before_it() {
    let mut bytes = Vec::new();
    for c in [0, 1, 2, 4] {
        bytes.extend_from_slice(&sensor(c)); // packet 3 dropped by the pen
    }
    bytes.push(0x55);
    for c in [5, 6] {
        bytes.extend_from_slice(&sensor(c));
    }
    let (got, d) = decode(&bytes);
    assert_eq!(got, [0, 1, 2, 5, 6].map(sensor).to_vec());
    assert_eq!(d.stats().lost, 2);

    // A status packet continues the sensor packet before it through its sensor counter.
    let status = |sensor_counter| {
        Frame::Status(StatusPacket {
            sensor_counter,
            ..Default::default()
        })
        .encode()
    };
    for (sc, out) in [(2u8, true), (9, false)] {
        let mut bytes = Vec::new();
        for c in 0..3 {
            bytes.extend_from_slice(&sensor(c));
        }
        bytes.extend_from_slice(&status(sc));
        bytes.push(0x55);
        let (got, _) = decode(&bytes);
        assert_eq!(got.contains(&status(sc)), out, "sensor counter {sc}");
    }
}

#[test]
fn garbage_that_looks_like_a_frame_after_a_frame_passes_only_with_the_next_counter() {
    // A 22-byte window of garbage with a sync pair and a right checksum, directly after frame 3 and followed by
    // more garbage: released only when its counter byte continues frame 3 (1 value in 256).
    let passing: Vec<u8> = (0..=255u8)
        .filter(|&c| {
            let mut w = [
                0x20, 0x0A, c, 0x99, 0x98, 0x97, 0x96, 0x95, 0x94, 0x93, 0x92, 0x91, 0x90,
            ];
            w[3] ^= c;
            let mut window = w.to_vec();
            window.resize(FRAME_LEN - 1, 0x77);
            window.push(window.iter().fold(0, |a, b| a ^ b));
            window.extend_from_slice(&[0x55, 0x55]);
            false_frames(&decode(&stream(&window)).0) > 0
        })
        .collect();
    assert_eq!(passing, vec![4]);
}
