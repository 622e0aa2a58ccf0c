//! The warp integrator's GPU kernel layout and its CPU twin: the f32
//! formula of `warp.wgsl` written once in Rust, function by function
//! (`wrap`, `texel`, `bilinear`, `pixel`), so that the GPU can be checked
//! pixel by pixel (`tests/augment_gpu.rs`).
//!
//! Per output pixel `(i, j)` (centre `(i + 0.5, j + 0.5)`) and channel: the
//! mean over the `n` instants of its line's exposure of the image's bilinear
//! interpolant (texel `x`'s centre at `x + 0.5`, linear light) at
//! `H_k(line) * centre`, where the frame-to-image map `H_k` is per instant
//! and, with a rolling shutter, per row or column; beyond the image the
//! border mode ([`super::Border`]). The same formula as
//! [`super::warp::integrate`] (which hoists the map out of the row loop);
//! the twin and the kernel hold four channels per texel (unused ones 0).

use super::warp::{Border, Maps, Src};
use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

/// Threads per workgroup side (`WG` in the shader: 8 x 8 pixels).
pub const WG: u32 = 8;

/// Largest |coordinate| (px) a sample point is clamped to before its texel
/// index is taken, so that the integer arithmetic never overflows (any
/// point this far out shows the border).
pub const FAR_PX: f32 = 1.0e7;

/// The kernel's parameter block (uniform; each field a 16-byte vector).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct WarpParams {
    /// Image width, height (px), instants per line `n`, line mode (0:
    /// global shutter, 1: one map set per row, 2: per column).
    pub dims: [u32; 4],
    /// Border (0 reflect, 1 replicate, 2 constant), first row of this
    /// dispatch, rows in this dispatch, 0.
    pub range: [u32; 4],
    /// The constant border's linear value per channel.
    pub fill: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<WarpParams>() == 48);
const _: () = assert!(std::mem::offset_of!(WarpParams, range) == 16);
const _: () = assert!(std::mem::offset_of!(WarpParams, fill) == 32);

/// One frame-px-to-image-px map: its rows (`w` of each unused).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct WarpMap {
    /// Row 0 (image x, homogeneous).
    pub r0: [f32; 4],
    /// Row 1 (image y, homogeneous).
    pub r1: [f32; 4],
    /// Row 2 (the homogeneous weight).
    pub r2: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<WarpMap>() == 48);

/// Border code of the kernel.
pub fn border_code(b: Border) -> u32 {
    match b {
        Border::Reflect => 0,
        Border::Replicate => 1,
        Border::Constant => 2,
    }
}

/// The kernel's inputs from the CPU path's: parameters for the whole image
/// (rows `0..h`), the maps, and the texels padded to four channels.
pub fn inputs(src: &Src, maps: &Maps) -> (WarpParams, Vec<WarpMap>, Vec<[f32; 4]>) {
    let mut fill = [0.0f32; 4];
    for (f, v) in fill.iter_mut().zip(src.fill) {
        *f = *v;
    }
    let p = WarpParams {
        dims: [src.w as u32, src.h as u32, maps.n as u32, maps.mode],
        range: [border_code(src.border), 0, src.h as u32, 0],
        fill,
    };
    let m = maps
        .m
        .iter()
        .map(|g| WarpMap {
            r0: [g[0], g[1], g[2], 0.0],
            r1: [g[3], g[4], g[5], 0.0],
            r2: [g[6], g[7], g[8], 0.0],
        })
        .collect();
    let c = src.c;
    let texels = src
        .v
        .chunks_exact(c)
        .map(|t| {
            let mut q = [0.0f32; 4];
            q[..c].copy_from_slice(t);
            q
        })
        .collect();
    (p, m, texels)
}

/// Index `i` of a line of `n` texels under `border` (`-1`: the constant
/// border). WGSL `wrap`.
#[inline]
pub fn wrap(i: i32, n: i32, border: u32) -> i32 {
    if i >= 0 && i < n {
        return i;
    }
    match border {
        1 => i.clamp(0, n - 1),
        0 => {
            if n == 1 {
                return 0;
            }
            let p = 2 * (n - 1);
            let mut m = i % p;
            if m < 0 {
                m += p;
            }
            if m < n {
                m
            } else {
                p - m
            }
        }
        _ => -1,
    }
}

/// Texel `(x, y)` or the border. WGSL `texel`.
#[inline]
pub fn texel(img: &[[f32; 4]], p: &WarpParams, x: i32, y: i32) -> [f32; 4] {
    let (w, h) = (p.dims[0] as i32, p.dims[1] as i32);
    let xx = wrap(x, w, p.range[0]);
    let yy = wrap(y, h, p.range[0]);
    if xx < 0 || yy < 0 {
        return p.fill;
    }
    img[(yy * w + xx) as usize]
}

