//! One frame's time window on the log's clock ([`FrameWindow`]): its start,
//! exposure and shutter, and its span from [`Shutter::busy_s`], shared by
//! the frames job ([`super::job`]) and the exposure MMBM of frames
//! ([`super::frames`]).

use crate::camera::{Camera, Shutter};
use crate::error::{Error, Result};
use crate::io::frames::VideoFrame;

/// One frame's time window: line `j` of `n` is exposed over
/// `[t_start + readout_s j / n, t_start + readout_s j / n + exposure_s]`
/// (docs/spec.md section 9), so the frame spans
/// `[t_start, t_start + shutter.busy_s(exposure_s)]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameWindow {
    /// 0-based row of the frame table.
    pub index: usize,
    /// Exposure start of the first line, s (the log's clock).
    pub t_start: f64,
    /// Exposure of each line, s.
    pub exposure_s: f64,
    /// The frame's shutter: its own readout (a frame table's `readout_s`),
    /// else the camera's, in the camera's direction.
    pub shutter: Shutter,
}

impl FrameWindow {
    /// The window of `frame` (row `index` of its table) under `camera`'s
    /// shutter; the frame is checked first ([`VideoFrame::check`]: the error
    /// names the frame and the column).
    pub fn of(camera: &Camera, index: usize, frame: &VideoFrame) -> Result<Self> {
        frame.check().map_err(|(column, message)| {
            Error::invalid(format!("frame {index}: {column}"), message)
        })?;
        Ok(FrameWindow {
            index,
            t_start: frame.t_start,
            exposure_s: frame.exposure_s,
            shutter: Shutter {
                readout_s: frame.readout_s.unwrap_or(camera.shutter.readout_s),
                direction: camera.shutter.direction,
            },
        })
    }

    /// Rolling-shutter readout of the frame, s (0: global shutter).
    pub fn readout_s(&self) -> f64 {
        self.shutter.readout_s
    }

    /// The frame's span, s: the first line's exposure start to the last
    /// line's exposure end ([`Shutter::busy_s`]).
    pub fn span_s(&self) -> f64 {
        self.shutter.busy_s(self.exposure_s)
    }

    /// The last line's exposure end, s (the log's clock).
    pub fn end_s(&self) -> f64 {
        self.t_start + self.span_s()
    }
}
