//! The rope model: a chain of beam elements in relative coordinates, with an
//! O(n) implicit articulated-body solve.
pub mod material;
pub use self::material::{preset, RopeMaterial, RopeSection, PRESET_NAMES};
pub mod chain;
pub mod contact;
pub use self::contact::{ContactError, CoulombFriction, Curve, ImpactLaw, PairContact, PairFriction, Span, SphereContact};
pub mod force;
pub use self::force::{AttachedForce, AttachedPair, ForceElement, FrictionBranch, PairElement, PairSpring, PairWrench, PointSpring, PointState, PointWrench};
pub mod spatial;
pub use self::chain::{
    AnchorSpring, BaseMotion, BaseState, Chain, ChainError, Forest, ForestPair, FreeBody, JointKind, Limb, LinkLoad, LinkMass, RotationSpring, SampledMotion,
    SpringLaw, StaticError, SubJoint,
};
pub mod rope;
pub use self::rope::{
    BodyInChain, LumpedBody, RopeBuilder, RopeEnd, RopeError, RopeLayout, RopeModel, RopePart, RopeStart, END_ROTATION_STIFFNESS_FACTOR, END_STIFFNESS_FACTOR,
    MAX_SEGMENTS, SLACK_STOP,
};
#[allow(clippy::module_inception)]
pub mod cable;
#[cfg(test)]
mod tangent_tests;
pub use self::cable::{Cable, CableError, ElementForces, LinkVelocity, RopeView};
