//! GoPro's GPMF telemetry (HERO5 and later) from the `gpmd` track of an
//! MP4, as GoPro's `gpmf-parser` documents it (README, "GPMF" and "Where to
//! find GPMF data"):
//!
//! - Each `gpmd` sample is a payload of KLV entries: a 4-byte key, a type
//!   byte, a structure size byte and a 16-bit big-endian repeat; the data
//!   (`size x repeat` bytes, big-endian) is padded to 4 bytes. Type 0 nests
//!   more KLV (`DEVC > STRM > ...`), at most [`MAX_GPMF_DEPTH`] deep.
//! - In a `STRM` holding `GYRO`: `SCAL` (a divisor, one or one per axis,
//!   never 0), `ORIN` (the axis of each channel, e.g. `ZXY`; lowercase is
//!   negated), then `GYRO` itself: `repeat` samples of 3 values, rad/s after
//!   `SCAL`. `TSMP` (total samples) and `STMP` are not needed: each
//!   payload's samples are spread evenly over its MP4 sample's duration
//!   (the track's `stts`), as gpmf-parser's timing does.
//! - Without `ORIN` (HERO5, HERO6, HERO7), the channel order is the HERO5
//!   order `ZXY` ([`DEFAULT_ORIN`]); a HERO6's `Y,-X,Z` needs `--imu-rotation`.
//! - GoPro's IMU axes (the README's "IMU Orientation" figure, a right-handed
//!   frame): X to the camera's left, Y out of the back screen (towards the
//!   user), Z up. The samples are returned in these axes; the `action-cam`
//!   orientation ([`super::orientation::Orientation::ActionCam`], the
//!   default for a GoPro file) takes them to mmbm's camera frame.
//!
//! Every length, count, scale and value is checked; a bad one is refused
//! with the file, the payload (MP4 sample number and byte offset), the key
//! path and the reason.

use super::mp4::{bad, Sample};
use crate::error::{Error, Result};
use crate::limits::{MAX_GPMF_DEPTH, MAX_GPMF_PAYLOAD_BYTES, MAX_TELEMETRY_SAMPLES};
use glam::{DMat3, DVec3};
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// The channel order assumed without an `ORIN` (HERO5's data order Z,X,Y).
pub const DEFAULT_ORIN: &str = "ZXY";

/// One KLV entry of a payload.
#[derive(Debug)]
struct Klv<'a> {
    key: [u8; 4],
    kind: u8,
    size: usize,
    repeat: usize,
    data: &'a [u8],
    at: usize,
}

/// The entries of `data` (one level).
fn entries<'a>(path: &Path, place: &str, base: usize, data: &'a [u8]) -> Result<Vec<Klv<'a>>> {
    let mut out = Vec::new();
    let mut at = 0usize;
    while at < data.len() {
        if data.len() - at < 8 {
            // GoPro pads payloads with zeros; a short zero tail is padding.
            if data[at..].iter().all(|&b| b == 0) {
                break;
            }
            return Err(bad(
                path,
                &format!("{place} at byte {}", base + at),
                "truncated KLV header",
            ));
        }
        let key: [u8; 4] = data[at..at + 4].try_into().expect("4 bytes");
        if key == [0; 4] {
            break;
        }
        let kind = data[at + 4];
        let size = data[at + 5] as usize;
        let repeat = u16::from_be_bytes([data[at + 6], data[at + 7]]) as usize;
        let len = size * repeat;
        let padded = len.div_ceil(4) * 4;
        let left = data.len() - at - 8;
        let kname = String::from_utf8_lossy(&key).into_owned();
        if padded > left {
            return Err(bad(
                path,
                &format!("{place}/{kname} at byte {}", base + at),
                format!("{size} x {repeat} bytes run past the {left} bytes left in its parent"),
            ));
        }
        out.push(Klv {
            key,
            kind,
            size,
            repeat,
            data: &data[at + 8..at + 8 + len],
            at: base + at + 8,
        });
        at += 8 + padded;
    }
    Ok(out)
}

