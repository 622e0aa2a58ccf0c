//! Frame times from `ffprobe -show_frames` (the frames a decoder gives, in
//! presentation order, so row `k` is ffmpeg's frame `n = k`): the
//! presentation time of each video frame, s, `best_effort_timestamp_time`
//! (else `pts_time`, else `pkt_pts_time`). Read forms:
//!
//! - `-of csv` (ffprobe's default CSV, no keys): `frame,video,STREAM,KEY,PTS,
//!   PTS_TIME,DTS,DTS_TIME,BEST_EFFORT,BEST_EFFORT_TIME,...` (the layout of
//!   ffmpeg 4 to 7); `-of csv=p=0` without the leading `frame`;
//! - keys (`-of csv=nk=0`, `-of compact`): `frame|media_type=video|...|pts_time=0.033`;
//! - one time per line (`-show_entries frame=best_effort_timestamp_time -of csv=p=0`,
//!   or `frame,TIME` with the section name).
//!
//! Frames of other media (audio) are skipped; frames of two video streams
//! are an error (`-select_streams v:0`). Times must increase. Errors name
//! the file, the line and the field.

use super::input::TextLines;
use crate::error::{quote, Error, Result};
use std::path::Path;

/// Media types of ffprobe's `media_type` field.
const MEDIA: [&str; 5] = ["video", "audio", "subtitle", "data", "attachment"];
/// The time fields, first present first.
const TIMES: [&str; 3] = ["best_effort_timestamp_time", "pts_time", "pkt_pts_time"];

/// True when `line` (a file's first non-blank line) looks like ffprobe's
/// frame output (a `frame` section, or `media_type=`/`pts_time=` keys).
pub fn is_ffprobe_line(line: &str) -> bool {
    let t = line.trim();
    t.starts_with("frame,")
        || t.starts_with("frame|")
        || t == "frame"
        || t.contains("media_type=")
        || TIMES.iter().any(|k| t.contains(&format!("{k}=")))
        || t.split(',').next().is_some_and(|f| MEDIA.contains(&f))
        || t.parse::<f64>().is_ok()
}

/// One line's frame: `None` for a line of another medium or section.
struct Parsed<'a> {
    stream: Option<&'a str>,
    time: &'a str,
    column: String,
}

fn parse_line(t: &str) -> std::result::Result<Option<Parsed<'_>>, String> {
    let sep = if t.contains('|') { '|' } else { ',' };
    let mut f: Vec<&str> = t.split(sep).map(str::trim).collect();
    if f.first() == Some(&"frame") {
        f.remove(0);
    } else if f.first().is_some_and(|x| x.starts_with("side_data")) {
        return Ok(None);
    }
    if f.iter().any(|x| x.contains('=')) {
        let get = |k: &str| {
            f.iter()
                .find_map(|x| x.strip_prefix(k).and_then(|r| r.strip_prefix('=')))
        };
        if get("media_type").is_some_and(|m| m != "video") {
            return Ok(None);
        }
        for k in TIMES {
            if let Some(v) = get(k).filter(|v| *v != "N/A") {
                return Ok(Some(Parsed {
                    stream: get("stream_index"),
                    time: v,
                    column: k.into(),
                }));
            }
        }
        return Err(format!(
            "no presentation time ({}, not N/A)",
            TIMES.join(", ")
        ));
    }
    match f.len() {
        0 => Err("an empty frame line".into()),
        1 => Ok(Some(Parsed {
            stream: None,
            time: f[0],
            column: "time".into(),
        })),
        _ if MEDIA.contains(&f[0]) => {
            if f[0] != "video" {
                return Ok(None);
            }
            // media_type, stream_index, key_frame, pts, pts_time, pkt_dts,
            // pkt_dts_time, best_effort_timestamp, best_effort_timestamp_time.
            // The best-effort time unless N/A (a number or an error), else pts_time.
            let usable = |i: usize| f.get(i).filter(|v| **v != "N/A");
            let (time, column) = match (usable(8), usable(4)) {
                (Some(v), _) => (*v, "best_effort_timestamp_time (field 10)"),
                (None, Some(v)) => (*v, "pts_time (field 6)"),
                _ => {
                    return Err(format!(
                        "no presentation time in fields 10 (best_effort_timestamp_time) or 6 \
                         (pts_time) of {} fields",
                        f.len() + 1
                    ))
                }
            };
            Ok(Some(Parsed {
                stream: f.get(1).copied(),
                time,
                column: column.into(),
            }))
        }
        _ => Err(
            "several fields without names: use -of csv (all fields), -of csv=nk=0 (with names) \
             or -show_entries frame=best_effort_timestamp_time"
                .into(),
        ),
    }
}

