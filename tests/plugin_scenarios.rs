//! Issue 10, item 1: every shipped scenario that the plugin can spawn,
//! run by `cablesim`'s runner (`sim::World`) and spawned into a headless
//! Bevy app with the plugin (`plugin::scenario::add_scenario`), gives the
//! same probe rows, bit for bit, at every frame. The scenarios the Bevy
//! side does not spawn yet are refused with an error naming the item.

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::plugin::scenario::{add_scenario, respawn_scenario, ScenarioRun};
use bevy_rapier_cable::plugin::CablePlugin;
use bevy_rapier_cable::scenario::{load, Scenario};
use bevy_rapier_cable::sim::{SimError, World};
use std::path::Path;

#[path = "common/scenario_run.rs"]
mod scenario_run;

fn frames(sc: &Scenario) -> u64 {
    (sc.simulation.duration / sc.simulation.dt).round() as u64
}

fn cablesim_rows(sc: &Scenario) -> Vec<(f64, Vec<f64>)> {
    let mut w = World::new(sc.clone()).unwrap_or_else(|e| panic!("{e}"));
    let mut rows = Vec::new();
    for _ in 0..frames(sc) {
        w.step().unwrap_or_else(|e| panic!("cablesim: {e}"));
        let mut row = Vec::new();
        w.sample(&mut row);
        rows.push((w.time, row));
    }
    rows
}

fn app() -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin, RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default()));
    app.insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    app
}

fn plugin_rows(sc: &Scenario) -> Result<Vec<(f64, Vec<f64>)>, SimError> {
    let mut app = app();
    add_scenario(&mut app, sc.clone())?;
    app.finish();
    app.cleanup();
    // The first update runs Startup and no fixed step (its delta is 0).
    app.update();
    // One update is one fixed step: a scenario sub-step.
    for _ in 0..frames(sc) * sc.simulation.substeps.unwrap_or(1).max(1) as u64 {
        app.update();
        if let Some((e, t, m)) = &app.world().resource::<ScenarioRun>().failed {
            panic!("plugin: cable {e} failed at t = {t}: {m}");
        }
    }
    Ok(app.world_mut().remove_resource::<ScenarioRun>().expect("the run").rows)
}

/// Names of the shipped scenarios.
fn shipped() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir("assets/scenarios")
        .expect("assets/scenarios")
        .filter_map(|e| e.ok()?.path().file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    names
}

/// Runs the shipped scenario `name` both ways over its whole duration and
/// compares every row, bit for bit.
fn compare(name: &str) {
    let sc = load(Path::new(&format!("assets/scenarios/{name}.toml"))).unwrap_or_else(|e| panic!("{e}"));
    compare_scenario(name, &sc);
}

/// Runs `sc` both ways and compares every row, bit for bit.
fn compare_scenario(name: &str, sc: &Scenario) {
    let plugin = plugin_rows(sc).unwrap_or_else(|e| panic!("{name}: {e}"));
    let cablesim = cablesim_rows(sc);
    assert_eq!(plugin.len(), cablesim.len(), "{name}: rows");
    assert!(!cablesim.is_empty() && !cablesim[0].1.is_empty(), "{name}: nothing compared");
    for (k, ((tp, p), (tc, c))) in plugin.iter().zip(&cablesim).enumerate() {
        assert_eq!(tp.to_bits(), tc.to_bits(), "{name}: time of row {k}");
        let differ: Vec<(usize, f64, f64)> =
            p.iter().zip(c).enumerate().filter(|(_, (a, b))| a.to_bits() != b.to_bits()).map(|(i, (a, b))| (i, *a, *b)).collect();
        assert!(differ.is_empty(), "{name}: row {k} (t = {tc} s) differs in columns (index, plugin, cablesim) {differ:?}");
    }
    println!("{name}: {} rows × {} columns identical", cablesim.len(), cablesim[0].1.len());
}

/// A shipped scenario's text with `from` replaced by `to` (which must
/// occur), parsed, and its duration cut to `duration` s.
fn variant(name: &str, from: &str, to: &str, duration: f64) -> Scenario {
    let base = std::fs::read_to_string(format!("assets/scenarios/{name}.toml")).expect("a shipped scenario");
    assert!(base.contains(from), "{name} no longer contains {from:?}: update this test");
    let mut sc = bevy_rapier_cable::scenario::parse(&base.replacen(from, to, 1), &format!("{name}_variant.toml")).unwrap_or_else(|e| panic!("{e}"));
    sc.simulation.duration = duration;
    sc
}

