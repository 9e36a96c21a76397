//! Validation of `[[probe]]`: one target, a quantity valid for it, unique
//! column names.

use std::collections::{HashMap, HashSet};

use super::controllers::Controller;
use super::raw::{RawProbe, S};
use super::span::Location;
use super::types::{Body, Cable, Joint, JointKind, Winch};
use super::validate::{fmt_num, list, Ctx, Res};

/// What a probe looks at.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ProbeTarget {
    /// A body, by name.
    Body(String),
    /// A cable, by name.
    Cable(String),
    /// A joint, by name.
    Joint(String),
    /// A winch, by name.
    Winch(String),
    /// A `[[controller]]`, by name.
    Controller(String),
    /// The whole system.
    System,
}

/// A probed quantity (which ones are valid depends on the target; see
/// `docs/scenario.md` for units).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Body origin / cable point (m); joint coordinate (m or degrees).
    Position,
    /// Body / cable point velocity (m/s); joint rate (m/s or deg/s).
    Velocity,
    /// Body orientation as XYZ Euler angles, degrees.
    Rotation,
    /// Body angular velocity, deg/s.
    AngularVelocity,
    /// Body: total contact force vector, N; cable: sum of contact normal force magnitudes, N.
    ContactForce,
    /// Cable axial force at `s`, N.
    Tension,
    /// Cable stretched length / winch free rope length, m.
    Length,
    /// Joint reaction force on body2, N (vector).
    Force,
    /// Winch rope speed, m/s.
    Speed,
    /// Winch drive torque, N·m.
    Torque,
    /// System kinetic + gravitational + elastic energy, J.
    Energy,
    /// System kinetic energy, J.
    KineticEnergy,
    /// Controller: the sway angle it measured at its last sample, degrees.
    Sway,
    /// Controller: its last command (m/s for the shapers' speed, N for the
    /// PIDs' force).
    Output,
    /// Controller: reference minus trolley position at its last sample, m.
    Error,
}

impl Quantity {
    /// The name used in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Position => "position",
            Quantity::Velocity => "velocity",
            Quantity::Rotation => "rotation",
            Quantity::AngularVelocity => "angular_velocity",
            Quantity::ContactForce => "contact_force",
            Quantity::Tension => "tension",
            Quantity::Length => "length",
            Quantity::Force => "force",
            Quantity::Speed => "speed",
            Quantity::Torque => "torque",
            Quantity::Energy => "energy",
            Quantity::KineticEnergy => "kinetic_energy",
            Quantity::Sway => "sway",
            Quantity::Output => "output",
            Quantity::Error => "error",
        }
    }
}

/// One component of a vector quantity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Component {
    /// x component.
    X,
    /// y component.
    Y,
    /// z component.
    Z,
    /// Euclidean norm.
    Norm,
}

/// A `[[probe]]`: one or three columns of results.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct Probe {
    /// Unique name (the column name or its prefix).
    pub name: String,
    /// What is probed.
    pub target: ProbeTarget,
    /// The quantity (valid for the target).
    pub quantity: Quantity,
    /// Arc length along the unstretched cable from its start, m (cable
    /// `position`, `velocity`, `tension` only).
    pub s: Option<f64>,
    /// The recorded component of a vector quantity (`None`: all three).
    pub component: Option<Component>,
    /// Where the `[[probe]]` table starts.
    pub location: Location,
}

impl Probe {
    /// True if the quantity is a vector for this target (three columns
    /// unless a `component` is chosen).
    pub fn is_vector(&self) -> bool {
        is_vector(&self.target, self.quantity)
    }

    /// The results.csv column names: `NAME` for a scalar or a single
    /// component, `NAME.x`, `NAME.y`, `NAME.z` for a whole vector.
    pub fn columns(&self) -> Vec<String> {
        if self.is_vector() && self.component.is_none() {
            ["x", "y", "z"].iter().map(|c| format!("{}.{c}", self.name)).collect()
        } else {
            vec![self.name.clone()]
        }
    }
}

use Quantity as Q;

