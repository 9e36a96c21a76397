//! A 1 t crate hanging 10 m below a gantry beam on 20 mm steel wire rope,
//! drawn with the render plugin (feature `demo`).
//!
//! ```sh
//! cargo run --release --features demo --example hanging_payload
//! ```
//!
//! * mouse drag: orbit the camera; mouse wheel: zoom;
//! * arrow keys / WASD: push the crate (a 2 kN `ExternalImpulse` every
//!   fixed step, along the camera's view on the ground); space: a big kick
//!   (3 m/s); R: reset (despawn and respawn the crate and its rope);
//! * T: tension colours on/off; G: gizmos on/off (nodes, contacts).
//!
//! Options:
//! * `--headless N`: no window and no renderer (`MinimalPlugins`): runs
//!   N fixed steps of 1/60 s with a scripted 1 m/s sideways kick at
//!   0.2 s, then prints one line with the time, the top tension and the
//!   sway angle (used by `tests/examples_headless.rs`).
//! * `--screenshot FILE.png`: the same scripted kick, then saves a
//!   screenshot of the window 1.8 s into the run (the swing's first
//!   extreme) and exits.

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::demo_support::*;
use bevy_rapier_cable::plugin::render::CableRender;
use bevy_rapier_cable::plugin::*;

/// Rope anchor under the beam, m.
const ANCHOR: Vec3 = Vec3::new(0.0, 12.0, 0.0);
/// Rope length, m.
const ROPE: f32 = 10.0;
/// Half extents of the crate, m.
const CRATE: Vec3 = Vec3::new(0.6, 0.4, 0.4);
/// Crate mass, kg.
const MASS: f32 = 1000.0;
/// Tension drawn red, N.
const RED_AT: f32 = 15_000.0;

const USAGE: &str = "usage: hanging_payload [--headless FRAMES] [--screenshot FILE.png]";

fn main() {
    let options = DemoOptions::from_args_or_exit(USAGE);
    let mut app = demo_app("bevy_rapier_cable: hanging payload", &options);
    if options.headless.is_some() {
        app.add_systems(FixedUpdate, headless_report.after(CableSystems::Readout));
    } else {
        app.init_resource::<Kick>().add_systems(Startup, setup_scene).add_systems(Update, (kick_key, reset_rig(spawn_rig), look_keys(RED_AT), hud));
    }
    app.add_plugins((RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default()))
        .add_systems(Startup, (setup_gantry, spawn_rig))
        .add_systems(FixedUpdate, push.before(CableSystems::Init));
    run_and_exit(app);
}

/// The crate.
#[derive(Component)]
struct Payload;

/// The crate's rope.
#[derive(Component)]
struct Rope;

/// A kick asked for in `Update` (space), given at the next fixed step.
#[derive(Resource, Default)]
struct Kick(bool);

/// The gantry: two legs and a beam (fixed bodies), and the ground.
fn setup_gantry(mut commands: Commands) {
    let steel = Tint(Color::srgb(0.95, 0.7, 0.1));
    commands.spawn((
        Name::new("ground"),
        RigidBody::Fixed,
        Collider::cuboid(20.0, 0.1, 20.0),
        Transform::from_xyz(0.0, -0.1, 0.0),
        Tint(Color::srgb(0.42, 0.45, 0.42)),
    ));
    for x in [-4.0, 4.0] {
        commands.spawn((Name::new("gantry leg"), RigidBody::Fixed, Collider::cuboid(0.2, 6.25, 0.2), Transform::from_xyz(x, 6.25, 0.0), steel));
    }
    commands.spawn((Name::new("gantry beam"), RigidBody::Fixed, Collider::cuboid(4.3, 0.25, 0.25), Transform::from_xyz(0.0, ANCHOR.y + 0.25, 0.0), steel));
}

/// The crate and its rope, statically settled.
fn spawn_rig(mut commands: Commands) {
    let payload = commands
        .spawn((
            Name::new("crate"),
            Payload,
            Rig,
            RigidBody::Dynamic,
            Collider::cuboid(CRATE.x, CRATE.y, CRATE.z),
            ColliderMassProperties::Mass(MASS),
            Transform::from_translation(ANCHOR - Vec3::Y * (ROPE + CRATE.y)),
            ExternalImpulse::default(),
            Tint(Color::srgb(0.75, 0.25, 0.12)),
        ))
        .id();
    commands.spawn((
        Name::new("rope"),
        Rope,
        Rig,
        CableDescriptor::new(ROPE)
            .material(RopeMaterial::steel_6x36_iwrc(0.020))
            .start(CableAnchor::world(ANCHOR))
            .end(CableAnchor::body(payload, Vec3::Y * CRATE.y))
            .static_start(4),
        // Drawn 3.5× thicker than the 20 mm rope so that it shows from afar.
        CableRender { radius: Some(0.035), color_by_tension: Some(RED_AT), ..default() },
    ));
}

