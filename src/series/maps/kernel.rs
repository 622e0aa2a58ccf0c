//! Host side of `maps.wgsl` (the GPU path of `frames --maps`): the
//! structs shared with WGSL (with layout asserts), their packing from a
//! frame's `Plan`, the dispatch loop both backends share, and the CPU twin
//! of the kernel: the same f32 operations, function by function (the lens
//! module's are twinned in [`crate::gpu::lens`], the lens table's in
//! [`super::table`]).
//!
//! The f64 reference is [`super::frame_maps`]; the twin and the kernel
//! agree with it to f32 rounding of the track (see `cli/tests/frames/maps_gpu.rs`).

use super::line::LineMotion;
pub use super::table::MapsTable;
use super::{plan, FrameMaps, MapRays, MapsJob, Plan};
use crate::error::{Error, Result};
use crate::gpu::lens::{self, LensGpu, MODEL_NONE, MODEL_TABLE};
use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

/// Threads per workgroup (`WG` in the shader).
pub const WG: u32 = 64;
/// Most workgroups along one dispatch dimension (WebGPU default limit).
pub const MAX_DISPATCH: u32 = 65_535;
/// Most bytes of motion samples per dispatch (a frame's lines are split
/// into dispatches under it).
pub const STEP_BYTES: usize = 32 << 20;
/// Output planes: disp.u, disp.v, path_px, flow.u, flow.v.
pub const PLANES: usize = 5;

/// The shader's `Params`: frame, lines of the dispatch, camera and lens.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct MapsParams {
    /// Frame width, px.
    pub width: u32,
    /// Frame height, px.
    pub height: u32,
    /// Pixels per line.
    pub line_len: u32,
    /// 1: lines are rows; 0: columns.
    pub rows: u32,
    /// First line of the dispatch.
    pub first_line: u32,
    /// Lines in the dispatch.
    pub n_lines: u32,
    /// Chords per line.
    pub steps: u32,
    /// 1 with a scene plane.
    pub use_plane: u32,
    /// Focal length, mm.
    pub f_mm: f32,
    /// `f / pitch_x`, px per normalised unit.
    pub fx: f32,
    /// `f / pitch_y`.
    pub fy: f32,
    /// Skew, px per normalised unit of y.
    pub skew: f32,
    /// Pixel pitch x, mm.
    pub pitch_x: f32,
    /// Pixel pitch y, mm.
    pub pitch_y: f32,
    /// Skew (px) over the focal length (mm).
    pub skew_over_f: f32,
    /// Workgroups along x.
    pub groups_x: u32,
    /// The lens ([`crate::gpu::lens`]): none, OpenCV or fisheye analytic,
    /// else the lens table ([`MapsTable`]).
    pub lens: LensGpu,
    /// The lens table's [`MapsTable::geometry`] (zeros without one).
    pub table: [f32; 4],
    /// The lens table's [`MapsTable::n`] (zeros without one).
    pub table_n: [u32; 4],
}

/// The shader's `Line`: the start flow polynomial and the scene plane.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct LineGpu {
    /// `du[0..6]` then `dv[0..6]` of [`crate::model::flow::FlowPoly`].
    pub poly: [f32; 12],
    /// Inverse depth along `(x, y, 1)`: `[a, b, c, 0]` for `a x + b y + c`.
    pub plane: [f32; 4],
}

/// The shader's `Step`: one motion sample of a line.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct StepGpu {
    /// Rotation from the line's start frame, quaternion `x, y, z, w`.
    pub q: [f32; 4],
    /// Offset of the start's centre (m) in `xyz`.
    pub b: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<MapsParams>() == 128);
const _: () = assert!(std::mem::offset_of!(MapsParams, f_mm) == 32);
const _: () = assert!(std::mem::offset_of!(MapsParams, groups_x) == 60);
const _: () = assert!(std::mem::offset_of!(MapsParams, lens) == 64);
const _: () = assert!(std::mem::offset_of!(MapsParams, table) == 96);
const _: () = assert!(std::mem::offset_of!(MapsParams, table_n) == 112);
const _: () = assert!(std::mem::size_of::<LineGpu>() == 64);
const _: () = assert!(std::mem::offset_of!(LineGpu, plane) == 48);
const _: () = assert!(std::mem::size_of::<StepGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(StepGpu, b) == 16);

/// The lens table of `rays`' camera when the kernel needs one (a model
/// without a formula in the lens module: [`MODEL_TABLE`]), else `None`.
pub fn lens_table(rays: &MapRays) -> Result<Option<MapsTable>> {
    match rays.camera().distortion.coefficients() {
        Some(_) => Ok(None),
        None => MapsTable::new(rays).map(Some),
    }
}

