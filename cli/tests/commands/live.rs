//! `mmbm live`: the same decisions as the offline runner (library and CLI),
//! the policies it refuses, and its handling of bad and out-of-order input.

use crate::common;

use mmbm::io::gyro::{read_log, GyroOptions, GyroSample};
use mmbm::metric::{Method, Scene};
use mmbm::series::mmbm_series;
use mmbm::trigger::{self, CameraTiming, Event, Frame, Live};
use std::io::Write;
use std::path::Path;
use std::process::{Output, Stdio};

/// Every causal policy form, with thresholds that make each trigger often.
const CAUSAL: &[&str] = &[
    "fixed:5",
    "fixed:7@0.03",
    "threshold:0.4",
    "adaptive",
    "adaptive:0.3:3",
    "forecast:0.4",
    "forecast:0.5:0.3",
    "phase:0.4",
    "phase:0.5:0.3",
    "fixed:5+exp:2",
    "phase:0.4+exp:2:0.005",
    "gate:0.8",
    "gate:0.6:4@0.1",
    "deadline:5",
    "deadline:5:0.4",
];

fn timing(exposure: f64) -> CameraTiming {
    CameraTiming {
        delay: 0.0025,
        exposure,
        readout: 0.0125,
        min_interval: 0.2,
        ..CameraTiming::default()
    }
}

/// Live frames whose exposure ended inside the stream, as `Exposed` reports them.
fn live_frames(policy: &str, t: &[f64], m: &[f64], timing: CameraTiming) -> Vec<Frame> {
    let mut live = Live::new(trigger::parse_policy(policy).unwrap(), timing).unwrap();
    let mut out = Vec::new();
    let mut triggers = 0;
    for (&a, &b) in t.iter().zip(m) {
        for e in live.push(a, b).unwrap() {
            match e {
                Event::Trigger(k, f) => {
                    assert_eq!(k, triggers);
                    assert!(f.mmbm_exposure_mm_s.is_nan());
                    triggers += 1;
                }
                Event::Exposed(k, f) => {
                    assert_eq!(k, out.len());
                    out.push(f);
                }
            }
        }
    }
    out
}

fn assert_same_as_offline(log: &[GyroSample], exposure: f64, what: &str) {
    let m = mmbm_series(log, &Scene::thesis(), Method::default()).unwrap();
    let t: Vec<f64> = log.iter().map(|s| s.t).collect();
    for p in CAUSAL {
        let offline = trigger::run(
            log,
            &m,
            trigger::parse_policy(p).unwrap().as_mut(),
            &timing(exposure),
        )
        .unwrap();
        let live = live_frames(p, &t, &m, timing(exposure));
        assert!(!offline.is_empty(), "{what} {p}: no frames offline");
        // Bit-identical frames: trigger sample, times, means, verdicts.
        assert_eq!(live, offline, "{what} {p}");
    }
}

#[test]
fn live_equals_offline_on_a_simulated_walk() {
    let dir = tempfile::tempdir().unwrap();
    let log = read_log(&common::simulated_walk(dir.path()), GyroOptions::default()).unwrap();
    assert_same_as_offline(&log, 0.07, "simulated walk");
}

#[test]
fn live_equals_offline_on_the_real_logs() {
    for (name, exposure) in [("running_phone", 0.02), ("dashboard_car", 0.03)] {
        if let Some(p) = common::shared_log(name) {
            let log = read_log(&p, GyroOptions::default()).unwrap();
            assert_same_as_offline(&log, exposure, name);
        }
    }
}

#[test]
fn oracle_and_percentiles_are_refused() {
    for p in ["oracle:0.4", "threshold:p20", "forecast:p30"] {
        let e = Live::new(trigger::parse_policy(p).unwrap(), timing(0.07))
            .err()
            .unwrap_or_else(|| panic!("{p} accepted"));
        let msg = e.to_string();
        assert!(msg.contains(p), "{msg}");
    }
    let o = common::mmbm_cmd()
        .args(["live", "--policy", "oracle:0.4"])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("oracle"));
}

/// Runs `mmbm live` with `input` on stdin.
fn live_cli(args: &[&str], input: &[u8]) -> Output {
    let mut child = common::mmbm_cmd()
        .arg("live")
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let data = input.to_vec();
    let writer = std::thread::spawn(move || {
        // The child may stop reading early (--strict): a broken pipe is fine.
        let _ = stdin.write_all(&data);
    });
    let o = child.wait_with_output().unwrap();
    writer.join().unwrap();
    o
}

