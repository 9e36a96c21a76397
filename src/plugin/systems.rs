//! The cable plugin's systems (see the order table in the module docs).

use super::components::{CableAnchor, CableDescriptor, CableDiverged, CableSim, CableState, CarriedBody};
use super::CableSettings;
use crate::cable::coupling::{follow, rail_drive, reaction, BodySample};
use crate::cable::{BaseMotion, BaseState, BodyInChain, Cable, LinkLoad, LinkVelocity, LumpedBody, RopeBuilder, RopeEnd, RopeStart};
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::dynamics::{JointMotor, RigidBody as RapierBody, RigidBodyType};
use glam::{DMat3, DVec3};
use std::sync::{Arc, Mutex};

type Target = Arc<dyn Fn(f64) -> (DVec3, DVec3) + Send + Sync>;

fn pose_of(rb: &RapierBody) -> (DVec3, DMat3) {
    let p = rb.position();
    (p.translation.as_dvec3(), DMat3::from_quat(p.rotation.as_dquat()))
}

fn lumped_of(rb: &RapierBody) -> LumpedBody {
    let (position, rotation) = pose_of(rb);
    let mp = &rb.mass_properties().local_mprops;
    let inertia = mp.reconstruct_inertia_matrix();
    LumpedBody {
        mass: mp.mass() as f64,
        inertia: DMat3::from_cols(inertia.x_axis.as_dvec3(), inertia.y_axis.as_dvec3(), inertia.z_axis.as_dvec3()),
        position,
        rotation,
        com: mp.local_com.as_dvec3(),
    }
}

fn sample_body(rb: &RapierBody, anchor: Vec3) -> BodySample {
    let (p, r) = pose_of(rb);
    let a = r * anchor.as_dvec3();
    let w = rb.angvel().as_dvec3();
    let com = rb.center_of_mass().as_dvec3();
    let v = rb.linvel().as_dvec3() + w.cross(p + a - com);
    BodySample { t0: 0.0, position: p + a, rotation: r, velocity: v, angular_velocity: w, acceleration: DVec3::ZERO, com }
}

