//! Every cap on what an input may ask for, in one place (layer 0).
//!
//! A cap bounds the memory or time a request can take: pixels, entries of a
//! list, lengths, light. Each is checked where the value is read, before
//! anything is sized by it, and refused with an error naming the value, the
//! cap and where it came from. `docs/limits.md` lists every cap here, and
//! `tests/limits_doc.rs` keeps that list true.

// == pixels and images ==

// == light and sensor noise ==

// == lists and entries ==

// == lens profiles ==

// == streams (live) ==

// == datasets ==

/// Smallest WebDataset tar shard size `--shard-bytes` accepts, bytes (64 KiB:
/// a few tar blocks per item file at least).
pub const MIN_SHARD_BYTES: u64 = 1 << 16;

/// Largest WebDataset tar shard size `--shard-bytes` accepts, bytes (1 TiB:
/// far past WebDataset's usual 1 GB; a tar shard is read as one stream).
pub const MAX_SHARD_BYTES: u64 = 1 << 40;
