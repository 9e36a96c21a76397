//! What the windowed demos (`examples/hanging_payload.rs`,
//! `overhead_crane.rs`, `tow_rope.rs`) and `cablesim view` share (feature
//! `demo`): their command line (`--headless N`, `--screenshot PATH`), the
//! windowed and the headless app, an orbit camera, a light, a ground grid,
//! a HUD with a help line, bodies drawn with their collider's shape, and
//! the screenshot that ends a `--screenshot` run.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_rapier_cable::demo_support::*;
//! let options = DemoOptions::from_args_or_exit("usage: my_demo [--headless FRAMES] [--screenshot FILE.png]");
//! let mut app = App::new();
//! if options.headless.is_some() {
//!     headless(&mut app);
//! } else {
//!     windowed(&mut app, "my demo", &options);
//!     let camera = Orbit { focus: Vec3::Y * 5.0, yaw: 0.5, pitch: -0.2, distance: 20.0, keys: false };
//!     app.add_systems(Startup, move |mut commands: Commands| spawn_scene(&mut commands, camera, 40.0, "drag: orbit   wheel: zoom"));
//! }
//! ```

use crate::plugin::render::{CableGizmos, CableRender, CableRenderPlugin};
use crate::plugin::CableError;
use bevy::app::ScheduleRunnerPlugin;
use bevy::ecs::system::SystemParam;
use bevy::input::mouse::{AccumulatedMouseMotion, AccumulatedMouseScroll, MouseScrollUnit};
use bevy::light::CascadeShadowConfigBuilder;
use bevy::prelude::*;
use bevy::render::view::screenshot::{save_to_disk, Screenshot, ScreenshotCaptured};
use bevy::text::FontSize;
use bevy::time::TimeUpdateStrategy;
use bevy::window::WindowResolution;
use bevy_rapier3d::prelude::*;
use std::path::PathBuf;

/// What a demo's command line asked for.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct DemoOptions {
    /// `--headless N`: no window and no renderer, N frames (fixed steps),
    /// then a report line and exit.
    pub headless: Option<u64>,
    /// `--screenshot PATH`: a PNG of the window after
    /// [`DemoOptions::screenshot_after`] s of simulated time, then exit.
    pub screenshot: Option<PathBuf>,
    /// When the screenshot is taken, s of (virtual) time. Default 1.8 s.
    pub screenshot_after: f32,
}

