//! An overhead (bridge) crane: a trolley runs along the bridge girder on a
//! rapier prismatic rail and carries a 1 t crate on 10 m of 20 mm steel
//! wire rope (feature `demo`). The trolley is a link of the rope's
//! implicit solve (as in `trolley_crane.rs`); you drive it with the rail
//! joint's velocity motor.
//!
//! ```sh
//! cargo run --release --features demo --example overhead_crane
//! ```
//!
//! * arrow keys left/right or A / D: drive the trolley (1.5 m/s; let go to
//!   brake), within ±8.5 m of the girder's middle;
//! * mouse drag: orbit the camera; mouse wheel: zoom;
//! * R: reset (the trolley, the crate and the rope respawned at rest);
//! * X: anti-sway on/off: your speed commands pass through a ZV input
//!   shaper (`crane::control::OnlineShaper`) tuned to the crate's pendulum,
//!   so the crate arrives without swinging, half a swing period later (the
//!   trolley still stops hard at the travel limits).
//!
//! There is no hoisting: the plugin has no winch (paying out or hauling
//! in rope) yet.
//!
//! The HUD shows the sway angle (the chord from the trolley to the crate,
//! from the vertical), the rope's top tension and the trolley's speed.
//!
//! Options:
//! * `--headless N`: no window and no renderer: N fixed steps of 1/60 s
//!   with a scripted drive (1.5 m/s for 2 s, then brake), then one line
//!   with the time, the trolley's position and speed, the sway and the
//!   tension (used by `tests/examples_headless.rs`).
//! * `--screenshot FILE.png`: the same script, a screenshot 3 s into the
//!   run (the crate swinging after the trolley stopped), then exit.
//! * `--anti-sway`: start with anti-sway on. The headless report then
//!   also gives the largest sway after 6 s (the shaped stop ends at 5.2 s).

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::crane::control::{InputShaper, OnlineShaper, ShaperKind};
use bevy_rapier_cable::demo_support::*;
use bevy_rapier_cable::plugin::render::CableRender;
use bevy_rapier_cable::plugin::*;

/// Height of the rail (the trolley's centre), m.
const RAIL: f32 = 12.0;
/// Rope length, m.
const ROPE: f32 = 10.0;
/// Half extents of the crate, m.
const CRATE: Vec3 = Vec3::new(0.5, 0.4, 0.5);
/// Crate mass, kg.
const MASS: f32 = 1000.0;
/// Trolley mass, kg.
const TROLLEY_MASS: f32 = 500.0;
/// Trolley travel speed, m/s.
const SPEED: f32 = 1.5;
/// The trolley stays within ±this of the girder's middle, m.
const TRAVEL: f32 = 8.5;
/// The drive's largest force, N.
const DRIVE_FORCE: f32 = 20_000.0;

const USAGE: &str = "usage: overhead_crane [--headless FRAMES] [--screenshot FILE.png] [--anti-sway]";

/// Anti-sway: a ZV shaper on the operator's speed commands.
#[derive(Resource)]
struct AntiSway {
    on: bool,
    shaper: OnlineShaper,
    /// Largest |sway| (deg) after 6 s, for the headless report.
    late_sway: f32,
}

impl AntiSway {
    fn new(on: bool) -> Self {
        // The crate's pendulum: from the rope's top to the crate's centre
        // (10 m + 0.4 m), its 16 kg of rope lumped (a compound pendulum,
        // 0.3 % shorter); undamped.
        let length = (ROPE + CRATE.y) as f64 * 0.997;
        let shaper = InputShaper::new(ShaperKind::Zv, (9.81 / length).sqrt(), 0.0).expect("a positive pendulum frequency");
        AntiSway { on, shaper: OnlineShaper::new(shaper), late_sway: 0.0 }
    }
}

fn main() {
    let (mut options, flags) = DemoOptions::from_args_with_flags_or_exit(USAGE, &["--anti-sway"]);
    let anti_sway = !flags.is_empty();
    options.screenshot_after = 3.0;
    let mut app = demo_app("bevy_rapier_cable: overhead crane", &options);
    if options.headless.is_some() {
        app.add_systems(FixedUpdate, headless_report.after(CableSystems::Readout));
    } else {
        app.add_systems(Startup, setup_scene).add_systems(Update, (reset_rig(spawn_rig), hud, toggle_anti_sway));
    }
    app.insert_resource(AntiSway::new(anti_sway));
    app.add_plugins((RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default()))
        .add_systems(Startup, (setup_crane, spawn_rig).chain())
        .add_systems(FixedUpdate, drive.before(CableSystems::Init));
    run_and_exit(app);
}

/// The girder the trolley's rail is fixed to.
#[derive(Component)]
struct Girder;

/// The trolley.
#[derive(Component)]
struct Trolley;

/// The crate.
#[derive(Component)]
struct Payload;

