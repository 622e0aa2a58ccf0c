//! `mmbm dataset`: blur datasets, sharded on SLURM job arrays or Kubernetes
//! Indexed Jobs.

use clap::Args;
use mmbm::error::{Error, Result};
use mmbm_lab::dataset::{self, DatasetConfig, Shard};
use std::path::PathBuf;

/// Generate a blur dataset: sharp/blurred pairs, flow and blur maps, a manifest.
#[derive(Args, Debug)]
#[command(
    after_help = "Each item i (0-based) depends only on the configuration and i, so any split
of the work gives the same bytes. Item files: DIR/items/NNNNNNNN/{blurred,sharp}.{exr,png}
(linear EXR, sRGB PNG), flow.exr (flow.u, flow.v at exposure start, px/s), maps.exr (path_px,
disp_px, speed_px_s), item.json (its manifest line: every parameter, the instantaneous MMBM at
exposure start and the exposure MMBM, file sizes and SHA-256; the item's seed as a decimal string, so
every number loads as int64 in Arrow / Hugging Face datasets). The sharp frame shows the middle of
the motion by default (sharp = \"mid\", as GoPro / REDS pair a blurred frame with its middle frame;
\"start\" or \"end\" in the configuration). A rerun skips complete items; DIR/dataset.json holds the
configuration's fingerprint, and a run with another configuration is refused (use a new --out);
a larger count grows the set (the items made are kept), a smaller one is refused.

Without --config the defaults are used, textures included: textures = \"builtin:\" is the five
textures compiled into mmbm (CC0 / public domain, from scikit-image), so it runs from any
directory. Relative paths in a configuration file are relative to that file's folder.

Sharding: --shard K/N (K from 1) makes the items with i mod N = K-1 and writes
DIR/manifest.part-K-of-N.jsonl; without --shard, a SLURM job array (SLURM_ARRAY_TASK_ID,
SLURM_ARRAY_TASK_COUNT, SLURM_ARRAY_TASK_MIN) or a Kubernetes Indexed Job
(JOB_COMPLETION_INDEX, with --shard-count N) picks the shard; otherwise the whole set is made
and DIR/manifest.jsonl written. --merge joins the parts into DIR/manifest.jsonl.

WebDataset: --format webdataset also packs the verified set into DIR/webdataset/mmbm-NNNNNN.tar
(at most --shard-bytes each, ~1 GB by default; one sample per item, its members keyed by the
8-digit index: KEY.json, KEY.blurred.exr, KEY.blurred.png, KEY.sharp.exr, KEY.sharp.png,
KEY.flow.exr, KEY.maps.exr) and DIR/webdataset/index.json (each shard's items, size, SHA-256).
The tar bytes depend only on the items, so a sharded run packed at --merge gives the same tars as
a single run; a rerun keeps complete shards. One packing at a time (a second is refused), all or
nothing (DIR/webdataset/ appears complete). --verify also checks the shards against the index.

Examples:
  mmbm dataset --print-config > ds.toml
  mmbm dataset --config ds.toml --out data/
  mmbm dataset --out data/ --count 1000         (the defaults, 1000 items)
  mmbm dataset --config ds.toml --out data/ --shard 2/8
  mmbm dataset --merge --out data/ && mmbm dataset --verify --out data/
  mmbm dataset --config ds.toml --out data/ --format webdataset
  mmbm dataset --merge --format webdataset --out data/   (after a sharded run)
  sbatch --array=1-8 examples/dataset.sbatch     (see examples/dataset-job.yaml for Kubernetes)"
)]
pub struct DatasetArgs {
    /// TOML configuration (missing keys take the defaults; see --print-config). Relative paths in it
    /// (textures, log:PATH) are relative to its folder.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Number of items, over the configuration's `count` (1..=100000000).
    #[arg(long, value_name = "N", conflicts_with_all = ["merge", "verify", "print_config"])]
    pub count: Option<u64>,
    /// Dataset directory.
    #[arg(long, value_name = "DIR", required_unless_present = "print_config")]
    pub out: Option<PathBuf>,
    /// Make shard K of N (K from 1; N at most 1000000 and at most the number of items).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Number of shards of a Kubernetes Indexed Job (with JOB_COMPLETION_INDEX).
    #[arg(long, value_name = "N")]
    pub shard_count: Option<u64>,
    /// Join DIR/manifest.part-K-of-N.jsonl into DIR/manifest.jsonl.
    #[arg(long, conflicts_with_all = ["config", "shard", "verify", "print_config"])]
    pub merge: bool,
    /// Check DIR against DIR/manifest.jsonl (files, sizes, SHA-256, indices, fingerprint; only the item
    /// files inside DIR are read).
    #[arg(long, conflicts_with_all = ["config", "shard", "print_config"])]
    pub verify: bool,
    /// Print the default configuration as TOML and exit.
    #[arg(long)]
    pub print_config: bool,
    /// Output form: `folder` (DIR/items/NNNNNNNN/) or `webdataset` (also the folder packed into
    /// DIR/webdataset/mmbm-NNNNNN.tar shards; a sharded run packs at --merge).
    #[arg(long, value_enum, default_value_t = Format::Folder)]
    pub format: Format,
    /// Most bytes per WebDataset tar shard (only with --format webdataset; 65536 to 2^40; default
    /// 1000000000).
    #[arg(long, value_name = "BYTES", value_parser = shard_bytes)]
    pub shard_bytes: Option<u64>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// `--format`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Item folders only.
    Folder,
    /// Item folders and WebDataset tar shards.
    Webdataset,
}

