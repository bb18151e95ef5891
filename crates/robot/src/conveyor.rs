//! URScript programs for a moving base: UR's conveyor tracking with the base's travel as the
//! conveyor (issue 27).
//!
//! **Why conveyor tracking, not an RTDE streaming client.** The arm must follow the base's
//! *measured* travel. With `conveyor_pulse_decode` + `track_conveyor_linear` the controller
//! itself reads the travel (quadrature pulses from the base's odometry on two digital inputs)
//! and shifts every motion target by it at its own servo rate, with no network or host in the
//! loop; the programs stay ordinary `movep` programs (constant tool speed, blends, the pump on
//! the analog output), so the controller limits already respected (≤ `max_moves_per_program`
//! targets per file, the flow tied to the planned speed, resume from a layer) carry over
//! unchanged, and `kappe robot lint` can check them offline. RTDE streaming (`servoj` at
//! 500 Hz from a host) would need a real-time host process, a network link inside the
//! tracking loop and the host's own copy of the base's odometry, for a base that creeps at
//! < 1 mm/s: its latency buys nothing here.
//!
//! **Frames.** When the base has travelled `s` along the world direction `d` from its pose `B₀`
//! (travel 0), a world point `p` is at `B(s)⁻¹·p = B₀⁻¹·p − s·R₀ᵀd` in the robot base frame: the
//! work moves by `−R₀ᵀd` per metre of travel, like a conveyor. A part's targets are written in
//! the base frame at the travel `S` where the part starts (the base stands still there, see the
//! handshake), and tracking starts there, so the controller's shift `(ticks − ticks at start) /
//! ticks_per_meter · direction` with `direction = −R₀ᵀd` keeps them world-fixed. Joint targets
//! (`movej`) are valid only at the base pose they were planned for, so they are used only before
//! tracking starts (approach, continuing a part) while the base stands still.
//!
//! **Handshake** (per program file, see `docs/moving-base.md`):
//! 1. the base drives to the part's start pose (its trajectory row at the part's start time)
//!    and stops, then raises `base_ready_input`;
//! 2. the program waits for it, approaches and primes (base still), starts tracking and raises
//!    `go_output`: the base follows its time-stamped trajectory from that row on;
//! 3. at the part's end the program stops tracking and drops `go_output`: the base completes its
//!    trajectory to the part's end row (where it holds) and drops `base_ready_input`.
//!
//! The file index ([`tracking_index_json`]) gives each file's start travel, start time and base
//! pose.

use parry3d_f64::glamx::DVec3;
use serde::{Deserialize, Serialize};

use crate::error::RobotError;
use crate::frames::Iso;
use crate::kinematics::UR10E;
pub use crate::lint::{lint_tracking, tracking_form_problems, uses_tracking};
use crate::moving::MovingPlan;
use crate::program::{ProgramFile, flow_output};
use crate::setup::{AnalogDomain, DigitalOutput, PauseMode};

/// The base's travel as a conveyor encoder, and the handshake signals.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ConveyorOptions {
    /// Decoder type of `conveyor_pulse_decode` (1 = quadrature: direction known; 2–4 single
    /// input edges). Default 1.
    pub decoder: u8,
    /// Digital inputs (0–3) of the encoder's A and B channels. Default 0 and 1.
    pub input_a: u8,
    pub input_b: u8,
    /// Encoder ticks per metre of base travel (> 0). Default 10 000 (0.1 mm per tick; the UR
    /// decodes up to 40 kHz, i.e. 4 m/s at this resolution).
    pub ticks_per_meter: f64,
    /// Standard digital input (0–7) the base raises when it stands at a part's start. Default 2.
    pub base_ready_input: u8,
    /// Output raised while the arm tracks (the base drives its trajectory). Default standard 1.
    pub go_output: DigitalOutput,
    /// Deceleration (rad/s²) of `stop_conveyor_tracking`. Default 20 (UR's default).
    pub stop_acceleration: f64,
}

impl Default for ConveyorOptions {
    fn default() -> Self {
        ConveyorOptions {
            decoder: 1,
            input_a: 0,
            input_b: 1,
            ticks_per_meter: 10_000.0,
            base_ready_input: 2,
            go_output: DigitalOutput::Standard(1),
            stop_acceleration: 20.0,
        }
    }
}

