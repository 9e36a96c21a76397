//! Rope dynamics against closed forms (verification-cases §3c, §5a, §5b) and
//! the stability of a stiff steel rope under a heavy payload at 1/60 s.

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::Scheme;
use glam::{DMat3, DVec3};

fn section(mu: f64, ea: f64, ei: f64, gj: f64) -> RopeSection {
    RopeSection { linear_density: mu, ea, ei, ei2: ei, gj, min_breaking_load: 0.0 }
}

fn fixed_at(p: DVec3) -> BaseMotion {
    BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, p))
}

/// A rope pinned at the origin, laid straight at `angle` (rad) from the
/// downward vertical in the x–y plane, with a sphere payload of `mass` kg
/// and radius `radius` m hanging on a ball joint at its end.
fn pendulum(l: f64, n: usize, sec: RopeSection, mass: f64, radius: f64, angle: f64) -> RopeModel {
    let dir = DVec3::new(angle.sin(), -angle.cos(), 0.0);
    let body = LumpedBody::sphere(mass, radius, dir * (l + radius));
    RopeBuilder::new(l, n, sec, 0.02)
        .path(vec![DVec3::ZERO, dir * l])
        .start(RopeStart::Pinned(fixed_at(DVec3::ZERO)))
        .end(RopeEnd::Body { body, anchor: -dir * radius, clamp: false })
        .build()
        .unwrap()
}

/// Times at which `x` crosses zero going up (linear interpolation).
fn upward_crossings(t: &[f64], x: &[f64]) -> Vec<f64> {
    (1..x.len()).filter(|&k| x[k - 1] < 0.0 && x[k] >= 0.0).map(|k| t[k - 1] + (t[k] - t[k - 1]) * (-x[k - 1]) / (x[k] - x[k - 1])).collect()
}