/// Bytes per value of a GPMF type, for the numeric types read here.
fn width(kind: u8) -> Option<usize> {
    match kind {
        b'b' | b'B' => Some(1),
        b's' | b'S' => Some(2),
        b'l' | b'L' | b'f' => Some(4),
        b'd' | b'j' | b'J' => Some(8),
        _ => None,
    }
}

/// Value `i` of a numeric entry.
fn value(kind: u8, d: &[u8]) -> f64 {
    match kind {
        b'b' => d[0] as i8 as f64,
        b'B' => d[0] as f64,
        b's' => i16::from_be_bytes([d[0], d[1]]) as f64,
        b'S' => u16::from_be_bytes([d[0], d[1]]) as f64,
        b'l' => i32::from_be_bytes(d[..4].try_into().expect("4 bytes")) as f64,
        b'L' => u32::from_be_bytes(d[..4].try_into().expect("4 bytes")) as f64,
        b'f' => f32::from_be_bytes(d[..4].try_into().expect("4 bytes")) as f64,
        b'd' => f64::from_be_bytes(d[..8].try_into().expect("8 bytes")),
        b'j' => i64::from_be_bytes(d[..8].try_into().expect("8 bytes")) as f64,
        _ => u64::from_be_bytes(d[..8].try_into().expect("8 bytes")) as f64,
    }
}

/// The numbers of a numeric entry, refusing another type.
fn numbers(path: &Path, place: &str, e: &Klv) -> Result<Vec<f64>> {
    let w = width(e.kind).ok_or_else(|| {
        bad(
            path,
            place,
            format!("type '{}' is not a number type", e.kind.escape_ascii()),
        )
    })?;
    if e.size % w != 0 {
        return Err(bad(
            path,
            place,
            format!("structure size {} is not a multiple of {w}", e.size),
        ));
    }
    Ok(e.data.chunks_exact(w).map(|c| value(e.kind, c)).collect())
}

/// The axis matrix of an `ORIN` string: column `i` of the data is GoPro's
/// axis named by letter `i` (uppercase +, lowercase -).
pub fn orin_matrix(orin: &str) -> std::result::Result<DMat3, String> {
    let letters: Vec<char> = orin.chars().collect();
    if letters.len() != 3 {
        return Err(format!("'{orin}': expected 3 axis letters such as ZXY"));
    }
    let mut cols = [DVec3::ZERO; 3];
    let mut seen = [false; 3];
    for (i, c) in letters.iter().enumerate() {
        let (axis, sign) = match c {
            'X' => (0, 1.0),
            'x' => (0, -1.0),
            'Y' => (1, 1.0),
            'y' => (1, -1.0),
            'Z' => (2, 1.0),
            'z' => (2, -1.0),
            _ => {
                return Err(format!(
                    "'{orin}': '{c}' is not an axis letter (X, Y, Z; lowercase negated)"
                ))
            }
        };
        if seen[axis] {
            return Err(format!("'{orin}': an axis is named twice"));
        }
        seen[axis] = true;
        let mut v = DVec3::ZERO;
        v[axis] = sign;
        cols[i] = v;
    }
    Ok(DMat3::from_cols(cols[0], cols[1], cols[2]))
}

/// What the GPMF track gave.
#[derive(Debug, Default)]
pub struct Gpmf {
    /// (time s, angular velocity rad/s in GoPro's IMU axes X left, Y back, Z up).
    pub samples: Vec<(f64, DVec3)>,
    /// The device name (`DVNM`), if any.
    pub device: Option<String>,
    /// The `ORIN` used (the file's, or [`DEFAULT_ORIN`]).
    pub orin: String,
}

