//! Cost of the rope model (docs/performance.md).
//!
//! * `step/N`: one frame step (1/60 s) of a swinging 20 m steel rope
//!   (μ 1.6 kg/m, EA 2e7 N, EI 50 N·m², GJ 35 N·m²) with a 1 t ball payload,
//!   released at 30° and advanced 1 s before timing, with the default scheme
//!   (generalized-α, ρ∞ = 0). The timed steps are the 60 consecutive steps
//!   of t = 1 … 2 s (mid-swing), repeated: at the end of the window the
//!   state is reset to t = 1 s and one *untimed* step is taken, so every
//!   timed step has the same history as in a real run (the integrator keeps
//!   predictor history in its own workspace, so swapping a stored state in
//!   front of a timed step would time a cold-predictor step). The time is
//!   the mean over that second of swing; the mean Newton iterations of the
//!   timed steps are counted and printed.
//! * `step_continuous/N`: steps without any reset (each continues the swing
//!   from wherever the previous one ended; criterion runs many seconds of
//!   simulated time), as a cross-check.
//! * `pass/N`: one residual pass (`Chain::residual_into`: kinematics, loads,
//!   tip-to-base sweep) and one O(n) tangent solve (`Chain::solve_into`:
//!   articulated-body backward sweep + forward substitution) at that state;
//!   `residual/N` and `solve/N` time the two halves, `fused/N` the fused
//!   `Chain::residual_and_correction_into` that Newton calls once per
//!   iteration (residual and backward sweep in one tip-to-base pass).
//! * `step_fast/N`: one frame step of the same swing with the fast preset
//!   (`Scheme::LinearlyImplicit`, w = 0.6: three residuals and one solve, no
//!   Newton loop), steps without reset; the summary prints the ratio
//!   `step/N` ÷ `step_fast/N`.
//!
//! N = 10, 100, 1 000, 10 000 elements (6 sub-joints each). Before timing,
//! the Newton work per step is printed (mean/min/max over the 60 steps of
//! the window). After timing, the per-step table and the log–log
//! least-squares exponent of cost vs N over N = 100 … 10 000 are printed from
//! criterion's own estimates (`$CARGO_TARGET_DIR/criterion/...`).
//!
//! Times are the benchmark thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`,
//! `benches/common/cpu_time.rs`), so that waiting for a core on a shared
//! machine is not counted; `BENCH_CLOCK=wall` measures wall time instead.
//!
//! `cargo bench --bench rope_step` (all), `cargo bench --bench rope_step -- step/1000`
//! (one). Environment: `ROPE_BENCH_SIZES=10,100` restricts the sizes.

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::{Scheme, State, StepStats};
use criterion::measurement::{Measurement, WallTime};
use criterion::{black_box, BenchmarkGroup, BenchmarkId, Criterion, SamplingMode, Throughput};
use glam::{DMat3, DVec3};
use std::path::PathBuf;
use std::time::Duration;

#[path = "common/cpu_time.rs"]
mod cpu_time;

const LENGTH: f64 = 20.0;
const PAYLOAD: f64 = 1000.0;
const RADIUS: f64 = 0.3;
const H: f64 = 1.0 / 60.0;
const RELEASE_DEG: f64 = 30.0;
/// Steps advanced before timing (1 s).
const PRE_STEPS: usize = 60;
/// Steps over which the Newton work is averaged.
const STAT_STEPS: usize = 60;

fn section() -> RopeSection {
    RopeSection { linear_density: 1.6, ea: 2e7, ei: 50.0, ei2: 50.0, gj: 35.0, min_breaking_load: 0.0 }
}

/// The rope pinned at the origin, laid straight at `deg` from the downward
/// vertical, the payload on a ball joint at its end (tests/dynamics.rs
/// `pendulum`).
fn swing_model(n: usize, deg: f64) -> RopeModel {
    let a = deg.to_radians();
    let dir = DVec3::new(a.sin(), -a.cos(), 0.0);
    let body = LumpedBody::sphere(PAYLOAD, RADIUS, dir * (LENGTH + RADIUS));
    RopeBuilder::new(LENGTH, n, section(), 0.02)
        .path(vec![DVec3::ZERO, dir * LENGTH])
        .start(RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, DVec3::ZERO))))
        .end(RopeEnd::Body { body, anchor: -dir * RADIUS, clamp: false })
        .build()
        .expect("valid rope")
}

/// The fast preset (`Scheme::LinearlyImplicit`, w = 0.6): one linearised
/// solve per step, no Newton loop.
const FAST: Scheme = Scheme::LinearlyImplicit { w: 0.6 };

/// A cable advanced `PRE_STEPS` steps from its release: mid-swing.
fn mid_swing(n: usize) -> Cable {
    mid_swing_with(n, Scheme::default())
}

