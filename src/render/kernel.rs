//! What the render kernel sees: the parameter block shared with
//! `shaders/render.wgsl` (bytemuck Pod, layout asserted), the per-pixel
//! sample set, and the pose table.
//!
//! Sample set: per pixel a rank-1 lattice of `N` points in (x, y, t) with
//! generator `(g1, g2, 1)` (`g1, g2` the integers coprime to `N` nearest to
//! `N * (0.75488, 0.56984)`, the R2 sequence's constants), shifted per pixel
//! by a hashed Cranley-Patterson rotation. Time coordinates are exactly
//! `k / N` (shifted), so consecutive time samples are `duration / N` apart,
//! and the x and y projections are exactly stratified too.

use super::target::{Target, TargetKind};
use super::texture::MipTexture;
use super::trajectory::Pose;
use crate::board::{BLOB_RED, BOARD_WHITE};
use crate::model::camera::Camera;
use bytemuck::{Pod, Zeroable};

/// Target kind codes in [`RenderParams::dims`].
pub const KIND_CHECKER: u32 = 0;
/// Blob board.
pub const KIND_BLOBS: u32 = 1;
/// Image texture.
pub const KIND_IMAGE: u32 = 2;

/// Texture minification: the mip level is chosen so that a texel covers about
/// `LOD_SCALE` of a pixel's footprint (supersampling integrates the rest).
pub const LOD_SCALE: f32 = 1.0 / 8.0;

/// Parameter block of one dispatch (uniform buffer; every field a 16-byte vector).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct RenderParams {
    /// fx, fy (focal length in px), cx, cy (principal point, px).
    pub cam: [f32; 4],
    /// skew (px), 1/sqrt(fx*fy) (pixel angular size), LOD_SCALE, 0.
    pub cam2: [f32; 4],
    /// Plane origin O (m), and n.O.
    pub origin: [f32; 4],
    /// In-plane right axis.
    pub e1: [f32; 4],
    /// In-plane down axis.
    pub e2: [f32; 4],
    /// Plane normal.
    pub normal: [f32; 4],
    /// Background linear RGB.
    pub background: [f32; 4],
    /// Checker: [S, 0, 0, 0]; blobs: [square, pitch, board half-width, 0];
    /// image: [width_m, height_m, texels per m (level 0), levels].
    pub tex: [f32; 4],
    /// First colour (blob red).
    pub colour_a: [f32; 4],
    /// Second colour (board white).
    pub colour_b: [f32; 4],
    /// width, height (full image, px), target kind, N (samples per pixel).
    pub dims: [u32; 4],
    /// g1, g2 (lattice generator), K (pose table segments), seed.
    pub lattice: [u32; 4],
    /// First row of this dispatch, first and end sample index k0, k1, (k0*g1) mod N.
    pub range: [u32; 4],
    /// (k0*g2) mod N, rows in this dispatch, 0, 0.
    pub range2: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<RenderParams>() == 14 * 16);
const _: () = assert!(std::mem::offset_of!(RenderParams, dims) == 10 * 16);
const _: () = assert!(std::mem::offset_of!(RenderParams, range2) == 13 * 16);

/// One pose table entry: quaternion (x, y, z, w) and position (m, w unused).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuPose {
    /// Rotation camera-to-world.
    pub q: [f32; 4],
    /// Camera centre, m.
    pub c: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<GpuPose>() == 32);

fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

fn coprime_near(n: u32, x: f64) -> u32 {
    if n <= 2 {
        return 1 % n.max(1);
    }
    let c = (x.round() as i64).clamp(1, n as i64 - 1);
    for d in 0..n as i64 {
        for g in [c + d, c - d] {
            if g >= 1 && g < n as i64 && gcd(g as u32, n) == 1 {
                return g as u32;
            }
        }
    }
    1
}

