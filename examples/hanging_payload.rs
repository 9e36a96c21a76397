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
//! * T: tension colours on/off; G: node gizmos on/off.
//!
//! Options:
//! * `--headless N`: no window and no renderer (`MinimalPlugins`): runs
//!   N fixed steps of 1/60 s with a scripted 1 m/s sideways kick at
//!   0.2 s, then prints one line with the time, the top tension and the
//!   sway angle (used by `tests/examples_headless.rs`).
//! * `--screenshot FILE.png`: the same scripted kick, then saves a
//!   screenshot of the window 1.8 s into the run (the swing's first
//!   extreme) and exits.

use bevy::app::ScheduleRunnerPlugin;
use bevy::input::mouse::{AccumulatedMouseMotion, AccumulatedMouseScroll, MouseScrollUnit};
use bevy::light::CascadeShadowConfigBuilder;
use bevy::prelude::*;
use bevy::render::view::screenshot::{save_to_disk, Screenshot, ScreenshotCaptured};
use bevy::text::FontSize;
use bevy::time::TimeUpdateStrategy;
use bevy::window::WindowResolution;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::plugin::render::{CableGizmos, CableRender, CableRenderPlugin};
use bevy_rapier_cable::plugin::*;
use std::path::PathBuf;

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

/// What the command line asked for.
#[derive(Resource, Clone, Default)]
struct Options {
    headless: Option<u64>,
    screenshot: Option<PathBuf>,
}

fn options() -> Result<Options, String> {
    let mut o = Options::default();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--headless" => {
                let n = args.next().ok_or("--headless needs a number of frames")?;
                o.headless = Some(n.parse().map_err(|_| format!("--headless: not a number of frames: {n}"))?);
            }
            "--screenshot" => o.screenshot = Some(args.next().ok_or("--screenshot needs a file name")?.into()),
            "-h" | "--help" => return Err(String::new()),
            other => return Err(format!("unknown argument {other}")),
        }
    }
    Ok(o)
}

fn main() {
    let options = match options() {
        Ok(o) => o,
        Err(why) => {
            if !why.is_empty() {
                eprintln!("{why}");
            }
            eprintln!("{USAGE}");
            std::process::exit(2);
        }
    };
    let mut app = App::new();
    match options.headless {
        Some(_) => {
            app.add_plugins((MinimalPlugins.set(ScheduleRunnerPlugin::run_loop(std::time::Duration::ZERO)), TransformPlugin))
                .insert_resource(TimeUpdateStrategy::FixedTimesteps(1))
                .add_systems(FixedUpdate, headless_report.after(CableSystems::Readout));
        }
        None => {
            let window = Window { title: "bevy_rapier_cable: hanging payload".into(), resolution: WindowResolution::new(1280, 720), ..default() };
            app.add_plugins((DefaultPlugins.set(WindowPlugin { primary_window: Some(window), ..default() }), CableRenderPlugin::default()))
                .insert_resource(ClearColor(Color::srgb(0.62, 0.75, 0.88)))
                .insert_resource(GlobalAmbientLight { brightness: 400.0, ..default() })
                .init_resource::<Kick>()
                .add_systems(Startup, setup_scene)
                .add_systems(FixedPostUpdate, record_bodies)
                .add_systems(Update, (dress_bodies, follow_bodies, orbit_camera, keys, hud, ground_grid, screenshot));
        }
    }
    let exit = app
        .add_plugins((RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default()))
        .insert_resource(Time::<Fixed>::from_hz(60.0))
        .insert_resource(TimestepMode::Fixed { dt: 1.0 / 60.0, substeps: 1 })
        .insert_resource(options)
        .add_systems(Startup, (setup_gantry, spawn_rig))
        .add_systems(FixedUpdate, push.before(CableSystems::Init))
        .run();
    if let AppExit::Error(code) = exit {
        std::process::exit(code.get().into());
    }
}

/// The crate.
#[derive(Component)]
struct Payload;

/// The crate's rope.
#[derive(Component)]
struct Rope;

/// What R despawns.
#[derive(Component)]
struct Rig;

/// The colour a body is drawn with.
#[derive(Component, Clone, Copy)]
struct Tint(Color);

/// A kick asked for in `Update` (space), given at the next fixed step.
#[derive(Resource, Default)]
struct Kick(bool);

