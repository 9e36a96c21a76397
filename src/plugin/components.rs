//! Components and messages of the cable plugin.

use crate::cable::{BodyInChain, RopeMaterial, RopeSection};
use crate::coupling::{BodyMotion, CoupledCable};
use crate::integrate::Scheme;
use bevy::ecs::entity::{EntityMapper, MapEntities};
use bevy::math::{DMat3, DQuat, DVec3};
use bevy::prelude::*;

/// Where a cable end is held.
#[derive(Debug, Clone, PartialEq, Reflect)]
#[reflect(Debug, PartialEq)]
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

impl CableAnchor {
    /// Pinned (a ball joint) at a world `point`, m.
    pub fn world(point: Vec3) -> Self {
        CableAnchor::World { point, clamp: false }
    }

    /// Clamped at a world `point`, m: position and the initial tangent held.
    pub fn world_clamped(point: Vec3) -> Self {
        CableAnchor::World { point, clamp: true }
    }

    /// Pinned (a ball joint) to rapier body `entity` at `anchor`, m, in the
    /// body's frame.
    pub fn body(entity: Entity, anchor: Vec3) -> Self {
        CableAnchor::Body { entity, anchor, clamp: false }
    }

    /// Clamped to rapier body `entity` at `anchor`, m, in the body's frame.
    pub fn body_clamped(entity: Entity, anchor: Vec3) -> Self {
        CableAnchor::Body { entity, anchor, clamp: true }
    }
}

impl MapEntities for CableAnchor {
    fn map_entities<E: EntityMapper>(&mut self, mapper: &mut E) {
        if let CableAnchor::Body { entity, .. } = self {
            *entity = mapper.get_mapped(*entity);
        }
    }
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
/// reported as a [`CableError`] ([`CableErrorKind::Configuration`]) at time 0 and the cable is not
/// built.
///
/// ```
/// use bevy::prelude::*;
/// use bevy_rapier_cable::cable::RopeMaterial;
/// use bevy_rapier_cable::plugin::{CableAnchor, CableDescriptor};
/// # let payload = Entity::PLACEHOLDER;
/// // 12 m of 16 mm steel wire rope from a world point to a payload's top.
/// let rope = CableDescriptor::new(12.0)
///     .material(RopeMaterial::steel_6x36_iwrc(0.016))
///     .segments(48)
///     .start(CableAnchor::world(Vec3::new(0.0, 15.0, 0.0)))
///     .end(CableAnchor::body(payload, Vec3::Y * 0.5))
///     .damping(0.005);
/// assert_eq!(rope.segments, 48);
/// ```
///
/// Entity references (the bodies in [`CableAnchor::Body`]) are mapped when
/// the component is cloned into another world or loaded from a scene
/// (`MapEntities`).
#[derive(Component, Debug, Clone, Reflect)]
#[reflect(Component, Debug)]
pub struct CableDescriptor {
    /// Unstretched length, m.
    pub length: f64,
    /// Number of beam elements (1 to [`MAX_SEGMENTS`](crate::cable::MAX_SEGMENTS)).
    pub segments: usize,
    /// Material and diameter.
    pub material: RopeMaterial,
    /// Shear stiffness GA, N (default EA).
    pub shear_stiffness: Option<f64>,
    /// Stiffness-proportional damping time constant, s.
    pub damping: f64,
    /// Velocity damping of the rope's elements, linear, 1/s
    /// ([`CableDescriptor::velocity_damping`]).
    pub linear_damping: f64,
    /// Velocity damping of the rope's elements, angular, 1/s.
    pub angular_damping: f64,
    /// Stiffness of the implicit spring that pins an end to a world point
    /// or a body, as a multiple of the element axial stiffness `EA/L_e`
    /// ([`CableDescriptor::end_stiffness`]; default
    /// [`END_STIFFNESS_FACTOR`](crate::cable::END_STIFFNESS_FACTOR), 1000).
    pub end_stiffness: f64,
    /// Tension-only axial law (default `true`: a rope cannot push);
    /// `false` keeps compression, for rods and beams
    /// ([`RopeBuilder::tension_only`](crate::cable::RopeBuilder::tension_only)).
    pub tension_only: bool,
    /// Initial centreline (world, m); default straight from start to end, or
    /// straight down from the start when the end is free or on a body.
    pub path: Option<Vec<Vec3>>,
    /// Start anchor (a free start needs a `path`).
    #[entities]
    pub start: CableAnchor,
    /// End anchor.
    #[entities]
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
    /// A cable whose static solve fails is not built (a [`CableError`]
    /// message at time 0). For a cable whose rope is grafted onto another's
    /// chain (a sling leg), the carrying cable's setting counts.
    pub static_start: Option<u32>,
    /// Contact of the rope with rapier's colliders (default `true`): its
    /// nodes, and its elements over edges and curved surfaces, are pushed
    /// out of the colliders of fixed and kinematic bodies (not the cable's
    /// own) by steel-on-steel Hertz contact
    /// ([`CableContact::steel`](crate::coupling::CableContact::steel)),
    /// inside the implicit solve, with Coulomb friction
    /// ([`CableDescriptor::friction`]); a dynamic body that reaches the
    /// rope is solved with it for that step, and other ropes and the
    /// rope's own elements are met too. Which colliders and ropes it meets:
    /// [`CableDescriptor::collision_groups`].
    pub contacts: bool,
    /// The rope's Coulomb friction coefficient (default 0.3), combined
    /// with each collider's bevy_rapier `Friction` as rapier combines two
    /// colliders' (with the defaults, the mean of the two). A contact
    /// sticks while the friction force stays below the coefficient times
    /// the normal force, and slips at that force beyond it.
    pub friction: f64,
    /// The rope's collision groups, as on a bevy_rapier collider (default
    /// `CollisionGroups::default()`: member of every group, meets every
    /// group, like a collider without the component). The rope touches a
    /// collider only if rapier's test passes between these and both the
    /// collider's `CollisionGroups` and its `SolverGroups` (both ways:
    /// each one's memberships meet the other's filters), and another rope
    /// only if it passes between the two ropes' groups. A rope always
    /// meets itself. Contacts between the bodies a rope carries and other
    /// colliders follow those colliders' own groups, as in rapier.
    pub collision_groups: bevy_rapier3d::prelude::CollisionGroups,
}

/// A constant point load on a cable (world frame).
#[derive(Debug, Clone, Copy, PartialEq, Reflect)]
#[reflect(Debug, PartialEq)]
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
/// scenario spawned into a Bevy app (`plugin::scenario`) gives the
/// same results as `cablesim`, bit for bit. Games do not need it.
#[derive(Component, Debug, Clone, Default, PartialEq, Reflect)]
#[reflect(Component, Debug, Default, PartialEq)]
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
/// into a Bevy app (`plugin::scenario`) carries it on every body.
#[derive(Component, Clone, Reflect)]
#[reflect(Component, Debug, from_reflect = false)]
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
    /// (Not reflected: a closure.)
    #[reflect(ignore)]
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
    /// A cable of `length` m with the defaults: a 20 mm steel wire rope
    /// ([`RopeMaterial::default`]), elements of about 0.5 m (4 to 100 of
    /// them, [`CableDescriptor::default_segments`]), pinned at the world
    /// origin with a free end, undamped, tension-only, generalized-α. Set
    /// the rest with the builder methods.
    pub fn new(length: f32) -> Self {
        let length = length as f64;
        Self::from_section(length, Self::default_segments(length), RopeMaterial::default(), CableAnchor::world(Vec3::ZERO), CableAnchor::Free)
    }

