//! The rapier side of [`World`](super::World): the scenario bodies and
//! joints that no cable absorbs, in a plain rapier3d [`PhysicsWorld`]
//! (no Bevy). See the module docs of `world.rs` for the frame order and
//! the coupling with the cables.
//!
//! Rapier works in f32; the poses, velocities and energies read back are
//! converted to f64.

use crate::coupling::set_velocity_drive;
use crate::scenario::{BodyKind, Drive, Joint, JointKind, Motion, Shape};
use glam::{DMat3, DQuat, DVec3};
use rapier3d::prelude as rp;

/// A scenario body kept by rapier.
#[derive(Debug)]
pub(crate) struct RapierBody {
    /// Scenario name.
    pub name: String,
    /// Rapier handle.
    pub handle: rp::RigidBodyHandle,
    /// Dynamic, fixed or kinematic.
    pub kind: BodyKind,
    /// Mass, kg (0 for fixed and kinematic bodies).
    pub mass: f64,
    /// Rotational inertia about the centre, body frame, kg·m²
    /// ([`shape_inertia`](super::shape_inertia)).
    pub inertia: DMat3,
    /// Prescribed motion of a kinematic body: (motion, `position`, `rotation`).
    pub motion: Option<(Motion, DVec3, DQuat)>,
    /// A link of a cable's chain (its state and energy are the cable's).
    pub carried: bool,
}

/// A scenario joint kept by rapier (an impulse joint).
#[derive(Debug)]
pub(crate) struct RapierJoint {
    /// Scenario name.
    pub name: String,
    /// Rapier handle.
    pub handle: rp::ImpulseJointHandle,
    /// Joint type.
    pub kind: JointKind,
    /// Rapier handles of body1 and body2 (the ground body for `world`).
    pub bodies: [rp::RigidBodyHandle; 2],
    /// Anchors in each body's frame, m.
    pub anchors: [DVec3; 2],
    /// Unit axis in body1's frame (revolute, prismatic; x otherwise).
    pub axis: DVec3,
    /// Relative orientation R1⁻¹·R2 at t = 0.
    pub rel0: DQuat,
    /// The drive, if any.
    pub drive: Option<Drive>,
    /// Unwrapped revolute angle, rad (0 at t = 0).
    pub angle: f64,
    /// Drive force (N) or torque (N·m) applied in the last frame, along or
    /// about the axis.
    pub drive_force: f64,
}

impl RapierJoint {
    /// The record of scenario joint `j`, rapier joint `handle` between
    /// `bodies` (body1, body2) whose orientations at t = 0 are `r1`, `r2`.
    pub fn new(j: &Joint, handle: rp::ImpulseJointHandle, bodies: [rp::RigidBodyHandle; 2], r1: DQuat, r2: DQuat) -> RapierJoint {
        RapierJoint {
            name: j.name.clone(),
            handle,
            kind: j.kind,
            bodies,
            anchors: [j.anchor1, j.anchor2],
            axis: j.axis.unwrap_or(DVec3::X),
            rel0: (r1.inverse() * r2).normalize(),
            drive: j.drive.clone(),
            angle: 0.0,
            drive_force: 0.0,
        }
    }

    /// World axis (body1's axis turned with body1).
    pub fn axis_world(&self, bodies: &rp::RigidBodySet) -> DVec3 {
        pose_of(bodies, self.bodies[0]).1 * self.axis
    }

    /// Revolute angle in (−π, π] from the bodies' orientations (twist of
    /// the relative rotation since t = 0 about the axis).
    fn raw_angle(&self, bodies: &rp::RigidBodySet) -> f64 {
        let (_, r1) = pose_of(bodies, self.bodies[0]);
        let (_, r2) = pose_of(bodies, self.bodies[1]);
        let d = (r1.inverse() * r2) * self.rel0.inverse();
        let twist = DVec3::new(d.x, d.y, d.z).dot(self.axis);
        let a = 2.0 * twist.atan2(d.w);
        if a > std::f64::consts::PI {
            a - std::f64::consts::TAU
        } else if a <= -std::f64::consts::PI {
            a + std::f64::consts::TAU
        } else {
            a
        }
    }

