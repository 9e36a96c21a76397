//! A rope: the beam-element chain of REFERENCE §1 built from a section, a
//! length, a number of elements, an initial centreline and its end
//! conditions, with the bodies that hang on it as lumped links.
//!
//! ## Discretisation
//! Element `i` is a rigid segment of length `L_e = L/N` carrying the
//! element's mass `μ L_e` (centre at mid-length) and its rotary inertia
//! (`μ L_e (L_e²/12 + r²/4)` transverse, `μ L_e r²/2` axial). It is joined to
//! its inboard neighbour (or to the start anchor) by a 6-DOF elastic joint:
//! bending about local z then y (`EI/L_e`, or `EI2/L_e`), torsion about the
//! element axis x (`GJ/L_e`), then the axial slide (`EA/L_e`, engineering
//! strain: the gap is `ε L_e`) and two shear slides (`GA/L_e`). The local x
//! axis of each element is its tangent. The coordinates of the relative
//! rotation are Euler angles z–y–x, small for every element of a converged
//! discretisation; large overall rotations are carried by the recursion, so
//! geometric nonlinearity is exact as `N → ∞`. Bending and torsion act
//! through one objective law on the rotation vector of the relative rotation
//! ([`RotationSpring`]: energy ½θᵀ diag(GJ, EI₂, EI)/L_e θ), not a spring
//! per angle. A pinned start has free bending and a per-angle torsion
//! spring (2GJ/L_e: the half element up to the pin); a clamp doubles the
//! first joint's stiffnesses likewise.

use super::cable::ElementForces;
use super::chain::{AnchorSpring, BaseMotion, BaseState, Chain, JointKind, LinkLoad, LinkMass, RotationSpring, SpringLaw, SubJoint, IN_CHAIN};
use super::material::RopeSection;
use glam::{DMat3, DQuat, DVec3, EulerRot};
use thiserror::Error;

/// Largest turn (rad) of a rope's laid path at one node: 179.9°. A fold
/// laid flat (180°) is refused ([`RopeBuilder::build`]); a fold laid open
/// by 5 mm over 1 m legs (179.7°) runs.
pub const FOLD_LIMIT: f64 = 179.9 * std::f64::consts::PI / 180.0;

/// Sub-joints per rope element.
pub const ELEMENT_DOFS: usize = 6;

/// Errors building a rope.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum RopeError {
    /// A parameter is out of range or not finite.
    #[error("rope parameter `{name}` = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What is wrong.
        reason: &'static str,
    },
    /// The initial path is unusable.
    #[error("rope path is invalid: {0}")]
    InvalidPath(String),
    /// The initial path is longer than the rope by more than the rope can
    /// stretch (typically a body placed farther from the anchor than the
    /// rope length).
    #[error(
        "the rope's initial path is {stretch:.3} m ({:.1} %) longer than the rope ({length} m): it would start stretched beyond {:.1} % (its breaking strain, or 2 % without a breaking load); place the body within the rope length or lengthen the rope",
        100.0 * stretch / length,
        100.0 * limit
    )]
    InitialStretch {
        /// Path length minus rope length, m.
        stretch: f64,
        /// Unstretched rope length, m.
        length: f64,
        /// The largest initial strain accepted (dimensionless).
        limit: f64,
    },
}

/// A rigid body that hangs on (or carries) a rope, as a lumped link of the
/// rope's chain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LumpedBody {
    /// Mass, kg.
    pub mass: f64,
    /// Rotational inertia about the centre of mass in the body frame, kg·m².
    pub inertia: DMat3,
    /// Initial position of the body frame origin (world), m.
    pub position: DVec3,
    /// Initial orientation.
    pub rotation: DMat3,
    /// Centre of mass in the body frame, m.
    pub com: DVec3,
}

impl LumpedBody {
    /// A solid sphere of mass `mass` (kg) and radius `radius` (m) at `position`.
    pub fn sphere(mass: f64, radius: f64, position: DVec3) -> Self {
        let i = 0.4 * mass * radius * radius;
        LumpedBody { mass, inertia: DMat3::from_diagonal(DVec3::splat(i)), position, rotation: DMat3::IDENTITY, com: DVec3::ZERO }
    }
}

/// How the rope's start is held.
#[derive(Debug, Clone)]
pub enum RopeStart {
    /// Pinned (bending free, torsion held) to a frame that is fixed or moves
    /// as prescribed; the frame origin is the rope's first point.
    Pinned(BaseMotion),
    /// Clamped (tangent and twist fixed to the frame as initially laid).
    Clamped(BaseMotion),
    /// A free start: the first element floats (three slides along the world
    /// axes, then three rotations, re-charted after every step so the
    /// Euler angles never approach their singularity). A path is required.
    Free,
    /// Held by a body that slides on a prismatic joint to the world (a
    /// trolley): the body is a link of the rope's chain.
    SlidingBody {
        /// The body.
        body: LumpedBody,
        /// Sliding axis, world frame (unit).
        axis: DVec3,
        /// Rope attachment point in the body frame, m.
        anchor: DVec3,
        /// Whether the rope is clamped (else pinned) to the body.
        clamp: bool,
    },
    /// Held by a free body (a car towing on the rope, a buoy): the body is
    /// the chain's floating root, its six coordinates three slides along
    /// the axes of its initial frame and three rotations, re-charted after
    /// every step so the angles never approach their singularity (as a
    /// [`Free`](Self::Free) start's).
    FloatingBody {
        /// The body.
        body: LumpedBody,
        /// Rope attachment point in the body frame, m.
        anchor: DVec3,
        /// Whether the rope is clamped (else pinned) to the body.
        clamp: bool,
    },
}

/// Sub-joint whose link is a [`RopeStart::FloatingBody`] (its rotations
/// are the sub-joints 3, 4 and 5).
pub const FLOATING_BODY_LINK: usize = 5;

