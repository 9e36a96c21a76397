//! Validation of `[[controller]]`: anti-sway control of a trolley on a
//! prismatic rail (input shaping or the PIDs of [`crate::crane::control`]),
//! with the defaults resolved from the crane the file describes.

use std::collections::HashMap;

use super::raw::{RawController, S};
use super::span::Location;
use super::types::{Body, BodyKind, Cable, CableEnd, Joint, JointKind, Simulation};
use super::validate::{fmt_num, list, Ctx, Res, Rule};
use crate::crane::control::{DoubleLoopPid, IncrementalPid, InputShaper, NonlinearSchedule, PidGains, ShapedMove, ShaperKind, TrolleyController, Waypoints};
use crate::crane::{CraneError, OverheadCrane};

/// The kinds of `[[controller]]`, by their `type` in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ControllerKind {
    /// `zv`: ZV input shaping of the trolley's speed command.
    Zv,
    /// `zvd`: ZVD input shaping of the trolley's speed command.
    Zvd,
    /// `pid_double_loop`: the double closed-loop PID (force).
    PidDoubleLoop,
    /// `pid_nonlinear`: the same with error-dependent position gains.
    PidNonlinear,
    /// `pid_incremental`: the velocity-form digital PID (force).
    PidIncremental,
}

/// The `type` names, in the order of [`ControllerKind`].
pub const CONTROLLER_TYPES: [&str; 5] = ["zv", "zvd", "pid_double_loop", "pid_nonlinear", "pid_incremental"];

impl ControllerKind {
    /// The name used in scenario files.
    pub fn name(self) -> &'static str {
        CONTROLLER_TYPES[self as usize]
    }

    /// True for the input shapers (speed commands), false for the PIDs
    /// (force commands).
    pub fn is_shaper(self) -> bool {
        matches!(self, ControllerKind::Zv | ControllerKind::Zvd)
    }
}

/// A `[[controller]]`, with every default resolved.
#[derive(Debug, Clone, PartialEq)]
pub struct Controller {
    /// Unique name.
    pub name: String,
    /// Which controller.
    pub kind: ControllerKind,
    /// The prismatic joint (the trolley's rail) it drives; its `drive` is
    /// replaced.
    pub joint: String,
    /// The hoist cable whose sway it measures.
    pub cable: String,
    /// The payload: the body at the cable's end (the sway is measured to
    /// its origin).
    pub payload: String,
    /// Waypoints `(t, x)` of the trolley position command, s and m along
    /// the rail from the joint's zero (see [`Waypoints`]).
    pub target: Vec<(f64, f64)>,
    /// Speed limit of the reference, m/s.
    pub max_speed: f64,
    /// Acceleration limit of the reference, m/s².
    pub max_acceleration: f64,
    /// Drive force limit, N (the rail motor's for the shapers, the output
    /// clamp for the PIDs).
    pub max_force: f64,
    /// Shaper design frequency, Hz (default: the crane's pendulum).
    pub frequency: f64,
    /// Shaper design damping ratio (0 ≤ ζ < 1).
    pub damping: f64,
    /// Sample time, s: the controller measures and commands every
    /// `sample_time` and holds its command in between (default `dt`).
    pub sample_time: f64,
    /// Position loop gains (N/m, N/(m·s), N·s/m).
    pub position: PidGains,
    /// Sway loop gains (N/rad, N/(rad·s), N·s/rad).
    pub sway: PidGains,
    /// The nonlinear PID's gain schedule.
    pub schedule: NonlinearSchedule,
    /// Where the `[[controller]]` table starts.
    pub location: Location,
}

impl Controller {
    /// The reference the controller follows; an error if its limits or
    /// waypoints are out of range (a [`Controller`] changed after
    /// validation).
    pub fn reference(&self) -> Result<Waypoints, CraneError> {
        Waypoints::new(&self.target, self.max_speed, self.max_acceleration)
    }

