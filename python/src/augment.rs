//! `mmbm.augment`: motion blur of a batch of image arrays (N, H, W, C) of
//! uint8, uint16, float32 or float64 along real or simulated motions, in
//! parallel with the GIL released, with the blur maps, the image-to-frame
//! homographies and on request the displacement fields.

use crate::camera::camera;
use crate::err;
use crate::interrupt::interruptible;
use glam::DVec3;
use mmbm::augment::{augment_batch, Augment, AugmentedImage, Image, Motion, PixelBuf, Pixels};
use mmbm::render::{BlurMaps, Quality};
use mmbm::Twist;
use numpy::ndarray::{Array, Array3, Array4, Array5};
use numpy::{Element, IntoPyArray, PyArray4, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The images, the maps, the homographies, the fields, the motions drawn and
/// the warp instants per image.
type Out<'py> = (
    Bound<'py, PyAny>,
    Option<Bound<'py, PyDict>>,
    Bound<'py, PyAny>,
    Option<Bound<'py, PyAny>>,
    Vec<String>,
    Vec<usize>,
);

fn shape_err(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// The motion named by the Python wrapper's arguments.
fn motion(
    motion: &str,
    omega: [f64; 3],
    velocity: [f64; 3],
    gyro: Option<Bound<'_, PyDict>>,
    at: Option<f64>,
) -> PyResult<Motion> {
    Ok(match motion {
        "shake" => Motion::Shake,
        "twist" => Motion::Twist(Twist::new(DVec3::from(omega), DVec3::from(velocity))),
        "log" => {
            let g = gyro.ok_or_else(|| PyValueError::new_err("motion 'log': give gyro"))?;
            let at = at.ok_or_else(|| PyValueError::new_err("motion 'log': give at (s)"))?;
            Motion::Log {
                samples: crate::args::dict_samples(&g)?,
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
    })
}

/// Runs the batch of `images` ((N, H, W, C), C-contiguous) of element `T`.
#[allow(clippy::type_complexity)]
fn run<'py, T: Element + Copy + Send + Sync>(
    py: Python<'py>,
    images: &Bound<'py, PyArray4<T>>,
    wrap: fn(&[T]) -> Pixels<'_>,
    unwrap: fn(PixelBuf) -> Option<Vec<T>>,
    srgb: bool,
    jobs: &[Augment],
) -> PyResult<(Bound<'py, PyAny>, Vec<AugmentedImage>)> {
    let ro = images.readonly();
    let (n, h, w, c) = ro.as_array().dim();
    let all = ro
        .as_slice()
        .map_err(|_| PyValueError::new_err("images: a C-contiguous array expected"))?;
    let per = h * w * c;
    let imgs: Vec<Image> = (0..n)
        .map(|k| Image {
            width: w as u32,
            height: h as u32,
            channels: c as u32,
            pixels: wrap(&all[k * per..(k + 1) * per]),
            srgb,
        })
        .collect();
    let outs = interruptible(py, err, || augment_batch(&imgs, jobs))?;
    let mut flat: Vec<T> = Vec::with_capacity(n * per);
    let mut rest = Vec::with_capacity(n);
    for mut o in outs {
        let px = std::mem::replace(&mut o.pixels, PixelBuf::F32(Vec::new()));
        flat.extend(unwrap(px).ok_or_else(|| PyValueError::new_err("augment: dtype changed"))?);
        rest.push(o);
    }
    let arr = Array4::from_shape_vec((n, h, w, c), flat).map_err(shape_err)?;
    Ok((arr.into_pyarray(py).into_any(), rest))
}

/// Blurs `images` ((N, H, W, C) uint8, uint16, float32 or float64,
/// C-contiguous; C 1, 3 or 4), image `k` with seed `seeds[k]`. `motion`:
/// `shake`, `sim:GAIT`, `twist` (with `omega`, `velocity`) or `log` (with
/// `gyro`, `at`). Returns (images, maps (N, H, W) each or None without
/// `maps`, homographies
/// (N, 3, 3, 3), fields (N, 3, H, W, 2) or None, motions drawn, warp
/// instants per image). `backend`: where the warp integrators run (`bulk`,
/// `auto`, `gpu` or `cpu`; [`Augment::backend`]).
#[pyfunction]
#[pyo3(signature = (images, seeds, motion, omega, velocity, gyro, at, exposure, cam, distance, zoom,
    sharp, quality, background, use_velocity, srgb, integrator, border, blur_px, fields, maps,
    backend="bulk"))]
