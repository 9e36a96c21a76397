//! Newton's method on the new acceleration for every implicit scheme.
//!
//! Each implicit scheme writes its new coordinates as an affine function of
//! the unknown acceleration `x`: `q = q_b + c_q x`, `v = v_b + c_v x`, and
//! asks for `r(t, q, v, x) = 0`. The Newton matrix is then exactly
//! `∂r/∂x = M + c_v C_t + c_q K_t`, which is what
//! [`SecondOrderSystem::solve_tangent`] solves with.

use super::error::IntegrateError;
use super::integrator::{StepStats, Workspace};
use super::state::all_finite;
use super::system::SecondOrderSystem;

/// Newton control for the implicit schemes.
#[derive(Clone, Debug, PartialEq)]
pub struct NewtonSettings {
    /// Iterations (residual + solve each) before a step counts as not
    /// converged. Default 8; values below 1 act as 1.
    pub max_iterations: usize,
    /// Largest split of a step in the fallback: a step that does not converge
    /// (or whose solve fails, or that turns non-finite) is redone as 2, 4, …
    /// sub-steps up to this many. Default 256; 1 disables the fallback.
    /// Under [`Substeps::Auto`](super::Substeps::Auto) the split is kept for
    /// the next steps and halved again after
    /// [`CALM_STEPS`](super::CALM_STEPS) easy ones.
    pub max_substeps: u32,
    /// Relative part of the convergence test: a coordinate's correction must
    /// stay below `tol + relative_tolerance·|q_i|` (positions) and
    /// `tol/h + relative_tolerance·|v_i|` (velocities), `tol` the system's
    /// [`position_tolerance`](SecondOrderSystem::position_tolerance).
    /// Default 1e-12 (dimensionless).
    pub relative_tolerance: f64,
    /// Line search along each Newton correction (default `true`): when the
    /// full correction overshoots the minimum of the step's incremental
    /// potential along its direction (the directional derivative
    /// `r(x + dx)·dx` changes sign and keeps more than half its size), the
    /// step is cut back by regula falsi. Needed for non-smooth laws (a slack
    /// rope's tension-only elements, where the tangent of the slack side
    /// sends a full correction deep into the taut side); free when the full
    /// step is good (the residual at the new iterate is computed anyway).
    pub line_search: bool,
    /// Chord iterations (m or rad; default [`CHORD_LIMIT`], 0 turns them
    /// off): once a Newton correction is at most this large in every
    /// coordinate (`c_q`·correction), the next iteration evaluates the
    /// residual and solves it with the last elimination
    /// ([`SecondOrderSystem::resolve_last_tangent`]) instead of a fresh
    /// fused residual-and-elimination pass, in systems whose re-solve is
    /// exact ([`SecondOrderSystem::resolves_exactly`]: a chain without force
    /// elements or pair contacts). The tangent then lags by at most that
    /// correction, so the
    /// iterations converge linearly at a rate of that order, and the
    /// convergence test is unchanged. A chord correction larger than the
    /// correction before it is not taken (the next iteration is a full
    /// pass at the same iterate), and one that shrinks by less than
    /// a factor of 10 turns chords off for the rest of the solve.
    pub chord_limit: f64,
    /// Energy-checked sub-steps (default `true`): a sub-step of a system
    /// with an energy account
    /// ([`SecondOrderSystem::energy_balance`](super::SecondOrderSystem::energy_balance))
    /// after which its step's energy has grown, beyond the work of its
    /// moving supports, by more than
    /// [`ENERGY_ACTIVE`](super::ENERGY_ACTIVE) allows is refused and the
    /// step split further, and a failed Newton solve of such a system is
    /// retried with the tangent's fallback at every split (not only from a
    /// calm state). It lets a rope laid with a corner across gravity run,
    /// and keeps a whipping slack rope from gaining energy at the frame
    /// step (docs/architecture.md, "Energy-checked sub-steps"). Off: the
    /// bare scheme (convergence studies of the scheme itself).
    pub energy_check: bool,
    /// Local refinement at the finest split (default
    /// [`RESCUE_PIECES`](super::RESCUE_PIECES), 1 turns it off): a sub-step
    /// of the finest split ([`max_substeps`](Self::max_substeps)) whose
    /// generalized-α Newton solve fails is taken again in 2, 4, … up to
    /// this many pieces before the step fails; only that sub-step is cut.
    /// Only for a system with an energy account
    /// ([`SecondOrderSystem::energy_balance`](super::SecondOrderSystem::energy_balance)),
    /// each cut energy-checked.
    pub rescue_pieces: u32,
}

