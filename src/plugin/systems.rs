//! The cable plugin's systems (see the order table in the module docs):
//! thin adapters that map entities to rapier handles and call the coupling
//! core ([`crate::coupling`]).

use super::components::{CableAnchor, CableDescriptor, CableDiverged, CableRopeOf, CableSim, CableState, CarriedBody};
use super::CableSettings;
use crate::cable::RopeBuilder;
use crate::coupling::{self, rail_drive, Attach, BodyInputs, Built, CableSpec, CoupledCable, CouplingError, Role};
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::dynamics::{JointMotor, RigidBodyHandle};
use glam::DVec3;
use std::collections::HashMap;

/// Cable entities the plugin has not built yet.
type NotBuilt = (Without<CableSim>, Without<CableRopeOf>);

/// Builds cables from new [`CableDescriptor`]s, all new ones of a step
/// together (so a body at the ends of two new cables is solved with both
/// as one island, see the module docs).
#[allow(clippy::too_many_arguments)]
pub(crate) fn init_cables(
    mut commands: Commands,
    new: Query<(Entity, &CableDescriptor), NotBuilt>,
    existing: Query<&CableSim>,
    mut ctx: WriteRapierContext,
    handles: Query<&RapierRigidBodyHandle>,
    config: Query<&RapierConfiguration>,
    mut diverged: MessageWriter<CableDiverged>,
) {
    if new.is_empty() {
        return;
    }
    let Ok(mut ctx) = ctx.single_mut() else {
        return;
    };
    let gravity = config.iter().next().map_or(DVec3::new(0.0, -9.81, 0.0), |c| c.gravity.as_dvec3());
    let mut new: Vec<(Entity, &CableDescriptor)> = new.iter().collect();
    new.sort_by_key(|(e, _)| *e);
    let mut specs = Vec::new();
    let mut owners = Vec::new();
    for (entity, d) in new {
        let attach = |a: &CableAnchor, end: &str| -> Result<(Attach, Option<(Entity, RigidBodyHandle)>), String> {
            Ok(match a {
                CableAnchor::Free => (Attach::Free, None),
                CableAnchor::World { point, clamp } => (Attach::World { point: point.as_dvec3(), clamp: *clamp }, None),
                CableAnchor::Body { entity: be, anchor, clamp } => {
                    let h = handles.get(*be).map_err(|_| format!("{end} body {be} has no rapier rigid body"))?.0;
                    (Attach::Body { body: h, anchor: anchor.as_dvec3(), clamp: *clamp }, Some((*be, h)))
                }
            })
        };
        let ends = attach(&d.start, "start").and_then(|s| Ok((s, attach(&d.end, "end")?)));
        let ((start, sb), (end, eb)) = match ends {
            Ok(x) => x,
            Err(message) => {
                diverged.write(CableDiverged { entity, time: 0.0, message });
                commands.entity(entity).remove::<CableDescriptor>();
                continue;
            }
        };
        let mut rope = RopeBuilder::new(d.length, d.segments, d.section, d.diameter).damping(d.damping).tension_only(d.tension_only).gravity(gravity);
        if let Some(ga) = d.shear_stiffness {
            rope = rope.shear_stiffness(ga);
        }
        let path = d.path.as_ref().map(|p| p.iter().map(|v| v.as_dvec3()).collect());
        specs.push(CableSpec { rope, path, start, end, scheme: d.scheme.clone(), exact: [None, None] });
        owners.push((entity, [sb, eb]));
    }
    let others: Vec<&CoupledCable> = existing.iter().map(|s| &s.coupled).collect();
    let built = coupling::build_cables(&specs, &others, &mut ctx.rigidbody_set.bodies, &mut ctx.joints.impulse_joints, &HashMap::new());
    let bodies = &ctx.rigidbody_set.bodies;
    // Entities of the bodies and cables of the batch, for messages.
    let entity_of: HashMap<RigidBodyHandle, Entity> = owners.iter().flat_map(|(_, ends)| ends.iter().flatten().map(|(e, h)| (*h, *e))).collect();
    let batch: Vec<Entity> = owners.iter().map(|(e, _)| *e).collect();
    let message = |e: &CouplingError| refusal(e, &entity_of, &batch);
    let mut sims: Vec<Option<CableSim>> = Vec::new();
    let mut ropes = Vec::new();
    for ((entity, ends), r) in owners.iter().copied().zip(built) {
        sims.push(None);
        let mut fail = |message: String| {
            diverged.write(CableDiverged { entity, time: 0.0, message });
            commands.entity(entity).remove::<CableDescriptor>();
        };
        let mut cc = match r {
            Ok(Built::Cable(cc)) => *cc,
            Ok(Built::Part { onto, part }) => {
                ropes.push((entity, onto, part));
                continue;
            }
            Err(e) => {
                fail(message(&e));
                continue;
            }
        };
        // The carried bodies' rapier velocities become the chain's initial rates.
        let velocity = |h: RigidBodyHandle| bodies.get(h).map_or((DVec3::ZERO, DVec3::ZERO), |rb| (rb.linvel().as_dvec3(), rb.angvel().as_dvec3()));
        if let Err((_, e)) = cc.start_velocities(&velocity) {
            fail(e.to_string());
            continue;
        }
        let mut carried = Vec::new();
        let mut rail = None;
        for (k, (be, h)) in ends.iter().enumerate().filter_map(|(k, e)| e.map(|e| (k, e))) {
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
                    Role::Explicit if k == 0 => CarriedBody::Explicit,
                    Role::Explicit => CarriedBody::ExplicitEnd,
                },
            ));
        }
        let last = sims.len() - 1;
        sims[last] = Some(CableSim { coupled: cc, bodies: carried, rail });
    }
    // A rope grafted onto another entity's chain: that entity must exist
    // (it fails with its ropes: initial velocities).
    for (entity, onto, part) in ropes {
        if sims[onto].is_none() {
            diverged.write(CableDiverged { entity, time: 0.0, message: message(&CouplingError::Island { cable: onto }) });
            commands.entity(entity).remove::<CableDescriptor>();
            continue;
        }
        commands.entity(entity).insert((CableRopeOf { cable: batch[onto], rope: part }, CableState::default()));
    }
    for (entity, sim) in batch.into_iter().zip(sims) {
        if let Some(sim) = sim {
            commands.entity(entity).insert((sim, CableState::default()));
        }
    }
}

