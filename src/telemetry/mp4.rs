//! The part of an MP4 (ISO BMFF / QuickTime) file that a gyro track needs,
//! read with every length checked: the top-level boxes are walked by their
//! headers (seeks, the video data is never read), the `moov` box is read
//! whole (at most [`MAX_MP4_MOOV_BYTES`]) and each track's sample table is
//! turned into (file offset, size, start time, duration) per sample.
//!
//! Boxes read: `moov > trak > mdia > {hdlr, mdhd, minf > stbl > {stsd,
//! stts, stsz, stsc, stco | co64}}`. A box whose length runs past its
//! parent (or the file), a table whose count does not fit its box, or a
//! sample past the end of the file is refused with the file, the box path
//! and the byte offset.

use crate::error::{Error, Result};
use crate::limits::{MAX_MP4_BOXES, MAX_MP4_MOOV_BYTES};
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// A refusal naming the file, the place and the reason.
pub fn bad(path: &Path, place: &str, reason: impl std::fmt::Display) -> Error {
    Error::Config {
        path: path.into(),
        message: format!("{place}: {reason}"),
    }
}

/// One sample of a track: where its bytes lie and when it plays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Offset in the file, bytes.
    pub offset: u64,
    /// Size, bytes.
    pub size: u64,
    /// Presentation start, s (from the track's `stts`).
    pub start_s: f64,
    /// Duration, s.
    pub duration_s: f64,
}

/// A track of the file.
#[derive(Debug, Clone)]
pub struct Track {
    /// Handler type (`vide`, `soun`, `meta`, ...).
    pub handler: [u8; 4],
    /// First sample entry's format (`avc1`, `gpmd`, ...).
    pub format: [u8; 4],
    /// Time units per second (`mdhd`).
    pub timescale: u32,
    /// The samples, in order.
    pub samples: Vec<Sample>,
}

impl Track {
    /// Mean frame rate, 1/s (samples over their total duration).
    pub fn rate(&self) -> Option<f64> {
        let d: f64 = self.samples.iter().map(|s| s.duration_s).sum();
        (d > 0.0).then(|| self.samples.len() as f64 / d)
    }
}

/// True when the file's first box is `ftyp` (MP4 / QuickTime).
pub fn looks_like_mp4(head: &[u8]) -> bool {
    head.len() >= 8 && &head[4..8] == b"ftyp"
}

/// A box's header: type, payload range within the parent's bytes.
#[derive(Debug)]
struct Header {
    kind: [u8; 4],
    body: std::ops::Range<usize>,
}

fn name(k: &[u8; 4]) -> String {
    k.iter()
        .map(|&b| if b.is_ascii_graphic() { b as char } else { '?' })
        .collect()
}

/// The boxes of `data` (one level), each checked to lie inside it.
fn boxes(path: &Path, place: &str, base: u64, data: &[u8]) -> Result<Vec<Header>> {
    let mut out = Vec::new();
    let mut at = 0usize;
    while at < data.len() {
        if out.len() >= MAX_MP4_BOXES {
            return Err(bad(path, place, format!("more than {MAX_MP4_BOXES} boxes")));
        }
        let here = base + at as u64;
        if data.len() - at < 8 {
            return Err(bad(
                path,
                &format!("{place} at byte {here}"),
                "truncated box header",
            ));
        }
        let size32 = u32::from_be_bytes(data[at..at + 4].try_into().expect("4 bytes"));
        let kind: [u8; 4] = data[at + 4..at + 8].try_into().expect("4 bytes");
        let (head, size) = match size32 {
            0 => (8usize, (data.len() - at) as u64),
            1 => {
                if data.len() - at < 16 {
                    return Err(bad(
                        path,
                        &format!("{place} at byte {here}"),
                        "truncated box header",
                    ));
                }
                (
                    16,
                    u64::from_be_bytes(data[at + 8..at + 16].try_into().expect("8 bytes")),
                )
            }
            n => (8, n as u64),
        };
        let left = (data.len() - at) as u64;
        if size < head as u64 || size > left {
            return Err(bad(
                path,
                &format!("{place}/{} at byte {here}", name(&kind)),
                format!("box length {size} does not fit (header {head} bytes, {left} bytes left in its parent)"),
            ));
        }
        out.push(Header {
            kind,
            body: at + head..at + size as usize,
        });
        at += size as usize;
    }
    Ok(out)
}

