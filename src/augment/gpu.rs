//! The GPU path of the warp integrator: `warp.wgsl` (beside this file) on
//! the shared wgpu device. The image is uploaded once (linear f32, four
//! channels per texel), the frame-to-image maps (per instant, and per row or
//! column with a rolling shutter) as a storage buffer; rows are dispatched
//! in bands of at most [`SAMPLES_PER_DISPATCH`] pixel-samples, each waited
//! for (no dispatch long enough to trip a watchdog; a stop request is seen
//! between them). CPU twin: [`super::warp_kernel`].

use super::warp::{Maps, Src};
use super::warp_kernel::{self as wk, WarpMap, WarpParams};
use crate::error::{Error, Result};
use crate::gpu::compute::{
    self, ensure, read_back, storage_entry, uniform_entry, Buf, Kernel, READ, STORAGE_DST,
    STORAGE_SRC,
};
use crate::gpu::{Backend, GpuContext, Resolved};
use std::sync::atomic::AtomicBool;
use std::sync::{Mutex, OnceLock};

/// WGSL source of the kernel.
pub const SHADER: &str = include_str!("warp.wgsl");

/// Most pixel-samples (pixels x instants) in one dispatch, count.
pub const SAMPLES_PER_DISPATCH: u64 = 1 << 25;

fn build(ctx: &GpuContext) -> Result<Kernel> {
    let layout = [
        uniform_entry(0),
        storage_entry(1, true),
        storage_entry(2, true),
        storage_entry(3, false),
    ];
    compute::build_one(ctx, "warp.wgsl", SHADER, &layout, "main")
}

static KERNEL: OnceLock<std::result::Result<Kernel, String>> = OnceLock::new();

/// The kernel's buffers, reused between images (grown when too small); the
/// lock also runs a batch's GPU images one after another.
struct Buffers {
    params: Option<Buf>,
    maps: Option<Buf>,
    img: Option<Buf>,
    out: Option<Buf>,
    read: Option<Buf>,
}

static BUFFERS: Mutex<Buffers> = Mutex::new(Buffers {
    params: None,
    maps: None,
    img: None,
    out: None,
    read: None,
});

/// Announces once that `bulk`/`auto` fell back to the CPU.
static ANNOUNCED: AtomicBool = AtomicBool::new(false);

/// Bytes of the largest buffer (image or output: 16 bytes a pixel) of a
/// `w` x `h` image.
fn image_bytes(w: usize, h: usize) -> u64 {
    w as u64 * h as u64 * 16
}

/// Whether the device's limits take a `w` x `h` image and `maps` maps.
fn fits(ctx: &GpuContext, w: usize, h: usize, maps: usize) -> bool {
    let lim = ctx.device.limits();
    let most = lim.max_storage_buffer_binding_size.min(lim.max_buffer_size);
    image_bytes(w, h) <= most && maps as u64 * 48 <= most
}

/// The device to run a `w` x `h` image with `maps` maps on, or `None` for
/// the CPU, as `backend` says ([`Backend::resolve`]): `bulk` and `auto`
/// also take the CPU when the image does not fit the device's buffers;
/// `gpu` is then an error.
pub fn device(
    backend: Backend,
    w: usize,
    h: usize,
    maps: usize,
) -> Result<Option<&'static GpuContext>> {
    match backend.resolve("augment", "warp integrator", &ANNOUNCED)? {
        Resolved::Cpu(_) => Ok(None),
        Resolved::Gpu(ctx) if fits(ctx, w, h, maps) => Ok(Some(ctx)),
        Resolved::Gpu(ctx) if backend == Backend::Gpu => Err(Error::Gpu(format!(
            "augment: a {w} x {h} image needs a {:.1} MiB buffer; {} allows {:.1} MiB \
             (use backend 'cpu')",
            image_bytes(w, h) as f64 / 1048576.0,
            ctx.description,
            ctx.device
                .limits()
                .max_storage_buffer_binding_size
                .min(ctx.device.limits().max_buffer_size) as f64
                / 1048576.0
        ))),
        Resolved::Gpu(_) => Ok(None),
    }
}

