//! What a choice of frames is worth against the truth: the mean true blur
//! of the picks, the share of picks over a blur limit, the largest time
//! with no pick (the library's [`coverage`]), and, for the budget task
//! ("every frame under B px"), precision, recall and F1.

use mmbm::series::select::coverage;

/// Blur over which a pick counts as blurred, px.
pub const BLURRED_PX: f64 = 2.0;

/// The worth of one picker's choice on one clip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Score {
    /// Frames picked.
    pub picks: usize,
    /// Mean true blur of the picks, px (NaN for none).
    pub mean_px: f64,
    /// Share of the picks whose true blur is over [`BLURRED_PX`] (0..1).
    pub over: f64,
    /// The largest time with no pick, s (the whole clip for none).
    pub hole_s: f64,
}

/// The largest time with no pick among frames starting at `t` (s): between
/// consecutive picks, or from the first frame to the first pick, or from
/// the last pick to the last frame ([`coverage`], every frame with a
/// value); the whole span when nothing is picked.
pub fn largest_hole(picks: &[usize], t: &[f64]) -> f64 {
    let all = vec![Some(0.0); t.len()];
    match coverage(picks, &all, t) {
        Some(c) => c.largest_hole_s,
        None => t.last().copied().unwrap_or(0.0) - t.first().copied().unwrap_or(0.0),
    }
}

/// The [`Score`] of `picks` (rows, in order) against the true blur `truth`
/// (px) of frames starting at `t` (s).
pub fn score(picks: &[usize], truth: &[f64], t: &[f64]) -> Score {
    let n = picks.len();
    let (sum, over) = picks.iter().fold((0.0, 0usize), |(s, o), &k| {
        (s + truth[k], o + usize::from(truth[k] > BLURRED_PX))
    });
    Score {
        picks: n,
        mean_px: if n == 0 { f64::NAN } else { sum / n as f64 },
        over: if n == 0 {
            f64::NAN
        } else {
            over as f64 / n as f64
        },
        hole_s: largest_hole(picks, t),
    }
}

/// Precision, recall and F1 of a yes/no call per frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prf {
    /// Share of the frames called yes that are yes (1 when none is called).
    pub precision: f64,
    /// Share of the frames that are yes called yes (1 when none is).
    pub recall: f64,
    /// Their harmonic mean (0 when both are 0).
    pub f1: f64,
}

/// The [`Prf`] of the calls `said` against the truth `is`.
pub fn prf(said: &[bool], is: &[bool]) -> Prf {
    let both = |a: bool, b: bool| {
        said.iter()
            .zip(is)
            .filter(|&(&s, &i)| s == a && i == b)
            .count()
    };
    let (tp, fp, fneg) = (both(true, true), both(true, false), both(false, true));
    let ratio = |a: usize, b: usize| {
        if a + b == 0 {
            1.0
        } else {
            a as f64 / (a + b) as f64
        }
    };
    let (p, r) = (ratio(tp, fp), ratio(tp, fneg));
    Prf {
        precision: p,
        recall: r,
        f1: if p + r == 0.0 {
            0.0
        } else {
            2.0 * p * r / (p + r)
        },
    }
}

/// The sharpness threshold that best tells `is` (sharp enough) from the
/// rest on one clip: the frame's sharpness `s >= threshold` called sharp,
/// the threshold among the clip's own values that maximises F1 (ties: the
/// lower).
pub fn tune_threshold(sharp: &[f64], is: &[bool]) -> f64 {
    let mut cands: Vec<f64> = sharp.iter().copied().filter(|x| x.is_finite()).collect();
    cands.sort_by(f64::total_cmp);
    cands.dedup();
    let mut best = (f64::NEG_INFINITY, f64::INFINITY);
    for &c in &cands {
        let said: Vec<bool> = sharp.iter().map(|&s| s >= c).collect();
        let f = prf(&said, is).f1;
        if f > best.0 {
            best = (f, c);
        }
    }
    best.1
}
