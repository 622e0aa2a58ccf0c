//! Helpers shared by the benchmarks in `benches/` (`cargo bench --bench
//! NAME`): the timing loop, deterministic rotations and the entry point.
//! Times are printed, never asserted.

use mmbm::error::Result;
use mmbm::Twist;
use std::process::ExitCode;
use std::time::Instant;

/// Runs a benchmark; an error is printed as the CLI prints it (exit 1).
pub fn main(bench: fn() -> Result<()>) -> ExitCode {
    match bench() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Runs `f` repeatedly for about `secs` seconds, returning seconds per call.
#[allow(dead_code)] // not every benchmark times this way
pub fn time_per_call(secs: f64, mut f: impl FnMut()) -> f64 {
    f();
    let mut n = 1u64;
    let t0 = Instant::now();
    loop {
        for _ in 0..n {
            f();
        }
        let el = t0.elapsed().as_secs_f64();
        if el > secs {
            let total: u64 = (1..=n).filter(|k| k.is_power_of_two()).sum();
            return el / total as f64;
        }
        n *= 2;
    }
}

/// `n` deterministic pseudo-random rotations (LCG): up to 1 rad/s about x
/// and y, 0.3 rad/s about z.
#[allow(dead_code)] // used by the metric and camera benchmarks only
pub fn twists(n: usize) -> Vec<Twist> {
    let mut s = 1u64;
    (0..n)
        .map(|_| {
            let mut r = || {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
            };
            Twist::rotation(r(), r(), r() * 0.3)
        })
        .collect()
}
