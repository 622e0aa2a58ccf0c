//! Quiver plots of a flow field (like thesis Figs. 3.3, 3.6, 3.7): arrows on a
//! downsampled grid of pixels, each the image displacement over an exposure
//! (px, optionally magnified by a stated factor), coloured by speed (px/s).

use crate::camera::Camera;
use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;

/// Arrows per row of the quiver plot (rows follow the sensor's aspect ratio).
pub const ARROWS_PER_ROW: u32 = 20;

/// Viridis-like colour map, `t` in `[0, 1]`.
pub fn colormap(t: f64) -> RGBColor {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.00, [68.0, 1.0, 84.0]),
        (0.25, [59.0, 82.0, 139.0]),
        (0.50, [33.0, 145.0, 140.0]),
        (0.75, [94.0, 201.0, 98.0]),
        (1.00, [253.0, 231.0, 37.0]),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let k = STOPS.iter().position(|s| s.0 >= t).unwrap_or(4).max(1);
    let (t0, c0) = STOPS[k - 1];
    let (t1, c1) = STOPS[k];
    let a = (t - t0) / (t1 - t0);
    let mix = |i: usize| (c0[i] + a * (c1[i] - c0[i])).round() as u8;
    RGBColor(mix(0), mix(1), mix(2))
}

/// The largest 1-2-5 factor (`..., 0.5, 1, 2, 5, 10, ...`) not above `x` (`x > 0`).
pub fn nice_factor_below(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let e = x.log10().floor();
    let base = 10f64.powf(e);
    let m = x / base;
    let step = if m >= 5.0 {
        5.0
    } else if m >= 2.0 {
        2.0
    } else {
        1.0
    };
    step * base
}

/// One arrow: start pixel position `(x, y)` and displacement `(dx, dy)` in px
/// (already scaled), plus the speed (px/s) it is coloured by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arrow {
    /// Start, px (pixel-centre coordinates).
    pub x: f64,
    /// Start, px.
    pub y: f64,
    /// Displacement, px.
    pub dx: f64,
    /// Displacement, px.
    pub dy: f64,
    /// Speed, px/s.
    pub speed: f64,
}

/// The arrows of a quiver plot and their magnification: flow (px/s) at the
/// centres of an `ARROWS_PER_ROW`-wide grid of blocks (none where the field
/// is NaN: masked beyond the lens's radial distortion limit), times the exposure
/// (s), times the largest 1-2-5 factor that keeps the longest arrow within
/// 0.9 of the arrow spacing (1 when the field is zero).
pub fn arrows(camera: &Camera, u: &[f32], v: &[f32], exposure_s: f64) -> Result<(Vec<Arrow>, f64)> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    if u.len() != w * h || v.len() != w * h {
        return Err(Error::invalid(
            "quiver field",
            format!(
                "{} and {} values for a {w}x{h} sensor (need {} each)",
                u.len(),
                v.len(),
                w * h
            ),
        ));
    }
    crate::check::positive("exposure (s)", exposure_s)?;
    let nx = ARROWS_PER_ROW.min(camera.width).max(1);
    let ny = ((nx as f64 * h as f64 / w as f64).round() as u32).clamp(1, camera.height);
    let spacing = (w as f64 / nx as f64).min(h as f64 / ny as f64);
    let mut out = Vec::with_capacity((nx * ny) as usize);
    for j in 0..ny {
        for i in 0..nx {
            let px = (((i as f64 + 0.5) * w as f64 / nx as f64) as usize).min(w - 1);
            let py = (((j as f64 + 0.5) * h as f64 / ny as f64) as usize).min(h - 1);
            let (a, b) = (u[py * w + px] as f64, v[py * w + px] as f64);
            if a.is_nan() && b.is_nan() {
                // Masked (beyond the lens's radial distortion limit): no arrow.
                continue;
            }
            if !(a.is_finite() && b.is_finite()) {
                return Err(Error::invalid(
                    "quiver field",
                    format!("non-finite flow at pixel ({px}, {py})"),
                ));
            }
            out.push(Arrow {
                x: px as f64 + 0.5,
                y: py as f64 + 0.5,
                dx: a * exposure_s,
                dy: b * exposure_s,
                speed: a.hypot(b),
            });
        }
    }
    let longest = out.iter().map(|a| a.dx.hypot(a.dy)).fold(0.0, f64::max);
    let mag = if longest > 0.0 {
        nice_factor_below(0.9 * spacing / longest)
    } else {
        1.0
    };
    for a in &mut out {
        a.dx *= mag;
        a.dy *= mag;
    }
    Ok((out, mag))
}

fn plot_err(path: &Path) -> impl Fn(String) -> Error + '_ {
    move |m| Error::Image {
        path: path.into(),
        message: format!("plotting: {m}"),
    }
}

