//! How a long computation reports progress and hears a request to stop: one [`Context`] travels
//! with it, so every stage ([`crate::design_cap`], [`crate::analysis::analyze`], the run) takes
//! the same two things in the same way instead of a ladder of `_until` variants.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::input::error::DesignError;

/// Progress and cancellation of a computation, together.
#[derive(Clone, Copy)]
pub struct Context<'a> {
    on_step: &'a (dyn Fn(usize) + Sync),
    stop: &'a AtomicBool,
}

fn ignore(_: usize) {}

/// Never set: the stop flag of [`Context::default`].
static NEVER: AtomicBool = AtomicBool::new(false);

impl Default for Context<'_> {
    /// Reports nowhere, never stops.
    fn default() -> Self {
        Context {
            on_step: &ignore,
            stop: &NEVER,
        }
    }
}

impl std::fmt::Debug for Context<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Context")
            .field("stopped", &self.stopped())
            .finish_non_exhaustive()
    }
}

impl<'a> Context<'a> {
    /// `on_step(total)` is called once per step finished (from worker threads), with the number
    /// of steps of the stage; once `stop` is set the computation gives up with
    /// [`DesignError::Cancelled`] at its next check.
    pub fn new(on_step: &'a (dyn Fn(usize) + Sync), stop: &'a AtomicBool) -> Self {
        Context { on_step, stop }
    }

    /// This context with another progress callback and the same stop flag.
    pub fn reporting_to(self, on_step: &'a (dyn Fn(usize) + Sync)) -> Self {
        Context { on_step, ..self }
    }

    /// One step of `total` is finished.
    pub fn step(&self, total: usize) {
        (self.on_step)(total);
    }

    /// Whether a stop was requested.
    pub fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// [`DesignError::Cancelled`] once a stop was requested.
    ///
    /// # Errors
    /// [`DesignError::Cancelled`].
    pub fn check(&self) -> Result<(), DesignError> {
        if self.stopped() {
            Err(DesignError::Cancelled)
        } else {
            Ok(())
        }
    }

    /// The stop flag (for code that polls it directly).
    pub fn stop_flag(&self) -> &'a AtomicBool {
        self.stop
    }
}
