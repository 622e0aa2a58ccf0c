//! `mmbm series`: MMBM for every gyro sample.

use super::args::{CameraArgs, SceneArgs};
use clap::Args;
use mmbm::error::Result;
use mmbm::io::gyro::{parse_rotation, AngleUnit, GyroOptions, GyroReader, TimeUnit};
use mmbm::series::{self, SeriesOptions};
use mmbm::{AnyMethod, Scene};
use std::path::PathBuf;

/// Options for reading a gyro log (shared by the commands that read one).
#[derive(Args, Debug, Clone)]
pub struct GyroArgs {
    /// Unit of the `t` column: s, ms, us or ns (CSV only: .mcap and .gcsv
    /// logs carry their own).
    #[arg(long, default_value = "s")]
    pub time_unit: TimeUnit,
    /// Unit of wx, wy, wz: rad or deg (per second; CSV only).
    #[arg(long, default_value = "rad")]
    pub angle_unit: AngleUnit,
    /// IMU-to-camera rotation, 9 numbers row-major, in mmbm's camera frame
    /// (x right, y down, z forward): w_camera = R * w_log (also v). Applied
    /// last: for a .gcsv log, after its orientation and --gyroflow-rotation.
    #[arg(long, value_name = "R11,...,R33", allow_hyphen_values = true, value_parser = rotation)]
    pub imu_rotation: Option<glam::DMat3>,
    /// .gcsv only: Gyroflow's IMU rotation, degrees, as Gyroflow's "IMU
    /// rotation" pitch, roll, yaw: Rz(roll) Ry(pitch) Rx(yaw) in Gyroflow's
    /// IMU frame (x up, y left, z back), after the orientation.
    #[arg(long, value_name = "PITCH,ROLL,YAW", allow_hyphen_values = true, value_parser = angles)]
    pub gyroflow_rotation: Option<[f64; 3]>,
    /// Added to every time stamp, s.
    #[arg(
        allow_negative_numbers = true,
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub time_offset: f64,
    /// ROS 2 MCAP log (.mcap): the topic of sensor_msgs/msg/Imu messages
    /// (default: the only IMU topic). Time from header.stamp, rad/s; the
    /// IMU-to-camera frame is --imu-rotation (/tf is not read).
    #[arg(long, value_name = "TOPIC")]
    pub topic: Option<String>,
    /// The device-to-camera rotation by name (before --imu-rotation):
    /// phone-back-portrait, phone-back-landscape (the phone's top to the
    /// left), phone-back-landscape-right, phone-front-portrait, action-cam
    /// (GoPro's IMU axes; a GoPro MP4's default) or camera (the identity).
    /// Matrices: docs/frames.md, "Gyro from the camera's own files".
    #[arg(long, value_name = "PRESET")]
    pub orientation: Option<mmbm::telemetry::Orientation>,
}

/// `--imu-rotation`: 9 numbers, a rotation matrix (clap reports a bad one, exit 2).
fn rotation(s: &str) -> std::result::Result<glam::DMat3, String> {
    parse_rotation(s).map_err(|e| e.to_string())
}

/// `--gyroflow-rotation`: 3 finite numbers, degrees (clap reports a bad one, exit 2).
fn angles(s: &str) -> std::result::Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("'{s}': expected 3 comma-separated numbers (degrees)"))?;
    match v[..] {
        [p, r, y] if v.iter().all(|x| x.is_finite()) => Ok([p, r, y]),
        _ => Err(format!(
            "'{s}': expected 3 finite numbers, pitch,roll,yaw (degrees)"
        )),
    }
}

impl GyroArgs {
    /// The options of a streamed log (`--orientation` is refused here: it
    /// applies where the log is read whole, `mmbm::telemetry`).
    pub fn options(&self) -> Result<GyroOptions> {
        if let Some(o) = self.orientation {
            return Err(mmbm::Error::invalid(
                "--orientation",
                format!(
                    "'{}' is not available for this command's streamed log; give the same rotation as --imu-rotation",
                    o.name()
                ),
            ));
        }
        self.log_options()
    }

