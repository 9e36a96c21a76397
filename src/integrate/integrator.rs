//! The [`Integrator`]: one scheme, its Newton and sub-step settings, and the
//! reusable work vectors.

use std::ops::AddAssign;

use super::error::IntegrateError;
use super::explicit;
use super::newmark_family::{step_alpha, step_linearly_implicit};
use super::newton::{Failure, NewtonSettings, LAST_RESORT_BRANCH_UPDATES, MAX_BRANCH_UPDATES};
use super::scheme::{stability_limit, Scheme};
use super::state::State;
use super::system::{EnergyBalance, SecondOrderSystem, SystemError};
use super::wilson::step_wilson;

/// How a step is split into sub-steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Substeps {
    /// Explicit schemes choose their sub-steps from the system's highest
    /// frequency ([`explicit::substeps_needed`](super::substeps_needed));
    /// implicit schemes take one step (splitting it only as the Newton
    /// fallback). The default.
    #[default]
    Auto,
    /// Exactly `n` equal sub-steps. For explicit schemes the sub-step is
    /// checked against the stability limit (symplectic Euler, RK4) or the
    /// 0.1 % growth bound (explicit and improved Euler) and the step fails
    /// with [`IntegrateError::StepTooLarge`] beyond it. Implicit schemes are
    /// not checked.
    Fixed(u32),
    /// Exactly `n` equal sub-steps and no check at all: the caller accepts
    /// growth or instability (needed to reproduce textbook recurrences of
    /// the explicit schemes at large steps).
    Unchecked(u32),
}

/// Work done by one call of [`Integrator::step`]. Counts include failed
/// attempts of the Newton fallback, so they measure cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepStats {
    /// Newton iterations (one residual and one tangent solve each, or a
    /// chord iteration's residual and re-solve), total.
    pub newton_iterations: usize,
    /// Of those, chord iterations: a residual solved with the last
    /// elimination ([`NewtonSettings::chord_limit`](super::NewtonSettings::chord_limit);
    /// counted in `residual_evals`, not in `solves`).
    pub chord_iterations: usize,
    /// Residual evaluations, total.
    pub residual_evals: usize,
    /// Tangent solves, total (including `c_v = c_q = 0` solves).
    pub solves: usize,
    /// Sub-steps of the accepted step (1 unless split).
    pub substeps_used: u64,
    /// Extra residual + solve passes of the Newton line search (included
    /// in `residual_evals` and `solves`, not in `newton_iterations`).
    pub line_search_evals: usize,
    /// Branch updates of non-smooth laws (a slack element going taut, or
    /// the reverse) inside Newton solves.
    pub branch_updates: usize,
    /// Steps retried with the tangent's fallback for indefinite iterates
    /// after their Newton solve failed
    /// ([`SecondOrderSystem::set_definite_tangent`]).
    pub definite_retries: usize,
    /// Steps of the fast preset ([`Scheme::LinearlyImplicit`]) whose single
    /// linearised solve did not hold and were taken again by the default
    /// scheme (generalized-α with Newton): it crossed a kink of a
    /// non-smooth law (a slack rope element pulled taut), or it moved
    /// beyond the system's [`LinearisationLimits`] (a rope's: 0.02 m or rad
    /// from the prediction, or a next Newton correction of more than 2 mm
    /// or 2 mrad; a step too nonlinear for one solve).
    ///
    /// [`LinearisationLimits`]: super::LinearisationLimits
    pub newton_fallbacks: usize,
    /// Sub-steps refused because a system's energy grew over its step,
    /// beyond its supports' work, by more than [`ENERGY_ACTIVE`] allows
    /// ([`SecondOrderSystem::energy_balance`]); each refusal splits the
    /// step further.
    pub energy_refusals: usize,
    /// Sub-steps at the finest split whose Newton solve failed and that
    /// were taken in pieces instead
    /// ([`NewtonSettings::rescue_pieces`]).
    pub rescued_substeps: usize,
}

