//! The adaptive integrators (issue 15): Dormand–Prince 5(4) with dense output
//! and TR-BDF2, each against a closed form (docs/verification.md, "Adaptive
//! integrators"). Run with `--nocapture` to see the measured values.
//!
//! Error bounds come from the method: each accepted step keeps its local
//! error estimate within `√(2n)·(atol + rtol·|z|)` per component (the RMS
//! test), and on the oscillators used here (ω = 1, so `(x, v)` is the
//! energy metric) the exact flow is an isometry (undamped) or a contraction
//! (damped), so the global error is at most the sum of the local errors
//! committed: `N_steps · √(2n)·(atol + rtol·z_max)`.

use std::f64::consts::{PI, TAU};

use bevy_rapier_cable::integrate::{
    AdaptiveError, AdaptiveStats, DenseSystem, DormandPrince, IntegrateError, Integrator, Pendulum, Scheme, SecondOrderSystem, State, StepStats, Substeps,
    SystemError, TrBdf2,
};

// ---------------------------------------------------------------- helpers

/// `ẍ + 2ζω ẋ + ω² x = 0` (ζ < 1) from `(x0, v0)`: `(x(t), v(t))`.
fn damped_exact(omega: f64, zeta: f64, (x0, v0): (f64, f64), t: f64) -> (f64, f64) {
    let wd = omega * (1.0 - zeta * zeta).sqrt();
    let decay = (-zeta * omega * t).exp();
    let (s, c) = (wd * t).sin_cos();
    let x = decay * (x0 * c + (v0 + zeta * omega * x0) / wd * s);
    let v = decay * (v0 * c - (omega * omega * x0 + zeta * omega * v0) / wd * s);
    (x, v)
}

fn damped_oscillator(omega: f64, zeta: f64) -> DenseSystem {
    DenseSystem::oscillator(1.0, 2.0 * zeta * omega, omega * omega).expect("valid oscillator")
}

/// The per-step local error allowance of the RMS test for `n` coordinates
/// with components bounded by `z_max`.
fn local_allowance(n: usize, rtol: f64, atol: f64, z_max: f64) -> f64 {
    (2.0 * n as f64).sqrt() * (atol + rtol * z_max)
}

/// Largest `max(|Δx|, |Δv|)` at step ends and at dense-output samples
/// (θ = 1/4, 1/2, 3/4 of every step) of an adaptive run on the oscillator.
struct Run {
    end_error: f64,
    max_step_error: f64,
    max_dense_error: f64,
    stats: AdaptiveStats,
}

/// Runs an adaptive integrator step by step on the oscillator with ω, ζ from
/// `(1, 0)` to `t_end`, comparing with the closed form.
macro_rules! run_oscillator {
    ($solver:expr, $omega:expr, $zeta:expr, $t_end:expr) => {{
        let (omega, zeta, t_end) = ($omega, $zeta, $t_end);
        let mut solver = $solver;
        let mut sys = damped_oscillator(omega, zeta);
        let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
        let mut run = Run { end_error: 0.0, max_step_error: 0.0, max_dense_error: 0.0, stats: AdaptiveStats::default() };
        let err = |t: f64, x: f64, v: f64| {
            let (xe, ve) = damped_exact(omega, zeta, (1.0, 0.0), t);
            (x - xe).abs().max((v - ve).abs())
        };
        while state.t < t_end {
            run.stats += solver.step(&mut sys, &mut state, t_end).expect("step");
            run.max_step_error = run.max_step_error.max(err(state.t, state.q[0], state.v[0]));
            let (t0, h) = solver.last_step().expect("a step");
            for theta in [0.25, 0.5, 0.75] {
                let (mut q, mut v) = ([0.0], [0.0]);
                solver.dense_output(t0 + theta * h, &mut q, &mut v).expect("inside the step");
                run.max_dense_error = run.max_dense_error.max(err(t0 + theta * h, q[0], v[0]));
            }
        }
        assert_eq!(state.t, t_end, "lands on t_end exactly");
        run.end_error = err(state.t, state.q[0], state.v[0]);
        run
    }};
}

/// Least-squares slope of `ln y` against `ln x`.
fn log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

// ------------------------------------------------- Dormand–Prince 5(4)

