//! Time integrators for second-order systems `M(q) q̈ = Q(t, q, q̇)`.
//!
//! Every scheme is written once against [`SecondOrderSystem`] and only calls
//! its residual and tangent solve, so the same code steps a 1-DOF oscillator,
//! a small [`DenseSystem`] or a rope with an O(n) solve.
//!
//! * [`Scheme`]: explicit (Euler, symplectic Euler, improved Euler, RK4) and
//!   implicit (linear acceleration, Newmark, Wilson-θ, HHT, generalized-α,
//!   the single linearly implicit step). Default: generalized-α, `ρ∞ = 0`.
//! * [`Integrator::step`] advances a [`State`] by a step `h`; implicit
//!   schemes run Newton on the new acceleration ([`NewtonSettings`]) and
//!   split a failing step into 2, 4, … 256 sub-steps (and keep the split
//!   for the next steps until they converge easily); explicit schemes choose
//!   sub-steps from [`SecondOrderSystem::max_frequency`] ([`Substeps`]).
//! * [`StepStats`] reports iterations, residuals, solves and sub-steps.
//! * Adaptive step size with local error control: [`DormandPrince`]
//!   (explicit 5(4), dense output) and [`TrBdf2`] (L-stable, for stiff
//!   systems, Newton on the stage accelerations); [`AdaptiveStats`] counts
//!   their work and rejected steps (tests in `tests/adaptive_integrators.rs`).
//!
//! Verified against the exact recurrences of `docs/verification-integrators.md`
//! (tests in `tests/integrators_sdof.rs`).

mod adaptive;
mod dense;
mod error;
mod explicit;
mod integrator;
mod newmark_family;
mod newton;
mod pendulum;
mod scheme;
mod state;
mod system;
mod wilson;

pub use self::adaptive::{AdaptiveError, AdaptiveSettings, AdaptiveStats, DormandPrince, TrBdf2};
pub(crate) use self::dense::gauss_solve;
pub use self::dense::{DenseSystem, DenseSystemError, ForceFn};
pub use self::error::IntegrateError;
pub use self::explicit::{substeps_needed, GROWTH, SAFETY};
pub use self::integrator::{Integrator, StepStats, Substeps, CALM_ITERATIONS, CALM_STEPS, ENERGY_ACTIVE, RESCUE_PIECES};
pub use self::newton::{NewtonSettings, CHORD_LIMIT, KINK_BAND, LAST_RESORT_BRANCH_UPDATES, MAX_BRANCH_UPDATES, PATIENT_BUDGET};
pub use self::pendulum::Pendulum;
pub use self::scheme::{stability_limit, AlphaParameters, Scheme, SchemeError, SchemeParams};
pub(crate) use self::state::all_finite;
pub use self::state::State;
pub use self::system::{EnergyBalance, LinearisationLimits, SecondOrderSystem, SystemError};
