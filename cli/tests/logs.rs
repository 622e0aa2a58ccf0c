//! The log readers and what reads logs: gcsv, MCAP, camera telemetry, the phone walk-through, `mmbm sync`, random bytes fed to every reader.
//!
//! One test binary of the subject; each module is one former test file
//! (`cli/tests/logs/NAME.rs`, see docs/testing.md).

mod common;
#[path = "logs/gcsv_fixture.rs"]
mod gcsv_fixture;
#[path = "logs/telemetry_fixture.rs"]
mod telemetry_fixture;

#[path = "logs/fuzz_readers.rs"]
mod fuzz_readers;
#[path = "logs/gcsv.rs"]
mod gcsv;
#[path = "logs/gcsv_gyroflow.rs"]
mod gcsv_gyroflow;
#[path = "logs/mcap.rs"]
mod mcap;
#[path = "logs/phone.rs"]
mod phone;
#[path = "logs/sync.rs"]
mod sync;
#[path = "logs/telemetry.rs"]
mod telemetry;
