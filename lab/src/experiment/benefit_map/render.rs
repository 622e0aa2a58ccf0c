//! The benefit map's renders: each frame rendered once without noise, then
//! judged (blob extraction) at every light level with the sensor noise of
//! that light and the gain a camera would set there (docs/spec.md section 10).

use super::super::corners;
use super::super::matches::{self, Features};
use super::super::measure::{blob_metrics, bulk_job, frame_motion};
use super::super::walk::Walk;
use crate::camera::{Camera, Noise};
use crate::error::Result;
use crate::io::images::dn_to_rgb8;
use crate::render::{self, Background, Quality, Target, Window};
use crate::trigger::Frame;

/// The window judged at each light: the blob grid padded by this many blob pitches.
pub const WINDOW_PITCHES: f64 = 3.0;

/// The camera's gain at one light level (docs/spec.md section 10).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// The sensor at this light (its `gain_dn_per_e` is the reference gain `K_ref`).
    pub noise: Noise,
    /// The reference exposure `T_ref`, s (white fills the range there).
    pub t_ref_s: f64,
    /// The sensor's maximum gain, DN/e-.
    pub max_gain_dn_per_e: f64,
}

impl Light {
    /// The sensor `base` (read noise, full well, bits, seed) at `phi` e-/s,
    /// with `K_ref = (2^bits - 1) / (phi T_ref)` capped at `max_gain_x` times
    /// the full-well gain `(2^bits - 1) / full_well`.
    pub fn new(base: &Noise, phi: f64, t_ref_s: f64, max_gain_x: f64) -> Self {
        let mut noise = Noise {
            phi_e_per_s: phi,
            gain_dn_per_e: None,
            ..*base
        };
        let max_gain = max_gain_x * noise.max_dn() / noise.full_well_e;
        noise.gain_dn_per_e = Some((noise.max_dn() / (phi * t_ref_s)).min(max_gain));
        Light {
            noise,
            t_ref_s,
            max_gain_dn_per_e: max_gain,
        }
    }

    /// The sensor for a frame whose policy raised the gain by `relative`:
    /// `K_ref * relative`, capped at the maximum gain.
    pub fn for_gain(&self, relative: f64) -> Noise {
        Noise {
            gain_dn_per_e: Some((self.noise.gain() * relative).min(self.max_gain_dn_per_e)),
            ..self.noise
        }
    }

    /// True when the cap binds for a relative gain (the frame is darker than intended).
    pub fn capped(&self, relative: f64) -> bool {
        self.noise.gain() * relative > self.max_gain_dn_per_e * (1.0 + 1e-12)
    }
}

/// What a frame gave at one light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Judged {
    /// All 16 blobs extracted at their true places (and no other).
    pub ok: bool,
    /// Blobs found away from every board place.
    pub false_alarms: usize,
    /// Corner repeatability in the window ([`super::corners`]); NaN without corners.
    pub corner_rep: f64,
}

/// How the map renders a frame for its lights.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Renders {
    /// The judged window only, once for all lights (the frame and its sharp
    /// reference: [`render::render_window`]); what the map runs.
    #[default]
    Shared,
    /// The whole frame and the whole sharp reference, again for each light,
    /// the window cut from them: the reference [`Renders::Shared`] must equal
    /// number for number (tests).
    PerLight,
}

/// What the matches between consecutive kept frames need of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameFeatures {
    /// The board's blob centres at mid-exposure, full-frame px (None off the image).
    pub board_px: Vec<Option<(f64, f64)>>,
    /// The described corners of the frame at each light (full-frame px).
    pub per_light: Vec<Features>,
}

