//! Gyro logs (SPEC section 5): a plain CSV with a header row, columns `t`
//! (seconds by default), `wx, wy, wz` (rad/s by default), optional `vx, vy, vz`
//! (m/s) and `depth` (m). Lines starting with `#` are comments. A ROS 2 MCAP
//! file (`mcap`) or a Gyroflow `.gcsv` log (`gcsv`) is
//! turned into the same CSV text first.
//!
//! [`GyroReader`] streams the file in constant memory and validates every
//! field; errors name the file, line and column.

use crate::error::{Error, Result};
pub use crate::model::log::GyroSample;
use crate::model::log::{is_gap, ImuLog, LogReadout};
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// Unit of the `t` column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TimeUnit {
    /// Seconds.
    #[default]
    S,
    /// Milliseconds.
    Ms,
    /// Microseconds.
    Us,
    /// Nanoseconds.
    Ns,
}

impl TimeUnit {
    /// Seconds per unit.
    pub fn seconds(self) -> f64 {
        match self {
            TimeUnit::S => 1.0,
            TimeUnit::Ms => 1e-3,
            TimeUnit::Us => 1e-6,
            TimeUnit::Ns => 1e-9,
        }
    }
}

impl FromStr for TimeUnit {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "s" => Ok(TimeUnit::S),
            "ms" => Ok(TimeUnit::Ms),
            "us" => Ok(TimeUnit::Us),
            "ns" => Ok(TimeUnit::Ns),
            _ => Err(Error::invalid(
                "time unit",
                format!("'{s}': expected s, ms, us or ns"),
            )),
        }
    }
}

/// Unit of the angular-velocity columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AngleUnit {
    /// Radians per second.
    #[default]
    Rad,
    /// Degrees per second.
    Deg,
}

impl FromStr for AngleUnit {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "rad" | "rad/s" => Ok(AngleUnit::Rad),
            "deg" | "deg/s" => Ok(AngleUnit::Deg),
            _ => Err(Error::invalid(
                "angle unit",
                format!("'{s}': expected rad or deg"),
            )),
        }
    }
}

/// How to turn the file's columns into camera-frame samples.
#[derive(Debug, Clone, PartialEq)]
pub struct GyroOptions {
    /// Unit of `t`.
    pub time_unit: TimeUnit,
    /// Unit of `wx, wy, wz`.
    pub angle_unit: AngleUnit,
    /// Rotation taking IMU-frame vectors to the camera frame (applied to `w` and `v`).
    pub imu_to_camera: DMat3,
    /// Added to every time stamp after unit conversion, s (camera clock = IMU clock + offset).
    pub time_offset: f64,
    /// MCAP input: the topic of `sensor_msgs/msg/Imu` messages (None: the
    /// only such topic in the file).
    pub topic: Option<String>,
}

impl Default for GyroOptions {
    fn default() -> Self {
        GyroOptions {
            time_unit: TimeUnit::S,
            angle_unit: AngleUnit::Rad,
            imu_to_camera: DMat3::IDENTITY,
            time_offset: 0.0,
            topic: None,
        }
    }
}

impl GyroOptions {
    /// A sample from raw column values in the log's units: `t` converted and
    /// offset, `w` converted to rad/s, `w` and `v` rotated into the camera
    /// frame (the same arithmetic as [`GyroReader`]).
    pub fn sample(&self, t: f64, w: DVec3, v: Option<DVec3>, depth: Option<f64>) -> GyroSample {
        let k = match self.angle_unit {
            AngleUnit::Rad => 1.0,
            AngleUnit::Deg => std::f64::consts::PI / 180.0,
        };
        GyroSample {
            t: t * self.time_unit.seconds() + self.time_offset,
            omega: self.imu_to_camera * (w * k),
            velocity: v.map(|v| self.imu_to_camera * v),
            depth,
        }
    }
}

