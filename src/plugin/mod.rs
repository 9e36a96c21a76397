//! The Bevy plugin: cables as entities, stepped beside bevy_rapier in its
//! schedule (`FixedUpdate` by default; [`CablePlugin::in_schedule`]),
//! coupled both ways with rapier bodies. A complete app and the topics of
//! embedding (schedules, reading cables, despawning, rendering) are in
//! `docs/embedding.md`. With the feature `render`, `plugin::render` draws every
//! cable as a tube mesh, interpolated between fixed steps
//! (`render::CableRenderPlugin`).
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
//! ## Order inside the schedule (deterministic, documented)
//! Placed this way by default; with
//! [`CablePlugin::with_default_system_setup`]`(false)` an app adds
//! [`CablePlugin::get_systems`] and orders the sets itself. The cables
//! advance by the time rapier advances (its `TimestepMode`, see
//! [`CablePlugin`]).
//! | set | runs | does |
//! |---|---|---|
//! | `PhysicsSet::SyncBackend` | bevy_rapier | creates rapier bodies, applies user changes (velocity writes, impulses) |
//! | [`CableSystems::Init`] | after it | builds new cables from [`CableDescriptor`]s |
//! | [`CableSystems::Step`] | then, before `PhysicsSet::StepSimulation` | the coupling core's phase 1: samples the bodies cable ends hang on, reads the carried bodies, advances every cable by the fixed step (f64, O(n) implicit) under rapier's gravity, hands the carried bodies to rapier, applies end forces to the bodies rapier keeps; nothing while rapier is paused (`RapierConfiguration::physics_pipeline_active` false) |
//! | `PhysicsSet::StepSimulation` | bevy_rapier | rapier steps |
//! | [`CableSystems::WriteBodies`] | after it, before `PhysicsSet::Writeback` | the core's phase 2: contact impulses on carried bodies, carried bodies put on the cable's pose and velocity, free bodies the ropes touched put on the pose the ropes' solve left them at; nothing while rapier is paused |
//! | `PhysicsSet::Writeback` | bevy_rapier | `Transform` and `Velocity` from rapier |
//! | [`CableSystems::Readout`] | after `Writeback` | refreshes [`CableState`] for other systems |
//!
//! ## Coupling (the coupling core, [`crate::coupling`], shared with `cablesim`)
//! * A **dynamic body at a cable's end that no joint holds and no other
//!   cable uses** (hook, payload) is a lumped link of the cable's implicit
//!   solve (so a 10 t payload on a 0.3 kg element is as stable as the rope
//!   itself). **It stays a dynamic rapier body**: its `RigidBody` is never
//!   rewritten and its colliders stay in rapier. Its `ExternalForce`,
//!   `GravityScale` and `Damping` act inside the cable solve; an
//!   `ExternalImpulse`, a write to its `Velocity`, and the impulses of
//!   rapier's contacts on it (a ball hitting it) are impulses `M Δv` on
//!   the cable's link, so rope and body take them together. `LockedAxes`
//!   on it are refused (a [`CableError`] message at creation). Its
//!   `Transform` and `Velocity` are the cable's after every step.
//! * A **dynamic body that no joint holds at a cable's start** (a car
//!   towing a trailer on the rope), on that cable alone, is carried in the
//!   same way, as the chain's floating root.
//! * A **dynamic body on a prismatic joint** to a fixed body at a cable's
//!   start (a trolley on its rail) becomes a prismatic link of the chain in
//!   the same way; the joint's rapier motor
//!   (`PrismaticJointBuilder::motor_velocity`/`motor_position`, read every
//!   step) drives it inside the cable solve: a spring–damper
//!   `k (x_target − x) + c (v_target − v)` on the chain's rail coordinate,
//!   implicit (`k`, `c` times the trolley's mass for
//!   `MotorModel::AccelerationBased`, as rapier scales them), or an explicit
//!   `max_force` when it would ask for more. The motor is switched off in
//!   rapier itself so that it does not act twice.
//! * The carried bodies' rapier `Velocity` at creation becomes the chain's
//!   initial rates, and before its first step a cable recomputes its
//!   acceleration with the loads and motors then acting.
//! * A **fixed or kinematic body** moves the cable end (the cable's base
//!   follows its pose, velocity and the velocity change over the last step).
//! * A **dynamic body that hangs on several cables** and that no joint
//!   holds (a payload in a two- or four-leg sling, a beam lifted by two
//!   cranes) is a hub: the first cable that ends on it carries it as above,
//!   and the others are solved in the same implicit chain as limbs grafted
//!   onto the body, their far ends held by the implicit anchor springs (the
//!   world, a fixed or kinematic body, or free). Such a cable entity gets
//!   [`CableRopeOf`] (the carrying entity and its rope index) and its own
//!   [`CableState`] instead of a [`CableSim`]. A cable between two hubs (a
//!   loop through two dynamic bodies) is refused with a [`CableError`]
//!   message naming both, and so are the other cables of that island. A
//!   body whose cable leads to a dynamic body that is no hub is a hub only
//!   if that cable ends on it; otherwise it is coupled explicitly. The
//!   cables of a hub must be spawned in the same step.
//! * Any **other dynamic body** (one rapier keeps: joint graphs, a body on
//!   several cables' starts only) gets the end force as an impulse each step
//!   (explicit exchange; stable while `k·h²/m` stays below ~1, with `k =
//!   EA/L_e`; above 1 a warning is logged when the cable is created, with
//!   the coupled sub-steps that would bring it to 1). Cables spawned in the same step are classified together. A
//!   cable spawned later on a body another cable already carries is
//!   refused.
//!
//! ## Despawning (logged through the `log` facade, as bevy_rapier does)
//! * **A cable entity despawned** (or its [`CableSim`] removed): the bodies
//!   it carried become ordinary rapier bodies again, as their components
//!   say (`GravityScale`, `Damping`, `ExternalForce`, `Sleeping`; the
//!   defaults where absent), keeping their velocity; a trolley's rail motor
//!   acts in rapier again; the sling legs solved in its chain are released
//!   (their [`CableRopeOf`], descriptor and state removed, so they are not
//!   rebuilt from their initial path).
//! * **A carried body despawned**: the cable is removed at the next fixed
//!   step ([`CableSim`], its descriptor and state; the entity stays yours),
//!   with a warning. It does not hold a phantom load.
//! * **A sling leg despawned**: its whole island is removed (the carrying
//!   cable and the other legs) and the body it carried falls free, with a
//!   warning. Respawn the legs you keep to hang it again.
//!
//!
//! ## Errors ([`CableError`], a message with a [`CableErrorKind`])
//! Every failure is sent as a [`CableError`] message and logged at error
//! level (`log` facade; Bevy's `LogPlugin` shows it):
//! * [`CableErrorKind::Configuration`]: the cable cannot be built as
//!   described (a bad field, an anchor on an entity without a rapier body,
//!   a load off the rope, a refused topology, locked axes, a failed static
//!   start). It is not built; its [`CableDescriptor`] is removed. A rope
//!   with contacts laid into a fixed or kinematic collider (a node's
//!   surface more than half its radius inside it: a rope laid with its
//!   centre on the ground is) is refused with this kind at its first
//!   step, and stops there. Lay ropes with their centre a radius above
//!   the surfaces they rest on.
//! * [`CableErrorKind::InvalidInput`]: a NaN or infinite `ExternalForce`,
//!   `GravityScale`, `Damping`, `Velocity` write or `ExternalImpulse` on a
//!   carried body, named. The cable stops before the step.
//! * [`CableErrorKind::Diverged`]: the implicit solve failed; the message
//!   names the time and the reason. The cable stops.
//!
//! A stopped cable keeps its last good state ([`CableState`] stays
//! readable); the ropes solved in its chain (sling legs) stop with it, each
//! with its own message. It no longer holds the bodies it carried: from the
//! step it stopped they are ordinary rapier bodies again, as when the cable
//! is despawned (a payload falls instead of hanging frozen where the rope
//! left it).
//!
//! **Edits after spawning**: a [`CableDescriptor`] changed after its cable
//! was built is ignored, with a warning (despawn the cable and spawn a new
//! one to change it).
//!
//! Tested in `tests/plugin_lifecycle.rs`.

