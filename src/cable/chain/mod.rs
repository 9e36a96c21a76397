//! A serial chain of one-degree-of-freedom sub-joints with rigid links, in
//! relative coordinates, and its O(n) residual and implicit tangent solve.
//!
//! This is the engine under every rope: an element's 6-DOF elastic joint is
//! six ordered sub-joints (bending about local z and y, torsion about the
//! element axis x, then axial and two shear slides), and lumped bodies
//! (trolley, hook, payload) are links of the same chain.
//!
//! * [`Chain::residual_into`] is a recursive Newton–Euler pass: forward
//!   kinematics (1)–(2) of REFERENCE §1, link velocities and accelerations,
//!   then the d'Alembert loads `m(g − a)` swept from tip to base. It also
//!   builds, in the same sweep, the symmetric 6×6 geometric-stiffness
//!   blocks `B_s` with `K_g = Σ J_sᵀ B_s J_s` (DESIGN.md "Stable at the
//!   frame step").
//! * [`Chain::solve_into`] solves `(M + c_v C + c_q (K + K_g)) x = b` with an
//!   articulated-body sweep in which link `s` carries `I_s + c_q B_s` and
//!   joint `s` the armature `c_v c_s + c_q k_s`. No matrix of the chain's
//!   size is ever formed: cost and memory are O(n).
//!
//! All spatial quantities are in the world frame about [`Chain::origin`].

mod forest;
mod nonsmooth;
mod parts;
mod sweep;

pub(crate) use forest::ExternalPoint;
pub use forest::{Forest, ForestPair, FreeBody};

pub use nonsmooth::StaticError;
pub use parts::*;
pub(crate) use sweep::*;

use super::force::{AttachedForce, AttachedPair, ForceElement, FrictionBranch, PairWrench, PointState, PointWrench};
use super::spatial::{M6, V6};
use crate::integrate::{EnergyBalance, SystemError};
use glam::{DMat3, DVec3};

/// Why a query on a link a rope layout names cannot fail: the layout was
/// built with its chain (crate-internal `expect` message).
pub(crate) const IN_CHAIN: &str = "a rope layout's links are links of its chain";

/// The exact inputs of the link-slot layout: sub-joint count, the links of
/// the loads then the anchors (in order), the rotation springs' first
/// sub-joints.
#[derive(Debug, Clone, Default)]
struct SlotKey {
    built: bool,
    n: usize,
    links: Vec<usize>,
    springs: Vec<usize>,
    limbs: Vec<Limb>,
}

/// A chain change or description that does not fit together: an index past
/// the chain's end, or a topology change that would cut through something
/// (a load, an anchor, a rotation spring, a limb).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ChainError {
    /// `what` refers to sub-joint `index`, which the chain does not have.
    #[error("{what} refers to sub-joint {index}, but the chain has {len} sub-joints")]
    Index {
        /// What holds the index (e.g. "load 2", "anchor 0").
        what: String,
        /// The sub-joint index it names.
        index: usize,
        /// Number of sub-joints of the chain.
        len: usize,
    },
    /// A topology change was refused; the reason names what it would cut.
    #[error("{0}")]
    Topology(String),
}

impl From<ChainError> for SystemError {
    fn from(e: ChainError) -> Self {
        SystemError::Model(e.to_string())
    }
}

