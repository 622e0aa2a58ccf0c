//! Per-pixel blur fields of video frames (`mmbm frames --maps`): for every
//! pixel of a frame, the image track of the scene point seen at its centre
//! at its own line's exposure start, followed over that line's exposure
//! (rolling shutter: each line its own window, docs/spec.md section 9), on the renderer's
//! motion ([`Trajectory::from_imu_log`]: the twist interpolated linearly
//! between gyro samples and integrated on SO(3)). No image is rendered.
//!
//! Per line the motion from the line's start to each of `steps + 1` instants
//! is one rotation `M_k` (and, with the log's velocity, one offset `b_k`), so
//! a pixel's track is `project(M_k r + b_k / s)` for its undistorted ray `r`
//! (cached per camera, [`MapRays`]) and its scene point's depth along the ray
//! `s`. The path is the sum of the track's chords, the displacement its end
//! minus its start. The scene: rotation only (points at infinity) unless
//! `use_velocity`; then a plane fixed in the world, given in the camera
//! frame at the frame's start (the options' plane, else the log's `depth`
//! at the frame's start as a fronto-parallel plane), as `render` has its
//! target.
//!
//! Pixels beyond the camera's radial distortion limit
//! ([`Camera::is_masked_mm`]), whose ray does not undistort, or whose scene
//! point is lost (behind the camera or off the plane) are NaN in every
//! channel.

pub mod gpu;
pub mod kernel;
mod line;
pub mod table;
pub mod write;

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::io::frames::VideoFrame;
pub use crate::limits::MAX_MAP_PIXELS;
use crate::model::log::ImuLog;
use crate::model::motion::Plane;
use crate::model::track::LineTrack;
use crate::model::trajectory::Trajectory;
use crate::series::window::FrameWindow;
use crate::series::SeriesOptions;
use line::LineMotion;
use rayon::prelude::*;

/// Channels of a frame's maps, in the EXR's order of [`FrameMaps::channels`].
pub const CHANNELS: [&str; 5] = ["disp.u", "disp.v", "path_px", "flow.u", "flow.v"];

/// The blur fields of one frame, row-major, top row first, `width * height`
/// values each (NaN where a pixel has none, see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameMaps {
    /// 0-based row of the frame table.
    pub frame: usize,
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Exposure of each line, s.
    pub exposure_s: f64,
    /// Rolling-shutter readout used, s.
    pub readout_s: f64,
    /// Chords per line's exposure.
    pub steps: usize,
    /// Displacement from the line's exposure start to its end, x (columns), px.
    pub disp_u: Vec<f32>,
    /// Displacement, y (rows, down), px.
    pub disp_v: Vec<f32>,
    /// Path length over the line's exposure, px.
    pub path_px: Vec<f32>,
    /// Image flow at the line's exposure start, x, px/s.
    pub flow_u: Vec<f32>,
    /// Image flow at the line's exposure start, y, px/s.
    pub flow_v: Vec<f32>,
}

