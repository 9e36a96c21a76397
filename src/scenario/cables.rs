//! Validation of `[[cable]]` (materials, ends, initial path) and `[[winch]]`.

use crate::cable::MAX_SEGMENTS;
use std::collections::HashMap;
use std::ops::Range;

use glam::DVec3;

use super::bodies::unknown_body;
use super::raw::{RawCable, RawEnd, RawWinch, S};
use super::types::{Body, Cable, CableEnd, CableSide, PointLoad, TimeSeries, Winch};
use super::validate::{fmt_num, fmt_vec, list, Ctx, Res, Rule};
use super::Location;
use crate::cable::{preset, PRESET_NAMES};

/// Distance within which a path end and an attachment point coincide, m.
const COINCIDE: f64 = 1e-3;

/// All `[[cable]]` tables.
pub(crate) fn cables(ctx: &Ctx<'_>, raw: &[S<RawCable>], bodies: &[Body]) -> Res<Vec<Cable>> {
    let mut seen = HashMap::new();
    raw.iter().map(|c| cable(ctx, c, bodies, &mut seen)).collect()
}

fn cable(ctx: &Ctx<'_>, raw: &S<RawCable>, bodies: &[Body], seen: &mut HashMap<String, Location>) -> Res<Cable> {
    let r = raw.get_ref();
    let name = ctx.name(&r.name, "cable", seen)?;
    let o = format!("cable `{name}`");
    let o = o.as_str();
    let length = ctx.check(&r.length, o, "length", Rule::Positive, "m")?;
    let n = *r.segments.get_ref();
    let segments = u32::try_from(n)
        .ok()
        .filter(|n| (1..=MAX_SEGMENTS as u32).contains(n))
        .ok_or_else(|| ctx.err(r.segments.span(), format!("{o}: `segments` must be between 1 and {MAX_SEGMENTS}, found {n}")))?;
    let diameter = ctx.check(&r.diameter, o, "diameter", Rule::Positive, "m")?;
    let section = match &r.material {
        Some(m) => Some(
            preset(m.get_ref(), diameter)
                .ok_or_else(|| ctx.err(m.span(), format!("{o}: unknown material `{}`; valid presets: {}", m.get_ref(), list(PRESET_NAMES))))?,
        ),
        None => None,
    };
    // Explicit fields override the preset; without a preset they are required.
    let prop = |v: &Option<S<f64>>, field: &str, unit: &str, from_preset: Option<f64>| -> Res<f64> {
        match (v, from_preset) {
            (Some(v), _) => ctx.check(v, o, field, Rule::Positive, unit),
            (None, Some(x)) => Ok(x),
            (None, None) => Err(ctx.err(raw.span(), format!("{o}: missing field `{field}` (give it, or a `material` preset)"))),
        }
    };
    let linear_density = prop(&r.linear_density, "linear_density", "kg/m", section.map(|s| s.linear_density))?;
    let ea = prop(&r.ea, "ea", "N", section.map(|s| s.ea))?;
    let ei = prop(&r.ei, "ei", "N·m²", section.map(|s| s.ei))?;
    let gj = prop(&r.gj, "gj", "N·m²", section.map(|s| s.gj))?;
    let ei2 = prop(&r.ei2, "ei2", "N·m²", Some(ei))?;
    let shear_stiffness = r.shear_stiffness.as_ref().map(|v| ctx.check(v, o, "shear_stiffness", Rule::Positive, "N")).transpose()?;
    let start = end(ctx, &r.start, o, "start", bodies)?;
    let end_ = end(ctx, &r.end, o, "end", bodies)?;
    let path = path(ctx, raw, o, length, &start, &end_, bodies)?;
    Ok(Cable {
        name,
        length,
        segments,
        diameter,
        material: r.material.as_ref().map(|m| m.get_ref().clone()),
        linear_density,
        ea,
        ei,
        ei2,
        gj,
        shear_stiffness,
        damping: ctx.check_or(&r.damping, o, "damping", Rule::NonNegative, "s", 0.0)?,
        linear_damping: ctx.check_or(&r.linear_damping, o, "linear_damping", Rule::NonNegative, "1/s", 0.0)?,
        angular_damping: ctx.check_or(&r.angular_damping, o, "angular_damping", Rule::NonNegative, "1/s", 0.0)?,
        end_stiffness: ctx.check_or(&r.end_stiffness, o, "end_stiffness", Rule::Positive, "(multiple of EA/L_e)", crate::cable::END_STIFFNESS_FACTOR)?,
        friction: ctx.check_or(&r.friction, o, "friction", Rule::NonNegative, "", 0.3)?,
        drag_normal: ctx.check_or(&r.drag_normal, o, "drag_normal", Rule::NonNegative, "", 1.2)?,
        drag_tangential: ctx.check_or(&r.drag_tangential, o, "drag_tangential", Rule::NonNegative, "", 0.008)?,
        added_mass: ctx.check_or(&r.added_mass, o, "added_mass", Rule::NonNegative, "", 1.0)?,
        start,
        end: end_,
        path,
        contacts: r.contacts.as_ref().is_none_or(|c| *c.get_ref()),
        collision_groups: ctx.groups(&r.collision_groups, o)?,
        loads: loads(ctx, r, o, length)?,
        stress_free: r.stress_free.as_ref().is_some_and(|c| *c.get_ref()),
        tension_only: r.tension_only.as_ref().is_none_or(|c| *c.get_ref()),
        location: ctx.loc(raw.span()),
    })
}

