//! The benchmark's clips: a true motion (the gait simulator or a real log)
//! rendered through [`mmbm::render::clip`] over a scene, with sensor noise,
//! a rolling shutter and H.264 (ffmpeg, [`mmbm::video::encode`]); two
//! stretches the gyro cannot see; and the gyro log a camera would have
//! recorded of the same motion (noise, bias, a known clock offset; seeded).
//!
//! Truth per frame (px): the renderer's blur maps' mean path length over
//! the pixels that see the scene ([`mmbm::render::clip::FrameTruth::mean_px`]). In the
//! **defocus** stretch the rendered frame is also convolved with a disc of
//! diameter `D` px and its truth is the motion's mean path plus `D` (the
//! extent of a point's image, motion then defocus). In the **optical
//! stabilisation** stretch the frame is rendered from the log's rotation
//! scaled by the residual share (a lens shift cancelling the rest within
//! the exposure; the orientation carried between frames stays the full
//! rotation) and its truth is that render's blur; the gyro log keeps the
//! full rotation.
//!
//! Clocks: frame `k` is shown at video time `k / fps`; it was exposed from
//! `start + k / fps` on the true motion's clock; the gyro log's clock is
//! the true one minus `start + offset`, so that video time = gyro time +
//! `offset` (the sign of [`mmbm::sync`] and `frames --time-offset`).

use super::rng::Rng;
use mmbm::camera::{Camera, Noise, Readout, Shutter};
use mmbm::error::{Error, Result};
use mmbm::model::log::{GyroSample, ImuLog};
use mmbm::model::trajectory::Trajectory;
use mmbm::render::clip::{Clip, ClipTarget};
use mmbm::render::texture::MipTexture;
use mmbm::render::{Backend, Background, Quality, Target};
use mmbm::video::{encode, Codec};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Distance of every target plane, m.
pub const DISTANCE_M: f64 = 2.0;
/// Horizontal field of view as the running phone's calibration gives it:
/// sensor width over focal length (`calib.txt`'s `fov`).
pub const WIDTH_OVER_FOCAL: f64 = 1.27;
/// Rolling-shutter readout, s (the running phone's is 16 ms).
pub const READOUT_S: f64 = 0.016;
/// Light level of the sensor noise, electrons/s at full white.
pub const LIGHT_E_PER_S: f64 = 4e5;
/// Gyro white noise per sample and axis, rad/s.
pub const GYRO_NOISE: f64 = 0.004;
/// Largest gyro bias per axis, rad/s (uniform in +- this).
pub const GYRO_BIAS: f64 = 0.01;
/// Share of the rotation left by the optical stabilisation (0..1).
pub const OIS_RESIDUAL: f64 = 0.3;
/// Defocus disc diameter at 320 px width, px (scaled with the width).
pub const DEFOCUS_PX_AT_320: f64 = 4.0;

/// Where the true motion comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// The gait simulator's fast walk ([`mmbm::sim`]) with this seed, its
    /// rotation scaled by `gain` (no gyro noise or bias: the true motion).
    Walk {
        /// Simulator seed.
        seed: u64,
        /// Factor on the angular rate.
        gain: f64,
    },
    /// A real gyro log (`t,wx,wy,wz`, camera frame), from `start_s`.
    Log {
        /// The log file.
        path: PathBuf,
        /// Where the clip starts on its clock, s.
        start_s: f64,
    },
}

/// What the camera looks at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scene {
    /// The thesis board on the procedural CC0 poster.
    Poster,
    /// A wall of CC0 photographs (`assets/textures`).
    Photos,
    /// A smooth, weakly textured wall.
    Wall,
    /// Segments: photographs, the wall, the poster, the wall again.
    Segments,
}

/// One clip of the benchmark.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipSpec {
    /// Short name (the table's column).
    pub name: &'static str,
    /// What it shows, for the docs.
    pub what: &'static str,
    /// The true motion.
    pub motion: Motion,
    /// The scene.
    pub scene: Scene,
    /// Exposure of each line, s.
    pub exposure_s: f64,
    /// Seed of the gyro's noise, bias and offset.
    pub seed: u64,
}

/// The size and length of every clip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Format {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Frame rate, frames/s.
    pub fps: f64,
    /// Frames per clip.
    pub frames: usize,
    /// Whether the clips hold the stretches the gyro cannot see
    /// ([`Stretches`]).
    pub invisible: bool,
}

