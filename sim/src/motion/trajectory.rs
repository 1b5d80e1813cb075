//! The time-parametrised pen pose: tip position and orientation as smooth functions of time.
//!
//! A trajectory is a chain of segments, each a function of time:
//! - `Hold`: the pen at rest;
//! - `Move`: a rest-to-rest minimum-jerk move of the tip with a minimum-jerk slerp of the orientation (pen-up
//!   moves, touch-down and lift-off, and the free motion of the `bar` and `tip` scenarios);
//! - `Draw`: the tip follows a planned curve on the object (minimum-jerk progress along the curve parameter, so
//!   speed and acceleration start and end at zero), the pen tilted 20-60 degrees from the surface normal towards
//!   the user's eye, with a slow roll about its axis. The button is held for exactly the duration of the segment.
//!
//! Every segment starts and ends at rest, so position, velocity and acceleration are continuous everywhere; the
//! IMU model differentiates the pose numerically.

use crate::motion::network::{PlannedStroke, Scene};
use crate::objects::V3;
use crate::rng::SimRng;
use nalgebra::{Unit, UnitQuaternion, Vector3};
use std::f64::consts::PI;
use std::sync::Arc;

/// Pen pose: tip position and pen -> world rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Tip, world, metres.
    pub tip: V3,
    /// Pen -> world rotation.
    pub q: UnitQuaternion<f64>,
}

/// Minimum-jerk progress `10 t^3 - 15 t^4 + 6 t^5` for `t` in [0, 1] (clamped).
pub fn min_jerk(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * t * (10.0 + t * (-15.0 + 6.0 * t))
}

/// Orientation whose pen +x axis is `x` (unit), rolled by `roll` about it.
pub fn orientation_from_axis(x: &V3, roll: f64) -> UnitQuaternion<f64> {
    // Pen +x -> world +z, then the shortest rotation from +z to x, then the roll about x.
    let base = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -PI / 2.0);
    let to_x = UnitQuaternion::rotation_between(&Vector3::z(), x)
        .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI));
    UnitQuaternion::from_axis_angle(&Unit::new_normalize(*x), roll) * to_x * base
}

#[derive(Clone, Debug)]
enum Segment {
    Hold(Pose),
    Move(Pose, Pose),
    Draw(DrawParams),
}

#[derive(Clone, Debug)]
struct DrawParams {
    stroke: usize,
    tilt0: f64,
    tilt_amp: f64,
    tilt_cycles: f64,
    tilt_phase: f64,
    roll0: f64,
    roll_amp: f64,
    roll_phase: f64,
    /// Direction (world) the pen leans towards, projected on the tangent plane: chosen per stroke far from every
    /// normal along the stroke so the projection is well conditioned.
    lean_ref: V3,
    /// Curve-parameter spacing of the normal-smoothing kernel (about 20 mm of arc).
    smooth_ds: f64,
}

#[derive(Clone, Debug)]
struct Timed {
    t0: f64,
    t1: f64,
    seg: Segment,
}

/// Motion ranges of a drawing session.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawStyle {
    /// Mean drawing speed range, m/s (peak is about 1.9 times the mean).
    pub mean_speed: (f64, f64),
    /// Peak drawing speed limit, m/s (strokes are slowed down to respect it).
    pub max_speed: f64,
    /// Pen tilt from the surface normal, radians.
    pub tilt: (f64, f64),
    /// Peak pen-up speed range, m/s.
    pub pen_up_speed: (f64, f64),
    /// Probability per stroke that the pen leans sideways and away from the cameras (LEDs dim, LED 1 hidden
    /// behind the object near its silhouette).
    pub away_lean_prob: f64,
    /// Radius of the planning disc as a fraction of the object size.
    pub extent: f64,
    /// Rotation (radians, about the world up axis) of the direction along which the network is projected onto
    /// the object, away from the cameras' viewing direction: a non-zero value puts the network on a side of the
    /// object that the cameras see obliquely or not at all (object occlusion).
    pub view_yaw: f64,
}

/// Free (non-drawing) motion: random waypoints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeMotion {
    /// Depth range of the tip along the viewing axis, metres.
    pub depth: (f64, f64),
    /// Mean speed range, m/s.
    pub mean_speed: (f64, f64),
    /// Largest angle between the pen's back direction and the direction to the cameras, radians.
    pub max_off_axis: f64,
}

