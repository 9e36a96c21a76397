//! Validation of `[[body]]` and `[[joint]]`.

use std::collections::HashMap;

use glam::{DQuat, DVec3, EulerRot};

use super::raw::{RawBody, RawDrive, RawJoint, RawMotion, S};
use super::types::{Body, BodyKind, Drive, Joint, JointKind, Motion, Shape, TimeSeries};
use super::validate::{fmt_num, fmt_vec, list, Ctx, Res, Rule};

/// Orientation from XYZ Euler angles in degrees: R = Rx·Ry·Rz.
pub(crate) fn euler_xyz_deg(deg: DVec3) -> DQuat {
    DQuat::from_euler(EulerRot::XYZ, deg.x.to_radians(), deg.y.to_radians(), deg.z.to_radians())
}

/// Error "unknown body" listing the known ones.
pub(crate) fn unknown_body(ctx: &Ctx<'_>, v: &S<String>, owner: &str, bodies: &[Body]) -> super::ScenarioError {
    let known: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
    let known = if known.is_empty() { "no bodies are defined".to_string() } else { format!("known bodies: {}", list(&known)) };
    ctx.err(v.span(), format!("{owner}: unknown body `{}` ({known}; `world` is the ground)", v.get_ref()))
}

/// All `[[body]]` tables.
pub(crate) fn bodies(ctx: &Ctx<'_>, raw: &[S<RawBody>]) -> Res<Vec<Body>> {
    let mut seen = HashMap::new();
    raw.iter().map(|b| body(ctx, b, &mut seen)).collect()
}

fn body(ctx: &Ctx<'_>, raw: &S<RawBody>, seen: &mut HashMap<String, super::Location>) -> Res<Body> {
    let r = raw.get_ref();
    if r.name.get_ref() == "world" {
        return Err(ctx.err(r.name.span(), "`world` is reserved for the ground and cannot be a body name"));
    }
    let name = ctx.name(&r.name, "body", seen)?;
    let o = format!("body `{name}`");
    let o = o.as_str();
    let kind = match ctx.choice(&r.kind, o, "body type", &["dynamic", "fixed", "kinematic"])? {
        "dynamic" => BodyKind::Dynamic,
        "fixed" => BodyKind::Fixed,
        _ => BodyKind::Kinematic,
    };
    let shape = shape(ctx, raw, o)?;
    let mass = match kind {
        BodyKind::Dynamic => {
            let m = ctx.need(&r.mass, raw.span(), o, "mass", " (required for a dynamic body)")?;
            Some(ctx.check(m, o, "mass", Rule::Positive, "kg")?)
        }
        _ => {
            ctx.forbid(&r.mass, o, "mass", "is only allowed for dynamic bodies")?;
            None
        }
    };
    if kind != BodyKind::Dynamic {
        let why = "is only allowed for dynamic bodies (a kinematic body moves by its `motion`)";
        ctx.forbid(&r.linear_velocity, o, "linear_velocity", why)?;
        ctx.forbid(&r.angular_velocity, o, "angular_velocity", why)?;
    }
    let motion = match &r.motion {
        Some(m) if kind == BodyKind::Kinematic => Some(motion(ctx, m, o)?),
        Some(m) => return Err(ctx.err(m.span(), format!("{o}: `motion` is only allowed for kinematic bodies"))),
        None => None,
    };
    let mut position = ctx.vec3_or(&r.position, o, "position", "m", DVec3::ZERO)?;
    if let Some(Motion::Table { points }) = &motion {
        let p0 = points.first().map_or(position, |p| p.1);
        match &r.position {
            Some(p) if position.distance(p0) > 1e-3 => {
                return Err(
                    ctx.err(p.span(), format!("{o}: `position` {} differs from the motion table's position at t = 0, {}", fmt_vec(position), fmt_vec(p0)))
                )
            }
            _ => position = p0,
        }
    }
    let rotation = ctx.vec3_or(&r.rotation, o, "rotation", "degrees", DVec3::ZERO)?;
    let angular = ctx.vec3_or(&r.angular_velocity, o, "angular_velocity", "deg/s", DVec3::ZERO)?;
    Ok(Body {
        name,
        kind,
        shape,
        mass,
        position,
        rotation: euler_xyz_deg(rotation),
        linear_velocity: ctx.vec3_or(&r.linear_velocity, o, "linear_velocity", "m/s", DVec3::ZERO)?,
        angular_velocity: angular * std::f64::consts::PI / 180.0,
        friction: ctx.check_or(&r.friction, o, "friction", Rule::NonNegative, "", 0.5)?,
        restitution: ctx.check_or(&r.restitution, o, "restitution", Rule::Between(0.0, 1.0), "", 0.0)?,
        collision_groups: ctx.groups(&r.collision_groups, o)?,
        wind_area: ctx.check_or(&r.wind_area, o, "wind_area", Rule::NonNegative, "m²", 0.0)?,
        wind_coefficient: ctx.check_or(&r.wind_coefficient, o, "wind_coefficient", Rule::NonNegative, "", 0.0)?,
        motion,
        location: ctx.loc(raw.span()),
    })
}

