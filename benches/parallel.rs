//! Independent ropes stepped in parallel (issue 14): `ropes` separate hoist
//! pendulums (20 m of 20 mm steel rope, EA 2e7 N, EI 50 N·m², 1.6 kg/m,
//! `n` elements each, a 1 t ball released at 30°, each on its own fixed
//! jib, 5 m apart), one 1/60 s frame step of `sim::World`, with the
//! cables' solves spread over 1 or 2 threads (`World::set_threads`,
//! `coupling::Threads`). Wall time (the point is the other core), median
//! of 10 samples. Before timing, the same scene run 1 s on 1 and on 2
//! threads is checked to give the same bits. `docs/performance.md`
//! reports the speed-ups for 2 and 16 ropes.

use bevy_rapier_cable::scenario;
use bevy_rapier_cable::sim::World;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

/// `ropes` hoist pendulums of `n` elements each, as a scenario.
fn scene(ropes: usize, n: usize) -> String {
    let mut src = String::from("[simulation]\nduration = 1000.0\ndt = 0.016666666666666666\n");
    for k in 0..ropes {
        let z = 5.0 * k as f64;
        src += &format!(
            r#"
[[body]]
name = "jib{k}"
type = "fixed"
shape = "cuboid"
half_extents = [0.5, 0.2, 0.2]
position = [0.0, 25.0, {z}]

[[body]]
name = "payload{k}"
type = "dynamic"
shape = "ball"
radius = 0.3
mass = 1000.0
position = [10.15, 7.219684, {z}]

[[cable]]
name = "hoist{k}"
length = 20.0
segments = {n}
diameter = 0.020
material = "steel_wire_rope_6x36_iwrc"
linear_density = 1.6
ea = 2.0e7
ei = 50.0
gj = 35.0
start = {{ body = "jib{k}", anchor = [0.0, -0.2, 0.0] }}
end = {{ body = "payload{k}", anchor = [-0.15, 0.259808, 0.0] }}
path = [[0.0, 24.8, {z}], [10.0, 7.479492, {z}]]
"#
        );
    }
    src
}

/// The scene on `threads` threads, run 0.5 s (30 frames) so the swing is
/// under way.
fn world(ropes: usize, n: usize, threads: usize) -> World {
    let sc = scenario::parse(&scene(ropes, n), "parallel_bench.toml").unwrap();
    let mut w = World::new(sc).unwrap();
    w.set_threads(threads);
    for _ in 0..30 {
        w.step().unwrap();
    }
    w
}

/// Every cable's coordinates and velocities, as bits.
fn bits(w: &World) -> Vec<u64> {
    w.cable_names().iter().filter_map(|name| w.cable(name)).flat_map(|c| c.state.q.iter().chain(&c.state.v).map(|x| x.to_bits()).collect::<Vec<_>>()).collect()
}

fn parallel(c: &mut Criterion) {
    let mut g = c.benchmark_group("parallel");
    g.sample_size(10);
    for (ropes, n) in [(2, 100), (2, 1000), (16, 100), (16, 1000)] {
        let (mut one, mut two) = (world(ropes, n, 1), world(ropes, n, 2));
        for _ in 0..30 {
            one.step().unwrap();
            two.step().unwrap();
        }
        assert_eq!(bits(&one), bits(&two), "{ropes} ropes of N = {n}: 2 threads changed the results");
        for threads in [1, 2] {
            let mut w = world(ropes, n, threads);
            g.bench_with_input(BenchmarkId::new(format!("{ropes}x{n}"), threads), &threads, |b, _| b.iter(|| w.step().unwrap()));
        }
    }
    g.finish();
}

criterion_group!(benches, parallel);
criterion_main!(benches);