mod components;
mod control;
#[cfg(feature = "render")]
pub mod render;
#[cfg(feature = "sim")]
pub mod scenario;
mod systems;

pub use self::components::{
    BodyExact, CableAnchor, CableDescriptor, CableError, CableErrorKind, CableExact, CablePointLoad, CableRopeOf, CableSim, CableState, CarriedBody,
};
pub use self::control::TrolleyControl;
use bevy::ecs::schedule::{InternedScheduleLabel, ScheduleConfigs, ScheduleLabel};
use bevy::ecs::system::ScheduleSystem;
use bevy::prelude::*;
use bevy_rapier3d::plugin::RapierTransformPropagateSet;
use bevy_rapier3d::prelude::PhysicsSet;

/// System sets of the cable plugin, in execution order, in the plugin's
/// schedule (`FixedUpdate` by default, [`CablePlugin::in_schedule`]).
#[derive(SystemSet, Debug, Hash, PartialEq, Eq, Clone, Copy)]
pub enum CableSystems {
    /// Builds new cables from [`CableDescriptor`]s.
    Init,
    /// Advances the cables and hands carried bodies and end forces to
    /// rapier (before rapier's step).
    Step,
    /// Puts carried bodies on the cable's state (after rapier's step,
    /// before its writeback).
    WriteBodies,
    /// Refreshes [`CableState`] after rapier's writeback.
    Readout,
}

