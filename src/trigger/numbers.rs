//! The numbers of a policy string (`name:args`): parsed with errors that
//! quote the whole specification; shared by the parser and the baselines.

use crate::error::{Error, Result};

/// A finite number, `what` in the specification `spec`.
pub(crate) fn parse_num(s: &str, what: &str, spec: &str) -> Result<f64> {
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| Error::invalid("policy", format!("'{spec}': {what} '{s}' is not a number")))?;
    if !x.is_finite() {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': {what} must be finite"),
        ));
    }
    Ok(x)
}

/// A number above 0, `what` in the specification `spec`.
pub(crate) fn parse_pos(s: &str, what: &str, spec: &str) -> Result<f64> {
    check_pos(parse_num(s, what, spec)?, what, spec)
}

/// Refuses a number that is not finite and above 0 (`what` in the
/// specification `spec`), with [`parse_pos`]'s messages.
pub(crate) fn check_pos(x: f64, what: &str, spec: &str) -> Result<f64> {
    if !x.is_finite() {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': {what} must be finite"),
        ));
    }
    if x <= 0.0 {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': {what} must be > 0, got {x}"),
        ));
    }
    Ok(x)
}
