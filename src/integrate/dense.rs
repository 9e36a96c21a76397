//! A small linear system `M ẍ + C ẋ + K x = F(t)` with constant dense
//! matrices, for tests and toy models.
//!
//! It solves its effective matrix by Gaussian elimination with partial
//! pivoting, O(n³) per solve: fine for a handful of coordinates. Ropes
//! implement [`SecondOrderSystem`] with their own O(n) articulated-body
//! solve instead.

use std::fmt;

use thiserror::Error;

use super::system::{SecondOrderSystem, SystemError};

/// Why a [`DenseSystem`] could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum DenseSystemError {
    /// A matrix or vector has the wrong size.
    #[error("{what} has {got} entries, expected {expected}")]
    DimensionMismatch {
        /// Which input (`mass`, `damping`, `stiffness`, `force`, or a row).
        what: &'static str,
        /// Expected number of entries.
        expected: usize,
        /// Number given.
        got: usize,
    },
    /// An entry is NaN or infinite.
    #[error("{what} has a non-finite entry")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
}

/// A time-dependent load: writes `F(t)` (N or N·m per coordinate) into the slice.
pub type ForceFn = dyn FnMut(f64, &mut [f64]) + Send + Sync;

enum Force {
    Zero,
    Constant(Vec<f64>),
    Function(Box<ForceFn>),
}

/// `M ẍ + C ẋ + K x = F(t)` with constant dense `n × n` matrices, stored
/// row-major. Units: M in kg (or kg·m²), C in N·s/m, K in N/m, F in N (or
/// the rotational equivalents).
pub struct DenseSystem {
    n: usize,
    mass: Vec<f64>,
    damping: Vec<f64>,
    stiffness: Vec<f64>,
    force: Force,
    f_buf: Vec<f64>,
    a_eff: Vec<f64>,
}

impl fmt::Debug for DenseSystem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("DenseSystem")
            .field("n", &self.n)
            .field("mass", &self.mass)
            .field("damping", &self.damping)
            .field("stiffness", &self.stiffness)
            .field(
                "force",
                &match &self.force {
                    Force::Zero => "zero",
                    Force::Constant(_) => "constant",
                    Force::Function(_) => "function",
                },
            )
            .finish()
    }
}

fn check_matrix(what: &'static str, m: &[f64], n: usize) -> Result<(), DenseSystemError> {
    if m.len() != n * n {
        return Err(DenseSystemError::DimensionMismatch { what, expected: n * n, got: m.len() });
    }
    if !m.iter().all(|x| x.is_finite()) {
        return Err(DenseSystemError::NonFinite { what });
    }
    Ok(())
}

fn flatten(what: &'static str, rows: &[Vec<f64>], n: usize) -> Result<Vec<f64>, DenseSystemError> {
    if rows.len() != n {
        return Err(DenseSystemError::DimensionMismatch { what, expected: n, got: rows.len() });
    }
    let mut flat = Vec::with_capacity(n * n);
    for row in rows {
        if row.len() != n {
            return Err(DenseSystemError::DimensionMismatch { what, expected: n, got: row.len() });
        }
        flat.extend_from_slice(row);
    }
    Ok(flat)
}

impl DenseSystem {
    /// A system with `n` coordinates from row-major `n × n` mass, damping and
    /// stiffness matrices, and no load.
    pub fn new(n: usize, mass: Vec<f64>, damping: Vec<f64>, stiffness: Vec<f64>) -> Result<Self, DenseSystemError> {
        check_matrix("mass", &mass, n)?;
        check_matrix("damping", &damping, n)?;
        check_matrix("stiffness", &stiffness, n)?;
        Ok(DenseSystem { n, mass, damping, stiffness, force: Force::Zero, f_buf: vec![0.0; n], a_eff: vec![0.0; n * n] })
    }

    /// Like [`new`](Self::new) with matrices given as rows.
    pub fn from_rows(mass: &[Vec<f64>], damping: &[Vec<f64>], stiffness: &[Vec<f64>]) -> Result<Self, DenseSystemError> {
        let n = mass.len();
        DenseSystem::new(n, flatten("mass", mass, n)?, flatten("damping", damping, n)?, flatten("stiffness", stiffness, n)?)
    }

