//! Blob detection for the IR LEDs on 8-bit frames (issue 5 item 1; the thesis used OpenCV +
//! cvBlob).
//!
//! One pass over the search region extracts runs of pixels above `threshold` (32-byte chunks
//! that contain no bright pixel are skipped with a vectorisable max), runs touching runs of the
//! previous row (8-connectivity) are merged with union-find, and per-component moments are
//! accumulated in closed form per run. Components are gated by area and elongation (ratio of the
//! principal standard deviations): the limit admits the streak of merged spots that a pen
//! pointing nearly at the camera images (four LEDs in a row reach an elongation of about 6), whose
//! second moments ([`Blob::shape`]) give the pen's image line. The sub-pixel centre is the intensity-weighted centroid over
//! the component's bounding box grown by `centroid_margin` pixels, with weights `max(I - b, 0)`
//! where `b` is the background (fixed, or the mean of the grown box's border ring). Including the
//! faint tails makes the centroid nearly unbiased for Gaussian spots (opentrack's point extractor
//! fixes the same one-pixel jumps with mean-shift).
//!
//! A search window predicted from the tracker state can be given; the detector falls back to the
//! full frame when the window yields too few blobs or a blob touches the window border.
//! Buffers are kept in the detector, so steady-state detection does not allocate.
//! Pixel centres are at integer coordinates (OpenCV convention).

use thiserror::Error;

/// Invalid image description.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum ImageError {
    /// The buffer is smaller than `stride * (height - 1) + width`, or stride < width.
    #[error("image buffer of {len} bytes too small for {width}x{height} with stride {stride}")]
    BufferTooSmall {
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// Row stride in bytes.
        stride: usize,
        /// Buffer length.
        len: usize,
    },
}

/// A borrowed 8-bit grey image.
#[derive(Debug, Clone, Copy)]
pub struct GrayImage<'a> {
    width: usize,
    height: usize,
    stride: usize,
    data: &'a [u8],
}

impl<'a> GrayImage<'a> {
    /// A tightly packed image (`stride == width`).
    pub fn new(width: usize, height: usize, data: &'a [u8]) -> Result<Self, ImageError> {
        Self::with_stride(width, height, width, data)
    }

    /// An image whose rows start every `stride` bytes.
    pub fn with_stride(
        width: usize,
        height: usize,
        stride: usize,
        data: &'a [u8],
    ) -> Result<Self, ImageError> {
        let needed = if height == 0 {
            0
        } else {
            stride * (height - 1) + width
        };
        if stride < width || data.len() < needed {
            return Err(ImageError::BufferTooSmall {
                width,
                height,
                stride,
                len: data.len(),
            });
        }
        Ok(Self {
            width,
            height,
            stride,
            data,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    fn row(&self, y: usize) -> &'a [u8] {
        &self.data[y * self.stride..y * self.stride + self.width]
    }
}

/// An axis-aligned pixel rectangle `[x, x + width) x [y, y + height)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct Rect {
    /// Left column.
    pub x: usize,
    /// Top row.
    pub y: usize,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
}

impl Rect {
    /// The bounding box of `points` grown by `margin` pixels, clipped to the image; None if empty.
    pub fn around(
        points: &[[f64; 2]],
        margin: f64,
        image_width: usize,
        image_height: usize,
    ) -> Option<Self> {
        let finite = points
            .iter()
            .filter(|p| p[0].is_finite() && p[1].is_finite());
        let (mut x0, mut y0, mut x1, mut y1) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        for p in finite {
            x0 = x0.min(p[0]);
            y0 = y0.min(p[1]);
            x1 = x1.max(p[0]);
            y1 = y1.max(p[1]);
        }
        if x0 > x1 {
            return None;
        }
        let clip = |v: f64, hi: usize| v.clamp(0.0, hi as f64) as usize;
        let (ax, ay) = (
            clip((x0 - margin).floor(), image_width),
            clip((y0 - margin).floor(), image_height),
        );
        let (bx, by) = (
            clip((x1 + margin).ceil() + 1.0, image_width),
            clip((y1 + margin).ceil() + 1.0, image_height),
        );
        (bx > ax && by > ay).then_some(Self {
            x: ax,
            y: ay,
            width: bx - ax,
            height: by - ay,
        })
    }

