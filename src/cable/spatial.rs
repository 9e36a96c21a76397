//! Spatial (6D) vectors and matrices in the world frame, about a fixed
//! reference point (Featherstone's notation).
//!
//! Motion vectors are `[ω; v]` (angular velocity, velocity of the body point
//! at the reference point), force vectors `[n; F]` (moment about the
//! reference point, force). All in f64.

use glam::{DMat3, DVec3};
use std::ops::{Add, AddAssign, Mul, Neg, Sub};

/// A spatial vector: `top` = angular part, `bot` = linear part.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct V6 {
    /// Angular part (ω or moment n).
    pub top: DVec3,
    /// Linear part (v or force F).
    pub bot: DVec3,
}

impl V6 {
    /// The zero vector.
    pub const ZERO: V6 = V6 { top: DVec3::ZERO, bot: DVec3::ZERO };

    /// Builds a spatial vector from its angular and linear parts.
    #[inline]
    pub fn new(top: DVec3, bot: DVec3) -> Self {
        Self { top, bot }
    }
    /// Scalar product `aᵀ b`.
    #[inline]
    pub fn dot(self, o: V6) -> f64 {
        self.top.dot(o.top) + self.bot.dot(o.bot)
    }
    /// Motion cross motion: `self ×ₘ m`.
    #[inline]
    pub fn cross_motion(self, m: V6) -> V6 {
        V6::new(self.top.cross(m.top), self.top.cross(m.bot) + self.bot.cross(m.top))
    }
    /// Motion cross force: `self ×* f`.
    #[inline]
    pub fn cross_force(self, f: V6) -> V6 {
        V6::new(self.top.cross(f.top) + self.bot.cross(f.bot), self.top.cross(f.bot))
    }
    /// Whether every component is finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.top.is_finite() && self.bot.is_finite()
    }
}

impl Add for V6 {
    type Output = V6;
    #[inline]
    fn add(self, o: V6) -> V6 {
        V6::new(self.top + o.top, self.bot + o.bot)
    }
}
impl AddAssign for V6 {
    #[inline]
    fn add_assign(&mut self, o: V6) {
        self.top += o.top;
        self.bot += o.bot;
    }
}
impl Sub for V6 {
    type Output = V6;
    #[inline]
    fn sub(self, o: V6) -> V6 {
        V6::new(self.top - o.top, self.bot - o.bot)
    }
}
impl Neg for V6 {
    type Output = V6;
    #[inline]
    fn neg(self) -> V6 {
        V6::new(-self.top, -self.bot)
    }
}
impl Mul<f64> for V6 {
    type Output = V6;
    #[inline]
    fn mul(self, s: f64) -> V6 {
        V6::new(self.top * s, self.bot * s)
    }
}

/// A 6×6 matrix in 3×3 blocks `[[a, b], [c, d]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct M6 {
    /// Upper-left block.
    pub a: DMat3,
    /// Upper-right block.
    pub b: DMat3,
    /// Lower-left block.
    pub c: DMat3,
    /// Lower-right block.
    pub d: DMat3,
}

impl Default for M6 {
    fn default() -> Self {
        M6::ZERO
    }
}

impl M6 {
    /// The zero matrix.
    pub const ZERO: M6 = M6 { a: DMat3::ZERO, b: DMat3::ZERO, c: DMat3::ZERO, d: DMat3::ZERO };

