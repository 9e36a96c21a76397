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
//! puts one such element there (on a curved surface, [`Curve`], against
//! the surface itself; for a rope element's interior, of the element's
//! segment, [`Span`]). Its tangents `K = ∂F_n/∂δ n nᵀ` and
//! `C = ∂F_n/∂δ̇ n nᵀ` enter the implicit solve like any force element, so
//! a steel contact is as stable at the frame step as the rope's own
//! springs.
//!
//! [`CoulombFriction`] adds Coulomb friction with a stick state at the
//! sphere's contact point `c = p − r n` (or its centre), as OrcaFlex's
//! seabed friction does: a
//! tangential spring–damper `F_t = −k_t P (c − a) − c_t P ċ` (`P = I − n nᵀ`)
//! toward an anchor `a` on the obstacle's surface (the "friction target"),
//! capped at `μ F_n` (with `F_n` bounded by the contact's normal force at
//! the end of the previous step and [`BOUND_GROWTH`] more,
//! [`CoulombFriction::normal_bound`]). While
//! `|F_t| ≤ μ F_n` the contact sticks: the anchor
//! stays where it is, and a rope on a slope below `atan μ` holds on the
//! spring's static deflection `μ F_n / k_t` at most (micrometres for steel)
//! and does not creep. Past it the contact slips with `|F_t| = μ F_n`
//! against the trial force's direction, and after the step the anchor is
//! moved to where the spring alone gives that force
//! ([`SphereContact::next_anchor`]), which the caller keeps for the next
//! step. With [`CoulombFriction::at_surface`] the spring stretches with
//! the slip of the sphere's material at the contact point `−r n` from its
//! centre (its displacement plus its turn times that arm), and the
//! friction force acts there, so it also puts the moment `(−r n) × F_t`
//! on the link: a ball rolls without stretching the spring. Without it
//! (the coupling's choice for rope elements) the friction acts at the
//! centre and the sphere does not roll.

use glam::{DMat3, DVec3};

use super::chain::rotation_vector;
use super::force::{ForceElement, FrictionBranch, PairElement, PairWrench, PointState, PointWrench};
use super::spatial::{outer3, skew, M6};

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
    /// and its rate `rate` (m/s, > 0 approaching): N, N/m, N·s/m. All zero
    /// outside; where the clamp at zero holds (inside, separating faster
    /// than the spring pushes), no force but the unclamped law's tangents
    /// (its stiffness no less than zero), which steer Newton into the
    /// contact it would enter.
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
        let k_t = spring_rate + dc * rate;
        if f <= 0.0 {
            // Separating faster than the damping lets the spring push: no
            // force (no adhesion), but the unclamped law's tangents, so
            // that Newton sees the contact it would enter (with none, a
            // contact bouncing off inside a step flipped between
            // thousands of newtons and nothing from one iterate to the
            // next; the tangent only steers Newton, the residual is exact).
            return (0.0, k_t.max(0.0), c);
        }
        (f, k_t, c)
    }

    /// The impact of a mass `mass` (kg) striking a rigid plane at `speed`
    /// (m/s, > 0) under this law alone: its coefficient of restitution
    /// (exit speed over `speed`) and the contact's duration (s), from the
    /// clamped law's equation of motion `m δ̈ = −F(δ, δ̇)` integrated by
    /// RK4 in 2 000 steps over three times the undamped depth's time
    /// `δ_max/speed` (and on until it leaves, its exit interpolated
    /// within the last step; verification case §7d's ODE). `None` for a
    /// non-positive or non-finite mass or speed, or a contact that does
    /// not end within twenty times that span. What a rope element's
    /// strike gives under the steel law (`CableContact::steel`):
    /// docs/verification.md, "Contact law".
    pub fn restitution(&self, mass: f64, speed: f64) -> Option<(f64, f64)> {
        if !(mass > 0.0 && speed > 0.0 && mass.is_finite() && speed.is_finite()) {
            return None;
        }
        let e = self.exponent;
        // The undamped law's deepest point: ½ m u² = K δ^(e+1)/(e+1).
        let deepest = ((e + 1.0) * mass * speed * speed / (2.0 * self.stiffness)).powf(1.0 / (e + 1.0));
        let dt = 3.0 * deepest / speed / 2000.0;
        let acceleration = |x: f64, v: f64| -self.force(x, v).0 / mass;
        let (mut x, mut v, mut t) = (0.0f64, speed, 0.0f64);
        for _ in 0..40_000 {
            let (x0, v0) = (x, v);
            let (k1x, k1v) = (v, acceleration(x, v));
            let (k2x, k2v) = (v + 0.5 * dt * k1v, acceleration(x + 0.5 * dt * k1x, v + 0.5 * dt * k1v));
            let (k3x, k3v) = (v + 0.5 * dt * k2v, acceleration(x + 0.5 * dt * k2x, v + 0.5 * dt * k2v));
            let (k4x, k4v) = (v + dt * k3v, acceleration(x + dt * k3x, v + dt * k3v));
            x += dt * (k1x + 2.0 * k2x + 2.0 * k3x + k4x) / 6.0;
            v += dt * (k1v + 2.0 * k2v + 2.0 * k3v + k4v) / 6.0;
            t += dt;
            if x <= 0.0 && v < 0.0 {
                // The exit within the step, linearly.
                let f = x0 / (x0 - x);
                return Some((-(v0 + f * (v - v0)) / speed, t - dt + f * dt));
            }
        }
        None
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
    /// Coulomb friction with a stick state (`None`: frictionless).
    pub friction: Option<CoulombFriction>,
    /// The obstacle's curved surface there (`None`: the plane).
    pub curve: Option<Curve>,
    /// The rope element's segment through the point, when the contact is
    /// of the element's capsule rather than of the sphere at the point
    /// (`None`: the sphere). See [`Span`].
    pub span: Option<Span>,
}

