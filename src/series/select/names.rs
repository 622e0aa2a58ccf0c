//! What the next tools read: image names (printf style, as ffmpeg's image2
//! muxer names frames), COLMAP image lists and ffmpeg `select` expressions.

use crate::error::{Error, Result};

/// A printf-style frame file name with one integer conversion (`%d`,
/// `%5d`, `%06d`; `%%` is a literal `%`), as ffmpeg's image2 muxer names
/// frames: `frame_%06d.png` names frame number 12 `frame_000012.png`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameName {
    prefix: String,
    suffix: String,
    width: usize,
    zeros: bool,
}

impl std::str::FromStr for FrameName {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let bad = |what: &str| {
            Error::invalid(
                "--frame-name",
                format!("'{s}': {what} (e.g. frame_%06d.png: one %d, %Nd or %0Nd; %% for a %)"),
            )
        };
        if s.contains(['\n', '\r']) {
            return Err(bad("a name cannot hold a line break"));
        }
        let mut parts = (String::new(), String::new());
        let mut conv: Option<(usize, bool)> = None;
        let mut chars = s.chars().peekable();
        while let Some(c) = chars.next() {
            let side = if conv.is_some() {
                &mut parts.1
            } else {
                &mut parts.0
            };
            if c != '%' {
                side.push(c);
                continue;
            }
            if chars.peek() == Some(&'%') {
                chars.next();
                side.push('%');
                continue;
            }
            let mut digits = String::new();
            while let Some(d) = chars.peek().filter(|d| d.is_ascii_digit()) {
                digits.push(*d);
                chars.next();
            }
            if chars.next() != Some('d') {
                return Err(bad("only integer conversions (d) are supported"));
            }
            if conv.is_some() {
                return Err(bad("more than one %d"));
            }
            let zeros = digits.starts_with('0');
            let width = if digits.is_empty() {
                0
            } else {
                digits
                    .parse::<usize>()
                    .ok()
                    .filter(|&w| w <= 32)
                    .ok_or_else(|| bad("the width must be at most 32"))?
            };
            conv = Some((width, zeros));
        }
        let Some((width, zeros)) = conv else {
            return Err(bad("no %d for the frame number"));
        };
        Ok(FrameName {
            prefix: parts.0,
            suffix: parts.1,
            width,
            zeros,
        })
    }
}

impl FrameName {
    /// The extension of the names (after the last `.` following the
    /// number), if any: `png` for `frame_%06d.png`.
    pub fn extension(&self) -> Option<&str> {
        let (_, ext) = self.suffix.rsplit_once('.')?;
        (!ext.is_empty() && !ext.contains(['/', '\\'])).then_some(ext)
    }

    /// The same name with the extension `ext` (replacing the name's own, or
    /// added): `frame_%06d.png` becomes `frame_%06d.exr`, so that a frame's
    /// maps and its image share the number.
    pub fn with_extension(&self, ext: &str) -> FrameName {
        let stem = match self.extension() {
            Some(old) => &self.suffix[..self.suffix.len() - old.len() - 1],
            None => self.suffix.as_str(),
        };
        FrameName {
            suffix: format!("{stem}.{ext}"),
            ..self.clone()
        }
    }

    /// True when the names hold a folder (`/` or `\\`).
    pub fn has_folder(&self) -> bool {
        self.prefix.contains(['/', '\\']) || self.suffix.contains(['/', '\\'])
    }

    /// The name of frame number `n`.
    pub fn name(&self, n: u64) -> String {
        let num = if self.zeros {
            format!("{n:0w$}", w = self.width)
        } else {
            format!("{n:w$}", w = self.width)
        };
        format!("{}{num}{}", self.prefix, self.suffix)
    }
}

/// Checks `--frame-start`: the number of the last of `frames` frames
/// (`start + frames - 1`) must fit in a u64, else the names would wrap.
pub fn check_frame_start(start: u64, frames: usize) -> Result<()> {
    let last = (frames.max(1) - 1) as u64;
    if start.checked_add(last).is_none() {
        return Err(Error::invalid(
            "--frame-start",
            format!(
                "{start} numbers the last of {frames} frames {start} + {last}, past the largest \
                 frame number {}",
                u64::MAX
            ),
        ));
    }
    Ok(())
}

/// The image list of `frames` (0-based rows, in order): one name per line,
/// frame `k` named with number `k + start` (ffmpeg's image2 numbers the
/// first frame 1 unless told `-start_number`).
pub fn image_list(frames: &[usize], name: &FrameName, start: u64) -> String {
    let mut out = String::new();
    for &k in frames {
        out.push_str(&name.name((k as u64).saturating_add(start)));
        out.push('\n');
    }
    out
}

/// ffmpeg's `select` expression for `frames` (0-based frame numbers, `n`):
/// `eq(n\,K)` for a lone frame, `between(n\,A\,B)` for a run of consecutive
/// frames, joined by `+`; `0` (no frame) for an empty list. Commas are
/// escaped for a filtergraph (`-vf "select=$(cat FILE)"`). One line, with
/// its `\n`.
pub fn ffmpeg_select(frames: &[usize]) -> String {
    let mut sorted = frames.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    let mut terms: Vec<String> = Vec::new();
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i;
        while j + 1 < sorted.len() && sorted[j + 1] == sorted[j] + 1 {
            j += 1;
        }
        terms.push(if j == i {
            format!("eq(n\\,{})", sorted[i])
        } else {
            format!("between(n\\,{}\\,{})", sorted[i], sorted[j])
        });
        i = j + 1;
    }
    if terms.is_empty() {
        terms.push("0".into());
    }
    let mut out = terms.join("+");
    out.push('\n');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_expressions() {
        let n: FrameName = "frame_%06d.png".parse().unwrap();
        assert_eq!(n.name(12), "frame_000012.png");
        let n: FrameName = "100%%/f%d.jpg".parse().unwrap();
        assert_eq!(n.name(7), "100%/f7.jpg");
        let n: FrameName = "f%4d".parse().unwrap();
        assert_eq!(n.name(7), "f   7");
        for bad in [
            "frame.png",
            "a%d%d",
            "%s.png",
            "%f",
            "x%",
            "a\nb%d",
            "%099d",
        ] {
            let e = bad.parse::<FrameName>().unwrap_err().to_string();
            assert!(e.contains("--frame-name"), "{bad}: {e}");
        }
        let n: FrameName = "frame_%06d.png".parse().unwrap();
        assert_eq!(
            image_list(&[0, 5], &n, 1),
            "frame_000001.png\nframe_000006.png\n"
        );
        assert_eq!(
            ffmpeg_select(&[40, 12, 13, 14, 99, 41]),
            "between(n\\,12\\,14)+between(n\\,40\\,41)+eq(n\\,99)\n"
        );
        assert_eq!(ffmpeg_select(&[]), "0\n");
        let n: FrameName = "img_%04d.jpg".parse().unwrap();
        assert_eq!(n.extension(), Some("jpg"));
        assert_eq!(n.with_extension("exr").name(6), "img_0006.exr");
        let n: FrameName = "f%d".parse().unwrap();
        assert_eq!(
            (n.extension(), n.with_extension("exr").name(6)),
            (None, "f6.exr".into())
        );
        assert!("a/f%d.png".parse::<FrameName>().unwrap().has_folder());
        assert!(!n.has_folder());
    }
}
