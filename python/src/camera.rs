//! The camera across the door: one dict of the camera file's keys
//! ([`CameraFile`], the library's one camera representation) from Python,
//! and every key of a library camera back as JSON.

use crate::err;
use mmbm::camera::{Camera, CameraFile};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The camera as the Python half passes it: a dict of the camera file's
/// keys ([`CameraFile`], the one camera representation). The sides are
/// checked by the library first ([`Camera::size_from`]), so a negative one
/// is a `ValueError` that names the resolution.
pub fn camera(spec: &Bound<'_, PyDict>) -> PyResult<Camera> {
    let mut v = json(spec.as_any(), "camera")?;
    for path in INTEGER_KEYS {
        integer(&mut v, path)?;
    }
    if let (Some(w), Some(h)) = (v["width"].as_i64(), v["height"].as_i64()) {
        Camera::size_from(w, h).map_err(err)?;
    }
    let file: CameraFile =
        serde_json::from_value(v).map_err(|e| PyValueError::new_err(format!("camera: {e}")))?;
    let cam = file.camera().map_err(err)?;
    cam.validate().map_err(err)?;
    Ok(cam)
}

/// The camera keys that are integers (`noise.bits` is the `bits` of the
/// `noise` dict).
const INTEGER_KEYS: [&[&str]; 4] = [
    &["width"],
    &["height"],
    &["noise", "bits"],
    &["noise", "seed"],
];

/// The integer key at `path` of `v`: a float with an integral value (`640.0`)
/// becomes that integer; any other float (`1.7`) is a `ValueError` naming
/// the key, never truncated to an integer.
fn integer(v: &mut serde_json::Value, path: &[&str]) -> PyResult<()> {
    let mut x = &mut *v;
    for k in path {
        match x.get_mut(*k) {
            Some(next) => x = next,
            None => return Ok(()),
        }
    }
    if x.is_i64() || x.is_u64() {
        return Ok(());
    }
    if let Some(f) = x.as_f64() {
        let name = format!("camera.{}", path.join("."));
        // Integral and within i64 (a u32 or u64 key refuses the rest by name).
        if f.fract() != 0.0 || f.abs() >= 9.2e18 {
            return Err(PyValueError::new_err(format!(
                "{name}: must be an integer, got {f}"
            )));
        }
        *x = serde_json::Value::from(f as i64);
    }
    Ok(())
}

/// A camera for the Python half: every key of its camera file, as JSON
/// (the Python `Camera`'s fields are these keys).
pub fn camera_json(c: &Camera) -> PyResult<String> {
    serde_json::to_string(&CameraFile::of(c)).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A Python value (dict, list, tuple, str, bool, int, float, None) as JSON
/// for the library's serde types; `key` names it in errors. JSON has no
/// NaN or infinity, so a non-finite float is refused here, by name.
fn json(x: &Bound<'_, PyAny>, key: &str) -> PyResult<serde_json::Value> {
    use pyo3::types::{PyBool, PyList, PyString, PyTuple};
    use serde_json::Value;
    if x.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = x.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if let Ok(d) = x.cast::<PyDict>() {
        let mut m = serde_json::Map::new();
        for (k, v) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| PyValueError::new_err(format!("{key}: keys must be strings")))?;
            let v = json(&v, &format!("{key}.{k}"))?;
            m.insert(k, v);
        }
        return Ok(Value::Object(m));
    }
    if x.cast::<PyList>().is_ok() || x.cast::<PyTuple>().is_ok() {
        let mut a = Vec::new();
        for (i, v) in x.try_iter()?.enumerate() {
            a.push(json(&v?, &format!("{key}[{i}]"))?);
        }
        return Ok(Value::Array(a));
    }
    if x.cast::<PyString>().is_ok() {
        return Ok(Value::String(x.extract()?));
    }
    if let Ok(i) = x.extract::<i64>() {
        return Ok(Value::from(i));
    }
    if let Ok(f) = x.extract::<f64>() {
        mmbm::check::finite(key, f).map_err(err)?;
        return Ok(Value::from(f));
    }
    Err(PyValueError::new_err(format!(
        "{key}: expected a number, a string, a list or a dict"
    )))
}
