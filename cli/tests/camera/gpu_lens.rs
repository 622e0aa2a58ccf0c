//! The field kernel's lens table mode (`src/field/table.rs`): every lens
//! model the kernel has no analytic formula for, and every camera masked
//! beyond a radial distortion limit, per pixel. The CPU twin against the
//! f64 formula and against the library's CPU metric (`riemann` on the same
//! cells, which drops masked nodes the same way); the GPU against the twin.
//! Cameras: Gyroflow's models written here, a masked fisheye, and the 40 real
//! profiles of `tests/fixtures/lens_profiles/` (digital lenses and masked
//! ones among them), each scaled down to a small sensor.

use crate::common;

use glam::DVec3;
use mmbm::camera::Distortion;
use mmbm::field::cpu as flow_cpu;
use mmbm::field::{flow_field, Backend, FlowRunner, Grid, LensTable, TwistGpu};
use mmbm::{mmbm, Camera, Method, Plane, Scene, Twist};

/// Gyroflow's other models on a 96 x 54 sensor (f = 60 px, 16:9), and a
/// fisheye that turns back at 1.2 (masked beyond it).
fn model_cameras() -> Vec<(String, Camera)> {
    let base = Camera {
        pitch_y_mm: 0.0052,
        ..Camera::new(0.3, 0.005, 96, 54)
    };
    let mut k12 = [0.0; 12];
    k12.copy_from_slice(&[
        -0.21, 0.05, 0.0012, -0.0009, -0.004, 0.08, -0.02, 0.006, 0.0021, -0.0007, -0.0015, 0.0004,
    ]);
    let mut gp = [0.0; 12];
    gp[0] = 1.0;
    gp[2] = -0.03;
    gp[4] = 0.002;
    let models = [
        Distortion::Poly3 { k1: 0.02 },
        Distortion::Poly5 {
            k1: -0.05,
            k2: 0.004,
        },
        Distortion::Ptlens {
            a: 0.002,
            b: -0.01,
            c: -0.02,
        },
        Distortion::Sony {
            k: [0.98, 0.01, -0.04, 0.01, -0.002, 0.0001],
        },
        Distortion::GenericPolynomial { k: gp },
        Distortion::Insta360 {
            k: [-0.02, 0.003, -0.0002, 0.0004, -0.0003, 0.2],
        },
        Distortion::OpencvStandard { k: k12 },
        Distortion::Fisheye {
            k1: 1.0,
            k2: -0.8,
            k3: 0.0,
            k4: 0.0,
        },
    ];
    models
        .into_iter()
        .map(|d| {
            let mut c = Camera {
                distortion: d,
                ..base
            };
            if matches!(d, Distortion::Fisheye { .. }) {
                // f = 40 px: the corners lie beyond the limit.
                c.focal_mm = 0.2;
            }
            (format!("{d:?}"), c)
        })
        .collect()
}

/// The 40 real profiles, each scaled to 1/40 of its size.
fn profile_cameras() -> Vec<(String, Camera)> {
    let dir = crate::common::repo_root().join("tests/fixtures/lens_profiles");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 40);
    files
        .iter()
        .map(|p| {
            let c = Camera::load(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            (name, c.scaled_to(c.width / 40, c.height / 40))
        })
        .collect()
}

fn scene(c: &Camera) -> Scene {
    Scene {
        camera: *c,
        plane: Some(Plane {
            normal: DVec3::new(0.15, -0.3, 1.0),
            d: 1.2,
        }),
    }
}

fn twist() -> Twist {
    Twist::new(DVec3::new(0.3, -0.5, 0.8), DVec3::new(0.4, -0.2, 1.5))
}

