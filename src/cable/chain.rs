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

use super::force::{point_to_spatial, spring_to, AttachedForce, ForceElement, PointState, PointWrench};
use super::spatial::{skew, M6, V6};
use crate::integrate::{SecondOrderSystem, SystemError};
use glam::{DMat3, DQuat, DVec3};
use std::sync::Arc;

/// Revolute or prismatic one-DOF joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the axis, rad.
    Revolute,
    /// Translation along the axis, m.
    Prismatic,
}

/// Mass properties of a link, in the link's own frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkMass {
    /// Mass, kg.
    pub mass: f64,
    /// Centre of mass in the link frame, m.
    pub com: DVec3,
    /// Rotational inertia about the centre of mass, in the link frame, kg·m².
    pub inertia: DMat3,
    /// Linear velocity damping, 1/s: a force `−c m v` at the centre of mass
    /// (rapier's `Damping::linear_damping`; air drag in its simplest form).
    /// Implicit (its tangent enters the solve).
    pub linear_damping: f64,
    /// Angular velocity damping, 1/s: a moment `−c I ω` (rapier's
    /// `Damping::angular_damping`). Implicit.
    pub angular_damping: f64,
}

impl LinkMass {
    /// Mass properties without damping.
    pub fn new(mass: f64, com: DVec3, inertia: DMat3) -> Self {
        LinkMass { mass, com, inertia, linear_damping: 0.0, angular_damping: 0.0 }
    }

    /// Combines two sets of mass properties given in the same frame (the
    /// damping rates are mass-weighted).
    pub fn combine(&self, o: &LinkMass) -> LinkMass {
        let m = self.mass + o.mass;
        let com = (self.com * self.mass + o.com * o.mass) / m;
        let shift = |lm: &LinkMass| {
            let d = lm.com - com;
            lm.inertia + (DMat3::from_diagonal(DVec3::splat(d.length_squared())) - super::spatial::outer3(d, d)) * lm.mass
        };
        LinkMass {
            mass: m,
            com,
            inertia: shift(self) + shift(o),
            linear_damping: (self.linear_damping * self.mass + o.linear_damping * o.mass) / m,
            angular_damping: (self.angular_damping * self.mass + o.angular_damping * o.mass) / m,
        }
    }
}

/// One sub-joint and the link that follows it.
#[derive(Debug, Clone, PartialEq)]
pub struct SubJoint {
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Unit axis in the joint frame.
    pub axis: DVec3,
    /// Joint point in the parent link frame, m.
    pub offset: DVec3,
    /// Constant rotation from the parent link frame to the joint frame.
    pub pre_rotation: DMat3,
    /// Spring stiffness, N/m or N·m/rad.
    pub stiffness: f64,
    /// Viscous damping, N·s/m or N·m·s/rad.
    pub damping: f64,
    /// Spring rest value, m or rad.
    pub rest: f64,
    /// Mass of the link after this joint; `None` for a massless sub-link.
    pub link: Option<LinkMass>,
    /// How the spring force depends on the coordinate: linear, or
    /// tension-only (a wire rope's axial slide: it cannot push). After
    /// changing it on a built chain, call [`Chain::invalidate_layout`].
    pub law: SpringLaw,
}

/// The force law of a sub-joint's spring and damper.
///
/// `x = q − rest` is the spring's extension (m or rad) and `v` its rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SpringLaw {
    /// `f = k x + c v` for every `x` (rods, beams, shear, bending).
    #[default]
    Linear,
    /// `f = max(0, k x + c v)`: a rope never pushes, neither with its
    /// spring nor with its damper. Without damping this is `k x` while
    /// stretched (`x > 0`) and zero once slack. With damping the spring and
    /// damper are clamped together, so the force is continuous and
    /// nondecreasing in the step's unknown (an element closing faster
    /// than `x/τ`, `τ = c/k`, goes slack a little before `x = 0`; one
    /// opening fast pulls a little before it), which keeps Newton's
    /// problem well posed: clamping the spring alone would make the force
    /// jump by `c v` at `x = 0`. The kink is not smoothed (the force is
    /// exact); Newton freezes each law on one branch per solve
    /// (`SecondOrderSystem::freeze_branches`).
    TensionOnly,
}

