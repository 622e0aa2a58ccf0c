//! Phone logs as Android apps and research code record them:
//!
//! - **IMU rows** ([`ImuRows`]): one CSV of sensor rows with a sensor-type
//!   column, e.g. `timestamp_ns,type,x,y,z`. Time in nanoseconds; the type a
//!   name (`gyro`, `gyroscope`, `accel`, `accelerometer`, ...) or Android's
//!   sensor number (`4` gyroscope, `1` accelerometer); gyro values in rad/s
//!   (the sensor's axes). Only gyro rows are read; the others are skipped
//!   (and named in the error when the file has no gyro row at all).
//! - **Image list** ([`read_image_list`]): one row per video frame with its
//!   nanosecond timestamp (exposure start of the first line) and exposure
//!   time, e.g. `timestamp_ns,exposure_ns`, and optionally each frame's
//!   rolling-shutter readout (`readout_ns`, or `readout_s` in seconds; the
//!   frame table's per-frame readout); without one the camera's.
//!
//! Header names are matched without case, spaces or a leading `#`, and
//! `name [ns]` is `name_ns` (`#timestamp [ns]`). Lines starting with `#`
//! after the header and blank lines are skipped. Errors name the file, the
//! line and the column.

use super::input::TextLines;
use crate::error::{quote, Error, Result};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// A header name as matched: lower case, no spaces, `[ns]` as `_ns`.
fn normal(name: &str) -> String {
    let n: String = name
        .trim()
        .trim_matches('"')
        .to_lowercase()
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    n.replace("[ns]", "_ns").replace("__", "_")
}

/// The normalised names of a header line (a leading `#` dropped).
fn names(line: &str) -> Vec<String> {
    line.trim_start()
        .trim_start_matches('#')
        .split(',')
        .map(normal)
        .collect()
}

fn position(names: &[String], options: &[&str]) -> Option<usize> {
    options
        .iter()
        .find_map(|o| names.iter().position(|n| n == o))
}

/// Time columns of the IMU rows (nanoseconds).
const IMU_TIME: [&str; 4] = ["timestamp_ns", "timestamp", "t_ns", "time_ns"];
/// Sensor-type columns.
const IMU_TYPE: [&str; 3] = ["type", "sensor", "sensor_type"];
/// Time columns of an image list (nanoseconds).
const FRAME_TIME: [&str; 3] = ["timestamp_ns", "timestamp", "t_ns"];
/// Exposure columns of an image list (nanoseconds).
const FRAME_EXPOSURE: [&str; 2] = ["exposure_ns", "exposure_time_ns"];
/// Readout columns of an image list and their unit (s per unit).
const FRAME_READOUT: [(&str, f64); 3] = [
    ("readout_ns", 1e-9),
    ("rolling_shutter_skew_ns", 1e-9),
    ("readout_s", 1.0),
];

/// The column positions of an IMU-row header: time, type, x, y, z.
fn imu_columns(names: &[String]) -> Option<[usize; 5]> {
    Some([
        position(names, &IMU_TIME)?,
        position(names, &IMU_TYPE)?,
        position(names, &["x"])?,
        position(names, &["y"])?,
        position(names, &["z"])?,
    ])
}

/// The first line of `path` that is not blank (a header, perhaps behind a
/// `#`), read only from a regular file (a pipe cannot be read twice).
fn first_line(path: &Path) -> Option<String> {
    if !super::input::is_regular_file(path) {
        return None;
    }
    let mut lines = TextLines::open(path).ok()?;
    while let Ok(Some((_, l))) = lines.next_line() {
        if !l.trim().is_empty() {
            return Some(l);
        }
    }
    None
}

/// True when `path` is a regular file whose header is IMU rows' (a time, a
/// sensor-type and `x, y, z` columns).
pub fn is_imu_rows(path: &Path) -> bool {
    first_line(path).is_some_and(|l| imu_columns(&names(&l)).is_some())
}

/// True when the header `line` is an image list's (nanosecond timestamp and
/// exposure columns).
pub fn is_image_list_header(line: &str) -> bool {
    let n = names(line);
    position(&n, &FRAME_TIME).is_some() && position(&n, &FRAME_EXPOSURE).is_some()
}

/// What a sensor-type field names.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Sensor {
    Gyro,
    Accel,
    Other(String),
}