/// The segment of a rope element through a [`SphereContact`]'s point: from
/// `lo` to `hi` (m, `lo ≤ 0 ≤ hi`) along the link's unit `axis` (link
/// frame) from the point. Against a [`Curve`] the contact is then at the
/// segment's point nearest the ball's centre or the cylinder's axis,
/// found again at every evaluation, and its force acts there
/// ([`PointWrench::arm`]): an element sliding over a box's edge (a
/// cylinder of radius 0) is held where the edge is under it now, not at
/// the material point that was over the edge at the step's start, whose
/// plane (square to the element then) let the element turn about that
/// point into the edge within the step (docs/architecture.md, "Sharp
/// edges and thin bars"). Its tangents are exact where the element
/// crosses the axis square (a rope over an edge, a bar or a drum) or
/// against a point. Against a plane the point itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    /// The element's unit axis, link frame.
    pub axis: DVec3,
    /// Start of the segment from the point along `axis`, m (≤ 0).
    pub lo: f64,
    /// End of the segment from the point along `axis`, m (≥ 0).
    pub hi: f64,
}

/// The curved obstacle of a [`SphereContact`], frozen for the step: a
/// ball (no `axis`) or the round side of a cylinder (its unit `axis`) of
/// `radius` m, tangent to the contact's plane at its `point` at its
/// `time` (its centre, or a point of its axis, `radius` inside along the
/// normal), moving at `centre_velocity`. The depth is `r + R − ρ`, `ρ` the
/// sphere's centre's distance from the ball's centre or the cylinder's
/// axis, and the normal points from there to it: a point sliding along
/// the surface within the step stays on it. Against the plane frozen at
/// the step's start, a point sliding `s` along a drum of radius `R` was
/// pushed `s²/(2R)` off its surface by the step's end, its normal tilted
/// against the motion (docs/architecture.md, "Curved obstacles").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Curve {
    /// Radius of the ball or the cylinder, m (≥ 0; 0 for a box's edge, a
    /// line, or its corner, a point).
    pub radius: f64,
    /// The cylinder's unit axis, world (`None`: a ball).
    pub axis: Option<DVec3>,
    /// Velocity of the centre (of a point of the axis), world, m/s.
    pub centre_velocity: DVec3,
}

/// Where a point is against a [`SphereContact`]'s obstacle.
#[derive(Debug, Clone, Copy)]
struct Touch {
    /// Penetration, m (> 0 inside).
    depth: f64,
    /// Its rate, m/s (> 0 approaching).
    rate: f64,
    /// The obstacle's outward unit normal there.
    normal: DVec3,
    /// Distance from a [`Curve`]'s centre or axis, m (infinite for a
    /// plane).
    reach: f64,
    /// The directions along which the normal does not turn as the point
    /// moves (a cylinder's or an edge's axis; with a [`Span`] whose nearest
    /// point is inside the segment, the element's axis too): the
    /// curvature's tangent is `(I − Σ a aᵀ − n nᵀ)/reach`.
    flat: [Option<DVec3>; 2],
    /// From the contact's point to where the force acts (a [`Span`]'s
    /// nearest point), world, m.
    arm: DVec3,
}

/// How far (a fraction) a [`SphereContact`]'s normal force may grow in a
/// step beyond the one it ended the last step with
/// ([`CoulombFriction::normal_bound`]) and still raise the friction limit.
/// The bound keeps an impact's growing normal force out of the limit (a
/// rope landing on a slope slipped at a limit growing with the impact, and
/// Newton failed at any split); at exactly the last step's force it also
/// cut the friction of a rope sliding steadily round a drum, whose normal
/// forces grow along the wrap as the rope moves on: hauled at 0.1 m/s
/// over a 0.5 m drum (`capstan_friction.toml`) it slipped at a tension
/// ratio 1.1 % below Euler–Eytelwein at 1/60 s, 0.47 % at 1/180 s (first
/// order in the step), against −0.14 % with 25 % of room (10 %: −0.18 %;
/// unbounded: −0.12 %).
pub const BOUND_GROWTH: f64 = 0.25;

