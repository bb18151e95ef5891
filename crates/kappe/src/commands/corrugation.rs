//! The gain of a corrugated centre section (issue 26, docs/corrugation.md): run the smooth cap
//! and every (amplitude, wavelength) of a grid through the same pipeline ([`crate::run`]) and
//! report the governing (lowest) buckling factor per kilogram and per print minute against the
//! smooth cap of the same span, rise and length.
//!
//! A variant whose wave is impossible (a named [`DesignError`]: too short, too deep, an arch that
//! cannot be form-found in compression) is a row with its error, not the end of the study; a
//! variant that runs but fails a check (overhang, stress, buckling, the robot) is a row with
//! `ok = false` and the failing checks named.

use crate::input::design::{CorrugationShape, CorrugationSpec, Design};
use crate::input::error::DesignError;
use crate::run::{Options, Outcome, run};

/// One design of the study.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Row {
    /// a, m (0: the smooth reference).
    pub amplitude: f64,
    /// λ, m.
    pub wavelength: f64,
    /// Lowest buckling factor over the analysed states (None: no buckling analysis ran).
    pub min_blf: Option<f64>,
    /// The state where it occurs.
    pub governing_state: Option<usize>,
    /// Printed mass, kg.
    pub mass_kg: f64,
    /// Print time, s (the robot plan's when planned, else the path at print speed).
    pub print_time_s: f64,
    /// Largest layer overhang, m.
    pub max_overhang_m: f64,
    /// Largest node residual of any print state's force pass, N (the part of the load the
    /// fixed corrugated geometry does not carry by pure axial forces; docs/corrugation.md).
    pub max_residual_n: f64,
    /// Largest compressive force of any state, N (the scale of `max_residual_n`).
    pub max_force_n: f64,
    /// The design passes every check.
    pub ok: bool,
    /// The failing checks (or the error that stopped the design), `;`-separated.
    pub failures: String,
}

impl Row {
    /// min BLF per kg.
    pub fn blf_per_kg(&self) -> Option<f64> {
        self.min_blf.map(|b| b / self.mass_kg)
    }
    /// min BLF per print minute.
    pub fn blf_per_minute(&self) -> Option<f64> {
        self.min_blf.map(|b| b / (self.print_time_s / 60.0))
    }
}

/// The study: the smooth reference and one row per grid point, amplitude-major.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Study {
    /// The smooth cap (no `[cap.corrugation]`).
    pub reference: Row,
    /// The corrugated variants.
    pub rows: Vec<Row>,
}

/// The design `base` with the wave (a, λ) (shape `crown`); a = 0 removes the corrugation.
pub fn with_wave(base: &Design, amplitude: f64, wavelength: f64) -> Design {
    let mut d = base.clone();
    d.cap.corrugation = (amplitude != 0.0).then_some(CorrugationSpec {
        amplitude,
        wavelength,
        shape: CorrugationShape::Crown,
    });
    d
}

fn row_of(amplitude: f64, wavelength: f64, out: &Outcome) -> Row {
    let summary = out.summary();
    let (min_blf, governing_state) = summary
        .states
        .iter()
        .filter_map(|s| s.blf.map(|b| (b, s.index)))
        .fold((None, None), |(best, at), (b, i)| match best {
            Some(m) if m <= b => (best, at),
            _ => (Some(b), Some(i)),
        });
    let max_residual_n = out
        .cap
        .states
        .iter()
        .map(|s| s.forces.max_residual)
        .fold(0.0, f64::max);
    let max_force_n = out
        .cap
        .states
        .iter()
        .map(|s| -s.forces.max_compression_force)
        .fold(0.0, f64::max);
    let failures: Vec<String> = summary.failures.iter().map(|f| f.to_string()).collect();
    Row {
        amplitude,
        wavelength,
        min_blf,
        governing_state,
        mass_kg: summary.mass_kg,
        print_time_s: summary.print_time_s,
        max_overhang_m: summary.max_overhang_m,
        max_residual_n,
        max_force_n,
        ok: summary.ok,
        failures: failures.join("; "),
    }
}

