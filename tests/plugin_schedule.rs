//! Scheduling as bevy_rapier does it (issue 11): the cable systems in the
//! schedule the user chooses, the cable step taken from rapier's
//! `TimestepMode`, the systems placed by hand, and clear refusals of what
//! the plugin cannot follow (another schedule than rapier's, an
//! interpolated timestep, a body in another rapier context). And what a
//! game does to rapier's `RapierConfiguration` at run time: pausing the
//! physics pauses the cables, a new gravity reaches them.

#[path = "common/plugin_app.rs"]
mod plugin_app;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeSection;
use bevy_rapier_cable::plugin::*;
use std::time::Duration;

const L: f32 = 10.0;
const R: f32 = 0.3;
const M: f32 = 100.0;
const EA: f64 = 1e8;

/// A bare app with the given rapier and cable plugins (no `finish` yet).
fn app_with(rapier: RapierPhysicsPlugin<NoUserData>, cables: CablePlugin, time: TimeUpdateStrategy) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin, rapier, cables));
    app.insert_resource(time);
    app
}

fn ready(mut app: App) -> App {
    app.finish();
    app.cleanup();
    app
}

/// A 100 kg ball on a light 10 m rope pinned at the origin, hanging at rest
/// with the rope unstretched. Returns (payload, cable).
fn spawn_hanging(app: &mut App, extra: impl Bundle) -> (Entity, Entity) {
    let w = app.world_mut();
    let payload = w.spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, -(L + R), 0.0), Collider::ball(R), ColliderMassProperties::Mass(M), extra)).id();
    let section = RopeSection { linear_density: 0.01, ea: EA, ei: 1e-3, ei2: 1e-3, gj: 1e-3, min_breaking_load: 0.0 };
    let d = CableDescriptor::new(L).segments(20).section(section, 0.01).end(CableAnchor::body(payload, Vec3::Y * R));
    let cable = w.spawn(d).id();
    (payload, cable)
}

/// Spawns the hanging payload pushed at 1 m/s along x, runs `frames`
/// updates without an error, and returns the payload's position and the
/// cable's nodes and time.
fn swing(mut app: App, frames: usize) -> (Vec3, Vec<Vec3>, f64) {
    let (payload, cable) = spawn_hanging(&mut app, Velocity::linear(Vec3::X));
    let errs = plugin_app::errors_over(&mut app, frames);
    assert!(errs.is_empty(), "{errs:?}");
    let state = app.world().get::<CableState>(cable).expect("built and read out").clone();
    (app.world().get::<Transform>(payload).unwrap().translation, state.nodes, state.time)
}

fn errors(app: &App) -> Vec<CableError> {
    app.world().resource::<Messages<CableError>>().iter_current_update_messages().cloned().collect()
}

/// The payload settles (rope damped by its own waves is not needed: it
/// starts at rest on an unstretched rope, so it oscillates axially about
/// the static stretch m g L/EA); the time-averaged height over the last
/// frames is that static position.
fn mean_height(app: &mut App, payload: Entity, frames: usize) -> f64 {
    let mut sum = 0.0;
    for _ in 0..frames {
        app.update();
        sum += app.world().get::<Transform>(payload).unwrap().translation.y as f64;
    }
    sum / frames as f64
}

/// bevy_rapier's own default: physics in `PostUpdate` with
/// `TimestepMode::Variable`. The cables, put in `PostUpdate` too, advance
/// by exactly the time rapier advances each frame (`min(Δt · scale,
/// max_dt)` in f32), and the payload hangs where the rope's stretch puts
/// it.
#[test]
fn cables_in_post_update_follow_rapier_variable_timestep() {
    let frame = Duration::from_secs_f64(1.0 / 50.0);
    let mut app = ready(app_with(
        RapierPhysicsPlugin::<NoUserData>::default(),
        CablePlugin::default().in_schedule(PostUpdate),
        TimeUpdateStrategy::ManualDuration(frame),
    ));
    let (payload, cable) = spawn_hanging(&mut app, ());
    let errs = plugin_app::errors_over(&mut app, 2);
    assert!(errs.is_empty(), "{errs:?}");
    let t0 = app.world().get::<CableSim>(cable).expect("cable built in PostUpdate").cable.time();
    let frames = 200;
    let y = mean_height(&mut app, payload, frames);
    let sim = app.world().get::<CableSim>(cable).unwrap();
    // Rapier advances min(Δt · 1, 1/60) per frame: here 1/60 s (Δt = 1/50 s
    // is longer than max_dt).
    let h = (frame.as_secs_f32() * 1.0).min(1.0 / 60.0) as f64;
    let elapsed = sim.cable.time() - t0;
    println!("cable time advanced {elapsed} s in {frames} frames; rapier's step {h} s; mean payload height {y:.6} m");
    assert!((elapsed - frames as f64 * h).abs() < 1e-9, "cable time {elapsed} vs {}", frames as f64 * h);
    let stretch = M as f64 * 9.81 * L as f64 / EA;
    let y_ref = -((L + R) as f64) - stretch;
    assert!((y - y_ref).abs() < 0.2 * stretch + 1e-5, "payload at {y} vs {y_ref}");
    assert!(!sim.failed);
}

