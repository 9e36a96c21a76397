//! The coupling core (feature `rapier`, no Bevy): cables stepped beside
//! rapier's sets, shared by the scenario runner ([`crate::sim`]) and the
//! Bevy plugin, which are thin adapters that map scenario names or entities
//! to rapier handles.
//!
//! [`Coupling`] owns the cables. It decides how each body a cable end is
//! attached to is coupled ([`classify`]), builds the cables from
//! [`CableSpec`]s written in rapier's terms, and runs the per-step exchange
//! with a [`rapier3d::prelude::RigidBodySet`]:
//!
//! | phase | call | does |
//! |---|---|---|
//! | before rapier's step | [`Coupling::step`] | samples the bodies that move cable ends; reads what the user and rapier did to the carried bodies since the last step; steps every cable; hands the carried bodies to rapier with the velocity that lands them on the cable's pose; applies the explicit reactions |
//! | after rapier's step | [`Coupling::after_rapier`] | reads the contact impulses rapier gave the carried bodies; puts them on the cable's pose and velocity |
//!
//! ## Roles of the bodies ([`Role`], decided by [`classify`])
//! * **Carried** ([`Role::Carried`], [`Role::Trolley`]): a dynamic body at
//!   the end of exactly one cable and at no other cable end, that no
//!   impulse joint holds (hook, payload); or a dynamic body at the start of
//!   exactly one cable and at no other cable end whose only joint is one
//!   prismatic joint to a fixed body (a trolley on its rail), or that no
//!   joint holds and whose axes are not locked (a car towing on the rope:
//!   the chain's floating root, [`RopeStart::FloatingBody`]). It is a link
//!   of that cable's chain, solved implicitly with the rope (a 10 t payload
//!   on a 0.3 kg element is as stable as the rope itself). **It stays a
//!   dynamic rapier body**: its body type is never changed and its
//!   colliders stay in rapier. Every step the core
//!   * takes the velocity change the user made since the last step (a
//!     velocity write, an impulse) and the one rapier's contacts made in
//!     its last step, as an impulse `J = M Δv` (and `I Δω`) on the body's
//!     link: the chain's rates jump by `(M + h C + h² K)⁻¹ Jᵀ` at once
//!     (the chain's floating root by `M⁻¹ Jᵀ`; [`Cable::apply_impulse`]),
//!     so the rope and the body share it as
//!     their joint inertia dictates (a contact that persists from step to
//!     step, a body resting on a dynamic one, is a load over the step);
//!   * applies the user's force and torque, gravity scale and damping
//!     ([`BodyInputs`]) inside the cable solve;
//!   * sets the rapier body's velocity so that rapier's own integration
//!     lands it on the cable's new pose (gravity, forces, damping, sleeping
//!     and gyroscopic torques are switched off on the rapier body itself:
//!     the cable solve has them), and after rapier's step puts it exactly on
//!     the cable's pose and velocity.
//!
//!   A trolley's rail joint stays in rapier with its motor switched off
//!   there; the adapter gives the motor to the cable (`rail_drive`).
//!   `LockedAxes` on a carried body are refused ([`CouplingError::LockedAxes`]).
//!   Contact impulses are those rapier computes for a free body of the
//!   carried body's mass (with the colliders' restitution and friction),
//!   reaching the chain at its next step.
//! * **Hub** (an island; [`Role::Carried`] in every cable on it): a dynamic
//!   body that no impulse joint holds, at two or more cable attachments of
//!   one batch, at least one of them a cable's end, and at none of the
//!   existing cables (a payload in a two- or four-leg sling, a beam lifted
//!   by two cranes). The cable that ends on it and whose other end is a
//!   dynamic body the chain cannot carry (a trolley, a jointed body), if
//!   any, else the first cable that ends on it and starts on a body on that
//!   cable alone (a car towing), else the first cable that ends on it,
//!   carries it as above; every other cable on it is built
//!   from the hub outwards (reversed when the hub is at its end) and
//!   grafted onto the body's link ([`RopeModel::graft`]): one chain, one
//!   O(n) implicit solve. Their far ends are anchor springs to the world
//!   or to a fixed or kinematic body, or free. [`classify`] says where each
//!   cable goes ([`Placement`]), [`build_cables`] answers [`Built::Part`]
//!   for a grafted one, and the carrying [`CoupledCable`] keeps the grafted
//!   cables' end roles in [`CoupledCable::parts`]. Refused by name
//!   ([`CouplingError::HubLoop`]): a cable from a hub to another hub (a
//!   loop through two dynamic bodies) or to itself; if one cable of an
//!   island cannot be built, none is ([`CouplingError::Island`]). A body
//!   with a cable to a dynamic body that is no hub and that the chain
//!   cannot carry (a jointed body, a trolley) is a hub only if that cable
//!   ends on it (then that cable carries it); otherwise it stays
//!   explicit. A dynamic body on one cable alone, with no joint, at the
//!   far end of a hub's cable is carried in the same chain: at a grafted
//!   cable's far end as the limb's end body (a payload on a rope under a
//!   hook block; the second trailer of a train), at the carrying cable's
//!   start as the chain's floating root (a car towing the train).
//! * **Base** ([`Role::Base`]): a fixed or kinematic body moves the cable
//!   end: the start's base or the end's anchor-spring target. With a
//!   [`BodyMotion`] given by the adapter (a scenario's prescribed motion)
//!   the cable reads the motion exactly; otherwise it samples rapier (pose,
//!   velocity, and the velocity change over the last step).
//! * **Explicit** ([`Role::Explicit`]): every other dynamic body (held by
//!   joints, only at several cable starts, or added to a body an existing cable
//!   couples explicitly). The cable end follows the body's sampled motion;
//!   the body gets the cable's reaction as an impulse every step.
//!   Stable roughly while `k·h²/m ≲ 1` with `k = EA/L_e` (see
//!   [`Coupling::explicit_ratios`]).

mod contact;
mod explicit;
pub use self::contact::{CableContact, Contacts};

#[cfg_attr(not(any(feature = "app", feature = "sim")), allow(unused_imports))]
pub(crate) use self::explicit::{follow, rail_motor, reaction, BodySample};
// Scenario velocity drives (the runner and `plugin::scenario`), and the
// plugin's trolley controllers:
#[cfg(any(feature = "sim", feature = "app"))]
pub(crate) use self::explicit::set_velocity_drive;
#[cfg(feature = "sim")]
pub(crate) use self::explicit::velocity_drive_motor;
use crate::cable::chain::rotation_vector;
use crate::cable::rope::FLOATING_BODY_LINK;
use crate::cable::{
    BaseMotion, BaseState, BodyInChain, Cable, CableError, LinkLoad, LinkVelocity, LumpedBody, RopeBuilder, RopeEnd, RopeError, RopeModel, RopeStart,
};
use crate::cable::{Chain, ForestPair, FreeBody, LinkMass};
use crate::integrate::{Scheme, State, StepStats};
use glam::{DMat3, DQuat, DVec3};
use rapier3d::prelude as rp;
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use thiserror::Error;

/// Where a cable end is held, in rapier's terms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Attach {
    /// A free end (a free start needs a path).
    Free,
    /// A world point, m; `clamp` also holds the tangent.
    World {
        /// The point, m.
        point: DVec3,
        /// Hold the tangent too.
        clamp: bool,
    },
    /// A point of a rapier body, in the body's frame, m.
    Body {
        /// The body.
        body: rp::RigidBodyHandle,
        /// Attachment point in the body frame, m.
        anchor: DVec3,
        /// Hold the tangent too.
        clamp: bool,
    },
}

/// Prescribed motion of a fixed or kinematic body, known in closed form:
/// `t ↦` the body frame (orientation, origin m) with its angular velocity
/// (rad/s), origin velocity (m/s), angular acceleration (rad/s²) and origin
/// acceleration (m/s²).
pub type BodyMotion = Arc<dyn Fn(f64) -> BaseState + Send + Sync>;

/// A cable to build, in rapier's terms.
#[derive(Debug, Clone)]
pub struct CableSpec {
    /// The rope: length, elements, section, damping, gravity… Its start,
    /// end and path are set by the core from the fields below.
    pub rope: RopeBuilder,
    /// Initial centreline (world, m). `None`: straight from start to end,
    /// or straight down from the start when the end is free or carried.
    pub path: Option<Vec<DVec3>>,
    /// Start.
    pub start: Attach,
    /// End.
    pub end: Attach,
    /// Time integrator.
    pub scheme: Scheme,
    /// Mass properties and initial pose of the start and end bodies, when
    /// the adapter knows them exactly (a scenario's f64 values); `None`:
    /// read from rapier (f32).
    pub exact: [Option<LumpedBody>; 2],
    /// Contact of the rope's elements with rapier's colliders (`None`:
    /// the rope passes through them). Grafted ropes take the setting of the
    /// cable that carries their hub.
    pub contact: Option<CableContact>,
}

/// How a body is coupled to a cable end (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Role {
    /// A link of the cable's chain behind the end (ball joint or clamped).
    Carried,
    /// A link of the cable's chain behind a prismatic sub-joint at its start
    /// (a trolley); the rapier joint is the rail.
    Trolley {
        /// The rail joint.
        joint: rp::ImpulseJointHandle,
        /// Rail direction (world, unit).
        axis: DVec3,
        /// The rail joint's coordinate (anchor gap along the axis, m) when
        /// the chain's rail coordinate is 0.
        offset: f64,
    },
    /// A fixed or kinematic body that moves the cable end.
    Base,
    /// A dynamic body rapier keeps, coupled explicitly.
    Explicit,
}

/// The body and its role at a cable's start and end (`None`: no body there).
pub type EndRoles = [Option<(rp::RigidBodyHandle, Role)>; 2];

/// What the user asks of a carried body besides its velocity (the plugin
/// reads bevy_rapier's components; a scenario body has the defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyInputs {
    /// Force at the centre of mass, world, N.
    pub force: DVec3,
    /// Torque, world, N·m.
    pub torque: DVec3,
    /// Gravity scale (1: normal gravity).
    pub gravity_scale: f64,
    /// Linear damping, 1/s (rapier's law: `−c m v`).
    pub linear_damping: f64,
    /// Angular damping, 1/s (`−c I ω`).
    pub angular_damping: f64,
}

impl Default for BodyInputs {
    fn default() -> Self {
        BodyInputs { force: DVec3::ZERO, torque: DVec3::ZERO, gravity_scale: 1.0, linear_damping: 0.0, angular_damping: 0.0 }
    }
}

/// Why a cable cannot be built or coupled.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum CouplingError {
    /// A handle does not name a rapier body.
    #[error("the cable's {end} is attached to a body that is not in rapier's body set")]
    MissingBody {
        /// `start` or `end`.
        end: &'static str,
    },
    /// A free start without a path.
    #[error("a free cable start needs a path (its first point is the start)")]
    FreeStartNeedsPath,
    /// The body is already carried by another cable.
    #[error("the cable's {end} is attached to a body that cable #{cable} already carries as a link of its chain; attach all cables of a body in the same batch (then they are solved together as one island)")]
    BodyTaken {
        /// `start` or `end`.
        end: &'static str,
        /// Index of the cable that carries it.
        cable: usize,
    },
    /// A carried body with locked axes.
    #[error("the body at the cable's {end} would be a link of the cable's chain, but it has locked axes (`LockedAxes`), which the cable solve does not model; unlock them, or hold the body with a joint")]
    LockedAxes {
        /// `start` or `end`.
        end: &'static str,
    },
    /// A clamped end on a spinning or dynamic body rapier keeps.
    #[error("the cable's end is clamped to a body that moves ({why}): the end spring's orientation hold has a fixed target; clamp the start instead, or leave the end pinned")]
    ClampedMovingEnd {
        /// What kind of body.
        why: &'static str,
    },
    /// A body solved as a hub (on several cables) would close a loop
    /// through another dynamic body, or a cable runs from the hub to itself.
    #[error("{}", self.default_names())]
    HubLoop {
        /// The hub body (dynamic, on several cables, no joints).
        hub: rp::RigidBodyHandle,
        /// The dynamic body at the cable's other end (`hub` itself for a
        /// cable from the hub to the hub).
        other: rp::RigidBodyHandle,
    },
    /// Another cable of the same island could not be built.
    #[error("{}", self.default_names())]
    Island {
        /// Index (in the batch) of the cable that failed.
        cable: usize,
    },
    /// The rope could not be built.
    #[error("{0}")]
    Build(#[from] RopeError),
    /// The cable could not be created or started.
    #[error("{0}")]
    Cable(Box<CableError>),
}

impl CouplingError {
    /// The message, with the bodies and batch cables named by the adapter
    /// (`body`: a rapier handle's name, e.g. "body `box`"; `cable`: a batch
    /// index's name, e.g. "cable `leg_a`"). [`Display`](std::fmt::Display)
    /// names them "rapier body #i" and "cable #k of the batch".
    pub fn describe(&self, body: &dyn Fn(rp::RigidBodyHandle) -> String, cable: &dyn Fn(usize) -> String) -> String {
        match *self {
            CouplingError::HubLoop { hub, other } if hub == other => format!(
                "the cable runs from {} to itself: a rope with both ends on one dynamic body (a handle, a strap round a load) closes a loop through it, which the cable solve does not handle; hang the body on two cables instead, each from it to the hook or the point it hangs from (a two-leg sling), or put the rope's other end on another body",
                body(hub)
            ),
            CouplingError::HubLoop { hub, other } => format!(
                "{} hangs on several cables and is solved with them as one island, but the cable from it to the dynamic {} would close a loop through two dynamic bodies, which the island solve does not handle; make one of them fixed or kinematic, hang the other on a single cable, or hold it with a joint (then it is coupled explicitly)",
                body(hub),
                body(other)
            ),
            CouplingError::Island { cable: k } => {
                format!("the cable is solved as one island with {} (they hold the same body), which could not be built", cable(k))
            }
            ref e => e.to_string(),
        }
    }

    fn default_names(&self) -> String {
        self.describe(&|h| format!("rapier body #{}", h.into_raw_parts().0), &|k| format!("cable #{k} of the batch"))
    }
}

/// A body that is a link of a cable's chain.
#[derive(Debug, Clone)]
pub struct CarriedLink {
    /// The rapier body.
    pub body: rp::RigidBodyHandle,
    /// Its place in the chain.
    pub place: BodyInChain,
    /// Mass, kg.
    pub mass: f64,
    /// Rotational inertia about the centre of mass, body frame, kg·m².
    pub inertia: DMat3,
    /// Centre of mass in the body frame, m.
    pub com: DVec3,
    /// The link's own damping rates before the body's were added, 1/s.
    link_damping: (f64, f64),
    /// Rapier's mass properties of the body when the link last took them
    /// (its f32 `local_mprops`): a change is a mass the user gave it.
    mprops: rp::MassProperties,
    /// Velocity (centre of mass) and angular velocity the core last left on
    /// the rapier body, exactly as rapier stores them.
    mark: Option<(rp::Vector, rp::Vector)>,
    /// Where the core last put the rapier body (its origin, exactly as
    /// rapier stores it), after rapier's step: elsewhere at the next step,
    /// the user moved it.
    pub(crate) left_at: Option<rp::Vector>,
    /// Velocity handed to rapier for its step (lands on the cable's pose).
    landing: (DVec3, DVec3),
    /// Impulse (N·s at the centre of mass) and angular impulse (N·m·s) that
    /// rapier's contacts gave the body in its last step.
    contact: (DVec3, DVec3),
    /// Whether rapier's contacts gave it an impulse in its last step (at
    /// the next step, an impulse after one is a contact that persists: a
    /// body resting on a dynamic one).
    touching: bool,
}

