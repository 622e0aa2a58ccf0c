//! Gradient auto-exposure (docs/spec.md section 11, family `auto-exposure`,
//! motion-blind): the exposure that maximises the frame's summed gradient
//! magnitude after a gamma, searched over a few candidates each frame (after
//! Shim et al., TCSVT 2018, and Zhang, Forster, Scaramuzza, ICRA 2017).

use super::baselines::AeParams;
use super::policy::{LogView, Observation, Policy};
use super::rules::Fixed;
use super::timing::CameraTiming;
use crate::error::{Error, Result};

/// `ae-grad:FPS[@PHASE][:white=F][:cap=Tms][:scene=F]`. Like [`super::AutoExposure`]
/// the state is the exposure-times-gain product `P` (relative to `T_ref` at
/// the nominal gain, 1 at the start) and the frame is predicted from the
/// scene, not read: a scene whose brightest radiance is `white` (the board's
/// white, default 1) on a mean `scene` (default 0.25, the background). Its
/// summed gradient magnitude after the gamma `g(x) = x^(1/GAMMA)` is, up to
/// the edges' length (the same for every candidate),
///
/// `G(P) = g(min(1, white P)) - g(min(1, scene P))`
///
/// (clipped at the full range). After each frame, `P` moves to the candidate
/// among `P * CANDIDATES` with the largest `G` (ties: the smallest change).
/// `G` grows with `P` until the white clips, then falls as the clipped white
/// loses contrast, so the policy settles at `P = 1 / white` within a factor
/// `sqrt 2`: the exposure that fills the range with the white, brighter than
/// the mean-level auto-exposure's `target / scene`. Exposure first up to the
/// cap, then gain, as [`super::AutoExposure`]. Noise is not modelled (the
/// policy does not know the light), so it never trades gradient for noise.
pub struct GradientAe {
    inner: Fixed,
    cap_s: Option<f64>,
    scene: f64,
    white: f64,
    log_p: f64,
}

impl GradientAe {
    /// The gamma the gradient is measured after.
    pub const GAMMA: f64 = 2.2;
    /// The candidate factors on `P` tried each frame (half-stop steps, +-1 stop),
    /// in the order that breaks ties (the smallest change first).
    pub const CANDIDATES: [f64; 5] = [
        1.0,
        std::f64::consts::FRAC_1_SQRT_2,
        std::f64::consts::SQRT_2,
        0.5,
        2.0,
    ];

    /// The schedule `fps`/`phase` (s), the cap and scene of `params`, the scene's `white`.
    pub fn new(spec: &str, fps: f64, phase: f64, params: AeParams, white: f64) -> Self {
        GradientAe {
            inner: Fixed::new(spec, fps, phase),
            cap_s: params.cap_s,
            scene: params.scene_mean,
            white,
            log_p: 0.0,
        }
    }

    /// The predicted summed gradient (arbitrary unit) at product `p`.
    pub fn gradient(&self, p: f64) -> f64 {
        let g = |x: f64| x.min(1.0).powf(1.0 / Self::GAMMA);
        g(self.white * p) - g(self.scene * p)
    }
}

impl Policy for GradientAe {
    fn label(&self) -> &str {
        self.inner.label()
    }
    fn prepare(&mut self, log: &LogView, timing: &CameraTiming) -> Result<()> {
        self.log_p = 0.0;
        self.inner.prepare(log, timing)
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        let go = self.inner.decide(obs);
        if go && obs.frames > 0 {
            let p = self.log_p.exp();
            let mut best = (f64::NEG_INFINITY, 1.0);
            for f in Self::CANDIDATES {
                let g = self.gradient(p * f);
                if g > best.0 + 1e-12 {
                    best = (g, f);
                }
            }
            self.log_p += best.1.ln();
        }
        go
    }
    fn exposure(&self, obs: &Observation) -> (f64, f64) {
        let t_ref = obs.timing.exposure;
        let p = self.log_p.exp();
        let te = (p * t_ref).min(self.cap_s.unwrap_or(t_ref)).min(t_ref);
        (te, p * t_ref / te)
    }
}

/// The `white=F` key of `ae-grad`, in (0, 1] and above the scene's mean.
pub(crate) fn parse_white(own: &[(&str, &str)], scene: f64, spec: &str) -> Result<f64> {
    let mut white = super::gyro_ae::AeVariant::WHITE;
    for &(_, v) in own {
        white = super::numbers::parse_pos(v, "white radiance", spec)?;
    }
    if white > 1.0 || white <= scene {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': white must be in (scene, 1] = ({scene}, 1], got {white}"),
        ));
    }
    Ok(white)
}

#[cfg(test)]
mod tests {
    use crate::trigger::{CameraTiming, PolicySpec};

    fn run(spec: &str) -> Vec<crate::trigger::Frame> {
        let t: Vec<f64> = (0..=6000).map(|k| k as f64 / 600.0).collect();
        let m = vec![0.5; t.len()];
        let mut p = PolicySpec::parse(spec).unwrap().build().unwrap();
        crate::trigger::run(&t, &m, p.as_mut(), &CameraTiming::default()).unwrap()
    }

    #[test]
    fn gradient_by_hand() {
        let g = |x: f64| x.powf(1.0 / 2.2);
        // white 0.5, scene 0.25, from P = 1: G(2) = 1 - g(0.5) = 0.2703 beats
        // G(sqrt 2) = g(0.707) - g(0.354) = 0.2306 and G(1) = 0.1972; at
        // P = 2, G(2 sqrt 2) = 1 - g(0.707) = 0.146: it stays at 2.
        assert!((1.0 - g(0.5)) > g(0.5f64.sqrt()) - g(0.25 * 2f64.sqrt()));
        let f = run("ae-grad:5:white=0.5:cap=10ms");
        assert!((f[0].exposure_s() - 0.01).abs() < 1e-12 && (f[0].gain - 7.0).abs() < 1e-9);
        for x in &f[1..] {
            assert!((x.exposure_s() - 0.01).abs() < 1e-12);
            assert!((x.gain - 14.0).abs() < 1e-9, "{}", x.gain);
        }
        // The board's white (1.0): P = 1 is the best, the camera's nominal
        // brightness (70 ms, gain 1); the motion does not matter.
        assert!(run("ae-grad:5")
            .iter()
            .all(|x| (x.exposure_s() - 0.07).abs() < 1e-12 && (x.gain - 1.0).abs() < 1e-12));
    }
}
