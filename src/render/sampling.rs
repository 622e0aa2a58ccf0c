//! The per-pixel sample set (see [`super::kernel`]): the rank-1 lattice's
//! generators, the PCG hash behind the per-pixel shifts, and the concentric
//! disc map of lens samples. The CPU twin uses these as the shader does.

fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

pub(crate) fn coprime_near(n: u32, x: f64) -> u32 {
    if n <= 2 {
        return 1 % n.max(1);
    }
    let c = (x.round() as i64).clamp(1, n as i64 - 1);
    for d in 0..n as i64 {
        for g in [c + d, c - d] {
            if g >= 1 && g < n as i64 && gcd(g as u32, n) == 1 {
                return g as u32;
            }
        }
    }
    1
}

/// Squared minimum toroidal distance between points of the lattice
/// `{(k g1, k g2, k) / n mod 1}` (the larger, the more evenly spread).
fn min_dist2(n: u32, g1: u32, g2: u32) -> f64 {
    let nf = n as f64;
    let wrap = |a: u64| {
        let x = (a % n as u64) as f64 / nf;
        x.min(1.0 - x)
    };
    let mut best = f64::INFINITY;
    for k in 1..n as u64 {
        let t = (k as f64 / nf).min(1.0 - k as f64 / nf);
        let d = t * t;
        if d >= best {
            continue;
        }
        let x = wrap(k * g1 as u64);
        let y = wrap(k * g2 as u64);
        best = best.min(d + x * x + y * y);
    }
    best
}

/// Lattice generators `(g1, g2)` for `n` points: among integers coprime to
/// `n` near `n * (0.75488, 0.56984)` (the R2 sequence's constants), the pair
/// whose lattice has the largest minimum point distance (cached per `n`).
pub fn generators(n: u32) -> (u32, u32) {
    use std::collections::HashMap;
    use std::sync::Mutex;
    static CACHE: Mutex<Option<HashMap<u32, (u32, u32)>>> = Mutex::new(None);
    if let Some(g) = CACHE.lock().ok().and_then(|c| c.as_ref()?.get(&n).copied()) {
        return g;
    }
    let nf = n as f64;
    let base = (
        coprime_near(n, nf * 0.754_877_666_2),
        coprime_near(n, nf * 0.569_840_291_0),
    );
    let mut best = (min_dist2(n, base.0, base.1), base);
    if n > 16 {
        // candidates: a window around the R2 generators, smaller for large n
        let r = ((2.0e7 / nf).sqrt() / 2.0).clamp(0.0, 12.0) as i64;
        for d1 in -r..=r {
            for d2 in -r..=r {
                let g1 = coprime_near(n, base.0 as f64 + 2.0 * d1 as f64);
                let g2 = coprime_near(n, base.1 as f64 + 2.0 * d2 as f64);
                let m = min_dist2(n, g1, g2);
                if m > best.0 {
                    best = (m, (g1, g2));
                }
            }
        }
    }
    if let Ok(mut c) = CACHE.lock() {
        c.get_or_insert_with(HashMap::new).insert(n, best.1);
    }
    best.1
}

/// PCG hash (same in WGSL).
#[inline]
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Per-pixel Cranley-Patterson shifts of x and y, in [0, 1) (same in WGSL).
#[inline]
pub fn shifts(i: u32, j: u32, seed: u32) -> (f32, f32) {
    let h1 = pcg(i.wrapping_add(pcg(j.wrapping_add(pcg(seed)))));
    let h2 = pcg(h1);
    let f = |h: u32| (h >> 8) as f32 * (1.0 / 16_777_216.0);
    (f(h1), f(h2))
}

/// The per-pixel shifts of the two aperture dimensions (defocus): the next
/// two values of the same hash chain as [`shifts`].
pub fn lens_shifts(i: u32, j: u32, seed: u32) -> (f32, f32) {
    let h1 = pcg(i.wrapping_add(pcg(j.wrapping_add(pcg(seed)))));
    let h3 = pcg(pcg(h1));
    let h4 = pcg(h3);
    let f = |h: u32| (h >> 8) as f32 * (1.0 / 16_777_216.0);
    (f(h3), f(h4))
}

/// A uniform point on the unit disc from a point of the unit square
/// (Shirley and Chiu's concentric map), with sine and cosine as polynomials
/// on `[-pi/4, pi/4]` (|error| < 4e-7) so that the shader computes the same.
#[inline]
pub fn concentric(u: f32, v: f32) -> (f32, f32) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let q = std::f32::consts::FRAC_PI_4;
    if a.abs() > b.abs() {
        let t = q * (b / a);
        (a * cos_p(t), a * sin_p(t))
    } else {
        let t = q * (a / b);
        (b * sin_p(t), b * cos_p(t))
    }
}

#[inline]
fn sin_p(x: f32) -> f32 {
    let x2 = x * x;
    x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)))
}

#[inline]
fn cos_p(x: f32) -> f32 {
    let x2 = x * x;
    1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_projections_are_permutations() {
        for n in [1u32, 2, 7, 64, 1000, 1024, 4097] {
            let (g1, g2) = generators(n);
            let mut sx: Vec<u64> = (0..n as u64).map(|k| k * g1 as u64 % n as u64).collect();
            let mut sy: Vec<u64> = (0..n as u64).map(|k| k * g2 as u64 % n as u64).collect();
            sx.sort_unstable();
            sy.sort_unstable();
            assert!(sx.iter().enumerate().all(|(i, &v)| v == i as u64), "n={n}");
            assert!(sy.iter().enumerate().all(|(i, &v)| v == i as u64), "n={n}");
        }
        let s = shifts(3, 4, 0);
        assert!((0.0..1.0).contains(&s.0) && (0.0..1.0).contains(&s.1));
        assert_ne!(shifts(3, 4, 0), shifts(4, 3, 0));
    }
}