/// A serial chain of one-DOF sub-joints (see the module docs).
///
/// The description (sub-joints, loads, anchors, force elements, rotation
/// springs, joint forces) is reached through accessors: their number only
/// changes through the chain ([`Chain::insert_joints`],
/// [`Chain::remove_joints`], [`Chain::add_limb`]), which keeps every
/// per-sub-joint array and every index in step; their contents may be
/// edited, and every index in them is checked at the next evaluation (an
/// error, never a panic). The per-step workspace is private.
#[derive(Clone)]
pub struct Chain {
    /// The sub-joints from base to tip.
    joints: Vec<SubJoint>,
    /// Base motion.
    pub base: BaseMotion,
    /// Gravity, m/s².
    pub gravity: DVec3,
    /// Reference point: internal positions are relative to it (keeps the
    /// spatial inertias well scaled far from the world origin), m.
    pub origin: DVec3,
    /// Anchor springs (implicit force elements).
    anchors: Vec<AnchorSpring>,
    /// Other implicit force elements (user laws, contact, drag).
    forces: Vec<AttachedForce>,
    /// Force elements between two points of the chain (self-contact, a
    /// rope on another rope of the tree).
    pairs: Vec<AttachedPair>,
    /// Per pair at the last residual: the points (relative to `origin`)
    /// and the tangents, for the solve's loop correction.
    pub(crate) pair_scratch: Vec<PairScratch>,
    /// Point wrenches a [`Forest`] sets on this chain's links for one
    /// evaluation (the chain's half of a pair element with another chain);
    /// transient: cleared by a topology change, and by whoever set them.
    pub(crate) external: Vec<ExternalPoint>,
    /// Tests only: `false` leaves the pair correction out of the solve.
    #[cfg(test)]
    pub(crate) pair_coupling: bool,
    /// External loads of fixed direction (explicit in value, their geometric
    /// stiffness implicit).
    loads: Vec<LinkLoad>,
    /// Generalized forces on the sub-joints (drives), N or N·m.
    joint_forces: Vec<f64>,
    /// Objective bending–torsion laws replacing the per-angle springs of
    /// their sub-joints.
    rotation_springs: Vec<RotationSpring>,
    /// Limbs (tree branches), sorted by their first sub-joint; empty for a
    /// serial chain (see [`Limb`], [`Chain::add_limb`]).
    limbs: Vec<Limb>,
    /// Per sub-joint (only when there are limbs): index into the limb
    /// scratch arrays if limbs hang from this link, else `u32::MAX`.
    limb_parent: Vec<u32>,
    /// Per parent link: the sweep carry of its limbs, and the forward
    /// passes' acceleration there.
    limb_carry: Vec<LimbCarry>,
    limb_acc: Vec<V6>,
    /// Per sub-joint (only when there are limbs): `true` where a limb starts.
    limb_start: Vec<bool>,
    /// Per sub-joint, what a pass needs to know of its constant geometry
    /// ([`SubJoint::code`]): built with the layout.
    joint_code: Vec<u8>,
    /// Per sub-joint: index of the rotation spring whose block starts here,
    /// [`BLOCK_INNER`] inside a block, `u32::MAX` for a single sub-joint.
    pub(crate) block: Vec<u32>,
    /// Per rotation spring: `A = ∂θ/∂(a, b, c)`, the block pivot inverse,
    /// and the geometric part of the law's tangent.
    pub(crate) rot_scratch: Vec<(DMat3, DMat3, DMat3)>,
    /// Rotation springs in the order of their last sub-joint (the
    /// kinematics pass evaluates each one there).
    spring_order: Vec<u32>,
    /// For each sub-joint, the index of its link's scratch in `links`
    /// (links with mass, loads or anchors), or `u32::MAX`.
    pub(crate) link_slot: Vec<u32>,
    pub(crate) links: Vec<LinkScratch>,
    /// Implicit stiffness and damping blocks of the anchor springs, one
    /// entry per anchored link.
    pub(crate) anchor_blocks: Vec<(M6, M6)>,
    /// What `link_slot`, `links`, `block` and `spring_order` were built for.
    slot_key: SlotKey,
    /// Newton tolerance on the coordinate corrections, m or rad (default
    /// 1e-9: a thousandth of a 2 cm steel element's stretch under load).
    /// 1e-8 saves 7 % of the Newton iterations on a 1 000-element swing
    /// (docs/performance.md) but lets the energy of an undamped rope drift
    /// more at small steps (`verify_energy`).
    pub position_tolerance: f64,
    /// Upper estimate of the highest natural frequency, rad/s (for explicit
    /// schemes' sub-steps); `None` if unknown.
    pub max_frequency: Option<f64>,
    pub(crate) poses: Vec<Pose>,
    pub(crate) rows: Vec<Row>,
    /// Base pose at the last kinematics pass (position relative to `origin`).
    base_pose: (DMat3, DVec3),
    /// Composite load on the whole chain at the last residual (spatial
    /// force about `origin`).
    base_load: V6,
    /// Per sub-joint: the frozen branch of a non-smooth law while
    /// `frozen` (see [`SecondOrderSystem::freeze_branches`]).
    branch: Vec<LawBranch>,
    frozen: bool,
    /// Per force element: the branch its law is held on while
    /// `forces_frozen` (`None`: a smooth law, or a contact not engaged at
    /// the solve's first iterate); read at the first evaluation after
    /// [`SecondOrderSystem::freeze_branches`] (empty until then).
    force_branch: Vec<Option<FrictionBranch>>,
    forces_frozen: bool,
    /// Per force element: the direction it slipped along at the last
    /// evaluation while free (zero if it did not), in this solve.
    slip_direction: Vec<DVec3>,
    /// The time of the last evaluation, s (the force elements' branches
    /// are checked against it).
    last_t: f64,
    /// Sub-joints with a non-smooth law (rebuilt with the layout).
    nonsmooth: Vec<u32>,
    /// The last elimination met a negative pivot: the tangent with the
    /// geometric stiffness of that iterate was indefinite (see
    /// [`Chain::solve_into`]).
    indefinite: bool,
    /// An indefinite tangent is solved again without the geometric
    /// stiffness ([`SecondOrderSystem::set_definite_tangent`](crate::integrate::SecondOrderSystem::set_definite_tangent)).
    pub(super) definite_tangent: bool,
    /// The elimination leaves the geometric stiffness out (set only while
    /// an indefinite tangent is solved again).
    without_geometric: bool,
    /// The last correction (fused pass or [`Chain::solve_into`]) was
    /// solved without the geometric stiffness: it is not a Newton step.
    fell_back: bool,
    /// Set during a static solve: rotation-spring blocks then carry only
    /// their law's Gauss–Newton part (positive semi-definite: the static
    /// solve minimises the energy).
    pub(crate) law_gauss_newton: bool,
    /// Zero accelerations for [`Chain::energy_balance_at`]'s kinematics.
    energy_zeros: Vec<f64>,
    /// Residual scratch for [`Chain::energy_balance_at`] when its supports
    /// move.
    energy_residual: Vec<f64>,
}

impl std::fmt::Debug for Chain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Chain").field("joints", &self.joints.len()).field("base", &self.base).finish()
    }
}

