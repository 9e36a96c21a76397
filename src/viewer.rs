//! `cablesim view FILE` (features `demo` and `sim`): a scenario file in a
//! window, stepped by the plugin exactly as `cablesim run` steps it
//! ([`plugin::scenario::add_scenario`](crate::plugin::scenario::add_scenario):
//! the same core, the same probe rows), the ropes drawn as tubes
//! ([`CableRenderPlugin`](crate::plugin::render::CableRenderPlugin)) and the
//! bodies with their collider shapes.
//!
//! Keys: mouse drag or arrow keys orbit, the wheel or PageUp / PageDown
//! zoom; Space pauses, N (or `.`) steps one frame (`dt`) while paused, R
//! reloads the file and starts again, `+` / `-` double / halve the time
//! scale, G shows the gizmos (nodes, contacts), T colours the ropes by tension. The HUD
//! shows the simulated time, the real-time factor, the largest tension
//! of any rope element and the probes of the file (the columns of
//! `results.csv`, last row). At the end of the scenario's `duration` the
//! viewer pauses (Space runs on, R restarts).
//!
//! `--headless N` runs N frames (of `dt`) without a window or renderer and
//! prints one line with the time and the largest tension, then the probes;
//! `--screenshot PATH` saves the window after 1.5 s of simulated time and
//! exits.

use crate::demo_support::{dress_bodies, exit_status, headless, look_keys, spawn_scene, windowed, DemoOptions, GroundGrid, Hud, Orbit, Tint};
use crate::plugin::render::{CableRender, CableRenderSystems};
use crate::plugin::scenario::{add_scenario, respawn_scenario, ScenarioRun};
use crate::plugin::{CableAnchor, CableDescriptor, CablePlugin, CableState, CableSystems};
use crate::scenario::{self, Scenario};
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;

/// Exit status of a viewer that ends without a problem.
pub const EXIT_OK: u8 = 0;
/// Exit status when the scenario cannot be spawned (as `cablesim run`'s
/// invalid file).
pub const EXIT_INVALID: u8 = 2;
/// Exit status when a cable or body diverged in a `--headless` run (as
/// `cablesim run`'s).
pub const EXIT_DIVERGED: u8 = 3;

/// Tension drawn red with T, N.
const RED_AT: f32 = 50_000.0;

/// Opens `scenario` in a window (or runs it headless, `options`); returns
/// the process exit status (0, or [`EXIT_INVALID`] when the plugin cannot
/// spawn it, with the error printed, or [`EXIT_DIVERGED`]).
pub fn run(scenario: Scenario, mut options: DemoOptions) -> u8 {
    let framing = Framing::of(&scenario);
    let mut app = App::new();
    match options.headless {
        Some(_) => {
            headless(&mut app);
            app.insert_resource(options.clone()).add_systems(FixedUpdate, headless_report.after(CableSystems::Readout));
        }
        None => {
            options.screenshot_after = 1.5;
            let title = format!("cablesim view {}", scenario.file.display());
            windowed(&mut app, &title, &options);
            app.insert_resource(GroundGrid { center: framing.ground, cells: framing.cells, spacing: framing.spacing })
                .add_plugins(ViewerPlugin)
                .add_systems(Startup, move |mut commands: Commands| {
                    let camera = Orbit { focus: framing.focus, yaw: 0.3, pitch: -0.2, distance: framing.distance, keys: true };
                    spawn_scene(&mut commands, camera, framing.distance, HELP);
                })
                // The tint is inserted by commands applied before `dress_bodies` runs.
                .add_systems(Update, tint_bodies.before(dress_bodies))
                .add_systems(
                    Update,
                    (move |commands: Commands,
                           meshes: ResMut<Assets<Mesh>>,
                           materials: ResMut<Assets<StandardMaterial>>,
                           new: Query<(Entity, &CableDescriptor), Without<CableRender>>| {
                        thicken(commands, meshes, materials, new, framing.distance)
                    })
                    .before(CableRenderSystems::Interpolate),
                )
                .add_systems(Update, drop_marks);
        }
    }
    app.add_plugins((RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(), CablePlugin::default()));
    if let Err(e) = add_scenario(&mut app, scenario) {
        eprintln!("error: {e}");
        return EXIT_INVALID;
    }
    let exit = app.run();
    exit_status(&exit)
}

