//! The seed paper's cable impact (Fang et al. 2009; feature `demo`): a
//! horizontal 20 mm steel rope pinned between two posts 4 m apart, and a
//! 2.5 m rope hanging from a gallows with a 50 kg hook, let go 50° out so
//! that it swings into the span at about 3.5 m/s, wraps over it and swings
//! back. Both ropes are beam chains stepped together in one implicit solve
//! while they touch (`assets/scenarios/cable_impact.toml` is the same
//! scene as a scenario file).
//!
//! ```sh
//! cargo run --release --features demo --example cable_impact
//! ```
//!
//! * space: let the hook go again from the release angle; up/down or
//!   W/S: release angle ±5° (20°–70°, taken at the next release);
//! * mouse drag: orbit the camera; mouse wheel: zoom;
//! * R: reset (both ropes and the hook respawned); T: tension colours
//!   on/off; G: gizmos on/off (nodes, contacts).
//!
//! The HUD shows the contact force between the ropes, the pendant's top
//! tension and the hook's speed. The step is slower than real time while
//! the ropes strike and wrap (about 0.7–0.9× on the machine of
//! docs/performance.md).
//!
//! Options:
//! * `--headless N`: no window and no renderer: N fixed steps of 1/60 s
//!   from the 50° release, then one line with the time, the hook's height
//!   and the largest contact force so far (used by
//!   `tests/examples_headless.rs`).
//! * `--screenshot FILE.png`: the same release, a screenshot 1 s in (the
//!   pendant wrapping over the span, near the largest contact force),
//!   then exit.

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::demo_support::*;
use bevy_rapier_cable::plugin::render::CableRender;
use bevy_rapier_cable::plugin::*;

/// The span's pins, m.
const SPAN: [Vec3; 2] = [Vec3::new(-2.0, 1.0, 0.0), Vec3::new(2.0, 1.0, 0.0)];
/// The pendant's pin, m.
const PIN: Vec3 = Vec3::new(0.0, 3.0, 0.0);
/// Pendant length, m.
const PENDANT: f32 = 2.5;
/// Hook: a steel ball, radius m and mass kg.
const HOOK: (f32, f32) = (0.1, 50.0);
/// Tension drawn red, N.
const RED_AT: f32 = 40_000.0;

const USAGE: &str = "usage: cable_impact [--headless FRAMES] [--screenshot FILE.png]";

fn main() {
    let mut options = DemoOptions::from_args_or_exit(USAGE);
    options.screenshot_after = 1.0;
    let mut app = demo_app("bevy_rapier_cable: cable impact", &options);
    if options.headless.is_some() {
        app.add_systems(FixedUpdate, headless_report.after(CableSystems::Readout));
    } else {
        app.add_systems(Startup, setup_scene).add_systems(Update, (release_keys, reset_rig(spawn_rig), look_keys(RED_AT), hud));
    }
    app.init_resource::<Release>()
        .init_resource::<Strongest>()
        .add_plugins((RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default()))
        .add_systems(Startup, (setup_posts, spawn_rig))
        .add_systems(FixedUpdate, strongest.after(CableSystems::Readout));
    run_and_exit(app);
}

/// The release angle, degrees from the vertical (towards −z).
#[derive(Resource)]
struct Release(f32);

impl Default for Release {
    fn default() -> Self {
        Release(50.0)
    }
}

/// The largest contact force between the ropes since the last release, N.
#[derive(Resource, Default)]
struct Strongest(f32);

/// The span.
#[derive(Component)]
struct Span;

/// The pendant.
#[derive(Component)]
struct Pendant;

/// The hook.
#[derive(Component)]
struct Hook;

/// The ground, the span's two posts and the pendant's gallows (fixed
/// bodies; the ropes are pinned to points on them).
fn setup_posts(mut commands: Commands) {
    let steel = Tint(Color::srgb(0.35, 0.38, 0.45));
    commands.spawn((
        Name::new("ground"),
        RigidBody::Fixed,
        Collider::cuboid(6.0, 0.1, 6.0),
        Transform::from_xyz(0.0, -0.1, 0.0),
        Tint(Color::srgb(0.42, 0.45, 0.42)),
    ));
    for pin in SPAN {
        // A post just outside the pin, so that the rope leaves it freely.
        let x = pin.x + 0.12 * pin.x.signum();
        commands.spawn((Name::new("post"), RigidBody::Fixed, Collider::cuboid(0.08, 0.55, 0.08), Transform::from_xyz(x, 0.55, 0.0), steel));
    }
    // The gallows stands beyond the span's left post, out of the
    // pendant's swing (the plane x = 0) and of the span (z = 0); its arm
    // reaches along x to the pin.
    commands.spawn((Name::new("gallows post"), RigidBody::Fixed, Collider::cuboid(0.08, 1.6, 0.08), Transform::from_xyz(-2.6, 1.6, 0.0), steel));
    commands.spawn((Name::new("gallows arm"), RigidBody::Fixed, Collider::cuboid(1.33, 0.06, 0.06), Transform::from_xyz(-1.3, PIN.y + 0.06, 0.0), steel));
}

