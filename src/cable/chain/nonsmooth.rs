//! The chain as a `SecondOrderSystem`: frozen branches of the non-smooth
//! laws, the link-by-link Newton update, static solves and the
//! highest-frequency estimate.

use super::*;
use crate::cable::spatial::V6;
use crate::integrate::{SecondOrderSystem, SystemError, KINK_BAND};
use glam::{DMat3, DQuat, DVec3};

/// Slack (m) within which a tension-only element starts a Newton solve on
/// its taut branch ([`SecondOrderSystem::freeze_branches`]): a rope laid
/// from coordinates rounded to the micrometre starts taut.
const TAUT_BAND: f64 = 1e-6;

impl SecondOrderSystem for Chain {
    fn dof(&self) -> usize {
        self.joints.len()
    }
    fn residual(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        self.residual_into(t, q, v, a, r)
    }
    fn solve_tangent(&mut self, _t: f64, _q: &[f64], _v: &[f64], _a: &[f64], c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        self.solve_into(c_v, c_q, b, x)
    }
    fn residual_and_correction(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        c_v: f64,
        c_q: f64,
        rhs: &mut [f64],
        x: &mut [f64],
    ) -> Result<(), SystemError> {
        self.residual_and_correction_into(t, q, v, a, c_v, c_q, rhs, x)
    }
    fn max_frequency(&self, _q: &[f64]) -> Option<f64> {
        self.max_frequency
    }
    fn calm(&self, q: &[f64], v: &[f64]) -> bool {
        self.calm_at(q, v)
    }
    fn set_definite_tangent(&mut self, on: bool) {
        self.use_definite_tangent(on);
    }
    fn tangent_fell_back(&self) -> bool {
        self.fell_back()
    }
    fn energy_balance(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64]) -> Option<crate::integrate::EnergyBalance> {
        self.energy_balance_at(t, q, v, a)
    }
    fn accounts_energy(&self) -> bool {
        Chain::accounts_energy(self)
    }
    fn position_tolerance(&self) -> f64 {
        self.position_tolerance
    }
    fn linearisation_limits(&self) -> Option<crate::integrate::LinearisationLimits> {
        Some(crate::integrate::LinearisationLimits::ROPE)
    }
    fn resolve_last_tangent(&mut self, b: &[f64], x: &mut [f64]) -> bool {
        // The tree's elimination only (no pair-element loop correction),
        // with the motion axes of the last residual: an estimate.
        self.resolve(b, x, |_, _| {});
        true
    }
    fn resolves_exactly(&self) -> bool {
        // The pair elements' loop correction is not in `resolve`. With
        // force elements (contacts, anchor springs) chords are not taken
        // either: a contact that opens between two iterations leaves the
        // elimination with its stiffness, and a chord correction measured
        // against that stiffer tangent can pass the convergence test while
        // the exact one would not (measured: a carried box resting on the
        // ground, a rope dropped on itself, failed).
        self.pairs.is_empty() && self.forces.is_empty()
    }
    fn freeze_branches(&mut self, start: (&[f64], &[f64]), predicted: (&[f64], &[f64])) {
        // Force elements (contacts' friction): read at the solve's first
        // evaluation, the predictor (`hold_force_branches`).
        self.force_branch.clear();
        self.forces_frozen = !self.forces.is_empty();
        // An invalid description freezes nothing: the next evaluation
        // reports it.
        if self.assign_slots().is_err() || self.nonsmooth.is_empty() {
            return;
        }
        self.branch.resize(self.joints.len(), LawBranch::Taut);
        // Taut unless both the step's start and the predictor are slack by
        // more than `TAUT_BAND` (or the position tolerance), in the law's
        // own measure `u + τ u̇` (a damped element unloading faster than its
        // damper is slack while still stretched): an
        // element at its kink (unstrained, or laid from rounded coordinates)
        // is taken taut, and the predictor's round-off (its acceleration on
        // a light element between heavy ones) cannot start it slack. A
        // wrong guess costs one branch update; starting a barely slack rope
        // slack would cost one update per element, as the pull reaches each
        // element only once the one above it is taut.
        let band = self.position_tolerance.max(TAUT_BAND);
        for &s in &self.nonsmooth {
            let s = s as usize;
            let j = &self.joints[s];
            self.branch[s] = if j.taut_measure(start.0[s], start.1[s]) >= -band || j.taut_measure(predicted.0[s], predicted.1[s]) >= -band {
                LawBranch::Taut
            } else if j.closed_measure(start.0[s], start.1[s]) < 0.0 || j.closed_measure(predicted.0[s], predicted.1[s]) < 0.0 {
                // Shortened to its stop at the start or by the
                // predictor: it pushes back.
                LawBranch::Closed
            } else {
                LawBranch::Slack
            };
        }
        self.frozen = true;
    }
    fn update_branches(&mut self, q: &[f64], v: &[f64]) -> usize {
        let mut moved = self.update_force_branches();
        if !self.frozen {
            return moved;
        }
        // A slack law that pulls moves to taut at once (and one that has
        // shortened past its stop to closed); a taut law moves to
        // slack only once it pushes beyond the kink band (`KINK_BAND`), and
        // a closed one once it pulls beyond it. Within the band it is
        // accepted anyway, and moving it would send the change down a rope
        // near zero tension (its own weight only) one element per update.
        let tol = self.position_tolerance;
        let band = tol.max(KINK_BAND);
        for i in 0..self.nonsmooth.len() {
            let s = self.nonsmooth[i] as usize;
            let limit = if self.branch[s] != LawBranch::Slack { band } else { tol };
            if self.disagreement(s, q, v) > limit {
                self.branch[s] = self.joints[s].branch_at(q[s], v[s]);
                moved += 1;
            }
        }
        moved
    }
    fn branch_disagreement(&self, q: &[f64], v: &[f64]) -> f64 {
        // Friction's, relative to its limit, in the same measure: at
        // `FRICTION_BAND` it is `KINK_BAND`.
        let friction = self.force_disagreements().fold(0.0, f64::max) * (KINK_BAND / FRICTION_BAND);
        if !self.frozen {
            return friction;
        }
        self.nonsmooth.iter().map(|&s| self.disagreement(s as usize, q, v)).fold(friction, f64::max)
    }
    fn release_branches(&mut self) {
        self.frozen = false;
        self.forces_frozen = false;
        self.force_branch.clear();
    }
    /// A chain with force elements ([`Chain::forces`]): a stiff one can
    /// whip a payload about at 100 g, where the inertia terms the O(n)
    /// tangent leaves out (not symmetric: it needs symmetric link blocks)
    /// slow Newton to a linear rate (docs/architecture.md, "Force
    /// elements").
    fn patient_newton(&self) -> bool {
        // The fallback for indefinite tangents converges linearly while it
        // leaves the geometric stiffness out.
        !self.forces.is_empty() || !self.pairs.is_empty() || self.definite_tangent
    }
    fn nonlinear_update(&mut self, q: &[f64], dx: &[f64], scale: f64, out: &mut [f64]) -> bool {
        // Only a chain closed by anchor springs needs it (an open chain's
        // tip is free, and the plain sum costs nothing).
        if self.anchors.is_empty() && self.forces.is_empty() && self.pairs.is_empty() {
            return false;
        }
        self.link_update(q, dx, scale, out);
        true
    }
}

