//! Implicit force elements: a force and moment at a point of a link, with
//! their 6×6 stiffness and damping tangents, entering the chain's implicit
//! solve (issue 10, item 7).
//!
//! A [`ForceElement`] sees the world state of one material point of a link
//! ([`PointState`]) and returns the wrench it applies there
//! ([`PointWrench`]): the force at the point, a moment, and the tangents
//! `K = −∂w/∂(δθ, δp)` and `C = −∂w/∂(δω, δv)` in 3×3 blocks over
//! (rotation, translation) of the point. The chain moves them to its
//! spatial frame (`Xᵀ K X`, `X` the point's motion from the link's) and
//! adds `c_q K + c_v C` to the link's articulated inertia, so a stiff
//! element stays stable at any step, as the rope's own springs do. The
//! change of the moment arm as the link turns is added by the chain.
//!
//! The articulated-body solve needs symmetric link blocks, so it uses the
//! symmetric part `½(K + Kᵀ)` (and of `C`). The residual always has the
//! element's exact wrench, so the answer does not change: a conservative
//! element (a spring from a potential of the point's position) or a linear
//! damper with a symmetric matrix keeps Newton's quadratic rate
//! (`tangent_tests::force_element_tangents_match_finite_differences`); a
//! non-symmetric one (a follower force, gyroscopic coupling) converges
//! linearly.
//!
//! The end springs that pin or clamp a rope to the world
//! ([`AnchorSpring`](super::chain::AnchorSpring)) are one; contact, drag,
//! added mass and brakes are the next ones. User elements go on a chain
//! through [`Chain::forces`](super::chain::Chain::forces) or
//! [`Cable::add_force_element`](super::cable::Cable::add_force_element).

use std::sync::Arc;

use glam::{DMat3, DVec3};

use super::spatial::M6;

/// World state of the point a force element acts on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointState {
    /// Orientation of the link (link frame to world).
    pub rotation: DMat3,
    /// The point, world, m.
    pub point: DVec3,
    /// The point's velocity, world, m/s.
    pub velocity: DVec3,
    /// The link's angular velocity, world, rad/s.
    pub angular_velocity: DVec3,
}

/// What a force element applies, world frame: at its point, or at the
/// point `arm` from it (a contact of a rope element sliding over an edge,
/// [`Span`](super::Span)).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PointWrench {
    /// Force, N, at the point `arm` from the element's point.
    pub force: DVec3,
    /// Moment, N·m.
    pub moment: DVec3,
    /// Stiffness `−∂(moment, force)/∂(δθ, δp)`, blocks `[[a, b], [c, d]]`
    /// over (rotation, displacement) of the point where the force acts
    /// (taken as a point of the link): `a` N·m/rad, `b` N·m/m = N,
    /// `c` N/rad, `d` N/m.
    pub stiffness: M6,
    /// Damping `−∂(moment, force)/∂(ω, v)`, the same blocks per unit rate
    /// (N·m·s/rad, N·s, N·s/rad, N·s/m).
    pub damping: M6,
    /// From the element's point to where the force acts, world, m (zero:
    /// at the point itself). The chain applies the force there, with its
    /// moment arm's change as the link turns and its tangents moved from
    /// there: exact for a force at a point of the link, where a moment
    /// whose arm turns with the link (a couple that is not zero) is not
    /// (measured: a contact's force moved along its element as a couple
    /// left a tangent error of 2.3, relative, against 2e-9 as a point
    /// force).
    pub arm: DVec3,
}

/// A force law at a point of a link, evaluated at every Newton iteration
/// with its tangents (implicit). `Send + Sync` so a chain can be stepped on
/// another thread.
pub trait ForceElement: Send + Sync {
    /// The wrench at time `t` (s) and point state `at`.
    fn wrench(&self, t: f64, at: &PointState) -> PointWrench;

    /// Potential energy stored in the element, J (0 for a dissipative or
    /// non-conservative one); counted in [`Cable::energy`](super::cable::Cable::energy).
    fn energy(&self, _t: f64, _at: &PointState) -> f64 {
        0.0
    }

    /// The normal force (N, ≥ 0) if the element is a contact
    /// ([`SphereContact`](super::SphereContact)), `None` otherwise: what a
    /// cable's `contact_force` reports.
    fn contact_force(&self, _t: f64, _at: &PointState) -> Option<f64> {
        None
    }

    /// Whether the element does no work on the chain but through its
    /// potential ([`ForceElement::energy`]) and dissipation: a spring to
    /// a fixed point, a contact with a fixed obstacle. A chain whose
    /// elements are all passive may be energy-checked by the integrator
    /// ([`Chain::is_passive`](super::chain::Chain::is_passive)). Default
    /// `false` (a load that does work, a moving target).
    fn is_passive(&self) -> bool {
        false
    }