impl AddAssign for StepStats {
    fn add_assign(&mut self, o: Self) {
        self.newton_iterations += o.newton_iterations;
        self.chord_iterations += o.chord_iterations;
        self.residual_evals += o.residual_evals;
        self.solves += o.solves;
        self.substeps_used += o.substeps_used;
        self.line_search_evals += o.line_search_evals;
        self.branch_updates += o.branch_updates;
        self.definite_retries += o.definite_retries;
        self.newton_fallbacks += o.newton_fallbacks;
        self.rescued_substeps += o.rescued_substeps;
        self.energy_refusals += o.energy_refusals;
    }
}

/// Reusable vectors, sized on the first step (no allocation afterwards
/// unless the number of coordinates changes).
#[derive(Debug, Default)]
pub(crate) struct Workspace {
    pub qb: Vec<f64>,
    pub vb: Vec<f64>,
    pub q: Vec<f64>,
    pub v: Vec<f64>,
    pub x: Vec<f64>,
    pub r: Vec<f64>,
    pub dx: Vec<f64>,
    /// The previous Newton correction (line search).
    pub dx_prev: Vec<f64>,
    /// The coordinates after a system's own (nonlinear) update.
    pub q_new: Vec<f64>,
    pub zeros: Vec<f64>,
    pub sq: Vec<f64>,
    pub sv: Vec<f64>,
    pub sa: Vec<f64>,
    pub dq_sum: Vec<f64>,
    pub dv_sum: Vec<f64>,
    /// Acceleration at the start of the previous generalized-α step, that
    /// step's size and end time (for the extrapolating predictor).
    pub a_prev: Vec<f64>,
    pub a_prev_h: f64,
    pub a_prev_next_t: f64,
    /// Branch updates a Newton solve may make (`MAX_BRANCH_UPDATES`, or
    /// more in the last-resort pass).
    pub branch_budget: usize,
    backup: [Vec<f64>; 4],
    backup_t: f64,
}

impl Workspace {
    fn ensure(&mut self, n: usize) {
        if self.zeros.len() == n {
            return;
        }
        let vectors = [
            &mut self.qb,
            &mut self.vb,
            &mut self.q,
            &mut self.v,
            &mut self.x,
            &mut self.r,
            &mut self.dx,
            &mut self.dx_prev,
            &mut self.q_new,
            &mut self.sq,
            &mut self.sv,
            &mut self.sa,
            &mut self.dq_sum,
            &mut self.dv_sum,
            &mut self.a_prev,
        ];
        for x in vectors.into_iter().chain(self.backup.iter_mut()) {
            x.resize(n, 0.0);
        }
        self.zeros.clear();
        self.zeros.resize(n, 0.0);
    }

    fn save(&mut self, s: &State) {
        self.backup_t = s.t;
        for (b, x) in self.backup.iter_mut().zip([&s.q, &s.v, &s.a, &s.a_hat]) {
            b.copy_from_slice(x);
        }
    }

    fn restore(&self, s: &mut State) {
        s.t = self.backup_t;
        for (b, x) in self.backup.iter().zip([&mut s.q, &mut s.v, &mut s.a, &mut s.a_hat]) {
            x.copy_from_slice(b);
        }
    }
}

/// Advances a [`State`] of any [`SecondOrderSystem`] with one [`Scheme`].
///
/// ```
/// use bevy_rapier_cable::integrate::{DenseSystem, Integrator, State};
/// // ẍ + (2π)² x = 0, x(0) = 1: one period with the default generalized-α.
/// let mut sys = DenseSystem::oscillator(1.0, 0.0, 4.0 * std::f64::consts::PI.powi(2)).unwrap();
/// let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).unwrap();
/// let mut integrator = Integrator::default();
/// for _ in 0..1000 {
///     integrator.step(&mut sys, &mut state, 1e-3).unwrap();
/// }
/// assert!((state.q[0] - 1.0).abs() < 1e-4);
/// ```
#[derive(Debug)]
pub struct Integrator {
    /// The scheme.
    pub scheme: Scheme,
    /// Newton control and fallback (implicit schemes).
    pub newton: NewtonSettings,
    /// Sub-step policy.
    pub substeps: Substeps,
    /// Largest number of sub-steps [`Substeps::Auto`] may choose for an
    /// explicit scheme before failing with
    /// [`IntegrateError::TooManySubsteps`]. Default 1 000 000 (explicit Euler
    /// needs 1.4·10⁷ sub-steps per 1/60 s step at ω = 10⁴ rad/s).
    pub max_explicit_substeps: u64,
    /// Adaptive split of the implicit schemes under [`Substeps::Auto`]: the
    /// sub-steps the last step needed (1 until a step fails), and how many
    /// steps in a row converged easily at it (after [`CALM_STEPS`] the split
    /// is halved).
    split: u32,
    calm: u32,
    /// The fast preset's current step is taken by the default scheme (its
    /// linearised solve did not hold).
    as_default: bool,
    /// The last step's last residual evaluation was at its end state (a
    /// converged Newton iterate, or the fast preset's acceptance test), so
    /// the system's kinematics and readouts are current.
    end_evaluated: bool,
    ws: Workspace,
}

