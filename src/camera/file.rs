//! Camera files: the project's own TOML/JSON description and Gyroflow lens
//! profiles (JSON with `fisheye_params`), so that the public collection of
//! Gyroflow profiles works as it is.
//!
//! Own format (every key of SPEC 1 and 9; pitch may be given once for square pixels):
//!
//! ```toml
//! focal_mm = 4.2548
//! pitch_mm = 0.00465
//! width = 640
//! height = 480
//! # cx, cy (default: the centre), skew (default 0)
//! readout_s = 0.016                  # rolling shutter (default 0: global)
//! readout_direction = "top-to-bottom" # or bottom-to-top, left-to-right, right-to-left
//! [distortion]
//! model = "opencv"                   # k1, k2, p1, p2, k3; or "fisheye" with k1..k4
//! k1 = -0.28
//! [noise]
//! phi_e_per_s = 50000                # read_noise_e, full_well_e, gain_dn_per_e, bits, seed
//! [lens]
//! f_number = 2.0
//! focus_m = 1.5
//! ```
//!
//! Gyroflow profile: `calib_dimension {w, h}`, `fisheye_params.camera_matrix`
//! (3x3, pixels), `fisheye_params.distortion_coeffs`, `distortion_model`
//! (`opencv_fisheye`, the default, or `opencv_standard`; older profiles say
//! `use_opencv_standard: true`), `frame_readout_time` (ms) and
//! `frame_readout_direction`. A profile gives pixels only: the pixel pitch is
//! `focal_length / fx` when the profile has a `focal_length` in mm, otherwise a
//! nominal 1 um ([`NOMINAL_PITCH_MM`]), which scales the mm/s outputs but not px/s.

use super::distortion::Distortion;
use super::intrinsics::Camera;
use super::lens::Lens;
use super::noise::Noise;
use super::shutter::{Readout, Shutter};
use crate::error::{Error, Result};
use serde::Deserialize;
use serde_json::Value;
use std::path::Path;

/// Pixel pitch (mm) assumed for a Gyroflow profile without a focal length in mm.
pub const NOMINAL_PITCH_MM: f64 = 0.001;

/// Largest camera file read, bytes (a real one is under 10 kB; Gyroflow
/// profiles a few kB). Bounds the parsers' time and memory: a 6 MB TOML
/// array took 5.7 s and 530 MB to refuse.
pub const MAX_CAMERA_BYTES: u64 = 1 << 20;

/// The text of the camera file `path`: a regular file or a pipe (a device
/// such as `/dev/zero` is refused before it is opened) of at most [`MAX_CAMERA_BYTES`].
fn read_camera_text(path: &Path) -> Result<String> {
    use std::io::Read;
    let refused = |message: String| Error::Config {
        path: path.into(),
        message,
    };
    // Checked before opening: opening a device can have effects of its own.
    let kind = std::fs::metadata(path)
        .map_err(|e| Error::io(path, e))?
        .file_type();
    #[cfg(unix)]
    let pipe = std::os::unix::fs::FileTypeExt::is_fifo(&kind);
    #[cfg(not(unix))]
    let pipe = false;
    if !(kind.is_file() || pipe) {
        return Err(refused(
            "is not a regular file or a pipe: a camera file is read whole".into(),
        ));
    }
    let f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut bytes = Vec::new();
    f.take(MAX_CAMERA_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > MAX_CAMERA_BYTES {
        return Err(refused(format!(
            "longer than {MAX_CAMERA_BYTES} bytes, the most a camera file may have"
        )));
    }
    String::from_utf8(bytes).map_err(|e| {
        refused(format!(
            "not UTF-8 text (byte {} is not part of a character)",
            e.utf8_error().valid_up_to()
        ))
    })
}

/// On-disk camera description.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    focal_mm: f64,
    pitch_mm: Option<f64>,
    pitch_x_mm: Option<f64>,
    pitch_y_mm: Option<f64>,
    width: u32,
    height: u32,
    cx: Option<f64>,
    cy: Option<f64>,
    #[serde(default)]
    skew: f64,
    #[serde(default)]
    readout_s: f64,
    #[serde(default)]
    readout_direction: Readout,
    #[serde(default)]
    distortion: Distortion,
    noise: Option<Noise>,
    lens: Option<Lens>,
}

