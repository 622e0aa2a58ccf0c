//! One dataset item: its parameters (drawn from the configuration and the
//! item's own seed) and the files made from them.

use super::config::{DatasetConfig, MotionSource};
use super::sensor::SensorPipeline;
use crate::camera::{Camera, CameraFile};
use crate::error::{Error, Result};
use crate::field::flow_field;
use crate::io::gyro::{read_log, GyroOptions, GyroSample};
use crate::io::images::write_exr;
use crate::io::input::{image_dimensions, is_regular_file};
use crate::metric::{mmbm, Method, Scene};
use crate::model::log::ImuLog;
use crate::model::motion::{Plane, Twist};
use crate::render::{
    self, Backend, FrameMotion, Quality, RenderJob, RenderOutput, SharpAt, Target,
};
use crate::sim::{simulate, GaitConfig};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Seconds of simulated walk before a simulated exposure may start.
const SIM_SETTLE_S: f64 = 1.0;

/// Every parameter of one item (the manifest's `params`): enough to make it
/// again, given the texture folder and the logs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ItemParams {
    /// Item index.
    pub index: u64,
    /// The item's seed (renderer shifts, simulated walk). Written as a
    /// decimal string: a u64 may pass 2^63 - 1, which Arrow (Hugging Face
    /// `datasets`), pandas and Python's C long cannot hold as a number; read
    /// from a string or (items of earlier versions) a number.
    #[serde(with = "seed_text")]
    pub seed: u64,
    /// Texture file name in the texture folder.
    pub texture: String,
    /// Texture width on the target, m.
    pub texture_width_m: f64,
    /// Motion source (`sim:GAIT` or `log:PATH`).
    pub motion: String,
    /// Exposure start on the motion's clock, s.
    pub start_s: f64,
    /// Exposure, s.
    pub exposure_s: f64,
    /// Target distance at exposure start, m.
    pub distance_m: f64,
    /// Target tilt about x and y, degrees.
    pub tilt_deg: [f64; 2],
    /// Image size, px.
    pub resolution: [u32; 2],
    /// Render preset.
    pub quality: String,
    /// Linear velocity used.
    pub use_velocity: bool,
    /// The configuration's `[camera]` keys over the thesis camera at
    /// `resolution` (absent when there are none).
    #[serde(default, skip_serializing_if = "super::config::is_empty")]
    pub camera: CameraFile,
    /// The configuration's `[sensor]` pipeline (absent when there is none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor: Option<SensorPipeline>,
    /// The instant the sharp frame shows (`start`, `mid`, `end`); absent in
    /// items of earlier versions, which were `start`.
    #[serde(default = "SharpAt::legacy")]
    pub sharp: SharpAt,
}

/// A u64 as a decimal string in JSON (read from a string or a number).
mod seed_text {
    use serde::{de, Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&v.to_string())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Seed {
            Text(String),
            Number(u64),
        }
        match Seed::deserialize(d)? {
            Seed::Number(n) => Ok(n),
            Seed::Text(t) => t.parse().map_err(|_| {
                de::Error::custom(format!(
                    "seed {:?} is not a whole number in 0..=18446744073709551615",
                    crate::error::clip(&t, 64)
                ))
            }),
        }
    }
}

