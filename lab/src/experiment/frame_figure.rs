//! The report's frame figure: per policy its sharpest and its most blurred
//! rendered frame, each cropped to the board (enlarged with nearest-neighbour
//! sampling, so a sensor pixel stays a visible square) with the full frame as
//! an inset (the crop outlined on it), under a label: policy, which frame,
//! trigger time (s), ground-truth blur (px) and the blob verdict (all 16 blobs
//! found, or how many were, and the false alarms).

use super::crop::pattern_box;
use crate::error::{Error, Result};
use crate::io::images::{linear_to_srgb8, save_rgb8};
use crate::plot::{ensure_font, plot_error};
use image::{Rgb, RgbImage};
use plotters::prelude::*;
use std::path::Path;

/// One rendered frame kept for the figure.
#[derive(Debug, Clone)]
pub struct Shot {
    /// Trigger time, s (walk clock).
    pub trigger_t: f64,
    /// Ground-truth blur (mean path length over the sensor), px.
    pub blur_px: f64,
    /// Board places with a blob.
    pub blobs_matched: usize,
    /// Board places (16 on the thesis board).
    pub blobs_expected: usize,
    /// Blobs found away from every board place.
    pub blobs_false: usize,
    /// All places found, no other blob.
    pub ok: bool,
    /// A start-up trigger: before the walk's first full decision horizon
    /// ([`crate::trigger::DEFAULT_HORIZON_S`] after its first sample), when
    /// no policy has seen the motion yet; never the "most blurred" pick while
    /// another frame is there, and marked in its label.
    pub startup: bool,
    /// The blob centres at mid-exposure, px (the crop is around them).
    pub expected_px: Vec<(f64, f64)>,
    /// Linear RGB, interleaved, the camera's size.
    pub rgb: Vec<f32>,
}

/// The sharpest and the most blurred rendered frame of one run.
#[derive(Debug, Clone)]
pub struct Extremes {
    /// The frame with the least ground-truth blur.
    pub sharpest: Shot,
    /// The frame with the most.
    pub blurriest: Shot,
}

impl Extremes {
    /// Starts with `s` as both.
    pub fn new(s: Shot) -> Self {
        Extremes {
            sharpest: s.clone(),
            blurriest: s,
        }
    }

    /// Keeps `s` where it is sharper than the sharpest or more blurred than
    /// the blurriest; a start-up trigger is the blurriest only while no
    /// other frame was offered.
    pub fn offer(&mut self, s: Shot) {
        if s.blur_px < self.sharpest.blur_px {
            self.sharpest = s.clone();
        }
        let b = &self.blurriest;
        if (b.startup && !s.startup) || (b.startup == s.startup && s.blur_px > b.blur_px) {
            self.blurriest = s;
        }
    }
}

/// The blob verdict of a shot, e.g. `all 16 blobs found`, `11/16 blobs found, 2 false alarms`.
pub fn verdict(s: &Shot) -> String {
    let found = if s.ok {
        format!("all {} blobs found", s.blobs_expected)
    } else {
        format!("{}/{} blobs found", s.blobs_matched, s.blobs_expected)
    };
    match s.blobs_false {
        0 => found,
        1 => format!("{found}, 1 false alarm"),
        n => format!("{found}, {n} false alarms"),
    }
}

/// The two label lines of a shot of `policy` (`which`: "sharpest" or "most blurred").
pub fn label(policy: &str, which: &str, s: &Shot) -> [String; 2] {
    [
        format!("{policy}: {which}"),
        format!(
            "t = {:.2} s{}, blur {:.1} px, {}",
            s.trigger_t,
            if s.startup { " (start-up trigger)" } else { "" },
            s.blur_px,
            verdict(s)
        ),
    ]
}

/// Panel width and image height, px; label height, px.
const PANEL_W: u32 = 420;
const IMAGE_H: u32 = 300;
const LABEL_H: u32 = 44;
const GUTTER: u32 = 6;

fn srgb(rgb: &[f32], width: u32, x: u32, y: u32) -> Rgb<u8> {
    let i = 3 * (y * width + x) as usize;
    Rgb([
        linear_to_srgb8(rgb[i]),
        linear_to_srgb8(rgb[i + 1]),
        linear_to_srgb8(rgb[i + 2]),
    ])
}

