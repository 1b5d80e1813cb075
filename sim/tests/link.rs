//! The byte stream decodes with `fires_protocol::StreamDecoder` to exactly the generated packets minus the
//! injected losses.

use fires_protocol::{Frame, StreamDecoder};
use fires_record::{PacketFate, RecordingReader};
use fires_sim::link::LinkConfig;
use fires_sim::{run, scenario, SimOptions};

fn decode(r: &RecordingReader) -> (Vec<Frame>, fires_protocol::DecoderStats) {
    let mut dec = StreamDecoder::new();
    let mut out = Vec::new();
    let chunks = r.link_chunks().unwrap();
    let mut last = 0;
    for c in &chunks {
        assert!(c.host_time_ns >= last, "host times are monotonic");
        last = c.host_time_ns;
        dec.feed(&c.bytes, |d| out.push(d.frame));
    }
    if let Some(d) = dec.finish() {
        out.push(d.frame);
    }
    (out, dec.stats())
}

fn simulate(link: LinkConfig, seed: u64, duration: f64) -> (tempfile::TempDir, RecordingReader) {
    let mut sc = scenario("fires-v1", seed, duration, None).unwrap();
    sc.link = link;
    let dir = tempfile::tempdir().unwrap();
    run(
        &sc,
        seed,
        duration,
        dir.path(),
        SimOptions {
            images: false,
            ..SimOptions::default()
        },
    )
    .unwrap();
    let r = RecordingReader::open(dir.path()).unwrap();
    (dir, r)
}

#[test]
fn whole_packet_losses_decode_to_exactly_the_delivered_packets() {
    let link = LinkConfig {
        pen_drop_prob: 0.02,
        packet_loss_prob: 0.02,
        ..LinkConfig::clean()
    };
    let (_dir, r) = simulate(link, 21, 4.0);
    let truth = r.packet_truth().unwrap().unwrap();
    let imu = r.imu_truth().unwrap().unwrap();
    // One sensor packet per IMU sample, counters consecutive (pen drops consume counters).
    let sensors: Vec<_> = truth
        .iter()
        .filter_map(|p| match p.frame {
            Frame::Sensor(s) => Some((s, p.fate)),
            _ => None,
        })
        .collect();
    assert_eq!(sensors.len(), imu.len());
    for (i, ((s, _), t)) in sensors.iter().zip(&imu).enumerate() {
        assert_eq!(s.counter, i as u8);
        assert_eq!(t.counter, s.counter);
    }
    let pen_dropped = sensors
        .iter()
        .filter(|s| s.1 == PacketFate::PenDropped)
        .count();
    let lost = truth.iter().filter(|p| p.fate == PacketFate::Lost).count();
    assert!(pen_dropped > 0 && lost > 0, "faults were injected");
    assert!(truth.iter().all(|p| matches!(
        p.fate,
        PacketFate::Delivered | PacketFate::PenDropped | PacketFate::Lost
    )));

    let delivered: Vec<Frame> = truth
        .iter()
        .filter(|p| p.fate == PacketFate::Delivered)
        .map(|p| p.frame)
        .collect();
    let (decoded, stats) = decode(&r);
    assert_eq!(
        decoded, delivered,
        "decoded stream == generated packets minus losses"
    );
    assert_eq!(stats.checksum_errors, 0);
    assert_eq!(stats.bytes_skipped, 0);
    // The decoder's lost count is the number of sensor counters missing.
    let missing = sensors
        .iter()
        .filter(|s| s.1 != PacketFate::Delivered)
        .count() as u64;
    assert_eq!(stats.lost, missing);
    // Status packets carry the pen's own drop count.
    let last_status = decoded.iter().rev().find_map(|f| match f {
        Frame::Status(s) => Some(*s),
        _ => None,
    });
    assert!(last_status.unwrap().dropped_packets as usize <= pen_dropped);
}

#[test]
fn byte_faults_and_a_disconnect_never_produce_a_phantom_packet() {
    let link = LinkConfig {
        pen_drop_prob: 0.01,
        packet_loss_prob: 0.01,
        byte_drop_prob: 0.002,
        byte_corrupt_prob: 0.002,
        disconnects: vec![(1.5, 0.7)],
        ..LinkConfig::clean()
    };
    let (_dir, r) = simulate(link, 22, 5.0);
    let truth = r.packet_truth().unwrap().unwrap();
    let delivered: Vec<Frame> = truth
        .iter()
        .filter(|p| p.fate == PacketFate::Delivered)
        .map(|p| p.frame)
        .collect();
    let faults = truth
        .iter()
        .filter(|p| p.fate != PacketFate::Delivered)
        .count();
    let damaged = truth
        .iter()
        .filter(|p| p.fate == PacketFate::Damaged)
        .count();
    let disconnected = truth
        .iter()
        .filter(|p| p.fate == PacketFate::Disconnected)
        .count();
    assert!(damaged > 0 && disconnected > 50);
    let (decoded, _) = decode(&r);
    // Every decoded frame is a delivered one, in order (a subsequence).
    let mut it = delivered.iter();
    for d in &decoded {
        assert!(
            it.any(|x| x == d),
            "decoded a frame that was not delivered intact: {d:?}"
        );
    }
    // An intact frame is only missed next to a fault (the decoder needs a clean neighbour to lock).
    let missed = delivered.len() - decoded.len();
    assert!(missed <= 2 * faults, "missed {missed} with {faults} faults");
    assert!(decoded.len() * 10 >= delivered.len() * 9);
}
