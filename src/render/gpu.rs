//! GPU path of the renderer: `render.wgsl` and `texture.wgsl`, each joined
//! with the renderer's prelude (`prelude.wgsl`: Params, the homography
//! table entry, the bindings, `line_base`), on the shared wgpu device.
//! Big images and long sample sets are split into dispatches of at most
//! [`SAMPLES_PER_DISPATCH`] pixel-samples (row tiles, then sample ranges
//! accumulated in place), each submitted and waited for separately, so that no
//! single dispatch runs long enough to trip a GPU watchdog.

use super::kernel::with_range;
use super::layout::{GpuHomography, RenderParams};
use super::texture::MipTexture;
use crate::error::{Error, Result};
use crate::gpu::{compute, GpuContext};
use std::sync::OnceLock;

/// WGSL source of the renderer's prelude after the lens module
/// ([`crate::gpu::lens::LENS_WGSL`]; valid by itself).
pub const PRELUDE: &str = concat!(
    include_str!("../gpu/lens.wgsl"),
    include_str!("prelude.wgsl")
);

/// WGSL source of the kernel: the lens module and the prelude joined with
/// `render.wgsl`.
pub const SHADER: &str = concat!(
    include_str!("../gpu/lens.wgsl"),
    include_str!("prelude.wgsl"),
    include_str!("render.wgsl")
);

/// WGSL source of the `analytic` kernel for image textures: the lens module
/// and the prelude joined with `texture.wgsl` (same bindings).
pub const TEXTURE_SHADER: &str = concat!(
    include_str!("../gpu/lens.wgsl"),
    include_str!("prelude.wgsl"),
    include_str!("texture.wgsl")
);

/// Upper bound of pixel-samples in one dispatch.
pub const SAMPLES_PER_DISPATCH: u64 = 1 << 25;

/// The compiled kernels: render.wgsl's entry points (`main`, `analytic`)
/// and texture.wgsl's (`texture`), all with the same bind group layout
/// entries.
struct Kernels {
    lattice: compute::Kernel,
    analytic: compute::Kernel,
    texture: compute::Kernel,
}

/// The kernel's buffers, reused between frames (grown when too small).
struct Buffers {
    homs: Option<compute::Buf>,
    texels: Option<compute::Buf>,
    levels: Option<compute::Buf>,
    params: Option<compute::Buf>,
    out: Option<compute::Buf>,
    read: Option<compute::Buf>,
}

static BUFFERS: std::sync::Mutex<Buffers> = std::sync::Mutex::new(Buffers {
    homs: None,
    texels: None,
    levels: None,
    params: None,
    out: None,
    read: None,
});

static KERNELS: OnceLock<std::result::Result<Kernels, String>> = OnceLock::new();

fn build(ctx: &GpuContext) -> Result<Kernels> {
    // One explicit layout for every entry point (`analytic` does not read
    // the texture bindings).
    let layout = [
        compute::uniform_entry(0),
        compute::storage_entry(1, true),
        compute::storage_entry(2, true),
        compute::storage_entry(3, true),
        compute::storage_entry(4, false),
    ];
    let [lattice, analytic] =
        compute::build_each(ctx, "render.wgsl", SHADER, &layout, ["main", "analytic"])?;
    let texture = compute::build_one(ctx, "texture.wgsl", TEXTURE_SHADER, &layout, "texture")?;
    Ok(Kernels {
        lattice,
        analytic,
        texture,
    })
}

