//! Issue 27, in the product: a design with `[robot.base] mode = "moving"` runs end to end,
//! its files carry the base trajectory, and a station design is unchanged.

use kappe::Design;

fn go(_: kappe::Progress) -> std::ops::ControlFlow<()> {
    std::ops::ControlFlow::Continue(())
}

/// The columns of a CSV text by header name, every cell parsed as f64.
fn csv(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|c| c.parse::<f64>().unwrap()).collect())
        .collect();
    (head, rows)
}

fn col(head: &[String], name: &str) -> usize {
    head.iter().position(|h| h == name).unwrap()
}

/// Linear interpolation of base_trajectory.csv at time t (the last sample at or before t and
/// the next one; equal times: the later sample, the base has not moved in between).
fn base_at(rows: &[Vec<f64>], t: f64) -> [f64; 3] {
    let k = rows.partition_point(|r| r[0] <= t);
    if k == 0 {
        return [rows[0][1], rows[0][2], rows[0][3]];
    }
    if k == rows.len() {
        let r = &rows[k - 1];
        return [r[1], r[2], r[3]];
    }
    let (a, b) = (&rows[k - 1], &rows[k]);
    let u = if b[0] > a[0] {
        (t - a[0]) / (b[0] - a[0])
    } else {
        1.0
    };
    [
        a[1] + u * (b[1] - a[1]),
        a[2] + u * (b[2] - a[2]),
        a[3] + u * (b[3] - a[3]),
    ]
}

/// An angle difference wrapped to (−π, π].
fn wrapped(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let w = a.rem_euclid(t);
    if w > std::f64::consts::PI { w - t } else { w }
}

