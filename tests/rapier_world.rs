//! Scenario bodies and joints that no cable absorbs run in rapier
//! (`sim::World`), coupled explicitly to the cables that hang on them.
//! Each test compares with a closed form; the tolerances are the errors of
//! rapier (f32, semi-implicit Euler, soft joints) at the stated step.

use bevy_rapier_cable::scenario;
use bevy_rapier_cable::sim::World;

/// Runs `src` for its duration; returns the world and the rows
/// `[time, probe columns...]` (the first row at t = 0).
fn run(src: &str) -> (World, Vec<Vec<f64>>) {
    let sc = scenario::parse(src, "test.toml").unwrap_or_else(|e| panic!("{e}"));
    let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let frames = (world.scenario.simulation.duration / world.scenario.simulation.dt).round() as u64;
    let mut row = Vec::new();
    world.sample(&mut row);
    let mut rows = vec![std::iter::once(0.0).chain(row.iter().copied()).collect::<Vec<_>>()];
    for _ in 0..frames {
        world.step().unwrap_or_else(|e| panic!("{e}"));
        world.sample(&mut row);
        rows.push(std::iter::once(world.time).chain(row.iter().copied()).collect());
    }
    (world, rows)
}

/// Times of upward zero crossings of column `col`, linearly interpolated.
fn upward_crossings(rows: &[Vec<f64>], col: usize) -> Vec<f64> {
    rows.windows(2).filter(|w| w[0][col] < 0.0 && w[1][col] >= 0.0).map(|w| w[0][0] + (w[1][0] - w[0][0]) * (-w[0][col]) / (w[1][col] - w[0][col])).collect()
}

const G: f64 = 9.81;

