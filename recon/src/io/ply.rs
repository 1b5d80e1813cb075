//! Stanford PLY: ASCII, binary little-endian and binary big-endian bodies.
//!
//! Reads the `x y z` properties of `vertex` (any scalar type; others ignored) and the
//! `vertex_indices`/`vertex_index` list of `face`; other elements and properties are
//! parsed and skipped. Writes `double` coordinates and `uchar`/`uint` + `int` face lists.

use std::io::{BufRead, Read, Write};

use super::lines::{check_count, truncate, Lines};
use super::soup::write_counted_face_lines;
use super::{limits, IoError, PolygonSoup};
use crate::geometry::Vec3;

/// Body encoding of a PLY file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyEncoding {
    /// Text body.
    Ascii,
    /// Little-endian binary body.
    BinaryLittleEndian,
    /// Big-endian binary body (read only).
    BinaryBigEndian,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
    fn is_float(self) -> bool {
        matches!(self, Self::F32 | Self::F64)
    }
    fn decode(self, b: &[u8], little: bool) -> f64 {
        macro_rules! d {
            ($t:ty, $n:literal) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                (if little {
                    <$t>::from_le_bytes(a)
                } else {
                    <$t>::from_be_bytes(a)
                }) as f64
            }};
        }
        match self {
            Self::I8 => b[0] as i8 as f64,
            Self::U8 => b[0] as f64,
            Self::I16 => d!(i16, 2),
            Self::U16 => d!(u16, 2),
            Self::I32 => d!(i32, 4),
            Self::U32 => d!(u32, 4),
            Self::F32 => d!(f32, 4),
            Self::F64 => d!(f64, 8),
        }
    }
}

#[derive(Debug, Clone)]
enum Kind {
    Scalar(Scalar),
    List(Scalar, Scalar),
}

#[derive(Debug, Clone)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

struct Header {
    encoding: PlyEncoding,
    elements: Vec<Element>,
}

fn parse_header<R: BufRead>(lines: &mut Lines<R>) -> Result<Header, IoError> {
    if lines.next_line()?.map(|l| l.1.trim()) != Some("ply") {
        return Err(IoError::syntax(1, "missing `ply` magic"));
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let end = lines.line + 1;
        let (ln, l) = lines
            .next_line()?
            .ok_or_else(|| IoError::syntax(end, "header ends without end_header"))?;
        let t: Vec<&str> = l.split_whitespace().collect();
        match t.first().copied() {
            Some("end_header") => break,
            Some("format") => {
                encoding = Some(match t.get(1).copied() {
                    Some("ascii") => PlyEncoding::Ascii,
                    Some("binary_little_endian") => PlyEncoding::BinaryLittleEndian,
                    Some("binary_big_endian") => PlyEncoding::BinaryBigEndian,
                    _ => return Err(IoError::syntax(ln, "unknown format")),
                })
            }
            Some("element") => {
                if elements.len() > 64 {
                    return Err(IoError::syntax(ln, "too many elements"));
                }
                let count: u64 = t
                    .get(2)
                    .and_then(|c| c.parse().ok())
                    .ok_or_else(|| IoError::syntax(ln, "bad element count"))?;
                let name = t.get(1).copied().unwrap_or("").to_owned();
                elements.push(Element {
                    name,
                    count: check_count("element count", count)?,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| IoError::syntax(ln, "property before element"))?;
                if e.props.len() > 256 {
                    return Err(IoError::syntax(ln, "too many properties"));
                }
                e.props.push(parse_property(&t, ln)?);
            }
            Some("comment" | "obj_info") | None => {}
            Some(other) => {
                return Err(IoError::syntax(
                    ln,
                    format!("unknown header keyword `{}`", truncate(other)),
                ))
            }
        }
    }
    let encoding = encoding.ok_or_else(|| IoError::syntax(lines.line, "missing format line"))?;
    // A record without properties occupies no bytes: a huge count would spin (and grow
    // the face list) without reading anything.
    if let Some(e) = elements.iter().find(|e| e.count > 0 && e.props.is_empty()) {
        return Err(IoError::syntax(
            lines.line,
            format!("element `{}` has no properties", truncate(&e.name)),
        ));
    }
    Ok(Header { encoding, elements })
}

fn parse_property(t: &[&str], ln: usize) -> Result<Property, IoError> {
    let bad = || IoError::syntax(ln, "bad property line");
    let scalar = |s: Option<&&str>| s.and_then(|s| Scalar::parse(s)).ok_or_else(bad);
    if t.get(1) == Some(&"list") {
        let (c, i) = (scalar(t.get(2))?, scalar(t.get(3))?);
        if c.is_float() {
            return Err(bad());
        }
        Ok(Property {
            name: t.get(4).ok_or_else(bad)?.to_string(),
            kind: Kind::List(c, i),
        })
    } else {
        Ok(Property {
            name: t.get(2).ok_or_else(bad)?.to_string(),
            kind: Kind::Scalar(scalar(t.get(1))?),
        })
    }
}

/// What a property feeds: a coordinate, the face list, or nothing.
#[derive(Clone, Copy, PartialEq)]
enum Role {
    Coord(usize),
    Faces,
    Skip,
}

fn roles(e: &Element) -> Vec<Role> {
    e.props
        .iter()
        .map(|p| match (e.name.as_str(), p.name.as_str(), &p.kind) {
            ("vertex", "x", Kind::Scalar(_)) => Role::Coord(0),
            ("vertex", "y", Kind::Scalar(_)) => Role::Coord(1),
            ("vertex", "z", Kind::Scalar(_)) => Role::Coord(2),
            ("face", "vertex_indices" | "vertex_index", Kind::List(..)) => Role::Faces,
            _ => Role::Skip,
        })
        .collect()
}

/// Reads a PLY file (any of the three encodings).
pub fn read_ply<R: BufRead>(reader: R) -> Result<PolygonSoup, IoError> {
    let mut lines = Lines::new(reader);
    let header = parse_header(&mut lines)?;
    let mut soup = PolygonSoup::new();
    let nv = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count);
    soup.points.reserve(nv.min(limits::RESERVE_CAP));
    let mut sink = Sink {
        soup: &mut soup,
        nv,
        face: Vec::new(),
        coord: [0.0; 3],
    };
    match header.encoding {
        PlyEncoding::Ascii => read_ascii_body(&mut lines, &header, &mut sink)?,
        enc => {
            let offset = lines.bytes;
            let mut r = Binary {
                r: lines.into_inner(),
                offset,
                little: enc == PlyEncoding::BinaryLittleEndian,
                buf: [0; 8],
            };
            read_binary_body(&mut r, &header, &mut sink)?;
        }
    }
    if soup.points.len() != nv {
        return Err(IoError::syntax(0, "vertex element lacks x, y or z"));
    }
    Ok(soup)
}