/// The `loads = [{ s, force, moment }, ...]` list.
fn loads(ctx: &Ctx<'_>, r: &RawCable, o: &str, length: f64) -> Res<Vec<PointLoad>> {
    let Some(list) = &r.loads else {
        return Ok(Vec::new());
    };
    let mut out = Vec::with_capacity(list.get_ref().len());
    for (i, item) in list.get_ref().iter().enumerate() {
        let l = item.get_ref();
        let o = &format!("{o}: load {}", i + 1);
        let s = ctx.check(&l.s, o, "s", Rule::NonNegative, "m")?;
        if s > length {
            return Err(ctx.err(l.s.span(), format!("{o}: `s` must be at most the cable's `length` {} m, found {}", fmt_num(length), fmt_num(s))));
        }
        out.push(PointLoad { s, force: ctx.vec3(&l.force, o, "force", "N")?, moment: ctx.vec3_or(&l.moment, o, "moment", "N·m", DVec3::ZERO)? });
    }
    Ok(out)
}

/// A `start`/`end` table.
fn end(ctx: &Ctx<'_>, raw: &Option<S<RawEnd>>, o: &str, field: &str, bodies: &[Body]) -> Res<CableEnd> {
    let Some(raw) = raw else {
        return Ok(CableEnd::Free);
    };
    let r = raw.get_ref();
    let o = &format!("{o}: `{field}`");
    let clamp = r.clamp.as_ref().is_some_and(|c| *c.get_ref());
    match (&r.body, &r.world) {
        (Some(b), None) => {
            let anchor = ctx.vec3_or(&r.anchor, o, "anchor", "m, body frame", DVec3::ZERO)?;
            if b.get_ref() == "world" {
                return Ok(CableEnd::World { point: anchor, clamp });
            }
            if !bodies.iter().any(|x| &x.name == b.get_ref()) {
                return Err(unknown_body(ctx, b, o, bodies));
            }
            Ok(CableEnd::Body { body: b.get_ref().clone(), anchor, clamp })
        }
        (None, Some(w)) => {
            ctx.forbid(&r.anchor, o, "anchor", "only applies with `body` (use `world = [x, y, z]` alone)")?;
            Ok(CableEnd::World { point: ctx.vec3(w, o, "world", "m")?, clamp })
        }
        (Some(_), Some(w)) => Err(ctx.err(w.span(), format!("{o}: give either `body` or `world`, not both"))),
        (None, None) => {
            Err(ctx.err(raw.span(), format!("{o}: needs `body = NAME, anchor = [x, y, z]` or `world = [x, y, z]` (omit `{field}` for a free end)")))
        }
    }
}

/// World position at t = 0 of an attached end.
fn end_point(e: &CableEnd, bodies: &[Body]) -> Option<DVec3> {
    match e {
        CableEnd::Free => None,
        CableEnd::World { point, .. } => Some(*point),
        CableEnd::Body { body, anchor, .. } => bodies.iter().find(|b| &b.name == body).map(|b| b.world_point(*anchor)),
    }
}

/// The initial centerline: the file's `path` checked against the ends, or
/// the default straight line.
fn path(ctx: &Ctx<'_>, raw: &S<RawCable>, o: &str, length: f64, start: &CableEnd, end: &CableEnd, bodies: &[Body]) -> Res<Vec<DVec3>> {
    let r = raw.get_ref();
    let (p_start, p_end) = (end_point(start, bodies), end_point(end, bodies));
    let Some(path) = &r.path else {
        let Some(a) = p_start else {
            return Err(ctx.err(raw.span(), format!("{o}: a cable with a free `start` needs a `path` [[x, y, z], ...]")));
        };
        let path = match p_end {
            None => vec![a, a - DVec3::Y * length],
            Some(b) if a.distance(b) > COINCIDE => vec![a, b],
            Some(b) => return Err(ctx.err(raw.span(), format!("{o}: the start and end points coincide at {}; give a `path`", fmt_vec(b)))),
        };
        if !path.iter().all(|p| p.is_finite()) {
            return Err(ctx.err(raw.span(), format!("{o}: the default path {} to {} is not finite (numbers too large)", fmt_vec(path[0]), fmt_vec(path[1]))));
        }
        return Ok(path);
    };
    let items = path.get_ref();
    if items.len() < 2 {
        return Err(ctx.err(path.span(), format!("{o}: `path` must have at least 2 points, found {}", items.len())));
    }
    let mut points = Vec::with_capacity(items.len());
    for (i, p) in items.iter().enumerate() {
        let x = ctx.vec3(p, o, "path", "m")?;
        if let Some(prev) = points.last() {
            if x == *prev {
                return Err(ctx.err(p.span(), format!("{o}: `path` points {} and {} coincide at {}", i, i + 1, fmt_vec(x))));
            }
        }
        points.push(x);
    }
    let spans: Vec<Range<usize>> = items.iter().map(|p| p.span()).collect();
    let ends = [("first", "start", p_start, points.first(), spans.first()), ("last", "end", p_end, points.last(), spans.last())];
    for (which, field, attach, point, span) in ends {
        if let (Some(a), Some(p), Some(span)) = (attach, point, span) {
            let d = a.distance(*p);
            if d > COINCIDE {
                return Err(ctx.err(
                    span.clone(),
                    format!(
                        "{o}: the {which} point of `path` {} does not coincide with the `{field}` attachment point {} (distance {} m; tolerance 1 mm)",
                        fmt_vec(*p),
                        fmt_vec(a),
                        fmt_num(d)
                    ),
                ));
            }
        }
    }
    Ok(points)
}