#[test]
fn moving_base_default_cap_end_to_end() {
    let mut d = Design::default();
    d.robot.base = kappe_robot::BaseMode::Moving(kappe_robot::MovingBase::default());
    // The structure's analysis is not what is tested here (it is the station design's, on
    // another clock); without it the test stays at the robot's planning time.
    let options = kappe::Options {
        analysis: None,
        allow_fail: true,
        ..kappe::Options::of(&d)
    };
    let out = kappe::run(&d, &options, &go).unwrap();
    let plan = out.robot.as_ref().unwrap().as_ref().unwrap();
    // One take: one station, and the schedule has no station change.
    assert_eq!(plan.stations.len(), 1);
    let m = out.moving.as_ref().expect("a moving plan");
    assert!(m.tracking.is_ok(), "{:?}", m.tracking);
    assert!((out.print_time() - plan.total_time).abs() < 1e-9);
    // The schedule (and so every layer's age in the analysis) is the moving plan's clock, and
    // it has no station pause: each gap between layers is the wait plus the layer change, and
    // the change is a move of a few centimetres at printing speed, ≪ the 60 s a station's
    // drive and re-localisation add (`[robot.plan] station_change_time`). The station plan of
    // the same cap does pause: its largest gap is at least that long.
    assert_eq!(out.schedule.source, kappe::schedule::TimeSource::RobotPlan);
    let times = kappe_robot::layer_times(plan);
    assert_eq!(out.schedule.layers.len(), times.len());
    for (s, t) in out.schedule.layers.iter().zip(&times) {
        assert!((s.start_s - t.start).abs() < 1e-9 && (s.end_s - t.end).abs() < 1e-9);
    }
    let gap =
        |s: &kappe::schedule::Schedule| s.layers.iter().map(|l| l.relocation_s).fold(0.0, f64::max);
    let moving_gap = gap(&out.schedule);
    // The largest gap a moving plan may have: a program change (switch time, then the pump
    // primed again) and 5 s of layer change (≤ 0.25 m, the default cap's foot-to-foot hop plus
    // approach, at the 0.05 m/s print speed); a station change adds 60 s more.
    let o = &plan.options;
    let allowed = o.program.program_switch_time + o.pump.prime_dwell + 5.0;
    assert!(
        allowed < o.station_change_time && moving_gap <= allowed,
        "a pause of {moving_gap} s in the moving schedule (allowed {allowed} s)"
    );
    let n = out.schedule.layers.len();
    let ages = out.schedule.ages(n);
    for k in 0..n - 1 {
        // Consecutive layers' ages differ by the upper layer's duration and the gap below it.
        let step = ages[k] - ages[k + 1];
        let dur = out.schedule.layers[k + 1].end_s - out.schedule.layers[k + 1].start_s;
        let wait = out.schedule.layers[k].wait_s;
        assert!(
            step <= dur + wait + allowed + 1e-9,
            "layer {k}: age step {step} s"
        );
    }
    let station = kappe::robot_plan::plan_robot(&out.cap).unwrap();
    let station_schedule =
        kappe::schedule::from_robot(&kappe_robot::layer_times(&station)).unwrap();
    if station.stations.len() > 1 {
        assert!(
            gap(&station_schedule) >= station.options.station_change_time - 1e-9,
            "the station plan pauses at its seams: {} s",
            gap(&station_schedule)
        );
    }

    let files = out.files().unwrap();
    let get = |name: &str| {
        let f = files.iter().find(|f| f.name == name);
        String::from_utf8(f.unwrap_or_else(|| panic!("{name} missing")).bytes.clone()).unwrap()
    };
    let (th, trows) = csv(&get("trajectory.csv"));
    let (_, brows) = csv(&get("base_trajectory.csv"));
    let (it, ix, iy, iyaw) = (
        col(&th, "t"),
        col(&th, "base_x"),
        col(&th, "base_y"),
        col(&th, "base_yaw"),
    );
    assert!(!trows.is_empty());
    // Every row's base pose is base_trajectory.csv's at the same t: 1e-6 m and 1e-6 rad (the
    // issue's kinematic tolerance; both files print full f64 precision, so only the
    // interpolation's rounding is left). The yaw is compared modulo 2π: trajectory.csv writes
    // −π/2 where base_trajectory.csv writes 3π/2, the same heading.
    for r in &trows {
        assert_eq!(r.len(), th.len());
        let b = base_at(&brows, r[it]);
        assert!(
            (r[ix] - b[0]).abs() <= 1e-6
                && (r[iy] - b[1]).abs() <= 1e-6
                && wrapped(r[iyaw] - b[2]).abs() <= 1e-6,
            "t = {}: row {:?} vs base {:?}",
            r[it],
            [r[ix], r[iy], r[iyaw]],
            b
        );
    }
    assert!(files.iter().any(|f| f.name == "base_trajectory.json"));
    // Programs (allow_fail) are the conveyor-tracking form, indexed in programs.json.
    let script = files
        .iter()
        .find(|f| f.name.ends_with(".script"))
        .expect("a program");
    let text = String::from_utf8(script.bytes.clone()).unwrap();
    assert!(text.contains("track_conveyor_linear"));
    assert!(get("programs.json").contains("travel"));

    let s = serde_json::to_value(out.summary()).unwrap();
    let b = &s["robot"]["base_trajectory"];
    let length = b["length_m"].as_f64().unwrap();
    assert!(length > 0.1, "the base travels along the bay: {length} m");
    assert!(b["max_speed_m_s"].as_f64().unwrap() <= 0.1 + 1e-12);
    assert!(b["tracking"]["max_deviation_m"].as_f64().unwrap() > 0.0);
    assert!(b["tracking"]["at_layer"].is_i64());

    // The report's arm rides on the moving base: a base pose per animation frame, the first at
    // the plan's start pose and every one on base_trajectory.csv at the frame's time (1e-6 m,
    // as above).
    let input = out.report_input();
    let anim = input.robot.as_ref().expect("an animation");
    assert_eq!(anim.base.len(), anim.times.len());
    let start = plan.stations[0].world_from_base;
    assert!((anim.base[0][0] - start[0][3]).abs() < 1e-6);
    assert!((anim.base[0][1] - start[1][3]).abs() < 1e-6);
    for (t, p) in anim.times.iter().zip(&anim.base).step_by(97) {
        let b = base_at(&brows, *t);
        assert!(
            (p[0] - b[0]).abs() <= 1e-6 && (p[1] - b[1]).abs() <= 1e-6,
            "t = {t}: {p:?} vs {b:?}"
        );
    }
    let travelled = (anim.base.last().unwrap()[1] - anim.base[0][1]).abs();
    assert!(
        travelled > 0.1,
        "the base moves in the report: {travelled} m"
    );
}