/// A planned pen trajectory.
#[derive(Clone, Debug)]
pub struct Trajectory {
    segs: Vec<Timed>,
    scene: Option<Arc<Scene>>,
    strokes: Vec<PlannedStroke>,
    stroke_times: Vec<(usize, f64, f64)>,
}

impl Trajectory {
    /// Plans a drawing session over `scene` lasting at least `duration` seconds (strokes are added until the
    /// timeline is long enough; the last one may end after `duration`).
    pub fn drawing(scene: Arc<Scene>, duration: f64, style: DrawStyle, rng: &mut SimRng) -> Self {
        let mut t = 0.0;
        let mut segs: Vec<Timed> = Vec::new();
        let mut stroke_times = Vec::new();
        // One planned network (about 40 s of drawing); a longer session rests after it.
        let strokes =
            crate::motion::plan_network(scene.rho, crate::motion::MAX_PLANNED_STROKES, rng);
        let mut traj = Trajectory {
            segs: Vec::new(),
            scene: Some(scene.clone()),
            strokes: Vec::new(),
            stroke_times: Vec::new(),
        };
        let mut prev_end: Option<Pose> = None;
        let mut prev_roll = rng.range(-PI, PI);
        let mut used = 0;
        while t < duration && used < strokes.len() {
            let idx = used;
            used += 1;
            traj.strokes = strokes.clone();
            let (length, max_rate) = traj.stroke_length(idx);
            let mut params = DrawParams {
                stroke: idx,
                tilt0: rng.range(style.tilt.0 + 0.09, style.tilt.1 - 0.09),
                tilt_amp: rng.range(0.0, 0.08) * (length / 0.2).min(1.0),
                tilt_cycles: rng.range(0.5, 1.5),
                tilt_phase: rng.range(0.0, 2.0 * PI),
                roll0: prev_roll + rng.range(-0.4, 0.4),
                roll_amp: rng.range(0.0, 0.3) * (length / 0.2).min(1.0),
                roll_phase: rng.range(0.0, 2.0 * PI),
                smooth_ds: (0.02 / length.max(0.01)).min(0.15),
                lean_ref: if rng.chance(style.away_lean_prob) {
                    let e = (scene.eye - scene.origin).normalize();
                    let side = if rng.chance(0.5) { scene.e1 } else { -scene.e1 };
                    (side - e * 0.6 + scene.up * 0.3).normalize()
                } else {
                    choose_lean(&scene, &strokes[idx].curve)
                },
            };
            params.roll0 -= params.roll_amp * params.roll_phase.sin();
            prev_roll = params.roll0 + params.roll_amp * (2.0 * PI + params.roll_phase).sin();
            let Some(start) = traj.draw_pose(&params, 0.0) else {
                continue;
            };
            let Some(end) = traj.draw_pose(&params, 1.0) else {
                continue;
            };
            let above_start = Pose {
                tip: scene.clear_point(&start.tip, 0.03),
                q: start.q,
            };
            match prev_end {
                None => {
                    push(&mut segs, &mut t, 1.0, Segment::Hold(above_start));
                }
                Some(pe) => {
                    let up = Pose {
                        tip: scene.clear_point(&pe.tip, 0.03),
                        q: pe.q,
                    };
                    let v = rng.range(style.pen_up_speed.0, style.pen_up_speed.1);
                    push(
                        &mut segs,
                        &mut t,
                        move_time(&pe.tip, &up.tip, v),
                        Segment::Move(pe, up),
                    );
                    push(
                        &mut segs,
                        &mut t,
                        move_time(&up.tip, &above_start.tip, v).max(0.4),
                        Segment::Move(up, above_start),
                    );
                }
            }
            let v = rng.range(style.pen_up_speed.0, style.pen_up_speed.1);
            push(
                &mut segs,
                &mut t,
                move_time(&above_start.tip, &start.tip, v),
                Segment::Move(above_start, start),
            );
            push(
                &mut segs,
                &mut t,
                rng.range(0.1, 0.25),
                Segment::Hold(start),
            );
            let speed = rng.range(style.mean_speed.0, style.mean_speed.1);
            // Minimum-jerk progress peaks at 1.875 times the mean rate; |dp/ds| varies along the lifted curve.
            let t_draw = (length / speed)
                .max(1.875 * max_rate / style.max_speed)
                .max(0.3);
            stroke_times.push((idx, t, t + t_draw));
            push(&mut segs, &mut t, t_draw, Segment::Draw(params));
            push(&mut segs, &mut t, rng.range(0.08, 0.2), Segment::Hold(end));
            prev_end = Some(end);
        }
        traj.strokes = strokes;
        traj.segs = segs;
        traj.stroke_times = stroke_times;
        traj
    }

