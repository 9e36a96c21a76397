//! A Bevy-free runner of scenario files (feature `sim`): builds the cables
//! (with the bodies they carry as lumped links) from a validated
//! `scenario::Scenario`, steps them frame by frame and samples the probes.
//! `cablesim run` uses it; the Bevy plugin steps the same
//! [`Cable`](crate::cable::Cable)s.
//!
//! With the feature `rapier` alone (the Bevy plugin, `app`, without `sim`)
//! this module holds only the static-solve settings that the runner and the
//! plugin share ([`STATIC_TOLERANCE`], [`STATIC_MAX_ITERATIONS`]).
#[cfg(feature = "sim")]
pub(crate) mod control;
#[cfg(feature = "sim")]
pub(crate) mod probe;
#[cfg(feature = "sim")]
pub(crate) mod rapier;
#[cfg(feature = "sim")]
mod world;
#[cfg(all(feature = "sim", feature = "app"))] // for `plugin::scenario`
pub(crate) use self::world::body_motion;
#[cfg(feature = "sim")]
pub use self::world::{shape_inertia, SimError, World};

/// Convergence tolerance of the static solve (`statics = true`): no
/// coordinate moves by more than this in the last iteration, m or rad.
pub const STATIC_TOLERANCE: f64 = 1e-9;
/// Iteration limit of the static solve, per load step.
pub const STATIC_MAX_ITERATIONS: usize = 500;