    fn log_options(&self) -> Result<GyroOptions> {
        Ok(GyroOptions {
            time_unit: self.time_unit,
            angle_unit: self.angle_unit,
            imu_to_camera: self.imu_rotation.unwrap_or(glam::DMat3::IDENTITY),
            gyroflow_rotation: self.gyroflow_rotation,
            time_offset: mmbm::check::finite("--time-offset", self.time_offset)?,
            topic: self.topic.clone(),
        })
    }

    /// The options of `mmbm::telemetry::read_gyro` (camera files and every log).
    pub fn telemetry(&self) -> Result<mmbm::telemetry::TelemetryOptions> {
        Ok(mmbm::telemetry::TelemetryOptions {
            gyro: self.log_options()?,
            orientation: self.orientation,
        })
    }
}

/// The samples of `gyro`: a log streamed by its reader, a camera file
/// (`mmbm::telemetry`) read whole.
fn source(gyro: &std::path::Path, g: &GyroArgs) -> Result<series::Samples> {
    if mmbm::telemetry::sniff(gyro)? == mmbm::telemetry::Format::Log && g.orientation.is_none() {
        return Ok(GyroReader::open(gyro, g.options()?)?.into());
    }
    let log = mmbm::telemetry::read_gyro(gyro, &g.telemetry()?)?;
    Ok(series::Samples::Read(log.into_samples().into_iter()))
}

/// MMBM for every gyro sample: CSV `t,mmbm_mm_s,mmbm_px_s`.
#[derive(Args, Debug)]
#[command(after_help = "Examples:
  mmbm series --gyro ../shared/data/running_phone/gyro.csv --out mmbm.csv
  mmbm series --gyro log.csv --time-unit ms --angle-unit deg --method gauss:4
  mmbm series --gyro log.csv --use-velocity --depth 3 --method gpu:64x48")]
pub struct SeriesArgs {
    /// Gyro log: CSV t,wx,wy,wz[,vx,vy,vz][,depth]; also a ROS 2 .mcap or a
    /// Gyroflow .gcsv IMU log (t*tscale s, g*gscale rad/s, its orientation),
    /// or a camera's own file: a GoPro MP4 (GPMF), a Gyroflow project
    /// (.gyroflow), Sensor Logger's or phyphox's gyroscope CSV.
    #[arg(long, value_name = "FILE")]
    pub gyro: PathBuf,
    /// riemann[:NUxNV], gauss[:N], exact[:TOL] or gpu[:WxH].
    /// Limits: 1,048,576 grid points, 1024 Gauss nodes per side.
    #[arg(long, default_value = "riemann:8x6")]
    pub method: AnyMethod,
    /// Output CSV (default: stdout).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Add a blur_px column: the expected blur length over an exposure of S
    /// seconds starting at each sample, px (MMBM x S / pitch, docs/spec.md section 3).
    #[arg(long, value_name = "S")]
    pub exposure: Option<f64>,
    /// Include the log's vx,vy,vz (needs a depth column, --depth or --plane).
    #[arg(long)]
    pub use_velocity: bool,
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub gyro_opts: GyroArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
}

pub fn run(a: SeriesArgs) -> Result<()> {
    // The output's place, against every input, before any work.
    mmbm::io::guard::OutputGuard::new()
        .output("--out", a.out.as_deref())
        .input("--gyro", Some(&a.gyro))
        .input("--camera", a.camera.camera.as_deref())
        .check()?;
    let method = a.method;
    let opts = SeriesOptions {
        scene: Scene {
            camera: a.camera.camera()?,
            plane: a.scene.plane()?,
        },
        method,
        use_velocity: a.use_velocity,
    };
    if let Some(p) = &opts.scene.plane {
        p.validate_for(&opts.scene.camera)?;
    }
    let reader = source(&a.gyro, &a.gyro_opts)?;
    let mut eval = series::evaluator(opts)?;
    let px = series::px_of(&opts)?;
    if let Some(te) = a.exposure {
        mmbm::check::positive("--exposure (s)", te)?;
    }
    let n = match &a.out {
        Some(p) => {
            let mut n = 0;
            mmbm::io::atomic::write_atomic(p, |w| {
                n = series::run(reader, &mut eval, &*px, a.exposure, w)?;
                Ok(())
            })?;
            n
        }
        None => series::run(
            reader,
            &mut eval,
            &*px,
            a.exposure,
            std::io::stdout().lock(),
        )?,
    };
    eprintln!("{n} samples, method {method}");
    Ok(())
}
