//! Two separate cables touching (issue 12): the contact between a rope of
//! one cable and a rope of another is a pair element between two chains,
//! and the cables that touch are stepped as one implicit system (a
//! `Forest`: each chain's own O(n) solve and one small loop correction
//! over the pairs). Before, a rope passed through every other cable.
#![cfg(feature = "sim")]

use bevy_rapier_cable::scenario;
use glam::DVec3;

#[path = "common/scenario_run.rs"]
mod scenario_run;
use scenario_run::{landing, run_scenario, run_shipped_variant, segment_distance};

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

/// The closest two centrelines (polylines through the nodes) come: the
/// smallest distance between any element of `a` and any element of `b`
/// (segment–segment, exact), m.
fn closest_between(a: &[DVec3], b: &[DVec3]) -> f64 {
    let mut m = f64::INFINITY;
    for x in a.windows(2) {
        for y in b.windows(2) {
            m = m.min(segment_distance(x[0], x[1], y[0], y[1]));
        }
    }
    m
}

/// Two ropes crossing at speed, in the air: a free 4 m rope of 20 mm
/// steel (N = 40), laid level 46 m above a taut rope of the same kind
/// pinned 4 m apart (laid 0.1 % short), across it at 60° and 0.7 m off
/// its middle, falls onto it and strikes it at 30 m/s (0.5 m per frame
/// step, 25 diameters: the contact passes find the pair contacts between
/// the two cables again as they close). At every frame the two
/// centrelines (exact segment distances over all elements) stay at least
/// a diameter apart less 0.2 mm (a Hertz indentation at the kilonewtons
/// of such a strike is tens of µm), and the falling rope ends above the
/// taut one: it never passes through (with `contacts = false` it passes
/// through between two frames, and only the last check sees it).
#[test]
fn a_rope_falling_across_a_taut_rope_at_30_m_s_does_not_pass_through_it() {
    let source = r#"
[simulation]
duration = 3.66
dt = 0.016666666666666666

[[cable]]
name = "lower"
length = 3.996
segments = 40
diameter = 0.020
material = "steel_wire_rope_6x36_iwrc"
damping = 0.01
start = { world = [-2.0, 1.0, 0.0] }
end = { world = [2.0, 1.0, 0.0] }

[[cable]]
name = "upper"
length = 4.0
segments = 40
diameter = 0.020
material = "steel_wire_rope_6x36_iwrc"
damping = 0.01
path = [[-0.3, 47.0, -1.7320508075688772], [1.7, 47.0, 1.7320508075688772]]
"#;
    let sc = scenario::parse(source, "crossing_at_speed.toml").unwrap_or_else(|e| panic!("{e}"));
    let frames = (sc.simulation.duration / sc.simulation.dt).round() as usize;
    let mut world = bevy_rapier_cable::sim::World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let diameter = 0.020;
    let (mut closest, mut fastest, mut struck) = (f64::INFINITY, 0.0f64, false);
    for _ in 0..frames {
        world.step().unwrap_or_else(|e| panic!("{e}"));
        let lower = world.cable("lower").unwrap().nodes();
        let upper = world.cable("upper").unwrap();
        let d = closest_between(&lower, &upper.nodes());
        if !struck {
            fastest = fastest.max(upper.node_velocities().iter().map(|v| -v.y).fold(0.0, f64::max));
        }
        struck |= d < diameter + 0.05;
        closest = closest.min(d);
    }
    let lower_mid = world.cable("lower").unwrap().nodes()[20];
    let upper_min = world.cable("upper").unwrap().nodes().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    eprintln!("crossing at speed: fastest fall {fastest:.2} m/s, closest {closest:.6} m, lower middle y {:.4} m, upper lowest y {upper_min:.4} m", lower_mid.y);
    assert!(fastest > 29.0, "the rope should strike at 30 m/s: {fastest} m/s");
    assert!(closest > diameter - 2e-4, "the ropes went into each other: centrelines {closest} m apart");
    assert!(upper_min > lower_mid.y - 0.05, "the falling rope ended below the taut one: {upper_min} m against {} m", lower_mid.y);
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

/// A rope lying across two rails on a slope: two 20 mm steel ropes 12 m
/// long pinned at both ends along the fall line of a frictionless fixed
/// slope (0.6 m apart, resting on it), and a free 1.2 m rope of the same
/// kind let go 1 mm above them, across them (horizontal). Rope-on-rope
/// friction `mu` on all three cables (combined as rapier's `Average`:
/// `mu`). Rows: t, then the free rope's middle (x, y, z).
fn rope_on_rails(degrees: f64, mu: f64) -> Vec<Vec<f64>> {
    let t = degrees.to_radians();
    // Slope frame: d up the fall line, n out of the face.
    let (d, n) = ([t.cos(), t.sin()], [-t.sin(), t.cos()]);
    let at = |along: f64, up: f64| [along * d[0] + up * n[0], along * d[1] + up * n[1]];
    let r = 0.010;
    let rail = |z: f64| {
        let (a, b) = (at(-6.0, r), at(6.0, r));
        format!(
            "[[cable]]\nname = \"rail{z}\"\nlength = 12.0\nsegments = 120\ndiameter = 0.020\nmaterial = \"steel_wire_rope_6x36_iwrc\"\ndamping = 0.01\nfriction = {mu}\nstart = {{ world = [{}, {}, {z}] }}\nend = {{ world = [{}, {}, {z}] }}\npath = [[{}, {}, {z}], [{}, {}, {z}]]\n\n",
            a[0], a[1], b[0], b[1], a[0], a[1], b[0], b[1]
        )
    };
    let top = at(0.0, 3.0 * r + 0.001);
    let source = format!(
        r#"[simulation]
duration = 2.0
dt = 0.016666666666666666

[[body]]
name = "slope"
type = "fixed"
shape = "cuboid"
half_extents = [20.0, 0.5, 5.0]
position = [{px}, {py}, 0.0]
rotation = [0.0, 0.0, {degrees}]
friction = 0.0

{rails}[[cable]]
name = "bar"
length = 1.2
segments = 24
diameter = 0.020
material = "steel_wire_rope_6x36_iwrc"
damping = 0.01
friction = {mu}
path = [[{x}, {y}, -0.6], [{x}, {y}, 0.6]]

[[probe]]
name = "middle"
cable = "bar"
quantity = "position"
s = 0.6
"#,
        px = -0.5 * n[0],
        py = -0.5 * n[1],
        rails = rail(-0.3) + &rail(0.3),
        x = top[0],
        y = top[1],
    );
    let sc = scenario::parse(&source, "rails.toml").unwrap_or_else(|e| panic!("{e}"));
    run_scenario(sc).1
}

/// Coulomb friction between ropes of separate cables (issue 12): a rope
/// lying across two rails (ropes pinned on a frictionless slope, see
/// `rope_on_rails`), rope-on-rope μ = 0.3 (friction angle 16.70°).
/// * At 10° it lands and sticks: after 1 s its middle moves less than
///   0.1 µm in a second, more slowly as time goes (the pinned rails
///   settling under the load, not creep).
/// * At 25° it slides down the rails at Coulomb's rate
///   `a = g (sin θ − μ cos θ)` = 1.478621 m/s² (its friction acts at its
///   centreline: it slides, it does not roll), measured from the
///   distances at 0.5, 1 and 1.5 s; frictionless it slides at `g sin θ`.
#[test]
fn a_rope_across_two_rails_sticks_below_the_friction_angle_and_slides_at_coulombs_rate_above() {
    let g = 9.81;
    let distance = |rows: &[Vec<f64>], k: usize| {
        let (a, b) = (&rows[0], &rows[k]);
        ((b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2) + (b[3] - a[3]).powi(2)).sqrt()
    };
    let rows = rope_on_rails(10.0, 0.3);
    let late = &rows[59..];
    let moved = (0..late.len()).map(|k| distance(late, k)).fold(0.0f64, f64::max);
    let (first, second) = (distance(&rows[59..], 30), distance(&rows[89..], 30));
    eprintln!("10°: slid {:.3e} m while landing, then moved {moved:e} m in 1 s ({first:e} m, then {second:e} m per half second)", distance(&rows, 59));
    assert!(moved < 1e-7, "10°, μ 0.3: the rope crept {moved} m along the rails");
    assert!(second < first, "10°, μ 0.3: creeping, not settling: {first} m then {second} m per half second");
    for (degrees, mu) in [(25.0, 0.3), (25.0, 0.0)] {
        let rows = rope_on_rails(degrees, mu);
        let s = |k: usize| distance(&rows, k);
        let dt = 0.5;
        let a = (s(89) - 2.0 * s(59) + s(29)) / (dt * dt);
        let th = f64::to_radians(degrees);
        let expected = g * (th.sin() - mu * th.cos());
        eprintln!("{degrees}°, μ {mu}: a = {a:.6} m/s² vs {expected:.6} ({:+.2e}); slid {:.3} m in 1.5 s", a / expected - 1.0, s(89));
        assert!((a / expected - 1.0).abs() < 2e-3, "{degrees}°, μ {mu}: a = {a} m/s² vs {expected}");
    }
}

/// `assets/scenarios/slack_rope_on_ground.toml`: a newcomer's slack rope
/// between two points 3 m up and 10 m apart (12 m of 16 mm steel rope, laid
/// as a horizontal parabola) swings down, grazes the ground at the bottom of
/// its first swings, and comes to rest as the catenary, with its ends on
/// soft anchors (`end_stiffness = 2`). It runs to the end; the energy never
/// grows (1e-9 of it: the rounding of the sum); the middle never sinks
/// into the ground by more than 1 mm; over the last second the middle's
/// height is the catenary's (sag `a (cosh(S/2a) − 1)`, `L = 2a sinh(S/2a)`)
/// and the first element's tension the catenary's `w a cosh(S/2a)` less
/// the weight of the rope's rise to that element's middle (`w Δy`), each
/// within 1 %. (With the default anchor, 1000 `EA/L_e`, it stopped at
/// 0.95 s, "Newton did not converge", until a failed contact pass was
/// taken again with its contacts found more often; it now runs there too,
/// at 39 Newton iterations per step against 16.)
#[test]
fn a_slack_rope_between_two_pins_swings_down_grazes_the_ground_and_hangs_as_the_catenary() {
    let rows = run_shipped_variant("slack_rope_on_ground", "end_stiffness = 2.0", "end_stiffness = 2.0");
    assert!((rows.last().unwrap()[0] - 12.0).abs() < 1e-9, "ran to {} s", rows.last().unwrap()[0]);
    let e0 = rows[0][1];
    let rise = rows.windows(2).map(|w| w[1][1] - w[0][1]).fold(f64::NEG_INFINITY, f64::max);
    let lowest = rows.iter().map(|r| r[4]).fold(f64::INFINITY, f64::min);
    // The catenary: L = 2a sinh(S/2a) for a by bisection.
    let (l, span, w, top) = (12.0f64, 10.0f64, 0.004 * 16.0 * 16.0 * 9.81, 3.0);
    let (mut lo, mut hi) = (0.5f64, 100.0f64);
    for _ in 0..200 {
        let a = 0.5 * (lo + hi);
        if 2.0 * a * (0.5 * span / a).sinh() > l {
            lo = a;
        } else {
            hi = a;
        }
    }
    let a = lo;
    let sag = a * ((0.5 * span / a).cosh() - 1.0);
    // The first element's middle, 0.125 m along the rope from the pin:
    // the catenary's slope there is close to the pin's, sinh(S/2a).
    let slope = (0.5 * span / a).sinh();
    let dy = 0.125 * slope / (1.0 + slope * slope).sqrt();
    let t_first = w * a * (0.5 * span / a).cosh() - w * dy;
    let late: Vec<&Vec<f64>> = rows.iter().filter(|r| r[0] > 11.0).collect();
    let mean = |k: usize| late.iter().map(|r| r[k]).sum::<f64>() / late.len() as f64;
    let (sag_sim, t_sim) = (top - mean(4), mean(2));
    eprintln!(
        "energy {e0:.2} J at the first step, largest rise per step {rise:.2e} J; lowest middle {lowest:.5} m; last second: sag {sag_sim:.4} m (catenary {sag:.4}), first element's tension {t_sim:.2} N ({t_first:.2})"
    );
    assert!(rise <= 1e-9 * e0, "the energy grew by {rise} J in a step");
    assert!(lowest > 0.008 - 1e-3, "the rope's middle sank into the ground: {lowest} m");
    assert!((sag_sim - sag).abs() < 1e-2 * sag, "sag {sag_sim} m, catenary {sag} m");
    assert!((t_sim - t_first).abs() < 1e-2 * t_first, "first element's tension {t_sim} N, catenary {t_first} N");
}
