//! [`World`]: the cables, rapier bodies and rapier joints of a scenario,
//! stepped together.
//!
//! ## What maps to what
//! * A cable end on a `fixed` body, a `kinematic` body (with its `motion`)
//!   or a world point is the base (start) or an implicit anchor spring (end)
//!   of that cable's chain.
//! * **Absorbed bodies.** A `dynamic` body at the `end` of exactly one
//!   cable, at no other cable end and in no joint (hook, payload) is a lumped
//!   link of the chain: a ball joint at the anchor (or rigidly clamped),
//!   with its mass and full rotary inertia. A `dynamic` body at the `start`
//!   of exactly one cable, at no other cable end, whose only joint is one
//!   `prismatic` joint to the world (a trolley on its rail) is a link of the
//!   chain too, behind a prismatic sub-joint; a `drive` on that joint acts
//!   on it (a force table, or a velocity drive: rapier's joint motor law,
//!   as the plugin reads it, [`crate::coupling`]'s `rail_motor`: an
//!   implicit damper `c (v_target − v)` with `c = m_trolley/h`, saturating
//!   at `max_force`).
//!   Absorbed bodies stay rapier bodies (the coupling core puts them on the
//!   chain's pose every sub-step; see [`crate::coupling`]); their rails'
//!   drives act in the chain, not in rapier.
//! * **Hubs (slings).** A `dynamic` body in no joint at the ends of two or
//!   more cables (or the end of one and the starts of others) is absorbed
//!   by the first cable that ends on it, and the other cables are limbs of
//!   that cable's chain, grafted onto the body, their far ends anchor
//!   springs (world, `fixed`, `kinematic`) or free: one implicit island
//!   ([`crate::coupling`], "Hub"). [`World::rope`] gives each cable's rope
//!   in its own direction; probes use it. A cable from a hub to another
//!   `dynamic` body that would close a loop through two dynamic bodies is
//!   refused, naming both.
//! * **Rapier bodies.** Every other body is a rapier3d body in a plain
//!   [`rapier3d::prelude::PhysicsWorld`] (no Bevy): dynamic, fixed or
//!   kinematic-position-based, with its one collider (ball, cuboid, capsule
//!   or cylinder along local y, the body's `friction`), the mass `mass` with
//!   the shape's uniform-solid inertia (rapier's collider mass properties,
//!   equal to [`shape_inertia`]), its initial `linear_velocity` /
//!   `angular_velocity`, `[simulation] gravity`, sleeping off, gyroscopic
//!   torques on. A kinematic body with a `motion` is moved to the motion's
//!   pose at the end of each frame (`set_next_kinematic_position`).
//! * **Rapier joints.** Every joint that is not an absorbed trolley's rail
//!   is a rapier impulse joint (`fixed`, `revolute`, `prismatic`,
//!   `spherical`) between the two bodies (`world`: a fixed ground body at
//!   the origin), at `anchor1`/`anchor2` (which must be the same world point
//!   at t = 0 within 1 mm), about/along `axis` (body1 frame). The joint
//!   frames coincide at t = 0, so the joint coordinate (revolute angle,
//!   prismatic slide) is 0 at t = 0 and `limits` are measured from there.
//!   Contacts between the two jointed bodies are off. A `drive` with a
//!   `force` table applies F(t + dt/2)·dt per frame along the axis (equal
//!   and opposite at the two anchor points), or a torque about it (revolute);
//!   a `velocity` drive is rapier's joint motor (acceleration-based damping
//!   1/dt: the velocity error halves every frame) with `max_force`.
//! * **Cables on dynamic rapier bodies (explicit coupling)**, as the Bevy
//!   plugin's `CarriedBody::Explicit` / `ExplicitEnd`: a cable `start` on a
//!   dynamic rapier body is the chain's base, following the body's anchor
//!   point sampled at the start of each sub-step (pose; velocity, angular
//!   velocity and acceleration from the pose's change over the last
//!   sub-step, since rapier's post-step velocities carry its soft
//!   constraints' bias; extrapolated over the sub-step); the body gets the chain's
//!   base load (the spatial force about the chain origin, moved to the body
//!   centre). A pinned cable `end` on a dynamic rapier body is the implicit
//!   end anchor spring whose target follows the sampled body point; the
//!   body gets minus the spring's force at that point. The reactions are
//!   applied as impulses over each sub-step.
//!   **Stability:** the exchange lags one sub-step, so it is an explicit
//!   scheme: it is stable roughly when k·h²/m ≲ 1, with k the coupling
//!   stiffness (about EA/L_e of the element next to the body), h the
//!   sub-step `dt/substeps` and m the body's effective mass at the anchor;
//!   the rope mass that follows the body rigidly should also be well below
//!   the body's. Joints that hold the body (a `fixed` joint to the world)
//!   raise its effective mass and keep it stable beyond that. `[simulation]
//!   substeps` sub-steps cables and rapier together, so n sub-steps buy a
//!   factor n² in k·h²/m. [`World::new`] puts a note in [`World::warnings`]
//!   for every coupling with EA·h²/(L_e·m) > 1, with the sub-steps that
//!   would bring it to 1.
//! * The other cable features: a free start floats (the path gives its
//!   initial shape). A kinematic body with a `spin` motion turns the base
//!   of a cable that starts on it (orientation, the anchor point's velocity
//!   and acceleration, angular velocity and acceleration); a cable end on it
//!   is an anchor spring to the turning point (a clamped end is refused).
//!   A cable's `loads` are constant point loads on its chain
//!   ([`Cable::add_point_load_and_moment`]); `stress_free` maps to
//!   [`RopeBuilder::stress_free_shape`] and `tension_only` (default true) to
//!   [`RopeBuilder::tension_only`]; `[simulation] statics = true` puts
//!   every cable into its static equilibrium before t = 0 (rapier bodies
//!   held where they are; [`Cable::solve_static`], [`STATIC_TOLERANCE`],
//!   [`STATIC_MAX_ITERATIONS`]), or fails with [`SimError::Static`].
//!   Initial `linear_velocity` / `angular_velocity` of absorbed bodies set
//!   the chain's rates ([`Cable::set_link_velocities`], after the static
//!   start), or fail with [`SimError::InitialVelocity`].
//!
//! ## Frame order (deterministic)
//! [`World::step`] advances one frame `dt` in `substeps` sub-steps of
//! `h = dt/substeps` (default 1), each:
//! 1. sample the dynamic rapier bodies that cables hang on (anchor point
//!    pose, velocity, acceleration by finite difference);
//! 2. step every cable by `h` with its trolley drive (before the very first
//!    step, recompute its acceleration with its loads and drives), and take
//!    its reactions on those bodies;
//! 3. apply the reactions to the rapier bodies as impulses;
//! 4. move kinematic bodies to their motion at t + h, apply joint force
//!    drives, set joint motor targets (at t + h), and step rapier by `h`
//!    (rapier sub-steps internally: `num_solver_iterations` = 4 sub-steps
//!    of symplectic Euler). A non-finite rapier body fails the frame with
//!    [`SimError::BodyDiverged`].
//!
//! ## Probes
//! Probes of rapier bodies read rapier (origin = centre of mass). Joint
//! probes of rapier joints: `position` is the revolute angle (deg,
//! unwrapped, 0 at t = 0) or the prismatic slide (anchor2 − anchor1)·axis
//! (m); `velocity` its rate; `force` is the drive's force (N) or torque
//! (N·m) along/about the world axis (velocity motors: rapier's motor
//! impulse over its last sub-step). The reaction force of an undriven
//! rapier joint is not reported yet: a `force` probe on one is refused.
//! `system` energies add the rapier dynamic bodies' kinetic energy
//! (translation + rotation) and gravitational energy −m g·x to the cables'.
//!
//! ## Refused
//! Anything this runner would simulate wrongly is reported with the file
//! position (exit status 2): winches, wind and water, winch probes, a
//! cable `end` clamped to a spinning body or to a dynamic rapier body (the
//! end spring's orientation hold has a fixed target), a `force` probe on
//! an undriven rapier joint, and joints whose anchors are not the same
//! point at t = 0. A cable's `contact_force` probe is the sum of its
//! contacts' normal forces; a body's is the force (normal and friction,
//! world) of the cables' contacts on it
//! ([`CoupledCable::contact_force_on`](crate::coupling::CoupledCable::contact_force_on)).

