//! Adaptive integrators with local error control for any
//! [`SecondOrderSystem`]: the explicit embedded Dormand–Prince 5(4)
//! ([`DormandPrince`], with its continuous extension for dense output) and
//! the L-stable TR-BDF2 of Hosea & Shampine ([`TrBdf2`], for stiff systems,
//! Newton on the stage accelerations with the system's own tangent solve).
//!
//! Both work on the first-order form `z = (q, v)`, `ż = (v, M⁻¹Q)`, and
//! control the local error of every component of `z` with the usual mixed
//! test (Hairer, Nørsett & Wanner, *Solving ODEs I*, II.4):
//!
//! `err = √( (1/2n) Σᵢ (eᵢ / (atolᵢ + rtol·max(|z₀ᵢ|, |z₁ᵢ|)))² ) ≤ 1`.
//!
//! A step is the accepted one of one or more attempts; a rejected attempt
//! leaves the state as it was and retries with a smaller step. Both keep
//! the state's acceleration `a` consistent with `(t, q, v)`, so a step of
//! either can follow a step of any [`Integrator`](super::Integrator) scheme
//! that does (and vice versa).

/// The builder, query and driver methods both integrators share (they
/// have `settings`, `h`, `last` and an `advance` method of the same shape).
macro_rules! adaptive_api {
    () => {
        /// Sets one absolute tolerance per component of `z = (q, v)`: the `n`
        /// coordinates (m or rad), then the `n` velocities (m/s or rad/s).
        pub fn with_atol_components(mut self, atol: Vec<f64>) -> Result<Self, AdaptiveError> {
            self.settings.atol_components = Some(atol);
            self.settings.validate(None)?;
            Ok(self)
        }

        /// Sets the first step (s, `> 0`) instead of the automatic choice.
        pub fn with_initial_step(mut self, h: f64) -> Result<Self, AdaptiveError> {
            self.settings.initial_step = Some(h);
            self.settings.validate(None)?;
            Ok(self)
        }

        /// Sets the largest step (s, `> 0`).
        pub fn with_max_step(mut self, h: f64) -> Result<Self, AdaptiveError> {
            self.settings.max_step = h;
            self.settings.validate(None)?;
            Ok(self)
        }

        /// Sets the most step attempts per call (`≥ 1`).
        pub fn with_max_steps(mut self, n: usize) -> Result<Self, AdaptiveError> {
            self.settings.max_steps = n;
            self.settings.validate(None)?;
            Ok(self)
        }

        /// The step (s) the controller will try next (0 before the first step).
        pub fn next_step(&self) -> f64 {
            self.h
        }

        /// The last accepted step as `(start, length)`, s.
        pub fn last_step(&self) -> Option<(f64, f64)> {
            self.last
        }

        /// Integrates `state` to `t_end` (s), landing on it exactly. The state's
        /// acceleration must be consistent with `(t, q, v)` ([`State::new`] and
        /// every step of either adaptive integrator leave it so, TR-BDF2 to
        /// its Newton tolerance).
        pub fn integrate<S: SecondOrderSystem + ?Sized>(&mut self, sys: &mut S, state: &mut State, t_end: f64) -> Result<AdaptiveStats, AdaptiveError> {
            self.drive(sys, state, t_end, true)
        }

        /// Takes one accepted step from `state` towards `t_end` (s), never past
        /// it (after rejected attempts if the error test asks for them).
        pub fn step<S: SecondOrderSystem + ?Sized>(&mut self, sys: &mut S, state: &mut State, t_end: f64) -> Result<AdaptiveStats, AdaptiveError> {
            self.drive(sys, state, t_end, false)
        }

        /// Accepted steps towards `t_end` until it is reached (`all`) or
        /// one (not `all`), within one attempt budget.
        fn drive<S: SecondOrderSystem + ?Sized>(&mut self, sys: &mut S, state: &mut State, t_end: f64, all: bool) -> Result<AdaptiveStats, AdaptiveError> {
            let mut stats = AdaptiveStats::default();
            let mut budget = self.settings.max_steps;
            while check_start(sys, &self.settings, state, t_end)? {
                self.advance(sys, state, t_end, &mut budget, &mut stats)?;
                if !all {
                    break;
                }
            }
            Ok(stats)
        }
    };
}

mod dopri;
mod trbdf2;

use std::ops::AddAssign;

