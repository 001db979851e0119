//! How a long job reports progress and learns that it should stop: the front end implements
//! [`Progress`] (a terminal bar, a Python signal check, an HTTP request's deadline) and the job
//! calls it between chunks of work.

use std::sync::atomic::{AtomicBool, Ordering};

/// A listener for a long job. Every method has a do-nothing default.
pub trait Progress: Sync {
    /// The job starts `total` units of work described by `what`.
    fn start(&self, _total: u64, _what: &str) {}
    /// `n` more units are done.
    fn advance(&self, _n: u64) {}
    /// Whether the job should stop at the next chunk boundary (Ctrl-C, a deadline).
    fn cancelled(&self) -> bool {
        false
    }
    /// The job is over (also after a cancellation or an error).
    fn finish(&self) {}
}

/// No reporting, never cancelled.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {}

/// A part of a larger job: it hears the whole job's cancellation but reports no progress of its
/// own (the whole job counts its parts).
#[derive(Clone, Copy)]
pub struct CancelOnly<'a>(pub &'a dyn Progress);

impl Progress for CancelOnly<'_> {
    fn cancelled(&self) -> bool {
        self.0.cancelled()
    }
}

/// A cancellation flag another thread (a signal handler) can raise.
#[derive(Debug, Default)]
pub struct CancelFlag(AtomicBool);

impl CancelFlag {
    /// A lowered flag.
    pub const fn new() -> Self {
        Self(AtomicBool::new(false))
    }

    /// Raises the flag.
    pub fn raise(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether it was raised.
    pub fn is_raised(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}
