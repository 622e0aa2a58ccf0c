//! Which profile of a Gyroflow lens profile file is used for a video
//! ([`Choice`]): the `compatible_settings` entry of the video's size, the
//! digital lens's widening and the `interpolations` at a zoom lens's focal
//! length (steps 1 to 3 of [`super::gyroflow`]'s doc), as Gyroflow's
//! `lens_profile.rs` chooses. Linear in the profile's size: only the entry
//! chosen is copied, and lists longer than [`MAX_PROFILE_ENTRIES`] are
//! refused by key.

use crate::error::{Error, Result};
pub use crate::limits::MAX_PROFILE_ENTRIES;
use serde_json::Value;

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
    if let Some(m) = p.as_object_mut() {
        m.insert(
            "calib_dimension".into(),
            serde_json::json!({"w": w, "h": h}),
        );
    }
}

/// Refuses a list of `n` entries under `key` past [`MAX_PROFILE_ENTRIES`].
fn check_entries(key: &str, n: usize) -> Result<()> {
    if n > MAX_PROFILE_ENTRIES {
        return Err(Error::invalid(
            key,
            format!(
                "{n} entries, more than the {MAX_PROFILE_ENTRIES} a lens profile may have \
                 (MAX_PROFILE_ENTRIES)"
            ),
        ));
    }
    Ok(())
}

/// `p` (an object) without `key`'s value: `key` set to `with`. One copy of
/// the rest, whatever the size of `key`'s value.
fn without(p: &Value, key: &str, with: Value) -> Value {
    let Some(m) = p.as_object() else {
        return p.clone();
    };
    let mut out: serde_json::Map<String, Value> = m
        .iter()
        .map(|(k, v)| (k.clone(), if k == key { Value::Null } else { v.clone() }))
        .collect();
    out.insert(key.into(), with);
    Value::Object(out)
}

/// `p`'s `fisheye_params` object, when it is one.
fn fisheye_mut(p: &mut Value) -> Option<&mut serde_json::Map<String, Value>> {
    p.get_mut("fisheye_params")?.as_object_mut()
}

/// Sets the numbers of `row` over `p`'s `fisheye_params.distortion_coeffs`
/// (a longer row extends it with zeros).
fn set_coeffs(p: &mut Value, row: &[Value]) {
    let Some(fp) = fisheye_mut(p) else {
        return;
    };
    let mut k = fp
        .get("distortion_coeffs")
        .and_then(Value::as_array)
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
    fp.insert("distortion_coeffs".into(), Value::Array(k));
}

/// `p`'s camera matrix element `[r][c]`, when the matrix has it.
fn matrix_mut(p: &mut Value, r: usize, c: usize) -> Option<&mut Value> {
    fisheye_mut(p)?
        .get_mut("camera_matrix")?
        .get_mut(r)?
        .get_mut(c)
}

/// The size of the copy for a `compatible_settings` entry `x` of a profile
/// of size `dims`, with the scale of each axis (None: the profile's size).
fn entry_size(
    x: &serde_json::Map<String, Value>,
    dims: Option<(u64, u64)>,
) -> Option<((u64, u64), f64, f64)> {
    let (nw, nh) = (
        x.get("width").and_then(Value::as_u64)?,
        x.get("height").and_then(Value::as_u64)?,
    );
    let (w, h) = dims?;
    if nw == 0 || nh == 0 {
        return None;
    }
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
    Some(((scale(w, rw), scale(h, rh)), rw, rh))
}