/// The twin (`mmbm::field::flow_field` on the CPU) per pixel against the
/// f64 formula (1e-4 of the largest speed: near a circular fisheye's limit
/// the f32 pinhole flow at a far point, times a small Jacobian, loses
/// digits; masked pixels NaN in both), and its mean against `riemann` at the
/// pixel centres (1e-5 relative: f32 sums against f64). Returns (worst per
/// pixel, worst mean, cameras with masked pixels) for the report.
fn twin_against_cpu(cams: &[(String, Camera)]) -> (f64, f64, usize) {
    let (mut worst_px, mut worst_mean, mut masked) = (0f64, 0f64, 0);
    for (name, cam) in cams {
        let s = scene(cam);
        let tw = twist();
        let f = flow_field(&s, &tw, 0, 0, Backend::Cpu { threads: None })
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let grid = Grid::new(cam, 0, 0).unwrap();
        let (reff, _) = flow_cpu::reference_f64(&grid, &tw, s.plane.as_ref());
        let max = reff
            .iter()
            .map(|a| a[0].hypot(a[1]))
            .filter(|x| !x.is_nan())
            .fold(0.0, f64::max);
        let (mut n_nan, mut worst) = (0, 0f64);
        for (k, r) in reff.iter().enumerate() {
            let (u, v) = (f.u[k] as f64, f.v[k] as f64);
            assert_eq!(
                u.is_nan(),
                r[0].is_nan(),
                "{name}: pixel {k} masked in one only"
            );
            if u.is_nan() {
                assert!(v.is_nan());
                n_nan += 1;
                continue;
            }
            let e = (u - r[0]).abs().max((v - r[1]).abs()) / max;
            assert!(e < 1e-4, "{name}: pixel {k}: {u}, {v} vs {r:?}");
            worst = worst.max(e);
        }
        worst_px = worst_px.max(worst);
        assert!(
            (f.masked - n_nan as f64 / f.u.len() as f64).abs() < 1e-12,
            "{name}"
        );
        if n_nan > 0 {
            masked += 1;
            assert!(grid.uses_table(), "{name}");
        }
        let m = mmbm(
            &s,
            &tw,
            Method::Riemann {
                nu: cam.width,
                nv: cam.height,
            },
        )
        .unwrap();
        let d = (f.mmbm.mm_s - m.mm_s).abs() / m.mm_s;
        let dp = (f.mmbm.px_s - m.px_s).abs() / m.px_s;
        eprintln!(
            "{name}: twin vs f64 per pixel {worst:.2e}, vs riemann {d:.2e} (px/s {dp:.2e}), masked {:.4}",
            f.masked
        );
        assert!(
            d < 1e-5 && dp < 1e-5,
            "{name}: {} vs {}",
            f.mmbm.mm_s,
            m.mm_s
        );
        worst_mean = worst_mean.max(d).max(dp);
    }
    (worst_px, worst_mean, masked)
}

#[test]
fn twin_matches_the_cpu_metric_for_every_model() {
    let cams = model_cameras();
    let (px, mean, masked) = twin_against_cpu(&cams);
    eprintln!("models: worst per pixel {px:.2e} of max speed, worst mean {mean:.2e}");
    assert_eq!(masked, 1, "the turning fisheye is masked");
    for (name, c) in &cams {
        assert!(Grid::new(c, 0, 0).unwrap().uses_table(), "{name}");
    }
}

#[test]
fn twin_matches_the_cpu_metric_for_the_real_profiles() {
    let cams = profile_cameras();
    let (px, mean, masked) = twin_against_cpu(&cams);
    eprintln!(
        "profiles: worst per pixel {px:.2e} of max speed, worst mean {mean:.2e}, {masked} masked"
    );
    assert!(masked >= 1, "the sample has masked profiles");
    assert!(
        cams.iter()
            .any(|(_, c)| matches!(c.distortion, Distortion::Digital { .. })),
        "the sample has digital lenses"
    );
}

#[test]
fn table_errors_and_masks_by_the_camera() {
    let (_, c) = model_cameras().pop().unwrap();
    let grid = Grid::new(&c, 0, 0).unwrap();
    let t = LensTable::new(&grid).unwrap();
    for j in 0..grid.height {
        for i in 0..grid.width {
            let (ud, vd) = c.pixel_to_mm(i as f64 + 0.5, j as f64 + 0.5);
            let k = (j * grid.width + i) as usize;
            assert_eq!(t.valid[k], !c.is_masked_mm(ud, vd));
            if !t.valid[k] {
                let z = t.samples[k];
                assert_eq!([z.q, z.j0, z.j1], [[0.0; 2]; 3]);
            }
        }
    }
    assert!(t.n_valid < grid.len() && t.n_valid > 0);
}

