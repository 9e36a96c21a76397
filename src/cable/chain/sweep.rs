//! The O(n) passes: kinematics, the tip-to-base residual sweep with the
//! articulated-body elimination, and the forward substitution.

use super::forest::{loop_correction, LoopPair};
use super::*;
use crate::cable::force::{point_to_spatial, ForceElement, FrictionBranch, PointState, PointWrench};
use crate::cable::spatial::{skew, M6, V6};
use crate::integrate::{all_finite, SystemError};
use glam::{DMat3, DQuat, DVec3};

/// Carry of the tip-to-base sweep that a limb hands to its parent link:
/// composite load, load tangent blocks and the articulated-body carry.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LimbCarry {
    fc: V6,
    ha: DMat3,
    hb: DMat3,
    inertia: M6,
    bias: V6,
}

impl Default for LimbCarry {
    /// Zero (glam's `DMat3::default()` is the identity).
    fn default() -> Self {
        LimbCarry { fc: V6::ZERO, ha: DMat3::ZERO, hb: DMat3::ZERO, inertia: M6::ZERO, bias: V6::ZERO }
    }
}

impl LimbCarry {
    fn add(&mut self, o: &LimbCarry) {
        self.fc += o.fc;
        self.ha += o.ha;
        self.hb += o.hb;
        self.inertia += o.inertia;
        self.bias += o.bias;
    }
}

/// What the solve needs of a pair element at the last residual: its two
/// points (relative to the chain's origin) and its tangents.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PairScratch {
    pub link_a: usize,
    pub link_b: usize,
    pub pa: DVec3,
    pub pb: DVec3,
    pub stiffness: DMat3,
    pub damping: DMat3,
    /// The one direction of the force and tangents, if any.
    pub normal: Option<DVec3>,
}

/// Pose of a sub-joint's link, rebuilt by every kinematics pass.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Pose {
    /// Link orientation.
    pub rot: DMat3,
    /// Link origin (relative to the chain origin).
    pub pos: DVec3,
    /// Link spatial velocity.
    pub vel: V6,
}

/// What the tip-to-base sweep and the solve need per sub-joint (written by
/// the kinematics pass, so the sweep and the solve stream this array alone).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Row {
    /// Motion subspace.
    pub s: V6,
    /// `G_s S_s`: the geometric-stiffness term the solve needs (see
    /// [`Chain::solve_into`]).
    pub gs: V6,
    /// ABA scratch: `U = I^A S`, `1/D`, `u`.
    pub u_vec: V6,
    pub d: f64,
    pub u: f64,
    /// Elastic + damping generalized force, N or N·m.
    pub elastic: f64,
    /// The sub-joint's stiffness and damping (its armature in the solve).
    pub stiffness: f64,
    pub damping: f64,
}

/// Scratch of a link with mass or with loads (one per element, and the
/// bodies). The spatial inertia `[[ia, ib], [ibᵀ, m 1]]` and the load
/// tangent `[[ha, hb], [0, 0]]` are kept as their non-trivial blocks.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LinkScratch {
    pub ia: DMat3,
    pub ib: DMat3,
    pub m: f64,
    /// Loads on this link alone (spatial force).
    pub f: V6,
    /// Load tangent `Σ B̃` of this link's loads (upper blocks).
    pub ha: DMat3,
    pub hb: DMat3,
    /// Index into [`Chain::anchor_blocks`], or `u32::MAX`.
    pub anchor: u32,
    /// Linear and angular velocity damping rates of the link's mass, 1/s.
    pub damping: (f64, f64),
}

impl Default for LinkScratch {
    fn default() -> Self {
        LinkScratch { ia: DMat3::ZERO, ib: DMat3::ZERO, m: 0.0, f: V6::ZERO, ha: DMat3::ZERO, hb: DMat3::ZERO, anchor: u32::MAX, damping: (0.0, 0.0) }
    }
}

impl LinkScratch {
    fn clear(&mut self) {
        let anchor = self.anchor;
        *self = LinkScratch { anchor, ..Default::default() };
    }
    /// Adds the load tangent `B̃` of a force of fixed direction at `p`.
    #[inline]
    fn add_point_load_tangent(&mut self, force: DVec3, p: DVec3) {
        let t = M6::point_load_tangent(force, p);
        self.ha += t.a;
        self.hb += t.b;
    }
}

