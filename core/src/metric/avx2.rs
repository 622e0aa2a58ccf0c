//! The grid rules' inner loops, compiled twice: plainly and for AVX2 + FMA
//! (4-wide f64 square roots), the AVX2 build chosen at run time when the CPU
//! has it. The only `unsafe` code in the crate: calling a
//! `#[target_feature]` function after checking that the feature is present.
#![allow(unsafe_code)]

use crate::camera::SensorRect;
use crate::model::flow::FlowPoly;

/// True when the CPU has AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
fn available() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// The Riemann rule: mean speed at the centres of `nu x nv` cells of `r`, mm/s.
pub(super) fn riemann(poly: &FlowPoly, r: &SensorRect, nu: u32, nv: u32) -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        if available() {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return unsafe { riemann_avx2(poly, r, nu, nv) };
        }
    }
    riemann_impl(poly, r, nu, nv)
}

/// A weighted point rule's sum (see [`rule_impl`]), mm/s.
pub(super) fn rule_mean(m: &[Vec<f64>; 5], w: &[f64], poly: &FlowPoly) -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        if available() {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return unsafe { rule_avx2(m, w, poly) };
        }
    }
    rule_impl(m, w, poly)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn riemann_avx2(poly: &FlowPoly, r: &SensorRect, nu: u32, nv: u32) -> f64 {
    riemann_impl(poly, r, nu, nv)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn rule_avx2(m: &[Vec<f64>; 5], w: &[f64], poly: &FlowPoly) -> f64 {
    rule_impl(m, w, poly)
}

/// The body of [`super::grid::riemann`].
#[inline(always)]
fn riemann_impl(poly: &FlowPoly, r: &SensorRect, nu: u32, nv: u32) -> f64 {
    let du = (r.u1 - r.u0) / nu as f64;
    let dv = (r.v1 - r.v0) / nv as f64;
    let (p, q) = (&poly.du, &poly.dv);
    let mut total = 0.0;
    for j in 0..nv {
        let v = r.v0 + (j as f64 + 0.5) * dv;
        // Along a row both components are quadratics in u: a0 + a1 u + a2 u^2.
        let (a0, a1, a2) = (p[0] + v * (p[2] + p[5] * v), p[1] + p[4] * v, p[3]);
        let (b0, b1, b2) = (q[0] + v * (q[2] + q[5] * v), q[1] + q[4] * v, q[3]);
        // Full blocks of 8 cells in straight-line code the compiler
        // vectorises (square roots included), then the remainder.
        let mut acc = [0.0f64; 8];
        let full = nu / 8 * 8;
        let mut i = 0u32;
        while i < full {
            let base = r.u0 + (i as f64 + 0.5) * du;
            for (k, a) in acc.iter_mut().enumerate() {
                let u = base + k as f64 * du;
                let x = a0 + u * (a1 + a2 * u);
                let y = b0 + u * (b1 + b2 * u);
                *a += (x * x + y * y).sqrt();
            }
            i += 8;
        }
        for i in full..nu {
            let u = r.u0 + (i as f64 + 0.5) * du;
            let x = a0 + u * (a1 + a2 * u);
            let y = b0 + u * (b1 + b2 * u);
            acc[0] += (x * x + y * y).sqrt();
        }
        total += acc.iter().sum::<f64>();
    }
    total / (nu as f64 * nv as f64)
}

/// The body of [`super::GridRule::mean_speed`]: the weighted sum over the
/// rule's points, whose monomials `u, v, u^2, uv, v^2` are `m` and weights
/// `w` (lengths a multiple of 8, zero-padded).
#[inline(always)]
fn rule_impl(m: &[Vec<f64>; 5], w: &[f64], poly: &FlowPoly) -> f64 {
    let (p, q) = (&poly.du, &poly.dv);
    let mut acc = [0.0f64; 8];
    let chunks = m[0]
        .chunks_exact(8)
        .zip(m[1].chunks_exact(8))
        .zip(m[2].chunks_exact(8))
        .zip(m[3].chunks_exact(8))
        .zip(m[4].chunks_exact(8))
        .zip(w.chunks_exact(8));
    for (((((u, v), uu), uv), vv), w) in chunks {
        for k in 0..8 {
            let x = p[0] + p[1] * u[k] + p[2] * v[k] + p[3] * uu[k] + p[4] * uv[k] + p[5] * vv[k];
            let y = q[0] + q[1] * u[k] + q[2] * v[k] + q[3] * uu[k] + q[4] * uv[k] + q[5] * vv[k];
            acc[k] += w[k] * (x * x + y * y).sqrt();
        }
    }
    acc.iter().sum()
}
