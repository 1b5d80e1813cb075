//! Skinning's automatic half pairing (FIRES thesis, §5.2: halves paired where the dihedral angle is below 90°): ellipse profiles at consecutive
//! dihedral angles 0–80°, random in-plane rotations and spine placements, halves labelled at random:
//! the pairing is right in 100% of cases.

mod common;

use common::disc::Rng;
use fires_recon::network::tools::pair_halves;
use std::f64::consts::PI;

/// Points of the ellipse (a, b) rotated by `phi` in the plane spanned by `u`, `v` at `o`, from angle
/// `t0` to `t1`.
#[allow(clippy::too_many_arguments)]
fn arc(
    o: [f64; 3],
    u: [f64; 3],
    v: [f64; 3],
    a: f64,
    b: f64,
    phi: f64,
    t0: f64,
    t1: f64,
) -> Vec<[f64; 3]> {
    (0..=60)
        .map(|k| {
            let t = t0 + (t1 - t0) * k as f64 / 60.0;
            let (x, y) = (a * t.cos(), b * t.sin());
            let (x, y) = (x * phi.cos() - y * phi.sin(), x * phi.sin() + y * phi.cos());
            [
                o[0] + x * u[0] + y * v[0],
                o[1] + x * u[1] + y * v[1],
                o[2] + x * u[2] + y * v[2],
            ]
        })
        .collect()
}

#[test]
fn half_pairing_is_right_in_every_randomised_case() {
    let mut rng = Rng(0xC0FFEE);
    let mut cases = 0;
    for _ in 0..2000 {
        let dihedral = rng.range(0.0, 80f64.to_radians());
        // Profile i in the plane z = 0; profile j in a plane tilted by `dihedral` about the x axis,
        // 60 mm further along the spine direction.
        let (ui, vi) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let (uj, vj) = ([1.0, 0.0, 0.0], [0.0, dihedral.cos(), dihedral.sin()]);
        let oj = [rng.range(-0.01, 0.01), rng.range(-0.01, 0.01), 0.06];
        let (a, b) = (rng.range(0.03, 0.06), rng.range(0.015, 0.03));
        let (a2, b2) = (a * rng.range(0.7, 1.3), b * rng.range(0.7, 1.3));
        let (phi_i, phi_j) = (rng.range(0.0, 2.0 * PI), rng.range(0.0, 2.0 * PI));
        // The spines cross each profile at two angles (not necessarily opposite); profile j's spine
        // points correspond to profile i's (same ellipse angles relative to its rotation, perturbed).
        let s0 = rng.range(0.0, 2.0 * PI);
        let s1 = s0 + rng.range(0.6 * PI, 1.4 * PI);
        let (e0, e1) = (rng.range(-0.2, 0.2), rng.range(-0.2, 0.2));
        let hi0 = arc([0.0; 3], ui, vi, a, b, phi_i, s0, s1);
        let hi1 = arc([0.0; 3], ui, vi, a, b, phi_i, s1, s0 + 2.0 * PI);
        // Profile j is drawn with the same in-plane rotation as i's (the object continues smoothly) plus
        // a random offset of up to ±0.3 rad, which moves its halves only a little.
        let phi_j = phi_i + (phi_j - PI).clamp(-0.3, 0.3);
        let hj0 = arc(oj, uj, vj, a2, b2, phi_j, s0 + e0, s1 + e1);
        let hj1 = arc(oj, uj, vj, a2, b2, phi_j, s1 + e1, s0 + e0 + 2.0 * PI);
        let swap = rng.unit() < 0.5;
        let j = if swap {
            [&hj1[..], &hj0[..]]
        } else {
            [&hj0[..], &hj1[..]]
        };
        let straight = pair_halves([&hi0, &hi1], j).unwrap();
        assert_eq!(straight, !swap, "dihedral {:.1}°", dihedral.to_degrees());
        cases += 1;
    }
    assert_eq!(cases, 2000);
}

// ---- The skinning tool: profiles and spines in, a tube of faces out. ----

use fires_recon::network::tools::{
    insert_boundary, skin_profiles, BoundaryOptions, CurveInput, SkinOptions, SkinReport, ToolError,
};
use fires_recon::network::{replay, EdgeId, Journal, Network, Step, StrokeInput};

