//! Camera files: the project's own TOML/JSON description and Gyroflow lens
//! profiles (JSON with `fisheye_params`), so that the public collection of
//! Gyroflow profiles works as it is.
//!
//! Own format (every key of docs/spec.md section 1 and 9; pitch may be given once for square pixels):
//!
//! ```toml
//! focal_mm = 4.2548
//! pitch_mm = 0.00465
//! width = 640
//! height = 480
//! # cx, cy (default: the centre), skew (default 0)
//! readout_s = 0.016                  # rolling shutter (default 0: global)
//! readout_direction = "top-to-bottom" # or bottom-to-top, left-to-right, right-to-left
//! [distortion]
//! model = "opencv"                   # k1, k2, p1, p2, k3; or "fisheye" with k1..k4
//! k1 = -0.28
//! [noise]
//! phi_e_per_s = 50000                # read_noise_e, full_well_e, gain_dn_per_e, bits, seed
//! [lens]
//! f_number = 2.0
//! focus_m = 1.5
//! ```
//!
//! [`CameraFile`] is this format's keys, each optional, and the one camera
//! representation of every door: a camera file on its own ([`Camera::load`]),
//! an experiment's `[camera]` section over the thesis camera
//! ([`CameraFile::thesis_at`]), the command line's `--camera FILE` with the
//! flags over it ([`Camera::resolve`], [`CameraOverrides`]) and the Python
//! package's `Camera` (this format as a dict).
//!
//! Gyroflow profile: `calib_dimension {w, h}`, `fisheye_params.camera_matrix`
//! (3x3, pixels), `fisheye_params.distortion_coeffs`, `distortion_model`
//! (`opencv_fisheye`, the default, or `opencv_standard`; older profiles say
//! `use_opencv_standard: true`), `frame_readout_time` (ms) and
//! `frame_readout_direction`. A profile gives pixels only: the pixel pitch is
//! `focal_length / fx` when the profile has a `focal_length` in mm, otherwise a
//! nominal 1 um (`gyroflow::NOMINAL_PITCH_MM`), which scales the mm/s outputs but not px/s.

use super::distortion::Distortion;
use super::intrinsics::Camera;
use super::lens::Lens;
use super::noise::Noise;
use super::shutter::{Readout, Shutter};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::Path;

pub use super::gyroflow::Choice;

/// Largest camera file read, bytes (a real one is under 10 kB; Gyroflow
/// profiles a few kB). Bounds the parsers' time and memory: a 6 MB TOML
/// array took 5.7 s and 530 MB to refuse.
pub const MAX_CAMERA_BYTES: u64 = 1 << 20;

/// The camera file's keys (docs/spec.md sections 1 and 9), every one optional: on
/// its own ([`CameraFile::camera`]) a file needs `focal_mm`, a pitch
/// (`pitch_mm`, or `pitch_x_mm` and `pitch_y_mm`), `width` and `height`;
/// over a base camera ([`CameraFile::over`]) each key given replaces the
/// base's and the others keep it. Serialised, the keys not given are left out.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraFile {
    /// Focal length, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub focal_mm: Option<f64>,
    /// Square pixel pitch, mm (both axes unless `pitch_x_mm` / `pitch_y_mm` say otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch_mm: Option<f64>,
    /// Horizontal pixel pitch, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch_x_mm: Option<f64>,
    /// Vertical pixel pitch, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch_y_mm: Option<f64>,
    /// Sensor width, px.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub width: Option<u32>,
    /// Sensor height, px.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height: Option<u32>,
    /// Principal point column, px (default: the centre of the width given,
    /// else the base's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cx: Option<f64>,
    /// Principal point row, px (default: the centre of the height given,
    /// else the base's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cy: Option<f64>,
    /// Skew, px (a file on its own: 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skew: Option<f64>,
    /// Rolling-shutter readout, s: first to last line's exposure start (a
    /// file on its own: 0, a global shutter).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub readout_s: Option<f64>,
    /// Readout direction (a file on its own: top-to-bottom).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub readout_direction: Option<Readout>,
    /// Lens distortion (a file on its own: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub distortion: Option<Distortion>,
    /// Sensor noise (a light level `phi_e_per_s` and the sensor's keys).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise: Option<Noise>,
    /// Thin lens (defocus).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lens: Option<Lens>,
}