/// How the rope's end is held.
#[derive(Clone)]
#[allow(clippy::large_enum_variant)] // built once per rope; boxing would only complicate the builder
pub enum RopeEnd {
    /// Free end.
    Free,
    /// Pinned to a world point: the origin of a fixed, sampled or
    /// prescribed frame (`BaseMotion::point(p)` for a fixed point).
    Pinned(BaseMotion),
    /// Clamped at a world point: position and the initial tangent held.
    Clamped(BaseMotion),
    /// A body hangs on the end (hook, payload).
    Body {
        /// The body.
        body: LumpedBody,
        /// Attachment point in the body frame, m.
        anchor: DVec3,
        /// Clamped (else a ball joint).
        clamp: bool,
    },
}

impl std::fmt::Debug for RopeEnd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RopeEnd::Free => f.write_str("Free"),
            RopeEnd::Pinned(m) => f.debug_tuple("Pinned").field(m).finish(),
            RopeEnd::Clamped(m) => f.debug_tuple("Clamped").field(m).finish(),
            RopeEnd::Body { body, anchor, clamp } => f.debug_struct("Body").field("body", body).field("anchor", anchor).field("clamp", clamp).finish(),
        }
    }
}

/// How far a tension-only (slack) element may shorten, as a fraction of
/// its length, before it pushes back with its axial stiffness
/// ([`SubJoint::stop`](crate::cable::SubJoint::stop) = −`SLACK_STOP` · L_e;
/// dimensionless). A slack element's shortening stands for the rope
/// buckling inside it; a chord of half the element's length stands for
/// the rope inside it bent into a 217° circular arc, the most a rope
/// bends within one element. At zero length (the stop before
/// 2026-11-28) a rope striking a plate at 30 m/s with one end first
/// telescoped elements to nothing, where their bending springs no longer
/// move any node, and the cable stopped ("Newton did not converge")
/// 70–110 ms after the strike.
pub const SLACK_STOP: f64 = 0.5;

/// Default [`RopeBuilder::end_stiffness_factor`]: the implicit spring that
/// pins a rope's end to a world point or a body is 1000 times the
/// element's axial stiffness `EA/L_e`. The last element's axial spring is
/// stiffened by `f/(f − 1)` (here 1.001) so that the two in series keep
/// the rope's axial compliance exactly (since 2026-11-28; before, the
/// anchor added 1/(1000 N) of the rope's compliance).
///
/// Why it is a setting (measured 2026-11-28, docs/architecture.md, "The
/// end anchor's stiffness"): the anchor closes a loop through the whole
/// rope in relative coordinates, and a stiff closure makes Newton's
/// residual strongly nonlinear in every joint angle. A 12 m, 16 mm steel
/// rope (48 elements, τ = 0.01 s) pinned 10 m apart and laid as a
/// horizontal parabola takes 98 Newton iterations per frame step in the
/// air at 1000 and 42 at 2; with still-air drag, landing on the ground and
/// coming to rest (`slack_rope_on_ground.toml`), 39 at 1000 and 16 at 2.
/// (Landing on the ground it stopped at 0.80 s at 1000 until a failed
/// contact pass was taken again with its contacts found more often, the
/// same day.) But a 20 kg ball resting on a damped taut rope jitters more
/// on a softer anchor (fastest in each later second ≤ 2.7 cm/s at 1000,
/// up to 2.9 at 300, 4.3 at 100, 5.1 at 30, 6.9 at 2): not understood,
/// so the default stays.
pub const END_STIFFNESS_FACTOR: f64 = 1e3;

/// The rotational part of a clamped end's anchor, as a multiple of the
/// last element's bending stiffness `max(EI, GJ)/L_e` (a compliance of
/// 1/1000 of one joint's, not compensated).
pub const END_ROTATION_STIFFNESS_FACTOR: f64 = 1e3;

/// Most elements a rope may have (a 100 000-element rope takes about
/// 0.55 GB, measured); more is refused with a
/// [`RopeError::InvalidParameter`] instead of exhausting memory (2³¹
/// elements asked for 51 GB and aborted).
pub const MAX_SEGMENTS: usize = 100_000;

/// Builder of a [`RopeModel`].
#[derive(Debug, Clone)]
#[must_use = "Builder functions return the updated builder"]
pub struct RopeBuilder {
    length: f64,
    segments: usize,
    section: RopeSection,
    diameter: f64,
    shear_stiffness: Option<f64>,
    damping: f64,
    path: Option<Vec<DVec3>>,
    start: RopeStart,
    end: RopeEnd,
    gravity: DVec3,
    end_stiffness_factor: f64,
    stress_free_shape: bool,
    tension_only: bool,
    linear_damping: f64,
    angular_damping: f64,
}

/// Where things are in a rope's chain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RopeLayout {
    /// Number of elements `N`.
    pub elements: usize,
    /// Unstretched element length `L_e`, m.
    pub element_length: f64,
    /// Index of the first sub-joint of element 0.
    pub first: usize,
    /// Where the start body (trolley) sits in the chain, if any.
    pub start_body: Option<BodyInChain>,
    /// Where the end body (hook, payload) sits in the chain, if any.
    pub end_body: Option<BodyInChain>,
    /// The first element floats (free start): its six sub-joints are three
    /// world slides and three rotations, not an elastic joint.
    pub free_start: bool,
    /// The chain's root is a free body ([`RopeStart::FloatingBody`]): its
    /// six sub-joints (three slides, three rotations) come before the
    /// first element.
    pub floating_start: bool,
}

/// Where a lumped body sits in a chain: the link that carries it and the
/// body frame relative to that link's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyInChain {
    /// Sub-joint index whose link carries the body.
    pub link: usize,
    /// Body frame orientation in the link frame.
    pub rotation: DMat3,
    /// Body frame origin in the link frame, m.
    pub origin: DVec3,
}

impl RopeLayout {
    /// Sub-joint index of DOF `k` (0..6: bend z, bend y, torsion, axial,
    /// shear y, shear z) of element `i`'s inboard joint.
    pub fn dof(&self, i: usize, k: usize) -> usize {
        self.first + ELEMENT_DOFS * i + k
    }
    /// Sub-joint index whose link is element `i`'s rigid segment.
    pub fn element_link(&self, i: usize) -> usize {
        self.dof(i, ELEMENT_DOFS - 1)
    }
}

