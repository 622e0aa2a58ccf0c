//! The exposure MMBM of video frames (docs/spec.md sections 3 and 9): for a frame
//! starting at `t0` with exposure `t_e` and rolling-shutter readout `t_r`,
//! line `j` of `n` is exposed over `[t0 + t_r j / n, t0 + t_r j / n + t_e]`,
//! and the frame's exposure MMBM is the sensor mean of each point's flow
//! speed averaged over its own line's window (mm/s). Blur length in pixels is
//! the same mean of the true pixel speed (px/s, [`crate::Mmbm::px_s`]: mm/s
//! over the pitch with square, unskewed pixels) times `t_e`.
//!
//! Time: the motion is the renderer's (`model::trajectory`), the twist
//! interpolated linearly between gyro samples, so at a sensor point the flow
//! is linear in time between samples and the speed is the length of that
//! interpolated flow, integrated in closed form ([`super::lerp`]); it is at
//! most the interpolation of the speeds at the samples (equal where the flow
//! does not turn). With a log's `depth` column the flow (which has `v / z`)
//! is interpolated, not the depth.
//! Space: the method's rule (`riemann`, `gauss`: nodes grouped by line, each
//! group averaged over its window; `riemann:Wx<lines>` has a node on every
//! line). `exact` (adaptive cubature of the window-averaged speed) is for
//! global shutters only: with a readout the integrand jumps at every line.

use super::lerp::{instant_speed, window_speed};
use super::window::FrameWindow;
use super::{sample_scene, SeriesOptions};
use crate::camera::{Camera, Shutter};
use crate::error::{Error, Result};
use crate::io::frames::VideoFrame;
use crate::io::gyro::GyroSample;
use crate::metric::{exact_with, gauss_points, riemann_points, GridRule, Method};
use crate::model::flow::FlowPoly;
use crate::model::log::{check_resolution, check_times, max_abs_time};
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
    /// Exposure MMBM as the true pixel speed, px/s (the same mean of each
    /// point's speed in px/s; `exposure_mm_s / pitch` with square, unskewed
    /// pixels).
    pub exposure_px_s: Option<f64>,
    /// Instantaneous MMBM at `t_start`, mm/s (`None` outside the log).
    pub start_mm_s: Option<f64>,
}

impl FrameMmbm {
    /// Blur length over the exposure, px: the exposure MMBM in px/s x `t_e`.
    pub fn blur_px(&self) -> Option<f64> {
        self.exposure_px_s.map(|p| p * self.exposure_s)
    }

    /// The last line's exposure end, s: `t_start` plus the shutter's busy
    /// time ([`FrameWindow::end_s`]).
    pub fn end_s(&self) -> f64 {
        let shutter = Shutter {
            readout_s: self.readout_s,
            ..Shutter::global()
        };
        self.t_start + shutter.busy_s(self.exposure_s)
    }
}

/// The flow (mm/s on the distorted sensor) of each of `polys` at the
/// distorted sensor point `(ud, vd)` mm, undistorted once; NaN where it does
/// not undistort (the caller reports a non-finite result).
fn point_flows(cam: &Camera, polys: &[FlowPoly], ud: f64, vd: f64, out: &mut Vec<(f64, f64)>) {
    out.clear();
    if cam.distortion.is_none() {
        out.extend(polys.iter().map(|p| p.eval(ud, vd)));
        return;
    }
    match cam.undistort_mm(ud, vd) {
        Some((u, v)) => {
            let j = cam.distortion_jacobian(u, v);
            out.extend(
                polys
                    .iter()
                    .map(|p| crate::camera::distortion::apply(&j, p.eval(u, v))),
            );
        }
        None => out.extend(polys.iter().map(|_| (f64::NAN, f64::NAN))),
    }
}

