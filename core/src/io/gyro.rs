//! Gyro logs (docs/spec.md section 5): a plain CSV with a header row, columns `t`
//! (seconds by default), `wx, wy, wz` (rad/s by default), optional `vx, vy, vz`
//! (m/s) and `depth` (m). Lines starting with `#` are comments. A ROS 2 MCAP
//! file (`mcap`) or a Gyroflow `.gcsv` log ([`super::gcsv`]) is read
//! by its own reader, which yields the samples directly (no text in between);
//! so is a phone's CSV of IMU rows with a sensor-type column
//! ([`super::phone`]: nanoseconds, gyro rows only), known by its header.
//!
//! [`GyroReader`] streams the file in constant memory and validates every
//! field, the same way for every format; errors name the file, line and
//! column.

mod fast;
mod plain;
mod raw;

use super::gcsv::GcsvReader;
use super::input::check_increasing;
use super::mcap::ImuStream;
use super::phone::ImuRows;
use crate::error::{Error, Result};
pub use crate::model::log::GyroSample;
use crate::model::log::{gap_reference, is_gap, ImuLog, LogReadout, GAP_REFERENCE_INTERVALS};
use glam::{DMat3, DVec3};
use plain::CsvSource;
use raw::Raw;
use serde::{Deserialize, Serialize};
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
    /// Rotation taking IMU-frame vectors to the camera frame (applied to `w`
    /// and `v`, last: for a `.gcsv` log, after its orientation and
    /// `gyroflow_rotation`, in mmbm's camera frame; `--imu-rotation`).
    pub imu_to_camera: DMat3,
    /// A `.gcsv` log only: Gyroflow's IMU rotation `[pitch, roll, yaw]`,
    /// degrees, in Gyroflow's IMU frame after the orientation
    /// ([`super::gcsv::gyroflow_rotation`]; `--gyroflow-rotation`). None: none.
    pub gyroflow_rotation: Option<[f64; 3]>,
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
            gyroflow_rotation: None,
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
    let det = m.determinant();
    if err > 1e-6 {
        return Err(Error::invalid(
            "rotation",
            format!(
                "'{s}' is not a rotation matrix (orthonormal, det +1): its rows are not \
                 orthonormal (largest entry of R R^T - I: {err:.3e}; determinant {det})"
            ),
        ));
    }
    if (det - 1.0).abs() > 1e-6 {
        let (row, proper) = proper_rotation(&v);
        let list: Vec<String> = proper.iter().map(|x| x.to_string()).collect();
        return Err(Error::invalid(
            "rotation",
            format!(
                "'{s}' is not a rotation matrix (orthonormal, det +1): its determinant is {det}, \
                 an axis swap or reflection (a left-handed frame). Negating one axis makes it a \
                 proper rotation: with row {row} negated it is '{}' (negating any other one row \
                 is a rotation too; which is right depends on the axis the calibration flips)",
                list.join(",")
            ),
        ));
    }
    Ok(m)
}

/// For an orthonormal row-major matrix `v` with determinant -1: the row
/// (1-based) to negate and the proper rotation that gives. The row chosen
/// makes the smallest rotation (the largest trace; the lowest row on a tie).
fn proper_rotation(v: &[f64]) -> (usize, [f64; 9]) {
    // Negating row i changes the trace by -2 v[i][i].
    let row = (0..3)
        .min_by(|&a, &b| v[4 * a].total_cmp(&v[4 * b]).then(a.cmp(&b)))
        .unwrap_or(2);
    let mut out = [0.0; 9];
    for (k, o) in out.iter_mut().enumerate() {
        // `0.0 - x` keeps a zero unsigned.
        *o = if k / 3 == row { 0.0 - v[k] } else { v[k] };
    }
    (row + 1, out)
}

/// Where a [`GyroReader`]'s samples come from.
enum Source {
    /// A plain gyro CSV (a file or standard input).
    Csv(CsvSource),
    /// A Gyroflow `.gcsv` log.
    Gcsv(GcsvReader),
    /// A ROS 2 MCAP log (line numbers: message number + 1).
    Mcap(ImuStream),
    /// A phone's IMU rows (sensor-type column, nanoseconds), gyro rows only.
    Phone(ImuRows),
}