/// The parameters of `plan`'s frame (lines 0..0 of the dispatch), with
/// `table`'s geometry in table mode.
fn params(plan: &Plan, table: Option<&MapsTable>) -> Result<MapsParams> {
    let c = &plan.cam;
    let lens = LensGpu::new(c.distortion.coefficients());
    let (table, table_n) = match (lens.model, table) {
        (MODEL_TABLE, Some(t)) => (t.geometry, t.n),
        (MODEL_TABLE, None) => {
            return Err(Error::invalid(
                "distortion",
                format!(
                    "the {} model needs the maps kernel's lens table",
                    c.distortion.name()
                ),
            ))
        }
        _ => ([0.0; 4], [0; 4]),
    };
    let steps = u32::try_from(plan.steps)
        .map_err(|_| Error::invalid("maps", format!("{} steps per line", plan.steps)))?;
    Ok(MapsParams {
        width: c.width,
        height: c.height,
        line_len: plan.lines().1 as u32,
        rows: plan.rows as u32,
        first_line: 0,
        n_lines: 0,
        steps,
        use_plane: plan.plane.is_some() as u32,
        f_mm: c.focal_mm as f32,
        fx: c.fx_px() as f32,
        fy: c.fy_px() as f32,
        skew: c.skew as f32,
        pitch_x: c.pitch_x_mm as f32,
        pitch_y: c.pitch_y_mm as f32,
        skew_over_f: (c.skew / c.focal_mm) as f32,
        groups_x: 0,
        lens,
        table,
        table_n,
    })
}

/// The rays of a camera as the kernel reads them: `(x, y, 1, 0)`, or zeros
/// where the pixel has none.
pub fn pack_rays(rays: &MapRays) -> Vec<[f32; 4]> {
    rays.rays()
        .par_iter()
        .with_min_len(4096)
        .map(|&(x, y)| {
            if x.is_finite() && y.is_finite() {
                [x as f32, y as f32, 1.0, 0.0]
            } else {
                [0.0; 4]
            }
        })
        .collect()
}

/// Packs one line's motion: its [`LineGpu`] and `steps + 1` [`StepGpu`]s.
fn pack_line(m: &LineMotion, steps: &mut [StepGpu]) -> LineGpu {
    for (s, (q, b)) in steps.iter_mut().zip(&m.steps) {
        *s = StepGpu {
            q: [q.x as f32, q.y as f32, q.z as f32, q.w as f32],
            b: [b.x as f32, b.y as f32, b.z as f32, 0.0],
        };
    }
    let plane = m.plane.map_or([0.0; 4], |(n, d)| {
        // n . (R r) / d = (R^T n) . r / d.
        let p = m.start.inverse() * n / d;
        [p.x as f32, p.y as f32, p.z as f32, 0.0]
    });
    let f = &m.flow;
    let mut poly = [0.0f32; 12];
    for k in 0..6 {
        poly[k] = f.du[k] as f32;
        poly[6 + k] = f.dv[k] as f32;
    }
    LineGpu { poly, plane }
}

/// Runs `dispatch(params, lines, steps)` over the job's frame's lines
/// (split so a dispatch's motion samples stay under `step_bytes`) and
/// returns the plan; `None` as [`super::frame_maps`]. `table`: the
/// camera's [`lens_table`].
/// `params.groups_x` is for a 1-D grid of `n_lines * line_len` threads in
/// up to [`MAX_DISPATCH`] columns.
pub(crate) fn drive(
    job: &MapsJob,
    table: Option<&MapsTable>,
    step_bytes: usize,
    mut dispatch: impl FnMut(&MapsParams, &[LineGpu], &[StepGpu]) -> Result<()>,
) -> Result<Option<Plan>> {
    let Some(plan) = plan(job)? else {
        return Ok(None);
    };
    let log = job.log;
    let mut p = params(&plan, table)?;
    let (n_lines, len) = plan.lines();
    let per_line = plan.steps + 1;
    let chunk = (step_bytes / (per_line * std::mem::size_of::<StepGpu>())).clamp(1, n_lines);
    let mut steps_buf = vec![StepGpu::zeroed(); chunk * per_line];
    let mut lines_buf = vec![LineGpu::zeroed(); chunk];
    for l0 in (0..n_lines).step_by(chunk) {
        crate::cancel::check()?;
        let nl = chunk.min(n_lines - l0);
        lines_buf[..nl]
            .par_iter_mut()
            .zip(steps_buf[..nl * per_line].par_chunks_mut(per_line))
            .enumerate()
            .for_each(|(k, (line, st))| *line = pack_line(&plan.line(log, l0 + k), st));
        let groups = ((nl * len) as u64).div_ceil(WG as u64);
        p.first_line = l0 as u32;
        p.n_lines = nl as u32;
        p.groups_x = groups.min(MAX_DISPATCH as u64) as u32;
        dispatch(&p, &lines_buf[..nl], &steps_buf[..nl * per_line])?;
    }
    Ok(Some(plan))
}

