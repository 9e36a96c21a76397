//! Raw serde types: the file as written, every value with its byte span.
//!
//! Everything here is `deny_unknown_fields`, so a misspelt key is an error
//! that names it. Checks of values, units and cross-references are done in
//! the validation that turns these into the public types.

use serde::de::{self, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use toml::Spanned;

/// A spanned value.
pub(crate) type S<T> = Spanned<T>;
/// A spanned array of spanned numbers (a vector such as `[x, y, z]`).
pub(crate) type Vector = Spanned<Vec<Spanned<f64>>>;

/// A value of any TOML type, used for the heterogeneous tables
/// (`[[t, v], ...]`, `[[t, [x, y, z]], ...]`) so that their shape can be
/// checked with a clear message.
#[derive(Debug)]
pub(crate) enum Datum {
    /// A number (integer or float).
    Num(f64),
    /// An array.
    List(Vec<Spanned<Datum>>),
    /// Anything else; the name of its type.
    Other(&'static str),
}

impl Datum {
    /// A short description of the value's type for messages.
    pub(crate) fn kind(&self) -> &'static str {
        match self {
            Datum::Num(_) => "a number",
            Datum::List(_) => "an array",
            Datum::Other(k) => k,
        }
    }
}

struct DatumVisitor;

impl<'de> Visitor<'de> for DatumVisitor {
    type Value = Datum;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("any TOML value")
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Datum, E> {
        Ok(Datum::Num(v as f64))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Datum, E> {
        Ok(Datum::Num(v as f64))
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Datum, E> {
        Ok(Datum::Num(v))
    }
    fn visit_bool<E: de::Error>(self, _: bool) -> Result<Datum, E> {
        Ok(Datum::Other("a boolean"))
    }
    fn visit_str<E: de::Error>(self, _: &str) -> Result<Datum, E> {
        Ok(Datum::Other("a string"))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Datum, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element::<Spanned<Datum>>()? {
            items.push(item);
        }
        Ok(Datum::List(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Datum, A::Error> {
        while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
        Ok(Datum::Other("a table or date"))
    }
}

impl<'de> Deserialize<'de> for Datum {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Datum, D::Error> {
        d.deserialize_any(DatumVisitor)
    }
}

/// The whole file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScenario {
    pub simulation: S<RawSimulation>,
    #[serde(default)]
    pub body: Vec<S<RawBody>>,
    #[serde(default)]
    pub joint: Vec<S<RawJoint>>,
    #[serde(default)]
    pub cable: Vec<S<RawCable>>,
    pub environment: Option<S<RawEnvironment>>,
    #[serde(default)]
    pub winch: Vec<S<RawWinch>>,
    #[serde(default)]
    pub probe: Vec<S<RawProbe>>,
    #[serde(default)]
    pub controller: Vec<S<RawController>>,
}

/// `[simulation]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSimulation {
    pub duration: S<f64>,
    pub dt: S<f64>,
    pub substeps: Option<S<i64>>,
    pub integrator: Option<S<String>>,
    pub beta: Option<S<f64>>,
    pub gamma: Option<S<f64>>,
    pub theta: Option<S<f64>>,
    pub alpha: Option<S<f64>>,
    pub rho_inf: Option<S<f64>>,
    pub w: Option<S<f64>>,
    pub gravity: Option<Vector>,
    pub output_interval: Option<S<f64>>,
    pub statics: Option<S<bool>>,
    pub static_load_steps: Option<S<i64>>,
}

/// `[[body]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBody {
    pub name: S<String>,
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub shape: S<String>,
    pub radius: Option<S<f64>>,
    pub half_extents: Option<Vector>,
    pub half_height: Option<S<f64>>,
    pub mass: Option<S<f64>>,
    pub position: Option<Vector>,
    pub rotation: Option<Vector>,
    pub linear_velocity: Option<Vector>,
    pub angular_velocity: Option<Vector>,
    pub friction: Option<S<f64>>,
    pub restitution: Option<S<f64>>,
    pub wind_area: Option<S<f64>>,
    pub wind_coefficient: Option<S<f64>>,
    pub motion: Option<S<RawMotion>>,
    pub collision_groups: Option<S<RawGroups>>,
}

/// `collision_groups = { memberships = [..], filter = [..] }` (group
/// numbers 1 to 32).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawGroups {
    pub memberships: Option<S<Vec<S<i64>>>>,
    pub filter: Option<S<Vec<S<i64>>>>,
}

/// A kinematic body's `motion = { ... }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMotion {
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub amplitude: Option<Vector>,
    pub period: Option<S<f64>>,
    pub phase: Option<S<f64>>,
    pub points: Option<S<Datum>>,
    pub axis: Option<Vector>,
    pub rate: Option<S<Datum>>,
}

/// `[[joint]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawJoint {
    pub name: S<String>,
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub body1: S<String>,
    pub body2: S<String>,
    pub anchor1: Option<Vector>,
    pub anchor2: Option<Vector>,
    pub axis: Option<Vector>,
    pub limits: Option<Vector>,
    pub drive: Option<S<RawDrive>>,
}

