//! The frames of a video and their maps, assembled once (as
//! [`crate::trigger::Session`] assembles a trigger run): [`FramesJob`] is the
//! camera with a log's own rolling-shutter readout applied once
//! ([`LogReadout::apply`]), the scene, the method and the velocity switch;
//! [`FrameWindow`] is one frame's time window on the log's clock, its span
//! the camera's busy time ([`crate::camera::Shutter::busy_s`]: exposure plus the frame's
//! readout, docs/spec.md section 9). `mmbm frames`, Python's `frames` and
//! `frame_maps`, [`super::frames::frame_mmbm`] and [`super::maps`] take their
//! windows from here and derive no span themselves.

use super::frames::{frame_mmbm, FrameMmbm};
use super::maps::{frame_maps, FrameMaps, MapRays};
pub use super::window::FrameWindow;
use super::SeriesOptions;
use crate::camera::Camera;
use crate::error::Result;
use crate::io::frames::VideoFrame;
use crate::io::gyro::GyroSample;
use crate::metric::{Method, Scene};
use crate::model::log::{ImuLog, LogReadout};
use crate::model::motion::Plane;

/// What a [`FramesJob`] is made of.
#[derive(Debug, Clone, Copy)]
pub struct FramesConfig {
    /// The camera (before a log's readout is applied).
    pub camera: Camera,
    /// The scene plane, if any (with `use_velocity` and no depth column).
    pub plane: Option<Plane>,
    /// The CPU metric method of the frames' exposure MMBM (not used by the maps).
    pub method: Method,
    /// Include the log's linear velocity.
    pub use_velocity: bool,
}

/// The frames of a video and their maps, assembled and checked: the camera
/// (with the log's readout applied once), the scene, the method.
#[derive(Debug, Clone, Copy)]
pub struct FramesJob {
    series: SeriesOptions,
    readout_from_log: bool,
}

impl FramesJob {
    /// Assembles a job: `log_readout` (a log's own rolling-shutter readout,
    /// e.g. a Gyroflow `.gcsv` header's, [`ImuLog::readout`]) applies when
    /// the camera has none ([`LogReadout::apply`]); the camera is validated.
    pub fn new(cfg: FramesConfig, log_readout: Option<LogReadout>) -> Result<Self> {
        let (camera, readout_from_log) = LogReadout::apply(log_readout, cfg.camera)?;
        camera.validate()?;
        Ok(FramesJob {
            series: SeriesOptions {
                scene: Scene {
                    camera,
                    plane: cfg.plane,
                },
                method: cfg.method,
                use_velocity: cfg.use_velocity,
            },
            readout_from_log,
        })
    }

    /// The job with its camera replaced by `f`'s result (validated): a
    /// caller's own fallback readout after the log's (`mmbm frames --sync`).
    pub fn map_camera(mut self, f: impl FnOnce(Camera) -> Camera) -> Result<Self> {
        let camera = f(self.series.scene.camera);
        camera.validate()?;
        self.series.scene.camera = camera;
        Ok(self)
    }

    /// The camera (with the log's readout when it was applied).
    pub fn camera(&self) -> &Camera {
        &self.series.scene.camera
    }

    /// Whether the log's readout was applied to the camera.
    pub fn readout_from_log(&self) -> bool {
        self.readout_from_log
    }

    /// The series options: scene, method, velocity.
    pub fn series(&self) -> &SeriesOptions {
        &self.series
    }

    /// The window of `frame`, row `index` of its table ([`FrameWindow::of`]).
    pub fn window(&self, index: usize, frame: &VideoFrame) -> Result<FrameWindow> {
        FrameWindow::of(self.camera(), index, frame)
    }

    /// The window of every frame, in table order (the first bad frame is an
    /// error naming it).
    pub fn windows(&self, frames: &[VideoFrame]) -> Result<Vec<FrameWindow>> {
        frames
            .iter()
            .enumerate()
            .map(|(k, f)| self.window(k, f))
            .collect()
    }

    /// The exposure MMBM of every frame and the indices of those whose
    /// window leaves the log ([`frame_mmbm`]).
    pub fn mmbm(
        &self,
        samples: &[GyroSample],
        frames: &[VideoFrame],
    ) -> Result<(Vec<FrameMmbm>, Vec<usize>)> {
        frame_mmbm(samples, &self.series, frames)
    }

    /// The rays of the job's camera, for its maps ([`MapRays::new`]).
    pub fn rays(&self) -> Result<MapRays> {
        MapRays::new(self.camera())
    }

