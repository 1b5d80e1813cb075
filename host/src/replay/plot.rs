//! Plots of replay results as PNG images, drawn with `plotters`' bitmap backend.
//!
//! Text comes from a built-in pixel font ([`super::plot_text`]), so nothing depends on the system's fonts:
//! the axes start at zero and carry their tick values and titles, grey grid lines mark the tick steps that
//! [`PlotScale`] reports (and `report.json` repeats), and the red line marks the 2 mm accuracy target.

pub use fires_record::report::PlotScale;
use std::path::Path;

use plotters::prelude::*;

use super::plot_text::{draw_text, text_width, tick_label, GLYPH};

/// Image pixels per font pixel of the labels.
const TEXT_SCALE: i32 = 2;

/// Size of the tip-error plot, pixels (width, height).
pub const TIP_ERROR_SIZE: (u32, u32) = (1000, 500);

/// The accuracy target drawn as a red line, millimetres.
pub const TARGET_MM: f64 = 2.0;

/// A plot could not be drawn or written.
#[derive(Debug, thiserror::Error)]
#[error("cannot draw {path}: {message}")]
pub struct PlotError {
    path: String,
    message: String,
}

/// The smallest step of 1, 2 or 5 times a power of ten that divides `span` into at most `max_ticks` steps.
fn nice_step(span: f64, max_ticks: f64) -> f64 {
    let raw = (span / max_ticks).max(1e-9);
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p)
}

/// Writes the tip error (millimetres) over time (seconds) as a PNG at `path`: one blue dot per sample joined
/// by a thin line, the 2 mm target in red. The y range covers the 99th percentile error (at least 3 mm).
pub fn tip_error_png(path: &Path, points: &[(f64, f64)]) -> Result<PlotScale, PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    let x_max = points.iter().map(|p| p.0).fold(0.0f64, f64::max).max(1e-3);
    let mut sorted: Vec<f64> = points
        .iter()
        .map(|p| p.1)
        .filter(|e| e.is_finite())
        .collect();
    sorted.sort_by(f64::total_cmp);
    let p99 = sorted
        .get(((sorted.len() as f64 - 1.0) * 0.99).round().max(0.0) as usize)
        .copied()
        .unwrap_or(0.0);
    let y_tick = nice_step((p99 * 1.1).max(3.0), 10.0);
    let y_max = ((p99 * 1.1).max(3.0) / y_tick).ceil() * y_tick;
    let x_tick = nice_step(x_max, 20.0);
    let x_max = (x_max / x_tick).ceil() * x_tick;

    let root = BitMapBackend::new(path, TIP_ERROR_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .margin(20)
        .margin_top(44)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(0f64..x_max, 0f64..y_max)
        .map_err(|e| err(&e))?;
    let grid = RGBColor(215, 215, 215);
    let ticks = |step: f64, max: f64| {
        (0..)
            .map(move |i| i as f64 * step)
            .take_while(move |v| *v <= max + step * 1e-6)
    };
    chart
        .draw_series(
            ticks(x_tick, x_max).map(|x| PathElement::new(vec![(x, 0.0), (x, y_max)], grid)),
        )
        .map_err(|e| err(&e))?;
    chart
        .draw_series(
            ticks(y_tick, y_max).map(|y| PathElement::new(vec![(0.0, y), (x_max, y)], grid)),
        )
        .map_err(|e| err(&e))?;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(0.0, 0.0), (x_max, y_max)],
            BLACK.stroke_width(2),
        )))
        .map_err(|e| err(&e))?;
    let clipped = |&(t, e): &(f64, f64)| (t, e.min(y_max));
    chart
        .draw_series(LineSeries::new(
            points.iter().map(clipped),
            RGBColor(150, 170, 230).stroke_width(1),
        ))
        .map_err(|e| err(&e))?;
    chart
        .draw_series(points.iter().map(|p| {
            let color = if p.1 > y_max {
                RGBColor(255, 140, 0)
            } else {
                RGBColor(20, 60, 200)
            };
            Circle::new(clipped(p), 2, color.filled())
        }))
        .map_err(|e| err(&e))?;
    chart
        .draw_series(std::iter::once(PathElement::new(
            vec![(0.0, TARGET_MM), (x_max, TARGET_MM)],
            RED.stroke_width(2),
        )))
        .map_err(|e| err(&e))?;
    let px = |x: f64, y: f64| chart.backend_coord(&(x, y));
    let ink = RGBColor(40, 40, 40);
    // Tick values, every k-th tick so that neighbouring labels keep a gap.
    let widest = text_width(&tick_label(x_max, x_tick), TEXT_SCALE) + 12;
    let tick_px = (px(x_tick, 0.0).0 - px(0.0, 0.0).0).max(1);
    let every = ((widest + tick_px - 1) / tick_px).max(1) as usize;
    for x in ticks(x_tick, x_max).step_by(every) {
        let label = tick_label(x, x_tick);
        let (cx, bottom) = px(x, 0.0);
        let at = (cx - text_width(&label, TEXT_SCALE) / 2, bottom + 8);
        draw_text(&root, &label, at, TEXT_SCALE, ink).map_err(|e| err(&e))?;
    }
    let glyph_h = GLYPH.1 * TEXT_SCALE;
    for y in ticks(y_tick, y_max) {
        let label = tick_label(y, y_tick);
        let (left, cy) = px(0.0, y);
        let at = (left - text_width(&label, TEXT_SCALE) - 8, cy - glyph_h / 2);
        draw_text(&root, &label, at, TEXT_SCALE, ink).map_err(|e| err(&e))?;
    }
    let (left, top) = px(0.0, y_max);
    let (right, bottom) = px(x_max, 0.0);
    draw_text(
        &root,
        "tip error (mm)",
        (left, top - glyph_h - 12),
        TEXT_SCALE,
        ink,
    )
    .map_err(|e| err(&e))?;
    let title = "time (s)";
    let at = (
        right - text_width(title, TEXT_SCALE),
        bottom + 8 + glyph_h + 8,
    );
    draw_text(&root, title, at, TEXT_SCALE, ink).map_err(|e| err(&e))?;
    let target = "2 mm target";
    let (_, ty) = px(x_max, TARGET_MM);
    let at = (right - text_width(target, TEXT_SCALE) - 6, ty - glyph_h - 6);
    draw_text(&root, target, at, TEXT_SCALE, RED).map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(PlotScale {
        x_max_s: x_max,
        x_tick_s: x_tick,
        y_max_mm: y_max,
        y_tick_mm: y_tick,
        points: points.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_1_2_5() {
        assert_eq!(nice_step(3.0, 10.0), 0.5);
        assert_eq!(nice_step(12.0, 20.0), 1.0);
        assert_eq!(nice_step(30.0, 10.0), 5.0);
    }
}
