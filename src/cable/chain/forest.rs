//! Several chains solved as one system: a [`Forest`], the chains coupled by
//! pair elements whose two points lie on different chains (a rope of one
//! cable touching a rope of another), and the loop correction that both a
//! single chain's pairs and a forest's use.
//!
//! Each chain keeps its own O(n) sweep: a pair element between two chains
//! puts each point's force on its link (the chain's [`ExternalPoint`]s),
//! exactly as a pair within one chain does, and the pair's stiffness and
//! damping are the same Woodbury correction, each back-substitution run
//! through the chains its column touches. The tangent of the forest is
//! block-diagonal but for that correction, so the cost is the chains' own
//! solves plus O(m n) for m pairs.

use super::sweep::{point_state, PairScratch};
use super::Chain;
use crate::cable::force::{PairElement, PointWrench};
use crate::cable::spatial::V6;
use crate::integrate::{SecondOrderSystem, SystemError};
use glam::{DMat3, DVec3};
use std::sync::Arc;

/// A chain's half of a pair element with another chain, set by a
/// [`Forest`] before each evaluation: the link,
/// the wrench at the current iterate and its point (relative to the
/// chain's origin).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ExternalPoint {
    pub link: usize,
    pub p: DVec3,
    pub wrench: PointWrench,
    /// The element's normal force if it is a contact (N).
    pub contact: Option<f64>,
}

/// A pair element between a point of one chain of a [`Forest`] and a point
/// of another (or of the same chain).
#[derive(Clone)]
pub struct ForestPair {
    /// Index of the first point's chain in the forest.
    pub chain_a: usize,
    /// Sub-joint index whose link carries the first point.
    pub link_a: usize,
    /// The first point in its link's frame, m.
    pub point_a: DVec3,
    /// Index of the second point's chain in the forest.
    pub chain_b: usize,
    /// Sub-joint index whose link carries the second point.
    pub link_b: usize,
    /// The second point in its link's frame, m.
    pub point_b: DVec3,
    /// The law: the force on the first point (the second gets the opposite).
    pub element: Arc<dyn PairElement>,
}

impl std::fmt::Debug for ForestPair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ForestPair").field("a", &(self.chain_a, self.link_a)).field("b", &(self.chain_b, self.link_b)).finish_non_exhaustive()
    }
}

/// A pair's two points for the loop correction: (chain, link, point
/// relative to that chain's origin) each, and the tangents.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LoopPair {
    pub a: (usize, usize, DVec3),
    pub b: (usize, usize, DVec3),
    pub stiffness: DMat3,
    pub damping: DMat3,
    pub normal: Option<DVec3>,
}

impl LoopPair {
    /// A pair within chain `chain`.
    pub fn within(chain: usize, p: &PairScratch) -> Self {
        LoopPair { a: (chain, p.link_a, p.pa), b: (chain, p.link_b, p.pb), stiffness: p.stiffness, damping: p.damping, normal: p.normal }
    }
}

