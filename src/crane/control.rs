//! Anti-sway control of a trolley (REFERENCE.md §8, seed 000): input
//! shaping (ZV, ZVD) of a speed command, the double closed-loop PID, the
//! nonlinear PID with error-dependent gains, and the incremental digital
//! PID. Bevy-free: a controller reads a [`TrolleyMeasurement`] and returns
//! a [`TrolleyCommand`]; [`OverheadCraneLoop`] closes the loop on the
//! reduced [`OverheadCrane`].

use super::{check_limit, check_positive, limit, CraneError, LagrangeSystem, OverheadCrane, TrolleyDrive};

use crate::integrate::{Integrator, State};

/// What a trolley controller reads at a sample.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TrolleyMeasurement {
    /// Time, s.
    pub time: f64,
    /// Trolley position along the rail, m.
    pub position: f64,
    /// Trolley speed, m/s.
    pub velocity: f64,
    /// Sway angle from the downward vertical, rad, positive when the
    /// payload is ahead of the trolley along the rail.
    pub sway: f64,
    /// Sway rate, rad/s.
    pub sway_rate: f64,
}

/// What a trolley controller asks of the drive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TrolleyCommand {
    /// A drive force, N.
    Force(f64),
    /// A trolley speed, m/s (for a speed-controlled drive).
    Speed(f64),
}

/// A controller of a trolley on a rail.
pub trait TrolleyController {
    /// The command for the sample at `m.time` (called once per sample, in
    /// time order).
    fn update(&mut self, m: &TrolleyMeasurement) -> TrolleyCommand;
}

impl<T: TrolleyController + ?Sized> TrolleyController for Box<T> {
    fn update(&mut self, m: &TrolleyMeasurement) -> TrolleyCommand {
        (**self).update(m)
    }
}

/// A point-to-point move of the trolley: from `start` (m) at time `t0` (s)
/// to `target` (m), with a speed limit (m/s) and an acceleration limit
/// (m/s²): the time-optimal trapezoidal (or triangular) speed profile.
/// Limits that are not positive and finite (or a non-finite distance or
/// start time) give no motion: the trolley is held at `start`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// Start time, s.
    pub t0: f64,
    /// Start position, m.
    pub start: f64,
    /// Target position, m.
    pub target: f64,
    /// Speed limit, m/s (positive).
    pub max_speed: f64,
    /// Acceleration limit, m/s² (positive).
    pub max_acceleration: f64,
}

impl Move {
    /// Acceleration time, cruise time, and the signed cruise speed (all 0,
    /// no motion, when a limit is not positive and finite or the distance
    /// is 0 or not finite).
    fn phases(&self) -> (f64, f64, f64) {
        let d = (self.target - self.start).abs();
        let (vm, am) = (self.max_speed.abs(), self.max_acceleration.abs());
        let sign = (self.target - self.start).signum();
        let usable = |x: f64| x.is_finite() && x > 0.0;
        if !(usable(vm) && usable(am) && usable(d) && self.t0.is_finite()) {
            return (0.0, 0.0, 0.0);
        }
        let ta = vm / am;
        if am * ta * ta >= d {
            // Triangular: never reaches the speed limit.
            let ta = (d / am).sqrt();
            (ta, 0.0, sign * am * ta)
        } else {
            (ta, (d - am * ta * ta) / vm, sign * vm)
        }
    }

    /// Duration of the move, s.
    pub fn duration(&self) -> f64 {
        let (ta, tc, _) = self.phases();
        2.0 * ta + tc
    }

    /// Commanded speed at time `t`, m/s.
    pub fn speed(&self, t: f64) -> f64 {
        let (ta, tc, v) = self.phases();
        let s = t - self.t0;
        if s <= 0.0 || s >= 2.0 * ta + tc {
            0.0
        } else if s < ta {
            v * s / ta
        } else if s <= ta + tc {
            v
        } else {
            v * (2.0 * ta + tc - s) / ta
        }
    }

