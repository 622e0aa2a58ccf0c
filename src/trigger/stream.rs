//! A live stream of IMU samples through [`Live`] runners: the loop behind
//! `mmbm live`.
//!
//! Samples arrive as text lines ([`LineParser`]: the gyro CSV or JSON lines)
//! from a reader such as stdin ([`Stream::lines`]) or in UDP datagrams of
//! one or more lines ([`Stream::udp`]), or from a recorded log replayed at
//! its own pace ([`Stream::replay`], read one sample at a time as it is
//! played: memory stays constant). Each sample's MMBM is evaluated once
//! ([`crate::series::sample_mmbm`]) and given to every policy; the decisions
//! are written as JSON lines, flushed at once.
//!
//! Bad input never ends a stream: a malformed line, or a sample whose MMBM
//! cannot be evaluated (not finite, for rates near the float range; no
//! velocity under `use_velocity`), is reported on stderr and skipped, and a
//! sample whose time does not increase is reported and dropped. With
//! [`StreamOptions::strict`] the first malformed line or bad sample ends the
//! stream ([`StreamEnd::Strict`]).
//!
//! A [`StreamControl`] shared with the caller (a signal handler) stops a
//! stream: during a replay's wait or a UDP poll within [`POLL`], on a line
//! reader at its next chunk of input, within a line too (an endless line
//! with no `\n`); a read blocked on a silent input is not interrupted: see
//! [`StreamControl::wait_ended`].

use super::latency::Latency;
use super::live::{Event, Live};
use super::pace::{self, Pacer};
use crate::error::{Error, Result};
use crate::io::gyro::{GyroOptions, GyroSample};
use crate::io::input::{line_too_long, read_line_or_stop, Line, MAX_LINE_BYTES};
use crate::io::lines::LineParser;
use crate::metric::Evaluator;
use crate::series::{check_values, sample_mmbm, SeriesOptions};
use std::io::{BufRead, Write};
use std::net::UdpSocket;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How soon a stop request is seen by a replay's wait or a UDP receive.
pub const POLL: Duration = pace::SLICE;

/// A handle shared by a running [`Stream`] and whoever may stop it (a
/// signal handler): the stop request, whether a stream is running, and its
/// latency statistics so far. Clones share the same state.
#[derive(Debug, Clone, Default)]
pub struct StreamControl(Arc<Shared>);

#[derive(Debug, Default)]
struct Shared {
    stop: AtomicBool,
    running: AtomicBool,
    latency: Mutex<Option<Latency>>,
}

impl StreamControl {
    /// Asks the stream to stop (it ends with [`StreamEnd::Stopped`]).
    pub fn stop(&self) {
        self.0.stop.store(true, Ordering::SeqCst);
    }

    /// True once [`StreamControl::stop`] was called.
    pub fn is_stopped(&self) -> bool {
        self.0.stop.load(Ordering::SeqCst)
    }

    /// True while a stream reads its input.
    pub fn is_running(&self) -> bool {
        self.0.running.load(Ordering::SeqCst)
    }

    /// The latency statistics so far (None unless [`StreamOptions::stats`]).
    pub fn latency(&self) -> Option<Latency> {
        self.0.latency.lock().ok().and_then(|g| g.clone())
    }

