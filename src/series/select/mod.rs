//! Choosing frames for the next tool: the sharpest frames of a video (for
//! COLMAP or a splatting pipeline), every frame under a blur budget, and the
//! blurriest ones (for a deblurrer), from the per-frame blur of
//! [`super::frames::frame_mmbm`]; and what those tools read
//! ([`names`]): an image list (one file name per line, COLMAP's
//! `--image_list_path`) and an ffmpeg `select` expression (`ffmpeg -i in.mp4
//! -vf "select=$(cat FILE)" -fps_mode passthrough out_%04d.png` writes
//! exactly those frames, in frame order).
//!
//! Three ways to choose:
//! - [`choose`]: greedy, sharpest first, with a blur budget and a smallest
//!   gap between picks (`--select`, `--gap`, `--max-blur`); it says why it
//!   kept fewer than asked ([`Refused`]).
//! - [`windows::best_per_window`]: the sharpest frame of each window of K
//!   frames, of S seconds, or of N equal windows (`--per-window`,
//!   `--per-seconds`, `--count`): even coverage, the largest hole bounded,
//!   optionally checked by an image metric of the decoded frames
//!   ([`windows::HYBRID_KEEP`]).
//! - [`coverage`]: what a choice covers (adjacent pairs, largest hole).
//!
//! Frames are 0-based rows of the frame table, which are the video's frames
//! in decoding order (ffmpeg's `n`). Frames without a value (their window
//! leaves the log) are never chosen. Every list is in frame order, so the
//! k-th image ffmpeg writes is the k-th name of the list.

pub mod clock;
pub mod names;
pub mod video;
pub mod windows;

pub use names::{check_frame_start, ffmpeg_select, image_list, FrameName};

use super::frames::FrameMmbm;
use crate::error::{Error, Result};

/// What [`choose`] keeps: at most `count` frames (all when `None`), each at
/// most `max_blur_px` (any when `None`), their starts at least `gap_s`
/// apart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Choice {
    /// Most frames kept (`None`: no limit).
    pub count: Option<usize>,
    /// Smallest time between two kept frames' starts, s (>= 0).
    pub gap_s: f64,
    /// Largest blur of a kept frame, px (`None`: no budget).
    pub max_blur_px: Option<f64>,
}

impl Choice {
    /// Checks the values: `gap_s` finite and >= 0, `max_blur_px` finite and >= 0.
    pub fn check(&self) -> Result<()> {
        if !(self.gap_s.is_finite() && self.gap_s >= 0.0) {
            return Err(Error::invalid(
                "--gap",
                format!("must be a finite time >= 0 s, got {}", self.gap_s),
            ));
        }
        check_budget(self.max_blur_px)
    }
}

/// Checks a blur budget: finite and >= 0 px (`None`: no budget).
pub fn check_budget(max_blur_px: Option<f64>) -> Result<()> {
    if let Some(b) = max_blur_px {
        if !(b.is_finite() && b >= 0.0) {
            return Err(Error::invalid(
                "--max-blur",
                format!("must be a finite blur >= 0 px, got {b}"),
            ));
        }
    }
    Ok(())
}

/// The blur (px, `None` outside the log) and start (s) of every frame, as
/// the choosers take them.
pub fn blur_and_times(frames: &[FrameMmbm]) -> (Vec<Option<f64>>, Vec<f64>) {
    (
        frames.iter().map(FrameMmbm::blur_px).collect(),
        frames.iter().map(|f| f.t_start).collect(),
    )
}

/// Checks the choosers' inputs: as many times as blurs, every time finite,
/// every blur finite and >= 0.
pub fn check_series(blur: &[Option<f64>], t: &[f64]) -> Result<()> {
    if blur.len() != t.len() {
        return Err(Error::invalid(
            "times_s",
            format!("{} times for {} blur values", t.len(), blur.len()),
        ));
    }
    if let Some(k) = blur
        .iter()
        .position(|b| b.is_some_and(|b| !(b.is_finite() && b >= 0.0)))
    {
        return Err(Error::invalid(
            "blur_px",
            format!("frame {k}: {:?} is not a finite blur >= 0 px", blur[k]),
        ));
    }
    if let Some(k) = t.iter().position(|x| !x.is_finite()) {
        return Err(Error::invalid("times_s", format!("frame {k}: not finite")));
    }
    Ok(())
}

