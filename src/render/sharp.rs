//! Which instant of an exposure a sharp frame shows ([`SharpAt`]): the
//! start, the middle or the end of the motion, and the sharp frame rendered
//! there ([`render_sharp_at`]).
//!
//! Deblurring sets such as GoPro and REDS pair a blurred frame (an average of
//! consecutive high-speed frames) with the **middle** one, and models trained
//! on them expect that convention: for a steady motion, the blurred frame's
//! streaks are centred on the sharp frame's points, with no net shift.

use super::{render_frame_stream, RenderJob, RenderOutput, Trajectory};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// The instant of the motion a sharp frame shows: its start, middle or end
/// (of the exposure; with a rolling shutter, of the whole span the motion
/// covers: the readout plus the exposure).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SharpAt {
    /// Exposure start (`t = 0`).
    Start,
    /// The middle of the span (`t = span / 2`): the GoPro / REDS convention.
    Mid,
    /// The end of the span (`t = span`).
    End,
}

impl SharpAt {
    /// The names, as written in configurations.
    pub const NAMES: [&'static str; 3] = ["start", "mid", "end"];

    /// The instant as a fraction of the span: 0, 1/2 or 1.
    pub fn fraction(self) -> f64 {
        match self {
            SharpAt::Start => 0.0,
            SharpAt::Mid => 0.5,
            SharpAt::End => 1.0,
        }
    }

    /// `start`, `mid` or `end`.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// True for [`SharpAt::Start`].
    pub fn is_start(&self) -> bool {
        *self == SharpAt::Start
    }

    /// What items written before the key existed used: the start.
    pub fn legacy() -> Self {
        SharpAt::Start
    }
}

impl fmt::Display for SharpAt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SharpAt {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.trim() {
            "start" => Ok(SharpAt::Start),
            "mid" => Ok(SharpAt::Mid),
            "end" => Ok(SharpAt::End),
            _ => Err(Error::invalid(
                "sharp",
                format!(
                    "{}: expected \"start\", \"mid\" or \"end\"",
                    crate::error::quote(s)
                ),
            )),
        }
    }
}

/// The sharp frame of `job` (no motion, same camera, target, quality and
/// backend) with the camera held at its pose at instant `at` of the
/// trajectory; with sensor noise, another realisation of it (RNG stream 1).
/// At the start this is [`super::render_sharp`], bytes included.
pub fn render_sharp_at(job: &RenderJob, at: SharpAt) -> Result<RenderOutput> {
    if at.is_start() {
        return super::render_sharp(job);
    }
    let span = job.trajectory.duration();
    let pose = job.trajectory.pose_at(at.fraction() * span);
    let still = RenderJob {
        trajectory: Trajectory::from_poses(span, vec![pose, pose])?,
        with_maps: false,
        ..job.clone()
    };
    render_frame_stream(&still, 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_bad_ones_are_named() {
        for n in SharpAt::NAMES {
            let s: SharpAt = n.parse().unwrap();
            assert_eq!(s.name(), n);
            assert_eq!(serde_json::to_string(&s).unwrap(), format!("\"{n}\""));
        }
        assert_eq!(SharpAt::Mid.fraction(), 0.5);
        let e = "middle".parse::<SharpAt>().unwrap_err().to_string();
        assert!(e.contains("sharp") && e.contains("middle"), "{e}");
    }
}