/// The pair elements' part of the tangent, over one or more chains, each
/// with its correction vector `x` (the solve of its own tangent `A`, the
/// chain's elimination still in place). `A` holds everything but the
/// pairs' stiffness and damping (their forces are in the residual, and
/// each force's moment-arm tangent on its link); the exact tangent adds,
/// per pair, `(J_a − J_b)ᵀ K (J_a − J_b)` (`K = c_q K_p + c_v C_p`, `J`
/// the points' Jacobians). With the pair's directions `D` (its normal
/// alone when `K` is a multiple of `n nᵀ`, else the three world axes) and
/// `K = D K_r Dᵀ`, that is `W K_b Wᵀ` with `W`'s column a unit force `+d`
/// at the first point and `−d` at the second, `K_b` block-diagonal. By
/// Woodbury, `x ← x − Z (I + K_b Wᵀ Z)⁻¹ K_b Wᵀ x` with `Z = A⁻¹ W`: one
/// back-substitution per direction and chain it touches, and a dense
/// system of one (or three) unknowns per pair. `I + K_b Wᵀ Z` is `I` plus
/// a product of two positive semidefinite matrices, so its eigenvalues are
/// at least 1 however stiff the pair: no inverse of `K`, and no
/// cancellation (a form that put each point's own stiffness in `A` and
/// subtracted the coupling solved `1 − k² g_a g_b` with `g ≈ 1/k`, and a
/// steel contact between two ropes lost every digit to it).
pub(crate) fn loop_correction(chains: &mut [(&mut Chain, &mut [f64])], pairs: &[LoopPair], c_v: f64, c_q: f64) -> Result<(), SystemError> {
    // (A pair without stiffness or damping, an open contact, adds nothing.)
    let pairs: Vec<&LoopPair> = pairs.iter().filter(|p| p.stiffness * c_q + p.damping * c_v != DMat3::ZERO).collect();
    if pairs.is_empty() {
        return Ok(());
    }
    // Per pair: its directions, `K_r` and its first column.
    let mut blocks: Vec<(Vec<DVec3>, Vec<f64>, usize)> = Vec::with_capacity(pairs.len());
    let mut cols = 0;
    for p in &pairs {
        let kt = p.stiffness * c_q + p.damping * c_v;
        let dirs = match p.normal {
            Some(nrm) => vec![nrm],
            None => vec![DVec3::X, DVec3::Y, DVec3::Z],
        };
        let kr: Vec<f64> = dirs.iter().flat_map(|di| dirs.iter().map(move |dj| di.dot(kt * *dj))).collect();
        let r = dirs.len();
        blocks.push((dirs, kr, cols));
        cols += r;
    }
    // Each column: a unit force `+d` at a pair's first point, `−d` at its
    // second; its two ends (chain, link, point, force).
    let mut columns: Vec<[(usize, usize, DVec3, DVec3); 2]> = Vec::with_capacity(cols);
    for (p, (dirs, _, _)) in pairs.iter().zip(&blocks) {
        columns.extend(dirs.iter().map(|&d| [(p.a.0, p.a.1, p.a.2, d), (p.b.0, p.b.1, p.b.2, -d)]));
    }
    // Per chain, the links the columns name (their motions give Wᵀ y).
    let mut slot: Vec<Vec<u32>> = chains.iter().map(|(c, _)| vec![u32::MAX; c.len()]).collect();
    let mut links: Vec<Vec<usize>> = vec![Vec::new(); chains.len()];
    for &(k, l, _, _) in columns.iter().flatten() {
        if slot[k][l] == u32::MAX {
            slot[k][l] = links[k].len() as u32;
            links[k].push(l);
        }
    }
    // Wᵀ y over every column, for the part of `y` in chain `k` (its link
    // motions `motion`), added to `out`.
    let w_t = |k: usize, motion: &[V6], out: &mut [f64]| {
        for (o, ends) in out.iter_mut().zip(&columns) {
            for &(ck, l, p, f) in ends {
                if ck == k {
                    let m = motion[slot[k][l] as usize];
                    *o += (m.bot + m.top.cross(p)).dot(f);
                }
            }
        }
    };
    // Z's columns, per chain they touch.
    let mut z: Vec<Vec<(usize, Vec<f64>)>> = Vec::with_capacity(cols);
    let mut motion: Vec<Vec<V6>> = links.iter().map(|l| vec![V6::ZERO; l.len()]).collect();
    let mut g = vec![0.0; cols * cols]; // g[r * cols + c] = W_rᵀ z_c
    let mut col_out = vec![0.0; cols];
    for (c, ends) in columns.iter().enumerate() {
        col_out.iter_mut().for_each(|o| *o = 0.0);
        let touched: Vec<usize> = if ends[0].0 == ends[1].0 { vec![ends[0].0] } else { vec![ends[0].0, ends[1].0] };
        let mut zc = Vec::with_capacity(touched.len());
        for k in touched {
            let chain = &mut *chains[k].0;
            let n = chain.len();
            let mut rhs = vec![0.0; n];
            for &(_, link, p, f) in ends.iter().filter(|e| e.0 == k) {
                let wrench = V6::new(p.cross(f), f);
                for s in chain.ancestors(link) {
                    rhs[s] += chain.rows[s].s.dot(wrench);
                }
            }
            let mut zk = vec![0.0; n];
            let (sl, mo) = (&slot[k], &mut motion[k]);
            chain.resolve(&rhs, &mut zk, |s, m| {
                if sl[s] != u32::MAX {
                    mo[sl[s] as usize] = m;
                }
            });
            w_t(k, &motion[k], &mut col_out);
            zc.push((k, zk));
        }
        for r in 0..cols {
            g[r * cols + c] = col_out[r];
        }
        z.push(zc);
    }
    let mut g0 = vec![0.0; cols];
    for (k, (chain, x)) in chains.iter().enumerate() {
        if !links[k].is_empty() {
            chain.link_motions(x, &links[k], &mut motion[k]);
            w_t(k, &motion[k], &mut g0);
        }
    }
    // K_b v, pair by pair.
    let apply_k = |v: &[f64], out: &mut [f64]| {
        for (dirs, kr, first) in &blocks {
            let r = dirs.len();
            for i in 0..r {
                out[first + i] = (0..r).map(|j| kr[i * r + j] * v[first + j]).sum();
            }
        }
    };
    // M = I + K_b G, column by column; right-hand side K_b g0.
    let mut mat = vec![0.0; cols * cols];
    let mut gc = vec![0.0; cols];
    let mut kgc = vec![0.0; cols];
    for c in 0..cols {
        for r in 0..cols {
            gc[r] = g[r * cols + c];
        }
        apply_k(&gc, &mut kgc);
        for r in 0..cols {
            mat[r * cols + c] = kgc[r] + if r == c { 1.0 } else { 0.0 };
        }
    }
    let mut rhs = vec![0.0; cols];
    apply_k(&g0, &mut rhs);
    let mut y = vec![0.0; cols];
    crate::integrate::gauss_solve(cols, &mut mat, &rhs, &mut y)?;
    for (&yc, zc) in y.iter().zip(&z) {
        if yc != 0.0 {
            for (k, zk) in zc {
                let x = &mut *chains[*k].1;
                for (xi, zi) in x.iter_mut().zip(zk) {
                    *xi -= zi * yc;
                }
            }
        }
    }
    Ok(())
}