/// Checks that the starts `t` are in order (non-decreasing), as windows of
/// seconds need.
pub fn check_ordered(t: &[f64]) -> Result<()> {
    if let Some(k) = t.windows(2).position(|w| w[1] < w[0]) {
        return Err(Error::invalid(
            "times_s",
            format!(
                "frame {}: starts at {} s, before the frame before it ({} s); windows of seconds need frames in time order",
                k + 1,
                t[k + 1],
                t[k]
            ),
        ));
    }
    Ok(())
}

/// The frames with a value and their blur, px, sharpest first (ties: the
/// earlier frame first).
fn by_blur(blur: &[Option<f64>]) -> Vec<(f64, usize)> {
    let mut order: Vec<(f64, usize)> = blur
        .iter()
        .enumerate()
        .filter_map(|(k, b)| b.map(|b| (b, k)))
        .collect();
    order.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    order
}

/// Why [`choose_series`] kept fewer frames than asked: frames passed over.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Refused {
    /// Frames without a value (their window leaves the log).
    pub without_value: usize,
    /// Frames over the blur budget.
    pub over_budget: usize,
    /// Frames within the budget refused for lying closer than the gap to a
    /// sharper frame already kept.
    pub by_gap: usize,
}

/// The frames `choice` keeps (indices into `frames`, in frame order):
/// greedy, sharpest first, a frame kept when it is within the blur budget
/// and at least `gap_s` from every frame already kept, until `count`.
pub fn choose(frames: &[FrameMmbm], choice: &Choice) -> Result<Vec<usize>> {
    let (blur, t) = blur_and_times(frames);
    Ok(choose_series(&blur, &t, choice)?.0)
}

/// [`choose`] of a series of blurs (px, `None`: no value) and starts (s),
/// with why fewer than `count` were kept (counted until `count` is reached).
pub fn choose_series(
    blur: &[Option<f64>],
    t: &[f64],
    choice: &Choice,
) -> Result<(Vec<usize>, Refused)> {
    choice.check()?;
    check_series(blur, t)?;
    let order = by_blur(blur);
    let mut refused = Refused {
        without_value: blur.len() - order.len(),
        ..Refused::default()
    };
    let mut kept: Vec<usize> = Vec::new();
    // Kept starts, sorted, for the gap test in log time.
    let mut starts: Vec<f64> = Vec::new();
    for (i, &(b, k)) in order.iter().enumerate() {
        if choice.count.is_some_and(|n| kept.len() >= n) {
            break;
        }
        if choice.max_blur_px.is_some_and(|m| b > m) {
            // Sorted by blur: no later frame is within the budget either.
            refused.over_budget = order.len() - i;
            break;
        }
        let at = starts.partition_point(|&s| s < t[k]);
        let near = |i: usize| {
            starts
                .get(i)
                .is_some_and(|&s| (s - t[k]).abs() < choice.gap_s)
        };
        if at > 0 && near(at - 1) || near(at) {
            refused.by_gap += 1;
            continue;
        }
        starts.insert(at, t[k]);
        kept.push(k);
    }
    kept.sort_unstable();
    Ok((kept, refused))
}

/// What a choice covers: how evenly its frames spread over the frames that
/// have a value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coverage {
    /// Pairs of chosen frames that are adjacent frames (`k`, `k + 1`).
    pub adjacent_pairs: usize,
    /// The largest time with no chosen frame, s: between two consecutive
    /// picks' starts, or from the first frame with a value to the first
    /// pick, or from the last pick to the last frame with a value.
    pub largest_hole_s: f64,
    /// The frames bounding it (rows; the first or last frame with a value at
    /// an end).
    pub hole: (usize, usize),
}

/// The [`Coverage`] of `chosen` (rows, in order) among frames with blurs
/// `blur` and starts `t`; `None` when nothing was chosen or no frame has a
/// value.
pub fn coverage(chosen: &[usize], blur: &[Option<f64>], t: &[f64]) -> Option<Coverage> {
    let first = blur.iter().position(Option::is_some)?;
    let last = blur.iter().rposition(Option::is_some)?;
    let (&a, &b) = (chosen.first()?, chosen.last()?);
    let mut marks = Vec::with_capacity(chosen.len() + 2);
    marks.push(first.min(a));
    marks.extend_from_slice(chosen);
    marks.push(last.max(b));
    let mut out = Coverage {
        adjacent_pairs: chosen.windows(2).filter(|w| w[1] == w[0] + 1).count(),
        largest_hole_s: 0.0,
        hole: (a, a),
    };
    for w in marks.windows(2) {
        let gap = t[w[1]] - t[w[0]];
        if gap > out.largest_hole_s {
            out.largest_hole_s = gap;
            out.hole = (w[0], w[1]);
        }
    }
    Some(out)
}