impl Chain {
    /// One base-to-tip pass: forward kinematics, velocities and
    /// accelerations; the d'Alembert and gravity loads of every link with
    /// mass; every sub-joint's elastic force (rotation springs at their
    /// last sub-joint). Loads of other links are cleared.
    pub(crate) fn kinematics(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64]) -> Result<(), ChainError> {
        self.assign_slots()?;
        let base = self.base.at(t);
        let bp = base.position - self.origin;
        let bw = base.angular_velocity;
        // Spatial velocity/acceleration of the base, at the reference point.
        let mut prev_vel = V6::new(bw, base.velocity - bw.cross(bp));
        let mut prev_acc = V6::new(base.angular_acceleration, base.acceleration - base.angular_acceleration.cross(bp) - bw.cross(base.velocity));
        let mut prev_rot = base.rotation;
        let mut prev_pos = bp;
        self.base_pose = (prev_rot, prev_pos);
        let (base_vel, base_acc) = (prev_vel, prev_acc);
        let tree = !self.limbs.is_empty();
        let mut next_limb = 0;
        let mut next_spring = 0;
        for (s, j) in self.joints.iter().enumerate() {
            if tree && self.limb_start[s] {
                // A limb starts here: its parent is not link s − 1.
                let limb = self.limbs[next_limb];
                next_limb += 1;
                match limb.parent {
                    None => (prev_vel, prev_acc, prev_rot, prev_pos) = (base_vel, base_acc, self.base_pose.0, self.base_pose.1),
                    Some(p) => {
                        let ps = self.poses[p];
                        (prev_vel, prev_acc, prev_rot, prev_pos) = (ps.vel, self.limb_acc[self.limb_parent[p] as usize], ps.rot, ps.pos);
                    }
                }
            }
            let code = self.joint_code[s];
            let (rj, pj) = j.frame(code, prev_rot, prev_pos);
            // Principal axes (every rope sub-joint) are column picks.
            let axis_id = code & 3;
            let aw = match axis_id {
                0 => rj.x_axis,
                1 => rj.y_axis,
                2 => rj.z_axis,
                _ => rj * j.axis,
            };
            let (sv, rot, pos) = match j.kind {
                JointKind::Revolute => (V6::new(aw, pj.cross(aw)), rotate_about_id(rj, axis_id, j.axis, q[s]), pj),
                JointKind::Prismatic => (V6::new(DVec3::ZERO, aw), rj, pj + aw * q[s]),
            };
            let vel = prev_vel + sv * v[s];
            let acc = prev_acc + prev_vel.cross_motion(sv) * v[s] + sv * a[s];
            self.poses[s] = Pose { rot, pos, vel };
            let row = &mut self.rows[s];
            row.s = sv;
            let (elastic, stiffness, damping) =
                if self.frozen && j.law != SpringLaw::Linear { j.spring_force_on_branch(q[s], v[s], self.branch[s]) } else { j.spring_force(q[s], v[s]) };
            row.stiffness = stiffness;
            row.damping = damping;
            row.elastic = elastic;
            let slot = self.link_slot[s];
            if slot != u32::MAX {
                let ls = &mut self.links[slot as usize];
                ls.clear();
                if let Some(lm) = &j.link {
                    // d'Alembert + gravity at the centre of mass.
                    let c = pos + rot * lm.com;
                    let ic = rot * lm.inertia * rot.transpose();
                    let w = vel.top;
                    let vc = vel.bot + w.cross(c);
                    let alpha = acc.top;
                    let ac = acc.bot + alpha.cross(c) + w.cross(vc);
                    let mut force = (self.gravity - ac) * lm.mass;
                    let mut moment = -(ic * alpha + w.cross(ic * w));
                    if lm.linear_damping != 0.0 || lm.angular_damping != 0.0 {
                        force -= vc * (lm.linear_damping * lm.mass);
                        moment -= ic * w * lm.angular_damping;
                        ls.damping = (lm.linear_damping, lm.angular_damping);
                    }
                    ls.f = V6::new(c.cross(force) + moment, force);
                    ls.add_point_load_tangent(force, c);
                    let cx = skew(c);
                    ls.ia = ic + cx * cx.transpose() * lm.mass;
                    ls.ib = cx * lm.mass;
                    ls.m = lm.mass;
                }
            }
            // A rotation spring whose three sub-joints are now known.
            while let Some(&k) = self.spring_order.get(next_spring) {
                let rs = self.rotation_springs[k as usize];
                if rs.first + 2 > s {
                    break;
                }
                next_spring += 1;
                let (forces, a_mat, geometric) = rotation_spring_forces(&rs, &self.joints, q, v, true);
                for (i, fi) in forces.iter().enumerate() {
                    self.rows[rs.first + i].elastic = *fi;
                }
                self.rot_scratch[k as usize].0 = a_mat;
                self.rot_scratch[k as usize].2 = geometric;
            }
            if tree && self.limb_parent[s] != u32::MAX {
                self.limb_acc[self.limb_parent[s] as usize] = acc;
            }
            prev_vel = vel;
            prev_acc = acc;
            prev_rot = rot;
            prev_pos = pos;
        }
        Ok(())
    }

    /// Residual `r = M(q) a − Q(t, q, v)` (see [`SecondOrderSystem`](crate::integrate::SecondOrderSystem)); also
    /// prepares everything [`Chain::solve_into`] needs at this state.
    pub fn residual_into(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        self.sweep(t, q, v, a, r, None)
    }

    /// Residual and Newton correction in one tip-to-base sweep: `rhs = −r`
    /// and `(M + c_v C + c_q (K + K_g)) x = rhs` (see
    /// [`SecondOrderSystem::residual_and_correction`](crate::integrate::SecondOrderSystem::residual_and_correction)).
    #[allow(clippy::too_many_arguments)]
    pub fn residual_and_correction_into(
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
        self.sweep(t, q, v, a, rhs, Some((c_v, c_q)))?;
        self.finish_solve(c_v, c_q, rhs, x)?;
        self.pair_correction(c_v, c_q, x)
    }

    /// The base-to-tip half of a fused pass's solve, or, when its
    /// elimination found the tangent indefinite, the whole solve again
    /// without the geometric stiffness (see [`Chain::solve_into`]).
    pub(super) fn finish_solve(&mut self, c_v: f64, c_q: f64, rhs: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        if self.indefinite && self.definite_tangent {
            self.solve_without_geometric(c_v, c_q, rhs, x)
        } else {
            self.forward_solve(x);
            Ok(())
        }
    }

    /// The tree's solve with the geometric stiffness left out:
    /// `(M + c_v C + c_q K) x = b`.
    fn solve_without_geometric(&mut self, c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        self.fell_back = true;
        self.without_geometric = true;
        let solved = self.solve_tree(c_v, c_q, b, x);
        self.without_geometric = false;
        solved
    }

    /// Whether the last correction was solved without the geometric
    /// stiffness (the fallback for an indefinite tangent): it is not a
    /// Newton step ([`SecondOrderSystem::tangent_fell_back`](crate::integrate::SecondOrderSystem::tangent_fell_back)).
    pub(crate) fn fell_back(&self) -> bool {
        self.fell_back
    }

    /// Turns the fallback for indefinite tangents on or off (see
    /// [`Chain::solve_into`]).
    pub(crate) fn use_definite_tangent(&mut self, on: bool) {
        self.definite_tangent = on;
    }

    /// Whether the state `(q, v)` is calm ([`SecondOrderSystem::calm`](crate::integrate::SecondOrderSystem::calm)):
    /// no contact or other force element and no pair element acts, and
    /// every tension-only element is stretched beyond `KINK_BAND` (the free
    /// end of a hanging chain, near zero tension, is not). The integrator
    /// retries a failed step with the fallback for indefinite tangents only
    /// from and to calm states. Measured where it would otherwise apply: a
    /// ball left a rope with 20 % more energy than it struck it with, a
    /// capstan's slip ratio was 19 % off, a box crept under a push below its
    /// friction limit, and `hanging_chain.toml`, released from a shape,
    /// turned an element inside out.
    pub(crate) fn calm_at(&self, q: &[f64], v: &[f64]) -> bool {
        if !self.forces.is_empty() || !self.pairs.is_empty() || q.len() != self.joints.len() || v.len() != self.joints.len() {
            return false;
        }
        let band = self.position_tolerance.max(crate::integrate::KINK_BAND);
        self.nonsmooth.iter().all(|&s| self.joints[s as usize].taut_measure(q[s as usize], v[s as usize]) > band)
    }

    /// Forward kinematics, loads, and the tip-to-base sweep. Without
    /// `solve`, writes the residual into `r`; with `solve = (c_v, c_q)`,
    /// writes `−r` into `r` and runs the articulated-body backward sweep
    /// for that right-hand side on the way (finish with `forward_solve`).
    fn sweep(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64], solve: Option<(f64, f64)>) -> Result<(), SystemError> {
        Self::check_finite(q, v, a)?;
        self.kinematics(t, q, v, a)?;
        self.sweep_loads(t, r, solve)
    }

    /// A NaN or infinity in `q`, `v` or `a`, by the first coordinate that
    /// holds one.
    pub(super) fn check_finite(q: &[f64], v: &[f64], a: &[f64]) -> Result<(), SystemError> {
        // One cheap pass (then find which coordinate, for the message).
        if !(all_finite(q) && all_finite(v) && all_finite(a)) {
            if let Some(index) = q.iter().chain(v).chain(a).position(|x| !x.is_finite()) {
                return Err(SystemError::NonFinite { index: index % q.len().max(1) });
            }
        }
        Ok(())
    }

    /// [`Chain::sweep`] after the kinematics pass: the loads and force
    /// elements, then the tip-to-base sweep.
    pub(super) fn sweep_loads(&mut self, t: f64, r: &mut [f64], solve: Option<(f64, f64)>) -> Result<(), SystemError> {
        self.indefinite = false;
        self.fell_back = false;
        let n = self.joints.len();
        for ld in &self.loads {
            let ps = &self.poses[ld.link];
            let ls = &mut self.links[self.link_slot[ld.link] as usize];
            let p = ps.pos + ps.rot * ld.local_point;
            ls.f += V6::new(p.cross(ld.force) + ld.moment, ld.force);
            ls.add_point_load_tangent(ld.force, p);
        }
        for blocks in self.anchor_blocks.iter_mut() {
            *blocks = (M6::ZERO, M6::ZERO);
        }
        for an in &self.anchors {
            let slot = self.link_slot[an.link] as usize;
            apply_force_element(&mut self.links[slot], &mut self.anchor_blocks, &self.poses[an.link], self.origin, an.local_point, t, an, None);
        }
        self.last_t = t;
        if self.forces_frozen {
            self.hold_force_branches(t);
        }
        for (k, fe) in self.forces.iter().enumerate() {
            let slot = self.link_slot[fe.link] as usize;
            let held = if self.forces_frozen { self.force_branch[k] } else { None };
            apply_force_element(
                &mut self.links[slot],
                &mut self.anchor_blocks,
                &self.poses[fe.link],
                self.origin,
                fe.local_point,
                t,
                fe.element.as_ref(),
                held,
            );
        }
        // Pair elements: each point's force on its link (with its
        // moment-arm tangent); their stiffness and damping are the solve's
        // pair correction.
        self.pair_scratch.clear();
        for pr in &self.pairs {
            let (at_a, pa) = point_state(&self.poses[pr.link_a], self.origin, pr.point_a);
            let (at_b, pb) = point_state(&self.poses[pr.link_b], self.origin, pr.point_b);
            let w = pr.element.wrench(t, &at_a, &at_b);
            for (link, p, force) in [(pr.link_a, pa, w.force), (pr.link_b, pb, -w.force)] {
                let point = PointWrench { force, ..PointWrench::default() };
                add_point_wrench(&mut self.links[self.link_slot[link] as usize], &mut self.anchor_blocks, p, &point);
            }
            self.pair_scratch.push(PairScratch { link_a: pr.link_a, link_b: pr.link_b, pa, pb, stiffness: w.stiffness, damping: w.damping, normal: w.normal });
        }
        // Halves of pair elements with other chains (a forest's).
        for e in &self.external {
            add_point_wrench(&mut self.links[self.link_slot[e.link] as usize], &mut self.anchor_blocks, e.p, &e.wrench);
        }
        // Tip-to-base sweep: composite loads, residual, geometric stiffness.
        // The load tangent H = [[ha, hb], [0, 0]] is summed tip to base; its
        // symmetric part ½(H + Hᵀ) = [[hs, ½hb], [½hbᵀ, 0]].
        let mut fc = V6::ZERO;
        let (mut ha, mut hb) = (DMat3::ZERO, DMat3::ZERO);
        let (mut hs, mut hb2) = (DMat3::ZERO, DMat3::ZERO);
        let mut aba = AbaCarry::default();
        let tree = !self.limbs.is_empty();
        let mut base_extra = V6::ZERO;
        if tree {
            self.limb_carry.iter_mut().for_each(|c| *c = LimbCarry::default());
        }
        let mut next_limb = self.limbs.len();
        for s in (0..n).rev() {
            let slot = self.link_slot[s];
            if tree && self.limb_parent[s] != u32::MAX {
                // The limbs hanging from this link.
                let c = self.limb_carry[self.limb_parent[s] as usize];
                fc += c.fc;
                ha += c.ha;
                hb += c.hb;
                hs = (ha + ha.transpose()) * 0.5;
                hb2 = hb * 0.5;
                if solve.is_some() {
                    aba.inertia += c.inertia;
                    aba.bias += c.bias;
                }
            }
            if slot != u32::MAX {
                let ls = &self.links[slot as usize];
                fc += ls.f;
                ha += ls.ha;
                hb += ls.hb;
                hs = (ha + ha.transpose()) * 0.5;
                hb2 = hb * 0.5;
            }
            let row = &mut self.rows[s];
            let res = -row.s.dot(fc) + row.elastic - self.joint_forces[s];
            // G_s = ½(H + Hᵀ) + ½(a zᵀ + z aᵀ), a = F̄(f^c) S = S ×* f^c,
            // zᵀS = 1, aᵀS = 0, so G_s S_s = ½(H + Hᵀ) S + ½ S ×* f^c.
            let sv = row.s;
            let sym = if sv.top == DVec3::ZERO { V6::new(hb2 * sv.bot, DVec3::ZERO) } else { V6::new(hs * sv.top + hb2 * sv.bot, hb2.transpose() * sv.top) };
            row.gs = sym + sv.cross_force(fc) * 0.5;
            match solve {
                None => r[s] = res,
                Some((c_v, c_q)) => {
                    r[s] = -res;
                    // With the fallback on, an indefinite tangent (a
                    // negative pivot, or one that vanishes) stops the
                    // elimination: the residual is finished, and the caller
                    // solves again without the geometric stiffness.
                    // (The fused sweep never runs without the geometric
                    // stiffness: only `solve_tree` does.)
                    if !(self.indefinite && self.definite_tangent) {
                        match self.eliminate(&mut aba, s, c_v, c_q, r) {
                            Err(SystemError::Singular { .. }) if self.definite_tangent => self.indefinite = true,
                            other => other?,
                        }
                    }
                }
            }
            if tree && self.limb_start[s] {
                // The limb is done: hand its carry to its parent link.
                next_limb -= 1;
                let carry = LimbCarry { fc, ha, hb, inertia: aba.inertia, bias: aba.bias };
                match self.limbs[next_limb].parent {
                    None => base_extra += fc,
                    Some(p) => self.limb_carry[self.limb_parent[p] as usize].add(&carry),
                }
                (fc, ha, hb, hs, hb2) = (V6::ZERO, DMat3::ZERO, DMat3::ZERO, DMat3::ZERO, DMat3::ZERO);
                aba = AbaCarry::default();
            }
        }
        self.base_load = fc + base_extra;
        Ok(())
    }

    /// Solves `(M + c_v C + c_q (K + K_g)) x = b` at the state of the last
    /// [`Chain::residual_into`] call, in O(n).
    ///
    /// The geometric stiffness is `K_g = Σ J_sᵀ B_s J_s` with
    /// `B_s = G_{s+1} − G_s`, so link `s` carries `I_s + c_q (G_{s+1} − G_s)`.
    /// The sweep runs on the shifted articulated inertia
    /// `Ĩ_s = I^A_s + c_q G_s`, which obeys the plain recursion
    /// `Ĩ_s = I_s + Ĩ_{s+1} − U_{s+1} U_{s+1}ᵀ / D_{s+1}`, and needs `G_s` only
    /// through `U_s = Ĩ_s S_s − c_q G_s S_s`: no 6×6 geometric block is formed.
    ///
    /// **An indefinite tangent can be solved without `K_g`.** `K_g` comes from
    /// the composite loads at the iterate. Far from equilibrium (a stiff
    /// anchor spring whose target moved a quarter millimetre past the
    /// rope's predicted end pulls with about EA), the loads no longer balance
    /// the joints' elastic forces. The shear slides and the rotations then
    /// couple through a `K_g` larger than their own stiffness, and the
    /// elimination meets a negative pivot. That direction turns soft modes
    /// by radians: 12.8 rad of torsion in `examples/tow_rope.rs`. With the
    /// fallback on ([`SecondOrderSystem::set_definite_tangent`](crate::integrate::SecondOrderSystem::set_definite_tangent),
    /// which the integrator turns on only to retry a step whose Newton solve
    /// failed), an elimination that meets a negative pivot (or a vanishing
    /// one) runs again with `M + c_v C + c_q K`, which is positive definite.
    /// The residual is unchanged, so the converged solution is the same;
    /// only the iterates that find the tangent indefinite converge linearly.
    /// Off (the default), an indefinite tangent is solved as it is: some
    /// converging solves pass through indefinite iterates (a rope struck by
    /// a body, a compressed rod) and need the exact tangent there.
    pub fn solve_into(&mut self, c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        self.fell_back = false;
        self.solve_tree(c_v, c_q, b, x)?;
        self.pair_correction(c_v, c_q, x)
    }

    /// [`Chain::solve_into`] without the pair elements' loop correction
    /// (the tree's own tangent, each pair point's stiffness on its link).
    pub(super) fn solve_tree(&mut self, c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        self.indefinite = false;
        let mut aba = AbaCarry::default();
        let tree = !self.limbs.is_empty();
        if tree {
            self.limb_carry.iter_mut().for_each(|c| *c = LimbCarry::default());
        }
        let mut next_limb = self.limbs.len();
        for s in (0..self.joints.len()).rev() {
            if tree && self.limb_parent[s] != u32::MAX {
                let c = self.limb_carry[self.limb_parent[s] as usize];
                aba.inertia += c.inertia;
                aba.bias += c.bias;
            }
            let fallback = self.definite_tangent && !self.without_geometric;
            match self.eliminate(&mut aba, s, c_v, c_q, b) {
                Err(SystemError::Singular { .. }) if fallback => self.indefinite = true,
                other => other?,
            }
            if self.indefinite && fallback {
                return self.solve_without_geometric(c_v, c_q, b, x);
            }
            if tree && self.limb_start[s] {
                next_limb -= 1;
                if let Some(p) = self.limbs[next_limb].parent {
                    let carry = LimbCarry { inertia: aba.inertia, bias: aba.bias, ..Default::default() };
                    self.limb_carry[self.limb_parent[p] as usize].add(&carry);
                }
                aba = AbaCarry::default();
            }
        }
        self.forward_solve(x);
        Ok(())
    }

    /// Solves the last factorized tangent (the elimination of the last
    /// [`Chain::residual_and_correction_into`] or [`Chain::solve_into`])
    /// for another right-hand side `b`, without the pair correction: the
    /// tip-to-base bias pass alone, then the forward substitution (O(n),
    /// a fraction of a full solve). Overwrites the rows' `u`.
    pub(super) fn resolve(&mut self, b: &[f64], x: &mut [f64], link: impl FnMut(usize, V6)) {
        let tree = !self.limbs.is_empty();
        if tree {
            self.limb_carry.iter_mut().for_each(|c| c.bias = V6::ZERO);
        }
        let mut bias = V6::ZERO;
        let mut next_limb = self.limbs.len();
        for s in (0..self.joints.len()).rev() {
            if tree && self.limb_parent[s] != u32::MAX {
                bias += self.limb_carry[self.limb_parent[s] as usize].bias;
            }
            match self.block[s] {
                u32::MAX => {
                    let row = &mut self.rows[s];
                    let u = b[s] - row.s.dot(bias);
                    row.u = u;
                    bias += row.u_vec * (u * row.d);
                }
                BLOCK_INNER => {}
                k => {
                    let f = &mut self.rows[s..s + 3];
                    let ub = DVec3::new(b[s] - f[0].s.dot(bias), b[s + 1] - f[1].s.dot(bias), b[s + 2] - f[2].s.dot(bias));
                    let y = self.rot_scratch[k as usize].1 * ub;
                    for (j, r) in f.iter_mut().enumerate() {
                        r.u = ub[j];
                    }
                    bias += f[0].u_vec * y.x + f[1].u_vec * y.y + f[2].u_vec * y.z;
                }
            }
            if tree && self.limb_start[s] {
                next_limb -= 1;
                if let Some(p) = self.limbs[next_limb].parent {
                    self.limb_carry[self.limb_parent[p] as usize].bias += bias;
                }
                bias = V6::ZERO;
            }
        }
        self.forward_solve_with(x, link);
    }

    /// The sub-joint whose link is the parent of sub-joint `s`'s link
    /// (`None`: the base).
    pub(super) fn joint_parent(&self, s: usize) -> Option<usize> {
        if !self.limbs.is_empty() && self.limb_start[s] {
            let k = self.limbs.partition_point(|l| l.first < s);
            return self.limbs.get(k).and_then(|l| l.parent);
        }
        s.checked_sub(1)
    }

    /// Sub-joint `s` and the sub-joints its link hangs from, to the base.
    pub(super) fn ancestors(&self, s: usize) -> impl Iterator<Item = usize> + '_ {
        std::iter::successors(Some(s), |&j| self.joint_parent(j))
    }

    /// The spatial motion of each of `links` for the coordinate change `x`
    /// (`Σ S_j x_j` over the link's ancestors), into `out`.
    pub(super) fn link_motions(&self, x: &[f64], links: &[usize], out: &mut [V6]) {
        for (o, &l) in out.iter_mut().zip(links) {
            *o = self.ancestors(l).fold(V6::ZERO, |m, s| m + self.rows[s].s * x[s]);
        }
    }

    /// The pair elements' stiffness and damping (see [`Chain::pairs`]):
    /// the sweep's tangent leaves them out, and this adds them exactly by
    /// a Woodbury correction over the pairs ([`loop_correction`]).
    fn pair_correction(&mut self, c_v: f64, c_q: f64, x: &mut [f64]) -> Result<(), SystemError> {
        #[cfg(test)]
        if !self.pair_coupling {
            return Ok(());
        }
        if self.pair_scratch.is_empty() {
            return Ok(());
        }
        let pairs: Vec<LoopPair> = self.pair_scratch.iter().map(|p| LoopPair::within(0, p)).collect();
        loop_correction(&mut [(self, x)], &pairs, c_v, c_q)
    }

    /// Tip-to-base elimination of sub-joint `s` (right-hand side `b`): a
    /// single sub-joint, the second or third sub-joint of a rotation-spring
    /// block (only its link is added; the block is eliminated at its first
    /// sub-joint), or a whole block.
    ///
    /// A negative pivot marks the tangent indefinite ([`Chain::solve_into`]).
    fn eliminate(&mut self, aba: &mut AbaCarry, s: usize, c_v: f64, c_q: f64, b: &[f64]) -> Result<(), SystemError> {
        let slot = self.link_slot[s];
        if slot != u32::MAX {
            let ls = &self.links[slot as usize];
            aba.add_link(ls, &self.anchor_blocks, c_v, c_q);
        }
        let c_g = if self.without_geometric { 0.0 } else { c_q };
        let negative = match self.block[s] {
            u32::MAX => aba.down(s, &mut self.rows[s], c_v, c_q, c_g, b[s])?,
            BLOCK_INNER => false,
            k => {
                let rs = &self.rotation_springs[k as usize];
                let (a_mat, pinv, geometric) = &mut self.rot_scratch[k as usize];
                let c_law = if self.law_gauss_newton { 0.0 } else { c_g };
                aba.down_block(s, &mut self.rows[s..s + 3], rs, (a_mat, geometric), pinv, (c_v, c_q, c_g, c_law), [b[s], b[s + 1], b[s + 2]])?
            }
        };
        self.indefinite |= negative;
        Ok(())
    }

    /// Base-to-tip half of the articulated-body solve.
    pub(super) fn forward_solve(&mut self, x: &mut [f64]) {
        self.forward_solve_with(x, |_, _| {});
    }

    /// [`Chain::forward_solve`], handing `link(s, motion)` the spatial
    /// motion of each link (`Σ S_j x_j` over its ancestors) as it is found.
    #[inline]
    fn forward_solve_with(&mut self, x: &mut [f64], mut link: impl FnMut(usize, V6)) {
        let mut acc = V6::ZERO;
        let n = self.rows.len();
        let tree = !self.limbs.is_empty();
        let mut next_limb = 0;
        let mut s = 0;
        while s < n {
            if tree {
                if s > 0 && self.limb_parent[s - 1] != u32::MAX {
                    // (Blocks never contain a parent link: s − 1 was done
                    // alone, and `acc` is its acceleration.)
                    self.limb_acc[self.limb_parent[s - 1] as usize] = acc;
                }
                if self.limb_start[s] {
                    acc = match self.limbs[next_limb].parent {
                        None => V6::ZERO,
                        Some(p) => self.limb_acc[self.limb_parent[p] as usize],
                    };
                    next_limb += 1;
                }
            }
            match self.block[s] {
                u32::MAX | BLOCK_INNER => {
                    let row = &self.rows[s];
                    let xs = (row.u - row.u_vec.dot(acc)) * row.d;
                    x[s] = xs;
                    acc += row.s * xs;
                    link(s, acc);
                    s += 1;
                }
                k => {
                    let f = &self.rows[s..s + 3];
                    let y = DVec3::new(f[0].u - f[0].u_vec.dot(acc), f[1].u - f[1].u_vec.dot(acc), f[2].u - f[2].u_vec.dot(acc));
                    let xb = self.rot_scratch[k as usize].1 * y;
                    x[s] = xb.x;
                    x[s + 1] = xb.y;
                    x[s + 2] = xb.z;
                    acc += f[0].s * xb.x + f[1].s * xb.y + f[2].s * xb.z;
                    // (The block's first two links carry nothing.)
                    link(s + 2, acc);
                    s += 3;
                }
            }
        }
    }
}

