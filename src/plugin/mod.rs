//! The Bevy plugin: cables as entities, stepped beside bevy_rapier in
//! `FixedUpdate`, coupled both ways with rapier bodies.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_rapier3d::prelude::*;
//! use bevy_rapier_cable::plugin::*;
//! App::new()
//!     .add_plugins((MinimalPlugins, TransformPlugin,
//!                   RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(),
//!                   CablePlugin::default()))
//!     .run();
//! ```
//!
//! ## Order inside `FixedUpdate` (deterministic, documented)
//! | set | runs | does |
//! |---|---|---|
//! | `PhysicsSet::SyncBackend` | bevy_rapier | creates rapier bodies, applies user changes |
//! | [`CableSystems::Init`] | after it | builds new cables from [`CableDescriptor`]s |
//! | [`CableSystems::ReadBodies`] | then | reads poses and velocities of the bodies the cable ends hang on |
//! | [`CableSystems::Step`] | then | advances every cable by the fixed step (f64, O(n) implicit) |
//! | [`CableSystems::WriteBodies`] | then, before `PhysicsSet::StepSimulation` | moves the bodies the cables carry, applies end forces to bodies rapier keeps |
//! | `PhysicsSet::StepSimulation`, `Writeback` | bevy_rapier | rapier steps |
//! | [`CableSystems::Readout`] | after `Writeback` | refreshes [`CableState`] for other systems |
//!
//! ## Coupling
//! * A **dynamic body at a cable's end that no joint holds** (hook, payload)
//!   becomes a lumped link of the cable's implicit solve: the plugin turns it
//!   into a kinematic body in rapier and moves it every step to the pose the
//!   cable computes (so a 10 t payload on a 0.3 kg element is as stable as
//!   the rope itself). Its [`ExternalForce`](bevy_rapier3d::prelude::ExternalForce) is applied in the cable solve.
//! * A **dynamic body on a prismatic joint** at a cable's start (a trolley on
//!   its rail) becomes a prismatic link of the chain in the same way; its
//!   `ExternalForce` along the rail drives it, and so does the joint's rapier
//!   motor (`PrismaticJointBuilder::motor_velocity`/`motor_position`, read
//!   every step): a spring–damper `k (x_target − x) + c (v_target − v)` on
//!   the chain's rail coordinate, implicit in the cable solve (`k`, `c` times
//!   the trolley's mass for `MotorModel::AccelerationBased`, as rapier
//!   scales them), or an explicit `max_force` when it would ask for more.
//! * The carried bodies' rapier `Velocity` at creation becomes the chain's
//!   initial rates, and before its first step a cable recomputes its
//!   acceleration with the loads and motors then acting.
//! * A **fixed or kinematic body** moves the cable end (the cable's base
//!   follows its pose, velocity and the velocity change over the last step).
//! * Any **other dynamic body** (one rapier keeps: contacts, joint graphs)
//!   gets the end force as an impulse each step (explicit exchange; stable
//!   while `k·h²/m` stays below ~1, with `k = EA/L_e`).

mod components;
mod systems;

pub use self::components::{CableAnchor, CableDescriptor, CableDiverged, CableSim, CableState, CarriedBody};
use bevy::prelude::*;
use bevy_rapier3d::prelude::PhysicsSet;

/// System sets of the cable plugin, in execution order (all in `FixedUpdate`).
#[derive(SystemSet, Debug, Hash, PartialEq, Eq, Clone, Copy)]
pub enum CableSystems {
    /// Builds new cables from [`CableDescriptor`]s.
    Init,
    /// Reads the poses of the bodies cable ends hang on.
    ReadBodies,
    /// Advances the cables.
    Step,
    /// Writes carried bodies and end forces back to rapier.
    WriteBodies,
    /// Refreshes [`CableState`] after rapier's writeback.
    Readout,
}

/// The cable plugin. Add it after `RapierPhysicsPlugin::in_fixed_schedule()`.
#[derive(Debug, Clone, Default)]
pub struct CablePlugin {
    /// Cable sub-steps per fixed step (default 1: the implicit solve is
    /// stable at the frame step).
    pub substeps: u32,
}

impl CablePlugin {
    /// Sets the cable sub-steps per fixed step.
    pub fn with_substeps(mut self, substeps: u32) -> Self {
        self.substeps = substeps;
        self
    }
}

/// Settings of the running plugin.
#[derive(Resource, Debug, Clone, Copy)]
pub struct CableSettings {
    /// Cable sub-steps per fixed step.
    pub substeps: u32,
}

impl Plugin for CablePlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(CableSettings { substeps: self.substeps.max(1) });
        app.register_type::<CableState>();
        app.add_message::<CableDiverged>();
        app.configure_sets(
            FixedUpdate,
            (CableSystems::Init, CableSystems::ReadBodies, CableSystems::Step, CableSystems::WriteBodies)
                .chain()
                .after(PhysicsSet::SyncBackend)
                .before(PhysicsSet::StepSimulation),
        );
        app.configure_sets(FixedUpdate, CableSystems::Readout.after(PhysicsSet::Writeback));
        app.add_systems(
            FixedUpdate,
            (
                systems::init_cables.in_set(CableSystems::Init),
                systems::read_bodies.in_set(CableSystems::ReadBodies),
                systems::step_cables.in_set(CableSystems::Step),
                systems::write_bodies.in_set(CableSystems::WriteBodies),
                systems::readout.in_set(CableSystems::Readout),
            ),
        );
    }
}
