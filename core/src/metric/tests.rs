//! Metric tests: thesis tables (values typed from the thesis), docs/spec.md reference
//! values, the roll closed form and properties.

use super::*;
use crate::model::motion::Plane;
use glam::DVec3;

fn twist(a: [f64; 6]) -> Twist {
    Twist::new(DVec3::new(a[0], a[1], a[2]), DVec3::new(a[3], a[4], a[5]))
}

fn scene(f: f64, z: f64) -> Scene {
    let mut camera = Camera::thesis();
    camera.focal_mm = f;
    Scene {
        camera,
        plane: Some(Plane::fronto(z)),
    }
}

fn grid86(s: &Scene, tw: &Twist) -> f64 {
    mmbm(s, tw, Method::default()).unwrap().mm_s
}

/// Thesis Table 4.1: `[w, v, z]`, f noise, MMBM, MMBM with noisy f (printed, truncated).
const TABLE_4_1: [([f64; 7], f64, f64, f64); 16] = [
    ([1., 0., 0., 0., 0., 0., 0.5], 0.05, 4.3514, 4.5594),
    ([1., 0., 0., 0., 0., 0., 0.5], -0.10, 4.3514, 3.9372),
    ([0., 0., 1., 0., 0., 0., 0.5], 0.05, 0.9951, 0.9951),
    ([0., 0., 1., 0., 0., 0., 0.5], -0.10, 0.9951, 0.9951),
    ([1., 0., 1., 0., 0., 0., 0.5], 0.05, 4.4020, 4.6073),
    ([1., 0., 1., 0., 0., 0., 0.5], -0.10, 4.4020, 3.9940),
    ([1., 1., 1., 0., 0., 0., 0.5], 0.05, 6.2514, 6.5412),
    ([1., 1., 1., 0., 0., 0., 0.5], -0.10, 6.2514, 5.6757),
    ([0., 0., 0., 1., 0., 0., 0.5], 0.05, 8.5095, 8.9350),
    ([0., 0., 0., 1., 0., 0., 0.5], -0.10, 8.5095, 7.6586),
    ([0., 0., 0., 0., 0., 1., 0.5], 0.05, 1.9902, 1.9902),
    ([0., 0., 0., 0., 0., 1., 0.5], -0.10, 1.9902, 1.9902),
    ([0., 0., 0., 1., 0., 1., 0.5], 0.05, 8.6073, 9.0279),
    ([0., 0., 0., 1., 0., 1., 0.5], -0.10, 8.6073, 7.7680),
    ([0., 0., 0., 1., 1., 1., 0.5], 0.05, 12.1280, 12.7253),
    ([0., 0., 0., 1., 1., 1., 0.5], -0.10, 12.1280, 10.9350),
];

#[test]
fn thesis_table_4_1() {
    let f0 = Camera::thesis().focal_mm;
    for (row, noise, m0, m1) in TABLE_4_1 {
        let tw = twist([row[0], row[1], row[2], row[3], row[4], row[5]]);
        let a = grid86(&scene(f0, row[6]), &tw);
        let b = grid86(&scene(f0 * (1.0 + noise), row[6]), &tw);
        assert!((a - m0).abs() <= 2.5e-4, "{row:?}: {a} vs thesis {m0}");
        assert!(
            (b - m1).abs() <= 2.5e-4,
            "{row:?} f{noise:+}: {b} vs thesis {m1}"
        );
    }
}

#[test]
fn thesis_table_4_4() {
    let rows = [(0.2, 7.1647), (1.0, 1.4329), (5.0, 0.2866), (20.0, 0.0716)];
    let tw = twist([0., 0., 0., 0.25, 0.125, -1.0]);
    for (z, m) in rows {
        let a = grid86(&scene(Camera::thesis().focal_mm, z), &tw);
        assert!((a - m).abs() <= 2.5e-4, "z={z}: {a} vs thesis {m}");
    }
}

