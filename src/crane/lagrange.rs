//! Lagrange's equations for machines made of point masses, derived
//! automatically from their positions (REFERENCE.md §6).
//!
//! A model gives the world positions `p_i(q)` of its point masses as a
//! function of the generalized coordinates, written once over [`Jet`]s.
//! Evaluating it on jets gives, exactly (no finite differences), the
//! velocity `J_i q̇` and the convective acceleration `J̇_i q̇` along `q̇`,
//! and the Jacobian columns along the unit directions. The equations of
//! motion are then d'Alembert's principle in generalized coordinates,
//!
//! `Σ_i m_i J_iᵀ (J_i q̈ + J̇_i q̇ − g) + diag(I_c) q̈ = Q_a(t, q, q̇)`,
//!
//! which is `d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q = Q_a` for
//! `T = ½ Σ m_i |J_i q̇|² + ½ Σ I_c q̇_c²` and `V = −Σ m_i g·p_i`.

use crate::integrate::{SecondOrderSystem, SystemError};

/// A number with its first and second derivative along one direction:
/// `f(q + s d)` at `s = 0` as `(f, f', f'')`. Arithmetic follows the
/// product and chain rules, so a model's position function written over
/// jets returns its velocity and its convective acceleration exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet {
    /// Value.
    pub v: f64,
    /// First derivative along the direction.
    pub d: f64,
    /// Second derivative along the direction.
    pub dd: f64,
}

impl Jet {
    /// A constant (zero derivatives).
    pub const fn constant(v: f64) -> Self {
        Jet { v, d: 0.0, dd: 0.0 }
    }
    /// A coordinate with value `v` moving at rate `d` (no second derivative).
    pub const fn variable(v: f64, d: f64) -> Self {
        Jet { v, d, dd: 0.0 }
    }
    /// Sine.
    pub fn sin(self) -> Self {
        let (s, c) = self.v.sin_cos();
        Jet { v: s, d: c * self.d, dd: c * self.dd - s * self.d * self.d }
    }
    /// Cosine.
    pub fn cos(self) -> Self {
        let (s, c) = self.v.sin_cos();
        Jet { v: c, d: -s * self.d, dd: -s * self.dd - c * self.d * self.d }
    }
}

impl std::ops::Add for Jet {
    type Output = Jet;
    fn add(self, o: Jet) -> Jet {
        Jet { v: self.v + o.v, d: self.d + o.d, dd: self.dd + o.dd }
    }
}

impl std::ops::Sub for Jet {
    type Output = Jet;
    fn sub(self, o: Jet) -> Jet {
        Jet { v: self.v - o.v, d: self.d - o.d, dd: self.dd - o.dd }
    }
}

impl std::ops::Neg for Jet {
    type Output = Jet;
    fn neg(self) -> Jet {
        Jet { v: -self.v, d: -self.d, dd: -self.dd }
    }
}

impl std::ops::Mul for Jet {
    type Output = Jet;
    fn mul(self, o: Jet) -> Jet {
        Jet { v: self.v * o.v, d: self.d * o.v + self.v * o.d, dd: self.dd * o.v + 2.0 * self.d * o.d + self.v * o.dd }
    }
}

impl std::ops::Mul<f64> for Jet {
    type Output = Jet;
    fn mul(self, k: f64) -> Jet {
        Jet { v: self.v * k, d: self.d * k, dd: self.dd * k }
    }
}

/// A machine of point masses in generalized coordinates (REFERENCE.md §6):
/// the description [`LagrangeSystem`] turns into equations of motion
/// (`Clone`: a model is data, and the explicit schemes' rate estimate
/// works on a copy).
pub trait PointMassModel: Clone {
    /// Number of generalized coordinates.
    fn dof(&self) -> usize;
    /// The point masses, kg (their number fixes the length of
    /// [`PointMassModel::positions`]' output).
    fn masses(&self) -> Vec<f64>;
    /// Constant inertia on coordinate `i` besides the point masses (kg for a
    /// slide, kg·m² for a rotation: a slewing jib, a drum). Default 0.
    fn coordinate_inertia(&self, _i: usize) -> f64 {
        0.0
    }
    /// World positions of the point masses (m) at coordinates given as jets.
    fn positions(&self, q: &[Jet], out: &mut [[Jet; 3]]);
    /// Gravitational acceleration, m/s² (world).
    fn gravity(&self) -> [f64; 3];
    /// Generalized applied forces besides gravity (drives, dampers),
    /// `Q_a(t, q, q̇)`, N or N·m, written into `out` (zeroed by the caller).
    fn applied_forces(&self, t: f64, q: &[f64], v: &[f64], out: &mut [f64]);
}

