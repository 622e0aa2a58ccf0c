//! The image motion between two consecutive frames: the translation of a
//! grid of patches, found coarse to fine on an image pyramid (an exhaustive
//! zero-mean SSD search on the coarsest level, a small search on each finer
//! one) and refined to a fraction of a pixel by Lucas-Kanade iterations on
//! the full analysis image. A patch without texture (a weak structure
//! tensor) or whose best match still differs much from it is left out.

/// A grey image, row-major, grey levels 0..255.
#[derive(Debug, Clone)]
pub struct Gray {
    w: usize,
    h: usize,
    px: Vec<f32>,
}

impl Gray {
    /// From 8-bit grey pixels (`w * h` of them).
    pub fn from_u8(w: usize, h: usize, px: &[u8]) -> Self {
        debug_assert_eq!(px.len(), w * h);
        Gray {
            w,
            h,
            px: px.iter().map(|&p| p as f32).collect(),
        }
    }

    /// Half size, each pixel the mean of a 2x2 block.
    fn half(&self) -> Gray {
        let (w, h) = ((self.w / 2).max(1), (self.h / 2).max(1));
        let mut px = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let s = self.at(2 * x as isize, 2 * y as isize)
                    + self.at(2 * x as isize + 1, 2 * y as isize)
                    + self.at(2 * x as isize, 2 * y as isize + 1)
                    + self.at(2 * x as isize + 1, 2 * y as isize + 1);
                px.push(0.25 * s);
            }
        }
        Gray { w, h, px }
    }

    /// The pixel at `(x, y)`, clamped to the image.
    #[inline]
    fn at(&self, x: isize, y: isize) -> f32 {
        let x = x.clamp(0, self.w as isize - 1) as usize;
        let y = y.clamp(0, self.h as isize - 1) as usize;
        self.px[y * self.w + x]
    }

    /// Bilinear value at `(x, y)` (pixel centres at integers), clamped.
    #[inline]
    fn bilinear(&self, x: f32, y: f32) -> f32 {
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (xi, yi) = (x0 as isize, y0 as isize);
        let a = self.at(xi, yi) * (1.0 - fx) + self.at(xi + 1, yi) * fx;
        let b = self.at(xi, yi + 1) * (1.0 - fx) + self.at(xi + 1, yi + 1) * fx;
        a * (1.0 - fy) + b * fy
    }
}

/// Levels of the pyramid (full, half, quarter).
const LEVELS: usize = 3;
/// Half size of a patch on the full analysis image, px (33 x 33 patches).
const HALF: isize = 16;
/// Smallest half size on a coarse level, px.
const MIN_HALF: isize = 6;
/// Exhaustive search radius on the coarsest level, px (x4 on the full image).
const COARSE_RADIUS: isize = 6;
/// Lucas-Kanade iterations at most.
const LK_ITERATIONS: usize = 8;
/// Smallest mean structure-tensor eigenvalue per pixel of a tracked patch,
/// (grey levels / px)^2.
const MIN_TEXTURE: f64 = 4.0;
/// Largest RMS difference after the match, as a share of the patch's own
/// standard deviation (plus 3 grey levels of noise).
const MAX_RESIDUAL: f64 = 0.6;

/// A frame's pyramid.
pub struct Pyramid(Vec<Gray>);

impl Pyramid {
    /// The pyramid of `img`.
    pub fn new(img: Gray) -> Self {
        let mut v = vec![img];
        while v.len() < LEVELS {
            let next = v.last().expect("one level").half();
            v.push(next);
        }
        Pyramid(v)
    }
}

/// Patch centres on the full analysis image, px: an `nx x ny` grid.
pub fn grid(w: usize, h: usize) -> Vec<(f64, f64)> {
    let (nx, ny) = (6usize, 4usize);
    let mut v = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            v.push((
                ((i as f64 + 0.5) * w as f64 / nx as f64).floor(),
                ((j as f64 + 0.5) * h as f64 / ny as f64).floor(),
            ));
        }
    }
    v
}

/// Zero-mean SSD per pixel between `prev` around `c` and `cur` around `c + d`.
fn zssd(prev: &Gray, cur: &Gray, c: (isize, isize), d: (isize, isize), half: isize) -> f64 {
    let (mut s, mut s2, mut n) = (0.0f64, 0.0f64, 0.0f64);
    for y in -half..=half {
        for x in -half..=half {
            let e = (cur.at(c.0 + d.0 + x, c.1 + d.1 + y) - prev.at(c.0 + x, c.1 + y)) as f64;
            s += e;
            s2 += e * e;
            n += 1.0;
        }
    }
    (s2 - s * s / n) / n
}

/// The integer `d` within `radius` of `start` that minimises the zero-mean SSD.
fn search(
    prev: &Gray,
    cur: &Gray,
    c: (isize, isize),
    start: (isize, isize),
    radius: isize,
    half: isize,
) -> (isize, isize) {
    let mut best = (f64::INFINITY, start);
    for dy in -radius..=radius {
        for dx in -radius..=radius {
            let d = (start.0 + dx, start.1 + dy);
            let e = zssd(prev, cur, c, d, half);
            if e < best.0 {
                best = (e, d);
            }
        }
    }
    best.1
}

