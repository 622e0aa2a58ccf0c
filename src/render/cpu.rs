//! CPU twin of `shaders/render.wgsl`: the same samples, pose interpolation,
//! ray/plane intersection and texture maths in f32, one pixel per task (rayon).

use super::kernel::{shifts, GpuPose, RenderParams, KIND_BLOBS, KIND_CHECKER};
use super::texture::MipTexture;
use glam::{Vec3, Vec4};
use rayon::prelude::*;

#[inline]
fn v3(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

#[inline]
fn rotate(q: Vec4, v: Vec3) -> Vec3 {
    let u = q.truncate();
    let t = u.cross(v) + v * q.w;
    v + 2.0 * u.cross(t)
}

#[inline]
fn fract(x: f32) -> f32 {
    x - x.floor()
}

/// Radiance (linear RGB) seen along one sample ray.
#[inline]
fn shade(p: &RenderParams, tex: Option<&MipTexture>, q: Vec4, c: Vec3, px: f32, py: f32) -> Vec3 {
    let bg = v3(p.background);
    let (fx, fy, cx, cy) = (p.cam[0], p.cam[1], p.cam[2], p.cam[3]);
    let yc = (py - cy) / fy;
    let dc = Vec3::new((px - cx - p.cam2[0] * yc) / fx, yc, 1.0);
    let dw = rotate(q, dc);
    let n = v3(p.normal);
    let den = n.dot(dw);
    let s = (p.origin[3] - n.dot(c)) / den;
    if den.abs() < 1e-12 || s.is_nan() || s <= 0.0 {
        return bg;
    }
    let d = c + dw * s - v3(p.origin);
    let a = d.dot(v3(p.e1));
    let b = d.dot(v3(p.e2));
    match p.dims[2] {
        KIND_CHECKER => {
            let sz = p.tex[0];
            let k = (a / sz).floor() as i32 + (b / sz).floor() as i32;
            let w = if k & 1 == 0 { 1.0 } else { 0.0 };
            Vec3::splat(w)
        }
        KIND_BLOBS => {
            let (sq, pitch, half) = (p.tex[0], p.tex[1], p.tex[2]);
            if a.abs() > half || b.abs() > half {
                return bg;
            }
            let ca = ((a / pitch + 2.0).floor().clamp(0.0, 3.0) - 1.5) * pitch;
            let cb = ((b / pitch + 2.0).floor().clamp(0.0, 3.0) - 1.5) * pitch;
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
                return bg;
            }
            let len = dw.length();
            let cos = den.abs() / len;
            let texels = s * len * p.cam2[1] / cos.sqrt() * p.tex[2];
            let lod = (texels * p.cam2[2]).max(1.0).log2();
            Vec3::from(t.trilinear(u, v, lod))
        }
    }
}

/// Sum (not mean) of the samples `k0..k1` of pixel `(i, j)`.
pub fn pixel_sum(
    p: &RenderParams,
    poses: &[GpuPose],
    tex: Option<&MipTexture>,
    i: u32,
    j: u32,
) -> Vec3 {
    let n = p.dims[3];
    let nf = n as f32;
    let (g1, g2, segs, seed) = (p.lattice[0], p.lattice[1], p.lattice[2], p.lattice[3]);
    let sh = shifts(i, j, seed);
    let (mut xi, mut yi) = (p.range[3], p.range2[0]);
    let mut acc = Vec3::ZERO;
    for k in p.range[1]..p.range[2] {
        let sx = fract(xi as f32 / nf + sh[0]);
        let sy = fract(yi as f32 / nf + sh[1]);
        let st = fract(k as f32 / nf + sh[2]);
        let tt = st * segs as f32;
        let idx = (tt as u32).min(segs - 1);
        let f = tt - idx as f32;
        let (a, b) = (&poses[idx as usize], &poses[idx as usize + 1]);
        let q = Vec4::from(a.q).lerp(Vec4::from(b.q), f).normalize();
        let c = v3(a.c).lerp(v3(b.c), f);
        acc += shade(p, tex, q, c, i as f32 + sx, j as f32 + sy);
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
/// `N` samples of each pixel. `threads = Some(1)` runs single-threaded.
pub fn render(
    p: &RenderParams,
    poses: &[GpuPose],
    tex: Option<&MipTexture>,
    threads: Option<usize>,
) -> Vec<f32> {
    let (w, h) = (p.dims[0], p.dims[1]);
    let inv = 1.0 / p.dims[3] as f32;
    let run = || {
        let mut out = vec![0.0f32; (w * h * 3) as usize];
        out.par_chunks_mut(3).enumerate().for_each(|(idx, o)| {
            let (i, j) = (idx as u32 % w, idx as u32 / w);
            let s = pixel_sum(p, poses, tex, i, j) * inv;
            o.copy_from_slice(&s.to_array());
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