    /// The branch a non-smooth law is on at time `t` (s) and point state
    /// `at` (Coulomb friction: sticking, or slipping along a direction),
    /// or `None` for a smooth law (the default) or one that is not
    /// engaged (a contact without normal force). In a Newton solve the
    /// chain holds a law that sticks at the first iterate sticking
    /// ([`ForceElement::wrench_on`]), and so one whose slip turns round
    /// between two iterates, and once the solve has converged releases
    /// those the solution contradicts
    /// ([`ForceElement::branch_disagreement`]), as it freezes a slack
    /// rope's tension-only elements
    /// ([`SecondOrderSystem::freeze_branches`](crate::integrate::SecondOrderSystem::freeze_branches)).
    fn branch(&self, _t: f64, _at: &PointState) -> Option<FrictionBranch> {
        None
    }

    /// [`ForceElement::wrench`] with the law held on `branch`. Default:
    /// the law itself.
    fn wrench_on(&self, t: f64, at: &PointState, _branch: FrictionBranch) -> PointWrench {
        self.wrench(t, at)
    }

    /// How far the state at `at` lies outside `branch`, relative to the
    /// law's limit (dimensionless, 0 inside it: Coulomb friction held
    /// sticking with a trial force 1 % over `μ F_n` gives 0.01, and so
    /// does one held slipping whose trial force is 1 % under it, or turned
    /// 0.01 rad from the held direction). Default 0.
    fn branch_disagreement(&self, _t: f64, _at: &PointState, _branch: FrictionBranch) -> f64 {
        0.0
    }
}

/// The branch of a Coulomb friction law ([`ForceElement::branch`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionBranch {
    /// The stick spring holds (`|F_trial| ≤ μ F_n`): the tangential force
    /// is the trial force.
    Stick,
    /// The contact slips: the tangential force is `μ F_n` along the trial
    /// force, whose direction (unit, world) this is. Held on this branch,
    /// the force keeps that direction (in the contact's plane): a smooth
    /// law, where the trial force's own direction swings round as the slip
    /// velocity passes zero.
    Slip(DVec3),
}

/// A force element on a link of a chain.
#[derive(Clone)]
pub struct AttachedForce {
    /// Sub-joint index whose link carries the element.
    pub link: usize,
    /// The point in the link frame, m.
    pub local_point: DVec3,
    /// The law.
    pub element: Arc<dyn ForceElement>,
}

impl std::fmt::Debug for AttachedForce {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AttachedForce").field("link", &self.link).field("local_point", &self.local_point).finish_non_exhaustive()
    }
}

/// A linear spring–damper from a point to a fixed world point, with an
/// optional linear drag on the point's velocity: `f = −k (p − target) − c v`
/// (N). The simplest implicit element: a mooring line's fairlead spring, a
/// tag line held by a person, viscous drag on a payload.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointSpring {
    /// Fixed world point the spring pulls toward, m.
    pub target: DVec3,
    /// Stiffness, N/m (≥ 0).
    pub stiffness: f64,
    /// Damping on the point's absolute velocity, N·s/m (≥ 0).
    pub damping: f64,
}

impl ForceElement for PointSpring {
    fn wrench(&self, _t: f64, at: &PointState) -> PointWrench {
        spring_to(at, self.target, DVec3::ZERO, self.stiffness, self.damping)
    }

    fn energy(&self, _t: f64, at: &PointState) -> f64 {
        0.5 * self.stiffness * at.point.distance_squared(self.target)
    }

    fn is_passive(&self) -> bool {
        true
    }
}

/// The wrench of an isotropic linear spring–damper (`stiffness` N/m,
/// `damping` N·s/m) from the point to `target` (m), which moves at
/// `target_velocity` (m/s): `f = −k (p − target) − c (v − target_velocity)`,
/// with its tangents `k I` and `c I`.
pub(crate) fn spring_to(at: &PointState, target: DVec3, target_velocity: DVec3, stiffness: f64, damping: f64) -> PointWrench {
    let mut w = PointWrench { force: -(at.point - target) * stiffness - (at.velocity - target_velocity) * damping, ..Default::default() };
    w.stiffness.d = DMat3::from_diagonal(DVec3::splat(stiffness));
    w.damping.d = DMat3::from_diagonal(DVec3::splat(damping));
    w
}

/// `Xᵀ K X`: a point tangent `k` (blocks over the rotation and the
/// displacement of the point at `p`, relative to the spatial origin) as a
/// spatial tangent about the origin. `X = [[I, 0], [p̃ᵀ, I]]` maps a spatial
/// displacement `(δθ, δx₀)` to the point's `(δθ, δx₀ + δθ × p)`.
/// Only the symmetric part of `k` is used (see the module docs).
pub(crate) fn point_to_spatial(k: &M6, px: DMat3) -> M6 {
    let b = (k.b + k.c.transpose()) * 0.5;
    let k = M6 { a: (k.a + k.a.transpose()) * 0.5, b, c: b.transpose(), d: (k.d + k.d.transpose()) * 0.5 };
    let pxt = px.transpose();
    let b = k.b + px * k.d;
    M6 { a: k.a + px * k.c + b * pxt, b, c: k.c + k.d * pxt, d: k.d }
}

