//! Gyroflow's IMU log, `.gcsv` (docs.gyroflow.xyz, "GCSV format"): a magic
//! line, `key,value` header lines, a column line, then raw samples.
//!
//! ```text
//! GYROFLOW IMU LOG            (or CAMERA IMU LOG)
//! version,1.3
//! orientation,YxZ
//! frame_readout_time,15.23    (ms, optional)
//! frame_readout_direction,0   (optional: 0 top-to-bottom, 1 bottom-to-top, 2 left-to-right, 3 right-to-left)
//! tscale,0.001
//! gscale,0.00122173047
//! t,gx,gy,gz,ax,ay,az         (gx, gy, gz required; other columns are not read)
//! 0,39,86,183,-1137,-15689,-2986
//! ```
//!
//! - Time: `t * tscale`, s. Angular velocity: `g * gscale`, rad/s. Both
//!   scales are required (no default is guessed).
//! - Axes, as Gyroflow reads them (telemetry-parser, and `orient` in
//!   Gyroflow's `gyro_source.rs`): letter `i` of `orientation` names the file
//!   column that becomes Gyroflow's IMU axis `i`, uppercase with its sign,
//!   lowercase negated ([`orientation_matrix`]; `YxZ`: `(gy, -gx, gz)`).
//!   Gyroflow's IMU frame has, for a level camera looking forward, x up,
//!   y left and z backwards (its "standard input orientation"; the same
//!   follows from its integrator's `(-y, x, z)` and its frame transform's sign
//!   flips into the OpenCV frame). mmbm's camera frame (x right, y down,
//!   z forward) is [`GYROFLOW_TO_CAMERA`] times that, so `w_camera =
//!   camera_matrix(orientation) * g * gscale` ([`camera_matrix`]). A header
//!   without `orientation` gets Gyroflow's default for `.gcsv`, `xzY`.
//! - `frame_readout_time` is in milliseconds; [`GcsvHeader::readout_s`] is in
//!   seconds. Other header keys are kept in [`GcsvHeader::fields`], unread.
//!
//! [`CsvStream`] turns the file into gyro CSV text (`t,wx,wy,wz`, s and
//! rad/s, camera frame, shortest round-trip decimals) one line at a time, so
//! that [`super::gyro::GyroReader`] applies its checks and options (order,
//! gaps, `--imu-rotation` after the orientation, `--time-offset`) in constant
//! memory. Each header line becomes a `#` comment line, so line numbers in the
//! CSV are line numbers in the `.gcsv` file; a bad row is reported by the
//! stream itself, naming the file, its line and the `.gcsv` column.

use super::input::{line_too_long, open_stream, read_line, Line, MAX_HEADER_BYTES, MAX_LINE_BYTES};
use crate::error::{quote, Error, Result};
use glam::{DMat3, DVec3};
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// The first line of a `.gcsv` file (either form).
pub const MAGIC: [&str; 2] = ["GYROFLOW IMU LOG", "CAMERA IMU LOG"];

/// Orientation used when the header has none (Gyroflow's default for `.gcsv`).
pub const DEFAULT_ORIENTATION: &str = "xzY";

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
    /// Seconds per unit of `t`.
    pub tscale: f64,
    /// rad/s per unit of `gx, gy, gz`.
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