    /// Waits up to `timeout` for a running stream to end (after a stop
    /// request): true when one was running and has ended, false when none
    /// was running or it still is (a read blocked on a silent input).
    pub fn wait_ended(&self, timeout: Duration) -> bool {
        if !self.is_running() {
            return false;
        }
        let start = Instant::now();
        while self.is_running() {
            if start.elapsed() >= timeout {
                return false;
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        true
    }

    fn add_latency(&self, d: Duration) {
        if let Ok(mut g) = self.0.latency.lock() {
            if let Some(l) = g.as_mut() {
                l.add(d);
            }
        }
    }
}

/// Marks a stream running until dropped.
struct Running(Arc<Shared>);

impl Running {
    fn new(c: &StreamControl) -> Self {
        c.0.running.store(true, Ordering::SeqCst);
        Running(c.0.clone())
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        self.0.running.store(false, Ordering::SeqCst);
    }
}

/// What a stream writes and how strict it is.
#[derive(Debug, Clone, Copy, Default)]
pub struct StreamOptions {
    /// A line for every sample, not only triggers and exposures.
    pub all: bool,
    /// End at the first malformed line or bad sample instead of skipping it.
    pub strict: bool,
    /// Keep latency statistics (sample read to decision written).
    pub stats: bool,
}

/// Why a stream ended.
#[derive(Debug)]
pub enum StreamEnd {
    /// The input ended (end of file, end of the replayed log).
    Eof,
    /// No UDP datagram for the idle time.
    Idle,
    /// [`StreamControl::stop`] was called.
    Stopped,
    /// The first malformed line or bad sample, under [`StreamOptions::strict`].
    Strict(Error),
}

/// How a stream ended and what it did.
#[derive(Debug)]
pub struct StreamOutcome {
    /// Why it ended.
    pub end: StreamEnd,
    /// Samples decided (malformed, bad and out-of-order ones not counted).
    pub samples: u64,
    /// Latency statistics (with [`StreamOptions::stats`]).
    pub latency: Option<Latency>,
}

/// Where a sample came from, for messages.
#[derive(Debug, Clone, Copy)]
enum At<'a> {
    /// Line `n` of a line source.
    Line(&'a str, u64),
    /// Sample `n` of a replayed log.
    Sample(&'a str, u64),
}

impl std::fmt::Display for At<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            At::Line(src, n) => write!(f, "{src}:{n}"),
            At::Sample(src, n) => write!(f, "{src}: sample {n}"),
        }
    }
}

impl At<'_> {
    /// A bad sample's error, named like a malformed line's.
    fn error(self, e: Error) -> Error {
        match self {
            At::Line(src, line) => Error::Parse {
                path: src.into(),
                line,
                column: "-".into(),
                message: e.to_string(),
            },
            At::Sample(..) => Error::invalid(self.to_string(), e.to_string()),
        }
    }

    fn unit(self) -> &'static str {
        match self {
            At::Line(..) => "line",
            At::Sample(..) => "sample",
        }
    }
}

/// Policies decided live on a stream of samples (see the module docs).
pub struct Stream {
    runs: Vec<Live>,
    series: SeriesOptions,
    eval: Evaluator,
    opts: StreamOptions,
    control: StreamControl,
    last_t: f64,
    samples: u64,
}

impl Stream {
    /// A stream deciding `runs` (one [`Live`] per policy) on the MMBM under
    /// `series` (a CPU method), stopped through `control`.
    pub fn new(
        runs: Vec<Live>,
        series: SeriesOptions,
        opts: StreamOptions,
        control: StreamControl,
    ) -> Result<Self> {
        let eval = Evaluator::new(&series.scene.camera, series.method)?;
        if let Ok(mut g) = control.0.latency.lock() {
            *g = opts.stats.then(Latency::new);
        }
        Ok(Stream {
            runs,
            series,
            eval,
            opts,
            control,
            last_t: f64::NEG_INFINITY,
            samples: 0,
        })
    }

    /// Decides on the sample lines of `input`, named `source` in messages
    /// (e.g. `<stdin>`), until it ends. A line that is not UTF-8 is a
    /// malformed line.
    pub fn lines(
        &mut self,
        input: &mut dyn BufRead,
        gyro: GyroOptions,
        source: &str,
        out: &mut dyn Write,
    ) -> Result<StreamOutcome> {
        let _running = Running::new(&self.control);
        let mut parser = LineParser::new(gyro, source);
        let mut line_no = 0;
        let mut raw = Vec::new();
        loop {
            if self.control.is_stopped() {
                return Ok(self.outcome(StreamEnd::Stopped));
            }
            // A line over the cap is read to its end in bounded memory and
            // is a malformed line.
            // A stop request is seen within a line too (an endless one).
            let stop = || self.control.is_stopped();
            let read = read_line_or_stop(input, &mut raw, MAX_LINE_BYTES, &stop)
                .map_err(|e| Error::io(source, e))?;
            let Some(read) = read else {
                return Ok(self.outcome(StreamEnd::Stopped));
            };
            match read {
                Line::Eof => return Ok(self.outcome(StreamEnd::Eof)),
                Line::TooLong => {
                    line_no += 1;
                    let e = line_too_long(Path::new(source), line_no, MAX_LINE_BYTES);
                    if self.opts.strict {
                        return Ok(self.outcome(StreamEnd::Strict(e)));
                    }
                    eprintln!("{e}; line skipped");
                    continue;
                }
                Line::Read => {}
            }
            let text = String::from_utf8_lossy(&raw);
            if let Some(end) = self.line(&mut parser, &text, &mut line_no, source, out)? {
                return Ok(self.outcome(end));
            }
        }
    }

