//! The physical model (SPEC sections 1-2): the camera's intrinsics
//! ([`camera`]), its motion and the scene plane ([`motion`]), and the
//! instantaneous image-plane flow they produce ([`flow`]). Everything else in
//! the crate builds on these; this layer imports nothing above `error`.

pub mod camera;
pub mod flow;
pub mod motion;

pub use camera::Camera;
pub use motion::{Plane, Twist};