/// [`mid_swing`] with another integration scheme.
fn mid_swing_with(n: usize, scheme: Scheme) -> Cable {
    let mut cable = Cable::new(swing_model(n, RELEASE_DEG), scheme).expect("initial state");
    for k in 0..PRE_STEPS {
        cable.step(H).unwrap_or_else(|e| panic!("N = {n}: pre-advance step {k} failed: {e}"));
    }
    cable
}

/// Newton work per step over `STAT_STEPS` steps from the cable's state (the
/// state is restored afterwards).
struct Work {
    mean_newton: f64,
    min_newton: usize,
    max_newton: usize,
    residuals: f64,
    solves: f64,
    refresh: f64,
    max_substeps: u64,
    /// The state before each of the `STAT_STEPS` steps.
    states: Vec<State>,
    /// Mean Newton iterations of the steps timed by `step/N`.
    timed_newton: f64,
    /// Mean Newton iterations of the steps timed by `step_continuous/N`,
    /// and the simulated time they covered, s.
    continuous_newton: f64,
    continuous_seconds: f64,
}

fn newton_work(cable: &mut Cable) -> Work {
    let saved = cable.state.clone();
    let mut states = Vec::with_capacity(STAT_STEPS);
    let mut total = StepStats::default();
    let (mut lo, mut hi, mut sub, mut split) = (usize::MAX, 0, 0, 0usize);
    for _ in 0..STAT_STEPS {
        states.push(cable.state.clone());
        let s = cable.step(H).expect("step");
        total += s;
        lo = lo.min(s.newton_iterations);
        hi = hi.max(s.newton_iterations);
        sub = sub.max(s.substeps_used);
        split += usize::from(s.substeps_used > 1);
    }
    cable.state = saved;
    cable.refresh();
    let k = STAT_STEPS as f64;
    Work {
        mean_newton: total.newton_iterations as f64 / k,
        min_newton: lo,
        max_newton: hi,
        residuals: total.residual_evals as f64 / k,
        solves: total.solves as f64 / k,
        // Cable::step re-evaluates the residual at the accepted state only
        // when Newton did not converge in one sub-step (src/cable/cable.rs).
        refresh: split as f64 / k,
        max_substeps: sub,
        states,
        timed_newton: f64::NAN,
        continuous_newton: f64::NAN,
        continuous_seconds: 0.0,
    }
}

/// `(c_v, c_q)` of the default scheme's Newton matrix at step `H`.
fn newton_coefficients() -> (f64, f64) {
    let p = Scheme::default().alpha_parameters().expect("generalized-α");
    let s = (1.0 - p.alpha_f) / (1.0 - p.alpha_m);
    (H * p.gamma * s, H * H * p.beta * s)
}

fn sizes() -> Vec<usize> {
    match std::env::var("ROPE_BENCH_SIZES") {
        Ok(s) => s.split(',').filter_map(|x| x.trim().parse().ok()).collect(),
        Err(_) => vec![10, 100, 1_000, 10_000],
    }
}

fn configure<M: Measurement>(group: &mut BenchmarkGroup<'_, M>, n: usize) {
    if n >= 1_000 {
        group.sampling_mode(SamplingMode::Flat).sample_size(10).measurement_time(Duration::from_secs(8));
    } else {
        group.sampling_mode(SamplingMode::Auto).sample_size(30).measurement_time(Duration::from_secs(5));
    }
}

/// The clock of the custom-timed benches (the same as criterion's
/// measurement for the others).
#[derive(Clone, Copy)]
enum Clock {
    Wall,
    ThreadCpu,
}

impl Clock {
    fn time(self, f: impl FnOnce()) -> Duration {
        match self {
            Clock::Wall => {
                let t0 = std::time::Instant::now();
                f();
                t0.elapsed()
            }
            Clock::ThreadCpu => {
                let t0 = cpu_time::thread_cpu_ns();
                f();
                Duration::from_nanos(cpu_time::thread_cpu_ns() - t0)
            }
        }
    }
}

fn main() {
    let wall = std::env::var("BENCH_CLOCK").is_ok_and(|v| v == "wall");
    println!("clock: {}", if wall { "wall time" } else { "thread CPU time (BENCH_CLOCK=wall for wall time)" });
    let base = Criterion::default().warm_up_time(Duration::from_secs(1));
    if wall {
        run(base.with_measurement(WallTime).configure_from_args(), Clock::Wall);
    } else {
        run(base.with_measurement(cpu_time::ThreadCpuTime).configure_from_args(), Clock::ThreadCpu);
    }
}