/// The rule's nodes grouped by line: (delay per second of readout, rule of
/// that line's nodes, and the factor that gives its weights their share of
/// the unmasked sensor's: [`GridRule::distorted`] rescales a lens's line to
/// weights summing to 1, so its factor is the line's unmasked weight over
/// every line's; 1 without a lens). Lines masked whole are left out.
fn line_groups(cam: &Camera, method: Method) -> Result<Vec<(f64, GridRule, f64)>> {
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
    let lens = !cam.distortion.is_none();
    let mut out = Vec::with_capacity(groups.len());
    let mut total = 0.0;
    for (d, p, w) in groups.into_values() {
        let kept: f64 = p
            .iter()
            .zip(&w)
            .filter(|(&(u, v), _)| !cam.is_masked_mm(u, v))
            .map(|(_, &x)| x)
            .sum();
        if lens && kept == 0.0 {
            continue;
        }
        total += kept;
        out.push((d, GridRule::from_points(&p, &w).distorted(cam)?, kept));
    }
    if lens && total <= 0.0 {
        return Err(Error::invalid(
            "distortion",
            "every node of the rule lies beyond the lens's radial distortion limit",
        ));
    }
    for g in &mut out {
        g.2 = if lens { g.2 / total } else { 1.0 };
    }
    Ok(out)
}

/// Checks every frame ([`VideoFrame::check`]) and that the time stamps of
/// the log and the frames resolve each frame's exposure (and readout):
/// the rule of `trigger` ([`check_resolution`]), so that nanosecond epoch
/// stamps read as seconds are refused with a hint at `--time-unit`, not
/// turned into confident blur.
fn check_frame_times(samples: &[GyroSample], frames: &[VideoFrame]) -> Result<()> {
    let t_max = frames
        .iter()
        .map(|f| f.t_start.abs())
        .fold(max_abs_time(samples), f64::max);
    for (k, f) in frames.iter().enumerate() {
        f.check()
            .map_err(|(column, message)| Error::invalid(format!("frame {k}: {column}"), message))?;
        check_resolution(t_max, f.exposure_s, &format!("frame {k}'s exposure"))?;
        if let Some(r) = f.readout_s {
            check_resolution(t_max, r, &format!("frame {k}'s readout"))?;
        }
    }
    Ok(())
}

