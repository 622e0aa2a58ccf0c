//! GPU support through wgpu: the process-wide device ([`context`]), the
//! compute plumbing every kernel shares (`compute`: shader build under an
//! error scope, buffers, read-back), the kernels' one lens module ([`lens`]:
//! `lens.wgsl`, its host struct and twins) and the [`Backend`] choice. The
//! kernels themselves live with their features (`field`, `series`,
//! `render`), each shader beside its kernel and its CPU twin.

pub(crate) mod compute;
pub mod context;
pub mod lens;
mod runtime_dir;

pub use context::{gpu, GpuContext};

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicBool, Ordering};

/// Where a kernel runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// The GPU when an adapter exists, else the CPU twin (announced on stderr).
    #[default]
    Auto,
    /// The GPU or an error.
    Gpu,
    /// For many frames: a hardware GPU when there is one; on a software
    /// adapter (`DeviceType::Cpu`, e.g. Mesa lavapipe) or none, the CPU twin
    /// (announced once). On lavapipe the twin is about twice as fast on 2
    /// cores, and lavapipe 22.3's process memory grows by about 1.5 MB per
    /// render dispatch that does work (measured; not bounded by the outputs).
    Bulk,
    /// The CPU twin; `threads = None` uses rayon's global pool.
    Cpu {
        /// Worker threads.
        threads: Option<usize>,
    },
}

impl std::str::FromStr for Backend {
    type Err = Error;
    /// `auto`, `gpu`, `cpu` (rayon's global pool) or `bulk`.
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(Backend::Auto),
            "gpu" => Ok(Backend::Gpu),
            "cpu" => Ok(Backend::Cpu { threads: None }),
            "bulk" => Ok(Backend::Bulk),
            _ => Err(Error::invalid(
                "backend",
                format!("'{s}': expected auto, gpu, cpu or bulk"),
            )),
        }
    }
}

/// A [`Backend`] resolved against the machine: the device, or the CPU twin.
#[derive(Clone, Copy)]
pub enum Resolved {
    /// Run on this device.
    Gpu(&'static GpuContext),
    /// Run the CPU twin with this many threads (`None`: rayon's global pool).
    Cpu(Option<usize>),
}

impl Backend {
    /// The device for `Gpu` (or an error) and `Auto` (when one exists), else
    /// the CPU twin. `Auto` without an adapter prints `"{what}: {error}; using
    /// the CPU {twin}"` on stderr, once per `announced` flag; with
    /// `MMBM_REQUIRE_GPU=1` in the environment (CI) it is an error instead, so
    /// that no check silently runs on the twin where the GPU was meant.
    pub fn resolve(self, what: &str, twin: &str, announced: &AtomicBool) -> Result<Resolved> {
        match self {
            Backend::Cpu { threads } => Ok(Resolved::Cpu(threads)),
            Backend::Gpu => Ok(Resolved::Gpu(gpu()?)),
            Backend::Bulk => match gpu() {
                Ok(ctx) if ctx.adapter.get_info().device_type != wgpu::DeviceType::Cpu => {
                    Ok(Resolved::Gpu(ctx))
                }
                Ok(ctx) => {
                    if !announced.swap(true, Ordering::Relaxed) {
                        log::info!(
                            "{what}: {} is a software adapter; using the CPU {twin} (faster there, bounded memory)",
                            ctx.description
                        );
                    }
                    Ok(Resolved::Cpu(None))
                }
                Err(_) => Ok(Resolved::Cpu(None)),
            },
            Backend::Auto => match gpu() {
                Ok(ctx) => Ok(Resolved::Gpu(ctx)),
                Err(e) if std::env::var("MMBM_REQUIRE_GPU").is_ok_and(|v| v == "1") => Err(
                    Error::Gpu(format!("{what}: MMBM_REQUIRE_GPU=1 and no adapter: {e}")),
                ),
                Err(e) => {
                    if !announced.swap(true, Ordering::Relaxed) {
                        log::warn!("{what}: {e}; using the CPU {twin}");
                    }
                    Ok(Resolved::Cpu(None))
                }
            },
        }
    }
}
