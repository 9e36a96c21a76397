//! The overhead (bridge) crane: a trolley on a rail carrying a payload on a
//! rope of fixed length (REFERENCE.md §6).

use super::lagrange::{Jet, LagrangeSystem, PointMassModel};
use super::{check_positive, CraneError, TrolleyDrive};
use crate::integrate::{DenseSystem, DenseSystemError};

/// Trolley (mass `M` on a horizontal rail, position `x`) and payload (point
/// mass `m` on a massless rope of length `l`, sway angle `θ` from the
/// downward vertical, positive when the payload is ahead of the trolley
/// along `+x`). Coordinates `q = [x, θ]` (m, rad). Equations of motion:
///
/// `(M + m) ẍ + m l (θ̈ cos θ − θ̇² sin θ) = F − c_x ẋ`,
/// `m l² θ̈ + m l ẍ cos θ + m g l sin θ = −c_θ θ̇`,
///
/// with `F` the drive force ([`TrolleyDrive`]). The world frame is y-up:
/// the trolley runs along x at height 0.
#[derive(Clone, Debug, PartialEq)]
pub struct OverheadCrane {
    /// Trolley mass `M`, kg (with the drive's inertia referred to the rail).
    pub trolley_mass: f64,
    /// Payload mass `m`, kg.
    pub payload_mass: f64,
    /// Rope length `l` (trolley to the payload's centre of mass), m.
    pub rope_length: f64,
    /// Gravitational acceleration `g`, m/s².
    pub gravity: f64,
    /// Viscous rail friction `c_x`, N·s/m.
    pub trolley_damping: f64,
    /// Viscous sway damping `c_θ`, N·m·s/rad.
    pub sway_damping: f64,
    /// The trolley drive.
    pub drive: TrolleyDrive,
}

impl OverheadCrane {
    /// An undamped crane in standard gravity (9.81 m/s²) with a zero drive
    /// force. Masses and the rope length must be positive and finite.
    pub fn new(trolley_mass: f64, payload_mass: f64, rope_length: f64) -> Result<Self, CraneError> {
        check_positive("overhead crane", "trolley_mass", trolley_mass)?;
        check_positive("overhead crane", "payload_mass", payload_mass)?;
        check_positive("overhead crane", "rope_length", rope_length)?;
        Ok(OverheadCrane { trolley_mass, payload_mass, rope_length, gravity: 9.81, trolley_damping: 0.0, sway_damping: 0.0, drive: TrolleyDrive::Force(0.0) })
    }

    /// The reduced model of a payload of mass `payload_mass` (kg) whose
    /// centre hangs `payload_distance` (m) below the trolley's rope point
    /// on a rope of `rope_length` m and `rope_density` kg/m (the rope
    /// straight from the rope point). The rope's mass is lumped as in a
    /// rigid compound pendulum: the payload becomes `m + ρL` at
    /// `l = (m d² + ρL³/3)/(m d + ρL²/2)`, which keeps the pendulum's
    /// `ω² = g (m d + ρL²/2)/(m d² + ρL³/3)`. Every value must be positive
    /// and finite (the rope density may be 0).
    pub fn with_rope_mass(trolley_mass: f64, payload_mass: f64, payload_distance: f64, rope_density: f64, rope_length: f64) -> Result<Self, CraneError> {
        check_positive("overhead crane", "payload_distance", payload_distance)?;
        check_positive("overhead crane", "rope_length", rope_length)?;
        if !(rope_density.is_finite() && rope_density >= 0.0) {
            return Err(CraneError::InvalidParameter {
                model: "overhead crane",
                field: "rope_density",
                value: rope_density,
                requirement: "non-negative and finite",
            });
        }
        let (m, d, rho, l) = (payload_mass, payload_distance, rope_density, rope_length);
        let length = (m * d * d + rho * l.powi(3) / 3.0) / (m * d + rho * l * l / 2.0);
        OverheadCrane::new(trolley_mass, m + rho * l, length)
    }

    /// With rail friction `c_x` (N·s/m) and sway damping `c_θ` (N·m·s/rad).
    pub fn with_damping(mut self, trolley: f64, sway: f64) -> Self {
        self.trolley_damping = trolley;
        self.sway_damping = sway;
        self
    }

    /// With a drive.
    pub fn with_drive(mut self, drive: TrolleyDrive) -> Self {
        self.drive = drive;
        self
    }

    /// Small-swing angular frequency with the trolley free (no drive force,
    /// no damping): `ω² = g (M + m)/(M l)`, rad/s.
    pub fn free_trolley_frequency(&self) -> f64 {
        (self.gravity * (self.trolley_mass + self.payload_mass) / (self.trolley_mass * self.rope_length)).sqrt()
    }

    /// Small-swing angular frequency with the trolley held still:
    /// `ω² = g/l`, rad/s.
    pub fn pendulum_frequency(&self) -> f64 {
        (self.gravity / self.rope_length).sqrt()
    }

    /// The equations linearised about rest (`θ = θ̇ = 0`), without the drive:
    /// `[[M + m, m l], [m l, m l²]] q̈ + diag(c_x, c_θ) q̇ + [[0, 0], [0, m g l]] q = [F, 0]`.
    /// An error when a field was set to a non-finite value.
    pub fn linearized(&self) -> Result<DenseSystem, DenseSystemError> {
        let (mm, m, l) = (self.trolley_mass, self.payload_mass, self.rope_length);
        DenseSystem::new(
            2,
            vec![mm + m, m * l, m * l, m * l * l],
            vec![self.trolley_damping, 0.0, 0.0, self.sway_damping],
            vec![0.0, 0.0, 0.0, m * self.gravity * l],
        )
    }

    /// The nonlinear equations as a system every integrator steps.
    pub fn system(self) -> LagrangeSystem<Self> {
        LagrangeSystem::new(self)
    }
}

impl PointMassModel for OverheadCrane {
    fn dof(&self) -> usize {
        2
    }
    fn masses(&self) -> Vec<f64> {
        vec![self.trolley_mass, self.payload_mass]
    }
    fn positions(&self, q: &[Jet], out: &mut [[Jet; 3]]) {
        let zero = Jet::constant(0.0);
        let l = self.rope_length;
        out[0] = [q[0], zero, zero];
        out[1] = [q[0] + q[1].sin() * l, -(q[1].cos() * l), zero];
    }
    fn gravity(&self) -> [f64; 3] {
        [0.0, -self.gravity, 0.0]
    }
    fn applied_forces(&self, _t: f64, _q: &[f64], v: &[f64], out: &mut [f64]) {
        out[0] = self.drive.force(v[0]) - self.trolley_damping * v[0];
        out[1] = -self.sway_damping * v[1];
    }
}