/// Reads the gyro of every payload of the `gpmd` track `payloads` of `path`.
pub fn read(path: &Path, payloads: &[Sample]) -> Result<Gpmf> {
    let mut file = crate::bounded::open_file(path)?;
    // Payloads do not overlap: more bytes in all than the file holds is a
    // table pointing many samples at the same bytes (time, not memory).
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    let total: u64 = payloads.iter().map(|s| s.size).sum();
    if total > len {
        return Err(bad(
            path,
            "gpmd track",
            format!(
                "its payloads add up to {total} bytes, more than the file's {len}: they overlap"
            ),
        ));
    }
    let mut out = Gpmf::default();
    let mut buf = Vec::new();
    let mut orin_seen: Option<String> = None;
    for (k, s) in payloads.iter().enumerate() {
        let place = format!("gpmd payload {k} (byte {})", s.offset);
        if s.size > MAX_GPMF_PAYLOAD_BYTES {
            return Err(bad(
                path,
                &place,
                format!("{} bytes, over the cap of {MAX_GPMF_PAYLOAD_BYTES} (limits::MAX_GPMF_PAYLOAD_BYTES)", s.size),
            ));
        }
        buf.resize(s.size as usize, 0);
        file.seek(SeekFrom::Start(s.offset))
            .map_err(|e| Error::io(path, e))?;
        file.read_exact(&mut buf).map_err(|e| Error::io(path, e))?;
        let mut found: Vec<DVec3> = Vec::new();
        walk(
            path,
            &place,
            s.offset as usize,
            &buf,
            0,
            &mut |strm_place, list| {
                gyro_stream(path, strm_place, list, &mut found, &mut out, &mut orin_seen)
            },
        )?;
        if out.samples.len() + found.len() > MAX_TELEMETRY_SAMPLES {
            return Err(bad(path, &place, format!("more than {MAX_TELEMETRY_SAMPLES} gyro samples (limits::MAX_TELEMETRY_SAMPLES)")));
        }
        let n = found.len();
        for (i, w) in found.into_iter().enumerate() {
            let t = s.start_s + s.duration_s * i as f64 / n as f64;
            out.samples.push((t, w));
        }
    }
    out.orin = orin_seen.unwrap_or_else(|| DEFAULT_ORIN.to_string());
    if out.samples.is_empty() {
        return Err(bad(
            path,
            "gpmd track",
            "no GYRO stream in any payload (a GoPro older than HERO5, or the gyro was off)",
        ));
    }
    Ok(out)
}

/// Walks nested KLV, calling `on` with each container's entries.
fn walk(
    path: &Path,
    place: &str,
    base: usize,
    data: &[u8],
    depth: usize,
    on: &mut dyn FnMut(&str, &[Klv]) -> Result<()>,
) -> Result<()> {
    if depth > MAX_GPMF_DEPTH {
        return Err(bad(
            path,
            place,
            format!("KLV nested deeper than {MAX_GPMF_DEPTH} levels (limits::MAX_GPMF_DEPTH)"),
        ));
    }
    let list = entries(path, place, base, data)?;
    on(place, &list)?;
    for e in list.iter().filter(|e| e.kind == 0) {
        let p = format!("{place}/{}", String::from_utf8_lossy(&e.key));
        walk(path, &p, e.at, e.data, depth + 1, on)?;
    }
    Ok(())
}

