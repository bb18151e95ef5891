//! The stopwatch of the solver statistics: `std::time::Instant`, except on
//! `wasm32-unknown-unknown` (the designer in the browser), where `std` has no clock and
//! `Instant::now` panics; there every elapsed time reads zero (the statistics are informative
//! only, nothing is decided on them).

#[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
pub use std::time::Instant;

/// A stopwatch that never runs (wasm32-unknown-unknown has no clock in `std`).
#[cfg(all(target_arch = "wasm32", target_os = "unknown"))]
#[derive(Debug, Clone, Copy)]
pub struct Instant;

#[cfg(all(target_arch = "wasm32", target_os = "unknown"))]
impl Instant {
    /// Now (no clock: a token).
    pub fn now() -> Instant {
        Instant
    }

    /// Zero.
    pub fn elapsed(&self) -> std::time::Duration {
        std::time::Duration::ZERO
    }
}