#[test]
fn exact_matches_spec_reference_values() {
    for (w, reference) in [
        ([1.0, 1.0, 1.0], 6.2563777263),
        ([0.0, 0.0, 1.0], 1.0024570820),
    ] {
        let r = mmbm(
            &Scene::thesis(),
            &Twist::rotation(w[0], w[1], w[2]),
            Method::Exact { tol: 1e-11 },
        )
        .unwrap();
        let rel = (r.mm_s - reference).abs() / reference;
        assert!(
            rel <= 1e-9,
            "w={w:?}: {} vs {reference} (rel {rel:e})",
            r.mm_s
        );
        let est = r.error_estimate.unwrap();
        assert!(est <= 1e-11 * r.mm_s * 1.0001, "error estimate {est}");
    }
}

#[test]
fn exact_matches_roll_closed_form() {
    let cams = [
        Camera::thesis(),
        Camera::new(8.0, 0.002, 1920, 1080),
        Camera {
            cx: 100.0,
            cy: 400.0,
            ..Camera::thesis()
        },
    ];
    for cam in cams {
        let closed = roll_mean_closed_form(&cam.sensor_rect());
        for wz in [1.0, -2.5] {
            let s = Scene {
                camera: cam,
                plane: None,
            };
            let r = mmbm(
                &s,
                &Twist::rotation(0.0, 0.0, wz),
                Method::Exact { tol: 1e-10 },
            )
            .unwrap();
            let want = wz.abs() * closed;
            assert!((r.mm_s - want).abs() <= 1e-9 * want, "{} vs {want}", r.mm_s);
            assert!((r.mm_s - want).abs() <= r.error_estimate.unwrap().max(1e-15) * 10.0);
        }
    }
}

#[test]
fn exact_error_estimate_is_honest() {
    // Random twists: the estimate at tol 1e-6 bounds the true error vs a 1e-12 reference.
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    for _ in 0..50 {
        let tw = twist([rnd(), rnd(), rnd(), rnd(), rnd(), rnd()]);
        let s = Scene {
            camera: Camera::thesis(),
            plane: Some(Plane::fronto(1.0 + rnd().abs())),
        };
        let lo = mmbm(&s, &tw, Method::Exact { tol: 1e-6 }).unwrap();
        let hi = mmbm(&s, &tw, Method::Exact { tol: 1e-12 }).unwrap();
        let true_err = (lo.mm_s - hi.mm_s).abs();
        assert!(
            true_err <= lo.error_estimate.unwrap() + 1e-13,
            "{true_err} > {:?}",
            lo.error_estimate
        );
        assert!(true_err <= 1e-6 * hi.mm_s, "{true_err}");
    }
}

#[test]
fn gauss_converges_to_exact_on_smooth_flow() {
    // Pure yaw: the flow never vanishes on the sensor, so Gauss converges fast.
    let tw = Twist::rotation(0.0, 1.0, 0.0);
    let s = Scene::thesis();
    let ex = mmbm(&s, &tw, Method::Exact { tol: 1e-13 }).unwrap().mm_s;
    let g = mmbm(&s, &tw, Method::Gauss { nu: 8, nv: 6 }).unwrap().mm_s;
    let r = mmbm(&s, &tw, Method::Riemann { nu: 8, nv: 6 })
        .unwrap()
        .mm_s;
    assert!((g - ex).abs() / ex < 1e-9, "gauss {g} exact {ex}");
    assert!((r - ex).abs() > 10.0 * (g - ex).abs());
}

#[test]
fn sign_symmetries_and_linearity() {
    let s = Scene::thesis();
    let base = [0.3, -0.7, 0.4];
    let m = |w: [f64; 3], k: f64| {
        mmbm(
            &s,
            &Twist::rotation(k * w[0], k * w[1], k * w[2]),
            Method::Exact { tol: 1e-12 },
        )
        .unwrap()
        .mm_s
    };
    let m0 = m(base, 1.0);
    // Reversing the motion reverses every flow vector: same speed.
    assert!((m(base, -1.0) - m0).abs() < 1e-10 * m0);
    // The centred sensor is symmetric under u -> -u and v -> -v.
    assert!((m([-base[0], base[1], -base[2]], 1.0) - m0).abs() < 1e-10 * m0);
    assert!((m([base[0], -base[1], -base[2]], 1.0) - m0).abs() < 1e-10 * m0);
    // Rotation-only MMBM is linear in |w| (for every method).
    for k in [0.5, 2.0, 10.0] {
        assert!((m(base, k) - k * m0).abs() < 1e-9 * k * m0);
        let r1 = mmbm(
            &s,
            &Twist::rotation(base[0], base[1], base[2]),
            Method::default(),
        )
        .unwrap()
        .mm_s;
        let rk = mmbm(
            &s,
            &Twist::rotation(k * base[0], k * base[1], k * base[2]),
            Method::default(),
        )
        .unwrap()
        .mm_s;
        assert!((rk - k * r1).abs() < 1e-12 * rk);
    }
}