/// A further rope in the same chain, grafted as a limb onto a body of it
/// ([`RopeModel::graft`]): a second leg of a sling, a second rope on a hub.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RopePart {
    /// Where its elements are in the chain (element 0 at the body it hangs
    /// from).
    pub layout: RopeLayout,
    /// Section properties.
    pub section: RopeSection,
    /// Diameter, m.
    pub diameter: f64,
    /// Unstretched length, m.
    pub length: f64,
    /// The rope as its user described it runs the other way: from the far
    /// end (its start) to the body (its end). Queries by arc length and node
    /// lists are given in the user's direction.
    pub reversed: bool,
}

/// A built rope: its chain and initial coordinates.
#[derive(Debug, Clone)]
pub struct RopeModel {
    /// The chain.
    pub chain: Chain,
    /// Layout of the chain.
    pub layout: RopeLayout,
    /// Initial coordinates.
    pub q0: Vec<f64>,
    /// Section properties.
    pub section: RopeSection,
    /// Shear stiffness GA used, N.
    pub shear_stiffness: f64,
    /// Rope diameter, m.
    pub diameter: f64,
    /// Unstretched length, m.
    pub length: f64,
    /// Further ropes grafted onto bodies of this chain (part `k ≥ 1` is
    /// `parts[k − 1]`; part 0 is the rope described by `layout`).
    pub parts: Vec<RopePart>,
}

fn check(name: &'static str, value: f64, positive: bool) -> Result<(), RopeError> {
    if !value.is_finite() {
        return Err(RopeError::InvalidParameter { name, value, reason: "not a finite number" });
    }
    if positive && value <= 0.0 {
        return Err(RopeError::InvalidParameter { name, value, reason: "must be > 0" });
    }
    if value < 0.0 {
        return Err(RopeError::InvalidParameter { name, value, reason: "must be ≥ 0" });
    }
    Ok(())
}