use thiserror::Error;

use super::error::IntegrateError;
use super::integrator::{StepStats, Workspace};
use super::state::{acceleration, State};
use super::system::{SecondOrderSystem, SystemError};

pub use self::dopri::DormandPrince;
pub use self::trbdf2::TrBdf2;

/// Why an adaptive integration could not start or go on. Every runtime
/// variant names the time `t` (s) at which it happened; on any error the
/// state is the last accepted one.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum AdaptiveError {
    /// A tolerance or setting is out of range (NaN, `rtol ≤ 0`, `atol < 0`,
    /// a step bound `≤ 0`, a component tolerance list of the wrong
    /// length); `what` names it.
    #[error("invalid {what}: {value}")]
    InvalidParameter {
        /// Which parameter (`rtol`, `atol`, `initial step`, …).
        what: &'static str,
        /// The value given (for a list: its length).
        value: f64,
    },
    /// The end time is NaN or before the state's time.
    #[error("invalid end time t_end = {t_end} s for a state at t = {t} s")]
    InvalidEnd {
        /// Time of the state, s.
        t: f64,
        /// The end time asked for, s.
        t_end: f64,
    },
    /// The step size the error control asks for fell below what the time
    /// can resolve (`h < 10 ε |t|`, or below the configured minimum):
    /// a singularity, a blow-up, or a tolerance below round-off.
    #[error("step size underflow at t = {t} s: h = {h:e} s")]
    StepUnderflow {
        /// Time of the last accepted state, s.
        t: f64,
        /// The step size that was too small, s.
        h: f64,
    },
    /// More step attempts (accepted and rejected) than allowed in one call.
    #[error("more than {max_steps} step attempts; stopped at t = {t} s (t_end = {t_end} s)")]
    TooManySteps {
        /// Time of the last accepted state, s.
        t: f64,
        /// The end time asked for, s.
        t_end: f64,
        /// The limit ([`AdaptiveSettings::max_steps`]).
        max_steps: usize,
    },
    /// The starting state is NaN or infinite, or every trial step from `t`
    /// went NaN or infinite down to the smallest step `t` can resolve (a
    /// trial step that goes non-finite is rejected and retried smaller).
    #[error("non-finite state at t = {t} s (at the start, or in every trial step from it)")]
    NonFinite {
        /// Time of the state, s.
        t: f64,
    },
    /// The system failed (a singular matrix, a model error) or the state's
    /// size does not match it.
    #[error(transparent)]
    Integrate(#[from] IntegrateError),
    /// Dense output asked for before any step was accepted, or at a time
    /// outside the last accepted step.
    #[error("dense output at t = {t} s outside the last step [{start}, {end}] s")]
    OutsideStep {
        /// The time asked for, s.
        t: f64,
        /// Start of the last accepted step, s (NaN before any step).
        start: f64,
        /// End of the last accepted step, s (NaN before any step).
        end: f64,
    },
}

/// Work done by one [`step`](DormandPrince::step) or
/// [`integrate`](DormandPrince::integrate) call. Counts include rejected
/// attempts, so they measure cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdaptiveStats {
    /// Residual evaluations (for Dormand–Prince: function evaluations
    /// `M⁻¹Q`, one residual and one solve each).
    pub residual_evals: usize,
    /// Tangent solves (including `c_v = c_q = 0` solves).
    pub solves: usize,
    /// Newton iterations (TR-BDF2; 0 for Dormand–Prince).
    pub newton_iterations: usize,
    /// Accepted steps.
    pub accepted_steps: usize,
    /// Rejected attempts: the error test failed, a stage went non-finite,
    /// or (TR-BDF2) Newton did not converge.
    pub rejected_steps: usize,
    /// Of the rejected attempts, those where Newton did not converge
    /// (TR-BDF2).
    pub newton_failures: usize,
}

impl AdaptiveStats {
    fn add_work(&mut self, s: &StepStats) {
        self.residual_evals += s.residual_evals;
        self.solves += s.solves;
        self.newton_iterations += s.newton_iterations;
    }
}

impl AddAssign for AdaptiveStats {
    fn add_assign(&mut self, o: Self) {
        self.residual_evals += o.residual_evals;
        self.solves += o.solves;
        self.newton_iterations += o.newton_iterations;
        self.accepted_steps += o.accepted_steps;
        self.rejected_steps += o.rejected_steps;
        self.newton_failures += o.newton_failures;
    }
}