impl ConveyorOptions {
    /// Check the settings against the controller; the error names the field (`conveyor.<f>`).
    pub fn validate(&self) -> Result<(), RobotError> {
        if !(1..=4).contains(&self.decoder) {
            return Err(RobotError::invalid(
                "conveyor.decoder",
                format!(
                    "{}: conveyor_pulse_decode types are 1 (quadrature), 2 (both edges), 3 (rising), 4 (falling)",
                    self.decoder
                ),
            ));
        }
        if self.input_a > 3 || self.input_b > 3 {
            return Err(RobotError::invalid(
                "conveyor.input_a / conveyor.input_b",
                format!(
                    "{} / {}: the encoder inputs are digital inputs 0–3",
                    self.input_a, self.input_b
                ),
            ));
        }
        if !(self.ticks_per_meter.is_finite() && self.ticks_per_meter > 0.0) {
            return Err(RobotError::invalid(
                "conveyor.ticks_per_meter",
                format!("{}: must be finite and > 0", self.ticks_per_meter),
            ));
        }
        if self.base_ready_input > 7 {
            return Err(RobotError::invalid(
                "conveyor.base_ready_input",
                format!("{}: standard digital inputs are 0–7", self.base_ready_input),
            ));
        }
        let n = match self.go_output {
            DigitalOutput::Standard(n)
            | DigitalOutput::Configurable(n)
            | DigitalOutput::Tool(n) => n,
        };
        if n > self.go_output.max_number() {
            return Err(RobotError::invalid(
                "conveyor.go_output",
                format!("{:?}: no such output", self.go_output),
            ));
        }
        if !(self.stop_acceleration.is_finite() && self.stop_acceleration > 0.0) {
            return Err(RobotError::invalid(
                "conveyor.stop_acceleration",
                format!("{}: must be finite and > 0", self.stop_acceleration),
            ));
        }
        Ok(())
    }
}

fn num(x: f64) -> String {
    let s = format!("{x:.6}");
    if s == "-0.000000" {
        "0.000000".into()
    } else {
        s
    }
}

fn pose(t: &Iso) -> String {
    let r = t.rotation_vector();
    format!(
        "p[{:.9}, {:.9}, {:.9}, {:.9}, {:.9}, {:.9}]",
        t.t.x, t.t.y, t.t.z, r.x, r.y, r.z
    )
}

fn joints(q: &[f64; 6]) -> String {
    let v: Vec<String> = q.iter().map(|x| format!("{x:.9}")).collect();
    format!("[{}]", v.join(", "))
}

/// Where a tracking file starts: its base travel (m) and plan time (s).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrackingStart {
    pub travel: f64,
    pub t: f64,
    /// The base pose there, row-major.
    pub world_from_base: crate::frames::Mat4,
}

