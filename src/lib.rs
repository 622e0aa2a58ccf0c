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
//! # Layers
//!
//! Modules import only from their own layer or the ones below it (checked by
//! `tests/layers.rs`, which also rejects import circles between modules):
//!
//! | layer | modules | holds |
//! |---|---|---|
//! | 0 | [`error`], [`check`], [`limits`], [`bounded`], [`stats`], [`diagnostics`], [`cancel`] | the error enum; value checks (finite, positive) that name the value; every cap on inputs; bounded whole-file reading (file kinds, the text cap); mean and percentile; where the library's warnings go (the `log` facade); stopping long calls from outside |
//! | 1 | [`camera`], [`model`], [`io`], [`gpu`] | the camera (intrinsics, distortion, shutter, noise, lens); motion, flow; files; the wgpu device and compute plumbing |
//! | 2 | [`metric`], [`board`], [`plot`], [`sim`], [`assess`], [`telemetry`] | MMBM rules; the thesis board, blobs, pose; figures; gait simulation; image blur metrics; the gyro from a camera's own files (GoPro MP4, Gyroflow projects, phone apps) |
//! | 3 | [`field`], [`tables`] | the flow-field kernel (GPU + CPU twin); thesis tables |
//! | 4 | [`series`], [`render`], [`sync`] | MMBM of a log (CPU and GPU batch); the blur renderer; the gyro-to-video offset from the video (ffmpeg) |
//! | 5 | [`trigger`], [`augment`] | trigger policies; motion-blur augmentation of any image |
//! | 6 | [`experiment`], [`dataset`] | the thesis experiment end to end; blur datasets at scale |
//!
//! The `mmbm` command (the workspace's `cli/` crate) sits on top; the throughput benchmarks are
//! `cargo bench` targets in `benches/`.
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod assess;
pub mod augment;
pub mod board;
pub mod bounded;
pub mod camera;
pub mod cancel;
pub mod check;
pub mod dataset;
pub mod diagnostics;
pub mod error;
pub mod experiment;
pub mod field;
pub mod gpu;
pub mod io;
pub mod limits;
pub mod metric;
pub mod model;
pub mod plot;
pub mod render;
pub mod series;
pub mod sim;
pub mod stats;
pub mod sync;
pub mod tables;
pub mod telemetry;
pub mod trigger;

pub use camera::Camera;
pub use error::{Error, Result};
pub use metric::{mmbm, AnyMethod, Method, Mmbm, Scene};
pub use model::motion::{Plane, Twist};
