//! Every example runs headless for a few frames (they are built by
//! `cargo test`; this runs the binaries). The demos (feature `demo`:
//! `cargo test --profile ci-demo --features demo --test examples_headless`,
//! as CI does, or `--release`) run
//! with `--headless N`: no window and no renderer.

use std::path::PathBuf;
use std::process::Command;

/// The example's binary, built (or found up to date) with the features this
/// test is built with, so that it shares its dependencies.
fn example(name: &str) -> PathBuf {
    // target/<profile>/deps/<this test> → target/<profile>/examples/<name>
    let exe = std::env::current_exe().unwrap();
    let profile_dir = exe.parent().unwrap().parent().unwrap();
    let path = profile_dir.join("examples").join(name);
    {
        // `cargo test` builds the examples; a filtered `cargo test --test …`
        // does not, and a binary left from an earlier build may be stale.
        let mut cmd = Command::new(env!("CARGO"));
        cmd.args(["build", "--example", name]);
        if cfg!(feature = "demo") {
            cmd.args(["--features", "demo"]);
        }
        // The profile this test was built with (its folder: `debug` is `dev`).
        match profile_dir.file_name().and_then(|p| p.to_str()) {
            Some("debug") | None => {}
            Some(profile) => {
                cmd.args(["--profile", profile]);
            }
        }
        assert!(cmd.status().unwrap().success(), "could not build example {name}");
    }
    path
}

#[test]
fn trolley_crane_runs_headless() {
    let out = Command::new(example("trolley_crane")).arg("130").output().expect("example built by cargo test");
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success());
    assert!(stdout.contains("t =  1.00 s") && stdout.contains("top tension"), "{stdout}");
}

/// The windowed demo, headless: 2 s with a 1 m/s sideways kick at 0.2 s.
/// A 1 t crate on 10 m of 20 mm rope (16 kg): the top tension stays near
/// (1000 + 16) kg · g = 9.97 kN (a 5.7° swing adds under 2 %), and the
/// rope leans by about 5.7° (the kick's swing, 1.8 s into its 6.3 s period).
#[cfg(feature = "demo")]
#[test]
fn hanging_payload_runs_headless() {
    let line = &report_line("hanging_payload", "120", "hanging_payload: t = 2.00 s");
    let (tension, sway) = (value_after(line, "top tension = "), value_after(line, "sway = "));
    assert!((9.5..10.5).contains(&tension), "top tension {tension} kN");
    assert!((3.0..8.0).contains(&sway), "sway {sway}°");
}

#[cfg(feature = "demo")]
#[test]
fn hanging_payload_refuses_bad_arguments() {
    let out = Command::new(example("hanging_payload")).args(["--headless", "many"]).output().expect("example built");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("usage"));
}

/// Runs a demo with `--headless FRAMES`: it succeeds, and prints a line
/// starting with `prefix` (returned).
#[cfg(feature = "demo")]
fn report_line(name: &str, frames: &str, prefix: &str) -> String {
    report_line_with(name, &["--headless", frames], prefix)
}

/// The report line of an example run with `args`.
#[cfg(feature = "demo")]
fn report_line_with(name: &str, args: &[&str], prefix: &str) -> String {
    let out = Command::new(example(name)).args(args).output().expect("example built by cargo test");
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success());
    stdout.lines().find(|l| l.starts_with(prefix)).unwrap_or_else(|| panic!("no report line: {stdout}")).to_string()
}

/// The number after `key` in `line`.
#[cfg(feature = "demo")]
fn value_after(line: &str, key: &str) -> f64 {
    let rest = &line[line.find(key).unwrap_or_else(|| panic!("{key} in {line}")) + key.len()..];
    rest.split_whitespace().next().map(|v| v.trim_end_matches(',')).and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("{key} in {line}"))
}

/// The overhead crane, headless: the trolley driven at 1.5 m/s for 2 s
/// (it reaches it in a few steps) stops near x = 2.9 m; 1 s later the crate
/// swings back (its first swing, period 6.5 s: a few degrees) on a top
/// tension near (1000 + 16) kg · g = 9.97 kN (the swing and the braking
/// add up to about 15 %).
#[cfg(feature = "demo")]
#[test]
fn overhead_crane_runs_headless() {
    let line = &report_line("overhead_crane", "180", "overhead_crane: t = 3.00 s");
    let (x, speed, sway, tension) =
        (value_after(line, "trolley x = "), value_after(line, "speed = "), value_after(line, "sway = "), value_after(line, "top tension = "));
    assert!((2.7..3.1).contains(&x), "trolley at {x} m");
    assert!(speed.abs() < 0.2, "trolley speed {speed} m/s");
    assert!((1.0..15.0).contains(&sway.abs()), "sway {sway}°");
    assert!((8.5..12.5).contains(&tension), "top tension {tension} kN");
}

