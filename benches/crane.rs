//! Cost of the reduced crane models (issue 15), thread CPU time: one
//! closed-loop step of the overhead crane (the double-loop PID, generalized-α
//! at 1 ms, the FD tangent), one RK4 step, one tower crane residual, and a
//! DOPRI5 integration of a swing. `docs/control.md` reports them as
//! multiples of real time.

use bevy_rapier_cable::crane::control::{DoubleLoopPid, Move, OverheadCraneLoop};
use bevy_rapier_cable::crane::{OverheadCrane, TowerCrane};
use bevy_rapier_cable::integrate::{DormandPrince, Integrator, Scheme, SecondOrderSystem, State, Substeps};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

#[path = "common/cpu_time.rs"]
mod cpu_time;

fn crane_loop(c: &mut Criterion<cpu_time::ThreadCpuTime>) {
    let crane = OverheadCrane::new(500.0, 1000.0, 10.0).unwrap();
    let mv = Move { t0: 0.0, start: 0.0, target: 10.0, max_speed: 1.0, max_acceleration: 0.25 };
    let (mut p, s) = DoubleLoopPid::place_poles(&crane, [(1.2, 0.7), (1.8, 0.7)]);
    p.ki = 0.05 * p.kp;
    let pid = DoubleLoopPid::new(mv, p, s, 2e4).unwrap();
    let mut lp = OverheadCraneLoop::new(crane.clone(), pid, 0.0, 1e6, 2e4).unwrap();
    c.bench_function("crane/overhead_pid_step_1ms", |b| b.iter(|| black_box(lp.step(1e-3).unwrap())));

    let mut sys = crane.clone().system();
    let mut state = State::new(&mut sys, 0.0, vec![0.0, 0.5], vec![0.0, 0.0]).unwrap();
    let mut rk4 = Integrator::new(Scheme::Rk4);
    rk4.substeps = Substeps::Unchecked(1);
    c.bench_function("crane/overhead_rk4_step_1ms", |b| b.iter(|| black_box(rk4.step(&mut sys, &mut state, 1e-3).unwrap())));

    let mut tower = TowerCrane::new(2e5, 800.0, 2000.0, 15.0).unwrap().system();
    let (q, v, a) = ([0.3, 20.0, 0.2, -0.1], [0.1, 0.5, 0.0, 0.2], [0.0; 4]);
    let mut r = [0.0; 4];
    c.bench_function("crane/tower_residual", |b| {
        b.iter(|| {
            tower.residual(0.0, black_box(&q), &v, &a, &mut r).unwrap();
            black_box(r[0])
        })
    });

    let mut sys = crane.system();
    c.bench_function("crane/overhead_dopri5_20s_tol1e-8", |b| {
        b.iter(|| {
            let mut state = State::new(&mut sys, 0.0, vec![0.0, 0.5], vec![0.0, 0.0]).unwrap();
            let mut dp = DormandPrince::new(1e-8, 1e-8).unwrap();
            black_box(dp.integrate(&mut sys, &mut state, 20.0).unwrap())
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(cpu_time::ThreadCpuTime).sample_size(20);
    targets = crane_loop
}
criterion_main!(benches);
