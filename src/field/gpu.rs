//! The compiled flow kernels (`src/gpu/lens.wgsl` joined with `field.wgsl`) and a runner that owns reusable
//! buffers and dispatches them. CPU twins: [`super::cpu`].

use super::kernel::{FlowParams, Grid, TwistGpu, MAX_DISPATCH, WG};
use super::table::{valid_len, LensTable};
use crate::error::{Error, Result};
use crate::gpu::compute::{
    self, ensure, read_back, storage_entry, uniform_entry, Buf, Kernel, READ, STORAGE_DST,
    STORAGE_SRC,
};
use crate::gpu::GpuContext;
use std::sync::{Arc, OnceLock};

/// The WGSL source of the flow kernels: the shared lens module
/// ([`crate::gpu::lens::LENS_WGSL`]) joined with `field.wgsl`.
pub const FIELD_WGSL: &str = concat!(include_str!("../gpu/lens.wgsl"), include_str!("field.wgsl"));

/// Grids of at most this many samples use `rows_per_twist` (one thread per
/// twist) for batches; larger ones use `flow_tiles` (one workgroup per tile).
pub const ROWS_KERNEL_MAX_SAMPLES: usize = 4096;

/// The two entry points (one bind group layout, [`compute::build_each`]).
pub struct Kernels {
    tiles: Kernel,
    rows: Kernel,
}

fn build(ctx: &GpuContext) -> Result<Kernels> {
    let layout = [
        uniform_entry(0),
        storage_entry(1, true),
        storage_entry(2, false),
        storage_entry(3, false),
        storage_entry(4, true),
    ];
    let [tiles, rows] = compute::build_each(
        ctx,
        "field.wgsl",
        FIELD_WGSL,
        &layout,
        ["flow_tiles", "rows_per_twist"],
    )?;
    Ok(Kernels { tiles, rows })
}

static KERNELS: OnceLock<std::result::Result<Kernels, String>> = OnceLock::new();

/// The shared device and the flow kernels (compiled once per process).
pub fn kernels() -> Result<(&'static GpuContext, &'static Kernels)> {
    compute::compiled(&KERNELS, build)
}

/// Dispatches the flow kernels, reusing its buffers between calls (they grow as needed).
pub struct FlowRunner {
    ctx: &'static GpuContext,
    k: &'static Kernels,
    params: wgpu::Buffer,
    twists: Option<Buf>,
    field: Option<Buf>,
    partials: Option<Buf>,
    field_read: Option<Buf>,
    partials_read: Option<Buf>,
    /// The lens table on the device (one dummy entry without a table) and
    /// the grid it is for.
    lens: Option<Buf>,
    lens_for: Option<Grid>,
}

impl FlowRunner {
    /// A runner on the shared device (errors when there is no adapter).
    pub fn new() -> Result<Self> {
        let (ctx, k) = kernels()?;
        let params = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("flow params"),
            size: std::mem::size_of::<FlowParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(FlowRunner {
            ctx,
            k,
            params,
            twists: None,
            field: None,
            partials: None,
            field_read: None,
            partials_read: None,
            lens: None,
            lens_for: None,
        })
    }

    /// The lens table of `grid` when it uses one ([`LensTable::cached`]),
    /// uploaded to the device once per grid and camera; without one a dummy
    /// entry is bound.
    pub fn lens(&mut self, grid: &Grid) -> Result<Option<Arc<LensTable>>> {
        let table = LensTable::cached(grid)?;
        let uploaded = self.lens.is_some() && (table.is_none() || self.lens_for == Some(*grid));
        if !uploaded {
            let bytes: &[u8] = match &table {
                Some(t) => bytemuck::cast_slice(&t.samples),
                None => &[0u8; 24],
            };
            self.lens_for = None;
            let buf = ensure(
                self.ctx,
                &mut self.lens,
                bytes.len() as u64,
                STORAGE_DST,
                "flow lens table",
            )?;
            self.ctx.queue.write_buffer(buf, 0, bytes);
            if table.is_some() {
                self.lens_for = Some(*grid);
            }
        }
        Ok(table)
    }

    /// `name (backend, type)` of the adapter.
    pub fn adapter(&self) -> &str {
        &self.ctx.description
    }

