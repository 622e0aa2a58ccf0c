//! The samples of a `.gcsv` file, one row at a time (constant memory).

use super::head::read_head;
use super::{
    camera_axes, next_line, parse_err, parse_orientation, utf8, Axes, Columns, GcsvHeader,
};
use crate::error::{quote, Error, Result};
use crate::io::input::{check_increasing, open_stream};
use glam::{DMat3, DVec3};
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

/// One sample row of a `.gcsv` file, scaled and oriented.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GcsvRow {
    /// The row's line number in the file (1-based).
    pub line: u64,
    /// `(t - t0) * tscale`, s, where `t0` is the first row's `t` (time from
    /// the first sample, as Gyroflow counts it).
    pub t: f64,
    /// `(gx, gy, gz) * gscale` in mmbm's camera frame ([`super::camera_matrix`],
    /// then [`GcsvReader::with_rotation`]'s rotation if any), rad/s.
    pub omega: DVec3,
}

/// Reads the rows of a `.gcsv` file after its header: each row's fields by
/// position (`t`, then the gyro's x, y, z; further fields, accelerometer and
/// magnetometer, are not read), scaled (`tscale`, `gscale`), its time counted
/// from the first row's, and turned into the camera frame (exact: a sign and a
/// pick per axis, unless a rotation is given). Blank and `#` lines are
/// skipped. A bad row (fewer than 4 fields, non-UTF-8 text, a non-number, a
/// non-finite value or product) is an error naming the file, its line and the
/// `.gcsv` column. The order of the times is the caller's to check
/// ([`crate::io::gyro::GyroReader`]).
pub struct GcsvReader {
    path: PathBuf,
    src: BufReader<File>,
    header: GcsvHeader,
    cols: Columns,
    axes: Axes,
    /// Camera-frame rotation applied after `axes` (Gyroflow's IMU rotation).
    rotation: Option<DMat3>,
    /// The first row's `t`, as written (None before the first row).
    t0: Option<f64>,
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
            rotation: None,
            t0: None,
            line,
            buf: Vec::new(),
        })
    }

    /// The reader with Gyroflow's IMU rotation `[pitch, roll, yaw]` (degrees,
    /// in Gyroflow's IMU frame, after the orientation:
    /// [`super::gyroflow_rotation`]) applied to every row.
    pub fn with_rotation(mut self, pitch_roll_yaw_deg: [f64; 3]) -> Result<Self> {
        let r = super::gyroflow_rotation(pitch_roll_yaw_deg)?;
        let g = super::GYROFLOW_TO_CAMERA;
        self.rotation = Some(g * r * g.transpose());
        Ok(self)
    }

    /// The first row's time `t0 * tscale`, s, which the rows' times are
    /// counted from (None before the first row is read).
    pub fn first_time_s(&self) -> Option<f64> {
        self.t0.map(|t0| t0 * self.header.tscale)
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

    /// The name of column `i` in errors: the column line's, else its position.
    fn column_name(&self, i: usize) -> String {
        match self.cols.names.get(i) {
            Some(n) if !n.is_empty() => n.clone(),
            _ => format!("column {}", i + 1),
        }
    }

    /// The line in `buf` as a row (None for a blank or `#` line).
    fn row(&mut self) -> Result<Option<GcsvRow>> {
        let (path, line) = (self.path.as_path(), self.line);
        let text = utf8(&self.buf, path, line)?.trim();
        if text.is_empty() || text.starts_with('#') {
            return Ok(None);
        }
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        if fields.len() < 4 {
            return Err(parse_err(
                path,
                line,
                &format!("field count (expected at least 4, found {})", fields.len()),
                "a row has t and the gyro's x, y, z first (t,gx,gy,gz,...)".into(),
            ));
        }
        let t_name = self.column_name(self.cols.t);
        let t_raw = scaled(fields[self.cols.t], 1.0, path, line, &t_name)?;
        let t0 = *self.t0.get_or_insert(t_raw);
        let num = |i: usize, scale: f64| scaled(fields[i], scale, path, line, &self.column_name(i));
        let t = (t_raw - t0) * self.header.tscale;
        if !t.is_finite() {
            return Err(parse_err(
                path,
                line,
                &t_name,
                format!(
                    "{} minus the first row's {t0}, times tscale {}, overflows",
                    quote(fields[self.cols.t]),
                    self.header.tscale
                ),
            ));
        }
        let g = [
            num(self.cols.g[0], self.header.gscale)?,
            num(self.cols.g[1], self.header.gscale)?,
            num(self.cols.g[2], self.header.gscale)?,
        ];
        let mut omega = DVec3::from_array(self.axes.map(|(a, s)| s * g[a]));
        if let Some(r) = self.rotation {
            omega = r * omega;
        }
        Ok(Some(GcsvRow { line, t, omega }))
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

/// The whole file as gyro CSV text, one line per line of the file: `#` for
/// each line before the column line, `t,wx,wy,wz`, then one row per sample
/// (s, rad/s, camera frame, `{:?}` decimals: shortest round trip), with `#`
/// for blank and `#` lines among the samples. Times must strictly increase.
/// (The readers take the samples from [`GcsvReader`]; this text is for
/// other tools.)
pub fn to_csv(path: &Path) -> Result<String> {
    let mut r = GcsvReader::open(path)?;
    let comments = |n: u64| "#\n".repeat(n as usize);
    let mut s = comments(r.lines_read().saturating_sub(1));
    s += "t,wx,wy,wz\n";
    let mut written = r.lines_read();
    let mut prev = None;
    while let Some(row) = r.next_row()? {
        check_increasing(path, row.line, r.time_column(), row.t, prev)?;
        prev = Some((row.t, row.line));
        s += &comments(row.line - written - 1);
        let w = row.omega;
        s += &format!("{:?},{:?},{:?},{:?}\n", row.t, w.x, w.y, w.z);
        written = row.line;
    }
    s += &comments(r.lines_read() - written);
    Ok(s)
}