/// The maps of `plan`'s frame from the kernel's planes (`PLANES` of
/// `width * height`): a pixel whose path is negative has none (NaN).
pub(crate) fn unpack(plan: &Plan, index: usize, out: &[f32]) -> FrameMaps {
    let n = plan.cam.width as usize * plan.cam.height as usize;
    let path = &out[2 * n..3 * n];
    let ch: [Vec<f32>; PLANES] = std::array::from_fn(|c| {
        out[c * n..(c + 1) * n]
            .iter()
            .zip(path)
            .map(|(&v, &p)| if p < 0.0 { f32::NAN } else { v })
            .collect()
    });
    plan.finish(index, ch)
}

/// The blur fields of a job's frame by the CPU twin of `maps.wgsl`
/// (f32, rayon), in the kernel's dispatches; as [`super::frame_maps`].
pub fn frame_maps_twin(job: &MapsJob) -> Result<Option<FrameMaps>> {
    let cam = &job.opts.scene.camera;
    let n = cam.width as usize * cam.height as usize;
    let packed = pack_rays(job.rays);
    let table = lens_table(job.rays)?;
    let mut out = vec![0.0f32; PLANES * n];
    let plan = drive(job, table.as_ref(), STEP_BYTES, |p, l, s| {
        dispatch_twin(p, &packed, table.as_ref(), l, s, &mut out);
        Ok(())
    })?;
    Ok(plan.map(|plan| unpack(&plan, job.index, &out)))
}

/// Twin of one dispatch of `maps`: every thread (pixel of the dispatch's
/// lines) writes its planes of `out`. `table`: the lens table in table mode.
pub fn dispatch_twin(
    p: &MapsParams,
    rays: &[[f32; 4]],
    table: Option<&MapsTable>,
    lines: &[LineGpu],
    steps: &[StepGpu],
    out: &mut [f32],
) {
    let n = p.width as usize * p.height as usize;
    let vals: Vec<(usize, Option<[f32; PLANES]>)> = (0..p.n_lines * p.line_len)
        .into_par_iter()
        .with_min_len(256)
        .map(|idx| thread(p, rays, table, lines, steps, idx))
        .collect();
    for (pix, v) in vals {
        match v {
            Some(v) => {
                for (c, x) in v.into_iter().enumerate() {
                    out[c * n + pix] = x;
                }
            }
            None => out[2 * n + pix] = -1.0,
        }
    }
}

/// Twin of the shader's `line_flow`.
#[inline(always)]
fn line_flow(l: &LineGpu, u: f32, v: f32) -> (f32, f32) {
    let c = &l.poly;
    let du = c[0] + u * (c[1] + c[3] * u + c[4] * v) + v * (c[2] + c[5] * v);
    let dv = c[6] + u * (c[7] + c[9] * u + c[10] * v) + v * (c[8] + c[11] * v);
    (du, dv)
}

/// Twin of the shader's `cross`.
#[inline(always)]
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Twin of the shader's `moved`.
#[inline(always)]
fn moved(st: &StepGpu, r: [f32; 3], s: f32) -> [f32; 3] {
    let v = [st.q[0], st.q[1], st.q[2]];
    let c = cross(v, r);
    let vc = cross(v, c);
    let d: [f32; 3] = std::array::from_fn(|k| 2.0 * st.q[3] * c[k] + 2.0 * vc[k] + st.b[k] * s);
    let z = 1.0 + d[2];
    [(d[0] - r[0] * d[2]) / z, (d[1] - r[1] * d[2]) / z, z]
}