/// Deviation rotation vector `θ = log(R₀ᵀ R)` of a rotation spring, and
/// `R₀ᵀ E_k` for its three axes.
pub(super) fn rotation_deviation(rs: &RotationSpring, joints: &[SubJoint], q: &[f64]) -> (DVec3, [DVec3; 3]) {
    let f = rs.first;
    deviation_at(rs, joints, [q[f], q[f + 1], q[f + 2]])
}

/// [`rotation_deviation`] at the spring's three angles `(a, b, c)`.
fn deviation_at(rs: &RotationSpring, joints: &[SubJoint], angles: [f64; 3]) -> (DVec3, [DVec3; 3]) {
    let f = rs.first;
    let rel = |a: f64, b: f64, c: f64| {
        let rz = rotate_about(DMat3::IDENTITY, DVec3::Z, a);
        let rzy = rotate_about(rz, DVec3::Y, b);
        (rz, rzy, rotate_about(rzy, DVec3::X, c))
    };
    let (rz, rzy, r) = rel(angles[0], angles[1], angles[2]);
    let rests = (joints[f].rest, joints[f + 1].rest, joints[f + 2].rest);
    if rests == (0.0, 0.0, 0.0) {
        return (rotation_vector(&r), [DVec3::Z, rz.y_axis, rzy.x_axis]);
    }
    let (_, _, r0) = rel(rests.0, rests.1, rests.2);
    let r0t = r0.transpose();
    let theta = rotation_vector(&(r0t * r));
    (theta, [r0t * DVec3::Z, r0t * rz.y_axis, r0t * rzy.x_axis])
}