/// GPU vs twin per pixel (1e-6 of the largest speed: the same f32 formula
/// on the same table) and per mean (1e-6 relative), for the field, the
/// single mean and the batched means (both batch kernels).
#[test]
fn gpu_matches_its_twin_for_every_model_and_mask() {
    if common::gpu().is_none() {
        return;
    }
    let mut cams = model_cameras();
    cams.extend(profile_cameras());
    let tw = twist();
    let mut runner = FlowRunner::new().unwrap();
    let (mut worst_px, mut worst_mean) = (0f64, 0f64);
    for (name, cam) in &cams {
        let s = scene(cam);
        let gpu = flow_field(&s, &tw, 0, 0, Backend::Gpu).unwrap_or_else(|e| panic!("{name}: {e}"));
        let twin = flow_field(&s, &tw, 0, 0, Backend::Cpu { threads: None }).unwrap();
        let max = twin
            .speed()
            .iter()
            .filter(|x| !x.is_nan())
            .fold(0f32, |a, &b| a.max(b)) as f64;
        for k in 0..gpu.u.len() {
            let (a, b) = ((gpu.u[k], gpu.v[k]), (twin.u[k], twin.v[k]));
            assert_eq!(a.0.is_nan(), b.0.is_nan(), "{name}: pixel {k}");
            if !a.0.is_nan() {
                let e = ((a.0 - b.0).abs().max((a.1 - b.1).abs())) as f64 / max;
                assert!(e <= 1e-6, "{name}: pixel {k}: {a:?} vs {b:?}");
                worst_px = worst_px.max(e);
            }
        }
        assert_eq!(gpu.masked, twin.masked);
        let d = (gpu.mmbm.mm_s - twin.mmbm.mm_s).abs() / twin.mmbm.mm_s;
        assert!(d <= 1e-6, "{name}: {} vs {}", gpu.mmbm.mm_s, twin.mmbm.mm_s);
        worst_mean = worst_mean.max(d);
        let single = mmbm::field::mmbm_gpu(&s, &tw, 0, 0).unwrap();
        assert!((single.mm_s - twin.mmbm.mm_s).abs() <= 1e-6 * twin.mmbm.mm_s);
        assert!((single.px_s - twin.mmbm.px_s).abs() <= 1e-6 * twin.mmbm.px_s);
        // Batches: rows_per_twist (<= 4096 samples) and flow_tiles.
        let g = TwistGpu::new(cam.focal_mm, &tw, s.plane.as_ref());
        let other = Twist::new(DVec3::new(-0.2, 0.1, 0.4), DVec3::new(0.1, 0.3, -0.5));
        let twists = [g, TwistGpu::new(cam.focal_mm, &other, s.plane.as_ref())];
        for (w, h) in [(32, 18), (cam.width, cam.height)] {
            let grid = Grid::new(cam, w, h).unwrap();
            let b = runner.batch_means(&grid, &twists).unwrap();
            let t = flow_cpu::batch_means(&grid, &twists).unwrap();
            for (x, y) in b.iter().zip(&t) {
                let d = (x - y).abs() / y;
                assert!(d <= 1e-6, "{name} {w}x{h}: batch {x} vs twin {y}");
                worst_mean = worst_mean.max(d);
            }
        }
    }
    eprintln!(
        "GPU vs twin over {} cameras: worst per pixel {worst_px:.2e} of max speed, worst mean {worst_mean:.2e}",
        cams.len()
    );
}

/// `mmbm flow` takes a masked real profile (it was refused): NaN beyond the
/// limit in the EXR, the masked share printed, the mean over the rest equal
/// to `mmbm eval --method riemann` on the same pixels.
#[test]
fn flow_command_masks_a_real_profile() {
    if common::gpu().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("mmbm-gpu-lens-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let prof = crate::common::repo_root().join(
        "tests/fixtures/lens_profiles/p26_POCO_f3_stab_off_1080p_16by9_1920x1080_29_57fps.json",
    );
    let prof = prof.to_str().unwrap();
    let out = dir.join("f.exr");
    let common = [
        "--omega",
        "0.3,-0.5,0.8",
        "--camera",
        prof,
        "--scale-to",
        "192x108",
    ];
    let mut args = vec!["flow", "--out", out.to_str().unwrap()];
    args.extend(common);
    let o = common::mmbm_ok_in(&dir, &args);
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(text.contains("masked: 29."), "{text}");
    let mm_s = |t: &str| -> f64 {
        let s = t.split("MMBM = ").nth(1).unwrap();
        s.split_whitespace().next().unwrap().parse().unwrap()
    };
    let mut args = vec!["eval", "--method", "riemann:192x108"];
    args.extend(common);
    let e = common::mmbm_ok_in(&dir, &args);
    let (a, b) = (mm_s(&text), mm_s(&String::from_utf8_lossy(&e.stdout)));
    assert!((a - b).abs() < 1e-6 * b, "flow {a} vs eval {b}");
    let (w, h, ch) = mmbm::io::images::read_exr(&out).unwrap();
    assert_eq!((w, h), (192, 108));
    let speed = &ch.iter().find(|(n, _)| n == "flow.speed").unwrap().1;
    let nan = speed.iter().filter(|x| x.is_nan()).count() as f64 / speed.len() as f64;
    assert!(nan > 0.29 && nan < 0.30, "{nan}");
    let _ = std::fs::remove_dir_all(&dir);
}
