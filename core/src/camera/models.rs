//! Gyroflow's optical distortion model names (`distortion_model`), the
//! form in which a digital lens keeps the optical model under its warp
//! (`Distortion::Digital`) and the lens profile loader names them.

use serde::{Deserialize, Serialize};

/// An optical distortion model, by Gyroflow's name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Model {
    /// The ideal pinhole.
    None,
    /// `opencv_standard` (12 coefficients; its first five are Brown-Conrady's).
    OpencvStandard,
    /// `opencv_fisheye` (4 coefficients).
    OpencvFisheye,
    /// `poly3` (1 coefficient).
    Poly3,
    /// `poly5` (2 coefficients).
    Poly5,
    /// `ptlens` (3 coefficients).
    Ptlens,
    /// `sony` (6 coefficients).
    Sony,
    /// `generic_polynomial` (12 coefficients).
    GenericPolynomial,
    /// `insta360` (6 coefficients).
    Insta360,
}

/// Every model with a Gyroflow name.
pub const GYROFLOW_MODELS: [Model; 8] = [
    Model::OpencvFisheye,
    Model::OpencvStandard,
    Model::Poly3,
    Model::Poly5,
    Model::Ptlens,
    Model::Sony,
    Model::GenericPolynomial,
    Model::Insta360,
];

impl Model {
    /// Gyroflow's name (`none` for the pinhole).
    pub fn name(self) -> &'static str {
        match self {
            Model::None => "none",
            Model::OpencvStandard => "opencv_standard",
            Model::OpencvFisheye => "opencv_fisheye",
            Model::Poly3 => "poly3",
            Model::Poly5 => "poly5",
            Model::Ptlens => "ptlens",
            Model::Sony => "sony",
            Model::GenericPolynomial => "generic_polynomial",
            Model::Insta360 => "insta360",
        }
    }

    /// The number of coefficients Gyroflow reads for the model.
    pub fn count(self) -> usize {
        match self {
            Model::None => 0,
            Model::Poly3 => 1,
            Model::Poly5 => 2,
            Model::Ptlens => 3,
            Model::OpencvFisheye => 4,
            Model::Sony | Model::Insta360 => 6,
            Model::OpencvStandard | Model::GenericPolynomial => 12,
        }
    }

    /// The model of a Gyroflow name.
    pub fn from_name(s: &str) -> Option<Self> {
        GYROFLOW_MODELS.into_iter().find(|m| m.name() == s)
    }
}
