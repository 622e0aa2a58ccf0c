//! MMBM of a gyro log: the one owner of "the MMBM of every sample".
//!
//! [`sample_scene`] turns a sample into its twist and validated scene (the
//! per-sample plane check lives only here); [`eval_batch_cpu`] evaluates a
//! batch with a CPU method and [`gpu::series_evaluator`] with the GPU flow
//! kernels; [`mmbm_series`] gives a whole in-memory log (what `trigger` and
//! `experiment` use), and [`run`] streams a file in constant memory to CSV
//! with header `t,mmbm_mm_s,mmbm_px_s` and shortest round-trip floats.

pub mod frames;
pub mod gpu;
pub mod job;
pub mod lerp;
pub mod maps;
pub mod select;
pub mod window;

use crate::error::{Error, Result};
use crate::io::gyro::{GyroReader, GyroSample};
use crate::metric::{AnyMethod, Evaluator, Method, Scene};
use crate::model::motion::{Plane, Twist};
use rayon::prelude::*;
use std::io::Write;

/// Samples evaluated per batch (also the GPU batch size).
pub const BATCH: usize = 16_384;

/// Options of a series run. `M` is the method's type: a CPU [`Method`]
/// (the default, for the evaluations that run only on the CPU) or an
/// [`AnyMethod`], which may also name the GPU ([`evaluator`]).
#[derive(Debug, Clone, Copy)]
pub struct SeriesOptions<M = Method> {
    /// Camera and (optional) fixed scene plane.
    pub scene: Scene,
    /// Metric method.
    pub method: M,
    /// Use the log's `vx, vy, vz` (and `depth` when present, else the scene plane).
    /// Off by default: the thesis metric is rotation-only.
    pub use_velocity: bool,
}

/// The twist and scene for one sample under `opts`: rotation only unless
/// `use_velocity`; then the sample's `depth` (a fronto-parallel plane) or
/// the options' plane, checked against the twist (errors name the sample's
/// time).
pub fn sample_scene<M>(s: &GyroSample, opts: &SeriesOptions<M>) -> Result<(Twist, Scene)> {
    if !opts.use_velocity {
        return Ok((
            Twist::new(s.omega, glam::DVec3::ZERO),
            Scene {
                plane: None,
                ..opts.scene
            },
        ));
    }
    let v = s
        .velocity
        .ok_or_else(|| Error::invalid("--use-velocity", "the log has no vx, vy, vz columns"))?;
    let plane = match s.depth {
        Some(z) => Some(Plane::fronto(z)),
        None => opts.scene.plane,
    };
    if plane.is_none() {
        return Err(Error::invalid(
            "depth",
            "translation needs a scene depth: a 'depth' column in the log or --depth",
        ));
    }
    let tw = Twist::new(s.omega, v);
    let scene = Scene {
        plane,
        ..opts.scene
    };
    scene
        .validate_for(&tw)
        .map_err(|e| Error::invalid(format!("sample at t = {} s", s.t), e.to_string()))?;
    Ok((tw, scene))
}

/// The MMBM (mm/s) of one sample under `opts`, with `ev` built for their
/// camera and method (a live stream's samples, one at a time, and every
/// sample of a CPU batch). Not checked for finiteness: see [`check_values`].
pub fn sample_mmbm(s: &GyroSample, opts: &SeriesOptions, ev: &Evaluator) -> Result<f64> {
    let (tw, scene) = sample_scene(s, opts)?;
    Ok(ev.mean_speed(&scene.flow_poly(&tw)))
}

/// The MMBM in px/s (the true pixel speed, [`Evaluator::mean_px_speed`])
/// of one sample whose MMBM in mm/s is `mm_s`, on a camera whose pixels are
/// not square or are skewed; `None` with square, unskewed pixels (where it
/// is `mm_s / pitch`).
pub fn sample_px(
    s: &GyroSample,
    opts: &SeriesOptions,
    ev: &Evaluator,
    mm_s: f64,
) -> Result<Option<f64>> {
    if crate::metric::pixel_map(&opts.scene.camera).is_none() {
        return Ok(None);
    }
    let (tw, scene) = sample_scene(s, opts)?;
    ev.mean_px_speed(&scene.flow_poly(&tw), mm_s).map(Some)
}