struct Sink<'a> {
    soup: &'a mut PolygonSoup,
    nv: usize,
    face: Vec<usize>,
    coord: [f64; 3],
}

impl Sink<'_> {
    fn index(&mut self, v: f64, at: impl Fn(String) -> IoError) -> Result<(), IoError> {
        if !(v >= 0.0 && v < self.nv as f64 && v.fract() == 0.0) {
            return Err(at(format!(
                "vertex index {v} out of range (nv = {})",
                self.nv
            )));
        }
        self.face.push(v as usize);
        Ok(())
    }
    fn coord(&mut self, c: usize, v: f64, at: impl Fn(String) -> IoError) -> Result<(), IoError> {
        if !v.is_finite() {
            return Err(at("non-finite coordinate".into()));
        }
        self.coord[c] = v;
        Ok(())
    }
    fn end_record(&mut self, e: &Element, has_xyz: bool) {
        if e.name == "vertex" && has_xyz {
            self.soup.points.push(Vec3::from_array(self.coord));
        } else if e.name == "face" {
            self.soup.push_face(&self.face);
        }
        self.face.clear();
    }
}

fn has_xyz(roles: &[Role]) -> bool {
    (0..3).all(|c| roles.contains(&Role::Coord(c)))
}

fn check_degree(n: f64, at: impl Fn(String) -> IoError) -> Result<usize, IoError> {
    if !(n >= 0.0 && n <= limits::MAX_FACE_DEGREE as f64) {
        return Err(at(format!("list length {n} out of range")));
    }
    Ok(n as usize)
}

fn read_ascii_body<R: BufRead>(
    lines: &mut Lines<R>,
    header: &Header,
    sink: &mut Sink<'_>,
) -> Result<(), IoError> {
    for e in &header.elements {
        let roles = roles(e);
        let xyz = has_xyz(&roles);
        for _ in 0..e.count {
            let (ln, l) = lines.require_content_line("an element list")?;
            let at = |m: String| IoError::syntax(ln, m);
            let mut toks = l.split_whitespace();
            let mut num = || -> Result<f64, IoError> {
                let t = toks.next().ok_or_else(|| at("missing value".into()))?;
                t.parse::<f64>()
                    .map_err(|_| at(format!("bad number `{}`", truncate(t))))
            };
            for (p, &role) in e.props.iter().zip(&roles) {
                match (&p.kind, role) {
                    (Kind::Scalar(_), Role::Coord(c)) => sink.coord(c, num()?, at)?,
                    (Kind::Scalar(_), _) => {
                        num()?;
                    }
                    (Kind::List(..), role) => {
                        let n = check_degree(num()?, at)?;
                        for _ in 0..n {
                            let v = num()?;
                            if role == Role::Faces {
                                sink.index(v, at)?;
                            }
                        }
                    }
                }
            }
            sink.end_record(e, xyz);
        }
    }
    Ok(())
}

struct Binary<R> {
    r: R,
    offset: u64,
    little: bool,
    buf: [u8; 8],
}

