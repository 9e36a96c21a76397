//! The validated scenario: plain SI values, angles in radians.
//!
//! Field-by-field reference: `docs/scenario.md`.

use std::ops::{Add, Div, Mul, Sub};
use std::path::PathBuf;

use glam::{DQuat, DVec3};

use super::probes::Probe;
use super::span::Location;

/// Names accepted by `[simulation] integrator`.
pub const INTEGRATOR_NAMES: &[&str] =
    &["euler", "improved_euler", "rk4", "linear_acceleration", "newmark", "wilson_theta", "hht", "generalized_alpha", "symplectic_euler", "linearly_implicit"];

/// A parsed and validated scenario file.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// The file it was read from (as given).
    pub file: PathBuf,
    /// `[simulation]`.
    pub simulation: Simulation,
    /// `[[body]]` tables in file order.
    pub bodies: Vec<Body>,
    /// `[[joint]]` tables in file order.
    pub joints: Vec<Joint>,
    /// `[[cable]]` tables in file order.
    pub cables: Vec<Cable>,
    /// `[environment]` (defaults when absent).
    pub environment: Environment,
    /// `[[winch]]` tables in file order.
    pub winches: Vec<Winch>,
    /// `[[controller]]` tables in file order.
    pub controllers: Vec<super::Controller>,
    /// `[[probe]]` tables in file order (= results.csv column order).
    pub probes: Vec<Probe>,
}

impl Scenario {
    /// The body named `name`, if any (`world` is not a body).
    pub fn body(&self, name: &str) -> Option<&Body> {
        self.bodies.iter().find(|b| b.name == name)
    }
    /// The cable named `name`, if any.
    pub fn cable(&self, name: &str) -> Option<&Cable> {
        self.cables.iter().find(|c| c.name == name)
    }
    /// All results.csv columns after `time`, in order (see [`Probe::columns`]).
    pub fn columns(&self) -> Vec<String> {
        self.probes.iter().flat_map(Probe::columns).collect()
    }
}

/// `[simulation]`: how long and how to step.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulation {
    /// Simulated time, s (> 0).
    pub duration: f64,
    /// Frame step, s (0 < dt ≤ 1).
    pub dt: f64,
    /// Cable sub-steps per frame (≥ 1); `None`: the project's default.
    pub substeps: Option<u32>,
    /// Cable integrator and its parameters.
    pub integrator: IntegratorChoice,
    /// Gravity, m/s² (default `[0, -9.81, 0]`).
    pub gravity: DVec3,
    /// Time between rows of results.csv, s (≥ dt; default dt).
    pub output_interval: f64,
    /// Start from the static equilibrium of every cable (extension;
    /// default false): solved before t = 0 under gravity, the cables'
    /// `loads` and their held ends.
    pub statics: bool,
    /// Equal load increments of that static solve (extension; ≥ 1,
    /// default 10): the cables' `loads` are applied in this many steps.
    pub static_load_steps: u32,
}

/// The cable integrator chosen in `[simulation]`, with the optional scheme
/// parameters. A parameter is `Some` only if it was given in the file (or,
/// for the default integrator, `rho_inf = Some(0.0)`); `None` means the
/// integrator's own default. Parameters are only accepted for their scheme.
#[derive(Debug, Clone, PartialEq)]
pub struct IntegratorChoice {
    /// One of [`INTEGRATOR_NAMES`] (default `generalized_alpha`).
    pub name: String,
    /// Newmark β (≥ 0), `newmark` only.
    pub beta: Option<f64>,
    /// Newmark γ (≥ 0.5), `newmark` only.
    pub gamma: Option<f64>,
    /// Wilson θ (≥ 1), `wilson_theta` only.
    pub theta: Option<f64>,
    /// HHT α (−1/3 ≤ α ≤ 0), `hht` only.
    pub alpha: Option<f64>,
    /// Generalized-α spectral radius at infinite frequency ρ∞ (0 ≤ ρ∞ ≤ 1),
    /// `generalized_alpha` only.
    pub rho_inf: Option<f64>,
    /// Implicitness weight w (0.5 ≤ w ≤ 1), `linearly_implicit` only.
    pub w: Option<f64>,
}