/// Gyroflow's copy of the profile for one `compatible_settings` entry `x`:
/// `base` (the profile with an empty `compatible_settings`) with the entry's
/// size and keys over it.
fn entry_copy(base: &Value, x: &serde_json::Map<String, Value>) -> Value {
    let mut c = base.clone();
    if let Some(((w, h), rw, rh)) = entry_size(x, dims(base)) {
        set_dims(&mut c, w, h);
        // Same aspect: sub- or super-sampling (the matrix scales);
        // else a sensor crop (the matrix stays).
        if (rw - rh).abs() < 0.001 {
            for (r, cols, ratio) in [(0, [0, 2], rw), (1, [1, 2], rh)] {
                for col in cols {
                    if let Some(m) = matrix_mut(&mut c, r, col) {
                        if let Some(v) = m.as_f64() {
                            *m = (v * ratio).into();
                        }
                    }
                }
            }
        }
    }
    if let Some(obj) = c.as_object_mut() {
        for key in [
            "frame_readout_time",
            "crop",
            "digital_lens",
            "focal_length",
            "interpolations",
        ] {
            if let Some(v) = x.get(key) {
                obj.insert(key.into(), v.clone());
            }
        }
    }
    if let Some(row) = x.get("distortion_coeffs").and_then(Value::as_array) {
        set_coeffs(&mut c, row);
    }
    c
}

/// The profile Gyroflow uses for `choice` (the steps of the module's doc).
///
/// Linear in the profile's size: the candidates of `compatible_settings`
/// (Gyroflow's `get_all_matching_profiles`: the profile, then a copy per
/// entry) are matched by their size alone, and only the one chosen is
/// copied. Lists longer than [`MAX_PROFILE_ENTRIES`] are refused by key.
pub fn select(p: &Value, choice: &Choice) -> Result<Value> {
    let entries: Vec<&serde_json::Map<String, Value>> =
        match p.get("compatible_settings").and_then(Value::as_array) {
            Some(a) => {
                check_entries("compatible_settings", a.len())?;
                a.iter().filter_map(Value::as_object).collect()
            }
            None => Vec::new(),
        };
    if let Some(m) = p.get("interpolations").and_then(Value::as_object) {
        check_entries("interpolations", m.len())?;
    }
    let mut chosen = None;
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
        // The candidates' sizes: the profile's (None), then each entry's.
        let sizes: Vec<(Option<usize>, (u64, u64))> = std::iter::once((None, (w, h)))
            .chain(
                entries
                    .iter()
                    .enumerate()
                    .map(|(i, x)| (Some(i), entry_size(x, Some((w, h))).map_or((w, h), |s| s.0))),
            )
            .collect();
        let by_size = sizes.iter().find(|c| c.1 == (vw, vh));
        let by_aspect = || {
            sizes
                .iter()
                .find(|c| aspect(c.1 .0, c.1 .1) == aspect(vw, vh))
        };
        if let Some(&(Some(i), _)) = by_size.or_else(by_aspect) {
            let base = without(p, "compatible_settings", Value::Array(vec![]));
            chosen = Some(entry_copy(&base, entries[i]));
        }
    }
    let mut chosen = chosen.unwrap_or_else(|| p.clone());
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

/// `base` (the profile without `interpolations`) with an `interpolations`
/// entry `v`'s camera matrix, coefficients and focal length over it.
fn overlay(base: &Value, v: &serde_json::Map<String, Value>) -> Value {
    let mut e = base.clone();
    if let Some(rows) = v.get("camera_matrix").and_then(Value::as_array) {
        for (i, r) in rows.iter().enumerate().take(3) {
            for (j, c) in r.as_array().into_iter().flatten().enumerate().take(3) {
                if c.is_number() {
                    if let Some(m) = matrix_mut(&mut e, i, j) {
                        *m = c.clone();
                    }
                }
            }
        }
    }
    if let Some(row) = v.get("distortion_coeffs").and_then(Value::as_array) {
        set_coeffs(&mut e, row);
    }
    if let (Some(fl), Some(obj)) = (
        v.get("focal_length").filter(|x| x.is_number()),
        e.as_object_mut(),
    ) {
        obj.insert("focal_length".into(), fl.clone());
    }
    e
}

