//! Implicit force elements (issue 10, item 7): a user law at a point of the
//! rope, with its stiffness and damping tangents in the implicit solve.

use std::sync::Arc;

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::Scheme;
use glam::DVec3;

const G: f64 = 9.81;
const L: f64 = 10.0;
const M: f64 = 1000.0;
const R: f64 = 0.01;

/// A 1 t, 1 cm ball on a ball joint at the end of a light, stiff 10 m line
/// (0.1 kg/m, EA 1e9 N: 1 kg of line, 1e-7 stretch), pinned at the origin
/// and released at angle `theta0` in the x–y plane; a [`PointSpring`]
/// (`k`, `c`) at the line's end pulls it toward the point below the pin.
fn pendulum(theta0: f64, k: f64, c: f64) -> Cable {
    let section = RopeSection { linear_density: 0.1, ea: 1e9, ei: 1e-3, ei2: 1e-3, gj: 1e-3, min_breaking_load: 0.0 };
    let dir = DVec3::new(theta0.sin(), -theta0.cos(), 0.0);
    let body = LumpedBody::sphere(M, R, dir * (L + R));
    let model =
        RopeBuilder::new(L, 10, section, 0.01).end(RopeEnd::Body { body, anchor: -dir * R, clamp: false }).path(vec![DVec3::ZERO, dir * L]).build().unwrap();
    let mut cable = Cable::new(model, Scheme::default()).unwrap();
    let spring = PointSpring { target: DVec3::new(0.0, -L, 0.0), stiffness: k, damping: c };
    assert!(cable.add_force_element(0, L, Arc::new(spring)));
    cable
}

/// The payload's x and the times its x crosses zero upwards, over
/// `duration` at step `h`.
fn swing(cable: &mut Cable, h: f64, duration: f64) -> (Vec<f64>, Vec<f64>) {
    let body = cable.model.layout.end_body.unwrap();
    let (mut xs, mut ups) = (Vec::new(), Vec::new());
    let mut prev = (cable.time(), cable.model.body_state(&body).0.x);
    while cable.time() < duration - 1e-9 {
        cable.step(h).unwrap_or_else(|e| panic!("{e}"));
        let (t, x) = (cable.time(), cable.model.body_state(&body).0.x);
        if prev.1 < 0.0 && x >= 0.0 {
            ups.push(prev.0 + (t - prev.0) * (-prev.1) / (x - prev.1));
        }
        xs.push(x);
        prev = (t, x);
    }
    (xs, ups)
}

