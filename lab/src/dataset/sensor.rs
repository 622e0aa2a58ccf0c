//! A dataset's camera pipeline (`[sensor]`): what turns the rendered linear
//! light into the 8-bit image a camera writes, applied to the items' PNG
//! files (the EXR files stay linear). In order: sensor noise (photon and
//! read noise, the `[camera.noise]` EMVA 1288 model, seeded per item),
//! saturation in linear light (clipped at white, or at the full well with
//! noise), a Bayer mosaic and its bilinear demosaicing, the response
//! (tone) curve, 8-bit quantisation, and JPEG compression at a quality
//! (decoded again, stored as PNG so the files keep their names). The sharp
//! frame goes through the same pipeline without blur and, unless
//! `sharp_noise`, without noise.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// The `[sensor]` section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorPipeline {
    /// Response curve from linear light to the encoded value: `srgb`,
    /// `linear`, `gamma:G` (`x^(1/G)`) or `points` (the measured curve in
    /// `response_points`).
    pub response: String,
    /// A measured response: `[linear, encoded]` pairs from `[0, 0]` to
    /// `[1, 1]`, increasing, linear in between (with `response = "points"`).
    pub response_points: Vec<[f64; 2]>,
    /// Bayer pattern of the mosaic (`rggb`, `bggr`, `grbg`, `gbrg`), or
    /// `none`.
    pub bayer: String,
    /// JPEG quality 1..=100, or 0 for none.
    pub jpeg_quality: u8,
    /// Noise in the sharp frame too (with `[camera.noise]`).
    pub sharp_noise: bool,
}

impl Default for SensorPipeline {
    fn default() -> Self {
        SensorPipeline {
            response: "srgb".into(),
            response_points: Vec::new(),
            bayer: "none".into(),
            jpeg_quality: 0,
            sharp_noise: false,
        }
    }
}

/// A parsed response curve.
#[derive(Debug, Clone, PartialEq)]
enum Response {
    Srgb,
    Linear,
    Gamma(f64),
    Points(Vec<[f64; 2]>),
}

impl SensorPipeline {
    fn response_curve(&self) -> Result<Response> {
        let bad = |m: String| Error::invalid("[sensor] response", m);
        let r = match self.response.as_str() {
            "srgb" => Response::Srgb,
            "linear" => Response::Linear,
            "points" => {
                let p = &self.response_points;
                if p.len() < 2
                    || p[0] != [0.0, 0.0]
                    || p[p.len() - 1] != [1.0, 1.0]
                    || p.windows(2)
                        .any(|w| !(w[1][0] > w[0][0] && w[1][1] >= w[0][1]))
                    || p.iter().flatten().any(|x| !x.is_finite())
                {
                    return Err(bad(
                        "response_points must run from [0, 0] to [1, 1], the linear values increasing and \
                         the encoded ones not decreasing"
                            .into(),
                    ));
                }
                Response::Points(p.clone())
            }
            s => match s.strip_prefix("gamma:").map(str::parse::<f64>) {
                Some(Ok(g)) if g.is_finite() && g > 0.0 => Response::Gamma(g),
                _ => {
                    return Err(bad(format!(
                        "'{s}': expected srgb, linear, gamma:G (G > 0) or points"
                    )))
                }
            },
        };
        if !matches!(r, Response::Points(_)) && !self.response_points.is_empty() {
            return Err(bad(
                "response_points is given but response is not \"points\"".into(),
            ));
        }
        Ok(r)
    }

    /// The Bayer pattern: the colour (0 R, 1 G, 2 B) at `(x mod 2, y mod 2)`.
    fn pattern(&self) -> Result<Option<[[usize; 2]; 2]>> {
        let c = |ch: u8| match ch {
            b'r' => 0,
            b'g' => 1,
            _ => 2,
        };
        match self.bayer.as_str() {
            "none" => Ok(None),
            p @ ("rggb" | "bggr" | "grbg" | "gbrg") => {
                let b = p.as_bytes();
                Ok(Some([[c(b[0]), c(b[1])], [c(b[2]), c(b[3])]]))
            }
            s => Err(Error::invalid(
                "[sensor] bayer",
                format!("'{s}': expected none, rggb, bggr, grbg or gbrg"),
            )),
        }
    }