/// A body that moves a cable end or takes its reaction explicitly.
#[derive(Debug)]
pub struct Follower {
    /// The rapier body.
    pub body: rp::RigidBodyHandle,
    /// Attachment point, body frame, m.
    pub anchor: DVec3,
    /// `true`: the cable's start (base); `false`: its end (anchor spring).
    pub start: bool,
    /// A dynamic body that gets the cable's reaction.
    pub dynamic: bool,
    sample: BodySample,
    /// Id of the [`BaseMotion::Sampled`] this follower refreshes (unique in
    /// the process, so a cable's followers stay distinct when its island is
    /// assembled from several drafts).
    source: usize,
    /// Time of the last sample, s.
    sampled: Option<f64>,
    /// Force (N) and moment about the centre of mass (N·m) of the cable on
    /// the body over the last step (dynamic bodies).
    pub reaction: (DVec3, DVec3),
}

/// One cable and its couplings.
#[derive(Debug)]
pub struct CoupledCable {
    /// The cable.
    pub cable: Cable,
    /// Role of the body at the start and at the end (`None`: no body).
    pub roles: EndRoles,
    /// Roles at the start and end of each further cable grafted onto the
    /// chain at a hub (`cable.rope(k + 1)`), in that cable's own direction.
    pub parts: Vec<EndRoles>,
    /// Bodies that are links of the chain.
    pub carried: Vec<CarriedLink>,
    /// Bodies sampled every step (bases without a closed-form motion,
    /// explicit couplings).
    pub followers: Vec<Follower>,
    /// Number of constant loads on the chain (the per-step loads follow).
    fixed_loads: usize,
    /// Contact of the rope's elements with rapier's colliders.
    pub contact: Option<CableContact>,
    /// Number of force elements that are not this step's contacts.
    fixed_forces: usize,
    /// Number of pair elements that are not this step's contacts.
    fixed_pairs: usize,
    /// The friction anchors of its contacts, from step to step.
    friction: contact::FrictionMemory,
    /// Whether this step's contacts include the carried bodies' own with
    /// fixed or kinematic colliders (then rapier's impulse from those is
    /// not applied again, see [`after_rapier`]).
    body_contacts: bool,
    /// The mean force (N, world) the island's ropes put on each free body
    /// over the last step (on the island's first cable; see
    /// [`CoupledCable::contact_force_on`]).
    free_forces: Vec<(rp::RigidBodyHandle, DVec3)>,
    /// Where the island's solve left each free body at the end of the last
    /// step (on the island's first cable), for [`after_rapier`].
    free_ends: Vec<BodyPass>,
    /// This step's contacts between a free body and a carried body that
    /// the island solved (`contact::carried_pairs`), as (free body,
    /// carried body): rapier's contact between the two, which repeats
    /// the island's, is not read back (`after_rapier`).
    carried_solved: Vec<(rp::RigidBodyHandle, rp::RigidBodyHandle)>,
    /// The last step's `carried_solved`: touches that stay the island's
    /// however fast they close (`contact::carried_pairs`).
    carried_resting: Vec<(rp::RigidBodyHandle, rp::RigidBodyHandle)>,
    /// Strikes on the carried bodies that rapier met in its last step
    /// (`reweigh_strikes`), as (free body, carried body): the island's from
    /// the next step on, however fast they close.
    carried_hit: Vec<(rp::RigidBodyHandle, rp::RigidBodyHandle)>,
    /// The step before's `carried_hit`, read at this step's start.
    carried_hit_last: Vec<(rp::RigidBodyHandle, rp::RigidBodyHandle)>,
    /// The friction anchors of the island's free bodies on fixed and
    /// kinematic colliders, from step to step (on the island's first
    /// cable).
    free_friction: Vec<(rp::RigidBodyHandle, contact::FrictionMemory)>,
    /// The free bodies [`after_rapier`] put on the island's pose and
    /// velocities (on the cable that kept them): the island's values (f64)
    /// and what rapier was given (f32), see [`Written`].
    free_written: Vec<(BodyPass, Written)>,
    /// Stopped after a failed step.
    pub failed: bool,
    /// The failure of this step's advance (time of the failing sub-step),
    /// collected in cable order after every cable advanced.
    advance_failure: Option<(f64, CableError)>,
    /// The last step's size and sub-step size, s (0 before the first):
    /// what `after_rapier` weighs rapier's strikes on the carried bodies
    /// with (`reweigh_strikes`).
    steps: (f64, f64),
    /// This step's bodies the cable's contacts leave out (its own bodies
    /// and a trolley's rail; none with contacts off), for every contact
    /// pass of the step and the free bodies' search.
    own: Vec<rp::RigidBodyHandle>,
}

impl CoupledCable {
    /// The force (N, world; normal and friction) of this cable's contacts
    /// on rapier body `body` now: its ropes pressing on the body's
    /// colliders, and, if the chain carries it, its own colliders' touch
    /// points on fixed and kinematic colliders; for a free dynamic body
    /// the ropes touched (one no cable holds), the mean force of the ropes
    /// of this cable's island on it over the last step (counted on the
    /// island's first cable). Rapier's own contacts (with dynamic bodies)
    /// are not counted.
    pub fn contact_force_on(&self, body: rp::RigidBodyHandle) -> DVec3 {
        let ch = &self.cable.model.chain;
        let t = self.cable.time();
        let forces = ch.forces().iter().zip(ch.force_element_points()).skip(self.fixed_forces).map(|(f, at)| f.element.wrench(t, &at).force);
        let free = self.free_forces.iter().filter(|(b, _)| *b == body).fold(DVec3::ZERO, |s, (_, f)| s + *f);
        self.friction.force_on(body, forces) + free
    }

    /// The force (N) and moment about `about` (N·m, world) that this
    /// cable's contacts put on `body` as their obstacle (a jointed body,
    /// [`Contacts::jointed`]) at the end of the last step.
    fn obstacle_wrench(&self, body: rp::RigidBodyHandle, about: DVec3) -> (DVec3, DVec3) {
        let ch = &self.cable.model.chain;
        let t = self.cable.time();
        let contacts = ch.forces().iter().zip(ch.force_element_points()).skip(self.fixed_forces).map(|(f, at)| {
            let w = f.element.wrench(t, &at);
            (at.point + w.arm, w.force)
        });
        self.friction.wrench_on_obstacle(body, contacts, about)
    }

    /// The role of `body` in this cable, if it is attached.
    pub fn role_of(&self, body: rp::RigidBodyHandle) -> Option<Role> {
        self.all_roles().find(|(b, _)| *b == body).map(|(_, r)| *r)
    }

    /// The bodies at the ends of the cable's ropes (its own, then the
    /// grafted ones) and their roles.
    pub fn all_roles(&self) -> impl Iterator<Item = &(rp::RigidBodyHandle, Role)> {
        std::iter::once(&self.roles).chain(&self.parts).flat_map(|r| r.iter().flatten())
    }

    /// Pose (origin, orientation), velocity of the centre of mass and
    /// angular velocity of a carried body, from the cable.
    fn carried_state(&self, c: &CarriedLink) -> (DVec3, DMat3, DVec3, DVec3) {
        let (p, r, v, w) = self.cable.model.body_state(&c.place);
        let rc = r * c.com;
        (p, r, v + w.cross(rc), w)
    }

    /// The time (s) over which the chain answers an impulse on link
    /// `link` at a (sub-)step of `step` s ([`Cable::apply_impulse`]'s `h`;
    /// [`Cable::point_mobility`] weighs a strike with the same).
    ///
    /// The response over the (sub-)step, `(M + h C + h² K)⁻¹ Jᵀ` with the
    /// rope's and its anchor springs' stiffness, as a pin or clamp would
    /// answer the impulse, and as the rope's stiff directions must: the
    /// instant response (the mass matrix alone) sends the jump into the
    /// cheapest motion, the shear slide at the
    /// body (the body alone moving across the last element), and the
    /// next step had that shear spring ring at the body's speed: a 1 t
    /// ball on 10.4 m of damped steel rope pushed at 0.2 m/s stopped
    /// with "Newton did not converge" (2026-11-28; the same with a
    /// sling's grafted leg giving way at its anchor spring before).
    /// The chain's floating root (a car towing) is the exception: its
    /// own six coordinates come first, so the instant response moves it
    /// without a kink, and over the step the taut rope took a `Velocity`
    /// write's jump every frame until a tow line driven that way stopped
    /// at 1.7 s.
    fn impulse_time(&self, link: usize, step: f64) -> f64 {
        let floating = self.cable.model.layout.floating_start.then_some(crate::cable::rope::FLOATING_BODY_LINK);
        if !self.cable.model.chain.anchors().is_empty() || Some(link) != floating {
            step
        } else {
            0.0
        }
    }

    /// Marks the cable's constant loads (those on the chain now): the
    /// per-step loads of the carried bodies are added after them.
    pub fn keep_loads(&mut self) {
        self.fixed_loads = self.cable.model.chain.loads().len();
    }
}

/// Where a cable's rope goes: the root of its own chain, or a limb grafted
/// onto another cable's chain at a hub body (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Placement {
    /// The cable has its own chain.
    Own,
    /// The cable's rope is grafted onto the chain of cable `onto` (its
    /// index in the batch), which carries `hub` at its end.
    Grafted {
        /// Index in the batch of the cable that carries the hub.
        onto: usize,
        /// The hub body.
        hub: rp::RigidBodyHandle,
        /// `true`: the hub is at this cable's end (the limb runs from the
        /// cable's end to its start); `false`: at its start.
        reversed: bool,
    },
}

/// How [`classify`] couples one cable of a batch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Classified {
    /// Roles of the bodies at the cable's start and end.
    pub roles: EndRoles,
    /// Its own chain, or a limb of another cable's chain.
    pub placement: Placement,
}

/// A body's attachments in a batch: (cable index, 0 at its start or 1 at
/// its end).
type Uses = Vec<(usize, usize)>;

/// The hubs of a batch: dynamic bodies with no joints at ≥ 2 cable ends of
/// the batch (at least one of them a cable's end) and at none of the
/// existing cables. Per hub: the carrying cable, or why there is none.
///
/// A cable from a candidate to another dynamic body is a loop through two
/// dynamic bodies unless that body can be carried in the same chain: one
/// on that cable alone, with no joint (and, at the cable's start, no
/// locked axes) — a payload hung below a hook block, a car towing a
/// train. Such a cable is grafted with the body at its far end, or, when
/// it ends on the candidate, may carry it (its far body then the chain's
/// floating root). Of the other cables to dynamic bodies (a trolley, a
/// jointed body): one that ends on the candidate carries it; with two, or
/// with one that starts on it, the candidate stays explicit. A cable to
/// another candidate, or from a candidate to itself, is refused.
fn hubs(
    specs: &[&CableSpec],
    batch: &HashMap<rp::RigidBodyHandle, Uses>,
    existing: &[&CoupledCable],
    bodies: &rp::RigidBodySet,
    joints: &rp::ImpulseJointSet,
) -> HashMap<rp::RigidBodyHandle, Result<usize, CouplingError>> {
    let dynamic = |h: &rp::RigidBodyHandle| bodies.get(*h).is_some_and(|rb| rb.is_dynamic());
    let used_before = |h: rp::RigidBodyHandle| existing.iter().any(|c| c.role_of(h).is_some());
    let unjointed = |h: rp::RigidBodyHandle| joints.attached_joints(h).next().is_none();
    let uses: HashMap<rp::RigidBodyHandle, &Uses> = batch
        .iter()
        .filter(|(hub, at)| at.len() >= 2 && dynamic(hub) && !used_before(**hub) && unjointed(**hub) && at.iter().any(|(_, k)| *k == 1))
        .map(|(h, at)| (*h, at))
        .collect();
    // A far body the hub's chain can carry: on this cable alone, with no
    // joint, and one `classify` carries ([`carried_alone`]).
    let carriable = |body: rp::RigidBodyHandle, at_start: bool| {
        batch.get(&body).is_some_and(|u| u.len() == 1)
            && !used_before(body)
            && unjointed(body)
            && bodies.get(body).is_some_and(|rb| carried_alone(rb, at_start))
    };
    let mut out = HashMap::new();
    for (&hub, at) in &uses {
        // The other end of each cable on the hub, when it is a dynamic body.
        let far = |&(i, k): &(usize, usize)| match if k == 0 { &specs[i].end } else { &specs[i].start } {
            Attach::Body { body, .. } if dynamic(body) => Some((i, k, *body)),
            _ => None,
        };
        let loops: Vec<(usize, usize, rp::RigidBodyHandle)> = at.iter().filter_map(far).collect();
        let carrier = if let Some(&(_, _, other)) = loops.iter().find(|l| l.2 == hub || uses.contains_key(&l.2)) {
            // A cable from the hub to itself, or to another hub: a loop
            // through two dynamic bodies.
            Err(CouplingError::HubLoop { hub, other })
        } else {
            let (graftable, kept): (Vec<_>, Vec<_>) = loops.iter().partition(|&&(_, k, body)| carriable(body, k == 1));
            match kept.as_slice() {
                [] => Ok(graftable.iter().find(|l| l.1 == 1).map(|l| l.0).unwrap_or_else(|| at.iter().find(|(_, k)| *k == 1).expect("an end is on the hub").0)),
                // The one cable to another dynamic body (a trolley, a
                // jointed body) carries the hub, if the hub is at its end.
                [(i, 1, _)] => Ok(*i),
                _ => continue,
            }
        };
        out.insert(hub, carrier);
    }
    out
}

/// Whether a dynamic body with no joint, at one cable end alone, is
/// carried in that cable's chain: at the cable's end always (a payload),
/// at its start (the chain's floating root, a car towing) unless its axes
/// are locked (kept explicit: a carried body's locked axes are refused, and
/// a game's vehicle often has them).
fn carried_alone(rb: &rp::RigidBody, at_start: bool) -> bool {
    !at_start || rb.locked_axes().is_empty()
}

/// Roles of the bodies at the ends of `specs`, cable by cable, and where
/// each cable's rope goes, given the bodies already used by `existing`
/// cables (see the module docs).
pub fn classify(
    specs: &[&CableSpec],
    existing: &[&CoupledCable],
    bodies: &rp::RigidBodySet,
    joints: &rp::ImpulseJointSet,
) -> Vec<Result<Classified, CouplingError>> {
    // Each body's attachments in the batch.
    let mut batch: HashMap<rp::RigidBodyHandle, Uses> = HashMap::new();
    for (i, s) in specs.iter().enumerate() {
        for (k, a) in [&s.start, &s.end].into_iter().enumerate() {
            if let Attach::Body { body, .. } = a {
                batch.entry(*body).or_default().push((i, k));
            }
        }
    }
    // Its attachments in all: the batch's and the existing cables'.
    let uses = |b: rp::RigidBodyHandle| batch.get(&b).map_or(0, Vec::len) + existing.iter().flat_map(|c| c.all_roles()).filter(|(h, _)| *h == b).count();
    let hubs = hubs(specs, &batch, existing, bodies, joints);
    specs
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let mut out = [None, None];
            let mut placement = Placement::Own;
            for (k, a) in [&s.start, &s.end].into_iter().enumerate() {
                let Attach::Body { body, .. } = a else {
                    continue;
                };
                let end = if k == 0 { "start" } else { "end" };
                let Some(rb) = bodies.get(*body) else {
                    return Err(CouplingError::MissingBody { end });
                };
                if let Some(ci) = existing.iter().position(|c| matches!(c.role_of(*body), Some(Role::Carried | Role::Trolley { .. }))) {
                    return Err(CouplingError::BodyTaken { end, cable: ci });
                }
                let role = if let Some(carrier) = hubs.get(body) {
                    let onto = carrier.clone()?;
                    if onto != i {
                        placement = Placement::Grafted { onto, hub: *body, reversed: k == 1 };
                    }
                    Role::Carried
                } else if !rb.is_dynamic() {
                    Role::Base
                } else if uses(*body) != 1 {
                    Role::Explicit
                } else {
                    let attached: Vec<_> = joints.attached_joints(*body).collect();
                    match (k, attached.as_slice()) {
                        // A payload at its end; a car towing on its start
                        // (the chain's floating root), see `carried_alone`.
                        (k, []) if carried_alone(rb, k == 0) => Role::Carried,
                        (0, [(b1, b2, jh, j)]) => {
                            let other = if *b1 == *body { *b2 } else { *b1 };
                            let prismatic = j.data.locked_axes == rp::JointAxesMask::LOCKED_PRISMATIC_AXES;
                            match bodies.get(other) {
                                Some(o) if prismatic && o.is_fixed() => {
                                    let (frame_body, frame) = if *b1 == other { (o, j.data.local_frame1) } else { (o, j.data.local_frame2) };
                                    let axis = (frame_body.position().rotation * (frame.rotation * rp::Vector::X)).as_dvec3().normalize();
                                    let (p1, p2) =
                                        (bodies[*b1].position() * j.data.local_frame1.translation, bodies[*b2].position() * j.data.local_frame2.translation);
                                    // The rapier coordinate: body2's anchor minus body1's along the axis.
                                    let offset = (p2 - p1).as_dvec3().dot(axis);
                                    Role::Trolley { joint: *jh, axis, offset }
                                }
                                _ => Role::Explicit,
                            }
                        }
                        _ => Role::Explicit,
                    }
                };
                if matches!(role, Role::Carried | Role::Trolley { .. }) && !rb.locked_axes().is_empty() {
                    return Err(CouplingError::LockedAxes { end });
                }
                out[k] = Some((*body, role));
            }
            Ok(Classified { roles: out, placement })
        })
        .collect()
}

