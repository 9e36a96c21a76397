//! The integration schemes, their parameters, names and stability limits.

use std::fmt;
use std::str::FromStr;

use thiserror::Error;

/// A time-integration scheme for `M(q) q̈ = Q(t, q, q̇)`.
///
/// Explicit schemes ([`is_explicit`](Self::is_explicit)) work on the
/// first-order form `z = (q, v)` and pick their sub-steps from the system's
/// highest frequency; the others are implicit and solve for the new
/// acceleration with Newton's method on the system's tangent.
///
/// Parameters are dimensionless. Build from a scenario name with
/// [`Scheme::from_name`], which checks the parameter ranges; a variant built
/// by hand is checked by [`Scheme::validate`] at every step.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "app", derive(bevy::reflect::Reflect))]
pub enum Scheme {
    /// Forward (explicit) Euler on `z = (q, v)`: `q₁ = q + h v`,
    /// `v₁ = v + h a`. Grows for every `h` on an undamped oscillator
    /// (`|λ| = √(1 + Ω²)`).
    ExplicitEuler,
    /// Symplectic (semi-explicit) Euler: `v₁ = v + h a(t, q, v)`, then
    /// `q₁ = q + h v₁`. Stable for `Ω = ω h ≤ 2`.
    SymplecticEuler,
    /// Improved Euler (Heun, explicit RK2) on `z = (q, v)`. Grows weakly for
    /// every `h` (`|λ|² = 1 + Ω⁴/4`).
    ImprovedEuler,
    /// Classical 4-stage Runge–Kutta on `z = (q, v)`. Stable for `Ω ≤ 2√2`.
    Rk4,
    /// Linear acceleration over the step: Newmark `β = 1/6, γ = 1/2`.
    /// Implicit but only conditionally stable (`Ω ≤ √12`); it is never
    /// sub-stepped automatically.
    LinearAcceleration,
    /// Newmark-β. `β = 1/4, γ = 1/2` is the average-acceleration
    /// (trapezoidal) rule, `β = 0` central difference, `β = 1/12`
    /// Fox–Goodwin. Requires `β ≥ 0`, `γ ≥ 1/2`.
    Newmark {
        /// β (dimensionless), `≥ 0`.
        beta: f64,
        /// γ (dimensionless), `≥ 1/2`.
        gamma: f64,
    },
    /// Wilson-θ (Bathe's form): linear acceleration over `θ h`, equation of
    /// motion at `t + θ h`, then interpolated back to `t + h`. `θ ≥ 1`;
    /// unconditionally stable for `θ ≥ (1 + √3)/2 ≈ 1.366`, but with the
    /// known displacement overshoot at large `Ω`: the first step from rest
    /// gives `x₁ ≈ −Ω² (1 − 1/θ)/2 · x₀` before the decay sets in.
    WilsonTheta {
        /// θ (dimensionless), `≥ 1`; 1.4 is usual.
        theta: f64,
    },
    /// Hilber–Hughes–Taylor α-method, `α ∈ [−1/3, 0]`
    /// (`β = (1 − α)²/4`, `γ = 1/2 − α`).
    Hht {
        /// α (dimensionless), in `[−1/3, 0]`; 0 is average acceleration.
        alpha: f64,
    },
    /// Generalized-α (Chung–Hulbert parameters, Arnold–Brüls form) with
    /// spectral radius at infinity `ρ∞ ∈ [0, 1]`. `ρ∞ = 0` (the default)
    /// annihilates the highest frequencies in one step and is still second
    /// order accurate.
    GeneralizedAlpha {
        /// ρ∞ (dimensionless), in `[0, 1]`.
        rho_inf: f64,
    },
    /// The fast game preset: one linearly implicit θ-step,
    /// `v₁ = v + h[(1 − w) a₀ + w a₁]`, `q₁ = q + h[(1 − w) v₀ + w v₁]`,
    /// linearised once and solved once with `M + h w C + h² w² K` (no
    /// convergence loop). `w = 1` is semi-implicit (linearly implicit)
    /// Euler, which on a linear system is backward Euler. `w ∈ [1/2, 1]`.
    ///
    /// The linearisation is at the predicted velocity `v + h a₀` and
    /// acceleration `a₀`; its configuration depends on the system's
    /// stiffness at this step ([`SecondOrderSystem::max_frequency`]
    /// `ω_max`): for `h ω_max ≤ 1` the predicted configuration
    /// `q + h v + h² w a₀` (one residual, one solve: a single Newton
    /// correction); otherwise, and when `ω_max` is unknown, the start
    /// configuration `q`, the predicted displacement entering linearly
    /// through a directional difference of the residual (two residuals, one
    /// solve). On a stiff rope the first form diverges (one correction
    /// cannot remove the second-order remainder of the extrapolated element
    /// stretch and bending: `tests/fast_preset.rs`); on a linear system both
    /// are the same θ-step.
    ///
    /// The stiff form checks its step: the residual at the end state (the
    /// pass that refreshes the rope's readouts), solved with the step's own
    /// elimination, gives what one more Newton correction would move. A step
    /// whose solve moved a coordinate by more than the system's limits
    /// ([`SecondOrderSystem::linearisation_limits`]; a rope's: 0.02 m or
    /// rad from the prediction, 2 mm or 2 mrad for the next correction), or
    /// whose solve crosses a kink of a non-smooth law (a slack element
    /// pulled taut), is taken again by the default scheme
    /// ([`StepStats::newton_fallbacks`]). A taut swing takes one solve per
    /// step; a whipping slack rope, a very heavy payload or a large step
    /// fall back on the steps one solve cannot take (measured in
    /// docs/architecture.md, "Fast preset").
    ///
    /// [`StepStats::newton_fallbacks`]: super::StepStats::newton_fallbacks
    ///
    /// [`SecondOrderSystem::max_frequency`]: super::SecondOrderSystem::max_frequency
    /// [`SecondOrderSystem::linearisation_limits`]: super::SecondOrderSystem::linearisation_limits
    LinearlyImplicit {
        /// Implicitness weight w (dimensionless), in `[1/2, 1]`.
        w: f64,
    },
}

