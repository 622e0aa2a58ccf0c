//! The camera's timing (thesis Fig. 5.1), a triggered [`Frame`], and the
//! exposure average of the MMBM series ([`Integral`]).

use super::spec::PolicySpec;
use crate::error::{Error, Result};
pub use crate::model::log::Integral;

/// Camera timing (thesis Fig. 5.1), seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraTiming {
    /// Decision-to-exposure delay `t_d` (thesis: 2-3 ms).
    pub delay: f64,
    /// Exposure `t_e` (thesis: 50 and 70 ms).
    pub exposure: f64,
    /// Readout after the exposure `t_r`; the camera is busy until it ends.
    pub readout: f64,
    /// Minimum interval between triggers of the MMBM-triggered policies.
    pub min_interval: f64,
    /// Pixel pitch, mm: turns an MMBM (mm/s) times an exposure into a blur
    /// length in px for exposure control (`+exp:B`).
    pub pitch_mm: f64,
}

impl Default for CameraTiming {
    /// Delay 2.5 ms, exposure 70 ms (thesis ch. 6), readout 12.5 ms (a
    /// 640 x 480 Flea2 at its 80 fps maximum; an assumption, the thesis gives
    /// none), minimum interval 0.2 s, the thesis camera's 4.65 um pitch.
    fn default() -> Self {
        CameraTiming {
            delay: Self::DEFAULT_DELAY_S,
            exposure: Self::DEFAULT_EXPOSURE_S,
            readout: Self::DEFAULT_READOUT_S,
            min_interval: Self::DEFAULT_MIN_INTERVAL_S,
            pitch_mm: Self::DEFAULT_PITCH_MM,
        }
    }
}

impl CameraTiming {
    /// Default decision-to-exposure delay `t_d`, s (thesis: 2-3 ms).
    pub const DEFAULT_DELAY_S: f64 = 0.0025;
    /// Default exposure `t_e`, s (thesis ch. 6).
    pub const DEFAULT_EXPOSURE_S: f64 = 0.07;
    /// Default readout `t_r` after the exposure, s (a 640 x 480 Flea2 at its
    /// 80 fps maximum; an assumption, the thesis gives none).
    pub const DEFAULT_READOUT_S: f64 = 0.0125;
    /// Default minimum interval between MMBM-triggered frames, s (the
    /// thesis's fair comparison with 5 fps).
    pub const DEFAULT_MIN_INTERVAL_S: f64 = 0.2;
    /// Default pixel pitch, mm: the thesis camera's 4.65 um.
    pub const DEFAULT_PITCH_MM: f64 = 0.00465;

    /// The timing of a rolling-shutter camera (docs/spec.md section 9): its last line's
    /// exposure ends `rolling_readout_s` after the first line's, so the camera
    /// is busy that much longer before the readout `t_r` that follows.
    pub fn with_rolling_readout(self, rolling_readout_s: f64) -> Self {
        CameraTiming {
            readout: self.readout + rolling_readout_s,
            ..self
        }
    }

    /// This timing for `camera`: its pixel pitch (x, mm) for exposure
    /// control, and its rolling readout added ([`Self::with_rolling_readout`]).
    pub fn for_camera(self, camera: &crate::camera::Camera) -> Self {
        CameraTiming {
            pitch_mm: camera.pitch_x_mm,
            ..self
        }
        .with_rolling_readout(camera.shutter.readout_s)
    }

    /// Checks that the times are finite, the exposure positive and the others non-negative.
    pub fn validate(&self) -> Result<()> {
        crate::check::positive("exposure", self.exposure)?;
        crate::check::positive("pixel pitch (mm)", self.pitch_mm)?;
        for (what, x) in [
            ("delay", self.delay),
            ("readout", self.readout),
            ("min-interval", self.min_interval),
        ] {
            crate::check::finite(what, x)?;
            if x < 0.0 {
                return Err(Error::invalid(what, format!("must be >= 0 s, got {x}")));
            }
        }
        Ok(())
    }
}

/// One triggered frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// The spec of the policy that triggered the frame, its
    /// [`Policy::spec`](crate::trigger::Policy::spec): the
    /// [`PolicySpec`] a built-in policy was built from, a
    /// [`PolicySpec::custom`] of a user's policy's label. Its `Display` is
    /// the `policy` column (the policy string exactly as given).
    pub policy: PolicySpec,
    /// Index of the gyro sample the decision was made on.
    pub index: usize,
    /// Time of that sample, s.
    pub trigger_t: f64,
    /// `trigger_t + delay`, s.
    pub exposure_start: f64,
    /// `exposure_start` plus the frame's exposure (the camera's, or the one
    /// an exposure-controlled policy chose), s.
    pub exposure_end: f64,
    /// MMBM of the decision sample, mm/s.
    pub mmbm_trigger_mm_s: f64,
    /// MMBM averaged over the exposure, mm/s.
    pub mmbm_exposure_mm_s: f64,
    /// False when a quality gate discarded the frame.
    pub kept: bool,
    /// Sensor gain relative to the nominal exposure's (1 unless an
    /// exposure-controlled policy shortened the exposure: then
    /// `nominal / chosen`, which keeps the image as bright).
    pub gain: f64,
}

impl Frame {
    /// The frame's exposure, s.
    pub fn exposure_s(&self) -> f64 {
        self.exposure_end - self.exposure_start
    }
}

/// The exposure average `E(i)` for a trigger at every sample (used by the oracle).
pub fn exposure_means(t: &[f64], m: &[f64], timing: &CameraTiming) -> Vec<f64> {
    let integral = Integral::new(t, m);
    t.iter()
        .map(|&ti| {
            let a = ti + timing.delay;
            integral.mean(a, a + timing.exposure)
        })
        .collect()
}
