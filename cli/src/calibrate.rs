//! `fires calibrate`: the stereo rig from chessboard image pairs (OpenCV, Zhang's method), written as the rig
//! JSON recordings use.

use std::path::PathBuf;

/// Arguments of `fires calibrate`.
#[derive(Debug, clap::Args)]
pub struct CalibrateArgs {
    /// Directory of image pairs `left_<id>.<ext>` / `right_<id>.<ext>` showing the same board pose.
    #[arg(long)]
    pub images: PathBuf,
    /// Inner corners of the chessboard, COLSxROWS (a board of 10x7 squares has 9x6).
    #[arg(long, default_value = "9x6", value_parser = parse_board)]
    pub board: (i32, i32),
    /// Side of one square, millimetres.
    #[arg(long, default_value_t = 25.0)]
    pub square_mm: f64,
    /// Where to write the rig calibration JSON (the `rig` object of a recording's meta.json).
    #[arg(long, default_value = "rig.json")]
    pub out: PathBuf,
}

fn parse_board(s: &str) -> Result<(i32, i32), String> {
    let err = || format!("'{s}' is not COLSxROWS, e.g. 9x6");
    let (c, r) = s.split_once(['x', 'X']).ok_or_else(err)?;
    let (c, r): (i32, i32) = (
        c.trim().parse().map_err(|_| err())?,
        r.trim().parse().map_err(|_| err())?,
    );
    if c < 2 || r < 2 {
        return Err(format!(
            "a board needs at least 2x2 inner corners, got {c}x{r}"
        ));
    }
    Ok((c, r))
}

/// Calibrates and writes the rig; prints a JSON report line.
#[cfg(feature = "opencv")]
pub fn run(args: &CalibrateArgs) -> anyhow::Result<()> {
    use anyhow::Context;
    use fires_host::calibrate::chessboard::{calibrate_stereo_dir, Chessboard};

    if !(args.square_mm.is_finite() && args.square_mm > 0.0) {
        anyhow::bail!("--square-mm must be a positive number of millimetres");
    }
    let board = Chessboard {
        cols: args.board.0,
        rows: args.board.1,
        square_m: args.square_mm / 1000.0,
    };
    let cal = calibrate_stereo_dir(&args.images, &board)
        .with_context(|| format!("calibration from {}", args.images.display()))?;
    let json = serde_json::to_string_pretty(&cal.to_rig())?;
    std::fs::write(&args.out, json + "\n")
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    let report = serde_json::json!({
        "kind": "calibration",
        "views": cal.views,
        "left_rms_px": cal.left.rms_px,
        "right_rms_px": cal.right.rms_px,
        "stereo_rms_px": cal.stereo_rms_px,
        "baseline_mm": 1000.0 * cal.translation_m.iter().map(|t| t * t).sum::<f64>().sqrt(),
        "out": args.out,
    });
    println!("{report}");
    Ok(())
}

/// Without OpenCV the command explains how to get it.
#[cfg(not(feature = "opencv"))]
pub fn run(_args: &CalibrateArgs) -> anyhow::Result<()> {
    anyhow::bail!(
        "this build has no OpenCV support; install libopencv-dev, clang and libclang-dev, then rebuild with \
         `cargo build --release -p fires-cli --features opencv`"
    )
}
