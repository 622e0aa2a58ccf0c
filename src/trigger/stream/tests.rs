use super::*;
use crate::metric::{Method, Scene};
use crate::trigger::{parse_policy, CameraTiming};
use glam::DVec3;
use std::cell::Cell;

fn stream(policies: &[&str], opts: StreamOptions, control: StreamControl) -> Stream {
    let timing = CameraTiming {
        exposure: 0.07,
        ..CameraTiming::default()
    };
    let runs = policies
        .iter()
        .map(|p| Live::new(parse_policy(p).unwrap(), timing).unwrap())
        .collect();
    let series = SeriesOptions {
        scene: Scene::thesis(),
        method: Method::default(),
        use_velocity: false,
    };
    Stream::new(runs, series, opts, control).unwrap()
}

fn sample(t: f64, wx: f64) -> GyroSample {
    GyroSample {
        t,
        omega: DVec3::new(wx, 0.1, 0.2),
        velocity: None,
        depth: None,
    }
}

fn ts(out: &[u8]) -> Vec<f64> {
    String::from_utf8(out.to_vec())
        .unwrap()
        .lines()
        .map(|l| {
            serde_json::from_str::<serde_json::Value>(l).unwrap()["t"]
                .as_f64()
                .unwrap()
        })
        .collect()
}

const ALL: StreamOptions = StreamOptions {
    all: true,
    strict: false,
    stats: false,
};

/// Counts the samples taken from the iterator at each write.
struct Probe<'a> {
    pulled: &'a Cell<usize>,
    at_write: Vec<usize>,
}

impl Write for Probe<'_> {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.at_write.push(self.pulled.get());
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn a_replay_takes_each_sample_when_it_is_played() {
    let pulled = Cell::new(0);
    let samples = (0..500).map(|k| {
        pulled.set(pulled.get() + 1);
        Ok(sample(k as f64 * 0.002, 0.3))
    });
    let mut probe = Probe {
        pulled: &pulled,
        at_write: Vec::new(),
    };
    let mut s = stream(&["fixed:5"], ALL, StreamControl::default());
    let o = s.replay(samples, "log", 0.0, &mut probe).unwrap();
    assert!(matches!(o.end, StreamEnd::Eof));
    assert_eq!(o.samples, 500);
    // Sample k's decisions are written before sample k + 1 is read: the
    // log is never held whole.
    assert_eq!(probe.at_write, (1..=500).collect::<Vec<_>>());
}

#[test]
fn a_replay_error_ends_it_after_the_samples_before() {
    let samples = (0..5).map(|k| match k {
        3 => Err(Error::invalid("log", "bad line")),
        _ => Ok(sample(k as f64 * 0.01, 0.3)),
    });
    let mut out = Vec::new();
    let mut s = stream(&["fixed:5"], ALL, StreamControl::default());
    let e = s.replay(samples, "log", 0.0, &mut out).unwrap_err();
    assert!(e.to_string().contains("bad line"), "{e}");
    assert_eq!(ts(&out), vec![0.0, 0.01, 0.02]);
}

