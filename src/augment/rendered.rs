//! The `render` integrator of an augmentation: the renderer's frame of the
//! image (exact pixel-area and exposure integrals), three channels a render.

use super::{Augment, Border, Image};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::render::{self, Backend, RenderJob, Target, Trajectory};

/// The renderer's frame of `img` (linear, its channels), three channels a
/// render; only a constant border (the renderer's background).
pub(super) fn rendered(
    img: &Image,
    a: &Augment,
    cam: &Camera,
    traj: Trajectory,
    width_m: f64,
) -> Result<Vec<f32>> {
    if a.border != Border::Constant {
        return Err(Error::invalid(
            "border",
            "integrator 'render' shows the background beyond the image: use border 'constant'",
        ));
    }
    let (w, h, c) = (
        img.width as usize,
        img.height as usize,
        img.channels as usize,
    );
    let lin = img.to_linear();
    let mut out = vec![0.0f32; w * h * c];
    for g in 0..c.div_ceil(3) {
        let chans: Vec<usize> = (g * 3..(g * 3 + 3).min(c)).collect();
        let mut rgb = vec![0.0f32; w * h * 3];
        for p in 0..w * h {
            for (k, &ch) in chans.iter().enumerate() {
                rgb[p * 3 + k] = lin[p * c + ch];
            }
        }
        let texture = render::texture::MipTexture::from_linear(w as u32, h as u32, rgb)?;
        let mut target = Target::from_texture(texture, width_m, a.distance_m);
        target.background = match c {
            3 => a.background,
            1 => [a.background[0]; 3],
            _ => [0.0; 3],
        };
        let mut job = RenderJob::new(*cam, a.exposure_s, traj.clone(), target);
        job.quality = a.quality;
        job.backend = Backend::Cpu { threads: None };
        job.seed = a.seed as u32;
        job.with_maps = false;
        let frame = render::render_frame(&job)?;
        for p in 0..w * h {
            for (k, &ch) in chans.iter().enumerate() {
                out[p * c + ch] = frame.rgb[p * 3 + k];
            }
        }
    }
    Ok(out)
}
