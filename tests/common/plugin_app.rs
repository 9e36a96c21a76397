//! A headless Bevy app with bevy_rapier in `FixedUpdate` and the cable
//! plugin, advancing exactly one fixed step of `dt` per `update()`.

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::plugin::{CableAnchor, CableDescriptor, CableError, CablePlugin};

#[allow(dead_code)] // a binary may build its own app
pub fn headless_app(dt: f32) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin, RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default()));
    app.insert_resource(Time::<Fixed>::from_seconds(dt as f64));
    app.insert_resource(TimestepMode::Fixed { dt, substeps: 1 });
    app.insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    app.finish();
    app.cleanup();
    app
}

/// The `CableError` messages written since the last call, as text
/// (drained: each is returned once).
#[allow(dead_code)] // not every test binary reads errors
pub fn cable_errors(app: &mut App) -> Vec<String> {
    app.world_mut().resource_mut::<Messages<CableError>>().drain().map(|e| e.to_string()).collect()
}

/// Runs `frames` updates and returns the `CableError`s sent in them.
#[allow(dead_code)] // not every test binary reads errors
pub fn errors_over(app: &mut App, frames: usize) -> Vec<CableError> {
    let mut errors = Vec::new();
    for _ in 0..frames {
        app.update();
        errors.extend(app.world().resource::<Messages<CableError>>().iter_current_update_messages().cloned());
    }
    errors
}

/// A free 3 m steel rope (20 mm, 30 elements) laid level along x at
/// height `y` (m, its centre), from x = −1.5 to 1.5 m at `z` m.
#[allow(dead_code)] // not every test binary lays one
pub fn free_rope_laid_level(y: f32, z: f32) -> CableDescriptor {
    CableDescriptor::new(3.0)
        .material(RopeMaterial::steel_6x36_iwrc(0.02))
        .segments(30)
        .start(CableAnchor::Free)
        .path([Vec3::new(-1.5, y, z), Vec3::new(1.5, y, z)])
}