impl RopeBuilder {
    /// A rope of unstretched length `length` (m) cut into `segments`
    /// elements, with section `section` and diameter `diameter` (m).
    /// Defaults: pinned at the world origin, free end, hanging straight
    /// down, no damping, gravity −9.81 m/s² along y, shear stiffness GA = EA,
    /// tension-only axial law ([`RopeBuilder::tension_only`]).
    pub fn new(length: f64, segments: usize, section: RopeSection, diameter: f64) -> Self {
        RopeBuilder {
            length,
            segments,
            section,
            diameter,
            shear_stiffness: None,
            damping: 0.0,
            path: None,
            start: RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, DVec3::ZERO))),
            end: RopeEnd::Free,
            gravity: DVec3::new(0.0, -9.81, 0.0),
            end_stiffness_factor: END_STIFFNESS_FACTOR,
            stress_free_shape: false,
            tension_only: true,
            linear_damping: 0.0,
            angular_damping: 0.0,
        }
    }

    /// The unstretched length, m.
    pub fn length(&self) -> f64 {
        self.length
    }
    /// Velocity damping of the rope's elements, 1/s: each element feels
    /// `−c m v` at its centre of mass (`c` = `linear`) and `−c I ω`
    /// (`c` = `angular`), as rapier's `Damping` does for a body — the
    /// simplest still-air drag, which lets a slack rope settle. Implicit
    /// (its tangent enters the solve), so any rate is stable. Default 0.
    pub fn velocity_damping(mut self, linear: f64, angular: f64) -> Self {
        self.linear_damping = linear;
        self.angular_damping = angular;
        self
    }
    /// Whether the rope's axial law is tension-only. With `true` each
    /// element's axial force is `max(0, EA/L_e · u + c u̇)`, the spring and
    /// its damper clamped together, so zero once the element is not pulling
    /// ([`SpringLaw::TensionOnly`]):
    /// a slack rope neither pushes nor damps axially (bending and torsion
    /// stay), so a payload placed closer to the anchor than the rope length
    /// falls until the rope is taut instead of being pushed away.
    ///
    /// Default `true`: a wire rope, chain or fibre line. `false` keeps the
    /// linear law in compression too, for rods and beams (a cantilever, a
    /// pre-curved hose that must push). Newton solves the kink by an active
    /// set frozen per solve (`docs/architecture.md`, "Slack"); a static
    /// solve ([`Cable::solve_static`](super::Cable::solve_static)) takes the
    /// taut branch and refuses an equilibrium that needs the rope to push.
    pub fn tension_only(mut self, yes: bool) -> Self {
        self.tension_only = yes;
        self
    }
    /// Shear stiffness GA, N (default: EA, effectively rigid but finite).
    pub fn shear_stiffness(mut self, ga: f64) -> Self {
        self.shear_stiffness = Some(ga);
        self
    }
    /// Stiffness-proportional damping time constant τ, s: every joint
    /// spring k gets a damper τ·k. On a tension-only rope the axial damper
    /// is clamped with its spring (`max(0, k u + τ k u̇)`); a rope that
    /// unloads faster than `u/τ` (a payload rebounding from a snap) can
    /// make Newton fail (`docs/architecture.md`, "Slack").
    pub fn damping(mut self, tau: f64) -> Self {
        self.damping = tau;
        self
    }
    /// Initial centreline polyline (world, m). Its first point must be the
    /// start anchor point. A path longer than the rope pre-strains a rope
    /// held at both ends (up to its breaking strain, else
    /// [`RopeError::InitialStretch`]); a rope with a free end lies along it
    /// unstretched from its held end (its start if both are free) and
    /// ends where its length does.
    pub fn path(mut self, points: Vec<DVec3>) -> Self {
        self.path = Some(points);
        self
    }
    /// Makes the initial path the stress-free shape (a pre-curved beam, a
    /// kinked wire): each element's initial relative rotation becomes the
    /// constant frame rotation `C` of its joint (REFERENCE §1 (2)) and its
    /// initial gap the rest stretch, so the coordinates start at zero and
    /// measure the deformation from that shape. Default `false`: a rope is
    /// straight when unstressed, and a curved path is a deformed state.
    pub fn stress_free_shape(mut self, yes: bool) -> Self {
        self.stress_free_shape = yes;
        self
    }
    /// How the start is held.
    pub fn start(mut self, start: RopeStart) -> Self {
        self.start = start;
        self
    }
    /// How the end is held.
    pub fn end(mut self, end: RopeEnd) -> Self {
        self.end = end;
        self
    }
    /// Gravity, m/s².
    pub fn gravity(mut self, g: DVec3) -> Self {
        self.gravity = g;
        self
    }
    /// Stiffness of the implicit spring that pins an end to a world point,
    /// as a multiple of the element axial stiffness `EA/L_e` (default
    /// [`END_STIFFNESS_FACTOR`], 1000; > 0). Above 1 the last element's axial
    /// spring is stiffened to `f/(f − 1)·EA/L_e`, so that the two in series
    /// keep the rope's axial compliance exactly; at 1 or below the anchor
    /// adds `1/f` of one element's compliance.
    pub fn end_stiffness_factor(mut self, f: f64) -> Self {
        self.end_stiffness_factor = f;
        self
    }

    fn start_point(&self) -> DVec3 {
        match &self.start {
            RopeStart::Pinned(b) | RopeStart::Clamped(b) => b.at(0.0).position,
            RopeStart::SlidingBody { body, anchor, .. } | RopeStart::FloatingBody { body, anchor, .. } => body.position + body.rotation * *anchor,
            RopeStart::Free => self.path.as_ref().and_then(|p| p.first().copied()).unwrap_or(DVec3::ZERO),
        }
    }

    /// Builds the rope.
    pub fn build(self) -> Result<RopeModel, RopeError> {
        let s = &self.section;
        check("length", self.length, true)?;
        check("diameter", self.diameter, true)?;
        check("linear_density", s.linear_density, true)?;
        check("ea", s.ea, true)?;
        check("ei", s.ei, false)?;
        check("ei2", s.ei2, false)?;
        check("gj", s.gj, false)?;
        check("damping", self.damping, false)?;
        check("linear_damping", self.linear_damping, false)?;
        check("angular_damping", self.angular_damping, false)?;
        if self.segments == 0 {
            return Err(RopeError::InvalidParameter { name: "segments", value: 0.0, reason: "must be ≥ 1" });
        }
        if self.segments > MAX_SEGMENTS {
            return Err(RopeError::InvalidParameter { name: "segments", value: self.segments as f64, reason: "must be at most 100000 (MAX_SEGMENTS)" });
        }
        let ga = self.shear_stiffness.unwrap_or(s.ea);
        check("shear_stiffness", ga, true)?;
        if !self.gravity.is_finite() {
            return Err(RopeError::InvalidParameter { name: "gravity", value: f64::NAN, reason: "not finite" });
        }
        check("end_stiffness_factor", self.end_stiffness_factor, true)?;
        let bodies = [
            match &self.start {
                RopeStart::SlidingBody { body, axis, anchor, .. } => {
                    if !(axis.is_finite() && axis.length() > 0.0 && anchor.is_finite()) {
                        return Err(RopeError::InvalidParameter {
                            name: "start axis/anchor",
                            value: axis.length(),
                            reason: "must be finite, the axis non-zero",
                        });
                    }
                    Some(("start body", body))
                }
                RopeStart::FloatingBody { body, anchor, .. } => {
                    if !anchor.is_finite() {
                        return Err(RopeError::InvalidParameter { name: "start anchor", value: f64::NAN, reason: "not finite" });
                    }
                    Some(("start body", body))
                }
                _ => None,
            },
            match &self.end {
                RopeEnd::Body { body, anchor, .. } => {
                    if !anchor.is_finite() {
                        return Err(RopeError::InvalidParameter { name: "end anchor", value: f64::NAN, reason: "not finite" });
                    }
                    Some(("end body", body))
                }
                _ => None,
            },
        ];
        for (name, body) in bodies.into_iter().flatten() {
            check(name, body.mass, true)?;
            let finite = body.inertia.is_finite() && body.position.is_finite() && body.rotation.is_finite() && body.com.is_finite();
            // A rotational inertia must be symmetric positive semi-definite:
            // non-negative diagonal at least.
            let diag = [body.inertia.x_axis.x, body.inertia.y_axis.y, body.inertia.z_axis.z];
            if !finite || diag.iter().any(|d| *d < 0.0) {
                return Err(RopeError::InvalidParameter {
                    name,
                    value: body.mass,
                    reason: "inertia, position, rotation and centre of mass must be finite, the inertia's diagonal ≥ 0",
                });
            }
        }
        let n = self.segments;
        let le = self.length / n as f64;
        let start = self.start_point();
        let free_start = matches!(self.start, RopeStart::Free);
        if free_start && self.path.is_none() {
            return Err(RopeError::InvalidPath("a free start needs a path".into()));
        }
        let path = match &self.path {
            Some(p) => p.clone(),
            None => vec![start, start + DVec3::new(0.0, -self.length, 0.0)],
        };
        // A rope with a free end cannot hold a stretch (released, it
        // snaps back along its whole length: a free 4 m steel rope laid on
        // a path 0.4 mm longer failed its solve at 0.16 s, one on a path
        // 1 % longer was "strained by 226 %" at its first step): laid
        // along a path longer than itself, it lies along the path from its
        // held end (its start if both are free) and ends where its length
        // does.
        let free_end = matches!(self.end, RopeEnd::Free);
        let path = if (free_start || free_end) && !self.stress_free_shape { along_for(&path, self.length, free_start && !free_end) } else { path };
        let nodes = resample(&path, n)?;
        // (A free start is where the rope now begins.)
        let start = if free_start { nodes[0] } else { start };
        if !self.stress_free_shape {
            let path_length: f64 = nodes.windows(2).map(|w| w[0].distance(w[1])).sum();
            let limit = if s.min_breaking_load > 0.0 { s.min_breaking_load / s.ea } else { 0.02 };
            let stretch = path_length - self.length;
            if stretch > limit * self.length {
                return Err(RopeError::InitialStretch { stretch, length: self.length, limit });
            }
        }
        if nodes[0].distance(start) > 1e-3 {
            return Err(RopeError::InvalidPath(format!("first path point {:?} is not the start anchor {:?}", nodes[0], start)));
        }
        // Element frames by parallel transport (no initial twist).
        let mut rots = Vec::with_capacity(n);
        let mut last = DVec3::ZERO;
        for i in 0..n {
            let d = (nodes[i + 1] - nodes[i]).normalize();
            // A path that doubles back on itself within one node (a fold
            // laid flat, its two legs on one line) would lie inside itself,
            // and the joint's bending law (a rotation vector) has no
            // direction at 180°: refused, naming the place.
            if last.dot(d) < FOLD_LIMIT.cos() {
                return Err(RopeError::InvalidPath(format!(
                    "the path turns back on itself by {:.2}° at {:.3} m along the rope (node {i}, at {:?}): its two legs would lie inside each other; open the fold by at least the rope's diameter",
                    last.dot(d).clamp(-1.0, 1.0).acos().to_degrees(),
                    i as f64 * le,
                    nodes[i]
                )));
            }
            last = d;
            let r = if i == 0 {
                let helper = if d.y.abs() < 0.9 { DVec3::Y } else { DVec3::X };
                let z = d.cross(helper).normalize();
                let y = z.cross(d);
                DMat3::from_cols(d, y, z)
            } else {
                let prev: DMat3 = rots[i - 1];
                DMat3::from_quat(DQuat::from_rotation_arc(prev.x_axis, d)) * prev
            };
            rots.push(r);
        }
        let tau = self.damping;
        let rho = s.linear_density;
        let r = 0.5 * self.diameter;
        let me = rho * le;
        let it = me * (le * le / 12.0 + r * r / 4.0);
        let element_mass = LinkMass {
            linear_damping: self.linear_damping,
            angular_damping: self.angular_damping,
            ..LinkMass::new(me, DVec3::new(0.5 * le, 0.0, 0.0), DMat3::from_diagonal(DVec3::new(0.5 * me * r * r, it, it)))
        };
        let mut joints = Vec::with_capacity(ELEMENT_DOFS * n + 6);
        let mut q0 = Vec::with_capacity(ELEMENT_DOFS * n + 6);
        let identity = DMat3::IDENTITY;
        let spring = |kind, axis, k: f64, link| SubJoint {
            kind,
            axis,
            offset: DVec3::ZERO,
            pre_rotation: identity,
            stiffness: k,
            damping: tau * k,
            rest: 0.0,
            link,
            law: SpringLaw::Linear,
            stop: f64::NEG_INFINITY,
        };
        // Root: base frame and (for a trolley) its prismatic sub-joint.
        let (base, clamp_start, parent_rot, first_offset, start_body) = match &self.start {
            RopeStart::Pinned(b) => (b.clone(), false, b.at(0.0).rotation, DVec3::ZERO, None),
            RopeStart::Clamped(b) => (b.clone(), true, b.at(0.0).rotation, DVec3::ZERO, None),
            RopeStart::SlidingBody { body, axis, anchor, clamp } => {
                let base = BaseMotion::Fixed(BaseState::fixed(body.rotation, body.position));
                let mut j = spring(JointKind::Prismatic, body.rotation.transpose() * axis.normalize(), 0.0, None);
                j.link = Some(LinkMass::new(body.mass, body.com, body.inertia));
                joints.push(j);
                q0.push(0.0);
                (base, *clamp, body.rotation, *anchor, Some(BodyInChain { link: 0, rotation: DMat3::IDENTITY, origin: DVec3::ZERO }))
            }
            RopeStart::FloatingBody { body, anchor, clamp } => {
                // The body's initial frame is the base; three slides along
                // its axes, then three rotations, the last carrying it.
                let base = BaseMotion::Fixed(BaseState::fixed(body.rotation, body.position));
                joints.extend([
                    spring(JointKind::Prismatic, DVec3::X, 0.0, None),
                    spring(JointKind::Prismatic, DVec3::Y, 0.0, None),
                    spring(JointKind::Prismatic, DVec3::Z, 0.0, None),
                    spring(JointKind::Revolute, DVec3::Z, 0.0, None),
                    spring(JointKind::Revolute, DVec3::Y, 0.0, None),
                    spring(JointKind::Revolute, DVec3::X, 0.0, Some(LinkMass::new(body.mass, body.com, body.inertia))),
                ]);
                q0.extend([0.0; 6]);
                (base, *clamp, body.rotation, *anchor, Some(BodyInChain { link: FLOATING_BODY_LINK, rotation: DMat3::IDENTITY, origin: DVec3::ZERO }))
            }
            RopeStart::Free => (BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, start)), false, DMat3::IDENTITY, DVec3::ZERO, None),
        };
        let first = joints.len();
        let mut rotation_springs = Vec::with_capacity(n);
        for i in 0..n {
            let (kb, kb2, kt) = if i == 0 {
                if clamp_start {
                    (2.0 * s.ei / le, 2.0 * s.ei2 / le, 2.0 * s.gj / le)
                } else {
                    (0.0, 0.0, 2.0 * s.gj / le)
                }
            } else {
                (s.ei / le, s.ei2 / le, s.gj / le)
            };
            if i == 0 && free_start {
                // Floating first element: world slides, then rotations.
                let mut jz = spring(JointKind::Revolute, DVec3::Z, 0.0, None);
                jz.pre_rotation = rots[0];
                joints.extend([
                    spring(JointKind::Prismatic, DVec3::X, 0.0, None),
                    spring(JointKind::Prismatic, DVec3::Y, 0.0, None),
                    spring(JointKind::Prismatic, DVec3::Z, 0.0, None),
                    jz,
                    spring(JointKind::Revolute, DVec3::Y, 0.0, None),
                    spring(JointKind::Revolute, DVec3::X, 0.0, Some(element_mass)),
                ]);
                q0.extend([0.0; 6]);
                continue;
            }
            let mut jz = spring(JointKind::Revolute, DVec3::Z, kb, None);
            let jy = spring(JointKind::Revolute, DVec3::Y, kb2, None);
            let jx = spring(JointKind::Revolute, DVec3::X, kt, None);
            let mut px = spring(JointKind::Prismatic, DVec3::X, s.ea / le, None);
            if self.tension_only {
                px.law = SpringLaw::TensionOnly;
                // A slack element shortens to half its length, no further.
                px.stop = -SLACK_STOP * le;
            }
            let py = spring(JointKind::Prismatic, DVec3::Y, ga / le, None);
            let pz = spring(JointKind::Prismatic, DVec3::Z, ga / le, Some(element_mass));
            let (angles, offset) = if i == 0 {
                jz.pre_rotation = parent_rot.transpose() * rots[0];
                ((0.0, 0.0, 0.0), first_offset)
            } else if self.stress_free_shape {
                jz.pre_rotation = rots[i - 1].transpose() * rots[i];
                ((0.0, 0.0, 0.0), DVec3::new(le, 0.0, 0.0))
            } else {
                let rel = rots[i - 1].transpose() * rots[i];
                (DQuat::from_mat3(&rel).to_euler(EulerRot::ZYX), DVec3::new(le, 0.0, 0.0))
            };
            jz.offset = offset;
            if i > 0 || clamp_start {
                rotation_springs.push(RotationSpring { first: joints.len(), k: DVec3::new(kt, kb2, kb), tau });
            }
            let gap = nodes[i + 1].distance(nodes[i]) - le;
            if self.stress_free_shape {
                px.rest = gap;
            }
            joints.extend([jz, jy, jx, px, py, pz]);
            q0.extend([angles.0, angles.1, angles.2, gap, 0.0, 0.0]);
        }
        let tip_link = first + ELEMENT_DOFS * n - 1;
        let mut end_body = None;
        let mut anchors = Vec::new();
        let k_end = self.end_stiffness_factor * s.ea / le;
        match &self.end {
            RopeEnd::Free => {}
            RopeEnd::Pinned(target) | RopeEnd::Clamped(target) => {
                // The anchor spring in series with the last element's axial
                // spring: that spring is stiffened so that the two together
                // have the element's own compliance L_e/EA exactly.
                let last_axial = first + ELEMENT_DOFS * (n - 1) + 3;
                if self.end_stiffness_factor > 1.0 && joints.get(last_axial).is_some_and(|j| j.kind == JointKind::Prismatic && j.axis == DVec3::X) {
                    let f = self.end_stiffness_factor;
                    joints[last_axial].stiffness = s.ea / le * f / (f - 1.0);
                    joints[last_axial].damping = tau * joints[last_axial].stiffness;
                    // Laid stretched, the pair shares the element's stretch
                    // in proportion to their compliances: the last element
                    // keeps (f − 1)/f of it and the anchor spring takes the
                    // rest, so that the rope starts with one tension along
                    // it (the end node sits short of its pin by that rest).
                    // (A slack element carries nothing: it stays as laid.)
                    let rest = joints[last_axial].rest;
                    if q0[last_axial] > rest || !self.tension_only {
                        q0[last_axial] = rest + (q0[last_axial] - rest) * (f - 1.0) / f;
                    }
                }
                let rotation = if matches!(self.end, RopeEnd::Clamped(_)) {
                    let kr = END_ROTATION_STIFFNESS_FACTOR * s.ei.max(s.gj).max(1e-9) / le;
                    Some((rots[n - 1], kr, tau * kr))
                } else {
                    None
                };
                anchors.push(AnchorSpring {
                    link: tip_link,
                    local_point: DVec3::new(le, 0.0, 0.0),
                    target: target.clone(),
                    stiffness: k_end,
                    damping: tau * k_end,
                    rotation,
                });
            }
            RopeEnd::Body { body, anchor, clamp } => {
                let c = rots[n - 1].transpose() * body.rotation;
                let local = LinkMass::new(body.mass, c * (body.com - *anchor), c * body.inertia * c.transpose());
                if *clamp {
                    let shifted = LinkMass { com: local.com + DVec3::new(le, 0.0, 0.0), ..local };
                    let lm = joints[tip_link].link.as_ref().map(|m| m.combine(&shifted));
                    joints[tip_link].link = lm;
                    end_body = Some(BodyInChain { link: tip_link, rotation: c, origin: DVec3::new(le, 0.0, 0.0) - c * *anchor });
                } else {
                    let mut jz = spring(JointKind::Revolute, DVec3::Z, 0.0, None);
                    jz.offset = DVec3::new(le, 0.0, 0.0);
                    let jy = spring(JointKind::Revolute, DVec3::Y, 0.0, None);
                    let jx = spring(JointKind::Revolute, DVec3::X, 0.0, Some(local));
                    joints.extend([jz, jy, jx]);
                    q0.extend([0.0, 0.0, 0.0]);
                    // The link frame is the last element's frame (no
                    // pre-rotation at the ball joint): the body frame sits at
                    // rotation c and origin −c·anchor in it.
                    end_body = Some(BodyInChain { link: joints.len() - 1, rotation: c, origin: -(c * *anchor) });
                }
            }
        }
        // Highest-frequency estimate (explicit schemes): element axial, shear,
        // bending, torsion, end-spring and tension-kink modes, 2√(k/m) each.
        let hanging = match &self.end {
            RopeEnd::Body { body, .. } => body.mass,
            _ => 0.0,
        } + rho * self.length;
        let t_max = 2.0 * hanging * self.gravity.length() + 0.0;
        let omega2 = [
            4.0 * s.ea.max(ga) / le / me,
            16.0 * s.ei.max(s.ei2) / le / it,
            4.0 * s.gj / le / (0.5 * me * r * r),
            if anchors.is_empty() { 0.0 } else { 4.0 * k_end / me },
            12.0 * t_max / (me * le),
        ]
        .into_iter()
        .fold(0.0, f64::max);
        let origin = start;
        let mut chain = Chain::new(joints, base, self.gravity, origin);
        *chain.anchors_mut() = anchors;
        *chain.rotation_springs_mut() = rotation_springs;
        chain.max_frequency = Some(omega2.sqrt());
        let floating_start = matches!(self.start, RopeStart::FloatingBody { .. });
        let layout = RopeLayout { elements: n, element_length: le, first, start_body, end_body, free_start, floating_start };
        let zeros = vec![0.0; q0.len()];
        let mut r = vec![0.0; q0.len()];
        chain.residual_into(0.0, &q0, &zeros, &zeros, &mut r).map_err(|e| RopeError::InvalidPath(format!("initial state: {e}")))?;
        Ok(RopeModel { chain, layout, q0, section: self.section, shear_stiffness: ga, diameter: self.diameter, length: self.length, parts: Vec::new() })
    }
}

