//! Writing the maps of many frames (`mmbm frames --maps DIR`): one EXR per
//! frame, computed on the backend chosen ([`super::maps_gpu::resolve`]: the
//! GPU kernel, or the f64 path of [`super::maps`]).

use super::maps::{frame_maps, MapRays, MapsJob};
use super::SeriesOptions;
use crate::error::{Error, Result};
use crate::io::frames::VideoFrame;
use crate::model::log::ImuLog;

/// The file name of frame `index`'s maps in a `--maps` directory.
pub fn file_name(index: usize) -> String {
    format!("frame_{index:06}.exr")
}

/// What [`write_maps`] wrote.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MapsWritten {
    /// Per written frame: its row, mean path (px) and share of pixels with a value.
    pub written: Vec<(usize, f64, f64)>,
    /// Rows without maps: their span leaves the log or crosses a gap in it.
    pub skipped: Vec<usize>,
    /// The GPU adapter that computed them, `None` for the CPU path.
    pub adapter: Option<String>,
}

/// Writes the maps of the frames `which` (rows of `frames`) to `dir`
/// (created if missing; a camera over [`super::maps::MAX_MAP_PIXELS`] is
/// refused first), one EXR each ([`file_name`]), each file
/// atomically; a frame whose span leaves the log or crosses a gap in it
/// gets none (listed in [`MapsWritten::skipped`]). `backend`: where the
/// maps are computed ([`super::maps_gpu::resolve`]: the GPU kernel or the
/// f64 path).
pub fn write_maps(
    log: &ImuLog,
    opts: &SeriesOptions,
    frames: &[VideoFrame],
    which: &[usize],
    dir: &std::path::Path,
    backend: crate::gpu::Backend,
) -> Result<MapsWritten> {
    super::maps::check_size(&opts.scene.camera)?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let rays = MapRays::new(&opts.scene.camera)?;
    let mut gpu = super::maps_gpu::resolve(backend, &opts.scene.camera)?;
    let mut out = MapsWritten {
        adapter: gpu.as_ref().map(|g| g.adapter().to_string()),
        ..Default::default()
    };
    for &k in which {
        crate::cancel::check()?;
        let f = frames.get(k).ok_or_else(|| {
            Error::invalid(
                "maps",
                format!("frame {k} is not in the table ({} rows)", frames.len()),
            )
        })?;
        let job = MapsJob {
            log,
            opts,
            rays: &rays,
            index: k,
            frame: f,
            steps: None,
        };
        let maps = match &mut gpu {
            Some(g) => g.frame_maps(&job)?,
            None => frame_maps(log, opts, &rays, k, f, None)?,
        };
        match maps {
            Some(m) => {
                m.write_exr(&dir.join(file_name(k)))?;
                let (mean, valid) = m.mean_path_px();
                out.written.push((k, mean, valid));
            }
            None => out.skipped.push(k),
        }
    }
    Ok(out)
}
