//! The exposure MMBM of video frames (SPEC sections 3 and 9): for a frame
//! starting at `t0` with exposure `t_e` and rolling-shutter readout `t_r`,
//! line `j` of `n` is exposed over `[t0 + t_r j / n, t0 + t_r j / n + t_e]`,
//! and the frame's exposure MMBM is the sensor mean of each point's flow
//! speed averaged over its own line's window (mm/s). Blur length in pixels is
//! that times `t_e` over the pixel pitch.
//!
//! Time: a point's speed is evaluated at the gyro samples and interpolated
//! linearly between them, the convention of the trigger's exposure average,
//! so with `t_r = 0` the result is the time average of the MMBM series.
//! Space: the method's rule (`riemann`, `gauss`: nodes grouped by line, each
//! group averaged over its window; `riemann:Wx<lines>` has a node on every
//! line). `exact` (adaptive cubature of the window-averaged speed) is for
//! global shutters only: with a readout the integrand jumps at every line.

use super::{sample_scene, SeriesOptions};
use crate::camera::{Camera, Shutter};
use crate::error::{Error, Result};
use crate::io::frames::VideoFrame;
use crate::io::gyro::GyroSample;
use crate::metric::{exact_with, gauss_points, point_speed, riemann_points, GridRule, Method};
use crate::model::flow::FlowPoly;
use crate::model::log::{check_times, Integral};
use std::collections::BTreeMap;

/// The exposure MMBM of one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameMmbm {
    /// 0-based row of the frame table.
    pub frame: usize,
    /// Exposure start of the first line, s.
    pub t_start: f64,
    /// Exposure per line, s.
    pub exposure_s: f64,
    /// Rolling-shutter readout used, s.
    pub readout_s: f64,
    /// Exposure MMBM, mm/s (`None` when the frame's window leaves the log).
    pub exposure_mm_s: Option<f64>,
    /// Instantaneous MMBM at `t_start`, mm/s (`None` outside the log).
    pub start_mm_s: Option<f64>,
}

impl FrameMmbm {
    /// Blur length over the exposure, px: exposure MMBM x `t_e` / pitch.
    pub fn blur_px(&self, cam: &Camera) -> Option<f64> {
        self.exposure_mm_s
            .map(|m| crate::camera::blur_px(m, self.exposure_s, cam.pitch_x_mm))
    }
}

/// The buffers of a frames run's window means, built once per run and
/// reused: the values at a window's samples and their [`Integral`] (no
/// allocation in the `exact` integrand once warm).
#[derive(Default)]
struct Window {
    /// The values at the window's samples.
    y: Vec<f64>,
    integral: Integral,
}

impl Window {
    /// Mean over `[a, b]` of the piecewise-linear function through
    /// `(t[i], y[i])` (`t` increasing, covering `[a, b]`); the value at `a`
    /// when `b <= a`.
    fn mean(&mut self, t: &[f64], a: f64, b: f64) -> f64 {
        self.integral.rebuild(t, &self.y);
        self.integral.mean(a, b)
    }

    /// [`Window::mean`] of the values `y`.
    fn mean_of(&mut self, t: &[f64], y: impl IntoIterator<Item = f64>, a: f64, b: f64) -> f64 {
        self.y.clear();
        self.y.extend(y);
        self.mean(t, a, b)
    }
}

/// The rule's nodes grouped by line: (delay per second of readout, rule of
/// that line's nodes with their share of the weights).
fn line_groups(cam: &Camera, method: Method) -> Result<Vec<(f64, GridRule)>> {
    let rect = cam.sensor_rect();
    let (pts, w) = match method {
        Method::Riemann { nu, nv } => riemann_points(&rect, nu, nv),
        Method::Gauss { nu, nv } => gauss_points(&rect, nu, nv),
        _ => unreachable!("grid rules only"),
    };
    let unit = Shutter {
        readout_s: 1.0,
        direction: cam.shutter.direction,
    };
    // Per line (keyed by the delay's bits): delay, points, weights.
    type Line = (f64, Vec<(f64, f64)>, Vec<f64>);
    let mut groups: BTreeMap<u64, Line> = BTreeMap::new();
    for (&(u, v), &wk) in pts.iter().zip(&w) {
        let (px, py) = cam.mm_to_pixel(u, v);
        let d = unit.delay_s(px, py, cam.width, cam.height);
        let g = groups.entry(d.to_bits()).or_insert((d, vec![], vec![]));
        g.1.push((u, v));
        g.2.push(wk);
    }
    groups
        .into_values()
        .map(|(d, p, w)| Ok((d, GridRule::from_points(&p, &w).distorted(cam)?)))
        .collect()
}