impl FrameMaps {
    /// `(name, values)` of every channel ([`CHANNELS`]).
    pub fn channels(&self) -> [(&'static str, &[f32]); 5] {
        [
            (CHANNELS[0], &self.disp_u),
            (CHANNELS[1], &self.disp_v),
            (CHANNELS[2], &self.path_px),
            (CHANNELS[3], &self.flow_u),
            (CHANNELS[4], &self.flow_v),
        ]
    }

    /// Writes the maps as a float EXR (atomically: temp file and rename).
    pub fn write_exr(&self, path: &std::path::Path) -> Result<()> {
        crate::io::images::write_exr(
            path,
            self.width as usize,
            self.height as usize,
            &self.channels(),
        )
    }

    /// Writes the channels `which` (indices into [`CHANNELS`], in that
    /// order) as an EXR of half floats (`half`) or floats, ZIP-compressed
    /// (atomically: temp file and rename).
    pub fn write_exr_as(&self, path: &std::path::Path, half: bool, which: &[usize]) -> Result<()> {
        let all = self.channels();
        let chosen: Vec<(&str, &[f32])> =
            which.iter().filter_map(|&i| all.get(i).copied()).collect();
        crate::io::images::write_exr_as(
            path,
            self.width as usize,
            self.height as usize,
            &chosen,
            half,
        )
    }

    /// Mean path length over the pixels that have one (px; the frame's
    /// exposure MMBM as a blur length) and their share of the pixels.
    pub fn mean_path_px(&self) -> (f64, f64) {
        let (mut s, mut n) = (0.0f64, 0usize);
        for &p in self.path_px.iter().filter(|p| p.is_finite()) {
            s += p as f64;
            n += 1;
        }
        (
            s / n.max(1) as f64,
            n as f64 / self.path_px.len().max(1) as f64,
        )
    }
}

/// The undistorted ray `(x, y)` (normalised, `z = 1`) through every pixel
/// centre of a camera, row-major; NaN where the pixel is masked or does not
/// undistort. Built once per video (the lens's iterative undistortion).
#[derive(Debug, Clone)]
pub struct MapRays {
    camera: Camera,
    rays: Vec<(f64, f64)>,
}

impl MapRays {
    /// The rays of `cam` (validated, at most [`MAX_MAP_PIXELS`]: checked
    /// before anything is allocated).
    pub fn new(cam: &Camera) -> Result<Self> {
        check_size(cam)?;
        cam.validate()?;
        let w = cam.width as usize;
        let rays = (0..w * cam.height as usize)
            .into_par_iter()
            .with_min_len(4096)
            .map(|idx| {
                let (x, y) = ((idx % w) as f64 + 0.5, (idx / w) as f64 + 0.5);
                let (ud, vd) = cam.pixel_to_mm(x, y);
                if cam.is_masked_mm(ud, vd) {
                    return (f64::NAN, f64::NAN);
                }
                cam.pixel_to_ray(x, y).unwrap_or((f64::NAN, f64::NAN))
            })
            .collect();
        Ok(MapRays { camera: *cam, rays })
    }

