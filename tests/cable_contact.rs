//! Two separate cables touching (issue 12): the contact between a rope of
//! one cable and a rope of another is a pair element between two chains,
//! and the cables that touch are stepped as one implicit system (a
//! `Forest`: each chain's own O(n) solve and one small loop correction
//! over the pairs). Before, a rope passed through every other cable.
#![cfg(feature = "sim")]

use bevy_rapier_cable::scenario;

#[path = "common/scenario_run.rs"]
mod scenario_run;
use scenario_run::{landing, run_scenario, run_shipped_variant};

/// The shipped `rope_on_rope.toml` with the upper rope let go at `height`
/// (m) above the ground. Rows: t, ground force (y), lower y and upper y at
/// the crossing, the two cables' contact forces.
fn rope_on_rope(height: f64) -> Vec<Vec<f64>> {
    run_shipped_variant("rope_on_rope", "[0.0, 0.2, -2.0], [0.0, 0.2, 2.0]", &format!("[0.0, {height}, -2.0], [0.0, {height}, 2.0]"))
}

/// Two steel ropes on the ground, the upper one let go 0.2 m above the
/// lower one and across it: it lands on it and rests there, the
/// centrelines one diameter apart less a Hertz indentation (under
/// 0.2 mm), never closer, and the ground carries both ropes' weight,
/// 2 × 4 m × 1.6 kg/m × g = 125.568 N, to 1e-6 (the upper rope's share at
/// the crossing through the lower one).
#[test]
fn a_rope_rests_on_another_cable() {
    let rows = rope_on_rope(0.2);
    let diameter = 0.020;
    let weight = 2.0 * 4.0 * 1.6 * 9.81;
    let gap = |r: &Vec<f64>| r[3] - r[2];
    let (closest, last_gap, _) = landing(&rows);
    let last = rows.last().unwrap();
    let ground = -last[1];
    // The pair force is in both cables' contact sums, the ground's in one.
    let pair = 0.5 * (last[4] + last[5] - ground);
    eprintln!("rope on rope: final gap {:.6} m, closest {closest:.6} m, ground {ground:.4} N (weight {weight:.4}), pair {pair:.3} N", last_gap);
    assert!(closest > diameter - 2e-4, "the upper rope went into the lower one: centrelines {closest} m apart");
    assert!((last_gap - diameter).abs() < 2e-4, "resting gap {} m", last_gap);
    assert!(((ground - weight) / weight).abs() < 1e-6, "ground force {ground} N against the weight {weight} N");
    assert!(pair > 5.0, "the upper rope should rest on the lower one: pair force {pair} N");
    // Still: no jitter over the last second.
    let late: Vec<f64> = rows.iter().filter(|r| r[0] > 1.0).map(gap).collect();
    let spread = late.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x)) - late.iter().fold(f64::INFINITY, |m, &x| m.min(x));
    assert!(spread < 1e-7, "the resting gap moves by {spread} m over the last second");
}

/// The upper rope let go 1.2 m up strikes the lower one at 4.8 m/s (8 cm
/// per frame step): the contact passes find the contacts between the two
/// cables again as they close, and it never goes through (centrelines
/// never closer than a diameter less 1 mm) and comes to rest on it.
#[test]
fn a_rope_dropped_on_another_cable_at_speed_does_not_pass_through() {
    let rows = rope_on_rope(1.2);
    let diameter = 0.020;
    let (closest, last_gap, speed) = landing(&rows);
    eprintln!("drop: closest {closest:.6} m, final gap {:.6} m, fastest fall {speed:.2} m/s", last_gap);
    assert!(speed > 4.0, "the upper rope should strike fast: {speed} m/s");
    assert!(closest > diameter - 1e-3, "the upper rope went through the lower one: centrelines {closest} m apart");
    assert!((last_gap - diameter).abs() < 2e-4, "resting gap {} m", last_gap);
}

/// The seed paper's example, `cable_impact.toml`: a pendant with a 50 kg
/// hook swings into a taut rope pinned at both ends at about 3.5 m/s,
/// wraps over it and swings back off it. The pendant's points near the
/// crossing never come nearer the span's centreline than a diameter less
/// 1 mm (it hits, and does not pass through); both cables report the same
/// contact force at every frame (action and reaction: one pair element
/// acts on both); from just before the strike on, the energy never grows
/// by more than 1e-3 of itself (contact and rope damping only take it
/// away).
#[test]
fn a_pendant_swinging_into_a_taut_rope_strikes_it_and_does_not_pass_through() {
    let source = std::fs::read_to_string("assets/scenarios/cable_impact.toml").unwrap();
    let sc = scenario::parse(&source, "cable_impact.toml").unwrap_or_else(|e| panic!("{e}"));
    let (_, rows) = run_scenario(sc);
    // Columns: t, span contact, pendant contact, hook xyz, span middle
    // xyz, energy, pendant points at s = 1.8 .. 2.2 (xyz each).
    let diameter = 0.020;
    let mut nearest = f64::INFINITY;
    let mut peak: f64 = 0.0;
    // The energy just before the strike (the span's own start, laid
    // straight and taut, has settled by then).
    let e0 = rows.iter().find(|r| r[0] > 0.8 - 1e-9).unwrap()[9];
    let mut most = e0;
    for r in &rows {
        assert!((r[1] - r[2]).abs() <= 1e-9 * r[1].abs().max(1.0), "t = {}: span {} N, pendant {} N", r[0], r[1], r[2]);
        peak = peak.max(r[1]);
        if r[0] > 0.8 {
            most = most.max(r[9]);
        }
        let (my, mz) = (r[7], r[8]);
        for k in 0..5 {
            let (y, z) = (r[11 + 3 * k], r[12 + 3 * k]);
            // The span runs along x: the distance to its centreline there.
            nearest = nearest.min(((y - my).powi(2) + (z - mz).powi(2)).sqrt());
        }
    }
    eprintln!("cable impact: peak contact {peak:.1} N, nearest {nearest:.6} m, energy {e0:.3} J -> at most {most:.3} J, last {:.3} J", rows.last().unwrap()[9]);
    assert!(peak > 500.0, "the pendant should strike the span: peak contact {peak} N");
    assert!(nearest > diameter - 1e-3, "the pendant went into the span: {nearest} m from its centreline");
    assert!(most < e0 * (1.0 + 1e-3), "the energy grew from {e0} J to {most} J");
}
