//! Speed of mesh closure, border gluing (identification and tube) and skinning on a 100-face network
//! (release build: `cargo test --release -p fires-recon --test network_glue_bench -- --ignored
//! --nocapture`); one JSON line per tool. The target is the issue's ≤ 1 ms per tool (interactive feedback).

mod common;

use std::f64::consts::PI;
use std::time::Instant;

use common::disc::{grid_drawing, Z};
use fires_recon::network::tools::{
    close_boundary, glue_borders, glue_tube, insert_boundary, skin_profiles, BoundaryOptions,
    CloseOptions, CurveInput, GlueOptions, SkinOptions, TubeHalves, TubeOptions,
};
use fires_recon::network::{build_network, BuildOptions, Network, StrokeInput};

fn hundred_faces() -> Network {
    let (drawing, _) = grid_drawing(0.2, 9, 0.03, 0, 0.003);
    let s: Vec<StrokeInput> = drawing
        .into_iter()
        .enumerate()
        .map(|(id, (points, closed))| StrokeInput {
            id: id as u32,
            points,
            closed,
            sigma_mm: None,
            mode: 0,
            untracked_mm: [0.0; 2],
        })
        .collect();
    let (net, report) = build_network(&s, &BuildOptions::default());
    assert_eq!(report.topology.faces, 100);
    net
}

fn on_circle(a: f64, z: f64) -> [f64; 3] {
    [0.2 * a.cos(), 0.2 * a.sin(), z]
}

fn median_ms(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn time(net: &Network, mut tool: impl FnMut(&mut Network)) -> f64 {
    let mut times = Vec::new();
    for _ in 0..51 {
        let mut n = net.clone();
        let t0 = Instant::now();
        tool(&mut n);
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        n.validate().unwrap();
    }
    median_ms(times)
}

#[test]
#[ignore = "benchmark: run in release with --ignored --nocapture"]
fn bench_closure_gluing_and_skinning() {
    let net = hundred_faces();
    let mut res = Vec::new();
    let locator = [on_circle(1.0, Z)];
    let ms = time(&net, |n| {
        close_boundary(n, CurveInput::new(&locator), &CloseOptions::default()).unwrap();
    });
    res.push(format!(
        "{{\"tool\":\"close_boundary\",\"faces\":100,\"median_ms\":{ms:.4}}}"
    ));
    // Two arcs of the boundary glued (a₁ = 0.3, a₂ = 1.2, b₂ = 1.9, b₁ = 2.8 rad).
    let m1 = [on_circle(0.3, Z), on_circle(2.8, Z)];
    let m2 = [on_circle(1.2, Z), on_circle(1.9, Z)];
    for (name, survivor) in [
        ("first", fires_recon::network::tools::Survivor::First),
        ("average", fires_recon::network::tools::Survivor::Average),
    ] {
        let o = GlueOptions {
            survivor,
            ..GlueOptions::default()
        };
        let ms = time(&net, |n| {
            glue_borders(n, CurveInput::new(&m1), Some(CurveInput::new(&m2)), &o).unwrap();
        });
        res.push(format!(
            "{{\"tool\":\"glue_borders\",\"survivor\":\"{name}\",\"faces\":100,\"median_ms\":{ms:.4}}}"
        ));
    }
    // A tube to a second disc 0.2 m above.
    let mut two = net.clone();
    let top: Vec<[f64; 3]> = (0..=420)
        .map(|i| on_circle(2.0 * PI * i as f64 / 420.0 + 0.05, Z + 0.2))
        .collect();
    insert_boundary(&mut two, CurveInput::new(&top), &BoundaryOptions::default()).unwrap();
    let c1 = [on_circle(0.3, Z), on_circle(0.3, Z + 0.2)];
    let c2 = [on_circle(3.4, Z), on_circle(3.4, Z + 0.2)];
    let o = TubeOptions {
        halves: TubeHalves::Auto,
        ..TubeOptions::default()
    };
    let ms = time(&two, |n| {
        glue_tube(n, CurveInput::new(&c1), CurveInput::new(&c2), &o).unwrap();
    });
    res.push(format!(
        "{{\"tool\":\"glue_tube\",\"faces\":101,\"halves\":\"auto\",\"median_ms\":{ms:.4}}}"
    ));
    // Five circular profiles of 120 points, 0.1 m apart, two straight spines.
    let profiles: Vec<Vec<[f64; 3]>> = (0..5)
        .map(|k| {
            (0..=120)
                .map(|i| {
                    let a = 2.0 * PI * i as f64 / 120.0;
                    [0.05 * a.cos(), 0.05 * a.sin(), 0.1 * k as f64]
                })
                .collect()
        })
        .collect();
    let spine = |x: f64| common::disc::line([x, 0.0, -0.02], [x, 0.0, 0.42], 0.002);
    let (s1, s2) = (spine(0.05), spine(-0.05));
    let ms = time(&net, |n| {
        let p: Vec<CurveInput> = profiles.iter().map(|p| CurveInput::new(p)).collect();
        skin_profiles(
            n,
            &p,
            [CurveInput::new(&s1), CurveInput::new(&s2)],
            &SkinOptions::default(),
        )
        .unwrap();
    });
    res.push(format!(
        "{{\"tool\":\"skin_profiles\",\"profiles\":5,\"profile_points\":121,\"spine_points\":{},\"median_ms\":{ms:.4}}}",
        s1.len()
    ));
    for r in res {
        println!("{r}");
    }
}