/// The quantities valid for each target kind, in the order of the docs.
fn valid(target: &ProbeTarget) -> &'static [Quantity] {
    match target {
        ProbeTarget::Body(_) => &[Q::Position, Q::Velocity, Q::Rotation, Q::AngularVelocity, Q::ContactForce],
        ProbeTarget::Cable(_) => &[Q::Position, Q::Velocity, Q::Tension, Q::Length, Q::ContactForce],
        ProbeTarget::Joint(_) => &[Q::Position, Q::Velocity, Q::Force],
        ProbeTarget::Winch(_) => &[Q::Length, Q::Speed, Q::Torque],
        ProbeTarget::Controller(_) => &[Q::Sway, Q::Output, Q::Error],
        ProbeTarget::System => &[Q::Energy, Q::KineticEnergy],
    }
}

/// Whether `q` is a vector quantity for `target`.
pub(crate) fn is_vector(target: &ProbeTarget, q: Quantity) -> bool {
    match target {
        ProbeTarget::Body(_) => true,
        ProbeTarget::Cable(_) => matches!(q, Q::Position | Q::Velocity),
        ProbeTarget::Joint(_) => q == Q::Force,
        ProbeTarget::Winch(_) | ProbeTarget::Controller(_) | ProbeTarget::System => false,
    }
}

/// All `[[probe]]` tables.
pub(crate) fn probes(
    ctx: &Ctx<'_>,
    raw: &[S<RawProbe>],
    bodies: &[Body],
    joints: &[Joint],
    cables: &[Cable],
    winches: &[Winch],
    controllers: &[Controller],
) -> Res<Vec<Probe>> {
    let mut seen = HashMap::new();
    let mut columns = HashSet::new();
    let mut out = Vec::with_capacity(raw.len());
    for p in raw {
        let probe = probe(ctx, p, (bodies, joints, cables), winches, controllers, &mut seen)?;
        for c in probe.columns() {
            if c == "time" || !columns.insert(c.clone()) {
                return Err(ctx.err(p.get_ref().name.span(), format!("probe `{}`: column `{c}` is already used (by `time` or another probe)", probe.name)));
            }
        }
        out.push(probe);
    }
    Ok(out)
}

/// Error "unknown KIND `name` (known KINDs: ...)".
fn unknown(ctx: &Ctx<'_>, v: &S<String>, o: &str, kind: &str, known: Vec<&str>) -> super::ScenarioError {
    let known = if known.is_empty() { format!("no {kind}s are defined") } else { format!("known {kind}s: {}", list(&known)) };
    ctx.err(v.span(), format!("{o}: unknown {kind} `{}` ({known})", v.get_ref()))
}