/// `TimestepMode::Fixed { dt: 1/60 }` with Bevy's default fixed clock
/// (64 Hz): rapier steps 1/60 s per fixed step, and so do the cables (not
/// the 1/64 s of `Time<Fixed>`): the two cannot drift apart.
#[test]
fn the_cable_step_is_rapier_fixed_dt_not_the_schedule_delta() {
    let mut app = app_with(RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default(), TimeUpdateStrategy::FixedTimesteps(1));
    let dt = 1.0f32 / 60.0;
    app.insert_resource(TimestepMode::Fixed { dt, substeps: 1 });
    let mut app = ready(app);
    assert_eq!(app.world().resource::<Time<Fixed>>().timestep(), Duration::from_micros(15625), "Bevy's default 64 Hz");
    let (_, cable) = spawn_hanging(&mut app, ());
    let errs = plugin_app::errors_over(&mut app, 3);
    assert!(errs.is_empty(), "{errs:?}");
    let t0 = app.world().get::<CableSim>(cable).unwrap().cable.time();
    plugin_app::errors_over(&mut app, 64);
    let elapsed = app.world().get::<CableSim>(cable).unwrap().cable.time() - t0;
    println!("64 fixed steps: cable advanced {elapsed} s (rapier: 64 × {dt} s)");
    assert!((elapsed - 64.0 * dt as f64).abs() < 1e-9, "{elapsed}");
}

