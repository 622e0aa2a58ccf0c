//! Cancelling long calls from outside: a [`Cancel`] token that the library's
//! long loops (rendering, series of a log, frames, simulation, trigger runs,
//! flow fields) poll between pixels, samples, batches and GPU dispatches.
//!
//! A caller runs a call under a token with [`with`]; the loops read the
//! calling thread's token with [`check`] (or capture it with [`current`] to
//! poll it from worker threads, e.g. rayon's), and once the token is
//! cancelled they stop and return [`Error::Interrupted`]. Nothing the call
//! would have returned is kept. The Python package cancels the token when a
//! signal (Ctrl-C) is pending, so a long call raises `KeyboardInterrupt`
//! within a fraction of a second instead of when it ends. Without a token
//! (the default) [`check`] never fails.

use crate::error::{Error, Result};
use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A stop request shared between a caller and the calls it runs
/// ([`with`]); clones share the request.
#[derive(Clone, Debug, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A token not yet cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every call running under this token to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Cancel::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// [`Error::Interrupted`] once cancelled, `Ok` before.
    pub fn check(&self) -> Result<()> {
        if self.is_cancelled() {
            Err(Error::Interrupted)
        } else {
            Ok(())
        }
    }
}

thread_local! {
    static CURRENT: RefCell<Option<Cancel>> = const { RefCell::new(None) };
}

/// Restores the thread's previous token when a [`with`] scope ends (also on
/// a panic).
struct Restore(Option<Cancel>);

impl Drop for Restore {
    fn drop(&mut self) {
        let prev = self.0.take();
        CURRENT.with(|c| *c.borrow_mut() = prev);
    }
}

/// Runs `f` with `token` as this thread's token: [`check`] and [`current`]
/// inside `f` see it. Scopes nest; the previous token is restored after.
pub fn with<R>(token: &Cancel, f: impl FnOnce() -> R) -> R {
    let prev = CURRENT.with(|c| c.borrow_mut().replace(token.clone()));
    let _restore = Restore(prev);
    f()
}

/// This thread's token (a fresh one, never cancelled, outside [`with`]): what
/// parallel loops capture to poll it from their worker threads.
pub fn current() -> Cancel {
    CURRENT.with(|c| c.borrow().clone()).unwrap_or_default()
}

/// [`Error::Interrupted`] when this thread's token is cancelled.
pub fn check() -> Result<()> {
    CURRENT.with(|c| c.borrow().as_ref().map_or(Ok(()), Cancel::check))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_sees_the_scope_token_only_inside_it() {
        let t = Cancel::new();
        assert!(check().is_ok());
        with(&t, || {
            assert!(check().is_ok());
            t.cancel();
            assert!(matches!(check(), Err(Error::Interrupted)));
            // Captured for another thread, it carries the request.
            let c = current();
            let seen = std::thread::spawn(move || c.is_cancelled()).join().unwrap();
            assert!(seen);
            // A nested scope with its own token, then the outer one back.
            with(&Cancel::new(), || assert!(check().is_ok()));
            assert!(check().is_err());
        });
        assert!(check().is_ok(), "the token leaked out of its scope");
        assert!(!current().is_cancelled());
    }

    #[test]
    fn the_token_is_restored_after_a_panic() {
        let t = Cancel::new();
        t.cancel();
        let r = std::panic::catch_unwind(|| with(&t, || panic!("boom")));
        assert!(r.is_err());
        assert!(check().is_ok());
    }
}
