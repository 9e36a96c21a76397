//! `[[controller]]` scenario entries (issue 15): every anti-sway controller
//! of `crane::control` drives the full rope simulation from a scenario
//! file, against the reduced model driven by the same controller, against
//! the closed-form robustness of input shaping, and with clear errors for
//! bad entries.
#![cfg(feature = "sim")]

use bevy_rapier_cable::crane::control::{OverheadCraneLoop, Reference, TrolleyController};
use bevy_rapier_cable::crane::OverheadCrane;
use bevy_rapier_cable::scenario::{self, Controller};
use bevy_rapier_cable::sim::World;

#[path = "common/scenario_run.rs"]
mod scenario_run;
use scenario_run::run_scenario;
use std::f64::consts::PI;

const SHIPPED: [(&str, &str); 5] = [
    ("ZV shaper", "crane_zv"),
    ("ZVD shaper", "crane_zvd"),
    ("double-loop PID", "crane_pid"),
    ("nonlinear PID", "crane_pid_nonlinear"),
    ("incremental PID, T = 50 ms", "crane_pid_incremental"),
];

/// The unshaped move as a velocity table on the rail (the time-optimal
/// trapezoid of the shipped waypoints).
const UNSHAPED: &str = "drive = { velocity = [[0.0, 0.0], [1.0, 0.0], [5.0, 1.0], [11.0, 1.0], [15.0, 0.0]], max_force = 20000.0 }";

/// A shipped crane scenario with the rope (and the payload) made `rope` m
/// long, the `[[controller]]` table replaced by `controller` (or removed,
/// with `rail_drive` on the rail), and probes of the two bodies and the
/// rail force only.
fn crane_text(name: &str, rope: f64, controller: Option<&str>, rail_drive: &str) -> String {
    let text = std::fs::read_to_string(format!("assets/scenarios/{name}.toml")).unwrap();
    let head = &text[..text.find("[[controller]]").unwrap()];
    let head = head
        .replace("length = 10.0", &format!("length = {rope}"))
        .replace("position = [0.0, -10.3, 0.0]", &format!("position = [0.0, -{}, 0.0]", rope + 0.3))
        .replace("[0.0, -10.0, 0.0]]", &format!("[0.0, -{rope}, 0.0]]"))
        .replace("axis = [1.0, 0.0, 0.0]\n", &format!("axis = [1.0, 0.0, 0.0]\n{rail_drive}\n"));
    let probes = r#"
[[probe]]
name = "trolley"
body = "trolley"
quantity = "position"

[[probe]]
name = "payload"
body = "payload"
quantity = "position"

[[probe]]
name = "force"
joint = "rail"
quantity = "force"
component = "x"
"#;
    format!("{head}{}{probes}", controller.unwrap_or(""))
}

/// The `[[controller]]` table of a shipped scenario, with `extra` lines.
fn controller_table(name: &str, extra: &str) -> String {
    let text = std::fs::read_to_string(format!("assets/scenarios/{name}.toml")).unwrap();
    let from = text.find("[[controller]]").unwrap();
    let to = from + text[from..].find("[[probe]]").unwrap();
    format!("{}\n{extra}\n\n", text[from..to].trim_end())
}

/// (t, trolley x, sway θ measured independently of the controller: the
/// trolley-to-payload-centre line, rad, drive force N) every frame.
fn run_full(text: &str) -> Vec<(f64, f64, f64, f64)> {
    let (_, rows) = run_scenario(scenario::parse(text, "crane.toml").unwrap_or_else(|e| panic!("{e}")));
    // [t, trolley xyz, payload xyz, rail force]
    rows.iter().map(|r| (r[0], r[1], (r[4] - r[1]).atan2(r[2] - r[5]), r[7])).collect()
}

/// The reduced model (rope mass lumped, `OverheadCrane::with_rope_mass`)
/// driven by the same controller at 1 ms (speeds through the rail motor's
/// law: a speed loop of `M/dt`).
fn run_reduced(c: &Controller, rope: f64, duration: f64) -> Vec<(f64, f64, f64, f64)> {
    let crane = OverheadCrane::with_rope_mass(500.0, 1000.0, rope + 0.3, density(), rope).unwrap();
    let controller: Box<dyn TrolleyController + Send + Sync> = c.build().unwrap();
    let sampled = Sampled { inner: controller, period: c.sample_time, next: 0.0, last: None };
    let mut lp = OverheadCraneLoop::new(crane, sampled, 0.0, 500.0 * 60.0, c.max_force).unwrap();
    let mut rows = Vec::new();
    while lp.state.t < duration - 1e-9 {
        let s = lp.step(1e-3).unwrap();
        rows.push((lp.state.t, lp.state.q[0], lp.state.q[1], s.force));
    }
    rows
}

