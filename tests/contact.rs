//! Contact (issue 12, first part): the IMPACT normal law and a sphere
//! contact as an implicit force element in the rope's solve.

use std::sync::Arc;

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::{Integrator, Scheme, SecondOrderSystem, State, SystemError};
use glam::DVec3;

/// A 1-DOF body of mass `m` above a plane: `x` the gap (m), pushed out by
/// the law at penetration `−x`.
struct Drop {
    m: f64,
    law: ImpactLaw,
}

impl SecondOrderSystem for Drop {
    fn dof(&self) -> usize {
        1
    }
    fn residual(&mut self, _t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        r[0] = self.m * a[0] - self.law.force(-q[0], -v[0]).0;
        Ok(())
    }
    fn solve_tangent(&mut self, _t: f64, q: &[f64], v: &[f64], _a: &[f64], c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        let (_, k, c) = self.law.force(-q[0], -v[0]);
        x[0] = b[0] / (self.m + c_v * c + c_q * k);
        Ok(())
    }
}

/// Verification case §7d: the IMPACT law (K = 1e7 N/m^1.5, e = 1.5,
/// C_max = 100 N·s/m, d_max = 1e-4 m) on 1 kg hitting a rigid plane at
/// v₀: the coefficient of restitution of the clamped law (an accurate ODE
/// solution in the notes; their tolerance 1e-3) within 1e-5, and its
/// contact time within 1e-5 relative, integrated by the crate's
/// trapezoidal rule at 1 µs.
#[test]
fn impact_law_restitution_matches_the_reference() {
    let law = ImpactLaw::new(1e7, 1.5, 100.0, 1e-4).unwrap();
    for (v0, cor, tc_ms) in [(0.1, 0.70567, 8.42863), (0.5, 0.74956, 6.05968), (1.0, 0.77358, 5.25431), (2.0, 0.79697, 4.55709)] {
        let (v_out, _, _, tc) = bounce(1.0, law, v0, 1e-6);
        let (e, tc) = (v_out / v0, tc * 1e3);
        println!("v0 {v0}: COR {e:.5} vs {cor} ({:+.1e}), contact {tc:.5} ms vs {tc_ms} ({:+.1e})", e - cor, tc / tc_ms - 1.0);
        assert!((e - cor).abs() < 1e-5, "v0 {v0}: COR {e}");
        assert!((tc / tc_ms - 1.0).abs() < 1e-5, "v0 {v0}: contact time {tc} ms");
    }
}

/// `ImpactLaw::restitution` (RK4 on the law's equation of motion, 2 000
/// steps over the undamped strike) against verification case §7d's
/// accurate ODE values: the coefficient of restitution within 1e-5 and
/// the contact time within 1e-5 relative (the notes ask 1e-3). And the
/// steel rope's own law (`CableContact::steel` for 20 mm rope, an element
/// of 0.08 kg): a strike ends within a millisecond at every speed from
/// 5 cm/s to 30 m/s, with the restitution that its damping, ramped in
/// over 1e-5 m and critical there, leaves (between 0.1 and 0.8; its rows
/// in docs/verification.md).
#[test]
fn impact_law_restitution_of_a_strike_matches_the_reference() {
    let law = ImpactLaw::new(1e7, 1.5, 100.0, 1e-4).unwrap();
    for (v0, cor, tc_ms) in [(0.1, 0.70567, 8.42863), (0.5, 0.74956, 6.05968), (1.0, 0.77358, 5.25431), (2.0, 0.79697, 4.55709)] {
        let (e, tc) = law.restitution(1.0, v0).unwrap();
        let tc = tc * 1e3;
        println!("v0 {v0}: COR {e:.6} vs {cor} ({:+.1e}), contact {tc:.5} ms vs {tc_ms} ({:+.1e})", e - cor, tc / tc_ms - 1.0);
        assert!((e - cor).abs() < 1e-5, "v0 {v0}: COR {e}");
        assert!((tc / tc_ms - 1.0).abs() < 1e-5, "v0 {v0}: contact time {tc} ms");
    }
    assert_eq!(law.restitution(0.0, 1.0), None);
    assert_eq!(law.restitution(1.0, f64::NAN), None);
    // `CableContact::steel(0.02, 0.08)`'s law: Hertz for steel on steel
    // (E* = E/(2(1 − ν²))), R* the rope's radius, damping critical for
    // the element's mass on the stiffness at 1e-5 m, ramped in to there.
    let e_star = 210e9 / (2.0 * (1.0 - 0.09));
    let k = 1.5 * (4.0 / 3.0) * e_star * 0.01f64.sqrt() * 1e-5f64.sqrt();
    let rope = ImpactLaw::hertz(e_star, 0.01, 2.0 * (k * 0.08f64).sqrt(), 1e-5).unwrap();
    for v0 in [0.05, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0] {
        let (e, tc) = rope.restitution(0.08, v0).unwrap();
        println!("steel rope element at {v0} m/s: COR {e:.4}, contact {:.4} ms", tc * 1e3);
        assert!(e > 0.1 && e < 0.8 && tc < 1e-3, "{v0} m/s: COR {e}, {tc} s");
    }
}

