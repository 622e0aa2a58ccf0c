//! The render kernel's memory layout: the parameter block and the
//! homography-table entry shared with `render.wgsl` (bytemuck Pod,
//! sizes and offsets asserted), and the target kinds' codes.

use crate::gpu::lens::LensGpu;
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
    /// Background linear RGB.
    pub background: [f32; 4],
    /// Checker: [S, 1/S, 0, 0]; blobs: [square, pitch, board half-width, 1/pitch];
    /// image: [width_m, height_m, texels per m (level 0), levels].
    pub tex: [f32; 4],
    /// First colour (blob red).
    pub colour_a: [f32; 4],
    /// Second colour (board white).
    pub colour_b: [f32; 4],
    /// LOD_SCALE, 1/N, poster layers (0: the plain background; `poster`), 0.
    pub lod: [f32; 4],
    /// width, height (full image, px), target kind, N (samples per pixel).
    pub dims: [u32; 4],
    /// g1, g2 (lattice generator), distortion table offset (`kernel::pixel_maps`;
    /// table mode only, else 0), seed.
    pub lattice: [u32; 4],
    /// First row of this dispatch, first and end sample index k0, k1, (k0*g1) mod N.
    pub range: [u32; 4],
    /// (k0*g2) mod N, rows in this dispatch, line mode (`homography::line_mode`), 0.
    pub range2: [u32; 4],
    /// x0, y0, x1, y1 (px, end exclusive): pixels outside see only the background.
    pub bbox: [u32; 4],
    /// Defocus (`kernel::lens_params`): aperture radius (m; 0: pinhole), and the
    /// pixel shift per metre of lens offset `fx / s`, `fy / s`, `skew / s`.
    pub lens: [f32; 4],
    /// Defocus lattice dimensions: g3, g4, (k0*g3) mod N, (k0*g4) mod N.
    pub lens_gen: [u32; 4],
    /// The poster's layers (`poster::kernel_block`): `[S, 1/S, pa, pb]`, `[r, g, b, 0]` each.
    pub poster: [[f32; 4]; 8],
    /// Lens distortion's pixel map (`pixel_map` in `prelude.wgsl`): `cx, cy`
    /// (px) and `pitch_x / f, pitch_y / f` (normalised units per px).
    pub pixel: [f32; 4],
    /// `skew` (px), 0, 0, 0.
    pub pixel2: [f32; 4],
    /// Lens distortion ([`crate::gpu::lens`]): none, OpenCV or fisheye in
    /// the kernel, else table mode (the per-pixel table at `lattice[2]`).
    pub distortion: LensGpu,
}

const _: () = assert!(std::mem::size_of::<RenderParams>() == 24 * 16);
const _: () = assert!(std::mem::offset_of!(RenderParams, pixel) == 20 * 16);
const _: () = assert!(std::mem::offset_of!(RenderParams, distortion) == 22 * 16);
const _: () = assert!(std::mem::offset_of!(RenderParams, poster) == 12 * 16);
const _: () = assert!(std::mem::offset_of!(RenderParams, lens) == 10 * 16);
const _: () = assert!(std::mem::offset_of!(RenderParams, dims) == 5 * 16);
const _: () = assert!(std::mem::offset_of!(RenderParams, range2) == 8 * 16);
const _: () = assert!(std::mem::offset_of!(RenderParams, bbox) == 9 * 16);

/// One instant of the homography table: rows of `H` (pixel `(x, y, 1)` to
/// homogeneous target coordinates `(a w, b w, w)`, scaled so that `w > 0`
/// exactly where the ray meets the plane in front of the camera); `h2[3]` is
/// `|det H|` (the target area per pixel area is `|det H| / w^3`, m^2).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GpuHomography {
    /// Row 0 (a), w unused.
    pub h0: [f32; 4],
    /// Row 1 (b), w unused.
    pub h1: [f32; 4],
    /// Row 2 (w), and |det H|.
    pub h2: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<GpuHomography>() == 48);