use super::control::{self, ControllerRun};
use super::probe::Probe;
use super::rapier::RapierWorld;
use super::{STATIC_MAX_ITERATIONS, STATIC_TOLERANCE};
use crate::cable::{BaseState, BodyInChain, Cable, CableError, LumpedBody, RopeBuilder, RopeError, RopeSection, RopeView};
use crate::coupling::{rail_motor, velocity_drive_motor, Attach, BodyInputs, BodyMotion, CableContact, CableSpec, Coupling, CouplingError, Role, Threads};
use crate::crane::control::TrolleyMeasurement;
use crate::integrate::{Scheme, SchemeParams, Substeps};
use crate::scenario::{self, BodyKind, CableEnd, Drive, Location, ProbeTarget, Quantity, Scenario, Shape};
use glam::{DMat3, DVec3};
use std::collections::HashMap;
use std::sync::Arc;
use thiserror::Error;

/// Why a scenario cannot be run or stopped.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum SimError {
    /// The scenario uses something this runner does not simulate yet.
    #[error("{file}:{location}: {what} is not supported yet")]
    Unsupported {
        /// Scenario file.
        file: String,
        /// Where.
        location: Location,
        /// What.
        what: String,
    },
    /// The scenario is inconsistent in a way the parser does not check.
    #[error("{file}:{location}: {message}")]
    Invalid {
        /// Scenario file.
        file: String,
        /// Where.
        location: Location,
        /// What is wrong.
        message: String,
    },
    /// A cable could not be built.
    #[error("{file}:{location}: cable `{cable}`: {source}")]
    Build {
        /// Scenario file.
        file: String,
        /// Where the cable is defined.
        location: Location,
        /// Cable name.
        cable: String,
        /// Why.
        source: RopeError,
    },
    /// The integrator setting is invalid.
    #[error("{file}: [simulation] integrator: {0}", file = .1)]
    Integrator(String, String),
    /// `[simulation] statics = true`: no static equilibrium found for a
    /// cable.
    #[error("{file}:{location}: cable `{cable}`: {source}")]
    Static {
        /// Scenario file.
        file: String,
        /// Where the cable is defined.
        location: Location,
        /// Cable name.
        cable: String,
        /// What the static solve reported.
        source: Box<CableError>,
    },
    /// A body's initial velocity cannot be given to the cable carrying it.
    #[error("{file}:{location}: initial velocity of body `{body}` on cable `{cable}`: {source}")]
    InitialVelocity {
        /// Scenario file.
        file: String,
        /// Where the body is defined.
        location: Location,
        /// Body name.
        body: String,
        /// Cable name.
        cable: String,
        /// What went wrong.
        source: Box<CableError>,
    },
    /// A rapier body's state became non-finite.
    #[error("body `{body}` diverged at t = {time} s (non-finite rapier state)")]
    BodyDiverged {
        /// Body name.
        body: String,
        /// Simulation time at the start of the failing frame, s.
        time: f64,
    },
    /// A cable diverged or its step failed.
    #[error("cable `{cable}` failed at t = {time} s: {source}")]
    Diverged {
        /// Cable name.
        cable: String,
        /// Simulation time at the start of the failing step, s.
        time: f64,
        /// What the cable reported.
        source: Box<CableError>,
    },
}