fn json_lines(o: &Output) -> Vec<serde_json::Value> {
    String::from_utf8(o.stdout.clone())
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

/// `trigger_t` of every frame of `mmbm trigger` on `log`.
fn offline_cli(log: &Path, policy: &str, exposure: &str) -> Vec<f64> {
    let o = common::mmbm_cmd()
        .args([
            "trigger",
            "--policy",
            policy,
            "--exposure",
            exposure,
            "--gyro",
        ])
        .arg(log)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut r = csv::Reader::from_reader(&o.stdout[..]);
    let col = r
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == "trigger_t")
        .unwrap();
    r.records()
        .map(|x| x.unwrap()[col].parse().unwrap())
        .collect()
}

fn triggers_of(lines: &[serde_json::Value]) -> Vec<f64> {
    lines
        .iter()
        .filter(|v| v["trigger"] == true)
        .map(|v| v["t"].as_f64().unwrap())
        .collect()
}

#[test]
fn cli_stdin_gives_the_offline_triggers() {
    let dir = tempfile::tempdir().unwrap();
    let mut logs = vec![(common::simulated_walk(dir.path()), "0.07")];
    if let Some(p) = common::shared_log("running_phone") {
        logs.push((p, "0.02"));
    }
    for (log, exposure) in &logs {
        let input = std::fs::read(log).unwrap();
        for p in CAUSAL {
            let o = live_cli(&["--policy", p, "--exposure", exposure], &input);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            let lines = json_lines(&o);
            let exposed: Vec<f64> = lines
                .iter()
                .filter(|v| v["exposed"] == true)
                .map(|v| v["trigger_t"].as_f64().unwrap())
                .collect();
            let offline = offline_cli(log, p, exposure);
            assert_eq!(exposed, offline, "{} {p}", log.display());
            // Every offline trigger was announced live when it happened.
            let live = triggers_of(&lines);
            assert_eq!(&live[..offline.len()], &offline[..], "{p}");
            assert!(live.len() <= offline.len() + 1, "{p}");
        }
    }
}

#[test]
fn json_lines_and_replay_match_csv_stdin() {
    let dir = tempfile::tempdir().unwrap();
    let walk = common::simulated_walk(dir.path());
    let log = read_log(&walk, GyroOptions::default()).unwrap();
    let mut js = String::new();
    for s in &log {
        js.push_str(&format!(
            "{{\"t\":{},\"wx\":{},\"wy\":{},\"wz\":{}}}\n",
            s.t, s.omega.x, s.omega.y, s.omega.z
        ));
    }
    let args = ["--policy", "threshold:0.4", "--policy", "fixed:5"];
    let a = live_cli(&args, &std::fs::read(&walk).unwrap());
    let b = live_cli(&args, js.as_bytes());
    let c = common::mmbm_cmd()
        .arg("live")
        .args(args)
        .args(["--speed", "0", "--replay"])
        .arg(&walk)
        .output()
        .unwrap();
    for o in [&a, &b, &c] {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    assert!(!json_lines(&a).is_empty());
    assert_eq!(json_lines(&a), json_lines(&b));
    assert_eq!(json_lines(&a), json_lines(&c));
}

#[test]
fn malformed_lines_are_skipped_or_stop_with_strict() {
    let input = "t,wx,wy,wz\n0.0,0.1,0.1,0.1\n0.01,abc,0.1,0.1\n0.02,0.1,0.1\n0.03,0.1,0.1,0.1\n";
    let o = live_cli(&["--policy", "fixed:5", "--all"], input.as_bytes());
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("<stdin>:3:wx"), "{err}");
    assert!(err.contains("<stdin>:4:"), "{err}");
    let ts: Vec<f64> = json_lines(&o)
        .iter()
        .map(|v| v["t"].as_f64().unwrap())
        .collect();
    assert_eq!(ts, vec![0.0, 0.03]);

    let o = live_cli(
        &["--policy", "fixed:5", "--all", "--strict"],
        input.as_bytes(),
    );
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("<stdin>:3:wx"), "{err}");
    assert_eq!(json_lines(&o).len(), 1, "stopped at line 3");
}

#[test]
fn time_going_backwards_is_reported_and_dropped() {
    let input = "t,wx,wy,wz\n0.0,0,0,0.1\n0.02,0,0,0.1\n0.01,0,0,0.1\n0.02,0,0,0.1\n0.03,0,0,0.1\n";
    let o = live_cli(&["--policy", "fixed:5", "--all"], input.as_bytes());
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("<stdin>:4:") && err.contains("dropped"),
        "{err}"
    );
    assert!(err.contains("<stdin>:5:"), "{err}");
    let ts: Vec<f64> = json_lines(&o)
        .iter()
        .map(|v| v["t"].as_f64().unwrap())
        .collect();
    assert_eq!(ts, vec![0.0, 0.02, 0.03]);
}