impl Default for IntegratorChoice {
    /// `generalized_alpha` with ρ∞ = 0.
    fn default() -> Self {
        IntegratorChoice { name: "generalized_alpha".to_string(), beta: None, gamma: None, theta: None, alpha: None, rho_inf: Some(0.0), w: None }
    }
}

/// Rapier body type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyKind {
    /// Moved by forces.
    Dynamic,
    /// Never moves.
    Fixed,
    /// Moved by its prescribed [`Motion`] (at rest without one).
    Kinematic,
}

/// The body's collider, in the body frame (capsule and cylinder along local y).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// Sphere of `radius`, m.
    Ball {
        /// Radius, m.
        radius: f64,
    },
    /// Box with half extents, m.
    Cuboid {
        /// Half extents along local x, y, z, m.
        half_extents: DVec3,
    },
    /// Capsule along local y.
    Capsule {
        /// Radius, m.
        radius: f64,
        /// Half height of the cylindrical part, m.
        half_height: f64,
    },
    /// Cylinder along local y.
    Cylinder {
        /// Radius, m.
        radius: f64,
        /// Half height, m.
        half_height: f64,
    },
}

/// A rapier rigid body with one collider.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Unique name (never `world`).
    pub name: String,
    /// Dynamic, fixed or kinematic.
    pub kind: BodyKind,
    /// Collider shape.
    pub shape: Shape,
    /// Mass, kg (`Some` exactly for dynamic bodies).
    pub mass: Option<f64>,
    /// Position of the body origin, m. For a sine motion the centre of the
    /// oscillation; for a table motion the table's position at t = 0.
    pub position: DVec3,
    /// Orientation: `DQuat::from_euler(EulerRot::XYZ, x, y, z)` of the file's
    /// degrees, i.e. R = Rx(x)·Ry(y)·Rz(z) (intrinsic X, then Y, then Z).
    pub rotation: DQuat,
    /// Initial linear velocity, m/s (dynamic bodies).
    pub linear_velocity: DVec3,
    /// Initial angular velocity, rad/s (the file gives deg/s).
    pub angular_velocity: DVec3,
    /// Coulomb friction coefficient of its contacts (default 0.5).
    pub friction: f64,
    /// Restitution coefficient (0 to 1) of rapier's contacts between it
    /// and other rigid bodies, combined as rapier combines two colliders'
    /// (their mean by default); 0 by default, rapier's.
    pub restitution: f64,
    /// Collision groups of its collider (extension; default every group).
    pub collision_groups: CollisionGroups,
    /// Exposed area for wind load, m² (default 0).
    pub wind_area: f64,
    /// Wind shape coefficient C (default 0).
    pub wind_coefficient: f64,
    /// Prescribed motion (kinematic bodies only).
    pub motion: Option<Motion>,
    /// Where the `[[body]]` table starts.
    pub location: Location,
}

impl Body {
    /// Prescribed position of the body origin at time `t`, m: the motion's
    /// position, or `position` for bodies without a motion.
    pub fn position_at(&self, t: f64) -> DVec3 {
        match &self.motion {
            Some(m) => m.position_at(t, self.position),
            None => self.position,
        }
    }

    /// Prescribed orientation at time `t`: `rotation`, turned by a `spin`
    /// motion's angle about its axis.
    pub fn rotation_at(&self, t: f64) -> DQuat {
        match &self.motion {
            Some(m) => m.rotation_at(t) * self.rotation,
            None => self.rotation,
        }
    }

    /// World position at time 0 of the body-local point `local`, m.
    pub fn world_point(&self, local: DVec3) -> DVec3 {
        self.position_at(0.0) + self.rotation_at(0.0) * local
    }
}