/// Linear density of the shipped cranes' 20 mm steel wire rope, kg/m.
fn density() -> f64 {
    bevy_rapier_cable::cable::RopeMaterial::steel_6x36_iwrc(0.02).section().linear_density
}

/// A controller sampled every `period` s and held in between, as the
/// scenario runners sample it.
struct Sampled {
    inner: Box<dyn TrolleyController + Send + Sync>,
    period: f64,
    next: f64,
    last: Option<bevy_rapier_cable::crane::control::TrolleyCommand>,
}

impl TrolleyController for Sampled {
    fn update(&mut self, m: &bevy_rapier_cable::crane::control::TrolleyMeasurement) -> bevy_rapier_cable::crane::control::TrolleyCommand {
        match self.last {
            Some(c) if m.time + 1e-9 < self.next => c,
            _ => {
                let c = self.inner.update(m);
                self.next += self.period;
                self.last = Some(c);
                c
            }
        }
    }
}

/// Travel time from the move's start (1 s) until the trolley stays
/// within 5 cm of 10 m, s.
fn travel(rows: &[(f64, f64, f64, f64)]) -> f64 {
    let last_out = rows.iter().rposition(|r| (r.1 - 10.0).abs() >= 0.05).map_or(0.0, |i| rows[i].0);
    last_out - 1.0
}

/// Largest |θ| from `from` s on, degrees.
fn residual(rows: &[(f64, f64, f64, f64)], from: f64) -> f64 {
    rows.iter().filter(|r| r.0 >= from).fold(0.0f64, |m, r| m.max(r.2.abs())).to_degrees()
}

fn peak_force(rows: &[(f64, f64, f64, f64)]) -> f64 {
    rows.iter().fold(0.0f64, |m, r| m.max(r.3.abs()))
}

/// Every controller, from its shipped scenario on the full rope (20 beam
/// elements at 1/60 s) and on the reduced model with the same controller:
/// the travel times agree within 0.05 s and the residual sway within 5 %
/// (+0.001°); the closed loops and ZVD leave less than 0.01° of sway and
/// ZV less than 3 % of the unshaped move's (the reduced model with the
/// rail's speed loop leaves the same: the loop's finite gain shifts the
/// sway frequency from the one the shaper was designed for).
/// Then on a 12 m rope with the settings of the 10 m one (the robustness
/// the issue asks for): ZV and ZVD keep the closed-form fractions of the
/// unshaped sway, `|cos(π ω / 2 ω_d)|` and its square, within 0.03 (the
/// fraction ZV leaves on the design rope); the PIDs still arrive and
/// settle.
#[test]
fn every_controller_moves_the_full_rope_crane_as_the_reduced_model_does() {
    let unshaped10 = residual(&run_full(&crane_text("crane_zv", 10.0, None, UNSHAPED)), 20.0);
    let unshaped12 = residual(&run_full(&crane_text("crane_zv", 12.0, None, UNSHAPED)), 20.0);
    println!("unshaped move: residual sway {unshaped10:.3}° (10 m rope), {unshaped12:.3}° (12 m)");
    println!("| controller | rope | travel s (reduced) | residual sway 30-40 s ° (reduced) | peak drive force N (reduced) |");
    let mut zv_on_design = 0.0;
    for (label, name) in SHIPPED {
        let text = std::fs::read_to_string(format!("assets/scenarios/{name}.toml")).unwrap();
        let sc = scenario::parse(&text, name).unwrap();
        let spec = sc.controllers[0].clone();
        // The settings resolved for the 10 m rope, written out for the 12 m one.
        let tuned = if spec.kind.is_shaper() {
            format!("frequency = {:?}", spec.frequency)
        } else {
            let (p, s) = (spec.position, spec.sway);
            format!("kp = {:?}\nki = {:?}\nkd = {:?}\nsway_kp = {:?}\nsway_ki = {:?}\nsway_kd = {:?}", p.kp, p.ki, p.kd, s.kp, s.ki, s.kd)
        };
        for rope in [10.0, 12.0] {
            let full = run_full(&crane_text(name, rope, Some(&controller_table(name, &tuned)), ""));
            let reduced = run_reduced(&spec, rope, 40.0);
            let (tf, tr) = (travel(&full), travel(&reduced));
            let (rf, rr) = (residual(&full, 30.0), residual(&reduced, 30.0));
            let (ff, fr) = (peak_force(&full), peak_force(&reduced));
            println!("| {label} | {rope} m | {tf:.2} ({tr:.2}) | {rf:.4} ({rr:.4}) | {ff:.0} ({fr:.0}) |");
            assert!((tf - tr).abs() < 0.05, "{label}, {rope} m: travel {tf} s, reduced {tr} s");
            assert!((rf - rr).abs() < 0.05 * rr + 1e-3, "{label}, {rope} m: residual sway {rf}°, reduced {rr}°");
            let last = full.last().unwrap().1;
            assert!((last - 10.0).abs() < 0.05, "{label}, {rope} m: trolley at {last} m");
            let ratio = if rope == 10.0 { rf / unshaped10 } else { rf / unshaped12 };
            match (name, rope == 10.0) {
                ("crane_zv", true) => {
                    zv_on_design = ratio;
                    assert!(ratio < 0.03, "ZV leaves {ratio} of the unshaped sway");
                }
                ("crane_zv" | "crane_zvd", false) => {
                    let omega = 2.0 * PI * spec.frequency;
                    // The 12 m pendulum with the rope's mass lumped (as the default design).
                    let actual = OverheadCrane::with_rope_mass(500.0, 1000.0, 12.3, density(), 12.0).unwrap().pendulum_frequency();
                    let zv = (PI * actual / (2.0 * omega)).cos().abs();
                    let closed = if name == "crane_zv" { zv } else { zv * zv };
                    println!("    fraction of the unshaped sway {ratio:.4}, closed form {closed:.4}");
                    assert!((ratio - closed).abs() < zv_on_design.max(0.01) + 0.01, "{label}: {ratio} vs closed form {closed}");
                }
                _ if rope == 10.0 => assert!(rf < 0.01, "{label} leaves {rf}°"),
                _ => assert!(rf < 0.05, "{label} on the longer rope leaves {rf}°"),
            }
        }
    }
}