/// Default [`NewtonSettings::chord_limit`], m or rad. Measured on
/// `perf_swing_1000.toml` (1 000 elements, 20 s, contacts off): 1e-6,
/// 3e-6, 1e-5, 3e-5, 1e-4, 1e-3 gave 14.9, 15.2, 15.8, 15.4, 15.2, 15.1×
/// real time against 14.3× without chords (2.28, 2.28, 2.34, 2.41, 2.46,
/// 2.52 Newton iterations per step against 2.28); 1e-2 gave 14.7× and
/// results 7e-4 m away from the exact Newton's (1e-5: 1.2e-7 m, the
/// drift of the 1e-9 m tolerance over 1 200 steps).
pub const CHORD_LIMIT: f64 = 1e-5;

/// A chord iteration whose correction is larger than this fraction of the
/// one before turns chords off for the rest of the Newton solve (the
/// tangent changed too much since its elimination for the chord to
/// converge fast).
const CHORD_CONTRACTION: f64 = 0.1;

impl Default for NewtonSettings {
    fn default() -> Self {
        NewtonSettings {
            max_iterations: 8,
            max_substeps: 256,
            relative_tolerance: 1e-12,
            line_search: true,
            chord_limit: CHORD_LIMIT,
            energy_check: true,
            rescue_pieces: super::RESCUE_PIECES,
        }
    }
}

/// Why one (sub-)step failed; the fallback decides what to do.
#[derive(Debug)]
pub(crate) enum Failure {
    /// Newton reached its iteration limit.
    NotConverged { iterations: usize },
    /// The system failed, or the state became non-finite.
    Error(IntegrateError),
    /// The fast preset's single linearised solve does not hold: it crossed
    /// a kink of a non-smooth law, or the residual it left at the step's end
    /// needs a further correction beyond the preset's limit (the step's
    /// nonlinearity is too large for one solve). The step is taken again by
    /// the default scheme.
    Linearisation,
    /// A passive system gained more energy over a sub-step than
    /// [`ENERGY_ACTIVE`](super::ENERGY_ACTIVE) allows: the step is split.
    EnergyGain,
}

impl From<IntegrateError> for Failure {
    fn from(e: IntegrateError) -> Self {
        Failure::Error(e)
    }
}

/// One Newton solve of an implicit scheme: the evaluation time and the
/// affine map's slopes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Affine {
    /// Time at which the equation of motion is enforced, s.
    pub t: f64,
    /// `∂q/∂x`, s².
    pub c_q: f64,
    /// `∂v/∂x`, s.
    pub c_v: f64,
    /// The (sub-)step, s (velocity tolerance `tol/h`).
    pub h: f64,
}

