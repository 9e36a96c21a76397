//! [`Cable`]: a rope model with its integrator state, stepped in time, with
//! the queries users read (node positions, tension, moments, energy).

use super::chain::{LinkLoad, StaticError};
use super::rope::{RopeModel, ELEMENT_DOFS};
use crate::integrate::{IntegrateError, Integrator, Scheme, State, StepStats};
use glam::{DMat3, DVec3};
use thiserror::Error;

/// Why a cable step failed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CableError {
    /// The integrator failed (Newton, solve, explicit step limit).
    #[error(transparent)]
    Integrate(#[from] IntegrateError),
    /// No static equilibrium was found ([`Cable::solve_static`]).
    #[error("static equilibrium not found at load step {step} of {steps}: {source}")]
    Static {
        /// Load step that failed (1-based).
        step: usize,
        /// Number of load steps.
        steps: usize,
        /// What the static solver reported.
        source: StaticError,
    },
    /// The state left physical sense (non-finite, or an element stretched
    /// or compressed by more than its length).
    #[error("cable diverged at t = {time} s: {reason}")]
    Diverged {
        /// Simulation time, s.
        time: f64,
        /// What went wrong.
        reason: String,
    },
}

/// A rope stepped in time.
#[derive(Debug)]
pub struct Cable {
    /// The rope model (chain, layout, section).
    pub model: RopeModel,
    /// Integrator state `(t, q, v, a, â)`.
    pub state: State,
    /// The time integrator.
    pub integrator: Integrator,
    /// Work done by the last step.
    pub last_stats: StepStats,
    /// Work done by all steps so far.
    pub total_stats: StepStats,
    /// Steps taken.
    pub steps: u64,
}

/// Internal forces of one element joint, in the element frame (x = axis).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ElementForces {
    /// Axial force (tension positive), N.
    pub tension: f64,
    /// Shear forces along local y and z, N.
    pub shear: [f64; 2],
    /// Bending moments about local z and y, N·m.
    pub bending: [f64; 2],
    /// Torsion moment, N·m.
    pub torsion: f64,
}

impl Cable {
    /// Starts a cable at rest in its built configuration at time 0.
    pub fn new(model: RopeModel, scheme: Scheme) -> Result<Self, CableError> {
        let mut model = model;
        let n = model.q0.len();
        if scheme.is_explicit() {
            // Explicit schemes size their sub-steps from the highest
            // frequency: measure it (power iteration on M⁻¹K, +20 %), and keep
            // the builder's analytic bound (which covers tension growth).
            let measured = model.chain.estimate_max_frequency(0.0, &model.q0, 60).map_err(|source| IntegrateError::System { t: 0.0, source })?;
            let analytic = model.chain.max_frequency.unwrap_or(0.0);
            model.chain.max_frequency = Some((1.2 * measured).max(analytic));
        }
        let state = State::new(&mut model.chain, 0.0, model.q0.clone(), vec![0.0; n])?;
        let mut c = Cable {
            model,
            state,
            integrator: Integrator::new(scheme),
            last_stats: StepStats::default(),
            total_stats: StepStats::default(),
            steps: 0,
        };
        c.refresh();
        Ok(c)
    }

    /// Advances the cable by `h` seconds. On error the state is left at the
    /// start of the step.
    pub fn step(&mut self, h: f64) -> Result<StepStats, CableError> {
        let stats = self.integrator.step(&mut self.model.chain, &mut self.state, h)?;
        self.last_stats = stats;
        self.total_stats += stats;
        self.steps += 1;
        // Newton schemes last evaluated the residual at their converged
        // iterate (within the position tolerance of the final state): the
        // chain's kinematics are current. Other schemes last evaluated an
        // intermediate stage.
        let newton_converged = matches!(
            self.integrator.scheme,
            Scheme::GeneralizedAlpha { .. } | Scheme::Hht { .. } | Scheme::Newmark { .. } | Scheme::LinearAcceleration
        ) && stats.substeps_used == 1;
        if self.model.layout.free_start {
            self.rechart_free_start()?;
        }
        if !newton_converged || self.model.layout.free_start {
            self.refresh();
        }
        self.check_sanity()?;
        Ok(stats)
    }

    /// Re-evaluates kinematics and loads at the current state (queries read
    /// them). Called by [`Cable::step`].
    pub fn refresh(&mut self) {
        let n = self.state.q.len();
        let mut r = vec![0.0; n];
        let s = &self.state;
        // A failure here means a non-finite state, caught by check_sanity.
        let _ = self.model.chain.residual_into(s.t, &s.q, &s.v, &s.a, &mut r);
    }

