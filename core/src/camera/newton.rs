//! The one inverse of a rising radial map, shared by the fisheye and the
//! Gyroflow radial models: Newton's method safeguarded by bisection.

/// The `th` in `[0, top]` with `g(th) = target`, for `g` rising on that
/// bracket with slope `dg`, from the first guess `start` (clamped to the
/// bracket), to `tol` in `g`. Each step is Newton's where that stays inside
/// the shrinking bracket and at least halves the last step, else bisection
/// (Newton alone can ping-pong across a bracket that barely shrinks). Stops
/// when `|g(th) - target| <= tol`, when the bracket is down to one ulp, or
/// after `max_steps` steps, and returns the last `th`.
pub fn solve_rising(
    g: impl Fn(f64) -> f64,
    dg: impl Fn(f64) -> f64,
    target: f64,
    top: f64,
    start: f64,
    tol: f64,
    max_steps: u32,
) -> f64 {
    let (mut lo, mut hi) = (0.0, top);
    let mut th = start.clamp(lo, hi);
    let mut last = hi - lo;
    for _ in 0..max_steps {
        let f = g(th) - target;
        if f.abs() <= tol {
            return th;
        }
        if f < 0.0 {
            lo = th;
        } else {
            hi = th;
        }
        let df = dg(th);
        let next = th - f / df;
        let newton = df > 0.0 && next > lo && next < hi && 2.0 * (f / df).abs() <= last;
        let prev = th;
        th = if newton { next } else { 0.5 * (lo + hi) };
        last = (th - prev).abs();
        if hi - lo <= f64::EPSILON * hi {
            return th;
        }
    }
    th
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverts_a_cubic_to_its_tolerance() {
        // g(x) = x + x^3 rises everywhere; g(1) = 2 exactly.
        let x = solve_rising(
            |x| x + x * x * x,
            |x| 1.0 + 3.0 * x * x,
            2.0,
            3.0,
            0.2,
            1e-14,
            200,
        );
        assert!((x - 1.0).abs() < 1e-13, "{x}");
    }

    #[test]
    fn bisects_where_newton_would_leave_the_bracket() {
        // g(x) = x + x^3 - 0.8 x^5 rises on [0, 1] (slope 1 + 3x^2 - 4x^4, zero at
        // x = 1): from a start near the top, plain Newton leaves the bracket.
        let g = |x: f64| x + x.powi(3) - 0.8 * x.powi(5);
        let dg = |x: f64| 1.0 + 3.0 * x * x - 4.0 * x.powi(4);
        let top = 1.0;
        let target = g(0.3);
        let x = solve_rising(g, dg, target, top, 0.99, 1e-15, 200);
        assert!((g(x) - target).abs() <= 1e-15, "{x}");
        assert!((x - 0.3).abs() < 1e-12, "{x}");
    }
}