    /// Commanded position at time `t`, m.
    pub fn position(&self, t: f64) -> f64 {
        let (ta, tc, v) = self.phases();
        let s = (t - self.t0).clamp(0.0, 2.0 * ta + tc);
        if ta == 0.0 {
            // No motion (see `phases`).
            return self.start;
        }
        let a = v / ta;
        let x = if s < ta {
            0.5 * a * s * s
        } else if s <= ta + tc {
            0.5 * v * ta + v * (s - ta)
        } else {
            let r = 2.0 * ta + tc - s;
            v * (ta + tc) - 0.5 * a * r * r
        };
        self.start + x
    }
}

/// A trolley position reference: what a controller follows.
pub trait Reference {
    /// Reference position at time `t` (s), m.
    fn position(&self, t: f64) -> f64;
    /// Reference speed at time `t` (s), m/s.
    fn speed(&self, t: f64) -> f64;
}

impl Reference for Move {
    fn position(&self, t: f64) -> f64 {
        Move::position(self, t)
    }
    fn speed(&self, t: f64) -> f64 {
        Move::speed(self, t)
    }
}

/// A trolley reference through waypoints `(t_i, x_i)` (s, m), as a
/// scenario's `[[controller]] target` gives them: the trolley holds `x_0`
/// until `t_0`; from each waypoint it moves to the next with a
/// trapezoidal speed profile within the speed and acceleration limits, at
/// rest at both ends. The move starts at `t_i` (or when the move before
/// it ends, if that is later) and arrives exactly at `t_{i+1}` when the
/// limits allow it (its cruise speed lowered to
/// `v = 2 a d / (a T + √(a²T² − 4 a d))`, `d` the distance and `T` the time
/// it has); when they do not, it is the time-optimal [`Move`] and arrives
/// late. A single move given as two waypoints whose times leave enough
/// room is exactly a [`Move`] with a lower speed limit.
#[derive(Clone, Debug, PartialEq)]
pub struct Waypoints {
    start: f64,
    moves: Vec<Move>,
}

impl Waypoints {
    /// The reference through `points` (times strictly increasing, all
    /// finite) within `max_speed` (m/s) and `max_acceleration` (m/s²),
    /// both positive and finite. Refused otherwise, naming the point.
    pub fn new(points: &[(f64, f64)], max_speed: f64, max_acceleration: f64) -> Result<Self, CraneError> {
        let model = "waypoints";
        check_positive(model, "max_speed", max_speed)?;
        check_positive(model, "max_acceleration", max_acceleration)?;
        let Some(&(_, x_first)) = points.first() else {
            return Err(CraneError::InvalidParameter { model, field: "points", value: 0.0, requirement: "at least one point" });
        };
        let mut moves = Vec::new();
        let mut free_at = f64::NEG_INFINITY;
        let mut prev: Option<(f64, f64)> = None;
        for &(t, x) in points {
            if !(t.is_finite() && x.is_finite()) {
                return Err(CraneError::InvalidParameter { model, field: "point", value: if t.is_finite() { x } else { t }, requirement: "finite" });
            }
            if let Some((tp, xp)) = prev {
                if t <= tp {
                    return Err(CraneError::InvalidParameter { model, field: "time", value: t, requirement: "strictly increasing" });
                }
                let d = (x - xp).abs();
                if d > 0.0 {
                    let t0 = tp.max(free_at);
                    let fastest = Move { t0, start: xp, target: x, max_speed, max_acceleration };
                    let (a, time) = (max_acceleration, t - t0);
                    let disc = a * a * time * time - 4.0 * a * d;
                    let mv = if time > 0.0 && disc >= 0.0 && time >= fastest.duration() {
                        Move { max_speed: (2.0 * a * d / (a * time + disc.sqrt())).min(max_speed), ..fastest }
                    } else {
                        fastest
                    };
                    free_at = t0 + mv.duration();
                    moves.push(mv);
                }
            }
            prev = Some((t, x));
        }
        Ok(Waypoints { start: x_first, moves })
    }

    /// The moves between the waypoints, in time order.
    pub fn moves(&self) -> &[Move] {
        &self.moves
    }

    /// When the last move ends, s (−∞ without moves).
    pub fn end_time(&self) -> f64 {
        self.moves.last().map_or(f64::NEG_INFINITY, |m| m.t0 + m.duration())
    }