    /// The one-coordinate oscillator `m ẍ + c ẋ + k x = 0` (kg, N·s/m, N/m).
    pub fn oscillator(m: f64, c: f64, k: f64) -> Result<Self, DenseSystemError> {
        DenseSystem::new(1, vec![m], vec![c], vec![k])
    }

    /// Sets a constant load vector `F` (N), one entry per coordinate.
    pub fn with_force_vector(mut self, force: Vec<f64>) -> Result<Self, DenseSystemError> {
        if force.len() != self.n {
            return Err(DenseSystemError::DimensionMismatch { what: "force", expected: self.n, got: force.len() });
        }
        if !force.iter().all(|x| x.is_finite()) {
            return Err(DenseSystemError::NonFinite { what: "force" });
        }
        self.force = Force::Constant(force);
        Ok(self)
    }

    /// Sets a time-dependent load: `f(t, out)` writes `F(t)` (N) into `out`
    /// (zeroed before each call).
    pub fn with_force(mut self, f: impl FnMut(f64, &mut [f64]) + Send + Sync + 'static) -> Self {
        self.force = Force::Function(Box::new(f));
        self
    }

    /// Mass matrix, row-major.
    pub fn mass(&self) -> &[f64] {
        &self.mass
    }

    /// Damping matrix, row-major.
    pub fn damping(&self) -> &[f64] {
        &self.damping
    }

    /// Stiffness matrix, row-major.
    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness
    }

    /// Mechanical energy `½ vᵀ M v + ½ qᵀ K q` (J).
    pub fn energy(&self, q: &[f64], v: &[f64]) -> f64 {
        0.5 * (quadratic(&self.mass, v, self.n) + quadratic(&self.stiffness, q, self.n))
    }

    fn load(&mut self, t: f64) {
        match &mut self.force {
            Force::Zero => self.f_buf.fill(0.0),
            Force::Constant(f) => self.f_buf.copy_from_slice(f),
            Force::Function(f) => {
                self.f_buf.fill(0.0);
                f(t, &mut self.f_buf);
            }
        }
    }
}

fn quadratic(m: &[f64], x: &[f64], n: usize) -> f64 {
    (0..n).map(|i| x[i] * (0..n).map(|j| m[i * n + j] * x[j]).sum::<f64>()).sum()
}

fn first_non_finite(xs: &[&[f64]]) -> Option<usize> {
    xs.iter().find_map(|x| x.iter().position(|y| !y.is_finite()))
}

impl SecondOrderSystem for DenseSystem {
    fn dof(&self) -> usize {
        self.n
    }

    /// `r = M a + C v + K q − F(t)`.
    fn residual(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        if let Some(index) = first_non_finite(&[q, v, a]) {
            return Err(SystemError::NonFinite { index });
        }
        self.load(t);
        let n = self.n;
        for (i, ri) in r.iter_mut().enumerate().take(n) {
            let row = i * n..(i + 1) * n;
            let (m, c, k) = (&self.mass[row.clone()], &self.damping[row.clone()], &self.stiffness[row]);
            let mut s = -self.f_buf[i];
            for j in 0..n {
                s += m[j] * a[j] + c[j] * v[j] + k[j] * q[j];
            }
            *ri = s;
        }
        Ok(())
    }

    /// Gaussian elimination with partial pivoting on `M + c_v C + c_q K`.
    fn solve_tangent(&mut self, _t: f64, _q: &[f64], _v: &[f64], _a: &[f64], c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        let n = self.n;
        let a = &mut self.a_eff;
        for (idx, e) in a.iter_mut().enumerate() {
            *e = self.mass[idx] + c_v * self.damping[idx] + c_q * self.stiffness[idx];
        }
        gauss_solve(n, a, b, x)
    }

    /// `√(λ_max(M⁻¹K))` bounded from above (rad/s): with a diagonal M by
    /// Gershgorin's rows of `M⁻¹K`; otherwise by `λ_max(K)/λ_min(M)` with
    /// Gershgorin bounds on both (`None` if that lower bound of M is not
    /// positive). Damping is ignored.
    fn max_frequency(&self, _q: &[f64]) -> Option<f64> {
        let n = self.n;
        let row_abs = |m: &[f64], i: usize| (0..n).map(|j| m[i * n + j].abs()).sum::<f64>();
        let diagonal = (0..n).all(|i| (0..n).all(|j| i == j || self.mass[i * n + j] == 0.0));
        let bound = if diagonal {
            let mut b = 0.0f64;
            for i in 0..n {
                let m = self.mass[i * n + i];
                if m <= 0.0 {
                    return None;
                }
                b = b.max(row_abs(&self.stiffness, i) / m);
            }
            b
        } else {
            let k_max = (0..n).map(|i| row_abs(&self.stiffness, i)).fold(0.0, f64::max);
            let m_min = (0..n).map(|i| 2.0 * self.mass[i * n + i] - row_abs(&self.mass, i)).fold(f64::INFINITY, f64::min);
            if m_min <= 0.0 {
                return None;
            }
            k_max / m_min
        };
        Some(bound.sqrt())
    }
}

