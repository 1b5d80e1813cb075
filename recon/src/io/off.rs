//! OFF (Object File Format): `OFF` header (also `COFF`, `NOFF`, `CNOFF`, `STOFF`…: extra
//! per-vertex values are ignored), counts `nv nf ne`, vertex lines, then
//! `k i₁ … i_k [colour]` face lines; `#` comments and blank lines allowed.

use std::io::{BufRead, Write};

use super::lines::{check_count, parse_coord, parse_usize, Lines};
use super::soup::write_counted_face_lines;
use super::{limits, IoError, PolygonSoup};
use crate::geometry::Vec3;

/// Reads an OFF file.
pub fn read_off<R: BufRead>(reader: R) -> Result<PolygonSoup, IoError> {
    let mut lines = Lines::new(reader);
    let (line, first) = lines.require_content_line("the header")?;
    let first = first.to_owned();
    let mut toks = first.split_whitespace();
    let keyword = toks.next().unwrap_or("");
    if !keyword.ends_with("OFF") || keyword.len() > 6 {
        return Err(IoError::syntax(line, "missing OFF header"));
    }
    let mut rest: Vec<String> = toks.map(str::to_owned).collect();
    let mut line = line;
    if rest.is_empty() {
        let (ln, l) = lines.require_content_line("the header")?;
        rest = l.split_whitespace().map(str::to_owned).collect();
        line = ln;
    }
    let mut it = rest.iter().map(String::as_str);
    let nv = check_count(
        "vertex count",
        parse_usize(it.next(), line, "vertex count")? as u64,
    )?;
    let nf = check_count(
        "face count",
        parse_usize(it.next(), line, "face count")? as u64,
    )?;
    let mut soup = PolygonSoup::new();
    soup.points.reserve(nv.min(limits::RESERVE_CAP));
    soup.face_starts.reserve(nf.min(limits::RESERVE_CAP));
    for _ in 0..nv {
        let (ln, l) = lines.require_content_line("the vertex list")?;
        let mut t = l.split_whitespace();
        soup.points.push(Vec3::new(
            parse_coord(t.next(), ln)?,
            parse_coord(t.next(), ln)?,
            parse_coord(t.next(), ln)?,
        ));
    }
    let mut face = Vec::new();
    for _ in 0..nf {
        let (ln, l) = lines.require_content_line("the face list")?;
        let mut t = l.split_whitespace();
        let k = parse_usize(t.next(), ln, "face degree")?;
        if k > limits::MAX_FACE_DEGREE {
            return Err(IoError::Limit {
                what: "face degree",
                value: k as u64,
                limit: limits::MAX_FACE_DEGREE as u64,
            });
        }
        face.clear();
        for _ in 0..k {
            let i = parse_usize(t.next(), ln, "vertex index")?;
            if i >= nv {
                return Err(IoError::syntax(
                    ln,
                    format!("vertex index {i} out of range (nv = {nv})"),
                ));
            }
            face.push(i);
        }
        soup.push_face(&face);
    }
    Ok(soup)
}

/// Writes an OFF file (coordinates in shortest round-trip form).
pub fn write_off<W: Write>(mut w: W, soup: &PolygonSoup) -> Result<(), IoError> {
    writeln!(w, "OFF\n{} {} 0", soup.points.len(), soup.n_faces())?;
    for p in &soup.points {
        writeln!(w, "{:?} {:?} {:?}", p.x, p.y, p.z)?;
    }
    write_counted_face_lines(&mut w, soup)
}
