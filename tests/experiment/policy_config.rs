//! Policies typed from deserialisation on: an experiment file's `policies`
//! and `[map] policies` are read as `PolicySpec`s (a bad entry refused while
//! the file is read, naming the key and the entry; an over-long list refused
//! by its length before any entry is parsed), they keep the text as given
//! through a save and a reload, and the map's fixed-rate grid is built from
//! numbers with the text and spec the parser gives for it.

use mmbm::trigger::{Family, PolicyFamily, PolicySpec};
use mmbm_lab::experiment::ExperimentConfig;

/// Writes `text` to `name` in `dir` and loads it.
fn load(dir: &std::path::Path, name: &str, text: &str) -> mmbm::Result<ExperimentConfig> {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    ExperimentConfig::load(&p)
}

#[test]
fn a_bad_policy_is_refused_at_load_naming_key_and_entry() {
    let d = tempfile::tempdir().unwrap();
    // Each case: the file, the key and entry named, and the position of the
    // list's `[` (line, column from 1) where the reader refused it.
    for (text, key, entry, at) in [
        (
            "policies = [\"fixed:5\", \"fixed:0\"]\n",
            "invalid policies:",
            "'fixed:0'",
            "line 1, column 12",
        ),
        (
            "policies = [ \"threshold:0.4\",\n  \"nope:1\"]\n",
            "invalid policies:",
            "'nope:1'",
            "line 1, column 12",
        ),
        // The map's list is read as typed too, lights or not: a bad entry is
        // never carried silently.
        (
            "[map]\n  policies = [\"ae:5:cap=3\"]\n",
            "invalid map.policies:",
            "'ae:5:cap=3'",
            "line 2, column 14",
        ),
    ] {
        let e = load(d.path(), "bad.toml", text).unwrap_err().to_string();
        assert!(e.contains("bad.toml: "), "{text}: {e}");
        assert!(e.contains(key) && e.contains(entry), "{text}: {e}");
        // The parser's message, as validate() gave it before.
        assert!(e.contains("invalid policy: "), "{text}: {e}");
        // Refused while the file was read (at the reader's position), not
        // afterwards by a check over strings; on one line.
        let want = format!("TOML parse error at {at}: {key}");
        assert!(e.contains(&want), "{text}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
    // An over-long list is refused by its length before any entry is parsed
    // (its entries are all bad: the length is what is named).
    let list = vec!["\"nope:1\""; 101].join(", ");
    let e = load(d.path(), "long.toml", &format!("policies = [{list}]\n"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("invalid policies: 101 entries: at most 100"),
        "{e}"
    );
    assert!(!e.contains("nope:1'"), "{e}");
}

#[test]
fn policies_keep_their_text_through_save_and_reload() {
    let d = tempfile::tempdir().unwrap();
    // Texts the parser accepts in more than one spelling: upper case,
    // spaces, a phase, a modifier with its default spelled out.
    let given = [
        "fixed:5",
        "PHASE:0.3:0.5",
        "gate:0.4:5@0.1",
        "deadline:5+exp:3:0.02",
        "ae:5:cap=10ms",
        "threshold: 0.4",
    ];
    let quoted: Vec<String> = given.iter().map(|s| format!("\"{s}\"")).collect();
    let text = format!(
        "policies = [{}]\n[map]\npolicies = [\"task:5:light=1000\", \"ae-imu:5\"]\n",
        quoted.join(", ")
    );
    let cfg = load(d.path(), "a.toml", &text).unwrap();
    // Typed: the families are known without reading the strings again.
    let fams: Vec<Family> = cfg.policies.iter().map(|p| p.family).collect();
    assert_eq!(
        fams,
        [
            Family::Fixed,
            Family::Phase,
            Family::Gate,
            Family::Deadline,
            Family::Ae,
            Family::Threshold
        ]
    );
    assert_eq!(cfg.map.policies[0].family, Family::Task);
    assert_eq!(
        cfg.map.policies[1].policy_family(),
        PolicyFamily::GyroExposure
    );
    // Display and as_str give the text as written in the file.
    let shown: Vec<String> = cfg.policies.iter().map(|p| p.to_string()).collect();
    assert_eq!(shown, given);
    // Saved and read back: the same lines of text, the same specs.
    let saved = cfg.to_toml();
    for s in given {
        assert!(saved.contains(&format!("\"{s}\"")), "{s}: {saved}");
    }
    let back = load(d.path(), "b.toml", &saved).unwrap();
    assert_eq!(back.policies, cfg.policies);
    assert_eq!(back.map.policies, cfg.map.policies);
    assert_eq!(back.to_toml(), saved);
    // A spec on its own is written as its string.
    let p: PolicySpec = "gate:0.4:5@0.1".parse().unwrap();
    assert_eq!(serde_json::to_string(&p).unwrap(), "\"gate:0.4:5@0.1\"");
    let e = serde_json::from_str::<PolicySpec>("\"gate:-1\"")
        .unwrap_err()
        .to_string();
    assert!(e.contains("'gate:-1'"), "{e}");
}

#[test]
fn the_fixed_rate_grid_is_built_as_the_parser_reads_it() {
    // The texts the map wrote and parsed back before: `fixed:{fps}` and
    // `fixed:{fps}@{t}ms`, numbers in Rust's shortest round-trip form.
    for (fps, t, text) in [
        (5.0, None, "fixed:5"),
        (2.5, Some(3.0), "fixed:2.5@3ms"),
        (5.0, Some(0.1 + 0.2), "fixed:5@0.30000000000000004ms"),
        (1000.0, Some(70.0), "fixed:1000@70ms"),
    ] {
        let built = PolicySpec::fixed(fps, t).unwrap();
        assert_eq!(built.as_str(), text);
        assert_eq!(built, PolicySpec::parse(text).unwrap(), "{text}");
        // The exposure is the string's milliseconds in seconds.
        assert_eq!(built.fixed_exposure_s, t.map(|t| t * 1e-3));
    }
    // Refused as the parser refuses them, naming the policy.
    for (fps, t) in [
        (0.0, None),
        (-5.0, Some(3.0)),
        (f64::NAN, None),
        (1000.5, None),
        (5.0, Some(0.0)),
        (5.0, Some(f64::INFINITY)),
    ] {
        let e = PolicySpec::fixed(fps, t).unwrap_err().to_string();
        assert!(e.starts_with("invalid policy: 'fixed:"), "{fps} {t:?}: {e}");
    }
}
