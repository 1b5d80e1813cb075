//! The rasteriser: orthographic projection fitted to the projected extent of the scene's
//! bounding geometry, z-buffered triangles with
//! flat two-sided Lambert shading, then polylines on top.

use image::{Rgb, RgbImage};

use super::{RenderOptions, Scene};
use crate::geometry::{triangle_normal, Vec3};

struct View {
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    scale: f64,
    cx: f64,
    cy: f64,
    w: f64,
    h: f64,
}

impl View {
    fn new(scene: &Scene, o: &RenderOptions) -> View {
        let forward = o
            .camera
            .direction
            .try_normalize()
            .unwrap_or(Vec3::new(0.0, 0.0, -1.0));
        let mut right = forward.cross(o.camera.up).normalize_or_zero();
        if right == Vec3::ZERO {
            right = forward.cross(Vec3::new(1.0, 0.0, 0.0)).normalize_or_zero();
        }
        let up = right.cross(forward);
        let (w, h) = (o.width as f64, o.height as f64);
        let mut lo = (f64::INFINITY, f64::INFINITY);
        let mut hi = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        let pts = scene
            .meshes
            .iter()
            .flat_map(|m| m.positions.iter())
            .chain(scene.polylines.iter().flat_map(|l| l.points.iter()));
        for c in pts.filter(|p| p.is_finite()) {
            let (x, y) = (c.dot(right), c.dot(up));
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        if !(lo.0 <= hi.0 && lo.1 <= hi.1) {
            lo = (-1.0, -1.0);
            hi = (1.0, 1.0);
        }
        let m = 2.0 * o.margin as f64;
        let sx = (w - m).max(1.0) / (hi.0 - lo.0).max(1e-300);
        let sy = (h - m).max(1.0) / (hi.1 - lo.1).max(1e-300);
        View {
            right,
            up,
            forward,
            scale: sx.min(sy),
            cx: 0.5 * (lo.0 + hi.0),
            cy: 0.5 * (lo.1 + hi.1),
            w,
            h,
        }
    }

    /// Pixel coordinates and depth (larger is farther).
    fn project(&self, p: Vec3) -> (f64, f64, f64) {
        (
            0.5 * self.w + (p.dot(self.right) - self.cx) * self.scale,
            0.5 * self.h - (p.dot(self.up) - self.cy) * self.scale,
            p.dot(self.forward),
        )
    }
}

fn shade(color: [u8; 3], intensity: f64) -> Rgb<u8> {
    Rgb(color.map(|c| (c as f64 * intensity).round().clamp(0.0, 255.0) as u8))
}

fn raster_triangle(img: &mut RgbImage, zbuf: &mut [f64], p: [(f64, f64, f64); 3], color: Rgb<u8>) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let area = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
    if area.abs() < 1e-12 || !area.is_finite() {
        return;
    }
    let xmin = p
        .iter()
        .map(|q| q.0)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as i64;
    let xmax = p
        .iter()
        .map(|q| q.0)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min((w - 1) as f64) as i64;
    let ymin = p
        .iter()
        .map(|q| q.1)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as i64;
    let ymax = p
        .iter()
        .map(|q| q.1)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min((h - 1) as f64) as i64;
    for y in ymin..=ymax {
        for x in xmin..=xmax {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let e = |a: (f64, f64, f64), b: (f64, f64, f64)| {
                (b.0 - a.0) * (py - a.1) - (px - a.0) * (b.1 - a.1)
            };
            let w0 = e(p[1], p[2]) / area;
            let w1 = e(p[2], p[0]) / area;
            let w2 = e(p[0], p[1]) / area;
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * p[0].2 + w1 * p[1].2 + w2 * p[2].2;
            let k = (y * w + x) as usize;
            if z < zbuf[k] {
                zbuf[k] = z;
                img.put_pixel(x as u32, y as u32, color);
            }
        }
    }
}

fn raster_line(img: &mut RgbImage, a: (f64, f64), b: (f64, f64), width: u32, color: Rgb<u8>) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).clamp(1, 1 << 16);
    let r = (width.max(1) as i64 - 1) / 2;
    for s in 0..=steps {
        let t = s as f64 / steps as f64;
        let (x, y) = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
        if !(x.is_finite() && y.is_finite()) {
            return;
        }
        let (xi, yi) = (x.floor() as i64, y.floor() as i64);
        for dy in -r..=r {
            for dx in -r..=r {
                let (px, py) = (xi + dx, yi + dy);
                if px >= 0 && py >= 0 && px < w && py < h {
                    img.put_pixel(px as u32, py as u32, color);
                }
            }
        }
    }
}

/// Draws the scene: the view is fitted to its bounding box.
pub fn render(scene: &Scene, o: &RenderOptions) -> RgbImage {
    let (w, h) = (o.width.max(1), o.height.max(1));
    let mut img = RgbImage::from_pixel(w, h, Rgb(o.background));
    let mut zbuf = vec![f64::INFINITY; (w as usize) * (h as usize)];
    let view = View::new(
        scene,
        &RenderOptions {
            width: w,
            height: h,
            ..*o
        },
    );
    let light = o.light.try_normalize().unwrap_or(view.forward);
    for m in &scene.meshes {
        let proj: Vec<_> = m.positions.iter().map(|&p| view.project(p)).collect();
        for f in &m.faces {
            if f.len() < 3 || f.iter().any(|&i| i >= m.positions.len()) {
                continue;
            }
            let pts: Vec<Vec3> = f.iter().map(|&i| m.positions[i]).collect();
            let mut n = Vec3::ZERO;
            for k in 1..pts.len() - 1 {
                n += triangle_normal(pts[0], pts[k], pts[k + 1]);
            }
            let n = n.normalize_or_zero();
            let lambert = n.dot(light).abs();
            let color = shade(m.color, o.ambient + (1.0 - o.ambient) * lambert);
            for k in 1..f.len() - 1 {
                raster_triangle(
                    &mut img,
                    &mut zbuf,
                    [proj[f[0]], proj[f[k]], proj[f[k + 1]]],
                    color,
                );
            }
        }
    }
    for l in &scene.polylines {
        let proj: Vec<_> = l.points.iter().map(|&p| view.project(p)).collect();
        let mut segs: Vec<(usize, usize)> = (1..proj.len()).map(|k| (k - 1, k)).collect();
        if l.closed && proj.len() > 2 {
            segs.push((proj.len() - 1, 0));
        }
        for (a, b) in segs {
            raster_line(
                &mut img,
                (proj[a].0, proj[a].1),
                (proj[b].0, proj[b].1),
                l.width,
                Rgb(l.color),
            );
        }
    }
    img
}