    /// The blur fields of every frame in f64 on the CPU ([`frame_maps`]),
    /// `None` where a frame's span leaves the log or crosses a gap in it.
    pub fn maps(
        &self,
        log: &ImuLog,
        frames: &[VideoFrame],
        steps: Option<usize>,
    ) -> Result<Vec<Option<FrameMaps>>> {
        let rays = self.rays()?;
        frames
            .iter()
            .enumerate()
            .map(|(k, f)| frame_maps(log, &self.series, &rays, k, f, steps))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Readout;
    use glam::DVec3;

    fn config(camera: Camera) -> FramesConfig {
        FramesConfig {
            camera,
            plane: None,
            method: Method::Riemann { nu: 8, nv: 6 },
            use_velocity: false,
        }
    }

    fn frame(t_start: f64, exposure_s: f64, readout_s: Option<f64>) -> VideoFrame {
        VideoFrame {
            t_start,
            exposure_s,
            readout_s,
        }
    }

    /// A log with a readout (16 ms, bottom to top) and a camera without:
    /// the readout is applied once, and each window is the hand computation
    /// `[t_start, t_start + exposure + readout]`; a frame's own readout wins.
    #[test]
    fn the_log_readout_applies_once_and_the_span_is_exposure_plus_readout() {
        let log_readout = LogReadout {
            readout_s: 0.016,
            direction: Some(Readout::BottomToTop),
        };
        let job = FramesJob::new(config(Camera::thesis()), Some(log_readout)).unwrap();
        assert!(job.readout_from_log());
        assert_eq!(job.camera().shutter.readout_s, 0.016);
        assert_eq!(job.camera().shutter.direction, Readout::BottomToTop);
        let w = job
            .windows(&[frame(1.5, 0.004, None), frame(2.0, 0.01, Some(0.03))])
            .unwrap();
        assert_eq!(
            (w[0].index, w[0].t_start, w[0].readout_s()),
            (0, 1.5, 0.016)
        );
        assert!((w[0].span_s() - 0.020).abs() < 1e-15);
        assert!((w[0].end_s() - 1.520).abs() < 1e-12);
        assert_eq!(w[0].shutter.direction, Readout::BottomToTop);
        assert_eq!((w[1].index, w[1].readout_s()), (1, 0.03));
        assert!((w[1].span_s() - 0.040).abs() < 1e-15);
        assert!((w[1].end_s() - 2.040).abs() < 1e-12);
        // The span is the shutter's busy time, not a sum of its own.
        assert_eq!(w[0].span_s(), job.camera().shutter.busy_s(0.004));
    }

    /// A camera with its own readout keeps it (the log's does not apply);
    /// without a log readout a global camera stays global (span = exposure).
    #[test]
    fn the_cameras_readout_wins_and_global_spans_the_exposure() {
        let mut cam = Camera::thesis();
        cam.shutter.readout_s = 0.02;
        let log_readout = Some(LogReadout {
            readout_s: 0.016,
            direction: None,
        });
        let job = FramesJob::new(config(cam), log_readout).unwrap();
        assert!(!job.readout_from_log());
        let w = job.window(3, &frame(0.0, 0.01, None)).unwrap();
        assert!((w.span_s() - 0.03).abs() < 1e-15);
        let global = FramesJob::new(config(Camera::thesis()), None).unwrap();
        assert!(!global.readout_from_log());
        let w = global.window(0, &frame(0.5, 0.01, None)).unwrap();
        assert_eq!((w.readout_s(), w.span_s(), w.end_s()), (0.0, 0.01, 0.51));
    }

    /// A bad frame is an error naming its row and column; a bad log readout
    /// is refused when the job is assembled.
    #[test]
    fn bad_frames_and_readouts_are_errors() {
        let job = FramesJob::new(config(Camera::thesis()), None).unwrap();
        let e = job
            .windows(&[frame(0.0, 0.01, None), frame(1.0, -0.01, None)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("frame 1") && e.contains("exposure_s"), "{e}");
        let bad = Some(LogReadout {
            readout_s: f64::NAN,
            direction: None,
        });
        assert!(FramesJob::new(config(Camera::thesis()), bad).is_err());
    }

    /// The job's exposure MMBM is the library's, on the job's camera: a
    /// frame of a constant rotation about the optical axis under a 16 ms
    /// log readout equals `frame_mmbm` with that readout on the camera.
    #[test]
    fn the_jobs_mmbm_uses_the_readout_once() {
        let s = |t| GyroSample {
            t,
            omega: DVec3::new(0.2, -0.1, 0.5),
            velocity: None,
            depth: None,
        };
        let samples: Vec<GyroSample> = (0..200).map(|k| s(k as f64 * 0.005)).collect();
        let log_readout = Some(LogReadout {
            readout_s: 0.016,
            direction: None,
        });
        let job = FramesJob::new(config(Camera::thesis()), log_readout).unwrap();
        let frames = [frame(0.1, 0.01, None), frame(0.99, 0.01, None)];
        let (rows, outside) = job.mmbm(&samples, &frames).unwrap();
        // The second frame's window [0.99, 1.016] leaves the log (last 0.995).
        assert_eq!(outside, vec![1]);
        assert_eq!(rows[0].readout_s, 0.016);
        let mut cam = Camera::thesis();
        cam.shutter.readout_s = 0.016;
        let mut opts = *job.series();
        opts.scene.camera = cam;
        let (direct, _) = frame_mmbm(&samples, &opts, &frames).unwrap();
        assert_eq!(rows, direct);
    }
}
