//! Exact MMBM: adaptive tensor Gauss-Kronrod (7/15) cubature in f64.
//!
//! The integrand `|flow|` has a kink (a cone) wherever the flow vanishes inside
//! the sensor, e.g. the principal point under pure roll. Fixed high-order
//! rules converge slowly there, so the sensor is bisected adaptively (the
//! region with the largest error estimate is split across its longer side)
//! until the summed error estimate falls below `tol * |value|`.
//! The per-region error estimate is `|K15xK15 - G7xG7|`, which is pessimistic
//! for smooth regions (it is the error of the lower-order rule).

use crate::camera::SensorRect;
use crate::model::flow::FlowPoly;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// 15-point Kronrod abscissae on [0, 1] (QUADPACK `qk15`), the last is 0.
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
/// Kronrod weights.
const WGK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_18,
    0.140_653_259_715_525_92,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_83,
];
/// 7-point Gauss weights for the Kronrod nodes 1, 3, 5, 7 (0-based odd indices).
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// The 15 nodes on [-1, 1] with Kronrod weights and Gauss weights (0 where not a Gauss node).
fn nodes() -> [(f64, f64, f64); 15] {
    let mut out = [(0.0, 0.0, 0.0); 15];
    for k in 0..7 {
        let g = if k % 2 == 1 { WG[k / 2] } else { 0.0 };
        out[k] = (-XGK[k], WGK[k], g);
        out[14 - k] = (XGK[k], WGK[k], g);
    }
    out[7] = (0.0, WGK[7], WG[3]);
    out
}

/// Result of the adaptive cubature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactResult {
    /// Mean flow speed over the sensor, mm/s.
    pub value: f64,
    /// Estimated absolute error of `value`, mm/s.
    pub error: f64,
    /// Integrand evaluations.
    pub evaluations: u64,
    /// Regions in the final partition.
    pub regions: usize,
}

#[derive(Debug, Clone, Copy)]
struct Region {
    r: SensorRect,
    value: f64,
    error: f64,
}

impl PartialEq for Region {
    fn eq(&self, o: &Self) -> bool {
        self.error == o.error
    }
}
impl Eq for Region {}
impl PartialOrd for Region {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Region {
    fn cmp(&self, o: &Self) -> Ordering {
        self.error.total_cmp(&o.error)
    }
}

/// Integrates `|flow|` over `r` (a sub-rectangle), returning the contribution
/// to the mean (integral / `total_area`) with the Kronrod rule and its error.
fn rule<F: Fn(f64, f64) -> f64>(
    speed: &F,
    r: SensorRect,
    total_area: f64,
    nd: &[(f64, f64, f64); 15],
) -> Region {
    let (cu, hu) = ((r.u0 + r.u1) * 0.5, (r.u1 - r.u0) * 0.5);
    let (cv, hv) = ((r.v0 + r.v1) * 0.5, (r.v1 - r.v0) * 0.5);
    let (mut k, mut g) = (0.0, 0.0);
    for &(yv, kv, gv) in nd {
        let v = cv + hv * yv;
        let (mut rk, mut rg) = (0.0, 0.0);
        for &(yu, ku, gu) in nd {
            let s = speed(cu + hu * yu, v);
            rk += ku * s;
            rg += gu * s;
        }
        k += kv * rk;
        g += gv * rg;
    }
    let scale = hu * hv / total_area;
    Region {
        r,
        value: k * scale,
        error: ((k - g) * scale).abs(),
    }
}

/// Exact mean flow speed over `rect` (mm/s) to relative tolerance `tol`
/// (absolute when the value is 0), at most ~2 million evaluations.
pub fn exact(poly: &FlowPoly, rect: &SensorRect, tol: f64) -> ExactResult {
    exact_with(|u, v| poly.speed(u, v), rect, tol)
}

/// [`exact`] for any speed function `speed(u, v)` (mm/s at sensor point
/// `(u, v)` mm), e.g. through a lens distortion or over an exposure.
pub fn exact_with<F: Fn(f64, f64) -> f64>(speed: F, rect: &SensorRect, tol: f64) -> ExactResult {
    const MAX_REGIONS: usize = 10_000;
    let nd = nodes();
    let area = rect.area();
    let first = rule(&speed, *rect, area, &nd);
    let mut heap = BinaryHeap::new();
    let (mut value, mut error) = (first.value, first.error);
    heap.push(first);
    let mut evals = 225u64;
    while error > tol * value.abs() && heap.len() < MAX_REGIONS {
        let worst = heap.pop().expect("heap is never empty");
        let r = worst.r;
        let (a, b) = if r.u1 - r.u0 >= r.v1 - r.v0 {
            let m = 0.5 * (r.u0 + r.u1);
            (SensorRect { u1: m, ..r }, SensorRect { u0: m, ..r })
        } else {
            let m = 0.5 * (r.v0 + r.v1);
            (SensorRect { v1: m, ..r }, SensorRect { v0: m, ..r })
        };
        let (ra, rb) = (rule(&speed, a, area, &nd), rule(&speed, b, area, &nd));
        evals += 450;
        value += ra.value + rb.value - worst.value;
        error += ra.error + rb.error - worst.error;
        heap.push(ra);
        heap.push(rb);
        // Re-sum now and then so that cancellation in the running sums cannot
        // stall or fool the stopping test.
        if heap.len() % 64 == 0 {
            value = heap.iter().map(|r| r.value).sum();
            error = heap.iter().map(|r| r.error).sum();
        }
    }
    let value: f64 = heap.iter().map(|r| r.value).sum();
    let error: f64 = heap.iter().map(|r| r.error).sum();
    ExactResult {
        value,
        error,
        evaluations: evals,
        regions: heap.len(),
    }
}

/// `int_0^a int_0^b sqrt(x^2 + y^2) dy dx`, extended as an odd function in
/// each argument (so signed corners can be combined by inclusion-exclusion).
fn corner_integral(x: f64, y: f64) -> f64 {
    let (a, b) = (x.abs(), y.abs());
    if a == 0.0 || b == 0.0 {
        return 0.0;
    }
    let d = (a * a + b * b).sqrt();
    let g =
        (2.0 * a * b * d + a.powi(3) * ((b + d) / a).ln() + b.powi(3) * ((a + d) / b).ln()) / 6.0;
    g * x.signum() * y.signum()
}

/// Closed form for pure roll: the mean distance (mm) from the principal point
/// to the points of the sensor rectangle. MMBM under roll `wz` is `|wz|` times this.
pub fn roll_mean_closed_form(r: &SensorRect) -> f64 {
    let i = corner_integral(r.u1, r.v1) - corner_integral(r.u0, r.v1) - corner_integral(r.u1, r.v0)
        + corner_integral(r.u0, r.v0);
    i / r.area()
}