/// Solves `r(t, q_b + c_q x, v_b + c_v x, x) = 0` for `x`, starting from the
/// `ws.x` given. `ws.qb`, `ws.vb` hold the affine bases. With
/// `one_shot` exactly one correction is made and no convergence is tested.
/// On success `ws.x` is the solution and `ws.q`, `ws.v` the matching
/// coordinates and velocities.
///
/// Non-smooth laws (tension-only rope elements) are solved by an active
/// set: Newton runs on the branches frozen from the step's start `start`
/// (coordinates, velocities) and the starting iterate
/// ([`SecondOrderSystem::freeze_branches`]); once it converges, every law
/// whose branch disagrees with the solution changes branch (a taut one only
/// beyond [`KINK_BAND`]) and Newton goes on, with a fresh iteration budget, up to
/// [`MAX_BRANCH_UPDATES`] times ([`LAST_RESORT_BRANCH_UPDATES`] in the
/// integrator's last-resort pass, `ws.branch_budget`). A solution whose branches then still
/// disagree by more than [`KINK_BAND`] is not accepted: the step fails as
/// not converged (and the fallback splits it).
pub(crate) fn solve<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    ws: &mut Workspace,
    map: Affine,
    settings: &NewtonSettings,
    one_shot: bool,
    stats: &mut StepStats,
    start: (&[f64], &[f64]),
) -> Result<(), Failure> {
    update_coordinates(ws, map.c_q, map.c_v);
    sys.freeze_branches(start, (&ws.q, &ws.v));
    let mut result = iterate(sys, ws, map, settings, one_shot, stats);
    if !one_shot {
        // Branch updates until the branches agree with the solution. After
        // the last update, laws still within `KINK_BAND` of their kink (a
        // run of elements near zero tension, whose branches chatter) are
        // accepted on the branch they are on; a larger disagreement (a
        // slack element that should carry the load) fails the solve, and
        // the step is split.
        let mut updates = 0;
        while result.is_ok() {
            if updates == ws.branch_budget.max(MAX_BRANCH_UPDATES) {
                if sys.branch_disagreement(&ws.q, &ws.v) > KINK_BAND {
                    result = Err(Failure::NotConverged { iterations: settings.max_iterations.max(1) });
                }
                break;
            }
            if sys.update_branches(&ws.q, &ws.v) == 0 {
                break;
            }
            updates += 1;
            stats.branch_updates += 1;
            result = iterate(sys, ws, map, settings, false, stats);
        }
    }
    sys.release_branches();
    result
}

/// Most branch updates of non-smooth laws in one Newton solve.
pub const MAX_BRANCH_UPDATES: usize = 3;

/// Most branch updates of one Newton solve in the integrator's last-resort
/// pass: when a step fails at every split up to
/// [`NewtonSettings::max_substeps`] with [`MAX_BRANCH_UPDATES`], it is
/// tried again from its first split with this many. A rope whose change of
/// branch walks down it one element per update (a damped rope unloading
/// while it carries only its own weight) needs about one update per
/// element. Steps that pass the first pass never see it.
pub const LAST_RESORT_BRANCH_UPDATES: usize = 64;

/// Largest disagreement (m or rad, the law's own measure: a tension-only
/// element's `x + (c/k) v`) between a law's frozen branch and the solution
/// that a Newton solve accepts after [`MAX_BRANCH_UPDATES`] updates. A
/// micrometre: such an element misses or adds at most `k·1e-6` (N), and it
/// is re-frozen at the next step.
pub const KINK_BAND: f64 = 1e-6;

/// A Newton solve in a system that asks for it
/// ([`SecondOrderSystem::patient_newton`]) may take up to this many times
/// [`NewtonSettings::max_iterations`], while each correction stays within
/// twice the smallest one so far (in norm); the first one past that ends it
/// (the step is then split). Measured on a light line whose end a stiff spring pulls with 100
/// times the payload's weight (docs/architecture.md, "Force elements"): the
/// frame step then converges in 4.1 iterations per step on average, with a
/// few steps needing 10 to 20, where splitting them failed down to 256
/// sub-steps.
pub const PATIENT_BUDGET: usize = 4;

/// Exact Newton iterations a solve may still take after a correction
/// solved with the tangent's fallback came within the tolerance.
pub(crate) const FINISHING_ITERATIONS: usize = 4;

/// Newton iterations on the current (frozen) laws.
///
/// A correction solved with the tangent's fallback
/// ([`SecondOrderSystem::tangent_fell_back`]) never ends the solve: once
/// one is within the tolerance, the fallback is switched off for the rest
/// of the solve, and only an exact Newton correction within the tolerance
/// is accepted.
fn iterate<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    ws: &mut Workspace,
    map: Affine,
    settings: &NewtonSettings,
    one_shot: bool,
    stats: &mut StepStats,
) -> Result<(), Failure> {
    let mut finishing = false;
    let result = iterate_exactly(sys, ws, map, settings, one_shot, stats, &mut finishing);
    if finishing {
        sys.set_definite_tangent(true);
    }
    result
}

