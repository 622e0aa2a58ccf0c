//! Every cap on what an input may ask for, in one place (layer 0).
//!
//! A cap bounds the memory or time a request can take: pixels, entries of a
//! list, lengths, light. Each is checked where the value is read, before
//! anything is sized by it, and refused with an error naming the value, the
//! cap and where it came from. `docs/limits.md` lists every cap here, and
//! `tests/limits_doc.rs` keeps that list true.

// == pixels and images ==

/// Most pixels (width x height) of an image `augment` takes, px; checked
/// from the shape before any value is read or copied (Python included).
pub const AUGMENT_MAX_PIXELS: u64 = 1 << 26;
/// Most warp instants per pixel of `augment` (the `exact` integrator at
/// 1/32 px spacing reaches it at 128 px of blur), count.
pub const AUGMENT_MAX_WARP_SAMPLES: usize = 4096;
/// Most pixel-samples (pixels x warp instants) of one `augment` image, count.
pub const AUGMENT_MAX_PIXEL_SAMPLES: u64 = 1 << 33;
/// Largest `blur_px` (mean path of an augmentation's blur), px.
pub const AUGMENT_MAX_BLUR_PX: f64 = 2000.0;

// == light and sensor noise ==

// == lists and entries ==

// == lens profiles ==

// == streams (live) ==

// == datasets ==
