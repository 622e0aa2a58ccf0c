//! A gyro log rendered as a video (`mmbm clip`): frame `k` starts at
//! `t_k = start + k / fps` (s, the log's clock) and is rendered by the
//! renderer of this module's parent over its own exposure (plus the
//! rolling-shutter readout, [`super::FrameMotion`]), with the camera's
//! orientation **carried** from frame to frame: the log's rotation
//! integrated from the clip's start to `t_k`, so the camera turns over the
//! target as it did in the log (a single render always starts facing it).
//!
//! The world frame is the camera's frame at the clip's start (the target is
//! placed in it as `mmbm render` places it at an exposure start). Frame
//! `k`'s trajectory is `q_k * q(t)` with `q_k` the carried orientation and
//! `q(t)` the frame's own rotation from its exposure start; rotation only
//! (the log's angular rate; the camera stays at the origin).
//!
//! Each frame comes with its true blur: the per-pixel blur maps
//! ([`super::maps`], whose path length is the blur length in px) and their
//! summary ([`FrameTruth`]: mean, median and largest path, px).

use super::clip_panorama::{self, Panorama};
use super::{render_frame, Backend, BlurMaps, FrameMotion, Quality, RenderJob, Target};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::limits::{CLIP_MAX_FPS, CLIP_MAX_FRAMES, CLIP_MAX_PIXELS};
use crate::model::log::ImuLog;
use crate::model::trajectory::{Pose, Trajectory};
use glam::DQuat;
use std::sync::Arc;

/// What the clip's camera looks at.
#[derive(Debug, Clone)]
pub enum ClipTarget {
    /// A plane of the renderer ([`Target`]), placed in the camera's frame at
    /// the clip's start.
    Plane(Target),
    /// An equirectangular panorama at infinity ([`Panorama`]): any rotation.
    Panorama(Arc<Panorama>),
}

/// Poses per frame of the carried trajectory (linear between them: far
/// under a millipixel apart for any exposure the renderer takes).
const CARRIED_POSES: usize = 2048;

/// What to render: a log over a target, at a rate, exposure and readout
/// (the camera's shutter).
#[derive(Debug, Clone)]
pub struct Clip<'a> {
    /// Camera intrinsics and shutter (its `readout_s` gives the rolling
    /// shutter's line delays).
    pub camera: Camera,
    /// The gyro log (validated; its clock is the clip's).
    pub log: &'a ImuLog,
    /// Frame rate, frames/s (> 0, at most [`CLIP_MAX_FPS`]).
    pub fps: f64,
    /// Exposure of each line, s (> 0, at most one frame period).
    pub exposure_s: f64,
    /// Start of frame 0's first line's exposure, s (the log's clock).
    pub start_s: f64,
    /// Number of frames (1 to [`CLIP_MAX_FRAMES`]).
    pub frames: usize,
    /// The target: a plane placed in the camera's frame at the clip's
    /// start, or a panorama at infinity.
    pub target: ClipTarget,
    /// Sampling quality of each frame.
    pub quality: Quality,
    /// Where frames are rendered.
    pub backend: Backend,
}

/// One frame's true blur and pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameTruth {
    /// Frame number, 0-based.
    pub frame: usize,
    /// Start of the first line's exposure, s (the log's clock).
    pub t_start_s: f64,
    /// Mean blur length over the pixels that see the target, px.
    pub mean_px: f64,
    /// Median blur length, px.
    pub p50_px: f64,
    /// Largest blur length, px.
    pub max_px: f64,
    /// Share of pixels with a tracked scene point (0..1).
    pub valid: f64,
    /// Camera-to-world rotation at the exposure start (the world: the
    /// camera's frame at the clip's start).
    pub orientation: DQuat,
}

impl FrameTruth {
    /// The header of [`Self::csv_row`].
    pub const CSV_HEADER: &'static str =
        "frame,t_start_s,blur_mean_px,blur_p50_px,blur_max_px,valid,qw,qx,qy,qz";

    /// One row of `truth.csv`.
    pub fn csv_row(&self) -> String {
        let q = self.orientation;
        format!(
            "{},{:.9},{:.6},{:.6},{:.6},{:.6},{:.12},{:.12},{:.12},{:.12}",
            self.frame,
            self.t_start_s,
            self.mean_px,
            self.p50_px,
            self.max_px,
            self.valid,
            q.w,
            q.x,
            q.y,
            q.z
        )
    }
}

/// A rendered frame of a clip.
#[derive(Debug, Clone)]
pub struct ClipFrame {
    /// Its true blur and pose.
    pub truth: FrameTruth,
    /// sRGB 8-bit R, G, B, row-major, top row first.
    pub rgb8: Vec<u8>,
    /// Its per-pixel blur maps.
    pub maps: BlurMaps,
}