/// Coulomb friction of a [`SphereContact`] with a stick state (see the
/// module docs): a tangential spring `stiffness` and damper `damping`
/// from the sphere's contact point to `anchor`, capped at `coefficient`
/// times the normal force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoulombFriction {
    /// Coulomb coefficient `μ` (≥ 0).
    pub coefficient: f64,
    /// Stick stiffness `k_t`, N/m (> 0).
    pub stiffness: f64,
    /// Stick damping `c_t` on the slip rate, N·s/m (≥ 0).
    pub damping: f64,
    /// The friction target: a point of the obstacle's surface at the
    /// contact's `time`, moving with it, world, m.
    pub anchor: DVec3,
    /// The link's orientation (link frame to world) at the contact's
    /// `time`. The slip since then is that of the sphere's material at the
    /// contact point `−r n` from its centre, `Δp + Δθ × (−r n)` with `Δθ`
    /// the rotation vector of `R Rₜᵀ` (`R` the orientation now, `Rₜ` this
    /// one): exact for a turn about a fixed axis, so a ball that rolls,
    /// however far in a step, does not stretch the stick spring, and one
    /// that spins in place does.
    pub frame: DMat3,
    /// The link's angular velocity at the contact's `time`, world, rad/s:
    /// with the one now it tells how many whole turns the link made in the
    /// step, which its orientation alone cannot (a 16 mm rope rolling at
    /// 4.5 m/s turns 9 rad in a 1/60 s step).
    pub spin: DVec3,
    /// The normal force the friction limit may use, N (the contact's at
    /// the end of the previous step; 0 for a new contact): the limit is
    /// `μ min(F_n, (1 + BOUND_GROWTH) normal_bound)`. Bounded for the
    /// step, the limit does not grow with an impact's normal force inside
    /// it, whose coupling the slipping tangent cannot carry (see the
    /// module docs): a rope landing on a slope slipped at a limit growing
    /// with the impact and Newton failed at any split of the step. The
    /// room of [`BOUND_GROWTH`] lets it follow a normal force that grows
    /// steadily (a rope sliding round a drum).
    pub normal_bound: f64,
    /// Whether the friction acts at the sphere's contact point `−r n` from
    /// its centre (`true`, [`CoulombFriction::from_law`]'s choice: a ball
    /// rolls, its moment `(−r n) × F_t` turning it), or at the centre
    /// (`false`: what the coupling gives a rope element, which then does
    /// not roll; see docs/architecture.md "Contact").
    pub at_surface: bool,
}

impl CoulombFriction {
    /// Friction `coefficient` (≥ 0) on a contact with normal law `law`:
    /// the stick spring is the law's own stiffness at its damping depth,
    /// `e K d_max^(e−1)`, damped by its `C_max`, so the stick state is as
    /// stiff and as damped as the contact's resting normal direction.
    /// `anchor` (m, world): see [`CoulombFriction::anchor`]; `start`: the
    /// link point's state at the contact's time (its orientation and
    /// angular velocity are [`CoulombFriction::frame`] and
    /// [`CoulombFriction::spin`]); `normal_bound` N: see
    /// [`CoulombFriction::normal_bound`].
    pub fn from_law(coefficient: f64, law: &ImpactLaw, anchor: DVec3, start: &PointState, normal_bound: f64) -> Result<Self, ContactError> {
        if !(coefficient >= 0.0 && coefficient.is_finite()) {
            return Err(ContactError::OutOfRange { name: "friction coefficient", value: coefficient, range: ">= 0" });
        }
        let stiffness = law.exponent * law.stiffness * law.damping_depth.powf(law.exponent - 1.0);
        if normal_bound.is_nan() || normal_bound < 0.0 {
            return Err(ContactError::OutOfRange { name: "normal bound", value: normal_bound, range: ">= 0 N" });
        }
        Ok(CoulombFriction {
            coefficient,
            stiffness,
            damping: law.max_damping,
            anchor,
            frame: start.rotation,
            spin: start.angular_velocity,
            normal_bound,
            at_surface: true,
        })
    }
}

/// The tangential part of a contact at one state: the force, the
/// factor on the stick tangents (1 sticking, `μ F_n/|F_trial|` slipping),
/// the slip direction (zero sticking), the contact point's arm from the
/// link point, the stick spring's stretch `P (c − a)`, and the trial
/// force and the limit.
struct Tangential {
    force: DVec3,
    scale: f64,
    direction: DVec3,
    arm: DVec3,
    stretch: DVec3,
    /// The trial force and the limit, N.
    trial: DVec3,
    limit: f64,
}

