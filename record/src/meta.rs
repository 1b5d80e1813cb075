//! Recording metadata (`meta.json`): rig calibration, pen geometry, board scale factors, stream descriptions.

use fires_protocol::ScaleFactors;
use serde::{Deserialize, Serialize};

/// Name written in `meta.json`'s `format` field.
pub const FORMAT_NAME: &str = "fires-recording";
/// Format version this crate writes (`MAJOR.MINOR`); readers accept any minor of the same major.
pub const FORMAT_VERSION: &str = "1.2";
/// Major version this crate reads.
pub const FORMAT_MAJOR: u32 = 1;

/// Pinhole intrinsics with OpenCV's distortion model (k1, k2, p1, p2, k3), pixel centres at integer coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraModel {
    /// Image width in pixels (the reported resolution, e.g. 1024 for a Wii camera).
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// Radial distortion r^2 coefficient.
    pub k1: f64,
    /// Radial distortion r^4 coefficient.
    pub k2: f64,
    /// Tangential distortion coefficient p1.
    pub p1: f64,
    /// Tangential distortion coefficient p2.
    pub p2: f64,
    /// Radial distortion r^6 coefficient.
    pub k3: f64,
}

impl CameraModel {
    /// An undistorted camera with the given horizontal field of view (radians), square pixels, centred principal point.
    pub fn from_hfov(width: u32, height: u32, hfov_rad: f64) -> Self {
        let f = f64::from(width) / 2.0 / (hfov_rad / 2.0).tan();
        CameraModel {
            width,
            height,
            fx: f,
            fy: f,
            cx: (f64::from(width) - 1.0) / 2.0,
            cy: (f64::from(height) - 1.0) / 2.0,
            k1: 0.0,
            k2: 0.0,
            p1: 0.0,
            p2: 0.0,
            k3: 0.0,
        }
    }

    /// Applies the OpenCV distortion to normalised image coordinates (x = X/Z, y = Y/Z).
    pub fn distort_normalized(&self, x: f64, y: f64) -> [f64; 2] {
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
        let xd = x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x);
        let yd = y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y;
        [xd, yd]
    }

    /// Projects a point given in this camera's frame (OpenCV: x right, y down, z forward) to distorted pixel
    /// coordinates; `None` when the point is not in front of the camera.
    pub fn project(&self, p_cam: [f64; 3]) -> Option<[f64; 2]> {
        // Also rejects NaN depths.
        if p_cam[2].is_nan() || p_cam[2] <= 1e-9 {
            return None;
        }
        let [xd, yd] = self.distort_normalized(p_cam[0] / p_cam[2], p_cam[1] / p_cam[2]);
        Some([self.fx * xd + self.cx, self.fy * yd + self.cy])
    }

    /// True when every distortion coefficient is zero (a pure pinhole).
    pub fn is_pinhole(&self) -> bool {
        self.k1 == 0.0 && self.k2 == 0.0 && self.p1 == 0.0 && self.p2 == 0.0 && self.k3 == 0.0
    }

    /// Mean focal length in pixels (converts normalised distances to pixels).
    pub fn focal_px(&self) -> f64 {
        0.5 * (self.fx + self.fy)
    }

    /// Pixel to distorted normalised coordinates (no distortion removal).
    pub fn pixel_to_distorted(&self, px: [f64; 2]) -> [f64; 2] {
        [(px[0] - self.cx) / self.fx, (px[1] - self.cy) / self.fy]
    }

    /// Pixel to undistorted normalised image coordinates `m = K^-1 [u, v, 1]^T` with the distortion removed:
    /// the inverse of [`Self::project`], by fixed-point iteration as OpenCV's `undistortPoints`, checked by
    /// distorting the result again (an error when it does not come back within 1e-3 px).
    pub fn undistort(&self, px: [f64; 2]) -> Result<[f64; 2], UndistortError> {
        if !(px[0].is_finite() && px[1].is_finite()) {
            return Err(UndistortError::NonFinite);
        }
        let [xd, yd] = self.pixel_to_distorted(px);
        if self.is_pinhole() {
            return Ok([xd, yd]);
        }
        let (mut x, mut y) = (xd, yd);
        for _ in 0..30 {
            let r2 = x * x + y * y;
            let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
            let dx = 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x);
            let dy = self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y;
            if radial.abs() < 1e-12 {
                return Err(UndistortError::Diverged);
            }
            x = (xd - dx) / radial;
            y = (yd - dy) / radial;
        }
        let [rx, ry] = self.distort_normalized(x, y);
        let err = ((rx - xd).powi(2) + (ry - yd).powi(2)).sqrt() * self.focal_px();
        if !(x.is_finite() && y.is_finite()) || err > 1e-3 {
            return Err(UndistortError::Diverged);
        }
        Ok([x, y])
    }

    /// Whether a pixel position lies on the sensor (within half a pixel of the outermost pixel centres).
    pub fn contains(&self, px: [f64; 2]) -> bool {
        px[0] >= -0.5
            && px[1] >= -0.5
            && px[0] < f64::from(self.width) - 0.5
            && px[1] < f64::from(self.height) - 0.5
    }
}

