use kappe::arch::{ArchSpec, Catenary, form_find_layer};
use kappe::frame::LayerFrame;
use kappe::section::build_sections;
use kappe::states::build_state;
fn main() {
    let d = kappe::Design::default();
    let spec = ArchSpec {
        span: d.cap.span,
        rise: d.cap.rise,
        tilt: d.tilt(),
        specific_weight: d.material.specific_weight,
        layer_width: d.print.layer_width,
        layer_height: d.print.layer_height,
        path_sampling: d.print.path_sampling,
    };
    let t = std::time::Instant::now();
    let arch = form_find_layer(&spec).unwrap();
    println!(
        "arch in {:?}: segs {} s {} mu {} its {} obj {:e}",
        t.elapsed(),
        arch.segments(),
        arch.segment_length,
        arch.crown_force,
        arch.weight_iterations,
        arch.objective
    );
    let cat = Catenary::new(spec.span, spec.rise, spec.tilt, spec.specific_weight);
    let a = d.print.layer_width * d.print.layer_height;
    let nc = arch.segments() / 2;
    println!(
        "crown stress {} vs {} ; spring {} vs {}",
        arch.segment_forces[nc] / a,
        cat.crown_stress,
        arch.segment_forces[0] / a,
        cat.springing_stress
    );
    let frame = LayerFrame::new(spec.tilt);
    let maxd = arch
        .points
        .iter()
        .map(|p| cat.distance_to(p, spec.span, &frame))
        .fold(0.0, f64::max);
    println!("max dist to catenary {maxd}");
    println!(
        "feet {:?} {:?}",
        arch.points[0],
        arch.points[arch.points.len() - 1]
    );
    let w = d.material.specific_weight * a;
    let sec = build_sections(
        &arch,
        &frame,
        d.cap.length,
        d.print.layer_height,
        0.0,
        |l| 0.5 * w * l,
    )
    .unwrap();
    println!(
        "N {} K {} back {:?}",
        sec.n_centre, sec.n_start, sec.translations[sec.n_start]
    );
    let t = std::time::Instant::now();
    let mut dmin: f64 = 1.0;
    let mut dmax: f64 = 0.0;
    for top in 0..sec.layers.len() {
        let st = build_state(&sec, &frame, 0.0, top).unwrap();
        for &f in &st.factors {
            if f < 1.0 - 1e-12 || true {
                dmin = dmin.min(f);
                dmax = dmax.max(f);
            }
        }
        if top == sec.layers.len() - 1 {
            println!(
                "final nodes {} trails {} devs {}",
                st.network.nodes.len(),
                st.network.trails.len(),
                st.network.deviation_edges.len()
            );
        }
    }
    println!("states in {:?}, d in [{dmin}, {dmax}]", t.elapsed());
    let ov = kappe::analysis::layer_overhangs(&sec, &frame);
    println!(
        "overhang min {} max {}",
        ov.iter().cloned().fold(f64::INFINITY, f64::min),
        ov.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
    );
}
