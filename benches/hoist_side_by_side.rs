//! The hoist pendulum of issue 14, run whole as `benches/exudyn/hoist_pendulum.py`
//! runs it in Exudyn, for the side-by-side table in `docs/performance.md`:
//! 20 m steel rope (1.6 kg/m, EA 2e7 N, EI 50 N·m², GJ 35 N·m²) pinned at
//! the top, a 1 t sphere (r = 0.3 m) on a ball joint at its end, released
//! from rest at 30° on a straight unstretched rope, h = 1/60 s, 20 s.
//! For N = 10, 100, 1 000 and the default scheme and the fast preset it
//! prints the CPU time of the 1 200 steps (thread CPU time, the best of
//! `HOIST_REPEAT` runs, default 3; model building excluded), the
//! real-time factor (20 s over that time), the period (zero crossings of
//! the payload centre's x) and the time mean of the stretch (arc length
//! − 20)/20 over the step ends, with their errors against the reference
//! (the default scheme at h/4: 9.1749 / 9.1748 / 9.1748 s, 5.287e-4 /
//! 5.281e-4 / 5.280e-4), and the Newton iterations per step.
//!
//! `cargo bench --bench hoist_side_by_side` (`HOIST_SIZES=100,1000` to
//! choose N). Run it and the Exudyn script one after the other on a quiet
//! machine.

use bevy_rapier_cable::cable::cable::Cable;
use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::Scheme;
use glam::{DMat3, DVec3};

#[path = "common/cpu_time.rs"]
#[allow(dead_code)]
mod cpu_time;

const L: f64 = 20.0;

fn hoist(n: usize) -> RopeModel {
    let angle = 30f64.to_radians();
    let dir = DVec3::new(angle.sin(), -angle.cos(), 0.0);
    let section = RopeSection { linear_density: 1.6, ea: 2e7, ei: 50.0, ei2: 50.0, gj: 35.0, min_breaking_load: 0.0 };
    RopeBuilder::new(L, n, section, 0.02)
        .path(vec![DVec3::ZERO, dir * L])
        .start(RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, DVec3::ZERO))))
        .end(RopeEnd::Body { body: LumpedBody::sphere(1000.0, 0.3, dir * (L + 0.3)), anchor: -dir * 0.3, clamp: false })
        .build()
        .expect("hoist pendulum")
}

/// One 20 s run: (CPU s, period s, mean stretch, Newton iterations per step).
fn run(n: usize, scheme: &Scheme) -> (f64, f64, f64, f64) {
    let h = 1.0 / 60.0;
    let mut cable = Cable::new(hoist(n), scheme.clone()).expect("cable");
    let body = cable.model.layout.end_body.expect("payload");
    let (mut ts, mut xs, mut stretch) = (vec![0.0], vec![cable.model.body_state(&body).0.x], 0.0);
    let mut cpu = 0u64;
    for _ in 0..1200 {
        let t0 = cpu_time::thread_cpu_ns();
        cable.step(h).expect("step");
        cpu += cpu_time::thread_cpu_ns() - t0;
        ts.push(cable.time());
        xs.push(cable.model.body_state(&body).0.x);
        stretch += (cable.stretched_length() - L) / L;
    }
    let c: Vec<f64> =
        (1..xs.len()).filter(|&k| (xs[k - 1] < 0.0) != (xs[k] < 0.0)).map(|k| ts[k - 1] + (ts[k] - ts[k - 1]) * (-xs[k - 1]) / (xs[k] - xs[k - 1])).collect();
    let period = 2.0 * (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64;
    (cpu as f64 * 1e-9, period, stretch / 1200.0, cable.total_stats.newton_iterations as f64 / 1200.0)
}

fn main() {
    let sizes: Vec<usize> = std::env::var("HOIST_SIZES").ok().map_or(vec![10, 100, 1000], |s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect());
    let repeat: usize = std::env::var("HOIST_REPEAT").ok().and_then(|s| s.parse().ok()).unwrap_or(3).max(1);
    println!("| N | scheme | CPU s (20 s simulated) | real-time factor | period s (error) | mean stretch (error) | Newton it/step |");
    println!("|---:|---|---:|---:|---:|---:|---:|");
    for n in sizes {
        let (period_ref, stretch_ref) = match n {
            10 => (9.1749, 5.287e-4),
            100 => (9.1748, 5.281e-4),
            _ => (9.1748, 5.280e-4),
        };
        for (name, scheme) in [("default", Scheme::default()), ("fast preset", Scheme::LinearlyImplicit { w: 0.6 })] {
            let runs: Vec<_> = (0..repeat).map(|_| run(n, &scheme)).collect();
            let best = runs.iter().copied().min_by(|a, b| a.0.total_cmp(&b.0)).expect("a run");
            let (cpu, period, stretch, newton) = best;
            println!(
                "| {n} | {name} | {cpu:.3} | {:.1} | {period:.4} ({:+.1e}) | {stretch:.4e} ({:+.1e}) | {newton:.2} |",
                20.0 / cpu,
                period / period_ref - 1.0,
                stretch / stretch_ref - 1.0
            );
        }
    }
}
