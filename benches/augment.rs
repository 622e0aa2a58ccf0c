//! `augment` (`cargo bench --bench augment`): seconds per call at 256 x 256
//! and 640 x 480 with about 20 px of blur for each integrator (fast, the
//! default; exact; render), and the accuracy against the exact exposure
//! integral at 2, 20 and 80 px of blur of the renderer, of the fast warp
//! integrator, and of the 30-pose warp-and-average that gyro-driven
//! generators use (SynIMU2Blurry-style: 30 bilinear warps at evenly spaced
//! instants, averaged). Times are printed, never asserted.
//! `bench/augment_bench.py` times the same against albumentations.
//!
//! Accuracy case: a lateral translation (image x) of a fronto-parallel
//! image, whose exact integrals are written here in closed form per axis:
//! the renderer's model (each pixel the mean of the image's bilinear
//! interpolant over the pixel's area and the exposure) and the warp
//! method's own (the interpolant at the pixel centre, averaged over the
//! exposure), so each method is judged against the exact integral of its
//! own spatial model and only the time integration differs.

use glam::DVec3;
use mmbm::augment::{augment, Augment, Border, Integrator, Motion};
use mmbm::Twist;
use std::time::Instant;

/// A deterministic texture with detail at every scale (linear, 0..1).
fn texture(w: usize, h: usize) -> Vec<f32> {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut v = vec![0.0f32; w * h * 3];
    for (k, x) in v.iter_mut().enumerate() {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        let (i, j) = ((k / 3) % w, k / 3 / w);
        let smooth = 0.5 + 0.25 * ((i as f64 * 0.11).sin() * (j as f64 * 0.07).cos());
        let noise = (s >> 40) as f64 / (1u64 << 24) as f64;
        *x = (0.6 * smooth + 0.4 * noise) as f32;
    }
    v
}

/// Focal length in px of the thesis camera.
fn f_px() -> f64 {
    4.2548 / 0.00465
}

/// Row `r`, channel `c` of the image's bilinear interpolant along x (texel
/// `j` at `j + 0.5`, clamped at the ends) and its antiderivative from 0.
struct Row {
    val: Vec<f64>,
    /// The integral from 0 to knot `k + 0.5`.
    at_knot: Vec<f64>,
}

impl Row {
    fn new(row: &[f32], c: usize, w: usize) -> Row {
        let val: Vec<f64> = (0..w).map(|j| row[j * 3 + c] as f64).collect();
        let mut at_knot = vec![0.5 * val[0]];
        for k in 1..w {
            let prev = at_knot[k - 1];
            at_knot.push(prev + 0.5 * (val[k - 1] + val[k]));
        }
        Row { val, at_knot }
    }
    fn f(&self, x: f64) -> f64 {
        let w = self.val.len();
        let u = (x - 0.5).clamp(0.0, (w - 1) as f64);
        let j = (u.floor() as usize).min(w - 2);
        let t = u - j as f64;
        self.val[j] * (1.0 - t) + self.val[j + 1] * t
    }
    /// `F(x)`, for 0 <= x <= w - 0.5.
    fn big_f(&self, x: f64) -> f64 {
        if x <= 0.5 {
            return x * self.val[0];
        }
        let k = ((x - 0.5).floor() as usize).min(self.val.len() - 1);
        let x0 = k as f64 + 0.5;
        self.at_knot[k] + 0.5 * (x - x0) * (self.f(x0) + self.f(x))
    }
}

/// Mean over s in [0, L] of `g(s)`, by 1024 midpoint steps of a smooth integrand.
fn mean_over(l: f64, g: impl Fn(f64) -> f64) -> f64 {
    let n = 1024;
    (0..n)
        .map(|k| g((k as f64 + 0.5) / n as f64 * l))
        .sum::<f64>()
        / n as f64
}

