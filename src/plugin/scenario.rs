//! A scenario file spawned into a Bevy app with the plugin: its bodies
//! become bevy_rapier entities, its cables [`CableDescriptor`] entities,
//! and the plugin steps them through the same coupling core as `cablesim`
//! ([`crate::sim::World`]). The probes are sampled every fixed step into
//! [`ScenarioRun::rows`] by the same code as `cablesim`'s `results.csv`.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy::time::TimeUpdateStrategy;
//! use bevy_rapier3d::prelude::*;
//! use bevy_rapier_cable::plugin::{scenario, CablePlugin};
//! let sc = bevy_rapier_cable::scenario::load(std::path::Path::new("assets/scenarios/hanging_payload.toml")).unwrap();
//! let mut app = App::new();
//! app.add_plugins((MinimalPlugins, TransformPlugin,
//!                  RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(),
//!                  CablePlugin::default()));
//! app.insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
//! scenario::add_scenario(&mut app, sc).unwrap();
//! app.finish();
//! app.cleanup();
//! for _ in 0..60 {
//!     app.update();
//! }
//! let run = app.world().resource::<scenario::ScenarioRun>();
//! println!("{} rows, last at t = {} s", run.rows.len(), run.time);
//! ```
//!
//! What makes it the same run as `cablesim` (tested bit for bit on the
//! 15 shipped scenarios over their whole duration, `tests/plugin_scenarios.rs`):
//! * the scenario's f64 data reach the core unrounded: cable paths and
//!   anchor points ([`CableExact`]), body mass properties, poses, initial
//!   velocities and the closed-form pose of fixed bodies ([`BodyExact`]),
//!   the step `dt` and gravity ([`CableSettings::step`],
//!   [`CableSettings::gravity`]); rapier gets the same f32 values as
//!   `cablesim`'s rapier world (`TimestepMode::Fixed` with `dt` as f32,
//!   `RapierConfiguration::gravity`);
//! * the plugin builds, loads, statically solves and starts the cables in
//!   `cablesim`'s order and steps them with the same core calls.
//!
//! Joints are spawned as bevy_rapier `ImpulseJoint`s on their body2's
//! entity (a fixed `world` entity stands for the ground), built by
//! `cablesim`'s own joint code; kinematic bodies follow their `motion`
//! (moved in rapier before its step, and read in closed form by the
//! cables).
//!
//! `[simulation] substeps` = n makes the app's fixed step `dt / n`: cables
//! and rapier step together n times per frame, as in `cablesim`, and a
//! row is sampled every n fixed steps. What bevy_rapier has no component
//! for is set on the rapier bodies directly (gyroscopic torques), and the
//! joints rapier keeps are recorded as `cablesim` records them (unwrapped
//! revolute angles, for their probes).
//!
//! Joint drives act as in `cablesim`: a `velocity` drive on a trolley's
//! rail becomes the rail joint's motor, which the plugin reads (the law
//! both runners share, `coupling::rail_motor`); the drives of joints rapier
//! keeps are applied to rapier before its step by `cablesim`'s own code.
//! A `[[controller]]` samples through the same code as in `cablesim`
//! (`sim::control`) before the cables' step, and its command becomes its
//! rail joint's motor (replacing the rail's `drive`).
//!
//! **Not yet spawned** (refused with [`SimError::Unsupported`] naming the
//! item): a `force` table on a trolley's rail (`cablesim` applies it as the
//! chain's joint force; the plugin drives a rail only through the joint's
//! motor), and two joints on the same body2 (bevy_rapier holds one joint
//! per entity). Everything `cablesim` refuses is refused here too, with the
//! same message.

