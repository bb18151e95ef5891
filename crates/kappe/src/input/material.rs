//! The green-state material: stiffness and strength that grow with the age of a layer
//! (`[material.time]`, green-state.md §2).
//!
//! A layer's **age** t is the time since it was completed (the top layer of a state has age 0).
//! Every property P (Young's modulus E, uniaxial compressive strength f_c, or the Mohr–Coulomb
//! cohesion c and friction angle φ) follows one law:
//! - `constant`: P(t) = P₀ (the default; the analysis is then exactly the one without a time
//!   model);
//! - `linear` (Wolfs, Bos & Salet 2018, Cement and Concrete Research 106:103–116):
//!   P(t) = P₀ + Ṗ·t;
//! - `exponential`, accelerating (the form of Perrot et al. 2016, Materials and Structures
//!   49:1213–1220, for the structuration of the yield stress):
//!   P(t) = P₀ + Ṗ·t_c·(e^{t/t_c} − 1). Ṗ is the initial rate; t_c → ∞ gives the linear law.
//!
//! Each property may be capped (`*_max`). ν is constant.
//!
//! **Strength.** Mohr–Coulomb with cohesion c and friction angle φ; the uniaxial compressive
//! strength is f_c = 2c·cos φ / (1 − sin φ). A model given by f_c alone takes φ from
//! `friction_angle_deg` (default 0°, i.e. Tresca, c = f_c/2). Why Mohr–Coulomb rather than
//! Drucker–Prager: (1) the bed-joint sliding check |τ| ≤ c + σ_n·tan φ uses the same two
//! parameters, so one calibrated pair serves both checks; (2) Wolfs 2018 measured exactly these
//! parameters (unconfined compression and shear box); (3) on the membrane (plane) stress state
//! of a shell, Mohr–Coulomb reproduces the uniaxial strength f_c exactly for every φ, whereas a
//! Drucker–Prager cone must choose which Mohr–Coulomb corner it matches and then misses the
//! others by up to a factor (1 + sin φ)/(1 − sin φ) in uniaxial tension vs compression.
//!
//! **Presets** (values with their sources in `docs/green-state.md`):
//! - `wolfs2018`: printable concrete, E = 0.0781 + 0.0012·t MPa, f_c = 5.984 + 0.147·t kPa
//!   (t in minutes), i.e. E₀ = 78.1 kPa, Ė = 20 Pa/s, f₀ = 5984 Pa, ḟ = 2.45 Pa/s; use it with
//!   ν = 0.3 and γ = 2070·9.81 = 20306.7 N/m³. The paper's cohesion and friction angle could not
//!   be read, so the preset is Tresca (φ = 0, c = f_c/2).
//! - `earth`: the cap paper's earth (γ = 23044 N/m³): E = 10 MPa and f_c = 20 kPa as the
//!   constant defaults of the design; **no rates** (none are public for the paper's mix; the
//!   paper calibrates from prototypes; `kappe calibrate` fits them from buildability prints).
//!
//! Fields given next to a preset override the preset's values.

use serde::{Deserialize, Serialize};

use crate::input::error::DesignError;

/// How a property changes with age.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeLaw {
    /// P(t) = P₀.
    #[default]
    Constant,
    /// P(t) = P₀ + Ṗ·t (Wolfs 2018).
    Linear,
    /// P(t) = P₀ + Ṗ·t_c·(e^{t/t_c} − 1) (accelerating; Ṗ is the initial rate).
    Exponential,
}

/// A named, sourced parameter set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// Wolfs, Bos & Salet 2018 printable concrete (linear).
    Wolfs2018,
    /// The cap paper's earth: today's constant E and strength, rates to be calibrated.
    Earth,
}