/// [`iterate`]'s loop; `finishing` is set when it switched the fallback
/// off (the caller switches it on again).
fn iterate_exactly<S: SecondOrderSystem + ?Sized>(
    sys: &mut S,
    ws: &mut Workspace,
    map: Affine,
    settings: &NewtonSettings,
    one_shot: bool,
    stats: &mut StepStats,
    finishing: &mut bool,
) -> Result<(), Failure> {
    let Affine { t, c_q, c_v, h } = map;
    let tol = sys.position_tolerance();
    let vel_tol = tol / h;
    let rel = settings.relative_tolerance;
    let max_iterations = if one_shot { 1 } else { settings.max_iterations.max(1) };
    let line_search = settings.line_search && !one_shot;
    // The directional derivative `g(0) = r(x₀)·dx` of the last full step.
    let mut pending: Option<f64> = None;
    // A patient system's solve continues past `max_iterations` while each
    // correction is within twice the smallest so far (squared norms).
    let patient = !one_shot && sys.patient_newton();
    let mut limit = if patient { PATIENT_BUDGET * max_iterations } else { max_iterations };
    let mut least_size = f64::INFINITY;
    let mut done = 0;
    let mut iteration = 0;
    // Whether the next iteration may solve with the last elimination.
    let mut chord = false;
    // The last correction's size, and whether chords are off for the rest
    // of this solve (one did not contract).
    let (mut last_largest, mut no_chords) = (f64::INFINITY, false);
    while iteration < limit {
        iteration += 1;
        done = iteration;
        update_coordinates(ws, c_q, c_v);
        // Whether `ws.dx` is a chord's correction (a line search below
        // replaces it with a full pass's).
        let mut from_chord = chord;
        if chord {
            from_chord = chord_pass(sys, ws, map, stats)?;
        } else {
            pass(sys, ws, map, stats)?;
        }
        stats.newton_iterations += 1;
        if let Some(g0) = pending.take() {
            // `ws.r` holds −r at x = x₀ + dx_prev.
            let g1 = -dot(&ws.r, &ws.dx_prev);
            if g0 < 0.0 && g1 > 0.5 * g0.abs() {
                // Overshoot: regula falsi on g(α) = r(x₀ + α dx)·dx over
                // [0, 1], a few evaluations, each a fused pass (the last one
                // accepted leaves its own correction in ws.dx).
                let (mut lo, mut g_lo, mut hi, mut g_hi) = (0.0f64, g0, 1.0f64, g1);
                let mut alpha = 1.0;
                for _ in 0..4 {
                    let width = hi - lo;
                    let next = (lo - g_lo * width / (g_hi - g_lo)).clamp(lo + 0.05 * width, hi - 0.05 * width);
                    for (xi, d) in ws.x.iter_mut().zip(&ws.dx_prev) {
                        *xi += (next - alpha) * d;
                    }
                    alpha = next;
                    update_coordinates(ws, c_q, c_v);
                    pass(sys, ws, map, stats)?;
                    from_chord = false;
                    stats.line_search_evals += 1;
                    let g = -dot(&ws.r, &ws.dx_prev);
                    if g.abs() <= 0.5 * g0.abs() {
                        break;
                    }
                    if g > 0.0 {
                        (hi, g_hi) = (alpha, g);
                    } else {
                        (lo, g_lo) = (alpha, g);
                    }
                }
            }
        }
        let mut converged = true;
        let mut largest = 0.0f64;
        let mut finite = true;
        for i in 0..ws.x.len() {
            let d = ws.dx[i];
            finite &= d.is_finite();
            let dq = (c_q * d).abs();
            largest = largest.max(dq);
            let dv = (c_v * d).abs();
            if dq > tol + rel * ws.q[i].abs() || dv > vel_tol + rel * ws.v[i].abs() {
                converged = false;
            }
        }
        if from_chord && !(finite && largest <= last_largest) {
            // A chord correction that does not contract (the tangent
            // changed too much since its elimination) is not taken: the
            // iterate stays, chords stop for this solve, and the next
            // iteration is a full pass there. Taken, it moved a damped
            // rope lying in a horizontal arc so far from the solution at
            // its first step (a 50 times larger correction) that Newton
            // failed at every split.
            no_chords = true;
            chord = false;
            pending = None;
            continue;
        }
        if !finite {
            return Err(IntegrateError::NonFinite { t }.into());
        }
        if converged && !one_shot && sys.tangent_fell_back() {
            // Not a Newton step: finish with the exact tangent.
            converged = false;
            *finishing = true;
            sys.set_definite_tangent(false);
            // Room for the exact corrections (quadratic from here).
            limit = limit.max(iteration + FINISHING_ITERATIONS);
        }
        // A correction within the tolerance gains nothing from the
        // system's own update (its second-order part is smaller still).
        apply_correction(sys, ws, c_q, !converged);
        if one_shot || converged {
            update_coordinates(ws, c_q, c_v);
            return Ok(());
        }
        if from_chord && largest > CHORD_CONTRACTION * last_largest {
            no_chords = true;
        }
        last_largest = largest;
        chord = !no_chords && !*finishing && largest <= settings.chord_limit && sys.resolves_exactly();
        if patient {
            let size = dot(&ws.dx, &ws.dx);
            if iteration >= max_iterations && size >= 4.0 * least_size {
                break;
            }
            least_size = least_size.min(size);
        }
        if line_search {
            // g(0) = r(x₀)·dx (negative for a descent direction).
            pending = Some(-dot(&ws.r, &ws.dx));
            std::mem::swap(&mut ws.dx, &mut ws.dx_prev);
        }
    }
    Err(Failure::NotConverged { iterations: done })
}