    /// Joint coordinate: revolute angle (rad, unwrapped), prismatic slide
    /// (m): (anchor2 − anchor1) · axis in the world; 0 for the others.
    pub fn position(&self, bodies: &rp::RigidBodySet) -> f64 {
        match self.kind {
            JointKind::Revolute => self.angle,
            JointKind::Prismatic => {
                let (p1, r1) = pose_of(bodies, self.bodies[0]);
                let (p2, r2) = pose_of(bodies, self.bodies[1]);
                ((p2 + r2 * self.anchors[1]) - (p1 + r1 * self.anchors[0])).dot(r1 * self.axis)
            }
            _ => 0.0,
        }
    }

    /// Rate of [`position`](Self::position): rad/s or m/s.
    pub fn velocity(&self, bodies: &rp::RigidBodySet) -> f64 {
        let (p1, r1) = pose_of(bodies, self.bodies[0]);
        let (p2, r2) = pose_of(bodies, self.bodies[1]);
        let (v1, w1) = velocity_of(bodies, self.bodies[0]);
        let (v2, w2) = velocity_of(bodies, self.bodies[1]);
        let a = r1 * self.axis;
        match self.kind {
            JointKind::Revolute => (w2 - w1).dot(a),
            JointKind::Prismatic => {
                let (x1, x2) = (r1 * self.anchors[0], r2 * self.anchors[1]);
                let (va, vb) = (v1 + w1.cross(x1), v2 + w2.cross(x2));
                (vb - va).dot(a) + ((p2 + x2) - (p1 + x1)).dot(w1.cross(a))
            }
            _ => 0.0,
        }
    }

    /// After a rapier step: unwraps the revolute angle and reads a
    /// velocity motor's force. Rapier sub-steps every step
    /// (`num_solver_iterations`, each `h_sub` s); the motor impulse it
    /// writes back is the last sub-step's, and acts on body2 with the
    /// opposite sign.
    pub fn after_step(&mut self, bodies: &rp::RigidBodySet, joints: &rp::ImpulseJointSet, h_sub: f64) {
        if self.kind == JointKind::Revolute {
            let raw = self.raw_angle(bodies);
            let turns = ((self.angle - raw) / std::f64::consts::TAU).round();
            self.angle = raw + turns * std::f64::consts::TAU;
        }
        if matches!(self.drive, Some(Drive::Velocity { .. })) {
            let free = if self.kind == JointKind::Revolute { rp::JointAxis::AngX } else { rp::JointAxis::LinX };
            let imp = joints.get(self.handle).map_or(0.0, |ij| ij.data.motors[free as usize].impulse);
            self.drive_force = -(imp as f64) / h_sub;
        }
    }
}

/// Rapier bodies and joints of a scenario.
pub(crate) struct RapierWorld {
    pub pw: rp::PhysicsWorld,
    /// The ground (`world`): a fixed body without collider at the origin.
    pub ground: rp::RigidBodyHandle,
    pub bodies: Vec<RapierBody>,
    pub joints: Vec<RapierJoint>,
}

impl std::fmt::Debug for RapierWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RapierWorld").field("bodies", &self.bodies).field("joints", &self.joints).finish_non_exhaustive()
    }
}

/// Rapier pose of a position and orientation.
pub(crate) fn pose(p: DVec3, q: DQuat) -> rp::Pose {
    rp::Pose::from_parts(p.as_vec3(), q.as_quat())
}

/// The collider of a scenario shape (local y is the capsule / cylinder axis).
pub(crate) fn collider(shape: &Shape) -> rp::ColliderBuilder {
    rp::ColliderBuilder::new(shared_shape(shape))
}

/// The rapier shape of a scenario shape (local y is the capsule / cylinder
/// axis), for `cablesim`'s colliders and the Bevy runner's.
pub(crate) fn shared_shape(shape: &Shape) -> rp::SharedShape {
    match *shape {
        Shape::Ball { radius } => rp::SharedShape::ball(radius as f32),
        Shape::Cuboid { half_extents: h } => rp::SharedShape::cuboid(h.x as f32, h.y as f32, h.z as f32),
        Shape::Capsule { radius, half_height } => rp::SharedShape::capsule_y(half_height as f32, radius as f32),
        Shape::Cylinder { radius, half_height } => rp::SharedShape::cylinder(half_height as f32, radius as f32),
    }
}