/// Rotational inertia (kg·m², body frame, about the centre) of a uniform
/// solid of mass `mass` (kg) and shape `shape`.
pub fn shape_inertia(shape: &Shape, mass: f64) -> DMat3 {
    let d = match *shape {
        Shape::Ball { radius } => DVec3::splat(0.4 * mass * radius * radius),
        Shape::Cuboid { half_extents: h } => DVec3::new(h.y * h.y + h.z * h.z, h.x * h.x + h.z * h.z, h.x * h.x + h.y * h.y) * (mass / 3.0),
        Shape::Cylinder { radius: r, half_height: hh } => {
            let side = mass * (3.0 * r * r + 4.0 * hh * hh) / 12.0;
            DVec3::new(side, 0.5 * mass * r * r, side)
        }
        Shape::Capsule { radius: r, half_height: hh } => {
            let h = 2.0 * hh;
            let (vc, vs) = (std::f64::consts::PI * r * r * h, 4.0 / 3.0 * std::f64::consts::PI * r * r * r);
            let (mc, ms) = (mass * vc / (vc + vs), mass * vs / (vc + vs));
            let axial = 0.5 * mc * r * r + 0.4 * ms * r * r;
            let side = mc * (h * h / 12.0 + r * r / 4.0) + ms * (0.4 * r * r + h * h / 4.0 + 3.0 * h * r / 8.0);
            DVec3::new(side, axial, side)
        }
    };
    DMat3::from_diagonal(d)
}

fn fmt_point(p: DVec3) -> String {
    format!("[{:.4}, {:.4}, {:.4}] m", p.x, p.y, p.z)
}

/// Names of one cable of the core and of the scenario bodies it carries.
#[derive(Debug)]
struct CableNames {
    /// The scenario cables whose ropes this core cable solves: its own
    /// (rope 0), then those grafted onto it at a hub ([`Cable::rope`]).
    ropes: Vec<String>,
    /// Scenario body name → its place in the chain.
    bodies: Vec<(String, BodyInChain)>,
    /// Prismatic joint of an absorbed trolley (joint name, drive).
    slide: Option<(String, Option<Drive>)>,
}

impl CableNames {
    /// The cable's name in messages (shown in backticks): its name, or the
    /// names of an island's cables joined by `` ` + ` ``.
    fn label(&self) -> String {
        self.ropes.join("` + `")
    }
}

/// The cables, rapier bodies and joints of a scenario, stepped together
/// (see the module docs).
#[derive(Debug)]
pub struct World {
    /// The scenario.
    pub scenario: Scenario,
    core: Coupling,
    names: Vec<CableNames>,
    rapier: RapierWorld,
    /// The exact motion of each fixed or kinematic body (cable ends and
    /// contacts read it instead of rapier's f32 pose).
    motions: Motions,
    /// Simulation time, s.
    pub time: f64,
    /// Frames stepped.
    pub steps: u64,
    /// Cable sub-steps per frame.
    pub substeps: u32,
    /// Notes about the run that are not errors: explicit couplings beyond
    /// their estimated stability limit (see the module docs).
    pub warnings: Vec<String>,
    /// The `[[controller]]`s and, for each, the index of the cable whose
    /// trolley rail it drives.
    controllers: Vec<(ControllerRun, usize)>,
    /// Most threads the cables' solves are spread over (1: one after the
    /// other on the calling thread; [`World::set_threads`]).
    threads: usize,
}

