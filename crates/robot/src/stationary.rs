//! Printing from stations (the base stands still while the arm prints): the entry that resolves
//! the base placement, plans every station ([`crate::planner`]), cuts the programs
//! ([`crate::program`]), times the motion ([`crate::timing`]) and checks the result
//! ([`crate::check`]). The moving base's counterpart is [`crate::moving`].

use crate::error::RobotError;
use crate::frames::Iso;
use crate::plan::{CertifiedClearance, Plan};
use crate::planner::{plan_station, summarise, validate};
use crate::setup::{BasePlacement, PlanOptions, PrintLayer, RobotSetup};

/// Plan the print: resolve the base placement (fixed, or searched with stations), plan every
/// station, cut the programs, time everything ([`crate::timing`]; waits from the minimum layer
/// time) and summarise. [`plan_print`] runs [`crate::check::check_plan`] on the result and fails
/// if it does not pass.
pub fn plan_print(
    layers: &[PrintLayer],
    setup: &RobotSetup,
    opts: &PlanOptions,
) -> Result<Plan, RobotError> {
    plan_print_with_waits(layers, setup, opts, None)
}

/// [`plan_print`] with per-layer waits (e.g. from the time-dependent schedule) instead of the
/// minimum layer time.
pub fn plan_print_with_waits(
    layers: &[PrintLayer],
    setup: &RobotSetup,
    opts: &PlanOptions,
    waits: Option<&[crate::timing::LayerWait]>,
) -> Result<Plan, RobotError> {
    let ctx = validate(layers, setup, opts)?;
    let stations = match &setup.base {
        BasePlacement::Fixed { world_from_base } => {
            let w = Iso::from_mat4(world_from_base)
                .map_err(|e| RobotError::invalid("base.world_from_base", e))?;
            vec![
                plan_station(&ctx, 0, &w, 0..ctx.layers.len(), 0.0)
                    .map_err(RobotError::Unplannable)?,
            ]
        }
        BasePlacement::Search(search) => crate::base::search_stations(&ctx, search)?,
    };
    let mut plan = summarise(&ctx, stations);
    plan.parts = crate::program::split_parts(&plan)?;
    crate::timing::apply_timing(&mut plan, waits)?;
    let report = crate::check::check_plan(&plan);
    if !report.problems.is_empty() {
        return Err(RobotError::Verification(report.problems));
    }
    plan.certified = Some(CertifiedClearance::of(&report));
    Ok(plan)
}