/// Why a pixel cannot be mapped back to normalised image coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum UndistortError {
    /// A pixel coordinate is NaN or infinite.
    #[error("non-finite pixel")]
    NonFinite,
    /// The iteration did not converge (a pixel far outside the calibrated field).
    #[error("undistortion did not converge")]
    Diverged,
}

/// Rigid transform from the world frame to a camera frame: `x_cam = rotation * x_world + translation_m`
/// (OpenCV's `R`, `t`; `rotation` is row-major).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Extrinsics {
    /// Rotation matrix, row-major, world -> camera.
    pub rotation: [[f64; 3]; 3],
    /// Translation in metres, world -> camera.
    pub translation_m: [f64; 3],
}

impl Extrinsics {
    /// The identity (the camera that defines the world frame).
    pub const IDENTITY: Extrinsics = Extrinsics {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation_m: [0.0; 3],
    };

    /// Maps a world point into the camera frame.
    pub fn world_to_camera(&self, p: [f64; 3]) -> [f64; 3] {
        let r = &self.rotation;
        let t = &self.translation_m;
        [
            r[0][0] * p[0] + r[0][1] * p[1] + r[0][2] * p[2] + t[0],
            r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2] + t[1],
            r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2] + t[2],
        ]
    }

    /// The camera centre in world coordinates (`-R^T t`).
    pub fn centre_world(&self) -> [f64; 3] {
        let r = &self.rotation;
        let t = &self.translation_m;
        let mut c = [0.0; 3];
        for (j, cj) in c.iter_mut().enumerate() {
            *cj = -(r[0][j] * t[0] + r[1][j] * t[1] + r[2][j] * t[2]);
        }
        c
    }
}

/// One calibrated camera of the rig.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CalibratedCamera {
    /// Intrinsics and distortion.
    pub intrinsics: CameraModel,
    /// World -> camera transform (identity for camera 0, which defines the world frame).
    pub extrinsics: Extrinsics,
}

impl CalibratedCamera {
    /// Projects a world point to distorted pixel coordinates (`None` behind the camera).
    pub fn project_world(&self, p_world: [f64; 3]) -> Option<[f64; 2]> {
        self.intrinsics
            .project(self.extrinsics.world_to_camera(p_world))
    }
}

/// Calibration of the stereo rig: camera 0 is the left camera and defines the world frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RigCalibration {
    /// The cameras, indexed by camera id.
    pub cameras: Vec<CalibratedCamera>,
}

/// Geometry of the pen. Pen frame: origin at the tip, +x along the axis from the back towards the tip.
/// LED `i` sits at `x = -(tip_offset_m + led_positions_m[i])`, `y = z = 0`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PenGeometry {
    /// Axial position of each LED measured from LED 1 away from the tip (LED 1 first, `led_positions_m[0] = 0`).
    pub led_positions_m: Vec<f64>,
    /// Distance from LED 1 to the pen tip, metres.
    pub tip_offset_m: f64,
    /// Where the accelerometer sits in the pen frame, metres, when the recording says (format 1.2):
    /// the lever from it to the tip turns the pen's rotation into tip acceleration the accelerometer
    /// does not feel (`ω̇ × r + ω × (ω × r)`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub imu_position_m: Option<[f64; 3]>,
}

impl PenGeometry {
    /// The FIRES pen: spacings 70/40/50 mm, so LEDs at 0, 70, 110, 160 mm; tip 20 mm beyond LED 1; the
    /// board's accelerometer on the axis 100 mm behind the tip (hardware-docs/pen-geometry.md).
    pub fn fires_default() -> Self {
        PenGeometry {
            led_positions_m: vec![0.0, 0.070, 0.110, 0.160],
            tip_offset_m: 0.020,
            imu_position_m: Some([-0.100, 0.0, 0.0]),
        }
    }

