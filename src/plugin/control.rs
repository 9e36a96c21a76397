//! Anti-sway control of a trolley as a Bevy component: any
//! [`TrolleyController`] of [`crate::crane::control`] (input shaping, the
//! PIDs) drives a trolley on a rapier rail while a cable carries its
//! payload.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_rapier_cable::crane::control::{InputShaper, Move, ShapedMove, ShaperKind};
//! use bevy_rapier_cable::plugin::TrolleyControl;
//! # fn spawn(mut commands: Commands, trolley: Entity, payload: Entity) {
//! // A 10 m move, ZV-shaped for a 10 m pendulum, on the trolley's rail
//! // motor (at most 20 kN).
//! let motion = Move { t0: 1.0, start: 0.0, target: 10.0, max_speed: 1.0, max_acceleration: 0.25 };
//! let shaper = InputShaper::new(ShaperKind::Zv, (9.81f64 / 10.3).sqrt(), 0.0).unwrap();
//! commands.entity(trolley).insert(TrolleyControl::new(ShapedMove { motion, shaper }, payload, Vec3::X).with_max_force(2e4));
//! # }
//! ```

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;

use crate::crane::control::{TrolleyCommand, TrolleyController, TrolleyMeasurement};

/// A controller driving the trolley entity it is on, which runs on a rapier
/// prismatic joint (an [`ImpulseJoint`] on the trolley) along `axis`.
///
/// Every fixed step, before rapier and the cables take their inputs
/// ([`PhysicsSet::SyncBackend`]), it measures:
/// * the trolley's position along `axis` from `origin` (m) and its speed;
/// * the sway angle of the payload: the angle from the downward vertical
///   (−y) of the line from the trolley's origin to the payload's origin,
///   in the vertical plane holding `axis`, positive when the payload is
///   ahead along `axis`, and its rate.
///
/// Speeds and rates are backward differences over the fixed step (as a
/// sampled sensor would give them; 0 at the first step). The controller's
/// command goes to the trolley: a force to its [`ExternalForce`] (inserted
/// if missing; the component's force is replaced), a speed to its rail
/// motor (rapier's acceleration-based velocity motor with damping `1/dt`,
/// the law of a scenario's velocity drive, limited to `max_force`).
#[derive(Component)]
pub struct TrolleyControl {
    /// The controller.
    pub controller: Box<dyn TrolleyController + Send + Sync>,
    /// The payload whose sway is measured.
    pub payload: Entity,
    /// The rail axis (world; normalised when measured).
    pub axis: Vec3,
    /// The world point where the trolley's position is 0, m.
    pub origin: Vec3,
    /// Force limit of the rail motor for speed commands, N.
    pub max_force: f32,
    last: Option<(f64, f64, f64)>,
    readout: Option<(TrolleyMeasurement, TrolleyCommand)>,
}

impl TrolleyControl {
    /// `controller` drives the trolley along `axis`, measuring `payload`'s
    /// sway; position 0 at the world origin, motor limit 1e6 N.
    pub fn new(controller: impl TrolleyController + Send + Sync + 'static, payload: Entity, axis: Vec3) -> Self {
        TrolleyControl { controller: Box::new(controller), payload, axis, origin: Vec3::ZERO, max_force: 1e6, last: None, readout: None }
    }

    /// With position 0 at the world point `origin` (m).
    pub fn with_origin(mut self, origin: Vec3) -> Self {
        self.origin = origin;
        self
    }

    /// With a rail motor force limit (N) for speed commands (its magnitude
    /// is used; NaN acts as 0).
    pub fn with_max_force(mut self, max_force: f32) -> Self {
        self.max_force = max_force;
        self
    }

    /// The last measurement and the command given for it.
    pub fn readout(&self) -> Option<(TrolleyMeasurement, TrolleyCommand)> {
        self.readout
    }
}

/// What the controller system reads and writes on a trolley.
type TrolleyItems = (Entity, &'static mut TrolleyControl, &'static Transform, Option<&'static mut ExternalForce>, Option<&'static mut ImpulseJoint>);

/// Measures, asks the controller, and writes the trolley's force or rail
/// motor.
pub(crate) fn trolley_control(mut commands: Commands, time: Res<Time<Fixed>>, mut trolleys: Query<TrolleyItems>, bodies: Query<&Transform>) {
    let dt = time.delta_secs_f64();
    let now = time.elapsed_secs_f64();
    for (entity, mut control, transform, force, joint) in &mut trolleys {
        let Ok(payload) = bodies.get(control.payload) else {
            continue;
        };
        let axis = control.axis.normalize_or_zero().as_dvec3();
        let d = (payload.translation - transform.translation).as_dvec3();
        let position = (transform.translation - control.origin).as_dvec3().dot(axis);
        let sway = d.dot(axis).atan2(-d.y);
        let (velocity, sway_rate) = match control.last {
            Some((x, th, t)) if now > t => ((position - x) / (now - t), (sway - th) / (now - t)),
            _ => (0.0, 0.0),
        };
        control.last = Some((position, sway, now));
        let m = TrolleyMeasurement { time: now, position, velocity, sway, sway_rate };
        let command = control.controller.update(&m);
        control.readout = Some((m, command));
        match command {
            TrolleyCommand::Force(f) => {
                let f = (axis * f).as_vec3();
                match force {
                    Some(mut ef) => ef.force = f,
                    None => {
                        commands.entity(entity).insert(ExternalForce { force: f, torque: Vec3::ZERO });
                    }
                }
            }
            TrolleyCommand::Speed(v) => {
                if let Some(mut joint) = joint {
                    let raw = &mut joint.data.as_mut().raw;
                    let max_force = if control.max_force.is_nan() { 0.0 } else { control.max_force.abs() as f64 };
                    crate::coupling::set_velocity_drive(raw, bevy_rapier3d::rapier::dynamics::JointAxis::LinX, v, max_force, dt.max(1e-9));
                }
            }
        }
    }
}
