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
use super::intrinsics::Camera;
use super::models::Model;
use super::shutter::{Readout, Shutter};
use crate::error::{Error, Result};
use serde_json::Value;

/// Pixel pitch (mm) assumed for a Gyroflow profile without a focal length in mm.
pub const NOMINAL_PITCH_MM: f64 = 0.001;

/// What a profile is read for: the video's size (`--scale-to`) and a zoom
/// lens's focal length (mm).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Choice {
    /// The video's size, px.
    pub video: Option<(u32, u32)>,
    /// The focal length for `interpolations`, mm.
    pub focal_mm: Option<f64>,
}

fn dims(p: &Value) -> Option<(u64, u64)> {
    let d = p.get("calib_dimension")?;
    Some((d.get("w")?.as_u64()?, d.get("h")?.as_u64()?))
}

fn set_dims(p: &mut Value, w: u64, h: u64) {
    p["calib_dimension"] = serde_json::json!({"w": w, "h": h});
}

/// Gyroflow's `get_all_matching_profiles`: the profile, then a copy per
/// `compatible_settings` entry.
fn matching(p: &Value) -> Vec<Value> {
    let mut out = vec![p.clone()];
    let Some(entries) = p.get("compatible_settings").and_then(Value::as_array) else {
        return out;
    };
    for x in entries.iter().filter_map(Value::as_object) {
        let mut c = p.clone();
        c["compatible_settings"] = Value::Array(vec![]);
        let size = (
            x.get("width").and_then(Value::as_u64),
            x.get("height").and_then(Value::as_u64),
        );
        if let ((Some(nw), Some(nh)), Some((w, h))) = (size, dims(p)) {
            if nw > 0 && nh > 0 {
                let mut rw = nw as f64 / w as f64;
                let rh = nh as f64 / h as f64;
                match x.get("digital_lens").and_then(Value::as_str) {
                    Some("gopro_superview") | Some("gopro6_superview") => rw /= 1.33333333333,
                    Some("gopro_hyperview") => rw /= 1.55555555555,
                    _ => {}
                }
                let scale = |v: u64, r: f64| {
                    let s = (v as f64 * r).round() as u64;
                    s - s % 2
                };
                set_dims(&mut c, scale(w, rw), scale(h, rh));
                // Same aspect: sub- or super-sampling (the matrix scales);
                // else a sensor crop (the matrix stays).
                if (rw - rh).abs() < 0.001 {
                    if let Some(m) = c["fisheye_params"]["camera_matrix"].as_array_mut() {
                        for (r, cols, ratio) in [(0, [0, 2], rw), (1, [1, 2], rh)] {
                            for col in cols {
                                if let Some(v) = m
                                    .get(r)
                                    .and_then(|row| row.get(col))
                                    .and_then(Value::as_f64)
                                {
                                    m[r][col] = (v * ratio).into();
                                }
                            }
                        }
                    }
                }
            }
        }
        for key in [
            "frame_readout_time",
            "crop",
            "digital_lens",
            "focal_length",
            "interpolations",
        ] {
            if let Some(v) = x.get(key) {
                c[key] = v.clone();
            }
        }
        if let Some(row) = x.get("distortion_coeffs").and_then(Value::as_array) {
            let mut k = c["fisheye_params"]["distortion_coeffs"]
                .as_array()
                .cloned()
                .unwrap_or_default();
            for (i, v) in row.iter().enumerate() {
                if v.is_number() {
                    if i >= k.len() {
                        k.resize(i + 1, 0.0.into());
                    }
                    k[i] = v.clone();
                }
            }
            c["fisheye_params"]["distortion_coeffs"] = Value::Array(k);
        }
        out.push(c);
    }
    out
}

/// The profile Gyroflow uses for `choice` (the steps of the module's doc).
pub fn select(p: &Value, choice: &Choice) -> Result<Value> {
    let all = matching(p);
    let mut chosen = p.clone();
    if let (Some((vw, vh)), Some((w, h))) = (choice.video, dims(p)) {
        // A portrait video on a landscape profile (or the other way): Gyroflow
        // turns the profile first; match in the profile's orientation.
        let turned = (vw > vh && w < h) || (vw < vh && w > h);
        let (vw, vh) = if turned {
            (vh as u64, vw as u64)
        } else {
            (vw as u64, vh as u64)
        };
        let aspect = |w: u64, h: u64| (w as f64 * 100.0 / h.max(1) as f64).round() as u64;
        let by_size = all.iter().find(|c| dims(c) == Some((vw, vh)));
        let by_aspect = || {
            all.iter()
                .find(|c| dims(c).is_some_and(|(w, h)| aspect(w, h) == aspect(vw, vh)))
        };
        if let Some(c) = by_size.or_else(by_aspect) {
            chosen = c.clone();
        }
    }
    // Gyroflow's `adjust_lens_profile` of a digital lens.
    if let (Some(lens), Some((w, h))) = (
        chosen.get("digital_lens").and_then(Value::as_str),
        dims(&chosen),
    ) {
        let aspect = (w as f64 / h as f64 * 100.0) as u64;
        let widen = match lens {
            "gopro_superview" | "gopro6_superview" if aspect == 133 => Some(1.3333333333333),
            "gopro_hyperview" if aspect == 114 => Some(1.55555555555),
            _ => None,
        };
        if let Some(f) = widen {
            set_dims(&mut chosen, (w as f64 * f).round() as u64, h);
        }
    }
    if let Some(f) = choice.focal_mm {
        chosen = interpolated(&chosen, f)?;
    }
    Ok(chosen)
}

