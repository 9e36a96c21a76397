//! Reduced crane models (issue 15): the equations Lagrange's machinery
//! derives, against the textbook equations, closed-form frequencies and
//! the conservation laws.

use bevy_rapier_cable::crane::*;
use bevy_rapier_cable::integrate::{Integrator, Scheme, SecondOrderSystem, State, Substeps};
use std::f64::consts::PI;

const G: f64 = 9.81;

/// RK4 at a fixed step `h` (the models give no frequency bound, so the
/// step is ours: 1 ms is ωh ≤ 0.01 for every mode below).
fn rk4() -> Integrator {
    let mut i = Integrator::new(Scheme::Rk4);
    i.substeps = Substeps::Unchecked(1);
    i
}

/// Times at which coordinate `k` crosses zero upward, over `duration`.
fn upward_crossings<S: SecondOrderSystem>(sys: &mut S, state: &mut State, k: usize, h: f64, duration: f64) -> Vec<f64> {
    let mut integrator = rk4();
    let mut ups = Vec::new();
    let (mut t0, mut x0) = (state.t, state.q[k]);
    while state.t < duration - 1e-12 {
        integrator.step(sys, state, h).unwrap();
        let (t1, x1) = (state.t, state.q[k]);
        if x0 < 0.0 && x1 >= 0.0 {
            // Cubic Hermite would be finer; linear in a 1 ms step is 1e-7 s.
            ups.push(t0 + (t1 - t0) * (-x0) / (x1 - x0));
        }
        (t0, x0) = (t1, x1);
    }
    ups
}

fn mean_period(ups: &[f64]) -> f64 {
    (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64
}

/// Complete elliptic integral of the first kind K(k) by the arithmetic–geometric mean.
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    for _ in 0..30 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (2.0 * a)
}

/// The residual the machinery derives equals REFERENCE.md §6's overhead
/// crane equations, `(M + m) ẍ + m l (θ̈ cos θ − θ̇² sin θ) = F − c_x ẋ` and
/// `m l (l θ̈ + ẍ cos θ + g sin θ) = −c_θ θ̇`, at arbitrary states.
#[test]
fn overhead_crane_equations_are_the_textbook_ones() {
    let crane = OverheadCrane::new(500.0, 1000.0, 10.0).unwrap().with_damping(40.0, 15.0).with_drive(TrolleyDrive::Force(2500.0));
    let (mm, m, l) = (500.0, 1000.0, 10.0);
    let mut sys = crane.system();
    let mut worst = 0.0f64;
    for (k, theta) in [-1.2, -0.3, 0.0, 0.4, 1.4].into_iter().enumerate() {
        let (x, xd, td, xdd, tdd) = (0.7 * k as f64, 0.3 - 0.2 * k as f64, -0.8 + 0.5 * k as f64, 1.1 - 0.4 * k as f64, 0.25 * k as f64 - 0.3);
        let mut r = [0.0; 2];
        sys.residual(0.0, &[x, theta], &[xd, td], &[xdd, tdd], &mut r).unwrap();
        let r0 = (mm + m) * xdd + m * l * (tdd * theta.cos() - td * td * theta.sin()) - (2500.0 - 40.0 * xd);
        let r1 = m * l * (l * tdd + xdd * theta.cos() + G * theta.sin()) + 15.0 * td;
        worst = worst.max((r[0] - r0).abs() / 1e4).max((r[1] - r1).abs() / 1e5);
    }
    println!("largest difference {worst:.2e} (relative to 1e4 N, 1e5 N·m)");
    assert!(worst < 1e-12, "residual differs from the textbook equations by {worst:e}");
}

/// Small swings (0.001 rad) with the trolley free: period `2π/ω`,
/// `ω² = g (M + m)/(M l)` (to 1e-5: the amplitude's own correction grows
/// as θ₀², measured 5.6e-5 at 0.01 rad and 5.6e-7 at 0.001 rad); and the
/// linearisation is the mass and stiffness of the
/// nonlinear system at rest.
#[test]
fn overhead_crane_swings_at_the_closed_form_frequencies() {
    let crane = OverheadCrane::new(500.0, 1000.0, 10.0).unwrap();
    let omega = crane.free_trolley_frequency();
    let lin = crane.linearized().unwrap();
    let mut sys = crane.clone().system();
    let mut state = State::new(&mut sys, 0.0, vec![0.0, 0.001], vec![0.0, 0.0]).unwrap();
    let ups = upward_crossings(&mut sys, &mut state, 1, 1e-3, 40.0);
    let period = mean_period(&ups);
    let err = period * omega / (2.0 * PI) - 1.0;
    println!("free trolley: period {period:.6} s vs {:.6} s ({err:+.2e})", 2.0 * PI / omega);
    assert!(ups.len() >= 10 && err.abs() < 1e-5, "period error {err:e}");
    // Linearisation: the mass matrix at rest and m g l.
    let m0 = sys.mass_matrix(&[0.0, 0.0]);
    for (a, b) in m0.iter().zip(lin.mass()) {
        assert!((a - b).abs() < 1e-9 * b.abs().max(1.0), "mass matrix {m0:?} vs {:?}", lin.mass());
    }
    assert!((lin.stiffness()[3] - 1000.0 * G * 10.0).abs() < 1e-9);
}

