//! Camera-orientation presets (`--orientation`): the rotation `R` taking a
//! device's gyro axes to mmbm's camera frame (x right in the image, y down,
//! z forward along the lens), `w_camera = R * w_device`. `--imu-rotation`
//! is the general form (any rotation, applied after the preset).
//!
//! Phone axes (Android's `SensorEvent` and iOS's Core Motion alike): in the
//! phone's natural portrait position, x to the right of the screen, y up
//! the screen, z out of the screen towards the user. The back camera looks
//! along -z; the front camera along +z.
//!
//! - `phone-back-portrait`: a portrait video from the back camera. The
//!   image's right is the phone's right (the camera looks the way the user
//!   does), its down is -y, forward is -z: rows `(1,0,0)`, `(0,-1,0)`,
//!   `(0,0,-1)`.
//! - `phone-back-landscape`: a landscape video with the phone's top to the
//!   left (turned a quarter counterclockwise as the user sees it; Android's
//!   `ROTATION_90`, iOS's `landscapeRight` interface, the usual landscape).
//!   The image's right is the phone's -y (its bottom), down is -x, forward
//!   -z: rows `(0,-1,0)`, `(-1,0,0)`, `(0,0,-1)`.
//! - `phone-back-landscape-right`: the phone's top to the right (Android's
//!   `ROTATION_270`): right is +y, down is +x, forward -z: rows `(0,1,0)`,
//!   `(1,0,0)`, `(0,0,-1)`.
//! - `phone-front-portrait`: the front (selfie) camera, portrait, the image
//!   not mirrored: the camera looks along +z, so its right is the phone's
//!   -x, down -y: rows `(-1,0,0)`, `(0,-1,0)`, `(0,0,1)`.
//! - `action-cam`: GoPro's IMU axes (gpmf-parser's "IMU Orientation"
//!   figure: X to the camera's left, Y out of the back screen, Z up) for a
//!   camera upright, lens forward: right is -X, down is -Z, forward is -Y:
//!   rows `(-1,0,0)`, `(0,0,-1)`, `(0,-1,0)`. The default for a GoPro file.
//! - `camera`: the identity (the file's axes already are the camera's).
//!
//! Each matrix is a proper rotation (orthonormal, determinant +1; checked
//! by the unit tests).

use crate::error::{Error, Result};
use glam::{DMat3, DVec3};
use std::str::FromStr;

/// A named device-to-camera rotation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Orientation {
    /// Phone, back camera, portrait video.
    PhoneBackPortrait,
    /// Phone, back camera, landscape with the phone's top to the left.
    PhoneBackLandscape,
    /// Phone, back camera, landscape with the phone's top to the right.
    PhoneBackLandscapeRight,
    /// Phone, front camera, portrait video (not mirrored).
    PhoneFrontPortrait,
    /// GoPro-style action camera (GoPro's IMU axes).
    ActionCam,
    /// The identity.
    Camera,
}

/// Every preset with its name, in the order of the docs.
pub const ALL: [(&str, Orientation); 6] = [
    ("phone-back-portrait", Orientation::PhoneBackPortrait),
    ("phone-back-landscape", Orientation::PhoneBackLandscape),
    (
        "phone-back-landscape-right",
        Orientation::PhoneBackLandscapeRight,
    ),
    ("phone-front-portrait", Orientation::PhoneFrontPortrait),
    ("action-cam", Orientation::ActionCam),
    ("camera", Orientation::Camera),
];

/// A matrix from its rows.
fn rows(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(a[0], b[0], c[0]),
        DVec3::new(a[1], b[1], c[1]),
        DVec3::new(a[2], b[2], c[2]),
    )
}

impl Orientation {
    /// The rotation device axes -> camera frame.
    pub fn matrix(self) -> DMat3 {
        match self {
            Orientation::PhoneBackPortrait => rows([1., 0., 0.], [0., -1., 0.], [0., 0., -1.]),
            Orientation::PhoneBackLandscape => rows([0., -1., 0.], [-1., 0., 0.], [0., 0., -1.]),
            Orientation::PhoneBackLandscapeRight => rows([0., 1., 0.], [1., 0., 0.], [0., 0., -1.]),
            Orientation::PhoneFrontPortrait => rows([-1., 0., 0.], [0., -1., 0.], [0., 0., 1.]),
            Orientation::ActionCam => rows([-1., 0., 0.], [0., 0., -1.], [0., -1., 0.]),
            Orientation::Camera => DMat3::IDENTITY,
        }
    }

    /// The preset's name.
    pub fn name(self) -> &'static str {
        ALL.iter()
            .find(|(_, o)| *o == self)
            .map_or("camera", |(n, _)| n)
    }
}

impl FromStr for Orientation {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        ALL.iter()
            .find(|(n, _)| *n == s)
            .map(|&(_, o)| o)
            .ok_or_else(|| {
                let names: Vec<&str> = ALL.iter().map(|(n, _)| *n).collect();
                Error::invalid(
                    "orientation",
                    format!(
                        "'{}': expected one of {}",
                        crate::error::clip(s, 64),
                        names.join(", ")
                    ),
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_is_a_proper_rotation() {
        for (name, o) in ALL {
            let m = o.matrix();
            let err = (m * m.transpose() - DMat3::IDENTITY)
                .to_cols_array()
                .iter()
                .fold(0.0f64, |a, x| a.max(x.abs()));
            assert!(err < 1e-12, "{name}: not orthonormal");
            assert!(
                (m.determinant() - 1.0).abs() < 1e-12,
                "{name}: determinant {}",
                m.determinant()
            );
            assert_eq!(name.parse::<Orientation>().unwrap(), o);
        }
        assert!("sideways"
            .parse::<Orientation>()
            .unwrap_err()
            .to_string()
            .contains("phone-back-portrait"));
    }

    #[test]
    fn each_preset_sends_the_named_device_axes_where_the_docs_say() {
        // The back camera's forward is the device's -z in every back preset.
        for o in [
            Orientation::PhoneBackPortrait,
            Orientation::PhoneBackLandscape,
            Orientation::PhoneBackLandscapeRight,
        ] {
            assert_eq!(o.matrix() * DVec3::new(0.0, 0.0, -1.0), DVec3::Z);
        }
        // Portrait: the device's up is the image's up (-y, camera).
        assert_eq!(
            Orientation::PhoneBackPortrait.matrix() * DVec3::Y,
            -DVec3::Y
        );
        // Landscape (top to the left): the device's up points to the image's left.
        assert_eq!(
            Orientation::PhoneBackLandscape.matrix() * DVec3::Y,
            -DVec3::X
        );
        assert_eq!(
            Orientation::PhoneBackLandscapeRight.matrix() * DVec3::Y,
            DVec3::X
        );
        // GoPro: Z up is the image's up, Y back is the camera's backward.
        assert_eq!(Orientation::ActionCam.matrix() * DVec3::Z, -DVec3::Y);
        assert_eq!(Orientation::ActionCam.matrix() * DVec3::Y, -DVec3::Z);
    }
}