/// The energy check of a step of a system with an energy account
/// ([`SecondOrderSystem::energy_balance`]: a passive system, or one whose
/// only outside work is its supports' prescribed motion,
/// [`NewtonSettings::energy_check`](super::NewtonSettings::energy_check)):
/// the step's energy may grow, over its checked sub-steps together, by the
/// supports' work (trapezoidal rule on their power per sub-step) and at
/// most this fraction more of the kinetic + elastic energy at the first of
/// them, or of the gravitational energy the first of them exchanged if
/// that is more (a step from rest, whose kinetic + elastic energy is
/// nearly zero), plus 1e-9 of the energy's size (round-off and the Newton
/// tolerance). A sub-step past that is refused and the step split further,
/// up to [`NewtonSettings::max_substeps`](super::NewtonSettings::max_substeps);
/// at the finest split the sub-step is taken as solved (one whose Newton
/// solve fails there is cut further,
/// [`NewtonSettings::rescue_pieces`](super::NewtonSettings::rescue_pieces),
/// and that cut checked on its own). Checked: every
/// sub-step of a split step, and a whole step from a state that is not calm
/// ([`SecondOrderSystem::calm`]: a slack element); a step taken whole from
/// a calm state is not (the check costs a kinematics pass, about half a
/// Newton iteration, or a residual pass when the supports move). Not for
/// conditionally stable schemes (they keep
/// their textbook behaviour). Measured (docs/architecture.md,
/// "Energy-checked sub-steps"): a V of steel rope let go between two pins
/// gains at most 0.33 J in a frame (175 J unchecked), and a 1 t block's
/// fall beside its slack rope takes 2.7 sub-steps per frame step (1.8
/// unchecked).
pub const ENERGY_ACTIVE: f64 = 1e-2;

/// Steps in a row that must converge in at most [`CALM_ITERATIONS`] Newton
/// iterations per sub-step before the adaptive split is halved.
pub const CALM_STEPS: u32 = 2;
/// See [`CALM_STEPS`].
pub const CALM_ITERATIONS: usize = 6;

impl Integrator {
    /// An integrator for `scheme` with default settings.
    pub fn new(scheme: Scheme) -> Self {
        Integrator {
            scheme,
            newton: NewtonSettings::default(),
            substeps: Substeps::Auto,
            max_explicit_substeps: 1_000_000,
            split: 1,
            calm: 0,
            as_default: false,
            end_evaluated: false,
            ws: Workspace::default(),
        }
    }

    /// Sets the sub-step policy.
    pub fn with_substeps(mut self, substeps: Substeps) -> Self {
        self.substeps = substeps;
        self
    }

    /// Sets the Newton settings.
    pub fn with_newton(mut self, newton: NewtonSettings) -> Self {
        self.newton = newton;
        self
    }

