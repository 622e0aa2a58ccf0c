//! Rendering a window of a frame: the pixels `[x0, y0, w, h]` of
//! [`render_frame`](super::render_frame)'s image, each the same number (the
//! same pass: instants from the job's largest path, over the whole sensor or
//! its [`spacing_window`](super::RenderJob::spacing_window), the same
//! homographies and pixel integrals), without the pixels outside. A caller
//! that judges only a window (the benefit map: the board and its
//! surroundings) pays only for it on the CPU; a GPU renders the whole frame
//! and the window is cut from it.

use super::rect::Window;
use super::{cpu, gpu, kernel, prepare, Pass, RenderJob, ANNOUNCED};
use crate::error::{Error, Result};
use crate::gpu::Resolved;

/// Renders the window `win` of `job`'s frame without noise: linear RGB,
/// interleaved, row-major (`win.w * win.h * 3` values), equal to the window
/// cut from [`render_frame`](super::render_frame)'s image. Refuses a camera
/// with sensor noise (its draws run over the whole image) and a window
/// outside the image.
pub fn render_window(job: &RenderJob, win: Window) -> Result<Vec<f32>> {
    let cam = &job.camera;
    if cam.noise.is_some() {
        return Err(Error::invalid(
            "window",
            "a window is rendered without sensor noise (the noise is drawn over the whole image)",
        ));
    }
    win.check("window", cam.width, cam.height)?;
    let Pass {
        params,
        homs,
        analytic,
        ..
    } = prepare(job)?;
    let tex = kernel::texture_of(&job.target);
    let mut rgb = match job.backend.resolve("render", "renderer", &ANNOUNCED)? {
        Resolved::Gpu(ctx) => win.cut(cam.width, &gpu::render(ctx, &params, &homs, tex, analytic)?),
        Resolved::Cpu(threads) => cpu::render_window(
            &params,
            &homs,
            tex,
            analytic,
            threads,
            [win.x0, win.y0, win.w, win.h],
        ),
    };
    crate::cancel::check()?;
    // Pixels beyond the lens's radial distortion limit see no ray: black.
    if let Some(mask) = kernel::masked_pixels(cam) {
        let inside = (win.y0..win.y0 + win.h)
            .flat_map(|y| (win.x0..win.x0 + win.w).map(move |x| (y * cam.width + x) as usize));
        for (px, k) in rgb.chunks_mut(3).zip(inside) {
            if mask[k] {
                px.fill(0.0);
            }
        }
    }
    Ok(rgb)
}