#[test]
fn station_design_summary_has_no_moving_block() {
    let mut d = Design::default();
    d.cap.length = 0.08;
    let options = kappe::Options {
        analysis: None,
        ..kappe::Options::of(&d)
    };
    let out = kappe::run(&d, &options, &go).unwrap();
    assert!(out.moving.is_none());
    let s = serde_json::to_value(out.summary()).unwrap();
    assert!(s["robot"].get("base_trajectory").is_none());
    let files = out.files().unwrap();
    assert!(!files.iter().any(|f| f.name.starts_with("base_trajectory")));
    let (th, _) = csv(&String::from_utf8(
        files
            .iter()
            .find(|f| f.name == "trajectory.csv")
            .unwrap()
            .bytes
            .clone(),
    )
    .unwrap());
    assert!(!th.iter().any(|h| h == "base_x"));
    // The resolved design does not name the base mode: station files read and write as before.
    assert!(!toml::to_string(&d).unwrap().contains("[robot.base]"));
}

#[test]
fn moving_base_limits_are_validated_by_name() {
    let text = "[robot.base]\nmode = \"moving\"\nspeed_max = -1.0\n";
    let e = Design::from_toml_str(text).unwrap_err().to_string();
    assert!(e.contains("robot.base.speed_max"), "{e}");
    let text = "[robot.base]\nmode = \"moving\"\nlead_range = [1.0, 0.5]\n";
    let e = Design::from_toml_str(text).unwrap_err().to_string();
    assert!(e.contains("robot.base.lead_range"), "{e}");
    let text = "[robot.base]\nmode = \"moving\"\nspeed = 1.0\n";
    assert!(
        Design::from_toml_str(text).is_err(),
        "unknown fields are refused"
    );
    let d = Design::from_toml_str("[robot.base]\nmode = \"stations\"\n").unwrap();
    assert_eq!(d.robot.base, kappe_robot::BaseMode::Stations);
}

/// The 1.5 m × 4 m bay of `kappe init --kind moving` (issue 27) form-finds: its final state's
/// start layers have the factor d = φ = 0 by construction (method.md §6: the start section is
/// shaped by that state's thrust line), so `d ≥ 0` sits on its bound. With 453 centre layers
/// the thrust per unit weight is ≈ 211 and the round-off in d is ≈ 1e-11, which the old fixed
/// 1e-12 refused ("layer −95: factor d = −0.0000 … cannot carry this state"). Here the final
/// state builds and every start factor is φ to 1e-8 (the round-off bound of
/// `form::states`, ≈ 1e-8 for this bay), and an intermediate state still has d in [0, 1].
#[test]
fn long_bay_start_section_final_state_builds() {
    use kappe::form::LayerFrame;
    use kappe::form::build_state;
    use kappe::form::{ArchSpec, form_find_layer};
    use kappe::form::{EndKind, build_sections_with_end};
    let d = Design::from_toml_str(kappe::commands::templates::MOVING_TOML).unwrap();
    assert_eq!((d.cap.span, d.cap.length), (1.5, 4.0), "the issue's bay");
    let tilt = d.tilt();
    let frame = LayerFrame::new(tilt);
    let spec = ArchSpec {
        span: d.cap.span,
        rise: d.cap.rise,
        tilt,
        specific_weight: d.material.specific_weight,
        layer_width: d.print.layer_width,
        layer_height: d.print.layer_height,
        path_sampling: d.print.path_sampling,
    };
    let arch = form_find_layer(&spec).unwrap();
    let w = d.material.specific_weight * d.print.layer_width * d.print.layer_height;
    let phi = d.print.start_arch_fraction;
    assert_eq!(phi, 0.0, "the bound case: φ = 0");
    let s = build_sections_with_end(
        &arch,
        &frame,
        d.cap.length,
        d.print.layer_height,
        phi,
        |c| 0.5 * c * w,
        EndKind::StartSection,
    )
    .unwrap();
    assert!(
        s.n_centre > 400 && s.n_start > 100,
        "{} {}",
        s.n_centre,
        s.n_start
    );
    let last = s.layers.len() - 1;
    let fin = build_state(&s, &frame, phi, last).unwrap();
    let worst = fin.factors[..s.n_start]
        .iter()
        .map(|f| (f - phi).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 1e-8, "start factors off φ by {worst:e}");
    let mid = build_state(&s, &frame, phi, s.n_start + s.n_centre / 2).unwrap();
    assert!(
        mid.factors[..s.n_start]
            .iter()
            .all(|f| (-1e-8..=1.0 + 1e-8).contains(f))
    );
}