    /// Re-charts the floating first element when its middle Euler angle
    /// passes 1 rad: folds its three rotation angles into the constant frame
    /// rotation, maps their rates to the new, zero angles and recomputes a
    /// consistent acceleration, so the angles never approach their
    /// singularity however the rope tumbles.
    fn rechart_free_start(&mut self) -> Result<(), CableError> {
        let l = self.model.layout;
        let s0 = l.dof(0, 3);
        if self.state.q[s0 + 1].abs() < 1.0 {
            return Ok(());
        }
        let q = &mut self.state.q;
        let (a, b, c) = (q[s0], q[s0 + 1], q[s0 + 2]);
        let rz = DMat3::from_rotation_z(a);
        let rzy = rz * DMat3::from_rotation_y(b);
        let r = rzy * DMat3::from_rotation_x(c);
        // Relative angular velocity (and acceleration, to first order) in the
        // old joint frame, then its components on the new frame's z, y, x.
        let to_new = |x: &[f64]| {
            let w = DVec3::Z * x[0] + rz * DVec3::Y * x[1] + rzy * DVec3::X * x[2];
            let w_new = r.transpose() * w;
            [w_new.z, w_new.y, w_new.x]
        };
        let joints = &mut self.model.chain.joints;
        joints[s0].pre_rotation *= r;
        q[s0..s0 + 3].iter_mut().for_each(|x| *x = 0.0);
        let new = to_new(&self.state.v[s0..s0 + 3]);
        self.state.v[s0..s0 + 3].copy_from_slice(&new);
        self.state.recompute_acceleration(&mut self.model.chain)?;
        Ok(())
    }

    fn check_sanity(&self) -> Result<(), CableError> {
        let l = &self.model.layout;
        if !self.state.is_finite() {
            return Err(CableError::Diverged { time: self.state.t, reason: "non-finite state".into() });
        }
        for i in usize::from(l.free_start)..l.elements {
            let gap = self.state.q[l.dof(i, 3)];
            if gap.abs() > l.element_length {
                return Err(CableError::Diverged {
                    time: self.state.t,
                    reason: format!("element {i} strained by {:.1} % (beyond any physical sense)", 100.0 * gap / l.element_length),
                });
            }
        }
        Ok(())
    }

    /// Simulation time, s.
    pub fn time(&self) -> f64 {
        self.state.t
    }

    /// World positions of the `N + 1` nodes, m.
    pub fn nodes(&self) -> Vec<DVec3> {
        self.model.nodes()
    }

    /// World velocities of the `N + 1` nodes, m/s.
    pub fn node_velocities(&self) -> Vec<DVec3> {
        let l = &self.model.layout;
        let ch = &self.model.chain;
        let mut out: Vec<DVec3> = (0..l.elements)
            .map(|i| {
                ch.joint_point_velocity(l.dof(i, 0))
            })
            .collect();
        if l.free_start {
            out[0] = ch.link_point_velocity(l.element_link(0), DVec3::ZERO);
        }
        out.push(ch.link_point_velocity(l.element_link(l.elements - 1), DVec3::new(l.element_length, 0.0, 0.0)));
        out
    }

    /// Position and velocity of the rope at arc length `s` (m, along the
    /// unstretched rope from the start), interpolated between nodes.
    pub fn point_at(&self, s: f64) -> (DVec3, DVec3) {
        let (i, f) = self.locate(s);
        let (p, v) = (self.nodes(), self.node_velocities());
        (p[i].lerp(p[i + 1], f), v[i].lerp(v[i + 1], f))
    }

    fn locate(&self, s: f64) -> (usize, f64) {
        let l = &self.model.layout;
        let x = (s / l.element_length).clamp(0.0, l.elements as f64);
        let i = (x.floor() as usize).min(l.elements - 1);
        (i, x - i as f64)
    }

    /// Internal forces of element joint `i` (between element `i − 1` and
    /// `i`; joint 0 holds the start), see [`RopeModel::element_forces`].
    pub fn element_forces(&self, i: usize) -> ElementForces {
        self.model.element_forces(i, &self.state.q, &self.state.v)
    }

    /// Axial tension (N) at arc length `s` (m): the force of the element
    /// joint nearest to `s`.
    pub fn tension_at(&self, s: f64) -> f64 {
        let (i, f) = self.locate(s);
        let i = if f > 0.5 { (i + 1).min(self.model.layout.elements - 1) } else { i };
        self.element_forces(i).tension
    }

    /// Current stretched length (polyline through the nodes), m.
    pub fn stretched_length(&self) -> f64 {
        self.nodes().windows(2).map(|w| w[0].distance(w[1])).sum()
    }

    /// Kinetic energy of the rope and its lumped bodies, J.
    pub fn kinetic_energy(&self) -> f64 {
        self.model.chain.kinetic_energy()
    }

    /// Elastic energy (joint springs and end springs), J.
    pub fn elastic_energy(&self) -> f64 {
        let ch = &self.model.chain;
        let mut e = ch.elastic_energy(&self.state.q);
        for an in &ch.anchors {
            let p = ch.link_point(an.link, an.local_point);
            let (target, _) = (an.target)(self.state.t);
            e += 0.5 * an.stiffness * p.distance_squared(target);
        }
        e
    }

