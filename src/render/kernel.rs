//! What the render kernel sees: the parameter block shared with
//! `shaders/render.wgsl` (bytemuck Pod, layout asserted), the per-pixel
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
//! only the background: the kernel writes it without sampling.

use super::target::{Target, TargetKind};
use super::texture::MipTexture;
use super::trajectory::Trajectory;
use crate::board::{BLOB_RED, BOARD_WHITE};
use crate::camera::Camera;
use bytemuck::{Pod, Zeroable};
use glam::{DMat3, DVec3};

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
    /// LOD_SCALE, 1/N, 0, 0.
    pub lod: [f32; 4],
    /// width, height (full image, px), target kind, N (samples per pixel).
    pub dims: [u32; 4],
    /// g1, g2 (lattice generator), distortion map offset ([`pixel_maps`]; 0: none), seed.
    pub lattice: [u32; 4],
    /// First row of this dispatch, first and end sample index k0, k1, (k0*g1) mod N.
    pub range: [u32; 4],
    /// (k0*g2) mod N, rows in this dispatch, line mode ([`line_mode`]), 0.
    pub range2: [u32; 4],
    /// x0, y0, x1, y1 (px, end exclusive): pixels outside see only the background.
    pub bbox: [u32; 4],
    /// Defocus ([`lens_params`]): aperture radius (m; 0: pinhole), and the
    /// pixel shift per metre of lens offset `fx / s`, `fy / s`, `skew / s`.
    pub lens: [f32; 4],
    /// Defocus lattice dimensions: g3, g4, (k0*g3) mod N, (k0*g4) mod N.
    pub lens_gen: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<RenderParams>() == 12 * 16);
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

/// The pixel-to-ray matrix: `K^-1 (x, y, 1)` is the camera-frame direction
/// `(u / f, v / f, 1)` through pixel coordinates `(x, y)` (affine, so read off
/// the camera's own mapping at three points).
fn pixel_to_ray(cam: &Camera) -> DMat3 {
    let d = |x: f64, y: f64| {
        let (u, v) = cam.pixel_to_mm(x, y);
        DVec3::new(u / cam.focal_mm, v / cam.focal_mm, 1.0)
    };
    let o = d(0.0, 0.0);
    DMat3::from_cols(d(1.0, 0.0) - o, d(0.0, 1.0) - o, o)
}

/// The homography of pose `pose` (f64).
pub fn homography(cam: &Camera, target: &Target, pose: &super::trajectory::Pose) -> DMat3 {
    let f = target.frame();
    let (q, c) = pose;
    let dist = f.normal.dot(f.origin) - f.normal.dot(*c);
    let rows = [
        f.normal * f.e1.dot(*c - f.origin) + f.e1 * dist,
        f.normal * f.e2.dot(*c - f.origin) + f.e2 * dist,
        f.normal,
    ];
    let m = DMat3::from_cols(rows[0], rows[1], rows[2]).transpose();
    let h = m * DMat3::from_quat(*q) * pixel_to_ray(cam);
    // s = dist / (n . d) > 0 exactly where sign(dist) * w > 0.
    if dist < 0.0 {
        -h
    } else {
        h
    }
}

/// Time of instant `m` of `n` (s after exposure start): the step midpoint.
pub fn instant(trajectory: &Trajectory, m: u32, n: u32) -> f64 {
    trajectory.duration() * (m as f64 + 0.5) / n as f64
}

/// Line mode of the homography table (`RenderParams::range2[2]`): 0 one set
/// of instants for every pixel (global shutter), 1 one set per row, 2 one per
/// column (rolling shutter, SPEC 9).
pub fn line_mode(cam: &Camera) -> u32 {
    match (cam.shutter.is_global(), cam.shutter.direction.is_rows()) {
        (true, _) => 0,
        (false, true) => 1,
        (false, false) => 2,
    }
}

/// Lines of the homography table: 1, the rows or the columns.
pub fn table_lines(cam: &Camera) -> u32 {
    match line_mode(cam) {
        0 => 1,
        1 => cam.height,
        _ => cam.width,
    }
}

/// Time (s after the trajectory's start) of instant `m` of `n` of table line
/// `line`: the line's delay plus the step midpoint of its own exposure of
/// `exposure_s` seconds. Without a readout this is [`instant`].
pub fn line_instant(
    cam: &Camera,
    trajectory: &Trajectory,
    exposure_s: f64,
    line: u32,
    m: u32,
    n: u32,
) -> f64 {
    if cam.shutter.is_global() {
        return instant(trajectory, m, n);
    }
    let c = line as f64 + 0.5;
    let delay = cam.shutter.delay_s(c, c, cam.width, cam.height);
    delay + exposure_s * (m as f64 + 0.5) / n as f64
}

/// Table entries per instant: 1, or 3 with defocus (`H`, `dH/dlx`, `dH/dly`).
pub fn table_stride(cam: &Camera) -> u32 {
    if cam.lens.is_some() {
        3
    } else {
        1
    }
}

