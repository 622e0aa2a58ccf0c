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

pub mod assess;
pub mod blobs;
pub mod camera;
pub mod error;
pub mod experiment;
pub mod flow;
pub mod gpu;
pub mod gyro;
pub mod imageio;
pub mod metric;
pub mod motion;
pub mod output;
pub mod plot;
pub mod pose;
pub mod quiver;
pub mod render;
pub mod series;
pub mod sim;
pub mod tables;
pub mod trigger;

pub use camera::Camera;
pub use error::{Error, Result};
pub use metric::{mmbm, Method, Mmbm, Scene};
pub use motion::{Plane, Twist};
