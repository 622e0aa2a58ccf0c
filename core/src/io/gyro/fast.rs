//! The fast path of a plain gyro CSV in a regular file
//! ([`super::plain::CsvSource`]): the file is read in blocks of whole lines
//! and each block is parsed in pieces by a tight one-pass loop over plain
//! numeric rows. Only the common, clean form is taken: one record per
//! line, `\n` or `\r\n` line ends, no quote, no comment or blank line, the
//! header's column count, every column read a finite number that
//! [`crate::io::decimal`] reads as [`crate::io::decimal::parse_f64`] does
//! (the exact reader's own first try, so the values are the same bits).
//! Anything else in a block is [`Unusual`]: the caller then reads on with
//! the exact `csv` reader from where the fast path stopped (its records
//! skipped), so every error and line number is the exact reader's.
//!
//! The pieces are parsed in turn on the reader's thread: on rayon's pool
//! (the pieces of a block in parallel) it took less CPU time than the `csv`
//! reader but more wall time on a loaded 2-core machine, where the pool is
//! busy with the metric and the reader waits for it.
//!
//! Line numbers are the exact reader's: the `csv` crate counts a record's
//! line before it reads the `\n` of a `\r\n` ending the line before, so a
//! record after a `\r\n` line is numbered one lower than its line.

use super::raw::Raw;
use crate::io::decimal::{parse_f64, parse_prefix};
use crate::io::input::MAX_LINE_BYTES;
use glam::DVec3;
use std::fs::File;
use std::os::unix::fs::FileExt;

/// Bytes read per block. A line still open after a block's worth of bytes
/// is [`Unusual`], so no line the fast path takes is as long as two blocks,
/// let alone over the exact reader's line cap.
const BLOCK: usize = 1 << 19;
const _: () = assert!(2 * BLOCK <= MAX_LINE_BYTES);

/// Bytes per piece of a block (about 700 rows of a 4-column log).
const PIECE: usize = 32 << 10;

/// Where a column's value goes: `t`, `wx, wy, wz`, `vx, vy, vz`, `depth`.
const T: u8 = 0;
const W: u8 = 1;
const V: u8 = 4;
const DEPTH: u8 = 7;
/// A column that is not read.
const SKIP: u8 = u8::MAX;

/// The fast path met something the exact reader must judge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Unusual;

/// The columns of the header: the slot of each (or [`SKIP`]).
#[derive(Debug, Clone)]
pub(super) struct Layout {
    slots: Vec<u8>,
    velocity: bool,
    depth: bool,
}

impl Layout {
    /// `count` columns with `t`, `w`, optional `v` and `depth` at these positions.
    pub fn new(
        count: usize,
        t: usize,
        w: [usize; 3],
        v: Option<[usize; 3]>,
        depth: Option<usize>,
    ) -> Self {
        let mut slots = vec![SKIP; count];
        slots[t] = T;
        for (k, &i) in w.iter().enumerate() {
            slots[i] = W + k as u8;
        }
        for (k, &i) in v.iter().flatten().enumerate() {
            slots[i] = V + k as u8;
        }
        if let Some(i) = depth {
            slots[i] = DEPTH;
        }
        Layout {
            slots,
            velocity: v.is_some(),
            depth: depth.is_some(),
        }
    }
}

/// The records of a clean file, block by block (see the module docs).
pub(super) struct FastRows {
    file: File,
    layout: Layout,
    /// File offset of the next byte to read.
    offset: u64,
    /// The start of a line carried over from the last block, then a block.
    buf: Vec<u8>,
    eof: bool,
    header_done: bool,
    /// The line number (1-based, counting `\n`) of the first line in `buf`.
    next_line: u64,
    /// The line before `buf` ended with `\r\n`.
    prev_crlf: bool,
    /// The parsed block, piece by piece, and the next record in it.
    pieces: Vec<Vec<Raw>>,
    at: (usize, usize),
    delivered: u64,
    block: usize,
    piece: usize,
}

