//! Runs a scenario in `cablesim`'s world, frame by frame.

use bevy_rapier_cable::scenario::Scenario;
use bevy_rapier_cable::sim::World;

/// Runs `sc` over its whole duration; rows are `[time, probes...]`, one
/// per frame.
pub fn run_scenario(sc: Scenario) -> (World, Vec<Vec<f64>>) {
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

/// The shipped scenario `assets/scenarios/<name>.toml` with the text
/// `from` replaced by `to` (a test's variant of it; `from` must be in the
/// file), run over its whole duration: its rows.
#[allow(dead_code)]
pub fn run_shipped_variant(name: &str, from: &str, to: &str) -> Vec<Vec<f64>> {
    let shipped = std::fs::read_to_string(format!("assets/scenarios/{name}.toml")).unwrap();
    assert!(shipped.contains(from), "`{from}` is not in {name}.toml any more: update the test");
    let source = shipped.replace(from, to);
    let sc = bevy_rapier_cable::scenario::parse(&source, &format!("{name}.toml")).unwrap_or_else(|e| panic!("{e}"));
    run_scenario(sc).1
}

/// A rope landing across another (or across itself), from rows whose
/// columns 2 and 3 are the heights (m) of the lower and the upper rope at
/// the crossing: the closest the two centrelines came (m), their distance
/// at the last row (m), and the upper rope's fastest fall (m/s).
#[allow(dead_code)]
pub fn landing(rows: &[Vec<f64>]) -> (f64, f64, f64) {
    let gap = |r: &Vec<f64>| r[3] - r[2];
    let closest = rows.iter().map(gap).fold(f64::INFINITY, f64::min);
    let speed = rows.windows(2).map(|w| (w[0][3] - w[1][3]) / (w[1][0] - w[0][0])).fold(0.0f64, f64::max);
    (closest, rows.last().map_or(f64::NAN, gap), speed)
}
