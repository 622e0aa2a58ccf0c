//! The clock check of `mmbm frames`: the video frames' time span against
//! the gyro log's, and the `--time-offset` to try when they do not meet.

use crate::error::{Error, Result};
use crate::series::frames::FrameMmbm;

/// The time spans of the frames and of the log, s (on the frames' clock,
/// the log's after the offset already given).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spans {
    /// First frame's start to the last frame's end (exposure and readout), s.
    pub video: (f64, f64),
    /// First to last gyro sample, s.
    pub log: (f64, f64),
}

impl Spans {
    /// The spans of `frames` and of the log's sample times `log_t` (`None`
    /// when either is empty).
    pub fn of(frames: &[FrameMmbm], log_t: &[f64]) -> Option<Spans> {
        let v0 = frames.iter().map(|f| f.t_start).reduce(f64::min)?;
        let v1 = frames.iter().map(|f| f.end_s()).reduce(f64::max)?;
        let g0 = log_t.iter().copied().reduce(f64::min)?;
        let g1 = log_t.iter().copied().reduce(f64::max)?;
        Some(Spans {
            video: (v0, v1),
            log: (g0, g1),
        })
    }

    /// The `--time-offset` to try (`current`: the one given): the one that
    /// aligns the starts when the video fits in the log, else the one that
    /// centres the video on the log. Added to the log's times.
    pub fn suggested_offset(&self, current: f64) -> f64 {
        let (v, g) = (self.video, self.log);
        let shift = if v.1 - v.0 <= g.1 - g.0 {
            v.0 - g.0
        } else {
            (v.0 + v.1) / 2.0 - (g.0 + g.1) / 2.0
        };
        current + shift
    }

    /// Both spans, in words.
    pub fn describe(&self, current: f64) -> String {
        format!(
            "the frames span {:.3} to {:.3} s, the gyro log {:.3} to {:.3} s (with --time-offset {current})",
            self.video.0, self.video.1, self.log.0, self.log.1
        )
    }
}

/// Refuses a run where no frame lies inside the log (`inside`: frames with
/// a value), naming both spans and the offset to try.
pub fn check_clock(spans: Option<Spans>, inside: usize, current: f64) -> Result<()> {
    match spans {
        Some(s) if inside == 0 => Err(Error::invalid(
            "--time-offset",
            format!(
                "no frame lies inside the gyro log: {}; is the clock offset right? \
                 try --time-offset={:.3} ({})",
                s.describe(current),
                s.suggested_offset(current),
                if s.video.1 - s.video.0 <= s.log.1 - s.log.0 {
                    "it aligns the starts"
                } else {
                    "it centres the video on the log"
                }
            ),
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(t: f64) -> FrameMmbm {
        FrameMmbm {
            frame: 0,
            t_start: t,
            exposure_s: 0.01,
            readout_s: 0.02,
            exposure_mm_s: None,
            exposure_px_s: None,
            start_mm_s: None,
        }
    }

    #[test]
    fn spans_and_offsets() {
        let f = [frame(100.0), frame(101.0)];
        let s = Spans::of(&f, &[0.0, 0.5, 10.0]).unwrap();
        assert_eq!(s.video, (100.0, 101.03));
        assert_eq!(s.log, (0.0, 10.0));
        // Fits: align the starts (the log moves by +100 s on top of the 2 s given).
        assert_eq!(s.suggested_offset(2.0), 102.0);
        // Longer than the log: centre it.
        let s = Spans::of(&f, &[0.0, 0.5]).unwrap();
        assert!((s.suggested_offset(0.0) - (100.515 - 0.25)).abs() < 1e-12);
        let e = check_clock(Some(s), 0, 0.0).unwrap_err().to_string();
        assert!(
            e.contains("100.000 to 101.030 s") && e.contains("0.000 to 0.500 s"),
            "{e}"
        );
        assert!(e.contains("--time-offset=100.265"), "{e}");
        assert!(check_clock(Some(s), 1, 0.0).is_ok());
        assert!(Spans::of(&[], &[1.0]).is_none());
    }
}