/// `β(φ²) = (1 − (φ/2)cot(φ/2))/φ²` of `J_l⁻¹`.
#[inline]
fn jinv_beta(phi2: f64) -> f64 {
    if phi2 < 1e-6 {
        1.0 / 12.0 + phi2 / 720.0
    } else {
        let phi = phi2.sqrt();
        (1.0 - 0.5 * phi / (0.5 * phi).tan()) / phi2
    }
}

/// `J_l⁻¹(θ) x = x − ½ θ×x + β θ×(θ×x)` (`sign` = 1), or
/// `J_l⁻ᵀ(θ) x = J_l⁻¹(−θ) x` (`sign` = −1), with `β` from [`jinv_beta`].
#[inline]
fn jinv(theta: DVec3, beta: f64, x: DVec3, sign: f64) -> DVec3 {
    x - 0.5 * sign * theta.cross(x) + beta * theta.cross(theta.cross(x))
}

/// `A = ∂θ/∂(a, b, c)`: the columns `J_l⁻¹(θ) R₀ᵀ E_k` for the deviation
/// `θ` and the axes `R₀ᵀ E_k` of [`rotation_deviation`].
#[inline]
fn jacobian_of(theta: DVec3, beta: f64, axes: &[DVec3; 3]) -> DMat3 {
    DMat3::from_cols(jinv(theta, beta, axes[0], 1.0), jinv(theta, beta, axes[1], 1.0), jinv(theta, beta, axes[2], 1.0))
}