impl FastRows {
    /// The records of `file` (read by offset: the file position, which the
    /// exact reader uses, is left alone), from its first line on.
    pub fn new(file: File, layout: Layout) -> Self {
        Self::with_sizes(file, layout, BLOCK, PIECE)
    }

    /// [`FastRows::new`] with other block and piece sizes (tests).
    pub fn with_sizes(file: File, layout: Layout, block: usize, piece: usize) -> Self {
        FastRows {
            file,
            layout,
            offset: 0,
            buf: Vec::new(),
            eof: false,
            header_done: false,
            next_line: 1,
            prev_crlf: false,
            pieces: Vec::new(),
            at: (0, 0),
            delivered: 0,
            block: block.clamp(1, BLOCK),
            piece: piece.max(1),
        }
    }

    /// Records handed out so far (all of the lines before the unusual block).
    pub fn delivered(&self) -> u64 {
        self.delivered
    }

    /// The next record, `None` at the end of the file.
    pub fn next_raw(&mut self) -> Result<Option<Raw>, Unusual> {
        loop {
            let (p, i) = self.at;
            if let Some(piece) = self.pieces.get(p) {
                match piece.get(i) {
                    Some(r) => {
                        self.at.1 += 1;
                        self.delivered += 1;
                        return Ok(Some(*r));
                    }
                    None => self.at = (p + 1, 0),
                }
                continue;
            }
            if !self.fill()? {
                // A file without records is the exact reader's to report.
                return if self.delivered == 0 {
                    Err(Unusual)
                } else {
                    Ok(None)
                };
            }
        }
    }

