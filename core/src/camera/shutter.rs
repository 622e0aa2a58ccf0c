//! Rolling shutter (docs/spec.md section 9): the exposure of line `j` of `n` starts
//! `readout_s * j / n` after the first line's. The readout direction is named
//! as Gyroflow names it; `../shared/data` and this crate stamp a frame at the
//! exposure start of its first line (Gyroflow stamps the middle of the readout:
//! `t_start = t_mid - readout_s / 2`).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Which lines are read first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Readout {
    /// Rows, top row first (the usual CMOS readout).
    #[default]
    TopToBottom,
    /// Rows, bottom row first (a sensor mounted upside down).
    BottomToTop,
    /// Columns, left column first.
    LeftToRight,
    /// Columns, right column first.
    RightToLeft,
}

impl std::str::FromStr for Readout {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "top-to-bottom" | "0" => Ok(Readout::TopToBottom),
            "bottom-to-top" | "1" => Ok(Readout::BottomToTop),
            "left-to-right" | "2" => Ok(Readout::LeftToRight),
            "right-to-left" | "3" => Ok(Readout::RightToLeft),
            _ => Err(Error::invalid(
                "readout_direction",
                format!(
                    "'{s}': expected top-to-bottom, bottom-to-top, left-to-right or right-to-left"
                ),
            )),
        }
    }
}

impl Readout {
    /// Parses Gyroflow's `frame_readout_direction`: `0`-`3`, the names
    /// `TopToBottom`, `BottomToTop`, `LeftToRight`, `RightToLeft`, or the
    /// sensor rotations Gyroflow also accepts (`180` bottom to top, `270` left
    /// to right, `90` right to left).
    pub fn from_gyroflow(s: &str) -> Option<Self> {
        match s.trim() {
            "0" | "TopToBottom" => Some(Readout::TopToBottom),
            "1" | "180" | "BottomToTop" => Some(Readout::BottomToTop),
            "2" | "270" | "LeftToRight" => Some(Readout::LeftToRight),
            "3" | "90" | "RightToLeft" => Some(Readout::RightToLeft),
            _ => None,
        }
    }

    /// The opposite direction (what a negative Gyroflow `frame_readout_time` means).
    pub fn reversed(self) -> Self {
        match self {
            Readout::TopToBottom => Readout::BottomToTop,
            Readout::BottomToTop => Readout::TopToBottom,
            Readout::LeftToRight => Readout::RightToLeft,
            Readout::RightToLeft => Readout::LeftToRight,
        }
    }

    /// True when the lines are rows (top-to-bottom or bottom-to-top).
    pub fn is_rows(self) -> bool {
        matches!(self, Readout::TopToBottom | Readout::BottomToTop)
    }
}

/// The shutter: global (`readout_s = 0`, the default) or rolling.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Shutter {
    /// Delay between the exposure starts of the first and the last line, s.
    pub readout_s: f64,
    /// Readout direction.
    pub direction: Readout,
}

impl Shutter {
    /// A global shutter (every line exposed at once).
    pub fn global() -> Self {
        Shutter::default()
    }

    /// True for a global shutter.
    pub fn is_global(&self) -> bool {
        self.readout_s == 0.0
    }

    /// Rejects a negative or non-finite readout time.
    pub fn validate(&self) -> Result<()> {
        if !(self.readout_s.is_finite() && self.readout_s >= 0.0) {
            return Err(Error::invalid(
                "readout_s",
                format!(
                    "must be a finite time >= 0 s (0 = global shutter), got {}",
                    self.readout_s
                ),
            ));
        }
        Ok(())
    }

    /// Delay (s) of the exposure start of the line holding pixel point
    /// `(x, y)` (pixels, `(0, 0)` = top-left corner) on a `width x height`
    /// sensor, after the frame's start (the first line's exposure start).
    /// A point within 1e-9 px below a line boundary counts to the next line, so
    /// that a point computed exactly on a boundary (a midpoint rule's node,
    /// through the mm-to-pixel map's rounding) lands on the same line every time.
    #[inline]
    pub fn delay_s(&self, x: f64, y: f64, width: u32, height: u32) -> f64 {
        if self.readout_s == 0.0 {
            return 0.0;
        }
        let line = |p: f64, n: u32| ((p + 1e-9).floor().clamp(0.0, n as f64 - 1.0), n as f64);
        let (j, n) = match self.direction {
            Readout::TopToBottom => line(y, height),
            Readout::BottomToTop => {
                let (j, n) = line(y, height);
                (n - 1.0 - j, n)
            }
            Readout::LeftToRight => line(x, width),
            Readout::RightToLeft => {
                let (j, n) = line(x, width);
                (n - 1.0 - j, n)
            }
        };
        self.readout_s * j / n
    }

    /// How long the camera is busy with a frame of exposure `exposure_s`:
    /// from the first line's exposure start to the end of the last line's
    /// exposure, s.
    pub fn busy_s(&self, exposure_s: f64) -> f64 {
        exposure_s + self.readout_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delays_follow_the_direction() {
        let s = Shutter {
            readout_s: 0.032,
            direction: Readout::TopToBottom,
        };
        assert_eq!(s.delay_s(10.0, 0.5, 640, 480), 0.0);
        assert!((s.delay_s(10.0, 479.5, 640, 480) - 0.032 * 479.0 / 480.0).abs() < 1e-15);
        let b = Shutter {
            direction: Readout::BottomToTop,
            ..s
        };
        assert!((b.delay_s(10.0, 0.5, 640, 480) - 0.032 * 479.0 / 480.0).abs() < 1e-15);
        let l = Shutter {
            direction: Readout::LeftToRight,
            ..s
        };
        assert!((l.delay_s(320.2, 0.5, 640, 480) - 0.032 * 320.0 / 640.0).abs() < 1e-15);
        assert_eq!(Shutter::global().delay_s(5.0, 400.0, 640, 480), 0.0);
        assert!(Shutter {
            readout_s: -1.0,
            ..s
        }
        .validate()
        .is_err());
    }
}
