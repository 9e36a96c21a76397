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
