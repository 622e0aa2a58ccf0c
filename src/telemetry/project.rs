//! Gyroflow project files (`.gyroflow`, JSON), read as Gyroflow's
//! `StabilizationManager::import_gyroflow_data` (`src/core/lib.rs`) reads
//! them:
//!
//! - `gyro_source.raw_imu`: the embedded samples, an array of
//!   `{"timestamp_ms": T, "gyro": [x, y, z]}` (ms; deg/s, the file's own
//!   axes, as telemetry-parser's `normalized_imu` gives them). A compressed
//!   `raw_imu` (a base91 string, Gyroflow's default export) is refused with
//!   what to do: export the project with "Include processed data" off, or
//!   give the gyro file itself.
//! - `gyro_source.imu_orientation` (Gyroflow's axis letters, default `XYZ`)
//!   and `gyro_source.rotation` (`[pitch, roll, yaw]` degrees or null):
//!   applied as for a `.gcsv` log ([`crate::io::gcsv::camera_matrix`],
//!   [`crate::io::gcsv::gyroflow_rotation`]).
//! - Without embedded samples, `gyro_source.filepath` (else `videofile`):
//!   the file of that *name* in the project's own folder is read (the way
//!   Gyroflow relinks a moved project); a name that is not a plain file name
//!   (`..`, a folder) is refused, so a project never reads outside its folder.
//! - `offsets`: Gyroflow's sync points, video time (us, the key) to offset
//!   (ms). Gyroflow looks the gyro up at `t_video - offset(t_video)`
//!   (`quat_at_timestamp`), the offset linear between points and constant
//!   beyond; each sample at gyro time `t` is moved to the video time that
//!   looks it up (solved by three fixed-point steps; exact for one offset).
//! - `video_info.fps`, `stabilization.frame_readout_time` (ms; its
//!   magnitude, the log's rolling-shutter readout) and `calibration_data`
//!   (the lens profile, kept for `--camera`).

use super::mp4::bad;
use super::{CameraFileInfo, Format};
use crate::error::Result;
use crate::limits::{check_len, MAX_PROJECT_OFFSETS, MAX_TELEMETRY_SAMPLES};
use glam::{DMat3, DVec3};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// True when `text` (the start of a file) is a JSON object that names
/// itself a Gyroflow data file or has a `gyro_source`.
pub fn looks_like_project(head: &[u8]) -> bool {
    let s = String::from_utf8_lossy(head);
    s.trim_start().starts_with('{')
        && (s.contains("Gyroflow data file") || s.contains("\"gyro_source\""))
}

/// What a project holds: its samples (s, rad/s camera frame; offsets not
/// yet applied) or the gyro file it points at, and its metadata.
pub struct Project {
    /// Embedded samples, or None.
    pub samples: Option<Vec<(f64, DVec3)>>,
    /// The gyro file to read instead (in the project's folder).
    pub gyro_file: Option<PathBuf>,
    /// Sync points: (video time s, offset s), sorted.
    pub offsets: Vec<(f64, f64)>,
    /// The metadata.
    pub info: CameraFileInfo,
}

fn num(path: &Path, key: &str, v: &Value) -> Result<f64> {
    v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
        bad(
            path,
            key,
            format!(
                "expected a finite number, got {}",
                crate::error::clip(&v.to_string(), 64)
            ),
        )
    })
}

