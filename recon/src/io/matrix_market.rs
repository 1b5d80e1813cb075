//! Matrix Market coordinate files (`%%MatrixMarket matrix coordinate real|integer|pattern
//! general|symmetric`), the input of `fires bench solve`.

use std::io::{BufRead, Write};

use super::lines::{check_count, parse_usize, truncate, Lines};
use super::{limits, IoError};
use crate::solve::{sparse_from_triplets, sparse_triplets, SparseMatrix};

/// Symmetry declared in the banner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MtxSymmetry {
    /// All entries stored.
    General,
    /// Only one triangle stored (either one is accepted).
    Symmetric,
}

/// A sparse matrix read from a Matrix Market file.
#[derive(Debug, Clone)]
pub struct MatrixMarket {
    /// Declared symmetry.
    pub symmetry: MtxSymmetry,
    /// Number of rows.
    pub nrows: usize,
    /// Number of columns.
    pub ncols: usize,
    /// 0-based `(row, col, value)` entries as stored in the file.
    pub entries: Vec<(usize, usize, f64)>,
}

impl MatrixMarket {
    /// The lower triangle (for symmetric files, entries of either stored triangle are
    /// mirrored into it); for general files, the entries with `row ≥ col`.
    pub fn lower_triangle(&self) -> Result<SparseMatrix, IoError> {
        let t: Vec<_> = self
            .entries
            .iter()
            .filter_map(|&(i, j, v)| match self.symmetry {
                MtxSymmetry::Symmetric => Some((i.max(j), i.min(j), v)),
                MtxSymmetry::General => (i >= j).then_some((i, j, v)),
            })
            .collect();
        sparse_from_triplets(self.nrows, self.ncols, &t)
            .map_err(|e| IoError::Unwritable(e.to_string()))
    }

    /// The full matrix (symmetric files mirrored).
    pub fn full(&self) -> Result<SparseMatrix, IoError> {
        let mut t = self.entries.clone();
        if self.symmetry == MtxSymmetry::Symmetric {
            t.extend(
                self.entries
                    .iter()
                    .filter(|e| e.0 != e.1)
                    .map(|&(i, j, v)| (j, i, v)),
            );
        }
        sparse_from_triplets(self.nrows, self.ncols, &t)
            .map_err(|e| IoError::Unwritable(e.to_string()))
    }
}

/// Reads a Matrix Market coordinate file.
pub fn read_matrix_market<R: BufRead>(reader: R) -> Result<MatrixMarket, IoError> {
    let mut lines = Lines::new(reader);
    let banner = lines
        .next_line()?
        .ok_or_else(|| IoError::syntax(1, "empty file"))?
        .1
        .to_ascii_lowercase();
    let b: Vec<&str> = banner.split_whitespace().collect();
    if b.len() < 5 || b[0] != "%%matrixmarket" || b[1] != "matrix" || b[2] != "coordinate" {
        return Err(IoError::syntax(
            1,
            "expected `%%MatrixMarket matrix coordinate …`",
        ));
    }
    let pattern = match b[3] {
        "real" | "integer" | "double" => false,
        "pattern" => true,
        other => {
            return Err(IoError::UnsupportedFormat(format!(
                "Matrix Market field `{}`",
                truncate(other)
            )))
        }
    };
    let symmetry = match b[4] {
        "general" => MtxSymmetry::General,
        "symmetric" => MtxSymmetry::Symmetric,
        other => {
            return Err(IoError::UnsupportedFormat(format!(
                "Matrix Market symmetry `{}`",
                truncate(other)
            )))
        }
    };
    let (ln, size_line) = loop {
        let end = lines.line + 1;
        let (ln, l) = lines
            .next_line()?
            .ok_or_else(|| IoError::syntax(end, "missing size line"))?;
        if !l.trim().is_empty() && !l.trim_start().starts_with('%') {
            break (ln, l.to_owned());
        }
    };
    let mut t = size_line.split_whitespace();
    let nrows = check_count("rows", parse_usize(t.next(), ln, "row count")? as u64)?;
    let ncols = check_count("columns", parse_usize(t.next(), ln, "column count")? as u64)?;
    let nnz = check_count("entries", parse_usize(t.next(), ln, "entry count")? as u64)?;
    for (what, value) in [("rows", nrows), ("columns", ncols)] {
        if value as u64 > limits::MAX_MATRIX_DIM {
            return Err(IoError::Limit {
                what,
                value: value as u64,
                limit: limits::MAX_MATRIX_DIM,
            });
        }
    }
    let mut entries = Vec::with_capacity(nnz.min(limits::RESERVE_CAP));
    for _ in 0..nnz {
        let (ln, l) = lines.require_content_line("the entries")?;
        let mut t = l.split_whitespace();
        let i = parse_usize(t.next(), ln, "row index")?;
        let j = parse_usize(t.next(), ln, "column index")?;
        if i == 0 || j == 0 || i > nrows || j > ncols {
            return Err(IoError::syntax(
                ln,
                format!("entry ({i}, {j}) out of range"),
            ));
        }
        let v = if pattern {
            1.0
        } else {
            super::lines::parse_coord(t.next(), ln)?
        };
        entries.push((i - 1, j - 1, v));
    }
    Ok(MatrixMarket {
        symmetry,
        nrows,
        ncols,
        entries,
    })
}

/// Writes the lower triangle of a symmetric matrix as `coordinate real symmetric`.
pub fn write_matrix_market_lower<W: Write>(mut w: W, a: &SparseMatrix) -> Result<(), IoError> {
    let t: Vec<_> = sparse_triplets(a.as_ref())
        .into_iter()
        .filter(|e| e.0 >= e.1)
        .collect();
    writeln!(
        w,
        "%%MatrixMarket matrix coordinate real symmetric\n% written by fires-recon"
    )?;
    writeln!(w, "{} {} {}", a.nrows(), a.ncols(), t.len())?;
    for (i, j, v) in t {
        writeln!(w, "{} {} {:?}", i + 1, j + 1, v)?;
    }
    Ok(())
}
