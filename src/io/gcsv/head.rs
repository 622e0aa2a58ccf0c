//! The head of a `.gcsv` file: the magic line, the `key,value` header lines
//! and the column line, read and checked one step at a time. Errors name the
//! file, the line and the header key or column.

use super::{
    is_magic, next_line, parse_err, parse_orientation, utf8, Columns, GcsvHeader, ReadoutDirection,
    DEFAULT_ORIENTATION, MAGIC,
};
use crate::error::{quote, Result};
use crate::io::input::MAX_HEADER_BYTES;
use std::io::BufRead;
use std::path::Path;

/// A `key,value` header line: key, value (both trimmed) and line number.
struct Field {
    key: String,
    value: String,
    line: u64,
}

/// The header lines and the column line, as read.
struct RawHead {
    fields: Vec<Field>,
    columns: Vec<String>,
    /// The column line's number.
    line: u64,
}

/// Reads the magic line, the header and the column line. Returns the header,
/// the columns and the number of lines read (the column line's number).
pub(super) fn read_head<R: BufRead>(
    src: &mut R,
    path: &Path,
) -> Result<(GcsvHeader, Columns, u64)> {
    let first_len = read_magic(src, path)?;
    let raw = read_lines(src, path, first_len)?;
    let keys = Keys {
        fields: &raw.fields,
        path,
        column_line: raw.line,
    };
    let tscale = keys.scale("tscale", "seconds per unit of t")?;
    let gscale = keys.scale("gscale", "rad/s per unit of gx, gy, gz")?;
    let orientation = keys.orientation()?;
    let readout_s = keys.readout_time()?;
    let readout_direction = keys.readout_direction()?;
    let g = gyro_columns(&raw.columns, path, raw.line)?;
    let header = GcsvHeader {
        readout_s,
        readout_direction,
        orientation,
        tscale,
        gscale,
        fields: raw.fields.into_iter().map(|f| (f.key, f.value)).collect(),
    };
    let cols = Columns {
        names: raw.columns,
        t: 0,
        g,
    };
    Ok((header, cols, raw.line))
}

/// Reads line 1, which must be a [`MAGIC`]; returns its length in bytes.
fn read_magic<R: BufRead>(src: &mut R, path: &Path) -> Result<usize> {
    let mut buf = Vec::new();
    if !next_line(src, &mut buf, path, 1)? || !is_magic(&buf) {
        return Err(parse_err(
            path,
            1,
            "-",
            format!(
                "not a Gyroflow IMU log: the first line must be '{}' or '{}'",
                MAGIC[0], MAGIC[1]
            ),
        ));
    }
    Ok(buf.len())
}

/// Reads the lines after the magic line up to the column line (the first
/// line starting with `t` or `time`): `key,value` lines, with blank and `#`
/// lines skipped, at most [`MAX_HEADER_BYTES`] in all.
fn read_lines<R: BufRead>(src: &mut R, path: &Path, first_len: usize) -> Result<RawHead> {
    let mut buf = Vec::new();
    let mut line = 1u64;
    let mut fields = Vec::new();
    let mut head_bytes = first_len;
    loop {
        if head_bytes > MAX_HEADER_BYTES {
            return Err(parse_err(
                path,
                line,
                "-",
                format!("the header (before the column line) is longer than {MAX_HEADER_BYTES} bytes, the most read"),
            ));
        }
        if !next_line(src, &mut buf, path, line + 1)? {
            return Err(parse_err(
                path,
                line,
                "-",
                "the file ends before the column line (t,gx,gy,gz,...)".into(),
            ));
        }
        line += 1;
        head_bytes += buf.len() + 1;
        let text = utf8(&buf, path, line)?.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let names: Vec<String> = text.split(',').map(|s| s.trim().to_string()).collect();
        if names[0] == "t" || names[0] == "time" {
            return Ok(RawHead {
                fields,
                columns: names,
                line,
            });
        }
        fields.push(key_value(text, path, line)?);
    }
}

