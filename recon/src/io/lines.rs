//! Bounded line reading for the text formats.

use std::io::{BufRead, Read};

use super::{limits, IoError};

/// Reads lines with a length limit, counting line numbers (1-based).
pub(crate) struct Lines<R> {
    reader: R,
    buf: Vec<u8>,
    /// Number of the line last returned.
    pub(crate) line: usize,
    /// Bytes consumed so far.
    pub(crate) bytes: u64,
}

impl<R: BufRead> Lines<R> {
    pub(crate) fn new(reader: R) -> Self {
        Self {
            reader,
            buf: Vec::with_capacity(256),
            line: 0,
            bytes: 0,
        }
    }

    /// The next line (1-based number, text without terminator), or `None` at the end.
    pub(crate) fn next_line(&mut self) -> Result<Option<(usize, &str)>, IoError> {
        self.buf.clear();
        let mut limited = self.reader.by_ref().take(limits::MAX_LINE as u64 + 1);
        let n = limited.read_until(b'\n', &mut self.buf)?;
        if n == 0 {
            return Ok(None);
        }
        self.line += 1;
        self.bytes += n as u64;
        if self.buf.len() > limits::MAX_LINE {
            return Err(IoError::syntax(self.line, "line too long"));
        }
        while matches!(self.buf.last(), Some(b'\n' | b'\r')) {
            self.buf.pop();
        }
        match std::str::from_utf8(&self.buf) {
            Ok(s) => Ok(Some((self.line, s))),
            Err(_) => Err(IoError::syntax(self.line, "not UTF-8 text")),
        }
    }

    /// The next line that is neither blank nor a `#` comment, trimmed.
    pub(crate) fn next_content_line(&mut self) -> Result<Option<(usize, &str)>, IoError> {
        loop {
            let (s, e) = match self.next_line()? {
                None => return Ok(None),
                Some((_, l)) => {
                    let t = l.trim();
                    if t.is_empty() || t.starts_with('#') {
                        continue;
                    }
                    (l.len() - l.trim_start().len(), l.trim_end().len())
                }
            };
            let text = std::str::from_utf8(&self.buf[s..e])
                .map_err(|_| IoError::syntax(self.line, "not UTF-8 text"))?;
            return Ok(Some((self.line, text)));
        }
    }

    /// Like [`Self::next_content_line`], failing at the end of input with "file ends inside `ctx`".
    pub(crate) fn require_content_line(&mut self, ctx: &str) -> Result<(usize, &str), IoError> {
        let end = self.line + 1;
        self.next_content_line()?
            .ok_or_else(|| IoError::syntax(end, format!("file ends inside {ctx}")))
    }

    /// Consumes the reader back (for formats that switch to binary after a text header).
    pub(crate) fn into_inner(self) -> R {
        self.reader
    }
}

/// Parses a finite `f64`.
pub(crate) fn parse_coord(tok: Option<&str>, line: usize) -> Result<f64, IoError> {
    let tok = tok.ok_or_else(|| IoError::syntax(line, "missing coordinate"))?;
    let v: f64 = tok
        .parse()
        .map_err(|_| IoError::syntax(line, format!("bad number `{}`", truncate(tok))))?;
    if !v.is_finite() {
        return Err(IoError::syntax(line, "non-finite coordinate"));
    }
    Ok(v)
}

/// Parses a count or index.
pub(crate) fn parse_usize(tok: Option<&str>, line: usize, what: &str) -> Result<usize, IoError> {
    let tok = tok.ok_or_else(|| IoError::syntax(line, format!("missing {what}")))?;
    tok.parse()
        .map_err(|_| IoError::syntax(line, format!("bad {what} `{}`", truncate(tok))))
}

/// Checks a header count against [`limits::MAX_ELEMENTS`].
pub(crate) fn check_count(what: &'static str, value: u64) -> Result<usize, IoError> {
    if value > limits::MAX_ELEMENTS {
        return Err(IoError::Limit {
            what,
            value,
            limit: limits::MAX_ELEMENTS,
        });
    }
    Ok(value as usize)
}

/// At most 40 characters of a token, for error messages.
pub(crate) fn truncate(s: &str) -> String {
    s.chars().take(40).collect()
}