#[test]
fn random_bytes_never_crash_the_reader() {
    // A deterministic stream of junk lines between good ones.
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut input = b"t,wx,wy,wz\n".to_vec();
    for k in 0..3000 {
        if k % 3 == 0 {
            input.extend(format!("{},0.1,0.2,0.3\n", k as f64 * 0.002).bytes());
            continue;
        }
        let len = (x % 40) as usize;
        for _ in 0..len {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let b = (x % 256) as u8;
            input.push(if b == b'\n' { b'{' } else { b });
        }
        input.push(b'\n');
    }
    let o = live_cli(&["--policy", "threshold:0.4", "--all"], &input);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(json_lines(&o).len(), 1000, "every good line decided");
}

#[test]
fn udp_datagrams_are_decided() {
    let (child, sock, addr) = common::udp_live();
    sock.send_to(b"t,wx,wy,wz", &addr).unwrap();
    for k in 0..20 {
        let line = format!("{},0.1,0.2,0.3", k as f64 * 0.01);
        sock.send_to(line.as_bytes(), &addr).unwrap();
    }
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lines = json_lines(&o);
    let decisions: Vec<_> = lines
        .iter()
        .filter(|v| v.get("trigger").is_some())
        .collect();
    assert_eq!(decisions.len(), 20, "{lines:?}");
    assert_eq!(decisions[0]["trigger"], true);
    assert_eq!(decisions[19]["t"].as_f64(), Some(0.19));
}

