//! Cameras: pinhole projection with OpenCV distortion (through [`fires_record::CameraModel`], the same code the
//! host uses), per-frame exposure times with jitter, the sensor's timing (a free-running clock whose rate is off
//! nominal, a rolling shutter that exposes each row at its own time, and an exposure that smears a moving spot
//! along its path), LED visibility (field of view, emission cone, occlusion by the object and by the hand),
//! spurious spots (LED reflections on the object, sunlight), and the device output: a blob list (Wii-like
//! cameras) or an 8-bit image with blurred spots, background and sensor noise.
//!
//! Rendering cost is kept low: the background is copied from a pre-generated noise table at a random offset
//! (one `memcpy` per frame), and each spot is evaluated only in a window of about 3.5 sigma around it.

use crate::motion::{Pose, Scene};
use crate::objects::V3;
use crate::pen::Pen;
use crate::rng::SimRng;
use fires_record::{Blob, CalibratedCamera, GrayImage, LedTruth, Visibility};

/// The simulated hand: a sphere fixed in the pen frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandModel {
    /// Centre in the pen frame, metres.
    pub centre_pen: V3,
    /// Radius, metres.
    pub radius: f64,
}

/// Image formation parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageModel {
    /// Mean background level, DN.
    pub background: f64,
    /// Sensor noise standard deviation, DN.
    pub noise_sigma: f64,
    /// Peak spot level (before saturation) of an LED seen on its axis at 1 m, DN.
    pub gain: f64,
    /// LED emitter diameter, metres (sets the spot size with distance).
    pub led_diameter_m: f64,
    /// Optical blur sigma, pixels.
    pub blur_px: f64,
}

/// What the camera device delivers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraOutput {
    /// A list of at most `max_blobs` blobs (the brightest), centroids with Gaussian noise.
    Blobs {
        /// Most blobs per frame (4 for a Wii remote).
        max_blobs: usize,
        /// Centroid noise, pixels.
        centroid_noise_px: f64,
        /// Spot size model (for blob areas).
        image: ImageModel,
    },
    /// 8-bit images.
    Images(ImageModel),
}

impl CameraOutput {
    /// The image formation model.
    pub fn image_model(&self) -> &ImageModel {
        match self {
            CameraOutput::Blobs { image, .. } | CameraOutput::Images(image) => image,
        }
    }
}

/// When a sensor's pixels are exposed (docs/simulator.md, "Camera timing").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorTiming {
    /// Exposure time of each row, seconds: a moving spot is smeared along its image path over this time.
    pub exposure_s: f64,
    /// Rolling-shutter readout, seconds: row `y` of `height` is exposed `readout_s * y / height` after row 0
    /// (0: a global shutter).
    pub readout_s: f64,
    /// Relative error of the free-running frame clock: frames come at `rate_hz * (1 + rate_error)`.
    pub rate_error: f64,
}

impl SensorTiming {
    /// A global shutter with an instantaneous exposure and an exact clock (the Wii camera's model).
    pub const IDEAL: SensorTiming = SensorTiming {
        exposure_s: 0.0,
        readout_s: 0.0,
        rate_error: 0.0,
    };
}

/// One simulated camera.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraConfig {
    /// Calibration (the true one; it is also what the recording stores).
    pub cal: CalibratedCamera,
    /// Nominal frame rate, hertz.
    pub rate_hz: f64,
    /// Time of the first exposure, seconds of session time (the offset between the unsynchronised cameras).
    pub offset_s: f64,
    /// Jitter (standard deviation) of the true exposure times around the nominal grid, seconds.
    pub jitter_s: f64,
    /// Noise of the reported timestamp around the true exposure time, seconds.
    pub timestamp_noise_s: f64,
    /// Exposure, rolling shutter and clock rate.
    pub timing: SensorTiming,
    /// Device output.
    pub output: CameraOutput,
    /// Brightness (relative, 1 = on-axis at 1 m) below which an LED is not seen.
    pub min_brightness: f64,
    /// Probability per visible LED per frame of a reflection on the object.
    pub reflection_rate: f64,
    /// Mean number of sunlight spots per frame.
    pub sunlight_rate: f64,
}

/// A bright spot to render or report.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    /// Pixel position (at the middle of the exposure).
    pub px: [f64; 2],
    /// Peak level before saturation of the spot at rest, DN.
    pub peak: f64,
    /// Gaussian sigma, pixels.
    pub sigma: f64,
    /// How far the spot moves during the exposure, pixels: it is smeared evenly from `px - streak / 2` to
    /// `px + streak / 2` (zero for a still spot or an instantaneous exposure).
    pub streak: [f64; 2],
}