fn shape(ctx: &Ctx<'_>, raw: &S<RawBody>, o: &str) -> Res<Shape> {
    let r = raw.get_ref();
    let at = raw.span();
    let shape = ctx.choice(&r.shape, o, "shape", &["ball", "cuboid", "capsule", "cylinder"])?;
    let why = format!("does not apply to a `{shape}` shape");
    let radius = |why_missing: &str| -> Res<f64> {
        let v = ctx.need(&r.radius, at.clone(), o, "radius", why_missing)?;
        ctx.check(v, o, "radius", Rule::Positive, "m")
    };
    Ok(match shape {
        "ball" => {
            ctx.forbid(&r.half_extents, o, "half_extents", &why)?;
            ctx.forbid(&r.half_height, o, "half_height", &why)?;
            Shape::Ball { radius: radius(" (required for a ball)")? }
        }
        "cuboid" => {
            ctx.forbid(&r.radius, o, "radius", &why)?;
            ctx.forbid(&r.half_height, o, "half_height", &why)?;
            let v = ctx.need(&r.half_extents, at.clone(), o, "half_extents", " (required for a cuboid)")?;
            let h = ctx.vec3(v, o, "half_extents", "m")?;
            if h.min_element() <= 0.0 {
                return Err(ctx.err(v.span(), format!("{o}: `half_extents` must all be greater than 0 m, found {}", fmt_vec(h))));
            }
            Shape::Cuboid { half_extents: h }
        }
        _ => {
            ctx.forbid(&r.half_extents, o, "half_extents", &why)?;
            let missing = format!(" (required for a {shape})");
            let radius = radius(&missing)?;
            let v = ctx.need(&r.half_height, at.clone(), o, "half_height", &missing)?;
            let half_height = ctx.check(v, o, "half_height", Rule::Positive, "m")?;
            if shape == "capsule" {
                Shape::Capsule { radius, half_height }
            } else {
                Shape::Cylinder { radius, half_height }
            }
        }
    })
}

