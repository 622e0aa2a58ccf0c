//! GPU support through wgpu: the shared device ([`context`]) and the kernels.
//! Every kernel has a CPU twin beside it in the source tree.

pub mod context;
pub mod flow;

pub use context::{gpu, GpuContext};