/// A rope laid by hand round a drum, springing onto it
/// (`edge_contact::a_rope_springing_onto_a_drum_from_rest_is_caught_by_its_contacts`):
/// its first contact search takes the nodes' accelerations from the
/// cable's consistent start acceleration, and the later ones from their
/// velocities' change, in a Bevy app as in `cablesim`, bit for bit.
#[test]
fn a_rope_springing_onto_a_drum_gives_the_same_rows() {
    let sc = bevy_rapier_cable::scenario::parse(&scenario_run::drum_scenario(0.5), "drum.toml").unwrap_or_else(|e| panic!("{e}"));
    compare_scenario("drum", &sc);
}

/// Drives in both runners (no shipped scenario has one): a velocity drive
/// on a trolley's rail (the chain's root sub-joint, driven by rapier's joint
/// motor law in both), and velocity and force drives on a joint rapier keeps
/// (`boom_hoist`'s boom foot).
#[test]
fn driven_joints_give_the_same_rows() {
    let rail =
        variant("trolley_kick", "axis = [1.0, 0.0, 0.0]", "axis = [1.0, 0.0, 0.0]\ndrive = { velocity = [[0, 0], [1, 0.5], [3, -0.3]], max_force = 2e3 }", 4.0);
    compare_scenario("trolley_kick + rail velocity drive", &rail);
    let slew = variant("boom_hoist", "axis = [0.0, 0.0, 1.0]", "axis = [0.0, 0.0, 1.0]\ndrive = { velocity = [[0, 0], [2, 0.05]], max_force = 5e6 }", 3.0);
    compare_scenario("boom_hoist + foot velocity drive", &slew);
    let luff = variant("boom_hoist", "axis = [0.0, 0.0, 1.0]", "axis = [0.0, 0.0, 1.0]\ndrive = { force = [[0, 0], [1, 2e5], [3, 1e5]] }", 3.0);
    compare_scenario("boom_hoist + foot force drive", &luff);
}

/// The shipped scenarios compared below, one test each.
const COMPARED: [&str; 36] = [
    "axial_bounce",
    "ball_hits_payload",
    "ball_on_rope",
    "bend_45",
    "boom_hoist",
    "cable_impact",
    "cantilever_end_moment",
    "cantilever_tip_load",
    "capstan_friction",
    "catenary",
    "collision_groups",
    "crane_pid",
    "crane_pid_incremental",
    "crane_pid_nonlinear",
    "crane_zv",
    "crane_zvd",
    "damped_drop",
    "hanging_chain",
    "hanging_payload",
    "hook_and_payload",
    "payload_set_down",
    "pendulum_60deg",
    "perf_swing_1000",
    "rope_crossing",
    "rope_on_ground",
    "rope_on_rope",
    "rope_on_slope",
    "rope_over_box",
    "rope_over_cylinder",
    "rope_round_post",
    "slack_rope_on_ground",
    "spin_up",
    "taut_string",
    "trolley_kick",
    "trolley_pendulum",
    "two_leg_sling",
];

/// A scenario added to `assets/scenarios` must be added here too.
#[test]
fn every_shipped_scenario_is_compared() {
    assert_eq!(shipped(), COMPARED.iter().map(|s| s.to_string()).collect::<Vec<_>>());
}

macro_rules! same_rows {
    ($($name:ident),* $(,)?) => {
        $(
            #[test]
            fn $name() {
                compare(stringify!($name));
            }
        )*
    };
}

same_rows!(
    axial_bounce,
    ball_hits_payload,
    ball_on_rope,
    bend_45,
    boom_hoist,
    cable_impact,
    capstan_friction,
    cantilever_end_moment,
    cantilever_tip_load,
    catenary,
    collision_groups,
    crane_pid,
    crane_pid_incremental,
    crane_pid_nonlinear,
    crane_zv,
    crane_zvd,
    damped_drop,
    hanging_chain,
    hanging_payload,
    hook_and_payload,
    payload_set_down,
    pendulum_60deg,
    perf_swing_1000,
    rope_crossing,
    rope_on_ground,
    rope_on_rope,
    rope_on_slope,
    rope_over_box,
    rope_over_cylinder,
    rope_round_post,
    slack_rope_on_ground,
    spin_up,
    taut_string,
    trolley_kick,
    trolley_pendulum,
    two_leg_sling,
);