/// The waypoint reference of a controller: two waypoints whose times
/// leave room are one trapezoid that arrives exactly on time; a waypoint
/// too soon for the limits is reached late, time-optimally.
#[test]
fn controller_waypoints_arrive_on_time_within_the_limits() {
    let sc = scenario::load(std::path::Path::new("assets/scenarios/crane_pid.toml")).unwrap();
    let c = &sc.controllers[0];
    assert_eq!(c.target, vec![(1.0, 0.0), (15.0, 10.0)]);
    let r = c.reference().unwrap();
    assert_eq!((r.position(0.5), r.position(15.0), r.position(30.0)), (0.0, 10.0, 10.0));
    // The 14 s the waypoints leave are the time-optimal trapezoid's.
    assert!((r.speed(8.0) - 1.0).abs() < 1e-12 && (r.speed(2.0) - 0.25).abs() < 1e-12);
    let slow = bevy_rapier_cable::crane::control::Waypoints::new(&[(0.0, 0.0), (20.0, 5.0), (21.0, 5.0), (22.0, 0.0)], 1.0, 0.25).unwrap();
    // 5 m in 20 s: cruise v = 2ad / (aT + √(a²T² − 4ad)) = 0.2679 m/s, on time.
    let v = 2.0 * 0.25 * 5.0 / (0.25 * 20.0 + (0.0625f64 * 400.0 - 5.0).sqrt());
    assert!((slow.speed(10.0) - v).abs() < 1e-12, "{}", slow.speed(10.0));
    assert!((slow.position(20.0) - 5.0).abs() < 1e-12 && slow.speed(20.0).abs() < 1e-12);
    // Back 5 m between the waypoints at 21 s and 22 s is too soon: the
    // time-optimal move from 21 s (4 s accelerating, 1 s at 1 m/s, 4 s
    // braking), 8 s late.
    assert!((slow.end_time() - 30.0).abs() < 1e-12, "{}", slow.end_time());
    assert!((slow.position(25.5) - 2.5).abs() < 1e-12 && (slow.speed(25.5) + 1.0).abs() < 1e-12);
}