    /// Runs one kernel: uploads `p` and `twists`, dispatches `groups`,
    /// returns `n_partials` f32 partial sums and, with `read_field`, the
    /// field of `field_len` samples.
    #[allow(clippy::too_many_arguments)]
    fn dispatch(
        &mut self,
        p: &FlowParams,
        twists: &[TwistGpu],
        rows: bool,
        groups: (u32, u32, u32),
        n_partials: u64,
        field_len: u64,
        read_field: bool,
    ) -> Result<(Vec<f32>, Vec<[f32; 2]>)> {
        let ctx = self.ctx;
        let tw_bytes: &[u8] = bytemuck::cast_slice(twists);
        let pbytes = n_partials * 4;
        let fbytes = field_len * 8;
        ensure(
            ctx,
            &mut self.twists,
            tw_bytes.len() as u64,
            STORAGE_DST,
            "flow twists",
        )?;
        ensure(
            ctx,
            &mut self.partials,
            pbytes,
            STORAGE_SRC,
            "flow partial sums",
        )?;
        ensure(
            ctx,
            &mut self.partials_read,
            pbytes,
            READ,
            "flow partials readback",
        )?;
        ensure(ctx, &mut self.field, fbytes, STORAGE_SRC, "flow field")?;
        if read_field {
            ensure(
                ctx,
                &mut self.field_read,
                fbytes,
                READ,
                "flow field readback",
            )?;
        }
        let (tw_buf, part, field, lens) =
            match (&self.twists, &self.partials, &self.field, &self.lens) {
                (Some(a), Some(b), Some(c), Some(d)) => (&a.buf, &b.buf, &c.buf, &d.buf),
                _ => return Err(Error::Gpu("flow buffers missing".into())),
            };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(p));
        ctx.queue.write_buffer(tw_buf, 0, tw_bytes);
        let bg = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("flow"),
            layout: &self.k.tiles.bgl,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: tw_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: field.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: part.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: lens.as_entire_binding(),
                },
            ],
        });
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("flow"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("flow"),
                timestamp_writes: None,
            });
            pass.set_pipeline(if rows {
                &self.k.rows.pipeline
            } else {
                &self.k.tiles.pipeline
            });
            pass.set_bind_group(0, &bg, &[]);
            pass.dispatch_workgroups(groups.0, groups.1, groups.2);
        }
        let pread = &self.partials_read.as_ref().expect("ensured").buf;
        enc.copy_buffer_to_buffer(part, 0, pread, 0, pbytes);
        if read_field {
            let fread = &self.field_read.as_ref().expect("ensured").buf;
            enc.copy_buffer_to_buffer(field, 0, fread, 0, fbytes);
        }
        ctx.queue.submit([enc.finish()]);
        let partials: Vec<f32> =
            bytemuck::pod_collect_to_vec(&read_back(ctx, pread, pbytes, "flow kernel")?);
        let field = if read_field {
            let fread = &self.field_read.as_ref().expect("ensured").buf;
            bytemuck::pod_collect_to_vec(&read_back(ctx, fread, fbytes, "flow kernel")?)
        } else {
            Vec::new()
        };
        Ok((partials, field))
    }

    /// `flow_tiles` for up to `MAX_DISPATCH` twists: per twist the sum of
    /// speeds (mm/s) over the grid (masked samples add 0: [`FlowRunner::lens`]), as f32 tile partials summed in f64, and
    /// (one twist, `with_field`) the field in px/s.
    pub fn tiles(
        &mut self,
        grid: &Grid,
        twists: &[TwistGpu],
        with_field: bool,
    ) -> Result<(Vec<f64>, Vec<[f32; 2]>)> {
        self.tiles_ext(grid, twists, with_field, with_field)
    }

    /// [`FlowRunner::tiles`], writing the field on the device without reading
    /// it back when `read_field` is false (for timing the kernel alone).
    pub fn tiles_ext(
        &mut self,
        grid: &Grid,
        twists: &[TwistGpu],
        with_field: bool,
        read_field: bool,
    ) -> Result<(Vec<f64>, Vec<[f32; 2]>)> {
        let n = twists.len() as u32;
        if n == 0 || n > MAX_DISPATCH || (with_field && n != 1) {
            return Err(Error::invalid(
                "flow_tiles",
                format!("{n} twists: need 1..={MAX_DISPATCH}, and exactly 1 with a field"),
            ));
        }
        self.lens(grid)?;
        let p = grid.params(n, with_field);
        let n_partials = n as u64 * p.tiles as u64;
        if n_partials >= u32::MAX as u64 {
            return Err(Error::invalid(
                "gpu batch",
                "too many twists x tiles in one dispatch",
            ));
        }
        let gz = p.tiles.div_ceil(p.tiles_x);
        let field_len = if with_field { grid.len() as u64 } else { 0 };
        let groups = (p.tiles_x, n, gz);
        let read = with_field && read_field;
        let (part, field) =
            self.dispatch(&p, twists, false, groups, n_partials, field_len, read)?;
        let sums = part
            .chunks(p.tiles as usize)
            .map(|c| c.iter().map(|&x| x as f64).sum())
            .collect();
        Ok((sums, field))
    }

    /// `rows_per_twist` for up to `MAX_DISPATCH * 64` twists: per twist the
    /// sum of speeds (mm/s) over the grid, f32 row sums added in f64.
    pub fn rows(&mut self, grid: &Grid, twists: &[TwistGpu]) -> Result<Vec<f64>> {
        let n = twists.len() as u64;
        if n == 0 || n > MAX_DISPATCH as u64 * WG as u64 {
            return Err(Error::invalid(
                "rows_per_twist",
                format!("{n} twists: need 1..={}", MAX_DISPATCH * WG),
            ));
        }
        self.lens(grid)?;
        let p = grid.params(n as u32, false);
        let n_partials = n * grid.height as u64;
        let groups = (n as u32).div_ceil(WG);
        let (part, _) = self.dispatch(&p, twists, true, (groups, 1, 1), n_partials, 0, false)?;
        Ok(part
            .chunks(grid.height as usize)
            .map(|c| c.iter().map(|&x| x as f64).sum())
            .collect())
    }

    /// Mean speed (mm/s) per twist over `grid` (its valid samples: masked
    /// ones are out of the mean), any number of twists: small grids with
    /// `rows_per_twist`, larger ones with `flow_tiles`, in chunks.
    pub fn batch_means(&mut self, grid: &Grid, twists: &[TwistGpu]) -> Result<Vec<f64>> {
        let n = valid_len(grid, self.lens(grid)?.as_deref()) as f64;
        let mut out = Vec::with_capacity(twists.len());
        if grid.len() <= ROWS_KERNEL_MAX_SAMPLES {
            for c in twists.chunks(16_384) {
                out.extend(self.rows(grid, c)?.into_iter().map(|s| s / n));
            }
        } else {
            // Keep the partials buffer under ~64 MiB.
            let per = ((16 << 20) / grid.tiles() as usize).clamp(1, MAX_DISPATCH as usize);
            for c in twists.chunks(per) {
                out.extend(self.tiles(grid, c, false)?.0.into_iter().map(|s| s / n));
            }
        }
        Ok(out)
    }
}
