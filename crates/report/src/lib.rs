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
//! ```
//! use kappe_report::{demo_input, render_html};
//! let html = render_html(&demo_input()).unwrap();
//! assert!(html.contains("id=\"kappe-data\""));
//! ```

mod demo;
mod error;
mod html;
mod input;
mod plots;
mod study;

pub use demo::demo_input;
pub use error::ReportError;
pub use html::{
    REPORT_CSS, THREE_BUNDLE, THREE_LICENSE, VIEWER_JS, escape_html, escape_inline_script,
    render_html, scene_json,
};
pub use input::{
    BedJoint, Bound, ConstraintRow, Layer, Parameter, Plot, PrintPath, PrintState, ReportInput,
    RobotAnimation, Series, Vec3,
};
pub use plots::{PLOT_SIZE, PlotSpec, ReferenceLine, fmt_num, render_svg, standard_plots};
pub use study::{StudyCell, StudyColumn, StudyRow, StudyTable, render_study_html};

/// The three.js revision of the vendored bundle (`THREE.REVISION`).
pub const THREE_REVISION: &str = "187";
