//! The shipped scenarios (assets/scenarios) run through the Bevy-free
//! runner and meet their closed forms.

use bevy_rapier_cable::scenario;
use bevy_rapier_cable::sim::World;
use std::path::Path;

fn run(file: &str) -> (World, Vec<Vec<f64>>) {
    let sc = scenario::load(Path::new(file)).unwrap_or_else(|e| panic!("{e}"));
    let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let frames = (world.scenario.simulation.duration / world.scenario.simulation.dt).round() as u64;
    let mut rows = Vec::new();
    let mut row = Vec::new();
    for _ in 0..frames {
        world.step().unwrap_or_else(|e| panic!("{e}"));
        world.sample(&mut row);
        let mut r = vec![world.time];
        r.extend(&row);
        rows.push(r);
    }
    (world, rows)
}

#[test]
fn every_shipped_scenario_is_valid_and_builds() {
    let mut n = 0;
    for entry in std::fs::read_dir("assets/scenarios").unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let sc = scenario::load(&path).unwrap_or_else(|e| panic!("{e}"));
            World::new(sc).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            n += 1;
        }
    }
    assert!(n >= 3);
}

/// verification-cases §5b from a scenario file: joint position probe.
#[test]
fn trolley_pendulum_scenario_matches_closed_form() {
    let (_, rows) = run("assets/scenarios/trolley_pendulum.toml");
    let x: Vec<f64> = rows.iter().map(|r| r[1]).collect();
    let t: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    // Period from maxima of the trolley position.
    let peaks: Vec<f64> = (1..x.len() - 1).filter(|&k| x[k] > x[k - 1] && x[k] >= x[k + 1]).map(|k| t[k]).collect();
    let period = (peaks[peaks.len() - 1] - peaks[0]) / (peaks.len() - 1) as f64;
    let p2p = x.iter().cloned().fold(f64::MIN, f64::max) - x.iter().cloned().fold(f64::MAX, f64::min);
    println!("period {period:.5} s (3.843178), trolley peak-to-peak {p2p:.5} m (1.666667)");
    assert!((period - 3.843178).abs() / 3.843178 < 2e-3);
    assert!((p2p - 1.666667).abs() / 1.666667 < 5e-3);
}

/// verification-cases §3c and the dynamic load factor from a scenario file.
#[test]
fn axial_bounce_scenario_dynamic_load_factor() {
    let (_, rows) = run("assets/scenarios/axial_bounce.toml");
    let peak = rows.iter().map(|r| r[2]).fold(f64::MIN, f64::max);
    let dlf = peak / (5000.0 * 9.81);
    println!("peak tension at the payload {peak:.0} N, DLF {dlf:.4}");
    assert!((dlf - 2.0).abs() < 0.02);
}

/// A velocity-tracking trolley drive ([[joint]] drive.velocity): the trolley
/// reaches the commanded 0.5 m/s, and a trolley that starts moving
/// abruptly sets the payload swinging with amplitude l·v/√(g l) relative to
/// the trolley (a pendulum whose support jumps to speed v).
#[test]
fn velocity_drive_moves_the_trolley_and_excites_the_swing() {
    let src = r#"
[simulation]
duration = 6.0
dt = 0.004166666666666667

[[body]]
name = "trolley"
type = "dynamic"
shape = "cuboid"
half_extents = [0.5, 0.2, 0.3]
mass = 1000.0

[[joint]]
name = "rail"
type = "prismatic"
body1 = "world"
body2 = "trolley"
anchor1 = [0.0, 0.0, 0.0]
anchor2 = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
drive = { velocity = [[0.0, 0.5], [10.0, 0.5]], max_force = 1e7 }

[[body]]
name = "payload"
type = "dynamic"
shape = "ball"
radius = 0.01
mass = 500.0
position = [0.0, -5.0, 0.0]

[[cable]]
name = "hoist"
length = 4.99
segments = 10
diameter = 0.02
linear_density = 0.001
ea = 1e10
ei = 0.001
gj = 0.001
start = { body = "trolley", anchor = [0.0, 0.0, 0.0] }
end = { body = "payload", anchor = [0.0, 0.01, 0.0] }

[[probe]]
name = "v"
joint = "rail"
quantity = "velocity"

[[probe]]
name = "x"
joint = "rail"
quantity = "position"

[[probe]]
name = "p"
body = "payload"
quantity = "position"
component = "x"
"#;
    let sc = scenario::parse(src, "velocity_drive.toml").unwrap_or_else(|e| panic!("{e}"));
    let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let (mut row, mut worst_sway) = (Vec::new(), 0.0f64);
    for _ in 0..(6.0 / (1.0 / 240.0)) as usize {
        world.step().unwrap();
        world.sample(&mut row);
        worst_sway = worst_sway.max((row[2] - row[1]).abs());
    }
    let expected = 5.0 * 0.5 / (9.81f64 * 5.0).sqrt();
    println!("trolley speed {:.6} m/s (0.5); sway amplitude {worst_sway:.4} m (l·v/√(gl) = {expected:.4} m)", row[0]);
    // The motor is a finite-gain servo (c = m_total/(2h)): the swinging
    // payload's pull (≈ m g θ ≈ 350 N) leaves ≈ 0.002 m/s of error.
    assert!((row[0] - 0.5).abs() < 2.5e-3);
    assert!((worst_sway - expected).abs() / expected < 0.03, "sway {worst_sway} vs {expected}");
}