/// One randomised tube: profile k is an ellipse in a plane tilted by α_k about x (consecutive
/// dihedral angles `δ` in 0–80°, alternating so the tube stays straight), 0.15 m apart along z, drawn from
/// a random start point in a random direction; the spines pass through the ellipse points at angles
/// s₀ + e and s₁ + e of every profile.
struct Tube {
    profiles: Vec<Vec<[f64; 3]>>,
    spines: [Vec<[f64; 3]>; 2],
    /// Per profile, the ellipse point in the middle of the arc from spine 1 to spine 2 (angle increasing).
    side0: Vec<[f64; 3]>,
    dihedral_max: f64,
}

fn ellipse_at(o: [f64; 3], alpha: f64, a: f64, b: f64, phi: f64, t: f64) -> [f64; 3] {
    let (u, v) = ([1.0, 0.0, 0.0], [0.0, alpha.cos(), alpha.sin()]);
    let (x, y) = (a * t.cos(), b * t.sin());
    let (x, y) = (x * phi.cos() - y * phi.sin(), x * phi.sin() + y * phi.cos());
    [
        o[0] + x * u[0] + y * v[0],
        o[1] + x * u[1] + y * v[1],
        o[2] + x * u[2] + y * v[2],
    ]
}

fn polyline_through(points: &[[f64; 3]], step: f64) -> Vec<[f64; 3]> {
    let mut out = vec![points[0]];
    for w in points.windows(2) {
        let (p, q) = (w[0], w[1]);
        let d = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2)).sqrt();
        let n = (d / step).ceil().max(1.0) as usize;
        for i in 1..=n {
            let t = i as f64 / n as f64;
            out.push([
                p[0] + t * (q[0] - p[0]),
                p[1] + t * (q[1] - p[1]),
                p[2] + t * (q[2] - p[2]),
            ]);
        }
    }
    out
}

fn tube(rng: &mut Rng, n: usize) -> Tube {
    let s0 = rng.range(0.0, 2.0 * PI);
    let s1 = s0 + rng.range(0.6 * PI, 1.4 * PI);
    let phi0 = rng.range(0.0, 2.0 * PI);
    let (mut alpha, mut phi) = (rng.range(-0.3, 0.3), phi0);
    let (mut a, mut b) = (rng.range(0.03, 0.06), rng.range(0.015, 0.03));
    let mut t = Tube {
        profiles: Vec::new(),
        spines: [Vec::new(), Vec::new()],
        side0: Vec::new(),
        dihedral_max: 0.0,
    };
    let mut through: [Vec<[f64; 3]>; 2] = [Vec::new(), Vec::new()];
    for k in 0..n {
        if k > 0 {
            let d = rng.range(0.0, 80f64.to_radians());
            t.dihedral_max = f64::max(t.dihedral_max, d);
            alpha += if alpha > 0.0 { -d } else { d };
            phi += rng.range(-0.3, 0.3);
            a = (a * rng.range(0.7, 1.3)).clamp(0.025, 0.07);
            b = (b * rng.range(0.7, 1.3)).clamp(0.012, 0.035);
        }
        let o = [
            rng.range(-0.01, 0.01),
            rng.range(-0.01, 0.01),
            0.15 * k as f64,
        ];
        let (e0, e1) = (rng.range(-0.2, 0.2), rng.range(-0.2, 0.2));
        through[0].push(ellipse_at(o, alpha, a, b, phi, s0 + e0));
        through[1].push(ellipse_at(o, alpha, a, b, phi, s1 + e1));
        t.side0
            .push(ellipse_at(o, alpha, a, b, phi, (s0 + e0 + s1 + e1) / 2.0));
        let start = rng.range(0.0, 2.0 * PI);
        let sign = if rng.unit() < 0.5 { 1.0 } else { -1.0 };
        t.profiles.push(
            (0..=120)
                .map(|i| {
                    let u = start + sign * 2.0 * PI * i as f64 / 120.0;
                    ellipse_at(o, alpha, a, b, phi, u)
                })
                .collect(),
        );
    }
    for (s, pts) in through.iter_mut().enumerate() {
        // Overshoot 20 mm at both ends; draw a spine backwards at random.
        let (f, l) = (pts[0], pts[pts.len() - 1]);
        pts.insert(0, [f[0], f[1], f[2] - 0.02]);
        pts.push([l[0], l[1], l[2] + 0.02]);
        let mut line = polyline_through(pts, 0.002);
        if rng.unit() < 0.5 {
            line.reverse();
        }
        t.spines[s] = line;
    }
    t
}