/// `x` cut into the parts `offsets[k]..offsets[k + 1]`.
fn split_parts<'x>(offsets: &[usize], mut x: &'x mut [f64]) -> Vec<&'x mut [f64]> {
    let mut parts = Vec::with_capacity(offsets.len().saturating_sub(1));
    for w in offsets.windows(2) {
        let (head, tail) = x.split_at_mut(w[1] - w[0]);
        parts.push(head);
        x = tail;
    }
    parts
}

/// Several [`Chain`]s stepped as one [`SecondOrderSystem`], coupled by
/// [`ForestPair`]s: its coordinates are the chains' in order. Each chain
/// keeps its own O(n) sweep; each pair's points get their own tangents on
/// their links, and the coupling between them (between two chains, or
/// within one) is one loop correction over all the pairs of the forest
/// (the chains' own [`Chain::pairs`] too), so a stiff contact between two
/// cables keeps Newton's rate as it does within one.
///
/// While the forest exists, each chain carries its halves of the pairs;
/// they stay on the chain afterwards with the last evaluated wrench (so
/// the chain's own queries and reactions include them) until the next
/// forest is built on it, or [`Chain::clear_external`].
pub struct Forest<'a> {
    pub(crate) chains: Vec<&'a mut Chain>,
    offsets: Vec<usize>,
    pairs: Vec<ForestPair>,
    /// Per pair: its index in each chain's external points.
    slots: Vec<(usize, usize)>,
    /// The cross pairs at the last evaluation.
    loops: Vec<LoopPair>,
}

impl std::fmt::Debug for Forest<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Forest").field("chains", &self.chains.len()).field("pairs", &self.pairs).finish_non_exhaustive()
    }
}

impl<'a> Forest<'a> {
    /// A forest of `chains` coupled by `pairs`. A pair naming a chain or a
    /// link that does not exist is an error (the message names it).
    pub fn new(mut chains: Vec<&'a mut Chain>, pairs: Vec<ForestPair>) -> Result<Self, SystemError> {
        let mut offsets = vec![0];
        for c in &mut chains {
            c.external.clear();
            offsets.push(offsets.last().copied().unwrap_or(0) + c.len());
        }
        let mut slots = Vec::with_capacity(pairs.len());
        for (i, p) in pairs.iter().enumerate() {
            let mut slot = [0; 2];
            for (j, (k, link)) in [(p.chain_a, p.link_a), (p.chain_b, p.link_b)].into_iter().enumerate() {
                let Some(chain) = chains.get_mut(k) else {
                    return Err(SystemError::Model(format!("forest pair {i} names chain {k} of {}", offsets.len() - 1)));
                };
                if link >= chain.len() {
                    return Err(SystemError::Model(format!("forest pair {i} names link {link} of chain {k}, which has {}", chain.len())));
                }
                slot[j] = chain.external.len();
                chain.external.push(ExternalPoint { link, p: DVec3::ZERO, wrench: PointWrench::default(), contact: None });
            }
            slots.push((slot[0], slot[1]));
        }
        Ok(Forest { chains, offsets, pairs, slots, loops: Vec::new() })
    }

