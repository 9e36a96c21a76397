//! Despawning in a Bevy app (issue 11 "Lifecycle", and the guide's
//! newcomer failure): a cable whose carried body is despawned is removed
//! (it cannot hold a phantom load), and so is one whose end's body (a hook)
//! is despawned, its payload falling free; a despawned cable gives its
//! bodies back to rapier as their components say; a despawned sling leg
//! releases its island; a hook made dynamic is refused by name; a cable
//! that stops hands its payload back to rapier. Nothing panics.

#[path = "common/plugin_app.rs"]
mod plugin_app;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::preset;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::plugin::*;

const DT: f32 = 1.0 / 60.0;
const G: f32 = 9.81;

fn rope(start: CableAnchor, end: CableAnchor) -> CableDescriptor {
    CableDescriptor::from_section(5.0, 20, RopeMaterial::custom(preset("steel_wire_rope_6x36_iwrc", 0.016).unwrap(), 0.016), start, end)
}

fn hang(app: &mut App, extra: impl Bundle) -> (Entity, Entity) {
    let w = app.world_mut();
    let payload = w
        .spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, -5.2, 0.0), Collider::ball(0.2), ColliderMassProperties::Mass(200.0), Velocity::default(), extra))
        .id();
    let cable =
        w.spawn(rope(CableAnchor::World { point: Vec3::ZERO, clamp: false }, CableAnchor::Body { entity: payload, anchor: Vec3::Y * 0.2, clamp: false })).id();
    (payload, cable)
}

fn run(app: &mut App, frames: usize) {
    for _ in 0..frames {
        app.update();
    }
}

#[test]
fn a_cable_whose_payload_is_despawned_is_removed() {
    let mut app = plugin_app::headless_app(DT);
    let (payload, cable) = hang(&mut app, ());
    run(&mut app, 30);
    assert!(app.world().get::<CableSim>(cable).is_some());
    assert!(app.world().get::<CableState>(cable).unwrap().tensions[0] > 1900.0, "the rope holds the payload");
    app.world_mut().despawn(payload);
    run(&mut app, 2);
    assert!(app.world().get::<CableSim>(cable).is_none(), "the cable still holds a despawned payload");
    assert!(app.world().get::<CableDescriptor>(cable).is_none(), "it would be rebuilt");
    assert!(app.world().get_entity(cable).is_ok(), "the entity itself stays the user's");
    run(&mut app, 10);
}

#[test]
fn a_despawned_cable_gives_its_payload_back_to_rapier_with_its_gravity_scale() {
    for scale in [1.0f32, 0.5] {
        let mut app = plugin_app::headless_app(DT);
        let (payload, cable) = hang(&mut app, GravityScale(scale));
        run(&mut app, 30);
        let v0 = app.world().get::<Velocity>(payload).unwrap().linear;
        assert!(v0.length() < 0.05, "hanging at rest: {v0}");
        app.world_mut().despawn(cable);
        run(&mut app, 30);
        let v = app.world().get::<Velocity>(payload).unwrap().linear;
        // Free fall for 30 steps of DT under scale·g (rapier's symplectic Euler
        // gives exactly n·h·g on the velocity).
        let expected = v0.y - scale * G * 30.0 * DT;
        println!("gravity scale {scale}: velocity after 0.5 s of free fall {v} (expected y {expected})");
        assert!((v.y - expected).abs() < 1e-3 * expected.abs() && v.x.abs() < 1e-4, "scale {scale}: {v} against {expected}");
    }
}