/// `A = ∂θ/∂(a, b, c)` at the spring's three angles.
fn law_jacobian(rs: &RotationSpring, joints: &[SubJoint], angles: [f64; 3]) -> DMat3 {
    let (theta, axes) = deviation_at(rs, joints, angles);
    jacobian_of(theta, jinv_beta(theta.length_squared()), &axes)
}

/// Deviation (rad) above which a rotation spring's tangent includes the
/// geometric part of its law ([`law_geometric_stiffness`]): below it that
/// part is under `|θ|` of the Gauss–Newton part `AᵀKA`, which Newton does
/// not notice.
const LAW_GEOMETRIC_ANGLE: f64 = 1e-2;

/// The geometric part of a rotation spring's tangent,
/// `G_kl = m · ∂A_k/∂q_l` with the law's moment `m = Kθ + τKθ̇` held
/// (symmetric: for the elastic part it is `Σ m_j ∇²θ_j`), by central
/// differences of `A` over the three angles. The full tangent of the
/// generalized forces `Q = Aᵀ m` is `AᵀKA + G`; `AᵀKA` alone (Gauss–Newton)
/// is exact for bending in one plane (`A` constant) and for a law near its
/// rest, and leaves out a term of the order of the moment for a rope bent
/// in space, where Newton then crawled (a helix of 10 mm steel rope laid
/// bent, not stress-free, needed 85–157 sub-steps per frame step).
fn law_geometric_stiffness(rs: &RotationSpring, joints: &[SubJoint], q: &[f64], moment: DVec3) -> DMat3 {
    let f = rs.first;
    let angles = [q[f], q[f + 1], q[f + 2]];
    let mut g = [[0.0; 3]; 3];
    for l in 0..3 {
        let eps = 1e-5 * (1.0 + angles[l].abs());
        let (mut plus, mut minus) = (angles, angles);
        plus[l] += eps;
        minus[l] -= eps;
        let d = (law_jacobian(rs, joints, plus) - law_jacobian(rs, joints, minus)) * (0.5 / eps);
        for (k, row) in g.iter_mut().enumerate() {
            row[l] = moment.dot(d.col(k));
        }
    }
    let g = DMat3::from_cols_array_2d(&g).transpose();
    (g + g.transpose()) * 0.5
}