use super::components::{BodyExact, CableAnchor, CableDescriptor, CableError, CableExact, CablePointLoad, CableRopeOf, CableSim};
use super::{CableSettings, CableSystems};
use crate::cable::{BodyInChain, Cable, RopeMaterial, RopeSection, RopeView};
use crate::coupling::set_velocity_drive;
use crate::coupling::{CoupledCable, Role};
use crate::crane::control::TrolleyMeasurement;
use crate::integrate::{Scheme, SchemeParams};
use crate::scenario::{BodyKind, CableEnd, Drive, Location, Quantity, Scenario};
use crate::sim::control::{self, ControllerRun};
use crate::sim::probe::{self, Probe, ProbeSource};
use crate::sim::rapier::{drive_joints, free_body_energies, joint_data, motion_pose, pose_of, shared_shape, velocity_of, RapierJoint};
use crate::sim::{body_motion, shape_inertia, SimError, World as SimWorld};
use bevy::math::{DMat3, DQuat, DVec3};
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::dynamics::{JointAxis, RigidBodyHandle, RigidBodySet};
use std::collections::HashMap;
use std::time::Duration;

/// A scenario running in the app: what [`add_scenario`] spawned, and the
/// probe rows sampled after every fixed step.
#[derive(Resource, Debug)]
pub struct ScenarioRun {
    /// The scenario.
    pub scenario: Scenario,
    /// Body name → its entity.
    pub bodies: HashMap<String, Entity>,
    /// Joint name → the entity that holds its `ImpulseJoint` (its body2).
    pub joints: HashMap<String, Entity>,
    /// Cable name → its entity, in file order.
    pub cables: Vec<(String, Entity)>,
    /// Sub-steps per frame (`[simulation] substeps`): the app's fixed step
    /// is `dt / substeps`, and a row is sampled every `substeps` fixed steps.
    pub substeps: u32,
    /// Sub-steps run in the current frame.
    pub substep: u32,
    /// Frames run.
    pub steps: u64,
    /// Simulation time after the last step, s (`steps · dt`, as `cablesim`).
    pub time: f64,
    /// (time s, every probe column in file order) after every fixed step,
    /// the columns of `cablesim`'s `results.csv`.
    pub rows: Vec<(f64, Vec<f64>)>,
    /// The first failure: (cable or body entity, time s, message).
    /// Sampling stops.
    pub failed: Option<(Entity, f64, String)>,
    /// The joints rapier keeps, as cablesim records them (unwrapped angles),
    /// once bevy_rapier has created them.
    rapier_joints: Option<Vec<RapierJoint>>,
    /// The joints that are rails of trolleys the cables carry.
    rails: Vec<String>,
    /// The `[[controller]]`s (each drives a rail).
    controllers: Vec<ControllerRun>,
}

impl ScenarioRun {
    /// The sub-step `h = dt / substeps`, s: the app's fixed step.
    fn substep_length(&self) -> f64 {
        self.scenario.simulation.dt / self.substeps as f64
    }

    /// Time at the start of the current sub-step, s (cablesim's
    /// `t0 + k h`).
    fn substep_time(&self) -> f64 {
        self.steps as f64 * self.scenario.simulation.dt + self.substep as f64 * self.substep_length()
    }
}

/// Once, after bevy_rapier has created the bodies and joints and before
/// the cables are built: what cablesim's rapier world sets that bevy_rapier
/// has no component for (gyroscopic torques on dynamic bodies), and the
/// records of the joints.
fn prepare(mut run: ResMut<ScenarioRun>, mut ctx: WriteRapierContext, handles: Query<&RapierRigidBodyHandle>, joint_handles: Query<&RapierImpulseJointHandle>) {
    if run.rapier_joints.is_some() {
        return;
    }
    let Ok(mut ctx) = ctx.single_mut() else {
        return;
    };
    let bodies = &mut ctx.rigidbody_set.bodies;
    let handle = |name: &str| run.bodies.get(name).and_then(|e| handles.get(*e).ok()).map(|h| h.0);
    for b in run.scenario.bodies.iter().filter(|b| b.kind == BodyKind::Dynamic) {
        if let Some(rb) = handle(&b.name).and_then(|h| bodies.get_mut(h)) {
            rb.enable_gyroscopic_forces(true);
        }
    }
    let mut records = Vec::new();
    for j in &run.scenario.joints {
        let (Some(h1), Some(h2), Some(jh)) = (handle(&j.body1), handle(&j.body2), run.joints.get(&j.name).and_then(|e| joint_handles.get(*e).ok())) else {
            continue;
        };
        let (r1, r2) = (pose_of(bodies, h1).1, pose_of(bodies, h2).1);
        let mut record = RapierJoint::new(j, jh.0, [h1, h2], r1, r2);
        if run.rails.contains(&j.name) {
            // Its drive acts in the chain (`drive_rails`), not in rapier.
            record.drive = None;
        }
        records.push(record);
    }
    run.rapier_joints = Some(records);
}