    /// Advances `state` by `h` (s). On error the state is left as it was.
    pub fn step<S: SecondOrderSystem + ?Sized>(&mut self, sys: &mut S, state: &mut State, h: f64) -> Result<StepStats, IntegrateError> {
        let t = state.t;
        let fixed = match self.substeps {
            Substeps::Auto => None,
            Substeps::Fixed(n) | Substeps::Unchecked(n) => Some(n),
        };
        if !(h.is_finite() && h > 0.0) || fixed == Some(0) {
            return Err(IntegrateError::InvalidStep { t, h, substeps: fixed.unwrap_or(1) });
        }
        self.scheme.validate().map_err(|source| IntegrateError::InvalidScheme { t, source })?;
        state.check_dimensions(sys.dof())?;
        self.ws.ensure(state.dof());
        self.ws.save(state);
        self.end_evaluated = false;
        let mut stats = StepStats::default();
        let result = if self.scheme.is_explicit() {
            self.step_explicit(sys, state, h, &mut stats)
        } else {
            self.step_implicit(sys, state, h, fixed.unwrap_or(1), &mut stats)
        };
        match result {
            Ok(()) if state.is_finite() => {
                state.t = t + h;
                Ok(stats)
            }
            Ok(()) => {
                self.ws.restore(state);
                Err(IntegrateError::NonFinite { t })
            }
            Err(e) => {
                self.ws.restore(state);
                Err(e)
            }
        }
    }