/// The tangential part from the trial force `trial` (N, in the contact's
/// plane, normal `n`) and the friction limit `limit` (N, > 0): the trial
/// force while it sticks, `limit` along it while it slips; on the law's
/// own branch (`forced` `None`: it sticks while `|trial| ≤ limit`) or held
/// on `forced` (a Newton solve's frozen branch,
/// [`ForceElement::wrench_on`]): sticking, the trial force however large;
/// slipping, `limit` along the held direction (projected on the plane),
/// with no tangential stiffness.
fn saturate(trial: DVec3, n: DVec3, limit: f64, forced: Option<FrictionBranch>, arm: DVec3, stretch: DVec3) -> Tangential {
    let size = trial.length();
    match forced {
        Some(FrictionBranch::Stick) => Tangential { force: trial, scale: 1.0, direction: DVec3::ZERO, arm, stretch, trial, limit },
        None if size <= limit => Tangential { force: trial, scale: 1.0, direction: DVec3::ZERO, arm, stretch, trial, limit },
        None => {
            let direction = trial / size;
            Tangential { force: direction * limit, scale: limit / size, direction, arm, stretch, trial, limit }
        }
        Some(FrictionBranch::Slip(held)) => {
            let direction = (held - n * held.dot(n)).try_normalize().unwrap_or(held);
            Tangential { force: direction * limit, scale: 0.0, direction, arm, stretch, trial, limit }
        }
    }
}

/// The branch of a trial force `trial` (N) with the limit `limit` (N).
fn branch_of(trial: DVec3, limit: f64) -> FrictionBranch {
    let size = trial.length();
    if size <= limit {
        FrictionBranch::Stick
    } else {
        FrictionBranch::Slip(trial / size)
    }
}

/// How far a trial force `trial` (N) lies outside `branch` with the limit
/// `limit` (N), relative to the limit ([`ForceElement::branch_disagreement`]):
/// beyond the limit while held sticking; within it, or turned from the
/// held direction (the chord between the unit directions, about the
/// angle), while held slipping.
fn outside(trial: DVec3, limit: f64, branch: FrictionBranch) -> f64 {
    let size = trial.length();
    match branch {
        FrictionBranch::Stick => (size - limit).max(0.0) / limit,
        FrictionBranch::Slip(held) => (limit - size).max(0.0) / limit + (trial / size - held).length().min(2.0),
    }
}

impl SphereContact {
    /// A contact with a fixed plane through `point` (m) with unit outward
    /// `normal`, for a sphere of `radius` m, frictionless.
    pub fn fixed(point: DVec3, normal: DVec3, radius: f64, law: ImpactLaw) -> Self {
        SphereContact { point, normal, velocity: DVec3::ZERO, time: 0.0, radius, law, friction: None, curve: None, span: None }
    }

    /// The same contact against the curved surface `curve` (tangent to
    /// the contact's plane at its point).
    pub fn with_curve(mut self, curve: Curve) -> Self {
        self.curve = Some(curve);
        self
    }

    /// The same contact of the element's segment `span` ([`Span`]).
    pub fn with_span(mut self, span: Span) -> Self {
        self.span = Some(span);
        self
    }

    /// The same contact with Coulomb friction.
    pub fn with_friction(mut self, friction: CoulombFriction) -> Self {
        self.friction = Some(friction);
        self
    }

    /// The friction force at time `t` (s) and the point's state (N, in
    /// the plane, zero without friction or contact), and whether the
    /// contact sticks.
    pub fn friction_force(&self, t: f64, at: &PointState) -> (DVec3, bool) {
        let (touch, normal) = self.pressed(t, at);
        self.tangential(t, at, touch.normal, normal).map_or((DVec3::ZERO, false), |x| (x.force, x.direction == DVec3::ZERO))
    }

    /// Where the friction anchor goes for the next step, at time `t` (s),
    /// the end of this one, and the point's state then (world, m), for a
    /// contact made then at the sphere's lowest point `p − r n` (with the
    /// link's orientation then as its [`CoulombFriction::frame`]): the
    /// stick spring keeps its stretch while the contact sticks; once it
    /// slips, the spring is left at the stretch that alone gives the
    /// slipping force; without contact it is relaxed. `None` without
    /// friction.
    pub fn next_anchor(&self, t: f64, at: &PointState) -> Option<DVec3> {
        let friction = self.friction?;
        let (touch, normal) = self.pressed(t, at);
        let stretch = match self.tangential(t, at, touch.normal, normal) {
            None => DVec3::ZERO,
            Some(x) if x.direction == DVec3::ZERO => x.stretch,
            Some(x) => -x.force / friction.stiffness,
        };
        let arm = if friction.at_surface { touch.normal * self.radius } else { DVec3::ZERO };
        Some(at.point - arm - stretch)
    }

    /// The tangential part at normal force `normal` (N), the obstacle's
    /// normal there `n` ([`Touch::normal`]); `None` without friction or
    /// without contact.
    fn tangential(&self, t: f64, at: &PointState, n: DVec3, normal: f64) -> Option<Tangential> {
        self.tangential_on(t, at, n, normal, None)
    }

