//! Rope ends that move the way a coupling moves them: a base sampled from a
//! turning body, and an end-spring target that jumps between two samples
//! (a body another engine moved further than the rope's predictor).
//!
//! The rope is the tow rope of `examples/tow_rope.rs`: 24 mm polyester
//! (EA = 2.26 MN), 6 m in 24 elements, pinned at both ends, 1 cm short of
//! its span.

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::Scheme;
use glam::{DMat3, DVec3};
use std::f64::consts::PI;
use std::sync::Arc;

const LENGTH: f64 = 6.0;
const SPAN: f64 = 6.01;
const N: usize = 24;
/// Follower id of the sampled base.
const SOURCE: usize = 7;
/// Turn rate of the sampled base about the vertical, rad/s (the tow
/// truck's at full lock and top speed).
const OMEGA: f64 = 0.5;

fn polyester() -> RopeSection {
    RopeMaterial::polyester(0.024).section()
}

/// The rope, its elements damped at `τ = 0.01 s` (stiffness-proportional)
/// and by `drag` (velocity damping, 1/s).
fn rope(start: RopeStart, end: BaseMotion, drag: f64) -> Cable {
    let model = RopeBuilder::new(LENGTH, N, polyester(), 0.024)
        .path(vec![DVec3::ZERO, DVec3::new(SPAN, 0.0, 0.0)])
        .start(start)
        .end(RopeEnd::Pinned(end))
        .damping(0.01)
        .velocity_damping(drag, 0.0)
        .build()
        .unwrap();
    Cable::new(model, Scheme::default()).unwrap()
}

/// Time the turntable takes to reach [`OMEGA`] (a smooth ramp), s.
const RAMP: f64 = 1.0;

/// The turntable under the rope's start: at the origin, turning about +y,
/// from rest to [`OMEGA`] over [`RAMP`] (`ω = Ω (1 − cos(π t/T))/2`), then
/// steadily.
fn turntable(t: f64) -> BaseState {
    let (angle, rate, accel) = if t < RAMP {
        let k = PI / RAMP;
        (0.5 * OMEGA * (t - (k * t).sin() / k), 0.5 * OMEGA * (1.0 - (k * t).cos()), 0.5 * OMEGA * k * (k * t).sin())
    } else {
        (0.5 * OMEGA * RAMP + OMEGA * (t - RAMP), OMEGA, 0.0)
    };
    BaseState {
        rotation: DMat3::from_rotation_y(angle),
        position: DVec3::ZERO,
        angular_velocity: DVec3::new(0.0, rate, 0.0),
        velocity: DVec3::ZERO,
        angular_acceleration: DVec3::new(0.0, accel, 0.0),
        acceleration: DVec3::ZERO,
    }
}

/// The turntable as a coupling samples it at `t0`.
fn sample(t0: f64) -> SampledMotion {
    let s = turntable(t0);
    SampledMotion {
        source: SOURCE,
        t0,
        rotation: s.rotation,
        position: s.position,
        velocity: s.velocity,
        angular_velocity: s.angular_velocity,
        acceleration: s.acceleration,
    }
}

/// A sampled motion at constant angular velocity extrapolates to the exact
/// rigid rotation `exp([ω dt]×) R(t0)`.
#[test]
fn a_sampled_motion_turns_at_its_angular_velocity() {
    let m = SampledMotion { angular_velocity: DVec3::new(0.3, -1.2, 0.7), ..sample(0.0) };
    let w = m.angular_velocity;
    let dt = 0.25;
    let expected = DMat3::from_axis_angle(w.normalize(), w.length() * dt) * m.rotation;
    let got = m.at(dt).rotation;
    let err = (got - expected).to_cols_array().iter().fold(0.0f64, |e, x| e.max(x.abs()));
    assert!(err < 1e-15, "rotation off by {err:e}");
    assert_eq!(m.at(m.t0).rotation, m.rotation);
}