/// Parses a rotation given as 9 comma-separated numbers (row-major 3x3).
pub fn parse_rotation(s: &str) -> Result<DMat3> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| {
            Error::invalid(
                "rotation",
                format!("'{s}': expected 9 comma-separated numbers"),
            )
        })?;
    if v.len() != 9 || v.iter().any(|x| !x.is_finite()) {
        return Err(Error::invalid(
            "rotation",
            format!("'{s}': expected 9 finite numbers (row-major 3x3)"),
        ));
    }
    let m = DMat3::from_cols_array(&[v[0], v[3], v[6], v[1], v[4], v[7], v[2], v[5], v[8]]);
    let err = (m * m.transpose() - DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .map(|x| x.abs())
        .fold(0.0, f64::max);
    if err > 1e-6 || (m.determinant() - 1.0).abs() > 1e-6 {
        return Err(Error::invalid(
            "rotation",
            format!("'{s}' is not a rotation matrix (orthonormal, det +1)"),
        ));
    }
    Ok(m)
}

/// Streaming, validating reader of a gyro CSV.
pub struct GyroReader {
    path: PathBuf,
    reader: csv::Reader<BufReader<Box<dyn Read + Send>>>,
    opts: GyroOptions,
    idx_t: usize,
    idx_w: [usize; 3],
    idx_v: Option<[usize; 3]>,
    idx_depth: Option<usize>,
    names: Vec<String>,
    record: csv::StringRecord,
    last_t: Option<(f64, u64)>,
    intervals: Vec<f64>,
    median_dt: Option<f64>,
    warnings: Vec<String>,
    count: u64,
    failed: bool,
    readout: Option<LogReadout>,
}

impl GyroReader {
    /// Opens `path` (`-`: standard input, named `<stdin>` in errors) and
    /// checks the header.
    pub fn open(path: &Path, opts: GyroOptions) -> Result<Self> {
        let mut readout = None;
        use super::input::{open_stream, LineCap, MAX_LINE_BYTES};
        let (file, path): (Box<dyn Read + Send>, &Path) = if path.as_os_str() == "-" {
            let name = Path::new("<stdin>");
            let stdin = LineCap::new(std::io::stdin(), name, MAX_LINE_BYTES);
            (Box::new(stdin), name)
        } else if super::mcap::is_mcap(path) {
            if opts.time_unit != TimeUnit::S || opts.angle_unit != AngleUnit::Rad {
                return Err(Error::invalid(
                    path.display().to_string(),
                    "an MCAP log holds ROS units (s, rad/s): leave --time-unit and --angle-unit at their defaults",
                ));
            }
            // The messages become CSV text so that they pass the same
            // checks (order, gaps) and options (rotation, offset) as a CSV
            // log; a line number in an error is the message number + 1.
            let messages = super::mcap::read_imu(path, opts.topic.as_deref())?;
            let text = super::mcap::to_csv(&messages).into_bytes();
            (Box::new(std::io::Cursor::new(text)), path)
        } else if super::gcsv::is_gcsv(path) {
            if opts.time_unit != TimeUnit::S || opts.angle_unit != AngleUnit::Rad {
                return Err(Error::invalid(
                    path.display().to_string(),
                    "a Gyroflow .gcsv log carries its own scales (tscale, gscale): leave --time-unit and --angle-unit at their defaults",
                ));
            }
            // Converted to CSV one line at a time (constant memory), with
            // the same line numbers; a bad row is reported by the stream.
            let stream = super::gcsv::CsvStream::open(path)?;
            let h = stream.header();
            readout = h.readout_s.map(|readout_s| LogReadout {
                readout_s,
                direction: h.readout_direction,
            });
            (Box::new(stream), path)
        } else {
            let file = LineCap::new(open_stream(path)?, path, MAX_LINE_BYTES);
            (Box::new(file), path)
        };
        let mut reader = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .trim(csv::Trim::All)
            .flexible(false)
            .from_reader(BufReader::with_capacity(1 << 16, file));
        let headers = reader
            .headers()
            .map_err(|e| csv_error(path, e, "header"))?
            .clone();
        let names: Vec<String> = headers.iter().map(|s| s.to_string()).collect();
        for n in ["t", "wx", "wy", "wz", "vx", "vy", "vz", "depth"] {
            if names.iter().filter(|h| *h == n).count() > 1 {
                return Err(Error::Parse {
                    path: path.into(),
                    line: 1,
                    column: n.into(),
                    message: format!("column '{n}' appears more than once in the header"),
                });
            }
        }
        let find = |n: &str| names.iter().position(|h| h == n);
        let need = |n: &str| {
            find(n).ok_or_else(|| Error::Parse {
                path: path.into(),
                line: 1,
                column: n.into(),
                message: format!(
                    "missing required column '{n}' (header is: {})",
                    names.join(",")
                ),
            })
        };
        let idx_t = need("t")?;
        let idx_w = [need("wx")?, need("wy")?, need("wz")?];
        let idx_v = match (find("vx"), find("vy"), find("vz")) {
            (Some(a), Some(b), Some(c)) => Some([a, b, c]),
            (None, None, None) => None,
            _ => {
                return Err(Error::Parse {
                    path: path.into(),
                    line: 1,
                    column: "vx,vy,vz".into(),
                    message: "velocity columns must come as all three of vx, vy, vz".into(),
                })
            }
        };
        let idx_depth = find("depth");
        Ok(GyroReader {
            path: path.into(),
            reader,
            opts,
            idx_t,
            idx_w,
            idx_v,
            idx_depth,
            names,
            record: csv::StringRecord::new(),
            last_t: None,
            intervals: Vec::new(),
            median_dt: None,
            warnings: Vec::new(),
            count: 0,
            failed: false,
            readout,
        })
    }

