//! `[[controller]]` in both scenario runners ([`World`](super::World) and
//! `plugin::scenario`): when a sample is due, the controller measures the
//! trolley and the sway through the runner's [`ProbeSource`] and gives a
//! command, which becomes the rail's motor until the next sample (the
//! motor the chain's root sub-joint reads, `coupling::rail_motor`). The
//! same code in both runners gives the same bits.

use super::probe::{Probe, ProbeSource};
use crate::coupling::set_velocity_drive;
use crate::crane::control::{Reference, TrolleyCommand, TrolleyController, TrolleyMeasurement, Waypoints};
use crate::crane::CraneError;
use crate::scenario::{Controller, Quantity, Scenario};
use glam::{DMat3, DVec3};
use rapier3d::prelude as rp;

/// A controller while a scenario runs.
pub(crate) struct ControllerRun {
    /// Its `[[controller]]`.
    pub spec: Controller,
    controller: Box<dyn TrolleyController + Send + Sync>,
    reference: Waypoints,
    /// Samples taken.
    samples: u64,
    command: TrolleyCommand,
    /// Sway (rad) and position error (m) at the last sample.
    sway: f64,
    error: f64,
}

impl std::fmt::Debug for ControllerRun {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ControllerRun").field("name", &self.spec.name).field("samples", &self.samples).field("command", &self.command).finish()
    }
}

impl ControllerRun {
    /// A fresh run of `spec`; an error if its values are out of range.
    pub fn new(spec: &Controller) -> Result<ControllerRun, CraneError> {
        let command = if spec.kind.is_shaper() { TrolleyCommand::Speed(0.0) } else { TrolleyCommand::Force(0.0) };
        if !(spec.sample_time > 0.0 && spec.sample_time.is_finite()) {
            return Err(CraneError::InvalidParameter {
                model: "controller",
                field: "sample_time",
                value: spec.sample_time,
                requirement: "positive and finite",
            });
        }
        Ok(ControllerRun { controller: spec.build()?, reference: spec.reference()?, spec: spec.clone(), samples: 0, command, sway: 0.0, error: 0.0 })
    }

    /// At the start of a sub-step at `t` (s): when a sample is due
    /// (`t ≥ k · sample_time` for the next sample `k`, within 1e-9 of the
    /// sample time), gives the controller `measurement` and keeps its
    /// command.
    pub fn sample(&mut self, t: f64, measurement: impl FnOnce() -> TrolleyMeasurement) {
        if !self.due(t) {
            return;
        }
        let m = measurement();
        self.command = self.controller.update(&m);
        self.sway = m.sway;
        self.error = self.reference.position(m.time) - m.position;
        // The next sample after `t` (a sample time shorter than the step
        // samples at every step).
        self.samples = ((t / self.spec.sample_time + 1e-9).floor() as u64 + 1).max(self.samples + 1);
    }

    /// Whether the controller has to sample at `t` (see [`Self::sample`]).
    pub fn due(&self, t: f64) -> bool {
        t + 1e-9 * self.spec.sample_time >= self.samples as f64 * self.spec.sample_time
    }

    /// The rail motor that carries the command over a sub-step of `h` s,
    /// as a rapier joint stores it: a speed is the velocity drive of a
    /// scenario (`velocity_drive_motor`, limited to `max_force`); a force
    /// `F` a force-based motor that asks for more than `|F|` toward the
    /// sign of `F` and is limited to `|F|`, so that it pushes with exactly
    /// `F` (in rapier's f32).
    pub fn motor(&self, h: f64) -> rp::JointMotor {
        let mut data = rp::GenericJoint::default();
        self.apply(&mut data, h);
        data.motors[rp::JointAxis::LinX as usize]
    }

    /// Sets [`Self::motor`] on the x axis of `data` (a rail joint's).
    pub fn apply(&self, data: &mut rp::GenericJoint, h: f64) {
        let axis = rp::JointAxis::LinX;
        match self.command {
            TrolleyCommand::Speed(v) => set_velocity_drive(data, axis, v, self.spec.max_force, h),
            TrolleyCommand::Force(f) => {
                data.set_motor_model(axis, rp::MotorModel::ForceBased);
                data.set_motor_velocity(axis, 1e30f32.copysign(f as f32), 1.0);
                data.set_motor_max_force(axis, f.abs() as f32);
            }
        }
    }

    /// A controller probe: `sway` (deg), `output` (m/s or N), `error` (m).
    pub fn probe(&self, quantity: Quantity) -> f64 {
        match quantity {
            Quantity::Sway => self.sway.to_degrees(),
            Quantity::Error => self.error,
            _ => match self.command {
                TrolleyCommand::Speed(v) => v,
                TrolleyCommand::Force(f) => f,
            },
        }
    }
}

/// What controller `c` measures at time `t` in the runner `src`: the
/// trolley's position along its rail (the joint probe's `position`, m from
/// the trolley's place at t = 0) and speed; the sway angle of the line
/// from the cable's start to the payload's origin (the body at the cable's
/// end) from the downward vertical (gravity's direction; −y without
/// gravity), in the vertical plane that holds the rail axis, positive when
/// the payload is ahead along the axis, and its rate (exact, from the
/// velocities). The payload's origin and not the cable's end: a payload
/// hung by a point above its centre rocks about it (a 0.3 m ball hooked at
/// its top: `ω = √(m g a / I)` = 9 rad/s), and a PID fed the end of the
/// cable pumps that rocking (on the shipped crane it doubled every 10 s);
/// fed the payload's centre it settles (docs/architecture.md).
pub(crate) fn measure(src: &dyn ProbeSource, scenario: &Scenario, c: &Controller, t: f64) -> TrolleyMeasurement {
    let scalar = |p: Probe| match p {
        Probe::Scalar(x) => x,
        Probe::Vector(_) => f64::NAN,
    };
    let position = scalar(src.joint(&c.joint, Quantity::Position));
    let velocity = scalar(src.joint(&c.joint, Quantity::Velocity));
    let g = scenario.simulation.gravity;
    let down = if g.length() > 0.0 { g.normalize() } else { DVec3::NEG_Y };
    let joint = scenario.joints.iter().find(|j| j.name == c.joint);
    let frame = joint.filter(|j| j.body1 != "world").map_or(DMat3::IDENTITY, |j| src.body_state(&j.body1).1);
    let axis = frame * joint.and_then(|j| j.axis).unwrap_or(DVec3::X);
    let ahead = (axis - down * axis.dot(down)).normalize_or_zero();
    let (mut sway, mut sway_rate) = (f64::NAN, f64::NAN);
    if let Some(rope) = src.rope(&c.cable) {
        let (p0, v0) = rope.point_at(0.0);
        let (p1, _, v1, _) = src.body_state(&c.payload);
        let (d, dd) = (p1 - p0, v1 - v0);
        let (x, y) = (d.dot(ahead), d.dot(down));
        sway = x.atan2(y);
        sway_rate = (dd.dot(ahead) * y - x * dd.dot(down)) / (x * x + y * y);
    }
    TrolleyMeasurement { time: t, position, velocity, sway, sway_rate }
}