    fn clipped(&self, width: usize, height: usize) -> Self {
        let x = self.x.min(width);
        let y = self.y.min(height);
        Self {
            x,
            y,
            width: self.width.min(width - x),
            height: self.height.min(height - y),
        }
    }

    fn grown(&self, margin: usize, width: usize, height: usize) -> Self {
        let x = self.x.saturating_sub(margin);
        let y = self.y.saturating_sub(margin);
        let x1 = (self.x + self.width + margin).min(width);
        let y1 = (self.y + self.height + margin).min(height);
        Self {
            x,
            y,
            width: x1 - x,
            height: y1 - y,
        }
    }
}

/// How the background level under a blob is estimated.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum BackgroundModel {
    /// A fixed grey level.
    Fixed(u8),
    /// The mean of the border ring of the blob's grown bounding box.
    LocalRing,
}

/// Detector settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BlobConfig {
    /// Pixels strictly above this level are foreground.
    pub threshold: u8,
    /// Minimum component area in pixels.
    pub min_area: u32,
    /// Maximum component area in pixels.
    pub max_area: u32,
    /// Maximum ratio of the principal standard deviations of the component.
    pub max_elongation: f64,
    /// Background estimate for the weighted centroid.
    pub background: BackgroundModel,
    /// Pixels added around the component's box for the weighted centroid.
    pub centroid_margin: usize,
    /// At most this many blobs are returned (the brightest).
    pub max_blobs: usize,
    /// Fall back to the full frame when a window yields fewer blobs than this.
    pub min_blobs_in_window: usize,
}

impl Default for BlobConfig {
    fn default() -> Self {
        Self {
            threshold: 60,
            min_area: 2,
            max_area: 2_000,
            max_elongation: 8.0,
            background: BackgroundModel::LocalRing,
            centroid_margin: 2,
            max_blobs: 16,
            min_blobs_in_window: 1,
        }
    }
}

/// The principal axis (unit vector) of second moments `[cxx, cxy, cyy]` and the elongation,
/// the ratio of the principal standard deviations.
pub fn principal_axis(shape: &[f64; 3]) -> ([f64; 2], f64) {
    let [cxx, cxy, cyy] = *shape;
    let angle = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
    let tr = 0.5 * (cxx + cyy);
    let disc = (0.25 * (cxx - cyy).powi(2) + cxy * cxy).sqrt();
    let elongation = ((tr + disc) / (tr - disc).max(1e-12)).sqrt();
    ([angle.cos(), angle.sin()], elongation)
}

/// One detected blob.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Blob {
    /// Sub-pixel centre x (pixels).
    pub x: f64,
    /// Sub-pixel centre y (pixels).
    pub y: f64,
    /// Thresholded area in pixels.
    pub area: u32,
    /// Sum of background-subtracted intensities used for the centroid.
    pub intensity: f64,
    /// Bounding box of the thresholded pixels.
    pub bbox: Rect,
    /// Central second moments `[cxx, cxy, cyy]` of the thresholded pixels, pixels²: the blob's
    /// extent and axis (a streak of merged LED spots lies along the pen's image).
    #[serde(default)]
    pub shape: [f64; 3],
}

/// Where the last detection searched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SearchRegion {
    /// Only the predicted window.
    Window,
    /// The whole frame (no window, or the window fallback).
    FullFrame,
}

#[derive(Debug, Clone, Copy)]
struct Run {
    y: u32,
    x0: u32,
    x1: u32,
}