    /// Free motion through random waypoints (the `bar` and `tip` scenarios): `sample_pose(rng, depth)` draws a
    /// waypoint at about that depth; the depth sweeps the range back and forth.
    pub fn free(
        duration: f64,
        motion: FreeMotion,
        rng: &mut SimRng,
        mut sample_pose: impl FnMut(&mut SimRng, f64) -> Pose,
    ) -> Self {
        let mut t = 0.0;
        let mut segs = Vec::new();
        let mut cur = sample_pose(rng, motion.depth.0);
        push(&mut segs, &mut t, 0.5, Segment::Hold(cur));
        // Sweep the depth range back and forth so every depth bin gets frames.
        let mut k = 0u32;
        while t < duration {
            let phase = (f64::from(k) * 0.13).sin() * 0.5 + 0.5;
            let depth = motion.depth.0 + (motion.depth.1 - motion.depth.0) * phase;
            let next = sample_pose(rng, depth);
            let v = rng.range(motion.mean_speed.0, motion.mean_speed.1);
            let dt = ((next.tip - cur.tip).norm() / v).max(0.3);
            push(&mut segs, &mut t, dt, Segment::Move(cur, next));
            push(&mut segs, &mut t, rng.range(0.05, 0.3), Segment::Hold(next));
            cur = next;
            k += 1;
        }
        Trajectory {
            segs,
            scene: None,
            strokes: Vec::new(),
            stroke_times: Vec::new(),
        }
    }

    /// A pen resting at `start` for `hold` seconds, then rest-to-rest minimum-jerk moves `(duration, target)`,
    /// then resting at the last target.
    pub fn waypoints(start: Pose, hold: f64, legs: &[(f64, Pose)]) -> Self {
        let mut t = 0.0;
        let mut segs = Vec::new();
        push(&mut segs, &mut t, hold, Segment::Hold(start));
        let mut cur = start;
        for &(dt, next) in legs {
            push(&mut segs, &mut t, dt, Segment::Move(cur, next));
            cur = next;
        }
        push(&mut segs, &mut t, f64::MAX, Segment::Hold(cur));
        Trajectory {
            segs,
            scene: None,
            strokes: Vec::new(),
            stroke_times: Vec::new(),
        }
    }

    /// A pen held still at `pose` forever.
    pub fn stationary(pose: Pose) -> Self {
        Trajectory {
            segs: vec![Timed {
                t0: 0.0,
                t1: f64::MAX,
                seg: Segment::Hold(pose),
            }],
            scene: None,
            strokes: Vec::new(),
            stroke_times: Vec::new(),
        }
    }

    /// The planned strokes (indexed by [`Trajectory::stroke_times`]).
    pub fn strokes(&self) -> &[PlannedStroke] {
        &self.strokes
    }

    /// Each drawn stroke: index into [`Trajectory::strokes`], start and end time in seconds (button press and
    /// release).
    pub fn stroke_times(&self) -> &[(usize, f64, f64)] {
        &self.stroke_times
    }

    /// The scene, if the pen draws on an object.
    pub fn scene(&self) -> Option<&Arc<Scene>> {
        self.scene.as_ref()
    }

    /// Whether the stroke button is held at time `t`.
    pub fn button(&self, t: f64) -> bool {
        self.buttons(t) & 1 != 0
    }

    /// The pen's button bits at time `t`: bit 0 (draw) while a stroke is drawn, with that stroke's
    /// pen mode on the mode buttons (bits 1–3, as the status packet carries them), 0 between strokes.
    pub fn buttons(&self, t: f64) -> u8 {
        self.stroke_times
            .iter()
            .find(|&&(_, a, b)| t >= a && t < b)
            .map_or(0, |&(idx, _, _)| 1 | (self.strokes[idx].mode & 0b111) << 1)
    }

