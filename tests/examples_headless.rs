//! Every example runs headless for a few frames (they are built by
//! `cargo test`; this runs the binaries).

use std::path::PathBuf;
use std::process::Command;

fn example(name: &str) -> PathBuf {
    // target/<profile>/deps/<this test> → target/<profile>/examples/<name>
    let exe = std::env::current_exe().unwrap();
    let profile_dir = exe.parent().unwrap().parent().unwrap();
    let path = profile_dir.join("examples").join(name);
    if !path.exists() {
        // `cargo test` builds the examples; a filtered `cargo test --test …` does not.
        let mut cmd = Command::new(env!("CARGO"));
        cmd.args(["build", "--example", name]);
        if profile_dir.file_name().is_some_and(|p| p == "release") {
            cmd.arg("--release");
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
