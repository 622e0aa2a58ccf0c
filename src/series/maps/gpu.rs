//! The GPU path of `frames --maps`: the compiled `maps.wgsl` (joined with
//! the lens module, `src/gpu/lens.wgsl`) and a runner that keeps the
//! camera's rays and lens table on the device and dispatches a
//! frame's lines. CPU twin: [`super::kernel::frame_maps_twin`]; the
//! packing and the dispatch loop are shared with it
//! ([`super::kernel`]).

use super::kernel::{self as mk, LineGpu, MapsParams, StepGpu, PLANES};
use super::table::NodeGpu;
use super::{FrameMaps, MapsJob};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::gpu::compute::{
    self, ensure, read_back, storage_entry, uniform_entry, Buf, Kernel, READ, STORAGE_DST,
    STORAGE_SRC,
};
use crate::gpu::{Backend, GpuContext, Resolved};
use bytemuck::Zeroable;
use std::sync::atomic::AtomicBool;
use std::sync::OnceLock;

/// The WGSL source of the maps kernel: the shared lens module
/// ([`crate::gpu::lens::LENS_WGSL`]) joined with `maps.wgsl`.
pub const MAPS_WGSL: &str = concat!(
    include_str!("../../gpu/lens.wgsl"),
    include_str!("maps.wgsl")
);

fn build(ctx: &GpuContext) -> Result<Kernel> {
    let layout = [
        uniform_entry(0),
        storage_entry(1, true),
        storage_entry(2, true),
        storage_entry(3, true),
        storage_entry(4, false),
        storage_entry(5, true),
        storage_entry(6, true),
    ];
    compute::build_one(ctx, "maps.wgsl", MAPS_WGSL, &layout, "maps")
}

static KERNEL: OnceLock<std::result::Result<Kernel, String>> = OnceLock::new();

/// Computes frames' maps on the GPU, reusing its buffers (the rays stay on
/// the device while the camera is the same).
pub struct MapsRunner {
    ctx: &'static GpuContext,
    k: &'static Kernel,
    params: wgpu::Buffer,
    rays_of: Option<Camera>,
    rays: Option<Buf>,
    table: Option<mk::MapsTable>,
    nodes: Option<Buf>,
    ray_jac: Option<Buf>,
    lines: Option<Buf>,
    steps: Option<Buf>,
    out: Option<Buf>,
    read: Option<Buf>,
    step_bytes: usize,
}

impl MapsRunner {
    /// A runner on the shared device (errors when there is no adapter).
    pub fn new() -> Result<Self> {
        let (ctx, k) = compute::compiled(&KERNEL, build)?;
        let params = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("maps params"),
            size: std::mem::size_of::<MapsParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(MapsRunner {
            ctx,
            k,
            params,
            rays_of: None,
            rays: None,
            table: None,
            nodes: None,
            ray_jac: None,
            lines: None,
            steps: None,
            out: None,
            read: None,
            step_bytes: mk::STEP_BYTES,
        })
    }

    /// Splits a frame's lines into dispatches of at most `bytes` of motion
    /// samples (at least one line each; default [`mk::STEP_BYTES`]).
    pub fn set_step_bytes(&mut self, bytes: usize) {
        self.step_bytes = bytes;
    }

    /// `name (backend, type)` of the adapter.
    pub fn adapter(&self) -> &str {
        &self.ctx.description
    }

    /// Checks that the kernel takes `cam`: its buffers within the
    /// device's limits (every lens model: the lens module's or the table).
    pub fn check(&self, cam: &Camera) -> Result<()> {
        let n = cam.width as u64 * cam.height as u64;
        let lim = self.ctx.device.limits();
        let most = lim.max_storage_buffer_binding_size.min(lim.max_buffer_size);
        let need = (n * 16).max(n * 4 * PLANES as u64);
        if need > most {
            return Err(Error::Gpu(format!(
                "maps of {}x{} need a {:.1} MiB buffer; {} allows {:.1} MiB: use --backend cpu",
                cam.width,
                cam.height,
                need as f64 / 1048576.0,
                self.ctx.description,
                most as f64 / 1048576.0
            )));
        }
        Ok(())
    }