/// Pose of a rapier body in f64: origin and orientation.
pub fn pose_of(rb: &rp::RigidBody) -> (DVec3, DMat3) {
    let p = rb.position();
    (p.translation.as_dvec3(), DMat3::from_quat(p.rotation.as_dquat().normalize()))
}

/// Mass properties and pose of a rapier body as a chain link.
fn lumped_of(rb: &rp::RigidBody) -> LumpedBody {
    let (position, rotation) = pose_of(rb);
    let mp = &rb.mass_properties().local_mprops;
    let i = mp.reconstruct_inertia_matrix();
    LumpedBody {
        mass: mp.mass() as f64,
        inertia: DMat3::from_cols(i.x_axis.as_dvec3(), i.y_axis.as_dvec3(), i.z_axis.as_dvec3()),
        position,
        rotation,
        com: mp.local_com.as_dvec3(),
    }
}

/// The velocities (of the centre of mass, m/s, and angular, rad/s) that
/// move a body from its pose to its `next_position` in `h` s: what rapier
/// gives a position-based kinematic body at its step
/// (`RigidBodyPosition::interpolate_velocity`), in f64.
fn velocities_to_target(rb: &rp::RigidBody, h: f64) -> (DVec3, DVec3) {
    let (pose, next) = (rb.position(), rb.next_position());
    let com = rb.local_center_of_mass().as_dvec3();
    let (r0, r1) = (pose.rotation.as_dquat().normalize(), next.rotation.as_dquat().normalize());
    let (c0, c1) = (pose.translation.as_dvec3() + r0 * com, next.translation.as_dvec3() + r1 * com);
    let turn = r1 * r0.conjugate();
    let turn = if turn.w < 0.0 { -turn } else { turn };
    ((c1 - c0) / h, turn.to_scaled_axis() / h)
}

/// Sample of the point `anchor` (body frame) of a rapier body.
fn sample_body(rb: &rp::RigidBody, anchor: DVec3) -> BodySample {
    let (p, r) = pose_of(rb);
    let a = r * anchor;
    let w = rb.angvel().as_dvec3();
    let com = rb.center_of_mass().as_dvec3();
    let v = rb.linvel().as_dvec3() + w.cross(p + a - com);
    BodySample { t0: 0.0, position: p + a, rotation: r, velocity: v, angular_velocity: w, acceleration: DVec3::ZERO }
}

/// The motion of the point `anchor` (body frame) of a body moving as `m`.
fn at_anchor(s: BaseState, anchor: DVec3) -> BaseState {
    let r = s.rotation * anchor;
    let (w, al) = (s.angular_velocity, s.angular_acceleration);
    BaseState {
        rotation: s.rotation,
        position: s.position + r,
        angular_velocity: w,
        velocity: s.velocity + w.cross(r),
        angular_acceleration: al,
        acceleration: s.acceleration + al.cross(r) + w.cross(w.cross(r)),
    }
}

/// A start held by a base: clamped (tangent held) or pinned.
fn held_start(b: BaseMotion, clamp: bool) -> RopeStart {
    if clamp {
        RopeStart::Clamped(b)
    } else {
        RopeStart::Pinned(b)
    }
}

/// An end held by an anchor spring to a target: clamped or pinned.
fn held_end(t: BaseMotion, clamp: bool) -> RopeEnd {
    if clamp {
        RopeEnd::Clamped(t)
    } else {
        RopeEnd::Pinned(t)
    }
}

/// The cables and their couplings (see the module docs).
#[derive(Debug, Default)]
pub struct Coupling {
    /// The cables, in the order they were added.
    pub cables: Vec<CoupledCable>,
}

impl Coupling {
    /// An empty core.
    pub fn new() -> Self {
        Coupling::default()
    }

    /// Builds the cables of `specs` and adds them (see [`build_cables`]);
    /// returns, per spec, where its rope is: (index of the cable in
    /// [`Coupling::cables`], rope index in it, [`Cable::rope`]: 0 for a
    /// cable's own rope, ≥ 1 for a rope grafted onto it at a hub), or why it
    /// was not built.
    pub fn add(
        &mut self,
        specs: &[CableSpec],
        bodies: &mut rp::RigidBodySet,
        joints: &mut rp::ImpulseJointSet,
        motions: &HashMap<rp::RigidBodyHandle, BodyMotion>,
    ) -> Vec<Result<(usize, usize), CouplingError>> {
        let existing: Vec<&CoupledCable> = self.cables.iter().collect();
        let built = build_cables(specs, &existing, bodies, joints, motions);
        let mut index = vec![None; specs.len()];
        let mut out: Vec<Result<(usize, usize), CouplingError>> = Vec::with_capacity(specs.len());
        let mut parts = Vec::new();
        for (i, r) in built.into_iter().enumerate() {
            out.push(match r {
                Ok(Built::Cable(cc)) => {
                    self.cables.push(*cc);
                    index[i] = Some(self.cables.len() - 1);
                    Ok((self.cables.len() - 1, 0))
                }
                Ok(Built::Part { onto, part }) => {
                    parts.push((i, onto, part));
                    Ok((usize::MAX, part))
                }
                Err(e) => Err(e),
            });
        }
        for (i, onto, part) in parts {
            out[i] = Ok((index[onto].expect("a part's carrying cable is built"), part));
        }
        out
    }

    /// Phase 1 over every cable: [`step_cables`], the cables' solves run by
    /// `each` ([`OneByOne`] or [`Threads`]).
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        bodies: &mut rp::RigidBodySet,
        colliders: &rp::ColliderSet,
        joints: &mut rp::ImpulseJointSet,
        h: f64,
        substeps: u32,
        inputs: &dyn Fn(rp::RigidBodyHandle) -> BodyInputs,
        motions: &dyn Fn(rp::RigidBodyHandle) -> Option<BodyMotion>,
        each: &dyn ForEachCable,
    ) -> Vec<(usize, f64, CableError)> {
        let mut all: Vec<&mut CoupledCable> = self.cables.iter_mut().collect();
        step_cables(&mut all, bodies, Contacts { colliders, motions, jointed: &[], kinematic: &[] }, joints, h, substeps, inputs, each)
    }

    /// Phase 2 over every cable: [`after_rapier`].
    pub fn after_rapier(&mut self, bodies: &mut rp::RigidBodySet, colliders: &rp::ColliderSet, narrow_phase: &rp::NarrowPhase) {
        let mut all: Vec<&mut CoupledCable> = self.cables.iter_mut().collect();
        after_rapier(&mut all, bodies, colliders, narrow_phase)
    }

    /// For every explicit coupling: (cable index, body, `true` at the
    /// cable's start, k·h²/m) with `k = EA/L_e` of the cable's elements and
    /// `m` the body's mass, at step `h`. Above about 1 the coupling may be
    /// unstable unless joints hold the body.
    pub fn explicit_ratios(&self, bodies: &rp::RigidBodySet, h: f64) -> Vec<(usize, rp::RigidBodyHandle, bool, f64)> {
        self.cables.iter().enumerate().flat_map(|(i, cc)| cc.explicit_ratios(bodies, h).into_iter().map(move |(b, s, r)| (i, b, s, r))).collect()
    }
}

impl CoupledCable {
    /// Gives the cable the velocities of the bodies it carries (`velocity`:
    /// a body's centre-of-mass velocity, m/s, and angular velocity, rad/s;
    /// the adapters read rapier's, or the scenario's exact values) as its
    /// initial rates ([`Cable::set_link_velocities`]: the rates of least
    /// stiffness energy). Does nothing when they are all at rest. On error,
    /// returns the body whose velocity the chain cannot take (or the first
    /// moving one).
    pub fn start_velocities(&mut self, velocity: &dyn Fn(rp::RigidBodyHandle) -> (DVec3, DVec3)) -> Result<(), (rp::RigidBodyHandle, CableError)> {
        let cc = self;
        let targets: Vec<(rp::RigidBodyHandle, LinkVelocity)> = cc
            .carried
            .iter()
            .map(|c| {
                let (linear, angular) = velocity(c.body);
                let link = LinkVelocity { link: c.place.link, point: c.place.origin + c.place.rotation * c.com, linear, angular };
                (c.body, link)
            })
            .collect();
        if targets.iter().all(|(_, t)| t.linear == DVec3::ZERO && t.angular == DVec3::ZERO) {
            return Ok(());
        }
        let links: Vec<LinkVelocity> = targets.iter().map(|(_, t)| *t).collect();
        cc.cable.set_link_velocities(&links).map_err(|e| {
            let who = match &e {
                CableError::Velocity { link, .. } => targets.iter().find(|(_, t)| t.link == *link).map(|(b, _)| *b),
                _ => None,
            };
            let who = who.or_else(|| targets.iter().find(|(_, t)| t.linear != DVec3::ZERO || t.angular != DVec3::ZERO).map(|(b, _)| *b));
            (who.expect("a moving body exists here"), e)
        })
    }

    /// For every explicit coupling of this cable: (body, `true` at the
    /// cable's start, k·h²/m) with `k = EA/L_e` and `m` the body's mass, at
    /// step `h` (see [`Coupling::explicit_ratios`]).
    pub fn explicit_ratios(&self, bodies: &rp::RigidBodySet, h: f64) -> Vec<(rp::RigidBodyHandle, bool, f64)> {
        let k = self.cable.model.section.ea / self.cable.model.layout.element_length;
        self.followers
            .iter()
            .filter(|f| f.dynamic)
            .map(|f| (f.body, f.start, k * h * h / bodies.get(f.body).map_or(f64::INFINITY, |rb| rb.mass() as f64)))
            .collect()
    }
}

/// Switches off on a carried rapier body what the cable solve does for it:
/// gravity, forces, damping, sleeping and gyroscopic torques.
fn hand_to_cable(rb: &mut rp::RigidBody) {
    rb.set_gravity_scale(0.0, false);
    rb.reset_forces(false);
    rb.reset_torques(false);
    rb.set_linear_damping(0.0);
    rb.set_angular_damping(0.0);
    rb.enable_gyroscopic_forces(false);
    let act = rb.activation_mut();
    if act.normalized_linear_threshold >= 0.0 || act.angular_threshold >= 0.0 {
        *act = rp::RigidBodyActivation::cannot_sleep();
    }
}

/// A carried body whose mass properties changed in rapier since its link
/// took them (the user gave it another mass, centre of mass or inertia: a
/// crate loaded, `ColliderMassProperties` or `AdditionalMassProperties`
/// edited, a collider added): its share of its link's mass properties is
/// replaced by the new ones, from this step on. The link keeps its
/// velocity (as rapier keeps a body's when its mass changes), and the rope
/// and the other bodies on the link keep their share.
fn reweigh(cable: &mut Cable, c: &mut CarriedLink, rb: &rp::RigidBody) {
    let mprops = rb.mass_properties().local_mprops;
    if mprops == c.mprops {
        return;
    }
    let lb = lumped_of(rb);
    // The body's share, in the link frame.
    let share = |mass: f64, com: DVec3, inertia: DMat3| {
        let r = c.place.rotation;
        LinkMass::new(mass, c.place.origin + r * com, r * inertia * r.transpose())
    };
    // The old share negated: combined with the link's, it takes the old
    // share out again (mass, first and second moments add, so this is
    // exact up to rounding).
    let (old, new) = (share(-c.mass, c.com, -c.inertia), share(lb.mass, lb.com, lb.inertia));
    let Some(lm) = cable.model.chain.joint_mut_same_layout(c.place.link).and_then(|j| j.link.as_mut()) else {
        return;
    };
    let rest = if lm.mass - c.mass > 1e-12 * lm.mass { Some(lm.combine(&old)) } else { None };
    let damping = (lm.linear_damping, lm.angular_damping);
    *lm = match rest {
        Some(rest) => rest.combine(&new),
        None => new,
    };
    (lm.linear_damping, lm.angular_damping) = damping;
    (c.mass, c.com, c.inertia, c.mprops) = (lb.mass, lb.com, lb.inertia, mprops);
}

/// Switches off the motors of a trolley's rail joint in rapier (the cable
/// solve drives the rail).
fn mute_motor(joints: &mut rp::ImpulseJointSet, joint: rp::ImpulseJointHandle) {
    if let Some(j) = joints.get_mut(joint, false) {
        if j.data.motors.iter().any(|m| m.max_force != 0.0) {
            for m in j.data.motors.iter_mut() {
                m.max_force = 0.0;
            }
        }
    }
}

/// The motion of a base body's point `anchor` (body frame): closed form
/// from `motions`, fixed, or sampled from rapier every step (a new
/// [`Follower`]).
fn base_motion(
    body: rp::RigidBodyHandle,
    anchor: DVec3,
    start: bool,
    rb: &rp::RigidBody,
    motions: &HashMap<rp::RigidBodyHandle, BodyMotion>,
    followers: &mut Vec<Follower>,
) -> BaseMotion {
    if let Some(m) = motions.get(&body) {
        if rb.is_fixed() {
            return BaseMotion::Fixed(at_anchor(m(0.0), anchor));
        }
        let m = m.clone();
        return BaseMotion::Prescribed(Arc::new(move |t| at_anchor(m(t), anchor)));
    }
    if rb.is_fixed() {
        let (p, r) = pose_of(rb);
        return BaseMotion::Fixed(BaseState::fixed(r, p + r * anchor));
    }
    static NEXT_SOURCE: AtomicUsize = AtomicUsize::new(0);
    let source = NEXT_SOURCE.fetch_add(1, Ordering::Relaxed);
    let sample = sample_body(rb, anchor);
    followers.push(Follower { body, anchor, start, dynamic: rb.is_dynamic(), sample, source, sampled: None, reaction: (DVec3::ZERO, DVec3::ZERO) });
    follow(&sample, source)
}

