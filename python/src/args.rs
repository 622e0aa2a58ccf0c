//! The arguments the pyfunctions share, turned into the library's types in
//! one place: the camera (a dict of the camera file's keys, [`camera`]), the
//! scene plane, a gyro log from arrays or from a `{t, omega[, velocity]}`
//! dict, a video's frame table, the metric method and the frames job
//! ([`mmbm::series::job::FramesJob`]) and render motion
//! ([`mmbm::render::FrameMotion`]) the library assembles from them. The
//! checks (shapes, lengths) and their messages are the ones the bindings
//! always gave.

use crate::camera::camera;
use crate::err;
use glam::DVec3;
use mmbm::gpu::Backend;
use mmbm::io::frames::VideoFrame;
use mmbm::io::gyro::GyroSample;
use mmbm::metric::{Method, Scene};
use mmbm::model::log::ImuLog;
use mmbm::model::motion::{Plane, Twist};
use mmbm::render::FrameMotion;
use mmbm::series::job::{FramesConfig, FramesJob};
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The scene plane `(nx, ny, nz, d)` (unit normal, m), if given.
pub fn plane(p: Option<PyReadonlyArray1<f64>>) -> PyResult<Option<Plane>> {
    let Some(p) = p else { return Ok(None) };
    let v = p.as_slice()?;
    if v.len() != 4 {
        return Err(PyValueError::new_err("plane: expected (nx, ny, nz, d)"));
    }
    Ok(Some(Plane {
        normal: DVec3::new(v[0], v[1], v[2]),
        d: v[3],
    }))
}

/// The rows of an `(N, 3)` array as vectors.
pub fn rows3(a: &PyReadonlyArray2<f64>) -> PyResult<Vec<DVec3>> {
    let v = a.as_array();
    if v.ncols() != 3 {
        return Err(PyValueError::new_err("expected an (N, 3) array"));
    }
    Ok(v.rows()
        .into_iter()
        .map(|r| DVec3::new(r[0], r[1], r[2]))
        .collect())
}

/// A camera and a scene plane: the scene.
pub fn scene(cam: &Bound<'_, PyDict>, plane_: Option<PyReadonlyArray1<f64>>) -> PyResult<Scene> {
    Ok(Scene {
        camera: camera(cam)?,
        plane: plane(plane_)?,
    })
}

/// A CPU metric method's name (`riemann:8x6`, ...).
pub fn method(m: &str) -> PyResult<Method> {
    m.parse().map_err(err)
}

/// A backend's name (`cpu`, `gpu`, `auto`, `bulk`).
pub fn backend(b: &str) -> PyResult<Backend> {
    b.parse::<Backend>().map_err(err)
}

/// Gyro samples from a log's arrays (the Python side checked the lengths).
pub fn log_samples(
    t: &[f64],
    w: &[DVec3],
    v: Option<&[DVec3]>,
    d: Option<&[f64]>,
) -> Vec<GyroSample> {
    t.iter()
        .enumerate()
        .map(|(k, &t)| GyroSample {
            t,
            omega: w[k],
            velocity: v.map(|v| v[k]),
            depth: d.map(|d| d[k]),
        })
        .collect()
}

/// Gyro samples from the NumPy arrays `t`, `omega` and the optional
/// `velocity` (N, 3) and `depth`.
pub fn samples(
    t: &PyReadonlyArray1<f64>,
    omega: &PyReadonlyArray2<f64>,
    velocity: Option<&PyReadonlyArray2<f64>>,
    depth: Option<&PyReadonlyArray1<f64>>,
) -> PyResult<Vec<GyroSample>> {
    let w = rows3(omega)?;
    let v = velocity.map(rows3).transpose()?;
    let d = depth.map(|d| d.as_slice()).transpose()?;
    Ok(log_samples(t.as_slice()?, &w, v.as_deref(), d))
}

/// Samples from a `{t, omega[, velocity][, depth]}` dict of arrays.
pub fn dict_samples(g: &Bound<'_, PyDict>) -> PyResult<Vec<GyroSample>> {
    let get = |k: &str| g.get_item(k);
    let t: Vec<f64> = get("t")?
        .ok_or_else(|| PyValueError::new_err("gyro: missing 't'"))?
        .extract()?;
    let w: Vec<[f64; 3]> = get("omega")?
        .ok_or_else(|| PyValueError::new_err("gyro: missing 'omega'"))?
        .extract()?;
    let v: Option<Vec<[f64; 3]>> = get("velocity")?.map(|x| x.extract()).transpose()?;
    if w.len() != t.len() || v.as_ref().is_some_and(|v| v.len() != t.len()) {
        return Err(PyValueError::new_err("gyro: arrays of different lengths"));
    }
    let w: Vec<DVec3> = w.into_iter().map(DVec3::from).collect();
    let v: Option<Vec<DVec3>> = v.map(|v| v.into_iter().map(DVec3::from).collect());
    Ok(log_samples(&t, &w, v.as_deref(), None))
}

/// A video's frame table from its columns (broadcast to one length by the
/// Python half): `t_start`, `exposure_s` and the optional `readout_s`.
pub fn video_frames(
    t_start: &PyReadonlyArray1<f64>,
    exposure_s: &PyReadonlyArray1<f64>,
    readout_s: Option<&PyReadonlyArray1<f64>>,
) -> PyResult<Vec<VideoFrame>> {
    let (ts, es) = (t_start.as_slice()?, exposure_s.as_slice()?);
    let rs = readout_s.map(|r| r.as_slice()).transpose()?;
    Ok((0..ts.len())
        .map(|k| VideoFrame {
            t_start: ts[k],
            exposure_s: es[k],
            readout_s: rs.map(|r| r[k]),
        })
        .collect())
}

/// The frames job of `cam` with the method named `m` (`None`: the maps,
/// which use no method): rotation only, no scene plane (the logs from
/// arrays carry no readout of their own).
pub fn frames_job(cam: &Bound<'_, PyDict>, m: Option<&str>) -> PyResult<FramesJob> {
    let camera = camera(cam)?;
    let cfg = FramesConfig {
        camera,
        plane: None,
        method: m.map_or(Ok(Method::Riemann { nu: 8, nv: 6 }), method)?,
        use_velocity: false,
    };
    FramesJob::new(cfg, None).map_err(err)
}

/// The camera's motion over a rendered frame: a constant twist (`omega`,
/// with `velocity`) or a window of `log` from `at` s on.
pub fn motion<'a>(
    omega: Option<[f64; 3]>,
    velocity: [f64; 3],
    log: Option<&'a ImuLog>,
    at: Option<f64>,
    use_velocity: bool,
) -> PyResult<FrameMotion<'a>> {
    match (omega, log) {
        (Some(w), None) => Ok(FrameMotion::Twist(Twist::new(
            DVec3::from(w),
            DVec3::from(velocity),
        ))),
        (None, Some(log)) => Ok(FrameMotion::Log {
            log,
            at_s: at.ok_or_else(|| PyValueError::new_err("at: required with gyro"))?,
            use_velocity,
        }),
        _ => Err(PyValueError::new_err(
            "motion: give either omega or gyro (with at)",
        )),
    }
}

/// The log of a render's `gyro` dict, when the motion is a log's (`omega`
/// not given).
pub fn render_log(
    omega: Option<[f64; 3]>,
    gyro: Option<&Bound<'_, PyDict>>,
) -> PyResult<Option<ImuLog>> {
    match (omega, gyro) {
        (None, Some(g)) => Ok(Some(ImuLog::new(dict_samples(g)?).map_err(err)?)),
        _ => Ok(None),
    }
}
