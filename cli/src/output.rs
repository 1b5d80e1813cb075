//! Files that several commands write: pretty JSON documents and the tracker's `track.csv`.

use std::io::Write;
use std::path::Path;

use anyhow::Context;
use fires_host::track::pipeline::{TrackQuality, TrackSample};

/// Writes `value` as pretty-printed JSON with a final newline.
pub fn write_json<T: serde::Serialize + ?Sized>(path: &Path, value: &T) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    std::fs::write(path, text + "\n").with_context(|| format!("cannot write {}", path.display()))
}

/// Writes `strokes.json` (docs/strokes.md) holding `strokes`.
pub fn write_strokes(path: &Path, strokes: &[fires_record::Stroke]) -> anyhow::Result<()> {
    fires_record::StrokesFile::new(strokes.to_vec())
        .write(path)
        .map_err(Into::into)
}

/// Writes one CSV row per tracker sample (with the display-smoothed tip in the last columns).
pub fn write_track_csv(
    path: &Path,
    samples: &[TrackSample],
    display_tips: &[Option<[f64; 3]>],
) -> anyhow::Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("cannot write {}", path.display()))?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(w, "t_ns,quality,leds,tip_x_m,tip_y_m,tip_z_m,dir_x,dir_y,dir_z,labels,confidence,interference,display_x_m,display_y_m,display_z_m")?;
    for (i, s) in samples.iter().enumerate() {
        let (q, n) = match s.quality {
            TrackQuality::Vision { leds } => ("vision", leds),
            TrackQuality::DeadReckoned => ("dead_reckoned", 0),
            TrackQuality::Lost => ("lost", 0),
        };
        let v3 = |v: Option<[f64; 3]>| {
            v.map_or(",,".to_string(), |p| {
                format!("{:.6},{:.6},{:.6}", p[0], p[1], p[2])
            })
        };
        let labels: String = s
            .labels
            .iter()
            .map(|l| l.map_or("-".into(), |(a, b)| format!("{a}:{b}")))
            .collect::<Vec<_>>()
            .join(" ");
        writeln!(
            w,
            "{},{q},{n},{},{},{labels},{:.3},{},{}",
            s.t_ns,
            v3(s.tip),
            v3(s.direction),
            s.confidence,
            s.interference,
            v3(display_tips.get(i).copied().flatten())
        )?;
    }
    w.flush()
        .with_context(|| format!("cannot write {}", path.display()))
}