/// The `[material.time]` table as written in a file: every field optional; a preset fills the
/// fields not given.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeModelSpec {
    /// A named parameter set (fields given here override it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<Preset>,
    /// The law: `constant`, `linear` or `exponential`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<TimeLaw>,
    /// E₀, Pa (default: `[material] youngs_modulus`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f64>,
    /// Ė, Pa/s (initial rate for `exponential`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub youngs_modulus_rate: Option<f64>,
    /// Cap on E, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub youngs_modulus_max: Option<f64>,
    /// f_c at age 0 (uniaxial compressive strength), Pa. Give this or `cohesion`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compressive_strength: Option<f64>,
    /// ḟ_c, Pa/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compressive_strength_rate: Option<f64>,
    /// Cap on f_c, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compressive_strength_max: Option<f64>,
    /// Mohr–Coulomb cohesion c at age 0, Pa (needs `friction_angle_deg`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cohesion: Option<f64>,
    /// ċ, Pa/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cohesion_rate: Option<f64>,
    /// Cap on c, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cohesion_max: Option<f64>,
    /// Friction angle φ at age 0, degrees (default 0 with `compressive_strength`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_angle_deg: Option<f64>,
    /// φ̇, degrees/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_angle_rate: Option<f64>,
    /// Cap on φ, degrees (at most 89°).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_angle_max_deg: Option<f64>,
    /// t_c of the exponential law, s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_constant: Option<f64>,
}

/// One age-dependent property: P₀, Ṗ and an optional cap.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Property {
    /// Value at age 0.
    pub initial: f64,
    /// Rate per second (initial rate for the exponential law).
    pub rate: f64,
    /// Cap (None: unbounded).
    pub max: Option<f64>,
}

impl Property {
    /// A property that does not change.
    pub fn constant(v: f64) -> Self {
        Property {
            initial: v,
            rate: 0.0,
            max: None,
        }
    }
}

/// How the strength is given.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Strength {
    /// Uniaxial compressive strength f_c(t) with a constant friction angle φ (degrees);
    /// c = f_c·(1 − sin φ)/(2 cos φ).
    Uniaxial {
        /// f_c, Pa.
        compressive_strength: Property,
        /// φ, degrees.
        friction_angle_deg: f64,
    },
    /// Mohr–Coulomb c(t), φ(t).
    MohrCoulomb {
        /// c, Pa.
        cohesion: Property,
        /// φ, degrees.
        friction_angle_deg: Property,
    },
}

/// The resolved time model: every number known and checked.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TimeModel {
    /// The law of every property.
    pub law: TimeLaw,
    /// t_c of the exponential law, s (unused otherwise).
    pub time_constant: f64,
    /// E, Pa.
    pub youngs_modulus: Property,
    /// Strength (None: no strength or sliding check).
    pub strength: Option<Strength>,
}

/// Mohr–Coulomb parameters at one age.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MohrCoulomb {
    /// Cohesion c, Pa.
    pub cohesion: f64,
    /// Friction angle φ, radians.
    pub friction_angle: f64,
}

impl MohrCoulomb {
    /// Uniaxial compressive strength 2c·cos φ / (1 − sin φ), Pa.
    pub fn compressive_strength(&self) -> f64 {
        let (s, c) = self.friction_angle.sin_cos();
        2.0 * self.cohesion * c / (1.0 - s)
    }

    /// Utilisation of a plane (membrane) stress state with in-plane principal stresses
    /// `s1 ≥ s2` (tension positive; the third principal stress is 0): the Mohr–Coulomb
    /// criterion (σ_max − σ_min)/2 + (σ_max + σ_min)/2·sin φ ≤ c·cos φ written as
    /// left side / (c·cos φ). Uniaxial compression −f_c gives exactly 1.
    pub fn utilisation(&self, s1: f64, s2: f64) -> f64 {
        let hi = s1.max(s2).max(0.0);
        let lo = s1.min(s2).min(0.0);
        let (sn, cs) = self.friction_angle.sin_cos();
        let demand = 0.5 * (hi - lo) + 0.5 * (hi + lo) * sn;
        let capacity = self.cohesion * cs;
        if capacity > 0.0 {
            demand / capacity
        } else if demand > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    }

