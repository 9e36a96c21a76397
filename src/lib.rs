//! # bevy_rapier_cable
//!
//! Wire ropes and cables for the Bevy game engine, stepped together with
//! rapier3d rigid bodies.
//!
//! A rope is a chain of beam elements in **relative coordinates** (each
//! element's displacement and rotation relative to its inboard neighbour),
//! with axial, shear, bending and torsion stiffness. It is advanced by an
//! O(n) articulated-body solve in which the joint springs *and* the tension's
//! geometric stiffness are implicit, so a stiff steel rope under a heavy
//! payload is stable at the frame step (1/60 s).
//!
//! Layers (data flows down):
//!
//! | module | knows | what |
//! |---|---|---|
//! | [`scenario`] | serde | the TOML scenario contract, validation with file:line:col |
//! | [`output`] | — | results.csv, summary.json, plot.png |
//! | [`cable`] | — | the rope model and its O(n) implicit solve (f64) |
//! | [`integrate`] | — | time integrators for any second-order system |
//!
//! With the feature `rapier` the crate also has the coupling core
//! ([`coupling`]: cables stepped beside rapier's sets, no Bevy) and the
//! scenario runner `sim`; with the default feature `app`, the Bevy plugin
//! and the `cablesim` runner, both thin adapters over the same core.
#![warn(missing_docs)]

/// The f64 vector types of the rope API (`DVec3`, `DMat3`, `DQuat`), the
/// glam version this crate is built with, re-exported so an app needs no
/// glam dependency of its own (as `bevy_rapier3d` re-exports rapier).
pub use glam;

pub mod cable;
#[cfg(feature = "rapier")]
pub mod coupling;
pub mod integrate;
pub mod output;
#[cfg(feature = "app")]
pub mod plugin;
pub mod scenario;
#[cfg(feature = "rapier")]
pub mod sim;

/// The README's code examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

/// The code of `docs/embedding.md` (the Bevy embedding guide), compiled as
/// doctests.
#[doc = include_str!("../docs/embedding.md")]
#[cfg(all(doctest, feature = "app"))]
pub struct EmbeddingDoctests;