    /// The move under way (or last finished) at `t`.
    fn active(&self, t: f64) -> Option<&Move> {
        let i = self.moves.partition_point(|m| m.t0 <= t);
        i.checked_sub(1).map(|i| &self.moves[i])
    }
}

impl Reference for Waypoints {
    fn position(&self, t: f64) -> f64 {
        self.active(t).map_or(self.start, |m| m.position(t))
    }
    fn speed(&self, t: f64) -> f64 {
        self.active(t).map_or(0.0, |m| m.speed(t))
    }
}

/// The input shapers of the crane industry: a sequence of impulses whose
/// convolution with a command cancels the residual sway of a pendulum of
/// angular frequency `ω` and damping ratio `ζ` (Singer & Seering 1990).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShaperKind {
    /// Zero vibration: 2 impulses over half a damped period.
    Zv,
    /// Zero vibration and derivative: 3 impulses over a damped period,
    /// robust to a frequency error.
    Zvd,
}

/// An input shaper: impulse amplitudes (summing to 1) and times, s.
#[derive(Clone, Debug, PartialEq)]
pub struct InputShaper {
    /// `(time, amplitude)` of each impulse.
    pub impulses: Vec<(f64, f64)>,
}

impl InputShaper {
    /// The ZV or ZVD shaper for angular frequency `omega` (rad/s) and
    /// damping ratio `zeta` (0 ≤ ζ < 1): with `K = exp(−ζπ/√(1−ζ²))` and the
    /// damped half period `T/2 = π/(ω√(1−ζ²))`, ZV is `[1, K]/(1+K)` at
    /// `[0, T/2]` and ZVD `[1, 2K, K²]/(1+K)²` at `[0, T/2, T]`. Refused
    /// unless ω is positive and finite and 0 ≤ ζ < 1.
    pub fn new(kind: ShaperKind, omega: f64, zeta: f64) -> Result<Self, CraneError> {
        check_positive("input shaper", "omega", omega)?;
        if !(0.0..1.0).contains(&zeta) {
            return Err(CraneError::InvalidParameter { model: "input shaper", field: "zeta", value: zeta, requirement: "in [0, 1)" });
        }
        let root = (1.0 - zeta * zeta).sqrt();
        let k = (-zeta * std::f64::consts::PI / root).exp();
        let half = std::f64::consts::PI / (omega * root);
        let impulses = match kind {
            ShaperKind::Zv => vec![(0.0, 1.0 / (1.0 + k)), (half, k / (1.0 + k))],
            ShaperKind::Zvd => {
                let s = (1.0 + k) * (1.0 + k);
                vec![(0.0, 1.0 / s), (half, 2.0 * k / s), (2.0 * half, k * k / s)]
            }
        };
        Ok(InputShaper { impulses })
    }

    /// Total delay the shaper adds, s.
    pub fn duration(&self) -> f64 {
        self.impulses.last().map_or(0.0, |i| i.0)
    }
}

/// Open-loop anti-sway: a reference's speed profile (a [`Move`], or any
/// [`Reference`] such as [`Waypoints`]) convolved with an
/// [`InputShaper`], sent to a speed-controlled drive.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapedMove<R = Move> {
    /// The move.
    pub motion: R,
    /// The shaper.
    pub shaper: InputShaper,
}

impl<R: Reference> ShapedMove<R> {
    /// The shaped speed command at `t`, m/s.
    pub fn speed(&self, t: f64) -> f64 {
        self.shaper.impulses.iter().map(|&(ti, a)| a * self.motion.speed(t - ti)).sum()
    }
}

impl<R: Reference> TrolleyController for ShapedMove<R> {
    fn update(&mut self, m: &TrolleyMeasurement) -> TrolleyCommand {
        TrolleyCommand::Speed(self.speed(m.time))
    }
}

/// Input shaping of a command given live (an operator's joystick): each
/// sample's command is remembered, and the shaped command at `t` is
/// `Σ A_i u(t − t_i)` with `u` held between samples (zero before the
/// first). The history kept spans the shaper's duration.
#[derive(Clone, Debug, PartialEq)]
pub struct OnlineShaper {
    /// The shaper.
    pub shaper: InputShaper,
    history: std::collections::VecDeque<(f64, f64)>,
}