/// Draws shot `s` (a `width` x `height` frame) into `canvas` with its image
/// area's top-left corner at `(x0, y0)`.
fn draw_shot(canvas: &mut RgbImage, s: &Shot, width: u32, height: u32, x0: u32, y0: u32) {
    let [cx, cy, cw, ch] = pattern_box(width, height, &s.expected_px);
    // Enlarge the crop to fit the image area (the same factor on both axes).
    let scale = (PANEL_W as f64 / cw.max(1) as f64).min(IMAGE_H as f64 / ch.max(1) as f64);
    let (dw, dh) = (
        ((cw as f64 * scale) as u32).min(PANEL_W),
        ((ch as f64 * scale) as u32).min(IMAGE_H),
    );
    let (ox, oy) = (x0 + (PANEL_W - dw) / 2, y0 + (IMAGE_H - dh) / 2);
    for y in 0..dh {
        for x in 0..dw {
            let sx = (cx + (x as f64 / scale) as u32).min(width - 1);
            let sy = (cy + (y as f64 / scale) as u32).min(height - 1);
            canvas.put_pixel(ox + x, oy + y, srgb(&s.rgb, width, sx, sy));
        }
    }
    // The inset: the full frame at a quarter of the panel's width, bottom
    // right, in a white border, with the crop outlined in yellow.
    let iw = PANEL_W / 4;
    let ih = (iw as f64 * height as f64 / width as f64).round().max(1.0) as u32;
    let ih = ih.min(IMAGE_H / 2);
    let (ix, iy) = (x0 + PANEL_W - iw - 3, y0 + IMAGE_H - ih - 3);
    for y in 0..ih + 2 {
        for x in 0..iw + 2 {
            canvas.put_pixel(ix + x - 1, iy + y - 1, Rgb([255, 255, 255]));
        }
    }
    let (fx, fy) = (width as f64 / iw as f64, height as f64 / ih as f64);
    for y in 0..ih {
        for x in 0..iw {
            let sx = ((x as f64 + 0.5) * fx) as u32;
            let sy = ((y as f64 + 0.5) * fy) as u32;
            let inside_x = sx >= cx && sx < cx + cw;
            let inside_y = sy >= cy && sy < cy + ch;
            let edge_x = (x as f64 * fx - cx as f64).abs() < fx
                || (x as f64 * fx - (cx + cw) as f64).abs() < fx;
            let edge_y = (y as f64 * fy - cy as f64).abs() < fy
                || (y as f64 * fy - (cy + ch) as f64).abs() < fy;
            let px = if (edge_x && inside_y) || (edge_y && inside_x) {
                Rgb([255, 220, 0])
            } else {
                srgb(&s.rgb, width, sx.min(width - 1), sy.min(height - 1))
            };
            canvas.put_pixel(ix + x, iy + y, px);
        }
    }
}

