//! Files in and out: atomic output ([`atomic`]: temp file + rename), image
//! files ([`images`]: EXR, sRGB PNG, textures) and gyro log readers
//! ([`gyro`]). This layer imports nothing above `error`.

pub mod atomic;
pub mod gyro;
pub mod images;
