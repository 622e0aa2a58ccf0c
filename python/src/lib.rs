//! `mmbm._mmbm`: the native half of the Python package. Thin: every function
//! takes contiguous float64 NumPy arrays whose shapes the Python half
//! (`mmbm/__init__.py`) has already checked and broadcast, calls the mmbm
//! library with the GIL released, and returns NumPy arrays. Library errors
//! become `OSError` (files) or `ValueError` (everything else). The
//! arguments every function shares (camera, plane, log, frame table,
//! method) are turned into the library's types in one place, `args.rs`; the
//! jobs are the library's (`series::job::FramesJob`, `RenderJob::for_motion`).

mod args;
mod augment;
mod camera;
mod dataset;
mod select;
mod telemetry;

use camera::{camera, camera_json};
use glam::DVec3;
use mmbm::camera::Camera;
use mmbm::io::gyro::{parse_rotation, GyroOptions, GyroSample};
use mmbm::metric::AnyMethod;
use mmbm::model::log::ImuLog;
use mmbm::model::motion::Twist;
use mmbm::render::{Integrator, Quality, RenderJob, Target};
use mmbm::trigger::CameraTiming;
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

mod interrupt;
use interrupt::interruptible;

fn err(e: mmbm::Error) -> PyErr {
    match e {
        mmbm::Error::Io { .. } => PyOSError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// Reads a camera file (TOML or JSON): its every key, as JSON (the fields
/// of the Python `Camera`).
#[pyfunction]
fn camera_from_file(path: PathBuf) -> PyResult<String> {
    camera_json(&Camera::load(&path).map_err(err)?)
}

/// The thesis camera's every key, as JSON.
#[pyfunction]
fn camera_thesis() -> PyResult<String> {
    camera_json(&Camera::thesis())
}

/// Validates a camera dict.
#[pyfunction]
fn camera_check(cam: Bound<'_, PyDict>) -> PyResult<()> {
    camera(&cam).map(|_| ())
}

/// MMBM (mm/s) of each row of `omega` with the matching row of `velocity`.
#[pyfunction]
#[pyo3(signature = (cam, omega, velocity, plane_, method))]
fn metric<'py>(
    py: Python<'py>,
    cam: Bound<'py, PyDict>,
    omega: PyReadonlyArray2<'py, f64>,
    velocity: PyReadonlyArray2<'py, f64>,
    plane_: Option<PyReadonlyArray1<'py, f64>>,
    method: &str,
) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
    let scene = args::scene(&cam, plane_)?;
    let method: AnyMethod = method.parse().map_err(err)?;
    let (w, v) = (args::rows3(&omega)?, args::rows3(&velocity)?);
    let long = w.len() > interrupt::SMALL_ROWS || matches!(method, AnyMethod::Gpu { .. });
    let out = interrupt::interruptible_if(py, err, long, || {
        w.iter()
            .zip(&v)
            .map(|(w, v)| {
                mmbm::cancel::check()?;
                let tw = Twist::new(*w, *v);
                match method {
                    AnyMethod::Cpu(m) => mmbm::mmbm(&scene, &tw, m),
                    AnyMethod::Gpu { width, height } => scene
                        .validate_for(&tw)
                        .and_then(|_| mmbm::field::mmbm_gpu(&scene, &tw, width, height)),
                }
                .map(|m| m.mm_s)
            })
            .collect::<mmbm::Result<Vec<f64>>>()
    })?;
    Ok(Array1::from(out).into_pyarray(py))
}

