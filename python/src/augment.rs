//! `mmbm.augment`: motion blur of an image array along a real or simulated
//! motion, with the blur maps and the image-to-frame homographies.

use crate::camera::camera;
use crate::err;
use crate::interrupt::interruptible;
use glam::DVec3;
use mmbm::augment::{augment as run, Augment, Motion};
use mmbm::render::Quality;
use mmbm::Twist;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The image, the maps, the homographies and the motion drawn.
type Out<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyDict>,
    Bound<'py, PyAny>,
    String,
);

/// Blurs `image` ((H, W, 3) float32, linear). `motion`: `shake`,
/// `sim:GAIT`, `twist` (with `omega`, `velocity`) or `log` (with `gyro`,
/// `at`). Returns (image, maps, homographies (3, 3, 3), motion drawn).
#[pyfunction]
#[pyo3(signature = (image, motion, omega, velocity, gyro, at, exposure, cam, distance, zoom, sharp,
    seed, quality, background, use_velocity))]
#[allow(clippy::too_many_arguments)]
pub fn augment<'py>(
    py: Python<'py>,
    image: PyReadonlyArray3<'py, f32>,
    motion: &str,
    omega: [f64; 3],
    velocity: [f64; 3],
    gyro: Option<Bound<'py, PyDict>>,
    at: Option<f64>,
    exposure: f64,
    cam: Option<Bound<'py, PyDict>>,
    distance: f64,
    zoom: f64,
    sharp: &str,
    seed: u64,
    quality: &str,
    background: [f32; 3],
    use_velocity: bool,
) -> PyResult<Out<'py>> {
    let a = image.as_array();
    let (h, w, c) = a.dim();
    if c != 3 {
        return Err(PyValueError::new_err(format!(
            "image: (H, W, 3) expected, got (H, W, {c})"
        )));
    }
    let rgb: Vec<f32> = a.iter().copied().collect();
    let m = match motion {
        "shake" => Motion::Shake,
        "twist" => Motion::Twist(Twist::new(DVec3::from(omega), DVec3::from(velocity))),
        "log" => {
            let g = gyro.ok_or_else(|| PyValueError::new_err("motion 'log': give gyro"))?;
            let at = at.ok_or_else(|| PyValueError::new_err("motion 'log': give at (s)"))?;
            Motion::Log {
                samples: crate::dict_samples(&g)?,
                at,
            }
        }
        s => match s.strip_prefix("sim:") {
            Some(g) => Motion::Gait(g.parse().map_err(err)?),
            None => {
                return Err(PyValueError::new_err(format!(
                "motion '{s}': expected 'shake', 'sim:slow|moderate|fast', a twist or a gyro log"
            )))
            }
        },
    };
    let mut job = Augment::new(m, exposure);
    job.camera = cam.map(|c| camera(&c)).transpose()?;
    job.distance_m = distance;
    job.zoom = zoom;
    job.sharp = sharp.parse().map_err(err)?;
    job.seed = seed;
    job.quality = quality.parse::<Quality>().map_err(err)?;
    job.background = background;
    job.use_velocity = use_velocity;
    let (w32, h32) = (w as u32, h as u32);
    let out = interruptible(py, err, || run(w32, h32, &rgb, &job))?;
    let img = Array3::from_shape_vec((h, w, 3), out.rgb)
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .into_pyarray(py)
        .into_any();
    let maps = PyDict::new(py);
    for (k, v) in [
        ("path_px", out.maps.path_px),
        ("disp_px", out.maps.disp_px),
        ("speed_px_s", out.maps.speed_px_s),
    ] {
        let a =
            Array2::from_shape_vec((h, w), v).map_err(|e| PyValueError::new_err(e.to_string()))?;
        maps.set_item(k, a.into_pyarray(py))?;
    }
    let hs: Vec<f64> = out.homographies.iter().flatten().copied().collect();
    let hs = Array3::from_shape_vec((3, 3, 3), hs)
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .into_pyarray(py)
        .into_any();
    Ok((img, maps, hs, out.motion))
}
