//! Image files: float EXR with named channels, sRGB PNG from linear values,
//! and reading textures. All writes are atomic (temp file + rename).

use crate::error::{Error, Result};
use crate::io::atomic::write_atomic_path;
use exr::prelude::*;
use std::path::Path;

/// Writes a float EXR with the given named channels (`width * height` values
/// each, row-major, top row first). Channel names may contain dots (`flow.u`).
pub fn write_exr(
    path: &Path,
    width: usize,
    height: usize,
    channels: &[(&str, &[f32])],
) -> Result<()> {
    write_exr_as(path, width, height, channels, false)
}

/// [`write_exr`] with the samples stored as half floats (f16: 11 bits of
/// mantissa, about 3 significant digits, up to 65504; larger magnitudes
/// become infinite) when `half`, else as f32; ZIP-compressed scan lines
/// either way.
pub fn write_exr_as(
    path: &Path,
    width: usize,
    height: usize,
    channels: &[(&str, &[f32])],
    half: bool,
) -> Result<()> {
    for (name, data) in channels {
        if data.len() != width * height {
            return Err(Error::invalid(
                "EXR channel",
                format!(
                    "'{name}' has {} values, expected {width}x{height}",
                    data.len()
                ),
            ));
        }
    }
    let samples = |data: &[f32]| {
        if half {
            FlatSamples::F16(
                data.iter()
                    .map(|&x| exr::prelude::f16::from_f32(x))
                    .collect(),
            )
        } else {
            FlatSamples::F32(data.to_vec())
        }
    };
    let list: Vec<AnyChannel<FlatSamples>> = channels
        .iter()
        .map(|(name, data)| AnyChannel::new(*name, samples(data)))
        .collect();
    let layer = Layer::new(
        (width, height),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    let image = exr::image::Image::from_layer(layer);
    write_atomic_path(path, |tmp| {
        image.write().to_file(tmp).map_err(|e| Error::Image {
            path: path.into(),
            message: e.to_string(),
        })
    })
}

/// Most samples (pixels x channels, all layers) an EXR may declare to be read.
pub const MAX_EXR_SAMPLES: u128 = 1 << 28;

/// Named channels of an EXR layer: `(name, values)`, row-major.
pub type ExrChannels = Vec<(String, Vec<f32>)>;

/// Reads every f32 (or f16, converted) channel of the first layer of an EXR:
/// `(width, height, [(name, values)])`.
pub fn read_exr(path: &Path) -> Result<(usize, usize, ExrChannels)> {
    // A missing or unreadable file is an I/O error (as for every input), and
    // only a regular file is read (never a device or a pipe).
    super::input::open_file(path)?;
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| Error::Image {
        path: path.into(),
        message: e.to_string(),
    })?;
    check_exr_samples(&meta, path)?;
    let img = read_all_flat_layers_from_file(path).map_err(|e| Error::Image {
        path: path.into(),
        message: e.to_string(),
    })?;
    exr_channels(img, path)
}

/// [`read_exr`] of an EXR file's bytes (e.g. a WebDataset sample's);
/// errors name `what` in place of a path.
pub fn read_exr_bytes(bytes: &[u8], what: &str) -> Result<(usize, usize, ExrChannels)> {
    let path = Path::new(what);
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| Error::Image {
            path: path.into(),
            message: e.to_string(),
        })?;
    check_exr_samples(&meta, path)?;
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| Error::Image {
            path: path.into(),
            message: e.to_string(),
        })?;
    exr_channels(img, path)
}

/// The header first: a file that claims more samples than any mmbm output
/// has is refused before anything is allocated for it.
fn check_exr_samples(meta: &exr::meta::MetaData, path: &Path) -> Result<()> {
    let samples: u128 = meta
        .headers
        .iter()
        .map(|h| {
            h.layer_size.width() as u128
                * h.layer_size.height() as u128
                * h.channels.list.len() as u128
        })
        .sum();
    if samples > MAX_EXR_SAMPLES {
        return Err(Error::Image {
            path: path.into(),
            message: format!(
                "the header declares {samples} samples, more than the {MAX_EXR_SAMPLES} mmbm reads"
            ),
        });
    }
    Ok(())
}

