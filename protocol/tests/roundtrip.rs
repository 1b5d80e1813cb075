//! Encode/decode round trips of every packet and command field value.

use fires_protocol::{
    Buttons, Command, CommandParser, Frame, Health, SensorPacket, StateFlags, StatusPacket,
    StatusReason, PROTOCOL_VERSION,
};
use proptest::prelude::*;

prop_compose! {
    fn sensor()(counter in any::<u8>(), accel in any::<[i16; 3]>(), gyro in any::<[i16; 3]>(),
                mag in any::<[i16; 3]>()) -> SensorPacket {
        SensorPacket { counter, accel, gyro, mag }
    }
}

prop_compose! {
    fn status()(sequence in any::<u8>(), sensor_counter in any::<u8>(), device_time_us in any::<u32>(),
                buttons in 0u8..16, flags in any::<u8>(), health in any::<u8>(), reason in any::<u8>(),
                battery_mv in any::<u16>(), dropped_packets in any::<u32>(),
                firmware_version in any::<(u8, u8)>(), protocol_version in any::<u8>()) -> StatusPacket {
        StatusPacket {
            sequence, sensor_counter, device_time_us, buttons: Buttons(buttons), flags: StateFlags(flags),
            health: Health(health), reason: StatusReason::from_byte(reason), battery_mv, dropped_packets,
            firmware_version, protocol_version,
        }
    }
}

fn command() -> impl Strategy<Value = Command> {
    prop_oneof![
        Just(Command::Start),
        Just(Command::Stop),
        extended_command()
    ]
}

fn extended_command() -> impl Strategy<Value = Command> {
    prop_oneof![
        any::<u16>().prop_map(|duration_ms| Command::Vibrate { duration_ms }),
        any::<(u16, u16)>().prop_map(|(frequency_hz, duration_ms)| Command::Beep {
            frequency_hz,
            duration_ms
        }),
        any::<bool>().prop_map(|on| Command::IrLeds { on }),
        Just(Command::RequestStatus),
    ]
}

proptest! {
    #[test]
    fn sensor_packets_round_trip(p in sensor()) {
        let raw = p.encode();
        prop_assert_eq!(raw.len(), 22);
        prop_assert_eq!(Frame::parse(&raw), Ok(Frame::Sensor(p)));
    }

    #[test]
    fn status_packets_round_trip(p in status()) {
        prop_assert_eq!(Frame::parse(&p.encode()), Ok(Frame::Status(p)));
    }

    #[test]
    fn any_single_byte_error_fails_the_checksum(p in sensor(), at in 0usize..22, flip in 1u8..=255) {
        let mut raw = p.encode();
        raw[at] ^= flip;
        prop_assert!(Frame::parse(&raw).is_err());
    }

    #[test]
    fn commands_round_trip(c in command()) {
        let mut parser = CommandParser::new();
        let got: Vec<Command> = c.encode().as_bytes().iter().filter_map(|&b| parser.push(b)).collect();
        prop_assert_eq!(got, vec![c]);
    }

    #[test]
    fn no_command_byte_is_start_stop_or_escape(c in command()) {
        let bytes = c.encode();
        if !matches!(c, Command::Start | Command::Stop) {
            prop_assert!(bytes.as_bytes().iter().all(|b| !matches!(b, b'=' | b':' | b'+')));
        }
    }

    #[test]
    fn a_lost_or_corrupted_command_byte_never_yields_another_command(
        c in extended_command(), at in 0usize..13, flip in 1u8..=255, lose in any::<bool>()
    ) {
        let mut bytes = c.encode().as_bytes().to_vec();
        let at = at % bytes.len();
        if lose { bytes.remove(at); } else { bytes[at] ^= flip; }
        let mut parser = CommandParser::new();
        let got: Vec<Command> = bytes.iter().filter_map(|&b| parser.push(b)).collect();
        // A byte corrupted into '=' or ':' is itself a (thesis) command; nothing else may come out.
        for g in &got {
            prop_assert!(matches!(g, Command::Start | Command::Stop), "got {:?} from damaged {:?}", g, c);
            prop_assert!(!lose);
        }
    }
}

#[test]
fn status_reason_values_are_stable() {
    for b in 0..=255u8 {
        assert_eq!(StatusReason::from_byte(b).to_byte(), b);
    }
    assert_eq!(PROTOCOL_VERSION, 1);
}

#[test]
fn worked_examples_match_the_protocol_doc() {
    let sensor = SensorPacket {
        counter: 0x07,
        accel: [16, -32, 1024],
        gyro: [-1, 0, 1],
        mag: [300, -300, 0],
    };
    let hex = |b: &[u8]| {
        b.iter()
            .map(|x| format!("{x:02X}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    assert_eq!(
        hex(&sensor.encode()),
        "20 0A 07 10 00 E0 FF 00 04 FF FF 00 00 01 00 2C 01 D4 FE 00 00 20"
    );
    let status = StatusPacket {
        sequence: 3,
        sensor_counter: 0x07,
        device_time_us: 1_000_000,
        buttons: Buttons::from_states([true, false, false, false]),
        flags: StateFlags(StateFlags::STREAMING | StateFlags::IR_LEDS_ON | StateFlags::CONNECTED),
        health: Health(Health::ALL_GOOD),
        reason: StatusReason::ButtonChange,
        battery_mv: 3900,
        dropped_packets: 2,
        firmware_version: (0, 1),
        protocol_version: PROTOCOL_VERSION,
    };
    assert_eq!(
        hex(&status.encode()),
        "20 0B 03 07 40 42 0F 00 01 0B 3F 01 3C 0F 02 00 00 00 00 01 01 27"
    );
    assert_eq!(
        Command::Vibrate { duration_ms: 500 }.encode().as_bytes(),
        b"!V01F48E\r"
    );
    assert_eq!(
        Command::Beep {
            frequency_hz: 2000,
            duration_ms: 100
        }
        .encode()
        .as_bytes(),
        b"!B07D000647A\r"
    );
    assert_eq!(
        Command::IrLeds { on: true }.encode().as_bytes(),
        b"!L01A0\r"
    );
    assert_eq!(
        Command::IrLeds { on: false }.encode().as_bytes(),
        b"!L00A7\r"
    );
    assert_eq!(Command::RequestStatus.encode().as_bytes(), b"!SBE\r");
    assert_eq!(Command::Start.encode().as_bytes(), b"=");
    assert_eq!(Command::Stop.encode().as_bytes(), b":");
}
