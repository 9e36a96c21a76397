//! The cable plugin's systems (see the order table in the module docs):
//! thin adapters that map entities to rapier handles and call the coupling
//! core ([`crate::coupling`]).

use super::components::{BodyExact, CableAnchor, CableDescriptor, CableError, CableErrorKind, CableExact, CableRopeOf, CableSim, CableState, CarriedBody};
use super::CableSettings;
use crate::cable::{LumpedBody, RopeBuilder};
use crate::coupling::{
    self, rail_motor, Attach, BodyInputs, BodyMotion, Built, CableContact, CableSpec, Contacts, CoupledCable, CouplingError, ForEachCable, OneByOne, Role,
};
use crate::sim::{STATIC_MAX_ITERATIONS, STATIC_TOLERANCE};
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::dynamics::RigidBodyHandle;
use glam::{DMat3, DVec3};
use std::collections::HashMap;

/// The order in which the plugin builds and steps cables: spawn order
/// (entity index, then generation), as `cablesim` takes a file's cables in
/// file order. (`Entity`'s own `Ord` compares its bit pattern, in which
/// Bevy 0.19 stores the index inverted: later spawns sort first.)
pub(crate) fn spawn_order(e: Entity) -> (u32, u32) {
    (e.index_u32(), e.generation().to_bits())
}

/// Set at start-up when the cable systems are not in the schedule of
/// rapier's systems: why (every new cable is refused with it).
#[derive(Resource, Debug, Clone)]
pub(crate) struct Misplaced(pub(crate) String);

/// Cable entities the plugin has not built yet.
type NotBuilt = (Without<CableSim>, Without<CableRopeOf>);