    /// The maps of a frame on the GPU, as [`super::frame_maps`]
    /// (f32 throughout; lenses without a formula in the lens module through
    /// the lens table, [`mk::lens_table`]).
    pub fn frame_maps(&mut self, job: &MapsJob) -> Result<Option<FrameMaps>> {
        let cam = job.opts.scene.camera;
        self.check(&cam)?;
        let ctx = self.ctx;
        let n = cam.width as u64 * cam.height as u64;
        if self.rays_of != Some(*job.rays.camera()) {
            let packed = mk::pack_rays(job.rays);
            let bytes: &[u8] = bytemuck::cast_slice(&packed);
            let buf = ensure(
                ctx,
                &mut self.rays,
                bytes.len() as u64,
                STORAGE_DST,
                "maps rays",
            )?;
            ctx.queue.write_buffer(buf, 0, bytes);
            // The lens table (one dummy node without one).
            self.table = mk::lens_table(job.rays)?;
            let dummy = [NodeGpu::zeroed()];
            let nodes = self.table.as_ref().map_or(&dummy[..], |t| &t.nodes[..]);
            let bytes: &[u8] = bytemuck::cast_slice(nodes);
            let buf = ensure(
                ctx,
                &mut self.nodes,
                bytes.len() as u64,
                STORAGE_DST,
                "maps lens table",
            )?;
            ctx.queue.write_buffer(buf, 0, bytes);
            let dummy = [[0.0f32; 4]];
            let jac = self.table.as_ref().map_or(&dummy[..], |t| &t.jac[..]);
            let bytes: &[u8] = bytemuck::cast_slice(jac);
            let buf = ensure(
                ctx,
                &mut self.ray_jac,
                bytes.len() as u64,
                STORAGE_DST,
                "maps ray Jacobians",
            )?;
            ctx.queue.write_buffer(buf, 0, bytes);
            self.rays_of = Some(*job.rays.camera());
        }
        let out_bytes = n * 4 * PLANES as u64;
        ensure(ctx, &mut self.out, out_bytes, STORAGE_SRC, "maps output")?;
        ensure(ctx, &mut self.read, out_bytes, READ, "maps readback")?;
        let table = self.table.take();
        let plan = mk::drive(job, table.as_ref(), self.step_bytes, |p, l, s| {
            self.dispatch(p, l, s)
        });
        self.table = table;
        let Some(plan) = plan? else {
            return Ok(None);
        };
        let (out, read) = match (&self.out, &self.read) {
            (Some(o), Some(r)) => (&o.buf, &r.buf),
            _ => return Err(Error::Gpu("maps buffers missing".into())),
        };
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("maps readback"),
            });
        enc.copy_buffer_to_buffer(out, 0, read, 0, out_bytes);
        ctx.queue.submit([enc.finish()]);
        let planes: Vec<f32> =
            bytemuck::pod_collect_to_vec(&read_back(ctx, read, out_bytes, "maps kernel")?);
        Ok(Some(mk::unpack(&plan, job.index, &planes)))
    }

    /// One dispatch of `maps` over the lines of `p`.
    fn dispatch(&mut self, p: &MapsParams, lines: &[LineGpu], steps: &[StepGpu]) -> Result<()> {
        let ctx = self.ctx;
        let lb: &[u8] = bytemuck::cast_slice(lines);
        let sb: &[u8] = bytemuck::cast_slice(steps);
        ensure(
            ctx,
            &mut self.lines,
            lb.len() as u64,
            STORAGE_DST,
            "maps lines",
        )?;
        ensure(
            ctx,
            &mut self.steps,
            sb.len() as u64,
            STORAGE_DST,
            "maps steps",
        )?;
        let (rays, lbuf, sbuf, out, nodes, jac) = match (
            &self.rays,
            &self.lines,
            &self.steps,
            &self.out,
            &self.nodes,
            &self.ray_jac,
        ) {
            (Some(a), Some(b), Some(c), Some(d), Some(e), Some(f)) => {
                (&a.buf, &b.buf, &c.buf, &d.buf, &e.buf, &f.buf)
            }
            _ => return Err(Error::Gpu("maps buffers missing".into())),
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(p));
        ctx.queue.write_buffer(lbuf, 0, lb);
        ctx.queue.write_buffer(sbuf, 0, sb);
        let entries: Vec<wgpu::BindGroupEntry> = [&self.params, rays, lbuf, sbuf, out, nodes, jac]
            .iter()
            .enumerate()
            .map(|(k, b)| wgpu::BindGroupEntry {
                binding: k as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        let bg = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("maps"),
            layout: &self.k.bgl,
            entries: &entries,
        });
        let groups = (p.n_lines as u64 * p.line_len as u64).div_ceil(mk::WG as u64);
        let gy = groups.div_ceil(p.groups_x as u64) as u32;
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("maps"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("maps"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.k.pipeline);
            pass.set_bind_group(0, &bg, &[]);
            pass.dispatch_workgroups(p.groups_x, gy, 1);
        }
        ctx.queue.submit([enc.finish()]);
        Ok(())
    }
}

/// Where `frames --maps` computes: `Some(runner)` for the GPU, `None` for
/// the f64 CPU path. `Gpu` errors without an adapter or when the kernel
/// cannot take the camera ([`MapsRunner::check`]); `Auto` and `Bulk` fall
/// back to the CPU then, saying why on the log ([`Backend::resolve`] for
/// the adapter; `MMBM_REQUIRE_GPU=1` makes a missing adapter an error).
pub fn resolve(backend: Backend, cam: &Camera) -> Result<Option<MapsRunner>> {
    static ANNOUNCED: AtomicBool = AtomicBool::new(false);
    match backend.resolve("frames --maps", "path", &ANNOUNCED)? {
        Resolved::Cpu(_) => Ok(None),
        Resolved::Gpu(_) => {
            let r = MapsRunner::new()?;
            match r.check(cam) {
                Ok(()) => Ok(Some(r)),
                Err(e) if backend == Backend::Gpu => Err(e),
                Err(e) => {
                    log::warn!("frames --maps: {e}; using the CPU path");
                    Ok(None)
                }
            }
        }
    }
}
