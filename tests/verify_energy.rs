//! Energy conservation of the undamped rope with the non-dissipative
//! implicit schemes (Newmark average acceleration, generalized-α ρ∞ = 1),
//! and the dissipation of the default generalized-α ρ∞ = 0 as a contrast.

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::Scheme;
use glam::{DMat3, DVec3};

/// A 5 m rope (μ 0.5 kg/m, EA 1e5 N, EI = GJ = 1), 10 elements, pinned at
/// the origin, laid straight at 30° from the downward vertical, with a
/// 10 kg sphere (r = 0.1 m) on a ball joint at its end. No damping; the
/// linear axial law.
fn rope_pendulum() -> RopeModel {
    let angle = 30f64.to_radians();
    let (l, r) = (5.0, 0.1);
    let dir = DVec3::new(angle.sin(), -angle.cos(), 0.0);
    let body = LumpedBody::sphere(10.0, r, dir * (l + r));
    RopeBuilder::new(l, 10, RopeSection { linear_density: 0.5, ea: 1e5, ei: 1.0, ei2: 1.0, gj: 1.0, min_breaking_load: 0.0 }, 0.02)
        .path(vec![DVec3::ZERO, dir * l])
        .start(RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, DVec3::ZERO))))
        .end(RopeEnd::Body { body, anchor: -dir * r, clamp: false })
        // The schemes' energy conservation on a smooth law: released
        // unstrained and undamped, this rope's stretch returns to zero every
        // axial period, and a tension-only kink crossed inside a step (not
        // located in time) costs the trapezoidal rule its exact balance.
        .tension_only(false)
        .build()
        .unwrap()
}

struct EnergyRun {
    /// (E(end) − E(0)) / swing energy.
    drift: f64,
    /// max |E(t) − E(0)| / swing energy.
    worst: f64,
    swing: f64,
    periods: f64,
    newton_per_step: f64,
    max_newton: usize,
}

fn run(scheme: Scheme, h: f64, duration: f64) -> EnergyRun {
    let mut c = Cable::new(rope_pendulum(), scheme).unwrap();
    let e0 = c.energy();
    let (mut worst, mut max_ke, mut newton, mut max_newton, mut steps) = (0.0f64, 0.0f64, 0, 0, 0);
    let mut last_sign = 0.0;
    let mut crossings = 0;
    while c.time() < duration - 0.5 * h {
        let s = c.step(h).unwrap();
        newton += s.newton_iterations;
        max_newton = max_newton.max(s.newton_iterations);
        steps += 1;
        worst = worst.max((c.energy() - e0).abs());
        max_ke = max_ke.max(c.kinetic_energy());
        let vx = c.node_velocities()[10].x;
        if last_sign < 0.0 && vx >= 0.0 {
            crossings += 1;
        }
        if vx != 0.0 {
            last_sign = vx.signum();
        }
    }
    EnergyRun {
        drift: (c.energy() - e0) / max_ke,
        worst: worst / max_ke,
        swing: max_ke,
        periods: crossings as f64,
        newton_per_step: newton as f64 / steps as f64,
        max_newton,
    }
}

/// Newmark average acceleration and generalized-α ρ∞ = 1 at h = 1 ms (and
/// 4 ms) conserve the total energy of the undamped rope pendulum over ~20
/// periods; generalized-α ρ∞ = 0 dissipates measurably.
#[test]
fn undamped_rope_pendulum_energy() {
    let duration = 92.0; // ≈ 20 periods of 4.6 s
    let cases: [(&str, Scheme, f64, f64); 5] = [
        ("Newmark ¼/½", Scheme::Newmark { beta: 0.25, gamma: 0.5 }, 1e-3, 1e-5),
        ("Newmark ¼/½", Scheme::Newmark { beta: 0.25, gamma: 0.5 }, 4e-3, 1e-4),
        ("gen-α ρ∞=1", Scheme::GeneralizedAlpha { rho_inf: 1.0 }, 1e-3, 1e-5),
        ("gen-α ρ∞=1", Scheme::GeneralizedAlpha { rho_inf: 1.0 }, 4e-3, 1e-4),
        ("gen-α ρ∞=0", Scheme::GeneralizedAlpha { rho_inf: 0.0 }, 1e-3, f64::INFINITY),
    ];
    let mut conservative_worst: f64 = 0.0;
    let mut dissipative = 0.0;
    let mut newmark_1ms = None;
    for (name, scheme, h, tol) in cases {
        let is_newmark = matches!(scheme, Scheme::Newmark { .. });
        let is_alpha1 = scheme == Scheme::GeneralizedAlpha { rho_inf: 1.0 };
        let r = run(scheme, h, duration);
        // Generalized-α with ρ∞ = 1 (α_m = α_f = ½, β = ¼, γ = ½) in the
        // Arnold–Brüls form with â₀ = a₀ is the trapezoidal rule itself.
        if h == 1e-3 && is_newmark {
            newmark_1ms = Some(r.drift);
        }
        if h == 1e-3 && is_alpha1 {
            let d = newmark_1ms.unwrap();
            println!("gen-α ρ∞=1 vs Newmark ¼/½ at 1 ms: energy drift {:.3e} vs {d:.3e}", r.drift);
            assert!((r.drift - d).abs() < 1e-9, "gen-α ρ∞ = 1 differs from Newmark average acceleration");
        }
        println!(
            "{name}, h = {h}: ΔE(end) {:+.2e}, max |ΔE| {:.2e} of the swing energy {:.2} J over {} periods; {:.2} Newton/step (max {})",
            r.drift, r.worst, r.swing, r.periods, r.newton_per_step, r.max_newton
        );
        if tol.is_finite() {
            assert!(r.worst < tol, "{name} h={h}: energy error {}", r.worst);
            if h == 1e-3 {
                conservative_worst = conservative_worst.max(r.worst);
            }
        } else {
            dissipative = -r.drift;
        }
        assert!(r.periods >= 18.0);
    }
    // The contrast: ρ∞ = 0 loses far more than the conservative schemes'
    // error band.
    assert!(dissipative > 100.0 * conservative_worst, "ρ∞ = 0 dissipation {dissipative} vs {conservative_worst}");
}