fn skin(net: &mut Network, t: &Tube, options: &SkinOptions) -> Result<SkinReport, ToolError> {
    let profiles: Vec<CurveInput> = t
        .profiles
        .iter()
        .enumerate()
        .map(|(i, p)| CurveInput {
            points: p,
            stroke: Some(i as u32),
            sigma_mm: None,
            untracked_mm: [0.0; 2],
        })
        .collect();
    let spine = |s: usize| CurveInput {
        points: &t.spines[s],
        stroke: Some(100 + s as u32),
        sigma_mm: None,
        untracked_mm: [0.0; 2],
    };
    skin_profiles(net, &profiles, [spine(0), spine(1)], options).map(|r| r.0)
}

/// Whether edge `e`'s polyline holds the point of its profile nearest to the side-0 marker.
fn on_side0(net: &Network, e: EdgeId, other: EdgeId, marker: [f64; 3]) -> bool {
    let d = |e: EdgeId| {
        net.edge_polyline(e)
            .unwrap()
            .points
            .iter()
            .map(|p| {
                ((p[0] - marker[0]).powi(2)
                    + (p[1] - marker[1]).powi(2)
                    + (p[2] - marker[2]).powi(2))
                .sqrt()
            })
            .fold(f64::INFINITY, f64::min)
    };
    d(e) < d(other)
}

#[test]
fn skinning_builds_a_tube_with_halves_paired_in_every_randomised_case() {
    let mut rng = Rng(0x5EED_0014);
    let (mut cases, mut sections, mut right) = (0, 0, 0);
    let mut worst_margin = f64::INFINITY;
    for case in 0..400 {
        let n = 2 + case % 4;
        let t = tube(&mut rng, n);
        let mut net = Network::new();
        let r = skin(&mut net, &t, &SkinOptions::default())
            .unwrap_or_else(|e| panic!("case {case}: {e}"));
        net.validate().unwrap();
        let topo = net.topology();
        assert_eq!(
            (topo.vertices, topo.edges, topo.faces),
            (2 * n, 4 * n - 2, 2 * (n - 1)),
            "case {case}"
        );
        assert_eq!(
            (topo.euler, topo.boundaries, topo.genus, topo.components),
            (0, 2, 0, 1)
        );
        for (i, [fa, fb]) in r.faces.iter().enumerate() {
            sections += 1;
            let mut ok = true;
            for f in [*fa, *fb] {
                // The face's half of profile i and of profile i + 1 lie on the same true side.
                let side = |k: usize| {
                    let [h0, h1] = r.halves[k];
                    let u = net
                        .face(f)
                        .unwrap()
                        .uses
                        .iter()
                        .find(|u| u.edge == h0 || u.edge == h1)
                        .unwrap()
                        .edge;
                    on_side0(&net, u, if u == h0 { h1 } else { h0 }, t.side0[k])
                };
                ok &= side(i) == side(i + 1);
            }
            right += usize::from(ok);
        }
        worst_margin = worst_margin.min(r.margins.iter().copied().fold(f64::INFINITY, f64::min));
        cases += 1;
    }
    assert_eq!(cases, 400);
    assert_eq!(
        right, sections,
        "{right} of {sections} sections paired right"
    );
    eprintln!("{sections} sections, all paired right; smallest margin {worst_margin:.3}");
}