    /// Utilisation of a joint with shear τ (magnitude) and normal stress σ_n (tension
    /// positive): |τ| / (c + (−σ_n)·tan φ). A joint in tension beyond c/tan φ has no capacity.
    pub fn sliding_utilisation(&self, tau: f64, sigma_n: f64) -> f64 {
        let capacity = self.cohesion - sigma_n * self.friction_angle.tan();
        let tau = tau.abs();
        if capacity > 0.0 {
            tau / capacity
        } else if tau > 0.0 || sigma_n > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    }
}

impl TimeModel {
    /// The constant model: E everywhere, no strength check.
    pub fn constant(youngs_modulus: f64) -> Self {
        TimeModel {
            law: TimeLaw::Constant,
            time_constant: f64::INFINITY,
            youngs_modulus: Property::constant(youngs_modulus),
            strength: None,
        }
    }

    /// The Wolfs 2018 printable concrete (see the module docs).
    pub fn wolfs_2018() -> Self {
        TimeModel {
            law: TimeLaw::Linear,
            time_constant: f64::INFINITY,
            youngs_modulus: Property {
                initial: 78.1e3,
                rate: 1.2e3 / 60.0,
                max: None,
            },
            strength: Some(Strength::Uniaxial {
                compressive_strength: Property {
                    initial: 5984.0,
                    rate: 147.0 / 60.0,
                    max: None,
                },
                friction_angle_deg: 0.0,
            }),
        }
    }

    /// Whether every property is the same at every age.
    pub fn is_constant(&self) -> bool {
        self.law == TimeLaw::Constant
    }

    fn value(&self, p: &Property, t: f64) -> f64 {
        let t = t.max(0.0);
        let v = match self.law {
            TimeLaw::Constant => p.initial,
            TimeLaw::Linear => p.initial + p.rate * t,
            TimeLaw::Exponential => {
                let tc = self.time_constant;
                p.initial + p.rate * tc * (t / tc).exp_m1()
            }
        };
        match p.max {
            Some(m) => v.min(m),
            None => v,
        }
    }

    /// E at age `t` s, Pa.
    pub fn modulus(&self, t: f64) -> f64 {
        self.value(&self.youngs_modulus, t)
    }

    /// Mohr–Coulomb parameters at age `t` s (None: no strength model).
    pub fn mohr_coulomb(&self, t: f64) -> Option<MohrCoulomb> {
        match self.strength? {
            Strength::Uniaxial {
                compressive_strength,
                friction_angle_deg,
            } => {
                let fc = self.value(&compressive_strength, t);
                let phi = friction_angle_deg.to_radians();
                let (s, c) = phi.sin_cos();
                Some(MohrCoulomb {
                    cohesion: fc * (1.0 - s) / (2.0 * c),
                    friction_angle: phi,
                })
            }
            Strength::MohrCoulomb {
                cohesion,
                friction_angle_deg,
            } => Some(MohrCoulomb {
                cohesion: self.value(&cohesion, t),
                friction_angle: self.value(&friction_angle_deg, t).min(89.0).to_radians(),
            }),
        }
    }

    /// Uniaxial compressive strength at age `t`, Pa (None: no strength model).
    pub fn compressive_strength(&self, t: f64) -> Option<f64> {
        self.mohr_coulomb(t).map(|m| m.compressive_strength())
    }
}

impl TimeModelSpec {
    /// The parameters of a preset as a spec.
    pub fn of_preset(p: Preset) -> TimeModelSpec {
        match p {
            Preset::Wolfs2018 => TimeModelSpec {
                model: Some(TimeLaw::Linear),
                youngs_modulus: Some(78.1e3),
                youngs_modulus_rate: Some(1.2e3 / 60.0),
                compressive_strength: Some(5984.0),
                compressive_strength_rate: Some(147.0 / 60.0),
                friction_angle_deg: Some(0.0),
                ..Default::default()
            },
            Preset::Earth => TimeModelSpec {
                model: Some(TimeLaw::Constant),
                youngs_modulus: Some(10.0e6),
                youngs_modulus_rate: Some(0.0),
                compressive_strength: Some(20.0e3),
                compressive_strength_rate: Some(0.0),
                friction_angle_deg: Some(0.0),
                ..Default::default()
            },
        }
    }

