//! Image arrays of any dtype for [`super::augment_image`]: (H, W, C) with C
//! in {1, 3, 4}, uint8 / uint16 / float32 / float64, decoded to linear f32
//! for the blur and encoded back to the input's dtype.
//!
//! Integers are sRGB-encoded (unless `srgb` is false: then linear, scaled
//! by 255 or 65535); floats are linear light. With C = 4 the fourth channel
//! is straight (not premultiplied) alpha, never sRGB-decoded: the colour is
//! premultiplied by it for the blur and divided back after, so a blurred
//! edge of a cut-out keeps its colour.

use crate::error::{Error, Result};
use std::sync::OnceLock;

/// Borrowed pixel values, interleaved, row-major.
#[derive(Debug, Clone, Copy)]
pub enum Pixels<'a> {
    /// 8-bit.
    U8(&'a [u8]),
    /// 16-bit.
    U16(&'a [u16]),
    /// float32.
    F32(&'a [f32]),
    /// float64.
    F64(&'a [f64]),
}

/// Owned pixel values of the same dtypes.
#[derive(Debug, Clone, PartialEq)]
pub enum PixelBuf {
    /// 8-bit.
    U8(Vec<u8>),
    /// 16-bit.
    U16(Vec<u16>),
    /// float32.
    F32(Vec<f32>),
    /// float64.
    F64(Vec<f64>),
}

impl Pixels<'_> {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            Pixels::U8(v) => v.len(),
            Pixels::U16(v) => v.len(),
            Pixels::F32(v) => v.len(),
            Pixels::F64(v) => v.len(),
        }
    }

    /// True without values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// An owned copy, bit for bit.
    pub fn to_buf(&self) -> PixelBuf {
        match self {
            Pixels::U8(v) => PixelBuf::U8(v.to_vec()),
            Pixels::U16(v) => PixelBuf::U16(v.to_vec()),
            Pixels::F32(v) => PixelBuf::F32(v.to_vec()),
            Pixels::F64(v) => PixelBuf::F64(v.to_vec()),
        }
    }
}

/// An image to augment.
#[derive(Debug, Clone, Copy)]
pub struct Image<'a> {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Channels: 1 (gray), 3 (RGB) or 4 (RGBA, straight alpha).
    pub channels: u32,
    /// Values, `height * width * channels`, interleaved.
    pub pixels: Pixels<'a>,
    /// Integer values are sRGB-encoded (ignored for floats).
    pub srgb: bool,
}

fn decode_u8() -> &'static [f32; 256] {
    static T: OnceLock<[f32; 256]> = OnceLock::new();
    T.get_or_init(|| std::array::from_fn(|v| srgb_to_linear(v as f64 / 255.0) as f32))
}

fn decode_u16() -> &'static [f32] {
    static T: OnceLock<Vec<f32>> = OnceLock::new();
    T.get_or_init(|| {
        (0..=u16::MAX)
            .map(|v| srgb_to_linear(v as f64 / 65535.0) as f32)
            .collect()
    })
}

/// Linear values at which the sRGB code rounds up: code `k + 1` from
/// `thr[k]` on (so encoding is `round(255 * srgb(x))` by a binary search).
fn thresholds(max: u32) -> Vec<f32> {
    (0..max)
        .map(|k| srgb_to_linear((k as f64 + 0.5) / max as f64) as f32)
        .collect()
}

fn encode_u8() -> &'static [f32] {
    static T: OnceLock<Vec<f32>> = OnceLock::new();
    T.get_or_init(|| thresholds(255))
}

fn encode_u16() -> &'static [f32] {
    static T: OnceLock<Vec<f32>> = OnceLock::new();
    T.get_or_init(|| thresholds(65535))
}