impl SubJoint {
    /// The spring + damper force at extension `q − rest` and rate `v`, and
    /// its tangents `(f, ∂f/∂q, ∂f/∂v)` (N or N·m; N/m or N·m/rad; N·s/m or
    /// N·m·s/rad).
    #[inline]
    pub fn spring_force(&self, q: f64, v: f64) -> (f64, f64, f64) {
        self.spring_force_on_branch(q, v, self.is_taut(q, v))
    }

    /// [`SubJoint::spring_force`] with the law held on one branch: `taut`
    /// gives the linear law whatever the sign of the extension, slack gives
    /// zero (what Newton solves while the branches are frozen).
    #[inline]
    pub fn spring_force_on_branch(&self, q: f64, v: f64, taut: bool) -> (f64, f64, f64) {
        match self.law {
            SpringLaw::TensionOnly if !taut => (0.0, 0.0, 0.0),
            _ => (self.stiffness * (q - self.rest) + self.damping * v, self.stiffness, self.damping),
        }
    }

    /// Whether the law is on its taut branch at `(q, v)` (always for a
    /// linear law; a tension-only spring pulls when `k x + c v > 0`).
    pub fn is_taut(&self, q: f64, v: f64) -> bool {
        self.law == SpringLaw::Linear || self.taut_measure(q, v) > 0.0
    }

    /// `(k x + c v)/k` (m or rad): the extension the spring and damper pull
    /// with together; its sign decides a tension-only law's branch.
    #[inline]
    pub(crate) fn taut_measure(&self, q: f64, v: f64) -> f64 {
        let x = q - self.rest;
        if self.stiffness > 0.0 {
            x + self.damping / self.stiffness * v
        } else {
            x
        }
    }

    /// The joint frame (orientation, origin) in the frame of the parent
    /// link at `(prev_rot, prev_pos)`: the constant pre-rotation and
    /// offset applied, before the joint's own motion.
    #[inline]
    pub(crate) fn frame(&self, prev_rot: DMat3, prev_pos: DVec3) -> (DMat3, DVec3) {
        let rj = if self.pre_rotation == DMat3::IDENTITY { prev_rot } else { prev_rot * self.pre_rotation };
        let pj = if self.offset == DVec3::ZERO { prev_pos } else { prev_pos + prev_rot * self.offset };
        (rj, pj)
    }

    /// Elastic energy stored at coordinate `q`, J.
    pub fn spring_energy(&self, q: f64) -> f64 {
        let x = q - self.rest;
        match self.law {
            SpringLaw::TensionOnly if x <= 0.0 => 0.0,
            _ => 0.5 * self.stiffness * x * x,
        }
    }
}

/// Pose, velocity and acceleration of the chain's base frame at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseState {
    /// Orientation of the base frame.
    pub rotation: DMat3,
    /// Position of the base frame origin (world), m.
    pub position: DVec3,
    /// Angular velocity, rad/s.
    pub angular_velocity: DVec3,
    /// Velocity of the base origin, m/s.
    pub velocity: DVec3,
    /// Angular acceleration, rad/s².
    pub angular_acceleration: DVec3,
    /// Acceleration of the base origin, m/s².
    pub acceleration: DVec3,
}

impl BaseState {
    /// A base at rest with the given pose.
    pub fn fixed(rotation: DMat3, position: DVec3) -> Self {
        BaseState { rotation, position, angular_velocity: DVec3::ZERO, velocity: DVec3::ZERO, angular_acceleration: DVec3::ZERO, acceleration: DVec3::ZERO }
    }
}

/// How the base frame moves: fixed, or a prescribed function of time.
#[derive(Clone)]
pub enum BaseMotion {
    /// At rest.
    Fixed(BaseState),
    /// Prescribed motion `t ↦ state` (kinematic body, moving crane hook…).
    Prescribed(Arc<dyn Fn(f64) -> BaseState + Send + Sync>),
}

impl BaseMotion {
    /// The base state at time `t`, s.
    pub fn at(&self, t: f64) -> BaseState {
        match self {
            BaseMotion::Fixed(s) => *s,
            BaseMotion::Prescribed(f) => f(t),
        }
    }
}