/// Prescribed motion of a kinematic body: a translation (`Sine`, `Table`;
/// the rotation stays constant) or a rotation about a fixed axis through
/// the body origin (`Spin`; the position stays constant).
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// `base + amplitude · sin(2π t / period + phase)`.
    Sine {
        /// Amplitude vector, m.
        amplitude: DVec3,
        /// Period, s (> 0).
        period: f64,
        /// Phase, rad (the file gives degrees).
        phase: f64,
    },
    /// Piecewise-linear world positions of the body origin, `(t s, [x,y,z] m)`
    /// with strictly increasing times; the end values hold outside.
    Table {
        /// The points.
        points: Vec<(f64, DVec3)>,
    },
    /// Rotation about the world axis `axis` through the body origin
    /// (`position`) at the angular rate `rate` (extension). The angle is
    /// the exact integral of the piecewise-linear rate from t = 0.
    Spin {
        /// Unit axis, world frame (the file's axis normalised).
        axis: DVec3,
        /// Angular rate against time, rad/s (the file gives deg/s); the end
        /// values hold outside the table.
        rate: TimeSeries,
    },
}

impl Motion {
    /// Position at time `t` (s) of a body whose `position` is `base`, m.
    /// (`base` is the sine's centre; a table gives absolute positions.)
    pub fn position_at(&self, t: f64, base: DVec3) -> DVec3 {
        match self {
            Motion::Sine { amplitude, period, phase } => base + *amplitude * (std::f64::consts::TAU * t / period + phase).sin(),
            Motion::Table { points } => interpolate(points, t).unwrap_or(base),
            Motion::Spin { .. } => base,
        }
    }

    /// Rotation turned by the motion from t = 0 to `t` (identity for the
    /// translations): the body's orientation is this times its `rotation`.
    pub fn rotation_at(&self, t: f64) -> DQuat {
        match self {
            Motion::Spin { axis, rate } => DQuat::from_axis_angle(*axis, rate.integral(0.0, t)),
            _ => DQuat::IDENTITY,
        }
    }

    /// Angular velocity at time `t`, rad/s, world frame (zero for the
    /// translations).
    pub fn angular_velocity_at(&self, t: f64) -> DVec3 {
        match self {
            Motion::Spin { axis, rate } => *axis * rate.value_at(t),
            _ => DVec3::ZERO,
        }
    }

    /// Angular acceleration at time `t`, rad/s², world frame: the slope of
    /// the rate segment that contains `t` (the mean of the two at a
    /// breakpoint, see [`TimeSeries::slope_at`], except at t = 0, where the
    /// run starts: there the slope after it); zero outside the table and
    /// for the translations.
    pub fn angular_acceleration_at(&self, t: f64) -> DVec3 {
        match self {
            Motion::Spin { axis, rate } => {
                let t = if t.abs() <= 1e-9 { 3e-9 } else { t };
                *axis * rate.slope_at(t)
            }
            _ => DVec3::ZERO,
        }
    }

    /// Velocity at time `t`, m/s (a table's segment slope; zero outside the
    /// table; at a breakpoint the slope of the segment that starts there).
    pub fn velocity_at(&self, t: f64) -> DVec3 {
        match self {
            Motion::Sine { amplitude, period, phase } => {
                let w = std::f64::consts::TAU / period;
                *amplitude * w * (w * t + phase).cos()
            }
            Motion::Table { points } => slope(points, t).unwrap_or(DVec3::ZERO),
            Motion::Spin { .. } => DVec3::ZERO,
        }
    }
}

/// A piecewise-linear function of time, `(t, value)` with strictly
/// increasing t; the end values hold outside the range.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeSeries {
    /// The points `(t s, value)`.
    pub points: Vec<(f64, f64)>,
}