/// The two ropes and the hook, the hook let go at the release angle.
fn spawn_rig(mut commands: Commands, release: Res<Release>, mut strongest: ResMut<Strongest>) {
    strongest.0 = 0.0;
    let rope = RopeMaterial::steel_6x36_iwrc(0.020);
    let look = CableRender { radius: Some(0.02), color_by_tension: Some(RED_AT), ..default() };
    commands.spawn((
        Name::new("span"),
        Span,
        Rig,
        // Laid 0.1 % short between the pins: taut.
        CableDescriptor::new(3.996).material(rope).segments(40).damping(0.01).start(CableAnchor::world(SPAN[0])).end(CableAnchor::world(SPAN[1])),
        look.clone(),
    ));
    // The pendant laid straight from the pin at the release angle, the
    // hook's centre one radius beyond its end.
    let out = Vec3::new(0.0, -release.0.to_radians().cos(), -release.0.to_radians().sin());
    let hook = commands
        .spawn((
            Name::new("hook"),
            Hook,
            Rig,
            RigidBody::Dynamic,
            Collider::ball(HOOK.0),
            ColliderMassProperties::Mass(HOOK.1),
            Velocity::zero(),
            Transform::from_translation(PIN + out * (PENDANT + HOOK.0)),
            Tint(Color::srgb(0.85, 0.6, 0.1)),
        ))
        .id();
    commands.spawn((
        Name::new("pendant"),
        Pendant,
        Rig,
        CableDescriptor::new(PENDANT).material(rope).segments(25).damping(0.01).start(CableAnchor::world(PIN)).end(CableAnchor::body(hook, -out * HOOK.0)),
        look,
    ));
}

/// Fixed step: the largest contact force between the ropes so far.
fn strongest(span: Query<&CableState, With<Span>>, mut most: ResMut<Strongest>) {
    if let Ok(state) = span.single() {
        most.0 = most.0.max(state.contact_force);
    }
}

/// Hook height, m, and speed, m/s.
fn hook_motion(hook: &Query<(&Transform, &Velocity), With<Hook>>) -> Option<(f32, f32)> {
    hook.single().ok().map(|(t, v)| (t.translation.y, v.linear.length()))
}

/// `--headless N`: one line after N fixed steps, then exit.
fn headless_report(mut report: HeadlessReport, span: Query<&CableState, With<Span>>, hook: Query<(&Transform, &Velocity), With<Hook>>, most: Res<Strongest>) {
    if report.due() {
        let line = span.single().ok().zip(hook_motion(&hook)).map(|(state, (y, speed))| {
            format!("t = {:.2} s, hook y = {:.3} m, hook speed = {:.3} m/s, largest contact force = {:.3} kN", state.time, y, speed, most.0 / 1000.0)
        });
        report.finish("cable_impact", line);
    }
}

/// Light, camera, help line and HUD.
fn setup_scene(mut commands: Commands) {
    let camera = Orbit { focus: Vec3::new(0.0, 1.3, 0.0), yaw: 0.45, pitch: -0.22, distance: 7.0, keys: false };
    spawn_scene(
        &mut commands,
        camera,
        6.0,
        "space: let go again   up/down: release angle   drag: orbit   wheel: zoom   R: reset   T: tension colours   G: gizmos",
    );
}

/// Space lets the hook go again (a respawn at the release angle); up/down
/// (W/S) change the angle for the next release.
fn release_keys(mut commands: Commands, keys: Res<ButtonInput<KeyCode>>, mut release: ResMut<Release>, rig: Query<Entity, With<Rig>>) {
    let step = if keys.any_just_pressed([KeyCode::ArrowUp, KeyCode::KeyW]) {
        5.0
    } else if keys.any_just_pressed([KeyCode::ArrowDown, KeyCode::KeyS]) {
        -5.0
    } else {
        0.0
    };
    release.0 = (release.0 + step).clamp(20.0, 70.0);
    if keys.just_pressed(KeyCode::Space) {
        for e in &rig {
            commands.entity(e).despawn();
        }
        commands.run_system_cached(spawn_rig);
    }
}

/// Time, contact force, the pendant's top tension, the hook's speed.
fn hud(
    time: Res<Time>,
    release: Res<Release>,
    most: Res<Strongest>,
    span: Query<&CableState, With<Span>>,
    pendant: Query<&CableState, With<Pendant>>,
    hook: Query<(&Transform, &Velocity), With<Hook>>,
    mut text: Query<&mut Text, With<Hud>>,
) {
    let Ok(mut text) = text.single_mut() else { return };
    **text = match (span.single(), pendant.single(), hook_motion(&hook)) {
        (Ok(span), Ok(pendant), Some((_, speed))) => format!(
            "t = {:6.2} s   contact {:6.2} kN (largest {:6.2} kN)   pendant top tension {:5.2} kN   hook {:4.2} m/s   release {:2.0} deg",
            time.elapsed_secs(),
            span.contact_force / 1000.0,
            most.0 / 1000.0,
            pendant.tensions.first().copied().unwrap_or(0.0) / 1000.0,
            speed,
            release.0
        ),
        _ => format!("t = {:6.2} s   (ropes building)   release {:2.0} deg", time.elapsed_secs(), release.0),
    };
}
