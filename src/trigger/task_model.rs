//! The model behind `task:...`: the predicted probability that a frame is
//! sharp from its blur and its signal-to-noise ratio ([`TaskModel`]).

/// The model of the predicted task success and the light it assumes.
///
/// A frame exposed for `t_e` at an MMBM `M` (mm/s) has the predicted blur
/// `b = M t_e / p` px (`p` the pixel pitch) and, for a white pixel, `mu =
/// phi t_e` electrons and the signal-to-noise ratio `snr = mu / sqrt(mu +
/// sigma_d^2)` (shot and read noise). The predicted probability that all
/// blobs are found is the product of two logistic curves,
///
/// `P = 1 / (1 + exp((b - B50) / WB)) * 1 / (1 + exp(-(ln snr - ln S50) / WS))`,
///
/// fitted by maximum likelihood on `frames.csv` of a training run (see
/// [`TaskModel::FITTED`]). The light `phi` is **stated** in the policy
/// string (the policy does not measure it; a camera would take it from a
/// light meter or its auto-exposure's level).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaskModel {
    /// Light: electrons per second a white pixel collects, e-/s (stated).
    pub light_e_per_s: f64,
    /// Read noise, e- RMS (default 2.5, the EMVA defaults of `camera::Noise`).
    pub read_noise_e: f64,
    /// Shortest exposure considered, s (default 0.2 ms).
    pub min_exposure_s: f64,
    /// Blur at which half the frames fail, px.
    pub b50_px: f64,
    /// Width of the blur curve, px.
    pub wb_px: f64,
    /// Signal-to-noise ratio at which half the frames fail.
    pub s50: f64,
    /// Width of the SNR curve, in natural-log units.
    pub ws: f64,
}

impl TaskModel {
    /// The fitted curve `(B50 px, WB px, S50, WS)`: maximum likelihood on
    /// the 720 rendered frames (`frames.csv`: `blur_px`, `blobs_ok`, the
    /// exposure) of a training run: half board, moderate 16 s walk, seed 6
    /// (disjoint from the evaluation seeds 1-5), the demo camera and sensor
    /// at 20,000 e-/s, `fixed:5` at 70, 35, 2, 1.2, 1.05, 0.95, 0.8, 0.5 and
    /// 0.35 ms (the short exposures span the SNR, the long ones the blur).
    /// The SNR curve is a cliff (24 % of the frames sharp at SNR 3.8, 95 % at
    /// 4.0). The training frames' gain was not capped; where a camera's gain
    /// cap darkens short exposures the cliff may lie higher.
    pub const FITTED: (f64, f64, f64, f64) = (8.63, 1.54, 3.85, 0.0148);
    /// Default shortest exposure, s.
    pub const MIN_EXPOSURE: f64 = 0.0002;
    /// Exposures tried, log-spaced from the camera's down to the shortest.
    pub const STEPS: usize = 40;

    /// The model at light `light_e_per_s` with the defaults and the fitted curve.
    pub fn at_light(light_e_per_s: f64) -> Self {
        let (b50_px, wb_px, s50, ws) = Self::FITTED;
        TaskModel {
            light_e_per_s,
            read_noise_e: 2.5,
            min_exposure_s: Self::MIN_EXPOSURE,
            b50_px,
            wb_px,
            s50,
            ws,
        }
    }

    /// Signal-to-noise ratio of a white pixel exposed for `exposure_s`.
    pub fn snr(&self, exposure_s: f64) -> f64 {
        let mu = self.light_e_per_s * exposure_s;
        mu / (mu + self.read_noise_e * self.read_noise_e).sqrt()
    }

    /// Predicted probability that a frame with blur `blur_px` exposed for `exposure_s` is sharp.
    pub fn p_sharp(&self, blur_px: f64, exposure_s: f64) -> f64 {
        let pb = 1.0 / (1.0 + ((blur_px - self.b50_px) / self.wb_px).exp());
        let snr = self.snr(exposure_s).max(1e-12);
        let ps = 1.0 / (1.0 + (-(snr.ln() - self.s50.ln()) / self.ws).exp());
        pb * ps
    }

    /// The exposure (s, between the shortest and `t_max`) with the highest
    /// predicted probability at MMBM `m` (mm/s) on pixels of `pitch_mm`, and
    /// that probability (the longest of equal ones).
    pub fn best(&self, m: f64, t_max: f64, pitch_mm: f64) -> (f64, f64) {
        let t_min = self.min_exposure_s.min(t_max);
        let mut out = (t_max, -1.0);
        for k in 0..Self::STEPS {
            let te = t_max * (t_min / t_max).powf(k as f64 / (Self::STEPS - 1) as f64);
            let p = self.p_sharp(crate::camera::blur_px(m, te, pitch_mm), te);
            if p > out.1 + 1e-12 {
                out = (te, p);
            }
        }
        out
    }
}