/// The lower natural frequency (rad/s) of the pendulum as two rigid
/// bodies (closed form): a massless line of length L from the pin, and the
/// ball (mass m, radius r, J = 2/5 m r²) on a ball joint at its end, with
/// the side spring k at the joint. Linearised in (θ₁ line, θ₂ ball):
/// `M = [[m L², m L r], [m L r, m r² + J]]`,
/// `K = [[m g L + k L², 0], [0, m g r]]`, `det(K − ω² M) = 0`.
fn two_body_frequency(k: f64) -> f64 {
    let j = 0.4 * M * R * R;
    let (m11, m12, m22) = (M * L * L, M * L * R, M * R * R + j);
    let (k11, k22) = (M * G * L + k * L * L, M * G * R);
    // (m11 m22 − m12²) λ² − (k11 m22 + k22 m11) λ + k11 k22 = 0.
    let (a, b, c) = (m11 * m22 - m12 * m12, -(k11 * m22 + k22 * m11), k11 * k22);
    let lambda = (-b - (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
    lambda.sqrt()
}

/// Small swings (0.05 rad) of the pendulum with a side spring k at the
/// line's end, 20 s at h = 1/240 s: the frequency matches
/// [`two_body_frequency`] within 0.1 % for k from 0 to 10 m g/L; and the
/// total energy, with the spring's potential ([`ForceElement::energy`]),
/// never rises by more than 1e-4 of the swing energy and loses at most
/// 2 % (the integrator's numerical dissipation; without the spring's
/// potential it would swing by up to 90 % at k = 1e4 N/m).
#[test]
fn side_spring_sets_the_pendulum_frequency() {
    for k in [0.0, 1e3, 1e4] {
        let mut cable = pendulum(0.05, k, 0.0);
        let e0 = cable.energy();
        let swing_energy = M * G * (L + R) * (1.0 - 0.05f64.cos()) + 0.5 * k * (L * 0.05f64.sin()).powi(2);
        let (mut rise, mut loss) = (0.0f64, 0.0f64);
        let (mut ups, mut prev) = (Vec::new(), (0.0, L * 0.05f64.sin()));
        let body = cable.model.layout.end_body.unwrap();
        let h = 1.0 / 240.0;
        while cable.time() < 20.0 - 1e-9 {
            cable.step(h).unwrap_or_else(|e| panic!("{e}"));
            let de = (cable.energy() - e0) / swing_energy;
            (rise, loss) = (rise.max(de), loss.min(de));
            let (t, x) = (cable.time(), cable.model.body_state(&body).0.x);
            if prev.1 < 0.0 && x >= 0.0 {
                ups.push(prev.0 + (t - prev.0) * (-prev.1) / (x - prev.1));
            }
            prev = (t, x);
        }
        let period = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
        let omega_ref = two_body_frequency(k);
        let err = 2.0 * std::f64::consts::PI / period / omega_ref - 1.0;
        println!(
            "k = {k:.0e} N/m: ω {:.5} rad/s vs {omega_ref:.5} ({err:+.2e}); energy at most {rise:+.1e}, at least {loss:+.1e} of the swing energy",
            2.0 * std::f64::consts::PI / period
        );
        assert!(ups.len() >= 3 && err.abs() < 1e-3, "k = {k}: frequency error {err:+.3e}");
        assert!(rise < 1e-4 && loss > -0.02, "k = {k}: energy rose by {rise:.2e}, fell by {loss:.2e}");
    }
}

/// A strong damper c at the line's end: the swing decays as the linear
/// closed form `e^{−ζωt}` with ζ = c L²/(2 m L'² ω), ω² = g/L' (the
/// amplitude after 3 periods within 2 % of it); and a spring of k h²/m = 28
/// at the frame step (1/60 s; an explicit force is unstable beyond 4),
/// started 2 mm from its target, never swings wider than that and settles
/// to rest there. (Started 1 cm away, see the next test.)
#[test]
fn damper_decays_the_swing_and_a_stiff_spring_is_stable_at_the_frame_step() {
    let lp = L + R;
    let omega = (G / lp).sqrt();
    let c = 100.0;
    let zeta = c * L * L / (2.0 * M * lp * lp * omega);
    let mut cable = pendulum(0.05, 0.0, c);
    let period = 2.0 * std::f64::consts::PI / (omega * (1.0 - zeta * zeta).sqrt());
    let (xs, _) = swing(&mut cable, 1.0 / 240.0, 4.0 * period + 0.5);
    let h = 1.0 / 240.0;
    // Peak |x| over the first and over the fourth swing period.
    let per = (period / h) as usize;
    let peak = |k: usize| xs[k * per..(k + 1) * per].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let ratio = peak(3) / peak(0);
    let expected = (-zeta * omega * 3.0 * period).exp();
    println!("ζ = {zeta:.4}: amplitude ratio over 3 periods {ratio:.4} vs {expected:.4} ({:+.2e})", ratio / expected - 1.0);
    assert!((ratio / expected - 1.0).abs() < 0.02, "decay {ratio} vs {expected}");

    let (k, theta0) = (28.0 * M * 3600.0, 2e-4);
    let mut stiff = pendulum(theta0, k, 0.0);
    let (xs, _) = swing(&mut stiff, 1.0 / 60.0, 5.0);
    let last = xs.last().copied().unwrap();
    let largest = xs.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    println!("k h²/m = 28 at 1/60 s: largest |x| {largest:.3e} m, last {last:.2e} m");
    assert!(largest <= L * theta0.sin() && last.abs() < 1e-4, "stiff spring not stable: largest {largest}, last {last}");
}

/// The open limit above, at 1 cm: the spring (k h²/m = 28 at 1/60 s)
/// started 1 cm from its target pulls the light line's end sideways with
/// 1.0e6 N, 103 times the payload's weight. The O(n) tangent leaves out the
/// inertia terms that are not symmetric, and Newton on it converges only
/// linearly there: a few steps need 10 to 20 iterations. A chain with force
/// elements is a patient system (`SecondOrderSystem::patient_newton`): its
/// solve continues past the 8-iteration budget while the corrections do not
/// grow. Splitting those steps instead failed down to 256 sub-steps (a
/// fine step resolves the whip of the light line, which the frame step's
/// numerical damping filters out).
/// * It runs 3 s at the frame step without splitting a step (it failed at
///   t = 0.083 s), at under 5 iterations per step on average.
/// * The scheme (generalized-α, ρ∞ = 0) only takes energy out: the total
///   energy falls at every step, and the payload stays within the
///   spring's reach.
/// * Started 10 cm off (1 030 times the weight), it runs its 3 s too, at
///   the finest split (256 sub-steps per frame step, 1 600 Newton
///   iterations): the sub-steps whose solve fails there are cut into up to
///   64 pieces (`NewtonSettings::rescue_pieces`; it failed at the first
///   step before). The finest split's sub-steps are not energy-checked and
///   a step may gain up to 2.8e4 J (6 % of the spring's energy), but the
///   total never rises above its start and the payload stays within the
///   10 cm it started from.
#[test]
fn a_spring_pulling_100_times_the_weight_runs_at_the_frame_step() {
    let k = 28.0 * M * 3600.0;
    let start = |off: f64| pendulum((off / L).asin(), k, 0.0);
    let mut cable = start(0.01);
    let body = cable.model.layout.end_body.unwrap();
    let mut e = cable.energy();
    let (mut rise, mut largest, mut steps) = (f64::NEG_INFINITY, 0.0f64, 0);
    while cable.time() < 3.0 - 1e-9 {
        let stats = cable.step(1.0 / 60.0).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(stats.substeps_used, 1, "a step was split at t = {}", cable.time());
        rise = rise.max(cable.energy() - e);
        e = cable.energy();
        largest = largest.max(cable.model.body_state(&body).0.x.abs());
        steps += 1;
    }
    let per_step = cable.total_stats.newton_iterations as f64 / steps as f64;
    println!(
        "1 cm: {per_step:.2} Newton iterations per step; largest energy change over a step {rise:+.3e} J (spring energy {:.0} J); largest |x| {largest:.3e} m",
        0.5 * k * 1e-4
    );
    assert!(per_step < 5.0, "{per_step} iterations per step");
    assert!(rise <= 0.0, "energy rose by {rise} J");
    assert!(largest <= 0.0101, "largest |x| {largest}");

    let mut far = start(0.1);
    let e_start = far.energy();
    let (mut e, mut rise, mut largest, mut steps, mut most_substeps, mut highest) = (e_start, f64::NEG_INFINITY, 0.0f64, 0, 0, f64::NEG_INFINITY);
    while far.time() < 3.0 - 1e-9 {
        let stats = far.step(1.0 / 60.0).unwrap_or_else(|e| panic!("10 cm: {e}"));
        most_substeps = most_substeps.max(stats.substeps_used);
        rise = rise.max(far.energy() - e);
        e = far.energy();
        highest = highest.max(e);
        largest = largest.max(far.model.body_state(&body).0.x.abs());
        steps += 1;
    }
    let s = far.total_stats;
    println!(
        "10 cm: {:.1} Newton iterations and {:.1} sub-steps per step (at most {most_substeps}), {} rescued sub-steps; largest energy change over a step {rise:+.3e} J (spring energy {:.0} J, total {e_start:.0} → {e:.0} J, at most {highest:.0} J); largest |x| {largest:.4} m",
        s.newton_iterations as f64 / steps as f64,
        s.substeps_used as f64 / steps as f64,
        s.rescued_substeps,
        0.5 * k * 1e-2
    );
    assert!(highest <= e_start, "10 cm: the total rose to {highest} J from {e_start} J");
    assert!(largest <= 0.1, "10 cm: largest |x| {largest}");
}