/// Builds cables from new [`CableDescriptor`]s, all new ones of a step
/// together (so a body at the ends of two new cables is solved with both
/// as one island, see the module docs), in the order `cablesim` does:
/// build, loads, static start, initial velocities.
#[allow(clippy::too_many_arguments)]
pub(crate) fn init_cables(
    mut commands: Commands,
    new: Query<(Entity, &CableDescriptor, Option<&CableExact>), NotBuilt>,
    existing: Query<(Entity, &CableSim)>,
    mut ctx: WriteRapierContext,
    handles: Query<&RapierRigidBodyHandle>,
    exact_bodies: Query<&BodyExact>,
    config: Query<&RapierConfiguration, With<DefaultRapierContext>>,
    contexts: (Query<Entity, With<DefaultRapierContext>>, Query<&RapierContextEntityLink>),
    (settings, mode, misplaced): (Res<CableSettings>, Option<Res<TimestepMode>>, Option<Res<Misplaced>>),
    mut errors: MessageWriter<CableError>,
) {
    if new.is_empty() {
        return;
    }
    // What no cable of the batch can be built with: a timestep the cables
    // cannot follow, or not exactly one default rapier context.
    let interpolated = (settings.step.is_none() && matches!(mode.as_deref(), Some(TimestepMode::Interpolated { .. }))).then(|| INTERPOLATED.to_string());
    let default_context = contexts.0.single().ok();
    let refused = misplaced.map(|m| m.0.clone()).or(interpolated).or_else(|| {
        default_context.is_none().then(|| {
            let n = contexts.0.iter().count();
            format!(
                "the cable plugin needs exactly one rapier context marked `DefaultRapierContext` (found {n}): add `RapierPhysicsPlugin` before `CablePlugin`"
            )
        })
    });
    let ctx = match refused {
        None => ctx.single_mut().ok(),
        Some(_) => None,
    };
    let Some(mut ctx) = ctx else {
        let why = refused.unwrap_or_else(|| "no rapier context".into());
        for (entity, _, _) in new.iter() {
            fail(&mut commands, &mut errors, entity, why.clone());
        }
        return;
    };
    let gravity = settings.gravity.unwrap_or_else(|| config.iter().next().map_or(DVec3::new(0.0, -9.81, 0.0), |c| c.gravity.as_dvec3()));
    let mut new: Vec<(Entity, &CableDescriptor, Option<&CableExact>)> = new.iter().collect();
    new.sort_by_key(|(e, _, _)| spawn_order(*e));
    let mut specs = Vec::new();
    let mut owners = Vec::new();
    // Exact motions of the fixed and kinematic bodies the batch hangs on.
    let mut motions = HashMap::new();
    for (entity, d, exact) in new {
        let attach = |a: &CableAnchor, point: Option<DVec3>, end: &str| -> Result<(Attach, Option<(Entity, RigidBodyHandle)>), String> {
            Ok(match a {
                CableAnchor::Free => (Attach::Free, None),
                CableAnchor::World { point: p, clamp } => (Attach::World { point: point.unwrap_or(p.as_dvec3()), clamp: *clamp }, None),
                CableAnchor::Body { entity: be, anchor, clamp } => {
                    let h = handles.get(*be).map_err(|_| format!("{end} body {be} has no rapier rigid body"))?.0;
                    if let (Ok(link), Some(default)) = (contexts.1.get(*be), default_context) {
                        if link.0 != default {
                            return Err(format!(
                                "{end} body {be} is in rapier context {}, not in the default context {default}: the cable plugin couples with the default rapier context only (several contexts are not supported yet)",
                                link.0
                            ));
                        }
                    }
                    (Attach::Body { body: h, anchor: point.unwrap_or(anchor.as_dvec3()), clamp: *clamp }, Some((*be, h)))
                }
            })
        };
        // A load the chain cannot take is refused by name, not stepped.
        if let Some((i, l)) =
            d.loads.iter().enumerate().find(|(_, l)| !(l.s.is_finite() && (0.0..=d.length).contains(&l.s) && l.force.is_finite() && l.moment.is_finite()))
        {
            let message = format!(
                "load {i} (s = {} m, force {} N, moment {} N·m): s must be within the cable's length {} m and every value finite",
                l.s, l.force, l.moment, d.length
            );
            fail(&mut commands, &mut errors, entity, message);
            continue;
        }
        let points = exact.map_or([None, None], |x| [x.start, x.end]);
        let ends = attach(&d.start, points[0], "start").and_then(|s| Ok((s, attach(&d.end, points[1], "end")?)));
        let ((start, sb), (end, eb)) = match ends {
            Ok(x) => x,
            Err(message) => {
                fail(&mut commands, &mut errors, entity, message);
                continue;
            }
        };
        let mut rope = RopeBuilder::new(d.length, d.segments, d.material.section(), d.material.diameter())
            .damping(d.damping)
            .velocity_damping(d.linear_damping, d.angular_damping)
            .end_stiffness_factor(d.end_stiffness)
            .gravity(gravity)
            .stress_free_shape(d.stress_free)
            .tension_only(d.tension_only);
        if let Some(ga) = d.shear_stiffness {
            rope = rope.shear_stiffness(ga);
        }
        let path = exact.and_then(|x| x.path.clone()).or_else(|| d.path.as_ref().map(|p| p.iter().map(|v| v.as_dvec3()).collect()));
        // Exact mass properties and pose of dynamic end bodies; exact
        // motions of the others.
        let lumped = |b: Option<(Entity, RigidBodyHandle)>| {
            let (be, h) = b?;
            let x = exact_bodies.get(be).ok()?;
            if ctx.rigidbody_set.bodies.get(h).is_some_and(|rb| rb.is_dynamic()) {
                Some(LumpedBody { mass: x.mass, inertia: x.inertia, position: x.position, rotation: DMat3::from_quat(x.rotation), com: DVec3::ZERO })
            } else {
                None
            }
        };
        for (be, h) in [sb, eb].into_iter().flatten() {
            if let Some(m) = exact_bodies.get(be).ok().and_then(|x| x.motion.clone()) {
                motions.insert(h, m);
            }
        }
        let exact_ends = [lumped(sb), lumped(eb)];
        let contact = if d.contacts {
            match CableContact::steel(d.material.diameter(), d.material.section().linear_density * d.length / d.segments.max(1) as f64)
                .and_then(|k| k.with_friction(d.friction))
                .map(|k| k.with_groups(d.collision_groups.into()))
            {
                Ok(k) => Some(k),
                Err(e) => {
                    fail(&mut commands, &mut errors, entity, e.to_string());
                    continue;
                }
            }
        } else {
            None
        };
        specs.push(CableSpec { rope, path, start, end, scheme: d.scheme.clone(), exact: exact_ends, contact });
        owners.push((entity, [sb, eb], d.loads.clone(), d.static_start));
    }
    let others: Vec<&CoupledCable> = existing.iter().map(|(_, s)| &s.coupled).collect();
    let carriers: Vec<Entity> = existing.iter().map(|(e, _)| e).collect();
    let built = coupling::build_cables(&specs, &others, &mut ctx.rigidbody_set.bodies, &mut ctx.joints.impulse_joints, &motions);
    let bodies = &ctx.rigidbody_set.bodies;
    // Entities of the bodies and cables of the batch, for messages.
    let entity_of: HashMap<RigidBodyHandle, Entity> = owners.iter().flat_map(|(_, ends, _, _)| ends.iter().flatten().map(|(e, h)| (*h, *e))).collect();
    let batch: Vec<Entity> = owners.iter().map(|(e, _, _, _)| *e).collect();
    let message = |e: &CouplingError| refusal(e, &entity_of, &batch, &carriers);
    // 1. Build: the cables with their own chain, and the ropes grafted
    //    onto another batch member's chain (onto, rope index).
    let mut sims: Vec<Option<CoupledCable>> = Vec::new();
    let mut parts: Vec<Option<(usize, usize)>> = Vec::new();
    for ((entity, _, _, _), r) in owners.iter().zip(built) {
        let (sim, part) = match r {
            Ok(Built::Cable(cc)) => (Some(*cc), None),
            Ok(Built::Part { onto, part }) => (None, Some((onto, part))),
            Err(e) => {
                fail(&mut commands, &mut errors, *entity, message(&e));
                (None, None)
            }
        };
        sims.push(sim);
        parts.push(part);
    }
    // 2. Loads: each cable's on its own rope, or on its rope in the chain
    //    it is grafted onto.
    for (k, (_, _, loads, _)) in owners.iter().enumerate() {
        let (i, rope) = match (sims[k].is_some(), parts[k]) {
            (true, _) => (k, 0),
            (false, Some((onto, part))) => (onto, part),
            _ => continue,
        };
        if let Some(cc) = sims[i].as_mut() {
            for l in loads {
                let added = cc.cable.add_rope_point_load(rope, l.s, l.force, l.moment);
                debug_assert!(added, "the core gave this rope");
            }
        }
    }
    // 3. Static start and initial velocities of the carried bodies (exact
    //    when the body has `BodyExact`, else rapier's).
    let velocity = |h: RigidBodyHandle| {
        let exact = entity_of.get(&h).and_then(|e| exact_bodies.get(*e).ok());
        match (exact, bodies.get(h)) {
            (Some(x), _) => (x.linear_velocity, x.angular_velocity),
            (None, Some(rb)) => (rb.linvel().as_dvec3(), rb.angvel().as_dvec3()),
            (None, None) => (DVec3::ZERO, DVec3::ZERO),
        }
    };
    for (k, (entity, _, _, statics)) in owners.iter().enumerate() {
        let Some(cc) = sims[k].as_mut() else { continue };
        cc.keep_loads();
        if let Some(steps) = statics {
            if let Err(e) = cc.cable.solve_static(*steps as usize, STATIC_TOLERANCE, STATIC_MAX_ITERATIONS) {
                fail(&mut commands, &mut errors, *entity, format!("static start: {e}"));
                sims[k] = None;
                continue;
            }
        }
        if let Err((_, e)) = cc.start_velocities(&velocity) {
            fail(&mut commands, &mut errors, *entity, e.to_string());
            sims[k] = None;
        }
    }
    // 4. Components.
    let alive: Vec<bool> = sims.iter().map(Option::is_some).collect();
    for (k, (entity, ends, _, _)) in owners.iter().enumerate() {
        if let Some((onto, part)) = parts[k] {
            // A rope grafted onto another entity's chain: that entity must
            // exist (it fails with its ropes).
            if !alive[onto] {
                fail(&mut commands, &mut errors, *entity, message(&CouplingError::Island { cable: onto }));
            } else {
                commands.entity(*entity).insert((CableRopeOf { cable: batch[onto], rope: part }, CableState::default()));
            }
            continue;
        }
        let Some(cc) = sims[k].take() else { continue };
        // An explicit exchange that is likely unstable at this step: said
        // once, at creation (`cablesim` warns the same way).
        let exchange = settings.step.unwrap_or(match mode.as_deref() {
            Some(TimestepMode::Fixed { dt, substeps }) => f64::from(*dt) / f64::from((*substeps).max(1) as u32),
            _ => 1.0 / 60.0,
        });
        for (body, start, ratio) in cc.explicit_ratios(&ctx.rigidbody_set.bodies, exchange) {
            if ratio > 1.0 {
                let who = ends.iter().flatten().find(|(_, h)| *h == body).map_or_else(|| format!("{body:?}"), |(e, _)| format!("{e}"));
                log::warn!(
                    "cable {entity}: its {} on body {who} is coupled explicitly (the body is held by joints, or on several cables' starts) with k·h²/m = {ratio:.2e} > 1 (k = EA/L_e, h = {exchange} s): it may be unstable; coupled sub-steps (`CablePlugin::with_coupled_substeps({})`) bring it to 1",
                    if start { "start" } else { "end" },
                    ratio.sqrt().ceil()
                );
            }
        }
        let mut carried = Vec::new();
        let mut rail = None;
        // Its own ends, then the far bodies its grafted ropes carry (a
        // payload below the hub).
        let limb_ends = owners
            .iter()
            .zip(&parts)
            .filter(|(_, p)| p.is_some_and(|(onto, _)| onto == k))
            .flat_map(|((_, e, _, _), _)| e.iter().flatten().copied())
            .filter(|(be, h)| ends.iter().flatten().all(|(own, _)| own != be) && cc.carried.iter().any(|c| c.body == *h))
            .map(|e| (1, e));
        let own_ends = ends.iter().enumerate().filter_map(|(i, e)| e.map(|e| (i, e)));
        for (i, (be, h)) in own_ends.chain(limb_ends) {
            let role = cc.role_of(h).expect("every body end has a role");
            carried.push((
                be,
                match role {
                    Role::Carried | Role::Trolley { .. } => {
                        let c = cc.carried.iter().find(|c| c.body == h).expect("carried");
                        if matches!(role, Role::Trolley { .. }) {
                            rail = Some(be);
                        }
                        CarriedBody::Lumped(c.place)
                    }
                    Role::Base => CarriedBody::Base,
                    Role::Explicit if i == 0 => CarriedBody::Explicit,
                    Role::Explicit => CarriedBody::ExplicitEnd,
                },
            ));
        }
        commands.entity(*entity).insert((CableSim { coupled: cc, bodies: carried, rail, warned_moved: false, released: false }, CableState::default()));
    }
}