impl std::fmt::Debug for BaseMotion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BaseMotion::Fixed(s) => f.debug_tuple("Fixed").field(s).finish(),
            BaseMotion::Prescribed(_) => f.write_str("Prescribed(..)"),
        }
    }
}

/// A spring–damper holding a point of a link to a (possibly moving) world
/// point, optionally also holding the link's orientation. Implicit: its
/// stiffness enters the articulated-body solve.
#[derive(Clone)]
pub struct AnchorSpring {
    /// Sub-joint index whose link is held.
    pub link: usize,
    /// Held point in the link frame, m.
    pub local_point: DVec3,
    /// Target world point (and its velocity) as a function of time.
    pub target: Arc<dyn Fn(f64) -> (DVec3, DVec3) + Send + Sync>,
    /// Translational stiffness, N/m.
    pub stiffness: f64,
    /// Translational damping, N·s/m.
    pub damping: f64,
    /// Optional orientation hold: target orientation, stiffness N·m/rad,
    /// damping N·m·s/rad.
    pub rotation: Option<(DMat3, f64, f64)>,
}

/// An anchor spring is the first force element: a spring–damper to a moving
/// world point, and optionally an orientation hold.
impl ForceElement for AnchorSpring {
    fn wrench(&self, t: f64, at: &PointState) -> PointWrench {
        let (target, target_v) = (self.target)(t);
        let mut w = spring_to(at, target, target_v, self.stiffness, self.damping);
        if let Some((rt, kr, cr)) = self.rotation {
            let err = rotation_vector(&(at.rotation * rt.transpose()));
            w.moment = -err * kr - at.angular_velocity * cr;
            w.stiffness.a = DMat3::from_diagonal(DVec3::splat(kr));
            w.damping.a = DMat3::from_diagonal(DVec3::splat(cr));
        }
        w
    }

    fn energy(&self, t: f64, at: &PointState) -> f64 {
        let (target, _) = (self.target)(t);
        let turn = self.rotation.map_or(0.0, |(rt, kr, _)| 0.5 * kr * rotation_vector(&(at.rotation * rt.transpose())).length_squared());
        0.5 * self.stiffness * at.point.distance_squared(target) + turn
    }
}

/// An objective elastic law for three consecutive revolute sub-joints
/// (about local z, then y, then x: an element's bending and torsion).
///
/// The Euler angles `(a, b, c)` give the relative rotation
/// `R = Rz(a) Ry(b) Rx(c)`; the rest angles (the sub-joints' `rest`) give
/// `R₀`. The energy is `½ θᵀ K θ` with `θ = log(R₀ᵀ R)` the rotation vector
/// of the deviation and `K = diag(k_x, k_y, k_z)` (torsion, bending about y,
/// bending about z), so bending and torsion moments act about the right
/// axes for any combination of the three angles (with one spring per Euler
/// angle they would not, and 3D bending–torsion would converge only as
/// O(1/N)). Generalized forces: `Q_k = −(Kθ)ᵀ J_l⁻¹(θ) R₀ᵀ E_k`, `E_k` the
/// sub-joint axes in the joint frame. The sub-joints' own `stiffness` and
/// `damping` are then only the diagonal of the implicit tangent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotationSpring {
    /// Index of the first (z) sub-joint of the three.
    pub first: usize,
    /// Stiffness about local x (torsion), y and z (bending), N·m/rad.
    pub k: DVec3,
    /// Stiffness-proportional damping time constant, s.
    pub tau: f64,
}

/// An external load on a link: a force of fixed direction at a point plus a
/// moment, world frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinkLoad {
    /// Sub-joint index whose link carries the load.
    pub link: usize,
    /// Force, N.
    pub force: DVec3,
    /// Application point in the link frame, m.
    pub local_point: DVec3,
    /// Moment, N·m.
    pub moment: DVec3,
}

/// A limb of a tree-shaped chain: the sub-joints from `first` up to the
/// next limb's first (or the chain's end) form a serial branch whose first
/// sub-joint hangs from link `parent` (`None`: from the base) instead of
/// from link `first − 1`. A chain without limbs is serial. The sub-joints
/// are in depth-first order: `parent < first`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limb {
    /// First sub-joint of the limb.
    pub first: usize,
    /// Link the limb hangs from (`None`: the base).
    pub parent: Option<usize>,
}

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

