//! The schedule as the report shows it: the one clock of the run, which check governs every
//! state, and the layers' ages at the governing states.

/// Utilisation the report shows for a state that is a mechanism (BLF 0): larger than any
/// real one, finite so the page's JSON can carry it.
pub const MECHANISM_UTILISATION: f64 = f64::MAX;

/// The schedule, which check governs every state and the layer ages at the governing state(s),
/// for the report (issue 11). Utilisation = demand / capacity per check: BLF_min/BLF
/// (analysed states), strength and sliding (with a strength model), stress (the larger of
/// σ_min,state/σ_min and σ_max,state/σ_max) and overhang (largest |l_o| so far / l_o,max). The
/// ages are shown at the worst state of every age-dependent constraint (`blf_min`, `strength`,
/// `sliding`).
pub fn report_schedule(
    cap: &crate::form::cap::Cap,
    analysis: Option<&crate::analysis::Analysis>,
    schedule: &crate::schedule::Schedule,
) -> kappe_report::PrintSchedule {
    let layer_id = |k: usize| cap.sections.layers.get(k).map_or(k as i32, |l| l.id);
    let layers = schedule
        .layers
        .iter()
        .map(|l| kappe_report::ScheduleRow {
            layer: layer_id(l.layer),
            start: l.start_s,
            end: l.end_s,
            wait: l.wait_s,
            pause: l.relocation_s,
        })
        .collect();
    let d = &cap.design;
    let (smin_lim, smax_lim, blf_min, lo_max) = (
        d.constraints.sigma_min,
        d.constraints.sigma_max,
        d.constraints.blf_min,
        d.overhang_max(),
    );
    let ratio = |v: f64, limit: f64| {
        if limit != 0.0 {
            (v / limit).max(0.0)
        } else if v != 0.0 {
            MECHANISM_UTILISATION
        } else {
            0.0
        }
    };
    let mut states = Vec::new();
    let mut ages = Vec::new();
    if let Some(a) = analysis {
        for s in &a.states {
            let mut checks = Vec::new();
            match s.buckling {
                crate::analysis::BucklingStatus::Analysed => {
                    if let Some(f) = s.blf {
                        let u = if f > 0.0 {
                            blf_min / f
                        } else {
                            MECHANISM_UTILISATION
                        };
                        checks.push(("buckling".to_string(), u));
                    }
                }
                crate::analysis::BucklingStatus::Mechanism => {
                    checks.push(("buckling".to_string(), MECHANISM_UTILISATION));
                }
                _ => {}
            }
            if let Some(u) = s.strength_utilisation {
                checks.push(("strength".to_string(), u));
            }
            if let Some(u) = s.sliding_utilisation {
                checks.push(("sliding".to_string(), u));
            }
            let stress = ratio(s.max_compression_stress_pa.min(0.0), smin_lim.min(0.0))
                .max(ratio(s.max_tension_stress_pa.max(0.0), smax_lim.max(0.0)));
            checks.push(("stress".to_string(), stress));
            checks.push(("overhang".to_string(), ratio(s.max_overhang_m, lo_max)));
            states.push(kappe_report::StateGoverning {
                state: s.index,
                checks,
            });
        }
        for (name, why) in [
            ("blf_min", "lowest BLF"),
            ("strength", "worst strength"),
            ("sliding", "worst sliding"),
        ] {
            let Some(q) = a
                .constraints
                .iter()
                .find(|c| c.name == name)
                .and_then(|c| c.state)
            else {
                continue;
            };
            if let Some(e) = ages
                .iter_mut()
                .find(|e: &&mut kappe_report::StateAges| e.state == q)
            {
                e.why.push_str(", ");
                e.why.push_str(why);
                continue;
            }
            ages.push(kappe_report::StateAges {
                state: q,
                why: why.to_string(),
                ages: schedule
                    .ages(q + 1)
                    .into_iter()
                    .enumerate()
                    .map(|(k, t)| (layer_id(k), t))
                    .collect(),
            });
        }
    }
    kappe_report::PrintSchedule {
        source: match schedule.source {
            crate::schedule::TimeSource::RobotPlan => {
                "robot plan's clock (print moves, layer changes, dwell, station changes, waits)"
            }
            crate::schedule::TimeSource::PathLength => {
                "path length / print speed and the [schedule] waits (no robot plan)"
            }
            crate::schedule::TimeSource::LayerTime => "constant layer time",
        }
        .to_string(),
        layers,
        states,
        ages,
    }
}