/// A cable of a batch is not built: its [`CableError`]
/// ([`CableErrorKind::Configuration`], time 0), logged, and its descriptor
/// removed so that it is not tried again.
fn fail(commands: &mut Commands, errors: &mut MessageWriter<CableError>, entity: Entity, message: String) {
    report(errors, CableError::new(entity, CableErrorKind::Configuration, 0.0, message));
    commands.entity(entity).remove::<CableDescriptor>();
}

/// Logs a [`CableError`] (error level, through the `log` facade that
/// Bevy's `LogPlugin` shows) and sends it.
pub(crate) fn report(errors: &mut MessageWriter<CableError>, error: CableError) {
    log::error!("{error}");
    errors.write(error);
}

/// Why a cable of the batch `batch` was not built, with entities for the
/// core's rapier handles and batch indices.
fn refusal(e: &CouplingError, entity_of: &HashMap<RigidBodyHandle, Entity>, batch: &[Entity], carriers: &[Entity]) -> String {
    if let CouplingError::BodyTaken { end, cable } = e {
        let by = carriers.get(*cable).map_or_else(|| format!("#{cable}"), |c| c.to_string());
        return format!(
            "the cable's {end} is attached to a body that cable {by} already carries as a link of its chain (cables are solved together with a body only when spawned in the same frame: despawn cable {by} and spawn all the body's cables together)"
        );
    }
    let body = |h: RigidBodyHandle| format!("body {}", entity_of.get(&h).map_or_else(|| format!("{h:?}"), |e| e.to_string()));
    e.describe(&body, &|k| format!("cable {}", batch[k]))
}