impl Default for Scheme {
    /// Generalized-α with `ρ∞ = 0`: the project default (see DESIGN.md,
    /// "Stable at the frame step").
    fn default() -> Self {
        Scheme::GeneralizedAlpha { rho_inf: 0.0 }
    }
}

/// Optional scheme parameters as they come from a scenario file. A parameter
/// left `None` takes the scheme's default; a parameter the scheme does not
/// use is an error ([`SchemeError::UnusedParameter`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SchemeParams {
    /// Newmark β (dimensionless). Default 1/4.
    pub beta: Option<f64>,
    /// Newmark γ (dimensionless). Default 1/2.
    pub gamma: Option<f64>,
    /// Wilson θ (dimensionless). Default 1.4.
    pub theta: Option<f64>,
    /// HHT α (dimensionless). Default −0.1.
    pub alpha: Option<f64>,
    /// Generalized-α ρ∞ (dimensionless). Default 0.
    pub rho_inf: Option<f64>,
    /// Linearly implicit weight w (dimensionless). Default 0.6.
    pub w: Option<f64>,
}

/// Why a scheme could not be built from a name and parameters.
#[derive(Clone, Debug, PartialEq, Error)]
#[non_exhaustive]
pub enum SchemeError {
    /// The name is not one of [`Scheme::NAMES`].
    #[error("unknown integrator `{name}`; expected one of: {}", Scheme::NAMES.join(", "))]
    UnknownName {
        /// The name that was given.
        name: String,
    },
    /// A parameter is outside the range where the scheme is defined.
    #[error("integrator `{scheme}`: parameter {parameter} = {value} is out of range (allowed: {allowed})")]
    OutOfRange {
        /// Canonical scheme name.
        scheme: &'static str,
        /// Parameter name (`beta`, `gamma`, `theta`, `alpha`, `rho_inf`, `w`).
        parameter: &'static str,
        /// The rejected value.
        value: f64,
        /// The allowed range, human readable.
        allowed: &'static str,
    },
    /// A parameter was given that the scheme does not use.
    #[error("integrator `{scheme}` does not take parameter {parameter}")]
    UnusedParameter {
        /// Canonical scheme name.
        scheme: &'static str,
        /// The parameter that was given.
        parameter: &'static str,
    },
}

