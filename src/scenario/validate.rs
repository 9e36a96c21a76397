//! Validation of the raw file: shared helpers, `[simulation]`,
//! `[environment]` and the order in which the sections are checked.

use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;

use glam::DVec3;

use super::error::ScenarioError;
use super::raw::{Datum, RawEnvironment, RawGroups, RawScenario, RawSimulation, Vector, S};
use super::span::{LineIndex, Location};
use super::types::{CollisionGroups, Environment, IntegratorChoice, Scenario, Simulation, INTEGRATOR_NAMES};

/// Result of a validation step.
pub(crate) type Res<T> = Result<T, ScenarioError>;

/// The file being validated, for errors with positions.
pub(crate) struct Ctx<'a> {
    file: &'a Path,
    src: &'a str,
    index: LineIndex<'a>,
}

impl<'a> Ctx<'a> {
    pub(crate) fn new(file: &'a Path, src: &'a str) -> Self {
        Ctx { file, src, index: LineIndex::new(src) }
    }

    /// An error at `span`.
    pub(crate) fn err(&self, span: Range<usize>, msg: impl Into<String>) -> ScenarioError {
        ScenarioError::new(self.file, self.src, span, msg)
    }

    /// Line and column of `span`.
    pub(crate) fn loc(&self, span: Range<usize>) -> Location {
        self.index.location(span.start)
    }

