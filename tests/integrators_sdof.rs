//! The integrators on the undamped oscillator (verification-cases §8), a
//! stiff oscillator, the large-amplitude pendulum and a damped 2-DOF system.
//!
//! Every §8 number is checked twice: against the printed table (within half a
//! unit of its last printed digit) and against the scheme's own recurrence or
//! amplification matrix, written independently here, to 1e-12 relative.
//! Run with `--nocapture` to see the measured values.

use std::f64::consts::{PI, TAU};

use bevy_rapier_cable::integrate::{
    stability_limit, DenseSystem, IntegrateError, Integrator, NewtonSettings, Pendulum, Scheme, SecondOrderSystem, State, StepStats, Substeps, SystemError,
};

// ---------------------------------------------------------------- helpers

fn oscillator(omega: f64) -> DenseSystem {
    DenseSystem::oscillator(1.0, 0.0, omega * omega).expect("valid oscillator")
}

/// Explicit schemes with one checked sub-step where the step is admissible,
/// unchecked where the scheme is unstable for every step (Euler, Heun).
fn integrator(scheme: Scheme) -> Integrator {
    let substeps = match scheme {
        Scheme::ExplicitEuler | Scheme::ImprovedEuler => Substeps::Unchecked(1),
        Scheme::SymplecticEuler | Scheme::Rk4 => Substeps::Fixed(1),
        _ => Substeps::Auto,
    };
    Integrator::new(scheme).with_substeps(substeps)
}

/// Half a unit in the last printed place of a decimal like `-3.30e-4`.
fn half_ulp(printed: &str) -> f64 {
    let (mantissa, exponent) = match printed.split_once('e') {
        Some((m, e)) => (m, e.parse::<i32>().expect("exponent")),
        None => (printed, 0),
    };
    let decimals = mantissa.split_once('.').map_or(0, |(_, d)| d.len()) as i32;
    0.5 * 10f64.powi(exponent - decimals)
}

/// Asserts `value` rounds to the printed table entry.
fn assert_printed(what: &str, value: f64, printed: &str) {
    // A trailing `*` marks a §8 entry that is one unit off in its last digit
    // (see the comment at the entry); it is accepted within one unit.
    let (digits, slack) = match printed.strip_suffix('*') {
        Some(d) => (d, 2.0),
        None => (printed, 1.0),
    };
    let reference: f64 = digits.parse().expect("table entry");
    let err = (value - reference).abs();
    println!("  {what:<48} {value:+.9e}  table {printed:>10}  |err| {err:.2e}");
    assert!(err <= slack * half_ulp(digits) * (1.0 + 1e-9), "{what}: {value} does not round to {printed}");
}

/// `max(|Δx|, |Δv|/ω) / max(|x|, |v|/ω)`.
fn rel_err(a: (f64, f64), b: (f64, f64), omega: f64) -> f64 {
    let d = (a.0 - b.0).abs().max((a.1 - b.1).abs() / omega);
    d / b.0.abs().max(b.1.abs() / omega)
}

fn run_oscillator(scheme: &Scheme, omega: f64, h: f64, steps: usize) -> Vec<(f64, f64)> {
    let mut sys = oscillator(omega);
    let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("initial state");
    let mut integ = integrator(scheme.clone());
    (0..steps)
        .map(|_| {
            integ.step(&mut sys, &mut state, h).expect("step");
            (state.q[0], state.v[0])
        })
        .collect()
}

// ------------------------------------------- independent reference algebra

/// The recurrences as published, for `ẍ + ω² x = 0`.
#[derive(Clone, Copy, Debug)]
enum Reference {
    /// Chung–Hulbert: `(1−α_m) a₁ + α_m a₀ + ω²[(1−α_f) x₁ + α_f x₀] = 0` with
    /// the Newmark update on a (HHT: α_m = 0, α_f = −α; Newmark: both 0).
    ChungHulbert { am: f64, af: f64, beta: f64, gamma: f64 },
    /// Wilson-θ in Bathe's effective-stiffness form.
    WilsonBathe { theta: f64 },
    /// `z₁ = A z` with a 2×2 amplification matrix on `(x, v)`.
    Matrix,
}

fn chung_hulbert(rho: f64) -> Reference {
    let am = (2.0 * rho - 1.0) / (rho + 1.0);
    let af = rho / (rho + 1.0);
    Reference::ChungHulbert { am, af, beta: 0.25 * (1.0 - am + af).powi(2), gamma: 0.5 - am + af }
}

fn hht(alpha: f64) -> Reference {
    Reference::ChungHulbert { am: 0.0, af: -alpha, beta: 0.25 * (1.0 - alpha).powi(2), gamma: 0.5 - alpha }
}

fn newmark(beta: f64, gamma: f64) -> Reference {
    Reference::ChungHulbert { am: 0.0, af: 0.0, beta, gamma }
}

type M2 = [[f64; 2]; 2];

fn mul(a: M2, b: M2) -> M2 {
    let mut c = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j];
        }
    }
    c
}

fn lin(terms: &[(f64, M2)]) -> M2 {
    let mut c = [[0.0; 2]; 2];
    for (s, m) in terms {
        for i in 0..2 {
            for j in 0..2 {
                c[i][j] += s * m[i][j];
            }
        }
    }
    c
}

/// Amplification matrix on `(x, v)` of the explicit schemes and backward
/// Euler from their stability functions `R(hA)`, `A = [[0, 1], [−ω², 0]]`.
fn explicit_matrix(scheme: &Scheme, omega: f64, h: f64) -> M2 {
    let id = [[1.0, 0.0], [0.0, 1.0]];
    let z = [[0.0, h], [-omega * omega * h, 0.0]];
    let z2 = mul(z, z);
    let z3 = mul(z2, z);
    let z4 = mul(z3, z);
    match scheme {
        Scheme::ExplicitEuler => lin(&[(1.0, id), (1.0, z)]),
        Scheme::ImprovedEuler => lin(&[(1.0, id), (1.0, z), (0.5, z2)]),
        Scheme::Rk4 => lin(&[(1.0, id), (1.0, z), (0.5, z2), (1.0 / 6.0, z3), (1.0 / 24.0, z4)]),
        Scheme::SymplecticEuler => {
            let o2 = (omega * h).powi(2);
            [[1.0 - o2, h], [-omega * omega * h, 1.0]]
        }
        Scheme::LinearlyImplicit { w } if *w == 1.0 => {
            // (I − Z)⁻¹
            let m = lin(&[(1.0, id), (-1.0, z)]);
            let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
            [[m[1][1] / det, -m[0][1] / det], [-m[1][0] / det, m[0][0] / det]]
        }
        other => panic!("no matrix reference for {other}"),
    }
}