#[allow(clippy::too_many_arguments)]
pub fn augment<'py>(
    py: Python<'py>,
    images: Bound<'py, PyAny>,
    seeds: Vec<u64>,
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
    quality: &str,
    background: [f32; 3],
    use_velocity: bool,
    srgb: bool,
    integrator: &str,
    border: &str,
    blur_px: Option<f64>,
    fields: bool,
    maps: bool,
    backend: &str,
) -> PyResult<Out<'py>> {
    let mut job = Augment::new(self::motion(motion, omega, velocity, gyro, at)?, exposure);
    job.camera = cam.map(|c| camera(&c)).transpose()?;
    job.distance_m = distance;
    job.zoom = zoom;
    job.sharp = sharp.parse().map_err(err)?;
    job.quality = quality.parse::<Quality>().map_err(err)?;
    job.background = background;
    job.use_velocity = use_velocity;
    job.integrator = integrator.parse().map_err(err)?;
    job.border = border.parse().map_err(err)?;
    job.blur_px = blur_px;
    job.fields = fields;
    job.maps = maps;
    job.backend = backend.parse().map_err(err)?;
    let jobs: Vec<Augment> = seeds
        .iter()
        .map(|&s| Augment {
            seed: s,
            ..job.clone()
        })
        .collect();
    // The shape first: the pixel cap before any value is read.
    let shape = images
        .cast::<numpy::PyUntypedArray>()
        .map_err(|_| PyValueError::new_err("images: a numpy array expected"))?
        .shape()
        .to_vec();
    let [n, h, w, _c] = shape[..] else {
        return Err(PyValueError::new_err(format!(
            "images: (N, H, W, C) expected, got shape {shape:?}"
        )));
    };
    if (h as u64) * (w as u64) > mmbm::limits::AUGMENT_MAX_PIXELS {
        return Err(PyValueError::new_err(format!(
            "image: {w} x {h} px: at most {} px",
            mmbm::limits::AUGMENT_MAX_PIXELS
        )));
    }
    if seeds.len() != n {
        return Err(PyValueError::new_err(format!(
            "seeds: {} for {n} images",
            seeds.len()
        )));
    }
    let (img, outs) = if let Ok(a) = images.cast::<PyArray4<u8>>() {
        run(
            py,
            a,
            |s| Pixels::U8(s),
            |b| match b {
                PixelBuf::U8(v) => Some(v),
                _ => None,
            },
            srgb,
            &jobs,
        )?
    } else if let Ok(a) = images.cast::<PyArray4<u16>>() {
        run(
            py,
            a,
            |s| Pixels::U16(s),
            |b| match b {
                PixelBuf::U16(v) => Some(v),
                _ => None,
            },
            srgb,
            &jobs,
        )?
    } else if let Ok(a) = images.cast::<PyArray4<f32>>() {
        run(
            py,
            a,
            |s| Pixels::F32(s),
            |b| match b {
                PixelBuf::F32(v) => Some(v),
                _ => None,
            },
            srgb,
            &jobs,
        )?
    } else if let Ok(a) = images.cast::<PyArray4<f64>>() {
        run(
            py,
            a,
            |s| Pixels::F64(s),
            |b| match b {
                PixelBuf::F64(v) => Some(v),
                _ => None,
            },
            srgb,
            &jobs,
        )?
    } else {
        return Err(PyValueError::new_err(
            "images: uint8, uint16, float32 or float64 expected",
        ));
    };
    let maps = if maps {
        let d = PyDict::new(py);
        for (k, get) in [
            (
                "path_px",
                (|m: &BlurMaps| &m.path_px) as fn(&BlurMaps) -> &Vec<f32>,
            ),
            ("disp_px", |m| &m.disp_px),
            ("speed_px_s", |m| &m.speed_px_s),
        ] {
            let v: Vec<f32> = outs
                .iter()
                .flat_map(|o| o.maps.iter().flat_map(|m| get(m).iter().copied()))
                .collect();
            let a = Array3::from_shape_vec((n, h, w), v).map_err(shape_err)?;
            d.set_item(k, a.into_pyarray(py))?;
        }
        Some(d)
    } else {
        None
    };
    let hs: Vec<f64> = outs
        .iter()
        .flat_map(|o| o.homographies.iter().flatten().copied())
        .collect();
    let hs = Array::from_shape_vec((n, 3, 3, 3), hs).map_err(shape_err)?;
    let fields = if fields {
        let v: Vec<f32> = outs
            .iter()
            .flat_map(|o| o.fields.iter().flatten().copied())
            .collect();
        let a = Array5::from_shape_vec((n, 3, h, w, 2), v).map_err(shape_err)?;
        Some(a.into_pyarray(py).into_any())
    } else {
        None
    };
    Ok((
        img,
        maps,
        hs.into_pyarray(py).into_any(),
        fields,
        outs.iter().map(|o| o.motion.clone()).collect(),
        outs.iter().map(|o| o.samples).collect(),
    ))
}