/// Keys only a Gyroflow lens profile has (a JSON camera file with one of
/// them and no `fisheye_params` is a profile missing that key).
const GYROFLOW_KEYS: [&str; 4] = [
    "calib_dimension",
    "compatible_settings",
    "interpolations",
    "calibrated_by",
];

/// The keys a camera file on its own must give.
const NEEDED: &str = "a camera file gives focal_mm, pitch_mm (or pitch_x_mm and pitch_y_mm), \
                      width and height";

impl CameraFile {
    /// Every key of `c` (the pitch as `pitch_x_mm` and `pitch_y_mm`; no
    /// distortion key for an ideal pinhole): `CameraFile::of(&c).camera()`
    /// is `c` again.
    pub fn of(c: &Camera) -> Self {
        CameraFile {
            focal_mm: Some(c.focal_mm),
            pitch_mm: None,
            pitch_x_mm: Some(c.pitch_x_mm),
            pitch_y_mm: Some(c.pitch_y_mm),
            width: Some(c.width),
            height: Some(c.height),
            cx: Some(c.cx),
            cy: Some(c.cy),
            skew: Some(c.skew),
            readout_s: Some(c.shutter.readout_s),
            readout_direction: Some(c.shutter.direction),
            distortion: (!c.distortion.is_none()).then_some(c.distortion),
            noise: c.noise,
            lens: c.lens,
        }
    }

    /// The camera these keys describe on their own (not validated): an
    /// error names a missing `focal_mm`, `width` or `height`; a missing
    /// pitch is NaN, which [`Camera::validate`] refuses by name.
    pub fn camera(&self) -> Result<Camera> {
        let need = |key: &str, given: bool| -> Result<()> {
            if given {
                Ok(())
            } else {
                Err(Error::invalid(
                    key,
                    format!("missing field `{key}` ({NEEDED})"),
                ))
            }
        };
        need("focal_mm", self.focal_mm.is_some())?;
        need("width", self.width.is_some())?;
        need("height", self.height.is_some())?;
        let (w, h) = (self.width.unwrap_or(0), self.height.unwrap_or(0));
        Ok(self.over(&Camera::new(f64::NAN, f64::NAN, w, h)))
    }

    /// `base` with each key given here in place of the base's. A `width`
    /// (`height`) given without `cx` (`cy`) puts the principal point at the
    /// new centre, as [`Camera::with_resolution`] does; `noise` and `lens`
    /// replace the base's whole. Not validated.
    pub fn over(&self, base: &Camera) -> Camera {
        let width = self.width.unwrap_or(base.width);
        let height = self.height.unwrap_or(base.height);
        let centre = |given: Option<u32>, side: u32, base: f64| match given {
            Some(_) => side as f64 / 2.0,
            None => base,
        };
        Camera {
            focal_mm: self.focal_mm.unwrap_or(base.focal_mm),
            pitch_x_mm: self.pitch_x_mm.or(self.pitch_mm).unwrap_or(base.pitch_x_mm),
            pitch_y_mm: self.pitch_y_mm.or(self.pitch_mm).unwrap_or(base.pitch_y_mm),
            width,
            height,
            cx: self.cx.unwrap_or(centre(self.width, width, base.cx)),
            cy: self.cy.unwrap_or(centre(self.height, height, base.cy)),
            skew: self.skew.unwrap_or(base.skew),
            distortion: self.distortion.unwrap_or(base.distortion),
            shutter: Shutter {
                readout_s: self.readout_s.unwrap_or(base.shutter.readout_s),
                direction: self.readout_direction.unwrap_or(base.shutter.direction),
            },
            noise: self.noise.or(base.noise),
            lens: self.lens.or(base.lens),
        }
        .refit_digital()
    }

    /// The camera of a configuration's `[camera]` section (the experiment's;
    /// the dataset's items use it with no keys): the thesis camera (its
    /// focal length and pitch) at `resolution` `[width, height]` px, with
    /// these keys over it. Not validated.
    pub fn thesis_at(&self, resolution: [u32; 2]) -> Camera {
        self.over(&Camera::thesis().with_resolution(resolution[0], resolution[1]))
    }

    /// Parses a camera file's text: TOML when `path` ends in `.toml`,
    /// otherwise JSON (the project's keys, or a Gyroflow lens profile: an
    /// object with `fisheye_params`). Errors name `path` and the key. Not
    /// validated.
    pub fn parse(text: &str, path: &Path) -> Result<Camera> {
        Self::parse_for(text, path, &Choice::default())
    }

