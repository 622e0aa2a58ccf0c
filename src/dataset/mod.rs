//! Blur datasets at scale (`mmbm dataset`): sharp/blurred pairs of textured
//! planes moved by real or simulated gyro motion, with exact per-pixel flow
//! and blur maps, made item by item so that any split of the work across
//! machines (`--shard K/N`, SLURM job arrays, Kubernetes Indexed Jobs) gives
//! the same bytes.
//!
//! - `config`: what items are drawn from (TOML, `--print-config`).
//! - [`item`]: one item's parameters (drawn from the configuration and the
//!   item's seed only) and files.
//! - `run`: making a shard (resumable), merging shard manifests, verifying
//!   a directory against its manifest.

pub(crate) mod config;
pub mod item;
pub(crate) mod run;

pub use config::DatasetConfig;
pub use item::{ItemParams, Sources};
pub use run::{merge, run, verify, ManifestLine, RunSummary, Shard};