    /// [`SphereContact::tangential`] held on `forced` (the law's own
    /// branch for `None`).
    fn tangential_on(&self, t: f64, at: &PointState, n: DVec3, normal: f64, forced: Option<FrictionBranch>) -> Option<Tangential> {
        let friction = self.friction?;
        let limit = friction.coefficient * normal.min(friction.normal_bound * (1.0 + BOUND_GROWTH));
        if limit <= 0.0 {
            return None;
        }
        let (arm, turn) = if friction.at_surface {
            let estimate = (friction.spin + at.angular_velocity) * (0.5 * (t - self.time));
            (-n * self.radius, unwrap_turn(rotation_vector(&(at.rotation * friction.frame.transpose())), estimate))
        } else {
            (DVec3::ZERO, DVec3::ZERO)
        };
        let anchor = friction.anchor + self.velocity * (t - self.time);
        let slip = at.velocity + at.angular_velocity.cross(arm) - self.velocity;
        let project = |x: DVec3| x - n * x.dot(n);
        let stretch = project(at.point + arm + turn.cross(arm) - anchor);
        let trial = -(stretch * friction.stiffness + project(slip) * friction.damping);
        Some(saturate(trial, n, limit, forced, arm, stretch))
    }

    /// Penetration (m, > 0 inside) and its rate (m/s, > 0 approaching) at
    /// time `t` (s) and the point's state.
    pub fn depth(&self, t: f64, at: &PointState) -> (f64, f64) {
        let x = self.touch(t, at);
        (x.depth, x.rate)
    }

    /// The point's state `at` against the plane or the [`Curve`], at time
    /// `t` (s); with a [`Span`] on a curve, at the segment's point nearest
    /// the curve's centre or axis.
    fn touch(&self, t: f64, at: &PointState) -> Touch {
        let dt = t - self.time;
        let (x, v, arm, along) = self.foot(dt, at);
        let plane = || {
            let plane = self.point + self.velocity * dt;
            let n = self.normal;
            Touch { depth: self.radius - (x - plane).dot(n), rate: -(v - self.velocity).dot(n), normal: n, reach: f64::INFINITY, flat: [None; 2], arm }
        };
        let Some(curve) = self.curve else {
            return plane();
        };
        let centre = self.centre(&curve, dt);
        let mut d = x - centre;
        if let Some(axis) = curve.axis {
            d -= axis * d.dot(axis);
        }
        let reach = d.length();
        // (At the centre or on the axis the direction is lost: the plane.)
        if reach.is_nan() || reach <= 1e-9 * curve.radius.max(self.radius) {
            return plane();
        }
        let n = d / reach;
        Touch { depth: self.radius + curve.radius - reach, rate: -(v - curve.centre_velocity).dot(n), normal: n, reach, flat: [curve.axis, along], arm }
    }

    /// The centre of `curve` (a point of its axis), `radius` inside the
    /// contact's plane at its point, `dt` s after the contact's time,
    /// world, m.
    fn centre(&self, curve: &Curve, dt: f64) -> DVec3 {
        self.point - self.normal * curve.radius + curve.centre_velocity * dt
    }

    /// Where the contact acts, `dt` s after its time: the point itself
    /// (its position and velocity, world, no arm); with a [`Span`] on a
    /// [`Curve`], the segment's point nearest the
    /// curve's centre or axis (position, velocity, its arm from the point,
    /// all world) and, when that lies inside the segment, the element's
    /// world axis (along which it then slides).
    fn foot(&self, dt: f64, at: &PointState) -> (DVec3, DVec3, DVec3, Option<DVec3>) {
        let (Some(span), Some(curve)) = (self.span, self.curve) else {
            return (at.point, at.velocity, DVec3::ZERO, None);
        };
        let e = at.rotation * span.axis;
        let w = at.point - self.centre(&curve, dt);
        // The nearest point of the element's line to the axis (the common
        // perpendicular's foot) or to the centre; the distance is convex
        // along the line, so the segment's nearest point is it clamped.
        let u = match curve.axis {
            Some(a) => {
                let b = e.dot(a);
                let square = 1.0 - b * b;
                if square > 1e-12 {
                    (b * a.dot(w) - e.dot(w)) / square
                } else {
                    0.0
                }
            }
            None => -e.dot(w),
        };
        let u = if u.is_finite() { u.clamp(span.lo, span.hi) } else { 0.0 };
        let arm = e * u;
        (at.point + arm, at.velocity + at.angular_velocity.cross(arm), arm, (u > span.lo && u < span.hi).then_some(e))
    }

    /// The normal force the plane puts on the sphere at time `t` (s), N
    /// (≥ 0).
    pub fn normal_force(&self, t: f64, at: &PointState) -> f64 {
        self.pressed(t, at).1
    }

    /// [`SphereContact::touch`] and the normal force there, N.
    fn pressed(&self, t: f64, at: &PointState) -> (Touch, f64) {
        let touch = self.touch(t, at);
        (touch, self.law.force(touch.depth, touch.rate).0)
    }
}