fn find<'a>(list: &'a [Header], kind: &[u8; 4]) -> Option<&'a Header> {
    list.iter().find(|h| &h.kind == kind)
}

/// Reads the file's `moov` box whole (its offset, its bytes).
fn read_moov(path: &Path, file: &mut File, len: u64) -> Result<(u64, Vec<u8>)> {
    let mut at = 0u64;
    let mut n = 0usize;
    let io = |e| Error::io(path, e);
    while at < len {
        n += 1;
        if n > MAX_MP4_BOXES {
            return Err(bad(
                path,
                "top level",
                format!("more than {MAX_MP4_BOXES} boxes"),
            ));
        }
        if len - at < 8 {
            return Err(bad(
                path,
                &format!("top level at byte {at}"),
                "truncated box header",
            ));
        }
        let mut h = [0u8; 16];
        file.seek(SeekFrom::Start(at)).map_err(io)?;
        let want = (len - at).min(16) as usize;
        file.read_exact(&mut h[..want]).map_err(io)?;
        let size32 = u32::from_be_bytes(h[0..4].try_into().expect("4 bytes"));
        let kind: [u8; 4] = h[4..8].try_into().expect("4 bytes");
        let (head, size) = match size32 {
            0 => (8u64, len - at),
            1 if want == 16 => (
                16,
                u64::from_be_bytes(h[8..16].try_into().expect("8 bytes")),
            ),
            1 => {
                return Err(bad(
                    path,
                    &format!("top level at byte {at}"),
                    "truncated box header",
                ))
            }
            s => (8, s as u64),
        };
        if size < head || size > len - at {
            return Err(bad(
                path,
                &format!("{} at byte {at}", name(&kind)),
                format!("box length {size} runs past the end of the file ({len} bytes)"),
            ));
        }
        if &kind == b"moov" {
            let body = size - head;
            if body > MAX_MP4_MOOV_BYTES {
                return Err(bad(
                    path,
                    &format!("moov at byte {at}"),
                    format!("{body} bytes, over the cap of {MAX_MP4_MOOV_BYTES} (limits::MAX_MP4_MOOV_BYTES)"),
                ));
            }
            let mut buf = vec![0u8; body as usize];
            file.seek(SeekFrom::Start(at + head)).map_err(io)?;
            file.read_exact(&mut buf).map_err(io)?;
            return Ok((at + head, buf));
        }
        at += size;
    }
    Err(bad(
        path,
        "MP4",
        "no moov box (the file's index): not a finished MP4 recording",
    ))
}

/// Big-endian reads inside a table box, each checked.
struct Cursor<'a> {
    path: &'a Path,
    place: String,
    data: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn u32(&mut self) -> Result<u32> {
        let b = self.data.get(self.at..self.at + 4).ok_or_else(|| {
            bad(
                self.path,
                &self.place,
                format!("truncated at byte {} of the box", self.at),
            )
        })?;
        self.at += 4;
        Ok(u32::from_be_bytes(b.try_into().expect("4 bytes")))
    }
    fn u64(&mut self) -> Result<u64> {
        let hi = self.u32()? as u64;
        Ok((hi << 32) | self.u32()? as u64)
    }
    /// A count of entries of `each` bytes that must fit in what is left.
    fn count(&mut self, each: usize) -> Result<usize> {
        let n = self.u32()? as usize;
        let left = self.data.len() - self.at;
        if n.checked_mul(each).is_none_or(|b| b > left) {
            return Err(bad(
                self.path,
                &self.place,
                format!("{n} entries of {each} bytes do not fit in the {left} bytes left"),
            ));
        }
        Ok(n)
    }
}