/// Streaming, validating reader of a gyro log (CSV, `.gcsv` or MCAP): each
/// source yields its samples directly; the options, the time order and the
/// gap rule are applied here, the same for every source.
pub struct GyroReader {
    path: PathBuf,
    source: Source,
    opts: GyroOptions,
    last_t: Option<(f64, u64)>,
    /// The first intervals (s) with the time (s) and line that ends each,
    /// until the gap rule's reference is known.
    intervals: Vec<(f64, f64, u64)>,
    median_dt: Option<f64>,
    warnings: Vec<String>,
    count: u64,
    failed: bool,
    readout: Option<LogReadout>,
}

impl GyroReader {
    /// Opens `path` (`-`: standard input, named `<stdin>` in errors) and
    /// checks the header. A plain CSV in a regular file is read by a fast parser
    /// while its rows are plain numbers, with the same samples, errors and
    /// line numbers as [`GyroReader::open_exact`].
    pub fn open(path: &Path, opts: GyroOptions) -> Result<Self> {
        Self::open_with(path, opts, true)
    }

    /// [`GyroReader::open`] with the plain CSV read by the exact (`csv`
    /// crate) reader alone, record by record: the reference the fast path is
    /// checked against.
    pub fn open_exact(path: &Path, opts: GyroOptions) -> Result<Self> {
        Self::open_with(path, opts, false)
    }

