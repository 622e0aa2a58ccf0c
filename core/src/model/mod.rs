//! The physical model (docs/spec.md sections 1-2): the camera (its own layer-1 folder,
//! [`crate::camera`]), its motion and the scene plane ([`motion`]), and the
//! instantaneous image-plane flow they produce ([`flow`]), and the IMU log that
//! measures the motion ([`log`]), and the camera's pose over an exposure
//! integrated from a twist or a log ([`trajectory`]). Everything else in the crate builds on
//! these; this layer imports only `camera` and layer 0.

pub mod flow;
pub mod log;
pub mod motion;
pub mod track;
pub mod trajectory;

pub use crate::camera::Camera;
pub use motion::{Plane, Twist};