/// Reads the tracks of the MP4 file `path` (sample tables only).
pub fn tracks(path: &Path) -> Result<Vec<Track>> {
    let mut file = crate::bounded::open_file(path)?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    let (base, moov) = read_moov(path, &mut file, len)?;
    let mut out = Vec::new();
    for trak in boxes(path, "moov", base, &moov)?
        .iter()
        .filter(|h| &h.kind == b"trak")
    {
        let tb = &moov[trak.body.clone()];
        let tbase = base + trak.body.start as u64;
        let tl = boxes(path, "moov/trak", tbase, tb)?;
        let Some(mdia) = find(&tl, b"mdia") else {
            continue;
        };
        let mb = &tb[mdia.body.clone()];
        let mbase = tbase + mdia.body.start as u64;
        let ml = boxes(path, "trak/mdia", mbase, mb)?;
        let (Some(hdlr), Some(mdhd), Some(minf)) =
            (find(&ml, b"hdlr"), find(&ml, b"mdhd"), find(&ml, b"minf"))
        else {
            continue;
        };
        let h = &mb[hdlr.body.clone()];
        let handler: [u8; 4] = h
            .get(8..12)
            .ok_or_else(|| bad(path, "mdia/hdlr", "truncated"))?
            .try_into()
            .expect("4 bytes");
        let d = &mb[mdhd.body.clone()];
        let mut c = Cursor {
            path,
            place: "mdia/mdhd".into(),
            data: d,
            at: 0,
        };
        let version = c.u32()? >> 24;
        if version == 1 {
            c.u64()?;
            c.u64()?;
        } else {
            c.u32()?;
            c.u32()?;
        }
        let timescale = c.u32()?;
        if timescale == 0 {
            return Err(bad(path, "mdia/mdhd", "timescale 0"));
        }
        let nb = &mb[minf.body.clone()];
        let nbase = mbase + minf.body.start as u64;
        let nl = boxes(path, "mdia/minf", nbase, nb)?;
        let Some(stbl) = find(&nl, b"stbl") else {
            continue;
        };
        let sb = &nb[stbl.body.clone()];
        let sl = boxes(path, "minf/stbl", nbase + stbl.body.start as u64, sb)?;
        let get = |k: &[u8; 4]| find(&sl, k).map(|h| &sb[h.body.clone()]);
        let format: [u8; 4] = match get(b"stsd").and_then(|d| d.get(12..16)) {
            Some(f) => f.try_into().expect("4 bytes"),
            None => continue,
        };
        let samples = sample_table(path, &handler, timescale, len, &get)?;
        out.push(Track {
            handler,
            format,
            timescale,
            samples,
        });
    }
    Ok(out)
}

