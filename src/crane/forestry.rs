//! The forestry crane's log bundle (seed 004): a trolley with a bundle of
//! logs swinging on its rope in the trolley's vertical plane and out of it.

use super::lagrange::{Jet, LagrangeSystem, PointMassModel};
use super::{check_positive, CraneError, TrolleyDrive};

/// Trolley (mass `M`, position `x` along its rail, the world x axis) and a
/// log bundle (mass `m`, lumped at the end of a massless rope of length
/// `l`, as in seed 004). Coordinates `q = [x, α, β]` (m, rad, rad): `α`
/// the swing in the trolley's vertical plane (positive ahead, along +x),
/// `β` the swing out of it (positive along +z); the bundle is at
/// `(x + l sin α cos β, −l cos α cos β, l sin β)`, y up.
///
/// Seed 004 writes the swing as a polar angle `θ` from the vertical and
/// an azimuth `φ` in the horizontal plane (the bundle at
/// `(x + l sin θ cos φ, −l cos θ, l sin θ sin φ)`). Its mass matrix is
/// singular at `θ = 0` (the azimuth is undefined when the bundle hangs
/// straight down), which every swing through the vertical crosses, so the
/// model uses the two regular angles and gives the seed's pair by
/// [`ForestryCrane::polar_angles`]. Dissipation: viscous on the trolley and
/// on both swing angles (the seed's dissipation function `D`).
#[derive(Clone, Debug, PartialEq)]
pub struct ForestryCrane {
    /// Trolley mass `M`, kg.
    pub trolley_mass: f64,
    /// Log bundle mass `m`, kg.
    pub bundle_mass: f64,
    /// Rope length `l`, m.
    pub rope_length: f64,
    /// Gravitational acceleration, m/s².
    pub gravity: f64,
    /// Viscous damping of the trolley (N·s/m) and of the swing angles
    /// (N·m·s/rad).
    pub damping: (f64, f64),
    /// The trolley drive.
    pub drive: TrolleyDrive,
}

impl ForestryCrane {
    /// An undamped crane in standard gravity with a zero drive force.
    pub fn new(trolley_mass: f64, bundle_mass: f64, rope_length: f64) -> Result<Self, CraneError> {
        check_positive("forestry crane", "trolley_mass", trolley_mass)?;
        check_positive("forestry crane", "bundle_mass", bundle_mass)?;
        check_positive("forestry crane", "rope_length", rope_length)?;
        Ok(ForestryCrane { trolley_mass, bundle_mass, rope_length, gravity: 9.81, damping: (0.0, 0.0), drive: TrolleyDrive::Force(0.0) })
    }

    /// Seed 004's swing angles `(θ, φ)` (rad): the polar angle of the rope
    /// from the downward vertical and its azimuth in the horizontal plane
    /// from +x (0 when the bundle hangs straight down).
    pub fn polar_angles(alpha: f64, beta: f64) -> (f64, f64) {
        let (dx, dz, down) = (alpha.sin() * beta.cos(), beta.sin(), alpha.cos() * beta.cos());
        let horizontal = dx.hypot(dz);
        (horizontal.atan2(down), if horizontal == 0.0 { 0.0 } else { dz.atan2(dx) })
    }

    /// The nonlinear equations as a system every integrator steps.
    pub fn system(self) -> LagrangeSystem<Self> {
        LagrangeSystem::new(self)
    }
}

impl PointMassModel for ForestryCrane {
    fn dof(&self) -> usize {
        3
    }
    fn masses(&self) -> Vec<f64> {
        vec![self.trolley_mass, self.bundle_mass]
    }
    fn positions(&self, q: &[Jet], out: &mut [[Jet; 3]]) {
        let zero = Jet::constant(0.0);
        let l = self.rope_length;
        let cb = q[2].cos();
        out[0] = [q[0], zero, zero];
        out[1] = [q[0] + q[1].sin() * cb * l, -(q[1].cos() * cb * l), q[2].sin() * l];
    }
    fn gravity(&self) -> [f64; 3] {
        [0.0, -self.gravity, 0.0]
    }
    fn applied_forces(&self, _t: f64, _q: &[f64], v: &[f64], out: &mut [f64]) {
        out[0] = self.drive.force(v[0]) - self.damping.0 * v[0];
        out[1] = -self.damping.1 * v[1];
        out[2] = -self.damping.1 * v[2];
    }
}
