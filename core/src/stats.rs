//! Summary statistics shared by the whole crate: one definition of the mean
//! and of the percentile.

/// The `q`-th percentile (0..100, clamped) with linear interpolation between
/// order statistics: rank `q / 100 * (n - 1)` of the sorted values (NumPy's
/// default, `method="linear"`). NaN values sort last (`f64::total_cmp`).
/// Infinite values are order statistics like any other: a rank on one of
/// them, or between a finite value and `+inf`, is that infinity (never the
/// NaN that `inf - inf` would give). `None` for an empty slice.
pub fn percentile(x: &[f64], q: f64) -> Option<f64> {
    if x.is_empty() {
        return None;
    }
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    let r = (q / 100.0).clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let lo = r.floor() as usize;
    let hi = r.ceil() as usize;
    let (a, b, f) = (v[lo], v[hi], r - lo as f64);
    Some(if f == 0.0 || a == b || a.is_infinite() {
        a
    } else if b.is_infinite() {
        b
    } else {
        a + f * (b - a)
    })
}

/// The arithmetic mean; `None` for an empty slice.
pub fn mean(x: &[f64]) -> Option<f64> {
    if x.is_empty() {
        None
    } else {
        Some(x.iter().sum::<f64>() / x.len() as f64)
    }
}

/// Average ranks (1-based, ties share their mean rank) of `x`.
fn ranks(x: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..x.len()).collect();
    idx.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let mut r = vec![0.0; x.len()];
    let mut k = 0;
    while k < idx.len() {
        let mut j = k;
        while j + 1 < idx.len() && x[idx[j + 1]] == x[idx[k]] {
            j += 1;
        }
        let avg = (k + j) as f64 / 2.0 + 1.0;
        for &i in &idx[k..=j] {
            r[i] = avg;
        }
        k = j + 1;
    }
    r
}

/// Spearman's rank correlation of the pairs where both values are finite
/// (ties get average ranks; the Pearson correlation of the ranks). `None`
/// with fewer than 3 pairs or a constant side.
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    let (a, b): (Vec<f64>, Vec<f64>) = x
        .iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .unzip();
    if a.len() < 3 {
        return None;
    }
    let (ra, rb) = (ranks(&a), ranks(&b));
    let n = ra.len() as f64;
    let (ma, mb) = (ra.iter().sum::<f64>() / n, rb.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (p, q) in ra.iter().zip(&rb) {
        sab += (p - ma) * (q - mb);
        saa += (p - ma) * (p - ma);
        sbb += (q - mb) * (q - mb);
    }
    (saa > 0.0 && sbb > 0.0).then(|| sab / (saa * sbb).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentile_keeps_infinities() {
        let inf = f64::INFINITY;
        // Ranks 0, 1 and 1.5 of [1, 2, inf]: 1, 2 and (between 2 and inf) inf.
        assert_eq!(percentile(&[1.0, 2.0, inf], 0.0), Some(1.0));
        assert_eq!(percentile(&[1.0, 2.0, inf], 50.0), Some(2.0));
        assert_eq!(percentile(&[inf, 1.0, 2.0], 75.0), Some(inf));
        assert_eq!(percentile(&[inf, inf], 50.0), Some(inf));
        assert_eq!(percentile(&[-inf, 0.0], 50.0), Some(-inf));
    }

    #[test]
    fn percentile_interpolates_like_numpy() {
        // numpy.percentile([1, 2, 3, 4], [0, 25, 50, 95, 100]) = 1, 1.75, 2.5, 3.85, 4
        let x = [4.0, 1.0, 3.0, 2.0];
        for (q, want) in [
            (0.0, 1.0),
            (25.0, 1.75),
            (50.0, 2.5),
            (95.0, 3.85),
            (100.0, 4.0),
        ] {
            let got = percentile(&x, q).unwrap();
            assert!((got - want).abs() < 1e-12, "q = {q}: {got} vs {want}");
        }
        assert_eq!(percentile(&[], 50.0), None);
        assert_eq!(percentile(&[7.0], 95.0), Some(7.0));
    }

    #[test]
    fn mean_of_values() {
        assert_eq!(mean(&[1.0, 2.0, 6.0]), Some(3.0));
        assert_eq!(mean(&[]), None);
    }

    #[test]
    fn spearman_by_hand() {
        // One swap in four: 1 - 6 * 2 / (4 * 15) = 0.8.
        let r = spearman(&[1.0, 2.0, 3.0, 4.0], &[1.0, 3.0, 2.0, 4.0]).unwrap();
        assert!((r - 0.8).abs() < 1e-12);
        // Ties share ranks 2.5: 4.5 / sqrt(4.5 * 5).
        let r = spearman(&[1.0, 2.0, 2.0, 3.0], &[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert!((r - 4.5 / 22.5f64.sqrt()).abs() < 1e-12);
        // Monotone but not linear: 1; reversed: -1; NaN pairs left out.
        let r = spearman(&[1.0, 8.0, 27.0, f64::NAN], &[1.0, 2.0, 3.0, 9.0]).unwrap();
        assert!((r - 1.0).abs() < 1e-12);
        assert!((spearman(&[3.0, 2.0, 1.0], &[1.0, 2.0, 3.0]).unwrap() + 1.0).abs() < 1e-12);
        assert_eq!(spearman(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]), None);
        assert_eq!(spearman(&[1.0, 2.0], &[1.0, 2.0]), None);
    }
}
