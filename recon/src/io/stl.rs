//! STL, ASCII and binary. Reading merges corners with bit-identical coordinates into shared
//! vertices; writing fan-triangulates polygons and computes facet normals. Binary STL
//! stores `f32`: coordinates round-trip exactly only if they are `f32`-representable.

use std::collections::HashMap;
use std::io::{BufRead, Read, Write};

use super::lines::{parse_coord, truncate, Lines};
use super::ply::flush_if_full;
use super::{limits, IoError, PolygonSoup};
use crate::geometry::{triangle_normal, Vec3};

/// STL flavour for writing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StlEncoding {
    /// `solid … endsolid` text.
    Ascii,
    /// 80-byte header, triangle count, 50 bytes per triangle.
    Binary,
}

/// Welds corners with identical coordinates into indexed vertices.
#[derive(Default)]
struct Welder {
    map: HashMap<[u64; 3], usize>,
    soup: PolygonSoup,
}

impl Welder {
    fn corner(&mut self, p: Vec3) -> usize {
        let key = p.to_array().map(|c| if c == 0.0 { 0 } else { c.to_bits() });
        let soup = &mut self.soup;
        *self.map.entry(key).or_insert_with(|| {
            soup.points.push(p);
            soup.points.len() - 1
        })
    }
    fn triangle(&mut self, t: [Vec3; 3]) {
        let idx = t.map(|p| self.corner(p));
        self.soup.push_face(&idx);
    }
}

/// Reads an STL file, detecting ASCII (`solid` followed by `facet`) or binary.
pub fn read_stl<R: BufRead>(mut reader: R) -> Result<PolygonSoup, IoError> {
    let head = reader.fill_buf()?;
    let text = head.starts_with(b"solid") && {
        let n = head.len().min(1024);
        head[..n].windows(5).any(|w| w == b"facet")
            || head[..n].windows(8).any(|w| w == b"endsolid")
    };
    let mut welder = Welder {
        soup: PolygonSoup::new(),
        ..Default::default()
    };
    if text {
        read_ascii(reader, &mut welder)?;
    } else {
        read_binary(reader, &mut welder)?;
    }
    Ok(welder.soup)
}

fn read_ascii<R: BufRead>(reader: R, welder: &mut Welder) -> Result<(), IoError> {
    let mut lines = Lines::new(reader);
    let mut corners: Vec<Vec3> = Vec::with_capacity(3);
    while let Some((ln, l)) = lines.next_content_line()? {
        let mut t = l.split_whitespace();
        match t.next() {
            Some("vertex") => {
                if corners.len() == 3 {
                    return Err(IoError::syntax(ln, "facet with more than 3 vertices"));
                }
                corners.push(Vec3::new(
                    parse_coord(t.next(), ln)?,
                    parse_coord(t.next(), ln)?,
                    parse_coord(t.next(), ln)?,
                ));
            }
            Some("endloop") => {
                if corners.len() != 3 {
                    return Err(IoError::syntax(ln, "facet without 3 vertices"));
                }
                welder.triangle([corners[0], corners[1], corners[2]]);
                corners.clear();
            }
            Some("solid" | "facet" | "outer" | "endfacet" | "endsolid") => {}
            Some(other) => {
                return Err(IoError::syntax(
                    ln,
                    format!("unexpected `{}`", truncate(other)),
                ))
            }
            None => {}
        }
    }
    if !corners.is_empty() {
        return Err(IoError::syntax(lines.line, "file ends inside a facet"));
    }
    Ok(())
}

fn read_binary<R: Read>(mut r: R, welder: &mut Welder) -> Result<(), IoError> {
    let mut header = [0u8; 84];
    read_exact_at(&mut r, &mut header, 0)?;
    let count = u32::from_le_bytes([header[80], header[81], header[82], header[83]]) as u64;
    if count > limits::MAX_ELEMENTS {
        return Err(IoError::Limit {
            what: "triangle count",
            value: count,
            limit: limits::MAX_ELEMENTS,
        });
    }
    welder
        .soup
        .points
        .reserve((count as usize).min(limits::RESERVE_CAP));
    let mut rec = [0u8; 50];
    for k in 0..count {
        let offset = 84 + 50 * k;
        read_exact_at(&mut r, &mut rec, offset)?;
        let f = |i: usize| f32::from_le_bytes([rec[i], rec[i + 1], rec[i + 2], rec[i + 3]]) as f64;
        let p = |c: usize| Vec3::new(f(12 + 12 * c), f(16 + 12 * c), f(20 + 12 * c));
        let t = [p(0), p(1), p(2)];
        if !t.iter().all(|p| p.is_finite()) {
            return Err(IoError::binary(offset, "non-finite coordinate"));
        }
        welder.triangle(t);
    }
    Ok(())
}

fn read_exact_at<R: Read>(r: &mut R, buf: &mut [u8], offset: u64) -> Result<(), IoError> {
    r.read_exact(buf).map_err(|e| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => IoError::binary(offset, "truncated file"),
        _ => IoError::Io(e),
    })
}

fn triangles(soup: &PolygonSoup) -> impl Iterator<Item = [Vec3; 3]> + '_ {
    soup.faces().flat_map(move |f| {
        let p = |i: usize| soup.points.get(f[i]).copied().unwrap_or(Vec3::ZERO);
        (1..f.len().saturating_sub(1)).map(move |k| [p(0), p(k), p(k + 1)])
    })
}

/// Writes an STL file (polygons fan-triangulated).
pub fn write_stl<W: Write>(
    mut w: W,
    soup: &PolygonSoup,
    encoding: StlEncoding,
) -> Result<(), IoError> {
    soup.check_indices()?;
    match encoding {
        StlEncoding::Ascii => {
            writeln!(w, "solid fires")?;
            for t in triangles(soup) {
                let n = triangle_normal(t[0], t[1], t[2]).normalize_or_zero();
                writeln!(w, "facet normal {:?} {:?} {:?}\nouter loop", n.x, n.y, n.z)?;
                for p in t {
                    writeln!(w, "vertex {:?} {:?} {:?}", p.x, p.y, p.z)?;
                }
                writeln!(w, "endloop\nendfacet")?;
            }
            writeln!(w, "endsolid fires")?;
        }
        StlEncoding::Binary => {
            let count = triangles(soup).count();
            let count = u32::try_from(count)
                .map_err(|_| IoError::Unwritable("more than 2³² triangles".into()))?;
            let mut header = [b' '; 80];
            header[..11].copy_from_slice(b"fires-recon");
            w.write_all(&header)?;
            w.write_all(&count.to_le_bytes())?;
            let mut buf = Vec::with_capacity(1 << 16);
            for t in triangles(soup) {
                let n = triangle_normal(t[0], t[1], t[2]).normalize_or_zero();
                for v in [n, t[0], t[1], t[2]] {
                    for c in v.to_array() {
                        buf.extend_from_slice(&(c as f32).to_le_bytes());
                    }
                }
                buf.extend_from_slice(&[0, 0]);
                flush_if_full(&mut w, &mut buf)?;
            }
            w.write_all(&buf)?;
        }
    }
    Ok(())
}
