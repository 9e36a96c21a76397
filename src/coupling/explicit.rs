//! Explicit coupling of a cable to a rigid body that another engine
//! (rapier) integrates: the body's sampled motion drives the cable's base
//! or end-spring target over a step, and the cable's reaction goes back to
//! the body; and the drive of a trolley absorbed into a cable's chain.
//! Used by the coupling core.
// With `rapier` alone (neither the plugin nor the runner) no rail is driven.
#![cfg_attr(not(any(feature = "app", feature = "sim")), allow(dead_code, unused_imports))]

use super::CoupledCable;
use crate::cable::chain::{rotation_vector, BaseMotion, SampledMotion, IN_CHAIN};
use crate::cable::Cable;
use glam::{DMat3, DVec3};
use rapier3d::prelude as rp;

/// Pose and motion of a body's attachment point at the start of a step,
/// copied into the cable's base motion or end-spring target ([`follow`]).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct BodySample {
    /// Time of the sample, s.
    pub t0: f64,
    /// Attachment point, m.
    pub position: DVec3,
    /// Body orientation.
    pub rotation: DMat3,
    /// Attachment point velocity, m/s.
    pub velocity: DVec3,
    /// Body angular velocity, rad/s.
    pub angular_velocity: DVec3,
    /// Velocity change over the last step, m/s².
    pub acceleration: DVec3,
}

impl BodySample {
    /// The sample as the chain's data, fed by follower `source`.
    pub fn motion(&self, source: usize) -> SampledMotion {
        SampledMotion {
            source,
            t0: self.t0,
            rotation: self.rotation,
            position: self.position,
            velocity: self.velocity,
            angular_velocity: self.angular_velocity,
            acceleration: self.acceleration,
        }
    }

    /// Replaces this sample by `new`, taken `since` seconds after it
    /// (`None`: the first sample, kept as given). The acceleration is the
    /// velocity change over `since`. With `from_poses`, the velocities are
    /// the pose change over `since` instead of the ones sampled: rapier's
    /// post-step velocities still carry its soft constraints' bias (a hinged
    /// beam at rest read 9e-3 m/s at its tip), which a stiff end spring's
    /// damping turns into an offset of the rope end (0.2 mm there).
    pub fn update(&mut self, mut new: BodySample, since: Option<f64>, from_poses: bool) {
        if let Some(dt) = since {
            if from_poses {
                new.velocity = (new.position - self.position) / dt;
                new.angular_velocity = rotation_vector(&(new.rotation * self.rotation.transpose())) / dt;
            }
            new.acceleration = (new.velocity - self.velocity) / dt;
        }
        *self = new;
    }
}

/// A base motion (or anchor target) that follows `sample`, extrapolated
/// with constant acceleration from its time; `source` is the follower id
/// that refreshes it each step ([`crate::cable::Chain::set_sampled`]).
pub(crate) fn follow(sample: &BodySample, source: usize) -> BaseMotion {
    BaseMotion::Sampled(sample.motion(source))
}

/// Force (N) and moment about `com` (world point, N·m) that a cable puts on
/// the body at its start (`start`: the chain's base load) or end (minus the
/// end anchor spring's force on the chain, at the spring's target point),
/// at time `t` (the end of the step just taken).
pub(crate) fn reaction(cable: &Cable, start: bool, com: DVec3, t: f64) -> (DVec3, DVec3) {
    let ch = &cable.model.chain;
    if start {
        let fc = ch.base_load();
        (fc.bot, fc.top - (com - ch.origin).cross(fc.bot))
    } else {
        let Some(an) = ch.anchors().first() else {
            return (DVec3::ZERO, DVec3::ZERO);
        };
        let p = ch.link_point(an.link, an.local_point).expect(IN_CHAIN);
        let pv = ch.link_point_velocity(an.link, an.local_point).expect(IN_CHAIN);
        let target = an.target.at(t);
        let (target, target_v) = (target.position, target.velocity);
        let on_chain = -(p - target) * an.stiffness - (pv - target_v) * an.damping;
        (-on_chain, (target - com).cross(-on_chain))
    }
}