impl Spot {
    /// A still spot.
    pub fn still(px: [f64; 2], peak: f64, sigma: f64) -> Self {
        Spot {
            px,
            peak,
            sigma,
            streak: [0.0; 2],
        }
    }
}

/// What one exposure sees.
#[derive(Clone, Debug, PartialEq)]
pub struct Observation {
    /// Per LED.
    pub leds: Vec<LedTruth>,
    /// Spots of visible LEDs.
    pub led_spots: Vec<Spot>,
    /// Spurious spots.
    pub spurious: Vec<Spot>,
}

impl CameraConfig {
    /// Spot sigma (pixels) of an LED at distance `d` metres.
    fn spot_sigma(&self, d: f64) -> f64 {
        let m = self.output.image_model();
        let f = self.cal.intrinsics.fx;
        let r = f * m.led_diameter_m / (4.0 * d.max(1e-3));
        (m.blur_px * m.blur_px + r * r).sqrt()
    }

    /// The frame time at which frame `index` is exposed nominally (row 0), with the clock's rate error.
    pub fn nominal_frame_time(&self, index: u64) -> f64 {
        self.offset_s + index as f64 / (self.rate_hz * (1.0 + self.timing.rate_error))
    }

    /// Time after the frame time at which pixel row `y` is exposed (rolling shutter), seconds.
    pub fn row_delay(&self, y: f64) -> f64 {
        let h = f64::from(self.cal.intrinsics.height);
        self.timing.readout_s * y.clamp(0.0, h) / h
    }

    /// When LED `led` is exposed in the frame of time `t` (row 0) and where the pen is then: with a rolling
    /// shutter, the time of the row the LED images in, found by fixed-point iteration (the row moves far less
    /// than a row per readout step at drawing speeds, so three steps settle it to well under a microsecond).
    fn led_exposure(
        &self,
        t: f64,
        led: usize,
        pen: &Pen,
        pose_at: &dyn Fn(f64) -> Pose,
        frame_pose: &Pose,
    ) -> (f64, Pose) {
        if self.timing.readout_s == 0.0 {
            return (t, *frame_pose);
        }
        let mut s = t;
        let mut pose = *frame_pose;
        for _ in 0..3 {
            let p = pen.leds_world(&pose.tip, &pose.q)[led];
            let Some(px) = self.cal.project_world([p.x, p.y, p.z]) else {
                break;
            };
            let next = t + self.row_delay(px[1]);
            if (next - s).abs() < 1e-9 {
                break;
            }
            s = next;
            pose = pose_at(s);
        }
        (s, pose)
    }

    /// How far LED `led`'s image moves over the exposure centred on `s`, pixels.
    fn streak(&self, s: f64, led: usize, pen: &Pen, pose_at: &dyn Fn(f64) -> Pose) -> [f64; 2] {
        let half = 0.5 * self.timing.exposure_s;
        if half == 0.0 {
            return [0.0; 2];
        }
        let image = |t: f64| {
            let pose = pose_at(t);
            let p = pen.leds_world(&pose.tip, &pose.q)[led];
            self.cal.project_world([p.x, p.y, p.z])
        };
        match (image(s - half), image(s + half)) {
            (Some(a), Some(b)) => [b[0] - a[0], b[1] - a[1]],
            _ => [0.0; 2],
        }
    }

