//! Gyroflow lens profiles (JSON with `fisheye_params`), read as Gyroflow's
//! `lens_profile.rs` reads them, for a video of a given size and a zoom
//! lens's focal length ([`Choice`]):
//!
//! 1. `compatible_settings`: the profile's entries for other video sizes
//!    (each a copy with its `width`, `height` and keys over the profile's;
//!    the camera matrix scaled when the aspect ratio stays, else a sensor
//!    crop with the matrix kept). With a video size, the first of the
//!    profile and its entries of that size is used, else the first of that
//!    aspect ratio (Gyroflow also matches the frame rate and the camera's
//!    identifier, which mmbm does not know), else the profile.
//! 2. A digital lens widens a 4:3 (`gopro_superview`, `gopro6_superview`)
//!    or 8:7 (`gopro_hyperview`) calibration by its factor, as Gyroflow's
//!    `adjust_lens_profile`.
//! 3. `interpolations` (zoom lenses: profiles keyed by focal length, mm):
//!    with a focal length, the entry of that focal length, else the linear
//!    interpolation of fx, fy, cx, cy, the coefficients, `crop` and
//!    `focal_length` between its neighbours (extrapolated beyond the ends);
//!    without one, the profile itself (Gyroflow without lens metadata).
//! 4. `radial_distortion_limit`: Gyroflow recomputes it from the
//!    coefficients whenever there are any (so do `Distortion::radial_limit`
//!    and the masking); a limit given without coefficients is refused.

use super::digital::{Lens, Warp};
use super::distortion::Distortion;
pub use super::gyroflow_choice::{select, Choice};
use super::intrinsics::Camera;
use super::models::Model;
use super::shutter::{Readout, Shutter};
use crate::error::{Error, Result};
use serde_json::Value;

/// Pixel pitch (mm) assumed for a Gyroflow profile without a focal length in mm.
pub const NOMINAL_PITCH_MM: f64 = 0.001;

fn num(v: &Value, key: &str) -> Result<f64> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| Error::invalid(key, format!("expected a finite number, got {v}")))
}

