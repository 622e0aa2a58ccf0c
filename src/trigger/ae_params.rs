//! What the auto-exposure policies are parsed into: the auto-exposure's
//! parameters ([`AeParams`]) and what an `ae-*` policy adds ([`AeVariant`]).

/// Auto-exposure parameters (`ae:FPS[:cap=Tms][:target=F][:damp=F][:scene=F]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AeParams {
    /// Longest exposure the auto-exposure may choose, s (default: the camera's).
    pub cap_s: Option<f64>,
    /// Target mean level, fraction of the output range (default 0.18, "18 % grey").
    pub target: f64,
    /// Damping: the share of the (logarithmic) error corrected per frame, in (0, 1] (default 0.5).
    pub damping: f64,
    /// The scene's mean linear radiance (0..1) that predicts a frame's mean
    /// level (default 0.25, the renderer's background grey, which fills
    /// about 99 % of the frame behind the board).
    pub scene_mean: f64,
}

impl AeParams {
    /// Default target mean level (18 % grey).
    pub const TARGET: f64 = 0.18;
    /// Default damping.
    pub const DAMPING: f64 = 0.5;
    /// Default scene mean radiance: the renderer's background grey
    /// (`render::target::DEFAULT_BACKGROUND`; the experiment's tests check they agree).
    pub const SCENE_MEAN: f64 = 0.25;
}

impl Default for AeParams {
    fn default() -> Self {
        AeParams {
            cap_s: None,
            target: Self::TARGET,
            damping: Self::DAMPING,
            scene_mean: Self::SCENE_MEAN,
        }
    }
}

/// How an `ae-*` policy differs from the plain `ae:` auto-exposure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AeVariant {
    /// `ae-blur`: the exposure capped at a blur budget, px.
    BlurCap {
        /// The predicted blur an exposure may reach, px.
        budget_px: f64,
    },
    /// `ae-imu`: `K = sqrt((v c + w0) / w)`.
    ImuTrade {
        /// `w`: what one unit of relative gain costs, in px of blur.
        weight_px: f64,
        /// `w0`: a constant added to `v c`, px.
        offset_px: f64,
    },
    /// `ae-grad`: the product among candidates that maximises the predicted
    /// summed gradient (see `GradientAe`).
    Gradient {
        /// The scene's brightest linear radiance (0..1], the board's white.
        white: f64,
    },
}

impl AeVariant {
    /// Default `w` of `ae-imu`, px per unit of relative gain.
    pub const IMU_WEIGHT_PX: f64 = 0.1;
    /// Default `w0` of `ae-imu`, px.
    pub const IMU_OFFSET_PX: f64 = 0.0;
    /// Default `white` of `ae-grad`: the renderer's board white (1.0).
    pub const WHITE: f64 = 1.0;

    /// True for the variants that read the gyro (`ae-blur`, `ae-imu`).
    pub fn reads_gyro(&self) -> bool {
        !matches!(self, AeVariant::Gradient { .. })
    }
}