impl OnlineShaper {
    /// Shapes live commands with `shaper`.
    pub fn new(shaper: InputShaper) -> Self {
        OnlineShaper { shaper, history: std::collections::VecDeque::new() }
    }

    /// Records the command `u` given at time `t` (s, non-decreasing) and
    /// returns the shaped command at `t`.
    pub fn shape(&mut self, t: f64, u: f64) -> f64 {
        self.history.push_back((t, u));
        let span = self.shaper.duration();
        // Keep the newest sample at or before t − span (it holds there).
        while self.history.len() > 1 && self.history[1].0 <= t - span {
            self.history.pop_front();
        }
        self.shaper
            .impulses
            .iter()
            .map(|&(ti, a)| {
                let at = t - ti;
                // The latest command given at or before `at` (ZOH).
                let i = self.history.partition_point(|(ts, _)| *ts <= at + 1e-12);
                if i == 0 {
                    0.0
                } else {
                    a * self.history[i - 1].1
                }
            })
            .sum()
    }

    /// Forgets the commands given so far.
    pub fn reset(&mut self) {
        self.history.clear();
    }
}

/// Gains of one PID loop: proportional (per unit of error), integral (per
/// unit of error·s) and derivative (per unit of error/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PidGains {
    /// Proportional gain.
    pub kp: f64,
    /// Integral gain.
    pub ki: f64,
    /// Derivative gain.
    pub kd: f64,
}

/// The double closed-loop PID of seed 000: an outer loop on the trolley
/// position (error `e = x_ref − x`, with the reference following a
/// [`Move`]) and an inner loop on the sway angle, both acting on the drive
/// force, `F = PID_x(e) + PID_θ(θ)`, clamped to `±max_force` (N; the
/// integral stops growing while the output saturates). Derivatives use the
/// measured rates (no derivative kick). Position gains in N/m, N/(m·s),
/// N·s/m; sway gains in N/rad, N/(rad·s), N·s/rad.
#[derive(Clone, Debug, PartialEq)]
pub struct DoubleLoopPid<R = Move> {
    /// The reference move (a [`Move`], or any [`Reference`]).
    pub motion: R,
    /// Position loop gains.
    pub position: PidGains,
    /// Sway loop gains.
    pub sway: PidGains,
    /// Force limit, N.
    pub max_force: f64,
    /// Error-dependent gain schedule of the position loop (the nonlinear
    /// PID), or `None` for fixed gains.
    pub schedule: Option<NonlinearSchedule>,
    integral: (f64, f64),
    last_time: Option<f64>,
}

/// The nonlinear PID's error-dependent gains (seed 000: strong
/// proportional action on a large error, more integral action on a small
/// one): with the position error `e` (m),
/// `k_p(e) = kp (1 + p_gain (1 − sech(e/e_p)))`,
/// `k_i(e) = ki sech(e/e_i)`, `k_d(e) = kd (1 + d_gain (1 − sech(e/e_p)))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NonlinearSchedule {
    /// Extra proportional gain at large errors (dimensionless).
    pub p_gain: f64,
    /// Extra derivative gain at large errors (dimensionless).
    pub d_gain: f64,
    /// Error scale of the proportional and derivative schedule, m.
    pub e_p: f64,
    /// Error scale beyond which the integral fades, m.
    pub e_i: f64,
}

/// Checks a PID's gains and force limit.
fn check_controller(model: &'static str, position: &PidGains, sway: &PidGains, max_force: f64) -> Result<(), CraneError> {
    check_limit(model, "max_force", max_force)?;
    for (field, value) in [
        ("position kp", position.kp),
        ("position ki", position.ki),
        ("position kd", position.kd),
        ("sway kp", sway.kp),
        ("sway ki", sway.ki),
        ("sway kd", sway.kd),
    ] {
        if !value.is_finite() {
            return Err(CraneError::InvalidParameter { model, field, value, requirement: "finite" });
        }
    }
    Ok(())
}

fn sech(x: f64) -> f64 {
    1.0 / x.cosh()
}