impl Chain {
    /// A chain with the given sub-joints and base.
    pub fn new(joints: Vec<SubJoint>, base: BaseMotion, gravity: DVec3, origin: DVec3) -> Self {
        let n = joints.len();
        Chain {
            joints,
            base,
            gravity,
            origin,
            anchors: Vec::new(),
            forces: Vec::new(),
            pairs: Vec::new(),
            pair_scratch: Vec::new(),
            external: Vec::new(),
            #[cfg(test)]
            pair_coupling: true,
            loads: Vec::new(),
            joint_forces: vec![0.0; n],
            rotation_springs: Vec::new(),
            limbs: Vec::new(),
            limb_parent: Vec::new(),
            limb_carry: Vec::new(),
            limb_acc: Vec::new(),
            limb_start: Vec::new(),
            joint_code: Vec::new(),
            block: vec![u32::MAX; n],
            rot_scratch: Vec::new(),
            spring_order: Vec::new(),
            link_slot: vec![u32::MAX; n],
            links: Vec::new(),
            anchor_blocks: Vec::new(),
            slot_key: SlotKey::default(),
            max_frequency: None,
            position_tolerance: 1e-9,
            poses: vec![Pose::default(); n],
            rows: vec![Row::default(); n],
            base_pose: (DMat3::IDENTITY, DVec3::ZERO),
            base_load: V6::ZERO,
            branch: Vec::new(),
            frozen: false,
            force_branch: Vec::new(),
            forces_frozen: false,
            slip_direction: Vec::new(),
            last_t: 0.0,
            nonsmooth: Vec::new(),
            indefinite: false,
            definite_tangent: false,
            without_geometric: false,
            fell_back: false,
            law_gauss_newton: false,
            energy_zeros: Vec::new(),
            energy_residual: Vec::new(),
        }
    }

