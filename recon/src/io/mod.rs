//! Mesh files: OBJ, OFF, PLY (ASCII, binary little- and big-endian) and STL (ASCII and
//! binary), plus Matrix Market for sparse matrices.
//!
//! Readers stream from any `BufRead` into a flat [`PolygonSoup`]; they never trust a count
//! in a header for allocation (reservations are capped at [`limits::RESERVE_CAP`]), bound
//! line lengths and polygon degrees, reject NaN/∞ coordinates and out-of-range indices,
//! and report the line (text) or byte offset (binary) of the problem in [`IoError`].
//! Writers print coordinates with Rust's shortest round-trip formatting (text) or as
//! `f64` (binary PLY), so coordinates round-trip bit-exactly; binary STL stores `f32` by
//! definition and is exact only for `f32`-representable input.

mod error;
mod lines;
mod matrix_market;
mod obj;
mod off;
mod ply;
mod soup;
mod stl;

pub use error::IoError;
pub use matrix_market::{read_matrix_market, write_matrix_market_lower, MatrixMarket, MtxSymmetry};
pub use obj::{read_obj, write_obj};
pub use off::{read_off, write_off};
pub use ply::{read_ply, write_ply, PlyEncoding};
pub use soup::PolygonSoup;
pub use stl::{read_stl, write_stl, StlEncoding};

use crate::mesh::{mesh_info, MeshInfo, Repairs, SurfaceMesh};
use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::Path;

/// Limits that protect readers from hostile input.
pub mod limits {
    /// Largest number of elements reserved up front from a header count.
    pub const RESERVE_CAP: usize = 1 << 20;
    /// Largest number of vertices or faces accepted (32-bit mesh handles).
    pub const MAX_ELEMENTS: u64 = (u32::MAX / 4) as u64;
    /// Largest polygon degree accepted.
    pub const MAX_FACE_DEGREE: usize = 1 << 16;
    /// Largest Matrix Market dimension (the column pointer array is allocated from it).
    pub const MAX_MATRIX_DIM: u64 = 1 << 26;
    /// Longest text line accepted, in bytes.
    pub const MAX_LINE: usize = 1 << 20;
}

/// A file format chosen from a path's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ.
    Obj,
    /// Object File Format.
    Off,
    /// Stanford PLY.
    Ply,
    /// Stereolithography.
    Stl,
}

impl MeshFormat {
    /// The format for a path's extension (case-insensitive), if known.
    pub fn from_path(path: &Path) -> Result<Self, IoError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Ok(Self::Obj),
            "off" => Ok(Self::Off),
            "ply" => Ok(Self::Ply),
            "stl" => Ok(Self::Stl),
            _ => Err(IoError::UnsupportedFormat(path.display().to_string())),
        }
    }
}

/// Reads a mesh file, choosing the format from the extension.
pub fn read_mesh_file(path: impl AsRef<Path>) -> Result<PolygonSoup, IoError> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let r = BufReader::with_capacity(1 << 16, File::open(path)?);
    match format {
        MeshFormat::Obj => read_obj(r),
        MeshFormat::Off => read_off(r),
        MeshFormat::Ply => read_ply(r),
        MeshFormat::Stl => read_stl(r),
    }
}

/// Reads a mesh file into a halfedge mesh, repairing what the file's polygons need (see
/// [`SurfaceMesh::from_polygons_repaired`]); returns the mesh and what was repaired.
pub fn read_mesh_file_repaired(path: impl AsRef<Path>) -> Result<(SurfaceMesh, Repairs), IoError> {
    read_mesh_file(path)?.to_mesh_repaired()
}

/// [`mesh_info`] of a mesh file read with [`read_mesh_file_repaired`].
pub fn mesh_file_info(path: impl AsRef<Path>) -> Result<MeshInfo, IoError> {
    let (mesh, repairs) = read_mesh_file_repaired(path)?;
    Ok(mesh_info(&mesh, &repairs))
}

/// Writes a mesh file, choosing the format from the extension (PLY and STL binary).
pub fn write_mesh_file(path: impl AsRef<Path>, soup: &PolygonSoup) -> Result<(), IoError> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let mut w = BufWriter::with_capacity(1 << 16, File::create(path)?);
    match format {
        MeshFormat::Obj => write_obj(&mut w, soup)?,
        MeshFormat::Off => write_off(&mut w, soup)?,
        MeshFormat::Ply => write_ply(&mut w, soup, PlyEncoding::BinaryLittleEndian)?,
        MeshFormat::Stl => write_stl(&mut w, soup, StlEncoding::Binary)?,
    }
    w.flush()?;
    Ok(())
}
