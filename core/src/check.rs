//! Value checks: a number that must be finite, or finite and positive,
//! named in the error ([`crate::error::Error::Invalid`]) so that a bad
//! parameter is reported with its key or flag. Every layer's validators
//! (the camera's, the models', the configurations') are built on these.

use crate::error::{Error, Result};

/// Checks that `x` is finite, naming it in the error.
pub fn finite(what: &str, x: f64) -> Result<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::invalid(
            what,
            format!("must be a finite number, got {x}"),
        ))
    }
}

/// Checks that `x` is finite and strictly positive, naming it in the error.
pub fn positive(what: &str, x: f64) -> Result<f64> {
    finite(what, x)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(Error::invalid(what, format!("must be > 0, got {x}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_values_are_named() {
        assert_eq!(positive("x", 2.0).unwrap(), 2.0);
        assert_eq!(finite("x", -2.0).unwrap(), -2.0);
        for (r, words) in [
            (
                positive("exposure_s", 0.0),
                "exposure_s: must be > 0, got 0",
            ),
            (positive("exposure_s", -1.0), "must be > 0, got -1"),
            (
                positive("rate", f64::NAN),
                "rate: must be a finite number, got NaN",
            ),
            (
                finite("speed", f64::INFINITY),
                "speed: must be a finite number, got inf",
            ),
        ] {
            let e = r.unwrap_err().to_string();
            assert!(e.contains(words), "{e}");
        }
    }
}
