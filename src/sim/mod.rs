//! A Bevy-free runner of scenario files: builds the cables (with the bodies
//! they carry as lumped links) from a validated [`Scenario`](crate::scenario::Scenario),
//! steps them frame by frame and samples the probes. `cablesim run` uses it;
//! the Bevy plugin steps the same [`Cable`](crate::cable::Cable)s.
pub(crate) mod probe;
pub(crate) mod rapier;
mod world;
pub(crate) use self::world::body_motion;
pub use self::world::{shape_inertia, SimError, World, STATIC_MAX_ITERATIONS, STATIC_TOLERANCE};
