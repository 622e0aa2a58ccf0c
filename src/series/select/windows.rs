//! Even coverage, as photogrammetry and splatting users choose frames: the
//! sharpest frame of each window.
//!
//! - [`Windows::Frames`] (`--per-window K`): rows `0..K`, `K..2K`, ...
//! - [`Windows::Seconds`] (`--per-seconds S`): frames whose start lies in
//!   `[t0 + iS, t0 + (i+1)S)`, `t0` the first frame's start.
//! - [`Windows::Count`] (`--count N`): the span from the first to the last
//!   frame with a value (`m` frames) cut into `min(N, m)` windows of
//!   `floor(m/N)` or `ceil(m/N)` frames (window `i`: rows `a + floor(i m /
//!   N)` up to `a + floor((i+1) m / N)`), the sharpest of each. Two
//!   consecutive picks then lie in the same or adjacent windows, so when
//!   every window has a pick no two are more than `2 ceil(m/N) - 1` frames
//!   apart, and the first and last are within `ceil(m/N) - 1` frames of the
//!   span's ends: the largest hole is bounded. A window with no frame
//!   within the budget gives none (and the hole grows; the summary says so).
//!
//! Within a window the pick is the frame with the least predicted blur
//! within the budget (ties: the earlier). With an image metric of the
//! decoded frames (the hybrid: a sharpness per frame, higher is sharper),
//! the gyro's pick stands unless its sharpness is below [`HYBRID_KEEP`]
//! times the best sharpness in the window (defocus, a moving subject,
//! optical stabilisation: what the gyro cannot see); then the pick is the
//! frame with the least predicted blur among those at least that sharp.

use super::{check_budget, check_ordered, check_series};
use crate::error::{Error, Result};
use std::ops::Range;

/// Share of the window's best image sharpness below which the hybrid
/// overrides the gyro's pick (a ratio, 0..1).
pub const HYBRID_KEEP: f64 = 0.5;

/// How the frames are cut into windows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Windows {
    /// Windows of this many consecutive frames (>= 1).
    Frames(usize),
    /// Windows of this many seconds of frame starts (finite, > 0).
    Seconds(f64),
    /// This many windows of (nearly) equal frame counts over the frames
    /// with a value (>= 1).
    Count(usize),
}

impl Windows {
    /// Checks the value (flag named as the CLI names it).
    pub fn check(&self) -> Result<()> {
        match *self {
            Windows::Frames(0) => Err(Error::invalid(
                "--per-window",
                "must be at least 1 frame per window",
            )),
            Windows::Count(0) => Err(Error::invalid("--count", "must be at least 1 frame")),
            Windows::Seconds(s) if !(s.is_finite() && s > 0.0) => Err(Error::invalid(
                "--per-seconds",
                format!("must be a finite time > 0 s, got {s}"),
            )),
            _ => Ok(()),
        }
    }
}

/// The windows' rows (half-open ranges, in order, none empty) for frames
/// with blurs `blur` (`None`: no value) and starts `t`, s.
pub fn ranges(blur: &[Option<f64>], t: &[f64], w: Windows) -> Result<Vec<Range<usize>>> {
    w.check()?;
    check_series(blur, t)?;
    let n = blur.len();
    Ok(match w {
        Windows::Frames(k) => (0..n).step_by(k).map(|a| a..(a + k).min(n)).collect(),
        Windows::Seconds(s) => {
            check_ordered(t)?;
            let mut out: Vec<Range<usize>> = Vec::new();
            let mut last: Option<f64> = None;
            for (k, &tk) in t.iter().enumerate() {
                let i = ((tk - t[0]) / s).floor();
                match out.last_mut() {
                    Some(r) if last == Some(i) => r.end = k + 1,
                    _ => out.push(k..k + 1),
                }
                last = Some(i);
            }
            out
        }
        Windows::Count(count) => {
            let (Some(a), Some(b)) = (
                blur.iter().position(Option::is_some),
                blur.iter().rposition(Option::is_some),
            ) else {
                return Ok(Vec::new());
            };
            let m = (b - a + 1) as u128;
            let c = (count as u128).min(m);
            let at = |i: u128| a + (i * m / c) as usize;
            (0..c).map(|i| at(i)..at(i + 1)).collect()
        }
    })
}

/// What [`best_per_window`] chose.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Picks {
    /// The chosen rows, in frame order (one per window at most).
    pub chosen: Vec<usize>,
    /// How many windows there were.
    pub windows: usize,
    /// Windows with no frame with a value within the budget (no pick).
    pub empty: usize,
    /// Windows where the image metric overrode the gyro's pick.
    pub overridden: usize,
}

