//! Wavefront OBJ: `v x y z [w]` and `f` lines (`i`, `i/t`, `i/t/n`, `i//n`, negative
//! relative indices; a face may only use vertices defined above it); every other statement (`vt`, `vn`, `g`, `o`, `s`, `usemtl`, `l`, …)
//! is skipped.

use std::io::{BufRead, Write};

use super::lines::{parse_coord, truncate, Lines};
use super::{limits, IoError, PolygonSoup};
use crate::geometry::Vec3;

/// Reads an OBJ file (geometry and faces only).
pub fn read_obj<R: BufRead>(reader: R) -> Result<PolygonSoup, IoError> {
    let mut lines = Lines::new(reader);
    let mut soup = PolygonSoup::new();
    let mut face = Vec::new();
    while let Some((ln, l)) = lines.next_content_line()? {
        let mut t = l.split_whitespace();
        match t.next() {
            Some("v") => {
                if soup.points.len() as u64 >= limits::MAX_ELEMENTS {
                    return Err(IoError::Limit {
                        what: "vertex count",
                        value: soup.points.len() as u64,
                        limit: limits::MAX_ELEMENTS,
                    });
                }
                soup.points.push(Vec3::new(
                    parse_coord(t.next(), ln)?,
                    parse_coord(t.next(), ln)?,
                    parse_coord(t.next(), ln)?,
                ));
            }
            Some("f") => {
                face.clear();
                for tok in t {
                    if face.len() >= limits::MAX_FACE_DEGREE {
                        return Err(IoError::Limit {
                            what: "face degree",
                            value: face.len() as u64,
                            limit: limits::MAX_FACE_DEGREE as u64,
                        });
                    }
                    face.push(parse_obj_index(tok, soup.points.len(), ln)?);
                }
                soup.push_face(&face);
            }
            _ => {}
        }
    }
    soup.check_indices()?;
    Ok(soup)
}

/// Resolves `i[/t[/n]]` (1-based, or negative relative to the `n_defined` vertices so far).
fn parse_obj_index(tok: &str, n_defined: usize, line: usize) -> Result<usize, IoError> {
    let first = tok.split('/').next().unwrap_or("");
    let i: i64 = first
        .parse()
        .map_err(|_| IoError::syntax(line, format!("bad face index `{}`", truncate(tok))))?;
    let resolved = match i {
        0 => None,
        i if i > 0 => Some(i as u64 - 1),
        i => (n_defined as u64).checked_sub(i.unsigned_abs()),
    };
    resolved
        .filter(|&r| r < n_defined as u64)
        .map(|r| r as usize)
        .ok_or_else(|| IoError::syntax(line, format!("face index {i} out of range")))
}

/// Writes an OBJ file (coordinates in shortest round-trip form, 1-based indices).
pub fn write_obj<W: Write>(mut w: W, soup: &PolygonSoup) -> Result<(), IoError> {
    for p in &soup.points {
        writeln!(w, "v {:?} {:?} {:?}", p.x, p.y, p.z)?;
    }
    for f in soup.faces() {
        write!(w, "f")?;
        for i in f {
            write!(w, " {}", i + 1)?;
        }
        writeln!(w)?;
    }
    Ok(())
}
