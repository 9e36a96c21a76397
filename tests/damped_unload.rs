//! Damped unloading (issue 10, item 4 and 6): a 1 t block falls 3 m onto a
//! 10 m steel rope with stiffness-proportional damping (τ = c/k), the rope
//! snaps taut, and the block rebounds while the rope unloads faster than
//! its damper lets it (`u + τ u̇ < 0`: the clamped law gives zero force
//! while the element is still stretched). Before the semi-smooth last
//! resort of the Newton solve this failed at every split down to 1/256 of
//! the frame step.
//!
//! Reference: the rope as a massless Kelvin–Voigt spring (k = EA/L,
//! c = τ k) under the block, closed form. From the moment it goes taut
//! (x = 0, ẋ = v₀ = √(2 g 3 m)) the stretch is the damped oscillator
//! `x = x_s + e^{−ζωt}(A cos ω_d t + B sin ω_d t)`, `x_s = m g/k`, until the
//! force `k x + c ẋ` returns to zero; the block then leaves with velocity
//! `ẋ` there (upwards). Peak force and that rebound velocity are the
//! checked quantities (the rope's own 16 kg and its waves make the
//! closed form approximate: a few per cent).

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::Scheme;
use glam::DVec3;

const G: f64 = 9.81;
const M: f64 = 1000.0;
const L: f64 = 10.0;
const DROP: f64 = 7.0;

fn steel20() -> RopeSection {
    preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap()
}

/// The block hangs `DROP` below the pin on a rope laid straight (its
/// elements overlapping: slack), damping τ.
fn drop_on(segments: usize, tau: f64) -> Cable {
    let attach = DVec3::new(0.0, -DROP, 0.0);
    let body = LumpedBody::sphere(M, 0.3, attach - DVec3::new(0.0, 0.3, 0.0));
    let model = RopeBuilder::new(L, segments, steel20(), 0.02)
        .end(RopeEnd::Body { body, anchor: DVec3::new(0.0, 0.3, 0.0), clamp: false })
        .path(vec![DVec3::ZERO, attach])
        .damping(tau)
        .build()
        .unwrap();
    Cable::new(model, Scheme::default()).unwrap()
}