/// Reads the magic line, the header and the column line. Returns the header,
/// the columns and the number of lines read (the column line's number).
fn read_head<R: BufRead>(src: &mut R, path: &Path) -> Result<(GcsvHeader, Columns, u64)> {
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
    let mut line = 1u64;
    // (key, value, line)
    let mut fields: Vec<(String, String, u64)> = Vec::new();
    let mut head_bytes = buf.len();
    let columns = loop {
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
            break names;
        }
        match text.split_once(',') {
            Some((k, v)) => fields.push((k.trim().to_string(), v.trim().to_string(), line)),
            None => {
                return Err(parse_err(
                    path,
                    line,
                    "-",
                    format!(
                    "{}: expected a 'key,value' header line or the column line (t,gx,gy,gz,...)",
                    quote(text)
                ),
                ))
            }
        }
    };
    // Keys that are read must appear at most once.
    let find = |key: &str| -> Result<Option<(&str, u64)>> {
        let mut hits = fields.iter().filter(|(k, _, _)| k == key);
        let first = hits.next();
        if let (Some(a), Some(b)) = (first, hits.next()) {
            return Err(parse_err(
                path,
                b.2,
                key,
                format!(
                    "header key '{key}' appears twice (lines {} and {})",
                    a.2, b.2
                ),
            ));
        }
        Ok(first.map(|(_, v, l)| (v.as_str(), *l)))
    };
    let scale = |key: &str, what: &str| -> Result<f64> {
        let (v, l) = find(key)?.ok_or_else(|| {
            parse_err(
                path,
                line,
                key,
                format!("missing header key '{key}' ({what}); it must come before the column line"),
            )
        })?;
        match v.parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
            _ => Err(parse_err(
                path,
                l,
                key,
                format!("{} is not a finite number > 0", quote(v)),
            )),
        }
    };
    let tscale = scale("tscale", "seconds per unit of t")?;
    let gscale = scale("gscale", "rad/s per unit of gx, gy, gz")?;
    let orientation = match find("orientation")? {
        Some((v, l)) => {
            parse_orientation(v).map_err(|m| parse_err(path, l, "orientation", m))?;
            v.to_string()
        }
        None => DEFAULT_ORIENTATION.to_string(),
    };
    let readout_s = match find("frame_readout_time")? {
        Some(("", _)) => None,
        Some((v, l)) => match v.parse::<f64>() {
            Ok(ms) if ms.is_finite() && ms >= 0.0 => Some(ms / 1000.0),
            _ => {
                return Err(parse_err(
                    path,
                    l,
                    "frame_readout_time",
                    format!("{} is not a finite number >= 0 (ms)", quote(v)),
                ))
            }
        },
        None => None,
    };
    let readout_direction = match find("frame_readout_direction")? {
        Some(("", _)) => None,
        Some((v, l)) => Some(ReadoutDirection::from_gyroflow(v).ok_or_else(|| {
            parse_err(
                path,
                l,
                "frame_readout_direction",
                format!(
                    "{}: expected 0 (top to bottom), 1 (bottom to top), 2 (left to right) or 3 (right to left)",
                    quote(v)
                ),
            )
        })?),
        None => None,
    };
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
    let g = [need("gx")?, need("gy")?, need("gz")?];
    let header = GcsvHeader {
        readout_s,
        readout_direction,
        orientation,
        tscale,
        gscale,
        fields: fields.into_iter().map(|(k, v, _)| (k, v)).collect(),
    };
    let cols = Columns {
        names: columns,
        t: 0,
        g,
    };
    Ok((header, cols, line))
}

/// Reads the header of the `.gcsv` file at `path` (up to its column line).
pub fn read_header(path: &Path) -> Result<GcsvHeader> {
    let mut src = BufReader::new(open_stream(path)?);
    read_head(&mut src, path).map(|(h, _, _)| h)
}

/// A `.gcsv` file as gyro CSV text, converted one line at a time: `#` for
/// each line before the column line, `t,wx,wy,wz`, then one row per sample
/// (s, rad/s, camera frame, `{:?}` decimals: shortest round trip). Blank and
/// `#` lines among the samples stay as `#` lines. A bad row (field count,
/// non-number, non-finite value, time not increasing) ends the text with an
/// I/O error that carries the [`Error`] (file, line, `.gcsv` column);
/// [`super::gyro::GyroReader`] reports that error as it is.
pub struct CsvStream {
    path: PathBuf,
    src: BufReader<File>,
    header: GcsvHeader,
    cols: Columns,
    axes: Axes,
    line: u64,
    last_t: Option<(f64, u64)>,
    buf: Vec<u8>,
    out: Vec<u8>,
    pos: usize,
    err: Option<Error>,
    eof: bool,
}

impl CsvStream {
    /// Opens `path` and reads its header (errors name the file, line and key).
    pub fn open(path: &Path) -> Result<Self> {
        let mut src = BufReader::with_capacity(1 << 16, open_stream(path)?);
        let (header, cols, line) = read_head(&mut src, path)?;
        let axes = camera_axes(
            &parse_orientation(&header.orientation)
                .map_err(|m| Error::invalid("orientation", m))?,
        );
        let mut out = b"#\n".repeat(line.saturating_sub(1) as usize);
        out.extend_from_slice(b"t,wx,wy,wz\n");
        Ok(CsvStream {
            path: path.into(),
            src,
            header,
            cols,
            axes,
            line,
            last_t: None,
            buf: Vec::new(),
            out,
            pos: 0,
            err: None,
            eof: false,
        })
    }

