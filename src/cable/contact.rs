//! Contact laws as implicit force elements (issue 12, first part).
//!
//! [`ImpactLaw`] is the Adams IMPACT normal law of REFERENCE §2:
//!
//! ```text
//! F_n = K δ^e + STEP(δ, 0, 0, d_max, C_max)·δ̇,   F_n ≥ 0
//! ```
//!
//! with `δ` the penetration (m, positive inside) and `δ̇` its rate
//! (positive while approaching). The damping is ramped in over `d_max` by
//! the cubic Hermite step, so the force starts from zero at first touch:
//! with `e > 1` the force and its stiffness are continuous there, which
//! Newton needs. The force is clamped at zero (no adhesion while the bodies
//! separate faster than the spring pushes): the "clamped" column of
//! verification case §7d.
//!
//! [`SphereContact`] applies it to a sphere of radius `r` centred on a
//! point of a link against a plane, frozen for the step (an active set
//! frozen per step): the contact issue finds, at the start of each step,
//! the closest point and normal of a collider for each rope element and
//! puts one such element there. Its tangents `K = ∂F_n/∂δ n nᵀ` and
//! `C = ∂F_n/∂δ̇ n nᵀ` enter the implicit solve like any force element, so
//! a steel contact is as stable at the frame step as the rope's own
//! springs.

use glam::{DMat3, DVec3};

use super::force::{ForceElement, PointState, PointWrench};

/// Why a contact law cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// A parameter is out of its range (or not finite).
    #[error("contact law: {name} = {value} is out of range ({range})")]
    OutOfRange {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        range: &'static str,
    },
}

/// The Adams IMPACT normal force law (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactLaw {
    /// `K`, N/m^e (> 0).
    pub stiffness: f64,
    /// `e`, the force exponent (≥ 1; 1.5 for Hertz).
    pub exponent: f64,
    /// `C_max`, the damping coefficient reached at `d_max`, N·s/m (≥ 0).
    pub max_damping: f64,
    /// `d_max`, the penetration over which the damping is ramped in, m
    /// (> 0).
    pub damping_depth: f64,
}

impl ImpactLaw {
    /// A law, its parameters checked: `stiffness` > 0 (N/m^e), `exponent`
    /// in [1, 4], `max_damping` ≥ 0 (N·s/m), `damping_depth` > 0 (m).
    pub fn new(stiffness: f64, exponent: f64, max_damping: f64, damping_depth: f64) -> Result<Self, ContactError> {
        let check = |name, value: f64, ok: bool, range| if ok && value.is_finite() { Ok(()) } else { Err(ContactError::OutOfRange { name, value, range }) };
        check("stiffness", stiffness, stiffness > 0.0, "> 0 N/m^e")?;
        check("exponent", exponent, (1.0..=4.0).contains(&exponent), "1 to 4")?;
        check("max_damping", max_damping, max_damping >= 0.0, ">= 0 N·s/m")?;
        check("damping_depth", damping_depth, damping_depth > 0.0, "> 0 m")?;
        Ok(ImpactLaw { stiffness, exponent, max_damping, damping_depth })
    }

    /// Hertz's law for two curved bodies (REFERENCE §2): `K = (4/3) E* √R*`,
    /// `e = 1.5`, with `1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂` and
    /// `1/R* = 1/R₁ + 1/R₂` (Pa, m; a flat body has `R = ∞`), and the given
    /// damping (N·s/m, reached at `damping_depth` m).
    pub fn hertz(e_star: f64, r_star: f64, max_damping: f64, damping_depth: f64) -> Result<Self, ContactError> {
        if !(e_star > 0.0 && e_star.is_finite()) {
            return Err(ContactError::OutOfRange { name: "E*", value: e_star, range: "> 0 Pa" });
        }
        if !(r_star > 0.0 && r_star.is_finite()) {
            return Err(ContactError::OutOfRange { name: "R*", value: r_star, range: "> 0 m" });
        }
        Self::new(4.0 / 3.0 * e_star * r_star.sqrt(), 1.5, max_damping, damping_depth)
    }

