//! The library's diagnostics (warnings such as a gap in a gyro log, a skipped
//! line of a live stream, the CPU twin standing in for a missing GPU) go
//! through the [`log`] facade, never straight to stderr: an application
//! chooses where they go. [`log_to_stderr`] is the choice of the `mmbm`
//! command and the Python package: each message on its own line, as written.

use log::{Level, LevelFilter, Log, Metadata, Record};

struct Stderr;

impl Log for Stderr {
    fn enabled(&self, m: &Metadata) -> bool {
        m.level() <= Level::Info
    }
    fn log(&self, r: &Record) {
        if self.enabled(r.metadata()) && r.target().starts_with("mmbm") {
            eprintln!("{}", r.args());
        }
    }
    fn flush(&self) {}
}

static STDERR: Stderr = Stderr;

/// Sends the library's messages (info and above) to stderr, one line each,
/// unless a logger is already installed (then that one keeps them).
pub fn log_to_stderr() {
    if log::set_logger(&STDERR).is_ok() {
        log::set_max_level(LevelFilter::Info);
    }
}
