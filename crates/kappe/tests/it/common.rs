//! Helpers shared by the test modules.

use kappe::Cap;
use kappe::analysis::{AnalysisOptions, CapGreen, StateBuckling, state_buckling, state_material};
use kappe::form::State;

/// The buckling of `state` (print index `top` of `cap`) as one state outside the analysis
/// solves it: the material aged by the cap's own schedule, the mesh error estimated from the
/// 2×2 split at most, a cold start.
pub fn single_state_buckling(
    cap: &Cap,
    state: &State,
    options: &AnalysisOptions,
    top: usize,
) -> StateBuckling {
    let green = CapGreen::new(cap).expect("the cap's own ages");
    state_buckling(
        state,
        &state_material(cap, options, top, Some(&green)),
        &options.with_split_at_most(2),
        &Default::default(),
    )
    .expect("the state buckles")
    .buckling
}
