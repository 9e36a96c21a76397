//! Runs a scenario in `cablesim`'s world, frame by frame.

use bevy_rapier_cable::scenario::Scenario;
use bevy_rapier_cable::sim::World;

/// Runs `sc` over its whole duration; rows are `[time, probes...]`, one
/// per frame.
#[allow(dead_code)]
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

/// A newcomer's rope over a drum, laid by hand, as scenario text of
/// `duration` s at 1/60 s: 16 mm steel rope (60 elements, `damping`
/// 0.003 s) from a pin 2 m below the left side of a fixed steel drum of
/// radius 0.5 m (axis along z), up and over it on a half-circle 2.2 cm
/// off its surface (bent, not moulded), down to a 200 kg ball; a tension
/// probe 5 cm from the ball.
#[allow(dead_code)]
pub fn drum_scenario(duration: f64) -> String {
    let r = 0.53;
    let mut path = vec![(-r, -2.0)];
    path.extend((0..=24).map(|k| {
        let a = std::f64::consts::PI * (1.0 - k as f64 / 24.0);
        (r * a.cos(), r * a.sin())
    }));
    path.push((r, -3.2));
    let length: f64 = path.windows(2).map(|w| ((w[1].0 - w[0].0).powi(2) + (w[1].1 - w[0].1).powi(2)).sqrt()).sum();
    let points: Vec<String> = path.iter().map(|(x, y)| format!("[{x}, {y}, 0.0]")).collect();
    format!(
        r#"[simulation]
duration = {duration}
dt = 0.016666666666666666

[[body]]
name = "drum"
type = "fixed"
shape = "cylinder"
radius = 0.5
half_height = 0.3
rotation = [90.0, 0.0, 0.0]

[[body]]
name = "ball"
type = "dynamic"
shape = "ball"
radius = 0.2
mass = 200.0
position = [{r}, -3.2, 0.0]

[[cable]]
name = "rope"
length = {length}
segments = 60
diameter = 0.016
material = "steel_wire_rope_6x36_iwrc"
damping = 0.003
start = {{ world = [{}, -2.0, 0.0] }}
end = {{ body = "ball" }}
path = [{}]

[[probe]]
name = "tension"
cable = "rope"
quantity = "tension"
s = {}
"#,
        -r,
        points.join(", "),
        length - 0.05
    )
}

/// The distance (m) between the segments `p1 q1` and `p2 q2` (world, m):
/// exact, from their nearest points (clamped to both segments).
#[allow(dead_code)]
pub fn segment_distance(p1: glam::DVec3, q1: glam::DVec3, p2: glam::DVec3, q2: glam::DVec3) -> f64 {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (aa, e, f, c, bb) = (d1.dot(d1), d2.dot(d2), d2.dot(r), d1.dot(r), d1.dot(d2));
    let den = aa * e - bb * bb;
    let mut s = if den > 1e-15 { ((bb * f - c * e) / den).clamp(0.0, 1.0) } else { 0.0 };
    let mut t = (bb * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / aa).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((bb - c) / aa).clamp(0.0, 1.0);
    }
    ((p1 + d1 * s) - (p2 + d2 * t)).length()
}