/// Slack (m) within which a tension-only element starts a Newton solve on
/// its taut branch ([`SecondOrderSystem::freeze_branches`]): a rope laid
/// from coordinates rounded to the micrometre starts taut.
const TAUT_BAND: f64 = 1e-6;

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

    /// One base-to-tip pass: forward kinematics, velocities and
    /// accelerations; the d'Alembert and gravity loads of every link with
    /// mass; every sub-joint's elastic force (rotation springs at their
    /// last sub-joint). Loads of other links are cleared.
    pub(crate) fn kinematics(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64]) {
        self.assign_slots();
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
            let (rj, pj) = j.frame(prev_rot, prev_pos);
            // Principal axes (every rope sub-joint) are column picks.
            let axis_id = axis_id(j.axis);
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
                if self.frozen && j.law != SpringLaw::Linear { j.spring_force_on_branch(q[s], v[s], self.branch[s] != 0) } else { j.spring_force(q[s], v[s]) };
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
                let (forces, a_mat) = rotation_spring_forces(&rs, &self.joints, q, v);
                for (i, fi) in forces.iter().enumerate() {
                    self.rows[rs.first + i].elastic = *fi;
                }
                self.rot_scratch[k as usize].0 = a_mat;
            }
            if tree && self.limb_parent[s] != u32::MAX {
                self.limb_acc[self.limb_parent[s] as usize] = acc;
            }
            prev_vel = vel;
            prev_acc = acc;
            prev_rot = rot;
            prev_pos = pos;
        }
    }

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

    /// Residual `r = M(q) a − Q(t, q, v)` (see [`SecondOrderSystem`]); also
    /// prepares everything [`Chain::solve_into`] needs at this state.
    pub fn residual_into(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        self.sweep(t, q, v, a, r, None)
    }

    /// Residual and Newton correction in one tip-to-base sweep: `rhs = −r`
    /// and `(M + c_v C + c_q (K + K_g)) x = rhs` (see
    /// [`SecondOrderSystem::residual_and_correction`]).
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
        self.forward_solve(x);
        Ok(())
    }

    /// Forward kinematics, loads, and the tip-to-base sweep. Without
    /// `solve`, writes the residual into `r`; with `solve = (c_v, c_q)`,
    /// writes `−r` into `r` and runs the articulated-body backward sweep
    /// for that right-hand side on the way (finish with `forward_solve`).
    fn sweep(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64], solve: Option<(f64, f64)>) -> Result<(), SystemError> {
        // One cheap pass: a NaN or infinity anywhere makes the sum non-finite
        // (then find which coordinate, for the message).
        if !(q.iter().sum::<f64>() + v.iter().sum::<f64>() + a.iter().sum::<f64>()).is_finite() {
            if let Some(index) = q.iter().chain(v).chain(a).position(|x| !x.is_finite()) {
                return Err(SystemError::NonFinite { index: index % q.len().max(1) });
            }
        }
        self.kinematics(t, q, v, a);
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
            apply_force_element(&mut self.links[slot], &mut self.anchor_blocks, &self.poses[an.link], self.origin, an.local_point, t, an);
        }
        for fe in &self.forces {
            let slot = self.link_slot[fe.link] as usize;
            apply_force_element(&mut self.links[slot], &mut self.anchor_blocks, &self.poses[fe.link], self.origin, fe.local_point, t, fe.element.as_ref());
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
                    self.eliminate(&mut aba, s, c_v, c_q, r)?;
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
    pub fn solve_into(&mut self, c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
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
            self.eliminate(&mut aba, s, c_v, c_q, b)?;
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

    /// Tip-to-base elimination of sub-joint `s` (right-hand side `b`): a
    /// single sub-joint, the second or third sub-joint of a rotation-spring
    /// block (only its link is added; the block is eliminated at its first
    /// sub-joint), or a whole block.
    fn eliminate(&mut self, aba: &mut AbaCarry, s: usize, c_v: f64, c_q: f64, b: &[f64]) -> Result<(), SystemError> {
        let slot = self.link_slot[s];
        if slot != u32::MAX {
            let ls = &self.links[slot as usize];
            aba.add_link(ls, &self.anchor_blocks, c_v, c_q);
        }
        match self.block[s] {
            u32::MAX => aba.down(s, &mut self.rows[s], c_v, c_q, b[s]),
            BLOCK_INNER => Ok(()),
            k => {
                let rs = &self.rotation_springs[k as usize];
                let (a_mat, pinv) = &mut self.rot_scratch[k as usize];
                aba.down_block(s, &mut self.rows[s..s + 3], rs, a_mat, pinv, c_v, c_q, [b[s], b[s + 1], b[s + 2]])
            }
        }
    }

    /// Base-to-tip half of the articulated-body solve.
    fn forward_solve(&mut self, x: &mut [f64]) {
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
                    s += 3;
                }
            }
        }
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

