//! # mmbm — camera motion blur
//!
//! A library (and the `mmbm` command) for the MMBM metric: the mean image-plane
//! flow speed over a camera sensor, predicted from the camera's angular (and
//! linear) velocity. Exact and real-time evaluation, per-pixel GPU flow fields,
//! a ground-truth motion-blur renderer, gait simulation and trigger policies.
//!
//! Units: focal length and sensor coordinates in mm, pixel pitch in mm,
//! angular velocity rad/s, linear velocity m/s, depth m, time s. The metric is
//! in mm/s on the sensor (also px/s). Camera frame: x right, y down, z forward.
//!
//! # Crates and layers
//!
//! The workspace holds the layers in three crates: the core
//! ([`mmbm_core`]: layers 0-2 without wgpu or plotters, which a robot can link
//! alone), this library (the GPU kernels, series, the renderer and the
//! trigger), which re-exports the core's modules at the same paths
//! (`mmbm::camera` is `mmbm_core::camera`), and the lab (crate `mmbm-lab`:
//! experiment, tables, plots, datasets). Inside each crate, modules import only
//! from their own layer or the ones below it (checked by `tests/layers.rs`,
//! which also rejects import circles between modules and between the files of
//! any folder); across crates the compiler enforces it:
//!
//! | layer | crate | modules | holds |
//! |---|---|---|---|
//! | 0 | core | [`error`], [`check`], [`limits`], [`bounded`], [`stats`], [`diagnostics`], [`cancel`] | the error enum; value checks (finite, positive) that name the value; every cap on inputs; bounded whole-file reading (file kinds, the text cap); mean and percentile; where the library's warnings go (the `log` facade); stopping long calls from outside |
//! | 1 | core | [`camera`], [`model`], [`io`] | the camera (intrinsics, distortion, shutter, noise, lens); motion, flow, the trajectory over an exposure; files |
//! | 1 | library | [`gpu`] | the wgpu device and compute plumbing |
//! | 2 | core | [`metric`], [`sim`] | MMBM rules; gait simulation |
//! | 2 | library | [`board`], [`assess`], [`telemetry`], [`video`] | the thesis board, blobs, pose; image blur metrics; the gyro from a camera's own files (GoPro MP4, Gyroflow projects, phone apps); video decoding, probing and encoding through ffmpeg |
//! | 2 | lab | `plot` | figures |
//! | 3 | library | [`field`] | the flow-field kernel (GPU + CPU twin) |
//! | 3 | lab | `tables` | thesis tables |
//! | 4 | library | [`series`], [`render`], [`sync`] | MMBM of a log (CPU and GPU batch); the blur renderer; the gyro-to-video offset from the video (ffmpeg) |
//! | 5 | library | [`trigger`], [`augment`], [`prelude`] | trigger policies; motion-blur augmentation of any image; the types a user needs first |
//! | 6 | lab | `experiment`, `dataset`, `pickers` | the thesis experiment end to end; blur datasets at scale; the frame-picking benchmark |
//!
//! The `mmbm` command (the workspace's `cli/` crate) sits on top; the throughput benchmarks are
//! `cargo bench` targets in `benches/`. [`prelude`] holds the types a user needs first.
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod assess;
pub mod augment;
pub mod board;
pub mod field;
pub mod gpu;
pub mod prelude;
pub mod render;
pub mod series;
pub mod sync;
pub mod telemetry;
pub mod trigger;
pub mod video;

// The core's modules at the paths they had in this crate (`crate::camera::X`
// inside the library, `mmbm::camera::X` outside).
pub use mmbm_core::{
    bounded, camera, cancel, check, diagnostics, error, io, limits, metric, model, sim, stats,
};

pub use camera::Camera;
pub use error::{Error, Result};
pub use metric::{mmbm, AnyMethod, Method, Mmbm, Scene};
pub use model::motion::{Plane, Twist};