fn reference_run(r: Reference, scheme: &Scheme, omega: f64, h: f64, steps: usize) -> Vec<(f64, f64)> {
    let w2 = omega * omega;
    let (mut x, mut v, mut a) = (1.0, 0.0, -w2);
    let mut out = Vec::with_capacity(steps);
    let m = matches!(r, Reference::Matrix).then(|| explicit_matrix(scheme, omega, h));
    for _ in 0..steps {
        match r {
            Reference::ChungHulbert { am, af, beta, gamma } => {
                let pred = x + h * v + h * h * (0.5 - beta) * a;
                let a1 = -(am * a + w2 * (1.0 - af) * pred + w2 * af * x) / ((1.0 - am) + w2 * (1.0 - af) * beta * h * h);
                x = pred + h * h * beta * a1;
                v += h * ((1.0 - gamma) * a + gamma * a1);
                a = a1;
            }
            Reference::WilsonBathe { theta } => {
                let th = theta * h;
                let (c0, c2) = (6.0 / (th * th), 6.0 / th);
                let x_theta = (c0 * x + c2 * v + 2.0 * a) / (w2 + c0);
                let a1 = c0 / theta * (x_theta - x) - c2 / theta * v + (1.0 - 3.0 / theta) * a;
                x += h * v + h * h / 6.0 * (a1 + 2.0 * a);
                v += h / 2.0 * (a1 + a);
                a = a1;
            }
            Reference::Matrix => {
                let m = m.expect("matrix");
                (x, v) = (m[0][0] * x + m[0][1] * v, m[1][0] * x + m[1][1] * v);
            }
        }
        out.push((x, v));
    }
    out
}

// -------------------------------------------------- §8 exact discrete test

struct ExactRow {
    label: &'static str,
    scheme: Scheme,
    reference: Reference,
    /// x(1), v(1), x(10), v(10) as printed in §8.
    printed: [&'static str; 4],
}

fn exact_rows() -> Vec<ExactRow> {
    let nm = |beta, gamma| Scheme::Newmark { beta, gamma };
    vec![
        ExactRow {
            label: "central difference (Newmark beta=0)",
            scheme: nm(0.0, 0.5),
            reference: newmark(0.0, 0.5),
            printed: ["+0.994148", "-0.644362", "+0.469265", "-5.267497"],
        },
        ExactRow {
            label: "Newmark average acceleration",
            scheme: nm(0.25, 0.5),
            reference: newmark(0.25, 0.5),
            printed: ["+0.980995", "+1.219131", "-0.372682", "+5.830540"],
        },
        ExactRow {
            label: "linear acceleration",
            scheme: Scheme::LinearAcceleration,
            reference: newmark(1.0 / 6.0, 0.5),
            printed: ["+0.995108", "+0.610470", "+0.549028", "+5.164403"],
        },
        ExactRow {
            label: "Fox-Goodwin (beta=1/12)",
            scheme: nm(1.0 / 12.0, 0.5),
            reference: newmark(1.0 / 12.0, 0.5),
            printed: ["+0.999998", "-0.012601", "+0.999785", "-0.126002"],
        },
        ExactRow {
            label: "Wilson theta=1.4",
            scheme: Scheme::WilsonTheta { theta: 1.4 },
            reference: Reference::WilsonBathe { theta: 1.4 },
            printed: ["+0.884260", "+1.767101", "-0.396619", "-1.162049"],
        },
        ExactRow {
            label: "HHT alpha=-0.1",
            scheme: Scheme::Hht { alpha: -0.1 },
            reference: hht(-0.1),
            printed: ["+0.960976", "+1.435213", "-0.641688", "+3.781674"],
        },
        ExactRow {
            label: "HHT alpha=-0.3",
            scheme: Scheme::Hht { alpha: -0.3 },
            reference: hht(-0.3),
            printed: ["+0.942739", "+1.653808", "-0.751774", "+1.720759"],
        },
        ExactRow {
            label: "generalized-alpha rho_inf=0.5",
            scheme: Scheme::GeneralizedAlpha { rho_inf: 0.5 },
            reference: chung_hulbert(0.5),
            printed: ["+0.942378", "+1.664414", "-0.752852", "+1.678584"],
        },
        ExactRow {
            label: "explicit Euler",
            scheme: Scheme::ExplicitEuler,
            reference: Reference::Matrix,
            printed: ["+4.126585", "+20.683999", "+1.5126e7", "+4.5962e7"],
        },
        ExactRow {
            label: "Heun / improved Euler",
            scheme: Scheme::ImprovedEuler,
            reference: Reference::Matrix,
            printed: ["+1.133532", "-2.670645", "-6.100030", "+18.320745"],
        },
        ExactRow { label: "RK4", scheme: Scheme::Rk4, reference: Reference::Matrix, printed: ["+0.995920", "+0.044066", "+0.957799", "+0.424487"] },
        ExactRow {
            label: "symplectic Euler (v first)",
            scheme: Scheme::SymplecticEuler,
            reference: Reference::Matrix,
            printed: ["+0.958402", "-0.714922", "+0.177050", "-5.844307"],
        },
        ExactRow {
            label: "backward Euler = linearly implicit w=1",
            scheme: Scheme::LinearlyImplicit { w: 1.0 },
            reference: Reference::Matrix,
            printed: ["+0.148088", "+0.742274", "0", "0"],
        },
        // Not in §8: w = 1/2 is the trapezoidal rule = Newmark average acceleration.
        ExactRow {
            label: "linearly implicit w=1/2 (= Newmark avg)",
            scheme: Scheme::LinearlyImplicit { w: 0.5 },
            reference: newmark(0.25, 0.5),
            printed: ["+0.980995", "+1.219131", "-0.372682", "+5.830540"],
        },
    ]
}

#[test]
fn section8_exact_discrete_values() {
    let (omega, h) = (TAU, 0.1);
    for row in exact_rows() {
        println!("{}:", row.label);
        let got = run_oscillator(&row.scheme, omega, h, 100);
        let reference = reference_run(row.reference, &row.scheme, omega, h, 100);
        let values = [got[9].0, got[9].1, got[99].0, got[99].1];
        let names = ["x(1)", "v(1)", "x(10)", "v(10)"];
        for ((name, value), printed) in names.iter().zip(values).zip(row.printed) {
            if printed == "0" {
                // "≈ 0" in the table
                println!("  {name:<48} {value:+.9e}  table        ~0");
                assert!(value.abs() < 1e-6, "{}: {name} = {value} is not ~0", row.label);
            } else {
                assert_printed(name, value, printed);
            }
        }
        let worst = got.iter().zip(&reference).map(|(g, r)| rel_err(*g, *r, omega)).fold(0.0, f64::max);
        println!("  worst relative deviation from the independent recurrence over 100 steps: {worst:.2e}");
        assert!(worst <= 1e-12, "{}: deviates from its recurrence by {worst:e}", row.label);
    }
}

#[test]
fn section8_closed_forms_for_x_n() {
    // Newmark average acceleration: x_n = cos(n·2·atan(Ω/2)); central difference:
    // x_n = cos(n·2·asin(Ω/2)).
    let (omega, h) = (TAU, 0.1);
    let o = omega * h;
    let cases = [(Scheme::Newmark { beta: 0.25, gamma: 0.5 }, 2.0 * (o / 2.0).atan()), (Scheme::Newmark { beta: 0.0, gamma: 0.5 }, 2.0 * (o / 2.0).asin())];
    for (scheme, omega_bar) in cases {
        let got = run_oscillator(&scheme, omega, h, 1000);
        let worst = got.iter().enumerate().map(|(n, (x, _))| (x - ((n + 1) as f64 * omega_bar).cos()).abs()).fold(0.0, f64::max);
        println!("{scheme}: max |x_n - cos(n Omega_bar)| over 1000 steps = {worst:.2e}");
        assert!(worst < 1e-12, "{scheme}: {worst:e}");
    }
}

#[test]
fn explicit_fixed_one_substep_is_refused_for_growing_schemes() {
    // Euler and Heun grow at every h: Fixed(1) at h = 0.1 must refuse.
    let mut sys = oscillator(TAU);
    for scheme in [Scheme::ExplicitEuler, Scheme::ImprovedEuler] {
        let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
        let before = state.clone();
        let mut integ = Integrator::new(scheme).with_substeps(Substeps::Fixed(1));
        let err = integ.step(&mut sys, &mut state, 0.1).expect_err("must refuse");
        assert!(matches!(err, IntegrateError::StepTooLarge { substeps: 1, .. }), "{err}");
        assert_eq!(state, before, "state must be untouched on error");
    }
}

// ------------------------------------ §8 spectral radius, PE, damping

#[derive(Clone, Copy, Debug)]
struct Cx {
    re: f64,
    im: f64,
}

impl Cx {
    fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }
}