#[test]
fn dopri_oscillators_error_falls_with_tolerance_order_five() {
    for (zeta, name) in [(0.0, "undamped"), (0.1, "damped zeta = 0.1")] {
        let t_end = 10.0 * TAU;
        let mut points = Vec::new();
        let mut previous = f64::INFINITY;
        for k in [4, 5, 6, 7, 8, 9, 10] {
            let tol = 10f64.powi(-k);
            let run = run_oscillator!(DormandPrince::new(tol, tol).expect("valid"), 1.0, zeta, t_end);
            let s = run.stats;
            let bound = (s.accepted_steps as f64) * local_allowance(1, tol, tol, 1.0);
            println!(
                "DOPRI5 {name}, tol {tol:.0e}: {} accepted, {} rejected, {} evaluations; error at t_end {:.2e}, worst at step ends {:.2e}, dense {:.2e} (bound {bound:.2e})",
                s.accepted_steps, s.rejected_steps, s.residual_evals, run.end_error, run.max_step_error, run.max_dense_error
            );
            // FSAL: six evaluations per attempt, one for the starting step.
            assert_eq!(s.residual_evals, 6 * (s.accepted_steps + s.rejected_steps) + 1);
            assert_eq!(s.solves, s.residual_evals);
            assert!(run.max_step_error <= bound, "global error within the sum of local allowances");
            assert!(run.max_dense_error <= bound, "dense output within the same budget");
            // The continuous extension is 4th order: its own error is of the
            // size of the embedded 4th-order estimate, at most one step's
            // allowance on top of the error at the step ends.
            assert!(run.max_dense_error <= run.max_step_error + local_allowance(1, tol, tol, 1.0));
            assert!(run.end_error < previous, "error falls with the tolerance");
            previous = run.end_error;
            points.push((s.residual_evals as f64, run.max_step_error));
        }
        let slope = log_slope(&points[2..]);
        println!("DOPRI5 {name}: slope of ln(error) against ln(evaluations), tol 1e-6..1e-10: {slope:.2}");
        assert!((-slope - 5.0).abs() < 0.5, "order 5 per evaluation: {slope}");
    }
}

/// Accuracy at equal work: DOPRI5 at `tol` against RK4 and generalized-α
/// with about the same number of evaluations, on a system from `(q0, 0)`
/// over `t_end`, error measured against `exact` at `t_end`.
fn equal_work<S: SecondOrderSystem>(name: &str, sys: &mut S, q0: f64, t_end: f64, exact: (f64, f64), tol: f64) -> (f64, f64, f64) {
    let error = |s: &State| (s.q[0] - exact.0).abs().max((s.v[0] - exact.1).abs());
    let mut state = State::new(sys, 0.0, vec![q0], vec![0.0]).expect("state");
    let stats = DormandPrince::new(tol, tol).expect("valid").integrate(sys, &mut state, t_end).expect("integrate");
    let (e_dp, budget) = (error(&state), stats.residual_evals);
    let fixed = |scheme: Scheme, sys: &mut S, per_step: usize| {
        let steps = budget / per_step;
        let h = t_end / steps as f64;
        let mut integ = Integrator::new(scheme).with_substeps(Substeps::Unchecked(1));
        let mut state = State::new(sys, 0.0, vec![q0], vec![0.0]).expect("state");
        let mut total = StepStats::default();
        for _ in 0..steps {
            total += integ.step(sys, &mut state, h).expect("step");
        }
        (error(&state), total.residual_evals, steps)
    };
    let (e_rk, n_rk, steps_rk) = fixed(Scheme::Rk4, sys, 4);
    // Generalized-α on these smooth problems: about 2 residuals per step
    // (measured below and reported).
    let (e_ga, n_ga, steps_ga) = fixed(Scheme::GeneralizedAlpha { rho_inf: 0.0 }, sys, 2);
    println!(
        "{name}: DOPRI5 tol {tol:.0e}: {budget} evaluations, error {e_dp:.2e}; RK4 {steps_rk} steps, {n_rk} evaluations, error {e_rk:.2e}; generalized-alpha {steps_ga} steps, {n_ga} residuals, error {e_ga:.2e}"
    );
    assert!(n_rk <= budget && n_ga <= 2 * budget);
    (e_dp, e_rk, e_ga)
}

/// Complete elliptic integral of the first kind K(m) = π / (2 AGM(1, √(1−m))).
fn elliptic_k(m: f64) -> f64 {
    // The AGM converges quadratically: 12 means reach round-off for any
    // m < 1 − 1e-12 (a fixed count: a test on |a − b| can cycle at the
    // last bit).
    let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
    for _ in 0..12 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (2.0 * a)
}