impl DemoOptions {
    /// Parses `--headless N` and `--screenshot PATH` (`-h`/`--help` gives
    /// `Err("")`; anything else an error message).
    pub fn parse(args: impl IntoIterator<Item = String>) -> Result<DemoOptions, String> {
        let mut o = DemoOptions { screenshot_after: 1.8, ..default() };
        let mut args = args.into_iter();
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

    /// [`DemoOptions::parse`] of the process's arguments; on an error
    /// prints it and `usage`, and exits with status 2.
    pub fn from_args_or_exit(usage: &str) -> DemoOptions {
        DemoOptions::from_args_with_flags_or_exit(usage, &[]).0
    }

    /// [`DemoOptions::from_args_or_exit`] for a demo with its own on/off
    /// `flags` (such as `--anti-sway`): also returns those given.
    pub fn from_args_with_flags_or_exit(usage: &str, flags: &[&'static str]) -> (DemoOptions, Vec<&'static str>) {
        let args: Vec<String> = std::env::args().skip(1).collect();
        let given: Vec<&'static str> = flags.iter().copied().filter(|f| args.iter().any(|a| a == f)).collect();
        match DemoOptions::parse(args.into_iter().filter(|a| !flags.contains(&a.as_str()))) {
            Ok(o) => (o, given),
            Err(why) => {
                if !why.is_empty() {
                    eprintln!("{why}");
                }
                eprintln!("{usage}");
                std::process::exit(2);
            }
        }
    }
}

/// A demo's app at 60 fixed steps per second (`Time<Fixed>` and rapier's
/// `TimestepMode`): [`headless`] with `--headless`, else [`windowed`]
/// titled `title`; with the [`DemoOptions`] resource. Add the physics
/// plugins and the demo's systems, then [`run_and_exit`].
pub fn demo_app(title: &str, options: &DemoOptions) -> App {
    let mut app = App::new();
    if options.headless.is_some() {
        headless(&mut app);
    } else {
        windowed(&mut app, title, options);
    }
    app.insert_resource(Time::<Fixed>::from_hz(60.0)).insert_resource(TimestepMode::Fixed { dt: 1.0 / 60.0, substeps: 1 }).insert_resource(options.clone());
    app
}

/// Runs the app and exits the process with its status ([`exit_status`]).
pub fn run_and_exit(mut app: App) -> ! {
    let exit = app.run();
    std::process::exit(exit_status(&exit).into())
}

/// What a demo's reset (R, [`reset_rig`]) despawns: its moving bodies and
/// ropes.
#[derive(Component, Debug, Clone, Copy, Default)]
pub struct Rig;

/// A system: R despawns every [`Rig`] entity and runs `spawn` (a system
/// that spawns them again).
pub fn reset_rig<M: 'static, S>(spawn: S) -> impl FnMut(Commands, Res<ButtonInput<KeyCode>>, Query<Entity, With<Rig>>)
where
    S: IntoSystem<(), (), M> + Copy + Send + Sync + 'static,
{
    move |mut commands: Commands, keys: Res<ButtonInput<KeyCode>>, rig: Query<Entity, With<Rig>>| {
        if keys.just_pressed(KeyCode::KeyR) {
            for e in &rig {
                commands.entity(e).despawn();
            }
            commands.run_system_cached(spawn);
        }
    }
}

/// Bevy's gizmo settings, if the app has gizmos.
type GizmoStore<'w> = Option<ResMut<'w, GizmoConfigStore>>;

/// A system: T switches the ropes' tension colours (red at `red_at` N)
/// on and off, G the gizmos ([`CableGizmos`]: nodes, contacts).
/// (Without Bevy's gizmos, G does nothing.)
pub fn look_keys(red_at: f32) -> impl FnMut(Res<ButtonInput<KeyCode>>, Query<&mut CableRender>, GizmoStore) {
    move |keys: Res<ButtonInput<KeyCode>>, mut looks: Query<&mut CableRender>, gizmos: GizmoStore| {
        if keys.just_pressed(KeyCode::KeyT) {
            for mut look in &mut looks {
                look.color_by_tension = if look.color_by_tension.is_some() { None } else { Some(red_at) };
            }
        }
        if let (true, Some(mut gizmos)) = (keys.just_pressed(KeyCode::KeyG), gizmos) {
            let (config, _) = gizmos.config_mut::<CableGizmos>();
            config.enabled = !config.enabled;
        }
    }
}

/// What a demo's `--headless N` report system needs: put it in a system
/// after the cables' readout, call [`HeadlessReport::due`] every fixed
/// step and [`HeadlessReport::finish`] once it is due.
#[derive(SystemParam)]
pub struct HeadlessReport<'w, 's> {
    options: Res<'w, DemoOptions>,
    steps: Local<'s, u64>,
    errors: MessageReader<'w, 's, CableError>,
    exit: MessageWriter<'w, AppExit>,
}

impl HeadlessReport<'_, '_> {
    /// Counts a fixed step and forwards the cables' errors (printed, exit
    /// status 3); `true` once N steps have run.
    pub fn due(&mut self) -> bool {
        for e in self.errors.read() {
            eprintln!("{e}");
            self.exit.write(AppExit::from_code(3));
        }
        *self.steps += 1;
        *self.steps >= self.options.headless.unwrap_or(0)
    }

    /// Prints the report `line` and exits with status 0; `None` (nothing
    /// to report: the rope is not there) prints why and exits with 1.
    pub fn finish(&mut self, demo: &str, line: Option<String>) {
        match line {
            Some(line) => {
                println!("{demo}: {line}");
                self.exit.write(AppExit::Success);
            }
            None => {
                eprintln!("{demo}: no rope state after {} steps", *self.steps);
                self.exit.write(AppExit::from_code(1));
            }
        }
    }
}

/// The headless app: `MinimalPlugins` run as fast as they can, one fixed
/// step per update (no window, no renderer, no GPU).
pub fn headless(app: &mut App) {
    app.add_plugins((MinimalPlugins.set(ScheduleRunnerPlugin::run_loop(std::time::Duration::ZERO)), TransformPlugin))
        .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
}

/// The windowed app: Bevy's `DefaultPlugins` with a 1280×720 window titled
/// `title`, the cable tubes ([`CableRenderPlugin`]), a sky, ambient light,
/// and [`DemoPlugin`] (bodies drawn, orbit camera, ground grid, the
/// screenshot of `--screenshot`).
pub fn windowed(app: &mut App, title: &str, options: &DemoOptions) {
    let window = Window { title: title.into(), resolution: WindowResolution::new(1280, 720), ..default() };
    app.add_plugins((DefaultPlugins.set(WindowPlugin { primary_window: Some(window), ..default() }), CableRenderPlugin::default(), DemoPlugin))
        .insert_resource(ClearColor(Color::srgb(0.62, 0.75, 0.88)))
        .insert_resource(GlobalAmbientLight { brightness: 400.0, ..default() })
        .insert_resource(options.clone());
}

/// The systems of a windowed demo: bodies drawn with their collider's
/// shape ([`Tint`], [`Follow`]), the [`Orbit`] camera, the
/// [`GroundGrid`], and the screenshot of [`DemoOptions::screenshot`]
/// (needs the [`DemoOptions`] resource).
pub struct DemoPlugin;

impl Plugin for DemoPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<GroundGrid>()
            .add_systems(FixedPostUpdate, record_bodies)
            .add_systems(Update, (dress_bodies, follow_bodies, orbit_camera, ground_grid, screenshot));
    }
}