impl CameraFile {
    fn into_camera(self) -> Camera {
        let p = self.pitch_mm.unwrap_or(f64::NAN);
        Camera {
            focal_mm: self.focal_mm,
            pitch_x_mm: self.pitch_x_mm.unwrap_or(p),
            pitch_y_mm: self.pitch_y_mm.unwrap_or(p),
            width: self.width,
            height: self.height,
            cx: self.cx.unwrap_or(self.width as f64 / 2.0),
            cy: self.cy.unwrap_or(self.height as f64 / 2.0),
            skew: self.skew,
            distortion: self.distortion,
            shutter: Shutter {
                readout_s: self.readout_s,
                direction: self.readout_direction,
            },
            noise: self.noise,
            lens: self.lens,
        }
    }
}

impl Camera {
    /// Loads a camera from a TOML (`.toml`) or JSON (any other extension)
    /// file: the project's format, or a Gyroflow lens profile (a JSON object
    /// with `fisheye_params`). Missing principal point fields default to the
    /// sensor centre. Errors name the file and the key.
    pub fn load(path: &Path) -> Result<Self> {
        let text = read_camera_text(path)?;
        let config = |message: String| Error::Config {
            path: path.into(),
            message,
        };
        let cam = if path.extension().is_some_and(|e| e == "toml") {
            let file: CameraFile = toml::from_str(&text).map_err(|e| config(e.to_string()))?;
            file.into_camera()
        } else {
            let value: Value = serde_json::from_str(&text).map_err(|e| config(e.to_string()))?;
            if value.get("fisheye_params").is_some() {
                from_gyroflow(&value).map_err(|e| config(e.to_string()))?
            } else {
                let file: CameraFile =
                    serde_json::from_value(value).map_err(|e| config(e.to_string()))?;
                file.into_camera()
            }
        };
        cam.validate().map_err(|e| config(e.to_string()))?;
        Ok(cam)
    }
}

fn num(v: &Value, key: &str) -> Result<f64> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .ok_or_else(|| Error::invalid(key, format!("expected a finite number, got {v}")))
}

/// A camera from a parsed Gyroflow lens profile.
pub fn from_gyroflow(p: &Value) -> Result<Camera> {
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
    let (fx, fy) = (k[0][0], k[1][1]);
    if !(fx > 0.0 && fy > 0.0) {
        return Err(Error::invalid(
            "fisheye_params.camera_matrix",
            format!("focal lengths must be positive, got fx = {fx}, fy = {fy}"),
        ));
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
    let c = |i: usize| coeffs.get(i).copied().unwrap_or(0.0);
    let model = match p.get("distortion_model").and_then(Value::as_str) {
        Some(s) => s.to_string(),
        None if p.get("use_opencv_standard").and_then(Value::as_bool) == Some(true) => {
            "opencv_standard".into()
        }
        None => "opencv_fisheye".into(),
    };
    let distortion = match model.as_str() {
        "opencv_fisheye" => Distortion::Fisheye {
            k1: c(0),
            k2: c(1),
            k3: c(2),
            k4: c(3),
        },
        "opencv_standard" => Distortion::Opencv {
            k1: c(0),
            k2: c(1),
            p1: c(2),
            p2: c(3),
            k3: c(4),
        },
        other => {
            return Err(Error::invalid(
                "distortion_model",
                format!(
                    "'{other}' is not supported (mmbm reads opencv_fisheye and opencv_standard)"
                ),
            ))
        }
    };
    let focal_mm = match p.get("focal_length").and_then(Value::as_f64) {
        Some(f) if f > 0.0 && f.is_finite() => f,
        _ => fx * NOMINAL_PITCH_MM,
    };
    let readout_s = match p.get("frame_readout_time") {
        None | Some(Value::Null) => 0.0,
        Some(v) => num(v, "frame_readout_time")? / 1000.0,
    };
    let direction = match p.get("frame_readout_direction") {
        None | Some(Value::Null) => Readout::TopToBottom,
        Some(Value::String(s)) => gyroflow_direction(s)?,
        Some(v) => gyroflow_direction(&v.to_string())?,
    };
    Ok(Camera {
        focal_mm,
        pitch_x_mm: focal_mm / fx,
        pitch_y_mm: focal_mm / fy,
        width: w,
        height: h,
        cx: k[0][2],
        cy: k[1][2],
        skew: k[0][1],
        distortion,
        shutter: Shutter {
            readout_s,
            direction,
        },
        noise: None,
        lens: None,
    })
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