/// Reads `GYRO` (with its `SCAL` and `ORIN`) from one container's entries.
fn gyro_stream(
    path: &Path,
    place: &str,
    list: &[Klv],
    found: &mut Vec<DVec3>,
    out: &mut Gpmf,
    orin_seen: &mut Option<String>,
) -> Result<()> {
    let mut scal: Vec<f64> = vec![1.0];
    let mut orin = DEFAULT_ORIN.to_string();
    let mut has_orin = false;
    for e in list {
        let p = format!(
            "{place}/{} at byte {}",
            String::from_utf8_lossy(&e.key),
            e.at
        );
        match &e.key {
            b"DVNM" if e.kind == b'c' => {
                out.device = Some(
                    String::from_utf8_lossy(e.data)
                        .trim_end_matches('\0')
                        .to_string(),
                );
            }
            b"SCAL" => {
                scal = numbers(path, &p, e)?;
                if scal.is_empty() || scal.iter().any(|&x| x == 0.0 || !x.is_finite()) {
                    return Err(bad(
                        path,
                        &p,
                        format!("scale {scal:?}: every SCAL must be a finite non-zero divisor"),
                    ));
                }
            }
            b"ORIN" => {
                if e.kind != b'c' {
                    return Err(bad(path, &p, "ORIN must be a string (type 'c')"));
                }
                orin = String::from_utf8_lossy(e.data)
                    .trim_end_matches('\0')
                    .to_string();
                has_orin = true;
            }
            b"GYRO" => {
                let w = width(e.kind).ok_or_else(|| {
                    bad(
                        path,
                        &p,
                        format!("type '{}' is not a number type", e.kind.escape_ascii()),
                    )
                })?;
                if e.size != 3 * w {
                    return Err(bad(
                        path,
                        &p,
                        format!("structure size {} is not 3 values of {w} bytes", e.size),
                    ));
                }
                if scal.len() != 1 && scal.len() != 3 {
                    return Err(bad(
                        path,
                        &p,
                        format!("{} SCAL values: expected 1 or 3", scal.len()),
                    ));
                }
                let axes = orin_matrix(&orin).map_err(|m| bad(path, &p, format!("ORIN {m}")))?;
                let m = axes;
                let v = numbers(path, &p, e)?;
                for (i, c) in v.chunks_exact(3).enumerate() {
                    let s = |j: usize| scal[if scal.len() == 3 { j } else { 0 }];
                    let raw = DVec3::new(c[0] / s(0), c[1] / s(1), c[2] / s(2));
                    if !raw.is_finite() {
                        return Err(bad(path, &p, format!("sample {i} is not finite")));
                    }
                    found.push(m * raw);
                }
                debug_assert_eq!(v.len(), 3 * e.repeat);
                if has_orin {
                    if orin_seen.as_ref().is_some_and(|o| *o != orin) {
                        return Err(bad(
                            path,
                            &p,
                            format!(
                                "ORIN changes from {} to {orin} within the file",
                                orin_seen.as_deref().unwrap_or("")
                            ),
                        ));
                    }
                    *orin_seen = Some(orin.clone());
                }
            }
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orin_names_the_axis_of_each_channel() {
        // ZXY: channel 0 is Z, 1 is X, 2 is Y; lowercase negates.
        let m = orin_matrix("ZXY").unwrap();
        assert_eq!(m * DVec3::new(1.0, 2.0, 3.0), DVec3::new(2.0, 3.0, 1.0));
        let m = orin_matrix("yXz").unwrap();
        assert_eq!(m * DVec3::new(1.0, 2.0, 3.0), DVec3::new(2.0, -1.0, -3.0));
        assert!(orin_matrix("ZZY").unwrap_err().contains("twice"));
        assert!(orin_matrix("ZX").unwrap_err().contains("3 axis letters"));
        assert!(orin_matrix("ZXW").unwrap_err().contains("'W'"));
    }

    #[test]
    fn klv_lengths_are_checked_and_zero_padding_ends_a_payload() {
        let p = Path::new("x.mp4");
        // GYRO 's' 6 x 2 = 12 bytes, then zero padding.
        let mut d = b"GYROs\x06\x00\x02".to_vec();
        d.extend_from_slice(&[0u8; 12]);
        d.extend_from_slice(&[0u8; 6]);
        let e = entries(p, "payload", 0, &d).unwrap();
        assert_eq!(e.len(), 1);
        assert_eq!((e[0].size, e[0].repeat, e[0].data.len()), (6, 2, 12));
        // 3 repeats need 18 (20 padded) bytes: 18 are there.
        let mut d = b"GYROs\x06\x00\x03".to_vec();
        d.extend_from_slice(&[1u8; 18]);
        let err = entries(p, "payload", 100, &d).unwrap_err().to_string();
        assert!(
            err.contains("GYRO at byte 100") && err.contains("run past"),
            "{err}"
        );
        // A truncated header that is not padding.
        let err = entries(p, "payload", 0, b"GYR").unwrap_err().to_string();
        assert!(err.contains("truncated KLV header"), "{err}");
    }
}