    /// The file's header.
    pub fn header(&self) -> &GcsvHeader {
        &self.header
    }

    /// Converts the next line into `out`.
    fn convert_line(&mut self) -> Result<bool> {
        if !next_line(&mut self.src, &mut self.buf, &self.path, self.line + 1)? {
            return Ok(false);
        }
        self.line += 1;
        let (path, line) = (self.path.as_path(), self.line);
        let text = utf8(&self.buf, path, line)?.trim();
        if text.is_empty() || text.starts_with('#') {
            self.out.extend_from_slice(b"#\n");
            return Ok(true);
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
        let num = |i: usize, scale: f64| -> Result<f64> {
            let s = fields[i];
            let x: f64 = s.parse().map_err(|_| {
                parse_err(
                    path,
                    line,
                    &names[i],
                    format!("{} is not a number", quote(s)),
                )
            })?;
            if !x.is_finite() {
                return Err(parse_err(
                    path,
                    line,
                    &names[i],
                    format!("{} is not finite", quote(s)),
                ));
            }
            let y = x * scale;
            if !y.is_finite() {
                return Err(parse_err(
                    path,
                    line,
                    &names[i],
                    format!("{} times the scale {scale} overflows", quote(s)),
                ));
            }
            Ok(y)
        };
        let t = num(self.cols.t, self.header.tscale)?;
        let g = [
            num(self.cols.g[0], self.header.gscale)?,
            num(self.cols.g[1], self.header.gscale)?,
            num(self.cols.g[2], self.header.gscale)?,
        ];
        if let Some((prev, prev_line)) = self.last_t {
            if t <= prev {
                return Err(parse_err(
                    path,
                    line,
                    &names[self.cols.t],
                    format!(
                        "time {t} s is not after the previous sample's {prev} s (line {prev_line}): time must strictly increase"
                    ),
                ));
            }
        }
        self.last_t = Some((t, line));
        let w = self.axes.map(|(a, s)| s * g[a]);
        self.out
            .extend_from_slice(format!("{t:?},{:?},{:?},{:?}\n", w[0], w[1], w[2]).as_bytes());
        Ok(true)
    }

    /// Refills `out` with at least 32 KiB of converted lines (less at the end
    /// of the file or before an error, which is kept for the next read).
    fn fill(&mut self) {
        self.out.clear();
        self.pos = 0;
        while !self.eof && self.err.is_none() && self.out.len() < 1 << 15 {
            match self.convert_line() {
                Ok(true) => {}
                Ok(false) => self.eof = true,
                Err(e) => self.err = Some(e),
            }
        }
    }
}

impl Read for CsvStream {
    fn read(&mut self, dst: &mut [u8]) -> std::io::Result<usize> {
        if self.pos == self.out.len() {
            self.fill();
        }
        if self.pos < self.out.len() {
            let n = dst.len().min(self.out.len() - self.pos);
            dst[..n].copy_from_slice(&self.out[self.pos..self.pos + n]);
            self.pos += n;
            return Ok(n);
        }
        match self.err.take() {
            Some(e) => {
                self.eof = true;
                Err(std::io::Error::other(e))
            }
            None => Ok(0),
        }
    }
}

/// The [`Error`] inside an I/O error made by [`CsvStream`], if it is one.
pub fn unwrap_error(e: std::io::Error) -> std::result::Result<Error, std::io::Error> {
    if !e.get_ref().is_some_and(|inner| inner.is::<Error>()) {
        return Err(e);
    }
    match e.into_inner().map(|inner| inner.downcast::<Error>()) {
        Some(Ok(err)) => Ok(*err),
        Some(Err(other)) => Err(std::io::Error::other(other)),
        None => Err(std::io::Error::other("I/O error")),
    }
}

/// The whole file as gyro CSV text ([`CsvStream`], read to the end).
pub fn to_csv(path: &Path) -> Result<String> {
    let mut s = String::new();
    CsvStream::open(path)?
        .read_to_string(&mut s)
        .map_err(|e| unwrap_error(e).unwrap_or_else(|e| Error::io(path, e)))?;
    Ok(s)
}

#[cfg(test)]
mod tests;