fn sensor(field: &str) -> Sensor {
    let t = normal(field);
    let t = t
        .strip_prefix("android.sensor.")
        .or_else(|| t.strip_prefix("type_"))
        .unwrap_or(&t);
    match t {
        "gyro" | "gyroscope" | "4" => Sensor::Gyro,
        "accel" | "acc" | "accelerometer" | "1" => Sensor::Accel,
        _ => Sensor::Other(field.trim().trim_matches('"').to_string()),
    }
}

/// A field of a row as a finite number, or an error naming file, line and column.
fn number(path: &Path, line: u64, column: &str, s: &str) -> Result<f64> {
    let err = |message: String| Error::Parse {
        path: path.into(),
        line,
        column: column.into(),
        message,
    };
    let s = s.trim().trim_matches('"');
    let x: f64 = s
        .parse()
        .map_err(|_| err(format!("{} is not a number", quote(s))))?;
    if !x.is_finite() {
        return Err(err(format!("{} is not finite", quote(s))));
    }
    Ok(x)
}

/// One gyro row: its line, time (s) and angular velocity (the file's unit and axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuRow {
    /// 1-based line of the row.
    pub line: u64,
    /// Time, s (the file's nanoseconds x 1e-9).
    pub t: f64,
    /// Angular velocity `x, y, z` (rad/s in the format, IMU axes).
    pub omega: DVec3,
}

/// The gyro rows of an IMU-row file, one at a time (see the module docs).
pub struct ImuRows {
    path: PathBuf,
    lines: TextLines,
    cols: [usize; 5],
    names: Vec<String>,
    gyro: u64,
    /// Rows of other types: (type as written, count), the first 16 types.
    others: Vec<(String, u64)>,
    last_line: u64,
}

impl ImuRows {
    /// Opens `path` and reads its header.
    pub fn open(path: &Path) -> Result<Self> {
        let mut lines = TextLines::open(path)?;
        let header_err = |line: u64, message: String| Error::Parse {
            path: path.into(),
            line,
            column: "header".into(),
            message,
        };
        loop {
            let Some((line, text)) = lines.next_line()? else {
                return Err(header_err(
                    1,
                    "the file is empty: expected a header such as timestamp_ns,type,x,y,z".into(),
                ));
            };
            if text.trim().is_empty() {
                continue;
            }
            let n = names(&text);
            let Some(cols) = imu_columns(&n) else {
                return Err(header_err(
                    line,
                    format!(
                        "expected IMU rows with a time ({}), a sensor type ({}) and x, y, z columns, found {}",
                        IMU_TIME.join("/"),
                        IMU_TYPE.join("/"),
                        quote(&text)
                    ),
                ));
            };
            return Ok(ImuRows {
                path: path.into(),
                lines,
                cols,
                names: n,
                gyro: 0,
                others: Vec::new(),
                last_line: line,
            });
        }
    }

    /// The time column's name (as matched).
    pub fn time_column(&self) -> &str {
        &self.names[self.cols[0]]
    }

    /// Lines read so far.
    pub fn lines_read(&self) -> u64 {
        self.last_line
    }

    /// The next gyro row (`None` at the end; an error at the end when the
    /// file has no gyro row, naming the types it has).
    pub fn next_row(&mut self) -> Result<Option<ImuRow>> {
        loop {
            let Some((line, text)) = self.lines.next_line()? else {
                if self.gyro == 0 {
                    return Err(self.no_gyro());
                }
                return Ok(None);
            };
            self.last_line = line;
            let t = text.trim();
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            let f: Vec<&str> = t.split(',').collect();
            let short = |i: usize| Error::Parse {
                path: self.path.clone(),
                line,
                column: self.names[i].clone(),
                message: format!(
                    "the row has {} fields, the header has {}",
                    f.len(),
                    self.names.len()
                ),
            };
            let kind = sensor(f.get(self.cols[1]).ok_or_else(|| short(self.cols[1]))?);
            match kind {
                Sensor::Gyro => {}
                Sensor::Accel => {
                    self.count_other("accel");
                    continue;
                }
                Sensor::Other(name) => {
                    self.count_other(&name);
                    continue;
                }
            }
            let need = |i: usize| f.get(i).copied().ok_or_else(|| short(i));
            let num = |i: usize| number(&self.path, line, &self.names[i], need(i)?);
            let ns = num(self.cols[0])?;
            let omega = DVec3::new(num(self.cols[2])?, num(self.cols[3])?, num(self.cols[4])?);
            self.gyro += 1;
            return Ok(Some(ImuRow {
                line,
                t: ns * 1e-9,
                omega,
            }));
        }
    }