/// Bounce of `m` at `v0` on the law: (exit speed, largest penetration,
/// largest force, contact time), by the trapezoidal rule at `h`.
fn bounce(m: f64, law: ImpactLaw, v0: f64, h: f64) -> (f64, f64, f64, f64) {
    let mut sys = Drop { m, law };
    let mut state = State::new(&mut sys, 0.0, vec![0.0], vec![-v0]).unwrap();
    let mut integ = Integrator::new(Scheme::Newmark { beta: 0.25, gamma: 0.5 });
    let (mut depth, mut force, mut t_in) = (0.0f64, 0.0f64, None);
    let mut prev = 0.0;
    loop {
        integ.step(&mut sys, &mut state, h).unwrap();
        let x = state.q[0];
        depth = depth.max(-x);
        force = force.max(law.force(-x, -state.v[0]).0);
        if t_in.is_none() && x < 0.0 {
            t_in = Some(state.t - h * x / (x - prev));
        }
        if let (Some(t0), true) = (t_in, x >= 0.0) {
            return (state.v[0], depth, force, state.t - h * x / (x - prev) - t0);
        }
        prev = x;
    }
}

/// Verification case §7a: a steel sphere (R = 10 mm, m = 0.032882 kg) on a
/// massive steel half-space at 1 m/s, Hertz's law from the materials
/// (`ImpactLaw::hertz`, E* = 1.15385e11 Pa, R* = R, no damping): largest
/// penetration, largest force and contact time of the closed form within
/// 1e-4, and the exit speed equals the entry speed (an elastic law).
#[test]
fn hertz_sphere_on_half_space_matches_the_closed_form() {
    let (e, nu, r, m) = (210e9, 0.3, 0.01, 0.032882);
    let e_star = 1.0 / (2.0 * (1.0 - nu * nu) / e);
    let law = ImpactLaw::hertz(e_star, r, 0.0, 1e-6).unwrap();
    let (v_out, depth, force, tc) = bounce(m, law, 1.0, 1e-8);
    println!("δ_max {depth:.5e} m, F_max {force:.2} N, t_c {tc:.5e} s, exit {v_out:.6} m/s");
    for (got, want, what) in [(depth, 2.34808e-5, "δ_max"), (force, 1750.47, "F_max"), (tc, 6.91104e-5, "t_c"), (v_out, 1.0, "exit speed")] {
        assert!((got / want - 1.0).abs() < 1e-4, "{what}: {got} vs {want}");
    }
}

/// Bad parameters are refused by name.
#[test]
fn impact_law_refuses_bad_parameters() {
    for (law, name) in [
        (ImpactLaw::new(0.0, 1.5, 0.0, 1e-4), "stiffness"),
        (ImpactLaw::new(1e7, 0.5, 0.0, 1e-4), "exponent"),
        (ImpactLaw::new(1e7, 1.5, -1.0, 1e-4), "max_damping"),
        (ImpactLaw::new(1e7, 1.5, 1.0, f64::NAN), "damping_depth"),
        (ImpactLaw::hertz(-1.0, 0.01, 0.0, 1e-4), "E*"),
    ] {
        let err = law.unwrap_err().to_string();
        assert!(err.contains(name), "{err}");
    }
}

const G: f64 = 9.81;

