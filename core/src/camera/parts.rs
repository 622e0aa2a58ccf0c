//! A distortion as Gyroflow names it: its model and coefficients in
//! Gyroflow's order (`distortion_coeffs`), both ways, and the model's name.

use super::distortion::Distortion;
use super::models::Model;

impl Distortion {
    /// The model with Gyroflow's `distortion_coeffs` `k` (zeros past the
    /// model's count; `opencv_standard` with zeros past `k3` is
    /// [`Distortion::Opencv`]).
    pub fn from_model(model: Model, k: [f64; 12]) -> Self {
        let six = [k[0], k[1], k[2], k[3], k[4], k[5]];
        match model {
            Model::None => Distortion::None,
            Model::OpencvStandard => Distortion::opencv_standard(k),
            Model::OpencvFisheye => Distortion::Fisheye {
                k1: k[0],
                k2: k[1],
                k3: k[2],
                k4: k[3],
            },
            Model::Poly3 => Distortion::Poly3 { k1: k[0] },
            Model::Poly5 => Distortion::Poly5 { k1: k[0], k2: k[1] },
            Model::Ptlens => Distortion::Ptlens {
                a: k[0],
                b: k[1],
                c: k[2],
            },
            Model::Sony => Distortion::Sony { k: six },
            Model::GenericPolynomial => Distortion::GenericPolynomial { k },
            Model::Insta360 => Distortion::Insta360 { k: six },
        }
    }

    /// The optical model and its coefficients in Gyroflow's order (for
    /// [`Distortion::Digital`], those of the model under the warp).
    pub fn parts(&self) -> (Model, [f64; 12]) {
        let mut out = [0.0; 12];
        let mut put = |c: &[f64]| out[..c.len()].copy_from_slice(c);
        let m = match *self {
            Distortion::None => Model::None,
            Distortion::Opencv { k1, k2, p1, p2, k3 } => {
                put(&[k1, k2, p1, p2, k3]);
                Model::OpencvStandard
            }
            Distortion::OpencvStandard { k } => {
                put(&k);
                Model::OpencvStandard
            }
            Distortion::Fisheye { k1, k2, k3, k4 } => {
                put(&[k1, k2, k3, k4]);
                Model::OpencvFisheye
            }
            Distortion::Poly3 { k1 } => {
                put(&[k1]);
                Model::Poly3
            }
            Distortion::Poly5 { k1, k2 } => {
                put(&[k1, k2]);
                Model::Poly5
            }
            Distortion::Ptlens { a, b, c } => {
                put(&[a, b, c]);
                Model::Ptlens
            }
            Distortion::Sony { k } => {
                put(&k);
                Model::Sony
            }
            Distortion::GenericPolynomial { k } => {
                put(&k);
                Model::GenericPolynomial
            }
            Distortion::Insta360 { k } => {
                put(&k);
                Model::Insta360
            }
            Distortion::Digital { optical, k, .. } => {
                put(&k);
                optical
            }
        };
        (m, out)
    }

    /// The optical model (under the warp for [`Distortion::Digital`], else itself).
    pub fn optical(&self) -> Self {
        match *self {
            Distortion::Digital { optical, k, .. } => Distortion::from_model(optical, k),
            d => d,
        }
    }

    /// The model's name as Gyroflow says it (`gopro_superview over
    /// opencv_fisheye` for a digital lens; `opencv` for the five-coefficient model).
    pub fn name(&self) -> String {
        match *self {
            Distortion::Opencv { .. } => "opencv".into(),
            Distortion::Digital { warp, optical, .. } => {
                format!("{} over {}", warp.lens.name(), optical.name())
            }
            d => d.parts().0.name().into(),
        }
    }
}

/// One distortion of each model (the unit tests of `distortion.rs` and this file).
#[cfg(test)]
pub(crate) fn samples() -> Vec<Distortion> {
    use crate::camera::digital::{Lens, Warp};
    {
        vec![
            Distortion::WIDE_ANGLE,
            Distortion::opencv_standard([
                0.1, 0.0, 0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.01,
            ]),
            Distortion::Fisheye {
                k1: 0.031,
                k2: 0.06,
                k3: -0.05,
                k4: 0.012,
            },
            Distortion::Poly3 { k1: -0.08 },
            Distortion::Poly5 { k1: -0.1, k2: 0.02 },
            Distortion::Ptlens {
                a: 0.01,
                b: -0.04,
                c: -0.03,
            },
            Distortion::Sony {
                k: [0.97, 0.02, -0.05, 0.01, -0.003, 0.0002],
            },
            Distortion::GenericPolynomial {
                k: [
                    1.0, 0.0, -0.04, 0.0, 0.003, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1e-5,
                ],
            },
            Distortion::Insta360 {
                k: [-0.03, 0.004, -0.0003, 0.0005, -0.0004, 0.3],
            },
            Distortion::Digital {
                warp: Warp {
                    lens: Lens::GoproSuperview,
                    params: [0.0; 16],
                    frame: [0.3, 0.5, 0.01, -0.02],
                },
                optical: Model::OpencvFisheye,
                k: [0.03, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn models() -> Vec<Distortion> {
        samples()
    }

    #[test]
    fn parts_rebuild_the_model_and_names_are_gyroflows() {
        for d in models() {
            if let Distortion::Digital { .. } = d {
                assert_eq!(d.name(), "gopro_superview over opencv_fisheye");
                continue;
            }
            let (m, k) = d.parts();
            assert_eq!(Distortion::from_model(m, k), d, "{d:?}");
            assert_eq!(Model::from_name(m.name()), Some(m));
        }
        // The radial limit of a barrel poly3: rd = r - 0.08 r^3 turns at r = 1/sqrt(0.24).
        let r = 1.0 / 0.24f64.sqrt();
        let want = r - 0.08 * r * r * r;
        let got = Distortion::Poly3 { k1: -0.08 }.radial_limit();
        assert!((got - want).abs() < 1e-9, "{got} vs {want}");
        assert_eq!(Distortion::Poly3 { k1: 0.08 }.radial_limit(), f64::INFINITY);
    }
}