/// Builds cables from new [`CableDescriptor`]s.
#[allow(clippy::too_many_arguments)]
pub(crate) fn init_cables(
    mut commands: Commands,
    new: Query<(Entity, &CableDescriptor), Without<CableSim>>,
    mut ctx: WriteRapierContext,
    handles: Query<&RapierRigidBodyHandle>,
    joints: Query<&ImpulseJoint>,
    config: Query<&RapierConfiguration>,
    mut kinds: Query<&mut RigidBody>,
    mut diverged: MessageWriter<CableDiverged>,
) {
    if new.is_empty() {
        return;
    }
    let Ok(mut ctx) = ctx.single_mut() else { return };
    let gravity = config.iter().next().map_or(DVec3::new(0.0, -9.81, 0.0), |c| c.gravity.as_dvec3());
    for (entity, d) in &new {
        let mut fail = |msg: String| {
            diverged.write(CableDiverged { entity, time: 0.0, message: msg });
        };
        let bodies_set = &mut ctx.rigidbody_set.bodies;
        let body = |e: Entity| handles.get(e).ok().and_then(|h| bodies_set.get(h.0));
        let mut carried = Vec::new();
        let mut samples = Vec::new();
        let mut rail = None;
        // Start.
        let (start, start_point) = match &d.start {
            CableAnchor::Free => {
                let Some(p0) = d.path.as_ref().and_then(|p| p.first()) else {
                    fail("a free cable start needs a path".into());
                    commands.entity(entity).remove::<CableDescriptor>();
                    continue;
                };
                (RopeStart::Free, p0.as_dvec3())
            }
            CableAnchor::World { point, clamp } => {
                let b = BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, point.as_dvec3()));
                (if *clamp { RopeStart::Clamped(b) } else { RopeStart::Pinned(b) }, point.as_dvec3())
            }
            CableAnchor::Body { entity: be, anchor, clamp } => {
                let Some(rb) = body(*be) else {
                    fail(format!("start body {be} has no rapier rigid body"));
                    commands.entity(entity).remove::<CableDescriptor>();
                    continue;
                };
                let sample = sample_body(rb, *anchor);
                // A prismatic joint to a fixed body: the rail axis (world)
                // and the rapier joint coordinate now.
                let slide = joints.get(*be).ok().and_then(|j| match &j.data {
                    TypedJoint::PrismaticJoint(pj) => {
                        let parent = body(j.parent)?;
                        let ((pp, rp), (pc, rc)) = (pose_of(parent), pose_of(rb));
                        let axis = rp * pj.local_axis1().as_dvec3();
                        let gap = pc + rc * pj.local_anchor2().as_dvec3() - pp - rp * pj.local_anchor1().as_dvec3();
                        (parent.body_type() == RigidBodyType::Fixed).then(|| (axis, gap.dot(axis.normalize())))
                    }
                    _ => None,
                });
                match (rb.body_type(), slide) {
                    (RigidBodyType::Dynamic, Some((axis, offset))) => {
                        rail = Some((*be, offset));
                        carried.push((*be, CarriedBody::Lumped(BodyInChain { link: 0, rotation: DMat3::IDENTITY, origin: DVec3::ZERO })));
                        (RopeStart::SlidingBody { body: lumped_of(rb), axis: axis.normalize(), anchor: anchor.as_dvec3(), clamp: *clamp }, sample.position)
                    }
                    (kind, _) => {
                        let shared = Arc::new(Mutex::new(sample));
                        carried.push((*be, if kind == RigidBodyType::Dynamic { CarriedBody::Explicit } else { CarriedBody::Base }));
                        samples.push((*be, *anchor, shared.clone()));
                        let b = follow(shared);
                        (if *clamp { RopeStart::Clamped(b) } else { RopeStart::Pinned(b) }, sample.position)
                    }
                }
            }
        };
        // End.
        let mut end_point = None;
        let end = match &d.end {
            CableAnchor::Free => RopeEnd::Free,
            CableAnchor::World { point, clamp } => {
                let p = point.as_dvec3();
                end_point = Some(p);
                let t: Target = Arc::new(move |_| (p, DVec3::ZERO));
                if *clamp { RopeEnd::Clamped(t) } else { RopeEnd::Pinned(t) }
            }
            CableAnchor::Body { entity: be, anchor, clamp } => {
                let Some(rb) = body(*be) else {
                    fail(format!("end body {be} has no rapier rigid body"));
                    commands.entity(entity).remove::<CableDescriptor>();
                    continue;
                };
                let sample = sample_body(rb, *anchor);
                end_point = Some(sample.position);
                if rb.body_type() == RigidBodyType::Dynamic && joints.get(*be).is_err() {
                    carried.push((*be, CarriedBody::Lumped(BodyInChain { link: usize::MAX, rotation: DMat3::IDENTITY, origin: DVec3::ZERO })));
                    RopeEnd::Body { body: lumped_of(rb), anchor: anchor.as_dvec3(), clamp: *clamp }
                } else {
                    // A fixed, kinematic or jointed dynamic body: the end's
                    // implicit anchor spring follows the body's point.
                    let shared = Arc::new(Mutex::new(sample));
                    samples.push((*be, *anchor, shared.clone()));
                    if rb.body_type() == RigidBodyType::Dynamic {
                        carried.push((*be, CarriedBody::ExplicitEnd));
                    } else {
                        carried.push((*be, CarriedBody::Base));
                    }
                    let BaseMotion::Prescribed(f) = follow(shared) else { unreachable!("follow() is prescribed") };
                    let t: Target = Arc::new(move |t| {
                        let s = f(t);
                        (s.position, s.velocity)
                    });
                    if *clamp { RopeEnd::Clamped(t) } else { RopeEnd::Pinned(t) }
                }
            }
        };
        let path = match (&d.path, end_point) {
            (Some(p), _) => p.iter().map(|v| v.as_dvec3()).collect(),
            (None, Some(e)) => vec![start_point, e],
            (None, None) => vec![start_point, start_point - DVec3::Y * d.length],
        };
        let mut builder = RopeBuilder::new(d.length, d.segments, d.section, d.diameter)
            .damping(d.damping)
            .gravity(gravity)
            .path(path)
            .start(start)
            .end(end);
        if let Some(ga) = d.shear_stiffness {
            builder = builder.shear_stiffness(ga);
        }
        let model = match builder.build() {
            Ok(m) => m,
            Err(e) => {
                fail(e.to_string());
                commands.entity(entity).remove::<CableDescriptor>();
                continue;
            }
        };
        for (_, c) in carried.iter_mut() {
            if let CarriedBody::Lumped(b) = c {
                if b.link == usize::MAX {
                    *b = model.layout.end_body.expect("end body built");
                }
            }
        }
        let mut cable = match Cable::new(model, d.scheme.clone()) {
            Ok(c) => c,
            Err(e) => {
                fail(e.to_string());
                commands.entity(entity).remove::<CableDescriptor>();
                continue;
            }
        };
        // The carried bodies' rapier velocities (at their centres of mass)
        // become the chain's initial rates.
        let targets: Vec<LinkVelocity> = carried
            .iter()
            .filter_map(|(be, c)| match c {
                CarriedBody::Lumped(b) => body(*be).map(|rb| LinkVelocity {
                    link: b.link,
                    point: b.origin + b.rotation * rb.mass_properties().local_mprops.local_com.as_dvec3(),
                    linear: rb.linvel().as_dvec3(),
                    angular: rb.angvel().as_dvec3(),
                }),
                _ => None,
            })
            .collect();
        if targets.iter().any(|t| t.linear != DVec3::ZERO || t.angular != DVec3::ZERO) {
            if let Err(e) = cable.set_link_velocities(&targets) {
                fail(e.to_string());
                commands.entity(entity).remove::<CableDescriptor>();
                continue;
            }
        }
        // Bodies the cable carries become kinematic in rapier: the cable moves them.
        for (be, c) in &carried {
            if matches!(c, CarriedBody::Lumped(_)) {
                if let Ok(h) = handles.get(*be) {
                    if let Some(rb) = ctx.rigidbody_set.bodies.get_mut(h.0) {
                        rb.set_body_type(RigidBodyType::KinematicPositionBased, true);
                    }
                }
                if let Ok(mut k) = kinds.get_mut(*be) {
                    *k = RigidBody::KinematicPositionBased;
                }
            }
        }
        commands.entity(entity).insert((CableSim { cable, bodies: carried, samples, rail, failed: false }, CableState::default()));
    }
}