    /// A finite number.
    pub(crate) fn num(&self, v: &S<f64>, owner: &str, field: &str) -> Res<f64> {
        let x = *v.get_ref();
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(v.span(), format!("{owner}: `{field}` must be a finite number, found {x}")))
        }
    }

    /// An optional finite number.
    pub(crate) fn opt(&self, v: &Option<S<f64>>, owner: &str, field: &str) -> Res<Option<f64>> {
        v.as_ref().map(|v| self.num(v, owner, field)).transpose()
    }

    /// A finite number with `ok(x)`; otherwise "`field` must be `rule` `unit`".
    pub(crate) fn check(&self, v: &S<f64>, owner: &str, field: &str, rule: Rule, unit: &str) -> Res<f64> {
        let x = self.num(v, owner, field)?;
        if rule.ok(x) {
            Ok(x)
        } else {
            let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
            Err(self.err(v.span(), format!("{owner}: `{field}` must be {}{unit}, found {}", rule.text(), fmt_num(x))))
        }
    }

    /// An optional checked number with a default.
    pub(crate) fn check_or(&self, v: &Option<S<f64>>, owner: &str, field: &str, rule: Rule, unit: &str, default: f64) -> Res<f64> {
        match v {
            Some(v) => self.check(v, owner, field, rule, unit),
            None => Ok(default),
        }
    }

    /// An optional `collision_groups = { memberships = [..], filter = [..] }`
    /// (group numbers 1 to 32; a list left out: every group).
    pub(crate) fn groups(&self, v: &Option<S<RawGroups>>, owner: &str) -> Res<CollisionGroups> {
        let Some(v) = v else {
            return Ok(CollisionGroups::default());
        };
        let mask = |list: &Option<S<Vec<S<i64>>>>, field: &str| -> Res<u32> {
            let Some(list) = list else {
                return Ok(u32::MAX);
            };
            let mut mask = 0u32;
            for g in list.get_ref() {
                let k = *g.get_ref();
                if !(1..=32).contains(&k) {
                    return Err(self.err(g.span(), format!("{owner}: `collision_groups.{field}` lists group {k}; groups are numbered 1 to 32")));
                }
                mask |= 1 << (k - 1);
            }
            Ok(mask)
        };
        let r = v.get_ref();
        Ok(CollisionGroups { memberships: mask(&r.memberships, "memberships")?, filter: mask(&r.filter, "filter")? })
    }

    /// A 3-vector of finite numbers.
    pub(crate) fn vec3(&self, v: &Vector, owner: &str, field: &str, unit: &str) -> Res<DVec3> {
        let items = v.get_ref();
        if items.len() != 3 {
            return Err(self.err(v.span(), format!("{owner}: `{field}` must have 3 components [x, y, z] ({unit}), found {}", items.len())));
        }
        let mut out = [0.0; 3];
        for (o, item) in out.iter_mut().zip(items) {
            *o = self.num(item, owner, field)?;
        }
        Ok(DVec3::from_array(out))
    }

    /// An optional 3-vector with a default.
    pub(crate) fn vec3_or(&self, v: &Option<Vector>, owner: &str, field: &str, unit: &str, default: DVec3) -> Res<DVec3> {
        v.as_ref().map_or(Ok(default), |v| self.vec3(v, owner, field, unit))
    }

    /// One of `valid`; otherwise an error listing them.
    pub(crate) fn choice<'v>(&self, v: &S<String>, owner: &str, field: &str, valid: &[&'v str]) -> Res<&'v str> {
        let s = v.get_ref().as_str();
        valid.iter().find(|x| **x == s).copied().ok_or_else(|| self.err(v.span(), format!("{owner}: unknown {field} `{s}`; expected one of {}", list(valid))))
    }

    /// Error if an optional field that does not apply is present.
    pub(crate) fn forbid<T>(&self, v: &Option<S<T>>, owner: &str, field: &str, why: &str) -> Res<()> {
        match v {
            Some(v) => Err(self.err(v.span(), format!("{owner}: `{field}` {why}"))),
            None => Ok(()),
        }
    }

    /// A required optional field.
    pub(crate) fn need<'v, T>(&self, v: &'v Option<S<T>>, at: Range<usize>, owner: &str, field: &str, why: &str) -> Res<&'v S<T>> {
        v.as_ref().ok_or_else(|| self.err(at, format!("{owner}: missing field `{field}`{why}")))
    }

    /// A non-empty name, unique in `seen` (which records it).
    pub(crate) fn name(&self, v: &S<String>, kind: &str, seen: &mut HashMap<String, Location>) -> Res<String> {
        let name = v.get_ref().clone();
        if name.trim().is_empty() {
            return Err(self.err(v.span(), format!("{kind} name must not be empty")));
        }
        let here = self.loc(v.span());
        if let Some(first) = seen.get(&name) {
            return Err(self.err(v.span(), format!("duplicate {kind} name `{name}` (first defined at line {})", first.line)));
        }
        seen.insert(name.clone(), here);
        Ok(name)
    }

    /// A piecewise-linear table `[[t, v], ...]` of finite numbers with
    /// strictly increasing times. Each value is passed through `value`.
    pub(crate) fn table<T>(&self, v: &S<Datum>, owner: &str, field: &str, shape: &str, mut value: impl FnMut(&S<Datum>) -> Res<T>) -> Res<Vec<(f64, T)>> {
        let bad = |span: Range<usize>, what: String| self.err(span, format!("{owner}: `{field}` must be a list of points {shape}; {what}"));
        let Datum::List(points) = v.get_ref() else {
            return Err(bad(v.span(), format!("found {}", v.get_ref().kind())));
        };
        if points.is_empty() {
            return Err(bad(v.span(), "found an empty list".into()));
        }
        let mut out: Vec<(f64, T)> = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            let n = i + 1;
            let pair = match p.get_ref() {
                Datum::List(pair) if pair.len() == 2 => pair,
                Datum::List(pair) => return Err(bad(p.span(), format!("point {n} has {} elements", pair.len()))),
                other => return Err(bad(p.span(), format!("point {n} is {}", other.kind()))),
            };
            let t = self.datum_num(&pair[0], owner, field, "time")?;
            if let Some(prev) = out.last() {
                if t <= prev.0 {
                    return Err(self.err(
                        pair[0].span(),
                        format!("{owner}: times in `{field}` must be strictly increasing; point {n} has t = {} after t = {}", fmt_num(t), fmt_num(prev.0)),
                    ));
                }
            }
            out.push((t, value(&pair[1])?));
        }
        Ok(out)
    }

    /// A finite number inside a table.
    pub(crate) fn datum_num(&self, d: &S<Datum>, owner: &str, field: &str, what: &str) -> Res<f64> {
        match d.get_ref() {
            Datum::Num(x) if x.is_finite() => Ok(*x),
            Datum::Num(x) => Err(self.err(d.span(), format!("{owner}: `{field}`: the {what} must be a finite number, found {x}"))),
            other => Err(self.err(d.span(), format!("{owner}: `{field}`: the {what} must be a number, found {}", other.kind()))),
        }
    }

    /// A `[x, y, z]` inside a table.
    pub(crate) fn datum_vec3(&self, d: &S<Datum>, owner: &str, field: &str) -> Res<DVec3> {
        let items = match d.get_ref() {
            Datum::List(items) if items.len() == 3 => items,
            Datum::List(items) => {
                return Err(self.err(d.span(), format!("{owner}: `{field}`: a position must have 3 components [x, y, z] (m), found {}", items.len())))
            }
            other => return Err(self.err(d.span(), format!("{owner}: `{field}`: expected a position [x, y, z] (m), found {}", other.kind()))),
        };
        let mut out = [0.0; 3];
        for (o, item) in out.iter_mut().zip(items) {
            *o = self.datum_num(item, owner, field, "coordinate")?;
        }
        Ok(DVec3::from_array(out))
    }
}