/// A spring–damper drive on the chain's root sub-joint (a trolley's rail):
/// `F = k (x_target − x) + c (v_target − v)`, `x = offset + q₀` (m, the
/// rail coordinate the targets use), implicit in the cable solve; when the
/// force it asks for at the current state exceeds `max_force` (N), the
/// explicit force `±max_force` toward the target instead. Sets the
/// sub-joint's stiffness, damping, rest and drive force for the coming step;
/// `k = c = 0` leaves the rail free.
pub(crate) fn rail_drive(cable: &mut Cable, k: f64, c: f64, offset: f64, target_x: f64, target_v: f64, max_force: f64) {
    let (x, v) = (offset + cable.state.q[0], cable.state.v[0]);
    let ch = &mut cable.model.chain;
    let Some(j) = ch.joint_mut_same_layout(0) else {
        return;
    };
    let needed = k * (target_x - x) + c * (target_v - v);
    let force = if needed.abs() <= max_force {
        (j.stiffness, j.damping, j.rest) = (k, c, target_x - offset);
        c * target_v
    } else {
        (j.stiffness, j.damping, j.rest) = (0.0, 0.0, 0.0);
        max_force.copysign(needed)
    };
    let _ = ch.set_joint_force(0, force);
}

/// The rapier motor of a trolley's prismatic joint (both runners: the
/// plugin reads it from the joint component, `cablesim` builds it from a
/// scenario `drive`, [`velocity_drive_motor`]), as a spring and damper
/// on the chain's root sub-joint: `F = k (x_target − x) + c (v_target − v)`
/// (with `AccelerationBased` motors, `k` and `c` times the trolley's mass,
/// as rapier scales them by the body's mass), implicit in the cable solve;
/// when the force this asks for now exceeds `max_force`, an explicit force
/// of `max_force` toward the target instead. `offset` is the rapier joint
/// coordinate at chain coordinate 0. Without a motor the root sub-joint is
/// free.
pub(crate) fn rail_motor(cc: &mut CoupledCable, motor: Option<rp::JointMotor>, offset: f64) {
    let cable = &mut cc.cable;
    let Some(m) = motor.filter(|m| m.stiffness != 0.0 || m.damping != 0.0) else {
        rail_drive(cable, 0.0, 0.0, offset, 0.0, 0.0, f64::INFINITY);
        return;
    };
    let scale = match m.model {
        rp::MotorModel::AccelerationBased => cable.model.chain.joints()[0].link.map_or(0.0, |l| l.mass),
        rp::MotorModel::ForceBased => 1.0,
    };
    let (k, c) = (m.stiffness as f64 * scale, m.damping as f64 * scale);
    rail_drive(cable, k, c, offset, m.target_pos as f64, m.target_vel as f64, m.max_force as f64);
}

/// The rapier joint motor of a scenario velocity drive over a step of `h`
/// s ([`set_velocity_drive`] on a joint's x axis), as a joint stores it.
#[cfg(feature = "sim")]
pub(crate) fn velocity_drive_motor(target: f64, max_force: f64, h: f64) -> rp::JointMotor {
    let mut data = rp::GenericJoint::default();
    set_velocity_drive(&mut data, rp::JointAxis::LinX, target, max_force, h);
    data.motors[rp::JointAxis::LinX as usize]
}

/// Sets the velocity motor of a scenario velocity drive on `data`'s axis
/// `axis` over a step of `h` s: target `target` (m/s or rad/s),
/// acceleration-based damping `1/h` (the velocity error halves every
/// step), saturating at `max_force` (N or N·m), in rapier's f32.
#[cfg(any(feature = "sim", feature = "app"))]
pub(crate) fn set_velocity_drive(data: &mut rp::GenericJoint, axis: rp::JointAxis, target: f64, max_force: f64, h: f64) {
    data.set_motor_model(axis, rp::MotorModel::AccelerationBased);
    data.set_motor_velocity(axis, target as f32, (1.0 / h) as f32);
    data.set_motor_max_force(axis, max_force as f32);
}