    /// Sets the pen mode held while drawing each planned stroke: `modes[id]` for stroke `id` (strokes
    /// beyond `modes` keep theirs; the curve network maps modes to tools, docs/network.md).
    pub fn set_stroke_modes(&mut self, modes: &[u8]) {
        for s in &mut self.strokes {
            if let Some(&m) = modes.get(s.id as usize) {
                s.mode = m & 0b111;
            }
        }
    }

    /// Pen pose at time `t` (seconds; clamped to the timeline).
    pub fn pose(&self, t: f64) -> Pose {
        let Some(last) = self.segs.last() else {
            return Pose {
                tip: V3::zeros(),
                q: UnitQuaternion::identity(),
            };
        };
        let i = self
            .segs
            .partition_point(|s| s.t1 <= t)
            .min(self.segs.len() - 1);
        let s = &self.segs[i];
        let tau = if t >= last.t1 {
            1.0
        } else {
            ((t - s.t0) / (s.t1 - s.t0)).clamp(0.0, 1.0)
        };
        match &s.seg {
            Segment::Hold(p) => *p,
            Segment::Move(a, b) => {
                let m = min_jerk(tau);
                Pose {
                    tip: a.tip + (b.tip - a.tip) * m,
                    q: a.q.slerp(&b.q, m),
                }
            }
            Segment::Draw(d) => self
                .draw_pose(d, min_jerk(tau))
                .unwrap_or_else(|| self.pose_fallback(i)),
        }
    }

    fn pose_fallback(&self, i: usize) -> Pose {
        match self.segs.get(i.wrapping_sub(1)).map(|s| &s.seg) {
            Some(Segment::Hold(p)) => *p,
            _ => Pose {
                tip: V3::zeros(),
                q: UnitQuaternion::identity(),
            },
        }
    }

    /// Pose while drawing stroke `d.stroke` at curve parameter `s`.
    fn draw_pose(&self, d: &DrawParams, s: f64) -> Option<Pose> {
        let scene = self.scene.as_ref()?;
        let stroke = self.strokes.get(d.stroke)?;
        let (p, _) = scene.lift(stroke.curve.uv(s))?;
        // The hand does not follow every bend of the surface: the pen is tilted relative to the normal averaged
        // over about +-40 mm of the curve (binomial weights), so the edges of the box do not spin it. Near such
        // edges the tilt from the local normal can therefore leave the 20-60 degree range.
        // On open curves the kernel narrows smoothly to zero at the ends (factor sin(pi s)), so it never samples
        // beyond the curve; on the closed boundary it wraps around.
        let width = match stroke.curve {
            crate::motion::Curve::Loop { .. } => d.smooth_ds,
            crate::motion::Curve::Chord { .. } => d.smooth_ds * (PI * s.clamp(0.0, 1.0)).sin(),
        };
        let mut n = V3::zeros();
        for (k, wk) in [(-2.0, 1.0), (-1.0, 4.0), (0.0, 6.0), (1.0, 4.0), (2.0, 1.0)] {
            let (_, nk) = scene.lift(stroke.curve.uv(s + k * width))?;
            n += nk * wk;
        }
        let n = n.try_normalize(1e-12)?;
        let tilt = (d.tilt0 + d.tilt_amp * (2.0 * PI * d.tilt_cycles * s + d.tilt_phase).sin())
            .clamp(20f64.to_radians(), 60f64.to_radians());
        // Lean towards the user (up and towards the cameras), see `choose_lean`.
        let w = d.lean_ref;
        let lean = (w - n * w.dot(&n))
            .try_normalize(1e-9)
            .unwrap_or_else(|| n.cross(&V3::x()).normalize());
        let back = n * tilt.cos() + lean * tilt.sin();
        let roll = d.roll0 + d.roll_amp * (2.0 * PI * s + d.roll_phase).sin();
        Some(Pose {
            tip: p,
            q: orientation_from_axis(&(-back), roll),
        })
    }

    /// Approximate length of stroke `i` on the surface (metres) and the largest `|dp/ds|` along it.
    fn stroke_length(&self, i: usize) -> (f64, f64) {
        let (Some(scene), Some(st)) = (self.scene.as_ref(), self.strokes.get(i)) else {
            return (0.0, 0.0);
        };
        let n = 256;
        let pts: Vec<V3> = st
            .curve
            .sample(n)
            .into_iter()
            .filter_map(|uv| scene.lift(uv).map(|(p, _)| p))
            .collect();
        let steps = pts.windows(2).map(|w| (w[1] - w[0]).norm());
        let length = steps.clone().sum();
        let max_rate = steps.fold(0.0, f64::max) * n as f64;
        (length, max_rate)
    }