    /// Gravitational potential energy (zero at y = 0 for gravity along −y), J.
    pub fn gravity_energy(&self) -> f64 {
        self.model.chain.gravity_energy()
    }

    /// Total mechanical energy: kinetic + gravitational + elastic, J.
    pub fn energy(&self) -> f64 {
        self.kinetic_energy() + self.gravity_energy() + self.elastic_energy()
    }

    /// Removes every external load (point and distributed).
    pub fn clear_loads(&mut self) {
        self.model.chain.loads.clear();
    }

    /// Adds a point force (N, world frame) at arc length `s` (m, along the
    /// unstretched rope). Loads keep their direction over a step (their
    /// moment-arm change is in the implicit tangent) and stay until
    /// [`Cable::clear_loads`].
    pub fn add_point_load(&mut self, s: f64, force: DVec3) {
        self.add_point_load_and_moment(s, force, DVec3::ZERO);
    }

    /// Adds a point force (N) and a moment (N·m), both world frame and of
    /// fixed direction, at arc length `s` (m, along the unstretched rope,
    /// clamped to `[0, length]`). Like [`Cable::add_point_load`], they stay
    /// until [`Cable::clear_loads`].
    pub fn add_point_load_and_moment(&mut self, s: f64, force: DVec3, moment: DVec3) {
        let l = &self.model.layout;
        let (i, f) = self.locate(s);
        let link = l.element_link(i);
        self.model.chain.loads.push(LinkLoad { link, force, local_point: DVec3::new(f * l.element_length, 0.0, 0.0), moment });
    }

    /// Replaces the state by the static equilibrium at the current time:
    /// gravity, the current loads and the held ends (a moving base counts
    /// with its motion at this instant). Gravity acts from the start; the
    /// loads (point and distributed, as added) are applied in `load_steps`
    /// equal increments (at least 1; one solve without loads), each solved by
    /// [`Chain::solve_static`](super::chain::Chain::solve_static) from the
    /// previous one with the convergence tolerance `tol` (m or rad per
    /// coordinate) and at most `max_iterations` iterations. The cable then
    /// starts at rest (v = 0) there, with the consistent acceleration.
    /// Returns the iterations used in all. On failure the state and the
    /// loads are left as they were.
    pub fn solve_static(&mut self, load_steps: usize, tol: f64, max_iterations: usize) -> Result<usize, CableError> {
        let steps = if self.model.chain.loads.is_empty() { 1 } else { load_steps.max(1) };
        let full = self.model.chain.loads.clone();
        let t = self.state.t;
        let mut q = self.state.q.clone();
        let mut iterations = 0;
        for step in 1..=steps {
            let f = step as f64 / steps as f64;
            for (ld, full) in self.model.chain.loads.iter_mut().zip(&full) {
                ld.force = full.force * f;
                ld.moment = full.moment * f;
            }
            match self.model.chain.solve_static(t, &mut q, tol, max_iterations) {
                Ok(it) => iterations += it,
                Err(source) => {
                    self.model.chain.loads = full;
                    self.refresh();
                    return Err(CableError::Static { step, steps, source });
                }
            }
        }
        self.model.chain.loads = full;
        let old = std::mem::replace(&mut self.state.q, q);
        let old_v = std::mem::replace(&mut self.state.v, vec![0.0; old.len()]);
        let checked = match self.state.recompute_acceleration(&mut self.model.chain) {
            Ok(()) => self.check_sanity(),
            Err(e) => Err(e.into()),
        };
        if let Err(e) = checked {
            self.state.q = old;
            self.state.v = old_v;
            let _ = self.state.recompute_acceleration(&mut self.model.chain);
            self.refresh();
            return Err(e);
        }
        self.refresh();
        Ok(iterations)
    }

    /// Adds a distributed load: `load(element, midpoint, midpoint velocity)`
    /// returns the force per unit length (N/m, world frame) on that element,
    /// applied at its midpoint over its unstretched length (contact, wind and
    /// water use this).
    pub fn add_distributed_load(&mut self, mut load: impl FnMut(usize, DVec3, DVec3) -> DVec3) {
        let l = self.model.layout;
        let mid = DVec3::new(0.5 * l.element_length, 0.0, 0.0);
        for i in 0..l.elements {
            let link = l.element_link(i);
            let (p, v) = (self.model.chain.link_point(link, mid), self.model.chain.link_point_velocity(link, mid));
            let force = load(i, p, v) * l.element_length;
            self.model.chain.loads.push(LinkLoad { link, force, local_point: mid, moment: DVec3::ZERO });
        }
    }

    /// Number of elements.
    pub fn elements(&self) -> usize {
        self.model.layout.elements
    }

    /// Coordinates per element (6).
    pub const fn element_dofs() -> usize {
        ELEMENT_DOFS
    }
}