impl TimeSeries {
    /// Value at time `t` (0 for an empty series).
    pub fn value_at(&self, t: f64) -> f64 {
        interpolate(&self.points, t).unwrap_or(0.0)
    }

    /// Slope of the segment that contains `t`, 0 outside the table; at a
    /// breakpoint (within 1e-9·max(1, |t|) s, so that times accumulated in
    /// floating point land on it) the mean of the slopes on either side,
    /// so that a time stepper sampling the breakpoints is not biased toward
    /// one segment.
    pub fn slope_at(&self, t: f64) -> f64 {
        let eps = 1e-9 * t.abs().max(1.0);
        let i = self.points.partition_point(|p| p.0 <= t + eps);
        let at_breakpoint = i.checked_sub(1).and_then(|k| self.points.get(k)).is_some_and(|p| p.0 >= t - eps);
        let one = |t: f64| slope(&self.points, t).unwrap_or(0.0);
        if at_breakpoint {
            0.5 * (one(t - 2.0 * eps) + one(t + 2.0 * eps))
        } else {
            one(t)
        }
    }

    /// Exact integral of the piecewise-linear function from `a` to `b`
    /// (negative for b < a), the end values held outside the table
    /// (0 for an empty series or a non-finite bound).
    pub fn integral(&self, a: f64, b: f64) -> f64 {
        if !(a.is_finite() && b.is_finite()) {
            return 0.0;
        }
        if b < a {
            return -self.integral(b, a);
        }
        if self.points.is_empty() {
            return 0.0;
        }
        // Breakpoints inside (a, b), then the trapezoids between them.
        let mut xs = vec![a];
        xs.extend(self.points.iter().map(|p| p.0).filter(|&x| x > a && x < b));
        xs.push(b);
        xs.windows(2).map(|w| 0.5 * (w[1] - w[0]) * (self.value_at(w[0]) + self.value_at(w[1]))).sum()
    }
}

/// Linear interpolation in `points` (times increasing), holding the ends.
fn interpolate<T>(points: &[(f64, T)], t: f64) -> Option<T>
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<f64, Output = T>,
{
    let (first, last) = (points.first()?, points.last()?);
    if t.is_nan() || t <= first.0 {
        return Some(first.1);
    }
    if t >= last.0 {
        return Some(last.1);
    }
    let i = points.partition_point(|p| p.0 <= t);
    let (a, b) = (points.get(i.checked_sub(1)?)?, points.get(i)?);
    let f = (t - a.0) / (b.0 - a.0);
    Some(a.1 + (b.1 - a.1) * f)
}

/// Slope of the segment of `points` that contains `t` (None outside).
fn slope<T>(points: &[(f64, T)], t: f64) -> Option<T>
where
    T: Copy + Sub<Output = T> + Div<f64, Output = T>,
{
    let i = points.partition_point(|p| p.0 <= t);
    let (a, b) = (points.get(i.checked_sub(1)?)?, points.get(i)?);
    Some((b.1 - a.1) / (b.0 - a.0))
}

/// Rapier joint type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// All relative motion locked.
    Fixed,
    /// Rotation about `axis`.
    Revolute,
    /// Translation along `axis`.
    Prismatic,
    /// Free rotation about the anchor.
    Spherical,
}

/// A joint motor or force along/about the joint axis.
#[derive(Debug, Clone, PartialEq)]
pub enum Drive {
    /// Prescribed force, N (N·m for revolute joints), linear in time.
    Force {
        /// Force or torque against time.
        force: TimeSeries,
    },
    /// Velocity-tracking motor.
    Velocity {
        /// Target velocity against time, m/s (rad/s for revolute joints;
        /// the file gives deg/s).
        velocity: TimeSeries,
        /// Force (N) or torque (N·m) limit of the motor (> 0).
        max_force: f64,
    },
}