/// What a [`PairElement`] applies between its two points, world frame: a
/// force on the first point (the second gets the opposite), with its
/// tangents with respect to the points' relative motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairWrench {
    /// Force on the first point, N (the second point gets `−force`).
    pub force: DVec3,
    /// Stiffness `−∂force/∂(p_a − p_b)`, N/m.
    pub stiffness: DMat3,
    /// Damping `−∂force/∂(v_a − v_b)`, N·s/m.
    pub damping: DMat3,
    /// The one direction (unit) the force and both tangents act along
    /// (`stiffness` and `damping` multiples of `n nᵀ`: a frictionless
    /// contact), if any: the solve then couples the two points along it
    /// alone (one back-substitution per chain the pair touches instead of
    /// three).
    pub normal: Option<DVec3>,
}

impl Default for PairWrench {
    /// No force, no stiffness, no damping (glam's `DMat3::default()` is
    /// the identity: a derived default gave an untouched contact 1 N/m and
    /// 1 N·s/m).
    fn default() -> Self {
        PairWrench { force: DVec3::ZERO, stiffness: DMat3::ZERO, damping: DMat3::ZERO, normal: None }
    }
}

/// A force law between two material points of a chain (on two links, or
/// twice the same link), evaluated at every Newton iteration with its
/// tangents: a contact of a rope with itself or with another rope of the
/// same cable, a spring between two links. The two points are anywhere in
/// the chain's tree (or on two chains of a
/// [`Forest`](super::chain::Forest)), so the law closes a loop; the solve
/// adds its stiffness and damping exactly (a small dense correction over
/// the pairs, see [`Chain::pairs`](super::chain::Chain::pairs)).
pub trait PairElement: Send + Sync {
    /// The force at time `t` (s) with the points at `a` and `b`.
    fn wrench(&self, t: f64, a: &PointState, b: &PointState) -> PairWrench;

    /// Potential energy stored in the element, J (0 for a dissipative one);
    /// counted in [`Cable::energy`](super::cable::Cable::energy).
    fn energy(&self, _t: f64, _a: &PointState, _b: &PointState) -> f64 {
        0.0
    }

    /// The normal force (N, ≥ 0) if the element is a contact, `None`
    /// otherwise: what a cable's `contact_force` reports.
    fn contact_force(&self, _t: f64, _a: &PointState, _b: &PointState) -> Option<f64> {
        None
    }

    /// Whether the element does no work on the chain but through its
    /// potential ([`PairElement::energy`]) and dissipation (a spring or a
    /// contact between two points of the chain), as
    /// [`ForceElement::is_passive`]. Default `false`.
    fn is_passive(&self) -> bool {
        false
    }
}

/// A [`PairElement`] between two links of a chain.
#[derive(Clone)]
pub struct AttachedPair {
    /// Sub-joint index whose link carries the first point.
    pub link_a: usize,
    /// The first point in its link's frame, m.
    pub point_a: DVec3,
    /// Sub-joint index whose link carries the second point.
    pub link_b: usize,
    /// The second point in its link's frame, m.
    pub point_b: DVec3,
    /// The law.
    pub element: Arc<dyn PairElement>,
}

impl std::fmt::Debug for AttachedPair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AttachedPair").field("link_a", &self.link_a).field("link_b", &self.link_b).finish_non_exhaustive()
    }
}

/// A linear spring–damper between two points: `f_a = −k (p_a − p_b) −
/// c (v_a − v_b)` on the first (N), the opposite on the second; zero rest
/// length. The simplest [`PairElement`] (tests, and a user's tether
/// between two links).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairSpring {
    /// Stiffness, N/m (≥ 0).
    pub stiffness: f64,
    /// Damping, N·s/m (≥ 0).
    pub damping: f64,
}

impl PairElement for PairSpring {
    fn wrench(&self, _t: f64, a: &PointState, b: &PointState) -> PairWrench {
        PairWrench {
            force: -(a.point - b.point) * self.stiffness - (a.velocity - b.velocity) * self.damping,
            stiffness: DMat3::from_diagonal(DVec3::splat(self.stiffness)),
            damping: DMat3::from_diagonal(DVec3::splat(self.damping)),
            normal: None,
        }
    }

    fn energy(&self, _t: f64, a: &PointState, b: &PointState) -> f64 {
        0.5 * self.stiffness * a.point.distance_squared(b.point)
    }

    fn is_passive(&self) -> bool {
        true
    }
}
