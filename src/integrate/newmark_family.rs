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

use super::error::IntegrateError;
use super::integrator::{StepStats, Workspace};
use super::newton::{self, Affine, Failure, NewtonSettings};
use super::scheme::AlphaParameters;
use super::state::State;
use super::system::{LinearisationLimits, SecondOrderSystem};

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
    newton::solve(sys, ws, map, settings, false, stats, (&state.q, &state.v))?;
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

/// Largest `Ω = h ω_max` (ω_max from [`SecondOrderSystem::max_frequency`])
/// at which [`step_linearly_implicit`] linearises at the predicted state;
/// above it (or when the system does not know its highest frequency) it
/// linearises at the start configuration.
const LINEARLY_IMPLICIT_STIFF_OMEGA: f64 = 1.0;

/// Fraction of the predicted displacement used for the directional
/// difference `J d ≈ (r(q₀ + ε d) − r(q₀))/ε` of the stiff form (a power of
/// two; the rope tolerates up to 0.2, the linear recurrences are exact to
/// round-off for any value).
const DIRECTION_FRACTION: f64 = 1.0 / 64.0;

/// One linearly implicit θ-step of size `h` (s) with weight `w`: one
/// linearised solve with the system's tangent, no convergence loop.
///
/// The θ-method `v₁ = v + h(1 − w) a₀ + h w a₁`,
/// `q₁ = q + h v + h² w (1 − w) a₀ + h² w² a₁` with `r(t₁, q₁, v₁, a₁) = 0`
/// is linearised once, around the predicted velocity `v_p = v + h a₀` and
/// acceleration `a₀`, and solved with `M + h w C + h² w² K`:
///
/// * non-stiff systems (`h ω_max ≤ 1`): at the predicted configuration
///   `q_p = q + h v + h² w a₀` (one fused residual + solve);
/// * stiff systems: at the start configuration `q`, the predicted
///   displacement `d = h v + h² w a₀` entering linearly through a
///   directional difference of the residual (two residuals, one solve).
///   Evaluating the residual at `q_p` extrapolates the stiff modes (element
///   stretch, the tension-stiffened bending of short elements) by `Ω` and
///   `Ω²`; with a single correction the second-order remainder of those
///   extrapolations is never removed, and on a chain in relative coordinates
///   it drives the top elements unstable (the hoist pendulum at N ≥ 100,
///   `tests/fast_preset.rs`).
///
/// On a linear system both forms are the same θ-step (exact linearisation).
///
/// The stiff form then evaluates the residual at the step's end (the pass
/// that refreshes the chain's readouts there, which the caller would
/// otherwise make) and keeps the step only if its solve corrected the
/// prediction by at most the system's
/// [`LinearisationLimits::correction`] and one more Newton correction,
/// estimated from that residual, would move no coordinate by more than its
/// [`LinearisationLimits::next_correction`] (systems without limits, whose
/// coordinates have no known scale, skip the check). A pass that fails
/// that test, or whose result
/// crosses a kink of a non-smooth law, fails with
/// [`Failure::Linearisation`]: the integrator takes the step again with the
/// default scheme. Returns whether the residual was last evaluated at the
/// step's end state.
pub(crate) fn step_linearly_implicit<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    state: &mut State,
    ws: &mut Workspace,
    w: f64,
    h: f64,
    settings: &NewtonSettings,
    stats: &mut StepStats,
) -> Result<bool, Failure> {
    // v₁ = v + h(1 − w) a₀ + h w a₁;  q₁ = q + h v + h² w (1 − w) a₀ + h² w² a₁.
    for i in 0..state.dof() {
        let a0 = state.a[i];
        ws.qb[i] = state.q[i] + h * state.v[i] + h * h * w * (1.0 - w) * a0;
        ws.vb[i] = state.v[i] + h * (1.0 - w) * a0;
        ws.x[i] = a0;
    }
    let map = Affine { t: state.t + h, c_q: h * h * w * w, c_v: h * w, h };
    let stiff = sys.max_frequency(&state.q).is_none_or(|omega| omega.is_nan() || omega * h > LINEARLY_IMPLICIT_STIFF_OMEGA);
    let mut end_evaluated = false;
    if stiff {
        linearised_at_start(sys, state, ws, map, stats)?;
        if let Some(limits) = sys.linearisation_limits() {
            check_linearisation(sys, ws, map, limits, stats)?;
            end_evaluated = true;
        }
    } else {
        newton::solve(sys, ws, map, settings, true, stats, (&state.q, &state.v))?;
    }
    state.q.copy_from_slice(&ws.q);
    state.v.copy_from_slice(&ws.v);
    state.a.copy_from_slice(&ws.x);
    state.a_hat.copy_from_slice(&ws.x);
    state.t += h;
    Ok(end_evaluated)
}

