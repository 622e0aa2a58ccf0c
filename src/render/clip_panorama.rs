//! An equirectangular panorama at infinity, for `mmbm clip` (rotation
//! only, any rotation): a texture indexed by direction, longitude
//! `atan2(x, z)` across its width (-pi..pi) and latitude `asin(-y)` down its
//! height (pi/2..-pi/2) in the world frame (the camera's frame at the
//! clip's start: x right, y down, z forward), bilinear, longitude wrapped.
//!
//! A frame is integrated by supersampling, as the renderer's `lattice`
//! integrator does for its non-image targets: per pixel, N samples of a
//! rank-1 lattice over the pixel's area and its line's exposure window
//! (rolling shutter: each line's own start, [`crate::camera::Shutter::delay_s`]),
//! shifted per pixel (Cranley-Patterson) so the pattern does not repeat; N
//! from the largest image path as the renderer chooses it
//! ([`super::Quality::samples_for`]).
//!
//! The built-in panorama ([`Panorama::builtin`]) is the project's CC0
//! poster ([`super::poster::at`]) wrapped around the sphere: no file needed.

use super::Quality;
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::limits::{MAX_IMAGE_PIXELS, MAX_PIXEL_SAMPLES};
use crate::model::trajectory::Trajectory;
use glam::{DQuat, DVec3};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::path::Path;

/// An equirectangular texture, linear RGB.
#[derive(Debug, Clone, PartialEq)]
pub struct Panorama {
    /// Width (longitude), px.
    pub width: u32,
    /// Height (latitude), px.
    pub height: u32,
    /// Linear RGB, interleaved, row-major, top row (latitude +pi/2) first.
    pub rgb: Vec<f32>,
}

impl Panorama {
    /// The built-in panorama: the CC0 poster's layers laid over longitude
    /// and latitude (2048 x 1024; about 4.3 m of poster per radian).
    pub fn builtin() -> Self {
        let (w, h) = (2048u32, 1024u32);
        let grey = super::DEFAULT_BACKGROUND;
        let mut rgb = Vec::with_capacity((w * h * 3) as usize);
        for j in 0..h {
            for i in 0..w {
                let lon = (i as f64 + 0.5) / w as f64 * 2.0 * PI;
                let lat = (j as f64 + 0.5) / h as f64 * PI;
                rgb.extend(super::poster::at(grey, 4.3 * lon, 4.3 * lat));
            }
        }
        Panorama {
            width: w,
            height: h,
            rgb,
        }
    }

    /// An equirectangular PNG or JPEG (sRGB), width twice its height
    /// (within a pixel).
    pub fn load(path: &Path) -> Result<Self> {
        let img = crate::io::images::read_rgb8(path)?;
        let (w, h) = img.dimensions();
        if (w as u64) * (h as u64) > MAX_IMAGE_PIXELS || w < 4 || h < 2 || w.abs_diff(2 * h) > 1 {
            return Err(Error::invalid(
                crate::error::show_path(path),
                format!(
                    "{w}x{h} px: an equirectangular panorama is twice as wide as high, \
                     at least 4x2 px"
                ),
            ));
        }
        let rgb = img
            .into_raw()
            .into_iter()
            .map(crate::io::images::srgb8_to_linear)
            .collect();
        Ok(Panorama {
            width: w,
            height: h,
            rgb,
        })
    }

    /// The radiance (linear RGB) in world direction `d` (any length > 0).
    pub fn sample(&self, d: DVec3) -> [f32; 3] {
        let n = d.length();
        let lon = d.x.atan2(d.z);
        let lat = (-d.y / n).clamp(-1.0, 1.0).asin();
        let (w, h) = (self.width as f64, self.height as f64);
        let u = (lon / (2.0 * PI) + 0.5) * w - 0.5;
        let v = ((0.5 - lat / PI) * h - 0.5).clamp(0.0, h - 1.0);
        let (i0, j0) = (u.floor(), v.floor());
        let (fu, fv) = ((u - i0) as f32, (v - j0) as f32);
        let wrap = |i: f64| (i as i64).rem_euclid(self.width as i64) as usize;
        let (ia, ib) = (wrap(i0), wrap(i0 + 1.0));
        let ja = j0 as usize;
        let jb = (ja + 1).min(self.height as usize - 1);
        let px = |i: usize, j: usize| {
            let k = 3 * (j * self.width as usize + i);
            [self.rgb[k], self.rgb[k + 1], self.rgb[k + 2]]
        };
        let (a, b, c, e) = (px(ia, ja), px(ib, ja), px(ia, jb), px(ib, jb));
        std::array::from_fn(|ch| {
            (a[ch] * (1.0 - fu) + b[ch] * fu) * (1.0 - fv) + (c[ch] * (1.0 - fu) + e[ch] * fu) * fv
        })
    }
}

/// The largest image path over the frame, px (with the renderer's 1.1
/// safety factor): the angle turned times the focal length in px at the
/// sensor's corner.
pub fn max_path_px(cam: &Camera, traj: &Trajectory) -> f64 {
    let r = cam.sensor_rect();
    let corner2 = r.u0.abs().max(r.u1.abs()).powi(2) + r.v0.abs().max(r.v1.abs()).powi(2);
    let gain = cam.fx_px().max(cam.fy_px()) * (1.0 + corner2 / (cam.focal_mm * cam.focal_mm));
    let table = traj.table(4096);
    let angle: f64 = table.windows(2).map(|w| w[0].0.angle_between(w[1].0)).sum();
    angle * gain * 1.1
}