/// Why a cable of the batch `batch` was not built, with entities for the
/// core's rapier handles and batch indices.
fn refusal(e: &CouplingError, entity_of: &HashMap<RigidBodyHandle, Entity>, batch: &[Entity]) -> String {
    let body = |h: RigidBodyHandle| format!("body {}", entity_of.get(&h).map_or_else(|| format!("{h:?}"), |e| e.to_string()));
    e.describe(&body, &|k| format!("cable {}", batch[k]))
}

/// The rapier motor of a trolley's prismatic joint, as a spring and damper
/// on the chain's root sub-joint: `F = k (x_target − x) + c (v_target − v)`
/// (with `AccelerationBased` motors, `k` and `c` times the trolley's mass,
/// as rapier scales them by the body's mass), implicit in the cable solve;
/// when the force this asks for now exceeds `max_force`, an explicit force
/// of `max_force` toward the target instead. `offset` is the rapier joint
/// coordinate at chain coordinate 0. Without a motor the root sub-joint is
/// free.
fn rail_motor(cc: &mut CoupledCable, motor: Option<JointMotor>, offset: f64) {
    let cable = &mut cc.cable;
    let Some(m) = motor.filter(|m| m.stiffness != 0.0 || m.damping != 0.0) else {
        rail_drive(cable, 0.0, 0.0, offset, 0.0, 0.0, f64::INFINITY);
        return;
    };
    let scale = match m.model {
        MotorModel::AccelerationBased => cable.model.chain.joints()[0].link.map_or(0.0, |l| l.mass),
        MotorModel::ForceBased => 1.0,
    };
    let (k, c) = (m.stiffness as f64 * scale, m.damping as f64 * scale);
    rail_drive(cable, k, c, offset, m.target_pos as f64, m.target_vel as f64, m.max_force as f64);
}