/// A 30° swing with the trolley held (a 1e12 kg trolley): the exact
/// pendulum period `4 K(sin(θ₀/2))/√(g/l)`, within 1e-6.
#[test]
fn overhead_crane_with_a_held_trolley_is_the_exact_pendulum() {
    let crane = OverheadCrane::new(1e12, 1000.0, 10.0).unwrap();
    let theta0 = 30f64.to_radians();
    let exact = 4.0 * elliptic_k((theta0 / 2.0).sin()) / crane.pendulum_frequency();
    let mut sys = crane.system();
    let mut state = State::new(&mut sys, 0.0, vec![0.0, -theta0], vec![0.0, 0.0]).unwrap();
    let ups = upward_crossings(&mut sys, &mut state, 1, 1e-3, 40.0);
    let period = mean_period(&ups);
    let err = period / exact - 1.0;
    println!("held trolley, 30°: period {period:.7} s vs {exact:.7} s ({err:+.2e})");
    assert!(err.abs() < 1e-6, "period error {err:e}");
}

/// A large swing (0.8 rad) with the trolley free and no damping: total
/// energy and the horizontal momentum `(M + m) ẋ + m l θ̇ cos θ` stay
/// constant (RK4 at 1 ms: ≤ 1e-9 of the swing energy and of `m √(g l)`).
#[test]
fn overhead_crane_conserves_energy_and_momentum() {
    let crane = OverheadCrane::new(500.0, 1000.0, 10.0).unwrap();
    let (mm, m, l) = (500.0, 1000.0, 10.0);
    let mut sys = crane.system();
    let mut state = State::new(&mut sys, 0.0, vec![0.0, 0.8], vec![0.3, 0.0]).unwrap();
    let energy = |sys: &mut LagrangeSystem<OverheadCrane>, s: &State| sys.kinetic_energy(&s.q, &s.v) + sys.potential_energy(&s.q);
    let momentum = |s: &State| (mm + m) * s.v[0] + m * l * s.v[1] * s.q[1].cos();
    let (e0, p0) = (energy(&mut sys, &state), momentum(&state));
    let swing = m * G * l * (1.0 - 0.8f64.cos());
    let mut integrator = rk4();
    let (mut de, mut dp) = (0.0f64, 0.0f64);
    while state.t < 20.0 - 1e-12 {
        integrator.step(&mut sys, &mut state, 1e-3).unwrap();
        de = de.max((energy(&mut sys, &state) - e0).abs() / swing);
        dp = dp.max((momentum(&state) - p0).abs() / (m * (G * l).sqrt()));
    }
    println!("20 s at 0.8 rad: energy drift {de:.2e} of the swing energy, momentum drift {dp:.2e}");
    assert!(de < 1e-9 && dp < 1e-9, "energy {de:e}, momentum {dp:e}");
}

/// A speed-controlled trolley started at rest with a 0.5 m/s command and a
/// stiff loop (time constant 2 ms): the payload is left behind as by an
/// instantaneous speed step, swinging with amplitude `v/√(g l)` about the
/// vertical (`θ = −(v/(l ω)) sin ωt`, `ω = √(g/l)`: the drive holds the
/// trolley's speed), within 1 %.
#[test]
fn overhead_crane_speed_step_excites_the_closed_form_sway() {
    let v = 0.5;
    let crane = OverheadCrane::new(500.0, 1000.0, 10.0).unwrap().with_drive(TrolleyDrive::Speed { command: v, gain: 7.5e5, max_force: 1e9 });
    let mut sys = crane.system();
    let mut state = State::new(&mut sys, 0.0, vec![0.0, 0.0], vec![0.0, 0.0]).unwrap();
    let mut integrator = rk4();
    let mut largest = 0.0f64;
    while state.t < 15.0 - 1e-12 {
        integrator.step(&mut sys, &mut state, 1e-4).unwrap();
        largest = largest.max(state.q[1].abs());
    }
    let expected = v / (G * 10.0f64).sqrt();
    let err = largest / expected - 1.0;
    println!("speed step 0.5 m/s: sway amplitude {largest:.5} rad vs {expected:.5} ({err:+.2e})");
    assert!(err.abs() < 0.01, "sway amplitude error {err:e}");
}

