//! The strokes file and the report: what a writer writes reads back equal, and a reader refuses what is not
//! its format, another major version, or values the format forbids, with an error naming the cause.

use fires_record::report::{BarFigures, BarMethod, BarReport, BarSmoothing, LinkSummary};
use fires_record::{Report, Stroke, StrokePiece, StrokePoint, StrokesError, StrokesFile};

fn stroke(id: u32) -> Stroke {
    let points = (0..5)
        .map(|i| StrokePoint {
            t_ns: 1_000 + i * 10,
            p_m: [0.01 * i as f64, -0.02, 0.7],
            sigma_mm: (i % 2 == 0).then_some(0.4),
        })
        .collect();
    Stroke {
        id,
        t_start_ns: 1_000,
        t_end_ns: 1_100,
        buttons: 0b0101,
        closed: false,
        raw_points: 12,
        pieces: vec![
            StrokePiece { points },
            StrokePiece {
                points: vec![StrokePoint {
                    t_ns: 1_090,
                    p_m: [0.1, -0.02, 0.7],
                    sigma_mm: None,
                }],
            },
        ],
    }
}

#[test]
fn a_strokes_file_reads_back_equal() {
    let file = StrokesFile::new(vec![stroke(0), stroke(3)]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("strokes.json");
    file.write(&path).unwrap();
    let back = StrokesFile::read(&path).unwrap();
    assert_eq!(back, file);
    let s = back.stroke(3).unwrap();
    assert_eq!((s.len(), s.polyline_m().len(), s.is_empty()), (6, 6, false));
}

#[test]
fn a_strokes_reader_refuses_what_the_format_forbids() {
    let good = serde_json::to_value(StrokesFile::new(vec![stroke(0), stroke(1)])).unwrap();
    let refuse = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v = good.clone();
        edit(&mut v);
        StrokesFile::from_json(&serde_json::to_vec(&v).unwrap()).unwrap_err()
    };
    assert!(matches!(
        refuse(&|v| v["format"] = "fires-recording".into()),
        StrokesError::NotAStrokesFile(_)
    ));
    assert!(matches!(
        refuse(&|v| v["version"] = "2.0".into()),
        StrokesError::UnsupportedVersion(_)
    ));
    let e = refuse(&|v| v["strokes"][1]["id"] = 0.into());
    assert_eq!(e.to_string(), "stroke 0: id used twice");
    let e = refuse(&|v| v["strokes"][0]["t_end_ns"] = 10.into());
    assert_eq!(e.to_string(), "stroke 0: ends before it starts");
    let e = refuse(&|v| v["strokes"][1]["pieces"][0]["points"][0]["sigma_mm"] = (-1.0).into());
    assert!(e.to_string().contains("uncertainty"), "{e}");
    assert!(matches!(
        refuse(&|v| v["strokes"][0]["pieces"] = "none".into()),
        StrokesError::Json { .. }
    ));
    assert!(StrokesFile::from_json(b"\xff\x00").is_err());
}

#[test]
fn a_bar_report_reads_back_equal_and_another_version_is_refused() {
    let figures = BarFigures {
        bar_nominal_mm: 81.0,
        bar_frames: 10,
        bar_frames_le_1m: 8,
        bar_frac_within_2mm_le_1m: Some(0.875),
        bar_frac_within_2mm: None,
        bar_rmse_mm_le_1m: 1.1,
    };
    let method = BarMethod {
        filtered: figures.clone(),
        single_frame: figures,
    };
    let report = Report::Bar(Box::new(BarReport {
        format: fires_record::REPORT_FORMAT.into(),
        version: fires_record::REPORT_VERSION.into(),
        recording: "rec".into(),
        bar_smoothing: BarSmoothing::default(),
        damaged: fires_record::Damage::default(),
        headline: method.clone(),
        method_midpoint: method.clone(),
        method_linear: method.clone(),
        method_normal_equations: method,
    }));
    let text = serde_json::to_vec(&report).unwrap();
    let v: serde_json::Value = serde_json::from_slice(&text).unwrap();
    // The headline figures sit at the top level, as the report's readers expect.
    assert_eq!(v["kind"], "bar");
    assert_eq!(v["bar_frames"], 10);
    assert_eq!(v["single_frame"]["bar_frames"], 10);
    assert_eq!(Report::from_json(&text).unwrap(), report);
    let mut other = v.clone();
    other["version"] = "2.1".into();
    assert!(Report::from_json(&serde_json::to_vec(&other).unwrap()).is_err());
}

#[test]
fn the_link_summary_flattens_the_decoder_counters() {
    let mut s = LinkSummary {
        bytes: 440,
        ..LinkSummary::default()
    };
    s.stats.sensor_frames = 20;
    s.stats.lost = 2;
    let v = serde_json::to_value(s).unwrap();
    assert_eq!(v["bytes"], 440);
    assert_eq!(v["sensor_frames"], 20);
    assert_eq!(v["lost"], 2);
    assert_eq!(serde_json::from_value::<LinkSummary>(v).unwrap(), s);
}

/// `Stroke::untracked_mm`: the button time against the first and last tracked points, times the speed
/// of the tracked points next to that end; gaps under 50 ms (latency) count as none.
#[test]
fn the_untracked_ends_are_the_gap_times_the_speed_next_to_them() {
    // Ten points 10 ms apart moving 1 mm each (0.1 m/s), tracked from 200 ms after the press to
    // 30 ms before the release.
    let points = (0..10u64)
        .map(|i| StrokePoint {
            t_ns: 200_000_000 + i * 10_000_000,
            p_m: [0.001 * i as f64, 0.0, 0.6],
            sigma_mm: None,
        })
        .collect();
    let mut s = Stroke {
        id: 0,
        t_start_ns: 0,
        t_end_ns: 320_000_000,
        buttons: 1,
        closed: false,
        raw_points: 10,
        pieces: vec![StrokePiece { points }],
    };
    let [a, b] = s.untracked_mm();
    assert!((a - 20.0).abs() < 1e-9, "{a}");
    assert_eq!(b, 0.0);
    s.t_end_ns = 400_000_000;
    let [_, b] = s.untracked_mm();
    assert!((b - 11.0).abs() < 1e-9, "{b}");
    s.pieces.clear();
    assert_eq!(s.untracked_mm(), [0.0; 2]);
}