    /// Checks every key.
    pub fn validate(&self) -> Result<()> {
        self.response_curve()?;
        self.pattern()?;
        if self.jpeg_quality > 100 {
            return Err(Error::invalid(
                "[sensor] jpeg_quality",
                format!("{}: expected 1..=100, or 0 for no JPEG", self.jpeg_quality),
            ));
        }
        Ok(())
    }

    /// The 8-bit RGB image of the linear `rgb` (`w` x `h`, interleaved;
    /// noise already applied).
    pub fn encode(&self, w: u32, h: u32, rgb: &[f32]) -> Result<Vec<u8>> {
        let curve = self.response_curve()?;
        let (wu, hu) = (w as usize, h as usize);
        // Saturation in linear light, before the curve.
        let mut lin: Vec<f32> = rgb.iter().map(|x| x.clamp(0.0, 1.0)).collect();
        if let Some(p) = self.pattern()? {
            lin = demosaic(&mosaic(&lin, wu, hu, &p), wu, hu, &p);
        }
        let mut out: Vec<u8> = lin
            .iter()
            .map(|&x| (apply(&curve, x as f64) * 255.0).round().clamp(0.0, 255.0) as u8)
            .collect();
        if self.jpeg_quality > 0 {
            out = jpeg_round_trip(w, h, out, self.jpeg_quality)?;
        }
        Ok(out)
    }
}

fn apply(c: &Response, x: f64) -> f64 {
    match c {
        Response::Srgb => {
            if x <= 0.003_130_8 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            }
        }
        Response::Linear => x,
        Response::Gamma(g) => x.powf(1.0 / g),
        Response::Points(p) => {
            let j = p.partition_point(|q| q[0] <= x).clamp(1, p.len() - 1);
            let (a, b) = (p[j - 1], p[j]);
            a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0])
        }
    }
}

/// One colour per pixel, as the pattern says.
fn mosaic(rgb: &[f32], w: usize, h: usize, p: &[[usize; 2]; 2]) -> Vec<f32> {
    (0..w * h)
        .map(|k| {
            let (x, y) = (k % w, k / w);
            rgb[k * 3 + p[y % 2][x % 2]]
        })
        .collect()
}

/// Bilinear demosaicing: each missing colour the mean of the nearest
/// pixels of that colour in the 3 x 3 neighbourhood (edges clamped).
fn demosaic(m: &[f32], w: usize, h: usize, p: &[[usize; 2]; 2]) -> Vec<f32> {
    let mut out = vec![0.0f32; w * h * 3];
    for y in 0..h {
        for x in 0..w {
            let own = p[y % 2][x % 2];
            for c in 0..3 {
                let v = if c == own {
                    m[y * w + x]
                } else {
                    let (mut s, mut n) = (0.0f32, 0u32);
                    for dy in -1i64..=1 {
                        for dx in -1i64..=1 {
                            let (xx, yy) = (x as i64 + dx, y as i64 + dy);
                            if xx < 0 || yy < 0 || xx >= w as i64 || yy >= h as i64 {
                                continue;
                            }
                            let (xx, yy) = (xx as usize, yy as usize);
                            if p[yy % 2][xx % 2] == c {
                                s += m[yy * w + xx];
                                n += 1;
                            }
                        }
                    }
                    if n > 0 {
                        s / n as f32
                    } else {
                        m[y * w + x]
                    }
                };
                out[(y * w + x) * 3 + c] = v;
            }
        }
    }
    out
}

