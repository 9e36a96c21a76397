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

mod nonsmooth;
mod parts;
mod sweep;

pub use nonsmooth::StaticError;
pub use parts::*;
pub(crate) use sweep::*;

use super::force::{AttachedForce, ForceElement};
use super::spatial::{M6, V6};
use glam::{DMat3, DVec3};

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

/// A serial chain of one-DOF sub-joints (see the module docs).
#[derive(Clone)]
pub struct Chain {
    /// The sub-joints from base to tip.
    pub joints: Vec<SubJoint>,
    /// Base motion.
    pub base: BaseMotion,
    /// Gravity, m/s².
    pub gravity: DVec3,
    /// Reference point: internal positions are relative to it (keeps the
    /// spatial inertias well scaled far from the world origin), m.
    pub origin: DVec3,
    /// Anchor springs (implicit force elements).
    pub anchors: Vec<AnchorSpring>,
    /// Other implicit force elements (user laws, contact, drag).
    pub forces: Vec<AttachedForce>,
    /// External loads of fixed direction (explicit in value, their geometric
    /// stiffness implicit).
    pub loads: Vec<LinkLoad>,
    /// Generalized forces on the sub-joints (drives), N or N·m.
    pub joint_forces: Vec<f64>,
    /// Objective bending–torsion laws replacing the per-angle springs of
    /// their sub-joints.
    pub rotation_springs: Vec<RotationSpring>,
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
    /// Per sub-joint: index of the rotation spring whose block starts here,
    /// [`BLOCK_INNER`] inside a block, `u32::MAX` for a single sub-joint.
    pub(crate) block: Vec<u32>,
    /// Per rotation spring: `A = ∂θ/∂(a, b, c)` and the block pivot inverse.
    pub(crate) rot_scratch: Vec<(DMat3, DMat3)>,
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
    /// Per sub-joint: the frozen branch of a non-smooth law (1 taut, 0
    /// slack) while `frozen` (see [`SecondOrderSystem::freeze_branches`]).
    branch: Vec<u8>,
    frozen: bool,
    /// Sub-joints with a non-smooth law (rebuilt with the layout).
    nonsmooth: Vec<u32>,
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
            loads: Vec::new(),
            joint_forces: vec![0.0; n],
            rotation_springs: Vec::new(),
            limbs: Vec::new(),
            limb_parent: Vec::new(),
            limb_carry: Vec::new(),
            limb_acc: Vec::new(),
            limb_start: Vec::new(),
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
            nonsmooth: Vec::new(),
        }
    }

    /// The links that carry loads, anchors or force elements, in that order.
    fn loaded_links(&self) -> impl Iterator<Item = usize> + '_ {
        self.loads.iter().map(|l| l.link).chain(self.anchors.iter().map(|a| a.link)).chain(self.forces.iter().map(|f| f.link))
    }

    /// Assigns link scratch slots to links with mass, loads, anchors or
    /// force elements (called by every residual evaluation; allocation-free
    /// once sized).
    fn assign_slots(&mut self) {
        let n = self.joints.len();
        // The layout only changes with the links that carry loads or
        // anchors and with the rotation springs: skip the rebuild when they
        // are exactly those of the last build (an exact key: a hash of the
        // indices collided, e.g. loads on links {0, 40} and {1, 9}).
        let key = &self.slot_key;
        let same = key.built
            && key.n == n
            && self.poses.len() == n
            && key.links.len() == self.loads.len() + self.anchors.len() + self.forces.len()
            && key.springs.len() == self.rotation_springs.len()
            && key.links.iter().copied().eq(self.loaded_links())
            && key.springs.iter().copied().eq(self.rotation_springs.iter().map(|r| r.first))
            && key.limbs == self.limbs;
        if same {
            return;
        }
        self.slot_key.built = true;
        self.slot_key.n = n;
        let links: Vec<usize> = self.loaded_links().collect();
        self.slot_key.links = links;
        self.slot_key.springs.clear();
        self.slot_key.springs.extend(self.rotation_springs.iter().map(|r| r.first));
        self.slot_key.limbs.clone_from(&self.limbs);
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
        for link in self.anchors.iter().map(|a| a.link).chain(self.forces.iter().map(|f| f.link)) {
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
        self.rot_scratch.resize(self.rotation_springs.len(), (DMat3::ZERO, DMat3::ZERO));
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
    /// last kinematics evaluation), m.
    pub fn link_point(&self, s: usize, local: DVec3) -> DVec3 {
        let p = &self.poses[s];
        p.pos + p.rot * local + self.origin
    }

    /// World velocity of a point given in the frame of link `s`, m/s.
    pub fn link_point_velocity(&self, s: usize, local: DVec3) -> DVec3 {
        let ps = &self.poses[s];
        let p = ps.pos + ps.rot * local;
        ps.vel.bot + ps.vel.top.cross(p)
    }

    /// Orientation of link `s` (after the last kinematics evaluation).
    pub fn link_rotation(&self, s: usize) -> DMat3 {
        self.poses[s].rot
    }

    /// Spatial velocity of link `s` (about the chain origin).
    pub fn link_velocity(&self, s: usize) -> V6 {
        self.poses[s].vel
    }

    /// Joint point of sub-joint `s` in the world, m.
    pub fn joint_point(&self, s: usize) -> DVec3 {
        let (rot, pos) = self.parent_pose(s);
        let offset = self.joints[s].offset;
        pos + rot * offset + self.origin
    }

    /// World velocity of sub-joint `s`'s joint point, m/s.
    pub fn joint_point_velocity(&self, s: usize) -> DVec3 {
        let p = self.joint_point(s) - self.origin;
        let vel = self.poses[s].vel;
        vel.bot + vel.top.cross(p)
    }

    /// Potential energy of the anchor springs and force elements
    /// ([`ForceElement::energy`]) at time `t` (s) and the last kinematics
    /// pass's poses, J.
    pub fn force_element_energy(&self, t: f64) -> f64 {
        let at = |link: usize, local: DVec3| point_state(&self.poses[link], self.origin, local).0;
        let anchors = self.anchors.iter().map(|a| a.energy(t, &at(a.link, a.local_point)));
        anchors.chain(self.forces.iter().map(|f| f.element.energy(t, &at(f.link, f.local_point)))).sum()
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
            Ok(k) => rotation_spring_forces(&self.rotation_springs[k], &self.joints, q, v).0,
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
            let (forces, _) = rotation_spring_forces(rs, &self.joints, q, v);
            out[rs.first..rs.first + 3].copy_from_slice(&forces);
        }
        out
    }
}
