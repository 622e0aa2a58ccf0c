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

/// Where long library jobs (an experiment's renders, a dataset's items)
/// report how far they are, like [`log`] for messages: an application installs
/// one with [`set_progress`] (the `mmbm` command draws progress bars); without
/// one, progress goes nowhere.
pub trait Progress: Send + Sync {
    /// Starts a job of `total` steps; `what` names the steps ("frames",
    /// "items"). The returned task is ended when it is dropped.
    fn start(&self, what: &str, total: u64) -> Box<dyn ProgressTask>;
}

/// One running job of a [`Progress`] (shared by the threads that do its steps).
pub trait ProgressTask: Send + Sync {
    /// Says what the job does now (e.g. the walk and policy of a frame).
    fn message(&self, msg: &str);
    /// Counts `n` more steps done.
    fn advance(&self, n: u64);
}

struct Nowhere;

impl ProgressTask for Nowhere {
    fn message(&self, _: &str) {}
    fn advance(&self, _: u64) {}
}

static PROGRESS: std::sync::OnceLock<Box<dyn Progress>> = std::sync::OnceLock::new();

/// Installs where progress goes (once per process; later calls are ignored
/// and return false).
pub fn set_progress(p: Box<dyn Progress>) -> bool {
    PROGRESS.set(p).is_ok()
}

/// Starts a job's progress: reported to the installed [`Progress`] when
/// `show` is true and one is installed, else nowhere.
#[doc(hidden)]
pub fn progress(show: bool, what: &str, total: u64) -> Box<dyn ProgressTask> {
    match PROGRESS.get() {
        Some(p) if show => p.start(what, total),
        _ => Box::new(Nowhere),
    }
}