/// Tolerances and step-size control shared by both adaptive integrators.
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveSettings {
    /// Relative tolerance (dimensionless), `> 0`.
    pub rtol: f64,
    /// Absolute tolerance, one value for every component (m or rad for `q`,
    /// m/s or rad/s for `v`), `≥ 0`.
    pub atol: f64,
    /// Absolute tolerance per component of `z = (q, v)` (first the `n`
    /// coordinates, then the `n` velocities), replacing `atol` when set.
    pub atol_components: Option<Vec<f64>>,
    /// Safety factor on the optimal step (dimensionless). Default 0.9.
    pub safety: f64,
    /// Smallest factor by which one step may shrink the next. Default 0.2.
    pub fac_min: f64,
    /// Largest factor by which one step may grow the next. Default 10
    /// (Dormand–Prince), 5 (TR-BDF2).
    pub fac_max: f64,
    /// First step (s); `None`: chosen by Hairer's starting-step algorithm
    /// (one extra function evaluation).
    pub initial_step: Option<f64>,
    /// Largest step (s). Default infinite.
    pub max_step: f64,
    /// Most step attempts (accepted and rejected) in one `step` or
    /// `integrate` call. Default 100 000.
    pub max_steps: usize,
}

impl AdaptiveSettings {
    fn new(rtol: f64, atol: f64, fac_max: f64) -> Result<Self, AdaptiveError> {
        let s = AdaptiveSettings {
            rtol,
            atol,
            atol_components: None,
            safety: 0.9,
            fac_min: 0.2,
            fac_max,
            initial_step: None,
            max_step: f64::INFINITY,
            max_steps: 100_000,
        };
        s.validate(None)?;
        Ok(s)
    }

    /// Checks every field; with `dof`, also the length of
    /// [`atol_components`](Self::atol_components) (`2·dof`).
    pub fn validate(&self, dof: Option<usize>) -> Result<(), AdaptiveError> {
        let bad = |what, value| Err(AdaptiveError::InvalidParameter { what, value });
        if !(self.rtol.is_finite() && self.rtol > 0.0) {
            return bad("rtol (must be finite and > 0)", self.rtol);
        }
        if !(self.atol.is_finite() && self.atol >= 0.0) {
            return bad("atol (must be finite and >= 0)", self.atol);
        }
        if let Some(a) = &self.atol_components {
            if let Some(x) = a.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
                return bad("atol component (must be finite and >= 0)", *x);
            }
            if dof.is_some_and(|n| a.len() != 2 * n) {
                return bad("atol component count (must be 2 x dof)", a.len() as f64);
            }
        }
        if !(self.safety > 0.0 && self.safety <= 1.0) {
            return bad("safety factor (must be in (0, 1])", self.safety);
        }
        if !(self.fac_min > 0.0 && self.fac_min < 1.0) {
            return bad("fac_min (must be in (0, 1))", self.fac_min);
        }
        if !(self.fac_max > 1.0 && self.fac_max.is_finite()) {
            return bad("fac_max (must be finite and > 1)", self.fac_max);
        }
        if let Some(h) = self.initial_step {
            if !(h.is_finite() && h > 0.0) {
                return bad("initial step (must be finite and > 0)", h);
            }
        }
        if self.max_step.is_nan() || self.max_step <= 0.0 {
            return bad("max step (must be > 0)", self.max_step);
        }
        if self.max_steps == 0 {
            return bad("max_steps (must be >= 1)", 0.0);
        }
        Ok(())
    }

    /// Absolute tolerance of component `i` of `z`.
    fn atol_of(&self, i: usize) -> f64 {
        self.atol_components.as_ref().map_or(self.atol, |a| a[i])
    }

    /// The scaled RMS norm of an error `e` against the start and end values
    /// `z0`, `z1` (all of length `2n`, `z = (q, v)`).
    fn error_norm(&self, e: &[f64], z0: &[f64], z1: &[f64]) -> f64 {
        let sum: f64 = (0..e.len())
            .map(|i| {
                let sk = self.atol_of(i) + self.rtol * z0[i].abs().max(z1[i].abs());
                (e[i] / sk).powi(2)
            })
            .sum();
        (sum / e.len() as f64).sqrt()
    }
}