    /// The links that carry loads, anchors or force elements, in that order.
    fn loaded_links(&self) -> impl Iterator<Item = usize> + '_ {
        self.loads
            .iter()
            .map(|l| l.link)
            .chain(self.anchors.iter().map(|a| a.link))
            .chain(self.forces.iter().map(|f| f.link))
            .chain(self.pairs.iter().flat_map(|p| [p.link_a, p.link_b]))
            .chain(self.external.iter().map(|e| e.link))
    }

    /// Assigns link scratch slots to links with mass, loads, anchors or
    /// force elements (called by every residual evaluation; allocation-free
    /// once sized).
    pub(crate) fn assign_slots(&mut self) -> Result<(), ChainError> {
        let n = self.joints.len();
        // The layout only changes with the links that carry loads or
        // anchors and with the rotation springs: skip the rebuild when they
        // are exactly those of the last build (an exact key: a hash of the
        // indices collided, e.g. loads on links {0, 40} and {1, 9}).
        let key = &self.slot_key;
        let same = key.built
            && key.n == n
            && self.poses.len() == n
            && key.links.len() == self.loads.len() + self.anchors.len() + self.forces.len() + 2 * self.pairs.len() + self.external.len()
            && key.springs.len() == self.rotation_springs.len()
            && key.links.iter().copied().eq(self.loaded_links())
            && key.springs.iter().copied().eq(self.rotation_springs.iter().map(|r| r.first))
            && key.limbs == self.limbs;
        if same {
            return Ok(());
        }
        self.check_indices()?;
        self.slot_key.built = true;
        self.slot_key.n = n;
        let links: Vec<usize> = self.loaded_links().collect();
        self.slot_key.links = links;
        self.slot_key.springs.clear();
        self.slot_key.springs.extend(self.rotation_springs.iter().map(|r| r.first));
        self.slot_key.limbs.clone_from(&self.limbs);
        self.joint_code.clear();
        self.joint_code.extend(self.joints.iter().map(SubJoint::code));
        self.limb_parent.clear();
        self.limb_start.clear();
        let mut parents = 0u32;
        if !self.limbs.is_empty() {
            self.limb_parent.resize(n, u32::MAX);
            self.limb_start.resize(n, false);
            for l in &self.limbs {
                self.limb_start[l.first] = true;
                if let Some(p) = l.parent {
                    if self.limb_parent[p] == u32::MAX {
                        self.limb_parent[p] = parents;
                        parents += 1;
                    }
                }
            }
        }
        self.limb_carry.clear();
        self.limb_carry.resize(parents as usize, LimbCarry::default());
        self.limb_acc.clear();
        self.limb_acc.resize(parents as usize, V6::ZERO);
        self.nonsmooth.clear();
        self.nonsmooth.extend((0..n as u32).filter(|&s| self.joints[s as usize].law != SpringLaw::Linear));
        self.poses.resize(n, Pose::default());
        self.rows.resize(n, Row::default());
        self.link_slot.clear();
        self.link_slot.resize(n, u32::MAX);
        let mut count = 0u32;
        for s in 0..n {
            let used = self.joints[s].link.is_some();
            self.link_slot[s] = if used {
                count += 1;
                count - 1
            } else {
                u32::MAX
            };
        }
        for k in 0..self.slot_key.links.len() {
            let s = self.slot_key.links[k];
            if s < n && self.link_slot[s] == u32::MAX {
                self.link_slot[s] = count;
                count += 1;
            }
        }
        self.links.clear();
        self.links.resize(count as usize, LinkScratch::default());
        self.anchor_blocks.clear();
        let pair_links: Vec<usize> = self.pairs.iter().flat_map(|p| [p.link_a, p.link_b]).chain(self.external.iter().map(|e| e.link)).collect();
        for link in self.anchors.iter().map(|a| a.link).chain(self.forces.iter().map(|f| f.link)).chain(pair_links) {
            let ls = &mut self.links[self.link_slot[link] as usize];
            if ls.anchor == u32::MAX {
                ls.anchor = self.anchor_blocks.len() as u32;
                self.anchor_blocks.push((M6::ZERO, M6::ZERO));
            }
        }
        // Rotation-spring blocks: three revolute sub-joints solved together
        // (their elastic law couples them), when no mass or load sits on the
        // two links between them.
        self.block.clear();
        self.block.resize(n, u32::MAX);
        self.rot_scratch.resize(self.rotation_springs.len(), (DMat3::ZERO, DMat3::ZERO, DMat3::ZERO));
        for (k, rs) in self.rotation_springs.iter().enumerate() {
            let f = rs.first;
            // A block never straddles a limb start or a limb's parent link.
            let tree_free =
                || self.limbs.is_empty() || (!self.limb_start[f + 1] && !self.limb_start[f + 2] && self.limb_parent[f..f + 3].iter().all(|x| *x == u32::MAX));
            if f + 2 < n && self.link_slot[f] == u32::MAX && self.link_slot[f + 1] == u32::MAX && tree_free() {
                self.block[f] = k as u32;
                self.block[f + 1] = BLOCK_INNER;
                self.block[f + 2] = BLOCK_INNER;
            }
        }
        self.spring_order.clear();
        self.spring_order.extend((0..self.rotation_springs.len() as u32).filter(|&k| self.rotation_springs[k as usize].first + 2 < n));
        self.spring_order.sort_by_key(|&k| self.rotation_springs[k as usize].first);
        Ok(())
    }

    /// Every sub-joint index in the description names a sub-joint of the
    /// chain (a rotation spring its three).
    fn check_indices(&self) -> Result<(), ChainError> {
        let len = self.joints.len();
        let bad = |what: String, index: usize| Err(ChainError::Index { what, index, len });
        for (k, l) in self.loads.iter().enumerate() {
            if l.link >= len {
                return bad(format!("load {k}"), l.link);
            }
        }
        for (k, a) in self.anchors.iter().enumerate() {
            if a.link >= len {
                return bad(format!("anchor spring {k}"), a.link);
            }
        }
        for (k, f) in self.forces.iter().enumerate() {
            if f.link >= len {
                return bad(format!("force element {k}"), f.link);
            }
        }
        for (k, p) in self.pairs.iter().enumerate() {
            if p.link_a >= len || p.link_b >= len {
                return bad(format!("pair element {k}"), p.link_a.max(p.link_b));
            }
        }
        for (k, e) in self.external.iter().enumerate() {
            if e.link >= len {
                return bad(format!("pair element {k} with another chain"), e.link);
            }
        }
        for (k, r) in self.rotation_springs.iter().enumerate() {
            if r.first + 2 >= len {
                return bad(format!("rotation spring {k} (sub-joints {}..={})", r.first, r.first + 2), r.first + 2);
            }
        }
        Ok(())
    }

    /// Forces the per-link layout (link slots, rotation-spring blocks, the
    /// list of non-smooth laws) to be rebuilt at the next evaluation. Loads,
    /// anchors, springs and the number of sub-joints are checked every time;
    /// call this after changing a [`SubJoint::law`] or a link's mass
    /// presence on a built chain.
    pub fn invalidate_layout(&mut self) {
        self.slot_key.built = false;
    }

    /// Number of sub-joints (= generalized coordinates).
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// Whether the chain has no sub-joints.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// The sub-joints from base to tip.
    pub fn joints(&self) -> &[SubJoint] {
        &self.joints
    }

    /// Sub-joint `s`, if the chain has it.
    pub fn joint(&self, s: usize) -> Option<&SubJoint> {
        self.joints.get(s)
    }

    /// Sub-joint `s` to edit, if the chain has it. The layout (link slots,
    /// rotation-spring blocks, the list of non-smooth laws) is rebuilt at
    /// the next evaluation, so a changed law or link mass takes effect.
    pub fn joint_mut(&mut self, s: usize) -> Option<&mut SubJoint> {
        self.slot_key.built = false;
        self.joints.get_mut(s)
    }

    /// Sub-joint `s` to edit without rebuilding the layout: for the
    /// per-step drives and damping the coupling sets, which change neither a
    /// law nor whether a link has mass, nor the joint's axis, offset or
    /// pre-rotation (the layout keeps a code of those:
    /// [`Chain::set_pre_rotation_same_layout`] changes the last).
    #[cfg_attr(not(feature = "rapier"), allow(dead_code))] // the coupling's drives
    pub(crate) fn joint_mut_same_layout(&mut self, s: usize) -> Option<&mut SubJoint> {
        self.joints.get_mut(s)
    }

    /// Sets sub-joint `s`'s pre-rotation without rebuilding the layout (a
    /// rope's Euler angles recharted), keeping the layout's code of it.
    pub(crate) fn set_pre_rotation_same_layout(&mut self, s: usize, rotation: DMat3) {
        if let Some(j) = self.joints.get_mut(s) {
            j.pre_rotation = rotation;
            let code = j.code();
            if let Some(c) = self.joint_code.get_mut(s) {
                *c = code;
            }
        }
    }

    /// The generalized forces (drives) on the sub-joints, one per
    /// sub-joint, N or N·m.
    pub fn joint_forces(&self) -> &[f64] {
        &self.joint_forces
    }

    /// The generalized force on sub-joint `s` (N or N·m), if the chain has it.
    pub fn joint_force(&self, s: usize) -> Option<f64> {
        self.joint_forces.get(s).copied()
    }

    /// Sets the generalized force (drive) on sub-joint `s`, N or N·m.
    pub fn set_joint_force(&mut self, s: usize, force: f64) -> Result<(), ChainError> {
        let len = self.joints.len();
        let f = self.joint_forces.get_mut(s).ok_or(ChainError::Index { what: "joint force".into(), index: s, len })?;
        *f = force;
        Ok(())
    }

    /// External loads of fixed direction (explicit in value, their geometric
    /// stiffness implicit).
    pub fn loads(&self) -> &[LinkLoad] {
        &self.loads
    }

    /// The loads, to add, edit or remove; their links are checked at the
    /// next evaluation ([`ChainError::Index`]).
    pub fn loads_mut(&mut self) -> &mut Vec<LinkLoad> {
        &mut self.loads
    }

    /// Anchor springs (implicit force elements) holding links to the world.
    pub fn anchors(&self) -> &[AnchorSpring] {
        &self.anchors
    }

    /// The anchor springs, to add, edit or remove; links checked at the next
    /// evaluation.
    pub fn anchors_mut(&mut self) -> &mut Vec<AnchorSpring> {
        &mut self.anchors
    }

    /// Other implicit force elements (user laws, contact, drag).
    pub fn forces(&self) -> &[AttachedForce] {
        &self.forces
    }

    /// The force elements, to add, edit or remove; links checked at the next
    /// evaluation.
    pub fn forces_mut(&mut self) -> &mut Vec<AttachedForce> {
        &mut self.forces
    }

    /// Force elements between two points of the chain ([`PairElement`](super::force::PairElement)):
    /// each closes a loop in the chain's tree, and the solve adds its
    /// stiffness and damping exactly: after the O(n) sweep (which has
    /// each pair's force, not its stiffness), a Woodbury correction over
    /// the pairs (per pair, one O(n) back-substitution and one unknown of
    /// a dense system when its law acts along one direction,
    /// [`PairWrench::normal`], else three), so Newton keeps its rate
    /// however stiff the pair is; the cost is O(m n) per Newton iteration
    /// for m pairs (docs/architecture.md, "Contact"; docs/performance.md).
    pub fn pairs(&self) -> &[AttachedPair] {
        &self.pairs
    }

    /// The pair elements, to add, edit or remove; links checked at the next
    /// evaluation.
    pub fn pairs_mut(&mut self) -> &mut Vec<AttachedPair> {
        &mut self.pairs
    }

    /// The world states of each pair element's two points ([`Chain::pairs`],
    /// in order) and the force the element applies at time `t` (s), at the
    /// last kinematics pass's poses.
    pub fn pair_wrenches(&self, t: f64) -> Vec<(PointState, PointState, PairWrench)> {
        self.pairs.iter().zip(self.pair_points()).map(|(p, (a, b))| (a, b, p.element.wrench(t, &a, &b))).collect()
    }

    /// The world states of each pair element's two points ([`Chain::pairs`],
    /// in order) at the last kinematics pass's poses.
    pub fn pair_points(&self) -> impl Iterator<Item = (PointState, PointState)> + '_ {
        let at = |link: usize, local: DVec3| point_state(&self.poses[link], self.origin, local).0;
        self.pairs.iter().map(move |p| (at(p.link_a, p.point_a), at(p.link_b, p.point_b)))
    }

    /// Objective bending–torsion laws replacing the per-angle springs of
    /// their three sub-joints.
    pub fn rotation_springs(&self) -> &[RotationSpring] {
        &self.rotation_springs
    }

    /// The rotation springs, to add, edit or remove (keep them sorted by
    /// their first sub-joint); checked at the next evaluation.
    pub fn rotation_springs_mut(&mut self) -> &mut Vec<RotationSpring> {
        &mut self.rotation_springs
    }

    /// Refreshes every [`BaseMotion::Sampled`] fed by `motion.source` (the
    /// base, anchor targets) with `motion`; returns how many it replaced.
    pub fn set_sampled(&mut self, motion: SampledMotion) -> usize {
        let mut n = 0;
        let targets = std::iter::once(&mut self.base).chain(self.anchors.iter_mut().map(|a| &mut a.target));
        for m in targets {
            if let BaseMotion::Sampled(s) = m {
                if s.source == motion.source {
                    *s = motion;
                    n += 1;
                }
            }
        }
        n
    }

    /// Inserts `joints` before sub-joint `at` (`at == len()`: after the
    /// last). Everything that names a sub-joint at or after `at` (loads,
    /// anchors, force elements, rotation springs, limbs and their parents,
    /// joint forces) moves with it; the new sub-joints get no joint force
    /// and belong to the limb of sub-joint `at` (of the last sub-joint when
    /// appending). The caller inserts the matching coordinates into the
    /// state ([`crate::integrate::State::insert`]).
    ///
    /// Refused (nothing changes): `at` past the end, or a position inside
    /// a rotation spring's three sub-joints.
    pub fn insert_joints(&mut self, at: usize, joints: Vec<SubJoint>) -> Result<(), ChainError> {
        let len = self.joints.len();
        if at > len {
            return Err(ChainError::Index { what: "insertion point".into(), index: at, len });
        }
        if let Some((k, r)) = self.rotation_springs.iter().enumerate().find(|(_, r)| r.first < at && at <= r.first + 2) {
            return Err(ChainError::Topology(format!(
                "cannot insert before sub-joint {at}: it is inside rotation spring {k} (sub-joints {}..={})",
                r.first,
                r.first + 2
            )));
        }
        let k = joints.len();
        if k == 0 {
            return Ok(());
        }
        let shift = |i: &mut usize| {
            if *i >= at {
                *i += k;
            }
        };
        self.loads.iter_mut().for_each(|l| shift(&mut l.link));
        self.anchors.iter_mut().for_each(|a| shift(&mut a.link));
        self.forces.iter_mut().for_each(|f| shift(&mut f.link));
        self.pairs.iter_mut().for_each(|p| {
            shift(&mut p.link_a);
            shift(&mut p.link_b);
        });
        self.rotation_springs.iter_mut().for_each(|r| shift(&mut r.first));
        for l in &mut self.limbs {
            // A limb starting at `at` keeps the new sub-joints as its start.
            if l.first > at {
                l.first += k;
            }
            if let Some(p) = l.parent.as_mut() {
                shift(p);
            }
        }
        self.joints.splice(at..at, joints);
        self.joint_forces.splice(at..at, std::iter::repeat_n(0.0, k));
        self.branch.clear();
        self.external.clear();
        self.slot_key.built = false;
        Ok(())
    }

    /// Removes the sub-joints `range` and returns them. Everything that
    /// names a later sub-joint moves with it; the caller removes the
    /// matching coordinates from the state ([`crate::integrate::State::remove`]).
    ///
    /// Refused (nothing changes): a range past the end, or one that holds a
    /// load, an anchor, a force element, part of a rotation spring, a
    /// limb's start or a link a limb hangs from (remove or move those
    /// first).
    pub fn remove_joints(&mut self, range: std::ops::Range<usize>) -> Result<Vec<SubJoint>, ChainError> {
        let len = self.joints.len();
        if range.start > range.end || range.end > len {
            return Err(ChainError::Index { what: format!("removal range {}..{}", range.start, range.end), index: range.end, len });
        }
        let inside = |i: usize| range.contains(&i);
        let refuse = |what: String| Err(ChainError::Topology(format!("cannot remove sub-joints {}..{}: {what}", range.start, range.end)));
        if let Some(k) = self.loads.iter().position(|l| inside(l.link)) {
            return refuse(format!("load {k} is on link {}", self.loads[k].link));
        }
        if let Some(k) = self.anchors.iter().position(|a| inside(a.link)) {
            return refuse(format!("anchor spring {k} holds link {}", self.anchors[k].link));
        }
        if let Some(k) = self.forces.iter().position(|f| inside(f.link)) {
            return refuse(format!("force element {k} acts on link {}", self.forces[k].link));
        }
        if let Some(k) = self.pairs.iter().position(|p| inside(p.link_a) || inside(p.link_b)) {
            return refuse(format!("pair element {k} acts on links {} and {}", self.pairs[k].link_a, self.pairs[k].link_b));
        }
        if let Some(k) = self.rotation_springs.iter().position(|r| (r.first..r.first + 3).any(inside)) {
            return refuse(format!("rotation spring {k} uses sub-joints {}..={}", self.rotation_springs[k].first, self.rotation_springs[k].first + 2));
        }
        if let Some(l) = self.limbs.iter().find(|l| inside(l.first) || l.parent.is_some_and(inside)) {
            return refuse(format!("the limb starting at sub-joint {} starts or hangs there", l.first));
        }
        // No limb (nor the serial part before the first limb) may lose all
        // its sub-joints: the limbs after it would lose their place.
        let starts: Vec<usize> = std::iter::once(0).chain(self.limbs.iter().map(|l| l.first)).collect();
        for (i, &a) in starts.iter().enumerate() {
            let b = starts.get(i + 1).copied().unwrap_or(len);
            if a < b && range.start <= a && b <= range.end && !(a == 0 && b == len) {
                return refuse(format!("the branch of sub-joints {a}..{b} would be empty"));
            }
        }
        let k = range.len();
        let shift = |i: &mut usize| {
            if *i >= range.end {
                *i -= k;
            }
        };
        self.loads.iter_mut().for_each(|l| shift(&mut l.link));
        self.anchors.iter_mut().for_each(|a| shift(&mut a.link));
        self.forces.iter_mut().for_each(|f| shift(&mut f.link));
        self.pairs.iter_mut().for_each(|p| {
            shift(&mut p.link_a);
            shift(&mut p.link_b);
        });
        self.rotation_springs.iter_mut().for_each(|r| shift(&mut r.first));
        for l in &mut self.limbs {
            shift(&mut l.first);
            if let Some(p) = l.parent.as_mut() {
                shift(p);
            }
        }
        self.joint_forces.drain(range.clone());
        self.branch.clear();
        self.external.clear();
        self.slot_key.built = false;
        Ok(self.joints.drain(range).collect())
    }
}