/// With [`CablePlugin::with_coupled_substeps`]: the set in `FixedUpdate`
/// of the system that runs [`CableSubstep`] `n` times (order your
/// `FixedUpdate` systems before or after it).
#[derive(SystemSet, Debug, Hash, PartialEq, Eq, Clone, Copy)]
pub struct CableSubsteps;

/// The schedule of one coupled sub-step (rapier's systems and the cables'),
/// run `n` times per fixed step with
/// [`CablePlugin::with_coupled_substeps`].
#[derive(ScheduleLabel, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CableSubstep;

/// Runs [`CableSubstep`] `n` times, rapier's step set to the fixed step / n.
fn run_coupled_substeps(n: u32) -> impl FnMut(&mut World) {
    move |world: &mut World| {
        let dt = world.resource::<Time>().delta_secs() / n as f32;
        world.insert_resource(bevy_rapier3d::plugin::TimestepMode::Fixed { dt, substeps: 1 });
        for _ in 0..n {
            world.run_schedule(CableSubstep);
        }
    }
}

/// The cable plugin. Add it after `RapierPhysicsPlugin`, in the same
/// schedule as rapier's systems: `FixedUpdate` by default, matching
/// `RapierPhysicsPlugin::in_fixed_schedule()`; [`CablePlugin::in_schedule`]
/// for another one (bevy_rapier's default is `PostUpdate`).
///
/// Each step the cables advance by the time rapier advances, taken from
/// rapier's `TimestepMode` resource as bevy_rapier's own step does
/// (`Fixed { dt, .. }`: `dt`; `Variable { max_dt, time_scale, .. }`:
/// `min(Time::delta_secs() · time_scale, max_dt)`), so the two cannot
/// drift apart. `TimestepMode::Interpolated` (a varying number of rapier
/// steps per frame) is refused with a [`CableError`]. Without a
/// `TimestepMode` resource the schedule's `Time` delta is used.
#[derive(Debug, Clone)]
pub struct CablePlugin {
    /// Cable sub-steps per step (default 1: the implicit solve is stable at
    /// the frame step). The chain is advanced in this many sub-steps of the
    /// rapier step; the exchange with the bodies rapier keeps (explicit
    /// coupling) stays once per step. `cablesim`'s `[simulation] substeps`
    /// sub-steps rapier as well: that is
    /// [`CablePlugin::with_coupled_substeps`] (bit-identical to a fixed
    /// timestep of `dt / substeps`, which `plugin::scenario::add_scenario`
    /// sets).
    pub substeps: u32,
    /// Step independent cables (islands) at once on Bevy's compute task
    /// pool (default `true`); the results are bit-identical to stepping
    /// them one after the other.
    pub parallel: bool,
    schedule: InternedScheduleLabel,
    default_system_setup: bool,
    coupled_substeps: Option<u32>,
}

