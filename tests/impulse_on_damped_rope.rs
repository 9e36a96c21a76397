//! A push on a damped rope or on its payload (`Cable::apply_impulse` over
//! the step, what the coupling does with a carried body's
//! `ExternalImpulse`, `Velocity` write or rapier contact impulse): the
//! rope is passive, so after the push its energy can only fall.

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::Scheme;
use glam::DVec3;

/// A 1 t ball on 10 m of 20 mm steel rope (50 elements, `damping` s),
/// pinned at the top, at its static equilibrium.
fn hanging(damping: f64) -> Cable {
    let section = preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap();
    let payload = LumpedBody::sphere(1000.0, 0.3, DVec3::new(0.0, -10.3, 0.0));
    let model = RopeBuilder::new(10.0, 50, section, 0.02)
        .damping(damping)
        .end(RopeEnd::Body { body: payload, anchor: DVec3::new(0.0, 0.3, 0.0), clamp: false })
        .build()
        .unwrap();
    let mut c = Cable::new(model, Scheme::default()).unwrap();
    c.solve_static(10, 1e-9, 50).unwrap();
    c.recompute_acceleration().unwrap();
    c
}

/// The energy balance of a passive system: a 500 N·s push on the ball
/// (0.5 m/s) and a 5 N·s kick on an element in the rope's middle, each
/// taken over the 1/60 s step as the coupling takes them, on the rope
/// undamped and damped at τ = 0.01 s and 0.05 s. Over the 60 frame steps
/// that follow the rope's total energy (kinetic, elastic, gravity) never
/// rises above what it was right after the push, by more than 1e-3 of
/// the kinetic energy the push gave. Before 2026-11-29 the damped rope's
/// next step gained 2.9 kJ (push on the ball, τ = 0.01 s) and 6.5 kJ (kick
/// in the middle): the acceleration recomputed after the jump held the
/// dampers' answer to it, which generalized-α's history carried into the
/// step's velocity.
#[test]
fn a_push_on_a_damped_rope_or_its_payload_puts_no_energy_into_it() {
    let h = 1.0 / 60.0;
    for damping in [0.0, 0.01, 0.05] {
        for (at_ball, push) in [(true, 500.0), (false, 5.0)] {
            let mut c = hanging(damping);
            let (link, point) = if at_ball {
                (c.model.chain.joints().len() - 1, DVec3::ZERO)
            } else {
                (c.model.layout.element_link(25), DVec3::new(c.model.layout.element_length, 0.0, 0.0))
            };
            let before = c.energy();
            c.apply_impulse(link, point, DVec3::new(push, 0.0, 0.0), DVec3::ZERO, h).unwrap();
            let pushed = c.energy();
            let (mut highest, mut iterations) = (f64::NEG_INFINITY, 0);
            for _ in 0..60 {
                iterations += c.step(h).unwrap().newton_iterations;
                highest = highest.max(c.energy());
            }
            let given = pushed - before;
            println!(
                "τ = {damping} s, {push} N·s {}: the push gave {given:.4} J; highest energy after it {:+.4} J; {iterations} Newton iterations in 60 frame steps",
                if at_ball { "on the ball" } else { "in the middle" },
                highest - pushed
            );
            assert!(given > 0.0, "the push gave {given} J");
            assert!(highest - pushed < 1e-3 * given, "τ = {damping} s, {push} N·s: the energy rose by {} J after the push", highest - pushed);
        }
    }
}