#[test]
fn dopri_beats_rk4_and_generalized_alpha_per_evaluation() {
    for tol in [1e-6, 1e-9] {
        // Oscillator ω = 1 over ten periods: back at (1, 0).
        let mut osc = damped_oscillator(1.0, 0.0);
        let (dp, rk, ga) = equal_work("oscillator", &mut osc, 1.0, 10.0 * TAU, (1.0, 0.0), tol);
        assert!(dp < rk && dp < ga);
        // Pendulum at 150°, g/l = 9.81 s⁻², over five periods
        // T = 4 K(sin²(θ0/2)) / √(g/l): back at (θ0, 0).
        let mut p = Pendulum::new(9.81, 1.0);
        let theta0 = 150f64.to_radians();
        let period = 4.0 * elliptic_k((theta0 / 2.0).sin().powi(2)) / p.natural_frequency();
        let (dp, rk, ga) = equal_work("pendulum 150 deg", &mut p, theta0, 5.0 * period, (theta0, 0.0), tol);
        assert!(dp < rk && dp < ga);
    }
}

// --------------------------------------------------------------- TR-BDF2

#[test]
fn trbdf2_oscillator_fixed_step_order_two_and_adaptive_accuracy() {
    // Fixed steps (rtol so loose that every step is accepted, max step = h):
    // the global error at t = 2π falls by 4 per halving.
    let t_end = TAU;
    let mut errors = Vec::new();
    for steps in [100, 200, 400, 800] {
        let h = t_end / steps as f64;
        let solver = TrBdf2::new(1e6, 1e6).and_then(|s| s.with_initial_step(h)).and_then(|s| s.with_max_step(h)).expect("valid");
        let run = run_oscillator!(solver, 1.0, 0.0, t_end);
        assert_eq!(run.stats.accepted_steps, steps);
        assert_eq!(run.stats.rejected_steps, 0);
        errors.push(run.end_error);
    }
    let ratios: Vec<f64> = errors.windows(2).map(|w| w[0] / w[1]).collect();
    let printed: Vec<String> = errors.iter().map(|e| format!("{e:.3e}")).collect();
    println!("TR-BDF2 fixed step on the oscillator, h = T/100..T/800: errors {printed:?}, ratios {ratios:.4?}");
    for r in &ratios[1..] {
        assert!((r - 4.0).abs() < 0.05 * 4.0, "second order: ratio {r}");
    }

    for (zeta, name) in [(0.0, "undamped"), (0.1, "damped zeta = 0.1")] {
        let mut previous = f64::INFINITY;
        let mut points = Vec::new();
        for k in [3, 4, 5, 6, 7] {
            let tol = 10f64.powi(-k);
            let run = run_oscillator!(TrBdf2::new(tol, tol).expect("valid"), 1.0, zeta, 10.0 * TAU);
            let s = run.stats;
            let bound = (s.accepted_steps as f64) * local_allowance(1, tol, tol, 1.0);
            println!(
                "TR-BDF2 {name}, tol {tol:.0e}: {} accepted, {} rejected, {} residuals, {} Newton iterations; error at t_end {:.2e}, worst at step ends {:.2e}, dense {:.2e} (bound {bound:.2e})",
                s.accepted_steps, s.rejected_steps, s.residual_evals, s.newton_iterations, run.end_error, run.max_step_error, run.max_dense_error
            );
            assert!(run.max_step_error <= bound);
            assert!(run.max_dense_error <= bound);
            assert!(run.end_error < previous);
            previous = run.end_error;
            points.push((s.accepted_steps as f64, run.max_step_error));
        }
        let slope = log_slope(&points);
        println!("TR-BDF2 {name}: slope of ln(error) against ln(steps): {slope:.2}");
        assert!((-slope - 2.0).abs() < 0.5, "order 2: {slope}");
    }
}