/// The stretches the gyro cannot see: frame ranges.
#[derive(Debug, Clone, PartialEq)]
pub struct Stretches {
    /// Frames blurred by a defocus disc.
    pub defocus: Range<usize>,
    /// Its diameter, px.
    pub defocus_px: f64,
    /// Frames rendered with optical stabilisation.
    pub ois: Range<usize>,
}

impl Stretches {
    /// 30-40 % of the clip defocused, 60-72 % stabilised (none without
    /// [`Format::invisible`]).
    pub fn of(f: &Format) -> Self {
        let at = |x: f64| {
            if f.invisible {
                (x * f.frames as f64).round() as usize
            } else {
                0
            }
        };
        Stretches {
            defocus: at(0.30)..at(0.40),
            defocus_px: DEFOCUS_PX_AT_320 * f.width as f64 / 320.0,
            ois: at(0.60)..at(0.72),
        }
    }
}

/// A rendered clip with its truth and its gyro log.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// The video (H.264 MP4).
    pub video: PathBuf,
    /// True blur per frame, px (see the module docs).
    pub truth: Vec<f64>,
    /// The gyro log as recorded (its own clock).
    pub gyro: ImuLog,
    /// The camera (intrinsics, readout) the gyro picker is told.
    pub camera: Camera,
    /// Exposure, s.
    pub exposure_s: f64,
    /// Frame rate, frames/s.
    pub fps: f64,
    /// The true offset: video time = gyro time + this, s.
    pub offset_s: f64,
    /// Render and encode time, s.
    pub render_s: f64,
}

impl Rendered {
    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.truth.len()
    }
}

/// The camera of every clip: the running phone's field of view, a rolling
/// shutter of [`READOUT_S`], sensor noise at [`LIGHT_E_PER_S`].
pub fn camera(width: u32, height: u32) -> Camera {
    let mut c = Camera::thesis().fitted_to(width, height);
    c.focal_mm = c.pitch_x_mm * width as f64 / WIDTH_OVER_FOCAL;
    c.shutter = Shutter {
        readout_s: READOUT_S,
        direction: Readout::TopToBottom,
    };
    c.noise = Some(Noise::at_light(LIGHT_E_PER_S));
    c
}

/// The true motion's log and where the clip starts on its clock (s).
fn true_log(m: &Motion, seconds: f64) -> Result<(ImuLog, f64)> {
    match m {
        Motion::Walk { seed, gain } => {
            let mut cfg = mmbm::sim::GaitConfig::preset(mmbm::sim::Gait::Fast);
            cfg.noise_std = 0.0;
            cfg.bias = [0.0; 3];
            let s = mmbm::sim::simulate(&cfg, seconds + 2.0, 200.0, *seed)?;
            let s = s
                .into_iter()
                .map(|g| GyroSample {
                    omega: g.omega * *gain,
                    velocity: None,
                    ..g
                })
                .collect();
            Ok((ImuLog::new(s)?, 1.0))
        }
        Motion::Log { path, start_s } => {
            let log = mmbm::telemetry::read_gyro(path, &Default::default())?;
            Ok((log, *start_s))
        }
    }
}

/// `log` with its rate scaled by `k`.
fn scaled(log: &ImuLog, k: f64) -> Result<ImuLog> {
    ImuLog::new(
        log.samples()
            .iter()
            .map(|s| GyroSample {
                omega: s.omega * k,
                ..*s
            })
            .collect(),
    )
}

/// The gyro a camera records of `log` over `[a, b]` (true clock, s):
/// white noise, a constant bias and the clock shifted by `a + offset`.
fn recorded(log: &ImuLog, a: f64, b: f64, offset: f64, rng: &mut Rng) -> Result<ImuLog> {
    let bias = glam::DVec3::new(rng.sym(GYRO_BIAS), rng.sym(GYRO_BIAS), rng.sym(GYRO_BIAS));
    let s: Vec<GyroSample> = log
        .samples()
        .iter()
        .filter(|s| s.t >= a - 0.5 && s.t <= b + 0.5)
        .map(|s| GyroSample {
            t: s.t - a - offset,
            omega: s.omega
                + bias
                + glam::DVec3::new(rng.normal(), rng.normal(), rng.normal()) * GYRO_NOISE,
            velocity: None,
            depth: None,
        })
        .collect();
    ImuLog::new(s)
}

