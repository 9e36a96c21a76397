//! Wilson-θ in Bathe's textbook form.
//!
//! Linear acceleration over the extended interval `τ = θ h`:
//! `q_θ = q + τ v + τ²/3 a₀ + τ²/6 a_θ`, `v_θ = v + τ/2 (a₀ + a_θ)`, with
//! the equation of motion enforced at `t + τ` (Newton on `a_θ`); then
//! `a₁ = a₀ + (a_θ − a₀)/θ` and `q₁`, `v₁` from the linear-acceleration
//! formulas with `h`. The stored `a₁` is this interpolated acceleration, not
//! the one the equation of motion gives at `(t₁, q₁, v₁)`. Loads are evaluated
//! at `t + τ` directly (Bathe extrapolates them linearly from `t` and
//! `t + h`: the same for loads linear in time).

use super::integrator::{StepStats, Workspace};
use super::newton::{self, Affine, Failure, NewtonSettings};
use super::state::State;
use super::system::SecondOrderSystem;

/// `θ` from which Wilson-θ is unconditionally stable: `(1 + √3)/2`.
pub(crate) const THETA_UNCONDITIONAL: f64 = 1.366_025_403_784_438_6;

/// One Wilson-θ step of size `h` (s).
#[allow(clippy::too_many_arguments)]
pub(crate) fn step_wilson<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    state: &mut State,
    ws: &mut Workspace,
    theta: f64,
    h: f64,
    settings: &NewtonSettings,
    stats: &mut StepStats,
) -> Result<(), Failure> {
    let tau = theta * h;
    for i in 0..state.dof() {
        let a0 = state.a[i];
        ws.qb[i] = state.q[i] + tau * state.v[i] + tau * tau / 3.0 * a0;
        ws.vb[i] = state.v[i] + 0.5 * tau * a0;
        ws.x[i] = a0;
    }
    let map = Affine { t: state.t + tau, c_q: tau * tau / 6.0, c_v: 0.5 * tau, h };
    newton::solve(sys, ws, map, settings, false, stats, (&state.q, &state.v))?;
    for i in 0..state.dof() {
        let a0 = state.a[i];
        let a1 = a0 + (ws.x[i] - a0) / theta;
        state.q[i] += h * state.v[i] + h * h * (a0 / 3.0 + a1 / 6.0);
        state.v[i] += 0.5 * h * (a0 + a1);
        state.a[i] = a1;
        state.a_hat[i] = a1;
    }
    state.t += h;
    Ok(())
}

/// Ω_crit of Wilson-θ on `ẍ + ω² x = 0`: `None` for
/// `θ ≥ (1 + √3)/2`, else found by bisection on the spectral radius of the
/// amplification matrix (θ = 1 is linear acceleration, √12).
pub(crate) fn stability_limit(theta: f64) -> Option<f64> {
    if theta.is_nan() || theta < 1.0 {
        return Some(0.0);
    }
    if theta >= THETA_UNCONDITIONAL {
        return None;
    }
    let unstable = |omega: f64| spectral_radius(theta, omega) > 1.0 + 1e-9;
    // Scan up from the linear-acceleration limit (the limit grows with θ).
    let mut lo = 3.0;
    let mut hi = lo;
    while !unstable(hi) {
        lo = hi;
        hi *= 1.1;
        if hi > 1e9 {
            return None;
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if unstable(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// Spectral radius of Wilson-θ's amplification matrix on `(x, h v, h² a)`
/// for `Ω = ω h`.
pub(crate) fn spectral_radius(theta: f64, omega: f64) -> f64 {
    let w2 = omega * omega;
    // Columns: images of unit x, v, a with h = 1.
    let column = |x: f64, v: f64, a: f64| {
        let t = theta;
        let a_t = -w2 * (x + t * v + t * t / 3.0 * a) / (1.0 + w2 * t * t / 6.0);
        let a1 = a + (a_t - a) / t;
        [x + v + a / 3.0 + a1 / 6.0, v + 0.5 * (a + a1), a1]
    };
    let c = [column(1.0, 0.0, 0.0), column(0.0, 1.0, 0.0), column(0.0, 0.0, 1.0)];
    let m = |i: usize, j: usize| c[j][i];
    let trace = m(0, 0) + m(1, 1) + m(2, 2);
    let minors = m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0) + m(0, 0) * m(2, 2) - m(0, 2) * m(2, 0) + m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1);
    let det = m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1)) - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0))
        + m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
    cubic_spectral_radius(trace, minors, det)
}

/// Largest root modulus of `λ³ − c2 λ² + c1 λ − c0`.
fn cubic_spectral_radius(c2: f64, c1: f64, c0: f64) -> f64 {
    let p = |l: f64| ((l - c2) * l + c1) * l - c0;
    let bound = 1.0 + c2.abs().max(c1.abs()).max(c0.abs());
    let (mut lo, mut hi) = (-bound, bound);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if p(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let r = 0.5 * (lo + hi);
    // λ³ − c2 λ² + c1 λ − c0 = (λ − r)(λ² + b λ + c)
    let b = r - c2;
    let c = c1 + r * b;
    let disc = b * b - 4.0 * c;
    let quad = if disc < 0.0 {
        c.abs().sqrt()
    } else {
        let s = disc.sqrt();
        (0.5 * (-b + s)).abs().max((0.5 * (-b - s)).abs())
    };
    r.abs().max(quad)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn theta_one_is_linear_acceleration() {
        let limit = {
            // θ = 1 takes the bisection path; it must find √12.
            let unstable = |o: f64| spectral_radius(1.0, o) > 1.0 + 1e-9;
            assert!(!unstable(3.46) && unstable(3.47));
            stability_limit(1.0).expect("conditional")
        };
        assert!((limit - 12f64.sqrt()).abs() < 1e-3, "{limit}");
    }

    #[test]
    fn unconditional_threshold() {
        let below = stability_limit(1.36).expect("conditional below 1.366");
        assert!(below > 12f64.sqrt(), "{below}");
        // Just above the threshold: stable at every Ω tried.
        for k in 0..200 {
            let omega = 0.01 * 1.1f64.powi(k);
            assert!(spectral_radius(1.3661, omega) <= 1.0 + 1e-9, "Ω = {omega}");
        }
        assert!(spectral_radius(1.3659, 1e4) > 1.0);
    }
}
