//! TR-BDF2 (Bank et al. 1985; Hosea & Shampine 1996, γ = 2 − √2) with its
//! embedded error estimate, for second-order systems: each implicit stage
//! is Newton on the stage acceleration with an affine map of `q` and `v`.

use std::f64::consts::SQRT_2;

use super::super::integrator::{StepStats, Workspace};
use super::super::newton::{self, Affine, Failure, NewtonSettings, MAX_BRANCH_UPDATES};
use super::super::state::State;
use super::super::system::SecondOrderSystem;
use super::{
    check_output, check_start, classic_factor, hermite, initial_step, is_non_finite, step_loop, theta_in, workspace, AdaptiveError, AdaptiveSettings,
    AdaptiveStats, Attempt,
};

/// γ = 2 − √2: the trapezoidal stage covers `γh`, and both stages then
/// share the matrix `I − (γ/2) h J` (`d = γ/2 = (1 − γ)/(2 − γ)`).
const GAMMA: f64 = 2.0 - SQRT_2;
/// `d = γ/2`.
const D: f64 = 0.5 * GAMMA;
/// BDF2 weights of the stage and of the step start:
/// `z₁ = W_G z_γ + W_N z₀ + d h f₁` with `W_G = 1/(γ(2 − γ))`,
/// `W_N = −(1 − γ)²/(γ(2 − γ))`.
const W_G: f64 = 1.0 / (GAMMA * (2.0 - GAMMA));
const W_N: f64 = -(1.0 - GAMMA) * (1.0 - GAMMA) / (GAMMA * (2.0 - GAMMA));
/// Hosea & Shampine's error constant, signed so that the estimate
/// `est = K_E h (f₀/γ − f_γ/(γ(1 − γ)) + f₁/(1 − γ))` approximates the
/// local error `z₁ − z(t + h)`: `K_E = (3γ² − 4γ + 2)/(6(2 − γ))`. The
/// bracket is `h²` times the second divided difference of `f` at `0, γh,
/// h`, `≈ h² z‴/2`, and the local error is `(K_E/2) h³ z‴ ≈ 0.0404 h³ z‴`
/// (checked against one step on the oscillator in the unit test).
const K_E: f64 = (3.0 * GAMMA * GAMMA - 4.0 * GAMMA + 2.0) / (6.0 * (2.0 - GAMMA));

