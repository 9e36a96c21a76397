//! The tower crane: a slewing jib, a trolley along it and a payload
//! swinging in two angles (REFERENCE.md §6).

use super::lagrange::{Jet, LagrangeSystem, PointMassModel};
use super::{check_positive, CraneError};

/// Slewing jib (inertia `J` about the vertical tower axis, slew angle `γ`),
/// trolley (mass `M` at radius `x` along the jib) and payload (point mass
/// `m` on a massless rope of length `l`). The sway is two angles: `α` in
/// the jib's vertical plane (positive outward, away from the tower) and
/// `β` out of it (positive toward increasing `γ`). Coordinates
/// `q = [γ, x, α, β]` (rad, m, rad, rad).
///
/// World frame y-up, tower along y through the origin; the jib points
/// along `e_r = (cos γ, 0, −sin γ)` (a rotation by `γ` about +y), and
/// `e_t = ŷ × e_r` is the direction the trolley moves when `γ` grows.
/// The payload is at `(x + l sin α cos β) e_r + l sin β e_t − l cos α cos β ŷ`.
/// Linearised about rest at radius `x` (REFERENCE.md §6):
///
/// `(M + m) ẍ + m l α̈ = F_x`, `l α̈ + ẍ + g α = 0`,
/// `(J + (M + m) x²) γ̈ + m l x β̈ = T`, `l β̈ + x γ̈ + g β = 0`.
///
/// With a [`TowerHoist`] ([`TowerCrane::with_hoist`]) the rope length is
/// a fifth coordinate, `q = [γ, x, α, β, l]`: the hoist pays the rope out
/// and hauls it in against the payload (its drum's inertia referred to
/// the rope, its pull, its damping), and the swing follows the length.
#[derive(Clone, Debug, PartialEq)]
pub struct TowerCrane {
    /// Slewing inertia of the jib, counterjib and slewing gear about the
    /// tower axis, kg·m² (the trolley and payload are added by the model).
    pub jib_inertia: f64,
    /// Trolley mass `M`, kg.
    pub trolley_mass: f64,
    /// Payload mass `m`, kg.
    pub payload_mass: f64,
    /// Rope length `l`, m.
    pub rope_length: f64,
    /// Gravitational acceleration `g`, m/s².
    pub gravity: f64,
    /// Slewing torque `T`, N·m.
    pub slew_torque: f64,
    /// Trolley drive force `F_x`, N.
    pub trolley_force: f64,
    /// Viscous damping of the slew (N·m·s/rad), the trolley (N·s/m) and
    /// both sway angles (N·m·s/rad).
    pub damping: [f64; 3],
    /// The hoist, when the rope length is a coordinate (`None`: the rope
    /// length is fixed at [`TowerCrane::rope_length`]).
    pub hoist: Option<TowerHoist>,
}

/// The hoist of a [`TowerCrane`]: the rope length `l` as a coordinate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TowerHoist {
    /// Drum, gear and motor inertia referred to the rope, `J_d / r²`, kg.
    pub drum_mass: f64,
    /// The hoist's pull on the rope, N (positive hauls in, shortening the
    /// rope; `m g` holds the payload at rest).
    pub force: f64,
    /// Viscous damping of the rope's motion, N·s/m.
    pub damping: f64,
}

impl TowerCrane {
    /// An undamped tower crane in standard gravity with no drive forces.
    /// Every parameter must be positive and finite.
    pub fn new(jib_inertia: f64, trolley_mass: f64, payload_mass: f64, rope_length: f64) -> Result<Self, CraneError> {
        check_positive("tower crane", "jib_inertia", jib_inertia)?;
        check_positive("tower crane", "trolley_mass", trolley_mass)?;
        check_positive("tower crane", "payload_mass", payload_mass)?;
        check_positive("tower crane", "rope_length", rope_length)?;
        Ok(TowerCrane {
            jib_inertia,
            trolley_mass,
            payload_mass,
            rope_length,
            gravity: 9.81,
            slew_torque: 0.0,
            trolley_force: 0.0,
            damping: [0.0; 3],
            hoist: None,
        })
    }

