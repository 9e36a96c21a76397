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
//! | module | feature | knows | what |
//! |---|---|---|---|
//! | `plugin` | `app` | Bevy, bevy_rapier3d | the Bevy plugin: cables as entities; `plugin::scenario` (also `sim`) spawns a scenario file into an app; `plugin::render` (`render`) draws them |
//! | `output` | `cli` | csv, serde_json, plotters | results.csv, summary.json, plot.png of `cablesim` |
//! | `sim` | `sim` | rapier3d | the Bevy-free scenario runner (`sim::World`, probes); with `rapier` alone, only the static-solve settings the plugin shares |
//! | `coupling` | `rapier` | rapier3d | the coupling core: cables stepped beside rapier's sets, shared by `sim` and `plugin` |
//! | `scenario` | `scenario` | serde, toml | the TOML scenario contract, validation with file:line:col |
//! | [`cable`] | — | — | the rope model and its O(n) implicit solve (f64) |
//! | [`crane`] | — | — | reduced crane models (overhead, tower) from Lagrange's equations |
//! | [`integrate`] | — | — | time integrators for any second-order system |
//!
//! ## Features
//!
//! | feature | adds | brings |
//! |---|---|---|
//! | (none) | `cable`, `crane`, `integrate` | glam, thiserror |
//! | `scenario` | `scenario` | serde, toml |
//! | `rapier` | `coupling` | rapier3d |
//! | `sim` | `scenario` + `rapier` + `sim` | — |
//! | `app` | `rapier` + `plugin` (and `plugin::scenario` with `sim`) | bevy, bevy_rapier3d, log |
//! | `cli` | `app` + `sim` + `output` and the `cablesim` binary | clap, indicatif, csv, serde_json, plotters |
//! | `render` | `app` + `plugin::render`: ropes drawn as lit tube meshes interpolated between fixed steps, gizmos for nodes, contacts and element frames (an app with its own window and renderer) | Bevy's `bevy_asset`, `bevy_mesh`, `bevy_pbr`, `bevy_gizmos` (and the render crates they need) |
//! | `demo` | `render` + a windowed Bevy for the examples (`hanging_payload`): winit on X11 only (no Wayland, audio or gamepads, so no system dev packages are needed to build), 3D and UI rendering, PNG screenshots | Bevy's `default_app`, `bevy_winit`, `x11`, `3d_bevy_render`, `ui_api`, ... |
//!
//! The default features are `app` and `cli`, so that `cargo run --release --
//! run file.toml` and `cargo test --release` work as they are, headless: the
//! default build compiles no renderer. A game needs
//! only the plugin, without any command-line crate:
//!
//! ```toml
//! bevy_rapier_cable = { version = "0.1", default-features = false, features = ["app"] }
//! ```
#![warn(missing_docs)]

/// The f64 vector types of the rope API (`DVec3`, `DMat3`, `DQuat`), the
/// glam version this crate is built with, re-exported so an app needs no
/// glam dependency of its own (as `bevy_rapier3d` re-exports rapier).
pub use glam;

pub mod cable;
#[cfg(feature = "rapier")]
pub mod coupling;
pub mod crane;
#[cfg(feature = "demo")]
pub mod demo_support;
pub mod integrate;
#[cfg(feature = "cli")]
pub mod output;
#[cfg(feature = "app")]
pub mod plugin;
#[cfg(feature = "scenario")]
pub mod scenario;
// With `rapier` alone: the static-solve settings the plugin shares.
#[cfg(feature = "rapier")]
pub mod sim;
#[cfg(all(feature = "demo", feature = "sim"))]
pub mod viewer;

/// The README's code examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

/// The code of `docs/embedding.md` (the Bevy embedding guide), compiled as
/// doctests.
#[doc = include_str!("../docs/embedding.md")]
#[cfg(all(doctest, feature = "app"))]
pub struct EmbeddingDoctests;
