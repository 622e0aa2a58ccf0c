//! `mmbm.read_gyro` for a camera's own files (`mmbm::telemetry`): a GoPro
//! MP4, a Gyroflow project, Sensor Logger's or phyphox's CSV, and every log
//! `read_log` reads (with the same samples), plus what the file says
//! (frame rate, readout, sync offsets, lens profile).

use super::{err, interruptible, samples_dict};
use mmbm::io::gyro::{parse_rotation, GyroOptions};
use mmbm::telemetry::{read_camera_file, Format, TelemetryOptions};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The samples of `path` (`{t, omega[, velocity][, depth]}`, camera frame)
/// with the file's metadata: `format`, and where the file has them
/// `readout_s`, `fps`, `offsets` (a list of (video s, offset s)),
/// `lens_profile` (Gyroflow's JSON, as text), `device`, `orientation`.
#[pyfunction]
#[pyo3(signature = (path, time_unit, angle_unit, imu_rotation, time_offset, topic, orientation))]
#[allow(clippy::too_many_arguments)]
pub fn read_camera<'py>(
    py: Python<'py>,
    path: PathBuf,
    time_unit: &str,
    angle_unit: &str,
    imu_rotation: Option<&str>,
    time_offset: f64,
    topic: Option<String>,
    orientation: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = TelemetryOptions {
        gyro: GyroOptions {
            time_unit: time_unit.parse().map_err(err)?,
            angle_unit: angle_unit.parse().map_err(err)?,
            imu_to_camera: match imu_rotation {
                Some(r) => parse_rotation(r).map_err(err)?,
                None => glam::DMat3::IDENTITY,
            },
            time_offset,
            topic,
            gyroflow_rotation: None,
        },
        orientation: orientation.map(str::parse).transpose().map_err(err)?,
    };
    let (log, info) = interruptible(py, err, || read_camera_file(&path, &opts))?;
    let d = samples_dict(py, &log)?;
    let format = match info.format {
        Format::GoProMp4 => "gopro-mp4",
        Format::GyroflowProject => "gyroflow-project",
        Format::App(mmbm::telemetry::apps::App::SensorLogger) => "sensor-logger",
        Format::App(mmbm::telemetry::apps::App::Phyphox) => "phyphox",
        Format::Log => "log",
    };
    d.set_item("format", format)?;
    if let Some(r) = log.readout() {
        d.set_item("readout_s", r.readout_s)?;
        if let Some(dir) = r.direction {
            let name = serde_json::to_value(dir)
                .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
            d.set_item("readout_direction", name.as_str().unwrap_or_default())?;
        }
    }
    if let Some(f) = info.fps {
        d.set_item("fps", f)?;
    }
    if !info.offsets.is_empty() {
        d.set_item("offsets", info.offsets.clone())?;
    }
    if let Some(l) = &info.lens_profile {
        d.set_item("lens_profile", l.to_string())?;
    }
    if let Some(dev) = &info.device {
        d.set_item("device", dev)?;
    }
    if let Some(o) = info.orientation {
        d.set_item("orientation", o.name())?;
    }
    Ok(d)
}
