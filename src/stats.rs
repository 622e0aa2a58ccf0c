//! Summary statistics shared by the whole crate: one definition of the mean
//! and of the percentile.

/// The `q`-th percentile (0..100, clamped) with linear interpolation between
/// order statistics: rank `q / 100 * (n - 1)` of the sorted values (NumPy's
/// default, `method="linear"`). NaN values sort last (`f64::total_cmp`).
/// `None` for an empty slice.
pub fn percentile(x: &[f64], q: f64) -> Option<f64> {
    if x.is_empty() {
        return None;
    }
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    let r = (q / 100.0).clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let lo = r.floor() as usize;
    let hi = r.ceil() as usize;
    Some(v[lo] + (r - lo as f64) * (v[hi] - v[lo]))
}

/// The arithmetic mean; `None` for an empty slice.
pub fn mean(x: &[f64]) -> Option<f64> {
    if x.is_empty() {
        None
    } else {
        Some(x.iter().sum::<f64>() / x.len() as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