/// Tower crane at rest at radius 20 m: the mass matrix is that of
/// REFERENCE.md §6's linearised equations
/// (`[[J + (M+m)x², 0, 0, m l x], [0, M+m, m l, 0], [0, m l, m l², 0], [m l x, 0, 0, m l²]]`),
/// and small swings (5e-4 rad) in each angle oscillate at the closed-form
/// radial and tangential frequencies (within 1e-5).
#[test]
fn tower_crane_swings_at_the_closed_form_frequencies() {
    let (j, mm, m, l, x) = (2e5, 800.0, 2000.0, 15.0, 20.0);
    let crane = TowerCrane::new(j, mm, m, l).unwrap();
    let (wr, wt) = (crane.radial_frequency(), crane.tangential_frequency(x));
    let mut sys = crane.system();
    let mass = sys.mass_matrix(&[0.3, x, 0.0, 0.0]);
    let expected = [j + (mm + m) * x * x, 0.0, 0.0, m * l * x, 0.0, mm + m, m * l, 0.0, 0.0, m * l, m * l * l, 0.0, m * l * x, 0.0, 0.0, m * l * l];
    for (a, b) in mass.iter().zip(expected) {
        assert!((a - b).abs() < 1e-9 * (1.0 + b.abs()), "mass matrix {mass:?}");
    }
    for (k, omega) in [(2usize, wr), (3, wt)] {
        let mut q = vec![0.0, x, 0.0, 0.0];
        q[k] = 0.0005;
        let mut state = State::new(&mut sys, 0.0, q, vec![0.0; 4]).unwrap();
        let ups = upward_crossings(&mut sys, &mut state, k, 1e-3, 40.0);
        let period = mean_period(&ups);
        let err = period * omega / (2.0 * PI) - 1.0;
        println!("tower crane, {}: period {period:.6} s vs {:.6} s ({err:+.2e})", if k == 2 { "radial α" } else { "tangential β" }, 2.0 * PI / omega);
        assert!(ups.len() >= 8 && err.abs() < 1e-5, "period error {err:e} over {} periods", ups.len());
    }
}

/// A large coupled motion of the tower crane (slewing at 0.2 rad/s, the
/// trolley moving, 0.3 and −0.2 rad of sway) with no torque, force or
/// damping: energy and the angular momentum about the tower axis stay
/// constant (RK4 at 1 ms, ≤ 1e-9 relative), while the motion exchanges
/// them between the jib, the trolley and the payload.
#[test]
fn tower_crane_conserves_energy_and_angular_momentum() {
    let crane = TowerCrane::new(2e5, 800.0, 2000.0, 15.0).unwrap();
    let mut sys = crane.system();
    let mut state = State::new(&mut sys, 0.0, vec![0.0, 20.0, 0.3, -0.2], vec![0.2, 0.5, 0.0, 0.1]).unwrap();
    let e0 = sys.kinetic_energy(&state.q, &state.v) + sys.potential_energy(&state.q);
    let h0 = sys.angular_momentum(&state.q, &state.v);
    let scale = sys.kinetic_energy(&state.q, &state.v);
    let mut integrator = rk4();
    let (mut de, mut dh, mut jib_swing) = (0.0f64, 0.0f64, (f64::MAX, f64::MIN));
    while state.t < 20.0 - 1e-12 {
        integrator.step(&mut sys, &mut state, 1e-3).unwrap();
        let e = sys.kinetic_energy(&state.q, &state.v) + sys.potential_energy(&state.q);
        de = de.max((e - e0).abs() / scale);
        dh = dh.max((sys.angular_momentum(&state.q, &state.v) - h0).abs() / h0.abs());
        jib_swing = (jib_swing.0.min(state.v[0]), jib_swing.1.max(state.v[0]));
    }
    println!("20 s: energy drift {de:.2e}, angular momentum drift {dh:.2e}; slew rate between {:.4} and {:.4} rad/s", jib_swing.0, jib_swing.1);
    assert!(de < 1e-9 && dh < 1e-9, "energy {de:e}, angular momentum {dh:e}");
    assert!(jib_swing.1 - jib_swing.0 > 1e-3, "the payload should exchange momentum with the jib");
}

/// Bad parameters are refused with an error naming the model and field.
#[test]
fn bad_crane_parameters_are_refused_by_name() {
    let e = OverheadCrane::new(500.0, f64::NAN, 10.0).unwrap_err();
    assert!(e.to_string().contains("overhead crane: payload_mass = NaN"), "{e}");
    let e = TowerCrane::new(2e5, 800.0, 2000.0, -1.0).unwrap_err();
    assert!(e.to_string().contains("tower crane: rope_length = -1"), "{e}");
}

/// A 10 t payload on a hoist rope of k = 2e6 N/m hoisted at 0.5 m/s
/// (REFERENCE.md §7), drum radius 0.5 m on 2 parts of line (r_e = 0.25 m).
fn hoist(boom_stiffness: f64, drive: HoistDrive) -> Hoist {
    Hoist::new(50.0, 0.25, 1.0, boom_stiffness, 2e6, 1e4).unwrap().with_drive(drive)
}

const V_HOIST: f64 = 0.5;

/// A drive stiff enough to hold its speed command (time constant 50 ns).
fn rigid_drive(command: f64) -> HoistDrive {
    HoistDrive::Speed { command, gain: 1e9, max_torque: 1e12 }
}

/// Steps `duration` at 1 ms with the default integrator (generalized-α)
/// and returns the largest rope force, N.
fn peak_rope_force(sys: &mut Hoist, q: Vec<f64>, v: Vec<f64>, duration: f64) -> f64 {
    let mut state = State::new(sys, 0.0, q, v).unwrap();
    let mut integrator = Integrator::default();
    let mut peak = 0.0f64;
    while state.t < duration - 1e-12 {
        integrator.step(sys, &mut state, 1e-3).unwrap();
        peak = peak.max(sys.rope_force(&state.q, &state.v));
    }
    peak
}