/// Checks that every value of a batch is a finite MMBM (an overflow of huge
/// rates gives inf or NaN), naming the first bad sample.
pub fn check_values(batch: &[GyroSample], values: &[f64]) -> Result<()> {
    match batch.iter().zip(values).find(|(_, m)| !m.is_finite()) {
        Some((s, m)) => Err(Error::invalid(
            format!("sample at t = {} s", s.t),
            format!("MMBM is {m}: the flow overflows (rates near the float range?)"),
        )),
        None => Ok(()),
    }
}

/// Evaluates a batch of samples on the CPU (rayon), mm/s per sample.
pub fn eval_batch_cpu(batch: &[GyroSample], opts: &SeriesOptions) -> Result<Vec<f64>> {
    let ev = Evaluator::new(&opts.scene.camera, opts.method)?;
    batch
        .par_iter()
        .with_min_len(1024)
        .map(|s| sample_mmbm(s, opts, &ev))
        .collect::<Result<Vec<f64>>>()
        .and_then(|v| check_values(batch, &v).map(|_| v))
}

/// The rotation-only MMBM (mm/s) of every sample, the thesis's metric, with
/// `scene`'s camera and a CPU `method` (the thesis used `riemann:8x6`).
pub fn mmbm_series(samples: &[GyroSample], scene: &Scene, method: Method) -> Result<Vec<f64>> {
    mmbm_series_with(
        samples,
        &SeriesOptions {
            scene: *scene,
            method,
            use_velocity: false,
        },
    )
}

/// MMBM of every sample under full series options (e.g. `use_velocity` with
/// the log's velocity and a depth: an option, not the thesis default).
pub fn mmbm_series_with(samples: &[GyroSample], opts: &SeriesOptions) -> Result<Vec<f64>> {
    opts.scene.camera.validate()?;
    let mut out = Vec::with_capacity(samples.len());
    for chunk in samples.chunks(BATCH) {
        crate::cancel::check()?;
        out.extend(eval_batch_cpu(chunk, opts)?);
    }
    Ok(out)
}

/// A batch evaluator: CPU methods, or a GPU one supplied by the caller.
pub type BatchFn<'a> = dyn FnMut(&[GyroSample]) -> Result<Vec<f64>> + 'a;

/// The batch evaluator of `opts`' method: [`eval_batch_cpu`] for a CPU
/// rule, [`gpu::series_evaluator`] on its grid for `gpu[:WxH]`.
pub fn evaluator(opts: SeriesOptions<AnyMethod>) -> Result<Box<BatchFn<'static>>> {
    match opts.method {
        AnyMethod::Gpu { width, height } => gpu::series_evaluator(opts, width, height),
        AnyMethod::Cpu(method) => {
            let cpu = SeriesOptions {
                scene: opts.scene,
                method,
                use_velocity: opts.use_velocity,
            };
            Ok(Box::new(move |b: &[GyroSample]| eval_batch_cpu(b, &cpu)))
        }
    }
}

/// The MMBM in px/s of a sample given its MMBM in mm/s (the true pixel
/// speed, as [`crate::Mmbm::px_s`]).
pub type PxFn = dyn Fn(&GyroSample, f64) -> Result<f64> + Sync;

