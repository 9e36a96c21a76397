//! Baseline (docs/performance.md): the rope of `benches/rope_step.rs` built
//! the way a Bevy user would today with rapier alone, and its stretch error
//! beside ours.
//!
//! The rope is N rigid capsule bodies (radius 0.01 m, mass μL/N = 32/N kg
//! each, inertia from the capsule shape) plus the 1 t payload ball
//! (radius 0.3 m), joined by spherical joints with contacts disabled between
//! joined bodies and rope–rope collisions filtered out by collision groups,
//! the first joint to a fixed body at the top anchor, sleeping disabled:
//!
//! * `impulse`: `ImpulseJoint` spherical joints;
//! * `multibody`: one `MultibodyJoint` chain (spherical) rooted at the fixed
//!   body (reduced coordinates);
//! * `impulse_32it`: the impulse chain with 32 solver iterations instead of
//!   the default 4 (what a user tries when the rope stretches).
//!
//! `rapier_step/{impulse,impulse_32it,multibody}/N` time one
//! `PhysicsPipeline::step` at dt = 1/60 s with the default
//! `IntegrationParameters` (4 solver iterations, 1 internal PGS iteration,
//! 1 stabilization iteration; single-threaded: the `parallel` feature is
//! off; `impulse_32it` sets `num_solver_iterations = 32`), swinging (released at 30°, advanced 1 s
//! before timing, then stepped continuously: every timed step is a mid-swing
//! step). Before timing, the stretch of the hanging rope at rest is measured:
//! released straight and unstretched, 5 s simulated, then the distance from
//! the top anchor to the payload attachment point minus L, over the last 1 s
//! and again after 30 s; also the largest stretch while swinging from 30°
//! (10 s). The same is measured for our elastic rope (`Cable`) and printed
//! beside the physical value L + mgL/EA + μgL²/(2EA).
//!
//! Times are thread CPU time (`benches/common/cpu_time.rs`; `BENCH_CLOCK=wall`
//! for wall time), like `benches/rope_step.rs`.
//!
//! `cargo bench --bench rapier_baseline`. Environment:
//! `RAPIER_BENCH_SIZES=10,100,1000` (default), `RAPIER_MULTIBODY_MAX_STEP_S`
//! (default 0.5): configurations whose single step takes longer (multibody
//! at N = 1000: about 3 minutes) are timed by hand over 3 steps instead of by
//! criterion (and their stretch runs,
//! 2 100 steps, are skipped when they would take over `RAPIER_STRETCH_MAX_S`,
//! default 120 s).
//! `RAPIER_SKIP_STRETCH=1` skips the stretch runs; `RAPIER_MULTIBODY_MAX_N`
//! (default 1000) skips larger multibody chains entirely.

use bevy_rapier3d::rapier::prelude::*;
use bevy_rapier_cable::cable as cab;
use bevy_rapier_cable::integrate::Scheme;
use criterion::measurement::{Measurement, WallTime};
use criterion::{black_box, BenchmarkId, Criterion, SamplingMode};
use std::time::Duration;

#[path = "common/cpu_time.rs"]
mod cpu_time;
use cpu_time::thread_cpu_ns;

/// Seconds of thread CPU time since `t0` (from `thread_cpu_ns`).
fn cpu_since(t0: u64) -> f64 {
    (thread_cpu_ns() - t0) as f64 * 1e-9
}

const LENGTH: f64 = 20.0;
const MU: f64 = 1.6;
const EA: f64 = 2e7;
const PAYLOAD: f64 = 1000.0;
const RADIUS: f64 = 0.3;
const ROPE_RADIUS: f64 = 0.01;
const G: f64 = 9.81;
const DT: f64 = 1.0 / 60.0;

#[derive(Clone, Copy, PartialEq, Debug)]
enum Kind {
    Impulse,
    Multibody,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Impulse => "impulse",
            Kind::Multibody => "multibody",
        }
    }
}

struct RapierRope {
    pipeline: PhysicsPipeline,
    gravity: Vector,
    params: IntegrationParameters,
    islands: IslandManager,
    broad_phase: BroadPhaseBvh,
    narrow_phase: NarrowPhase,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    ccd: CCDSolver,
    payload: RigidBodyHandle,
}