/// A rope end held by an anchor spring to a world point or to a body that
/// rapier keeps (base or explicit); returns the end and the point it is
/// held at now.
fn held_far_end(
    attach: Attach,
    bodies: &rp::RigidBodySet,
    motions: &HashMap<rp::RigidBodyHandle, BodyMotion>,
    followers: &mut Vec<Follower>,
) -> Result<(RopeEnd, Option<DVec3>), CouplingError> {
    Ok(match attach {
        Attach::Free => (RopeEnd::Free, None),
        Attach::World { point, clamp } => (held_end(BaseMotion::point(point), clamp), Some(point)),
        Attach::Body { body, anchor, clamp } => {
            let rb = &bodies[body];
            let (p, r) = pose_of(rb);
            let moving = !rb.is_fixed()
                && !motions.get(&body).is_some_and(|m| {
                    let (a, b) = (m(0.0), m(1.0));
                    a.rotation == b.rotation && a.angular_velocity == DVec3::ZERO
                });
            if clamp && rb.is_dynamic() {
                return Err(CouplingError::ClampedMovingEnd { why: "a dynamic body rapier keeps" });
            }
            if clamp && moving && !rb.is_dynamic() {
                return Err(CouplingError::ClampedMovingEnd { why: "a kinematic body that may turn" });
            }
            let t = base_motion(body, anchor, false, rb, motions, followers);
            (held_end(t, clamp), Some(p + r * anchor))
        }
    })
}

/// A cable's chain before its grafts and integrator: the rope model, the
/// bodies it carries (body, its exact mass properties if the adapter gave
/// them, place; `usize::MAX` link: the end body), the followers, and the
/// end body's initial pose (origin, orientation) in the chain.
struct Draft {
    model: RopeModel,
    carried: Vec<(rp::RigidBodyHandle, Option<LumpedBody>, BodyInChain)>,
    followers: Vec<Follower>,
    end_pose: Option<(DVec3, DMat3)>,
}

/// Builds one cable's own chain from its spec and the roles of its end
/// bodies.
fn draft(spec: &CableSpec, roles: EndRoles, bodies: &rp::RigidBodySet, motions: &HashMap<rp::RigidBodyHandle, BodyMotion>) -> Result<Draft, CouplingError> {
    let mut followers = Vec::new();
    let mut carried = Vec::new();
    let mut rope = spec.rope.clone();
    let start_point;
    rope = match (spec.start, roles[0]) {
        (Attach::Free, _) => {
            let p = spec.path.as_ref().and_then(|p| p.first()).ok_or(CouplingError::FreeStartNeedsPath)?;
            start_point = *p;
            rope.start(RopeStart::Free)
        }
        (Attach::World { point, clamp }, _) => {
            start_point = point;
            let b = BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, point));
            rope.start(held_start(b, clamp))
        }
        (Attach::Body { body, anchor, clamp }, Some((_, role))) => {
            let rb = &bodies[body];
            let (p, r) = pose_of(rb);
            start_point = p + r * anchor;
            if let Role::Trolley { axis, .. } = role {
                carried.push((body, spec.exact[0], BodyInChain { link: 0, rotation: DMat3::IDENTITY, origin: DVec3::ZERO }));
                rope.start(RopeStart::SlidingBody { body: spec.exact[0].unwrap_or_else(|| lumped_of(rb)), axis, anchor, clamp })
            } else if role == Role::Carried {
                carried.push((body, spec.exact[0], BodyInChain { link: FLOATING_BODY_LINK, rotation: DMat3::IDENTITY, origin: DVec3::ZERO }));
                rope.start(RopeStart::FloatingBody { body: spec.exact[0].unwrap_or_else(|| lumped_of(rb)), anchor, clamp })
            } else {
                let b = base_motion(body, anchor, true, rb, motions, &mut followers);
                rope.start(held_start(b, clamp))
            }
        }
        (Attach::Body { .. }, None) => unreachable!("classify gives every body end a role"),
    };
    let end_point;
    let mut end_body = None;
    rope = match (spec.end, roles[1]) {
        (Attach::Body { body, anchor, clamp }, Some((_, Role::Carried))) => {
            let rb = &bodies[body];
            let (p, r) = pose_of(rb);
            end_point = Some(p + r * anchor);
            carried.push((body, spec.exact[1], BodyInChain { link: usize::MAX, rotation: DMat3::IDENTITY, origin: DVec3::ZERO }));
            let lumped = spec.exact[1].unwrap_or_else(|| lumped_of(rb));
            end_body = Some((lumped.rotation, anchor));
            rope.end(RopeEnd::Body { body: lumped, anchor, clamp })
        }
        (end, _) => {
            let (e, point) = held_far_end(end, bodies, motions, &mut followers)?;
            end_point = point;
            rope.end(e)
        }
    };
    let path = match (&spec.path, end_point) {
        (Some(p), _) => p.clone(),
        (None, Some(e)) => vec![start_point, e],
        (None, None) => vec![start_point, start_point - DVec3::Y * spec.rope.length()],
    };
    // The end body sits where the path ends (its origin −R·anchor from there).
    let tip = *path.last().expect("a rope path has points");
    let end_pose = end_body.map(|(r, anchor): (DMat3, DVec3)| (tip - r * anchor, r));
    let model = rope.path(path).build()?;
    Ok(Draft { model, carried, followers, end_pose })
}

/// Grafts a cable's rope onto the chain of `draft`, whose end body is the
/// hub the cable is attached to (at its end when `reversed`, else at its
/// start). The limb starts at the hub and ends at the cable's other
/// attachment: an anchor spring, free, or a body the chain carries (`role`
/// [`Role::Carried`]: a payload below the hub; it becomes the limb's end
/// body and one of the draft's carried bodies).
fn graft(
    draft: &mut Draft,
    spec: &CableSpec,
    reversed: bool,
    roles: EndRoles,
    bodies: &rp::RigidBodySet,
    motions: &HashMap<rp::RigidBodyHandle, BodyMotion>,
) -> Result<(), CouplingError> {
    let (near, far) = if reversed { (spec.end, spec.start) } else { (spec.start, spec.end) };
    let far_k = usize::from(!reversed);
    let Attach::Body { anchor, clamp, .. } = near else {
        unreachable!("a grafted cable is attached to its hub");
    };
    let (origin, r) = draft.end_pose.expect("the carrying cable ends on the hub");
    let at = origin + r * anchor;
    let mut far_body = None;
    let (end, far_point) = match (far, roles[far_k]) {
        (Attach::Body { body, anchor, clamp }, Some((_, Role::Carried))) => {
            let rb = &bodies[body];
            let (p, r) = pose_of(rb);
            let exact = spec.exact[far_k];
            far_body = Some((body, exact));
            (RopeEnd::Body { body: exact.unwrap_or_else(|| lumped_of(rb)), anchor, clamp }, Some(p + r * anchor))
        }
        _ => held_far_end(far, bodies, motions, &mut draft.followers)?,
    };
    let path = match &spec.path {
        Some(p) if reversed => p.iter().rev().copied().collect(),
        Some(p) => p.clone(),
        None => match far_point {
            Some(e) => vec![at, e],
            None if reversed => return Err(CouplingError::FreeStartNeedsPath),
            None => vec![at, at - DVec3::Y * spec.rope.length()],
        },
    };
    let limb = spec.rope.clone().start(held_start(BaseMotion::Fixed(BaseState::fixed(r, at)), clamp)).end(end).path(path).build()?;
    let place = draft.model.layout.end_body.expect("the carrying cable ends on the hub");
    let part = draft.model.graft(limb, &place, reversed)?;
    if let Some((body, exact)) = far_body {
        let limb_end = draft.model.parts[part - 1].layout.end_body.expect("a limb built with an end body has one");
        draft.carried.push((body, exact, limb_end));
    }
    Ok(())
}

/// Finishes a drafted chain: the carried bodies' links and the cable with
/// its integrator.
fn finish(spec: &CableSpec, roles: EndRoles, parts: Vec<EndRoles>, draft: Draft, bodies: &rp::RigidBodySet) -> Result<CoupledCable, CouplingError> {
    let Draft { model, carried, followers, .. } = draft;
    let carried = carried
        .into_iter()
        .map(|(body, exact, mut place)| {
            if place.link == usize::MAX {
                place = model.layout.end_body.expect("end body built");
            }
            let lb = exact.unwrap_or_else(|| lumped_of(&bodies[body]));
            let link_damping = model.chain.joints()[place.link].link.map_or((0.0, 0.0), |l| (l.linear_damping, l.angular_damping));
            let rb = &bodies[body];
            CarriedLink {
                body,
                place,
                mass: lb.mass,
                inertia: lb.inertia,
                com: lb.com,
                link_damping,
                mprops: rb.mass_properties().local_mprops,
                mark: Some((rb.linvel(), rb.angvel())),
                left_at: None,
                landing: (DVec3::ZERO, DVec3::ZERO),
                contact: (DVec3::ZERO, DVec3::ZERO),
                touching: false,
            }
        })
        .collect();
    let cable = Cable::new(model, spec.scheme.clone()).map_err(|e| CouplingError::Cable(Box::new(e)))?;
    let fixed_loads = cable.model.chain.loads().len();
    let fixed_forces = cable.model.chain.forces().len();
    let fixed_pairs = cable.model.chain.pairs().len();
    Ok(CoupledCable {
        cable,
        roles,
        parts,
        carried,
        followers,
        fixed_loads,
        contact: spec.contact,
        fixed_forces,
        fixed_pairs,
        friction: contact::FrictionMemory::default(),
        body_contacts: false,
        failed: false,
        free_forces: Vec::new(),
        free_ends: Vec::new(),
        carried_solved: Vec::new(),
        carried_resting: Vec::new(),
        carried_hit: Vec::new(),
        carried_hit_last: Vec::new(),
        free_friction: Vec::new(),
        free_written: Vec::new(),
        advance_failure: None,
        steps: (0.0, 0.0),
        own: Vec::new(),
    })
}

/// Runs a job on every cable of a step: one after the other, or at once on
/// a thread pool (the cables of a step share no data while their own
/// solves run; the results are bit-identical either way).
pub trait ForEachCable: Sync {
    /// Calls `job` once on every cable.
    fn for_each(&self, cables: &mut [&mut CoupledCable], job: &(dyn Fn(&mut CoupledCable) + Sync));
}

/// [`ForEachCable`] one after the other, on the calling thread.
#[derive(Debug, Clone, Copy, Default)]
pub struct OneByOne;

impl ForEachCable for OneByOne {
    fn for_each(&self, cables: &mut [&mut CoupledCable], job: &(dyn Fn(&mut CoupledCable) + Sync)) {
        for cc in cables.iter_mut() {
            job(cc);
        }
    }
}

/// [`ForEachCable`] on up to `threads` threads of the standard library
/// (`std::thread::scope`; no pool is kept): the cables are dealt into one
/// group per thread, the costliest first (by the number of coordinates)
/// onto the least loaded group, and one group runs on the calling thread.
/// `cablesim` uses it; the Bevy plugin uses Bevy's compute task pool
/// instead. Each cable's solve is the same code on its own data, so the
/// results are bit-identical to [`OneByOne`]'s, whatever the thread count.
/// With fewer than two cables, or `threads` ≤ 1, it runs them one by one.
/// Starting the threads costs some tens of µs per step: worth it for
/// ropes of a hundred elements or more (`docs/performance.md`).
#[derive(Debug, Clone, Copy)]
pub struct Threads {
    /// Most threads to use (the calling thread counts as one).
    pub threads: usize,
}

impl ForEachCable for Threads {
    fn for_each(&self, cables: &mut [&mut CoupledCable], job: &(dyn Fn(&mut CoupledCable) + Sync)) {
        let groups = self.threads.min(cables.len());
        if groups <= 1 {
            return OneByOne.for_each(cables, job);
        }
        let cost = |cc: &CoupledCable| if cc.failed { 0 } else { cc.cable.state.q.len() + 1 };
        let mut order: Vec<usize> = (0..cables.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(cost(cables[i])));
        let (mut group_of, mut load) = (vec![0; cables.len()], vec![0usize; groups]);
        for i in order {
            let g = (0..groups).min_by_key(|&g| load[g]).unwrap_or(0);
            group_of[i] = g;
            load[g] += cost(cables[i]);
        }
        let mut dealt: Vec<Vec<&mut CoupledCable>> = (0..groups).map(|_| Vec::new()).collect();
        for (cc, &g) in cables.iter_mut().zip(&group_of) {
            dealt[g].push(&mut **cc);
        }
        std::thread::scope(|scope| {
            let mut rest = dealt.into_iter();
            let here = rest.next().unwrap_or_default();
            for group in rest {
                scope.spawn(move || group.into_iter().for_each(job));
            }
            here.into_iter().for_each(job);
        });
    }
}