/// `path` cut where it reaches `length` (m) along it from its first
/// point (or from its last, `from_end`); `path` itself if it is no longer.
fn along_for(path: &[DVec3], length: f64, from_end: bool) -> Vec<DVec3> {
    if path.len() < 2 || path.iter().any(|p| !p.is_finite()) {
        // (`resample` names the fault.)
        return path.to_vec();
    }
    let mut points: Vec<DVec3> = path.to_vec();
    if from_end {
        points.reverse();
    }
    let mut cut = vec![points[0]];
    let mut left = length;
    for w in points.windows(2) {
        let d = w[0].distance(w[1]);
        if d >= left {
            if d > 0.0 {
                cut.push(w[0].lerp(w[1], left / d));
            }
            if from_end {
                cut.reverse();
            }
            return cut;
        }
        left -= d;
        cut.push(w[1]);
    }
    path.to_vec()
}

/// Resamples a polyline at `n + 1` points equally spaced in arc length.
fn resample(path: &[DVec3], n: usize) -> Result<Vec<DVec3>, RopeError> {
    if path.len() < 2 {
        return Err(RopeError::InvalidPath("needs at least 2 points".into()));
    }
    if path.iter().any(|p| !p.is_finite()) {
        return Err(RopeError::InvalidPath("contains a non-finite point".into()));
    }
    let seg: Vec<f64> = path.windows(2).map(|w| w[0].distance(w[1])).collect();
    let total: f64 = seg.iter().sum();
    if total <= 0.0 {
        return Err(RopeError::InvalidPath("has zero length".into()));
    }
    let mut out = Vec::with_capacity(n + 1);
    let (mut k, mut acc) = (0usize, 0.0);
    for i in 0..=n {
        let target = total * i as f64 / n as f64;
        while k + 1 < seg.len() && acc + seg[k] < target {
            acc += seg[k];
            k += 1;
        }
        let t = if seg[k] > 0.0 { ((target - acc) / seg[k]).clamp(0.0, 1.0) } else { 0.0 };
        out.push(path[k].lerp(path[k + 1], t));
    }
    Ok(out)
}

