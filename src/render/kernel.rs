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
use crate::gpu::lens::LensGpu;

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

/// The renderer's lens distortion ([`RenderParams::distortion`]), by the
/// one strategy of every kernel ([`crate::gpu::lens`]): none for a pinhole
/// camera; the OpenCV and fisheye models computed in the kernel; table mode
/// (the host's f64 per-pixel table, [`pixel_maps`]) for every other model
/// and for a camera with a pixel centre beyond its radial distortion limit
/// ([`masked_pixels`]: the table holds its placeholder).
pub fn distortion(cam: &Camera) -> LensGpu {
    match cam.distortion.coefficients() {
        Some(m) if masked_pixels(cam).is_none() => LensGpu::new(Some(m)),
        _ => LensGpu::table(),
    }
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
        pixel: [
            cam.cx as f32,
            cam.cy as f32,
            (cam.pitch_x_mm / cam.focal_mm) as f32,
            (cam.pitch_y_mm / cam.focal_mm) as f32,
        ],
        pixel2: [cam.skew as f32, 0.0, 0.0, 0.0],
        distortion: distortion(cam),
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
    use super::super::layout::GpuHomography;
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

    /// An OpenCV barrel lens and an unmasked fisheye, with skew and an
    /// off-centre principal point (the pixel map's every term).
    fn lens_cameras() -> Vec<Camera> {
        use crate::camera::Distortion;
        let base = Camera {
            skew: 0.7,
            cx: 30.5,
            cy: 25.0,
            ..Camera::new(0.7, 0.00465, 64, 48)
        };
        vec![
            Camera {
                distortion: Distortion::Opencv {
                    k1: -0.3,
                    k2: 0.08,
                    p1: 0.001,
                    p2: -0.002,
                    k3: 0.01,
                },
                ..base
            },
            Camera {
                distortion: Distortion::Fisheye {
                    k1: 0.05,
                    k2: -0.01,
                    k3: 0.002,
                    k4: 0.0,
                },
                ..base
            },
        ]
    }

    /// Table mode's parameters and table for `cam` (the host's f64 map).
    fn table_mode(
        p: &RenderParams,
        homs: &[GpuHomography],
        cam: &Camera,
    ) -> (RenderParams, Vec<GpuHomography>) {
        let mut q = *p;
        let mut h = homs.to_vec();
        q.distortion = LensGpu::table();
        q.lattice[2] = h.len() as u32;
        h.extend(pixel_maps(cam).unwrap().unwrap());
        (q, h)
    }

    #[test]
    fn kernel_pixel_map_matches_the_host_table() {
        // The analytic models' map in f32 (the lens module's twins) against
        // the host's f64 table: the point to 1e-3 px, the Jacobian to 1e-4.
        for cam in lens_cameras() {
            assert!(masked_pixels(&cam).is_none());
            let p = params(&cam, &Target::checker(0.02, 1.0), 16, [0, 0, 64, 48], 0);
            assert_eq!(p.distortion.model, cam.distortion.coefficients().unwrap().0);
            let (t, h) = table_mode(&p, &[], &cam);
            let (mut dp, mut dl) = (0.0f32, 0.0f32);
            for (i, j) in (0..48).flat_map(|j| (0..64).map(move |i| (i, j))) {
                let (a, b) = (
                    super::super::pixel_map::pixel_map(&p, &[], i, j),
                    super::super::pixel_map::pixel_map(&t, &h, i, j),
                );
                dp = dp.max((a.p[0] - b.p[0]).abs().max((a.p[1] - b.p[1]).abs()));
                for r in 0..2 {
                    for c in 0..2 {
                        dl = dl.max((a.l[r][c] - b.l[r][c]).abs());
                    }
                }
            }
            let name = cam.distortion.name();
            eprintln!("{name}: pixel map, max |point| {dp:.2e} px, max |L| {dl:.2e}");
            assert!(dp <= 1e-3 && dl <= 1e-4, "{name}: {dp} px, {dl}");
        }
    }

    #[test]
    fn analytic_lens_renders_as_the_table() {
        // The CPU twin's image with the lens in the kernel against table
        // mode (the renderer before the shared lens module): a sample may
        // cross an edge (1/N), the mean stays at the f32 level.
        use crate::model::motion::Twist;
        use crate::model::trajectory::Trajectory;
        let tw = Twist::new(
            glam::DVec3::new(0.5, -0.7, 1.0),
            glam::DVec3::new(0.1, 0.05, 0.3),
        );
        let tr = Trajectory::from_twist(tw, 0.03).unwrap();
        let n = 32;
        for cam in lens_cameras() {
            for target in [Target::blobs(0.5, 1.5), Target::checker(0.03, 1.2)] {
                let homs = homographies(&cam, &target, &tr, 0.03, n);
                let p = params(&cam, &target, n, [0, 0, 64, 48], 3);
                let (t, h) = table_mode(&p, &homs, &cam);
                for analytic in [false, true] {
                    let a = super::super::cpu::render(&p, &homs, None, analytic, None);
                    let b = super::super::cpu::render(&t, &h, None, analytic, None);
                    let d: Vec<f32> = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).collect();
                    let max = d.iter().cloned().fold(0.0, f32::max);
                    let mean = d.iter().sum::<f32>() / d.len() as f32;
                    let name = cam.distortion.name();
                    eprintln!("{name} analytic {analytic}: max {max:.2e}, mean {mean:.2e}");
                    assert!(
                        max <= 3.0 / n as f32 + 1e-3 && mean <= 1e-4,
                        "{name} {analytic}: {max} {mean}"
                    );
                }
            }
        }
    }
}