/// The colour a body is drawn with (default: a light grey).
#[derive(Component, Clone, Copy, Debug)]
pub struct Tint(pub Color);

/// The orbit camera: it looks at `focus` (m) from `distance` m, turned by
/// `yaw` about +Y and tilted by `pitch` (rad, negative: from above).
/// Mouse drag orbits, the wheel zooms; with `keys`, also the arrow keys
/// (orbit) and PageUp / PageDown (zoom).
#[derive(Component, Clone, Copy, Debug)]
pub struct Orbit {
    /// The point looked at, m.
    pub focus: Vec3,
    /// Turn about +Y, rad.
    pub yaw: f32,
    /// Tilt, rad (negative: looking down).
    pub pitch: f32,
    /// Distance from the focus, m.
    pub distance: f32,
    /// The arrow keys and PageUp / PageDown move the camera too.
    pub keys: bool,
}

impl Orbit {
    /// The camera's pose.
    pub fn transform(&self) -> Transform {
        let rot = Quat::from_euler(EulerRot::YXZ, self.yaw, self.pitch, 0.0);
        Transform::from_translation(self.focus + rot * Vec3::Z * self.distance).looking_at(self.focus, Vec3::Y)
    }
}

/// The HUD text (the line under the help line); demos write into it.
#[derive(Component, Debug)]
pub struct Hud;

/// The ground grid drawn with gizmos: `cells` squares of `spacing` m on
/// each side, centred on `center` (its y is the ground height, m).
#[derive(Resource, Clone, Copy, Debug)]
pub struct GroundGrid {
    /// Centre of the grid, m.
    pub center: Vec3,
    /// Cells along each side.
    pub cells: u32,
    /// Cell size, m.
    pub spacing: f32,
}

impl Default for GroundGrid {
    /// 20 × 20 cells of 2 m around the origin.
    fn default() -> Self {
        GroundGrid { center: Vec3::ZERO, cells: 20, spacing: 2.0 }
    }
}

/// A light (shadows out to `size` m), the [`Orbit`] camera, and the HUD:
/// the `help` line and an empty [`Hud`] line below it, top left.
pub fn spawn_scene(commands: &mut Commands, camera: Orbit, size: f32, help: &str) {
    let size = if size.is_finite() && size > 1.0 { size } else { 1.0 };
    commands.spawn((
        DirectionalLight { illuminance: 9000.0, shadow_maps_enabled: true, ..default() },
        Transform::from_xyz(8.0, 20.0, 10.0).looking_at(Vec3::ZERO, Vec3::Y),
        CascadeShadowConfigBuilder { maximum_distance: 3.0 * size, first_cascade_far_bound: 0.9 * size, ..default() }.build(),
    ));
    commands.spawn((Camera3d::default(), camera.transform(), camera));
    let font = TextFont { font_size: FontSize::Px(16.0), ..default() };
    commands
        .spawn((
            Node {
                position_type: PositionType::Absolute,
                top: px(10),
                left: px(10),
                padding: UiRect::all(px(8)),
                flex_direction: FlexDirection::Column,
                row_gap: px(4),
                ..default()
            },
            BackgroundColor(Color::srgba(0.0, 0.0, 0.0, 0.55)),
        ))
        .with_children(|p| {
            p.spawn((Text::new(help), font.clone()));
            p.spawn((Hud, Text::new(""), font.clone(), TextColor(Color::srgb(1.0, 0.92, 0.5))));
        });
}

/// Mouse drag orbits, the wheel zooms (and the keys, [`Orbit::keys`]).
pub fn orbit_camera(
    time: Res<Time<bevy::time::Real>>,
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
    motion: Res<AccumulatedMouseMotion>,
    scroll: Res<AccumulatedMouseScroll>,
    mut camera: Query<(&mut Orbit, &mut Transform)>,
) {
    let Ok((mut o, mut t)) = camera.single_mut() else { return };
    let mut turn = Vec2::ZERO;
    if buttons.any_pressed([MouseButton::Left, MouseButton::Right]) {
        turn += motion.delta * 0.005;
    }
    let mut notches = match scroll.unit {
        MouseScrollUnit::Line => scroll.delta.y,
        MouseScrollUnit::Pixel => scroll.delta.y / 40.0,
    };
    if o.keys {
        let dt = time.delta_secs();
        let key = |k: KeyCode| if keys.pressed(k) { 1.0 } else { 0.0 };
        // 1 rad/s of orbit, 5 notches/s of zoom.
        turn.x += (key(KeyCode::ArrowRight) - key(KeyCode::ArrowLeft)) * 200.0 * 0.005 * dt;
        turn.y += (key(KeyCode::ArrowDown) - key(KeyCode::ArrowUp)) * 200.0 * 0.005 * dt;
        notches += (key(KeyCode::PageUp) - key(KeyCode::PageDown)) * 5.0 * dt;
    }
    o.yaw -= turn.x;
    o.pitch = (o.pitch - turn.y).clamp(-1.4, 0.3);
    o.distance = (o.distance * (-0.1 * notches).exp()).clamp(1.0, 2000.0);
    *t = o.transform();
}

