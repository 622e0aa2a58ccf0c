//! Gyroflow's IMU log, `.gcsv` (docs.gyroflow.xyz, "GCSV format"), read as
//! Gyroflow's telemetry-parser reads it: a magic line, header lines, a column
//! line, then raw samples.
//!
//! ```text
//! GYROFLOW IMU LOG            (or CAMERA IMU LOG)
//! version,1.3                 (a line without a comma, e.g. version:1.3, is skipped)
//! orientation,YxZ             (optional: default xzY)
//! frame_readout_time,15.23    (ms, optional; negative: the direction reversed)
//! frame_readout_direction,0   (optional: 0 top-to-bottom, 1 bottom-to-top, 2 left-to-right, 3 right-to-left)
//! tscale,0.001                (optional: default 0.001, ms)
//! gscale,0.00122173047        (optional: default 1.0, rad/s)
//! t,gx,gy,gz,ax,ay,az         (the column line: its first field t or time)
//! 0,39,86,183,-1137,-15689,-2986
//! ```
//!
//! - Columns by position, as telemetry-parser reads them: field 1 is the
//!   time, fields 2-4 the gyro's x, y, z, whatever the column line names them
//!   (only its first field, `t` or `time`, is looked for); further fields
//!   (accelerometer, magnetometer) are not read. A row needs at least 4 fields.
//! - Time: `(t - t0) * tscale`, s, where `t0` is the first row's `t`: time
//!   from the first sample, as Gyroflow counts it (the reader states `t0`;
//!   `--time-offset` is added after). Angular velocity: `g * gscale`, rad/s.
//!   A scale the header does not give is telemetry-parser's default,
//!   [`DEFAULT_TSCALE`] (ms) and [`DEFAULT_GSCALE`] (rad/s).
//! - Axes, as Gyroflow reads them (telemetry-parser, and `orient` in
//!   Gyroflow's IMU transforms): letter `i` of `orientation` names the file
//!   column that becomes Gyroflow's IMU axis `i`, uppercase with its sign,
//!   lowercase negated ([`orientation_matrix`]; `YxZ`: `(gy, -gx, gz)`).
//!   Gyroflow's IMU frame has, for a level camera looking forward, x up,
//!   y left and z backwards (its "standard input orientation"; the same
//!   follows from its integrator's `(-y, x, z)` and its frame transform's sign
//!   flips into the OpenCV frame). mmbm's camera frame (x right, y down,
//!   z forward) is [`GYROFLOW_TO_CAMERA`] times that, so `w_camera =
//!   camera_matrix(orientation) * g * gscale` ([`camera_matrix`]). A header
//!   without `orientation` gets Gyroflow's default for `.gcsv`, `xzY`.
//!   Gyroflow's IMU rotation (pitch, roll, yaw in degrees, applied in its
//!   IMU frame after the orientation) is [`gyroflow_rotation`]
//!   (`--gyroflow-rotation`); mmbm's `--imu-rotation` applies last, in the
//!   camera frame.
//! - `frame_readout_time` is in milliseconds; [`GcsvHeader::readout_s`] is in
//!   seconds, its magnitude; a negative time reverses the direction
//!   (Gyroflow's sign: bottom to top for the default top to bottom). Other
//!   header keys are kept in [`GcsvHeader::fields`], unread.
//!
//! [`GcsvReader`] yields the rows as samples (s, rad/s, camera frame) one
//! line at a time, each with its line in the file, so that
//! [`super::gyro::GyroReader`] applies its checks and options (order, gaps,
//! `--imu-rotation` after the orientation, `--time-offset`) in constant
//! memory, with no text in between; a bad row is reported by the reader
//! itself, naming the file, its line and the `.gcsv` column. The head
//! (magic line, header, column line) is read in small steps (`gcsv/head.rs`).

mod head;
mod rows;

use super::input::{line_too_long, read_line, Line, MAX_LINE_BYTES};
use crate::error::{quote, Error, Result};
use glam::{DMat3, DVec3};
pub use head::read_header;
pub use rows::{to_csv, GcsvReader, GcsvRow};
use std::fs::File;
use std::io::{BufRead, Read};
use std::path::Path;

/// The first line of a `.gcsv` file (either form).
pub const MAGIC: [&str; 2] = ["GYROFLOW IMU LOG", "CAMERA IMU LOG"];

/// Orientation used when the header has none (Gyroflow's default for `.gcsv`).
pub const DEFAULT_ORIENTATION: &str = "xzY";

