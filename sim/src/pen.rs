//! The pen: LED geometry along the axis, tip offset, and the LEDs' emission cone.
//!
//! Pen frame (docs/architecture.md §2): origin at the tip, +x along the axis from the back towards the tip. LED `i` is at
//! `x = -(tip_offset + l_i)`. The LEDs face backwards (along -x, away from the tip, towards a user-facing camera
//! rig); brightness falls off as `cos(theta)^exponent` with the angle `theta` between -x and the direction to the
//! camera and is zero beyond `cutoff_deg`.

use fires_record::PenGeometry;
use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Emission pattern of an LED.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EmissionCone {
    /// Exponent of the cosine falloff (1 = Lambertian, larger = narrower).
    pub exponent: f64,
    /// Angle off the emission axis beyond which nothing is emitted, degrees.
    pub cutoff_deg: f64,
}

impl Default for EmissionCone {
    fn default() -> Self {
        // A wide-angle IR LED (half power at about 60 degrees), nothing beyond 100 degrees.
        EmissionCone {
            exponent: 1.0,
            cutoff_deg: 100.0,
        }
    }
}

impl EmissionCone {
    /// Relative intensity (0..=1) towards a direction at `angle_rad` off the emission axis.
    pub fn intensity(&self, angle_rad: f64) -> f64 {
        if angle_rad.to_degrees() > self.cutoff_deg {
            return 0.0;
        }
        // Beyond 90 degrees the LED's side still leaks a little light; keep a floor until the cutoff.
        angle_rad.cos().max(0.05).powf(self.exponent)
    }
}

/// The simulated pen.
#[derive(Clone, Debug, PartialEq)]
pub struct Pen {
    /// Geometry written to the recording.
    pub geometry: PenGeometry,
    /// Emission cone of every LED.
    pub cone: EmissionCone,
    /// LEDs that are never rendered (e.g. LED 1 in the `tip` scenario).
    pub disabled: Vec<bool>,
    /// Pen body radius, metres (for the simulated hand placement).
    pub body_radius_m: f64,
}

impl Pen {
    /// The FIRES pen with all LEDs enabled.
    pub fn fires_default() -> Self {
        Pen::new(PenGeometry::fires_default())
    }

    /// A pen with the given geometry, default cone, all LEDs enabled.
    pub fn new(geometry: PenGeometry) -> Self {
        let n = geometry.led_positions_m.len();
        Pen {
            geometry,
            cone: EmissionCone::default(),
            disabled: vec![false; n],
            body_radius_m: 0.008,
        }
    }

    /// Number of LEDs.
    pub fn led_count(&self) -> usize {
        self.geometry.led_positions_m.len()
    }

    /// LED positions in the pen frame.
    pub fn leds_pen_frame(&self) -> Vec<Vector3<f64>> {
        self.geometry
            .led_positions_m
            .iter()
            .map(|l| Vector3::new(-(self.geometry.tip_offset_m + l), 0.0, 0.0))
            .collect()
    }

    /// LED positions in the world for a pose (tip position, pen -> world rotation).
    pub fn leds_world(&self, tip: &Vector3<f64>, q: &UnitQuaternion<f64>) -> Vec<Vector3<f64>> {
        self.leds_pen_frame().iter().map(|p| tip + q * p).collect()
    }

    /// Relative intensity of an LED seen from `eye` (world), for the pen at orientation `q`.
    pub fn intensity_towards(
        &self,
        led: &Vector3<f64>,
        q: &UnitQuaternion<f64>,
        eye: &Vector3<f64>,
    ) -> f64 {
        let axis = q * Vector3::new(-1.0, 0.0, 0.0);
        let to_eye = eye - led;
        let n = to_eye.norm();
        if n < 1e-12 {
            return 0.0;
        }
        let c = (axis.dot(&to_eye) / n).clamp(-1.0, 1.0);
        self.cone.intensity(c.acos())
    }
}