/// Exposure MMBM (and the instantaneous MMBM at the start) of every frame.
/// A frame's readout is its own (`readout_s` of the table) or else the
/// camera's. Frames whose window `[t_start, t_start + t_r + t_e]` is not
/// inside the log get `None` values; their indices are returned as well.
/// Every frame is checked first ([`VideoFrame::check`]).
pub fn frame_mmbm(
    samples: &[GyroSample],
    opts: &SeriesOptions,
    frames: &[VideoFrame],
) -> Result<(Vec<FrameMmbm>, Vec<usize>)> {
    let cam = opts.scene.camera;
    cam.validate()?;
    if samples.len() < 2 {
        return Err(Error::invalid("gyro log", "needs at least 2 samples"));
    }
    check_times(samples, "gyro log")?;
    let groups = match opts.method {
        Method::Riemann { .. } | Method::Gauss { .. } => Some(line_groups(&cam, opts.method)?),
        Method::Exact { .. } => None,
    };
    let t: Vec<f64> = samples.iter().map(|s| s.t).collect();
    let (first, last) = (t[0], t[t.len() - 1]);
    // One set of window buffers for the whole run (the `exact` integrand
    // borrows it for each point).
    let window = std::cell::RefCell::new(Window::default());
    let mut out = Vec::with_capacity(frames.len());
    let mut outside = Vec::new();
    for (k, f) in frames.iter().enumerate() {
        crate::cancel::check()?;
        f.check()
            .map_err(|(column, message)| Error::invalid(format!("frame {k}: {column}"), message))?;
        let readout = f.readout_s.unwrap_or(cam.shutter.readout_s);
        if readout > 0.0 && groups.is_none() {
            return Err(Error::invalid(
                "method",
                format!(
                    "exact is not available with a rolling shutter (frame {k}: readout {readout} s): \
                     the {} lines each have their own window, so the integrand jumps at every line; \
                     use riemann with one node per line, e.g. riemann:64x{}, exact in time per line",
                    if cam.shutter.direction.is_rows() { cam.height } else { cam.width },
                    if cam.shutter.direction.is_rows() { cam.height } else { cam.width },
                ),
            ));
        }
        let (a, b) = (f.t_start, f.t_start + readout + f.exposure_s);
        let mut r = FrameMmbm {
            frame: k,
            t_start: f.t_start,
            exposure_s: f.exposure_s,
            readout_s: readout,
            exposure_mm_s: None,
            start_mm_s: None,
        };
        if a < first || b > last {
            outside.push(k);
            out.push(r);
            continue;
        }
        // Samples bracketing the whole window.
        let lo = t.partition_point(|&s| s <= a).saturating_sub(1);
        let hi = t.partition_point(|&s| s < b).min(t.len() - 1);
        let ts = &t[lo..=hi];
        let polys = samples[lo..=hi]
            .iter()
            .map(|s| sample_scene(s, opts).map(|(tw, sc)| sc.flow_poly(&tw)))
            .collect::<Result<Vec<FlowPoly>>>()?;
        let (exposure, start) = match &groups {
            Some(groups) => {
                let mut total = vec![0.0; polys.len()];
                let mut e = 0.0;
                for (delay, rule) in groups {
                    let y: Vec<f64> = polys.iter().map(|p| rule.mean_speed(p)).collect();
                    for (tot, yi) in total.iter_mut().zip(&y) {
                        *tot += yi;
                    }
                    let w0 = a + readout * delay;
                    e += window.borrow_mut().mean_of(ts, y, w0, w0 + f.exposure_s);
                }
                (e, window.borrow_mut().mean_of(ts, total, a, a))
            }
            None => {
                let Method::Exact { tol } = opts.method else {
                    unreachable!()
                };
                let shutter = Shutter {
                    readout_s: readout,
                    direction: cam.shutter.direction,
                };
                let e = exact_with(
                    |u, v| {
                        let (px, py) = cam.mm_to_pixel(u, v);
                        let w0 = a + shutter.delay_s(px, py, cam.width, cam.height);
                        let y = polys.iter().map(|p| point_speed(&cam, p, u, v));
                        window.borrow_mut().mean_of(ts, y, w0, w0 + f.exposure_s)
                    },
                    &cam.sensor_rect(),
                    tol,
                )
                .value;
                let m: Vec<f64> = polys
                    .iter()
                    .map(|p| crate::metric::mmbm_poly(&cam, p, opts.method).map(|m| m.mm_s))
                    .collect::<Result<_>>()?;
                (e, window.borrow_mut().mean_of(ts, m, a, a))
            }
        };
        if !(exposure.is_finite() && start.is_finite()) {
            return Err(Error::invalid(
                format!("frame {k} (t_start = {} s)", f.t_start),
                "the exposure MMBM is not finite (rates near the float range?)",
            ));
        }
        // The blur in px must be a number too (what `blur_px` then gives).
        crate::camera::checked_blur_px(exposure, f.exposure_s, cam.pitch_x_mm).map_err(|e| {
            Error::invalid(
                format!("frame {k} (t_start = {} s)", f.t_start),
                e.to_string(),
            )
        })?;
        r.exposure_mm_s = Some(exposure);
        r.start_mm_s = Some(start);
        out.push(r);
    }
    Ok((out, outside))
}

/// The `n` frames with the least blur whose starts are at least `gap_s`
/// apart (greedy, sharpest first; frames without a value are never chosen),
/// in frame order.
pub fn select_sharpest(frames: &[FrameMmbm], cam: &Camera, n: usize, gap_s: f64) -> Vec<usize> {
    let mut order: Vec<(f64, usize)> = frames
        .iter()
        .filter_map(|f| f.blur_px(cam).map(|b| (b, f.frame)))
        .collect();
    order.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let mut picked: Vec<usize> = Vec::new();
    for (_, k) in order {
        if picked.len() == n {
            break;
        }
        let tk = frames[k].t_start;
        if picked
            .iter()
            .all(|&j| (frames[j].t_start - tk).abs() >= gap_s)
        {
            picked.push(k);
        }
    }
    picked.sort_unstable();
    picked
}