    /// A new integrator with the settings of `like` (scheme, Newton,
    /// sub-steps) and the adaptive split of the most split of `all` (with
    /// the fewest calm steps of them): for a step of several systems taken
    /// as one.
    pub(crate) fn joint<'a>(like: &Integrator, all: impl Iterator<Item = &'a Integrator>) -> Integrator {
        let (split, calm) = all.fold((1, u32::MAX), |(s, c), i| (s.max(i.split), c.min(i.calm)));
        Integrator {
            scheme: like.scheme.clone(),
            newton: like.newton.clone(),
            substeps: like.substeps,
            max_explicit_substeps: like.max_explicit_substeps,
            split,
            calm: if calm == u32::MAX { 0 } else { calm },
            as_default: false,
            end_evaluated: false,
            ws: Workspace::default(),
        }
    }

    /// Takes the adaptive split of a joint step ([`Integrator::joint`]).
    pub(crate) fn take_split(&mut self, joint: &Integrator) {
        self.split = joint.split;
        self.calm = joint.calm;
    }

    /// Forgets what the integrator kept from earlier steps (the predictor's
    /// previous acceleration, the sub-step split, the last step's backup).
    /// Call it after the system's coordinates changed in number or meaning
    /// ([`State::insert`], [`State::remove`]).
    pub fn reset_history(&mut self) {
        self.ws = Workspace::default();
        self.split = 1;
        self.calm = 0;
    }

    /// Forgets the predictor's previous acceleration: the next step's
    /// Newton starts from the state's acceleration, not from its linear
    /// extrapolation (after a jump in the rates,
    /// [`Cable::apply_impulse`](crate::cable::Cable::apply_impulse)).
    pub(crate) fn forget_predictor(&mut self) {
        self.ws.a_prev_next_t = f64::NAN;
    }

    /// Puts `state` back where it was at the start of the last
    /// [`step`](Self::step) call (time included): for a caller that rejects
    /// a step the integrator accepted (a cable whose element stretched past
    /// its length).
    pub fn undo_step(&self, state: &mut State) {
        self.ws.restore(state);
    }

    /// Whether the last successful [`step`](Self::step)'s last residual
    /// evaluation was at the state it ended on (an implicit scheme whose
    /// Newton solve converged, or the fast preset's acceptance test), so a
    /// system's kinematics need no refresh there. False after an explicit
    /// or Wilson-θ step, after the fast preset's non-stiff form, and after
    /// its stiff form on a system without
    /// [`linearisation_limits`](SecondOrderSystem::linearisation_limits).
    pub fn evaluated_at_end(&self) -> bool {
        self.end_evaluated
    }

    /// Whether steps are energy-checked: the setting, and not for
    /// conditionally stable schemes (they keep their textbook behaviour,
    /// divergence included).
    fn checks_energy(&self) -> bool {
        self.newton.energy_check && stability_limit(&self.scheme).is_none()
    }

    fn step_explicit<S: SecondOrderSystem + ?Sized>(&mut self, sys: &mut S, state: &mut State, h: f64, stats: &mut StepStats) -> Result<(), IntegrateError> {
        let (t, scheme) = (state.t, self.scheme.name());
        let n = match self.substeps {
            Substeps::Unchecked(n) => u64::from(n),
            policy => {
                let omega = sys.max_frequency(&state.q).filter(|w| !w.is_nan()).ok_or(IntegrateError::UnknownFrequency { t, scheme })?;
                let needed = explicit::substeps_needed(&self.scheme, h, omega).unwrap_or(1.0);
                match policy {
                    Substeps::Fixed(n) => {
                        let limit = explicit::admissible_substep(&self.scheme, h, omega);
                        if h / f64::from(n) > limit {
                            return Err(IntegrateError::StepTooLarge { t, h, substeps: n, limit, omega_max: omega, scheme });
                        }
                        u64::from(n)
                    }
                    _ if needed.ceil() > self.max_explicit_substeps as f64 => {
                        return Err(IntegrateError::TooManySubsteps { t, h, needed: needed.ceil(), max: self.max_explicit_substeps, omega_max: omega, scheme });
                    }
                    _ => needed.ceil() as u64,
                }
            }
        };
        for k in 0..n {
            let hs = h / n as f64;
            state.t = t + h * (k as f64) / (n as f64);
            explicit::step(sys, state, &mut self.ws, &self.scheme, hs, stats)?;
        }
        stats.substeps_used += n;
        Ok(())
    }

    fn step_implicit<S: SecondOrderSystem + ?Sized>(
        &mut self,
        sys: &mut S,
        state: &mut State,
        h: f64,
        n0: u32,
        stats: &mut StepStats,
    ) -> Result<(), IntegrateError> {
        self.ws.branch_budget = MAX_BRANCH_UPDATES;
        self.as_default = false;
        let result = self.step_implicit_splits(sys, state, h, n0, stats);
        self.as_default = false;
        result
    }

    /// The body of [`step_implicit`](Self::step_implicit): the step, split
    /// further while it fails.
    fn step_implicit_splits<S: SecondOrderSystem + ?Sized>(
        &mut self,
        sys: &mut S,
        state: &mut State,
        h: f64,
        n0: u32,
        stats: &mut StepStats,
    ) -> Result<(), IntegrateError> {
        let t = state.t;
        let auto = matches!(self.substeps, Substeps::Auto);
        let max_n = n0.saturating_mul(self.newton.max_substeps.max(1));
        // Under `Auto` a step starts at the split the last one needed (a
        // slack rope's first whip needs fine steps for a while; retrying the
        // full step every frame would cost a failed solve each time).
        let mut n = if auto { self.split.clamp(n0, max_n) } else { n0 };
        let start_n = n;
        let checking = self.checks_energy();
        loop {
            let before = stats.newton_iterations;
            // At the finest split a sub-step is taken as solved (not
            // energy-checked), and for a system with an energy account one
            // whose Newton solve fails there is cut further, each cut
            // energy-checked ([`rescue_substep`]). Not for others (a rope
            // touching colliders): the coupling's retry of a failed step
            // with more contact passes is cheaper there (measured: the
            // 1 000-element landing took 21 499 instead of 13 238 Newton
            // iterations per frame step over its first three frames with
            // the cut in its last-resort pass).
            let finest = n.saturating_mul(2) > max_n;
            let rescue = finest && checking && sys.accounts_energy();
            let check = checking && !finest;
            match self.try_substeps(sys, state, h, n, check, rescue, stats) {
                Ok(()) => {
                    stats.substeps_used += u64::from(n);
                    if auto {
                        let easy = stats.newton_iterations - before <= CALM_ITERATIONS * n as usize;
                        self.calm = if easy { self.calm + 1 } else { 0 };
                        self.split = n;
                        if self.calm >= CALM_STEPS && n > n0 {
                            self.split = n / 2;
                            self.calm = 0;
                        }
                    }
                    return Ok(());
                }
                Err(failure) => {
                    self.ws.restore(state);
                    if matches!(failure, Failure::Linearisation) {
                        // The fast preset: the whole step again with the
                        // default scheme, from its acceleration.
                        stats.newton_fallbacks += 1;
                        self.as_default = true;
                        state.a_hat.copy_from_slice(&state.a);
                        self.ws.a_prev_next_t = f64::NAN;
                        continue;
                    }
                    // A calm step whose first solve failed is tried again at
                    // the same split with the tangent's fallback for
                    // indefinite iterates (a stiff end spring whose target
                    // jumped), before splitting; kept only if it ends calm.
                    // So is a step of a system with an energy account
                    // (passive, or its supports' work counted) at every
                    // split, its energy checked as any other attempt's: the fallback's
                    // corrections are not Newton steps, and where the exact
                    // tangent is indefinite (a whipping slack rope) they
                    // can lead to a solution that gains energy.
                    let not_converged = matches!(failure, Failure::NotConverged { .. });
                    let calm_retry = not_converged && n == start_n && stats.definite_retries == 0 && sys.calm(&state.q, &state.v);
                    let accounted = not_converged && !calm_retry && checking && sys.accounts_energy();
                    if calm_retry || accounted {
                        stats.definite_retries += 1;
                        sys.set_definite_tangent(true);
                        // An accounted system's fallback is checked at the
                        // finest split too: only a solution whose energy the
                        // check accepts replaces the exact Newton's failure.
                        let retried = self.try_substeps(sys, state, h, n, check || accounted, false, stats);
                        sys.set_definite_tangent(false);
                        if retried.is_ok() && (accounted || sys.calm(&state.q, &state.v)) {
                            stats.substeps_used += u64::from(n);
                            if auto {
                                self.calm = 0;
                                self.split = n;
                            }
                            return Ok(());
                        }
                        self.ws.restore(state);
                    }
                    let next = n.saturating_mul(2);
                    let exhausted = next > max_n || next == n;
                    // Every split failed to converge: the last-resort pass,
                    // once, from the first split with a larger
                    // branch-update budget.
                    if exhausted && not_converged && self.ws.branch_budget == MAX_BRANCH_UPDATES {
                        self.ws.branch_budget = LAST_RESORT_BRANCH_UPDATES;
                        n = start_n;
                        continue;
                    }
                    if exhausted {
                        return Err(match failure {
                            Failure::NotConverged { iterations } => IntegrateError::NotConverged { t, h, substeps: n, iterations },
                            Failure::Error(e) => e,
                            Failure::Linearisation | Failure::EnergyGain => IntegrateError::NotConverged { t, h, substeps: n, iterations: 1 },
                        });
                    }
                    n = next;
                }
            }
        }
    }

    /// The `n` sub-steps of one attempt. With `check_energy`, a sub-step
    /// of a passive system, of a split step or from a state that is not
    /// calm, after which the attempt's energy has grown by more than
    /// [`ENERGY_ACTIVE`] allows fails the attempt ([`Failure::EnergyGain`]).
    /// With `rescue` (the finest split), a generalized-α sub-step whose
    /// Newton solve fails is cut further ([`rescue_substep`]).
    #[allow(clippy::too_many_arguments)]
    fn try_substeps<S: SecondOrderSystem + ?Sized>(
        &mut self,
        sys: &mut S,
        state: &mut State,
        h: f64,
        n: u32,
        check_energy: bool,
        rescue: bool,
        stats: &mut StepStats,
    ) -> Result<(), Failure> {
        let (t, hs) = (state.t, h / f64::from(n));
        let ws = &mut self.ws;
        let newton = &self.newton;
        // The energy at the start of the next sub-step, when known.
        let mut known: Option<EnergyBalance> = None;
        // The attempt's net gain so far over its checked sub-steps, and its
        // budget (ENERGY_ACTIVE of the first checked sub-step's kinetic +
        // elastic energy, or of the gravitational energy that sub-step
        // exchanged if more), J: a share of the energy in motion, in the
        // springs or changing form, not of the total (whose gravitational
        // part depends on the origin). From rest the first share is nearly
        // zero: the hoist swing's release was refused three times and
        // split into 8 sub-steps for any gain at all.
        let (mut net, mut budget) = (0.0, None::<f64>);
        for k in 0..n {
            state.t = t + h * f64::from(k) / f64::from(n);
            let before = if check_energy && (n > 1 || !sys.calm(&state.q, &state.v)) {
                known.take().or_else(|| sys.energy_balance(state.t, &state.q, &state.v, &state.a))
            } else {
                None
            };
            known = None;
            self.end_evaluated = match self.scheme {
                Scheme::WilsonTheta { theta } => {
                    step_wilson(sys, state, ws, theta, hs, newton, stats)?;
                    false
                }
                Scheme::LinearlyImplicit { w } if !self.as_default => step_linearly_implicit(sys, state, ws, w, hs, newton, stats)?,
                ref s => {
                    let p = if self.as_default { Scheme::default().alpha_parameters() } else { s.alpha_parameters() };
                    let p = p.expect("every other implicit scheme is generalized-α");
                    match step_alpha(sys, state, ws, p, hs, newton, stats) {
                        // At the finest split, a sub-step whose solve did not
                        // converge or met a singular effective matrix (an
                        // iterate that left the tangent singular) is cut
                        // further; a failed solve leaves the state as it was.
                        Err(failed @ (Failure::NotConverged { .. } | Failure::Error(IntegrateError::System { source: SystemError::Singular { .. }, .. })))
                            if rescue =>
                        {
                            rescue_substep(sys, state, ws, p, hs, newton, stats).map_err(|_| failed)?;
                            // (Its energy check's pass may have overwritten
                            // the last residual's.)
                            false
                        }
                        other => {
                            other?;
                            true
                        }
                    }
                }
            };
            if !state.is_finite() {
                return Err(Failure::Error(IntegrateError::NonFinite { t: state.t }));
            }
            if let Some(e0) = before {
                // The energy's pass overwrote the last residual's.
                self.end_evaluated = false;
                if let Some(e1) = sys.energy_balance(state.t, &state.q, &state.v, &state.a) {
                    net += e0.gain_to(&e1, hs);
                    let budget = *budget.get_or_insert_with(|| active_share(&e0).max(ENERGY_ACTIVE * (e1.parts[1] - e0.parts[1]).abs()));
                    if net > budget + round_off(&e0) {
                        stats.energy_refusals += 1;
                        return Err(Failure::EnergyGain);
                    }
                    known = Some(e1);
                }
            }
        }
        Ok(())
    }
}

