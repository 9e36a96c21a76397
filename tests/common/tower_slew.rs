//! The reduced tower crane through a slew, for the tests that compare
//! against it.

use bevy_rapier_cable::crane::control::ShapedMove;
use bevy_rapier_cable::crane::TowerCrane;
use bevy_rapier_cable::integrate::{Integrator, State};

/// `TowerCrane` (J = 2e5 kg·m², trolley 800 kg held at radius `x` m by a
/// stiff loop, a 2 t point payload on a massless `l` m rope) slewed by a
/// stiff speed loop following `shaped`, 1 ms steps until `end` + 20 s:
/// the largest swing after `end` (s), the payload's horizontal offset
/// from the trolley over `l`, rad.
pub fn reduced_slew_swing(shaped: &ShapedMove, end: f64, x: f64, l: f64) -> f64 {
    let mut sys = TowerCrane::new(2e5, 800.0, 2000.0, l).unwrap().system();
    let mut state = State::new(&mut sys, 0.0, vec![0.0, x, 0.0, 0.0], vec![0.0; 4]).unwrap();
    let mut integrator = Integrator::default();
    let mut swing = 0.0f64;
    while state.t < end + 20.0 {
        // A stiff slew speed loop; the trolley held at its radius.
        sys.model.slew_torque = 1e9 * (shaped.speed(state.t) - state.v[0]);
        sys.model.trolley_force = -1e7 * (state.q[1] - x) - 1e6 * state.v[1];
        integrator.step(&mut sys, &mut state, 1e-3).unwrap();
        if state.t > end {
            let p = sys.points(&state.q, &state.v);
            let (dx, dz) = (p[1].0[0] - p[0].0[0], p[1].0[2] - p[0].0[2]);
            swing = swing.max(dx.hypot(dz) / l);
        }
    }
    swing
}