/// After rapier's step, as cablesim does: a body whose state is no longer
/// finite fails the run; revolute angles are unwrapped.
fn after_rapier_step(mut run: ResMut<ScenarioRun>, ctx: ReadRapierContext, handles: Query<&RapierRigidBodyHandle>) {
    let Ok(ctx) = ctx.single() else {
        return;
    };
    let bodies = &ctx.rigidbody_set.bodies;
    if run.failed.is_none() {
        let t = run.substep_time();
        for b in &run.scenario.bodies {
            let Some((e, rb)) = run.bodies.get(&b.name).and_then(|e| Some((*e, bodies.get(handles.get(*e).ok()?.0)?))) else { continue };
            let p = rb.position();
            let finite = p.translation.is_finite() && p.rotation.is_finite() && rb.linvel().is_finite() && rb.angvel().is_finite();
            if !finite || !rb.is_enabled() {
                let message = SimError::BodyDiverged { body: b.name.clone(), time: t }.to_string();
                run.failed = Some((e, t, message));
                break;
            }
        }
    }
    let iterations = ctx.simulation.integration_parameters.num_solver_iterations.max(1) as f64;
    let h_sub = ctx.simulation.integration_parameters.dt as f64 / iterations;
    if let Some(joints) = run.rapier_joints.as_mut() {
        for j in joints {
            j.after_step(bodies, &ctx.joints.impulse_joints, h_sub);
        }
    }
}

/// Spawns `scenario` into `app` (which must have bevy_rapier's plugin in
/// the fixed schedule and [`CablePlugin`](super::CablePlugin)): sets the
/// fixed step to the scenario's `dt` (`Time<Fixed>`, rapier's
/// `TimestepMode::Fixed`, the cables' exact step), rapier's gravity and
/// the cables', spawns one entity per body and per cable, and inserts
/// [`ScenarioRun`]. Errors: everything `cablesim` refuses, with its
/// message, and what is not spawned yet (module docs).
///
/// Call it once per app; [`respawn_scenario`] replaces the scenario later
/// (a viewer's reset).
pub fn add_scenario(app: &mut App, scenario: Scenario) -> Result<(), SimError> {
    let gravity = scenario.simulation.gravity;
    let checked = check_scenario(&scenario)?;
    spawn_scenario(app.world_mut(), scenario, checked);
    // Before the first frame rapier's configuration entity does not exist
    // yet: its gravity is set at start-up.
    app.add_systems(Startup, move |mut config: Query<&mut RapierConfiguration>| {
        for mut c in &mut config {
            c.gravity = gravity.as_vec3();
        }
    });
    app.add_systems(
        FixedUpdate,
        (
            prepare.after(PhysicsSet::SyncBackend).before(CableSystems::Init),
            drive_rails.after(CableSystems::Init).before(CableSystems::Step),
            (move_kinematic, drive_rapier_joints).chain().after(CableSystems::Step).before(PhysicsSet::StepSimulation),
            after_rapier_step.after(PhysicsSet::StepSimulation).before(CableSystems::WriteBodies),
            sample.in_set(CableSystems::Readout),
        ),
    );
    Ok(())
}