/// Dynamic load factor of the hoist against REFERENCE.md §7's estimate
/// `m g + v √(k m)` (exact for a rigid drive and boom, an undamped rope,
/// and a speed that changes at once), within 0.5 %:
/// * a grounded payload lifted at 0.5 m/s (the drum already at speed);
/// * a hanging payload whose drum starts at once (the drive's 50 ns time
///   constant);
/// * a payload lowered at 0.5 m/s whose drum stops at once (braking);
/// * with a flexible boom (k_b = 4e6 N/m) and a light tip, the rope and boom
///   in series, `k_eff = k k_b/(k + k_b)`: `m g + v √(k_eff m)`.
#[test]
fn hoist_dynamic_load_factor_matches_the_closed_form() {
    let rigid = 1e12;
    let w = 1e4 * G;
    let re = 0.25;
    // Grounded, lifted at speed: the payload rests on the ground spring.
    let mut sys = hoist(rigid, rigid_drive(V_HOIST));
    let ground = -w / sys.ground.0;
    let lift = peak_rope_force(&mut sys, vec![0.0, 0.0, ground], vec![V_HOIST / re, 0.0, 0.0], 2.0);
    // Hanging, started.
    let sys = hoist(rigid, rigid_drive(V_HOIST));
    let start = peak_rope_force(&mut sys.clone(), sys.hanging(4.0), vec![0.0; 3], 2.0);
    // Lowering, braked.
    let sys = hoist(rigid, rigid_drive(0.0));
    let brake = peak_rope_force(&mut sys.clone(), sys.hanging(4.0), vec![-V_HOIST / re, 0.0, -V_HOIST], 2.0);
    let estimate = sys.load_factor_estimate(V_HOIST);
    for (case, peak) in [("lift off the ground", lift), ("start", start), ("brake while lowering", brake)] {
        let err = peak / w / estimate - 1.0;
        println!("{case}: load factor {:.4} vs 1 + v√(k/m)/g = {estimate:.4} ({err:+.2e})", peak / w);
        assert!(err.abs() < 5e-3, "{case}: {err:e}");
    }
    // Flexible boom in series with the rope.
    let kb = 4e6;
    let keff = 2e6 * kb / (2e6 + kb);
    let mut sys = hoist(kb, rigid_drive(V_HOIST));
    let ground = -w / sys.ground.0;
    let lift = peak_rope_force(&mut sys, vec![0.0, 0.0, ground], vec![V_HOIST / re, 0.0, 0.0], 2.0);
    let expected = 1.0 + V_HOIST * (keff / 1e4).sqrt() / G;
    let err = lift / w / expected - 1.0;
    println!("flexible boom (k_b = 4e6 N/m): load factor {:.4} vs {expected:.4} ({err:+.2e})", lift / w);
    assert!(err.abs() < 5e-3, "flexible boom: {err:e}");
}

/// The same lift with a realistic drive: a proportional speed loop that
/// droops 1.2 % under the static load, torque-limited to 1.5 times the
/// static torque, so the drum (with the payload's referred inertia)
/// reaches speed in about 0.1 s instead of at once: the load factor must
/// lie between 1 and the instant-start estimate with the flexible boom
/// in series (measured:
/// docs/verification.md).
#[test]
fn hoist_with_a_real_drive_lifts_softer_than_the_estimate() {
    let w = 1e4 * G;
    let re = 0.25;
    let drive = HoistDrive::Speed { command: V_HOIST, gain: 1e6, max_torque: 1.5 * w * re };
    let mut sys = hoist(4e6, drive);
    let ground = -w / sys.ground.0;
    let lift = peak_rope_force(&mut sys, vec![0.0, 0.0, ground], vec![0.0; 3], 4.0);
    // The estimate with the boom in series with the rope (k_eff).
    let keff: f64 = 2e6 * 4e6 / 6e6;
    let (dlf, estimate) = (lift / w, 1.0 + V_HOIST * (keff / 1e4).sqrt() / G);
    println!("real drive, flexible boom: load factor {dlf:.4} (instant-start estimate {estimate:.4}, rigid boom {:.4})", sys.load_factor_estimate(V_HOIST));
    assert!(dlf > 1.0 && dlf < estimate, "load factor {dlf}");
}