    /// The camera the rays are of.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The rays, row-major (NaN: none).
    pub fn rays(&self) -> &[(f64, f64)] {
        &self.rays
    }
}

/// Refuses a camera of more than [`MAX_MAP_PIXELS`] pixels for blur maps
/// (before anything is sized by it; every backend and door calls it).
pub fn check_size(cam: &Camera) -> Result<()> {
    crate::limits::check_pixels(
        "camera",
        "a frame's blur maps (frames --maps)",
        cam.width as u64,
        cam.height as u64,
        MAX_MAP_PIXELS,
    )
}

/// The chords per line's exposure for `traj`'s motion: about one per pixel
/// of the largest image motion (a bound from the largest rotation rate of
/// the log in the frame's span, at the sensor corner, plus translation at
/// the plane's nearest corner), 16 to 2048.
fn auto_steps(cam: &Camera, log: &ImuLog, a: f64, b: f64, te: f64, inv_depth: f64) -> usize {
    let lo = log.partition_point(|s| s.t <= a).saturating_sub(1);
    let hi = log.partition_point(|s| s.t < b).min(log.len() - 1);
    let (mut w, mut v) = (0.0f64, 0.0f64);
    for s in &log[lo..=hi] {
        w = w.max(s.omega.length());
        v = v.max(s.velocity.map_or(0.0, |v| v.length()));
    }
    let r = cam.sensor_rect();
    let corner2 = r.u0.abs().max(r.u1.abs()).powi(2) + r.v0.abs().max(r.v1.abs()).powi(2);
    let fpx = cam.fx_px().max(cam.fy_px());
    let px = (w * (1.0 + corner2 / (cam.focal_mm * cam.focal_mm)) + v * inv_depth) * fpx * te;
    (px.ceil() as usize).clamp(16, 2048)
}

/// True when `[a, b]` lies inside the log and crosses no gap in it (an
/// interval much longer than the median, where no motion is known: the
/// renderer's rule, [`Trajectory::from_imu_log`]).
fn covers(log: &ImuLog, a: f64, b: f64) -> bool {
    match (log.first(), log.last()) {
        (Some(f), Some(l)) if log.len() >= 2 && a >= f.t && b <= l.t => {}
        _ => return false,
    }
    let median = log.median_interval().unwrap_or(0.0);
    let lo = log.partition_point(|s| s.t <= a).saturating_sub(1);
    let hi = log.partition_point(|s| s.t < b).min(log.len() - 1);
    !log[lo..=hi]
        .windows(2)
        .any(|w| w[1].t > a && w[0].t < b && crate::model::log::is_gap(w[1].t - w[0].t, median))
}

/// The scene plane of a frame's maps (world = camera frame at `t_start`),
/// `None` for rotation only (see the module docs).
fn world_plane(log: &ImuLog, opts: &SeriesOptions, t_start: f64) -> Result<Option<Plane>> {
    if !opts.use_velocity {
        return Ok(None);
    }
    let k = log.partition_point(|s| s.t <= t_start).saturating_sub(1);
    match (log[k].depth, opts.scene.plane) {
        (_, Some(p)) => Ok(Some(p)),
        (Some(z), None) => Ok(Some(Plane::fronto(z))),
        (None, None) => Err(Error::invalid(
            "depth",
            "translation needs a scene depth: a 'depth' column in the log or --depth",
        )),
    }
}

/// What every line of a frame's maps shares: the frame's motion, scene
/// and chord count ([`plan`]).
pub(crate) struct Plan {
    pub cam: Camera,
    /// Frame start (s, log clock), exposure and readout (s).
    pub t_start: f64,
    pub exposure_s: f64,
    pub readout_s: f64,
    pub traj: Trajectory,
    pub plane: Option<Plane>,
    /// Chords per line's exposure.
    pub steps: usize,
    /// Lines are rows (else columns).
    pub rows: bool,
}

/// One frame's maps to compute: the arguments of [`frame_maps`], as the
/// GPU path and its twin take them
/// ([`gpu::MapsRunner::frame_maps`],
/// [`kernel::frame_maps_twin`]).
#[derive(Clone, Copy)]
pub struct MapsJob<'a> {
    /// The motion.
    pub log: &'a ImuLog,
    /// Camera, scene and velocity (the method is not used).
    pub opts: &'a SeriesOptions,
    /// The camera's rays (built for `opts.scene.camera`).
    pub rays: &'a MapRays,
    /// Row of the frame in its table.
    pub index: usize,
    /// The frame.
    pub frame: &'a VideoFrame,
    /// Chords per line's exposure (`None`: about one per pixel of motion).
    pub steps: Option<usize>,
}

/// The plan of a job's frame (see [`frame_maps`]), `None` when its span is
/// not inside the log or crosses a gap in it.
pub(crate) fn plan(job: &MapsJob) -> Result<Option<Plan>> {
    let (log, opts, index, frame) = (job.log, job.opts, job.index, job.frame);
    let cam = opts.scene.camera;
    if job.rays.camera != cam {
        return Err(Error::invalid(
            "maps",
            "the rays were built for another camera than the options'",
        ));
    }
    let win = FrameWindow::of(&cam, index, frame)?;
    let (te, readout) = (win.exposure_s, win.readout_s());
    let (a, b) = (win.t_start, win.end_s());
    if !covers(log, a, b) {
        return Ok(None);
    }
    let at = |e: Error| Error::invalid(format!("frame {index} (t_start = {a} s)"), e.to_string());
    let traj = Trajectory::from_imu_log(log, a, win.span_s(), opts.use_velocity).map_err(at)?;
    let plane = world_plane(log, opts, a)?;
    if let Some(p) = &plane {
        p.validate_for(&cam).map_err(at)?;
    }
    let inv_depth = plane.map_or(0.0, |p| {
        let r = cam.sensor_rect();
        [(r.u0, r.v0), (r.u0, r.v1), (r.u1, r.v0), (r.u1, r.v1)]
            .iter()
            .map(|&(u, v)| p.inverse_depth(cam.focal_mm, u, v).abs())
            .fold(0.0, f64::max)
    });
    let steps = job
        .steps
        .unwrap_or_else(|| auto_steps(&cam, log, a, b, te, inv_depth))
        .max(1);
    Ok(Some(Plan {
        cam,
        t_start: a,
        exposure_s: te,
        readout_s: readout,
        traj,
        plane,
        steps,
        rows: cam.shutter.direction.is_rows(),
    }))
}