/// Reads the project `path`.
pub fn read(path: &Path) -> Result<Project> {
    let text = crate::bounded::read_text(path)?;
    let doc: Value = serde_json::from_str(&text).map_err(|e| bad(path, "JSON", e))?;
    let Some(root) = doc.as_object() else {
        return Err(bad(path, "JSON", "expected an object (a Gyroflow project)"));
    };
    let mut info = CameraFileInfo::new(Format::GyroflowProject);
    let gs = root
        .get("gyro_source")
        .ok_or_else(|| bad(path, "gyro_source", "missing: not a Gyroflow project"))?;
    let orientation = match gs.get("imu_orientation") {
        None | Some(Value::Null) => "XYZ".to_string(),
        Some(Value::String(s)) => s.clone(),
        Some(v) => {
            return Err(bad(
                path,
                "gyro_source.imu_orientation",
                format!("expected a string, got {v}"),
            ))
        }
    };
    let mut m = crate::io::gcsv::camera_matrix(&orientation)
        .map_err(|e| bad(path, "gyro_source.imu_orientation", e))?;
    if let Some(r) = gs.get("rotation").filter(|v| !v.is_null()) {
        let a = r.as_array().filter(|a| a.len() == 3).ok_or_else(|| {
            bad(
                path,
                "gyro_source.rotation",
                "expected [pitch, roll, yaw] (degrees) or null",
            )
        })?;
        let k = "gyro_source.rotation";
        let angles = [
            num(path, k, &a[0])?,
            num(path, k, &a[1])?,
            num(path, k, &a[2])?,
        ];
        if angles != [0.0; 3] {
            let g = crate::io::gcsv::gyroflow_rotation(angles).map_err(|e| bad(path, k, e))?;
            m = crate::io::gcsv::GYROFLOW_TO_CAMERA
                * g
                * crate::io::gcsv::GYROFLOW_TO_CAMERA.transpose()
                * m;
        }
    }
    let samples = match gs.get("raw_imu") {
        None | Some(Value::Null) => None,
        Some(Value::String(_)) => return Err(bad(
            path,
            "gyro_source.raw_imu",
            "compressed (base91) samples are not read: export the project from Gyroflow without \
                 \"Include processed data\", or give the gyro file itself (--gyro VIDEO.mp4)",
        )),
        Some(Value::Array(a)) => Some(raw_imu(path, a, m)?),
        Some(v) => {
            return Err(bad(
                path,
                "gyro_source.raw_imu",
                format!("expected an array, got {}", type_name(v)),
            ))
        }
    };
    let gyro_file = if samples.is_none() {
        Some(referenced(path, gs, root)?)
    } else {
        None
    };
    let offsets = offsets(path, root.get("offsets"))?;
    if let Some(fps) = root
        .get("video_info")
        .and_then(|v| v.get("fps"))
        .filter(|v| !v.is_null())
    {
        let f = num(path, "video_info.fps", fps)?;
        info.fps = (f > 0.0).then_some(f);
    }
    if let Some(r) = root
        .get("stabilization")
        .and_then(|v| v.get("frame_readout_time"))
        .filter(|v| !v.is_null())
    {
        let ms = num(path, "stabilization.frame_readout_time", r)?;
        info.readout_s = (ms != 0.0).then_some(ms.abs() / 1000.0);
    }
    info.lens_profile = root
        .get("calibration_data")
        .filter(|v| v.as_object().is_some_and(|o| !o.is_empty()))
        .cloned();
    info.offsets = offsets.clone();
    Ok(Project {
        samples,
        gyro_file,
        offsets,
        info,
    })
}

