//! CPU twin of `render.wgsl`: the same samples, homography table,
//! background box and texture maths in f32, one pixel per task (rayon).

use super::layout::{GpuHomography, RenderParams, KIND_BLOBS, KIND_CHECKER};
use super::pixel_map::{pixel_map, PixelMap};
use super::sampling::{concentric, lens_shifts, shifts};
use super::texture::MipTexture;
use crate::gpu::lens::MODEL_NONE;
use glam::Vec3;
use rayon::prelude::*;

#[inline]
fn v3(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

#[inline]
fn fract(x: f32) -> f32 {
    x - x.floor()
}

/// Radiance (linear RGB) seen at pixel point `(px, py)` through homography `h`.
#[inline]
fn shade(p: &RenderParams, tex: Option<&MipTexture>, h: &GpuHomography, px: f32, py: f32) -> Vec3 {
    let bg = v3(p.background);
    let w = h.h2[0] * px + h.h2[1] * py + h.h2[2];
    if w.is_nan() || w <= 0.0 {
        return bg;
    }
    let r = 1.0 / w;
    let a = (h.h0[0] * px + h.h0[1] * py + h.h0[2]) * r;
    let b = (h.h1[0] * px + h.h1[1] * py + h.h1[2]) * r;
    match p.dims[2] {
        KIND_CHECKER => {
            let inv_sz = p.tex[1];
            let k = (a * inv_sz).floor() as i32 + (b * inv_sz).floor() as i32;
            let w = if k & 1 == 0 { 1.0 } else { 0.0 };
            Vec3::splat(w)
        }
        KIND_BLOBS => {
            let (sq, pitch, half) = (p.tex[0], p.tex[1], p.tex[2]);
            if a.abs() > half || b.abs() > half {
                return poster_point(p, a, b);
            }
            let inv_pitch = p.tex[3];
            let ca = ((a * inv_pitch + 2.0).floor().clamp(0.0, 3.0) - 1.5) * pitch;
            let cb = ((b * inv_pitch + 2.0).floor().clamp(0.0, 3.0) - 1.5) * pitch;
            if (a - ca).abs() <= 0.5 * sq && (b - cb).abs() <= 0.5 * sq {
                v3(p.colour_a)
            } else {
                v3(p.colour_b)
            }
        }
        _ => {
            let Some(t) = tex else { return bg };
            let u = a / p.tex[0] + 0.5;
            let v = b / p.tex[1] + 0.5;
            if !(0.0..=1.0).contains(&u) || !(0.0..=1.0).contains(&v) {
                return poster_point(p, a, b);
            }
            // Footprint side (m) = sqrt(|det H| / w^3); in texels of level 0.
            let texels = (h.h2[3] * r * r * r).sqrt() * p.tex[2];
            let lod = (texels * p.lod[0]).max(1.0).log2();
            Vec3::from(t.trilinear(u, v, lod))
        }
    }
}

/// Twin of the shader's `poster_point`: the poster (`super::poster`) at
/// plane point `(a, b)`, or the plain background without one.
#[inline]
fn poster_point(p: &RenderParams, a: f32, b: f32) -> Vec3 {
    let mut c = v3(p.background);
    if p.lod[2] == 0.0 || a.abs() > p.poster[1][3] || b.abs() > p.poster[3][3] {
        return c;
    }
    for k in 0..p.lod[2] as usize {
        let [_, is, pa, pb] = p.poster[2 * k];
        let sa = ((a + pa) * is).floor() as i32;
        let sb = ((b + pb) * is).floor() as i32;
        let v = if (sa + sb) & 1 == 0 { 1.0 } else { -1.0 };
        c += v * v3(p.poster[2 * k + 1]);
    }
    c
}

/// Twin of the shader's `poster_mean`: the poster averaged over a footprint
/// with marginal half-widths `(pa, qa)` along `a` and `(pb, qb)` along `b`.
#[inline]
fn poster_mean(p: &RenderParams, a: f32, b: f32, w: [f32; 4]) -> Vec3 {
    let bg = v3(p.background);
    let (ha, hb) = (p.poster[1][3], p.poster[3][3]);
    // The poster's coverage of the footprint (independent axes, as the board's).
    let cover =
        trap_in(-ha, ha, a, w[0], w[1], TINY * ha) * trap_in(-hb, hb, b, w[2], w[3], TINY * hb);
    if cover <= 0.0 {
        return bg;
    }
    let mut c = bg;
    for k in 0..p.lod[2] as usize {
        let [sz, is, oa, ob] = p.poster[2 * k];
        let m = square_mean(a + oa, w[0], w[1], sz, is) * square_mean(b + ob, w[2], w[3], sz, is);
        c += m * v3(p.poster[2 * k + 1]);
    }
    bg + (c - bg) * cover
}

/// Twin of the shader's `lens_sample`: the sample through lens point `l`
/// (m) of the instant whose three table entries start at `e`.
#[inline]
fn lens_sample(
    p: &RenderParams,
    tex: Option<&MipTexture>,
    homs: &[GpuHomography],
    e: usize,
    l: (f32, f32),
    qx: f32,
    qy: f32,
) -> Vec3 {
    let (h, gx, gy) = (&homs[e], &homs[e + 1], &homs[e + 2]);
    let mix = |a: [f32; 4], b: [f32; 4], c: [f32; 4], w: f32| {
        [
            a[0] + l.0 * b[0] + l.1 * c[0],
            a[1] + l.0 * b[1] + l.1 * c[1],
            a[2] + l.0 * b[2] + l.1 * c[2],
            w,
        ]
    };
    let hl = GpuHomography {
        h0: mix(
            h.h0,
            gx.h0,
            gy.h0,
            h.h0[3] + l.0 * gx.h0[3] + l.1 * gy.h0[3],
        ),
        h1: mix(
            h.h1,
            gx.h1,
            gy.h1,
            h.h1[3] + l.0 * gx.h1[3] + l.1 * gy.h1[3],
        ),
        h2: mix(h.h2, gx.h2, gy.h2, h.h2[3]),
    };
    let px = qx - (l.0 * p.lens[1] + l.1 * p.lens[3]);
    let py = qy - l.1 * p.lens[2];
    shade(p, tex, &hl, px, py)
}

/// Twin of the shader's `line_base`: the first table entry of pixel `(i, j)`'s
/// line (rolling shutter: one set of instants per row or column).
#[inline]
pub fn line_base(p: &RenderParams, i: u32, j: u32) -> u32 {
    match p.range2[2] {
        1 => j * p.dims[3],
        2 => i * p.dims[3],
        _ => 0,
    }
}

/// Sum (not mean) of the samples `k0..k1` of pixel `(i, j)`.
pub fn pixel_sum(
    p: &RenderParams,
    homs: &[GpuHomography],
    tex: Option<&MipTexture>,
    i: u32,
    j: u32,
) -> Vec3 {
    let n = p.dims[3];
    let count = p.range[2] - p.range[1];
    let b = p.bbox;
    if i < b[0] || j < b[1] || i >= b[2] || j >= b[3] {
        return v3(p.background) * count as f32;
    }
    let (g1, g2, seed) = (p.lattice[0], p.lattice[1], p.lattice[3]);
    let (shx, shy) = shifts(i, j, seed);
    let inv_n = p.lod[1];
    let (mut xi, mut yi) = (p.range[3], p.range2[0]);
    let mut acc = Vec3::ZERO;
    let (fi, fj) = (i as f32, j as f32);
    let base = line_base(p, i, j);
    let map = (p.distortion.model != MODEL_NONE).then(|| pixel_map(p, homs, i, j));
    let (shlx, shly) = lens_shifts(i, j, seed);
    let (mut xl, mut yl) = (p.lens_gen[2], p.lens_gen[3]);
    for k in p.range[1]..p.range[2] {
        let sx = fract(xi as f32 * inv_n + shx);
        let sy = fract(yi as f32 * inv_n + shy);
        let (qx, qy) = match map {
            Some(m) => pixel_point(&m, sx, sy),
            None => (fi + sx, fj + sy),
        };
        if p.lens[0] > 0.0 {
            let d = concentric(
                fract(xl as f32 * inv_n + shlx),
                fract(yl as f32 * inv_n + shly),
            );
            let l = (d.0 * p.lens[0], d.1 * p.lens[0]);
            acc += lens_sample(p, tex, homs, ((base + k) * 3) as usize, l, qx, qy);
            xl += p.lens_gen[0];
            if xl >= n {
                xl -= n;
            }
            yl += p.lens_gen[1];
            if yl >= n {
                yl -= n;
            }
        } else {
            acc += shade(p, tex, &homs[(base + k) as usize], qx, qy);
        }
        xi += g1;
        if xi >= n {
            xi -= n;
        }
        yi += g2;
        if yi >= n {
            yi -= n;
        }
    }
    acc
}

/// Renders the whole image on the CPU: linear RGB, interleaved, mean over the
/// `N` samples (or instants, `analytic`; images: `exact`) of each pixel.
/// `threads = Some(1)` runs single-threaded.
pub fn render(
    p: &RenderParams,
    homs: &[GpuHomography],
    tex: Option<&MipTexture>,
    analytic: bool,
    threads: Option<usize>,
) -> Vec<f32> {
    render_window(
        p,
        homs,
        tex,
        analytic,
        threads,
        [0, 0, p.dims[0], p.dims[1]],
    )
}

/// [`render`] of the pixels `[x0, y0, w, h]` only (inside the image), row-major:
/// each pixel is the same number as in the whole image's render.
pub fn render_window(
    p: &RenderParams,
    homs: &[GpuHomography],
    tex: Option<&MipTexture>,
    analytic: bool,
    threads: Option<usize>,
    [x0, y0, w, h]: [u32; 4],
) -> Vec<f32> {
    let inv = 1.0 / p.dims[3] as f32;
    // Once a stop is requested (crate::cancel) the pixels left are skipped;
    // the caller checks the token and drops the image.
    let stop = crate::cancel::current();
    let run = || {
        let mut out = vec![0.0f32; (w as usize) * (h as usize) * 3];
        out.par_chunks_mut(3).enumerate().for_each(|(idx, o)| {
            if stop.is_cancelled() {
                return;
            }
            let (i, j) = (x0 + idx as u32 % w, y0 + idx as u32 / w);
            let s = if let (true, Some(t)) = (analytic, tex) {
                super::exact::pixel_sum(p, homs, t, line_base(p, i, j), i, j)
            } else if analytic {
                pixel_sum_analytic(p, homs, i, j)
            } else {
                pixel_sum(p, homs, tex, i, j)
            };
            o.copy_from_slice(&(s * inv).to_array());
        });
        out
    };
    match threads {
        Some(t) => match rayon::ThreadPoolBuilder::new().num_threads(t).build() {
            Ok(pool) => pool.install(run),
            Err(_) => run(),
        },
        None => run(),
    }
}

// ---- analytic area integration (twin of the same names in render.wgsl) ----
//
// At one instant the pixel square maps, through the affine part of the
// homography at the pixel centre, to a parallelogram in target coordinates:
// `a = a_c + x * J_ax + y * J_ay` with `x, y` uniform on [-1/2, 1/2], so `a`
// is `a_c + U(-p, p) + U(-q, q)` with `p, q` the larger and smaller of
// `|J_ax| / 2`, `|J_ay| / 2` (a trapezoidal distribution), and likewise `b`.
// The kernel averages the target over these two marginals, taken as
// independent (exact for axis-aligned footprints and wherever one edge
// crosses the footprint).
//
// Checker: value = (1 + s(a) s(b)) / 2 with the square wave s (period 2S).
// With T = integral of s (a triangle wave) and M(c) = mean of T over
// [c - q, c + q], E[s(a_c + U_p + U_q)] = (M(a_c + p) - M(a_c - p)) / (2p).
// M is T plus, when a kink of T (at multiples of S, slope change +-2) lies
// within q of c, delta * (q - d)^2 / (4q) (d: distance to the kink); for
// q >= S/4 it is the difference of the integral of T. Blob board: interval
// probabilities of the trapezoid, from its CDF
// F(x) = (R(x + p) - R(x - p)) / (2p), R(c) = mean of max(c, 0) over [c - q, c + q].

/// Feature-relative width below which a footprint is a point.
const TINY: f32 = 0.001;

fn tri(x: f32, sz: f32, is: f32) -> f32 {
    let y = x - (x * (0.5 * is)).floor() * (2.0 * sz);
    if y < sz {
        y
    } else {
        2.0 * sz - y
    }
}

fn tri_int(y: f32, sz: f32, is: f32) -> f32 {
    let per = (y * (0.5 * is)).floor();
    let r = y - per * 2.0 * sz;
    let v = if r >= sz {
        0.5 * sz * sz + 2.0 * sz * (r - sz) - 0.5 * (r * r - sz * sz)
    } else {
        0.5 * r * r
    };
    per * sz * sz + v
}

fn tri_mean(c: f32, q: f32, sz: f32, is: f32) -> f32 {
    if q < TINY * sz {
        return tri(c, sz, is);
    }
    if q < 0.25 * sz {
        let k = (c * is).round();
        let d = (c - k * sz).abs();
        let mut m = tri(c, sz, is);
        if d < q {
            let delta = if (k as i32) & 1 == 0 { 2.0 } else { -2.0 };
            m += delta * (q - d) * (q - d) / (4.0 * q);
        }
        return m;
    }
    let base = ((c - q) * (0.5 * is)).floor() * (2.0 * sz);
    (tri_int(c + q - base, sz, is) - tri_int(c - q - base, sz, is)) / (2.0 * q)
}

/// Mean of the square wave over `x + U(-p, p) + U(-q, q)`, `p >= q`
/// (`sz` = S, `is` = 1/S).
pub fn square_mean(x: f32, p: f32, q: f32, sz: f32, is: f32) -> f32 {
    // No edge within reach (most footprints), or a point footprint: s(x).
    let k = (x * is).round();
    if (x - k * sz).abs() >= p + q || p < TINY * sz {
        return if ((x * is).floor() as i32) & 1 == 0 {
            1.0
        } else {
            -1.0
        };
    }
    (tri_mean(x + p, q, sz, is) - tri_mean(x - p, q, sz, is)) / (2.0 * p)
}

fn ramp_mean(c: f32, q: f32, tiny: f32) -> f32 {
    let mut m = c.max(0.0);
    if q >= tiny && c.abs() < q {
        m += (q - c.abs()) * (q - c.abs()) / (4.0 * q);
    }
    m
}

/// `P(U(-p, p) + U(-q, q) <= x)`, `p >= q`.
pub fn trap_cdf(x: f32, p: f32, q: f32, tiny: f32) -> f32 {
    if x >= p + q {
        return 1.0;
    }
    if x <= -(p + q) {
        return 0.0;
    }
    if p < tiny {
        return if x >= 0.0 { 1.0 } else { 0.0 };
    }
    ((ramp_mean(x + p, q, tiny) - ramp_mean(x - p, q, tiny)) / (2.0 * p)).clamp(0.0, 1.0)
}

fn trap_in(lo: f32, hi: f32, c: f32, p: f32, q: f32, tiny: f32) -> f32 {
    trap_cdf(hi - c, p, q, tiny) - trap_cdf(lo - c, p, q, tiny)
}

fn board_axis(prm: &RenderParams, c: f32, p: f32, q: f32) -> (f32, f32) {
    let (sq, pitch, half) = (prm.tex[0], prm.tex[1], prm.tex[2]);
    let tiny = TINY * sq;
    let board = trap_in(-half, half, c, p, q, tiny);
    let mut blobs = 0.0;
    for k in 0..4 {
        let cc = (k as f32 - 1.5) * pitch;
        blobs += trap_in(cc - 0.5 * sq, cc + 0.5 * sq, c, p, q, tiny);
    }
    (board, blobs)
}

/// The target averaged over the footprint of pixel centre `(px, py)` through `h`.
fn footprint_mean(prm: &RenderParams, h: &GpuHomography, px: f32, py: f32) -> Vec3 {
    let bg = v3(prm.background);
    let w = h.h2[0] * px + h.h2[1] * py + h.h2[2];
    if w.is_nan() || w <= 0.0 {
        return bg;
    }
    let r = 1.0 / w;
    let a = (h.h0[0] * px + h.h0[1] * py + h.h0[2]) * r;
    let b = (h.h1[0] * px + h.h1[1] * py + h.h1[2]) * r;
    let dax = ((h.h0[0] - a * h.h2[0]) * r).abs();
    let day = ((h.h0[1] - a * h.h2[1]) * r).abs();
    let dbx = ((h.h1[0] - b * h.h2[0]) * r).abs();
    let dby = ((h.h1[1] - b * h.h2[1]) * r).abs();
    footprint_eval(prm, a, b, [dax, day, dbx, dby])
}

/// Twin of the shader's `footprint_mean_l`: the footprint through the
/// pixel's undistortion Jacobian `l` (rows `l[0]`, `l[1]`) at the pinhole
/// pixel point `(px, py)`.
fn footprint_mean_l(
    prm: &RenderParams,
    h: &GpuHomography,
    px: f32,
    py: f32,
    l: [[f32; 2]; 2],
) -> Vec3 {
    let bg = v3(prm.background);
    let w = h.h2[0] * px + h.h2[1] * py + h.h2[2];
    if w.is_nan() || w <= 0.0 {
        return bg;
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
    footprint_eval(prm, a, b, d)
}

/// Twin of the shader's `footprint_eval`: the target averaged over the
/// footprint with axis extents `d = [|da/dx|, |da/dy|, |db/dx|, |db/dy|]`.
fn footprint_eval(prm: &RenderParams, a: f32, b: f32, d: [f32; 4]) -> Vec3 {
    let bg = v3(prm.background);
    let [dax, day, dbx, dby] = d;
    let (pa, qa) = (0.5 * dax.max(day), 0.5 * dax.min(day));
    let (pb, qb) = (0.5 * dbx.max(dby), 0.5 * dbx.min(dby));
    if prm.dims[2] == KIND_CHECKER {
        let (sz, is) = (prm.tex[0], prm.tex[1]);
        let m = square_mean(a, pa, qa, sz, is) * square_mean(b, pb, qb, sz, is);
        return Vec3::splat(0.5 + 0.5 * m);
    }
    let (ba, ca) = board_axis(prm, a, pa, qa);
    let (bb, cb) = board_axis(prm, b, pb, qb);
    let (white, red) = (v3(prm.colour_b), v3(prm.colour_a));
    // Behind the board: the poster where there is one (not needed where the
    // board covers the whole footprint).
    let board = ba * bb;
    let bg = if prm.lod[2] > 0.0 && board < 1.0 {
        poster_mean(prm, a, b, [pa, qa, pb, qb])
    } else {
        bg
    };
    bg + (white - bg) * board + (red - white) * (ca * cb)
}

/// Twin of the shader's `pixel_point`: sample `(sx, sy)` of a pixel through
/// its distortion map `m`.
#[inline]
fn pixel_point(m: &PixelMap, sx: f32, sy: f32) -> (f32, f32) {
    let (dx, dy) = (sx - 0.5, sy - 0.5);
    (
        m.p[0] + m.l[0][0] * dx + m.l[0][1] * dy,
        m.p[1] + m.l[1][0] * dx + m.l[1][1] * dy,
    )
}

/// Sum over the instants `k0..k1` of pixel `(i, j)` (analytic area).
pub fn pixel_sum_analytic(p: &RenderParams, homs: &[GpuHomography], i: u32, j: u32) -> Vec3 {
    let count = p.range[2] - p.range[1];
    let b = p.bbox;
    if i < b[0] || j < b[1] || i >= b[2] || j >= b[3] {
        return v3(p.background) * count as f32;
    }
    let (px, py) = (i as f32 + 0.5, j as f32 + 0.5);
    let mut acc = Vec3::ZERO;
    let base = line_base(p, i, j);
    if p.distortion.model != MODEL_NONE {
        let m = pixel_map(p, homs, i, j);
        for k in p.range[1]..p.range[2] {
            acc += footprint_mean_l(p, &homs[(base + k) as usize], m.p[0], m.p[1], m.l);
        }
        return acc;
    }
    for k in p.range[1]..p.range[2] {
        acc += footprint_mean(p, &homs[(base + k) as usize], px, py);
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: E[f(x + U(-p, p) + U(-q, q))] on a fine 2-D grid (f64).
    fn brute(f: impl Fn(f64) -> f64, x: f64, p: f64, q: f64) -> f64 {
        let n = 800;
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

    #[test]
    fn square_mean_matches_brute_force() {
        let sz = 0.02f64;
        let sq = |y: f64| {
            if (y / sz).floor() as i64 % 2 == 0 {
                1.0
            } else {
                -1.0
            }
        };
        // Footprints from a point to several squares, near and far from edges,
        // at both signs of x (the regimes of tri_mean).
        for &(x, p, q) in &[
            (0.0105, 0.001, 0.0),
            (0.0195, 0.0012, 0.0004),
            (-0.0403, 0.002, 0.0019),
            (0.5012, 0.004, 0.003),
            (0.013, 0.009, 0.006),
            (-0.27, 0.03, 0.011),
            (0.0101, 0.000_001, 0.0),
        ] {
            let got = square_mean(x as f32, p as f32, q as f32, sz as f32, (1.0 / sz) as f32);
            let want = brute(sq, x, p, q);
            assert!(
                (got as f64 - want).abs() < 2e-3,
                "x {x} p {p} q {q}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn trapezoid_cdf_matches_brute_force() {
        let step = |y: f64| if y <= 0.0 { 1.0 } else { 0.0 };
        for &(x, p, q) in &[
            (0.0, 1.0, 0.5),
            (0.7, 1.0, 0.5),
            (-1.2, 1.0, 0.5),
            (0.3, 1.0, 0.0),
            (0.2, 0.5, 0.5),
            (-0.05, 0.3, 0.001),
        ] {
            let got = trap_cdf(x as f32, p as f32, q as f32, 1e-6);
            // P(U + V <= x) = E[step(U + V - x)]
            let want = brute(step, -x, p, q);
            assert!(
                (got as f64 - want).abs() < 2e-3,
                "x {x} p {p} q {q}: {got} vs {want}"
            );
        }
    }
}