/// What the Bevy side does not spawn yet is refused with an error that
/// names the item and where it is: a force table on a trolley's rail (it
/// acts in the chain in cablesim; the plugin drives a rail only through the
/// joint motor), and a second joint on the same body2 (bevy_rapier holds
/// one joint per entity).
#[test]
fn what_a_bevy_app_cannot_run_yet_is_refused_by_name() {
    let base = std::fs::read_to_string("assets/scenarios/trolley_kick.toml").expect("trolley_kick");
    let driven = base.replace("axis = [1.0, 0.0, 0.0]", "axis = [1.0, 0.0, 0.0]\ndrive = { force = [[0, 0], [1, 500]] }");
    assert_ne!(driven, base, "the rail's axis line moved: update this test");
    let sc = bevy_rapier_cable::scenario::parse(&driven, "driven.toml").unwrap_or_else(|e| panic!("{e}"));
    World::new(sc.clone()).unwrap_or_else(|e| panic!("cablesim runs it: {e}"));
    let e = plugin_rows(&sc).expect_err("a force table on a rail in a Bevy app").to_string();
    assert!(e.starts_with("driven.toml:") && e.contains("the `force` drive of joint `rail`, a trolley's rail") && e.contains("not supported yet"), "{e}");
    let second = format!(
        "{base}\n[[joint]]\nname = \"stop\"\ntype = \"spherical\"\nbody1 = \"world\"\nbody2 = \"trolley\"\nanchor1 = [0.0, 0.0, 0.0]\nanchor2 = [0.0, 0.0, 0.0]\n"
    );
    let sc = bevy_rapier_cable::scenario::parse(&second, "second.toml").unwrap_or_else(|e| panic!("{e}"));
    let e = plugin_rows(&sc).expect_err("two joints on one body2").to_string();
    assert!(e.contains("joint `stop`") && e.contains("body `trolley` is body2 of joint `rail` too"), "{e}");
}

/// `respawn_scenario` (the viewer's reset) starts the scenario again from
/// t = 0: after some frames, a respawn of the same file gives the same rows
/// again, bit for bit (boom_hoist: a world joint, a rapier-kept boom,
/// sub-steps; trolley_kick: a trolley's driven rail). A scenario the plugin
/// refuses leaves the running one as it was.
#[test]
fn respawn_starts_the_scenario_again() {
    for name in ["boom_hoist", "trolley_kick"] {
        let sc = load(Path::new(&format!("assets/scenarios/{name}.toml"))).unwrap_or_else(|e| panic!("{e}"));
        let updates = 30 * sc.simulation.substeps.unwrap_or(1).max(1) as u64;
        let mut app = app();
        add_scenario(&mut app, sc.clone()).unwrap();
        app.finish();
        app.cleanup();
        app.update();
        let run = |app: &mut App| {
            for _ in 0..updates {
                app.update();
            }
            let run = app.world().resource::<ScenarioRun>();
            assert!(run.failed.is_none(), "{name}: {:?}", run.failed);
            run.rows.clone()
        };
        let first = run(&mut app);
        assert_eq!(first.len(), 30, "{name}");
        let count = |app: &mut App| app.world_mut().query_filtered::<(), Or<(With<RigidBody>, With<Name>)>>().iter(app.world()).count();
        let entities = count(&mut app);
        respawn_scenario(app.world_mut(), sc.clone()).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(app.world().resource::<ScenarioRun>().time, 0.0);
        let again = run(&mut app);
        assert_eq!(again.len(), 30, "{name}");
        for (k, ((t0, a), (t1, b))) in first.iter().zip(&again).enumerate() {
            assert_eq!(t0.to_bits(), t1.to_bits(), "{name}: time of row {k}");
            for (x, y) in a.iter().zip(b) {
                assert!(x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()), "{name}: row {k}: {a:?} then {b:?}");
            }
        }
        // The old bodies and cables went: as many now as before the respawn.
        assert_eq!(count(&mut app), entities, "{name}: bodies and cables");
        // A refused scenario (two joints on one body2) keeps the running one.
        let mut bad = sc.clone();
        if let Some(j) = sc.joints.first() {
            let mut twin = j.clone();
            twin.name = format!("{}_twin", j.name);
            bad.joints.push(twin);
            let time = app.world().resource::<ScenarioRun>().time;
            assert!(respawn_scenario(app.world_mut(), bad).is_err(), "{name}: the twin joint is refused");
            assert_eq!(app.world().resource::<ScenarioRun>().time, time, "{name}: the running scenario is kept");
        }
    }
}
