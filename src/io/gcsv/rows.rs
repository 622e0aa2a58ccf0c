//! The samples of a `.gcsv` file, one row at a time (constant memory).

use super::{
    camera_axes, next_line, parse_err, parse_orientation, read_head, utf8, Axes, Columns,
    GcsvHeader,
};
use crate::error::{quote, Error, Result};
use crate::io::input::open_stream;
use glam::DVec3;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

/// One sample row of a `.gcsv` file, scaled and oriented.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GcsvRow {
    /// The row's line number in the file (1-based).
    pub line: u64,
    /// `t * tscale`, s.
    pub t: f64,
    /// `(gx, gy, gz) * gscale` in mmbm's camera frame ([`super::camera_matrix`]), rad/s.
    pub omega: DVec3,
}

/// Reads the rows of a `.gcsv` file after its header: each row scaled
/// (`tscale`, `gscale`) and turned into the camera frame (exact: a sign and
/// a pick per axis). Blank and `#` lines are skipped. A bad row (field
/// count, non-UTF-8 text, a non-number, a non-finite value or product) is an
/// error naming the file, its line and the `.gcsv` column. The order of the
/// times is the caller's to check ([`crate::io::gyro::GyroReader`]).
pub struct GcsvReader {
    path: PathBuf,
    src: BufReader<File>,
    header: GcsvHeader,
    cols: Columns,
    axes: Axes,
    line: u64,
    buf: Vec<u8>,
}

impl GcsvReader {
    /// Opens `path` and reads its header (errors name the file, line and key).
    pub fn open(path: &Path) -> Result<Self> {
        let mut src = BufReader::with_capacity(1 << 16, open_stream(path)?);
        let (header, cols, line) = read_head(&mut src, path)?;
        let axes = camera_axes(
            &parse_orientation(&header.orientation)
                .map_err(|m| Error::invalid("orientation", m))?,
        );
        Ok(GcsvReader {
            path: path.into(),
            src,
            header,
            cols,
            axes,
            line,
            buf: Vec::new(),
        })
    }

    /// The file's header.
    pub fn header(&self) -> &GcsvHeader {
        &self.header
    }

    /// The name of the time column (`t` or `time`).
    pub fn time_column(&self) -> &str {
        &self.cols.names[self.cols.t]
    }

    /// Lines read so far (the column line's number before the first row).
    pub fn lines_read(&self) -> u64 {
        self.line
    }

    /// The next sample row (None at the end of the file).
    pub fn next_row(&mut self) -> Result<Option<GcsvRow>> {
        loop {
            if !next_line(&mut self.src, &mut self.buf, &self.path, self.line + 1)? {
                return Ok(None);
            }
            self.line += 1;
            if let Some(row) = self.row()? {
                return Ok(Some(row));
            }
        }
    }

    /// The line in `buf` as a row (None for a blank or `#` line).
    fn row(&self) -> Result<Option<GcsvRow>> {
        let (path, line) = (self.path.as_path(), self.line);
        let text = utf8(&self.buf, path, line)?.trim();
        if text.is_empty() || text.starts_with('#') {
            return Ok(None);
        }
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        let names = &self.cols.names;
        if fields.len() != names.len() {
            return Err(parse_err(
                path,
                line,
                &format!(
                    "field count (expected {}, found {})",
                    names.len(),
                    fields.len()
                ),
                format!(
                    "a row must have one field per column of the column line ({})",
                    names.join(",")
                ),
            ));
        }
        let num = |i: usize, scale: f64| scaled(fields[i], scale, path, line, &names[i]);
        let t = num(self.cols.t, self.header.tscale)?;
        let g = [
            num(self.cols.g[0], self.header.gscale)?,
            num(self.cols.g[1], self.header.gscale)?,
            num(self.cols.g[2], self.header.gscale)?,
        ];
        let w = self.axes.map(|(a, s)| s * g[a]);
        Ok(Some(GcsvRow {
            line,
            t,
            omega: DVec3::from_array(w),
        }))
    }
}

/// Field `s` (column `column` of `line`) times `scale`: a finite number
/// whose product is finite.
fn scaled(s: &str, scale: f64, path: &Path, line: u64, column: &str) -> Result<f64> {
    let x: f64 = s
        .parse()
        .map_err(|_| parse_err(path, line, column, format!("{} is not a number", quote(s))))?;
    if !x.is_finite() {
        return Err(parse_err(
            path,
            line,
            column,
            format!("{} is not finite", quote(s)),
        ));
    }
    let y = x * scale;
    if !y.is_finite() {
        return Err(parse_err(
            path,
            line,
            column,
            format!("{} times the scale {scale} overflows", quote(s)),
        ));
    }
    Ok(y)
}