/// `TimestepMode::Interpolated` (a varying number of rapier steps per
/// frame) is refused by name when a cable is created, as a configuration
/// error; the cable is not built.
#[test]
fn an_interpolated_timestep_is_refused_by_name() {
    let mut app = app_with(RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default(), TimeUpdateStrategy::FixedTimesteps(1));
    app.insert_resource(TimestepMode::Interpolated { dt: 1.0 / 64.0, time_scale: 1.0, substeps: 1 });
    let mut app = ready(app);
    let (_, cable) = spawn_hanging(&mut app, ());
    let errs = plugin_app::errors_over(&mut app, 3);
    println!("{}", errs.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"));
    assert_eq!(errs.len(), 1, "{errs:?}");
    assert_eq!((errs[0].entity, errs[0].kind), (cable, CableErrorKind::Configuration));
    assert!(errs[0].message.contains("TimestepMode::Interpolated"), "{}", errs[0]);
    assert!(app.world().get::<CableSim>(cable).is_none());
}

/// Rapier in `PostUpdate` (its default) and the cables in `FixedUpdate`
/// (theirs): the cables could not be ordered around rapier's step, so
/// every cable is refused with a message that says how to fix it.
#[test]
fn cables_outside_rapier_schedule_are_refused_with_the_fix() {
    let mut app = ready(app_with(RapierPhysicsPlugin::<NoUserData>::default(), CablePlugin::default(), TimeUpdateStrategy::FixedTimesteps(1)));
    let (_, cable) = spawn_hanging(&mut app, ());
    let errs = plugin_app::errors_over(&mut app, 3);
    println!("{}", errs.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"));
    assert_eq!(errs.len(), 1, "{errs:?}");
    assert_eq!((errs[0].entity, errs[0].kind), (cable, CableErrorKind::Configuration));
    assert!(errs[0].message.contains("not in that schedule") && errs[0].message.contains("in_fixed_schedule"), "{}", errs[0]);
    assert!(app.world().get::<CableSim>(cable).is_none());
}

/// A payload in a second rapier context: the plugin couples with the
/// default context only, and says so, naming the body and the context
/// (instead of reading another body with the same handle).
#[test]
fn a_body_in_another_rapier_context_is_refused_by_name() {
    let mut app =
        ready(app_with(RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default(), TimeUpdateStrategy::FixedTimesteps(1)));
    app.update();
    let other = app.world_mut().spawn(RapierContextSimulation::default()).id();
    let (payload, cable) = spawn_hanging(&mut app, RapierContextEntityLink(other));
    let errs = plugin_app::errors_over(&mut app, 3);
    println!("{}", errs.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"));
    assert_eq!(errs.len(), 1, "{errs:?}");
    assert_eq!((errs[0].entity, errs[0].kind), (cable, CableErrorKind::Configuration));
    let m = &errs[0].message;
    assert!(m.contains(&format!("{payload}")) && m.contains(&format!("{other}")) && m.contains("default rapier context"), "{m}");
}

/// `with_default_system_setup(false)`: the app places the cable systems
/// itself ([`CablePlugin::get_systems`]), here in `FixedUpdate` around
/// rapier's sets as the plugin would, and the payload hangs as with the
/// default setup, bit for bit.
#[test]
fn systems_placed_by_hand_run_like_the_default_setup() {
    let hang = |manual: bool| {
        let cables = CablePlugin::default().with_default_system_setup(!manual);
        let mut app = app_with(RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), cables, TimeUpdateStrategy::FixedTimesteps(1));
        app.insert_resource(TimestepMode::Fixed { dt: 1.0 / 64.0, substeps: 1 });
        if manual {
            app.configure_sets(FixedUpdate, (CableSystems::Init, CableSystems::Step).chain().after(PhysicsSet::SyncBackend).before(PhysicsSet::StepSimulation));
            app.configure_sets(FixedUpdate, CableSystems::WriteBodies.after(PhysicsSet::StepSimulation).before(PhysicsSet::Writeback));
            app.configure_sets(FixedUpdate, CableSystems::Readout.after(PhysicsSet::Writeback));
            for set in [CableSystems::Init, CableSystems::Step, CableSystems::WriteBodies, CableSystems::Readout] {
                app.add_systems(FixedUpdate, CablePlugin::get_systems(set));
            }
        }
        swing(ready(app), 60)
    };
    let (a, b) = (hang(false), hang(true));
    println!("default setup: payload {:?} at t = {}; by hand: {:?} at t = {}", a.0, a.2, b.0, b.2);
    assert!(a.2 > 0.5, "the cable ran: t = {}", a.2);
    assert!(a.0.x > 0.1, "the pushed payload swung: {:?}", a.0);
    assert_eq!(a, b);
}

/// Coupled sub-steps mean what `cablesim`'s `substeps` means: rapier and
/// the cables both step `dt / n`, `n` times per fixed step. A 64 Hz app
/// with `with_coupled_substeps(4)` gives the same bits as a 256 Hz app
/// stepped four times as often (a pushed payload swinging, 1 s).
#[test]
fn coupled_substeps_are_the_finer_fixed_step_bit_for_bit() {
    let run_with = |coupled: bool| {
        let (rapier, cables, hz, frames) = if coupled {
            (RapierPhysicsPlugin::<NoUserData>::default().in_schedule(CableSubstep), CablePlugin::default().with_coupled_substeps(4), 64.0, 64)
        } else {
            (RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default(), 256.0, 256)
        };
        let mut app = app_with(rapier, cables, TimeUpdateStrategy::FixedTimesteps(1));
        app.insert_resource(Time::<Fixed>::from_hz(hz));
        app.insert_resource(TimestepMode::Fixed { dt: 1.0 / 256.0, substeps: 1 });
        swing(ready(app), frames + 1)
    };
    let (a, b) = (run_with(true), run_with(false));
    println!("coupled sub-steps: payload {:?} at t = {}; fine fixed step: {:?} at t = {}", a.0, a.2, b.0, b.2);
    assert!(a.0.x > 0.5, "the payload swung: {:?}", a.0);
    assert_eq!(a, b);
}

/// A fixed-step app (rapier and the cables in `FixedUpdate`, 1/60 s, one
/// fixed step per update).
fn fixed_app() -> App {
    let mut app = app_with(RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default(), TimeUpdateStrategy::FixedTimesteps(1));
    app.insert_resource(Time::<Fixed>::from_hz(60.0));
    app.insert_resource(TimestepMode::Fixed { dt: 1.0 / 60.0, substeps: 1 });
    ready(app)
}

/// Edits the default rapier context's `RapierConfiguration`, as a game's
/// system would.
fn configure(app: &mut App, edit: impl Fn(&mut RapierConfiguration)) {
    let mut q = app.world_mut().query_filtered::<&mut RapierConfiguration, With<DefaultRapierContext>>();
    for mut c in q.iter_mut(app.world_mut()) {
        edit(&mut c);
    }
}

/// The payload's position and velocity, the cable's nodes and its time.
fn snapshot(app: &App, payload: Entity, cable: Entity) -> (Vec3, Vec3, Vec<Vec3>, f64) {
    let w = app.world();
    let state = w.get::<CableState>(cable).expect("built and read out");
    (w.get::<Transform>(payload).unwrap().translation, w.get::<Velocity>(payload).unwrap().linear, state.nodes.clone(), state.time)
}

/// A game's pause menu: `RapierConfiguration::physics_pipeline_active =
/// false`. Rapier then neither steps nor writes its bodies back, and the
/// cables stop with it: over 20 paused frames the swinging payload (a
/// carried body of the cable's solve), its velocity, the rope's nodes and
/// the cable's time stay as they were, bit for bit; resumed, the run goes
/// on bit for bit as the same run that never paused. (Before 2026-11-29
/// the cables kept stepping while rapier was paused: the cable's time ran
/// on by the paused frames.)
#[test]
fn pausing_rapier_pauses_the_cables_and_resuming_goes_on_bit_for_bit() {
    let (mut never, mut paused) = (fixed_app(), fixed_app());
    let (pn, cn) = spawn_hanging(&mut never, Velocity::linear(Vec3::X));
    let (pp, cp) = spawn_hanging(&mut paused, Velocity::linear(Vec3::X));
    for app in [&mut never, &mut paused] {
        let errs = plugin_app::errors_over(app, 31);
        assert!(errs.is_empty(), "{errs:?}");
    }
    let before = snapshot(&paused, pp, cp);
    configure(&mut paused, |c| c.physics_pipeline_active = false);
    let errs = plugin_app::errors_over(&mut paused, 20);
    assert!(errs.is_empty(), "{errs:?}");
    let during = snapshot(&paused, pp, cp);
    println!("paused 20 frames: payload {:?} → {:?}, cable time {} → {}", before.0, during.0, before.3, during.3);
    assert_eq!(before, during, "something moved while rapier was paused");
    configure(&mut paused, |c| c.physics_pipeline_active = true);
    for app in [&mut never, &mut paused] {
        let errs = plugin_app::errors_over(app, 30);
        assert!(errs.is_empty(), "{errs:?}");
    }
    let (a, b) = (snapshot(&never, pn, cn), snapshot(&paused, pp, cp));
    println!("after resuming: payload {:?} at t = {} (never paused: {:?} at t = {})", b.0, b.3, a.0, a.3);
    assert!(a.0.x > 0.5, "the payload swung: {:?}", a.0);
    assert_eq!(a, b);
}

/// A low-gravity level: `RapierConfiguration::gravity` changed at run time
/// reaches the cables at their next step, as it reaches rapier's bodies.
/// The 100 kg ball on the 10 m rope (a carried body: its weight is in the
/// cable's solve) hangs at rest; the rope's top carries the weight below
/// it, `(M + ρ L) g`, averaged over the last 30 frames: first with
/// rapier's default gravity, then 2 s after the switch to the Moon's
/// 1.62 m/s², within 1e-3 of each. (Before 2026-11-29 the cables kept the
/// gravity they were built with: the top still carried 982 N on the Moon.)
#[test]
fn a_new_rapier_gravity_reaches_the_cables() {
    let mut app = fixed_app();
    let (_, cable) = spawn_hanging(&mut app, ());
    let top_tension = |app: &mut App, frames: usize| {
        let mut sum = 0.0;
        for _ in 0..frames {
            app.update();
            assert!(errors(app).is_empty(), "{:?}", errors(app));
            sum += app.world().get::<CableState>(cable).unwrap().tensions[0] as f64;
        }
        sum / frames as f64
    };
    let mass = M as f64 + 0.01 * L as f64;
    let errs = plugin_app::errors_over(&mut app, 2);
    assert!(errs.is_empty(), "{errs:?}");
    top_tension(&mut app, 90);
    let earth = top_tension(&mut app, 30);
    configure(&mut app, |c| c.gravity = Vec3::new(0.0, -1.62, 0.0));
    top_tension(&mut app, 90);
    let moon = top_tension(&mut app, 30);
    let (g_earth, g_moon) = (9.81f32 as f64, 1.62f32 as f64);
    println!("top tension {earth:.3} N against (M + ρ L) g = {:.3} N; on the Moon {moon:.3} N against {:.3} N", mass * g_earth, mass * g_moon);
    assert!((earth / (mass * g_earth) - 1.0).abs() < 1e-3, "{earth}");
    assert!((moon / (mass * g_moon) - 1.0).abs() < 1e-3, "{moon}");
    assert_eq!(app.world().get::<CableSim>(cable).unwrap().cable.gravity(), bevy::math::DVec3::new(0.0, -g_moon, 0.0));
}
