//! The camera's motion over one frame ([`FrameMotion`]: a constant twist or
//! a window of a gyro log), turned once into a trajectory spanning the
//! camera's busy time (exposure plus rolling-shutter readout,
//! [`crate::camera::Shutter::busy_s`]), so callers (the CLI, Python, the
//! dataset code, [`super::RenderJob::for_motion`]) never derive the span
//! themselves; and the camera a log's frame is taken with
//! ([`FrameMotion::camera`]: the log's own rolling-shutter readout applied).

use crate::camera::Camera;
use crate::error::Result;
use crate::model::log::ImuLog;
use crate::model::motion::Twist;
use crate::model::trajectory::Trajectory;

/// Where the camera's motion over one frame comes from.
#[derive(Debug, Clone, Copy)]
pub enum FrameMotion<'a> {
    /// A constant twist (angular velocity rad/s, linear velocity m/s).
    Twist(Twist),
    /// A gyro log, from `at_s` (s, the log's clock) on; linear velocity from
    /// the log when `use_velocity` (it must have it).
    Log {
        /// The log (validated).
        log: &'a ImuLog,
        /// Start of the first line's exposure, s.
        at_s: f64,
        /// Also integrate the log's linear velocity.
        use_velocity: bool,
    },
}

impl FrameMotion<'_> {
    /// The camera a frame of this motion is taken with: for a log's motion,
    /// `camera` with the log's own rolling-shutter readout where the camera
    /// has none ([`ImuLog::apply_readout`], the one place a log's readout is
    /// applied); `camera` unchanged for a twist. Returns the camera and
    /// whether the log's readout was applied.
    pub fn camera(&self, camera: Camera) -> Result<(Camera, bool)> {
        match *self {
            FrameMotion::Twist(_) => Ok((camera, false)),
            FrameMotion::Log { log, .. } => log.apply_readout(camera),
        }
    }

    /// The trajectory over a frame of `camera` exposed `exposure_s` s per line:
    /// it spans `camera.shutter.busy_s(exposure_s)` (the first line's exposure
    /// start to the last line's exposure end).
    pub fn trajectory(&self, camera: &Camera, exposure_s: f64) -> Result<Trajectory> {
        crate::check::positive("exposure", exposure_s)?;
        let span = camera.shutter.busy_s(exposure_s);
        match *self {
            FrameMotion::Twist(tw) => Trajectory::from_twist(tw, span),
            FrameMotion::Log {
                log,
                at_s,
                use_velocity,
            } => Trajectory::from_imu_log(log, at_s, span, use_velocity),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{RenderJob, Target};
    use glam::DVec3;

    fn rolling() -> Camera {
        let mut cam = Camera::thesis();
        cam.shutter.readout_s = 0.02;
        cam
    }

    /// The trajectory spans exposure + readout (0.01 + 0.02 s), the job's
    /// timing check accepts it, and a trajectory over the exposure alone
    /// (what a caller that forgot the readout would build) is refused.
    #[test]
    fn a_job_spans_the_exposure_plus_the_readout() {
        let tw = Twist::new(DVec3::new(0.1, 0.2, 0.3), DVec3::ZERO);
        let target = Target::checker(0.05, 2.0);
        let job =
            RenderJob::for_motion(rolling(), 0.01, FrameMotion::Twist(tw), target.clone()).unwrap();
        assert!((job.trajectory.duration() - 0.03).abs() < 1e-15);
        job.check_timing().unwrap();
        let short = Trajectory::from_twist(tw, 0.01).unwrap();
        let bad = RenderJob::new(rolling(), 0.01, short, target);
        let e = bad.check_timing().unwrap_err().to_string();
        assert!(e.contains("readout"), "{e}");
    }

    /// A log window starts at `at_s` and spans the busy time too; a window
    /// past the log's end is an error, not a panic.
    #[test]
    fn a_log_window_spans_the_busy_time() {
        let s = |t| crate::model::log::GyroSample {
            t,
            omega: DVec3::new(0.0, 0.0, 1.0),
            velocity: None,
            depth: None,
        };
        let log = ImuLog::new((0..100).map(|k| s(k as f64 * 0.005)).collect()).unwrap();
        let at = |at_s| FrameMotion::Log {
            log: &log,
            at_s,
            use_velocity: false,
        };
        let traj = at(0.1).trajectory(&rolling(), 0.01).unwrap();
        assert!((traj.duration() - 0.03).abs() < 1e-15);
        assert!(at(0.48).trajectory(&rolling(), 0.01).is_err());
        assert!(at(0.1).trajectory(&rolling(), 0.0).is_err());
    }

    /// A log's own readout reaches the job's camera through
    /// [`RenderJob::for_motion`] (a global shutter takes it, the span grows
    /// by it); a rolling camera keeps its own; a twist leaves the camera be.
    #[test]
    fn a_log_readout_reaches_the_job_once() {
        use crate::model::log::LogReadout;
        let s = |t| crate::model::log::GyroSample {
            t,
            omega: DVec3::new(0.0, 0.0, 1.0),
            velocity: None,
            depth: None,
        };
        let log = ImuLog::new((0..100).map(|k| s(k as f64 * 0.005)).collect())
            .unwrap()
            .with_readout(Some(LogReadout {
                readout_s: 0.015,
                direction: None,
            }));
        let motion = FrameMotion::Log {
            log: &log,
            at_s: 0.1,
            use_velocity: false,
        };
        let target = Target::checker(0.05, 2.0);
        let job = RenderJob::for_motion(Camera::thesis(), 0.01, motion, target.clone()).unwrap();
        assert_eq!(job.camera.shutter.readout_s, 0.015);
        assert!((job.trajectory.duration() - 0.025).abs() < 1e-15);
        job.check_timing().unwrap();
        let job = RenderJob::for_motion(rolling(), 0.01, motion, target).unwrap();
        assert_eq!(job.camera.shutter.readout_s, 0.02);
        let tw = FrameMotion::Twist(Twist::new(DVec3::X, DVec3::ZERO));
        assert!(!tw.camera(Camera::thesis()).unwrap().1);
        assert!(motion.camera(Camera::thesis()).unwrap().1);
    }
}
