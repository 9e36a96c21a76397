//! A rope touching itself (issue 12): the contacts between two elements
//! of one cable are pair elements inside the cable's implicit solve, their
//! loop coupling solved exactly (`Chain::pairs`, a Woodbury correction
//! over the pairs after the O(n) sweep). Without them the rope passed
//! through itself.
#![cfg(feature = "sim")]

#[path = "common/scenario_run.rs"]
mod scenario_run;
use scenario_run::{landing, run_scenario, run_shipped_variant, segment_distance};

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

/// The same upper pass let go 1.2 m up strikes the lower one at 5.1 m/s,
/// 8.5 cm per frame step: the contact passes find the pair contacts again
/// as it closes, it never goes further into the lower pass than the same
/// strike resolved at 1/960 s does (its contact law's compression at the
/// strike: the centrelines 17.07 mm apart, 2.9 mm closer than a diameter,
/// at 5.8 m/s), and it comes to rest on it: at 2 s the two passes'
/// centrelines (exact segment distances) are a diameter apart less a
/// Hertz indentation (under 0.2 mm). (The upper pass is a bent rope
/// pivoting about its foot on the ground, and its free end falls faster
/// than a free body: 5.8 m/s resolved, 5.1 m/s at the frame step.)
#[test]
fn a_rope_dropped_on_itself_at_speed_does_not_pass_through() {
    let diameter = 0.020;
    let shipped = std::fs::read_to_string("assets/scenarios/rope_crossing.toml").unwrap();
    let dropped = shipped.replace("[0.0, 0.2, 1.5], [0.0, 0.2, -1.5]", "[0.0, 1.2, 1.5], [0.0, 1.2, -1.5]");
    let run = |source: &str| run_scenario(bevy_rapier_cable::scenario::parse(source, "rope_crossing.toml").unwrap_or_else(|e| panic!("{e}")));
    let (world, rows) = run(&dropped);
    let (closest, _, speed) = landing(&rows);
    let resting = closest_to_itself(&world.cable("rope").unwrap().nodes());
    // The same drop at 1/960 s, over the strike (0.8 s).
    let (_, fine) = run(&dropped.replace("dt = 0.016666666666666666", "dt = 0.0010416666666666667").replace("duration = 2.0", "duration = 0.8"));
    let (resolved, _, resolved_speed) = landing(&fine);
    eprintln!("drop: closest {closest:.6} m, at rest {resting:.6} m, fastest fall {speed:.2} m/s; at 1/960 s: closest {resolved:.6} m, fastest fall {resolved_speed:.2} m/s");
    assert!(speed > 4.0, "the upper pass should strike fast: {speed} m/s");
    assert!(closest > resolved - 5e-4, "the upper pass went {} m further into the lower one than resolved at 1/960 s", resolved - closest);
    assert!(resolved > diameter - 5e-3, "resolved at 1/960 s the upper pass went {} m into the lower one", diameter - resolved);
    assert!(resting < diameter && resting > diameter - 2e-4, "resting centrelines {resting} m apart");
}

/// The smallest distance (m) between the centrelines of two elements of
/// one rope (`nodes`) at least four elements apart (exact segment–segment
/// distances).
fn closest_to_itself(nodes: &[glam::DVec3]) -> f64 {
    let mut m = f64::INFINITY;
    for i in 0..nodes.len() - 1 {
        for j in i + 4..nodes.len() - 1 {
            m = m.min(segment_distance(nodes[i], nodes[i + 1], nodes[j], nodes[j + 1]));
        }
    }
    m
}