impl RopeModel {
    /// Grafts `other` onto this chain as a limb hanging from the body at
    /// `at` (a body of this chain), and returns its part number
    /// (see [`RopeModel::parts`]). `other` must have been built with a
    /// fixed pinned or clamped start at the attachment point on the body
    /// (with the body's orientation as the base frame for a clamp); its end
    /// may be free, pinned or clamped to the world (then the chain closes a
    /// loop through an implicit anchor spring, as a rope pinned at both ends
    /// does), or a body of its own ([`RopeEnd::Body`]: a payload hung under
    /// the hub, found in the part's layout, [`RopePart::layout`]`.end_body`).
    /// The pin or clamp then moves with the body.
    /// Both chains must be at their initial coordinates and have the same
    /// gravity. `reversed`: the rope as its user described it runs from
    /// `other`'s end to the body.
    ///
    /// A two-leg sling: 1 t on two 10 m steel legs from anchors 12 m apart.
    /// ```
    /// use bevy_rapier_cable::cable::*;
    /// use bevy_rapier_cable::integrate::Scheme;
    /// use glam::{DMat3, DVec3};
    ///
    /// let steel = preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap();
    /// let (a, b, apex) = (DVec3::new(-6.0, 0.0, 0.0), DVec3::new(6.0, 0.0, 0.0), DVec3::new(0.0, -8.0, 0.0));
    /// let fixed = |p| RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, p)));
    /// // Leg 0 carries the payload (centre of mass at the attachment point).
    /// let mut model = RopeBuilder::new(10.0, 10, steel, 0.02)
    ///     .start(fixed(a))
    ///     .path(vec![a, apex])
    ///     .end(RopeEnd::Body { body: LumpedBody::sphere(1000.0, 0.3, apex), anchor: DVec3::ZERO, clamp: false })
    ///     .build()?;
    /// let payload = model.layout.end_body.unwrap();
    /// // Leg 1, built from the payload to its anchor, grafted onto the payload.
    /// let leg = RopeBuilder::new(10.0, 10, steel, 0.02)
    ///     .start(fixed(apex))
    ///     .path(vec![apex, b])
    ///     .end(RopeEnd::Pinned(BaseMotion::point(b)))
    ///     .build()?;
    /// let part = model.graft(leg, &payload, true)?;
    /// let mut cable = Cable::new(model, Scheme::default()).unwrap();
    /// for _ in 0..30 {
    ///     cable.step(1.0 / 60.0).unwrap();
    /// }
    /// let leg1 = cable.rope(part).unwrap();
    /// assert!(leg1.nodes()[0].distance(b) < 1e-3); // node 0 is the user's start
    /// assert!(leg1.tension_at(0.0) > 0.0);
    /// # Ok::<(), RopeError>(())
    /// ```
    pub fn graft(&mut self, other: RopeModel, at: &BodyInChain, reversed: bool) -> Result<usize, RopeError> {
        let base = match &other.chain.base {
            BaseMotion::Fixed(b) if other.layout.start_body.is_none() && !other.layout.free_start => *b,
            _ => return Err(RopeError::InvalidPath("a grafted rope must start at a fixed pin or clamp on the body".into())),
        };
        if other.chain.gravity != self.chain.gravity {
            return Err(RopeError::InvalidPath("a grafted rope must have the chain's gravity".into()));
        }
        if at.link >= self.chain.len() {
            return Err(RopeError::InvalidPath(format!("no link {} to graft onto", at.link)));
        }
        // The body link's pose at the initial coordinates.
        let n0 = self.q0.len();
        let zeros = vec![0.0; n0];
        let mut r = vec![0.0; n0];
        self.chain.residual_into(0.0, &self.q0, &zeros, &zeros, &mut r).map_err(|e| RopeError::InvalidPath(format!("initial state: {e}")))?;
        let (Some(rl), Some(pl)) = (self.chain.link_rotation(at.link), self.chain.link_point(at.link, DVec3::ZERO)) else {
            return Err(RopeError::InvalidPath(format!("no link {} to graft onto", at.link)));
        };
        let RopeModel { chain: oc, layout: ol, q0: oq0, section, diameter, length, .. } = other;
        let mut joints = oc.joints().to_vec();
        // Re-express the first joint frame in the body link's frame.
        let (rb, pb) = (base.rotation, base.position);
        let j0 = &mut joints[0];
        let (rj, pj) = (rb * j0.pre_rotation, pb + rb * j0.offset);
        j0.pre_rotation = rl.transpose() * rj;
        j0.offset = rl.transpose() * (pj - pl);
        let first = self.chain.add_limb(joints, Some(at.link)).map_err(RopeError::InvalidPath)?;
        for (k, f) in oc.joint_forces().iter().enumerate() {
            self.chain.set_joint_force(first + k, *f).map_err(|e| RopeError::InvalidPath(e.to_string()))?;
        }
        self.chain.anchors_mut().extend(oc.anchors().iter().map(|a| AnchorSpring { link: a.link + first, ..a.clone() }));
        self.chain.loads_mut().extend(oc.loads().iter().map(|l| LinkLoad { link: l.link + first, ..*l }));
        self.chain.rotation_springs_mut().extend(oc.rotation_springs().iter().map(|rs| RotationSpring { first: rs.first + first, ..*rs }));
        self.chain.rotation_springs_mut().sort_by_key(|rs| rs.first);
        self.chain.max_frequency = match (self.chain.max_frequency, oc.max_frequency) {
            (Some(a), Some(b)) => Some(a.max(b)),
            _ => None,
        };
        self.q0.extend(oq0);
        // Its end body (a payload under a hook block: two bodies in
        // series) is a link of the limb: its place moves with the limb.
        let end_body = ol.end_body.map(|b| BodyInChain { link: b.link + first, ..b });
        let layout = RopeLayout { first: ol.first + first, end_body, ..ol };
        self.parts.push(RopePart { layout, section, diameter, length, reversed });
        let n = self.q0.len();
        let (zeros, mut r) = (vec![0.0; n], vec![0.0; n]);
        self.chain.residual_into(0.0, &self.q0, &zeros, &zeros, &mut r).map_err(|e| RopeError::InvalidPath(format!("initial state: {e}")))?;
        Ok(self.parts.len())
    }