    /// Position of LED `i` in the pen frame (`None` if there is no such LED).
    pub fn led_in_pen_frame(&self, i: usize) -> Option<[f64; 3]> {
        self.led_positions_m
            .get(i)
            .map(|l| [-(self.tip_offset_m + l), 0.0, 0.0])
    }
}

/// Serial link parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinkInfo {
    /// UART rate between the pen's MCU and its radio, baud (8N1).
    pub baud: u32,
    /// Nominal sensor packet rate, hertz.
    pub sample_rate_hz: u32,
}

/// What a camera's frame stream carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameContent {
    /// Blob lists only (as a Wii remote's camera reports): the host uses them directly.
    Blobs,
    /// 8-bit images only (binary PGM): the host's blob detector must process them.
    Images,
}

/// Description of one camera's frame stream.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraStream {
    /// Camera id (index into `rig.cameras`); frames live in `cam{id}/`.
    pub id: u8,
    /// What the frames carry.
    pub provides: FrameContent,
    /// Nominal frame rate, hertz.
    pub nominal_rate_hz: f64,
    /// Exposure time of one row, seconds (0: unknown or negligible). A frame's `exposure_time_ns` is the middle
    /// of its first row's exposure, so a moving spot is smeared symmetrically about that time's position.
    #[serde(default)]
    pub exposure_s: f64,
    /// Rolling-shutter readout, seconds: row `y` (of `height`) is exposed `readout_s * y / height` after the first
    /// row (0: a global shutter, every row at the frame time). Format 1.1; absent in 1.0 files.
    #[serde(default)]
    pub readout_s: f64,
    /// Standard deviation of the frames' exposure times about their period, seconds (0 for a free-running
    /// camera's crystal clock, or unknown). Format 1.1, optional.
    #[serde(default)]
    pub exposure_jitter_s: f64,
    /// Standard deviation of the recorded `exposure_time_ns` about the true exposure time, seconds (a webcam
    /// stamped by the host on USB arrival: about 1 ms; 0: exact or unknown, and the tracker uses the stamps as
    /// they are). Format 1.1, optional.
    #[serde(default)]
    pub timestamp_noise_s: f64,
}

impl CameraStream {
    /// A global-shutter stream with negligible exposure (the format 1.0 meaning).
    pub fn global(id: u8, provides: FrameContent, nominal_rate_hz: f64) -> Self {
        CameraStream {
            id,
            provides,
            nominal_rate_hz,
            exposure_s: 0.0,
            readout_s: 0.0,
            exposure_jitter_s: 0.0,
            timestamp_noise_s: 0.0,
        }
    }

    /// The rolling-shutter delay of one pixel row after the previous, seconds, for a sensor of `height` rows
    /// (0 for a global shutter).
    pub fn row_period_s(&self, height: u32) -> f64 {
        if height == 0 {
            0.0
        } else {
            self.readout_s / f64::from(height)
        }
    }
}

/// Where a recording came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Source {
    /// `"simulator"` or `"hardware"` (free text).
    pub kind: String,
    /// Simulator scenario name, if simulated.
    pub scenario: Option<String>,
    /// Simulator seed, if simulated.
    pub seed: Option<u64>,
    /// Producing program and version, free text.
    pub generator: Option<String>,
}

/// Contents of `meta.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Meta {
    /// Always [`FORMAT_NAME`].
    pub format: String,
    /// `MAJOR.MINOR`; see [`FORMAT_VERSION`].
    pub format_version: String,
    /// Provenance.
    pub source: Source,
    /// Stereo rig calibration.
    pub rig: RigCalibration,
    /// Pen geometry.
    pub pen: PenGeometry,
    /// Board scale factors (raw counts -> SI).
    pub scale_factors: ScaleFactors,
    /// Link parameters.
    pub link: LinkInfo,
    /// One entry per camera stream.
    pub cameras: Vec<CameraStream>,
    /// Whether a `truth/` directory with ground truth is present.
    pub has_truth: bool,
}

impl Meta {
    /// A metadata record with the current format name and version.
    pub fn new(
        source: Source,
        rig: RigCalibration,
        pen: PenGeometry,
        cameras: Vec<CameraStream>,
        has_truth: bool,
    ) -> Self {
        Meta {
            format: FORMAT_NAME.to_string(),
            format_version: FORMAT_VERSION.to_string(),
            source,
            rig,
            pen,
            scale_factors: ScaleFactors::FIRES_PEN,
            link: LinkInfo {
                baud: fires_protocol::LINK_BAUD,
                sample_rate_hz: fires_protocol::SAMPLE_RATE_HZ,
            },
            cameras,
            has_truth,
        }
    }
}
