//! Errors of the integrators. Every message names what failed and the
//! simulation time `t` (s) at the start of the failing step.

use thiserror::Error;

use super::scheme::SchemeError;
use super::system::SystemError;

/// Why a step (or the initial state) could not be computed. On any error
/// [`Integrator::step`](super::Integrator::step) leaves the state as it was.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum IntegrateError {
    /// Newton did not converge within its iteration limit even after the
    /// sub-step fallback.
    #[error(
        "Newton did not converge at t = {t} s (step h = {h} s split into {substeps} sub-steps, \
         {iterations} iterations in the last attempt)"
    )]
    NotConverged {
        /// Time at the start of the step, s.
        t: f64,
        /// Step size asked for, s.
        h: f64,
        /// Sub-steps of the last attempt.
        substeps: u32,
        /// Newton iterations of the failing sub-step in the last attempt.
        iterations: usize,
    },
    /// The system could not evaluate its residual or solve its tangent.
    #[error("system error at t = {t} s: {source}")]
    System {
        /// Time of the failing evaluation, s.
        t: f64,
        /// What the system reported.
        source: SystemError,
    },
    /// An explicit step with fixed sub-steps is beyond the scheme's stability
    /// (or, for explicit and improved Euler, growth) limit.
    #[error(
        "{scheme}: step too large at t = {t} s: sub-step h/n = {h:e} s / {substeps} exceeds the \
         limit {limit:e} s at omega_max = {omega_max:e} rad/s; use more sub-steps, Substeps::Auto, \
         Substeps::Unchecked or an implicit scheme"
    )]
    StepTooLarge {
        /// Time at the start of the step, s.
        t: f64,
        /// Step size asked for, s.
        h: f64,
        /// Fixed number of sub-steps.
        substeps: u32,
        /// Largest admissible sub-step, s.
        limit: f64,
        /// The system's highest frequency estimate, rad/s.
        omega_max: f64,
        /// Scheme name.
        scheme: &'static str,
    },
    /// Automatic sub-stepping would need more sub-steps than allowed.
    #[error(
        "{scheme}: at t = {t} s the step h = {h:e} s needs {needed} sub-steps at omega_max = \
         {omega_max:e} rad/s, more than the limit {max}; use an implicit scheme"
    )]
    TooManySubsteps {
        /// Time at the start of the step, s.
        t: f64,
        /// Step size asked for, s.
        h: f64,
        /// Sub-steps the stability/growth criterion asks for.
        needed: f64,
        /// The configured maximum.
        max: u64,
        /// The system's highest frequency estimate, rad/s.
        omega_max: f64,
        /// Scheme name.
        scheme: &'static str,
    },
    /// An explicit scheme must check its step but the system reports no
    /// highest frequency ([`SecondOrderSystem::max_frequency`](super::SecondOrderSystem::max_frequency)).
    #[error(
        "{scheme}: at t = {t} s the system reports no highest frequency, so the explicit \
         sub-steps cannot be chosen or checked; use Substeps::Unchecked(n) or an implicit scheme"
    )]
    UnknownFrequency {
        /// Time at the start of the step, s.
        t: f64,
        /// Scheme name.
        scheme: &'static str,
    },
    /// The state became NaN or infinite.
    #[error("non-finite state at t = {t} s")]
    NonFinite {
        /// Time of the step that produced it, s.
        t: f64,
    },
    /// The step size is not a positive finite number, or a sub-step count is 0.
    #[error("invalid step at t = {t} s: h = {h} s with {substeps} sub-steps")]
    InvalidStep {
        /// Time at the start of the step, s.
        t: f64,
        /// The rejected step, s.
        h: f64,
        /// The requested sub-steps.
        substeps: u32,
    },
    /// The state's vectors do not match the system's number of coordinates.
    #[error("at t = {t} s: {what} has length {got}, the system has {expected} coordinates")]
    DimensionMismatch {
        /// Time of the state, s.
        t: f64,
        /// Which vector (`q`, `v`, `a`, `a_hat`).
        what: &'static str,
        /// The system's `dof()`.
        expected: usize,
        /// The vector's length.
        got: usize,
    },
    /// An index into the state's coordinates past their end.
    #[error("at t = {t} s: {what} {index} is past the state's {len} coordinates")]
    IndexOutOfRange {
        /// Time of the state, s.
        t: f64,
        /// What the index is (an insertion point, a range end).
        what: &'static str,
        /// The index.
        index: usize,
        /// Number of coordinates.
        len: usize,
    },
    /// The scheme's parameters are out of range.
    #[error("invalid scheme at t = {t} s: {source}")]
    InvalidScheme {
        /// Time at the start of the step, s.
        t: f64,
        /// What is wrong with it.
        source: SchemeError,
    },
}
