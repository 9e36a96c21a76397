//! Scenario files: the TOML contract of `cablesim` (see `docs/scenario.md`),
//! parsed and validated into plain SI types.
//!
//! [`parse`] and [`load`] never panic; every problem comes back as a
//! [`ScenarioError`] with file, line, column and the offending source line:
//!
//! ```
//! let err = bevy_rapier_cable::scenario::parse(
//!     "[simulation]\nduration = 10\ndt = 0\n",
//!     "demo.toml",
//! )
//! .unwrap_err();
//! assert_eq!((err.line, err.col), (3, 6));
//! assert!(err.to_string().contains("`dt` must be greater than 0"));
//! ```
//!
//! Validation resolves everything the physics needs and that can be checked
//! without simulating: material presets, defaults, body poses, the cables'
//! initial centerlines, cross-references by name, probe columns.

mod bodies;
mod cables;
mod controllers;
mod error;
mod probes;
mod raw;
mod span;
mod types;
mod validate;

use std::path::Path;

pub use self::controllers::{Controller, ControllerKind, CONTROLLER_TYPES, DEFAULT_KI_RATIO, DEFAULT_POLES, DEFAULT_SCHEDULE};
pub use self::error::ScenarioError;
pub use self::probes::{Component, Probe, ProbeTarget, Quantity};
pub use self::span::Location;
pub use self::types::{
    Body, BodyKind, Cable, CableEnd, CableSide, CollisionGroups, Drive, Environment, IntegratorChoice, Joint, JointKind, Motion, PointLoad, Scenario, Shape,
    Simulation, TimeSeries, Winch, INTEGRATOR_NAMES,
};
pub use self::validate::MAX_STEPS;

/// Read and validate the scenario file at `path`.
pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
    let source = std::fs::read_to_string(path).map_err(|e| ScenarioError::io(path, e))?;
    parse_at(&source, path)
}

/// Validate scenario text `source`; `file_name` is used in messages and
/// stored in [`Scenario::file`].
pub fn parse(source: &str, file_name: &str) -> Result<Scenario, ScenarioError> {
    parse_at(source, Path::new(file_name))
}

fn parse_at(source: &str, file: &Path) -> Result<Scenario, ScenarioError> {
    let toml_err = |e: toml::de::Error, prefix: &str| {
        let span = e.span().unwrap_or(0..0);
        let mut msg = e.message().trim_end().replace('\n', "; ");
        if msg == "missing field `simulation`" {
            msg = "missing the `[simulation]` table (`duration` and `dt` are required)".into();
        } else if msg == "duplicate key" {
            if let Some(key) = source.get(span.clone()).filter(|k| !k.is_empty()) {
                msg = format!("duplicate key `{key}`");
            }
        }
        ScenarioError::new(file, source, span, format!("{prefix}{msg}"))
    };
    // Syntax first, so that syntax errors say so.
    source.parse::<toml::Table>().map_err(|e| toml_err(e, "TOML syntax error: "))?;
    let raw: raw::RawScenario = toml::from_str(source).map_err(|e| toml_err(e, ""))?;
    let ctx = validate::Ctx::new(file, source);
    validate::validate(&ctx, file, raw)
}

#[cfg(test)]
mod tests {
    /// The example of the module documentation.
    #[test]
    fn scenario_doc_example() {
        let err = super::parse("[simulation]\nduration = 10\ndt = 0\n", "demo.toml").unwrap_err();
        assert_eq!((err.line, err.col), (3, 6));
        assert!(err.to_string().contains("`dt` must be greater than 0"));
        assert!(err.to_string().contains("demo.toml:3:6"));
    }

    #[test]
    fn scenario_integrator_names_match_the_integrators() {
        let mut ours = super::INTEGRATOR_NAMES.to_vec();
        let mut theirs = crate::integrate::Scheme::NAMES.to_vec();
        ours.sort_unstable();
        theirs.sort_unstable();
        assert_eq!(ours, theirs);
    }

    #[test]
    fn scenario_load_reports_missing_file() {
        let err = super::load(std::path::Path::new("/nonexistent/x.toml")).unwrap_err();
        assert!(err.io.is_some() && err.line == 0);
        assert!(err.to_string().starts_with("error: cannot read /nonexistent/x.toml"));
    }
}