/// A plane at [`DISTANCE_M`] showing `texture` at about one texel per
/// pixel of `cam`, the poster around it.
fn wall_of(texture: MipTexture, texels: f64, cam: &Camera) -> Target {
    let px_per_m = cam.fx_px() / DISTANCE_M;
    let mut t = Target::from_texture(texture, texels / px_per_m, DISTANCE_M);
    t.surround = Background::Poster;
    t
}

/// The photographs (`assets/textures`: chelsea, coffee, rocket; CC0 or
/// public domain) tiled 3 x 3 at 600 x 400 px each.
pub fn photos(repo: &Path, cam: &Camera) -> Result<Target> {
    let names = ["chelsea.png", "coffee.png", "rocket.jpg"];
    let mut tiles = Vec::new();
    for n in names {
        let img = mmbm::io::images::read_rgb8(&repo.join("assets/textures").join(n))?;
        tiles.push(image::imageops::resize(
            &img,
            600,
            400,
            image::imageops::FilterType::Triangle,
        ));
    }
    let mut canvas = image::RgbImage::new(1800, 1200);
    for i in 0..3u32 {
        for j in 0..3u32 {
            let tile = &tiles[((i + 2 * j) % 3) as usize];
            image::imageops::replace(&mut canvas, tile, (600 * i) as i64, (400 * j) as i64);
        }
    }
    Ok(wall_of(MipTexture::from_srgb8(&canvas)?, 1800.0, cam))
}

/// A smooth wall: value noise of 2 % contrast on mid grey, 256 x 256
/// texels spread over about 2000 px (seeded).
pub fn low_texture(cam: &Camera, seed: u64) -> Result<Target> {
    let n = 256usize;
    let mut rng = Rng::new(seed);
    let grid: Vec<f32> = (0..n * n).map(|_| rng.sym(1.0) as f32).collect();
    let mut rgb = Vec::with_capacity(n * n * 3);
    for j in 0..n {
        for i in 0..n {
            // A 3 x 3 box over the noise: smooth, no edges.
            let mut s = 0.0;
            for dj in 0..3 {
                for di in 0..3 {
                    s += grid[((j + dj) % n) * n + (i + di) % n];
                }
            }
            let v = 0.18 * (1.0 + 0.02 * s / 3.0);
            rgb.extend([v, v * 0.97, v * 0.92]);
        }
    }
    let tex = MipTexture::from_linear(n as u32, n as u32, rgb)?;
    Ok(wall_of(tex, 2000.0, cam))
}

/// The poster: the thesis board on the procedural poster.
pub fn poster() -> Target {
    let mut t = Target::blobs(1.0, DISTANCE_M);
    t.surround = Background::Poster;
    t
}

/// The targets of `scene` and which one frame `k` of `n` shows.
fn targets(scene: Scene, repo: &Path, cam: &Camera, seed: u64) -> Result<Vec<Target>> {
    Ok(match scene {
        Scene::Poster => vec![poster()],
        Scene::Photos => vec![photos(repo, cam)?],
        Scene::Wall => vec![low_texture(cam, seed)?],
        Scene::Segments => {
            let wall = low_texture(cam, seed)?;
            vec![photos(repo, cam)?, wall.clone(), poster(), wall]
        }
    })
}

/// A disc blur of diameter `d` px on an 8-bit RGB image (edges clamped).
pub fn defocus(rgb: &mut [u8], w: usize, h: usize, d: f64) {
    let r = d / 2.0;
    let ri = r.ceil() as isize;
    let taps: Vec<(isize, isize)> = (-ri..=ri)
        .flat_map(|y| (-ri..=ri).map(move |x| (x, y)))
        .filter(|&(x, y)| ((x * x + y * y) as f64) <= r * r)
        .collect();
    let src = rgb.to_vec();
    for y in 0..h as isize {
        for x in 0..w as isize {
            let mut s = [0u32; 3];
            for &(dx, dy) in &taps {
                let xx = (x + dx).clamp(0, w as isize - 1) as usize;
                let yy = (y + dy).clamp(0, h as isize - 1) as usize;
                let k = 3 * (yy * w + xx);
                for c in 0..3 {
                    s[c] += src[k + c] as u32;
                }
            }
            let k = 3 * (y as usize * w + x as usize);
            let n = taps.len() as u32;
            for c in 0..3 {
                rgb[k + c] = ((s[c] + n / 2) / n) as u8;
            }
        }
    }
}