/// Forestry crane (trolley 300 kg, log bundle 1.5 t, rope 6 m): small
/// swings in the trolley's plane with the trolley free at
/// `ω² = g(M+m)/(M l)`, out of it at `ω² = g/l` (the trolley does not take
/// part), within 1e-5; a conical swing with the trolley held (1e12 kg) at
/// polar angle 30° and `Ω² = g/(l cos θ)` keeps its polar angle (seed 004's
/// θ, by `polar_angles`) within 1e-7 rad over 20 s and turns its azimuth at
/// Ω (within 1e-6); energy stays constant.
#[test]
fn forestry_crane_swings_in_both_planes_and_as_a_cone() {
    let (mm, m, l) = (300.0, 1500.0, 6.0);
    let crane = ForestryCrane::new(mm, m, l).unwrap();
    let mut sys = crane.system();
    for (k, omega) in [(1usize, (G * (mm + m) / (mm * l)).sqrt()), (2, (G / l).sqrt())] {
        let mut q = vec![0.0; 3];
        q[k] = 5e-4;
        let mut state = State::new(&mut sys, 0.0, q, vec![0.0; 3]).unwrap();
        let ups = upward_crossings(&mut sys, &mut state, k, 1e-3, 45.0);
        let err = mean_period(&ups) * omega / (2.0 * PI) - 1.0;
        println!("forestry crane, {}: period error {err:+.2e}", if k == 1 { "in plane" } else { "out of plane" });
        assert!(ups.len() >= 8 && err.abs() < 1e-5, "period error {err:e}");
    }
    // Conical swing: the bundle starts at polar angle θ₀ in the x–y plane
    // (α = θ₀, β = 0) moving along +z at l sin θ₀ Ω.
    let held = ForestryCrane::new(1e12, m, l).unwrap();
    let mut sys = held.system();
    let theta0 = 30f64.to_radians();
    let omega = (G / (l * theta0.cos())).sqrt();
    // β̇ from the bundle's z velocity l cos β β̇ = l sin θ₀ Ω.
    let mut state = State::new(&mut sys, 0.0, vec![0.0, theta0, 0.0], vec![0.0, 0.0, theta0.sin() * omega]).unwrap();
    let e0 = sys.kinetic_energy(&state.q, &state.v) + sys.potential_energy(&state.q);
    let mut integrator = rk4();
    let (mut dtheta, mut de) = (0.0f64, 0.0f64);
    let mut turns = 0.0;
    let mut last_phi = 0.0;
    while state.t < 20.0 - 1e-12 {
        integrator.step(&mut sys, &mut state, 1e-3).unwrap();
        let (theta, phi) = ForestryCrane::polar_angles(state.q[1], state.q[2]);
        dtheta = dtheta.max((theta - theta0).abs());
        let mut d = phi - last_phi;
        if d < -PI {
            d += 2.0 * PI;
        }
        turns += d;
        last_phi = phi;
        de = de.max((sys.kinetic_energy(&state.q, &state.v) + sys.potential_energy(&state.q) - e0).abs() / (m * G * l));
    }
    let rate_err = turns / 20.0 / omega - 1.0;
    println!("conical swing at 30°: polar angle within {dtheta:.2e} rad, azimuth rate {rate_err:+.2e}, energy {de:.2e}");
    assert!(dtheta < 1e-7 && rate_err.abs() < 1e-6 && de < 1e-10, "cone: {dtheta:e}, {rate_err:e}, {de:e}");
}

/// With the default sub-step policy, RK4 chooses its sub-steps from the
/// model's own rate estimate (`max_frequency`): a 1/60 s frame step on the
/// overhead crane with a stiff speed-controlled trolley (1e6 N·s/m on
/// 1.5 t of trolley and payload: a rate of about 2000 1/s) runs stably and
/// agrees with generalized-α at 1 ms to 1e-4 rad of sway.
#[test]
fn explicit_schemes_pick_their_substeps_on_a_crane_model() {
    let crane = OverheadCrane::new(500.0, 1000.0, 10.0).unwrap().with_drive(TrolleyDrive::Speed { command: 0.5, gain: 1e6, max_force: 1e9 });
    let mut sys = crane.clone().system();
    let rate = sys.max_frequency(&[0.0, 0.0]).unwrap();
    let mut state = State::new(&mut sys, 0.0, vec![0.0, 0.0], vec![0.0, 0.0]).unwrap();
    let mut rk4 = Integrator::new(Scheme::Rk4);
    let mut substeps = 0;
    while state.t < 5.0 - 1e-9 {
        substeps += rk4.step(&mut sys, &mut state, 1.0 / 60.0).unwrap().substeps_used;
    }
    let mut fine_sys = crane.system();
    let mut fine = State::new(&mut fine_sys, 0.0, vec![0.0, 0.0], vec![0.0, 0.0]).unwrap();
    let mut ga = Integrator::default();
    while fine.t < 5.0 - 1e-9 {
        ga.step(&mut fine_sys, &mut fine, 1e-3).unwrap();
    }
    let diff = (state.q[1] - fine.q[1]).abs();
    println!("rate estimate {rate:.0} 1/s; RK4 took {} sub-steps per frame; sway differs by {diff:.2e} rad", substeps as f64 / 300.0);
    assert!(rate > 1500.0 && diff < 1e-4, "rate {rate}, difference {diff}");
}