/// The profile at focal length `f` mm of its `interpolations` (unchanged without any).
fn interpolated(p: &Value, f: f64) -> Result<Value> {
    let Some(map) = p.get("interpolations").and_then(Value::as_object) else {
        return Ok(p.clone());
    };
    if !f.is_finite() || f <= 0.0 {
        return Err(Error::invalid(
            "lens focal length",
            format!("must be a positive number of mm, got {f}"),
        ));
    }
    // Gyroflow's parsed interpolations: keyed by round(focal * 1e6).
    let mut entries: Vec<(i64, Value)> = Vec::new();
    for (k, v) in map {
        let (Ok(key), Some(v)) = (k.parse::<f64>(), v.as_object()) else {
            continue;
        };
        if v.contains_key("identifier") && !v.contains_key("camera_matrix") {
            return Err(Error::invalid(
                format!("interpolations.{k}"),
                "names another profile of Gyroflow's database by its identifier; mmbm reads                  one file (give the entry's camera_matrix and distortion_coeffs)",
            ));
        }
        let mut e = p.clone();
        e["interpolations"] = Value::Null;
        if let Some(rows) = v.get("camera_matrix").and_then(Value::as_array) {
            for (i, r) in rows.iter().enumerate().take(3) {
                for (j, c) in r.as_array().into_iter().flatten().enumerate().take(3) {
                    if c.is_number() {
                        e["fisheye_params"]["camera_matrix"][i][j] = c.clone();
                    }
                }
            }
        }
        if let Some(row) = v.get("distortion_coeffs").and_then(Value::as_array) {
            for (i, c) in row.iter().enumerate() {
                if c.is_number() {
                    e["fisheye_params"]["distortion_coeffs"][i] = c.clone();
                }
            }
        }
        if let Some(fl) = v.get("focal_length").filter(|x| x.is_number()) {
            e["focal_length"] = fl.clone();
        }
        entries.push(((key * 1e6).round() as i64, e));
    }
    entries.sort_by_key(|e| e.0);
    let key = (f * 1e6).round() as i64;
    if let Some(e) = entries.iter().find(|e| e.0 == key) {
        return Ok(e.1.clone());
    }
    if entries.len() < 2 {
        return Ok(entries.pop().map_or_else(|| p.clone(), |e| e.1));
    }
    let (first, last) = (entries[0].0, entries[entries.len() - 1].0);
    let lookup = key.min(last - 1).max(first + 1);
    let i1 = entries.iter().rposition(|e| e.0 <= lookup).unwrap_or(0);
    let i2 = entries
        .iter()
        .position(|e| e.0 >= lookup)
        .unwrap_or(entries.len() - 1);
    let (p1, p2) = (&entries[i1], &entries[i2]);
    if p1.0 == lookup || p1.0 == p2.0 {
        return Ok(p1.1.clone());
    }
    let t = (key - p1.0) as f64 / (p2.0 - p1.0) as f64;
    let lerp = |a: f64, b: f64| a * (1.0 - t) + b * t;
    let get = |v: &Value, path: &[&str], idx: &[usize]| -> Option<f64> {
        let mut x = v;
        for k in path {
            x = x.get(*k)?;
        }
        for i in idx {
            x = x.get(*i)?;
        }
        x.as_f64()
    };
    let mut out = p.clone();
    out["interpolations"] = Value::Null;
    for (r, c) in [(0, 0), (1, 1), (0, 2), (1, 2)] {
        let path = ["fisheye_params", "camera_matrix"];
        if let (Some(a), Some(b)) = (get(&p1.1, &path, &[r, c]), get(&p2.1, &path, &[r, c])) {
            out["fisheye_params"]["camera_matrix"][r][c] = lerp(a, b).into();
        }
    }
    let coeffs = |v: &Value| {
        v["fisheye_params"]["distortion_coeffs"]
            .as_array()
            .map(|a| a.iter().filter_map(Value::as_f64).collect::<Vec<_>>())
            .unwrap_or_default()
    };
    let (k1, k2, k0) = (coeffs(&p1.1), coeffs(&p2.1), coeffs(p));
    if k1.len() == k2.len() && k1.len() == k0.len() {
        let k: Vec<f64> = k1.iter().zip(&k2).map(|(a, b)| lerp(*a, *b)).collect();
        out["fisheye_params"]["distortion_coeffs"] = k.into();
    }
    let crop = |v: &Value| v.get("crop").and_then(Value::as_f64).unwrap_or(1.0);
    out["crop"] = lerp(crop(&p1.1), crop(&p2.1)).into();
    if let (Some(a), Some(b)) = (
        get(&p1.1, &["focal_length"], &[]),
        get(&p2.1, &["focal_length"], &[]),
    ) {
        out["focal_length"] = lerp(a, b).into();
    }
    Ok(out)
}

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