/// One fused residual + correction pass at the current `ws.q`, `ws.v`,
/// `ws.x`: `ws.r = −r`, `ws.dx` the correction.
fn pass<S: SecondOrderSystem + ?Sized>(sys: &mut S, ws: &mut Workspace, map: Affine, stats: &mut StepStats) -> Result<(), Failure> {
    let Affine { t, c_q, c_v, .. } = map;
    sys.residual_and_correction(t, &ws.q, &ws.v, &ws.x, c_v, c_q, &mut ws.r, &mut ws.dx)
        .map_err(|source| Failure::Error(IntegrateError::System { t, source }))?;
    stats.residual_evals += 1;
    stats.solves += 1;
    if !all_finite(&ws.r) {
        return Err(IntegrateError::NonFinite { t }.into());
    }
    Ok(())
}

/// A chord iteration at the current `ws.q`, `ws.v`, `ws.x`: the residual,
/// then the correction solved with the last elimination
/// ([`SecondOrderSystem::resolve_last_tangent`]): `ws.r = −r`, `ws.dx` the
/// correction. Answers whether it was a chord (`false`: the system could
/// not re-solve, and a full pass was made).
fn chord_pass<S: SecondOrderSystem + ?Sized>(sys: &mut S, ws: &mut Workspace, map: Affine, stats: &mut StepStats) -> Result<bool, Failure> {
    let t = map.t;
    sys.residual(t, &ws.q, &ws.v, &ws.x, &mut ws.r).map_err(|source| Failure::Error(IntegrateError::System { t, source }))?;
    stats.residual_evals += 1;
    for r in ws.r.iter_mut() {
        *r = -*r;
    }
    if !all_finite(&ws.r) {
        return Err(IntegrateError::NonFinite { t }.into());
    }
    if !sys.resolve_last_tangent(&ws.r, &mut ws.dx) {
        pass(sys, ws, map, stats)?;
        return Ok(false);
    }
    stats.chord_iterations += 1;
    Ok(true)
}

/// `x += dx`, or, when `own_update` is asked for and `c_q > 0`, through
/// the system's own coordinate update if it has one (then `dx` becomes the
/// step actually taken).
fn apply_correction<S: SecondOrderSystem + ?Sized>(sys: &mut S, ws: &mut Workspace, c_q: f64, own_update: bool) {
    if own_update && c_q > 0.0 && sys.nonlinear_update(&ws.q, &ws.dx, c_q, &mut ws.q_new) {
        for i in 0..ws.x.len() {
            let x = (ws.q_new[i] - ws.qb[i]) / c_q;
            ws.dx[i] = x - ws.x[i];
            ws.x[i] = x;
        }
        return;
    }
    for (xi, d) in ws.x.iter_mut().zip(&ws.dx) {
        *xi += d;
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `q = q_b + c_q x`, `v = v_b + c_v x` from the affine bases and `x`.
pub(crate) fn update_coordinates(ws: &mut Workspace, c_q: f64, c_v: f64) {
    for i in 0..ws.x.len() {
        ws.q[i] = ws.qb[i] + c_q * ws.x[i];
        ws.v[i] = ws.vb[i] + c_v * ws.x[i];
    }
}