/// Phase 1 of a step of length `h`, before rapier steps: samples the
/// followers (at each cable's own time), reads the carried bodies (`inputs` gives each one's force,
/// gravity scale and damping), steps every cable that has not failed in
/// `substeps` equal sub-steps (before its very first step it recomputes
/// its acceleration with the loads then acting), then hands the carried
/// bodies to rapier and applies the explicit reactions as impulses.
/// Returns the cables that failed in this step, with the error and the
/// time of the failing sub-step; a failed cable keeps its last good
/// state and is skipped from then on.
///
/// The cables' own solves (the costly part) are run by `each`: one by one
/// ([`OneByOne`], `cablesim`) or on a thread pool (the Bevy plugin runs
/// them on Bevy's compute task pool); the results are the same bits.
#[allow(clippy::too_many_arguments)]
pub fn step_cables(
    cables: &mut [&mut CoupledCable],
    bodies: &mut rp::RigidBodySet,
    contacts: Contacts<'_>,
    joints: &mut rp::ImpulseJointSet,
    h: f64,
    substeps: u32,
    inputs: &dyn Fn(rp::RigidBodyHandle) -> BodyInputs,
    each: &dyn ForEachCable,
) -> Vec<(usize, f64, CableError)> {
    // The dynamic bodies a joint holds and no cable does: moving obstacles
    // for the ropes (`Contacts::jointed`). Solved as the island's free
    // bodies, rapier's joint and contacts were not in the island's solve
    // and rapier's pose then stood: a rope let go on a hinged plank lying
    // on the ground was thrown 9.7 m up (2026-11-27).
    // (None without contacts.)
    let touching = any_contacts(cables);
    let jointed: Vec<rp::RigidBodyHandle> = if touching {
        let held = held_by_cables(cables);
        bodies
            .iter()
            .filter(|(h, rb)| rb.is_dynamic() && rb.is_enabled() && !held.contains(h) && joints.attached_joints(*h).next().is_some())
            .map(|(h, _)| h)
            .collect()
    } else {
        Vec::new()
    };
    // A position-based kinematic body moves over the step to the target
    // the user set; rapier gives it the velocities that do so only at its
    // own step, after this one, so until then it reads the last step's
    // (`Contacts::kinematic`). Met at those, a platform accelerating at
    // 2 m/s² carried a box (and the rope on it) a h slower each step: it
    // slid 8 cm back in 2 s (2026-11-27).
    // (None without contacts.)
    let kinematic: Vec<(rp::RigidBodyHandle, DVec3, DVec3)> = if touching {
        bodies
            .iter()
            .filter(|(_, rb)| rb.body_type() == rp::RigidBodyType::KinematicPositionBased)
            .map(|(handle, rb)| {
                let (v, w) = velocities_to_target(rb, h);
                (handle, v, w)
            })
            .collect()
    } else {
        Vec::new()
    };
    let contacts = Contacts { jointed: &jointed, kinematic: &kinematic, ..contacts };
    // 1. Sample every follower before any cable moves a body.
    for cc in cables.iter_mut().filter(|c| !c.failed) {
        let t = cc.cable.time();
        for f in &mut cc.followers {
            let Some(rb) = bodies.get(f.body) else {
                continue;
            };
            let mut s = sample_body(rb, f.anchor);
            s.t0 = t;
            let since = f.sampled.map(|t0| t - t0).filter(|d| *d > 0.0);
            // A dynamic body's velocity from its pose change (see BodySample::update).
            f.sample.update(s, since, rb.is_dynamic());
            cc.cable.model.chain.set_sampled(f.sample.motion(f.source));
            f.sampled = Some(t);
            f.reaction = (DVec3::ZERO, DVec3::ZERO);
        }
    }
    // 2. Carried bodies: impulses and loads; step the cables.
    let n = substeps.max(1);
    let mut failures = Vec::new();
    for cc in cables.iter_mut() {
        cc.free_forces.clear();
        cc.free_ends.clear();
        cc.carried_resting = std::mem::take(&mut cc.carried_solved);
        cc.carried_hit_last = std::mem::take(&mut cc.carried_hit);
    }
    for cc in cables.iter_mut().filter(|c| !c.failed) {
        cc.cable.model.chain.loads_mut().truncate(cc.fixed_loads);
        // Rapier may have re-read the user's joint motor and body settings.
        if let Some((_, Role::Trolley { joint, .. })) = cc.roles[0] {
            mute_motor(joints, joint);
        }
        // The impulses given to the carried bodies since the last step
        // (rapier's contacts, the user's impulses and velocity writes),
        // applied as jumps in the chain's rates once the step's loads are
        // set (`Cable::apply_impulse`).
        let mut impulses = Vec::new();
        for k in 0..cc.carried.len() {
            let Some(rb) = bodies.get_mut(cc.carried[k].body) else {
                continue;
            };
            hand_to_cable(rb);
            let c = &mut cc.carried[k];
            reweigh(&mut cc.cable, c, rb);
            let (_, r) = pose_of(rb);
            let i_world = r * c.inertia * r.transpose();
            // What the user did to the body since the core left it
            // (velocity writes, impulses), exactly as rapier stores it.
            let mut j = c.contact;
            // A contact impulse in two steps running is a persisting
            // contact (a body resting on a dynamic one): a load over the
            // step, which holds it as the old rule did; a new one (a
            // strike), a user's impulse or velocity write, a jump.
            let struck = c.contact != (DVec3::ZERO, DVec3::ZERO);
            let persisting = struck && c.touching;
            c.touching = struck;
            if let Some((v, w)) = c.mark {
                if rb.linvel() != v || rb.angvel() != w {
                    j.0 += (rb.linvel() - v).as_dvec3() * c.mass;
                    j.1 += i_world * (rb.angvel() - w).as_dvec3();
                }
            }
            c.contact = (DVec3::ZERO, DVec3::ZERO);
            let input = inputs(c.body);
            let g = cc.cable.model.chain.gravity;
            let mut force = input.force + g * (c.mass * (input.gravity_scale - 1.0));
            let mut moment = input.torque;
            let local_point = c.place.origin + c.place.rotation * c.com;
            if persisting {
                force += j.0 / h;
                moment += j.1 / h;
            } else if j.0 != DVec3::ZERO || j.1 != DVec3::ZERO {
                impulses.push((c.place.link, local_point, j));
            }
            let (link, mass) = (c.place.link, c.mass);
            let (ld, ad) = c.link_damping;
            if let Some(lm) = cc.cable.model.chain.joint_mut_same_layout(link).and_then(|j| j.link.as_mut()) {
                let share = mass / lm.mass;
                lm.linear_damping = ld + input.linear_damping * share;
                lm.angular_damping = ad + input.angular_damping * share;
            }
            if force != DVec3::ZERO || moment != DVec3::ZERO {
                cc.cable.model.chain.loads_mut().push(LinkLoad { link, force, local_point, moment });
            }
        }
        let step = h / n as f64;
        cc.steps = (h, step);
        // Without the last step's contacts (the step's own are found
        // below, on the cleared chain): their stick springs would take the
        // jump over the step, and a car on the ground whose `Velocity` the
        // user writes did not move at all.
        contact::clear(&mut cc.cable, cc.fixed_forces, cc.fixed_pairs);
        for (link, point, (impulse, angular)) in impulses {
            let over = cc.impulse_time(link, step);
            if let Err(e) = cc.cable.apply_impulse(link, point, impulse, angular, over) {
                cc.advance_failure = Some((cc.cable.time(), e));
            }
        }
    }
    // Contacts of the rope elements with rapier's colliders, frozen for the
    // step (the cable's own bodies excluded), and how many contact passes
    // each cable's step needs (see `contact_passes`).
    let mut passes: Vec<u32> = Vec::with_capacity(cables.len());
    for (ci, cc) in cables.iter_mut().enumerate() {
        cc.own.clear();
        let mut count = 1;
        if !cc.failed {
            // (The last step's contacts were cleared above.)
            cc.friction.discard_step();
            cc.body_contacts = false;
            // The acceleration a cable starts from, before its first step,
            // without its contacts: a rope laid a few micrometres into a
            // collider has a starting acceleration of thousands of m/s²
            // there, an impulse the contact spends in microseconds, which
            // generalized-α would carry into the whole first step (its
            // velocity update takes a quarter of it, and Newton started
            // from it), and the step failed at every split (a free rope
            // laid 10 µm into the ground, 2026-11-27).
            if cc.cable.steps == 0 {
                if let Err(e) = cc.cable.recompute_acceleration() {
                    cc.failed = true;
                    failures.push((ci, cc.cable.time(), e));
                    passes.push(count);
                    continue;
                }
            }
            if let Some(settings) = cc.contact {
                // The cable's own bodies, and a trolley's rail (rapier does not
                // collide jointed bodies either).
                let rails = cc.all_roles().filter_map(|(_, r)| match r {
                    Role::Trolley { joint, .. } => joints.get(*joint).map(|j| [j.body1(), j.body2()]),
                    _ => None,
                });
                let own: Vec<rp::RigidBodyHandle> = cc.all_roles().map(|(b, _)| *b).chain(cc.carried.iter().map(|c| c.body)).chain(rails.flatten()).collect();
                cc.own = own;
                let start = cc.cable.time();
                let (ropes, deepest) = contact::add_contacts(&mut cc.cable, &settings, &mut cc.friction, &contacts, bodies, &cc.own, h, start);
                // A rope laid into a collider is refused at its first step
                // (`CableError::StartsInside`).
                let radius = 0.5 * cc.cable.model.diameter;
                if let Some(d) = deepest.filter(|d| cc.cable.steps == 0 && d.depth > STARTS_INSIDE * radius) {
                    // (Its contacts dropped: read at the refused start,
                    // they reported meganewtons.)
                    contact::clear(&mut cc.cable, cc.fixed_forces, cc.fixed_pairs);
                    cc.friction.discard_step();
                    cc.failed = true;
                    failures.push((
                        ci,
                        start,
                        CableError::StartsInside { rope: d.rope, node: d.node, element: d.element, point: d.point, depth: d.depth, radius },
                    ));
                    passes.push(count);
                    continue;
                }
                let ropes = ropes.max(contact::add_self_contacts(&mut cc.cable, &settings, &mut cc.friction, h));
                let (any, carried) = contact::add_body_contacts(&mut cc.cable, &cc.carried, &mut cc.friction, &contacts, bodies, &cc.own, h, start);
                cc.body_contacts = any;
                cc.friction.attach(&mut cc.cable.model.chain, cc.fixed_forces);
                count = contact_passes(ropes.max(carried), h);
            }
        }
        passes.push(count);
    }
    // Ropes of different cables that touch: such cables form an island,
    // stepped as one system (`advance_island`).
    let free = free_bodies(cables, bodies, &contacts);
    let islands = cable_islands(cables, &free, bodies, contacts.colliders, h);
    let mut alone = vec![true; cables.len()];
    for island in &islands {
        island.members.iter().for_each(|&i| alone[i] = false);
    }
    // A cable touching no other and no free body keeps no such touches.
    for (cc, _) in cables.iter_mut().zip(&alone).filter(|(_, a)| **a) {
        cc.friction.cross_pairs.clear();
        cc.free_friction.clear();
    }
    // The other cables' own solves: independent of each other and of
    // rapier (every body a cable reads was sampled or handed over above),
    // so they may run at once; the results do not depend on the order.
    // A cable alone takes its passes (one, unless its contacts close
    // fast); a step that fails is taken again from where it failed with
    // its contacts found more often (`retry_alone`, `advance_alone`).
    let advance = |cc: &mut CoupledCable| {
        if !cc.failed {
            advance_by(cc, h, n);
        }
    };
    if passes.iter().zip(&alone).all(|(&p, &a)| p == 1 || !a) {
        let mut loners: Vec<&mut CoupledCable> = cables.iter_mut().zip(&alone).filter(|(_, a)| **a).map(|(c, _)| &mut **c).collect();
        // Each one's start, and whether a failure was recorded before its
        // advance (an impulse it could not take): that one is not retried.
        let starts: Vec<(f64, bool)> = loners.iter().map(|cc| (cc.cable.time(), cc.advance_failure.is_some())).collect();
        each.for_each(&mut loners, &advance);
        // (The retries one by one: the contact search is not shared
        // between threads.)
        for (cc, &(start, before)) in loners.iter_mut().zip(&starts) {
            if cc.advance_failure.is_some() && !before {
                retry_alone(cc, &contacts, bodies, (start, start + h), 1, n);
            }
        }
    } else {
        // A cable whose contacts close fast finds them again at each of its
        // passes (cables one by one: the same bits as at once).
        for ((cc, &count), _) in cables.iter_mut().zip(&passes).zip(&alone).filter(|(_, a)| **a) {
            if !cc.failed {
                // (More than one pass only with contacts on.)
                let count = if cc.contact.is_some() { count } else { 1 };
                advance_alone(cc, &contacts, bodies, h, count, n, count == 1);
            }
        }
    }
    for island in &islands {
        let count = island.members.iter().map(|&i| passes[i]).max().unwrap_or(1).max(island.passes);
        advance_island(cables, island, &contacts, bodies, inputs, h, count, n);
    }
    for (ci, cc) in cables.iter_mut().enumerate() {
        if let Some((time, e)) = cc.advance_failure.take() {
            cc.failed = true;
            failures.push((ci, time, e));
        } else if !cc.failed {
            remember_contacts(cc, h);
        }
    }
    // 3. Hand the carried bodies to rapier; explicit reactions.
    // The ropes' contact forces on the jointed bodies, as impulses.
    for &handle in &jointed {
        let Some(rb) = bodies.get_mut(handle) else {
            continue;
        };
        let com = rb.center_of_mass().as_dvec3();
        let (force, moment) = cables.iter().filter(|c| !c.failed).fold((DVec3::ZERO, DVec3::ZERO), |(f, m), c| {
            let (df, dm) = c.obstacle_wrench(handle, com);
            (f + df, m + dm)
        });
        if force != DVec3::ZERO || moment != DVec3::ZERO {
            rb.apply_impulse((force * h).as_vec3(), true);
            rb.apply_torque_impulse((moment * h).as_vec3(), true);
        }
    }
    for cc in cables.iter_mut().filter(|c| !c.failed) {
        for k in 0..cc.carried.len() {
            let (p1, r1, _, _) = cc.carried_state(&cc.carried[k]);
            let c = &mut cc.carried[k];
            let Some(rb) = bodies.get_mut(c.body) else {
                continue;
            };
            // Rapier moves the centre of mass by v·h and turns the body
            // by exp(ω h) about it.
            let (p0, r0) = pose_of(rb);
            let v = (p1 + r1 * c.com - (p0 + r0 * c.com)) / h;
            let w = rotation_vector(&(r1 * r0.transpose())) / h;
            rb.set_linvel(v.as_vec3(), true);
            rb.set_angvel(w.as_vec3(), true);
            c.landing = (rb.linvel().as_dvec3(), rb.angvel().as_dvec3());
        }
        let time = cc.cable.time();
        for f in cc.followers.iter_mut().filter(|f| f.dynamic) {
            let Some(rb) = bodies.get_mut(f.body) else {
                continue;
            };
            let com = rb.center_of_mass().as_dvec3();
            let (force, moment) = reaction(&cc.cable, f.start, com, time);
            f.reaction = (force, moment);
            rb.apply_impulse((force * h).as_vec3(), true);
            rb.apply_torque_impulse((moment * h).as_vec3(), true);
        }
    }
    failures
}

/// Steps a cable that is alone (in no island) by `h` (s) in `count`
/// contact passes of `n` sub-steps each, its contacts found again at each
/// pass's start (with `found`, the first pass keeps those found at the
/// step's start). If a pass fails and the cable had contacts in it, the
/// rest of the step is taken again from where the failure left the cable
/// (the start of its failing sub-step) with twice the passes, up to
/// [`MAX_CONTACT_PASSES`], as an island's step is: a contact is a plane
/// frozen for its pass, and a rope that wraps round a post's corner within
/// one pass is held by the corner's plane where there is no post.
/// Measured on a newcomer's rope between two posts (12 m of 16 mm steel
/// rope pinned 5 cm above two 0.2 m posts 10 m apart, laid as a
/// horizontal parabola, swinging down): the pass from 0.25 s to 0.267 s
/// failed at every split down to 65 µs, its one contact the plane through
/// the corner of a post's top, found at 0.25 s. Steps that pass their
/// first attempt give the same bits as before.
fn advance_alone(cc: &mut CoupledCable, contacts: &Contacts<'_>, bodies: &rp::RigidBodySet, h: f64, count: u32, n: u32, found: bool) -> bool {
    let start = cc.cable.time();
    let count = count.max(1);
    // (A failure recorded before the advance, an impulse the cable could
    // not take, is not retried.)
    let before = cc.advance_failure.is_some();
    passes_alone(cc, contacts, bodies, (start, h), count, n, found) || (!before && retry_alone(cc, contacts, bodies, (start, start + h), count, n))
}

/// [`advance_alone`]'s retry after a pass of `count` failed in the step
/// from `step_start` to `end` (s): if the cable had contacts in it, the
/// rest of the step again from where the failure left the cable, in twice
/// the passes, doubled again at each failure up to
/// [`MAX_CONTACT_PASSES`]. Answers whether the cable reached `end`;
/// otherwise its failure is the last attempt's.
fn retry_alone(cc: &mut CoupledCable, contacts: &Contacts<'_>, bodies: &rp::RigidBodySet, (step_start, end): (f64, f64), mut count: u32, n: u32) -> bool {
    while cc.contact.is_some() && count < MAX_CONTACT_PASSES && cc.friction.has_contacts() {
        cc.advance_failure = None;
        count = (2 * count).min(MAX_CONTACT_PASSES);
        let span = end - cc.cable.time();
        if passes_alone(cc, contacts, bodies, (step_start, span), count, n, false) {
            return true;
        }
    }
    false
}

/// `count` contact passes of a cable alone over `span` s from its time,
/// in a step that started at `step_start` (s; the colliders' poses are
/// rapier's then), `n` sub-steps each, its contacts found again at each
/// pass's start (with `found`, the first pass keeps the contacts it has).
/// Answers whether every pass succeeded (on failure the cable is at the
/// start of its failing sub-step, `advance_failure` set).
fn passes_alone(
    cc: &mut CoupledCable,
    contacts: &Contacts<'_>,
    bodies: &rp::RigidBodySet,
    (step_start, span): (f64, f64),
    count: u32,
    n: u32,
    found: bool,
) -> bool {
    let hp = span / count as f64;
    for k in 0..count {
        if let Some(settings) = cc.contact.filter(|_| !(k == 0 && found)) {
            find_contacts(cc, &settings, contacts, bodies, hp, step_start);
        }
        if !advance_by(cc, hp, n) {
            return false;
        }
        if k + 1 < count {
            remember_contacts(cc, hp);
        }
    }
    true
}