#[test]
fn a_non_finite_sample_is_skipped_or_ends_a_strict_stream() {
    let input = "t,wx,wy,wz\n0,0,0,0.1\n0.01,1.7e308,0,0\n0.02,0,0,0.1\n";
    let mut out = Vec::new();
    let mut s = stream(&["fixed:5"], ALL, StreamControl::default());
    let o = s
        .lines(
            &mut input.as_bytes(),
            GyroOptions::default(),
            "<in>",
            &mut out,
        )
        .unwrap();
    assert!(matches!(o.end, StreamEnd::Eof));
    assert_eq!((o.samples, ts(&out)), (2, vec![0.0, 0.02]));

    let mut out = Vec::new();
    let strict = StreamOptions {
        strict: true,
        ..ALL
    };
    let mut s = stream(&["fixed:5"], strict, StreamControl::default());
    let o = s
        .lines(
            &mut input.as_bytes(),
            GyroOptions::default(),
            "<in>",
            &mut out,
        )
        .unwrap();
    match o.end {
        StreamEnd::Strict(e) => {
            let e = e.to_string();
            assert!(e.contains("<in>:3:") && e.contains("MMBM is inf"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(ts(&out), vec![0.0]);

    // The same in a replay: skipped, named by its sample number.
    let mut out = Vec::new();
    let mut s = stream(&["fixed:5"], strict, StreamControl::default());
    let log = [sample(0.0, 0.3), sample(0.01, 1.7e308), sample(0.02, 0.3)];
    let o = s.replay(log.map(Ok), "log", 0.0, &mut out).unwrap();
    match o.end {
        StreamEnd::Strict(e) => assert!(e.to_string().contains("log: sample 2"), "{e}"),
        other => panic!("{other:?}"),
    }
    let mut out = Vec::new();
    let mut s = stream(&["fixed:5"], ALL, StreamControl::default());
    let o = s.replay(log.map(Ok), "log", 0.0, &mut out).unwrap();
    assert_eq!((o.samples, ts(&out)), (2, vec![0.0, 0.02]));
}

#[test]
fn stop_ends_an_endless_replay_wait_with_the_statistics() {
    let control = StreamControl::default();
    let opts = StreamOptions { stats: true, ..ALL };
    let mut s = stream(&["threshold:0.4"], opts, control.clone());
    // The second sample is due in 10 s (0.01 s at the slowest speed).
    let log = [sample(0.0, 0.3), sample(0.01, 0.3)];
    let mut out = Vec::new();
    let o = std::thread::scope(|scope| {
        let c = control.clone();
        scope.spawn(move || {
            while !c.is_running() {
                std::thread::sleep(Duration::from_millis(1));
            }
            std::thread::sleep(Duration::from_millis(100));
            c.stop();
            assert!(c.wait_ended(Duration::from_secs(10)));
        });
        s.replay(
            log.map(Ok),
            "log",
            crate::limits::MIN_REPLAY_SPEED,
            &mut out,
        )
        .unwrap()
    });
    assert!(matches!(o.end, StreamEnd::Stopped));
    assert_eq!(o.samples, 1);
    assert_eq!(o.latency.map(|l| l.len()), Some(1));
    assert!(!control.is_running());
    assert!(!control.wait_ended(Duration::ZERO), "nothing running");
    // A stopped control stops the next stream at once.
    let mut s = stream(&["threshold:0.4"], ALL, control);
    let o = s
        .lines(
            &mut "t,wx,wy,wz\n0,0,0,0\n".as_bytes(),
            GyroOptions::default(),
            "<in>",
            &mut out,
        )
        .unwrap();
    assert!(matches!(o.end, StreamEnd::Stopped));
    assert_eq!(o.samples, 0);
}

#[test]
fn replay_speed_and_idle_time_are_checked() {
    let mut s = stream(&["fixed:5"], ALL, StreamControl::default());
    let mut out = Vec::new();
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        let e = s
            .replay([Ok(sample(0.0, 0.1))], "log", bad, &mut out)
            .unwrap_err();
        assert!(e.to_string().contains("replay speed"), "{e}");
    }
    for bad in [0.0, -1.0, f64::NAN] {
        let e = s
            .udp("127.0.0.1:0", Some(bad), GyroOptions::default(), &mut out)
            .unwrap_err();
        assert!(e.to_string().contains("idle"), "{e}");
    }
    // A huge idle time is a wait that never ends, not an overflow.
    let control = StreamControl::default();
    let mut s = stream(&["fixed:5"], ALL, control.clone());
    control.stop();
    let o = s
        .udp("127.0.0.1:0", Some(1e300), GyroOptions::default(), &mut out)
        .unwrap();
    assert!(matches!(o.end, StreamEnd::Stopped));
    // And a tiny one ends at the first quiet poll.
    let mut s = stream(&["fixed:5"], ALL, StreamControl::default());
    let o = s
        .udp(
            "127.0.0.1:0",
            Some(1e-300),
            GyroOptions::default(),
            &mut out,
        )
        .unwrap();
    assert!(matches!(o.end, StreamEnd::Idle));
    assert!(out.is_empty());
}

/// An input that sends two samples, then one endless line (digits, never a
/// `\n`), 4 kB per read; the `stop_after`-th read of the line asks `control`
/// to stop.
struct EndlessLine {
    head: &'static [u8],
    reads: usize,
    stop_after: usize,
    control: StreamControl,
    chunk: [u8; 4096],
}

impl std::io::Read for EndlessLine {
    fn read(&mut self, _: &mut [u8]) -> std::io::Result<usize> {
        unreachable!("read through BufRead")
    }
}

impl BufRead for EndlessLine {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        if !self.head.is_empty() {
            return Ok(self.head);
        }
        self.reads += 1;
        if self.reads == self.stop_after {
            self.control.stop();
        }
        // A line that never ends (bounded here only to fail, not hang, if
        // the stop is missed: 4 GB would take minutes).
        if self.reads > 1_000_000 {
            return Ok(b"\n");
        }
        Ok(&self.chunk)
    }
    fn consume(&mut self, n: usize) {
        if !self.head.is_empty() {
            self.head = &self.head[n..];
        }
    }
}

/// Issue #23: Ctrl-C during an endless stdin line (no `\n`) was seen only
/// when the line ended. The line reader now returns at the stop request,
/// within one chunk of input.
#[test]
fn a_stop_is_seen_within_an_endless_line() {
    let control = StreamControl::default();
    let mut input = EndlessLine {
        head: b"t,wx,wy,wz\n0,0,0,0.1\n0.01,0,0,0.1\n",
        reads: 0,
        stop_after: 100,
        control: control.clone(),
        chunk: [b'7'; 4096],
    };
    let mut out = Vec::new();
    let mut s = stream(&["fixed:5"], ALL, control);
    let o = s
        .lines(&mut input, GyroOptions::default(), "<in>", &mut out)
        .unwrap();
    assert!(matches!(o.end, StreamEnd::Stopped), "{:?}", o.end);
    assert_eq!((o.samples, ts(&out)), (2, vec![0.0, 0.01]));
    // Seen at the read after the stop request, not a megabyte later.
    assert_eq!(input.reads, 100);
}