fn eigenvalues(m: &[Vec<f64>]) -> Vec<Cx> {
    let quadratic = |b: f64, c: f64| {
        // roots of λ² + bλ + c
        let d = b * b - 4.0 * c;
        if d < 0.0 {
            vec![Cx { re: -b / 2.0, im: (-d).sqrt() / 2.0 }, Cx { re: -b / 2.0, im: -(-d).sqrt() / 2.0 }]
        } else {
            vec![Cx { re: (-b + d.sqrt()) / 2.0, im: 0.0 }, Cx { re: (-b - d.sqrt()) / 2.0, im: 0.0 }]
        }
    };
    if m.len() == 2 {
        let (tr, det) = (m[0][0] + m[1][1], m[0][0] * m[1][1] - m[0][1] * m[1][0]);
        return quadratic(-tr, det);
    }
    let c2 = m[0][0] + m[1][1] + m[2][2];
    let c1 = m[0][0] * m[1][1] - m[0][1] * m[1][0] + m[0][0] * m[2][2] - m[0][2] * m[2][0] + m[1][1] * m[2][2] - m[1][2] * m[2][1];
    let c0 = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let p = |l: f64| ((l - c2) * l + c1) * l - c0;
    let bound = 1.0 + c2.abs().max(c1.abs()).max(c0.abs());
    let (mut lo, mut hi) = (-bound, bound);
    for _ in 0..400 {
        let mid = 0.5 * (lo + hi);
        if p(mid) < 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    let r = 0.5 * (lo + hi);
    let b = r - c2;
    let mut ev = quadratic(b, c1 + r * b);
    ev.push(Cx { re: r, im: 0.0 });
    ev
}

/// Amplification matrix of one integrator step on `ẍ + ω² x = 0`, obtained
/// by stepping unit states: on `(x, v, â)` for the generalized-α family
/// (with `a = −ω² x`), on `(x, v, a)` for Wilson-θ, on `(x, v)` otherwise.
fn amplification(scheme: &Scheme, omega: f64, h: f64) -> Vec<Vec<f64>> {
    let mut sys = oscillator(omega);
    let w2 = omega * omega;
    let third = if scheme.alpha_parameters().is_some() {
        Some(true)
    } else if matches!(scheme, Scheme::WilsonTheta { .. }) {
        Some(false)
    } else {
        None
    };
    let n = if third.is_some() { 3 } else { 2 };
    let mut m = vec![vec![0.0; n]; n];
    for j in 0..n {
        let unit = |k: usize| if j == k { 1.0 } else { 0.0 };
        let (x, v, s) = (unit(0), unit(1), unit(2));
        let (a, a_hat) = match third {
            Some(true) => (-w2 * x, s),
            Some(false) => (s, s),
            None => (-w2 * x, -w2 * x),
        };
        let mut state = State { t: 0.0, q: vec![x], v: vec![v], a: vec![a], a_hat: vec![a_hat] };
        let mut integ = Integrator::new(scheme.clone()).with_substeps(Substeps::Unchecked(1));
        integ.step(&mut sys, &mut state, h).expect("one step");
        let out = [state.q[0], state.v[0], if third == Some(true) { state.a_hat[0] } else { state.a[0] }];
        for (row, &o) in m.iter_mut().zip(&out) {
            row[j] = o;
        }
    }
    m
}

#[derive(Clone, Copy, Debug)]
struct Spectral {
    rho: f64,
    pe: f64,
    xi: f64,
    /// |λ_principal|^(T/h)
    amp_per_period: f64,
}

fn spectral(scheme: &Scheme, h_over_t: f64) -> Spectral {
    let (omega, h) = (TAU, h_over_t);
    let ev = eigenvalues(&amplification(scheme, omega, h));
    let rho = ev.iter().map(|e| e.abs()).fold(0.0, f64::max);
    let principal = ev.iter().filter(|e| e.im > 0.0).max_by(|a, b| a.abs().total_cmp(&b.abs())).copied().expect("complex principal pair");
    let omega_bar = principal.im.atan2(principal.re).abs();
    let o = omega * h;
    Spectral { rho, pe: o / omega_bar - 1.0, xi: -principal.abs().ln() / omega_bar, amp_per_period: principal.abs().powf(1.0 / h_over_t) }
}

#[derive(Clone, Copy)]
enum Quantity {
    Rho,
    Pe,
    Xi,
    AmpPerPeriod,
}

const H_OVER_T: [f64; 5] = [0.01, 0.05, 0.1, 0.2, 0.3];

#[test]
fn section8_spectral_radius_period_elongation_damping() {
    use Quantity::*;
    let nm = |beta, gamma| Scheme::Newmark { beta, gamma };
    let rows: Vec<(&str, Scheme, Quantity, [&str; 5])> = vec![
        ("Newmark avg", nm(0.25, 0.5), Pe, ["3.289e-4", "8.171e-3", "3.207e-2", "0.1200", "0.2470"]),
        ("linear accel", Scheme::LinearAcceleration, Pe, ["1.644e-4", "4.084e-3", "1.600e-2", "5.915e-2", "0.1174"]),
        ("central difference", nm(0.0, 0.5), Pe, ["-1.645e-4", "-4.141e-3", "-1.693e-2", "-7.517e-2", "-0.2337"]),
        ("Fox-Goodwin", nm(1.0 / 12.0, 0.5), Pe, ["-3.2e-8", "-2.04e-5", "-3.30e-4", "-5.62e-3", "-3.36e-2"]),
        ("Wilson 1.4", Scheme::WilsonTheta { theta: 1.4 }, Rho, ["0.999999", "0.999285", "0.991758", "0.942802", "0.872175"]),
        ("Wilson 1.4", Scheme::WilsonTheta { theta: 1.4 }, Pe, ["7.157e-4", "1.711e-2", "6.146e-2", "0.1937", "0.3540"]),
        ("Wilson 1.4", Scheme::WilsonTheta { theta: 1.4 }, Xi, ["2.07e-5", "2.316e-3", "1.398e-2", "5.595e-2", "9.824e-2"]),
        ("HHT -0.05", Scheme::Hht { alpha: -0.05 }, Rho, ["1.000000", "0.999948", "0.999282", "0.993015", "0.980780"]),
        // §8 prints 3.75e-4 at h/T = 0.01; the recurrence gives 3.7449e-4 (3.74e-4
        // when rounded once; 3.75e-4 looks like a double rounding of 3.745e-4).
        ("HHT -0.05", Scheme::Hht { alpha: -0.05 }, Pe, ["3.75e-4*", "9.28e-3", "3.61e-2", "0.132", "0.266"]),
        ("HHT -0.05", Scheme::Hht { alpha: -0.05 }, Xi, ["1.4e-6", "1.67e-4", "1.18e-3", "6.31e-3", "1.30e-2"]),
        ("HHT -0.1", Scheme::Hht { alpha: -0.1 }, Rho, ["1.000000", "0.999907", "0.998728", "0.987832", "0.966719"]),
        ("HHT -0.1", Scheme::Hht { alpha: -0.1 }, Pe, ["4.13e-4", "1.02e-2", "3.95e-2", "0.142", "0.283"]),
        ("HHT -0.1", Scheme::Hht { alpha: -0.1 }, Xi, ["2.5e-6", "3.00e-4", "2.11e-3", "1.11e-2", "2.30e-2"]),
        ("HHT -0.3", Scheme::Hht { alpha: -0.3 }, Rho, ["1.000000", "0.999832", "0.997750", "0.979310", "0.944614"]),
        ("HHT -0.3", Scheme::Hht { alpha: -0.3 }, Pe, ["4.92e-4", "1.21e-2", "4.66e-2", "0.165", "0.323"]),
        ("HHT -0.3", Scheme::Hht { alpha: -0.3 }, Xi, ["4.5e-6", "5.41e-4", "3.75e-3", "1.94e-2", "4.00e-2"]),
        ("gen-alpha 0.8", Scheme::GeneralizedAlpha { rho_inf: 0.8 }, Rho, ["1.000000", "0.999994", "0.999904", "0.998853", "0.996002"]),
        ("gen-alpha 0.5", Scheme::GeneralizedAlpha { rho_inf: 0.5 }, Rho, ["1.000000", "0.999831", "0.997733", "0.979178", "0.944296"]),
        ("Newmark 0.6/0.3025", nm(0.3025, 0.6), Xi, ["3.14e-3", "1.55e-2", "2.95e-2", "5.05e-2", "6.23e-2"]),
        ("explicit Euler", Scheme::ExplicitEuler, Rho, ["1.001972", "1.048187", "1.181010", "1.605969", "2.133789"]),
        ("Heun", Scheme::ImprovedEuler, Rho, ["1.000002", "1.001217", "1.019296", "1.274134", "2.038640"]),
        ("Heun", Scheme::ImprovedEuler, Pe, ["-6.57e-4", "-1.57e-2", "-5.40e-2", "-0.1055", "-0.0391"]),
        // §8 prints ρ = "1 − 5e-13" at h/T = 0.01; |λ|² = 1 − Ω⁶/72 + Ω⁸/576 gives
        // 1 − 4.27e-10 (checked against the closed form below), so that cell is skipped.
        ("RK4", Scheme::Rk4, Rho, ["", "0.999993", "0.999594", "0.977805", "0.808520"]),
        ("RK4", Scheme::Rk4, Pe, ["1.3e-7", "7.83e-5", "1.12e-3", "1.06e-2", "-4.6e-4"]),
        ("backward Euler", Scheme::LinearlyImplicit { w: 1.0 }, Rho, ["0.998032", "0.954028", "0.846733", "0.622677", "0.468650"]),
        ("explicit Euler", Scheme::ExplicitEuler, AmpPerPeriod, ["1.217748", "2.563159", "5.278798", "", ""]),
        ("Heun", Scheme::ImprovedEuler, AmpPerPeriod, ["1.000195", "1.024621", "1.210603", "", ""]),
        ("RK4", Scheme::Rk4, AmpPerPeriod, ["1.000000", "0.999868", "0.995945", "", ""]),
        ("Wilson 1.4", Scheme::WilsonTheta { theta: 1.4 }, AmpPerPeriod, ["0.999870", "0.985792", "0.920575", "", ""]),
        ("HHT -0.1", Scheme::Hht { alpha: -0.1 }, AmpPerPeriod, ["0.999984", "0.998138", "0.987350", "", ""]),
        ("HHT -0.3", Scheme::Hht { alpha: -0.3 }, AmpPerPeriod, ["0.999971", "0.996648", "0.977725", "", ""]),
        ("backward Euler", Scheme::LinearlyImplicit { w: 1.0 }, AmpPerPeriod, ["0.821188", "0.390144", "0.189437", "", ""]),
    ];
    for (label, scheme, quantity, printed) in rows {
        for (h_over_t, p) in H_OVER_T.iter().zip(printed) {
            if p.is_empty() {
                continue;
            }
            let s = spectral(&scheme, *h_over_t);
            let (name, value) = match quantity {
                Rho => ("rho", s.rho),
                Pe => ("PE", s.pe),
                Xi => ("xi", s.xi),
                AmpPerPeriod => ("|lambda|^(T/h)", s.amp_per_period),
            };
            assert_printed(&format!("{label} {name} h/T={h_over_t}"), value, p);
        }
    }
}

#[test]
fn section8_spectral_closed_forms() {
    for h_over_t in H_OVER_T {
        let o = TAU * h_over_t;
        // Absolute 1e-12: ρ, PE and the amplitude ratio are all dimensionless and O(1) or smaller.
        let close = |what: &str, got: f64, want: f64| {
            assert!((got - want).abs() <= 1e-12, "{what} h/T={h_over_t}: {got} vs {want}");
        };
        // Non-dissipative schemes: ρ = 1 and no amplitude change per period.
        for s in [
            Scheme::Newmark { beta: 0.25, gamma: 0.5 },
            Scheme::LinearAcceleration,
            Scheme::Newmark { beta: 0.0, gamma: 0.5 },
            Scheme::Newmark { beta: 1.0 / 12.0, gamma: 0.5 },
            Scheme::SymplecticEuler,
            Scheme::GeneralizedAlpha { rho_inf: 1.0 },
        ] {
            let sp = spectral(&s, h_over_t);
            close(&format!("{s} rho"), sp.rho, 1.0);
            close(&format!("{s} amplitude per period"), sp.amp_per_period, 1.0);
        }
        // Newmark γ = ½: cos Ω̄ = (1 − (½ − β)Ω²)/(1 + βΩ²), i.e. (without
        // cancellation) sin(Ω̄/2) = Ω / (2 √(1 + βΩ²)).
        for beta in [0.0, 1.0 / 12.0, 1.0 / 6.0, 0.25] {
            let want = 2.0 * (o / (2.0 * (1.0 + beta * o * o).sqrt())).asin();
            let pe = spectral(&Scheme::Newmark { beta, gamma: 0.5 }, h_over_t).pe;
            close(&format!("Newmark beta={beta} PE"), pe, o / want - 1.0);
        }
        close("symplectic Euler PE", spectral(&Scheme::SymplecticEuler, h_over_t).pe, o / (2.0 * (o / 2.0).asin()) - 1.0);
        close("Euler rho", spectral(&Scheme::ExplicitEuler, h_over_t).rho, (1.0 + o * o).sqrt());
        close("Heun rho", spectral(&Scheme::ImprovedEuler, h_over_t).rho, (1.0 + o.powi(4) / 4.0).sqrt());
        close("RK4 rho", spectral(&Scheme::Rk4, h_over_t).rho, (1.0 - o.powi(6) / 72.0 + o.powi(8) / 576.0).sqrt());
        close("backward Euler rho", spectral(&Scheme::LinearlyImplicit { w: 1.0 }, h_over_t).rho, 1.0 / (1.0 + o * o).sqrt());
    }
    let one_minus = 1.0 - spectral(&Scheme::Rk4, 0.01).rho;
    println!("RK4 at h/T = 0.01: 1 - rho = {one_minus:.4e} (section 8 prints 5e-13; closed form Omega^6/144 = {:.4e})", (TAU * 0.01f64).powi(6) / 144.0);
    assert!((one_minus - 4.27e-10).abs() < 0.01e-10);
}

#[test]
fn period_elongation_measured_from_simulated_free_vibration() {
    // Newmark average acceleration at h/T = 0.1: count zero crossings of a long run.
    let h = 0.1;
    let steps = 20_000;
    let xs = run_oscillator(&Scheme::Newmark { beta: 0.25, gamma: 0.5 }, TAU, h, steps);
    let mut crossings = Vec::new();
    let mut prev = (0.0, 1.0);
    for (n, (x, _)) in xs.iter().enumerate() {
        let t = (n + 1) as f64 * h;
        if prev.1 < 0.0 && *x >= 0.0 {
            crossings.push(prev.0 + h * (-prev.1) / (x - prev.1));
        }
        prev = (t, *x);
    }
    let period = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let pe = period - 1.0;
    println!("Newmark avg h/T=0.1: measured PE = {pe:.5e} over {} periods (table 3.207e-2)", crossings.len());
    assert!((pe - 3.207e-2).abs() < 2e-5, "{pe}");

    // HHT α = −0.1 at h/T = 0.05: amplitude ratio per period from the decay of
    // the energy (∝ amplitude²), averaged over the first and the last period of
    // a 50-period run (the average removes most of the within-period ripple).
    let h = 0.05;
    let xs = run_oscillator(&Scheme::Hht { alpha: -0.1 }, TAU, h, 1000);
    let energy = |(x, v): &(f64, f64)| 0.5 * v * v + 0.5 * TAU * TAU * x * x;
    let mean = |r: std::ops::Range<usize>| xs[r].iter().map(energy).sum::<f64>() / 20.0;
    let ratio = (mean(980..1000) / mean(0..20)).powf(1.0 / (2.0 * 49.0));
    println!("HHT -0.1 h/T=0.05: measured amplitude ratio per period = {ratio:.6} (table 0.998138)");
    assert!((ratio - 0.998138).abs() < 2e-4, "{ratio}");
}

// ----------------------------------------------------------- stability

fn grows(scheme: &Scheme, h_over_t: f64, steps: usize) -> (bool, f64) {
    let mut sys = oscillator(TAU);
    let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
    let mut integ = Integrator::new(scheme.clone()).with_substeps(Substeps::Unchecked(1));
    let mut max_amp: f64 = 1.0;
    for _ in 0..steps {
        match integ.step(&mut sys, &mut state, h_over_t) {
            Ok(_) => {}
            Err(IntegrateError::NonFinite { .. }) => return (true, f64::INFINITY),
            Err(e) => panic!("{scheme}: {e}"),
        }
        max_amp = max_amp.max(state.q[0].abs().max(state.v[0].abs() / TAU));
        if max_amp > 1e6 {
            return (true, max_amp);
        }
    }
    (false, max_amp)
}

#[test]
fn stability_limits_and_divergence_just_beyond() {
    // (scheme, Ω_crit, printed h/T_crit of §8)
    let cases = [
        (Scheme::Newmark { beta: 0.0, gamma: 0.5 }, 2.0, "0.318310"),
        (Scheme::SymplecticEuler, 2.0, "0.318310"),
        (Scheme::Newmark { beta: 1.0 / 12.0, gamma: 0.5 }, 6f64.sqrt(), "0.389848"),
        (Scheme::LinearAcceleration, 12f64.sqrt(), "0.551329"),
        (Scheme::Rk4, 2.0 * 2f64.sqrt(), "0.450158"),
    ];
    for (scheme, omega_crit, printed) in cases {
        let limit = stability_limit(&scheme).expect("conditionally stable");
        assert!((limit - omega_crit).abs() < 1e-12);
        let h_crit = limit / TAU;
        assert_printed(&format!("{scheme} h/T_crit"), h_crit, printed);
        let (below, amp_below) = grows(&scheme, 0.99 * h_crit, 10_000);
        let (above, amp_above) = grows(&scheme, 1.01 * h_crit, 10_000);
        println!("    0.99 h_crit: max amplitude {amp_below:.3}; 1.01 h_crit: {amp_above:.3e}");
        assert!(!below && amp_below < 10.0, "{scheme} must stay bounded just below its limit");
        assert!(above, "{scheme} must diverge just above its limit");
    }
    // Linear acceleration: h = 0.56 T grows without bound, 0.54 T stays bounded.
    let (g56, a56) = grows(&Scheme::LinearAcceleration, 0.56, 10_000);
    let (g54, a54) = grows(&Scheme::LinearAcceleration, 0.54, 10_000);
    println!("linear acceleration: h = 0.56 T -> {a56:.3e} (diverged {g56}); h = 0.54 T -> max {a54:.3}");
    assert!(g56 && !g54 && a54 < 10.0);
    // Wilson θ = 1.4 is unconditionally stable: bounded and decaying at 10 T and
    // 100 T. Its well-known displacement overshoot shows in the first steps
    // (x₁ ≈ −(h ω)²/7 x₀ for h ω ≫ 1), then the spectral radius < 1 wins.
    assert_eq!(stability_limit(&Scheme::WilsonTheta { theta: 1.4 }), None);
    for h_over_t in [10.0, 100.0] {
        let mut sys = oscillator(TAU);
        let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
        let mut integ = Integrator::new(Scheme::WilsonTheta { theta: 1.4 });
        let amps: Vec<f64> = (0..10_000)
            .map(|_| {
                integ.step(&mut sys, &mut state, h_over_t).expect("stable step");
                state.q[0].abs().max(state.v[0].abs() / TAU)
            })
            .collect();
        let first = amps[..10].iter().copied().fold(0.0, f64::max);
        let last = amps[9_000..].iter().copied().fold(0.0, f64::max);
        let o2 = (TAU * h_over_t).powi(2);
        println!(
            "Wilson 1.4 at h = {h_over_t} T: overshoot {first:.4e} in the first 10 steps ((h omega)^2/7 = {:.4e}), max over the last 1000 steps {last:.2e}",
            o2 / 7.0
        );
        assert!(first < o2 && last < 1e-12, "Wilson must stay bounded and decay");
    }
    // Explicit and improved Euler grow for every h.
    assert!(grows(&Scheme::ExplicitEuler, 0.01, 100_000).0);
    assert_eq!(stability_limit(&Scheme::ImprovedEuler), Some(0.0));
}

// --------------------------------------------------------------- energy

fn max_energy_drift(scheme: Scheme, steps: usize) -> f64 {
    let mut sys = oscillator(TAU);
    let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
    let e0 = sys.energy(&state.q, &state.v);
    let mut integ = Integrator::new(scheme);
    let mut worst: f64 = 0.0;
    for _ in 0..steps {
        integ.step(&mut sys, &mut state, 0.05).expect("step");
        worst = worst.max((sys.energy(&state.q, &state.v) / e0 - 1.0).abs());
    }
    worst
}

#[test]
fn energy_conserved_by_average_acceleration_and_rho_inf_one() {
    let avg = max_energy_drift(Scheme::Newmark { beta: 0.25, gamma: 0.5 }, 10_000);
    let ga1 = max_energy_drift(Scheme::GeneralizedAlpha { rho_inf: 1.0 }, 10_000);
    let ga08 = max_energy_drift(Scheme::GeneralizedAlpha { rho_inf: 0.8 }, 10_000);
    println!("max relative energy drift over 10 000 steps at h/T = 0.05: Newmark avg {avg:.2e}, gen-alpha rho=1 {ga1:.2e}, rho=0.8 {ga08:.2e}");
    assert!(avg <= 1e-12 && ga1 <= 1e-12);
    assert!(ga08 > 1e-3, "a dissipative scheme must fail the same check");
}

// ------------------------------------------------- explicit sub-stepping

#[test]
fn explicit_auto_substeps_keep_a_stiff_oscillator_stable() {
    let omega: f64 = 1e4;
    let h: f64 = 1.0 / 60.0;
    let x = h * omega;
    let ln = 1e-3f64.ln_1p();
    let cases = [
        (Scheme::SymplecticEuler, 60, (x / (0.9 * 2.0)).ceil()),
        (Scheme::Rk4, 60, (x / (0.9 * 8f64.sqrt())).ceil()),
        (Scheme::ImprovedEuler, 10, (x.powi(4) / (8.0 * ln)).cbrt().ceil()),
        (Scheme::ExplicitEuler, 2, (x * x / (2.0 * ln)).ceil()),
    ];
    for (scheme, steps, expected_n) in cases {
        let mut sys = oscillator(omega);
        let mut state = State::new(&mut sys, 0.0, vec![1e-3], vec![0.0]).expect("state");
        let e0 = sys.energy(&state.q, &state.v);
        let mut integ = Integrator::new(scheme.clone());
        integ.max_explicit_substeps = 20_000_000;
        let mut max_amp: f64 = 0.0;
        let mut stats = StepStats::default();
        for _ in 0..steps {
            stats = integ.step(&mut sys, &mut state, h).expect("auto sub-steps");
            max_amp = max_amp.max((sys.energy(&state.q, &state.v) / e0).sqrt());
        }
        let growth = (sys.energy(&state.q, &state.v) / e0).sqrt();
        println!(
            "{scheme}: omega=1e4, h=1/60: {} sub-steps per step, {} residuals per step, amplitude ratio after {steps} steps {growth:.6}, max {max_amp:.3}",
            stats.substeps_used, stats.residual_evals
        );
        assert_eq!(stats.substeps_used as f64, expected_n, "{scheme}");
        assert!(max_amp < 10.0, "{scheme} must stay bounded");
        if matches!(scheme, Scheme::ExplicitEuler | Scheme::ImprovedEuler) {
            // Growth over each step h within 0.1 %.
            assert!(growth > 1.0 && growth <= 1.001f64.powi(steps), "{scheme}: {growth}");
        }
        // Fixed(1) at the same step is refused, naming h and the limit.
        let mut fixed = Integrator::new(scheme.clone()).with_substeps(Substeps::Fixed(1));
        let before = state.clone();
        match fixed.step(&mut sys, &mut state, h) {
            Err(e @ IntegrateError::StepTooLarge { h: eh, limit, .. }) => {
                let msg = e.to_string();
                println!("  Fixed(1): {msg}");
                assert_eq!(eh, h);
                assert!(limit < h && msg.contains(&format!("{h:e}")) && msg.contains(&format!("{limit:e}")));
                assert!(msg.contains("t = "), "message must name the time");
            }
            other => panic!("{scheme}: expected StepTooLarge, got {other:?}"),
        }
        assert_eq!(state, before);
    }
    // With the default cap, explicit Euler refuses 1.4e7 sub-steps per step.
    let mut sys = oscillator(omega);
    let mut state = State::new(&mut sys, 0.0, vec![1e-3], vec![0.0]).expect("state");
    let err = Integrator::new(Scheme::ExplicitEuler).step(&mut sys, &mut state, h).expect_err("cap");
    println!("default cap: {err}");
    assert!(matches!(err, IntegrateError::TooManySubsteps { .. }));
}

/// A system that does not report its highest frequency.
struct NoFrequency(DenseSystem);

impl SecondOrderSystem for NoFrequency {
    fn dof(&self) -> usize {
        self.0.dof()
    }
    fn residual(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        self.0.residual(t, q, v, a, r)
    }
    fn solve_tangent(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        self.0.solve_tangent(t, q, v, a, c_v, c_q, b, x)
    }
}

#[test]
fn explicit_without_frequency_refuses_auto_but_runs_unchecked() {
    let mut sys = NoFrequency(oscillator(TAU));
    let mut state = State::new(&mut sys, 2.5, vec![1.0], vec![0.0]).expect("state");
    let err = Integrator::new(Scheme::Rk4).step(&mut sys, &mut state, 0.01).expect_err("unknown");
    assert!(matches!(err, IntegrateError::UnknownFrequency { .. }) && err.to_string().contains("t = 2.5 s"), "{err}");
    let stats = Integrator::new(Scheme::Rk4).with_substeps(Substeps::Unchecked(3)).step(&mut sys, &mut state, 0.01);
    assert_eq!(stats.expect("unchecked").substeps_used, 3);
}

// ----------------------------------------------------- nonlinear pendulum

/// Complete elliptic integral of the first kind K(m) = π / (2 AGM(1, √(1−m))).
fn elliptic_k(m: f64) -> f64 {
    // The AGM converges quadratically: 12 rounds reach round-off for any
    // m < 1 (a tolerance test can cycle forever at the last bit).
    let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
    for _ in 0..12 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (2.0 * a)
}

fn pendulum_period_exact(p: &Pendulum, amplitude: f64) -> f64 {
    4.0 * elliptic_k((amplitude / 2.0).sin().powi(2)) / p.natural_frequency()
}

#[test]
fn pendulum_60_degrees_period_and_newton_iterations() {
    let mut p = Pendulum::new(9.81, 1.0);
    let theta0 = 60f64.to_radians();
    let t_exact = pendulum_period_exact(&p, theta0);
    let t_small = TAU / p.natural_frequency();

    // Period from gen-α ρ∞ = 0 at h = T/2000 over 20 periods.
    let h = t_exact / 2000.0;
    let mut state = State::new(&mut p, 0.0, vec![theta0], vec![0.0]).expect("state");
    let mut integ = Integrator::default();
    let mut crossings = Vec::new();
    for _ in 0..40_000 {
        let (t0, x0) = (state.t, state.q[0]);
        integ.step(&mut p, &mut state, h).expect("step");
        if x0 < 0.0 && state.q[0] >= 0.0 {
            crossings.push(t0 + h * (-x0) / (state.q[0] - x0));
        }
    }
    let period = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let rel = period / t_exact - 1.0;
    println!("pendulum 60 deg: exact period {t_exact:.9} s (small-amplitude {t_small:.6}), gen-alpha rho=0 h=T/2000: {period:.9} s, rel. error {rel:.2e}");
    assert!(rel.abs() < 1e-4);
    assert!(t_exact / t_small - 1.0 > 0.07, "the 60 deg period is 7 % longer than the linear one");

    // Newton iterations per step at h = T/100 over 10 periods.
    let h = t_exact / 100.0;
    let mut state = State::new(&mut p, 0.0, vec![theta0], vec![0.0]).expect("state");
    let (mut worst, mut total) = (0, StepStats::default());
    for _ in 0..1000 {
        let stats = integ.step(&mut p, &mut state, h).expect("step");
        worst = worst.max(stats.newton_iterations);
        assert_eq!(stats.substeps_used, 1);
        total += stats;
    }
    println!("pendulum 60 deg at h = T/100: max {worst} Newton iterations per step, mean {:.2}", total.newton_iterations as f64 / 1000.0);
    assert!(worst <= 4);
}

/// The pendulum with a tangent that ignores gravity: Newton degrades into a
/// fixed-point iteration that converges only for small `c_q g/l`.
struct StaleTangent(Pendulum, f64);

impl SecondOrderSystem for StaleTangent {
    fn dof(&self) -> usize {
        1
    }
    fn residual(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        self.0.residual(t, q, v, a, r)
    }
    fn solve_tangent(&mut self, _t: f64, _q: &[f64], _v: &[f64], _a: &[f64], _c_v: f64, _c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        x[0] = self.1 * b[0];
        Ok(())
    }
}

#[test]
fn newton_fallback_splits_steps_and_reports_failure() {
    // c_q (g/l) = h²/2 · 9.81 ≈ 0.7 at h = 0.38: no convergence in 8 iterations,
    // but fine in sub-steps.
    // (Without the line search: it rescues this case in one step, below.)
    let mut sys = StaleTangent(Pendulum::new(9.81, 1.0), 1.0);
    let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
    let plain = NewtonSettings { line_search: false, ..NewtonSettings::default() };
    let mut integ = Integrator::default().with_newton(plain.clone());
    let stats = integ.step(&mut sys, &mut state, 0.38).expect("fallback");
    println!("stale tangent, h = 0.38: {stats:?}");
    assert!(stats.substeps_used > 1);
    // The split is kept for the next steps (no failed attempt first), and
    // halved back after CALM_STEPS steps that converge easily.
    let split = stats.substeps_used;
    let mut probe = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
    let mut remembering = Integrator::default().with_newton(plain.clone());
    remembering.step(&mut sys, &mut probe, 0.38).expect("fallback");
    let next = remembering.step(&mut sys, &mut probe, 0.01).expect("small step");
    assert_eq!(next.substeps_used, split, "{next:?}");
    let mut splits = vec![];
    for _ in 0..20 {
        splits.push(remembering.step(&mut sys, &mut probe, 0.01).expect("small step").substeps_used);
    }
    println!("splits after the fallback: {split}, then {splits:?}");
    assert_eq!(*splits.last().unwrap(), 1);
    assert!(splits.windows(2).all(|w| w[1] <= w[0]));
    // The line search shortens the overshooting corrections of the stale
    // tangent: one step, no split.
    let mut searched = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
    let stats = Integrator::default().step(&mut sys, &mut searched, 0.38).expect("line search");
    println!("stale tangent with line search, h = 0.38: {stats:?}");
    assert_eq!(stats.substeps_used, 1);
    assert!(stats.line_search_evals > 0);
    // A wrong-signed tangent diverges at every split: NotConverged, state untouched.
    let mut bad = StaleTangent(Pendulum::new(9.81, 1.0), -1.0);
    let before = state.clone();
    let err = integ.step(&mut bad, &mut state, 0.01).expect_err("diverges");
    println!("wrong tangent: {err}");
    assert!(matches!(err, IntegrateError::NotConverged { substeps: 256, .. } | IntegrateError::NonFinite { .. }), "{err:?}");
    assert!(err.to_string().contains(&format!("t = {}", before.t)));
    assert_eq!(state, before);
    // Without fallback (no split, no cut of the finest split's sub-step)
    // the first case fails.
    let mut strict = Integrator::default().with_newton(NewtonSettings { max_substeps: 1, rescue_pieces: 1, ..plain });
    let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
    assert!(matches!(strict.step(&mut sys, &mut state, 0.38), Err(IntegrateError::NotConverged { .. })));
}

// ---------------------------------------------------- damped 2-DOF system

/// Closed-form modal solution of M q̈ + C q̇ + K q = F (constant F,
/// Rayleigh damping C = a M + b K) for symmetric 2×2 M, K.
struct Modal {
    q_static: [f64; 2],
    modes: [([f64; 2], f64, f64, f64, f64); 2], // (φ, ω, ζ, η0, η̇0)
}

impl Modal {
    fn new(m: [[f64; 2]; 2], k: [[f64; 2]; 2], (ra, rb): (f64, f64), f: [f64; 2], q0: [f64; 2], v0: [f64; 2]) -> Self {
        let det_k = k[0][0] * k[1][1] - k[0][1] * k[1][0];
        let q_static = [(k[1][1] * f[0] - k[0][1] * f[1]) / det_k, (k[0][0] * f[1] - k[1][0] * f[0]) / det_k];
        // det(K − λM) = A λ² + B λ + C
        let a = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        let b = -(k[0][0] * m[1][1] + k[1][1] * m[0][0] - k[0][1] * m[1][0] - k[1][0] * m[0][1]);
        let c = det_k;
        let disc = (b * b - 4.0 * a * c).sqrt();
        let mform = |x: [f64; 2], y: [f64; 2]| x[0] * (m[0][0] * y[0] + m[0][1] * y[1]) + x[1] * (m[1][0] * y[0] + m[1][1] * y[1]);
        let u0 = [q0[0] - q_static[0], q0[1] - q_static[1]];
        let modes = [(-b - disc) / (2.0 * a), (-b + disc) / (2.0 * a)].map(|lambda| {
            let phi = [-(k[0][1] - lambda * m[0][1]), k[0][0] - lambda * m[0][0]];
            let norm = mform(phi, phi).sqrt();
            let phi = [phi[0] / norm, phi[1] / norm];
            let w = lambda.sqrt();
            (phi, w, 0.5 * (ra / w + rb * w), mform(phi, u0), mform(phi, v0))
        });
        Modal { q_static, modes }
    }

    fn q(&self, t: f64) -> [f64; 2] {
        let mut q = self.q_static;
        for (phi, w, z, e0, ed0) in self.modes {
            let wd = w * (1.0 - z * z).sqrt();
            let eta = (-z * w * t).exp() * (e0 * (wd * t).cos() + (ed0 + z * w * e0) / wd * (wd * t).sin());
            q[0] += phi[0] * eta;
            q[1] += phi[1] * eta;
        }
        q
    }
}

#[test]
fn damped_two_dof_matches_modal_solution() {
    let m = [[2.0, 0.5], [0.5, 1.0]];
    let k = [[6.0, -2.0], [-2.0, 4.0]];
    let (ra, rb) = (0.1, 0.02);
    let c = [0, 1].map(|i| [0, 1].map(|j| ra * m[i][j] + rb * k[i][j]));
    let f = [1.0, 0.0];
    let (q0, v0) = ([1.0, 0.0], [0.0, 1.0]);
    let modal = Modal::new(m, k, (ra, rb), f, q0, v0);
    let rows = |x: [[f64; 2]; 2]| x.iter().map(|r| r.to_vec()).collect::<Vec<_>>();
    // Max deviation from the modal solution over 10 s, sampled every 0.1 s.
    let error = |scheme: &Scheme, h: f64| {
        let mut sys = DenseSystem::from_rows(&rows(m), &rows(c), &rows(k)).expect("valid").with_force_vector(f.to_vec()).expect("force");
        let mut state = State::new(&mut sys, 0.0, q0.to_vec(), v0.to_vec()).expect("state");
        let mut integ = Integrator::new(scheme.clone());
        let steps = (10.0 / h).round() as usize;
        let every = (0.1 / h).round() as usize;
        let mut worst: f64 = 0.0;
        for n in 1..=steps {
            integ.step(&mut sys, &mut state, h).expect("step");
            if n % every == 0 {
                let exact = modal.q(state.t);
                worst = worst.max((state.q[0] - exact[0]).abs().max((state.q[1] - exact[1]).abs()));
            }
        }
        worst
    };
    let rk4 = error(&Scheme::Rk4, 1e-3);
    println!("2-DOF damped, rk4, h = 1e-3: max |q - q_modal| over 10 s = {rk4:.2e}");
    assert!(rk4 < 1e-11, "{rk4:e}");
    // Second-order implicit schemes: error below 5e-5 at h = 1e-3 and
    // quartered when h is halved.
    for scheme in [
        Scheme::GeneralizedAlpha { rho_inf: 0.0 },
        Scheme::GeneralizedAlpha { rho_inf: 0.8 },
        Scheme::Hht { alpha: -0.1 },
        Scheme::Newmark { beta: 0.25, gamma: 0.5 },
    ] {
        let (e1, e2) = (error(&scheme, 1e-3), error(&scheme, 5e-4));
        println!("2-DOF damped, {scheme}: max error {e1:.3e} at h = 1e-3, {e2:.3e} at h = 5e-4 (ratio {:.3})", e1 / e2);
        assert!(e1 < 5e-5 && (3.8..4.2).contains(&(e1 / e2)), "{scheme}: {e1:e}, {e2:e}");
    }
}

// ------------------------------------------------ the game preset

#[test]
fn linearly_implicit_preset_is_one_solve_per_step_and_stable() {
    // A 20 m pendulum (the scale of DESIGN.md's rope) released at 85 degrees,
    // h = 1/60 s, 20 s: one residual and one solve per step, never a fallback;
    // w = 1 dissipates (ξ̄ ≈ Ω/2), w = 0.55 ten times less (ξ̄ ≈ (w − ½)Ω).
    let theta0 = 85f64.to_radians();
    for (w, min_loss, max_loss) in [(1.0, 0.05, 0.3), (0.55, 0.0, 0.05)] {
        let mut p = Pendulum::new(9.81, 20.0);
        let mut state = State::new(&mut p, 0.0, vec![theta0], vec![0.0]).expect("state");
        let e0 = p.energy(state.q[0], state.v[0]);
        let mut integ = Integrator::new(Scheme::LinearlyImplicit { w });
        for _ in 0..1200 {
            let stats = integ.step(&mut p, &mut state, 1.0 / 60.0).expect("step");
            assert_eq!((stats.residual_evals, stats.solves, stats.substeps_used), (1, 1, 1));
        }
        let loss = 1.0 - p.energy(state.q[0], state.v[0]) / e0;
        println!("linearly implicit w = {w}: pendulum 85 deg, h = 1/60 s, 20 s: energy lost {:.2} %", 100.0 * loss);
        assert!(loss > min_loss && loss < max_loss, "w = {w}: {loss}");
    }
}

// ------------------------------------------- time-dependent load

#[test]
fn ramp_load_converges_at_the_scheme_order() {
    // m ẍ + c ẋ + k x = F₀ t has x_p = (F₀/k)(t − c/k); the rest is a damped
    // free vibration. A load evaluated at the wrong stage time drops the order.
    let (m, c, k, f0): (f64, f64, f64, f64) = (1.0, 0.4, 25.0, 10.0);
    let (x0, v0) = (0.5, 0.0);
    let exact = |t: f64| {
        let (wn, z) = ((k / m).sqrt(), c / (2.0 * (k * m).sqrt()));
        let wd = wn * (1.0 - z * z).sqrt();
        let (u0, du0) = (x0 + f0 * c / (k * k), v0 - f0 / k);
        let u = (-z * wn * t).exp() * (u0 * (wd * t).cos() + (du0 + z * wn * u0) / wd * (wd * t).sin());
        f0 / k * (t - c / k) + u
    };
    let error = |scheme: &Scheme, h: f64| {
        let mut sys = DenseSystem::oscillator(m, c, k).expect("valid").with_force(move |t, f| f[0] = f0 * t);
        let mut state = State::new(&mut sys, 0.0, vec![x0], vec![v0]).expect("state");
        let mut integ = Integrator::new(scheme.clone());
        let steps = (4.0 / h).round() as usize;
        let mut worst: f64 = 0.0;
        for _ in 0..steps {
            integ.step(&mut sys, &mut state, h).expect("step");
            worst = worst.max((state.q[0] - exact(state.t)).abs());
        }
        worst
    };
    let cases = [
        (Scheme::Rk4, 16.0),
        (Scheme::ImprovedEuler, 4.0),
        (Scheme::SymplecticEuler, 2.0),
        (Scheme::Newmark { beta: 0.25, gamma: 0.5 }, 4.0),
        (Scheme::LinearAcceleration, 4.0),
        (Scheme::WilsonTheta { theta: 1.4 }, 4.0),
        (Scheme::Hht { alpha: -0.1 }, 4.0),
        (Scheme::GeneralizedAlpha { rho_inf: 0.0 }, 4.0),
        (Scheme::LinearlyImplicit { w: 0.5 }, 4.0),
        (Scheme::LinearlyImplicit { w: 1.0 }, 2.0),
    ];
    for (scheme, order_ratio) in cases {
        let (e1, e2) = (error(&scheme, 2e-3), error(&scheme, 1e-3));
        let ratio = e1 / e2;
        println!("ramp load, {scheme}: max error {e1:.3e} (h = 2e-3), {e2:.3e} (h = 1e-3), ratio {ratio:.3} (expected {order_ratio})");
        assert!((ratio / order_ratio - 1.0).abs() < 0.1, "{scheme}: ratio {ratio}");
    }
}
