//! Long calls that Ctrl-C can stop.
//!
//! Python runs its signal handlers (SIGINT's raises `KeyboardInterrupt`)
//! only between bytecodes of the main thread: while a native call runs with
//! the GIL released, a Ctrl-C is only noted. [`interruptible`] therefore runs
//! the library call on a worker thread, under an [`mmbm::cancel::Cancel`]
//! token, while the calling thread waits for it in slices of [`POLL`] and
//! runs the pending handlers in between (`PyErr_CheckSignals`). When a
//! handler raises, the token is cancelled, the library's loops stop at their
//! next check (between pixels, samples, batches and GPU dispatches), the
//! partial result is dropped and the handler's exception (`KeyboardInterrupt`)
//! is raised: the call returns nothing and writes nothing.
//!
//! Python checks signals only on the main thread: a call from another
//! Python thread runs to its end, as in Python itself.

use mmbm::cancel::{self, Cancel};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::sync::{mpsc, Mutex};
use std::time::Duration;

/// How often a waiting call runs Python's pending signal handlers.
pub const POLL: Duration = Duration::from_millis(20);

/// Stack of the worker thread, bytes (the main thread's usual 8 MiB: the
/// library's calls run there as they would on the caller's thread).
const STACK: usize = 8 << 20;

/// Most rows of a CPU metric call run without a worker thread: starting one
/// costs about 0.1 ms, more than such a call takes (at most about 2 ms).
pub const SMALL_ROWS: usize = 256;

/// [`interruptible`] when `long`; otherwise `f` runs on this thread with the
/// GIL released (a call too short to need stopping, spared the thread).
pub fn interruptible_if<T, F>(
    py: Python<'_>,
    err: fn(mmbm::Error) -> PyErr,
    long: bool,
    f: F,
) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> mmbm::Result<T> + Send,
{
    if long {
        interruptible(py, err, f)
    } else {
        py.detach(f).map_err(err)
    }
}

/// Runs `f` with the GIL released, raising the pending signal handlers'
/// exception (`KeyboardInterrupt`) as soon as one is raised, within about
/// [`POLL`] plus the library's check interval. A library error becomes what
/// `err` makes of it.
pub fn interruptible<T, F>(py: Python<'_>, err: fn(mmbm::Error) -> PyErr, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> mmbm::Result<T> + Send,
{
    let token = Cancel::new();
    let (done_tx, done_rx) = mpsc::channel::<()>();
    // Shared with the closures that wait with the GIL released (a receiver
    // alone is not `Sync`).
    let done_rx = Mutex::new(done_rx);
    std::thread::scope(|s| {
        let worker = std::thread::Builder::new()
            .name("mmbm-call".into())
            .stack_size(STACK)
            .spawn_scoped(s, || {
                let r = cancel::with(&token, f);
                // The receiver may be gone (never: the scope waits); a
                // panic drops the sender instead, which also ends the wait.
                let _ = done_tx.send(());
                r
            })
            .map_err(|e| PyRuntimeError::new_err(format!("cannot start a worker thread: {e}")))?;
        loop {
            let finished = py.detach(|| match done_rx.lock() {
                Ok(rx) => !matches!(rx.recv_timeout(POLL), Err(mpsc::RecvTimeoutError::Timeout)),
                // Never poisoned (nothing panics while holding it): just join.
                Err(_) => true,
            });
            if finished {
                break;
            }
            if let Err(e) = py.check_signals() {
                token.cancel();
                // The loops stop at their next check: wait for them, so
                // nothing outlives the call, and drop what they made.
                let _ = py.detach(move || worker.join());
                return Err(e);
            }
        }
        match py.detach(move || worker.join()) {
            Ok(r) => r.map_err(err),
            Err(panic) => std::panic::resume_unwind(panic),
        }
    })
}
