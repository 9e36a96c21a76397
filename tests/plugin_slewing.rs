//! A payload on a slewing jib through the plugin: the jib is a kinematic
//! rapier body turning about the vertical (the plugin samples its pose and
//! velocities before every step), the rope pinned at its tip. At steady
//! slewing the payload is a conical pendulum about the tip.

#[path = "common/plugin_app.rs"]
mod plugin_app;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::{RopeMaterial, RopeSection};
use bevy_rapier_cable::plugin::*;

const DT: f32 = 1.0 / 60.0;
const G: f64 = 9.81;
/// Slewing rate, rad/s.
const OMEGA: f32 = 0.3;
/// The tip's distance from the slewing axis, m.
const REACH: f32 = 3.0;
/// Rope length and the payload's radius and mass.
const L: f32 = 5.0;
const R: f32 = 0.3;
const M: f32 = 100.0;
/// Height of the rope's pin, m.
const PIN_Y: f32 = 9.9;

/// Drag of the payload's rapier `Damping`, 1/s.
const DRAG: f32 = 0.5;

/// The steady state of a conical pendulum of length `l` about a pin at
/// `reach` from the slewing axis, turning at `omega` about +y, with a drag
/// `−c v` per unit mass: in the frame turning with the jib, the rope lies
/// along the sum of gravity, the centrifugal force `ω² (x, 0, z)` and the
/// drag of the payload's velocity `ω × p`. Returns the payload relative to
/// the pin's foot on the axis: (radius, depth below the pin, angle behind
/// the pin in rad). Fixed-point iteration, converged to round-off.
fn conical_pendulum(reach: f64, l: f64, omega: f64, c: f64) -> (f64, f64, f64) {
    let (mut x, mut y, mut z) = (reach, -l, 0.0f64);
    for _ in 0..2000 {
        let v = (omega * z, 0.0, -omega * x);
        let f = (omega * omega * x - c * v.0, -G - c * v.1, omega * omega * z - c * v.2);
        let n = (f.0 * f.0 + f.1 * f.1 + f.2 * f.2).sqrt();
        let next = (reach + l * f.0 / n, l * f.1 / n, l * f.2 / n);
        (x, y, z) = (0.5 * (x + next.0), 0.5 * (y + next.1), 0.5 * (z + next.2));
    }
    ((x * x + z * z).sqrt(), -y, z.atan2(x))
}

/// A 100 kg ball on a light, stiff 5 m rope (0.05 kg, 5e-4 of the payload)
/// from the tip of a kinematic jib slewing at 0.3 rad/s about the vertical,
/// started at rest below the tip (the swing this starts decays through the
/// payload's rapier `Damping`, which acts inside the cable solve), 40 s at
/// 1/60 s. The payload settles on the steady conical pendulum with that
/// drag: its radius, its height and its lag behind the jib.
#[test]
fn a_payload_on_a_slewing_jib_settles_on_the_conical_pendulum() {
    let mut app = plugin_app::headless_app(DT);
    let w = app.world_mut();
    let jib = w
        .spawn((
            RigidBody::KinematicVelocityBased,
            Transform::from_xyz(0.0, PIN_Y + 0.1, 0.0),
            Collider::cuboid(REACH, 0.1, 0.1),
            Velocity::angular(Vec3::Y * OMEGA),
        ))
        .id();
    let payload = w
        .spawn((
            RigidBody::Dynamic,
            Transform::from_xyz(REACH, PIN_Y - L - R, 0.0),
            Collider::ball(R),
            ColliderMassProperties::Mass(M),
            Velocity::zero(),
            Damping { linear_damping: DRAG, angular_damping: 0.0 },
        ))
        .id();
    let section = RopeSection { linear_density: 0.01, ea: 1e8, ei: 1e-3, ei2: 1e-3, gj: 1e-3, min_breaking_load: 0.0 };
    let cable = w
        .spawn(CableDescriptor::from_section(
            L as f64,
            20,
            RopeMaterial::custom(section, 0.01),
            CableAnchor::Body { entity: jib, anchor: Vec3::new(REACH, -0.1, 0.0), clamp: false },
            CableAnchor::Body { entity: payload, anchor: Vec3::Y * R, clamp: false },
        ))
        .id();
    let frames = 2400;
    let mut iterations = 0;
    for _ in 0..frames {
        app.update();
        if let Some(state) = app.world().get::<CableState>(cable) {
            iterations += state.newton_iterations;
        }
    }
    let p = app.world().get::<Transform>(payload).unwrap().translation.as_dvec3();
    let radius = (p.x * p.x + p.z * p.z).sqrt();
    let l = (L + R) as f64;
    let (expected, depth, behind) = conical_pendulum(REACH as f64, l, OMEGA as f64, DRAG as f64);
    let (no_drag, _, _) = conical_pendulum(REACH as f64, l, OMEGA as f64, 0.0);
    let height = PIN_Y as f64 - depth;
    // The payload's angle about the axis against the jib's (rotation about
    // +y turns +x toward −z); the jib's pose is one frame ahead of `t`.
    let t = frames as f64 * DT as f64;
    let jib_angle = OMEGA as f64 * t;
    let payload_angle = (-p.z).atan2(p.x);
    let lag = (jib_angle - payload_angle + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    println!(
        "{t:.1} s: radius {radius:.5} m (steady state {expected:.5} m, {:+.2e}; {no_drag:.5} m without the drag), height {:.5} m ({height:.5} m, {:+.2e} m), {:.2}° behind the jib ({:.2}°); {:.2} Newton iterations per frame",
        radius / expected - 1.0,
        p.y,
        p.y - height,
        lag.to_degrees(),
        behind.to_degrees(),
        iterations as f64 / frames as f64
    );
    assert!((radius / expected - 1.0).abs() < 1e-4, "radius {radius} m, steady conical pendulum {expected} m");
    assert!((p.y - height).abs() < 1e-3, "height {} m, steady conical pendulum {height} m", p.y);
    assert!((lag - behind).abs() < 0.5f64.to_radians(), "payload {:.2}° behind the jib, steady state {:.2}°", lag.to_degrees(), behind.to_degrees());
}