/// A rope pinned to a turntable that a coupling samples before every step
/// (pose and angular velocity, no angular acceleration) moves as the same
/// rope on the prescribed turntable, up to what the samples leave out
/// while the turntable spins up. A pin turning about the vertical under a
/// rope laid along x leaves the rope where it is (bending at a pin is
/// free; only the pin's torsion spring twists the rope): both ropes keep
/// their initial tension and stay in their vertical plane.
///
/// (A consistency check of the sampled base: this rope also runs with the
/// sample's orientation held over the step, as it was before. The tow
/// rope that did not is `examples_headless::tow_rope_steers_headless`.)
#[test]
fn a_rope_on_a_sampled_turning_base_moves_as_on_the_prescribed_one() {
    let end = BaseMotion::point(DVec3::new(SPAN, 0.0, 0.0));
    let mut exact = rope(RopeStart::Pinned(BaseMotion::Prescribed(Arc::new(turntable))), end.clone(), 0.0);
    let mut sampled = rope(RopeStart::Pinned(BaseMotion::Sampled(sample(0.0))), end, 0.0);
    let h = 1.0 / 600.0;
    let tension = |c: &Cable| (0..N).filter_map(|i| c.element_forces(i)).map(|f| f.tension).fold(0.0f64, f64::max);
    let t_start = tension(&exact);
    let (mut its_exact, mut its_sampled) = (0, 0);
    let (mut peak_exact, mut peak_sampled) = (0.0f64, 0.0f64);
    let steps = 1800;
    for _ in 0..steps {
        assert_eq!(sampled.model.chain.set_sampled(sample(sampled.time())), 1);
        let t = exact.time();
        its_exact += exact.step(h).unwrap_or_else(|e| panic!("prescribed, t = {t:.4} s: {e}")).newton_iterations;
        its_sampled += sampled.step(h).unwrap_or_else(|e| panic!("sampled, t = {t:.4} s: {e}")).newton_iterations;
        peak_exact = peak_exact.max((tension(&exact) - t_start).abs());
        peak_sampled = peak_sampled.max((tension(&sampled) - t_start).abs());
    }
    println!("largest tension change {peak_exact:.2} N (prescribed), {peak_sampled:.2} N (sampled)");
    let gap = exact.nodes().iter().zip(sampled.nodes()).map(|(a, b)| a.distance(b)).fold(0.0f64, f64::max);
    let (te, ts) = (tension(&exact), tension(&sampled));
    println!(
        "3 s: nodes {gap:.3e} m apart; tension {t_start:.1} N at the start, {te:.1} / {ts:.1} N (prescribed / sampled); Newton iterations per step {:.2} / {:.2}; the pin turned {:.0}°",
        its_exact as f64 / steps as f64,
        its_sampled as f64 / steps as f64,
        OMEGA * exact.time() * 180.0 / PI
    );
    // The turning pin leaves the rope where it was.
    let plane = |c: &Cable| c.nodes().iter().map(|p| p.z.abs()).fold(0.0f64, f64::max);
    let (pe, ps) = (plane(&exact), plane(&sampled));
    println!("largest distance from the vertical plane: {pe:.3e} m (prescribed), {ps:.3e} m (sampled)");
    assert!(gap < 2e-4, "sampled and prescribed ropes {gap:e} m apart");
    assert!((ts - te).abs() < 1e-4 * te, "tensions {te} / {ts}");
    assert!(pe.max(ps) < 1e-3, "a rope left its vertical plane by {:e} m", pe.max(ps));
    assert!((te - t_start).abs() < 1e-3 * t_start && (ts - t_start).abs() < 1e-3 * t_start, "tension {t_start} → {te} / {ts}");
    assert!(peak_sampled < 1.01 * peak_exact + 1.0, "the sampled rope's tension swung by {peak_sampled} N, the prescribed one's by {peak_exact} N");
}

