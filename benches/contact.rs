//! Cost of contact (issue 12), thread CPU time: one 1/60 s step of a free
//! steel rope (20 mm) of N = 100 and 1 000 elements lying on a fixed ground
//! box (every node in contact), with friction (μ = 0.4 on both, what the
//! defaults 0.3 and 0.5 combine to) and frictionless (0 on both), against the same
//! rope with `contacts = false` and no gravity (at rest in the same place,
//! no contact elements; with gravity it would fall for ever). Each is
//! settled for 1 s before timing. `docs/performance.md` reports the ratios
//! and the growth from N = 100 to 1 000. Two and ten separate ropes
//! resting across each other on the ground (one island, stepped as one
//! system) against the same ropes lying apart. A 1 000-element (and a
//! 100-element) rope coiled flat on the ground, its turns apart (ground
//! contacts only) or touching (a pair contact between neighbouring turns),
//! against the same coil without contact. The 1 000-element hoist
//! pendulum in a level of 1 000 fixed or dynamic crates far from it,
//! against the same without crates (and without the rope's contacts).

use bevy_rapier_cable::cable::preset;
use bevy_rapier_cable::scenario;
use bevy_rapier_cable::sim::World;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion};

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

/// Pitch of a coil whose turns do not touch (2.5 diameters: a 30 mm gap).
const SPACED: f64 = 0.05;
/// Pitch of a coil whose neighbouring turns touch (one diameter and 1 mm:
/// 1 mm apart, within the pair contacts' reach).
const TOUCHING: f64 = 0.021;

/// A flat Archimedean spiral `r = 0.5 m + pitch·θ/2π` in the plane
/// y = 0.011 (a 20 mm rope 1 mm above the ground), from the inside out:
/// `n + 1` points 0.05 m of arc apart, and the length of that polyline.
fn coil_path(n: usize, pitch: f64) -> (Vec<[f64; 3]>, f64) {
    let b = pitch / std::f64::consts::TAU;
    let r = |th: f64| 0.5 + b * th;
    let mut path = vec![[r(0.0), 0.011, 0.0]];
    // The arc length integrated (midpoint rule) in steps of 1e-5 rad, each
    // point placed where the arc reaches its multiple of 0.05 m.
    let (dth, mut th, mut s) = (1e-5, 0.0f64, 0.0f64);
    while path.len() < n + 1 {
        let ds = (r(th + 0.5 * dth).powi(2) + b * b).sqrt() * dth;
        let next = 0.05 * path.len() as f64;
        if s + ds >= next {
            let t = th + dth * (next - s) / ds;
            path.push([r(t) * t.cos(), 0.011, r(t) * t.sin()]);
        }
        s += ds;
        th += dth;
    }
    let laid = path.windows(2).map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][2] - w[0][2]).powi(2)).sqrt()).sum();
    (path, laid)
}

/// A rope of `n` elements of 0.05 m coiled flat on a fixed ground box
/// ([`coil_path`]: its coil is its stress-free shape, let go 1 mm above the
/// ground; the defaults' friction, 0.3 on the rope and 0.5 on the ground,
/// μ = 0.4 combined; damping 0.05 s), with contacts, or without contact nor
/// gravity (at rest where it was laid), settled for 1 s.
fn coil_world(n: usize, pitch: f64, contacts: bool) -> World {
    let (path, laid) = coil_path(n, pitch);
    let half = path.iter().map(|p| p[0].hypot(p[2])).fold(0.0, f64::max) + 1.0;
    let points: Vec<String> = path.iter().map(|p| format!("[{}, {}, {}]", p[0], p[1], p[2])).collect();
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
half_extents = [{half}, 0.5, {half}]
position = [0.0, -0.5, 0.0]

[[cable]]
name = "rope"
length = {laid}
segments = {n}
diameter = 0.020
material = "steel_wire_rope_6x36_iwrc"
damping = 0.05
stress_free = true
contacts = {contacts}
path = [{points}]
"#,
        g = if contacts { -9.81 } else { 0.0 },
        points = points.join(", "),
    );
    let w = settled(&src, "coil_bench.toml");
    // The scene is what it says: the ground carries the rope's weight, every
    // node rests on it, at rest; pair contacts between the turns only where
    // they touch (about one per node of the inner of two neighbouring
    // turns: an outer turn's node is farther than its chords).
    let rope = w.rope("rope").unwrap();
    let weight = preset("steel_wire_rope_6x36_iwrc", 0.020).unwrap().linear_density * rope.length() * 9.81;
    let force = rope.contact_force();
    let pairs = w.cable("rope").unwrap().model.chain.pairs().len();
    let lowest = rope.nodes().iter().map(|p| p.y).fold(f64::MAX, f64::min);
    let highest = rope.nodes().iter().map(|p| p.y).fold(f64::MIN, f64::max);
    let fastest = rope.node_velocities().iter().map(|v| v.length()).fold(0.0, f64::max);
    eprintln!("coil, N = {n}, pitch {pitch} m, contacts {contacts}: contact force {force:.3} N (weight {weight:.3} N), {pairs} pair contacts, nodes at y {lowest:.5}..{highest:.5} m, fastest {fastest:.1e} m/s");
    assert!(fastest < 1e-6, "not at rest: {fastest} m/s");
    // On the ground (its top at y = 0) within 0.1 mm; without contact where it was laid.
    let y = if contacts { 0.010 } else { 0.011 };
    assert!((lowest - y).abs() < 1e-4 && (highest - y).abs() < 1e-4, "nodes at y {lowest}..{highest} m");
    if contacts {
        assert!((force - weight).abs() < 1e-3 * weight, "contact force {force} N for a weight of {weight} N");
    } else {
        assert_eq!(force, 0.0);
    }
    if contacts && pitch < SPACED {
        assert!(pairs >= n / 4 && pairs <= 2 * n, "{pairs} pair contacts between touching turns");
    } else {
        assert_eq!(pairs, 0, "pair contacts between turns that do not touch");
    }
    w
}

