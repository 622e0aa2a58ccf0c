//! The gyro-to-video clock offset from the video itself (`mmbm sync`), as
//! Gyroflow finds it: the image motion measured between consecutive frames
//! against the motion the gyro's rotation predicts through the camera's
//! intrinsics (roll included), over candidate offsets.
//!
//! - [`decode`]: the video through `ffprobe` / `ffmpeg` subprocesses,
//!   streamed as small grey frames (never the whole clip);
//! - [`track`]: the motion of a grid of patches between two frames;
//! - [`search`]: the offset and rolling-shutter readout that explain it best,
//!   with a confidence.
//!
//! Sign: video time = gyro time + `offset_s`, the value `frames
//! --time-offset` takes (it is added to the gyro's times).

pub use crate::video::decode;
pub mod plan;
pub mod report;
pub mod search;
pub mod track;

use crate::camera::Camera;
use crate::camera::{Readout, Shutter};
use crate::error::{show_path, Error, Result};
use crate::model::flow::flow_distorted;
use crate::model::log::ImuLog;
use crate::model::motion::Twist;
use glam::DVec3;
use search::{Angle, LineObs, PairObs, Problem};
use std::path::Path;

pub use report::{read_sync_file, SyncFile};

/// What `sync` is asked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SyncOptions {
    /// Exposure of every frame, s (the middle of each line's exposure is its time).
    pub exposure_s: f64,
    /// Offset at the middle of the search, s.
    pub centre_s: f64,
    /// Half width of the search, s.
    pub search_s: f64,
}

/// The offset found, with what it was found from.
#[derive(Debug, Clone)]
pub struct SyncOutcome {
    /// The search's estimate.
    pub estimate: search::Estimate,
    /// Frames decoded.
    pub frames: usize,
    /// Windows of consecutive frames decoded (1: the whole clip; [`plan`]).
    pub windows: usize,
    /// Share of the patches tracked (textured and matched), 0..1.
    pub tracked_share: f64,
    /// RMS of the tracked patches' motion between frames, px at the analysis size.
    pub motion_rms_px: f64,
    /// The analysis size, px.
    pub analysis_size: (u32, u32),
    /// The video's first and last presentation time, s.
    pub video_span: (f64, f64),
    /// The gyro log's first and last time, s.
    pub gyro_span: (f64, f64),
    /// The camera's shutter with the log's own rolling-shutter readout, when
    /// it was applied ([`ImuLog::apply_readout`]: the camera had none).
    pub log_shutter: Option<Shutter>,
}

/// Least RMS motion between frames for an offset to be told at all, px at
/// the analysis size: below it the confidence is 0.
const MIN_MOTION_RMS_PX: f64 = 0.05;
/// Least share of tracked patches over the clip.
const MIN_TRACKED_SHARE: f64 = 0.02;

/// The readout line fraction (0 first line read, 1 last) of analysis pixel
/// `(x, y)` on a `w x h` image.
fn line_fraction(dir: Readout, x: f64, y: f64, w: f64, h: f64) -> f64 {
    match dir {
        Readout::TopToBottom => y / h,
        Readout::BottomToTop => 1.0 - y / h,
        Readout::LeftToRight => x / w,
        Readout::RightToLeft => 1.0 - x / w,
    }
}

/// The error for a video and a log that never overlap within the search.
fn no_overlap(video: &Path, v: (f64, f64), g: (f64, f64), o: &SyncOptions) -> Error {
    let suggest = 0.5 * (v.0 + v.1) - 0.5 * (g.0 + g.1);
    Error::invalid(
        show_path(video),
        format!(
            "no {} frame pairs lie inside the gyro log at any offset within {} +- {} s: the video \
             spans {:.3} to {:.3} s (its clock), the gyro log {:.3} to {:.3} s (its clock); their \
             middles meet at --time-offset={suggest:.3} (give it, or a wider --search)",
            search::MIN_PAIRS,
            o.centre_s,
            o.search_s,
            v.0,
            v.1,
            g.0,
            g.1
        ),
    )
}

/// Where the patches lie and what their motion means, at the analysis size.
struct Geometry<'a> {
    size: (u32, u32),
    centres: &'a [(f64, f64)],
    /// Each patch's flow per radian about x, y, z (analysis px / rad).
    jac: &'a [[DVec3; 2]],
    /// The readout line fractions, and each patch's.
    lines: &'a [f64],
    line_of: &'a [usize],
}

