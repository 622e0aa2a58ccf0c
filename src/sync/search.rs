//! The offset search: the image motion measured between frames against the
//! motion the gyro predicts at a candidate offset, over a coarse grid of
//! offsets, then refined with a parabola, for each rolling-shutter readout
//! of a small scan.
//!
//! Model (rotation only): a patch at line fraction `l` (0 first line, 1
//! last) of frame `k` is seen at `t_k + e/2 + r*l` on the video's clock
//! (`t_k` the presentation time, `e` the exposure, `r` the readout: the
//! middle of that line's exposure). Between frames `k-1` and `k` it moves by
//! `J * (A(t_k + c - o) - A(t_(k-1) + c - o))` px, where `A` is the gyro's
//! integrated angle (rad, camera frame), `o` the offset (video time = gyro
//! time + `o`, `frames --time-offset`'s convention), `c = e/2 + r*l` and `J`
//! the rotation-only flow of the patch per radian ([`crate::model::flow`]).
//!
//! Cost at `(o, r)`: `1 - max(0, <m, p>)^2 / (|m|^2 |p|^2)` over all
//! measured motions `m` and predictions `p` of the frame pairs inside the
//! log: the share of the measured motion a single scale of the gyro's
//! prediction does not explain (0 perfect, 1 none; the scale, `<m, p> /
//! |p|^2`, is 1 when the camera's focal length is right).

use crate::error::{Error, Result};
use glam::DVec3;
use rayon::prelude::*;

/// The fewest frame pairs inside the log for an offset to be scored.
pub const MIN_PAIRS: usize = 10;
/// Step of the coarse offset grid, s.
const COARSE_STEP_S: f64 = 0.002;
/// Half width of the fine search around the coarse minimum, s.
const FINE_HALF_S: f64 = 0.006;
/// Step of the fine search, s.
const FINE_STEP_S: f64 = 0.0001;
/// Half width of the parabola fitted around the fine minimum, s.
const FIT_HALF_S: f64 = 0.0015;
/// Readouts scanned: `READOUT_STEPS + 1` values from 0 to 0.9 frame intervals.
const READOUT_STEPS: usize = 8;

/// One frame pair's measured motion, summed per readout line (the patches
/// seen at one line fraction share their times).
#[derive(Debug, Clone)]
pub struct PairObs {
    /// Presentation time of the earlier frame (video clock), s.
    pub t_prev: f64,
    /// Presentation time of the later frame, s.
    pub t_cur: f64,
    /// The lines' sums.
    pub lines: Vec<LineObs>,
}

/// Sums over the tracked patches of one line fraction of one frame pair.
#[derive(Debug, Clone, Copy, Default)]
pub struct LineObs {
    /// Line fraction, 0 (first line read) to 1 (last).
    pub line: f64,
    /// Sum of `J^T m` (px^2 / rad).
    pub g: DVec3,
    /// Sum of `J^T J` (px^2 / rad^2), upper triangle xx, xy, xz, yy, yz, zz.
    pub h: [f64; 6],
    /// Sum of `|m|^2`, px^2.
    pub c: f64,
}

impl LineObs {
    /// Adds one patch's motion `m` (px) with its flow per radian `j` (rows: u, v).
    pub fn add(&mut self, j: [DVec3; 2], m: (f64, f64)) {
        self.g += j[0] * m.0 + j[1] * m.1;
        let [a, b] = j;
        self.h[0] += a.x * a.x + b.x * b.x;
        self.h[1] += a.x * a.y + b.x * b.y;
        self.h[2] += a.x * a.z + b.x * b.z;
        self.h[3] += a.y * a.y + b.y * b.y;
        self.h[4] += a.y * a.z + b.y * b.z;
        self.h[5] += a.z * a.z + b.z * b.z;
        self.c += m.0 * m.0 + m.1 * m.1;
    }

