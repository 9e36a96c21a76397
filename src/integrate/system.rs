//! The one trait every second-order system implements so that every
//! integrator can step it: a 1-DOF oscillator, a small dense model, or a rope
//! with thousands of elements (which implements the solve in O(n)).

use thiserror::Error;

/// Why a system could not evaluate its residual or solve its tangent.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum SystemError {
    /// The effective (tangent) matrix is singular or not positive at some pivot.
    #[error("singular effective matrix at coordinate {index} (pivot {pivot:e})")]
    Singular {
        /// Index of the coordinate (or sub-joint) where the pivot failed.
        index: usize,
        /// The offending pivot value.
        pivot: f64,
    },
    /// The state contains NaN or infinite values.
    #[error("non-finite state at coordinate {index}")]
    NonFinite {
        /// Index of the first non-finite coordinate.
        index: usize,
    },
    /// The system's description does not fit together (an index past its
    /// end); the message names what.
    #[error("invalid model: {0}")]
    Model(String),
}

/// A second-order system `M(q) q̈ = Q(t, q, q̇)` in residual form.
///
/// Coordinates `q` live in a plain vector space ℝⁿ (for a rope: relative
/// displacements in m and relative rotation angles in rad).
///
/// The residual is `r(t, q, v, a) = M(q) a − Q(t, q, v)`; it is zero at the
/// true acceleration. Implicit integrators drive it to zero with Newton's
/// method, solving with the scheme's effective matrix
/// `M + c_v·C_t + c_q·K_t`, where `C_t = ∂r/∂v` and `K_t = ∂r/∂q` (exact or
/// approximate tangents: Newton converges to the exact residual either way,
/// only the rate depends on the tangent).
pub trait SecondOrderSystem {
    /// Number of generalized coordinates `n`.
    fn dof(&self) -> usize;