    /// Internal forces of element joint `i` (between element `i − 1` and
    /// `i`; joint 0 holds the start; all zero for a free start) at `(q, v)`:
    /// what the outboard part of the rope exerts on the inboard part at the
    /// joint, in element `i`'s frame (x along the element). The axial and
    /// shear forces are the slide sub-joints' spring + damper forces; the
    /// moments are the bending–torsion law's moment vector
    /// ([`Chain::joint_moment`]), objective for any rotation. Reads the
    /// kinematics of the last residual evaluation (current after a step).
    /// `None` past the last element (`i ≥ N`).
    pub fn element_forces(&self, i: usize, q: &[f64], v: &[f64]) -> Option<ElementForces> {
        (i < self.layout.elements).then(|| self.element_forces_in(&self.layout, i, q, v))
    }

    /// [`RopeModel::element_forces`] of element joint `i` of the rope laid
    /// out as `l` in this chain (the main rope or a grafted part); `i < N`.
    pub(crate) fn element_forces_in(&self, l: &RopeLayout, i: usize, q: &[f64], v: &[f64]) -> ElementForces {
        if i == 0 && l.free_start {
            return ElementForces::default();
        }
        let ch = &self.chain;
        let f = |k: usize| {
            let s = l.dof(i, k);
            ch.joints()[s].spring_force(q[s], v[s]).0
        };
        let m = ch.link_rotation(l.element_link(i)).expect(IN_CHAIN).transpose() * ch.joint_moment(l.dof(i, 0), q, v);
        ElementForces { tension: f(3), shear: [f(4), f(5)], bending: [m.z, m.y], torsion: m.x }
    }

