//! What drawing the ropes costs per frame on the CPU (docs/performance.md,
//! "Drawing the ropes"): the render plugin's systems for R ropes of N nodes
//! whose nodes move every fixed step, in a headless app (`MinimalPlugins`,
//! `AssetPlugin`, `MeshPlugin`, `CableRenderPlugin`; no GPU, so no upload
//! to the render world is timed).
//!
//! Each timed `app.update()` runs one fixed step (the nodes recorded) and
//! one frame (blended, every tube's positions, normals and colours
//! rewritten in place in its mesh asset). `tube_mesh/empty` is the same app
//! without ropes (Bevy's own per-update cost), to subtract.
//!
//! `cargo bench --features render --bench tube_mesh` (criterion, wall
//! time).

use bevy::mesh::MeshPlugin;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier_cable::plugin::render::{CableRender, CableRenderPlugin};
use bevy_rapier_cable::plugin::CableState;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::time::Duration;

/// The render plugin alone, one fixed step of 1/60 s per update.
fn app() -> App {
    let step = Duration::from_secs_f64(1.0 / 60.0);
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), MeshPlugin, CableRenderPlugin::default()));
    app.insert_resource(Time::<Fixed>::from_duration(step));
    app.insert_resource(TimeUpdateStrategy::ManualDuration(step));
    app.finish();
    app.cleanup();
    app
}

/// A hanging rope of `nodes` nodes, 10 m, swinging with phase `t`.
fn rope(nodes: usize, x: f32, t: f32) -> Vec<Vec3> {
    let angle = 0.3 * t.sin();
    (0..nodes).map(|i| Vec3::new(x, 12.0, 0.0) + Quat::from_rotation_z(angle) * Vec3::new(0.0, -10.0 * i as f32 / (nodes - 1) as f32, 0.0)).collect()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("tube_mesh");
    group.measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    let mut empty = app();
    group.bench_function("empty", |b| b.iter(|| empty.update()));
    // (ropes, nodes per rope), 12 sides.
    for (ropes, nodes) in [(1, 11), (1, 101), (1, 1001), (10, 101)] {
        let mut app = app();
        let cables: Vec<Entity> = (0..ropes)
            .map(|r| {
                let state = CableState { nodes: rope(nodes, r as f32, 0.0), tensions: vec![10_000.0; nodes - 1], ..default() };
                app.world_mut().spawn((state, CableRender { color_by_tension: Some(20_000.0), ..default() })).id()
            })
            .collect();
        for _ in 0..3 {
            app.update();
        }
        let mut t = 0.0f32;
        group.bench_with_input(BenchmarkId::new(format!("{ropes}_ropes"), nodes), &nodes, |b, &nodes| {
            b.iter(|| {
                t += 1.0 / 60.0;
                for (r, e) in cables.iter().enumerate() {
                    if let Some(mut s) = app.world_mut().get_mut::<CableState>(*e) {
                        s.nodes = rope(nodes, r as f32, t);
                    }
                }
                app.update();
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