/// TR-BDF2: an L-stable, second-order, one-step implicit Runge–Kutta
/// method with an embedded third-order error estimate (Hosea & Shampine
/// 1996, MATLAB's `ode23tb`), for stiff [`SecondOrderSystem`]s.
///
/// A step of `h` from `(t, q₀, v₀, a₀)`, with `d = γ/2`, `γ = 2 − √2`:
/// 1. trapezoid over `γh`: unknown `a_γ`,
///    `v_γ = v₀ + d h (a₀ + a_γ)`, `q_γ = q₀ + γh v₀ + (dh)² (a₀ + a_γ)`,
///    residual at `t + γh`;
/// 2. BDF2 over `h`: unknown `a₁`, `v₁ = v_b + d h a₁` with
///    `v_b = W_G v_γ + W_N v₀`, `q₁ = q_b + (dh)² a₁` with
///    `q_b = W_G q_γ + W_N q₀ + d h v_b`, residual at `t + h`.
///
/// Each stage is Newton on the acceleration with the map `c_v = d h`,
/// `c_q = (d h)²`, through the system's own tangent solve (so the O(n)
/// rope solve serves it too), with the crate's Newton settings, line search
/// and branch freezing. The local error of `z = (q, v)` is estimated by
/// `K_E h (f₀/γ − f_γ/(γ(1 − γ)) + f₁/(1 − γ))`, `f = (v, a)`; step sizes
/// follow `h · safety · err^(−1/3)`. A Newton failure rejects the attempt
/// and quarters the step. Dense output is the cubic Hermite interpolant of
/// `(q, v)` with derivatives `(v, a)` at both ends (third order, above the
/// method's second).
///
/// ```
/// use bevy_rapier_cable::integrate::{DenseSystem, State, TrBdf2};
/// // A stiff, damped oscillator (ω = 10⁴ rad/s, ζ = 0.5) released from
/// // x = 1: the transient (10 ms) is resolved to the tolerance, then the
/// // decayed mode no longer limits the step (an explicit method would stay
/// // near 3/ω = 0.3 ms).
/// let mut sys = DenseSystem::oscillator(1.0, 1e4, 1e8).unwrap();
/// let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).unwrap();
/// let mut tr = TrBdf2::new(1e-6, 1e-8).unwrap();
/// tr.integrate(&mut sys, &mut state, 0.01).unwrap();
/// let stats = tr.integrate(&mut sys, &mut state, 10.0).unwrap();
/// assert!(state.q[0].abs() < 1e-8);
/// assert!(stats.accepted_steps < 30, "{stats:?}");
/// ```
#[derive(Debug)]
pub struct TrBdf2 {
    /// Tolerances and step control (defaults: safety 0.9, factors 0.2 and
    /// 5).
    pub settings: AdaptiveSettings,
    /// Newton control of each stage. `max_substeps` is not used (a failing
    /// stage rejects the step instead).
    pub newton: NewtonSettings,
    h: f64,
    /// Start state and the trapezoidal stage `(q, v, a)`.
    q0: Vec<f64>,
    v0: Vec<f64>,
    a0: Vec<f64>,
    qg: Vec<f64>,
    vg: Vec<f64>,
    ag: Vec<f64>,
    /// Error estimate, `z₀` and `z₁` (length `2n`).
    e: Vec<f64>,
    z0: Vec<f64>,
    z1: Vec<f64>,
    /// The last accepted step: start and length, s.
    last: Option<(f64, f64)>,
    ws: Workspace,
}

impl TrBdf2 {
    /// A TR-BDF2 integrator with relative tolerance `rtol` (dimensionless,
    /// `> 0`) and absolute tolerance `atol` (units of each component of
    /// `z = (q, v)`, `≥ 0`).
    pub fn new(rtol: f64, atol: f64) -> Result<Self, AdaptiveError> {
        Ok(TrBdf2 {
            settings: AdaptiveSettings::new(rtol, atol, 5.0)?,
            newton: NewtonSettings::default(),
            h: 0.0,
            q0: Vec::new(),
            v0: Vec::new(),
            a0: Vec::new(),
            qg: Vec::new(),
            vg: Vec::new(),
            ag: Vec::new(),
            e: Vec::new(),
            z0: Vec::new(),
            z1: Vec::new(),
            last: None,
            ws: Workspace::default(),
        })
    }

    adaptive_api!();

    /// Sets the Newton settings of the stages.
    pub fn with_newton(mut self, newton: NewtonSettings) -> Self {
        self.newton = newton;
        self
    }

    /// Forgets the step size and the last step.
    pub fn reset(&mut self) {
        self.h = 0.0;
        self.last = None;
    }

    /// The solution at `t` (s) inside the last accepted step (cubic
    /// Hermite): coordinates into `q`, velocities into `v`.
    pub fn dense_output(&self, t: f64, q: &mut [f64], v: &mut [f64]) -> Result<(), AdaptiveError> {
        let theta = theta_in(t, self.last)?;
        let h = self.last.map_or(0.0, |l| l.1);
        let n = self.q0.len();
        check_output(t, n, q, v)?;
        // After acceptance q0, v0, a0 still hold the step's start, z1 its
        // end (q₁, v₁) and ag the end acceleration a₁.
        for i in 0..n {
            q[i] = hermite(theta, h, self.q0[i], self.z1[i], self.v0[i], self.z1[n + i]);
            v[i] = hermite(theta, h, self.v0[i], self.z1[n + i], self.a0[i], self.ag[i]);
        }
        Ok(())
    }