    /// Writes `r = M(q) a − Q(t, q, v)` into `r` (length `n`).
    fn residual(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], r: &mut [f64]) -> Result<(), SystemError>;

    /// Solves `(M + c_v·C_t + c_q·K_t) x = b` with the tangents taken at
    /// `(t, q, v, a)`. Explicit schemes call it with `c_v = c_q = 0` (then it
    /// is the forward-dynamics solve `x = M⁻¹ b`).
    ///
    /// Integrators always call [`residual`](Self::residual) at the same
    /// `(t, q, v, a)` just before, so an implementation may reuse what the
    /// residual computed (kinematics, loads).
    #[allow(clippy::too_many_arguments)]
    fn solve_tangent(&mut self, t: f64, q: &[f64], v: &[f64], a: &[f64], c_v: f64, c_q: f64, b: &[f64], x: &mut [f64]) -> Result<(), SystemError>;

    /// One Newton iteration's work: writes the right-hand side `rhs = −r(t,
    /// q, v, a)` and the correction `x` solving
    /// `(M + c_v·C_t + c_q·K_t) x = rhs`. The default calls
    /// [`residual`](Self::residual) then [`solve_tangent`](Self::solve_tangent);
    /// a system may fuse the two (a chain does both in one tip-to-base
    /// sweep).
    #[allow(clippy::too_many_arguments)]
    fn residual_and_correction(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        c_v: f64,
        c_q: f64,
        rhs: &mut [f64],
        x: &mut [f64],
    ) -> Result<(), SystemError> {
        self.residual(t, q, v, a, rhs)?;
        for r in rhs.iter_mut() {
            *r = -*r;
        }
        self.solve_tangent(t, q, v, a, c_v, c_q, rhs, x)
    }

    /// An upper estimate of the highest natural angular frequency of the
    /// system at `q`, rad/s. Explicit schemes use it to choose their
    /// sub-steps; `None` means unknown (explicit schemes then refuse to pick
    /// sub-steps automatically).
    fn max_frequency(&self, _q: &[f64]) -> Option<f64> {
        None
    }

    /// Absolute tolerance on the Newton position correction, in the units of
    /// `q` (m or rad). Default `1e-10`.
    fn position_tolerance(&self) -> f64 {
        1e-10
    }

    /// Limits of the fast preset's step check ([`Scheme::LinearlyImplicit`]
    /// at its stiff form), in the units of `q`: a step whose single solve
    /// goes beyond them is taken again by the default scheme. `None` (the
    /// default, for coordinates without a known scale) keeps every step
    /// that crosses no kink.
    ///
    /// [`Scheme::LinearlyImplicit`]: super::Scheme::LinearlyImplicit
    fn linearisation_limits(&self) -> Option<LinearisationLimits> {
        None
    }

    /// Solves the tangent of the last [`solve_tangent`](Self::solve_tangent)
    /// (its elimination kept, the kinematics of the last residual) for
    /// another right-hand side `b` into `x`, if the system can do that
    /// cheaply; returns whether it did. The fast preset's step check uses
    /// it to estimate the next Newton correction. Default: `false`.
    fn resolve_last_tangent(&mut self, _b: &[f64], _x: &mut [f64]) -> bool {
        false
    }

    /// Whether [`resolve_last_tangent`](Self::resolve_last_tangent) solves
    /// with the whole tangent of the last solve (not an estimate without
    /// some of its terms), so that Newton may take a chord iteration with
    /// it. Default: `false`.
    fn resolves_exactly(&self) -> bool {
        false
    }

    /// Non-smooth laws (a slack rope's tension-only elements; contact
    /// next): freeze each law on a branch (taut or slack) chosen from the
    /// coordinates and velocities `(q, v)` at the start of the step,
    /// `start`, and the predicted ones, `predicted`, so that Newton solves
    /// a smooth system. Called by
    /// the implicit schemes at the start of each Newton solve. Default:
    /// nothing to freeze.
    fn freeze_branches(&mut self, _start: (&[f64], &[f64]), _predicted: (&[f64], &[f64])) {}

    /// After Newton converged on the frozen branches: moves every law whose
    /// branch disagrees with `(q, v)` to the other branch (a slack law that
    /// pulls by more than the position tolerance; a taut law that pushes
    /// by more than [`KINK_BAND`](crate::integrate::KINK_BAND), within
    /// which it is accepted taut) and returns how many moved (0: the converged point
    /// solves the exact, non-smooth equations). Default 0.
    fn update_branches(&mut self, _q: &[f64], _v: &[f64]) -> usize {
        0
    }

    /// The largest disagreement between a frozen branch and `(q, v)`, in
    /// the law's own measure (m or rad; 0 when every branch agrees).
    /// Default 0.
    fn branch_disagreement(&self, _q: &[f64], _v: &[f64]) -> f64 {
        0.0
    }

    /// Back to the exact laws (end of the Newton solve). Default: nothing.
    fn release_branches(&mut self) {}

    /// Applies a Newton correction `dq = scale·dx` of the coordinates at `q`
    /// in the system's own way and writes the new coordinates to `out`, or
    /// returns `false` (leaving `out` alone) to have the plain sum `q + dq`
    /// used (the default). Called
    /// right after [`residual_and_correction`](Self::residual_and_correction)
    /// at `q`. Any update that agrees with `q + dq` to first order keeps
    /// Newton's convergence rate; a chain in relative coordinates moves each
    /// link by its own linearised motion, so that the second-order error of
    /// a long lever stays local.
    fn nonlinear_update(&mut self, _q: &[f64], _dx: &[f64], _scale: f64, _out: &mut [f64]) -> bool {
        false
    }

    /// Whether a Newton solve may continue past
    /// [`NewtonSettings::max_iterations`](crate::integrate::NewtonSettings::max_iterations),
    /// up to [`PATIENT_BUDGET`](crate::integrate::PATIENT_BUDGET) times it,
    /// as long as each correction stays within twice the smallest one so
    /// far. A system
    /// whose tangent leaves out terms that can be large opts in: Newton on
    /// it then converges linearly, not quadratically, and a few more
    /// iterations solve the same equations where splitting the step would
    /// resolve dynamics the full step filters out. Default `false`.
    fn patient_newton(&self) -> bool {
        false
    }

    /// Whether a step from or to the state `(q, v)` is calm: no event
    /// inside it (a contact, a slip, a slack element snapping taut) that
    /// splitting the step would resolve in time. Only a calm step whose
    /// Newton solve failed is retried with the tangent's fallback
    /// ([`set_definite_tangent`](Self::set_definite_tangent)), and the retry
    /// is kept only if it also ends calm. Default: never (`false`).
    fn calm(&self, _q: &[f64], _v: &[f64]) -> bool {
        false
    }

    /// Switches the tangent's fallback for indefinite iterates on or off:
    /// on, a solve whose tangent turns out indefinite at the iterate is
    /// solved again with a positive definite part of it (a chain leaves out
    /// the geometric stiffness, see [`Chain::solve_into`](crate::cable::Chain::solve_into)).
    /// The integrator turns it on only to retry a calm step whose Newton
    /// solve failed, so steps that converge with the exact tangent are
    /// unchanged. Default: no fallback (nothing to switch).
    fn set_definite_tangent(&mut self, _on: bool) {}

    /// Whether the last correction
    /// ([`residual_and_correction`](Self::residual_and_correction)) was
    /// solved with the fallback of
    /// [`set_definite_tangent`](Self::set_definite_tangent) instead of the
    /// exact tangent. Such a correction is not a Newton step: where the
    /// exact tangent is nearly singular it is much smaller than the
    /// iterate's error, so Newton does not take it as a sign of
    /// convergence (it finishes with exact corrections). Default `false`.
    fn tangent_fell_back(&self) -> bool {
        false
    }

    /// The energy account of a system whose energy the integrator can
    /// check, at `(t, q, v, a)`: its mechanical energy in three parts
    /// `[kinetic, gravitational, elastic]` (J) and the power (W) that the
    /// prescribed motions of its supports deliver to it there (a moving
    /// base or anchor target; zero for a **passive** system, one whose
    /// supports are at rest: gravity and springs conservative, dampers
    /// dissipative, so its energy cannot grow). Over a sub-step of length
    /// `h` the energy may then grow by the supports' work, taken as
    /// `h (P₀ + P₁) / 2`, and by at most
    /// [`ENERGY_ACTIVE`](super::ENERGY_ACTIVE) more; past that the
    /// integrator refuses the sub-step and splits the step: on a whipping
    /// slack rope the discrete step can gain energy where the motion is
    /// not resolved. `a` is the true acceleration at the state (the
    /// supports' reactions need it). `None` (the default): loads or drives
    /// of unknown work, or not known; nothing is checked.
    fn energy_balance(&mut self, _t: f64, _q: &[f64], _v: &[f64], _a: &[f64]) -> Option<EnergyBalance> {
        None
    }

    /// Whether [`energy_balance`](Self::energy_balance) gives an account
    /// (without computing it). Default `false`.
    fn accounts_energy(&self) -> bool {
        false
    }
}