/// The hoist pendulum of `assets/scenarios/perf_swing_1000.toml` (20 m of
/// 20 mm steel rope in 1 000 elements, a 1 t ball released at 30°; the
/// rope's contacts on or off) in a level of `bodies` crates (1 m cubes,
/// 50 kg when `dynamic`, else fixed) on a ground box, in a 32-wide grid
/// 20 m and more from the rope: colliders the rope never comes near.
fn far_bodies_world(bodies: usize, dynamic: bool, contacts: bool) -> World {
    let pendulum = include_str!("../assets/scenarios/perf_swing_1000.toml");
    let mut src = if contacts { pendulum.to_string() } else { pendulum.replace("[[cable]]\n", "[[cable]]\ncontacts = false\n") };
    src += "\n[[body]]\nname = \"ground\"\ntype = \"fixed\"\nshape = \"cuboid\"\nhalf_extents = [60.0, 0.5, 60.0]\nposition = [0.0, -0.5, 0.0]\n";
    for k in 0..bodies {
        let (x, z) = (-50.0 + (k % 32) as f64 * 3.0, 20.0 + (k / 32) as f64 * 3.0);
        let kind = if dynamic { "dynamic\"\nmass = 50.0" } else { "fixed\"" };
        src += &format!("\n[[body]]\nname = \"crate{k}\"\ntype = \"{kind}\nshape = \"cuboid\"\nhalf_extents = [0.5, 0.5, 0.5]\nposition = [{x}, 0.5, {z}]\n");
    }
    settled(&src, "far_bodies_bench.toml")
}

/// One frame step of the world `make` builds, as the benchmark `id` of
/// `g`; built (and settled) on the benchmark's first run only, so that a
/// filter that skips it skips the settling too.
fn bench_step(g: &mut BenchmarkGroup<'_, cpu_time::ThreadCpuTime>, id: BenchmarkId, make: impl FnOnce() -> World) {
    let mut make = Some(make);
    let mut world = None;
    g.bench_function(id, |b| {
        let w = world.get_or_insert_with(|| make.take().expect("built once")());
        b.iter(|| w.step().unwrap())
    });
}

fn contact(c: &mut Criterion<cpu_time::ThreadCpuTime>) {
    let mut g = c.benchmark_group("contact/ropes_crossing_step");
    for ropes in [2usize, 10] {
        for crossing in [false, true] {
            let id = BenchmarkId::new(if crossing { "crossing" } else { "apart" }, ropes);
            bench_step(&mut g, id, || ropes_world(ropes, crossing));
        }
    }
    g.finish();
    let mut g = c.benchmark_group("contact/rope_on_itself_step");
    for n in [200usize, 1000] {
        for crossings in [0usize, 1, 10] {
            let id = BenchmarkId::new(format!("crossings_{crossings}"), n);
            bench_step(&mut g, id, || crossing_world(n, crossings));
        }
    }
    g.finish();
    let mut g = c.benchmark_group("contact/rope_on_ground_step");
    for n in [100usize, 1000] {
        for (name, contacts) in [("friction", Some(0.4)), ("frictionless", Some(0.0)), ("no_contacts", None)] {
            bench_step(&mut g, BenchmarkId::new(name, n), || world(n, contacts));
        }
    }
    g.finish();
    let mut g = c.benchmark_group("contact/far_bodies_step");
    for (name, bodies, dynamic, contacts) in
        [("none", 0, false, true), ("fixed_1000", 1000, false, true), ("dynamic_1000", 1000, true, true), ("dynamic_1000_no_contacts", 1000, true, false)]
    {
        bench_step(&mut g, BenchmarkId::new(name, 1000), || far_bodies_world(bodies, dynamic, contacts));
    }
    g.finish();
    let mut g = c.benchmark_group("contact/coiled_rope_step");
    for n in [100usize, 1000] {
        for (name, pitch, contacts) in [("spaced", SPACED, true), ("touching", TOUCHING, true), ("no_contacts", SPACED, false)] {
            bench_step(&mut g, BenchmarkId::new(name, n), || coil_world(n, pitch, contacts));
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