impl Plan {
    /// Lines of the frame and pixels per line.
    pub fn lines(&self) -> (usize, usize) {
        let (w, h) = (self.cam.width as usize, self.cam.height as usize);
        if self.rows {
            (h, w)
        } else {
            (w, h)
        }
    }

    /// The motion of line `l` over its exposure.
    pub fn line(&self, log: &ImuLog, l: usize) -> LineMotion {
        let shutter = crate::camera::Shutter {
            readout_s: self.readout_s,
            direction: self.cam.shutter.direction,
        };
        // The line's window and poses: the one per-pixel track's.
        let track = LineTrack::line(
            &self.traj,
            &shutter,
            &self.cam,
            l,
            self.exposure_s,
            self.steps,
        );
        LineMotion::new(log, &track, self.plane.as_ref(), &self.cam, self.t_start)
    }

    /// The maps of frame `index` from its channels, row-major.
    pub fn finish(&self, index: usize, ch: [Vec<f32>; 5]) -> FrameMaps {
        let [disp_u, disp_v, path_px, flow_u, flow_v] = ch;
        FrameMaps {
            frame: index,
            width: self.cam.width,
            height: self.cam.height,
            exposure_s: self.exposure_s,
            readout_s: self.readout_s,
            steps: self.steps,
            disp_u,
            disp_v,
            path_px,
            flow_u,
            flow_v,
        }
    }
}

/// The blur fields of `frame` (row `index` of its table) from `log` with
/// the camera of `rays` (which must be `opts.scene.camera`) and `opts`' scene
/// and velocity (its method is not used): `None` when the frame's span
/// `[t_start, t_start + readout + exposure]` is not inside the log or
/// crosses a gap in it (no motion is known there). `steps`:
/// chords per line's exposure (`None`: about one per pixel of motion, at
/// least 16). The readout is the frame's own, else the camera's. In f64 on
/// the CPU (rayon); the GPU path is [`gpu`].
pub fn frame_maps(
    log: &ImuLog,
    opts: &SeriesOptions,
    rays: &MapRays,
    index: usize,
    frame: &VideoFrame,
    steps: Option<usize>,
) -> Result<Option<FrameMaps>> {
    let job = MapsJob {
        log,
        opts,
        rays,
        index,
        frame,
        steps,
    };
    let Some(plan) = plan(&job)? else {
        return Ok(None);
    };
    let cam = plan.cam;
    let rows = plan.rows;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let len = plan.lines().1;
    let stop = crate::cancel::current();
    let mut vals = vec![[f32::NAN; 5]; w * h];
    vals.par_chunks_mut(len).enumerate().for_each(|(l, out)| {
        if stop.is_cancelled() {
            return;
        }
        let line = line::Line::from(plan.line(log, l));
        let ray = |m: usize| {
            let (i, j) = if rows { (m, l) } else { (l, m) };
            rays.rays[j * w + i]
        };
        if cam.distortion.is_none() {
            line.pinhole(&cam, ray, out);
            return;
        }
        for (m, o) in out.iter_mut().enumerate() {
            if let Some(v) = line.pixel(&cam, ray(m)) {
                *o = v;
            }
        }
    });
    crate::cancel::check()?;
    let mut ch: [Vec<f32>; 5] = Default::default();
    for (k, c) in ch.iter_mut().enumerate() {
        *c = if rows {
            vals.iter().map(|v| v[k]).collect()
        } else {
            (0..w * h)
                .map(|idx| vals[(idx % w) * h + idx / w][k])
                .collect()
        };
    }
    Ok(Some(plan.finish(index, ch)))
}
