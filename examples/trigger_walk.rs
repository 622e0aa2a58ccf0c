//! Trigger policies on a simulated walk: a seeded 60 s moderate gait at
//! 600 Hz, its MMBM series, and the thesis rule against a fixed 5 fps.
//!
//! `cargo run --release --example trigger_walk`

use mmbm::series::mmbm_series;
use mmbm::sim::{simulate, Gait, GaitConfig};
use mmbm::trigger::{parse_policy, run, summary_over, CameraTiming};
use mmbm::{Method, Scene};

fn main() -> mmbm::Result<()> {
    let duration_s = 60.0;
    let walk = simulate(&GaitConfig::preset(Gait::Moderate), duration_s, 600.0, 1)?;
    // Rotation-only MMBM of every sample (mm/s), riemann:8x6 on the thesis camera.
    let series = mmbm_series(&walk, &Scene::thesis(), Method::default())?;
    let timing = CameraTiming {
        exposure: 0.07, // s; delay 2.5 ms, readout 12.5 ms, minimum interval 0.2 s
        ..CameraTiming::default()
    };
    for spec in ["fixed:5", "threshold:0.4"] {
        let mut policy = parse_policy(spec)?;
        let frames = run(&walk, &series, policy.as_mut(), &timing)?;
        let s = summary_over(&frames, duration_s);
        println!(
            "{spec:>13}: {} frames, {:.2} fps, mean exposure MMBM {:.3} mm/s, mean blur {:.2} px",
            s.kept,
            s.effective_fps,
            s.mean_mm_s,
            s.mean_blur_mm / timing.pitch_mm
        );
    }
    Ok(())
}