/// Run the smooth cap of `base` and every (amplitude, wavelength) pair with `options`;
/// `on_design(done, total)` after each design. The smooth cap must run; a variant's error is
/// its row's `failures`.
pub fn study(
    base: &Design,
    amplitudes: &[f64],
    wavelengths: &[f64],
    options: &Options,
    on_design: &dyn Fn(usize, usize),
) -> Result<Study, DesignError> {
    for (field, values) in [("amplitudes", amplitudes), ("wavelengths", wavelengths)] {
        if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
            return Err(DesignError::Invalid {
                field: if field == "amplitudes" {
                    "corrugation study amplitudes"
                } else {
                    "corrugation study wavelengths"
                },
                value: format!("{values:?}"),
                allowed: "allowed: at least one finite value, m".into(),
            });
        }
    }
    let total = 1 + amplitudes.len() * wavelengths.len();
    let smooth = with_wave(base, 0.0, 1.0);
    let reference = row_of(0.0, 0.0, &run(&smooth, options, &crate::run::no_progress)?);
    on_design(1, total);
    let mut rows = Vec::with_capacity(total - 1);
    for &a in amplitudes {
        for &l in wavelengths {
            let d = with_wave(base, a, l);
            let row = match run(&d, options, &crate::run::no_progress) {
                Ok(out) => row_of(a, l, &out),
                Err(DesignError::Cancelled) => return Err(DesignError::Cancelled),
                Err(e) => Row {
                    amplitude: a,
                    wavelength: l,
                    min_blf: None,
                    governing_state: None,
                    mass_kg: f64::NAN,
                    print_time_s: f64::NAN,
                    max_overhang_m: f64::NAN,
                    max_residual_n: f64::NAN,
                    max_force_n: f64::NAN,
                    ok: false,
                    failures: format!("error: {e}"),
                },
            };
            rows.push(row);
            on_design(rows.len() + 1, total);
        }
    }
    Ok(Study { reference, rows })
}

impl Study {
    /// The row with the highest min BLF among those that pass and use at most
    /// `(1 + max_material_increase)` times the smooth cap's mass.
    pub fn best(&self, max_material_increase: f64) -> Option<&Row> {
        let limit = self.reference.mass_kg * (1.0 + max_material_increase);
        self.rows
            .iter()
            .filter(|r| r.ok && r.mass_kg <= limit)
            .filter(|r| r.min_blf.is_some())
            .max_by(|a, b| {
                a.min_blf
                    .partial_cmp(&b.min_blf)
                    .unwrap_or(std::cmp::Ordering::Equal)
            })
    }

    /// The table as CSV: one line for the smooth cap, then one per variant; ratios against the
    /// smooth cap (`blf_ratio` = min BLF / smooth min BLF, `mass_ratio`, and the per-kg and
    /// per-minute ratios).
    pub fn to_csv(&self) -> String {
        use std::fmt::Write as _;
        let mut t = String::from(
            "amplitude_m,wavelength_m,min_blf,governing_state,mass_kg,print_time_s,blf_per_kg,\
             blf_per_min,blf_ratio,mass_ratio,blf_per_kg_ratio,blf_per_min_ratio,max_overhang_m,\
             max_residual_n,max_force_n,ok,failures\n",
        );
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.6}"));
        let r0 = &self.reference;
        for r in std::iter::once(r0).chain(&self.rows) {
            let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
                (Some(a), Some(b)) if b != 0.0 => Some(a / b),
                _ => None,
            };
            let _ = writeln!(
                t,
                "{},{},{},{},{:.4},{:.1},{},{},{},{:.5},{},{},{:.6},{:.3e},{:.4},{},\"{}\"",
                r.amplitude,
                r.wavelength,
                opt(r.min_blf),
                r.governing_state.map_or(String::new(), |s| s.to_string()),
                r.mass_kg,
                r.print_time_s,
                opt(r.blf_per_kg()),
                opt(r.blf_per_minute()),
                opt(ratio(r.min_blf, r0.min_blf)),
                r.mass_kg / r0.mass_kg,
                opt(ratio(r.blf_per_kg(), r0.blf_per_kg())),
                opt(ratio(r.blf_per_minute(), r0.blf_per_minute())),
                r.max_overhang_m,
                r.max_residual_n,
                r.max_force_n,
                r.ok,
                r.failures.replace('"', "'")
            );
        }
        t
    }
}