/// Mean, median and largest of the finite values of `path` (px); NaN when
/// none is finite.
pub fn summary(path: &[f32]) -> (f64, f64, f64) {
    let mut v: Vec<f32> = path.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let mean = v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64;
    let max = v.iter().copied().fold(f32::MIN, f32::max) as f64;
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    (mean, *m as f64, max)
}

impl Clip<'_> {
    /// Frame `k`'s exposure start, s.
    pub fn t_start(&self, k: usize) -> f64 {
        self.start_s + k as f64 / self.fps
    }

    /// Checks everything before any work: rate, exposure (at most one frame
    /// period), frame count, frame size, the target against the camera, and
    /// a log that covers the whole clip (both spans named when not).
    pub fn check(&self) -> Result<()> {
        if !(self.fps.is_finite() && self.fps > 0.0 && self.fps <= CLIP_MAX_FPS) {
            return Err(Error::invalid(
                "--fps",
                format!(
                    "{}: must be > 0 and at most {CLIP_MAX_FPS} frames/s",
                    self.fps
                ),
            ));
        }
        let period = 1.0 / self.fps;
        if !(self.exposure_s.is_finite() && self.exposure_s > 0.0 && self.exposure_s <= period) {
            return Err(Error::invalid(
                "--exposure",
                format!(
                    "{} s: must be > 0 and at most one frame period ({period:.6} s at {} fps)",
                    self.exposure_s, self.fps
                ),
            ));
        }
        if self.frames == 0 || self.frames > CLIP_MAX_FRAMES {
            return Err(Error::invalid(
                "--duration",
                format!(
                    "gives {} frames at {} fps: a clip has 1 to {CLIP_MAX_FRAMES} frames",
                    self.frames, self.fps
                ),
            ));
        }
        let px = self.camera.width as u64 * self.camera.height as u64;
        if px > CLIP_MAX_PIXELS {
            return Err(Error::invalid(
                "--resolution",
                format!(
                    "{}x{} = {px} px per frame: a clip frame has at most {CLIP_MAX_PIXELS} px",
                    self.camera.width, self.camera.height
                ),
            ));
        }
        crate::video::encode::check_format((self.camera.width, self.camera.height), self.fps)?;
        crate::check::finite("--start", self.start_s)?;
        if let ClipTarget::Plane(t) = &self.target {
            t.validate_for(&self.camera)?;
        }
        let busy = self.camera.shutter.busy_s(self.exposure_s);
        let (a, b) = (self.start_s, self.t_start(self.frames - 1) + busy);
        let s = self.log.samples();
        let (first, last) = (s[0].t, s[s.len() - 1].t);
        if a < first || b > last {
            return Err(Error::invalid(
                "--gyro",
                format!(
                    "the clip spans [{a:.6}, {b:.6}] s ({} frames at {} fps from --start, each \
                     busy {busy:.6} s), but the log covers [{first:.6}, {last:.6}] s: choose \
                     --start and --duration inside it",
                    self.frames, self.fps
                ),
            ));
        }
        Ok(())
    }

    /// Frame `k`'s trajectory over its busy time, starting at `orientation`.
    pub fn frame_trajectory(&self, k: usize, orientation: DQuat) -> Result<Trajectory> {
        let own = FrameMotion::Log {
            log: self.log,
            at_s: self.t_start(k),
            use_velocity: false,
        }
        .trajectory(&self.camera, self.exposure_s)?;
        let poses: Vec<Pose> = own
            .table(CARRIED_POSES)
            .into_iter()
            .map(|(q, c)| ((orientation * q).normalize(), orientation * c))
            .collect();
        Trajectory::from_poses(own.duration(), poses)
    }

    /// The rotation from `t_k` to `t_{k+1}` (one frame period), integrated
    /// from the log.
    fn step(&self, k: usize) -> Result<DQuat> {
        let period = 1.0 / self.fps;
        let t = Trajectory::from_imu_log(self.log, self.t_start(k), period, false)?;
        Ok(t.pose_at(period).0)
    }

    /// Renders frame `k` at the carried `orientation`.
    pub fn render_one(&self, k: usize, orientation: DQuat) -> Result<ClipFrame> {
        let traj = self.frame_trajectory(k, orientation)?;
        let (rgb, maps) = match &self.target {
            ClipTarget::Plane(target) => {
                let mut job = RenderJob::new(self.camera, self.exposure_s, traj, target.clone());
                job.quality = self.quality;
                job.backend = self.backend;
                job.seed = k as u32;
                job.with_maps = true;
                let out = render_frame(&job)?;
                let maps = out
                    .maps
                    .ok_or_else(|| Error::invalid("clip", "the renderer gave no blur maps"))?;
                (out.rgb, maps)
            }
            ClipTarget::Panorama(pano) => {
                let cam = &self.camera;
                let (mut rgb, _) = clip_panorama::render(
                    cam,
                    pano,
                    &traj,
                    self.exposure_s,
                    self.quality,
                    k as u32,
                )?;
                if let Some(noise) = &cam.noise {
                    noise.apply(&mut rgb, self.exposure_s, k as u64)?;
                }
                // Rotation only: the image motion does not depend on depth, so
                // the maps of the frame's own rotation over any plane in front
                // (every ray of the view meets it) are those of infinity.
                let own = FrameMotion::Log {
                    log: self.log,
                    at_s: self.t_start(k),
                    use_velocity: false,
                }
                .trajectory(cam, self.exposure_s)?;
                let lmax = clip_panorama::max_path_px(cam, &own);
                let steps = ((lmax / 0.25).ceil() as usize).clamp(64, 4096);
                let plane = Target::checker(1.0, 1.0);
                let maps = super::maps::blur_maps(cam, &plane, &own, self.exposure_s, steps);
                crate::cancel::check()?;
                (rgb, maps)
            }
        };
        let (mean_px, p50_px, max_px) = summary(&maps.path_px);
        let valid = maps.means().valid;
        let rgb8 = rgb
            .iter()
            .map(|&x| crate::io::images::linear_to_srgb8(x))
            .collect();
        Ok(ClipFrame {
            truth: FrameTruth {
                frame: k,
                t_start_s: self.t_start(k),
                mean_px,
                p50_px,
                max_px,
                valid,
                orientation,
            },
            rgb8,
            maps,
        })
    }

    /// Renders every frame in order, the orientation carried, and hands
    /// each to `each` (then drops it: one frame in memory). Checks first.
    pub fn render(&self, mut each: impl FnMut(ClipFrame) -> Result<()>) -> Result<()> {
        self.check()?;
        let mut q = DQuat::IDENTITY;
        for k in 0..self.frames {
            crate::cancel::check()?;
            let frame = self.render_one(k, q)?;
            each(frame)?;
            if k + 1 < self.frames {
                q = (q * self.step(k)?).normalize();
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::log::GyroSample;
    use glam::DVec3;

    fn log(omega: DVec3, secs: f64) -> ImuLog {
        let n = (secs * 200.0) as usize;
        ImuLog::new(
            (0..=n)
                .map(|k| GyroSample {
                    t: k as f64 / 200.0,
                    omega,
                    velocity: None,
                    depth: None,
                })
                .collect(),
        )
        .unwrap()
    }

    fn clip(log: &ImuLog) -> Clip<'_> {
        let mut camera = Camera::thesis();
        camera.width = 64;
        camera.height = 48;
        Clip {
            camera,
            log,
            fps: 30.0,
            exposure_s: 0.01,
            start_s: 0.1,
            frames: 10,
            target: ClipTarget::Plane(Target::checker(0.1, 2.0)),
            quality: Quality::Fast,
            backend: Backend::Cpu { threads: None },
        }
    }

    /// The orientation carried over k frames of a constant rate is the
    /// rotation by omega k / fps (closed form), and a frame's trajectory
    /// starts there.
    #[test]
    fn orientation_is_carried() {
        let w = DVec3::new(0.0, 0.6, 0.2);
        let l = log(w, 2.0);
        let c = clip(&l);
        let mut q = DQuat::IDENTITY;
        for k in 0..5 {
            q = (q * c.step(k).unwrap()).normalize();
        }
        let want = DQuat::from_scaled_axis(w * 5.0 / 30.0);
        assert!(q.angle_between(want) < 1e-9, "{q:?} vs {want:?}");
        let t = c.frame_trajectory(5, q).unwrap();
        assert!(t.pose_at(0.0).0.angle_between(want) < 1e-9);
    }

    #[test]
    fn bad_clips_refused_before_work() {
        let l = log(DVec3::ZERO, 1.0);
        let mut c = clip(&l);
        c.fps = 0.0;
        assert!(c.check().unwrap_err().to_string().contains("--fps"));
        let mut c = clip(&l);
        c.exposure_s = 0.05;
        assert!(c.check().unwrap_err().to_string().contains("--exposure"));
        let mut c = clip(&l);
        c.frames = 100;
        let e = c.check().unwrap_err().to_string();
        assert!(e.contains("--gyro") && e.contains("covers"), "{e}");
        let mut c = clip(&l);
        c.frames = CLIP_MAX_FRAMES + 1;
        assert!(c.check().unwrap_err().to_string().contains("--duration"));
        assert_eq!(summary(&[1.0, f32::NAN, 3.0, 2.0]), (2.0, 2.0, 3.0));
        assert!(summary(&[f32::NAN]).0.is_nan());
    }
}