/// How far (relative to its limit) a force element's friction may lie
/// outside the branch it is held on and the solve still accepted
/// ([`ForceElement::branch_disagreement`]): a contact held sticking whose
/// trial force is 0.1 % over `μ F_n`. Beyond it,
/// [`SecondOrderSystem::update_branches`] releases it to its own law.
pub const FRICTION_BAND: f64 = 1e-3;

impl Chain {
    /// At each evaluation of a Newton solve on frozen branches: at the
    /// first, every force element whose law sticks there is held sticking
    /// (a slipping one stays free); later, a free one whose slip turned
    /// round since the last evaluation (its trial force's direction
    /// reversed) is held sticking from here on. A slip that reverses from
    /// one Newton iterate to the next is Coulomb's sign switching inside
    /// the tiny band where the stick spring's damper alone holds it
    /// (`|c_t v| < μ F_n`, micrometres per second for steel): Newton
    /// steps across it at every iterate, and a rope heap at rest
    /// (2026-11-29) cycled so through every frame step. Held, the contact
    /// settles; if the solution slips after all, `update_branches`
    /// releases it.
    pub(super) fn hold_force_branches(&mut self, t: f64) {
        let first = self.force_branch.len() != self.forces.len();
        if first {
            self.force_branch.clear();
            self.force_branch.resize(self.forces.len(), None);
            self.slip_direction.clear();
            self.slip_direction.resize(self.forces.len(), DVec3::ZERO);
        }
        for ((fe, held), last) in self.forces.iter().zip(self.force_branch.iter_mut()).zip(self.slip_direction.iter_mut()) {
            if held.is_some() {
                continue;
            }
            let (at, _) = super::sweep::point_state(&self.poses[fe.link], self.origin, fe.local_point);
            match fe.element.branch(t, &at) {
                Some(FrictionBranch::Stick) if first => *held = Some(FrictionBranch::Stick),
                Some(FrictionBranch::Slip(d)) if d.dot(*last) < 0.0 => *held = Some(FrictionBranch::Stick),
                Some(FrictionBranch::Slip(d)) => *last = d,
                _ => *last = DVec3::ZERO,
            }
        }
    }

