//! Ground-truth types (`truth/`): present only in simulated recordings.

use fires_protocol::Frame;
use serde::{Deserialize, Serialize};

/// Pose of the pen at one instant, in the world frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseTruth {
    /// Tip position, metres.
    pub tip_m: [f64; 3],
    /// Orientation pen -> world as a unit quaternion `[x, y, z, w]`.
    pub orientation_xyzw: [f64; 4],
    /// World position of every LED (LED 1 first), metres.
    pub leds_m: Vec<[f64; 3]>,
}

/// Ground truth at one IMU sample (one line of `truth/imu.jsonl`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImuTruth {
    /// Sample index since the pen started streaming (the packet counter is this modulo 256).
    pub sample_index: u64,
    /// Packet counter of this sample.
    pub counter: u8,
    /// Pen device clock at the sample, microseconds (not wrapped).
    pub device_time_us: u64,
    /// Host-clock time at which the sample was taken, nanoseconds.
    pub time_ns: u64,
    /// Pen pose.
    pub pose: PoseTruth,
    /// Ideal specific force in the pen frame (gravity included), m/s^2, before bias, noise and quantisation.
    pub specific_force_mps2: [f64; 3],
    /// Ideal angular velocity in the pen frame, rad/s, before bias and noise.
    pub angular_velocity_radps: [f64; 3],
    /// Ideal Earth field in the pen frame, tesla, before hard/soft iron and noise.
    pub earth_field_t: [f64; 3],
    /// Gyro bias at this sample, rad/s.
    pub gyro_bias_radps: [f64; 3],
    /// Mode buttons pressed (bit i = button i+1).
    pub buttons: u8,
}

/// Why an LED is or is not seen by a camera in one exposure (the first reason that applies, in declaration
/// order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Visibility {
    /// Seen.
    Visible,
    /// Never rendered (disabled by the scenario, e.g. LED 1 in `tip`).
    Disabled,
    /// Behind the camera.
    BehindCamera,
    /// Projects outside the image.
    OutOfView,
    /// Emission cone points away from the camera (too dim).
    TooDim,
    /// The target object is between the LED and the camera.
    OccludedByObject,
    /// The simulated hand is between the LED and the camera.
    OccludedByHand,
}

/// One LED in one exposure.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LedTruth {
    /// Exact projected pixel (distorted), if in front of the camera.
    pub pixel: Option<[f64; 2]>,
    /// Visibility.
    pub visibility: Visibility,
    /// Relative brightness (1 = on axis at 1 m), before saturation.
    pub brightness: f64,
}

/// Ground truth of one camera exposure (one line of `truth/exposures.jsonl`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExposureTruth {
    /// Camera id.
    pub camera: u8,
    /// Frame index (matches the frame stream).
    pub index: u64,
    /// True mid-exposure time, host clock, nanoseconds (the frame stream carries the reported, jittered one).
    pub exposure_time_ns: u64,
    /// Pen pose at the exposure.
    pub pose: PoseTruth,
    /// Per LED, LED 1 first.
    pub leds: Vec<LedTruth>,
    /// Pixel positions of spurious spots (reflections, sunlight) in this frame.
    pub spurious: Vec<[f64; 2]>,
}

/// What happened to one packet the pen produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PacketFate {
    /// All 22 bytes arrived unchanged.
    Delivered,
    /// Dropped on the pen (backpressure): never sent, counter consumed.
    PenDropped,
    /// Lost whole in the radio.
    Lost,
    /// Sent while the link was disconnected.
    Disconnected,
    /// Arrived with at least one byte dropped or corrupted.
    Damaged,
}

/// One packet produced by the pen (one line of `truth/packets.jsonl`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PacketTruth {
    /// Host-clock time at which the first byte left the pen's UART (or would have), nanoseconds.
    pub send_time_ns: u64,
    /// The packet.
    pub frame: Frame,
    /// Its fate.
    pub fate: PacketFate,
}

/// Role of a stroke in the curve network.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StrokeKind {
    /// The closed boundary loop (drawn first).
    Boundary,
    /// A curve starting and ending on earlier curves, crossing others.
    Crossing,
}

/// One drawn stroke (element of `truth/strokes.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokeTruth {
    /// Stroke id, 0-based in drawing order.
    pub id: u32,
    /// Role in the network.
    pub kind: StrokeKind,
    /// Host-clock time of the button press (tip touches down), nanoseconds.
    pub start_time_ns: u64,
    /// Host-clock time of the button release, nanoseconds (the end of the recording if `complete` is false).
    pub end_time_ns: u64,
    /// False when the recording ends before the button release (the last stroke may be cut off).
    pub complete: bool,
    /// Id of the earlier stroke the start point lies on (None for the boundary).
    pub starts_on: Option<u32>,
    /// Id of the earlier stroke the end point lies on (None for the boundary).
    pub ends_on: Option<u32>,
    /// Ids of earlier strokes crossed in the interior.
    pub crosses: Vec<u32>,
    /// True tip polyline, metres, sampled every 10 ms of drawing (first and last point exact).
    pub tip_polyline_m: Vec<[f64; 3]>,
    /// Pen mode held while drawing (the mode buttons, `buttons >> 1`; 0: curve insertion). Absent in
    /// files written before modes were simulated: 0.
    #[serde(default)]
    pub mode: u8,
}