impl<R: Read> Binary<R> {
    fn bytes(&mut self, out: &mut [u8]) -> Result<(), IoError> {
        if let Err(e) = self.r.read_exact(out) {
            return Err(match e.kind() {
                std::io::ErrorKind::UnexpectedEof => IoError::binary(self.offset, "truncated file"),
                _ => IoError::Io(e),
            });
        }
        self.offset += out.len() as u64;
        Ok(())
    }

    fn scalar(&mut self, s: Scalar) -> Result<f64, IoError> {
        let mut b = self.buf;
        self.bytes(&mut b[..s.size()])?;
        Ok(s.decode(&b[..s.size()], self.little))
    }
}

/// Byte offset of every scalar property in a record, or `None` if the element has lists.
fn fixed_layout(e: &Element) -> Option<(usize, Vec<(usize, Scalar)>)> {
    let mut off = 0;
    let mut layout = Vec::with_capacity(e.props.len());
    for p in &e.props {
        let Kind::Scalar(s) = p.kind else { return None };
        layout.push((off, s));
        off += s.size();
    }
    Some((off, layout))
}

fn read_binary_body<R: Read>(
    r: &mut Binary<R>,
    header: &Header,
    sink: &mut Sink<'_>,
) -> Result<(), IoError> {
    let mut record = Vec::new();
    for e in &header.elements {
        let roles = roles(e);
        let xyz = has_xyz(&roles);
        let fixed = fixed_layout(e);
        for _ in 0..e.count {
            let start = r.offset;
            let at = |m: String| IoError::binary(start, m);
            if let Some((size, layout)) = &fixed {
                record.resize(*size, 0);
                r.bytes(&mut record)?;
                for (&(off, s), &role) in layout.iter().zip(&roles) {
                    if let Role::Coord(c) = role {
                        sink.coord(c, s.decode(&record[off..], r.little), at)?;
                    }
                }
                sink.end_record(e, xyz);
                continue;
            }
            for (p, &role) in e.props.iter().zip(&roles) {
                match (&p.kind, role) {
                    (Kind::Scalar(s), Role::Coord(c)) => {
                        let v = r.scalar(*s)?;
                        sink.coord(c, v, at)?
                    }
                    (Kind::Scalar(s), _) => {
                        r.scalar(*s)?;
                    }
                    (Kind::List(cs, is), role) => {
                        let n = check_degree(r.scalar(*cs)?, at)?;
                        record.resize(n * is.size(), 0);
                        r.bytes(&mut record)?;
                        if role != Role::Faces {
                            continue;
                        }
                        if is.is_float() {
                            return Err(at("face indices must be integers".into()));
                        }
                        for k in 0..n {
                            sink.index(is.decode(&record[k * is.size()..], r.little), at)?;
                        }
                    }
                }
            }
            sink.end_record(e, xyz);
        }
    }
    Ok(())
}

/// Writes a PLY file with `double` coordinates. Big-endian writing is not supported.
pub fn write_ply<W: Write>(
    mut w: W,
    soup: &PolygonSoup,
    encoding: PlyEncoding,
) -> Result<(), IoError> {
    let fmt = match encoding {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        PlyEncoding::BinaryBigEndian => return Err(IoError::Unwritable("big-endian PLY".into())),
    };
    if soup.points.len() > i32::MAX as usize {
        return Err(IoError::Unwritable("more than 2³¹ vertices".into()));
    }
    let max_degree = soup.faces().map(<[usize]>::len).max().unwrap_or(0);
    let count_type = if max_degree <= 255 { "uchar" } else { "uint" };
    write!(
        w,
        "ply\nformat {fmt} 1.0\ncomment fires-recon\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement face {}\nproperty list {count_type} int vertex_indices\nend_header\n",
        soup.points.len(),
        soup.n_faces()
    )?;
    if encoding == PlyEncoding::Ascii {
        for p in &soup.points {
            writeln!(w, "{:?} {:?} {:?}", p.x, p.y, p.z)?;
        }
        return write_counted_face_lines(&mut w, soup);
    }
    let mut buf = Vec::with_capacity(1 << 16);
    for p in &soup.points {
        for c in p.to_array() {
            buf.extend_from_slice(&c.to_le_bytes());
        }
        flush_if_full(&mut w, &mut buf)?;
    }
    for f in soup.faces() {
        if count_type == "uchar" {
            buf.push(f.len() as u8);
        } else {
            buf.extend_from_slice(&(f.len() as u32).to_le_bytes());
        }
        for &i in f {
            buf.extend_from_slice(&(i as i32).to_le_bytes());
        }
        flush_if_full(&mut w, &mut buf)?;
    }
    w.write_all(&buf)?;
    Ok(())
}

pub(crate) fn flush_if_full<W: Write>(w: &mut W, buf: &mut Vec<u8>) -> Result<(), IoError> {
    if buf.len() >= (1 << 16) - 1024 {
        w.write_all(buf)?;
        buf.clear();
    }
    Ok(())
}