impl Chain {
    /// The pose (orientation, origin relative to [`Chain::origin`]) of the
    /// link sub-joint `s` hangs from, at the last kinematics pass.
    fn parent_pose(&self, s: usize) -> (DMat3, DVec3) {
        match self.parent_of(s) {
            None => self.base_pose,
            Some(p) => (self.poses[p].rot, self.poses[p].pos),
        }
    }

    /// The link sub-joint `s` hangs from (`None`: the base).
    pub fn parent_of(&self, s: usize) -> Option<usize> {
        match self.limbs.binary_search_by_key(&s, |l| l.first) {
            Ok(k) => self.limbs[k].parent,
            Err(_) => s.checked_sub(1),
        }
    }

    #[cfg(test)]
    pub(crate) fn clear_limbs(&mut self) {
        self.limbs.clear();
        self.slot_key.built = false;
    }

    /// The limbs of a tree-shaped chain (empty for a serial chain).
    pub fn limbs(&self) -> &[Limb] {
        &self.limbs
    }

    /// Appends `joints` as a new limb hanging from link `parent` (`None`:
    /// the base); returns the index of its first sub-joint. Anchors, loads
    /// and rotation springs of the limb are added by the caller with their
    /// sub-joint indices shifted by that index.
    pub fn add_limb(&mut self, joints: Vec<SubJoint>, parent: Option<usize>) -> Result<usize, String> {
        let first = self.joints.len();
        if joints.is_empty() {
            return Err("a limb needs at least one sub-joint".into());
        }
        if let Some(p) = parent {
            if p >= first {
                return Err(format!("limb parent link {p} is not in the chain ({first} sub-joints)"));
            }
        }
        if first == 0 && parent.is_some() {
            return Err("the first sub-joints of a chain hang from its base".into());
        }
        let n = joints.len();
        self.joints.extend(joints);
        self.joint_forces.resize(first + n, 0.0);
        if first > 0 {
            self.limbs.push(Limb { first, parent });
        }
        self.slot_key.built = false;
        Ok(first)
    }

