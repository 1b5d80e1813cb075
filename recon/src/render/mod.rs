//! A small software rasteriser for pictures of meshes and curves, shared by every command
//! that draws: z-buffered flat-shaded (Lambert) polygons, polylines drawn over them, an
//! orthographic camera fitted automatically to the scene (its projected extent), PNG output.
//!
//! ```no_run
//! use fires_recon::render::{render, save_png, RenderOptions, Scene, SceneMesh};
//! let mesh = fires_recon::generate::icosphere(3, 1.0);
//! let mut scene = Scene::default();
//! scene.meshes.push(SceneMesh::from_mesh(&mesh, [200, 180, 150]));
//! let img = render(&scene, &RenderOptions::default());
//! save_png(&img, "sphere.png").unwrap();
//! ```

mod raster;

pub use image::RgbImage;
pub use raster::render;

use std::path::Path;

use crate::geometry::Vec3;
use crate::mesh::SurfaceMesh;

/// Errors of image output.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Encoding or writing the PNG failed.
    #[error("writing PNG: {0}")]
    Image(#[from] image::ImageError),
}

/// Polygons (any degree; fan-triangulated) with one colour.
#[derive(Debug, Clone, Default)]
pub struct SceneMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Polygons as vertex-index lists.
    pub faces: Vec<Vec<usize>>,
    /// Base colour (RGB).
    pub color: [u8; 3],
}

impl SceneMesh {
    /// The live faces of a mesh (indices as stored).
    pub fn from_mesh(mesh: &SurfaceMesh, color: [u8; 3]) -> Self {
        Self::from_positions(mesh, mesh.positions(), color)
    }

    /// A mesh's faces with other positions (e.g. an edited copy).
    pub fn from_positions(mesh: &SurfaceMesh, positions: &[Vec3], color: [u8; 3]) -> Self {
        Self {
            positions: positions.to_vec(),
            faces: mesh.face_index_lists(),
            color,
        }
    }
}

/// A polyline drawn over the surfaces.
#[derive(Debug, Clone, Default)]
pub struct Polyline {
    /// Points in order.
    pub points: Vec<Vec3>,
    /// Colour (RGB).
    pub color: [u8; 3],
    /// Width in pixels (≥ 1).
    pub width: u32,
    /// Join the last point to the first.
    pub closed: bool,
}

/// Everything to draw.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    /// Shaded surfaces.
    pub meshes: Vec<SceneMesh>,
    /// Lines drawn over the surfaces.
    pub polylines: Vec<Polyline>,
}

impl Scene {
    /// Axis-aligned bounds `(min, max)` of everything in the scene, `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let pts = self
            .meshes
            .iter()
            .flat_map(|m| m.positions.iter())
            .chain(self.polylines.iter().flat_map(|l| l.points.iter()));
        let mut out: Option<(Vec3, Vec3)> = None;
        for p in pts.filter(|p| p.is_finite()) {
            out = Some(match out {
                None => (*p, *p),
                Some((lo, hi)) => (
                    Vec3::new(lo.x.min(p.x), lo.y.min(p.y), lo.z.min(p.z)),
                    Vec3::new(hi.x.max(p.x), hi.y.max(p.y), hi.z.max(p.z)),
                ),
            });
        }
        out
    }
}

/// An orthographic camera looking along `direction`; the view is fitted to the scene.
#[derive(Debug, Clone, Copy)]
pub struct Camera {
    /// Viewing direction (from the eye into the scene).
    pub direction: Vec3,
    /// Approximate up direction on the image.
    pub up: Vec3,
}

impl Default for Camera {
    /// A three-quarter view from (+x, −y, +z), z up.
    fn default() -> Self {
        Self {
            direction: Vec3::new(-1.0, 1.0, -0.7),
            up: Vec3::new(0.0, 0.0, 1.0),
        }
    }
}

/// Image size, colours, light and camera.
#[derive(Debug, Clone, Copy)]
pub struct RenderOptions {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Background colour.
    pub background: [u8; 3],
    /// Direction the light travels (two-sided Lambert shading).
    pub light: Vec3,
    /// Ambient fraction of the base colour (0..1).
    pub ambient: f64,
    /// The camera.
    pub camera: Camera,
    /// Border kept free around the fitted view, in pixels.
    pub margin: u32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            background: [255, 255, 255],
            light: Vec3::new(-0.5, 0.8, -1.0),
            ambient: 0.25,
            camera: Camera::default(),
            margin: 12,
        }
    }
}

/// Writes an image as PNG.
pub fn save_png(img: &RgbImage, path: impl AsRef<Path>) -> Result<(), RenderError> {
    img.save_with_format(path, image::ImageFormat::Png)?;
    Ok(())
}

/// Images placed left to right on a common height (background white).
pub fn side_by_side(images: &[RgbImage]) -> RgbImage {
    let w: u32 = images.iter().map(|i| i.width()).sum();
    let h = images.iter().map(|i| i.height()).max().unwrap_or(0);
    let mut out = RgbImage::from_pixel(w.max(1), h.max(1), image::Rgb([255, 255, 255]));
    let mut x0 = 0;
    for img in images {
        for (x, y, p) in img.enumerate_pixels() {
            out.put_pixel(x0 + x, y, *p);
        }
        x0 += img.width();
    }
    out
}