    /// This spec with the fields it leaves open taken from its preset (if any).
    pub fn with_preset(&self) -> TimeModelSpec {
        let Some(p) = self.preset else {
            return self.clone();
        };
        let base = TimeModelSpec::of_preset(p);
        let pick = |a: Option<f64>, b: Option<f64>| a.or(b);
        // Strength given one way overrides the preset's other way.
        let own_cohesion = self.cohesion.is_some();
        let own_fc = self.compressive_strength.is_some();
        let (fc, fc_rate) = if own_cohesion {
            (None, None)
        } else {
            (
                pick(self.compressive_strength, base.compressive_strength),
                pick(
                    self.compressive_strength_rate,
                    base.compressive_strength_rate,
                ),
            )
        };
        let (c, c_rate) = if own_fc {
            (None, None)
        } else {
            (
                pick(self.cohesion, base.cohesion),
                pick(self.cohesion_rate, base.cohesion_rate),
            )
        };
        TimeModelSpec {
            preset: Some(p),
            model: self.model.or(base.model),
            youngs_modulus: pick(self.youngs_modulus, base.youngs_modulus),
            youngs_modulus_rate: pick(self.youngs_modulus_rate, base.youngs_modulus_rate),
            youngs_modulus_max: pick(self.youngs_modulus_max, base.youngs_modulus_max),
            compressive_strength: fc,
            compressive_strength_rate: fc_rate,
            compressive_strength_max: pick(
                self.compressive_strength_max,
                base.compressive_strength_max,
            ),
            cohesion: c,
            cohesion_rate: c_rate,
            cohesion_max: pick(self.cohesion_max, base.cohesion_max),
            friction_angle_deg: if own_cohesion {
                self.friction_angle_deg
            } else {
                pick(self.friction_angle_deg, base.friction_angle_deg)
            },
            friction_angle_rate: pick(self.friction_angle_rate, base.friction_angle_rate),
            friction_angle_max_deg: pick(self.friction_angle_max_deg, base.friction_angle_max_deg),
            time_constant: pick(self.time_constant, base.time_constant),
        }
    }