/// The closed-form motion of a fixed or kinematic scenario body (its
/// frame; for a `spin`, the angular velocity and acceleration too; the
/// origin's acceleration by a central difference of the velocity), for
/// cable steps of `h` (s).
///
/// A `table` is piecewise linear: its velocity jumps at a point, and its
/// acceleration there is an impulse. Given as such (zero acceleration and
/// the jump in the velocity), the cable's relative coordinates never saw
/// it: a payload hung from a table-driven trolley set off with the
/// trolley, rigidly, instead of swinging back (and the central difference
/// of the velocity at the jump gave a hook starting at 0.1 m/s a
/// 5 000 m/s² base acceleration, and the rope's first element turned
/// inside out). So a table's velocity is its mean over the last step,
/// `(x(t) − x(t − h))/h`, and its acceleration the change of that mean
/// over a step, `(v(t) − v(t − h))/h`: the slope between points and zero
/// acceleration there, and at a point the velocity change spread over two
/// steps as a finite acceleration of the same impulse. Before its first
/// point the table goes on with its first segment's slope (a rope starts
/// moving with its base, as the state at t = 0 has it).
pub(crate) fn body_motion(b: &scenario::Body, h: f64) -> BodyMotion {
    let rot = DMat3::from_quat(b.rotation);
    match &b.motion {
        None => {
            let s = BaseState::fixed(rot, b.position);
            Arc::new(move |_| s)
        }
        Some(m) => {
            let (m, base, r0) = (m.clone(), b.position, b.rotation);
            let first = match &m {
                scenario::Motion::Table { points } => points.first().map(|p| p.0),
                _ => None,
            };
            Arc::new(move |t| {
                let eps = 1e-5;
                let (velocity, acceleration) = match first {
                    Some(t0) => {
                        let x = |s: f64| if s < t0 { m.position_at(t0, base) + m.velocity_at(t0) * (s - t0) } else { m.position_at(s, base) };
                        let mean = |s: f64| (x(s) - x(s - h)) / h;
                        (mean(t), (mean(t) - mean(t - h)) / h)
                    }
                    None => (m.velocity_at(t), (m.velocity_at(t + eps) - m.velocity_at(t - eps)) / (2.0 * eps)),
                };
                BaseState {
                    rotation: DMat3::from_quat(m.rotation_at(t) * r0),
                    position: m.position_at(t, base),
                    angular_velocity: m.angular_velocity_at(t),
                    velocity,
                    angular_acceleration: m.angular_acceleration_at(t),
                    acceleration,
                }
            })
        }
    }
}

/// The core's spec of a scenario cable.
fn cable_spec(sc: &Scenario, c: &scenario::Cable, scheme: &Scheme, rapier: &RapierWorld) -> CableSpec {
    let section = RopeSection { linear_density: c.linear_density, ea: c.ea, ei: c.ei, ei2: c.ei2, gj: c.gj, min_breaking_load: 0.0 };
    let mut rope = RopeBuilder::new(c.length, c.segments as usize, section, c.diameter)
        .damping(c.damping)
        .velocity_damping(c.linear_damping, c.angular_damping)
        .end_stiffness_factor(c.end_stiffness)
        .gravity(sc.simulation.gravity)
        .stress_free_shape(c.stress_free)
        .tension_only(c.tension_only);
    if let Some(ga) = c.shear_stiffness {
        rope = rope.shear_stiffness(ga);
    }
    let attach = |e: &CableEnd| match e {
        CableEnd::Free => Attach::Free,
        CableEnd::World { point, clamp } => Attach::World { point: *point, clamp: *clamp },
        CableEnd::Body { body, anchor, clamp } => {
            Attach::Body { body: rapier.body(body).expect("validated: every body is a rapier body").handle, anchor: *anchor, clamp: *clamp }
        }
    };
    // The scenario's exact (f64) mass properties and pose of dynamic end bodies.
    let exact = |e: &CableEnd| match e {
        CableEnd::Body { body, .. } => sc.body(body).filter(|b| b.kind == BodyKind::Dynamic).map(|b| {
            let mass = b.mass.unwrap_or(0.0);
            LumpedBody { mass, inertia: shape_inertia(&b.shape, mass), position: b.position, rotation: DMat3::from_quat(b.rotation), com: DVec3::ZERO }
        }),
        _ => None,
    };
    CableSpec {
        rope,
        path: Some(c.path.clone()),
        start: attach(&c.start),
        end: attach(&c.end),
        scheme: scheme.clone(),
        exact: [exact(&c.start), exact(&c.end)],
        contact: if c.contacts {
            CableContact::steel(c.diameter, c.linear_density * c.length / c.segments.max(1) as f64)
                .and_then(|k| k.with_friction(c.friction))
                .map(|k| k.with_groups(c.collision_groups.into()))
                .ok()
        } else {
            None
        },
    }
}