/// The px/s of `opts`' samples ([`PxFn`]): mm/s over the pitch with square,
/// unskewed pixels; otherwise the mean true pixel speed
/// ([`Evaluator::mean_px_speed`]) with the CPU method, or for `gpu:WxH` the
/// midpoint rule at the field's `W x H` cells (the points the field averages).
pub fn px_of(opts: &SeriesOptions<AnyMethod>) -> Result<Box<PxFn>> {
    let cam = opts.scene.camera;
    if crate::metric::pixel_map(&cam).is_none() {
        let pitch = cam.pitch_x_mm;
        return Ok(Box::new(move |_, m| crate::camera::checked_px_s(m, pitch)));
    }
    let method = match opts.method {
        AnyMethod::Cpu(m) => m,
        AnyMethod::Gpu { width, height } => Method::Riemann {
            nu: if width == 0 { cam.width } else { width },
            nv: if height == 0 { cam.height } else { height },
        },
    };
    let ev = Evaluator::new(&cam, method)?;
    let cpu = SeriesOptions {
        scene: opts.scene,
        method,
        use_velocity: opts.use_velocity,
    };
    Ok(Box::new(move |s, m| {
        let (tw, scene) = sample_scene(s, &cpu)?;
        ev.mean_px_speed(&scene.flow_poly(&tw), m)
    }))
}

/// What [`run`] reads: a log streamed by its [`GyroReader`], or samples
/// already read (a camera file, `crate::telemetry`).
pub enum Samples {
    /// A streaming log reader (its warnings printed when it is done).
    Reader(Box<GyroReader>),
    /// Samples in memory.
    Read(std::vec::IntoIter<GyroSample>),
}

impl From<GyroReader> for Samples {
    fn from(r: GyroReader) -> Self {
        Samples::Reader(Box::new(r))
    }
}

impl Samples {
    fn print_warnings(&self) {
        if let Samples::Reader(r) = self {
            r.print_warnings();
        }
    }
}

impl Iterator for Samples {
    type Item = Result<GyroSample>;
    fn next(&mut self) -> Option<Self::Item> {
        match self {
            Samples::Reader(r) => r.next(),
            Samples::Read(s) => s.next().map(Ok),
        }
    }
}

/// Streams `reader` through `eval` in batches of [`BATCH`] and writes the CSV.
/// Parsing runs on a second thread, overlapped with evaluation and
/// formatting (shortest round-trip floats, `push_f64`). Returns the number of samples.
/// `px` gives each sample's px/s ([`px_of`]); `blur_px` is px/s times the exposure.
pub fn run<W: Write>(
    reader: impl Into<Samples>,
    eval: &mut BatchFn,
    px: &PxFn,
    exposure_s: Option<f64>,
    out: W,
) -> Result<u64> {
    let reader: Samples = reader.into();
    // Rows come formatted in blocks of FORMAT_CHUNK (about 100 KB): a
    // buffer smaller than a block passes them straight to `out`, uncopied.
    let mut out = std::io::BufWriter::with_capacity(1 << 16, out);
    let werr = |e: std::io::Error| Error::io("<series output>", e);
    out.write_all(match exposure_s {
        Some(_) => b"t,mmbm_mm_s,mmbm_px_s,blur_px\n".as_slice(),
        None => b"t,mmbm_mm_s,mmbm_px_s\n".as_slice(),
    })
    .map_err(werr)?;
    let (tx, rx) = std::sync::mpsc::sync_channel::<Result<Vec<GyroSample>>>(2);
    std::thread::scope(|scope| {
        scope.spawn(move || {
            let mut reader = reader;
            loop {
                let mut batch = Vec::with_capacity(BATCH);
                let mut failed = None;
                for s in reader.by_ref().take(BATCH) {
                    match s {
                        Ok(s) => batch.push(s),
                        Err(e) => {
                            failed = Some(e);
                            break;
                        }
                    }
                }
                let done = batch.len() < BATCH || failed.is_some();
                let msg = match failed {
                    Some(e) => Err(e),
                    None => Ok(batch),
                };
                // A closed channel means the consumer failed: just stop.
                if tx.send(msg).is_err() || done {
                    reader.print_warnings();
                    return;
                }
            }
        });
        let mut n = 0;
        for batch in rx {
            let batch = batch?;
            if batch.is_empty() {
                break;
            }
            // The exposure of blur_px must be resolved by the time stamps
            // (`trigger`'s rule: ns epoch stamps read as seconds are refused).
            if let Some(te) = exposure_s {
                crate::model::log::check_resolution(
                    crate::model::log::max_abs_time(&batch),
                    te,
                    "the exposure (--exposure)",
                )?;
            }
            let vals = eval(&batch)?;
            if vals.len() != batch.len() {
                return Err(Error::invalid(
                    "series",
                    format!("{} values for {} samples", vals.len(), batch.len()),
                ));
            }
            // Formatted in parallel, written in order (the first error is
            // the first bad sample's).
            let texts: Vec<Result<Vec<u8>>> = batch
                .par_chunks(FORMAT_CHUNK)
                .zip(vals.par_chunks(FORMAT_CHUNK))
                .map(|(b, v)| format_rows(b, v, px, exposure_s))
                .collect();
            for text in texts {
                out.write_all(&text?).map_err(werr)?;
            }
            n += batch.len() as u64;
        }
        out.flush().map_err(werr)?;
        Ok(n)
    })
}