/// The motion of the patch at `centre` (full analysis image, px) from
/// `prev` to `cur`: where its content lies in `cur` minus where it lay,
/// px; `None` without texture or a good match.
pub fn track_patch(prev: &Pyramid, cur: &Pyramid, centre: (f64, f64)) -> Option<(f64, f64)> {
    let full = &prev.0[0];
    let c0 = (centre.0 as isize, centre.1 as isize);
    // Texture: the structure tensor of the template.
    let (mut gxx, mut gxy, mut gyy) = (0.0f64, 0.0f64, 0.0f64);
    let mut grads = Vec::with_capacity(((2 * HALF + 1) * (2 * HALF + 1)) as usize);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for y in -HALF..=HALF {
        for x in -HALF..=HALF {
            let (px, py) = (c0.0 + x, c0.1 + y);
            let gx = 0.5 * (full.at(px + 1, py) - full.at(px - 1, py)) as f64;
            let gy = 0.5 * (full.at(px, py + 1) - full.at(px, py - 1)) as f64;
            gxx += gx * gx;
            gxy += gx * gy;
            gyy += gy * gy;
            let t = full.at(px, py) as f64;
            sum += t;
            sum2 += t * t;
            grads.push((gx, gy, t));
        }
    }
    let n = grads.len() as f64;
    let tr = 0.5 * (gxx + gyy);
    let lmin = tr - (0.25 * (gxx - gyy).powi(2) + gxy * gxy).sqrt();
    if lmin / n < MIN_TEXTURE {
        return None;
    }
    let t_mean = sum / n;
    let t_std = (sum2 / n - t_mean * t_mean).max(0.0).sqrt();
    // Coarse to fine, integer steps.
    let mut d = (0isize, 0isize);
    for l in (0..LEVELS).rev() {
        let scale = 1isize << l;
        let half = (HALF / scale).max(MIN_HALF);
        let c = (c0.0 / scale, c0.1 / scale);
        d = if l == LEVELS - 1 {
            search(&prev.0[l], &cur.0[l], c, (0, 0), COARSE_RADIUS, half)
        } else {
            search(&prev.0[l], &cur.0[l], c, (2 * d.0, 2 * d.1), 1, half)
        };
    }
    // Lucas-Kanade on the full image (translation, brightness offset removed).
    let det = gxx * gyy - gxy * gxy;
    let (mut dx, mut dy) = (d.0 as f64, d.1 as f64);
    let img = &cur.0[0];
    let mut rms = f64::INFINITY;
    for _ in 0..LK_ITERATIONS {
        let mut vals = Vec::with_capacity(grads.len());
        let mut k = 0;
        for y in -HALF..=HALF {
            for x in -HALF..=HALF {
                let v = img.bilinear((c0.0 + x) as f32 + dx as f32, (c0.1 + y) as f32 + dy as f32)
                    as f64;
                vals.push(v - grads[k].2);
                k += 1;
            }
        }
        let mean = vals.iter().sum::<f64>() / n;
        let (mut bx, mut by, mut e2) = (0.0, 0.0, 0.0);
        for (e, g) in vals.iter().zip(&grads) {
            let e = e - mean;
            bx += g.0 * e;
            by += g.1 * e;
            e2 += e * e;
        }
        rms = (e2 / n).sqrt();
        let sx = -(gyy * bx - gxy * by) / det;
        let sy = -(-gxy * bx + gxx * by) / det;
        dx += sx;
        dy += sy;
        if sx.abs() + sy.abs() < 0.005 {
            break;
        }
    }
    let reach = (COARSE_RADIUS << (LEVELS - 1)) as f64 + 4.0;
    let ok = rms <= MAX_RESIDUAL * t_std + 3.0
        && dx.is_finite()
        && dy.is_finite()
        && dx.abs() <= reach
        && dy.abs() <= reach;
    ok.then_some((dx, dy))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth random-ish texture, shifted by `(sx, sy)` px.
    fn texture(w: usize, h: usize, sx: f64, sy: f64) -> Gray {
        let mut px = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let (u, v) = (x as f64 - sx, y as f64 - sy);
                // Periods of 40 to 140 px: no repeat within the search's reach.
                let p = 128.0
                    + 40.0 * (0.11 * u + 0.03 * v).sin()
                    + 30.0 * (0.07 * v - 0.05 * u + 1.0).sin()
                    + 25.0 * (0.13 * u + 0.09 * v + 2.0).sin()
                    + 20.0 * (0.045 * u + 0.15 * v).cos();
                px.push(p as f32);
            }
        }
        Gray { w, h, px }
    }

    #[test]
    fn recovers_subpixel_shifts() {
        let a = Pyramid::new(texture(160, 120, 0.0, 0.0));
        for (sx, sy) in [(0.0, 0.0), (2.3, -1.7), (-9.6, 4.25), (17.4, 11.1)] {
            let b = Pyramid::new(texture(160, 120, sx, sy));
            let (dx, dy) = track_patch(&a, &b, (80.0, 60.0)).expect("textured patch");
            assert!(
                (dx - sx).abs() < 0.05 && (dy - sy).abs() < 0.05,
                "{sx},{sy}: {dx},{dy}"
            );
        }
    }

    #[test]
    fn flat_patch_is_left_out() {
        let flat = Gray {
            w: 64,
            h: 64,
            px: vec![90.0; 64 * 64],
        };
        let p = Pyramid::new(flat);
        assert_eq!(track_patch(&p, &p, (32.0, 32.0)), None);
    }
}
