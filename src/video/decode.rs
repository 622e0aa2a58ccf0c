//! Reading a video: `ffprobe` for the stream's size, rate, span and frame
//! count, then `ffmpeg` decoding it to raw grey or RGB frames of a chosen
//! size on a pipe, one at a time ([`decode_raw`]), optionally with each
//! frame's presentation time from the `showinfo` filter on its stderr. The
//! clip is never held: each frame is handed to the caller and dropped.
//! Frames are decoded frame for frame (`-fps_mode passthrough`: no frame
//! duplicated or dropped), so frame `k` is ffmpeg's frame `n = k`.
//! `mmbm sync` decodes as stored (`-noautorotate`: the sensor's own axes,
//! those of the gyro), small grey frames at most [`SYNC_MAX_WIDTH_PX`] wide
//! ([`decode`]).

use super::{read_frame, run_tool, spawn_error, tail_of};
use crate::error::{show_path, Error, Result};
use crate::limits::{SYNC_MAX_FRAMES, SYNC_MAX_WIDTH_PX};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

/// The last meaningful lines of a tool's stderr, for an error message.
fn tail(lines: &[String]) -> String {
    tail_of(&lines.join("\n"), 2)
}

/// What `ffprobe` says of the first video stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VideoInfo {
    /// Width as stored, px.
    pub width: u32,
    /// Height as stored, px.
    pub height: u32,
    /// Presentation time of the first frame (stream start), s.
    pub start_s: f64,
    /// Duration, s (the stream's, else the container's).
    pub duration_s: f64,
    /// Average frame rate, frames/s.
    pub fps: f64,
}

impl VideoInfo {
    /// The analysis size: at most [`SYNC_MAX_WIDTH_PX`] wide, the aspect
    /// kept, both sides even (at least 2), px.
    pub fn analysis_size(&self) -> (u32, u32) {
        let w = self.width.clamp(2, SYNC_MAX_WIDTH_PX) & !1;
        let h = ((self.height as f64 * w as f64 / self.width as f64).round() as u32).max(2) & !1;
        (w, h)
    }
}

/// The error for a program that could not be started: named, with how to
/// install it when it is missing.
/// A positive finite number from ffprobe's JSON (a string or a number).
fn number(v: &serde_json::Value) -> Option<f64> {
    match v {
        serde_json::Value::String(s) => s.parse().ok(),
        serde_json::Value::Number(n) => n.as_f64(),
        _ => None,
    }
    .filter(|x: &f64| x.is_finite())
}

/// A frame rate `N/D` from ffprobe.
fn rate(v: &serde_json::Value) -> Option<f64> {
    let s = v.as_str()?;
    let (n, d) = s.split_once('/')?;
    let r = n.parse::<f64>().ok()? / d.parse::<f64>().ok()?;
    (r.is_finite() && r > 0.0).then_some(r)
}

/// The first video stream of `video` (run before any decoding): refused,
/// naming the file, when it is missing, is not a video ffprobe reads, or
/// has no video stream.
pub fn probe(video: &Path) -> Result<VideoInfo> {
    std::fs::File::open(video).map_err(|e| Error::io(video, e))?;
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0", "-show_entries"])
        .arg("stream=width,height,avg_frame_rate,r_frame_rate,start_time,duration:format=duration,start_time")
        .args(["-of", "json"])
        .arg(video)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| spawn_error("ffprobe", e))?;
    let what = show_path(video);
    let bad = |m: String| Error::invalid(what.clone(), m);
    if !out.status.success() {
        let err: Vec<String> = String::from_utf8_lossy(&out.stderr)
            .lines()
            .map(String::from)
            .collect();
        return Err(bad(format!(
            "not a video ffprobe can read ({})",
            tail(&err)
        )));
    }
    let json: serde_json::Value = serde_json::from_slice(&out.stdout)
        .map_err(|e| bad(format!("ffprobe's output is not JSON: {e}")))?;
    let stream = json["streams"]
        .get(0)
        .ok_or_else(|| bad("no video stream (ffprobe lists none)".into()))?;
    let side = |k: &str| {
        stream[k]
            .as_u64()
            .filter(|&v| v > 0 && v <= 1 << 16)
            .map(|v| v as u32)
    };
    let (Some(width), Some(height)) = (side("width"), side("height")) else {
        return Err(bad(
            "the video stream has no size (width, height of 1 to 65536 px)".into(),
        ));
    };
    let fps = rate(&stream["avg_frame_rate"])
        .or_else(|| rate(&stream["r_frame_rate"]))
        .ok_or_else(|| bad("the video stream has no frame rate".into()))?;
    let start_s = number(&stream["start_time"])
        .or_else(|| number(&json["format"]["start_time"]))
        .unwrap_or(0.0);
    let duration_s = number(&stream["duration"])
        .or_else(|| number(&json["format"]["duration"]))
        .filter(|&d| d > 0.0)
        .ok_or_else(|| bad("the video has no duration".into()))?;
    let frames = duration_s * fps;
    if frames > SYNC_MAX_FRAMES as f64 {
        return Err(bad(format!(
            "about {frames:.0} frames ({duration_s:.1} s at {fps:.3} fps): sync reads at most \
             {SYNC_MAX_FRAMES} frames; cut the clip first (ffmpeg -i IN -t 60 -c copy OUT)"
        )));
    }
    Ok(VideoInfo {
        width,
        height,
        start_s,
        duration_s,
        fps,
    })
}

