//! Synthetic strokes on a disc of radius R = 0.1 m in the plane z = 0.5 m (metres, like the tracker).

#![allow(dead_code)]

use std::f64::consts::PI;

pub const R: f64 = 0.1;
pub const Z: f64 = 0.5;
/// The minor semi-axis: the disc is a slight ellipse so its diameter (where the boundary is split) is
/// unique, at 0° and 180°.
pub const B: f64 = 0.097;

pub fn at(angle: f64) -> [f64; 3] {
    [R * angle.cos(), B * angle.sin(), Z]
}

/// The boundary ellipse, drawn counter-clockwise, `n` points, the last a copy of the first.
pub fn circle(n: usize) -> Vec<[f64; 3]> {
    (0..=n)
        .map(|i| at(2.0 * PI * i as f64 / n as f64))
        .collect()
}

/// Points every `step` metres from `a` to `b` (both included).
pub fn line(a: [f64; 3], b: [f64; 3], step: f64) -> Vec<[f64; 3]> {
    let d = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
    let n = (d / step).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            [
                a[0] + t * (b[0] - a[0]),
                a[1] + t * (b[1] - a[1]),
                a[2] + t * (b[2] - a[2]),
            ]
        })
        .collect()
}

/// The chord between two boundary angles, sampled every 2 mm, with its ends moved along the chord by
/// `extra` metres (positive: overshoot past the circle, negative: stop short).
pub fn chord(a0: f64, a1: f64, extra: f64) -> Vec<[f64; 3]> {
    let (a, b) = (at(a0), at(a1));
    let d = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    let u = [(b[0] - a[0]) / d, (b[1] - a[1]) / d];
    let a = [a[0] - extra * u[0], a[1] - extra * u[1], Z];
    let b = [b[0] + extra * u[0], b[1] + extra * u[1], Z];
    line(a, b, 0.002)
}

/// The vertical chord x = `x` from the top arc to the bottom arc.
pub fn vertical(x: f64) -> Vec<[f64; 3]> {
    let y = B / R * (R * R - x * x).sqrt();
    line([x, y, Z], [x, -y, Z], 0.002)
}

/// A small deterministic generator (xorshift64*).
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// Where the 2D chords `a0→a1` and `b0→b1` (boundary angles) cross, if they do.
pub fn chord_crossing(a: (f64, f64), b: (f64, f64)) -> Option<[f64; 2]> {
    let (p, q) = (at(a.0), at(a.1));
    let (r, s) = (at(b.0), at(b.1));
    let d1 = [q[0] - p[0], q[1] - p[1]];
    let d2 = [s[0] - r[0], s[1] - r[1]];
    let den = d1[0] * d2[1] - d1[1] * d2[0];
    if den.abs() < 1e-15 {
        return None;
    }
    let w = [r[0] - p[0], r[1] - p[1]];
    let t = (w[0] * d2[1] - w[1] * d2[0]) / den;
    let u = (w[0] * d1[1] - w[1] * d1[0]) / den;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u))
        .then(|| [p[0] + t * d1[0], p[1] + t * d1[1]])
}

/// Random chords of the disc, kept only where the network they make is unambiguous for the default
/// thresholds: every crossing at least `gap` from every other crossing and every chord end, ends at
/// least `gap` apart and from the boundary's split points (0°, 180°), crossing angles ≥ 25°.
/// Returns the chords as boundary-angle pairs.
pub fn separated_chords(rng: &mut Rng, n: usize, gap: f64) -> Vec<(f64, f64)> {
    let mut chords: Vec<(f64, f64)> = Vec::new();
    let mut tries = 0;
    while chords.len() < n && tries < 100_000 {
        tries += 1;
        let a0 = rng.range(0.0, 2.0 * PI);
        let a1 = a0 + rng.range(0.6, 2.0 * PI - 0.6);
        let c = (a0, a1);
        let mut ends = vec![at(0.0), at(PI)];
        let mut points: Vec<[f64; 2]> = Vec::new();
        for &d in &chords {
            ends.push(at(d.0));
            ends.push(at(d.1));
        }
        let far = |p: [f64; 2], q: [f64; 3]| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt() >= gap
        };
        let mine = [at(a0), at(a1)];
        if !mine
            .iter()
            .all(|m| ends.iter().all(|e| far([m[0], m[1]], *e)))
        {
            continue;
        }
        let mut ok = true;
        for (k, &d) in chords.iter().enumerate() {
            if let Some(x) = chord_crossing(c, d) {
                let dir = |c: (f64, f64)| {
                    let (p, q) = (at(c.0), at(c.1));
                    let l = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
                    [(q[0] - p[0]) / l, (q[1] - p[1]) / l]
                };
                let (u, v) = (dir(c), dir(d));
                let sin = (u[0] * v[1] - u[1] * v[0]).abs();
                if sin < 25f64.to_radians().sin() || !ends.iter().chain(&mine).all(|e| far(x, *e)) {
                    ok = false;
                    break;
                }
                points.push(x);
            }
            // Earlier crossings of the other chords.
            for &e in chords.iter().take(k) {
                if let Some(y) = chord_crossing(chords[k], e) {
                    if points.iter().any(|p| !far(*p, [y[0], y[1], Z])) {
                        ok = false;
                    }
                }
            }
            if !ok {
                break;
            }
        }
        // Crossings of this chord among themselves.
        for i in 0..points.len() {
            for j in 0..i {
                if !far(points[i], [points[j][0], points[j][1], Z]) {
                    ok = false;
                }
            }
        }
        if ok {
            chords.push(c);
        }
    }
    chords
}

/// A drawn stroke: points and whether it is closed.
pub type Drawn = (Vec<[f64; 3]>, bool);

/// A grid drawing on a circle of radius `radius` centred at the origin (z = Z): the boundary circle,
/// `n` horizontal and `n` vertical lines `spacing` apart (centred), then `cells` short strokes, each
/// cutting the top-left corner off one grid cell (from its left side's midpoint to its top side's
/// midpoint). All lines are sampled every `step` metres. Returns the strokes (boundary first) and the
/// number of line crossings.
pub fn grid_drawing(
    radius: f64,
    n: usize,
    spacing: f64,
    cells: usize,
    step: f64,
) -> (Vec<Drawn>, usize) {
    let m = (2.0 * PI * radius / step).ceil() as usize;
    let mut out = vec![(
        (0..=m)
            .map(|i| {
                let a = 2.0 * PI * i as f64 / m as f64 + 0.1;
                [radius * a.cos(), radius * a.sin(), Z]
            })
            .collect(),
        true,
    )];
    let c: Vec<f64> = (0..n)
        .map(|k| (k as f64 - (n as f64 - 1.0) / 2.0) * spacing)
        .collect();
    for &y in &c {
        let x = (radius * radius - y * y).sqrt();
        out.push((line([-x, y, Z], [x, y, Z], step), false));
    }
    for &x in &c {
        let y = (radius * radius - x * x).sqrt();
        out.push((line([x, y, Z], [x, -y, Z], step), false));
    }
    let mut k = 0;
    'cells: for i in 0..n.saturating_sub(1) {
        for j in 0..n.saturating_sub(1) {
            if k == cells {
                break 'cells;
            }
            let (x, y) = (c[i], c[j]);
            out.push((
                line(
                    [x, y + 0.5 * spacing, Z],
                    [x + 0.5 * spacing, y + spacing, Z],
                    step.min(0.002),
                ),
                false,
            ));
            k += 1;
        }
    }
    (out, n * n)
}
