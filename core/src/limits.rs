//! Every cap on what an input may ask for, in one place (layer 0).
//!
//! A cap bounds the memory or time a request can take: pixels, entries of a
//! list, lengths, light. Each is checked where the value is read, before
//! anything is sized by it, and refused with an error naming the value, the
//! cap and where it came from. `docs/limits.md` lists every cap here, and
//! `cli/tests/docs/limits_doc.rs` keeps that list true.

use crate::error::{Error, Result};

// == pixels and images ==

/// Most pixels of a rendered frame (`render`, datasets, the experiment),
/// px. Memory: about 24 bytes each with maps.
pub const MAX_PIXELS: u64 = 1 << 26;

/// Most pixel-samples of one rendered frame (pixels x samples per pixel): work.
pub const MAX_PIXEL_SAMPLES: u64 = 1 << 40;

/// Most cells of a flow field (`flow`, `field::flow_field`, Python), cells.
pub const MAX_FIELD_PIXELS: u64 = 1 << 26;

/// Most pixels an input PNG/JPEG may declare in its header (checked before
/// decoding), px: 2^28, 1 GiB as 8-bit RGBA.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;

/// Most pixels of one frame's blur maps (`frames --maps`, Python's
/// `frames(maps=True)`), px: the camera's width x height, checked before
/// anything is allocated, on every backend. The f64 path holds about 58
/// bytes per pixel at its peak (measured: 349 MB for 3000 x 2000; a cached
/// ray of 16 bytes, the five f32 channels twice, the EXR being written), so
/// 2^25 pixels (a 5.8k x 5.8k sensor; 8K UHD's 33.2 million fit) take
/// about 2 GB.
pub const MAX_MAP_PIXELS: u64 = 1 << 25;

/// Most pixels an image given to `mmbm assess` (and `assess::load_grey`)
/// may declare, px, checked from its header before it is decoded. The
/// metrics hold about 64 bytes per pixel at their peak (measured: 1.0 GB
/// for a 4000 x 4000 grey PNG: the decoded image, its grey copy, edge maps,
/// f64 gradients), so 2^25 pixels (8K UHD fits) take about 2.1 GB.
pub const MAX_ASSESS_PIXELS: u64 = 1 << 25;

/// Refuses `width` x `height` over `max` pixels, naming `what` (a flag, key
/// or file) and `doing` (what would have been sized by it).
pub fn check_pixels(what: &str, doing: &str, width: u64, height: u64, max: u64) -> Result<()> {
    let pixels = width as u128 * height as u128;
    if pixels > max as u128 {
        return Err(Error::invalid(
            what,
            format!("{width}x{height} = {pixels} pixels: {doing} takes at most {max} pixels"),
        ));
    }
    Ok(())
}

/// Most pixels (width x height) of an image `augment` takes, px; checked
/// from the shape before any value is read or copied (Python included).
pub const AUGMENT_MAX_PIXELS: u64 = 1 << 26;

/// Most warp instants per pixel of `augment` (the `exact` integrator at
/// 1/32 px spacing, with its 1.1 margin, reaches it at about 116 px of
/// blur at the peak speed), count.
pub const AUGMENT_MAX_WARP_SAMPLES: usize = 4096;

/// Most pixel-samples (pixels x warp instants) of one `augment` image, count.
pub const AUGMENT_MAX_PIXEL_SAMPLES: u64 = 1 << 33;

/// Largest `blur_px` (mean path of an augmentation's blur), px.
pub const AUGMENT_MAX_BLUR_PX: f64 = 2000.0;

// == light and sensor noise ==

/// Most light a sensor may be given, e-/s for a white pixel (`--light`,
/// `[camera.noise] phi_e_per_s` of camera files, dataset and experiment
/// configs, `map.lights_e_per_s`, `task:...:light=`, Python). No real pixel
/// holds more than about 1e6 to 1e7 electrons (its full well), so 1e12 e-/s
/// fills even that in 10 us: generous for any exposure, and finite.
pub const MAX_LIGHT_E_PER_S: f64 = 1e12;

/// Most illuminance `mmbm light` takes, lux (direct sun is about 1e5).
pub const LIGHT_MAX_LUX: f64 = 1e7;

/// Smallest f-number `mmbm light` takes (0.5: the limit of a lens in air).
pub const LIGHT_MIN_F_NUMBER: f64 = 0.5;

/// Largest f-number `mmbm light` takes.
pub const LIGHT_MAX_F_NUMBER: f64 = 1000.0;

/// Largest pixel pitch `mmbm light` takes, um.
pub const LIGHT_MAX_PIXEL_UM: f64 = 1000.0;

/// Largest mean (electrons) whose shot noise is drawn from the exact
/// Poisson sampler; above it, from the normal approximation `N(mu, mu)`
/// rounded and clamped at 0, which is bounded in time for every mean (the
/// exact samplers lose their precision at huge means, and the one of
/// `rand_distr` 0.4, which the noise used before 0.6, spins near 1e305;
/// 0.6 refuses means above 1.8e19). The difference between the two
/// distributions is of the order of the skewness `1/sqrt(mu)`, at most
/// 3.2e-5 here, and a mean this large is clipped at any real full well.
pub const MAX_EXACT_POISSON_MEAN_E: f64 = 1e9;