impl RapierRope {
    /// The rope pinned at the origin, straight at `deg` from the downward
    /// vertical, unstretched, at rest.
    fn new(n: usize, kind: Kind, deg: f64, solver_iterations: Option<usize>) -> Self {
        let a = deg.to_radians() as f32;
        let dir = Vector::new(a.sin(), -a.cos(), 0.0);
        let rot = Vector::new(0.0, 0.0, a); // local −y along `dir`
        let le = (LENGTH / n as f64) as f32;
        let r = ROPE_RADIUS as f32;
        let seg_mass = (MU * LENGTH / n as f64) as f32;
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        let mut impulse_joints = ImpulseJointSet::new();
        let mut multibody_joints = MultibodyJointSet::new();
        let rope_groups = InteractionGroups::new(Group::GROUP_1, !Group::GROUP_1, InteractionTestMode::And);
        let top = bodies.insert(RigidBodyBuilder::fixed());
        let mut parent = top;
        let mut parent_anchor = Vector::ZERO;
        let mut joint = |p: RigidBodyHandle, pa: Vector, c: RigidBodyHandle, ca: Vector| {
            let j = SphericalJointBuilder::new().local_anchor1(pa).local_anchor2(ca).contacts_enabled(false);
            match kind {
                Kind::Impulse => {
                    impulse_joints.insert(p, c, j, true);
                }
                Kind::Multibody => {
                    multibody_joints.insert(p, c, j, true).expect("multibody chain");
                }
            }
        };
        for i in 0..n {
            let centre = dir * ((i as f32 + 0.5) * le);
            let h = bodies.insert(RigidBodyBuilder::dynamic().translation(centre).rotation(rot).can_sleep(false));
            let half = 0.5 * le - r;
            let shape = if half > 1e-4 { ColliderBuilder::capsule_y(half, r) } else { ColliderBuilder::ball(0.5 * le) };
            colliders.insert_with_parent(shape.mass(seg_mass).collision_groups(rope_groups), h, &mut bodies);
            joint(parent, parent_anchor, h, Vector::new(0.0, 0.5 * le, 0.0));
            parent = h;
            parent_anchor = Vector::new(0.0, -0.5 * le, 0.0);
        }
        let pr = RADIUS as f32;
        let payload = bodies.insert(RigidBodyBuilder::dynamic().translation(dir * (LENGTH as f32 + pr)).rotation(rot).can_sleep(false));
        colliders.insert_with_parent(ColliderBuilder::ball(pr).mass(PAYLOAD as f32), payload, &mut bodies);
        joint(parent, parent_anchor, payload, Vector::new(0.0, pr, 0.0));
        let mut params = IntegrationParameters { dt: DT as f32, ..IntegrationParameters::default() };
        if let Some(k) = solver_iterations {
            params.num_solver_iterations = k;
        }
        RapierRope {
            pipeline: PhysicsPipeline::new(),
            gravity: Vector::new(0.0, -G as f32, 0.0),
            params,
            islands: IslandManager::new(),
            broad_phase: BroadPhaseBvh::new(),
            narrow_phase: NarrowPhase::new(),
            bodies,
            colliders,
            impulse_joints,
            multibody_joints,
            ccd: CCDSolver::new(),
            payload,
        }
    }

    fn step(&mut self) {
        self.pipeline.step(
            self.gravity,
            &self.params,
            &mut self.islands,
            &mut self.broad_phase,
            &mut self.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.ccd,
            &(),
            &(),
        );
    }

    /// Top anchor (the origin) to the payload attachment point, minus L, m.
    fn stretch(&self) -> f64 {
        let p = self.bodies[self.payload].position().transform_point(Vector::new(0.0, RADIUS as f32, 0.0));
        p.length() as f64 - LENGTH
    }

    fn finite(&self) -> bool {
        self.bodies.iter().all(|(_, b)| b.translation().is_finite() && b.linvel().is_finite())
    }
}

/// Our elastic rope, pinned at the origin, straight at `deg` from the
/// downward vertical, unstretched.
fn our_rope(n: usize, deg: f64) -> cab::Cable {
    use glam::{DMat3, DVec3};
    let a = deg.to_radians();
    let dir = DVec3::new(a.sin(), -a.cos(), 0.0);
    let sec = cab::RopeSection { linear_density: MU, ea: EA, ei: 50.0, ei2: 50.0, gj: 35.0, min_breaking_load: 0.0 };
    let body = cab::LumpedBody::sphere(PAYLOAD, RADIUS, dir * (LENGTH + RADIUS));
    let model = cab::RopeBuilder::new(LENGTH, n, sec, 2.0 * ROPE_RADIUS)
        .path(vec![DVec3::ZERO, dir * LENGTH])
        .start(cab::RopeStart::Pinned(cab::BaseMotion::Fixed(cab::BaseState::fixed(DMat3::IDENTITY, DVec3::ZERO))))
        .end(cab::RopeEnd::Body { body, anchor: -dir * RADIUS, clamp: false })
        .build()
        .expect("valid rope");
    cab::Cable::new(model, Scheme::default()).expect("initial state")
}

