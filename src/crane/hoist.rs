//! The 3-mass, 2-DOF hoisting mechanism of a boom crane (seed 000,
//! REFERENCE.md §7): the drive referred to the drum, the boom tip, and the
//! payload on the hoist rope.

use super::{check_positive, CraneError};
use crate::integrate::{SecondOrderSystem, SystemError};

/// How the hoist drum is driven.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HoistDrive {
    /// A given torque on the drum, N·m (positive hauls in).
    Torque(f64),
    /// A speed-controlled drive: the hook speed command `command` (m/s,
    /// positive hoists) becomes a drum speed `command / r_e`, and the
    /// torque is `clamp(gain (ω_cmd − φ̇), ±max_torque)`.
    Speed {
        /// Hook speed command, m/s.
        command: f64,
        /// Speed-loop gain, N·m·s/rad.
        gain: f64,
        /// Torque limit, N·m.
        max_torque: f64,
    },
}

/// Drum (angle `φ`, rad, positive hauling in; inertia `J` of motor, gear
/// and drum referred to the drum shaft), boom tip (vertical deflection
/// `y_b`, m, positive up, from its unloaded position; mass `m_b`,
/// stiffness `k_b`) and payload with hook (height `y_p`, m, above the
/// ground; mass `m`). The rope between the boom tip and the hook has
/// stiffness `k` and damping `c` (N/m, N·s/m, the whole reeving as seen at
/// the hook) and carries tension only; it hauls in `r_e = R/a` metres of
/// hook travel per radian (drum radius `R`, `a` parts of line).
/// Coordinates `q = [φ, y_b, y_p]`. The rope stretch is
/// `e = r_e φ + y_b − y_p − slack`, its force `F = max(0, k e + c ė)` when
/// `e > 0`, and
///
/// `J φ̈ = T − r_e F`, `m_b ÿ_b = −k_b y_b − c_b ẏ_b − F`,
/// `m ÿ_p = F − m g + N`,
///
/// with `T` the drive torque ([`HoistDrive`]) and `N` the ground's
/// reaction on a payload resting on it (a stiff, damped penalty for
/// `y_p < 0`, compression only). With `slack = 0`, `q = 0` is a grounded
/// payload on a rope just taut.
#[derive(Clone, Debug, PartialEq)]
pub struct Hoist {
    /// Drive inertia referred to the drum, `J`, kg·m².
    pub drum_inertia: f64,
    /// Hook travel per drum radian, `r_e = R/a`, m/rad.
    pub effective_radius: f64,
    /// Boom tip mass `m_b`, kg (the boom's mass lumped at its tip).
    pub boom_mass: f64,
    /// Boom tip stiffness `k_b`, N/m.
    pub boom_stiffness: f64,
    /// Boom tip damping `c_b`, N·s/m.
    pub boom_damping: f64,
    /// Rope stiffness `k` (tip to hook, all parts of line), N/m.
    pub rope_stiffness: f64,
    /// Rope damping `c`, N·s/m.
    pub rope_damping: f64,
    /// Payload and hook mass `m`, kg.
    pub payload_mass: f64,
    /// Slack rope at `q = 0`, m (0: just taut).
    pub slack: f64,
    /// Ground stiffness and damping under the payload, N/m and N·s/m.
    pub ground: (f64, f64),
    /// Gravitational acceleration, m/s².
    pub gravity: f64,
    /// The drive.
    pub drive: HoistDrive,
}

impl Hoist {
    /// A hoist with an undamped rope and boom, no slack, a zero drive
    /// torque, a ground of 1e3 times the rope's stiffness (critically
    /// damped for the payload) and standard gravity. Every value must be
    /// positive and finite.
    pub fn new(
        drum_inertia: f64,
        effective_radius: f64,
        boom_mass: f64,
        boom_stiffness: f64,
        rope_stiffness: f64,
        payload_mass: f64,
    ) -> Result<Self, CraneError> {
        for (field, value) in [
            ("drum_inertia", drum_inertia),
            ("effective_radius", effective_radius),
            ("boom_mass", boom_mass),
            ("boom_stiffness", boom_stiffness),
            ("rope_stiffness", rope_stiffness),
            ("payload_mass", payload_mass),
        ] {
            check_positive("hoist", field, value)?;
        }
        let kg = 1e3 * rope_stiffness;
        Ok(Hoist {
            drum_inertia,
            effective_radius,
            boom_mass,
            boom_stiffness,
            boom_damping: 0.0,
            rope_stiffness,
            rope_damping: 0.0,
            payload_mass,
            slack: 0.0,
            ground: (kg, 2.0 * (kg * payload_mass).sqrt()),
            gravity: 9.81,
            drive: HoistDrive::Torque(0.0),
        })
    }

    /// With a drive.
    pub fn with_drive(mut self, drive: HoistDrive) -> Self {
        self.drive = drive;
        self
    }