    /// World positions of the `N + 1` nodes (element ends) after the last
    /// residual evaluation of the chain, m.
    pub fn nodes(&self) -> Vec<DVec3> {
        self.nodes_in(&self.layout, false)
    }

    /// World positions (m) or, with `velocity`, velocities (m/s) of the
    /// `N + 1` nodes of the rope laid out as `l` in this chain (the main
    /// rope or a grafted part), in the layout's order.
    pub(crate) fn nodes_in(&self, l: &RopeLayout, velocity: bool) -> Vec<DVec3> {
        let ch = &self.chain;
        let point = |link: usize, local: DVec3| if velocity { ch.link_point_velocity(link, local) } else { ch.link_point(link, local) }.expect(IN_CHAIN);
        let mut out: Vec<DVec3> =
            (0..l.elements).map(|i| if velocity { ch.joint_point_velocity(l.dof(i, 0)) } else { ch.joint_point(l.dof(i, 0)) }.expect(IN_CHAIN)).collect();
        if l.free_start {
            out[0] = point(l.element_link(0), DVec3::ZERO);
        }
        out.push(point(l.element_link(l.elements - 1), DVec3::new(l.element_length, 0.0, 0.0)));
        out
    }

    /// World pose and velocity of a body in the chain: position of the body
    /// origin (m), orientation, velocity of the origin (m/s), angular
    /// velocity (rad/s).
    pub fn body_state(&self, b: &BodyInChain) -> (DVec3, DMat3, DVec3, DVec3) {
        let ch = &self.chain;
        (
            ch.link_point(b.link, b.origin).expect(IN_CHAIN),
            ch.link_rotation(b.link).expect(IN_CHAIN) * b.rotation,
            ch.link_point_velocity(b.link, b.origin).expect(IN_CHAIN),
            ch.link_velocity(b.link).expect(IN_CHAIN).top,
        )
    }

    /// Axial force of element joint `i` (tension positive), N: `EA/L_e · u +
    /// damping`, at coordinates `q` and rates `v`.
    pub fn tension(&self, i: usize, q: &[f64], v: &[f64]) -> f64 {
        if i == 0 && self.layout.free_start {
            return 0.0;
        }
        let s = self.layout.dof(i, 3);
        self.chain.joints()[s].spring_force(q[s], v[s]).0
    }
}