/// Closed form of the massless Kelvin–Voigt rope: (peak force, rebound
/// speed when the force returns to zero).
fn kelvin_voigt(tau: f64) -> (f64, f64) {
    let k = steel20().ea / L;
    let c = tau * k;
    let v0 = (2.0 * G * (L - DROP)).sqrt();
    let w = (k / M).sqrt();
    let zeta = c / (2.0 * (k * M).sqrt());
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let xs = M * G / k;
    let (a, b) = (-xs, (v0 - zeta * w * xs) / wd);
    let state = |t: f64| {
        let e = (-zeta * w * t).exp();
        let (s, co) = (wd * t).sin_cos();
        let x = xs + e * (a * co + b * s);
        let xd = e * ((-zeta * w) * (a * co + b * s) + wd * (-a * s + b * co));
        (x, xd)
    };
    let force = |t: f64| {
        let (x, xd) = state(t);
        k * x + c * xd
    };
    // Scan for the peak and the first return of the force to zero.
    let dt = 1e-6;
    let (mut t, mut peak) = (dt, 0.0f64);
    while force(t) > 0.0 {
        peak = peak.max(force(t));
        t += dt;
    }
    let (mut lo, mut hi) = (t - dt, t);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if force(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (peak, -state(lo).1)
}

/// What a run measured: peak axial force, largest upward block speed,
/// least axial force, the largest rise of the total energy above its start
/// (J), Newton iterations and sub-steps per step.
struct Run {
    peak: f64,
    rebound: f64,
    least: f64,
    energy_rise: f64,
    newton: f64,
    substeps: f64,
}

fn run(segments: usize, tau: f64, h: f64, t_end: f64) -> Result<Run, String> {
    let mut cable = drop_on(segments, tau);
    let body = cable.model.layout.end_body.unwrap();
    let e0 = cable.energy();
    let (mut peak, mut rebound, mut least, mut rise) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let n = cable.elements();
    while cable.time() < t_end - 1e-9 {
        cable.step(h).map_err(|e| format!("N = {segments}, τ = {tau}, h = {h:.2e}: {e}"))?;
        for i in 0..n {
            let f = cable.element_forces(i).expect("element").tension;
            peak = peak.max(f);
            least = least.min(f);
        }
        rebound = rebound.max(cable.model.body_state(&body).2.y);
        rise = rise.max(cable.energy() - e0);
    }
    let s = cable.total_stats;
    let steps = cable.steps as f64;
    Ok(Run { peak, rebound, least, energy_rise: rise, newton: s.newton_iterations as f64 / steps, substeps: s.substeps_used as f64 / steps })
}

/// At a fine step the peak force and the rebound speed match the massless
/// Kelvin–Voigt rope within 5 % where the clamped law's early pull is small
/// (τ = 0.002: the damper engages in the last τ v₀ = 1.5 cm of an
/// element's 7.5 cm of slack); with larger τ it engages at once and the
/// block is caught softer (measured −9 % at τ = 0.01), never harder.
/// At the frame step (1/60 s) the drop and
/// several rebounds run for N = 40 and 100 and τ = 0.002 to 0.05 with no
/// push and no energy gain, and the scheme only removes energy: the block
/// rebounds (upward speed > 0) but no faster, and the rope pulls no
/// harder, than the continuous model (5 % for the rope's own mass). The
/// snap lasts π/ω = 74 ms, four and a half frame steps at ω h = 0.71, where
/// generalized-α with ρ∞ = 0 damps: the frame-step rebound is about 20 %
/// slower (printed, docs/verification.md).
#[test]
fn damped_drop_snaps_taut_and_rebounds_like_a_kelvin_voigt_rope() {
    let swing = M * G * L; // energy scale, J
    for tau in [0.002, 0.01, 0.05] {
        // ζ = τ ω/2 ≥ 1 (τ = 0.05): overdamped, the block does not rebound
        // and the closed form below has no return to zero force.
        let underdamped = 0.5 * tau * (steel20().ea / L / M).sqrt() < 1.0;
        let (peak_ref, rebound_ref) = if underdamped { kelvin_voigt(tau) } else { (f64::INFINITY, f64::INFINITY) };
        if underdamped {
            let fine = run(40, tau, 5e-4, 1.2).expect("fine step");
            let (e_peak, e_reb) = (fine.peak / peak_ref - 1.0, fine.rebound / rebound_ref - 1.0);
            println!(
                "τ = {tau}: closed form peak {peak_ref:.4e} N, rebound {rebound_ref:.3} m/s; h = 0.5 ms, N = 40: peak {:.4e} N ({e_peak:+.2e}), rebound {:.3} m/s ({e_reb:+.2e}), {:.2} Newton it/step",
                fine.peak, fine.rebound, fine.newton
            );
            if tau * (2.0 * G * (L - DROP)).sqrt() < 0.25 * (L - DROP) / 40.0 {
                // The damper engages at u = −τ u̇ (the clamped law): in the
                // last τ v₀ of each element's slack (7.5 cm here). Below a
                // quarter of it the closed form, which has no such early
                // pull, holds.
                assert!(e_peak.abs() < 0.05 && e_reb.abs() < 0.05, "fine step off the closed form: peak {e_peak:+.3}, rebound {e_reb:+.3}");
            } else {
                // Larger τ: the early pull only takes energy out.
                assert!(e_peak < 0.05 && e_reb < 0.05, "fine step above the closed form: peak {e_peak:+.3}, rebound {e_reb:+.3}");
            }
        } else {
            println!("τ = {tau}: overdamped (ζ ≥ 1), frame-step robustness only");
        }
        for n in [40, 100] {
            let frame = run(n, tau, 1.0 / 60.0, 4.0).expect("frame step");
            let e_reb = frame.rebound / rebound_ref - 1.0;
            println!(
                "    h = 1/60 s, N = {n}: peak {:.4e} N ({:+.2e}), rebound {:.3} m/s ({e_reb:+.2e}), least axial force {:.1e} m g, energy rise {:.1e} of m g L, {:.2} Newton it/step, {:.2} sub-steps/step",
                frame.peak,
                frame.peak / peak_ref - 1.0,
                frame.rebound,
                frame.least / (M * G),
                frame.energy_rise / swing,
                frame.newton,
                frame.substeps
            );
            assert!(frame.least > -0.01 * M * G, "the rope pushed: {} N", frame.least);
            assert!(frame.energy_rise < 1e-3 * swing, "energy rose by {} J", frame.energy_rise);
            assert!(frame.peak.is_finite() && frame.peak < 1.05 * peak_ref, "peak {} N", frame.peak);
            if underdamped {
                assert!(frame.rebound > 0.0 && e_reb < 0.05, "rebound {} m/s vs {rebound_ref} m/s", frame.rebound);
            }
        }
    }
}
