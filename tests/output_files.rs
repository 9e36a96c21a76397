//! Result files: results.csv, summary.json, plot.png.

use std::path::PathBuf;

use bevy_rapier_cable::output::{OutputError, Recorder};

fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("output_files").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn cols(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

/// A recorder with a scalar, a vector, a constant and a column with NaN.
fn sample() -> Recorder {
    let mut r = Recorder::new(cols(&["tension", "hook.x", "hook.y", "hook.z", "const", "gappy"]));
    for i in 0..50 {
        let t = i as f64 * 0.1;
        let gap = if (20..25).contains(&i) || i == 30 { f64::NAN } else { t * t };
        r.push_row(t, &[1000.0 + 10.0 * t, t.sin(), -5.0 + t.cos(), 0.1 * t, 3.0, gap]).unwrap();
    }
    r
}

/// Width and height from a PNG's IHDR, after checking signature and IEND.
fn png_size(path: &std::path::Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert!(bytes.len() > 1000, "{} is only {} bytes", path.display(), bytes.len());
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    assert_eq!(&bytes[12..16], b"IHDR");
    assert_eq!(&bytes[bytes.len() - 8..bytes.len() - 4], b"IEND");
    let be = |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    (be(16), be(20))
}

#[test]
fn csv_has_header_and_rows() {
    let d = dir("csv");
    let mut r = Recorder::new(cols(&["a", "v.x", "v.y", "v.z"]));
    r.push_row(0.0, &[1.5, 0.0, -2.0, 3.25]).unwrap();
    r.push_row(0.05, &[2.0, f64::NAN, 1e-9, -0.0]).unwrap();
    let path = d.join("results.csv");
    r.write_csv(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines, ["time,a,v.x,v.y,v.z", "0,1.5,0,-2,3.25", "0.05,2,NaN,0.000000001,-0"]);
    // Round trip of the numbers.
    let back: Vec<f64> = lines[2].split(',').skip(2).map(|s| s.parse().unwrap()).collect();
    assert!(back[0].is_nan() && back[1] == 1e-9);
}

#[test]
fn push_row_checks_the_length() {
    let mut r = Recorder::new(cols(&["a", "b"]));
    let e = r.push_row(0.0, &[1.0]).unwrap_err();
    assert!(matches!(e, OutputError::RowLength { expected: 2, found: 1 }));
    assert!(r.is_empty());
}

#[test]
fn summary_numbers() {
    let d = dir("summary");
    let r = sample();
    let path = d.join("summary.json");
    r.write_summary(&path, 3000, 5.0, 2.0).unwrap();
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(v["steps"], 3000);
    assert_eq!((v["simulated_s"].as_f64(), v["wall_s"].as_f64()), (Some(5.0), Some(2.0)));
    assert_eq!(v["real_time_factor"].as_f64(), Some(2.5));
    let p = &v["probes"];
    assert_eq!(p.as_object().unwrap().len(), 6);
    let t = &p["tension"];
    assert_eq!(t["min"].as_f64(), Some(1000.0));
    approx::assert_relative_eq!(t["max"].as_f64().unwrap(), 1049.0, epsilon = 1e-9);
    approx::assert_relative_eq!(t["mean"].as_f64().unwrap(), 1024.5, epsilon = 1e-9);
    approx::assert_relative_eq!(t["final"].as_f64().unwrap(), 1049.0, epsilon = 1e-9);
    let c = &p["const"];
    assert_eq!((c["min"].as_f64(), c["max"].as_f64(), c["mean"].as_f64()), (Some(3.0), Some(3.0), Some(3.0)));
    // NaN values are skipped in min/max/mean.
    let g = &p["gappy"];
    assert_eq!(g["min"].as_f64(), Some(0.0));
    approx::assert_relative_eq!(g["max"].as_f64().unwrap(), 4.9 * 4.9, epsilon = 1e-9);
    let finite: Vec<f64> = r.series(5).map(|(_, v)| v).filter(|v| v.is_finite()).collect();
    approx::assert_relative_eq!(g["mean"].as_f64().unwrap(), finite.iter().sum::<f64>() / finite.len() as f64);
    assert_eq!(finite.len(), 44);
    let st = r.stats(1);
    approx::assert_relative_eq!(st.last, 4.9f64.sin());
}

#[test]
fn summary_of_non_finite_values_is_null() {
    let d = dir("summary_nan");
    let mut r = Recorder::new(cols(&["bad"]));
    r.push_row(0.0, &[f64::NAN]).unwrap();
    let path = d.join("summary.json");
    r.write_summary(&path, 1, 0.01, 0.0).unwrap();
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert!(v["probes"]["bad"]["min"].is_null() && v["probes"]["bad"]["final"].is_null());
    assert!(v["real_time_factor"].is_null(), "division by zero wall time gives null");
}

#[test]
fn plot_is_a_png() {
    let d = dir("plot");
    let r = sample();
    let panels = r.default_panels();
    assert_eq!(
        panels,
        vec![("tension".to_string(), vec![0]), ("hook".to_string(), vec![1, 2, 3]), ("const".to_string(), vec![4]), ("gappy".to_string(), vec![5]),]
    );
    let path = d.join("plot.png");
    r.write_plot(&path, &panels).unwrap();
    assert_eq!(png_size(&path), (900, 1200));
}

#[test]
fn plot_edge_cases() {
    let d = dir("plot_edges");
    // One row.
    let mut one = Recorder::new(cols(&["a", "v.x", "v.y", "v.z"]));
    one.push_row(0.0, &[1.0, 0.0, 0.0, 0.0]).unwrap();
    let path = d.join("one.png");
    one.write_plot(&path, &one.default_panels()).unwrap();
    png_size(&path);
    // All NaN, infinities and a constant.
    let mut bad = Recorder::new(cols(&["nan", "inf", "zero"]));
    for i in 0..5 {
        bad.push_row(i as f64, &[f64::NAN, if i == 2 { f64::INFINITY } else { 1.0 }, 0.0]).unwrap();
    }
    let path = d.join("bad.png");
    bad.write_plot(&path, &[("nan", vec![0]), ("inf", vec![1]), ("zero", vec![2])]).unwrap();
    assert_eq!(png_size(&path), (900, 900));
    // No rows, no panels.
    let empty = Recorder::new(Vec::new());
    let path = d.join("empty.png");
    empty.write_plot::<&str>(&path, &[]).unwrap();
    png_size(&path);
    // Many panels go into two columns.
    let mut many = Recorder::new((0..6).map(|i| format!("p{i}")).collect());
    many.push_row(0.0, &[0.0; 6]).unwrap();
    many.push_row(1.0, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]).unwrap();
    let path = d.join("many.png");
    many.write_plot(&path, &many.default_panels()).unwrap();
    assert_eq!(png_size(&path), (1800, 900));
}

#[test]
fn errors_name_the_path() {
    let d = dir("errors");
    let r = sample();
    let missing = d.join("no_such_dir").join("results.csv");
    let e = r.write_csv(&missing).unwrap_err();
    assert!(e.to_string().contains("no_such_dir"), "{e}");
    let e = r.write_summary(&d.join("no_such_dir/summary.json"), 1, 1.0, 1.0).unwrap_err();
    assert!(matches!(e, OutputError::Io { .. }) && e.to_string().contains("summary.json"), "{e}");
    let e = r.write_plot(&d.join("no_such_dir/plot.png"), &r.default_panels()).unwrap_err();
    assert!(e.to_string().contains("plot.png"), "{e}");
    let e = r.write_plot(&d.join("plot.png"), &[("x", vec![99])]).unwrap_err();
    assert!(matches!(e, OutputError::Column { index: 99, columns: 6, .. }), "{e}");
}
