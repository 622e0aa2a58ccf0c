//! # mmbm-core — camera motion blur without a GPU
//!
//! The core of [mmbm](https://docs.rs/mmbm): the layers of the house that need
//! no wgpu and no plotters, so that a robot (or the live trigger) can link the
//! metric alone. The `mmbm` library re-exports every module here at the same
//! path (`mmbm::camera` is `mmbm_core::camera`).
//!
//! Units: focal length and sensor coordinates in mm, pixel pitch in mm,
//! angular velocity rad/s, linear velocity m/s, depth m, time s. The metric is
//! in mm/s on the sensor (also px/s). Camera frame: x right, y down, z forward.
//!
//! # Layers
//!
//! Modules import only from their own layer or the ones below it (checked by
//! `tests/layers.rs`, which also rejects import circles between modules and
//! between the files of any folder); the crate boundary keeps everything here
//! from importing the library above it:
//!
//! | layer | modules | holds |
//! |---|---|---|
//! | 0 | [`error`], [`check`], [`limits`], [`bounded`], [`stats`], [`diagnostics`], [`cancel`] | the error enum; value checks (finite, positive) that name the value; every cap on inputs; bounded whole-file reading (file kinds, the text cap); mean and percentile; where the library's warnings go (the `log` facade); stopping long calls from outside |
//! | 1 | [`camera`], [`model`], [`io`] | the camera (intrinsics, distortion, shutter, noise, lens); motion, flow, the trajectory over an exposure; files |
//! | 2 | [`metric`], [`sim`] | MMBM rules; gait simulation |
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod bounded;
pub mod camera;
pub mod cancel;
pub mod check;
pub mod diagnostics;
pub mod error;
pub mod io;
pub mod limits;
pub mod metric;
pub mod model;
pub mod sim;
pub mod stats;

pub use camera::Camera;
pub use error::{Error, Result};
pub use metric::{mmbm, AnyMethod, Method, Mmbm, Scene};
pub use model::motion::{Plane, Twist};