/// What the user asks of a carried body through bevy_rapier's components.
type InputComponents =
    (Option<&'static ExternalForce>, Option<&'static GravityScale>, Option<&'static Damping>, Option<&'static RigidBody>, Has<RigidBodyDisabled>);

/// Advances every cable by the fixed step (the core's phase 1: before
/// rapier's step).
#[allow(clippy::too_many_arguments)]
pub(crate) fn step_cables(
    mut cables: Query<(Entity, &mut CableSim)>,
    mut ctx: WriteRapierContext,
    inputs: Query<InputComponents>,
    handles: Query<&RapierRigidBodyHandle>,
    exact_bodies: Query<(&RapierRigidBodyHandle, &BodyExact)>,
    joints: Query<&ImpulseJoint>,
    ropes: Query<(Entity, &CableRopeOf)>,
    settings: Res<CableSettings>,
    time: Res<Time>,
    mode: Option<Res<TimestepMode>>,
    config: Query<&RapierConfiguration, With<DefaultRapierContext>>,
    mut errors: MessageWriter<CableError>,
) {
    // Rapier paused (`physics_pipeline_active` false): it does not step,
    // and neither do the cables (their time, ropes and carried bodies
    // stay as they are).
    if paused(&config) {
        return;
    }
    let mut list: Vec<(Entity, Mut<CableSim>)> = cables.iter_mut().collect();
    list.sort_by_key(|(e, _)| spawn_order(*e));
    let dt = match (settings.step, rapier_step(mode.as_deref(), &time)) {
        // A scenario's exact step, on the frames the schedule advances.
        (Some(h), _) if time.delta_secs_f64() > 0.0 => h,
        (Some(_), _) => return,
        (None, Ok(h)) => h,
        (None, Err(why)) => {
            for (entity, sim) in list.iter_mut().filter(|(_, s)| !s.failed) {
                halt(&mut errors, &ropes, *entity, &mut sim.coupled, CableErrorKind::Configuration, why.clone());
            }
            return;
        }
    };
    if dt <= 0.0 {
        return;
    }
    let Ok(mut ctx) = ctx.single_mut() else {
        return;
    };
    // Gravity as rapier has it now (unless the settings fix it): a change
    // of `RapierConfiguration::gravity` reaches the ropes and their carried
    // bodies at this step, as it reaches rapier's bodies.
    let gravity = settings.gravity.or_else(|| config.iter().next().map(|c| c.gravity.as_dvec3()));
    let mut given: HashMap<RigidBodyHandle, BodyInputs> = HashMap::new();
    for (entity, sim) in &mut list {
        let sim = &mut **sim;
        if let Some(g) = gravity.filter(|g| *g != sim.coupled.cable.gravity()) {
            if let Err(e) = sim.coupled.cable.set_gravity(g) {
                if !sim.coupled.failed {
                    halt(&mut errors, &ropes, *entity, &mut sim.coupled, CableErrorKind::InvalidInput, format!("rapier's {e}"));
                }
                continue;
            }
        }
        let mut invalid = None;
        // A body that moves a cable end (fixed or kinematic when the cable
        // was built) made dynamic: the cable would follow it without
        // pulling it.
        let mut unfit = sim.bodies.iter().filter(|(_, c)| matches!(c, CarriedBody::Base)).find_map(|(be, _)| match inputs.get(*be) {
            Ok((_, _, _, Some(RigidBody::Dynamic), _)) => Some(format!(
                "body {be}, which moves one of its ends, was made `RigidBody::Dynamic`: the cable follows a fixed or kinematic body without pulling it, so it cannot hold this one; the cable is stopped (despawn it, and spawn a new one to couple the rope to the body as it is now)"
            )),
            _ => None,
        });
        for (be, _) in sim.bodies.iter().filter(|(_, c)| matches!(c, CarriedBody::Lumped(_))) {
            let (Ok((force, scale, damping, kind, disabled)), Ok(h)) = (inputs.get(*be), handles.get(*be)) else {
                continue;
            };
            unfit = unfit.or_else(|| not_carriable(*be, kind, disabled, ctx.rigidbody_set.bodies.get(h.0)));
            // (A stopped cable's bodies are rapier's again: they move.)
            if !sim.warned_moved && !sim.coupled.failed {
                if let Some((off, at)) = moved_from_rope(&sim.coupled, &ctx.rigidbody_set.bodies, h.0) {
                    sim.warned_moved = true;
                    log::warn!(
                        "cable {entity}: its carried body {be} was moved (its `Transform` written) to ({:.3}, {:.3}, {:.3}), {off:.3} m from where the rope holds it; a carried body's pose is the cable's, so the move is undone (move the rope's other end instead, or despawn the cable, move the body and spawn a new cable)",
                        at.x,
                        at.y,
                        at.z
                    );
                }
            }
            let input = BodyInputs {
                force: force.map_or(DVec3::ZERO, |f| f.force.as_dvec3()),
                torque: force.map_or(DVec3::ZERO, |f| f.torque.as_dvec3()),
                gravity_scale: scale.map_or(1.0, |s| s.0 as f64),
                linear_damping: damping.map_or(0.0, |d| d.linear_damping as f64),
                angular_damping: damping.map_or(0.0, |d| d.angular_damping as f64),
            };
            // The user's velocity writes and impulses are on the rapier
            // body by now (bevy_rapier's `SyncBackend` applied them).
            let velocity = ctx.rigidbody_set.bodies.get(h.0).map(|rb| (rb.linvel(), rb.angvel()));
            invalid = invalid.or_else(|| invalid_input(*be, &input, velocity));
            given.insert(h.0, input);
        }
        let refused = unfit.map(|m| (CableErrorKind::Configuration, m)).or(invalid.map(|m| (CableErrorKind::InvalidInput, m)));
        if let (false, Some((kind, message))) = (sim.coupled.failed, refused) {
            halt(&mut errors, &ropes, *entity, &mut sim.coupled, kind, message);
            continue;
        }
        if let (Some(trolley), Some((_, Role::Trolley { offset, .. }))) = (sim.rail, sim.coupled.roles[0]) {
            // The motor along the rail (a `PrismaticJoint`, or any joint
            // whose free axis is its local x).
            let motor = joints.get(trolley).ok().and_then(|j| match &j.data {
                TypedJoint::PrismaticJoint(pj) => pj.motor().copied(),
                data => data.as_ref().motor(JointAxis::LinX).copied(),
            });
            rail_motor(&mut sim.coupled, motor, offset);
        }
    }
    let mut refs: Vec<&mut CoupledCable> = list.iter_mut().map(|(_, s)| &mut s.coupled).collect();
    let each: &dyn ForEachCable = if settings.parallel { &OnTaskPool } else { &OneByOne };
    // Exact motions of the bodies that carry `BodyExact` (a scenario's),
    // for the contacts' geometry, as `cablesim` has them.
    let motions: HashMap<RigidBodyHandle, BodyMotion> = exact_bodies.iter().filter_map(|(h, x)| x.motion.clone().map(|m| (h.0, m))).collect();
    let failures = coupling::step_cables(
        &mut refs,
        &mut ctx.rigidbody_set.bodies,
        Contacts { colliders: &ctx.colliders.colliders, motions: &|b| motions.get(&b).cloned(), jointed: &[], kinematic: &[] },
        &mut ctx.joints.impulse_joints,
        dt,
        settings.substeps,
        &|h| given.get(&h).copied().unwrap_or_default(),
        each,
    );
    for (i, t, e) in failures {
        // A rope laid into a collider is the user's layout, not a failed solve.
        let kind = if matches!(e, crate::cable::CableError::StartsInside { .. }) { CableErrorKind::Configuration } else { CableErrorKind::Diverged };
        stop(&mut errors, &ropes, CableError::new(list[i].0, kind, t, e.to_string()));
    }
}