    fn quad(&self, d: DVec3) -> f64 {
        let h = &self.h;
        h[0] * d.x * d.x
            + h[3] * d.y * d.y
            + h[5] * d.z * d.z
            + 2.0 * (h[1] * d.x * d.y + h[2] * d.x * d.z + h[4] * d.y * d.z)
    }
}

/// The gyro's integrated angle (trapezoids), rad, camera frame, on the log's clock.
pub struct Angle {
    t: Vec<f64>,
    a: Vec<DVec3>,
}

impl Angle {
    /// From times (s, increasing) and angular velocities (rad/s).
    pub fn new(samples: impl Iterator<Item = (f64, DVec3)>) -> Self {
        let (mut t, mut a) = (Vec::new(), Vec::<DVec3>::new());
        let mut last: Option<(f64, DVec3)> = None;
        for (ti, wi) in samples {
            let acc = match (last, a.last()) {
                (Some((tp, wp)), Some(&ap)) => ap + (wp + wi) * (0.5 * (ti - tp)),
                _ => DVec3::ZERO,
            };
            t.push(ti);
            a.push(acc);
            last = Some((ti, wi));
        }
        Angle { t, a }
    }

    /// First and last time, s.
    pub fn span(&self) -> (f64, f64) {
        (self.t[0], self.t[self.t.len() - 1])
    }

    /// The angle at `t`, linear between samples; `None` outside the log.
    fn at(&self, t: f64) -> Option<DVec3> {
        let (t0, t1) = self.span();
        if !(t >= t0 && t <= t1) {
            return None;
        }
        let i = self
            .t
            .partition_point(|&x| x <= t)
            .clamp(1, self.t.len() - 1);
        let (ta, tb) = (self.t[i - 1], self.t[i]);
        let f = if tb > ta { (t - ta) / (tb - ta) } else { 0.0 };
        Some(self.a[i - 1].lerp(self.a[i], f))
    }
}

/// The measurements and the gyro, ready to score offsets.
pub struct Problem<'a> {
    /// Frame pairs.
    pub obs: &'a [PairObs],
    /// The gyro's angle.
    pub angle: &'a Angle,
    /// Exposure, s.
    pub exposure_s: f64,
}

/// Sums of one `(offset, readout)`: `<m,p>`, `|p|^2`, `|m|^2`, pairs inside.
#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    mp: f64,
    pp: f64,
    mm: f64,
    pairs: usize,
}

impl Sums {
    fn cost(&self) -> f64 {
        if self.pp <= 0.0 || self.mm <= 0.0 {
            return 1.0;
        }
        1.0 - (self.mp.max(0.0).powi(2) / (self.pp * self.mm)).min(1.0)
    }
}

impl Problem<'_> {
    fn sums(&self, offset: f64, readout: f64) -> Sums {
        let mut s = Sums::default();
        let (t0, t1) = self.angle.span();
        let c = 0.5 * self.exposure_s - offset;
        for p in self.obs {
            if p.t_prev + c < t0 || p.t_cur + c + readout > t1 {
                continue;
            }
            s.pairs += 1;
            for l in &p.lines {
                let dt = c + readout * l.line;
                let (Some(a), Some(b)) =
                    (self.angle.at(p.t_prev + dt), self.angle.at(p.t_cur + dt))
                else {
                    continue;
                };
                let d = b - a;
                s.mp += l.g.dot(d);
                s.pp += l.quad(d);
                s.mm += l.c;
            }
        }
        s
    }

    /// Frame pairs inside the log at `offset` with `readout`.
    fn pairs(&self, offset: f64, readout: f64) -> usize {
        let (t0, t1) = self.angle.span();
        let c = 0.5 * self.exposure_s - offset;
        self.obs
            .iter()
            .filter(|p| p.t_prev + c >= t0 && p.t_cur + c + readout <= t1)
            .count()
    }
}