/// Renders `frame` of `walk` on `target` (`blobs` or `blobs:0.5`, with
/// `surround` behind it) with the noiseless camera `cam` and returns,
/// for each of `lights`, the blob verdict, the false alarms and the corner
/// repeatability against the sharp frame at mid-exposure (noiseless, the
/// same window). `seed` seeds the render's sampling lattice and the noise
/// (RNG stream `seed * 64 + light index`). `renders` says whether the
/// lights share one render of the window ([`Renders::Shared`]) or each
/// renders the whole frame ([`Renders::PerLight`]); the numbers are the same.
/// With them, the frame's described corners at each light and the board's
/// blob centres ([`FrameFeatures`]) for the matches to the next kept frame.
#[allow(clippy::too_many_arguments)]
pub fn judge_at_lights(
    target: &str,
    surround: Background,
    walk: &Walk,
    frame: &Frame,
    cam: Camera,
    quality: Quality,
    seed: u32,
    lights: &[Light],
    renders: Renders,
) -> Result<(Vec<Judged>, FrameFeatures)> {
    let cam = Camera { noise: None, ..cam };
    let exposure = frame.exposure_s();
    let (distance, traj) = frame_motion(walk, frame, &cam)?;
    let mut target = Target::parse(target, distance)?;
    target.surround = surround;
    let mut job = bulk_job(cam, exposure, &traj, &target, quality, seed);
    job.with_maps = false;
    // True blob centres at mid-exposure, as the experiment's measure.
    let mid = traj.pose_at(0.5 * cam.shutter.busy_s(exposure));
    let board_px: Vec<Option<(f64, f64)>> = target
        .blob_centres()
        .unwrap_or_default()
        .iter()
        .map(|&p| render::project(&cam, &mid, p))
        .collect();
    let expected: Vec<(f64, f64)> = board_px.iter().flatten().copied().collect();
    // Noise, extraction and corners on a window around the board (the blob
    // grid padded by WINDOW_PITCHES pitches), not the whole frame.
    let win = judged_window(&cam, &expected);
    // The instants are spaced for the window's own image paths (the
    // renderer's rule, applied to the pixels judged).
    job.spacing_window = Some(win);
    let still = corners::still_at(&job, mid)?;
    // The noiseless frame and its sharp reference in the window: rendered
    // once (shared) or for each light from the whole frame.
    let whole = |j: &render::RenderJob| -> Result<Vec<f32>> {
        Ok(win.cut(cam.width, &render::render_frame(j)?.rgb))
    };
    let shared = match renders {
        Renders::Shared => {
            let sharp = render::render_window(&still, win)?;
            Some((
                render::render_window(&job, win)?,
                corners::corners(&corners::luma(win.w, win.h, &sharp)?),
            ))
        }
        Renders::PerLight => None,
    };
    let (cw, ch) = (win.w, win.h);
    let shifted: Vec<(f64, f64)> = expected
        .iter()
        .map(|&(x, y)| (x - f64::from(win.x0), y - f64::from(win.y0)))
        .collect();
    let mut ok = Vec::with_capacity(lights.len());
    let mut per_light = Vec::with_capacity(lights.len());
    for (k, light) in lights.iter().enumerate() {
        let own;
        let (rgb, sharp_corners) = match &shared {
            Some((window, sharp_corners)) => (std::borrow::Cow::Borrowed(window), sharp_corners),
            None => {
                own = corners::corners(&corners::luma(cw, ch, &whole(&still)?)?);
                (std::borrow::Cow::Owned(whole(&job)?), &own)
            }
        };
        // The noisy frame's codes, to 8-bit sRGB through a table: the bytes
        // `to_rgb8` gives the noisy linear frame (`Noise::apply`).
        let sensor = light.for_gain(frame.gain);
        let dn = sensor.apply_dn(&rgb, exposure, u64::from(seed) * 64 + k as u64)?;
        let img = dn_to_rgb8(cw, ch, &dn, sensor.max_dn() as u16)?;
        let b = blob_metrics(&img, &shifted);
        let gray = crate::assess::luma(&img);
        let found = corners::corners(&gray);
        per_light.push(matches::features(
            &gray,
            &found,
            (f64::from(win.x0), f64::from(win.y0)),
        )?);
        ok.push(Judged {
            ok: b.ok,
            false_alarms: b.false_alarms,
            corner_rep: corners::repeatability_strongest(sharp_corners, &found).unwrap_or(f64::NAN),
        });
    }
    Ok((
        ok,
        FrameFeatures {
            board_px,
            per_light,
        },
    ))
}

/// The window judged around the board: the projected blob centres
/// `expected` (px) padded by [`WINDOW_PITCHES`] blob pitches, inside the
/// image; the whole image when no centre projects.
pub fn judged_window(cam: &Camera, expected: &[(f64, f64)]) -> Window {
    let (w, h) = (cam.width as usize, cam.height as usize);
    if expected.is_empty() {
        return Window {
            x0: 0,
            y0: 0,
            w: cam.width,
            h: cam.height,
        };
    }
    let pad = WINDOW_PITCHES * super::super::crop::pitch_px(expected);
    let lo = |v: f64| (v - pad).floor().max(0.0) as usize;
    let (xs, ys) = (expected.iter().map(|p| p.0), expected.iter().map(|p| p.1));
    let x0 = lo(xs.clone().fold(f64::INFINITY, f64::min)).min(w - 1);
    let y0 = lo(ys.clone().fold(f64::INFINITY, f64::min)).min(h - 1);
    let x1 =
        ((xs.fold(f64::NEG_INFINITY, f64::max) + pad).ceil().max(0.0) as usize).clamp(x0 + 1, w);
    let y1 =
        ((ys.fold(f64::NEG_INFINITY, f64::max) + pad).ceil().max(0.0) as usize).clamp(y0 + 1, h);
    Window {
        x0: x0 as u32,
        y0: y0 as u32,
        w: (x1 - x0) as u32,
        h: (y1 - y0) as u32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_gain_fills_the_range_and_is_capped() {
        let base = Noise::at_light(1.0);
        // 20,000 e-/s: 1,400 e- of white in 70 ms fill 255 DN.
        let l = Light::new(&base, 20_000.0, 0.07, 256.0);
        assert!((l.noise.gain() * 1400.0 - 255.0).abs() < 1e-9);
        // The maximum: 256 x 255 / 10,000 DN/e-.
        assert!((l.max_gain_dn_per_e - 6.528).abs() < 1e-12);
        // 3 ms at 23.3x the gain is below the cap; 1 ms at 70x is not.
        assert!(!l.capped(0.07 / 0.003) && l.capped(70.0));
        assert!((l.for_gain(1e6).gain() - 6.528).abs() < 1e-12);
        // 500 e-/s: even the reference gain (7.3 DN/e-) is above the cap.
        let dim = Light::new(&base, 500.0, 0.07, 256.0);
        assert!((dim.noise.gain() - 6.528).abs() < 1e-12 && dim.capped(1.0 + 1e-6));
    }
}
