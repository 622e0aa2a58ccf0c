//! The real gyro logs of `../shared/data` (when present beside the checkout;
//! required when `MMBM_REQUIRE_DATA=1`, as in CI): they parse, and their MMBM
//! matches the figures printed in `../shared/data/README.md` (computed
//! independently of this project: thesis camera, 8x6 grid, mm/s).

use crate::common;

use mmbm::io::gyro::{read_log, GyroOptions};
use mmbm::metric::{Evaluator, Method, Scene};
use std::path::PathBuf;

fn data(name: &str) -> Option<PathBuf> {
    common::shared_log(name)
}

fn median_and_max(name: &str) -> Option<(f64, f64, usize)> {
    let p = data(name)?;
    let log = read_log(&p, GyroOptions::default()).unwrap();
    let s = Scene::thesis();
    let ev = Evaluator::new(&s.camera, Method::default()).unwrap();
    let mut m: Vec<f64> = log
        .iter()
        .map(|x| ev.mean_speed(&s.flow_poly(&mmbm::Twist::new(x.omega, glam::DVec3::ZERO))))
        .collect();
    m.sort_by(f64::total_cmp);
    Some((m[m.len() / 2], *m.last().unwrap(), m.len()))
}

#[test]
fn running_phone_matches_data_readme() {
    if let Some((median, max, n)) = median_and_max("running_phone") {
        assert!(n > 1500, "{n} samples");
        assert!((median - 2.19).abs() < 0.01, "median {median}");
        assert!((max - 8.87).abs() < 0.01, "max {max}");
    }
}

#[test]
fn dashboard_car_matches_data_readme() {
    if let Some((median, max, n)) = median_and_max("dashboard_car") {
        assert!(n > 20000, "{n} samples");
        assert!((median - 0.22).abs() < 0.01, "median {median}");
        assert!((max - 3.28).abs() < 0.01, "max {max}");
    }
}