    /// World position of a point given in the frame of link `s` (after the
    /// last kinematics evaluation), m; `None` if the chain has no link `s`.
    pub fn link_point(&self, s: usize, local: DVec3) -> Option<DVec3> {
        let p = self.poses.get(s)?;
        Some(p.pos + p.rot * local + self.origin)
    }

    /// World velocity of a point given in the frame of link `s`, m/s;
    /// `None` if the chain has no link `s`.
    pub fn link_point_velocity(&self, s: usize, local: DVec3) -> Option<DVec3> {
        let ps = self.poses.get(s)?;
        let p = ps.pos + ps.rot * local;
        Some(ps.vel.bot + ps.vel.top.cross(p))
    }

    /// Orientation of link `s` (after the last kinematics evaluation);
    /// `None` if the chain has no link `s`.
    pub fn link_rotation(&self, s: usize) -> Option<DMat3> {
        self.poses.get(s).map(|p| p.rot)
    }

    /// Spatial velocity of link `s` (about the chain origin); `None` if the
    /// chain has no link `s`.
    pub fn link_velocity(&self, s: usize) -> Option<V6> {
        self.poses.get(s).map(|p| p.vel)
    }

    /// Joint point of sub-joint `s` in the world, m; `None` if the chain
    /// has no sub-joint `s`.
    pub fn joint_point(&self, s: usize) -> Option<DVec3> {
        let offset = self.joints.get(s)?.offset;
        self.poses.get(s)?;
        let (rot, pos) = self.parent_pose(s);
        Some(pos + rot * offset + self.origin)
    }

