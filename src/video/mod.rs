//! The video through FFmpeg run as a subprocess.

pub mod decode;