fn main() {
    println!(
        "augment: {}",
        std::env::var("MMBM_BENCH_NOTE").unwrap_or_default()
    );
    // Speed: ~20 px of yaw blur over 30 ms.
    let yaw = 20.0 / (f_px() * 0.03);
    for (w, h) in [(256u32, 256u32), (640, 480)] {
        let img = texture(w as usize, h as usize);
        for integrator in [Integrator::Fast, Integrator::Exact, Integrator::Render] {
            let mut a = Augment::new(
                Motion::Twist(Twist::new(DVec3::new(0.0, yaw, 0.0), DVec3::ZERO)),
                0.03,
            );
            a.integrator = integrator;
            a.border = Border::Constant;
            let t0 = Instant::now();
            let mut n = 0;
            while n < 2 || t0.elapsed().as_secs_f64() < 5.0 {
                augment(w, h, &img, &a).expect("augment");
                n += 1;
            }
            let s = t0.elapsed().as_secs_f64() / n as f64;
            println!(
                "  {w} x {h}, 20 px of blur, {integrator:?}: {s:.3} s per call ({:.2} calls/s, {n} calls)",
                1.0 / s
            );
        }
    }
    // Accuracy: translation of L px along x over the exposure.
    let (w, h) = (320usize, 96usize);
    let img = texture(w, h);
    println!("  accuracy, {w} x {h}, lateral translation (8-bit levels, pixels whose motion stays on the image):");
    println!("  | blur px | render mean | render p99 | fast mean | fast p99 | 30 warps mean | 30 warps p99 |");
    println!("  |---|---|---|---|---|---|---|");
    for l in [2.0f64, 20.0, 80.0] {
        let (d, t) = (2.0, 0.03);
        let v = l * d / (f_px() * t);
        // The camera moves +x: the image moves -x on the frame, texture x = frame x + s.
        let mut a = Augment::new(
            Motion::Twist(Twist::new(DVec3::ZERO, DVec3::new(v, 0.0, 0.0))),
            t,
        );
        let fast = augment(w as u32, h as u32, &img, &a).expect("augment");
        a.integrator = Integrator::Render;
        a.border = Border::Constant;
        let out = augment(w as u32, h as u32, &img, &a).expect("augment");
        let (mut e_m, mut e_w, mut e_f) = (Vec::new(), Vec::new(), Vec::new());
        let rows: Vec<Row> = (0..h)
            .flat_map(|j| (0..3).map(move |c| (j, c)))
            .map(|(j, c)| Row::new(&img[j * w * 3..(j + 1) * w * 3], c, w))
            .collect();
        let k = [0.125, 0.75, 0.125];
        for j in 1..h - 1 {
            for i in 1..w - 1 - (l.ceil() as usize + 1) {
                for c in 0..3 {
                    // Renderer's model: the pixel box in x, the motion; (1/8, 3/4, 1/8) in y.
                    let mut exact = 0.0;
                    for (dj, kw) in k.iter().enumerate() {
                        let r = &rows[(j + dj - 1) * 3 + c];
                        exact += kw
                            * mean_over(l, |s| r.big_f(i as f64 + 1.0 + s) - r.big_f(i as f64 + s));
                    }
                    let r = &rows[j * 3 + c];
                    // Warp model: the interpolant at the pixel centre; its mean over s in
                    // [0, L] is (F(x + L) - F(x)) / L.
                    let x0 = i as f64 + 0.5;
                    let point = (r.big_f(x0 + l) - r.big_f(x0)) / l;
                    let warps: f64 = (0..30)
                        .map(|q| r.f(x0 + (q as f64 + 0.5) / 30.0 * l))
                        .sum::<f64>()
                        / 30.0;
                    let got = out.rgb[(j * w + i) * 3 + c] as f64;
                    e_m.push((got - exact).abs() * 255.0);
                    e_w.push((warps - point).abs() * 255.0);
                    e_f.push((fast.rgb[(j * w + i) * 3 + c] as f64 - point).abs() * 255.0);
                }
            }
        }
        let stat = |e: &mut Vec<f64>| {
            e.sort_by(|a, b| a.total_cmp(b));
            (
                e.iter().sum::<f64>() / e.len() as f64,
                e[(e.len() as f64 * 0.99) as usize],
            )
        };
        let ((mm, mp), (wm, wp)) = (stat(&mut e_m), stat(&mut e_w));
        let (fm, fp) = stat(&mut e_f);
        println!("  | {l} | {mm:.3} | {mp:.3} | {fm:.3} | {fp:.3} | {wm:.3} | {wp:.3} |");
    }
}