/// How far (m) body `body` is from where the core left it after rapier's
/// last step (on its cable's pose), and where it is (m, world), when that
/// is more than 1 mm: the user wrote its `Transform` since.
fn moved_from_rope(cc: &CoupledCable, bodies: &bevy_rapier3d::rapier::dynamics::RigidBodySet, body: RigidBodyHandle) -> Option<(f64, DVec3)> {
    let left = cc.carried.iter().find(|c| c.body == body)?.left_at?.as_dvec3();
    let at = bodies.get(body)?.translation().as_dvec3();
    let off = at.distance(left);
    (off > 1e-3).then_some((off, at))
}

/// Whether rapier's default context is paused
/// (`RapierConfiguration::physics_pipeline_active` false): bevy_rapier then
/// neither steps nor writes its bodies back, and the cables do not step.
fn paused(config: &Query<&RapierConfiguration, With<DefaultRapierContext>>) -> bool {
    config.iter().next().is_some_and(|c| !c.physics_pipeline_active)
}

/// Why the cables refuse rapier's `TimestepMode::Interpolated`.
const INTERPOLATED: &str = "rapier's `TimestepMode::Interpolated` takes a varying number of rapier steps per frame, which the cables cannot follow: use `TimestepMode::Fixed { dt, .. }` (with the cables in `FixedUpdate`, dt = the fixed timestep) or `TimestepMode::Variable`";

/// The time rapier advances in one run of its step system, s, as
/// bevy_rapier's `step_simulation` computes it from `TimestepMode` (in
/// f32, as rapier does), or why the cables cannot follow it. Without the
/// resource: the schedule's `Time` delta.
pub(crate) fn rapier_step(mode: Option<&TimestepMode>, time: &Time) -> Result<f64, String> {
    match mode {
        None => Ok(time.delta_secs_f64()),
        Some(TimestepMode::Fixed { dt, .. }) => Ok(*dt as f64),
        Some(TimestepMode::Variable { max_dt, time_scale, .. }) => Ok((time.delta_secs() * time_scale).min(*max_dt) as f64),
        Some(TimestepMode::Interpolated { .. }) => Err(INTERPOLATED.into()),
    }
}

/// [`ForEachCable`] on Bevy's compute task pool: one task per cable, when
/// there are several and the pool exists (else one after the other).
struct OnTaskPool;