    /// Computes LED visibility and spots for the frame exposed at `t` (its first row), the pen moving as
    /// `pose_at` says: each LED is seen at its own row's time and smeared over the exposure.
    pub fn observe(
        &self,
        t: f64,
        pose_at: &dyn Fn(f64) -> Pose,
        pen: &Pen,
        scene: Option<&Scene>,
        hand: Option<&HandModel>,
        rng: &mut SimRng,
    ) -> Observation {
        let centre = V3::from(self.cal.extrinsics.centre_world());
        let frame_pose = pose_at(t);
        let gain = self.output.image_model().gain;
        let mut out = Observation {
            leds: Vec::with_capacity(pen.geometry.led_positions_m.len()),
            led_spots: Vec::new(),
            spurious: Vec::new(),
        };
        for i in 0..pen.geometry.led_positions_m.len() {
            let (s, pose) = self.led_exposure(t, i, pen, pose_at, &frame_pose);
            let led = pen.leds_world(&pose.tip, &pose.q)[i];
            let hand_world = hand.map(|h| (pose.tip + pose.q * h.centre_pen, h.radius));
            let pixel = self.cal.project_world([led.x, led.y, led.z]);
            let d = (centre - led).norm();
            let brightness = pen.intensity_towards(&led, &pose.q, &centre) / (d * d).max(1e-6);
            let visibility = if pen.disabled.get(i).copied().unwrap_or(false) {
                Visibility::Disabled
            } else if pixel.is_none() {
                Visibility::BehindCamera
            } else if !pixel.is_some_and(|p| self.cal.intrinsics.contains(p)) {
                Visibility::OutOfView
            } else if scene.is_some_and(|s| s.shape.blocks_segment(&led, &centre, 1e-4)) {
                Visibility::OccludedByObject
            } else if hand_world.is_some_and(|(c, r)| segment_hits_sphere(&led, &centre, &c, r)) {
                Visibility::OccludedByHand
            } else if brightness < self.min_brightness {
                Visibility::TooDim
            } else {
                Visibility::Visible
            };
            if let (Visibility::Visible, Some(px)) = (visibility, pixel) {
                out.led_spots.push(Spot {
                    px,
                    peak: gain * brightness,
                    sigma: self.spot_sigma(d),
                    streak: self.streak(s, i, pen, pose_at),
                });
                if let Some(sc) = scene {
                    if rng.chance(self.reflection_rate) {
                        if let Some(spot) = self.reflection(sc, &pose.tip, &led, gain * brightness)
                        {
                            out.spurious.push(spot);
                        }
                    }
                }
            }
            out.leds.push(LedTruth {
                pixel,
                visibility,
                brightness,
            });
        }
        let n_sun = poisson(rng, self.sunlight_rate);
        for _ in 0..n_sun {
            let w = f64::from(self.cal.intrinsics.width);
            let h = f64::from(self.cal.intrinsics.height);
            out.spurious.push(Spot::still(
                [rng.range(0.0, w - 1.0), rng.range(0.0, h - 1.0)],
                rng.range(0.3, 1.5) * 255.0,
                rng.range(0.8, 3.0),
            ));
        }
        out
    }

    /// A specular reflection of `led` in the object's tangent plane near the tip, if it lands in the image.
    fn reflection(&self, scene: &Scene, tip: &V3, led: &V3, peak: f64) -> Option<Spot> {
        let dist = scene.shape.sdf(tip);
        if dist.abs() > 0.05 {
            return None;
        }
        let n = scene.shape.normal(tip);
        let surface = tip - n * dist;
        let mirror = led - n * (2.0 * (led - surface).dot(&n));
        let px = self.cal.project_world([mirror.x, mirror.y, mirror.z])?;
        if !self.cal.intrinsics.contains(px) {
            return None;
        }
        let centre = V3::from(self.cal.extrinsics.centre_world());
        Some(Spot::still(
            px,
            0.3 * peak,
            self.spot_sigma((centre - mirror).norm()),
        ))
    }

    /// The device's blob list for an observation.
    pub fn blobs(&self, obs: &Observation, rng: &mut SimRng) -> Vec<Blob> {
        let (max_blobs, noise) = match self.output {
            CameraOutput::Blobs {
                max_blobs,
                centroid_noise_px,
                ..
            } => (max_blobs, centroid_noise_px),
            CameraOutput::Images(_) => (64, 0.2),
        };
        let threshold = 2.0 * self.output.image_model().noise_sigma.max(1.0)
            + self.output.image_model().background;
        let mut spots: Vec<&Spot> = obs
            .led_spots
            .iter()
            .chain(&obs.spurious)
            .filter(|s| s.peak > threshold)
            .collect();
        // The brightest first (stable: ties keep LED order), then report in x order like a sensor scan.
        spots.sort_by(|a, b| b.peak.total_cmp(&a.peak));
        spots.truncate(max_blobs);
        let mut out: Vec<Blob> = spots
            .into_iter()
            .map(|s| Blob {
                x: s.px[0] + rng.gauss(noise),
                y: s.px[1] + rng.gauss(noise),
                area: (std::f64::consts::PI * 4.0 * s.sigma * s.sigma)
                    .round()
                    .max(1.0),
                intensity: s.peak.min(255.0).round(),
            })
            .collect();
        out.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        out
    }
}

/// Whether the segment `a`-`b` passes through the sphere (`c`, `r`).
pub fn segment_hits_sphere(a: &V3, b: &V3, c: &V3, r: f64) -> bool {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 < 1e-24 {
        return (a - c).norm() < r;
    }
    let t = ((c - a).dot(&ab) / len2).clamp(0.0, 1.0);
    (a + ab * t - c).norm() < r
}