/// The adaptive integrators on a reduced crane model (issue 15: "test both
/// on the reduced models"): the overhead crane swinging 0.5 rad with the
/// trolley free, 20 s. Reference: RK4 at 0.25 ms (80 000 steps). DOPRI5 at
/// tol 1e-9 lands within 1e-6 rad of it with a fraction of RK4-at-1-ms's
/// 80 000 evaluations; TR-BDF2 at tol 1e-7 within 1e-3 rad; both keep the
/// energy within 1e-4 of the swing energy.
#[test]
fn adaptive_integrators_on_the_overhead_crane() {
    use bevy_rapier_cable::integrate::{DormandPrince, TrBdf2};
    let crane = OverheadCrane::new(500.0, 1000.0, 10.0).unwrap();
    let swing = 1000.0 * G * 10.0 * (1.0 - 0.5f64.cos());
    let start = |sys: &mut LagrangeSystem<OverheadCrane>| State::new(sys, 0.0, vec![0.0, 0.5], vec![0.0, 0.0]).unwrap();
    let mut sys = crane.clone().system();
    let mut reference = start(&mut sys);
    let mut integrator = rk4();
    while reference.t < 20.0 - 1e-12 {
        integrator.step(&mut sys, &mut reference, 2.5e-4).unwrap();
    }
    let e0 = {
        let s = start(&mut sys);
        sys.kinetic_energy(&s.q, &s.v) + sys.potential_energy(&s.q)
    };
    let mut dp_state = start(&mut sys);
    let dp = DormandPrince::new(1e-9, 1e-9).unwrap().integrate(&mut sys, &mut dp_state, 20.0).unwrap();
    let mut tr_state = start(&mut sys);
    let tr = TrBdf2::new(1e-7, 1e-7).unwrap().integrate(&mut sys, &mut tr_state, 20.0).unwrap();
    for (name, state, evals, tol) in [("DOPRI5", &dp_state, dp.residual_evals, 1e-6), ("TR-BDF2", &tr_state, tr.residual_evals, 1e-3)] {
        let err = (state.q[1] - reference.q[1]).abs().max((state.q[0] - reference.q[0]).abs());
        let de = (sys.kinetic_energy(&state.q, &state.v) + sys.potential_energy(&state.q) - e0).abs() / swing;
        println!("{name}: error {err:.2e} (rad or m) with {evals} residual evaluations; energy {de:.2e} of the swing energy");
        assert!(err < tol && de < 1e-4, "{name}: error {err:e}, energy {de:e}");
    }
    assert!(dp.residual_evals < 80_000 / 4, "DOPRI5 took {} evaluations", dp.residual_evals);
}

/// The tower crane's hoist (the rope length a fifth coordinate,
/// `TowerCrane::with_hoist`):
/// * with a constant pull `F` below the payload's weight (0.9 m g) and no
///   damping, a large coupled motion (slewing, trolley moving, both
///   sways, the rope paying out) keeps `T + V + F l` constant (RK4 at
///   1 ms, ≤ 1e-9 relative) and the angular momentum about the tower;
/// * hauling a swinging payload in slowly (15 m to 7.5 m at 0.05 m/s
///   through a stiff speed loop, pivot held) grows its swing as the
///   variable-length pendulum's adiabatic invariant says,
///   `θ ∝ l^(−3/4)`: by `2^(3/4)` = 1.682, within 1 %.
#[test]
fn tower_crane_hoist_conserves_energy_and_keeps_the_adiabatic_invariant() {
    let (m, l0) = (2000.0, 15.0);
    let mut crane = TowerCrane::new(2e5, 800.0, m, l0).unwrap().with_hoist(300.0).unwrap();
    let pull = 0.9 * m * G;
    crane.hoist.as_mut().unwrap().force = pull;
    let mut sys = crane.system();
    let mut state = State::new(&mut sys, 0.0, vec![0.0, 20.0, 0.3, -0.2, l0], vec![0.2, 0.5, 0.0, 0.1, 0.0]).unwrap();
    let energy = |sys: &mut bevy_rapier_cable::crane::LagrangeSystem<TowerCrane>, state: &State| {
        sys.kinetic_energy(&state.q, &state.v) + sys.potential_energy(&state.q) + pull * state.q[4]
    };
    let (e0, h0) = (energy(&mut sys, &state), sys.angular_momentum(&state.q, &state.v));
    let scale = sys.kinetic_energy(&state.q, &state.v);
    let mut integrator = rk4();
    let (mut de, mut dh) = (0.0f64, 0.0f64);
    while state.t < 10.0 - 1e-12 {
        integrator.step(&mut sys, &mut state, 1e-3).unwrap();
        de = de.max((energy(&mut sys, &state) - e0).abs() / scale);
        dh = dh.max((sys.angular_momentum(&state.q, &state.v) - h0).abs() / h0.abs());
    }
    println!("hoist paying out under 0.9 m g for 10 s (rope {:.3} m): energy drift {de:.2e}, angular momentum drift {dh:.2e}", state.q[4]);
    assert!(state.q[4] > l0 + 1.0, "the rope should pay out: {}", state.q[4]);
    assert!(de < 1e-9 && dh < 1e-9, "energy {de:e}, angular momentum {dh:e}");
    // Hauling in a swinging payload under a held pivot.
    let crane = TowerCrane::new(1e12, 1e12, m, l0).unwrap().with_hoist(300.0).unwrap();
    let mut sys = crane.system();
    let mut state = State::new(&mut sys, 0.0, vec![0.0, 20.0, 0.02, 0.0, l0], vec![0.0; 5]).unwrap();
    let mut integrator = Integrator::default();
    let (speed, haul) = (0.05, 7.5);
    let (start, stop) = (20.0, 20.0 + haul / speed);
    let (mut before, mut after) = (0.0f64, 0.0f64);
    while state.t < stop + 20.0 {
        let t = state.t;
        let command = if t >= start && t < stop { -speed } else { 0.0 };
        let target = l0 - speed * (t - start).clamp(0.0, stop - start);
        // Speed loop with a weak position term, on top of holding the weight.
        sys.model.hoist.as_mut().unwrap().force = m * G + 1e5 * (state.v[4] - command) + 1e4 * (state.q[4] - target);
        integrator.step(&mut sys, &mut state, 1e-3).unwrap();
        if state.t < start {
            before = before.max(state.q[2].abs());
        } else if state.t > stop {
            after = after.max(state.q[2].abs());
        }
    }
    let (ratio, closed) = (after / before, (l0 / (l0 - haul)).powf(0.75));
    println!(
        "hauled in from 15 m to {:.4} m: swing {before:.5} → {after:.5} rad, ×{ratio:.4} vs (l₀/l₁)^(3/4) = {closed:.4} ({:+.2e})",
        state.q[4],
        ratio / closed - 1.0
    );
    assert!((state.q[4] - (l0 - haul)).abs() < 1e-3, "rope at {}", state.q[4]);
    assert!((ratio / closed - 1.0).abs() < 0.01, "swing ratio {ratio} vs {closed}");
}