/// The equations of motion of a [`PointMassModel`] as a
/// [`SecondOrderSystem`]: every integrator of [`crate::integrate`] steps it.
///
/// The residual is exact. The tangents `∂r/∂q` and `∂r/∂q̇` of the Newton
/// matrix are central differences of the residual (a reduced model has a
/// handful of coordinates; the tangent only sets Newton's rate, not the
/// answer), solved by Gaussian elimination with partial pivoting.
#[derive(Clone, Debug)]
pub struct LagrangeSystem<M: PointMassModel> {
    /// The model.
    pub model: M,
    masses: Vec<f64>,
    points: Vec<[Jet; 3]>,
    jacobian: Vec<[f64; 3]>,
    jets: Vec<Jet>,
}

impl<M: PointMassModel> LagrangeSystem<M> {
    /// Wraps a model.
    pub fn new(model: M) -> Self {
        let masses = model.masses();
        let (n, p) = (model.dof(), masses.len());
        LagrangeSystem { model, masses, points: vec![[Jet::constant(0.0); 3]; p], jacobian: vec![[0.0; 3]; n * p], jets: vec![Jet::constant(0.0); n] }
    }

    /// Re-reads the masses after the model was changed.
    pub fn refresh(&mut self) {
        self.masses = self.model.masses();
        let (n, p) = (self.model.dof(), self.masses.len());
        self.points.resize(p, [Jet::constant(0.0); 3]);
        self.jacobian.resize(n * p, [0.0; 3]);
        self.jets.resize(n, Jet::constant(0.0));
    }

    /// Positions (m) and velocities (m/s) of the point masses at `(q, q̇)`.
    pub fn points(&mut self, q: &[f64], v: &[f64]) -> Vec<([f64; 3], [f64; 3])> {
        self.eval(q, v);
        self.points.iter().map(|p| ([p[0].v, p[1].v, p[2].v], [p[0].d, p[1].d, p[2].d])).collect()
    }

    /// Kinetic energy `T`, J.
    pub fn kinetic_energy(&mut self, q: &[f64], v: &[f64]) -> f64 {
        self.eval(q, v);
        let mut t: f64 = self.points.iter().zip(&self.masses).map(|(p, m)| 0.5 * m * (p[0].d * p[0].d + p[1].d * p[1].d + p[2].d * p[2].d)).sum();
        for (i, vi) in v.iter().enumerate() {
            t += 0.5 * self.model.coordinate_inertia(i) * vi * vi;
        }
        t
    }

    /// Gravitational potential energy `V = −Σ m_i g·p_i`, J.
    pub fn potential_energy(&mut self, q: &[f64]) -> f64 {
        let zeros = vec![0.0; q.len()];
        self.eval(q, &zeros);
        let g = self.model.gravity();
        -self.points.iter().zip(&self.masses).map(|(p, m)| m * (g[0] * p[0].v + g[1] * p[1].v + g[2] * p[2].v)).sum::<f64>()
    }