/// Exposure MMBM (mm/s, each line over its own rolling-shutter window) and
/// the MMBM at the start of every video frame, and the blur in px
/// (`FrameMmbm::blur_px`); NaN where a frame's window leaves the log.
/// Returns `(exposure_mm_s, blur_px, start_mm_s)`.
#[pyfunction]
#[pyo3(signature = (cam, t, omega, t_start, exposure_s, readout_s, method))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn frames<'py>(
    py: Python<'py>,
    cam: Bound<'py, PyDict>,
    t: PyReadonlyArray1<'py, f64>,
    omega: PyReadonlyArray2<'py, f64>,
    t_start: PyReadonlyArray1<'py, f64>,
    exposure_s: PyReadonlyArray1<'py, f64>,
    readout_s: Option<PyReadonlyArray1<'py, f64>>,
    method: &str,
) -> PyResult<(
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<f64>>,
)> {
    let samples = args::samples(&t, &omega, None, None)?;
    let video = args::video_frames(&t_start, &exposure_s, readout_s.as_ref())?;
    let job = args::frames_job(&cam, Some(method))?;
    let (rows, _) = interruptible(py, err, || job.mmbm(&samples, &video))?;
    let e: Vec<f64> = rows
        .iter()
        .map(|r| r.exposure_mm_s.unwrap_or(f64::NAN))
        .collect();
    let blur: Vec<f64> = rows
        .iter()
        .map(|r| r.blur_px().unwrap_or(f64::NAN))
        .collect();
    let s0: Vec<f64> = rows
        .iter()
        .map(|r| r.start_mm_s.unwrap_or(f64::NAN))
        .collect();
    Ok((
        Array1::from(e).into_pyarray(py),
        Array1::from(blur).into_pyarray(py),
        Array1::from(s0).into_pyarray(py),
    ))
}

/// The per-pixel blur fields of every video frame (`mmbm frames --maps`,
/// `series::maps`): per frame a `(5, height, width)` float32 array of the
/// channels `disp.u, disp.v, path_px, flow.u, flow.v` (px, px/s; NaN beyond
/// the lens's radial limit), or `None` where the frame's span leaves the log
/// or crosses a gap in it. Rotation only.
#[pyfunction]
#[pyo3(signature = (cam, t, omega, t_start, exposure_s, readout_s))]
#[allow(clippy::type_complexity)]
fn frame_maps<'py>(
    py: Python<'py>,
    cam: Bound<'py, PyDict>,
    t: PyReadonlyArray1<'py, f64>,
    omega: PyReadonlyArray2<'py, f64>,
    t_start: PyReadonlyArray1<'py, f64>,
    exposure_s: PyReadonlyArray1<'py, f64>,
    readout_s: Option<PyReadonlyArray1<'py, f64>>,
) -> PyResult<Vec<Option<Bound<'py, numpy::PyArray3<f32>>>>> {
    let samples = args::samples(&t, &omega, None, None)?;
    let video = args::video_frames(&t_start, &exposure_s, readout_s.as_ref())?;
    let job = args::frames_job(&cam, None)?;
    let maps = interruptible(py, err, || job.maps(&ImuLog::new(samples)?, &video, None))?;
    let (w, h) = (job.camera().width as usize, job.camera().height as usize);
    maps.into_iter()
        .map(|m| {
            m.map(|m| {
                let data: Vec<f32> = m
                    .channels()
                    .iter()
                    .flat_map(|c| c.1.iter().copied())
                    .collect();
                Array3::from_shape_vec((5, h, w), data)
                    .map(|a| a.into_pyarray(py))
                    .map_err(|e| PyValueError::new_err(e.to_string()))
            })
            .transpose()
        })
        .collect()
}

/// MMBM (mm/s) of a log: samples `t`, `omega`, optional `velocity` and `depth`.
#[pyfunction]
#[pyo3(signature = (cam, t, omega, velocity, depth, plane_, method))]
#[allow(clippy::too_many_arguments)]
fn series<'py>(
    py: Python<'py>,
    cam: Bound<'py, PyDict>,
    t: PyReadonlyArray1<'py, f64>,
    omega: PyReadonlyArray2<'py, f64>,
    velocity: Option<PyReadonlyArray2<'py, f64>>,
    depth: Option<PyReadonlyArray1<'py, f64>>,
    plane_: Option<PyReadonlyArray1<'py, f64>>,
    method: &str,
) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
    let samples = args::samples(&t, &omega, velocity.as_ref(), depth.as_ref())?;
    let opts = mmbm::series::SeriesOptions {
        scene: args::scene(&cam, plane_)?,
        method: args::method(method)?,
        use_velocity: velocity.is_some(),
    };
    let out = interruptible(py, err, || mmbm::series::mmbm_series_with(&samples, &opts))?;
    Ok(Array1::from(out).into_pyarray(py))
}