impl<R: Reference> DoubleLoopPid<R> {
    /// A double-loop PID following `motion` with fixed gains. Refused
    /// unless `max_force` is positive (N; infinite is allowed) and every
    /// gain finite.
    pub fn new(motion: R, position: PidGains, sway: PidGains, max_force: f64) -> Result<Self, CraneError> {
        check_controller("double-loop PID", &position, &sway, max_force)?;
        Ok(DoubleLoopPid { motion, position, sway, max_force, schedule: None, integral: (0.0, 0.0), last_time: None })
    }

    /// The nonlinear PID: the same loops with the position gains scheduled
    /// on the error.
    pub fn nonlinear(mut self, schedule: NonlinearSchedule) -> Self {
        self.schedule = Some(schedule);
        self
    }

    fn gains(&self, e: f64) -> PidGains {
        match self.schedule {
            None => self.position,
            Some(s) => {
                let grow = 1.0 - sech(e / s.e_p);
                PidGains {
                    kp: self.position.kp * (1.0 + s.p_gain * grow),
                    ki: self.position.ki * sech(e / s.e_i),
                    kd: self.position.kd * (1.0 + s.d_gain * grow),
                }
            }
        }
    }
}

impl DoubleLoopPid {
    /// Gains that place the poles of the double-loop PD on the
    /// linearised crane ([`OverheadCrane::linearized`], no damping) at the
    /// two pairs `s² + 2ζ_k ω_k s + ω_k²` (ω in rad/s): with
    /// `M ẍ = F + m g θ`, `l θ̈ = −ẍ − g θ` and
    /// `F = −K_p x − K_d ẋ + K_θ θ + C_θ θ̇`, the closed loop is
    /// `M l s⁴ + (K_d l + C_θ) s³ + (K_p l + (M+m) g + K_θ) s² + K_d g s + K_p g`,
    /// matched term by term. Returns `(position, sway)` gains with no
    /// integral action (add a small `ki` for zero steady-state error).
    pub fn place_poles(crane: &OverheadCrane, poles: [(f64, f64); 2]) -> (PidGains, PidGains) {
        let (mm, m, l, g) = (crane.trolley_mass, crane.payload_mass, crane.rope_length, crane.gravity);
        let [(w1, z1), (w2, z2)] = poles;
        let ml = mm * l;
        let kp = ml * w1 * w1 * w2 * w2 / g;
        let kd = ml * (2.0 * z1 * w1 * w2 * w2 + 2.0 * z2 * w2 * w1 * w1) / g;
        let c_theta = ml * (2.0 * z1 * w1 + 2.0 * z2 * w2) - kd * l;
        let k_theta = ml * (w1 * w1 + w2 * w2 + 4.0 * z1 * z2 * w1 * w2) - kp * l - (mm + m) * g;
        (PidGains { kp, ki: 0.0, kd }, PidGains { kp: k_theta, ki: 0.0, kd: c_theta })
    }
}

impl<R: Reference> TrolleyController for DoubleLoopPid<R> {
    fn update(&mut self, m: &TrolleyMeasurement) -> TrolleyCommand {
        let dt = self.last_time.map_or(0.0, |t| (m.time - t).max(0.0));
        self.last_time = Some(m.time);
        let e = self.motion.position(m.time) - m.position;
        let de = self.motion.speed(m.time) - m.velocity;
        let g = self.gains(e);
        let unclamped = g.kp * e + g.ki * self.integral.0 + g.kd * de + self.sway.kp * m.sway + self.sway.ki * self.integral.1 + self.sway.kd * m.sway_rate;
        let f = limit(unclamped, self.max_force);
        // Conditional integration: no wind-up while saturated.
        if f == unclamped {
            self.integral.0 += e * dt;
            self.integral.1 += m.sway * dt;
        }
        TrolleyCommand::Force(f)
    }
}