/// The motion measured in one run of decoded frames.
struct Measured {
    /// Presentation times of the frames, s.
    times: Vec<f64>,
    /// (index of the pair's first frame in `times`, its observations).
    pairs: Vec<(usize, Vec<LineObs>)>,
    tracked: usize,
    tried: usize,
    /// Sum of the tracked patches' squared motion, px^2.
    m2: f64,
}

/// Decodes `window` of `video` (None: the whole clip) and tracks the patches
/// from each frame to the next.
fn measure(video: &Path, g: &Geometry, window: Option<decode::Window>) -> Result<Measured> {
    let (w, h) = g.size;
    let mut out = Measured {
        times: Vec::new(),
        pairs: Vec::new(),
        tracked: 0,
        tried: 0,
        m2: 0.0,
    };
    let mut prev: Option<track::Pyramid> = None;
    let each = |fi: usize, px: &[u8]| -> Result<()> {
        crate::cancel::check()?;
        let cur = track::Pyramid::new(track::Gray::from_u8(w as usize, h as usize, px));
        if let Some(p) = &prev {
            use rayon::prelude::*;
            let found: Vec<Option<(f64, f64)>> = g
                .centres
                .par_iter()
                .map(|&c| track::track_patch(p, &cur, c))
                .collect();
            let mut obs: Vec<LineObs> = g
                .lines
                .iter()
                .map(|&line| LineObs {
                    line,
                    ..Default::default()
                })
                .collect();
            for (i, f) in found.iter().enumerate() {
                out.tried += 1;
                if let Some(m) = *f {
                    out.tracked += 1;
                    out.m2 += m.0 * m.0 + m.1 * m.1;
                    obs[g.line_of[i]].add(g.jac[i], m);
                }
            }
            out.pairs.push((fi - 1, obs));
        }
        prev = Some(cur);
        Ok(())
    };
    out.times = match window {
        None => decode::decode(video, g.size, each)?,
        Some(win) => decode::decode_window(video, g.size, win, each)?,
    };
    Ok(out)
}

/// Finds the offset between `log` (its own clock, no offset applied) and
/// `video`, whose frames `camera` took (scaled to the video's size; with
/// the log's own rolling-shutter readout where it has none,
/// [`SyncOutcome::log_shutter`]), decoding about
/// [`plan::DEFAULT_DECODE_FRAMES`] frames of a long clip ([`sync_decoding`]).
pub fn sync(video: &Path, log: &ImuLog, camera: &Camera, o: &SyncOptions) -> Result<SyncOutcome> {
    sync_decoding(video, log, camera, o, plan::DEFAULT_DECODE_FRAMES)
}