#[derive(Debug, Clone, Copy, Default)]
struct Moments {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    syy: f64,
    sxy: f64,
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

impl Moments {
    fn add_run(&mut self, r: &Run) {
        let (a, b, y) = (f64::from(r.x0), f64::from(r.x1) - 1.0, f64::from(r.y));
        let n = b - a + 1.0;
        let sx = n * (a + b) * 0.5;
        let sq = |k: f64| k * (k + 1.0) * (2.0 * k + 1.0) / 6.0;
        let sxx = sq(b) - sq(a - 1.0);
        if self.n == 0.0 {
            (self.x0, self.y0, self.x1, self.y1) = (r.x0, r.y, r.x1, r.y + 1);
        } else {
            self.x0 = self.x0.min(r.x0);
            self.x1 = self.x1.max(r.x1);
            self.y0 = self.y0.min(r.y);
            self.y1 = self.y1.max(r.y + 1);
        }
        self.n += n;
        self.sx += sx;
        self.sy += n * y;
        self.sxx += sxx;
        self.syy += n * y * y;
        self.sxy += sx * y;
    }

    /// Central second moments `[cxx, cxy, cyy]` of the component's pixels, pixels² (pixel
    /// quantisation variance 1/12 added).
    fn shape(&self) -> [f64; 3] {
        let (mx, my) = (self.sx / self.n, self.sy / self.n);
        let cxx = self.sxx / self.n - mx * mx + 1.0 / 12.0;
        let cyy = self.syy / self.n - my * my + 1.0 / 12.0;
        let cxy = self.sxy / self.n - mx * my;
        [cxx, cxy, cyy]
    }

    /// Ratio of principal standard deviations (pixel quantisation variance 1/12 added).
    fn elongation(&self) -> f64 {
        principal_axis(&self.shape()).1
    }

    fn bbox(&self) -> Rect {
        Rect {
            x: self.x0 as usize,
            y: self.y0 as usize,
            width: (self.x1 - self.x0) as usize,
            height: (self.y1 - self.y0) as usize,
        }
    }
}

/// Blob detector with reusable buffers.
#[derive(Debug, Clone, Default)]
pub struct BlobDetector {
    /// Settings.
    pub config: BlobConfig,
    runs: Vec<Run>,
    parent: Vec<u32>,
    moments: Vec<Moments>,
}

impl BlobDetector {
    /// A detector with the given settings.
    pub fn new(config: BlobConfig) -> Self {
        Self {
            config,
            ..Default::default()
        }
    }

    /// Detects blobs, in `window` if given (with full-frame fallback), sorted by decreasing intensity.
    pub fn detect(&mut self, image: &GrayImage<'_>, window: Option<Rect>) -> Vec<Blob> {
        let mut out = Vec::new();
        self.detect_into(image, window, &mut out);
        out
    }

    /// As [`Self::detect`], into a caller-owned vector; returns where the blobs were found.
    pub fn detect_into(
        &mut self,
        image: &GrayImage<'_>,
        window: Option<Rect>,
        out: &mut Vec<Blob>,
    ) -> SearchRegion {
        let full = Rect {
            x: 0,
            y: 0,
            width: image.width,
            height: image.height,
        };
        if let Some(w) = window.map(|w| w.clipped(image.width, image.height)) {
            if w.width > 0 && w.height > 0 {
                self.detect_region(image, &w, out);
                let cut = out.iter().any(|b| touches_inner_border(&b.bbox, &w, &full));
                if out.len() >= self.config.min_blobs_in_window && !cut {
                    return SearchRegion::Window;
                }
            }
        }
        self.detect_region(image, &full, out);
        SearchRegion::FullFrame
    }

    fn detect_region(&mut self, image: &GrayImage<'_>, region: &Rect, out: &mut Vec<Blob>) {
        out.clear();
        self.label(image, region);
        self.accumulate();
        for m in self.moments.iter().filter(|m| m.n > 0.0) {
            let area = m.n as u32;
            if area < self.config.min_area
                || area > self.config.max_area
                || m.elongation() > self.config.max_elongation
                || touches_image_edge(&m.bbox(), image)
            {
                continue;
            }
            if let Some(b) = weighted_centroid(image, &m.bbox(), area, &self.config) {
                out.push(Blob {
                    shape: m.shape(),
                    ..b
                });
            }
        }
        out.sort_by(|a, b| b.intensity.total_cmp(&a.intensity));
        out.truncate(self.config.max_blobs);
    }

