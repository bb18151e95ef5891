//! The element stresses are the form's (`crate::form::stresses`): every state's extremes come
//! with its force pass in [`crate::design_cap`].
pub(crate) use crate::form::stresses::{
    ElementStress, STRESS_REL_TOL, StressExtremes, element_stresses,
};