/// The orbit camera: it looks at `focus` from `distance` m, at `yaw` and
/// `pitch`, rad.
#[derive(Component)]
struct Orbit {
    focus: Vec3,
    yaw: f32,
    pitch: f32,
    distance: f32,
}

/// The HUD line.
#[derive(Component)]
struct Hud;

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
    options: Res<Options>,
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
fn headless_report(
    options: Res<Options>,
    mut steps: Local<u64>,
    rope: Query<&CableState, With<Rope>>,
    mut errors: MessageReader<CableError>,
    mut exit: MessageWriter<AppExit>,
) {
    for e in errors.read() {
        eprintln!("{e}");
        exit.write(AppExit::from_code(3));
    }
    *steps += 1;
    if *steps < options.headless.unwrap_or(0) {
        return;
    }
    match rope.single() {
        Ok(state) => {
            let (top, sway) = readings(state);
            println!("hanging_payload: t = {:.2} s, top tension = {:.3} kN, sway = {:.2} deg", state.time, top / 1000.0, sway);
            exit.write(AppExit::Success);
        }
        Err(_) => {
            eprintln!("hanging_payload: no rope state after {} steps", *steps);
            exit.write(AppExit::from_code(1));
        }
    }
}

/// Light, camera, help line and HUD.
fn setup_scene(mut commands: Commands) {
    commands.spawn((
        DirectionalLight { illuminance: 9000.0, shadow_maps_enabled: true, ..default() },
        Transform::from_xyz(8.0, 20.0, 10.0).looking_at(Vec3::ZERO, Vec3::Y),
        CascadeShadowConfigBuilder { maximum_distance: 60.0, first_cascade_far_bound: 18.0, ..default() }.build(),
    ));
    let orbit = Orbit { focus: Vec3::new(0.0, 6.0, 0.0), yaw: 0.6, pitch: -0.14, distance: 19.0 };
    commands.spawn((Camera3d::default(), orbit_transform(&orbit), orbit));
    let font = TextFont { font_size: FontSize::Px(17.0), ..default() };
    commands
        .spawn((
            Node {
                position_type: PositionType::Absolute,
                bottom: px(10),
                left: px(10),
                padding: UiRect::all(px(8)),
                flex_direction: FlexDirection::Column,
                row_gap: px(4),
                ..default()
            },
            BackgroundColor(Color::srgba(0.0, 0.0, 0.0, 0.55)),
        ))
        .with_children(|p| {
            p.spawn((Text::new("drag: orbit   wheel: zoom   arrows/WASD: push   space: kick   R: reset   T: tension colours   G: gizmos"), font.clone()));
            p.spawn((Hud, Text::new(""), font.clone(), TextColor(Color::srgb(1.0, 0.92, 0.5))));
        });
}

/// Where the orbit camera is.
fn orbit_transform(o: &Orbit) -> Transform {
    let rot = Quat::from_euler(EulerRot::YXZ, o.yaw, o.pitch, 0.0);
    Transform::from_translation(o.focus + rot * Vec3::Z * o.distance).looking_at(o.focus, Vec3::Y)
}

/// Mouse drag orbits, the wheel zooms.
fn orbit_camera(
    buttons: Res<ButtonInput<MouseButton>>,
    motion: Res<AccumulatedMouseMotion>,
    scroll: Res<AccumulatedMouseScroll>,
    mut camera: Query<(&mut Orbit, &mut Transform)>,
) {
    let Ok((mut o, mut t)) = camera.single_mut() else { return };
    if buttons.any_pressed([MouseButton::Left, MouseButton::Right]) {
        o.yaw -= motion.delta.x * 0.005;
        o.pitch = (o.pitch - motion.delta.y * 0.005).clamp(-1.4, 0.3);
    }
    let notches = match scroll.unit {
        MouseScrollUnit::Line => scroll.delta.y,
        MouseScrollUnit::Pixel => scroll.delta.y / 40.0,
    };
    o.distance = (o.distance * (-0.1 * notches).exp()).clamp(3.0, 80.0);
    *t = orbit_transform(&o);
}

