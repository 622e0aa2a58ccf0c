//! Helpers shared by integration tests.

use std::path::PathBuf;

/// `../shared/data/NAME/gyro.csv` when it is beside the checkout; a missing
/// log is a failure under `MMBM_REQUIRE_DATA=1` (as in CI), else a printed skip.
pub fn shared_log(name: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data")
        .join(name)
        .join("gyro.csv");
    if p.exists() {
        return Some(p);
    }
    if std::env::var("MMBM_REQUIRE_DATA").is_ok_and(|v| v == "1") {
        panic!("MMBM_REQUIRE_DATA=1 but {} is missing", p.display());
    }
    eprintln!("SKIPPED: {} not found", p.display());
    None
}