/// Replaces the running scenario (of an app set up by [`add_scenario`]) by
/// `scenario`, from its start: checks it as [`add_scenario`] does (an error
/// leaves the running scenario as it is), despawns the entities of the
/// running one (its bodies, joints and cables), spawns the new one and
/// sets the fixed step and gravity again. Run it from an exclusive system
/// or with `World::run_system_cached_with`-style access to the world,
/// between frames (a viewer's reset). [`ScenarioRun`] starts again at
/// t = 0 s.
pub fn respawn_scenario(world: &mut World, scenario: Scenario) -> Result<(), SimError> {
    let checked = check_scenario(&scenario)?;
    if let Some(old) = world.remove_resource::<ScenarioRun>() {
        let cables = old.cables.iter().map(|(_, e)| *e);
        // Cables first, then the bodies they hang from.
        for e in cables.chain(old.bodies.values().copied()) {
            if let Ok(e) = world.get_entity_mut(e) {
                e.despawn();
            }
        }
    }
    let gravity = scenario.simulation.gravity.as_vec3();
    spawn_scenario(world, scenario, checked);
    let mut config = world.query::<&mut RapierConfiguration>();
    for mut c in config.iter_mut(world) {
        c.gravity = gravity;
    }
    Ok(())
}

/// What [`add_scenario`] refuses beyond `cablesim`'s checks; returns the
/// rails (the joints of trolleys the cables carry) and the cables'
/// integrator.
fn check_scenario(scenario: &Scenario) -> Result<(Vec<String>, Scheme), SimError> {
    let file = scenario.file.display().to_string();
    let unsupported = |location: Location, what: String| SimError::Unsupported { file: file.clone(), location, what };
    // bevy_rapier holds a joint on the entity of its body2 (one per entity).
    for (k, j) in scenario.joints.iter().enumerate() {
        if let Some(other) = scenario.joints[..k].iter().find(|o| o.body2 == j.body2) {
            return Err(unsupported(j.location, format!("joint `{}` in a Bevy app: body `{}` is body2 of joint `{}` too", j.name, j.body2, other.name)));
        }
    }
    // Everything cablesim refuses, with its message.
    let rails: Vec<String> = SimWorld::new(scenario.clone())?.rails().into_iter().map(String::from).collect();
    // A force table on a trolley's rail acts in the chain as a joint force
    // in cablesim; the plugin drives a rail only through the joint's motor.
    if let Some(j) = scenario.joints.iter().find(|j| rails.contains(&j.name) && matches!(j.drive, Some(Drive::Force { .. }))) {
        return Err(unsupported(
            j.location,
            format!("the `force` drive of joint `{}`, a trolley's rail, in a Bevy app (cablesim runs it; a `velocity` drive runs in both)", j.name),
        ));
    }
    let ic = &scenario.simulation.integrator;
    let params = SchemeParams { beta: ic.beta, gamma: ic.gamma, theta: ic.theta, alpha: ic.alpha, rho_inf: ic.rho_inf, w: ic.w };
    let scheme = Scheme::from_name(&ic.name, &params).map_err(|e| SimError::Integrator(e.to_string(), file.clone()))?;
    Ok((rails, scheme))
}

