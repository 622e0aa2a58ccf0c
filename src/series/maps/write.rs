//! Writing the maps of many frames (`mmbm frames --maps DIR`): one EXR per
//! frame, computed on the backend chosen ([`super::gpu::resolve`]: the
//! GPU kernel, or the f64 path of [`super`]).
//!
//! All or nothing: [`stage_maps`] writes every map into a hidden staging
//! folder (`.mmbm-maps-PID-N`: inside DIR when it exists, else in its
//! nearest existing ancestor), registered for
//! [`crate::io::atomic::remove_pending`] (an interrupt removes it);
//! [`StagedMaps::publish`] moves the maps into DIR once every other output
//! of the command was written. A failure or an interrupt before then leaves
//! DIR as it was.

use super::{frame_maps, MapRays, MapsJob, CHANNELS};
use crate::error::{Error, Result};
use crate::io::atomic::PendingDir;
use crate::io::frames::VideoFrame;
use crate::model::log::ImuLog;
use crate::series::select::FrameName;
use crate::series::SeriesOptions;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The file name of frame `index`'s maps in a `--maps` directory with the
/// default [`MapsOutput`] (`frame_%06d.exr` numbered from 1, as the image
/// list's default `frame_%06d.png`).
pub fn file_name(index: usize) -> String {
    MapsOutput::default().name(index)
}

/// How the maps are stored: the samples' type and the channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MapsFormat {
    /// Half floats (f16, about 3 significant digits; the default: half the
    /// size, far finer than a blur map needs).
    #[default]
    Half,
    /// 32-bit floats.
    Float,
}

impl std::str::FromStr for MapsFormat {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "half" => Ok(Self::Half),
            "float" => Ok(Self::Float),
            _ => Err(Error::invalid(
                "--maps-format",
                format!("'{s}': expected half or float"),
            )),
        }
    }
}

/// The channels to write: indices into [`CHANNELS`], from a list of their
/// names (`path_px,disp.u`; written in [`CHANNELS`]' order, each once).
pub fn parse_channels(s: &str) -> Result<Vec<usize>> {
    let mut out = Vec::new();
    for name in s.split(',').map(str::trim) {
        let i = CHANNELS.iter().position(|&c| c == name).ok_or_else(|| {
            Error::invalid(
                "--maps-channels",
                format!("'{name}': not a channel (they are {})", CHANNELS.join(", ")),
            )
        })?;
        out.push(i);
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// How the maps are named and stored (see [`MapsFormat`], [`parse_channels`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MapsOutput {
    /// The file name, printf style (the image list's `--frame-name` with
    /// the extension `.exr`).
    pub name: FrameName,
    /// The number of row 0 in the names (`--frame-start`).
    pub start: u64,
    /// Half or float samples.
    pub format: MapsFormat,
    /// Channels written, indices into [`CHANNELS`] in order.
    pub channels: Vec<usize>,
}

impl Default for MapsOutput {
    fn default() -> Self {
        MapsOutput {
            name: "frame_%06d.exr".parse().expect("a valid name"),
            start: 1,
            format: MapsFormat::Float,
            channels: (0..CHANNELS.len()).collect(),
        }
    }
}

impl MapsOutput {
    /// The file name of row `index`'s maps.
    pub fn name(&self, index: usize) -> String {
        self.name.name((index as u64).saturating_add(self.start))
    }
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
/// (created if missing; a camera over [`super::MAX_MAP_PIXELS`] is
/// refused first), one EXR each ([`file_name`]), all or none
/// ([`stage_maps`], then [`StagedMaps::publish`]); a frame whose span leaves
/// the log or crosses a gap in it gets none (listed in
/// [`MapsWritten::skipped`]). `backend`: where the maps are computed
/// ([`super::gpu::resolve`]: the GPU kernel or the f64 path).
pub fn write_maps(
    log: &ImuLog,
    opts: &SeriesOptions,
    frames: &[VideoFrame],
    which: &[usize],
    dir: &Path,
    backend: crate::gpu::Backend,
) -> Result<MapsWritten> {
    stage_maps(
        log,
        opts,
        frames,
        which,
        dir,
        backend,
        &MapsOutput::default(),
    )?
    .publish()
}

/// True for the name of a file [`write_maps`] may write in its folder
/// (any `.exr` directly in it, whatever `--frame-name` names them),
/// relative to the folder.
pub fn is_map_name(rel: &Path) -> bool {
    rel.components().count() == 1
        && rel
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
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
    out: &MapsOutput,
) -> Result<StagedMaps> {
    if out.name.has_folder() {
        return Err(Error::invalid(
            "--frame-name",
            "the maps are named after it: give a name without a folder with --maps",
        ));
    }
    super::check_size(&opts.scene.camera)?;
    let mut staged = StagedMaps::empty(dir)?;
    let root = staged.root().to_path_buf();
    let rays = MapRays::new(&opts.scene.camera)?;
    let mut gpu = super::gpu::resolve(backend, &opts.scene.camera)?;
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
                let name = out.name(k);
                m.write_exr_as(
                    &root.join(&name),
                    out.format == MapsFormat::Half,
                    &out.channels,
                )
                // An interrupt may remove the staging folder under the write:
                // the interrupt is the error, not the missing folder.
                .map_err(|e| crate::cancel::check().err().unwrap_or(e))?;
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
    /// An empty staging folder for `dir` (see the module docs), for files
    /// written into [`Self::root`] and named with [`Self::add`] (the frames
    /// `frames --extract` extracts).
    pub fn empty(dir: &Path) -> Result<StagedMaps> {
        let base = if dir.is_dir() {
            dir.to_path_buf()
        } else {
            nearest_existing(dir)?
        };
        let stage = PendingDir::create(&base.join(stage_name()))?;
        Ok(StagedMaps {
            written: MapsWritten::default(),
            names: Vec::new(),
            dir: dir.to_path_buf(),
            stage: Some(stage),
        })
    }

    /// The staging folder.
    pub fn root(&self) -> &Path {
        self.stage.as_ref().map_or(Path::new(""), |s| s.path())
    }

    /// Files written into [`Self::root`], moved into the folder by [`Self::publish`].
    pub fn add(&mut self, names: Vec<String>) {
        self.names.extend(names);
    }

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
        assert!(is_map_name(Path::new("img12.exr")));
        assert!(!is_map_name(Path::new("t.csv")));
        assert!(!is_map_name(Path::new("sub/frame_000012.exr")));
        // Named as the image list's default names the frame (numbered from 1).
        assert_eq!(file_name(7), "frame_000008.exr");
        let out = MapsOutput {
            name: "img_%04d.png"
                .parse::<FrameName>()
                .unwrap()
                .with_extension("exr"),
            start: 0,
            ..MapsOutput::default()
        };
        assert_eq!(out.name(5), "img_0005.exr");
        assert_eq!(parse_channels("path_px, disp.u,path_px").unwrap(), [0, 2]);
        let e = parse_channels("blur").unwrap_err().to_string();
        assert!(e.contains("--maps-channels") && e.contains("flow.v"), "{e}");
        assert!(is_map_name(Path::new(&file_name(7))));
    }
}