    /// A fresh controller (its state at t = 0); an error naming the field
    /// if a value is out of range (a [`Controller`] changed after
    /// validation).
    pub fn build(&self) -> Result<Box<dyn TrolleyController + Send + Sync>, CraneError> {
        let motion = self.reference()?;
        let omega = 2.0 * std::f64::consts::PI * self.frequency;
        let shaper = |kind| InputShaper::new(kind, omega, self.damping);
        let pid = || DoubleLoopPid::new(motion.clone(), self.position, self.sway, self.max_force);
        Ok(match self.kind {
            ControllerKind::Zv => Box::new(ShapedMove { motion: motion.clone(), shaper: shaper(ShaperKind::Zv)? }),
            ControllerKind::Zvd => Box::new(ShapedMove { motion: motion.clone(), shaper: shaper(ShaperKind::Zvd)? }),
            ControllerKind::PidDoubleLoop => Box::new(pid()?),
            ControllerKind::PidNonlinear => Box::new(pid()?.nonlinear(self.schedule)),
            ControllerKind::PidIncremental => Box::new(IncrementalPid::new(motion.clone(), self.position, self.sway, self.sample_time, self.max_force)?),
        })
    }
}

/// The default poles of the double-loop PD, as multiples of the crane's
/// pendulum frequency ω₀ with damping ratio 0.7: `(1.2 ω₀, 0.7)` and
/// `(1.8 ω₀, 0.7)`.
pub const DEFAULT_POLES: [(f64, f64); 2] = [(1.2, 0.7), (1.8, 0.7)];
/// The default position integral gain, as a fraction of `kp` (1/s).
pub const DEFAULT_KI_RATIO: f64 = 0.05;
/// The default nonlinear schedule (`p_gain`, `d_gain`, `e_p` m, `e_i` m).
pub const DEFAULT_SCHEDULE: NonlinearSchedule = NonlinearSchedule { p_gain: 1.0, d_gain: 0.5, e_p: 0.5, e_i: 0.05 };

/// All `[[controller]]` tables.
pub(crate) fn controllers(
    ctx: &Ctx<'_>,
    raw: &[S<RawController>],
    sim: &Simulation,
    bodies: &[Body],
    joints: &[Joint],
    cables: &[Cable],
) -> Res<Vec<Controller>> {
    let mut seen = HashMap::new();
    let mut driven: HashMap<String, String> = HashMap::new();
    let mut out = Vec::with_capacity(raw.len());
    for c in raw {
        let controller = controller(ctx, c, sim, bodies, joints, cables, &mut seen)?;
        if let Some(other) = driven.insert(controller.joint.clone(), controller.name.clone()) {
            return Err(ctx.err(
                c.get_ref().joint.span(),
                format!(
                    "controller `{}`: joint `{}` is already driven by controller `{other}`; a rail takes one controller",
                    controller.name, controller.joint
                ),
            ));
        }
        out.push(controller);
    }
    Ok(out)
}