/// The seed of item `i` (SplitMix64 of the master seed and `i`).
pub fn item_seed(master: u64, i: u64) -> u64 {
    let mut z = master ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Inputs shared by all items: texture names and decoded logs.
#[derive(Debug, Clone)]
pub struct Sources {
    /// The texture folder.
    pub textures_dir: PathBuf,
    /// Texture file names, sorted.
    pub textures: Vec<String>,
    logs: HashMap<PathBuf, ImuLog>,
}

impl Sources {
    /// Lists the textures (each checked to be a readable image) and reads
    /// the logs of `cfg` (each checked to outlast the longest exposure).
    /// Relative paths are resolved against the configuration's folder
    /// ([`DatasetConfig::resolve`]); errors about them name the key.
    pub fn open(cfg: &DatasetConfig) -> Result<Self> {
        let written = &cfg.textures;
        let (textures_dir, textures) = if super::textures::is_builtin(written) {
            let names = super::textures::BUILTIN_FILES.map(|(n, _)| n.to_string());
            (written.clone(), names.to_vec())
        } else {
            let dir = cfg.resolve(written);
            let textures = list_textures(&dir).map_err(|e| {
                cfg.key_error(
                    "textures",
                    &written.display().to_string(),
                    written,
                    e.to_string(),
                )
            })?;
            (dir, textures)
        };
        let mut logs = HashMap::new();
        let shutter = cfg.camera().shutter;
        let readout_s = shutter.readout_s;
        for m in &cfg.motion {
            if let MotionSource::Log(p) = MotionSource::parse(m)? {
                let bad = |e: String| cfg.key_error("motion", m, &p, e);
                let s = read_log(&cfg.resolve(&p), GyroOptions::default())
                    .map_err(|e| bad(e.to_string()))?;
                let span = s.last().map_or(0.0, |l| l.t) - s.first().map_or(0.0, |f| f.t);
                if span < shutter.busy_s(cfg.exposure_s[1]) {
                    return Err(bad(format!(
                        "the log spans {span:.4} s, shorter than the longest exposure ({} s){}",
                        cfg.exposure_s[1],
                        if readout_s > 0.0 {
                            format!(" plus the camera's readout ({readout_s} s)")
                        } else {
                            String::new()
                        }
                    )));
                }
                // Keyed as written: items name their motion as written.
                logs.insert(p, s);
            }
        }
        Ok(Sources {
            textures_dir,
            textures,
            logs,
        })
    }

    /// The texture `name` (of [`Self::textures`]), decoded.
    pub fn texture(&self, name: &str) -> Result<crate::render::texture::MipTexture> {
        if super::textures::is_builtin(&self.textures_dir) {
            super::textures::load_builtin(name)
        } else {
            crate::render::texture::MipTexture::load(&self.textures_dir.join(name))
        }
    }

    /// Size and SHA-256 (hex) of the texture file `name`.
    pub fn texture_sum(&self, name: &str) -> Result<(u64, String)> {
        if super::textures::is_builtin(&self.textures_dir) {
            return super::textures::builtin_sum(name);
        }
        super::textures::file_sum(&self.textures_dir.join(name))
    }
}

/// The texture images of the folder `dir`, sorted, each checked to be a
/// readable image.
fn list_textures(dir: &Path) -> Result<Vec<String>> {
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut textures = Vec::new();
    for e in rd {
        let e = e.map_err(|e| Error::io(dir, e))?;
        let file_name = e.file_name();
        let lossy = file_name.to_string_lossy();
        let ext = lossy.rsplit('.').next().unwrap_or("").to_ascii_lowercase();
        let p = dir.join(&file_name);
        // Only regular files are textures (a pipe named f.png would
        // block the read; a folder or a device is not an image).
        if ["png", "jpg", "jpeg"].contains(&ext.as_str()) && is_regular_file(&p) {
            // Items and manifests name their texture as text: a name
            // that is not UTF-8 is refused as it is (not read as another).
            let name = file_name.to_str().map(str::to_string).ok_or_else(|| {
                Error::invalid(
                    "texture",
                    format!(
                        "{}: the file name is not valid UTF-8 (items and manifests name \
                             their texture as text); rename the file",
                        crate::error::show_path(&p)
                    ),
                )
            })?;
            image_dimensions(&p).map_err(|e| match e {
                Error::Image { path, message } => Error::Image {
                    path,
                    message: format!("not a readable image: {message}"),
                },
                e => e,
            })?;
            textures.push(name);
        }
    }
    textures.sort();
    if textures.is_empty() {
        return Err(Error::invalid(
            dir.display().to_string(),
            "no texture images (.png, .jpg, .jpeg) in this folder",
        ));
    }
    Ok(textures)
}

impl Sources {
    /// SHA-256 (hex) of the decoded samples of the log `p` (time, angular
    /// and linear velocity, depth, as f64 bits), for the dataset's
    /// fingerprint: what the items are made from, whatever file it came in.
    pub fn log_digest(&self, p: &Path) -> Result<String> {
        use sha2::{Digest, Sha256};
        let s = self.logs.get(p).ok_or_else(|| {
            Error::invalid("motion", format!("log {} was not opened", p.display()))
        })?;
        let mut h = Sha256::new();
        let opt = |h: &mut Sha256, v: Option<&[f64]>| match v {
            Some(v) => {
                h.update([1u8]);
                for x in v {
                    h.update(x.to_bits().to_le_bytes());
                }
            }
            None => h.update([0u8]),
        };
        for x in s.samples() {
            h.update(x.t.to_bits().to_le_bytes());
            opt(&mut h, Some(&x.omega.to_array()));
            opt(
                &mut h,
                x.velocity.map(|v| v.to_array()).as_ref().map(|a| &a[..]),
            );
            opt(&mut h, x.depth.as_ref().map(std::slice::from_ref));
        }
        h.update(format!("{:?}", s.readout()).as_bytes());
        Ok(format!("{:x}", h.finalize()))
    }
}

/// Draws the parameters of item `i` (depends only on `cfg` and `i`).
pub fn plan(cfg: &DatasetConfig, src: &Sources, i: u64) -> Result<ItemParams> {
    let seed = item_seed(cfg.seed, i);
    let cam = cfg.camera();
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut draw = |r: [f64; 2]| {
        let u: f64 = rng.gen();
        r[0] + (r[1] - r[0]) * u
    };
    let exposure_s = draw(cfg.exposure_s);
    let distance_m = draw(cfg.distance_m);
    let tilt_deg = [draw(cfg.tilt_deg), draw(cfg.tilt_deg)];
    let ti = (draw([0.0, 1.0]) * src.textures.len() as f64) as usize;
    let mi = (draw([0.0, 1.0]) * cfg.motion.len() as f64) as usize;
    let u_start = draw([0.0, 1.0]);
    let texture = src.textures[ti.min(src.textures.len() - 1)].clone();
    let motion = cfg.motion[mi.min(cfg.motion.len() - 1)].clone();
    let (start_s, has_velocity) = match MotionSource::parse(&motion)? {
        MotionSource::Sim(_) => (SIM_SETTLE_S + u_start, true),
        MotionSource::Log(p) => {
            let s = src.logs.get(&p).ok_or_else(|| {
                Error::invalid("motion", format!("log {} was not opened", p.display()))
            })?;
            // A rolling shutter's motion spans its readout too (0: global shutter).
            let (a, b) = (s[0].t, s[s.len() - 1].t - cam.shutter.busy_s(exposure_s));
            (
                a + (b - a) * u_start,
                s.iter().all(|x| x.velocity.is_some()),
            )
        }
    };
    let fov_w = distance_m * cam.width as f64 * cam.pitch_x_mm / cam.focal_mm;
    Ok(ItemParams {
        index: i,
        seed,
        texture,
        texture_width_m: cfg.fill * fov_w,
        motion,
        start_s,
        exposure_s,
        distance_m,
        tilt_deg,
        resolution: cfg.resolution,
        quality: cfg.quality.clone(),
        use_velocity: cfg.use_velocity && has_velocity,
        camera: cfg.camera.clone(),
        sensor: cfg.sensor.clone(),
        sharp: cfg.sharp,
    })
}

/// An item's camera: its `[camera]` keys over the thesis camera at its
/// resolution, validated (parameters may come from a manifest).
fn camera(p: &ItemParams) -> Result<Camera> {
    let cam = p.camera.thesis_at(p.resolution);
    cam.validate()
        .map_err(|e| Error::invalid("item camera", e.to_string()))?;
    Ok(cam)
}

/// The samples an item's motion is a window of: a simulated walk outlasts
/// the frame's busy time `busy_s` (s, [`crate::camera::Shutter::busy_s`]).
fn samples(p: &ItemParams, busy_s: f64, src: &Sources) -> Result<ImuLog> {
    match MotionSource::parse(&p.motion)? {
        MotionSource::Sim(g) => ImuLog::new(simulate(
            &GaitConfig::preset(g),
            SIM_SETTLE_S + 1.0 + busy_s + 0.5,
            600.0,
            p.seed,
        )?),
        MotionSource::Log(path) => match src.logs.get(&path) {
            Some(s) => Ok(s.clone()),
            None => read_log(&path, GyroOptions::default()),
        },
    }
}

/// The twist at time `t`: samples interpolated linearly (as the trajectory does).
fn twist_at(s: &[GyroSample], t: f64, use_velocity: bool) -> Twist {
    let j = s.partition_point(|x| x.t < t).clamp(1, s.len().max(2) - 1);
    let (a, b) = (&s[j - 1], &s[j.min(s.len() - 1)]);
    let f = if b.t > a.t {
        ((t - a.t) / (b.t - a.t)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let v = |x: &GyroSample| {
        if use_velocity {
            x.velocity.unwrap_or(DVec3::ZERO)
        } else {
            DVec3::ZERO
        }
    };
    Twist::new(a.omega.lerp(b.omega, f), v(a).lerp(v(b), f))
}

/// What an item measured, for the manifest.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ItemMeasures {
    /// Instantaneous MMBM at exposure start (exact cubature), mm/s.
    pub mmbm_start_mm_s: f64,
    /// The same in px/s.
    pub mmbm_start_px_s: f64,
    /// Exposure MMBM (the blur maps' mean speed), px/s.
    pub mmbm_exposure_px_s: f64,
    /// The same in mm/s.
    pub mmbm_exposure_mm_s: f64,
    /// Mean image path length over the exposure (blur length), px.
    pub blur_path_px: f64,
}

/// The files of an item, by name.
pub const FILES: [&str; 6] = [
    "blurred.exr",
    "blurred.png",
    "sharp.exr",
    "sharp.png",
    "flow.exr",
    "maps.exr",
];

/// `STEM.exr` (linear) and `STEM.png` (sRGB, or the `[sensor]` pipeline's output).
fn write_rgb(
    dir: &Path,
    stem: &str,
    o: &RenderOutput,
    sensor: Option<&SensorPipeline>,
) -> Result<()> {
    o.write_image(&dir.join(format!("{stem}.exr")))?;
    let png = dir.join(format!("{stem}.png"));
    match sensor {
        None => o.write_image(&png),
        Some(s) => {
            let bytes = s.encode(o.width, o.height, &o.rgb)?;
            let img = image::RgbImage::from_raw(o.width, o.height, bytes).ok_or_else(|| {
                Error::invalid("item", "the sensor pipeline's image has the wrong size")
            })?;
            crate::io::images::save_rgb8(&png, &img)
        }
    }
}

/// Makes item `p` into `dir` (which must exist): the [`FILES`]. Rendered on
/// the CPU twin: deterministic per pixel, so the same build gives the same
/// bytes on machines of the same architecture and C library.
pub fn make(p: &ItemParams, src: &Sources, dir: &Path) -> Result<ItemMeasures> {
    let mut cam = camera(p)?;
    if p.sensor.is_some() {
        // With a sensor pipeline, each item's noise has its own seed.
        if let Some(n) = cam.noise.as_mut() {
            n.seed = p.seed;
        }
    }
    let s = samples(p, cam.shutter.busy_s(p.exposure_s), src)?;
    // The motion spans the camera's busy time (readout plus exposure).
    let traj = FrameMotion::Log {
        log: &s,
        at_s: p.start_s,
        use_velocity: p.use_velocity,
    }
    .trajectory(&cam, p.exposure_s)?;
    crate::check::positive("texture_width_m", p.texture_width_m)?;
    let mut target =
        Target::from_texture(src.texture(&p.texture)?, p.texture_width_m, p.distance_m);
    target.tilt_deg = p.tilt_deg;
    let mut job = RenderJob::new(cam, p.exposure_s, traj, target.clone());
    job.quality = p.quality.parse::<Quality>()?;
    job.backend = Backend::Cpu { threads: None };
    job.seed = p.seed as u32;
    job.with_maps = true;
    let blurred = render::render_frame(&job)?;
    // The camera held at the pose of `p.sharp`'s instant.
    let sharp = match &p.sensor {
        // The sharp frame without noise, unless asked.
        Some(s) if !s.sharp_noise => {
            let mut quiet = job.clone();
            quiet.camera.noise = None;
            render::render_sharp_at(&quiet, p.sharp)?
        }
        _ => render::render_sharp_at(&job, p.sharp)?,
    };
    let maps = blurred
        .maps
        .as_ref()
        .ok_or_else(|| Error::invalid("item", "the renderer returned no blur maps"))?;
    let f = target.frame();
    let scene = Scene {
        camera: cam,
        plane: Some(Plane {
            normal: f.normal,
            d: f.normal.dot(f.origin),
        }),
    };
    let tw = twist_at(&s, p.start_s, p.use_velocity);
    let flow = flow_field(&scene, &tw, 0, 0, Backend::Cpu { threads: None })?;
    let start = mmbm(&scene, &tw, "exact:1e-9".parse::<Method>()?)?;
    write_rgb(dir, "blurred", &blurred, p.sensor.as_ref())?;
    write_rgb(dir, "sharp", &sharp, p.sensor.as_ref())?;
    let (w, h) = (flow.width as usize, flow.height as usize);
    write_exr(
        &dir.join("flow.exr"),
        w,
        h,
        &[("flow.u", &flow.u), ("flow.v", &flow.v)],
    )?;
    maps.write_exr(&dir.join("maps.exr"))?;
    let m = maps.means();
    Ok(ItemMeasures {
        mmbm_start_mm_s: start.mm_s,
        mmbm_start_px_s: start.px_s,
        mmbm_exposure_px_s: m.speed_px_s,
        // mm/s: the maps' own with pixels that are not square (no single
        // pitch turns px into mm), else px/s times the pitch.
        mmbm_exposure_mm_s: match crate::metric::pixel_map(&cam) {
            None => m.speed_px_s * cam.pitch_x_mm,
            Some(_) => m.speed_mm_s,
        },
        blur_path_px: m.path_px,
    })
}