    /// A cable from exact (f64) values: `length` m in `segments` elements
    /// of `material`, from `start` to `end`, undamped, tension-only,
    /// generalized-α (what `plugin::scenario` uses).
    pub fn from_section(length: f64, segments: usize, material: RopeMaterial, start: CableAnchor, end: CableAnchor) -> Self {
        CableDescriptor {
            length,
            segments,
            material,
            shear_stiffness: None,
            damping: 0.0,
            linear_damping: 0.0,
            angular_damping: 0.0,
            end_stiffness: crate::cable::END_STIFFNESS_FACTOR,
            tension_only: true,
            path: None,
            start,
            end,
            scheme: Scheme::default(),
            loads: Vec::new(),
            stress_free: false,
            static_start: None,
            contacts: true,
            friction: 0.3,
            collision_groups: bevy_rapier3d::prelude::CollisionGroups::default(),
        }
    }

    /// The number of elements [`CableDescriptor::new`] gives a cable of
    /// `length` m: one per 0.5 m, at least 4 and at most 100.
    pub fn default_segments(length: f64) -> usize {
        let n = (length / 0.5).round();
        if n.is_finite() {
            (n as usize).clamp(4, 100)
        } else {
            4
        }
    }

    /// Sets the number of beam elements (1 to [`MAX_SEGMENTS`](crate::cable::MAX_SEGMENTS); more is
    /// stiffer bending detail and cost linear in the number).
    pub fn segments(mut self, segments: usize) -> Self {
        self.segments = segments;
        self
    }

    /// Sets the material and diameter.
    pub fn material(mut self, material: RopeMaterial) -> Self {
        self.material = material;
        self
    }

    /// A section given property by property, drawn with `diameter`, m.
    pub fn section(self, section: RopeSection, diameter: f32) -> Self {
        self.material(RopeMaterial::custom(section, diameter as f64))
    }

