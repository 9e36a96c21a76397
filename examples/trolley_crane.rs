//! A bridge-crane trolley on a rapier prismatic rail carries a 1 t payload on
//! 10 m of steel wire rope; the operator pushes the trolley for two seconds,
//! then lets go, and the payload sway is printed once a second.
//!
//! Headless (no window, no GPU): `cargo run --release --example trolley_crane [frames]`.
//! The trolley and the payload are links of the cable's implicit solve
//! (see `bevy_rapier_cable::plugin`), so the 1/60 s frame step is stable.

use bevy::app::ScheduleRunnerPlugin;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::plugin::*;

#[derive(Component)]
struct Trolley;

#[derive(Component)]
struct Payload;

#[derive(Resource)]
struct Frames(u64);

fn main() {
    let frames = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(1200u64);
    App::new()
        .add_plugins((
            MinimalPlugins.set(ScheduleRunnerPlugin::run_loop(std::time::Duration::ZERO)),
            TransformPlugin,
            RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(),
            CablePlugin::default(),
        ))
        .insert_resource(Time::<Fixed>::from_hz(60.0))
        .insert_resource(TimestepMode::Fixed { dt: 1.0 / 60.0, substeps: 1 })
        .insert_resource(TimeUpdateStrategy::FixedTimesteps(1))
        .insert_resource(Frames(frames))
        .add_systems(Startup, setup)
        .add_systems(FixedUpdate, (operator.before(CableSystems::Init), report.after(CableSystems::Readout)))
        .run();
}

fn setup(mut commands: Commands) {
    let rail = commands.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, 12.0, 0.0))).id();
    let trolley = commands
        .spawn((
            Trolley,
            RigidBody::Dynamic,
            Transform::from_xyz(0.0, 12.0, 0.0),
            Collider::cuboid(0.6, 0.25, 0.4),
            ColliderMassProperties::Mass(500.0),
            ExternalForce::default(),
            ImpulseJoint::new(rail, PrismaticJointBuilder::new(Vec3::X)),
        ))
        .id();
    let payload =
        commands.spawn((Payload, RigidBody::Dynamic, Transform::from_xyz(0.0, 1.45, 0.0), Collider::ball(0.3), ColliderMassProperties::Mass(1000.0))).id();
    commands.spawn(
        CableDescriptor::new(10.0)
            .material(RopeMaterial::steel_6x36_iwrc(0.020))
            .segments(50)
            .start(CableAnchor::body(trolley, Vec3::new(0.0, -0.25, 0.0)))
            .end(CableAnchor::body(payload, Vec3::new(0.0, 0.3, 0.0))),
    );
}

/// Pushes the trolley with 2 kN for the first two seconds.
fn operator(time: Res<Time>, mut q: Query<&mut ExternalForce, With<Trolley>>) {
    for mut f in &mut q {
        f.force = if time.elapsed_secs() < 2.0 { Vec3::X * 2000.0 } else { Vec3::ZERO };
    }
}

fn report(
    cables: Query<&CableState>,
    trolley: Query<&Transform, With<Trolley>>,
    payload: Query<&Transform, With<Payload>>,
    mut frames: ResMut<Frames>,
    mut diverged: MessageReader<CableError>,
    mut exit: MessageWriter<AppExit>,
) {
    for d in diverged.read() {
        eprintln!("cable diverged at t = {} s: {}", d.time, d.message);
        exit.write(AppExit::from_code(3));
    }
    let (Ok(state), Ok(t), Ok(p)) = (cables.single(), trolley.single(), payload.single()) else { return };
    let step = (state.time * 60.0).round() as u64;
    if step.is_multiple_of(60) {
        let sway = (p.translation.x - t.translation.x).atan2(t.translation.y - p.translation.y).to_degrees();
        println!(
            "t = {:5.2} s  trolley x = {:6.3} m  sway = {:6.2}°  top tension = {:7.0} N  ({} Newton iterations)",
            state.time,
            t.translation.x,
            sway,
            state.tensions.first().copied().unwrap_or(0.0),
            state.newton_iterations
        );
    }
    if frames.0 == 0 {
        exit.write(AppExit::Success);
    } else {
        frames.0 -= 1;
    }
}