/// A range rule for a number.
#[derive(Clone, Copy)]
pub(crate) enum Rule {
    /// x > 0.
    Positive,
    /// x ≥ 0.
    NonNegative,
    /// x ≥ a.
    AtLeast(f64),
    /// a ≤ x ≤ b.
    Between(f64, f64),
}

impl Rule {
    fn ok(self, x: f64) -> bool {
        match self {
            Rule::Positive => x > 0.0,
            Rule::NonNegative => x >= 0.0,
            Rule::AtLeast(a) => x >= a,
            Rule::Between(a, b) => (a..=b).contains(&x),
        }
    }
    fn text(self) -> String {
        match self {
            Rule::Positive => "greater than 0".into(),
            Rule::NonNegative => "at least 0".into(),
            Rule::AtLeast(a) => format!("at least {}", fmt_num(a)),
            Rule::Between(a, b) => format!("between {} and {}", fmt_num(a), fmt_num(b)),
        }
    }
}

/// A number for messages: integers without decimals, others with at most
/// six decimals.
pub(crate) fn fmt_num(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".into();
    }
    if x.abs() < 1e-4 || x.abs() >= 1e15 {
        return format!("{x:e}");
    }
    if x == x.round() {
        return format!("{}", x as i64);
    }
    let s = format!("{x:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// `[x, y, z]` for messages.
pub(crate) fn fmt_vec(v: DVec3) -> String {
    format!("[{}, {}, {}]", fmt_num(v.x), fmt_num(v.y), fmt_num(v.z))
}

/// "`a`, `b`, `c`".
pub(crate) fn list<S: AsRef<str>>(names: &[S]) -> String {
    names.iter().map(|n| format!("`{}`", n.as_ref())).collect::<Vec<_>>().join(", ")
}

/// Validate the whole file.
pub(crate) fn validate(ctx: &Ctx<'_>, file: &Path, raw: RawScenario) -> Res<Scenario> {
    let simulation = simulation(ctx, &raw.simulation)?;
    let environment = match &raw.environment {
        Some(env) => environment(ctx, env.get_ref())?,
        None => Environment::default(),
    };
    let bodies = super::bodies::bodies(ctx, &raw.body)?;
    let joints = super::bodies::joints(ctx, &raw.joint, &bodies)?;
    let cables = super::cables::cables(ctx, &raw.cable, &bodies)?;
    let winches = super::cables::winches(ctx, &raw.winch, &cables)?;
    let controllers = super::controllers::controllers(ctx, &raw.controller, &simulation, &bodies, &joints, &cables)?;
    let probes = super::probes::probes(ctx, &raw.probe, &bodies, &joints, &cables, &winches, &controllers)?;
    Ok(Scenario { file: file.to_path_buf(), simulation, bodies, joints, cables, environment, winches, controllers, probes })
}

/// Most steps (frames × sub-steps) a scenario may ask for: 10⁸, about a
/// day of stepping a small scenario. More is refused before the run starts.
pub const MAX_STEPS: u64 = 100_000_000;

/// `[simulation]`.
fn simulation(ctx: &Ctx<'_>, raw: &S<RawSimulation>) -> Res<Simulation> {
    let o = "[simulation]";
    let r = raw.get_ref();
    let duration = ctx.check(&r.duration, o, "duration", Rule::Positive, "s")?;
    let dt = ctx.check(&r.dt, o, "dt", Rule::Positive, "s")?;
    if dt > 1.0 {
        return Err(ctx.err(r.dt.span(), format!("{o}: `dt` must be at most 1 s, found {}", fmt_num(dt))));
    }
    let substeps = match &r.substeps {
        Some(v) => {
            let n = *v.get_ref();
            if !(1..=i64::from(u32::MAX)).contains(&n) {
                return Err(ctx.err(v.span(), format!("{o}: `substeps` must be at least 1, found {n}")));
            }
            u32::try_from(n).ok()
        }
        None => None,
    };
    // A run that cannot finish is refused before it starts.
    let steps = (duration / dt).ceil() * f64::from(substeps.unwrap_or(1));
    if steps > MAX_STEPS as f64 {
        return Err(ctx.err(
            r.dt.span(),
            format!(
                "{o}: `dt` = {} s gives {} steps over `duration` = {} s{}; at most {MAX_STEPS} can be run: raise `dt` or shorten `duration`",
                fmt_num(dt),
                fmt_num(steps),
                fmt_num(duration),
                substeps.map_or(String::new(), |n| format!(" with `substeps` = {n}"))
            ),
        ));
    }
    let output_interval = match &r.output_interval {
        Some(v) => {
            let x = ctx.check(v, o, "output_interval", Rule::Positive, "s")?;
            if x < dt {
                // Full precision: the two may agree to the digits `fmt_num` shows.
                return Err(ctx.err(v.span(), format!("{o}: `output_interval` must be at least `dt` = {dt} s, found {x} s")));
            }
            x
        }
        None => dt,
    };
    let statics = r.statics.as_ref().is_some_and(|v| *v.get_ref());
    let static_load_steps = match &r.static_load_steps {
        Some(v) if !statics => return Err(ctx.err(v.span(), format!("{o}: `static_load_steps` only applies with `statics = true`"))),
        Some(v) => {
            let n = *v.get_ref();
            u32::try_from(n)
                .ok()
                .filter(|n| (1..=10_000).contains(n))
                .ok_or_else(|| ctx.err(v.span(), format!("{o}: `static_load_steps` must be between 1 and 10000, found {n}")))?
        }
        None => 10,
    };
    Ok(Simulation {
        duration,
        dt,
        substeps,
        integrator: integrator(ctx, r)?,
        gravity: ctx.vec3_or(&r.gravity, o, "gravity", "m/s²", DVec3::new(0.0, -9.81, 0.0))?,
        output_interval,
        statics,
        static_load_steps,
    })
}

/// The integrator name and the parameters of its scheme.
fn integrator(ctx: &Ctx<'_>, r: &RawSimulation) -> Res<IntegratorChoice> {
    let o = "[simulation]";
    let name = match &r.integrator {
        Some(v) => ctx.choice(v, o, "integrator", INTEGRATOR_NAMES)?,
        None => "generalized_alpha",
    };
    // (field, value, scheme it belongs to, range)
    let params: [(&str, &Option<S<f64>>, &str, Rule); 6] = [
        ("beta", &r.beta, "newmark", Rule::NonNegative),
        ("gamma", &r.gamma, "newmark", Rule::AtLeast(0.5)),
        ("theta", &r.theta, "wilson_theta", Rule::AtLeast(1.0)),
        ("alpha", &r.alpha, "hht", Rule::Between(-1.0 / 3.0, 0.0)),
        ("rho_inf", &r.rho_inf, "generalized_alpha", Rule::Between(0.0, 1.0)),
        ("w", &r.w, "linearly_implicit", Rule::Between(0.5, 1.0)),
    ];
    let mut values = [None; 6];
    for (slot, (field, value, scheme, rule)) in values.iter_mut().zip(params) {
        if let Some(v) = value {
            if scheme != name {
                return Err(ctx.err(v.span(), format!("{o}: `{field}` is a parameter of the `{scheme}` integrator, but the integrator is `{name}`")));
            }
            *slot = Some(ctx.check(v, o, field, rule, "")?);
        }
    }
    let [beta, gamma, theta, alpha, mut rho_inf, w] = values;
    if r.integrator.is_none() && rho_inf.is_none() {
        rho_inf = Some(0.0);
    }
    Ok(IntegratorChoice { name: name.to_string(), beta, gamma, theta, alpha, rho_inf, w })
}

/// `[environment]`.
fn environment(ctx: &Ctx<'_>, r: &RawEnvironment) -> Res<Environment> {
    let o = "[environment]";
    let d = Environment::default();
    let water_surface = ctx.opt(&r.water_surface, o, "water_surface")?;
    if water_surface.is_none() {
        let why = "needs `water_surface` (there is no water without it)";
        ctx.forbid(&r.current, o, "current", why)?;
    }
    Ok(Environment {
        air_density: ctx.check_or(&r.air_density, o, "air_density", Rule::NonNegative, "kg/m³", d.air_density)?,
        wind: ctx.vec3_or(&r.wind, o, "wind", "m/s", d.wind)?,
        water_surface,
        water_density: ctx.check_or(&r.water_density, o, "water_density", Rule::Positive, "kg/m³", d.water_density)?,
        current: ctx.vec3_or(&r.current, o, "current", "m/s", d.current)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenario_fmt_num_is_short() {
        assert_eq!(fmt_num(3.0), "3");
        assert_eq!(fmt_num(-0.5), "-0.5");
        assert_eq!(fmt_num(0.1 + 0.2), "0.3");
        assert_eq!(fmt_num(1e-9), "1e-9");
        assert_eq!(fmt_num(f64::NAN), "NaN");
        assert_eq!(fmt_vec(DVec3::new(0.0, 10.5, -2.0)), "[0, 10.5, -2]");
    }
}