fn motion(ctx: &Ctx<'_>, raw: &S<RawMotion>, o: &str) -> Res<Motion> {
    let r = raw.get_ref();
    let at = raw.span();
    let o = &format!("{o}: motion");
    let kind = ctx.choice(&r.kind, o, "motion type", &["sine", "table", "spin"])?;
    if kind != "spin" {
        let why = format!("does not apply to a `{kind}` motion");
        ctx.forbid(&r.axis, o, "axis", &why)?;
        ctx.forbid(&r.rate, o, "rate", &why)?;
    }
    match kind {
        "sine" => {
            let why = "does not apply to a `sine` motion";
            ctx.forbid(&r.points, o, "points", why)?;
            let a = ctx.need(&r.amplitude, at.clone(), o, "amplitude", " (required for a sine)")?;
            let p = ctx.need(&r.period, at.clone(), o, "period", " (required for a sine)")?;
            Ok(Motion::Sine {
                amplitude: ctx.vec3(a, o, "amplitude", "m")?,
                period: ctx.check(p, o, "period", Rule::Positive, "s")?,
                phase: ctx.opt(&r.phase, o, "phase")?.unwrap_or(0.0).to_radians(),
            })
        }
        "spin" => {
            let why = "does not apply to a `spin` motion";
            ctx.forbid(&r.amplitude, o, "amplitude", why)?;
            ctx.forbid(&r.period, o, "period", why)?;
            ctx.forbid(&r.phase, o, "phase", why)?;
            ctx.forbid(&r.points, o, "points", why)?;
            let a = ctx.need(&r.axis, at.clone(), o, "axis", " (required for a spin)")?;
            let axis = ctx.vec3(a, o, "axis", "world frame")?;
            let Some(axis) = axis.try_normalize().filter(|_| axis.length() >= 1e-9) else {
                return Err(ctx.err(a.span(), format!("{o}: `axis` must be a nonzero direction, found {}", fmt_vec(axis))));
            };
            let rate = ctx.need(&r.rate, at, o, "rate", " (required for a spin)")?;
            let points = ctx.table(rate, o, "rate", "[[t, rate], ...] (s, deg/s)", |d| Ok(ctx.datum_num(d, o, "rate", "rate")?.to_radians()))?;
            Ok(Motion::Spin { axis, rate: TimeSeries { points } })
        }
        _ => {
            let why = "does not apply to a `table` motion";
            ctx.forbid(&r.amplitude, o, "amplitude", why)?;
            ctx.forbid(&r.period, o, "period", why)?;
            ctx.forbid(&r.phase, o, "phase", why)?;
            let pts = ctx.need(&r.points, at, o, "points", " (required for a table)")?;
            let points = ctx.table(pts, o, "points", "[[t, [x, y, z]], ...] (s, m)", |d| ctx.datum_vec3(d, o, "points"))?;
            Ok(Motion::Table { points })
        }
    }
}

/// All `[[joint]]` tables.
pub(crate) fn joints(ctx: &Ctx<'_>, raw: &[S<RawJoint>], bodies: &[Body]) -> Res<Vec<Joint>> {
    let mut seen = HashMap::new();
    raw.iter().map(|j| joint(ctx, j, bodies, &mut seen)).collect()
}