fn run<M: Measurement<Value = Duration>>(mut c: Criterion<M>, clock: Clock) {
    let sizes = sizes();
    let (c_v, c_q) = newton_coefficients();

    // Build every cable once, mid-swing, and print its Newton work.
    let mut cables = Vec::new();
    println!("rope: L = {LENGTH} m, μ 1.6 kg/m, EA 2e7 N, EI 50 N·m², payload {PAYLOAD} kg, released at {RELEASE_DEG}°, h = 1/60 s, generalized-α ρ∞ = 0");
    println!("{:>6} {:>8} {:>10} {:>10} {:>10} {:>8} {:>9} {:>9}", "N", "dofs", "Newton/st", "min..max", "resid/st", "solve/st", "refresh", "substeps");
    for &n in &sizes {
        let mut cable = mid_swing(n);
        let w = newton_work(&mut cable);
        println!(
            "{:>6} {:>8} {:>10.2} {:>10} {:>10.2} {:>8.2} {:>9.2} {:>9}",
            n,
            cable.model.chain.len(),
            w.mean_newton,
            format!("{}..{}", w.min_newton, w.max_newton),
            w.residuals,
            w.solves,
            w.refresh,
            w.max_substeps
        );
        cables.push((n, cable, w));
    }

    {
        let mut group = c.benchmark_group("step");
        for (n, cable, w) in cables.iter_mut() {
            configure(&mut group, *n);
            group.throughput(Throughput::Elements(*n as u64));
            let saved = cable.state.clone();
            let states = &w.states;
            // Position in the window; past its end the cable is reset to its
            // start and one untimed step gives the predictor its history.
            let mut pos = usize::MAX;
            let (mut steps, mut newton) = (0usize, 0usize);
            group.bench_function(BenchmarkId::from_parameter(*n), |b| {
                b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    let mut left = iters as usize;
                    while left > 0 {
                        if pos >= states.len() {
                            cable.state = states[0].clone();
                            cable.step(H).expect("untimed step");
                            pos = 1;
                        }
                        let k = left.min(states.len() - pos);
                        let before = cable.total_stats.newton_iterations;
                        total += clock.time(|| {
                            for _ in 0..k {
                                black_box(cable.step(H).expect("step"));
                            }
                        });
                        newton += cable.total_stats.newton_iterations - before;
                        steps += k;
                        left -= k;
                        pos += k;
                    }
                    total
                })
            });
            w.timed_newton = newton as f64 / steps.max(1) as f64;
            cable.state = saved.clone();
            // Continuous: steps without any reset (each continues the swing
            // from wherever the previous one ended); the state is restored after.
            cable.step(H).expect("untimed step");
        }
        group.finish();
    }
    {
        let mut group = c.benchmark_group("step_continuous");
        for (n, cable, w) in cables.iter_mut() {
            configure(&mut group, *n);
            group.throughput(Throughput::Elements(*n as u64));
            let saved = cable.state.clone();
            let (mut steps, mut newton) = (0usize, 0usize);
            group.bench_function(BenchmarkId::from_parameter(*n), |b| {
                b.iter_custom(|iters| {
                    let before = cable.total_stats.newton_iterations;
                    let d = clock.time(|| {
                        for _ in 0..iters {
                            black_box(cable.step(H).expect("step"));
                        }
                    });
                    newton += cable.total_stats.newton_iterations - before;
                    steps += iters as usize;
                    d
                })
            });
            w.continuous_newton = newton as f64 / steps.max(1) as f64;
            w.continuous_seconds = steps as f64 * H;
            cable.state = saved;
            cable.refresh();
        }
        group.finish();
    }

    {
        // The fast preset, steps without reset (it keeps no predictor
        // history beyond the state's acceleration).
        let mut group = c.benchmark_group("step_fast");
        for n in &sizes {
            let n = *n;
            configure(&mut group, n);
            group.throughput(Throughput::Elements(n as u64));
            let mut cable = mid_swing_with(n, FAST);
            group.bench_function(BenchmarkId::from_parameter(n), |b| {
                b.iter_custom(|iters| {
                    clock.time(|| {
                        for _ in 0..iters {
                            black_box(cable.step(H).expect("fast step"));
                        }
                    })
                })
            });
        }
        group.finish();
    }

    for (name, what) in [("pass", 3u8), ("fused", 4), ("residual", 1), ("solve", 2)] {
        let mut group = c.benchmark_group(name);
        for (n, cable, _) in cables.iter_mut() {
            configure(&mut group, *n);
            group.throughput(Throughput::Elements(*n as u64));
            let st = cable.state.clone();
            let dof = st.q.len();
            let (mut r, mut x) = (vec![0.0; dof], vec![0.0; dof]);
            let chain = &mut cable.model.chain;
            chain.residual_into(st.t, &st.q, &st.v, &st.a, &mut r).expect("residual");
            group.bench_function(BenchmarkId::from_parameter(*n), |b| {
                b.iter(|| {
                    if what & 1 != 0 {
                        chain.residual_into(st.t, &st.q, &st.v, &st.a, &mut r).expect("residual");
                    }
                    if what & 2 != 0 {
                        chain.solve_into(c_v, c_q, &r, &mut x).expect("solve");
                    }
                    if what & 4 != 0 {
                        chain.residual_and_correction_into(st.t, &st.q, &st.v, &st.a, c_v, c_q, &mut r, &mut x).expect("fused");
                    }
                    black_box(&x);
                })
            });
        }
        group.finish();
    }

    c.final_summary();
    report(&cables.iter().map(|(n, _, w)| (*n, w)).collect::<Vec<_>>());
}