/// Refuses a light level that is not finite, not positive or above
/// [`MAX_LIGHT_E_PER_S`], naming where it came from (`what`).
pub fn check_light(what: &str, phi_e_per_s: f64) -> Result<f64> {
    if !(phi_e_per_s.is_finite() && phi_e_per_s > 0.0) {
        return Err(Error::invalid(
            what,
            format!("must be > 0 e-/s, got {phi_e_per_s}"),
        ));
    }
    if phi_e_per_s > MAX_LIGHT_E_PER_S {
        return Err(Error::invalid(
            what,
            format!(
                "{phi_e_per_s:e} e-/s is above the cap of {MAX_LIGHT_E_PER_S:e} e-/s \
                 (a white pixel would pass any real full well in under 10 us)"
            ),
        ));
    }
    Ok(phi_e_per_s)
}

// == lists and entries ==

/// Most entries of each list of an experiment config (`policies`, `walks`,
/// `sweep_exposures_s`, `map.lights_e_per_s`, `map.gaits`, `map.boards`,
/// `map.policies`, `map.grid_ms`; `seeds` and `map.seeds` had this cap
/// already): each entry multiplies the frames rendered, and 100 of them
/// already run for hours.
pub const MAX_LIST_ENTRIES: usize = 100;

/// Refuses a list of `len` entries over `max`, naming its key.
pub fn check_len(key: &str, len: usize, max: usize) -> Result<()> {
    if len > max {
        return Err(Error::invalid(
            key,
            format!("{len} entries: at most {max} are accepted"),
        ));
    }
    Ok(())
}

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

/// Smallest WebDataset tar shard size `--shard-bytes` accepts, bytes (64 KiB:
/// a few tar blocks per item file at least).
pub const MIN_SHARD_BYTES: u64 = 1 << 16;

/// Largest WebDataset tar shard size `--shard-bytes` accepts, bytes (1 TiB:
/// far past WebDataset's usual 1 GB; a tar shard is read as one stream).
pub const MAX_SHARD_BYTES: u64 = 1 << 40;

// == sync (video decoding) ==

/// Most frames `mmbm sync` decodes from one video, frames: checked from
/// ffprobe's duration x frame rate before decoding, and again while it
/// decodes. Memory: about 0.4 KB of patch sums per frame (80 MB at the cap,
/// 55 minutes at 60 fps).
pub const SYNC_MAX_FRAMES: usize = 200_000;

/// Widest analysis image of `mmbm sync`, px: ffmpeg scales every frame down
/// to it (aspect kept) before mmbm sees it, so a frame held is at most
/// 480 x 480 grey bytes whatever the video's size.
pub const SYNC_MAX_WIDTH_PX: u32 = 480;

/// Largest `mmbm sync --search` (half width of the offset search), s: the
/// search's work grows with it (one score per 2 ms).
pub const SYNC_MAX_SEARCH_S: f64 = 60.0;

// == clip (mmbm clip: a gyro log rendered as a video) ==

/// Most frames `mmbm clip` renders into one video, frames: checked from
/// --duration x --fps before any work (about 55 minutes at 30 fps; each
/// frame is rendered, encoded and forgotten, so memory is one frame).
pub const CLIP_MAX_FRAMES: usize = 100_000;

/// Highest `mmbm clip --fps`, frames/s.
pub const CLIP_MAX_FPS: f64 = 1000.0;

/// Most pixels of one `mmbm clip` frame, px (4096 x 4096: a 4K frame fits;
/// about 200 MB of linear RGB and blur maps in memory per frame).
pub const CLIP_MAX_PIXELS: u64 = 1 << 24;

// == video frames (frames --image-metric, --extract) ==

/// Widest a decoded frame is scored at by `frames --image-metric`, px:
/// ffmpeg scales each frame to at most this width (aspect kept) before the
/// image metric, so one frame in memory is at most 640 x 640 x aspect bytes
/// (grey), and the metric's time per frame is bounded.
pub const SCORE_MAX_WIDTH: u32 = 640;

/// Longest ffmpeg `select` expression `frames --extract` passes on
/// ffmpeg's command line, bytes (Linux takes 128 KiB per argument); a
/// longer choice is refused before ffmpeg runs.
pub const MAX_SELECT_EXPR_BYTES: usize = 100_000;

// == camera files (telemetry) ==

/// Largest `moov` box of an MP4 read for its gyro track (`mmbm::telemetry`),
/// bytes: the box is read whole (the sample tables); an hour of 4K GoPro
/// video has a `moov` of a few MB. The video itself (`mdat`) is never read,
/// only the telemetry payloads it points at.
pub const MAX_MP4_MOOV_BYTES: u64 = 64 << 20;

/// Most boxes walked at the top level of an MP4 and inside its `moov`,
/// boxes (time: each is a seek or a slice).
pub const MAX_MP4_BOXES: usize = 1 << 16;

/// Largest single GPMF payload (one `gpmd` sample) read, bytes; GoPro's are
/// a few kB (one second of telemetry).
pub const MAX_GPMF_PAYLOAD_BYTES: u64 = 16 << 20;

/// Deepest nesting of GPMF KLV containers followed, levels (GoPro uses 2:
/// DEVC > STRM).
pub const MAX_GPMF_DEPTH: usize = 8;

/// Most gyro samples read from one camera file or app CSV, samples: about
/// 80 bytes each in memory (670 MB at the cap), 44 minutes at 3200 Hz.
pub const MAX_TELEMETRY_SAMPLES: usize = 1 << 23;

/// Most entries of a Gyroflow project's `offsets` map (sync points),
/// entries.
pub const MAX_PROJECT_OFFSETS: usize = 100_000;