/// The incremental (velocity-form) digital PID of seed 000 on both loops:
/// sampled every `sample_time` (s) and held in between,
/// `Δu(k) = Kp [e(k) − e(k−1)] + Ki T e(k) + (Kd/T) [e(k) − 2e(k−1) + e(k−2)]`
/// for the position error and the same for the sway angle, `u` summed and
/// clamped to `±max_force` (N) (the clamp of the accumulated output is the
/// velocity form's built-in anti-windup).
#[derive(Clone, Debug, PartialEq)]
pub struct IncrementalPid<R = Move> {
    /// The reference move (a [`Move`], or any [`Reference`]).
    pub motion: R,
    /// Position loop gains.
    pub position: PidGains,
    /// Sway loop gains.
    pub sway: PidGains,
    /// Sample time `T`, s.
    pub sample_time: f64,
    /// Force limit, N.
    pub max_force: f64,
    history: [(f64, f64); 2],
    output: f64,
    next_sample: Option<f64>,
}

impl<R: Reference> IncrementalPid<R> {
    /// An incremental PID sampled every `sample_time` (s). Refused unless
    /// the sample time is positive and finite, `max_force` positive (N) and
    /// every gain finite.
    pub fn new(motion: R, position: PidGains, sway: PidGains, sample_time: f64, max_force: f64) -> Result<Self, CraneError> {
        check_controller("incremental PID", &position, &sway, max_force)?;
        check_positive("incremental PID", "sample_time", sample_time)?;
        Ok(IncrementalPid { motion, position, sway, sample_time, max_force, history: [(0.0, 0.0); 2], output: 0.0, next_sample: None })
    }
}

impl<R: Reference> TrolleyController for IncrementalPid<R> {
    fn update(&mut self, m: &TrolleyMeasurement) -> TrolleyCommand {
        let due = self.next_sample.is_none_or(|t| m.time >= t - 1e-9 * self.sample_time);
        if due {
            let t = self.sample_time;
            // Errors: position `x_ref − x`; the sway loop acts on `θ` with
            // the double-loop PID's signs (its set point is 0).
            let e = (self.motion.position(m.time) - m.position, m.sway);
            let [e1, e2] = self.history;
            let inc = |g: &PidGains, e: f64, e1: f64, e2: f64| g.kp * (e - e1) + g.ki * t * e + g.kd / t * (e - 2.0 * e1 + e2);
            let du = inc(&self.position, e.0, e1.0, e2.0) + inc(&self.sway, e.1, e1.1, e2.1);
            self.output = limit(self.output + du, self.max_force);
            self.history = [e, e1];
            self.next_sample = Some(self.next_sample.map_or(m.time, |s| s) + t);
        }
        TrolleyCommand::Force(self.output)
    }
}

/// One sample of a closed-loop run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LoopSample {
    /// The measurement.
    pub measurement: TrolleyMeasurement,
    /// The drive force applied, N.
    pub force: f64,
}

/// A controller closing the loop on the reduced [`OverheadCrane`]: every
/// step `h` it reads the state, asks the controller, sets the drive (a
/// force, or a speed loop of `speed_gain` N·s/m limited to `max_force` N),
/// and steps the nonlinear model with the default integrator.
pub struct OverheadCraneLoop<C: TrolleyController> {
    /// The plant.
    pub system: LagrangeSystem<OverheadCrane>,
    /// Its state.
    pub state: State,
    /// The controller.
    pub controller: C,
    /// Speed-loop gain for speed commands, N·s/m.
    pub speed_gain: f64,
    /// Drive force limit, N.
    pub max_force: f64,
    integrator: Integrator,
}

impl<C: TrolleyController> OverheadCraneLoop<C> {
    /// The crane at rest at trolley position `x0` (m), hanging still.
    /// Refused unless `speed_gain` (N·s/m) and `max_force` (N) are
    /// positive.
    pub fn new(crane: OverheadCrane, controller: C, x0: f64, speed_gain: f64, max_force: f64) -> Result<Self, CraneError> {
        check_positive("overhead crane loop", "speed_gain", speed_gain)?;
        check_limit("overhead crane loop", "max_force", max_force)?;
        let mut system = crane.system();
        let state = State::new(&mut system, 0.0, vec![x0, 0.0], vec![0.0, 0.0])?;
        Ok(OverheadCraneLoop { system, state, controller, speed_gain, max_force, integrator: Integrator::default() })
    }

    /// The current measurement.
    pub fn measurement(&self) -> TrolleyMeasurement {
        let (q, v) = (&self.state.q, &self.state.v);
        TrolleyMeasurement { time: self.state.t, position: q[0], velocity: v[0], sway: q[1], sway_rate: v[1] }
    }