/// [`sync`] decoding about `budget` frames of a clip of more than twice
/// that many, in windows from keyframes spread over it ([`plan::plan`]);
/// 0: every frame.
pub fn sync_decoding(
    video: &Path,
    log: &ImuLog,
    camera: &Camera,
    o: &SyncOptions,
    budget: usize,
) -> Result<SyncOutcome> {
    let (camera, from_log) = log.apply_readout(*camera)?;
    let log_shutter = from_log.then_some(camera.shutter);
    let info = decode::probe(video)?;
    let frame_dt = 1.0 / info.fps;
    let samples = log.samples();
    let angle = Angle::new(samples.iter().map(|s| (s.t, s.omega)));
    let gyro_span = angle.span();
    search::check_log_length("gyro log", gyro_span, frame_dt)?;
    // Before decoding: can the clip's span meet the log's at any offset?
    let v_span = (info.start_s, info.start_s + info.duration_s);
    let need = search::MIN_PAIRS as f64 * frame_dt;
    let overlap = |off: f64| v_span.1.min(gyro_span.1 + off) - v_span.0.max(gyro_span.0 + off);
    let steps = 2000;
    let best = (0..=steps)
        .map(|i| o.centre_s - o.search_s + 2.0 * o.search_s * i as f64 / steps as f64)
        .chain(
            [v_span.0 - gyro_span.0, v_span.1 - gyro_span.1]
                .into_iter()
                .map(|x| x.clamp(o.centre_s - o.search_s, o.centre_s + o.search_s)),
        )
        .map(overlap)
        .fold(f64::NEG_INFINITY, f64::max);
    if best < need {
        return Err(no_overlap(video, v_span, gyro_span, o));
    }
    let (w, h) = info.analysis_size();
    let cam = camera.fitted_to(info.width, info.height);
    let (sx, sy) = (w as f64 / info.width as f64, h as f64 / info.height as f64);
    let centres = track::grid(w as usize, h as usize);
    // Each patch's flow per radian about x, y, z (analysis px / rad) and line.
    let jac: Vec<[DVec3; 2]> = centres
        .iter()
        .map(|&(x, y)| {
            let (u, v) = cam.pixel_to_mm((x + 0.5) / sx, (y + 0.5) / sy);
            let mut j = [DVec3::ZERO; 2];
            for (axis, w) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
                let (du, dv) = flow_distorted(&cam, u, v, &Twist::new(w, DVec3::ZERO), None)
                    .unwrap_or((0.0, 0.0));
                let (px, py) = cam.mm_to_px_velocity(du, dv);
                j[0][axis] = px * sx;
                j[1][axis] = py * sy;
            }
            j
        })
        .collect();
    let mut lines: Vec<f64> = Vec::new();
    let line_of: Vec<usize> = centres
        .iter()
        .map(|&(x, y)| {
            let l = line_fraction(cam.shutter.direction, x + 0.5, y + 0.5, w as f64, h as f64);
            match lines.iter().position(|&m| (m - l).abs() < 1e-9) {
                Some(i) => i,
                None => {
                    lines.push(l);
                    lines.len() - 1
                }
            }
        })
        .collect();
    let windows = if budget > 0 && info.duration_s * info.fps > 2.0 * budget as f64 {
        let (packets, keys) = plan::keyframes(video)?;
        plan::plan(packets, &keys, info.start_s, info.fps, budget)
    } else {
        None
    };
    let geometry = Geometry {
        size: (w, h),
        centres: &centres,
        jac: &jac,
        lines: &lines,
        line_of: &line_of,
    };
    let n_windows = windows.as_ref().map_or(1, Vec::len);
    // The windows decode and track at once (one ffmpeg each; two cores are
    // kept busy by two windows), each its own pairs.
    let per_window: Vec<Result<Measured>> = {
        use rayon::prelude::*;
        (0..n_windows)
            .into_par_iter()
            .map(|k| measure(video, &geometry, windows.as_ref().map(|ws| ws[k])))
            .collect()
    };
    let mut motions: Vec<(usize, Vec<LineObs>)> = Vec::new();
    let mut times: Vec<f64> = Vec::new();
    let (mut tracked, mut tried, mut m2) = (0usize, 0usize, 0.0f64);
    for m in per_window {
        let m = m?;
        let base = times.len();
        motions.extend(m.pairs.into_iter().map(|(i, o)| (base + i, o)));
        times.extend(m.times);
        tracked += m.tracked;
        tried += m.tried;
        m2 += m.m2;
    }
    let frames = times.len();
    let pairs: Vec<PairObs> = motions
        .into_iter()
        .map(|(k, lines)| PairObs {
            t_prev: times[k],
            t_cur: times[k + 1],
            lines: lines
                .into_iter()
                .filter(|l| l.c > 0.0 || l.h[0] > 0.0)
                .collect(),
        })
        .collect();
    let video_span = (
        times.first().copied().unwrap_or(v_span.0),
        times.last().copied().unwrap_or(v_span.1),
    );
    let tracked_share = if tried > 0 {
        tracked as f64 / tried as f64
    } else {
        0.0
    };
    if frames < 2 || tracked_share < MIN_TRACKED_SHARE {
        return Err(Error::invalid(
            show_path(video),
            format!(
                "too little texture to measure the image motion: {tracked} of {tried} patches \
                 tracked over {frames} frames (sync needs at least {:.0} %)",
                100.0 * MIN_TRACKED_SHARE
            ),
        ));
    }
    let problem = Problem {
        obs: &pairs,
        angle: &angle,
        exposure_s: o.exposure_s,
    };
    let mut estimate = search::estimate(&problem, o.centre_s, o.search_s, frame_dt)
        .map_err(|_| no_overlap(video, video_span, gyro_span, o))?;
    let motion_rms_px = (m2 / tracked.max(1) as f64).sqrt();
    if motion_rms_px < MIN_MOTION_RMS_PX {
        estimate.confidence = 0.0;
    }
    Ok(SyncOutcome {
        estimate,
        frames,
        windows: n_windows,
        tracked_share,
        motion_rms_px,
        analysis_size: (w, h),
        video_span,
        gyro_span,
        log_shutter,
    })
}