/// A `key,value` header line (the value is everything after the first comma).
fn key_value(text: &str, path: &Path, line: u64) -> Result<Field> {
    match text.split_once(',') {
        Some((k, v)) => Ok(Field {
            key: k.trim().to_string(),
            value: v.trim().to_string(),
            line,
        }),
        None => Err(parse_err(
            path,
            line,
            "-",
            format!(
                "{}: expected a 'key,value' header line or the column line (t,gx,gy,gz,...)",
                quote(text)
            ),
        )),
    }
}

/// The header's keys, looked up by name.
struct Keys<'a> {
    fields: &'a [Field],
    path: &'a Path,
    /// Where a missing key is reported.
    column_line: u64,
}

impl Keys<'_> {
    /// The value and line of `key`; a key that is read must appear at most once.
    fn find(&self, key: &str) -> Result<Option<(&str, u64)>> {
        let mut hits = self.fields.iter().filter(|f| f.key == key);
        let first = hits.next();
        if let (Some(a), Some(b)) = (first, hits.next()) {
            return Err(parse_err(
                self.path,
                b.line,
                key,
                format!(
                    "header key '{key}' appears twice (lines {} and {})",
                    a.line, b.line
                ),
            ));
        }
        Ok(first.map(|f| (f.value.as_str(), f.line)))
    }

    /// A required scale (`tscale`, `gscale`): a finite number > 0.
    fn scale(&self, key: &str, what: &str) -> Result<f64> {
        let (v, l) = self.find(key)?.ok_or_else(|| {
            parse_err(
                self.path,
                self.column_line,
                key,
                format!("missing header key '{key}' ({what}); it must come before the column line"),
            )
        })?;
        match v.parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
            _ => Err(parse_err(
                self.path,
                l,
                key,
                format!("{} is not a finite number > 0", quote(v)),
            )),
        }
    }

    /// `orientation` (validated), or [`DEFAULT_ORIENTATION`].
    fn orientation(&self) -> Result<String> {
        match self.find("orientation")? {
            Some((v, l)) => {
                parse_orientation(v).map_err(|m| parse_err(self.path, l, "orientation", m))?;
                Ok(v.to_string())
            }
            None => Ok(DEFAULT_ORIENTATION.to_string()),
        }
    }

    /// `frame_readout_time` (ms, >= 0) in seconds; empty or absent: None.
    fn readout_time(&self) -> Result<Option<f64>> {
        match self.find("frame_readout_time")? {
            Some(("", _)) | None => Ok(None),
            Some((v, l)) => match v.parse::<f64>() {
                Ok(ms) if ms.is_finite() && ms >= 0.0 => Ok(Some(ms / 1000.0)),
                _ => Err(parse_err(
                    self.path,
                    l,
                    "frame_readout_time",
                    format!("{} is not a finite number >= 0 (ms)", quote(v)),
                )),
            },
        }
    }

    /// `frame_readout_direction` (Gyroflow's codes); empty or absent: None.
    fn readout_direction(&self) -> Result<Option<ReadoutDirection>> {
        match self.find("frame_readout_direction")? {
            Some(("", _)) | None => Ok(None),
            Some((v, l)) => ReadoutDirection::from_gyroflow(v).map(Some).ok_or_else(|| {
                parse_err(
                    self.path,
                    l,
                    "frame_readout_direction",
                    format!(
                        "{}: expected 0 (top to bottom), 1 (bottom to top), 2 (left to right) or 3 (right to left)",
                        quote(v)
                    ),
                )
            }),
        }
    }
}

/// The positions of `gx, gy, gz` in the column line (`t`, `gx`, `gy`, `gz`
/// at most once each).
fn gyro_columns(columns: &[String], path: &Path, line: u64) -> Result<[usize; 3]> {
    for n in ["t", "gx", "gy", "gz"] {
        if columns.iter().filter(|c| *c == n).count() > 1 {
            return Err(parse_err(
                path,
                line,
                n,
                format!("column '{n}' appears more than once in the column line"),
            ));
        }
    }
    let need = |n: &str| {
        columns.iter().position(|c| c == n).ok_or_else(|| {
            parse_err(
                path,
                line,
                n,
                format!(
                    "missing column '{n}' (the column line is: {})",
                    columns.join(",")
                ),
            )
        })
    };
    Ok([need("gx")?, need("gy")?, need("gz")?])
}