/// The result of the search.
#[derive(Debug, Clone)]
pub struct Estimate {
    /// Offset, s: video time = gyro time + offset.
    pub offset_s: f64,
    /// Best readout of the scan, s.
    pub readout_s: f64,
    /// Cost at the estimate (0..1).
    pub cost: f64,
    /// Lowest cost of the coarse grid farther than the exclusion from the estimate.
    pub rival_cost: f64,
    /// Offset of that rival, s.
    pub rival_offset_s: f64,
    /// `<m,p> / |p|^2` at the estimate: 1 when the focal length is right.
    pub scale: f64,
    /// Frame pairs scored at the estimate.
    pub pairs: usize,
    /// Per scanned readout: (readout s, best offset s, cost).
    pub readout_scan: Vec<(f64, f64, f64)>,
    /// Whether the readout scan's costs differ enough to choose one.
    pub readout_distinguishable: bool,
    /// 0..1: `(1 - cost) * (rival - cost) / rival`.
    pub confidence: f64,
}

/// Searches offsets in `centre +- half_range` (s) and readouts from 0 to 0.9
/// `frame_dt`. `Err` (a message for the caller to place) when fewer than
/// [`MIN_PAIRS`] frame pairs lie inside the log at every offset.
pub fn estimate(
    p: &Problem,
    centre: f64,
    half_range: f64,
    frame_dt: f64,
) -> std::result::Result<Estimate, usize> {
    let r_max = 0.9 * frame_dt;
    let readouts: Vec<f64> = (0..=READOUT_STEPS)
        .map(|i| r_max * i as f64 / READOUT_STEPS as f64)
        .collect();
    let r_mid = readouts[READOUT_STEPS / 2];
    let n = (2.0 * half_range / COARSE_STEP_S).ceil() as usize;
    let offsets: Vec<f64> = (0..=n)
        .map(|j| centre - half_range + 2.0 * half_range * j as f64 / n.max(1) as f64)
        .collect();
    let counts: Vec<usize> = offsets.par_iter().map(|&o| p.pairs(o, r_max)).collect();
    let most = counts.iter().copied().max().unwrap_or(0);
    if most < MIN_PAIRS {
        return Err(most);
    }
    let min_pairs = MIN_PAIRS.max(most / 2);
    let coarse: Vec<f64> = offsets
        .par_iter()
        .zip(&counts)
        .map(|(&o, &c)| {
            if c < min_pairs {
                f64::INFINITY
            } else {
                p.sums(o, r_mid).cost()
            }
        })
        .collect();
    let (jbest, _) = coarse
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .expect("offsets");
    let o_coarse = offsets[jbest];
    let refine = |r: f64| -> (f64, f64) {
        let m = (FINE_HALF_S / FINE_STEP_S).round() as i64;
        // A later readout moves the lines' times by (r - r_mid) x the mean
        // line fraction (about 1/2), and the best offset with them.
        let centre_r = o_coarse + 0.5 * (r - r_mid);
        let pts: Vec<(f64, f64)> = (-m..=m)
            .into_par_iter()
            .map(|k| {
                let o = centre_r + k as f64 * FINE_STEP_S;
                let s = p.sums(o, r);
                (
                    o,
                    if s.pairs < min_pairs {
                        f64::INFINITY
                    } else {
                        s.cost()
                    },
                )
            })
            .collect();
        let &(o_min, c_min) = pts
            .iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("points");
        let o = parabola(&pts, o_min, FIT_HALF_S).unwrap_or(o_min);
        let c = p.sums(o, r).cost();
        if c <= c_min {
            (o, c)
        } else {
            (o_min, c_min)
        }
    };
    let scan: Vec<(f64, f64, f64)> = readouts
        .iter()
        .map(|&r| {
            let (o, c) = refine(r);
            (r, o, c)
        })
        .collect();
    let &(readout_s, offset_s, cost) = scan
        .iter()
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .expect("readouts");
    let worst = scan.iter().map(|s| s.2).fold(0.0f64, f64::max);
    let readout_distinguishable = worst - cost > 0.2 * cost + 0.002;
    let exclude = (3.0 * frame_dt).max(0.1);
    let (rival_offset_s, rival_cost) = offsets
        .iter()
        .zip(&coarse)
        .filter(|(o, c)| (**o - offset_s).abs() > exclude && c.is_finite())
        .map(|(&o, &c)| (o, c))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((f64::NAN, 1.0));
    let s = p.sums(offset_s, readout_s);
    let scale = if s.pp > 0.0 { s.mp / s.pp } else { 0.0 };
    let uniqueness = if rival_cost > 0.0 {
        ((rival_cost - cost) / rival_cost).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let confidence = ((1.0 - cost) * uniqueness).clamp(0.0, 1.0);
    Ok(Estimate {
        offset_s,
        readout_s,
        cost,
        rival_cost,
        rival_offset_s,
        scale,
        pairs: s.pairs,
        readout_scan: scan,
        readout_distinguishable,
        confidence,
    })
}

/// The vertex of the least-squares parabola through the points within
/// `half` of `x0`, when it opens upwards and lies there.
fn parabola(pts: &[(f64, f64)], x0: f64, half: f64) -> Option<f64> {
    // Normal equations of y = a x^2 + b x + c in x - x0.
    let mut m = [[0.0f64; 3]; 3];
    let mut v = [0.0f64; 3];
    let mut n = 0;
    for &(x, y) in pts {
        let x = x - x0;
        if x.abs() > half || !y.is_finite() {
            continue;
        }
        let f = [x * x, x, 1.0];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += f[i] * f[j];
            }
            v[i] += f[i] * y;
        }
        n += 1;
    }
    if n < 5 {
        return None;
    }
    let [a, b, _] = solve3(m, v)?;
    if a <= 0.0 {
        return None;
    }
    let x = -b / (2.0 * a);
    (x.abs() <= half).then_some(x0 + x)
}

