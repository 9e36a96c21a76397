//! The `cablesim` command: exit statuses and files of SCENARIO.md.

use std::process::Command;

fn cablesim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_cablesim"))
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("cablesim-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn run_writes_results_summary_and_plot() {
    let out = tmp("run");
    let st = cablesim().args(["run", "assets/scenarios/trolley_pendulum.toml", "--plot", "--quiet", "--out"]).arg(&out).status().unwrap();
    assert_eq!(st.code(), Some(0));
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert_eq!(header, "time,trolley_x,payload.x,payload.y,payload.z,tension");
    assert!(csv.lines().count() > 4000);
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["real_time_factor"].as_f64().unwrap() > 0.0);
    assert!(summary["probes"]["trolley_x"]["max"].as_f64().unwrap() > 0.0);
    let png = std::fs::read(out.join("plot.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

#[test]
fn invalid_file_exits_2_with_position() {
    let dir = tmp("bad");
    let f = dir.join("bad.toml");
    std::fs::write(&f, "[simulation]\nduration = 1.0\ndt = 0.01\n\n[[cable]]\nname = \"c\"\nlength = -3.0\nsegments = 4\ndiameter = 0.01\nmaterial = \"steel_wire_rope_6x36_iwrc\"\nstart = { world = [0, 0, 0] }\n").unwrap();
    for cmd in ["check", "run"] {
        let o = cablesim().arg(cmd).arg(&f).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        println!("{err}");
        assert_eq!(o.status.code(), Some(2), "{cmd}");
        assert!(err.contains("bad.toml:7:"), "{err}");
        assert!(err.contains("length"), "{err}");
    }
}

#[test]
fn divergence_exits_3_and_keeps_the_rows() {
    // Linear acceleration is only conditionally stable (Ω ≤ √12): at 1/60 s
    // the axial mode of a stiff rope is far beyond it, so the run diverges.
    let dir = tmp("div");
    let f = dir.join("div.toml");
    std::fs::write(&f, "[simulation]\nduration = 5.0\ndt = 0.016666666666666666\nintegrator = \"linear_acceleration\"\n\n[[body]]\nname = \"p\"\ntype = \"dynamic\"\nshape = \"ball\"\nradius = 0.2\nmass = 100.0\nposition = [0.0, -10.2, 0.0]\n\n[[cable]]\nname = \"stiff\"\nlength = 10.0\nsegments = 20\ndiameter = 0.02\nmaterial = \"steel_wire_rope_6x36_iwrc\"\nstart = { world = [0, 0, 0] }\nend = { body = \"p\", anchor = [0.0, 0.2, 0.0] }\n\n[[probe]]\nname = \"t\"\ncable = \"stiff\"\nquantity = \"tension\"\ns = 0.0\n").unwrap();
    let out = dir.join("out");
    let o = cablesim().arg("run").arg(&f).arg("--out").arg(&out).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{err}");
    assert_eq!(o.status.code(), Some(3));
    assert!(err.contains("stiff") && err.contains("t = "), "{err}");
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert!(csv.lines().count() >= 2, "rows up to the failure are kept");
}

/// A rope laid with its centre on the ground (`rope_on_ground.toml` with
/// the path at y = 0 instead of a radius up) stops at t = 0 with status 3
/// and a message naming the cable, the node, the depth and what to do.
#[test]
fn a_rope_laid_into_the_ground_stops_at_once_naming_the_node() {
    let dir = tmp("inside");
    let f = dir.join("inside.toml");
    let scenario = std::fs::read_to_string("assets/scenarios/rope_on_ground.toml").unwrap();
    let into = scenario.replace("path = [[-5.0, 0.011, 0.0], [5.0, 0.011, 0.0]]", "path = [[-5.0, 0.0, 0.0], [5.0, 0.0, 0.0]]");
    assert_ne!(into, scenario);
    std::fs::write(&f, into).unwrap();
    let o = cablesim().arg("run").arg(&f).arg("--out").arg(dir.join("out")).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{err}");
    assert_eq!(o.status.code(), Some(3));
    assert!(err.contains("cable `rope` failed at t = 0 s: rope 0's node 0 starts 0.0100 m inside a collider"), "{err}");
    assert!(err.contains("at least its radius (0.01 m)"), "{err}");
}

/// A second run into the same folder without `--plot` leaves no stale plot
/// of the first; results.csv holds the second run's rows only.
#[test]
fn a_rerun_removes_the_earlier_runs_files() {
    let out = tmp("rerun");
    let st = cablesim().args(["run", "assets/scenarios/catenary.toml", "--plot", "--quiet", "--out"]).arg(&out).status().unwrap();
    assert_eq!(st.code(), Some(0));
    assert!(out.join("plot.png").exists());
    let first = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let st = cablesim().args(["run", "assets/scenarios/catenary.toml", "--quiet", "--out"]).arg(&out).status().unwrap();
    assert_eq!(st.code(), Some(0));
    assert!(!out.join("plot.png").exists(), "a stale plot.png of the earlier run is left");
    assert_eq!(std::fs::read_to_string(out.join("results.csv")).unwrap(), first, "the same run writes the same rows");
}

/// An output folder that cannot be created (a file is in the way) exits
/// with the documented status 4 and says which path.
#[test]
fn an_output_folder_that_cannot_be_made_exits_4() {
    let dir = tmp("blocked");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a_file");
    std::fs::write(&file, "x").unwrap();
    let o = cablesim().args(["run", "assets/scenarios/catenary.toml", "--quiet", "--out"]).arg(file.join("out")).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert!(err.contains("cannot create") && err.contains("a_file"), "{err}");
}

/// results.csv grows while the run goes: a run killed half-way keeps the
/// rows it made (they used to be written only at the end).
#[test]
fn an_interrupted_run_keeps_its_rows() {
    let out = tmp("interrupted");
    let mut child = cablesim().args(["run", "assets/scenarios/perf_swing_1000.toml", "--quiet", "--out"]).arg(&out).spawn().unwrap();
    let csv = out.join("results.csv");
    let started = std::time::Instant::now();
    let mut rows_seen = 0;
    while started.elapsed().as_secs() < 60 {
        rows_seen = std::fs::read_to_string(&csv).map_or(0, |s| s.lines().count().saturating_sub(1));
        if rows_seen >= 3 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let still_running = child.try_wait().unwrap().is_none();
    child.kill().ok();
    child.wait().ok();
    assert!(still_running, "the run ended before it was interrupted: this check needs a longer scenario");
    assert!(rows_seen >= 3, "no rows on disk while the run was going ({rows_seen})");
    let kept = std::fs::read_to_string(&csv).unwrap();
    assert!(kept.starts_with("time,") && kept.lines().count() > 3, "{kept}");
}

/// A scenario that cannot be read (not UTF-8, missing, a folder) exits with
/// status 2 and a message naming the file and the cause.
#[test]
fn unreadable_scenario_exits_2_naming_file_and_cause() {
    let dir = tmp("unreadable");
    let latin1 = dir.join("latin1.toml");
    std::fs::write(&latin1, b"[simulation]\nduration = 1.0\n# caf\xe9\n").unwrap();
    let folder = dir.join("folder.toml");
    std::fs::create_dir_all(&folder).unwrap();
    let missing = dir.join("missing.toml");
    for (f, cause) in [(&latin1, "valid UTF-8"), (&folder, "directory"), (&missing, "No such file")] {
        for cmd in ["check", "run"] {
            let o = cablesim().arg(cmd).arg(f).output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            println!("{err}");
            assert_eq!(o.status.code(), Some(2), "{cmd} {f:?}");
            assert!(err.contains("cannot read") && err.contains(&*f.to_string_lossy()) && err.contains(cause), "{err}");
        }
    }
}

/// `cablesim view` in a build without the viewer (feature `demo`): exit 2,
/// naming the feature and the command that builds it.
#[cfg(not(feature = "demo"))]
#[test]
fn view_without_the_demo_feature_exits_2_naming_it() {
    let out = cablesim().args(["view", "assets/scenarios/boom_hoist.toml"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("feature `demo`") && stderr.contains("cargo run --release --features demo -- view assets/scenarios/boom_hoist.toml"), "{stderr}");
}

/// `--threads`: three independent hoist pendulums (different lengths,
/// 40 elements each, released at 30°), and the two ropes of
/// `rope_on_rope.toml` (one island: they touch), run on 1 and on 3 threads
/// write the same results.csv, byte for byte.
#[test]
fn threads_give_the_same_results() {
    let dir = tmp("threads");
    let mut src = String::from("[simulation]\nduration = 2.0\ndt = 0.016666666666666666\n");
    for (k, length) in [12.0f64, 16.0, 20.0].into_iter().enumerate() {
        let (z, (s, c)) = (5.0 * k as f64, 30f64.to_radians().sin_cos());
        let end = [length * s, 25.0 - length * c];
        let ball = [end[0] + 0.3 * s, end[1] - 0.3 * c];
        src += &format!(
            "\n[[body]]\nname = \"p{k}\"\ntype = \"dynamic\"\nshape = \"ball\"\nradius = 0.3\nmass = 1000.0\nposition = [{}, {}, {z}]\n\n[[cable]]\nname = \"c{k}\"\nlength = {length}\nsegments = 40\ndiameter = 0.02\nmaterial = \"steel_wire_rope_6x36_iwrc\"\nstart = {{ world = [0, 25, {z}] }}\nend = {{ body = \"p{k}\", anchor = [{}, {}, 0.0] }}\npath = [[0, 25, {z}], [{}, {}, {z}]]\n\n[[probe]]\nname = \"t{k}\"\ncable = \"c{k}\"\nquantity = \"tension\"\ns = 0.0\n\n[[probe]]\nname = \"x{k}\"\nbody = \"p{k}\"\nquantity = \"position\"\n",
            ball[0], ball[1], -0.3 * s, 0.3 * c, end[0], end[1]
        );
    }
    let f = dir.join("three.toml");
    std::fs::write(&f, src).unwrap();
    for file in [f.as_path(), std::path::Path::new("assets/scenarios/rope_on_rope.toml")] {
        let results: Vec<String> = ["1", "3"]
            .iter()
            .map(|n| {
                let out = dir.join(format!("out{n}"));
                let st = cablesim().arg("run").arg(file).args(["--quiet", "--threads", n, "--out"]).arg(&out).status().unwrap();
                assert_eq!(st.code(), Some(0), "{} on {n} threads", file.display());
                std::fs::read_to_string(out.join("results.csv")).unwrap()
            })
            .collect();
        assert!(results[0].lines().count() > 100, "{}", file.display());
        assert!(results[0] == results[1], "{}: 3 threads changed results.csv", file.display());
    }
}
