//! `mmbm render`: a ground-truth motion-blurred image of a planar target.

use super::args::{check_ext, parse_vec3, CameraArgs};
use super::series::GyroArgs;
use clap::Args;
use glam::DVec3;
use mmbm::error::{Error, Result};
use mmbm::io::atomic::all_or_nothing;
use mmbm::io::guard::OutputGuard;
use mmbm::io::images::{write_exr, write_png_linear_rgb};
use mmbm::render::{
    self, Backend, FrameMotion, Integrator, Quality, RenderJob, RenderOutput, Target,
};
use mmbm::Twist;
use std::path::{Path, PathBuf};

/// Render a ground-truth motion-blurred image of a planar target.
#[derive(Args, Debug)]
#[command(
    after_help = "Targets: checker:S (S = square side, m), blobs[:SCALE] (thesis 4x4 red board),
image:PATH:WIDTH_M (PNG/JPEG, sRGB).
Examples:
  mmbm render --omega 0.5,-0.3,0.2 --exposure 0.05 --target checker:0.05 --distance 2 --out blur.png
  mmbm render --omega 0,0,0 --velocity 0.3,0,0 --exposure 0.07 --target blobs --distance 3 \\
      --resolution 320x240 --out blobs.exr --maps maps.exr --sharp sharp.png --psf 160,120:psf.png
  mmbm render --gyro ../shared/data/running_phone/gyro.csv --at 2.0 --exposure 0.03 \\
      --target checker:0.1 --distance 3 --out frame.png"
)]
pub struct RenderArgs {
    #[command(flatten)]
    pub opts: Box<RenderOpts>,
}

/// The options of `mmbm render` (boxed: the command enum stays small).
#[derive(Args, Debug)]
pub struct RenderOpts {
    /// Constant angular velocity WX,WY,WZ, rad/s (camera frame).
    #[arg(long, value_name = "WX,WY,WZ", value_parser = parse_vec3, allow_hyphen_values = true,
          required_unless_present = "gyro", conflicts_with = "gyro")]
    pub omega: Option<DVec3>,
    /// Constant linear velocity VX,VY,VZ, m/s (with --omega).
    #[arg(long, value_name = "VX,VY,VZ", value_parser = parse_vec3, allow_hyphen_values = true,
          requires = "omega")]
    pub velocity: Option<DVec3>,
    /// Gyro log (CSV, ROS 2 .mcap or Gyroflow .gcsv): the trajectory is
    /// integrated from its samples.
    #[arg(long, value_name = "FILE", requires = "at")]
    pub gyro: Option<PathBuf>,
    /// Exposure start on the log's clock, s (with --gyro).
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "T",
        allow_hyphen_values = true
    )]
    pub at: Option<f64>,
    /// Use the log's vx,vy,vz (with --gyro).
    #[arg(long)]
    pub use_velocity: bool,
    /// Exposure time, s.
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "S",
        allow_hyphen_values = true
    )]
    pub exposure: f64,
    /// checker:S, blobs[:SCALE] or image:PATH:WIDTH_M.
    #[arg(long, value_name = "SPEC")]
    pub target: String,
    /// Distance of the target plane along the optical axis at exposure start, m.
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "D",
        allow_hyphen_values = true
    )]
    pub distance: f64,
    /// Target tilt about its horizontal and vertical axes, degrees.
    #[arg(long, value_name = "AX,AY", allow_hyphen_values = true)]
    pub tilt: Option<String>,
    /// Target offset X (right), Y (down), m.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub offset: Option<String>,
    /// Background linear RGB where rays miss the target.
    #[arg(allow_hyphen_values = true, long, value_name = "R,G,B", value_parser = parse_vec3)]
    pub background: Option<DVec3>,
    /// Output image: .exr (linear float R,G,B) or .png (sRGB 8-bit).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Also write per-pixel blur maps (EXR: path_px, disp_px, speed_px_s).
    #[arg(long, value_name = "FILE.exr")]
    pub maps: Option<PathBuf>,
    /// Also write the sharp frame at exposure start (.exr or .png).
    #[arg(long, value_name = "FILE")]
    pub sharp: Option<PathBuf>,
    /// Also write the PSF at pixel X,Y (.exr raw weights summing to 1, or .png scaled to its peak).
    #[arg(allow_hyphen_values = true, long, value_name = "X,Y:FILE")]
    pub psf: Option<String>,
    /// default, fast, or MIN_SAMPLES:SPACING_PX.
    #[arg(long, default_value = "default")]
    pub quality: Quality,
    /// Area integration: auto (analytic, or lattice with defocus), analytic
    /// (closed-form pixel area, one sample per instant: checker, blobs and
    /// images) or lattice (supersampled area and time; the reference).
    #[arg(long, default_value = "auto")]
    pub integrator: Integrator,
    /// bulk (the default: a hardware GPU, else the CPU twin, which is faster
    /// than a software adapter such as lavapipe), auto (GPU if any, software
    /// ones included, else CPU), gpu (a GPU or an error) or cpu.
    #[arg(long, default_value = "bulk")]
    pub backend: Backend,
    /// Seed of the per-pixel sample shifts.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    #[command(flatten)]
    pub gyro_opts: GyroArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
}