/// A rotation spring's generalized forces on its three sub-joints,
/// `A = ∂θ/∂(a, b, c)` (the columns `J_l⁻¹ R₀ᵀ E_k`), and, when `geometric`
/// is asked for (the solve's tangent; readouts do not need it), the
/// geometric part of its tangent ([`law_geometric_stiffness`]; zero within
/// [`LAW_GEOMETRIC_ANGLE`] of the rest, and when not asked for).
pub(super) fn rotation_spring_forces(rs: &RotationSpring, joints: &[SubJoint], q: &[f64], v: &[f64], geometric: bool) -> ([f64; 3], DMat3, DMat3) {
    let (theta, axes) = rotation_deviation(rs, joints, q);
    let f = rs.first;
    let omega = axes[0] * v[f] + axes[1] * v[f + 1] + axes[2] * v[f + 2];
    let phi2 = theta.length_squared();
    let beta = jinv_beta(phi2);
    let theta_dot = jinv(theta, beta, omega, 1.0);
    let moment = rs.k * theta + rs.k * theta_dot * rs.tau;
    // Q_k = (Kθ + τKθ̇)ᵀ J⁻¹ E_k = (J⁻ᵀ m)·E_k.
    let m = jinv(theta, beta, moment, -1.0);
    let a = jacobian_of(theta, beta, &axes);
    let g = if geometric && phi2 > LAW_GEOMETRIC_ANGLE * LAW_GEOMETRIC_ANGLE { law_geometric_stiffness(rs, joints, q, moment) } else { DMat3::ZERO };
    ([m.dot(axes[0]), m.dot(axes[1]), m.dot(axes[2])], a, g)
}