#[test]
fn trbdf2_pendulum_energy_is_dissipated_within_the_tolerance() {
    let mut p = Pendulum::new(9.81, 1.0);
    let theta0 = 150f64.to_radians();
    let period = 4.0 * elliptic_k((theta0 / 2.0).sin().powi(2)) / p.natural_frequency();
    let mut previous = f64::INFINITY;
    for tol in [1e-4, 1e-6, 1e-8] {
        let mut state = State::new(&mut p, 0.0, vec![theta0], vec![0.0]).expect("state");
        let e0 = p.energy(theta0, 0.0);
        let mut solver = TrBdf2::new(tol, tol).expect("valid");
        let (mut total, mut worst_rise, mut last) = (AdaptiveStats::default(), 0.0f64, e0);
        while state.t < 10.0 * period {
            total += solver.step(&mut p, &mut state, 10.0 * period).expect("step");
            let e = p.energy(state.q[0], state.v[0]);
            worst_rise = worst_rise.max(e - last);
            last = e;
        }
        let drift = (last - e0) / e0;
        let phase = (state.q[0] - theta0).abs().max(state.v[0].abs());
        // The exact flow keeps E, so the energy error is the sum of what
        // each step's local error changes it by: at most
        // N · max|∇E| · √2 (atol + rtol z_max), with ∇E = ((g/l) sin θ, θ̇),
        // |θ̇| ≤ √(2 E0) = z_max.
        let z_max = (2.0 * e0).sqrt();
        let grad = (p.natural_frequency().powi(4) + 2.0 * e0).sqrt();
        let bound = total.accepted_steps as f64 * grad * local_allowance(1, tol, tol, z_max) / e0;
        println!(
            "TR-BDF2 pendulum 150 deg, tol {tol:.0e}, 10 periods: {} steps, {} rejected ({} Newton failures), {} Newton iterations; energy drift {drift:.2e} (bound {bound:.1e}), worst rise per step {worst_rise:.1e}, state error after 10 periods {phase:.2e}",
            total.accepted_steps, total.rejected_steps, total.newton_failures, total.newton_iterations
        );
        assert!(drift < 0.0 && -drift <= bound, "dissipative, within the sum of local errors");
        assert!(-drift < previous, "the drift falls with the tolerance");
        previous = -drift;
    }
}

// ------------------------------------------------------------------ stiff

/// Two coordinates mixing a soft undamped mode (1 rad/s) and a stiff mode
/// (10⁴ rad/s, ζ = 0.5) through a 30° rotation: `K = R diag(1, 10⁸) Rᵀ`,
/// `C = R diag(0, 10⁴) Rᵀ`, `M = I`.
fn stiff_pair() -> (DenseSystem, [[f64; 2]; 2]) {
    let (s, c) = 30f64.to_radians().sin_cos();
    let r = [[c, -s], [s, c]];
    let modal = |d: [f64; 2]| -> Vec<Vec<f64>> { (0..2).map(|i| (0..2).map(|j| r[i][0] * d[0] * r[j][0] + r[i][1] * d[1] * r[j][1]).collect()).collect() };
    let sys = DenseSystem::from_rows(&[vec![1.0, 0.0], vec![0.0, 1.0]], &modal([0.0, 1e4]), &modal([1.0, 1e8])).expect("valid");
    (sys, r)
}