/// The four parameters of the generalized-α family (Arnold–Brüls form):
/// `(1 − α_m) â₁ + α_m â₀ = (1 − α_f) a₁ + α_f a₀`,
/// `q₁ = q₀ + h v₀ + h²(½ − β) â₀ + h² β â₁`,
/// `v₁ = v₀ + h(1 − γ) â₀ + h γ â₁`. All dimensionless.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaParameters {
    /// α_m (weight of the old pseudo-acceleration).
    pub alpha_m: f64,
    /// α_f (weight of the old acceleration).
    pub alpha_f: f64,
    /// Newmark β.
    pub beta: f64,
    /// Newmark γ.
    pub gamma: f64,
}

impl AlphaParameters {
    /// Chung–Hulbert parameters for spectral radius at infinity `ρ∞`.
    pub fn chung_hulbert(rho_inf: f64) -> Self {
        let alpha_m = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
        let alpha_f = rho_inf / (rho_inf + 1.0);
        let gamma = 0.5 - alpha_m + alpha_f;
        let beta = 0.25 * (1.0 - alpha_m + alpha_f).powi(2);
        AlphaParameters { alpha_m, alpha_f, beta, gamma }
    }

    /// HHT-α: `α_m = 0`, `α_f = −α`, `β = (1 − α)²/4`, `γ = ½ − α`.
    pub fn hht(alpha: f64) -> Self {
        AlphaParameters { alpha_m: 0.0, alpha_f: -alpha, beta: 0.25 * (1.0 - alpha).powi(2), gamma: 0.5 - alpha }
    }

    /// Newmark-β: `α_m = α_f = 0`.
    pub fn newmark(beta: f64, gamma: f64) -> Self {
        AlphaParameters { alpha_m: 0.0, alpha_f: 0.0, beta, gamma }
    }
}

/// Ω = ω h at which the scheme becomes unstable on the undamped oscillator
/// `ẍ + ω² x = 0`: `None` when it is unconditionally stable, `Some(0.0)`
/// when it grows for every step (explicit Euler, Heun).
///
/// Values: symplectic Euler and central difference 2, Fox–Goodwin √6, linear
/// acceleration √12, RK4 2√2, Newmark (γ ≥ ½, β < γ/2) `1/√(γ/2 − β)`,
/// Wilson-θ for `1 ≤ θ < (1 + √3)/2` computed from its amplification matrix.
pub fn stability_limit(scheme: &Scheme) -> Option<f64> {
    match *scheme {
        Scheme::ExplicitEuler | Scheme::ImprovedEuler => Some(0.0),
        Scheme::SymplecticEuler => Some(2.0),
        Scheme::Rk4 => Some(2.0 * std::f64::consts::SQRT_2),
        Scheme::LinearAcceleration => newmark_limit(1.0 / 6.0, 0.5),
        Scheme::Newmark { beta, gamma } => newmark_limit(beta, gamma),
        Scheme::WilsonTheta { theta } => super::wilson::stability_limit(theta),
        Scheme::Hht { .. } | Scheme::GeneralizedAlpha { .. } | Scheme::LinearlyImplicit { .. } => None,
    }
}

/// Undamped Newmark limit `Ω_crit = 1/√(γ/2 − β)` (None when `β ≥ γ/2`).
fn newmark_limit(beta: f64, gamma: f64) -> Option<f64> {
    let d = 0.5 * gamma - beta;
    (d > 0.0).then(|| 1.0 / d.sqrt())
}