/// Spawns a checked scenario's entities ([`check_scenario`]), sets the
/// step and inserts [`ScenarioRun`] (the systems are [`add_scenario`]'s).
fn spawn_scenario(world: &mut World, scenario: Scenario, (rails, scheme): (Vec<String>, Scheme)) {
    let sim = &scenario.simulation;
    // The app's fixed step is the scenario's sub-step: cables and rapier
    // step together `substeps` times per frame, as in cablesim.
    let substeps = sim.substeps.unwrap_or(1).max(1);
    let (dt, gravity) = (sim.dt, sim.gravity);
    let h = dt / substeps as f64;
    world.insert_resource(Time::<Fixed>::from_duration(Duration::from_secs_f64(h)));
    world.insert_resource(TimestepMode::Fixed { dt: h as f32, substeps: 1 });
    {
        let mut settings = world.get_resource_or_insert_with(|| CableSettings { substeps: 1, parallel: true, step: None, gravity: None });
        settings.substeps = 1;
        settings.step = Some(h);
        settings.gravity = Some(gravity);
    }
    let mut bodies = HashMap::new();
    // The ground (`world` in joints), as cablesim's: a fixed body without
    // collider at the origin, created first.
    if scenario.joints.iter().any(|j| j.body1 == "world" || j.body2 == "world") {
        bodies.insert("world".to_string(), world.spawn((Name::new("world"), RigidBody::Fixed, Transform::IDENTITY)).id());
    }
    for b in &scenario.bodies {
        let body = match b.kind {
            BodyKind::Dynamic => RigidBody::Dynamic,
            BodyKind::Fixed => RigidBody::Fixed,
            BodyKind::Kinematic => RigidBody::KinematicPositionBased,
        };
        let collider = Collider::from(shared_shape(&b.shape));
        let mass = b.mass.unwrap_or(0.0);
        let exact = BodyExact {
            mass,
            inertia: shape_inertia(&b.shape, mass),
            position: b.position_at(0.0),
            rotation: b.rotation_at(0.0),
            linear_velocity: b.linear_velocity,
            angular_velocity: b.angular_velocity,
            motion: (b.kind != BodyKind::Dynamic).then(|| body_motion(b, h)),
        };
        let mut e = world.spawn((
            Name::new(b.name.clone()),
            body,
            Transform::from_translation(b.position_at(0.0).as_vec3()).with_rotation(b.rotation_at(0.0).as_quat()),
            collider,
            Friction::coefficient(b.friction as f32),
            Restitution::coefficient(b.restitution as f32),
            groups(b.collision_groups),
            Velocity { linear: b.linear_velocity.as_vec3(), angular: b.angular_velocity.as_vec3() },
            Sleeping::disabled(),
            exact,
        ));
        if b.kind == BodyKind::Dynamic {
            e.insert(ColliderMassProperties::Mass(mass as f32));
        }
        bodies.insert(b.name.clone(), e.id());
    }
    // Joints, on body2's entity, built as cablesim builds them.
    let mut joints = HashMap::new();
    for j in &scenario.joints {
        let rotation = |name: &str| scenario.body(name).map_or(DQuat::IDENTITY, |b| b.rotation_at(0.0).as_quat().as_dquat().normalize());
        let data = joint_data(j, rotation(&j.body1), rotation(&j.body2), dt);
        let (parent, entity) = (bodies[&j.body1], bodies[&j.body2]);
        world.entity_mut(entity).insert(ImpulseJoint::new(parent, TypedJoint::GenericJoint(GenericJoint { raw: data })));
        joints.insert(j.name.clone(), entity);
    }
    let mut cables = Vec::new();
    for c in &scenario.cables {
        let section = RopeSection { linear_density: c.linear_density, ea: c.ea, ei: c.ei, ei2: c.ei2, gj: c.gj, min_breaking_load: 0.0 };
        let anchor = |end: &CableEnd| match end {
            CableEnd::Free => (CableAnchor::Free, None),
            CableEnd::World { point, clamp } => (CableAnchor::World { point: point.as_vec3(), clamp: *clamp }, Some(*point)),
            CableEnd::Body { body, anchor, clamp } => (CableAnchor::Body { entity: bodies[body], anchor: anchor.as_vec3(), clamp: *clamp }, Some(*anchor)),
        };
        let ((start, sp), (end, ep)) = (anchor(&c.start), anchor(&c.end));
        let mut d = CableDescriptor::from_section(c.length, c.segments as usize, RopeMaterial::custom(section, c.diameter), start, end);
        d.shear_stiffness = c.shear_stiffness;
        d.damping = c.damping;
        (d.linear_damping, d.angular_damping) = (c.linear_damping, c.angular_damping);
        d.end_stiffness = c.end_stiffness;
        d.tension_only = c.tension_only;
        d.contacts = c.contacts;
        d.friction = c.friction;
        d.collision_groups = groups(c.collision_groups);
        d.scheme = scheme.clone();
        d.stress_free = c.stress_free;
        d.static_start = sim.statics.then_some(sim.static_load_steps);
        d.loads = c.loads.iter().map(|l| CablePointLoad { s: l.s, force: l.force, moment: l.moment }).collect();
        let exact = CableExact { path: Some(c.path.clone()), start: sp, end: ep };
        let e = world.spawn((Name::new(c.name.clone()), d, exact)).id();
        cables.push((c.name.clone(), e));
    }
    // `check_scenario` built them already (in `cablesim`'s runner): none fails here.
    let controllers = scenario.controllers.iter().filter_map(|c| ControllerRun::new(c).ok()).collect();
    world.insert_resource(ScenarioRun {
        scenario,
        bodies,
        joints,
        cables,
        substeps,
        substep: 0,
        steps: 0,
        time: 0.0,
        rows: Vec::new(),
        failed: None,
        rapier_joints: None,
        rails,
        controllers,
    });
}