fn our_stretch(c: &cab::Cable) -> f64 {
    let nodes = c.nodes();
    nodes[nodes.len() - 1].distance(nodes[0]) - LENGTH
}

/// Stretch statistics of a run: (mean, min, max) over a window, mm.
#[derive(Default)]
struct Window {
    sum: f64,
    count: usize,
    min: f64,
    max: f64,
}

impl Window {
    fn new() -> Self {
        Window { sum: 0.0, count: 0, min: f64::INFINITY, max: f64::NEG_INFINITY }
    }
    fn push(&mut self, x: f64) {
        self.sum += x;
        self.count += 1;
        self.min = self.min.min(x);
        self.max = self.max.max(x);
    }
    fn show(&self) -> String {
        if self.count == 0 || !self.sum.is_finite() {
            return "diverged".into();
        }
        format!("{:8.2} [{:.2} … {:.2}]", 1e3 * self.sum / self.count as f64, 1e3 * self.min, 1e3 * self.max)
    }
}

/// Runs `steps` steps with `step`, recording `stretch` over the last
/// `window` steps; `None` if the run diverged.
fn run_window(steps: usize, window: usize, mut step: impl FnMut() -> Option<f64>) -> Window {
    let mut w = Window::new();
    for k in 0..steps {
        match step() {
            Some(s) if s.is_finite() => {
                if k + window >= steps {
                    w.push(s)
                }
            }
            _ => return Window::new(),
        }
    }
    w
}

/// Largest N for the multibody chain (`RAPIER_MULTIBODY_MAX_N`, default
/// 1000): its step costs O(N³) here (3 minutes at N = 1000).
fn multibody_max_n() -> usize {
    std::env::var("RAPIER_MULTIBODY_MAX_N").ok().and_then(|s| s.parse().ok()).unwrap_or(1000)
}

fn stretch_report(sizes: &[usize], max_stretch_run_s: f64) {
    let physical = PAYLOAD * G * LENGTH / EA + MU * G * LENGTH * LENGTH / (2.0 * EA);
    println!("== stretch of the hanging rope (top anchor → payload attachment, minus L = 20 m), mm ==");
    println!("physical (elastic, static): mgL/EA + μgL²/(2EA) = {:.3} mm", 1e3 * physical);
    println!(
        "columns: mean [min … max] over 4–5 s after release at rest, straight & unstretched | same over 29–30 s | largest while swinging from 30° (0–10 s)"
    );
    let hang = 300;
    let win = 60;
    for &n in sizes {
        // Ours.
        if n <= 1000 {
            let mut c = our_rope(n, 0.0);
            let mut st = || c.step(DT).ok().map(|_| our_stretch(&c));
            let w5 = run_window(hang, win, &mut st);
            let w30 = run_window(1500, win, &mut st);
            let mut s = our_rope(n, 30.0);
            let swing = run_window(600, 600, || s.step(DT).ok().map(|_| our_stretch(&s)));
            // Exact static stretch of the discrete model.
            let mut c0 = our_rope(n, 0.0);
            let mut q = c0.model.q0.clone();
            let stat = c0.model.chain.solve_static(0.0, &mut q, 1e-12, 500).ok().map(|_| our_stretch(&c0));
            println!(
                "ours (Cable, EA 2e7)       N={n:>5}: {} | {} | max {:8.2}   (static solve {:.3} mm)",
                w5.show(),
                w30.show(),
                1e3 * swing.max,
                stat.map_or(f64::NAN, |x| 1e3 * x)
            );
        }
        for (kind, iters) in [(Kind::Impulse, None), (Kind::Impulse, Some(32)), (Kind::Multibody, None)] {
            if kind == Kind::Multibody && n > multibody_max_n() {
                println!("rapier {:<19} N={n:>5}: skipped (RAPIER_MULTIBODY_MAX_N)", kind.name());
                continue;
            }
            if kind == Kind::Multibody {
                let mut probe = RapierRope::new(n, kind, 0.0, iters);
                let t0 = thread_cpu_ns();
                probe.step();
                let t = cpu_since(t0);
                if t * 2100.0 > max_stretch_run_s {
                    println!("rapier {:<19} N={n:>5}: skipped (one step takes {:.2} s; 2 100 steps would take {:.0} s)", kind.name(), t, t * 2100.0);
                    continue;
                }
            }
            let mut r = RapierRope::new(n, kind, 0.0, iters);
            let mut st = || {
                r.step();
                r.finite().then(|| r.stretch())
            };
            let w5 = run_window(hang, win, &mut st);
            let w30 = run_window(1500, win, &mut st);
            let mut s = RapierRope::new(n, kind, 30.0, iters);
            let swing = run_window(600, 600, || {
                s.step();
                s.finite().then(|| s.stretch())
            });
            let label = format!("{} ({} it)", kind.name(), iters.unwrap_or(4));
            println!(
                "rapier {label:<19} N={n:>5}: {} | {} | max {}",
                w5.show(),
                w30.show(),
                if swing.count > 0 { format!("{:8.2}", 1e3 * swing.max) } else { "diverged".into() }
            );
        }
    }
    println!();
}