    /// Each held force element's disagreement with its branch at the last
    /// evaluation ([`ForceElement::branch_disagreement`]).
    fn force_disagreements(&self) -> impl Iterator<Item = f64> + '_ {
        let held = self.forces_frozen && self.force_branch.len() == self.forces.len();
        let t = self.last_t;
        self.forces
            .iter()
            .zip(self.force_element_points())
            .zip(&self.force_branch)
            .filter(move |_| held)
            .filter_map(move |((fe, at), b)| b.map(|b| fe.element.branch_disagreement(t, &at, b)))
    }

    /// Moves each held force element whose law the last evaluation puts
    /// beyond [`FRICTION_BAND`] of its branch to the branch it is on
    /// there; returns how many moved.
    fn update_force_branches(&mut self) -> usize {
        if !(self.forces_frozen && self.force_branch.len() == self.forces.len()) {
            return 0;
        }
        let t = self.last_t;
        let mut moved = 0;
        let points: Vec<PointState> = self.force_element_points().collect();
        for ((fe, at), b) in self.forces.iter().zip(&points).zip(self.force_branch.iter_mut()) {
            if let Some(held) = *b {
                if fe.element.branch_disagreement(t, at, held) > FRICTION_BAND {
                    // Released: free again (a slipping law is solved on
                    // its own law).
                    *b = fe.element.branch(t, at).filter(|b| *b == FrictionBranch::Stick);
                    moved += 1;
                }
            }
        }
        moved
    }

    /// A Newton correction `dq = scale·dx` applied link by link: each
    /// sub-link is moved by its own linearised motion `δX_s = Σ_{j≤s} S_j dq_j` (a rotation
    /// `exp(ω)` and the displacement `v + ω × p` of its origin), and the
    /// new coordinates are read back from the moved links, base to tip
    /// (a revolute sub-joint takes the rotation about its axis that is
    /// left, a slide the distance along its axis). To first order this is
    /// `q + dq`; the second-order error of a rotation far up the chain is
    /// no longer carried to the tip (where a stiff anchor spring turns it
    /// into a huge force) but left as a small local stretch of each
    /// element. Uses the poses and motion subspaces of the last kinematics
    /// pass, which must have been at `q`.
    pub(crate) fn link_update(&self, q: &[f64], dx: &[f64], scale: f64, out: &mut [f64]) {
        let (mut prev_rot, mut prev_pos) = self.base_pose;
        let mut tw = V6::ZERO;
        let tree = !self.limbs.is_empty();
        let mut stash = vec![(V6::ZERO, DMat3::IDENTITY, DVec3::ZERO); self.limb_acc.len()];
        let mut next_limb = 0;
        for (s, j) in self.joints.iter().enumerate() {
            if tree {
                if s > 0 && self.limb_parent[s - 1] != u32::MAX {
                    stash[self.limb_parent[s - 1] as usize] = (tw, prev_rot, prev_pos);
                }
                if self.limb_start[s] {
                    (tw, prev_rot, prev_pos) = match self.limbs[next_limb].parent {
                        None => (V6::ZERO, self.base_pose.0, self.base_pose.1),
                        Some(p) => stash[self.limb_parent[p] as usize],
                    };
                    next_limb += 1;
                }
            }
            let dq = scale * dx[s];
            tw += self.rows[s].s * dq;
            let pose = &self.poses[s];
            let w = tw.top;
            // (The layout's codes are those of the kinematics pass at `q`.)
            let (rj, pj) = j.frame(self.joint_code[s], prev_rot, prev_pos);
            let aw = rj * j.axis;
            match j.kind {
                JointKind::Revolute => {
                    let target = DMat3::from_quat(DQuat::from_scaled_axis(w)) * pose.rot;
                    let lin = q[s] + dq;
                    let r_lin = rotate_about(rj, j.axis, lin);
                    let e = rotation_vector(&(target * r_lin.transpose()));
                    out[s] = lin + e.dot(aw);
                    prev_rot = rotate_about(rj, j.axis, out[s]);
                    prev_pos = pj;
                }
                JointKind::Prismatic => {
                    let target = pose.pos + tw.bot + w.cross(pose.pos);
                    out[s] = aw.dot(target - pj);
                    prev_rot = rj;
                    prev_pos = pj + aw * out[s];
                }
            }
        }
    }
}

