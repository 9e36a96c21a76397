//! Trolley controllers as Bevy components (issue 15): `TrolleyControl`
//! drives a trolley on a rapier rail in a headless app while a cable
//! carries its 1 t payload, as a game would use it.
#![cfg(feature = "app")]

#[path = "common/plugin_app.rs"]
mod plugin_app;

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::crane::control::*;
use bevy_rapier_cable::crane::OverheadCrane;
use bevy_rapier_cable::plugin::*;
use plugin_app::headless_app;

#[derive(Component)]
struct Payload;

/// A 500 kg trolley on a rail at y = 12 m and a 1 t ball (r 0.3 m) on 10 m
/// of 20 mm steel rope (20 elements) under it, the controller on the
/// trolley; runs `seconds` at 1/60 s and returns (t, x, θ) per step from
/// the controller's readout.
fn run(controller: impl TrolleyController + Send + Sync + 'static, seconds: f64) -> Vec<(f64, f64, f64)> {
    let mut app = headless_app(1.0 / 60.0);
    let world = app.world_mut();
    let rail = world.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, 12.0, 0.0))).id();
    let trolley = world
        .spawn((
            RigidBody::Dynamic,
            Transform::from_xyz(0.0, 12.0, 0.0),
            Collider::cuboid(0.6, 0.25, 0.4),
            ColliderMassProperties::Mass(500.0),
            ImpulseJoint::new(rail, PrismaticJointBuilder::new(Vec3::X)),
        ))
        .id();
    let payload =
        world.spawn((Payload, RigidBody::Dynamic, Transform::from_xyz(0.0, 1.45, 0.0), Collider::ball(0.3), ColliderMassProperties::Mass(1000.0))).id();
    world.spawn(
        CableDescriptor::new(10.0)
            .material(RopeMaterial::steel_6x36_iwrc(0.020))
            .segments(20)
            .start(CableAnchor::body(trolley, Vec3::new(0.0, -0.25, 0.0)))
            .end(CableAnchor::body(payload, Vec3::new(0.0, 0.3, 0.0))),
    );
    world.entity_mut(trolley).insert(TrolleyControl::new(controller, payload, Vec3::X).with_max_force(1e6));
    let mut rows = Vec::new();
    for _ in 0..(seconds * 60.0).round() as usize {
        app.update();
        let mut errors = app.world_mut().resource_mut::<Messages<CableError>>();
        if let Some(e) = errors.drain().next() {
            panic!("cable error at {} s: {}", e.time, e.message);
        }
        if let Some((m, _)) = app.world().get::<TrolleyControl>(trolley).and_then(|c| c.readout()) {
            rows.push((m.time, m.position, m.sway));
        }
    }
    rows
}

fn residual(rows: &[(f64, f64, f64)], from: f64) -> f64 {
    rows.iter().filter(|r| r.0 >= from).fold(0.0, |m, r| m.max(r.2.abs()))
}

fn ten_metres() -> Move {
    Move { t0: 1.0, start: 0.0, target: 10.0, max_speed: 1.0, max_acceleration: 0.25 }
}

/// The 10 m move through the rail motor (speed commands): unshaped, the
/// residual sway is the reduced model's (with the same speed loop, the
/// rope lumped as a compound pendulum about the trolley's rope point;
/// within 3 %: here the sway is measured between the bodies' centres);
/// ZV-shaped for that pendulum it falls below 5 % of it. With the
/// double-loop PID (forces on `ExternalForce`, poles placed on the reduced
/// model) the trolley arrives within 5 cm and the sway dies below 0.5°.
#[test]
fn trolley_control_moves_a_payload_without_sway_in_a_bevy_app() {
    let mv = ten_metres();
    let none = ShapedMove { motion: mv, shaper: InputShaper { impulses: vec![(0.0, 1.0)] } };
    let rows = run(none.clone(), 40.0);
    let after = mv.t0 + mv.duration() + 1.0;
    let unshaped = residual(&rows, after);
    // The reduced model as in tests/crane_full_rope.rs.
    let rho = RopeMaterial::steel_6x36_iwrc(0.02).section().linear_density;
    let crane = OverheadCrane::with_rope_mass(500.0, 1000.0, 10.3, rho, 10.0).unwrap();
    let l_eq = crane.rope_length;
    let mut lp = OverheadCraneLoop::new(crane, none, 0.0, 500.0 * 60.0, 1e6).unwrap();
    let mut reduced = Vec::new();
    while lp.state.t < 40.0 {
        lp.step(1e-3).unwrap();
        reduced.push((lp.state.t, lp.state.q[0], lp.state.q[1]));
    }
    let expected = residual(&reduced, after);
    println!(
        "unshaped in a Bevy app: residual sway {:.4}° vs reduced model {:.4}° ({:+.2e})",
        unshaped.to_degrees(),
        expected.to_degrees(),
        unshaped / expected - 1.0
    );
    assert!((unshaped / expected - 1.0).abs() < 0.03, "unshaped {unshaped} vs {expected}");

    let zv = ShapedMove { motion: mv, shaper: InputShaper::new(ShaperKind::Zv, (9.81 / l_eq).sqrt(), 0.0).unwrap() };
    let end = after + zv.shaper.duration();
    let rows = run(zv, 40.0);
    let shaped = residual(&rows, end);
    println!("ZV in a Bevy app: residual sway {:.4}° = {:.4} of unshaped", shaped.to_degrees(), shaped / unshaped);
    assert!(shaped < 0.05 * unshaped, "ZV leaves {shaped}");

    let reduced_crane = OverheadCrane::with_rope_mass(500.0, 1000.0, 10.3, rho, 10.0).unwrap();
    let (mut p, s) = DoubleLoopPid::place_poles(&reduced_crane, [(1.2, 0.7), (1.8, 0.7)]);
    p.ki = 0.05 * p.kp;
    let rows = run(DoubleLoopPid::new(mv, p, s, 2e4).unwrap(), 40.0);
    let (x, sway) = (rows.last().unwrap().1, residual(&rows, 30.0));
    println!("double-loop PID in a Bevy app: trolley at {x:.4} m, sway after 30 s {:.4}°", sway.to_degrees());
    assert!((x - 10.0).abs() < 0.05 && sway.to_degrees() < 0.5, "PID: x {x}, sway {sway}");
}