fn sizes() -> Vec<usize> {
    match std::env::var("RAPIER_BENCH_SIZES") {
        Ok(s) => s.split(',').filter_map(|x| x.trim().parse().ok()).collect(),
        Err(_) => vec![10, 100, 1_000],
    }
}

fn main() {
    let sizes = sizes();
    let max_mb: f64 = std::env::var("RAPIER_MULTIBODY_MAX_STEP_S").ok().and_then(|s| s.parse().ok()).unwrap_or(0.5);
    if std::env::var_os("RAPIER_SKIP_STRETCH").is_none() {
        let max_s = std::env::var("RAPIER_STRETCH_MAX_S").ok().and_then(|s| s.parse().ok()).unwrap_or(120.0);
        stretch_report(&sizes, max_s);
    }
    let wall = std::env::var("BENCH_CLOCK").is_ok_and(|v| v == "wall");
    println!("clock: {}", if wall { "wall time" } else { "thread CPU time (BENCH_CLOCK=wall for wall time)" });
    let base = Criterion::default().warm_up_time(Duration::from_secs(1));
    if wall {
        bench(base.with_measurement(WallTime).configure_from_args(), &sizes, max_mb);
    } else {
        bench(base.with_measurement(cpu_time::ThreadCpuTime).configure_from_args(), &sizes, max_mb);
    }
}

fn bench<M: Measurement>(mut c: Criterion<M>, sizes: &[usize], max_mb: f64) {
    let mut manual = Vec::new();
    {
        let mut group = c.benchmark_group("rapier_step");
        for (kind, iterations, label) in [(Kind::Impulse, None, "impulse"), (Kind::Impulse, Some(32), "impulse_32it"), (Kind::Multibody, None, "multibody")] {
            for &n in sizes {
                if kind == Kind::Multibody && n > multibody_max_n() {
                    manual.push(format!("rapier_step/multibody/{n}: skipped (RAPIER_MULTIBODY_MAX_N)"));
                    continue;
                }
                let mut r = RapierRope::new(n, kind, 30.0, iterations);
                // One step to see whether criterion can time it.
                let t0 = thread_cpu_ns();
                r.step();
                let first = cpu_since(t0);
                if first > max_mb {
                    // Too slow for criterion: a few steps by hand.
                    let k = 3;
                    let t0 = thread_cpu_ns();
                    for _ in 0..k {
                        r.step();
                    }
                    let per = cpu_since(t0) / k as f64;
                    manual.push(format!(
                        "rapier_step/{}/{n}: {:.3} s CPU per step (mean of {k} steps after the first, timed by hand; t < 0.1 s after release)",
                        label, per
                    ));
                    continue;
                }
                for _ in 0..59 {
                    r.step();
                }
                if n >= 1000 || first > 0.01 {
                    group.sampling_mode(SamplingMode::Flat).sample_size(10).measurement_time(Duration::from_secs(8));
                } else {
                    group.sampling_mode(SamplingMode::Auto).sample_size(30).measurement_time(Duration::from_secs(5));
                }
                group.bench_function(BenchmarkId::new(label, n), |b| {
                    b.iter(|| {
                        r.step();
                        black_box(&r.bodies);
                    })
                });
                if !r.finite() {
                    manual.push(format!("rapier_step/{label}/{n}: the state became non-finite while timing"));
                }
            }
        }
        group.finish();
    }
    c.final_summary();
    for m in manual {
        println!("{m}");
    }
}