/// The presentation time in one `showinfo` line (`... n: 3 pts: 3 pts_time:0.1 ...`).
fn showinfo_time(line: &str) -> Option<Option<f64>> {
    if !line.contains("Parsed_showinfo") {
        return None;
    }
    let rest = line.split_once(" pts_time:")?.1;
    let tok = rest.split_whitespace().next().unwrap_or("");
    Some(tok.parse::<f64>().ok().filter(|t| t.is_finite()))
}

/// The layout of a raw frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pixels {
    /// One byte per pixel (`gray`).
    Gray,
    /// Three bytes per pixel, R, G, B (`rgb24`).
    Rgb,
}

impl Pixels {
    /// Bytes per pixel.
    pub fn bytes(self) -> usize {
        match self {
            Pixels::Gray => 1,
            Pixels::Rgb => 3,
        }
    }

    /// ffmpeg's name of the pixel format.
    pub fn ffmpeg_name(self) -> &'static str {
        match self {
            Pixels::Gray => "gray",
            Pixels::Rgb => "rgb24",
        }
    }
}

/// How [`decode_raw`] decodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RawDecode<'a> {
    /// Width and height the frames are scaled to (area filter), px.
    pub size: (u32, u32),
    /// Grey or RGB.
    pub pixels: Pixels,
    /// Decode as stored, ignoring a rotation tag (`-noautorotate`).
    pub as_stored: bool,
    /// Also read each frame's presentation time (the `showinfo` filter).
    pub times: bool,
    /// Most frames read; one more is an error naming `who`.
    pub max_frames: usize,
    /// Who reads, for that error (e.g. "sync").
    pub who: &'a str,
}

/// Decodes `video` to `sync`'s grey frames of `size` (the analysis size) and
/// calls `each(k, pixels)` for every frame in order (`pixels`: row-major,
/// one byte each). Returns every frame's presentation time, s. A failing
/// `each` stops ffmpeg and is returned.
pub fn decode(
    video: &Path,
    size: (u32, u32),
    each: impl FnMut(usize, &[u8]) -> Result<()>,
) -> Result<Vec<f64>> {
    decode_raw(video, &sync_frames(size, SYNC_MAX_FRAMES), each)
}

/// How `sync` decodes: grey, as stored, with times, at most `max_frames`.
fn sync_frames(size: (u32, u32), max_frames: usize) -> RawDecode<'static> {
    RawDecode {
        size,
        pixels: Pixels::Gray,
        as_stored: true,
        times: true,
        max_frames,
        who: "sync",
    }
}

/// A stretch of consecutive frames to decode (instead of the whole clip).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Window {
    /// Seek position, s from the start of the file (ffmpeg's input `-ss`):
    /// decoding starts at the keyframe at or before it and the frames before
    /// it are dropped, so a keyframe's own time costs no extra decoding.
    pub start_s: f64,
    /// Most frames decoded from there.
    pub frames: usize,
}

/// Decodes the frames of `window` of `video` to `sync`'s grey frames of
/// `size`, as [`decode`] does the whole clip: `each(k, pixels)` for the
/// window's `k`-th frame; returns their presentation times, s (on the
/// file's clock, as [`decode`] gives them).
pub fn decode_window(
    video: &Path,
    size: (u32, u32),
    window: Window,
    each: impl FnMut(usize, &[u8]) -> Result<()>,
) -> Result<Vec<f64>> {
    decode_at(video, &sync_frames(size, window.frames), Some(window), each)
}