/// What the user asks of a carried body through bevy_rapier's components.
type InputComponents = (Option<&'static ExternalForce>, Option<&'static GravityScale>, Option<&'static Damping>);

/// Advances every cable by the fixed step (the core's phase 1: before
/// rapier's step).
#[allow(clippy::too_many_arguments)]
pub(crate) fn step_cables(
    mut cables: Query<(Entity, &mut CableSim)>,
    mut ctx: WriteRapierContext,
    inputs: Query<InputComponents>,
    handles: Query<&RapierRigidBodyHandle>,
    joints: Query<&ImpulseJoint>,
    ropes: Query<(Entity, &CableRopeOf)>,
    settings: Res<CableSettings>,
    time: Res<Time>,
    mut diverged: MessageWriter<CableDiverged>,
) {
    let dt = time.delta_secs_f64();
    if dt <= 0.0 {
        return;
    }
    let Ok(mut ctx) = ctx.single_mut() else {
        return;
    };
    let mut list: Vec<(Entity, Mut<CableSim>)> = cables.iter_mut().collect();
    list.sort_by_key(|(e, _)| *e);
    let mut given: HashMap<RigidBodyHandle, BodyInputs> = HashMap::new();
    for (_, sim) in &mut list {
        let sim = &mut **sim;
        for (be, _) in sim.bodies.iter().filter(|(_, c)| matches!(c, CarriedBody::Lumped(_))) {
            let (Ok((force, scale, damping)), Ok(h)) = (inputs.get(*be), handles.get(*be)) else {
                continue;
            };
            given.insert(
                h.0,
                BodyInputs {
                    force: force.map_or(DVec3::ZERO, |f| f.force.as_dvec3()),
                    torque: force.map_or(DVec3::ZERO, |f| f.torque.as_dvec3()),
                    gravity_scale: scale.map_or(1.0, |s| s.0 as f64),
                    linear_damping: damping.map_or(0.0, |d| d.linear_damping as f64),
                    angular_damping: damping.map_or(0.0, |d| d.angular_damping as f64),
                },
            );
        }
        if let (Some(trolley), Some((_, Role::Trolley { offset, .. }))) = (sim.rail, sim.coupled.roles[0]) {
            let motor = joints.get(trolley).ok().and_then(|j| match &j.data {
                TypedJoint::PrismaticJoint(pj) => pj.motor().copied(),
                _ => None,
            });
            rail_motor(&mut sim.coupled, motor, offset);
        }
    }
    let mut refs: Vec<&mut CoupledCable> = list.iter_mut().map(|(_, s)| &mut s.coupled).collect();
    let failures = coupling::step_cables(&mut refs, &mut ctx.rigidbody_set.bodies, &mut ctx.joints.impulse_joints, dt, settings.substeps, &|h| {
        given.get(&h).copied().unwrap_or_default()
    });
    for (i, t, e) in failures {
        let owner = list[i].0;
        diverged.write(CableDiverged { entity: owner, time: t, message: e.to_string() });
        // The ropes solved in the same chain stop with it.
        for (entity, _) in ropes.iter().filter(|(_, of)| of.cable == owner) {
            diverged.write(CableDiverged { entity, time: t, message: format!("solved as one island with cable {owner}, which failed: {e}") });
        }
    }
}

/// The core's phase 2, after rapier's step and before its writeback: the
/// contact impulses rapier gave the carried bodies are kept for the next
/// step, and the bodies are put on the cable's pose and velocity.
pub(crate) fn write_bodies(mut cables: Query<(Entity, &mut CableSim)>, mut ctx: WriteRapierContext) {
    let Ok(mut ctx) = ctx.single_mut() else {
        return;
    };
    let mut list: Vec<(Entity, Mut<CableSim>)> = cables.iter_mut().collect();
    list.sort_by_key(|(e, _)| *e);
    let mut refs: Vec<&mut CoupledCable> = list.iter_mut().map(|(_, s)| &mut s.coupled).collect();
    coupling::after_rapier(&mut refs, &mut ctx.rigidbody_set.bodies, &ctx.simulation.narrow_phase);
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
