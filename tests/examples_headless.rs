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
    let out = Command::new(example("hanging_payload")).args(["--headless", "120"]).output().expect("example built by cargo test");
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success());
    let line = stdout.lines().find(|l| l.starts_with("hanging_payload: t = 2.00 s")).unwrap_or_else(|| panic!("no report line: {stdout}"));
    let value = |key: &str| -> f64 {
        let rest = &line[line.find(key).unwrap_or_else(|| panic!("{key} in {line}")) + key.len()..];
        rest.split_whitespace().next().and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("{key} in {line}"))
    };
    let (tension, sway) = (value("top tension = "), value("sway = "));
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