/// Fixed step, before the cables: arrow keys / WASD push the crate, space
/// (or the script of `--headless` and `--screenshot`) kicks it.
fn push(
    time: Res<Time>,
    options: Res<DemoOptions>,
    keys: Option<Res<ButtonInput<KeyCode>>>,
    mut kick: Option<ResMut<Kick>>,
    camera: Query<&Transform, With<Orbit>>,
    mut payload: Query<&mut ExternalImpulse, With<Payload>>,
) {
    let Ok(mut impulse) = payload.single_mut() else { return };
    let dt = time.delta_secs();
    // The camera's forward and right on the ground.
    let (forward, right) = camera.single().map_or((Vec3::NEG_Z, Vec3::X), |t| {
        let f = Vec3::new(t.forward().x, 0.0, t.forward().z).normalize_or(Vec3::NEG_Z);
        (f, f.cross(Vec3::Y))
    });
    let mut push = Vec3::ZERO;
    if let Some(keys) = &keys {
        let key = |a: KeyCode, b: KeyCode| if keys.pressed(a) || keys.pressed(b) { 1.0 } else { 0.0 };
        push += forward * (key(KeyCode::ArrowUp, KeyCode::KeyW) - key(KeyCode::ArrowDown, KeyCode::KeyS));
        push += right * (key(KeyCode::ArrowRight, KeyCode::KeyD) - key(KeyCode::ArrowLeft, KeyCode::KeyA));
    }
    let mut j = push.normalize_or_zero() * 2000.0 * dt; // 2 kN, N·s
    if kick.as_mut().is_some_and(|k| std::mem::take(&mut k.0)) {
        j += forward * 3.0 * MASS; // 3 m/s
    }
    let scripted = options.headless.is_some() || options.screenshot.is_some();
    if scripted && (time.elapsed_secs() - 0.2).abs() < 0.5 * dt {
        j += Vec3::X * 1.0 * MASS; // 1 m/s sideways
    }
    if j != Vec3::ZERO || impulse.impulse != Vec3::ZERO {
        impulse.impulse = j;
    }
}

/// The top tension, N, and the sway angle, degrees, of the rope.
fn readings(state: &CableState) -> (f32, f32) {
    let top = state.tensions.first().copied().unwrap_or(0.0);
    let sway = match (state.nodes.first(), state.nodes.last()) {
        (Some(a), Some(b)) if a != b => (*a - *b).angle_between(Vec3::Y).to_degrees(),
        _ => 0.0,
    };
    (top, sway)
}

/// `--headless N`: one line after N fixed steps, then exit.
fn headless_report(mut report: HeadlessReport, rope: Query<&CableState, With<Rope>>) {
    if report.due() {
        let line = rope.single().ok().map(|state| {
            let (top, sway) = readings(state);
            format!("t = {:.2} s, top tension = {:.3} kN, sway = {:.2} deg", state.time, top / 1000.0, sway)
        });
        report.finish("hanging_payload", line);
    }
}

/// Light, camera, help line and HUD.
fn setup_scene(mut commands: Commands) {
    let camera = Orbit { focus: Vec3::new(0.0, 7.3, 0.0), yaw: 0.6, pitch: -0.14, distance: 21.0, keys: false };
    spawn_scene(&mut commands, camera, 20.0, "drag: orbit   wheel: zoom   arrows/WASD: push   space: kick   R: reset   T: tension colours   G: gizmos");
}

/// Space kicks (R, T and G: [`reset_rig`], [`look_keys`]).
fn kick_key(keys: Res<ButtonInput<KeyCode>>, mut kick: ResMut<Kick>) {
    if keys.just_pressed(KeyCode::Space) {
        kick.0 = true;
    }
}

/// Time, top tension and sway.
fn hud(time: Res<Time>, rope: Query<&CableState, With<Rope>>, mut text: Query<&mut Text, With<Hud>>) {
    let Ok(mut text) = text.single_mut() else { return };
    **text = match rope.single() {
        Ok(state) => {
            let (top, sway) = readings(state);
            format!("t = {:6.2} s   top tension {:6.2} kN   sway {:5.2} deg   (1 t crate, 10 m of 20 mm steel rope)", time.elapsed_secs(), top / 1000.0, sway)
        }
        Err(_) => format!("t = {:6.2} s   (rope building)", time.elapsed_secs()),
    };
}