/// Tip-to-base state of the articulated-body solve: the shifted
/// articulated inertia `Ĩ` and bias carried to the parent.
#[derive(Default)]
struct AbaCarry {
    inertia: M6,
    bias: V6,
}

impl AbaCarry {
    /// One sub-joint of the backward sweep (see [`Chain::solve_into`]).
    /// `c_g` multiplies the geometric stiffness (`c_q`, or 0 to leave it
    /// out). Answers whether the pivot is negative.
    #[inline]
    fn down(&mut self, s: usize, row: &mut Row, c_v: f64, c_q: f64, c_g: f64, b: f64) -> Result<bool, SystemError> {
        let uv = self.inertia.mul_motion(row.s) - row.gs * c_g;
        let armature = c_v * row.damping + c_q * row.stiffness;
        let d = row.s.dot(uv) + armature;
        // The effective matrix may be indefinite (compression, large c_q);
        // only a vanishing pivot is fatal: |d| ≲ 1e-14 (|S||U| + |armature|).
        if !d.is_finite() || d * d <= 1e-28 * (row.s.dot(row.s) * uv.dot(uv) + armature * armature) {
            return Err(SystemError::Singular { index: s, pivot: d });
        }
        let inv_d = 1.0 / d;
        let u = b - row.s.dot(self.bias);
        row.u_vec = uv;
        row.d = inv_d;
        row.u = u;
        self.inertia.add_outer(uv, uv, -inv_d);
        self.bias += uv * (u * inv_d);
        Ok(d < 0.0)
    }

    /// Adds a link's inertia (and implicit anchor springs).
    #[inline]
    fn add_link(&mut self, ls: &LinkScratch, anchor_blocks: &[(M6, M6)], c_v: f64, c_q: f64) {
        self.inertia.a += ls.ia;
        self.inertia.b += ls.ib;
        self.inertia.c += ls.ib.transpose();
        self.inertia.d += DMat3::from_diagonal(DVec3::splat(ls.m));
        let (ld, ad) = ls.damping;
        if ld != 0.0 || ad != 0.0 {
            // Velocity damping −c_l m v_c, −c_a I_c ω: tangent
            // c_l [[m c×c×ᵀ, m c×], [m c×ᵀ, m]] + c_a [[I_c, 0], [0, 0]].
            let mcc = ls.ib * ls.ib.transpose() * (1.0 / ls.m);
            let ic = ls.ia - mcc;
            self.inertia.a += (mcc * ld + ic * ad) * c_v;
            self.inertia.b += ls.ib * (ld * c_v);
            self.inertia.c += ls.ib.transpose() * (ld * c_v);
            self.inertia.d += DMat3::from_diagonal(DVec3::splat(ls.m * ld * c_v));
        }
        if ls.anchor != u32::MAX {
            let (k, c) = &anchor_blocks[ls.anchor as usize];
            self.inertia.add_scaled(k, c_q);
            self.inertia.add_scaled(c, c_v);
        }
    }

    /// Three coupled revolute sub-joints (a rotation spring) eliminated
    /// together with a 3×3 pivot: `P_kl = S_k·U_l` (k ≤ l, symmetric) plus
    /// the law's Gauss–Newton stiffness `(c_q + c_v τ) Aᵀ K A` and its
    /// geometric part `c_q G` ([`law_geometric_stiffness`]), with
    /// `U_k = Ĩ S_k − c_q G_k S_k` (no mass sits between the three).
    #[allow(clippy::too_many_arguments)]
    fn down_block(
        &mut self,
        s: usize,
        f: &mut [Row],
        rs: &RotationSpring,
        (a_mat, geometric): (&DMat3, &DMat3),
        pinv: &mut DMat3,
        (c_v, c_q, c_g, c_law): (f64, f64, f64, f64),
        b: [f64; 3],
    ) -> Result<bool, SystemError> {
        let u: [V6; 3] = [0, 1, 2].map(|k| self.inertia.mul_vec(f[k].s) - f[k].gs * c_g);
        let mut p = [[0.0; 3]; 3];
        for k in 0..3 {
            for l in k..3 {
                p[k][l] = f[k].s.dot(u[l]);
                p[l][k] = p[k][l];
            }
        }
        let ka = DMat3::from_cols(a_mat.x_axis * rs.k, a_mat.y_axis * rs.k, a_mat.z_axis * rs.k);
        // The law's geometric part (`c_law`: `c_q`, or 0 in static solves)
        // goes with the chain's geometric stiffness (left out, with it, by
        // the definite fallback).
        let h = a_mat.transpose() * ka * (c_q + c_v * rs.tau) + *geometric * c_law;
        let pm = DMat3::from_cols_array_2d(&p) + h;
        let det = pm.determinant();
        let scale = pm.x_axis.length() * pm.y_axis.length() * pm.z_axis.length();
        if !det.is_finite() || det.abs() <= 1e-14 * scale {
            return Err(SystemError::Singular { index: s, pivot: det });
        }
        // Sylvester's criterion: the block pivot is positive definite iff
        // its leading minors are positive.
        let (p11, p12, p22) = (pm.x_axis.x, pm.y_axis.x, pm.y_axis.y);
        let negative = p11 <= 0.0 || p11 * p22 - p12 * p12 <= 0.0 || det <= 0.0;
        *pinv = pm.inverse();
        let ub = DVec3::new(b[0] - f[0].s.dot(self.bias), b[1] - f[1].s.dot(self.bias), b[2] - f[2].s.dot(self.bias));
        let y = *pinv * ub;
        for k in 0..3 {
            f[k].u_vec = u[k];
            f[k].u = ub[k];
            let w = u[0] * pinv.col(k).x + u[1] * pinv.col(k).y + u[2] * pinv.col(k).z;
            self.inertia.add_outer(w, u[k], -1.0);
        }
        self.bias += u[0] * y.x + u[1] * y.y + u[2] * y.z;
        Ok(negative)
    }
}