/// [`ENERGY_ACTIVE`] of an account's kinetic + elastic energy, J: the
/// check's budget (a share of the energy in motion and in the springs, not
/// of the total, whose gravitational part depends on the origin).
fn active_share(e: &EnergyBalance) -> f64 {
    ENERGY_ACTIVE * (e.parts[0] + e.parts[2])
}

/// 1e-9 of an account's size (the sum of its parts' magnitudes), J: the
/// round-off and Newton tolerance the check lets pass.
fn round_off(e: &EnergyBalance) -> f64 {
    1e-9 * e.parts.iter().map(|p| p.abs()).sum::<f64>()
}

/// Default [`NewtonSettings::rescue_pieces`]: the most pieces a sub-step
/// of the finest split whose Newton solve fails is cut into (with the
/// default 256 sub-steps, a 1/60 s step is then resolved down to 1 µs where
/// it needs it).
pub const RESCUE_PIECES: u32 = 64;

/// A sub-step of `hs` (s) at the finest split whose generalized-α Newton
/// solve did not converge or met a singular effective matrix, taken again
/// from `state` (the sub-step's start, which the failed solve left as it
/// was) in 2, 4, … [`NewtonSettings::rescue_pieces`] pieces with exact
/// Newton solves. A local refinement of the finest split: only the
/// sub-step that needs it is cut. Called only for a system with an energy
/// account ([`SecondOrderSystem::energy_balance`]): the first cut whose
/// pieces all converge is kept if the sub-step's energy grew beyond its
/// supports' work by at most [`ENERGY_ACTIVE`] of its kinetic + elastic
/// energy at its start (else the next cut is tried). On failure the state
/// is as it was.
fn rescue_substep<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    state: &mut State,
    ws: &mut Workspace,
    p: super::scheme::AlphaParameters,
    hs: f64,
    newton: &NewtonSettings,
    stats: &mut StepStats,
) -> Result<(), Failure> {
    if newton.rescue_pieces < 2 {
        return Err(Failure::NotConverged { iterations: 0 });
    }
    let e0 = sys.energy_balance(state.t, &state.q, &state.v, &state.a);
    let start = state.clone();
    let mut m = 2;
    loop {
        let mut attempt = (0..m).try_for_each(|i| {
            state.t = start.t + hs * f64::from(i) / f64::from(m);
            step_alpha(sys, state, ws, p, hs / f64::from(m), newton, stats)
        });
        if attempt.is_ok() && !state.is_finite() {
            attempt = Err(Failure::Error(IntegrateError::NonFinite { t: state.t }));
        }
        if let (Ok(()), Some(e0)) = (&attempt, e0) {
            let e1 = sys.energy_balance(start.t + hs, &state.q, &state.v, &state.a);
            let gain = e1.map_or(f64::INFINITY, |e1| e0.gain_to(&e1, hs));
            if gain.is_nan() || gain > active_share(&e0) + round_off(&e0) {
                stats.energy_refusals += 1;
                attempt = Err(Failure::EnergyGain);
            }
        }
        match attempt {
            Ok(()) => {
                stats.rescued_substeps += 1;
                state.t = start.t + hs;
                return Ok(());
            }
            Err(failed) => {
                state.clone_from(&start);
                // (The predictor's previous acceleration is a refused
                // piece's.)
                ws.a_prev_next_t = f64::NAN;
                if m >= newton.rescue_pieces {
                    return Err(failed);
                }
            }
        }
        m *= 2;
    }
}