    /// The file's own rolling-shutter readout (a `.gcsv` header's), if any.
    pub fn readout(&self) -> Option<LogReadout> {
        self.readout
    }

    /// True when the log has `vx, vy, vz`.
    pub fn has_velocity(&self) -> bool {
        self.idx_v.is_some()
    }

    /// True when the log has `depth`.
    pub fn has_depth(&self) -> bool {
        self.idx_depth.is_some()
    }

    /// Prints [`GyroReader::warnings`] on stderr, one `warning: ...` line each.
    pub fn print_warnings(&self) {
        for w in &self.warnings {
            log::warn!("warning: {w}");
        }
    }

    /// Warnings so far (gaps much longer than the median interval), at most 20 kept.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Samples read so far.
    pub fn count(&self) -> u64 {
        self.count
    }

    fn field(&self, idx: usize, line: u64) -> Result<f64> {
        let s = &self.record[idx];
        let col = &self.names[idx];
        let x: f64 = s.parse().map_err(|_| Error::Parse {
            path: self.path.clone(),
            line,
            column: col.clone(),
            message: format!("{} is not a number", crate::error::quote(s)),
        })?;
        if !x.is_finite() {
            return Err(Error::Parse {
                path: self.path.clone(),
                line,
                column: col.clone(),
                message: format!("{} is not finite", crate::error::quote(s)),
            });
        }
        Ok(x)
    }