/// Kinetic energy (translation + rotation) and gravitational energy
/// −m g·x (J) of the rapier bodies `free` (mass kg, body-frame inertia
/// kg·m², handle), each summed in their order: the dynamic bodies rapier
/// keeps, for the `system` probes of both runners.
pub(crate) fn free_body_energies(bodies: &rp::RigidBodySet, free: &[(f64, DMat3, rp::RigidBodyHandle)], gravity: DVec3) -> (f64, f64) {
    let ke = free
        .iter()
        .map(|(m, i, h)| {
            let (v, w) = velocity_of(bodies, *h);
            rigid_energy(*m, i, pose_of(bodies, *h).1, v, w)
        })
        .sum();
    let pe = free.iter().map(|(m, _, h)| -m * gravity.dot(pose_of(bodies, *h).0)).sum();
    (ke, pe)
}

/// Pose (origin, orientation) of rapier body `h` in f64.
pub(crate) fn pose_of(bodies: &rp::RigidBodySet, h: rp::RigidBodyHandle) -> (DVec3, DQuat) {
    let p = bodies[h].position();
    (p.translation.as_dvec3(), p.rotation.as_dquat().normalize())
}

/// Velocity of rapier body `h`'s origin (= centre of mass) and its angular
/// velocity, f64.
pub(crate) fn velocity_of(bodies: &rp::RigidBodySet, h: rp::RigidBodyHandle) -> (DVec3, DVec3) {
    let rb = &bodies[h];
    (rb.linvel().as_dvec3(), rb.angvel().as_dvec3())
}

/// Kinetic energy (J) of a rigid body of mass `mass` (kg) and body-frame
/// inertia `inertia` (kg·m²) at orientation `q`, velocity `v` (m/s) and
/// angular velocity `w` (rad/s, world).
pub(crate) fn rigid_energy(mass: f64, inertia: &DMat3, q: DQuat, v: DVec3, w: DVec3) -> f64 {
    let wl = DMat3::from_quat(q).transpose() * w;
    0.5 * mass * v.length_squared() + 0.5 * wl.dot(*inertia * wl)
}

/// The rapier joint of scenario joint `j` between bodies at orientations
/// `r1` and `r2` at t = 0 (see [`RapierWorld::add_joint`]).
pub(crate) fn joint_data(j: &Joint, r1: DQuat, r2: DQuat, dt: f64) -> rp::GenericJoint {
    let axis = j.axis.unwrap_or(DVec3::X);
    let frame = DQuat::from_rotation_arc(DVec3::X, axis);
    let locked = match j.kind {
        JointKind::Fixed => rp::JointAxesMask::LOCKED_FIXED_AXES,
        JointKind::Revolute => rp::JointAxesMask::LOCKED_REVOLUTE_AXES,
        JointKind::Prismatic => rp::JointAxesMask::LOCKED_PRISMATIC_AXES,
        JointKind::Spherical => rp::JointAxesMask::LOCKED_SPHERICAL_AXES,
    };
    let mut data = rp::GenericJointBuilder::new(locked).contacts_enabled(false).build();
    data.local_frame1 = pose(j.anchor1, frame);
    data.local_frame2 = pose(j.anchor2, (r2.inverse() * r1 * frame).normalize());
    let free = if j.kind == JointKind::Revolute { rp::JointAxis::AngX } else { rp::JointAxis::LinX };
    if let Some([lo, hi]) = j.limits {
        data.set_limits(free, [lo as f32, hi as f32]);
    }
    if let Some(Drive::Velocity { velocity, max_force }) = &j.drive {
        set_velocity_drive(&mut data, free, velocity.value_at(dt), *max_force, dt);
    }
    data
}

/// The pose of a kinematic body with motion `m` from `p0`, `r0` at time
/// `t`, in rapier's f32.
pub(crate) fn motion_pose(m: &Motion, p0: DVec3, r0: DQuat, t: f64) -> rp::Pose {
    pose(m.position_at(t, p0), m.rotation_at(t) * r0)
}

