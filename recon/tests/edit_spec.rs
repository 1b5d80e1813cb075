//! The JSON edit specification and the session contract (issue 16 items 1 and 7).

mod edit_common;

use edit_common::*;
use fires_recon::edit::{
    EditError, EditProblem, EditSession, EditSpec, ImplicitEditor, PoissonEditor, Role, Select,
};
use fires_recon::generate::{icosphere, plane_grid};

#[test]
fn full_spec_parses_and_transform_order_is_scale_rotate_translate() {
    let json = r#"{"roi": "all", "anchors": {"vertices": [0, 1]}, "anchor_weight": 2.0,
        "handles": [{"select": {"sphere": {"center": [1, 0, 4], "radius": 0.01}}, "weight": 3,
                     "fix_gradient": true,
                     "transform": {"scale": 2, "rotate": {"axis": [0, 0, 1], "deg": 90},
                                   "about": [1, 0, 0], "translate": [0, 0, 1]}}]}"#;
    let spec = EditSpec::from_json(json).unwrap();
    let mesh = relief_cylinder();
    let p = EditProblem::new(&mesh, &spec).unwrap();
    let t = p.spec_transforms[0];
    // (2, 0, 0): scale about (1,0,0) → (3,0,0); rotate 90° about z there → (1,2,0); +z.
    let q = t.apply(fires_recon::Vec3::new(2.0, 0.0, 0.0));
    assert!(
        q.distance(fires_recon::Vec3::new(1.0, 2.0, 1.0)) < 1e-12,
        "{q:?}"
    );
    assert_eq!(p.role[p.local[0]], Role::Anchor);
    assert!(p.handles[0].fix_gradient && p.handles[0].weight == 3.0);
    let back = EditSpec::from_json(&spec.to_json()).unwrap();
    assert_eq!(back, spec);
}

#[test]
fn default_about_is_the_handle_centroid_and_default_anchors_the_outer_ring() {
    let mesh = plane_grid(10, 10, 1.0, 1.0, false);
    let json = r#"{"roi": {"box": {"min": [0.25, 0.25, -1], "max": [0.75, 0.75, 1]}},
        "handles": [{"select": {"sphere": {"center": [0.5, 0.5, 0], "radius": 0.11}},
                     "transform": {"rotate": {"axis": [0, 0, 1], "deg": 180}}}]}"#;
    let p = EditProblem::new(&mesh, &EditSpec::from_json(json).unwrap()).unwrap();
    let c = p.handles[0].centroid;
    assert!(p.spec_transforms[0].apply(c).distance(c) < 1e-12);
    // ROI 0.3..0.7 → 5×5 = 25 vertices; the ring outside is the 7×7 frame minus the two
    // corners that no cell diagonal reaches: 49 − 25 − 2 = 22.
    assert_eq!(p.n_roi, 25);
    assert_eq!(p.role.iter().filter(|r| **r == Role::Ring).count(), 22);
}