/// `a + t (b - a)` per channel (the shader's `lerp4`).
#[inline]
fn lerp4(a: [f32; 4], b: [f32; 4], t: f32) -> [f32; 4] {
    [0, 1, 2, 3].map(|c| a[c] + t * (b[c] - a[c]))
}

/// The bilinear interpolant at texel coordinates `(u, v)` (texel `x`'s
/// centre at `x`). WGSL `bilinear`.
#[inline]
pub fn bilinear(img: &[[f32; 4]], p: &WarpParams, u: f32, v: f32) -> [f32; 4] {
    let u = u.clamp(-FAR_PX, FAR_PX);
    let v = v.clamp(-FAR_PX, FAR_PX);
    let (x0, y0) = (u.floor(), v.floor());
    let (fx, fy) = (u - x0, v - y0);
    let (x, y) = (x0 as i32, y0 as i32);
    let (w, h) = (p.dims[0] as i32, p.dims[1] as i32);
    let [t00, t10, t01, t11] = if x >= 0 && y >= 0 && x + 1 < w && y + 1 < h {
        // Inside: the four texels directly (what `texel` gives there).
        let a = (y * w + x) as usize;
        let w = w as usize;
        [img[a], img[a + 1], img[a + w], img[a + w + 1]]
    } else {
        [
            texel(img, p, x, y),
            texel(img, p, x + 1, y),
            texel(img, p, x, y + 1),
            texel(img, p, x + 1, y + 1),
        ]
    };
    let top = lerp4(t00, t10, fx);
    let bot = lerp4(t01, t11, fx);
    lerp4(top, bot, fy)
}

/// Output pixel `(i, j)`: the mean over its line's `n` instants. WGSL `pixel`.
#[inline]
pub fn pixel(img: &[[f32; 4]], p: &WarpParams, maps: &[WarpMap], i: u32, j: u32) -> [f32; 4] {
    let n = p.dims[2];
    let line = match p.dims[3] {
        1 => j,
        2 => i,
        _ => 0,
    };
    let (x, y) = (i as f32 + 0.5, j as f32 + 0.5);
    let mut acc = [0.0f32; 4];
    for k in 0..n {
        let g = &maps[(line * n + k) as usize];
        let z = g.r2[0] * x + g.r2[1] * y + g.r2[2];
        let s = if z <= 0.0 {
            p.fill
        } else {
            let r = 1.0 / z;
            let u = (g.r0[0] * x + g.r0[1] * y + g.r0[2]) * r - 0.5;
            let v = (g.r1[0] * x + g.r1[1] * y + g.r1[2]) * r - 0.5;
            bilinear(img, p, u, v)
        };
        for c in 0..4 {
            acc[c] += s[c];
        }
    }
    let inv = 1.0 / n as f32;
    acc.map(|a| a * inv)
}

/// The twin over the whole image (rows in parallel): four channels per pixel.
pub fn integrate(img: &[[f32; 4]], p: &WarpParams, maps: &[WarpMap]) -> Vec<[f32; 4]> {
    let (w, h) = (p.dims[0] as usize, p.dims[1] as usize);
    let mut out = vec![[0.0f32; 4]; w * h];
    out.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(j, row)| {
            for (i, o) in row.iter_mut().enumerate() {
                *o = pixel(img, p, maps, i as u32, j as u32);
            }
        });
    out
}

/// Four-channel pixels back to `c` interleaved channels.
pub fn narrow(px: &[[f32; 4]], c: usize) -> Vec<f32> {
    px.iter().flat_map(|q| q[..c].iter().copied()).collect()
}

/// The twin on the CPU path's inputs: `c` channels interleaved (what
/// [`super::warp::integrate`] returns, within f32 rounding).
pub fn twin(src: &Src, maps: &Maps) -> Vec<f32> {
    let (p, m, texels) = inputs(src, maps);
    narrow(&integrate(&texels, &p, &m), src.c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_matches_the_cpu_borders() {
        let r: Vec<_> = (-3..7).map(|i| wrap(i, 4, 0)).collect();
        assert_eq!(r, [3, 2, 1, 0, 1, 2, 3, 2, 1, 0]);
        assert_eq!(wrap(-2, 4, 1), 0);
        assert_eq!(wrap(9, 4, 1), 3);
        assert_eq!(wrap(4, 4, 2), -1);
        assert_eq!(wrap(-5, 1, 0), 0);
    }
}