    /// Sets the start anchor.
    pub fn start(mut self, start: CableAnchor) -> Self {
        self.start = start;
        self
    }

    /// Sets the end anchor.
    pub fn end(mut self, end: CableAnchor) -> Self {
        self.end = end;
        self
    }

    /// Sets the initial centreline (world, m; the `path` field). Unless
    /// [`stress_free`](Self::stress_free) is set, a curved path is a bent,
    /// stressed state of a straight rope, which springs back when
    /// released (a rope laid strongly bent between two posts whips and may
    /// fail to converge). A path that turns back on itself by more than
    /// 179.9° at one node (a fold laid flat) is refused with a
    /// [`CableError`] naming the place. A path longer than the rope
    /// stretches a rope anchored at both ends; a rope with a free end
    /// ([`CableAnchor::Free`]) lies along it unstretched from its anchored
    /// end (its start if both are free) and ends where its length does.
    pub fn path(mut self, path: impl IntoIterator<Item = Vec3>) -> Self {
        self.path = Some(path.into_iter().collect());
        self
    }

    /// Whether the initial path is the rope's unstressed shape (the
    /// `stress_free` field; default `false`: the rope is straight when
    /// unstressed). Set it for a pre-curved rope, a kinked wire, or a
    /// rope laid round a post that should not spring off it.
    pub fn stress_free(mut self, yes: bool) -> Self {
        self.stress_free = yes;
        self
    }

    /// Stiffness-proportional damping with time constant `tau`, s (each
    /// spring's damper is `tau` times its stiffness).
    pub fn damping(mut self, tau: f32) -> Self {
        self.damping = tau as f64;
        self
    }

    /// Velocity damping of the rope's elements, 1/s: each element feels
    /// `−linear · m v` at its centre of mass and `−angular · I ω`, as
    /// rapier's `Damping` does for a body (still-air drag, so that a slack
    /// rope comes to rest; implicit, stable at any rate). Default 0
    /// ([`RopeBuilder::velocity_damping`](crate::cable::RopeBuilder::velocity_damping)).
    pub fn velocity_damping(mut self, linear: f32, angular: f32) -> Self {
        self.linear_damping = linear as f64;
        self.angular_damping = angular as f64;
        self
    }

    /// Stiffness of the implicit spring that pins an end to a world point
    /// or a body, as a multiple of the element axial stiffness `EA/L_e`
    /// (> 0, dimensionless; default 1000). The last element's axial spring
    /// is stiffened so that the two in series keep the rope's compliance
    /// exactly. A soft anchor (2) lets Newton converge in fewer iterations
    /// on a slack rope pinned at both ends (2.4 times fewer on a rope that
    /// swings down and lands on the ground; see
    /// [`RopeBuilder::end_stiffness_factor`](crate::cable::RopeBuilder::end_stiffness_factor)
    /// for what it costs elsewhere).
    pub fn end_stiffness(mut self, factor: f32) -> Self {
        self.end_stiffness = factor as f64;
        self
    }

    /// Keeps compression (`false`: a rod or a beam) or not (`true`, the
    /// default: a rope cannot push).
    pub fn tension_only(mut self, yes: bool) -> Self {
        self.tension_only = yes;
        self
    }

    /// Contact with rapier's colliders on (`true`, the default) or off (the
    /// rope passes through them); see [`CableDescriptor::contacts`].
    pub fn contacts(mut self, yes: bool) -> Self {
        self.contacts = yes;
        self
    }

    /// Sets the rope's Coulomb friction coefficient (≥ 0; default 0.3);
    /// see [`CableDescriptor::friction`]. A negative or non-finite value
    /// is refused when the cable is built, with its name.
    pub fn friction(mut self, mu: f64) -> Self {
        self.friction = mu;
        self
    }

    /// Sets the rope's collision groups (default: every group); see
    /// [`CableDescriptor::collision_groups`]. For example a crane's hoist
    /// rope that should pass through its own boom: put the boom's collider
    /// in a group the rope's filter leaves out.
    pub fn collision_groups(mut self, groups: bevy_rapier3d::prelude::CollisionGroups) -> Self {
        self.collision_groups = groups;
        self
    }

    /// Sets the time integrator (default generalized-α).
    pub fn scheme(mut self, scheme: Scheme) -> Self {
        self.scheme = scheme;
        self
    }

    /// Starts from the static equilibrium, reached in `load_steps` load
    /// steps (the `static_start` field).
    pub fn static_start(mut self, load_steps: u32) -> Self {
        self.static_start = Some(load_steps);
        self
    }