/// `tscale` when the header has none: s per unit of `t` (telemetry-parser's
/// default, milliseconds).
pub const DEFAULT_TSCALE: f64 = 0.001;

/// `gscale` when the header has none: rad/s per unit of the gyro columns
/// (telemetry-parser's default).
pub const DEFAULT_GSCALE: f64 = 1.0;

/// Gyroflow's IMU frame (x up, y left, z backwards for a level camera looking
/// forward) to mmbm's camera frame (x right, y down, z forward):
/// `(x, y, z) -> (-y, -x, -z)`, a rotation (determinant +1).
pub const GYROFLOW_TO_CAMERA: DMat3 = DMat3::from_cols(
    DVec3::new(0.0, -1.0, 0.0),
    DVec3::new(-1.0, 0.0, 0.0),
    DVec3::new(0.0, 0.0, -1.0),
);

/// Order in which the lines of a rolling-shutter frame are read: the
/// camera's own type ([`crate::camera::Readout`]), parsed from Gyroflow's
/// values by [`crate::camera::Readout::from_gyroflow`].
pub type ReadoutDirection = crate::camera::Readout;

/// The header of a `.gcsv` file.
#[derive(Debug, Clone, PartialEq)]
pub struct GcsvHeader {
    /// `frame_readout_time` converted from ms to s (None: not given).
    pub readout_s: Option<f64>,
    /// `frame_readout_direction` (None: not given; Gyroflow then assumes top to bottom).
    pub readout_direction: Option<ReadoutDirection>,
    /// `orientation` as written (validated), or [`DEFAULT_ORIENTATION`].
    pub orientation: String,
    /// Seconds per unit of `t` ([`DEFAULT_TSCALE`] when the header has none).
    pub tscale: f64,
    /// rad/s per unit of the gyro columns ([`DEFAULT_GSCALE`] when the header has none).
    pub gscale: f64,
    /// Every `key,value` header line, in file order (the value is everything
    /// after the first comma, trimmed).
    pub fields: Vec<(String, String)>,
}

impl GcsvHeader {
    /// File gyro axes to mmbm's camera frame ([`camera_matrix`] of the orientation).
    pub fn camera_matrix(&self) -> Result<DMat3> {
        camera_matrix(&self.orientation)
    }