fn type_name(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

fn raw_imu(path: &Path, a: &[Value], m: DMat3) -> Result<Vec<(f64, DVec3)>> {
    if a.len() > MAX_TELEMETRY_SAMPLES {
        return Err(bad(
            path,
            "gyro_source.raw_imu",
            format!(
                "{} samples, over the cap of {MAX_TELEMETRY_SAMPLES}",
                a.len()
            ),
        ));
    }
    let k = std::f64::consts::PI / 180.0;
    let mut out = Vec::with_capacity(a.len());
    for (i, s) in a.iter().enumerate() {
        let place = format!("gyro_source.raw_imu[{i}]");
        let t = num(
            path,
            &format!("{place}.timestamp_ms"),
            s.get("timestamp_ms").unwrap_or(&Value::Null),
        )?;
        let g = match s.get("gyro") {
            None | Some(Value::Null) => continue, // an accelerometer-only row
            Some(Value::Array(g)) if g.len() == 3 => g,
            Some(v) => {
                return Err(bad(
                    path,
                    &format!("{place}.gyro"),
                    format!(
                        "expected [x, y, z] (deg/s), got {}",
                        crate::error::clip(&v.to_string(), 64)
                    ),
                ))
            }
        };
        let key = format!("{place}.gyro");
        let w = DVec3::new(
            num(path, &key, &g[0])?,
            num(path, &key, &g[1])?,
            num(path, &key, &g[2])?,
        );
        out.push((t / 1000.0, m * (w * k)));
    }
    if out.is_empty() {
        return Err(bad(
            path,
            "gyro_source.raw_imu",
            "no sample with a gyro value",
        ));
    }
    Ok(out)
}

/// The gyro file a project without samples points at: that name in the
/// project's folder.
fn referenced(path: &Path, gs: &Value, root: &serde_json::Map<String, Value>) -> Result<PathBuf> {
    let (key, v) = match gs
        .get("filepath")
        .and_then(Value::as_str)
        .filter(|s| !s.is_empty())
    {
        Some(s) => ("gyro_source.filepath", s),
        None => match root
            .get("videofile")
            .and_then(Value::as_str)
            .filter(|s| !s.is_empty())
        {
            Some(s) => ("videofile", s),
            None => {
                return Err(bad(
                    path,
                    "gyro_source",
                    "no raw_imu samples and no filepath or videofile to read them from",
                ))
            }
        },
    };
    let s = v.strip_prefix("file://").unwrap_or(v);
    let name = s.rsplit(['/', '\\']).next().unwrap_or("");
    if name.is_empty() || name == "." || name == ".." {
        return Err(bad(
            path,
            key,
            format!("'{}' names no file", crate::error::clip(v, 128)),
        ));
    }
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let file = dir.join(name);
    if !file.is_file() {
        return Err(bad(
            path,
            key,
            format!(
                "the project holds no samples and points at '{}'; its file name is looked for in the project's folder only, and {} is not there",
                crate::error::clip(v, 128),
                file.display()
            ),
        ));
    }
    Ok(file)
}

fn offsets(path: &Path, v: Option<&Value>) -> Result<Vec<(f64, f64)>> {
    let map = match v {
        None | Some(Value::Null) => return Ok(Vec::new()),
        Some(Value::Object(m)) => m,
        Some(v) => {
            return Err(bad(
                path,
                "offsets",
                format!(
                    "expected an object (timestamp us: offset ms), got {}",
                    type_name(v)
                ),
            ))
        }
    };
    check_len("offsets", map.len(), MAX_PROJECT_OFFSETS).map_err(|e| bad(path, "offsets", e))?;
    let mut out = Vec::with_capacity(map.len());
    for (k, v) in map {
        let place = format!("offsets.{}", crate::error::clip(k, 32));
        let us: i64 = k.trim().parse().map_err(|_| {
            bad(
                path,
                &place,
                "the key must be a whole number of microseconds",
            )
        })?;
        let ms = num(path, &place, v)?;
        out.push((us as f64 * 1e-6, ms * 1e-3));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(out)
}

/// The offset at video time `t`, s, as Gyroflow's `offset_at_timestamp`:
/// linear between points, the end values beyond, 0 without points.
pub fn offset_at(offsets: &[(f64, f64)], t: f64) -> f64 {
    match offsets {
        [] => 0.0,
        [(_, o)] => *o,
        _ => {
            let i = offsets.partition_point(|p| p.0 <= t);
            if i == 0 {
                return offsets[0].1;
            }
            if i == offsets.len() {
                return offsets[i - 1].1;
            }
            let (a, b) = (offsets[i - 1], offsets[i]);
            a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
        }
    }
}

/// The video time of a sample at gyro time `t`: `tv` with
/// `tv - offset(tv) = t`, by three fixed-point steps (each multiplies the
/// error by the offset's slope, a few ms per s at most: under 1e-9 s after
/// three; exact for a constant offset).
pub fn video_time(offsets: &[(f64, f64)], t: f64) -> f64 {
    let mut tv = t + offset_at(offsets, t);
    for _ in 0..2 {
        tv = t + offset_at(offsets, tv);
    }
    tv
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_interpolate_clamp_and_invert_as_gyroflow_reads_them() {
        assert_eq!(offset_at(&[], 3.0), 0.0);
        assert_eq!(offset_at(&[(5.0, 0.02)], -1.0), 0.02);
        let o = [(0.0, 0.01), (10.0, 0.03)];
        assert_eq!(offset_at(&o, -1.0), 0.01);
        assert_eq!(offset_at(&o, 11.0), 0.03);
        assert!((offset_at(&o, 5.0) - 0.02).abs() < 1e-15);
        // tv - off(tv) = t: with off = 0.01 + 0.002 tv, tv = (t + 0.01) / 0.998.
        for t in [0.0, 1.0, 4.5, 9.0] {
            let tv = video_time(&o, t);
            assert!((tv - offset_at(&o, tv) - t).abs() < 1e-9, "{t}: {tv}");
        }
        // One offset: exact.
        assert_eq!(video_time(&[(0.0, -0.005)], 2.0), 1.995);
    }

    #[test]
    fn a_project_is_known_by_its_title_or_gyro_source() {
        assert!(looks_like_project(b"  {\"title\": \"Gyroflow data file\""));
        assert!(looks_like_project(b"{\"gyro_source\": {}}"));
        assert!(!looks_like_project(b"{\"fisheye_params\": {}}"));
        assert!(!looks_like_project(b"t,wx,wy,wz"));
    }
}
