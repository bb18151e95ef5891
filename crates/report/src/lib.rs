//! # kappe-report
//!
//! Plots and the self-contained, offline HTML report of a Kappe design (issue 8).
//!
//! The crate takes plain data, [`ReportInput`] (layers with their bead centre lines and stresses,
//! bed joints, the print path, the print states, the constraint table and an optional robot
//! animation), so it does not depend on the pipeline crates; the CLI fills it. Then
//! [`render_html`] writes one HTML file that opens from `file://` without network access:
//! three.js and OrbitControls (vendored, MIT, rebuilt by `web/build.sh`; `cargo build` never
//! runs npm), a small hand-written viewer, the scene data as a JSON island and the plots as
//! inline SVG (plotters; no fonts needed at generation time).
//!
//! [`render_study_html`] writes the design-study table of `kappe study` ([`StudyTable`]).
//!
//! ## Filling [`ReportInput`] from the pipeline (for `kappe design`)
//! - `layers`: in print order (−K..−1, 0..N−1); `nodes` = the layer's bead centre line,
//!   `segment_stress` = final-state σ of its deviation edges (N/(lw·lh), compression < 0),
//!   `plane_normal` = n = (0, cos am, sin am), `overhang` = l_o of method.md §3 (`None` for the
//!   first layer).
//! - `bed_joints`: the trail edges between layers, `layer` = id of the upper layer.
//! - `states`: one per analysed state; `layers_printed` counts layers in print order;
//!   `segment_stress` (optional) = that state's σ of the printed layers' segments, concatenated.
//! - `print_path`: nozzle tip points, tool axis (−n), layer id per point.
//! - `robot`: per time step the joint values and the world end points of each link capsule
//!   (from FK), `link_radii` one per capsule; any number of capsules.
//! - `constraints`: worst value per constraint; rows named `blf`, `sigma_min`, `sigma_max`,
//!   `overhang` also draw their limits in the plots (units `kPa`/`Pa`/`MPa`, `mm`/`m`).
//!
//! Write the string with the CLI's `write_file_atomic`; the page is about 0.8 MB plus the data
//! (8 MB at the default design's size with per-state stresses, see `examples/size_table.rs`).
//!
//! ```
//! use kappe_report::{demo_input, render_html};
//! let html = render_html(&demo_input()).unwrap();
//! assert!(html.contains("id=\"kappe-data\""));
//! ```

mod demo;
mod error;
mod html;
mod input;
mod island;
mod plots;
mod study;

pub use demo::demo_input;
pub use error::ReportError;
pub use html::{
    ISLAND_SIGNIFICANT_DIGITS, REPORT_CSS, THREE_BUNDLE, THREE_LICENSE, UR10E_LICENSE,
    UR10E_MESHES, VIEWER_JS, escape_html, escape_inline_script, render_html, scene_json,
};
pub use input::{
    BedJoint, Bound, BoxBody, Capsule, Cell, ConstraintRow, Layer, ModeShape, Parameter, Plot,
    PrintPath, PrintState, Quantity, QuantityPer, ReportInput, RobotAnimation, Series, Station,
    Timeline, Vec3, WorstPlace,
};
pub use island::read_island;
pub use plots::{
    CursorAxis, PLOT_SIZE, PlotFrame, PlotSpec, ReferenceLine, RenderedPlot, VerticalMarker,
    fmt_num, render_plot, render_svg, standard_plots,
};
pub use study::{StudyCell, StudyColumn, StudyRow, StudyTable, render_study_html};

/// The three.js revision of the vendored bundle (`THREE.REVISION`).
pub const THREE_REVISION: &str = "187";