#[allow(clippy::too_many_arguments)]
fn probe(
    ctx: &Ctx<'_>,
    raw: &S<RawProbe>,
    (bodies, joints, cables): (&[Body], &[Joint], &[Cable]),
    winches: &[Winch],
    controllers: &[Controller],
    seen: &mut HashMap<String, Location>,
) -> Res<Probe> {
    let r = raw.get_ref();
    let name = ctx.name(&r.name, "probe", seen)?;
    let o = format!("probe `{name}`");
    let o = o.as_str();

    // Exactly one target.
    let mut targets = Vec::new();
    for (field, v) in [("body", &r.body), ("cable", &r.cable), ("joint", &r.joint), ("winch", &r.winch), ("controller", &r.controller)] {
        if let Some(v) = v {
            targets.push((field, v.span()));
        }
    }
    if let Some(s) = r.system.as_ref().filter(|s| *s.get_ref()) {
        targets.push(("system", s.span()));
    }
    match targets.as_slice() {
        [] => return Err(ctx.err(raw.span(), format!("{o}: needs exactly one target: `body`, `cable`, `joint`, `winch`, `controller` or `system = true`"))),
        [_] => {}
        [first, second, ..] => return Err(ctx.err(second.1.clone(), format!("{o}: has several targets (`{}` and `{}`); give exactly one", first.0, second.0))),
    }
    let mut cable = None;
    let mut joint_kind = None;
    let target = if let Some(b) = &r.body {
        if !bodies.iter().any(|x| &x.name == b.get_ref()) {
            return Err(unknown(ctx, b, o, "body", bodies.iter().map(|x| x.name.as_str()).collect()));
        }
        ProbeTarget::Body(b.get_ref().clone())
    } else if let Some(c) = &r.cable {
        cable = cables.iter().find(|x| &x.name == c.get_ref());
        if cable.is_none() {
            return Err(unknown(ctx, c, o, "cable", cables.iter().map(|x| x.name.as_str()).collect()));
        }
        ProbeTarget::Cable(c.get_ref().clone())
    } else if let Some(j) = &r.joint {
        joint_kind = joints.iter().find(|x| &x.name == j.get_ref()).map(|x| x.kind);
        if joint_kind.is_none() {
            return Err(unknown(ctx, j, o, "joint", joints.iter().map(|x| x.name.as_str()).collect()));
        }
        ProbeTarget::Joint(j.get_ref().clone())
    } else if let Some(w) = &r.winch {
        if !winches.iter().any(|x| &x.name == w.get_ref()) {
            return Err(unknown(ctx, w, o, "winch", winches.iter().map(|x| x.name.as_str()).collect()));
        }
        ProbeTarget::Winch(w.get_ref().clone())
    } else if let Some(c) = &r.controller {
        if !controllers.iter().any(|x| &x.name == c.get_ref()) {
            return Err(unknown(ctx, c, o, "controller", controllers.iter().map(|x| x.name.as_str()).collect()));
        }
        ProbeTarget::Controller(c.get_ref().clone())
    } else {
        ProbeTarget::System
    };

    let kind = targets.first().map_or("system", |t| t.0);
    let valid = valid(&target);
    let quantity = valid.iter().copied().find(|q| q.name() == r.quantity.get_ref()).ok_or_else(|| {
        let names: Vec<&str> = valid.iter().map(|q| q.name()).collect();
        ctx.err(r.quantity.span(), format!("{o}: quantity `{}` is not available for a {kind} probe; valid quantities: {}", r.quantity.get_ref(), list(&names)))
    })?;
    if matches!(quantity, Q::Position | Q::Velocity) {
        if let Some(k @ (JointKind::Fixed | JointKind::Spherical)) = joint_kind {
            return Err(ctx.err(
                r.quantity.span(),
                format!("{o}: `{}` needs a revolute or prismatic joint, but the joint is {}", quantity.name(), format!("{k:?}").to_lowercase()),
            ));
        }
    }

    // Arc length: required exactly for cable point quantities.
    let at_point = cable.is_some() && matches!(quantity, Q::Position | Q::Velocity | Q::Tension);
    let s = match (&r.s, cable) {
        (Some(v), Some(c)) if at_point => {
            let s = ctx.num(v, o, "s")?;
            if !(0.0..=c.length).contains(&s) {
                return Err(ctx.err(v.span(), format!("{o}: `s` must be between 0 and the cable length {} m, found {}", fmt_num(c.length), fmt_num(s))));
            }
            Some(s)
        }
        (Some(v), _) => return Err(ctx.err(v.span(), format!("{o}: `s` only applies to cable `position`, `velocity` and `tension` probes"))),
        (None, _) if at_point => {
            return Err(ctx.err(r.quantity.span(), format!("{o}: cable `{}` needs `s`, the arc length from the cable start (m)", quantity.name())))
        }
        (None, _) => None,
    };

    let component = match &r.component {
        Some(c) => {
            if !is_vector(&target, quantity) {
                return Err(ctx.err(c.span(), format!("{o}: `component` only applies to vector quantities; `{}` is a scalar", quantity.name())));
            }
            let names: &[&str] = if quantity == Q::Rotation { &["x", "y", "z"] } else { &["x", "y", "z", "norm"] };
            Some(match ctx.choice(c, o, "component", names)? {
                "x" => Component::X,
                "y" => Component::Y,
                "z" => Component::Z,
                _ => Component::Norm,
            })
        }
        None => None,
    };
    Ok(Probe { name, target, quantity, s, component, location: ctx.loc(raw.span()) })
}