/// The overhead crane's anti-sway switch, headless: the same scripted
/// drive (1.5 m/s for 2 s, then stop) through the ZV shaper leaves the
/// crate hanging still after the shaped stop (largest sway from 6 to 10 s
/// below 0.5°; the shaper on the full rope leaves a few hundredths of the
/// unshaped swing), while without it the crate swings by degrees.
#[cfg(feature = "demo")]
#[test]
fn overhead_crane_anti_sway_stops_the_swing() {
    let on = &report_line_with("overhead_crane", &["--headless", "600", "--anti-sway"], "overhead_crane: t = 10.00 s");
    let off = &report_line_with("overhead_crane", &["--headless", "600"], "overhead_crane: t = 10.00 s");
    let (late_on, late_off) = (value_after(on, "largest sway since 6 s = "), value_after(off, "largest sway since 6 s = "));
    assert!(on.contains("anti-sway on") && off.contains("anti-sway off"), "{on} / {off}");
    assert!(late_on < 0.5 && late_off > 2.0, "largest late sway: {late_on}° with anti-sway, {late_off}° without");
}

/// The tow rope, headless: 3 s of full throttle (1.5 m/s² to 4 m/s), then
/// coasting; at 4 s the trailer follows at the truck's speed, the rope
/// about its length between the hitches, and it does not sag towards the
/// ground (no rope–ground contact yet: the demo keeps it up).
#[cfg(feature = "demo")]
#[test]
fn tow_rope_runs_headless() {
    let line = &report_line("tow_rope", "240", "tow_rope: t = 4.00 s");
    let (truck, trailer, gap, lowest) =
        (value_after(line, "truck = "), value_after(line, "trailer = "), value_after(line, "gap = "), value_after(line, "lowest rope point = "));
    assert!((3.4..4.0).contains(&truck), "truck {truck} m/s");
    assert!((trailer - truck).abs() < 0.5, "trailer {trailer} m/s, truck {truck} m/s");
    assert!((5.8..6.3).contains(&gap), "gap {gap} m");
    assert!(lowest > 1.0, "the rope sags to {lowest} m");
}

/// The tow rope, headless, steering full left from 1 s (`--steer`): the
/// truck turns about 1 rad by 4 s and the trailer follows on a wider arc.
/// Before, the cable stopped with "Newton did not converge" at 1.58 s: the
/// sampled truck's orientation was held over each step (every new sample
/// then swung the rope about its pin), and the trailer end's anchor spring
/// made the tangent indefinite when its target jumped.
#[cfg(feature = "demo")]
#[test]
fn tow_rope_steers_headless() {
    let line = &report_line_with("tow_rope", &["--headless", "240", "--steer"], "tow_rope: t = 4.00 s");
    let (truck, trailer, gap, tension, lowest) = (
        value_after(line, "truck = "),
        value_after(line, "trailer = "),
        value_after(line, "gap = "),
        value_after(line, "tension = "),
        value_after(line, "lowest rope point = "),
    );
    assert!((3.4..4.0).contains(&truck), "truck {truck} m/s");
    assert!((trailer - truck).abs() < 0.6, "trailer {trailer} m/s, truck {truck} m/s");
    // Turning, the hitches come closer than the rope's 6 m.
    assert!((4.5..6.1).contains(&gap), "gap {gap} m");
    assert!(tension < 10.0, "tension {tension} kN");
    assert!(lowest > 1.0, "the rope sags to {lowest} m");
}

/// The seed paper's cable impact, headless: 1.25 s from the 50° release. The
/// pendant strikes the span and wraps over it: the largest contact force
/// between the ropes is that of `cable_impact.toml` run by `cablesim`
/// (1.317 kN at the frame step, at 1.03 s), here within 10 %.
#[cfg(feature = "demo")]
#[test]
fn cable_impact_runs_headless() {
    let line = &report_line("cable_impact", "75", "cable_impact: t = 1.25 s");
    let (contact, speed) = (value_after(line, "largest contact force = "), value_after(line, "hook speed = "));
    assert!((1.185..1.45).contains(&contact), "largest contact force {contact} kN");
    assert!(speed < 5.0, "hook speed {speed} m/s");
}