    /// The same crane with a hoist: the rope length becomes the fifth
    /// coordinate (its value at rest `rope_length`), the drum's inertia
    /// referred to the rope `drum_mass` (kg, ≥ 0, finite), the pull set to
    /// hold the payload (`m g`), no damping.
    pub fn with_hoist(mut self, drum_mass: f64) -> Result<Self, CraneError> {
        if !(drum_mass.is_finite() && drum_mass >= 0.0) {
            return Err(CraneError::InvalidParameter { model: "tower crane", field: "drum_mass", value: drum_mass, requirement: "at least 0 and finite" });
        }
        self.hoist = Some(TowerHoist { drum_mass, force: self.payload_mass * self.gravity, damping: 0.0 });
        Ok(self)
    }

    /// Small-swing angular frequency of `α` (in the jib plane) at rest with
    /// the trolley free: `ω² = g (M + m)/(M l)`, rad/s.
    pub fn radial_frequency(&self) -> f64 {
        (self.gravity * (self.trolley_mass + self.payload_mass) / (self.trolley_mass * self.rope_length)).sqrt()
    }

    /// Small-swing angular frequency of `β` (out of the jib plane) at rest
    /// at radius `x` (m) with the slew free:
    /// `ω² = g (J + (M + m) x²)/(l (J + M x²))`, rad/s.
    pub fn tangential_frequency(&self, x: f64) -> f64 {
        let (j, mm, m) = (self.jib_inertia, self.trolley_mass, self.payload_mass);
        (self.gravity * (j + (mm + m) * x * x) / (self.rope_length * (j + mm * x * x))).sqrt()
    }

    /// The nonlinear equations as a system every integrator steps.
    pub fn system(self) -> LagrangeSystem<Self> {
        LagrangeSystem::new(self)
    }
}

impl LagrangeSystem<TowerCrane> {
    /// Angular momentum about the tower axis (+y), kg·m²/s, at `(q, q̇)`:
    /// conserved without slewing torque and slew damping.
    pub fn angular_momentum(&mut self, q: &[f64], v: &[f64]) -> f64 {
        let points = self.points(q, v);
        let mut h = self.model.jib_inertia * v[0];
        for ((p, u), m) in points.iter().zip([self.model.trolley_mass, self.model.payload_mass]) {
            // (p × u)·ŷ = z u_x − x u_z.
            h += m * (p[2] * u[0] - p[0] * u[2]);
        }
        h
    }
}

impl PointMassModel for TowerCrane {
    fn dof(&self) -> usize {
        if self.hoist.is_some() {
            5
        } else {
            4
        }
    }
    fn masses(&self) -> Vec<f64> {
        vec![self.trolley_mass, self.payload_mass]
    }
    fn coordinate_inertia(&self, i: usize) -> f64 {
        match (i, self.hoist) {
            (0, _) => self.jib_inertia,
            (4, Some(h)) => h.drum_mass,
            _ => 0.0,
        }
    }
    fn positions(&self, q: &[Jet], out: &mut [[Jet; 3]]) {
        let (cg, sg) = (q[0].cos(), q[0].sin());
        let l = if self.hoist.is_some() { q[4] } else { Jet::constant(self.rope_length) };
        // Radial and tangential distances, and the height.
        let (sa, ca, sb, cb) = (q[2].sin(), q[2].cos(), q[3].sin(), q[3].cos());
        let radial = q[1] + sa * cb * l;
        let tangential = sb * l;
        // e_r = (cos γ, 0, −sin γ), e_t = (−sin γ, 0, −cos γ).
        out[0] = [q[1] * cg, Jet::constant(0.0), -(q[1] * sg)];
        out[1] = [radial * cg - tangential * sg, -(ca * cb * l), -(radial * sg) - tangential * cg];
    }
    fn gravity(&self) -> [f64; 3] {
        [0.0, -self.gravity, 0.0]
    }
    fn applied_forces(&self, _t: f64, _q: &[f64], v: &[f64], out: &mut [f64]) {
        out[0] = self.slew_torque - self.damping[0] * v[0];
        out[1] = self.trolley_force - self.damping[1] * v[1];
        out[2] = -self.damping[2] * v[2];
        out[3] = -self.damping[2] * v[3];
        if let Some(h) = self.hoist {
            // Hauling in shortens the rope.
            out[4] = -h.force - h.damping * v[4];
        }
    }
}