/// A rapier joint between two bodies (or a body and the world).
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Unique name.
    pub name: String,
    /// Joint type.
    pub kind: JointKind,
    /// First body name, or `world`.
    pub body1: String,
    /// Second body name, or `world`.
    pub body2: String,
    /// Joint point in body1's frame (world frame for `world`), m.
    pub anchor1: DVec3,
    /// Joint point in body2's frame (world frame for `world`), m.
    pub anchor2: DVec3,
    /// Unit axis in body1's frame (revolute and prismatic joints).
    pub axis: Option<DVec3>,
    /// `[min, max]`, m for prismatic, rad for revolute (file: degrees).
    pub limits: Option<[f64; 2]>,
    /// Optional drive (revolute and prismatic joints).
    pub drive: Option<Drive>,
    /// Where the `[[joint]]` table starts.
    pub location: Location,
}

/// How a cable end is held.
#[derive(Debug, Clone, PartialEq)]
pub enum CableEnd {
    /// A free end.
    Free,
    /// Pinned to a point of a body.
    Body {
        /// Body name.
        body: String,
        /// The point in the body's local frame, m.
        anchor: DVec3,
        /// Also fix the cable's tangent to the body (cantilever).
        clamp: bool,
    },
    /// Pinned to a point fixed in space.
    World {
        /// The point, m.
        point: DVec3,
        /// Also fix the tangent (cantilever).
        clamp: bool,
    },
}

/// A wire rope / cable.
#[derive(Debug, Clone, PartialEq)]
pub struct Cable {
    /// Unique name.
    pub name: String,
    /// Unstretched length, m (> 0).
    pub length: f64,
    /// Number of beam elements (≥ 1).
    pub segments: u32,
    /// Diameter, m (contact radius = diameter / 2).
    pub diameter: f64,
    /// The material preset the properties came from, if any.
    pub material: Option<String>,
    /// Linear density, kg/m.
    pub linear_density: f64,
    /// Axial stiffness EA, N.
    pub ea: f64,
    /// Bending stiffness EI (first bending plane), N·m².
    pub ei: f64,
    /// Bending stiffness of the second plane, N·m² (extension; default `ei`).
    pub ei2: f64,
    /// Torsional stiffness GJ, N·m².
    pub gj: f64,
    /// Shear stiffness GA, N (extension; `None`: the project's default).
    pub shear_stiffness: Option<f64>,
    /// Stiffness-proportional damping time constant, s (default 0).
    pub damping: f64,
    /// Velocity damping of the rope's elements, linear, 1/s (default 0;
    /// [`RopeBuilder::velocity_damping`](crate::cable::RopeBuilder::velocity_damping)).
    pub linear_damping: f64,
    /// Velocity damping of the rope's elements, angular, 1/s (default 0).
    pub angular_damping: f64,
    /// Stiffness of the implicit spring that pins an end to a world point
    /// or a body, as a multiple of the element axial stiffness `EA/L_e`
    /// (> 0; default 1000;
    /// [`RopeBuilder::end_stiffness_factor`](crate::cable::RopeBuilder::end_stiffness_factor)).
    pub end_stiffness: f64,
    /// Coulomb friction coefficient of its contacts (default 0.3).
    pub friction: f64,
    /// Normal drag coefficient (default 1.2).
    pub drag_normal: f64,
    /// Tangential drag coefficient (default 0.008).
    pub drag_tangential: f64,
    /// Added-mass coefficient (default 1.0).
    pub added_mass: f64,
    /// How the start is held.
    pub start: CableEnd,
    /// How the end is held.
    pub end: CableEnd,
    /// Initial centerline, m (≥ 2 points, from the start point to the end
    /// point): the file's `path` or the default straight line.
    pub path: Vec<DVec3>,
    /// Contacts with colliders and other cables (default true).
    pub contacts: bool,
    /// Which colliders and cables its contacts meet (extension; default
    /// every group).
    pub collision_groups: CollisionGroups,
    /// Constant point loads, fixed in world direction, for the whole run
    /// (extension; default none).
    pub loads: Vec<PointLoad>,
    /// The `path` is the stress-free shape (a pre-curved beam) instead of
    /// a deformed straight cable (extension; default false).
    pub stress_free: bool,
    /// The axial law is tension-only: a rope cannot push (extension;
    /// default true). `false` keeps compression, for rods and beams.
    pub tension_only: bool,
    /// Where the `[[cable]]` table starts.
    pub location: Location,
}