/// Samples the bodies that move cable bases.
pub(crate) fn read_bodies(mut cables: Query<&mut CableSim>, ctx: ReadRapierContext, handles: Query<&RapierRigidBodyHandle>, time: Res<Time>) {
    let Ok(ctx) = ctx.single() else { return };
    let dt = time.delta_secs_f64().max(1e-9);
    for sim in &mut cables {
        for (be, anchor, shared) in &sim.samples {
            let Some(rb) = handles.get(*be).ok().and_then(|h| ctx.rigidbody_set.bodies.get(h.0)) else { continue };
            let mut s = sample_body(rb, *anchor);
            s.t0 = sim.cable.time();
            // A dynamic body's velocity from its pose change (see
            // BodySample::update); kinematic ones report theirs exactly.
            let since = (sim.cable.steps > 0).then_some(dt);
            shared.lock().unwrap_or_else(|e| e.into_inner()).update(s, since, rb.body_type() == RigidBodyType::Dynamic);
        }
    }
}

/// The rapier motor of an absorbed trolley's prismatic joint, as a spring
/// and damper on the chain's root sub-joint: `F = k (x_target − x) +
/// c (v_target − v)` (with `AccelerationBased` motors, `k` and `c` times the
/// trolley's mass, as rapier scales them by the body's mass), implicit in
/// the cable solve; when the force this asks for now exceeds `max_force`,
/// an explicit force of `max_force` toward the target instead. `offset` is
/// the rapier joint coordinate at chain coordinate 0. Without a motor the
/// root sub-joint is free.
fn rail_motor(cable: &mut Cable, motor: Option<JointMotor>, offset: f64) {
    let Some(m) = motor.filter(|m| m.stiffness != 0.0 || m.damping != 0.0) else {
        rail_drive(cable, 0.0, 0.0, offset, 0.0, 0.0, f64::INFINITY);
        return;
    };
    let scale = match m.model {
        MotorModel::AccelerationBased => cable.model.chain.joints[0].link.map_or(0.0, |l| l.mass),
        MotorModel::ForceBased => 1.0,
    };
    let (k, c) = (m.stiffness as f64 * scale, m.damping as f64 * scale);
    rail_drive(cable, k, c, offset, m.target_pos as f64, m.target_vel as f64, m.max_force as f64);
}

