//! The warp integrator: each output pixel the mean, over `n` instants of
//! its line's exposure (midpoint rule), of the image's bilinear interpolant
//! at the image point its centre sees then. Its exact integral (`n` to
//! infinity) is the time integral of the interpolant along the pixel
//! centre's path; the number of instants is chosen from the largest path so
//! that neighbouring samples are at most `spacing` px apart
//! ([`super::Integrator`]), which keeps the error against that integral
//! within the image contract (mean 0.5/255, p99 3/255; `tests/augment/augment_api.rs`).
//!
//! Without motion (every instant's map the identity) the image is returned
//! as it is, never resampled.

use crate::error::{Error, Result};
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::str::FromStr;

/// What the image shows beyond its edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Border {
    /// Mirrored about the edge pixels (`dcb|abcd|cba`, OpenCV's
    /// `BORDER_REFLECT_101`, albumentations' default).
    #[default]
    Reflect,
    /// The edge pixels repeated.
    Replicate,
    /// A constant value (the background colour; transparent with alpha).
    Constant,
}

impl FromStr for Border {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "reflect" => Ok(Border::Reflect),
            "replicate" => Ok(Border::Replicate),
            "constant" => Ok(Border::Constant),
            _ => Err(Error::invalid(
                "border",
                format!("'{s}': expected reflect, replicate or constant"),
            )),
        }
    }
}

/// Index `i` of a line of `n` texels under `border` (`None`: constant).
#[inline]
fn wrap(i: i64, n: i64, border: Border) -> Option<usize> {
    if (0..n).contains(&i) {
        return Some(i as usize);
    }
    match border {
        Border::Constant => None,
        Border::Replicate => Some(i.clamp(0, n - 1) as usize),
        Border::Reflect => {
            let p = 2 * (n - 1);
            let m = i.rem_euclid(p);
            Some(if m < n { m } else { p - m } as usize)
        }
    }
}

/// A linear image, `c` channels interleaved.
pub struct Src<'a> {
    /// Width, px.
    pub w: usize,
    /// Height, px.
    pub h: usize,
    /// Channels.
    pub c: usize,
    /// Values.
    pub v: &'a [f32],
    /// Beyond the edges.
    pub border: Border,
    /// The constant border's value per channel.
    pub fill: &'a [f32],
}

impl Src<'_> {
    /// Adds `wt` times the bilinear interpolant at texel coordinates
    /// `(u, v)` (texel `i`'s centre at `i`) to `acc`.
    #[inline]
    fn add(&self, u: f32, v: f32, acc: &mut [f32]) {
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = (u - x0, v - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        // acc has the image's channel count (a constant once inlined).
        let c = acc.len();
        let (w, h) = (self.w as i64, self.h as i64);
        let wts = [
            (1.0 - fx) * (1.0 - fy),
            fx * (1.0 - fy),
            (1.0 - fx) * fy,
            fx * fy,
        ];
        if x0 >= 0 && y0 >= 0 && x0 + 1 < w && y0 + 1 < h {
            let i = (y0 as usize * self.w + x0 as usize) * c;
            let r = self.w * c;
            let offs = [i, i + c, i + r, i + r + c];
            for (k, a) in acc.iter_mut().enumerate() {
                let v = &self.v;
                *a += wts[0] * v[offs[0] + k]
                    + wts[1] * v[offs[1] + k]
                    + wts[2] * v[offs[2] + k]
                    + wts[3] * v[offs[3] + k];
            }
            return;
        }
        let taps = [(x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1)];
        for (&(x, y), &wt) in taps.iter().zip(&wts) {
            if wt == 0.0 {
                continue;
            }
            match (wrap(x, w, self.border), wrap(y, h, self.border)) {
                (Some(x), Some(y)) => {
                    let i = (y * self.w + x) * c;
                    for (a, v) in acc[..c].iter_mut().zip(&self.v[i..i + c]) {
                        *a += wt * v;
                    }
                }
                _ => {
                    for (a, f) in acc[..c].iter_mut().zip(&self.fill[..c]) {
                        *a += wt * f;
                    }
                }
            }
        }
    }
}

/// Frame-px-to-image-px maps: `lines` lines (1 with a global shutter, else
/// one per row or column) of `n` instants each, line-major.
pub struct Maps {
    /// The maps (f64 row-major 3x3 would be exact; f32 is within 1e-4 px
    /// over 4096 px, far below the contract).
    pub m: Vec<[f32; 9]>,
    /// Instants per line.
    pub n: usize,
    /// 0: global, 1: per row, 2: per column.
    pub mode: u32,
}

/// Row-major f32 of a frame-to-image map.
pub fn to_f32(m: &DMat3) -> [f32; 9] {
    let t = m.transpose().to_cols_array();
    t.map(|x| x as f32)
}