    fn ensure(&mut self, n: usize) {
        workspace(&mut self.ws, n);
        self.ws.branch_budget = MAX_BRANCH_UPDATES;
        for x in [&mut self.q0, &mut self.v0, &mut self.a0, &mut self.qg, &mut self.vg, &mut self.ag] {
            x.resize(n, 0.0);
        }
        for x in [&mut self.e, &mut self.z0, &mut self.z1] {
            x.resize(2 * n, 0.0);
        }
    }

    fn advance<S: SecondOrderSystem + ?Sized>(
        &mut self,
        sys: &mut S,
        state: &mut State,
        t_end: f64,
        budget: &mut usize,
        stats: &mut AdaptiveStats,
    ) -> Result<(), AdaptiveError> {
        let n = state.dof();
        self.ensure(n);
        if self.h <= 0.0 {
            self.h = initial_step(sys, &self.settings, state, t_end, 3, &mut self.ws, stats)?;
        }
        let t = state.t;
        let mut h = self.h;
        let mut rejected = false;
        // The attempts overwrite what the dense output reads.
        self.last = None;
        step_loop((self.settings.max_step, self.settings.max_steps), t, t_end, &mut h, budget, stats, |h_try, last, stats| {
            let attempt = self.attempt(sys, state, h_try, stats)?;
            match attempt {
                Attempt::Accepted(h_next) => {
                    self.last = Some((t, h_try));
                    state.q.copy_from_slice(&self.z1[..n]);
                    state.v.copy_from_slice(&self.z1[n..]);
                    state.a.copy_from_slice(&self.ag);
                    state.a_hat.copy_from_slice(&self.ag);
                    state.t = if last { t_end } else { t + h_try };
                    self.h = if rejected { h_next.min(h_try) } else { h_next };
                }
                Attempt::Rejected(_) | Attempt::NonFinite(_) => rejected = true,
            }
            Ok(attempt)
        })
    }

    /// One Newton solve for a stage at time `t` with the bases already in
    /// `ws.qb`, `ws.vb` and the starting guess in `ws.x`. `Ok(None)`:
    /// converged; `Ok(Some(rejection))`: Newton did not converge or the
    /// iterate went non-finite, retry with a quarter of `h`.
    fn stage<S: SecondOrderSystem + ?Sized>(&mut self, sys: &mut S, t: f64, h: f64, stats: &mut AdaptiveStats) -> Result<Option<Attempt>, AdaptiveError> {
        let c_v = D * h;
        let map = Affine { t, c_q: c_v * c_v, c_v, h };
        let mut work = StepStats::default();
        let result = newton::solve(sys, &mut self.ws, map, &self.newton, false, &mut work, (&self.q0, &self.v0));
        stats.add_work(&work);
        match result {
            Ok(()) => Ok(None),
            Err(Failure::NotConverged { .. } | Failure::Linearisation | Failure::EnergyGain) => {
                stats.newton_failures += 1;
                Ok(Some(Attempt::Rejected(0.25 * h)))
            }
            Err(Failure::Error(e)) if is_non_finite(&e) => Ok(Some(Attempt::NonFinite(0.25 * h))),
            Err(Failure::Error(e)) => Err(e.into()),
        }
    }