    /// The mass matrix `M(q) = Σ m_i J_iᵀ J_i + diag(I_c)`, row-major.
    pub fn mass_matrix(&mut self, q: &[f64]) -> Vec<f64> {
        let n = self.model.dof();
        self.jacobians(q);
        let mut m = vec![0.0; n * n];
        for r in 0..n {
            for c in 0..n {
                let mut s = 0.0;
                for (k, mass) in self.masses.iter().enumerate() {
                    let (a, b) = (self.jacobian[r * self.masses.len() + k], self.jacobian[c * self.masses.len() + k]);
                    s += mass * (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
                }
                m[r * n + c] = s;
            }
            m[r * n + r] += self.model.coordinate_inertia(r);
        }
        m
    }

    /// Adds `coef ∂r/∂q` (or `coef ∂r/∂q̇` with `wrt_velocity`) at
    /// `(t, q, q̇, q̈)` to the row-major `out`, by central differences of the
    /// residual (step `1e-6 (1 + |x|)` per coordinate).
    #[allow(clippy::too_many_arguments)]
    fn add_tangent(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], wrt_velocity: bool, coef: f64, out: &mut [f64]) -> Result<(), SystemError> {
        let n = self.model.dof();
        let (mut rp, mut rm) = (vec![0.0; n], vec![0.0; n]);
        let (mut qs, mut vs) = (q.to_vec(), v.to_vec());
        for c in 0..n {
            let x = if wrt_velocity { &mut vs } else { &mut qs };
            let base = x[c];
            let e = 1e-6 * (1.0 + base.abs());
            x[c] = base + e;
            self.residual(t, &qs, &vs, a, &mut rp)?;
            let x = if wrt_velocity { &mut vs } else { &mut qs };
            x[c] = base - e;
            self.residual(t, &qs, &vs, a, &mut rm)?;
            let x = if wrt_velocity { &mut vs } else { &mut qs };
            x[c] = base;
            for row in 0..n {
                out[row * n + c] += coef * (rp[row] - rm[row]) / (2.0 * e);
            }
        }
        Ok(())
    }

    /// Positions on jets along direction `v` (into `self.points`).
    fn eval(&mut self, q: &[f64], v: &[f64]) {
        for ((j, qi), vi) in self.jets.iter_mut().zip(q).zip(v) {
            *j = Jet::variable(*qi, *vi);
        }
        self.model.positions(&self.jets, &mut self.points);
    }

    /// The Jacobian columns `∂p_k/∂q_c` (into `self.jacobian[c·P + k]`).
    fn jacobians(&mut self, q: &[f64]) {
        let (n, p) = (self.model.dof(), self.masses.len());
        for c in 0..n {
            for (i, j) in self.jets.iter_mut().enumerate() {
                *j = Jet::variable(q[i], if i == c { 1.0 } else { 0.0 });
            }
            self.model.positions(&self.jets, &mut self.points);
            for k in 0..p {
                self.jacobian[c * p + k] = [self.points[k][0].d, self.points[k][1].d, self.points[k][2].d];
            }
        }
    }
}

impl<M: PointMassModel> SecondOrderSystem for LagrangeSystem<M> {
    fn dof(&self) -> usize {
        self.model.dof()
    }

    fn residual(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        if let Some(index) = q.iter().chain(v).chain(a).position(|x| !x.is_finite()) {
            return Err(SystemError::NonFinite { index: index % q.len().max(1) });
        }
        let (n, p) = (self.model.dof(), self.masses.len());
        self.jacobians(q);
        self.eval(q, v);
        let g = self.model.gravity();
        r.iter_mut().for_each(|x| *x = 0.0);
        self.model.applied_forces(t, q, v, r);
        for x in r.iter_mut() {
            *x = -*x;
        }
        for k in 0..p {
            // Acceleration of mass k minus gravity: J a + J̇ q̇ − g.
            let mut acc = [self.points[k][0].dd - g[0], self.points[k][1].dd - g[1], self.points[k][2].dd - g[2]];
            for (c, ac) in a.iter().enumerate() {
                let jc = self.jacobian[c * p + k];
                for d in 0..3 {
                    acc[d] += jc[d] * ac;
                }
            }
            for (row, rr) in r.iter_mut().enumerate() {
                let jr = self.jacobian[row * p + k];
                *rr += self.masses[k] * (jr[0] * acc[0] + jr[1] * acc[1] + jr[2] * acc[2]);
            }
        }
        for (i, (rr, ai)) in r.iter_mut().zip(a).enumerate().take(n) {
            *rr += self.model.coordinate_inertia(i) * ai;
        }
        Ok(())
    }

