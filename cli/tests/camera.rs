//! Cameras and lenses: camera files, lens profiles, the GPU flow fields and lenses against their CPU twins.
//!
//! One test binary of the subject; each module is one former test file
//! (`cli/tests/camera/NAME.rs`, see docs/testing.md).

mod common;

#[path = "camera/camera.rs"]
mod camera;
#[path = "camera/gpu_flow.rs"]
mod gpu_flow;
#[path = "camera/gpu_lens.rs"]
mod gpu_lens;
#[path = "camera/lens_profiles.rs"]
mod lens_profiles;