    /// Number of chains.
    pub fn len(&self) -> usize {
        self.chains.len()
    }

    /// Whether the forest has no chain.
    pub fn is_empty(&self) -> bool {
        self.chains.is_empty()
    }

    fn range(&self, k: usize) -> std::ops::Range<usize> {
        self.offsets[k]..self.offsets[k + 1]
    }

    /// Kinematics of every chain, the cross pairs' wrenches on their
    /// points, then every chain's loads and tip-to-base sweep (`solve`: with
    /// its elimination).
    fn evaluate(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64], solve: Option<(f64, f64)>) -> Result<(), SystemError> {
        Chain::check_finite(q, v, a)?;
        for k in 0..self.chains.len() {
            let rg = self.range(k);
            self.chains[k].kinematics(t, &q[rg.clone()], &v[rg.clone()], &a[rg])?;
        }
        self.loops.clear();
        for (p, &(sa, sb)) in self.pairs.iter().zip(&self.slots) {
            let (ca, cb) = (&self.chains[p.chain_a], &self.chains[p.chain_b]);
            let (at_a, pa) = point_state(&ca.poses[p.link_a], ca.origin, p.point_a);
            let (at_b, pb) = point_state(&cb.poses[p.link_b], cb.origin, p.point_b);
            let w = p.element.wrench(t, &at_a, &at_b);
            // (The pair's stiffness and damping are the loop correction's.)
            let contact = p.element.contact_force(t, &at_a, &at_b);
            let half = |link, p, force| ExternalPoint { link, p, wrench: PointWrench { force, ..PointWrench::default() }, contact };
            self.chains[p.chain_a].external[sa] = half(p.link_a, pa, w.force);
            self.chains[p.chain_b].external[sb] = half(p.link_b, pb, -w.force);
            self.loops.push(LoopPair {
                a: (p.chain_a, p.link_a, pa),
                b: (p.chain_b, p.link_b, pb),
                stiffness: w.stiffness,
                damping: w.damping,
                normal: w.normal,
            });
        }
        for (chain, rk) in self.chains.iter_mut().zip(split_parts(&self.offsets, r)) {
            chain.sweep_loads(t, rk, solve)?;
        }
        Ok(())
    }

    /// The loop correction over every pair of the forest: the chains' own
    /// and the cross pairs.
    fn correct(&mut self, c_v: f64, c_q: f64, x: &mut [f64]) -> Result<(), SystemError> {
        let mut pairs: Vec<LoopPair> = Vec::new();
        for (k, c) in self.chains.iter().enumerate() {
            pairs.extend(c.pair_scratch.iter().map(|p| LoopPair::within(k, p)));
        }
        pairs.extend_from_slice(&self.loops);
        let xs = split_parts(&self.offsets, x);
        let mut parts: Vec<(&mut Chain, &mut [f64])> = self.chains.iter_mut().map(|c| &mut **c).zip(xs).collect();
        loop_correction(&mut parts, &pairs, c_v, c_q)
    }
}

