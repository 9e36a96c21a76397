//! Reduced crane models (Bevy-free): few-coordinate machines in the form
//! every integrator of [`crate::integrate`] steps, for controller design,
//! fast what-if studies and as references for the full rope simulation
//! (REFERENCE.md §6–§8, seeds 000, 003, 004).
//!
//! * [`OverheadCrane`]: trolley on a rail and a swinging payload;
//! * [`TowerCrane`]: slewing jib, trolley and a payload swinging in two angles;
//! * [`ForestryCrane`]: a trolley and a log bundle swinging in and out of
//!   the trolley's plane (seed 004);
//! * [`Hoist`]: the 3-mass, 2-DOF hoisting mechanism (drive, boom tip,
//!   payload on the rope) and its dynamic load factor;
//! * [`control`]: anti-sway controllers (ZV/ZVD input shaping, the double
//!   closed-loop, nonlinear and incremental PIDs, slew and trolley of a
//!   tower crane together) and closed loops on the reduced overhead and
//!   tower cranes;
//! * [`lagrange`]: the machinery that derives their equations of motion from
//!   the positions of their point masses ([`PointMassModel`], [`LagrangeSystem`]).
//!
//! Each model gives its closed-form small-swing frequencies, and
//! [`linearize`] its linearisation about rest from its own nonlinear
//! residual; `tests/crane_models.rs` checks the nonlinear equations
//! against both and against energy and momentum conservation.

pub mod control;
mod forestry;
mod hoist;
pub mod lagrange;
mod overhead;
mod tower;

pub use forestry::ForestryCrane;
pub use hoist::{Hoist, HoistDrive};
pub use lagrange::{Jet, LagrangeSystem, PointMassModel};
pub use overhead::OverheadCrane;
pub use tower::{TowerCrane, TowerHoist};

use thiserror::Error;

/// Why a crane model could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum CraneError {
    /// A parameter is out of range (NaN, infinite, zero or negative where it
    /// must be positive).
    #[error("{model}: {field} = {value} must be {requirement}")]
    InvalidParameter {
        /// Which model.
        model: &'static str,
        /// Which parameter.
        field: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        requirement: &'static str,
    },
    /// A closed loop could not start or step (the model's integrator failed).
    #[error(transparent)]
    Integrate(#[from] crate::integrate::IntegrateError),
}

/// A force limit: positive, infinity allowed (no limit).
pub(crate) fn check_limit(model: &'static str, field: &'static str, value: f64) -> Result<(), CraneError> {
    if value > 0.0 {
        Ok(())
    } else {
        Err(CraneError::InvalidParameter { model, field, value, requirement: "positive" })
    }
}

/// `x` limited to `±bound` (N): `|bound|` is used, a NaN bound gives 0.
pub(crate) fn limit(x: f64, bound: f64) -> f64 {
    let b = bound.abs();
    if b.is_nan() {
        0.0
    } else {
        x.clamp(-b, b)
    }
}

pub(crate) fn check_positive(model: &'static str, field: &'static str, value: f64) -> Result<(), CraneError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(CraneError::InvalidParameter { model, field, value, requirement: "positive and finite" })
    }
}

/// How a trolley is driven along its rail.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrolleyDrive {
    /// A given drive force, N.
    Force(f64),
    /// A speed-controlled drive: `F = clamp(gain (command − ẋ), ±max_force)`.
    Speed {
        /// Commanded trolley speed, m/s.
        command: f64,
        /// Proportional gain of the speed loop, N·s/m.
        gain: f64,
        /// Force limit of the drive, N.
        max_force: f64,
    },
}

impl TrolleyDrive {
    /// The drive force (N) at trolley speed `speed` (m/s).
    pub fn force(&self, speed: f64) -> f64 {
        match *self {
            TrolleyDrive::Force(f) => f,
            TrolleyDrive::Speed { command, gain, max_force } => limit(gain * (command - speed), max_force),
        }
    }
}

/// The linearisation of `sys` about rest at `q0` (an equilibrium: zero
/// velocity and acceleration there) at time `t`:
/// `M Δq̈ + C Δq̇ + K Δq = 0` with `M = ∂r/∂a` (exact: the residual is
/// linear in the acceleration), `C = ∂r/∂v` and `K = ∂r/∂q` by central
/// differences of the nonlinear residual `r = M(q) a − Q(t, q, v)` (steps
/// of 1e-6 of each coordinate's scale). Every reduced model has its
/// linearisation this way, from its own nonlinear equations.
pub fn linearize<S: crate::integrate::SecondOrderSystem + ?Sized>(sys: &mut S, t: f64, q0: &[f64]) -> Result<crate::integrate::DenseSystem, CraneError> {
    let n = sys.dof();
    if q0.len() != n || !q0.iter().all(|x| x.is_finite()) {
        return Err(CraneError::InvalidParameter {
            model: "linearisation",
            field: "q0",
            value: q0.len() as f64,
            requirement: "one finite value per coordinate",
        });
    }
    let zero = vec![0.0; n];
    let mut eval = |q: &[f64], v: &[f64], a: &[f64]| -> Result<Vec<f64>, CraneError> {
        let mut r = vec![0.0; n];
        sys.residual(t, q, v, a, &mut r).map_err(|source| crate::integrate::IntegrateError::System { t, source })?;
        Ok(r)
    };
    let r0 = eval(q0, &zero, &zero)?;
    let (mut mass, mut damping, mut stiffness) = (vec![0.0; n * n], vec![0.0; n * n], vec![0.0; n * n]);
    for j in 0..n {
        let eps = 1e-6 * q0[j].abs().max(1.0);
        let unit = |x: f64| {
            let mut e = zero.clone();
            e[j] = x;
            e
        };
        let ra = eval(q0, &zero, &unit(1.0))?;
        let (rqp, rqm) = (eval(&add(q0, &unit(eps)), &zero, &zero)?, eval(&add(q0, &unit(-eps)), &zero, &zero)?);
        let (rvp, rvm) = (eval(q0, &unit(eps), &zero)?, eval(q0, &unit(-eps), &zero)?);
        for i in 0..n {
            mass[i * n + j] = ra[i] - r0[i];
            stiffness[i * n + j] = (rqp[i] - rqm[i]) / (2.0 * eps);
            damping[i * n + j] = (rvp[i] - rvm[i]) / (2.0 * eps);
        }
    }
    crate::integrate::DenseSystem::new(n, mass, damping, stiffness).map_err(|_| CraneError::InvalidParameter {
        model: "linearisation",
        field: "matrices",
        value: f64::NAN,
        requirement: "finite",
    })
}

fn add(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + y).collect()
}