    /// Gives the payload a horizontal push of `impulse` N·s along the rail:
    /// the velocities jump by `Δq̇ = M(q)⁻¹ Jᵀ p`, `J` the payload's
    /// horizontal velocity `ẋ + l θ̇ cos θ` as a row (the trolley reacts
    /// through the rope), then the accelerations are recomputed.
    pub fn push_payload(&mut self, impulse: f64) -> Result<(), CraneError> {
        let l = self.system.model.rope_length;
        let m = self.system.mass_matrix(&self.state.q);
        let jt = [impulse, impulse * l * self.state.q[1].cos()];
        let det = m[0] * m[3] - m[1] * m[2];
        self.state.v[0] += (m[3] * jt[0] - m[1] * jt[1]) / det;
        self.state.v[1] += (m[0] * jt[1] - m[2] * jt[0]) / det;
        Ok(self.state.recompute_acceleration(&mut self.system)?)
    }

    /// One control sample and one step of `h` seconds.
    pub fn step(&mut self, h: f64) -> Result<LoopSample, CraneError> {
        let measurement = self.measurement();
        let drive = match self.controller.update(&measurement) {
            TrolleyCommand::Force(f) => TrolleyDrive::Force(limit(f, self.max_force)),
            TrolleyCommand::Speed(v) => TrolleyDrive::Speed { command: v, gain: self.speed_gain, max_force: self.max_force },
        };
        self.system.model.drive = drive;
        let force = drive.force(measurement.velocity);
        self.integrator.step(&mut self.system, &mut self.state, h)?;
        Ok(LoopSample { measurement, force })
    }
}

/// What a tower crane controller reads at a sample (the coordinates of
/// [`TowerCrane`](super::TowerCrane) and their rates).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TowerMeasurement {
    /// Time, s.
    pub time: f64,
    /// Slew angle `γ`, rad, and its rate, rad/s.
    pub slew: (f64, f64),
    /// Trolley radius `x`, m, and its rate, m/s.
    pub radius: (f64, f64),
    /// Sway `α` in the jib's plane (positive outward), rad, and its rate.
    pub radial_sway: (f64, f64),
    /// Sway `β` out of the jib's plane (positive toward growing `γ`), rad,
    /// and its rate.
    pub tangential_sway: (f64, f64),
}

/// Slew and trolley of a tower crane under feedback together: two
/// double-loop PIDs ([`DoubleLoopPid`]). About rest at radius `x₀` the
/// linearised tower crane (see [`TowerCrane`](super::TowerCrane)) splits
/// into two overhead cranes: along the jib, the trolley `M` with the
/// payload `m` on `l` and the radial sway `α`; across it, in arc length
/// `s = x₀ γ`, a "trolley" of `J/x₀² + M` with the tangential sway `β`,
/// driven by `F_t = T/x₀`. Each loop follows its own reference (the slew
/// in arc length, the radius in metres) and damps its own sway; the slew
/// loop's force becomes the torque `T = x₀ F_t`. The radial loop also takes
/// out the centripetal swing `x γ̇²` a slew gives, which shaping the slew
/// command cannot (docs/control.md).
#[derive(Clone, Debug, PartialEq)]
pub struct TowerCranePid {
    /// The slew loop, in arc length at the design radius (m, N).
    pub slew: DoubleLoopPid,
    /// The trolley loop (m, N).
    pub trolley: DoubleLoopPid,
    /// The design radius `x₀`, m.
    pub radius: f64,
}

