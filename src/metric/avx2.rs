//! The grid rules' inner loops compiled for AVX2 + FMA (4-wide f64 square
//! roots), chosen at run time when the CPU has them. The only `unsafe` code
//! in the crate: calling a `#[target_feature]` function, after checking the
//! feature is present.
#![allow(unsafe_code)]

use super::grid::{riemann_impl, GridRule};
use crate::model::camera::SensorRect;
use crate::model::flow::FlowPoly;

/// True when the CPU has AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
fn available() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// The Riemann rule on AVX2 + FMA, or `None` when the CPU lacks them.
pub(super) fn riemann(poly: &FlowPoly, r: &SensorRect, nu: u32, nv: u32) -> Option<f64> {
    #[cfg(target_arch = "x86_64")]
    {
        if available() {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return Some(unsafe { riemann_avx2(poly, r, nu, nv) });
        }
    }
    let _ = (poly, r, nu, nv);
    None
}

/// A [`GridRule`]'s mean on AVX2 + FMA, or `None` when the CPU lacks them.
pub(super) fn rule_mean(rule: &GridRule, poly: &FlowPoly) -> Option<f64> {
    #[cfg(target_arch = "x86_64")]
    {
        if available() {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return Some(unsafe { rule_mean_avx2(rule, poly) });
        }
    }
    let _ = (rule, poly);
    None
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn riemann_avx2(poly: &FlowPoly, r: &SensorRect, nu: u32, nv: u32) -> f64 {
    riemann_impl(poly, r, nu, nv)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn rule_mean_avx2(rule: &GridRule, poly: &FlowPoly) -> f64 {
    rule.mean_speed_impl(poly)
}
