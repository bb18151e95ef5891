//! `[analysis.ageing]`, the older form of `[material.time]` (linear E only): read as that time
//! model ([`crate::input::Design::time_model`]), so a layer's age always comes from the run's
//! one clock ([`crate::schedule`]).

use serde::{Deserialize, Serialize};

/// Linear ageing of the green material (buckling.md §6, Wolfs et al. 2018):
/// `E(t) = min(E₀ + Ė·t, E_max)`, t the age of a layer at the state (time since it was printed).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ageing {
    /// E₀: modulus of a freshly printed layer, Pa (> 0).
    pub initial_modulus: f64,
    /// Ė: growth rate, Pa/s (≥ 0).
    pub rate: f64,
    /// E_max: cap on the modulus, Pa (optional).
    #[serde(default)]
    pub max_modulus: Option<f64>,
}

impl Ageing {
    /// E at age `t` seconds.
    pub fn modulus(&self, t: f64) -> f64 {
        let e = self.initial_modulus + self.rate * t.max(0.0);
        match self.max_modulus {
            Some(m) => e.min(m),
            None => e,
        }
    }
}