fn srgb_to_linear(s: f64) -> f64 {
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

impl Image<'_> {
    /// Checks the size, the channel count and (floats) finiteness.
    pub fn validate(&self) -> Result<()> {
        let (w, h, c) = (self.width, self.height, self.channels);
        if ![1, 3, 4].contains(&c) {
            return Err(Error::invalid(
                "augment image",
                format!("{c} channels: expected 1, 3 or 4"),
            ));
        }
        let px = w as u64 * h as u64;
        if px > crate::limits::AUGMENT_MAX_PIXELS {
            return Err(Error::invalid(
                "augment image",
                format!(
                    "{w} x {h} px: at most {} px",
                    crate::limits::AUGMENT_MAX_PIXELS
                ),
            ));
        }
        if w < 2 || h < 2 || self.pixels.len() as u64 != px * c as u64 {
            return Err(Error::invalid(
                "augment image",
                format!(
                    "{w} x {h} px with {} values: expected (H, W, {c}), at least 2 x 2",
                    self.pixels.len()
                ),
            ));
        }
        let bad = match self.pixels {
            Pixels::F32(v) => v.iter().position(|x| !x.is_finite()),
            Pixels::F64(v) => v.iter().position(|x| !x.is_finite()),
            _ => None,
        };
        if let Some(i) = bad {
            let p = i / c as usize;
            return Err(Error::invalid(
                "augment image",
                format!(
                    "value {i} (pixel {}, {}) is not finite",
                    p % w as usize,
                    p / w as usize
                ),
            ));
        }
        Ok(())
    }

    /// Linear f32 values, colour premultiplied by alpha with 4 channels.
    pub fn to_linear(&self) -> Vec<f32> {
        let c = self.channels as usize;
        // Integer codes: the sRGB table (colour) or the scale (alpha, linear).
        fn decode<T: Copy + Into<u32>>(
            v: &[T],
            table: &[f32],
            max: f32,
            srgb: bool,
            c: usize,
        ) -> Vec<f32> {
            v.iter()
                .enumerate()
                .map(|(k, &x)| {
                    let x: u32 = x.into();
                    if srgb && !(c == 4 && k % 4 == 3) {
                        table[x as usize]
                    } else {
                        x as f32 / max
                    }
                })
                .collect()
        }
        let mut out: Vec<f32> = match self.pixels {
            Pixels::U8(v) => decode(v, decode_u8(), 255.0, self.srgb, c),
            Pixels::U16(v) => {
                let t = if self.srgb { decode_u16() } else { &[] };
                decode(v, t, 65535.0, self.srgb, c)
            }
            Pixels::F32(v) => v.to_vec(),
            Pixels::F64(v) => v.iter().map(|&x| x as f32).collect(),
        };
        if c == 4 {
            for px in out.chunks_exact_mut(4) {
                let a = px[3];
                px[..3].iter_mut().for_each(|x| *x *= a);
            }
        }
        out
    }

    /// Encodes linear `lin` (premultiplied with 4 channels; consumed) in
    /// this image's dtype: integers rounded to the nearest code, clamped.
    pub fn encode(&self, mut lin: Vec<f32>) -> PixelBuf {
        let c = self.channels as usize;
        if c == 4 {
            for px in lin.chunks_exact_mut(4) {
                let a = px[3];
                let inv = if a > 0.0 { 1.0 / a } else { 0.0 };
                px[..3].iter_mut().for_each(|x| *x *= inv);
            }
        }
        let alpha = |k: usize| c == 4 && k % 4 == 3;
        let code = |x: f32, thr: &[f32], max: f32, k: usize| -> u32 {
            if self.srgb && !alpha(k) {
                thr.partition_point(|&t| t <= x) as u32
            } else {
                (x.clamp(0.0, 1.0) * max + 0.5) as u32
            }
        };
        match self.pixels {
            Pixels::U8(_) => {
                let thr = encode_u8();
                PixelBuf::U8(
                    lin.iter()
                        .enumerate()
                        .map(|(k, &x)| code(x, thr, 255.0, k) as u8)
                        .collect(),
                )
            }
            Pixels::U16(_) => {
                let thr = if self.srgb { encode_u16() } else { &[] };
                PixelBuf::U16(
                    lin.iter()
                        .enumerate()
                        .map(|(k, &x)| code(x, thr, 65535.0, k) as u16)
                        .collect(),
                )
            }
            Pixels::F32(_) => PixelBuf::F32(lin),
            Pixels::F64(_) => PixelBuf::F64(lin.iter().map(|&x| x as f64).collect()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_srgb_code_round_trips() {
        let v: Vec<u8> = (0..=255).collect();
        let img = Image {
            width: 16,
            height: 16,
            channels: 1,
            pixels: Pixels::U8(&v),
            srgb: true,
        };
        assert_eq!(img.encode(img.to_linear()), PixelBuf::U8(v.clone()));
        let w: Vec<u16> = (0..=u16::MAX).step_by(7).collect();
        let img = Image {
            pixels: Pixels::U16(&w),
            width: w.len() as u32,
            height: 1,
            ..img
        };
        assert_eq!(img.encode(img.to_linear()), PixelBuf::U16(w.clone()));
    }

    #[test]
    fn alpha_is_linear_and_colour_premultiplied() {
        let v = [255u8, 0, 0, 128];
        let img = Image {
            width: 1,
            height: 1,
            channels: 4,
            pixels: Pixels::U8(&v),
            srgb: true,
        };
        let lin = img.to_linear();
        assert!((lin[3] - 128.0 / 255.0).abs() < 1e-7);
        assert!((lin[0] - 128.0 / 255.0).abs() < 1e-7);
        assert_eq!(img.encode(lin), PixelBuf::U8(v.to_vec()));
    }
}