/// The turn `rv` (a rotation vector, `|rv| ≤ π`) plus the whole turns
/// about its axis that bring it nearest to `estimate` (rad; the mean
/// angular velocity times the time since the start).
fn unwrap_turn(rv: DVec3, estimate: DVec3) -> DVec3 {
    let angle = rv.length();
    let axis = if angle > 1e-12 { rv / angle } else { estimate.normalize_or_zero() };
    let turns = ((estimate.dot(axis) - angle) / std::f64::consts::TAU).round();
    if turns == 0.0 {
        rv
    } else {
        axis * (angle + std::f64::consts::TAU * turns)
    }
}

/// The tangents of a force `F(c, ċ)` at `c = p + a + δθ × a` (the arm `a`
/// fixed in the world for the step) with `−∂F/∂c = m`, and its moment
/// `a × F` about the link point: blocks over (rotation, point) of
/// `−∂(a × F, F)/∂(δθ, δp)` (symmetric when `m` is).
fn at_arm(arm: DVec3, m: DMat3) -> M6 {
    let s = skew(arm);
    M6 { a: -(s * m * s), b: s * m, c: -(m * s), d: m }
}

/// A contact between two material points of one chain, or of two chains
/// stepped together (a rope touching itself, another rope, or a free
/// body): two spheres whose radii sum to `radius` pushed apart along
/// `normal` (from the second point to the first), frozen for the step as
/// a contact's plane is. Penetration `δ = radius − (p_a − p_b)·n`, its
/// rate `δ̇ = −(v_a − v_b)·n`, the force `F_n(δ, δ̇) n` of the
/// [`ImpactLaw`] on the first point and the opposite on the second, with
/// the tangents `∂F_n/∂δ n nᵀ` and `∂F_n/∂δ̇ n nᵀ`; with
/// [`PairFriction`], Coulomb friction with a stick state between the two
/// points (see there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairContact {
    /// Unit normal from the second point to the first, world.
    pub normal: DVec3,
    /// Sum of the two spheres' radii, m.
    pub radius: f64,
    /// The normal law.
    pub law: ImpactLaw,
    /// Coulomb friction with a stick state (`None`: frictionless).
    pub friction: Option<PairFriction>,
}

/// Coulomb friction of a [`PairContact`] with a stick state, acting at the
/// two points themselves (a rope's centreline: a rope element does not
/// roll, as with [`CoulombFriction::at_surface`] `false`; a free body's
/// point is on its surface, so the body's turn counts in the slip): a
/// tangential spring `stiffness` and damper `damping` on the points'
/// relative motion in the contact's plane, `F_t = −k_t P((p_a − p_b) −
/// offset) − c_t P(v_a − v_b)` on the first point (`P = I − n nᵀ`),
/// capped at `coefficient` times the normal force (limited by
/// `normal_bound`, as [`CoulombFriction::normal_bound`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairFriction {
    /// Coulomb coefficient `μ` (≥ 0).
    pub coefficient: f64,
    /// Stick stiffness `k_t`, N/m (> 0).
    pub stiffness: f64,
    /// Stick damping `c_t` on the slip rate, N·s/m (≥ 0).
    pub damping: f64,
    /// The relative position `p_a − p_b` (world, m) at which the stick
    /// spring is relaxed (only its part in the contact's plane counts).
    pub offset: DVec3,
    /// The normal force the friction limit may use, N (the contact's at
    /// the end of the previous step; 0 for a new contact): the limit is
    /// `μ min(F_n, normal_bound)`.
    pub normal_bound: f64,
}

impl PairFriction {
    /// Friction `coefficient` (≥ 0) on a pair contact with normal law
    /// `law`: the stick spring is the law's stiffness at its damping depth,
    /// `e K d_max^(e−1)`, damped by its `C_max` (as
    /// [`CoulombFriction::from_law`]). `offset` (m) and `normal_bound` (N):
    /// see [`PairFriction::offset`] and [`PairFriction::normal_bound`].
    pub fn from_law(coefficient: f64, law: &ImpactLaw, offset: DVec3, normal_bound: f64) -> Result<Self, ContactError> {
        if !(coefficient >= 0.0 && coefficient.is_finite()) {
            return Err(ContactError::OutOfRange { name: "friction coefficient", value: coefficient, range: ">= 0" });
        }
        if normal_bound.is_nan() || normal_bound < 0.0 {
            return Err(ContactError::OutOfRange { name: "normal bound", value: normal_bound, range: ">= 0 N" });
        }
        let stiffness = law.exponent * law.stiffness * law.damping_depth.powf(law.exponent - 1.0);
        Ok(PairFriction { coefficient, stiffness, damping: law.max_damping, offset, normal_bound })
    }
}

impl PairContact {
    /// A frictionless contact along unit `normal` (from the second point
    /// to the first) between spheres whose radii sum to `radius` (m).
    pub fn new(normal: DVec3, radius: f64, law: ImpactLaw) -> Self {
        PairContact { normal, radius, law, friction: None }
    }

    /// Penetration (m, > 0 when touching) and its rate (m/s).
    pub fn depth(&self, a: &PointState, b: &PointState) -> (f64, f64) {
        (self.radius - (a.point - b.point).dot(self.normal), -(a.velocity - b.velocity).dot(self.normal))
    }

