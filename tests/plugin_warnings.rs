//! Warnings the plugin logs (this file installs its own logger, so it is
//! its own test binary): at a cable's creation, and when a carried body is
//! moved by hand.

#[path = "common/plugin_app.rs"]
mod plugin_app;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::plugin::*;
use std::sync::Mutex;

static LOGGED: Mutex<Vec<String>> = Mutex::new(Vec::new());

struct Capture;

impl log::Log for Capture {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.level() <= log::Level::Warn
    }
    fn log(&self, r: &log::Record) {
        if self.enabled(r.metadata()) {
            LOGGED.lock().unwrap().push(format!("{}: {}", r.level(), r.args()));
        }
    }
    fn flush(&self) {}
}

/// Installs the capturing logger once for the binary's tests.
fn install_logger() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        log::set_boxed_logger(Box::new(Capture)).unwrap();
        log::set_max_level(log::LevelFilter::Warn);
    });
}

/// A 10 kg body held by a revolute joint (so rapier keeps it) at the start
/// of 10 m of 20 mm steel rope: the cable couples it explicitly, with
/// `k h²/m` ≈ 1 000 at 1/60 s. The plugin says so once, at creation, with
/// the number of coupled sub-steps that would bring it to 1, as `cablesim`
/// does; a payload the cable carries gets no such warning.
/// A 20 mm steel rope of `length` m from the origin of body `from` to the
/// point `at` of body `to` (its frame, m).
fn steel_rope(length: f32, from: Entity, to: Entity, at: Vec3) -> CableDescriptor {
    CableDescriptor::new(length).material(RopeMaterial::steel_6x36_iwrc(0.02)).start(CableAnchor::body(from, Vec3::ZERO)).end(CableAnchor::body(to, at))
}

#[test]
fn an_explicit_coupling_likely_unstable_is_warned_at_creation() {
    install_logger();
    let mut app = plugin_app::headless_app(1.0 / 60.0);
    let w = app.world_mut();
    let post = w.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, 10.0, 0.0))).id();
    let arm = w
        .spawn((
            RigidBody::Dynamic,
            Transform::from_xyz(1.0, 10.0, 0.0),
            Collider::ball(0.1),
            ColliderMassProperties::Mass(10.0),
            ImpulseJoint::new(post, RevoluteJointBuilder::new(Vec3::Z).local_anchor1(Vec3::new(1.0, 0.0, 0.0))),
        ))
        .id();
    let payload = w.spawn((RigidBody::Dynamic, Transform::from_xyz(1.0, -0.3, 0.0), Collider::ball(0.3), ColliderMassProperties::Mass(100.0))).id();
    w.spawn(steel_rope(10.0, arm, payload, Vec3::Y * 0.3));
    for _ in 0..3 {
        app.update();
    }
    let logged = LOGGED.lock().unwrap().clone();
    println!("{logged:#?}");
    let warned: Vec<&String> = logged.iter().filter(|l| l.contains("coupled explicitly")).collect();
    assert_eq!(warned.len(), 1, "{logged:?}");
    assert!(
        warned[0].starts_with("WARN")
            && warned[0].contains("its start on body")
            && warned[0].contains("k·h²/m")
            && warned[0].contains("with_coupled_substeps("),
        "{}",
        warned[0]
    );
}

/// A game "teleports" a crate hanging on a rope by writing its `Transform`.
/// A carried body's pose is the cable's: the move is undone at the next
/// step, and the plugin says so once, naming the body, the place and the
/// way to do it instead. Nothing is logged while nobody moves it (also with
/// the crate swinging), nor for a second move.
#[test]
fn a_carried_body_moved_by_hand_is_warned_once() {
    install_logger();
    let mut app = plugin_app::headless_app(1.0 / 60.0);
    let w = app.world_mut();
    let hook = w.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, 10.0, 0.0))).id();
    let crate_ = w
        .spawn((
            RigidBody::Dynamic,
            Transform::from_xyz(0.0, 4.5, 0.0),
            Collider::cuboid(0.5, 0.5, 0.5),
            ColliderMassProperties::Mass(500.0),
            Velocity::linear(Vec3::X),
        ))
        .id();
    w.spawn(steel_rope(5.0, hook, crate_, Vec3::Y * 0.5));
    let moved = || LOGGED.lock().unwrap().iter().filter(|l| l.contains("was moved")).cloned().collect::<Vec<String>>();
    for _ in 0..60 {
        app.update();
    }
    assert!(moved().is_empty(), "{:?}", moved());
    let x = |app: &App| app.world().get::<Transform>(crate_).unwrap().translation.x;
    let before = x(&app);
    for _ in 0..2 {
        app.world_mut().get_mut::<Transform>(crate_).unwrap().translation.x += 1.0;
        for _ in 0..3 {
            app.update();
        }
    }
    let logged = moved();
    println!("{logged:#?}; crate at x = {} (before the moves {before})", x(&app));
    assert_eq!(logged.len(), 1, "{logged:?}");
    assert!(logged[0].starts_with("WARN") && logged[0].contains(&format!("{crate_}")) && logged[0].contains("the move is undone"), "{}", logged[0]);
    assert!((x(&app) - before).abs() < 0.2, "the crate stayed on its rope: {} vs {before}", x(&app));
}

/// A cable that stops hands its payload back to rapier, which then falls:
/// that is not a move by hand, and is not warned as one.
#[test]
fn the_falling_payload_of_a_stopped_cable_is_not_warned_as_moved() {
    install_logger();
    let mut app = plugin_app::headless_app(1.0 / 60.0);
    let w = app.world_mut();
    // (Entities numbered apart from the other tests' in this binary, whose
    // messages share the log.)
    for _ in 0..40 {
        w.spawn_empty();
    }
    let hook = w.spawn((RigidBody::KinematicPositionBased, Transform::from_xyz(0.0, 10.0, 0.0), Collider::ball(0.05))).id();
    let crate_ = w.spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, 4.5, 0.0), Collider::cuboid(0.5, 0.5, 0.5), ColliderMassProperties::Mass(500.0))).id();
    w.spawn(steel_rope(5.0, hook, crate_, Vec3::Y * 0.5));
    for _ in 0..30 {
        app.update();
    }
    // The hook made dynamic stops the cable (a `Configuration` error).
    app.world_mut().entity_mut(hook).insert((RigidBody::Dynamic, ColliderMassProperties::Mass(50.0)));
    for _ in 0..30 {
        app.update();
    }
    let y = app.world().get::<Transform>(crate_).unwrap().translation.y;
    let moved = LOGGED.lock().unwrap().iter().filter(|l| l.contains("was moved") && l.contains(&format!("{crate_}"))).cloned().collect::<Vec<String>>();
    println!("the crate fell to y = {y} m; warnings: {moved:?}");
    assert!(y < 3.5, "the payload of the stopped cable did not fall: y = {y}");
    assert!(moved.is_empty(), "{moved:?}");
}