#[test]
fn capped_skins_are_closed_and_refusals_leave_the_network_unchanged() {
    let mut rng = Rng(77);
    let t = tube(&mut rng, 3);
    let mut net = Network::new();
    let r = skin(
        &mut net,
        &t,
        &SkinOptions {
            caps: true,
            ..SkinOptions::default()
        },
    )
    .unwrap();
    net.validate().unwrap();
    let topo = net.topology();
    assert_eq!(
        (topo.faces, topo.euler, topo.boundaries, topo.genus),
        (6, 2, 0, 0)
    );
    assert_eq!(r.caps.len(), 2);
    // A network with content: a skin beside a disc.
    let disc: Vec<[f64; 3]> = (0..=200)
        .map(|i| {
            let a = 2.0 * PI * i as f64 / 200.0;
            [0.5 + 0.1 * a.cos(), 0.097 * a.sin(), 0.0]
        })
        .collect();
    let mut net = Network::new();
    let c = CurveInput {
        points: &disc,
        stroke: Some(50),
        sigma_mm: None,
        untracked_mm: [0.0; 2],
    };
    insert_boundary(&mut net, c, &BoundaryOptions::default()).unwrap();
    let before = net.clone();
    // Spine 2 stops before the last profile.
    let mut short = tube(&mut rng, 3);
    let keep = short.spines[1].len() / 2;
    if short.spines[1][0][2] < short.spines[1][keep][2] {
        short.spines[1].truncate(keep);
    } else {
        short.spines[1].drain(..keep);
    }
    let e = skin(&mut net, &short, &SkinOptions::default()).unwrap_err();
    assert_eq!(e.rule(), "spines cross every profile", "{e}");
    assert!(e.distance_mm().unwrap() > 5.0);
    assert_eq!(net, before);
    // An open profile.
    let mut open = tube(&mut rng, 2);
    let n = open.profiles[1].len();
    open.profiles[1].truncate(n - 20);
    let e = skin(&mut net, &open, &SkinOptions::default()).unwrap_err();
    assert!(matches!(e, ToolError::NotClosed { .. }), "{e}");
    assert_eq!(net, before);
    // Both spines through the same points.
    let mut same = tube(&mut rng, 2);
    same.spines[1] = same.spines[0].clone();
    let e = skin(&mut net, &same, &SkinOptions::default()).unwrap_err();
    assert_eq!(e.rule(), "spines cross a profile apart");
    assert_eq!(net, before);
    // A skin next to the disc: two components, Euler numbers add.
    let ok = tube(&mut rng, 4);
    let (_, txn) = {
        let profiles: Vec<CurveInput> = ok.profiles.iter().map(|p| CurveInput::new(p)).collect();
        skin_profiles(
            &mut net,
            &profiles,
            [
                CurveInput::new(&ok.spines[0]),
                CurveInput::new(&ok.spines[1]),
            ],
            &SkinOptions::default(),
        )
        .unwrap()
    };
    net.validate().unwrap();
    let topo = net.topology();
    assert_eq!((topo.components, topo.euler, topo.boundaries), (2, 1, 3));
    net.undo(&txn);
    assert_eq!(net, before);
}

#[test]
fn a_journal_skin_step_replays_bit_for_bit() {
    let mut rng = Rng(2024);
    let t = tube(&mut rng, 3);
    let mut strokes: Vec<StrokeInput> = t
        .profiles
        .iter()
        .enumerate()
        .map(|(i, p)| StrokeInput {
            id: i as u32,
            points: p.clone(),
            closed: true,
            sigma_mm: None,
            mode: 5 << 1,
            untracked_mm: [0.0; 2],
        })
        .collect();
    for s in 0..2 {
        strokes.push(StrokeInput {
            id: 100 + s as u32,
            points: t.spines[s].clone(),
            closed: false,
            sigma_mm: None,
            mode: 5 << 1,
            untracked_mm: [0.0; 2],
        });
    }
    let journal = Journal {
        steps: vec![Step::Skin {
            profiles: vec![0, 1, 2],
            spines: [100, 101],
            options: SkinOptions::default(),
        }],
        ..Journal::default()
    };
    let text = serde_json::to_string(&journal).unwrap();
    assert!(text.contains(r#""tool":"skin""#), "{text}");
    let back: Journal = serde_json::from_str(&text).unwrap();
    let replayed = replay(&back, &strokes).unwrap();
    let mut direct = Network::new();
    skin(&mut direct, &t, &SkinOptions::default()).unwrap();
    assert_eq!(replayed, direct);
}