/// The crate's rope.
#[derive(Component)]
struct Rope;

/// The bridge girder on two end frames, and the ground.
fn setup_crane(mut commands: Commands) {
    let steel = Tint(Color::srgb(0.95, 0.7, 0.1));
    commands.spawn((
        Name::new("ground"),
        RigidBody::Fixed,
        Collider::cuboid(20.0, 0.1, 20.0),
        Transform::from_xyz(0.0, -0.1, 0.0),
        Tint(Color::srgb(0.42, 0.45, 0.42)),
    ));
    // The girder sits on top of the trolley's wheels; no collider touches
    // the trolley (the rail joint holds it).
    commands.spawn((Name::new("girder"), Girder, RigidBody::Fixed, Collider::cuboid(10.0, 0.3, 0.25), Transform::from_xyz(0.0, RAIL + 0.6, 0.0), steel));
    for x in [-10.2, 10.2] {
        commands.spawn((
            Name::new("end frame"),
            RigidBody::Fixed,
            Collider::cuboid(0.2, 0.5 * (RAIL + 0.9), 0.3),
            Transform::from_xyz(x, 0.5 * (RAIL + 0.9), 0.0),
            steel,
        ));
    }
}

/// The trolley on its rail, the crate and the rope, statically settled.
fn spawn_rig(mut commands: Commands, girder: Query<Entity, With<Girder>>) {
    let Ok(girder) = girder.single() else { return };
    // The rail: the trolley slides along x on the girder's entity.
    let rail = PrismaticJointBuilder::new(Vec3::X).local_anchor1(Vec3::new(0.0, -0.6, 0.0));
    let trolley = commands
        .spawn((
            Name::new("trolley"),
            Trolley,
            Rig,
            RigidBody::Dynamic,
            Collider::cuboid(0.6, 0.25, 0.4),
            ColliderMassProperties::Mass(TROLLEY_MASS),
            Transform::from_xyz(0.0, RAIL, 0.0),
            Velocity::default(),
            ImpulseJoint::new(girder, rail),
            Tint(Color::srgb(0.2, 0.35, 0.75)),
        ))
        .id();
    let payload = commands
        .spawn((
            Name::new("crate"),
            Payload,
            Rig,
            RigidBody::Dynamic,
            Collider::cuboid(CRATE.x, CRATE.y, CRATE.z),
            ColliderMassProperties::Mass(MASS),
            Transform::from_xyz(0.0, RAIL - 0.25 - ROPE - CRATE.y, 0.0),
            Tint(Color::srgb(0.75, 0.25, 0.12)),
        ))
        .id();
    commands.spawn((
        Name::new("rope"),
        Rope,
        Rig,
        CableDescriptor::new(ROPE)
            .material(RopeMaterial::steel_6x36_iwrc(0.020))
            .segments(40)
            .start(CableAnchor::body(trolley, Vec3::new(0.0, -0.25, 0.0)))
            .end(CableAnchor::body(payload, Vec3::Y * CRATE.y))
            .static_start(4),
        // Drawn 3.5× thicker than the 20 mm rope so that it shows from afar.
        CableRender { radius: Some(0.035), color_by_tension: Some(15_000.0), ..default() },
    ));
}

/// The trolley's target speed, m/s: the keys, or the script of
/// `--headless` and `--screenshot` (1.5 m/s for 2 s, then stop); zero
/// beyond the travel limits.
fn target_speed(time: &Time, options: &DemoOptions, keys: Option<&ButtonInput<KeyCode>>, x: f32) -> f32 {
    let scripted = options.headless.is_some() || options.screenshot.is_some();
    let wanted = if scripted {
        if time.elapsed_secs() < 2.0 {
            SPEED
        } else {
            0.0
        }
    } else if let Some(keys) = keys {
        let key = |a: KeyCode, b: KeyCode| if keys.pressed(a) || keys.pressed(b) { 1.0 } else { 0.0 };
        SPEED * (key(KeyCode::ArrowRight, KeyCode::KeyD) - key(KeyCode::ArrowLeft, KeyCode::KeyA))
    } else {
        0.0
    };
    within_travel(x, wanted)
}

/// `v` (m/s), or 0 when it would take the trolley at `x` (m) past a
/// travel limit.
fn within_travel(x: f32, v: f32) -> f32 {
    if (x >= TRAVEL && v > 0.0) || (x <= -TRAVEL && v < 0.0) {
        0.0
    } else {
        v
    }
}

/// X toggles anti-sway (the shaper keeps listening while off, so turning
/// it on mid-move does not jump).
fn toggle_anti_sway(keys: Res<ButtonInput<KeyCode>>, mut anti: ResMut<AntiSway>) {
    if keys.just_pressed(KeyCode::KeyX) {
        anti.on = !anti.on;
    }
}