/// The fixed and kinematic bodies' exact motions (closures: printed by
/// count).
struct Motions(HashMap<rapier3d::prelude::RigidBodyHandle, BodyMotion>);

impl std::fmt::Debug for Motions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Motions({} bodies)", self.0.len())
    }
}

impl World {
    /// Builds every cable of `scenario` (see the module docs for what is
    /// supported).
    pub fn new(scenario: Scenario) -> Result<World, SimError> {
        let file = scenario.file.display().to_string();
        let unsupported = |location: Location, what: String| SimError::Unsupported { file: file.clone(), location, what };
        if let Some(w) = scenario.winches.first() {
            return Err(unsupported(w.location, format!("winch `{}`", w.name)));
        }
        let env = &scenario.environment;
        if env.wind != DVec3::ZERO || env.water_surface.is_some() {
            return Err(unsupported(Location { line: 0, col: 0 }, "[environment] wind / water".into()));
        }
        for p in &scenario.probes {
            if matches!(p.target, ProbeTarget::Winch(_)) {
                return Err(unsupported(p.location, format!("probe `{}` ({})", p.name, p.quantity.name())));
            }
        }
        let sim = &scenario.simulation;
        let ic = &sim.integrator;
        let params = SchemeParams { beta: ic.beta, gamma: ic.gamma, theta: ic.theta, alpha: ic.alpha, rho_inf: ic.rho_inf, w: ic.w };
        let scheme = Scheme::from_name(&ic.name, &params).map_err(|e| SimError::Integrator(e.to_string(), file.clone()))?;
        // Every body and joint is in rapier; the core decides which bodies
        // become links of a cable's chain.
        // The cable step: the step of the prescribed motions' table velocities.
        let h_motion = sim.dt / sim.substeps.unwrap_or(1).max(1) as f64;
        let mut rapier = RapierWorld::new(sim.gravity, h_motion);
        for b in &scenario.bodies {
            rapier.add_body(b);
        }
        for j in &scenario.joints {
            let point = |body: &str, anchor: DVec3| scenario.body(body).map_or(anchor, |b| b.world_point(anchor));
            let (p1, p2) = (point(&j.body1, j.anchor1), point(&j.body2, j.anchor2));
            if p1.distance(p2) > 1e-3 {
                return Err(SimError::Invalid {
                    file: file.clone(),
                    location: j.location,
                    message: format!(
                        "joint `{}`: `anchor1` is at {} in the world but `anchor2` at {}; a joint's two anchors must be the same point at t = 0 (within 1 mm)",
                        j.name,
                        fmt_point(p1),
                        fmt_point(p2)
                    ),
                });
            }
            let handle = |n: &str| rapier.body(n).map(|b| b.handle);
            let (h1, h2) = (handle(&j.body1), handle(&j.body2));
            rapier.add_joint(j, h1, h2, sim.dt);
        }
        let motions: HashMap<_, BodyMotion> = scenario
            .bodies
            .iter()
            .filter(|b| b.kind != BodyKind::Dynamic)
            .map(|b| (rapier.body(&b.name).expect("added").handle, body_motion(b, h_motion)))
            .collect();
        let specs: Vec<CableSpec> = scenario.cables.iter().map(|c| cable_spec(&scenario, c, &scheme, &rapier)).collect();
        let mut core = Coupling::new();
        let built = core.add(&specs, &mut rapier.pw.bodies, &mut rapier.pw.impulse_joints, &motions);
        let name_of = |rapier: &RapierWorld, h| rapier.bodies.iter().find(|b| b.handle == h).map_or("?".to_string(), |b| b.name.clone());
        // The first error that is not only a consequence of another (an island member's).
        let first_error =
            built.iter().position(|r| matches!(r, Err(e) if !matches!(e, CouplingError::Island { .. }))).or_else(|| built.iter().position(|r| r.is_err()));
        if let Some(k) = first_error {
            let c = &scenario.cables[k];
            let Err(e) = &built[k] else { unreachable!("an error") };
            return Err(match e.clone() {
                CouplingError::Build(source) => SimError::Build { file: file.clone(), location: c.location, cable: c.name.clone(), source },
                CouplingError::ClampedMovingEnd { why } => {
                    let body = match (&c.start, &c.end) {
                        (_, CableEnd::Body { body, clamp: true, .. }) | (CableEnd::Body { body, clamp: true, .. }, _) => body.as_str(),
                        _ => "?",
                    };
                    unsupported(
                        c.location,
                        if why.starts_with("a dynamic") {
                            format!("cable `{}` with an end clamped to body `{body}`, which rapier keeps (a dynamic body held by joints or other cables: the end spring's orientation hold has a fixed target; clamp the `start` instead, or leave the end pinned)", c.name)
                        } else {
                            format!("cable `{}` with an end clamped to spinning body `{body}` (clamp the `start` instead)", c.name)
                        },
                    )
                }
                e @ (CouplingError::HubLoop { .. } | CouplingError::Island { .. }) => {
                    let message = e.describe(&|h| format!("body `{}`", name_of(&rapier, h)), &|k| format!("cable `{}`", scenario.cables[k].name));
                    SimError::Invalid { file: file.clone(), location: c.location, message: format!("cable `{}`: {message}", c.name) }
                }
                e => SimError::Invalid { file: file.clone(), location: c.location, message: format!("cable `{}`: {e}", c.name) },
            });
        }
        let places: Vec<(usize, usize)> = built.into_iter().map(|r| r.expect("errors are returned above")).collect();
        let mut names: Vec<CableNames> = core.cables.iter().map(|_| CableNames { ropes: Vec::new(), bodies: Vec::new(), slide: None }).collect();
        for (c, &(i, part)) in scenario.cables.iter().zip(&places) {
            let n = &mut names[i];
            if n.ropes.len() <= part {
                n.ropes.resize(part + 1, String::new());
            }
            n.ropes[part] = c.name.clone();
            let cc = &mut core.cables[i];
            for l in &c.loads {
                let added = cc.cable.add_rope_point_load(part, l.s, l.force, l.moment);
                debug_assert!(added, "the core gave this rope");
            }
        }
        for (cc, n) in core.cables.iter_mut().zip(&mut names) {
            cc.keep_loads();
            n.bodies = cc.carried.iter().map(|cb| (name_of(&rapier, cb.body), cb.place)).collect();
            n.slide = match cc.roles[0] {
                Some((_, Role::Trolley { joint, .. })) => {
                    let k = rapier.joints.iter().position(|j| j.handle == joint).expect("the rail is a scenario joint");
                    // The cable drives the rail; rapier keeps it as a joint only.
                    let drive = rapier.joints[k].drive.take();
                    Some((rapier.joints[k].name.clone(), drive))
                }
                _ => None,
            };
            for cb in &cc.carried {
                if let Some(rb) = rapier.bodies.iter_mut().find(|b| b.handle == cb.body) {
                    rb.carried = true;
                }
            }
        }
        for p in &scenario.probes {
            let ProbeTarget::Joint(name) = &p.target else { continue };
            if names.iter().any(|n| n.slide.as_ref().is_some_and(|(j, _)| j == name)) {
                continue;
            }
            let Some(j) = scenario.joints.iter().find(|j| j.name == *name) else { continue };
            if p.quantity == Quantity::Force && j.drive.is_none() {
                return Err(unsupported(
                    p.location,
                    format!("probe `{}`: the `force` of joint `{name}`, which has no `drive` (the reaction force of a rapier joint; a driven joint reports its drive force)", p.name),
                ));
            }
        }
        if sim.statics {
            // Start from the static equilibrium (gravity, loads, held ends).
            let steps = sim.static_load_steps as usize;
            for (cc, n) in core.cables.iter_mut().zip(&names) {
                let location = scenario.cables.iter().find(|c| c.name == n.ropes[0]).expect("a scenario cable").location;
                cc.cable.solve_static(steps, STATIC_TOLERANCE, STATIC_MAX_ITERATIONS).map_err(|source| SimError::Static {
                    file: file.clone(),
                    location,
                    cable: n.label(),
                    source: Box::new(source),
                })?;
            }
        }
        // Initial velocities of the carried bodies (after the static start).
        let exact = |h| {
            let b = scenario.body(&name_of(&rapier, h)).expect("a scenario body");
            (b.linear_velocity, b.angular_velocity)
        };
        for (cc, n) in core.cables.iter_mut().zip(&names) {
            if let Err((h, source)) = cc.start_velocities(&exact) {
                let name = name_of(&rapier, h);
                let who = scenario.body(&name).expect("a scenario body");
                return Err(SimError::InitialVelocity { file: file.clone(), location: who.location, body: name, cable: n.label(), source: Box::new(source) });
            }
        }
        let substeps = sim.substeps.unwrap_or(1);
        for cc in &mut core.cables {
            if !scheme.is_explicit() {
                cc.cable.integrator.substeps = Substeps::Auto;
            }
        }
        // Explicit couplings: estimated stability k·h²/m.
        let h = sim.dt / substeps as f64;
        let mut warnings = Vec::new();
        for (i, body, start, ratio) in core.explicit_ratios(&rapier.pw.bodies, h) {
            if ratio > 1.0 {
                let b = rapier.bodies.iter().find(|b| b.handle == body).expect("a scenario body");
                let k = ratio * b.mass / (h * h);
                warnings.push(format!(
                    "cable `{}` {} on body `{}` is coupled explicitly with k·h²/m = {ratio:.3e} > 1 (k = EA/L_e = {k:.4e} N/m, h = {h} s, m = {} kg): it may be unstable unless joints hold the body; `substeps = {}` would bring it to 1 (see docs/scenario.md \"Explicit coupling\")",
                    names[i].ropes[0],
                    if start { "start" } else { "end" },
                    b.name,
                    b.mass,
                    (substeps as f64 * ratio.sqrt()).ceil()
                ));
            }
        }
        let mut controllers = Vec::with_capacity(scenario.controllers.len());
        for c in &scenario.controllers {
            let Some(i) = names.iter().position(|n| n.slide.as_ref().is_some_and(|(j, _)| *j == c.joint)) else {
                return Err(unsupported(
                    c.location,
                    format!(
                        "controller `{}` on joint `{}`, which no cable carries as a trolley's rail (rapier keeps it); a controller drives the rail of a trolley whose cable starts on it",
                        c.name, c.joint
                    ),
                ));
            };
            // The controller replaces the rail's `drive`.
            if let Some(slide) = names[i].slide.as_mut() {
                slide.1 = None;
            }
            let run = ControllerRun::new(c).map_err(|e| SimError::Invalid {
                file: file.clone(),
                location: c.location,
                message: format!("controller `{}`: {e}", c.name),
            })?;
            controllers.push((run, i));
        }
        Ok(World { scenario, core, names, rapier, motions: Motions(motions), time: 0.0, steps: 0, substeps, warnings, controllers, threads: 1 })
    }

