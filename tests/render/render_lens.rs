//! The renderer with Gyroflow's other lens models and with a radial
//! distortion limit (issue 25): the per-pixel distortion map is built from
//! the camera's own maps for every model, so the GPU and its CPU twin agree
//! on each; pixels beyond the limit see no ray: 0 in the image (before
//! sensor noise) and NaN in the blur maps, exactly the camera's masked
//! pixels, on both backends.

use crate::common;

use glam::DVec3;
use mmbm::camera::Distortion;
use mmbm::render::{render_frame, Backend, Integrator, Quality, RenderJob, Target, Trajectory};
use mmbm::{Camera, Twist};

/// The masked fisheye of the tests (`common::turning_fisheye`).
fn masked() -> Camera {
    common::turning_fisheye()
}

fn job(cam: Camera, backend: Backend) -> RenderJob {
    let te = 0.004;
    let tw = Twist::new(DVec3::new(0.4, -0.7, 0.9), DVec3::new(0.3, 0.1, -0.2));
    let mut target = Target::checker(0.05, 1.5);
    target.tilt_deg = [0.0, 0.0];
    let mut j = RenderJob::new(cam, te, Trajectory::from_twist(tw, te).unwrap(), target);
    j.backend = backend;
    j.with_maps = true;
    j.quality = Quality::Custom {
        min_samples: 64,
        max_spacing_px: 0.5,
    };
    j
}

fn mask_of(cam: &Camera) -> Vec<bool> {
    (0..cam.height)
        .flat_map(|j| (0..cam.width).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (u, v) = cam.pixel_to_mm(i as f64 + 0.5, j as f64 + 0.5);
            cam.is_masked_mm(u, v)
        })
        .collect()
}

#[test]
fn masked_pixels_are_black_and_nan_in_the_maps() {
    let cam = masked();
    let mask = mask_of(&cam);
    let n = mask.iter().filter(|&&m| m).count();
    assert!(n > 50 && n < 1500, "{n} masked pixels");
    let out = render_frame(&job(cam, Backend::Cpu { threads: None })).unwrap();
    let maps = out.maps.as_ref().unwrap();
    let mut lit = 0;
    for (k, &m) in mask.iter().enumerate() {
        let px = &out.rgb[3 * k..3 * k + 3];
        if m {
            assert_eq!(px, [0.0; 3], "pixel {k}");
            assert!(maps.speed_px_s[k].is_nan(), "pixel {k}");
        } else {
            lit += usize::from(px.iter().any(|&c| c > 0.0));
            assert!(maps.speed_px_s[k].is_finite(), "pixel {k}");
        }
    }
    // The checker's dark squares are not black: every pixel with a ray is lit.
    assert_eq!(lit, mask.len() - n);
    let means = maps.means();
    assert!((means.valid - (1.0 - n as f64 / mask.len() as f64)).abs() < 1e-12);
}

/// GPU against its CPU twin (the tolerances of `tests/render/render_gpu.rs`: a few
/// lattice samples on an edge may flip) for the other models, a digital
/// lens and the masked fisheye; masked pixels 0 on both.
#[test]
fn gpu_renders_every_model_as_its_twin() {
    if common::gpu().is_none() {
        return;
    }
    let base = Camera::new(0.3, 0.005, 64, 48);
    let mut k12 = [0.0; 12];
    k12[..8].copy_from_slice(&[-0.21, 0.05, 0.0012, -0.0009, -0.004, 0.08, -0.02, 0.006]);
    let p01 = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(
        "tests/fixtures/lens_profiles/p01_GoPro_HERO7_Black_Superview_HS_EIS_4k_16by9_3840x2160_29_97f.json",
    );
    let superview = Camera::load(&p01).unwrap().scaled_to(64, 36);
    let cams = [
        Camera {
            distortion: Distortion::Poly5 {
                k1: -0.05,
                k2: 0.004,
            },
            ..base
        },
        Camera {
            distortion: Distortion::Insta360 {
                k: [-0.02, 0.003, -0.0002, 0.0004, -0.0003, 0.2],
            },
            ..base
        },
        Camera {
            distortion: Distortion::OpencvStandard { k: k12 },
            ..base
        },
        superview,
        masked(),
    ];
    for (cam, integrator) in cams
        .iter()
        .flat_map(|c| [(*c, Integrator::Auto), (*c, Integrator::Lattice)])
    {
        let run = |backend| {
            let mut j = job(cam, backend);
            j.integrator = integrator;
            render_frame(&j).unwrap()
        };
        let (g, c) = (run(Backend::Gpu), run(Backend::Cpu { threads: None }));
        let n = g.samples_per_pixel as f32;
        let (max, mean) = common::abs_diff_max_mean(&g.rgb, &c.rgb);
        let name = cam.distortion.name();
        eprintln!("{name} ({integrator}): N {n}, max |gpu - cpu| {max:.2e}, mean {mean:.2e}");
        assert!(max <= 3.0 / n + 1e-3, "{name}: max {max}");
        assert!(mean <= 1e-4, "{name}: mean {mean}");
        for (k, &m) in mask_of(&cam).iter().enumerate() {
            if m {
                assert_eq!(&g.rgb[3 * k..3 * k + 3], [0.0; 3], "{name}: pixel {k}");
            }
        }
    }
}
