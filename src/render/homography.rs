//! The homography table (see [`super::kernel`]): at each instant, for each
//! rolling-shutter line, the map from pixel coordinates to target-plane
//! coordinates, computed in f64 on the host; the lens derivatives of each map
//! for defocus, the distortion's pixel maps, and the bounding box of the
//! target over the exposure.

use super::layout::GpuHomography;
use super::target::Target;
use crate::camera::Camera;
use crate::model::trajectory::Trajectory;
use glam::{DMat3, DVec3};

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
pub fn homography(cam: &Camera, target: &Target, pose: &crate::model::trajectory::Pose) -> DMat3 {
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
/// column (rolling shutter, docs/spec.md section 9).
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

/// Defocus (docs/spec.md section 9, thin lens): a ray through lens point `L = (lx, ly, 0)`
/// m (camera frame) toward the in-focus point of pinhole pixel `p` is the
/// ray of a camera moved by `R L` through pixel `p - K L / s`. The homography
/// is affine in the camera centre, so the moved camera's is
/// `H + lx Gx + ly Gy`: these are `Gx`, `Gy` (same scaling and sign as `H`).
pub fn lens_derivatives(
    cam: &Camera,
    target: &Target,
    pose: &crate::model::trajectory::Pose,
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

/// Lens distortion: one table entry per pixel, to append after the
/// homographies (the kernel finds them at `RenderParams::lattice[2]`):
/// `h0 = (x', y', L00, L01)`, `h1 = (L10, L11, 0, 0)` with `(x', y')` the
/// pinhole pixel coordinates of the ray through the pixel centre and `L`
/// the Jacobian of the undistortion map (pixel to pinhole pixel) there, in
/// f64 from [`Camera::pixel_to_ray`] and the distortion's Jacobian. `None`
/// for a pinhole camera; an error names a pixel that does not undistort.
/// A pixel beyond the lens's radial distortion limit ([`masked_pixels`])
/// sees no ray: its entry is the identity at its own centre, a placeholder
/// whose colour the renderer replaces by 0.
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
            let (ud, vd) = cam.pixel_to_mm(x, y);
            if cam.is_masked_mm(ud, vd) {
                out.push(GpuHomography {
                    h0: [x as f32, y as f32, 1.0, 0.0],
                    h1: [0.0, 1.0, 0.0, 0.0],
                    h2: [0.0; 4],
                });
                continue;
            }
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

/// Per pixel (row-major), true where its centre lies beyond the lens's
/// radial distortion limit ([`Camera::is_masked_mm`]): no ray, black (0) in
/// a rendered image before sensor noise, NaN in the blur maps. `None` when
/// no pixel is masked.
pub fn masked_pixels(cam: &Camera) -> Option<Vec<bool>> {
    if cam.distortion.is_none() || cam.masked_fraction() == 0.0 {
        return None;
    }
    let mask: Vec<bool> = (0..cam.height)
        .flat_map(|j| (0..cam.width).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (ud, vd) = cam.pixel_to_mm(i as f64 + 0.5, j as f64 + 0.5);
            cam.is_masked_mm(ud, vd)
        })
        .collect();
    mask.iter().any(|&m| m).then_some(mask)
}

/// The pixel box outside which the target is never seen during the exposure
/// (the whole image for the unbounded checker, or when a target corner passes
/// behind the camera): the projections of the target's corners at every
/// instant, widened by one pixel against rounding.
pub fn target_bbox(cam: &Camera, target: &Target, trajectory: &Trajectory, n: u32) -> [u32; 4] {
    let full = [0, 0, cam.width, cam.height];
    // The finite target, with the poster around it when it has one.
    let Some((ha, hb)) = target.painted_half_extent_m() else {
        return full;
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