/// Before rapier's step, as `cablesim` does: kinematic bodies with a
/// `motion` go to its pose at the end of the step.
fn move_kinematic(run: Res<ScenarioRun>, mut ctx: WriteRapierContext, handles: Query<&RapierRigidBodyHandle>) {
    let Ok(mut ctx) = ctx.single_mut() else {
        return;
    };
    let h = run.substep_length();
    let t = run.substep_time();
    for b in &run.scenario.bodies {
        let (Some(m), Some(handle)) = (&b.motion, run.bodies.get(&b.name).and_then(|e| handles.get(*e).ok())) else {
            continue;
        };
        if let Some(rb) = ctx.rigidbody_set.bodies.get_mut(handle.0) {
            rb.set_next_kinematic_position(motion_pose(m, b.position, b.rotation, t + h));
        }
    }
}

/// Before the cables' step: the velocity drive of a trolley's rail becomes
/// the rail joint's motor, which the plugin reads (the same motor `cablesim`
/// gives the chain, [`crate::coupling::velocity_drive_motor`]); a
/// `[[controller]]` samples when due (measuring what `cablesim` measures)
/// and its command becomes the motor of its rail instead.
#[allow(clippy::too_many_arguments)]
fn drive_rails(
    mut run: ResMut<ScenarioRun>,
    mut joints: Query<&mut ImpulseJoint>,
    sims: Query<&CableSim>,
    ropes: Query<&CableRopeOf>,
    ctx: ReadRapierContext,
    handles: Query<&RapierRigidBodyHandle>,
    joint_handles: Query<&RapierImpulseJointHandle>,
) {
    let h = run.substep_length();
    let t = run.substep_time();
    if run.controllers.iter().any(|c| c.due(t)) {
        let Ok(ctx) = ctx.single() else {
            return;
        };
        let measured: Vec<Option<TrolleyMeasurement>> = {
            let view = View::new(&run, &sims, &ropes, &ctx.rigidbody_set.bodies, &handles, &joint_handles);
            run.controllers.iter().map(|c| c.due(t).then(|| control::measure(&view, &run.scenario, &c.spec, t))).collect()
        };
        for (c, m) in run.controllers.iter_mut().zip(measured) {
            if let Some(m) = m {
                c.sample(t, || m);
            }
        }
    }
    for c in &run.controllers {
        if let Some(mut joint) = run.joints.get(&c.spec.joint).and_then(|e| joints.get_mut(*e).ok()) {
            c.apply(&mut joint.data.as_mut().raw, h);
        }
    }
    for j in run.scenario.joints.iter().filter(|j| run.rails.contains(&j.name) && !run.controllers.iter().any(|c| c.spec.joint == j.name)) {
        let (Some(Drive::Velocity { velocity, max_force }), Some(mut joint)) = (&j.drive, run.joints.get(&j.name).and_then(|e| joints.get_mut(*e).ok())) else {
            continue;
        };
        set_velocity_drive(&mut joint.data.as_mut().raw, JointAxis::LinX, velocity.value_at(t + h), *max_force, h);
    }
}

