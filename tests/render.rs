//! The renderer (library): the camera model of a render, exactness against the area-and-time integral, GPU against its twin and the goldens, lenses, properties, textures, rendered blobs, the shaders' validation.
//!
//! One test binary of the subject; each module is one former test file
//! (`tests/render/NAME.rs`, see docs/testing.md).

mod common;

#[path = "render/blobs_rendered.rs"]
mod blobs_rendered;
#[path = "render/houseg.rs"]
mod houseg;
#[path = "render/render_camera.rs"]
mod render_camera;
#[path = "render/render_exact.rs"]
mod render_exact;
#[path = "render/render_gpu.rs"]
mod render_gpu;
#[path = "render/render_lens.rs"]
mod render_lens;
#[path = "render/render_props.rs"]
mod render_props;
#[path = "render/render_texture.rs"]
mod render_texture;
#[path = "render/shaders.rs"]
mod shaders;
#[path = "render/speed.rs"]
mod speed;