    /// The friction force on the first point (N, in the contact's plane;
    /// zero without friction or contact) and whether it sticks.
    pub fn friction_force(&self, a: &PointState, b: &PointState) -> (DVec3, bool) {
        let (depth, rate) = self.depth(a, b);
        let normal = self.law.force(depth, rate).0;
        self.tangential(a, b, normal).map_or((DVec3::ZERO, false), |x| (x.force, x.direction == DVec3::ZERO))
    }

    /// The stick spring's stretch (m, world, in the contact's plane) to
    /// carry into the next step's contact at the same place, with the
    /// points at `a` and `b` at the end of this one: kept while the
    /// contact sticks; once it slips, the stretch that alone gives the
    /// slipping force; relaxed without a friction limit (a new contact, or
    /// none now); `None` without friction.
    pub fn next_stretch(&self, a: &PointState, b: &PointState) -> Option<DVec3> {
        let friction = self.friction?;
        let (depth, rate) = self.depth(a, b);
        Some(match self.tangential(a, b, self.law.force(depth, rate).0) {
            None => DVec3::ZERO,
            Some(x) if x.direction == DVec3::ZERO => x.stretch,
            Some(x) => -x.force / friction.stiffness,
        })
    }

    /// The tangential part at normal force `normal` (N); `None` without
    /// friction or without a limit.
    fn tangential(&self, a: &PointState, b: &PointState, normal: f64) -> Option<Tangential> {
        let friction = self.friction?;
        let limit = friction.coefficient * normal.min(friction.normal_bound);
        if limit <= 0.0 {
            return None;
        }
        let n = self.normal;
        let project = |x: DVec3| x - n * x.dot(n);
        let stretch = project(a.point - b.point - friction.offset);
        let trial = -(stretch * friction.stiffness + project(a.velocity - b.velocity) * friction.damping);
        Some(saturate(trial, n, limit, None, DVec3::ZERO, stretch))
    }
}

impl PairElement for PairContact {
    fn wrench(&self, _t: f64, a: &PointState, b: &PointState) -> PairWrench {
        let (depth, rate) = self.depth(a, b);
        let (f, k, c) = self.law.force(depth, rate);
        let n = self.normal;
        let nn = outer3(n, n);
        // (At zero force, inside and separating: the tangents alone, see
        // `ImpactLaw::force`.)
        let mut w = PairWrench { force: n * f, stiffness: nn * k, damping: nn * c, normal: Some(n) };
        if f > 0.0 {
            if let (Some(friction), Some(x)) = (self.friction, self.tangential(a, b, f)) {
                // As `SphereContact`'s (at the centreline): sticking
                // k_t P, slipping k_t (μ F_n/|F_trial|)(P − d̂ d̂ᵀ); the
                // slip force's coupling to the normal one left out.
                let d = x.direction;
                let tangent = DMat3::IDENTITY - nn - outer3(d, d);
                w.force += x.force;
                w.stiffness += tangent * (friction.stiffness * x.scale);
                w.damping += tangent * (friction.damping * x.scale);
                w.normal = None;
            }
        }
        w
    }

    fn energy(&self, _t: f64, a: &PointState, b: &PointState) -> f64 {
        let (depth, rate) = self.depth(a, b);
        let stick = match (self.friction, self.tangential(a, b, self.law.force(depth, rate).0)) {
            (Some(friction), Some(x)) if x.direction == DVec3::ZERO => 0.5 * friction.stiffness * x.stretch.length_squared(),
            _ => 0.0,
        };
        self.law.potential(depth) + stick
    }

    fn contact_force(&self, _t: f64, a: &PointState, b: &PointState) -> Option<f64> {
        let (depth, rate) = self.depth(a, b);
        Some(self.law.force(depth, rate).0)
    }

    /// A contact between two points of the chain: its normal law's
    /// potential, its damping and friction dissipate (within a step, with
    /// its normal and friction anchor frozen).
    fn is_passive(&self) -> bool {
        true
    }
}

