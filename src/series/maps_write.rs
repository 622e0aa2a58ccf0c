//! Writing the maps of many frames (`mmbm frames --maps DIR`): one EXR per
//! frame, computed on the backend chosen ([`super::maps_gpu::resolve`]: the
//! GPU kernel, or the f64 path of [`super::maps`]).
//!
//! All or nothing: [`stage_maps`] writes every map into a hidden staging
//! folder (`.mmbm-maps-PID-N`: inside DIR when it exists, else in its
//! nearest existing ancestor), registered for
//! [`crate::io::atomic::remove_pending`] (an interrupt removes it);
//! [`StagedMaps::publish`] moves the maps into DIR once every other output
//! of the command was written. A failure or an interrupt before then leaves
//! DIR as it was.

use super::maps::{frame_maps, MapRays, MapsJob};
use super::SeriesOptions;
use crate::error::{Error, Result};
use crate::io::atomic::PendingDir;
use crate::io::frames::VideoFrame;
use crate::model::log::ImuLog;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

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
/// refused first), one EXR each ([`file_name`]), all or none
/// ([`stage_maps`], then [`StagedMaps::publish`]); a frame whose span leaves
/// the log or crosses a gap in it gets none (listed in
/// [`MapsWritten::skipped`]). `backend`: where the maps are computed
/// ([`super::maps_gpu::resolve`]: the GPU kernel or the f64 path).
pub fn write_maps(
    log: &ImuLog,
    opts: &SeriesOptions,
    frames: &[VideoFrame],
    which: &[usize],
    dir: &Path,
    backend: crate::gpu::Backend,
) -> Result<MapsWritten> {
    stage_maps(log, opts, frames, which, dir, backend)?.publish()
}

/// True for the name of a file [`write_maps`] writes in its folder
/// (`frame_NNNNNN.exr`, six digits or more), relative to the folder.
pub fn is_map_name(rel: &Path) -> bool {
    let s = rel.to_string_lossy();
    s.strip_prefix("frame_")
        .and_then(|r| r.strip_suffix(".exr"))
        .is_some_and(|d| d.len() >= 6 && d.bytes().all(|b| b.is_ascii_digit()))
}

/// Maps computed and written into a staging folder, not yet in their
/// folder: [`Self::publish`] moves them there; dropped unpublished, the
/// staging folder is removed.
pub struct StagedMaps {
    written: MapsWritten,
    names: Vec<String>,
    dir: PathBuf,
    stage: Option<PendingDir>,
}

/// A staging folder's name, unique in this process.
fn stage_name() -> String {
    static N: AtomicUsize = AtomicUsize::new(0);
    format!(
        ".mmbm-maps-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    )
}

/// Computes the maps of the frames `which` (rows of `frames`) and writes
/// them into a staging folder for `dir` (see the module docs); nothing is
/// in `dir` until [`StagedMaps::publish`].
pub fn stage_maps(
    log: &ImuLog,
    opts: &SeriesOptions,
    frames: &[VideoFrame],
    which: &[usize],
    dir: &Path,
    backend: crate::gpu::Backend,
) -> Result<StagedMaps> {
    super::maps::check_size(&opts.scene.camera)?;
    let base = if dir.is_dir() {
        dir.to_path_buf()
    } else {
        nearest_existing(dir)?
    };
    let stage = PendingDir::create(&base.join(stage_name()))?;
    let mut staged = StagedMaps {
        written: MapsWritten::default(),
        names: Vec::new(),
        dir: dir.to_path_buf(),
        stage: None,
    };
    let root = stage.path().to_path_buf();
    staged.stage = Some(stage);
    let rays = MapRays::new(&opts.scene.camera)?;
    let mut gpu = super::maps_gpu::resolve(backend, &opts.scene.camera)?;
    staged.written.adapter = gpu.as_ref().map(|g| g.adapter().to_string());
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
                let name = file_name(k);
                m.write_exr(&root.join(&name))?;
                staged.names.push(name);
                let (mean, valid) = m.mean_path_px();
                staged.written.written.push((k, mean, valid));
            }
            None => staged.written.skipped.push(k),
        }
    }
    Ok(staged)
}

/// The nearest existing folder at or above `dir`.
fn nearest_existing(dir: &Path) -> Result<PathBuf> {
    let mut d = dir;
    loop {
        match d.parent() {
            Some(up) if !up.as_os_str().is_empty() => {
                if up.is_dir() {
                    return Ok(up.to_path_buf());
                }
                d = up;
            }
            _ => return Ok(PathBuf::from(".")),
        }
    }
}

impl StagedMaps {
    /// What was computed (the maps are not yet in their folder).
    pub fn written(&self) -> &MapsWritten {
        &self.written
    }

    /// Moves the maps into their folder (created if missing: the staging
    /// folder is renamed to it; otherwise each file is renamed into it).
    pub fn publish(mut self) -> Result<MapsWritten> {
        let stage = self
            .stage
            .take()
            .ok_or_else(|| Error::invalid("maps", "staging folder already published"))?;
        let root = stage.path().to_path_buf();
        let moved = if self.dir.is_dir() {
            self.names.iter().try_for_each(|n| {
                let to = self.dir.join(n);
                std::fs::rename(root.join(n), &to).map_err(|e| Error::io(&to, e))
            })
        } else {
            match self.dir.parent() {
                Some(up) if !up.as_os_str().is_empty() => {
                    std::fs::create_dir_all(up).map_err(|e| Error::io(up, e))
                }
                _ => Ok(()),
            }
            .and_then(|()| std::fs::rename(&root, &self.dir).map_err(|e| Error::io(&self.dir, e)))
        };
        let _ = std::fs::remove_dir_all(&root);
        drop(stage);
        moved?;
        Ok(std::mem::take(&mut self.written))
    }
}

impl Drop for StagedMaps {
    fn drop(&mut self) {
        if let Some(s) = self.stage.take() {
            let _ = std::fs::remove_dir_all(s.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_names() {
        assert!(is_map_name(Path::new("frame_000012.exr")));
        assert!(is_map_name(Path::new("frame_1234567.exr")));
        assert!(!is_map_name(Path::new("frame_12.exr")));
        assert!(!is_map_name(Path::new("t.csv")));
        assert!(!is_map_name(Path::new("sub/frame_000012.exr")));
        assert_eq!(file_name(7), "frame_000007.exr");
        assert!(is_map_name(Path::new(&file_name(7))));
    }
}