    /// The rope force (N) at `(q, q̇)` (0 when slack).
    pub fn rope_force(&self, q: &[f64], v: &[f64]) -> f64 {
        self.rope(q, v).0
    }

    fn rope(&self, q: &[f64], v: &[f64]) -> (f64, f64, f64) {
        let e = self.effective_radius * q[0] + q[1] - q[2] - self.slack;
        let de = self.effective_radius * v[0] + v[1] - v[2];
        let f = self.rope_stiffness * e + self.rope_damping * de;
        if e > 0.0 && f > 0.0 {
            (f, self.rope_stiffness, self.rope_damping)
        } else {
            (0.0, 0.0, 0.0)
        }
    }

    fn ground_force(&self, y: f64, vy: f64) -> (f64, f64, f64) {
        let (k, c) = self.ground;
        let n = -k * y - c * vy;
        if y < 0.0 && n > 0.0 {
            (n, k, c)
        } else {
            (0.0, 0.0, 0.0)
        }
    }

    fn drive_torque(&self, omega: f64) -> (f64, f64) {
        match self.drive {
            HoistDrive::Torque(t) => (t, 0.0),
            HoistDrive::Speed { command, gain, max_torque } => {
                let t = gain * (command / self.effective_radius - omega);
                if t.abs() <= max_torque.abs() {
                    (t, gain)
                } else {
                    (max_torque.abs().copysign(t), 0.0)
                }
            }
        }
    }

    /// The dynamic load factor's classic estimate for hoisting at speed `v`
    /// (m/s) with a rigid drive and boom: `1 + v √(k/m)/g`, the peak rope
    /// force over `m g` when a grounded payload is lifted, a hanging one is
    /// started, or a hoisting one is stopped instantly (REFERENCE.md §7).
    pub fn load_factor_estimate(&self, v: f64) -> f64 {
        1.0 + v.abs() * (self.rope_stiffness / self.payload_mass).sqrt() / self.gravity
    }

    /// The coordinates of static equilibrium with the payload hanging and
    /// the drum at angle `phi` (rad), with `q̇ = 0` (the payload is clear of
    /// the ground when `y_p` = `q[2]` is positive).
    pub fn hanging(&self, phi: f64) -> Vec<f64> {
        let w = self.payload_mass * self.gravity;
        let yb = -w / self.boom_stiffness;
        // r_e φ + y_b − y_p − slack = w/k.
        let yp = self.effective_radius * phi + yb - self.slack - w / self.rope_stiffness;
        vec![phi, yb, yp]
    }
}

impl SecondOrderSystem for Hoist {
    fn dof(&self) -> usize {
        3
    }

    fn residual(&mut self, _t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError> {
        if let Some(index) = q.iter().chain(v).chain(a).position(|x| !x.is_finite()) {
            return Err(SystemError::NonFinite { index: index % 3 });
        }
        let (f, _, _) = self.rope(q, v);
        let (n, _, _) = self.ground_force(q[2], v[2]);
        let (torque, _) = self.drive_torque(v[0]);
        r[0] = self.drum_inertia * a[0] - (torque - self.effective_radius * f);
        r[1] = self.boom_mass * a[1] + self.boom_stiffness * q[1] + self.boom_damping * v[1] + f;
        r[2] = self.payload_mass * a[2] - (f - self.payload_mass * self.gravity + n);
        Ok(())
    }

    fn solve_tangent(&mut self, _t: f64, q: &[f64], v: &[f64], _a: &[f64], c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError> {
        let (_, k, c) = self.rope(q, v);
        let (_, kg, cg) = self.ground_force(q[2], v[2]);
        let (_, kd) = self.drive_torque(v[0]);
        // ∂F/∂(q, q̇) along the stretch gradient g = (r_e, 1, −1).
        let re = self.effective_radius;
        let g = [re, 1.0, -1.0];
        let s = c_q * k + c_v * c;
        // Rows: drum (+r_e F), boom (+F), payload (−F).
        let sign = [re, 1.0, -1.0];
        let mut m = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = sign[i] * s * g[j];
            }
        }
        m[0][0] += self.drum_inertia + c_v * kd;
        m[1][1] += self.boom_mass + c_q * self.boom_stiffness + c_v * self.boom_damping;
        m[2][2] += self.payload_mass + c_q * kg + c_v * cg;
        let mat = glam::DMat3::from_cols_array_2d(&m).transpose();
        let det = mat.determinant();
        if !det.is_finite() || det == 0.0 {
            return Err(SystemError::Singular { index: 0, pivot: det });
        }
        let y = mat.inverse() * glam::DVec3::new(b[0], b[1], b[2]);
        x.copy_from_slice(&[y.x, y.y, y.z]);
        Ok(())
    }
}