/// The payload hanging from a kinematic hook instead of a world point:
/// (app, hook, payload, cable), run for 0.5 s.
fn on_hook() -> (App, Entity, Entity, Entity) {
    let mut app = plugin_app::headless_app(DT);
    let w = app.world_mut();
    let hook = w.spawn((RigidBody::KinematicPositionBased, Transform::from_xyz(0.0, 0.0, 0.0), Collider::ball(0.05))).id();
    let payload =
        w.spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, -5.2, 0.0), Collider::ball(0.2), ColliderMassProperties::Mass(200.0), Velocity::default())).id();
    let cable = w.spawn(rope(CableAnchor::body(hook, Vec3::ZERO), CableAnchor::Body { entity: payload, anchor: Vec3::Y * 0.2, clamp: false })).id();
    run(&mut app, 30);
    assert!(app.world().get::<CableState>(cable).unwrap().tensions[0] > 1900.0, "the rope holds the payload");
    (app, hook, payload, cable)
}

/// Despawning the hook a cable hangs from removes the cable, as rapier
/// drops a joint whose body is despawned: the payload is a rapier body
/// again and falls free (exactly `n h g` on its velocity after n steps).
/// (Before 2026-11-29 the rope went on hanging from where the hook had
/// been, holding the payload in the air.)
#[test]
fn a_cable_whose_hook_is_despawned_is_removed_and_its_payload_falls() {
    let (mut app, hook, payload, cable) = on_hook();
    let v0 = app.world().get::<Velocity>(payload).unwrap().linear;
    app.world_mut().despawn(hook);
    run(&mut app, 30);
    assert!(app.world().get::<CableSim>(cable).is_none() && app.world().get::<CableDescriptor>(cable).is_none(), "the cable was not removed");
    let v = app.world().get::<Velocity>(payload).unwrap().linear;
    let expected = v0.y - G * 30.0 * DT;
    println!("the payload's velocity 0.5 s after the hook was despawned: {v} (free fall: y {expected})");
    assert!((v.y - expected).abs() < 1e-3 * expected.abs() && v.x.abs() < 1e-4, "{v} against {expected}");
}

/// A hook made dynamic while a cable hangs from it: the cable follows a
/// fixed or kinematic body without pulling it, so it stops before its next
/// step with one `Configuration` error naming the hook. (Before
/// 2026-11-29 it went on following the hook as it fell.)
#[test]
fn a_hook_made_dynamic_stops_its_cable_by_name() {
    let (mut app, hook, _, cable) = on_hook();
    app.world_mut().entity_mut(hook).insert((RigidBody::Dynamic, ColliderMassProperties::Mass(50.0)));
    let errors = plugin_app::errors_over(&mut app, 3);
    println!("{errors:?}");
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert_eq!((errors[0].entity, errors[0].kind), (cable, CableErrorKind::Configuration));
    assert!(errors[0].message.contains(&format!("{hook}")) && errors[0].message.contains("was made `RigidBody::Dynamic`"), "{}", errors[0]);
    assert!(app.world().get::<CableSim>(cable).unwrap().failed);
}

/// A cable that stops (here: its hook made dynamic) no longer holds its
/// payload: the payload is a rapier body again, with its gravity, and
/// falls free from the velocity it had (exactly `n h g` after n steps).
/// Before 2026-11-29 it hung frozen where the rope had left it (gravity
/// off, put back on the stopped cable's pose at every step).
#[test]
fn a_stopped_cable_hands_its_payload_back_to_rapier() {
    let (mut app, hook, payload, cable) = on_hook();
    let v0 = app.world().get::<Velocity>(payload).unwrap().linear;
    assert!(v0.length() < 0.05, "hanging at rest: {v0}");
    app.world_mut().entity_mut(hook).insert((RigidBody::Dynamic, ColliderMassProperties::Mass(50.0)));
    let errors = plugin_app::errors_over(&mut app, 30);
    assert_eq!(errors.iter().map(|e| (e.entity, e.kind)).collect::<Vec<_>>(), vec![(cable, CableErrorKind::Configuration)], "{errors:?}");
    let v = app.world().get::<Velocity>(payload).unwrap().linear;
    let expected = v0.y - G * 30.0 * DT;
    println!("after the stop: payload velocity {v} (free fall: y {expected})");
    assert!((v.y - expected).abs() < 1e-3 * expected.abs() && v.x.abs() < 1e-4, "{v} against {expected}");
    // The stopped cable keeps its entity and its last good state (the 29
    // steps of `on_hook`'s 30 frames: the first frame builds it).
    let st = app.world().get::<CableState>(cable).unwrap();
    assert!(st.tensions[0] > 1900.0 && (st.time - 29.0 * f64::from(DT)).abs() < 1e-6, "{} N at {} s", st.tensions[0], st.time);
}

