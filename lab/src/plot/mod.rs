//! Figures with plotters (bitmap backend): the shared font and error
//! plumbing here, flow-field quivers in [`quiver`]. Labels use the bundled
//! DejaVu Sans (`assets/DejaVuSans.ttf`, licence beside it), registered once
//! per process. Figures of a feature live with it (`tables`, `experiment`).

pub mod quiver;

use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

static FONT: &[u8] = include_bytes!("../../../assets/DejaVuSans.ttf");

/// Registers the bundled font as plotters' `sans-serif` (once per process).
pub fn ensure_font() -> Result<()> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::invalid(
            "font",
            "the bundled DejaVuSans.ttf could not be loaded",
        ))
    }
}

/// Turns a plotters error into ours, naming the file.
pub fn plot_error<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::Image {
        path: path.into(),
        message: format!("plot: {e}"),
    }
}

/// Relative luminance of an sRGB colour, 0 (black) .. 1 (white), with the
/// Rec. 709 weights on the 8-bit channels (no linearisation: a threshold
/// test, not a colorimetric value).
pub fn luminance(c: RGBColor) -> f64 {
    (0.2126 * f64::from(c.0) + 0.7152 * f64::from(c.1) + 0.0722 * f64::from(c.2)) / 255.0
}

/// The text colour that reads on background `bg`: white on dark (luminance
/// below 0.5), black on light.
pub fn text_on(bg: RGBColor) -> RGBColor {
    if luminance(bg) < 0.5 {
        WHITE
    } else {
        BLACK
    }
}

/// A ratio's colour on the diverging scale of the heat maps: `log2(r)`
/// clamped to [-1, 1] (0.5x .. 2x), red below 1, white at 1, blue above;
/// grey for an undefined ratio.
pub fn ratio_colour(r: f64) -> RGBColor {
    if !(r.is_finite() && r > 0.0) {
        return RGBColor(200, 200, 200);
    }
    let t = r.log2().clamp(-1.0, 1.0);
    if t >= 0.0 {
        let v = (255.0 * (1.0 - t)) as u8;
        RGBColor(v, v, 255)
    } else {
        let v = (255.0 * (1.0 + t)) as u8;
        RGBColor(255, v, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_reads_on_every_scale_colour() {
        // Saturated red and blue (the scale's ends) are dark: white text;
        // the scale's middle (white) and the grey of n/a: black text.
        assert_eq!(text_on(ratio_colour(0.25)), WHITE);
        assert_eq!(text_on(ratio_colour(4.0)), WHITE);
        assert_eq!(text_on(ratio_colour(1.0)), BLACK);
        assert_eq!(text_on(ratio_colour(f64::NAN)), BLACK);
        // The contrast rule holds over the whole scale.
        for k in 0..=40 {
            let c = ratio_colour(2f64.powf(-1.0 + k as f64 / 20.0));
            let l = luminance(c);
            let t = luminance(text_on(c));
            assert!((l - t).abs() >= 0.5, "{c:?}");
        }
    }
}