/// Bad `[[controller]]` entries are refused with the field and the line.
#[test]
fn bad_controllers_are_refused_by_name() {
    let base = std::fs::read_to_string("assets/scenarios/crane_pid.toml").unwrap();
    let cases: [(&str, &str, &str); 9] = [
        ("type = \"pid_double_loop\"", "type = \"lqr\"", "unknown type `lqr`; expected one of `zv`, `zvd`, `pid_double_loop`"),
        ("joint = \"rail\"\ncable", "joint = \"gantry\"\ncable", "controller `anti_sway`: unknown joint `gantry` (prismatic joints: `rail`)"),
        ("cable = \"hoist\"\ntarget", "cable = \"sling\"\ntarget", "unknown cable `sling` (known cables: `hoist`)"),
        ("max_force = 20000.0\n", "", "controller `anti_sway`: missing field `max_force` (N)"),
        ("max_speed = 1.0", "max_speed = -1.0", "`max_speed` must be greater than 0 m/s, found -1"),
        ("max_force = 20000.0\n", "max_force = 20000.0\nfrequency = 0.15\n", "`frequency` does not apply to a `pid_double_loop` controller"),
        (
            "max_force = 20000.0\n",
            "max_force = 20000.0\ne_p = 0.5\n",
            "`e_p` does not apply to a `pid_double_loop` controller (only `pid_nonlinear` schedules its gains)",
        ),
        ("[15.0, 10.0]]", "[15.0, 10.0], [12.0, 0.0]]", "times in `target` must be strictly increasing"),
        (
            "controller = \"anti_sway\"\nquantity = \"sway\"",
            "controller = \"anti_swing\"\nquantity = \"sway\"",
            "unknown controller `anti_swing` (known controllers: `anti_sway`)",
        ),
    ];
    for (from, to, expected) in cases {
        assert!(base.contains(from), "{from}");
        let text = base.replacen(from, to, 1);
        let e = scenario::parse(&text, "crane.toml").unwrap_err().to_string();
        assert!(e.contains(expected), "{expected}\n  got: {e}");
        assert!(e.contains("crane.toml:"), "{e}");
    }
    // A rail that no cable carries (the trolley does not hold the cable).
    let text = base.replace("start = { body = \"trolley\", anchor = [0.0, 0.0, 0.0] }", "start = { world = [0.0, 0.0, 0.0] }");
    let e = scenario::parse(&text, "crane.toml").unwrap_err().to_string();
    assert!(e.contains("cable `hoist` must start on the trolley `trolley`"), "{e}");
    // A controller changed after validation is refused by the runner, not
    // a panic.
    let mut sc = scenario::parse(&base, "crane.toml").unwrap();
    sc.controllers[0].max_speed = -1.0;
    let e = World::new(sc).unwrap_err().to_string();
    assert!(e.contains("controller `anti_sway`") && e.contains("max_speed = -1"), "{e}");
    // A controller replaces the rail's drive (the file's drive is ignored).
    let with_drive = base.replace("axis = [1.0, 0.0, 0.0]\n", &format!("axis = [1.0, 0.0, 0.0]\n{UNSHAPED}\n")).replace("duration = 40.0", "duration = 2.0");
    let plain = base.replace("duration = 40.0", "duration = 2.0");
    let rows = |t: &str| scenario_rows(t);
    assert_eq!(rows(&with_drive), rows(&plain));
}

fn scenario_rows(text: &str) -> Vec<Vec<f64>> {
    run_scenario(scenario::parse(text, "crane.toml").unwrap()).1
}

/// The full rope crane of a shipped scenario spawned into a Bevy app with
/// the plugin, its payload pushed along the rail with an `ExternalImpulse`
/// of 500 N·s at 40 s (0.5 m/s, about 2.9° of sway): (t, trolley x, sway
/// θ in degrees as the controller measures it) every frame.
#[cfg(feature = "app")]
fn pushed_in_a_bevy_app(name: &str, seconds: f64) -> Vec<(f64, f64, f64)> {
    use bevy::prelude::*;
    use bevy::time::TimeUpdateStrategy;
    use bevy_rapier3d::prelude::*;
    use bevy_rapier_cable::plugin::scenario::{add_scenario, ScenarioRun};
    use bevy_rapier_cable::plugin::CablePlugin;
    let mut sc = scenario::load(std::path::Path::new(&format!("assets/scenarios/{name}.toml"))).unwrap();
    sc.simulation.duration = seconds;
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin, RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default()));
    app.insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    add_scenario(&mut app, sc).unwrap();
    app.finish();
    app.cleanup();
    app.update();
    let frames = (seconds * 60.0).round() as u64;
    for k in 0..frames {
        if k == 40 * 60 {
            let payload = app.world().resource::<ScenarioRun>().bodies["payload"];
            app.world_mut().entity_mut(payload).insert(ExternalImpulse { impulse: Vec3::X * 500.0, torque_impulse: Vec3::ZERO });
        }
        app.update();
        let run = app.world().resource::<ScenarioRun>();
        assert!(run.failed.is_none(), "{:?}", run.failed);
    }
    app.world().resource::<ScenarioRun>().rows.iter().map(|(t, r)| (*t, r[0], r[1])).collect()
}