    /// `(F_n, ∂F_n/∂δ, ∂F_n/∂δ̇)` at penetration `depth` (m, > 0 inside)
    /// and its rate `rate` (m/s, > 0 approaching): N, N/m, N·s/m. Zero
    /// outside, and where the clamp at zero holds.
    pub fn force(&self, depth: f64, rate: f64) -> (f64, f64, f64) {
        if depth <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let (k, e) = (self.stiffness, self.exponent);
        let spring = k * depth.powf(e);
        let spring_rate = e * k * depth.powf(e - 1.0);
        // STEP(δ, 0, 0, d_max, C_max) = C_max Δ² (3 − 2Δ), Δ = δ/d_max ≤ 1.
        let x = depth / self.damping_depth;
        let (c, dc) = if x >= 1.0 {
            (self.max_damping, 0.0)
        } else {
            (self.max_damping * x * x * (3.0 - 2.0 * x), self.max_damping * 6.0 * x * (1.0 - x) / self.damping_depth)
        };
        let f = spring + c * rate;
        if f <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        (f, spring_rate + dc * rate, c)
    }

    /// Energy stored in the spring part at penetration `depth` (m):
    /// `K δ^(e+1)/(e+1)`, J.
    pub fn potential(&self, depth: f64) -> f64 {
        if depth <= 0.0 {
            0.0
        } else {
            self.stiffness * depth.powf(self.exponent + 1.0) / (self.exponent + 1.0)
        }
    }
}

/// A sphere of radius `radius` centred on a link point, against a plane
/// through `point` with unit outward `normal` (the obstacle's surface,
/// frozen for the step), which translates at `velocity` from time `time`
/// (a moving obstacle; zero for a fixed one), pushed out by an
/// [`ImpactLaw`] on the penetration and its rate relative to the plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereContact {
    /// A point of the plane at `time`, world, m.
    pub point: DVec3,
    /// The plane's unit normal, out of the obstacle, world.
    pub normal: DVec3,
    /// The plane's velocity, world, m/s.
    pub velocity: DVec3,
    /// The time at which the plane passes through `point`, s.
    pub time: f64,
    /// The sphere's radius (the rope's radius for a rope element), m.
    pub radius: f64,
    /// The normal law.
    pub law: ImpactLaw,
}

impl SphereContact {
    /// A contact with a fixed plane through `point` (m) with unit outward
    /// `normal`, for a sphere of `radius` m.
    pub fn fixed(point: DVec3, normal: DVec3, radius: f64, law: ImpactLaw) -> Self {
        SphereContact { point, normal, velocity: DVec3::ZERO, time: 0.0, radius, law }
    }

    /// Penetration (m, > 0 inside) and its rate (m/s, > 0 approaching) at
    /// time `t` (s) and the point's state.
    pub fn depth(&self, t: f64, at: &PointState) -> (f64, f64) {
        let plane = self.point + self.velocity * (t - self.time);
        (self.radius - (at.point - plane).dot(self.normal), -(at.velocity - self.velocity).dot(self.normal))
    }

    /// The normal force the plane puts on the sphere at time `t` (s), N
    /// (≥ 0).
    pub fn normal_force(&self, t: f64, at: &PointState) -> f64 {
        let (d, r) = self.depth(t, at);
        self.law.force(d, r).0
    }
}

impl ForceElement for SphereContact {
    fn wrench(&self, t: f64, at: &PointState) -> PointWrench {
        let (depth, rate) = self.depth(t, at);
        let (f, k, c) = self.law.force(depth, rate);
        if f == 0.0 {
            return PointWrench::default();
        }
        let n = self.normal;
        let nn = DMat3::from_cols(n * n.x, n * n.y, n * n.z);
        let mut w = PointWrench { force: n * f, ..Default::default() };
        // f = F_n(δ, δ̇) n with δ = r − (p − p₀)·n, δ̇ = −v·n:
        // −∂f/∂p = ∂F_n/∂δ n nᵀ, −∂f/∂v = ∂F_n/∂δ̇ n nᵀ.
        w.stiffness.d = nn * k;
        w.damping.d = nn * c;
        w
    }

    fn energy(&self, t: f64, at: &PointState) -> f64 {
        self.law.potential(self.depth(t, at).0)
    }

    fn contact_force(&self, t: f64, at: &PointState) -> Option<f64> {
        Some(self.normal_force(t, at))
    }
}