fn pair(s: &str, what: &str) -> Result<[f64; 2]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| {
            Error::invalid(what, format!("'{s}': expected two comma-separated numbers"))
        })?;
    if v.len() != 2 || v.iter().any(|x| !x.is_finite()) {
        return Err(Error::invalid(
            what,
            format!("'{s}': expected two finite numbers"),
        ));
    }
    Ok([v[0], v[1]])
}

/// The texture file of an `image:PATH:WIDTH_M` target.
fn texture_path(spec: &str) -> Option<PathBuf> {
    let rest = spec.strip_prefix("image:")?;
    rest.rsplit_once(':').map(|(p, _)| PathBuf::from(p))
}

fn write_image(p: &Path, o: &RenderOutput) -> Result<()> {
    check_ext(p, &["exr", "png"], "output")?;
    o.write_image(p)
}

pub fn run(args: RenderArgs) -> Result<()> {
    let a = *args.opts;
    // Validate every output name and place before any work, so nothing is
    // half-written (and no two outputs share a file); the files then appear
    // all together or not at all.
    check_ext(&a.out, &["exr", "png"], "--out")?;
    let mut outputs: Vec<(&str, &Path)> = vec![("--out", &a.out)];
    if let Some(p) = &a.maps {
        check_ext(p, &["exr"], "--maps")?;
        outputs.push(("--maps", p));
    }
    if let Some(p) = &a.sharp {
        check_ext(p, &["exr", "png"], "--sharp")?;
        outputs.push(("--sharp", p));
    }
    let psf = match &a.psf {
        Some(s) => {
            let (xy, file) = s
                .split_once(':')
                .ok_or_else(|| Error::invalid("--psf", format!("'{s}': expected X,Y:FILE")))?;
            let [x, y] = pair(xy, "--psf")?;
            let file = PathBuf::from(file);
            check_ext(&file, &["exr", "png"], "--psf")?;
            Some((x, y, file))
        }
        None => None,
    };
    if let Some((_, _, file)) = &psf {
        outputs.push(("--psf", file));
    }
    // Every output writable, none on another nor on an input, before any work.
    let mut guard = OutputGuard::new();
    for (flag, p) in outputs {
        guard = guard.output(flag, Some(p));
    }
    guard
        .input("--gyro", a.gyro.as_deref())
        .input("--camera", a.camera.camera.as_deref())
        .input("--target image:", texture_path(&a.target).as_deref())
        .check()?;
    let camera = a.camera.camera()?;
    let log = match &a.gyro {
        Some(g) => Some(mmbm::telemetry::read_gyro(g, &a.gyro_opts.telemetry()?)?),
        None => None,
    };
    let motion = match (&a.omega, &log) {
        (Some(w), None) => FrameMotion::Twist(Twist::new(*w, a.velocity.unwrap_or_default())),
        (None, Some(log)) => FrameMotion::Log {
            log,
            at_s: a
                .at
                .ok_or_else(|| Error::invalid("--at", "required with --gyro"))?,
            use_velocity: a.use_velocity,
        },
        _ => {
            return Err(Error::invalid(
                "motion",
                "give either --omega or --gyro with --at",
            ))
        }
    };
    // A log's own rolling-shutter readout, where the camera has none.
    let (camera, from_log) = motion.camera(camera)?;
    if let (true, Some(g)) = (from_log, &a.gyro) {
        super::args::print_log_readout(&camera.shutter, g);
    }
    let mut target = Target::parse(&a.target, a.distance)?;
    if let Some(s) = &a.tilt {
        target.tilt_deg = pair(s, "--tilt")?;
    }
    if let Some(s) = &a.offset {
        target.offset = pair(s, "--offset")?;
    }
    if let Some(b) = a.background {
        target.background = [b.x as f32, b.y as f32, b.z as f32];
    }
    // The exposure first (a non-positive one is the flag's fault, not the log's).
    mmbm::check::positive("--exposure", a.exposure)?;
    // The trajectory spans the camera's busy time (exposure plus readout).
    let trajectory = motion
        .trajectory(&camera, a.exposure)
        .map_err(|e| match &a.gyro {
            Some(path) => Error::invalid("--gyro", format!("{}: {e}", path.display())),
            None => e,
        })?;
    target.validate_for(&camera)?;
    let mut job = RenderJob::new(camera, a.exposure, trajectory, target);
    job.quality = a.quality;
    job.backend = a.backend;
    job.seed = a.seed;
    job.integrator = a.integrator;
    job.with_maps = a.maps.is_some();
    let t0 = std::time::Instant::now();
    let out = render::render_frame(&job)?;
    let psf_img = match &psf {
        Some((x, y, _)) => Some(render::psf(
            &job.camera,
            &job.target,
            &job.trajectory,
            *x,
            *y,
        )?),
        None => None,
    };
    let sharp = match &a.sharp {
        Some(_) => Some(render::render_sharp(&job)?),
        None => None,
    };
    all_or_nothing(|| {
        write_image(&a.out, &out)?;
        if let (Some(p), Some(m)) = (&a.maps, &out.maps) {
            m.write_exr(p)?;
            let mm = m.means();
            eprintln!(
                "exposure MMBM: mean path {:.3} px, mean displacement {:.3} px, mean speed {:.2} px/s = {:.4} mm/s ({:.1}% of pixels tracked)",
                mm.path_px, mm.disp_px, mm.speed_px_s, mm.speed_px_s * job.camera.pitch_x_mm, mm.valid * 100.0
            );
        }
        if let (Some(p), Some(s)) = (&a.sharp, &sharp) {
            write_image(p, s)?;
        }
        if let (Some((_, _, p)), Some(k)) = (&psf, &psf_img) {
            let n = k.size as usize;
            if check_ext(p, &["exr", "png"], "--psf")? == "exr" {
                write_exr(p, n, n, &[("psf", &k.weights)])?;
            } else {
                let peak = k.weights.iter().cloned().fold(0.0f32, f32::max).max(1e-30);
                let rgb: Vec<f32> = k.weights.iter().flat_map(|w| [w / peak; 3]).collect();
                write_png_linear_rgb(p, k.size, k.size, &rgb)?;
            }
        }
        Ok(())
    })?;
    eprintln!(
        "{}x{}, {} samples/pixel (max path {:.1} px), {} in {:.2} s",
        out.width,
        out.height,
        out.samples_per_pixel,
        out.max_path_px,
        out.backend_used,
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
