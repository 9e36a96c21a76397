//! A rope bridge you drop crates on (feature `demo`): two 20 mm steel wire
//! ropes, 6.03 m long, pinned between two pairs of posts 6 m apart and
//! 0.6 m apart, sag under their own weight. Each crate (20 kg, 0.4 × 0.2 ×
//! 0.9 m, a bevy_rapier body the game spawns) falls onto them and is, while
//! it touches them, a free body of the ropes' implicit step: the ropes sag
//! under it, it bounces, slides and comes to rest on them, and crates
//! dropped on crates stack (rapier's contact between them).
//!
//! ```sh
//! cargo run --release --features demo --example rope_bridge
//! ```
//!
//! * space: drop a crate above the marker; left/right or A/D: move the
//!   marker along the span;
//! * C: remove the crates; R: reset (ropes and crates respawned);
//! * mouse drag: orbit the camera; mouse wheel: zoom;
//! * T: tension colours on/off; G: gizmos on/off (nodes, and each
//!   contact's point and force on the rope: 1 kN drawn 3 m long).
//!
//! The HUD shows the crates on the bridge, the ropes' largest tension and
//! the middle's sag. While crates land and stack the step is slower than
//! real time (about 0.4× over a series of six; a dozen piled on the bridge
//! 0.05×: docs/performance.md, "Dynamic bodies on ropes"). The ropes are
//! damped (0.05 s): undamped, they ring after every landing and can stop
//! (docs/embedding.md, "Contact and friction").
//!
//! Options:
//! * `--headless N`: no window and no renderer: N fixed steps of 1/60 s
//!   in which six crates are dropped 0.7 s apart (the sixth on the first
//!   two) and the first is removed at 6 s, then one line with the time,
//!   the crates still on the bridge, the lowest and highest crate and the
//!   largest tension (used by `tests/examples_headless.rs`).
//! * `--screenshot FILE.png`: the same drops, a screenshot 4.5 s in, then
//!   exit.
//! * `--gizmos`: the gizmos on from the start.

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::demo_support::*;
use bevy_rapier_cable::plugin::render::{CableGizmos, CableRender};
use bevy_rapier_cable::plugin::*;

/// Half the span between the posts' pins, m.
const HALF_SPAN: f32 = 3.0;
/// The pins' height, m.
const PIN_Y: f32 = 2.0;
/// The ropes' z, m.
const ROPES_Z: [f32; 2] = [-0.3, 0.3];
/// Rope length, m (0.5 % longer than the span: it sags).
const ROPE: f32 = 6.03;
/// A crate's half extents, m, and mass, kg.
const CRATE: (Vec3, f32) = (Vec3::new(0.2, 0.1, 0.45), 20.0);
/// Crates are let go this far above the pins, m.
const DROP_HEIGHT: f32 = 0.7;
/// Tension drawn red, N.
const RED_AT: f32 = 5_000.0;
/// `--headless` and `--screenshot`: (time s, x m) of each crate dropped.
const DROPS: [(f32, f32); 6] = [(0.0, 0.0), (0.7, 0.8), (1.4, -0.8), (2.1, 1.5), (2.8, -1.5), (3.5, 0.4)];
/// `--headless`: when the first crate is removed, s.
const REMOVE_AT: f32 = 6.0;

const USAGE: &str = "usage: rope_bridge [--headless FRAMES] [--screenshot FILE.png] [--gizmos]";

fn main() {
    let (mut options, flags) = DemoOptions::from_args_with_flags_or_exit(USAGE, &["--gizmos"]);
    options.screenshot_after = 4.5;
    let scripted = options.headless.is_some() || options.screenshot.is_some();
    let mut app = demo_app("bevy_rapier_cable: rope bridge", &options);
    if options.headless.is_some() {
        app.add_systems(FixedUpdate, headless_report.after(CableSystems::Readout));
    } else {
        app.add_systems(Startup, setup_scene).add_systems(Update, (drop_keys, clear_keys, reset_rig(spawn_ropes), look_keys(RED_AT), hud, show_marker));
        let on = flags.contains(&"--gizmos");
        app.add_systems(Startup, move |store: ResMut<GizmoConfigStore>| gizmos(store, on));
    }
    if scripted {
        app.add_systems(FixedUpdate, scripted_drops.before(CableSystems::Step));
    }
    app.init_resource::<Marker>()
        .init_resource::<Tallies>()
        .add_plugins((RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default()))
        .add_systems(Startup, (setup_posts, spawn_ropes))
        .add_systems(FixedUpdate, tally.after(CableSystems::Readout));
    run_and_exit(app);
}

/// Where the next crate is dropped: x along the span, m.
#[derive(Resource, Default)]
struct Marker(f32);

