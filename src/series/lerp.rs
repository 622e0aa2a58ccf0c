//! Flow speeds of the motion interpolated linearly between gyro samples
//! (the renderer's motion, `model::trajectory`): between samples `k` and
//! `k + 1` the twist, and so the flow at a fixed sensor point, is
//! `F(s) = F_k + s (F_{k+1} - F_k)` for `s` in `[0, 1]`, and its speed is
//! `|F(s)|`, not the interpolation of the two speeds (they differ where the
//! flow turns within the interval). The time integral of `|F|` has a closed
//! form (the arc length of a parabola's derivative, docs/spec.md section 3's square root of a
//! quadratic in time).

/// `integral_{s0}^{s1} |a + s d| ds` for 2-D vectors `a`, `d` (any units;
/// the result is in those units times those of `s`), in closed form:
/// with `L = |d|`, `x` the signed distance along the line from its closest
/// point to the origin and `h` that distance,
/// `integral sqrt(x^2 + h^2) dx = (x r + h^2 asinh(x / h)) / 2`, over `L`.
/// When `|d| <= 1e-4 |a|` the midpoint value is used (relative error below
/// about 1e-9; the closed form would lose digits to cancellation there).
pub fn lerp_speed_integral(a: (f64, f64), d: (f64, f64), s0: f64, s1: f64) -> f64 {
    let dd = d.0 * d.0 + d.1 * d.1;
    let aa = a.0 * a.0 + a.1 * a.1;
    if dd <= 1e-8 * aa || dd == 0.0 {
        let m = 0.5 * (s0 + s1);
        return (a.0 + m * d.0).hypot(a.1 + m * d.1) * (s1 - s0);
    }
    let l = dd.sqrt();
    let h = (a.0 * d.1 - a.1 * d.0).abs() / l;
    let x = |s: f64| (a.0 * d.0 + a.1 * d.1 + s * dd) / l;
    let prim = |x: f64| {
        let r = x.hypot(h);
        let tail = if h > 0.0 {
            h * h * (x / h).asinh()
        } else {
            0.0
        };
        0.5 * (x * r + tail)
    };
    (prim(x(s1)) - prim(x(s0))) / l
}

/// Sample `k`'s flows at the `n = weights.len()` points of a rule:
/// `flows[k * n + i]` is point `i`'s flow at time `t[k]`.
fn at(flows: &[(f64, f64)], n: usize, k: usize) -> &[(f64, f64)] {
    &flows[k * n..(k + 1) * n]
}

/// `sum_i w_i |F_i(x)|` at time `x` (inside `t`, which is increasing), with
/// the flows `F_i` linear between the samples (layout as in [`window_speed`]).
pub fn instant_speed(t: &[f64], flows: &[(f64, f64)], weights: &[f64], x: f64) -> f64 {
    let n = weights.len();
    let k = t.partition_point(|&s| s <= x).clamp(1, t.len().max(2) - 1) - 1;
    let s = if t.len() < 2 {
        0.0
    } else {
        ((x - t[k]) / (t[k + 1] - t[k])).clamp(0.0, 1.0)
    };
    let f0 = at(flows, n, k);
    let f1 = if t.len() < 2 { f0 } else { at(flows, n, k + 1) };
    weights
        .iter()
        .zip(f0.iter().zip(f1))
        .map(|(w, (p, q))| w * (p.0 + s * (q.0 - p.0)).hypot(p.1 + s * (q.1 - p.1)))
        .sum()
}

