//! The software rasteriser: fitting, z-buffer, lines on top, PNG round trip.

use fires_recon::generate::{cube, icosphere};
use fires_recon::render::{
    render, save_png, side_by_side, Polyline, RenderOptions, Scene, SceneMesh,
};
use fires_recon::Vec3;

#[test]
fn sphere_fills_the_middle_and_leaves_the_corners_blank() {
    let mut scene = Scene::default();
    scene
        .meshes
        .push(SceneMesh::from_mesh(&icosphere(3, 1.0), [200, 100, 50]));
    let o = RenderOptions {
        width: 200,
        height: 200,
        ..Default::default()
    };
    let img = render(&scene, &o);
    assert_eq!(img.get_pixel(0, 0).0, [255, 255, 255]);
    assert_ne!(img.get_pixel(100, 100).0, [255, 255, 255]);
    // Fitted: the disc reaches within the margin of the image border.
    let row: Vec<bool> = (0..200)
        .map(|x| img.get_pixel(x, 100).0 != [255, 255, 255])
        .collect();
    let first = row.iter().position(|&b| b).unwrap();
    assert!((10..=14).contains(&first), "left edge at {first}");
}

#[test]
fn nearer_surface_wins_and_lines_are_drawn_over() {
    let mut near = SceneMesh::from_mesh(&cube(1.0, true), [255, 0, 0]);
    for p in &mut near.positions {
        *p = *p * 0.5 + Vec3::new(0.0, 0.0, 2.0);
    }
    let far = SceneMesh::from_mesh(&cube(2.0, true), [0, 0, 255]);
    let mut scene = Scene::default();
    scene.meshes.push(far);
    scene.meshes.push(near);
    let mut o = RenderOptions {
        width: 100,
        height: 100,
        ambient: 1.0,
        ..Default::default()
    };
    o.camera.direction = Vec3::new(0.0, 0.0, -1.0);
    o.camera.up = Vec3::new(0.0, 1.0, 0.0);
    let img = render(&scene, &o);
    assert_eq!(
        img.get_pixel(50, 50).0,
        [255, 0, 0],
        "the nearer red cube is in front"
    );
    assert_eq!(img.get_pixel(20, 50).0, [0, 0, 255]);
    scene.polylines.push(Polyline {
        points: vec![Vec3::new(-1.0, 0.0, 5.0 - 10.0), Vec3::new(1.0, 0.0, -5.0)],
        color: [0, 255, 0],
        width: 3,
        closed: false,
    });
    let img = render(&scene, &o);
    assert_eq!(
        img.get_pixel(50, 50).0,
        [0, 255, 0],
        "lines are drawn over surfaces"
    );
    let dir = std::env::temp_dir().join("fires_render_test.png");
    save_png(&side_by_side(&[img.clone(), img]), &dir).unwrap();
    let back = image::open(&dir).unwrap().to_rgb8();
    assert_eq!(back.width(), 200);
}
