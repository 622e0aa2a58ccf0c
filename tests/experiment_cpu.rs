//! Without a GPU adapter the experiment still runs: the renderer falls back
//! to its CPU twin (announced on stderr) and the quiver uses the CPU flow
//! twin. The adapter filter below matches nothing, so this test needs no GPU
//! and behaves the same on machines with one.

use mmbm_lab::experiment::{self, ExperimentConfig};

#[test]
fn experiment_without_adapter_uses_cpu_twins() {
    // Set before anything touches the GPU context (one test in this binary).
    // This test is about the fallback itself, so CI's "no silent fallback"
    // rule (MMBM_REQUIRE_GPU=1) is lifted for it alone.
    std::env::set_var("MMBM_ADAPTER", "no-such-adapter-for-this-test");
    std::env::remove_var("MMBM_REQUIRE_GPU");
    assert!(mmbm::gpu::gpu().is_err());
    let d = tempfile::tempdir().unwrap();
    let cfg = ExperimentConfig {
        duration_s: Some(2.0),
        policies: vec!["fixed:5".into()],
        resolution: [160, 120],
        quality: "8:2.0".into(),
        max_frames_per_policy: 2,
        start_distance_m: 2.5,
        ..ExperimentConfig::default()
    };
    let o = experiment::run(&cfg, d.path(), false).unwrap();
    assert_eq!(o.rendered, 2);
    assert!(d.path().join("quiver_moderate.png").exists());
    let csv = std::fs::read_to_string(d.path().join("frames.csv")).unwrap();
    assert!(
        csv.lines()
            .skip(1)
            .filter(|l| l.split(',').nth(2).is_some_and(|b| !b.is_empty()))
            .count()
            == 2
    );
}