/// Why a static solve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StaticError {
    /// The tangent solve failed.
    #[error(transparent)]
    System(#[from] SystemError),
    /// No equilibrium found within the iteration limit.
    #[error("no static equilibrium after {iterations} iterations (largest residual {residual:e})")]
    NotConverged {
        /// Iterations done.
        iterations: usize,
        /// Largest residual component left, N or N·m.
        residual: f64,
    },
    /// The equilibrium found needs a tension-only (rope) element to push.
    #[error("the equilibrium needs sub-joint {joint} of a tension-only rope to push with {force:.6e} N (a rope cannot; `tension_only(false)` keeps compression for a rod or beam)")]
    Compressed {
        /// Sub-joint index of the most compressed axial slide.
        joint: usize,
        /// Its force on the linear law (negative: compression), N.
        force: f64,
    },
}

impl Chain {
    /// Finds the static equilibrium `r(t, q, 0, 0) = 0` from the starting
    /// coordinates `q` (updated in place) by pseudo-transient continuation:
    /// steps `Δq = c (M + c K_t)⁻¹ (−r)` with the pseudo-time factor `c`
    /// (s²) ×4 after every step and ÷2 after a step that needed the
    /// rotation limit (0.1 rad per iteration, so a far start cannot jump to
    /// another equilibrium): damped Newton that becomes full Newton near the
    /// solution. Returns the iterations used.
    ///
    /// Converged when a step moves no coordinate by more than `tol` (m or
    /// rad) and a full Newton step (`c → ∞`) from there would not either;
    /// this is independent of the residual's round-off floor (stiff anchor
    /// springs make it large in newtons).
    ///
    /// Tension-only laws are solved on their taut branch (a rope at rest
    /// under gravity and loads is taut wherever it is straight or hangs);
    /// an equilibrium that needs a tension-only element to push by more
    /// than `tol` is refused ([`StaticError::Compressed`]).
    pub fn solve_static(&mut self, t: f64, q: &mut [f64], tol: f64, max_iterations: usize) -> Result<usize, StaticError> {
        self.freeze_taut();
        // Pseudo-transient continuation on the Gauss–Newton tangent of the
        // bending–torsion law: with the law's geometric part (exact, but
        // not convex where a joint is bent), the static solve of the
        // two-leg sling stalled at a residual of 8e-4 after 2 000 steps.
        self.law_gauss_newton = true;
        let result = self.solve_static_on_branches(t, q, tol, max_iterations);
        self.law_gauss_newton = false;
        self.release_branches();
        let iterations = result?;
        let compressed = self.nonsmooth.iter().map(|&s| s as usize).map(|s| (s, q[s] - self.joints[s].rest)).min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((joint, x)) = compressed.filter(|&(_, x)| x < -tol) {
            return Err(StaticError::Compressed { joint, force: self.joints[joint].stiffness * x });
        }
        Ok(iterations)
    }

    /// How far (m or rad, [`SubJoint::taut_measure`] and
    /// [`SubJoint::closed_measure`]) the non-smooth law of sub-joint `s` is
    /// on the other side of a kink from its frozen branch at `(q, v)`; 0
    /// when they agree.
    fn disagreement(&self, s: usize, q: &[f64], v: &[f64]) -> f64 {
        let j = &self.joints[s];
        let (taut, closed) = (j.taut_measure(q[s], v[s]), j.closed_measure(q[s], v[s]));
        match self.branch[s] {
            LawBranch::Taut => (-taut).max(0.0),
            LawBranch::Closed => closed.max(0.0),
            LawBranch::Slack => taut.max(-closed).max(0.0),
        }
    }

    /// Every tension-only law frozen on its taut branch (the linear law).
    fn freeze_taut(&mut self) {
        if self.assign_slots().is_err() {
            return;
        }
        self.branch.clear();
        self.branch.resize(self.joints.len(), LawBranch::Taut);
        self.frozen = !self.nonsmooth.is_empty();
    }