/// The lens of a thread: the lens module's, or the table with the cell of
/// the pixel's ray.
enum ThreadLens<'a> {
    Module(&'a LensGpu),
    Table(&'a MapsTable, [f32; 4]),
}

/// Twin of the shader's `position`.
#[inline(always)]
fn position(p: &MapsParams, l: &ThreadLens, r: [f32; 2], e: [f32; 2]) -> [f32; 2] {
    let q = match l {
        ThreadLens::Table(t, c) => t.distort(*c, e),
        ThreadLens::Module(m) if m.model != MODEL_NONE => {
            lens::distort(m, r[0] + e[0], r[1] + e[1])
        }
        ThreadLens::Module(_) => (e[0], e[1]),
    };
    [p.fx * q.0 + p.skew * q.1, p.fy * q.1]
}

/// Twin of one thread of `maps`: the pixel index and its five values, or
/// `None` (path -1 on the GPU). The negated comparisons are the shader's
/// (false for NaN).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn thread(
    p: &MapsParams,
    rays: &[[f32; 4]],
    table: Option<&MapsTable>,
    lines: &[LineGpu],
    steps: &[StepGpu],
    idx: u32,
) -> (usize, Option<[f32; PLANES]>) {
    let ll = idx / p.line_len;
    let m = idx % p.line_len;
    let line = p.first_line + ll;
    let (i, j) = if p.rows == 0 { (line, m) } else { (m, line) };
    let pix = (j * p.width + i) as usize;
    let ray = rays[pix];
    let l = &lines[ll as usize];
    let r = [ray[0], ray[1], 1.0];
    let s = l.plane[0] * r[0] + l.plane[1] * r[1] + l.plane[2];
    if !(ray[2] != 0.0 && (p.use_plane == 0 || s > 0.0)) {
        return (pix, None);
    }
    let lp = match table {
        Some(t) if p.lens.model == MODEL_TABLE => ThreadLens::Table(t, t.cell(r[0], r[1])),
        _ => ThreadLens::Module(&p.lens),
    };
    let base = (ll * (p.steps + 1)) as usize;
    let (mut first, mut prev, mut path) = ([0.0f32; 2], [0.0f32; 2], 0.0f32);
    for (k, st) in steps[base..=base + p.steps as usize].iter().enumerate() {
        let t = moved(st, r, s);
        if !(t[2] > 1e-12) {
            return (pix, None);
        }
        let q = position(p, &lp, [r[0], r[1]], [t[0], t[1]]);
        if k == 0 {
            first = q;
        } else {
            let d = [q[0] - prev[0], q[1] - prev[1]];
            path += (d[0] * d[0] + d[1] * d[1]).sqrt();
        }
        prev = q;
    }
    let (mut fu, mut fv) = line_flow(l, p.f_mm * r[0], p.f_mm * r[1]);
    if p.lens.model != MODEL_NONE {
        let jm = match lp {
            ThreadLens::Table(t, _) => {
                let g = t.jac[pix];
                [[g[0], g[1]], [g[2], g[3]]]
            }
            ThreadLens::Module(m) => lens::jacobian(m, r[0], r[1]),
        };
        (fu, fv) = (jm[0][0] * fu + jm[0][1] * fv, jm[1][0] * fu + jm[1][1] * fv);
    }
    // Twin of the shader's `px_velocity`.
    let vel = [fu / p.pitch_x + p.skew_over_f * fv, fv / p.pitch_y];
    (
        pix,
        Some([prev[0] - first[0], prev[1] - first[1], path, vel[0], vel[1]]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::gpu::compute::shader_const;

    #[test]
    fn shader_constants_and_struct_sizes_match_host() {
        let m = naga::front::wgsl::parse_str(super::super::gpu::MAPS_WGSL).expect("parses");
        assert_eq!(shader_const(&m, "UNDISTORT_STEPS"), lens::UNDISTORT_STEPS);
        assert_eq!(shader_const(&m, "WG"), WG);
        assert_eq!(m.entry_points.len(), 1);
        assert_eq!(m.entry_points[0].workgroup_size, [WG, 1, 1]);
        // The WGSL structs' sizes (naga's layout) equal the host structs'.
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(m.to_ctx()).expect("layout");
        for (name, size) in [
            ("Params", std::mem::size_of::<MapsParams>()),
            ("Line", std::mem::size_of::<LineGpu>()),
            ("Step", std::mem::size_of::<StepGpu>()),
            ("Node", std::mem::size_of::<super::super::table::NodeGpu>()),
            ("Lens", std::mem::size_of::<LensGpu>()),
        ] {
            let (h, _) = m
                .types
                .iter()
                .find(|(_, t)| t.name.as_deref() == Some(name))
                .unwrap_or_else(|| panic!("maps.wgsl has no struct {name}"));
            assert_eq!(layouter[h].size as usize, size, "{name}");
        }
    }

    #[test]
    fn every_model_has_a_lens_strategy() {
        // The analytic models run from the lens module, every other from the table.
        let cam = Camera {
            distortion: crate::camera::Distortion::Poly3 { k1: 0.01 },
            ..Camera::thesis().scaled_to(32, 24)
        };
        let rays = MapRays::new(&cam).unwrap();
        let t = lens_table(&rays).unwrap().expect("poly3 takes the table");
        assert_eq!(t.nodes.len(), (t.n[0] * t.n[1]) as usize);
        let thesis = MapRays::new(&Camera::thesis().scaled_to(32, 24)).unwrap();
        assert!(lens_table(&thesis).unwrap().is_none());
    }
}
