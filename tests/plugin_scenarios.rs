//! Issue 10, item 1: every shipped scenario that the plugin can spawn,
//! run by `cablesim`'s runner (`sim::World`) and spawned into a headless
//! Bevy app with the plugin (`plugin::scenario::add_scenario`), gives the
//! same probe rows, bit for bit, at every frame. The scenarios the Bevy
//! side does not spawn yet are refused with an error naming the item.

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::plugin::scenario::{add_scenario, ScenarioRun};
use bevy_rapier_cable::plugin::CablePlugin;
use bevy_rapier_cable::scenario::{load, Scenario};
use bevy_rapier_cable::sim::{SimError, World};
use std::path::Path;

/// Simulated time compared per scenario, s (the whole run when shorter).
const SPAN: f64 = 3.0;

fn frames(sc: &Scenario) -> u64 {
    (sc.simulation.duration.min(SPAN) / sc.simulation.dt).round() as u64
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
    for _ in 0..frames(sc) {
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

/// What the Bevy side does not spawn yet, and the item its refusal names.
const NOT_YET: [(&str, &str); 1] = [("boom_hoist", "substeps = 12 (above 1)")];

#[test]
fn every_shipped_scenario_gives_the_same_rows_in_cablesim_and_in_a_bevy_app() {
    let mut same = Vec::new();
    for name in shipped() {
        let sc = load(Path::new(&format!("assets/scenarios/{name}.toml"))).unwrap_or_else(|e| panic!("{e}"));
        let plugin = plugin_rows(&sc);
        if let Some((_, what)) = NOT_YET.iter().find(|(n, _)| *n == name) {
            let e = plugin.expect_err("the Bevy side now spawns this scenario: compare it and update NOT_YET and the docs");
            let text = e.to_string();
            assert!(matches!(e, SimError::Unsupported { .. }) && text.contains(what) && text.contains("not supported yet"), "{name}: {text}");
            println!("{name}: refused: {text}");
            continue;
        }
        let plugin = plugin.unwrap_or_else(|e| panic!("{name}: {e}"));
        let cablesim = cablesim_rows(&sc);
        assert_eq!(plugin.len(), cablesim.len(), "{name}: rows");
        assert!(!cablesim.is_empty() && !cablesim[0].1.is_empty(), "{name}: nothing compared");
        for (k, ((tp, p), (tc, c))) in plugin.iter().zip(&cablesim).enumerate() {
            assert_eq!(tp.to_bits(), tc.to_bits(), "{name}: time of row {k}");
            let differ: Vec<(usize, f64, f64)> =
                p.iter().zip(c).enumerate().filter(|(_, (a, b))| a.to_bits() != b.to_bits()).map(|(i, (a, b))| (i, *a, *b)).collect();
            assert!(differ.is_empty(), "{name}: row {k} (t = {tc} s) differs in columns (index, plugin, cablesim) {differ:?}");
        }
        println!("{name}: {} rows × {} columns identical", cablesim.len(), cablesim[0].1.len());
        same.push(name);
    }
    assert_eq!(same.len() + NOT_YET.len(), shipped().len());
}