/// The stability radius of DOPRI5 along the direction `angle` (rad) of the
/// complex plane: the first `r` where `|R(r e^{iφ})| = 1` for its stability
/// polynomial `R(z) = Σ_{k≤5} z^k/k! + z⁶/600`, by scanning then bisection.
fn dopri_stability_radius(angle: f64) -> f64 {
    let amplification = |r: f64| {
        let (mut re, mut im) = (0.0, 0.0);
        let mut factorial = 1.0;
        for k in 0..=6 {
            if k > 0 {
                factorial *= k as f64;
            }
            let c = if k == 6 { 1.0 / 600.0 } else { 1.0 / factorial };
            let (s, co) = (k as f64 * angle).sin_cos();
            re += c * r.powi(k) * co;
            im += c * r.powi(k) * s;
        }
        (re * re + im * im).sqrt()
    };
    let mut hi = 0.01;
    while amplification(hi) <= 1.0 {
        hi += 0.01;
    }
    let mut lo = hi - 0.01;
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if amplification(mid) <= 1.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[test]
fn stiff_pair_dopri_is_stability_limited_trbdf2_is_not() {
    let (omega_s, zeta_s) = (1e4f64, 0.5f64);
    let t_end = TAU;
    // Modal start: soft mode at 1, stiff mode displaced by 1e-4.
    let modal0 = [1.0, 1e-4];
    // The stiff eigenvalues ω(−ζ ± i√(1 − ζ²)) lie at 120° from the real axis.
    let radius = dopri_stability_radius((-zeta_s).acos());
    let stability_steps = t_end * omega_s / radius;
    println!("DOPRI5 stability radius at 120 deg: {radius:.4}; steps at the limit over 2 pi: {stability_steps:.0}");
    let mut dopri_steps = Vec::new();
    for (name, tol) in [("DOPRI5", 1e-3), ("DOPRI5", 1e-6), ("TR-BDF2", 1e-6)] {
        let (mut sys, r) = stiff_pair();
        let q0 = vec![r[0][0] * modal0[0] + r[0][1] * modal0[1], r[1][0] * modal0[0] + r[1][1] * modal0[1]];
        let mut state = State::new(&mut sys, 0.0, q0, vec![0.0, 0.0]).expect("state");
        let stats = if name == "DOPRI5" {
            DormandPrince::new(tol, tol).expect("valid").integrate(&mut sys, &mut state, t_end)
        } else {
            TrBdf2::new(tol, tol).expect("valid").integrate(&mut sys, &mut state, t_end)
        }
        .expect("integrate");
        // Back to modal coordinates: Rᵀ q.
        let modal = |x: &[f64], k: usize| r[0][k] * x[0] + r[1][k] * x[1];
        let (x_soft, v_soft) = (modal(&state.q, 0), modal(&state.v, 0));
        let (xe, ve) = damped_exact(1.0, 0.0, (modal0[0], 0.0), t_end);
        let soft_error = (x_soft - xe).abs().max((v_soft - ve).abs());
        let stiff_left = modal(&state.q, 1).abs().max(modal(&state.v, 1).abs() / omega_s);
        // z_max = 1: the soft mode's amplitude, and the stiff velocity's
        // peak is below ω_s · 1e-4 = 1 m/s.
        let bound = stats.accepted_steps as f64 * local_allowance(2, tol, tol, 1.0);
        println!(
            "stiff pair, {name}, tol {tol:.0e}, t = 2 pi: {} accepted, {} rejected, {} residuals, {} solves, {} Newton iterations; soft-mode error {soft_error:.2e} (bound {bound:.1e}); stiff mode left {stiff_left:.1e} (exact {:.1e})",
            stats.accepted_steps,
            stats.rejected_steps,
            stats.residual_evals,
            stats.solves,
            stats.newton_iterations,
            damped_exact(omega_s, zeta_s, (modal0[1], 0.0), t_end).0.abs()
        );
        assert!(soft_error <= bound, "the soft mode meets the tolerance");
        assert!(stiff_left <= tol, "the stiff mode has decayed");
        if name == "DOPRI5" {
            // Stability-limited: within a factor 2 of the stability limit,
            // whatever the tolerance.
            assert!(stats.accepted_steps as f64 >= 0.5 * stability_steps);
            dopri_steps.push(stats.accepted_steps as f64);
        } else {
            // L-stable: the step follows the soft mode's accuracy only.
            assert!(stats.accepted_steps as f64 <= 0.05 * dopri_steps[1]);
        }
    }
    // 1000 times the tolerance would change a non-stiff DOPRI5 run's steps
    // by 1000^(1/5) ≈ 4; here they change by less than 10 %.
    assert!((dopri_steps[0] / dopri_steps[1] - 1.0).abs() < 0.1, "{dopri_steps:?}");
}

// ----------------------------------------------------------------- errors

/// `ẍ = x²`: from `x(0) = 1`, `v(0) = 12/√6³` the solution is
/// `x = 6/(t* − t)²`, which blows up at `t* = √6` s.
struct BlowUp;

impl SecondOrderSystem for BlowUp {
    fn dof(&self) -> usize {
        1
    }

    fn residual(&mut self, _t: f64, q: &[f64], _v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        r[0] = a[0] - q[0] * q[0];
        Ok(())
    }

    fn solve_tangent(&mut self, _t: f64, q: &[f64], _v: &[f64], _a: &[f64], _c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        x[0] = b[0] / (1.0 - 2.0 * c_q * q[0]);
        Ok(())
    }
}

#[test]
fn errors_are_typed_and_name_the_time() {
    for (rtol, atol) in [(0.0, 1e-6), (-1e-6, 1e-6), (f64::NAN, 1e-6), (1e-6, -1.0), (1e-6, f64::INFINITY)] {
        let dp = DormandPrince::new(rtol, atol);
        let tr = TrBdf2::new(rtol, atol);
        println!("tolerances ({rtol}, {atol}): {}", dp.as_ref().expect_err("refused"));
        assert!(matches!(dp, Err(AdaptiveError::InvalidParameter { .. })));
        assert!(matches!(tr, Err(AdaptiveError::InvalidParameter { .. })));
    }
    assert!(matches!(DormandPrince::new(1e-6, 1e-6).and_then(|s| s.with_initial_step(0.0)), Err(AdaptiveError::InvalidParameter { .. })));

    let mut sys = damped_oscillator(1.0, 0.0);
    let mut state = State::new(&mut sys, 1.0, vec![1.0], vec![0.0]).expect("state");
    let mut dp = DormandPrince::new(1e-6, 1e-6).expect("valid");
    let mut tr = TrBdf2::new(1e-6, 1e-6).expect("valid");
    for t_end in [0.5, f64::NAN] {
        assert!(matches!(dp.integrate(&mut sys, &mut state, t_end), Err(AdaptiveError::InvalidEnd { t: 1.0, .. })));
        assert!(matches!(tr.integrate(&mut sys, &mut state, t_end), Err(AdaptiveError::InvalidEnd { t: 1.0, .. })));
    }
    assert_eq!(dp.integrate(&mut sys, &mut state, 1.0).expect("nothing to do"), AdaptiveStats::default());
    let e = dp.dense_output(1.0, &mut [0.0], &mut [0.0]).expect_err("no step yet");
    println!("{e}");
    assert!(matches!(e, AdaptiveError::OutsideStep { .. }));
    let mut stepped = state.clone();
    tr.step(&mut sys, &mut stepped, 2.0).expect("step");
    let (t0, h) = tr.last_step().expect("a step");
    assert!(matches!(tr.dense_output(t0 + 2.0 * h, &mut [0.0], &mut [0.0]), Err(AdaptiveError::OutsideStep { .. })));
    let e = tr.dense_output(t0, &mut [0.0], &mut [0.0; 2]).expect_err("wrong length");
    println!("{e}");
    assert!(matches!(e, AdaptiveError::Integrate(IntegrateError::DimensionMismatch { what: "dense output v", expected: 1, got: 2, .. })));
    // Component tolerances: 2n of them.
    let mut bad = DormandPrince::new(1e-6, 1e-6).and_then(|s| s.with_atol_components(vec![1e-6])).expect("checked at the step");
    assert!(matches!(bad.integrate(&mut sys, &mut state, 2.0), Err(AdaptiveError::InvalidParameter { .. })));

    let mut nan = state.clone();
    nan.v[0] = f64::NAN;
    assert!(matches!(dp.integrate(&mut sys, &mut nan, 2.0), Err(AdaptiveError::NonFinite { t: 1.0 })));
    assert!(matches!(tr.integrate(&mut sys, &mut nan, 2.0), Err(AdaptiveError::NonFinite { t: 1.0 })));

    // Too many attempts: ten steps cannot cover 100 periods at 1e-10.
    let mut few = DormandPrince::new(1e-10, 1e-10).and_then(|s| s.with_max_steps(10)).expect("valid");
    let e = few.integrate(&mut sys, &mut state.clone(), 100.0 * TAU).expect_err("too many");
    println!("{e}");
    assert!(matches!(e, AdaptiveError::TooManySteps { max_steps: 10, .. }));

    // A singular mass matrix: the system error, with its time.
    let mut singular = DenseSystem::oscillator(0.0, 0.0, 1.0).expect("valid");
    let mut s0 = State { t: 0.0, q: vec![1.0], v: vec![0.0], a: vec![0.0], a_hat: vec![0.0] };
    let e = DormandPrince::new(1e-6, 1e-6).expect("valid").integrate(&mut singular, &mut s0, 1.0).expect_err("singular");
    println!("{e}");
    assert!(matches!(e, AdaptiveError::Integrate(IntegrateError::System { source: SystemError::Singular { .. }, .. })));

    // A load that turns NaN at t = 1 s: every trial step across it goes
    // non-finite, the step shrinks to nothing, and the error names the
    // last good time, just before 1 s.
    for name in ["DOPRI5", "TR-BDF2"] {
        let mut poisoned = DenseSystem::oscillator(1.0, 0.0, 1.0).expect("valid").with_force(|t, f| {
            if t > 1.0 {
                f[0] = f64::NAN;
            }
        });
        let mut state = State::new(&mut poisoned, 0.0, vec![1.0], vec![0.0]).expect("state");
        let result = if name == "DOPRI5" {
            DormandPrince::new(1e-6, 1e-6).expect("valid").integrate(&mut poisoned, &mut state, 2.0)
        } else {
            TrBdf2::new(1e-6, 1e-6).expect("valid").integrate(&mut poisoned, &mut state, 2.0)
        };
        let e = result.expect_err("non-finite");
        println!("{name}, load NaN after 1 s: {e}");
        match e {
            AdaptiveError::NonFinite { t } => assert!(t <= 1.0 && 1.0 - t < 1e-12 && t == state.t, "{t}"),
            other => panic!("{name}: expected a non-finite error, got {other}"),
        }
    }

    // Step underflow at the blow-up t* = √6 s.
    let t_star = 6f64.sqrt();
    for name in ["DOPRI5", "TR-BDF2"] {
        let mut sys = BlowUp;
        let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![12.0 / t_star.powi(3)]).expect("state");
        let result = if name == "DOPRI5" {
            DormandPrince::new(1e-8, 1e-8).expect("valid").integrate(&mut sys, &mut state, 10.0)
        } else {
            TrBdf2::new(1e-8, 1e-8).expect("valid").integrate(&mut sys, &mut state, 10.0)
        };
        let e = result.expect_err("blows up");
        println!("{name} on x'' = x^2 (blow-up at {t_star:.12} s): {e}; x = {:.3e}", state.q[0]);
        match e {
            AdaptiveError::StepUnderflow { t, h } => {
                assert_eq!(t, state.t, "the state is the last accepted one");
                assert!(t < t_star && t_star - t < 1e-3, "{t}");
                assert!(h < 10.0 * f64::EPSILON * t_star * 1.01);
            }
            other => panic!("{name}: expected a step underflow, got {other}"),
        }
    }
}