    fn open_with(path: &Path, opts: GyroOptions, fast: bool) -> Result<Self> {
        let mut readout = None;
        let own_units = |what: &str| -> Result<()> {
            if opts.time_unit != TimeUnit::S || opts.angle_unit != AngleUnit::Rad {
                return Err(Error::invalid(path.display().to_string(), what));
            }
            Ok(())
        };
        let gcsv = path.as_os_str() != "-" && super::gcsv::is_gcsv(path);
        if opts.gyroflow_rotation.is_some() && !gcsv {
            return Err(Error::invalid(
                path.display().to_string(),
                "Gyroflow's IMU rotation (--gyroflow-rotation) applies to a Gyroflow .gcsv log only, in Gyroflow's IMU frame; for this log give --imu-rotation (camera frame)",
            ));
        }
        let (source, path) = if path.as_os_str() == "-" {
            let name = Path::new("<stdin>");
            (
                Source::Csv(CsvSource::open(Box::new(std::io::stdin()), name)?),
                name,
            )
        } else if super::mcap::is_mcap(path) {
            own_units("an MCAP log holds ROS units (s, rad/s): leave --time-unit and --angle-unit at their defaults")?;
            (
                Source::Mcap(ImuStream::open(path, opts.topic.as_deref())?),
                path,
            )
        } else if gcsv {
            own_units("a Gyroflow .gcsv log carries its own scales (tscale, gscale): leave --time-unit and --angle-unit at their defaults")?;
            let mut rows = GcsvReader::open(path)?;
            if let Some(angles) = opts.gyroflow_rotation {
                rows = rows.with_rotation(angles)?;
            }
            let h = rows.header();
            readout = h.readout_s.map(|readout_s| LogReadout {
                readout_s,
                direction: h.readout_direction,
            });
            (Source::Gcsv(rows), path)
        } else if super::phone::is_imu_rows(path) {
            if opts.time_unit != TimeUnit::S {
                return Err(Error::invalid(
                    path.display().to_string(),
                    "IMU rows (a sensor-type column) carry nanosecond timestamps: leave --time-unit at its default",
                ));
            }
            (Source::Phone(ImuRows::open(path)?), path)
        } else {
            let file = super::input::open_stream(path)?;
            (Source::Csv(CsvSource::open_file(file, path, fast)?), path)
        };
        Ok(GyroReader {
            path: path.into(),
            source,
            opts,
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
        matches!(&self.source, Source::Csv(c) if c.has_velocity())
    }

    /// True when the log has `depth`.
    pub fn has_depth(&self) -> bool {
        matches!(&self.source, Source::Csv(c) if c.has_depth())
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

    /// The next sample of the source, in the file's units and axes.
    fn next_raw(&mut self) -> Result<Option<Raw>> {
        match &mut self.source {
            Source::Csv(c) => c.next_raw(),
            Source::Gcsv(g) => Ok(g.next_row()?.map(|r| Raw {
                line: r.line,
                t: r.t,
                w: r.omega,
                v: None,
                depth: None,
            })),
            Source::Phone(p) => Ok(p.next_row()?.map(|r| Raw {
                line: r.line,
                t: r.t,
                w: r.omega,
                v: None,
                depth: None,
            })),
            Source::Mcap(m) => match m.next().transpose()? {
                Some(msg) => Ok(Some(Raw {
                    line: m.messages_read() as u64 + 1,
                    t: msg.t,
                    w: msg.omega,
                    v: None,
                    depth: None,
                })),
                None => Ok(None),
            },
        }
    }

    /// The time column's name in the source.
    fn time_column(&self) -> &str {
        match &self.source {
            Source::Csv(c) => c.time_column(),
            Source::Gcsv(g) => g.time_column(),
            Source::Phone(p) => p.time_column(),
            Source::Mcap(_) => "t",
        }
    }

    /// The line where the end of the source is (where "no samples" is reported).
    fn end_line(&self) -> u64 {
        match &self.source {
            Source::Csv(c) => c.position_line(),
            Source::Gcsv(g) => g.lines_read() + 1,
            Source::Phone(p) => p.lines_read() + 1,
            Source::Mcap(m) => m.messages_read() as u64 + 2,
        }
    }

    fn next_sample(&mut self) -> Result<Option<GyroSample>> {
        let Some(raw) = self.next_raw()? else {
            if self.count == 0 {
                return Err(Error::Parse {
                    path: self.path.clone(),
                    line: self.end_line(),
                    column: "-".into(),
                    message: "the log has no samples".into(),
                });
            }
            self.finish_gaps();
            return Ok(None);
        };
        if self.count == 0 {
            self.state_gcsv_conventions();
        }
        let s = self.opts.sample(raw.t, raw.w, raw.v, raw.depth);
        let line = raw.line;
        check_increasing(&self.path, line, self.time_column(), s.t, self.last_t)?;
        if let Some((prev, _)) = self.last_t {
            self.check_gap(s.t - prev, s.t, line);
        }
        self.last_t = Some((s.t, line));
        self.count += 1;
        Ok(Some(s))
    }

    /// For a `.gcsv` log, says on the log (info) where its time starts and
    /// which scales it took: `(t - t0) * tscale`, with the first row's `t0`.
    fn state_gcsv_conventions(&self) {
        let Source::Gcsv(g) = &self.source else {
            return;
        };
        let h = g.header();
        let given = |key: &str| {
            if h.get(key).is_some() {
                "from the header"
            } else {
                "telemetry-parser's default: the header has none"
            }
        };
        log::info!(
            "{}: Gyroflow .gcsv log: time from the first sample (t0 = {} s is t = 0), tscale {} s ({}), gscale {} rad/s ({}), orientation {}",
            self.path.display(),
            g.first_time_s().unwrap_or(0.0),
            h.tscale,
            given("tscale"),
            h.gscale,
            given("gscale"),
            h.orientation
        );
    }

    /// Gap detection in constant memory: the median of the first 101 intervals
    /// is the reference; any later interval over 5x it is a warning. A
    /// shorter log's reference is the median of all its intervals (from 3
    /// samples up, [`Self::finish_gaps`]).
    fn check_gap(&mut self, dt: f64, t: f64, line: u64) {
        const N: usize = GAP_REFERENCE_INTERVALS;
        match self.median_dt {
            None => {
                self.intervals.push((dt, t, line));
                if self.intervals.len() == N {
                    let mut v: Vec<f64> = self.intervals.iter().map(|i| i.0).collect();
                    self.intervals = Vec::new();
                    let Some(med) = gap_reference(&mut v) else {
                        return;
                    };
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

    /// At the end of a log shorter than the gap rule's reference: its gaps
    /// against the median of the intervals it has (none below 3 samples).
    fn finish_gaps(&mut self) {
        if self.median_dt.is_some() {
            return;
        }
        let first = std::mem::take(&mut self.intervals);
        let mut v: Vec<f64> = first.iter().map(|i| i.0).collect();
        let Some(med) = gap_reference(&mut v) else {
            return;
        };
        self.median_dt = Some(med);
        for (dt, t, line) in first {
            if is_gap(dt, med) {
                self.warn(format!(
                    "{}:{line}: gap of {dt:.6} s before t = {t} s (median interval {med:.6} s of a short log)",
                    self.path.display()
                ));
            }
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
