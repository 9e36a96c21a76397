//! Newton's method on the new acceleration for every implicit scheme.
//!
//! Each implicit scheme writes its new coordinates as an affine function of
//! the unknown acceleration `x`: `q = q_b + c_q x`, `v = v_b + c_v x`, and
//! asks for `r(t, q, v, x) = 0`. The Newton matrix is then exactly
//! `∂r/∂x = M + c_v C_t + c_q K_t`, which is what
//! [`SecondOrderSystem::solve_tangent`] solves with.

use super::error::IntegrateError;
use super::integrator::{StepStats, Workspace};
use super::system::SecondOrderSystem;

/// Newton control for the implicit schemes.
#[derive(Clone, Debug, PartialEq)]
pub struct NewtonSettings {
    /// Iterations (residual + solve each) before a step counts as not
    /// converged. Default 8; values below 1 act as 1.
    pub max_iterations: usize,
    /// Largest split of a step in the fallback: a step that does not converge
    /// (or whose solve fails, or that turns non-finite) is redone as 2, 4, …
    /// sub-steps up to this many. Default 8; 1 disables the fallback.
    pub max_substeps: u32,
    /// Relative part of the convergence test: a coordinate's correction must
    /// stay below `tol + relative_tolerance·|q_i|` (positions) and
    /// `tol/h + relative_tolerance·|v_i|` (velocities), `tol` the system's
    /// [`position_tolerance`](SecondOrderSystem::position_tolerance).
    /// Default 1e-12 (dimensionless).
    pub relative_tolerance: f64,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        NewtonSettings { max_iterations: 8, max_substeps: 8, relative_tolerance: 1e-12 }
    }
}

/// Why one (sub-)step failed; the fallback decides what to do.
#[derive(Debug)]
pub(crate) enum Failure {
    /// Newton reached its iteration limit.
    NotConverged { iterations: usize },
    /// The system failed, or the state became non-finite.
    Error(IntegrateError),
}

impl From<IntegrateError> for Failure {
    fn from(e: IntegrateError) -> Self {
        Failure::Error(e)
    }
}

/// One Newton solve of an implicit scheme: the evaluation time and the
/// affine map's slopes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Affine {
    /// Time at which the equation of motion is enforced, s.
    pub t: f64,
    /// `∂q/∂x`, s².
    pub c_q: f64,
    /// `∂v/∂x`, s.
    pub c_v: f64,
    /// The (sub-)step, s (velocity tolerance `tol/h`).
    pub h: f64,
}

/// Solves `r(t, q_b + c_q x, v_b + c_v x, x) = 0` for `x`, starting from the
/// `ws.x` given. `ws.qb`, `ws.vb` hold the affine bases. With
/// `one_shot` exactly one correction is made and no convergence is tested.
/// On success `ws.x` is the solution and `ws.q`, `ws.v` the matching
/// coordinates and velocities.
pub(crate) fn solve<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    ws: &mut Workspace,
    map: Affine,
    settings: &NewtonSettings,
    one_shot: bool,
    stats: &mut StepStats,
) -> Result<(), Failure> {
    let Affine { t, c_q, c_v, h } = map;
    let tol = sys.position_tolerance();
    let vel_tol = tol / h;
    let rel = settings.relative_tolerance;
    let max_iterations = if one_shot { 1 } else { settings.max_iterations.max(1) };
    let sys_err = |source| Failure::Error(IntegrateError::System { t, source });
    for _ in 0..max_iterations {
        update_coordinates(ws, c_q, c_v);
        sys.residual_and_correction(t, &ws.q, &ws.v, &ws.x, c_v, c_q, &mut ws.r, &mut ws.dx).map_err(sys_err)?;
        stats.residual_evals += 1;
        if !ws.r.iter().all(|x| x.is_finite()) {
            return Err(IntegrateError::NonFinite { t }.into());
        }
        stats.solves += 1;
        stats.newton_iterations += 1;
        let mut converged = true;
        for i in 0..ws.x.len() {
            let d = ws.dx[i];
            if !d.is_finite() {
                return Err(IntegrateError::NonFinite { t }.into());
            }
            ws.x[i] += d;
            let dq = (c_q * d).abs();
            let dv = (c_v * d).abs();
            if dq > tol + rel * ws.q[i].abs() || dv > vel_tol + rel * ws.v[i].abs() {
                converged = false;
            }
        }
        if one_shot || converged {
            update_coordinates(ws, c_q, c_v);
            return Ok(());
        }
    }
    Err(Failure::NotConverged { iterations: max_iterations })
}

fn update_coordinates(ws: &mut Workspace, c_q: f64, c_v: f64) {
    for i in 0..ws.x.len() {
        ws.q[i] = ws.qb[i] + c_q * ws.x[i];
        ws.v[i] = ws.vb[i] + c_v * ws.x[i];
    }
}