/// Renders on the GPU; returns linear RGB interleaved (mean over the N
/// samples, or instants with `analytic`).
pub fn render(
    ctx: &GpuContext,
    p: &RenderParams,
    homs: &[GpuHomography],
    tex: Option<&MipTexture>,
    analytic: bool,
) -> Result<Vec<f32>> {
    let (_, k) = compute::compiled(&KERNELS, build)?;
    let kernel = match (analytic, tex.is_some()) {
        (true, true) => &k.texture,
        (true, false) => &k.analytic,
        (false, _) => &k.lattice,
    };
    let (pipe, bgl) = (&kernel.pipeline, &kernel.bgl);
    let dev = &ctx.device;
    let (w, h, n) = (p.dims[0], p.dims[1], p.dims[3]);
    let npix = w as u64 * h as u64;
    let out_bytes = npix * 16;
    if out_bytes > ctx.device.limits().max_storage_buffer_binding_size {
        return Err(Error::Gpu(format!(
            "{w}x{h} output ({out_bytes} bytes) exceeds the device's storage binding limit"
        )));
    }
    let scope = dev.push_error_scope(wgpu::ErrorFilter::Validation);
    let (texels, levels) = match tex {
        Some(t) => t.packed(),
        None => (vec![0.0f32; 4], vec![[0u32, 1, 1, 0]]),
    };
    // Buffers are kept between frames and grown when too small: no
    // allocation per frame.
    let mut slots = BUFFERS
        .lock()
        .map_err(|_| Error::Gpu("render: buffer cache poisoned".into()))?;
    let sl = &mut *slots;
    let homs_bytes: &[u8] = bytemuck::cast_slice(homs);
    let tex_bytes: &[u8] = bytemuck::cast_slice(&texels);
    let lev_bytes: &[u8] = bytemuck::cast_slice(&levels);
    let params_size = std::mem::size_of::<RenderParams>() as u64;
    compute::ensure(
        ctx,
        &mut sl.homs,
        homs_bytes.len() as u64,
        compute::STORAGE_DST,
        "homographies",
    )?;
    compute::ensure(
        ctx,
        &mut sl.texels,
        tex_bytes.len() as u64,
        compute::STORAGE_DST,
        "texels",
    )?;
    compute::ensure(
        ctx,
        &mut sl.levels,
        lev_bytes.len() as u64,
        compute::STORAGE_DST,
        "mip levels",
    )?;
    compute::ensure(
        ctx,
        &mut sl.params,
        params_size,
        wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        "render params",
    )?;
    compute::ensure(
        ctx,
        &mut sl.out,
        out_bytes,
        compute::STORAGE_SRC | wgpu::BufferUsages::COPY_DST,
        "render output",
    )?;
    compute::ensure(
        ctx,
        &mut sl.read,
        out_bytes,
        compute::READ,
        "render readback",
    )?;
    let (Some(b_homs), Some(b_tex), Some(b_lev), Some(b_par), Some(b_out), Some(b_read)) = (
        sl.homs.as_ref(),
        sl.texels.as_ref(),
        sl.levels.as_ref(),
        sl.params.as_ref(),
        sl.out.as_ref(),
        sl.read.as_ref(),
    ) else {
        return Err(Error::Gpu("render: buffers missing".into()));
    };
    let (b_homs, b_tex, b_lev, b_par, b_out, b_read) = (
        &b_homs.buf,
        &b_tex.buf,
        &b_lev.buf,
        &b_par.buf,
        &b_out.buf,
        &b_read.buf,
    );
    ctx.queue.write_buffer(b_homs, 0, homs_bytes);
    ctx.queue.write_buffer(b_tex, 0, tex_bytes);
    ctx.queue.write_buffer(b_lev, 0, lev_bytes);
    {
        let mut enc = dev.create_command_encoder(&Default::default());
        enc.clear_buffer(b_out, 0, Some(out_bytes));
        ctx.queue.submit([enc.finish()]);
    }
    let bg = dev.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("render"),
        layout: bgl,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: b_par.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: b_homs.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: b_tex.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: b_lev.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: b_out.as_entire_binding(),
            },
        ],
    });
    // Tiling: rows per dispatch, and samples per dispatch when one row is too much.
    let row_cost = w as u64 * n as u64;
    let rows = (SAMPLES_PER_DISPATCH / row_cost.max(1)).clamp(1, h as u64) as u32;
    let kstep = if rows == 1 {
        (SAMPLES_PER_DISPATCH / w as u64).clamp(1, n as u64) as u32
    } else {
        n
    };
    let mut row0 = 0;
    while row0 < h {
        let nr = rows.min(h - row0);
        let mut k0 = 0;
        while k0 < n {
            // A stop request (crate::cancel) is seen between dispatches.
            crate::cancel::check()?;
            let k1 = (k0 + kstep).min(n);
            let pr = with_range(p, row0, nr, k0, k1);
            ctx.queue.write_buffer(b_par, 0, bytemuck::bytes_of(&pr));
            let mut enc = dev.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipe);
                pass.set_bind_group(0, &bg, &[]);
                pass.dispatch_workgroups(w.div_ceil(8), nr.div_ceil(8), 1);
            }
            ctx.queue.submit([enc.finish()]);
            dev.poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| Error::Gpu(format!("render dispatch: {e}")))?;
            k0 = k1;
        }
        row0 += nr;
    }
    let mut enc = dev.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(b_out, 0, b_read, 0, out_bytes);
    ctx.queue.submit([enc.finish()]);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(Error::Gpu(format!("render: {e}")));
    }
    let bytes = compute::read_back(ctx, b_read, out_bytes, "render readback")?;
    let sums: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes);
    let inv = 1.0 / n as f32;
    let mut out = Vec::with_capacity((npix * 3) as usize);
    for s in &sums {
        out.extend_from_slice(&[s[0] * inv, s[1] * inv, s[2] * inv]);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #[test]
    fn shader_parses_and_validates() {
        let m = naga::front::wgsl::parse_str(super::SHADER).expect("render.wgsl parses");
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&m)
        .expect("render.wgsl validates");
        let m = naga::front::wgsl::parse_str(super::TEXTURE_SHADER).expect("texture.wgsl parses");
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&m)
        .expect("texture.wgsl validates");
    }

    #[test]
    fn params_match_the_host_struct() {
        use super::super::layout::{GpuHomography, RenderParams};
        use crate::gpu::compute::struct_size;
        use std::mem::size_of;
        for src in [super::SHADER, super::TEXTURE_SHADER] {
            assert_eq!(struct_size(src, "Params"), size_of::<RenderParams>());
            assert_eq!(struct_size(src, "Homography"), size_of::<GpuHomography>());
            assert_eq!(
                struct_size(src, "Lens"),
                size_of::<crate::gpu::lens::LensGpu>()
            );
        }
    }
}