    /// Appends up to a block of the file to `buf`.
    fn read_more(&mut self) -> Result<(), Unusual> {
        let mut n = self.buf.len();
        self.buf.resize(n + self.block, 0);
        while n < self.buf.len() && !self.eof {
            match self.file.read_at(&mut self.buf[n..], self.offset) {
                Ok(0) => self.eof = true,
                Ok(k) => {
                    n += k;
                    self.offset += k as u64;
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(_) => return Err(Unusual),
            }
        }
        self.buf.truncate(n);
        Ok(())
    }

    /// Takes the header line off `buf` once it is there: it must be the
    /// file's first line, as the exact reader read it (not a comment, a
    /// blank line or quoted).
    fn header(&mut self) -> Result<(), Unusual> {
        let Some(end) = memchr::memchr(b'\n', &self.buf) else {
            return Ok(());
        };
        let (line, crlf) = strip_cr(&self.buf[..end]);
        if line.is_empty() || line[0] == b'#' || memchr::memchr2(b'"', b'\r', line).is_some() {
            return Err(Unusual);
        }
        self.header_done = true;
        self.prev_crlf = crlf;
        self.next_line = 2;
        self.buf.drain(..=end);
        Ok(())
    }

    /// Reads and parses the next block of whole lines; false at the end of
    /// the file.
    fn fill(&mut self) -> Result<bool, Unusual> {
        self.pieces.clear();
        self.at = (0, 0);
        let end = loop {
            if self.buf.len() >= BLOCK {
                // A line longer than a block.
                return Err(Unusual);
            }
            self.read_more()?;
            if !self.header_done {
                self.header()?;
            }
            if self.eof {
                if !self.header_done {
                    return Err(Unusual);
                }
                break self.buf.len();
            }
            if let Some(k) = memchr::memrchr(b'\n', &self.buf).filter(|_| self.header_done) {
                break k + 1;
            }
        };
        if end == 0 {
            return Ok(false);
        }
        let data = &self.buf[..end];
        let mut bounds = Vec::new();
        let mut s = 0;
        while s < data.len() {
            let e = match data.get(s + self.piece..) {
                Some(rest) => {
                    memchr::memchr(b'\n', rest).map_or(data.len(), |k| s + self.piece + k + 1)
                }
                None => data.len(),
            };
            let crlf = if s == 0 {
                self.prev_crlf
            } else {
                s >= 2 && data[s - 2] == b'\r'
            };
            bounds.push((s, e, crlf));
            s = e;
        }
        let layout = &self.layout;
        self.pieces = bounds
            .iter()
            .map(|&(s, e, crlf)| parse_piece(&data[s..e], layout, crlf))
            .collect::<Result<_, _>>()?;
        // Local line numbers to the file's.
        let mut base = self.next_line;
        for piece in &mut self.pieces {
            for r in piece.iter_mut() {
                r.line += base - 1;
            }
            base += piece.len() as u64;
        }
        self.next_line = base;
        self.prev_crlf = data.ends_with(b"\r\n");
        self.buf.drain(..end);
        Ok(true)
    }
}

/// `line` without one `\r` at its end, and whether it had one.
fn strip_cr(line: &[u8]) -> (&[u8], bool) {
    match line.strip_suffix(b"\r") {
        Some(l) => (l, true),
        None => (line, false),
    }
}

/// The records of `data` (whole lines; the last may lack its `\n` at the
/// end of the file), `prev_crlf` if the line before ended with `\r\n`. Each
/// record's `line` is its line's number within `data` (1-based) as the exact
/// reader counts it: one less after a `\r\n` line.
pub(super) fn parse_piece(
    data: &[u8],
    layout: &Layout,
    prev_crlf: bool,
) -> Result<Vec<Raw>, Unusual> {
    // A quote anywhere, or a `\r` that does not end a line.
    for i in memchr::memchr2_iter(b'"', b'\r', data) {
        if data[i] == b'"' || data.get(i + 1) != Some(&b'\n') {
            return Err(Unusual);
        }
    }
    let mut out = Vec::with_capacity(data.len() / 24 + 1);
    let mut prev_crlf = prev_crlf;
    let mut rest = data;
    let mut j = 1u64;
    while !rest.is_empty() {
        let (line, next) = match memchr::memchr(b'\n', rest) {
            Some(k) => (&rest[..k], &rest[k + 1..]),
            None => (rest, &rest[rest.len()..]),
        };
        rest = next;
        let (line, crlf) = strip_cr(line);
        if line.is_empty() || line[0] == b'#' {
            return Err(Unusual);
        }
        let mut r = record(line, layout)?;
        r.line = j - u64::from(prev_crlf);
        out.push(r);
        prev_crlf = crlf;
        j += 1;
    }
    Ok(out)
}

/// One line's record (its `line` left 0), or [`Unusual`]. A field read is
/// taken in one pass where it is a plain number up to its comma
/// ([`parse_prefix`]), else trimmed and read as the exact reader reads it.
#[inline]
fn record(line: &[u8], layout: &Layout) -> Result<Raw, Unusual> {
    let mut vals = [0.0f64; 8];
    let last = layout.slots.len() - 1;
    let mut p = 0;
    for (k, &slot) in layout.slots.iter().enumerate() {
        let rest = &line[p..];
        let plain = match slot {
            SKIP => None,
            _ => parse_prefix(rest).filter(|&(_, n)| rest.get(n).is_none_or(|&b| b == b',')),
        };
        let n = match plain {
            Some((x, n)) => {
                vals[slot as usize] = x;
                n
            }
            None => {
                let n = memchr::memchr(b',', rest).unwrap_or(rest.len());
                if slot != SKIP {
                    let x = parse_f64(rest[..n].trim_ascii()).ok_or(Unusual)?;
                    if !x.is_finite() {
                        return Err(Unusual);
                    }
                    vals[slot as usize] = x;
                }
                n
            }
        };
        // Each field but the last ends at a comma, the last at the line's end.
        if (n == rest.len()) != (k == last) {
            return Err(Unusual);
        }
        p += n + 1;
    }
    let v3 = |k: usize| DVec3::new(vals[k], vals[k + 1], vals[k + 2]);
    Ok(Raw {
        line: 0,
        t: vals[T as usize],
        w: v3(W as usize),
        v: layout.velocity.then(|| v3(V as usize)),
        depth: layout.depth.then_some(vals[DEPTH as usize]),
    })
}