/// The largest distance (px) between where the map sends a few probe
/// points (corners, centre) and the points themselves.
pub fn max_shift(m: &DMat3, w: f64, h: f64) -> f64 {
    let probes = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h), (0.5 * w, 0.5 * h)];
    probes
        .iter()
        .map(|&(x, y)| {
            let p = *m * DVec3::new(x, y, 1.0);
            if p.z <= 0.0 {
                return f64::INFINITY;
            }
            ((p.x / p.z - x).powi(2) + (p.y / p.z - y).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

/// The warp average of `src` over `maps`: linear values, `c` channels.
pub fn integrate(src: &Src, maps: &Maps) -> Vec<f32> {
    match src.c {
        1 => integrate_c::<1>(src, maps),
        3 => integrate_c::<3>(src, maps),
        _ => integrate_c::<4>(src, maps),
    }
}

/// A map `g` (row-major) along the row of pixel centres at height `y`, as
/// affine functions of the column `i`: `(u, v, z)` numerators at pixel
/// `i` are `(k[0] + k[1] i, k[2] + k[3] i, k[4] + k[5] i)` (the centre at
/// `i + 0.5`), so a pixel costs no matrix product.
#[inline]
fn along_row(g: &[f32; 9], y: f32) -> [f32; 6] {
    [
        g[0] * 0.5 + g[1] * y + g[2],
        g[0],
        g[3] * 0.5 + g[4] * y + g[5],
        g[3],
        g[6] * 0.5 + g[7] * y + g[8],
        g[6],
    ]
}

/// Adds the interpolant at column `i` under the row map `k` to `acc`.
#[inline(always)]
fn sample<const C: usize>(src: &Src, k: &[f32; 6], fi: f32, acc: &mut [f32; C]) {
    let z = k[4] + k[5] * fi;
    if z <= 0.0 {
        for (a, f) in acc.iter_mut().zip(src.fill) {
            *a += f;
        }
        return;
    }
    let r = 1.0 / z;
    let u = (k[0] + k[1] * fi) * r - 0.5;
    let v = (k[2] + k[3] * fi) * r - 0.5;
    let (x0, y0) = (u.floor(), v.floor());
    let (xi, yi) = (x0 as i64, y0 as i64);
    if xi >= 0 && yi >= 0 && xi + 1 < src.w as i64 && yi + 1 < src.h as i64 {
        // Inside: two lerps along x, one along y, per channel.
        let (fx, fy) = (u - x0, v - y0);
        let i = (yi as usize * src.w + xi as usize) * C;
        let r = src.w * C;
        let t = &src.v[i..i + C * 2];
        let b = &src.v[i + r..i + r + C * 2];
        for c in 0..C {
            let top = t[c] + fx * (t[c + C] - t[c]);
            let bot = b[c] + fx * (b[c + C] - b[c]);
            acc[c] += top + fy * (bot - top);
        }
    } else {
        src.add(u, v, acc);
    }
}

/// Pixel by pixel, each pixel's instants summed in registers; the maps of
/// a row precomputed once per row (per pixel only with a column-wise
/// rolling shutter, `mode` 2), rows in parallel.
fn integrate_c<const C: usize>(src: &Src, maps: &Maps) -> Vec<f32> {
    let (w, h) = (src.w, src.h);
    let n = maps.n;
    let scale = 1.0 / n as f32;
    let mut out = vec![0.0f32; w * h * C];
    out.par_chunks_mut(w * C).enumerate().for_each(|(j, row)| {
        let y = j as f32 + 0.5;
        let line = if maps.mode == 1 { j } else { 0 };
        let ks: Vec<[f32; 6]> = maps.m[line * n..(line + 1) * n]
            .iter()
            .map(|g| along_row(g, y))
            .collect();
        for (i, px) in row.chunks_exact_mut(C).enumerate() {
            let fi = i as f32;
            let mut acc = [0.0f32; C];
            if maps.mode == 2 {
                for g in &maps.m[i * n..(i + 1) * n] {
                    sample::<C>(src, &along_row(g, y), fi, &mut acc);
                }
            } else {
                for k in &ks {
                    sample::<C>(src, k, fi, &mut acc);
                }
            }
            for (p, a) in px.iter_mut().zip(acc) {
                *p = a * scale;
            }
        }
    });
    out
}

/// Per-pixel displacement (px, x then y) from each frame pixel's centre to
/// the image point it sees under each of `at` (one map per line), as
/// `at.len()` planes of (H, W, 2).
pub fn fields(w: usize, h: usize, mode: u32, at: &[Vec<DMat3>]) -> Vec<f32> {
    let mut out = vec![0.0f32; at.len() * w * h * 2];
    out.par_chunks_mut(w * 2).enumerate().for_each(|(r, row)| {
        let (plane, j) = (r / h, r % h);
        let y = j as f64 + 0.5;
        for i in 0..w {
            let line = match mode {
                0 => 0,
                1 => j,
                _ => i,
            };
            let x = i as f64 + 0.5;
            let p = at[plane][line] * DVec3::new(x, y, 1.0);
            row[2 * i] = (p.x / p.z - x) as f32;
            row[2 * i + 1] = (p.y / p.z - y) as f32;
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn borders_map_indices() {
        let r: Vec<_> = (-3..7).map(|i| wrap(i, 4, Border::Reflect)).collect();
        let want = [3, 2, 1, 0, 1, 2, 3, 2, 1, 0].map(Some);
        assert_eq!(r, want);
        assert_eq!(wrap(-2, 4, Border::Replicate), Some(0));
        assert_eq!(wrap(9, 4, Border::Replicate), Some(3));
        assert_eq!(wrap(4, 4, Border::Constant), None);
    }

    #[test]
    fn a_half_pixel_shift_averages_neighbours() {
        let v = [0.0f32, 1.0, 0.0, 1.0];
        let src = Src {
            w: 2,
            h: 2,
            c: 1,
            v: &v,
            border: Border::Replicate,
            fill: &[0.0],
        };
        let mut acc = [0.0];
        src.add(0.5, 0.0, &mut acc);
        assert!((acc[0] - 0.5).abs() < 1e-7);
    }
}