impl ForEachCable for OnTaskPool {
    fn for_each(&self, cables: &mut [&mut CoupledCable], job: &(dyn Fn(&mut CoupledCable) + Sync)) {
        match bevy::tasks::ComputeTaskPool::try_get() {
            Some(pool) if cables.len() > 1 && pool.thread_num() > 1 => {
                pool.scope(|scope| {
                    for cc in cables.iter_mut() {
                        scope.spawn(async move { job(cc) });
                    }
                });
            }
            _ => OneByOne.for_each(cables, job),
        }
    }
}

/// Why the inputs of carried body `body` cannot enter the cable solve (a
/// non-finite value, named), or `None`.
fn invalid_input(body: Entity, input: &BodyInputs, velocity: Option<(Vec3, Vec3)>) -> Option<String> {
    // Checked every step for every carried body: the values are formatted
    // only for the message.
    let named: [(&str, bool, &dyn std::fmt::Display); 5] = [
        ("ExternalForce::force (N)", input.force.is_finite(), &input.force),
        ("ExternalForce::torque (N·m)", input.torque.is_finite(), &input.torque),
        ("GravityScale", input.gravity_scale.is_finite(), &input.gravity_scale),
        ("Damping::linear_damping (1/s)", input.linear_damping.is_finite(), &input.linear_damping),
        ("Damping::angular_damping (1/s)", input.angular_damping.is_finite(), &input.angular_damping),
    ];
    if let Some((what, _, value)) = named.iter().find(|(_, ok, _)| !ok) {
        return Some(format!("carried body {body}: its {what} is not finite ({value})"));
    }
    let (lin, ang) = velocity?;
    if !(lin.is_finite() && ang.is_finite()) {
        return Some(format!(
            "carried body {body}: its velocity is not finite (linear {lin} m/s, angular {ang} rad/s): a `Velocity` write or an `ExternalImpulse` with a NaN or infinite value"
        ));
    }
    None
}

/// Why carried body `body` cannot stay in its cable's solve: the user made
/// it fixed or kinematic (`kind`), disabled it, or took its mass away (its
/// colliders removed); `rb` is its rapier body.
fn not_carriable(body: Entity, kind: Option<&RigidBody>, disabled: bool, rb: Option<&bevy_rapier3d::rapier::dynamics::RigidBody>) -> Option<String> {
    const FIX: &str = "a body the cable carries moves in the cable's solve and must stay a dynamic, enabled rapier body with mass; the cable is stopped (despawn it, and spawn a new one to hang a rope on the body as it is now)";
    let why = match (kind, disabled, rb.map(|rb| rb.mass())) {
        (Some(k), _, _) if *k != RigidBody::Dynamic => format!("was made `RigidBody::{k:?}`"),
        (_, true, _) => "was disabled (`RigidBodyDisabled`)".to_string(),
        (_, _, Some(m)) if m.is_nan() || m <= 0.0 => format!("has no mass left ({m} kg: its colliders removed, or zero mass properties)"),
        _ => return None,
    };
    Some(format!("carried body {body} {why}: {FIX}"))
}

/// Stops cable `entity` before its step: its core marked failed, and a
/// [`CableError`] of `kind` at its time ([`stop`]).
fn halt(
    errors: &mut MessageWriter<CableError>,
    ropes: &Query<(Entity, &CableRopeOf)>,
    entity: Entity,
    coupled: &mut CoupledCable,
    kind: CableErrorKind,
    message: String,
) {
    coupled.failed = true;
    let t = coupled.cable.time();
    stop(errors, ropes, CableError::new(entity, kind, t, message));
}

/// Stops a cable: its [`CableError`], logged, and the same for every rope
/// solved in its chain (a sling leg stops with the cable that carries it).
fn stop(errors: &mut MessageWriter<CableError>, ropes: &Query<(Entity, &CableRopeOf)>, error: CableError) {
    let (owner, kind, time, reason) = (error.entity, error.kind, error.time, error.message.clone());
    report(errors, error);
    for (entity, _) in ropes.iter().filter(|(_, of)| of.cable == owner) {
        report(errors, CableError::new(entity, kind, time, format!("solved as one island with cable {owner}, which stopped: {reason}")));
    }
}

/// The core's phase 2, after rapier's step and before its writeback: the
/// contact impulses rapier gave the carried bodies are kept for the next
/// step, and the bodies are put on the cable's pose and velocity.
pub(crate) fn write_bodies(
    mut cables: Query<(Entity, &mut CableSim)>,
    mut ctx: WriteRapierContext,
    config: Query<&RapierConfiguration, With<DefaultRapierContext>>,
) {
    // Nothing stepped while rapier is paused.
    if paused(&config) {
        return;
    }
    let Ok(mut ctx) = ctx.single_mut() else {
        return;
    };
    let mut list: Vec<(Entity, Mut<CableSim>)> = cables.iter_mut().collect();
    list.sort_by_key(|(e, _)| spawn_order(*e));
    let mut refs: Vec<&mut CoupledCable> = list.iter_mut().map(|(_, s)| &mut s.coupled).collect();
    coupling::after_rapier(&mut refs, &mut ctx.rigidbody_set.bodies, &ctx.colliders.colliders, &ctx.simulation.narrow_phase);
}