/// A body to draw: its collider, colour, kind and pose.
type NewBody<'a> = (Entity, &'a Collider, Option<&'a Tint>, &'a RigidBody, &'a Transform);

/// Bodies are drawn with their collider's shape (cuboid, ball, capsule,
/// cylinder), in their [`Tint`]. A fixed or kinematic body carries its
/// mesh; a dynamic one is drawn by a separate entity ([`Follow`]) whose
/// pose is interpolated between fixed steps, as the rope is, so that the
/// rope's end stays on the body at any frame rate (the body's own
/// `Transform` is rapier's, at the fixed steps).
pub fn dress_bodies(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    new: Query<NewBody, Added<Collider>>,
) {
    for (e, collider, tint, body, pose) in &new {
        let mesh = if let Some(c) = collider.as_cuboid() {
            Mesh::from(Cuboid::from_size(2.0 * c.half_extents()))
        } else if let Some(b) = collider.as_ball() {
            Mesh::from(Sphere::new(b.radius()))
        } else if let Some(c) = collider.as_capsule() {
            let (center, rotation) = c.transform_wrt_y();
            Mesh::from(Capsule3d::new(c.radius(), c.height())).transformed_by(Transform::from_translation(center).with_rotation(rotation))
        } else if let Some(c) = collider.as_cylinder() {
            Mesh::from(Cylinder::new(c.radius(), 2.0 * c.half_height()))
        } else {
            continue;
        };
        let color = tint.map_or(Color::srgb(0.8, 0.8, 0.78), |t| t.0);
        let look = (Mesh3d(meshes.add(mesh)), MeshMaterial3d(materials.add(StandardMaterial { base_color: color, perceptual_roughness: 0.6, ..default() })));
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
#[derive(Component, Debug)]
pub struct Follow {
    /// The body drawn.
    pub body: Entity,
    /// Its pose at the fixed step before the last one.
    pub previous: Transform,
    /// Its pose at the last fixed step.
    pub current: Transform,
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

/// The [`GroundGrid`].
fn ground_grid(mut gizmos: Gizmos, grid: Res<GroundGrid>) {
    let on_ground = Isometry3d::new(grid.center + Vec3::Y * 0.005, Quat::from_rotation_x(std::f32::consts::FRAC_PI_2));
    gizmos.grid(on_ground, UVec2::splat(grid.cells), Vec2::splat(grid.spacing), Color::srgba(0.1, 0.1, 0.1, 0.6));
}

/// Frames, and real time, s, rendered with the simulation paused before a
/// `--screenshot` run starts: the frames of a software renderer come out
/// black while its pipelines compile (seconds in an unoptimised build,
/// however many frames a light scene renders meanwhile).
const WARM_UP: (u32, f32) = (20, 10.0);

/// `--screenshot PATH`: the simulation held for the [`WARM_UP`], then a
/// screenshot once [`DemoOptions::screenshot_after`] s have passed, then
/// exit.
fn screenshot(
    mut commands: Commands,
    mut virt: ResMut<Time<Virtual>>,
    real: Res<Time<bevy::time::Real>>,
    options: Res<DemoOptions>,
    mut frames: Local<u32>,
    mut warm: Local<bool>,
    mut taken: Local<bool>,
) {
    let Some(path) = &options.screenshot else { return };
    *frames += 1;
    if !*warm {
        if *frames < WARM_UP.0 || real.elapsed_secs() < WARM_UP.1 {
            virt.pause();
            return;
        }
        *warm = true;
        virt.unpause();
    }
    if *taken || virt.elapsed_secs() < options.screenshot_after {
        return;
    }
    *taken = true;
    commands.spawn(Screenshot::primary_window()).observe(save_to_disk(path.clone())).observe(|_: On<ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| {
        exit.write(AppExit::Success);
    });
}

/// The process exit status of an app's exit (0 on success).
pub fn exit_status(exit: &AppExit) -> u8 {
    match exit {
        AppExit::Success => 0,
        AppExit::Error(code) => code.get(),
    }
}