/// Squared minimum toroidal distance between points of the lattice
/// `{(k g1, k g2, k) / n mod 1}` (the larger, the more evenly spread).
fn min_dist2(n: u32, g1: u32, g2: u32) -> f64 {
    let nf = n as f64;
    let wrap = |a: u64| {
        let x = (a % n as u64) as f64 / nf;
        x.min(1.0 - x)
    };
    let mut best = f64::INFINITY;
    for k in 1..n as u64 {
        let t = (k as f64 / nf).min(1.0 - k as f64 / nf);
        let d = t * t;
        if d >= best {
            continue;
        }
        let x = wrap(k * g1 as u64);
        let y = wrap(k * g2 as u64);
        best = best.min(d + x * x + y * y);
    }
    best
}

/// Lattice generators `(g1, g2)` for `n` points: among integers coprime to
/// `n` near `n * (0.75488, 0.56984)` (the R2 sequence's constants), the pair
/// whose lattice has the largest minimum point distance (cached per `n`).
pub fn generators(n: u32) -> (u32, u32) {
    use std::collections::HashMap;
    use std::sync::Mutex;
    static CACHE: Mutex<Option<HashMap<u32, (u32, u32)>>> = Mutex::new(None);
    if let Some(g) = CACHE.lock().ok().and_then(|c| c.as_ref()?.get(&n).copied()) {
        return g;
    }
    let nf = n as f64;
    let base = (
        coprime_near(n, nf * 0.754_877_666_2),
        coprime_near(n, nf * 0.569_840_291_0),
    );
    let mut best = (min_dist2(n, base.0, base.1), base);
    if n > 16 {
        // candidates: a window around the R2 generators, smaller for large n
        let r = ((2.0e7 / nf).sqrt() / 2.0).clamp(0.0, 12.0) as i64;
        for d1 in -r..=r {
            for d2 in -r..=r {
                let g1 = coprime_near(n, base.0 as f64 + 2.0 * d1 as f64);
                let g2 = coprime_near(n, base.1 as f64 + 2.0 * d2 as f64);
                let m = min_dist2(n, g1, g2);
                if m > best.0 {
                    best = (m, (g1, g2));
                }
            }
        }
    }
    if let Ok(mut c) = CACHE.lock() {
        c.get_or_insert_with(HashMap::new).insert(n, best.1);
    }
    best.1
}

/// PCG hash (same in WGSL).
#[inline]
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Per-pixel Cranley-Patterson shifts in [0, 1) (same in WGSL).
#[inline]
pub fn shifts(i: u32, j: u32, seed: u32) -> [f32; 3] {
    let h1 = pcg(i.wrapping_add(pcg(j.wrapping_add(pcg(seed)))));
    let h2 = pcg(h1);
    let h3 = pcg(h2);
    let f = |h: u32| (h >> 8) as f32 * (1.0 / 16_777_216.0);
    [f(h1), f(h2), f(h3)]
}

/// Converts a pose table for upload: f32, consecutive quaternions sign-aligned.
pub fn gpu_poses(table: &[Pose]) -> Vec<GpuPose> {
    let mut prev = glam::DQuat::IDENTITY;
    table
        .iter()
        .map(|(q, c)| {
            let q = if q.dot(prev) < 0.0 { -*q } else { *q };
            prev = q;
            GpuPose {
                q: [q.x as f32, q.y as f32, q.z as f32, q.w as f32],
                c: [c.x as f32, c.y as f32, c.z as f32, 0.0],
            }
        })
        .collect()
}

