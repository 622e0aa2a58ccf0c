//! Files in and out: atomic output ([`atomic`]: temp file + rename), image
//! files ([`images`]: EXR, sRGB PNG, textures) and gyro log readers
//! ([`gyro`]: CSV, and ROS 2 MCAP through [`mcap`]; [`lines`]: one line at a
//! time, for live streams); video frame tables ([`frames`]). This layer
//! imports nothing above `error`.

pub mod atomic;
pub mod frames;
pub mod gyro;
pub mod images;
pub mod lines;
pub mod mcap;