/// The conveyor-tracking program files of a moving plan (`<prefix>NN.script`), one per part of
/// `mp.plan.parts`, each with exactly the part's motion targets, and where each starts.
pub fn tracking_program_files(
    mp: &MovingPlan,
    conveyor: &ConveyorOptions,
    prefix: &str,
) -> Result<Vec<(ProgramFile, TrackingStart)>, RobotError> {
    conveyor.validate()?;
    mp.validate_shape()?;
    if !mp.check.problems.is_empty() {
        return Err(RobotError::Verification(mp.check.problems.clone()));
    }
    let plan = &mp.plan;
    let o = &plan.options;
    let pr = &o.program;
    let pump = &o.pump;
    let tool = Iso::from_mat4(&plan.flange_from_tcp)
        .map_err(|e| RobotError::invalid("flange_from_tcp", e))?;
    let st = plan
        .stations
        .first()
        .ok_or_else(|| RobotError::invalid("plan", "no station"))?;
    let start = Iso::from_mat4(&st.world_from_base)
        .map_err(|e| RobotError::invalid("world_from_base", e))?;
    let d = DVec3::from(mp.trajectory.direction);
    // The work moves by −R₀ᵀd in the base frame per metre of travel.
    let dir_b = -(start.r.transpose() * d);
    let aout = |v: f64| format!("set_standard_analog_out({}, {})", pump.flow_output, num(v));
    let enable = |on: bool| pump.enable_output.map(|e| e.call(on));
    let n_parts = plan.parts.len();
    let mut out = Vec::new();
    for (pi, part) in plan.parts.iter().enumerate() {
        let layers = st
            .layers
            .get(part.first..=part.last)
            .ok_or_else(|| RobotError::invalid("parts", "names layers the plan lacks"))?;
        let first_wp = layers
            .first()
            .and_then(|l| l.waypoints.first())
            .ok_or_else(|| RobotError::invalid("parts", "an empty layer"))?;
        let last_wp = layers
            .last()
            .and_then(|l| l.waypoints.last())
            .ok_or_else(|| RobotError::invalid("parts", "an empty layer"))?;
        // Where the part starts: its first target (starting the print), or the previous
        // layer's last target (continuing).
        let (s0, t0, q0) = if part.starts_station {
            (mp.travel[part.first][0], first_wp.t, first_wp.q)
        } else {
            let li = part.first - 1;
            let w = st.layers[li]
                .waypoints
                .last()
                .ok_or_else(|| RobotError::invalid("parts", "an empty layer"))?;
            let s = *mp.travel[li]
                .last()
                .ok_or_else(|| RobotError::invalid("parts", "an empty layer"))?;
            (s, w.t + w.hold, w.q)
        };
        let base_s0 = Iso::new(start.r, start.t + d * s0);
        let s0_from_world = base_s0.inverse();
        let fname = format!("{prefix}{:02}.script", pi + 1);
        let func = format!("kappe_track_{:02}{}", pi + 1, plan.mark.function_suffix());
        let mut w = String::new();
        let mut depth = 1usize;
        let mut line = |s: &str, dd: &mut usize| {
            if s == "end" {
                *dd -= 1;
            }
            for _ in 0..*dd {
                w.push_str("  ");
            }
            w.push_str(s);
            w.push('\n');
            if s.ends_with(':') {
                *dd += 1;
            }
        };
        let mut targets = 0usize;
        line(&format!("set_tcp({})", pose(&tool)), &mut depth);
        line(
            &format!(
                "set_payload({}, [{}, {}, {}])",
                num(pr.payload_mass),
                num(pr.payload_cog[0]),
                num(pr.payload_cog[1]),
                num(pr.payload_cog[2])
            ),
            &mut depth,
        );
        let domain = match pump.flow_domain {
            AnalogDomain::Current => 0,
            AnalogDomain::Voltage => 1,
        };
        line(
            &format!("set_analog_outputdomain({}, {domain})", pump.flow_output),
            &mut depth,
        );
        line(
            "# the base's travel as a conveyor: quadrature pulses of its odometry",
            &mut depth,
        );
        line(
            &format!(
                "conveyor_pulse_decode({}, {}, {})",
                conveyor.decoder, conveyor.input_a, conveyor.input_b
            ),
            &mut depth,
        );
        line(&conveyor.go_output.call(false), &mut depth);
        line(
            &format!(
                "# handshake: wait for the base standing at travel {} m (plan time {} s)",
                num(s0),
                num(t0)
            ),
            &mut depth,
        );
        line(
            &format!(
                "while not get_standard_digital_in({}):",
                conveyor.base_ready_input
            ),
            &mut depth,
        );
        line("sync()", &mut depth);
        line("end", &mut depth);
        let mut flow_now: f64;
        if part.starts_station {
            line(&aout(0.0), &mut depth);
            if let Some(s) = enable(false) {
                line(&s, &mut depth);
            }
            let qa = crate::kinematics::approach_config(
                &first_wp.q,
                &tool,
                pr.approach_distance,
                &o.limits.position(),
            )?;
            line("# approach with the base standing still", &mut depth);
            line(
                &format!(
                    "movej({}, a={}, v={})",
                    joints(&qa),
                    num(pr.joint_acceleration),
                    num(pr.joint_speed)
                ),
                &mut depth,
            );
            line(
                &format!(
                    "movel({}, a={}, v={})",
                    pose(&UR10E.fk(&first_wp.q).mul(&tool)),
                    num(pr.tool_acceleration),
                    num(pr.approach_speed)
                ),
                &mut depth,
            );
            targets += 2;
            let v1 = layers
                .iter()
                .flat_map(|l| &l.waypoints)
                .nth(1)
                .map_or(o.print_speed, |w| w.speed);
            flow_now = flow_output(plan, v1);
            line(&aout(flow_now), &mut depth);
            if let Some(s) = enable(true) {
                line(&s, &mut depth);
            }
            line(&format!("sleep({})", num(pump.prime_dwell)), &mut depth);
        } else {
            line(
                "# continue where the previous program stopped (base standing still)",
                &mut depth,
            );
            line(
                &format!(
                    "movej({}, a={}, v={})",
                    joints(&q0),
                    num(pr.joint_acceleration),
                    num(pr.joint_speed)
                ),
                &mut depth,
            );
            targets += 1;
            if pump.pause == PauseMode::Stop {
                line(&aout(flow_output(plan, first_wp.speed)), &mut depth);
                if let Some(s) = enable(true) {
                    line(&s, &mut depth);
                }
                line(&format!("sleep({})", num(pump.prime_dwell)), &mut depth);
            }
            flow_now = f64::NAN;
        }
        line(
            "# track the base: the targets below are world points in the base frame at this travel",
            &mut depth,
        );
        line(
            &format!(
                "track_conveyor_linear(p[{:.9}, {:.9}, {:.9}, 0, 0, 0], {})",
                dir_b.x,
                dir_b.y,
                dir_b.z,
                num(conveyor.ticks_per_meter)
            ),
            &mut depth,
        );
        line(&conveyor.go_output.call(true), &mut depth);
        let cmd = if pr.use_movel { "movel" } else { "movep" };
        let n_layers = layers.len();
        for (li, l) in layers.iter().enumerate() {
            line(
                &format!("# layer {} ({} points)", l.layer, l.waypoints.len()),
                &mut depth,
            );
            for (k, wp) in l.waypoints.iter().enumerate() {
                if part.starts_station && li == 0 && k == 0 {
                    continue;
                }
                let f = flow_output(plan, wp.speed);
                if flow_now.is_nan() || (f - flow_now).abs() > 1e-4 {
                    line(&aout(f), &mut depth);
                    flow_now = f;
                }
                let is_last = k + 1 == l.waypoints.len();
                let stop = is_last && (wp.hold > 0.0 || li + 1 == n_layers);
                let r = if stop { 0.0 } else { pr.blend_radius };
                let world = mp
                    .base_pose(part.first + li, k)
                    .mul(&UR10E.fk(&wp.q))
                    .mul(&tool);
                line(
                    &format!(
                        "{cmd}({}, a={}, v={}, r={})",
                        pose(&s0_from_world.mul(&world)),
                        num(pr.tool_acceleration),
                        num(wp.speed),
                        num(r)
                    ),
                    &mut depth,
                );
                targets += 1;
            }
            if li + 1 == n_layers {
                break;
            }
            let hold = l.waypoints.last().map_or(0.0, |w| w.hold);
            if hold > 0.0 {
                match pump.pause {
                    PauseMode::KeepPrimed => {
                        line(
                            &format!("# pause {} s (the base holds too), pump primed", num(hold)),
                            &mut depth,
                        );
                        line(&aout(pump.hold()), &mut depth);
                        line(&format!("sleep({})", num(hold)), &mut depth);
                    }
                    PauseMode::Stop => {
                        line(
                            &format!("# pause {} s, pump stopped, then primed again", num(hold)),
                            &mut depth,
                        );
                        line(&aout(0.0), &mut depth);
                        if let Some(s) = enable(false) {
                            line(&s, &mut depth);
                        }
                        line(
                            &format!("sleep({})", num((hold - pump.prime_dwell).max(0.0))),
                            &mut depth,
                        );
                        line(&aout(flow_output(plan, o.print_speed)), &mut depth);
                        if let Some(s) = enable(true) {
                            line(&s, &mut depth);
                        }
                        line(&format!("sleep({})", num(pump.prime_dwell)), &mut depth);
                    }
                }
                flow_now = f64::NAN;
            }
        }
        line("# part done: stop tracking, release the base", &mut depth);
        line(
            &format!(
                "stop_conveyor_tracking({})",
                num(conveyor.stop_acceleration)
            ),
            &mut depth,
        );
        line(&conveyor.go_output.call(false), &mut depth);
        if part.ends_station {
            line("# print done: pump off, retract", &mut depth);
            line(&aout(0.0), &mut depth);
            if let Some(s) = enable(false) {
                line(&s, &mut depth);
            }
            let back = UR10E.fk(&last_wp.q).mul(&tool).mul(&Iso::translation(
                0.0,
                0.0,
                -pr.approach_distance,
            ));
            line(
                &format!(
                    "movel({}, a={}, v={})",
                    pose(&back),
                    num(pr.tool_acceleration),
                    num(pr.approach_speed)
                ),
                &mut depth,
            );
            targets += 1;
        } else {
            match pump.pause {
                PauseMode::KeepPrimed => {
                    line(
                        "# the next program continues the bead: pump stays primed",
                        &mut depth,
                    );
                    line(&aout(pump.hold()), &mut depth);
                }
                PauseMode::Stop => {
                    line("# the next program primes again", &mut depth);
                    line(&aout(0.0), &mut depth);
                    if let Some(s) = enable(false) {
                        line(&s, &mut depth);
                    }
                }
            }
        }
        let mut text = crate::program::program_head(
            (&fname, targets, part.targets),
            (pi, n_parts),
            (
                "a UR10e on a moving base",
                "conveyor tracking; generated, verified by kappe-robot",
            ),
            &plan.mark,
        )?;
        text.push_str(&format!(
            "# layers {}..{}, {} motion targets; starts at base travel {} m, plan time {} s to {} s\n",
            part.first_layer,
            part.last_layer,
            targets,
            num(s0),
            num(t0),
            num(last_wp.t)
        ));
        text.push_str(&format!(
            "# units m, rad, s; poses in the robot base frame at that travel; conveyor ticks {} per m along {:?} (base frame)\n",
            num(conveyor.ticks_per_meter),
            dir_b.to_array()
        ));
        text.push_str(&format!("def {func}():\n"));
        text.push_str(&w);
        text.push_str("end\n");
        text.push_str(&format!("{func}()\n"));
        out.push((
            ProgramFile {
                name: fname,
                part: part.clone(),
                world_from_base: base_s0.to_mat4(),
                start: first_wp.t,
                end: last_wp.t,
                mark: mp.plan.mark.clone(),
                text,
            },
            TrackingStart {
                travel: s0,
                t: t0,
                world_from_base: base_s0.to_mat4(),
            },
        ));
    }
    Ok(out)
}

/// The index of the tracking files (JSON): order, file, layers, targets, plan times and where
/// the base must stand when each starts (the handshake's start pose).
pub fn tracking_index_json(files: &[(ProgramFile, TrackingStart)]) -> String {
    let list: Vec<serde_json::Value> = files
        .iter()
        .enumerate()
        .map(|(i, (f, s))| {
            let m = &s.world_from_base;
            serde_json::json!({
                "order": i + 1,
                "file": f.name,
                "first_layer": f.part.first_layer,
                "last_layer": f.part.last_layer,
                "targets": f.part.targets,
                "start_travel_m": s.travel,
                "start_time_s": s.t,
                "base_x_m": m[0][3],
                "base_y_m": m[1][3],
                "base_yaw_rad": m[1][0].atan2(m[0][0]),
                "start_s": f.start,
                "end_s": f.end,
                "title": f.mark.title(),
                "failing_design": f.mark.failing_design,
                "resumed_from_layer": f.mark.resumed_from_layer,
            })
        })
        .collect();
    serde_json::to_string_pretty(
        &serde_json::json!({ "programs": list, "mode": "moving base, conveyor tracking" }),
    )
    .unwrap_or_else(|_| "{}".into())
}
