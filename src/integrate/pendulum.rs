//! A nonlinear example system: the simple pendulum.

use super::system::{SecondOrderSystem, SystemError};

/// The planar simple pendulum `θ̈ + c θ̇ + (g/l) sin θ = 0` (θ in rad from
/// the downward vertical), with its exact tangent `K_t = (g/l) cos θ`,
/// `C_t = c`, `M = 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct Pendulum {
    /// Gravitational acceleration g, m/s².
    pub gravity: f64,
    /// Length l, m.
    pub length: f64,
    /// Viscous damping c, 1/s.
    pub damping: f64,
}

impl Pendulum {
    /// An undamped pendulum of length `length` (m) in gravity `gravity` (m/s²).
    pub fn new(gravity: f64, length: f64) -> Self {
        Pendulum { gravity, length, damping: 0.0 }
    }

    /// Small-amplitude angular frequency `√(g/l)`, rad/s.
    pub fn natural_frequency(&self) -> f64 {
        (self.gravity / self.length).sqrt()
    }

    /// Energy per unit `m l²`: `½ θ̇² + (g/l)(1 − cos θ)`, 1/s².
    pub fn energy(&self, theta: f64, omega: f64) -> f64 {
        0.5 * omega * omega + self.gravity / self.length * (1.0 - theta.cos())
    }
}

impl SecondOrderSystem for Pendulum {
    fn dof(&self) -> usize {
        1
    }

    fn residual(&mut self, _t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        if !(q[0].is_finite() && v[0].is_finite() && a[0].is_finite()) {
            return Err(SystemError::NonFinite { index: 0 });
        }
        r[0] = a[0] + self.damping * v[0] + self.gravity / self.length * q[0].sin();
        Ok(())
    }

    fn solve_tangent(&mut self, _t: f64, q: &[f64], _v: &[f64], _a: &[f64], c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        let pivot = 1.0 + c_v * self.damping + c_q * self.gravity / self.length * q[0].cos();
        if pivot.is_nan() || pivot.abs() <= 1e-14 {
            return Err(SystemError::Singular { index: 0, pivot });
        }
        x[0] = b[0] / pivot;
        Ok(())
    }

    /// `√(g/l)` (an upper bound: the tangent stiffness is `(g/l) cos θ`).
    fn max_frequency(&self, _q: &[f64]) -> Option<f64> {
        Some(self.natural_frequency())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_matches_finite_differences() {
        let mut p = Pendulum { gravity: 9.81, length: 2.0, damping: 0.3 };
        let (q, v, a) = (1.1, -0.4, 0.7);
        let (c_v, c_q) = (0.02, 1e-3);
        let r = |p: &mut Pendulum, x: f64| {
            let mut r = [0.0];
            p.residual(0.0, &[q + c_q * x], &[v + c_v * x], &[a + x], &mut r).expect("finite");
            r[0]
        };
        let eps = 1e-6;
        let jac = (r(&mut p, eps) - r(&mut p, -eps)) / (2.0 * eps);
        let mut x = [0.0];
        p.solve_tangent(0.0, &[q], &[v], &[a], c_v, c_q, &[jac], &mut x).expect("regular");
        assert!((x[0] - 1.0).abs() < 1e-9, "{}", x[0]);
    }
}
