//! Components and messages of the cable plugin.

use crate::cable::{BodyInChain, RopeSection};
use crate::coupling::{BodyMotion, CoupledCable};
use crate::integrate::Scheme;
use bevy::math::{DMat3, DQuat, DVec3};
use bevy::prelude::*;

/// Where a cable end is held.
#[derive(Debug, Clone, PartialEq)]
pub enum CableAnchor {
    /// A free end.
    Free,
    /// A world point, m; `clamp` also fixes the tangent.
    World {
        /// The point.
        point: Vec3,
        /// Fix the tangent too.
        clamp: bool,
    },
    /// A point of a rapier body (an entity with `RigidBody`), in the body's
    /// local frame, m.
    Body {
        /// The body entity.
        entity: Entity,
        /// Attachment point in the body frame, m.
        anchor: Vec3,
        /// Fix the tangent too.
        clamp: bool,
    },
}

/// Spawn an entity with this to get a cable. The plugin builds it at the
/// next fixed step (after rapier created the bodies it hangs on) and adds
/// [`CableSim`] and [`CableState`]. The rapier velocities of the bodies the
/// cable carries (payload, trolley) at that moment become the chain's
/// initial rates ([`Cable::set_link_velocities`](crate::cable::Cable::set_link_velocities):
/// the rope takes the shape their push would deflect it into); with all of
/// them at rest the cable starts at rest relative to its base, and a base
/// that already moves carries the whole cable along at its velocity. A
/// velocity the chain cannot take (a trolley moving across its rail) is
/// reported as a [`CableDiverged`] message at time 0 and the cable is not
/// built.
#[derive(Component, Debug, Clone)]
pub struct CableDescriptor {
    /// Unstretched length, m.
    pub length: f64,
    /// Number of beam elements (≥ 1).
    pub segments: usize,
    /// Section properties (see `cable::preset`).
    pub section: RopeSection,
    /// Diameter, m.
    pub diameter: f64,
    /// Shear stiffness GA, N (default EA).
    pub shear_stiffness: Option<f64>,
    /// Stiffness-proportional damping time constant, s.
    pub damping: f64,
    /// Tension-only axial law (default `true`: a rope cannot push);
    /// `false` keeps compression, for rods and beams
    /// ([`RopeBuilder::tension_only`](crate::cable::RopeBuilder::tension_only)).
    pub tension_only: bool,
    /// Initial centreline (world, m); default straight from start to end, or
    /// straight down from the start when the end is free or on a body.
    pub path: Option<Vec<Vec3>>,
    /// Start anchor (a free start needs a `path`).
    pub start: CableAnchor,
    /// End anchor.
    pub end: CableAnchor,
    /// Time integrator.
    pub scheme: Scheme,
    /// Constant point loads on the rope, kept for the whole run (explicit:
    /// [`Cable::add_rope_point_load`](crate::cable::Cable::add_rope_point_load)).
    pub loads: Vec<CablePointLoad>,
    /// The initial path is the unstretched shape (no bending or torsion
    /// stress in it; [`RopeBuilder::stress_free_shape`](crate::cable::RopeBuilder::stress_free_shape)).
    pub stress_free: bool,
    /// `Some(n)`: start from the static equilibrium (gravity, loads, held
    /// ends; bodies rapier keeps held where they are), reached in `n` load
    /// steps ([`Cable::solve_static`](crate::cable::Cable::solve_static)
    /// with the tolerance of `cablesim`, [`crate::sim::STATIC_TOLERANCE`]).
    /// A cable whose static solve fails is not built (a [`CableDiverged`]
    /// message at time 0). For a cable whose rope is grafted onto another's
    /// chain (a sling leg), the carrying cable's setting counts.
    pub static_start: Option<u32>,
}

/// A constant point load on a cable (world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CablePointLoad {
    /// Arc length from the cable's start, m.
    pub s: f64,
    /// Force, N.
    pub force: DVec3,
    /// Moment, N·m.
    pub moment: DVec3,
}

/// Exact (f64) inputs of a cable, replacing the f32 values of its
/// [`CableDescriptor`] when present: a scenario file's values, so that a
/// scenario spawned into a Bevy app ([`crate::plugin::scenario`]) gives the
/// same results as `cablesim`, bit for bit. Games do not need it.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct CableExact {
    /// Initial centreline (world, m), replacing [`CableDescriptor::path`].
    pub path: Option<Vec<DVec3>>,
    /// The start's point (world or body frame, m), replacing the
    /// [`CableAnchor`]'s.
    pub start: Option<DVec3>,
    /// The end's point (world or body frame, m).
    pub end: Option<DVec3>,
}