/// Advances every cable by the fixed step.
pub(crate) fn step_cables(
    mut cables: Query<(Entity, &mut CableSim)>,
    forces: Query<&ExternalForce>,
    joints: Query<&ImpulseJoint>,
    settings: Res<CableSettings>,
    time: Res<Time>,
    mut diverged: MessageWriter<CableDiverged>,
) {
    let dt = time.delta_secs_f64();
    if dt <= 0.0 {
        return;
    }
    let n = settings.substeps.max(1);
    for (entity, mut sim) in &mut cables {
        if sim.failed {
            continue;
        }
        let sim = &mut *sim;
        // User forces on carried bodies act inside the cable solve.
        sim.cable.model.chain.loads.clear();
        for (be, c) in &sim.bodies {
            if let (CarriedBody::Lumped(b), Ok(f)) = (c, forces.get(*be)) {
                let lm = sim.cable.model.chain.joints[b.link].link.map_or(DVec3::ZERO, |m| m.com);
                sim.cable.model.chain.loads.push(LinkLoad { link: b.link, force: f.force.as_dvec3(), local_point: lm, moment: f.torque.as_dvec3() });
            }
        }
        if let Some((trolley, offset)) = sim.rail {
            let motor = joints.get(trolley).ok().and_then(|j| match &j.data {
                TypedJoint::PrismaticJoint(pj) => pj.motor().copied(),
                _ => None,
            });
            rail_motor(&mut sim.cable, motor, offset);
        }
        // Before the first step: start from the acceleration these loads and
        // drives give (not the force-free one of the cable's creation).
        if sim.cable.steps == 0 {
            if let Err(e) = sim.cable.recompute_acceleration() {
                sim.failed = true;
                diverged.write(CableDiverged { entity, time: sim.cable.time(), message: e.to_string() });
                continue;
            }
        }
        for _ in 0..n {
            let t = sim.cable.time();
            if let Err(e) = sim.cable.step(dt / n as f64) {
                sim.failed = true;
                let message = e.to_string();
                diverged.write(CableDiverged { entity, time: t, message });
                break;
            }
        }
    }
}

/// Moves carried bodies to the cable's pose and gives explicitly coupled
/// bodies the end force.
pub(crate) fn write_bodies(cables: Query<&CableSim>, mut ctx: WriteRapierContext, handles: Query<&RapierRigidBodyHandle>, time: Res<Time>) {
    let Ok(mut ctx) = ctx.single_mut() else { return };
    let dt = time.delta_secs_f64();
    for sim in &cables {
        for (be, c) in &sim.bodies {
            let Some(rb) = handles.get(*be).ok().and_then(|h| ctx.rigidbody_set.bodies.get_mut(h.0)) else { continue };
            match c {
                CarriedBody::Lumped(b) => {
                    let (p, r, _, _) = sim.cable.model.body_state(b);
                    let q = glam::DQuat::from_mat3(&r).as_quat();
                    rb.set_next_kinematic_position(bevy_rapier3d::rapier::math::Pose::from_parts(p.as_vec3(), q));
                }
                CarriedBody::ExplicitEnd | CarriedBody::Explicit if !sim.failed => {
                    // The chain's base load (start), or minus the end anchor
                    // spring's force at its point (end).
                    let com = rb.center_of_mass().as_dvec3();
                    let (force, moment) = reaction(&sim.cable, *c == CarriedBody::Explicit, com, sim.cable.time());
                    rb.apply_impulse((force * dt).as_vec3(), true);
                    rb.apply_torque_impulse((moment * dt).as_vec3(), true);
                }
                _ => {}
            }
        }
    }
}

/// Refreshes [`CableState`].
pub(crate) fn readout(mut cables: Query<(&CableSim, &mut CableState)>) {
    for (sim, mut st) in &mut cables {
        let c = &sim.cable;
        st.nodes = c.nodes().iter().map(|p| p.as_vec3()).collect();
        st.tensions = (0..c.elements()).map(|i| c.element_forces(i).tension as f32).collect();
        st.stretched_length = c.stretched_length() as f32;
        st.energy = c.energy();
        st.time = c.time();
        st.newton_iterations = c.last_stats.newton_iterations;
    }
}
