//! Augmentation (library): the streak of a dot, the API, speed and accuracy.
//!
//! One test binary of the subject; each module is one former test file
//! (`tests/augment/NAME.rs`, see docs/testing.md).

#[path = "augment/augment_fixture.rs"]
mod augment_fixture;
mod common;

#[path = "augment/augment.rs"]
mod augment;
#[path = "augment/augment_api.rs"]
mod augment_api;
#[path = "augment/augment_gpu.rs"]
mod augment_gpu;
#[path = "augment/augment_speed.rs"]
mod augment_speed;