/// Steps `cc`'s cable by `h` (s) in `n` equal sub-steps; on a failure, records it
/// with the failing sub-step's time and returns `false`.
fn advance_by(cc: &mut CoupledCable, h: f64, n: u32) -> bool {
    let t = cc.cable.time();
    let hs = h / n as f64;
    for k in 0..n {
        if let Err(e) = cc.cable.step(hs) {
            cc.advance_failure = Some((t + k as f64 * hs, e));
            return false;
        }
    }
    true
}

/// This pass's contacts of `cc` (its ropes and carried bodies against
/// rapier's colliders, its ropes against themselves), found again at the
/// pass's start with the pass's speculative reach (`hp` s), leaving out
/// the cable's own bodies (`own`).
fn find_contacts(cc: &mut CoupledCable, settings: &CableContact, contacts: &Contacts<'_>, bodies: &rp::RigidBodySet, hp: f64, start: f64) {
    contact::clear(&mut cc.cable, cc.fixed_forces, cc.fixed_pairs);
    cc.friction.discard_step();
    contact::add_contacts(&mut cc.cable, settings, &mut cc.friction, contacts, bodies, &cc.own, hp, start);
    contact::add_self_contacts(&mut cc.cable, settings, &mut cc.friction, hp);
    cc.body_contacts = contact::add_body_contacts(&mut cc.cable, &cc.carried, &mut cc.friction, contacts, bodies, &cc.own, hp, start).0;
    cc.friction.attach(&mut cc.cable.model.chain, cc.fixed_forces);
}

/// Cables whose ropes touch each other at a step's start (within the
/// speculative reach), and the free dynamic bodies that touch their ropes,
/// stepped as one system: the cable indices (in order), the bodies, and
/// the passes their closing speed asks for.
struct Island {
    members: Vec<usize>,
    /// Each body, and whether the island can solve its contacts with
    /// fixed and kinematic colliders ([`contact::touches_are_solved`]; no
    /// joint holds a free body, [`Contacts::jointed`]).
    bodies: Vec<(rp::RigidBodyHandle, bool)>,
    passes: u32,
    /// The carried bodies a free body strikes at the step's start, as
    /// (free body, carried body): rapier's (`contact::carried_pairs`).
    struck: Vec<(rp::RigidBodyHandle, rp::RigidBodyHandle)>,
}

/// Whether a cable that has not failed has its contacts on.
fn any_contacts(cables: &[&mut CoupledCable]) -> bool {
    cables.iter().any(|c| !c.failed && c.contact.is_some())
}

/// The bodies the cables hold: their ends' bodies, carried bodies and
/// followers.
fn held_by_cables(cables: &[&mut CoupledCable]) -> Vec<rp::RigidBodyHandle> {
    cables.iter().flat_map(|c| c.all_roles().map(|(b, _)| *b).chain(c.carried.iter().map(|k| k.body)).chain(c.followers.iter().map(|f| f.body))).collect()
}

/// The dynamic rapier bodies no cable holds (not a cable's end, carried
/// body, follower or rail) and no joint holds ([`Contacts::jointed`]:
/// obstacles), with colliders, that may touch a rope: each with a bound
/// on its surface's speed (m/s).
fn free_bodies(cables: &[&mut CoupledCable], bodies: &rp::RigidBodySet, contacts: &Contacts<'_>) -> Vec<(rp::RigidBodyHandle, f64)> {
    let colliders = contacts.colliders;
    if !any_contacts(cables) {
        return Vec::new();
    }
    let mut held = held_by_cables(cables);
    held.extend(cables.iter().flat_map(|cc| cc.own.iter().copied()));
    let mut free: Vec<(rp::RigidBodyHandle, f64)> = bodies
        .iter()
        .filter(|(h, rb)| rb.is_dynamic() && rb.is_enabled() && !held.contains(h) && !contacts.jointed.contains(h))
        .filter(|(_, rb)| rb.colliders().iter().any(|c| colliders.get(*c).is_some_and(|c| !c.is_sensor())))
        .map(|(h, rb)| (h, rb.linvel().as_dvec3().length() + rb.angvel().as_dvec3().length() * contact::body_extent(rb, colliders)))
        .collect();
    // (Rapier's arena order: the same on every run.)
    free.sort_by_key(|(h, _)| h.into_raw_parts());
    free
}

/// [`pair_search_inputs`]'s two aligned lists.
type PairSearch<'a> = (Vec<(&'a Cable, &'a CableContact)>, Vec<&'a [Vec<DVec3>]>);

/// What [`contact::rope_pairs`] searches between the cables `indices` of
/// `cables` that have contacts on, in that order: each cable with its
/// contact settings, and its ropes' start accelerations
/// ([`contact::FrictionMemory::start_accelerations_of`]), built together so
/// that the two lists stay aligned.
fn pair_search_inputs<'a>(cables: &'a [&mut CoupledCable], indices: &[usize]) -> PairSearch<'a> {
    indices
        .iter()
        .filter_map(|&i| {
            let cc = &*cables[i];
            Some(((&cc.cable, cc.contact.as_ref()?), cc.friction.start_accelerations_of(&cc.cable)))
        })
        .unzip()
}

/// The islands of this step: the cables with contacts on that have not
/// failed, joined by the contacts between their ropes and by the free
/// bodies that touch them (union–find; each island's cables in cable
/// order, islands in the order of their first cable). A cable alone is
/// not listed.
fn cable_islands(
    cables: &[&mut CoupledCable],
    free: &[(rp::RigidBodyHandle, f64)],
    bodies: &rp::RigidBodySet,
    colliders: &rp::ColliderSet,
    h: f64,
) -> Vec<Island> {
    let candidates: Vec<usize> = (0..cables.len()).filter(|&i| !cables[i].failed && cables[i].contact.is_some()).collect();
    if candidates.is_empty() || (candidates.len() < 2 && free.is_empty()) {
        return Vec::new();
    }
    let (list, accelerations) = pair_search_inputs(cables, &candidates);
    let (pairs, mut approach) = contact::rope_pairs(&list, &accelerations, h, false);
    let extents: Vec<contact::CableExtent> = list.iter().map(|(cable, _)| contact::CableExtent::of(cable)).collect();
    // Nodes 0.. are the candidates, then the free bodies.
    let nodes = candidates.len() + free.len();
    let mut root: Vec<usize> = (0..nodes).collect();
    fn find(root: &mut [usize], mut i: usize) -> usize {
        while root[i] != i {
            root[i] = root[root[i]];
            i = root[i];
        }
        i
    }
    let join = |root: &mut Vec<usize>, a: usize, b: usize| {
        let (a, b) = (find(root, a), find(root, b));
        root[a.max(b)] = a.min(b);
    };
    for p in &pairs {
        join(&mut root, p.cable_a, p.cable_b);
    }
    approach.resize(nodes, 0.0);
    let mut struck = Vec::new();
    for (k, &(handle, speed)) in free.iter().enumerate() {
        let Some(rb) = bodies.get(handle) else {
            continue;
        };
        let shapes = contact::BodyShapes::of(rb, colliders);
        let (origin, rotation) = pose_of(rb);
        let resting: Vec<rp::RigidBodyHandle> =
            cables.iter().flat_map(|c| c.carried_resting.iter().chain(&c.carried_hit_last)).filter(|(f, _)| *f == handle).map(|(_, c)| *c).collect();
        for (c, (cable, settings)) in list.iter().enumerate() {
            let (touches, closing) = contact::body_pairs((cable, &extents[c]), settings, c, &shapes, (origin, rotation), speed, 0, FreeBody::LINK, h);
            let carried = contact::carried_pairs(
                cable,
                &cables[candidates[c]].carried,
                c,
                (bodies, colliders),
                (rb.mass() as f64, &shapes),
                (origin, rotation),
                (rb.linvel().as_dvec3(), rb.angvel().as_dvec3(), rb.local_center_of_mass().as_dvec3()),
                speed,
                (0, FreeBody::LINK),
                (h, Some((strike_speed(cable, h), &resting))),
                &[],
            );
            struck.extend(carried.struck.iter().map(|&c| (handle, c)));
            let closing = closing.max(carried.approach);
            if !touches.is_empty() || !carried.pairs.is_empty() {
                join(&mut root, c, candidates.len() + k);
                approach[c] = approach[c].max(closing);
                approach[candidates.len() + k] = approach[candidates.len() + k].max(closing);
            }
        }
    }
    let mut size = vec![0usize; nodes];
    for k in 0..nodes {
        size[find(&mut root, k)] += 1;
    }
    let mut islands: Vec<Island> = Vec::new();
    let mut slot = vec![usize::MAX; nodes];
    for k in 0..nodes {
        let r = find(&mut root, k);
        if size[r] < 2 {
            continue;
        }
        if slot[r] == usize::MAX {
            slot[r] = islands.len();
            islands.push(Island { members: Vec::new(), bodies: Vec::new(), passes: 1, struck: struck.clone() });
        }
        let island = &mut islands[slot[r]];
        if k < candidates.len() {
            island.members.push(candidates[k]);
        } else {
            // Whether the island can solve its contacts with fixed and
            // kinematic colliders too: all its colliders have touch points
            // (asked of the island's bodies only, not of every dynamic body
            // at every step; a jointed body is an obstacle, not a free one).
            let handle = free[k - candidates.len()].0;
            let solvable = bodies.get(handle).is_some_and(|rb| contact::touches_are_solved(rb, colliders));
            island.bodies.push((handle, solvable));
        }
        island.passes = island.passes.max(contact_passes(approach[k], h));
    }
    islands
}

/// What [`put_free_body`] gave rapier (f32): the pose, and the velocities
/// if it set them. A body whose rapier state still reads exactly so at the
/// next step (nobody moved it) starts that step from the island's own f64
/// values: read back from rapier, a grounded body's pose was rounded to
/// f32 every frame (up to 0.5 µm at 8 m from the origin), micrometre jumps
/// of its stiff ground contacts and stick springs that the next step had
/// to undo (a crate resting on a 10° ramp under a short rope needed 32
/// sub-steps per frame, and failed at 16).
#[derive(Debug, Clone, Copy)]
struct Written {
    translation: glam::Vec3,
    rotation: glam::Quat,
    velocities: Option<(glam::Vec3, glam::Vec3)>,
}

/// A free body of an island between passes: its frame's pose and its
/// centre of mass's and angular velocities (world), and whether the
/// island solves its contacts with fixed and kinematic colliders.
#[derive(Debug, Clone, Copy)]
struct BodyPass {
    handle: rp::RigidBodyHandle,
    grounded: bool,
    origin: DVec3,
    rotation: DMat3,
    velocity: DVec3,
    angular_velocity: DVec3,
}

/// Steps the cables and free bodies of `island` together by `h` (s) in
/// `count` contact passes of `n` sub-steps each: every pass finds each
/// member's contacts again, the contacts between the members' ropes and
/// between their ropes and the bodies, and steps them as one system
/// ([`Cable::step_with_bodies`]). If a pass fails, the island goes back
/// to the step's start and tries again with twice the passes, up to
/// [`MAX_CONTACT_PASSES`]: contacts found again more often are what a step
/// with a rope bouncing off or wrapping over another needs (Newton's own
/// sub-steps keep the contacts of the pass's start; measured on
/// `cable_impact.toml`, where a pendant struck a taut rope and its step
/// after the impact, at two passes, failed at any split, and ran at
/// four). On a last failure every member records it. A free body stays
/// rapier's: the ropes' impulse on it over the step (its momentum change
/// in the joint solve, less what gravity and its applied forces gave) is
/// applied to it, and rapier moves it.
#[allow(clippy::too_many_arguments)]
fn advance_island(
    cables: &mut [&mut CoupledCable],
    island: &Island,
    contacts: &Contacts<'_>,
    bodies: &mut rp::RigidBodySet,
    inputs: &dyn Fn(rp::RigidBodyHandle) -> BodyInputs,
    h: f64,
    count: u32,
    n: u32,
) {
    let members = &island.members[..];
    let start = cables[members[0]].cable.time();
    let fail = |cables: &mut [&mut CoupledCable], t: f64, e: CableError| {
        for &i in members {
            cables[i].advance_failure = Some((t, e.clone()));
        }
    };
    // The free bodies' friction anchors on the ground, kept by whichever
    // member had them (the island's first cable keeps them after the
    // step): `None` for a body new to the island.
    let kept: Vec<Option<contact::FrictionMemory>> = island
        .bodies
        .iter()
        .map(|&(handle, _)| {
            members.iter().find_map(|&i| {
                let kept = &mut cables[i].free_friction;
                kept.iter().position(|(h, _)| *h == handle).map(|k| kept.swap_remove(k).1)
            })
        })
        .collect();
    let mut memories: Vec<contact::FrictionMemory> = Vec::with_capacity(kept.len());
    let mut starts: Vec<BodyPass> = Vec::with_capacity(kept.len());
    for (&(handle, solvable), memory) in island.bodies.iter().zip(kept) {
        let Some(rb) = bodies.get(handle) else {
            continue;
        };
        let (mut origin, mut rotation) = pose_of(rb);
        let (mut velocity, mut angular_velocity) = (rb.linvel().as_dvec3(), rb.angvel().as_dvec3());
        // The island's own values where rapier still holds what it was
        // given (`Written`).
        let written = members.iter().find_map(|&i| cables[i].free_written.iter().find(|(end, _)| end.handle == handle));
        if let Some((end, w)) = written {
            let p = rb.position();
            if p.translation == w.translation && p.rotation == w.rotation {
                (origin, rotation) = (end.origin, end.rotation);
                if w.velocities == Some((rb.linvel(), rb.angvel())) {
                    (velocity, angular_velocity) = (end.velocity, end.angular_velocity);
                }
            }
        }
        // A body new to the island comes from rapier's resting contacts,
        // sunk into the ground by rapier's allowed error: moved out of it.
        // (One that goes on comes from the island's pose, whose contact
        // preload the move would take away: a box sliding down a slope
        // under a rope then started every step with no normal force and
        // no friction, and slid 7 % faster than Coulomb's rate.) One sunk
        // deeper stays where it is, its contacts offset
        // (`FrictionMemory::sunk`).
        let grounded = solvable;
        if solvable && memory.is_none() {
            origin = contact::out_of_obstacles(handle, (origin, rotation), contacts, bodies, start);
        }
        let resting: Vec<rp::RigidBodyHandle> =
            members.iter().flat_map(|&i| cables[i].carried_resting.iter()).filter(|(f, _)| *f == handle).map(|(_, c)| *c).collect();
        let carried: Vec<(&Cable, &[CarriedLink])> = members.iter().map(|&i| (&cables[i].cable, &cables[i].carried[..])).collect();
        origin = contact::out_of_carried(handle, (origin, rotation), &carried, &resting, bodies, contacts.colliders);
        starts.push(BodyPass { handle, grounded, origin, rotation, velocity, angular_velocity });
        memories.push(memory.unwrap_or_default());
    }
    // (Those of bodies no longer in the island are dropped.)
    for &i in members {
        cables[i].free_friction.clear();
    }
    // What a retry goes back to.
    let saved: Vec<(State, Chain, u64, StepStats, contact::FrictionMemory)> = members
        .iter()
        .map(|&i| {
            let c = &cables[i];
            (c.cable.state.clone(), c.cable.model.chain.clone(), c.cable.steps, c.cable.total_stats, c.friction.clone())
        })
        .collect();
    let mut count = count.max(1);
    loop {
        let mut ends = starts.clone();
        let mut friction = memories.clone();
        match island_passes(cables, (members, &island.struck), &mut ends, &mut friction, contacts, bodies, inputs, h, count, n) {
            Ok(()) => {
                cables[members[0]].free_friction = starts.iter().map(|b| b.handle).zip(friction).collect();
                // The ropes' impulse on each free body, to rapier.
                let gravity = cables[members[0]].cable.model.chain.gravity;
                for (b0, b1) in starts.iter().zip(&ends) {
                    let input = inputs(b0.handle);
                    let Some(rb) = bodies.get_mut(b0.handle) else {
                        continue;
                    };
                    let body = lumped_of(rb);
                    let world = |r: DMat3| r * body.inertia * r.transpose();
                    let push = (b1.velocity - b0.velocity) * body.mass - (gravity * (body.mass * input.gravity_scale) + input.force) * h;
                    let turn = world(b1.rotation) * b1.angular_velocity - world(b0.rotation) * b0.angular_velocity - input.torque * h;
                    rb.apply_impulse(push.as_vec3(), true);
                    rb.apply_torque_impulse(turn.as_vec3(), true);
                    cables[members[0]].free_forces.push((b0.handle, push / h));
                    cables[members[0]].free_ends.push(*b1);
                }
                return;
            }
            Err(_) if count < MAX_CONTACT_PASSES => {
                for (&i, (state, chain, steps, stats, friction)) in members.iter().zip(&saved) {
                    let cc = &mut *cables[i];
                    cc.cable.state = state.clone();
                    cc.cable.model.chain = chain.clone();
                    (cc.cable.steps, cc.cable.total_stats) = (*steps, *stats);
                    cc.friction = friction.clone();
                    cc.cable.refresh();
                }
                count = (2 * count).min(MAX_CONTACT_PASSES);
            }
            Err((t, e)) => return fail(cables, t, e),
        }
    }
}