/// Reads a gyro log (CSV or MCAP): `{t, omega[, velocity][, depth]}`.
#[pyfunction]
#[pyo3(signature = (path, time_unit, angle_unit, imu_rotation, time_offset, topic))]
fn read_gyro<'py>(
    py: Python<'py>,
    path: PathBuf,
    time_unit: &str,
    angle_unit: &str,
    imu_rotation: Option<&str>,
    time_offset: f64,
    topic: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = GyroOptions {
        time_unit: time_unit.parse().map_err(err)?,
        angle_unit: angle_unit.parse().map_err(err)?,
        imu_to_camera: match imu_rotation {
            Some(r) => parse_rotation(r).map_err(err)?,
            None => glam::DMat3::IDENTITY,
        },
        time_offset,
        topic,
        gyroflow_rotation: None,
    };
    let log = interruptible(py, err, || mmbm::io::gyro::read_log(&path, opts))?;
    let d = samples_dict(py, &log)?;
    // The file's own rolling-shutter readout (a Gyroflow .gcsv header's).
    if let Some(r) = log.readout() {
        d.set_item("readout_s", r.readout_s)?;
        if let Some(dir) = r.direction {
            // The camera files' name of the direction, e.g. "top-to-bottom".
            let name =
                serde_json::to_value(dir).map_err(|e| PyValueError::new_err(e.to_string()))?;
            d.set_item("readout_direction", name.as_str().unwrap_or_default())?;
        }
    }
    Ok(d)
}

fn samples_dict<'py>(py: Python<'py>, s: &[GyroSample]) -> PyResult<Bound<'py, PyDict>> {
    let n = s.len();
    let d = PyDict::new(py);
    d.set_item(
        "t",
        Array1::from_iter(s.iter().map(|x| x.t)).into_pyarray(py),
    )?;
    let vec3 =
        |f: &dyn Fn(&GyroSample) -> DVec3| Array2::from_shape_fn((n, 3), |(i, j)| f(&s[i])[j]);
    d.set_item("omega", vec3(&|x| x.omega).into_pyarray(py))?;
    if n > 0 && s.iter().all(|x| x.velocity.is_some()) {
        d.set_item(
            "velocity",
            vec3(&|x| x.velocity.unwrap_or_default()).into_pyarray(py),
        )?;
    }
    if n > 0 && s.iter().all(|x| x.depth.is_some()) {
        let v = Array1::from_iter(s.iter().map(|x| x.depth.unwrap_or(f64::NAN)));
        d.set_item("depth", v.into_pyarray(py))?;
    }
    Ok(d)
}

/// The flow field (px/s) at every pixel centre: `(H, W, 2)` float32.
#[pyfunction]
#[pyo3(signature = (cam, omega, velocity, plane_, backend_))]
fn flow_field<'py>(
    py: Python<'py>,
    cam: Bound<'py, PyDict>,
    omega: [f64; 3],
    velocity: [f64; 3],
    plane_: Option<PyReadonlyArray1<'py, f64>>,
    backend_: &str,
) -> PyResult<Bound<'py, numpy::PyArray3<f32>>> {
    let scene = args::scene(&cam, plane_)?;
    let tw = Twist::new(DVec3::from(omega), DVec3::from(velocity));
    let b = args::backend(backend_)?;
    let f = interruptible(py, err, || mmbm::field::flow_field(&scene, &tw, 0, 0, b))?;
    let (w, h) = (f.width as usize, f.height as usize);
    let a = Array3::from_shape_fn((h, w, 2), |(y, x, c)| {
        if c == 0 {
            f.u[y * w + x]
        } else {
            f.v[y * w + x]
        }
    });
    Ok(a.into_pyarray(py))
}