/// The parameter block for a whole image (`range` set to all rows and samples).
pub fn params(cam: &Camera, target: &Target, n: u32, segments: u32, seed: u32) -> RenderParams {
    let f = target.frame();
    let v4 = |v: glam::DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
    let (kind, tex) = match &target.kind {
        TargetKind::Checker { size } => (KIND_CHECKER, [*size as f32, 0.0, 0.0, 0.0]),
        TargetKind::Blobs { .. } => {
            // The shader and its CPU twin draw a 4 x 4 grid (see the test below).
            let b = target.board().unwrap_or_else(crate::board::Board::thesis);
            let (sq, pitch, half) = (b.square_m, b.pitch_m(), b.half_width_m());
            (KIND_BLOBS, [sq as f32, pitch as f32, half as f32, 0.0])
        }
        TargetKind::Image {
            width_m, texture, ..
        } => {
            let h = width_m / texture.aspect();
            let tpm = texture.levels[0].w as f64 / width_m;
            (
                KIND_IMAGE,
                [
                    *width_m as f32,
                    h as f32,
                    tpm as f32,
                    texture.levels.len() as f32,
                ],
            )
        }
    };
    let (fx, fy) = (cam.fx_px(), cam.fy_px());
    let (g1, g2) = generators(n);
    let bg = target.background;
    RenderParams {
        cam: [fx as f32, fy as f32, cam.cx as f32, cam.cy as f32],
        cam2: [
            cam.skew as f32,
            (1.0 / (fx * fy).sqrt()) as f32,
            LOD_SCALE,
            0.0,
        ],
        origin: v4(f.origin, f.normal.dot(f.origin)),
        e1: v4(f.e1, 0.0),
        e2: v4(f.e2, 0.0),
        normal: v4(f.normal, 0.0),
        background: [bg[0], bg[1], bg[2], 0.0],
        tex,
        colour_a: [BLOB_RED[0], BLOB_RED[1], BLOB_RED[2], 0.0],
        colour_b: [BOARD_WHITE[0], BOARD_WHITE[1], BOARD_WHITE[2], 0.0],
        dims: [cam.width, cam.height, kind, n],
        lattice: [g1, g2, segments, seed],
        range: [0, 0, n, 0],
        range2: [0, cam.height, 0, 0],
    }
}

/// Sets the row and sample range of one dispatch.
pub fn with_range(p: &RenderParams, row0: u32, rows: u32, k0: u32, k1: u32) -> RenderParams {
    let n = p.dims[3] as u64;
    let mut q = *p;
    q.range = [row0, k0, k1, ((k0 as u64 * p.lattice[0] as u64) % n) as u32];
    q.range2 = [((k0 as u64 * p.lattice[1] as u64) % n) as u32, rows, 0, 0];
    q
}

/// The texture the kernel reads (a 1-texel dummy for procedural targets).
pub fn texture_of(target: &Target) -> Option<&MipTexture> {
    match &target.kind {
        TargetKind::Image { texture, .. } => Some(texture),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_projections_are_permutations() {
        for n in [1u32, 2, 7, 64, 1000, 1024, 4097] {
            let (g1, g2) = generators(n);
            let mut sx: Vec<u64> = (0..n as u64).map(|k| k * g1 as u64 % n as u64).collect();
            let mut sy: Vec<u64> = (0..n as u64).map(|k| k * g2 as u64 % n as u64).collect();
            sx.sort_unstable();
            sy.sort_unstable();
            assert!(sx.iter().enumerate().all(|(i, &v)| v == i as u64), "n={n}");
            assert!(sy.iter().enumerate().all(|(i, &v)| v == i as u64), "n={n}");
        }
        let s = shifts(3, 4, 0);
        assert!(s.iter().all(|&x| (0.0..1.0).contains(&x)));
        assert_ne!(shifts(3, 4, 0), shifts(4, 3, 0));
    }

    #[test]
    fn kernel_board_is_the_thesis_board() {
        // render.wgsl and cpu.rs index the squares as a 4 x 4 grid
        // (`clamp(floor(a / pitch + 2), 0, 3) - 1.5`); the board they are given
        // must be that grid, with the sizes of `board::Board`.
        let b = crate::board::Board::thesis();
        assert_eq!((b.cols, b.rows), (4, 4));
        let t = Target::blobs(0.5, 3.0);
        let p = params(&crate::model::camera::Camera::thesis(), &t, 64, 256, 0);
        let h = b.scaled(0.5);
        assert_eq!(p.tex[0], h.square_m as f32);
        assert_eq!(p.tex[1], h.pitch_m() as f32);
        assert_eq!(p.tex[2], h.half_width_m() as f32);
        assert_eq!(t.blob_centres().map(|c| c.len()), Some(16));
    }
}