    /// Spreads the cables' solves over at most `threads` threads
    /// ([`crate::coupling::Threads`]; 0 counts as 1, the default: one after
    /// the other). Independent cables then step at once; the results are
    /// the same bits whatever the count.
    pub fn set_threads(&mut self, threads: usize) {
        self.threads = threads.max(1);
    }

    /// Most threads the cables' solves are spread over ([`World::set_threads`]).
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Advances the world by one frame `dt` in `substeps` sub-steps, each:
    /// the trolley drives, the core's cable step, rapier's step, the core's
    /// read-back (see the module docs).
    pub fn step(&mut self) -> Result<(), SimError> {
        let dt = self.scenario.simulation.dt;
        let h = dt / self.substeps as f64;
        let t0 = self.time;
        for k in 0..self.substeps {
            let t = t0 + k as f64 * h;
            if self.controllers.iter().any(|(c, _)| c.due(t)) {
                let measured: Vec<Option<TrolleyMeasurement>> =
                    self.controllers.iter().map(|(c, _)| c.due(t).then(|| control::measure(&*self, &self.scenario, &c.spec, t))).collect();
                for ((c, _), m) in self.controllers.iter_mut().zip(measured) {
                    if let Some(m) = m {
                        c.sample(t, || m);
                    }
                }
            }
            for (c, i) in &self.controllers {
                let cc = &mut self.core.cables[*i];
                if let Some((_, Role::Trolley { offset, .. })) = cc.roles[0] {
                    rail_motor(cc, Some(c.motor(h)), offset);
                }
            }
            for (cc, n) in self.core.cables.iter_mut().zip(&self.names) {
                match &n.slide {
                    Some((_, Some(Drive::Force { force }))) => {
                        // Drive force at the sub-step's midpoint.
                        let _ = cc.cable.model.chain.set_joint_force(0, force.value_at(t + 0.5 * h));
                    }
                    Some((_, Some(Drive::Velocity { velocity, max_force }))) => {
                        // Rapier's joint motor, read by the plugin from the
                        // joint component in the same way.
                        if let Some((_, Role::Trolley { offset, .. })) = cc.roles[0] {
                            rail_motor(cc, Some(velocity_drive_motor(velocity.value_at(t + h), *max_force, h)), offset);
                        }
                    }
                    _ => {}
                }
            }
            let failures = self.core.step(
                &mut self.rapier.pw.bodies,
                &self.rapier.pw.colliders,
                &mut self.rapier.pw.impulse_joints,
                h,
                1,
                &|_| BodyInputs::default(),
                &|b| self.motions.0.get(&b).cloned(),
                &Threads { threads: self.threads },
            );
            if let Some((i, time, source)) = failures.into_iter().next() {
                return Err(SimError::Diverged { cable: self.names[i].label(), time, source: Box::new(source) });
            }
            self.rapier.prepare_step(t, h);
            self.rapier.step().map_err(|body| SimError::BodyDiverged { body, time: t })?;
            self.core.after_rapier(&mut self.rapier.pw.bodies, &self.rapier.pw.colliders, &self.rapier.pw.narrow_phase);
        }
        self.steps += 1;
        self.time = self.steps as f64 * dt;
        Ok(())
    }