/// Deviation rotation vector `θ = log(R₀ᵀ R)` of a rotation spring, and
/// `R₀ᵀ E_k` for its three axes.
fn rotation_deviation(rs: &RotationSpring, joints: &[SubJoint], q: &[f64]) -> (DVec3, [DVec3; 3]) {
    let f = rs.first;
    let rel = |a: f64, b: f64, c: f64| {
        let rz = rotate_about(DMat3::IDENTITY, DVec3::Z, a);
        let rzy = rotate_about(rz, DVec3::Y, b);
        (rz, rzy, rotate_about(rzy, DVec3::X, c))
    };
    let (rz, rzy, r) = rel(q[f], q[f + 1], q[f + 2]);
    let rests = (joints[f].rest, joints[f + 1].rest, joints[f + 2].rest);
    if rests == (0.0, 0.0, 0.0) {
        return (rotation_vector(&r), [DVec3::Z, rz.y_axis, rzy.x_axis]);
    }
    let (_, _, r0) = rel(rests.0, rests.1, rests.2);
    let r0t = r0.transpose();
    let theta = rotation_vector(&(r0t * r));
    (theta, [r0t * DVec3::Z, r0t * rz.y_axis, r0t * rzy.x_axis])
}

/// A rotation spring's generalized forces on its three sub-joints and
/// `A = ∂θ/∂(a, b, c)` (the columns `J_l⁻¹ R₀ᵀ E_k`).
fn rotation_spring_forces(rs: &RotationSpring, joints: &[SubJoint], q: &[f64], v: &[f64]) -> ([f64; 3], DMat3) {
    let (theta, axes) = rotation_deviation(rs, joints, q);
    let f = rs.first;
    let omega = axes[0] * v[f] + axes[1] * v[f + 1] + axes[2] * v[f + 2];
    // J_l⁻¹(θ) x = x − ½ θ×x + β θ×(θ×x), β = (1 − (φ/2)cot(φ/2))/φ²;
    // J_l⁻ᵀ(θ) = J_l⁻¹(−θ).
    let phi2 = theta.length_squared();
    let beta = if phi2 < 1e-6 {
        1.0 / 12.0 + phi2 / 720.0
    } else {
        let phi = phi2.sqrt();
        (1.0 - 0.5 * phi / (0.5 * phi).tan()) / phi2
    };
    let jinv = |x: DVec3, sign: f64| x - 0.5 * sign * theta.cross(x) + beta * theta.cross(theta.cross(x));
    let theta_dot = jinv(omega, 1.0);
    let moment = rs.k * theta + rs.k * theta_dot * rs.tau;
    // Q_k = (Kθ + τKθ̇)ᵀ J⁻¹ E_k = (J⁻ᵀ m)·E_k.
    let m = jinv(moment, -1.0);
    ([m.dot(axes[0]), m.dot(axes[1]), m.dot(axes[2])], DMat3::from_cols(jinv(axes[0], 1.0), jinv(axes[1], 1.0), jinv(axes[2], 1.0)))
}

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
    fn position_tolerance(&self) -> f64 {
        self.position_tolerance
    }
    fn freeze_branches(&mut self, start: &[f64], predicted: &[f64]) {
        self.assign_slots();
        if self.nonsmooth.is_empty() {
            return;
        }
        self.branch.resize(self.joints.len(), 1);
        // Taut unless both the step's start and the predictor are slack by
        // more than `TAUT_BAND` (or the position tolerance): an
        // element at its kink (unstrained, or laid from rounded coordinates)
        // is taken taut, and the predictor's round-off (its acceleration on
        // a light element between heavy ones) cannot start it slack. A
        // wrong guess costs one branch update; starting a barely slack rope
        // slack would cost one update per element, as the pull reaches each
        // element only once the one above it is taut.
        let band = self.position_tolerance.max(TAUT_BAND);
        for &s in &self.nonsmooth {
            let s = s as usize;
            let rest = self.joints[s].rest;
            self.branch[s] = u8::from(start[s] - rest >= -band || predicted[s] - rest >= -band);
        }
        self.frozen = true;
    }
    fn update_branches(&mut self, q: &[f64], v: &[f64]) -> usize {
        if !self.frozen {
            return 0;
        }
        let tol = self.position_tolerance;
        let mut moved = 0;
        for i in 0..self.nonsmooth.len() {
            let s = self.nonsmooth[i] as usize;
            if self.disagreement(s, q, v) > tol {
                self.branch[s] ^= 1;
                moved += 1;
            }
        }
        moved
    }
    fn branch_disagreement(&self, q: &[f64], v: &[f64]) -> f64 {
        if !self.frozen {
            return 0.0;
        }
        self.nonsmooth.iter().map(|&s| self.disagreement(s as usize, q, v)).fold(0.0, f64::max)
    }
    fn release_branches(&mut self) {
        self.frozen = false;
    }
    fn nonlinear_update(&mut self, q: &[f64], dx: &[f64], scale: f64, out: &mut [f64]) -> bool {
        // Only a chain closed by anchor springs needs it (an open chain's
        // tip is free, and the plain sum costs nothing).
        if self.anchors.is_empty() && self.forces.is_empty() {
            return false;
        }
        self.link_update(q, dx, scale, out);
        true
    }
}

