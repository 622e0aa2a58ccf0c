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

/// Most entries of a Gyroflow lens profile's `compatible_settings` list, and
/// of its `interpolations` map (each list on its own), entries. Gyroflow's
/// database profiles list a few dozen at most; a longer list is refused
/// naming the key and the count before any entry is read. The selection is
/// linear in the profile's size (a 1 MiB profile at most,
/// `MAX_CAMERA_BYTES`): 8192 entries take milliseconds (they took 16 s when
/// each entry copied the whole profile, and 35,000 over 10 minutes).
pub const MAX_PROFILE_ENTRIES: usize = 8192;

// == streams (live) ==

/// Slowest `mmbm live --replay --speed` (times slower than real time is
/// `1 / speed`), dimensionless: at 1e-3 a 1 s log plays for about 17
/// minutes; slower is no replay (1e-300 would wait forever). 0 (as fast as
/// possible) is allowed besides the range.
pub const MIN_REPLAY_SPEED: f64 = 1e-3;

/// Fastest `mmbm live --replay --speed`, dimensionless: at 1e6 a day of
/// log plays in 0.09 s, below the pacing's resolution; for no pacing at
/// all give 0.
pub const MAX_REPLAY_SPEED: f64 = 1e6;

// == datasets ==