fn check(scheme: &'static str, parameter: &'static str, value: f64, ok: bool, allowed: &'static str) -> Result<(), SchemeError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(SchemeError::OutOfRange { scheme, parameter, value, allowed })
    }
}

impl Scheme {
    /// Every name [`from_name`](Self::from_name) accepts (canonical names;
    /// `central_difference`, `backward_euler`, `heun` and `explicit_euler`
    /// are accepted as aliases too).
    pub const NAMES: &'static [&'static str] = &[
        "euler",
        "symplectic_euler",
        "improved_euler",
        "rk4",
        "linear_acceleration",
        "newmark",
        "wilson_theta",
        "hht",
        "generalized_alpha",
        "linearly_implicit",
    ];

    /// Builds a scheme from its scenario name and optional parameters, with
    /// defaults for parameters left out (see [`SchemeParams`]) and range
    /// checks: `β ≥ 0`, `γ ≥ ½`, `θ ≥ 1`, `α ∈ [−⅓, 0]`, `ρ∞ ∈ [0, 1]`,
    /// `w ∈ [½, 1]`.
    pub fn from_name(name: &str, params: &SchemeParams) -> Result<Self, SchemeError> {
        let canonical: &'static str = match name.trim().to_ascii_lowercase().as_str() {
            "euler" | "explicit_euler" => "euler",
            "symplectic_euler" => "symplectic_euler",
            "improved_euler" | "heun" => "improved_euler",
            "rk4" => "rk4",
            "linear_acceleration" => "linear_acceleration",
            "newmark" => "newmark",
            "central_difference" => "central_difference",
            "wilson_theta" => "wilson_theta",
            "hht" => "hht",
            "generalized_alpha" => "generalized_alpha",
            "linearly_implicit" => "linearly_implicit",
            "backward_euler" => "backward_euler",
            _ => return Err(SchemeError::UnknownName { name: name.to_string() }),
        };
        let uses: &[&str] = match canonical {
            "newmark" => &["beta", "gamma"],
            "wilson_theta" => &["theta"],
            "hht" => &["alpha"],
            "generalized_alpha" => &["rho_inf"],
            "linearly_implicit" => &["w"],
            _ => &[],
        };
        let given =
            [("beta", params.beta), ("gamma", params.gamma), ("theta", params.theta), ("alpha", params.alpha), ("rho_inf", params.rho_inf), ("w", params.w)];
        for (parameter, value) in given {
            if value.is_some() && !uses.contains(&parameter) {
                return Err(SchemeError::UnusedParameter { scheme: canonical, parameter });
            }
        }
        let scheme = match canonical {
            "euler" => Scheme::ExplicitEuler,
            "symplectic_euler" => Scheme::SymplecticEuler,
            "improved_euler" => Scheme::ImprovedEuler,
            "rk4" => Scheme::Rk4,
            "linear_acceleration" => Scheme::LinearAcceleration,
            "newmark" => Scheme::Newmark { beta: params.beta.unwrap_or(0.25), gamma: params.gamma.unwrap_or(0.5) },
            "central_difference" => Scheme::Newmark { beta: 0.0, gamma: 0.5 },
            "wilson_theta" => Scheme::WilsonTheta { theta: params.theta.unwrap_or(1.4) },
            "hht" => Scheme::Hht { alpha: params.alpha.unwrap_or(-0.1) },
            "generalized_alpha" => Scheme::GeneralizedAlpha { rho_inf: params.rho_inf.unwrap_or(0.0) },
            "backward_euler" => Scheme::LinearlyImplicit { w: 1.0 },
            _ => Scheme::LinearlyImplicit { w: params.w.unwrap_or(0.6) },
        };
        scheme.validate()?;
        Ok(scheme)
    }

    /// Checks the parameter ranges (see [`from_name`](Self::from_name)).
    pub fn validate(&self) -> Result<(), SchemeError> {
        let name = self.name();
        match *self {
            Scheme::Newmark { beta, gamma } => {
                check(name, "beta", beta, beta >= 0.0, "beta >= 0")?;
                check(name, "gamma", gamma, gamma >= 0.5, "gamma >= 1/2")
            }
            Scheme::WilsonTheta { theta } => check(name, "theta", theta, theta >= 1.0, "theta >= 1"),
            Scheme::Hht { alpha } => check(name, "alpha", alpha, (-1.0 / 3.0..=0.0).contains(&alpha), "-1/3 <= alpha <= 0"),
            Scheme::GeneralizedAlpha { rho_inf } => check(name, "rho_inf", rho_inf, (0.0..=1.0).contains(&rho_inf), "0 <= rho_inf <= 1"),
            Scheme::LinearlyImplicit { w } => check(name, "w", w, (0.5..=1.0).contains(&w), "1/2 <= w <= 1"),
            _ => Ok(()),
        }
    }

    /// Canonical scenario name (`"generalized_alpha"`, `"rk4"`, …).
    pub fn name(&self) -> &'static str {
        match self {
            Scheme::ExplicitEuler => "euler",
            Scheme::SymplecticEuler => "symplectic_euler",
            Scheme::ImprovedEuler => "improved_euler",
            Scheme::Rk4 => "rk4",
            Scheme::LinearAcceleration => "linear_acceleration",
            Scheme::Newmark { .. } => "newmark",
            Scheme::WilsonTheta { .. } => "wilson_theta",
            Scheme::Hht { .. } => "hht",
            Scheme::GeneralizedAlpha { .. } => "generalized_alpha",
            Scheme::LinearlyImplicit { .. } => "linearly_implicit",
        }
    }

    /// True for the schemes that never solve with the tangent's stiffness:
    /// explicit Euler, symplectic Euler, improved Euler and RK4. (Newmark
    /// with `β = 0`, central difference, is run through the implicit path:
    /// it solves with `M + γ h C`.)
    pub fn is_explicit(&self) -> bool {
        matches!(self, Scheme::ExplicitEuler | Scheme::SymplecticEuler | Scheme::ImprovedEuler | Scheme::Rk4)
    }

    /// True for the schemes that solve for the new acceleration with Newton
    /// (`!is_explicit()`).
    pub fn is_implicit(&self) -> bool {
        !self.is_explicit()
    }

    /// The generalized-α parameters for the Newmark family (linear
    /// acceleration, Newmark, HHT, generalized-α); `None` for the others.
    pub fn alpha_parameters(&self) -> Option<AlphaParameters> {
        match *self {
            Scheme::LinearAcceleration => Some(AlphaParameters::newmark(1.0 / 6.0, 0.5)),
            Scheme::Newmark { beta, gamma } => Some(AlphaParameters::newmark(beta, gamma)),
            Scheme::Hht { alpha } => Some(AlphaParameters::hht(alpha)),
            Scheme::GeneralizedAlpha { rho_inf } => Some(AlphaParameters::chung_hulbert(rho_inf)),
            _ => None,
        }
    }
}