/// A rope tied around itself: an overhand knot, tied loose in 10 mm steel
/// rope (160 elements of 2 cm) and let go under a 5 kg ball, tightens and
/// holds. The knot is an open trefoil (`x = s (sin t + 2 sin 2t)`,
/// `y = s (cos t − 2 cos 2t)`, `z = −s sin 3t`, s = 5 cm, t from 0.3 to
/// 2π − 0.3) with a 1 m tail along the curve's direction at each end,
/// turned so the tails hang; the rope is laid bent along it (stressed, not
/// moulded), its top pinned, the ball on its lower end. The strands
/// spring together in the first frame step (the bent rope's elastic
/// energy, about 92 J of it taken out by the contacts and the rope's damping in
/// the first 0.25 s) and the knot pulls tight: at every frame no two
/// elements four or more apart come nearer than a diameter less 0.2 mm
/// (measured 0.10 mm; before the ropes' touches counted their nodes'
/// start accelerations in their reach, the first step found no touch
/// from rest and ended with two strands 5.2 mm into each other), the
/// strands still touch at the
/// end, the ball hangs (the knot keeps its rope: untied, the ball would
/// hang 1.5 m lower) and the top carries the ball and the rope, on
/// average over the last second, to 5 %.
#[test]
fn an_overhand_knot_tied_loose_tightens_and_holds_a_weight() {
    let s = 0.05;
    let (t0, t1) = (0.3, 2.0 * std::f64::consts::PI - 0.3);
    let curve = |t: f64| glam::DVec3::new(s * (t.sin() + 2.0 * (2.0 * t).sin()), s * (t.cos() - 2.0 * (2.0 * t).cos()), -s * (3.0 * t).sin());
    let tangent = |t: f64| glam::DVec3::new(t.cos() + 4.0 * (2.0 * t).cos(), -t.sin() + 4.0 * (2.0 * t).sin(), -3.0 * (3.0 * t).cos()).normalize();
    let mut path = vec![curve(t0) - tangent(t0)];
    path.extend((0..=120).map(|k| curve(t0 + (t1 - t0) * k as f64 / 120.0)));
    path.push(curve(t1) + tangent(t1));
    // Turn the tails' mean direction to hang down (−y), 3 m up.
    let down = (tangent(t0) + tangent(t1)).normalize();
    let turn = glam::DQuat::from_rotation_arc(down, glam::DVec3::NEG_Y);
    let path: Vec<glam::DVec3> = path.iter().map(|p| turn * *p + glam::DVec3::new(0.0, 3.0, 0.0)).collect();
    let length: f64 = path.windows(2).map(|w| w[0].distance(w[1])).sum();
    let (top, bottom) = (path[0], path[path.len() - 1]);
    let points: Vec<String> = path.iter().map(|p| format!("[{:.9}, {:.9}, {:.9}]", p.x, p.y, p.z)).collect();
    let source = format!(
        r#"
[simulation]
duration = 2.0
dt = 0.016666666666666666

[[body]]
name = "weight"
type = "dynamic"
shape = "ball"
radius = 0.05
mass = 5.0
position = [{bx}, {by}, {bz}]

[[cable]]
name = "rope"
length = {length}
segments = 160
diameter = 0.010
material = "steel_wire_rope_6x36_iwrc"
damping = 0.01
start = {{ world = [{tx}, {ty}, {tz}] }}
end = {{ body = "weight", anchor = [0.0, 0.05, 0.0] }}
path = [{path}]

[[probe]]
name = "top_tension"
cable = "rope"
quantity = "tension"
s = 0.0
"#,
        bx = bottom.x,
        by = bottom.y - 0.05,
        bz = bottom.z,
        tx = top.x,
        ty = top.y,
        tz = top.z,
        path = points.join(", ")
    );
    let sc = bevy_rapier_cable::scenario::parse(&source, "overhand_knot.toml").unwrap_or_else(|e| panic!("{e}"));
    let frames = (sc.simulation.duration / sc.simulation.dt).round() as usize;
    let mut world = bevy_rapier_cable::sim::World::new(sc).unwrap_or_else(|e| panic!("{e}"));
    let diameter = 0.010;
    let (mut closest, mut first, mut tensions) = (f64::INFINITY, f64::NAN, Vec::new());
    let mut row = Vec::new();
    for f in 0..frames {
        world.step().unwrap_or_else(|e| panic!("{e}"));
        let d = closest_to_itself(&world.cable("rope").unwrap().nodes());
        if f == 0 {
            first = d;
        }
        closest = closest.min(d);
        world.sample(&mut row);
        if world.time > 1.0 + 1e-9 {
            tensions.push(row[0]);
        }
    }
    let rope = world.cable("rope").unwrap();
    let nodes = rope.nodes();
    let (end, ball) = (closest_to_itself(&nodes), nodes[nodes.len() - 1].y - 0.05);
    let mean = tensions.iter().sum::<f64>() / tensions.len() as f64;
    let load = (5.0 + 0.004 * 10.0 * 10.0 * length) * 9.81;
    let untied = top.y - length - 0.05;
    eprintln!(
        "overhand knot: rope {length:.4} m; closest strands {closest:.6} m (first frame {first:.6}, end {end:.6}); ball at {ball:.4} m (untied: {untied:.4} m); \
         top tension over the last second {mean:.2} N against {load:.2} N ({:+.2e})",
        mean / load - 1.0
    );
    assert!(closest > diameter - 2e-4, "the strands went into each other: {closest} m");
    assert!(end < diameter + 5e-4, "the knot should be tight at the end: strands {end} m apart");
    assert!(ball > untied + 1.0, "the knot let go: the ball at {ball} m");
    assert!((mean / load - 1.0).abs() < 0.05, "the top carries {mean} N, not the ball and the rope's {load} N");
}