/// The presentation time (s) of every video frame of an ffprobe output.
pub fn read_ffprobe_times(path: &Path) -> Result<Vec<f64>> {
    let mut lines = TextLines::open(path)?;
    let err = |line: u64, column: &str, message: String| Error::Parse {
        path: path.into(),
        line,
        column: column.into(),
        message,
    };
    let mut out: Vec<f64> = Vec::new();
    let mut stream: Option<(String, u64)> = None;
    let mut prev_line = 0;
    while let Some((line, text)) = lines.next_line()? {
        let t = text.trim();
        if t.is_empty() {
            continue;
        }
        let Some(p) = parse_line(t).map_err(|m| err(line, "-", format!("{m}: {}", quote(t))))?
        else {
            continue;
        };
        let x: f64 = p
            .time
            .parse()
            .ok()
            .filter(|x: &f64| x.is_finite())
            .ok_or_else(|| {
                err(
                    line,
                    &p.column,
                    format!("{} is not a finite time", quote(p.time)),
                )
            })?;
        if let Some(s) = p.stream {
            match &stream {
                None => stream = Some((s.to_string(), line)),
                Some((first, at)) if first != s => {
                    return Err(err(
                        line,
                        "stream_index",
                        format!(
                            "a frame of video stream {s} after stream {first}'s (line {at}): \
                             probe one stream (ffprobe -select_streams v:0)"
                        ),
                    ))
                }
                Some(_) => {}
            }
        }
        if let Some(&last) = out.last() {
            if x <= last {
                return Err(err(
                    line,
                    &p.column,
                    format!(
                        "time {x} s is not after the previous frame's {last} s (line {prev_line}): \
                         frames must be in presentation order"
                    ),
                ));
            }
        }
        prev_line = line;
        out.push(x);
    }
    if out.is_empty() {
        return Err(err(prev_line + 1, "-", "no video frames".into()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_forms() {
        let t = |s: &str| parse_line(s).unwrap().map(|p| p.time.to_string());
        assert_eq!(
            t("frame,video,0,1,0,0.000000,0,0.000000,512,0.033333,N/A").as_deref(),
            Some("0.033333")
        );
        assert_eq!(
            t("frame,video,0,1,0,0.5,N/A,N/A,N/A,N/A").as_deref(),
            Some("0.5")
        );
        assert_eq!(t("frame,audio,1,1,0,0.0,0,0.0,0,0.0"), None);
        assert_eq!(
            t("frame|media_type=video|stream_index=0|pts_time=1.25|best_effort_timestamp_time=N/A")
                .as_deref(),
            Some("1.25")
        );
        assert_eq!(t("0.041708").as_deref(), Some("0.041708"));
        assert_eq!(t("frame,0.041708").as_deref(), Some("0.041708"));
        assert!(parse_line("1,2").is_err());
        assert!(parse_line("frame|media_type=video|pts_time=N/A").is_err());
        assert!(is_ffprobe_line("frame,video,0,1"));
        assert!(is_ffprobe_line("0.0"));
        assert!(!is_ffprobe_line("t_start,exposure_s"));
    }
}