/// New cables are drawn at least 1/400 of the camera distance thick (a
/// 20 mm rope seen from 50 m is under a pixel), and their world anchors
/// as small dark balls ([`AnchorMark`]).
fn thicken(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    new: Query<(Entity, &CableDescriptor), Without<CableRender>>,
    distance: f32,
) {
    for (e, d) in &new {
        let radius = (0.5 * d.material.diameter() as f32).max(distance / 800.0);
        commands.entity(e).insert(CableRender { radius: Some(radius), ..default() });
        for anchor in [&d.start, &d.end] {
            if let CableAnchor::World { point, .. } = anchor {
                let look = (Mesh3d(meshes.add(Sphere::new(4.0 * radius))), MeshMaterial3d(materials.add(Color::srgb(0.15, 0.15, 0.17))));
                commands.spawn((look, Transform::from_translation(*point), AnchorMark(e)));
            }
        }
    }
}

/// A world anchor's ball, drawn while its cable exists.
#[derive(Component)]
struct AnchorMark(Entity);

/// The balls of despawned cables go.
fn drop_marks(mut commands: Commands, marks: Query<(Entity, &AnchorMark)>, cables: Query<(), With<CableDescriptor>>) {
    for (e, m) in &marks {
        if !cables.contains(m.0) {
            commands.entity(e).despawn();
        }
    }
}

/// New bodies of the scenario get a colour (the file's bodies in turn).
fn tint_bodies(mut commands: Commands, run: Res<ScenarioRun>, new: Query<Entity, (Added<Collider>, Without<Tint>)>) {
    let palette = [Color::srgb(0.95, 0.7, 0.1), Color::srgb(0.75, 0.25, 0.12), Color::srgb(0.2, 0.45, 0.8), Color::srgb(0.3, 0.6, 0.3)];
    for (k, b) in run.scenario.bodies.iter().enumerate() {
        if let Some(e) = run.bodies.get(&b.name).filter(|e| new.contains(**e)) {
            commands.entity(*e).insert(Tint(palette[k % palette.len()]));
        }
    }
}

/// The viewer's controls and HUD, for an app with a scenario
/// ([`add_scenario`]) and Bevy's `InputPlugin`: Space pauses
/// (`Time<Virtual>`), N or `.` steps one frame while paused, `+` / `-`
/// double / halve the time scale, R reloads the scenario's file and
/// respawns it ([`respawn_scenario`]), T and G toggle the tension colours
/// and the node gizmos; at the scenario's duration it pauses once; the
/// [`Hud`] text (if there is one) shows time, real-time factor, largest
/// tension and probes.
pub struct ViewerPlugin;

impl Plugin for ViewerPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Rate>()
            .init_resource::<Status>()
            .add_systems(Update, (controls, look_keys(RED_AT), reset.run_if(reset_asked), (pause_at_end, hud).chain()).chain());
    }
}

const HELP: &str = "drag/arrows: orbit   wheel/PgUp/PgDn: zoom   space: pause   N: step   R: reset   +/-: time scale   T: tension colours   G: gizmos";

/// Where to look from, and the ground grid, for a scenario.
#[derive(Clone, Copy, Debug)]
struct Framing {
    focus: Vec3,
    distance: f32,
    ground: Vec3,
    cells: u32,
    spacing: f32,
}

