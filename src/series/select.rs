//! Choosing frames for the next tool: the sharpest frames of a video (for
//! COLMAP or a splatting pipeline), every frame under a blur budget, and the
//! blurriest ones (for a deblurrer), from the per-frame blur of
//! [`super::frames::frame_mmbm`]; and what those tools read: an image list
//! (one file name per line, COLMAP's `--image_list_path`) and an ffmpeg
//! `select` expression (`ffmpeg -i in.mp4 -vf "select=$(cat FILE)" -vsync 0
//! out_%04d.png` writes exactly those frames, in frame order).
//!
//! Frames are 0-based rows of the frame table, which are the video's frames
//! in decoding order (ffmpeg's `n`). Frames without a value (their window
//! leaves the log) are never chosen. Every list is in frame order, so the
//! k-th image ffmpeg writes is the k-th name of the list.

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
        if let Some(b) = self.max_blur_px {
            if !(b.is_finite() && b >= 0.0) {
                return Err(Error::invalid(
                    "--max-blur",
                    format!("must be a finite blur >= 0 px, got {b}"),
                ));
            }
        }
        Ok(())
    }
}

/// The frames with a value and their blur, px, sharpest first (ties: the
/// earlier frame first).
fn by_blur(frames: &[FrameMmbm]) -> Vec<(f64, usize)> {
    let mut order: Vec<(f64, usize)> = frames
        .iter()
        .enumerate()
        .filter_map(|(k, f)| f.blur_px().map(|b| (b, k)))
        .collect();
    order.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    order
}

/// The frames `choice` keeps (indices into `frames`, in frame order):
/// greedy, sharpest first, a frame kept when it is within the blur budget
/// and at least `gap_s` from every frame already kept, until `count`.
pub fn choose(frames: &[FrameMmbm], choice: &Choice) -> Result<Vec<usize>> {
    choice.check()?;
    let mut kept: Vec<usize> = Vec::new();
    // Kept starts, sorted, for the gap test in log time.
    let mut starts: Vec<f64> = Vec::new();
    for (blur, k) in by_blur(frames) {
        if choice.count.is_some_and(|n| kept.len() >= n) {
            break;
        }
        if choice.max_blur_px.is_some_and(|m| blur > m) {
            // Sorted by blur: no later frame is within the budget either.
            break;
        }
        let t = frames[k].t_start;
        let at = starts.partition_point(|&s| s < t);
        let near = |i: usize| starts.get(i).is_some_and(|&s| (s - t).abs() < choice.gap_s);
        if at > 0 && near(at - 1) || near(at) {
            continue;
        }
        starts.insert(at, t);
        kept.push(k);
    }
    kept.sort_unstable();
    Ok(kept)
}

/// The default number of frames for a deblurrer: the blurriest 10 % of the
/// `with_value` frames that have a value, rounded up (0 for none).
pub fn default_worst(with_value: usize) -> usize {
    with_value.div_ceil(10)
}

/// The `n` blurriest frames with a value (indices into `frames`, in frame
/// order); `None`: [`default_worst`] of the frames with a value.
pub fn blurriest(frames: &[FrameMmbm], n: Option<usize>) -> Vec<usize> {
    let order = by_blur(frames);
    let n = n.unwrap_or(default_worst(order.len())).min(order.len());
    let mut out: Vec<usize> = order[order.len() - n..].iter().map(|&(_, k)| k).collect();
    out.sort_unstable();
    out
}

/// A printf-style frame file name with one integer conversion (`%d`,
/// `%5d`, `%06d`; `%%` is a literal `%`), as ffmpeg's image2 muxer names
/// frames: `frame_%06d.png` names frame number 12 `frame_000012.png`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameName {
    prefix: String,
    suffix: String,
    width: usize,
    zeros: bool,
}