    /// Resolve and check the model. `default_modulus` is `[material] youngs_modulus`, used when
    /// the table gives no E₀. `prefix` names the table in errors (`material.time`).
    pub fn resolve(&self, default_modulus: f64) -> Result<TimeModel, DesignError> {
        let s = self.with_preset();
        let law = s.model.unwrap_or(TimeLaw::Constant);
        let time_constant = match (law, s.time_constant) {
            (TimeLaw::Exponential, None) => {
                return Err(invalid(
                    "material.time.time_constant",
                    "missing".into(),
                    "the exponential law needs time_constant = t_c > 0 s",
                ));
            }
            (TimeLaw::Exponential, Some(tc)) => {
                positive("material.time.time_constant", tc)?;
                tc
            }
            _ => f64::INFINITY,
        };
        let e0 = s.youngs_modulus.unwrap_or(default_modulus);
        positive("material.time.youngs_modulus", e0)?;
        let youngs_modulus = property(
            "material.time.youngs_modulus_rate",
            "material.time.youngs_modulus_max",
            e0,
            s.youngs_modulus_rate,
            s.youngs_modulus_max,
        )?;
        let strength = match (s.compressive_strength, s.cohesion) {
            (Some(_), Some(_)) => {
                return Err(invalid(
                    "material.time.cohesion",
                    "given together with compressive_strength".into(),
                    "give the strength either as compressive_strength (uniaxial, with an optional \
                     constant friction_angle_deg) or as cohesion + friction_angle_deg (Mohr–Coulomb)",
                ));
            }
            (Some(fc), None) => {
                positive("material.time.compressive_strength", fc)?;
                let phi = s.friction_angle_deg.unwrap_or(0.0);
                angle("material.time.friction_angle_deg", phi)?;
                if s.friction_angle_rate.is_some_and(|r| r != 0.0) {
                    return Err(invalid(
                        "material.time.friction_angle_rate",
                        format!("{:?}", s.friction_angle_rate),
                        "a friction angle that changes with age needs the Mohr–Coulomb form \
                         (cohesion + friction_angle_deg)",
                    ));
                }
                no_orphan("material.time.cohesion_rate", s.cohesion_rate)?;
                Some(Strength::Uniaxial {
                    compressive_strength: property(
                        "material.time.compressive_strength_rate",
                        "material.time.compressive_strength_max",
                        fc,
                        s.compressive_strength_rate,
                        s.compressive_strength_max,
                    )?,
                    friction_angle_deg: phi,
                })
            }
            (None, Some(c)) => {
                positive("material.time.cohesion", c)?;
                let Some(phi) = s.friction_angle_deg else {
                    return Err(invalid(
                        "material.time.friction_angle_deg",
                        "missing".into(),
                        "a Mohr–Coulomb strength (cohesion) needs friction_angle_deg, \
                         0 ≤ φ < 89°",
                    ));
                };
                angle("material.time.friction_angle_deg", phi)?;
                no_orphan(
                    "material.time.compressive_strength_rate",
                    s.compressive_strength_rate,
                )?;
                let friction = property(
                    "material.time.friction_angle_rate",
                    "material.time.friction_angle_max_deg",
                    phi,
                    s.friction_angle_rate,
                    s.friction_angle_max_deg,
                )?;
                if let Some(m) = friction.max {
                    angle("material.time.friction_angle_max_deg", m)?;
                }
                Some(Strength::MohrCoulomb {
                    cohesion: property(
                        "material.time.cohesion_rate",
                        "material.time.cohesion_max",
                        c,
                        s.cohesion_rate,
                        s.cohesion_max,
                    )?,
                    friction_angle_deg: friction,
                })
            }
            (None, None) => {
                no_orphan(
                    "material.time.compressive_strength_rate",
                    s.compressive_strength_rate,
                )?;
                no_orphan("material.time.cohesion_rate", s.cohesion_rate)?;
                no_orphan("material.time.friction_angle_deg", s.friction_angle_deg)?;
                None
            }
        };
        Ok(TimeModel {
            law,
            time_constant,
            youngs_modulus,
            strength,
        })
    }
}

fn invalid(field: &'static str, value: String, allowed: &str) -> DesignError {
    DesignError::Invalid {
        field,
        value,
        allowed: format!("allowed: {allowed}"),
    }
}

fn positive(field: &'static str, v: f64) -> Result<(), DesignError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(invalid(field, v.to_string(), "a finite value > 0"))
    }
}

fn angle(field: &'static str, v: f64) -> Result<(), DesignError> {
    if v.is_finite() && (0.0..89.0).contains(&v) {
        Ok(())
    } else {
        Err(invalid(field, v.to_string(), "0 ≤ φ < 89 degrees"))
    }
}

fn no_orphan(field: &'static str, v: Option<f64>) -> Result<(), DesignError> {
    match v {
        Some(x) => Err(invalid(
            field,
            x.to_string(),
            "only together with the value at age 0 it is the rate of \
             (compressive_strength, cohesion, friction_angle_deg with cohesion)",
        )),
        None => Ok(()),
    }
}

fn property(
    rate_field: &'static str,
    max_field: &'static str,
    initial: f64,
    rate: Option<f64>,
    max: Option<f64>,
) -> Result<Property, DesignError> {
    let rate = rate.unwrap_or(0.0);
    if !(rate.is_finite() && rate >= 0.0) {
        return Err(invalid(
            rate_field,
            rate.to_string(),
            "a finite rate ≥ 0 per second (green material does not soften with age here)",
        ));
    }
    if let Some(m) = max
        && !(m.is_finite() && m >= initial)
    {
        return Err(invalid(
            max_field,
            m.to_string(),
            &format!("a finite cap ≥ the value at age 0 ({initial})"),
        ));
    }
    Ok(Property { initial, rate, max })
}