/// Writes the figure: one row per `(policy, extremes)`, the sharpest frame
/// on the left and the most blurred on the right; `width` x `height` is the
/// frames' size.
pub fn frames_png(
    path: &Path,
    width: u32,
    height: u32,
    rows: &[(String, &Extremes)],
) -> Result<()> {
    if rows.is_empty() {
        return Err(Error::invalid("frame figure", "no frames to show"));
    }
    for (p, e) in rows {
        for s in [&e.sharpest, &e.blurriest] {
            if s.rgb.len() != 3 * width as usize * height as usize {
                return Err(Error::invalid(
                    "frame figure",
                    format!(
                        "{p}: {} values are not a {width}x{height} RGB frame",
                        s.rgb.len()
                    ),
                ));
            }
        }
    }
    ensure_font()?;
    let cols = 2u32;
    let cell_h = LABEL_H + IMAGE_H + GUTTER;
    let (w, h) = (
        cols * (PANEL_W + GUTTER) + GUTTER,
        rows.len() as u32 * cell_h + GUTTER,
    );
    let mut canvas = RgbImage::from_pixel(w, h, Rgb([255, 255, 255]));
    let mut labels = Vec::new();
    for (r, (policy, e)) in rows.iter().enumerate() {
        for (c, (which, s)) in [("sharpest", &e.sharpest), ("most blurred", &e.blurriest)]
            .into_iter()
            .enumerate()
        {
            let x0 = GUTTER + c as u32 * (PANEL_W + GUTTER);
            let y0 = GUTTER + r as u32 * cell_h;
            // The image area's background: mid grey (the letterbox).
            for y in 0..IMAGE_H {
                for x in 0..PANEL_W {
                    canvas.put_pixel(x0 + x, y0 + LABEL_H + y, Rgb([90, 90, 90]));
                }
            }
            draw_shot(&mut canvas, s, width, height, x0, y0 + LABEL_H);
            labels.push((x0, y0, s.ok, label(policy, which, s)));
        }
    }
    {
        let e = plot_error(path);
        let root = BitMapBackend::with_buffer(canvas.as_mut(), (w, h)).into_drawing_area();
        for (x0, y0, ok, [l1, l2]) in &labels {
            let (x, y) = (*x0 as i32 + 2, *y0 as i32 + 2);
            root.draw(&Text::new(
                l1.clone(),
                (x, y),
                ("sans-serif", 17).into_font(),
            ))
            .map_err(&e)?;
            let colour = if *ok {
                RGBColor(0, 110, 0)
            } else {
                RGBColor(170, 0, 0)
            };
            root.draw(&Text::new(
                l2.clone(),
                (x, y + 21),
                ("sans-serif", 15).into_font().color(&colour),
            ))
            .map_err(&e)?;
        }
        root.present().map_err(&e)?;
    }
    save_rgb8(path, &canvas)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shot(ok: bool, matched: usize, false_alarms: usize) -> Shot {
        let (w, h) = (64u32, 48u32);
        // A dark frame with a bright square where the "board" is.
        let mut rgb = vec![0.05f32; (3 * w * h) as usize];
        for y in 20..28 {
            for x in 28..36 {
                rgb[(3 * (y * w + x)) as usize] = 0.9;
            }
        }
        Shot {
            trigger_t: 3.13579,
            blur_px: 2.25,
            blobs_matched: matched,
            blobs_expected: 16,
            blobs_false: false_alarms,
            ok,
            startup: false,
            expected_px: vec![(30.0, 22.0), (34.0, 22.0), (30.0, 26.0), (34.0, 26.0)],
            rgb,
        }
    }

    #[test]
    fn labels_name_time_blur_and_verdict() {
        let s = shot(true, 16, 0);
        let [a, b] = label("threshold:0.4", "sharpest", &s);
        assert_eq!(a, "threshold:0.4: sharpest");
        assert_eq!(b, "t = 3.14 s, blur 2.2 px, all 16 blobs found");
        assert_eq!(
            verdict(&shot(false, 11, 2)),
            "11/16 blobs found, 2 false alarms"
        );
        assert_eq!(
            verdict(&shot(false, 16, 1)),
            "16/16 blobs found, 1 false alarm"
        );
    }

    #[test]
    fn figure_has_one_row_per_policy_and_the_crop_enlarged() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("f.png");
        let mut e = Extremes::new(shot(true, 16, 0));
        e.offer(Shot {
            blur_px: 9.0,
            ..shot(false, 3, 1)
        });
        assert_eq!(e.blurriest.blobs_matched, 3);
        assert_eq!(e.sharpest.blobs_matched, 16);
        // A blurrier start-up trigger is not the most blurred pick; alone it
        // is, marked in its label.
        let early = Shot {
            blur_px: 20.0,
            trigger_t: 0.003,
            startup: true,
            ..shot(false, 1, 0)
        };
        let mut f = e.clone();
        f.offer(early.clone());
        assert_eq!(f.blurriest.blobs_matched, 3);
        let mut g = Extremes::new(early);
        assert!(label("p", "most blurred", &g.blurriest)[1].contains("(start-up trigger)"));
        g.offer(shot(true, 16, 0));
        assert_eq!(g.blurriest.blobs_matched, 16);
        frames_png(&p, 64, 48, &[("a".into(), &e), ("b".into(), &e)]).unwrap();
        let img = image::open(&p).unwrap().to_rgb8();
        assert_eq!(img.width(), 2 * (PANEL_W + GUTTER) + GUTTER);
        assert_eq!(img.height(), 2 * (LABEL_H + IMAGE_H + GUTTER) + GUTTER);
        // The crop (the whole 64 x 48 frame: the box is at least 128 px, clamped)
        // is enlarged: the bright square covers many output pixels.
        let red = img
            .pixels()
            .filter(|p| p.0[0] > 200 && p.0[1] < 100)
            .count();
        assert!(red > 4 * 64 * 2, "{red} bright pixels");
        // A frame of the wrong size is an error, and nothing is written.
        let bad = Extremes::new(Shot {
            rgb: vec![0.0; 3],
            ..shot(true, 16, 0)
        });
        let q = d.path().join("g.png");
        assert!(frames_png(&q, 64, 48, &[("a".into(), &bad)]).is_err());
        assert!(!q.exists());
    }
}