/// The sharpest frame of each window (see the module docs): `blur` per
/// frame (px, `None`: no value), `t` their starts (s), `max_blur_px` a
/// budget, `sharpness` an image metric per frame (higher is sharper; NaN:
/// unknown) for the hybrid.
pub fn best_per_window(
    blur: &[Option<f64>],
    t: &[f64],
    w: Windows,
    max_blur_px: Option<f64>,
    sharpness: Option<&[f64]>,
) -> Result<Picks> {
    check_budget(max_blur_px)?;
    if let Some(s) = sharpness {
        if s.len() != blur.len() {
            return Err(Error::invalid(
                "image metric",
                format!("{} scores for {} frames", s.len(), blur.len()),
            ));
        }
    }
    let windows = ranges(blur, t, w)?;
    let mut out = Picks {
        windows: windows.len(),
        ..Picks::default()
    };
    for r in windows {
        // Frames with a value within the budget: (blur, row).
        let cands: Vec<(f64, usize)> = r
            .filter_map(|k| blur[k].map(|b| (b, k)))
            .filter(|&(b, _)| max_blur_px.is_none_or(|m| b <= m))
            .collect();
        let least = |ok: &dyn Fn(usize) -> bool| {
            cands
                .iter()
                .filter(|&&(_, k)| ok(k))
                .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
                .map(|&(_, k)| k)
        };
        let Some(gyro) = least(&|_| true) else {
            out.empty += 1;
            continue;
        };
        let mut pick = gyro;
        if let Some(s) = sharpness {
            let best = cands
                .iter()
                .map(|&(_, k)| s[k])
                .filter(|x| x.is_finite())
                .fold(f64::NEG_INFINITY, f64::max);
            let floor = HYBRID_KEEP * best;
            if best > 0.0 && s[gyro].is_finite() && s[gyro] < floor {
                if let Some(k) = least(&|k| s[k] >= floor) {
                    pick = k;
                    out.overridden += 1;
                }
            }
        }
        out.chosen.push(pick);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn times(n: usize) -> Vec<f64> {
        (0..n).map(|k| k as f64 * 0.1).collect()
    }

    #[test]
    fn windows_of_frames_seconds_and_count() {
        let b = vec![Some(1.0); 10];
        let t = times(10);
        assert_eq!(
            ranges(&b, &t, Windows::Frames(4)).unwrap(),
            [0..4, 4..8, 8..10]
        );
        // 0.25 s windows of starts 0, 0.1, ..., 0.9: [0, 0.25) holds 0, 0.1, 0.2.
        assert_eq!(
            ranges(&b, &t, Windows::Seconds(0.25)).unwrap(),
            [0..3, 3..5, 5..8, 8..10]
        );
        assert_eq!(
            ranges(&b, &t, Windows::Count(3)).unwrap(),
            [0..3, 3..6, 6..10]
        );
        // Count over the span with a value only; more windows than frames: one each.
        let mut b2 = b.clone();
        b2[0] = None;
        b2[9] = None;
        assert_eq!(ranges(&b2, &t, Windows::Count(2)).unwrap(), [1..5, 5..9]);
        assert_eq!(ranges(&b2, &t, Windows::Count(99)).unwrap().len(), 8);
        assert!(ranges(&[None, None], &[0.0, 1.0], Windows::Count(2))
            .unwrap()
            .is_empty());
        for bad in [Windows::Frames(0), Windows::Count(0), Windows::Seconds(0.0)] {
            assert!(ranges(&b, &t, bad).is_err(), "{bad:?}");
        }
        assert!(ranges(&b, &[0.0; 3], Windows::Frames(1)).is_err());
        let mut back = t.clone();
        back[5] = 0.0;
        let e = ranges(&b, &back, Windows::Seconds(1.0)).unwrap_err();
        assert!(e.to_string().contains("frame 5"), "{e}");
    }

    #[test]
    fn picks_the_least_blur_of_each_window() {
        // Windows of 3: minima at 1, 5 (tie with 4? no: 4 is 2.0), 6 (a tie: the earlier).
        let b = [
            Some(3.0),
            Some(1.0),
            Some(2.0),
            None,
            Some(2.0),
            Some(0.5),
            Some(0.7),
            Some(0.7),
            Some(9.0),
        ];
        let t = times(b.len());
        let p = best_per_window(&b, &t, Windows::Frames(3), None, None).unwrap();
        assert_eq!(p.chosen, [1, 5, 6]);
        assert_eq!((p.windows, p.empty, p.overridden), (3, 0, 0));
        // A budget of 0.6 px empties the first and last windows.
        let p = best_per_window(&b, &t, Windows::Frames(3), Some(0.6), None).unwrap();
        assert_eq!((p.chosen, p.empty), (vec![5], 2));
    }

    #[test]
    fn hybrid_overrides_only_a_much_less_sharp_gyro_pick() {
        let b = [
            Some(0.5),
            Some(1.0),
            Some(2.0),
            Some(0.5),
            Some(1.0),
            Some(2.0),
        ];
        let t = times(b.len());
        // Window 1: the gyro's pick (0) is defocused (10 < 0.5 x 100): the
        // next least blurred frame at least 50 sharp is 1. Window 2: the
        // gyro's pick (3) is 60, above half of 100: it stands.
        let s = [10.0, 80.0, 100.0, 60.0, 70.0, 100.0];
        let p = best_per_window(&b, &t, Windows::Frames(3), None, Some(&s)).unwrap();
        assert_eq!(p.chosen, [1, 3]);
        assert_eq!(p.overridden, 1);
        assert!(best_per_window(&b, &t, Windows::Frames(3), None, Some(&s[..2])).is_err());
    }

    #[test]
    fn count_bounds_the_largest_hole() {
        // Blur rising within each stretch so the sharpest sits at a window's
        // start or end: whatever the blur, picks of adjacent windows are at
        // most 2 ceil(m/N) - 1 frames apart.
        let m = 103;
        for seed in 0..20u64 {
            let b: Vec<Option<f64>> = (0..m)
                .map(|k| {
                    let x = (k as u64 + 1).wrapping_mul(seed * 2654435761 + 11) % 1000;
                    Some(x as f64)
                })
                .collect();
            let t = times(m);
            for n in [1, 7, 10, 50, 103] {
                let p = best_per_window(&b, &t, Windows::Count(n), None, None).unwrap();
                assert_eq!(p.chosen.len(), n);
                let w = m.div_ceil(n);
                let gaps = p.chosen.windows(2).map(|x| x[1] - x[0]);
                assert!(gaps.max().unwrap_or(0) < 2 * w, "seed {seed} n {n}");
                assert!(p.chosen[0] < w && m - 1 - p.chosen[n - 1] < w);
            }
        }
    }
}