/// Poisson-distributed count (Knuth's method; fine for small means).
pub fn poisson(rng: &mut SimRng, mean: f64) -> u32 {
    if mean <= 0.0 {
        return 0;
    }
    let l = (-mean).exp();
    let mut k = 0;
    let mut p = 1.0;
    loop {
        p *= rng.uniform();
        if p <= l || k >= 1000 {
            return k;
        }
        k += 1;
    }
}

/// Pre-generated background noise for fast frame rendering.
#[derive(Clone, Debug)]
pub struct NoiseTable {
    data: Vec<u8>,
    frame_len: usize,
}

/// Number of distinct start offsets in the noise table.
const NOISE_OFFSETS: usize = 1 << 20;

impl NoiseTable {
    /// A table for `width x height` frames with the model's background and noise.
    pub fn new(width: u32, height: u32, m: &ImageModel, rng: &mut SimRng) -> Self {
        let frame_len = width as usize * height as usize;
        let data = (0..NOISE_OFFSETS + frame_len)
            .map(|_| {
                (m.background + rng.gauss(m.noise_sigma))
                    .round()
                    .clamp(0.0, 255.0) as u8
            })
            .collect();
        NoiseTable { data, frame_len }
    }

    /// Renders a frame: noise background plus Gaussian spots (saturating at 255).
    pub fn render(&self, width: u32, height: u32, spots: &[Spot], rng: &mut SimRng) -> GrayImage {
        let off = rng.below(NOISE_OFFSETS as u64) as usize;
        let mut img = GrayImage {
            width,
            height,
            data: self.data[off..off + self.frame_len].to_vec(),
        };
        for s in spots {
            draw_spot(&mut img, s);
        }
        img
    }
}