    fn count_other(&mut self, name: &str) {
        if let Some((_, c)) = self.others.iter_mut().find(|(n, _)| n == name) {
            *c += 1;
        } else if self.others.len() < 16 {
            self.others.push((name.to_string(), 1));
        }
    }

    fn no_gyro(&self) -> Error {
        let found: Vec<String> = self
            .others
            .iter()
            .map(|(n, c)| format!("{} ({c} rows)", quote(n)))
            .collect();
        Error::Parse {
            path: self.path.clone(),
            line: self.last_line + 1,
            column: self.names[self.cols[1]].clone(),
            message: format!(
                "no gyro rows (type gyro, gyroscope or 4); the file has {}",
                if found.is_empty() {
                    "no rows".to_string()
                } else {
                    found.join(", ")
                }
            ),
        }
    }
}

/// One row of an image list, s: exposure start of the first line, exposure,
/// and the frame's own rolling-shutter readout when the list has a column
/// for it (`FRAME_READOUT`).
pub type ImageListRow = (f64, f64, Option<f64>);

/// An image list's header: the time, exposure and readout (with its unit,
/// s per unit) columns, and every column's name.
type ImageListHeader = (usize, usize, Option<(usize, f64)>, Vec<String>);

/// The frames of an image list ([`ImageListRow`] per row, in file order).
/// The header is the first non-blank line ([`is_image_list_header`]); each
/// exposure must be > 0, a readout >= 0.
pub fn read_image_list(path: &Path) -> Result<Vec<ImageListRow>> {
    let mut lines = TextLines::open(path)?;
    let mut header: Option<ImageListHeader> = None;
    let mut out = Vec::new();
    while let Some((line, text)) = lines.next_line()? {
        let t = text.trim();
        if t.is_empty() {
            continue;
        }
        let Some((it, ie, ir, names)) = &header else {
            let n = names(t);
            let (Some(it), Some(ie)) = (position(&n, &FRAME_TIME), position(&n, &FRAME_EXPOSURE))
            else {
                return Err(Error::Parse {
                    path: path.into(),
                    line,
                    column: "header".into(),
                    message: format!(
                        "expected an image list with timestamp_ns and exposure_ns columns, found {}",
                        quote(t)
                    ),
                });
            };
            let ir = FRAME_READOUT
                .iter()
                .find_map(|(name, unit)| n.iter().position(|h| h == name).map(|i| (i, *unit)));
            header = Some((it, ie, ir, n));
            continue;
        };
        if t.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = t.split(',').collect();
        let get = |i: usize| -> Result<f64> {
            let s = f.get(i).ok_or_else(|| Error::Parse {
                path: path.into(),
                line,
                column: names[i].clone(),
                message: format!(
                    "the row has {} fields, the header has {}",
                    f.len(),
                    names.len()
                ),
            })?;
            number(path, line, &names[i], s)
        };
        let (ts, te) = (get(*it)?, get(*ie)?);
        if te <= 0.0 {
            return Err(Error::Parse {
                path: path.into(),
                line,
                column: names[*ie].clone(),
                message: format!("the exposure must be > 0 ns, got {te}"),
            });
        }
        let readout = match ir {
            Some((i, unit)) => {
                let r = get(*i)?;
                if r < 0.0 {
                    return Err(Error::Parse {
                        path: path.into(),
                        line,
                        column: names[*i].clone(),
                        message: format!("the readout must be >= 0, got {r}"),
                    });
                }
                Some(r * unit)
            }
            None => None,
        };
        out.push((ts * 1e-9, te * 1e-9, readout));
    }
    if header.is_none() {
        return Err(Error::Parse {
            path: path.into(),
            line: 1,
            column: "header".into(),
            message: "the file is empty: expected a header such as timestamp_ns,exposure_ns".into(),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_names_and_sensor_types() {
        assert_eq!(
            names("#timestamp [ns], Exposure_NS"),
            ["timestamp_ns", "exposure_ns"]
        );
        assert!(imu_columns(&names("timestamp_ns,type,x,y,z")).is_some());
        assert!(imu_columns(&names("t,wx,wy,wz")).is_none());
        assert_eq!(sensor(" 4"), Sensor::Gyro);
        assert_eq!(sensor("android.sensor.gyroscope"), Sensor::Gyro);
        assert_eq!(sensor("TYPE_ACCELEROMETER"), Sensor::Accel);
        assert_eq!(sensor("mag"), Sensor::Other("mag".into()));
    }
}