/// The default number of frames for a deblurrer: the blurriest 10 % of the
/// `with_value` frames that have a value, rounded up (0 for none).
pub fn default_worst(with_value: usize) -> usize {
    with_value.div_ceil(10)
}

/// The `n` blurriest frames with a value (indices into `frames`, in frame
/// order); `None`: [`default_worst`] of the frames with a value.
pub fn blurriest(frames: &[FrameMmbm], n: Option<usize>) -> Vec<usize> {
    let order = by_blur(&blur_and_times(frames).0);
    let n = n.unwrap_or(default_worst(order.len())).min(order.len());
    let mut out: Vec<usize> = order[order.len() - n..].iter().map(|&(_, k)| k).collect();
    out.sort_unstable();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;

    fn frames(blur: &[Option<f64>]) -> Vec<FrameMmbm> {
        blur.iter()
            .enumerate()
            .map(|(k, b)| FrameMmbm {
                frame: k,
                t_start: k as f64 * 0.1,
                exposure_s: 0.01,
                readout_s: 0.0,
                // blur_px = px/s x exposure
                exposure_mm_s: b.map(|b| b * Camera::thesis().pitch_x_mm / 0.01),
                exposure_px_s: b.map(|b| b / 0.01),
                start_mm_s: b.map(|_| 0.0),
            })
            .collect()
    }

    #[test]
    fn coverage_counts_adjacent_pairs_and_the_largest_hole() {
        // Frames 0.1 s apart, 1 and 8 without a value (the first and last
        // with one: 0 and 9).
        let b: Vec<Option<f64>> = (0..10).map(|k| (k != 1 && k != 8).then_some(1.0)).collect();
        let t: Vec<f64> = (0..10).map(|k| k as f64 * 0.1).collect();
        // Picks 2, 3, 7: one adjacent pair; holes 0.2 (0-2), 0.1, 0.4 (3-7), 0.2 (7-9).
        let c = coverage(&[2, 3, 7], &b, &t).unwrap();
        assert_eq!(c.adjacent_pairs, 1);
        assert!((c.largest_hole_s - 0.4).abs() < 1e-12);
        assert_eq!(c.hole, (3, 7));
        assert!(coverage(&[], &b, &t).is_none());
        // Why fewer: 2 without a value; with a 0.15 s gap the sharpest-first
        // greedy keeps 0, 2, 4, 6, 9 (ties: the earlier) and refuses 3, 5, 7.
        let (kept, r) = choose_series(
            &b,
            &t,
            &Choice {
                count: Some(9),
                gap_s: 0.15,
                max_blur_px: None,
            },
        )
        .unwrap();
        assert_eq!(kept, [0, 2, 4, 6, 9]);
        assert_eq!(
            r,
            Refused {
                without_value: 2,
                over_budget: 0,
                by_gap: 3
            }
        );
    }

    #[test]
    fn choose_keeps_the_sharpest_within_gap_and_budget() {
        let f = frames(&[Some(3.0), Some(1.0), Some(2.0), None, Some(0.5), Some(4.0)]);
        let all = |count, gap_s, max_blur_px| {
            choose(
                &f,
                &Choice {
                    count,
                    gap_s,
                    max_blur_px,
                },
            )
            .unwrap()
        };
        assert_eq!(all(Some(2), 0.0, None), [1, 4]);
        // With a 0.15 s gap every other frame is within 0.1 s of frame 1 or 4.
        assert_eq!(all(Some(3), 0.15, None), [1, 4]);
        assert_eq!(all(None, 0.15, None), [1, 4]);
        assert_eq!(all(None, 0.0, Some(2.0)), [1, 2, 4]);
        assert_eq!(all(None, 0.0, Some(0.1)), Vec::<usize>::new());
        // No value is never chosen.
        assert_eq!(all(None, 0.0, None), [0, 1, 2, 4, 5]);
        assert!(choose(
            &f,
            &Choice {
                count: None,
                gap_s: -1.0,
                max_blur_px: None
            }
        )
        .is_err());
        assert_eq!(blurriest(&f, Some(2)), [0, 5]);
        assert_eq!(blurriest(&f, None), [5]);
        assert_eq!(blurriest(&f, Some(99)).len(), 5);
        assert_eq!(
            (default_worst(0), default_worst(10), default_worst(11)),
            (0, 1, 2)
        );
    }
}