/// Solves the row-major `n × n` system `a x = b` by Gaussian elimination
/// with partial pivoting, O(n³) (`a` is overwritten). A pivot below
/// `1e-14 n max|a|` is [`SystemError::Singular`].
pub(crate) fn gauss_solve(n: usize, a: &mut [f64], b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
    x.copy_from_slice(b);
    let scale = a.iter().fold(0.0f64, |s, e| s.max(e.abs()));
    for col in 0..n {
        let (piv, pmax) = (col..n).map(|r| (r, a[r * n + col].abs())).fold((col, -1.0), |best, c| if c.1 > best.1 { c } else { best });
        if pmax.is_nan() || pmax <= 1e-14 * scale * n as f64 {
            return Err(SystemError::Singular { index: col, pivot: a[piv * n + col] });
        }
        if piv != col {
            for j in 0..n {
                a.swap(col * n + j, piv * n + j);
            }
            x.swap(col, piv);
        }
        let p = a[col * n + col];
        for r in col + 1..n {
            let f = a[r * n + col] / p;
            if f != 0.0 {
                for j in col..n {
                    a[r * n + j] -= f * a[col * n + j];
                }
                x[r] -= f * x[col];
            }
        }
    }
    for col in (0..n).rev() {
        let mut s = x[col];
        for j in col + 1..n {
            s -= a[col * n + j] * x[j];
        }
        x[col] = s / a[col * n + col];
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_matches_a_known_system() {
        // A zero first pivot forces a row swap.
        let mut s = DenseSystem::new(3, vec![0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 2.0], vec![0.0; 9], vec![0.0; 9]).expect("valid");
        let mut x = [0.0; 3];
        s.solve_tangent(0.0, &[0.0; 3], &[0.0; 3], &[0.0; 3], 0.0, 0.0, &[1.0, 2.0, 3.0], &mut x).expect("regular");
        assert_eq!(x, [2.0, 1.0, 1.5]);
        let mut z = DenseSystem::oscillator(0.0, 0.0, 0.0).expect("valid");
        let mut y = [0.0];
        assert!(matches!(z.solve_tangent(0.0, &[0.0], &[0.0], &[0.0], 1.0, 1.0, &[1.0], &mut y), Err(SystemError::Singular { index: 0, .. })));
    }

    #[test]
    fn residual_with_force_and_frequency_bounds() {
        let mut s = DenseSystem::from_rows(&[vec![2.0, 0.0], vec![0.0, 1.0]], &[vec![0.1, 0.0], vec![0.0, 0.1]], &[vec![6.0, -2.0], vec![-2.0, 4.0]])
            .expect("valid")
            .with_force(|t, f| f[1] = t);
        let mut r = [0.0; 2];
        s.residual(3.0, &[1.0, 1.0], &[1.0, 0.0], &[1.0, 2.0], &mut r).expect("finite");
        assert_eq!(r, [2.0 + 0.1 + 4.0, 2.0 + 2.0 - 3.0]);
        // Gershgorin rows of M⁻¹K: max(8/2, 6/1) = 6.
        assert_eq!(s.max_frequency(&[0.0; 2]), Some(6f64.sqrt()));
        let osc = DenseSystem::oscillator(2.0, 0.0, 8.0).expect("valid");
        assert_eq!(osc.max_frequency(&[0.0]), Some(2.0));
        assert!(DenseSystem::new(2, vec![1.0; 3], vec![0.0; 4], vec![0.0; 4]).is_err());
        assert!(DenseSystem::oscillator(f64::NAN, 0.0, 1.0).is_err());
        assert!(matches!(s.residual(0.0, &[f64::NAN, 0.0], &[0.0; 2], &[0.0; 2], &mut r), Err(SystemError::NonFinite { index: 0 })));
    }
}
