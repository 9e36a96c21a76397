//! What a chain is made of: sub-joints, link masses, base motion, anchor
//! springs, rotation springs, loads and limbs.

use super::rotation_vector;
use crate::cable::force::{spring_to, ForceElement, PointState, PointWrench};
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
            lm.inertia + (DMat3::from_diagonal(DVec3::splat(d.length_squared())) - crate::cable::spatial::outer3(d, d)) * lm.mass
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
    /// changing it on a built chain, call [`Chain::invalidate_layout`](super::Chain::invalidate_layout).
    pub law: SpringLaw,
    /// Extension `q − rest` (m or rad) below which a
    /// [`SpringLaw::TensionOnly`] spring pushes back with its stiffness and
    /// damping (the law's closed branch, [`LawBranch::Closed`]):
    /// `−L_e/2` for a rope element's axial slide
    /// ([`SLACK_STOP`](crate::cable::SLACK_STOP)), so that a slack element
    /// shortens freely down to half its length but no further.
    /// `f64::NEG_INFINITY` (the default) for none.
    /// Ignored by linear laws.
    pub stop: f64,
}

/// Which branch of a [`SpringLaw::TensionOnly`] law holds: what Newton
/// freezes for a solve ([`SubJoint::spring_force_on_branch`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum LawBranch {
    /// No force (a slack rope element).
    Slack = 0,
    /// The linear law `k x + c v` (a taut element; every linear law).
    #[default]
    Taut = 1,
    /// The linear law about the stop, `k (x − stop) + c v` (a slack
    /// element shortened to its stop, half its length: it pushes).
    Closed = 2,
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
    /// A sub-joint with no spring, no damper and no mass, about or along
    /// `axis` (unit) of its parent's frame: a free body's slide or turn.
    pub fn free(kind: JointKind, axis: DVec3) -> Self {
        SubJoint {
            kind,
            axis,
            offset: DVec3::ZERO,
            pre_rotation: DMat3::IDENTITY,
            stiffness: 0.0,
            damping: 0.0,
            rest: 0.0,
            link: None,
            law: SpringLaw::Linear,
            stop: f64::NEG_INFINITY,
        }
    }

    /// The spring + damper force at extension `q − rest` and rate `v`, and
    /// its tangents `(f, ∂f/∂q, ∂f/∂v)` (N or N·m; N/m or N·m/rad; N·s/m or
    /// N·m·s/rad).
    #[inline]
    pub fn spring_force(&self, q: f64, v: f64) -> (f64, f64, f64) {
        self.spring_force_on_branch(q, v, self.branch_at(q, v))
    }

    /// [`SubJoint::spring_force`] with the law held on one branch: taut
    /// gives the linear law whatever the sign of the extension, slack gives
    /// zero, closed gives the linear law about [`SubJoint::stop`] (what
    /// Newton solves while the branches are frozen). Linear laws ignore
    /// the branch.
    #[inline]
    pub fn spring_force_on_branch(&self, q: f64, v: f64, branch: LawBranch) -> (f64, f64, f64) {
        match (self.law, branch) {
            (SpringLaw::TensionOnly, LawBranch::Slack) => (0.0, 0.0, 0.0),
            (SpringLaw::TensionOnly, LawBranch::Closed) => (self.stiffness * (q - self.rest - self.stop) + self.damping * v, self.stiffness, self.damping),
            _ => (self.stiffness * (q - self.rest) + self.damping * v, self.stiffness, self.damping),
        }
    }

    /// The branch the law is on at `(q, v)`: always taut for a linear law;
    /// a tension-only spring pulls when `k x + c v > 0`, pushes when
    /// `k (x − stop) + c v < 0`, and is slack between.
    #[inline]
    pub fn branch_at(&self, q: f64, v: f64) -> LawBranch {
        if self.law == SpringLaw::Linear || self.taut_measure(q, v) > 0.0 {
            LawBranch::Taut
        } else if self.closed_measure(q, v) < 0.0 {
            LawBranch::Closed
        } else {
            LawBranch::Slack
        }
    }

    /// Whether the law is on its taut branch at `(q, v)` (always for a
    /// linear law; a tension-only spring pulls when `k x + c v > 0`).
    pub fn is_taut(&self, q: f64, v: f64) -> bool {
        self.branch_at(q, v) == LawBranch::Taut
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

    /// `(k (x − stop) + c v)/k` (m or rad): negative when a tension-only
    /// law is on its closed branch (pushing back at its stop).
    #[inline]
    pub(crate) fn closed_measure(&self, q: f64, v: f64) -> f64 {
        self.taut_measure(q, v) - self.stop
    }

    /// What a pass needs to know of the joint's constant geometry, in one
    /// byte: its axis class ([`axis_id`](super::sweep::axis_id), bits 0–1),
    /// whether it has a pre-rotation (bit 2, [`JOINT_TURNED`]) and an
    /// offset (bit 3, [`JOINT_OFFSET`]). The chain keeps it per sub-joint
    /// with its layout, so that a pass tests one byte instead of nine and
    /// three float compares.
    pub(crate) fn code(&self) -> u8 {
        let mut code = super::sweep::axis_id(self.axis);
        if self.pre_rotation != DMat3::IDENTITY {
            code |= JOINT_TURNED;
        }
        if self.offset != DVec3::ZERO {
            code |= JOINT_OFFSET;
        }
        code
    }

    /// The joint frame (orientation, origin) in the frame of the parent
    /// link at `(prev_rot, prev_pos)`: the constant pre-rotation and
    /// offset applied, before the joint's own motion; `code` is the
    /// joint's [`SubJoint::code`].
    #[inline]
    pub(crate) fn frame(&self, code: u8, prev_rot: DMat3, prev_pos: DVec3) -> (DMat3, DVec3) {
        let rj = if code & JOINT_TURNED != 0 { prev_rot * self.pre_rotation } else { prev_rot };
        let pj = if code & JOINT_OFFSET != 0 { prev_pos + prev_rot * self.offset } else { prev_pos };
        (rj, pj)
    }

    /// Elastic energy stored at coordinate `q`, J.
    pub fn spring_energy(&self, q: f64) -> f64 {
        let x = q - self.rest;
        match self.law {
            SpringLaw::TensionOnly if x < self.stop => 0.5 * self.stiffness * (x - self.stop) * (x - self.stop),
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

/// A motion sampled at time `t0` and extrapolated from there with constant
/// acceleration and constant angular velocity: what a coupling gives a rope end
/// that follows a body another engine moves, refreshed before every step
/// ([`Chain::set_sampled`](super::Chain::set_sampled)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledMotion {
    /// Who refreshes it (a coupling's follower id); the chain only matches
    /// it in [`Chain::set_sampled`](super::Chain::set_sampled).
    pub source: usize,
    /// Time of the sample, s.
    pub t0: f64,
    /// Orientation at `t0`.
    pub rotation: DMat3,
    /// Position at `t0`, m.
    pub position: DVec3,
    /// Velocity at `t0`, m/s.
    pub velocity: DVec3,
    /// Angular velocity (world frame, held), rad/s.
    pub angular_velocity: DVec3,
    /// Acceleration (held), m/s².
    pub acceleration: DVec3,
}

impl SampledMotion {
    /// The extrapolated state at time `t`, s: the orientation turns at the
    /// angular velocity, `R(t) = exp([ω (t − t0)]×) R(t0)`. (Held instead,
    /// a pinned rope end on a turning body counter-rotated at `−ω` in its
    /// relative coordinates while its base stood still, and every new sample
    /// swung the whole rope by `ω h` about the pin: 6e8 N·m of first
    /// residual per sub-step in `examples/tow_rope.rs` while steering.)
    pub fn at(&self, t: f64) -> BaseState {
        let dt = t - self.t0;
        BaseState {
            rotation: DMat3::from_quat(DQuat::from_scaled_axis(self.angular_velocity * dt)) * self.rotation,
            position: self.position + self.velocity * dt + 0.5 * self.acceleration * dt * dt,
            angular_velocity: self.angular_velocity,
            velocity: self.velocity + self.acceleration * dt,
            angular_acceleration: DVec3::ZERO,
            acceleration: self.acceleration,
        }
    }
}

/// How a frame moves (a chain's base, an anchor spring's target): fixed,
/// sampled, or a prescribed function of time. The first two are data:
/// they clone, compare and print; a cloned chain never shares its motion
/// with the original.
#[derive(Clone)]
pub enum BaseMotion {
    /// At rest.
    Fixed(BaseState),
    /// Sampled and extrapolated (a body another engine moves).
    Sampled(SampledMotion),
    /// Prescribed motion `t ↦ state` (kinematic body, moving crane hook…).
    Prescribed(Arc<dyn Fn(f64) -> BaseState + Send + Sync>),
}

impl BaseMotion {
    /// At rest at the world point `p` (m), axes along the world's.
    pub fn point(p: DVec3) -> Self {
        BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, p))
    }

    /// The state at time `t`, s.
    pub fn at(&self, t: f64) -> BaseState {
        match self {
            BaseMotion::Fixed(s) => *s,
            BaseMotion::Sampled(m) => m.at(t),
            BaseMotion::Prescribed(f) => f(t),
        }
    }
}