/// The largest tension in the ropes since the last reset, N, and the
/// fixed steps run.
#[derive(Resource, Default)]
struct Tallies {
    most: f32,
    steps: u32,
}

/// One of the bridge's ropes.
#[derive(Component)]
struct BridgeRope;

/// A crate.
#[derive(Component)]
struct Crate;

/// The marker's gizmo stand-in: a flat box above the bridge.
#[derive(Component)]
struct MarkerBox;

/// The ground and the four posts (fixed bodies; the ropes are pinned to
/// points on their tops).
fn setup_posts(mut commands: Commands) {
    commands.spawn((
        Name::new("ground"),
        RigidBody::Fixed,
        Collider::cuboid(8.0, 0.1, 5.0),
        Transform::from_xyz(0.0, -0.1, 0.0),
        Tint(Color::srgb(0.40, 0.47, 0.36)),
    ));
    let wood = Tint(Color::srgb(0.45, 0.32, 0.2));
    for x in [-HALF_SPAN, HALF_SPAN] {
        for z in ROPES_Z {
            // Just outside the pin, so that the rope leaves it freely.
            let at = Vec3::new(x + 0.1 * x.signum(), 0.5 * PIN_Y, z);
            commands.spawn((Name::new("post"), RigidBody::Fixed, Collider::cuboid(0.07, 0.5 * PIN_Y, 0.07), Transform::from_translation(at), wood));
        }
    }
}

/// The two ropes, laid straight between their pins (they sag to their
/// catenary in the first second).
fn spawn_ropes(mut commands: Commands, mut tallies: ResMut<Tallies>) {
    tallies.most = 0.0;
    let rope = RopeMaterial::steel_6x36_iwrc(0.020);
    for z in ROPES_Z {
        let (a, b) = (Vec3::new(-HALF_SPAN, PIN_Y, z), Vec3::new(HALF_SPAN, PIN_Y, z));
        commands.spawn((
            Name::new("bridge rope"),
            BridgeRope,
            Rig,
            // Rope damping (a time constant, s) calms the strikes' waves.
            CableDescriptor::new(ROPE).material(rope).segments(30).damping(0.05).friction(0.5).start(CableAnchor::world(a)).end(CableAnchor::world(b)),
            CableRender { radius: Some(0.02), color_by_tension: Some(RED_AT), ..default() },
        ));
    }
}

/// A crate let go at rest above the bridge at `x`.
fn drop_crate(commands: &mut Commands, x: f32) {
    commands.spawn((
        Name::new("crate"),
        Crate,
        Rig,
        RigidBody::Dynamic,
        Collider::cuboid(CRATE.0.x, CRATE.0.y, CRATE.0.z),
        ColliderMassProperties::Mass(CRATE.1),
        Friction::coefficient(0.5),
        Velocity::zero(),
        Transform::from_xyz(x, PIN_Y + DROP_HEIGHT, 0.0),
        Tint(Color::srgb(0.72, 0.52, 0.3)),
    ));
}

/// `--headless` and `--screenshot`: the crates of [`DROPS`], and the
/// first one removed at [`REMOVE_AT`].
fn scripted_drops(mut commands: Commands, mut tallies: ResMut<Tallies>, crates: Query<Entity, With<Crate>>) {
    let t = tallies.steps as f32 / 60.0;
    tallies.steps += 1;
    for (at, x) in DROPS {
        if (t - at).abs() < 0.5 / 60.0 {
            drop_crate(&mut commands, x);
        }
    }
    if (t - REMOVE_AT).abs() < 0.5 / 60.0 {
        if let Some(first) = crates.iter().min() {
            commands.entity(first).despawn();
        }
    }
}

/// Fixed step: the largest tension so far.
fn tally(ropes: Query<&CableState, With<BridgeRope>>, mut tallies: ResMut<Tallies>) {
    for state in &ropes {
        tallies.most = state.tensions.iter().copied().fold(tallies.most, f32::max);
    }
}

/// The crates on the bridge (their centres less than a metre below the
/// pins and at most a crate's height above them: not falling onto it, not
/// fallen through), the lowest and highest of them, m.
fn on_bridge(crates: &Query<&Transform, With<Crate>>) -> (usize, f32, f32) {
    crates
        .iter()
        .map(|t| t.translation.y)
        .filter(|y| (PIN_Y - 1.0..PIN_Y + 2.0 * CRATE.0.y).contains(y))
        .fold((0, f32::INFINITY, f32::NEG_INFINITY), |(n, low, high), y| (n + 1, low.min(y), high.max(y)))
}