/// The homography table: `n` instants for each of [`table_lines`] lines
/// (line-major: instant `line * n + m`) over each line's exposure of
/// `exposure_s` seconds, [`table_stride`] entries each, for upload.
pub fn homographies(
    cam: &Camera,
    target: &Target,
    trajectory: &Trajectory,
    exposure_s: f64,
    n: u32,
) -> Vec<GpuHomography> {
    let lines = table_lines(cam);
    let r = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
    let entry = |h: DMat3, det: f64| GpuHomography {
        h0: r(h.row(0), 0.0),
        h1: r(h.row(1), 0.0),
        h2: r(h.row(2), det),
    };
    let mut out = Vec::with_capacity((lines * n * table_stride(cam)) as usize);
    for e in 0..lines * n {
        let t = line_instant(cam, trajectory, exposure_s, e / n, e % n, n);
        let pose = trajectory.pose_at(t);
        let h = homography(cam, target, &pose);
        out.push(entry(h, h.determinant().abs()));
        if cam.lens.is_some() {
            let (gx, gy) = lens_derivatives(cam, target, &pose);
            out.push(entry(gx, 0.0));
            out.push(entry(gy, 0.0));
        }
    }
    out
}

/// Defocus (SPEC 9, thin lens): a ray through lens point `L = (lx, ly, 0)`
/// m (camera frame) toward the in-focus point of pinhole pixel `p` is the
/// ray of a camera moved by `R L` through pixel `p - K L / s`. The homography
/// is affine in the camera centre, so the moved camera's is
/// `H + lx Gx + ly Gy`: these are `Gx`, `Gy` (same scaling and sign as `H`).
pub fn lens_derivatives(
    cam: &Camera,
    target: &Target,
    pose: &super::trajectory::Pose,
) -> (DMat3, DMat3) {
    let f = target.frame();
    let (q, c) = pose;
    let dist = f.normal.dot(f.origin) - f.normal.dot(*c);
    let rot = DMat3::from_quat(*q);
    let g = |delta: DVec3| {
        let rows = [
            f.normal * f.e1.dot(delta) - f.e1 * f.normal.dot(delta),
            f.normal * f.e2.dot(delta) - f.e2 * f.normal.dot(delta),
            DVec3::ZERO,
        ];
        let m = DMat3::from_cols(rows[0], rows[1], rows[2]).transpose();
        let h = m * rot * pixel_to_ray(cam);
        if dist < 0.0 {
            -h
        } else {
            h
        }
    };
    (g(rot * DVec3::X), g(rot * DVec3::Y))
}

/// The defocus parameters ([`RenderParams::lens`]): the aperture radius is
/// that of `A' = A s / (s - f)` (`A = f / N`), so that a point at depth `z`
/// spreads over SPEC 9's disc `c = A f / (s - f) |z - s| / z` (the lens is
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

/// Lens distortion: one table entry per pixel, to append after the
/// homographies (the kernel finds them at `RenderParams::lattice[2]`):
/// `h0 = (x', y', L00, L01)`, `h1 = (L10, L11, 0, 0)` with `(x', y')` the
/// pinhole pixel coordinates of the ray through the pixel centre and `L`
/// the Jacobian of the undistortion map (pixel to pinhole pixel) there, in
/// f64 from [`Camera::pixel_to_ray`] and the distortion's Jacobian. `None`
/// for a pinhole camera; an error names a pixel that does not undistort.
pub fn pixel_maps(cam: &Camera) -> crate::error::Result<Option<Vec<GpuHomography>>> {
    if cam.distortion.is_none() {
        return Ok(None);
    }
    let f = cam.focal_mm;
    // A = d(mm)/d(pixel) and its inverse (the camera's affine pixel map).
    let (px, py) = (cam.pitch_x_mm, cam.pitch_y_mm);
    let a = [[px, -cam.skew * py * px / f], [0.0, py]];
    let ainv = [[1.0 / px, cam.skew / f], [0.0, 1.0 / py]];
    let mul = |x: [[f64; 2]; 2], y: [[f64; 2]; 2]| {
        [
            [
                x[0][0] * y[0][0] + x[0][1] * y[1][0],
                x[0][0] * y[0][1] + x[0][1] * y[1][1],
            ],
            [
                x[1][0] * y[0][0] + x[1][1] * y[1][0],
                x[1][0] * y[0][1] + x[1][1] * y[1][1],
            ],
        ]
    };
    let mut out = Vec::with_capacity(cam.width as usize * cam.height as usize);
    for j in 0..cam.height {
        for i in 0..cam.width {
            let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
            let (rx, ry) = cam.pixel_to_ray(x, y).ok_or_else(|| {
                crate::error::Error::invalid(
                    "distortion",
                    format!("pixel ({x}, {y}) does not undistort"),
                )
            })?;
            let (cx, cy) = cam.mm_to_pixel(f * rx, f * ry);
            let jd = cam.distortion.jacobian(rx, ry);
            let det = jd[0][0] * jd[1][1] - jd[0][1] * jd[1][0];
            let jinv = [
                [jd[1][1] / det, -jd[0][1] / det],
                [-jd[1][0] / det, jd[0][0] / det],
            ];
            let l = mul(ainv, mul(jinv, a));
            out.push(GpuHomography {
                h0: [cx as f32, cy as f32, l[0][0] as f32, l[0][1] as f32],
                h1: [l[1][0] as f32, l[1][1] as f32, 0.0, 0.0],
                h2: [0.0; 4],
            });
        }
    }
    Ok(Some(out))
}