/// Rejection of a push on the full rope in a Bevy app (the payload stays a
/// rapier body the game can push): the closed loops catch a 500 N·s push
/// as the reduced model with the same controller does (largest sway within
/// 5 %, trolley excursion within 10 %, back below 0.1° within 0.5 s of the
/// reduced model's time), and the open-loop shapers do not (the sway the
/// push gave stays).
#[cfg(feature = "app")]
#[test]
fn the_closed_loops_catch_a_pushed_payload_in_a_bevy_app_as_the_reduced_model_does() {
    println!("| controller | largest sway after the push ° (reduced) | trolley excursion m (reduced) | back below 0.1° after s (reduced) |");
    for (label, name) in SHIPPED {
        let full = pushed_in_a_bevy_app(name, 60.0);
        let spec = scenario::load(std::path::Path::new(&format!("assets/scenarios/{name}.toml"))).unwrap().controllers[0].clone();
        let reduced = run_reduced_pushed(&spec, 60.0, 40.0, 500.0);
        let after = |rows: &[(f64, f64, f64)]| {
            let x0 = rows.iter().rfind(|r| r.0 <= 40.0).unwrap().1;
            let post: Vec<&(f64, f64, f64)> = rows.iter().filter(|r| r.0 > 40.0).collect();
            let sway = post.iter().fold(0.0f64, |m, r| m.max(r.2.abs()));
            let excursion = post.iter().fold(0.0f64, |m, r| m.max((r.1 - x0).abs()));
            let settle = post.iter().rposition(|r| r.2.abs() >= 0.1).map_or(0.0, |i| post[i].0 - 40.0);
            (sway, excursion, settle, post.last().unwrap().2.abs())
        };
        let (sf, xf, tf, endf) = after(&full);
        let (sr, xr, tr, _) = after(&reduced);
        println!("| {label} | {sf:.3} ({sr:.3}) | {xf:.3} ({xr:.3}) | {tf:.1} ({tr:.1}) |");
        assert!((sf / sr - 1.0).abs() < 0.05, "{label}: largest sway {sf}° vs reduced {sr}°");
        if spec.kind.is_shaper() {
            assert!(endf > 1.0, "{label}: an open loop cannot damp the push; sway at the end {endf}°");
        } else {
            assert!((xf / xr - 1.0).abs() < 0.1, "{label}: excursion {xf} m vs reduced {xr} m");
            assert!((tf - tr).abs() < 0.5 && tf < 15.0, "{label}: settles after {tf} s vs reduced {tr} s");
        }
    }
}

/// The reduced model of [`run_reduced`] with a push of `impulse` N·s on
/// the payload at `at` s: (t, x, θ in degrees).
#[cfg(feature = "app")]
fn run_reduced_pushed(c: &Controller, duration: f64, at: f64, impulse: f64) -> Vec<(f64, f64, f64)> {
    let crane = OverheadCrane::with_rope_mass(500.0, 1000.0, 10.3, density(), 10.0).unwrap();
    let sampled = Sampled { inner: c.build().unwrap(), period: c.sample_time, next: 0.0, last: None };
    let mut lp = OverheadCraneLoop::new(crane, sampled, 0.0, 500.0 * 60.0, c.max_force).unwrap();
    let mut rows = Vec::new();
    let mut pushed = false;
    while lp.state.t < duration - 1e-9 {
        if !pushed && lp.state.t >= at - 1e-9 {
            lp.push_payload(impulse).unwrap();
            pushed = true;
        }
        lp.step(1e-3).unwrap();
        rows.push((lp.state.t, lp.state.q[0], lp.state.q[1].to_degrees()));
    }
    rows
}