/// The middle's sag below the pins (the first rope), m.
fn sag(ropes: &Query<&CableState, With<BridgeRope>>) -> Option<f32> {
    ropes.iter().next().and_then(|s| s.nodes.get(s.nodes.len() / 2)).map(|p| PIN_Y - p.y)
}

/// `--headless N`: one line after N fixed steps, then exit.
fn headless_report(mut report: HeadlessReport, ropes: Query<&CableState, With<BridgeRope>>, crates: Query<&Transform, With<Crate>>, tallies: Res<Tallies>) {
    if report.due() {
        let (n, low, high) = on_bridge(&crates);
        let line = ropes.iter().next().map(|state| {
            format!(
                "t = {:.2} s, crates on the bridge = {n} of {}, lowest crate y = {low:.3} m, highest crate y = {high:.3} m, largest tension = {:.3} kN",
                state.time,
                crates.iter().count(),
                tallies.most / 1000.0
            )
        });
        report.finish("rope_bridge", line);
    }
}

/// Light, camera, help line, HUD and the drop marker.
fn setup_scene(mut commands: Commands, mut meshes: ResMut<Assets<Mesh>>, mut materials: ResMut<Assets<StandardMaterial>>) {
    let camera = Orbit { focus: Vec3::new(0.0, 1.5, 0.0), yaw: 0.55, pitch: -0.3, distance: 9.0, keys: false };
    spawn_scene(
        &mut commands,
        camera,
        10.0,
        "space: drop a crate   left/right: move the marker   C: clear crates   drag: orbit   wheel: zoom   R: reset   T: tension colours   G: gizmos",
    );
    commands.spawn((
        MarkerBox,
        Mesh3d(meshes.add(Cuboid::new(2.0 * CRATE.0.x, 0.02, 2.0 * CRATE.0.z))),
        MeshMaterial3d(materials.add(StandardMaterial { base_color: Color::srgba(0.95, 0.8, 0.2, 0.5), alpha_mode: AlphaMode::Blend, ..default() })),
        Transform::from_xyz(0.0, PIN_Y + DROP_HEIGHT + CRATE.0.y, 0.0),
    ));
}

/// The cable gizmos: a crate's contact forces are tens of newtons each,
/// so 1 kN is drawn 3 m long; on from the start with `--gizmos`.
fn gizmos(mut store: ResMut<GizmoConfigStore>, on: bool) {
    let (config, ext) = store.config_mut::<CableGizmos>();
    config.enabled = on;
    ext.force_scale = 3e-3;
}

/// Space drops a crate above the marker; left/right (A/D) move the marker.
fn drop_keys(mut commands: Commands, keys: Res<ButtonInput<KeyCode>>, time: Res<Time>, mut marker: ResMut<Marker>) {
    let mut dx = 0.0;
    if keys.any_pressed([KeyCode::ArrowLeft, KeyCode::KeyA]) {
        dx -= 1.5;
    }
    if keys.any_pressed([KeyCode::ArrowRight, KeyCode::KeyD]) {
        dx += 1.5;
    }
    marker.0 = (marker.0 + dx * time.delta_secs()).clamp(-HALF_SPAN + 0.6, HALF_SPAN - 0.6);
    if keys.just_pressed(KeyCode::Space) {
        drop_crate(&mut commands, marker.0);
    }
}

/// C removes every crate.
fn clear_keys(mut commands: Commands, keys: Res<ButtonInput<KeyCode>>, crates: Query<Entity, With<Crate>>) {
    if keys.just_pressed(KeyCode::KeyC) {
        for e in &crates {
            commands.entity(e).despawn();
        }
    }
}

/// The marker follows [`Marker`].
fn show_marker(marker: Res<Marker>, mut boxes: Query<&mut Transform, With<MarkerBox>>) {
    for mut t in &mut boxes {
        t.translation.x = marker.0;
    }
}

/// Time, crates, largest tension, sag.
fn hud(
    time: Res<Time>,
    tallies: Res<Tallies>,
    ropes: Query<&CableState, With<BridgeRope>>,
    crates: Query<&Transform, With<Crate>>,
    mut text: Query<&mut Text, With<Hud>>,
) {
    let Ok(mut text) = text.single_mut() else { return };
    let (n, _, _) = on_bridge(&crates);
    let now = ropes.iter().flat_map(|s| s.tensions.iter().copied()).fold(0.0f32, f32::max);
    **text = match sag(&ropes) {
        Some(sag) => format!(
            "t = {:6.2} s   crates on the bridge {n}   tension {:5.2} kN (largest {:5.2} kN)   sag {:4.2} m",
            time.elapsed_secs(),
            now / 1000.0,
            tallies.most / 1000.0,
            sag
        ),
        None => format!("t = {:6.2} s   (ropes building)", time.elapsed_secs()),
    };
}