/// `crane::linearize` (every model's linearisation from its own nonlinear
/// residual): on the overhead crane it gives `OverheadCrane::linearized`'s
/// hand-written matrices (damping included) within 1e-7; on the tower
/// crane at 20 m the mass matrix of REFERENCE.md §6 and the stiffness
/// `diag(0, 0, m g l, m g l)`, and on the forestry crane
/// `diag(0, m g l, m g l)`, each with `det(K − ω² M) = 0` at the
/// closed-form frequencies (relative to `det(ω² M)`, within 1e-6); with
/// the tower's hoist held by `m g`, the rope length adds the inertia
/// `m + m_d` and no stiffness.
#[test]
fn every_crane_model_linearises_to_its_closed_form() {
    let close = |a: &[f64], b: &[f64], tol: f64, what: &str| {
        let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= tol * scale, "{what}: {a:?} vs {b:?}");
        }
    };
    // Overhead crane, with damping.
    let crane = OverheadCrane::new(500.0, 1000.0, 10.0).unwrap().with_damping(30.0, 200.0);
    let hand = crane.linearized().unwrap();
    let generic = linearize(&mut crane.system(), 0.0, &[0.0, 0.0]).unwrap();
    close(generic.mass(), hand.mass(), 1e-7, "overhead mass");
    close(generic.damping(), hand.damping(), 1e-7, "overhead damping");
    close(generic.stiffness(), hand.stiffness(), 1e-7, "overhead stiffness");
    // det(K − ω² M) for an n × n system, by Gaussian elimination.
    let det = |sys: &bevy_rapier_cable::integrate::DenseSystem, w: f64| -> (f64, f64) {
        let n = (sys.mass().len() as f64).sqrt() as usize;
        let mut a: Vec<f64> = sys.stiffness().iter().zip(sys.mass()).map(|(k, m)| k - w * w * m).collect();
        let mut scaled: Vec<f64> = sys.mass().iter().map(|m| w * w * m).collect();
        let mut d = [1.0, 1.0];
        for (k, mat) in [&mut a, &mut scaled].into_iter().enumerate() {
            for c in 0..n {
                let p = (c..n).max_by(|&i, &j| mat[i * n + c].abs().total_cmp(&mat[j * n + c].abs())).unwrap();
                if p != c {
                    for x in 0..n {
                        mat.swap(c * n + x, p * n + x);
                    }
                    d[k] = -d[k];
                }
                let piv = mat[c * n + c];
                d[k] *= piv;
                if piv == 0.0 {
                    break;
                }
                for r in c + 1..n {
                    let f = mat[r * n + c] / piv;
                    for x in c..n {
                        mat[r * n + x] -= f * mat[c * n + x];
                    }
                }
            }
        }
        (d[0], d[1])
    };
    // Tower crane at radius 20 m.
    let (j, mm, m, l, x) = (2e5, 800.0, 2000.0, 15.0, 20.0);
    let tower = TowerCrane::new(j, mm, m, l).unwrap();
    let (wr, wt) = (tower.radial_frequency(), tower.tangential_frequency(x));
    let lin = linearize(&mut tower.clone().system(), 0.0, &[0.3, x, 0.0, 0.0]).unwrap();
    let mgl = m * G * l;
    let expected_mass = [j + (mm + m) * x * x, 0.0, 0.0, m * l * x, 0.0, mm + m, m * l, 0.0, 0.0, m * l, m * l * l, 0.0, m * l * x, 0.0, 0.0, m * l * l];
    close(lin.mass(), &expected_mass, 1e-9, "tower mass");
    close(lin.stiffness(), &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, mgl, 0.0, 0.0, 0.0, 0.0, mgl], 1e-7, "tower stiffness");
    for (name, w) in [("tower radial", wr), ("tower tangential", wt)] {
        let (d, s) = det(&lin, w);
        println!("{name}: det(K − ω²M)/det(ω²M) = {:.1e} at the closed-form ω = {w:.6} rad/s", d / s);
        assert!((d / s).abs() < 1e-6, "{name}: {}", d / s);
    }
    // A frequency off by 1 % is not a root.
    assert!((det(&lin, 1.01 * wr).0 / det(&lin, 1.01 * wr).1).abs() > 1e-3);
    // Forestry crane.
    let (mf, mb, lf) = (300.0, 1500.0, 6.0);
    let lin = linearize(&mut ForestryCrane::new(mf, mb, lf).unwrap().system(), 0.0, &[0.0; 3]).unwrap();
    let k = mb * G * lf;
    close(lin.stiffness(), &[0.0, 0.0, 0.0, 0.0, k, 0.0, 0.0, 0.0, k], 1e-7, "forestry stiffness");
    for (name, w) in [("forestry in plane", (G * (mf + mb) / (mf * lf)).sqrt()), ("forestry across", (G / lf).sqrt())] {
        let (d, s) = det(&lin, w);
        println!("{name}: det(K − ω²M)/det(ω²M) = {:.1e}", d / s);
        assert!((d / s).abs() < 1e-6, "{name}: {}", d / s);
    }
    // The tower's hoist held by m g.
    let hoisted = tower.with_hoist(300.0).unwrap();
    let lin = linearize(&mut hoisted.system(), 0.0, &[0.3, x, 0.0, 0.0, l]).unwrap();
    assert!((lin.mass()[24] - (m + 300.0)).abs() < 1e-9 * m, "hoist inertia {}", lin.mass()[24]);
    assert!(
        lin.stiffness()[20..25].iter().chain([4usize, 9, 14, 19].iter().map(|&i| &lin.stiffness()[i])).all(|k| k.abs() < 1e-6 * mgl),
        "hoist stiffness {:?}",
        lin.stiffness()
    );
}