    /// Run extraction and union-find labelling over `region`.
    fn label(&mut self, image: &GrayImage<'_>, region: &Rect) {
        self.runs.clear();
        self.parent.clear();
        let t = self.config.threshold;
        let mut prev = 0..0;
        for y in region.y..region.y + region.height {
            let start = self.runs.len();
            let row = &image.row(y)[region.x..region.x + region.width];
            scan_row(row, t, |x0, x1| {
                self.runs.push(Run {
                    y: y as u32,
                    x0: (region.x + x0) as u32,
                    x1: (region.x + x1) as u32,
                });
            });
            let cur = start..self.runs.len();
            for k in cur.clone() {
                self.parent.push(k as u32);
            }
            self.link_rows(prev.clone(), cur.clone());
            prev = cur;
        }
    }

    /// Unions every run of `cur` with the 8-connected runs of `prev` (both sorted by x).
    fn link_rows(&mut self, prev: std::ops::Range<usize>, cur: std::ops::Range<usize>) {
        let mut p = prev.start;
        for c in cur {
            let (cx0, cx1) = (self.runs[c].x0, self.runs[c].x1);
            while p < prev.end && self.runs[p].x1 < cx0 {
                p += 1;
            }
            let mut q = p;
            while q < prev.end && self.runs[q].x0 <= cx1 {
                union(&mut self.parent, q as u32, c as u32);
                q += 1;
            }
        }
    }

    fn accumulate(&mut self) {
        self.moments.clear();
        self.moments.resize(self.runs.len(), Moments::default());
        for k in 0..self.runs.len() {
            let root = find(&mut self.parent, k as u32) as usize;
            let run = self.runs[k];
            self.moments[root].add_run(&run);
        }
    }
}

/// Calls `emit(x0, x1)` for every maximal run of pixels `> t` in `row` (x1 exclusive).
fn scan_row(row: &[u8], t: u8, mut emit: impl FnMut(usize, usize)) {
    const CHUNK: usize = 32;
    let n = row.len();
    let mut open: Option<usize> = None;
    let mut x = 0;
    while x < n {
        if open.is_none()
            && x + CHUNK <= n
            && row[x..x + CHUNK].iter().fold(0u8, |a, &b| a.max(b)) <= t
        {
            x += CHUNK;
            continue;
        }
        let hot = row[x] > t;
        match (open, hot) {
            (None, true) => open = Some(x),
            (Some(s), false) => {
                emit(s, x);
                open = None;
            }
            _ => {}
        }
        x += 1;
    }
    if let Some(s) = open {
        emit(s, n);
    }
}

fn find(parent: &mut [u32], mut a: u32) -> u32 {
    while parent[a as usize] != a {
        let g = parent[parent[a as usize] as usize];
        parent[a as usize] = g;
        a = g;
    }
    a
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        parent[hi as usize] = lo;
    }
}

/// True when a blob's thresholded pixels reach the image's edge: the spot is cut there and its
/// centre pulled inwards by up to its radius (fires-v2 seed 3: LED 4 imaged 0.1 px outside the
/// right image gave a blob 3.4 px from it, which labelled as LED 4 put the tip off), so it is
/// no measurement of the LED.
fn touches_image_edge(b: &Rect, image: &GrayImage<'_>) -> bool {
    b.x == 0 || b.y == 0 || b.x + b.width >= image.width || b.y + b.height >= image.height
}

fn touches_inner_border(b: &Rect, window: &Rect, full: &Rect) -> bool {
    (b.x == window.x && window.x > full.x)
        || (b.y == window.y && window.y > full.y)
        || (b.x + b.width == window.x + window.width && window.x + window.width < full.width)
        || (b.y + b.height == window.y + window.height && window.y + window.height < full.height)
}

