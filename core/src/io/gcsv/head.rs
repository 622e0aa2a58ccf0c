//! The head of a `.gcsv` file: the magic line, the `key,value` header lines
//! and the column line, read and checked one step at a time. Errors name the
//! file, the line and the header key or column.

use super::{
    is_magic, next_line, parse_err, parse_orientation, utf8, Columns, GcsvHeader, ReadoutDirection,
    DEFAULT_GSCALE, DEFAULT_ORIENTATION, DEFAULT_TSCALE, MAGIC,
};
use crate::error::{quote, Result};
use crate::io::input::{open_stream, MAX_HEADER_BYTES};
use std::io::{BufRead, BufReader};
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
    };
    let tscale = keys.scale("tscale", DEFAULT_TSCALE)?;
    let gscale = keys.scale("gscale", DEFAULT_GSCALE)?;
    let orientation = keys.orientation()?;
    let readout = keys.readout_time()?;
    let mut readout_direction = keys.readout_direction()?;
    // A negative frame_readout_time reverses the direction (Gyroflow's
    // sign convention: -15 ms top to bottom is 15 ms bottom to top).
    let readout_s = readout.map(|ms| {
        if ms < 0.0 {
            readout_direction = Some(readout_direction.unwrap_or_default().reversed());
        }
        ms.abs() / 1000.0
    });
    check_columns(&raw.columns, path, raw.line)?;
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
        g: [1, 2, 3],
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
/// line whose first field is `t` or `time`): `key,value` lines, with blank
/// and `#` lines and lines without a comma (`version:1.3`, as telemetry-parser
/// skips them) skipped, at most [`MAX_HEADER_BYTES`] in all.
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
        if text.is_empty() || text.starts_with('#') || !text.contains(',') {
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
            format!("{}: expected a 'key,value' header line", quote(text)),
        )),
    }
}

/// The header's keys, looked up by name.
struct Keys<'a> {
    fields: &'a [Field],
    path: &'a Path,
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

    /// A scale (`tscale`, `gscale`): a finite number > 0, or `default` when
    /// the key is absent (telemetry-parser's defaults).
    fn scale(&self, key: &str, default: f64) -> Result<f64> {
        let Some((v, l)) = self.find(key)? else {
            return Ok(default);
        };
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

    /// `frame_readout_time` as written, ms (negative: the direction
    /// reversed); empty or absent: None.
    fn readout_time(&self) -> Result<Option<f64>> {
        match self.find("frame_readout_time")? {
            Some(("", _)) | None => Ok(None),
            Some((v, l)) => match v.parse::<f64>() {
                Ok(ms) if ms.is_finite() => Ok(Some(ms)),
                _ => Err(parse_err(
                    self.path,
                    l,
                    "frame_readout_time",
                    format!("{} is not a finite number (ms)", quote(v)),
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

/// The column line names the columns, but the reader takes them by position
/// (t, then the gyro's x, y, z), as telemetry-parser does: only `t` or `time`
/// first is required (the column line is found by it), and names may repeat.
/// A column line with fewer than 4 fields is an error.
fn check_columns(columns: &[String], path: &Path, line: u64) -> Result<()> {
    if columns.len() < 4 {
        return Err(parse_err(
            path,
            line,
            "-",
            format!(
                "the column line has {} fields ({}): expected at least 4, t and the gyro's x, y, z by position (t,gx,gy,gz,...)",
                columns.len(),
                columns.join(",")
            ),
        ));
    }
    Ok(())
}

/// Reads the header of the `.gcsv` file at `path` (up to its column line).
pub fn read_header(path: &Path) -> Result<GcsvHeader> {
    let mut src = BufReader::new(open_stream(path)?);
    read_head(&mut src, path).map(|(h, _, _)| h)
}