impl Framing {
    /// Around the bodies and the cables' initial paths.
    fn of(sc: &Scenario) -> Framing {
        let points = sc.bodies.iter().map(|b| b.position_at(0.0).as_vec3()).chain(sc.cables.iter().flat_map(|c| c.path.iter().map(|p| p.as_vec3())));
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in points.filter(|p| p.is_finite()) {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        if !lo.is_finite() {
            (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        }
        let size = (hi - lo).max_element().max(2.0);
        // Looking a little above the middle, so that the scene sits below
        // the HUD (top left).
        let focus = 0.5 * (lo + hi) + Vec3::Y * 0.12 * size;
        // A 45° vertical field of view: the box fills about 60 % of it.
        let distance = 2.0 * size;
        let ground_y = if lo.y >= 0.0 { 0.0 } else { lo.y - 0.1 * size };
        // The grid: about 10 cells of 0.5, 1, 2, 5, 10, 20 or 50 m over the scene.
        let spacing = [0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0f32].into_iter().find(|s| *s >= size / 10.0).unwrap_or(50.0);
        let cells = ((2.0 * size / spacing).ceil() as u32).clamp(4, 60);
        Framing { focus, distance, ground: Vec3::new(focus.x, ground_y, focus.z), cells, spacing }
    }
}

/// The real-time factor, measured over half a second of real time.
#[derive(Resource, Default)]
struct Rate {
    since_real: f64,
    since_sim: f64,
    value: f64,
}

/// A reset asked for (R), the file's error after a failed reload, the
/// end of the scenario reached.
#[derive(Resource, Default)]
struct Status {
    reset: bool,
    message: Option<String>,
    ended: bool,
}

fn reset_asked(status: Res<Status>) -> bool {
    status.reset
}

/// Space, N, +/-, R (T and G: [`look_keys`]).
fn controls(
    keys: Res<ButtonInput<KeyCode>>,
    mut virt: ResMut<Time<Virtual>>,
    mut fixed: ResMut<Time<Fixed>>,
    run: Res<ScenarioRun>,
    mut status: ResMut<Status>,
) {
    if keys.just_pressed(KeyCode::Space) {
        if virt.is_paused() {
            virt.unpause();
        } else {
            virt.pause();
        }
    }
    if virt.is_paused() && keys.any_just_pressed([KeyCode::KeyN, KeyCode::Period]) {
        // One frame: `substeps` fixed steps, run by the next frame's fixed loop.
        let step = fixed.timestep() * run.substeps;
        fixed.accumulate_overstep(step);
    }
    let speed = virt.relative_speed();
    if keys.any_just_pressed([KeyCode::Equal, KeyCode::NumpadAdd]) {
        virt.set_relative_speed((speed * 2.0).min(8.0));
    }
    if keys.any_just_pressed([KeyCode::Minus, KeyCode::NumpadSubtract]) {
        virt.set_relative_speed((speed * 0.5).max(1.0 / 64.0));
    }
    if keys.just_pressed(KeyCode::KeyR) {
        status.reset = true;
    }
}

/// R: reload the file and start again (a file that no longer loads is
/// reported in the HUD and the running scenario kept).
fn reset(world: &mut World) {
    world.resource_mut::<Status>().reset = false;
    let file = world.resource::<ScenarioRun>().scenario.file.clone();
    let loaded = scenario::load(&file).map_err(|e| e.to_string()).and_then(|sc| respawn_scenario(world, sc).map_err(|e| format!("error: {e}")));
    let message = match loaded {
        Ok(()) => {
            world.resource_mut::<Time<Virtual>>().unpause();
            None
        }
        Err(e) => {
            eprintln!("{e}");
            Some(format!("reload failed (the running scenario is kept): {}", e.lines().next().unwrap_or("")))
        }
    };
    let mut status = world.resource_mut::<Status>();
    status.message = message;
    status.ended = false;
}

/// At the scenario's duration the viewer pauses once.
fn pause_at_end(run: Res<ScenarioRun>, mut status: ResMut<Status>, mut virt: ResMut<Time<Virtual>>) {
    let end = run.scenario.simulation.duration - 0.5 * run.scenario.simulation.dt;
    if !status.ended && run.time >= end {
        status.ended = true;
        virt.pause();
    }
}

/// The largest element tension over all ropes, N, and its rope's name.
fn max_tension<'a>(cables: impl Iterator<Item = (&'a CableState, Option<&'a Name>)>) -> Option<(f32, String)> {
    cables
        .filter_map(|(s, n)| s.tensions.iter().copied().filter(|t| t.is_finite()).reduce(f32::max).map(|t| (t, n.map_or(String::new(), |n| n.to_string()))))
        .reduce(|a, b| if b.0 > a.0 { b } else { a })
}

/// The probes' last values, `name = value` (at most `limit`).
fn probe_lines(run: &ScenarioRun, limit: usize) -> Vec<String> {
    let columns = run.scenario.columns();
    let Some((_, row)) = run.rows.last() else { return Vec::new() };
    let mut lines: Vec<String> = columns.iter().zip(row).take(limit).map(|(c, v)| format!("{c} = {v:.5}")).collect();
    if columns.len() > limit {
        lines.push(format!("... {} more (cablesim run writes them all)", columns.len() - limit));
    }
    lines
}

/// Time, real-time factor, largest tension, probes.
fn hud(
    run: Res<ScenarioRun>,
    real: Res<Time<bevy::time::Real>>,
    virt: Res<Time<Virtual>>,
    mut rate: ResMut<Rate>,
    status: Res<Status>,
    cables: Query<(&CableState, Option<&Name>)>,
    mut text: Query<&mut Text, With<Hud>>,
) {
    let now = real.elapsed_secs_f64();
    if run.time < rate.since_sim {
        // Reset: measure again.
        (rate.since_sim, rate.since_real) = (run.time, now);
    } else if now - rate.since_real >= 0.5 {
        rate.value = (run.time - rate.since_sim) / (now - rate.since_real);
        (rate.since_sim, rate.since_real) = (run.time, now);
    }
    let Ok(mut text) = text.single_mut() else { return };
    let tension = match max_tension(cables.iter()) {
        Some((t, name)) => format!("max tension {:.3} kN ({name})", t / 1000.0),
        None => "max tension -".into(),
    };
    let state = if virt.is_paused() {
        if status.ended {
            "ended, paused".to_string()
        } else {
            "paused".to_string()
        }
    } else {
        format!("x{} time scale", virt.relative_speed())
    };
    let mut lines = vec![format!("t = {:.3} s of {} s   {:.2}x real time   {state}   {tension}", run.time, run.scenario.simulation.duration, rate.value)];
    lines.extend(probe_lines(&run, 12));
    if let Some((_, t, m)) = &run.failed {
        lines.push(format!("DIVERGED at t = {t:.3} s: {m} (R: reset)"));
    }
    if let Some(m) = &status.message {
        lines.push(m.clone());
    }
    **text = lines.join("\n");
}

/// `--headless N`: after N frames, the time, the largest tension and the
/// probes; exit 3 on a divergence (as `cablesim run`).
fn headless_report(options: Res<DemoOptions>, run: Res<ScenarioRun>, cables: Query<(&CableState, Option<&Name>)>, mut exit: MessageWriter<AppExit>) {
    if let Some((_, t, m)) = &run.failed {
        eprintln!("error: simulation diverged at t = {t} s: {m}");
        exit.write(AppExit::from_code(EXIT_DIVERGED));
        return;
    }
    if run.steps < options.headless.unwrap_or(0) || run.substep != 0 {
        return;
    }
    let (t, name) = max_tension(cables.iter()).unwrap_or((f32::NAN, String::new()));
    println!("{}: t = {:.3} s, {} frames, max tension = {:.3} kN ({name})", run.scenario.file.display(), run.time, run.steps, t / 1000.0);
    for line in probe_lines(&run, usize::MAX) {
        println!("  {line}");
    }
    exit.write(AppExit::Success);
}
