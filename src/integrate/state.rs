//! The integrator state `(t, q, v, a, â)`.

use super::error::IntegrateError;
use super::integrator::StepStats;
use super::system::SecondOrderSystem;

/// The state a scheme carries from step to step.
///
/// Units follow the system's coordinates: `q` in m or rad, `v` in m/s or
/// rad/s, `a` and `a_hat` in m/s² or rad/s².
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Time, s.
    pub t: f64,
    /// Generalized coordinates.
    pub q: Vec<f64>,
    /// Generalized velocities.
    pub v: Vec<f64>,
    /// Accelerations. Consistent with `(t, q, v)` after [`State::new`] and
    /// after every step of the explicit, Newmark-family and linearly
    /// implicit schemes (to the Newton tolerance); Wilson-θ stores its
    /// interpolated acceleration, which is not.
    pub a: Vec<f64>,
    /// Generalized-α pseudo-acceleration â (equal to `a` for every other
    /// scheme).
    pub a_hat: Vec<f64>,
}

impl State {
    /// A state at time `t` (s) with coordinates `q` and velocities `v`, and
    /// the consistent initial acceleration `a₀ = M⁻¹ Q(t, q, v)` (one
    /// residual and one solve with `c_v = c_q = 0`); `â₀ = a₀`.
    pub fn new<S: SecondOrderSystem + ?Sized>(sys: &mut S, t: f64, q: Vec<f64>, v: Vec<f64>) -> Result<Self, IntegrateError> {
        let n = q.len();
        let mut state = State { t, q, v, a: vec![0.0; n], a_hat: vec![0.0; n] };
        state.check_dimensions(sys.dof())?;
        state.recompute_acceleration(sys)?;
        Ok(state)
    }

    /// Number of coordinates.
    pub fn dof(&self) -> usize {
        self.q.len()
    }

    /// Recomputes `a` (and sets `â = a`) from `(t, q, v)`. Call it after
    /// changing `q` or `v` by hand (a teleport) or before switching from
    /// Wilson-θ to another scheme.
    pub fn recompute_acceleration<S: SecondOrderSystem + ?Sized>(&mut self, sys: &mut S) -> Result<(), IntegrateError> {
        self.check_dimensions(sys.dof())?;
        let n = self.dof();
        let (zeros, mut r) = (vec![0.0; n], vec![0.0; n]);
        let mut stats = StepStats::default();
        acceleration(sys, self.t, &self.q, &self.v, &zeros, &mut r, &mut self.a, &mut stats)?;
        self.a_hat.copy_from_slice(&self.a);
        Ok(())
    }

    /// Checks that all four vectors have `dof` entries.
    pub(crate) fn check_dimensions(&self, dof: usize) -> Result<(), IntegrateError> {
        let vectors = [("q", &self.q), ("v", &self.v), ("a", &self.a), ("a_hat", &self.a_hat)];
        for (what, x) in vectors {
            if x.len() != dof {
                return Err(IntegrateError::DimensionMismatch { t: self.t, what, expected: dof, got: x.len() });
            }
        }
        Ok(())
    }

    /// Inserts coordinates `q` (m or rad) with velocities `v` before index
    /// `at`, with zero acceleration, to match a system that grew there (a
    /// chain's [`insert_joints`](crate::cable::Chain::insert_joints)). Then
    /// recompute the acceleration ([`State::recompute_acceleration`]) and
    /// reset the integrator's history
    /// ([`Integrator::reset_history`](crate::integrate::Integrator::reset_history)).
    /// Refused when `at` is past the end or `q` and `v` differ in length.
    pub fn insert(&mut self, at: usize, q: &[f64], v: &[f64]) -> Result<(), IntegrateError> {
        let n = self.q.len();
        if at > n {
            return Err(IntegrateError::IndexOutOfRange { t: self.t, what: "insertion point", index: at, len: n });
        }
        if q.len() != v.len() {
            return Err(IntegrateError::DimensionMismatch { t: self.t, what: "inserted velocities", expected: q.len(), got: v.len() });
        }
        let zeros = std::iter::repeat_n(0.0, q.len());
        self.q.splice(at..at, q.iter().copied());
        self.v.splice(at..at, v.iter().copied());
        self.a.splice(at..at, zeros.clone());
        self.a_hat.splice(at..at, zeros);
        Ok(())
    }