fn controller(
    ctx: &Ctx<'_>,
    raw: &S<RawController>,
    sim: &Simulation,
    bodies: &[Body],
    joints: &[Joint],
    cables: &[Cable],
    seen: &mut HashMap<String, Location>,
) -> Res<Controller> {
    let r = raw.get_ref();
    let name = ctx.name(&r.name, "controller", seen)?;
    let o = format!("controller `{name}`");
    let o = o.as_str();
    let kind = match ctx.choice(&r.kind, o, "type", &CONTROLLER_TYPES)? {
        "zv" => ControllerKind::Zv,
        "zvd" => ControllerKind::Zvd,
        "pid_double_loop" => ControllerKind::PidDoubleLoop,
        "pid_nonlinear" => ControllerKind::PidNonlinear,
        _ => ControllerKind::PidIncremental,
    };
    let t = kind.name();

    // The rail.
    let Some(joint) = joints.iter().find(|j| &j.name == r.joint.get_ref()) else {
        let known: Vec<&str> = joints.iter().filter(|j| j.kind == JointKind::Prismatic).map(|j| j.name.as_str()).collect();
        let known = if known.is_empty() { "no prismatic joints are defined".to_string() } else { format!("prismatic joints: {}", list(&known)) };
        return Err(ctx.err(r.joint.span(), format!("{o}: unknown joint `{}` ({known})", r.joint.get_ref())));
    };
    if joint.kind != JointKind::Prismatic {
        return Err(ctx.err(
            r.joint.span(),
            format!("{o}: joint `{}` is {}; a controller drives a trolley's prismatic rail", joint.name, format!("{:?}", joint.kind).to_lowercase()),
        ));
    }
    let trolley = bodies.iter().find(|b| b.name == joint.body2).filter(|b| b.kind == BodyKind::Dynamic).ok_or_else(|| {
        ctx.err(r.joint.span(), format!("{o}: the trolley of joint `{}` (its `body2`, `{}`) must be a dynamic body", joint.name, joint.body2))
    })?;

    // The hoist cable and its payload.
    let Some(cable) = cables.iter().find(|c| &c.name == r.cable.get_ref()) else {
        let known: Vec<&str> = cables.iter().map(|c| c.name.as_str()).collect();
        let known = if known.is_empty() { "no cables are defined".to_string() } else { format!("known cables: {}", list(&known)) };
        return Err(ctx.err(r.cable.span(), format!("{o}: unknown cable `{}` ({known})", r.cable.get_ref())));
    };
    if !matches!(&cable.start, CableEnd::Body { body, .. } if *body == trolley.name) {
        return Err(ctx.err(
            r.cable.span(),
            format!("{o}: cable `{}` must start on the trolley `{}` (the sway is measured from the cable's start to its end)", cable.name, trolley.name),
        ));
    }
    let payload = match &cable.end {
        CableEnd::Body { body, .. } => bodies.iter().find(|b| &b.name == body && b.kind == BodyKind::Dynamic),
        _ => None,
    }
    .ok_or_else(|| ctx.err(r.cable.span(), format!("{o}: cable `{}` must end on a dynamic body, the payload whose sway is measured", cable.name)))?;

    // The reference.
    let target = ctx.table(&r.target, o, "target", "[[t, x], ...] (s, m along the rail)", |d| ctx.datum_num(d, o, "target", "position"))?;
    let need = |v: &Option<S<f64>>, field: &str, unit: &str| -> Res<f64> {
        let v = ctx.need(v, raw.span(), o, field, &format!(" ({unit})"))?;
        ctx.check(v, o, field, Rule::Positive, unit)
    };
    let max_speed = need(&r.max_speed, "max_speed", "m/s")?;
    let max_acceleration = need(&r.max_acceleration, "max_acceleration", "m/s²")?;
    let max_force = need(&r.max_force, "max_force", "N")?;
    let sample_time = match &r.sample_time {
        Some(v) => {
            let x = ctx.check(v, o, "sample_time", Rule::Positive, "s")?;
            if x > sim.duration {
                return Err(ctx.err(v.span(), format!("{o}: `sample_time` must be at most the duration {} s, found {}", fmt_num(sim.duration), fmt_num(x))));
            }
            x
        }
        None => sim.dt,
    };

    // Fields that belong to other types.
    let why = |what: &str| format!("does not apply to a `{t}` controller ({what})");
    let shaper_only = [("frequency", &r.frequency), ("damping", &r.damping)];
    let pid_only = [("kp", &r.kp), ("ki", &r.ki), ("kd", &r.kd), ("sway_kp", &r.sway_kp), ("sway_ki", &r.sway_ki), ("sway_kd", &r.sway_kd)];
    let nonlinear_only = [("p_gain", &r.p_gain), ("d_gain", &r.d_gain), ("e_p", &r.e_p), ("e_i", &r.e_i)];
    if kind.is_shaper() {
        for (field, v) in pid_only.iter().chain(&nonlinear_only) {
            ctx.forbid(v, o, field, &why("input shapers take `frequency` and `damping`"))?;
        }
    } else {
        for (field, v) in shaper_only {
            ctx.forbid(v, o, field, &why("the PIDs take gains"))?;
        }
        if kind != ControllerKind::PidNonlinear {
            for (field, v) in nonlinear_only {
                ctx.forbid(v, o, field, &why("only `pid_nonlinear` schedules its gains"))?;
            }
        }
    }

    // The crane, for the defaults: the trolley, the payload, the rope.
    let g = sim.gravity.length();
    let distance = cable.path.first().map_or(0.0, |p| p.distance(payload.position));
    let crane = OverheadCrane::with_rope_mass(trolley.mass.unwrap_or(0.0), payload.mass.unwrap_or(0.0), distance, cable.linear_density, cable.length)
        .map(|mut c| {
            c.gravity = g;
            c
        })
        .ok()
        .filter(|c| c.pendulum_frequency().is_finite() && c.pendulum_frequency() > 0.0);
    let no_default = |field: &str| {
        ctx.err(
            raw.span(),
            format!("{o}: `{field}` has no default here: it comes from the crane (trolley and payload masses, the payload hanging below the trolley, gravity), which this file does not give; set `{field}`"),
        )
    };
    let omega0 = crane.as_ref().map(|c| c.pendulum_frequency());

    let frequency = match &r.frequency {
        Some(v) => ctx.check(v, o, "frequency", Rule::Positive, "Hz")?,
        None if kind.is_shaper() => omega0.ok_or_else(|| no_default("frequency"))? / (2.0 * std::f64::consts::PI),
        None => 0.0,
    };
    let damping = match &r.damping {
        Some(v) => {
            let z = ctx.num(v, o, "damping")?;
            if !(0.0..1.0).contains(&z) {
                return Err(ctx.err(v.span(), format!("{o}: `damping` (the shaper's damping ratio) must be at least 0 and less than 1, found {}", fmt_num(z))));
            }
            z
        }
        None => 0.0,
    };

    let (mut position, mut sway) = (PidGains::default(), PidGains::default());
    if !kind.is_shaper() {
        let placed = crane.as_ref().map(|c| {
            let w = c.pendulum_frequency();
            let (mut p, s) = DoubleLoopPid::place_poles(c, DEFAULT_POLES.map(|(k, z)| (k * w, z)));
            p.ki = DEFAULT_KI_RATIO * p.kp;
            (p, s)
        });
        let gain = |v: &Option<S<f64>>, field: &str, pick: fn(&(PidGains, PidGains)) -> f64| -> Res<f64> {
            match v {
                Some(v) => ctx.num(v, o, field),
                None => placed.as_ref().map(pick).ok_or_else(|| no_default(field)),
            }
        };
        position = PidGains { kp: gain(&r.kp, "kp", |g| g.0.kp)?, ki: gain(&r.ki, "ki", |g| g.0.ki)?, kd: gain(&r.kd, "kd", |g| g.0.kd)? };
        sway = PidGains {
            kp: gain(&r.sway_kp, "sway_kp", |g| g.1.kp)?,
            ki: gain(&r.sway_ki, "sway_ki", |g| g.1.ki)?,
            kd: gain(&r.sway_kd, "sway_kd", |g| g.1.kd)?,
        };
    }
    let d = DEFAULT_SCHEDULE;
    let schedule = NonlinearSchedule {
        p_gain: ctx.check_or(&r.p_gain, o, "p_gain", Rule::NonNegative, "", d.p_gain)?,
        d_gain: ctx.check_or(&r.d_gain, o, "d_gain", Rule::NonNegative, "", d.d_gain)?,
        e_p: ctx.check_or(&r.e_p, o, "e_p", Rule::Positive, "m", d.e_p)?,
        e_i: ctx.check_or(&r.e_i, o, "e_i", Rule::Positive, "m", d.e_i)?,
    };
    Ok(Controller {
        name,
        kind,
        joint: joint.name.clone(),
        cable: cable.name.clone(),
        payload: payload.name.clone(),
        target: target.into_iter().collect(),
        max_speed,
        max_acceleration,
        max_force,
        frequency,
        damping,
        sample_time,
        position,
        sway,
        schedule,
        location: ctx.loc(raw.span()),
    })
}