/// Rows formatted per parallel task by [`run`].
const FORMAT_CHUNK: usize = 2048;

/// The CSV rows of `batch` with its MMBM values `vals` (mm/s): `t`, mm/s,
/// px/s and, with an exposure, the blur in px, shortest round-trip floats
/// ([`push_f64`]); an error names the first sample whose px value overflows.
fn format_rows(
    batch: &[GyroSample],
    vals: &[f64],
    px: &PxFn,
    exposure_s: Option<f64>,
) -> Result<Vec<u8>> {
    let mut out = Vec::with_capacity(batch.len() * 72);
    let mut z = zmij::Buffer::new();
    for (s, m) in batch.iter().zip(vals) {
        let at = |e: Error| Error::invalid(format!("sample at t = {} s", s.t), e.to_string());
        let px = px(s, *m).map_err(at)?;
        let blur = exposure_s.map(|te| px * te);
        if let Some(b) = blur.filter(|b| !b.is_finite()) {
            return Err(at(Error::invalid(
                "blur",
                format!("{px:?} px/s over the exposure is {b} px, not a finite number"),
            )));
        }
        push_f64(&mut out, &mut z, s.t);
        out.push(b',');
        push_f64(&mut out, &mut z, *m);
        out.push(b',');
        push_f64(&mut out, &mut z, px);
        if let Some(blur) = blur {
            out.push(b',');
            push_f64(&mut out, &mut z, blur);
        }
        out.push(b'\n');
    }
    Ok(out)
}

/// Appends `x` as `ryu` writes it (the shortest text that reads back to
/// `x`: `0.005`, `1e-7`, `1e16`), by `zmij`, about twice as fast and the
/// same but for the `+` of a positive exponent (`1e+16`), dropped here.
fn push_f64(out: &mut Vec<u8>, z: &mut zmij::Buffer, x: f64) {
    if !x.is_finite() {
        out.extend_from_slice(ryu::Buffer::new().format(x).as_bytes());
        return;
    }
    let text = z.format_finite(x).as_bytes();
    match memchr::memchr(b'+', text) {
        None => out.extend_from_slice(text),
        Some(i) => {
            out.extend_from_slice(&text[..i]);
            out.extend_from_slice(&text[i + 1..]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::push_f64;
    use rand::{Rng, SeedableRng};

    #[test]
    fn floats_are_written_as_ryu_writes_them() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(24);
        let mut z = zmij::Buffer::new();
        let mut r = ryu::Buffer::new();
        let special = [
            0.0,
            -0.0,
            1e-5,
            1e-6,
            1e-7,
            1e15,
            1e16,
            -1e16,
            5e-324,
            f64::MAX,
            f64::MIN_POSITIVE,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let random = (0..1_000_000).flat_map(|_| {
            let t = f64::from(rng.gen_range(0..10_000_000)) * 0.005;
            let x = rng.gen_range(-1.0..1.0) * 10f64.powi(rng.gen_range(-30..30));
            [f64::from_bits(rng.gen()), t, x]
        });
        for x in special.into_iter().chain(random) {
            let mut out = Vec::new();
            push_f64(&mut out, &mut z, x);
            assert_eq!(out, r.format(x).as_bytes(), "{x:e}");
        }
    }
}