    fn solve_static_on_branches(&mut self, t: f64, q: &mut [f64], tol: f64, max_iterations: usize) -> Result<usize, StaticError> {
        let n = self.len();
        let zero = vec![0.0; n];
        let mut r = vec![0.0; n];
        let mut x = vec![0.0; n];
        let mut c: f64 = 1e-2;
        let mut last_norm = f64::INFINITY;
        for it in 1..=max_iterations {
            self.residual_into(t, q, &zero, &zero, &mut r)?;
            let norm = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            last_norm = norm;
            for v in r.iter_mut() {
                *v = -*v;
            }
            self.solve_into(0.0, c, &r, &mut x)?;
            let max_rot = self.joints.iter().zip(&x).filter(|(j, _)| j.kind == JointKind::Revolute).fold(0.0f64, |m, (_, xi)| m.max((c * xi).abs()));
            let factor = if max_rot > 0.1 { 0.1 / max_rot } else { 1.0 };
            // Steps that need the rotation limit are too long: shorten the
            // pseudo-time; otherwise lengthen it toward full Newton.
            let c_next = if factor < 1.0 { c * 0.5 } else { c * 4.0 };
            let mut worst: f64 = 0.0;
            for (qi, xi) in q.iter_mut().zip(&x) {
                let dq = factor * c * xi;
                *qi += dq;
                worst = worst.max(dq.abs());
            }
            c = c_next.clamp(1e-6, 1e12);
            if worst < tol {
                // Would a full Newton step move anything? (c → ∞.)
                let big = 1e12;
                self.residual_into(t, q, &zero, &zero, &mut r)?;
                for v in r.iter_mut() {
                    *v = -*v;
                }
                self.solve_into(0.0, big, &r, &mut x)?;
                let full = x.iter().fold(0.0f64, |m, v| m.max((big * v).abs()));
                if full < 10.0 * tol {
                    self.residual_into(t, q, &zero, &zero, &mut r)?;
                    return Ok(it);
                }
            }
        }
        Err(StaticError::NotConverged { iterations: max_iterations, residual: last_norm })
    }
}

impl Chain {
    /// Estimates the highest natural angular frequency (rad/s) of the chain
    /// linearised at `(t, q)` at rest: power iteration on `M⁻¹ K_t`, with
    /// `K_t x` from central differences of the residual and `M⁻¹` from the
    /// O(n) solve (O(n) per iteration). Used to choose explicit sub-steps.
    /// Tension-only laws count on their taut (stiff) branch: the
    /// differences would straddle the kink of an unstrained element.
    pub fn estimate_max_frequency(&mut self, t: f64, q: &[f64], iterations: usize) -> Result<f64, SystemError> {
        self.freeze_taut();
        let result = self.power_iteration(t, q, iterations);
        self.release_branches();
        Ok(result?.max(0.0).sqrt())
    }

    /// The largest eigenvalue of `M⁻¹ K_t` by power iteration (1/s²).
    fn power_iteration(&mut self, t: f64, q: &[f64], iterations: usize) -> Result<f64, SystemError> {
        let n = self.len();
        let zero = vec![0.0; n];
        let (mut rp, mut rm, mut y) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        // Deterministic start vector with every coordinate present.
        let mut x: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * ((i as f64) * 0.7548776662).fract()).collect();
        let mut lambda: f64 = 0.0;
        for _ in 0..iterations {
            let norm = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if norm == 0.0 || !norm.is_finite() {
                break;
            }
            x.iter_mut().for_each(|v| *v /= norm);
            let eps = 1e-7;
            let qp: Vec<f64> = q.iter().zip(&x).map(|(a, b)| a + eps * b).collect();
            let qm: Vec<f64> = q.iter().zip(&x).map(|(a, b)| a - eps * b).collect();
            self.residual_into(t, &qp, &zero, &zero, &mut rp)?;
            self.residual_into(t, &qm, &zero, &zero, &mut rm)?;
            let kx: Vec<f64> = rp.iter().zip(&rm).map(|(a, b)| (a - b) / (2.0 * eps)).collect();
            self.residual_into(t, q, &zero, &zero, &mut rp)?;
            self.solve_into(0.0, 0.0, &kx, &mut y)?;
            lambda = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            std::mem::swap(&mut x, &mut y);
        }
        Ok(lambda)
    }
}