/// Decodes `video` as `o` says and calls `each(k, pixels)` for every frame
/// in order (`pixels`: row-major, top row first, [`Pixels::bytes`] per
/// pixel; one frame in memory at a time). Returns every frame's
/// presentation time, s, when `o.times` (else an empty list). A failing
/// `each` stops ffmpeg and is returned.
pub fn decode_raw(
    video: &Path,
    o: &RawDecode<'_>,
    each: impl FnMut(usize, &[u8]) -> Result<()>,
) -> Result<Vec<f64>> {
    decode_at(video, o, None, each)
}

/// [`decode_raw`], of the whole clip or of one window (at most
/// `o.max_frames` of it, not an error there: ffmpeg stops at that count).
fn decode_at(
    video: &Path,
    o: &RawDecode<'_>,
    window: Option<Window>,
    mut each: impl FnMut(usize, &[u8]) -> Result<()>,
) -> Result<Vec<f64>> {
    let (w, h) = o.size;
    let mut vf = format!("scale={w}:{h}:flags=area,format={}", o.pixels.ffmpeg_name());
    if o.times {
        vf.push_str(",showinfo");
    }
    let mut cmd = Command::new("ffmpeg");
    cmd.args(["-hide_banner", "-nostdin", "-nostats", "-loglevel", "info"]);
    if o.as_stored {
        cmd.arg("-noautorotate");
    }
    if let Some(win) = window {
        // The file's own timestamps (-copyts), so that the times are those of a whole decode.
        cmd.args(["-ss", &format!("{:.6}", win.start_s.max(0.0)), "-copyts"]);
    }
    cmd.arg("-i").arg(video);
    if let Some(win) = window {
        cmd.args(["-frames:v", &win.frames.to_string()]);
    }
    let mut child = cmd
        .args(["-map", "0:v:0", "-an", "-sn", "-dn", "-vf"])
        .arg(vf)
        .args(["-fps_mode", "passthrough", "-f", "rawvideo", "-pix_fmt"])
        .args([o.pixels.ffmpeg_name(), "pipe:1"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| spawn_error("ffmpeg", e))?;
    let stderr = child.stderr.take().expect("piped stderr");
    // stderr is read on its own thread so that neither pipe can fill and stall ffmpeg.
    let reader = std::thread::spawn(move || {
        let mut times = Vec::new();
        let mut bad_times = 0usize;
        let mut last: Vec<String> = Vec::new();
        for line in BufReader::new(stderr).split(b'\n') {
            let Ok(line) = line else { break };
            let line = String::from_utf8_lossy(&line).into_owned();
            match showinfo_time(&line) {
                Some(Some(t)) => times.push(t),
                Some(None) => bad_times += 1,
                None if !line.contains("Parsed_showinfo") => {
                    last.push(line);
                    if last.len() > 8 {
                        last.remove(0);
                    }
                }
                None => {}
            }
        }
        (times, bad_times, last)
    });
    let mut stdout = child.stdout.take().expect("piped stdout");
    let mut buf = vec![0u8; w as usize * h as usize * o.pixels.bytes()];
    let mut k = 0usize;
    let mut failed = None;
    loop {
        if let Err(e) = crate::cancel::check() {
            failed = Some(e);
            break;
        }
        match read_frame(&mut stdout, &mut buf) {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => {
                failed = Some(Error::io(video, e));
                break;
            }
        }
        if k >= o.max_frames && window.is_none() {
            let (n, who) = (o.max_frames, o.who);
            failed = Some(Error::invalid(
                show_path(video),
                format!("more than {n} frames: {who} reads at most {n}"),
            ));
            break;
        }
        if let Err(e) = each(k, &buf) {
            failed = Some(e);
            break;
        }
        k += 1;
    }
    if failed.is_some() {
        let _ = child.kill();
    }
    drop(stdout);
    let status = child.wait().map_err(|e| Error::io(video, e))?;
    let (times, bad_times, last) = reader.join().unwrap_or_default();
    if let Some(e) = failed {
        return Err(e);
    }
    if !status.success() {
        return Err(Error::invalid(
            show_path(video),
            format!("ffmpeg could not decode it ({})", tail(&last)),
        ));
    }
    if !o.times {
        return Ok(Vec::new());
    }
    let mut times = times;
    if window.is_some() {
        // The filter may see a frame past -frames:v before ffmpeg stops.
        times.truncate(k);
    }
    if bad_times > 0 || times.len() != k {
        return Err(Error::invalid(
            show_path(video),
            format!(
                "ffmpeg gave {k} frames but {} presentation times ({bad_times} unreadable)",
                times.len()
            ),
        ));
    }
    if let Some(i) = (1..times.len()).find(|&i| times[i] <= times[i - 1]) {
        return Err(Error::invalid(
            show_path(video),
            format!(
                "frame {i}'s presentation time {} s does not follow frame {}'s {} s",
                times[i],
                i - 1,
                times[i - 1]
            ),
        ));
    }
    Ok(times)
}

/// ffprobe's `entries` (its `-show_entries`, e.g. `stream=width,height`)
/// of the first video stream of `video`, as CSV without section names.
pub fn probe_csv(video: &Path, entries: &str) -> Result<String> {
    let out = run_tool(
        "ffprobe",
        &[
            "-v".as_ref(),
            "error".as_ref(),
            "-select_streams".as_ref(),
            "v:0".as_ref(),
            "-show_entries".as_ref(),
            entries.as_ref(),
            "-of".as_ref(),
            "csv=p=0".as_ref(),
            video.as_os_str(),
        ],
    )?;
    Ok(String::from_utf8_lossy(&out).into_owned())
}

/// The video's first video stream's width and height, px (ffprobe).
pub fn probe_size(video: &Path) -> Result<(u32, u32)> {
    crate::io::input::open_file(video)?;
    let text = probe_csv(video, "stream=width,height")?;
    let bad = || {
        Error::invalid(
            "--video",
            format!(
                "{}: no video stream ffprobe can size ({})",
                video.display(),
                text.trim()
            ),
        )
    };
    let line = text.lines().next().ok_or_else(bad)?;
    let (w, h) = line
        .trim()
        .trim_end_matches(',')
        .split_once(',')
        .ok_or_else(bad)?;
    match (w.trim().parse::<u32>(), h.trim().parse::<u32>()) {
        (Ok(w), Ok(h)) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(bad()),
    }
}

/// The number of frames (packets) of the video's first video stream, as
/// ffprobe counts them (demuxed, not decoded).
pub fn count_frames(video: &Path) -> Result<usize> {
    crate::io::input::open_file(video)?;
    let out = run_tool(
        "ffprobe",
        &[
            "-v".as_ref(),
            "error".as_ref(),
            "-select_streams".as_ref(),
            "v:0".as_ref(),
            "-count_packets".as_ref(),
            "-show_entries".as_ref(),
            "stream=nb_read_packets".as_ref(),
            "-of".as_ref(),
            "csv=p=0".as_ref(),
            video.as_os_str(),
        ],
    )?;
    let text = String::from_utf8_lossy(&out);
    text.trim()
        .trim_end_matches(',')
        .parse::<usize>()
        .map_err(|_| {
            Error::invalid(
                "--video",
                format!(
                    "{}: ffprobe counts no video frames ({})",
                    video.display(),
                    text.trim()
                ),
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn showinfo_lines() {
        let l = "[Parsed_showinfo_2 @ 0x5581] n:   3 pts:   3072 pts_time:0.1     duration:1024";
        assert_eq!(showinfo_time(l), Some(Some(0.1)));
        assert_eq!(
            showinfo_time("[Parsed_showinfo_2 @ 0x1] color_range:tv"),
            None
        );
        assert_eq!(showinfo_time("Stream #0:0: Video: h264"), None);
        assert_eq!(
            showinfo_time("[Parsed_showinfo_2 @ 0x1] n: 0 pts: 0 pts_time:nan x"),
            Some(None)
        );
    }

    #[test]
    fn analysis_size_even_and_capped() {
        let v = |width, height| VideoInfo {
            width,
            height,
            start_s: 0.0,
            duration_s: 1.0,
            fps: 30.0,
        };
        assert_eq!(v(320, 240).analysis_size(), (320, 240));
        assert_eq!(v(1920, 1080).analysis_size(), (SYNC_MAX_WIDTH_PX, 270));
        assert_eq!(v(1, 1).analysis_size(), (2, 2));
    }
}
