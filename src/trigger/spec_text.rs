//! A [`PolicySpec`] as text: built from the numbers of a fixed rate with
//! the text the parser would be given ([`PolicySpec::fixed`]), read from
//! text (`FromStr`, serde) and written as the text it was given
//! (`Display`, serde), and compared with it.

use super::family::Family;
use super::numbers::check_pos;
use super::parse::check_fps;
use super::spec::{PolicySpec, Rate};
use crate::error::{Error, Result};

impl PolicySpec {
    /// The fixed rate `fixed:FPS` (`exposure_ms` `None`) or the fixed rate
    /// with a fixed exposure `fixed:FPS@Tms`, built from its numbers: the
    /// same spec, text included, as [`Self::parse`] gives for that string
    /// (`FPS` and `T` written in Rust's shortest round-trip form), checked
    /// the same way.
    ///
    /// ```
    /// use mmbm::trigger::PolicySpec;
    /// let p = PolicySpec::fixed(5.0, Some(3.0))?;
    /// assert_eq!(p, PolicySpec::parse("fixed:5@3ms")?);
    /// assert!(PolicySpec::fixed(0.0, None).is_err());
    /// # Ok::<(), mmbm::Error>(())
    /// ```
    pub fn fixed(fps: f64, exposure_ms: Option<f64>) -> Result<Self> {
        let text = match exposure_ms {
            Some(t) => format!("fixed:{fps}@{t}ms"),
            None => format!("fixed:{fps}"),
        };
        let fps = check_fps(check_pos(fps, "frame rate", &text)?, "frame rate", &text)?;
        let fixed_exposure_s = match exposure_ms {
            Some(t) => Some(check_pos(t, "exposure (ms)", &text)? * 1e-3),
            None => None,
        };
        Ok(PolicySpec {
            base_len: text.len(),
            text: text.into(),
            family: Family::Fixed,
            rate: Some(Rate { fps, phase: 0.0 }),
            threshold: None,
            horizon: None,
            exposure: None,
            fixed_exposure_s,
            ae: None,
            ae_variant: None,
            task: None,
        })
    }
}

impl std::str::FromStr for PolicySpec {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        PolicySpec::parse(s)
    }
}

/// A spec equals the string it was given as.
impl PartialEq<str> for PolicySpec {
    fn eq(&self, other: &str) -> bool {
        self.as_str() == other
    }
}

impl PartialEq<&str> for PolicySpec {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

/// Written as its string ([`PolicySpec::as_str`]).
impl serde::Serialize for PolicySpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

/// Read from a string and parsed ([`PolicySpec::parse`]): a bad string is
/// refused with the parser's message.
impl<'de> serde::Deserialize<'de> for PolicySpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        PolicySpec::parse(&s).map_err(serde::de::Error::custom)
    }
}

impl std::fmt::Display for PolicySpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}