impl Chain {
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
            let (rj, pj) = j.frame(prev_rot, prev_pos);
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

/// Tip-to-base state of the articulated-body solve: the shifted
/// articulated inertia `Ĩ` and bias carried to the parent.
#[derive(Default)]
struct AbaCarry {
    inertia: M6,
    bias: V6,
}

impl AbaCarry {
    /// One sub-joint of the backward sweep (see [`Chain::solve_into`]).
    #[inline]
    fn down(&mut self, s: usize, row: &mut Row, c_v: f64, c_q: f64, b: f64) -> Result<(), SystemError> {
        let uv = self.inertia.mul_motion(row.s) - row.gs * c_q;
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
        Ok(())
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
    /// the law's Gauss–Newton stiffness `(c_q + c_v τ) Aᵀ K A`, with
    /// `U_k = Ĩ S_k − c_q G_k S_k` (no mass sits between the three).
    #[allow(clippy::too_many_arguments)]
    fn down_block(
        &mut self,
        s: usize,
        f: &mut [Row],
        rs: &RotationSpring,
        a_mat: &DMat3,
        pinv: &mut DMat3,
        c_v: f64,
        c_q: f64,
        b: [f64; 3],
    ) -> Result<(), SystemError> {
        let u: [V6; 3] = [0, 1, 2].map(|k| self.inertia.mul_vec(f[k].s) - f[k].gs * c_q);
        let mut p = [[0.0; 3]; 3];
        for k in 0..3 {
            for l in k..3 {
                p[k][l] = f[k].s.dot(u[l]);
                p[l][k] = p[k][l];
            }
        }
        let ka = DMat3::from_cols(a_mat.x_axis * rs.k, a_mat.y_axis * rs.k, a_mat.z_axis * rs.k);
        let h = a_mat.transpose() * ka * (c_q + c_v * rs.tau);
        let pm = DMat3::from_cols_array_2d(&p) + h;
        let det = pm.determinant();
        let scale = pm.x_axis.length() * pm.y_axis.length() * pm.z_axis.length();
        if !det.is_finite() || det.abs() <= 1e-14 * scale {
            return Err(SystemError::Singular { index: s, pivot: det });
        }
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
        Ok(())
    }
}

/// Marker in [`Chain::block`] for the second and third sub-joint of a block.
pub(crate) const BLOCK_INNER: u32 = u32::MAX - 1;

/// The rotation vector `θ = log(R)`, accurate to round-off for small angles
/// (`2 atan2(|v|, w)` on the quaternion, not `2 acos(w)`, which loses half
/// the digits near zero).
/// The world state of `local_point` on the link at `ps`, and the point
/// relative to `origin`.
fn point_state(ps: &Pose, origin: DVec3, local_point: DVec3) -> (PointState, DVec3) {
    let p = ps.pos + ps.rot * local_point;
    (PointState { rotation: ps.rot, point: p + origin, velocity: ps.vel.bot + ps.vel.top.cross(p), angular_velocity: ps.vel.top }, p)
}

/// Evaluates a force element at `local_point` of the link at `ps` and adds
/// its wrench to the link's load, the moment-arm tangent to the link's load
/// tangent, and its stiffness and damping (moved to the spatial frame) to
/// the link's implicit blocks.
#[allow(clippy::too_many_arguments)]
fn apply_force_element(ls: &mut LinkScratch, blocks: &mut [(M6, M6)], ps: &Pose, origin: DVec3, local_point: DVec3, t: f64, element: &dyn ForceElement) {
    let (at, p) = point_state(ps, origin, local_point);
    let w = element.wrench(t, &at);
    let px = skew(p);
    let (k, c) = &mut blocks[ls.anchor as usize];
    k.add_scaled(&point_to_spatial(&w.stiffness, px), 1.0);
    c.add_scaled(&point_to_spatial(&w.damping, px), 1.0);
    ls.f += V6::new(p.cross(w.force) + w.moment, w.force);
    ls.add_point_load_tangent(w.force, p);
}

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
fn small_sin_cos(x: f64) -> (f64, f64) {
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
fn rotate_about(r: DMat3, axis: DVec3, angle: f64) -> DMat3 {
    rotate_about_id(r, axis_id(axis), axis, angle)
}

/// Classifies a joint axis for [`rotate_about_id`]: 0, 1, 2 for the unit
/// x, y, z axes, 3 for any other.
#[inline]
fn axis_id(axis: DVec3) -> u8 {
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
fn rotate_about_id(r: DMat3, id: u8, axis: DVec3, angle: f64) -> DMat3 {
    let (sn, cs) = small_sin_cos(angle);
    match id {
        0 => DMat3::from_cols(r.x_axis, r.y_axis * cs + r.z_axis * sn, r.z_axis * cs - r.y_axis * sn),
        1 => DMat3::from_cols(r.x_axis * cs - r.z_axis * sn, r.y_axis, r.x_axis * sn + r.z_axis * cs),
        2 => DMat3::from_cols(r.x_axis * cs + r.y_axis * sn, r.y_axis * cs - r.x_axis * sn, r.z_axis),
        _ => r * DMat3::from_axis_angle(axis, angle),
    }
}

/// Why a static solve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
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
        let result = self.solve_static_on_branches(t, q, tol, max_iterations);
        self.release_branches();
        let iterations = result?;
        let compressed = self.nonsmooth.iter().map(|&s| s as usize).map(|s| (s, q[s] - self.joints[s].rest)).min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((joint, x)) = compressed.filter(|&(_, x)| x < -tol) {
            return Err(StaticError::Compressed { joint, force: self.joints[joint].stiffness * x });
        }
        Ok(iterations)
    }

    /// How far (m or rad, [`SubJoint::taut_measure`]) the non-smooth law of
    /// sub-joint `s` is on the other side of its kink from its frozen
    /// branch at `(q, v)`; 0 when they agree.
    fn disagreement(&self, s: usize, q: &[f64], v: &[f64]) -> f64 {
        let x = self.joints[s].taut_measure(q[s], v[s]);
        if (self.branch[s] != 0) == (x > 0.0) {
            0.0
        } else {
            x.abs()
        }
    }

    /// Every tension-only law frozen on its taut branch (the linear law).
    fn freeze_taut(&mut self) {
        self.assign_slots();
        self.branch.clear();
        self.branch.resize(self.joints.len(), 1);
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

#[cfg(test)]
pub(crate) fn small_sin_cos_for_tests(x: f64) -> (f64, f64) {
    small_sin_cos(x)
}