/// [`advance_island`]'s passes: `count` of them, `n` sub-steps each, the
/// free bodies from `free` (their state at the step's start, moved on to
/// the step's end); the time and error of a failure.
#[allow(clippy::too_many_arguments)]
fn island_passes(
    cables: &mut [&mut CoupledCable],
    (members, struck): (&[usize], &[(rp::RigidBodyHandle, rp::RigidBodyHandle)]),
    free: &mut [BodyPass],
    friction: &mut [contact::FrictionMemory],
    contacts: &Contacts<'_>,
    bodies: &rp::RigidBodySet,
    inputs: &dyn Fn(rp::RigidBodyHandle) -> BodyInputs,
    h: f64,
    count: u32,
    n: u32,
) -> Result<(), (f64, CableError)> {
    let start = cables[members[0]].cable.time();
    let hp = h / count as f64;
    let gravity = cables[members[0]].cable.model.chain.gravity;
    for k in 0..count {
        for &i in members {
            let cc = &mut *cables[i];
            if let Some(settings) = cc.contact {
                find_contacts(cc, &settings, contacts, bodies, hp, start);
            }
        }
        let t = cables[members[0]].cable.time();
        // The members with contacts (all of them: an island is made of ropes
        // that touch), as the pairs' chain indices count them.
        let listed: Vec<usize> = members.iter().copied().filter(|&i| cables[i].contact.is_some()).collect();
        let (list, accelerations) = pair_search_inputs(cables, &listed);
        let mut found = contact::rope_pairs(&list, &accelerations, hp, false).0;
        let extents: Vec<contact::CableExtent> = list.iter().map(|(cable, _)| contact::CableExtent::of(cable)).collect();
        // The free bodies at the pass's start, as chains of their own.
        // (A body rapier no longer has keeps its state and gets no chain.)
        let mut chains: Vec<(usize, FreeBody)> = Vec::with_capacity(free.len());
        let mut solved: Vec<(rp::RigidBodyHandle, rp::RigidBodyHandle)> = Vec::new();
        for (b, body) in free.iter().enumerate() {
            let Some(rb) = bodies.get(body.handle) else {
                continue;
            };
            let index = list.len() + chains.len();
            let input = inputs(body.handle);
            let lumped = lumped_of(rb);
            let mut chain = FreeBody::new(
                lumped.mass,
                lumped.com,
                lumped.inertia,
                body.origin,
                body.rotation,
                body.velocity,
                body.angular_velocity,
                gravity * input.gravity_scale,
                input.force,
                input.torque,
                t,
            )
            .map_err(|source| (t, CableError::Integrate(crate::integrate::IntegrateError::System { t, source })))?;
            if body.grounded {
                contact::add_free_body_contacts(&mut chain, body.handle, &mut friction[b], contacts, bodies, hp, t, start);
                // Its `Damping`, in the solve (after its contacts: their
                // friction memory counts the force elements from the first).
                let (linear, angular) = (rb.linear_damping() as f64, rb.angular_damping() as f64);
                if linear != 0.0 || angular != 0.0 {
                    let element = BodyDamping { linear: lumped.mass * linear, angular: lumped.inertia * angular };
                    chain.chain.forces_mut().push(crate::cable::AttachedForce { link: FreeBody::LINK, local_point: lumped.com, element: Arc::new(element) });
                }
            }
            let shapes = contact::BodyShapes::of(rb, contacts.colliders);
            let speed = body.velocity.length() + body.angular_velocity.length() * contact::body_extent(rb, contacts.colliders);
            for (c, (cable, settings)) in list.iter().enumerate() {
                let (pairs, _) =
                    contact::body_pairs((cable, &extents[c]), settings, c, &shapes, (body.origin, body.rotation), speed, index, FreeBody::LINK, hp);
                found.extend(pairs);
                let leave: Vec<rp::RigidBodyHandle> = struck.iter().filter(|(f, _)| *f == body.handle).map(|(_, c)| *c).collect();
                let carried = contact::carried_pairs(
                    cable,
                    &cables[listed[c]].carried,
                    c,
                    (bodies, contacts.colliders),
                    (lumped.mass, &shapes),
                    (body.origin, body.rotation),
                    (body.velocity, body.angular_velocity, lumped.com),
                    speed,
                    (index, FreeBody::LINK),
                    (hp, None),
                    &leave,
                );
                found.extend(carried.pairs);
                solved.extend(carried.touched.into_iter().map(|c| (body.handle, c)));
            }
            chains.push((b, chain));
        }
        // Their friction, from the same touches at the end of the last pass
        // (kept by the members).
        let elements: Vec<(crate::cable::PairContact, f64)> = found
            .iter()
            .map(|p| {
                let (a, b) =
                    (point_of(cables, &listed, &chains, p.cable_a, p.link_a, p.point_a), point_of(cables, &listed, &chains, p.cable_b, p.link_b, p.point_b));
                let recalled = contact::FrictionMemory::recall(listed.iter().map(|&i| &cables[i].friction.cross_pairs[..]), (a.point + b.point) * 0.5);
                contact::recalled_pair(p.element, p.mu, &a, &b, recalled)
            })
            .collect();
        let pairs: Vec<ForestPair> = found
            .into_iter()
            .zip(&elements)
            .map(|(p, element)| ForestPair {
                chain_a: p.cable_a,
                link_a: p.link_a,
                point_a: p.point_a,
                chain_b: p.cable_b,
                link_b: p.link_b,
                point_b: p.point_b,
                element: Arc::new(element.0),
            })
            .collect();
        let kept = &mut cables[members[0]].carried_solved;
        for pair in solved {
            if !kept.contains(&pair) {
                kept.push(pair);
            }
        }
        let hs = hp / n as f64;
        for _ in 0..n {
            let t = cables[members[0]].cable.time();
            let mut group: Vec<&mut Cable> = cables.iter_mut().enumerate().filter(|(i, _)| listed.contains(i)).map(|(_, c)| &mut c.cable).collect();
            let mut moving: Vec<&mut FreeBody> = chains.iter_mut().map(|(_, c)| c).collect();
            Cable::step_with_bodies(&mut group, &mut moving, pairs.clone(), hs).map_err(|e| (t, e))?;
        }
        for (b, chain) in &chains {
            let ((origin, rotation), (velocity, angular_velocity)) = (chain.pose(), chain.velocity());
            free[*b] = BodyPass { origin, rotation, velocity, angular_velocity, ..free[*b] };
            friction[*b].remember(chain.state.t, chain.chain.force_element_points());
        }
        // The friction states of the pairs between members and bodies (each
        // kept by its first point's cable), after every pass.
        for &i in members {
            cables[i].friction.cross_pairs.clear();
        }
        for (p, element) in pairs.iter().zip(&elements) {
            let (a, b) =
                (point_of(cables, &listed, &chains, p.chain_a, p.link_a, p.point_a), point_of(cables, &listed, &chains, p.chain_b, p.link_b, p.point_b));
            if let Some(&owner) = listed.get(p.chain_a) {
                cables[owner].friction.remember_cross(&element.0, &a, &b, hp, element.1);
            }
        }
        if k + 1 < count {
            for &i in members {
                remember_contacts(cables[i], hp);
            }
        }
    }
    Ok(())
}

/// The world state of point `local` of link `link` of an island pass's
/// chain `chain`: a member's (`listed`) or a free body's (`chains`, after
/// the members).
fn point_of(cables: &[&mut CoupledCable], listed: &[usize], chains: &[(usize, FreeBody)], chain: usize, link: usize, local: DVec3) -> crate::cable::PointState {
    match listed.get(chain) {
        Some(&i) => contact::chain_point(&cables[i].cable.model.chain, link, local),
        None => contact::chain_point(&chains[chain - listed.len()].1.chain, link, local),
    }
}

/// Where each contact's friction anchor goes for the next step (or pass)
/// of `h` s: `cc`'s contacts with rapier's colliders and its ropes' with
/// themselves, from their points now.
fn remember_contacts(cc: &mut CoupledCable, h: f64) {
    let t = cc.cable.time();
    let chain = &cc.cable.model.chain;
    cc.friction.remember(t, chain.force_element_points().skip(cc.fixed_forces));
    cc.friction.remember_pairs(chain.pair_points().skip(cc.fixed_pairs), h);
}

/// Approach (m) that one contact pass may close (or an obstacle near the
/// rope may move): contacts are frozen planes found at a pass's start,
/// and a rope struck by an obstacle that closes much more than this
/// within a pass fails its solve (measured on a taut steel rope struck at
/// 4 m/s: a cube runs at 1.7 cm per pass and fails at 3.3 cm; a ball,
/// which the rope wraps, fails at 9.5 mm and runs at 4.8 mm;
/// docs/architecture.md, "Contact").
pub const APPROACH_PER_PASS: f64 = 0.005;

/// How far (a fraction of the rope's radius) a rope's surface may start
/// inside a fixed or kinematic collider at the cable's first step; deeper,
/// the cable is refused ([`CableError::StartsInside`]). A steel rope
/// resting on steel sinks about a micrometre; the Hertz contact of a
/// free 20 mm rope laid 10 µm into the ground already throws it off
/// within the first step, and its solve failed there, at every split;
/// laid with its centre on the surface (half a diameter in), it failed
/// with a singular matrix; 5 cm in beside a box, it was thrown 2.6 km up.
/// Half the radius refuses a rope laid with its centre on a surface (the
/// first layout a new user tries) with a message that says what to do.
pub const STARTS_INSIDE: f64 = 0.5;

/// Most contact passes in one step.
pub const MAX_CONTACT_PASSES: u32 = 64;

/// How many contact passes a step of `h` (s) takes when its contacts
/// close at up to `approach` (m/s; or an obstacle near the rope moves that
/// fast): enough that each closes at most [`APPROACH_PER_PASS`], at most
/// [`MAX_CONTACT_PASSES`], at least 1. The cable's step then finds its
/// contacts again at the start of each pass (the obstacles at their exact
/// or extrapolated pose then) and steps the pass.
pub fn contact_passes(approach: f64, h: f64) -> u32 {
    let need = (approach * h / APPROACH_PER_PASS).ceil();
    if need.is_finite() && need > 1.0 {
        (need as u32).min(MAX_CONTACT_PASSES)
    } else {
        1
    }
}

/// Phase 2, after rapier's step: the velocity change rapier's contacts
/// gave each carried body (only if one of its colliders has an active
/// contact) is kept as an impulse for the next step; the body is put on
/// the cable's pose and velocity. A failed cable no longer holds its
/// bodies: they are left as rapier moved them.
pub fn after_rapier(cables: &mut [&mut CoupledCable], bodies: &mut rp::RigidBodySet, colliders: &rp::ColliderSet, narrow_phase: &rp::NarrowPhase) {
    let held = held_by_cables(cables);
    // Contacts between free and carried bodies that an island solved:
    // rapier's contact between the two only repeats it.
    let solved: Vec<(rp::RigidBodyHandle, rp::RigidBodyHandle)> = cables.iter().flat_map(|c| c.carried_solved.iter().copied()).collect();
    let parent = |other: rp::ColliderHandle| colliders.get(other).and_then(|c| c.parent());
    for cc in cables.iter_mut() {
        cc.free_written.clear();
        if cc.failed {
            cc.free_ends.clear();
            continue;
        }
        for end in std::mem::take(&mut cc.free_ends) {
            let solved_with = |other: rp::ColliderHandle| parent(other).is_some_and(|b| solved.contains(&(end.handle, b)));
            if let Some(written) = put_free_body(end, bodies, colliders, narrow_phase, &solved_with) {
                cc.free_written.push((end, written));
            }
        }
        for k in 0..cc.carried.len() {
            let strikes = reweigh_strikes(cc, k, &held, &solved, bodies, colliders, narrow_phase);
            let (p, r, v, w) = cc.carried_state(&cc.carried[k]);
            // Contacts with fixed and kinematic colliders are in the cable's
            // solve when its carried bodies' contacts are
            // (`add_body_contacts`): only the others (dynamic bodies) count
            // then.
            let me = cc.carried[k].body;
            let handled = |other: rp::ColliderHandle| {
                (cc.body_contacts && owner_is_dynamic(other, bodies, colliders) == Some(false)) || parent(other).is_some_and(|b| solved.contains(&(b, me)))
            };
            let touched = bodies.get(cc.carried[k].body).is_some_and(|rb| rapier_touches(rb, narrow_phase, |other| !handled(other)));
            let c = &mut cc.carried[k];
            let Some(rb) = bodies.get_mut(c.body) else {
                continue;
            };
            if touched {
                let (_, r_now) = pose_of(rb);
                let i_world = r_now * c.inertia * r_now.transpose();
                c.contact = ((rb.linvel().as_dvec3() - c.landing.0) * c.mass + strikes.0, i_world * (rb.angvel().as_dvec3() - c.landing.1) + strikes.1);
            }
            rb.set_position(rp::Pose::from_parts(p.as_vec3(), DQuat::from_mat3(&r).as_quat()), true);
            rb.set_linvel(v.as_vec3(), true);
            rb.set_angvel(w.as_vec3(), true);
            c.mark = Some((rb.linvel(), rb.angvel()));
            c.left_at = Some(rb.translation());
        }
    }
}

/// How fast (m/s) a free body and a carried one must close to strike
/// (rapier's contact, with its restitution) rather than touch (the
/// island's, `contact::carried_pairs`): two frame steps `h` (s) of
/// `cable`'s gravity. A body resting on a carried one closes at one.
fn strike_speed(cable: &Cable, h: f64) -> f64 {
    2.0 * cable.model.chain.gravity.length() * h
}