/// Solves a 3x3 system (Cramer's rule); `None` when singular.
fn solve3(m: [[f64; 3]; 3], v: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    if d.abs() < 1e-300 || !d.is_finite() {
        return None;
    }
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let mut mk = m;
        for i in 0..3 {
            mk[i][k] = v[i];
        }
        *o = det(&mk) / d;
    }
    Some(out)
}

/// Refuses a log shorter than [`MIN_PAIRS`] frame intervals, naming it.
pub fn check_log_length(what: &str, span: (f64, f64), frame_dt: f64) -> Result<()> {
    let need = MIN_PAIRS as f64 * frame_dt;
    if span.1 - span.0 < need {
        return Err(Error::invalid(
            what,
            format!(
                "spans only {:.3} s ({:.3} to {:.3} s): sync needs at least {MIN_PAIRS} frame \
                 intervals ({need:.3} s) of it over the video",
                span.1 - span.0,
                span.0,
                span.1
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parabola_vertex() {
        let pts: Vec<(f64, f64)> = (-20..=20)
            .map(|k| {
                let x = k as f64 * 1e-4;
                (x, 3.0 * (x - 2.3e-4).powi(2) + 0.1)
            })
            .collect();
        let v = parabola(&pts, 2e-4, 1.5e-3).unwrap();
        assert!((v - 2.3e-4).abs() < 1e-9, "{v}");
    }

    #[test]
    fn angle_integrates_trapezoids() {
        let a = Angle::new((0..=10).map(|i| (i as f64 * 0.1, DVec3::new(i as f64, 1.0, 0.0))));
        // x: integral of 10 t dt from 0 to 0.5 = 1.25; y: 0.5.
        let v = a.at(0.5).unwrap();
        assert!(
            (v.x - 1.25).abs() < 1e-12 && (v.y - 0.5).abs() < 1e-12,
            "{v}"
        );
        assert!(a.at(1.01).is_none());
    }
}