/// A cable refused at its first step (its rope laid through a collider)
/// leaves its payload to rapier: it falls as a body without a rope does.
#[test]
fn a_cable_refused_at_its_first_step_leaves_its_payload_to_rapier() {
    let mut app = plugin_app::headless_app(DT);
    let w = app.world_mut();
    w.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, -2.0, 0.0), Collider::cuboid(0.5, 0.1, 0.5)));
    let (payload, cable) = hang(&mut app, ());
    let lone = app
        .world_mut()
        .spawn((RigidBody::Dynamic, Transform::from_xyz(5.0, -5.2, 0.0), Collider::ball(0.2), ColliderMassProperties::Mass(200.0), Velocity::default()))
        .id();
    let errors = plugin_app::errors_over(&mut app, 30);
    assert_eq!(errors.iter().map(|e| (e.entity, e.kind)).collect::<Vec<_>>(), vec![(cable, CableErrorKind::Configuration)], "{errors:?}");
    assert!(errors[0].message.contains("inside a collider"), "{}", errors[0]);
    let w = app.world();
    let (v, free) = (w.get::<Velocity>(payload).unwrap().linear, w.get::<Velocity>(lone).unwrap().linear);
    let (y, y_free) = (w.get::<Transform>(payload).unwrap().translation.y, w.get::<Transform>(lone).unwrap().translation.y);
    println!("payload of the refused cable: y {y} m, velocity {v}; a body without a rope: y {y_free} m, velocity {free}");
    assert!(free.y < -0.9 * G * 30.0 * DT, "the lone body falls: {free}");
    assert!((v - free).length() < 1e-6 && (y - y_free).abs() < 1e-5, "the payload does not fall as the lone body does");
}

/// A payload hanging on two legs from (±3, 0, 0): (app, payload, leg a,
/// leg b), run for 0.5 s. Leg a carries the payload, b is grafted onto it.
fn sling() -> (App, Entity, Entity, Entity) {
    let mut app = plugin_app::headless_app(DT);
    let w = app.world_mut();
    let payload =
        w.spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, -4.0, 0.0), Collider::ball(0.2), ColliderMassProperties::Mass(200.0), Velocity::default())).id();
    let leg = |x: f32| {
        rope(CableAnchor::World { point: Vec3::new(x, 0.0, 0.0), clamp: false }, CableAnchor::Body { entity: payload, anchor: Vec3::ZERO, clamp: false })
    };
    let a = w.spawn(leg(-3.0)).id();
    let b = w.spawn(leg(3.0)).id();
    run(&mut app, 30);
    assert!(app.world().get::<CableSim>(a).is_some() && app.world().get::<CableRopeOf>(b).is_some(), "one island: a carries, b is grafted");
    (app, payload, a, b)
}