/// Before a rapier step over `[t, t + dt]`: applies the force drives of
/// the joints rapier keeps (value at t + dt/2) as impulses, and sets their
/// velocity motors' targets (value at t + dt).
pub(crate) fn drive_joints(joints: &mut [RapierJoint], bodies: &mut rp::RigidBodySet, impulse_joints: &mut rp::ImpulseJointSet, t: f64, dt: f64) {
    for j in joints.iter_mut() {
        let free = if j.kind == JointKind::Revolute { rp::JointAxis::AngX } else { rp::JointAxis::LinX };
        match j.drive.clone() {
            Some(Drive::Force { force }) => {
                let f = force.value_at(t + 0.5 * dt);
                let a = j.axis_world(bodies);
                let [h1, h2] = j.bodies;
                if j.kind == JointKind::Revolute {
                    let imp = (a * f * dt).as_vec3();
                    bodies[h2].apply_torque_impulse(imp, true);
                    bodies[h1].apply_torque_impulse(-imp, true);
                } else {
                    // Equal and opposite at the joint points.
                    let (p1, r1) = pose_of(bodies, h1);
                    let (p2, r2) = pose_of(bodies, h2);
                    let imp = (a * f * dt).as_vec3();
                    let (x1, x2) = ((p1 + r1 * j.anchors[0]).as_vec3(), (p2 + r2 * j.anchors[1]).as_vec3());
                    bodies[h2].apply_impulse_at_point(imp, x2, true);
                    bodies[h1].apply_impulse_at_point(-imp, x1, true);
                }
                j.drive_force = f;
            }
            Some(Drive::Velocity { velocity, max_force }) => {
                if let Some(ij) = impulse_joints.get_mut(j.handle, true) {
                    set_velocity_drive(&mut ij.data, free, velocity.value_at(t + dt), max_force, dt);
                }
            }
            None => {}
        }
    }
}

impl RapierWorld {
    /// An empty world with `gravity` stepping at `dt`.
    pub fn new(gravity: DVec3, dt: f64) -> RapierWorld {
        let mut pw = rp::PhysicsWorld::new();
        pw.gravity = gravity.as_vec3();
        pw.integration_parameters.dt = dt as f32;
        let ground = pw.insert_body(rp::RigidBodyBuilder::fixed());
        RapierWorld { pw, ground, bodies: Vec::new(), joints: Vec::new() }
    }

    /// Adds a scenario body with its one collider (mass from `mass`, the
    /// rotary inertia of the shape as a uniform solid: rapier's collider
    /// mass properties, which equal [`shape_inertia`](super::shape_inertia)).
    pub fn add_body(&mut self, b: &crate::scenario::Body) {
        let builder = match b.kind {
            BodyKind::Dynamic => rp::RigidBodyBuilder::dynamic(),
            BodyKind::Fixed => rp::RigidBodyBuilder::fixed(),
            BodyKind::Kinematic => rp::RigidBodyBuilder::kinematic_position_based(),
        };
        let rb = builder
            .pose(pose(b.position_at(0.0), b.rotation_at(0.0)))
            .linvel(b.linear_velocity.as_vec3())
            .angvel(b.angular_velocity.as_vec3())
            .can_sleep(false)
            .gyroscopic_forces_enabled(true);
        let mass = b.mass.unwrap_or(0.0);
        let mut co = collider(&b.shape).friction(b.friction as f32).restitution(b.restitution as f32).collision_groups(b.collision_groups.into());
        if b.kind == BodyKind::Dynamic {
            co = co.mass(mass as f32);
        }
        let handle = self.pw.insert_body(rb);
        self.pw.insert_collider(co, Some(handle));
        self.bodies.push(RapierBody {
            name: b.name.clone(),
            handle,
            kind: b.kind,
            mass,
            inertia: super::shape_inertia(&b.shape, mass),
            motion: b.motion.clone().map(|m| (m, b.position, b.rotation)),
            carried: false,
        });
    }

    /// The rapier body of scenario body `name`.
    pub fn body(&self, name: &str) -> Option<&RapierBody> {
        self.bodies.iter().find(|b| b.name == name)
    }

    /// Pose (origin, orientation) of a rapier body in f64.
    pub fn pose_of(&self, h: rp::RigidBodyHandle) -> (DVec3, DQuat) {
        pose_of(&self.pw.bodies, h)
    }

    /// Velocity of the origin (= centre of mass) and angular velocity, f64.
    pub fn velocity_of(&self, h: rp::RigidBodyHandle) -> (DVec3, DVec3) {
        velocity_of(&self.pw.bodies, h)
    }

