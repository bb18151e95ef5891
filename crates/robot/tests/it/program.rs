//! Issue 13 acceptance, checked from the written files alone: `trajectory.csv` (joint speeds and
//! accelerations from its rows and times, FK from its joints against the targets, tool speed
//! against the design speed), the program files (lint, target limit, pump switched on once per
//! station), resume, and bad input.

use kappe_robot::frames::Iso;
use kappe_robot::setup::{DigitalOutput, PauseMode};
use kappe_robot::synthetic::cap_path;
use kappe_robot::*;

/// 16 layers of 12 points from a fixed base (as in `plan.rs`), ≤ 50 targets per program.
fn small() -> (Vec<PrintLayer>, RobotSetup, PlanOptions) {
    let layers = cap_path(0.8, 0.2, 25.0, 0.008, 16, 12);
    let setup = kappe_robot::synthetic::fixed_base_setup();
    let opts = PlanOptions {
        program: ProgramOptions {
            max_moves_per_program: 50,
            ..Default::default()
        },
        ..PlanOptions::default()
    };
    (layers, setup, opts)
}

/// Standard-DH forward kinematics written out here (robot.md §1.1 table), independent of the
/// crate's: `T = Π Rz(θi)·Tz(di)·Tx(ai)·Rx(αi)`, row-major 4×4.
fn fk(q: &[f64; 6]) -> [[f64; 4]; 4] {
    let d = [0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655];
    let a = [0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0];
    let h = std::f64::consts::FRAC_PI_2;
    let alpha = [h, 0.0, 0.0, h, -h, 0.0];
    let mut t = [[0.0; 4]; 4];
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for i in 0..6 {
        let (st, ct) = q[i].sin_cos();
        let (sa, ca) = alpha[i].sin_cos();
        let m = [
            [ct, -st * ca, st * sa, a[i] * ct],
            [st, ct * ca, -ct * sa, a[i] * st],
            [0.0, sa, ca, d[i]],
            [0.0, 0.0, 0.0, 1.0],
        ];
        t = mul(&t, &m);
    }
    t
}

fn mul(a: &[[f64; 4]; 4], b: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let mut c = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            c[i][j] = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

struct Row {
    station: usize,
    layer: i64,
    index: usize,
    t: f64,
    q: [f64; 6],
    v_tool: f64,
    flow: f64,
}

fn rows(plan: &Plan) -> Vec<Row> {
    let mut csv = Vec::new();
    write_trajectory_csv(plan, &mut csv).unwrap();
    let text = String::from_utf8(csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "station,layer,index,t,q1,q2,q3,q4,q5,q6,v_tool,flow"
    );
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            Row {
                station: f[0].parse().unwrap(),
                layer: f[1].parse().unwrap(),
                index: f[2].parse().unwrap(),
                t: f[3].parse().unwrap(),
                q: std::array::from_fn(|j| f[4 + j].parse().unwrap()),
                v_tool: f[10].parse().unwrap(),
                flow: f[11].parse().unwrap(),
            }
        })
        .collect()
}