/// The 3-mass hoist (drum J = 50 kg·m², r_e = 0.25 m, boom tip 100 kg on
/// k_b = 4e6 N/m, rope k = 2e6 N/m, 10 t) held by the static torque
/// `r_e m g`, hanging: `linearize` gives REFERENCE.md §7's matrices in
/// `(φ, y_b, y_p)` (`M = diag(J, m_b, m)`, `K` from `½k_b y_b² + ½k(r_e φ +
/// y_b − y_p)²`) within 1e-7, with a zero mode (drum and payload turning
/// and falling together) and the rope–boom modes; undamped, a swing of
/// the payload keeps `T + V − T_hold φ` constant (RK4 at 0.1 ms, 5 s, the
/// rope taut throughout, ≤ 1e-9 relative).
#[test]
fn hoist_linearises_to_its_closed_form_and_conserves_energy() {
    let (j, re, mb, kb, k, m) = (50.0, 0.25, 100.0, 4e6, 2e6, 1e4);
    let hold = re * m * G;
    let hoist = Hoist::new(j, re, mb, kb, k, m).unwrap().with_drive(HoistDrive::Torque(hold));
    let q0 = hoist.hanging(4.0);
    let mut sys = hoist.clone();
    let lin = linearize(&mut sys, 0.0, &q0).unwrap();
    let expected_k = [k * re * re, k * re, -k * re, k * re, k + kb, -k, -k * re, -k, k];
    let expected_m = [j, 0.0, 0.0, 0.0, mb, 0.0, 0.0, 0.0, m];
    for (what, got, want) in [("mass", lin.mass(), &expected_m[..]), ("stiffness", lin.stiffness(), &expected_k[..])] {
        let scale = want.iter().fold(0.0f64, |s, x| s.max(x.abs()));
        for (a, b) in got.iter().zip(want) {
            assert!((a - b).abs() < 1e-7 * scale, "hoist {what}: {got:?} vs {want:?}");
        }
    }
    // The zero mode: K is singular (drum and payload moving together).
    let kk = lin.stiffness();
    let det = kk[0] * (kk[4] * kk[8] - kk[5] * kk[7]) - kk[1] * (kk[3] * kk[8] - kk[5] * kk[6]) + kk[2] * (kk[3] * kk[7] - kk[4] * kk[6]);
    let size = (k * re * re) * (k + kb) * k;
    assert!(det.abs() < 1e-6 * size, "det K = {det:e} of {size:e}");
    // Energy with the holding torque's potential −T φ.
    let energy = |q: &[f64], v: &[f64]| {
        let e = re * q[0] + q[1] - q[2] - hoist.slack;
        0.5 * j * v[0] * v[0] + 0.5 * mb * v[1] * v[1] + 0.5 * m * v[2] * v[2] + 0.5 * kb * q[1] * q[1] + 0.5 * k * e.max(0.0).powi(2) + m * G * q[2]
            - hold * q[0]
    };
    let mut state = State::new(&mut sys, 0.0, q0.clone(), vec![0.0, 0.0, 0.05]).unwrap();
    let e0 = energy(&state.q, &state.v);
    let scale = 0.5 * m * 0.05 * 0.05;
    let mut integrator = rk4();
    let (mut de, mut least) = (0.0f64, f64::INFINITY);
    while state.t < 5.0 - 1e-12 {
        integrator.step(&mut sys, &mut state, 1e-4).unwrap();
        de = de.max((energy(&state.q, &state.v) - e0).abs() / scale);
        least = least.min(sys.rope_force(&state.q, &state.v));
    }
    println!("hoist held by its static torque: linearisation as REFERENCE.md §7; energy drift {de:.2e} of the swing's over 5 s, least rope force {least:.0} N");
    assert!(least > 0.0, "the rope went slack");
    assert!(de < 1e-9, "energy drift {de:e}");
}