    /// End of the planned timeline, seconds.
    pub fn end_time(&self) -> f64 {
        self.segs.last().map_or(0.0, |s| s.t1)
    }
}

/// The lean reference of a stroke: the first of "mostly up", "up and towards the cameras", "mostly towards the
/// cameras" that stays at least 30 degrees from every surface normal along the stroke (else the best of them).
fn choose_lean(scene: &Scene, curve: &crate::motion::Curve) -> V3 {
    let e = (scene.eye - scene.origin).normalize();
    let candidates = [
        (scene.up + e * 0.35).normalize(),
        (scene.up + e).normalize(),
        (scene.up * 0.35 + e).normalize(),
    ];
    let normals: Vec<V3> = curve
        .sample(32)
        .into_iter()
        .filter_map(|uv| scene.lift(uv).map(|(_, n)| n))
        .collect();
    let score = |w: &V3| {
        normals
            .iter()
            .map(|n| (w - n * w.dot(n)).norm())
            .fold(f64::INFINITY, f64::min)
    };
    let mut best = (candidates[0], -1.0);
    for c in candidates {
        let sc = score(&c);
        if sc >= 0.5 {
            return c;
        }
        if sc > best.1 {
            best = (c, sc);
        }
    }
    best.0
}

fn push(segs: &mut Vec<Timed>, t: &mut f64, dt: f64, seg: Segment) {
    segs.push(Timed {
        t0: *t,
        t1: *t + dt,
        seg,
    });
    *t += dt;
}

/// Duration of a minimum-jerk move of length `|b - a|` with peak speed `v_peak`.
fn move_time(a: &V3, b: &V3, v_peak: f64) -> f64 {
    (1.875 * (b - a).norm() / v_peak).max(0.2)
}

/// Random helper shared by scenarios: a unit vector within `max_angle` of `axis`.
pub fn random_direction_near(axis: &V3, max_angle: f64, rng: &mut SimRng) -> V3 {
    let axis = axis.normalize();
    let cos_max = max_angle.cos();
    let c = rng.range(cos_max, 1.0);
    let s = (1.0 - c * c).max(0.0).sqrt();
    let phi = rng.range(0.0, 2.0 * PI);
    let helper = if axis.x.abs() < 0.9 { V3::x() } else { V3::y() };
    let u = axis.cross(&helper).normalize();
    let v = axis.cross(&u);
    axis * c + (u * phi.cos() + v * phi.sin()) * s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_jerk_starts_and_ends_at_rest() {
        assert_eq!(min_jerk(0.0), 0.0);
        assert_eq!(min_jerk(1.0), 1.0);
        assert!((min_jerk(0.5) - 0.5).abs() < 1e-15);
        let h = 1e-6;
        let d = |t: f64| (min_jerk(t + h) - min_jerk(t - h)) / (2.0 * h);
        assert!(d(h).abs() < 1e-9 && d(1.0 - h).abs() < 1e-9);
        // Peak speed of a minimum-jerk move is 1.875 times the mean.
        assert!((d(0.5) - 1.875).abs() < 1e-6);
    }

    #[test]
    fn orientation_from_axis_maps_pen_x_to_the_axis() {
        for axis in [
            V3::z(),
            V3::x(),
            V3::new(0.3, -0.5, 0.8).normalize(),
            V3::new(0.0, 1.0, 1e-3).normalize(),
        ] {
            for roll in [0.0, 1.0, -2.5] {
                let q = orientation_from_axis(&axis, roll);
                assert!((q * V3::x() - axis).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn waypoint_moves_follow_the_minimum_jerk_profile() {
        let q = UnitQuaternion::identity();
        let a = Pose {
            tip: V3::zeros(),
            q,
        };
        let b = Pose {
            tip: V3::new(0.2, 0.0, 0.0),
            q,
        };
        let traj = Trajectory::waypoints(a, 0.5, &[(1.0, b)]);
        assert_eq!(traj.pose(0.2).tip, a.tip);
        assert!((traj.pose(0.75).tip.x - 0.2 * min_jerk(0.25)).abs() < 1e-15);
        assert_eq!(traj.pose(5.0).tip, b.tip);
    }
}