    /// [`CameraFile::parse`] for a video of `choice`'s size and a zoom lens's
    /// focal length (a Gyroflow profile's `compatible_settings` and
    /// `interpolations`, `super::gyroflow`).
    pub fn parse_for(text: &str, path: &Path, choice: &Choice) -> Result<Camera> {
        let config = |message: String| Error::Config {
            path: path.into(),
            message,
        };
        if path.extension().is_some_and(|e| e == "toml") {
            let file: CameraFile = toml::from_str(text).map_err(|e| config(e.to_string()))?;
            return file.camera().map_err(|e| config(e.to_string()));
        }
        let value: Value = serde_json::from_str(text).map_err(|e| config(e.to_string()))?;
        if value.get("fisheye_params").is_some() {
            return super::gyroflow::from_gyroflow(&value, choice)
                .map_err(|e| config(e.to_string()));
        }
        // A Gyroflow profile's own keys without its `fisheye_params`: the
        // missing key, not "unknown field calib_dimension".
        if let Some(key) = GYROFLOW_KEYS.iter().find(|k| value.get(**k).is_some()) {
            return Err(config(
                Error::invalid(
                    "fisheye_params",
                    format!(
                        "missing: the file reads as a Gyroflow lens profile (it has {key}), which \
                         needs fisheye_params {{camera_matrix, distortion_coeffs}}"
                    ),
                )
                .to_string(),
            ));
        }
        let file: CameraFile = serde_json::from_value(value).map_err(|e| config(e.to_string()))?;
        file.camera().map_err(|e| config(e.to_string()))
    }
}

/// What a command line changes in its camera (`--focal`, `--pitch`,
/// `--sensor`, `--scale-to`, `--rolling-readout`, `--readout-direction`,
/// `--light`), applied by [`Camera::resolve`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CameraOverrides {
    /// Camera-file keys over the file's (or the thesis camera's): focal
    /// length, pitch, sensor size (principal point re-centred), readout.
    pub keys: CameraFile,
    /// Then the camera scaled to this `(width, height)`, px, transposed
    /// first for the other orientation ([`Camera::fitted_to`]: the field of
    /// view stays).
    pub scale_to: Option<(u32, u32)>,
    /// Then sensor noise at this light level (electrons per second of a
    /// white pixel), with the camera's other noise keys or their defaults.
    pub light_e_per_s: Option<f64>,
    /// A Gyroflow zoom profile's focal length, mm: its `interpolations` at
    /// that focal length (none: the profile as it is, as Gyroflow without
    /// lens metadata).
    pub lens_focal_mm: Option<f64>,
}

impl Camera {
    /// Loads a camera from a TOML (`.toml`) or JSON (any other extension)
    /// file: the project's format, or a Gyroflow lens profile (a JSON object
    /// with `fisheye_params`). Missing principal point fields default to the
    /// sensor centre. The file is read as every configuration is
    /// ([`crate::bounded::read_text`]: a regular file or a pipe, at most
    /// [`crate::bounded::MAX_TEXT_BYTES`]). Errors name the file and the key.
    pub fn load(path: &Path) -> Result<Self> {
        Self::load_for(path, &Choice::default())
    }

    /// [`Camera::load`] for a video of `choice`'s size and a zoom lens's focal
    /// length (a Gyroflow profile's `compatible_settings` and `interpolations`).
    pub fn load_for(path: &Path, choice: &Choice) -> Result<Self> {
        let text = crate::bounded::read_text_at_most(path, MAX_CAMERA_BYTES)?;
        let cam = CameraFile::parse_for(&text, path, choice)?;
        cam.validate().map_err(|e| Error::Config {
            path: path.into(),
            message: e.to_string(),
        })?;
        Ok(cam)
    }