/// A camera from a parsed Gyroflow lens profile.
pub fn from_gyroflow(p: &Value, choice: &Choice) -> Result<Camera> {
    let p = &select(p, choice)?;
    let dims = p.get("calib_dimension").ok_or_else(|| {
        Error::invalid(
            "calib_dimension",
            "missing (expected {\"w\": .., \"h\": ..})",
        )
    })?;
    let dim = |k: &str| -> Result<u32> {
        let key = format!("calib_dimension.{k}");
        let v = dims.get(k).ok_or_else(|| Error::invalid(&key, "missing"))?;
        v.as_u64()
            .filter(|&n| n > 0 && n <= u32::MAX as u64)
            .map(|n| n as u32)
            .ok_or_else(|| Error::invalid(&key, format!("expected a positive integer, got {v}")))
    };
    let (w, h) = (dim("w")?, dim("h")?);
    let fp = &p["fisheye_params"];
    let m = fp
        .get("camera_matrix")
        .and_then(Value::as_array)
        .filter(|rows| rows.len() == 3)
        .ok_or_else(|| Error::invalid("fisheye_params.camera_matrix", "expected a 3x3 array"))?;
    let mut k = [[0.0; 3]; 3];
    for (r, row) in m.iter().enumerate() {
        let row = row.as_array().filter(|c| c.len() == 3).ok_or_else(|| {
            Error::invalid("fisheye_params.camera_matrix", "expected a 3x3 array")
        })?;
        for (c, v) in row.iter().enumerate() {
            k[r][c] = num(v, &format!("fisheye_params.camera_matrix[{r}][{c}]"))?;
        }
    }
    // Gyroflow divides the focal lengths by `crop` and takes their size
    // (a negative fx or fy is a mirrored calibration; the speed is the same).
    let crop = match p.get("crop") {
        None | Some(Value::Null) => 1.0,
        Some(v) => num(v, "crop")?,
    };
    if crop.is_nan() || crop <= 0.0 {
        return Err(Error::invalid(
            "crop",
            format!("must be positive, got {crop}"),
        ));
    }
    let (fx, fy) = ((k[0][0] / crop).abs(), (k[1][1] / crop).abs());
    if !(fx > 0.0 && fy > 0.0) {
        return Err(Error::invalid(
            "fisheye_params.camera_matrix",
            format!(
                "focal lengths must be non-zero, got fx = {}, fy = {}",
                k[0][0], k[1][1]
            ),
        ));
    }
    let digital = match p.get("digital_lens") {
        None | Some(Value::Null) => None,
        Some(Value::String(s)) => Some(Lens::from_name(s).ok_or_else(|| {
            Error::invalid(
                "digital_lens",
                format!(
                    "'{s}' is not a digital lens mmbm has (gopro_superview, gopro6_superview, \
                     gopro_hyperview, gopro_warp, digital_stretch)"
                ),
            )
        })?),
        Some(v) => {
            return Err(Error::invalid(
                "digital_lens",
                format!("expected a name, got {v}"),
            ))
        }
    };
    let mut params = [0.0; 16];
    if let Some(a) = p.get("digital_lens_params").and_then(Value::as_array) {
        for (i, v) in a.iter().enumerate().take(16) {
            params[i] = num(v, &format!("digital_lens_params[{i}]"))?;
        }
    }
    let coeffs: Vec<f64> = match fp.get("distortion_coeffs") {
        None | Some(Value::Null) => vec![],
        Some(Value::Array(a)) => a
            .iter()
            .enumerate()
            .map(|(i, v)| num(v, &format!("fisheye_params.distortion_coeffs[{i}]")))
            .collect::<Result<_>>()?,
        Some(v) => {
            return Err(Error::invalid(
                "fisheye_params.distortion_coeffs",
                format!("expected an array, got {v}"),
            ))
        }
    };
    let model = match p.get("distortion_model").and_then(Value::as_str) {
        Some(s) => s.to_string(),
        None if p.get("use_opencv_standard").and_then(Value::as_bool) == Some(true) => {
            "opencv_standard".into()
        }
        None => "opencv_fisheye".into(),
    };
    let given_limit = fp.get("radial_distortion_limit").and_then(Value::as_f64);
    if coeffs.is_empty() && given_limit.is_some_and(|l| l > 0.0) {
        return Err(Error::invalid(
            "fisheye_params.radial_distortion_limit",
            "a radial distortion limit without distortion coefficients (a masked pinhole) is \
             not supported; with coefficients Gyroflow and mmbm compute the limit from them",
        ));
    }
    let optical = gyroflow_distortion(&model, &coeffs)?;
    let focal_mm = match p.get("focal_length").and_then(Value::as_f64) {
        Some(f) if f > 0.0 && f.is_finite() => f,
        _ => fx * NOMINAL_PITCH_MM,
    };
    let readout_ms = match p.get("frame_readout_time") {
        None | Some(Value::Null) => 0.0,
        Some(v) => num(v, "frame_readout_time")?,
    };
    let mut direction = match p.get("frame_readout_direction") {
        None | Some(Value::Null) => Readout::TopToBottom,
        Some(Value::String(s)) => gyroflow_direction(s)?,
        Some(v) => gyroflow_direction(&v.to_string())?,
    };
    // Gyroflow: a negative readout time is the opposite direction.
    if readout_ms < 0.0 {
        direction = direction.reversed();
    }
    // The principal point is the image centre unless the profile says
    // `asymmetrical: true` (Gyroflow's `get_camera_matrix`).
    let asymmetrical = p.get("asymmetrical").and_then(Value::as_bool) == Some(true);
    let (cx, cy) = if asymmetrical {
        (k[0][2], k[1][2])
    } else {
        (w as f64 / 2.0, h as f64 / 2.0)
    };
    let mut cam = Camera {
        focal_mm,
        pitch_x_mm: focal_mm / fx,
        pitch_y_mm: focal_mm / fy,
        width: w,
        height: h,
        cx,
        cy,
        skew: k[0][1],
        distortion: optical,
        shutter: Shutter {
            readout_s: readout_ms.abs() / 1000.0,
            direction,
        },
        noise: None,
        lens: None,
    };
    if let Some(lens) = digital {
        let (m, k) = optical.parts();
        cam.distortion = Distortion::Digital {
            warp: Warp {
                lens,
                params,
                frame: [0.0; 4],
            },
            optical: m,
            k,
        };
        cam = cam.refit_digital();
    }
    Ok(cam)
}

/// The distortion of a Gyroflow profile's `distortion_model` and
/// `distortion_coeffs` (missing coefficients are 0). Coefficients that are
/// all zero (or none) are the plain pinhole, as in Gyroflow; a model mmbm
/// does not implement is refused by name, and so is a coefficient past the
/// model's count that is not zero (none is dropped silently).
fn gyroflow_distortion(model: &str, coeffs: &[f64]) -> Result<Distortion> {
    let m = Model::from_name(model).ok_or_else(|| {
        Error::invalid(
            "distortion_model",
            format!(
                "'{model}' is not supported (mmbm reads opencv_fisheye, opencv_standard, poly3, \
                 poly5, ptlens, sony, generic_polynomial and insta360; Gyroflow's gopro model, \
                 which needs the camera's own POLY telemetry, is not implemented)"
            ),
        )
    })?;
    let most = m.count();
    if let Some(i) = (most..coeffs.len()).find(|&i| coeffs[i] != 0.0) {
        return Err(Error::invalid(
            format!("fisheye_params.distortion_coeffs[{i}]"),
            format!(
                "{model} has {most} coefficients, this profile gives a non-zero {}th",
                i + 1
            ),
        ));
    }
    if coeffs.iter().all(|&x| x == 0.0) {
        return Ok(Distortion::None);
    }
    let k = std::array::from_fn(|i| coeffs.get(i).copied().unwrap_or(0.0));
    Ok(Distortion::from_model(m, k))
}

/// Gyroflow's direction names and numbers ([`Readout::from_gyroflow`]).
fn gyroflow_direction(s: &str) -> Result<Readout> {
    Readout::from_gyroflow(s.trim_matches('"')).ok_or_else(|| {
        Error::invalid(
            "frame_readout_direction",
            format!("'{s}' is not a readout direction"),
        )
    })
}