/// Intensity-weighted centroid over `bbox` grown by the margin, weights `max(I - background, 0)`.
fn weighted_centroid(
    image: &GrayImage<'_>,
    bbox: &Rect,
    area: u32,
    config: &BlobConfig,
) -> Option<Blob> {
    let region = bbox.grown(config.centroid_margin, image.width, image.height);
    let background = match config.background {
        BackgroundModel::Fixed(b) => f64::from(b),
        BackgroundModel::LocalRing => ring_mean(image, &region),
    };
    let (mut sw, mut swx, mut swy) = (0.0, 0.0, 0.0);
    for y in region.y..region.y + region.height {
        let row = &image.row(y)[region.x..region.x + region.width];
        let (mut rw, mut rwx) = (0.0, 0.0);
        for (i, &v) in row.iter().enumerate() {
            let w = (f64::from(v) - background).max(0.0);
            rw += w;
            rwx += w * (region.x + i) as f64;
        }
        sw += rw;
        swx += rwx;
        swy += rw * y as f64;
    }
    (sw > 0.0).then(|| Blob {
        x: swx / sw,
        y: swy / sw,
        area,
        intensity: sw,
        bbox: *bbox,
        shape: [0.0; 3],
    })
}

/// Mean grey level of the border pixels of `r`.
fn ring_mean(image: &GrayImage<'_>, r: &Rect) -> f64 {
    let (mut sum, mut n) = (0u64, 0u64);
    for y in r.y..r.y + r.height {
        let row = &image.row(y)[r.x..r.x + r.width];
        if y == r.y || y + 1 == r.y + r.height {
            sum += row.iter().map(|&v| u64::from(v)).sum::<u64>();
            n += row.len() as u64;
        } else if let (Some(a), Some(b)) = (row.first(), row.last()) {
            sum += u64::from(*a) + u64::from(*b);
            n += 2;
        }
    }
    if n == 0 {
        0.0
    } else {
        sum as f64 / n as f64
    }
}