    /// Matrix–vector product.
    #[inline]
    pub fn mul_vec(&self, x: V6) -> V6 {
        V6::new(self.a * x.top + self.b * x.bot, self.c * x.top + self.d * x.bot)
    }
    /// Product with a motion vector `[ω; v]` that may be purely linear
    /// (`ω = 0`, a prismatic axis): half the work then.
    #[inline]
    pub fn mul_motion(&self, x: V6) -> V6 {
        if x.top == DVec3::ZERO {
            V6::new(self.b * x.bot, self.d * x.bot)
        } else {
            self.mul_vec(x)
        }
    }
    /// Transpose.
    #[inline]
    pub fn transpose(&self) -> M6 {
        M6 { a: self.a.transpose(), b: self.c.transpose(), c: self.b.transpose(), d: self.d.transpose() }
    }
    /// Outer product `u wᵀ`.
    #[inline]
    pub fn outer(u: V6, w: V6) -> M6 {
        M6 { a: outer3(u.top, w.top), b: outer3(u.top, w.bot), c: outer3(u.bot, w.top), d: outer3(u.bot, w.bot) }
    }
    /// Scales every entry.
    #[inline]
    pub fn scale(&self, s: f64) -> M6 {
        M6 { a: self.a * s, b: self.b * s, c: self.c * s, d: self.d * s }
    }
    /// Spatial inertia of a rigid body: mass `m`, centre of mass `c` and
    /// rotational inertia `ic` about the centre of mass, all in the world
    /// frame (relative to the reference point).
    #[inline]
    pub fn inertia(m: f64, c: DVec3, ic: DMat3) -> M6 {
        let cx = skew(c);
        M6 { a: ic + cx * cx.transpose() * m, b: cx * m, c: cx.transpose() * m, d: DMat3::from_diagonal(DVec3::splat(m)) }
    }
    /// `F̄(f)`: the matrix with `a ×* f = F̄(f) a`.
    #[inline]
    pub fn fbar(f: V6) -> M6 {
        let nx = skew(f.top);
        let fx = skew(f.bot);
        M6 { a: -nx, b: -fx, c: -fx, d: DMat3::ZERO }
    }
    /// `B̃`: the load tangent of a force `force` of fixed direction applied
    /// at the world point `c` (its spatial force changes by `B̃ δ` under a
    /// rigid displacement `δ` of the body).
    #[inline]
    pub fn point_load_tangent(force: DVec3, c: DVec3) -> M6 {
        let fx = skew(force);
        M6 { a: fx * skew(c), b: -fx, c: DMat3::ZERO, d: DMat3::ZERO }
    }
    /// `self += other · s`.
    #[inline]
    pub fn add_scaled(&mut self, o: &M6, s: f64) {
        self.a += o.a * s;
        self.b += o.b * s;
        self.c += o.c * s;
        self.d += o.d * s;
    }
    /// `self += s · u wᵀ`.
    #[inline]
    pub fn add_outer(&mut self, u: V6, w: V6, s: f64) {
        let (ut, ub) = (u.top * s, u.bot * s);
        self.a += outer3(ut, w.top);
        self.b += outer3(ut, w.bot);
        self.c += outer3(ub, w.top);
        self.d += outer3(ub, w.bot);
    }
    /// `½(u wᵀ + w uᵀ)`.
    #[inline]
    pub fn sym_outer(u: V6, w: V6) -> M6 {
        let mut m = M6::outer(u, w);
        m.add_outer(w, u, 1.0);
        m.scale(0.5)
    }
    /// Largest absolute entry (for scaling tests and tolerances).
    pub fn max_abs(&self) -> f64 {
        [self.a, self.b, self.c, self.d].iter().flat_map(|m| m.to_cols_array()).fold(0.0, |acc, x| acc.max(x.abs()))
    }
}

impl Add for M6 {
    type Output = M6;
    #[inline]
    fn add(self, o: M6) -> M6 {
        M6 { a: self.a + o.a, b: self.b + o.b, c: self.c + o.c, d: self.d + o.d }
    }
}
impl AddAssign for M6 {
    #[inline]
    fn add_assign(&mut self, o: M6) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
        self.d += o.d;
    }
}
impl Sub for M6 {
    type Output = M6;
    #[inline]
    fn sub(self, o: M6) -> M6 {
        M6 { a: self.a - o.a, b: self.b - o.b, c: self.c - o.c, d: self.d - o.d }
    }
}

/// The cross-product matrix `[c×]`.
#[inline]
pub fn skew(c: DVec3) -> DMat3 {
    DMat3::from_cols(DVec3::new(0.0, c.z, -c.y), DVec3::new(-c.z, 0.0, c.x), DVec3::new(c.y, -c.x, 0.0))
}

/// Outer product `u wᵀ` of two 3-vectors.
#[inline]
pub fn outer3(u: DVec3, w: DVec3) -> DMat3 {
    DMat3::from_cols(u * w.x, u * w.y, u * w.z)
}

/// Rotation matrix about a principal axis (`axis` = 0, 1, 2 for x, y, z)
/// or, for any other unit vector, about that vector.
#[inline]
pub fn rotation_about(axis: DVec3, angle: f64) -> DMat3 {
    DMat3::from_axis_angle(axis, angle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fbar_matches_cross_force() {
        let a = V6::new(DVec3::new(0.3, -1.2, 0.7), DVec3::new(2.0, 0.1, -0.4));
        let f = V6::new(DVec3::new(-0.5, 0.8, 1.1), DVec3::new(0.9, -2.2, 0.3));
        let x = a.cross_force(f);
        let y = M6::fbar(f).mul_vec(a);
        assert!((x - y).top.length() + (x - y).bot.length() < 1e-14);
    }

    #[test]
    fn point_load_tangent_is_antisymmetric_part_fbar() {
        // B̃ − B̃ᵀ = F̄(f) for f the spatial force of F at c.
        let force = DVec3::new(0.4, -3.0, 1.5);
        let c = DVec3::new(1.0, 2.0, -0.5);
        let b = M6::point_load_tangent(force, c);
        let f = V6::new(c.cross(force), force);
        let diff = b - b.transpose() - M6::fbar(f);
        assert!(diff.max_abs() < 1e-13);
    }
}