/// The profile at focal length `f` mm of its `interpolations`; a profile
/// without any is refused (`--lens-focal` applies only to a zoom profile).
/// Linear in the profile's size: the entries are sorted by focal length and
/// only the one or two used are laid over the profile.
fn interpolated(p: &Value, f: f64) -> Result<Value> {
    let Some(map) = p.get("interpolations").and_then(Value::as_object) else {
        return Err(Error::invalid(
            "--lens-focal",
            "the profile has no interpolations; --lens-focal applies only to a zoom lens's \
             profile with interpolations (keyed by focal length, mm)",
        ));
    };
    check_entries("interpolations", map.len())?;
    if !f.is_finite() || f <= 0.0 {
        return Err(Error::invalid(
            "lens focal length",
            format!("must be a positive number of mm, got {f}"),
        ));
    }
    // Gyroflow's parsed interpolations: keyed by round(focal * 1e6).
    let mut entries: Vec<(i64, &serde_json::Map<String, Value>)> = Vec::new();
    for (k, v) in map {
        let (Ok(key), Some(v)) = (k.parse::<f64>(), v.as_object()) else {
            continue;
        };
        if v.contains_key("identifier") && !v.contains_key("camera_matrix") {
            return Err(Error::invalid(
                format!("interpolations.{k}"),
                "names another profile of Gyroflow's database by its identifier; mmbm reads \
                 one file (give the entry's camera_matrix and distortion_coeffs)",
            ));
        }
        entries.push(((key * 1e6).round() as i64, v));
    }
    entries.sort_by_key(|e| e.0);
    let base = without(p, "interpolations", Value::Null);
    let key = (f * 1e6).round() as i64;
    if let Some(e) = entries.iter().find(|e| e.0 == key) {
        return Ok(overlay(&base, e.1));
    }
    if entries.len() < 2 {
        return Ok(entries
            .pop()
            .map_or_else(|| p.clone(), |e| overlay(&base, e.1)));
    }
    let (first, last) = (entries[0].0, entries[entries.len() - 1].0);
    let lookup = key.min(last - 1).max(first + 1);
    let i1 = entries.iter().rposition(|e| e.0 <= lookup).unwrap_or(0);
    let i2 = entries
        .iter()
        .position(|e| e.0 >= lookup)
        .unwrap_or(entries.len() - 1);
    let (p1, p2) = (
        (entries[i1].0, overlay(&base, entries[i1].1)),
        (entries[i2].0, overlay(&base, entries[i2].1)),
    );
    if p1.0 == lookup || p1.0 == p2.0 {
        return Ok(p1.1);
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
    let mut out = base;
    for (r, c) in [(0, 0), (1, 1), (0, 2), (1, 2)] {
        let path = ["fisheye_params", "camera_matrix"];
        if let (Some(a), Some(b)) = (get(&p1.1, &path, &[r, c]), get(&p2.1, &path, &[r, c])) {
            if let Some(m) = matrix_mut(&mut out, r, c) {
                *m = lerp(a, b).into();
            }
        }
    }
    let coeffs = |v: &Value| {
        v.get("fisheye_params")
            .and_then(|f| f.get("distortion_coeffs"))
            .and_then(Value::as_array)
            .map(|a| a.iter().filter_map(Value::as_f64).collect::<Vec<_>>())
            .unwrap_or_default()
    };
    let (k1, k2, k0) = (coeffs(&p1.1), coeffs(&p2.1), coeffs(p));
    if k1.len() == k2.len() && k1.len() == k0.len() {
        let k: Vec<f64> = k1.iter().zip(&k2).map(|(a, b)| lerp(*a, *b)).collect();
        if let Some(fp) = fisheye_mut(&mut out) {
            fp.insert("distortion_coeffs".into(), k.into());
        }
    }
    let crop = |v: &Value| v.get("crop").and_then(Value::as_f64).unwrap_or(1.0);
    let focal = match (
        get(&p1.1, &["focal_length"], &[]),
        get(&p2.1, &["focal_length"], &[]),
    ) {
        (Some(a), Some(b)) => Some(lerp(a, b)),
        _ => None,
    };
    if let Some(obj) = out.as_object_mut() {
        obj.insert("crop".into(), lerp(crop(&p1.1), crop(&p2.1)).into());
        if let Some(fl) = focal {
            obj.insert("focal_length".into(), fl.into());
        }
    }
    Ok(out)
}