/// Refreshes [`CableState`] of every cable, and of the ropes grafted onto
/// another cable's chain ([`CableRopeOf`]).
pub(crate) fn readout(mut cables: Query<(&CableSim, &mut CableState)>, mut ropes: Query<(&CableRopeOf, &mut CableState), Without<CableSim>>) {
    let fill = |c: &crate::cable::Cable, rope: usize, st: &mut CableState| {
        let Some(r) = c.rope(rope) else {
            return;
        };
        st.nodes = r.nodes().iter().map(|p| p.as_vec3()).collect();
        st.tensions = (0..r.elements()).map(|i| r.element_forces(i).map_or(0.0, |f| f.tension as f32)).collect();
        st.stretched_length = r.stretched_length() as f32;
        st.contact_force = r.contact_force() as f32;
        st.frames = r.element_frames().iter().map(|m| Quat::from_mat3(&m.as_mat3()).normalize()).collect();
        st.contacts = r.contacts().iter().map(|(p, f)| (p.as_vec3(), f.as_vec3())).collect();
        st.energy = c.energy();
        st.time = c.time();
        st.newton_iterations = c.last_stats.newton_iterations;
    };
    for (sim, mut st) in &mut cables {
        fill(&sim.cable, 0, &mut st);
    }
    for (of, mut st) in &mut ropes {
        if let Ok((sim, _)) = cables.get(of.cable) {
            fill(&sim.cable, of.rope, &mut st);
        }
    }
}

/// Which cable entity's chain solves each sling leg ([`CableRopeOf`]), kept
/// so that a despawned leg can still be traced to its island.
#[derive(Resource, Debug, Default)]
pub(crate) struct Legs(pub(crate) HashMap<Entity, Entity>);

/// Records the legs of new islands (after [`init_cables`]' commands).
pub(crate) fn record_legs(mut legs: ResMut<Legs>, new: Query<(Entity, &CableRopeOf), Added<CableRopeOf>>) {
    for (e, of) in &new {
        legs.0.insert(e, of.cable);
    }
}

/// What bevy_rapier's components ask of a body once no cable carries it.
type ReleaseComponents = (Option<&'static GravityScale>, Option<&'static Damping>, Option<&'static ExternalForce>, Option<&'static Sleeping>);

/// A cable's [`CableSim`] is going (the cable entity despawned, or the
/// plugin removing it because a body it carries was despawned): the bodies
/// it carried become ordinary rapier bodies again ([`release_bodies`]), and
/// the sling legs solved in its chain are released (their descriptors
/// removed, so they are not rebuilt from their initial path). Logged.
#[allow(clippy::too_many_arguments)]
pub(crate) fn release_cable(
    remove: On<Remove, CableSim>,
    sims: Query<&CableSim>,
    mut ctx: WriteRapierContext,
    handles: Query<&RapierRigidBodyHandle>,
    components: Query<ReleaseComponents>,
    mut joints: Query<&mut ImpulseJoint>,
    mut legs: ResMut<Legs>,
    mut commands: Commands,
) {
    let cable = remove.entity;
    let Ok(sim) = sims.get(cable) else {
        return;
    };
    let Ok(mut ctx) = ctx.single_mut() else {
        return;
    };
    // A stopped cable's bodies were released when it stopped.
    let released = if sim.released { Vec::new() } else { release_bodies(sim, &mut ctx.rigidbody_set.bodies, &handles, &components, &mut joints) };
    let grafted: Vec<Entity> = legs.0.iter().filter(|(_, c)| **c == cable).map(|(l, _)| *l).collect();
    for leg in &grafted {
        legs.0.remove(leg);
        if let Ok(mut e) = commands.get_entity(*leg) {
            e.remove::<(CableRopeOf, CableDescriptor, CableState)>();
        }
    }
    log::info!("cable {cable} removed: bodies {released:?} are rapier bodies again, sling legs {grafted:?} released");
}

/// A cable that stopped ([`CableError`]) no longer holds the bodies it
/// carried: at the step it stopped they become ordinary rapier bodies
/// again ([`release_bodies`]), as when the rope is removed, so a payload
/// falls (or flies on) under rapier instead of hanging frozen where the
/// rope left it, with gravity and damping off. The cable keeps its last
/// good state ([`CableState`]) and its entity.
pub(crate) fn release_stopped(
    mut cables: Query<(Entity, &mut CableSim)>,
    mut ctx: WriteRapierContext,
    handles: Query<&RapierRigidBodyHandle>,
    components: Query<ReleaseComponents>,
    mut joints: Query<&mut ImpulseJoint>,
) {
    let Ok(mut ctx) = ctx.single_mut() else {
        return;
    };
    for (cable, mut sim) in &mut cables {
        if sim.coupled.failed && !sim.released {
            sim.released = true;
            let released = release_bodies(&sim, &mut ctx.rigidbody_set.bodies, &handles, &components, &mut joints);
            log::info!("cable {cable} stopped: the bodies it carried, {released:?}, are rapier bodies again");
        }
    }
}