/// A free 10 m steel rope (20 mm, 6×36 IWRC, N = 20) laid straight on a
/// rigid plane y = 0, a [`SphereContact`] of the rope's radius at each
/// node: Hertz steel on a flat (E* = 1.154e11 Pa, R* = 10 mm; K = 1.5e10
/// N/m^1.5) with C_max = 2e3 N·s/m over d_max = 1e-5 m, released 1 mm
/// above the plane. Stepped at the frame step.
fn rope_on_ground(n: usize) -> (Cable, ImpactLaw, f64) {
    let d = 0.02;
    let section = RopeMaterial::steel_6x36_iwrc(d).section();
    let r = d / 2.0;
    let y = r + 1e-3;
    let model = RopeBuilder::new(10.0, n, section, d).start(RopeStart::Free).path(vec![DVec3::new(0.0, y, 0.0), DVec3::new(10.0, y, 0.0)]).build().unwrap();
    let mut cable = Cable::new(model, Scheme::default()).unwrap();
    let e_star = 1.0 / (2.0 * (1.0 - 0.09) / 210e9);
    let law = ImpactLaw::hertz(e_star, r, 2e3, 1e-5).unwrap();
    for k in 0..=n {
        let contact = SphereContact::fixed(DVec3::ZERO, DVec3::Y, r, law);
        assert!(cable.add_force_element(0, 10.0 * k as f64 / n as f64, Arc::new(contact)));
    }
    (cable, law, section.linear_density)
}

/// The contact forces at the rope's nodes (N) and the largest penetration (m).
fn ground_forces(cable: &Cable, law: ImpactLaw, n: usize) -> (Vec<f64>, f64) {
    let r = 0.01;
    let contact = SphereContact::fixed(DVec3::ZERO, DVec3::Y, r, law);
    let mut forces = Vec::new();
    let mut depth = 0.0f64;
    for k in 0..=n {
        let (point, velocity) = cable.point_at(10.0 * k as f64 / n as f64);
        let at = PointState { rotation: glam::DMat3::IDENTITY, point, velocity, angular_velocity: DVec3::ZERO };
        forces.push(contact.normal_force(cable.time(), &at));
        depth = depth.max(contact.depth(cable.time(), &at).0);
    }
    (forces, depth)
}

/// Issue 12's first check: a rope lying on the ground carries exactly its
/// weight in contact force and does not sink. After 2 s at 1/60 s the
/// contact forces add up to ρ g L within 1e-6, the deepest node sinks by
/// no more than the Hertz depth of twice a node's share of the weight,
/// and between 2 s and 4 s no node moves up or down by 1e-12 m (no creep
/// into the ground).
#[test]
fn a_rope_lying_on_the_ground_carries_its_weight_and_does_not_sink() {
    let n = 20;
    let (mut cable, law, rho) = rope_on_ground(n);
    let weight = rho * 10.0 * G;
    let mut steps = 0;
    while cable.time() < 2.0 - 1e-9 {
        cable.step(1.0 / 60.0).unwrap_or_else(|e| panic!("{e}"));
        steps += 1;
    }
    let (forces, depth) = ground_forces(&cable, law, n);
    let total: f64 = forces.iter().sum();
    let share = weight / n as f64;
    let bound = (2.0 * share / law.stiffness).powf(1.0 / law.exponent);
    let nodes_2s = cable.nodes();
    while cable.time() < 4.0 - 1e-9 {
        cable.step(1.0 / 60.0).unwrap_or_else(|e| panic!("{e}"));
        steps += 1;
    }
    let moved = cable.nodes().iter().zip(&nodes_2s).map(|(a, b)| (a.y - b.y).abs()).fold(0.0f64, f64::max);
    let slid = cable.nodes().iter().zip(&nodes_2s).map(|(a, b)| (a.x - b.x).hypot(a.z - b.z)).fold(0.0f64, f64::max);
    println!("slid {slid:.2e} m along the ground");
    println!(
        "contact {total:.6} N vs weight {weight:.6} N ({:+.2e}); deepest {depth:.3e} m (bound {bound:.3e}); sank {moved:.2e} m from 2 s to 4 s; {:.2} Newton iterations per step",
        total / weight - 1.0,
        cable.total_stats.newton_iterations as f64 / steps as f64
    );
    assert!((total / weight - 1.0).abs() < 1e-6, "contact {total} vs weight {weight}");
    assert!(depth > 0.0 && depth < bound, "deepest {depth}, bound {bound}");
    assert!(moved < 1e-12, "sank {moved} m");
}