/// The far end's target jumps 1 mm along each axis between two steps (a
/// body moved by another engine further than the rope's predictor knew).
/// The end's anchor spring (1000·EA/L_e = 9.0e9 N/m) then pulls with
/// 1.6e7 N, seven times EA, at the predicted state. The geometric
/// stiffness of that unbalanced load makes the tangent indefinite, and the
/// Newton direction turns soft modes by radians: the step failed down to
/// 32 sub-steps (124 Newton iterations). The integrator now retries the
/// failed step with the fallback that solves indefinite iterates without
/// the geometric stiffness (`SecondOrderSystem::set_definite_tangent`), which
/// converges at the full step. Afterwards the rope settles at the tension
/// of the longer span: ΔT = EA·Δd/L for a taut string (the sag's share,
/// `EA w²L²/(12 T³)`, is 2.5e-3 of it here).
#[test]
fn a_jump_of_the_end_target_beyond_ea_converges() {
    let jump = DVec3::splat(1e-3);
    let t_jump = 1.0;
    let base = DVec3::new(SPAN, 0.0, 0.0);
    let target = move |t: f64| BaseState::fixed(DMat3::IDENTITY, if t < t_jump { base } else { base + jump });
    // Drag settles the sideways swing the jump starts (static tension).
    let mut c = rope(RopeStart::Pinned(BaseMotion::point(DVec3::ZERO)), BaseMotion::Prescribed(Arc::new(target)), 2.0);
    let h = 1.0 / 600.0;
    let tension_at_end = |c: &Cable| c.element_forces(N - 1).map_or(f64::NAN, |f| f.tension);
    let mut worst = StepsAtJump { iterations: 0, substeps: 0, retries: 0 };
    let mut before = 0.0;
    while c.time() < 4.0 {
        if c.time() + h >= t_jump && c.time() < t_jump {
            before = tension_at_end(&c);
        }
        let stats = c.step(h).unwrap_or_else(|e| panic!("t = {:.4} s: {e}", c.time()));
        if (c.time() - t_jump).abs() < 2.5 * h {
            worst.iterations = worst.iterations.max(stats.newton_iterations);
            worst.substeps = worst.substeps.max(stats.substeps_used);
            worst.retries += stats.definite_retries;
        }
    }
    let after = tension_at_end(&c);
    let expected = polyester().ea * (SPAN + jump.x - LENGTH) / LENGTH - polyester().ea * (SPAN - LENGTH) / LENGTH;
    let err = (after - before - expected) / expected;
    println!(
        "jump: at most {} Newton iterations and {} sub-steps per step, {} steps retried; tension {before:.1} → {after:.1} N, rise {:.2} N, EA·Δd/L = {expected:.2} N ({err:+.2e})",
        worst.iterations,
        worst.substeps,
        worst.retries,
        after - before
    );
    assert!(worst.substeps <= 1, "the jump's step was split into {} sub-steps", worst.substeps);
    assert!(worst.iterations <= 30, "{} Newton iterations at the jump", worst.iterations);
    assert!(err.abs() < 0.01, "tension rise off by {err:e}");
}

/// The worst of the steps around the jump.
struct StepsAtJump {
    iterations: usize,
    substeps: u64,
    retries: usize,
}

/// A prescribed support that shakes along x (0.3 m, period 1 s) and
/// tilts about z (0.2 rad, period 0.7 s) about its origin at `p0`.
fn shaking(p0: DVec3) -> impl Fn(f64) -> BaseState + Send + Sync + 'static {
    move |t: f64| {
        let (wx, wz) = (2.0 * PI, 2.0 * PI / 0.7);
        let (ax, az) = (0.3, 0.2);
        let angle = az * (wz * t).sin();
        BaseState {
            rotation: DMat3::from_rotation_z(angle),
            position: p0 + DVec3::new(ax * (wx * t).sin(), 0.0, 0.0),
            angular_velocity: DVec3::new(0.0, 0.0, az * wz * (wz * t).cos()),
            velocity: DVec3::new(ax * wx * (wx * t).cos(), 0.0, 0.0),
            angular_acceleration: DVec3::new(0.0, 0.0, -az * wz * wz * (wz * t).sin()),
            acceleration: DVec3::new(-ax * wx * wx * (wx * t).sin(), 0.0, 0.0),
        }
    }
}

