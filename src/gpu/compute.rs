//! Compute plumbing shared by every kernel: building a WGSL module and its
//! pipelines under a validation error scope (every runner builds its
//! kernels with [`build_one`] or [`build_each`]), bind group layout entries,
//! growable storage buffers with limit checks, and mapping a buffer back to
//! the host.

use super::context::GpuContext;
use crate::error::{Error, Result};

/// A storage buffer binding visible to compute shaders.
pub fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A uniform buffer binding visible to compute shaders.
pub fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A kernel's entry point: its bind group 0 layout and its pipeline.
pub struct Kernel {
    /// The layout of bind group 0 (shared by the entry points of one
    /// [`build_each`]: a bind group made with it serves each of them).
    pub bgl: wgpu::BindGroupLayout,
    /// The entry point's pipeline.
    pub pipeline: wgpu::ComputePipeline,
}

/// Compiles `source` (named `file` in errors) with the explicit bind group 0
/// `layout` and builds the one entry point `entry`; validation errors come
/// back as [`Error::Gpu`] naming `file`.
pub fn build_one(
    ctx: &GpuContext,
    file: &str,
    source: &str,
    layout: &[wgpu::BindGroupLayoutEntry],
    entry: &str,
) -> Result<Kernel> {
    let [k] = build_each(ctx, file, source, layout, [entry])?;
    Ok(k)
}

/// [`build_one`] for a shader with several entry points: one [`Kernel`] per
/// entry of `entries`, in order, all with the same bind group 0 layout
/// (the module compiled once). Validation errors come back as
/// [`Error::Gpu`] naming `file`.
pub fn build_each<const N: usize>(
    ctx: &GpuContext,
    file: &str,
    source: &str,
    layout: &[wgpu::BindGroupLayoutEntry],
    entries: [&str; N],
) -> Result<[Kernel; N]> {
    let d = &ctx.device;
    let scope = d.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(file),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(file),
        entries: layout,
    });
    let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(file),
        bind_group_layouts: &[Some(&bgl)],
        immediate_size: 0,
    });
    let kernels = entries.map(|entry| Kernel {
        bgl: bgl.clone(),
        pipeline: d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        }),
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(Error::Gpu(format!("building {file}: {e}")));
    }
    Ok(kernels)
}

/// The `u32` value of the WGSL `const` `name` in the parsed module `m` (for
/// tests that tie a shader's constants to the host's).
///
/// # Panics
/// When the module has no such `const`, or it is not a `u32` literal.
#[cfg(test)]
pub(crate) fn shader_const(m: &naga::Module, name: &str) -> u32 {
    let c = m
        .constants
        .iter()
        .map(|(_, c)| c)
        .find(|c| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("the shader has no const {name}"));
    match m.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => v,
        ref e => panic!("const {name} is not a u32 literal: {e:?}"),
    }
}

/// The size in bytes of the WGSL struct `name` in `src` (naga's layout; for
/// tests that tie a shader's structs to the host's).
///
/// # Panics
/// When `src` does not parse or has no such struct.
#[cfg(test)]
pub(crate) fn struct_size(src: &str, name: &str) -> usize {
    let m = naga::front::wgsl::parse_str(src).expect("the shader parses");
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(m.to_ctx()).expect("layout");
    let (h, _) = m
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("the shader has no struct {name}"));
    layouter[h].size as usize
}

/// The shared device and a kernel compiled once per process into `cell` by
/// `build`; a failed build is cached and returned to every caller.
pub fn compiled<K>(
    cell: &'static std::sync::OnceLock<std::result::Result<K, String>>,
    build: impl FnOnce(&GpuContext) -> Result<K>,
) -> Result<(&'static GpuContext, &'static K)> {
    let ctx = super::gpu()?;
    let k = cell
        .get_or_init(|| build(ctx).map_err(|e| e.to_string()))
        .as_ref()
        .map_err(|e| Error::Gpu(e.trim_start_matches("GPU: ").to_string()))?;
    Ok((ctx, k))
}

/// A device buffer and its size in bytes.
pub struct Buf {
    /// The buffer.
    pub buf: wgpu::Buffer,
    /// Its size, bytes.
    pub size: u64,
}

/// Storage buffer written from the host.
pub const STORAGE_DST: wgpu::BufferUsages =
    wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_DST);
/// Storage buffer copied back to the host.
pub const STORAGE_SRC: wgpu::BufferUsages =
    wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_SRC);
/// Host-readable staging buffer.
pub const READ: wgpu::BufferUsages =
    wgpu::BufferUsages::MAP_READ.union(wgpu::BufferUsages::COPY_DST);

/// Makes `slot` hold a buffer of at least `size` bytes (rounded up to 16),
/// reusing the one there when large enough. Sizes over the device's limits
/// and failed allocations are errors naming `label`.
pub fn ensure<'a>(
    ctx: &GpuContext,
    slot: &'a mut Option<Buf>,
    size: u64,
    usage: wgpu::BufferUsages,
    label: &str,
) -> Result<&'a wgpu::Buffer> {
    let size = size.max(16).next_multiple_of(16);
    let lim = ctx.device.limits();
    let storage = usage.contains(wgpu::BufferUsages::STORAGE);
    if size > lim.max_buffer_size || (storage && size > lim.max_storage_buffer_binding_size) {
        return Err(Error::Gpu(format!(
            "{label} needs a {:.1} MiB buffer; {} allows at most {:.1} MiB per storage buffer \
             (use a smaller sensor or grid)",
            size as f64 / 1048576.0,
            ctx.description,
            lim.max_storage_buffer_binding_size.min(lim.max_buffer_size) as f64 / 1048576.0
        )));
    }
    match slot {
        Some(b) if b.size >= size => {}
        _ => {
            *slot = None;
            let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
            let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            });
            if let Some(e) = pollster::block_on(scope.pop()) {
                return Err(Error::Gpu(format!(
                    "allocating {label} ({size} bytes): {e}"
                )));
            }
            *slot = Some(Buf { buf, size });
        }
    }
    slot.as_ref()
        .map(|b| &b.buf)
        .ok_or_else(|| Error::Gpu(format!("{label}: buffer missing")))
}

/// Waits for the queue and reads the first `size` bytes of a `MAP_READ`
/// buffer; `what` names the work in errors.
pub fn read_back(ctx: &GpuContext, buf: &wgpu::Buffer, size: u64, what: &str) -> Result<Vec<u8>> {
    let slice = buf.slice(..size);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Gpu(format!("waiting for the {what}: {e}")))?;
    rx.recv()
        .map_err(|e| Error::Gpu(format!("{what}: buffer map callback lost: {e}")))?
        .map_err(|e| Error::Gpu(format!("{what}: mapping the result buffer: {e}")))?;
    let out = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("{what}: reading the result buffer: {e}")))?;
        view.to_vec()
    };
    buf.unmap();
    Ok(out)
}