/// Fixed step, before the cables: the rail's velocity motor (the plugin
/// reads it: the trolley is a link of the rope's solve), the operator's
/// command shaped when anti-sway is on.
fn drive(
    time: Res<Time>,
    options: Res<DemoOptions>,
    keys: Option<Res<ButtonInput<KeyCode>>>,
    mut anti: ResMut<AntiSway>,
    mut trolley: Query<(&Transform, &mut ImpulseJoint), With<Trolley>>,
) {
    let Ok((pose, mut joint)) = trolley.single_mut() else { return };
    let x = pose.translation.x;
    let wanted = target_speed(&time, &options, keys.as_deref(), x);
    let shaped = anti.shaper.shape(time.elapsed_secs_f64(), wanted as f64) as f32;
    let v = if anti.on { shaped } else { wanted };
    // The travel limits stop the trolley whatever the shaper still asks.
    let v = within_travel(x, v);
    let h = time.delta_secs().max(1e-6);
    // Acceleration-based: the speed error halves every step, up to 20 kN.
    joint
        .data
        .as_mut()
        .set_motor_model(JointAxis::LinX, MotorModel::AccelerationBased)
        .set_motor_velocity(JointAxis::LinX, v, 1.0 / h)
        .set_motor_max_force(JointAxis::LinX, DRIVE_FORCE);
}

/// Sway angle from the vertical, degrees (positive: the crate trails in
/// −x), top tension, N, and trolley speed along the rail, m/s.
fn readings(trolley: (&Transform, &Velocity), payload: &Transform, rope: &CableState) -> (f32, f32, f32) {
    let d = trolley.0.translation - payload.translation;
    let sway = d.x.atan2(d.y).to_degrees();
    (sway, rope.tensions.first().copied().unwrap_or(0.0), trolley.1.linear.x)
}

/// `--headless N`: one line after N fixed steps, then exit.
fn headless_report(
    mut report: HeadlessReport,
    mut anti: ResMut<AntiSway>,
    trolley: Query<(&Transform, &Velocity), With<Trolley>>,
    payload: Query<&Transform, With<Payload>>,
    rope: Query<&CableState, With<Rope>>,
) {
    if let (Ok(t), Ok(p), Ok(state)) = (trolley.single(), payload.single(), rope.single()) {
        if state.time > 6.0 {
            anti.late_sway = anti.late_sway.max(readings(t, p, state).0.abs());
        }
    }
    if !report.due() {
        return;
    }
    let line = match (trolley.single(), payload.single(), rope.single()) {
        (Ok(t), Ok(p), Ok(state)) => {
            let (sway, tension, speed) = readings(t, p, state);
            let late = if state.time > 6.0 { format!(", largest sway since 6 s = {:.3} deg", anti.late_sway) } else { String::new() };
            Some(format!(
                "t = {:.2} s, trolley x = {:.3} m, speed = {:.3} m/s, sway = {:.2} deg, top tension = {:.3} kN, anti-sway {}{late}",
                state.time,
                t.0.translation.x,
                speed,
                sway,
                tension / 1000.0,
                if anti.on { "on" } else { "off" }
            ))
        }
        _ => None,
    };
    report.finish("overhead_crane", line);
}

/// Light, camera, help line and HUD.
fn setup_scene(mut commands: Commands, mut grid: ResMut<GroundGrid>) {
    grid.cells = 20;
    let camera = Orbit { focus: Vec3::new(0.0, 6.5, 0.0), yaw: 0.35, pitch: -0.12, distance: 27.0, keys: false };
    spawn_scene(
        &mut commands,
        camera,
        25.0,
        "left/right or A/D: drive the trolley   X: anti-sway on/off   drag: orbit   wheel: zoom   R: reset   (no hoist yet)",
    );
}

/// Time, sway, tension, trolley speed.
fn hud(
    time: Res<Time>,
    anti: Res<AntiSway>,
    trolley: Query<(&Transform, &Velocity), With<Trolley>>,
    payload: Query<&Transform, With<Payload>>,
    rope: Query<&CableState, With<Rope>>,
    mut text: Query<&mut Text, With<Hud>>,
) {
    let Ok(mut text) = text.single_mut() else { return };
    **text = match (trolley.single(), payload.single(), rope.single()) {
        (Ok(t), Ok(p), Ok(state)) => {
            let (sway, tension, speed) = readings(t, p, state);
            format!(
                "t = {:6.2} s   sway {:6.2} deg   rope tension {:6.2} kN   trolley {:5.2} m/s at x = {:5.2} m   anti-sway {}",
                time.elapsed_secs(),
                sway,
                tension / 1000.0,
                speed,
                t.0.translation.x,
                if anti.on { "ON (ZV)" } else { "off" }
            )
        }
        _ => format!("t = {:6.2} s   (rope building)", time.elapsed_secs()),
    };
}
