//! Closed-form pixel area for image textures (the `analytic` integrator on
//! `image:` targets): CPU twin of `texture.wgsl` (same names, f32).
//!
//! The image is the bilinear interpolant of the linear-light texels of one
//! mip level (texel centres at integer texel coordinates `x = u w - 1/2`,
//! clamped to the edge texels out to the image's border `x = -1/2`,
//! `w - 1/2`; background beyond). At one instant the pixel's footprint is
//! taken as in `cpu.rs` (`footprint_mean`): the affine part of the
//! homography at the pixel centre, its marginals along the target's axes
//! trapezoids `U(-p, p) + U(-q, q)`, taken as independent. The bilinear
//! interpolant is a sum of products `T[m, n] hat(x - m) hat(y - n)`, so its
//! mean is `sum wx[m] wy[n] T[m, n]` with `wx[m]` the mean of the (clamped,
//! cut) hat of node `m` under the x trapezoid: exact, from the hat's twice
//! integrated form (a second difference of a piecewise cubic), evaluated
//! locally so that nothing large cancels in f32.
//!
//! With `R(c) = E[max(c + X, 0)]` (X the trapezoid), a hat is
//! `max(t + 1, 0) - 2 max(t, 0) + max(t - 1, 0)`, so its mean at `t` is
//! `R(t + 1) - 2 R(t) + R(t - 1)`; the edge nodes' pieces (constant out to
//! the border, then background) add the trapezoid's CDF. `R` is the first
//! difference over `p` of the mean of `max(z, 0)^2 / 2` over `[z - q, z + q]`
//! (a closed-form piecewise cubic), so no step divides by `q`.
//!
//! Cost and level: a footprint reaching `s = p + q` texels from its centre
//! touches at most `2 s + 3` nodes per axis; the kernel uses the finest mip
//! level where `s <= MAX_REACH` on both axes (`MAX_NODES` nodes, at most
//! `MAX_NODES^2` texel reads per instant). Level 0 (the image as loaded)
//! whenever a pixel covers at most about 5 texels; coarser levels (2x2 box
//! averages) only for more minified footprints, where the lattice reference
//! also reads coarser levels. No tables are precomputed: the memory is the mip
//! pyramid the lattice already uses (4/3 of the image, 12 bytes a texel).

use super::layout::{GpuHomography, RenderParams};
use super::texture::MipTexture;
use glam::Vec3;

/// Most nodes per axis (the shader's weight arrays).
pub const MAX_NODES: usize = 8;
/// Largest footprint reach `p + q` (texels of the level used) per axis.
pub const MAX_REACH: f32 = 2.5;
/// Half-widths (texels) below which a uniform is a point: then the
/// trapezoid's formulas would divide by almost nothing.
const TINY: f32 = 1e-3;

/// Mean of `max(z, 0)^2 / 2` over `[z - q, z + q]`.
#[inline]
fn sq_mean(z: f32, q: f32) -> f32 {
    if z >= q {
        return 0.5 * z * z + q * q / 6.0;
    }
    if z <= -q {
        return 0.0;
    }
    let t = z + q;
    t * t * t / (12.0 * q)
}

/// Mean of `max(z, 0)` over `[z - q, z + q]`.
#[inline]
fn lin_mean(z: f32, q: f32) -> f32 {
    if z >= q {
        return z;
    }
    if z <= -q {
        return 0.0;
    }
    let t = z + q;
    t * t / (4.0 * q)
}

/// `E[max(c + X, 0)]`, X = U(-p, p) + U(-q, q), `p >= q`.
#[inline]
pub fn ramp(c: f32, p: f32, q: f32) -> f32 {
    if c >= p + q {
        return c;
    }
    if c <= -(p + q) {
        return 0.0;
    }
    if p < TINY {
        return c.max(0.0);
    }
    if q < TINY {
        // sq_mean with q = 0 is max(z, 0)^2 / 2.
        let (a, b) = ((c + p).max(0.0), (c - p).max(0.0));
        return (a * a - b * b) / (4.0 * p);
    }
    (sq_mean(c + p, q) - sq_mean(c - p, q)) / (2.0 * p)
}

/// `P(c + X > 0)`.
#[inline]
pub fn above(c: f32, p: f32, q: f32) -> f32 {
    if c >= p + q {
        return 1.0;
    }
    if c <= -(p + q) {
        return 0.0;
    }
    if p < TINY {
        return if c > 0.0 { 1.0 } else { 0.0 };
    }
    let m = |z: f32| {
        if q < TINY {
            z.max(0.0)
        } else {
            lin_mean(z, q)
        }
    };
    ((m(c + p) - m(c - p)) / (2.0 * p)).clamp(0.0, 1.0)
}