#[test]
fn clear_errors() {
    let mesh = relief_cylinder();
    let err = |json: &str| {
        EditSpec::from_json(json).and_then(|s| EditProblem::new(&mesh, &s).map(|_| ()))
    };
    let e = err(r#"{"roi": "all", "handles": [], "colour": 1}"#).unwrap_err();
    assert!(
        matches!(&e, EditError::Spec(m) if m.contains("colour")),
        "{e}"
    );
    let e = err(r#"{"roi": "all", "handles": [{"select": "all", "transform": {"rotate": {"axis": [0,0,1], "deg": 3, "extra": 1}}}]}"#).unwrap_err();
    assert!(
        matches!(&e, EditError::Spec(m) if m.contains("extra")),
        "{e}"
    );
    let e = err(r#"{"roi": {"sphere": {"center": [9, 9, 9], "radius": 0.1}}, "handles": []}"#)
        .unwrap_err();
    assert_eq!(e, EditError::EmptySelection("roi".into()));
    let e = err(r#"{"roi": {"box": {"min": [-2, -2, 1], "max": [2, 2, 3]}},
        "handles": [{"select": {"vertices": [0]}}]}"#)
    .unwrap_err();
    assert_eq!(
        e,
        EditError::HandleOutsideRoi {
            handle: 0,
            vertex: 0
        }
    );
    let e = err(r#"{"roi": "all", "handles": [{"select": {"vertices": [0]}}]}"#).unwrap_err();
    assert_eq!(e, EditError::NothingFixed);
    let e = err(r#"{"roi": "all", "anchors": {"vertices": [5]}, "handles": [{"select": {"vertices": [5]}}]}"#).unwrap_err();
    assert_eq!(
        e,
        EditError::HandleIsAnchor {
            handle: 0,
            vertex: 5
        }
    );
    let e = err(r#"{"roi": "all", "anchors": {"vertices": [99999]}, "handles": []}"#).unwrap_err();
    assert!(matches!(e, EditError::InvalidVertex { index: 99999, .. }));
    let e = err(r#"{"roi": "all", "anchors": {"vertices": [1]}, "handles": [{"select": {"vertices": [3]}, "transform": {"rotate": {"axis": [0,0,0], "deg": 3}}}]}"#).unwrap_err();
    assert!(matches!(e, EditError::BadTransform { handle: 0, .. }));
}

#[test]
fn implicit_rejects_a_planar_anchor_loop_without_gradient_constraint() {
    // A flat grid patch: the fixed ring and the handle all lie in z = 0.
    let mesh = plane_grid(8, 8, 1.0, 1.0, false);
    let json = r#"{"roi": {"box": {"min": [0.1, 0.1, -1], "max": [0.9, 0.9, 1]}},
        "handles": [{"select": {"sphere": {"center": [0.5, 0.5, 0], "radius": 0.01}},
                     "transform": {"translate": [0, 0, 0.2]}}]}"#;
    let spec = EditSpec::from_json(json).unwrap();
    let e = EditSession::<ImplicitEditor>::new(&mesh, &spec, Default::default()).unwrap_err();
    assert!(matches!(e, EditError::Singular(_)), "{e}");
    let fixed = json.replace("\"transform\"", "\"fix_gradient\": true, \"transform\"");
    let spec = EditSpec::from_json(&fixed).unwrap();
    let mut s = EditSession::<ImplicitEditor>::new(&mesh, &spec, Default::default()).unwrap();
    let out = s.solve_spec().unwrap();
    assert!(out.iter().all(|p| p.is_finite()));
    // Every interior vertex of the flat grid is degenerate and was displaced.
    assert!(s.method().n_degenerate > 0);
    assert_eq!(s.method().n_still_degenerate, 0);
}

#[test]
fn moves_never_refactor_and_equal_fresh_solves() {
    let mesh = icosphere(3, 1.0);
    let spec = EditSpec::from_json(
        r#"{"roi": {"sphere": {"center": [0, 0, 1], "radius": 1.0}},
            "handles": [{"select": {"sphere": {"center": [0, 0, 1], "radius": 0.2}}}]}"#,
    )
    .unwrap();
    let mut s = EditSession::<PoissonEditor>::new(&mesh, &spec, Default::default()).unwrap();
    let mut last = Vec::new();
    for k in 0..5 {
        let mut sp = spec.clone();
        sp.handles[0].transform.translate = Some([0.0, 0.05 * k as f64, 0.1]);
        s.set_spec(&sp).unwrap();
        last = s.solve_spec().unwrap();
    }
    assert_eq!(s.stats().factorizations, 1);
    assert_eq!(s.stats().solves, 5);
    let mut sp = spec.clone();
    sp.handles[0].transform.translate = Some([0.0, 0.2, 0.1]);
    let fresh = EditSession::<PoissonEditor>::new(&mesh, &sp, Default::default())
        .unwrap()
        .solve_spec()
        .unwrap();
    assert!(max_dist(&last, &fresh) < 1e-12);
    // A new ROI refactors once.
    sp.roi = Select::All;
    sp.anchors = Some(Select::Vertices(vec![0]));
    s.set_spec(&sp).unwrap();
    assert_eq!(s.stats().factorizations, 2);
}
