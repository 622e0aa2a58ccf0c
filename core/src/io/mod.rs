//! Files in and out: atomic output ([`atomic`]: temp file + rename), one
//! check of a command's outputs against each other and its inputs before
//! any work ([`guard`]), image
//! files ([`images`]: EXR, sRGB PNG, textures) and gyro log readers
//! (`gyro`: CSV, ROS 2 MCAP through `mcap` and Gyroflow `.gcsv` through
//! [`gcsv`]; [`lines`]: one line at a time, for live streams); video frame
//! tables ([`frames`]; a phone's image list and IMU rows in [`phone`],
//! ffprobe's frames in [`ffprobe`]); [`input`]: the kind and size checks every reader
//! shares (regular files and pipes only, capped lines, headers and image
//! sizes); [`decimal`]: the numbers of text logs, read fast and to the bit as
//! `str::parse` reads them. Besides layer 0 it imports only its own layer's
//! `model` (the validated log a reader yields) and `camera` (a log's readout).

pub mod atomic;
pub mod decimal;
pub mod ffprobe;
pub mod frames;
pub mod gcsv;
pub mod guard;
pub mod gyro;
pub mod images;
pub mod input;
pub mod lines;
pub(crate) mod mcap;
pub mod phone;
