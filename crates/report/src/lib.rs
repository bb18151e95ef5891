//! # kappe-report
//!
//! Plots and the self-contained, offline HTML report of a Kappe design (issues 8, 14).
//!
//! The crate takes plain data, [`ReportInput`] (layers with their bead centre lines and stresses,
//! bed joints, the print path, the print states, the constraint table and an optional robot
//! animation), so it does not depend on the pipeline crates; the CLI fills it. Then
//! [`render_html`] writes one HTML file that opens from `file://` without network access:
//! three.js and OrbitControls (vendored, MIT, rebuilt by `web/build.sh`; `cargo build` never
//! runs npm), a small hand-written viewer, the scene data as a JSON island (long arrays as
//! base64 typed arrays, see `island.rs`; [`read_island`] reads a page back) and the plots as
//! inline SVG (plotters; no fonts needed at generation time). With a robot cell the page also
//! carries the UR10e collision meshes (`assets/ur10e-meshes.json`, BSD-3-Clause, 75 kB).
//!
//! The viewer (`assets/viewer.js`) has one timeline: a moment of the print shows the beads
//! printed by then (the partly printed layer included), the robot posed by the plan, the
//! analysed state of the complete layers in the side panel and a cursor in every plot. Named
//! views, fit, axis triad, scale bar, follow-the-nozzle; the state's buckling mode (scaled) and a
//! marker at each constraint's worst place (a table row goes there); colour by any quantity of
//! the island. Test hook: `window.kappeReport` (`seek`, `state`, `layers`, `robotTime`,
//! `totalTime`, `nozzle`), used by `web/e2e/report.test.mjs`.
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
//! - `robot`: per time step the joint values and the station (with a `cell` the viewer poses the
//!   UR10e meshes by the URDF chain), or the world end points of link capsules (`link_radii`).
//! - `constraints`: worst value per constraint; rows named `blf`, `sigma_min`, `sigma_max`,
//!   `overhang` also draw their limits in the plots (units `kPa`/`Pa`/`MPa`, `mm`/`m`).
//! - `timeline` (time of each path point), `cell` (stations, tool, mobile base, beams, floor),
//!   `modes` (mode 1 on the bead nodes), `worst_places`, `quantities` (more colour quantities,
//!   e.g. layer age and stiffness; each also gets a plot): `kappe::output::report_input` fills them.
//!
//! Size: three.js is 0.77 MB; the default design's page is 2.4 MB; 1008 states (ten times the
//! default) 20.3 MB (`cargo run --release -p kappe-report --example size_table`).
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
mod markup;
mod placement;
mod plots;
mod robot_summary;
mod schedule;
mod series;
mod study;

pub use demo::demo_input;
pub use error::ReportError;
pub use html::{
    ISLAND_SIGNIFICANT_DIGITS, REPORT_CSS, THREE_BUNDLE, THREE_LICENSE, UR10E_LICENSE,
    UR10E_MESHES, VIEWER_JS, escape_inline_script, render_html, scene_json,
};
pub use input::{
    BedJoint, Bound, BoxBody, Capsule, Cell, ConstraintRow, Layer, ModeShape, Parameter, Plot,
    PrintPath, PrintState, Quantity, QuantityPer, ReportInput, RobotAnimation, Series, Station,
    Timeline, Vec3, WorstPlace,
};
pub use island::read_island;
pub use markup::escape_html;
pub use placement::{PlacementShapes, StationShape, placement_shapes, placement_svg};
pub use plots::{
    CursorAxis, PLOT_SIZE, PlotFrame, PlotSpec, ReferenceLine, RenderedPlot, VerticalMarker,
    fmt_num, render_plot, render_svg, standard_plots,
};
pub use robot_summary::{ClearanceRow, RobotSummary, SlowdownRow};
pub use schedule::{PrintSchedule, ScheduleRow, StateAges, StateGoverning};
pub use study::{StudyCell, StudyColumn, StudyRow, StudyTable, render_study_html};

/// The three.js revision of the vendored bundle (`THREE.REVISION`).
pub const THREE_REVISION: &str = "187";
