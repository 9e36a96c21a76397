//! The rope model: a chain of beam elements in relative coordinates, with an
//! O(n) implicit articulated-body solve.
pub mod material;
pub use self::material::{preset, RopeSection, PRESET_NAMES};
pub mod chain;
pub mod spatial;
pub use self::chain::{Limb, RotationSpring, StaticError, AnchorSpring, BaseMotion, BaseState, Chain, JointKind, LinkLoad, LinkMass, SpringLaw, SubJoint};
pub mod rope;
pub use self::rope::{BodyInChain, LumpedBody, RopeBuilder, RopeEnd, RopeError, RopeLayout, RopeModel, RopePart, RopeStart};
#[cfg(test)]
mod tangent_tests;
#[allow(clippy::module_inception)]
pub mod cable;
pub use self::cable::{Cable, CableError, ElementForces, LinkVelocity, RopeView};