impl FromStr for Scheme {
    type Err = SchemeError;

    /// [`Scheme::from_name`] with default parameters.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Scheme::from_name(s, &SchemeParams::default())
    }
}

impl fmt::Display for Scheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Scheme::Newmark { beta, gamma } => write!(f, "newmark(beta={beta}, gamma={gamma})"),
            Scheme::WilsonTheta { theta } => write!(f, "wilson_theta(theta={theta})"),
            Scheme::Hht { alpha } => write!(f, "hht(alpha={alpha})"),
            Scheme::GeneralizedAlpha { rho_inf } => write!(f, "generalized_alpha(rho_inf={rho_inf})"),
            Scheme::LinearlyImplicit { w } => write!(f, "linearly_implicit(w={w})"),
            _ => f.write_str(self.name()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_defaults() {
        for name in Scheme::NAMES {
            let s: Scheme = name.parse().expect("canonical names parse");
            assert_eq!(s.name(), *name);
        }
        assert_eq!(Scheme::default(), Scheme::GeneralizedAlpha { rho_inf: 0.0 });
        assert_eq!("central_difference".parse::<Scheme>(), Ok(Scheme::Newmark { beta: 0.0, gamma: 0.5 }));
        assert_eq!("backward_euler".parse::<Scheme>(), Ok(Scheme::LinearlyImplicit { w: 1.0 }));
        assert!(Scheme::Rk4.is_explicit() && Scheme::LinearAcceleration.is_implicit());
    }

    #[test]
    fn typed_errors() {
        let e = "verlet".parse::<Scheme>().unwrap_err();
        assert!(matches!(e, SchemeError::UnknownName { .. }));
        assert!(e.to_string().contains("generalized_alpha"));
        let p = |f: fn(&mut SchemeParams)| {
            let mut p = SchemeParams::default();
            f(&mut p);
            p
        };
        let cases: [(&str, SchemeParams, &str); 7] = [
            ("newmark", p(|p| p.beta = Some(-0.1)), "beta"),
            ("newmark", p(|p| p.gamma = Some(0.4)), "gamma"),
            ("wilson_theta", p(|p| p.theta = Some(0.9)), "theta"),
            ("hht", p(|p| p.alpha = Some(-0.5)), "alpha"),
            ("hht", p(|p| p.alpha = Some(0.1)), "alpha"),
            ("generalized_alpha", p(|p| p.rho_inf = Some(1.5)), "rho_inf"),
            ("linearly_implicit", p(|p| p.w = Some(0.4)), "w"),
        ];
        for (name, params, param) in cases {
            match Scheme::from_name(name, &params) {
                Err(SchemeError::OutOfRange { parameter, .. }) => assert_eq!(parameter, param),
                other => panic!("{name}: expected OutOfRange, got {other:?}"),
            }
        }
        let nan = p(|p| p.rho_inf = Some(f64::NAN));
        assert!(Scheme::from_name("generalized_alpha", &nan).is_err());
        let unused = p(|p| p.theta = Some(1.4));
        assert_eq!(Scheme::from_name("newmark", &unused), Err(SchemeError::UnusedParameter { scheme: "newmark", parameter: "theta" }));
    }

    #[test]
    fn alpha_parameters_match_known_cases() {
        let g = AlphaParameters::chung_hulbert(1.0);
        assert_eq!((g.alpha_m, g.alpha_f, g.beta, g.gamma), (0.5, 0.5, 0.25, 0.5));
        let g0 = AlphaParameters::chung_hulbert(0.0);
        assert_eq!((g0.alpha_m, g0.alpha_f, g0.beta, g0.gamma), (-1.0, 0.0, 1.0, 1.5));
        // ρ∞ = 1/2 is HHT with α = −1/3.
        let a = AlphaParameters::chung_hulbert(0.5);
        let b = AlphaParameters::hht(-1.0 / 3.0);
        assert!((a.beta - b.beta).abs() < 1e-15 && (a.gamma - b.gamma).abs() < 1e-15);
    }

    #[test]
    fn stability_limits_of_section_8() {
        let cases = [
            (Scheme::Newmark { beta: 0.0, gamma: 0.5 }, 2.0),
            (Scheme::SymplecticEuler, 2.0),
            (Scheme::Newmark { beta: 1.0 / 12.0, gamma: 0.5 }, 6f64.sqrt()),
            (Scheme::LinearAcceleration, 12f64.sqrt()),
            (Scheme::Rk4, 8f64.sqrt()),
        ];
        for (s, limit) in cases {
            let got = stability_limit(&s).expect("conditionally stable");
            assert!((got - limit).abs() < 1e-12, "{s}: {got} vs {limit}");
        }
        assert_eq!(stability_limit(&Scheme::ExplicitEuler), Some(0.0));
        assert_eq!(stability_limit(&Scheme::Newmark { beta: 0.25, gamma: 0.5 }), None);
        assert_eq!(stability_limit(&Scheme::default()), None);
        assert_eq!(stability_limit(&Scheme::WilsonTheta { theta: 1.4 }), None);
    }
}
