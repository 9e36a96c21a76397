//! Probe evaluation shared by the scenario runners: [`World`](super::World)
//! (`cablesim`) and a scenario spawned into a Bevy app with the plugin
//! ([`crate::plugin::scenario`]). Each runner says where a name's state is
//! ([`ProbeSource`]); the values and their columns are computed here once,
//! so the two give the same `results.csv` for the same state.

use super::rapier::RapierJoint;
use crate::cable::chain::IN_CHAIN;
use crate::cable::{Cable, RopeView};
use crate::scenario::{self, Component, JointKind, ProbeTarget, Quantity};
use glam::{DMat3, DQuat, DVec3, EulerRot};

/// One probe's value.
pub(crate) enum Probe {
    /// A scalar column.
    Scalar(f64),
    /// A vector: three columns, or one picked by the probe's component.
    Vector(DVec3),
}

/// Where a scenario runner keeps what the probes read.
pub(crate) trait ProbeSource {
    /// The cables with their own chain, in the order the core built them
    /// (energies are summed in this order).
    fn chains(&self) -> Vec<&Cable>;
    /// Kinetic energy and gravitational energy −m g·x of the dynamic
    /// bodies rapier keeps (not those a cable carries), J.
    fn rapier_energies(&self) -> (f64, f64);
    /// The rope of the scenario cable `name`, in the scenario's direction.
    fn rope(&self, name: &str) -> Option<RopeView<'_>>;
    /// Body `name`: origin (m), orientation, velocity (m/s), angular
    /// velocity (rad/s), world frame.
    fn body_state(&self, name: &str) -> (DVec3, DMat3, DVec3, DVec3);
    /// Body `name`'s contact force: the sum over the cables of
    /// [`CoupledCable::contact_force_on`](crate::coupling::CoupledCable::contact_force_on), N, world.
    fn body_contact_force(&self, name: &str) -> DVec3;
    /// A joint probe's value (see the module docs of `world.rs`).
    fn joint(&self, name: &str, quantity: Quantity) -> Probe;
    /// A `[[controller]]` probe's value ([`super::control::ControllerRun::probe`]).
    fn controller(&self, name: &str, quantity: Quantity) -> f64;
}

/// The value of probe `p`.
pub(crate) fn probe(src: &dyn ProbeSource, p: &scenario::Probe) -> Probe {
    match &p.target {
        ProbeTarget::System => {
            // Cables (with the bodies they carry) + rapier's dynamic bodies.
            let chains = src.chains();
            let e = |f: fn(&Cable) -> f64| chains.iter().map(|c| f(c)).sum::<f64>();
            let (ke, pe) = src.rapier_energies();
            match p.quantity {
                Quantity::KineticEnergy => Probe::Scalar(e(Cable::kinetic_energy) + ke),
                _ => Probe::Scalar(e(Cable::energy) + ke + pe),
            }
        }
        ProbeTarget::Body(name) if p.quantity == Quantity::ContactForce => Probe::Vector(src.body_contact_force(name)),
        ProbeTarget::Body(name) => {
            let (pos, rot, vel, w) = src.body_state(name);
            Probe::Vector(match p.quantity {
                Quantity::Position => pos,
                Quantity::Velocity => vel,
                Quantity::Rotation => {
                    let (x, y, z) = DQuat::from_mat3(&rot).to_euler(EulerRot::XYZ);
                    DVec3::new(x, y, z) * (180.0 / std::f64::consts::PI)
                }
                _ => w * (180.0 / std::f64::consts::PI),
            })
        }
        ProbeTarget::Cable(name) => {
            let Some(c) = src.rope(name) else {
                return Probe::Scalar(f64::NAN);
            };
            let s = p.s.unwrap_or(0.0);
            match p.quantity {
                Quantity::Position => Probe::Vector(c.point_at(s).0),
                Quantity::Velocity => Probe::Vector(c.point_at(s).1),
                Quantity::Tension => Probe::Scalar(c.tension_at(s)),
                Quantity::ContactForce => Probe::Scalar(c.contact_force()),
                _ => Probe::Scalar(c.stretched_length()),
            }
        }
        ProbeTarget::Joint(name) => src.joint(name, p.quantity),
        ProbeTarget::Winch(_) => Probe::Scalar(f64::NAN),
        ProbeTarget::Controller(name) => Probe::Scalar(src.controller(name, p.quantity)),
    }
}

/// A probe of the rail of a trolley that `cable` carries (the chain's root
/// prismatic sub-joint): `position` the slide (m), `velocity` its rate
/// (m/s), `force` the drive force along the rail, the motor's damper
/// included (N, world vector).
pub(crate) fn rail(cable: &Cable, quantity: Quantity) -> Probe {
    match quantity {
        Quantity::Position => Probe::Scalar(cable.state.q[0]),
        Quantity::Velocity => Probe::Scalar(cable.state.v[0]),
        _ => {
            let ch = &cable.model.chain;
            let axis = ch.link_rotation(0).expect(IN_CHAIN) * ch.joints()[0].axis;
            Probe::Vector(axis * (ch.joint_forces()[0] - ch.joints()[0].damping * cable.state.v[0]))
        }
    }
}

/// A probe of a joint that rapier keeps: `position` the revolute angle
/// (deg, unwrapped, 0 at t = 0) or the prismatic slide (m), `velocity` its
/// rate, `force` the drive's force (N) or torque (N·m) along or about the
/// world axis.
pub(crate) fn rapier_joint(j: &RapierJoint, bodies: &rapier3d::prelude::RigidBodySet, quantity: Quantity) -> Probe {
    let deg = if j.kind == JointKind::Revolute { 180.0 / std::f64::consts::PI } else { 1.0 };
    match quantity {
        Quantity::Position => Probe::Scalar(j.position(bodies) * deg),
        Quantity::Velocity => Probe::Scalar(j.velocity(bodies) * deg),
        // The drive force / torque (non-driven joints are refused).
        _ => Probe::Vector(j.axis_world(bodies) * j.drive_force),
    }
}

/// Appends the value of every probe column of `probes` (file order) to
/// `out`, after clearing it.
pub(crate) fn sample(probes: &[scenario::Probe], src: &dyn ProbeSource, out: &mut Vec<f64>) {
    out.clear();
    for p in probes {
        match (probe(src, p), p.component) {
            (Probe::Scalar(x), _) => out.push(x),
            (Probe::Vector(v), None) => out.extend([v.x, v.y, v.z]),
            (Probe::Vector(v), Some(c)) => out.push(match c {
                Component::X => v.x,
                Component::Y => v.y,
                Component::Z => v.z,
                Component::Norm => v.length(),
            }),
        }
    }
}
