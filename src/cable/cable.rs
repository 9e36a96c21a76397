//! [`Cable`]: a rope model with its integrator state, stepped in time, with
//! the queries users read (node positions, tension, moments, energy).

use super::chain::{Chain, Forest, ForestPair, FreeBody, LinkLoad, SpringLaw, StaticError, IN_CHAIN};
use super::force::{AttachedForce, ForceElement, PointState, PointWrench};
use super::rope::{RopeLayout, RopeModel, ELEMENT_DOFS};
use super::spatial::V6;
use crate::integrate::{IntegrateError, Integrator, Scheme, State, StepStats};
use glam::{DMat3, DVec3};
use std::sync::Arc;
use thiserror::Error;

/// Where [`CableError::StartsInside`] found the rope inside a collider.
fn inside_where(node: usize, element: Option<usize>) -> String {
    match element {
        Some(e) => format!("element {e} (between nodes {e} and {}, nearer node {node})", e + 1),
        None => format!("node {node}"),
    }
}

/// Why a cable step failed.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
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
    /// The integrator did not converge on a rope without damping some of
    /// whose tension-only elements were slack at the failing step's start:
    /// the error, with the advice that usually lets such a run go on (an
    /// undamped rope that snaps taut rings at its element scale, and once
    /// it goes slack again that energy whips it; see `docs/architecture.md`,
    /// "Slack … Known failures").
    #[error(
        "{source}; the rope has no damping and was slack here: undamped, every snap taut rings on at the element scale and whips the slack rope. \
         A damping time τ of about 0.01 s (`RopeBuilder::damping`, `CableDescriptor::damping`, scenario `damping`) usually lets such a run go on"
    )]
    UndampedSlack {
        /// What the integrator reported.
        source: IntegrateError,
    },
    /// [`Cable::solve_static`] on a tension-only rope: the equilibrium on
    /// the taut branch needs an element to push, which a rope cannot.
    #[error("static equilibrium needs element {element} of rope {rope} to push with {compression:.4e} N: a rope cannot (use `tension_only(false)` for a rod or beam)")]
    Compressed {
        /// Rope of the chain ([`Cable::rope`]; 0 for a single rope).
        rope: usize,
        /// Element index from that rope's start, as its user described it.
        element: usize,
        /// The compressive force it would carry on the linear law, N (> 0).
        compression: f64,
    },
    /// [`Cable::set_link_velocities`]: a velocity the chain cannot take
    /// (e.g. a trolley moving across its rail), or a bad target.
    #[error("cannot give link {link} its velocity: {reason}")]
    Velocity {
        /// Sub-joint index of the link.
        link: usize,
        /// What is wrong.
        reason: String,
    },
    /// A rope laid into a collider: at the cable's first step, a node's
    /// surface, or an element's between its nodes (an element laid through
    /// a thin post or across an edge), starts deeper inside a fixed or
    /// kinematic collider than
    /// [`STARTS_INSIDE`](crate::coupling::STARTS_INSIDE) times the rope's
    /// radius (a rope laid with its centre on a surface is). The contact
    /// law would throw the rope out with the energy of that depth (a rope
    /// laid with one end 5 cm into a slope was thrown 2.6 km up), or fail
    /// to solve the first step, so the cable is refused instead.
    #[error(
        "rope {rope}'s {} starts {depth:.4} m inside a collider, at ({:.4}, {:.4}, {:.4}) m: lay the rope with its centre at least its radius ({radius} m) from colliders' surfaces, or turn its contacts off",
        inside_where(*node, *element),
        point.x,
        point.y,
        point.z
    )]
    StartsInside {
        /// Rope of the chain ([`Cable::rope`]; 0 for a single rope).
        rope: usize,
        /// Node index from that rope's start (for an element's interior,
        /// the element's nearer node).
        node: usize,
        /// The element (index from the rope's start) whose interior lies
        /// inside the collider, if the deepest point is not a node.
        element: Option<usize>,
        /// The node's position, or the element's deepest point, world, m.
        point: DVec3,
        /// How deep its surface lies inside the collider's, m.
        depth: f64,
        /// The rope's radius, m.
        radius: f64,
    },
    /// [`Cable::set_gravity`] with a vector that is not finite.
    #[error("gravity ({}, {}, {}) m/s² is not finite", gravity.x, gravity.y, gravity.z)]
    Gravity {
        /// The vector refused, m/s².
        gravity: DVec3,
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

/// A velocity to give a link of the chain at the start of a run (see
/// [`Cable::set_link_velocities`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkVelocity {
    /// Sub-joint index whose link is meant (a body's
    /// [`BodyInChain::link`](super::rope::BodyInChain)).
    pub link: usize,
    /// Point in the link frame whose velocity is `linear`, m.
    pub point: DVec3,
    /// World velocity of that point, m/s.
    pub linear: DVec3,
    /// World angular velocity of the link, rad/s.
    pub angular: DVec3,
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
        let mut c = Cable { model, state, integrator: Integrator::new(scheme), last_stats: StepStats::default(), total_stats: StepStats::default(), steps: 0 };
        c.refresh();
        Ok(c)
    }

    /// Whether the chain has tension-only elements without damping, and
    /// one of them is slack in the current state.
    fn undamped_and_slack(&self) -> bool {
        let (q, v) = (&self.state.q, &self.state.v);
        self.model.chain.joints().iter().enumerate().any(|(s, j)| {
            j.law == super::chain::SpringLaw::TensionOnly && j.damping == 0.0 && q.get(s).zip(v.get(s)).is_some_and(|(q, v)| j.taut_measure(*q, *v) < 0.0)
        })
    }

    /// Advances the cable by `h` seconds. On error (Newton failure, a solve
    /// failure, or a state that left physical sense) the state and the time
    /// are left at the start of the step, so the results so far stay valid.
    /// A Newton failure on an undamped rope that was slack is
    /// [`CableError::UndampedSlack`], with the advice.
    pub fn step(&mut self, h: f64) -> Result<StepStats, CableError> {
        // The integrator restores the state itself when it fails; the sanity
        // check's rejection undoes the step through it as well.
        let stats = match self.integrator.step(&mut self.model.chain, &mut self.state, h) {
            Ok(stats) => stats,
            Err(e) => {
                self.refresh();
                if matches!(e, IntegrateError::NotConverged { .. }) && self.undamped_and_slack() {
                    return Err(CableError::UndampedSlack { source: e });
                }
                return Err(e.into());
            }
        };
        if let Err(e) = self.check_sanity() {
            self.integrator.undo_step(&mut self.state);
            self.refresh();
            return Err(e);
        }
        self.last_stats = stats;
        self.total_stats += stats;
        self.steps += 1;
        // Newton schemes last evaluated the residual at their converged
        // iterate (within the position tolerance of the final state), the
        // fast preset at its end state (its acceptance test): the chain's
        // kinematics are current. Other schemes last evaluated an
        // intermediate stage.
        let current = self.integrator.evaluated_at_end() && stats.substeps_used == 1;
        let recharted = self.rechart()?;
        if !current || recharted {
            self.refresh();
        }
        Ok(stats)
    }

    /// Advances several cables by `h` seconds as one system, coupled by
    /// `pairs` (pair elements between points of different cables, or of
    /// one: [`ForestPair`]'s `chain_a`/`chain_b` index `cables`): a rope of
    /// one cable touching a rope of another. Each cable keeps its own O(n)
    /// solve; the pairs' coupling is one loop correction over all of them
    /// ([`Forest`]). The cables must be at the same time (to round-off;
    /// they end at the first one's time plus `h`); the step uses
    /// the first cable's scheme and Newton settings. On error every cable
    /// is left at the start of the step (as [`Cable::step`] leaves one).
    /// With one cable and no pairs this is [`Cable::step`].
    pub fn step_together(cables: &mut [&mut Cable], pairs: Vec<ForestPair>, h: f64) -> Result<StepStats, CableError> {
        Cable::step_with_bodies(cables, &mut [], pairs, h)
    }

    /// [`Cable::step_together`] with free rigid bodies in the same system
    /// ([`FreeBody`]: a body touching the ropes, its inertia in their
    /// solve): `pairs` index the cables, then the bodies (chain
    /// `cables.len() + k` is body `k`). The bodies are stepped to the
    /// cables' time; on error they are left as they were.
    pub fn step_with_bodies(cables: &mut [&mut Cable], bodies: &mut [&mut FreeBody], pairs: Vec<ForestPair>, h: f64) -> Result<StepStats, CableError> {
        let Some(first) = cables.first() else {
            return Ok(StepStats::default());
        };
        if cables.len() == 1 && pairs.is_empty() && bodies.is_empty() {
            return cables[0].step(h);
        }
        let t = first.state.t;
        // (Cables stepped apart in different passes before may differ in
        // the last bits of their time.)
        if let Some(c) = cables.iter().find(|c| (c.state.t - t).abs() > 1e-9 * h.max(t.abs())) {
            return Err(CableError::Diverged { time: t, reason: format!("cables stepped together at different times ({t} s and {} s)", c.state.t) });
        }
        let mut integrator = Integrator::joint(&first.integrator, cables.iter().map(|c| &c.integrator));
        for b in bodies.iter_mut() {
            b.state.t = t;
        }
        let states: Vec<&State> = cables.iter().map(|c| &c.state).chain(bodies.iter().map(|b| &b.state)).collect();
        let join = |f: fn(&State) -> &Vec<f64>| states.iter().flat_map(|s| f(s).iter().copied()).collect::<Vec<f64>>();
        let mut state = State { t, q: join(|s| &s.q), v: join(|s| &s.v), a: join(|s| &s.a), a_hat: join(|s| &s.a_hat) };
        let saved: Vec<State> = cables.iter().map(|c| c.state.clone()).collect();
        let saved_bodies: Vec<State> = bodies.iter().map(|b| b.state.clone()).collect();
        // Each free body's coordinates in the joint state (after the
        // cables'), and whether it is new to the step.
        let mut at = cables.iter().map(|c| c.state.q.len()).sum::<usize>();
        let fresh: Vec<(usize, usize)> = bodies
            .iter()
            .filter_map(|b| {
                let n = b.state.q.len();
                at += n;
                (!b.settled).then_some((at - n, n))
            })
            .collect();
        let result = {
            let chains: Vec<&mut Chain> = cables.iter_mut().map(|c| &mut c.model.chain).chain(bodies.iter_mut().map(|b| &mut b.chain)).collect();
            Forest::new(chains, pairs).map_err(|source| CableError::Integrate(IntegrateError::System { t, source })).and_then(|mut forest| {
                if !fresh.is_empty() {
                    // A body new to the step starts from its acceleration
                    // with the ropes' pairs acting, not from the free fall
                    // `FreeBody::new` gives it: generalized-α's velocity
                    // update takes `(1 − γ) h` of the start acceleration
                    // (the first step's velocity was off by `h (γ − 1)`
                    // times the ropes' pull), and resting on a rope the
                    // free fall's predictor put it 20 µm into the rope at
                    // a 2 ms step, 10 times its weight's depth, at every
                    // contact pass's start.
                    let mut start = state.clone();
                    start.recompute_acceleration(&mut forest)?;
                    for &(at, n) in &fresh {
                        state.a[at..at + n].copy_from_slice(&start.a[at..at + n]);
                        state.a_hat[at..at + n].copy_from_slice(&start.a[at..at + n]);
                    }
                }
                integrator.step(&mut forest, &mut state, h).map_err(CableError::from)
            })
        };
        let restore = |cables: &mut [&mut Cable]| {
            for (c, s) in cables.iter_mut().zip(&saved) {
                c.state = s.clone();
                c.refresh();
            }
        };
        let stats = match result {
            Ok(stats) => stats,
            Err(e) => {
                restore(cables);
                return Err(e);
            }
        };
        let mut at = 0;
        let cable_states = cables.iter_mut().map(|c| &mut c.state);
        for st in cable_states.chain(bodies.iter_mut().map(|b| &mut b.state)) {
            let n = st.q.len();
            st.t = state.t;
            st.q.copy_from_slice(&state.q[at..at + n]);
            st.v.copy_from_slice(&state.v[at..at + n]);
            st.a.copy_from_slice(&state.a[at..at + n]);
            st.a_hat.copy_from_slice(&state.a_hat[at..at + n]);
            at += n;
        }
        if let Some(e) = cables.iter().find_map(|c| c.check_sanity().err()) {
            restore(cables);
            for (b, s) in bodies.iter_mut().zip(saved_bodies) {
                b.state = s;
                b.refresh();
            }
            return Err(e);
        }
        for c in cables.iter_mut() {
            c.integrator.take_split(&integrator);
            c.last_stats = stats;
            c.total_stats += stats;
            c.steps += 1;
            c.rechart()?;
            c.refresh();
        }
        for b in bodies.iter_mut() {
            b.settled = true;
            b.refresh();
        }
        Ok(stats)
    }

    /// Recomputes the acceleration from the equations of motion at the
    /// current state, loads and drives (the integrator's starting value).
    /// [`Cable::new`] does this with the loads the model has then: call it
    /// again after setting loads or drives before the first step, so that
    /// generalized-α does not start from an acceleration that misses them
    /// (which would lag the response by about half a step). The kinematics
    /// are refreshed.
    pub fn recompute_acceleration(&mut self) -> Result<(), CableError> {
        self.state.recompute_acceleration(&mut self.model.chain)?;
        self.refresh();
        Ok(())
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

    /// Re-charts the floating rotations of a free start (its first
    /// element) or of a floating start body
    /// ([`RopeStart::FloatingBody`](crate::cable::RopeStart::FloatingBody)),
    /// so their Euler angles never approach their singularity however the
    /// rope tumbles ([`Cable::rechart_rotations`]); answers whether the
    /// rope has such rotations (its readouts are then refreshed).
    fn rechart(&mut self) -> Result<bool, CableError> {
        let l = self.model.layout;
        if l.free_start {
            self.rechart_rotations(l.dof(0, 3))?;
        }
        if l.floating_start {
            self.rechart_rotations(crate::cable::rope::FLOATING_BODY_LINK - 2)?;
        }
        Ok(l.free_start || l.floating_start)
    }

    /// Once the middle of the three Euler angles at sub-joints `s0`,
    /// `s0 + 1`, `s0 + 2` (about z, y, x) passes 1 rad: folds them into the
    /// first one's constant frame rotation, maps their rates to the new,
    /// zero angles and recomputes a consistent acceleration.
    fn rechart_rotations(&mut self, s0: usize) -> Result<(), CableError> {
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
        if let Some(turned) = self.model.chain.joints().get(s0).map(|j| j.pre_rotation * r) {
            self.model.chain.set_pre_rotation_same_layout(s0, turned);
        }
        q[s0..s0 + 3].iter_mut().for_each(|x| *x = 0.0);
        let new = to_new(&self.state.v[s0..s0 + 3]);
        self.state.v[s0..s0 + 3].copy_from_slice(&new);
        self.state.recompute_acceleration(&mut self.model.chain)?;
        Ok(())
    }

    fn check_sanity(&self) -> Result<(), CableError> {
        if !self.state.is_finite() {
            return Err(CableError::Diverged { time: self.state.t, reason: "non-finite state".into() });
        }
        for (part, l) in std::iter::once(&self.model.layout).chain(self.model.parts.iter().map(|p| &p.layout)).enumerate() {
            self.check_strain(part, l)?;
        }
        Ok(())
    }

    fn check_strain(&self, part: usize, l: &RopeLayout) -> Result<(), CableError> {
        let which = if part == 0 { String::new() } else { format!("rope {part}, ") };
        for i in usize::from(l.free_start)..l.elements {
            let s = l.dof(i, 3);
            let gap = self.state.q[s];
            // A tension-only (slack) element may shorten (to its stop, or
            // past it within a step), but not turn inside out beyond its own length
            // (`gap < −2 L_e`): it would then be a stretched element that
            // its law (written for the slide's sign) takes as slack and lets
            // lengthen without force.
            let tension_only = self.model.chain.joints()[s].law == SpringLaw::TensionOnly;
            let least = if tension_only { -2.0 * l.element_length } else { -l.element_length };
            if gap > l.element_length || gap < least {
                let inverted = if tension_only && gap < least { ", turned inside out past its own length" } else { "" };
                return Err(CableError::Diverged {
                    time: self.state.t,
                    reason: format!("{which}element {i} strained by {:.1} %{inverted} (beyond any physical sense)", 100.0 * gap / l.element_length),
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
        self.main_rope().nodes()
    }

    /// World velocities of the `N + 1` nodes, m/s.
    pub fn node_velocities(&self) -> Vec<DVec3> {
        self.main_rope().node_velocities()
    }

    /// Position and velocity of the rope at arc length `s` (m, along the
    /// unstretched rope from the start), interpolated between nodes.
    pub fn point_at(&self, s: f64) -> (DVec3, DVec3) {
        self.main_rope().point_at(s)
    }

    /// Internal forces of element joint `i` (between element `i − 1` and
    /// `i`; joint 0 holds the start), see [`RopeModel::element_forces`].
    /// `None` past the last element (`i ≥ N`).
    pub fn element_forces(&self, i: usize) -> Option<ElementForces> {
        self.model.element_forces(i, &self.state.q, &self.state.v)
    }

    /// Axial tension (N) at arc length `s` (m): the force of the element
    /// joint nearest to `s`.
    pub fn tension_at(&self, s: f64) -> f64 {
        self.main_rope().tension_at(s)
    }

    /// Current stretched length (polyline through the nodes), m.
    pub fn stretched_length(&self) -> f64 {
        self.main_rope().stretched_length()
    }

    /// The ropes of this cable's chain: 1 plus the ropes grafted onto its
    /// bodies ([`RopeModel::graft`], a sling's further legs).
    pub fn ropes(&self) -> usize {
        1 + self.model.parts.len()
    }

    /// Rope `part` of the chain (0: the cable's own rope; `k ≥ 1`: the
    /// grafted rope `model.parts[k − 1]`), or `None` if there is no such part.
    pub fn rope(&self, part: usize) -> Option<RopeView<'_>> {
        if part == 0 {
            return Some(self.main_rope());
        }
        let p = self.model.parts.get(part - 1)?;
        Some(RopeView { cable: self, layout: p.layout, reversed: p.reversed, length: p.length })
    }

    fn main_rope(&self) -> RopeView<'_> {
        RopeView { cable: self, layout: self.model.layout, reversed: false, length: self.model.length }
    }

    /// Kinetic energy of the rope and its lumped bodies, J.
    pub fn kinetic_energy(&self) -> f64 {
        self.model.chain.kinetic_energy()
    }

    /// Elastic energy (joint springs, end springs and the potential of the
    /// force elements, [`ForceElement::energy`]), J.
    pub fn elastic_energy(&self) -> f64 {
        let ch = &self.model.chain;
        ch.elastic_energy(&self.state.q) + ch.force_element_energy(self.state.t)
    }

    /// Gravity acting on the rope and on the bodies its chain carries,
    /// m/s² (world).
    pub fn gravity(&self) -> DVec3 {
        self.model.chain.gravity
    }

    /// Changes gravity, m/s² (world), from the next step on: the rope's
    /// weight, its carried bodies' (each times its gravity scale), the
    /// bodies its contacts make free bodies of an island with it, and the
    /// gravitational energy. The state is kept: the change is a step in the
    /// load, as a force applied at once. A vector that is not finite is
    /// refused ([`CableError::Gravity`]) and changes nothing.
    pub fn set_gravity(&mut self, gravity: DVec3) -> Result<(), CableError> {
        if !gravity.is_finite() {
            return Err(CableError::Gravity { gravity });
        }
        self.model.chain.gravity = gravity;
        Ok(())
    }

    /// Gravitational potential energy (zero at y = 0 for gravity along −y), J.
    pub fn gravity_energy(&self) -> f64 {
        self.model.chain.gravity_energy()
    }

    /// Total mechanical energy: kinetic + gravitational + elastic, J.
    pub fn energy(&self) -> f64 {
        self.kinetic_energy() + self.gravity_energy() + self.elastic_energy()
    }

    /// Adds an implicit force element ([`ForceElement`]) at arc length `s`
    /// (m, along the unstretched rope from its start as its user described
    /// it, clamped to `[0, length]`) of rope `rope` ([`Cable::rope`]; 0 is
    /// the first). Unlike a load, it is evaluated at every Newton iteration
    /// with its stiffness and damping tangents, so a stiff spring or a strong
    /// damper stays stable at the frame step. It stays until
    /// [`Cable::clear_force_elements`]. Returns `false` (and adds nothing)
    /// when there is no such rope.
    #[must_use]
    pub fn add_force_element(&mut self, rope: usize, s: f64, element: Arc<dyn ForceElement>) -> bool {
        let Some((link, local_point)) = self.rope_point(rope, s) else {
            return false;
        };
        self.model.chain.forces_mut().push(AttachedForce { link, local_point, element });
        true
    }

    /// Each force element's point (world state) and the wrench it applies
    /// there now, in the order they were added ([`Chain::forces`](super::chain::Chain::forces)): the
    /// contact force of a [`SphereContact`](super::SphereContact), the
    /// pull of a [`PointSpring`](super::PointSpring).
    pub fn force_element_wrenches(&self) -> Vec<(PointState, PointWrench)> {
        self.model.chain.force_element_wrenches(self.state.t)
    }

    /// Removes every force element added with [`Cable::add_force_element`]
    /// (the end springs stay).
    pub fn clear_force_elements(&mut self) {
        self.model.chain.forces_mut().clear();
    }

    /// The link and the point in its frame at arc length `s` (m) of rope
    /// `rope`, from that rope's start in its user's direction.
    pub(crate) fn rope_point(&self, rope: usize, s: f64) -> Option<(usize, DVec3)> {
        let view = self.rope(rope)?;
        let (l, reversed, length) = (*view.layout(), view.reversed(), view.length());
        let (mut i, mut f) = locate(&l, if reversed { length - s } else { s });
        // An element's link carries its slides at its start: its local
        // (L_e, 0, 0) is the next node exactly, its origin is the node
        // moved by the element's stretch and shear. A point at a node goes
        // on the element that ends there.
        if f == 0.0 && i > 0 {
            (i, f) = (i - 1, 1.0);
        }
        Some((l.element_link(i), DVec3::new(f * l.element_length, 0.0, 0.0)))
    }

    /// Removes every external load (point and distributed). Force elements
    /// stay ([`Cable::clear_force_elements`]).
    pub fn clear_loads(&mut self) {
        self.model.chain.loads_mut().clear();
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
        let added = self.add_rope_point_load(0, s, force, moment);
        debug_assert!(added, "rope 0 exists");
    }

    /// [`Cable::add_point_load_and_moment`] on rope `rope` of the chain
    /// ([`Cable::rope`]), at arc length `s` (m) from that rope's start as
    /// its user described it. Returns `false` (and adds nothing) when there
    /// is no such rope.
    #[must_use]
    pub fn add_rope_point_load(&mut self, rope: usize, s: f64, force: DVec3, moment: DVec3) -> bool {
        let Some((link, local_point)) = self.rope_point(rope, s) else {
            return false;
        };
        self.model.chain.loads_mut().push(LinkLoad { link, force, local_point, moment });
        true
    }

    /// The rope and element (from that rope's start, in its user's
    /// direction) whose sub-joints include `joint`.
    fn element_of_joint(&self, joint: usize) -> Option<(usize, usize)> {
        (0..=self.model.parts.len()).find_map(|rope| {
            let view = self.rope(rope)?;
            let l = view.layout();
            let n = l.elements;
            let i = joint.checked_sub(l.first)? / ELEMENT_DOFS;
            (i < n).then(|| (rope, if view.reversed() { n - 1 - i } else { i }))
        })
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
        let steps = if self.model.chain.loads().is_empty() { 1 } else { load_steps.max(1) };
        let full = self.model.chain.loads().to_vec();
        let t = self.state.t;
        let mut q = self.state.q.clone();
        let mut iterations = 0;
        for step in 1..=steps {
            let f = step as f64 / steps as f64;
            for (ld, full) in self.model.chain.loads_mut().iter_mut().zip(&full) {
                ld.force = full.force * f;
                ld.moment = full.moment * f;
            }
            match self.model.chain.solve_static(t, &mut q, tol, max_iterations) {
                Ok(it) => iterations += it,
                Err(source) => {
                    *self.model.chain.loads_mut() = full;
                    self.refresh();
                    if let StaticError::Compressed { joint, force } = source {
                        if let Some((rope, element)) = self.element_of_joint(joint) {
                            return Err(CableError::Compressed { rope, element, compression: -force });
                        }
                    }
                    return Err(CableError::Static { step, steps, source });
                }
            }
        }
        *self.model.chain.loads_mut() = full;
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

    /// Gives links of the chain (the bodies it carries) the velocities in
    /// `targets`, by setting the joint rates; positions are unchanged, the
    /// acceleration is recomputed. Meant for the start of a run (a payload
    /// already swinging, a trolley already moving).
    ///
    /// The rates chosen are those that give the targets with the least
    /// stiffness energy rate: the minimum of `½ vᵀ (K_t + M/c) v` (tangent
    /// stiffness with the tension's geometric part, mass weighted by `1/c`,
    /// c = 1e6 s², so the mass only decides among motions that cost no
    /// stiffness energy) under the target
    /// constraints `J v = V`: the rope moves in the shape the bodies'
    /// impulse would deflect it into statically (a hanging payload given a
    /// swing velocity swings with the rope in its deflection shape, slope
    /// ∝ 1/tension), not with a kink at the body as the least-kinetic-energy
    /// (impulsive) rates would give. Free directions (a rope that can turn
    /// about its pin without straining) cost nothing in `K_t` and are
    /// decided by the mass term. Solved with the O(n)
    /// articulated-body solve of `M + c K_t`, six right-hand sides per
    /// target, and a symmetric 6k×6k system (pseudo-inverse: directions
    /// the chain cannot move in are left out). A target the chain cannot
    /// reach (more than 1e-6 of the largest velocity given, or 1e-9 m/s)
    /// is an error and leaves the state as it was. Velocities of links not
    /// listed are free: list every body whose velocity matters, at zero if
    /// it starts at rest.
    pub fn set_link_velocities(&mut self, targets: &[LinkVelocity]) -> Result<(), CableError> {
        let n = self.state.q.len();
        for tg in targets {
            let bad = |reason: &str| Err(CableError::Velocity { link: tg.link, reason: reason.into() });
            if tg.link >= n {
                return bad(&format!("the chain has {n} links"));
            }
            if !(tg.point.is_finite() && tg.linear.is_finite() && tg.angular.is_finite()) {
                return bad("non-finite point or velocity");
            }
        }
        if targets.is_empty() {
            return Ok(());
        }
        const C: f64 = 1e6;
        let t = self.state.t;
        let q = self.state.q.clone();
        let zero = vec![0.0; n];
        let mut r = vec![0.0; n];
        let system = |source| CableError::Integrate(IntegrateError::System { t, source });
        let ch = &mut self.model.chain;
        // Link velocities with all rates zero: what the base alone gives.
        ch.residual_into(t, &q, &zero, &zero, &mut r).map_err(system)?;
        let m = 6 * targets.len();
        // Velocities and forces at each target's own point (angular, then
        // linear): about the chain origin, a body 10 m away from it has its
        // swing compliance (about 1e-10 m/(N s²) here) hidden under its
        // rotation's lever arm (|p|²/I, about 4), and the pseudo-inverse
        // below dropped it (a hook block and its payload got 4 % of the
        // swing asked).
        let points: Vec<DVec3> = targets.iter().map(|tg| ch.link_point(tg.link, tg.point).expect(IN_CHAIN) - ch.origin).collect();
        let at_point = |x: V6, p: DVec3| {
            [
                x.top.x,
                x.top.y,
                x.top.z,
                x.bot.x + x.top.y * p.z - x.top.z * p.y,
                x.bot.y + x.top.z * p.x - x.top.x * p.z,
                x.bot.z + x.top.x * p.y - x.top.y * p.x,
            ]
        };
        let mut want = Vec::with_capacity(m);
        for (tg, p) in targets.iter().zip(&points) {
            let now = at_point(ch.link_velocity(tg.link).expect(IN_CHAIN), *p);
            want.extend([tg.angular.x, tg.angular.y, tg.angular.z, tg.linear.x, tg.linear.y, tg.linear.z].iter().zip(now).map(|(t, v)| t - v));
        }
        // Responses u = (M + c K_t)⁻¹ Jᵀ e to a unit moment or a unit force
        // at each target's point (generalized force S_s·e, e the wrench
        // about the origin, on every sub-joint inboard).
        let link_velocity =
            |ch: &super::chain::Chain, x: &[f64], link: usize| ch.rows[..=link].iter().zip(x).fold(V6::ZERO, |acc, (row, xs)| acc + row.s * *xs);
        let mut responses = vec![vec![0.0; n]; m];
        let mut rhs = vec![0.0; n];
        for (i, (tg, p)) in targets.iter().zip(&points).enumerate() {
            for k in 0..6 {
                let e = if k < 3 { V6::new(DVec3::AXES[k], DVec3::ZERO) } else { V6::new(p.cross(DVec3::AXES[k - 3]), DVec3::AXES[k - 3]) };
                for (s, b) in rhs.iter_mut().enumerate() {
                    *b = if s <= tg.link { ch.rows[s].s.dot(e) } else { 0.0 };
                }
                ch.solve_into(0.0, C, &rhs, &mut responses[6 * i + k]).map_err(system)?;
            }
        }
        let mut a = vec![0.0; m * m];
        for (i, (tg, p)) in targets.iter().zip(&points).enumerate() {
            for (b, u) in responses.iter().enumerate() {
                for (k, x) in at_point(link_velocity(ch, u, tg.link), *p).iter().enumerate() {
                    a[(6 * i + k) * m + b] = *x;
                }
            }
        }
        // Solved, then refined twice on what the rates actually give: the
        // stiff directions (a taut rope stretching as a body moves off)
        // have eigenvalues near the cut, where one solve is good to about
        // 1e-6 only (a car starting at 3 cm/s on a taut tow line missed
        // by 1.1e-6 of its speed and was refused).
        let mut v = vec![0.0; n];
        let mut rest = want.clone();
        for _ in 0..3 {
            let lambda = symmetric_pseudo_solve(&a, &rest, m);
            for (u, l) in responses.iter().zip(&lambda) {
                v.iter_mut().zip(u).for_each(|(vs, us)| *vs += l * us);
            }
            for (i, (tg, p)) in targets.iter().zip(&points).enumerate() {
                let got = at_point(link_velocity(ch, &v, tg.link), *p);
                for k in 0..6 {
                    rest[6 * i + k] = want[6 * i + k] - got[k];
                }
            }
        }
        // Did every target get its velocity? (`rest`: what the last
        // refinement left.)
        let scale = want.iter().fold(0.0f64, |acc, x| acc.max(x.abs()));
        for (i, tg) in targets.iter().enumerate() {
            let miss = rest[6 * i..6 * i + 6].iter().fold(0.0f64, |acc, x| acc.max(x.abs()));
            if miss > 1e-6 * scale + 1e-9 {
                ch.residual_into(t, &q, &self.state.v, &self.state.a, &mut r).map_err(system)?;
                return Err(CableError::Velocity {
                    link: tg.link,
                    reason: format!(
                        "{miss:.3e} (m/s or rad/s) of it is a motion the chain cannot make (a trolley moves along its rail only, \
                         a pinned end cannot move)"
                    ),
                });
            }
        }
        self.take_rates(v, false)
    }

    /// The chain's rates set to `v` and the acceleration recomputed there
    /// (on an error, the old rates put back and the acceleration
    /// recomputed at them). With
    /// `jump`, `v` is a jump in the rates within the run (an impulse): the
    /// integrator's history (generalized-α's `â`) goes on from before it
    /// and its predictor starts afresh ([`Cable::apply_impulse`]); without,
    /// `v` starts the run (initial velocities) from the consistent
    /// acceleration.
    fn take_rates(&mut self, v: Vec<f64>, jump: bool) -> Result<(), CableError> {
        let old_hat = jump.then(|| self.state.a_hat.clone());
        let old = std::mem::replace(&mut self.state.v, v);
        if let Err(e) = self.state.recompute_acceleration(&mut self.model.chain) {
            self.state.v = old;
            let _ = self.state.recompute_acceleration(&mut self.model.chain);
            self.refresh();
            return Err(e.into());
        }
        if let Some(old_hat) = old_hat {
            // The acceleration just recomputed holds the rope dampers'
            // answer to the jump (their relative rates, damped in
            // microseconds), which carried in â entered the next step's
            // velocity explicitly (`v₁ = v₀ + h (¼ â₀ + ¾ a₁)` at ρ∞ = 0):
            // a 500 N·s push on a 1 t payload hanging on 10 m of steel
            // rope damped at 0.01 s put 2.9 kJ into the rope's elements
            // next to it in that step, and a 5 N·s kick on an element in
            // its middle 6.5 kJ (`tests/impulse_on_damped_rope.rs`). The
            // implicit step answers the jump itself; Newton starts from
            // the recomputed acceleration, not from an extrapolation
            // across the jump.
            self.state.a_hat.copy_from_slice(&old_hat);
            self.integrator.forget_predictor();
        }
        self.refresh();
        Ok(())
    }

    /// Gives the chain an impulse `impulse` (N·s, world) at the point
    /// `point` of link `link` (link frame, m) and an angular impulse
    /// `angular` (N·m·s, world): its rates jump by
    /// `(M + h C + h² K)⁻¹ Jᵀ (L + r × P, P)` at once (the O(n)
    /// articulated-body solve of the implicit tangent), and the
    /// acceleration is recomputed at the new rates (the integrator's
    /// history, generalized-α's `â`, kept from before the jump, and its
    /// predictor started afresh: on a damped rope the recomputed
    /// acceleration holds the dampers' instant answer to the jump, which
    /// carried into the next step put kilojoules into the rope). `h` (s, ≥ 0) is the
    /// time over which the chain's springs and dampers answer the impulse:
    /// 0 for the mass matrix alone (the instant response), the step size
    /// for an impulse taken in a step (a loop closed by a stiff anchor
    /// spring, as a sling's, then does not give way at the anchor). What a
    /// body the chain carries receives from a collision or a user's
    /// impulse: spread as a force over the next step instead,
    /// generalized-α (ρ∞ = 0) brought the body to its new velocity over
    /// several steps, and a ball that had struck it met it again. A
    /// non-finite impulse or `h`, or an unknown link, is an error that
    /// changes nothing.
    pub fn apply_impulse(&mut self, link: usize, point: DVec3, impulse: DVec3, angular: DVec3, h: f64) -> Result<(), CableError> {
        let Some((_, dv)) = self.impulse_response(link, point, impulse, angular, h)? else {
            return Ok(());
        };
        let v = self.state.v.iter().zip(&dv).map(|(v, d)| v + d).collect();
        self.take_rates(v, true)
    }

    /// How fast the point `point` of link `link` (link frame, m) moves
    /// along the unit vector `direction` (world) per unit impulse along it,
    /// m/(N·s) = 1/kg: the jump [`Cable::apply_impulse`] would give it with
    /// the same `h` (s), `dᵀ J (M + h C + h² K)⁻¹ Jᵀ d`. The inverse of the
    /// mass a body striking that point meets: a payload's own `1/m` when
    /// the rope is slack, far less when taut ropes hold the point along
    /// `direction`. Nothing changes. A non-finite input, an unknown link or
    /// a zero direction is an error.
    pub fn point_mobility(&mut self, link: usize, point: DVec3, direction: DVec3, h: f64) -> Result<f64, CableError> {
        let d = direction.normalize_or_zero();
        if d == DVec3::ZERO {
            return Err(CableError::Velocity { link, reason: "zero or non-finite direction".into() });
        }
        let (rhs, dv) = self.impulse_response(link, point, d, DVec3::ZERO, h)?.expect("a non-zero impulse");
        // (The power of the unit impulse on the jump: `Jᵀ d` is `rhs`.)
        Ok(rhs.iter().zip(&dv).map(|(r, v)| r * v).sum())
    }

    /// The generalized impulse `Jᵀ (L + r × P, P)` of an impulse at a link
    /// point and the jump in the rates it gives over `h`
    /// ([`Cable::apply_impulse`]); `None` for a zero impulse.
    #[allow(clippy::type_complexity)]
    fn impulse_response(&mut self, link: usize, point: DVec3, impulse: DVec3, angular: DVec3, h: f64) -> Result<Option<(Vec<f64>, Vec<f64>)>, CableError> {
        let n = self.state.q.len();
        let bad = |reason: &str| Err(CableError::Velocity { link, reason: reason.into() });
        if link >= n {
            return bad(&format!("the chain has {n} links"));
        }
        if !(point.is_finite() && impulse.is_finite() && angular.is_finite() && h.is_finite() && h >= 0.0) {
            return bad("non-finite impulse or negative time");
        }
        if impulse == DVec3::ZERO && angular == DVec3::ZERO {
            return Ok(None);
        }
        let t = self.state.t;
        let system = |source| CableError::Integrate(IntegrateError::System { t, source });
        let ch = &mut self.model.chain;
        let mut r = vec![0.0; n];
        ch.residual_into(t, &self.state.q, &self.state.v, &self.state.a, &mut r).map_err(system)?;
        let p = ch.link_point(link, point).expect(IN_CHAIN) - ch.origin;
        let f = V6::new(angular + p.cross(impulse), impulse);
        // The generalized impulse: on every sub-joint from the link to the
        // base.
        let mut rhs = vec![0.0; n];
        let mut s = Some(link);
        while let Some(k) = s {
            rhs[k] = ch.rows[k].s.dot(f);
            s = ch.parent_of(k);
        }
        let mut dv = vec![0.0; n];
        ch.solve_into(h, h * h, &rhs, &mut dv).map_err(system)?;
        if !dv.iter().all(|x| x.is_finite()) {
            return bad("the impulse gives no finite rates");
        }
        Ok(Some((rhs, dv)))
    }

    /// Adds a distributed load: `load(element, midpoint, midpoint velocity)`
    /// returns the force per unit length (N/m, world frame) on that element,
    /// applied at its midpoint over its unstretched length.
    ///
    /// The closure is called **once, now**, with the current midpoints and
    /// velocities; the forces it returns are point loads like
    /// [`Cable::add_point_load`]'s (fixed direction, their moment-arm change
    /// implicit) and **stay, and add up, until [`Cable::clear_loads`]**. A
    /// load that depends on the rope's state (wind drag on the relative
    /// velocity, a current) must be cleared and added again before each
    /// step, so that it is explicit over one step; for a load whose state
    /// dependence is stiff (strong drag, a contact), use an implicit
    /// [`ForceElement`] ([`Cable::add_force_element`]).
    pub fn add_distributed_load(&mut self, mut load: impl FnMut(usize, DVec3, DVec3) -> DVec3) {
        let l = self.model.layout;
        let mid = DVec3::new(0.5 * l.element_length, 0.0, 0.0);
        for i in 0..l.elements {
            let link = l.element_link(i);
            let (p, v) = (self.model.chain.link_point(link, mid).expect(IN_CHAIN), self.model.chain.link_point_velocity(link, mid).expect(IN_CHAIN));
            let force = load(i, p, v) * l.element_length;
            self.model.chain.loads_mut().push(LinkLoad { link, force, local_point: mid, moment: DVec3::ZERO });
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

/// Element and fraction of arc length `s` (m) along a rope laid out as `l`.
fn locate(l: &RopeLayout, s: f64) -> (usize, f64) {
    let x = (s / l.element_length).clamp(0.0, l.elements as f64);
    let i = (x.floor() as usize).min(l.elements - 1);
    (i, x - i as f64)
}

/// One rope of a cable's chain, in the direction its user described it
/// ([`Cable::rope`]).
#[derive(Clone, Copy)]
pub struct RopeView<'a> {
    cable: &'a Cable,
    layout: RopeLayout,
    reversed: bool,
    length: f64,
}

impl RopeView<'_> {
    /// Number of elements.
    pub fn elements(&self) -> usize {
        self.layout.elements
    }

    /// Unstretched length, m.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// The chain's layout of this rope (element 0 is at the chain's side:
    /// for a reversed rope, at the user's end).
    pub fn layout(&self) -> &RopeLayout {
        &self.layout
    }

    /// Whether the user's start is the chain layout's far end.
    pub fn reversed(&self) -> bool {
        self.reversed
    }

    /// Chain-side nodes (element ends) in the layout's order.
    fn chain_nodes(&self, velocity: bool) -> Vec<DVec3> {
        let mut out = self.cable.model.nodes_in(&self.layout, velocity);
        if self.reversed {
            out.reverse();
        }
        out
    }

    /// World positions of the `N + 1` nodes from the user's start, m.
    pub fn nodes(&self) -> Vec<DVec3> {
        self.chain_nodes(false)
    }

    /// World velocities of the `N + 1` nodes from the user's start, m/s.
    pub fn node_velocities(&self) -> Vec<DVec3> {
        self.chain_nodes(true)
    }

    /// Position and velocity at arc length `s` (m, unstretched, from the
    /// user's start), interpolated between nodes.
    pub fn point_at(&self, s: f64) -> (DVec3, DVec3) {
        let (i, f) = locate(&self.layout, s);
        let (p, v) = (self.nodes(), self.node_velocities());
        (p[i].lerp(p[i + 1], f), v[i].lerp(v[i + 1], f))
    }

    /// Internal forces of the element joint `i` counted from the user's
    /// start (see [`RopeModel::element_forces`]). For a reversed rope the
    /// joint between user elements `i − 1` and `i` is the chain's joint of
    /// element `N − i`; at the user's joint 0 (the chain's tip) only the
    /// tension is given: the end spring's pull along the last element.
    /// `None` past the last element (`i ≥ N`).
    pub fn element_forces(&self, i: usize) -> Option<ElementForces> {
        let n = self.layout.elements;
        if i >= n {
            return None;
        }
        Some(self.element_forces_checked(i))
    }

    /// [`RopeView::element_forces`] for `i < N`.
    fn element_forces_checked(&self, i: usize) -> ElementForces {
        let n = self.layout.elements;
        let l = &self.layout;
        let (q, v) = (&self.cable.state.q, &self.cable.state.v);
        let m = &self.cable.model;
        if self.reversed && i == 0 {
            // The user's start is the chain's tip: the end spring's pull
            // along the last element there (zero for a free end).
            let ch = &m.chain;
            let link = l.element_link(n - 1);
            let tension = ch.anchors().iter().filter(|a| a.link == link).fold(0.0, |acc, a| {
                let p = ch.link_point(a.link, a.local_point).expect(IN_CHAIN);
                let pv = ch.link_point_velocity(a.link, a.local_point).expect(IN_CHAIN);
                let target = a.target.at(self.cable.state.t);
                let (target, target_v) = (target.position, target.velocity);
                let force = -(p - target) * a.stiffness - (pv - target_v) * a.damping;
                acc + force.dot(ch.link_rotation(link).expect(IN_CHAIN).x_axis)
            });
            return ElementForces { tension, ..Default::default() };
        }
        let k = if self.reversed { n - i } else { i };
        m.element_forces_in(l, k, q, v)
    }

    /// The chain's sub-joints (links) of this rope.
    fn links(&self) -> std::ops::Range<usize> {
        self.layout.dof(0, 0)..self.layout.dof(self.layout.elements, 0)
    }

    /// The sum of the normal forces of the contacts on this rope
    /// ([`ForceElement::contact_force`]: the [`SphereContact`](super::SphereContact)s
    /// among its force elements, and the [`PairContact`](super::PairContact)s
    /// with another rope of the cable or of another cable stepped with it,
    /// [`Cable::step_together`]) now, N. Its contacts with itself are
    /// internal and not counted.
    pub fn contact_force(&self) -> f64 {
        let ch = &self.cable.model.chain;
        let on_rope = |link: &usize| self.links().contains(link);
        let t = self.cable.state.t;
        let own = ch.forces().iter().zip(ch.force_element_points()).filter(|(f, _)| on_rope(&f.link)).filter_map(|(f, at)| f.element.contact_force(t, &at));
        // Contacts with another rope of the cable count; a rope's contacts
        // with itself are internal and do not.
        let other = ch
            .pairs()
            .iter()
            .zip(ch.pair_points())
            .filter(|(p, _)| on_rope(&p.link_a) != on_rope(&p.link_b))
            .filter_map(|(p, (a, b))| p.element.contact_force(t, &a, &b));
        // Contacts with another cable's ropes (a joint step's).
        let cables = ch.external_contacts().filter(|(l, _)| on_rope(l)).map(|(_, f)| f);
        own.sum::<f64>() + other.sum::<f64>() + cables.sum::<f64>()
    }

    /// Orientation (link frame to world) of each element's rigid segment,
    /// from the user's start: its local x runs along the element in the
    /// chain's direction (towards the user's start for a
    /// [`reversed`](RopeView::reversed) rope), y and z are its bending axes.
    pub fn element_frames(&self) -> Vec<DMat3> {
        let ch = &self.cable.model.chain;
        let mut out: Vec<DMat3> = (0..self.layout.elements).filter_map(|i| ch.link_rotation(self.layout.element_link(i))).collect();
        if self.reversed {
            out.reverse();
        }
        out
    }

    /// The contacts acting on this rope now, for drawing and inspection:
    /// each as the point on the rope where it acts (world, m) and the force
    /// it puts on the rope there (world, N: the normal force and the
    /// friction together). The contacts of [`RopeView::contact_force`], and
    /// also the rope's contacts with itself (both of their points). Order:
    /// the contacts with colliders, then with the cable's own ropes, then
    /// with other chains stepped with it (free bodies, other cables).
    pub fn contacts(&self) -> Vec<(DVec3, DVec3)> {
        let ch = &self.cable.model.chain;
        let on_rope = |link: usize| self.links().contains(&link);
        let t = self.cable.state.t;
        let mut out: Vec<(DVec3, DVec3)> = ch
            .forces()
            .iter()
            .zip(ch.force_element_points())
            .filter(|(f, at)| on_rope(f.link) && f.element.contact_force(t, at).is_some())
            .map(|(f, at)| {
                let w = f.element.wrench(t, &at);
                (at.point + w.arm, w.force)
            })
            .collect();
        for (p, (a, b)) in ch.pairs().iter().zip(ch.pair_points()) {
            if p.element.contact_force(t, &a, &b).is_none() {
                continue;
            }
            let force = p.element.wrench(t, &a, &b).force;
            if on_rope(p.link_a) {
                out.push((a.point, force));
            }
            if on_rope(p.link_b) {
                out.push((b.point, -force));
            }
        }
        out.extend(ch.external_contact_forces().filter(|(l, _, _)| on_rope(*l)).map(|(_, p, f)| (p + ch.origin, f)));
        out
    }

    /// Axial tension (N) at arc length `s` (m, from the user's start): the
    /// force of the element joint nearest to `s`.
    pub fn tension_at(&self, s: f64) -> f64 {
        let n = self.layout.elements;
        let (i, f) = locate(&self.layout, s);
        let i = if f > 0.5 { (i + 1).min(n - 1) } else { i };
        self.element_forces_checked(i).tension
    }

    /// Current stretched length (polyline through the nodes), m.
    pub fn stretched_length(&self) -> f64 {
        self.nodes().windows(2).map(|w| w[0].distance(w[1])).sum()
    }
}

/// Solves the symmetric positive semi-definite system `a x = b` (`m × m`,
/// row-major) in the least-squares sense: cyclic Jacobi eigen-decomposition,
/// eigenvalues below 1e-12 of the largest left out.
fn symmetric_pseudo_solve(a: &[f64], b: &[f64], m: usize) -> Vec<f64> {
    // Symmetrize (round-off of the two products).
    let mut d: Vec<f64> = (0..m * m).map(|k| 0.5 * (a[k] + a[(k % m) * m + k / m])).collect();
    let mut vecs: Vec<f64> = (0..m * m).map(|k| if k / m == k % m { 1.0 } else { 0.0 }).collect();
    for _sweep in 0..60 {
        let off: f64 = (0..m * m).filter(|k| k / m != k % m).map(|k| d[k] * d[k]).sum();
        let diag: f64 = (0..m).map(|i| d[i * m + i] * d[i * m + i]).sum();
        if off <= 1e-30 * diag || off == 0.0 {
            break;
        }
        for p in 0..m {
            for q in p + 1..m {
                let apq = d[p * m + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (d[q * m + q] - d[p * m + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..m {
                    let (dkp, dkq) = (d[k * m + p], d[k * m + q]);
                    d[k * m + p] = c * dkp - s * dkq;
                    d[k * m + q] = s * dkp + c * dkq;
                }
                for k in 0..m {
                    let (dpk, dqk) = (d[p * m + k], d[q * m + k]);
                    d[p * m + k] = c * dpk - s * dqk;
                    d[q * m + k] = s * dpk + c * dqk;
                }
                for k in 0..m {
                    let (vkp, vkq) = (vecs[k * m + p], vecs[k * m + q]);
                    vecs[k * m + p] = c * vkp - s * vkq;
                    vecs[k * m + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    let largest = (0..m).fold(0.0f64, |acc, i| acc.max(d[i * m + i].abs()));
    let mut x = vec![0.0; m];
    for j in 0..m {
        let lam = d[j * m + j];
        if lam.abs() <= 1e-12 * largest || lam == 0.0 {
            continue;
        }
        let proj: f64 = (0..m).map(|k| vecs[k * m + j] * b[k]).sum::<f64>() / lam;
        for k in 0..m {
            x[k] += proj * vecs[k * m + j];
        }
    }
    x
}