/// The first layer's channels as f32.
fn exr_channels(img: FlatImage, path: &Path) -> Result<(usize, usize, ExrChannels)> {
    let layer = img.layer_data.first().ok_or_else(|| Error::Image {
        path: path.into(),
        message: "no layers".into(),
    })?;
    let (w, h) = (layer.size.width(), layer.size.height());
    let chans = layer
        .channel_data
        .list
        .iter()
        .map(|c| {
            let v: Vec<f32> = c.sample_data.values_as_f32().collect();
            (c.name.to_string(), v)
        })
        .collect();
    Ok((w, h, chans))
}

/// Linear light (0..1) to 8-bit sRGB.
pub fn linear_to_srgb8(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let s = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// 8-bit sRGB to linear light (0..1).
pub fn srgb8_to_linear(v: u8) -> f32 {
    let s = v as f32 / 255.0;
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

/// Saves an RGB8 (or any `image`-supported) buffer as PNG/JPEG by extension, atomically.
pub fn save_rgb8(path: &Path, img: &image::RgbImage) -> Result<()> {
    let format = image::ImageFormat::from_path(path).map_err(|e| Error::Image {
        path: path.into(),
        message: e.to_string(),
    })?;
    write_atomic_path(path, |tmp| {
        img.save_with_format(tmp, format).map_err(|e| Error::Image {
            path: path.into(),
            message: e.to_string(),
        })
    })
}

/// Writes linear RGB (interleaved, 0..1) as an sRGB 8-bit PNG.
pub fn write_png_linear_rgb(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<()> {
    let bytes: Vec<u8> = rgb.iter().map(|&x| linear_to_srgb8(x)).collect();
    let img = image::RgbImage::from_raw(width, height, bytes).ok_or_else(|| {
        Error::invalid(
            "PNG",
            format!(
                "{} values do not make a {width}x{height} RGB image",
                rgb.len()
            ),
        )
    })?;
    save_rgb8(path, &img)
}

/// Decodes any PNG/JPEG (format guessed from the content), naming the
/// file in errors: a regular file whose header declares at most
/// [`super::input::MAX_IMAGE_PIXELS`] (checked before decoding).
pub fn decode(path: &Path) -> Result<image::DynamicImage> {
    let (w, h) = super::input::image_dimensions(path)?;
    let file = super::input::open_file(path)?;
    let mut r = image::ImageReader::new(std::io::BufReader::new(file))
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?;
    // The decoder holds to the size its header declared (and was checked).
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    r.limits(limits);
    r.decode().map_err(|e| Error::Image {
        path: path.into(),
        message: e.to_string(),
    })
}

/// Reads any PNG/JPEG as RGB8 ([`decode`]).
pub fn read_rgb8(path: &Path) -> Result<image::RgbImage> {
    Ok(decode(path)?.to_rgb8())
}

/// Linear RGB (interleaved) to an 8-bit sRGB image.
pub fn to_rgb8(width: u32, height: u32, rgb: &[f32]) -> Result<image::RgbImage> {
    let bytes: Vec<u8> = rgb.iter().map(|&x| linear_to_srgb8(x)).collect();
    rgb8_image(width, height, bytes)
}

/// The RGB8 image of `bytes` (one per value), or an error when they are not
/// `width x height x 3`.
fn rgb8_image(width: u32, height: u32, bytes: Vec<u8>) -> Result<image::RgbImage> {
    let n = bytes.len();
    image::RgbImage::from_raw(width, height, bytes).ok_or_else(|| {
        Error::invalid(
            "frame",
            format!("{n} values are not a {width}x{height} RGB image"),
        )
    })
}

/// [`to_rgb8`] of the linear values `dn / max_dn` (the digital numbers of
/// [`crate::camera::Noise::apply_dn`], `max_dn = 2^bits - 1`), byte for byte,
/// through a table of the `max_dn + 1` codes instead of a power per value.
pub fn dn_to_rgb8(width: u32, height: u32, dn: &[u16], max_dn: u16) -> Result<image::RgbImage> {
    let table: Vec<u8> = (0..=max_dn)
        .map(|d| linear_to_srgb8((f64::from(d) / f64::from(max_dn)) as f32))
        .collect();
    let bytes = dn
        .iter()
        .map(|&d| {
            table.get(usize::from(d)).copied().ok_or_else(|| {
                Error::invalid(
                    "frame",
                    format!("digital number {d} above the largest, {max_dn}"),
                )
            })
        })
        .collect::<Result<Vec<u8>>>()?;
    rgb8_image(width, height, bytes)
}

/// 2x2 box downsampling of linear RGB (for the montage).
pub fn half(width: u32, height: u32, rgb: &[f32]) -> Vec<f32> {
    let (w2, h2) = ((width / 2) as usize, (height / 2) as usize);
    let w = width as usize;
    let mut out = vec![0.0; w2 * h2 * 3];
    for y in 0..h2 {
        for x in 0..w2 {
            for c in 0..3 {
                let at = |xx: usize, yy: usize| rgb[(yy * w + xx) * 3 + c];
                out[(y * w2 + x) * 3 + c] = 0.25
                    * (at(2 * x, 2 * y)
                        + at(2 * x + 1, 2 * y)
                        + at(2 * x, 2 * y + 1)
                        + at(2 * x + 1, 2 * y + 1));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_averages_2x2_and_to_rgb8_checks_the_size() {
        // 2x2 RGB: one white pixel of four: a quarter.
        let rgb = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        assert_eq!(half(2, 2, &rgb), vec![0.25; 3]);
        assert!(to_rgb8(2, 2, &rgb).is_ok());
        assert!(to_rgb8(3, 2, &rgb).is_err());
    }

    /// Every code of 1, 8, 12 and 16 bits gives the byte `to_rgb8` gives its value.
    #[test]
    fn dn_to_rgb8_is_to_rgb8_of_the_codes() {
        for bits in [1u32, 8, 12, 16] {
            let max = ((1u32 << bits) - 1) as u16;
            let codes: Vec<u16> = (0..=max).collect();
            let lin: Vec<f32> = codes
                .iter()
                .map(|&d| (f64::from(d) / f64::from(max)) as f32)
                .collect();
            let n = codes.len() as u32;
            // One row of RGB pixels: the codes padded with zeros to a multiple of 3.
            let pad = (3 - codes.len() % 3) % 3;
            let codes: Vec<u16> = codes
                .into_iter()
                .chain(std::iter::repeat_n(0, pad))
                .collect();
            let lin: Vec<f32> = lin
                .into_iter()
                .chain(std::iter::repeat_n(0.0, pad))
                .collect();
            let w = (n + pad as u32) / 3;
            assert_eq!(
                dn_to_rgb8(w, 1, &codes, max).unwrap(),
                to_rgb8(w, 1, &lin).unwrap(),
                "{bits} bits"
            );
        }
        let e = dn_to_rgb8(1, 1, &[0, 256, 0], 255).unwrap_err().to_string();
        assert!(e.contains("256"), "{e}");
        assert!(dn_to_rgb8(2, 1, &[0, 1, 2], 255).is_err());
    }

    #[test]
    fn exr_round_trip_and_srgb() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("x.exr");
        let a: Vec<f32> = (0..12).map(|i| i as f32 * 0.5).collect();
        let b: Vec<f32> = (0..12).map(|i| -(i as f32)).collect();
        write_exr(&p, 4, 3, &[("flow.u", &a), ("flow.v", &b)]).unwrap();
        let (w, h, ch) = read_exr(&p).unwrap();
        assert_eq!((w, h), (4, 3));
        let u = &ch.iter().find(|c| c.0 == "flow.u").unwrap().1;
        assert_eq!(u, &a);
        assert!(write_exr(&p, 5, 3, &[("x", &a)]).is_err());
        for v in [0u8, 1, 10, 100, 200, 255] {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(v)), v);
        }
        assert!(read_rgb8(&d.path().join("missing.png"))
            .unwrap_err()
            .to_string()
            .contains("missing.png"));
    }
}