/// `--shard-bytes`, checked as it is parsed (before any item is made).
fn shard_bytes(s: &str) -> std::result::Result<u64, String> {
    let n: u64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a whole number of bytes"))?;
    dataset::check_shard_bytes(n).map_err(|e| e.to_string())?;
    Ok(n)
}

/// Packs `out` into tar shards when `--format webdataset`.
fn pack(a: &DatasetArgs, out: &std::path::Path) -> Result<()> {
    if a.format != Format::Webdataset {
        return Ok(());
    }
    let bytes = a.shard_bytes.unwrap_or(dataset::DEFAULT_SHARD_BYTES);
    let p = dataset::pack(out, bytes, !a.quiet)?;
    eprintln!(
        "packed {} items into {} WebDataset shard(s) ({} written, {} kept; {:.1} MB) in {}",
        p.items,
        p.shards,
        p.written,
        p.shards - p.written,
        p.bytes as f64 / 1e6,
        out.join("webdataset").display()
    );
    Ok(())
}

/// The shard from `--shard`, else from a scheduler's environment, else all.
fn shard(a: &DatasetArgs) -> Result<(Shard, &'static str)> {
    if let Some(s) = &a.shard {
        return Ok((Shard::parse(s)?, "--shard"));
    }
    let env = |k: &str| std::env::var(k).ok().filter(|v| !v.is_empty());
    let num = |k: &str, v: String| {
        v.trim()
            .parse::<u64>()
            .map_err(|_| Error::invalid(k, format!("'{v}' is not a whole number")))
    };
    if let Some(id) = env("SLURM_ARRAY_TASK_ID") {
        let id = num("SLURM_ARRAY_TASK_ID", id)?;
        let count = env("SLURM_ARRAY_TASK_COUNT").ok_or_else(|| {
            Error::invalid(
                "SLURM_ARRAY_TASK_COUNT",
                "not set (needed with SLURM_ARRAY_TASK_ID)",
            )
        })?;
        let count = num("SLURM_ARRAY_TASK_COUNT", count)?;
        let min = match env("SLURM_ARRAY_TASK_MIN") {
            Some(m) => num("SLURM_ARRAY_TASK_MIN", m)?,
            None => 0,
        };
        let k = id.checked_sub(min).ok_or_else(|| {
            Error::invalid(
                "SLURM_ARRAY_TASK_ID",
                format!("{id} is below SLURM_ARRAY_TASK_MIN {min}"),
            )
        })?;
        return Ok((Shard::new(k.saturating_add(1), count)?, "SLURM job array"));
    }
    if let Some(idx) = env("JOB_COMPLETION_INDEX") {
        let idx = num("JOB_COMPLETION_INDEX", idx)?;
        let n = a.shard_count.ok_or_else(|| {
            Error::invalid(
                "--shard-count",
                "JOB_COMPLETION_INDEX is set (Kubernetes Indexed Job): give the Job's completions as --shard-count N",
            )
        })?;
        return Ok((
            Shard::new(idx.saturating_add(1), n)?,
            "Kubernetes Indexed Job",
        ));
    }
    Ok((Shard::ALL, "no shard"))
}

pub fn run(a: DatasetArgs) -> Result<()> {
    if a.shard_bytes.is_some() && a.format != Format::Webdataset {
        return Err(Error::invalid(
            "--shard-bytes",
            "sizes the WebDataset tar shards: give it with --format webdataset (or leave it out)",
        ));
    }
    if a.print_config {
        print!("{}", DatasetConfig::default().to_toml()?);
        return Ok(());
    }
    let out = a
        .out
        .clone()
        .ok_or_else(|| Error::invalid("dataset", "--out DIR is required"))?;
    if a.merge {
        let n = dataset::merge(&out)?;
        eprintln!(
            "merged {n} items into {}",
            out.join("manifest.jsonl").display()
        );
        return pack(&a, &out);
    }
    if a.verify {
        let n = dataset::verify(&out)?;
        eprintln!(
            "{}: {n} items, every file present and matching",
            out.display()
        );
        if let Some(k) = dataset::verify_tars(&out)? {
            eprintln!(
                "{}: {k} WebDataset shard(s), each matching its index",
                out.display()
            );
        }
        return Ok(());
    }
    let mut cfg = match &a.config {
        Some(p) => DatasetConfig::load(p)?,
        None => DatasetConfig::default(),
    };
    if let Some(n) = a.count {
        if n == 0 || n > dataset::MAX_COUNT {
            return Err(Error::invalid(
                "--count",
                format!("{n} is not in 1..={}", dataset::MAX_COUNT),
            ));
        }
        cfg.count = n;
    }
    // The dataset folder writable and none of its inputs under a name
    // written there, before any work.
    mmbm::io::guard::OutputGuard::new()
        .output_dir("--out", Some(&out), dataset::writes)
        .input("--config", a.config.as_deref())
        .check()?;
    let (sh, from) = shard(&a)?;
    let s = dataset::run(&cfg, &out, sh, !a.quiet)?;
    eprintln!(
        "shard {}/{} ({from}): {} items ({} made, {} already complete) in {:.1} s ({:.1} items/min); wrote {}",
        sh.k,
        sh.n,
        s.items,
        s.made,
        s.items - s.made,
        s.seconds,
        if s.seconds > 0.0 { s.made as f64 / s.seconds * 60.0 } else { 0.0 },
        out.join(sh.manifest_name()).display()
    );
    if sh.n > 1 {
        if a.format == Format::Webdataset {
            eprintln!(
                "WebDataset shards are packed from the whole set: when every shard is done, run \
                 mmbm dataset --merge --format webdataset --out {}",
                out.display()
            );
        }
        return Ok(());
    }
    pack(&a, &out)
}