impl Default for CablePlugin {
    fn default() -> Self {
        CablePlugin { substeps: 1, parallel: true, schedule: FixedUpdate.intern(), default_system_setup: true, coupled_substeps: None }
    }
}

impl CablePlugin {
    /// Sets the cable sub-steps per step.
    pub fn with_substeps(mut self, substeps: u32) -> Self {
        self.substeps = substeps;
        self
    }

    /// Coupled sub-steps, as `cablesim`'s `[simulation] substeps`: every
    /// fixed step runs rapier *and* the cables `n` times with `dt / n`
    /// (`dt` the fixed timestep), the exchange with the bodies rapier keeps
    /// included each time. Put rapier's systems in [`CableSubstep`]
    /// (`RapierPhysicsPlugin::in_schedule(CableSubstep)`); the cable
    /// systems go there too, and the plugin runs that schedule `n` times
    /// from `FixedUpdate` (in [`CableSubsteps`], also with
    /// [`CablePlugin::with_default_system_setup`]`(false)`), setting
    /// rapier's `TimestepMode` to `Fixed { dt: dt / n, substeps: 1 }`
    /// before. It takes precedence over [`CablePlugin::in_schedule`]. For
    /// stiff explicit couplings (a rope on a light jointed boom).
    pub fn with_coupled_substeps(mut self, n: u32) -> Self {
        self.coupled_substeps = Some(n.max(1));
        self
    }

    /// The schedule of the cable systems: [`CableSubstep`] with coupled
    /// sub-steps, else the one chosen ([`CablePlugin::in_schedule`]).
    fn schedule(&self) -> InternedScheduleLabel {
        if self.coupled_substeps.is_some() {
            CableSubstep.intern()
        } else {
            self.schedule
        }
    }

    /// Steps independent cables on Bevy's compute task pool (`true`, the
    /// default) or one after the other on the system's thread.
    pub fn with_parallel(mut self, parallel: bool) -> Self {
        self.parallel = parallel;
        self
    }

    /// Runs the cable systems in `FixedUpdate` (the default), with
    /// `RapierPhysicsPlugin::in_fixed_schedule()`.
    pub fn in_fixed_schedule(self) -> Self {
        self.in_schedule(FixedUpdate)
    }

    /// Runs the cable systems in `schedule`, which must be the schedule of
    /// rapier's systems (`RapierPhysicsPlugin::in_schedule(schedule)`; an
    /// error is logged at start-up when rapier's systems are not there).
    pub fn in_schedule(mut self, schedule: impl ScheduleLabel) -> Self {
        self.schedule = schedule.intern();
        self
    }

    /// With `false`, the plugin registers its types, messages, resources
    /// and observers but adds no systems and configures no sets: add them
    /// yourself with [`CablePlugin::get_systems`] and order the sets
    /// around rapier's `PhysicsSet`s as the module docs' table says (as
    /// bevy_rapier's `with_default_system_setup`).
    pub fn with_default_system_setup(mut self, default_system_setup: bool) -> Self {
        self.default_system_setup = default_system_setup;
        self
    }

