//! What the render kernel sees: the parameter block shared with
//! `render.wgsl` (bytemuck Pod, layout asserted), the per-pixel
//! sample set, and the homography table.
//!
//! Sample set: per pixel a rank-1 lattice of `N` points in (x, y, t) with
//! generator `(g1, g2, 1)` (`g1, g2` the integers coprime to `N` nearest to
//! `N * (0.75488, 0.56984)`, the R2 sequence's constants), shifted per pixel
//! by a hashed Cranley-Patterson rotation in x and y. The time coordinate of
//! sample `k` is the midpoint `(k + 0.5) / N` of step `k` (the same `N`
//! instants for every pixel, `duration / N` apart: a midpoint rule in time;
//! the per-pixel x and y shifts decorrelate which sensor point meets which
//! instant), and the x and y projections are exactly stratified. Every lane
//! of a SIMD group reads the same table entry at the same step.
//!
//! Homography table: at each instant `m`, the map from pixel coordinates
//! `(x, y, 1)` to target-plane coordinates `(a, b)` (m) is a 3x3 homography
//! `H_m` (ray through the pixel from the camera pose at that instant,
//! intersected with the plane), computed once per frame in f64 on the host.
//! The kernel's per-sample work is one table read, 9 multiply-adds and a
//! division, instead of interpolating a pose and intersecting a ray.
//!
//! Pixels that the target never reaches during the exposure (outside the
//! bounding box of the finite target's projections at every instant) see
//! only the background: the kernel writes it without sampling (the box
//! includes the poster around the target when it has one).

use super::homography::line_mode;
use super::sampling::{coprime_near, generators};
use super::target::{Target, TargetKind};
use super::texture::MipTexture;
use crate::board::{BLOB_RED, BOARD_WHITE};
use crate::camera::Camera;

pub use super::homography::{homographies, masked_pixels, pixel_maps, target_bbox};
pub use super::layout::{RenderParams, KIND_BLOBS, KIND_CHECKER, KIND_IMAGE, LOD_SCALE};

/// The defocus parameters ([`RenderParams::lens`]): the aperture radius is
/// that of `A' = A s / (s - f)` (`A = f / N`), so that a point at depth `z`
/// spreads over docs/spec.md section 9's disc `c = A f / (s - f) |z - s| / z` (the lens is
/// modelled as a shift of the pinhole by the lens point, toward the in-focus
/// point at depth `s`).
pub fn lens_params(cam: &Camera) -> [f32; 4] {
    let Some(l) = cam.lens else {
        return [0.0; 4];
    };
    let (f, s) = (cam.focal_mm, l.focus_m * 1000.0);
    let radius_m = 0.5 * l.aperture_mm(f) * s / (s - f) / 1000.0;
    [
        radius_m as f32,
        (cam.fx_px() / l.focus_m) as f32,
        (cam.fy_px() / l.focus_m) as f32,
        (cam.skew / l.focus_m) as f32,
    ]
}

/// The parameter block for a whole image (`range` set to all rows and samples).
pub fn params(cam: &Camera, target: &Target, n: u32, bbox: [u32; 4], seed: u32) -> RenderParams {
    let (kind, tex) = match &target.kind {
        TargetKind::Checker { size } => {
            (KIND_CHECKER, [*size as f32, (1.0 / size) as f32, 0.0, 0.0])
        }
        TargetKind::Blobs { .. } => {
            // The shader and its CPU twin draw a 4 x 4 grid (see the test below).
            let b = target.board().unwrap_or_else(crate::board::Board::thesis);
            let (sq, pitch, half) = (b.square_m, b.pitch_m(), b.half_width_m());
            (
                KIND_BLOBS,
                [sq as f32, pitch as f32, half as f32, (1.0 / pitch) as f32],
            )
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
    let (g1, g2) = generators(n);
    // The aperture's two lattice dimensions (defocus only): integers coprime
    // to N near N times the R4 sequence's last two constants.
    let (g3, g4) = if cam.lens.is_some() {
        (
            coprime_near(n, n as f64 * 0.524_888_4),
            coprime_near(n, n as f64 * 0.379_706_3),
        )
    } else {
        (0, 0)
    };
    let bg = target.background;
    // The checker covers the whole plane: nothing is behind it.
    let (poster, layers) = match target.half_extent_m() {
        Some(half) => super::poster::kernel_block(target.surround, half),
        None => super::poster::kernel_block(super::poster::Background::Plain, (0.0, 0.0)),
    };
    RenderParams {
        background: [bg[0], bg[1], bg[2], 0.0],
        tex,
        colour_a: [BLOB_RED[0], BLOB_RED[1], BLOB_RED[2], 0.0],
        colour_b: [BOARD_WHITE[0], BOARD_WHITE[1], BOARD_WHITE[2], 0.0],
        lod: [LOD_SCALE, (1.0 / n as f64) as f32, layers as f32, 0.0],
        dims: [cam.width, cam.height, kind, n],
        lattice: [g1, g2, 0, seed],
        range: [0, 0, n, 0],
        range2: [0, cam.height, line_mode(cam), 0],
        bbox,
        lens: lens_params(cam),
        lens_gen: [g3, g4, 0, 0],
        poster,
    }
}

/// Sets the row and sample range of one dispatch.
pub fn with_range(p: &RenderParams, row0: u32, rows: u32, k0: u32, k1: u32) -> RenderParams {
    let n = p.dims[3] as u64;
    let mut q = *p;
    q.range = [row0, k0, k1, ((k0 as u64 * p.lattice[0] as u64) % n) as u32];
    q.range2 = [
        ((k0 as u64 * p.lattice[1] as u64) % n) as u32,
        rows,
        p.range2[2],
        0,
    ];
    q.lens_gen[2] = ((k0 as u64 * p.lens_gen[0] as u64) % n) as u32;
    q.lens_gen[3] = ((k0 as u64 * p.lens_gen[1] as u64) % n) as u32;
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
    fn kernel_board_is_the_thesis_board() {
        // render.wgsl and cpu.rs index the squares as a 4 x 4 grid
        // (`clamp(floor(a / pitch + 2), 0, 3) - 1.5`); the board they are given
        // must be that grid, with the sizes of `board::Board`.
        let b = crate::board::Board::thesis();
        assert_eq!((b.cols, b.rows), (4, 4));
        let t = Target::blobs(0.5, 3.0);
        let p = params(&crate::camera::Camera::thesis(), &t, 64, [0, 0, 1, 1], 0);
        let h = b.scaled(0.5);
        assert_eq!(p.tex[0], h.square_m as f32);
        assert_eq!(p.tex[1], h.pitch_m() as f32);
        assert_eq!(p.tex[2], h.half_width_m() as f32);
        assert_eq!(t.blob_centres().map(|c| c.len()), Some(16));
    }
}
