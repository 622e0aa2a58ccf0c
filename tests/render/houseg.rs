//! The renderer's lens on the shared lens module (issue 34): the OpenCV and
//! fisheye models are computed in the render kernels (`pixel_map` in
//! `src/render/prelude.wgsl`, with `src/gpu/lens.wgsl`'s `undistort` and
//! `jacobian`) and in their CPU twin with the same f32 operations; the GPU
//! must match the twin per pixel for both models, with skew and an
//! off-centre principal point, for every integrator and target kind.

use crate::common;

use glam::DVec3;
use mmbm::camera::Distortion;
use mmbm::render::{render_frame, Backend, Integrator, Quality, RenderJob, Target, Trajectory};
use mmbm::{Camera, Twist};

/// An OpenCV lens and an unmasked fisheye (both analytic in the kernel).
fn cameras() -> Vec<Camera> {
    let base = Camera {
        skew: 0.7,
        cx: 30.5,
        cy: 25.0,
        ..Camera::new(0.7, 0.00465, 64, 48)
    };
    vec![
        Camera {
            distortion: Distortion::Opencv {
                k1: -0.3,
                k2: 0.08,
                p1: 0.001,
                p2: -0.002,
                k3: 0.01,
            },
            ..base
        },
        Camera {
            distortion: Distortion::Fisheye {
                k1: 0.05,
                k2: -0.01,
                k3: 0.002,
                k4: 0.0,
            },
            ..base
        },
    ]
}

#[test]
fn gpu_renders_the_analytic_lenses_as_its_twin() {
    if common::gpu().is_none() {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    let tex = d.path().join("stripes.png");
    image::RgbImage::from_fn(128, 96, |x, y| {
        let s = if (x / 4 + y / 8) % 2 == 0 { 230 } else { 20 };
        image::Rgb([s, (x * 2) as u8, (y * 255 / 95) as u8])
    })
    .save(&tex)
    .unwrap();
    let image = Target::parse(&format!("image:{}:0.3", tex.display()), 1.0).unwrap();
    let tw = Twist::new(DVec3::new(0.5, -0.7, 1.0), DVec3::new(0.1, 0.05, 0.3));
    for cam in cameras() {
        let targets = [
            ("blobs", Target::blobs(0.5, 1.5)),
            ("checker", Target::checker(0.03, 1.2)),
            ("image", image.clone()),
        ];
        for (kind, target) in targets {
            for integrator in [Integrator::Auto, Integrator::Lattice] {
                let mut job = RenderJob::new(
                    cam,
                    0.03,
                    Trajectory::from_twist(tw, 0.03).unwrap(),
                    target.clone(),
                );
                job.integrator = integrator;
                job.quality = Quality::Custom {
                    min_samples: 64,
                    max_spacing_px: 0.5,
                };
                job.with_maps = false;
                job.backend = Backend::Gpu;
                let g = render_frame(&job).unwrap();
                job.backend = Backend::Cpu { threads: None };
                let c = render_frame(&job).unwrap();
                let n = g.samples_per_pixel as f32;
                let (max, mean) = common::abs_diff_max_mean(&g.rgb, &c.rgb);
                let name = cam.distortion.name();
                eprintln!(
                    "{name} {kind} ({integrator}): N {n}, max |gpu - cpu| {max:.2e}, mean {mean:.2e}"
                );
                // The tolerances of render_gpu.rs: a few lattice samples on
                // an edge may flip (1/N each); f32 rounding otherwise.
                assert!(max <= 3.0 / n + 1e-3, "{name} {integrator}: max {max}");
                assert!(mean <= 1e-4, "{name} {integrator}: mean {mean}");
            }
        }
    }
}