/// Renders a frame: `(image (H, W, 3) float32 linear, maps dict or None)`.
#[pyfunction]
#[pyo3(signature = (cam, target, distance, tilt, offset, background, exposure, omega, velocity,
    gyro, at, use_velocity, quality, integrator, backend_, seed, maps, sharp))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    cam: Bound<'py, PyDict>,
    target: &str,
    distance: f64,
    tilt: [f64; 2],
    offset: [f64; 2],
    background: Option<[f64; 3]>,
    exposure: f64,
    omega: Option<[f64; 3]>,
    velocity: [f64; 3],
    gyro: Option<Bound<'py, PyDict>>,
    at: Option<f64>,
    use_velocity: bool,
    quality: &str,
    integrator: &str,
    backend_: &str,
    seed: u32,
    maps: bool,
    sharp: bool,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let camera = camera(&cam)?;
    let mut t = Target::parse(target, distance).map_err(err)?;
    t.tilt_deg = tilt;
    t.offset = offset;
    if let Some(b) = background {
        t.background = [b[0] as f32, b[1] as f32, b[2] as f32];
    }
    let log = args::render_log(omega, gyro.as_ref())?;
    let motion = args::motion(omega, velocity, log.as_ref(), at, use_velocity)?;
    // The motion spans the camera's busy time (readout plus exposure), as in
    // `mmbm render`.
    let mut job = RenderJob::for_motion(camera, exposure, motion, t).map_err(err)?;
    job.quality = quality.parse::<Quality>().map_err(err)?;
    job.backend = args::backend(backend_)?;
    job.seed = seed;
    job.integrator = integrator.parse::<Integrator>().map_err(err)?;
    job.with_maps = maps;
    let out = interruptible(py, err, || {
        if sharp {
            mmbm::render::render_sharp(&job)
        } else {
            mmbm::render::render_frame(&job)
        }
    })?;
    let (w, h) = (out.width as usize, out.height as usize);
    let img = Array3::from_shape_vec((h, w, 3), out.rgb)
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .into_pyarray(py)
        .into_any();
    let m = match out.maps {
        Some(m) => {
            let d = PyDict::new(py);
            for (k, v) in [
                ("path_px", m.path_px),
                ("disp_px", m.disp_px),
                ("speed_px_s", m.speed_px_s),
            ] {
                let a = Array2::from_shape_vec((h, w), v)
                    .map_err(|e| PyValueError::new_err(e.to_string()))?;
                d.set_item(k, a.into_pyarray(py))?;
            }
            d.into_any()
        }
        None => py.None().into_bound(py),
    };
    Ok((img, m))
}

/// A simulated gait log: `{t, omega, velocity}`.
#[pyfunction]
#[pyo3(signature = (gait, duration, rate, seed, config))]
fn simulate<'py>(
    py: Python<'py>,
    gait: &str,
    duration: f64,
    rate: f64,
    seed: u64,
    config: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let g: mmbm::sim::Gait = gait.parse().map_err(err)?;
    let cfg = match config {
        Some(p) => mmbm::sim::GaitConfig::load(&p, g).map_err(err)?,
        None => mmbm::sim::GaitConfig::preset(g),
    };
    let s = interruptible(py, err, || mmbm::sim::simulate(&cfg, duration, rate, seed))?;
    samples_dict(py, &s)
}

/// Runs policies on an MMBM series: a list of frame dicts.
#[pyfunction]
#[pyo3(signature = (t, mmbm_mm_s, policies, exposure, delay, readout, min_interval, pitch_mm))]
#[allow(clippy::too_many_arguments)]
fn trigger<'py>(
    py: Python<'py>,
    t: PyReadonlyArray1<'py, f64>,
    mmbm_mm_s: PyReadonlyArray1<'py, f64>,
    policies: Vec<String>,
    exposure: f64,
    delay: f64,
    readout: f64,
    min_interval: f64,
    pitch_mm: f64,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let t = t.as_slice()?.to_vec();
    let m = mmbm_mm_s.as_slice()?.to_vec();
    let timing = CameraTiming {
        delay,
        exposure,
        readout,
        min_interval,
        pitch_mm,
    };
    let frames = interruptible(py, err, || {
        let specs = policies
            .iter()
            .map(|p| mmbm::trigger::PolicySpec::parse(p))
            .collect::<mmbm::Result<Vec<_>>>()?;
        // The runner uses only the times: no samples are made up.
        mmbm::trigger::Policies::new(specs, timing)?.run(&t, &m)
    })?
    .concat();
    frames
        .iter()
        .map(|f| {
            let d = PyDict::new(py);
            d.set_item("policy", f.policy.as_str())?;
            d.set_item("index", f.index)?;
            d.set_item("trigger_t", f.trigger_t)?;
            d.set_item("exposure_start", f.exposure_start)?;
            d.set_item("exposure_end", f.exposure_end)?;
            d.set_item("mmbm_trigger_mm_s", f.mmbm_trigger_mm_s)?;
            d.set_item("mmbm_exposure_mm_s", f.mmbm_exposure_mm_s)?;
            d.set_item("kept", f.kept)?;
            d.set_item("gain", f.gain)?;
            Ok(d)
        })
        .collect()
}