    /// One attempt of size `h` from `state` (left unchanged). Accepted: the
    /// next step to try; `z1` and `ag` hold `(q₁, v₁)` and `a₁`.
    fn attempt<S: SecondOrderSystem + ?Sized>(&mut self, sys: &mut S, state: &State, h: f64, stats: &mut AdaptiveStats) -> Result<Attempt, AdaptiveError> {
        let n = state.dof();
        let t = state.t;
        self.q0.copy_from_slice(&state.q);
        self.v0.copy_from_slice(&state.v);
        self.a0.copy_from_slice(&state.a);
        let dh = D * h;
        // Stage 1: trapezoid over γh, started from a₀.
        for i in 0..n {
            self.ws.vb[i] = self.v0[i] + dh * self.a0[i];
            self.ws.qb[i] = self.q0[i] + GAMMA * h * self.v0[i] + dh * dh * self.a0[i];
            self.ws.x[i] = self.a0[i];
        }
        if let Some(rejection) = self.stage(sys, t + GAMMA * h, h, stats)? {
            return Ok(rejection);
        }
        self.qg.copy_from_slice(&self.ws.q);
        self.vg.copy_from_slice(&self.ws.v);
        self.ag.copy_from_slice(&self.ws.x);
        // Stage 2: BDF2 over h, started from the linear extrapolation of
        // a₀, a_γ to t + h.
        for i in 0..n {
            self.ws.vb[i] = W_G * self.vg[i] + W_N * self.v0[i];
            self.ws.qb[i] = W_G * self.qg[i] + W_N * self.q0[i] + dh * self.ws.vb[i];
            self.ws.x[i] = self.a0[i] + (self.ag[i] - self.a0[i]) / GAMMA;
        }
        if let Some(rejection) = self.stage(sys, t + h, h, stats)? {
            return Ok(rejection);
        }
        for i in 0..n {
            let (q1, v1, a1) = (self.ws.q[i], self.ws.v[i], self.ws.x[i]);
            let divided = |f0: f64, fg: f64, f1: f64| K_E * h * (f0 / GAMMA - fg / (GAMMA * (1.0 - GAMMA)) + f1 / (1.0 - GAMMA));
            self.e[i] = divided(self.v0[i], self.vg[i], v1);
            self.e[n + i] = divided(self.a0[i], self.ag[i], a1);
            self.z0[i] = self.q0[i];
            self.z0[n + i] = self.v0[i];
            self.z1[i] = q1;
            self.z1[n + i] = v1;
        }
        let err = self.settings.error_norm(&self.e, &self.z0, &self.z1);
        if !err.is_finite() || !self.z1.iter().all(|x| x.is_finite()) {
            return Ok(Attempt::NonFinite(h * self.settings.fac_min));
        }
        let fac = classic_factor(&self.settings, err, 3.0);
        if err <= 1.0 {
            self.ag.copy_from_slice(&self.ws.x);
            Ok(Attempt::Accepted(h * fac))
        } else {
            Ok(Attempt::Rejected(h * fac.min(1.0)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::DenseSystem;

    /// The embedded estimate is the local error to leading order: one step
    /// of `h` from the exact state of `ẍ + x = 0`, estimate over true error
    /// → 1 as `h` → 0 (the ratio's deviation falls like `h`).
    #[test]
    fn error_estimate_matches_the_local_error() {
        let mut sys = DenseSystem::oscillator(1.0, 0.0, 1.0).expect("valid");
        let t0 = 0.3f64;
        let mut deviations = Vec::new();
        for h in [1e-2, 5e-3, 2.5e-3] {
            let state = State::new(&mut sys, t0, vec![t0.cos()], vec![-t0.sin()]).expect("state");
            let mut tr = TrBdf2::new(1e6, 1e6).expect("valid");
            tr.ensure(1);
            let mut stats = AdaptiveStats::default();
            assert!(matches!(tr.attempt(&mut sys, &state, h, &mut stats).expect("attempt"), Attempt::Accepted(_)));
            let t1 = t0 + h;
            let true_err = [tr.z1[0] - t1.cos(), tr.z1[1] + t1.sin()];
            let ratio = [tr.e[0] / true_err[0], tr.e[1] / true_err[1]];
            deviations.push((ratio[0] - 1.0).abs().max((ratio[1] - 1.0).abs()));
        }
        assert!(deviations[0] < 0.05, "{deviations:?}");
        assert!(deviations[2] < 0.3 * deviations[0], "{deviations:?}");
    }
}
