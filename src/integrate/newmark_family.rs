//! Generalized-α in the Arnold–Brüls form, with Newmark, linear acceleration
//! and HHT as special cases; and the single linearly implicit step.
//!
//! Generalized-α (Arnold & Brüls 2007) carries a pseudo-acceleration â:
//!
//! ```text
//! (1 − α_m) â₁ + α_m â₀ = (1 − α_f) a₁ + α_f a₀
//! q₁ = q₀ + h v₀ + h²(½ − β) â₀ + h² β â₁
//! v₁ = v₀ + h(1 − γ) â₀ + h γ â₁
//! r(t₁, q₁, v₁, a₁) = 0
//! ```
//!
//! The equation of motion holds exactly at every step end, so a₁ is a true
//! acceleration. For a linear system, weighting the equations at t₀ and t₁
//! by α_f and 1 − α_f gives `M â_{n+1−α_m} + C v_{n+1−α_f} + K q_{n+1−α_f}
//! = F_{n+1−α_f}` (F interpolated linearly in time): the Chung–Hulbert
//! recurrence with â in the role of its acceleration. With α_m = 0 and
//! α_f = −α it is HHT; with α_m = α_f = 0, â = a and it is Newmark.

use super::integrator::{StepStats, Workspace};
use super::newton::{self, Affine, Failure, NewtonSettings};
use super::scheme::AlphaParameters;
use super::state::State;
use super::system::SecondOrderSystem;

/// One generalized-α step of size `h` (s) with Newton on `a₁` from the
/// predictor `a₁ = a₀ + (a₀ − a₋₁) h/h₋₁` (linear extrapolation when the
/// previous step ended where this one starts, else `a₁ = a₀`). The
/// predictor changes only where Newton starts, not what it converges to.
pub(crate) fn step_alpha<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    state: &mut State,
    ws: &mut Workspace,
    p: AlphaParameters,
    h: f64,
    settings: &NewtonSettings,
    stats: &mut StepStats,
) -> Result<(), Failure> {
    let AlphaParameters { alpha_m, alpha_f, beta, gamma } = p;
    let d = 1.0 / (1.0 - alpha_m);
    // â₁ = s·a₁ + â_b with s = (1 − α_f)/(1 − α_m).
    let s = (1.0 - alpha_f) * d;
    let (h2, n) = (h * h, state.dof());
    let extrapolate = ws.a_prev_next_t == state.t && ws.a_prev_h > 0.0;
    let ratio = if extrapolate { h / ws.a_prev_h } else { 0.0 };
    for i in 0..n {
        let (a0, ah0) = (state.a[i], state.a_hat[i]);
        let ah_base = (alpha_f * a0 - alpha_m * ah0) * d;
        ws.qb[i] = state.q[i] + h * state.v[i] + h2 * ((0.5 - beta) * ah0 + beta * ah_base);
        ws.vb[i] = state.v[i] + h * ((1.0 - gamma) * ah0 + gamma * ah_base);
        ws.x[i] = a0 + ratio * (a0 - ws.a_prev[i]);
    }
    let map = Affine { t: state.t + h, c_q: h2 * beta * s, c_v: h * gamma * s, h };
    newton::solve(sys, ws, map, settings, false, stats)?;
    for i in 0..n {
        let ah_base = (alpha_f * state.a[i] - alpha_m * state.a_hat[i]) * d;
        state.a_hat[i] = s * ws.x[i] + ah_base;
    }
    ws.a_prev.copy_from_slice(&state.a);
    ws.a_prev_h = h;
    state.q.copy_from_slice(&ws.q);
    state.v.copy_from_slice(&ws.v);
    state.a.copy_from_slice(&ws.x);
    state.t += h;
    ws.a_prev_next_t = state.t;
    Ok(())
}

/// One linearly implicit θ-step of size `h` (s) with weight `w`: exactly one
/// Newton correction from `a₁ = a₀`, no convergence test.
pub(crate) fn step_linearly_implicit<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    state: &mut State,
    ws: &mut Workspace,
    w: f64,
    h: f64,
    settings: &NewtonSettings,
    stats: &mut StepStats,
) -> Result<(), Failure> {
    // v₁ = v + h(1 − w) a₀ + h w a₁;  q₁ = q + h v + h² w (1 − w) a₀ + h² w² a₁.
    for i in 0..state.dof() {
        let a0 = state.a[i];
        ws.qb[i] = state.q[i] + h * state.v[i] + h * h * w * (1.0 - w) * a0;
        ws.vb[i] = state.v[i] + h * (1.0 - w) * a0;
        ws.x[i] = a0;
    }
    let map = Affine { t: state.t + h, c_q: h * h * w * w, c_v: h * w, h };
    newton::solve(sys, ws, map, settings, true, stats)?;
    state.q.copy_from_slice(&ws.q);
    state.v.copy_from_slice(&ws.v);
    state.a.copy_from_slice(&ws.x);
    state.a_hat.copy_from_slice(&ws.x);
    state.t += h;
    Ok(())
}