/// What an adaptive step attempt produced.
enum Attempt {
    /// Accepted (scaled error `≤ 1`): the step to try next, s.
    Accepted(f64),
    /// Rejected by the error test or a Newton failure: the step to try
    /// next, s.
    Rejected(f64),
    /// Rejected because a stage or the result went NaN or infinite: the
    /// step to try next, s.
    NonFinite(f64),
}

/// Checks the end time and the starting state; returns `false` when the
/// state is already at `t_end`.
fn check_start<S: SecondOrderSystem + ?Sized>(sys: &S, settings: &AdaptiveSettings, state: &State, t_end: f64) -> Result<bool, AdaptiveError> {
    settings.validate(Some(sys.dof()))?;
    state.check_dimensions(sys.dof())?;
    let t = state.t;
    if t_end.is_nan() || t_end < t || t.is_nan() {
        return Err(AdaptiveError::InvalidEnd { t, t_end });
    }
    if !state.is_finite() {
        return Err(AdaptiveError::NonFinite { t });
    }
    Ok(t_end > t)
}

/// The step to attempt from `t` towards `t_end`: `h` bounded by the
/// maximum step, stretched to land on `t_end` when within 1 % of it.
/// Fails when `h` is below what `t` can resolve.
fn clip_step(max_step: f64, t: f64, t_end: f64, h: f64) -> Result<(f64, bool), AdaptiveError> {
    let h = h.min(max_step);
    if h.is_nan() || h < 10.0 * f64::EPSILON * t.abs().max(f64::MIN_POSITIVE) {
        return Err(AdaptiveError::StepUnderflow { t, h });
    }
    if t + 1.01 * h >= t_end {
        Ok((t_end - t, true))
    } else {
        Ok((h, false))
    }
}

/// Hairer's starting step (*Solving ODEs I*, II.4, algorithm `hinit`) for a
/// method whose local error estimate goes as `h^error_order` (DOPRI5: 5,
/// TR-BDF2: 3), with one extra function evaluation.
#[allow(clippy::too_many_arguments)]
fn initial_step<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    settings: &AdaptiveSettings,
    state: &State,
    t_end: f64,
    error_order: i32,
    ws: &mut Workspace,
    stats: &mut AdaptiveStats,
) -> Result<f64, AdaptiveError> {
    if let Some(h) = settings.initial_step {
        return Ok(h);
    }
    let n = state.dof();
    let z0: Vec<f64> = state.q.iter().chain(&state.v).copied().collect();
    let f0: Vec<f64> = state.v.iter().chain(&state.a).copied().collect();
    let zero = vec![0.0; 2 * n];
    let d0 = settings.error_norm(&z0, &z0, &zero);
    let d1 = settings.error_norm(&f0, &z0, &zero);
    let mut h0 = if d0 < 1e-10 || d1 < 1e-10 { 1e-6 } else { 0.01 * d0 / d1 };
    h0 = h0.min(settings.max_step).min(t_end - state.t);
    let t1 = state.t + h0;
    for i in 0..n {
        ws.q[i] = state.q[i] + h0 * state.v[i];
        ws.v[i] = state.v[i] + h0 * state.a[i];
    }
    let mut work = StepStats::default();
    let result = acceleration(sys, t1, &ws.q, &ws.v, &ws.zeros, &mut ws.r, &mut ws.x, &mut work);
    stats.add_work(&work);
    if let Err(e) = result {
        return if is_non_finite(&e) { Ok(0.01 * h0) } else { Err(e.into()) };
    }
    // (f(t₁, z₁) − f(t₀, z₀)) / h0 with f = (v, a).
    let df: Vec<f64> = (0..2 * n).map(|i| (if i < n { ws.v[i] - state.v[i] } else { ws.x[i - n] - state.a[i - n] }) / h0).collect();
    let d2 = settings.error_norm(&df, &z0, &zero);
    let dm = d1.max(d2);
    let h1 = if dm <= 1e-15 { (h0 * 1e-3).max(1e-6) } else { (0.01 / dm).powf(1.0 / f64::from(error_order)) };
    Ok((100.0 * h0).min(h1).min(settings.max_step))
}

/// A stage evaluation that failed only because the trial state went NaN or
/// infinite: the attempt is rejected and retried smaller.
fn is_non_finite(e: &IntegrateError) -> bool {
    matches!(e, IntegrateError::NonFinite { .. } | IntegrateError::System { source: SystemError::NonFinite { .. }, .. })
}

