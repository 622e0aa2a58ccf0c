//! GPU support through wgpu: the shared device ([`context`]) and the kernels.
//! Every kernel has a CPU twin beside it in the source tree.

pub mod context;
pub mod flow;
pub mod flow_bench;
pub mod flow_cpu;
pub mod flow_params;
pub mod flow_runner;

pub use context::{gpu, GpuContext};
