//! Explicit schemes on the first-order form `z = (q, v)`, `ż = (v, a(t, q, v))`
//! with `a = M⁻¹ Q` (one residual at `a = 0` and one solve with
//! `c_v = c_q = 0` per evaluation), and their automatic sub-steps.
//!
//! Every step starts from `state.a` (the acceleration at the step start,
//! computed by the previous step or [`State::new`]) and ends by computing
//! the acceleration at the new state, so evaluations per step are: explicit
//! and symplectic Euler 1, improved Euler 2, RK4 4.

use std::f64::consts::SQRT_2;

use super::error::IntegrateError;
use super::integrator::{StepStats, Workspace};
use super::scheme::Scheme;
use super::state::{acceleration, State};
use super::system::SecondOrderSystem;

/// Safety factor on the stability limit of symplectic Euler and RK4.
pub const SAFETY: f64 = 0.9;

/// Allowed amplitude growth over one whole step `h` for explicit Euler and
/// improved Euler, which grow at every step size (0.1 %).
pub const GROWTH: f64 = 1e-3;

/// Sub-steps an explicit scheme needs for a step `h` (s) on a system whose
/// highest frequency is `omega` (rad/s), as a real number (`≥ 1`, not yet
/// rounded up):
/// * symplectic Euler, RK4: `h ω / (SAFETY · Ω_crit)`;
/// * explicit Euler: amplitude growth `(1 + Ω_s²)^{n/2} ≤ 1 + GROWTH` with
///   `Ω_s = h ω / n`, guaranteed by `n ≥ (h ω)² / (2 ln(1 + GROWTH))`;
/// * improved Euler: `(1 + Ω_s⁴/4)^{n/2} ≤ 1 + GROWTH`, guaranteed by
///   `n ≥ ((h ω)⁴ / (8 ln(1 + GROWTH)))^{1/3}`.
///
/// `None` for implicit schemes.
pub fn substeps_needed(scheme: &Scheme, h: f64, omega: f64) -> Option<f64> {
    let x = h * omega.max(0.0);
    let ln_growth = GROWTH.ln_1p();
    let n = match scheme {
        Scheme::SymplecticEuler => x / (SAFETY * 2.0),
        Scheme::Rk4 => x / (SAFETY * 2.0 * SQRT_2),
        Scheme::ExplicitEuler => x * x / (2.0 * ln_growth),
        Scheme::ImprovedEuler => (x.powi(4) / (8.0 * ln_growth)).cbrt(),
        _ => return None,
    };
    Some(n.max(1.0))
}

/// Largest admissible sub-step (s) for `Substeps::Fixed` at frequency
/// `omega` (rad/s): the stability limit `Ω_crit/ω` for symplectic Euler and
/// RK4 (no safety factor), and for the Euler schemes `h/n_needed`, the
/// sub-step that keeps the growth over `h` within [`GROWTH`].
pub(crate) fn admissible_substep(scheme: &Scheme, h: f64, omega: f64) -> f64 {
    match scheme {
        Scheme::SymplecticEuler => 2.0 / omega,
        Scheme::Rk4 => 2.0 * SQRT_2 / omega,
        _ => h / substeps_needed(scheme, h, omega).unwrap_or(1.0).ceil(),
    }
}

/// One explicit step of size `h` (s).
pub(crate) fn step<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    state: &mut State,
    ws: &mut Workspace,
    scheme: &Scheme,
    h: f64,
    stats: &mut StepStats,
) -> Result<(), IntegrateError> {
    let (t, n) = (state.t, state.dof());
    let Workspace { r, zeros, sq, sv, sa, dq_sum, dv_sum, .. } = ws;
    let mut acc = |t: f64, q: &[f64], v: &[f64], out: &mut [f64], stats: &mut StepStats| acceleration(sys, t, q, v, zeros, r, out, stats);
    match scheme {
        Scheme::ExplicitEuler => {
            for i in 0..n {
                state.q[i] += h * state.v[i];
                state.v[i] += h * state.a[i];
            }
        }
        Scheme::SymplecticEuler => {
            for i in 0..n {
                state.v[i] += h * state.a[i];
                state.q[i] += h * state.v[i];
            }
        }
        Scheme::ImprovedEuler => {
            for i in 0..n {
                sq[i] = state.q[i] + h * state.v[i];
                sv[i] = state.v[i] + h * state.a[i];
            }
            acc(t + h, sq, sv, sa, stats)?;
            for i in 0..n {
                state.q[i] += 0.5 * h * (state.v[i] + sv[i]);
                state.v[i] += 0.5 * h * (state.a[i] + sa[i]);
            }
        }
        Scheme::Rk4 => {
            let h2 = 0.5 * h;
            for i in 0..n {
                sq[i] = state.q[i] + h2 * state.v[i];
                sv[i] = state.v[i] + h2 * state.a[i];
            }
            acc(t + h2, sq, sv, sa, stats)?;
            for i in 0..n {
                dq_sum[i] = state.v[i] + 2.0 * sv[i];
                dv_sum[i] = state.a[i] + 2.0 * sa[i];
                sq[i] = state.q[i] + h2 * sv[i];
                sv[i] = state.v[i] + h2 * sa[i];
            }
            acc(t + h2, sq, sv, sa, stats)?;
            for i in 0..n {
                dq_sum[i] += 2.0 * sv[i];
                dv_sum[i] += 2.0 * sa[i];
                sq[i] = state.q[i] + h * sv[i];
                sv[i] = state.v[i] + h * sa[i];
            }
            acc(t + h, sq, sv, sa, stats)?;
            for i in 0..n {
                state.q[i] += h / 6.0 * (dq_sum[i] + sv[i]);
                state.v[i] += h / 6.0 * (dv_sum[i] + sa[i]);
            }
        }
        _ => unreachable!("explicit::step called with implicit scheme {scheme}"),
    }
    state.t = t + h;
    acc(t + h, &state.q, &state.v, &mut state.a, stats)?;
    state.a_hat.copy_from_slice(&state.a);
    Ok(())
}
