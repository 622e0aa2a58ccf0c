//! The small experiment configuration the map's tests share: one 2-s
//! moderate walk per seed (seeds 1 and 2), the half board before the poster,
//! the `fast` preset, no sweep, the camera's sensor at 20,000 e-/s, and a
//! `[map]` of the given lights, policies and hindsight grid.

use mmbm::camera::{CameraFile, Noise};
use mmbm_lab::experiment::{ExperimentConfig, MapSection};

/// The small configuration with the map's `lights` (e-/s), `policies` and
/// hindsight `grid_ms`.
pub fn config(lights: &[f64], policies: &[&str], grid_ms: &[f64]) -> ExperimentConfig {
    ExperimentConfig {
        walks: vec!["moderate".into()],
        duration_s: Some(2.0),
        policies: vec!["fixed:5".parse().unwrap()],
        quality: "fast".into(),
        sweep_exposures_s: Vec::new(),
        background: "poster".into(),
        camera: CameraFile {
            noise: Some(Noise {
                seed: 1,
                ..Noise::at_light(20_000.0)
            }),
            ..Default::default()
        },
        map: MapSection {
            lights_e_per_s: lights.to_vec(),
            boards: vec!["blobs:0.5".into()],
            seeds: vec![1, 2],
            policies: policies.iter().map(|p| p.parse().unwrap()).collect(),
            grid_ms: grid_ms.to_vec(),
            ..MapSection::default()
        },
        ..ExperimentConfig::default()
    }
}
