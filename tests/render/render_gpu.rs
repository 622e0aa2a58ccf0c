//! GPU kernel vs its CPU twin, per pixel, and the golden renders.

use crate::common;

use glam::DVec3;
use mmbm::io::images::{read_rgb8, save_rgb8, write_png_linear_rgb};
use mmbm::render::{self, Backend, Integrator, Quality, RenderJob, Target, Trajectory};
use mmbm::{Camera, Twist};
use std::path::PathBuf;

fn scenes(tex: &std::path::Path) -> Vec<(&'static str, RenderJob)> {
    let cam = Camera::thesis().with_resolution(80, 60);
    let mut checker = Target::checker(0.03, 1.2);
    checker.tilt_deg = [12.0, -18.0];
    let mut image = Target::parse(&format!("image:{}:0.3", tex.display()), 1.0).unwrap();
    image.offset = [0.05, -0.02];
    let tw6 = Twist::new(DVec3::new(0.6, -0.9, 1.3), DVec3::new(0.2, -0.1, 0.3));
    let roll = Twist::rotation(0.0, 0.0, 3.0);
    vec![
        (
            "checker 6-DoF",
            RenderJob::new(
                cam,
                0.04,
                Trajectory::from_twist(tw6, 0.04).unwrap(),
                checker,
            ),
        ),
        (
            "blobs roll",
            RenderJob::new(
                cam,
                0.05,
                Trajectory::from_twist(roll, 0.05).unwrap(),
                Target::blobs(0.5, 1.5),
            ),
        ),
        (
            "image 6-DoF",
            RenderJob::new(
                cam,
                0.03,
                Trajectory::from_twist(tw6, 0.03).unwrap(),
                image.clone(),
            ),
        ),
        (
            // Lens distortion (docs/spec.md section 9): the per-pixel undistortion map.
            "blobs 6-DoF barrel distortion",
            RenderJob::new(
                Camera {
                    distortion: mmbm::camera::Distortion::Opencv {
                        k1: -0.3,
                        k2: 0.08,
                        p1: 0.001,
                        p2: -0.002,
                        k3: 0.0,
                    },
                    ..cam
                },
                0.03,
                Trajectory::from_twist(tw6, 0.03).unwrap(),
                Target::blobs(0.5, 1.5),
            ),
        ),
        (
            // Defocus (docs/spec.md section 9): two aperture dimensions of the lattice, the
            // homography's lens derivatives.
            "image 6-DoF defocus",
            RenderJob::new(
                Camera {
                    lens: Some(mmbm::camera::Lens {
                        f_number: 1.4,
                        focus_m: 0.6,
                    }),
                    ..cam
                },
                0.03,
                Trajectory::from_twist(tw6, 0.03).unwrap(),
                image.clone(),
            ),
        ),
        (
            // The image's closed-form area (texture.wgsl) with a rolling
            // shutter and lens distortion together.
            "image 6-DoF rolling barrel",
            RenderJob::new(
                Camera {
                    shutter: mmbm::camera::Shutter {
                        readout_s: 0.02,
                        direction: mmbm::camera::Readout::TopToBottom,
                    },
                    distortion: mmbm::camera::Distortion::Opencv {
                        k1: -0.3,
                        k2: 0.08,
                        p1: 0.001,
                        p2: -0.002,
                        k3: 0.0,
                    },
                    ..cam
                },
                0.03,
                Trajectory::from_twist(tw6, 0.05).unwrap(),
                image.clone(),
            ),
        ),
        (
            // Rolling shutter (docs/spec.md section 9): one table of instants per column; the
            // trajectory spans readout + exposure.
            "checker 6-DoF rolling left-to-right",
            RenderJob::new(
                Camera {
                    shutter: mmbm::camera::Shutter {
                        readout_s: 0.02,
                        direction: mmbm::camera::Readout::LeftToRight,
                    },
                    ..cam
                },
                0.04,
                Trajectory::from_twist(tw6, 0.06).unwrap(),
                {
                    let mut c = Target::checker(0.03, 1.2);
                    c.tilt_deg = [12.0, -18.0];
                    c
                },
            ),
        ),
    ]
}

fn test_texture(dir: &std::path::Path) -> PathBuf {
    // 256 x 192 stripes and a gradient: minified about 4x at 1 m.
    let img = image::RgbImage::from_fn(256, 192, |x, y| {
        let s = if (x / 4 + y / 8) % 2 == 0 { 230 } else { 20 };
        image::Rgb([s, (x % 256) as u8, (y * 255 / 191) as u8])
    });
    let p = dir.join("stripes.png");
    img.save(&p).unwrap();
    p
}

