//! The embedded Dormand–Prince 5(4) pair with Hairer's PI step control and
//! his 4th-order continuous extension (the `DOPRI5` code of Hairer,
//! Nørsett & Wanner, *Solving ODEs I*, II.5 and II.6).

use super::super::integrator::{StepStats, Workspace};
use super::super::state::{acceleration, State};
use super::super::system::SecondOrderSystem;
use super::{check_output, check_start, initial_step, is_non_finite, step_loop, theta_in, workspace, AdaptiveError, AdaptiveSettings, AdaptiveStats, Attempt};

/// Nodes `c₂ … c₇`.
const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];

/// The Runge–Kutta matrix, row `s` for stage `s + 1`; row 6 is the 5th
/// order solution (FSAL: stage 7 is evaluated at it).
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];

/// Error coefficients `b̂ − b` (5th minus 4th order weights) of stages 1–7.
const E: [f64; 7] = [71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0];

/// Hairer's dense-output coefficients `d₁ … d₇` (contd5).
const D: [f64; 7] = [
    -12715105075.0 / 11282082432.0,
    0.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

/// Exponent weight of the previous error in Hairer's PI controller
/// (`β = 0.04`; 0 gives the classic controller).
const BETA: f64 = 0.04;

/// Explicit embedded Dormand–Prince 5(4) with error control and dense
/// output, for any [`SecondOrderSystem`] in the first-order form
/// `z = (q, v)`, `ż = (v, M⁻¹Q)` (one residual and one `c_v = c_q = 0`
/// solve per function evaluation, six per step: the seventh stage is the
/// next step's first, FSAL).
///
/// Step control as in Hairer's `DOPRI5`: the 4th-order embedded error,
/// Hairer's mixed norm ([`AdaptiveSettings`]), the PI controller
/// `h_new = h · safety · err^(−0.2 + 0.75 β) · err_prev^β` with `β = 0.04`,
/// the change limited to a factor in `[fac_min, fac_max]`, no growth right
/// after a rejection. Explicit: on a stiff system its step is held near the
/// stability limit `≈ 3.3/ω_max`, whatever the tolerance (use [`TrBdf2`](super::TrBdf2)).
///
/// ```
/// use bevy_rapier_cable::integrate::{DenseSystem, DormandPrince, State};
/// // ẍ + x = 0, x(0) = 1: x(t) = cos t.
/// let mut sys = DenseSystem::oscillator(1.0, 0.0, 1.0).unwrap();
/// let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).unwrap();
/// let mut dp = DormandPrince::new(1e-8, 1e-10).unwrap();
/// let stats = dp.integrate(&mut sys, &mut state, 10.0).unwrap();
/// assert!((state.q[0] - 10f64.cos()).abs() < 1e-6);
/// assert!(stats.accepted_steps < 200);
/// ```
#[derive(Debug)]
pub struct DormandPrince {
    /// Tolerances and step control (defaults: safety 0.9, factors 0.2 and
    /// 10).
    pub settings: AdaptiveSettings,
    /// The next step to try, s (0 before the first step: chosen then).
    h: f64,
    /// The previous accepted error (PI controller).
    err_prev: f64,
    /// Stage derivatives `k₁ … k₇`, each of length `2n`.
    k: [Vec<f64>; 7],
    /// `z₀`, a stage or trial state, and the error estimate (length `2n`).
    z0: Vec<f64>,
    z: Vec<f64>,
    e: Vec<f64>,
    /// The continuous extension of the last accepted step, its start and
    /// length (s).
    cont: [Vec<f64>; 5],
    last: Option<(f64, f64)>,
    ws: Workspace,
}

impl DormandPrince {
    /// A Dormand–Prince integrator with relative tolerance `rtol`
    /// (dimensionless, `> 0`) and absolute tolerance `atol` (units of each
    /// component of `z = (q, v)`, `≥ 0`).
    pub fn new(rtol: f64, atol: f64) -> Result<Self, AdaptiveError> {
        Ok(DormandPrince {
            settings: AdaptiveSettings::new(rtol, atol, 10.0)?,
            h: 0.0,
            err_prev: 1e-4,
            k: Default::default(),
            z0: Vec::new(),
            z: Vec::new(),
            e: Vec::new(),
            cont: Default::default(),
            last: None,
            ws: Workspace::default(),
        })
    }

    adaptive_api!();

    /// Forgets the step size and the last step (call it after changing the
    /// state by hand or switching systems).
    pub fn reset(&mut self) {
        self.h = 0.0;
        self.err_prev = 1e-4;
        self.last = None;
    }

    /// The solution at `t` (s) inside the last accepted step, from the
    /// 4th-order continuous extension: coordinates into `q`, velocities into
    /// `v` (each of length `n`).
    pub fn dense_output(&self, t: f64, q: &mut [f64], v: &mut [f64]) -> Result<(), AdaptiveError> {
        let theta = theta_in(t, self.last)?;
        let n = self.z0.len() / 2;
        check_output(t, n, q, v)?;
        let theta1 = 1.0 - theta;
        let [r1, r2, r3, r4, r5] = &self.cont;
        for i in 0..2 * n {
            let y = r1[i] + theta * (r2[i] + theta1 * (r3[i] + theta * (r4[i] + theta1 * r5[i])));
            if i < n {
                q[i] = y;
            } else {
                v[i - n] = y;
            }
        }
        Ok(())
    }

    fn ensure(&mut self, n: usize) {
        workspace(&mut self.ws, n);
        for x in self.k.iter_mut().chain(self.cont.iter_mut()).chain([&mut self.z0, &mut self.z, &mut self.e]) {
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
            self.h = initial_step(sys, &self.settings, state, t_end, 5, &mut self.ws, stats)?;
        }
        let t = state.t;
        let mut h = self.h;
        let mut rejected = false;
        step_loop((self.settings.max_step, self.settings.max_steps), t, t_end, &mut h, budget, stats, |h_try, last, stats| {
            let attempt = self.attempt(sys, state, h_try, rejected, stats)?;
            match attempt {
                Attempt::Accepted(h_next) => {
                    self.accept(state, h_try, if last { t_end } else { t + h_try });
                    self.h = h_next;
                }
                Attempt::Rejected(_) | Attempt::NonFinite(_) => rejected = true,
            }
            Ok(attempt)
        })
    }

    /// One attempt of size `h` from `state` (left unchanged). Accepted:
    /// the next step to try; `z`, `k₇` hold the new state.
    fn attempt<S: SecondOrderSystem + ?Sized>(
        &mut self,
        sys: &mut S,
        state: &State,
        h: f64,
        after_reject: bool,
        stats: &mut AdaptiveStats,
    ) -> Result<Attempt, AdaptiveError> {
        let n = state.dof();
        let t = state.t;
        for i in 0..n {
            self.z0[i] = state.q[i];
            self.z0[n + i] = state.v[i];
            self.k[0][i] = state.v[i];
            self.k[0][n + i] = state.a[i];
        }
        let s = &self.settings;
        for stage in 1..7 {
            for i in 0..2 * n {
                let incr: f64 = (0..stage).map(|j| A[stage][j] * self.k[j][i]).sum();
                self.z[i] = self.z0[i] + h * incr;
            }
            let (kq, kv) = self.k[stage].split_at_mut(n);
            kq.copy_from_slice(&self.z[n..]);
            let mut work = StepStats::default();
            let ws = &mut self.ws;
            let result = acceleration(sys, t + C[stage] * h, &self.z[..n], &self.z[n..], &ws.zeros, &mut ws.r, kv, &mut work);
            stats.add_work(&work);
            match result {
                Ok(()) => {}
                Err(e) if is_non_finite(&e) => return Ok(Attempt::NonFinite(h * s.fac_min)),
                Err(e) => return Err(e.into()),
            }
        }
        for i in 0..2 * n {
            self.e[i] = h * (0..7).map(|j| E[j] * self.k[j][i]).sum::<f64>();
        }
        let err = s.error_norm(&self.e, &self.z0, &self.z);
        if !err.is_finite() {
            return Ok(Attempt::NonFinite(h * s.fac_min));
        }
        // Hairer's PI controller: fac = err^expo1 / err_prev^β / safety,
        // limited to [1/fac_max, 1/fac_min]; h_new = h / fac.
        let expo1 = 0.2 - BETA * 0.75;
        let fac11 = err.powf(expo1);
        if err <= 1.0 {
            let fac = (fac11 / self.err_prev.powf(BETA) / s.safety).clamp(1.0 / s.fac_max, 1.0 / s.fac_min);
            self.err_prev = err.max(1e-4);
            let mut h_next = h / fac;
            if after_reject {
                h_next = h_next.min(h);
            }
            Ok(Attempt::Accepted(h_next))
        } else {
            Ok(Attempt::Rejected(h / (fac11 / s.safety).min(1.0 / s.fac_min)))
        }
    }

    /// Builds the continuous extension of the accepted step and moves the
    /// state to its end `t1` (s).
    fn accept(&mut self, state: &mut State, h: f64, t1: f64) {
        let n = state.dof();
        let k = &self.k;
        let [r1, r2, r3, r4, r5] = &mut self.cont;
        for i in 0..2 * n {
            let dz = self.z[i] - self.z0[i];
            let bspl = h * k[0][i] - dz;
            r1[i] = self.z0[i];
            r2[i] = dz;
            r3[i] = bspl;
            r4[i] = dz - h * k[6][i] - bspl;
            r5[i] = h * (0..7).map(|j| D[j] * k[j][i]).sum::<f64>();
        }
        self.last = Some((state.t, h));
        state.q.copy_from_slice(&self.z[..n]);
        state.v.copy_from_slice(&self.z[n..]);
        state.a.copy_from_slice(&self.k[6][n..]);
        state.a_hat.copy_from_slice(&state.a);
        state.t = t1;
    }
}