impl std::str::FromStr for FrameName {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let bad = |what: &str| {
            Error::invalid(
                "--frame-name",
                format!("'{s}': {what} (e.g. frame_%06d.png: one %d, %Nd or %0Nd; %% for a %)"),
            )
        };
        if s.contains(['\n', '\r']) {
            return Err(bad("a name cannot hold a line break"));
        }
        let mut parts = (String::new(), String::new());
        let mut conv: Option<(usize, bool)> = None;
        let mut chars = s.chars().peekable();
        while let Some(c) = chars.next() {
            let side = if conv.is_some() {
                &mut parts.1
            } else {
                &mut parts.0
            };
            if c != '%' {
                side.push(c);
                continue;
            }
            if chars.peek() == Some(&'%') {
                chars.next();
                side.push('%');
                continue;
            }
            let mut digits = String::new();
            while let Some(d) = chars.peek().filter(|d| d.is_ascii_digit()) {
                digits.push(*d);
                chars.next();
            }
            if chars.next() != Some('d') {
                return Err(bad("only integer conversions (d) are supported"));
            }
            if conv.is_some() {
                return Err(bad("more than one %d"));
            }
            let zeros = digits.starts_with('0');
            let width = if digits.is_empty() {
                0
            } else {
                digits
                    .parse::<usize>()
                    .ok()
                    .filter(|&w| w <= 32)
                    .ok_or_else(|| bad("the width must be at most 32"))?
            };
            conv = Some((width, zeros));
        }
        let Some((width, zeros)) = conv else {
            return Err(bad("no %d for the frame number"));
        };
        Ok(FrameName {
            prefix: parts.0,
            suffix: parts.1,
            width,
            zeros,
        })
    }
}

impl FrameName {
    /// The name of frame number `n`.
    pub fn name(&self, n: u64) -> String {
        let num = if self.zeros {
            format!("{n:0w$}", w = self.width)
        } else {
            format!("{n:w$}", w = self.width)
        };
        format!("{}{num}{}", self.prefix, self.suffix)
    }
}

/// Checks `--frame-start`: the number of the last of `frames` frames
/// (`start + frames - 1`) must fit in a u64, else the names would wrap.
pub fn check_frame_start(start: u64, frames: usize) -> Result<()> {
    let last = (frames.max(1) - 1) as u64;
    if start.checked_add(last).is_none() {
        return Err(Error::invalid(
            "--frame-start",
            format!(
                "{start} numbers the last of {frames} frames {start} + {last}, past the largest \
                 frame number {}",
                u64::MAX
            ),
        ));
    }
    Ok(())
}

/// The image list of `frames` (0-based rows, in order): one name per line,
/// frame `k` named with number `k + start` (ffmpeg's image2 numbers the
/// first frame 1 unless told `-start_number`).
pub fn image_list(frames: &[usize], name: &FrameName, start: u64) -> String {
    let mut out = String::new();
    for &k in frames {
        out.push_str(&name.name((k as u64).saturating_add(start)));
        out.push('\n');
    }
    out
}

/// ffmpeg's `select` expression for `frames` (0-based frame numbers, `n`):
/// `eq(n\,K)` for a lone frame, `between(n\,A\,B)` for a run of consecutive
/// frames, joined by `+`; `0` (no frame) for an empty list. Commas are
/// escaped for a filtergraph (`-vf "select=$(cat FILE)"`). One line, with
/// its `\n`.
pub fn ffmpeg_select(frames: &[usize]) -> String {
    let mut sorted = frames.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    let mut terms: Vec<String> = Vec::new();
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i;
        while j + 1 < sorted.len() && sorted[j + 1] == sorted[j] + 1 {
            j += 1;
        }
        terms.push(if j == i {
            format!("eq(n\\,{})", sorted[i])
        } else {
            format!("between(n\\,{}\\,{})", sorted[i], sorted[j])
        });
        i = j + 1;
    }
    if terms.is_empty() {
        terms.push("0".into());
    }
    let mut out = terms.join("+");
    out.push('\n');
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

    #[test]
    fn names_and_expressions() {
        let n: FrameName = "frame_%06d.png".parse().unwrap();
        assert_eq!(n.name(12), "frame_000012.png");
        let n: FrameName = "100%%/f%d.jpg".parse().unwrap();
        assert_eq!(n.name(7), "100%/f7.jpg");
        let n: FrameName = "f%4d".parse().unwrap();
        assert_eq!(n.name(7), "f   7");
        for bad in [
            "frame.png",
            "a%d%d",
            "%s.png",
            "%f",
            "x%",
            "a\nb%d",
            "%099d",
        ] {
            let e = bad.parse::<FrameName>().unwrap_err().to_string();
            assert!(e.contains("--frame-name"), "{bad}: {e}");
        }
        let n: FrameName = "frame_%06d.png".parse().unwrap();
        assert_eq!(
            image_list(&[0, 5], &n, 1),
            "frame_000001.png\nframe_000006.png\n"
        );
        assert_eq!(
            ffmpeg_select(&[40, 12, 13, 14, 99, 41]),
            "between(n\\,12\\,14)+between(n\\,40\\,41)+eq(n\\,99)\n"
        );
        assert_eq!(ffmpeg_select(&[]), "0\n");
    }
}