/// Renders Gaussian spots on a constant background (tests and benches).
pub fn render_spots(
    width: usize,
    height: usize,
    background: u8,
    spots: &[(f64, f64, f64, f64)],
) -> Vec<u8> {
    let mut img = vec![background; width * height];
    for &(cx, cy, sigma, amplitude) in spots {
        let r = (4.0 * sigma).ceil() as i64;
        for y in (cy.round() as i64 - r).max(0)..=(cy.round() as i64 + r).min(height as i64 - 1) {
            for x in (cx.round() as i64 - r).max(0)..=(cx.round() as i64 + r).min(width as i64 - 1)
            {
                let d2 = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2);
                let v = amplitude * (-d2 / (2.0 * sigma * sigma)).exp();
                let p = &mut img[y as usize * width + x as usize];
                *p = (f64::from(*p) + v).round().min(255.0) as u8;
            }
        }
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn subpixel_centroids_of_gaussian_spots() {
        let mut rng = SplitMix64::new(1);
        let mut det = BlobDetector::new(BlobConfig::default());
        let mut worst: f64 = 0.0;
        for _ in 0..50 {
            let spots: Vec<_> = (0..4)
                .map(|k| {
                    (
                        60.0 + 140.0 * k as f64 + rng.uniform(0.0, 1.0),
                        rng.uniform(40.0, 440.0),
                        rng.uniform(1.0, 2.0),
                        200.0,
                    )
                })
                .collect();
            let img = render_spots(640, 480, 20, &spots);
            let blobs = det.detect(&GrayImage::new(640, 480, &img).unwrap(), None);
            assert_eq!(blobs.len(), 4);
            for s in &spots {
                let b = blobs
                    .iter()
                    .min_by(|a, b| {
                        (a.x - s.0)
                            .hypot(a.y - s.1)
                            .total_cmp(&(b.x - s.0).hypot(b.y - s.1))
                    })
                    .unwrap();
                worst = worst.max((b.x - s.0).hypot(b.y - s.1));
            }
        }
        assert!(worst < 0.05, "worst centroid error {worst} px");
    }

    /// Four touching spots in a row at 30 degrees (a pen pointing nearly at the camera) are one
    /// blob, kept, whose second moments lie along the row.
    #[test]
    fn a_streak_of_merged_spots_is_kept_with_its_axis() {
        let (w, h) = (120, 100);
        let mut img = vec![10u8; w * h];
        let angle = 30f64.to_radians();
        for k in 0..4 {
            let (cx, cy) = (
                40.0 + 7.0 * k as f64 * angle.cos(),
                40.0 + 7.0 * k as f64 * angle.sin(),
            );
            for y in 0..h {
                for x in 0..w {
                    if (x as f64 - cx).hypot(y as f64 - cy) <= 3.5 {
                        img[y * w + x] = 220;
                    }
                }
            }
        }
        let mut det = BlobDetector::new(BlobConfig::default());
        let blobs = det.detect(&GrayImage::new(w, h, &img).unwrap(), None);
        assert_eq!(blobs.len(), 1, "{blobs:?}");
        let [cxx, cxy, cyy] = blobs[0].shape;
        let axis = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
        assert!(
            (axis - angle).abs() < 1f64.to_radians(),
            "axis {} deg",
            axis.to_degrees()
        );
        let tr = 0.5 * (cxx + cyy);
        let disc = (0.25 * (cxx - cyy).powi(2) + cxy * cxy).sqrt();
        let elongation = ((tr + disc) / (tr - disc)).sqrt();
        assert!(elongation > 3.0, "elongation {elongation}");
    }

    #[test]
    fn gates_reject_big_and_elongated_components() {
        let (w, h) = (200, 100);
        let mut img = vec![10u8; w * h];
        let mut fill = |x0: usize, y0: usize, ww: usize, hh: usize| {
            for y in y0..y0 + hh {
                img[y * w + x0..y * w + x0 + ww].fill(220);
            }
        };
        fill(10, 10, 40, 2); // elongated bar (elongation 19)
        fill(60, 10, 50, 50); // too big (2500 px)
        fill(150, 50, 4, 4); // a good blob
        let mut det = BlobDetector::new(BlobConfig::default());
        let blobs = det.detect(&GrayImage::new(w, h, &img).unwrap(), None);
        assert_eq!(blobs.len(), 1);
        assert!((blobs[0].x - 151.5).abs() < 1e-9 && (blobs[0].y - 51.5).abs() < 1e-9);
        assert_eq!(blobs[0].area, 16);
    }

    /// A spot cut by each of the image's four edges is no blob (its centre would be pulled in by
    /// the cut); the same spot a few pixels inside is found at its centre.
    #[test]
    fn spots_cut_by_the_image_edge_are_not_blobs() {
        let mut det = BlobDetector::new(BlobConfig::default());
        for (x, y) in [(0.4, 200.0), (639.3, 150.0), (300.0, 0.6), (200.0, 479.5)] {
            let img = render_spots(
                640,
                480,
                15,
                &[(x, y, 1.5, 180.0), (320.0, 240.0, 1.5, 180.0)],
            );
            let blobs = det.detect(&GrayImage::new(640, 480, &img).unwrap(), None);
            assert_eq!(blobs.len(), 1, "spot at ({x}, {y})");
            assert!((blobs[0].x - 320.0).abs() < 0.1 && (blobs[0].y - 240.0).abs() < 0.1);
        }
        let img = render_spots(640, 480, 15, &[(8.0, 200.0, 1.5, 180.0)]);
        let blobs = det.detect(&GrayImage::new(640, 480, &img).unwrap(), None);
        assert_eq!(blobs.len(), 1);
        assert!((blobs[0].x - 8.0).abs() < 0.1, "{}", blobs[0].x);
    }

    #[test]
    fn window_agrees_with_full_frame_and_falls_back() {
        let spots = [
            (100.3, 200.7, 1.5, 180.0),
            (130.8, 210.2, 1.5, 180.0),
            (500.0, 400.0, 1.5, 180.0),
        ];
        let img = render_spots(640, 480, 15, &spots);
        let image = GrayImage::new(640, 480, &img).unwrap();
        let mut det = BlobDetector::new(BlobConfig::default());
        let full = det.detect(&image, None);
        let win = Rect::around(&[[100.3, 200.7], [130.8, 210.2]], 12.0, 640, 480);
        let mut out = Vec::new();
        assert_eq!(det.detect_into(&image, win, &mut out), SearchRegion::Window);
        assert_eq!(out.len(), 2);
        for b in &out {
            assert!(full.iter().any(|f| f.x == b.x && f.y == b.y));
        }
        // A window on empty sky falls back to the full frame.
        let empty = Some(Rect {
            x: 300,
            y: 10,
            width: 40,
            height: 40,
        });
        assert_eq!(
            det.detect_into(&image, empty, &mut out),
            SearchRegion::FullFrame
        );
        assert_eq!(out.len(), 3);
        // A window cutting through a blob falls back too.
        let cut = Some(Rect {
            x: 90,
            y: 190,
            width: 11,
            height: 30,
        });
        assert_eq!(
            det.detect_into(&image, cut, &mut out),
            SearchRegion::FullFrame
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        #[test]
        fn arbitrary_images_and_windows_never_panic(
            w in 1usize..80, h in 1usize..60, seed in 0u64..1000,
            wx in 0usize..100, wy in 0usize..100, ww in 0usize..100, wh in 0usize..100,
        ) {
            let mut rng = SplitMix64::new(seed);
            let img: Vec<u8> = (0..w * h).map(|_| (rng.next_u64() % 256) as u8).collect();
            let image = GrayImage::new(w, h, &img).unwrap();
            let mut det = BlobDetector::new(BlobConfig { threshold: 128, ..Default::default() });
            let blobs = det.detect(&image, Some(Rect { x: wx, y: wy, width: ww, height: wh }));
            for b in blobs {
                proptest::prop_assert!(b.x.is_finite() && b.y.is_finite());
                proptest::prop_assert!(b.x >= 0.0 && b.x < w as f64 && b.y >= 0.0 && b.y < h as f64);
            }
        }
    }

    #[test]
    fn rejects_short_buffers() {
        assert!(GrayImage::new(10, 10, &[0; 99]).is_err());
        assert!(GrayImage::with_stride(10, 2, 12, &[0; 22]).is_ok());
    }
}
#[cfg(test)]
mod noise_tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// Sensor noise of 2/4/8 grey levels on a 180-level spot (σ 1.3 px) over a level-20
    /// background: RMS centroid error (measured 0.023 / 0.046 / 0.095 px on 640x480).
    #[test]
    fn centroid_error_with_sensor_noise() {
        let mut rng = SplitMix64::new(5);
        let mut det = BlobDetector::new(BlobConfig::default());
        for (noise, limit) in [(2.0, 0.04), (4.0, 0.08)] {
            let (mut se, mut n) = (0.0, 0);
            for _ in 0..100 {
                let s = (
                    rng.uniform(20.0, 140.0),
                    rng.uniform(20.0, 100.0),
                    1.3,
                    180.0,
                );
                let mut img = render_spots(160, 120, 20, &[s]);
                for p in &mut img {
                    *p = (f64::from(*p) + noise * rng.gaussian())
                        .round()
                        .clamp(0.0, 255.0) as u8;
                }
                let b = det.detect(&GrayImage::new(160, 120, &img).unwrap(), None);
                if let Some(b) = b.first() {
                    se += (b.x - s.0).powi(2) + (b.y - s.1).powi(2);
                    n += 1;
                }
            }
            let rms = (se / f64::from(n)).sqrt();
            assert!(n == 100 && rms < limit, "noise {noise}: {rms} px over {n}");
        }
    }
}