impl SecondOrderSystem for Forest<'_> {
    fn dof(&self) -> usize {
        self.offsets.last().copied().unwrap_or(0)
    }
    fn residual(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        self.evaluate(t, q, v, a, r, None)
    }
    fn solve_tangent(&mut self, _t: f64, _q: &[f64], _v: &[f64], _a: &[f64], c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        for ((chain, w), xk) in self.chains.iter_mut().zip(self.offsets.windows(2)).zip(split_parts(&self.offsets, x)) {
            chain.solve_tree(c_v, c_q, &b[w[0]..w[1]], xk)?;
        }
        self.correct(c_v, c_q, x)
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
        self.evaluate(t, q, v, a, rhs, Some((c_v, c_q)))?;
        for ((chain, w), xk) in self.chains.iter_mut().zip(self.offsets.windows(2)).zip(split_parts(&self.offsets, x)) {
            chain.finish_solve(c_v, c_q, &rhs[w[0]..w[1]], xk)?;
        }
        self.correct(c_v, c_q, x)
    }
    fn max_frequency(&self, q: &[f64]) -> Option<f64> {
        let mut top: Option<f64> = None;
        for (k, c) in self.chains.iter().enumerate() {
            top = Some(top.unwrap_or(0.0).max(c.max_frequency(&q[self.range(k)])?));
        }
        top
    }
    fn position_tolerance(&self) -> f64 {
        self.chains.iter().map(|c| c.position_tolerance).fold(f64::INFINITY, f64::min)
    }
    fn linearisation_limits(&self) -> Option<crate::integrate::LinearisationLimits> {
        Some(crate::integrate::LinearisationLimits::ROPE)
    }
    fn freeze_branches(&mut self, start: (&[f64], &[f64]), predicted: (&[f64], &[f64])) {
        for k in 0..self.chains.len() {
            let rg = self.range(k);
            self.chains[k].freeze_branches((&start.0[rg.clone()], &start.1[rg.clone()]), (&predicted.0[rg.clone()], &predicted.1[rg]));
        }
    }
    fn update_branches(&mut self, q: &[f64], v: &[f64]) -> usize {
        (0..self.chains.len())
            .map(|k| {
                let rg = self.range(k);
                self.chains[k].update_branches(&q[rg.clone()], &v[rg])
            })
            .sum()
    }
    fn branch_disagreement(&self, q: &[f64], v: &[f64]) -> f64 {
        (0..self.chains.len()).map(|k| self.chains[k].branch_disagreement(&q[self.range(k)], &v[self.range(k)])).fold(0.0, f64::max)
    }
    fn release_branches(&mut self) {
        self.chains.iter_mut().for_each(|c| c.release_branches());
    }
    fn patient_newton(&self) -> bool {
        !self.pairs.is_empty() || self.chains.iter().any(|c| c.patient_newton())
    }
    fn calm(&self, q: &[f64], v: &[f64]) -> bool {
        // As a chain's, over every chain.
        self.pairs.is_empty() && (0..self.chains.len()).all(|k| self.chains[k].calm_at(&q[self.range(k)], &v[self.range(k)]))
    }
    fn set_definite_tangent(&mut self, on: bool) {
        self.chains.iter_mut().for_each(|c| c.use_definite_tangent(on));
    }
    fn tangent_fell_back(&self) -> bool {
        self.chains.iter().any(|c| c.fell_back())
    }
    fn nonlinear_update(&mut self, q: &[f64], dx: &[f64], scale: f64, out: &mut [f64]) -> bool {
        let mut any = false;
        for ((chain, w), ok) in self.chains.iter_mut().zip(self.offsets.windows(2)).zip(split_parts(&self.offsets, out)) {
            let rg = w[0]..w[1];
            if chain.nonlinear_update(&q[rg.clone()], &dx[rg.clone()], scale, ok) {
                any = true;
            } else {
                for ((o, qi), di) in ok.iter_mut().zip(&q[rg.clone()]).zip(&dx[rg]) {
                    *o = qi + scale * di;
                }
            }
        }
        any
    }
}

impl Chain {
    /// The normal forces (N) of the contacts with other chains that the
    /// last [`Forest`] evaluation put on this chain, with their links.
    pub fn external_contacts(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.external.iter().filter_map(|e| e.contact.map(|f| (e.link, f)))
    }

    /// The contacts with other chains that the last [`Forest`] evaluation
    /// put on this chain: each link, point (relative to the chain's origin,
    /// m) and force on this chain (world, N).
    pub fn external_contact_forces(&self) -> impl Iterator<Item = (usize, DVec3, DVec3)> + '_ {
        self.external.iter().filter(|e| e.contact.is_some()).map(|e| (e.link, e.p, e.wrench.force))
    }

    /// Drops the halves of pair elements with other chains that the last
    /// [`Forest`] left on this chain.
    pub fn clear_external(&mut self) {
        self.external.clear();
    }
}