    /// An estimate of the fastest rate of the linearised model at `q`
    /// (rad/s or 1/s) for the explicit schemes' sub-steps: the larger of
    /// `√(max row sum |M⁻¹K_t|)` and `max row sum |M⁻¹C_t|` (Gershgorin
    /// bounds of the stiffness and damping rates), with the tangents taken
    /// at rest (`q̇ = q̈ = 0`, `t = 0`: a drive's speed loop is its damping).
    fn max_frequency(&self, q: &[f64]) -> Option<f64> {
        let n = self.model.dof();
        let mut sys = self.clone();
        let zeros = vec![0.0; n];
        let mass = sys.mass_matrix(q);
        // Gershgorin bound of M⁻¹ T for the stiffness (T = K_t) and the
        // damping (T = C_t) tangents.
        let mut bound = |wrt_velocity: bool| -> Option<f64> {
            let mut tangent = vec![0.0; n * n];
            sys.add_tangent(0.0, q, &zeros, &zeros, wrt_velocity, 1.0, &mut tangent).ok()?;
            let mut rows = vec![0.0f64; n];
            let mut col = vec![0.0; n];
            for c in 0..n {
                let mut m = mass.clone();
                let b: Vec<f64> = (0..n).map(|r| tangent[r * n + c]).collect();
                crate::integrate::gauss_solve(n, &mut m, &b, &mut col).ok()?;
                for (row, x) in rows.iter_mut().zip(&col) {
                    *row += x.abs();
                }
            }
            Some(rows.iter().fold(0.0f64, |m, x| m.max(*x)))
        };
        let stiffness = bound(false)?;
        let damping = bound(true)?;
        Some(stiffness.sqrt().max(damping))
    }

    fn solve_tangent(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        let n = self.model.dof();
        // M exactly, K_t and C_t by central differences of the residual.
        let mut m = self.mass_matrix(q);
        if c_q != 0.0 {
            self.add_tangent(t, q, v, a, false, c_q, &mut m)?;
        }
        if c_v != 0.0 {
            self.add_tangent(t, q, v, a, true, c_v, &mut m)?;
        }
        crate::integrate::gauss_solve(n, &mut m, b, x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A free point mass in a plane described in polar coordinates: the
    /// generated equations are the textbook ones,
    /// `m (r̈ − r θ̇²) = F_r`, `m (r² θ̈ + 2 r ṙ θ̇) = F_θ` (no gravity).
    #[derive(Clone)]
    struct Polar;
    impl PointMassModel for Polar {
        fn dof(&self) -> usize {
            2
        }
        fn masses(&self) -> Vec<f64> {
            vec![2.0]
        }
        fn positions(&self, q: &[Jet], out: &mut [[Jet; 3]]) {
            out[0] = [q[0] * q[1].cos(), q[0] * q[1].sin(), Jet::constant(0.0)];
        }
        fn gravity(&self) -> [f64; 3] {
            [0.0; 3]
        }
        fn applied_forces(&self, _t: f64, _q: &[f64], _v: &[f64], _out: &mut [f64]) {}
    }

    #[test]
    fn polar_coordinates_give_the_textbook_equations() {
        let mut sys = LagrangeSystem::new(Polar);
        let (q, v, a) = ([1.7, 0.4], [-0.3, 1.1], [0.25, -0.6]);
        let mut r = [0.0; 2];
        sys.residual(0.0, &q, &v, &a, &mut r).unwrap();
        let m = 2.0;
        let r0 = m * (a[0] - q[0] * v[1] * v[1]);
        let r1 = m * (q[0] * q[0] * a[1] + 2.0 * q[0] * v[0] * v[1]);
        assert!((r[0] - r0).abs() < 1e-12 && (r[1] - r1).abs() < 1e-12, "{r:?} vs {r0}, {r1}");
    }

    #[test]
    fn jets_follow_the_chain_rule() {
        // f(s) = sin(x + s d)·cos(x + s d) = ½ sin(2(x + s d)).
        let (x, d) = (0.37, 1.9);
        let j = Jet::variable(x, d);
        let f = j.sin() * j.cos();
        assert!((f.v - 0.5 * (2.0 * x).sin()).abs() < 1e-15);
        assert!((f.d - d * (2.0 * x).cos()).abs() < 1e-14);
        assert!((f.dd + 2.0 * d * d * (2.0 * x).sin()).abs() < 1e-13);
    }
}
