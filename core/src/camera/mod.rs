//! The camera (docs/spec.md sections 1 and 9): pinhole intrinsics (`intrinsics`),
//! lens distortion (`distortion`), rolling shutter (`shutter`), sensor
//! noise (`noise`), thin-lens defocus (`lens`), blur in px of an MMBM over
//! an exposure (`blur`) and the files that describe
//! them, Gyroflow lens profiles included (`file`: [`CameraFile`], the
//! one camera representation of files, configurations, the command line and
//! Python). This layer imports nothing above layer 0 (`error`, `check`, and
//! `bounded` to read its files).

pub(crate) mod blur;
pub(crate) mod digital;
#[doc(hidden)]
pub mod distortion;
pub(crate) mod file;
pub(crate) mod fisheye;
pub(crate) mod gyroflow;
pub(crate) mod gyroflow_choice;
pub(crate) mod insta360;
pub(crate) mod intrinsics;
pub(crate) mod lens;
pub(crate) mod light;
pub(crate) mod models;
pub(crate) mod newton;
pub(crate) mod noise;
pub(crate) mod opencv;
pub(crate) mod parts;
pub(crate) mod poly3;
pub(crate) mod poly5;
pub(crate) mod ptlens;
pub(crate) mod radial;
pub(crate) mod shutter;
pub(crate) mod sony;

pub use blur::{blur_px, checked_blur_of_px_s, checked_blur_px, checked_px_s, exposure_for_blur};
pub use digital::{Lens as DigitalLens, Warp};
pub use distortion::Distortion;
pub use file::{CameraFile, CameraOverrides, MAX_CAMERA_BYTES};
pub use gyroflow::Choice;
pub use intrinsics::{Camera, SensorRect};
pub use lens::Lens;
pub use light::{scene_table_md, SceneLight, PHOTONS_PER_LUX_S_M2, SCENES, TABLE_CAMERA};
pub use models::Model;
pub use noise::Noise;
pub use shutter::{Readout, Shutter};