fn joint(ctx: &Ctx<'_>, raw: &S<RawJoint>, bodies: &[Body], seen: &mut HashMap<String, super::Location>) -> Res<Joint> {
    let r = raw.get_ref();
    let name = ctx.name(&r.name, "joint", seen)?;
    let o = format!("joint `{name}`");
    let o = o.as_str();
    let kind = match ctx.choice(&r.kind, o, "joint type", &["fixed", "revolute", "prismatic", "spherical"])? {
        "fixed" => JointKind::Fixed,
        "revolute" => JointKind::Revolute,
        "prismatic" => JointKind::Prismatic,
        _ => JointKind::Spherical,
    };
    for b in [&r.body1, &r.body2] {
        if b.get_ref() != "world" && !bodies.iter().any(|x| &x.name == b.get_ref()) {
            return Err(unknown_body(ctx, b, o, bodies));
        }
    }
    if r.body1.get_ref() == r.body2.get_ref() {
        return Err(ctx.err(r.body2.span(), format!("{o}: `body1` and `body2` are both `{}`; a joint needs two different bodies", r.body2.get_ref())));
    }
    let has_axis = matches!(kind, JointKind::Revolute | JointKind::Prismatic);
    let (axis, limits, drive) = if has_axis {
        let v = ctx.need(&r.axis, raw.span(), o, "axis", " (required for revolute and prismatic joints)")?;
        let a = ctx.vec3(v, o, "axis", "body1 frame")?;
        let Some(a) = a.try_normalize().filter(|_| a.length() >= 1e-9) else {
            return Err(ctx.err(v.span(), format!("{o}: `axis` must be a nonzero direction, found {}", fmt_vec(a))));
        };
        let revolute = kind == JointKind::Revolute;
        let limits = match &r.limits {
            Some(l) => {
                let unit = if revolute { "degrees" } else { "m" };
                let items = l.get_ref();
                if items.len() != 2 {
                    return Err(ctx.err(l.span(), format!("{o}: `limits` must be [min, max] ({unit}), found {} numbers", items.len())));
                }
                let (lo, hi) = (ctx.num(&items[0], o, "limits")?, ctx.num(&items[1], o, "limits")?);
                if lo >= hi {
                    return Err(ctx.err(l.span(), format!("{o}: `limits` must have min < max, found [{}, {}]", fmt_num(lo), fmt_num(hi))));
                }
                Some(if revolute { [lo.to_radians(), hi.to_radians()] } else { [lo, hi] })
            }
            None => None,
        };
        let drive = r.drive.as_ref().map(|d| drive(ctx, d, o, revolute)).transpose()?;
        (Some(a), limits, drive)
    } else {
        let why = "only applies to revolute and prismatic joints";
        ctx.forbid(&r.axis, o, "axis", why)?;
        ctx.forbid(&r.limits, o, "limits", why)?;
        ctx.forbid(&r.drive, o, "drive", why)?;
        (None, None, None)
    };
    Ok(Joint {
        name,
        kind,
        body1: r.body1.get_ref().clone(),
        body2: r.body2.get_ref().clone(),
        anchor1: ctx.vec3_or(&r.anchor1, o, "anchor1", "m", DVec3::ZERO)?,
        anchor2: ctx.vec3_or(&r.anchor2, o, "anchor2", "m", DVec3::ZERO)?,
        axis,
        limits,
        drive,
        location: ctx.loc(raw.span()),
    })
}

fn drive(ctx: &Ctx<'_>, raw: &S<RawDrive>, o: &str, revolute: bool) -> Res<Drive> {
    let r = raw.get_ref();
    let o = &format!("{o}: drive");
    match (&r.force, &r.velocity) {
        (Some(f), None) => {
            ctx.forbid(&r.max_force, o, "max_force", "only applies to a `velocity` drive")?;
            let shape = if revolute { "[[t, torque], ...] (s, N·m)" } else { "[[t, F], ...] (s, N)" };
            let points = ctx.table(f, o, "force", shape, |d| ctx.datum_num(d, o, "force", "force"))?;
            Ok(Drive::Force { force: TimeSeries { points } })
        }
        (None, Some(v)) => {
            let shape = if revolute { "[[t, v], ...] (s, deg/s)" } else { "[[t, v], ...] (s, m/s)" };
            let scale = if revolute { std::f64::consts::PI / 180.0 } else { 1.0 };
            let points = ctx.table(v, o, "velocity", shape, |d| Ok(ctx.datum_num(d, o, "velocity", "velocity")? * scale))?;
            let m = ctx.need(&r.max_force, raw.span(), o, "max_force", " (required for a `velocity` drive)")?;
            let unit = if revolute { "N·m" } else { "N" };
            Ok(Drive::Velocity { velocity: TimeSeries { points }, max_force: ctx.check(m, o, "max_force", Rule::Positive, unit)? })
        }
        (Some(_), Some(v)) => Err(ctx.err(v.span(), format!("{o}: give either `force` or `velocity`, not both"))),
        (None, None) => Err(ctx.err(raw.span(), format!("{o}: needs `force = [[t, F], ...]` or `velocity = [[t, v], ...]`"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenario_euler_xyz_is_rx_ry_rz() {
        let (a, b, c) = (30.0_f64, -50.0_f64, 75.0_f64);
        let q = euler_xyz_deg(DVec3::new(a, b, c));
        let r = DQuat::from_rotation_x(a.to_radians()) * DQuat::from_rotation_y(b.to_radians()) * DQuat::from_rotation_z(c.to_radians());
        assert!(q.dot(r).abs() > 1.0 - 1e-12);
    }
}