/// A system's energy and the power its moving supports deliver to it
/// ([`SecondOrderSystem::energy_balance`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyBalance {
    /// `[kinetic, gravitational, elastic]`, J.
    pub parts: [f64; 3],
    /// Power delivered by the prescribed motion of the supports (a moving
    /// base or anchor target), W; zero when they are at rest.
    pub power: f64,
}

impl EnergyBalance {
    /// The total `kinetic + gravitational + elastic`, J.
    pub fn total(&self) -> f64 {
        self.parts.iter().sum()
    }

    /// The energy gained from this account to `end`, `h` (s) later, beyond
    /// the supports' work over it (trapezoidal rule on their power), J.
    pub fn gain_to(&self, end: &EnergyBalance, h: f64) -> f64 {
        end.total() - self.total() - 0.5 * h * (self.power + end.power)
    }
}

/// How far the fast preset's single linearised solve may go before its
/// step is taken again by the default scheme
/// ([`SecondOrderSystem::linearisation_limits`]), in the units of the
/// coordinates (m or rad for a rope).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearisationLimits {
    /// Largest correction the solve may make to the predicted
    /// configuration, any coordinate.
    pub correction: f64,
    /// Largest next Newton correction, any coordinate: the residual at the
    /// step's end solved with the step's elimination
    /// ([`SecondOrderSystem::resolve_last_tangent`]), or, for a system that
    /// cannot re-solve, estimated as the solve's correction scaled by the
    /// ratio of the end residual to the linearised prediction's (max
    /// norms).
    pub next_correction: f64,
}

impl LinearisationLimits {
    /// A rope's (relative coordinates: m and rad).
    ///
    /// * `correction` 0.02: at most 8.5·10⁻³ on the hoist pendulum at
    ///   1/60 s (`tests/fast_preset.rs`, N = 10, 100, 1 000). Its first
    ///   0.5 s step from rest corrects by 1.1, and the default scheme could
    ///   not step on from the state that step left (released at 31° and
    ///   40°). On the slack V the kept steps that corrected by 0.014 to
    ///   0.057 each raised the kinetic energy from under 1 J to 8–135 J; at
    ///   0.02 the kicks were at most 8 J (3 J at 0.01), with the ratio
    ///   estimate of the next correction below.
    /// * `next_correction` 2·10⁻³ (the re-solved correction): at most
    ///   1.35·10⁻³ on the hoist pendulum (N = 1 000, in the release's axial
    ///   bounce; 9.7·10⁻⁴ at N = 100). On the slack V the steps kept at this
    ///   limit raise the kinetic energy by at most 0.12 J (3·10⁻³: 1.1 J;
    ///   the ratio estimate at 10⁻³ kept steps that raised it by up to
    ///   4.6 J, from a state the default scheme left nearly at rest).
    pub const ROPE: LinearisationLimits = LinearisationLimits { correction: 0.02, next_correction: 2e-3 };
}