/// Before rapier's step, after the kinematic bodies, as `cablesim` does:
/// the drives of the joints rapier keeps.
fn drive_rapier_joints(mut run: ResMut<ScenarioRun>, mut ctx: WriteRapierContext) {
    let Ok(mut ctx) = ctx.single_mut() else {
        return;
    };
    let h = run.substep_length();
    let t = run.substep_time();
    let (bodies, impulse_joints) = (&mut ctx.rigidbody_set.bodies, &mut ctx.joints.impulse_joints);
    if let Some(joints) = run.rapier_joints.as_mut() {
        drive_joints(joints, bodies, impulse_joints, t, h);
    }
}

/// After every fixed step: the probe row (or the first failure).
fn sample(
    mut run: ResMut<ScenarioRun>,
    sims: Query<&CableSim>,
    ropes: Query<&CableRopeOf>,
    ctx: ReadRapierContext,
    handles: Query<&RapierRigidBodyHandle>,
    joint_handles: Query<&RapierImpulseJointHandle>,
    mut diverged: MessageReader<CableError>,
) {
    if let Some(m) = diverged.read().next() {
        if run.failed.is_none() {
            run.failed = Some((m.entity, m.time, m.message.clone()));
        }
    }
    if run.failed.is_some() {
        return;
    }
    let Ok(ctx) = ctx.single() else {
        return;
    };
    run.substep += 1;
    if run.substep < run.substeps {
        return;
    }
    run.substep = 0;
    run.steps += 1;
    run.time = run.steps as f64 * run.scenario.simulation.dt;
    let view = View::new(&run, &sims, &ropes, &ctx.rigidbody_set.bodies, &handles, &joint_handles);
    let mut row = Vec::new();
    probe::sample(&run.scenario.probes, &view, &mut row);
    let t = run.time;
    run.rows.push((t, row));
}

/// What the probes read in the app: the cables' chains, the bodies they
/// carry, and rapier's bodies.
struct View<'a> {
    run: &'a ScenarioRun,
    /// Cable name → (its chain, rope index).
    ropes: HashMap<&'a str, (&'a Cable, usize)>,
    /// Carried body name → (its chain, its place).
    carried: HashMap<&'a str, (&'a Cable, BodyInChain)>,
    bodies: &'a RigidBodySet,
    handles: HashMap<&'a str, RigidBodyHandle>,
    /// Rail joint name → the chain of the trolley on it.
    rails: HashMap<&'a str, &'a Cable>,
    /// The coupled cables (their chains, and the bodies' contact forces),
    /// in the core's build order (cable entity order).
    coupled: Vec<&'a CoupledCable>,
}