impl TowerCranePid {
    /// The loops for a slew `slew` (a [`Move`] in radians, rad/s, rad/s²)
    /// and a trolley move `trolley` (m), at the design radius `radius`
    /// (m, positive), with the closed-loop poles of both linearised axes at
    /// `poles` (as [`DoubleLoopPid::place_poles`]; `ki` = `ki_ratio · kp`,
    /// 1/s), the slew torque limited to `max_torque` (N·m) and the trolley
    /// force to `max_force` (N).
    #[allow(clippy::too_many_arguments)]
    pub fn place_poles(
        crane: &super::TowerCrane,
        radius: f64,
        slew: Move,
        trolley: Move,
        poles: [(f64, f64); 2],
        ki_ratio: f64,
        max_torque: f64,
        max_force: f64,
    ) -> Result<Self, CraneError> {
        check_positive("tower crane PID", "radius", radius)?;
        let with_gravity = |mut c: OverheadCrane| {
            c.gravity = crane.gravity;
            c
        };
        let radial = with_gravity(OverheadCrane::new(crane.trolley_mass, crane.payload_mass, crane.rope_length)?);
        let across = with_gravity(OverheadCrane::new(crane.jib_inertia / (radius * radius) + crane.trolley_mass, crane.payload_mass, crane.rope_length)?);
        let gains = |c: &OverheadCrane| {
            let (mut p, s) = DoubleLoopPid::place_poles(c, poles);
            p.ki = ki_ratio * p.kp;
            (p, s)
        };
        let arc = Move {
            t0: slew.t0,
            start: radius * slew.start,
            target: radius * slew.target,
            max_speed: radius * slew.max_speed,
            max_acceleration: radius * slew.max_acceleration,
        };
        let (sp, ss) = gains(&across);
        let (tp, ts) = gains(&radial);
        Ok(TowerCranePid { slew: DoubleLoopPid::new(arc, sp, ss, max_torque / radius)?, trolley: DoubleLoopPid::new(trolley, tp, ts, max_force)?, radius })
    }

    /// `(slew torque N·m, trolley force N)` for the sample `m`.
    pub fn update(&mut self, m: &TowerMeasurement) -> (f64, f64) {
        let x0 = self.radius;
        let across =
            TrolleyMeasurement { time: m.time, position: x0 * m.slew.0, velocity: x0 * m.slew.1, sway: m.tangential_sway.0, sway_rate: m.tangential_sway.1 };
        let along = TrolleyMeasurement { time: m.time, position: m.radius.0, velocity: m.radius.1, sway: m.radial_sway.0, sway_rate: m.radial_sway.1 };
        let force = |c: TrolleyCommand| match c {
            TrolleyCommand::Force(f) | TrolleyCommand::Speed(f) => f,
        };
        (x0 * force(self.slew.update(&across)), force(self.trolley.update(&along)))
    }
}

/// A [`TowerCranePid`] closing the loop on the reduced
/// [`TowerCrane`](super::TowerCrane), sampled every step.
pub struct TowerCraneLoop {
    /// The plant.
    pub system: LagrangeSystem<super::TowerCrane>,
    /// Its state `[γ, x, α, β]`.
    pub state: State,
    /// The controller.
    pub controller: TowerCranePid,
    integrator: Integrator,
}

impl TowerCraneLoop {
    /// The crane at rest at slew angle `slew` (rad) and radius `radius`
    /// (m), hanging still.
    pub fn new(crane: super::TowerCrane, controller: TowerCranePid, slew: f64, radius: f64) -> Result<Self, CraneError> {
        // With a hoist, the rope starts at its length (the hoist's pull is
        // left as the crane has it).
        let mut q = vec![slew, radius, 0.0, 0.0];
        if crane.hoist.is_some() {
            q.push(crane.rope_length);
        }
        let n = q.len();
        let mut system = crane.system();
        let state = State::new(&mut system, 0.0, q, vec![0.0; n])?;
        Ok(TowerCraneLoop { system, state, controller, integrator: Integrator::default() })
    }

    /// The current measurement.
    pub fn measurement(&self) -> TowerMeasurement {
        let (q, v) = (&self.state.q, &self.state.v);
        TowerMeasurement { time: self.state.t, slew: (q[0], v[0]), radius: (q[1], v[1]), radial_sway: (q[2], v[2]), tangential_sway: (q[3], v[3]) }
    }

    /// One control sample and one step of `h` s; returns the commands.
    pub fn step(&mut self, h: f64) -> Result<(f64, f64), CraneError> {
        let m = self.measurement();
        let (torque, force) = self.controller.update(&m);
        self.system.model.slew_torque = torque;
        self.system.model.trolley_force = force;
        self.integrator.step(&mut self.system, &mut self.state, h)?;
        Ok((torque, force))
    }
}