#[test]
fn gpu_matches_cpu_twin_per_pixel() {
    let Some(ctx) = common::gpu() else {
        return;
    };
    eprintln!("adapter: {}", ctx.description);
    let d = tempfile::tempdir().unwrap();
    let tex = test_texture(d.path());
    for (name, scene) in scenes(&tex) {
        for integrator in [Integrator::Auto, Integrator::Lattice] {
            let mut job = scene.clone();
            job.integrator = integrator;
            job.quality = Quality::Custom {
                min_samples: 256,
                max_spacing_px: 0.5,
            };
            job.with_maps = false;
            job.backend = Backend::Gpu;
            let g = render::render_frame(&job).unwrap();
            job.backend = Backend::Cpu { threads: None };
            let c = render::render_frame(&job).unwrap();
            let n = g.samples_per_pixel as f32;
            let (max, mean) = common::abs_diff_max_mean(&g.rgb, &c.rgb);
            eprintln!("{name} ({integrator}): N {n}, max |gpu - cpu| {max:.2e}, mean {mean:.2e}");
            // Lattice: f32 rounding may flip a few samples that lie on an edge
            // (each flip is 1/N) and texture filtering rounds differently: 3
            // flips + 1e-3. Analytic: no discontinuity, f32 rounding only.
            assert!(max <= 3.0 / n + 1e-3, "{name} {integrator}: max {max}");
            assert!(mean <= 1e-4, "{name} {integrator}: mean {mean}");
            if g.samples_per_pixel != 256 {
                // Analytic (its instants, not the lattice's 256 samples):
                // closed forms on both sides, f32 rounding only.
                assert!(max <= 1e-5, "{name} {integrator}: analytic max {max}");
            }
        }
    }
}

/// Golden renders: PNG (sRGB 8-bit) under `golden/`. Written only with
/// `MMBM_REGEN_GOLDEN=1` (a missing golden fails); otherwise compared in 8-bit levels: mean
/// |diff| <= 0.5 and 99th percentile <= 3 levels (the renderer's stated error
/// is 0.5/255 mean and 3/255 p99 in linear light; sRGB encoding stretches
/// dark values, so this is looser there). On failure the actual image and a
/// difference image (x16) are written to `target/tmp/golden-failures/`.
#[test]
fn golden_renders() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("golden");
    let fail_dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("golden-failures");
    let regen = std::env::var("MMBM_REGEN_GOLDEN").is_ok_and(|v| v == "1");
    let cam = Camera::thesis().with_resolution(160, 120);
    let lateral = Twist::new(DVec3::ZERO, DVec3::new(0.25, -0.1, 0.0));
    let tw6 = Twist::new(DVec3::new(0.5, -0.7, 1.0), DVec3::new(0.1, 0.05, 0.3));
    let mut tilted = Target::checker(0.04, 1.5);
    tilted.tilt_deg = [15.0, -25.0];
    let cases = [
        (
            "checker_lateral.png",
            Trajectory::from_twist(lateral, 0.05).unwrap(),
            Target::checker(0.02, 1.0),
        ),
        (
            "checker_6dof_tilted.png",
            Trajectory::from_twist(tw6, 0.05).unwrap(),
            tilted,
        ),
        (
            "blobs_roll.png",
            Trajectory::from_twist(Twist::rotation(0.1, -0.2, 2.5), 0.07).unwrap(),
            Target::blobs(0.5, 2.5),
        ),
    ];
    let mut failures = vec![];
    for (name, tr, target) in cases {
        let mut job = RenderJob::new(cam, tr.duration(), tr, target);
        job.with_maps = false;
        let out = render::render_frame(&job).unwrap();
        let path = dir.join(name);
        if regen {
            write_png_linear_rgb(&path, out.width, out.height, &out.rgb).unwrap();
            eprintln!(
                "wrote golden {} (look at it before committing)",
                path.display()
            );
            continue;
        }
        if !path.exists() {
            failures.push(format!(
                "{name}: golden missing ({}); regenerate with MMBM_REGEN_GOLDEN=1 and check it",
                path.display()
            ));
            continue;
        }
        let gold = read_rgb8(&path).unwrap();
        let actual: Vec<u8> = out
            .rgb
            .iter()
            .map(|&x| mmbm::io::images::linear_to_srgb8(x))
            .collect();
        let mut d: Vec<i32> = gold
            .as_raw()
            .iter()
            .zip(&actual)
            .map(|(&a, &b)| (a as i32 - b as i32).abs())
            .collect();
        let diff_img: Vec<u8> = d.iter().map(|&x| (x * 16).min(255) as u8).collect();
        let mean = d.iter().sum::<i32>() as f64 / d.len() as f64;
        d.sort_unstable();
        let p99 = d[d.len() * 99 / 100];
        eprintln!(
            "{name}: mean |diff| {mean:.3} levels, p99 {p99} ({})",
            out.backend_used
        );
        if mean > 0.5 || p99 > 3 {
            std::fs::create_dir_all(&fail_dir).unwrap();
            let save = |suffix: &str, px: Vec<u8>| {
                let img = image::RgbImage::from_raw(out.width, out.height, px).unwrap();
                save_rgb8(
                    &fail_dir.join(format!("{}.{suffix}.png", name.trim_end_matches(".png"))),
                    &img,
                )
                .unwrap();
            };
            save("actual", actual);
            save("diff16", diff_img);
            failures.push(format!(
                "{name}: mean {mean:.3}, p99 {p99} (see {})",
                fail_dir.display()
            ));
        }
    }
    assert!(failures.is_empty(), "golden mismatches: {failures:?}");
}