/// Hands the bodies cable `sim` carried back to rapier, as their
/// components say (gravity scale, damping, external force, sleeping; the
/// defaults where a component is absent; gyroscopic torques on, rapier's
/// default), and a trolley's rail motor acts in rapier again. Returns the
/// bodies released.
fn release_bodies(
    sim: &CableSim,
    bodies: &mut bevy_rapier3d::rapier::dynamics::RigidBodySet,
    handles: &Query<&RapierRigidBodyHandle>,
    components: &Query<ReleaseComponents>,
    joints: &mut Query<&mut ImpulseJoint>,
) -> Vec<Entity> {
    let mut released = Vec::new();
    for (be, kind) in &sim.bodies {
        let CarriedBody::Lumped(_) = kind else { continue };
        let Some(rb) = handles.get(*be).ok().and_then(|h| bodies.get_mut(h.0)) else {
            continue;
        };
        let (scale, damping, force, sleeping) = components.get(*be).unwrap_or((None, None, None, None));
        rb.set_gravity_scale(scale.map_or(1.0, |s| s.0), true);
        rb.set_linear_damping(damping.map_or(0.0, |d| d.linear_damping));
        rb.set_angular_damping(damping.map_or(0.0, |d| d.angular_damping));
        rb.reset_forces(true);
        rb.reset_torques(true);
        if let Some(f) = force {
            rb.add_force(f.force, true);
            rb.add_torque(f.torque, true);
        }
        rb.enable_gyroscopic_forces(true);
        let act = rb.activation_mut();
        let default = bevy_rapier3d::rapier::dynamics::RigidBodyActivation::active();
        act.normalized_linear_threshold = sleeping.map_or(default.normalized_linear_threshold, |s| s.normalized_linear_threshold);
        act.angular_threshold = sleeping.map_or(default.angular_threshold, |s| s.angular_threshold);
        released.push(*be);
    }
    if let Some(rail) = sim.rail {
        // bevy_rapier writes the joint (with its motor) into rapier again.
        if let Ok(mut j) = joints.get_mut(rail) {
            j.set_changed();
        }
    }
    released
}

/// Cables whose carried body was despawned, or a body that holds one of
/// their ends (a hook, a post: as rapier drops a joint whose body is
/// despawned), or one of whose sling legs was: the cable is removed
/// ([`CableSim`] and its descriptor, so that it is not rebuilt;
/// [`release_cable`] frees the rest), with a warning. A cable cannot hold a
/// phantom load, nor hang from a body that is gone.
pub(crate) fn drop_orphans(
    mut commands: Commands,
    cables: Query<(Entity, &CableSim)>,
    exists: Query<(), With<RigidBody>>,
    mut removed_legs: RemovedComponents<CableRopeOf>,
    entities: Query<Entity>,
    mut legs: ResMut<Legs>,
    grafted: Query<(Entity, &CableRopeOf, &CableDescriptor)>,
) {
    for (cable, sim) in &cables {
        if let Some((gone, kind)) = sim.bodies.iter().find(|(b, _)| exists.get(*b).is_err()) {
            if matches!(kind, CarriedBody::Lumped(_)) {
                log::warn!("cable {cable}: its carried body {gone} was despawned; the cable is removed (despawn or respawn the cable entity yourself to keep a rope there)");
            } else {
                // As rapier drops a joint whose body is despawned.
                log::warn!(
                    "cable {cable}: body {gone}, which held one of its ends, was despawned; the cable is removed and the bodies it carried are rapier bodies again (despawn or respawn the cable entity yourself to keep a rope there)"
                );
            }
            commands.entity(cable).remove::<(CableSim, CableDescriptor, CableState)>();
        }
    }
    // A sling leg's own end body (its hook) despawned: its island goes, as
    // when the leg itself is despawned; the leg's descriptor too (it
    // could not be built again without the body).
    for (leg, of, d) in &grafted {
        let gone = [&d.start, &d.end].into_iter().find_map(|a| match a {
            CableAnchor::Body { entity, .. } if exists.get(*entity).is_err() => Some(*entity),
            _ => None,
        });
        if let (Some(gone), true) = (gone, cables.contains(of.cable)) {
            log::warn!("sling leg {leg}: body {gone}, which held one of its ends, was despawned; its island (cable {}) is removed and the bodies it carried are released", of.cable);
            commands.entity(of.cable).remove::<(CableSim, CableDescriptor, CableState)>();
            commands.entity(leg).remove::<CableDescriptor>();
        }
    }
    for leg in removed_legs.read() {
        if entities.contains(leg) {
            continue;
        }
        if let Some(carrier) = legs.0.remove(&leg) {
            if cables.contains(carrier) {
                log::warn!("sling leg {leg} was despawned: its island (cable {carrier} and its other legs) is removed and the bodies it carried are released");
                commands.entity(carrier).remove::<(CableSim, CableDescriptor, CableState)>();
            }
        }
    }
}

/// A cable's descriptor with the change ticks of its build.
type EditedCable = (Entity, Ref<'static, CableDescriptor>, Option<Ref<'static, CableSim>>, Option<Ref<'static, CableRopeOf>>);

/// A [`CableDescriptor`] edited after its cable was built: the edit is
/// refused with a warning (the running cable keeps its state; despawn the
/// entity and spawn a new one to change it).
pub(crate) fn refuse_edits(edited: Query<EditedCable, Changed<CableDescriptor>>, ticks: bevy::ecs::system::SystemChangeTick) {
    for (e, desc, sim, leg) in &edited {
        let Some(built) = sim.map(|s| s.added()).or_else(|| leg.map(|l| l.added())) else {
            continue;
        };
        if desc.last_changed().is_newer_than(built, ticks.this_run()) {
            log::warn!("cable {e}: its CableDescriptor was changed after the cable was built; the change is ignored (despawn the cable and spawn a new one)");
        }
    }
}