/// All `[[winch]]` tables.
pub(crate) fn winches(ctx: &Ctx<'_>, raw: &[S<RawWinch>], cables: &[Cable]) -> Res<Vec<Winch>> {
    let mut seen = HashMap::new();
    let mut ends: HashMap<(String, bool), String> = HashMap::new();
    let mut out = Vec::with_capacity(raw.len());
    for w in raw {
        let winch = winch(ctx, w, cables, &mut seen)?;
        let key = (winch.cable.clone(), winch.at == CableSide::Start);
        if let Some(other) = ends.get(&key) {
            return Err(
                ctx.err(w.get_ref().at.span(), format!("winch `{}`: that end of cable `{}` is already wound on winch `{other}`", winch.name, winch.cable))
            );
        }
        ends.insert(key, winch.name.clone());
        out.push(winch);
    }
    Ok(out)
}

fn winch(ctx: &Ctx<'_>, raw: &S<RawWinch>, cables: &[Cable], seen: &mut HashMap<String, Location>) -> Res<Winch> {
    let r = raw.get_ref();
    let name = ctx.name(&r.name, "winch", seen)?;
    let o = format!("winch `{name}`");
    let o = o.as_str();
    let Some(cable) = cables.iter().find(|c| &c.name == r.cable.get_ref()) else {
        let known: Vec<&str> = cables.iter().map(|c| c.name.as_str()).collect();
        let known = if known.is_empty() { "no cables are defined".into() } else { format!("known cables: {}", list(&known)) };
        return Err(ctx.err(r.cable.span(), format!("{o}: unknown cable `{}` ({known})", r.cable.get_ref())));
    };
    let at = match ctx.choice(&r.at, o, "cable end", &["start", "end"])? {
        "start" => CableSide::Start,
        _ => CableSide::End,
    };
    let held = if at == CableSide::Start { &cable.start } else { &cable.end };
    if *held == CableEnd::Free {
        return Err(ctx.err(
            r.at.span(),
            format!("{o}: the `{}` of cable `{}` is free; a winch needs an end attached to a body or the world", r.at.get_ref(), cable.name),
        ));
    }
    let speed = ctx.table(&r.speed, o, "speed", "[[t, v], ...] (s, m/s)", |d| ctx.datum_num(d, o, "speed", "speed"))?;
    let min_length = ctx.opt(&r.min_length, o, "min_length")?;
    let max_length = ctx.opt(&r.max_length, o, "max_length")?;
    if let (Some(v), Some(x)) = (&r.min_length, min_length) {
        ctx.check(v, o, "min_length", Rule::NonNegative, "m")?;
        if x > cable.length {
            return Err(ctx.err(v.span(), format!("{o}: `min_length` {} m is above the cable's initial length {} m", fmt_num(x), fmt_num(cable.length))));
        }
    }
    if let (Some(v), Some(x)) = (&r.max_length, max_length) {
        ctx.check(v, o, "max_length", Rule::Positive, "m")?;
        if x < cable.length {
            return Err(ctx.err(v.span(), format!("{o}: `max_length` {} m is below the cable's initial length {} m", fmt_num(x), fmt_num(cable.length))));
        }
    }
    if let (Some(lo), Some(hi), Some(v)) = (min_length, max_length, &r.max_length) {
        if lo >= hi {
            return Err(ctx.err(v.span(), format!("{o}: `min_length` must be less than `max_length`, found {} and {}", fmt_num(lo), fmt_num(hi))));
        }
    }
    Ok(Winch {
        name,
        cable: cable.name.clone(),
        at,
        drum_radius: ctx.check(&r.drum_radius, o, "drum_radius", Rule::Positive, "m")?,
        drum_inertia: ctx.check(&r.drum_inertia, o, "drum_inertia", Rule::NonNegative, "kg·m²")?,
        max_torque: ctx.check(&r.max_torque, o, "max_torque", Rule::Positive, "N·m")?,
        speed: TimeSeries { points: speed },
        brake: r.brake.as_ref().is_none_or(|b| *b.get_ref()),
        min_length,
        max_length,
        location: ctx.loc(raw.span()),
    })
}