/// Issue 12's check "a payload lowered onto the ground stops without
/// jitter, and its rope tension drops to zero", on the rope model alone: a
/// 1 t steel ball (R = 0.5 m) on 10 m of 20 mm steel rope (N = 20), its
/// bottom 0.2 m above a rigid floor; the pin is lowered by 0.5 m at up to
/// 0.1 m/s (a cosine ramp over 5 s), so the ball lands at about 0.1 m/s
/// and the rope ends 0.3 m slack. The ball's contact is a
/// [`SphereContact`] at its centre, Hertz steel on a rigid flat (E* = 2.31e11
/// Pa, R* = 0.5 m) with C_max = 1e6 N·s/m over 1e-5 m. At the frame step,
/// 3 s after the pin stops:
/// * the ball rests at the Hertz depth of its weight, `(m g/K)^(2/3)`,
///   within 1 %, and moves by less than 1e-9 m over the last second (no
///   jitter);
/// * the contact carries the ball's weight within 0.5 %, and the rope's
///   tension at the ball is below 1 % of the weight.
#[test]
fn a_payload_lowered_onto_the_ground_comes_to_rest_and_its_rope_goes_slack() {
    let (m, radius, d) = (1000.0, 0.5, 0.02);
    let section = RopeMaterial::steel_6x36_iwrc(d).section();
    let top = 0.2 + 2.0 * radius + 10.0;
    let lower = move |t: f64| {
        // 0.5 m over 5 s, cosine ramp: v = 0.1 sin²(π t/5) m/s.
        let t = t.clamp(0.0, 5.0);
        let w = std::f64::consts::PI / 5.0;
        let y = 0.05 * t - 0.05 * (2.0 * w * t).sin() / (2.0 * w);
        let v = 0.1 * (w * t).sin().powi(2);
        let a = 0.1 * w * (2.0 * w * t).sin();
        BaseState {
            position: DVec3::new(0.0, top - y, 0.0),
            velocity: DVec3::new(0.0, -v, 0.0),
            acceleration: DVec3::new(0.0, -a, 0.0),
            ..BaseState::fixed(glam::DMat3::IDENTITY, DVec3::ZERO)
        }
    };
    let body = LumpedBody::sphere(m, radius, DVec3::new(0.0, top - 10.0 - radius, 0.0));
    let model = RopeBuilder::new(10.0, 20, section, d)
        .start(RopeStart::Pinned(BaseMotion::Prescribed(Arc::new(lower))))
        .end(RopeEnd::Body { body, anchor: DVec3::new(0.0, radius, 0.0), clamp: false })
        .path(vec![DVec3::new(0.0, top, 0.0), DVec3::new(0.0, top - 10.0, 0.0)])
        .build()
        .unwrap();
    let mut cable = Cable::new(model, Scheme::default()).unwrap();
    let eb = cable.model.layout.end_body.unwrap();
    let e_star = 210e9 / (1.0 - 0.09);
    let law = ImpactLaw::hertz(e_star, radius, 1e6, 1e-5).unwrap();
    let floor = SphereContact::fixed(DVec3::ZERO, DVec3::Y, radius, law);
    cable.model.chain.forces_mut().push(AttachedForce { link: eb.link, local_point: eb.origin, element: Arc::new(floor) });
    let (mut steps, mut last_second) = (0, Vec::new());
    while cable.time() < 8.0 - 1e-9 {
        cable.step(1.0 / 60.0).unwrap_or_else(|e| panic!("t = {}: {e}", cable.time()));
        steps += 1;
        if cable.time() > 7.0 - 1e-9 {
            last_second.push(cable.model.body_state(&eb).0);
        }
    }
    let rest = (m * G / law.stiffness).powf(1.0 / 1.5);
    let centre = cable.model.body_state(&eb).0;
    let depth = radius - centre.y;
    let jitter = last_second.iter().map(|p| p.distance(last_second[0])).fold(0.0f64, f64::max);
    let contact = cable.force_element_wrenches()[0].1.force.y;
    let tension = cable.tension_at(10.0);
    println!(
        "depth {depth:.4e} m vs Hertz {rest:.4e} ({:+.2e}); moved {jitter:.2e} m over the last second; contact {contact:.1} N ({:+.2e} of m g); rope tension at the ball {tension:.2} N; {:.2} Newton iterations and {:.2} sub-steps per step",
        depth / rest - 1.0,
        contact / (m * G) - 1.0,
        cable.total_stats.newton_iterations as f64 / steps as f64,
        cable.total_stats.substeps_used as f64 / steps as f64
    );
    assert!((depth / rest - 1.0).abs() < 0.01, "depth {depth} vs {rest}");
    assert!(jitter < 1e-9, "moved {jitter} m");
    assert!((contact / (m * G) - 1.0).abs() < 5e-3, "contact {contact}");
    assert!(tension.abs() < 0.01 * m * G, "tension {tension}");
}