    /// Removes the coordinates `range`, to match a system that shrank there
    /// (a chain's [`remove_joints`](crate::cable::Chain::remove_joints));
    /// then recompute the acceleration and reset the integrator's history
    /// as for [`State::insert`]. Refused when the range is past the end.
    pub fn remove(&mut self, range: std::ops::Range<usize>) -> Result<(), IntegrateError> {
        let n = self.q.len();
        if range.start > range.end || range.end > n {
            return Err(IntegrateError::IndexOutOfRange { t: self.t, what: "removal range end", index: range.end, len: n });
        }
        for x in [&mut self.q, &mut self.v, &mut self.a, &mut self.a_hat] {
            x.drain(range.clone());
        }
        Ok(())
    }

    /// True when every entry of `q`, `v`, `a` and `a_hat` is finite.
    pub fn is_finite(&self) -> bool {
        [&self.q, &self.v, &self.a, &self.a_hat].iter().all(|x| all_finite(x))
    }
}

/// True when every entry of `x` is finite. `x·0` is zero for a finite `x`
/// and NaN for an infinity or a NaN; summed in eight independent lanes the
/// test vectorises (an `all(is_finite)` loop branches on every entry, and a
/// plain sum chains every addition on the one before).
#[inline]
pub(crate) fn all_finite(x: &[f64]) -> bool {
    let mut lanes = [0.0f64; 8];
    let chunks = x.chunks_exact(8);
    let tail: f64 = chunks.remainder().iter().map(|v| v * 0.0).sum();
    for c in chunks {
        for (l, v) in lanes.iter_mut().zip(c) {
            *l += v * 0.0;
        }
    }
    lanes.iter().sum::<f64>() + tail == 0.0
}

/// Forward dynamics `out = M⁻¹ Q(t, q, v)`: the residual at `a = 0` is `−Q`,
/// then one solve with `c_v = c_q = 0`. `zeros` must be all zero; `r` is
/// scratch.
#[allow(clippy::too_many_arguments)]
pub(crate) fn acceleration<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    t: f64,
    q: &[f64],
    v: &[f64],
    zeros: &[f64],
    r: &mut [f64],
    out: &mut [f64],
    stats: &mut StepStats,
) -> Result<(), IntegrateError> {
    let sys_err = |source| IntegrateError::System { t, source };
    sys.residual(t, q, v, zeros, r).map_err(sys_err)?;
    stats.residual_evals += 1;
    for ri in r.iter_mut() {
        *ri = -*ri;
    }
    sys.solve_tangent(t, q, v, zeros, 0.0, 0.0, r, out).map_err(sys_err)?;
    stats.solves += 1;
    if all_finite(out) {
        Ok(())
    } else {
        Err(IntegrateError::NonFinite { t })
    }
}

#[cfg(test)]
mod finite_tests {
    use super::all_finite;

    /// A NaN or an infinity at any place (in the eight lanes or the tail)
    /// is found; finite values, however large or of either zero's sign,
    /// pass (`x·0` cannot overflow, unlike a sum of the values).
    #[test]
    fn all_finite_finds_every_nan_and_infinity_and_passes_huge_values() {
        for n in [0usize, 1, 7, 8, 9, 17, 64, 67] {
            let mut x: Vec<f64> = (0..n).map(|i| if i % 2 == 0 { f64::MAX } else { -0.0 }).collect();
            assert!(all_finite(&x), "n = {n}");
            for i in 0..n {
                for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    let keep = x[i];
                    x[i] = bad;
                    assert!(!all_finite(&x), "n = {n}, {bad} at {i}");
                    x[i] = keep;
                }
            }
        }
    }
}