/// The warp average of `src` over `maps` on the GPU: linear values, `c`
/// channels interleaved, as [`super::warp::integrate`] (the formula of
/// [`wk::pixel`]).
pub fn integrate(ctx: &GpuContext, src: &Src, maps: &Maps) -> Result<Vec<f32>> {
    let (p, m, texels) = wk::inputs(src, maps);
    Ok(wk::narrow(&run(ctx, &p, &m, &texels)?, src.c))
}

/// Runs the kernel on prepared inputs (`p`'s row range is set per
/// dispatch): four channels per pixel.
pub fn run(
    ctx: &GpuContext,
    p: &WarpParams,
    maps: &[WarpMap],
    texels: &[[f32; 4]],
) -> Result<Vec<[f32; 4]>> {
    let (w, h, n) = (p.dims[0], p.dims[1], p.dims[2]);
    let lines = match p.dims[3] {
        1 => h,
        2 => w,
        _ => 1,
    } as usize;
    if w == 0 || h == 0 || n == 0 {
        return Err(Error::invalid("augment", "an empty image or no instants"));
    }
    if texels.len() != (w * h) as usize || maps.len() < lines * n as usize {
        return Err(Error::invalid(
            "augment gpu",
            format!(
                "{} texels, {} maps for {w} x {h} px, {lines} lines x {n} instants",
                texels.len(),
                maps.len()
            ),
        ));
    }
    let (ctx_k, k) = compute::compiled(&KERNEL, build)?;
    if !std::ptr::eq(ctx_k, ctx) {
        return Err(Error::Gpu("augment: not the shared device".into()));
    }
    let dev = &ctx.device;
    let out_bytes = image_bytes(w as usize, h as usize);
    let mut slots = BUFFERS
        .lock()
        .map_err(|_| Error::Gpu("augment: buffer cache poisoned".into()))?;
    let sl = &mut *slots;
    let scope = dev.push_error_scope(wgpu::ErrorFilter::Validation);
    let map_bytes: &[u8] = bytemuck::cast_slice(maps);
    let img_bytes: &[u8] = bytemuck::cast_slice(texels);
    let params = ensure(
        ctx,
        &mut sl.params,
        std::mem::size_of::<WarpParams>() as u64,
        wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        "augment params",
    )?
    .clone();
    let b_maps = ensure(
        ctx,
        &mut sl.maps,
        map_bytes.len() as u64,
        STORAGE_DST,
        "augment maps",
    )?
    .clone();
    let b_img = ensure(
        ctx,
        &mut sl.img,
        img_bytes.len() as u64,
        STORAGE_DST,
        "augment image",
    )?
    .clone();
    let b_out = ensure(ctx, &mut sl.out, out_bytes, STORAGE_SRC, "augment output")?.clone();
    let b_read = ensure(ctx, &mut sl.read, out_bytes, READ, "augment readback")?.clone();
    ctx.queue.write_buffer(&b_maps, 0, map_bytes);
    ctx.queue.write_buffer(&b_img, 0, img_bytes);
    let bg = dev.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("augment"),
        layout: &k.bgl,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: params.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: b_maps.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: b_img.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: b_out.as_entire_binding(),
            },
        ],
    });
    let rows = (SAMPLES_PER_DISPATCH / (w as u64 * n as u64).max(1)).clamp(1, h as u64) as u32;
    let mut row0 = 0;
    while row0 < h {
        crate::cancel::check()?;
        let nr = rows.min(h - row0);
        let mut pr = *p;
        pr.range[1] = row0;
        pr.range[2] = nr;
        ctx.queue.write_buffer(&params, 0, bytemuck::bytes_of(&pr));
        let mut enc = dev.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&k.pipeline);
            pass.set_bind_group(0, &bg, &[]);
            pass.dispatch_workgroups(w.div_ceil(wk::WG), nr.div_ceil(wk::WG), 1);
        }
        ctx.queue.submit([enc.finish()]);
        dev.poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("augment dispatch: {e}")))?;
        row0 += nr;
    }
    let mut enc = dev.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(&b_out, 0, &b_read, 0, out_bytes);
    ctx.queue.submit([enc.finish()]);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(Error::Gpu(format!("augment: {e}")));
    }
    let bytes = read_back(ctx, &b_read, out_bytes, "augment readback")?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}