/// A per-pixel hash in 0..1 (the lattice's shift).
fn hash01(i: u32, j: u32, seed: u32, c: u32) -> f64 {
    let mut x = i.wrapping_mul(0x9E37_79B1)
        ^ j.wrapping_mul(0x85EB_CA77)
        ^ seed.wrapping_mul(0xC2B2_AE3D)
        ^ c.wrapping_mul(0x27D4_EB2F);
    x ^= x >> 15;
    x = x.wrapping_mul(0x2C1B_3C6D);
    x ^= x >> 12;
    x = x.wrapping_mul(0x297A_2D39);
    x ^= x >> 15;
    x as f64 / 4_294_967_296.0
}

/// Renders `pano` seen by `cam` along `traj` (its poses' rotations;
/// `exposure_s` per line), linear RGB; returns the image and the samples
/// per pixel.
pub fn render(
    cam: &Camera,
    pano: &Panorama,
    traj: &Trajectory,
    exposure_s: f64,
    quality: Quality,
    seed: u32,
) -> Result<(Vec<f32>, u32)> {
    let n = quality.samples_for(max_path_px(cam, traj))?;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let pixel_samples = (w as u64) * (h as u64) * n as u64;
    if pixel_samples > MAX_PIXEL_SAMPLES {
        return Err(Error::invalid(
            "resolution",
            format!(
                "{w}x{h} pixels x {n} samples: the panorama takes at most {MAX_PIXEL_SAMPLES} \
                 pixel-samples per frame; shorten the exposure or lower the resolution"
            ),
        ));
    }
    // Rank-1 lattice generators over (x, y, t): Korobov-style, a = 1, g, g^2 mod n.
    let g = ((n as f64 * 0.618_033_988_7) as u64).max(1) | 1;
    let gen = [1u64, g % n as u64, (g * g) % n as u64];
    // Poses at fine steps over the span (interpolated linearly by the trajectory).
    let steps = ((n as usize) * 4).clamp(256, 1 << 16);
    let table: Vec<DQuat> = traj.table(steps).into_iter().map(|p| p.0).collect();
    let span = traj.duration();
    let rot_at = |t: f64| -> DQuat {
        let x = (t / span).clamp(0.0, 1.0) * steps as f64;
        let k = (x.floor() as usize).min(steps - 1);
        let (a, b) = (table[k], table[k + 1]);
        let b = if a.dot(b) < 0.0 { -b } else { b };
        (a * (1.0 - (x - k as f64)) + b * (x - k as f64)).normalize()
    };
    let stop = crate::cancel::current();
    let rows: Vec<Vec<f32>> = (0..h)
        .into_par_iter()
        .map(|j| {
            let mut row = vec![0f32; 3 * w];
            if stop.is_cancelled() {
                return row;
            }
            for i in 0..w {
                let t0 = cam
                    .shutter
                    .delay_s(i as f64 + 0.5, j as f64 + 0.5, cam.width, cam.height);
                let shift: [f64; 3] =
                    std::array::from_fn(|c| hash01(i as u32, j as u32, seed, c as u32));
                let mut acc = [0f64; 3];
                let mut hits = 0u32;
                for s in 0..n as u64 {
                    let p: [f64; 3] = std::array::from_fn(|c| {
                        ((s * gen[c]) % n as u64) as f64 / n as f64 + shift[c]
                    });
                    let p = p.map(|x| x - x.floor());
                    let Some((rx, ry)) = cam.pixel_to_ray(i as f64 + p[0], j as f64 + p[1]) else {
                        continue;
                    };
                    let q = rot_at(t0 + p[2] * exposure_s);
                    let c = pano.sample(q * DVec3::new(rx, ry, 1.0));
                    for ch in 0..3 {
                        acc[ch] += c[ch] as f64;
                    }
                    hits += 1;
                }
                for ch in 0..3 {
                    row[3 * i + ch] = (acc[ch] / hits.max(1) as f64) as f32;
                }
            }
            row
        })
        .collect();
    crate::cancel::check()?;
    Ok((rows.concat(), n))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The texture is indexed by direction: forward (+z) is the centre
    /// column at the equator, +x a quarter turn right, up (-y) the top row.
    #[test]
    fn directions_index_the_texture() {
        let (w, h) = (8u32, 4u32);
        let mut rgb = vec![0f32; (w * h * 3) as usize];
        let mark = |rgb: &mut Vec<f32>, i: u32, j: u32, v: f32| rgb[(3 * (j * w + i)) as usize] = v;
        // Centre of texel (i, j) is lon = ((i + 0.5) / 8 - 0.5) 2 pi, lat = (0.5 - (j + 0.5) / 4) pi.
        mark(&mut rgb, 4, 1, 1.0);
        let p = Panorama {
            width: w,
            height: h,
            rgb,
        };
        let lon = (4.5 / 8.0 - 0.5) * 2.0 * PI;
        let lat = (0.5 - 1.5 / 4.0) * PI;
        let d = DVec3::new(lon.sin() * lat.cos(), -lat.sin(), lon.cos() * lat.cos());
        assert!((p.sample(d)[0] - 1.0).abs() < 1e-5);
        assert!(p.sample(-d)[0].abs() < 1e-6);
        let b = Panorama::builtin();
        assert_eq!(b.rgb.len(), 2048 * 1024 * 3);
        assert!(b.rgb.iter().all(|x| x.is_finite() && *x >= 0.0));
    }
}