    /// The camera of a command line: the camera file `file` (or the thesis
    /// camera) with `over` applied, validated.
    pub fn resolve(file: Option<&Path>, over: &CameraOverrides) -> Result<Self> {
        let base = match file {
            Some(p) => Camera::load_for(
                p,
                &Choice {
                    video: over.scale_to,
                    focal_mm: over.lens_focal_mm,
                },
            )?,
            None => Camera::thesis(),
        };
        let mut c = over.keys.over(&base);
        if let Some((w, h)) = over.scale_to {
            c = c.fitted_to(w, h);
        }
        if let Some(phi) = over.light_e_per_s {
            c.noise = Some(Noise {
                phi_e_per_s: phi,
                ..c.noise.unwrap_or(Noise::at_light(phi))
            });
        }
        c.validate()?;
        Ok(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wide() -> Camera {
        Camera {
            cx: 322.5,
            cy: 238.0,
            skew: 0.4,
            distortion: Distortion::WIDE_ANGLE,
            shutter: Shutter {
                readout_s: 0.016,
                direction: Readout::LeftToRight,
            },
            noise: Some(Noise::at_light(5e4)),
            lens: Some(Lens {
                f_number: 2.0,
                focus_m: 1.5,
            }),
            ..Camera::new(2.8, 0.0028, 640, 480)
        }
    }

    #[test]
    fn every_key_round_trips() {
        let c = wide();
        assert_eq!(CameraFile::of(&c).camera().unwrap(), c);
        let json = serde_json::to_string(&CameraFile::of(&c)).unwrap();
        let back: CameraFile = serde_json::from_str(&json).unwrap();
        assert_eq!(back.camera().unwrap(), c);
        // The ideal pinhole has no distortion key.
        assert!(CameraFile::of(&Camera::thesis()).distortion.is_none());
        assert_eq!(
            CameraFile::of(&Camera::thesis()).camera().unwrap(),
            Camera::thesis()
        );
    }

    #[test]
    fn keys_over_a_base_replace_only_themselves() {
        let base = wide();
        assert_eq!(CameraFile::default().over(&base), base);
        let sized = CameraFile {
            width: Some(320),
            height: Some(200),
            ..Default::default()
        };
        assert_eq!(sized.over(&base), base.with_resolution(320, 200));
        let pitch = CameraFile {
            pitch_mm: Some(0.002),
            pitch_y_mm: Some(0.003),
            readout_s: Some(0.0),
            ..Default::default()
        }
        .over(&base);
        assert_eq!((pitch.pitch_x_mm, pitch.pitch_y_mm), (0.002, 0.003));
        assert!(pitch.shutter.is_global());
        assert_eq!(pitch.shutter.direction, Readout::LeftToRight);
        assert_eq!((pitch.cx, pitch.distortion), (322.5, base.distortion));
        assert_eq!(
            CameraFile::default().thesis_at([320, 240]),
            Camera::thesis().with_resolution(320, 240)
        );
    }

    #[test]
    fn command_line_flags_over_a_file() {
        let over = CameraOverrides {
            keys: CameraFile {
                focal_mm: Some(3.0),
                readout_s: Some(0.01),
                ..Default::default()
            },
            scale_to: Some((1280, 960)),
            light_e_per_s: Some(1000.0),
            lens_focal_mm: None,
        };
        let c = Camera::resolve(None, &over).unwrap();
        let mut want = Camera {
            focal_mm: 3.0,
            ..Camera::thesis()
        }
        .scaled_to(1280, 960);
        want.shutter.readout_s = 0.01;
        want.noise = Some(Noise::at_light(1000.0));
        assert_eq!(c, want);
        let bad = CameraOverrides {
            keys: CameraFile {
                focal_mm: Some(-1.0),
                ..Default::default()
            },
            ..Default::default()
        };
        let e = Camera::resolve(None, &bad).unwrap_err().to_string();
        assert!(e.contains("focal length"), "{e}");
    }

    #[test]
    fn a_file_on_its_own_names_what_is_missing() {
        let p = Path::new("cam.toml");
        let e = CameraFile::parse("focal_mm = 3\nwidth = 10\n", p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cam.toml") && e.contains("height"), "{e}");
        let e = CameraFile::parse("focal_mm = 3\nwidth = 10\nheight = 8\n", p)
            .unwrap()
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("pixel pitch"), "{e}");
        let e = CameraFile::parse("{\"focal_mm\": 3, \"zoom\": 2}", Path::new("c.json"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.json") && e.contains("zoom"), "{e}");
    }

    #[test]
    fn camera_files_are_read_with_the_configuration_caps() {
        let e = Camera::load(Path::new("/dev/zero"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("/dev/zero") && e.contains("character device"),
            "{e}"
        );
        let e = Camera::load(Path::new("/")).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
    }
}