/// Exact (f64) data of a rapier body entity that cables hang on,
/// replacing what the plugin would read from rapier (f32): mass
/// properties, the pose and velocities at the start, and for a fixed or
/// kinematic body its prescribed motion in closed form. A scenario spawned
/// into a Bevy app ([`crate::plugin::scenario`]) carries it on every body.
#[derive(Component, Clone)]
pub struct BodyExact {
    /// Mass, kg.
    pub mass: f64,
    /// Rotational inertia about the centre of mass, body frame, kg·m².
    pub inertia: DMat3,
    /// Origin (= centre of mass) at t = 0, m.
    pub position: DVec3,
    /// Orientation at t = 0.
    pub rotation: DQuat,
    /// Velocity at t = 0, m/s.
    pub linear_velocity: DVec3,
    /// Angular velocity at t = 0, rad/s.
    pub angular_velocity: DVec3,
    /// The motion of a fixed or kinematic body (`t` in s ↦ its frame and
    /// rates); the cable end on it follows this instead of sampling rapier.
    pub motion: Option<BodyMotion>,
}

impl std::fmt::Debug for BodyExact {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BodyExact")
            .field("mass", &self.mass)
            .field("inertia", &self.inertia)
            .field("position", &self.position)
            .field("rotation", &self.rotation)
            .field("linear_velocity", &self.linear_velocity)
            .field("angular_velocity", &self.angular_velocity)
            .field("motion", &self.motion.as_ref().map(|_| "closed form"))
            .finish()
    }
}

impl CableDescriptor {
    /// A cable of `length` m with `segments` elements of `section`, from
    /// `start` to `end`, generalized-α, undamped, tension-only.
    pub fn new(length: f64, segments: usize, section: RopeSection, diameter: f64, start: CableAnchor, end: CableAnchor) -> Self {
        CableDescriptor {
            length,
            segments,
            section,
            diameter,
            shear_stiffness: None,
            damping: 0.0,
            tension_only: true,
            path: None,
            start,
            end,
            scheme: Scheme::default(),
            loads: Vec::new(),
            stress_free: false,
            static_start: None,
        }
    }
}

/// How the plugin couples a body to a cable (the core's
/// [`Role`](crate::coupling::Role), with the body's place in the chain).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CarriedBody {
    /// The body is a link of the cable's chain (payload, hook, trolley). It
    /// stays a dynamic rapier body: the cable solve moves it, and reads the
    /// user's velocity writes, impulses, forces, gravity scale and damping
    /// and rapier's contact impulses on it.
    Lumped(BodyInChain),
    /// The body moves the cable's base or end (fixed or kinematic in rapier).
    Base,
    /// The body is dynamic in rapier (jointed, or on several cables) and
    /// receives the start's reaction force (explicit exchange).
    Explicit,
    /// The body is dynamic in rapier and holds the cable's end through the
    /// implicit anchor spring; it receives the spring's force (explicit
    /// exchange).
    ExplicitEnd,
}

/// The simulated cable (f64 core) and its couplings. Dereferences to the
/// core's [`CoupledCable`] (`sim.cable`, `sim.failed`, …).
#[derive(Component, Debug)]
pub struct CableSim {
    /// The cable and its couplings, as the coupling core keeps them.
    pub coupled: CoupledCable,
    /// Bodies coupled to the cable and how.
    pub bodies: Vec<(Entity, CarriedBody)>,
    /// A trolley that is the chain's root prismatic link: its entity, which
    /// holds the rapier `ImpulseJoint` whose motor drives it.
    pub(crate) rail: Option<Entity>,
}

impl std::ops::Deref for CableSim {
    type Target = CoupledCable;
    fn deref(&self) -> &CoupledCable {
        &self.coupled
    }
}

impl std::ops::DerefMut for CableSim {
    fn deref_mut(&mut self) -> &mut CoupledCable {
        &mut self.coupled
    }
}

/// Put by the plugin on a cable entity whose rope is solved as a limb of
/// another cable entity's chain: a cable on a body that hangs on several
/// cables (a sling leg), grafted onto the cable that carries the body. That
/// entity has the [`CableSim`]; this one has its own [`CableState`] and no
/// `CableSim`.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, Reflect)]
#[reflect(Component, Debug, PartialEq)]
pub struct CableRopeOf {
    /// The cable entity whose chain solves this rope.
    pub cable: Entity,
    /// The rope's index in that chain ([`Cable::rope`](crate::cable::Cable::rope), ≥ 1).
    pub rope: usize,
}

/// What other systems read about a cable (f32, world frame), refreshed
/// every fixed step after rapier's writeback.
#[derive(Component, Debug, Clone, Default, Reflect)]
#[reflect(Component, Debug, Default)]
pub struct CableState {
    /// Node positions (N + 1), m.
    pub nodes: Vec<Vec3>,
    /// Axial force of each element joint (N), tension positive.
    pub tensions: Vec<f32>,
    /// Stretched length, m.
    pub stretched_length: f32,
    /// Kinetic + gravitational + elastic energy of the cable's chain, J (for
    /// a [`CableRopeOf`] rope: of the whole chain it is solved in).
    pub energy: f64,
    /// Simulation time of the cable, s.
    pub time: f64,
    /// Newton iterations of the last step.
    pub newton_iterations: usize,
}

/// Sent when a cable diverges; the cable stops, its last good state stays.
#[derive(Message, Debug, Clone)]
pub struct CableDiverged {
    /// The cable entity.
    pub entity: Entity,
    /// Simulation time at the start of the failing step, s.
    pub time: f64,
    /// What failed.
    pub message: String,
}
