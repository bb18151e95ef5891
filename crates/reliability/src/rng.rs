//! Random draws from ChaCha8 used by the samplers.
//!
//! Standard normal numbers come from the inverse transform z = Φ⁻¹(v) of one open-interval
//! uniform v per number: each normal takes exactly one 64-bit word, so the position of every
//! sample in the stream is fixed (no rejection), which keeps batch splitting exact.

use crate::stdnormal;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::Rng;

/// A uniform number in the open interval (0, 1): (k + ½)/2⁵³ with k the top 53 bits of a word.
pub(crate) fn open01(rng: &mut ChaCha8Rng) -> f64 {
    ((rng.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
}

/// A standard normal number, Φ⁻¹ of an open uniform.
pub(crate) fn std_normal(rng: &mut ChaCha8Rng) -> f64 {
    stdnormal::inv_cdf(open01(rng))
}
