//! The frame-picking benchmark's scoring and pickers (`mmbm_lab::pickers`,
//! issue 36): closed forms for the scores, and the gyro picker on a tiny
//! rendered clip whose blur per frame is known by construction.
//!
//! One test binary of the subject; each module one file
//! (`tests/pickers/NAME.rs`, see docs/testing.md).

mod common;
#[path = "pickers/scoring.rs"]
mod scoring;