/// The weight of each node along one axis of `n` texels for a footprint
/// centred at texel coordinate `x` with half-widths `p >= q` (texels):
/// `(first node, count, weights, mass inside the image)`.
pub fn axis_weights(x: f32, p: f32, q: f32, n: u32) -> (u32, u32, [f32; MAX_NODES], f32) {
    let mut w = [0.0f32; MAX_NODES];
    let (lo, hi) = (-0.5f32, n as f32 - 0.5);
    let out_lo = 1.0 - above(x - lo, p, q);
    let out_hi = above(x - hi, p, q);
    let inside = (1.0 - out_lo - out_hi).max(0.0);
    let s = p + q;
    let m0 = ((x - s - 1.0).ceil().max(0.0)) as i64;
    let m1 = ((x + s + 1.0).floor() as i64).min(n as i64 - 1);
    if inside <= 0.0 || m1 < m0 {
        return (0, 0, w, 0.0);
    }
    let count = ((m1 - m0 + 1) as usize).min(MAX_NODES);
    // r[k] = R(x - m0 + 1 - k): node m0 + k reads r[k], r[k + 1], r[k + 2].
    let mut r = [0.0f32; MAX_NODES + 2];
    let t0 = x - m0 as f32 + 1.0;
    for (k, rk) in r.iter_mut().enumerate().take(count + 2) {
        *rk = ramp(t0 - k as f32, p, q);
    }
    for (k, wk) in w.iter_mut().enumerate().take(count) {
        let m = m0 + k as i64;
        *wk = if n == 1 {
            inside
        } else if m == 0 {
            // 1 out to the border, then down to 0 at node 1.
            1.0 - r[k + 1] + r[k + 2] - out_lo
        } else if m == n as i64 - 1 {
            r[k] - r[k + 1] - out_hi
        } else {
            r[k] - 2.0 * r[k + 1] + r[k + 2]
        };
    }
    (m0 as u32, count as u32, w, inside)
}

/// The image averaged over a footprint centred at target point `(a, b)` (m)
/// with axis extents `d = [|da/dx|, |da/dy|, |db/dx|, |db/dy|]` (m per px).
pub fn footprint_eval(prm: &RenderParams, t: &MipTexture, a: f32, b: f32, d: [f32; 4]) -> Vec3 {
    let bg = Vec3::new(prm.background[0], prm.background[1], prm.background[2]);
    let (wm, hm) = (prm.tex[0], prm.tex[1]);
    let (u, v) = (a / wm + 0.5, b / hm + 0.5);
    // Half-widths in the image's normalized coordinates.
    let (pa, qa) = (0.5 * d[0].max(d[1]) / wm, 0.5 * d[0].min(d[1]) / wm);
    let (pb, qb) = (0.5 * d[2].max(d[3]) / hm, 0.5 * d[2].min(d[3]) / hm);
    let last = t.levels.len() - 1;
    let mut l = 0;
    while l < last {
        let lv = &t.levels[l];
        if (pa + qa) * lv.w as f32 <= MAX_REACH && (pb + qb) * lv.h as f32 <= MAX_REACH {
            break;
        }
        l += 1;
    }
    let lv = &t.levels[l];
    let (sw, sh) = (lv.w as f32, lv.h as f32);
    let (x0, nx, wx, ix) = axis_weights(u * sw - 0.5, pa * sw, qa * sw, lv.w);
    let (y0, ny, wy, iy) = axis_weights(v * sh - 0.5, pb * sh, qb * sh, lv.h);
    let mut acc = bg * (1.0 - ix * iy);
    for (jy, &wyj) in wy.iter().enumerate().take(ny as usize) {
        let row = (y0 + jy as u32) * lv.w;
        let mut r = Vec3::ZERO;
        for (jx, &wxj) in wx.iter().enumerate().take(nx as usize) {
            let o = ((row + x0 + jx as u32) * 3) as usize;
            r += Vec3::new(lv.rgb[o], lv.rgb[o + 1], lv.rgb[o + 2]) * wxj;
        }
        acc += r * wyj;
    }
    acc
}

/// Twin of the shader's `texture_mean`: the image averaged over the
/// footprint of pinhole pixel point `(px, py)` through `h`, the pixel's axes
/// mapped by `l` (rows; the identity without distortion).
#[inline]
pub fn footprint_mean(
    prm: &RenderParams,
    t: &MipTexture,
    h: &GpuHomography,
    px: f32,
    py: f32,
    l: [[f32; 2]; 2],
) -> Vec3 {
    let w = h.h2[0] * px + h.h2[1] * py + h.h2[2];
    if w.is_nan() || w <= 0.0 {
        return Vec3::new(prm.background[0], prm.background[1], prm.background[2]);
    }
    let r = 1.0 / w;
    let a = (h.h0[0] * px + h.h0[1] * py + h.h0[2]) * r;
    let b = (h.h1[0] * px + h.h1[1] * py + h.h1[2]) * r;
    let sax = (h.h0[0] - a * h.h2[0]) * r;
    let say = (h.h0[1] - a * h.h2[1]) * r;
    let sbx = (h.h1[0] - b * h.h2[0]) * r;
    let sby = (h.h1[1] - b * h.h2[1]) * r;
    let d = [
        (sax * l[0][0] + say * l[1][0]).abs(),
        (sax * l[0][1] + say * l[1][1]).abs(),
        (sbx * l[0][0] + sby * l[1][0]).abs(),
        (sbx * l[0][1] + sby * l[1][1]).abs(),
    ];
    footprint_eval(prm, t, a, b, d)
}