/// A sling leg hanging from a kinematic hook whose hook is despawned: the
/// island goes as when the leg itself is despawned (both legs released,
/// neither rebuilt), and the payload falls free. (Before 2026-11-29 the
/// leg hung on from where its hook had been.)
#[test]
fn a_sling_legs_hook_despawned_releases_its_island() {
    let mut app = plugin_app::headless_app(DT);
    let w = app.world_mut();
    let payload =
        w.spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, -4.0, 0.0), Collider::ball(0.2), ColliderMassProperties::Mass(200.0), Velocity::default())).id();
    let hook = w.spawn((RigidBody::KinematicPositionBased, Transform::from_xyz(3.0, 0.0, 0.0), Collider::ball(0.05))).id();
    let to_payload = CableAnchor::Body { entity: payload, anchor: Vec3::ZERO, clamp: false };
    let a = w.spawn(rope(CableAnchor::World { point: Vec3::new(-3.0, 0.0, 0.0), clamp: false }, to_payload.clone())).id();
    let b = w.spawn(rope(CableAnchor::body(hook, Vec3::ZERO), to_payload)).id();
    run(&mut app, 30);
    assert!(app.world().get::<CableSim>(a).is_some() && app.world().get::<CableRopeOf>(b).is_some(), "one island: a carries, b is grafted");
    app.world_mut().despawn(hook);
    let errors = {
        run(&mut app, 30);
        plugin_app::cable_errors(&mut app)
    };
    let w = app.world();
    for leg in [a, b] {
        assert!(
            w.get::<CableSim>(leg).is_none() && w.get::<CableRopeOf>(leg).is_none() && w.get::<CableDescriptor>(leg).is_none(),
            "leg {leg} was not released"
        );
    }
    assert!(errors.is_empty(), "{errors:?}");
    let v = w.get::<Velocity>(payload).unwrap().linear;
    assert!(v.y < -0.9 * G * 29.0 * DT, "the payload does not fall freely: {v}");
}

#[test]
fn a_despawned_sling_leg_releases_its_island() {
    // Despawning the grafted leg releases the carrying one, and the other
    // way round.
    for grafted_goes in [true, false] {
        let (mut app, payload, a, b) = sling();
        let (gone, kept) = if grafted_goes { (b, a) } else { (a, b) };
        app.world_mut().despawn(gone);
        run(&mut app, 30);
        let w = app.world();
        assert!(
            w.get::<CableSim>(kept).is_none() && w.get::<CableRopeOf>(kept).is_none() && w.get::<CableDescriptor>(kept).is_none(),
            "the other leg was not released (grafted leg despawned: {grafted_goes})"
        );
        let v = w.get::<Velocity>(payload).unwrap().linear;
        assert!(v.y < -0.9 * G * 29.0 * DT, "the payload does not fall freely: {v}");
    }
}

/// Editing a built cable's descriptor is ignored (with a logged warning):
/// the running cable keeps its elements and its state, nothing panics.
#[test]
fn an_edit_after_spawning_is_ignored() {
    let mut app = plugin_app::headless_app(DT);
    let (_, cable) = hang(&mut app, ());
    run(&mut app, 10);
    let before = app.world().get::<CableState>(cable).unwrap().nodes.len();
    app.world_mut().get_mut::<CableDescriptor>(cable).unwrap().segments = 7;
    run(&mut app, 10);
    let st = app.world().get::<CableState>(cable).unwrap();
    assert_eq!((before, st.nodes.len()), (21, 21), "the edit was applied or the cable lost");
    assert!(app.world().get::<CableSim>(cable).is_some() && st.tensions[0] > 1900.0);
}

/// A point load the chain cannot take (off the rope, or not finite) is
/// refused with a message naming it, and nothing panics.
#[test]
fn a_bad_point_load_is_refused_by_name() {
    for (s, force) in [(7.0, Vec3::NEG_Y), (1.0, Vec3::new(f32::NAN, 0.0, 0.0)), (f64::NAN, Vec3::NEG_Y)] {
        let mut app = plugin_app::headless_app(DT);
        let mut d = rope(CableAnchor::World { point: Vec3::ZERO, clamp: false }, CableAnchor::Free);
        d.loads.push(CablePointLoad { s, force: force.as_dvec3() * 100.0, moment: bevy::math::DVec3::ZERO });
        let cable = app.world_mut().spawn(d).id();
        run(&mut app, 3);
        let messages: Vec<String> = app.world_mut().resource_mut::<Messages<CableError>>().drain().map(|m| m.message).collect();
        assert!(app.world().get::<CableSim>(cable).is_none(), "s = {s}: the cable was built");
        assert!(messages.iter().any(|m| m.starts_with("load 0 (s = ")), "s = {s}: {messages:?}");
    }
}