/// Reads a float EXR, from a path or from its bytes: `{channel: (H, W) float32}`.
#[pyfunction]
fn read_exr<'py>(py: Python<'py>, src: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
    let (w, h, chans) = if let Ok(b) = src.cast::<pyo3::types::PyBytes>() {
        let bytes = b.as_bytes().to_vec();
        interruptible(py, err, move || {
            mmbm::io::images::read_exr_bytes(&bytes, "<EXR bytes>")
        })?
    } else {
        let path: PathBuf = src.extract()?;
        interruptible(py, err, || mmbm::io::images::read_exr(&path))?
    };
    let d = PyDict::new(py);
    for (name, v) in chans {
        let a =
            Array2::from_shape_vec((h, w), v).map_err(|e| PyValueError::new_err(e.to_string()))?;
        d.set_item(name, a.into_pyarray(py))?;
    }
    Ok(d)
}

/// The native module.
#[pymodule]
fn _mmbm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The library's warnings (gaps in a log, the CPU twin standing in) on stderr.
    mmbm::diagnostics::log_to_stderr();
    // NumPy's C API now, not at the first array a call returns: imported
    // lazily, after a long call during which a Ctrl-C came, the import ran
    // the pending handler, failed with KeyboardInterrupt, and the numpy
    // crate turned that into a panic (a PanicException about the capsule).
    m.py().import("numpy")?;
    numpy::PyArray1::<f64>::zeros(m.py(), 0, false);
    m.add_function(wrap_pyfunction!(camera_from_file, m)?)?;
    m.add_function(wrap_pyfunction!(camera_thesis, m)?)?;
    m.add_function(wrap_pyfunction!(camera_check, m)?)?;
    m.add_function(wrap_pyfunction!(metric, m)?)?;
    m.add_function(wrap_pyfunction!(series, m)?)?;
    m.add_function(wrap_pyfunction!(frames, m)?)?;
    m.add_function(wrap_pyfunction!(frame_maps, m)?)?;
    m.add_function(wrap_pyfunction!(read_gyro, m)?)?;
    m.add_function(wrap_pyfunction!(flow_field, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(trigger, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(select::choose_frames, m)?)?;
    m.add_function(wrap_pyfunction!(telemetry::read_camera, m)?)?;
    m.add_class::<dataset::DatasetMaker>()?;
    m.add_function(wrap_pyfunction!(augment::augment, m)?)?;
    // The camera timing's defaults, from their one place in the library.
    m.add("AUGMENT_MAX_PIXELS", mmbm::limits::AUGMENT_MAX_PIXELS)?;
    m.add("DEFAULT_DELAY_S", CameraTiming::DEFAULT_DELAY_S)?;
    m.add("DEFAULT_EXPOSURE_S", CameraTiming::DEFAULT_EXPOSURE_S)?;
    m.add("DEFAULT_READOUT_S", CameraTiming::DEFAULT_READOUT_S)?;
    m.add(
        "DEFAULT_MIN_INTERVAL_S",
        CameraTiming::DEFAULT_MIN_INTERVAL_S,
    )?;
    m.add("DEFAULT_PITCH_MM", CameraTiming::DEFAULT_PITCH_MM)?;
    Ok(())
}