impl SphereContact {
    /// [`ForceElement::wrench`], its friction held on `forced` (the law's
    /// own branch for `None`).
    fn wrench_held(&self, t: f64, at: &PointState, forced: Option<FrictionBranch>) -> PointWrench {
        let touch = self.touch(t, at);
        let (f, k, c) = self.law.force(touch.depth, touch.rate);
        let n = touch.normal;
        let nn = outer3(n, n);
        // The normal force acts where the contact is ([`Touch::arm`] from
        // the point: a span's nearest point), with its tangents there.
        let at_point = |m: DMat3| M6 { d: m, ..M6::default() };
        if f == 0.0 {
            // Outside, or inside and separating (the tangents alone, see
            // `ImpactLaw::force`); no friction without a normal force.
            return PointWrench { stiffness: at_point(nn * k), damping: at_point(nn * c), arm: touch.arm, ..Default::default() };
        }
        // f = F_n(δ, δ̇) n with δ = r − (p − p₀)·n, δ̇ = −v·n:
        // −∂f/∂p = ∂F_n/∂δ n nᵀ, −∂f/∂v = ∂F_n/∂δ̇ n nᵀ; on a curve, an
        // edge or a corner the normal turns with the point:
        // −(F_n/ρ)(Q − n nᵀ), Q the projection off the directions along
        // which it does not ([`Touch::flat`]).
        let mut m = nn * k;
        if touch.reach.is_finite() {
            let mut q = DMat3::IDENTITY;
            let mut kept: Option<DVec3> = None;
            for a in touch.flat.into_iter().flatten() {
                let a = kept.map_or(a, |b| (a - b * a.dot(b)).normalize_or_zero());
                q -= outer3(a, a);
                kept = Some(a);
            }
            m -= (q - nn) * (f / touch.reach);
        }
        let mut w = PointWrench { force: n * f, moment: DVec3::ZERO, stiffness: at_point(m), damping: at_point(nn * c), arm: touch.arm };
        if let Some(e) = touch.flat[1] {
            // A span's nearest point inside its segment: the distance is the
            // element's line's from the axis, whose normal turns with the
            // element, `δn = e (δθ·t)` with `t = n × e`, and which a turn
            // about the point across `t` shortens, `δρ = −ρ (δθ·t)²/2`.
            let t = n.cross(e);
            w.stiffness.a += outer3(t, t) * (f * touch.reach);
            w.stiffness.b -= outer3(t, e) * f;
            w.stiffness.c -= outer3(e, t) * f;
        }
        if let (Some(friction), Some(x)) = (self.friction, self.tangential_on(t, at, n, f, forced)) {
            // Sticking: −∂F_t/∂c = k_t P. Slipping, F_t = μ F_n d̂ with
            // d̂ the trial force's direction: k_t (μ F_n/|F_trial|)(P − d̂ d̂ᵀ),
            // symmetric; the term μ d̂ ∂F_n/∂c that couples the slip
            // force to the normal one is left out of the tangent (the
            // solve would only take its symmetric part, which is
            // indefinite), so Newton converges linearly while slipping.
            // The turn's tangent is taken at a small turn since the step's
            // start (the rotation vector's own derivative left out). It
            // acts at its own arm from the point, moved to where the
            // normal force acts.
            let d = x.direction;
            let tangent = DMat3::IDENTITY - nn - outer3(d, d);
            let arm = x.arm - touch.arm;
            w.force += x.force;
            w.moment += arm.cross(x.force);
            w.stiffness += at_arm(arm, tangent * (friction.stiffness * x.scale));
            w.damping += at_arm(arm, tangent * (friction.damping * x.scale));
        }
        w
    }
}

impl ForceElement for SphereContact {
    fn wrench(&self, t: f64, at: &PointState) -> PointWrench {
        self.wrench_held(t, at, None)
    }

    fn wrench_on(&self, t: f64, at: &PointState, branch: FrictionBranch) -> PointWrench {
        self.wrench_held(t, at, Some(branch))
    }

    /// Sticking, or slipping along the trial force, while the contact
    /// presses with friction.
    fn branch(&self, t: f64, at: &PointState) -> Option<FrictionBranch> {
        // (A frictionless contact has none: not worth finding its touch
        // at every evaluation.)
        self.friction?;
        let (touch, normal) = self.pressed(t, at);
        let x = self.tangential(t, at, touch.normal, normal)?;
        Some(branch_of(x.trial, x.limit))
    }

    fn branch_disagreement(&self, t: f64, at: &PointState, branch: FrictionBranch) -> f64 {
        let (touch, normal) = self.pressed(t, at);
        self.tangential(t, at, touch.normal, normal).map_or(0.0, |x| outside(x.trial, x.limit, branch))
    }

    fn energy(&self, t: f64, at: &PointState) -> f64 {
        let (touch, force) = self.pressed(t, at);
        let normal = self.law.potential(touch.depth);
        // The stick spring's energy while it sticks (a slipping contact
        // dissipates).
        let stick = match (self.friction, self.tangential(t, at, touch.normal, force)) {
            (Some(friction), Some(x)) if x.direction == DVec3::ZERO => 0.5 * friction.stiffness * x.stretch.length_squared(),
            _ => 0.0,
        };
        normal + stick
    }

    fn contact_force(&self, t: f64, at: &PointState) -> Option<f64> {
        Some(self.normal_force(t, at))
    }

    // Not yet counted passive (the default `false`), although against a
    // fixed obstacle it is: with it, the energy check refused sub-steps
    // of a rope landing on a 16° slope with friction (μ = 0.3) until it
    // slid 0.13 m where it sticks, a carried box on the ground crept
    // under a push below its friction, and a slack rope swinging onto
    // its posts' corners gained 1.6 J in a step (measured 2026-11-28;
    // its stick spring's energy is counted only while it sticks).
}