#[test]
fn focal_scaling_of_pure_pitch_and_lateral_translation() {
    // Lateral translation alone: flow = -f/z * v everywhere, so MMBM scales exactly with f.
    let tw = twist([0., 0., 0., 1., 0., 0.]);
    let a = grid86(&scene(4.0, 0.5), &tw);
    let b = grid86(&scene(6.0, 0.5), &tw);
    assert!((b / a - 1.5).abs() < 1e-12);
    // Roll does not depend on f at all.
    let tw = twist([0., 0., 1., 0., 0., 0.]);
    assert_eq!(grid86(&scene(4.0, 0.5), &tw), grid86(&scene(6.0, 0.5), &tw));
}

#[test]
fn bad_inputs_are_errors() {
    let s = Scene::thesis();
    let nan = Twist::rotation(f64::NAN, 0.0, 0.0);
    assert!(mmbm(&s, &nan, Method::default()).is_err());
    // Translation without depth.
    let tw = twist([0., 0., 0., 1., 0., 0.]);
    let e = mmbm(&s, &tw, Method::default()).unwrap_err().to_string();
    assert!(e.contains("depth"), "{e}");
    // Zero focal length.
    let mut cam = Camera::thesis();
    cam.focal_mm = 0.0;
    let e = mmbm(
        &Scene {
            camera: cam,
            plane: None,
        },
        &Twist::rotation(1., 0., 0.),
        Method::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("focal"), "{e}");
    // Plane behind the camera, and a tilted plane that crosses the view.
    for p in [
        Plane::fronto(-1.0),
        Plane {
            normal: DVec3::new(1.0, 0.0, 0.1),
            d: 1.0,
        },
    ] {
        let s = Scene {
            camera: Camera::thesis(),
            plane: Some(p),
        };
        let e = mmbm(&s, &tw, Method::default()).unwrap_err().to_string();
        assert!(e.contains("behind"), "{e}");
    }
    for bad in [
        "riemann:0x6",
        "riemann:8",
        "gauss:-1",
        "exact:0",
        "exact:abc",
        "simpson",
    ] {
        assert!(bad.parse::<Method>().is_err(), "{bad}");
    }
}

#[test]
fn method_strings_round_trip() {
    for s in ["riemann:8x6", "gauss:5x5"] {
        assert_eq!(s.parse::<Method>().unwrap().to_string(), s);
    }
    for s in ["riemann:8x6", "gauss:5x5", "gpu", "gpu:320x240"] {
        assert_eq!(s.parse::<AnyMethod>().unwrap().to_string(), s);
    }
    // The GPU field is not a CPU method: the type cannot hold it.
    let e = "gpu".parse::<Method>().unwrap_err().to_string();
    assert!(e.contains("not a CPU method"), "{e}");
    assert_eq!(
        "gauss:4x3".parse::<AnyMethod>().unwrap(),
        AnyMethod::Cpu(Method::Gauss { nu: 4, nv: 3 })
    );
    let e = "simpson".parse::<AnyMethod>().unwrap_err().to_string();
    assert!(e.contains("gpu[:WxH]"), "{e}");
    assert_eq!(
        "riemann".parse::<Method>().unwrap(),
        Method::Riemann { nu: 8, nv: 6 }
    );
    assert_eq!(
        "exact:1e-8".parse::<Method>().unwrap(),
        Method::Exact { tol: 1e-8 }
    );
}