// ------------------------------------------------------------ rope chain

/// TR-BDF2 through the chain's own O(n) tangent solve: a 50 m rope (N = 20,
/// μ = 1.6 kg/m, EA = 1.6e7 N, stiffness-proportional damping τ = 0.02 s,
/// the default tension-only axial law, which starts at its kink and stays
/// taut) pinned at the top, released unstretched with a 5 t payload, settles to
/// its static stretch. The payload bounce (ω ≈ 8 rad/s, ζ = ωτ/2 ≈ 0.08) has
/// decayed to e^{−ζω·30 s} ≈ 5e-9 of its 0.15 m amplitude by t = 30 s; the
/// element modes are overdamped with rates up to τ·4EA/(μL_e²) ≈ 1.3e5 s⁻¹,
/// which hold an explicit method at steps of ≈ 3/1.3e5 s.
#[test]
fn trbdf2_steps_a_rope_chain_with_its_own_solve_to_the_static_stretch() {
    use bevy_rapier_cable::cable::{BaseMotion, BaseState, Cable, LumpedBody, RopeBuilder, RopeEnd, RopeSection, RopeStart};
    use glam::{DMat3, DVec3};
    let (l, n, mu, ea, m, g, tau) = (50.0f64, 20usize, 1.6f64, 1.6e7f64, 5000.0f64, 9.81f64, 0.02f64);
    let build = || {
        let body = LumpedBody::sphere(m, 0.5, DVec3::new(0.0, -l - 0.5, 0.0));
        let model = RopeBuilder::new(l, n, RopeSection { linear_density: mu, ea, ei: 50.0, ei2: 50.0, gj: 35.0, min_breaking_load: 0.0 }, 0.02)
            .damping(tau)
            .start(RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, DVec3::ZERO))))
            .end(RopeEnd::Body { body, anchor: DVec3::new(0.0, 0.5, 0.0), clamp: false })
            .build()
            .expect("valid rope");
        Cable::new(model, Scheme::default()).expect("cable")
    };
    let mut cable = build();
    let y0 = cable.nodes()[n].y;
    let mut tr = TrBdf2::new(1e-6, 1e-6).expect("valid");
    let stats = tr.integrate(&mut cable.model.chain, &mut cable.state, 30.0).expect("integrate");
    cable.refresh();
    let drop = y0 - cable.nodes()[n].y;
    // Discrete chain (element mass at mid-length, each joint carries the
    // elements below it; the pinned start is the chain's exact base joint):
    // δ = m g L/EA + μ g L_e² N(N+1)/(2 EA).
    let le = l / n as f64;
    let delta = m * g * l / ea + mu * g * le * le * (n * (n + 1)) as f64 / (2.0 * ea);
    let speed = cable.node_velocities()[n].length();
    println!(
        "rope + 5 t payload, TR-BDF2 tol 1e-6 to 30 s: {} accepted, {} rejected ({} Newton failures), {} Newton iterations, {} solves; stretch {drop:.9} m vs {delta:.9} m ({:+.2e} m), payload speed {speed:.1e} m/s",
        stats.accepted_steps,
        stats.rejected_steps,
        stats.newton_failures,
        stats.newton_iterations,
        stats.solves,
        drop - delta
    );
    // DOPRI5 on the first 0.2 s of the same release, for the step count.
    let mut explicit = build();
    let dp = DormandPrince::new(1e-6, 1e-6).expect("valid").integrate(&mut explicit.model.chain, &mut explicit.state, 0.2).expect("integrate");
    println!("same rope, DOPRI5 tol 1e-6, first 0.2 s only: {} accepted, {} rejected, {} evaluations", dp.accepted_steps, dp.rejected_steps, dp.residual_evals);
    // The static state is a fixed point of TR-BDF2; what is left is the
    // decaying bounce, within the relative tolerance of the stretch and of
    // the bounce's peak speed ω δ ≈ 1.2 m/s.
    assert!((drop - delta).abs() <= 1e-6 * delta, "{drop} vs {delta}");
    assert!(speed <= 1e-6 * 8.0 * delta);
    assert_eq!(stats.newton_failures, 0);
    assert!(dp.accepted_steps > 10 * stats.accepted_steps, "explicit: stability-limited by the overdamped element modes");
}