/// A link disconnection interval.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    /// Start, host clock, nanoseconds.
    pub start_ns: u64,
    /// End, host clock, nanoseconds.
    pub end_ns: u64,
}

/// Session-wide ground truth (`truth/world.json`): the physical constants the simulator used.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorldTruth {
    /// Gravitational acceleration in the world frame, m/s^2 (points down).
    pub gravity_world_mps2: [f64; 3],
    /// Earth magnetic field in the world frame, tesla.
    pub earth_field_world_t: [f64; 3],
    /// Magnetometer hard-iron offset in the pen frame, tesla.
    pub hard_iron_t: [f64; 3],
    /// Magnetometer soft-iron matrix, row-major (`m = S * b_body + hard_iron`).
    pub soft_iron: [[f64; 3]; 3],
    /// Accelerometer bias, m/s^2.
    pub accel_bias_mps2: [f64; 3],
    /// Pen clock rate error: device seconds per host second minus one, parts per million.
    pub pen_clock_drift_ppm: f64,
    /// Host-clock time of device time 0, nanoseconds.
    pub pen_clock_origin_ns: u64,
    /// Link disconnections.
    pub disconnects: Vec<Interval>,
    /// Target object description (free text, e.g. `sphere r=0.100 at [..]`).
    pub object: String,
    /// The target object as data (kind, pose, size, shape parameters) and the scene the strokes were planned
    /// in; absent in recordings written before it existed and in sessions without an object.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target: Option<TargetTruth>,
}

/// The target object and the drawing scene (`target` in `truth/world.json`; docs/recording.md).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetTruth {
    /// The object's geometry.
    pub object: ObjectTruth,
    /// The parameter plane the simulator planned the strokes in.
    pub scene: SceneTruth,
}

/// A target object's geometry, tagged by `kind`; every length in metres, every direction a unit vector in the
/// world frame. The formulas are the simulator's (`sim/src/objects/`), repeated in docs/recording.md.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ObjectTruth {
    /// `|p - centre| = radius`.
    Sphere {
        /// Centre, metres.
        centre_m: [f64; 3],
        /// Radius, metres.
        radius_m: f64,
    },
    /// A solid cylinder with flat caps: radial distance from the axis `radius`, axial `|h| <= half_length`.
    Cylinder {
        /// Centre of the axis segment, metres.
        centre_m: [f64; 3],
        /// Unit axis direction.
        axis: [f64; 3],
        /// Radius, metres.
        radius_m: f64,
        /// Half the length along the axis, metres.
        half_length_m: f64,
    },
    /// A box with rounded edges: the box of half extents `half_extents - rounding` grown by a ball of radius
    /// `rounding`, turned by `yaw` about `up` (box axes: y = -up, z = world z made perpendicular to y, x = y × z,
    /// then the yaw about y).
    RoundedBox {
        /// Centre, metres.
        centre_m: [f64; 3],
        /// Half extents along the box axes, including the rounding, metres.
        half_extents_m: [f64; 3],
        /// Edge rounding radius, metres.
        rounding_m: f64,
        /// World up (unit; the box's local y is `-up`).
        up: [f64; 3],
        /// Turn about the box's local y axis, radians.
        yaw_rad: f64,
    },
    /// A star-shaped blob: in the direction `u` from the centre the surface lies at
    /// `R(u) = mean_radius (1 + 0.12 sin(3 u_x + 1) sin(2 u_y) + 0.08 cos(4 u_z - 0.5) + 0.06 sin(5 u_x u_y))`.
    Blob {
        /// Centre, metres.
        centre_m: [f64; 3],
        /// Mean radius, metres.
        mean_radius_m: f64,
    },
}

/// The parameter plane of the drawing (the simulator's `Scene`): plane point `(u, v)` lies under the world
/// point `origin + u e1 + v e2`, and is lifted onto the object by a ray along `view`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneTruth {
    /// Unit viewing direction, from the cameras into the scene.
    pub view: [f64; 3],
    /// First in-plane axis (unit, perpendicular to `view`).
    pub e1: [f64; 3],
    /// Second in-plane axis (unit, `e1 = e2 × view`).
    pub e2: [f64; 3],
    /// Origin of the plane, metres (the centre of the object's bounding sphere).
    pub origin_m: [f64; 3],
    /// Radius of the planning disc in the plane, metres.
    pub rho_m: f64,
    /// Where the user's eye is, metres (the mean of the camera centres; the pen leans towards it).
    pub eye_m: [f64; 3],
    /// World up (unit).
    pub up: [f64; 3],
}
