//! The `stress` scenario exercises every fault the models can inject.

use fires_record::{PacketFate, RecordingReader, Visibility};
use fires_sim::{run_scenario, SimOptions};
use std::collections::BTreeSet;

#[test]
fn stress_has_occlusions_reflections_link_faults_and_a_disconnect() {
    let dir = tempfile::tempdir().unwrap();
    let opts = SimOptions {
        images: false,
        ..SimOptions::default()
    };
    run_scenario("stress", 3, 12.0, dir.path(), opts).unwrap();
    let r = RecordingReader::open(dir.path()).unwrap();
    let ex = r.exposure_truth().unwrap().unwrap();
    let seen: BTreeSet<String> = ex
        .iter()
        .flat_map(|e| e.leds.iter().map(|l| format!("{:?}", l.visibility)))
        .collect();
    for v in [
        Visibility::OccludedByHand,
        Visibility::OccludedByObject,
        Visibility::Visible,
    ] {
        assert!(
            seen.contains(&format!("{v:?}")),
            "{v:?} never happens: {seen:?}"
        );
    }
    assert!(ex.iter().filter(|e| !e.spurious.is_empty()).count() * 5 > ex.len());
    let fates: BTreeSet<String> = r
        .packet_truth()
        .unwrap()
        .unwrap()
        .iter()
        .map(|p| format!("{:?}", p.fate))
        .collect();
    for f in [
        PacketFate::Delivered,
        PacketFate::PenDropped,
        PacketFate::Lost,
        PacketFate::Disconnected,
        PacketFate::Damaged,
    ] {
        assert!(fates.contains(&format!("{f:?}")), "{f:?} never happens");
    }
    let world = r.world_truth().unwrap().unwrap();
    assert_eq!(world.disconnects.len(), 1);
    // Nothing arrives during the disconnection (plus the radio latency).
    let d = world.disconnects[0];
    let chunks = r.link_chunks().unwrap();
    assert!(!chunks
        .iter()
        .any(|c| c.host_time_ns > d.start_ns + 100_000_000 && c.host_time_ns < d.end_ns));
}