/// A workspace for the Newton solver and the stage evaluations, sized for
/// `n` coordinates.
fn workspace(ws: &mut Workspace, n: usize) {
    if ws.zeros.len() == n {
        return;
    }
    for x in [&mut ws.qb, &mut ws.vb, &mut ws.q, &mut ws.v, &mut ws.x, &mut ws.r, &mut ws.dx, &mut ws.dx_prev, &mut ws.q_new, &mut ws.zeros] {
        x.clear();
        x.resize(n, 0.0);
    }
}

/// The shared outer loop of `step` (`limits`: the largest step, s, and the
/// attempt limit): attempts until one is accepted, with
/// the step-size bookkeeping, the attempt budget and the underflow test.
/// `attempt(h, last)` tries a step of `h` (landing exactly on `t_end` when
/// `last`) and reports acceptance or the next step to try.
fn step_loop<F>(
    (max_step, max_steps): (f64, usize),
    state_t: f64,
    t_end: f64,
    h: &mut f64,
    budget: &mut usize,
    stats: &mut AdaptiveStats,
    mut attempt: F,
) -> Result<(), AdaptiveError>
where
    F: FnMut(f64, bool, &mut AdaptiveStats) -> Result<Attempt, AdaptiveError>,
{
    let mut non_finite = false;
    loop {
        if *budget == 0 {
            return Err(AdaptiveError::TooManySteps { t: state_t, t_end, max_steps });
        }
        *budget -= 1;
        let (h_try, last) = match clip_step(max_step, state_t, t_end, *h) {
            // Shrunk to nothing by trial steps that kept going non-finite.
            Err(AdaptiveError::StepUnderflow { .. }) if non_finite => return Err(AdaptiveError::NonFinite { t: state_t }),
            other => other?,
        };
        let result = attempt(h_try, last, stats)?;
        non_finite = matches!(result, Attempt::NonFinite(_));
        match result {
            Attempt::Accepted(_) => {
                stats.accepted_steps += 1;
                return Ok(());
            }
            Attempt::Rejected(h_next) | Attempt::NonFinite(h_next) => {
                stats.rejected_steps += 1;
                *h = h_next;
            }
        }
    }
}

/// The classic controller's factor for a method whose error estimate is of
/// order `q` (error ∝ hᵠ): `safety · err^(−1/q)`, limited.
fn classic_factor(settings: &AdaptiveSettings, err: f64, q: f64) -> f64 {
    if err == 0.0 {
        return settings.fac_max;
    }
    (settings.safety * err.powf(-1.0 / q)).clamp(settings.fac_min, settings.fac_max)
}

/// Cubic Hermite interpolation of one component over a step of length `h`
/// at `θ ∈ [0, 1]` from values `y0`, `y1` and derivatives `d0`, `d1`.
fn hermite(theta: f64, h: f64, y0: f64, y1: f64, d0: f64, d1: f64) -> f64 {
    let t2 = theta * theta;
    let t3 = t2 * theta;
    (2.0 * t3 - 3.0 * t2 + 1.0) * y0 + (t3 - 2.0 * t2 + theta) * h * d0 + (-2.0 * t3 + 3.0 * t2) * y1 + (t3 - t2) * h * d1
}

/// Maps `t` into the last accepted step `[t0, t0 + h]` (a relative slack of
/// 1e-12 of `h` for round-off), or fails.
fn theta_in(t: f64, step: Option<(f64, f64)>) -> Result<f64, AdaptiveError> {
    let (start, h) = step.unwrap_or((f64::NAN, f64::NAN));
    let theta = (t - start) / h;
    if theta.is_finite() && (-1e-12..=1.0 + 1e-12).contains(&theta) {
        Ok(theta.clamp(0.0, 1.0))
    } else {
        Err(AdaptiveError::OutsideStep { t, start, end: start + h })
    }
}

/// Checks the lengths of the dense-output buffers against `n` coordinates.
fn check_output(t: f64, n: usize, q: &[f64], v: &[f64]) -> Result<(), AdaptiveError> {
    for (what, x) in [("dense output q", q), ("dense output v", v)] {
        if x.len() != n {
            return Err(IntegrateError::DimensionMismatch { t, what, expected: n, got: x.len() }.into());
        }
    }
    Ok(())
}