/// Adds a Gaussian spot to an image within a 3.5-sigma window; a streaked spot is the same energy spread evenly
/// along its streak (a sum of Gaussians at most half a sigma apart, which is smooth to 0.3% of the peak).
pub fn draw_spot(img: &mut GrayImage, s: &Spot) {
    let len = s.streak[0].hypot(s.streak[1]);
    let n = ((len / (0.5 * s.sigma)).ceil() as usize).clamp(1, 256);
    let r = (3.5 * s.sigma).ceil() + 1.0;
    let half = [0.5 * s.streak[0].abs(), 0.5 * s.streak[1].abs()];
    let (w, h) = (i64::from(img.width), i64::from(img.height));
    let x0 = ((s.px[0] - half[0] - r).floor() as i64).max(0);
    let x1 = ((s.px[0] + half[0] + r).ceil() as i64).min(w - 1);
    let y0 = ((s.px[1] - half[1] - r).floor() as i64).max(0);
    let y1 = ((s.px[1] + half[1] + r).ceil() as i64).min(h - 1);
    let k = -0.5 / (s.sigma * s.sigma);
    // Sample centres evenly inside the streak (the midpoint rule), each with 1/n of the energy.
    let centres: Vec<[f64; 2]> = (0..n)
        .map(|j| {
            let f = if n == 1 {
                0.0
            } else {
                (j as f64 + 0.5) / n as f64 - 0.5
            };
            [s.px[0] + f * s.streak[0], s.px[1] + f * s.streak[1]]
        })
        .collect();
    let peak = s.peak / n as f64;
    for y in y0..=y1 {
        for x in x0..=x1 {
            let v: f64 = centres
                .iter()
                .map(|c| {
                    let (dx, dy) = (x as f64 - c[0], y as f64 - c[1]);
                    peak * ((dx * dx + dy * dy) * k).exp()
                })
                .sum();
            let idx = (y * w + x) as usize;
            let cur = f64::from(img.data[idx]);
            img.data[idx] = (cur + v).round().min(255.0) as u8;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::trajectory::orientation_from_axis;
    use crate::objects::ObjectKind;
    use fires_record::{CameraModel, Extrinsics};

    fn camera() -> CameraConfig {
        let image = ImageModel {
            background: 10.0,
            noise_sigma: 0.0,
            gain: 500.0,
            led_diameter_m: 0.005,
            blur_px: 1.0,
        };
        CameraConfig {
            cal: CalibratedCamera {
                intrinsics: CameraModel::from_hfov(640, 480, 1.0),
                extrinsics: Extrinsics::IDENTITY,
            },
            rate_hz: 15.0,
            offset_s: 0.0,
            jitter_s: 0.0,
            timestamp_noise_s: 0.0,
            timing: SensorTiming::IDEAL,
            output: CameraOutput::Images(image),
            min_brightness: 0.02,
            reflection_rate: 0.0,
            sunlight_rate: 0.0,
        }
    }

    /// A pen standing still at `p`.
    fn still(p: Pose) -> impl Fn(f64) -> Pose {
        move |_| p
    }

    /// The pen 1 m in front of the camera, pointing away from it (LEDs facing the camera).
    fn pose(tip: V3) -> Pose {
        Pose {
            tip,
            q: orientation_from_axis(&V3::z(), 0.0),
        }
    }

    #[test]
    fn leds_behind_an_object_or_the_hand_are_occluded() {
        let cam = camera();
        let pen = Pen::fires_default();
        let mut rng = SimRng::stream(1, 1);
        let p = pose(V3::new(0.0, 0.0, 1.0));
        let free = cam.observe(0.0, &still(p), &pen, None, None, &mut rng);
        assert!(free
            .leds
            .iter()
            .all(|l| l.visibility == Visibility::Visible));
        assert_eq!(free.led_spots.len(), 4);
        // A sphere between the pen and the camera hides every LED.
        let shape = ObjectKind::Sphere.build(V3::new(0.0, 0.0, 0.5), 0.05, V3::new(0.0, -1.0, 0.0));
        let scene = Scene::new(shape, V3::z(), V3::new(0.0, -1.0, 0.0), V3::zeros(), 0.02);
        let hidden = cam.observe(0.0, &still(p), &pen, Some(&scene), None, &mut rng);
        assert!(hidden
            .leds
            .iter()
            .all(|l| l.visibility == Visibility::OccludedByObject));
        // A hand sphere on the camera side of LED 2 hides LED 2 only.
        let led2 = pen.leds_pen_frame()[1];
        // Pen off the optical axis, hand 3 cm from LED 2 on the line to the camera.
        let p = pose(V3::new(0.3, 0.0, 1.0));
        let led2_world = p.tip + p.q * led2;
        let h_world = led2_world + (V3::zeros() - led2_world).normalize() * 0.03;
        let hand = HandModel {
            centre_pen: p.q.inverse() * (h_world - p.tip),
            radius: 0.01,
        };
        let o = cam.observe(0.0, &still(p), &pen, None, Some(&hand), &mut rng);
        let vis: Vec<_> = o.leds.iter().map(|l| l.visibility).collect();
        assert_eq!(vis[1], Visibility::OccludedByHand);
        assert_eq!(vis[0], Visibility::Visible);
        assert_eq!(vis[2], Visibility::Visible);
        // Brightness falls with the square of the distance.
        let far = cam.observe(
            0.0,
            &still(pose(V3::new(0.0, 0.0, 2.0))),
            &pen,
            None,
            None,
            &mut rng,
        );
        let ratio = free.leds[0].brightness / far.leds[0].brightness;
        let (d1, d2) = (1.0 - 0.02, 2.0 - 0.02);
        assert!((ratio - (d2 * d2) / (d1 * d1)).abs() < 1e-9);
    }

    #[test]
    fn spots_are_rendered_where_the_leds_project() {
        let cam = camera();
        let mut rng = SimRng::stream(2, 2);
        let table = NoiseTable::new(640, 480, cam.output.image_model(), &mut rng);
        let spot = Spot::still([100.3, 200.7], 150.0, 1.5);
        let img = table.render(640, 480, &[spot], &mut rng);
        let at = |x: usize, y: usize| img.data[y * 640 + x];
        assert_eq!(
            at(100, 201),
            10 + (150.0f64 * (-(0.09 + 0.09) / 4.5f64).exp()).round() as u8
        );
        assert_eq!(at(10, 10), 10);
        // Intensity-weighted centroid of the background-subtracted window is the spot centre.
        let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
        for y in 190..212 {
            for x in 90..112 {
                let w = f64::from(at(x, y)) - 10.0;
                sx += w * x as f64;
                sy += w * y as f64;
                sw += w;
            }
        }
        assert!((sx / sw - 100.3).abs() < 0.05 && (sy / sw - 200.7).abs() < 0.05);
    }

    #[test]
    fn poisson_has_the_right_mean() {
        let mut rng = SimRng::stream(3, 3);
        let n = 20_000;
        let total: u32 = (0..n).map(|_| poisson(&mut rng, 0.3)).sum();
        assert!((f64::from(total) / f64::from(n) - 0.3).abs() < 0.02);
        assert_eq!(poisson(&mut rng, 0.0), 0);
    }
}