/// Waits for `child` at most `secs` seconds (killed and failed after that).
fn wait_for(child: &mut std::process::Child, secs: f64, what: &str) -> std::process::ExitStatus {
    let start = std::time::Instant::now();
    loop {
        if let Some(st) = child.try_wait().unwrap() {
            return st;
        }
        if start.elapsed().as_secs_f64() > secs {
            let _ = child.kill();
            panic!("{what}: still running after {secs} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

fn interrupt(child: &std::process::Child) {
    let st = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
}

/// Issue 23: a wait beyond what a `Duration` holds (a tiny `--speed`, huge
/// time stamps, a huge `--idle-exit`) panicked (exit 101). It is a wait that
/// lasts until Ctrl-C, which ends it with the statistics and exit 130.
#[test]
fn endless_waits_never_panic_and_ctrl_c_ends_them() {
    let dir = tempfile::tempdir().unwrap();
    let walk = dir.path().join("walk.csv");
    std::fs::write(&walk, "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.01,0.1,0.2,0.3\n").unwrap();
    let huge = dir.path().join("huge.csv");
    std::fs::write(&huge, "t,wx,wy,wz\n0,0,0,0.1\n1.7e308,0,0,0.1\n").unwrap();
    let addr = common::free_udp_addr();
    let w = walk.to_str().unwrap();
    let h = huge.to_str().unwrap();
    let cases: Vec<Vec<&str>> = vec![
        // The slowest speed (a tinier one is refused: cli/tests/refusals/parsing.rs).
        vec!["--replay", w, "--speed", "1e-3"],
        vec!["--replay", h],
        vec!["--replay", h, "--speed", "1e-3"],
        vec!["--udp", &addr, "--idle-exit", "1e300"],
    ];
    for args in cases {
        let what = args.join(" ");
        let mut child = common::mmbm_cmd()
            .args(["live", "--policy", "fixed:5", "--all", "--stats"])
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = String::new();
        if args[0] == "--replay" {
            // The first sample is due at once.
            let mut r = std::io::BufReader::new(child.stdout.take().unwrap());
            std::io::BufRead::read_line(&mut r, &mut first).unwrap();
            assert!(first.contains("\"t\":0.0"), "{what}: {first}");
            child.stdout = None;
            std::thread::spawn(move || std::io::copy(&mut r, &mut std::io::sink()));
        }
        std::thread::sleep(std::time::Duration::from_millis(300));
        assert!(child.try_wait().unwrap().is_none(), "{what}: ended early");
        interrupt(&child);
        let st = wait_for(&mut child, 10.0, &what);
        let mut err = String::new();
        std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
        assert_eq!(st.code(), Some(130), "{what}: {err}");
        assert!(!err.contains("panicked"), "{what}: {err}");
        let samples = if args[0] == "--replay" { 1 } else { 0 };
        let stats = match samples {
            0 => "latency: no samples".to_string(),
            n => format!("over {n} samples"),
        };
        assert!(
            err.contains(&stats) && err.contains("interrupted"),
            "{what}: {err}"
        );
    }
}

/// A wait blocked on a silent stdin still ends at Ctrl-C with the statistics.
#[test]
fn ctrl_c_on_a_silent_stdin() {
    let mut child = common::mmbm_cmd()
        .args(["live", "--policy", "fixed:5", "--stats"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(b"t,wx,wy,wz\n0,0.1,0.2,0.3\n").unwrap();
    stdin.flush().unwrap();
    std::thread::sleep(std::time::Duration::from_millis(500));
    interrupt(&child);
    let st = wait_for(&mut child, 10.0, "silent stdin");
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(st.code(), Some(130), "{err}");
    assert!(err.contains("over 1 samples"), "{err}");
    assert_eq!(json_lines(&o).len(), 1);
    drop(stdin);
}

#[test]
fn bad_speed_and_idle_time_exit_2() {
    for args in [
        vec!["--replay", "x.csv", "--speed", "nan"],
        vec!["--replay", "x.csv", "--speed=-1"],
        vec!["--replay", "x.csv", "--speed", "inf"],
        vec!["--udp", "127.0.0.1:0", "--idle-exit=-1"],
        vec!["--udp", "127.0.0.1:0", "--idle-exit", "0"],
        vec!["--udp", "127.0.0.1:0", "--idle-exit", "nan"],
    ] {
        let o = common::mmbm_cmd()
            .args(["live", "--policy", "fixed:5"])
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(args[2].trim_start_matches("--").split('=').next().unwrap()),
            "{err}"
        );
    }
}

/// Issue 23: one sample whose MMBM is not finite ended the stream (exit 1);
/// it is reported and skipped like a malformed line (--strict: exit 2).
#[test]
fn a_non_finite_sample_is_skipped_like_a_malformed_line() {
    let input = "t,wx,wy,wz\n0,0,0,0.1\n0,0,0,0.1\n0.01,1.7e308,0,0\n0.02,0,0,0.1\n";
    let o = live_cli(&["--policy", "fixed:5", "--all"], input.as_bytes());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("<stdin>:4:") && err.contains("MMBM is inf"),
        "{err}"
    );
    assert!(err.contains("line skipped"), "{err}");
    let ts: Vec<f64> = json_lines(&o)
        .iter()
        .map(|v| v["t"].as_f64().unwrap())
        .collect();
    assert_eq!(ts, vec![0.0, 0.02]);
    let o = live_cli(
        &["--policy", "fixed:5", "--all", "--strict"],
        input.as_bytes(),
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("<stdin>:4:"));
    assert_eq!(json_lines(&o).len(), 1);
}

/// Issue 23: a single such datagram stopped the UDP listener.
#[test]
fn a_bad_datagram_does_not_stop_the_listener() {
    let (child, sock, addr) = common::udp_live();
    for d in [
        "t,wx,wy,wz",
        "0,0,0,0.1",
        "0.01,1.7e308,0,0",
        "0.02,0,0,0.1\n0.03,0,0,0.1",
    ] {
        sock.send_to(d.as_bytes(), &addr).unwrap();
    }
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("<udp>:3:") && err.contains("skipped"), "{err}");
    let ts: Vec<f64> = json_lines(&o)
        .iter()
        .map(|v| v["t"].as_f64().unwrap())
        .collect();
    assert_eq!(ts, vec![0.0, 0.02, 0.03]);
}

/// Issue 23: `--replay` loaded the whole log before the first decision. It
/// reads as it plays: a bad line late in the log ends the replay after the
/// decisions on the samples before it (the whole-log reader wrote none).
#[test]
fn a_replay_plays_the_log_as_it_reads_it() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("log.csv");
    let mut text = "t,wx,wy,wz\n".to_string();
    for k in 0..200 {
        text.push_str(&format!("{},0.1,0.2,0.3\n", k as f64 * 0.005));
    }
    text.push_str("1.0,x,0,0\n");
    std::fs::write(&log, text).unwrap();
    let o = common::mmbm_cmd()
        .args([
            "live", "--policy", "fixed:5", "--all", "--speed", "0", "--replay",
        ])
        .arg(&log)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains(":202:wx"), "{err}");
    let decided = json_lines(&o)
        .iter()
        .filter(|v| v.get("trigger").is_some())
        .count();
    assert_eq!(decided, 200);
}
