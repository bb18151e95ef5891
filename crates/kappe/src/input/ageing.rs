//! Linear ageing of the green material (buckling.md §6, Wolfs et al. 2018): a layer's modulus
//! grows with the time since it was printed.

use serde::{Deserialize, Serialize};

use crate::form::section::Sections;

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

/// Age of every layer (print order) at the state whose top has print index `top`, s: the print
/// time of the layers printed after it (layer length / `print_speed`).
pub fn layer_ages(sections: &Sections, print_speed: f64, top: usize) -> Vec<(i32, f64)> {
    let layers = &sections.layers;
    let mut ages = Vec::with_capacity(top + 1);
    let mut t = 0.0;
    for q in (0..=top.min(layers.len().saturating_sub(1))).rev() {
        ages.push((layers[q].id, t));
        t += layers[q].length() / print_speed;
    }
    ages.reverse();
    ages
}
