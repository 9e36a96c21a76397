//! The shipped scenarios (assets/scenarios) run through the Bevy-free
//! runner and meet their closed forms.

use bevy_rapier_cable::scenario;
use bevy_rapier_cable::sim::World;
use glam::DVec3;
use std::path::Path;

#[path = "common/irvine.rs"]
mod irvine;
use irvine::irvine_leg;
#[path = "common/scenario_run.rs"]
mod scenario_run;
use scenario_run::run_scenario;

fn run(file: &str) -> (World, Vec<Vec<f64>>) {
    run_scenario(scenario::load(Path::new(file)).unwrap_or_else(|e| panic!("{e}")))
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

/// `collision_groups.toml`: the hoist rope, whose groups leave out the
/// boom's, hangs through the boom and holds its ball at rest with
/// m g + ρ g L = 4 974.06 N at the top; the draped rope (default groups)
/// lies on the boom, its centreline one radius above the top (5.11 m),
/// carrying its weight ρ g L = 62.784 N. Without the groups the hoist rope,
/// laid through the boom, is refused at its first step.
#[test]
fn collision_groups_scenario_hoist_through_its_boom() {
    let (_, rows) = run("assets/scenarios/collision_groups.toml");
    let last = rows.last().unwrap();
    let (top, ball_y, contact, middle_y) = (last[1], last[3], last[5], last[7]);
    let (g, rho) = (9.81, 1.6);
    let hoist = 500.0 * g + rho * 4.4 * g;
    println!("top tension {top:.4} N (m g + ρ g L = {hoist:.4}); ball at {ball_y:.6} m; draped contact {contact:.4} N, middle at {middle_y:.6} m");
    assert!((top / hoist - 1.0).abs() < 1e-6, "top tension {top} N against {hoist} N");
    assert!((ball_y - 1.3).abs() < 2e-3, "the ball should hang where it was laid, less the stretch: {ball_y} m");
    assert!((contact / (rho * 4.0 * g) - 1.0).abs() < 1e-6, "draped contact force {contact} N");
    assert!((middle_y - 5.11).abs() < 1e-5, "the draped rope's middle at {middle_y} m");
    let src = std::fs::read_to_string("assets/scenarios/collision_groups.toml").unwrap();
    let plain = src.replace("collision_groups = { memberships = [1], filter = [1] }", "");
    let sc = scenario::parse(&plain, "no_groups.toml").unwrap_or_else(|e| panic!("{e}"));
    let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let refused = (0..10).find_map(|_| world.step().err());
    println!("without the hoist's groups: {refused:?}");
    assert!(refused.is_some_and(|e| e.to_string().contains("hoist")), "the hoist laid through the boom should be refused");
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
/// Initial velocities (`linear_velocity` of carried bodies): the trolley
/// kicked along its rail under a payload at rest. Closed form (linear
/// Lagrange model, REFERENCE §6): momentum M u0 kept; the trolley moves as
/// x_T = V t + (u0 − V)/ω sin ωt with V = M u0/(M + m) and
/// ω² = (M + m) g/(M l).
#[test]
fn trolley_kick_scenario_initial_velocity() {
    let (_, rows) = run("assets/scenarios/trolley_kick.toml");
    let (mt, mp, u0, g, l): (f64, f64, f64, f64, f64) = (1000.0, 500.0, 0.2, 9.81, 5.0);
    let v_cm = mt * u0 / (mt + mp);
    let omega = ((mt + mp) * g / (mt * l)).sqrt();
    // Row 0 is after the first step; the state at t = 0 is checked through
    // a fresh world.
    let sc = scenario::load(Path::new("assets/scenarios/trolley_kick.toml")).unwrap();
    let w0 = World::new(sc).unwrap();
    let mut r0 = Vec::new();
    w0.sample(&mut r0);
    println!("t = 0: trolley v {:.12} m/s (0.2), payload vx {:.3e} m/s (0)", r0[1], r0[2]);
    assert!((r0[1] - u0).abs() < 1e-9 && r0[2].abs() < 1e-9, "{r0:?}");
    let momentum_err = rows.iter().map(|r| (mt * r[2] + mp * r[3] - mt * u0).abs()).fold(0.0, f64::max) / (mt * u0);
    // Oscillation about the centre-of-mass drift.
    let rel: Vec<f64> = rows.iter().map(|r| r[1] - v_cm * r[0]).collect();
    let amp = 0.5 * (rel.iter().cloned().fold(f64::MIN, f64::max) - rel.iter().cloned().fold(f64::MAX, f64::min));
    let t: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    let ups: Vec<f64> =
        (1..rel.len()).filter(|&k| rel[k - 1] < 0.0 && rel[k] >= 0.0).map(|k| t[k - 1] + (t[k] - t[k - 1]) * rel[k - 1] / (rel[k - 1] - rel[k])).collect();
    let period = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
    let (amp_ref, period_ref) = ((u0 - v_cm) / omega, 2.0 * std::f64::consts::PI / omega);
    println!(
        "momentum error {momentum_err:.2e}; amplitude {amp:.6} m ({amp_ref:.6}, {:+.2e}); period {period:.6} s ({period_ref:.6}, {:+.2e}); {} rows",
        amp / amp_ref - 1.0,
        period / period_ref - 1.0,
        rows.len()
    );
    assert!(momentum_err < 5e-5, "{momentum_err}");
    assert!((amp / amp_ref - 1.0).abs() < 1e-4, "{amp}");
    assert!((period / period_ref - 1.0).abs() < 5e-4, "{period}");
}

/// A velocity the chain cannot take (the trolley across its rail) is an
/// error at the body's file:line:col.
#[test]
fn impossible_initial_velocity_is_refused_with_its_position() {
    let src = std::fs::read_to_string("assets/scenarios/trolley_kick.toml")
        .unwrap()
        .replace("linear_velocity = [0.2, 0.0, 0.0]", "linear_velocity = [0.2, 0.0, 0.5]");
    let sc = scenario::parse(&src, "v.toml").unwrap_or_else(|e| panic!("{e}"));
    let err = World::new(sc).unwrap_err().to_string();
    println!("{err}");
    assert!(err.contains("v.toml:14:1") && err.contains("initial velocity") && err.contains("trolley") && err.contains("cannot make"), "{err}");
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

/// Builds the scenario in `file` (a `statics = true` file is at its static
/// equilibrium then), samples the probes at t = 0, runs the whole duration
/// and samples again: (row at t = 0, row at the end).
fn static_then_run(file: &str) -> (Vec<f64>, Vec<f64>) {
    let sc = scenario::load(Path::new(file)).unwrap_or_else(|e| panic!("{e}"));
    assert!(sc.simulation.statics, "{file}: not a statics scenario");
    let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let (mut first, mut last) = (Vec::new(), Vec::new());
    world.sample(&mut first);
    let frames = (world.scenario.simulation.duration / world.scenario.simulation.dt).round() as u64;
    for _ in 0..frames {
        world.step().unwrap_or_else(|e| panic!("{e}"));
    }
    world.sample(&mut last);
    (first, last)
}

/// The run starts at rest at the static equilibrium and stays there:
/// every probe moves by less than `tol` (relative to its size, or absolute
/// below 1).
fn assert_stays(first: &[f64], last: &[f64], tol: f64) {
    for (k, (a, b)) in first.iter().zip(last).enumerate() {
        assert!((a - b).abs() <= tol * a.abs().max(1.0), "column {k}: {a} at t = 0, {b} at the end");
    }
}

/// verification-cases §1a from a scenario file (`statics = true`, point
/// `loads`): Mattiasson's cantilever at α = 1, 5, 10 with N = 40; the same
/// tolerances as `statics::cantilever_tip_load_mattiasson` at N = 40.
#[test]
fn cantilever_tip_load_scenario_mattiasson() {
    let (row, end) = static_then_run("assets/scenarios/cantilever_tip_load.toml");
    let table = [(1.0, 0.05643, 0.30172, 0.46135), (5.0, 0.38763, 0.71379, 1.21537), (10.0, 0.55500, 0.81061, 1.43029)];
    for (k, &(alpha, u_ref, w_ref, th_ref)) in table.iter().enumerate() {
        // Columns: tip (3), node one element before the tip (3), per cable.
        let c = 6 * k;
        let z0 = k as f64;
        let (tip, prev) = (&row[c..c + 3], &row[c + 3..c + 6]);
        let (u, w) = (1.0 - tip[0], -tip[1]);
        // Tip rotation from the last element's chord (rigid element).
        let th = (prev[1] - tip[1]).atan2(tip[0] - prev[0]);
        let (eu, ew, et) = ((u - u_ref) / u_ref, (w - w_ref) / w_ref, (th - th_ref) / th_ref);
        println!("α={alpha}: u/L {u:.5} ({eu:+.2e}), w/L {w:.5} ({ew:+.2e}), θ {th:.5} ({et:+.2e}), z − z0 {:.1e}", tip[2] - z0);
        assert!(ew.abs() < 6e-4 && eu.abs() < 1.8e-3 && et.abs() < 6e-4, "α={alpha}");
        assert!((tip[2] - z0).abs() < 1e-9);
    }
    assert_stays(&row, &end, 1e-9);
}

/// verification-cases §1b from a scenario file (`statics = true`, a point
/// `moment`): the tip at φ = π/2, π, 2π with N = 20 within 1e-3·L, as
/// `statics::cantilever_end_moment_rolls_into_circle`.
#[test]
fn cantilever_end_moment_scenario_rolls_into_circle() {
    let (row, end) = static_then_run("assets/scenarios/cantilever_end_moment.toml");
    let pi = std::f64::consts::PI;
    for (k, phi) in [0.5 * pi, pi, 2.0 * pi].into_iter().enumerate() {
        let clamp = glam::DVec3::new(0.0, -2.0 * k as f64, 0.0);
        let tip = glam::DVec3::from_slice(&row[3 * k..3 * k + 3]) - clamp;
        let exact = glam::DVec3::new(phi.sin() / phi, 0.0, (1.0 - phi.cos()) / phi);
        let err = tip.distance(exact);
        println!("φ = {phi:.4}: tip {tip:.6} exact {exact:.6} |err| {err:.2e} L");
        assert!(err < 1e-3, "φ = {phi}: tip error {err}");
    }
    assert_stays(&row, &end, 1e-9);
}

/// verification-cases §2b from a scenario file (`statics = true`): the
/// elastic catenary's H, T_end and sag within 1e-3, as
/// `statics::elastic_catenary_level_supports`.
#[test]
fn catenary_scenario_elastic_irvine() {
    let (row, end) = static_then_run("assets/scenarios/catenary.toml");
    let rows = [
        ("L0 = 102, EA = 1e9", 1447.630, 1534.839, 8.72098),
        ("L0 = 102, EA = 1e6", 1396.061, 1486.300, 9.03686),
        ("L0 = 99.9, EA = 1e7", 12619.389, 12629.270, 0.98942),
    ];
    for (k, (what, h_ref, t_ref, sag_ref)) in rows.into_iter().enumerate() {
        let (t_end, h, sag) = (row[3 * k], row[3 * k + 1], -row[3 * k + 2]);
        let (eh, et, es) = ((h - h_ref) / h_ref, (t_end - t_ref) / t_ref, (sag - sag_ref) / sag_ref);
        println!("{what}: H {h:.3} ({eh:+.2e}), T_end {t_end:.3} ({et:+.2e}), sag {sag:.5} ({es:+.2e})");
        assert!(eh.abs() < 1e-3 && et.abs() < 1e-3 && es.abs() < 1e-3, "{what}");
    }
    assert_stays(&row, &end, 1e-6);
}

/// verification-cases §1c from a scenario file (`statics = true`,
/// `stress_free = true`, a point load): the 45° bend's tip displacement at
/// P = 300 and 600 with N = 32 within 0.5 % of |Δ| (the §1c bar, as
/// `verify_beams::bend45_meets_section_1c_tolerance_with_16_elements`).
#[test]
fn bend_45_scenario_out_of_plane_tip_load() {
    let (row, end) = static_then_run("assets/scenarios/bend_45.toml");
    let r = 100.0;
    let c45 = std::f64::consts::FRAC_PI_4;
    let initial = glam::DVec3::new(r - r * c45.cos(), 0.0, r * c45.sin());
    let cases = [(300.0, 0.0, glam::DVec3::new(-7.045, 40.192, -11.932)), (600.0, 100.0, glam::DVec3::new(-13.605, 53.475, -23.561))];
    for (k, (p, x0, reference)) in cases.into_iter().enumerate() {
        let tip = glam::DVec3::from_slice(&row[3 * k..3 * k + 3]);
        let d = tip - initial - glam::DVec3::new(x0, 0.0, 0.0);
        let err = d.distance(reference) / reference.length();
        println!(
            "P={p}: Δ = ({:.3}, {:.3}, {:.3}) vs ({:.3}, {:.3}, {:.3}): |error| {:.3} % of |Δ|",
            d.x,
            d.y,
            d.z,
            reference.x,
            reference.y,
            reference.z,
            100.0 * err
        );
        assert!(err < 5e-3, "P={p}: {err}");
    }
    assert_stays(&row, &end, 1e-9);
}

/// verification-cases §9a from a scenario file (a kinematic hub with a
/// `spin` motion, the beam clamped to it): v_tip, the tip deflection
/// transverse to the rotating chord, peaks within 1 % of −0.57375 m and
/// 0.05 s of 6.76 s; the table instants within 1 % of the peak; the
/// residual vibration after spin-up within 20 % of 0.0037 m (N = 20, as
/// `verify_spinup::spin_up_beam_tip_deflection`).
#[test]
fn spin_up_scenario_tip_deflection() {
    let sc = scenario::load(Path::new("assets/scenarios/spin_up.toml")).unwrap_or_else(|e| panic!("{e}"));
    let hub = sc.body("hub").unwrap().clone();
    let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let h = world.scenario.simulation.dt;
    let frames = (world.scenario.simulation.duration / h).round() as u64;
    let (mut ts, mut vs, mut row) = (vec![0.0], vec![0.0], Vec::new());
    let mut worst_rate: f64 = 0.0;
    for _ in 0..frames {
        world.step().unwrap_or_else(|e| panic!("{e}"));
        world.sample(&mut row);
        // Tip in the hub frame; the direction of motion of +x under a
        // rotation about +y is −z.
        let tip = hub.rotation_at(world.time).inverse() * glam::DVec3::from_slice(&row[0..3]);
        ts.push(world.time);
        vs.push(-tip.z);
        // The hub's rate probe (deg/s) against the §9a closed form.
        let (t, w_s, t_s) = (world.time, 6.0, 15.0);
        let rate = if t <= t_s { w_s / t_s * (t - t_s / std::f64::consts::TAU * (std::f64::consts::TAU * t / t_s).sin()) } else { w_s };
        worst_rate = worst_rate.max((row[3].to_radians() - rate).abs());
    }
    let k = (1..vs.len() - 1).min_by(|&a, &b| vs[a].total_cmp(&vs[b])).unwrap();
    let (y0, y1, y2) = (vs[k - 1], vs[k], vs[k + 1]);
    let off = 0.5 * (y0 - y2) / (y0 - 2.0 * y1 + y2);
    let (t_peak, peak) = (ts[k] + off * h, y1 - 0.25 * (y0 - y2) * off);
    let (peak_ref, t_peak_ref) = (-0.57375, 6.76);
    let (ep, et) = (peak / peak_ref - 1.0, t_peak - t_peak_ref);
    println!(
        "peak v_tip {peak:.5} m at {t_peak:.3} s (ref {peak_ref} at {t_peak_ref}): {:+.3} %, {et:+.3} s; hub rate vs closed form within {worst_rate:.1e} rad/s",
        100.0 * ep
    );
    let table = [
        (1.0, -0.02054),
        (2.0, -0.10237),
        (3.0, -0.21725),
        (4.0, -0.34225),
        (5.0, -0.46844),
        (6.0, -0.54354),
        (7.0, -0.57122),
        (8.0, -0.54273),
        (10.0, -0.36267),
        (12.0, -0.15084),
        (14.0, -0.02028),
    ];
    let mut worst: f64 = 0.0;
    for (t, v_ref) in table {
        let i = ts.iter().position(|&x| (x - t).abs() < 0.5 * h).unwrap();
        println!("  t = {t}: {:.5} ({:+.5})", vs[i], vs[i] - v_ref);
        worst = worst.max((vs[i] - v_ref).abs());
    }
    let after: Vec<f64> = ts.iter().zip(&vs).filter(|(t, _)| **t > 16.0).map(|(_, v)| *v).collect();
    let mean = after.iter().sum::<f64>() / after.len() as f64;
    let amp = after.iter().map(|v| (v - mean).abs()).fold(0.0, f64::max);
    println!("  worst table deviation {worst:.5} m; residual vibration ±{amp:.4} m (≈ 0.0037 m)");
    assert!(ep.abs() < 0.01, "peak error {ep}");
    assert!(et.abs() < 0.05, "peak time error {et}");
    assert!(worst < 0.01 * peak_ref.abs(), "table deviation {worst}");
    assert!((amp / 0.0037 - 1.0).abs() < 0.2, "residual vibration {amp}");
}

/// `statics = true` that cannot converge (a tip load α = P L²/EI = 1e5 in
/// one load step) is refused before the run, naming the file, the cable's
/// line and the cable.
#[test]
fn static_start_failure_names_the_cable() {
    let src = r#"[simulation]
duration = 0.1
dt = 0.01
gravity = [0, 0, 0]
statics = true
static_load_steps = 1

[[cable]]
name = "beam"
length = 1.0
segments = 20
diameter = 0.01
linear_density = 0.001
ea = 1e7
ei = 1.0
gj = 1.0
start = { world = [0.0, 0.0, 0.0], clamp = true }
path = [[0, 0, 0], [1, 0, 0]]
loads = [{ s = 1.0, force = [0.0, -1e5, 0.0] }]
"#;
    let sc = scenario::parse(src, "overload.toml").unwrap_or_else(|e| panic!("{e}"));
    let err = World::new(sc).unwrap_err();
    let shown = err.to_string();
    println!("{shown}");
    assert!(matches!(err, bevy_rapier_cable::sim::SimError::Static { .. }), "{shown}");
    assert!(shown.starts_with("overload.toml:8:1: cable `beam`: static equilibrium not found at load step 1 of 1"), "{shown}");
}

/// A cable `end` clamped to a spinning body is refused (the end spring's
/// orientation hold has a fixed target); a pinned one is accepted.
#[test]
fn clamped_end_on_a_spinning_body_is_refused() {
    let src = |clamp: bool| {
        format!(
            r#"[simulation]
duration = 0.1
dt = 0.01

[[body]]
name = "hub"
type = "kinematic"
shape = "ball"
radius = 0.1
position = [0, -2, 0]
motion = {{ type = "spin", axis = [0, 1, 0], rate = [[0, 0], [1, 90]] }}

[[cable]]
name = "rope"
length = 2.0
segments = 4
diameter = 0.01
linear_density = 0.5
ea = 1e6
ei = 1
gj = 1
start = {{ world = [0, 0, 0] }}
end = {{ body = "hub", clamp = {clamp} }}
"#
        )
    };
    let sc = scenario::parse(&src(true), "spin_end.toml").unwrap_or_else(|e| panic!("{e}"));
    let err = World::new(sc).unwrap_err().to_string();
    println!("{err}");
    assert!(err.contains("spin_end.toml:13:1") && err.contains("clamped to spinning body `hub`"), "{err}");
    let sc = scenario::parse(&src(false), "spin_end.toml").unwrap_or_else(|e| panic!("{e}"));
    World::new(sc).unwrap_or_else(|e| panic!("{e}"));
}

/// A cable clamped to a spinning body off its axis: the runner's base
/// motion (the anchor point's ω × r and α × r + ω × (ω × r), the body's ω
/// and α) gives the same motion as a hand-written `BaseMotion::Prescribed`
/// of the same spin: rate 90t deg/s for t ≤ 1 s, then 90 deg/s, about +y;
/// the anchor 1 m off the axis, the beam along +x. A beam keeps
/// compression (`tension_only = false`): as a tension-only rope, its first
/// element, pushed by the spin-up, turned inside out (refused since).
#[test]
fn spin_motion_drives_an_off_axis_clamp_like_the_prescribed_base() {
    use bevy_rapier_cable::cable::*;
    use bevy_rapier_cable::integrate::Scheme;
    use glam::{DMat3, DVec3};
    let src = r#"[simulation]
duration = 3.0
dt = 0.01
gravity = [0, 0, 0]

[[body]]
name = "hub"
type = "kinematic"
shape = "ball"
radius = 0.1
position = [0, 0, 0]
motion = { type = "spin", axis = [0, 1, 0], rate = [[0, 0], [1, 90]] }

[[cable]]
name = "beam"
length = 1.0
segments = 5
diameter = 0.02
linear_density = 1.0
ea = 1e6
ei = 1.0
gj = 1.0
tension_only = false
start = { body = "hub", anchor = [0, 0, 1], clamp = true }
path = [[0, 0, 1], [1, 0, 1]]
"#;
    let sc = scenario::parse(src, "spin_clamp.toml").unwrap_or_else(|e| panic!("{e}"));
    let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let w0 = std::f64::consts::FRAC_PI_2;
    let base = BaseMotion::Prescribed(std::sync::Arc::new(move |t: f64| {
        let (th, w, al) = if t < 1.0 - 1e-9 {
            (0.5 * w0 * t * t, w0 * t, w0)
        } else if t <= 1.0 + 1e-9 {
            (0.5 * w0, w0, 0.5 * w0)
        } else {
            (0.5 * w0 + w0 * (t - 1.0), w0, 0.0)
        };
        let rot = DMat3::from_rotation_y(th);
        let r = rot * DVec3::Z;
        let (wv, av) = (DVec3::Y * w, DVec3::Y * al);
        BaseState {
            rotation: rot,
            position: r,
            angular_velocity: wv,
            velocity: wv.cross(r),
            angular_acceleration: av,
            acceleration: av.cross(r) + wv.cross(wv.cross(r)),
        }
    }));
    let sec = RopeSection { linear_density: 1.0, ea: 1e6, ei: 1.0, ei2: 1.0, gj: 1.0, min_breaking_load: 0.0 };
    let model = RopeBuilder::new(1.0, 5, sec, 0.02)
        .path(vec![DVec3::Z, DVec3::new(1.0, 0.0, 1.0)])
        .start(RopeStart::Clamped(base))
        .gravity(DVec3::ZERO)
        .tension_only(false)
        .build()
        .unwrap();
    let mut api = Cable::new(model, Scheme::default()).unwrap();
    let mut worst: f64 = 0.0;
    let mut bent: f64 = 0.0;
    for _ in 0..300 {
        world.step().unwrap_or_else(|e| panic!("{e}"));
        api.step(0.01).unwrap();
        let (a, b) = (world.cable("beam").unwrap().nodes(), api.nodes());
        worst = a.iter().zip(&b).map(|(p, q)| p.distance(*q)).fold(worst, f64::max);
        // Deflection of the tip from the rigidly turning straight beam.
        let th = world.scenario.body("hub").unwrap().rotation_at(world.time);
        bent = bent.max(a[5].distance(th * DVec3::new(1.0, 0.0, 1.0)));
    }
    println!("largest node difference scenario vs prescribed base {worst:.2e} m; largest tip deflection {bent:.3} m");
    assert!(bent > 0.05, "the test does not load the beam: {bent}");
    assert!(worst < 1e-9, "{worst}");
}

/// A constant force drive on the trolley rail from t = 0 (the trolley and
/// its payload at rest): the horizontal momentum of trolley + rope +
/// payload is F t at every frame. The runner recomputes the cable's
/// starting acceleration with the drive acting; from the force-free one,
/// generalized-α would keep the momentum F h/2 behind.
#[test]
fn force_drive_from_rest_gives_momentum_f_t() {
    let src = std::fs::read_to_string("assets/scenarios/trolley_kick.toml")
        .unwrap()
        .replace("linear_velocity = [0.2, 0.0, 0.0]\n", "")
        .replace("axis = [1.0, 0.0, 0.0]", "axis = [1.0, 0.0, 0.0]\ndrive = { force = [[0.0, 300.0], [100.0, 300.0]] }")
        .replace("duration = 12.0", "duration = 2.0");
    let sc = scenario::parse(&src, "drive.toml").unwrap_or_else(|e| panic!("{e}"));
    let dt = sc.simulation.dt;
    let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let (f, mut worst, mut row) = (300.0, 0.0f64, Vec::new());
    for _ in 0..(2.0 / dt).round() as usize {
        world.step().unwrap();
        world.sample(&mut row);
        // Columns: trolley_x, trolley_v, payload_vx (rope mass 5 g neglected).
        let p = 1000.0 * row[1] + 500.0 * row[2];
        worst = worst.max((p - f * world.time).abs() / (f * dt));
    }
    println!("largest |P − F t| over 2 s: {worst:.2e} of one step's impulse F h");
    // The rope (5 g at up to 0.6 m/s, 3e-3 N·s = 2.4e-3 F h) is left out of P.
    assert!(worst < 1e-2, "{worst}");
}

/// `boom_hoist.toml`: a boom that rapier keeps, held by a pendant rope and
/// carrying a hoist rope with a swinging payload (two explicit couplings,
/// 12 sub-steps per 1/60 s frame). Averaged over whole half periods of the
/// swing, the tip carries the hanging weight: the pendant's tension near
/// the tip and the boom's sag match the statics in the file's header.
#[test]
fn boom_hoist_scenario_statics_on_average() {
    let (_, rows) = run("assets/scenarios/boom_hoist.toml");
    let t: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    let x: Vec<f64> = rows.iter().map(|r| r[4] - 10.0).collect();
    let ups: Vec<f64> = (1..x.len()).filter(|&k| x[k - 1] < 0.0 && x[k] >= 0.0).map(|k| t[k - 1] + (t[k] - t[k - 1]) * -x[k - 1] / (x[k] - x[k - 1])).collect();
    let period = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
    // The last two swing periods (four half periods of the vertical load).
    let (t1, t0) = (ups[ups.len() - 1], ups[ups.len() - 1] - 2.0 * period);
    let window: Vec<&Vec<f64>> = rows.iter().filter(|r| r[0] > t0 && r[0] <= t1).collect();
    let mean = |c: usize| window.iter().map(|r| r[c]).sum::<f64>() / window.len() as f64;
    let (angle, tension) = (mean(1), mean(2));
    let g: f64 = 9.81;
    let v_tip: f64 = (2000.0 * 5.0 + (1000.0 + 1.6 * 20.0) * 10.0) * g / 10.0;
    let w_p = 1.6 * g * 14.142136;
    let h = v_tip + w_p / 2.0;
    // The probe reads the last element's inboard joint, 0.707 m up the
    // 45° pendant: + μ g L_e sin 45°·(its vertical share) = μ g L_e / 2.
    let t_ref = h.hypot(v_tip) + 1.6 * g * (14.142136 / 20.0) / 2.0;
    let angle_ref = -(std::f64::consts::SQRT_2 * h.hypot(v_tip) * 14.142136 / 2e7 / 10.0).to_degrees();
    println!(
        "swing period {period:.4} s; over t = {t0:.2}…{t1:.2} s: pendant tension {tension:.1} N vs {t_ref:.1} N ({:+.2e}), boom angle {angle:.5}° vs {angle_ref:.5}° ({:+.2e})",
        tension / t_ref - 1.0,
        angle / angle_ref - 1.0
    );
    assert!((tension / t_ref - 1.0).abs() < 5e-3, "{tension}");
    assert!((angle / angle_ref - 1.0).abs() < 1e-2, "{angle}");
}

/// A 1 t box on a two-leg sling (`assets/scenarios/two_leg_sling.toml`),
/// run by the scenario runner at the frame step with the defaults: the two
/// cables and the box are one implicit island (the box is a hub). Against
/// the elastic catenary of one leg carrying half the box's weight (Irvine):
/// * from the static equilibrium (`statics = true`), the shackle's depth,
///   each leg's pull at its anchor (leg_b, grafted onto leg_a's chain
///   reversed, is reported from its own start like leg_a) and leg_b's
///   tension next to the box, held for 2 s;
/// * released from straight legs (the file as shipped), it settles there
///   (damped, τ = 0.05 s; the slowest sag modes still creep at 8 s).
#[test]
fn two_leg_sling_scenario_settles_on_the_catenary() {
    let s = bevy_rapier_cable::cable::preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap();
    let (g, w) = (9.81, s.linear_density * 9.81);
    let v0 = 1000.0 * g / 2.0;
    let (depth, h) = irvine_leg(10.0, w, s.ea, 6.0, v0);
    let (t_top, t_low) = (h.hypot(v0 + w * 10.0), h.hypot(v0 + w * 0.5));
    let e = |x: f64, r: f64| (x - r) / r;
    let src = std::fs::read_to_string("assets/scenarios/two_leg_sling.toml").unwrap();
    let statics = src.replace("duration = 8.0", "duration = 2.0\nstatics = true");
    for (what, src, tol) in [("static start", statics, (1e-7, 1e-5)), ("released", src, (1e-5, 1e-3))] {
        let sc = scenario::parse(&src, "two_leg_sling.toml").unwrap_or_else(|e| panic!("{e}"));
        let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
        let mut last = Vec::new();
        while world.time < world.scenario.simulation.duration - 1e-9 {
            world.step().unwrap_or_else(|e| panic!("{what}: {e}"));
        }
        world.sample(&mut last);
        let (p, a_top, b_top, b_low) = (glam::DVec3::from_slice(&last[..3]), last[3], last[4], last[5]);
        let shackle = -(p.y + 0.25);
        println!(
            "{what}: shackle depth {shackle:.7} (Irvine {depth:.7}) {:+.1e}; tops {a_top:.3} / {b_top:.3} (Irvine {t_top:.3}) {:+.1e} / {:+.1e}; leg_b at the box {b_low:.3} ({t_low:.3}) {:+.1e}; {:.2} Newton its/step",
            e(shackle, depth),
            e(a_top, t_top),
            e(b_top, t_top),
            e(b_low, t_low),
            world.work().0 as f64 / world.steps as f64
        );
        assert!(e(shackle, depth).abs() < tol.0 && p.x.abs() < 1e-4 && p.z.abs() < 1e-4, "{what}: box at {p}");
        for t in [a_top, b_top] {
            assert!(e(t, t_top).abs() < tol.1, "{what}: top tension {t} vs {t_top}");
        }
        assert!(e(b_low, t_low).abs() < tol.1, "{what}: leg_b at the box {b_low} vs {t_low}");
        assert!(world.cable("leg_a").is_some_and(|c| c.ropes() == 2) && world.cable("leg_b").is_none() && world.rope("leg_b").is_some());
        assert_eq!(world.cable_names(), ["leg_a", "leg_b"]);
    }
}

/// A loop through two dynamic bodies: the box hangs on `leg_a` from the
/// world and on `leg_b` from a block that itself hangs on a cable from the
/// world. Both bodies are hubs, and the island would close a loop between
/// them: refused before stepping, naming the cable and both bodies. (A
/// free block at `leg_b`'s start is not a loop: `leg_b` then carries the
/// box, with `leg_a` grafted onto it, and the block is the chain's
/// floating root, all in one implicit solve; before 2026-11-28 the block
/// was coupled explicitly, with a stability warning.)
#[test]
fn sling_loop_through_two_dynamic_bodies_is_refused() {
    let src = std::fs::read_to_string("assets/scenarios/two_leg_sling.toml").unwrap();
    let free = src.replace("start = { world = [6.0, 0.0, 0.0] }", "start = { body = \"block\", anchor = [0.0, 0.0, 0.0] }")
        + "\n[[body]]\nname = \"block\"\ntype = \"dynamic\"\nshape = \"ball\"\nradius = 0.2\nmass = 50.0\nposition = [6.0, 0.0, 0.0]\n";
    let sc = scenario::parse(&free, "free.toml").unwrap_or_else(|e| panic!("{e}"));
    let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    assert!(world.warnings.iter().all(|w| !w.contains("coupled explicitly")), "{:?}", world.warnings);
    assert!(world.cable("leg_b").is_some_and(|c| c.ropes() == 2) && world.cable("leg_a").is_none() && world.rope("leg_a").is_some());
    for _ in 0..60 {
        world.step().unwrap_or_else(|e| panic!("the block on leg_b's start: {e}"));
    }
    let looped = free.clone()
        + "\n[[cable]]\nname = \"c\"\nlength = 3.0\nsegments = 6\ndiameter = 0.02\nmaterial = \"steel_wire_rope_6x36_iwrc\"\nstart = { world = [6.0, 3.0, 0.0] }\nend = { body = \"block\", anchor = [0.0, 0.0, 0.0] }\n";
    let sc = scenario::parse(&looped, "loop.toml").unwrap_or_else(|e| panic!("{e}"));
    let err = World::new(sc).unwrap_err().to_string();
    println!("{err}");
    assert!(err.starts_with("loop.toml:") && err.contains("body `block`") && err.contains("`box`") && err.contains("loop through two dynamic bodies"), "{err}");
}

/// `damped_drop.toml` (issue 10, damped unloading at the frame step): the
/// block falls 3 m onto the slack, damped (τ = 0.02 s) rope, snaps it
/// taut, rebounds while the rope unloads faster than its damper, and comes
/// to rest. Checks: the run completes at 1/60 s; at the end the hook
/// carries the block and the rope, (M + ρ L) g; the peak top tension is
/// within 25 % of the same file at h = 0.5 ms (the 50 ms snap spans three
/// frame steps) and below it.
#[test]
fn damped_drop_scenario_comes_to_rest_at_the_frame_step() {
    let s = bevy_rapier_cable::cable::preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap();
    let rest_ref = (1000.0 + s.linear_density * 10.0) * 9.81;
    let (_, rows) = run("assets/scenarios/damped_drop.toml");
    let peak = rows.iter().map(|r| r[1]).fold(0.0f64, f64::max);
    let rest = rows.last().unwrap()[1];
    let src = std::fs::read_to_string("assets/scenarios/damped_drop.toml").unwrap();
    let fine = src.replace("dt = 0.016666666666666666", "dt = 0.0005").replace("duration = 10.0", "duration = 1.2");
    let sc = scenario::parse(&fine, "damped_drop.toml").unwrap_or_else(|e| panic!("{e}"));
    let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let (mut row, mut peak_fine) = (Vec::new(), 0.0f64);
    while world.time < world.scenario.simulation.duration - 1e-9 {
        world.step().unwrap_or_else(|e| panic!("fine step: {e}"));
        world.sample(&mut row);
        peak_fine = peak_fine.max(row[0]);
    }
    let (e_rest, e_peak) = (rest / rest_ref - 1.0, peak / peak_fine - 1.0);
    println!(
        "damped drop at 1/60 s: rest tension {rest:.2} N ({e_rest:+.1e} from (M + ρL) g), peak {peak:.4e} N ({e_peak:+.2e} from h = 0.5 ms: {peak_fine:.4e} N)"
    );
    assert!(e_rest.abs() < 1e-6, "not at rest: {e_rest:+.2e}");
    assert!(e_peak < 0.0 && e_peak > -0.25, "peak {e_peak:+.3}");
}

/// An incomplete `[[controller]]` names the missing field at its table
/// (the entries themselves: `tests/crane_scenarios.rs`).
#[test]
fn an_incomplete_controller_entry_names_the_missing_field() {
    let src = "[simulation]\nduration = 1.0\ndt = 0.01\n\n[[controller]]\nname = \"anti_sway\"\ntype = \"zv\"\n";
    let e = scenario::parse(src, "ctl.toml").unwrap_err().to_string();
    assert!(e.contains("ctl.toml:5:") && e.contains("missing field `joint`"), "{e}");
}

/// `rope_on_ground.toml` (issue 12): a free 10 m steel rope dropped 1 mm
/// onto a fixed ground box, its elements in contact with the box's
/// collider through the coupling core. After 4 s at 1/60 s the contact
/// force carries the rope's weight within 1e-6, and the rope's middle lies
/// on the ground within the Hertz depth (it neither sinks nor floats):
/// its centre 10 mm (the radius) above the top face within 2 µm, still
/// over the last second within 1e-9 m.
#[test]
fn rope_on_ground_scenario_carries_its_weight() {
    let (world, rows) = run("assets/scenarios/rope_on_ground.toml");
    let weight =
        world.rope("rope").map(|r| r.length()).unwrap() * bevy_rapier_cable::cable::RopeMaterial::steel_6x36_iwrc(0.02).section().linear_density * 9.81;
    let last = rows.last().unwrap();
    let (contact, y) = (last[1], last[3]);
    let second = &rows[rows.len() - 61..];
    let still = second.iter().map(|r| (r[3] - y).abs()).fold(0.0f64, f64::max);
    println!(
        "contact {contact:.6} N vs weight {weight:.6} N ({:+.2e}); middle at y = {y:.7} m; moved {still:.2e} m over the last second",
        contact / weight - 1.0
    );
    assert!((contact / weight - 1.0).abs() < 1e-6, "contact {contact} vs {weight}");
    assert!((y - 0.01).abs() < 2e-6, "middle at {y}");
    assert!(still < 1e-9, "moved {still}");
}

/// `rope_over_box.toml` (issue 12, edges): a free 3 m steel rope (damping
/// 0.05 s) let go over a fixed 1 m cube, 1 m over each of two top edges,
/// 3 s at 1/60 s. At rest the cube carries the rope's weight: its
/// `contact_force` probe (the rope's force on it) is (0, −ρ g L, 0) within
/// 1e-4 of the weight (measured 1.7e-6); the middle rests on the top,
/// bowed up by the legs' bending moments at the edges (between the
/// radius and 5 cm above the top), still over the last second within
/// 1e-6 m; the ends hang below the top.
#[test]
fn rope_over_box_scenario_rests_on_the_edges_with_its_weight() {
    let (world, rows) = run("assets/scenarios/rope_over_box.toml");
    let weight =
        world.rope("rope").map(|r| r.length()).unwrap() * bevy_rapier_cable::cable::RopeMaterial::steel_6x36_iwrc(0.02).section().linear_density * 9.81;
    let last = rows.last().unwrap();
    let (force, middle, end) = ([last[1], last[2], last[3]], last[5], last[8]);
    let second = &rows[rows.len() - 61..];
    let still = second.iter().map(|r| (r[5] - middle).abs()).fold(0.0f64, f64::max);
    println!(
        "force on the cube {force:.5?} N vs weight {weight:.5} N ({:+.2e}); middle {middle:.5} m, end {end:.4} m; moved {still:.2e} m over the last second",
        -force[1] / weight - 1.0
    );
    assert!((-force[1] / weight - 1.0).abs() < 1e-4 && force[0].abs() < 1e-3 * weight && force[2].abs() < 1e-3 * weight, "force {force:?} vs {weight}");
    assert!(middle > 1.01 - 1e-4 && middle < 1.05, "middle at {middle}");
    assert!(still < 1e-6, "moved {still}");
    assert!(end < 1.0, "end at {end}");
}

/// `rope_over_cylinder.toml` (issue 12, frictionless capstan): 20 mm steel
/// rope (its bending stiffness a tenth of the preset's) pinned 3 m from a
/// fixed horizontal cylinder, over its top and a quarter turn down its side
/// to a 1 t ball, 6 s at 1/60 s.
/// * The contact carries the normal force of a frictionless wrap,
///   `∫ (T/R + ρ g sin φ) R dφ = T̄ π/2 + ρ g R`, within 2e-4.
/// * Frictionless, the tension changes along the wrap by the rope's own
///   weight only, `T₂ − T₁ = ρ g (y₂ − y₁)` (−12.85 N), within 10 % of it
///   (measured 4.6 %: the bending moments of the stress-free arc where it
///   no longer matches the cylinder; with the preset's ten times stiffer
///   rope they move it by 8.6 N, docs/architecture.md). The scenario sets
///   `friction = 0` on the rope and the drum: with μ = 0.3 the tension
///   could differ by up to 60 % of T across the wrap, 460 times the weight
///   term (`capstan_friction.toml` checks that).
#[test]
fn rope_over_cylinder_scenario_is_a_frictionless_capstan() {
    let (world, rows) = run("assets/scenarios/rope_over_cylinder.toml");
    let rho = bevy_rapier_cable::cable::RopeMaterial::steel_6x36_iwrc(0.02).section().linear_density;
    let g = 9.81;
    let last = rows.last().unwrap();
    let (t1, t2, contact) = (last[1], last[2], last[3]);
    let rope = world.rope("rope").unwrap();
    let (y1, y2) = (rope.point_at(2.7).0.y, rope.point_at(3.0 + std::f64::consts::FRAC_PI_2 * 0.515 + 0.3).0.y);
    let weight_change = rho * g * (y2 - y1);
    let expected_contact = 0.5 * (t1 + t2) * std::f64::consts::FRAC_PI_2 + rho * g * 0.51;
    println!(
        "T1 {t1:.3} N, T2 {t2:.3} N: T2 − T1 = {:.3} N vs ρ g (y2 − y1) = {weight_change:.3} N; contact {contact:.2} N vs {expected_contact:.2} N ({:+.2e}); payload at {:?}",
        t2 - t1,
        contact / expected_contact - 1.0,
        &last[4..7]
    );
    assert!(((t2 - t1) - weight_change).abs() < 0.1 * weight_change.abs(), "T2 − T1 = {} vs {weight_change}", t2 - t1);
    assert!((contact / expected_contact - 1.0).abs() < 2e-4, "contact {contact} vs {expected_contact}");
}

/// `rope_over_cylinder.toml` as a newcomer lays it: the preset's bending
/// stiffness (50 N·m², ten times the file's) and the rope laid bent over
/// the drum with its bending stress (`stress_free = false`: straight at
/// rest). It runs its 6 s at 1/60 s, and the hanging run carries what
/// hangs below it: over the last second the tension 0.3 m below the wrap
/// is `(m + ρ l) g` (the ball and the 4.7 m of rope under the probe)
/// within 1e-3, and the ball stays below the drum's side, within 5 cm of
/// the tangent line `x = R + r` (it swings a little as the rope, let go
/// bent, settles). (Until 2026-11-29 the scenario's comment said such a
/// rope whipped straight and failed its first frame step.)
#[test]
fn rope_over_cylinder_laid_bent_with_the_presets_bending_stiffness_holds() {
    let from = "stress_free = true\nei = 5.0";
    let rows = scenario_run::run_shipped_variant("rope_over_cylinder", from, "stress_free = false");
    let rho = bevy_rapier_cable::cable::RopeMaterial::steel_6x36_iwrc(0.02).section().linear_density;
    let below = 8.808635273 - 4.108635273;
    let expected = (1000.0 + rho * below) * 9.81;
    let last_second = &rows[rows.len() - 60..];
    let mean = last_second.iter().map(|r| r[2]).sum::<f64>() / 60.0;
    let off = rows.iter().map(|r| (r[4] - 0.51).abs()).fold(0.0f64, f64::max);
    println!(
        "hanging run's tension over the last second {mean:.3} N vs (m + ρ l) g = {expected:.3} N ({:+.2e}); the ball at most {off:.4} m off x = R + r",
        mean / expected - 1.0
    );
    assert!((mean / expected - 1.0).abs() < 1e-3, "tension {mean} vs {expected}");
    assert!(off < 0.05, "the ball swung {off} m off the tangent line");
}

/// `payload_set_down.toml` (issue 12: "a payload lowered onto the ground
/// stops without jitter, and its rope tension drops to zero"): a kinematic
/// hook lowers a 1 t crate (1 m cube) on 10.5 m of steel rope onto a fixed
/// ground box; the crate's corners touch the ground inside the rope's
/// implicit solve. After 12 s at 1/60 s: the crate rests flat at its
/// height less the Hertz depth of a quarter of its weight on a corner
/// (within 1e-4 m), tilted less than 1e-4°, still over the last second
/// (1e-9 m), and the rope's tension at the crate is below 1 % of the
/// crate's weight. (Before: rapier's contact reached the carried crate one
/// step late and it sank 0.56 m and tipped 20–29° in 4.5 s.)
#[test]
fn payload_set_down_scenario_rests_on_the_ground() {
    let (_, rows) = run("assets/scenarios/payload_set_down.toml");
    let last = rows.last().unwrap();
    let (y, tilt, tension) = (last[2], last[4].abs().max(last[6].abs()), last[7]);
    let second = &rows[rows.len() - 61..];
    let still = second.iter().map(|r| (r[2] - y).abs().max((r[1] - last[1]).abs())).fold(0.0f64, f64::max);
    let low = rows.iter().map(|r| r[2]).fold(f64::INFINITY, f64::min);
    println!("crate centre y {y:.7} m (lowest {low:.7}), tilt {tilt:.2e}°, moved {still:.2e} m over the last second, rope tension at the crate {tension:.2} N");
    assert!((y - 0.5).abs() < 1e-4, "crate at {y}");
    assert!(low > 0.5 - 1e-3, "sank to {low}");
    assert!(tilt < 1e-4, "tilt {tilt}°");
    assert!(still < 1e-9, "moved {still}");
    assert!(tension.abs() < 0.01 * 1000.0 * 9.81, "tension {tension}");
    // The body `contact_force` probes: the ground holds the crate up with
    // its weight and the part of the slack rope that rests on it (between
    // none and the whole rope's weight: its 0.5 m of slack piles on the
    // crate's top, where a slack element closed to zero length pushes), and
    // the crate pushes the ground down as much.
    let (on_crate, on_ground) = (DVec3::new(last[8], last[9], last[10]), DVec3::new(last[11], last[12], last[13]));
    let rope_weight = 10.5 * 1.6 * 9.81;
    let rope_on_crate = on_crate.y - 1000.0 * 9.81;
    println!(
        "contact force on the crate {on_crate} N, on the ground {on_ground} N: the rope rests on the crate with {rope_on_crate:.2} N of its {rope_weight:.1} N"
    );
    assert!(rope_on_crate > -1e-6 && rope_on_crate < rope_weight && on_crate.x.abs() < 1e-6 && on_crate.z.abs() < 1e-6, "on the crate: {on_crate}");
    assert!(tension > -rope_weight, "the rope pushes on the crate with more than its weight: {tension}");
    assert!((on_crate + on_ground).length() < 1e-9 * on_crate.length(), "on the ground: {on_ground}");
}

/// A hook block and its payload (`hook_and_payload.toml`): two bodies in
/// series on two ropes, one implicit chain (the hook a hub, the sling
/// grafted onto it with the payload as its end body). Reference: the
/// linearised double pendulum of point masses m₁, m₂ on straight rigid
/// uniform rods of masses μ₁, μ₂ (the ropes), lengths l₁, l₂ (read from
/// the static start, so stretched by the static tension), by Lagrange:
/// `M = [[(m₁+m₂+μ₂) l₁² + μ₁l₁²/3, (m₂+μ₂/2) l₁l₂], [·, (m₂+μ₂/3) l₂²]]`,
/// `K = diag((m₁+m₂+μ₂+μ₁/2) g l₁, (m₂+μ₂/2) g l₂)`. Started in each mode's
/// velocity shape (the file as shipped: the slow mode at 0.02 rad; the
/// fast one at 0.002 rad by replacing the velocities: its period grows
/// with amplitude faster, +0.7 % at 0.02 rad by a nonlinear RK4 integration
/// of the point-mass double pendulum), each swings at its own period with
/// its own angle ratio θ₂/θ₁. The slow mode at the frame step, the fast
/// one at a tenth of it (the scheme's period error), with the defaults.
#[test]
fn hook_and_payload_swings_in_the_double_pendulum_modes() {
    let src = std::fs::read_to_string("assets/scenarios/hook_and_payload.toml").unwrap();
    let s = bevy_rapier_cable::cable::preset("steel_wire_rope_6x36_iwrc", 0.012).unwrap();
    let (g, m1, m2) = (9.81, 1000.0, 2000.0);
    let (mu1, mu2) = (10.0 * s.linear_density, 3.0 * s.linear_density);
    // The fast mode at a tenth of the frame step: at 1/60 s (ωh = 0.058)
    // generalized-α ρ∞ = 0 lengthens its period by 1.5e-3 (0.46 (ωh)², as
    // the trolley pendulum's +3.9e-4 at ωh = 0.029); measured +1.6e-3.
    let fast = src
        .replace("dt = 0.016666666666666666", "dt = 0.0016666666666666668")
        .replace("linear_velocity = [0.17996, 0.0, 0.0]", "linear_velocity = [0.069286, 0.0, 0.0]")
        .replace("linear_velocity = [0.23871, 0.0, 0.0]", "linear_velocity = [-0.026182, 0.0, 0.0]");
    assert_ne!(fast, src);
    for (mode, text) in [src, fast].into_iter().enumerate() {
        let sc = scenario::parse(&text, "hook_and_payload.toml").unwrap_or_else(|e| panic!("{e}"));
        let (world, rows) = run_scenario(sc);
        // Columns: time, hook xyz, payload xyz, hoist_top, sling_top.
        let (l1, l2) = (-rows[0][2], rows[0][2] - rows[0][5]);
        let mm = [[(m1 + m2 + mu2) * l1 * l1 + mu1 * l1 * l1 / 3.0, (m2 + mu2 / 2.0) * l1 * l2], [(m2 + mu2 / 2.0) * l1 * l2, (m2 + mu2 / 3.0) * l2 * l2]];
        let kk = [(m1 + m2 + mu2 + mu1 / 2.0) * g * l1, (m2 + mu2 / 2.0) * g * l2];
        // det(K − ω² M) = 0: a ω⁴ + b ω² + c = 0.
        let a = mm[0][0] * mm[1][1] - mm[0][1] * mm[1][0];
        let b = -(kk[0] * mm[1][1] + kk[1] * mm[0][0]);
        let c = kk[0] * kk[1];
        let disc = (b * b - 4.0 * a * c).sqrt();
        let omega2 = if mode == 0 { (-b - disc) / (2.0 * a) } else { (-b + disc) / (2.0 * a) };
        let ratio = -(kk[0] - omega2 * mm[0][0]) / (-omega2 * mm[0][1]);
        let period = 2.0 * std::f64::consts::PI / omega2.sqrt();
        let measured = period_of(&rows, 1);
        let (th1, th2): (Vec<f64>, Vec<f64>) = rows.iter().map(|r| (r[1] / l1, (r[4] - r[1]) / l2)).unzip();
        let got_ratio = th1.iter().zip(&th2).map(|(a, b)| a * b).sum::<f64>() / th1.iter().map(|a| a * a).sum::<f64>();
        let amplitude = th1.iter().fold(0.0f64, |m, t| m.max(t.abs()));
        println!(
            "mode {mode}: l₁ = {l1:.5} m, l₂ = {l2:.5} m; period {measured:.5} s against {period:.5} s ({:+.1e}); θ₂/θ₁ {got_ratio:.5} against {ratio:.5} ({:+.1e}); θ₁ amplitude {amplitude:.4} rad; {:.2} Newton its/step",
            measured / period - 1.0,
            got_ratio / ratio - 1.0,
            world.work().0 as f64 / world.steps as f64
        );
        assert!((measured / period - 1.0).abs() < 5e-4, "mode {mode}: period {measured} against {period}");
        assert!((got_ratio / ratio - 1.0).abs() < 2e-3, "mode {mode}: angle ratio {got_ratio} against {ratio}");
        let asked = [0.02, 0.002][mode];
        assert!((amplitude / asked - 1.0).abs() < 2e-2, "mode {mode}: amplitude {amplitude} against {asked}");
    }
}

/// A `table` motion's velocity jump is an impulse on what hangs from the
/// body: a 1 t payload on 5 m of 20 mm steel rope from a kinematic
/// trolley that sets off at v = 0.5 m/s at t = 0.5 s (a table: at rest,
/// then constant speed). In the trolley's frame the payload then swings
/// with the relative velocity −v it was left with: amplitude v/ω about
/// the point under the trolley, ω² = (g/l)(M + m_r/2)/(M + m_r/3) (the
/// straight rope's mass m_r). The table's jump is spread over two steps
/// (`sim::world::body_motion`), so the amplitude is that of an impulse
/// smeared over two steps, within (ωh)² = 1.3e-3 of v/ω. Before,
/// the relative coordinates never saw the jump: the payload set off with
/// the trolley, rigidly, and did not swing at all.
#[test]
fn a_table_driven_trolley_setting_off_leaves_its_payload_swinging() {
    let v = 0.5;
    let src = format!(
        r#"
[simulation]
duration = 10.0
dt = 0.016666666666666666
statics = true

[[body]]
name = "trolley"
type = "kinematic"
shape = "cuboid"
half_extents = [0.3, 0.1, 0.3]
position = [0.0, 0.0, 0.0]
motion = {{ type = "table", points = [[0.0, [0.0, 0.0, 0.0]], [0.5, [0.0, 0.0, 0.0]], [20.0, [{x}, 0.0, 0.0]]] }}

[[body]]
name = "payload"
type = "dynamic"
shape = "ball"
radius = 0.3
mass = 1000.0
position = [0.0, -5.0, 0.0]

[[cable]]
name = "hoist"
length = 5.0
segments = 20
diameter = 0.020
material = "steel_wire_rope_6x36_iwrc"
start = {{ body = "trolley", anchor = [0.0, 0.0, 0.0] }}
end = {{ body = "payload", anchor = [0.0, 0.0, 0.0] }}

[[probe]]
name = "trolley"
body = "trolley"
quantity = "position"

[[probe]]
name = "payload"
body = "payload"
quantity = "position"
"#,
        x = v * 19.5
    );
    let sc = scenario::parse(&src, "set_off.toml").unwrap_or_else(|e| panic!("{e}"));
    let (_, rows) = run_scenario(sc);
    let s = bevy_rapier_cable::cable::preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap();
    let (g, m, m_r) = (9.81, 1000.0, 5.0 * s.linear_density);
    let l = -rows[0][5];
    let omega = (g / l * (m + m_r / 2.0) / (m + m_r / 3.0)).sqrt();
    // Relative sway after the set-off.
    let rel: Vec<(f64, f64)> = rows.iter().filter(|r| r[0] > 0.6).map(|r| (r[0], r[4] - r[1])).collect();
    let amplitude = rel.iter().fold(0.0f64, |a, r| a.max(r.1.abs()));
    let expected = v / omega;
    let mean = rel.iter().map(|r| r.1).sum::<f64>() / rel.len() as f64;
    let before = rows.iter().filter(|r| r[0] < 0.5).fold(0.0f64, |a, r| a.max((r[4] - r[1]).abs()));
    println!("pivot set off at {v} m/s: sway amplitude {amplitude:.5} m against v/ω = {expected:.5} m ({:+.1e}); mean {mean:.2e} m; before the set-off {before:.1e} m", amplitude / expected - 1.0);
    assert!(before < 1e-9, "the payload moved before the trolley did: {before}");
    assert!((amplitude / expected - 1.0).abs() < 5e-3, "sway amplitude {amplitude} against {expected}");
}

/// An undamped slack snap under a swinging jib runs (docs/architecture.md,
/// "Energy-checked sub-steps"): a 200 kg hook block on 8 m of 16 mm steel
/// rope laid 0.2 m slack from a kinematic jib swinging ±1.5 m along x (4 s
/// period), a 1 t crate on 1.8 m below it, undamped, the crate given
/// 0.5 m/s along z. The rope snaps taut and whips. Until 2026-11-28 Newton
/// failed at every split at 0.617 s and the run stopped with the advice to
/// damp the rope; now the moving jib's work is counted in the energy check
/// (so the tangent's fallback is tried, energy-checked, at every split, as
/// for a fixed jib) and a sub-step of the finest split whose Newton solve
/// fails is cut into up to 64 pieces. Undamped it runs its first 1.5 s
/// here (the whole 10 s in 188 s of CPU: about 1 600 sub-steps and 3 200
/// Newton iterations per frame step while it whips); with damping
/// (τ = 0.01 s) the same scene runs its 10 s at the frame step's cost.
/// (The advice on a failure that remains:
/// `slack::a_failure_on_an_undamped_slack_rope_says_to_damp_it`.)
#[test]
fn an_undamped_slack_snap_under_a_swinging_jib_runs() {
    let scene = |damping: &str, duration: f64| {
        format!(
            r#"
[simulation]
duration = {duration}
dt = 0.016666666666666666

[[body]]
name = "jib"
type = "kinematic"
shape = "cuboid"
half_extents = [0.5, 0.2, 0.5]
position = [0.0, 12.0, 0.0]
motion = {{ type = "sine", amplitude = [1.5, 0.0, 0.0], period = 4.0 }}

[[body]]
name = "hook"
type = "dynamic"
shape = "ball"
radius = 0.2
mass = 200.0
position = [0.0, 3.8, 0.0]

[[body]]
name = "crate"
type = "dynamic"
shape = "cuboid"
half_extents = [0.6, 0.4, 0.6]
mass = 1000.0
position = [0.0, 1.4, 0.0]
linear_velocity = [0.0, 0.0, 0.5]

[[cable]]
name = "hoist"
length = 8.0
segments = 32
diameter = 0.016
material = "steel_wire_rope_6x36_iwrc"
{damping}
start = {{ body = "jib", anchor = [0.0, -0.2, 0.0] }}
end = {{ body = "hook", anchor = [0.0, 0.2, 0.0] }}

[[cable]]
name = "sling"
length = 1.8
segments = 8
diameter = 0.016
material = "steel_wire_rope_6x36_iwrc"
{damping}
start = {{ body = "hook", anchor = [0.0, -0.2, 0.0] }}
end = {{ body = "crate", anchor = [0.0, 0.4, 0.0] }}
"#
        )
    };
    let run = |src: String| {
        let sc = scenario::parse(&src, "snap.toml").unwrap_or_else(|e| panic!("{e}"));
        let mut world = World::new(sc).unwrap_or_else(|e| panic!("{e}"));
        while world.time < world.scenario.simulation.duration - 1e-9 {
            if let Err(e) = world.step() {
                return Err((world.time, e.to_string()));
            }
        }
        Ok(world.work().0 as f64 / world.steps as f64)
    };
    let iterations = run(scene("", 1.5)).unwrap_or_else(|(t, e)| panic!("undamped: stopped at {t} s: {e}"));
    println!("undamped: ran 1.5 s at {iterations:.1} Newton iterations per step");
    let iterations = run(scene("damping = 0.01", 10.0)).unwrap_or_else(|(t, e)| panic!("damped: stopped at {t} s: {e}"));
    println!("damped (τ = 0.01 s): ran 10 s at {iterations:.1} Newton iterations per step");
}

/// A cable's `linear_damping` and `angular_damping` (1/s) reach the rope
/// (`RopeBuilder::velocity_damping`): a free 4 m steel rope (both ends
/// free, laid along x) with c = 2 /s falls at v(t) = −(g/c)(1 − e^(−ct)),
/// every node, over 2 s at 1/60 s (the model's own test,
/// `slack::velocity_damping_matches_the_closed_form_fall`, bounds the
/// same fall at 2e-3 of g/c); and without them it falls freely, −g t.
#[test]
fn a_cables_velocity_damping_fields_damp_its_fall_as_the_closed_form() {
    for c in [2.0, 0.0] {
        let src = format!(
            r#"
[simulation]
duration = 2.0
dt = 0.016666666666666666

[[cable]]
name = "rope"
length = 4.0
segments = 8
diameter = 0.02
material = "steel_wire_rope_6x36_iwrc"
linear_damping = {c}
angular_damping = {c}
path = [[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]]
"#
        );
        let mut w = World::new(scenario::parse(&src, "damped_fall.toml").unwrap()).unwrap();
        let mut worst = 0.0f64;
        for _ in 0..120 {
            w.step().unwrap();
            let rope = w.cable("rope").unwrap();
            let t = rope.time();
            let exact = if c > 0.0 { -(9.81 / c) * (1.0 - (-c * t).exp()) } else { -9.81 * t };
            for v in rope.node_velocities() {
                worst = worst.max((v.y - exact).abs() / 9.81);
            }
        }
        println!("c = {c} /s: largest velocity error {worst:.2e} × g·s");
        assert!(worst < 2e-3, "c = {c}: {worst}");
    }
}

/// A newcomer's sling laid slack (2026-11-28): a 500 kg crate
/// (1 × 0.6 × 1 m) on two 3.2 m legs of 16 mm steel rope from one hook
/// 2.9 m above its centre to the middles of its two top edges (2.65 m
/// away: 0.55 m of slack each, the legs laid straight), undamped, contacts
/// on, 4 s at 1/60 s, with the ropes' friction (0.3) and frictionless.
/// Nothing does work on it (the hook is fixed), so its energy may only
/// fall. The crate drops, snaps the legs taut and rebounds, and the slack
/// legs whip into each other near the hook (both in one plane) at up to
/// 100 m/s. Before, a leg's elements were found 15.7 mm inside the other's
/// at a contact pass, the Hertz law took that overlap as 170 kJ of stored
/// energy, and the run gained 35 MJ, threw the crate 8 m up and stopped at
/// 0.55 s ("element 10 strained by 105 %"); frictionless, it stopped at
/// 0.50 s. Now an overlap found at a pass's start is not elastic energy
/// (`coupling::contact::pair_overlap`), and the tree with its pair
/// contacts is energy-checked (`Chain::is_passive`). The bound, 1e-3 of
/// the drop's energy m g · 0.55 m, is a guard: the run never rose above
/// its start at all.
#[test]
fn an_undamped_sling_laid_slack_from_one_hook_never_gains_energy() {
    for friction in ["", "friction = 0.0"] {
        let leg = |name: &str, x: f64| {
            format!(
                r#"
[[cable]]
name = "{name}"
length = 3.2
segments = 16
diameter = 0.016
material = "steel_wire_rope_6x36_iwrc"
{friction}
start = {{ world = [0.0, 2.9, 0.0] }}
end = {{ body = "crate", anchor = [{x}, 0.3, 0.0] }}
"#
            )
        };
        let src = format!(
            r#"
[simulation]
duration = 4.0
dt = 0.016666666666666666

[[body]]
name = "crate"
type = "dynamic"
shape = "cuboid"
half_extents = [0.5, 0.3, 0.5]
mass = 500.0
position = [0.0, 0.0, 0.0]
{}{}
[[probe]]
name = "crate"
body = "crate"
quantity = "position"

[[probe]]
name = "energy"
system = true
quantity = "energy"

[[probe]]
name = "a_on_b"
cable = "leg_a"
quantity = "contact_force"
"#,
            leg("leg_a", -0.5),
            leg("leg_b", 0.5)
        );
        let sc = scenario::parse(&src, "sling_slack.toml").unwrap_or_else(|e| panic!("{e}"));
        let e0 = {
            let w = World::new(sc.clone()).unwrap_or_else(|e| panic!("{e}"));
            let mut row = Vec::new();
            w.sample(&mut row);
            row[3]
        };
        let (world, rows) = run_scenario(sc);
        let most = rows.iter().map(|r| r[4]).fold(f64::NEG_INFINITY, f64::max);
        let highest = rows.iter().map(|r| r[2]).fold(f64::NEG_INFINITY, f64::max);
        let touches = rows.iter().filter(|r| r[5] > 0.0).count();
        let scale = 500.0 * 9.81 * 0.55;
        println!(
            "{}: energy {e0:.2} J at the start, at most {most:.2} J, {:.2} J at 4 s; crate at most {highest:.4} m up; legs touching at {touches} frame ends; {:.1} Newton iterations per frame",
            if friction.is_empty() { "friction 0.3" } else { "frictionless" },
            rows.last().unwrap()[4],
            world.work().0 as f64 / world.steps as f64
        );
        assert!(most - e0 < 1e-3 * scale, "the energy rose from {e0} J to {most} J");
        assert!(highest < 0.01, "the crate was thrown up to {highest} m");
    }
}