/// Criterion's output directory (the rule of criterion 0.5).
fn criterion_dir() -> PathBuf {
    if let Some(v) = std::env::var_os("CRITERION_HOME") {
        return PathBuf::from(v);
    }
    std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| PathBuf::from("target")).join("criterion")
}

/// Median time (ns) of benchmark `group/id` from criterion's last run.
fn median_ns(group: &str, id: usize) -> Option<f64> {
    let p = criterion_dir().join(group).join(id.to_string()).join("new").join("estimates.json");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(p).ok()?).ok()?;
    v["median"]["point_estimate"].as_f64()
}

/// Least-squares slope of ln t against ln N.
fn exponent(points: &[(f64, f64)]) -> Option<f64> {
    if points.len() < 2 {
        return None;
    }
    let k = points.len() as f64;
    let (mx, my) = points.iter().fold((0.0, 0.0), |(a, b), (n, t)| (a + n.ln() / k, b + t.ln() / k));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), (n, t)| (a + (n.ln() - mx) * (t.ln() - my), b + (n.ln() - mx).powi(2)));
    Some(sxy / sxx)
}

fn report(work: &[(usize, &Work)]) {
    const GROUPS: [&str; 7] = ["step", "pass", "fused", "residual", "solve", "step_continuous", "step_fast"];
    println!("\n== summary (criterion medians from {}) ==", criterion_dir().display());
    println!("| N | step µs | µs/element/step | Newton it/step (window; timed) | sweeps/step | pass µs | ns/element/pass | fused µs | residual µs | solve µs | continuous step µs (Newton it/step, simulated s) | fast preset step µs (default/fast) |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut fits: Vec<(&str, Vec<(f64, f64)>)> = GROUPS.iter().map(|g| (*g, vec![])).collect();
    for (n, w) in work {
        let t: Vec<Option<f64>> = GROUPS.iter().map(|g| median_ns(g, *n)).collect();
        let us = |x: Option<f64>| x.map_or("–".to_string(), |v| format!("{:.1}", v / 1e3));
        let per = |x: Option<f64>, k: f64| x.map_or("–".to_string(), |v| format!("{:.2}", v / k / *n as f64));
        println!(
            "| {} | {} | {} | {:.2}; {:.2} | {:.2} | {} | {} | {} | {} | {} | {} ({:.2}, {:.0}) | {} ({}) |",
            n,
            us(t[0]),
            per(t[0], 1e3),
            w.mean_newton,
            w.timed_newton,
            w.residuals + w.refresh,
            us(t[1]),
            t[1].map_or("–".to_string(), |v| format!("{:.0}", v / *n as f64)),
            us(t[2]),
            us(t[3]),
            us(t[4]),
            us(t[5]),
            w.continuous_newton,
            w.continuous_seconds,
            us(t[6]),
            t[0].zip(t[6]).map_or("–".to_string(), |(d, f)| format!("{:.2}×", d / f))
        );
        if *n >= 100 {
            for (k, f) in fits.iter_mut().enumerate() {
                if let Some(v) = t[k] {
                    f.1.push((*n as f64, v));
                }
            }
        }
    }
    if let Some(v) = median_ns("step", 1_000) {
        println!("(N = 1000: {:.1}× real time from the step time alone: 16 667 µs of simulated time per step)", H * 1e9 / v);
    }
    for (g, pts) in &fits {
        match exponent(pts) {
            Some(e) => println!(
                "exponent of {g} time vs N (log-log least squares over N = {}): {e:.3}",
                pts.iter().map(|p| format!("{}", p.0)).collect::<Vec<_>>().join(", ")
            ),
            None => println!("exponent of {g}: not enough sizes measured"),
        }
    }
    // Local slopes, to see where the cost per element changes.
    for (g, pts) in &fits {
        let local: Vec<String> = pts.windows(2).map(|w| format!("{}→{}: {:.2}", w[0].0, w[1].0, (w[1].1 / w[0].1).ln() / (w[1].0 / w[0].0).ln())).collect();
        if !local.is_empty() {
            println!("local exponents of {g}: {}", local.join(", "));
        }
    }
}