impl<'a> View<'a> {
    fn new(
        run: &'a ScenarioRun,
        sims: &'a Query<&CableSim>,
        ropes: &Query<&CableRopeOf>,
        bodies: &'a RigidBodySet,
        handles: &Query<&RapierRigidBodyHandle>,
        joint_handles: &Query<&RapierImpulseJointHandle>,
    ) -> View<'a> {
        let mut own: Vec<(Entity, &'a CableSim)> = run.cables.iter().filter_map(|(_, e)| sims.get(*e).ok().map(|s| (*e, s))).collect();
        own.sort_by_key(|(e, _)| super::systems::spawn_order(*e));
        let mut by_name = HashMap::new();
        for (name, e) in &run.cables {
            if let Ok(s) = sims.get(*e) {
                by_name.insert(name.as_str(), (&s.coupled.cable, 0));
            } else if let Ok(of) = ropes.get(*e) {
                if let Ok(s) = sims.get(of.cable) {
                    by_name.insert(name.as_str(), (&s.coupled.cable, of.rope));
                }
            }
        }
        let mut carried = HashMap::new();
        let mut body_handles = HashMap::new();
        for (name, e) in &run.bodies {
            let Ok(h) = handles.get(*e) else { continue };
            body_handles.insert(name.as_str(), h.0);
            for (_, s) in &own {
                if let Some(c) = s.coupled.carried.iter().find(|c| c.body == h.0) {
                    carried.insert(name.as_str(), (&s.coupled.cable, c.place));
                }
            }
        }
        let mut rails = HashMap::new();
        for (name, e) in &run.joints {
            let Ok(h) = joint_handles.get(*e) else { continue };
            for (_, s) in &own {
                if matches!(s.coupled.roles[0], Some((_, Role::Trolley { joint, .. })) if joint == h.0) {
                    rails.insert(name.as_str(), &s.coupled.cable);
                }
            }
        }
        let coupled = own.iter().map(|(_, s)| &s.coupled).collect();
        View { run, ropes: by_name, carried, bodies, handles: body_handles, rails, coupled }
    }
}

impl ProbeSource for View<'_> {
    fn chains(&self) -> Vec<&Cable> {
        self.coupled.iter().map(|c| &c.cable).collect()
    }

    fn rapier_energies(&self) -> (f64, f64) {
        let g = self.run.scenario.simulation.gravity;
        let free = self.run.scenario.bodies.iter().filter(|b| b.kind == BodyKind::Dynamic && !self.carried.contains_key(b.name.as_str()));
        let free: Vec<(f64, DMat3, RigidBodyHandle)> = free
            .filter_map(|b| self.handles.get(b.name.as_str()).map(|&h| (b.mass.unwrap_or(0.0), shape_inertia(&b.shape, b.mass.unwrap_or(0.0)), h)))
            .collect();
        free_body_energies(self.bodies, &free, g)
    }

    fn rope(&self, name: &str) -> Option<RopeView<'_>> {
        self.ropes.get(name).and_then(|(c, k)| c.rope(*k))
    }

    fn body_state(&self, name: &str) -> (DVec3, DMat3, DVec3, DVec3) {
        if let Some((c, place)) = self.carried.get(name) {
            return c.model.body_state(place);
        }
        match self.handles.get(name) {
            Some(&h) => {
                let (p, q) = pose_of(self.bodies, h);
                let (v, w) = velocity_of(self.bodies, h);
                (p, DMat3::from_quat(q), v, w)
            }
            None => (DVec3::NAN, DMat3::NAN, DVec3::NAN, DVec3::NAN),
        }
    }

    fn body_contact_force(&self, name: &str) -> DVec3 {
        self.handles.get(name).map_or(DVec3::ZERO, |&h| self.coupled.iter().fold(DVec3::ZERO, |sum, c| sum + c.contact_force_on(h)))
    }

    fn controller(&self, name: &str, quantity: Quantity) -> f64 {
        self.run.controllers.iter().find(|c| c.spec.name == name).map_or(f64::NAN, |c| c.probe(quantity))
    }

    fn joint(&self, name: &str, quantity: Quantity) -> Probe {
        // Probes of other joints are refused by `add_scenario`.
        if let Some(c) = self.rails.get(name) {
            return probe::rail(c, quantity);
        }
        match self.run.rapier_joints.iter().flatten().find(|j| j.name == name) {
            Some(j) => probe::rapier_joint(j, self.bodies, quantity),
            None => Probe::Scalar(f64::NAN),
        }
    }
}

/// A scenario's collision groups as bevy_rapier's component.
fn groups(g: crate::scenario::CollisionGroups) -> CollisionGroups {
    CollisionGroups::new(Group::from_bits_retain(g.memberships), Group::from_bits_retain(g.filter))
}