/// Renders `spec` at `f` into `dir` (`NAME.mp4`): the clip, its truth and
/// its gyro log. `repo`: the repository root (textures, logs).
pub fn render(spec: &ClipSpec, f: &Format, repo: &Path, dir: &Path) -> Result<Rendered> {
    let t0 = std::time::Instant::now();
    let cam = camera(f.width, f.height);
    let seconds = f.frames as f64 / f.fps;
    let (log, start_s) = true_log(&spec.motion, seconds)?;
    let ois_log = scaled(&log, OIS_RESIDUAL)?;
    let targets = targets(spec.scene, repo, &cam, spec.seed)?;
    let st = Stretches::of(f);
    let clip = |k: usize| Clip {
        camera: cam,
        log: if st.ois.contains(&k) { &ois_log } else { &log },
        fps: f.fps,
        exposure_s: spec.exposure_s,
        start_s,
        frames: f.frames,
        target: ClipTarget::Plane(targets[k * targets.len() / f.frames].clone()),
        quality: Quality::Fast,
        backend: Backend::Cpu { threads: None },
    };
    clip(0).check()?;
    let mut rng = Rng::new(spec.seed);
    let offset_s = 0.02 + 0.03 * rng.unit();
    let end = start_s + seconds + 0.1;
    let gyro = recorded(&log, start_s, end, offset_s, &mut rng)?;
    let video = dir.join(format!("{}.mp4", spec.name));
    let (w, h) = (f.width as usize, f.height as usize);
    let mut truth = Vec::with_capacity(f.frames);
    let period = 1.0 / f.fps;
    encode::encode(
        &video,
        (f.width, f.height),
        f.fps,
        Codec::available()?,
        |enc| {
            let mut q = glam::DQuat::IDENTITY;
            for k in 0..f.frames {
                let c = clip(k);
                let mut frame = c.render_one(k, q)?;
                let mut blur = frame.truth.mean_px;
                if st.defocus.contains(&k) {
                    defocus(&mut frame.rgb8, w, h, st.defocus_px);
                    blur += st.defocus_px;
                }
                if !blur.is_finite() {
                    return Err(Error::invalid(
                        spec.name,
                        format!("frame {k}: no true blur"),
                    ));
                }
                truth.push(blur);
                enc.push(&frame.rgb8)?;
                // The full rotation carried to the next frame.
                let step = Trajectory::from_imu_log(&log, c.t_start(k), period, false)?;
                q = (q * step.pose_at(period).0).normalize();
            }
            Ok(())
        },
    )?;
    Ok(Rendered {
        video,
        truth,
        gyro,
        camera: cam,
        exposure_s: spec.exposure_s,
        fps: f.fps,
        offset_s,
        render_s: t0.elapsed().as_secs_f64(),
    })
}

/// The four clips of the benchmark (seeds stated in the docs).
pub fn specs(repo: &Path) -> Vec<ClipSpec> {
    let running = repo.join("../shared/data/running_phone/gyro.csv");
    vec![
        ClipSpec {
            name: "walk-poster",
            what: "the gait simulator's fast walk (seed 11, rate x 2) over the thesis board on the CC0 poster",
            motion: Motion::Walk { seed: 11, gain: 2.0 },
            scene: Scene::Poster,
            exposure_s: 0.010,
            seed: 101,
        },
        ClipSpec {
            name: "run-photos",
            what: "the running_phone log's real motion (from 1.0 s) over a wall of CC0 photographs",
            motion: Motion::Log {
                path: running.clone(),
                start_s: 1.0,
            },
            scene: Scene::Photos,
            exposure_s: 0.012,
            seed: 102,
        },
        ClipSpec {
            name: "run-wall",
            what: "the running_phone log's real motion (from 2.5 s) over a smooth wall of 2 % contrast",
            motion: Motion::Log {
                path: running,
                start_s: 2.5,
            },
            scene: Scene::Wall,
            exposure_s: 0.008,
            seed: 103,
        },
        ClipSpec {
            name: "walk-changing",
            what: "the fast walk (seed 12, rate x 2) over four segments: photographs, the smooth wall, the poster, the wall",
            motion: Motion::Walk { seed: 12, gain: 2.0 },
            scene: Scene::Segments,
            exposure_s: 0.016,
            seed: 104,
        },
    ]
}
