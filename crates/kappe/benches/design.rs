//! `cargo bench -p kappe`: the default cap through the whole pipeline, and its stages.

use kappe::form::{ArchSpec, form_find_layer};
use kappe::{Design, design_cap};

fn main() {
    divan::main();
}

/// Everything: layer form-finding, sections, all 113 states with their force passes, path, mesh.
#[divan::bench(sample_count = 20)]
fn default_design_all_states() -> kappe::Cap {
    design_cap(
        divan::black_box(&Design::default()),
        kappe::Context::default(),
    )
    .unwrap()
}

/// Layer form-finding alone (constrained CEM inside the self-weight fixed point).
#[divan::bench(sample_count = 50)]
fn layer_form_finding() -> kappe::form::Arch {
    let d = Design::default();
    let spec = ArchSpec {
        span: d.cap.span,
        rise: d.cap.rise,
        tilt: d.tilt(),
        specific_weight: d.material.specific_weight,
        layer_width: d.print.layer_width,
        layer_height: d.print.layer_height,
        path_sampling: d.print.path_sampling,
    };
    form_find_layer(divan::black_box(&spec)).unwrap()
}