impl std::fmt::Debug for BaseMotion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BaseMotion::Fixed(s) => f.debug_tuple("Fixed").field(s).finish(),
            BaseMotion::Sampled(m) => f.debug_tuple("Sampled").field(m).finish(),
            BaseMotion::Prescribed(_) => f.write_str("Prescribed(..)"),
        }
    }
}

/// A spring–damper holding a point of a link to a (possibly moving) world
/// point, optionally also holding the link's orientation. Implicit: its
/// stiffness enters the articulated-body solve.
#[derive(Debug, Clone)]
pub struct AnchorSpring {
    /// Sub-joint index whose link is held.
    pub link: usize,
    /// Held point in the link frame, m.
    pub local_point: DVec3,
    /// Target: the world point is the motion's origin (position and
    /// velocity; its orientation is not used).
    pub target: BaseMotion,
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
        let target = self.target.at(t);
        let mut w = spring_to(at, target.position, target.velocity, self.stiffness, self.damping);
        if let Some((rt, kr, cr)) = self.rotation {
            let err = rotation_vector(&(at.rotation * rt.transpose()));
            w.moment = -err * kr - at.angular_velocity * cr;
            w.stiffness.a = DMat3::from_diagonal(DVec3::splat(kr));
            w.damping.a = DMat3::from_diagonal(DVec3::splat(cr));
        }
        w
    }

    fn energy(&self, t: f64, at: &PointState) -> f64 {
        let target = self.target.at(t).position;
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

/// [`SubJoint::code`]'s bit for a sub-joint with a pre-rotation.
pub(crate) const JOINT_TURNED: u8 = 4;
/// [`SubJoint::code`]'s bit for a sub-joint with an offset.
pub(crate) const JOINT_OFFSET: u8 = 8;