    /// The value of header key `key` (the last one if repeated).
    pub fn get(&self, key: &str) -> Option<&str> {
        self.fields
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// Signed axis map: output axis `i` is `sign * input[axis]`.
type Axes = [(usize, f64); 3];

fn parse_orientation(s: &str) -> std::result::Result<Axes, String> {
    let b = s.as_bytes();
    let bad = || {
        format!(
            "{}: expected 3 letters, a permutation of x, y, z (uppercase: same sign, lowercase: negated), e.g. XYZ or YxZ",
            quote(s)
        )
    };
    if b.len() != 3 {
        return Err(bad());
    }
    let mut axes = [(0, 1.0); 3];
    let mut seen = [false; 3];
    for (i, &c) in b.iter().enumerate() {
        let axis = match c.to_ascii_lowercase() {
            b'x' => 0,
            b'y' => 1,
            b'z' => 2,
            _ => return Err(bad()),
        };
        if std::mem::replace(&mut seen[axis], true) {
            return Err(bad());
        }
        axes[i] = (axis, if c.is_ascii_uppercase() { 1.0 } else { -1.0 });
    }
    Ok(axes)
}

fn axes_matrix(axes: &Axes) -> DMat3 {
    let mut m = [[0.0; 3]; 3]; // m[col][row]
    for (row, &(col, sign)) in axes.iter().enumerate() {
        m[col][row] = sign;
    }
    DMat3::from_cols_array_2d(&m)
}

/// Gyroflow's orientation step: the matrix taking the file's `(gx, gy, gz)`
/// to Gyroflow's IMU frame (row `i` has `+-1` in the column of letter `i`;
/// `XYZ` is the identity, `YxZ` gives `(gy, -gx, gz)`). An error names
/// `orientation` unless the string is a permutation of x, y, z.
pub fn orientation_matrix(orientation: &str) -> Result<DMat3> {
    parse_orientation(orientation)
        .map(|a| axes_matrix(&a))
        .map_err(|m| Error::invalid("orientation", m))
}

/// The file's `(gx, gy, gz)` to mmbm's camera frame:
/// [`GYROFLOW_TO_CAMERA`] `*` [`orientation_matrix`]. `XYZ` gives
/// `(-gy, -gx, -gz)`, `YxZ` gives `(gx, -gy, -gz)`.
pub fn camera_matrix(orientation: &str) -> Result<DMat3> {
    Ok(GYROFLOW_TO_CAMERA * orientation_matrix(orientation)?)
}

/// Gyroflow's IMU rotation from its `[pitch, roll, yaw]` angles in degrees
/// (the project's `gyro_source.rotation`, Gyroflow's "IMU rotation"), as its
/// IMU transforms build it: `Rz(roll) * Ry(pitch) * Rx(yaw)` (nalgebra's
/// `from_euler_angles(yaw, pitch, roll)`), acting on vectors in Gyroflow's
/// IMU frame (x up, y left, z back) after the orientation: Gyroflow's
/// `w = R * orientation_matrix * g`. So yaw turns about the up axis, pitch
/// about the left axis, roll about the backward axis. In mmbm's camera frame
/// it is `GYROFLOW_TO_CAMERA * R * GYROFLOW_TO_CAMERA^T`
/// ([`GcsvReader::with_rotation`]). An error names the angle that is not finite.
pub fn gyroflow_rotation(pitch_roll_yaw_deg: [f64; 3]) -> Result<DMat3> {
    for (v, name) in pitch_roll_yaw_deg.iter().zip(["pitch", "roll", "yaw"]) {
        if !v.is_finite() {
            return Err(Error::invalid(
                "Gyroflow IMU rotation",
                format!("{name} = {v} degrees is not finite"),
            ));
        }
    }
    let [pitch, roll, yaw] = pitch_roll_yaw_deg.map(f64::to_radians);
    Ok(DMat3::from_rotation_z(roll) * DMat3::from_rotation_y(pitch) * DMat3::from_rotation_x(yaw))
}

/// `camera_matrix` as a signed axis map (exact arithmetic: a sign and a pick).
fn camera_axes(orientation: &Axes) -> Axes {
    // GYROFLOW_TO_CAMERA: camera x = -gyroflow y, y = -gyroflow x, z = -gyroflow z.
    let neg = |(a, s): (usize, f64)| (a, -s);
    [
        neg(orientation[1]),
        neg(orientation[0]),
        neg(orientation[2]),
    ]
}

/// True for a first line (BOM and surrounding white space removed) that is a [`MAGIC`].
fn is_magic(line: &[u8]) -> bool {
    let line = line.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(line);
    let line = line.trim_ascii();
    MAGIC.iter().any(|m| line == m.as_bytes())
}

/// True when `path` is a `.gcsv` file: its extension is `gcsv` (any case), or
/// its first line is `GYROFLOW IMU LOG` or `CAMERA IMU LOG`. (A `.gcsv` file
/// whose first line is neither is then an error, not a CSV.)
pub fn is_gcsv(path: &Path) -> bool {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gcsv"))
    {
        return true;
    }
    // Only a regular file is sniffed (reading a pipe would consume it).
    if !super::input::is_regular_file(path) {
        return false;
    }
    let mut head = Vec::with_capacity(64);
    let read = File::open(path).and_then(|f| f.take(64).read_to_end(&mut head));
    if read.is_err() {
        return false;
    }
    let first = head.split(|&b| b == b'\n').next().unwrap_or(&[]);
    is_magic(first)
}

/// The `.gcsv` columns the reader uses.
#[derive(Debug, Clone)]
struct Columns {
    names: Vec<String>,
    t: usize,
    g: [usize; 3],
}

/// Reads line number `line` (without its `\n` / `\r\n`) into `buf`; false
/// at end of file. A line over [`MAX_LINE_BYTES`] is an error.
fn next_line<R: BufRead>(src: &mut R, buf: &mut Vec<u8>, path: &Path, line: u64) -> Result<bool> {
    match read_line(src, buf, MAX_LINE_BYTES).map_err(|e| Error::io(path, e))? {
        Line::Eof => return Ok(false),
        Line::TooLong => return Err(line_too_long(path, line, MAX_LINE_BYTES)),
        Line::Read => {}
    }
    if buf.last() == Some(&b'\n') {
        buf.pop();
        if buf.last() == Some(&b'\r') {
            buf.pop();
        }
    }
    Ok(true)
}

fn parse_err(path: &Path, line: u64, column: &str, message: String) -> Error {
    Error::Parse {
        path: path.into(),
        line,
        column: column.into(),
        message,
    }
}

fn utf8<'a>(bytes: &'a [u8], path: &Path, line: u64) -> Result<&'a str> {
    std::str::from_utf8(bytes)
        .map_err(|_| parse_err(path, line, "-", "the line is not UTF-8 text".into()))
}

#[cfg(test)]
mod tests;