    /// Adds a constant point load `force`, N, at arc length `s`, m, from the
    /// start (world frame).
    pub fn point_load(mut self, s: f32, force: Vec3) -> Self {
        self.loads.push(CablePointLoad { s: s as f64, force: force.as_dvec3(), moment: DVec3::ZERO });
        self
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
///
/// Reflected as an opaque component (the core's f64 state is not
/// reflected; read [`CableState`] for the values a game shows).
#[derive(Component, Debug, Reflect)]
#[reflect(Component, Debug, from_reflect = false)]
pub struct CableSim {
    /// The cable and its couplings, as the coupling core keeps them.
    #[reflect(ignore)]
    pub coupled: CoupledCable,
    /// Bodies coupled to the cable and how.
    #[reflect(ignore)]
    pub bodies: Vec<(Entity, CarriedBody)>,
    /// A trolley that is the chain's root prismatic link: its entity, which
    /// holds the rapier `ImpulseJoint` whose motor drives it.
    #[reflect(ignore)]
    pub(crate) rail: Option<Entity>,
    /// Whether the plugin has warned that a carried body's `Transform` was
    /// written (once per cable).
    #[reflect(ignore)]
    pub(crate) warned_moved: bool,
    /// Whether the bodies of a stopped cable were handed back to rapier
    /// (once, at the step it stopped).
    #[reflect(ignore)]
    pub(crate) released: bool,
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
    /// Sum of the normal forces of the rope's contacts with colliders, N
    /// (its weight, for a rope lying on the ground;
    /// [`CableDescriptor::contacts`]).
    pub contact_force: f32,
    /// Orientation of each element's frame (world; its local x along the
    /// element, y and z its bending axes), from the start
    /// (`RopeView::element_frames`).
    pub frames: Vec<Quat>,
    /// The contacts on the rope: each point on the rope (world, m) and the
    /// force the contact puts on it there (world, N: normal and friction;
    /// `RopeView::contacts`, its contacts with itself included).
    pub contacts: Vec<(Vec3, Vec3)>,
    /// Kinetic + gravitational + elastic energy of the cable's chain, J (for
    /// a [`CableRopeOf`] rope: of the whole chain it is solved in).
    pub energy: f64,
    /// Simulation time of the cable, s.
    pub time: f64,
    /// Newton iterations of the last step.
    pub newton_iterations: usize,
}

/// What kind of failure a [`CableError`] reports, so that a game can react
/// to each (fix a description, clamp an input, or stop a level).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Reflect)]
#[reflect(Debug, PartialEq, Hash)]
#[non_exhaustive]
pub enum CableErrorKind {
    /// The cable cannot be built as described: a field out of range, an
    /// anchor on an entity that is no rapier body, a load off the rope, a
    /// topology the coupling refuses (a loop between two dynamic bodies,
    /// locked axes on a carried body), a static start that fails, or a
    /// timestep mode the cables cannot follow. The cable is not built (its
    /// [`CableDescriptor`] is removed); `time` is 0.
    Configuration,
    /// A value the game gave a running cable cannot be used: a non-finite
    /// `ExternalForce`, `GravityScale`, `Damping`, velocity write or
    /// impulse on a body the cable carries. The cable stops before the step
    /// and keeps its last good state; its carried bodies are rapier's again.
    InvalidInput,
    /// The cable's implicit solve failed (Newton did not converge at any
    /// split of the step, or the state left physical sense). The cable stops
    /// and keeps its last good state; its carried bodies are rapier's again.
    Diverged,
}

/// Sent when a cable fails or is refused; logged through the `log` facade
/// (Bevy's `LogPlugin` shows it) at error level as well. The cable stops
/// (or is not built); its last good state stays, and the bodies it carried
/// are ordinary rapier bodies again. `Display` gives one line
/// with the entity, the kind, the time and the reason.
#[derive(Message, Debug, Clone, PartialEq, Reflect)]
#[reflect(Debug, PartialEq)]
pub struct CableError {
    /// The cable entity.
    pub entity: Entity,
    /// What kind of failure.
    pub kind: CableErrorKind,
    /// Simulation time at the start of the failing step (0 for a cable
    /// refused at creation), s.
    pub time: f64,
    /// What failed, naming the value, body or element.
    pub message: String,
}

impl CableError {
    /// A new message (not yet sent or logged).
    pub fn new(entity: Entity, kind: CableErrorKind, time: f64, message: impl Into<String>) -> Self {
        CableError { entity, kind, time, message: message.into() }
    }
}

impl std::fmt::Display for CableError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match self.kind {
            CableErrorKind::Configuration => "refused (configuration)",
            CableErrorKind::InvalidInput => "stopped (invalid input)",
            CableErrorKind::Diverged => "stopped (diverged)",
        };
        write!(f, "cable {} {kind} at t = {} s: {}", self.entity, self.time, self.message)
    }
}

impl std::error::Error for CableError {}
