//! Phone logging apps' gyro CSVs, known by their header row:
//!
//! - **Sensor Logger** (Kelvin Choi; Android and iOS), `Gyroscope.csv`:
//!   `time,seconds_elapsed,z,y,x` (the header telemetry-parser's
//!   `sensor_logger_android.rs` detects): `time` in ns since the epoch,
//!   `seconds_elapsed` s since the recording started, `x, y, z` rad/s in
//!   the device's axes. mmbm's time is `seconds_elapsed` (the recording's
//!   clock; `time` is not read).
//! - **phyphox** (RWTH Aachen), `Gyroscope rotation rate.csv` or the
//!   `Raw Data.csv` of its gyroscope experiments: `"Time (s)","Gyroscope x
//!   (rad/s)","Gyroscope y (rad/s)","Gyroscope z (rad/s)"` and optionally
//!   `"Absolute (rad/s)"` or acceleration columns (not read). phyphox's
//!   export options separate by comma, tab or semicolon; with semicolons
//!   the decimal mark is a comma (its "decimal comma" export).
//!
//! Both apps report the device's axes (Android's and iOS's: x right, y up,
//! z out of the screen, in portrait); `--orientation` names the camera.
//! Lines are read one at a time ([`crate::io::input::TextLines`], each at
//! most `MAX_LINE_BYTES`); errors name the file, the line and the column.

use super::mp4::bad;
use crate::error::{Error, Result};
use crate::io::input::TextLines;
use crate::limits::MAX_TELEMETRY_SAMPLES;
use glam::DVec3;
use std::path::Path;

/// Which app wrote the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum App {
    /// Sensor Logger's `Gyroscope.csv`.
    SensorLogger,
    /// phyphox's gyroscope export.
    Phyphox,
}

impl App {
    /// The app's name.
    pub fn name(self) -> &'static str {
        match self {
            App::SensorLogger => "Sensor Logger",
            App::Phyphox => "phyphox",
        }
    }
}

/// The header's fields (quotes and spaces trimmed) with the separator used.
fn split(line: &str) -> (char, Vec<String>) {
    let sep = if line.contains('\t') {
        '\t'
    } else if line.contains(';') {
        ';'
    } else {
        ','
    };
    let f = line
        .split(sep)
        .map(|s| s.trim().trim_matches('"').trim().to_string())
        .collect();
    (sep, f)
}

/// The app whose header `line` is, and the columns of (t, x, y, z).
fn columns(line: &str) -> Option<(App, [usize; 4])> {
    let (_, f) = split(line.trim_start_matches('\u{feff}'));
    let at = |name: &str| f.iter().position(|c| c.eq_ignore_ascii_case(name));
    if let (Some(t), Some(x), Some(y), Some(z)) = (at("seconds_elapsed"), at("x"), at("y"), at("z"))
    {
        if at("time").is_some() {
            return Some((App::SensorLogger, [t, x, y, z]));
        }
    }
    if let (Some(t), Some(x), Some(y), Some(z)) = (
        at("Time (s)"),
        at("Gyroscope x (rad/s)"),
        at("Gyroscope y (rad/s)"),
        at("Gyroscope z (rad/s)"),
    ) {
        return Some((App::Phyphox, [t, x, y, z]));
    }
    None
}

/// The app that wrote `head` (the file's first line), if one of these.
pub fn detect(head: &str) -> Option<App> {
    columns(head.lines().next().unwrap_or("")).map(|(a, _)| a)
}

/// Reads an app's gyro CSV: (time s, angular velocity rad/s, device axes).
pub fn read(path: &Path) -> Result<(App, Vec<(f64, DVec3)>)> {
    let mut lines = TextLines::open(path)?;
    let Some((_, header)) = lines.next_line()? else {
        return Err(bad(path, "line 1", "empty file"));
    };
    let (app, cols) = columns(&header)
        .ok_or_else(|| bad(path, "line 1", "not a Sensor Logger or phyphox gyro header"))?;
    let (sep, names) = split(header.trim_start_matches('\u{feff}'));
    let comma_decimal = sep == ';';
    let mut out = Vec::new();
    while let Some((line, text)) = lines.next_line()? {
        if text.trim().is_empty() {
            continue;
        }
        if out.len() >= MAX_TELEMETRY_SAMPLES {
            return Err(bad(
                path,
                &format!("line {line}"),
                format!(
                    "more than {MAX_TELEMETRY_SAMPLES} samples (limits::MAX_TELEMETRY_SAMPLES)"
                ),
            ));
        }
        let fields: Vec<&str> = text.split(sep).collect();
        let mut v = [0.0; 4];
        for (k, &c) in cols.iter().enumerate() {
            let column = names[c].clone();
            let raw = fields
                .get(c)
                .map(|s| s.trim().trim_matches('"'))
                .ok_or_else(|| Error::Parse {
                    path: path.into(),
                    line,
                    column: column.clone(),
                    message: format!(
                        "missing: the row has {} fields, the header {}",
                        fields.len(),
                        names.len()
                    ),
                })?;
            let s = if comma_decimal {
                raw.replace(',', ".")
            } else {
                raw.to_string()
            };
            v[k] = s
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| Error::Parse {
                    path: path.into(),
                    line,
                    column,
                    message: format!("'{}' is not a finite number", crate::error::clip(raw, 64)),
                })?;
        }
        out.push((v[0], DVec3::new(v[1], v[2], v[3])));
    }
    if out.is_empty() {
        return Err(bad(path, app.name(), "no samples after the header"));
    }
    Ok((app, out))
}