#[test]
fn component_tolerances_act_per_component() {
    let run = |solver: DormandPrince| {
        let mut solver = solver;
        let mut sys = damped_oscillator(1.0, 0.0);
        let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
        let stats = solver.integrate(&mut sys, &mut state, TAU).expect("integrate");
        (stats, state)
    };
    let scalar = run(DormandPrince::new(1e-8, 1e-8).expect("valid"));
    let same = run(DormandPrince::new(1e-8, 1.0).and_then(|s| s.with_atol_components(vec![1e-8, 1e-8])).expect("valid"));
    assert_eq!(scalar, same, "the component list replaces the scalar");
    // A loose absolute tolerance on one component needs fewer steps (with
    // rtol = 0 only the absolute part remains).
    let tight = run(DormandPrince::new(1e-12, 0.0).and_then(|s| s.with_atol_components(vec![1e-8, 1e-8])).expect("valid"));
    let loose = run(DormandPrince::new(1e-12, 0.0).and_then(|s| s.with_atol_components(vec![1e-8, 1e-2])).expect("valid"));
    println!("component atol (1e-8, 1e-8): {} steps; (1e-8, 1e-2): {} steps", tight.0.accepted_steps, loose.0.accepted_steps);
    assert!(loose.0.accepted_steps < tight.0.accepted_steps);
}