/// Marker in [`Chain::block`] for the second and third sub-joint of a block.
pub(crate) const BLOCK_INNER: u32 = u32::MAX - 1;

/// The world state of `local_point` on the link at `ps`, and the point
/// relative to `origin`.
pub(super) fn point_state(ps: &Pose, origin: DVec3, local_point: DVec3) -> (PointState, DVec3) {
    let p = ps.pos + ps.rot * local_point;
    (PointState { rotation: ps.rot, point: p + origin, velocity: ps.vel.bot + ps.vel.top.cross(p), angular_velocity: ps.vel.top }, p)
}

/// Evaluates a force element at `local_point` of the link at `ps` (its
/// law held on `held`, if given: [`ForceElement::wrench_on`]) and adds
/// its wrench to the link's load, the moment-arm tangent to the link's load
/// tangent, and its stiffness and damping (moved to the spatial frame) to
/// the link's implicit blocks.
#[allow(clippy::too_many_arguments)]
pub(super) fn apply_force_element(
    ls: &mut LinkScratch,
    blocks: &mut [(M6, M6)],
    ps: &Pose,
    origin: DVec3,
    local_point: DVec3,
    t: f64,
    element: &dyn ForceElement,
    held: Option<FrictionBranch>,
) {
    let (at, p) = point_state(ps, origin, local_point);
    let w = match held {
        Some(branch) => element.wrench_on(t, &at, branch),
        None => element.wrench(t, &at),
    };
    add_point_wrench(ls, blocks, p + w.arm, &w);
}

/// Adds the wrench `w` at the point `p` (relative to the chain's origin)
/// to the link's load, the moment-arm tangent to the link's load tangent,
/// and its stiffness and damping (moved to the spatial frame) to the
/// link's implicit blocks.
fn add_point_wrench(ls: &mut LinkScratch, blocks: &mut [(M6, M6)], p: DVec3, w: &PointWrench) {
    let px = skew(p);
    let (k, c) = &mut blocks[ls.anchor as usize];
    k.add_scaled(&point_to_spatial(&w.stiffness, px), 1.0);
    c.add_scaled(&point_to_spatial(&w.damping, px), 1.0);
    ls.f += V6::new(p.cross(w.force) + w.moment, w.force);
    ls.add_point_load_tangent(w.force, p);
}

/// The rotation vector `θ = log(R)`, accurate to round-off for small angles
/// (`2 atan2(|v|, w)` on the quaternion, not `2 acos(w)`, which loses half
/// the digits near zero).
pub(crate) fn rotation_vector(r: &DMat3) -> DVec3 {
    // 2 sin φ · axis = vee(R − Rᵀ); 2 cos φ = tr R − 1.
    let w = 0.5 * DVec3::new(r.y_axis.z - r.z_axis.y, r.z_axis.x - r.x_axis.z, r.x_axis.y - r.y_axis.x);
    let s2 = w.length_squared();
    let c = 0.5 * (r.x_axis.x + r.y_axis.y + r.z_axis.z - 1.0);
    if c > 0.0 && s2 < 2.5e-3 {
        // φ/sin φ = asin(s)/s = 1 + s²/6 + 3s⁴/40 + 5s⁶/112 + 35s⁸/1152 (s < 0.05: < 2e-14).
        return w * (1.0 + s2 * (1.0 / 6.0 + s2 * (3.0 / 40.0 + s2 * (5.0 / 112.0 + s2 * (35.0 / 1152.0)))));
    }
    let q = DQuat::from_mat3(r);
    let q = if q.w < 0.0 { -q } else { q };
    let v = DVec3::new(q.x, q.y, q.z);
    let s = v.length();
    if s < 1e-300 {
        return v * 2.0;
    }
    v * (2.0 * s.atan2(q.w) / s)
}

/// `(sin x, cos x)`; Taylor polynomials for |x| < 0.03 (truncation below
/// 1e-19, i.e. round-off), the library otherwise. Relative rotations of
/// rope elements are almost always that small.
#[inline]
pub(super) fn small_sin_cos(x: f64) -> (f64, f64) {
    if x.abs() < 0.03 {
        let x2 = x * x;
        let s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)));
        let c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
        (s, c)
    } else {
        x.sin_cos()
    }
}

/// `r · R(axis, angle)` for a unit axis; fast paths for the principal axes.
#[inline]
pub(super) fn rotate_about(r: DMat3, axis: DVec3, angle: f64) -> DMat3 {
    rotate_about_id(r, axis_id(axis), axis, angle)
}

/// Classifies a joint axis for [`rotate_about_id`]: 0, 1, 2 for the unit
/// x, y, z axes, 3 for any other.
#[inline]
pub(super) fn axis_id(axis: DVec3) -> u8 {
    if axis == DVec3::X {
        0
    } else if axis == DVec3::Y {
        1
    } else if axis == DVec3::Z {
        2
    } else {
        3
    }
}

/// [`rotate_about`] with the axis already classified (0, 1, 2 = x, y, z;
/// anything else = the general `axis`).
#[inline]
pub(super) fn rotate_about_id(r: DMat3, id: u8, axis: DVec3, angle: f64) -> DMat3 {
    let (sn, cs) = small_sin_cos(angle);
    match id {
        0 => DMat3::from_cols(r.x_axis, r.y_axis * cs + r.z_axis * sn, r.z_axis * cs - r.y_axis * sn),
        1 => DMat3::from_cols(r.x_axis * cs - r.z_axis * sn, r.y_axis, r.x_axis * sn + r.z_axis * cs),
        2 => DMat3::from_cols(r.x_axis * cs + r.y_axis * sn, r.y_axis * cs - r.x_axis * sn, r.z_axis),
        _ => r * DMat3::from_axis_angle(axis, angle),
    }
}

#[cfg(test)]
pub(crate) fn small_sin_cos_for_tests(x: f64) -> (f64, f64) {
    small_sin_cos(x)
}