/// Time mean over `[a, b]` of `sum_i w_i |F_i(t)|`, the flows `F_i` linear
/// between the samples: `flows[k * n + i]` is point `i`'s flow at `t[k]`
/// (`n = weights.len()`, `t` increasing and covering `[a, b]`). The value at
/// `a` when `b <= a`. Exact (closed form per interval, [`lerp_speed_integral`]).
pub fn window_speed(t: &[f64], flows: &[(f64, f64)], weights: &[f64], a: f64, b: f64) -> f64 {
    if b <= a || t.len() < 2 {
        return instant_speed(t, flows, weights, a);
    }
    let n = weights.len();
    let first = t.partition_point(|&s| s <= a).saturating_sub(1);
    let mut total = 0.0;
    for k in first..t.len() - 1 {
        let (t0, t1) = (t[k], t[k + 1]);
        if t0 >= b {
            break;
        }
        let (lo, hi) = (a.max(t0), b.min(t1));
        if hi <= lo {
            continue;
        }
        let dt = t1 - t0;
        let (s0, s1) = ((lo - t0) / dt, (hi - t0) / dt);
        let sum: f64 = weights
            .iter()
            .zip(at(flows, n, k).iter().zip(at(flows, n, k + 1)))
            .map(|(w, (p, q))| w * lerp_speed_integral(*p, (q.0 - p.0, q.1 - p.1), s0, s1))
            .sum();
        total += sum * dt;
    }
    total / (b - a)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Midpoint sums with many steps, written out.
    fn brute(a: (f64, f64), d: (f64, f64), s0: f64, s1: f64) -> f64 {
        let n = 200_000;
        let h = (s1 - s0) / n as f64;
        (0..n)
            .map(|k| {
                let s = s0 + (k as f64 + 0.5) * h;
                (a.0 + s * d.0).hypot(a.1 + s * d.1) * h
            })
            .sum()
    }

    #[test]
    fn closed_form_matches_sums() {
        let cases = [
            ((1.0, 0.0), (0.0, 1.0), 0.0, 1.0),
            ((1.0, 2.0), (-2.0, -3.0), 0.0, 1.0), // passes near the origin
            ((1.0, 1.0), (-2.0, -2.0), 0.0, 1.0), // through the origin (h = 0)
            ((3.0, -1.0), (0.2, 0.1), 0.25, 0.75),
            ((0.0, 0.0), (1.0, -1.0), 0.1, 0.9),
            ((1e-3, 2.0), (1e-9, 1e-9), 0.0, 1.0), // nearly constant: midpoint
            ((5.0, 5.0), (-4.9, -5.1), 0.3, 1.0),
        ];
        for (a, d, s0, s1) in cases {
            let (c, b) = (lerp_speed_integral(a, d, s0, s1), brute(a, d, s0, s1));
            assert!(
                (c - b).abs() <= 1e-9 * b.abs().max(1e-12),
                "{a:?} {d:?}: {c} vs {b}"
            );
        }
        // Where the flow turns, the interpolated speed is below the speeds' interpolation.
        let turn = lerp_speed_integral((1.0, 0.0), (-1.0, 1.0), 0.0, 1.0);
        assert!(turn < 1.0 && (turn - brute((1.0, 0.0), (-1.0, 1.0), 0.0, 1.0)).abs() < 1e-9);
    }

    #[test]
    fn window_means_over_several_intervals() {
        let t = [0.0, 1.0, 2.0, 4.0];
        // Two points, weights 0.25 and 0.75.
        let w = [0.25, 0.75];
        let flows = [
            (1.0, 0.0),
            (0.0, 2.0),
            (0.0, 1.0),
            (1.0, 1.0),
            (-1.0, 0.5),
            (3.0, 0.0),
            (2.0, 2.0),
            (0.0, -1.0),
        ];
        let (a, b) = (0.5, 3.0);
        // Direct: fine midpoint sums over the window of the interpolated flows.
        let n = 300_000;
        let h = (b - a) / n as f64;
        let mut direct = 0.0;
        for k in 0..n {
            let x = a + (k as f64 + 0.5) * h;
            let j = if x < 1.0 {
                0
            } else if x < 2.0 {
                1
            } else {
                2
            };
            let s = (x - t[j]) / (t[j + 1] - t[j]);
            for i in 0..2 {
                let (p, q) = (flows[j * 2 + i], flows[(j + 1) * 2 + i]);
                direct += w[i] * (p.0 + s * (q.0 - p.0)).hypot(p.1 + s * (q.1 - p.1)) * h;
            }
        }
        direct /= b - a;
        let got = window_speed(&t, &flows, &w, a, b);
        assert!((got - direct).abs() < 1e-9, "{got} vs {direct}");
        // The value at an instant, and a zero-length window.
        let v = instant_speed(&t, &flows, &w, 1.5);
        let expect = 0.25 * (-0.5f64).hypot(0.75) + 0.75 * 2.0f64.hypot(0.5);
        assert!((v - expect).abs() < 1e-12);
        assert_eq!(window_speed(&t, &flows, &w, 1.5, 1.5), v);
    }
}