fn mean_period(c: &[f64]) -> f64 {
    (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64
}

/// verification-cases §5a: large-amplitude pendulum, T/T₀ = 2K(sin(θ₀/2))/π
/// (1.017409 at 30°, 1.073182 at 60°), point mass on a stiff cable.
#[test]
fn large_amplitude_pendulum_period() {
    let g = 9.81;
    for (deg, ratio) in [(30.0f64, 1.017409), (60.0, 1.073182)] {
        let (l, m, r) = (10.0, 1000.0, 0.01);
        let sec = section(0.01, 1e10, 1e-2, 1e-2);
        let mut cable = Cable::new(pendulum(l, 20, sec, m, r, deg.to_radians()), Scheme::default()).unwrap();
        let h = 1.0 / 60.0;
        let (mut ts, mut xs) = (vec![], vec![]);
        let mut iters = 0;
        while cable.time() < 40.0 {
            iters += cable.step(h).unwrap().newton_iterations;
            let v = cable.node_velocities();
            ts.push(cable.time());
            xs.push(v[v.len() - 1].x);
        }
        let c = upward_crossings(&ts, &xs);
        let period = mean_period(&c);
        // Pendulum length to the payload centre, plus the rope's static
        // stretch and the rope's own (tiny) mass as a compound pendulum.
        let le = l + r + m * g * l / 1e10;
        let mu_l = 0.01 * l;
        let i_pivot = m * le * le + mu_l * l * l / 3.0;
        let moment = m * le + mu_l * l / 2.0;
        let t0 = 2.0 * std::f64::consts::PI * (i_pivot / (moment * g)).sqrt();
        let exact = t0 * ratio;
        let err = (period - exact) / exact;
        println!(
            "{deg}°: period {period:.5} s vs {exact:.5} s ({err:+.2e}), {} periods, {:.2} Newton iterations/step",
            c.len() - 1,
            iters as f64 / ts.len() as f64
        );
        assert!(err.abs() < 5e-4, "period error {err}");
    }
}

/// DESIGN.md "Stable at the frame step": 20 m steel rope (EA 2e7 N,
/// 1.6 kg/m, EI 50 N·m²), 100 elements, 1 t payload, released at 30° and at
/// 85° with no damping, stepped at 1/60 s with no sub-steps: stays stable,
/// conserves energy to a fraction of the swing energy, keeps the static
/// stretch.
#[test]
fn steel_rope_heavy_payload_stable_at_frame_step() {
    let g = 9.81;
    for deg in [30.0f64, 85.0] {
        let sec = section(1.6, 2e7, 50.0, 35.0);
        let mut cable = Cable::new(pendulum(20.0, 100, sec, 1000.0, 0.3, deg.to_radians()), Scheme::default()).unwrap();
        let e0 = cable.energy();
        let swing = 1032.0 * g * 20.0 * (1.0 - deg.to_radians().cos());
        let h = 1.0 / 60.0;
        let mut max_iter = 0;
        let mut total = 0;
        let steps = (20.0 / h) as usize;
        for _ in 0..steps {
            let s = cable.step(h).unwrap();
            max_iter = max_iter.max(s.newton_iterations);
            total += s.newton_iterations;
        }
        let de = (cable.energy() - e0) / swing;
        println!("{deg}°: energy change {:+.3} % of the swing energy over 20 s; Newton {:.2}/step (max {max_iter})", 100.0 * de, total as f64 / steps as f64);
        assert!(de.abs() < 0.01, "energy drift {de}");
        assert!(de <= 1e-6, "energy must not grow");
    }
}

/// verification-cases §5b: free trolley M = 1000 kg on a frictionless rail
/// with m = 500 kg on l = 5 m. Period 3.843178 s at 30°, trolley
/// peak-to-peak 2μl sin φ₀ = 1.666667 m, horizontal momentum conserved.
#[test]
fn trolley_pendulum_coupled_period_and_momentum() {
    let (big_m, m, l) = (1000.0, 500.0, 5.0);
    for (deg, t_ref, p2p_ref) in [(5.0f64, 3.667783, 0.290519), (30.0, 3.843178, 1.666667)] {
        let phi = deg.to_radians();
        let dir = DVec3::new(phi.sin(), -phi.cos(), 0.0);
        let trolley =
            LumpedBody { mass: big_m, inertia: DMat3::from_diagonal(DVec3::splat(100.0)), position: DVec3::ZERO, rotation: DMat3::IDENTITY, com: DVec3::ZERO };
        let r = 0.01;
        // Rope length l − r so the payload centre is at l from the rail.
        let payload = LumpedBody::sphere(m, r, dir * l);
        let model = RopeBuilder::new(l - r, 10, section(1e-3, 1e10, 1e-3, 1e-3), 0.02)
            .path(vec![DVec3::ZERO, dir * (l - r)])
            .start(RopeStart::SlidingBody { body: trolley, axis: DVec3::X, anchor: DVec3::ZERO, clamp: false })
            .end(RopeEnd::Body { body: payload, anchor: -dir * r, clamp: false })
            .build()
            .unwrap();
        let mut cable = Cable::new(model, Scheme::default()).unwrap();
        let h = 1.0 / 240.0;
        let (mut ts, mut vs, mut xs) = (vec![], vec![], vec![]);
        let mut worst_p: f64 = 0.0;
        while cable.time() < 8.0 * t_ref {
            cable.step(h).unwrap();
            ts.push(cable.time());
            vs.push(cable.state.v[0]);
            xs.push(cable.state.q[0]);
            let p: f64 = (0..cable.model.chain.len())
                .map(|s| {
                    let ch = &cable.model.chain;
                    ch.joints()[s].link.map_or(0.0, |lm| lm.mass * ch.link_point_velocity(s, lm.com).unwrap().x)
                })
                .sum();
            worst_p = worst_p.max(p.abs());
        }
        let c = upward_crossings(&ts, &vs);
        let period = mean_period(&c);
        let p2p = xs.iter().cloned().fold(f64::MIN, f64::max) - xs.iter().cloned().fold(f64::MAX, f64::min);
        let (et, ep) = ((period - t_ref) / t_ref, (p2p - p2p_ref) / p2p_ref);
        let scale = m * (2.0 * 9.81 * l * (1.0 - phi.cos())).sqrt();
        println!("{deg}°: period {period:.5} s ({et:+.2e}), trolley p2p {p2p:.5} m ({ep:+.2e}), |P_x| ≤ {:.1e} of m·v_max", worst_p / scale);
        assert!(et.abs() < 1e-3 && ep.abs() < 5e-3);
        // Generalized-α does not conserve a cyclic momentum exactly for a
        // configuration-dependent mass matrix; measured ≤ 1.1e-5 at 1/240 s.
        assert!(worst_p / scale < 5e-5);
    }
}

/// verification-cases §3c ("crane" row) and the dynamic load factor: a 5 t
/// payload released on a slack-free, unstretched 50 m rope (EA 1.6e7 N,
/// 1.6 kg/m) bounces at ω₁ = 7.978729 rad/s ((ωl/c) tan(ωl/c) = μl/m) with
/// a peak tension of about twice the static load.
#[test]
fn axial_bounce_frequency_and_dynamic_load_factor() {
    let (l, mu, ea, m, g) = (50.0, 1.6, 1.6e7, 5000.0, 9.81);
    let body = LumpedBody::sphere(m, 0.5, DVec3::new(0.0, -l - 0.5, 0.0));
    let model = RopeBuilder::new(l, 50, section(mu, ea, 50.0, 35.0), 0.02)
        .start(RopeStart::Pinned(fixed_at(DVec3::ZERO)))
        .end(RopeEnd::Body { body, anchor: DVec3::new(0.0, 0.5, 0.0), clamp: false })
        .build()
        .unwrap();
    let mut cable = Cable::new(model, Scheme::default()).unwrap();
    let h = 1e-3;
    let (mut ts, mut ys, mut peak) = (vec![], vec![], 0.0f64);
    while cable.time() < 4.0 {
        cable.step(h).unwrap();
        ts.push(cable.time());
        ys.push(cable.node_velocities()[50].y);
        peak = peak.max(cable.tension_at(l));
    }
    let c = upward_crossings(&ts, &ys);
    let omega = 2.0 * std::f64::consts::PI / mean_period(&c);
    let err = (omega - 7.978729) / 7.978729;
    let static_load = m * g;
    let dlf = peak / static_load;
    println!("ω₁ {omega:.5} rad/s ({err:+.2e}); peak tension at the payload {peak:.0} N, DLF {dlf:.4}");
    assert!(err.abs() < 1e-3, "bounce frequency error {err}");
    assert!((dlf - 2.0).abs() < 0.02, "dynamic load factor {dlf}");
}

/// Explicit schemes on a rope: with automatic sub-steps (from the rope's
/// highest element frequency) RK4 and symplectic Euler stay stable at a
/// 1/60 s frame and agree with generalized-α at a small step; with one fixed
/// sub-step they refuse with an error naming the step and the limit.
#[test]
fn explicit_schemes_substep_on_a_rope_or_refuse() {
    use bevy_rapier_cable::integrate::{IntegrateError, Substeps};
    let sec = section(0.5, 2e4, 0.5, 0.5);
    let make = |scheme: Scheme| Cable::new(pendulum(2.0, 8, sec, 5.0, 0.05, 0.5), scheme).unwrap();
    let mut reference = make(Scheme::default());
    for _ in 0..2000 {
        reference.step(1e-3).unwrap();
    }
    let tip_ref = reference.nodes()[8];
    for scheme in [Scheme::Rk4, Scheme::SymplecticEuler] {
        let mut c = make(scheme.clone());
        let mut substeps = 0;
        for _ in 0..120 {
            substeps += c.step(1.0 / 60.0).unwrap().substeps_used;
        }
        let err = c.nodes()[8].distance(tip_ref);
        println!("{}: {} sub-steps per frame, tip off by {err:.2e} m after 2 s", scheme.name(), substeps / 120);
        assert!(err < 2e-3, "{} tip error {err}", scheme.name());
        let mut fixed = make(scheme);
        fixed.integrator.substeps = Substeps::Fixed(1);
        match fixed.step(1.0 / 60.0) {
            Err(CableError::Integrate(e @ IntegrateError::StepTooLarge { .. })) => println!("  Fixed(1): {e}"),
            other => panic!("expected StepTooLarge, got {other:?}"),
        }
    }
}

/// verification-cases §5d: a uniform stiff rod (all its mass in the rope
/// itself, no payload) pinned at its top swings as a compound pendulum,
/// T = 2π√(2L/3g)·2K(sin(θ₀/2))/π: 1.703421 s at 45°, 1.933335 s at 90°.
#[test]
fn compound_pendulum_of_a_stiff_rod() {
    for (deg, t_ref) in [(45.0f64, 1.703421), (90.0, 1.933335)] {
        let a = deg.to_radians();
        let dir = DVec3::new(a.sin(), -a.cos(), 0.0);
        let model = RopeBuilder::new(1.0, 20, section(0.6165, 2e9, 2e4, 2e4), 0.01)
            .path(vec![DVec3::ZERO, dir])
            .start(RopeStart::Pinned(fixed_at(DVec3::ZERO)))
            .build()
            .unwrap();
        let mut c = Cable::new(model, Scheme::default()).unwrap();
        let h = 1e-3;
        let (mut ts, mut xs) = (vec![], vec![]);
        while c.time() < 6.0 * t_ref {
            c.step(h).unwrap();
            ts.push(c.time());
            xs.push(c.node_velocities()[20].x);
        }
        let period = mean_period(&upward_crossings(&ts, &xs));
        let err = (period - t_ref) / t_ref;
        println!("{deg}°: period {period:.6} s vs {t_ref} s ({err:+.2e})");
        assert!(err.abs() < 1e-3, "period error {err}");
    }
}

/// The reported pose of a ball-jointed payload: its centre is at
/// rope end + R_body·(−anchor), whatever the rope's direction.
#[test]
fn payload_pose_is_reported_where_the_body_is() {
    let a: f64 = 30f64.to_radians();
    let dir = DVec3::new(a.sin(), -a.cos(), 0.0);
    let body_pos = dir * 20.3;
    let model = pendulum(20.0, 10, section(1.6, 2e7, 50.0, 35.0), 1000.0, 0.3, a);
    let b = model.layout.end_body.unwrap();
    let (p, r, _, _) = model.body_state(&b);
    println!("payload reported at {p:?}, placed at {body_pos:?}");
    assert!(p.distance(body_pos) < 1e-9);
    assert!((r - DMat3::IDENTITY).abs_diff_eq(DMat3::ZERO, 1e-12));
}

/// `Cable::set_link_velocities` on a 20 m steel rope (EA 2e7 N, EI 50,
/// μ 1.6 kg/m) with a 1 t payload hanging at rest in static equilibrium:
/// given a horizontal u0 = 0.5 m/s, the payload has it exactly, and the
/// rope moves in the shape a horizontal force at the payload would
/// deflect it into (the rates of least stiffness energy), not with a kink:
/// slope ∝ 1/T(s) with T(s) = m g + μ g (L − s), so the node at arc length
/// s moves at u0 ln(T(0)/T(s)) / ln(T(0)/T(L)). Then the swing amplitude is
/// u0/ω with ω from the measured period (the energy went into the swing
/// mode, not into rope waves).
#[test]
fn initial_payload_velocity_swings_the_rope_in_its_deflection_shape() {
    let (l, m, r, u0, mu, g) = (20.0, 1000.0, 0.3, 0.5, 1.6, 9.81);
    let n = 40;
    let model = pendulum(l, n, section(mu, 2e7, 50.0, 35.0), m, r, 0.0);
    let mut c = Cable::new(model, Scheme::default()).unwrap();
    c.solve_static(1, 1e-10, 500).unwrap();
    let body = c.model.layout.end_body.unwrap();
    c.set_link_velocities(&[LinkVelocity { link: body.link, point: body.origin, linear: DVec3::new(u0, 0.0, 0.0), angular: DVec3::ZERO }]).unwrap();
    let (_, _, v, w) = c.model.body_state(&body);
    println!("payload velocity {v:?} m/s, angular {w:?} rad/s");
    assert!(v.distance(DVec3::new(u0, 0.0, 0.0)) < 1e-9 && w.length() < 1e-9);
    let tension = |s: f64| m * g + mu * g * (l - s);
    let profile = |s: f64| u0 * (tension(0.0) / tension(s)).ln() / (tension(0.0) / tension(l)).ln();
    let worst = c.node_velocities().iter().enumerate().map(|(i, vx)| vx.distance(DVec3::new(profile(l * i as f64 / n as f64), 0.0, 0.0))).fold(0.0, f64::max);
    let rigid = c.node_velocities().iter().enumerate().map(|(i, vx)| (vx.x - u0 * i as f64 / n as f64).abs()).fold(0.0, f64::max);
    println!("largest node deviation from the deflection shape {worst:.3e} m/s (from a straight rope {rigid:.3e} m/s)");
    assert!(worst < 1e-5 * u0, "{worst}");
    let (mut t, mut x) = (Vec::new(), Vec::new());
    for _ in 0..(3.0 * 9.0 * 60.0) as usize {
        c.step(1.0 / 60.0).unwrap();
        t.push(c.time());
        x.push(c.model.body_state(&body).0.x);
    }
    let period = mean_period(&upward_crossings(&t, &x.iter().map(|v| -v).collect::<Vec<_>>()));
    let amp = 0.5 * (x.iter().cloned().fold(f64::MIN, f64::max) - x.iter().cloned().fold(f64::MAX, f64::min));
    let expected = u0 * period / (2.0 * std::f64::consts::PI);
    println!("period {period:.5} s, amplitude {amp:.6} m vs u0/ω {expected:.6} m: {:+.2e}", amp / expected - 1.0);
    assert!((amp / expected - 1.0).abs() < 1e-3);
}