    /// The cables' reactions on the dynamic rapier bodies they are coupled
    /// to explicitly, over the last sub-step: (cable, body, `true` for the
    /// cable's start, force N, moment about the body's centre N·m).
    pub fn coupling_reactions(&self) -> Vec<(&str, &str, bool, DVec3, DVec3)> {
        let name = |h| self.rapier.bodies.iter().find(|b| b.handle == h).map_or("?", |b| b.name.as_str());
        self.core
            .cables
            .iter()
            .zip(&self.names)
            .flat_map(|(cc, n)| {
                cc.followers.iter().filter(|f| f.dynamic).map(move |f| (n.ropes[0].as_str(), name(f.body), f.start, f.reaction.0, f.reaction.1))
            })
            .collect()
    }

    /// The cable named `name`, when it has its own chain; `None` for an
    /// unknown name and for a cable whose rope is grafted onto another
    /// cable's chain at a hub (see [`World::rope`]).
    pub fn cable(&self, name: &str) -> Option<&Cable> {
        self.names.iter().position(|n| n.ropes[0] == name).map(|i| &self.core.cables[i].cable)
    }

    /// The rope of the cable named `name`, in the direction the scenario
    /// gives it, wherever it is solved: its own chain, or a limb of another
    /// cable's chain (a sling leg on a hub body).
    pub fn rope(&self, name: &str) -> Option<RopeView<'_>> {
        self.names.iter().enumerate().find_map(|(i, n)| n.ropes.iter().position(|r| r == name).and_then(|k| self.core.cables[i].cable.rope(k)))
    }

    /// Appends the current value of every probe column (file order) to `out`.
    pub fn sample(&self, out: &mut Vec<f64>) {
        super::probe::sample(&self.scenario.probes, self, out);
    }

    fn body_state(&self, name: &str) -> (DVec3, DMat3, DVec3, DVec3) {
        for (cc, n) in self.core.cables.iter().zip(&self.names) {
            if let Some((_, b)) = n.bodies.iter().find(|(n, _)| n == name) {
                return cc.cable.model.body_state(b);
            }
        }
        if let Some(b) = self.rapier.body(name) {
            let (p, q) = self.rapier.pose_of(b.handle);
            let (v, w) = self.rapier.velocity_of(b.handle);
            return (p, DMat3::from_quat(q), v, w);
        }
        let b = self.scenario.body(name).expect("probe targets are validated");
        let t = self.time;
        let (v, w) = b.motion.as_ref().map_or((DVec3::ZERO, DVec3::ZERO), |m| (m.velocity_at(t), m.angular_velocity_at(t)));
        (b.position_at(t), DMat3::from_quat(b.rotation_at(t)), v, w)
    }

    /// Names of the prismatic joints of the trolleys the cables carry (the
    /// rails whose coordinate is the chain's root sub-joint; their drives
    /// act in the chain).
    #[cfg(feature = "app")] // for `plugin::scenario`
    pub(crate) fn rails(&self) -> Vec<&str> {
        self.names.iter().filter_map(|n| n.slide.as_ref().map(|(j, _)| j.as_str())).collect()
    }

    /// Names of the cables.
    pub fn cable_names(&self) -> Vec<&str> {
        self.scenario.cables.iter().map(|c| c.name.as_str()).collect()
    }

    /// Newton iterations, residual evaluations and solves of all cables so far.
    pub fn work(&self) -> (usize, usize) {
        self.core.cables.iter().fold((0, 0), |(a, b), c| (a + c.cable.total_stats.newton_iterations, b + c.cable.total_stats.solves))
    }
}