/// The samples of one track from its `stts`, `stsz`, `stsc` and chunk offsets.
fn sample_table<'a>(
    path: &Path,
    handler: &[u8; 4],
    timescale: u32,
    file_len: u64,
    get: &dyn Fn(&[u8; 4]) -> Option<&'a [u8]>,
) -> Result<Vec<Sample>> {
    let t = name(handler);
    let need = |k: &[u8; 4]| {
        get(k).ok_or_else(|| {
            bad(
                path,
                &format!("{t} track/stbl"),
                format!("no {} box", name(k)),
            )
        })
    };
    let cur = |k: &[u8; 4], d: &'a [u8]| Cursor {
        path,
        place: format!("{t} track/stbl/{}", name(k)),
        data: d,
        at: 4,
    };
    // stsz: sizes.
    let mut c = cur(b"stsz", need(b"stsz")?);
    let fixed = c.u32()?;
    let n = c.u32()? as usize;
    let sizes: Vec<u64> = if fixed != 0 {
        if n > crate::limits::MAX_TELEMETRY_SAMPLES {
            return Err(bad(path, &c.place, format!("{n} samples, over the cap")));
        }
        vec![fixed as u64; n]
    } else {
        c.at -= 4;
        let m = c.count(4)?;
        (0..m)
            .map(|_| c.u32().map(u64::from))
            .collect::<Result<_>>()?
    };
    // Chunk offsets.
    let offsets: Vec<u64> = if let Some(d) = get(b"stco") {
        let mut c = cur(b"stco", d);
        let m = c.count(4)?;
        (0..m)
            .map(|_| c.u32().map(u64::from))
            .collect::<Result<_>>()?
    } else {
        let mut c = cur(b"co64", need(b"co64")?);
        let m = c.count(8)?;
        (0..m).map(|_| c.u64()).collect::<Result<_>>()?
    };
    // stsc: (first chunk, samples per chunk).
    let mut c = cur(b"stsc", need(b"stsc")?);
    let m = c.count(12)?;
    let mut runs = Vec::with_capacity(m);
    for _ in 0..m {
        let first = c.u32()? as usize;
        let per = c.u32()? as usize;
        c.u32()?;
        if first == 0 || runs.last().is_some_and(|&(f, _)| first <= f) {
            return Err(bad(
                path,
                &c.place,
                format!("first chunk {first} is not increasing from 1"),
            ));
        }
        runs.push((first, per));
    }
    // stts: (count, delta).
    let mut c = cur(b"stts", need(b"stts")?);
    let m = c.count(8)?;
    let mut deltas = Vec::with_capacity(sizes.len());
    for _ in 0..m {
        let count = c.u32()? as usize;
        let delta = c.u32()?;
        if deltas.len() + count > sizes.len() {
            return Err(bad(
                path,
                &c.place,
                format!("times for more samples than the {} of stsz", sizes.len()),
            ));
        }
        deltas.extend(std::iter::repeat_n(delta, count));
    }
    if deltas.len() != sizes.len() {
        return Err(bad(
            path,
            &c.place,
            format!(
                "times for {} samples, stsz has {}",
                deltas.len(),
                sizes.len()
            ),
        ));
    }
    let mut out = Vec::with_capacity(sizes.len());
    let mut k = 0usize;
    let mut clock = 0u64;
    let place = format!("{t} track");
    // The run of each chunk, walked once (runs are in increasing order).
    let mut run = 0usize;
    for (ci, &chunk_at) in offsets.iter().enumerate() {
        while run + 1 < runs.len() && runs[run + 1].0 <= ci + 1 {
            run += 1;
        }
        let per = runs.get(run).filter(|r| r.0 <= ci + 1).map_or(0, |r| r.1);
        let mut at = chunk_at;
        for _ in 0..per {
            if k >= sizes.len() {
                break;
            }
            let size = sizes[k];
            if at.checked_add(size).is_none_or(|e| e > file_len) {
                return Err(bad(
                    path,
                    &format!("{place} sample {k}"),
                    format!(
                        "bytes {at}..{} lie past the end of the file ({file_len} bytes)",
                        at.saturating_add(size)
                    ),
                ));
            }
            out.push(Sample {
                offset: at,
                size,
                start_s: clock as f64 / timescale as f64,
                duration_s: deltas[k] as f64 / timescale as f64,
            });
            clock += deltas[k] as u64;
            at += size;
            k += 1;
        }
    }
    if k != sizes.len() {
        return Err(bad(
            path,
            &place,
            format!("the chunks hold {k} samples, stsz lists {}", sizes.len()),
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_lengths_must_fit_their_parent() {
        let p = Path::new("x.mp4");
        let mut d = 16u32.to_be_bytes().to_vec();
        d.extend_from_slice(b"free");
        d.extend_from_slice(&[0u8; 8]);
        assert_eq!(boxes(p, "moov", 0, &d).unwrap().len(), 1);
        d[3] = 17;
        let e = boxes(p, "moov", 40, &d).unwrap_err().to_string();
        assert!(
            e.contains("moov/free at byte 40") && e.contains("does not fit"),
            "{e}"
        );
        d[3] = 4; // shorter than its own header
        assert!(boxes(p, "moov", 0, &d).is_err());
        assert!(boxes(p, "moov", 0, &d[..5])
            .unwrap_err()
            .to_string()
            .contains("truncated"));
    }

    #[test]
    fn a_table_count_must_fit_its_box() {
        let p = Path::new("x.mp4");
        let data = [0u8, 0, 0, 0, 0x40, 0, 0, 0, 1, 2, 3, 4];
        let mut c = Cursor {
            path: p,
            place: "stco".into(),
            data: &data,
            at: 4,
        };
        let e = c.count(4).unwrap_err().to_string();
        assert!(
            e.contains("1073741824 entries of 4 bytes do not fit in the 4 bytes left"),
            "{e}"
        );
    }
}