/// Rapier's contacts between carried body `k` of `cc` and the dynamic
/// bodies no cable holds (a ball striking a payload, a crate resting on a
/// plank), weighed again with the cable's answer at the contact point.
/// Rapier solved each as if the carried body were free, with its own mass:
/// a 60 kg ball dropped at 5 m/s on a 10 kg plank hung on two taut steel
/// ropes was slowed by a seventh of the closing speed per step, as by a
/// free plank, while the ropes held the plank: the ball sank through it
/// (2026-11-29). For each such pair, the normal impulse `λ` rapier gave is
/// scaled by `(w_free + w_B) / (w_cable + w_B)`, the mobilities along the
/// normal at the impulse's point of the free body (`1/m + (r×n)·I⁻¹(r×n)`),
/// of the striking body, and of the carried body through the cable
/// ([`Cable::point_mobility`], over the impulse's time in the next step):
/// the closing speed rapier's impulse removed (or reversed, with its
/// restitution) is then removed with the mass the cable gives the point.
/// The striking body gets the difference at once (velocities, and its
/// position as rapier would have moved it at them over the step, less the
/// way the carried point would have given under the strike over the step,
/// as it takes its share only at the cable's next step); the carried
/// body's share is returned (impulse at its centre of mass, N·s, and
/// angular impulse, N·m·s) for the cable's next step, with the rest of
/// rapier's. Only new strikes (no contact impulse in the last step): a
/// resting contact is the island's (`contact::carried_pairs`). A body that
/// is fixed, kinematic, held by a cable or carried is left alone, and so
/// is friction (rapier's tangential impulses are kept as they are).
fn reweigh_strikes(
    cc: &mut CoupledCable,
    k: usize,
    held: &[rp::RigidBodyHandle],
    solved: &[(rp::RigidBodyHandle, rp::RigidBodyHandle)],
    bodies: &mut rp::RigidBodySet,
    colliders: &rp::ColliderSet,
    narrow_phase: &rp::NarrowPhase,
) -> (DVec3, DVec3) {
    let (h, sub) = cc.steps;
    let mut total = (DVec3::ZERO, DVec3::ZERO);
    let c = &cc.carried[k];
    let Some(rb) = bodies.get(c.body) else {
        return total;
    };
    if h <= 0.0 {
        return total;
    }
    // Each pair's normal impulse on the striking body (N·s, world, from
    // the carried body towards it), its point, and the striking body.
    let mut strikes: Vec<(rp::RigidBodyHandle, DVec3, DVec3, f64)> = Vec::new();
    for &mine in rb.colliders() {
        for pair in narrow_phase.contact_pairs_with(mine) {
            let other = if pair.collider1 == mine { pair.collider2 } else { pair.collider1 };
            let Some(ob) = colliders.get(other).and_then(|c| c.parent()) else {
                continue;
            };
            if ob == c.body || held.contains(&ob) || solved.contains(&(ob, c.body)) || !bodies.get(ob).is_some_and(|b| b.is_dynamic()) {
                continue;
            }
            let Some(first) = colliders.get(pair.collider1) else {
                continue;
            };
            let sign = if pair.collider1 == mine { 1.0 } else { -1.0 };
            let (mut impulse, mut at, mut sum) = (DVec3::ZERO, DVec3::ZERO, 0.0);
            for m in pair.solver_manifolds() {
                let normal = m.data.normal.as_dvec3() * sign;
                let pose = match m.subshape_poses.as_ref().and_then(|p| p.pos1) {
                    Some(sub) => *first.position() * sub,
                    None => *first.position(),
                };
                for p in &m.points {
                    let l = p.data.impulse as f64;
                    if l > 0.0 {
                        impulse += l * normal;
                        at += l * (pose * p.local_p1).as_dvec3();
                        sum += l;
                    }
                }
            }
            if sum > 0.0 {
                strikes.push((ob, impulse, at / sum, impulse.length()));
            }
        }
    }
    // A strike rapier has met is the island's from the next step on,
    // however fast the two still close (rapier's contact one step late
    // left a ball on a plank whose slack ropes snapped taut closing at
    // 0.6 m/s step after step, each step a strike, and it went through).
    let body = c.body;
    cc.carried_hit.extend(strikes.iter().map(|s| (s.0, body)));
    let c = &cc.carried[k];
    // (Only new strikes are weighed: a contact that goes on is the
    // island's, or, if the island cannot take it, rapier's as before;
    // weighed again every step, a 20 kg ball resting on a 10 kg plank on
    // steel ropes set the plank ringing and sank through it in 5 s.)
    if c.touching {
        return total;
    }
    let (pc, rc, _, _) = cc.carried_state(c);
    let (mass, inertia, place) = (c.mass, rc * c.inertia * rc.transpose(), c.place);
    let com = pc + rc * c.com;
    let over = cc.impulse_time(place.link, sub);
    for (ob, impulse, at, lambda) in strikes {
        let n = impulse / lambda;
        let free = |m: f64, i: DMat3, r: DVec3| {
            let rn = r.cross(n);
            1.0 / m + rn.dot(i.inverse() * rn)
        };
        let Some(b) = bodies.get(ob) else {
            continue;
        };
        let lb = lumped_of(b);
        let (rb_pose, b_com) = (lb.rotation, lb.position + lb.rotation * lb.com);
        let ib = rb_pose * lb.inertia * rb_pose.transpose();
        let w_b = free(lb.mass, ib, at - b_com);
        let w_free = free(mass, inertia, at - com);
        // The point in the link's frame.
        let chain = &cc.cable.model.chain;
        let (Some(lp), Some(lr)) = (chain.link_point(place.link, DVec3::ZERO), chain.link_rotation(place.link)) else {
            continue;
        };
        let local = lr.transpose() * (at - lp);
        let Ok(w_cable) = cc.cable.point_mobility(place.link, local, n, over) else {
            continue;
        };
        let w_cable = w_cable.max(0.0);
        let scale = (w_free + w_b) / (w_cable + w_b);
        if !(scale.is_finite() && w_b.is_finite() && w_free.is_finite()) {
            continue;
        }
        let extra = (scale - 1.0) * impulse;
        // The carried body takes its share at the cable's next step: over
        // this one it moved on without it, while the striking body moved
        // at its new velocity. That body is put back by what the share
        // would have moved the carried point over the step (`h w_cable λ*`
        // along the normal).
        let lag = n * (h * w_cable * scale * lambda);
        // The striking body: its share now, and the displacement rapier
        // would have given it over its step.
        let Some(b) = bodies.get_mut(ob) else {
            continue;
        };
        let dv = extra / lb.mass;
        let dw = ib.inverse() * (at - b_com).cross(extra);
        if !(dv.is_finite() && dw.is_finite()) {
            continue;
        }
        let pose = *b.position();
        let turn = DQuat::from_scaled_axis(dw * h);
        let centre = b_com + dv * h + lag;
        let rotation = (turn * pose.rotation.as_dquat()).normalize();
        let origin = centre - rotation * lb.com;
        b.set_position(rp::Pose::from_parts(origin.as_vec3(), rotation.as_quat()), true);
        b.set_linvel(b.linvel() + dv.as_vec3(), true);
        b.set_angvel(b.angvel() + dw.as_vec3(), true);
        total.0 -= extra;
        total.1 -= (at - com).cross(extra);
    }
    total
}

/// Whether the body owning collider `other` is dynamic (`None`: no such
/// collider, or one without a body).
fn owner_is_dynamic(other: rp::ColliderHandle, bodies: &rp::RigidBodySet, colliders: &rp::ColliderSet) -> Option<bool> {
    colliders.get(other).and_then(|c| c.parent()).and_then(|b| bodies.get(b)).map(|b| b.is_dynamic())
}

/// Whether one of rapier's active contacts on `rb`'s colliders is with a
/// collider `counts` accepts.
fn rapier_touches(rb: &rp::RigidBody, narrow_phase: &rp::NarrowPhase, counts: impl Fn(rp::ColliderHandle) -> bool) -> bool {
    rb.colliders()
        .iter()
        .any(|h| narrow_phase.contact_pairs_with(*h).any(|p| p.has_any_active_contact() && counts(if p.collider1 == *h { p.collider2 } else { p.collider1 })))
}

/// A free body the ropes of an island touched, after rapier's step: if
/// rapier changed nothing but what the island's solve already holds (no
/// active contact of rapier's touches it, it has no damping, and its
/// linear velocity is the island's end velocity: no joint pulled it), it
/// is put on the pose and the velocities the island's solve left it at.
/// Rapier integrates the ropes' impulse as a kick at the step's start
/// (then gravity over its sub-steps), the island as forces over the step:
/// a 20 kg ball resting on a rope ended each 1/60 s step 1.2 mm higher in
/// rapier than in the island, met the rope at the next step's start
/// moving down at 6 cm/s, and bounced on it for ever (docs/architecture.md,
/// "Free bodies on ropes"). The angular velocity is not compared: rapier's
/// explicit gyroscopic term turns a spinning box's angular velocity away
/// from the island's exact one, and a box that kept rapier's pose for that
/// met the ropes out of place at the next step (crates on a rope bridge
/// thrown up at 3 m/s). A body that rapier's contacts with other dynamic
/// bodies alone touched (a crate landing on it) is put on the island's
/// pose with rapier's velocities: rapier had pushed a crate lying on ropes
/// into them. Its contacts with fixed and kinematic colliders (the ground)
/// were solved in the island when it is `grounded`
/// ([`contact::add_free_body_contacts`]): rapier's only repeated them.
/// Otherwise one that touches such a collider, or that rapier damped,
/// keeps rapier's pose and velocities: the island did not hold those
/// contacts, and on its pose a box on the ground under a rope sank 5 cm
/// into it.
fn put_free_body(
    end: BodyPass,
    bodies: &mut rp::RigidBodySet,
    colliders: &rp::ColliderSet,
    narrow_phase: &rp::NarrowPhase,
    solved: &dyn Fn(rp::ColliderHandle) -> bool,
) -> Option<Written> {
    let rb = bodies.get(end.handle)?;
    // Rapier's active contacts on the body: with dynamic bodies (but the
    // carried bodies whose contacts with it the island solved), and with
    // anything else (fixed or kinematic bodies, colliders without a body).
    let dynamic = |other| owner_is_dynamic(other, bodies, colliders) == Some(true);
    let touched = |other| dynamic(other) && !solved(other);
    let (touched, held) = (rapier_touches(rb, narrow_phase, touched), rapier_touches(rb, narrow_phase, |other| !dynamic(other)));
    let rb = bodies.get_mut(end.handle)?;
    let close = |a: DVec3, b: DVec3| (a - b).length() <= 1e-5 * (1.0 + b.length());
    // A body whose contacts with fixed and kinematic colliders the island
    // solved (`add_free_body_contacts`), and its damping (`BodyDamping`),
    // has no joint either: rapier's ground contact and damping only
    // repeated the island's. Another keeps rapier's state if rapier did
    // something the island did not (held it, damped it, or a joint pulled
    // it).
    let damped = rb.linear_damping() != 0.0 || rb.angular_damping() != 0.0;
    if !end.grounded && (damped || held || !(touched || close(rb.linvel().as_dvec3(), end.velocity))) {
        return None;
    }
    rb.set_position(rp::Pose::from_parts(end.origin.as_vec3(), DQuat::from_mat3(&end.rotation).normalize().as_quat()), false);
    let mut velocities = None;
    if !touched {
        rb.set_linvel(end.velocity.as_vec3(), false);
        rb.set_angvel(end.angular_velocity.as_vec3(), false);
        velocities = Some((rb.linvel(), rb.angvel()));
    }
    let p = rb.position();
    Some(Written { translation: p.translation, rotation: p.rotation, velocities })
}

/// A free body's rapier `Damping` in an island's solve: the force
/// `−linear · v` at its centre of mass (`linear` = mass × rapier's linear
/// damping, N·s/m) and the moment `−R angular Rᵀ ω` (`angular` = the
/// body-frame inertia × rapier's angular damping, N·m·s), rapier's
/// `dv/dt = −c v` and `dω/dt = −c ω` made implicit.
struct BodyDamping {
    linear: f64,
    angular: DMat3,
}

impl crate::cable::ForceElement for BodyDamping {
    fn wrench(&self, _t: f64, at: &crate::cable::PointState) -> crate::cable::PointWrench {
        let turn = at.rotation * self.angular * at.rotation.transpose();
        let mut w = crate::cable::PointWrench { force: -at.velocity * self.linear, moment: -(turn * at.angular_velocity), ..Default::default() };
        w.damping.a = turn;
        w.damping.d = DMat3::from_diagonal(DVec3::splat(self.linear));
        w
    }
}

/// What [`build_cables`] made of one spec.
#[derive(Debug)]
pub enum Built {
    /// A cable with its own chain (and the ropes grafted onto it).
    Cable(Box<CoupledCable>),
    /// The spec's rope is rope `part` (≥ 1, see [`Cable::rope`]) of the
    /// chain built for spec `onto` of the same batch.
    Part {
        /// Index in the batch of the spec whose cable holds this rope.
        onto: usize,
        /// The rope's index in that cable ([`Cable::rope`]).
        part: usize,
    },
}

/// Builds the cables of `specs`, classified together and with the bodies
/// `existing` cables use ([`classify`]); returns, per spec, what was built
/// or why not. A cable on a hub is grafted onto the cable that carries the
/// hub ([`Built::Part`]); if one cable of such an island fails, all fail
/// (the others with [`CouplingError::Island`]). `motions` gives closed-form
/// motions of fixed or kinematic bodies (others are sampled). Carried
/// bodies get the rapier settings the module docs describe and a trolley's
/// rail motor is switched off in rapier; initial velocities are not given
/// to the chains yet ([`CoupledCable::start_velocities`]).
pub fn build_cables(
    specs: &[CableSpec],
    existing: &[&CoupledCable],
    bodies: &mut rp::RigidBodySet,
    joints: &mut rp::ImpulseJointSet,
    motions: &HashMap<rp::RigidBodyHandle, BodyMotion>,
) -> Vec<Result<Built, CouplingError>> {
    let refs: Vec<&CableSpec> = specs.iter().collect();
    let classes = classify(&refs, existing, bodies, joints);
    let n = specs.len();
    // Own chains first, then the grafts in batch order.
    let mut drafts: Vec<Option<Result<Draft, CouplingError>>> = (0..n)
        .map(|i| match &classes[i] {
            Ok(c) if c.placement == Placement::Own => Some(draft(&specs[i], c.roles, bodies, motions)),
            _ => None,
        })
        .collect();
    let mut out: Vec<Option<Result<Built, CouplingError>>> = (0..n).map(|_| None).collect();
    let mut parts: Vec<Vec<EndRoles>> = vec![Vec::new(); n];
    for i in 0..n {
        match &classes[i] {
            Err(e) => out[i] = Some(Err(e.clone())),
            Ok(Classified { roles, placement: Placement::Grafted { onto, reversed, .. } }) => {
                let onto = *onto;
                let r = match &mut drafts[onto] {
                    Some(Ok(d)) => graft(d, &specs[i], *reversed, *roles, bodies, motions),
                    _ => Err(CouplingError::Island { cable: onto }),
                };
                out[i] = Some(match r {
                    Ok(()) => {
                        parts[onto].push(*roles);
                        Ok(Built::Part { onto, part: parts[onto].len() })
                    }
                    Err(e) => {
                        // The island is not built without this rope.
                        if matches!(drafts[onto], Some(Ok(_))) {
                            drafts[onto] = Some(Err(CouplingError::Island { cable: i }));
                        }
                        Err(e)
                    }
                });
            }
            Ok(_) => {}
        }
    }
    for i in 0..n {
        let Some(d) = drafts[i].take() else { continue };
        let roles = classes[i].as_ref().expect("drafted").roles;
        let r = d.and_then(|d| finish(&specs[i], roles, std::mem::take(&mut parts[i]), d, bodies)).map(|cc| {
            for c in &cc.carried {
                hand_to_cable(&mut bodies[c.body]);
            }
            if let Some((_, Role::Trolley { joint, .. })) = cc.roles[0] {
                mute_motor(joints, joint);
            }
            Built::Cable(Box::new(cc))
        });
        out[i] = Some(r);
    }
    // An island whose carrying cable failed: its grafted ropes fail too.
    for i in 0..n {
        if let Ok(Classified { placement: Placement::Grafted { onto, .. }, .. }) = &classes[i] {
            if matches!(out[*onto], Some(Err(_))) && matches!(out[i], Some(Ok(_))) {
                out[i] = Some(Err(CouplingError::Island { cable: *onto }));
            }
        }
    }
    out.into_iter().map(|r| r.expect("every spec is decided")).collect()
}
