//! Text for the plots from a built-in 5x7 pixel font, so the images carry axis labels without
//! depending on the system's fonts (plotters' text needs FreeType/fontconfig or a bundled TTF).
//! Only the characters the plots use are defined; others draw as blanks.

use plotters::prelude::*;

/// Glyph width and height in font pixels.
pub const GLYPH: (i32, i32) = (5, 7);

/// Rows of a glyph, most significant of the 5 low bits = leftmost pixel.
fn glyph(c: char) -> [u8; 7] {
    match c {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        '.' => [0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C],
        '-' => [0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00],
        '(' => [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02],
        ')' => [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08],
        'a' => [0x00, 0x00, 0x0E, 0x01, 0x0F, 0x11, 0x0F],
        'e' => [0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E],
        'g' => [0x00, 0x0F, 0x11, 0x11, 0x0F, 0x01, 0x0E],
        'i' => [0x04, 0x00, 0x0C, 0x04, 0x04, 0x04, 0x0E],
        'm' => [0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11],
        'o' => [0x00, 0x00, 0x0E, 0x11, 0x11, 0x11, 0x0E],
        'p' => [0x00, 0x00, 0x1E, 0x11, 0x1E, 0x10, 0x10],
        'r' => [0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10],
        's' => [0x00, 0x00, 0x0E, 0x10, 0x0E, 0x01, 0x1E],
        't' => [0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06],
        _ => [0; 7],
    }
}

/// Width in image pixels of `text` at `scale` image pixels per font pixel (one font pixel between
/// characters).
pub fn text_width(text: &str, scale: i32) -> i32 {
    let n = text.chars().count() as i32;
    (n * (GLYPH.0 + 1) - 1).max(0) * scale
}

/// Draws `text` with its top-left corner at pixel `at`.
pub fn draw_text<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    text: &str,
    at: (i32, i32),
    scale: i32,
    color: RGBColor,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    for (k, c) in text.chars().enumerate() {
        let x0 = at.0 + k as i32 * (GLYPH.0 + 1) * scale;
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..GLYPH.0 {
                if bits & (1 << (GLYPH.0 - 1 - col)) != 0 {
                    let (x, y) = (x0 + col * scale, at.1 + row as i32 * scale);
                    for (dx, dy) in (0..scale).flat_map(|dx| (0..scale).map(move |dy| (dx, dy))) {
                        area.draw_pixel((x + dx, y + dy), &color)?;
                    }
                }
            }
        }
    }
    Ok(())
}

/// A tick value with as many decimals as the step needs.
pub fn tick_label(value: f64, step: f64) -> String {
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10()).ceil().clamp(0.0, 6.0) as usize
    };
    format!("{value:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyph_pixels_land_where_the_font_says() {
        let (w, h) = (40u32, 16u32);
        let mut buf = vec![255u8; (w * h * 3) as usize];
        {
            let area = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            draw_text(&area, "1.", (2, 3), 1, BLACK).unwrap();
            area.present().unwrap();
        }
        let dark = |x: u32, y: u32| buf[((y * w + x) * 3) as usize] < 128;
        for (row, bits) in glyph('1').iter().enumerate() {
            for col in 0..5u32 {
                let on = bits & (1 << (4 - col)) != 0;
                assert_eq!(dark(2 + col, 3 + row as u32), on, "'1' row {row} col {col}");
            }
        }
        // The '.' follows one blank column later: its dot is in the last two rows.
        assert!(dark(2 + 6 + 1, 3 + 5) && dark(2 + 6 + 2, 3 + 6));
        assert!(!dark(2 + 6 + 1, 3));
        assert_eq!(text_width("1.", 2), 22);
    }

    #[test]
    fn tick_labels_show_the_step_s_decimals() {
        assert_eq!(tick_label(2.0, 0.5), "2.0");
        assert_eq!(tick_label(0.25, 0.05), "0.25");
        assert_eq!(tick_label(10.0, 5.0), "10");
    }
}
