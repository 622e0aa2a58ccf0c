//! Image textures for `image:PATH:WIDTH_M` targets: decoded from PNG/JPEG,
//! sRGB converted to linear light, and a mip pyramid (2x2 box averages in
//! linear light) for minification. Sampling is trilinear (bilinear within a
//! level, linear between levels), clamped to the edge; the same maths runs in
//! `render.wgsl`.

use crate::error::{Error, Result};
use crate::io::images::{read_rgb8, srgb8_to_linear};
use std::path::Path;

/// Largest base level, texels per side; larger images are area-downsampled at load.
pub const MAX_TEXTURE_SIDE: u32 = 2048;

/// One mip level: `w x h` texels, linear RGB interleaved.
#[derive(Debug, Clone, PartialEq)]
pub struct MipLevel {
    /// Width, texels.
    pub w: u32,
    /// Height, texels.
    pub h: u32,
    /// Linear RGB, row-major, top row first.
    pub rgb: Vec<f32>,
}

/// A mip-mapped linear-light texture.
#[derive(Debug, Clone, PartialEq)]
pub struct MipTexture {
    /// Level 0 is the full resolution.
    pub levels: Vec<MipLevel>,
}

fn halve(l: &MipLevel) -> MipLevel {
    let (w, h) = (l.w.div_ceil(2).max(1), l.h.div_ceil(2).max(1));
    let mut rgb = vec![0.0f32; (w * h * 3) as usize];
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0.0f32; 3];
            let mut n = 0.0;
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (sx, sy) = (2 * x + dx, 2 * y + dy);
                if sx < l.w && sy < l.h {
                    let i = ((sy * l.w + sx) * 3) as usize;
                    for (c, a) in acc.iter_mut().enumerate() {
                        *a += l.rgb[i + c];
                    }
                    n += 1.0;
                }
            }
            let o = ((y * w + x) * 3) as usize;
            for c in 0..3 {
                rgb[o + c] = acc[c] / n;
            }
        }
    }
    MipLevel { w, h, rgb }
}

impl MipTexture {
    /// Builds the pyramid from linear RGB level 0.
    pub fn from_linear(w: u32, h: u32, rgb: Vec<f32>) -> Result<Self> {
        if w == 0 || h == 0 || rgb.len() != (w * h * 3) as usize {
            return Err(Error::invalid(
                "texture",
                format!("{} values do not make a {w}x{h} RGB image", rgb.len()),
            ));
        }
        let mut levels = vec![MipLevel { w, h, rgb }];
        while levels
            .last()
            .is_some_and(|l| l.w > MAX_TEXTURE_SIDE || l.h > MAX_TEXTURE_SIDE)
        {
            let l = halve(levels.last().expect("non-empty"));
            levels = vec![l];
        }
        while levels.last().is_some_and(|l| l.w > 1 || l.h > 1) {
            let l = halve(levels.last().expect("non-empty"));
            levels.push(l);
        }
        Ok(MipTexture { levels })
    }

    /// Loads a PNG/JPEG (sRGB) as linear light.
    pub fn load(path: &Path) -> Result<Self> {
        Self::from_srgb8(&read_rgb8(path)?)
    }

    /// An 8-bit sRGB image as linear light.
    pub fn from_srgb8(img: &image::RgbImage) -> Result<Self> {
        let (w, h) = img.dimensions();
        let lut: Vec<f32> = (0..=255u8).map(srgb8_to_linear).collect();
        let rgb = img.as_raw().iter().map(|&v| lut[v as usize]).collect();
        Self::from_linear(w, h, rgb)
    }

    /// Width / height of level 0.
    pub fn aspect(&self) -> f64 {
        self.levels[0].w as f64 / self.levels[0].h as f64
    }

    /// Bilinear lookup in level `l` at normalized `(u, v)` (0..1, texel centres at `(i+0.5)/w`).
    pub fn bilinear(&self, l: usize, u: f32, v: f32) -> [f32; 3] {
        let lv = &self.levels[l.min(self.levels.len() - 1)];
        let x = (u * lv.w as f32 - 0.5).clamp(0.0, (lv.w - 1) as f32);
        let y = (v * lv.h as f32 - 0.5).clamp(0.0, (lv.h - 1) as f32);
        let (x0, y0) = (x.floor() as u32, y.floor() as u32);
        let (x1, y1) = ((x0 + 1).min(lv.w - 1), (y0 + 1).min(lv.h - 1));
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let at = |xx: u32, yy: u32, c: usize| lv.rgb[((yy * lv.w + xx) * 3) as usize + c];
        let mut o = [0.0; 3];
        for (c, oc) in o.iter_mut().enumerate() {
            let a = at(x0, y0, c) * (1.0 - fx) + at(x1, y0, c) * fx;
            let b = at(x0, y1, c) * (1.0 - fx) + at(x1, y1, c) * fx;
            *oc = a * (1.0 - fy) + b * fy;
        }
        o
    }

    /// Trilinear lookup at level-of-detail `lod` (0 = full resolution).
    pub fn trilinear(&self, u: f32, v: f32, lod: f32) -> [f32; 3] {
        let maxl = (self.levels.len() - 1) as f32;
        let lod = lod.clamp(0.0, maxl);
        let l0 = lod.floor();
        let f = lod - l0;
        let a = self.bilinear(l0 as usize, u, v);
        if f == 0.0 {
            return a;
        }
        let b = self.bilinear(l0 as usize + 1, u, v);
        [
            a[0] + (b[0] - a[0]) * f,
            a[1] + (b[1] - a[1]) * f,
            a[2] + (b[2] - a[2]) * f,
        ]
    }

    /// GPU layout: all levels' RGB concatenated, and per level `[offset (floats), w, h, 0]`.
    pub fn packed(&self) -> (Vec<f32>, Vec<[u32; 4]>) {
        let mut data = Vec::new();
        let mut info = Vec::new();
        for l in &self.levels {
            info.push([data.len() as u32, l.w, l.h, 0]);
            data.extend_from_slice(&l.rgb);
        }
        (data, info)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pyramid_preserves_mean_and_bilinear_hits_texels() {
        let (w, h) = (6u32, 3u32);
        let rgb: Vec<f32> = (0..w * h * 3).map(|i| (i % 7) as f32 / 7.0).collect();
        let t = MipTexture::from_linear(w, h, rgb.clone()).unwrap();
        assert_eq!(t.levels.len(), 4); // 6x3, 3x2, 2x1, 1x1
        assert_eq!((t.levels[1].w, t.levels[1].h), (3, 2));
        // texel centre (i+0.5)/w returns the texel exactly
        let c = t.bilinear(0, 2.5 / 6.0, 1.5 / 3.0);
        let i = ((w + 2) * 3) as usize; // texel (2, 1)
        assert_eq!(c, [rgb[i], rgb[i + 1], rgb[i + 2]]);
        assert!(MipTexture::from_linear(2, 2, vec![0.0; 3]).is_err());
        assert!(MipTexture::load(Path::new("/nonexistent/tex.png")).is_err());
    }
}