impl Default for Integrator {
    fn default() -> Self {
        Integrator::new(Scheme::default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::DenseSystem;

    /// The example of the [`Integrator`] docs.
    #[test]
    fn doc_example_one_period() {
        let mut sys = DenseSystem::oscillator(1.0, 0.0, 4.0 * std::f64::consts::PI.powi(2)).expect("valid");
        let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
        let mut integrator = Integrator::default();
        for _ in 0..1000 {
            integrator.step(&mut sys, &mut state, 1e-3).expect("step");
        }
        assert!((state.q[0] - 1.0).abs() < 1e-4, "{}", state.q[0]);
    }

    #[test]
    fn invalid_inputs_are_typed_errors() {
        let mut sys = DenseSystem::oscillator(1.0, 0.0, 1.0).expect("valid");
        let mut state = State::new(&mut sys, 0.0, vec![1.0], vec![0.0]).expect("state");
        let mut integ = Integrator::default();
        assert!(matches!(integ.step(&mut sys, &mut state, 0.0), Err(IntegrateError::InvalidStep { .. })));
        assert!(matches!(integ.step(&mut sys, &mut state, f64::NAN), Err(IntegrateError::InvalidStep { .. })));
        integ.substeps = Substeps::Fixed(0);
        assert!(matches!(integ.step(&mut sys, &mut state, 0.1), Err(IntegrateError::InvalidStep { .. })));
        let mut bad = Integrator::new(Scheme::Hht { alpha: 0.5 });
        let e = bad.step(&mut sys, &mut state, 0.1).expect_err("alpha out of range");
        assert!(matches!(e, IntegrateError::InvalidScheme { .. }) && e.to_string().contains("t = 0 s"), "{e}");
        integ.substeps = Substeps::Auto;
        let mut short = State { t: 0.0, q: vec![], v: vec![], a: vec![], a_hat: vec![] };
        assert!(matches!(integ.step(&mut sys, &mut short, 0.1), Err(IntegrateError::DimensionMismatch { expected: 1, got: 0, .. })));
        assert!(State::new(&mut sys, 0.0, vec![1.0, 2.0], vec![0.0, 0.0]).is_err());
    }
}
