//! The controls of `cablesim view` (`viewer::ViewerPlugin`), headless: a
//! scenario spawned with `add_scenario`, key presses sent as Bevy's
//! keyboard messages, one fixed step per update. Space pauses, N steps
//! exactly one frame while paused, `+` / `-` scale time, R starts the
//! file again from t = 0.

use bevy::input::keyboard::{Key, KeyboardInput};
use bevy::input::{ButtonState, InputPlugin};
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::plugin::scenario::{add_scenario, ScenarioRun};
use bevy_rapier_cable::plugin::CablePlugin;
use bevy_rapier_cable::scenario::load;
use bevy_rapier_cable::viewer::ViewerPlugin;
use std::path::Path;
use std::time::Duration;

/// The viewer's app without a window: hanging_payload.toml (dt = 1/60 s),
/// virtual time advancing by dt per update (one fixed step).
fn viewer() -> App {
    let sc = load(Path::new("assets/scenarios/hanging_payload.toml")).unwrap();
    let dt = sc.simulation.dt;
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin, InputPlugin, RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default()));
    app.add_plugins(ViewerPlugin);
    add_scenario(&mut app, sc).unwrap();
    app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(dt)));
    app.finish();
    app.cleanup();
    app.update();
    app
}

/// Presses and releases `key` over one update.
fn press(app: &mut App, key: KeyCode) {
    for state in [ButtonState::Pressed, ButtonState::Released] {
        app.world_mut().write_message(KeyboardInput {
            key_code: key,
            logical_key: Key::Unidentified(bevy::input::keyboard::NativeKey::Unidentified),
            state,
            text: None,
            repeat: false,
            window: Entity::PLACEHOLDER,
        });
        app.update();
    }
}

fn steps(app: &App) -> u64 {
    app.world().resource::<ScenarioRun>().steps
}

fn run(app: &mut App, updates: usize) {
    for _ in 0..updates {
        app.update();
    }
}

#[test]
fn space_pauses_n_steps_one_frame_r_restarts() {
    let mut app = viewer();
    run(&mut app, 10);
    let before = steps(&app);
    assert!(before >= 8, "the scenario runs: {before} frames");
    // Space: paused, no more frames.
    press(&mut app, KeyCode::Space);
    assert!(app.world().resource::<Time<Virtual>>().is_paused());
    let paused_at = steps(&app);
    run(&mut app, 10);
    assert_eq!(steps(&app), paused_at, "paused");
    // N (and `.`): exactly one frame each.
    press(&mut app, KeyCode::KeyN);
    run(&mut app, 3);
    assert_eq!(steps(&app), paused_at + 1, "N steps one frame");
    press(&mut app, KeyCode::Period);
    run(&mut app, 3);
    assert_eq!(steps(&app), paused_at + 2, ". steps one frame");
    // Space again: running.
    press(&mut app, KeyCode::Space);
    run(&mut app, 5);
    assert!(steps(&app) > paused_at + 2, "running again");
    // R: from t = 0 again, running.
    press(&mut app, KeyCode::KeyR);
    let run_state = app.world().resource::<ScenarioRun>();
    assert!(run_state.steps <= 2, "restarted: {} frames", run_state.steps);
    assert!(!app.world().resource::<Time<Virtual>>().is_paused());
}

#[test]
fn plus_and_minus_scale_time() {
    let mut app = viewer();
    press(&mut app, KeyCode::Equal);
    assert_eq!(app.world().resource::<Time<Virtual>>().relative_speed(), 2.0);
    press(&mut app, KeyCode::Minus);
    press(&mut app, KeyCode::NumpadSubtract);
    assert_eq!(app.world().resource::<Time<Virtual>>().relative_speed(), 0.5);
    // At half speed, 20 updates of dt are 10 frames (± the one in flight).
    let before = steps(&app);
    run(&mut app, 20);
    let frames = steps(&app) - before;
    assert!((9..=11).contains(&frames), "{frames} frames at half speed");
}
