//! The metric and its inputs (library): the real logs, Gyroflow's lens model, the fast gyro reader, the image metrics' code.
//!
//! One test binary of the subject; each module is one former test file
//! (`tests/metric/NAME.rs`, see docs/testing.md).

mod common;

#[path = "metric/assess_code.rs"]
mod assess_code;
#[path = "metric/gyro_fast.rs"]
mod gyro_fast;
#[path = "metric/lens_gyroflow.rs"]
mod lens_gyroflow;
#[path = "metric/real_logs.rs"]
mod real_logs;