/// Exposure MMBM (and the instantaneous MMBM at the start) of every frame.
/// A frame's readout is its own (`readout_s` of the table) or else the
/// camera's. Frames whose window ([`FrameWindow`]: `[t_start, t_start + t_e + t_r]`) is not
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
    check_frame_times(samples, frames)?;
    let groups = match opts.method {
        Method::Riemann { .. } | Method::Gauss { .. } => Some(line_groups(&cam, opts.method)?),
        Method::Exact { .. } => None,
    };
    let t: Vec<f64> = samples.iter().map(|s| s.t).collect();
    let (first, last) = (t[0], t[t.len() - 1]);
    // Non-square or skewed pixels: the px/s speeds are averaged too.
    let map = crate::metric::pixel_map(&cam);
    let to_px = |m: [f64; 4], f: &mut (f64, f64)| {
        *f = (m[0] * f.0 + m[1] * f.1, m[2] * f.0 + m[3] * f.1);
    };
    // Buffers reused by every frame: the rule's weights and flows at the
    // samples (grid rules), one point's flows (the `exact` integrand).
    let (mut weights, mut flows) = (Vec::new(), Vec::new());
    let point_buf = std::cell::RefCell::new(Vec::new());
    let mut out = Vec::with_capacity(frames.len());
    let mut outside = Vec::new();
    for (k, f) in frames.iter().enumerate() {
        crate::cancel::check()?;
        // The frame's window: its own readout, else the camera's; the span
        // is the shutter's busy time (super::job).
        let win = FrameWindow::of(&cam, k, f)?;
        let readout = win.readout_s();
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
        let (a, b) = (win.t_start, win.end_s());
        let mut r = FrameMmbm {
            frame: k,
            t_start: f.t_start,
            exposure_s: f.exposure_s,
            readout_s: readout,
            exposure_mm_s: None,
            exposure_px_s: None,
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
        let (exposure, exposure_px, start) = match &groups {
            Some(groups) => {
                let (mut e, mut e_px, mut start) = (0.0, 0.0, 0.0);
                for (delay, rule, share) in groups {
                    // Each node's flow at each sample (sample-major), once.
                    weights.clear();
                    weights.extend(rule.node_flows(&polys[0]).map(|(w, _)| w * share));
                    flows.clear();
                    for p in &polys {
                        flows.extend(rule.node_flows(p).map(|(_, f)| f));
                    }
                    let w0 = a + readout * delay;
                    e += window_speed(ts, &flows, &weights, w0, w0 + f.exposure_s);
                    start += instant_speed(ts, &flows, &weights, a);
                    if let Some(m) = map {
                        flows.iter_mut().for_each(|x| to_px(m, x));
                        e_px += window_speed(ts, &flows, &weights, w0, w0 + f.exposure_s);
                    }
                }
                (e, e_px, start)
            }
            None => {
                let Method::Exact { tol } = opts.method else {
                    unreachable!()
                };
                let shutter = win.shutter;
                // Beyond the lens's radial distortion limit no ray: 0 there,
                // and the mean over the unmasked share (as `exact` does).
                let valid = cam.valid_fraction();
                let window = |m: Option<[f64; 4]>| {
                    exact_with(
                        |u, v| {
                            if cam.is_masked_mm(u, v) {
                                return 0.0;
                            }
                            let (px, py) = cam.mm_to_pixel(u, v);
                            let w0 = a + shutter.delay_s(px, py, cam.width, cam.height);
                            let mut buf = point_buf.borrow_mut();
                            point_flows(&cam, &polys, u, v, &mut buf);
                            if let Some(m) = m {
                                buf.iter_mut().for_each(|x| to_px(m, x));
                            }
                            window_speed(ts, &buf, &[1.0], w0, w0 + f.exposure_s)
                        },
                        &cam.sensor_rect(),
                        tol,
                    )
                    .value
                        / valid
                };
                let e = window(None);
                let e_px = map.map_or(0.0, |m| window(Some(m)));
                // The MMBM of the interpolated motion at the start: the
                // twist (so the flow poly) interpolated to `a`.
                let k = ts.partition_point(|&s| s <= a).clamp(1, ts.len() - 1) - 1;
                let s = ((a - ts[k]) / (ts[k + 1] - ts[k])).clamp(0.0, 1.0);
                let lerp =
                    |x: &[f64; 6], y: &[f64; 6]| std::array::from_fn(|i| x[i] + s * (y[i] - x[i]));
                let p = FlowPoly {
                    du: lerp(&polys[k].du, &polys[k + 1].du),
                    dv: lerp(&polys[k].dv, &polys[k + 1].dv),
                };
                let m = crate::metric::mmbm_poly(&cam, &p, opts.method)?.mm_s;
                (e, e_px, m)
            }
        };
        if !(exposure.is_finite() && start.is_finite()) {
            return Err(Error::invalid(
                format!("frame {k} (t_start = {} s)", f.t_start),
                "the exposure MMBM is not finite (rates near the float range?)",
            ));
        }
        // The blur in px must be a number too (what `blur_px` then gives).
        let exposure_px = match map {
            None => crate::camera::checked_px_s(exposure, cam.pitch_x_mm),
            Some(_) => Ok(exposure_px),
        }
        .and_then(|px| crate::camera::checked_blur_of_px_s(px, f.exposure_s).map(|_| px))
        .map_err(|e| {
            Error::invalid(
                format!("frame {k} (t_start = {} s)", f.t_start),
                e.to_string(),
            )
        })?;
        r.exposure_mm_s = Some(exposure);
        r.exposure_px_s = Some(exposure_px);
        r.start_mm_s = Some(start);
        out.push(r);
    }
    Ok((out, outside))
}

/// The `n` frames with the least blur whose starts are at least `gap_s`
/// apart (greedy, sharpest first; frames without a value are never chosen),
/// in frame order.
pub fn select_sharpest(frames: &[FrameMmbm], n: usize, gap_s: f64) -> Vec<usize> {
    let mut order: Vec<(f64, usize)> = frames
        .iter()
        .filter_map(|f| f.blur_px().map(|b| (b, f.frame)))
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