    /// World velocity of sub-joint `s`'s joint point, m/s; `None` if the
    /// chain has no sub-joint `s`.
    pub fn joint_point_velocity(&self, s: usize) -> Option<DVec3> {
        let p = self.joint_point(s)? - self.origin;
        let vel = self.poses[s].vel;
        Some(vel.bot + vel.top.cross(p))
    }

    /// The world state of each force element's point ([`Chain::forces`],
    /// in order) and the wrench the element applies there at time `t` (s),
    /// at the last kinematics pass's poses.
    pub fn force_element_wrenches(&self, t: f64) -> Vec<(PointState, PointWrench)> {
        self.forces.iter().zip(self.force_element_points()).map(|(f, at)| (at, f.element.wrench(t, &at))).collect()
    }

    /// The world state of each force element's point ([`Chain::forces`],
    /// in order) at the last kinematics pass's poses.
    pub fn force_element_points(&self) -> impl Iterator<Item = PointState> + '_ {
        self.forces.iter().map(|f| point_state(&self.poses[f.link], self.origin, f.local_point).0)
    }

    /// Potential energy of the anchor springs and force elements
    /// ([`ForceElement::energy`]) at time `t` (s) and the last kinematics
    /// pass's poses, J.
    pub fn force_element_energy(&self, t: f64) -> f64 {
        let at = |link: usize, local: DVec3| point_state(&self.poses[link], self.origin, local).0;
        let anchors = self.anchors.iter().map(|a| a.energy(t, &at(a.link, a.local_point)));
        let pairs = self.pairs.iter().map(|p| p.element.energy(t, &at(p.link_a, p.point_a), &at(p.link_b, p.point_b)));
        anchors.chain(self.forces.iter().map(|f| f.element.energy(t, &at(f.link, f.local_point)))).chain(pairs).sum()
    }

    /// Total load the chain puts on its base at the last residual
    /// evaluation: gravity, inertia, loads and anchor forces of every link,
    /// as a spatial force `[moment about the chain origin; force]`, N·m and
    /// N. (The base holds the chain with the opposite force.)
    pub fn base_load(&self) -> V6 {
        self.base_load
    }

    /// Kinetic energy at the last kinematics evaluation, J.
    pub fn kinetic_energy(&self) -> f64 {
        self.joints
            .iter()
            .zip(&self.poses)
            .filter_map(|(j, ps)| {
                j.link.map(|lm| {
                    let c = ps.pos + ps.rot * lm.com;
                    let w = ps.vel.top;
                    let vc = ps.vel.bot + w.cross(c);
                    0.5 * lm.mass * vc.length_squared() + 0.5 * w.dot(ps.rot * (lm.inertia * (ps.rot.transpose() * w)))
                })
            })
            .sum()
    }

    /// Gravitational potential energy `−Σ m g·c` at the last kinematics
    /// evaluation (zero at the world origin), J.
    pub fn gravity_energy(&self) -> f64 {
        self.joints.iter().zip(&self.poses).filter_map(|(j, ps)| j.link.map(|lm| -lm.mass * self.gravity.dot(ps.pos + ps.rot * lm.com + self.origin))).sum()
    }

    /// Whether nothing outside the chain does work on it: its base and
    /// every anchor target (of every limb) at rest, no loads or drives, only
    /// passive force and pair elements ([`ForceElement::is_passive`]: springs
    /// to fixed points, contacts with fixed obstacles and between two of its
    /// points) and no wrenches set by a forest. Its springs, contacts (and
    /// gravity) are then conservative and its dampers and friction
    /// dissipative: its energy cannot grow.
    pub fn is_passive(&self) -> bool {
        self.supports_at_rest() && self.passive_inside()
    }

    /// The base and every anchor target (of every limb) at rest.
    fn supports_at_rest(&self) -> bool {
        let at_rest = |b: &BaseMotion| matches!(b, BaseMotion::Fixed(_));
        at_rest(&self.base) && self.anchors.iter().all(|a| at_rest(&a.target))
    }

    /// Whether the only work done on the chain from outside is that of its
    /// supports' prescribed motion (a moving base or anchor target, which
    /// [`SecondOrderSystem::energy_balance`](crate::integrate::SecondOrderSystem::energy_balance)
    /// counts): passive but for the supports
    /// ([`Chain::is_passive`]).
    pub fn accounts_energy(&self) -> bool {
        self.passive_inside()
    }

    /// No loads, drives or forest wrenches, and only passive force and
    /// pair elements.
    fn passive_inside(&self) -> bool {
        self.loads.is_empty()
            && self.forces.iter().all(|f| f.element.is_passive())
            && self.pairs.iter().all(|p| p.element.is_passive())
            && self.external.is_empty()
            && self.joint_forces.iter().all(|f| *f == 0.0)
    }

    /// The chain's energy account at `(t, q, v, a)`
    /// ([`SecondOrderSystem::energy_balance`](crate::integrate::SecondOrderSystem::energy_balance)):
    /// `[kinetic, gravitational, elastic]` (J) and the power (W) its
    /// supports' motion delivers, `−V_base · F_base` (the base's spatial
    /// velocity and the load the chain puts on it, [`Chain::base_load`])
    /// plus, for each anchor spring, its force on the chain times its
    /// target's velocity. A passive chain ([`Chain::is_passive`]) takes one
    /// kinematics pass at zero acceleration (its power is zero); one with
    /// moving supports a residual pass at `a` (the base load includes the
    /// chain's inertia). The last residual's poses and loads are
    /// overwritten. `None` for a chain without an account
    /// ([`Chain::accounts_energy`]).
    pub(crate) fn energy_balance_at(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64]) -> Option<EnergyBalance> {
        if !self.accounts_energy() || q.len() != self.joints.len() || v.len() != q.len() || a.len() != q.len() {
            return None;
        }
        // (`accounts_energy` held: passive when the supports are at rest.)
        let power = if self.supports_at_rest() {
            let zeros = std::mem::take(&mut self.energy_zeros);
            let zeros = if zeros.len() == q.len() { zeros } else { vec![0.0; q.len()] };
            let done = self.kinematics(t, q, v, &zeros);
            self.energy_zeros = zeros;
            done.ok()?;
            0.0
        } else {
            let mut r = std::mem::take(&mut self.energy_residual);
            r.resize(q.len(), 0.0);
            let done = self.residual_into(t, q, v, a, &mut r);
            self.energy_residual = r;
            done.ok()?;
            let base = self.base.at(t);
            let bw = base.angular_velocity;
            let base_vel = V6::new(bw, base.velocity - bw.cross(base.position - self.origin));
            let anchors: f64 = self
                .anchors
                .iter()
                .map(|an| {
                    let at = point_state(&self.poses[an.link], self.origin, an.local_point).0;
                    an.wrench(t, &at).force.dot(an.target.at(t).velocity)
                })
                .sum();
            -base_vel.dot(self.base_load) + anchors
        };
        let parts = [self.kinetic_energy(), self.gravity_energy(), self.elastic_energy(q) + self.force_element_energy(t)];
        (parts.iter().all(|e| e.is_finite()) && power.is_finite()).then_some(EnergyBalance { parts, power })
    }

    /// Elastic energy of the joint springs at `q`, J.
    pub fn elastic_energy(&self, q: &[f64]) -> f64 {
        let mut coupled = vec![false; self.joints.len()];
        let mut e = 0.0;
        for rs in &self.rotation_springs {
            coupled[rs.first..rs.first + 3].iter_mut().for_each(|c| *c = true);
            let theta = rotation_deviation(rs, &self.joints, q).0;
            e += 0.5 * theta.dot(rs.k * theta);
        }
        e + self.joints.iter().zip(q).zip(&coupled).filter(|(_, c)| !**c).map(|((j, qs), _)| j.spring_energy(*qs)).sum::<f64>()
    }

    /// The moment (N·m, world frame) carried by the three revolute
    /// sub-joints `first`, `first + 1`, `first + 2` at `(q, v)`: the vector
    /// `W` whose component on each sub-joint's axis is that sub-joint's
    /// elastic + damping generalized force (the rotation spring's objective
    /// law where one starts at `first`, else the per-axis springs). In
    /// equilibrium it is the moment of everything outboard about the joint
    /// point. The axes are those of the last kinematics pass (current after
    /// [`Chain::residual_into`] at `q`). Zero if the axes are degenerate.
    pub fn joint_moment(&self, first: usize, q: &[f64], v: &[f64]) -> DVec3 {
        let linear = |s: usize| self.joints[s].spring_force(q[s], v[s]).0;
        let forces = match self.rotation_springs.binary_search_by_key(&first, |r| r.first) {
            Ok(k) => rotation_spring_forces(&self.rotation_springs[k], &self.joints, q, v, false).0,
            Err(_) => [linear(first), linear(first + 1), linear(first + 2)],
        };
        let axes = DMat3::from_cols(self.rows[first].s.top, self.rows[first + 1].s.top, self.rows[first + 2].s.top);
        let det = axes.determinant();
        if !det.is_finite() || det.abs() < 1e-9 {
            return DVec3::ZERO;
        }
        axes.transpose().inverse() * DVec3::from_array(forces)
    }

    /// Each sub-joint's spring + damper generalized force at `(q, v)`, N or
    /// N·m (the rotation springs' law where they apply).
    #[cfg(test)]
    pub(crate) fn elastic_forces(&self, q: &[f64], v: &[f64]) -> Vec<f64> {
        let mut out: Vec<f64> = self.joints.iter().enumerate().map(|(s, j)| j.spring_force(q[s], v[s]).0).collect();
        for rs in &self.rotation_springs {
            let (forces, ..) = rotation_spring_forces(rs, &self.joints, q, v, false);
            out[rs.first..rs.first + 3].copy_from_slice(&forces);
        }
        out
    }
}