/// Encodes as JPEG at `quality` and decodes again.
fn jpeg_round_trip(w: u32, h: u32, rgb: Vec<u8>, quality: u8) -> Result<Vec<u8>> {
    let mut buf = Vec::new();
    let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut buf, quality);
    image::ImageEncoder::write_image(enc, &rgb, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| Error::invalid("JPEG", e.to_string()))?;
    let img = image::load_from_memory_with_format(&buf, image::ImageFormat::Jpeg)
        .map_err(|e| Error::invalid("JPEG", e.to_string()))?;
    Ok(img.to_rgb8().into_raw())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_pipeline_is_the_srgb_png() {
        let s = SensorPipeline::default();
        let rgb: Vec<f32> = (0..48).map(|i| i as f32 / 40.0 - 0.1).collect();
        let got = s.encode(4, 4, &rgb).unwrap();
        let want: Vec<u8> = rgb
            .iter()
            .map(|&x| crate::io::images::linear_to_srgb8(x))
            .collect();
        assert_eq!(got, want);
    }

    #[test]
    fn curves_map_as_stated() {
        let g = Response::Gamma(2.0);
        assert!((apply(&g, 0.25) - 0.5).abs() < 1e-12);
        let p = Response::Points(vec![[0.0, 0.0], [0.2, 0.5], [1.0, 1.0]]);
        assert!((apply(&p, 0.1) - 0.25).abs() < 1e-12);
        assert!((apply(&p, 0.6) - 0.75).abs() < 1e-12);
        assert_eq!(apply(&p, 1.0), 1.0);
        let bad = SensorPipeline {
            response: "points".into(),
            response_points: vec![[0.0, 0.0], [0.5, 0.6], [0.4, 0.8], [1.0, 1.0]],
            ..Default::default()
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("increasing"));
        for (k, v) in [("gamma:0", "gamma"), ("log", "srgb, linear")] {
            let s = SensorPipeline {
                response: k.into(),
                ..Default::default()
            };
            assert!(s.validate().unwrap_err().to_string().contains(v), "{k}");
        }
    }

    #[test]
    fn demosaicing_keeps_flat_colour_and_the_measured_samples() {
        let p = SensorPipeline {
            bayer: "rggb".into(),
            ..Default::default()
        }
        .pattern()
        .unwrap()
        .unwrap();
        assert_eq!(p, [[0, 1], [1, 2]]);
        let (w, h) = (6, 4);
        let flat: Vec<f32> = (0..w * h).flat_map(|_| [0.8f32, 0.4, 0.1]).collect();
        let back = demosaic(&mosaic(&flat, w, h, &p), w, h, &p);
        for (a, b) in back.iter().zip(&flat) {
            assert!((a - b).abs() < 1e-6);
        }
        // A red dot on one R site: the G and B there are their neighbours'.
        let mut img = vec![0.0f32; w * h * 3];
        img[(2 * w + 2) * 3] = 1.0;
        let m = mosaic(&img, w, h, &p);
        assert_eq!(m[2 * w + 2], 1.0);
        let d = demosaic(&m, w, h, &p);
        assert_eq!(d[(2 * w + 2) * 3], 1.0);
        // The G site beside it interpolates red from its two R neighbours.
        assert!((d[(2 * w + 3) * 3] - 0.5).abs() < 1e-6);
    }

    #[test]
    fn jpeg_changes_the_bytes_a_little() {
        let (w, h) = (32u32, 24u32);
        let rgb: Vec<u8> = (0..w * h * 3).map(|i| ((i * 37) % 256) as u8).collect();
        let hi = jpeg_round_trip(w, h, rgb.clone(), 95).unwrap();
        let lo = jpeg_round_trip(w, h, rgb.clone(), 10).unwrap();
        let err = |x: &[u8]| {
            x.iter()
                .zip(&rgb)
                .map(|(a, b)| (*a as f64 - *b as f64).abs())
                .sum::<f64>()
                / rgb.len() as f64
        };
        assert!(err(&hi) < err(&lo), "{} {}", err(&hi), err(&lo));
        assert!(err(&lo) > 1.0);
        let bad = SensorPipeline {
            jpeg_quality: 101,
            ..Default::default()
        };
        assert!(bad.validate().is_err());
    }
}