/// A joint's `drive = { ... }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDrive {
    pub force: Option<S<Datum>>,
    pub velocity: Option<S<Datum>>,
    pub max_force: Option<S<f64>>,
}

/// `[[cable]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCable {
    pub name: S<String>,
    pub length: S<f64>,
    pub segments: S<i64>,
    pub diameter: S<f64>,
    pub linear_density: Option<S<f64>>,
    pub ea: Option<S<f64>>,
    pub ei: Option<S<f64>>,
    pub ei2: Option<S<f64>>,
    pub gj: Option<S<f64>>,
    pub shear_stiffness: Option<S<f64>>,
    pub damping: Option<S<f64>>,
    pub linear_damping: Option<S<f64>>,
    pub angular_damping: Option<S<f64>>,
    pub end_stiffness: Option<S<f64>>,
    pub material: Option<S<String>>,
    pub friction: Option<S<f64>>,
    pub drag_normal: Option<S<f64>>,
    pub drag_tangential: Option<S<f64>>,
    pub added_mass: Option<S<f64>>,
    pub start: Option<S<RawEnd>>,
    pub end: Option<S<RawEnd>>,
    pub path: Option<S<Vec<Vector>>>,
    pub contacts: Option<S<bool>>,
    pub loads: Option<S<Vec<S<RawLoad>>>>,
    pub stress_free: Option<S<bool>>,
    pub tension_only: Option<S<bool>>,
    pub collision_groups: Option<S<RawGroups>>,
}

/// One entry of a cable's `loads = [{ s, force, moment }, ...]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLoad {
    pub s: S<f64>,
    pub force: Vector,
    pub moment: Option<Vector>,
}

/// A cable's `start = { ... }` or `end = { ... }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawEnd {
    pub body: Option<S<String>>,
    pub anchor: Option<Vector>,
    pub world: Option<Vector>,
    pub clamp: Option<S<bool>>,
}

/// `[environment]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawEnvironment {
    pub air_density: Option<S<f64>>,
    pub wind: Option<Vector>,
    pub water_surface: Option<S<f64>>,
    pub water_density: Option<S<f64>>,
    pub current: Option<Vector>,
}

/// `[[winch]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawWinch {
    pub name: S<String>,
    pub cable: S<String>,
    pub at: S<String>,
    pub drum_radius: S<f64>,
    pub drum_inertia: S<f64>,
    pub max_torque: S<f64>,
    pub speed: S<Datum>,
    pub brake: Option<S<bool>>,
    pub min_length: Option<S<f64>>,
    pub max_length: Option<S<f64>>,
}

/// `[[probe]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawProbe {
    pub name: S<String>,
    pub body: Option<S<String>>,
    pub cable: Option<S<String>>,
    pub joint: Option<S<String>>,
    pub winch: Option<S<String>>,
    pub controller: Option<S<String>>,
    pub system: Option<S<bool>>,
    pub quantity: S<String>,
    pub s: Option<S<f64>>,
    pub component: Option<S<String>>,
}

/// `[[controller]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawController {
    pub name: S<String>,
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub joint: S<String>,
    pub cable: S<String>,
    pub target: S<Datum>,
    pub max_speed: Option<S<f64>>,
    pub max_acceleration: Option<S<f64>>,
    pub max_force: Option<S<f64>>,
    pub frequency: Option<S<f64>>,
    pub damping: Option<S<f64>>,
    pub sample_time: Option<S<f64>>,
    pub kp: Option<S<f64>>,
    pub ki: Option<S<f64>>,
    pub kd: Option<S<f64>>,
    pub sway_kp: Option<S<f64>>,
    pub sway_ki: Option<S<f64>>,
    pub sway_kd: Option<S<f64>>,
    pub p_gain: Option<S<f64>>,
    pub d_gain: Option<S<f64>>,
    pub e_p: Option<S<f64>>,
    pub e_i: Option<S<f64>>,
}