/// A free dynamic ball (no cable, no joint) falls. Rapier integrates
/// semi-implicit (symplectic) Euler in 4 sub-steps per step
/// (`num_solver_iterations`, hs = h/4): after N = 4n sub-steps
/// v = −g N hs, y = y0 − g hs² N(N+1)/2 (the continuous y0 − g t²/2 is
/// off by g hs t/2 = 0.020 m at t = 1 s, h = 1/60 s). The system energy
/// probe includes the body.
#[test]
fn free_body_falls_by_the_discrete_formula() {
    let (world, rows) = run(r#"
[simulation]
duration = 1.0
dt = 0.016666666666666666

[[body]]
name = "ball"
type = "dynamic"
shape = "ball"
radius = 0.2
mass = 2.0
position = [1.0, 10.0, -2.0]
linear_velocity = [0.5, 0.0, 0.0]

[[probe]]
name = "y"
body = "ball"
quantity = "position"

[[probe]]
name = "vy"
body = "ball"
quantity = "velocity"
component = "y"

[[probe]]
name = "E"
system = true
quantity = "energy"
"#);
    let h = world.scenario.simulation.dt / 4.0;
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    for (n, r) in rows.iter().enumerate() {
        let n = 4.0 * n as f64;
        let y = 10.0 - G * h * h * n * (n + 1.0) / 2.0;
        let x = 1.0 + 0.5 * n * h;
        let v = -G * n * h;
        worst.0 = worst.0.max((r[2] - y).abs()).max((r[1] - x).abs()).max((r[3] + 2.0).abs());
        worst.1 = worst.1.max((r[4] - v).abs());
        let e = 0.5 * 2.0 * (0.25 + r[4] * r[4]) + 2.0 * G * r[2];
        worst.2 = worst.2.max((r[5] - e).abs());
    }
    let last = rows.last().unwrap();
    let continuous = 10.0 - G / 2.0;
    println!(
        "y(1 s) = {:.6} m, discrete {:.6}, continuous {continuous:.6}; worst |Δpos| {:.2e} m, |Δv| {:.2e} m/s, |ΔE| {:.2e} J",
        last[2],
        10.0 - G * h * h * 240.0 * 241.0 / 2.0,
        worst.0,
        worst.1,
        worst.2
    );
    assert!(worst.0 < 2e-5, "position off the discrete formula by {:.3e} m", worst.0);
    assert!(worst.1 < 2e-5, "velocity off by {:.3e} m/s", worst.1);
    assert!(worst.2 < 1e-3, "energy probe off by {:.3e} J", worst.2);
    assert!((last[2] - continuous + G * h * 1.0 / 2.0).abs() < 1e-4);
}

/// A compound pendulum: a uniform 10 kg cuboid 1 m long (0.1 × 1 × 0.1 m)
/// on a revolute joint about z at its top end, released at 2°. Reference
/// T = 2π√(I_pivot/(m g d))·(1 + θ₀²/16), I_pivot = m(hx² + hy²)/3 + m d²,
/// d = 0.5 m. Step h = 1/600 s (symplectic Euler's period error
/// (ωh)²/24 ≈ 2e-6 there).
#[test]
fn compound_pendulum_on_a_revolute_joint_has_its_period() {
    let theta0: f64 = 2.0;
    let (s, c) = theta0.to_radians().sin_cos();
    let src = format!(
        r#"
[simulation]
duration = 8.0
dt = 0.0016666666666666668

[[body]]
name = "rod"
type = "dynamic"
shape = "cuboid"
half_extents = [0.05, 0.5, 0.05]
mass = 10.0
position = [{x}, {y}, 0.0]
rotation = [0.0, 0.0, {theta0}]

[[joint]]
name = "pivot"
type = "revolute"
body1 = "world"
body2 = "rod"
anchor1 = [0.0, 0.0, 0.0]
anchor2 = [0.0, 0.5, 0.0]
axis = [0.0, 0.0, 1.0]

[[probe]]
name = "angle"
joint = "pivot"
quantity = "position"

[[probe]]
name = "rate"
joint = "pivot"
quantity = "velocity"
"#,
        x = 0.5 * s,
        y = -0.5 * c
    );
    let (_, mut rows) = run(&src);
    // The joint coordinate is 0 at t = 0 (the release); the angle from the
    // vertical is θ₀ + it.
    for r in &mut rows {
        r[1] += theta0;
    }
    let (m, d, hx, hy) = (10.0, 0.5, 0.05, 0.5);
    let ip = m * (hx * hx + hy * hy) / 3.0 + m * d * d;
    let th = theta0.to_radians();
    let reference = 2.0 * std::f64::consts::PI * (ip / (m * G * d)).sqrt() * (1.0 + th * th / 16.0);
    let ups = upward_crossings(&rows, 1);
    assert!(ups.len() >= 4, "{ups:?}");
    let period = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
    let amp = rows.iter().map(|r| r[1].abs()).fold(0.0, f64::max);
    println!("period {period:.6} s vs {reference:.6} s ({:+.2e}); amplitude {amp:.4}° (released at {theta0}°)", period / reference - 1.0);
    assert!((period / reference - 1.0).abs() < 2e-3, "period {period} vs {reference}");
    assert!((amp - theta0).abs() < 0.02, "amplitude {amp}° (energy drift)");
    // The first sample is the release angle; the rate probe is the angle's slope.
    assert!((rows[0][1] - theta0).abs() < 1e-3, "{}", rows[0][1]);
    let k = rows.len() / 3;
    let slope = (rows[k + 1][1] - rows[k - 1][1]) / (rows[k + 1][0] - rows[k - 1][0]);
    assert!((slope - rows[k][2]).abs() < 0.01 * amp * 4.0, "rate {} vs slope {slope}", rows[k][2]);
}

/// A 1000 kg block on a `fixed` joint to the world holds a 5 m rope
/// (1 kg/m, EA 1e7 N, 10 elements) with a 100 kg payload; the cable
/// STARTS on the block (explicit base: the rope's base follows the block,
/// the block gets the base load). Static start, 10 s at h = 1/60 s.
/// Reference: payload centre at 9.5 − 5 − 0.2 − δ, δ = (m g L + μ g L²/2)/EA;
/// top tension (m + μL) g; the block stays put (its joint carries the load).
#[test]
fn block_on_a_fixed_joint_holds_a_cable_with_a_payload() {
    let (world, rows) = run(r#"
[simulation]
duration = 10.0
dt = 0.016666666666666666
statics = true

[[body]]
name = "block"
type = "dynamic"
shape = "cuboid"
half_extents = [0.5, 0.5, 0.5]
mass = 1000.0
position = [0.0, 10.0, 0.0]

[[body]]
name = "payload"
type = "dynamic"
shape = "ball"
radius = 0.2
mass = 100.0
position = [0.0, 4.3, 0.0]

[[joint]]
name = "weld"
type = "fixed"
body1 = "world"
body2 = "block"
anchor1 = [0.0, 10.0, 0.0]
anchor2 = [0.0, 0.0, 0.0]

[[cable]]
name = "rope"
length = 5.0
segments = 10
diameter = 0.02
linear_density = 1.0
ea = 1e7
ei = 10.0
gj = 10.0
start = { body = "block", anchor = [0.0, -0.5, 0.0] }
end = { body = "payload", anchor = [0.0, 0.2, 0.0] }

[[probe]]
name = "block"
body = "block"
quantity = "position"

[[probe]]
name = "payload_y"
body = "payload"
quantity = "position"
component = "y"

[[probe]]
name = "top"
cable = "rope"
quantity = "tension"
s = 0.0
"#);
    let (m, mu, l, ea) = (100.0, 1.0, 5.0, 1e7);
    let delta = (m * G * l + mu * G * l * l / 2.0) / ea;
    let y_ref = 9.5 - 5.0 - 0.2 - delta;
    let t_ref = (m + mu * l) * G;
    let (mut dy, mut dblock, mut dt) = (0.0f64, 0.0f64, 0.0f64);
    for r in &rows {
        dblock = dblock.max((r[1].powi(2) + (r[2] - 10.0).powi(2) + r[3].powi(2)).sqrt());
        dy = dy.max((r[4] - y_ref).abs());
        dt = dt.max((r[5] - t_ref).abs());
    }
    println!("warnings: {:?}", world.warnings);
    println!(
        "payload y ref {y_ref:.6} m (δ = {:.3} mm): worst |Δy| {dy:.2e} m; block drift {dblock:.2e} m; top tension ref {t_ref:.3} N, worst |ΔT| {dt:.3} N",
        delta * 1e3
    );
    assert!(dblock < 1e-3, "the block drifted {dblock} m");
    assert!(dy < 1e-3, "payload off by {dy} m");
    assert!(dt < 0.01 * t_ref, "top tension off by {dt} N");
    let last = rows.last().unwrap();
    assert!((last[4] - y_ref).abs() < 2e-4, "final payload y {} vs {y_ref}", last[4]);
}

/// A cable END on a heavy jointed body: a 500 kg beam 2 m long
/// (2 × 0.2 × 0.2 m) on a revolute joint about z at its left end, held
/// level by a vertical 3 m rope (EA 1e6 N, 1 kg/m, damping 0.02 s) from a
/// world point above its right end. h = 1/600 s (the explicit exchange
/// needs k·h²/m_eff ≲ 1: k = EA/L_e = 3.3e6 N/m, m_eff = I_pivot/r² =
/// 167 kg → 0.055). Reference after 10 s: static balance T_end·2 m =
/// m g·1 m, T_end = m g/2; the beam tilts by the rope stretch (end force
/// and the rope's own weight) over the 2 m lever. (This test found the
/// coupling reading rapier's post-step velocities, which still carry the
/// soft constraints' bias: the end spring's damping turned them into a
/// 0.2 mm offset of the rope end, a 2 % tilt error. The samples now take
/// their velocities from the poses' change over the frame.)
#[test]
fn cable_end_on_a_heavy_jointed_beam_is_in_static_balance() {
    beam_balance("dt = 0.0016666666666666668");
}

/// The same beam at the frame step 1/60 s, where the explicit end coupling
/// has k·h²/m_eff = 5.5 (it diverges within 0.15 s; the warning, which
/// uses the body's own mass, says k·h²/m = 1.85 and names `substeps = 2`),
/// with `substeps = 10`: cables and rapier advance together in 1/600 s
/// sub-steps and give the 1/600 s result.
#[test]
fn coupling_substeps_stabilize_the_beam_at_the_frame_step() {
    let sc = scenario::parse(&BEAM.replace("{TIMING}", "dt = 0.016666666666666666"), "w.toml").unwrap();
    let warnings = World::new(sc).unwrap().warnings;
    println!("{warnings:?}");
    assert!(warnings.len() == 1 && warnings[0].contains("substeps = 2"), "{warnings:?}");
    beam_balance("dt = 0.016666666666666666\nsubsteps = 10");
}

const BEAM: &str = r#"
[simulation]
duration = 10.0
{TIMING}

[[body]]
name = "beam"
type = "dynamic"
shape = "cuboid"
half_extents = [1.0, 0.1, 0.1]
mass = 500.0
position = [1.0, 0.0, 0.0]

[[joint]]
name = "hinge"
type = "revolute"
body1 = "world"
body2 = "beam"
anchor1 = [0.0, 0.0, 0.0]
anchor2 = [-1.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]

[[cable]]
name = "stay"
length = 3.0
segments = 10
diameter = 0.02
linear_density = 1.0
ea = 1e6
ei = 1.0
gj = 1.0
damping = 0.02
start = { world = [2.0, 3.0, 0.0] }
end = { body = "beam", anchor = [1.0, 0.0, 0.0] }

[[probe]]
name = "angle"
joint = "hinge"
quantity = "position"

[[probe]]
name = "t_end"
cable = "stay"
quantity = "tension"
s = 3.0

[[probe]]
name = "beam"
body = "beam"
quantity = "position"

[[probe]]
name = "beam_rot"
body = "beam"
quantity = "rotation"
component = "z"
"#;

fn beam_balance(timing: &str) {
    let (world, rows) = run(&BEAM.replace("{TIMING}", timing));
    let t_ref = 500.0 * G / 2.0;
    // Stretch of the rope under the end force plus its own weight, for the
    // discrete chain (each element's weight hangs below its axial spring:
    // joint i carries N − i elements): T L/EA + μ g L_e² Σ(N − i)/EA.
    let (n, le) = (10.0, 0.3);
    let stretch = (t_ref * 3.0 + 1.0 * G * le * le * n * (n + 1.0) / 2.0) / 1e6;
    let angle_ref = -(stretch / 2.0).asin().to_degrees();
    // Means over the last second (a residual wobble of ~1e-3° remains).
    let per_second = (1.0 / world.scenario.simulation.dt).round() as usize;
    let tail = &rows[rows.len() - per_second..];
    let mean = |c: usize| tail.iter().map(|r| r[c]).sum::<f64>() / tail.len() as f64;
    let (angle, t_end) = (mean(1), mean(2));
    // The end spring's force on the beam is the tension at s = L minus the
    // last element's weight μ g L_e.
    let force = t_end - 1.0 * G * 0.3;
    let swing = tail.iter().map(|r| r[1]).fold(f64::NEG_INFINITY, f64::max) - tail.iter().map(|r| r[1]).fold(f64::INFINITY, f64::min);
    let pivot = {
        let r = rows.last().unwrap();
        let th = r[6].to_radians();
        (r[3] - th.cos(), r[4] - th.sin())
    };
    println!("warnings: {:?}; last reactions {:?}", world.warnings, world.coupling_reactions());
    println!("angle {angle:.5}° vs {angle_ref:.5}° ({:+.2e}); end force {force:.3} N vs {t_ref:.3} N ({:+.2e}); last-second swing {swing:.2e}°; pivot off by {pivot:?} m", angle / angle_ref - 1.0, force / t_ref - 1.0);
    assert!(world.warnings.is_empty());
    assert!((force / t_ref - 1.0).abs() < 5e-3, "end force {force} vs {t_ref}");
    assert!((angle / angle_ref - 1.0).abs() < 5e-3, "angle {angle} vs {angle_ref}");
    assert!(swing < 5e-3, "still swinging: {swing}°");
    assert!(pivot.0.abs() < 1e-4 && pivot.1.abs() < 1e-4, "the hinge opened: {pivot:?}");
}

/// A velocity drive on a revolute joint: a 20 kg disc (cylinder r 0.5 m,
/// I = m r²/2 = 2.5 kg·m²) about its axis y, commanded to 360 deg/s with
/// max 5 N·m: it spins up at α = 2 rad/s² while the motor saturates (the
/// `force` probe reports +5 N·m about y), reaches the command at t = π s
/// and holds it.
#[test]
fn velocity_drive_spins_a_disc_up_at_its_torque_limit() {
    let (_, rows) = run(r#"
[simulation]
duration = 5.0
dt = 0.005

[[body]]
name = "disc"
type = "dynamic"
shape = "cylinder"
radius = 0.5
half_height = 0.1
mass = 20.0

[[joint]]
name = "shaft"
type = "revolute"
body1 = "world"
body2 = "disc"
axis = [0.0, 1.0, 0.0]
drive = { velocity = [[0.0, 360.0]], max_force = 5.0 }

[[probe]]
name = "rate"
joint = "shaft"
quantity = "velocity"

[[probe]]
name = "torque"
joint = "shaft"
quantity = "force"
"#);
    let at = |t: f64| rows.iter().find(|r| r[0] >= t - 1e-9).unwrap();
    let r1 = at(1.0);
    let w_ref = 2.0f64.to_degrees();
    println!(
        "t = 1 s: rate {:.4} deg/s vs {w_ref:.4}; torque {:?}; t = 5 s: rate {:.4}, torque {:?}",
        r1[1],
        &r1[2..5],
        rows.last().unwrap()[1],
        &rows.last().unwrap()[2..5]
    );
    assert!((r1[1] / w_ref - 1.0).abs() < 5e-3, "rate {} vs {w_ref}", r1[1]);
    assert!((r1[3] - 5.0).abs() < 0.05 && r1[2].abs() < 1e-6 && r1[4].abs() < 1e-6, "torque {:?}", &r1[2..5]);
    let last = rows.last().unwrap();
    assert!((last[1] - 360.0).abs() < 0.5, "final rate {}", last[1]);
    assert!(last[3].abs() < 0.5, "holding torque {}", last[3]);
}

/// A force drive on a prismatic joint: a 10 kg block pushed along x by
/// 100 N: x_n = a h² n(n+1)/2 (semi-implicit Euler), a = 10 m/s²; the
/// joint probes give the slide and its rate, the force probe 100 N along x.
#[test]
fn force_drive_pushes_a_block_along_its_rail() {
    let (world, rows) = run(r#"
[simulation]
duration = 1.0
dt = 0.01

[[body]]
name = "cart"
type = "dynamic"
shape = "cuboid"
half_extents = [0.2, 0.2, 0.2]
mass = 10.0
position = [0.0, 1.0, 0.0]

[[joint]]
name = "rail"
type = "prismatic"
body1 = "world"
body2 = "cart"
anchor1 = [0.0, 1.0, 0.0]
axis = [1.0, 0.0, 0.0]
drive = { force = [[0.0, 100.0]] }

[[probe]]
name = "x"
joint = "rail"
quantity = "position"

[[probe]]
name = "v"
joint = "rail"
quantity = "velocity"

[[probe]]
name = "f"
joint = "rail"
quantity = "force"
component = "x"

[[probe]]
name = "y"
body = "cart"
quantity = "position"
component = "y"
"#);
    let h = world.scenario.simulation.dt;
    let n = (rows.len() - 1) as f64;
    let last = rows.last().unwrap();
    let x_ref = 10.0 * h * h * n * (n + 1.0) / 2.0;
    println!("x {:.6} vs {x_ref:.6}; v {:.6} vs 10; f {}; y {:.2e}", last[1], last[2], last[3], last[4] - 1.0);
    assert!((last[1] - x_ref).abs() < 1e-4, "x {} vs {x_ref}", last[1]);
    assert!((last[2] - 10.0).abs() < 1e-4, "v {}", last[2]);
    assert!((last[3] - 100.0).abs() < 1e-9);
    assert!((last[4] - 1.0).abs() < 1e-4, "the rail lets the cart sag: {}", last[4]);
}

/// A kinematic body with a sine motion is moved by it in rapier (its probe
/// reads rapier) and pushes nothing it does not touch.
#[test]
fn kinematic_body_follows_its_motion() {
    let (_, rows) = run(r#"
[simulation]
duration = 2.0
dt = 0.01

[[body]]
name = "shaker"
type = "kinematic"
shape = "ball"
radius = 0.1
position = [0.0, 2.0, 0.0]
motion = { type = "sine", amplitude = [0.3, 0.0, 0.0], period = 1.5 }

[[probe]]
name = "x"
body = "shaker"
quantity = "position"
component = "x"
"#);
    let worst = rows.iter().map(|r| (r[1] - 0.3 * (std::f64::consts::TAU * r[0] / 1.5).sin()).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-6, "kinematic body off its motion by {worst} m");
}