impl Cable {
    /// Length of the initial centerline [`Cable::path`], m.
    pub fn path_length(&self) -> f64 {
        self.path.windows(2).map(|w| w[0].distance(w[1])).sum()
    }
}

/// A constant point load on a cable (extension): a force and a moment of
/// fixed world direction at one point of the cable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLoad {
    /// Arc length from the start along the unstretched cable, m
    /// (0 ≤ s ≤ `length`).
    pub s: f64,
    /// Force, N, world frame.
    pub force: DVec3,
    /// Moment, N·m, world frame (default zero).
    pub moment: DVec3,
}

/// `[environment]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Environment {
    /// Air density, kg/m³ (default 1.225).
    pub air_density: f64,
    /// Uniform wind velocity, m/s (default zero).
    pub wind: DVec3,
    /// y of the calm water surface, m (`None`: no water).
    pub water_surface: Option<f64>,
    /// Water density, kg/m³ (default 1025).
    pub water_density: f64,
    /// Uniform current velocity below the surface, m/s (default zero).
    pub current: DVec3,
}

impl Default for Environment {
    fn default() -> Self {
        Environment { air_density: 1.225, wind: DVec3::ZERO, water_surface: None, water_density: 1025.0, current: DVec3::ZERO }
    }
}

/// Which end of a cable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CableSide {
    /// The `start` end (s = 0).
    Start,
    /// The `end` end (s = length).
    End,
}

/// A drum that hauls in or pays out a cable.
#[derive(Debug, Clone, PartialEq)]
pub struct Winch {
    /// Unique name.
    pub name: String,
    /// The cable it drives.
    pub cable: String,
    /// The cable end wound on the drum (never a free end).
    pub at: CableSide,
    /// Drum radius, m (> 0).
    pub drum_radius: f64,
    /// Inertia of drum, gear and motor at the drum shaft, kg·m² (≥ 0).
    pub drum_inertia: f64,
    /// Drive torque limit, N·m (> 0).
    pub max_torque: f64,
    /// Rope speed command, m/s (+ hauls in, − pays out).
    pub speed: TimeSeries,
    /// Holding brake when the command is zero (default true).
    pub brake: bool,
    /// Lower limit of the free rope length, m.
    pub min_length: Option<f64>,
    /// Upper limit of the free rope length, m.
    pub max_length: Option<f64>,
    /// Where the `[[winch]]` table starts.
    pub location: Location,
}

/// Collision groups as rapier's `InteractionGroups` (test mode "and"): bit
/// `k − 1` of each mask is group `k` of the file (1 to 32). Two colliders
/// (or a cable and a collider, or two cables) interact when each one's
/// memberships meet the other's filter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CollisionGroups {
    /// The groups it belongs to.
    pub memberships: u32,
    /// The groups it interacts with.
    pub filter: u32,
}

#[cfg(feature = "rapier")]
impl From<CollisionGroups> for rapier3d::prelude::InteractionGroups {
    fn from(g: CollisionGroups) -> Self {
        use rapier3d::prelude::{Group, InteractionTestMode};
        rapier3d::prelude::InteractionGroups::new(Group::from_bits_retain(g.memberships), Group::from_bits_retain(g.filter), InteractionTestMode::And)
    }
}

impl Default for CollisionGroups {
    /// Every group, both ways (a rapier collider's default).
    fn default() -> Self {
        CollisionGroups { memberships: u32::MAX, filter: u32::MAX }
    }
}