/// A free rigid body as a chain of its own, for a step of a [`Forest`] with
/// ropes it touches (a dynamic body another engine owns, its inertia in the
/// ropes' solve for that step): a base at rest at the body's pose at the
/// step's start, three slides along the body's axes and three turns (about
/// z, y, x), the last link carrying its mass. Its coordinates are zero at
/// the start; the slides' and turns' rates are the body's velocity there.
#[derive(Debug, Clone)]
pub struct FreeBody {
    /// The chain (six sub-joints; the body is the last link).
    pub chain: Chain,
    /// Its state.
    pub state: crate::integrate::State,
    /// Centre of mass in the body frame, m.
    pub com: DVec3,
    /// Mass, kg.
    pub mass: f64,
    /// Whether its acceleration has been made consistent with the ropes
    /// it touches ([`Cable::step_with_bodies`](crate::cable::Cable::step_with_bodies)
    /// does so before its first step): [`FreeBody::new`] gives it the
    /// acceleration of its own loads alone, a free fall.
    pub(crate) settled: bool,
}

impl FreeBody {
    /// Sub-joint whose link is the body.
    pub const LINK: usize = 5;

    /// A body of `mass` (kg, > 0) with its centre of mass at `com` and its
    /// inertia `inertia` about it (kg·m²), both in its frame, whose frame
    /// is at `origin` (m) turned by `rotation`, moving with its centre of
    /// mass at `velocity` (m/s) and turning at `angular_velocity` (rad/s),
    /// under `gravity` (m/s²) and the constant `force` (N, at the centre
    /// of mass) and `torque` (N·m), at time `t` (s).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        mass: f64,
        com: DVec3,
        inertia: DMat3,
        origin: DVec3,
        rotation: DMat3,
        velocity: DVec3,
        angular_velocity: DVec3,
        gravity: DVec3,
        force: DVec3,
        torque: DVec3,
        t: f64,
    ) -> Result<Self, SystemError> {
        use super::parts::{BaseMotion, BaseState, JointKind, LinkMass, SubJoint};
        if !(mass > 0.0 && mass.is_finite()) {
            return Err(SystemError::Model(format!("a free body needs a positive mass, not {mass} kg")));
        }
        let joint = |kind, axis| SubJoint::free(kind, axis);
        let mut joints = vec![
            joint(JointKind::Prismatic, DVec3::X),
            joint(JointKind::Prismatic, DVec3::Y),
            joint(JointKind::Prismatic, DVec3::Z),
            joint(JointKind::Revolute, DVec3::Z),
            joint(JointKind::Revolute, DVec3::Y),
            joint(JointKind::Revolute, DVec3::X),
        ];
        joints[Self::LINK].link = Some(LinkMass::new(mass, com, inertia));
        let mut chain = Chain::new(joints, BaseMotion::Fixed(BaseState::fixed(rotation, origin)), gravity, origin);
        if force != DVec3::ZERO || torque != DVec3::ZERO {
            chain.loads_mut().push(super::parts::LinkLoad { link: Self::LINK, force, local_point: com, moment: torque });
        }
        // The frame origin's velocity, in the body's axes; the turns' rates
        // (about z, y, x at zero angles: the angular velocity's components).
        let w = rotation.transpose() * angular_velocity;
        let v0 = rotation.transpose() * (velocity - angular_velocity.cross(rotation * com));
        let v = vec![v0.x, v0.y, v0.z, w.z, w.y, w.x];
        let state = crate::integrate::State::new(&mut chain, t, vec![0.0; 6], v).map_err(|e| SystemError::Model(e.to_string()))?;
        Ok(FreeBody { chain, state, com, mass, settled: false })
    }

    /// Evaluates the chain at its state (the queries read it).
    pub fn refresh(&mut self) {
        let mut r = [0.0; 6];
        let s = &self.state;
        let _ = self.chain.residual_into(s.t, &s.q, &s.v, &s.a, &mut r);
    }

    /// The body's frame origin (m) and orientation now.
    pub fn pose(&self) -> (DVec3, DMat3) {
        let rot = self.chain.link_rotation(Self::LINK).unwrap_or(DMat3::IDENTITY);
        (self.chain.link_point(Self::LINK, DVec3::ZERO).unwrap_or(DVec3::ZERO), rot)
    }

    /// Its centre of mass's velocity (m/s) and its angular velocity
    /// (rad/s) now.
    pub fn velocity(&self) -> (DVec3, DVec3) {
        let v = self.chain.link_point_velocity(Self::LINK, self.com).unwrap_or(DVec3::ZERO);
        (v, self.chain.link_velocity(Self::LINK).map_or(DVec3::ZERO, |m| m.top))
    }
}