/// Writes a quiver PNG of a sensor-resolution field (`u`, `v` in px/s,
/// row-major, `camera.width x camera.height`): arrows are the displacement over
/// `exposure_s` seconds (times the magnification stated in the title), coloured
/// by speed with a colour bar. Written atomically.
pub fn quiver_png(
    camera: &Camera,
    field_u: &[f32],
    field_v: &[f32],
    exposure_s: f64,
    path: &Path,
) -> Result<()> {
    let (arrows, mag) = arrows(camera, field_u, field_v, exposure_s)?;
    crate::plot::ensure_font()?;
    // The mean over the samples with a flow (masked ones are NaN).
    let speeds = || {
        field_u
            .iter()
            .zip(field_v)
            .map(|(a, b)| (*a as f64).hypot(*b as f64))
            .filter(|s| !s.is_nan())
    };
    let mean = speeds().sum::<f64>() / speeds().count().max(1) as f64;
    let vmax = arrows.iter().map(|a| a.speed).fold(0.0, f64::max);
    let (w, h) = (camera.width as f64, camera.height as f64);
    // Arrows start at block centres and are at most 0.9 spacing long.
    let pad = 0.5 * w / ARROWS_PER_ROW.min(camera.width) as f64;
    let plot_w = 760u32;
    let plot_h = ((plot_w as f64 * h / w).round() as u32).clamp(120, 1400);
    let (cw, ch) = (plot_w + 200, plot_h + 130);
    let mut buf = vec![255u8; (cw * ch * 3) as usize];
    let err = plot_err(path);
    {
        let root = BitMapBackend::with_buffer(&mut buf, (cw, ch)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let (main, bar) = root.split_horizontally(plot_w + 80);
        let title = format!(
            "flow over a {:.0} ms exposure, arrows x{mag}; mean speed {mean:.1} px/s ({:.2} px)",
            exposure_s * 1e3,
            mean * exposure_s
        );
        let mut chart = ChartBuilder::on(&main)
            .caption(title, ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(-pad..w + pad, h + pad..-pad)
            .map_err(|e| err(e.to_string()))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| format!("{y:.0}"))
            .x_desc("column (px)")
            .y_desc("row (px)")
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(|e| err(e.to_string()))?;
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(0.0, 0.0), (w, h)],
                ShapeStyle::from(&BLACK.mix(0.4)).stroke_width(1),
            )))
            .map_err(|e| err(e.to_string()))?;
        let scale = if vmax > 0.0 { vmax } else { 1.0 };
        let head = 0.25 * (w / ARROWS_PER_ROW as f64);
        for a in &arrows {
            let col = colormap(a.speed / scale);
            let style = ShapeStyle::from(&col).stroke_width(2);
            let len = a.dx.hypot(a.dy);
            let (x1, y1) = (a.x + a.dx, a.y + a.dy);
            chart
                .draw_series(std::iter::once(Circle::new((a.x, a.y), 2, col.filled())))
                .map_err(|e| err(e.to_string()))?;
            if len <= 1e-9 {
                continue;
            }
            let (ux, uy) = (a.dx / len, a.dy / len);
            let hl = (0.35 * len).min(head);
            let left = (x1 - hl * (ux + 0.5 * uy), y1 - hl * (uy - 0.5 * ux));
            let right = (x1 - hl * (ux - 0.5 * uy), y1 - hl * (uy + 0.5 * ux));
            chart
                .draw_series([
                    PathElement::new(vec![(a.x, a.y), (x1, y1)], style),
                    PathElement::new(vec![left, (x1, y1), right], style),
                ])
                .map_err(|e| err(e.to_string()))?;
        }
        // Colour bar: speed in px/s.
        let (bx, by0, by1) = (20i32, 50i32, 40 + plot_h as i32);
        let steps = 100;
        for k in 0..steps {
            let t = 1.0 - k as f64 / steps as f64;
            let y = by0 + (k * (by1 - by0)) / steps;
            let y2 = by0 + ((k + 1) * (by1 - by0)) / steps;
            bar.draw(&Rectangle::new(
                [(bx, y), (bx + 20, y2)],
                colormap(t).filled(),
            ))
            .map_err(|e| err(e.to_string()))?;
        }
        let font = ("sans-serif", 13).into_font();
        for k in 0..=4 {
            let t = k as f64 / 4.0;
            let y = by1 - ((by1 - by0) as f64 * t) as i32;
            bar.draw(&Text::new(
                format!("{:.1}", vmax * t),
                (bx + 26, y - 6),
                font.clone(),
            ))
            .map_err(|e| err(e.to_string()))?;
        }
        bar.draw(&Text::new("speed (px/s)", (bx - 5, by0 - 25), font))
            .map_err(|e| err(e.to_string()))?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    let img =
        image::RgbImage::from_raw(cw, ch, buf).ok_or_else(|| err("bitmap size mismatch".into()))?;
    crate::io::images::save_rgb8(path, &img)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factors_and_colours() {
        assert_eq!(nice_factor_below(7.3), 5.0);
        assert_eq!(nice_factor_below(0.31), 0.2);
        assert_eq!(nice_factor_below(1.0), 1.0);
        assert_eq!(nice_factor_below(19.9), 10.0);
        assert_eq!(colormap(0.0), RGBColor(68, 1, 84));
        assert_eq!(colormap(1.0), RGBColor(253, 231, 37));
    }

    #[test]
    fn arrows_scale_with_exposure_and_fit_spacing() {
        let cam = Camera::thesis().with_resolution(40, 30);
        let n = 40 * 30;
        let u = vec![100.0f32; n];
        let v = vec![-50.0f32; n];
        let (a, m) = arrows(&cam, &u, &v, 0.07).unwrap();
        assert_eq!(a.len(), 20 * 15);
        // Displacement 7 x -3.5 px, spacing 2 px: 0.9*2/7.83 = 0.23 -> 0.2.
        assert_eq!(m, 0.2);
        assert!((a[0].dx - 100.0 * 0.07 * 0.2).abs() < 1e-9);
        assert!((a[0].dy + 50.0 * 0.07 * 0.2).abs() < 1e-9);
        assert!(arrows(&cam, &u[1..], &v, 0.07).is_err());
        assert!(arrows(&cam, &u, &v, 0.0).is_err());
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("q.png");
        quiver_png(&cam, &u, &v, 0.07, &p).unwrap();
        let img = crate::io::images::read_rgb8(&p).unwrap();
        assert!(img.width() > 700);
    }
}