/// The rope bridge, headless: 50 frames (0.83 s). The first crate, let go
/// at rest 0.7 m above the pins, has struck the two sagging ropes at about
/// 3.5 m/s and rides them (its centre between 1.6 and 2.2 m: not through
/// them, not thrown off); the second, let go at 0.7 s, is still falling.
/// The ropes' largest tension lies between the crate's static share
/// (about 0.7 kN per rope) and 20 kN. The full drop series (six crates,
/// stacking, one removed) runs in `plugin_contact.rs`.
#[cfg(feature = "demo")]
#[test]
fn rope_bridge_runs_headless() {
    let line = &report_line("rope_bridge", "50", "rope_bridge: t = 0.83 s");
    let (on, low, high, tension) = (
        value_after(line, "crates on the bridge = "),
        value_after(line, "lowest crate y = "),
        value_after(line, "highest crate y = "),
        value_after(line, "largest tension = "),
    );
    assert_eq!(on, 1.0, "{line}");
    assert!(low > 1.6 && high < 2.2, "{line}");
    assert!((0.7..20.0).contains(&tension), "largest tension {tension} kN");
}

/// `cablesim view --headless N` steps a scenario as `cablesim run` does:
/// the probes it prints after 1 s are `run`'s results.csv row at 1 s.
#[cfg(all(feature = "demo", feature = "cli"))]
#[test]
fn cablesim_view_runs_headless_as_run() {
    let dir = std::env::temp_dir().join(format!("cablesim_view_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The shipped hanging payload, 1 s long.
    let text = std::fs::read_to_string("assets/scenarios/hanging_payload.toml").unwrap();
    let short = text.lines().map(|l| if l.starts_with("duration") { "duration = 1.0".to_string() } else { l.to_string() }).collect::<Vec<_>>().join("\n");
    let file = dir.join("hanging_payload_1s.toml");
    std::fs::write(&file, short).unwrap();
    let cablesim = env!("CARGO_BIN_EXE_cablesim");
    let run = Command::new(cablesim).arg("run").arg(&file).arg("--out").arg(&dir).arg("--quiet").output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let last: Vec<f64> = csv.lines().last().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    assert!((last[0] - 1.0).abs() < 1e-9, "last row at {} s", last[0]);
    let out = Command::new(cablesim).arg("view").arg(&file).args(["--headless", "60"]).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success());
    assert!(stdout.contains("t = 1.000 s, 60 frames, max tension = "), "{stdout}");
    for (name, want) in header.iter().zip(&last).skip(1) {
        let line = stdout.lines().find(|l| l.trim_start().starts_with(&format!("{name} = "))).unwrap_or_else(|| panic!("no probe {name}: {stdout}"));
        let got = value_after(line, " = ");
        assert!((got - want).abs() <= 1e-5 * want.abs().max(1.0), "{name}: view {got}, run {want}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `cablesim view` on a bad file: `run`'s message (file:line:col) and exit
/// status 2, no panic, no window.
#[cfg(all(feature = "demo", feature = "cli"))]
#[test]
fn cablesim_view_refuses_a_bad_file() {
    let dir = std::env::temp_dir().join(format!("cablesim_view_bad_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.toml");
    std::fs::write(&file, "[simulation]\nduration = 1.0\ndt = -0.01\n").unwrap();
    let cablesim = env!("CARGO_BIN_EXE_cablesim");
    let view = Command::new(cablesim).arg("view").arg(&file).args(["--headless", "5"]).output().unwrap();
    let run = Command::new(cablesim).arg("check").arg(&file).output().unwrap();
    let stderr = String::from_utf8_lossy(&view.stderr);
    assert_eq!(view.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr, String::from_utf8_lossy(&run.stderr), "view and check give the same message");
    assert!(stderr.contains("bad.toml:3:"), "{stderr}");
    let missing = Command::new(cablesim).args(["view", "no/such/file.toml", "--headless", "5"]).output().unwrap();
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no/such/file.toml"));
    let _ = std::fs::remove_dir_all(&dir);
}