/// Space kicks, R resets, T and G toggle the looks.
fn keys(
    mut commands: Commands,
    keys: Res<ButtonInput<KeyCode>>,
    mut kick: ResMut<Kick>,
    rig: Query<Entity, With<Rig>>,
    mut looks: Query<&mut CableRender>,
    mut gizmos: ResMut<GizmoConfigStore>,
) {
    if keys.just_pressed(KeyCode::Space) {
        kick.0 = true;
    }
    if keys.just_pressed(KeyCode::KeyR) {
        for e in &rig {
            commands.entity(e).despawn();
        }
        commands.run_system_cached(spawn_rig);
    }
    if keys.just_pressed(KeyCode::KeyT) {
        for mut look in &mut looks {
            look.color_by_tension = if look.color_by_tension.is_some() { None } else { Some(RED_AT) };
        }
    }
    if keys.just_pressed(KeyCode::KeyG) {
        let (config, _) = gizmos.config_mut::<CableGizmos>();
        config.enabled = !config.enabled;
    }
}

/// Bodies are drawn with their collider's shape (cuboids and balls here).
/// A fixed body carries its mesh; a dynamic one is drawn by a separate
/// entity ([`Follow`]) whose pose is interpolated between fixed steps, as
/// the rope is, so that the rope's end stays on the crate at any frame
/// rate (the body's own `Transform` is rapier's, at the fixed steps).
fn dress_bodies(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    new: Query<(Entity, &Collider, &Tint, &RigidBody, &Transform), Added<Collider>>,
) {
    for (e, collider, tint, body, pose) in &new {
        let mesh = if let Some(c) = collider.as_cuboid() {
            meshes.add(Cuboid::from_size(2.0 * c.half_extents()))
        } else if let Some(b) = collider.as_ball() {
            meshes.add(Sphere::new(b.radius()))
        } else {
            continue;
        };
        let look = (Mesh3d(mesh), MeshMaterial3d(materials.add(StandardMaterial { base_color: tint.0, perceptual_roughness: 0.6, ..default() })));
        match body {
            RigidBody::Dynamic => {
                commands.spawn((look, *pose, Follow { body: e, previous: *pose, current: *pose }));
            }
            _ => {
                commands.entity(e).insert(look);
            }
        }
    }
}

/// A visual entity drawing a dynamic body, at its pose blended between the
/// last two fixed steps.
#[derive(Component)]
struct Follow {
    body: Entity,
    previous: Transform,
    current: Transform,
}

/// Fixed step: the bodies' poses after the step.
fn record_bodies(mut visuals: Query<&mut Follow>, bodies: Query<&Transform>) {
    for mut f in &mut visuals {
        if let Ok(t) = bodies.get(f.body) {
            f.previous = f.current;
            f.current = *t;
        }
    }
}

/// Frame: blend by the overstep; a visual whose body is gone goes too.
fn follow_bodies(mut commands: Commands, time: Res<Time<Fixed>>, mut visuals: Query<(Entity, &Follow, &mut Transform)>, bodies: Query<(), With<RigidBody>>) {
    let a = time.overstep_fraction().clamp(0.0, 1.0);
    for (e, f, mut t) in &mut visuals {
        if bodies.get(f.body).is_err() {
            commands.entity(e).despawn();
            continue;
        }
        t.translation = f.previous.translation.lerp(f.current.translation, a);
        t.rotation = f.previous.rotation.slerp(f.current.rotation, a);
    }
}

/// A 2 m grid on the ground.
fn ground_grid(mut gizmos: Gizmos) {
    let on_ground = Isometry3d::new(Vec3::Y * 0.005, Quat::from_rotation_x(std::f32::consts::FRAC_PI_2));
    gizmos.grid(on_ground, UVec2::splat(20), Vec2::splat(2.0), Color::srgba(0.1, 0.1, 0.1, 0.6));
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

/// `--screenshot FILE`: a screenshot 1.8 s into the run, then exit.
fn screenshot(mut commands: Commands, time: Res<Time>, options: Res<Options>, mut taken: Local<bool>) {
    let Some(path) = &options.screenshot else { return };
    if *taken || time.elapsed_secs() < 1.8 {
        return;
    }
    *taken = true;
    commands.spawn(Screenshot::primary_window()).observe(save_to_disk(path.clone())).observe(|_: On<ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| {
        exit.write(AppExit::Success);
    });
}