    /// Decides on the sample lines of the UDP datagrams received on `addr`
    /// (one or more lines each, named `<udp>` in messages), until
    /// `idle_exit` seconds (> 0) pass without a datagram (None: never).
    pub fn udp(
        &mut self,
        addr: &str,
        idle_exit: Option<f64>,
        gyro: GyroOptions,
        out: &mut dyn Write,
    ) -> Result<StreamOutcome> {
        let idle = match idle_exit {
            Some(s) => Some(pace::due(
                crate::check::positive("UDP idle time (s)", s)?,
                1.0,
            )),
            None => None,
        };
        let name = format!("udp {addr}");
        let sock = UdpSocket::bind(addr).map_err(|e| Error::io(&name, e))?;
        let poll = idle.map_or(POLL, |d| d.min(POLL));
        sock.set_read_timeout(Some(poll.max(Duration::from_micros(1))))
            .map_err(|e| Error::io(&name, e))?;
        let _running = Running::new(&self.control);
        let mut parser = LineParser::new(gyro, "<udp>");
        let mut line_no = 0;
        let mut buf = vec![0u8; 65536];
        let mut last = Instant::now();
        loop {
            if self.control.is_stopped() {
                return Ok(self.outcome(StreamEnd::Stopped));
            }
            let n = match sock.recv(&mut buf) {
                Ok(n) => n,
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock
                            | std::io::ErrorKind::TimedOut
                            | std::io::ErrorKind::Interrupted
                    ) =>
                {
                    // A quiet poll, or a signal (Ctrl-C) while waiting.
                    if idle.is_some_and(|d| last.elapsed() >= d) {
                        return Ok(self.outcome(StreamEnd::Idle));
                    }
                    continue;
                }
                Err(e) => return Err(Error::io(&name, e)),
            };
            last = Instant::now();
            let text = String::from_utf8_lossy(&buf[..n]).into_owned();
            for l in text.lines() {
                if let Some(end) = self.line(&mut parser, l, &mut line_no, "<udp>", out)? {
                    return Ok(self.outcome(end));
                }
            }
        }
    }

    /// Decides on a recorded log's `samples` (e.g. a
    /// [`crate::io::gyro::GyroReader`], named `name` in messages), each
    /// taken from the iterator when it is due: at its time since the first
    /// divided by `speed` (0: as fast as possible). An error of the
    /// iterator ends the stream with that error.
    pub fn replay(
        &mut self,
        samples: impl IntoIterator<Item = Result<GyroSample>>,
        name: &str,
        speed: f64,
        out: &mut dyn Write,
    ) -> Result<StreamOutcome> {
        let mut pacer = Pacer::new(speed)?;
        let _running = Running::new(&self.control);
        for (k, s) in samples.into_iter().enumerate() {
            if self.control.is_stopped() {
                return Ok(self.outcome(StreamEnd::Stopped));
            }
            let s = s?;
            if !pacer.wait(s.t, &self.control.0.stop) {
                return Ok(self.outcome(StreamEnd::Stopped));
            }
            let read_at = Instant::now();
            if let Some(end) = self.take(&s, read_at, At::Sample(name, k as u64 + 1), out)? {
                return Ok(self.outcome(end));
            }
        }
        Ok(self.outcome(StreamEnd::Eof))
    }

    fn outcome(&self, end: StreamEnd) -> StreamOutcome {
        StreamOutcome {
            end,
            samples: self.samples,
            latency: self.control.latency(),
        }
    }

    /// One text line: a sample decided, a header or comment taken, or a
    /// malformed line reported and skipped (`Some` to end the stream).
    fn line(
        &mut self,
        parser: &mut LineParser,
        text: &str,
        line_no: &mut u64,
        source: &str,
        out: &mut dyn Write,
    ) -> Result<Option<StreamEnd>> {
        *line_no += 1;
        let read_at = Instant::now();
        match parser.parse(text, *line_no) {
            Ok(Some(s)) => self.take(&s, read_at, At::Line(source, *line_no), out),
            Ok(None) => Ok(None),
            Err(e) if self.opts.strict => Ok(Some(StreamEnd::Strict(e))),
            Err(e) => {
                log::warn!("{e}; line skipped");
                Ok(None)
            }
        }
    }

    /// One sample: order check, MMBM, decisions, latency.
    fn take(
        &mut self,
        s: &GyroSample,
        read_at: Instant,
        at: At,
        out: &mut dyn Write,
    ) -> Result<Option<StreamEnd>> {
        if s.t <= self.last_t {
            log::warn!(
                "{at}: time {} s does not follow {} s; sample dropped",
                s.t,
                self.last_t
            );
            return Ok(None);
        }
        // The MMBM and, on pixels that are not square, its px/s (for the
        // pixel budgets).
        // Every runner checks the sample before any takes it (its time base
        // for the exposure, above all): a bad one is skipped by all.
        let values = sample_mmbm(s, &self.series, &self.eval)
            .and_then(|m| check_values(std::slice::from_ref(s), &[m]).map(|_| m))
            .and_then(|m| crate::series::sample_px(s, &self.series, &self.eval, m).map(|p| (m, p)))
            .and_then(|v| {
                self.runs
                    .iter()
                    .try_for_each(|r| r.check(s.t, v.0))
                    .map(|_| v)
            });
        let (m, px) = match values {
            Ok(v) => v,
            Err(e) => {
                let e = at.error(e);
                if self.opts.strict {
                    return Ok(Some(StreamEnd::Strict(e)));
                }
                log::warn!("{e}; {} skipped", at.unit());
                return Ok(None);
            }
        };
        self.last_t = s.t;
        self.decide(s, m, px, out)?;
        self.samples += 1;
        if self.opts.stats {
            self.control.add_latency(read_at.elapsed());
        }
        Ok(None)
    }

    /// Gives sample `s` with MMBM `m` to every policy and writes the lines
    /// it produces.
    fn decide(
        &mut self,
        s: &GyroSample,
        m: f64,
        px: Option<f64>,
        out: &mut dyn Write,
    ) -> Result<()> {
        let mut text = String::new();
        for live in self.runs.iter_mut() {
            let events = live.push_px(s.t, m, px)?;
            let triggered = events.iter().any(|e| matches!(e, Event::Trigger(..)));
            for e in events {
                let v = match e {
                    Event::Trigger(k, f) => serde_json::json!({
                        "t": f.trigger_t, "policy": f.policy, "trigger": true, "frame": k,
                        "mmbm_mm_s": f.mmbm_trigger_mm_s, "exposure_start": f.exposure_start,
                        "exposure_end": f.exposure_end, "gain": f.gain,
                    }),
                    Event::Exposed(k, f) => serde_json::json!({
                        "t": s.t, "policy": f.policy, "exposed": true, "frame": k,
                        "trigger_t": f.trigger_t, "mmbm_exposure_mm_s": f.mmbm_exposure_mm_s,
                        "kept": f.kept,
                    }),
                };
                text.push_str(&v.to_string());
                text.push('\n');
            }
            if self.opts.all && !triggered {
                let v = serde_json::json!({
                    "t": s.t, "policy": live.label(), "trigger": false, "mmbm_mm_s": m,
                });
                text.push_str(&v.to_string());
                text.push('\n');
            }
        }
        if !text.is_empty() {
            out.write_all(text.as_bytes())
                .and_then(|_| out.flush())
                .map_err(|e| Error::io("<stdout>", e))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