    /// Adds a scenario joint between two rapier bodies (`None`: the ground)
    /// given their poses at t = 0. The joint frames coincide at t = 0: the
    /// joint coordinate (revolute angle, prismatic slide) is zero there and
    /// `limits` are measured from there. Contacts between the two bodies are
    /// off.
    pub fn add_joint(&mut self, j: &Joint, b1: Option<rp::RigidBodyHandle>, b2: Option<rp::RigidBodyHandle>, dt: f64) {
        let (h1, h2) = (b1.unwrap_or(self.ground), b2.unwrap_or(self.ground));
        let (_, r1) = self.pose_of(h1);
        let (_, r2) = self.pose_of(h2);
        let data = joint_data(j, r1, r2, dt);
        let handle = self.pw.insert_impulse_joint(h1, h2, data);
        self.joints.push(RapierJoint::new(j, handle, [h1, h2], r1, r2));
    }

    /// Before a rapier step over `[t, t + dt]`: moves kinematic bodies to
    /// their motion at t + dt, applies force drives (value at t + dt/2) as
    /// impulses, sets velocity motors' targets (value at t + dt).
    pub fn prepare_step(&mut self, t: f64, dt: f64) {
        for b in &self.bodies {
            if let Some((m, p0, r0)) = &b.motion {
                self.pw.bodies[b.handle].set_next_kinematic_position(motion_pose(m, *p0, *r0, t + dt));
            }
        }
        drive_joints(&mut self.joints, &mut self.pw.bodies, &mut self.pw.impulse_joints, t, dt);
    }

    /// Steps rapier by its `dt`, then unwraps the revolute angles and reads
    /// the velocity motors' forces. Returns the name of the first body whose
    /// state is no longer finite.
    pub fn step(&mut self) -> Result<(), String> {
        self.pw.step();
        for b in &self.bodies {
            let rb = &self.pw.bodies[b.handle];
            let p = rb.position();
            let finite = p.translation.is_finite() && p.rotation.is_finite() && rb.linvel().is_finite() && rb.angvel().is_finite();
            // Rapier disables (quarantines) bodies whose state became non-finite.
            if !finite || !rb.is_enabled() {
                return Err(b.name.clone());
            }
        }
        // Rapier sub-steps every step (`num_solver_iterations`); the motor
        // impulse it writes back is the last sub-step's, and acts on body2
        // with the opposite sign.
        let h_sub = self.pw.integration_parameters.dt as f64 / self.pw.integration_parameters.num_solver_iterations.max(1) as f64;
        for j in &mut self.joints {
            j.after_step(&self.pw.bodies, &self.pw.impulse_joints, h_sub);
        }
        Ok(())
    }

    /// Kinetic and gravitational energy (J) of the dynamic bodies rapier
    /// keeps ([`free_body_energies`]).
    pub fn energies(&self, gravity: DVec3) -> (f64, f64) {
        let free: Vec<_> = self.bodies.iter().filter(|b| b.kind == BodyKind::Dynamic && !b.carried).map(|b| (b.mass, b.inertia, b.handle)).collect();
        free_body_energies(&self.pw.bodies, &free, gravity)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rapier's collider mass properties (uniform density from `mass`)
    /// equal [`shape_inertia`](super::super::shape_inertia) for every shape.
    #[test]
    fn rapier_mass_properties_match_shape_inertia() {
        let shapes = [
            Shape::Ball { radius: 0.7 },
            Shape::Cuboid { half_extents: DVec3::new(0.5, 1.5, 0.25) },
            Shape::Capsule { radius: 0.3, half_height: 1.2 },
            Shape::Cylinder { radius: 0.4, half_height: 0.9 },
        ];
        for s in &shapes {
            let m = 250.0;
            let co = collider(s).mass(m as f32).build();
            let mp = co.mass_properties();
            let i = mp.reconstruct_inertia_matrix();
            let ours = super::super::shape_inertia(s, m);
            assert!((mp.mass() as f64 - m).abs() < 1e-3, "{s:?}: mass {}", mp.mass());
            for (c, (a, b)) in [(i.x_axis, ours.x_axis), (i.y_axis, ours.y_axis), (i.z_axis, ours.z_axis)].into_iter().enumerate() {
                let d = (a.as_dvec3() - b).abs().max_element();
                assert!(d <= 1e-5 * ours.x_axis.x.max(ours.y_axis.y), "{s:?} column {c}: rapier {a:?} vs {b:?}");
            }
        }
    }
}