/// Both leave `state.a` consistent with `(t, q, v)` (DOPRI5 exactly: its
/// FSAL stage; TR-BDF2 to its Newton tolerance), so a fixed-step scheme can
/// take over, and the state is at `t_end` exactly.
#[test]
fn adaptive_steps_leave_a_consistent_acceleration() {
    let omega2 = 4.0;
    let mut sys = DenseSystem::oscillator(1.0, 0.3, omega2).expect("valid");
    let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.5]).expect("state");
    DormandPrince::new(1e-8, 1e-8).expect("valid").integrate(&mut sys, &mut state, 1.0).expect("integrate");
    assert_eq!(state.t, 1.0);
    assert_eq!(state.a[0], -0.3 * state.v[0] - omega2 * state.q[0]);
    assert_eq!(state.a_hat, state.a);
    TrBdf2::new(1e-8, 1e-8).expect("valid").integrate(&mut sys, &mut state, 2.0).expect("integrate");
    assert_eq!(state.t, 2.0);
    let consistent = -0.3 * state.v[0] - omega2 * state.q[0];
    // Newton stops once its correction is below 1e-10 m in q (c_q·|Δa|,
    // c_q = (γh/2)²); on this linear system its second iteration is exact.
    println!("TR-BDF2 acceleration residual {:.1e} m/s²", (state.a[0] - consistent).abs());
    assert!((state.a[0] - consistent).abs() <= 1e-9 * (1.0 + consistent.abs()));
    // At t = 2 s against the closed form (ω = 2 rad/s, ζ = 0.075).
    let (x, v) = damped_exact(2.0, 0.075, (1.0, 0.5), 2.0);
    let error = (state.q[0] - x).abs().max((state.v[0] - v).abs());
    println!("after DOPRI5 to 1 s and TR-BDF2 to 2 s: error {error:.1e}");
    Integrator::default().step(&mut sys, &mut state, 0.01).expect("a fixed step follows");
    assert_eq!(state.t, 2.01);
}