    /// The systems of one set, already in it, for an app that places them
    /// itself ([`CablePlugin::with_default_system_setup`]).
    pub fn get_systems(set: CableSystems) -> ScheduleConfigs<ScheduleSystem> {
        match set {
            CableSystems::Init => {
                (systems::drop_orphans, systems::refuse_edits, systems::init_cables, systems::record_legs).chain().in_set(CableSystems::Init).into_configs()
            }
            CableSystems::Step => (systems::step_cables, systems::release_stopped).chain().in_set(CableSystems::Step).into_configs(),
            CableSystems::WriteBodies => systems::write_bodies.in_set(CableSystems::WriteBodies).into_configs(),
            CableSystems::Readout => systems::readout.in_set(CableSystems::Readout).into_configs(),
        }
    }
}

/// Settings of the running plugin.
#[derive(Resource, Debug, Clone, Copy, Reflect)]
#[reflect(Resource, Debug)]
pub struct CableSettings {
    /// Cable sub-steps per step ([`CablePlugin::substeps`]).
    pub substeps: u32,
    /// Independent cables stepped at once ([`CablePlugin::parallel`]).
    pub parallel: bool,
    /// The cable step, s, replacing the step taken from rapier's
    /// `TimestepMode` when set. Bevy keeps time in whole nanoseconds (1/60 s
    /// becomes 16 666 667 ns); a scenario spawned into the app
    /// (`plugin::scenario`) sets its exact `dt`.
    pub step: Option<f64>,
    /// Gravity of the cables, m/s², replacing rapier's (f32)
    /// `RapierConfiguration::gravity` when set. Unset, the cables follow
    /// rapier's gravity, read at every step (a change at run time reaches
    /// them at their next step).
    pub gravity: Option<bevy::math::DVec3>,
}

impl Plugin for CablePlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(CableSettings { substeps: self.substeps.max(1), parallel: self.parallel, step: None, gravity: None });
        app.register_type::<CableDescriptor>()
            .register_type::<CableSim>()
            .register_type::<CableState>()
            .register_type::<CableRopeOf>()
            .register_type::<CableExact>()
            .register_type::<BodyExact>()
            .register_type::<CableSettings>()
            .register_type::<CableError>()
            .register_type::<CableErrorKind>();
        app.add_message::<CableError>();
        app.init_resource::<systems::Legs>();
        app.add_observer(systems::release_cable);
        if let Some(n) = self.coupled_substeps {
            app.init_schedule(CableSubstep);
            app.add_systems(FixedUpdate, run_coupled_substeps(n).in_set(CableSubsteps));
        }
        if !self.default_system_setup {
            return;
        }
        let schedule = self.schedule();
        app.configure_sets(schedule, (CableSystems::Init, CableSystems::Step).chain().after(PhysicsSet::SyncBackend).before(PhysicsSet::StepSimulation));
        app.configure_sets(schedule, CableSystems::WriteBodies.after(PhysicsSet::StepSimulation).before(PhysicsSet::Writeback));
        app.configure_sets(schedule, CableSystems::Readout.after(PhysicsSet::Writeback));
        for set in [CableSystems::Init, CableSystems::Step, CableSystems::WriteBodies, CableSystems::Readout] {
            app.add_systems(schedule, Self::get_systems(set));
        }
        // Trolley controllers write their commands before rapier and the
        // cables take their inputs.
        app.add_systems(schedule, control::trolley_control.before(PhysicsSet::SyncBackend));
    }

    fn finish(&self, app: &mut App) {
        // Rapier's default setup puts its transform propagation set in its
        // schedule; the cables' order is only meaningful beside it.
        // Cables are refused (each with a `CableError`) when they are not.
        let schedule = self.schedule();
        if self.default_system_setup && !app.get_schedule(schedule).is_some_and(|s| s.graph().system_sets.contains(RapierTransformPropagateSet)) {
            let why = format!(
                "the cable plugin runs in {:?}, but rapier's systems are not in that schedule: put both in the same one (`RapierPhysicsPlugin::in_fixed_schedule()` with `CablePlugin::default()`, or `in_schedule(S)` on both; with `with_coupled_substeps`, `RapierPhysicsPlugin::in_schedule(CableSubstep)`)",
                schedule
            );
            log::error!("{why}");
            app.insert_resource(systems::Misplaced(why));
        }
    }
}