    fn next_sample(&mut self) -> Result<Option<GyroSample>> {
        let more = self
            .reader
            .read_record(&mut self.record)
            .map_err(|e| csv_error(&self.path, e, "record"))?;
        if !more {
            if self.count == 0 {
                return Err(Error::Parse {
                    path: self.path.clone(),
                    line: self.reader.position().line(),
                    column: "-".into(),
                    message: "the log has no samples".into(),
                });
            }
            return Ok(None);
        }
        let line = self.record.position().map_or(0, |p| p.line());
        let t =
            self.field(self.idx_t, line)? * self.opts.time_unit.seconds() + self.opts.time_offset;
        let k = match self.opts.angle_unit {
            AngleUnit::Rad => 1.0,
            AngleUnit::Deg => std::f64::consts::PI / 180.0,
        };
        let w = DVec3::new(
            self.field(self.idx_w[0], line)?,
            self.field(self.idx_w[1], line)?,
            self.field(self.idx_w[2], line)?,
        ) * k;
        let velocity = match self.idx_v {
            Some(i) => Some(
                self.opts.imu_to_camera
                    * DVec3::new(
                        self.field(i[0], line)?,
                        self.field(i[1], line)?,
                        self.field(i[2], line)?,
                    ),
            ),
            None => None,
        };
        let depth = match self.idx_depth {
            Some(i) => Some(self.field(i, line)?),
            None => None,
        };
        if let Some((prev, prev_line)) = self.last_t {
            if t <= prev {
                return Err(Error::Parse {
                    path: self.path.clone(),
                    line,
                    column: self.names[self.idx_t].clone(),
                    message: format!(
                        "time {t} s is not after the previous sample's {prev} s (line {prev_line}): time must strictly increase"
                    ),
                });
            }
            self.check_gap(t - prev, t, line);
        }
        self.last_t = Some((t, line));
        self.count += 1;
        Ok(Some(GyroSample {
            t,
            omega: self.opts.imu_to_camera * w,
            velocity,
            depth,
        }))
    }

    /// Gap detection in constant memory: the median of the first 101 intervals
    /// is the reference; any later interval over 5x it is a warning.
    fn check_gap(&mut self, dt: f64, t: f64, line: u64) {
        const N: usize = 101;
        match self.median_dt {
            None => {
                self.intervals.push(dt);
                if self.intervals.len() == N {
                    let mut v = std::mem::take(&mut self.intervals);
                    v.sort_by(f64::total_cmp);
                    let med = v[N / 2];
                    self.median_dt = Some(med);
                    for &d in &v {
                        if is_gap(d, med) {
                            self.warn(format!("gap of {d:.6} s among the first {N} samples (median interval {med:.6} s)"));
                        }
                    }
                }
            }
            Some(med) if is_gap(dt, med) => self.warn(format!(
                "{}:{line}: gap of {dt:.6} s before t = {t} s (median interval {med:.6} s)",
                self.path.display()
            )),
            Some(_) => {}
        }
    }

    fn warn(&mut self, w: String) {
        if self.warnings.len() < 20 {
            self.warnings.push(w);
        }
    }
}

impl Iterator for GyroReader {
    type Item = Result<GyroSample>;
    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        match self.next_sample() {
            Ok(Some(s)) => Some(Ok(s)),
            Ok(None) => None,
            Err(e) => {
                self.failed = true;
                Some(Err(e))
            }
        }
    }
}

/// A CSV reader error as an [`Error`]; an error made by the source itself (a
/// `.gcsv` row, see [`super::gcsv::CsvStream`]) is returned as it is.
fn csv_error(path: &Path, e: csv::Error, what: &str) -> Error {
    let (line, column) = match e.kind() {
        csv::ErrorKind::UnequalLengths {
            pos,
            expected_len,
            len,
        } => (
            pos.as_ref().map_or(0, |p| p.line()),
            format!("field count (expected {expected_len}, found {len})"),
        ),
        _ => (e.position().map_or(0, |p| p.line()), what.to_string()),
    };
    let message = e.to_string();
    if let csv::ErrorKind::Io(io) = e.into_kind() {
        if let Ok(inner) = super::gcsv::unwrap_error(io) {
            return inner;
        }
    }
    Error::Parse {
        path: path.into(),
        line,
        column,
        message,
    }
}

/// Reads a whole log into memory (for windows and policies that need random
/// access), with the file's own readout where it has one. Its warnings
/// (gaps) are printed on stderr as `warning: ...`.
pub fn read_log(path: &Path, opts: GyroOptions) -> Result<ImuLog> {
    let mut r = GyroReader::open(path, opts)?;
    let samples = r.by_ref().collect::<Result<Vec<_>>>()?;
    r.print_warnings();
    Ok(ImuLog::new(samples)?.with_readout(r.readout()))
}

#[cfg(test)]
mod tests;
