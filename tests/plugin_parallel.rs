//! Independent cables (islands) stepped at once on Bevy's compute task
//! pool (issue 11): the same bits as one after the other. A test binary of
//! its own, so that the process-wide pool can be given several threads
//! before any app starts (on a 2-core machine Bevy's default gives the
//! compute pool one thread, and the plugin then steps one by one).

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::plugin::*;

const R: f32 = 0.3;
const M: f32 = 100.0;

fn app_with(cables: CablePlugin) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin, RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), cables));
    app.insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    app.insert_resource(TimestepMode::Fixed { dt: 1.0 / 60.0, substeps: 1 });
    app.finish();
    app.cleanup();
    app
}

/// Independent cables (islands) are stepped at once on Bevy's compute task
/// pool, and the results are bit-identical to stepping them one after the
/// other: four payloads on four ropes, pushed differently, 2 s.
#[test]
fn islands_stepped_in_parallel_give_the_same_bits() {
    bevy::tasks::ComputeTaskPool::get_or_init(|| bevy::tasks::TaskPoolBuilder::new().num_threads(4).build());
    let run = |parallel: bool| {
        let mut app = app_with(CablePlugin::default().with_parallel(parallel));
        let threads = bevy::tasks::ComputeTaskPool::get().thread_num();
        let mut ids = Vec::new();
        for k in 0..4 {
            let x = 3.0 * k as f32;
            let l = 4.0 + k as f32;
            let payload = app
                .world_mut()
                .spawn((
                    RigidBody::Dynamic,
                    Transform::from_xyz(x, -(l + R), 0.0),
                    Collider::ball(R),
                    ColliderMassProperties::Mass(M),
                    Velocity::linear(Vec3::new(0.5 * k as f32, 0.0, 0.3)),
                ))
                .id();
            let cable = app
                .world_mut()
                .spawn(CableDescriptor::new(l).segments(10 + 10 * k).start(CableAnchor::world(Vec3::X * x)).end(CableAnchor::body(payload, Vec3::Y * R)))
                .id();
            ids.push(cable);
        }
        for _ in 0..120 {
            app.update();
            let errors = app.world().resource::<Messages<CableError>>();
            assert!(errors.is_empty(), "{:?}", errors.iter_current_update_messages().collect::<Vec<_>>());
        }
        let states: Vec<(Vec<Vec3>, Vec<f32>, f64)> = ids
            .iter()
            .map(|c| {
                let s = app.world().get::<CableState>(*c).unwrap();
                (s.nodes.clone(), s.tensions.clone(), s.energy)
            })
            .collect();
        (states, threads)
    };
    let ((parallel, threads), (serial, _)) = (run(true), run(false));
    println!("compute task pool: {threads} threads; tip of cable 3: {:?}", parallel[3].0.last());
    assert!(threads > 1, "the pool has one thread: the parallel path did not run");
    assert!(parallel[3].0.last().unwrap().x > 9.0 + 0.1, "the pushed payload swung");
    assert_eq!(parallel, serial);
}