/// The pixel box outside which the target is never seen during the exposure
/// (the whole image for the unbounded checker, or when a target corner passes
/// behind the camera): the projections of the target's corners at every
/// instant, widened by one pixel against rounding.
pub fn target_bbox(cam: &Camera, target: &Target, trajectory: &Trajectory, n: u32) -> [u32; 4] {
    let full = [0, 0, cam.width, cam.height];
    let (ha, hb) = match &target.kind {
        TargetKind::Checker { .. } => return full,
        TargetKind::Blobs { .. } => {
            let b = target.board().unwrap_or_else(crate::board::Board::thesis);
            (b.half_width_m(), b.half_width_m())
        }
        TargetKind::Image {
            width_m, texture, ..
        } => (0.5 * width_m, 0.5 * width_m / texture.aspect()),
    };
    let corners = [(-ha, -hb), (ha, -hb), (ha, hb), (-ha, hb)].map(|(a, b)| target.point(a, b));
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for m in 0..n {
        let pose = trajectory.pose_at(instant(trajectory, m, n));
        for c in corners {
            let Some((x, y)) = super::target::project(cam, &pose, c) else {
                return full;
            };
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
    }
    let clampx = |v: f64| v.clamp(0.0, cam.width as f64) as u32;
    let clampy = |v: f64| v.clamp(0.0, cam.height as f64) as u32;
    if !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
        return full;
    }
    [
        clampx(x0.floor() - 1.0),
        clampy(y0.floor() - 1.0),
        clampx(x1.ceil() + 1.0),
        clampy(y1.ceil() + 1.0),
    ]
}

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

/// Per-pixel Cranley-Patterson shifts of x and y, in [0, 1) (same in WGSL).
#[inline]
pub fn shifts(i: u32, j: u32, seed: u32) -> (f32, f32) {
    let h1 = pcg(i.wrapping_add(pcg(j.wrapping_add(pcg(seed)))));
    let h2 = pcg(h1);
    let f = |h: u32| (h >> 8) as f32 * (1.0 / 16_777_216.0);
    (f(h1), f(h2))
}

/// The per-pixel shifts of the two aperture dimensions (defocus): the next
/// two values of the same hash chain as [`shifts`].
pub fn lens_shifts(i: u32, j: u32, seed: u32) -> (f32, f32) {
    let h1 = pcg(i.wrapping_add(pcg(j.wrapping_add(pcg(seed)))));
    let h3 = pcg(pcg(h1));
    let h4 = pcg(h3);
    let f = |h: u32| (h >> 8) as f32 * (1.0 / 16_777_216.0);
    (f(h3), f(h4))
}

/// A uniform point on the unit disc from a point of the unit square
/// (Shirley and Chiu's concentric map), with sine and cosine as polynomials
/// on `[-pi/4, pi/4]` (|error| < 4e-7) so that the shader computes the same.
#[inline]
pub fn concentric(u: f32, v: f32) -> (f32, f32) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let q = std::f32::consts::FRAC_PI_4;
    if a.abs() > b.abs() {
        let t = q * (b / a);
        (a * cos_p(t), a * sin_p(t))
    } else {
        let t = q * (a / b);
        (b * sin_p(t), b * cos_p(t))
    }
}

#[inline]
fn sin_p(x: f32) -> f32 {
    let x2 = x * x;
    x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)))
}

#[inline]
fn cos_p(x: f32) -> f32 {
    let x2 = x * x;
    1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)))
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
    RenderParams {
        background: [bg[0], bg[1], bg[2], 0.0],
        tex,
        colour_a: [BLOB_RED[0], BLOB_RED[1], BLOB_RED[2], 0.0],
        colour_b: [BOARD_WHITE[0], BOARD_WHITE[1], BOARD_WHITE[2], 0.0],
        lod: [LOD_SCALE, (1.0 / n as f64) as f32, 0.0, 0.0],
        dims: [cam.width, cam.height, kind, n],
        lattice: [g1, g2, 0, seed],
        range: [0, 0, n, 0],
        range2: [0, cam.height, line_mode(cam), 0],
        bbox,
        lens: lens_params(cam),
        lens_gen: [g3, g4, 0, 0],
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
        assert!((0.0..1.0).contains(&s.0) && (0.0..1.0).contains(&s.1));
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
        let p = params(&crate::camera::Camera::thesis(), &t, 64, [0, 0, 1, 1], 0);
        let h = b.scaled(0.5);
        assert_eq!(p.tex[0], h.square_m as f32);
        assert_eq!(p.tex[1], h.pitch_m() as f32);
        assert_eq!(p.tex[2], h.half_width_m() as f32);
        assert_eq!(t.blob_centres().map(|c| c.len()), Some(16));
    }
}