/// Period from upward zero crossings of column `col` about its mean.
fn period_of(rows: &[Vec<f64>], col: usize) -> f64 {
    let mean = rows.iter().map(|r| r[col]).sum::<f64>() / rows.len() as f64;
    let ups: Vec<f64> = (1..rows.len())
        .filter(|&k| rows[k - 1][col] < mean && rows[k][col] >= mean)
        .map(|k| {
            let (a, b) = (rows[k - 1][col] - mean, rows[k][col] - mean);
            rows[k - 1][0] + (rows[k][0] - rows[k - 1][0]) * (-a) / (b - a)
        })
        .collect();
    (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64
}

/// verification-cases §3b from a scenario file: the hanging chain's first
/// Bessel frequency ω₁ = 1.190935 rad/s (L = 10 m).
#[test]
fn hanging_chain_scenario_bessel_frequency() {
    let (_, rows) = run("assets/scenarios/hanging_chain.toml");
    let omega = 2.0 * std::f64::consts::PI / period_of(&rows, 1);
    let err = (omega - 1.190935) / 1.190935;
    println!("ω₁ {omega:.6} rad/s (1.190935): {err:+.2e}");
    assert!(err.abs() < 2e-3);
}

/// verification-cases §5a from a scenario file: 60° pendulum at 1/60 s.
#[test]
fn pendulum_scenario_large_amplitude_period() {
    let (_, rows) = run("assets/scenarios/pendulum_60deg.toml");
    let t0 = 2.0 * std::f64::consts::PI * (10.01f64 / 9.81).sqrt();
    let exact = t0 * 1.073182;
    let period = period_of(&rows, 1);
    let err = (period - exact) / exact;
    println!("period {period:.5} s ({exact:.5}): {err:+.2e}");
    assert!(err.abs() < 5e-4);
}

/// What the runner cannot simulate yet is refused with the file position,
/// never silently dropped: an initial velocity of a dynamic body.
#[test]
fn unsupported_initial_velocity_is_refused_with_its_position() {
    let src = std::fs::read_to_string("assets/scenarios/pendulum_60deg.toml").unwrap().replace("mass = 1000.0", "mass = 1000.0\nlinear_velocity = [1.0, 0.0, 0.0]");
    let sc = scenario::parse(&src, "v.toml").unwrap_or_else(|e| panic!("{e}"));
    let err = World::new(sc).unwrap_err().to_string();
    println!("{err}");
    assert!(err.contains("v.toml:8:1") && err.contains("initial velocity") && err.contains("bob"), "{err}");
}

/// verification-cases §3a from a scenario file: the taut string's first
/// frequency, f₁ = c/(2L) = 1.581139 Hz (the rigid-element model is
/// +θ²/24 = +2.6e-4 above the continuum at 40 elements).
#[test]
fn taut_string_scenario_first_frequency() {
    let (_, rows) = run("assets/scenarios/taut_string.toml");
    let f = 1.0 / period_of(&rows, 1);
    let t_mean = rows.iter().map(|r| r[2]).sum::<f64>() / rows.len() as f64;
    let err = (f - 1.581139) / 1.581139;
    println!("f₁ {f:.6} Hz (1.581139): {err:+.2e}; mean tension {t_mean:.2} N");
    assert!((err - 2.6e-4).abs() < 5e-5, "{err}");
    assert!((t_mean - 1000.0).abs() < 1.0);
}