/// Check a plan from its `trajectory.csv` rows alone (see the module docs); returns the number
/// of print moves whose speed was checked against the design speed and the number inside
/// reported slowdowns.
fn check_rows(plan: &Plan, layers: &[PrintLayer], opts: &PlanOptions, amax: f64) -> (usize, usize) {
    let rows = rows(plan);
    // UR10e: 120 °/s joints 1–2, 180 °/s joints 3–6, used up to speed_fraction.
    let vmax: [f64; 6] = [120.0, 120.0, 180.0, 180.0, 180.0, 180.0].map(|d: f64| d.to_radians());
    let mut slowed = 0;
    let target = |layer: i64, index: usize| {
        layers
            .iter()
            .find(|l| l.layer == layer)
            .and_then(|l| l.points.iter().find(|p| p.index == index))
            .unwrap()
    };
    let base = plan.stations[0].world_from_base;
    let tool = plan.flange_from_tcp;
    let slow = |layer: i64, index: usize| {
        plan.slowdowns
            .iter()
            .any(|s| (layer, index) >= s.from && (layer, index) <= s.to)
    };
    let mut vel: Vec<(f64, [f64; 6])> = Vec::new();
    let (mut max_pos_err, mut checked_speed) = (0.0f64, 0);
    for (k, r) in rows.iter().enumerate() {
        // FK from the joints: on the path.csv target within 1e-6 m (acceptance).
        let w = mul(&mul(&base, &fk(&r.q)), &tool);
        let p = target(r.layer, r.index);
        let err = (0..3)
            .map(|i| (w[i][3] - p.position[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        max_pos_err = max_pos_err.max(err);
        // Tool axis: the TCP z column against the target axis, 1e-6 rad.
        let cos: f64 = (0..3).map(|i| w[i][2] * p.axis[i]).sum();
        assert!(cos.clamp(-1.0, 1.0).acos() <= 1e-6);
        if k == 0 || rows[k - 1].station != r.station {
            continue;
        }
        let a = &rows[k - 1];
        let dt = r.t - a.t;
        assert!(dt > 0.0, "time must increase at row {k}");
        let v: [f64; 6] = std::array::from_fn(|j| (r.q[j] - a.q[j]) / dt);
        for j in 0..6 {
            // 1e-9: relative slack for the division.
            assert!(
                v[j].abs() <= opts.speed_fraction * vmax[j] * (1.0 + 1e-9),
                "joint {} at {} rad/s, row {k}",
                j + 1,
                v[j]
            );
        }
        if let Some((dt0, v0)) = vel.last()
            && rows[k - 2].station == r.station
        {
            let tau = 0.5 * (dt0 + dt);
            for j in 0..6 {
                let acc = (v[j] - v0[j]) / tau;
                // 1e-6 relative: the rows are written with round-trip precision, the timing
                // keeps 1e-9 of margin.
                assert!(
                    acc.abs() <= amax * (1.0 + 1e-6),
                    "joint {} accelerates at {acc} rad/s², row {k}",
                    j + 1
                );
            }
        }
        vel.push((dt, v));
        // Tool speed recomputed from the targets and the times: within 2 % of the design
        // speed (0.05 m/s) on every print move, except where the plan reports a slowdown.
        let pa = target(a.layer, a.index);
        let dist = (0..3)
            .map(|i| (p.position[i] - pa.position[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        if dist > 0.0 {
            let speed = dist / dt;
            if slow(r.layer, r.index) {
                slowed += 1;
                // A slowdown is reported where the tool is below 98 % of the design speed.
                assert!(speed < opts.print_speed);
            } else {
                assert!(
                    (speed / opts.print_speed - 1.0).abs() <= 0.02,
                    "tool at {speed} m/s at layer {} point {}",
                    r.layer,
                    r.index
                );
                checked_speed += 1;
            }
            // The flow follows the planned speed: factor · lw·lh·v (L/min) + offset.
            let q_lpm = 0.02 * 0.008 * r.v_tool * 60_000.0;
            assert!(
                (r.flow - (opts.pump.flow_offset + opts.pump.flow_factor * q_lpm)).abs() < 1e-12
            );
        }
    }
    assert!(max_pos_err <= 1e-6, "{max_pos_err}");
    (checked_speed, slowed)
}

#[test]
fn trajectory_rows_respect_limits_and_stay_on_the_path() {
    let (layers, setup, opts) = small();
    let plan = plan_print(&layers, &setup, &opts).unwrap();
    // 5 rad/s²: the default acceleration limit.
    let (checked, _) = check_rows(&plan, &layers, &opts, 5.0);
    assert!(checked > 0);
    let rows = rows(&plan);
    // The pump is off on the approach and primes at the first move's flow (0.02 × 0.008 m at
    // 0.05 m/s = 0.48 L/min → 0.48 with the default factor 1 per L/min); 1e-12: round-off.
    assert_eq!(rows[0].flow, 0.0);
    assert!((rows[1].t - rows[0].t - opts.pump.prime_dwell).abs() < 1e-12);
    assert!((rows[1].flow - 0.48).abs() < 1e-12, "{}", rows[1].flow);
    // Every layer change is a printed move: the rows go straight from a layer's last point to
    // the next layer's first (no row off the path in between, checked above by the FK).
    assert_eq!(
        rows.iter().filter(|r| r.index == 0).count(),
        16 + 1, // + the priming hold row at the very first target
    );
}

/// With a low acceleration limit the tool must slow down at the corners of the path (the
/// layer changes turn by 90° twice): the rows still respect the limit, the slow moves are
/// reported, and the flow set-point follows the lower speed (checked in `check_rows`).
#[test]
fn where_the_limits_bind_the_tool_and_the_flow_slow_down_and_it_is_reported() {
    let (layers, setup, mut opts) = small();
    // A third of the largest acceleration the plan needs at the default limit.
    let free = plan_print(&layers[..4], &setup, &opts).unwrap();
    let amax = free.max_acceleration_ratio * 5.0 / 3.0;
    opts.limits.max_acceleration = [amax; 6];
    let plan = plan_print(&layers[..4], &setup, &opts).unwrap();
    assert!(!plan.slowdowns.is_empty());
    assert!(plan.max_acceleration_ratio <= 1.0 + 1e-9);
    let (checked, slowed) = check_rows(&plan, &layers, &opts, amax);
    assert!(checked > 0 && slowed > 0, "{checked} {slowed}");
    assert!(
        plan.slowdowns
            .iter()
            .all(|s| s.reason == "joint acceleration")
    );
    let files = program_files(&plan, "p").unwrap();
    let slow_flow = plan
        .slowdowns
        .iter()
        .map(|s| s.min_speed_ratio)
        .fold(f64::INFINITY, f64::min)
        * 0.48;
    // The lowest flow set-point written equals the slowest move's flow (6 decimals).
    let min_written = files
        .iter()
        .flat_map(|f| f.text.lines())
        .filter_map(|l| l.trim().strip_prefix("set_standard_analog_out(0, "))
        .filter_map(|v| v.trim_end_matches(')').parse::<f64>().ok())
        .filter(|v| *v > 0.0)
        .fold(f64::INFINITY, f64::min);
    assert!(
        (min_written - slow_flow).abs() < 1e-6,
        "{min_written} {slow_flow}"
    );
}

#[test]
fn programs_lint_fit_and_switch_the_pump_once_per_station() {
    let (layers, setup, opts) = small();
    let plan = plan_print(&layers, &setup, &opts).unwrap();
    let files = program_files(&plan, "program_part").unwrap();
    assert!(files.len() >= 4, "{}", files.len());
    let mut on_per_station = vec![0; plan.stations.len()];
    let mut off_per_station = vec![0; plan.stations.len()];
    for f in &files {
        let rep = lint(&f.text, 50);
        assert!(rep.ok(), "{}: {:?}", f.name, rep.problems);
        assert!(rep.targets <= 50);
        assert_eq!(rep.targets, f.part.targets);
        on_per_station[f.part.station] +=
            f.text.matches("set_standard_digital_out(0, True)").count();
        off_per_station[f.part.station] +=
            f.text.matches("set_standard_digital_out(0, False)").count();
    }
    assert_eq!(on_per_station, vec![1; plan.stations.len()]);
    // Off before the approach (safety) and at the station's end.
    assert_eq!(off_per_station, vec![2; plan.stations.len()]);
    // The index lists every file in order with its station.
    let idx: serde_json::Value = serde_json::from_str(&index_json(&files)).unwrap();
    let list = idx["programs"].as_array().unwrap();
    assert_eq!(list.len(), files.len());
    assert_eq!(list[0]["file"], "program_part01.script");
    assert_eq!(list[0]["station"], 1);
}

#[test]
fn program_files_are_balanced() {
    let (layers, setup, mut opts) = small();
    // 40 targets: 3 layers of 12 points per file, so a greedy cut of the 16 layers would end
    // with a file of one layer (3,3,3,3,3,1); a balanced one is 3,3,3,3,2,2.
    opts.program.max_moves_per_program = 40;
    let plan = plan_print(&layers, &setup, &opts).unwrap();
    // Per station the fewest files; the largest as small as any cut into that many files can
    // make it; then the smallest as large as possible (an exhaustive search over the cuts, with
    // a file's target count restated here: approach movej + movel + the other points for a
    // starting file, a movej + every point for a continuing one, one retract more at the end).
    for (si, st) in plan.stations.iter().enumerate() {
        let sizes: Vec<usize> = st.layers.iter().map(|l| l.waypoints.len()).collect();
        let n = sizes.len();
        let cost = |a: usize, b: usize| sizes[a..b].iter().sum::<usize>() + 1 + usize::from(b == n);
        // All cuts into k files: recursive enumeration (n = 16 keeps it small).
        fn cuts(n: usize, a: usize, k: usize, cur: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
            if k == 1 {
                cur.push(n);
                out.push(cur.clone());
                cur.pop();
                return;
            }
            for b in a + 1..n {
                cur.push(b);
                cuts(n, b, k - 1, cur, out);
                cur.pop();
            }
        }
        let mut best: Option<(usize, usize, usize)> = None;
        for k in 1..=n {
            let mut all = Vec::new();
            cuts(n, 0, k, &mut Vec::new(), &mut all);
            for c in &all {
                let mut a = 0;
                let mut files = Vec::new();
                for &b in c {
                    files.push(cost(a, b));
                    a = b;
                }
                if files.iter().all(|&f| f <= 40) {
                    let (mx, mn) = (*files.iter().max().unwrap(), *files.iter().min().unwrap());
                    let key = (k, mx, usize::MAX - mn);
                    if best.is_none_or(|b| key < b) {
                        best = Some(key);
                    }
                }
            }
            if best.is_some() {
                break;
            }
        }
        let (k, mx, inv_mn) = best.unwrap();
        let mine: Vec<usize> = plan
            .parts
            .iter()
            .filter(|p| p.station == si)
            .map(|p| p.targets)
            .collect();
        assert_eq!(mine.len(), k, "station {si}: {mine:?}");
        assert_eq!(*mine.iter().max().unwrap(), mx, "station {si}: {mine:?}");
        assert_eq!(
            *mine.iter().min().unwrap(),
            usize::MAX - inv_mn,
            "station {si}: {mine:?}"
        );
    }
    // No file of one layer at a station's end (the greedy cut's flaw).
    assert!(
        plan.parts.iter().all(|p| p.last > p.first),
        "{:?}",
        plan.parts
    );
    for f in program_files(&plan, "program_part").unwrap() {
        let rep = lint(&f.text, 40);
        assert!(
            rep.ok() && rep.targets <= 40,
            "{}: {:?}",
            f.name,
            rep.problems
        );
    }
}

#[test]
fn waits_become_pauses_and_the_schedule_agrees() {
    let (layers, setup, mut opts) = small();
    opts.waits.min_layer_time = 5.0;
    let plan = plan_print(&layers[..6], &setup, &opts).unwrap();
    let times = layer_times(&plan);
    for w in times.windows(2) {
        // 1e-9 s: round-off of the summed durations.
        assert!(w[1].start - w[0].start >= 5.0 - 1e-9, "{w:?}");
    }
    // Given waits replace the minimum layer time; the programs sleep exactly those times.
    opts.waits.min_layer_time = 0.0;
    // (Layer 1: inside the first of the two balanced files of 3 layers.)
    let waits = [LayerWait {
        layer: 1,
        wait: 7.5,
    }];
    let plan = plan_print_with_waits(&layers[..6], &setup, &opts, Some(&waits)).unwrap();
    let t = layer_times(&plan);
    assert_eq!(t[1].wait, 7.5);
    let files = program_files(&plan, "p").unwrap();
    assert!(files.iter().any(|f| f.text.contains("sleep(7.500000)")));
    // Stopping the pump in pauses switches it on again after each.
    opts.pump.pause = PauseMode::Stop;
    let plan = plan_print_with_waits(&layers[..6], &setup, &opts, Some(&waits)).unwrap();
    let files = program_files(&plan, "p").unwrap();
    let ons: usize = files
        .iter()
        .map(|f| f.text.matches("set_standard_digital_out(0, True)").count())
        .sum();
    // Once at the start, once after the wait, once at the start of each continuing program.
    assert_eq!(ons, 2 + files.len() - 1);
    for f in &files {
        assert!(lint(&f.text, 50).ok());
    }
}

#[test]
fn resume_starts_with_the_layers_first_target() {
    let (layers, setup, opts) = small();
    let plan = plan_print(&layers, &setup, &opts).unwrap();
    let k = 9;
    let resumed = resume_plan(&plan, k).unwrap();
    assert!(check_plan(&resumed).problems.is_empty());
    let first = &resumed.stations[0].layers[0];
    assert_eq!(first.layer, k);
    let orig = plan.stations[0]
        .layers
        .iter()
        .find(|l| l.layer == k)
        .unwrap();
    assert_eq!(first.waypoints[0].q, orig.waypoints[0].q);
    let files = program_files(&resumed, "resume_part").unwrap();
    // The first program approaches from the safe pose and descends (movel) onto layer k's
    // first target: compare the movel position with the target in the base frame.
    let text = &files[0].text;
    let movel = text
        .lines()
        .find(|l| l.trim_start().starts_with("movel(p["))
        .unwrap();
    let nums: Vec<f64> = movel
        .split(['[', ']', ','])
        .skip(1)
        .take(3)
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let base = Iso::from_mat4_unchecked(&plan.stations[0].world_from_base);
    let p = layers.iter().find(|l| l.layer == k).unwrap().points[0].position;
    let local = base.inverse().point(p.into());
    for i in 0..3 {
        // 1e-8 m: the program prints 9 decimals.
        assert!((nums[i] - local[i]).abs() < 1e-8, "{movel}");
    }
    assert!(text.contains("set_standard_digital_out(0, True)"));
    for f in &files {
        assert!(lint(&f.text, 50).ok());
    }
    let e = resume_plan(&plan, 99).unwrap_err().to_string();
    assert!(e.contains("layer 99 is not in the plan"), "{e}");
}

#[test]
fn bad_program_input_is_named() {
    let (layers, setup, opts) = small();
    let mut o = opts.clone();
    o.program.max_moves_per_program = 12; // a layer of 12 points needs 2 + 11 + 1 = 14
    let e = plan_print(&layers[..2], &setup, &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("max_moves_per_program") && e.contains("layer 0"),
        "{e}"
    );
    let mut o = opts.clone();
    o.pump.flow_factor = 0.0;
    let e = plan_print(&layers[..2], &setup, &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("flow_factor"), "{e}");
    let mut o = opts.clone();
    o.pump.flow_output = 2;
    let e = plan_print(&layers[..2], &setup, &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("analog output 2"), "{e}");
    let mut o = opts.clone();
    o.pump.enable_output = Some(DigitalOutput::Standard(8));
    let e = plan_print(&layers[..2], &setup, &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("enable_output"), "{e}");
    let mut o = opts;
    o.pump.flow_factor = 10.0; // 0.48 L/min → 4.8 > 1
    let e = plan_print(&layers[..2], &setup, &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("> 1"), "{e}");
}

/// The check covers the approach from the safe pose: one out of reach is named.
#[test]
fn an_unreachable_approach_pose_fails_the_check() {
    let (layers, setup, opts) = small();
    let mut plan = plan_print(&layers[..2], &setup, &opts).unwrap();
    assert!(check_plan(&plan).problems.is_empty());
    plan.options.program.approach_distance = 3.0; // beyond the 1.3 m reach
    let problems = check_plan(&plan).problems;
    assert!(
        problems
            .iter()
            .any(|p| p.contains("approach") && p.contains("no joint configuration")),
        "{problems:?}"
    );
}

#[test]
fn lint_rejects_what_the_controller_would() {
    let ok = "def a():\n  movej([0, -1.5, 1.0, 0, 1.2, 0], a=1.0, v=0.5)\n  sleep(0.5)\nend\na()\n";
    assert!(lint(ok, 10).ok(), "{:?}", lint(ok, 10).problems);
    let cases = [
        ("def a():\n  fly(1)\nend\na()\n", "unknown function fly"),
        (
            "def a():\n  movej([0,0,0,0,0,0], 1, 2, 3, 4, 5)\nend\na()\n",
            "at most 5",
        ),
        (
            "def a():\n  movep(p[0,0,0,0,0,0], b=2)\nend\na()\n",
            "no parameter b",
        ),
        ("def a():\n  sleep(1e999)\nend\na()\n", "not finite"),
        (
            "def a():\n  movej([0, 0, 3.5, 0, 0, 0])\nend\na()\n",
            "joint 3",
        ),
        (
            "def a():\n  movej([7.0, 0, 0, 0, 0, 0])\nend\na()\n",
            "joint 1",
        ),
        (
            "def a():\n  set_standard_analog_out(2, 0.5)\nend\na()\n",
            "does not exist",
        ),
        (
            "def a():\n  set_standard_digital_out(8, True)\nend\na()\n",
            "does not exist",
        ),
        ("def a():\n  sleep(1)\na()\n", "never closed"),
        ("def a():\n  sleep(1)\nend\n", "never called"),
        ("def a():\n  movel(p[0,0,0,0,0])\nend\na()\n", "5 values"),
        (
            "def a():\n  movej([0,-1,1,0,1,0])\n  movej([0,-1,1,0,1,0])\nend\na()\n",
            "more than the limit 1",
        ),
    ];
    for (text, want) in cases {
        let rep = lint(text, if want.contains("limit 1") { 1 } else { 10 });
        assert!(
            rep.problems.iter().any(|p| p.contains(want)),
            "{want}: {:?}",
            rep.problems
        );
    }
}

#[test]
fn plan_clears_ur_collision_meshes() {
    let (layers, setup, opts) = small();
    let plan = plan_print(&layers[..6], &setup, &opts).unwrap();
    let rep = kappe_robot::meshes::verify_meshes(&plan, 1).unwrap();
    assert_eq!(rep.waypoints_checked, plan.waypoint_count());
    assert!(rep.problems.is_empty(), "{:?}", rep.problems);
    // Both models report a positive clearance to the environment and on the self pairs; the
    // capsule model is what the planner held to its 10 mm margin.
    assert!(rep.meshes.environment.distance > 0.0);
    assert!(rep.meshes.self_distance.distance > 0.0);
    assert!(rep.capsules.environment.distance >= opts.clearance);
    assert!(rep.nozzle.distance >= opts.clearance);
}

/// Numbers inside the first `(...)` of a URScript call, e.g. `movep(p[1, 2, 3, …], a=…, v=…)`:
/// the pose (or joint list) values and the named `v=`.
fn pose_and_v(line: &str) -> (Vec<f64>, Option<f64>) {
    let inner = line
        .split_once('[')
        .and_then(|(_, r)| r.split_once(']'))
        .map_or("", |(p, _)| p);
    let p: Vec<f64> = inner
        .split(',')
        .filter_map(|x| x.trim().parse().ok())
        .collect();
    let v = line
        .split("v=")
        .nth(1)
        .and_then(|r| r.split([',', ')']).next())
        .and_then(|x| x.trim().parse().ok());
    (p, v)
}

#[test]
fn one_clock_for_trajectory_schedule_programs_and_total() {
    let (layers, setup, mut opts) = small();
    // Waits (3 s per layer at least) and several files per station, so pauses and program
    // changes are on the clock too.
    opts.waits.min_layer_time = 3.0;
    let plan = plan_print(&layers, &setup, &opts).unwrap();
    let times = layer_times(&plan);
    let rows = rows(&plan);
    let files = program_files(&plan, "p").unwrap();
    assert!(files.len() >= 3, "{}", files.len());
    let last = times.last().unwrap();
    // The total is the end of the last layer, the last row of trajectory.csv and the end of
    // the last program: the same number, not within a tolerance.
    assert_eq!(plan.total_time, last.end + last.pause);
    assert_eq!(plan.total_time, rows.last().unwrap().t);
    assert_eq!(plan.total_time, files.last().unwrap().end);
    // The clock starts with the first program's approach: the first target is reached after it.
    let approach = kappe_robot::timing::trapezoid_time(
        opts.program.approach_distance,
        opts.program.approach_speed,
        opts.program.tool_acceleration,
    );
    assert_eq!(rows[0].t, approach);
    // Every layer's start and end are its first and last rows.
    for lt in &times {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.layer == lt.layer).collect();
        assert_eq!(mine.first().unwrap().t, lt.start, "layer {}", lt.layer);
        let end = mine.last().unwrap().t;
        assert_eq!(end, lt.end + lt.pause, "layer {}", lt.layer);
    }
    // The programs' own time: per station, the sleeps plus every print move's length over its
    // `v=`, plus the program switch between the station's files (the operator's time, on the
    // plan's clock, not in a file), equals the station's span from its first to its last
    // target.
    for (si, st) in plan.stations.iter().enumerate() {
        let mut prog_time = 0.0;
        let mut prev: Option<[f64; 3]> = None;
        let mine: Vec<&ProgramFile> = files.iter().filter(|f| f.part.station == si).collect();
        for f in &mine {
            let mut printing = false;
            for line in f.text.lines().map(str::trim) {
                if line.starts_with("movel(") && !printing && f.part.starts_station {
                    // The approach's descent ends at the first target.
                    prev = Some(pose_and_v(line).0[..3].try_into().unwrap());
                    printing = true;
                } else if line.starts_with("movep(") {
                    printing = true;
                    let (p, v) = pose_and_v(line);
                    let p: [f64; 3] = p[..3].try_into().unwrap();
                    let a = prev.unwrap();
                    let d = ((p[0] - a[0]).powi(2) + (p[1] - a[1]).powi(2) + (p[2] - a[2]).powi(2))
                        .sqrt();
                    prog_time += d / v.unwrap();
                    prev = Some(p);
                } else if line.starts_with("sleep(") && printing {
                    prog_time += line[6..line.len() - 1].parse::<f64>().unwrap();
                }
            }
        }
        prog_time += (mine.len() - 1) as f64 * opts.program.program_switch_time;
        let first = st.layers[0].waypoints[0].t;
        let span = st.layers.last().unwrap().waypoints.last().unwrap().t - first;
        // Relative 1e-4: the programs round v to 1e-6 m/s (2e-5 of 0.05 m/s) and positions to
        // 1e-9 m; the times themselves are exact.
        assert!(
            (prog_time - span).abs() <= 1e-4 * span,
            "station {si}: programs {prog_time} s, plan {span} s"
        );
    }
}