/// The work–energy theorem for a rope on moving supports (the account the
/// integrator's energy check uses, `SecondOrderSystem::energy_balance`):
/// an undamped rope's energy changes by the work its supports' prescribed
/// motion does, `W = ∫ P dt` with `P = −V_base · F_base` (spatial velocity
/// of the base and the load the rope puts on it, force and moment) plus
/// each anchor spring's force times its target's velocity. Two undamped
/// polyester ropes (6 m, 24 elements, hanging 6 m) stepped at h = 25 µs
/// for 2 s: one clamped to a shaking (0.3 m) and tilting (0.2 rad) support
/// and hanging free (the base's force and moment), one pinned at a fixed
/// top with its end pinned to a shaking point below (the end's anchor
/// spring). `E(t) − E(0) − W(t)` (W by the trapezoidal rule per step)
/// stays within 1e-3 of the largest `|W|`. Measured: 1.2e-4 of 23.6 J and
/// 1.1e-4 of 8.3 J; what is left is the scheme's numerical damping (the
/// anchor case: 4.3e-3 at h = 0.1 ms, 7.7e-4 at 50 µs; the tilting case
/// loses 1.9 mJ once, at 0.35 s, at every step size: a kink of the slack
/// tail). Without the moment term the tilt's work (0.95 J) would be
/// missed, without the anchor's share all of its 8.3 J.
#[test]
fn the_energy_of_a_rope_on_moving_supports_changes_by_their_work() {
    use bevy_rapier_cable::integrate::SecondOrderSystem;
    let build = |start: RopeStart, end: RopeEnd, path: Vec<DVec3>| {
        let model = RopeBuilder::new(LENGTH, N, polyester(), 0.024).path(path).start(start).end(end).damping(0.0).build().unwrap();
        Cable::new(model, Scheme::default()).unwrap()
    };
    let top = DVec3::new(0.0, 6.0, 0.0);
    let hanging = build(RopeStart::Clamped(BaseMotion::Prescribed(Arc::new(shaking(top)))), RopeEnd::Free, vec![top, DVec3::ZERO]);
    let mut span =
        build(RopeStart::Pinned(BaseMotion::point(top)), RopeEnd::Pinned(BaseMotion::Prescribed(Arc::new(shaking(DVec3::ZERO)))), vec![top, DVec3::ZERO]);
    // A soft end spring (ω ≈ 630 rad/s with the last element's mass), so
    // that the step resolves it: the end pin's own spring (9.0e9 N/m)
    // rings at h ω ≈ 10 here, where the scheme's numerical damping takes
    // energy out.
    span.model.chain.anchors_mut()[0].stiffness = 2e4;
    for (label, mut c) in [("clamped to a shaking support", hanging), ("end pinned to a shaking point", span)] {
        let balance = |c: &mut Cable| {
            let (t, q, v, a) = (c.time(), c.state.q.clone(), c.state.v.clone(), c.state.a.clone());
            SecondOrderSystem::energy_balance(&mut c.model.chain, t, &q, &v, &a).expect("an undamped rope on moving supports has an energy account")
        };
        let h = 2.5e-5;
        let first = balance(&mut c);
        let (mut prev, mut work, mut most_work, mut worst) = (first, 0.0, 0.0f64, 0.0f64);
        while c.time() < 2.0 - 1e-9 {
            c.step(h).unwrap_or_else(|e| panic!("{label}, t = {:.4} s: {e}", c.time()));
            let now = balance(&mut c);
            work += 0.5 * h * (prev.power + now.power);
            most_work = most_work.max(work.abs());
            worst = worst.max((now.total() - first.total() - work).abs());
            prev = now;
        }
        println!("{label}: largest |W| {most_work:.3} J, largest |E − E0 − W| {worst:.3e} J ({:.2e} of it)", worst / most_work);
        assert!(most_work > 1.0, "{label}: the supports did only {most_work} J");
        assert!(worst < 1e-3 * most_work, "{label}: energy off its supports' work by {worst} J (work up to {most_work} J)");
    }
}