impl super::probe::ProbeSource for World {
    fn chains(&self) -> Vec<&Cable> {
        self.core.cables.iter().map(|c| &c.cable).collect()
    }

    fn rapier_energies(&self) -> (f64, f64) {
        self.rapier.energies(self.scenario.simulation.gravity)
    }

    fn rope(&self, name: &str) -> Option<RopeView<'_>> {
        World::rope(self, name)
    }

    fn body_state(&self, name: &str) -> (DVec3, DMat3, DVec3, DVec3) {
        World::body_state(self, name)
    }

    fn body_contact_force(&self, name: &str) -> DVec3 {
        self.rapier.body(name).map_or(DVec3::ZERO, |b| self.core.cables.iter().fold(DVec3::ZERO, |sum, c| sum + c.contact_force_on(b.handle)))
    }

    fn controller(&self, name: &str, quantity: Quantity) -> f64 {
        self.controllers.iter().find(|(c, _)| c.spec.name == name).map_or(f64::NAN, |(c, _)| c.probe(quantity))
    }

    fn joint(&self, name: &str, quantity: Quantity) -> Probe {
        let c = self.names.iter().position(|n| n.slide.as_ref().is_some_and(|(j, _)| j == name)).map(|i| &self.core.cables[i]);
        match (c, quantity) {
            (Some(c), q) => super::probe::rail(&c.cable, q),
            (None, q) => match self.rapier.joints.iter().find(|j| j.name == *name) {
                Some(j) => super::probe::rapier_joint(j, &self.rapier.pw.bodies, q),
                None => Probe::Scalar(f64::NAN),
            },
        }
    }
}
