//! The `mmbm frames` command and its per-frame blur maps: selection, choice, video, the maps on CPU and GPU.
//!
//! One test binary of the subject; each module is one former test file
//! (`cli/tests/frames/NAME.rs`, see docs/testing.md).

mod common;
#[path = "frames/frames_fixture.rs"]
mod frames_fixture;
#[path = "frames/maps_fixture.rs"]
mod maps_fixture;
#[path = "logs/telemetry_fixture.rs"]
mod telemetry_fixture;

#[path = "frames/frame_maps.rs"]
mod frame_maps;
#[path = "frames/frames.rs"]
mod frames;
#[path = "frames/frames_choose.rs"]
mod frames_choose;
#[path = "frames/frames_select.rs"]
mod frames_select;
#[path = "frames/frames_video.rs"]
mod frames_video;
#[path = "frames/maps_gpu.rs"]
mod maps_gpu;
#[path = "frames/maps_gpu_lens.rs"]
mod maps_gpu_lens;
#[path = "frames/worked_example.rs"]
mod worked_example;
