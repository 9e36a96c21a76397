//! A rope touching itself (issue 12): the contacts between two elements
//! of one cable are pair elements inside the cable's implicit solve, their
//! loop coupling solved exactly (`Chain::pairs`, a Woodbury correction
//! over the pairs after the O(n) sweep). Without them the rope passed
//! through itself.
#![cfg(feature = "sim")]

#[path = "common/scenario_run.rs"]
mod scenario_run;
use scenario_run::{landing, run_shipped_variant};

/// The shipped `rope_crossing.toml` (a 20 mm steel rope on the ground,
/// moulded into a path that comes back across its own first straight)
/// with the upper pass let go at `height` (m) above the ground: the
/// crossing at x = 0 is at arc length 2 m (lower) and 9.01 m (upper).
/// Rows: t, total contact force with the ground (N), lower y, upper y (m),
/// every frame for 2 s.
fn crossing(height: f64) -> Vec<Vec<f64>> {
    run_shipped_variant("rope_crossing", "[0.0, 0.2, 1.5], [0.0, 0.2, -1.5]", &format!("[0.0, {height}, 1.5], [0.0, {height}, -1.5]"))
}

/// The rope's upper pass, let go 0.2 m above the ground, lands on its own
/// lower pass and rests on it: at the crossing the two centrelines end one
/// rope diameter apart less a Hertz indentation (under 0.2 mm), never
/// closer than that while it lands, and the ground carries the whole
/// rope's weight (10.52 m × 1.6 kg/m × g) to 1e-6, the upper pass's share
/// through the lower one. Before the pair contacts it fell through to the
/// ground.
#[test]
fn a_rope_crossing_itself_rests_on_itself() {
    let rows = crossing(0.2);
    let diameter = 0.020;
    let weight = 10.52 * 1.6 * 9.81;
    let gap = |r: &Vec<f64>| r[3] - r[2];
    let (closest, last_gap, _) = landing(&rows);
    let last = rows.last().unwrap();
    eprintln!("crossing: final gap {:.6} m, closest {closest:.6} m, ground {:.3} N (weight {weight:.3})", gap(last), last[1]);
    assert!(closest > diameter - 2e-4, "the upper pass went into the lower one: centrelines {closest} m apart");
    assert!((last_gap - diameter).abs() < 2e-4, "resting gap {} m", last_gap);
    assert!(((last[1] - weight) / weight).abs() < 1e-6, "ground force {} N against the weight {weight} N", last[1]);
}

/// The same upper pass let go 1.2 m up strikes the lower one at 4.8 m/s,
/// 8 cm per frame step: the contact passes find the pair contacts again
/// as it closes, and it never goes through (the centrelines never closer
/// than a diameter less 1 mm) and comes to rest on it.
#[test]
fn a_rope_dropped_on_itself_at_speed_does_not_pass_through() {
    let rows = crossing(1.2);
    let diameter = 0.020;
    let (closest, last_gap, speed) = landing(&rows);
    eprintln!("drop: closest {closest:.6} m, final gap {:.6} m, fastest fall {speed:.2} m/s", last_gap);
    assert!(speed > 4.0, "the upper pass should strike fast: {speed} m/s");
    assert!(closest > diameter - 1e-3, "the upper pass went through the lower one: centrelines {closest} m apart");
    assert!((last_gap - diameter).abs() < 2e-4, "resting gap {} m", last_gap);
}
