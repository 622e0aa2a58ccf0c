//! `mmbm.choose_frames`: the chosen frames' indices from a blur per frame,
//! as `mmbm frames` chooses them (`mmbm::series::select`).

use crate::err;
use mmbm::series::select::windows::{best_per_window, Windows};
use mmbm::series::select::{choose_series, Choice};
use numpy::PyReadonlyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The chosen rows, in order, from `blur_px` (px per frame; NaN: no value,
/// never chosen) and `times_s` (frame starts, s; default: the row number,
/// as if 1 s apart). One mode at most of `per_window` (the sharpest of
/// every K frames), `per_seconds` (of every S s of starts), `count` (N
/// windows of equal frame counts) and `select` (the N sharpest, at least
/// `gap` s apart); `max_blur` (px) alone keeps every frame under it, with a
/// mode only picks within it.
#[pyfunction]
#[pyo3(signature = (blur_px, times_s=None, per_window=None, per_seconds=None, count=None, select=None, gap=0.0, max_blur=None))]
#[allow(clippy::too_many_arguments)]
pub fn choose_frames(
    blur_px: PyReadonlyArray1<'_, f64>,
    times_s: Option<PyReadonlyArray1<'_, f64>>,
    per_window: Option<usize>,
    per_seconds: Option<f64>,
    count: Option<usize>,
    select: Option<usize>,
    gap: f64,
    max_blur: Option<f64>,
) -> PyResult<Vec<usize>> {
    let blur: Vec<Option<f64>> = blur_px
        .as_slice()?
        .iter()
        .map(|&b| (!b.is_nan()).then_some(b))
        .collect();
    let t: Vec<f64> = match &times_s {
        Some(t) => t.as_slice()?.to_vec(),
        None => (0..blur.len()).map(|k| k as f64).collect(),
    };
    let modes = [
        per_window.is_some(),
        per_seconds.is_some(),
        count.is_some(),
        select.is_some(),
    ];
    if modes.iter().filter(|&&m| m).count() > 1 {
        return Err(PyValueError::new_err(
            "choose_frames: give at most one of per_window, per_seconds, count and select",
        ));
    }
    let windows = match (per_window, per_seconds, count) {
        (Some(k), _, _) => Some(Windows::Frames(k)),
        (_, Some(s), _) => Some(Windows::Seconds(s)),
        (_, _, Some(n)) => Some(Windows::Count(n)),
        _ => None,
    };
    if per_seconds.is_some() && times_s.is_none() {
        return Err(PyValueError::new_err(
            "choose_frames: per_seconds needs times_s (the frames' starts, s)",
        ));
    }
    match windows {
        Some(w) => {
            if gap != 0.0 {
                return Err(PyValueError::new_err(
                    "choose_frames: gap goes with select (the windows already space the picks)",
                ));
            }
            Ok(best_per_window(&blur, &t, w, max_blur, None)
                .map_err(err)?
                .chosen)
        }
        None if select.is_none() && max_blur.is_none() => Err(PyValueError::new_err(
            "choose_frames: give per_window, per_seconds, count, select or max_blur",
        )),
        None => {
            let choice = Choice {
                count: select,
                gap_s: gap,
                max_blur_px: max_blur,
            };
            Ok(choose_series(&blur, &t, &choice).map_err(err)?.0)
        }
    }
}