/// Sum over the instants `k0..k1` of pixel `(i, j)`, whose line's first
/// table entry is `base` (twin of the shader's `texture` entry point).
pub fn pixel_sum(
    p: &RenderParams,
    homs: &[GpuHomography],
    t: &MipTexture,
    base: u32,
    i: u32,
    j: u32,
) -> Vec3 {
    let count = p.range[2] - p.range[1];
    let bb = p.bbox;
    if i < bb[0] || j < bb[1] || i >= bb[2] || j >= bb[3] {
        return Vec3::new(p.background[0], p.background[1], p.background[2]) * count as f32;
    }
    let (mut px, mut py) = (i as f32 + 0.5, j as f32 + 0.5);
    let mut l = [[1.0, 0.0], [0.0, 1.0]];
    if p.distortion.model != crate::gpu::lens::MODEL_NONE {
        let m = super::pixel_map::pixel_map(p, homs, i, j);
        ([px, py], l) = (m.p, m.l);
    }
    let mut acc = Vec3::ZERO;
    for k in p.range[1]..p.range[2] {
        acc += footprint_mean(p, t, &homs[(base + k) as usize], px, py, l);
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: E[f(x + U(-p, p) + U(-q, q))] on a fine 2-D grid (f64).
    fn brute(f: impl Fn(f64) -> f64, x: f64, p: f64, q: f64) -> f64 {
        let n = 600;
        let mut s = 0.0;
        for i in 0..n {
            for j in 0..n {
                let u = -p + 2.0 * p * (i as f64 + 0.5) / n as f64;
                let v = -q + 2.0 * q * (j as f64 + 0.5) / n as f64;
                s += f(x + u + v);
            }
        }
        s / (n * n) as f64
    }

    /// The clamped, cut 1-D interpolant of `vals` at texel coordinate `y`.
    fn interp(vals: &[f64], y: f64) -> f64 {
        let n = vals.len();
        if !(-0.5..=n as f64 - 0.5).contains(&y) {
            return 0.0;
        }
        let c = y.clamp(0.0, (n - 1) as f64);
        let m = (c.floor() as usize).min(n.saturating_sub(2));
        if n == 1 {
            return vals[0];
        }
        let f = c - m as f64;
        vals[m] * (1.0 - f) + vals[m + 1] * f
    }

    #[test]
    fn axis_weights_integrate_the_interpolant() {
        // Interior, both edges, out of the image, a 1- and a 2-texel axis,
        // box (q = 0), point (p = 0) and wide footprints.
        let vals6 = [0.3, 0.9, 0.1, 0.5, 0.7, 0.2];
        for (vals, x, p, q) in [
            (&vals6[..], 2.3, 0.6, 0.25),
            (&vals6[..], 0.1, 0.5, 0.5),
            (&vals6[..], -0.2, 1.1, 0.3),
            (&vals6[..], 5.4, 0.9, 0.0),
            (&vals6[..], 6.5, 1.2, 0.4),
            (&vals6[..], -3.0, 0.5, 0.2),
            (&vals6[..], 3.7, 0.0, 0.0),
            (&vals6[..], 2.5, 2.0, 0.5),
            (&vals6[..2], 0.4, 0.8, 0.3),
            (&vals6[..1], 0.2, 0.6, 0.2),
        ] {
            let (m0, cnt, w, inside) =
                axis_weights(x as f32, p as f32, q as f32, vals.len() as u32);
            let got: f64 = (0..cnt as usize)
                .map(|k| w[k] as f64 * vals[m0 as usize + k])
                .sum();
            let want = brute(|y| interp(vals, y), x, p, q);
            let in_want = brute(
                |y| f64::from(u8::from((-0.5..=vals.len() as f64 - 0.5).contains(&y))),
                x,
                p,
                q,
            );
            assert!(
                (got - want).abs() < 2e-3 && (inside as f64 - in_want).abs() < 2e-3,
                "x {x} p {p} q {q} n {}: {got} vs {want}, inside {inside} vs {in_want}",
                vals.len()
            );
        }
    }
}