/// The acceptance test of the stiff form (see [`step_linearly_implicit`]):
/// the residual at the end state `(ws.q, ws.v, ws.x)`, solved with the
/// step's own elimination ([`SecondOrderSystem::resolve_last_tangent`]) for
/// the next Newton correction; a system that cannot re-solve estimates it
/// as the solve's correction `ws.dx` times the ratio of the end residual to
/// the linearised prediction's `ws.r` (max norms). That ratio is dominated
/// by the stiff directions and misses errors in the soft ones: on the
/// slack V it let steps through that the re-solve rejects (their kinetic
/// energy kicks went from up to 4.6 J to at most 0.12 J).
fn check_linearisation<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    ws: &mut Workspace,
    map: Affine,
    limits: LinearisationLimits,
    stats: &mut StepStats,
) -> Result<(), Failure> {
    let Affine { t, c_q, .. } = map;
    sys.residual(t, &ws.q, &ws.v, &ws.x, &mut ws.sq).map_err(|source| Failure::Error(IntegrateError::System { t, source }))?;
    stats.residual_evals += 1;
    let max_abs = |x: &[f64]| x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (r0, r1) = (max_abs(&ws.r), max_abs(&ws.sq));
    if !r1.is_finite() {
        return Err(IntegrateError::NonFinite { t }.into());
    }
    let correction = c_q * max_abs(&ws.dx);
    let next_correction =
        if sys.resolve_last_tangent(&ws.sq, &mut ws.dv_sum) { c_q * max_abs(&ws.dv_sum) } else { correction * (r1 / r0.max(f64::MIN_POSITIVE)) };
    if correction <= limits.correction && next_correction <= limits.next_correction {
        Ok(())
    } else {
        Err(Failure::Linearisation)
    }
}

/// The stiff form of [`step_linearly_implicit`]: with `x = a₀` in `ws.x`
/// and the affine bases in `ws.qb`, `ws.vb`, solves
/// `(M + c_v C + c_q K) δ = −r(t₁, q, v_p, a₀) − K d` at `(q, v_p, a₀)`,
/// `K d` by a directional difference, and leaves `x = a₀ + δ` and the
/// matching coordinates in `ws`. Fails with [`Failure::Linearisation`] when the
/// result lies on another branch of a non-smooth law than the one
/// linearised (beyond the tolerances of
/// [`SecondOrderSystem::update_branches`]): one linear solve does not hold
/// across a kink.
fn linearised_at_start<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    state: &State,
    ws: &mut Workspace,
    map: Affine,
    stats: &mut StepStats,
) -> Result<(), Failure> {
    let Affine { t, c_q, c_v, .. } = map;
    let n = state.dof();
    let eps = DIRECTION_FRACTION;
    // The predicted configuration and velocity v_p; d = q_p − q.
    newton::update_coordinates(ws, c_q, c_v);
    for i in 0..n {
        ws.dq_sum[i] = ws.q[i] - state.q[i];
    }
    // Non-smooth laws on the branch of the predicted configuration, as the
    // one-correction form has them.
    sys.freeze_branches((&state.q, &state.v), (&ws.q, &ws.v));
    for i in 0..n {
        ws.q[i] = state.q[i] + eps * ws.dq_sum[i];
    }
    if let Err(e) = linear_solve_at(sys, state, ws, map, stats) {
        sys.release_branches();
        return Err(e);
    }
    if !ws.dx.iter().all(|x| x.is_finite()) {
        sys.release_branches();
        return Err(IntegrateError::NonFinite { t }.into());
    }
    // The step's displacement from q, applied in the system's own way if it
    // has one (a chain closed by anchors: link by link).
    for i in 0..n {
        ws.x[i] += ws.dx[i];
        ws.dx_prev[i] = ws.qb[i] + c_q * ws.x[i] - state.q[i];
    }
    if c_q > 0.0 && sys.nonlinear_update(&state.q, &ws.dx_prev, 1.0, &mut ws.q_new) {
        for i in 0..n {
            ws.x[i] = (ws.q_new[i] - ws.qb[i]) / c_q;
        }
    }
    newton::update_coordinates(ws, c_q, c_v);
    let same_branches = sys.update_branches(&ws.q, &ws.v) == 0;
    sys.release_branches();
    if same_branches {
        Ok(())
    } else {
        Err(Failure::Linearisation)
    }
}

/// The two residuals and the solve of [`linearised_at_start`] (branches
/// frozen by the caller): `ws.dx = δ`.
fn linear_solve_at<S: SecondOrderSystem + ?Sized>(sys: &mut S, state: &State, ws: &mut Workspace, map: Affine, stats: &mut StepStats) -> Result<(), Failure> {
    let Affine { t, c_q, c_v, .. } = map;
    let eps = DIRECTION_FRACTION;
    let system = |source| Failure::Error(IntegrateError::System { t, source });
    sys.residual(t, &ws.q, &ws.v, &ws.x, &mut ws.sq).map_err(system)?;
    stats.residual_evals += 1;
    // Last: the tangent is taken here.
    sys.residual(t, &state.q, &ws.v, &ws.x, &mut ws.r).map_err(system)?;
    stats.residual_evals += 1;
    for (r, r_eps) in ws.r.iter_mut().zip(&ws.sq) {
        *r = -(*r + (r_eps - *r) / eps);
    }
    if !ws.r.iter().all(|x| x.is_finite()) {
        return Err(IntegrateError::NonFinite { t }.into());
    }
    sys.solve_tangent(t, &state.q, &ws.v, &ws.x, c_v, c_q, &ws.r, &mut ws.dx).map_err(system)?;
    stats.solves += 1;
    stats.newton_iterations += 1;
    Ok(())
}
