//! Cost of contact (issue 12), thread CPU time: one 1/60 s step of a free
//! steel rope (20 mm) of N = 100 and 1 000 elements lying on a fixed ground
//! box (every node in contact), with friction (μ = 0.4 on both, what the
//! defaults 0.3 and 0.5 combine to) and frictionless (0 on both), against the same
//! rope with `contacts = false` and no gravity (at rest in the same place,
//! no contact elements; with gravity it would fall for ever). Each is
//! settled for 1 s before timing. `docs/performance.md` reports the ratios
//! and the growth from N = 100 to 1 000. Two and ten separate ropes
//! resting across each other on the ground (one island, stepped as one
//! system) against the same ropes lying apart.

use bevy_rapier_cable::scenario;
use bevy_rapier_cable::sim::World;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

#[path = "common/cpu_time.rs"]
mod cpu_time;

/// A rope of `n` elements, 0.5 m each, laid 1 mm above a ground box, with
/// contacts (and friction coefficient `mu` on the rope and the ground) or
/// without.
fn world(n: usize, contacts: Option<f64>) -> World {
    let length = 0.5 * n as f64;
    let src = format!(
        r#"
[simulation]
duration = 1000.0
dt = 0.016666666666666666
gravity = [0.0, {g}, 0.0]

[[body]]
name = "ground"
type = "fixed"
shape = "cuboid"
half_extents = [{half}, 0.5, 5.0]
position = [0.0, -0.5, 0.0]
friction = {mu}

[[cable]]
name = "rope"
length = {length}
segments = {n}
diameter = 0.020
material = "steel_wire_rope_6x36_iwrc"
contacts = {on}
friction = {mu}
path = [[{x0}, 0.011, 0.0], [{x1}, 0.011, 0.0]]
"#,
        g = if contacts.is_some() { -9.81 } else { 0.0 },
        on = contacts.is_some(),
        mu = contacts.unwrap_or(0.0),
        half = 0.5 * length + 5.0,
        x0 = -0.5 * length,
        x1 = 0.5 * length,
    );
    settled(&src, "contact_bench.toml")
}

/// The scenario `src` (named `name`) run for 1 s (60 frame steps).
fn settled(src: &str, name: &str) -> World {
    let sc = scenario::parse(src, name).unwrap();
    let mut w = World::new(sc).unwrap();
    for _ in 0..60 {
        w.step().unwrap();
    }
    w
}

/// A rope lying on the ground whose last part comes back across its own
/// first straight `crossings` times (a zig-zag 0.1 m elements, moulded
/// stress-free, let go 1 mm above touching), with `n` elements in all:
/// `crossings` pair contacts at rest (rope on itself), settled for 1 s.
fn crossing_world(n: usize, crossings: usize) -> World {
    let length = 0.1 * n as f64;
    // The zig-zag: legs from z = +0.5 to z = −0.5 and back, each crossing
    // the straight at z = 0; the straight takes the rest of the length.
    let leg = |dx: f64| (dx * dx + 1.0f64).sqrt();
    let span = 4.0f64.max(0.4 * crossings as f64);
    let dx = span / crossings.max(1) as f64;
    let zig = if crossings > 0 { 0.5 + crossings as f64 * leg(dx) } else { 0.0 };
    let straight = length - zig - 0.05;
    let mut path = vec![[-straight + span * 0.5, 0.011, 0.0], [span * 0.5, 0.011, 0.0]];
    if crossings > 0 {
        path.push([span * 0.5, 0.032, 0.5]);
        for k in 0..crossings {
            let z = if k % 2 == 0 { -0.5 } else { 0.5 };
            path.push([span * 0.5 - (k + 1) as f64 * dx, 0.032, z]);
        }
    }
    let points: Vec<String> = path.iter().map(|p| format!("[{}, {}, {}]", p[0], p[1], p[2])).collect();
    let laid: f64 = path.windows(2).map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2) + (w[1][2] - w[0][2]).powi(2)).sqrt()).sum();
    let src = format!(
        r#"{ground}
[[cable]]
name = "rope"
length = {laid}
segments = {n}
diameter = 0.020
material = "steel_wire_rope_6x36_iwrc"
damping = 0.05
stress_free = true
friction = 0.0
path = [{points}]
"#,
        ground = frictionless_ground(length + 10.0, 5.0),
        points = points.join(", "),
    );
    let w = settled(&src, "crossing_bench.toml");
    // The scene is what it says: a pair contact at each crossing (a
    // crossing holds up to four where it falls near a node: two elements
    // on each side).
    let pairs = w.cable("rope").unwrap().model.chain.pairs().len();
    eprintln!("rope on itself, N = {n}, {crossings} crossings: {pairs} pair contacts");
    assert!(pairs >= crossings && pairs <= 4 * crossings, "{pairs} pair contacts for {crossings} crossings");
    w
}

