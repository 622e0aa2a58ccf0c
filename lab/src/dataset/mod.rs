//! Blur datasets at scale (`mmbm dataset`): sharp/blurred pairs of textured
//! planes moved by real or simulated gyro motion, with exact per-pixel flow
//! and blur maps, made item by item so that any split of the work across
//! machines (`--shard K/N`, SLURM job arrays, Kubernetes Indexed Jobs) gives
//! the same bytes.
//!
//! - `config`: what items are drawn from (TOML, `--print-config`).
//! - [`item`]: one item's parameters (drawn from the configuration and the
//!   item's seed only) and files.
//! - `run`: making a shard (resumable); `shard`: which items a
//!   shard makes, and the cap on shard counts.
//! - `manifest`: merging shard manifests, verifying a directory against
//!   its manifest (which is input: every path it names is confined).
//! - `guard`: the configuration's fingerprint (`DIR/dataset.json`).
//! - `lock`: the locks that keep each shard, and the packing, to one
//!   writer (their files removed when the run ends).
//! - `sensor`: the camera pipeline of the PNG files (`[sensor]`).
//! - [`textures`]: the built-in textures (`textures = "builtin:"`, the
//!   default), compiled in from `assets/textures/`.
//! - `webdataset`: the directory packed into WebDataset tar shards
//!   (`--format webdataset`); `tarcheck`: the shards checked against their
//!   index (`--verify`).

pub(crate) mod config;
pub(crate) mod guard;
pub mod item;
pub(crate) mod lock;
pub(crate) mod manifest;
pub(crate) mod run;
pub(crate) mod sensor;
pub(crate) mod shard;
pub(crate) mod tarcheck;
pub(crate) mod tarindex;
pub mod textures;
pub(crate) mod webdataset;

pub use config::{DatasetConfig, Origin, MAX_COUNT};
pub use guard::Record;
pub use item::{ItemParams, Sources};
pub use lock::{PackLock, RunLock};
pub use manifest::{merge, verify, ManifestLine};
pub use run::{make_item, run, writes, RunSummary};
pub use sensor::SensorPipeline;
pub use shard::{Shard, MAX_SHARDS};
pub use tarcheck::verify_tars;
pub use webdataset::{
    check_shard_bytes, pack, PackSummary, TarIndex, TarShard, DEFAULT_SHARD_BYTES, MAX_SHARD_BYTES,
    MIN_SHARD_BYTES,
};
