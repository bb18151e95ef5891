//! # kappe: the 3D-printed cap ceiling
//!
//! The method of the paper (`cap-ceiling-paper.txt`) made precise in `method.md`:
//! a design spec ([`Design`]) → the layer arch form-found with constrained CEM ([`arch`]) →
//! the centre and start sections ([`section`]) → the network of every print state ([`states`]),
//! its forces from CEM's fixed-geometry force pass → the print path ([`path`]) and the bead mesh
//! ([`mesh`]).

pub mod analysis;
pub mod arch;
pub mod buildability;
pub mod calibrate;
pub mod ceiling;
pub mod design_loop;
pub mod ends;
pub mod error;
pub mod evaluate;
pub mod export;
pub mod forces;
pub mod frame;
pub mod green;
pub mod material;
pub mod mesh;
pub mod output;
pub mod path;
pub mod pipeline;
pub mod print_calibration;
pub mod report_input;
pub mod robot_plan;
pub mod schedule;
pub mod section;
pub mod shell;
pub mod spec;
pub mod states;
pub mod study;
pub mod templates;
pub mod verdict;
pub mod wait_search;
pub mod window;

/// The analysis under its old name (`kappe::constraints`), for code written before the split;
/// use [`analysis`].
#[doc(hidden)]
pub use analysis as constraints;
pub use error::DesignError;
pub use evaluate::{Options, Outcome, Progress, Stage, evaluate, no_progress, run};
pub use pipeline::{Cap, StateSummary, design_cap};
pub use spec::Design;