/// A scenario's head: a long run at the frame step, and a frictionless
/// fixed ground box (its top at y = 0) of half extents `x` and `z` (m).
fn frictionless_ground(x: f64, z: f64) -> String {
    format!(
        r#"
[simulation]
duration = 1000.0
dt = 0.016666666666666666

[[body]]
name = "ground"
type = "fixed"
shape = "cuboid"
half_extents = [{x}, 0.5, {z}]
position = [0.0, -0.5, 0.0]
friction = 0.0
"#
    )
}

/// `ropes` separate 4 m ropes (0.1 m elements) on a frictionless ground
/// box: half along x, 0.5 m apart, the other half along z across them,
/// let go 1 mm above touching (`crossing`) or laid on the ground beside
/// the first half, touching nothing (`false`); settled for 1 s. Crossing,
/// the ropes rest on each other at `(ropes/2)²` crossings, all the cables
/// one island stepped as one system.
fn ropes_world(ropes: usize, crossing: bool) -> World {
    let half = ropes / 2;
    let mut src = frictionless_ground(20.0, 20.0);
    let offset = |k: usize| (k as f64 - 0.5 * (half as f64 - 1.0)) * 0.5;
    for k in 0..ropes {
        let path = if k < half {
            let z = offset(k);
            format!("[[-2.0, 0.011, {z}], [2.0, 0.011, {z}]]")
        } else if crossing {
            let x = offset(k - half);
            format!("[[{x}, 0.032, -2.0], [{x}, 0.032, 2.0]]")
        } else {
            let x = offset(k - half);
            format!("[[{x}, 0.011, 3.0], [{x}, 0.011, 7.0]]")
        };
        src.push_str(&format!(
            r#"
[[cable]]
name = "rope{k}"
length = 4.0
segments = 40
diameter = 0.020
material = "steel_wire_rope_6x36_iwrc"
damping = 0.05
friction = 0.0
path = {path}
"#
        ));
    }
    settled(&src, "ropes_bench.toml")
}

fn contact(c: &mut Criterion<cpu_time::ThreadCpuTime>) {
    let mut g = c.benchmark_group("contact/ropes_crossing_step");
    for ropes in [2usize, 10] {
        for crossing in [false, true] {
            let mut w = ropes_world(ropes, crossing);
            let id = BenchmarkId::new(if crossing { "crossing" } else { "apart" }, ropes);
            g.bench_function(id, |b| b.iter(|| w.step().unwrap()));
        }
    }
    g.finish();
    let mut g = c.benchmark_group("contact/rope_on_itself_step");
    for n in [200usize, 1000] {
        for crossings in [0usize, 1, 10] {
            let mut w = crossing_world(n, crossings);
            let id = BenchmarkId::new(format!("crossings_{crossings}"), n);
            g.bench_function(id, |b| b.iter(|| w.step().unwrap()));
        }
    }
    g.finish();
    let mut g = c.benchmark_group("contact/rope_on_ground_step");
    for n in [100usize, 1000] {
        for (name, contacts) in [("friction", Some(0.4)), ("frictionless", Some(0.0)), ("no_contacts", None)] {
            let mut w = world(n, contacts);
            let id = BenchmarkId::new(name, n);
            g.bench_function(id, |b| b.iter(|| w.step().unwrap()));
        }
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(cpu_time::ThreadCpuTime).sample_size(20);
    targets = contact
}
criterion_main!(benches);
