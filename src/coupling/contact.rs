//! Ropes and carried bodies against rapier's colliders (issue 12): at the
//! start of each step, each node of a cable with contacts on (and each
//! element whose middle dips nearer to a collider than its nodes, a rope
//! over an edge), and each touch point of the bodies the chain carries,
//! is tested against the colliders near it; each collider within the
//! speculative margin gets a [`SphereContact`] there, on the tangent plane
//! at its nearest point, frozen for the step, which pushes only once the
//! rope or the body reaches it. Fixed and kinematic colliders only, for
//! now (see `add_contacts`).
//!
//! The nearest points come from parry's point projection (f32) in the
//! collider's own frame, with the face's own normal where there is one:
//! the rope's points are moved into that frame in f64 first, so a flat
//! face's plane comes out as the shape's own constant (a cuboid's half
//! extent, exact in f32) step after step, and a resting rope does not see
//! its ground jitter by the f32 rounding of world coordinates (1e-6 m at
//! 10 m, against Hertz depths of 1e-6 m). Measured and rejected: parry's
//! capsule–shape `contact` query (GJK/EPA for a capsule on a cuboid) gave
//! face normals tilted by up to 1.2e-3 rad and contact points anywhere
//! along an element lying flat, and the rope on the ground failed at its
//! first contact step.

use super::{BodyMotion, CarriedLink};
use crate::cable::{
    AttachedForce, AttachedPair, BaseState, Cable, Chain, ContactError, CoulombFriction, Curve, ImpactLaw, PairContact, PairFriction, PointState, Span,
    SphereContact,
};
use glam::{DMat3, DVec3};
use rapier3d::prelude as rp;
use std::collections::HashMap;
use std::sync::Arc;

/// Contact settings of one cable: its elements against rapier's colliders.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CableContact {
    /// The normal law.
    pub law: ImpactLaw,
    /// The rope's Coulomb friction coefficient (≥ 0), combined with each
    /// collider's own as rapier combines two colliders' (the collider's
    /// `friction_combine_rule`, against the rope's `Average`): with
    /// rapier's defaults, the mean of the two. 0 on both sides:
    /// frictionless.
    pub friction: f64,
    /// The rope's collision groups, as a rapier collider's (the same
    /// groups for rapier's collision and solver tests): the rope touches a
    /// collider only if these pass rapier's test
    /// ([`InteractionGroups::test`](rp::InteractionGroups::test)) against
    /// both the collider's collision groups and its solver groups, and
    /// another cable only if the two cables' groups pass it. Its own
    /// elements always meet (self contact). Default
    /// [`InteractionGroups::all`](rp::InteractionGroups::all), a rapier
    /// collider's default: it touches every collider that keeps its
    /// default groups.
    pub groups: rp::InteractionGroups,
}

impl CableContact {
    /// Steel wire rope on steel: Hertz (`ImpactLaw::hertz`) with
    /// E* = 1.154e11 Pa (E = 210 GPa, ν = 0.3 on both sides) and R* the
    /// rope's radius (a flat or larger obstacle), damping ramped in over
    /// 1e-5 m to `C_max = 2 √(k m_e)`, critical for an element of mass
    /// `element_mass` (kg) on the contact's stiffness `k` at that depth;
    /// Coulomb friction 0.3 (SCENARIO.md's default; see
    /// [`CableContact::with_friction`]). `diameter` m.
    pub fn steel(diameter: f64, element_mass: f64) -> Result<Self, ContactError> {
        Ok(CableContact { law: steel_law(0.5 * diameter, element_mass)?, friction: 0.3, groups: rp::InteractionGroups::all() })
    }

    /// The same with the rope's collision groups `groups` (see
    /// [`CableContact::groups`]).
    pub fn with_groups(self, groups: rp::InteractionGroups) -> Self {
        CableContact { groups, ..self }
    }

    /// Whether the rope touches `collider` at all: its groups pass rapier's
    /// test against the collider's collision groups and its solver groups.
    pub fn touches(&self, collider: &rp::Collider) -> bool {
        self.groups.test(collider.collision_groups()) && self.groups.test(collider.solver_groups())
    }

    /// The same with the rope's friction coefficient `mu` (≥ 0, finite).
    pub fn with_friction(self, mu: f64) -> Result<Self, ContactError> {
        if !(mu >= 0.0 && mu.is_finite()) {
            return Err(ContactError::OutOfRange { name: "friction", value: mu, range: ">= 0" });
        }
        Ok(CableContact { friction: mu, ..self })
    }
}

/// Whether two colliders touch in the island's own contacts (a carried or
/// free body against a collider, or against another body): rapier's test of
/// their collision groups and of their solver groups, as rapier filters
/// the contacts it solves.
fn colliders_touch(a: &rp::Collider, b: &rp::Collider) -> bool {
    a.collision_groups().test(b.collision_groups()) && a.solver_groups().test(b.solver_groups())
}

/// Two friction coefficients combined as rapier combines two colliders'
/// (`CoefficientCombineRule::combine`, the higher rule of the two wins).
fn combine(a: f64, b: f64, rule_a: rp::CoefficientCombineRule, rule_b: rp::CoefficientCombineRule) -> f64 {
    use rp::CoefficientCombineRule as Rule;
    match rule_a.max(rule_b) {
        Rule::Average => 0.5 * (a + b),
        Rule::Min => a.min(b).abs(),
        Rule::Multiply => a * b,
        Rule::Max => a.max(b),
        Rule::ClampedSum => (a + b).clamp(0.0, 1.0),
        Rule::GeometricMean => (a.max(0.0) * b.max(0.0)).sqrt(),
    }
}

/// Which contact a friction anchor belongs to, from one step to the next.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Site {
    /// Rope `rope`'s node `k` (`2k`) or element `i`'s interior
    /// (`2i + 1`), against `obstacle`.
    Rope { rope: usize, site: usize, obstacle: rp::ColliderHandle },
    /// Touch point `point` of a carried body's collider `collider`,
    /// against `obstacle`.
    Body { collider: rp::ColliderHandle, point: usize, obstacle: rp::ColliderHandle },
}

/// The friction anchors ("friction targets") of a cable's contacts, kept
/// from one step to the next: a contact that sticks keeps its anchor, one
/// that is not found again forgets it. An element interior's contact also
/// keeps its material point (the fraction along the element): the search
/// for the element's nearest point moves it by rounding from step to step
/// (1e-6 m, as much as a steel contact's whole stick deflection), which
/// would read as slip and make a resting wrap chatter (measured: tensions
/// across a still capstan wrap swinging ±5 %).
#[derive(Debug, Clone, Default)]
pub(crate) struct FrictionMemory {
    /// Each site's anchor at the cable's time (world, m), its fraction
    /// along the element (0 at a node or a body) and its normal force at
    /// the end of the last step (N).
    anchors: HashMap<Site, (DVec3, f64, f64)>,
    /// This step's contacts, in the order of their force elements: the
    /// site, the contact, its fraction along its element and its friction
    /// coefficient.
    step: Vec<(Site, SphereContact, f64, f64)>,
    /// The bodies in each of this step's contacts, in the same order
    /// (kept after the step, for the bodies' `contact_force`): the
    /// obstacle's body and, for a carried body's touch point, that body.
    bodies: Vec<[Option<rp::RigidBodyHandle>; 2]>,
    /// The friction states of the cable's pair contacts of its ropes with
    /// themselves (and each other) at the end of the last step.
    own_pairs: Vec<PairTouch>,
    /// Those of its ropes' pair contacts with other cables and with free
    /// bodies (of the pairs whose first point is this cable's) at the end
    /// of the last step: see [`FrictionMemory::recall`].
    pub(crate) cross_pairs: Vec<PairTouch>,
    /// This step's own pair contacts, in the order of the chain's pair
    /// elements after the fixed ones, each with its overlap offset (m, see
    /// [`pair_overlap`]).
    pair_step: Vec<(PairContact, f64)>,
    /// Each body touch point's contact at the end of the last step (open
    /// ones too, friction or not): its depth then, without its offset,
    /// and its offset (m): see [`FrictionMemory::sunk`].
    sunk: HashMap<Site, (f64, f64)>,
    /// This step's contacts' offsets (m), in the order of `step`.
    step_sunk: Vec<f64>,
    /// The last search for the cable's contacts with colliders, for the
    /// next search's reach ([`node_accelerations`]).
    searched: Option<Search>,
}

/// A search for a cable's contacts with colliders, as the next search's
/// reach needs it ([`node_accelerations`]).
#[derive(Debug, Clone)]
struct Search {
    /// Its time, s.
    time: f64,
    /// Each rope's node velocities then, m/s.
    velocities: Vec<Vec<DVec3>>,
    /// The node accelerations it used (magnitudes), m/s².
    accelerations: Vec<Vec<f64>>,
    /// The same as vectors (world, m/s²), for the reach of the ropes'
    /// touches with each other ([`rope_pairs`]).
    vectors: Vec<Vec<DVec3>>,
}

/// A pair contact's friction state kept from one step to the next, found
/// again by where it is (the two ropes, or a rope and a body, slide along
/// each other: no material point stays the contact's, and a touch found
/// at a node one step may be found between two elements at the next).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PairTouch {
    /// Midpoint of its two points at the end of the step, world, m.
    at: DVec3,
    /// How far from `at` the next step's contact may be to be this one:
    /// the two radii and twice the slip over the step, m.
    reach: f64,
    /// The stick spring's stretch to carry over, world, m (zero without
    /// friction).
    stretch: DVec3,
    /// The normal force at the end of the step, N.
    normal: f64,
    /// The part of that overlap that was not elastic ([`pair_overlap`]), m.
    offset: f64,
}

impl PairTouch {
    /// The state to remember of `contact` (its overlap offset `offset`
    /// m) with its points at `a` and `b` at the end of a step of `h` s
    /// (`None` if open).
    fn of(contact: &PairContact, a: &PointState, b: &PointState, h: f64, offset: f64) -> Option<PairTouch> {
        let stretch = contact.next_stretch(a, b).unwrap_or(DVec3::ZERO);
        let n = contact.normal;
        let slip = a.velocity - b.velocity;
        let (depth, rate) = contact.depth(a, b);
        let normal = contact.law.force(depth, rate).0;
        // An open contact is not kept: a touch found near it at the next
        // step is more likely the closed one beside it (two ropes crossing
        // near a node touch there twice), whose friction it would cut.
        (normal > 0.0).then(|| PairTouch {
            at: (a.point + b.point) * 0.5,
            reach: contact.radius + offset + 2.0 * h * (slip - n * slip.dot(n)).length(),
            stretch,
            normal,
            offset,
        })
    }
}

/// A pair contact found at a pass's start between points now at `a` and
/// `b`, as the step solves it, with what `recalled` (the same touch at the
/// end of the last pass, [`FrictionMemory::recall`]) kept of it: its
/// overlap that is not elastic ([`pair_overlap`]) and its friction
/// ([`pair_friction`], coefficient `mu`). Returns the contact and that
/// overlap's offset (m), to remember after the pass.
pub(crate) fn recalled_pair(contact: PairContact, mu: f64, a: &PointState, b: &PointState, recalled: Option<PairTouch>) -> (PairContact, f64) {
    let (contact, offset) = pair_overlap(contact, a, b, recalled);
    (pair_friction(contact, mu, a, b, recalled), offset)
}

/// `contact` between points now at `a` and `b`, with Coulomb friction
/// `mu` (frictionless if 0) whose stick state is `recalled`'s (the same
/// touch at the end of the last step, [`FrictionMemory::recall`]): its
/// stretch carried over and its normal force as the limit's bound; a new
/// touch starts relaxed with no friction in its first step (as a
/// [`SphereContact`]'s).
fn pair_friction(contact: PairContact, mu: f64, a: &PointState, b: &PointState, recalled: Option<PairTouch>) -> PairContact {
    if mu <= 0.0 {
        return contact;
    }
    let (stretch, normal) = recalled.map_or((DVec3::ZERO, 0.0), |t| (t.stretch, t.normal));
    PairFriction::from_law(mu, &contact.law, a.point - b.point - stretch, normal).map_or(contact, |f| PairContact { friction: Some(f), ..contact })
}

/// `contact` (its two capsules' radii in `radius`) between points now at
/// `a` and `b`, with the part of their overlap that is not elastic taken
/// out of its radius, and that part (m). Found already overlapping (the
/// ropes passed into each other between two contact passes: a whipping
/// slack rope's elements cross at up to 100 m/s), the overlap is not
/// stored energy of the stiff law: a contact new to the pass (no
/// `recalled` touch) starts at zero depth (its overlap beyond
/// [`SUNK_TOLERANCE`] its offset), a continuing one keeps its offset,
/// which shrinks only as the two come apart, as a body touch point's
/// ([`FrictionMemory::sunk`]). (Adding a continuing contact's growth
/// between passes to its offset, as for body touch points, let the
/// pendant of `cable_impact.toml` ratchet 1.1 mm into the span.) Taken
/// as elastic, a 15.7 mm overlap of two 16 mm steel ropes holds 170 kJ
/// of Hertz energy: an undamped two-leg sling whose slack legs whipped
/// into each other gained 27 kJ in one frame and threw its 500 kg crate
/// 8 m up (2026-11-28).
fn pair_overlap(contact: PairContact, a: &PointState, b: &PointState, recalled: Option<PairTouch>) -> (PairContact, f64) {
    let depth = contact.depth(a, b).0;
    let offset = match recalled {
        Some(t) => t.offset,
        None if depth > SUNK_TOLERANCE => depth,
        None => 0.0,
    }
    .min(depth.max(0.0));
    (PairContact { radius: contact.radius - offset, ..contact }, offset)
}

/// The world state of point `local` of `chain`'s link `link` (at its last
/// evaluation).
pub(crate) fn chain_point(chain: &Chain, link: usize, local: DVec3) -> PointState {
    PointState {
        rotation: chain.link_rotation(link).unwrap_or(DMat3::IDENTITY),
        point: chain.link_point(link, local).unwrap_or(DVec3::ZERO),
        velocity: chain.link_point_velocity(link, local).unwrap_or(DVec3::ZERO),
        angular_velocity: chain.link_velocity(link).map_or(DVec3::ZERO, |v| v.top),
    }
}

impl FrictionMemory {
    /// Where along element interior `site` the contact goes this step: at
    /// the material point of the last step while the nearest point `f`
    /// (a fraction of the element) found now is within 0.1 of it, else at
    /// `f`.
    fn fraction(&self, site: Site, f: f64) -> f64 {
        self.anchors.get(&site).map(|x| x.1).filter(|old| (old - f).abs() < 0.1).unwrap_or(f)
    }

    /// Where along element interior `site` a contact of the element's
    /// segment ([`Span`]) has its material point this step: the last
    /// step's, wherever the nearest point `f` (a fraction of the element)
    /// is now, else `f`. (Moved to the nearest point once it was a tenth
    /// of the element away, as [`FrictionMemory::fraction`] does, the
    /// friction anchor of an element entering a drum's wrap was reset once
    /// per element passing, and that step slipped at the kinetic force:
    /// `capstan_friction.toml`'s ratio 1.6 % off in one frame in 30.)
    fn kept_fraction(&self, site: Site, f: f64) -> f64 {
        self.anchors.get(&site).map_or(f, |x| x.1)
    }

    /// Whether this step (or pass) has any contact: with a collider, a
    /// carried body's, or a pair of the cable's own ropes.
    pub(crate) fn has_contacts(&self) -> bool {
        !self.step.is_empty() || !self.pair_step.is_empty()
    }

    /// Notes this step's next contact (its force element the next one
    /// added): at `site`, `fraction` along its element, with the friction
    /// coefficient `mu` (none if 0). [`FrictionMemory::attach`] gives it
    /// its friction.
    fn note(&mut self, site: Site, contact: SphereContact, mu: f64, fraction: f64, bodies: [Option<rp::RigidBodyHandle>; 2]) -> SphereContact {
        self.note_sunk(site, contact, mu, fraction, bodies, 0.0)
    }

    /// [`FrictionMemory::note`] for a contact whose obstacle's surface
    /// was moved in by `offset` m ([`FrictionMemory::sunk`]).
    fn note_sunk(
        &mut self,
        site: Site,
        contact: SphereContact,
        mu: f64,
        fraction: f64,
        bodies: [Option<rp::RigidBodyHandle>; 2],
        offset: f64,
    ) -> SphereContact {
        self.step.push((site, contact, fraction, mu));
        self.bodies.push(bodies);
        self.step_sunk.push(offset);
        contact
    }

    /// The force (N, world) the contacts put on `body`, given each
    /// contact's force on its sphere in order: that force where `body`
    /// carries the sphere (a carried body's touch point), its opposite
    /// where `body` is the obstacle.
    pub(crate) fn force_on(&self, body: rp::RigidBodyHandle, forces: impl Iterator<Item = DVec3>) -> DVec3 {
        self.bodies.iter().zip(forces).fold(DVec3::ZERO, |sum, ([obstacle, own], f)| {
            if *own == Some(body) {
                sum + f
            } else if *obstacle == Some(body) {
                sum - f
            } else {
                sum
            }
        })
    }

    /// The force (N) and moment about `about` (N·m, world) that the
    /// contacts put on `body` where it is their obstacle, given each
    /// contact's point and force on its sphere in order (the opposite
    /// force, at the sphere's centre).
    pub(crate) fn wrench_on_obstacle(&self, body: rp::RigidBodyHandle, contacts: impl Iterator<Item = (DVec3, DVec3)>, about: DVec3) -> (DVec3, DVec3) {
        self.bodies
            .iter()
            .zip(contacts)
            .filter(|([obstacle, _], _)| *obstacle == Some(body))
            .fold((DVec3::ZERO, DVec3::ZERO), |(f, m), (_, (at, force))| (f - force, m + (at - about).cross(-force)))
    }

    /// Gives each contact noted this step (force elements `fixed..` of
    /// `cable`, at the step's start) its friction: the normal force its
    /// site had at the end of the last step as the limit's bound (none: no
    /// friction this step), its anchor then if it touches at the same
    /// fraction along its element (else the contact point now), and the
    /// link's orientation now as its frame.
    pub(crate) fn attach(&mut self, chain: &mut Chain, fixed: usize) {
        let points: Vec<PointState> = chain.force_element_points().skip(fixed).collect();
        let forces = chain.forces_mut();
        for (k, ((site, contact, fraction, mu), at)) in self.step.iter_mut().zip(points).enumerate() {
            if *mu <= 0.0 {
                continue;
            }
            let last = self.anchors.get(site).copied();
            let kept = last.filter(|x| x.1 == *fraction);
            // A rope element's friction acts at its centreline (it does not
            // roll), a carried body's at its touch point's surface.
            let at_surface = matches!(site, Site::Body { .. });
            let arm = if at_surface { contact.normal * contact.radius } else { DVec3::ZERO };
            let anchor = kept.map_or(at.point - arm, |x| x.0);
            // The same site touching at another material point (a rope
            // sliding along the obstacle moved it by more than a tenth of
            // an element) keeps its normal force as the limit's bound, its
            // stick spring relaxed at the point now: it slips within the
            // step at the kinetic force. With no bound it had no friction
            // for that step, and a rope sliding over a capstan lost it at
            // one element in three, one step each (tension-ratio blips of
            // up to 19 % for a frame).
            let normal = last.map_or(0.0, |x| x.2);
            if let Ok(friction) = CoulombFriction::from_law(*mu, &contact.law, anchor, &at, normal).map(|f| CoulombFriction { at_surface, ..f }) {
                *contact = contact.with_friction(friction);
                forces[fixed + k].element = Arc::new(*contact);
            }
        }
    }

    /// After the step: each contact's anchor for the next one, from the
    /// points of this step's contact force elements at time `t` (s).
    pub(crate) fn remember(&mut self, t: f64, points: impl Iterator<Item = PointState>) {
        let points: Vec<PointState> = points.collect();
        self.sunk = self
            .step
            .iter()
            .zip(&self.step_sunk)
            .zip(&points)
            .filter(|(((site, ..), _), _)| matches!(site, Site::Body { .. }))
            .map(|(((site, c, ..), offset), at)| (*site, (c.depth(t, at).0 + offset, *offset)))
            .collect();
        self.step_sunk.clear();
        self.anchors =
            self.step.drain(..).zip(points).filter_map(|((site, c, f, _), at)| c.next_anchor(t, &at).map(|a| (site, (a, f, c.normal_force(t, &at))))).collect();
    }

    /// Forgets this step's contacts (a step that was not taken).
    pub(crate) fn discard_step(&mut self) {
        self.step.clear();
        self.bodies.clear();
        self.pair_step.clear();
        self.step_sunk.clear();
    }

    /// How far (m) a body touch point's contact at `site`, starting
    /// `depth` m inside its obstacle, has its obstacle's surface moved in
    /// this step: the depth the body did not reach in the cable's or the
    /// island's own solve. A body rapier put into a collider (laid there,
    /// or pushed in, beyond [`SUNK_TOLERANCE`]) does not have that overlap
    /// as elastic energy of the contact's stiff law: its touch points
    /// start at the depth they ended the last step with (at zero for a
    /// touch point new to the step), and the offset shrinks only as the
    /// body comes out. (Taken as elastic, a 30 kg crate laid 5 cm into the
    /// ground under a rope was thrown, the rope 0.7 m up, and the solve
    /// failed, 2026-11-27.)
    ///
    /// Against a moving (kinematic) collider (`fixed` false) only a touch
    /// point new to the step takes its overlap as an offset (a body rapier
    /// left in a platform that was rising, when it joins a rope's island);
    /// a continuing one never adds to its offset: the plane, moved on at
    /// the obstacle's velocity over the step, misses its acceleration, and
    /// an offset grown by that let a box sink 3.2 cm into an accelerating
    /// platform. (With no offset at all against moving colliders, a 20 kg
    /// box under a rope, which rapier had left 0.28 mm in a platform rising
    /// at 2 m/s², started its first island step 1.1 mm in it, beyond
    /// [`GROUNDED_DEPTH`], and the steel contact threw it up at 108 m/s,
    /// 2026-11-27.)
    fn sunk(&self, site: Site, depth: f64, fixed: bool) -> f64 {
        let (end, offset, known) = self.sunk.get(&site).map_or((0.0, 0.0, false), |&(end, offset)| (end, offset, true));
        let grown = depth - end;
        let added = if (fixed || !known) && grown > SUNK_TOLERANCE { grown } else { 0.0 };
        (offset + added).min(depth.max(0.0))
    }

    /// The remembered pair touch nearest to `at` (m, world; the midpoint of
    /// a contact's two points now) within its reach, among `memories`.
    pub(crate) fn recall<'m>(memories: impl IntoIterator<Item = &'m [PairTouch]>, at: DVec3) -> Option<PairTouch> {
        memories.into_iter().flatten().map(|t| (t.at.distance(at), t)).filter(|(d, t)| *d <= t.reach).min_by(|x, y| x.0.total_cmp(&y.0)).map(|(_, t)| *t)
    }

    /// After a step of `h` s: the friction state of each of this step's
    /// own pair contacts, from their points now (the chain's pair points
    /// after the fixed ones, in order).
    pub(crate) fn remember_pairs(&mut self, points: impl Iterator<Item = (PointState, PointState)>, h: f64) {
        self.own_pairs = self.pair_step.iter().zip(points).filter_map(|((c, offset), (a, b))| PairTouch::of(c, &a, &b, h, *offset)).collect();
    }

    /// After a step of `h` s: `contact`'s friction state, its points now
    /// at `a` and `b`, kept as one of this cable's touches with other
    /// cables or free bodies.
    pub(crate) fn remember_cross(&mut self, contact: &PairContact, a: &PointState, b: &PointState, h: f64, offset: f64) {
        self.cross_pairs.extend(PairTouch::of(contact, a, b, h, offset));
    }
}

/// Steel on steel (E = 210 GPa, ν = 0.3 on both sides: E* = 1.154e11 Pa),
/// Hertz with R* = `r_star` (m), damping ramped in over 1e-5 m to the
/// critical damping `2 √(k m)` of `damped_mass` (kg) on the contact's
/// stiffness `k` at that depth.
fn steel_law(r_star: f64, damped_mass: f64) -> Result<ImpactLaw, ContactError> {
    let e_star = 1.0 / (2.0 * (1.0 - 0.09) / 210e9);
    let depth: f64 = 1e-5;
    let k = 1.5 * (4.0 / 3.0) * e_star * r_star.sqrt() * depth.sqrt();
    ImpactLaw::hertz(e_star, r_star, 2.0 * (k * damped_mass.max(0.0)).sqrt(), depth)
}

/// What the rope elements may touch: rapier's colliders, and the exact
/// (f64) motion of the fixed and kinematic bodies that have one (a
/// scenario's bodies, in both runners), used instead of rapier's f32 pose
/// so that `cablesim` and a Bevy app find the same contacts to the bit.
#[derive(Clone, Copy)]
pub struct Contacts<'a> {
    /// The colliders.
    pub colliders: &'a rp::ColliderSet,
    /// A body's exact motion, if the adapter knows it.
    pub motions: &'a dyn Fn(rp::RigidBodyHandle) -> Option<BodyMotion>,
    /// The dynamic bodies that an impulse joint holds and no cable does:
    /// the ropes meet them as moving obstacles (rapier's pose moved on
    /// with their velocities), and their contact forces go back to rapier
    /// as impulses ([`crate::coupling::step_cables`] fills it; adapters
    /// pass `&[]`).
    pub jointed: &'a [rp::RigidBodyHandle],
    /// The position-based kinematic bodies' velocities over the step (of
    /// the centre of mass, m/s, and angular, rad/s): from their pose to the
    /// target the user set (rapier's `next_position`). Rapier gives them
    /// those velocities only at its own step, after the cables'; until then
    /// they read the last step's ([`crate::coupling::step_cables`] fills
    /// it; adapters pass `&[]`).
    pub kinematic: &'a [(rp::RigidBodyHandle, DVec3, DVec3)],
}

impl Contacts<'_> {
    /// A body's velocities over the step (of its centre of mass, m/s, and
    /// angular, rad/s): [`Contacts::kinematic`]'s for a position-based
    /// kinematic body, else rapier's.
    pub(crate) fn velocities(&self, handle: rp::RigidBodyHandle, rb: &rp::RigidBody) -> (DVec3, DVec3) {
        self.kinematic.iter().find(|k| k.0 == handle).map_or((rb.linvel().as_dvec3(), rb.angvel().as_dvec3()), |k| (k.1, k.2))
    }
}

/// A collider's pose relative to its body (identity without a body).
fn offset(collider: &rp::Collider) -> (DVec3, DMat3) {
    collider.position_wrt_parent().map_or((DVec3::ZERO, DMat3::IDENTITY), |l| (l.translation.as_dvec3(), DMat3::from_quat(l.rotation.as_dquat().normalize())))
}

/// An obstacle collider at the step's start: its frame (its body's exact
/// pose when the adapter knows its motion, with the collider's offset on
/// it; else rapier's f32 pose) and how its surface moves.
struct Obstacle<'a> {
    handle: rp::ColliderHandle,
    collider: &'a rp::Collider,
    origin: DVec3,
    rotation: DMat3,
    exact: Option<BaseState>,
    body: Option<&'a rp::RigidBody>,
    /// Without an exact motion, its body's centre of mass at `now` (m) and
    /// velocities over the step ([`Contacts::velocities`]: m/s, rad/s).
    moving: Option<(DVec3, DVec3, DVec3)>,
    /// The time the obstacle is taken at, s (a contact pass's start).
    now: f64,
    /// Its bounding box then, world, m ([`Obstacle::aabb`]).
    bounds: (DVec3, DVec3),
    /// Its surface's speed bound, m/s ([`Obstacle::speed`]).
    speed: f64,
}

impl<'a> Obstacle<'a> {
    /// The obstacle at `now` (s); rapier's pose is the one at `start`
    /// (the coupling step's start), moved on with its body's velocities
    /// when `now` is later (a contact pass inside the step).
    fn new(handle: rp::ColliderHandle, collider: &'a rp::Collider, world: &Contacts<'_>, bodies: &'a rp::RigidBodySet, now: f64, start: f64) -> Self {
        let body = collider.parent().and_then(|p| bodies.get(p));
        let exact = collider.parent().and_then(|p| (world.motions)(p)).map(|m| m(now));
        let dt = now - start;
        let moving = match (&exact, body, collider.parent()) {
            (None, Some(rb), Some(p)) => {
                let (v, w) = world.velocities(p, rb);
                Some((rb.center_of_mass().as_dvec3() + v * dt.max(0.0), v, w))
            }
            _ => None,
        };
        let (origin, rotation) = match &exact {
            Some(b) => {
                let (lt, lr) = offset(collider);
                (b.position + b.rotation * lt, b.rotation * lr)
            }
            None => {
                let pose = collider.position();
                let (mut origin, mut rotation) = (pose.translation.as_dvec3(), DMat3::from_quat(pose.rotation.as_dquat().normalize()));
                if let (Some(rb), Some((_, v, w)), true) = (body, moving, dt > 0.0) {
                    let com = rb.center_of_mass().as_dvec3();
                    let turn = DMat3::from_quat(glam::DQuat::from_scaled_axis(w * dt));
                    origin = com + turn * (origin - com) + v * dt;
                    rotation = turn * rotation;
                }
                (origin, rotation)
            }
        };
        let (lo, hi) = if now > start {
            placed_aabb(collider, origin, rotation)
        } else {
            let aabb = collider.compute_aabb();
            (aabb.mins.as_dvec3(), aabb.maxs.as_dvec3())
        };
        let corner = |c: DVec3| (c - lo).abs().max((c - hi).abs()).length();
        let speed = match (&exact, moving) {
            (Some(b), _) => b.velocity.length() + b.angular_velocity.length() * corner(b.position),
            (None, Some((com, v, w))) => v.length() + w.length() * corner(com),
            (None, None) => 0.0,
        };
        Obstacle { handle, collider, origin, rotation, exact, body, moving, now, bounds: (lo, hi), speed }
    }

    /// Every collider a rope or a carried body may touch this step, at
    /// `now` (s): not a sensor, not on a dynamic body (see
    /// [`add_contacts`]) unless a joint holds it ([`Contacts::jointed`]),
    /// and not on a body in `exclude`. With a `region` (world box, m,
    /// padded by the caller's whole reach), a collider that cannot move (no
    /// body, or a fixed one) whose box lies outside it is left out before
    /// its record is built: most of a level's colliders are far from any
    /// rope, and the record (its exact pose, box and speed) cost 0.24 µs
    /// per collider, cable and contact pass. Its box is rapier's, widened
    /// by 1 mm and 1e-6 relative (an exact motion's pose differs from
    /// rapier's `f32` one by round-off).
    fn all(
        world: &Contacts<'a>,
        bodies: &'a rp::RigidBodySet,
        exclude: &[rp::RigidBodyHandle],
        (now, start): (f64, f64),
        region: Option<(DVec3, DVec3)>,
        rope: Option<&CableContact>,
    ) -> Vec<Obstacle<'a>> {
        let outside = |c: &rp::Collider| {
            let Some((lo, hi)) = region else {
                return false;
            };
            if !c.parent().and_then(|p| bodies.get(p)).is_none_or(|rb| rb.is_fixed()) {
                return false;
            }
            let aabb = c.compute_aabb();
            let margin = |p: DVec3| p.abs() * 1e-6 + DVec3::splat(1e-3);
            let (clo, chi) = (aabb.mins.as_dvec3(), aabb.maxs.as_dvec3());
            (clo - margin(clo)).cmpgt(hi).any() || (chi + margin(chi)).cmplt(lo).any()
        };
        world
            .colliders
            .iter()
            .filter(|(_, c)| !outside(c))
            .filter(|(_, c)| {
                // Dynamic bodies are not obstacles: their motion frozen
                // over the step, a falling ball squeezed the rope into the
                // ground and failed the solve (measured: a 50 kg ball at
                // 4.4 m/s onto a rope lying on the ground). They need their
                // inertia in the rope's solve: a free body of the island
                // (`body_pairs`), or a carried body's link.
                let dynamic =
                    c.parent().and_then(|p| bodies.get(p)).is_some_and(|rb| rb.is_dynamic()) && !c.parent().is_some_and(|p| world.jointed.contains(&p));
                !c.is_sensor() && !dynamic && !c.parent().is_some_and(|p| exclude.contains(&p)) && rope.is_none_or(|r| r.touches(c))
            })
            .map(|(h, c)| Obstacle::new(h, c, world, bodies, now, start))
            .collect()
    }

    /// A bound on the speed of the collider's surface over the step, m/s
    /// (its body's speed plus its turn times the farthest corner of its
    /// bounding box from the turn's centre), so that the speculative reach
    /// covers what the obstacle moves too: 0 for a fixed one.
    fn speed(&self) -> f64 {
        self.speed
    }

    /// The collider's bounding box, world, m: rapier's at the step's
    /// start, or, for a later contact pass, the shape's at the obstacle's
    /// pose then.
    fn aabb(&self) -> (DVec3, DVec3) {
        self.bounds
    }

    /// The nearest surface point to the world point `p` (m), its outward
    /// normal and the signed distance of `p` (see [`nearest`]), in the
    /// obstacle's frame.
    fn nearest(&self, p: DVec3) -> Option<(DVec3, DVec3, f64)> {
        self.nearest_local(self.local(p))
    }

    /// [`Obstacle::nearest`] to a point given in the obstacle's frame.
    fn nearest_local(&self, q: DVec3) -> Option<(DVec3, DVec3, f64)> {
        nearest(self.collider.shape(), q)
    }

    /// The supporting plane of the (convex) shape across the element from
    /// `a` to `b` (its frame, m) that penetrates it: the normal along
    /// which the segment leaves the shape soonest (parry's penetration
    /// query, f32), through the shape's support point in that direction
    /// (exact for a box's edge or corner), and the signed distance of `p`
    /// from it. At a box's edge the plane holds the element where it
    /// crosses the edge; a nearest-face plane at a point inside the box
    /// near the edge is the side face's, which lets the element sink
    /// through the top. `None` for shapes without a support map
    /// (meshes, compounds) or when the query finds no penetration.
    fn segment_plane(&self, a: DVec3, b: DVec3, p: DVec3) -> Option<(DVec3, DVec3, f64)> {
        use rapier3d::parry::{math::Pose, query, shape::Segment};
        let shape = self.collider.shape();
        let support = shape.as_support_map()?;
        let segment = Segment::new(a.as_vec3(), b.as_vec3());
        let c = query::contact(&Pose::IDENTITY, &segment, &Pose::IDENTITY, shape, 0.0).ok()??;
        // normal1 points from the segment into the shape.
        let n = (-c.normal1).as_dvec3().normalize();
        if c.dist >= 0.0 || !n.is_finite() {
            return None;
        }
        let q = support.local_support_point(n.as_vec3()).as_dvec3();
        Some((q, n, (p - q).dot(n)))
    }

    /// [`Obstacle::nearest_local`], and whether that surface point lies on
    /// an edge or a vertex of the shape ([`nearest_and_edge`]).
    fn nearest_local_and_edge(&self, q: DVec3) -> Option<((DVec3, DVec3, f64), bool)> {
        nearest_and_edge(self.collider.shape(), q)
    }

    /// The world point `p` (m) in the obstacle's frame.
    fn local(&self, p: DVec3) -> DVec3 {
        self.rotation.transpose() * (p - self.origin)
    }

    /// The contact of a sphere of `radius` (m) with the obstacle's tangent
    /// plane at the surface point `q` with normal `normal` (its frame), for
    /// the step; on a ball, a cylinder's round side or a capsule
    /// ([`round_at`]), with the curved surface itself ([`Curve`]), its
    /// point and normal recomputed in `f64` from the shape's centre or
    /// axis.
    fn contact(&self, (q, normal, _): (DVec3, DVec3, f64), radius: f64, law: ImpactLaw) -> SphereContact {
        let point = self.origin + self.rotation * q;
        let contact = SphereContact {
            point,
            normal: self.rotation * normal,
            velocity: self.surface_velocity(point),
            time: self.now,
            radius,
            law,
            friction: None,
            curve: None,
            span: None,
        };
        match round_at(self.collider.shape(), q, normal) {
            Some((r, centre, axis)) => {
                // The exact surface point and normal across from the centre.
                let mut d = q - centre;
                if let Some(a) = axis {
                    d -= a * d.dot(a);
                }
                let n = d.normalize();
                if !n.is_finite() {
                    return contact;
                }
                let point = self.origin + self.rotation * (centre + n * r);
                let exact = SphereContact { point, normal: self.rotation * n, velocity: self.surface_velocity(point), ..contact };
                let c = self.origin + self.rotation * centre;
                exact.with_curve(Curve { radius: r, axis: axis.map(|a| self.rotation * a), centre_velocity: self.surface_velocity(c) })
            }
            None => contact,
        }
    }

    /// The contact of a rope element's interior, whose segment through the
    /// contact's point is `span`, with the surface point `hit` (as
    /// [`Obstacle::contact`]'s): on a ball, a cylinder's round side or a
    /// capsule, and on a box's edge or corner ([`Obstacle::edge_curve`]),
    /// of the segment against the curved surface ([`Span`]), so that it
    /// acts where the surface is under the element as the rope slides;
    /// elsewhere (a face) of the point.
    fn element_contact(&self, hit: (DVec3, DVec3, f64), radius: f64, law: ImpactLaw, span: Span) -> SphereContact {
        let contact = self.contact(hit, radius, law);
        if contact.curve.is_some() {
            return contact.with_span(span);
        }
        match self.edge_curve(hit.0) {
            Some((point, curve)) => SphereContact { point, ..contact }.with_curve(curve).with_span(span),
            None => contact,
        }
    }

    /// The edge or the corner of a box at the surface point `q` (its frame,
    /// m) as a curve of radius 0 (a line, or a point), and its point
    /// (world, m). `None` when the obstacle is not a box or `q` is not on
    /// one of its edges or corners.
    fn edge_curve(&self, q: DVec3) -> Option<(DVec3, Curve)> {
        let h = self.collider.shape().as_cuboid()?.half_extents.as_dvec3();
        // Parry's projection is `f32`: the edge's coordinates snapped to
        // the box's (the faces within 1e-5 relative and 1 µm).
        let mut exact = q;
        let mut along = None;
        let mut on = 0;
        for j in 0..3 {
            if (q[j].abs() - h[j]).abs() <= 1e-5 * h[j] + 1e-6 {
                exact[j] = h[j].copysign(q[j]);
                on += 1;
            } else {
                along = Some(j);
            }
        }
        let axis = match (on, along) {
            (2, Some(j)) => {
                let mut a = DVec3::ZERO;
                a[j] = 1.0;
                Some(self.rotation * a)
            }
            (3, _) => None,
            _ => return None,
        };
        let point = self.origin + self.rotation * exact;
        Some((point, Curve { radius: 0.0, axis, centre_velocity: self.surface_velocity(point) }))
    }

    /// Velocity of the obstacle's surface at world point `q`, m/s.
    fn surface_velocity(&self, q: DVec3) -> DVec3 {
        match (&self.exact, self.moving) {
            (Some(b), _) => b.velocity + b.angular_velocity.cross(q - b.position),
            (None, Some((com, v, w))) => v + w.cross(q - com),
            (None, None) => DVec3::ZERO,
        }
    }
}

/// Whether the surface point `q` of `shape` with outward normal `normal`
/// (collider frame, as parry's `f32` projection gives them) lies on a ball
/// or on the round side of a cylinder or a capsule: the radius there (m),
/// the exact centre (of the ball, or the point of the axis across from
/// `q`; collider frame, m) and the cylinder's axis (`None` for a ball or
/// a capsule's end). `None` on flat faces, rims and other shapes.
fn round_at(shape: &dyn rp::Shape, q: DVec3, normal: DVec3) -> Option<(f64, DVec3, Option<DVec3>)> {
    // On the round surface as far as `f32` tells (parry's projection is
    // off by up to 2e-6 m on a 0.5 m drum).
    let on = |centre: DVec3, r: f64| (q - normal * r - centre).length() <= 1e-4 * r;
    if let Some(ball) = shape.as_ball() {
        let r = f64::from(ball.radius);
        return on(DVec3::ZERO, r).then_some((r, DVec3::ZERO, None));
    }
    if let Some(cylinder) = shape.as_cylinder() {
        let (r, half) = (f64::from(cylinder.radius), f64::from(cylinder.half_height));
        // (A support point across a penetrating element lies on the rim
        // with the side's radial normal: the side's plane too.)
        let side = q.y.abs() <= half * (1.0 + 1e-6) && normal.y.abs() < 1e-4;
        let centre = DVec3::new(0.0, q.y, 0.0);
        return (side && on(centre, r)).then_some((r, centre, Some(DVec3::Y)));
    }
    if let Some(capsule) = shape.as_capsule() {
        let (a, b, r) = (capsule.segment.a.as_dvec3(), capsule.segment.b.as_dvec3(), f64::from(capsule.radius));
        let ab = b - a;
        let len2 = ab.length_squared();
        let f = if len2 > 0.0 { ((q - a).dot(ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
        let centre = a + ab * f;
        let axis = (f > 0.0 && f < 1.0).then(|| ab / len2.sqrt());
        return on(centre, r).then_some((r, centre, axis));
    }
    None
}

/// Where the element from `a` to `b` (collider frame, m) comes nearest a
/// ball, a capsule or the round side of a cylinder: the fraction along the
/// element of its point nearest the ball's centre or the shape's axis, the
/// surface point across from it and the outward normal there (collider
/// frame), and the point's distance from the surface (m, negative
/// inside), all exact in `f64`. `None` for other shapes, and on a
/// cylinder where that point is beyond its round side (over a cap or its
/// rim), or on the centre or the axis itself.
fn round_foot(shape: &dyn rp::Shape, a: DVec3, b: DVec3) -> Option<(f64, DVec3, DVec3, f64)> {
    let (f, radius, centre, axis) = if let Some(ball) = shape.as_ball() {
        (closest_on_segment(a, b, DVec3::ZERO), f64::from(ball.radius), DVec3::ZERO, None)
    } else if let Some(capsule) = shape.as_capsule() {
        let (p, q) = (capsule.segment.a.as_dvec3(), capsule.segment.b.as_dvec3());
        let (f, g) = closest_on_segments(a, b, p, q);
        let axis = (g > 0.0 && g < 1.0).then(|| (q - p).normalize()).filter(|x| x.is_finite());
        (f, f64::from(capsule.radius), p.lerp(q, g), axis)
    } else if let Some(cylinder) = shape.as_cylinder() {
        // Nearest the axis (the y axis): the least distance across it
        // (the middle of an element along it).
        let (ax, dx) = (DVec3::new(a.x, 0.0, a.z), DVec3::new(b.x - a.x, 0.0, b.z - a.z));
        let across = dx.length_squared();
        let f = if across > 1e-300 { (-ax.dot(dx) / across).clamp(0.0, 1.0) } else { 0.5 };
        let y = a.y + (b.y - a.y) * f;
        if y.abs() > f64::from(cylinder.half_height) {
            return None;
        }
        (f, f64::from(cylinder.radius), DVec3::new(0.0, y, 0.0), Some(DVec3::Y))
    } else {
        return None;
    };
    let p = a.lerp(b, f);
    let mut d = p - centre;
    if let Some(axis) = axis {
        d -= axis * d.dot(axis);
    }
    let reach = d.length();
    let n = d / reach;
    (reach > 1e-9 * radius && n.is_finite()).then(|| (f, centre + n * radius, n, reach - radius))
}

/// Where the element from `a` to `b` (a box's frame, m) comes nearest the
/// box of half extents `h`, when that is on one of its edges or corners:
/// the fraction along the element, the point of the edge or the corner
/// (its coordinates on the faces exact), the unit normal from it to the
/// element's point, and that point's distance (m). The distance to a box
/// is convex along the element; its minimum by ternary search, in `f64`.
/// `None` when the nearest point is on a face or the element is inside.
fn box_edge_foot(h: DVec3, a: DVec3, b: DVec3) -> Option<(f64, DVec3, DVec3, f64)> {
    // Both ends over the same face (its slab, the only coordinate beyond
    // the box): so is the whole element, nearest that face. (A rope lying
    // on the ground, every element, skips the search.)
    let over = |p: DVec3| p.abs().cmpgt(h).bitmask();
    let (oa, ob) = (over(a), over(b));
    if oa == ob && oa.count_ones() == 1 && (a * b).cmpgt(DVec3::ZERO).bitmask() & oa == oa {
        return None;
    }
    let dist = |f: f64| {
        let p = a.lerp(b, f);
        (p - p.clamp(-h, h)).length()
    };
    let f = convex_min(dist, 0.0, 1.0, 40);
    let p = a.lerp(b, f);
    let q = p.clamp(-h, h);
    let d = p - q;
    let outside = d.cmpne(DVec3::ZERO).bitmask().count_ones();
    let gap = d.length();
    (outside >= 2 && gap > 0.0).then(|| (f, q, d / gap, gap))
}

/// The surface point of `shape` nearest to `p` (collider frame, m), its
/// outward unit normal there, and the signed distance of `p` along it
/// (negative inside). A face's normal is its own (a cuboid's face normal
/// exactly); at an edge or a vertex, and on shapes without feature
/// normals, the direction from the surface point to `p`.
fn nearest(shape: &dyn rp::Shape, p: DVec3) -> Option<(DVec3, DVec3, f64)> {
    nearest_and_edge(shape, p).map(|(hit, _)| hit)
}

/// [`nearest`], and whether the surface point lies on an edge or a vertex
/// of the shape (not inside a face), from the same projection.
fn nearest_and_edge(shape: &dyn rp::Shape, p: DVec3) -> Option<((DVec3, DVec3, f64), bool)> {
    use rapier3d::parry::shape::FeatureId;
    let (proj, feature) = shape.project_local_point_and_get_feature(p.as_vec3());
    let q = proj.point.as_dvec3();
    let d = if proj.is_inside { q - p } else { p - q };
    // An edge's or a vertex's "normal" from parry is the mean of its faces'
    // (a cuboid edge's 45° diagonal whatever side the point is on): a rope
    // resting on a knife edge was pushed along it and slid off. The plane
    // normal to `p − q` through the nearest point supports the convex
    // shape there instead. A point on the surface itself keeps the
    // feature's.
    let face = matches!(feature, FeatureId::Face(_));
    let normal = match shape.feature_normal_at_point(feature, proj.point) {
        Some(n) if face || d.length() < 1e-9 => n.as_dvec3().normalize(),
        _ => d.normalize(),
    };
    let edge = matches!(feature, FeatureId::Edge(_) | FeatureId::Vertex(_));
    normal.is_finite().then(|| ((q, normal, (p - q).dot(normal)), edge))
}

/// Elements per leaf of a rope's broad phase ([`RopeBroadPhase`]).
const BROAD_RUN: usize = 8;

/// A rope's broad phase for one contact pass: its elements in runs of
/// [`BROAD_RUN`], each run's box (the box of every element in it, padded
/// by that element's own pad) a leaf of a parry BVH. An obstacle meets
/// only the elements of the runs its box overlaps, so a collider far from
/// the rope costs a box test at the BVH's root instead of one per element
/// (1 000 fixed crates 20 m from a 1 000-element rope made its step three
/// times slower). Each box is widened by a relative 1e-9 and rounded
/// outwards to the BVH's `f32`: the exact test pads an element's box by
/// its own reach and the obstacle's in one sum, the broad phase pads each
/// box by its own part, and the two may round apart by an `f64` ulp; so no
/// element the exact test would keep is left out.
struct RopeBroadPhase {
    /// `None`: a box was not finite, and every run is a candidate.
    bvh: Option<rapier3d::parry::partitioning::Bvh>,
    elements: usize,
}

impl RopeBroadPhase {
    /// The broad phase of the elements between `nodes` (world, m), element
    /// `i` padded by `pad(i)` (m).
    fn new(nodes: &[DVec3], pad: impl Fn(usize) -> f64) -> Self {
        let elements = nodes.len().saturating_sub(1);
        let mut leaves = Vec::with_capacity(elements.div_ceil(BROAD_RUN));
        for run in 0..elements.div_ceil(BROAD_RUN) {
            let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            let mut finite = true;
            for i in run * BROAD_RUN..((run + 1) * BROAD_RUN).min(elements) {
                let p = DVec3::splat(pad(i));
                // (`min` and `max` pass a NaN over: test each box.)
                let (a, b) = (nodes[i].min(nodes[i + 1]) - p, nodes[i].max(nodes[i + 1]) + p);
                finite &= a.is_finite() && b.is_finite() && nodes[i].is_finite() && nodes[i + 1].is_finite();
                lo = lo.min(a);
                hi = hi.max(b);
            }
            let Some(aabb) = outward(lo, hi).filter(|_| finite) else {
                return RopeBroadPhase { bvh: None, elements };
            };
            leaves.push((run, aabb));
        }
        let bvh = rapier3d::parry::partitioning::Bvh::from_iter(rapier3d::parry::partitioning::BvhBuildStrategy::Binned, leaves);
        RopeBroadPhase { bvh: Some(bvh), elements }
    }

    /// The elements of the runs whose boxes overlap the box `lo`–`hi`
    /// (world, m), in order.
    fn elements_near(&self, lo: DVec3, hi: DVec3) -> Vec<usize> {
        let runs: Vec<usize> = match (&self.bvh, outward(lo, hi)) {
            (Some(bvh), Some(aabb)) => {
                let mut runs: Vec<usize> = bvh.intersect_aabb(&aabb).map(|r| r as usize).collect();
                runs.sort_unstable();
                runs
            }
            _ => (0..self.elements.div_ceil(BROAD_RUN)).collect(),
        };
        runs.into_iter().flat_map(|r| r * BROAD_RUN..((r + 1) * BROAD_RUN).min(self.elements)).collect()
    }
}

/// The box `lo`–`hi` (m) widened by a relative 1e-9 (and 1e-9 m), in
/// `f32`, rounded outwards; `None` if it is not finite.
fn outward(lo: DVec3, hi: DVec3) -> Option<rapier3d::parry::bounding_volume::Aabb> {
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let widen = |p: DVec3| (p.abs() + DVec3::ONE) * 1e-9;
    let (lo, hi) = (lo - widen(lo), hi + widen(hi));
    let down = |x: f64| {
        let f = x as f32;
        if f as f64 > x {
            f.next_down()
        } else {
            f
        }
    };
    let up = |x: f64| {
        let f = x as f32;
        if (f as f64) < x {
            f.next_up()
        } else {
            f
        }
    };
    let v = |p: DVec3, r: &dyn Fn(f64) -> f32| glam::Vec3::new(r(p.x), r(p.y), r(p.z));
    Some(rapier3d::parry::bounding_volume::Aabb::new(v(lo, &down), v(hi, &up)))
}

/// Adds this step's contacts of every rope of `cable` against the
/// fixed and kinematic colliders of `world` (sensors, dynamic bodies and
/// the bodies in `exclude` skipped), each as a [`SphereContact`] force
/// element. Every node within the speculative margin of a collider gets one
/// (on the tangent plane at the collider's nearest point), and so does an
/// element whose nearest point to the collider lies inside it, nearer
/// than both its nodes (a rope over an edge). `h` (s) sets the margin:
/// `2 h |v| + h² |g|` plus the rope's radius beyond the rope's surface at
/// the step's start (`v` the faster of the element's nodes). Returns how
/// fast the contacts may close (m/s), and the node whose surface lies
/// deepest inside a collider ([`Deepest`]; none if none is inside).
#[allow(clippy::too_many_arguments)]
pub(crate) fn add_contacts(
    cable: &mut Cable,
    contact: &CableContact,
    memory: &mut FrictionMemory,
    world: &Contacts<'_>,
    bodies: &rp::RigidBodySet,
    exclude: &[rp::RigidBodyHandle],
    h: f64,
    start: f64,
) -> (f64, Option<Deepest>) {
    let mut approach = 0.0f64;
    let mut deepest: Option<Deepest> = None;
    let radius = 0.5 * cable.model.diameter;
    let gravity = cable.model.chain.gravity.length();
    // Each rope's nodes and their velocities, read once (a read walks the
    // rope).
    let ropes: Vec<(usize, Vec<DVec3>, Vec<DVec3>)> = (0..cable.ropes()).filter_map(|r| cable.rope(r).map(|v| (r, v.nodes(), v.node_velocities()))).collect();
    let accelerations = node_accelerations(cable, memory, &ropes);
    // Only colliders near the cable: its nodes' box padded by the widest
    // element box below (`radius + reach`, at the fastest node).
    let extent = CableExtent::of_nodes(ropes.iter().map(|(_, p, v)| (&p[..], &v[..])));
    let fastest_change = accelerations.iter().flatten().fold(gravity, |m, a| m.max(*a));
    let widest = 2.0 * radius + 2.0 * h * extent.fastest + h * h * fastest_change;
    let region = (extent.lo - DVec3::splat(widest), extent.hi + DVec3::splat(widest));
    let obstacles = Obstacle::all(world, bodies, exclude, (cable.time(), start), Some(region), Some(contact));
    for ((rope, nodes, velocities), accelerations) in ropes.into_iter().zip(accelerations) {
        let Some(view) = cable.rope(rope) else {
            continue;
        };
        let layout = *view.layout();
        let element_length = layout.element_length;
        let n = nodes.len().saturating_sub(1);
        // Nodes held by a pin, a clamp or an anchor spring, or at a carried
        // body, get no contact: the rope is fastened there, often on a
        // collider's face (a hook under a beam), and a contact would fight
        // the fastening (measured: the hanging_payload demo's rope, pinned
        // to the gantry beam's underside, pulled 337 kN).
        let (held_first, held_last) = held_ends(cable, &view);
        // Speculative reach of each element beyond the rope's surface:
        // what it may travel in the step (twice its speed, plus twice
        // what its acceleration, at least gravity's, adds from rest),
        // plus one radius.
        let reach: Vec<f64> = (0..n)
            .map(|i| {
                radius + 2.0 * h * velocities[i].length().max(velocities[i + 1].length()) + h * h * gravity.max(accelerations[i]).max(accelerations[i + 1])
            })
            .collect();
        let mut hits: Vec<(f64, SphereContact)> = Vec::new();
        let broad = RopeBroadPhase::new(&nodes, |i| radius + reach[i]);
        for obstacle in &obstacles {
            let (cmin, cmax) = obstacle.aabb();
            // What the obstacle itself may move in the step.
            let own_reach = 2.0 * h * obstacle.speed();
            // The elements whose padded boxes may overlap it (every one
            // that `near` below keeps), and their nodes.
            let candidates = broad.elements_near(cmin - DVec3::splat(own_reach), cmax + DVec3::splat(own_reach));
            if candidates.is_empty() {
                continue;
            }
            let mut candidate_nodes: Vec<usize> = candidates.iter().flat_map(|&i| [i, i + 1]).collect();
            candidate_nodes.dedup();
            let co = obstacle.collider;
            let mu = combine(contact.friction, co.friction() as f64, rp::CoefficientCombineRule::Average, co.friction_combine_rule());
            let reach = |i: usize| reach[i] + own_reach;
            let site = |site: usize| Site::Rope { rope, site, obstacle: obstacle.handle };
            let mut add = |memory: &mut FrictionMemory, at: usize, s: f64, element: SphereContact, fraction| {
                let c = memory.note(site(at), element, mu, fraction, [obstacle.collider.parent(), None]);
                hits.push((s, c));
            };
            // An element's interior at `s` (m) over the surface point
            // `hit`: the contact of its segment on a curve or a box's edge
            // or corner ([`Obstacle::element_contact`]).
            let interior = |s: f64, hit: (DVec3, DVec3, f64)| match cable.rope_point(rope, s) {
                Some((_, local)) => obstacle.element_contact(hit, radius, contact.law, Span { axis: DVec3::X, lo: -local.x, hi: element_length - local.x }),
                None => obstacle.contact(hit, radius, contact.law),
            };
            let near = |i: usize| {
                let (a, b) = (nodes[i], nodes[i + 1]);
                let pad = DVec3::splat(radius + reach(i));
                !((a.min(b) - pad).cmpgt(cmax).any() || (a.max(b) + pad).cmplt(cmin).any())
            };
            // On a ball, a capsule or a cylinder's round side every element
            // within reach touches as a capsule: its segment against the
            // curved surface ([`Span`]), wherever it slides or turns within
            // the step; on a box, every element whose nearest point is on
            // an edge or a corner, against that edge's line or the corner
            // (`box_edge_foot`: the square beam's Atwood machine took 43
            // Newton iterations per step with the nodes' edge planes, 32
            // with these). (With contacts at the nodes and at interiors nearer
            // than both nodes, found at the step's start, a rope hauled
            // over a 2 cm bar turned an element onto the bar within a step
            // with no contact there, and the next step found it inside:
            // the rope caught on the bar and Newton failed.) Their nodes'
            // own contacts are left out where an element beside them has
            // one: the segment's nearest point is the node when that is
            // nearest. (Not at a held end, as there: an element whose
            // nearest point is its fastened node gets none.)
            let spans: Vec<(usize, (f64, DVec3, DVec3, f64))> = candidates
                .iter()
                .filter(|&&i| near(i))
                .filter_map(|&i| {
                    let (a, b) = (obstacle.local(nodes[i]), obstacle.local(nodes[i + 1]));
                    let (f, q, normal, gap) = match co.shape().as_cuboid() {
                        Some(c) => box_edge_foot(c.half_extents.as_dvec3(), a, b),
                        None => round_foot(co.shape(), a, b),
                    }?;
                    let fastened = (i == 0 && held_first && f <= 0.0) || (i + 1 == n && held_last && f >= 1.0);
                    (gap - radius <= reach(i) && !fastened).then_some((i, (f, q, normal, gap)))
                })
                .collect();
            // Which elements have one (by index; empty if none).
            let mut touching = vec![false; if spans.is_empty() { 0 } else { n }];
            for &(i, _) in &spans {
                touching[i] = true;
            }
            let has_span = |i: usize| touching.get(i).copied().unwrap_or(false);
            let spanned = |k: usize| has_span(k) || (k > 0 && has_span(k - 1));
            // Nodes.
            for k in candidate_nodes.into_iter().filter(|&k| !((k == 0 && held_first) || (k == n && held_last))) {
                let reach_k = reach(k.min(n.saturating_sub(1))).max(if k > 0 { reach(k - 1) } else { 0.0 });
                let touches = (k < n && near(k)) || (k > 0 && near(k - 1));
                if !touches {
                    continue;
                }
                // An obstacle moving near the rope drags it: its own speed
                // counts too (a node it carries along closes at 0).
                approach = approach.max(obstacle.speed());
                let Some(hit) = obstacle.nearest(nodes[k]) else {
                    continue;
                };
                // How fast the node and the obstacle close, within reach or
                // not (the step's contact passes follow it).
                let (q, normal) = (obstacle.origin + obstacle.rotation * hit.0, obstacle.rotation * hit.1);
                approach = approach.max(-(velocities[k] - obstacle.surface_velocity(q)).dot(normal));
                if radius - hit.2 > deepest.map_or(0.0, |d| d.depth) {
                    deepest = Some(Deepest { rope, node: k, element: None, point: nodes[k], depth: radius - hit.2 });
                }
                if hit.2 - radius <= reach_k && !(spanned(k) && (round_at(co.shape(), hit.0, hit.1).is_some() || obstacle.edge_curve(hit.0).is_some())) {
                    add(memory, 2 * k, k as f64 * element_length, obstacle.contact(hit, radius, contact.law), 0.0);
                }
            }
            for &(i, (f, q, normal, gap)) in &spans {
                let (a, b) = (nodes[i], nodes[i + 1]);
                if f > 0.02 && f < 0.98 && radius - gap > deepest.map_or(0.0, |d| d.depth) {
                    let node = if f < 0.5 { i } else { i + 1 };
                    deepest = Some(Deepest { rope, node, element: Some(i), point: a.lerp(b, f), depth: radius - gap });
                }
                // At the material point of the last step (the friction's
                // anchor; the contact itself is at the segment's nearest
                // point wherever that is), else at the nearest point.
                let f = memory.kept_fraction(site(2 * i + 1), f);
                let s = (i as f64 + f) * element_length;
                add(memory, 2 * i + 1, s, interior(s, (q, normal, gap)), f);
            }
            // Element interiors nearer than both their nodes.
            for i in candidates.into_iter().filter(|&i| near(i) && !has_span(i)) {
                let (a, b) = (obstacle.local(nodes[i]), obstacle.local(nodes[i + 1]));
                let along = (b - a).normalize();
                let dist = |f: f64| obstacle.nearest_local(a.lerp(b, f)).map_or(f64::INFINITY, |hit| hit.2);
                // The distance to a convex shape is convex along the
                // element. A quarter-point below both ends starts a search
                // around it; a straight run along a face has none. Else,
                // if the distance falls from an end inward, the minimum is
                // searched over the whole element (quarter points alone
                // missed an edge 15 % in from a node, and the element went
                // through it).
                let (d0, d1) = (dist(0.0), dist(1.0));
                let ends = d0.min(d1);
                let quarter = [0.25, 0.5, 0.75].map(|f| (f, dist(f))).into_iter().filter(|(_, d)| *d < ends - 1e-3 * radius).min_by(|x, y| x.1.total_cmp(&y.1));
                let falls = || dist(EDGE_FRACTION) < d0 - 1e-3 * radius || dist(1.0 - EDGE_FRACTION) < d1 - 1e-3 * radius;
                let Some((best, span, iterations, whole)) = quarter.map(|(f, _)| (f, 0.25, 24, false)).or_else(|| falls().then_some((0.5, 0.5, 30, true)))
                else {
                    // The element is nearest at a node that sits over an
                    // edge or a corner: within the step the rope may slide
                    // or turn so that the edge comes under the element's
                    // interior, which no node contact holds (a rope
                    // sliding off a plate over its edge went 0.40 mm into
                    // it without this contact, 0.14 mm with it). A contact a little
                    // in from that node, of the element's segment against
                    // the edge on a box (else on the plane through the
                    // edge square to the element), holds the element on
                    // the edge wherever it slides.
                    let free = |k: usize| !((k == 0 && held_first) || (k == n && held_last));
                    let (end, k, f, into) = if d0 <= d1 { (a, i, EDGE_FRACTION, along) } else { (b, i + 1, 1.0 - EDGE_FRACTION, -along) };
                    if free(k) {
                        if let Some(((q, _, gap), true)) = obstacle.nearest_local_and_edge(end) {
                            let m = end - q;
                            let normal = (m - m.dot(along) * along).normalize();
                            // Only where the edge lies beside the element,
                            // not behind its node: there the element's
                            // line, not the element, passes the edge (the
                            // element beyond the node has its own check).
                            let beside = (q - end).dot(into) > 0.0;
                            if beside && gap - radius <= reach(i) && normal.is_finite() {
                                let kept = if co.shape().as_cuboid().is_some() {
                                    memory.kept_fraction(site(2 * i + 1), f)
                                } else {
                                    memory.fraction(site(2 * i + 1), f)
                                };
                                let f = kept.clamp(EDGE_FRACTION, 1.0 - EDGE_FRACTION);
                                let s = (i as f64 + f) * element_length;
                                add(memory, 2 * i + 1, s, interior(s, (q, normal, m.dot(normal))), f);
                            }
                        }
                    }
                    continue;
                };
                let f = convex_min(dist, best - span, best + span, iterations);
                let d = dist(f);
                // An element laid through a thin post or across an edge
                // overlaps the collider between its nodes, which may both
                // lie outside it.
                if f > 0.02 && f < 0.98 && radius - d > deepest.map_or(0.0, |d| d.depth) {
                    let node = if f < 0.5 { i } else { i + 1 };
                    deepest = Some(Deepest { rope, node, element: Some(i), point: nodes[i].lerp(nodes[i + 1], f), depth: radius - d });
                }
                if f > 0.02 && f < 0.98 && d < ends - 1e-3 * radius && d - radius <= reach(i) {
                    // At an edge (the nearest surface point on an edge or
                    // a vertex) the contact is at the element's nearest
                    // point now, even where it sits at the material point
                    // of the last step (friction's anchor): on a box, of
                    // the element's segment against the edge's line or the
                    // corner ([`Obstacle::element_contact`]: held on the
                    // edge wherever the rope slides or turns within the
                    // step); on other shapes, on the plane through the
                    // edge square to the element (its normal the common
                    // perpendicular of the element and the edge, so every
                    // point of the element has the same distance from it).
                    // (At the material point's own nearest surface point
                    // the normal tilted toward the element: a rope sliding
                    // off a plate over its edge sank a radius into it
                    // within a step.)
                    // Inside the shape the nearest face may not be the one
                    // the element came through: an element sunk a little
                    // near a box's edge has the side face nearest, a plane
                    // it crosses steeply, which cannot hold it up. Then
                    // the segment's own way out and the shape's supporting
                    // plane across it are used. Elsewhere (a face, a
                    // curved surface) the plane is at the contact's own
                    // point, as before; a minimum found only by the whole
                    // element's search is kept at edges alone (on a
                    // drum it added contacts beside the nodes' and moved
                    // the capstan's slip ratio by 6 %).
                    let p = a.lerp(b, f);
                    let steep = |hit: &(DVec3, DVec3, f64)| hit.2 < 0.0 && hit.1.dot(along).abs() > 0.5;
                    let here = obstacle.nearest_local_and_edge(p);
                    // (On a box's edge the contact is of the segment: its
                    // material point kept, see `kept_fraction`.)
                    let anchored = match here {
                        Some((hit, true)) if !steep(&hit) && co.shape().as_cuboid().is_some() => memory.kept_fraction(site(2 * i + 1), f),
                        _ => memory.fraction(site(2 * i + 1), f),
                    };
                    let s = (i as f64 + anchored) * element_length;
                    let element = match here {
                        Some((hit, _)) if steep(&hit) => Some(obstacle.contact(obstacle.segment_plane(a, b, p).unwrap_or(hit), radius, contact.law)),
                        Some((hit, true)) => Some(interior(s, hit)),
                        _ if whole => continue,
                        _ if anchored != f => obstacle.nearest_local(a.lerp(b, anchored)).map(|hit| interior(s, hit)),
                        _ => here.map(|(hit, _)| interior(s, hit)),
                    };
                    if let Some(element) = element {
                        add(memory, 2 * i + 1, s, element, anchored);
                    }
                }
            }
        }
        for (s, element) in hits {
            let added = cable.add_force_element(rope, s, Arc::new(element));
            debug_assert!(added, "rope {rope} exists");
        }
    }
    (approach, deepest)
}

/// Each rope's node accelerations (m/s², magnitudes) for the reach of
/// [`add_contacts`]: the change of the nodes' velocities (`ropes`: each
/// rope's index, nodes and node velocities now) since the cable's last
/// search, over its time; at a cable's first search, from its
/// consistent start acceleration ([`start_accelerations`]); at a search
/// at or before the last one's time (a step or pass taken again), the
/// last search's. Remembers the velocities and the accelerations for
/// the next search.
///
/// Gravity alone in the reach missed contacts a rope accelerating faster
/// than that runs into within one step: a steel rope laid round a drum
/// 2 cm off its surface (bent, not moulded), let go under a 200 kg
/// payload, sprang onto it at 22 g and ended its first frame step 8 mm
/// inside with no contact, which the next search then found and turned
/// into a 10⁷ N push (the run diverged at 0.017 s).
fn node_accelerations(cable: &mut Cable, memory: &mut FrictionMemory, ropes: &[(usize, Vec<DVec3>, Vec<DVec3>)]) -> Vec<Vec<f64>> {
    let t = cable.time();
    let fits = |old: &[Vec<DVec3>]| old.len() == ropes.len() && old.iter().zip(ropes).all(|(o, r)| o.len() == r.2.len());
    let lengths = |vectors: &[Vec<DVec3>]| vectors.iter().map(|r| r.iter().map(|a| a.length()).collect()).collect();
    let (out, vectors) = match memory.searched.take() {
        Some(last) if last.time < t && fits(&last.velocities) => {
            let dt = t - last.time;
            let changes: Vec<Vec<DVec3>> = ropes.iter().zip(&last.velocities).map(|((_, _, v), o)| v.iter().zip(o).map(|(v, o)| *v - *o).collect()).collect();
            (
                changes.iter().map(|r| r.iter().map(|d| d.length() / dt).collect()).collect(),
                changes.iter().map(|r| r.iter().map(|d| *d / dt).collect()).collect(),
            )
        }
        Some(last) if fits(&last.velocities) => (last.accelerations, last.vectors),
        _ if cable.steps == 0 => {
            let vectors = start_accelerations(cable, ropes);
            (lengths(&vectors), vectors)
        }
        _ => (ropes.iter().map(|(_, _, v)| vec![0.0; v.len()]).collect(), ropes.iter().map(|(_, _, v)| vec![DVec3::ZERO; v.len()]).collect()),
    };
    memory.searched = Some(Search { time: t, velocities: ropes.iter().map(|(_, _, v)| v.clone()).collect(), accelerations: out.clone(), vectors });
    out
}

impl FrictionMemory {
    /// The node accelerations (world, m/s², per rope of the cable) of
    /// `cable`'s first search for colliders ([`add_contacts`], from its
    /// consistent start acceleration), while the cable has taken no step;
    /// empty after (see [`rope_pairs`]).
    pub(crate) fn start_accelerations_of(&self, cable: &Cable) -> &[Vec<DVec3>] {
        match &self.searched {
            Some(s) if cable.steps == 0 && s.time == cable.time() => &s.vectors,
            _ => &[],
        }
    }
}

/// [`node_accelerations`] at a cable's first search: the nodes'
/// velocities for the generalized velocities `a` (its consistent start
/// acceleration), `J a`, by a kinematics pass, which is then made again
/// at the state. They include the base's velocity at that time (a moving
/// support's speed read as an acceleration: a larger reach, no missed
/// contact). Zero if a kinematics pass fails.
fn start_accelerations(cable: &mut Cable, ropes: &[(usize, Vec<DVec3>, Vec<DVec3>)]) -> Vec<Vec<DVec3>> {
    let zero: Vec<Vec<DVec3>> = ropes.iter().map(|(_, _, v)| vec![DVec3::ZERO; v.len()]).collect();
    let (t, q, v, a) = (cable.state.t, cable.state.q.clone(), cable.state.v.clone(), cable.state.a.clone());
    let zeros = vec![0.0; q.len()];
    let out = if cable.model.chain.kinematics(t, &q, &a, &zeros).is_ok() {
        ropes
            .iter()
            .zip(&zero)
            .map(|((r, ..), z)| cable.rope(*r).map(|view| view.node_velocities()).filter(|x| x.len() == z.len()).unwrap_or_else(|| z.clone()))
            .collect()
    } else {
        zero
    };
    let _ = cable.model.chain.kinematics(t, &q, &v, &a);
    out
}

/// A rope node, or an element's interior, whose surface lies inside a
/// collider ([`add_contacts`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Deepest {
    /// Rope of the chain.
    pub rope: usize,
    /// Node index from that rope's start (the nearer node of the element,
    /// for a point inside one).
    pub node: usize,
    /// The element whose interior lies deepest, if it is not a node.
    pub element: Option<usize>,
    /// The node or the element's deepest point, world, m.
    pub point: DVec3,
    /// How deep its surface lies inside the collider's, m (its radius
    /// less its centre's distance from the collider's surface).
    pub depth: f64,
}

/// The contact law of a carried body's touch points: steel on steel,
/// Hertz with R* = 10 mm (a corner or an edge rounded to 1 cm), damping
/// ramped in over 1e-5 m to the critical damping of a quarter of the
/// body's mass `mass` (kg) on the contact's stiffness there (four corners
/// share a resting box).
fn body_law(mass: f64) -> Result<ImpactLaw, ContactError> {
    steel_law(0.01, 0.25 * mass)
}

/// Points of a collider shape that can touch an obstacle, in the shape's
/// frame, each with the radius of the sphere around it (m): a ball's centre
/// with its radius, a capsule's two segment ends with its radius, a
/// cuboid's eight corners, a cylinder's two rims (16 points each), a cone's
/// apex and base rim (16 points), a convex polyhedron's, a triangle mesh's,
/// a segment's or a triangle's vertices, a compound's parts' points placed
/// by their poses, and a rounded shape's inner points with its border
/// radius added. Heightfields, polylines and voxels: none (a body carried
/// in a chain with such a collider still reaches it through rapier's
/// impulse, one step late).
fn touch_points(shape: &dyn rp::Shape) -> Vec<(DVec3, f64)> {
    let vertices = |v: &[rp::Vector]| v.iter().map(|v| (v.as_dvec3(), 0.0)).collect::<Vec<_>>();
    let rim = |r: f64, y: f64| {
        (0..16).map(move |k| {
            let a = std::f64::consts::TAU * k as f64 / 16.0;
            (DVec3::new(r * a.cos(), y, r * a.sin()), 0.0)
        })
    };
    let rounded = |inner: Vec<(DVec3, f64)>, border: f32| inner.into_iter().map(|(q, r)| (q, r + border as f64)).collect::<Vec<_>>();
    if let Some(b) = shape.as_ball() {
        return vec![(DVec3::ZERO, b.radius as f64)];
    }
    if let Some(c) = shape.as_capsule() {
        return vec![(c.segment.a.as_dvec3(), c.radius as f64), (c.segment.b.as_dvec3(), c.radius as f64)];
    }
    if let Some(c) = shape.as_cuboid() {
        let e = c.half_extents.as_dvec3();
        return (0..8)
            .map(|k| (DVec3::new(if k & 1 == 0 { -e.x } else { e.x }, if k & 2 == 0 { -e.y } else { e.y }, if k & 4 == 0 { -e.z } else { e.z }), 0.0))
            .collect();
    }
    if let Some(c) = shape.as_cylinder() {
        let (r, h) = (c.radius as f64, c.half_height as f64);
        return rim(r, -h).chain(rim(r, h)).collect();
    }
    if let Some(c) = shape.as_cone() {
        let (r, h) = (c.radius as f64, c.half_height as f64);
        return rim(r, -h).chain(std::iter::once((DVec3::new(0.0, h, 0.0), 0.0))).collect();
    }
    if let Some(p) = shape.as_convex_polyhedron() {
        return vertices(p.points());
    }
    if let Some(m) = shape.as_trimesh() {
        return vertices(m.vertices());
    }
    if let Some(s) = shape.as_segment() {
        return vertices(&[s.a, s.b]);
    }
    if let Some(t) = shape.as_triangle() {
        return vertices(&[t.a, t.b, t.c]);
    }
    if let Some(c) = shape.as_compound() {
        return c
            .shapes()
            .iter()
            .flat_map(|(pose, part)| {
                let (t, r) = (pose.translation.as_dvec3(), DMat3::from_quat(pose.rotation.as_dquat().normalize()));
                touch_points(part.as_ref()).into_iter().map(move |(q, radius)| (t + r * q, radius))
            })
            .collect();
    }
    if let Some(s) = shape.as_round_cuboid() {
        return rounded(touch_points(&s.inner_shape), s.border_radius);
    }
    if let Some(s) = shape.as_round_cylinder() {
        return rounded(touch_points(&s.inner_shape), s.border_radius);
    }
    if let Some(s) = shape.as_round_cone() {
        return rounded(touch_points(&s.inner_shape), s.border_radius);
    }
    if let Some(s) = shape.as_round_convex_polyhedron() {
        return rounded(touch_points(&s.inner_shape), s.border_radius);
    }
    if let Some(s) = shape.as_round_triangle() {
        return rounded(touch_points(&s.inner_shape), s.border_radius);
    }
    Vec::new()
}

/// [`touch_points`] of `collider`, in its body's frame (m).
fn placed_touch_points(collider: &rp::Collider) -> Vec<(DVec3, f64)> {
    let (lt, lr) = offset(collider);
    touch_points(collider.shape()).into_iter().map(|(q, radius)| (lt + lr * q, radius)).collect()
}

/// Adds this step's contacts of the bodies the chain carries against the
/// colliders of fixed and kinematic bodies (their own cable's bodies and
/// sensors left out): each touch point of each of a body's colliders
/// ([`touch_points`]) within the speculative reach of an obstacle gets a
/// [`SphereContact`] on the body's link, so a payload set down on the
/// ground rests on it inside the implicit solve instead of through
/// rapier's impulse one step late. Returns whether any was added.
#[allow(clippy::too_many_arguments)]
pub(crate) fn add_body_contacts(
    cable: &mut Cable,
    carried: &[CarriedLink],
    memory: &mut FrictionMemory,
    world: &Contacts<'_>,
    bodies: &rp::RigidBodySet,
    exclude: &[rp::RigidBodyHandle],
    h: f64,
    start: f64,
) -> (bool, f64) {
    let mut approach = 0.0f64;
    let gravity = cable.model.chain.gravity.length();
    let touches: Vec<(&rp::RigidBody, BodyTouch)> = carried
        .iter()
        .filter_map(|c| {
            let state = cable.model.body_state(&c.place);
            Some((bodies.get(c.body)?, BodyTouch { body: c.body, mass: c.mass, state, link: c.place.link, place: (c.place.origin, c.place.rotation) }))
        })
        .collect();
    // Only colliders near the bodies' touch points, each padded by its
    // reach below.
    let mut region = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for (rb, touch) in &touches {
        for (point, radius, speed) in touch.points(rb, world.colliders) {
            let pad = DVec3::splat(radius + 2.0 * h * speed + h * h * gravity + 0.01);
            region = (region.0.min(point - pad), region.1.max(point + pad));
        }
    }
    let obstacles = Obstacle::all(world, bodies, exclude, (cable.time(), start), Some(region), None);
    let mut hits: Vec<AttachedForce> = Vec::new();
    for (rb, touch) in &touches {
        approach = approach.max(touch.add(rb, world.colliders, &obstacles, memory, gravity, h, &mut hits));
    }
    let any = !hits.is_empty();
    cable.model.chain.forces_mut().extend(hits);
    (any, approach)
}

/// A rigid body in a chain, for its contacts with fixed and kinematic
/// colliders: the rapier body, its mass (kg), its frame's pose and
/// velocity in the chain (origin (m), rotation, origin velocity (m/s),
/// angular velocity (rad/s)), and the link that carries it with the
/// body frame's pose in that link's frame.
struct BodyTouch {
    body: rp::RigidBodyHandle,
    mass: f64,
    state: (DVec3, DMat3, DVec3, DVec3),
    link: usize,
    place: (DVec3, DMat3),
}

impl BodyTouch {
    /// Each touch point of `rb`'s non-sensor colliders: where it is (world,
    /// m), its radius (m) and its speed (m/s), as [`BodyTouch::add`] takes
    /// them.
    fn points(&self, rb: &rp::RigidBody, colliders: &rp::ColliderSet) -> Vec<(DVec3, f64, f64)> {
        let (p, r, v, w) = self.state;
        body_touch_points(rb, colliders).into_iter().map(|(q, radius, _)| (p + r * q, radius, (v + w.cross(r * q)).length())).collect()
    }

    /// Pushes onto `hits` a [`SphereContact`] for each touch point
    /// ([`touch_points`]) of each of `rb`'s non-sensor colliders within
    /// the speculative reach (over `h` s, under `gravity` m/s²) of one of
    /// `obstacles`, noted in `memory` for its friction. Returns how fast
    /// they may close (m/s).
    #[allow(clippy::too_many_arguments)]
    fn add(
        &self,
        rb: &rp::RigidBody,
        colliders: &rp::ColliderSet,
        obstacles: &[Obstacle<'_>],
        memory: &mut FrictionMemory,
        gravity: f64,
        h: f64,
        hits: &mut Vec<AttachedForce>,
    ) -> f64 {
        let mut approach = 0.0f64;
        let Ok(law) = body_law(self.mass) else {
            return approach;
        };
        let (p, r, v, w) = self.state;
        for own in rb.colliders() {
            let Some(collider) = colliders.get(*own) else {
                continue;
            };
            if collider.is_sensor() {
                continue;
            }
            let points = placed_touch_points(collider);
            for obstacle in obstacles.iter().filter(|o| colliders_touch(collider, o.collider)) {
                let (cmin, cmax) = obstacle.aabb();
                let co = obstacle.collider;
                let mu = combine(collider.friction() as f64, co.friction() as f64, collider.friction_combine_rule(), co.friction_combine_rule());
                let own_reach = 2.0 * h * obstacle.speed();
                for (point, (q, radius)) in points.iter().enumerate() {
                    let world_point = p + r * *q;
                    let speed = (v + w.cross(r * *q)).length();
                    let reach = 2.0 * h * speed + h * h * gravity + 0.01 + own_reach;
                    let pad = DVec3::splat(radius + reach);
                    if (world_point - pad).cmpgt(cmax).any() || (world_point + pad).cmplt(cmin).any() {
                        continue;
                    }
                    let Some(hit) = obstacle.nearest(world_point) else {
                        continue;
                    };
                    let (sq, sn) = (obstacle.origin + obstacle.rotation * hit.0, obstacle.rotation * hit.1);
                    approach = approach.max(-(v + w.cross(r * *q) - obstacle.surface_velocity(sq)).dot(sn));
                    if hit.2 - radius > reach {
                        continue;
                    }
                    let site = Site::Body { collider: *own, point, obstacle: obstacle.handle };
                    let mut contact = obstacle.contact(hit, *radius, law);
                    // (Against a moving collider only a new touch point's
                    // overlap: `FrictionMemory::sunk`.)
                    let fixed = obstacle.body.is_none_or(|b| b.is_fixed());
                    let offset = memory.sunk(site, radius - hit.2, fixed);
                    contact.point -= contact.normal * offset;
                    let element = memory.note_sunk(site, contact, mu, 0.0, [co.parent(), Some(self.body)], offset);
                    hits.push(AttachedForce { link: self.link, local_point: self.place.0 + self.place.1 * *q, element: Arc::new(element) });
                }
            }
        }
        approach
    }
}

/// Whether the contacts of `rb` with fixed and kinematic colliders can be
/// solved with it ([`add_free_body_contacts`]): every non-sensor collider
/// of it has touch points ([`touch_points`]).
pub(crate) fn touches_are_solved(rb: &rp::RigidBody, colliders: &rp::ColliderSet) -> bool {
    rb.colliders().iter().filter_map(|c| colliders.get(*c)).filter(|c| !c.is_sensor()).all(|c| !touch_points(c.shape()).is_empty())
}

/// Most a free body new to an island is moved out of the fixed and
/// kinematic colliders it starts in (a touch point's depth, m;
/// [`out_of_obstacles`]): rapier's resting contacts sink about 70 µm.
/// One deeper starts where it is, its contacts' overlap taken as an
/// offset ([`FrictionMemory::sunk`]): moved out by centimetres, it would
/// be pushed into a rope lying on it.
pub(crate) const GROUNDED_DEPTH: f64 = 1e-3;

/// Growth of a body touch point's depth between two steps (m) beyond
/// which it counts as rapier's doing ([`FrictionMemory::sunk`]): more
/// than the rounding of a pose to rapier's f32 (about 1e-7 m).
pub(crate) const SUNK_TOLERANCE: f64 = 1e-6;

/// Where a free body new to an island (the rapier body `handle` with its
/// frame at `origin`, turned by `rotation`) starts its step with its
/// contacts with fixed and kinematic colliders solved in the island: moved
/// out of those it sinks into, along the deepest touch point's normal, a
/// few times over, while the deepest is no deeper than
/// [`GROUNDED_DEPTH`] (`origin` itself if rapier no longer has the body).
/// Rapier's resting contact lets a box on the ground sink about 70 µm (its
/// allowed error); the island's steel contact law, met at that depth,
/// threw a 20 kg box 6 mm up when it joined a rope's step (a rope let go
/// on it). Moving the body out adds no velocity. A body sunk deeper stays
/// where it is, and its contacts start from their overlap
/// ([`FrictionMemory::sunk`]). (Before, 2026-11-27, such a body was left
/// to rapier's contacts while the island moved it too: rapier lifted a
/// crate laid 5 cm into the ground by 1 cm in a step, into a rope lying on
/// it, which was thrown and failed the solve; and a crate laid half into
/// the ground, in the island's steel law without the offset, was thrown
/// 1.6 km.)
pub(crate) fn out_of_obstacles(
    handle: rp::RigidBodyHandle,
    (origin, rotation): (DVec3, DMat3),
    world: &Contacts<'_>,
    bodies: &rp::RigidBodySet,
    now: f64,
) -> DVec3 {
    let Some(rb) = bodies.get(handle) else {
        return origin;
    };
    let obstacles = Obstacle::all(world, bodies, &[handle], (now, now), None, None);
    let points = body_touch_points(rb, world.colliders);
    moved_out((origin, rotation), &points, &obstacles, GROUNDED_DEPTH, |obstacle, p, radius, own| {
        if !colliders_touch(own, obstacle.collider) {
            return None;
        }
        let (cmin, cmax) = obstacle.aabb();
        if (p - radius).cmpgt(cmax).any() || (p + radius).cmplt(cmin).any() {
            return None;
        }
        obstacle.nearest(p).map(|hit| (radius - hit.2, obstacle.rotation * hit.1))
    })
}

/// The touch points ([`placed_touch_points`]) of `rb`'s non-sensor
/// colliders, in its frame (m), each with its radius (m) and its collider.
fn body_touch_points<'c>(rb: &rp::RigidBody, colliders: &'c rp::ColliderSet) -> Vec<(DVec3, f64, &'c rp::Collider)> {
    rb.colliders()
        .iter()
        .filter_map(|c| colliders.get(*c))
        .filter(|c| !c.is_sensor())
        .flat_map(|c| placed_touch_points(c).into_iter().map(move |(q, radius)| (q, radius, c)))
        .collect()
}

/// A body's frame `origin` (turned by `rotation`) moved out of `surfaces`
/// along the normal of its deepest touch point (`points`, body frame, with
/// their radii and colliders), up to four times, while that depth is
/// positive and at most `limit` (m): `depth(surface, point, radius,
/// collider)` gives a world touch point's depth into a surface and the
/// surface's outward world normal there (`None`: no touch, or the two
/// colliders' groups keep them apart). The surfaces are searched in
/// order, each over every point; the first of equal depths wins.
fn moved_out<S>(
    (origin, rotation): (DVec3, DMat3),
    points: &[(DVec3, f64, &rp::Collider)],
    surfaces: &[S],
    limit: f64,
    depth: impl Fn(&S, DVec3, f64, &rp::Collider) -> Option<(f64, DVec3)>,
) -> DVec3 {
    let mut origin = origin;
    for _ in 0..4 {
        let mut deepest: Option<(f64, DVec3)> = None;
        for surface in surfaces {
            for (q, radius, own) in points {
                if let Some((d, normal)) = depth(surface, origin + rotation * *q, *radius, own) {
                    if d > deepest.map_or(0.0, |d| d.0) {
                        deepest = Some((d, normal));
                    }
                }
            }
        }
        match deepest {
            Some((d, normal)) if d <= limit => origin += normal * d,
            _ => break,
        }
    }
    origin
}

/// `origin` (the frame of free body `handle`, turned by `rotation`) moved
/// out of the colliders of the bodies `carried` (each cable's, at the
/// cable's pose) that its touch points overlap, but those in `resting`
/// (held on them by the island at the last step): a body that struck a
/// carried body in rapier's last step, into which rapier let it go before
/// it met it (a 20 kg ball falling 8 cm a frame: 5 cm into a plank), as
/// rapier moves a body out of a fixed one (over half a second there; here
/// at once, as [`out_of_obstacles`] does). The island's pair would keep
/// that overlap while the two touch ([`pair_overlap`]). Adds no velocity.
pub(crate) fn out_of_carried(
    handle: rp::RigidBodyHandle,
    (origin, rotation): (DVec3, DMat3),
    carried: &[(&Cable, &[CarriedLink])],
    resting: &[rp::RigidBodyHandle],
    bodies: &rp::RigidBodySet,
    colliders: &rp::ColliderSet,
) -> DVec3 {
    let Some(rb) = bodies.get(handle) else {
        return origin;
    };
    let points = body_touch_points(rb, colliders);
    let mut surfaces: Vec<(&rp::Collider, DVec3, DMat3)> = Vec::new();
    for (cable, links) in carried {
        for c in links.iter().filter(|c| !resting.contains(&c.body) && c.body != handle) {
            let Some(body) = bodies.get(c.body) else {
                continue;
            };
            let (p, r, _, _) = cable.model.body_state(&c.place);
            surfaces.extend(BodyShapes::of(body, colliders).colliders.into_iter().map(|(co, lt, lr)| (co, p + r * lt, r * lr)));
        }
    }
    moved_out((origin, rotation), &points, &surfaces, f64::INFINITY, |&(co, o, r), at, radius, own| {
        if !colliders_touch(own, co) {
            return None;
        }
        nearest(co.shape(), r.transpose() * (at - o)).map(|(_, normal, d)| (radius - d, r * normal))
    })
}

/// Adds this pass's contacts of a free body of an island (the rapier body
/// `handle`, as the chain `body`) against the fixed and kinematic
/// colliders, as [`add_body_contacts`] does for a carried body: a box on
/// the ground that a rope lands on rests on the ground inside the
/// island's solve. Its friction anchors are `memory`'s (`memory` takes
/// this pass's contacts; [`FrictionMemory::remember`] after the pass).
#[allow(clippy::too_many_arguments)]
pub(crate) fn add_free_body_contacts(
    body: &mut crate::cable::FreeBody,
    handle: rp::RigidBodyHandle,
    memory: &mut FrictionMemory,
    world: &Contacts<'_>,
    bodies: &rp::RigidBodySet,
    h: f64,
    now: f64,
    start: f64,
) {
    let Some(rb) = bodies.get(handle) else {
        return;
    };
    memory.discard_step();
    let (origin, rotation) = body.pose();
    let (velocity, angular_velocity) = body.velocity();
    let frame_velocity = velocity - angular_velocity.cross(rotation * body.com);
    let touch = BodyTouch {
        body: handle,
        mass: body.mass,
        state: (origin, rotation, frame_velocity, angular_velocity),
        link: crate::cable::FreeBody::LINK,
        place: (DVec3::ZERO, DMat3::IDENTITY),
    };
    let obstacles = Obstacle::all(world, bodies, &[handle], (now, start), None, None);
    let mut hits = Vec::new();
    touch.add(rb, world.colliders, &obstacles, memory, body.chain.gravity.length(), h, &mut hits);
    let chain = &mut body.chain;
    let fixed = chain.forces_mut().len();
    chain.forces_mut().extend(hits);
    memory.attach(chain, fixed);
}

/// Drops the force elements past `keep` and the pair elements past
/// `keep_pairs` (the last step's contacts).
pub(crate) fn clear(cable: &mut Cable, keep: usize, keep_pairs: usize) {
    cable.model.chain.forces_mut().truncate(keep);
    cable.model.chain.pairs_mut().truncate(keep_pairs);
    cable.model.chain.clear_external();
}

/// Whether a rope's first and last nodes (in its user's direction) are
/// held: by a pin, a clamp or an anchor spring, or at a carried body.
fn held_ends(cable: &Cable, view: &crate::cable::RopeView<'_>) -> (bool, bool) {
    let layout = *view.layout();
    let first_link = layout.element_link(0);
    let last_link = layout.element_link(layout.elements - 1);
    let anchored = |link: usize| cable.model.chain.anchors().iter().any(|a| a.link == link);
    let held_start = !layout.free_start || anchored(first_link);
    let held_end = layout.end_body.is_some() || anchored(last_link);
    if view.reversed() {
        (held_end, held_start)
    } else {
        (held_start, held_end)
    }
}

/// An element of one of a cable's ropes at the step's start, for the
/// contacts of ropes with each other.
struct Segment {
    cable: usize,
    rope: usize,
    element: usize,
    a: DVec3,
    b: DVec3,
    /// The rope's nodes before `a` and after `b`, if any.
    before: Option<DVec3>,
    after: Option<DVec3>,
    va: DVec3,
    vb: DVec3,
    /// The nodes' accelerations (m/s², zero where not known).
    aa: DVec3,
    ab: DVec3,
    element_length: f64,
    radius: f64,
    /// The arc lengths (m) from the rope's start within which a touch is
    /// left out (a held end's neighbourhood), and from which on again.
    free: (f64, f64),
}

/// Whether the rope comes nearer to `q` (m) than its node `node` does, to
/// first order, going from the node towards either neighbour in `sides`
/// (the nodes beside it along the rope). A node's touch counts only where
/// the rope is nearest at the node (its bend's outer corner, or a rope
/// lying along the other, square to it): a node beside the crossing of
/// two ropes sliding over each other touches the other rope's surface
/// only as the rope does there, but its normal, frozen for the step, is
/// tilted, and the other rope slid into that plane (a rope sliding down
/// two rails jolted at every rail node and lost a third of its friction).
fn nearer_beside(node: DVec3, q: DVec3, sides: [Option<DVec3>; 2]) -> bool {
    let n = node - q;
    sides.into_iter().flatten().any(|side| {
        let d = side - node;
        n.dot(d) < -1e-6 * n.length() * d.length()
    })
}

/// Where along an element, as a fraction from the node, the contact of an
/// element whose node sits over an obstacle's edge goes
/// ([`add_contacts`]).
const EDGE_FRACTION: f64 = 0.05;

/// The minimum of `f`, convex on `[lo, hi]`, by `iterations` steps of a
/// ternary search: the middle of the last bracket.
fn convex_min(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, iterations: usize) -> f64 {
    for _ in 0..iterations {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if f(m1) <= f(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    0.5 * (lo + hi)
}

/// The parameter `t` in [0, 1] of the point of the segment `a + t (b − a)`
/// nearest to `p`.
fn closest_on_segment(a: DVec3, b: DVec3, p: DVec3) -> f64 {
    let d = b - a;
    let l2 = d.length_squared();
    if l2 <= 1e-300 {
        return 0.0;
    }
    ((p - a).dot(d) / l2).clamp(0.0, 1.0)
}

/// The parameters `(s, t)` in [0, 1] of the closest points of the
/// segments `p1 + s (q1 − p1)` and `p2 + t (q2 − p2)`.
fn closest_on_segments(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> (f64, f64) {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    if a <= 1e-300 && e <= 1e-300 {
        return (0.0, 0.0);
    }
    if a <= 1e-300 {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(r);
    if e <= 1e-300 {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    let mut s = if denom > 1e-12 * a * e { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// Adds this step's contacts of `cable` with itself: every two elements
/// of its ropes (of one rope, or of two ropes of its tree) whose capsules
/// of the rope's radius come within the speculative reach get a
/// [`PairContact`] (see [`rope_pairs`]).
/// Returns how fast the contacts close (m/s), for the step's passes.
pub(crate) fn add_self_contacts(cable: &mut Cable, contact: &CableContact, memory: &mut FrictionMemory, h: f64) -> f64 {
    let accelerations = memory.start_accelerations_of(cable);
    if cannot_touch_itself(cable, accelerations, h) {
        return 0.0;
    }
    let (pairs, approach) = rope_pairs(&[(&*cable, contact)], &[accelerations], h, true);
    // Each with its friction, from the same touch at the end of the last
    // step.
    let chain = &cable.model.chain;
    let attached: Vec<AttachedPair> = pairs
        .iter()
        .map(|p| {
            let (a, b) = (chain_point(chain, p.link_a, p.point_a), chain_point(chain, p.link_b, p.point_b));
            let recalled = FrictionMemory::recall([&memory.own_pairs[..]], (a.point + b.point) * 0.5);
            let (element, offset) = recalled_pair(p.element, p.mu, &a, &b, recalled);
            memory.pair_step.push((element, offset));
            AttachedPair { link_a: p.link_a, point_a: p.point_a, link_b: p.link_b, point_b: p.point_b, element: Arc::new(element) }
        })
        .collect();
    cable.model.chain.pairs_mut().extend(attached);
    approach[0]
}

/// Whether two elements of one rope, `apart` elements apart along it
/// (1: neighbours), are too near along the rope to touch each other: the
/// rope between them is shorter than half a turn around the rope (`π r`,
/// `radius` r and `element_length` in m). A rope cannot fold that tight,
/// and neighbours always touch. [`rope_pairs`] leaves such pairs out, and
/// [`cannot_touch_itself`] starts past them.
fn too_near_along(apart: usize, element_length: f64, radius: f64) -> bool {
    (apart.saturating_sub(1) as f64) * element_length < std::f64::consts::PI * radius
}

/// Whether `cable`, a single rope, is too little bent to touch itself in
/// a step of `h` s: then [`rope_pairs`] would find no pair and no pair
/// near enough to count for the step's passes, and its search is skipped
/// (on a swinging 1 000-element rope it was 5 % of the step).
///
/// The bound: if the rope's element directions turn by Θ < π in all, every
/// direction lies within Θ/2 of one (the middle of their path on the unit
/// sphere), so two points of the rope an arc `s` apart are at least
/// `s cos(Θ/2)` apart. [`rope_pairs`] looks at elements `m` apart only for
/// `(m − 1) L_e ≥ π r`, and drops a pair whose midpoints are farther apart
/// than their half lengths, the two radii and `2 h` times their nodes'
/// fastest relative speed plus half a radius. Their midpoints are at
/// least `c (m − 1) ℓ_min − (1 − c) ℓ_max` beyond their half lengths
/// (`c = cos(Θ/2)`, `ℓ` the elements' lengths now), and their nodes move
/// apart at most at `(m + 1) J` (`J` the largest velocity difference of
/// two neighbouring nodes). The rope cannot touch itself when that margin
/// exceeds `2.5 r + 2 h (m + 1) J` for every `m` looked at, with `Θ`
/// taken as the turn over `m` joints (at most `m` times the sharpest, and
/// at most the whole rope's): checked up to the `m` where that reaches
/// the whole rope's turn, beyond which the margin grows with `m`. Each
/// angle between two unit directions is bounded by
/// `|t₁ − t₂|/√(1 − |t₁ − t₂|²/4)` (no inverse trigonometry; within 1e-4
/// of the angle for the 0.025 rad between elements of a 0.8π arc of 100
/// elements).
fn cannot_touch_itself(cable: &Cable, accelerations: &[Vec<DVec3>], h: f64) -> bool {
    if cable.ropes() != 1 {
        return false;
    }
    let Some(view) = cable.rope(0) else {
        return false;
    };
    let (nodes, velocities) = (view.nodes(), view.node_velocities());
    let n = nodes.len().saturating_sub(1);
    if n < 3 {
        return false;
    }
    let radius = 0.5 * cable.model.diameter;
    let element_length = view.layout().element_length;
    let (mut total, mut sharpest, mut jump, mut shortest, mut longest) = (0.0f64, 0.0f64, 0.0f64, f64::INFINITY, 0.0f64);
    let mut last: Option<DVec3> = None;
    for i in 0..n {
        let d = nodes[i + 1] - nodes[i];
        let length = d.length();
        shortest = shortest.min(length);
        longest = longest.max(length);
        let t = d / length;
        if let Some(prev) = last {
            // θ = 2 asin(x) ≤ 2 tan(asin(x)) = 2x/√(1 − x²), x = |Δt|/2:
            // tight for the small turns between elements.
            let chord2 = (t - prev).length_squared();
            if chord2 >= 3.99 {
                return false;
            }
            let turn = (chord2 / (1.0 - 0.25 * chord2)).sqrt();
            total += turn;
            sharpest = sharpest.max(turn);
        }
        last = Some(t);
        jump = jump.max((velocities[i + 1] - velocities[i]).length());
    }
    // What the nodes' accelerations add over the step (`h² |Δa|` between
    // neighbours), as [`rope_pairs`] counts it.
    if let Some(a) = accelerations.first().filter(|a| a.len() == nodes.len()) {
        let jump_a = a.windows(2).map(|w| (w[1] - w[0]).length()).fold(0.0f64, f64::max);
        jump += 0.5 * h * jump_a;
    }
    if !(total.is_finite() && shortest > 0.0 && jump.is_finite()) {
        return false;
    }
    // Elements `m` apart turn by at most `m` times the sharpest turn, and
    // by at most the total. The least `m` that `rope_pairs` looks at:
    let first = (1..n).find(|&m| !too_near_along(m, element_length, radius)).unwrap_or(n);
    for m in first..n {
        let turn = (m as f64 * sharpest).min(total);
        if turn >= std::f64::consts::PI {
            return false;
        }
        let (c, m) = ((0.5 * turn).cos(), m as f64);
        let margin = c * (m - 1.0) * shortest - (1.0 - c) * longest - 2.5 * radius - 2.0 * h * (m + 1.0) * jump;
        if margin <= 1e-3 * radius {
            return false;
        }
        // From here on the turn is the total and the margin grows with m.
        if turn == total {
            return c * shortest > 2.0 * h * jump;
        }
    }
    true
}

/// A contact between two rope elements found by [`rope_pairs`]: the
/// cables (indices into its list), links and points of its two ends.
pub(crate) struct RopePair {
    pub cable_a: usize,
    pub link_a: usize,
    pub point_a: DVec3,
    pub cable_b: usize,
    pub link_b: usize,
    pub point_b: DVec3,
    pub element: PairContact,
    /// The friction coefficient between the two (≥ 0).
    pub mu: f64,
}

/// A node of one of two elements: `(true, n)` the first element's rope's
/// node `n`, `(false, n)` the second's.
type NodeOf = (bool, usize);

/// A touch between two ropes found by [`rope_pairs`], before the
/// duplicates are dropped: the distance between the centrelines (m),
/// where it is on each rope (cable, rope, arc length in radii), for a
/// node's touch the node and the other rope (cable, rope, node, cable,
/// rope), and the contact.
struct Found {
    distance: f64,
    at: [(usize, usize, f64); 2],
    key: Option<(usize, usize, usize, usize, usize)>,
    pair: RopePair,
}

/// The elements of `segments` (with their `boxes`, min and max corners, m)
/// whose box overlaps the box around all the elements of another of the
/// `cables` cables, in their order: those that may touch another cable.
fn reaching_other_cables(segments: &[Segment], boxes: &[(DVec3, DVec3)], cables: usize) -> Vec<usize> {
    let mut around = vec![(DVec3::INFINITY, DVec3::NEG_INFINITY); cables];
    for (g, (lo, hi)) in segments.iter().zip(boxes) {
        let b = &mut around[g.cable];
        *b = (b.0.min(*lo), b.1.max(*hi));
    }
    let overlap = |a: &(DVec3, DVec3), b: &(DVec3, DVec3)| !(a.0.cmpgt(b.1).any() || a.1.cmplt(b.0).any());
    // Only the cables whose boxes overlap another's are searched further.
    let near: Vec<Vec<usize>> = (0..cables).map(|c| (0..cables).filter(|&d| d != c && overlap(&around[c], &around[d])).collect()).collect();
    (0..segments.len()).filter(|&i| near[segments[i].cable].iter().any(|&d| overlap(&boxes[i], &around[d]))).collect()
}

/// This step's contacts between rope elements of `cables` (each with its
/// contact settings): of one rope with itself, of two ropes of a cable's
/// tree, and of two cables. Every two elements whose capsules (each of its
/// rope's radius) come within the speculative reach (twice what their
/// relative speed closes in the step, plus half the smaller radius) get a
/// [`PairContact`] between their nearest material points, with the
/// direction between them as its normal, frozen for the step. Elements of
/// one rope nearer along it than half a turn of the rope around itself
/// (`π r`) are left out: a rope cannot fold that tight, and neighbours
/// always touch. Between two cables the law is the softer of the two
/// cables' (the lower `K`). Candidates come from a sweep over the
/// elements' boxes along the axis of their largest spread (O(n log n) for
/// ropes that are not balled up). `within`: the pairs within each cable
/// (its ropes with themselves and each other), else only those between
/// two cables. `accelerations`: per cable, its ropes' node accelerations
/// at its first step (world, m/s²; [`FrictionMemory::start_accelerations_of`],
/// empty after it): an element's reach counts what its acceleration adds
/// over the step (`h² |a|`, relative to the others), as a collider
/// contact's does ([`add_contacts`]), so that a rope laid bent near itself
/// and let go from rest (a loose knot), whose speeds give no reach, finds
/// the touches it springs into within its first step. Only then: with the
/// accelerations of a whipping rope (the change of its speeds between
/// searches) in every step's reach, the pairs found far within it, their
/// normals frozen for the step, pushed the slack legs of an undamped sling
/// apart with 95 J the run did not have
/// (`scenarios::an_undamped_sling_laid_slack_from_one_hook_never_gains_energy`).
/// Returns the pairs and, per cable, how fast its contacts close (m/s:
/// their fastest relative node speed, and for a touch within reach its
/// speed plus what its acceleration adds in the step; not what the
/// accelerations of near elements without a touch add: at a slack rope's
/// first step the start accelerations of the elements next to a pin
/// differ by 2 000 m/s², which as a closing speed asked for passes no
/// touch needed), for the step's passes.
pub(crate) fn rope_pairs(cables: &[(&Cable, &CableContact)], accelerations: &[&[Vec<DVec3>]], h: f64, within: bool) -> (Vec<RopePair>, Vec<f64>) {
    let mut segments = Vec::new();
    // Two elements close at their relative speed: each box is padded by
    // the rope's radius and twice its speed relative to the mean of all
    // the elements (a swinging rope's elements move together; two boxes'
    // pads then add up to at least twice the two elements' relative
    // speed).
    for (c, (cable, _)) in cables.iter().enumerate() {
        let radius = 0.5 * cable.model.diameter;
        for rope in 0..cable.ropes() {
            let Some(view) = cable.rope(rope) else {
                continue;
            };
            let (nodes, velocities) = (view.nodes(), view.node_velocities());
            let element_length = view.layout().element_length;
            // Near a held end the rope is fastened, often at the same
            // point as another rope (a pendant and a hoist rope at a boom
            // tip): no touch there, within an element or half a turn
            // around the rope (`π r`), whichever is longer.
            let (held_first, held_last) = held_ends(cable, &view);
            let margin = element_length.max(std::f64::consts::PI * radius);
            let length = view.length();
            let free = (if held_first { margin } else { f64::NEG_INFINITY }, if held_last { length - margin } else { f64::INFINITY });
            let known = accelerations.get(c).and_then(|a| a.get(rope)).filter(|a| a.len() == nodes.len());
            let acceleration = |k: usize| known.map_or(DVec3::ZERO, |a| a[k]);
            for i in 0..nodes.len().saturating_sub(1) {
                let (va, vb) = (velocities[i], velocities[i + 1]);
                let (aa, ab) = (acceleration(i), acceleration(i + 1));
                let (before, after) = (i.checked_sub(1).map(|k| nodes[k]), nodes.get(i + 2).copied());
                segments.push(Segment {
                    cable: c,
                    rope,
                    element: i,
                    a: nodes[i],
                    b: nodes[i + 1],
                    before,
                    after,
                    va,
                    vb,
                    aa,
                    ab,
                    element_length,
                    radius,
                    free,
                });
            }
        }
    }
    let mean = segments.iter().fold(DVec3::ZERO, |m, g| m + g.va + g.vb) / (2.0 * segments.len().max(1) as f64);
    let mean_a = segments.iter().fold(DVec3::ZERO, |m, g| m + g.aa + g.ab) / (2.0 * segments.len().max(1) as f64);
    let pads: Vec<f64> = segments
        .iter()
        .map(|g| g.radius + 2.0 * h * (g.va - mean).length().max((g.vb - mean).length()) + h * h * (g.aa - mean_a).length().max((g.ab - mean_a).length()))
        .collect();
    let boxes: Vec<(DVec3, DVec3)> = segments.iter().zip(&pads).map(|(g, &pad)| (g.a.min(g.b) - DVec3::splat(pad), g.a.max(g.b) + DVec3::splat(pad))).collect();
    // Candidates: a sweep over the boxes along the axis in which the
    // elements spread most (a rope's length, for a rope that is not balled
    // up, so each element meets only its neighbours along the rope and
    // whatever crosses it). Sorted with a total order: the same pairs in
    // the same order on every run (each pair with its lower-numbered
    // element first).
    let (lo_all, hi_all) = boxes.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), b| (l.min(b.0), h.max(b.1)));
    let spread = hi_all - lo_all;
    let axis = if spread.x >= spread.y && spread.x >= spread.z {
        0
    } else if spread.y >= spread.z {
        1
    } else {
        2
    };
    // Between cables, only the elements whose boxes reach into another
    // cable's box can touch it: the others are left out of the sweep. The
    // sweep alone met every element of each of 16 ropes hanging side by
    // side (each in its own plane across the sweep's axis) as a candidate
    // of every other of its rope, O(n²): 29 % of the step of 16 ropes of
    // 1 000 elements, for no pair at all.
    let mut order: Vec<usize> = if within { (0..segments.len()).collect() } else { reaching_other_cables(&segments, &boxes, cables.len()) };
    order.sort_by(|&i, &j| boxes[i].0[axis].total_cmp(&boxes[j].0[axis]).then(i.cmp(&j)));
    let mut approach = vec![0.0f64; cables.len()];
    let mut found: Vec<Found> = Vec::new();
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if boxes[j].0[axis] > boxes[i].1[axis] {
                break;
            }
            let (gi, gj) = (&segments[i.min(j)], &segments[i.max(j)]);
            if (gi.cable == gj.cable) != within {
                continue;
            }
            if gi.cable != gj.cable && !cables[gi.cable].1.groups.test(cables[gj.cable].1.groups) {
                continue;
            }
            let same_rope = gi.cable == gj.cable && gi.rope == gj.rope;
            if same_rope && too_near_along(gi.element.abs_diff(gj.element), gi.element_length, gi.radius) {
                continue;
            }
            if boxes[j].0.cmpgt(boxes[i].1).any() || boxes[j].1.cmplt(boxes[i].0).any() {
                continue;
            }
            let (radii, least) = (gi.radius + gj.radius, gi.radius.min(gj.radius));
            // Cheap rejection first (most candidates are a rope's
            // neighbours moving with it): the midpoints farther apart than
            // the two half lengths, the two radii and the reach of their
            // fastest relative node motion.
            let fastest = (gi.va - gj.va).length().max((gi.va - gj.vb).length()).max((gi.vb - gj.va).length()).max((gi.vb - gj.vb).length());
            let fastest_change = (gi.aa - gj.aa).length().max((gi.aa - gj.ab).length()).max((gi.ab - gj.aa).length()).max((gi.ab - gj.ab).length());
            let half = 0.5 * (gi.a.distance(gi.b) + gj.a.distance(gj.b));
            if (gi.a + gi.b).distance(gj.a + gj.b) * 0.5 - half - radii > 2.0 * h * fastest + h * h * fastest_change + 0.5 * least {
                continue;
            }
            // Two elements this near count their fastest relative node
            // motion for the step's passes, touching or not (a rope
            // wrapping over another, or bouncing off it, moves its touch
            // points that fast: a swinging pendant hitting a taut rope
            // failed the step after the impact with one pass, whose
            // touches closed at under 1 m/s while the pendant's nodes
            // around them moved at 3 m/s).
            approach[gi.cable] = approach[gi.cable].max(fastest);
            approach[gj.cable] = approach[gj.cable].max(fastest);
            // The touches of the two capsules: each node of either element
            // against the other element (a rope wrapped over another, or
            // lying along it, is held at every node), and the nearest
            // points of the two when both lie inside their elements (two
            // ropes crossing between nodes).
            let (fa, fb) = closest_on_segments(gi.a, gi.b, gj.a, gj.b);
            // (fa, fb, and for a node's touch: whether the node is the
            // first element's, and which)
            let mut touches: Vec<(f64, f64, Option<NodeOf>)> = Vec::with_capacity(5);
            if fa > 0.0 && fa < 1.0 && fb > 0.0 && fb < 1.0 {
                touches.push((fa, fb, None));
            }
            // (A node only where it is nearer to the other element than the
            // rope on both sides of it, see `nearer_beside`.)
            for (k, node, sides) in [(0.0, gi.a, [Some(gi.b), gi.before]), (1.0, gi.b, [Some(gi.a), gi.after])] {
                let f = closest_on_segment(gj.a, gj.b, node);
                if !nearer_beside(node, gj.a.lerp(gj.b, f), sides) {
                    touches.push((k, f, Some((true, gi.element + k as usize))));
                }
            }
            for (k, node, sides) in [(0.0, gj.a, [Some(gj.b), gj.before]), (1.0, gj.b, [Some(gj.a), gj.after])] {
                let f = closest_on_segment(gi.a, gi.b, node);
                if !nearer_beside(node, gi.a.lerp(gi.b, f), sides) {
                    touches.push((f, k, Some((false, gj.element + k as usize))));
                }
            }
            for (fa, fb, vertex) in touches {
                let (sa, sb) = ((gi.element as f64 + fa) * gi.element_length, (gj.element as f64 + fb) * gj.element_length);
                if sa < gi.free.0 || sa > gi.free.1 || sb < gj.free.0 || sb > gj.free.1 {
                    continue;
                }
                let (pa, pb) = (gi.a.lerp(gi.b, fa), gj.a.lerp(gj.b, fb));
                let d = pa.distance(pb);
                let relative = gi.va.lerp(gi.vb, fa) - gj.va.lerp(gj.vb, fb);
                let change = gi.aa.lerp(gi.ab, fa) - gj.aa.lerp(gj.ab, fb);
                let reach = 2.0 * h * relative.length() + h * h * change.length() + 0.5 * least;
                if d - radii > reach || d <= 1e-9 * least {
                    continue;
                }
                // A touch within reach closes at most at its speed plus
                // what its acceleration adds in the step.
                let closing = relative.length() + h * change.length();
                approach[gi.cable] = approach[gi.cable].max(closing);
                approach[gj.cable] = approach[gj.cable].max(closing);
                let normal = (pa - pb) / d;
                let (ca, cb) = (cables[gi.cable].0, cables[gj.cable].0);
                let (Some((link_a, point_a)), Some((link_b, point_b))) = (ca.rope_point(gi.rope, sa), cb.rope_point(gj.rope, sb)) else {
                    continue;
                };
                let (la, lb) = (cables[gi.cable].1.law, cables[gj.cable].1.law);
                let law = if lb.stiffness < la.stiffness { lb } else { la };
                let element = PairContact::new(normal, radii, law);
                // Rope on rope: the two ropes' coefficients combined as
                // rapier's `Average`.
                let mu = 0.5 * (cables[gi.cable].1.friction + cables[gj.cable].1.friction);
                let at = [(gi.cable, gi.rope, sa / gi.radius), (gj.cable, gj.rope, sb / gj.radius)];
                // A node's touch is keyed by the node and the other rope.
                let key =
                    vertex.map(|(first, node)| if first { (gi.cable, gi.rope, node, gj.cable, gj.rope) } else { (gj.cable, gj.rope, node, gi.cable, gi.rope) });
                found.push(Found {
                    distance: d,
                    at,
                    key,
                    pair: RopePair { cable_a: gi.cable, link_a, point_a, cable_b: gj.cable, link_b, point_b, element, mu },
                });
            }
        }
    }
    // One contact per touch: a node found against both elements that meet
    // at the nearest point of the other rope, or two touches at the same
    // place found from both ropes. Nearest first, a touch is kept unless
    // one kept is of the same node against the same rope, or within a
    // twentieth of a radius of it along both ropes.
    let mut kept: Vec<usize> = Vec::new();
    let mut by_distance: Vec<usize> = (0..found.len()).collect();
    by_distance.sort_by(|&i, &j| found[i].distance.total_cmp(&found[j].distance).then(i.cmp(&j)));
    for i in by_distance {
        let ([a, b], key) = (found[i].at, found[i].key);
        let near = |k: &usize| {
            let ([ka, kb], kkey) = (found[*k].at, found[*k].key);
            let same_place = (ka.0, ka.1, kb.0, kb.1) == (a.0, a.1, b.0, b.1) && (ka.2 - a.2).abs() < 0.05 && (kb.2 - b.2).abs() < 0.05;
            same_place || (key.is_some() && kkey == key)
        };
        if !kept.iter().any(near) {
            kept.push(i);
        }
    }
    kept.sort_unstable();
    let mut found: Vec<Option<RopePair>> = found.into_iter().map(|f| Some(f.pair)).collect();
    let pairs = kept.into_iter().filter_map(|i| found[i].take()).collect();
    (pairs, approach)
}

/// A dynamic rapier body's colliders at a pose, for its contacts with
/// ropes: each collider's shape and its pose in the body's frame.
pub(crate) struct BodyShapes<'a> {
    pub colliders: Vec<(&'a rp::Collider, DVec3, DMat3)>,
}

/// The radius (m) of the largest of the bounding spheres, about their own
/// centres, of `rb`'s colliders (sensors too): with its angular speed, a
/// bound on how fast its surface moves.
pub(crate) fn body_extent(rb: &rp::RigidBody, colliders: &rp::ColliderSet) -> f64 {
    rb.colliders().iter().filter_map(|c| colliders.get(*c)).map(|c| c.shape().compute_local_bounding_sphere().radius as f64).fold(0.0, f64::max)
}

/// Where a cable's ropes are at a step's start: the box around all their
/// nodes (world, m) and the fastest node's speed (m/s), for
/// [`body_pairs`]'s first test. Computed once per cable and pass: reading
/// a rope's nodes walks it (O(n)), and a scene holds many bodies far from
/// every rope (1 000 crates resting 20 m from a 1 000-element rope made
/// its step ten times slower when each body read the rope again).
pub(crate) struct CableExtent {
    lo: DVec3,
    hi: DVec3,
    fastest: f64,
}

impl CableExtent {
    /// The extent of `cable`'s ropes now.
    pub fn of(cable: &Cable) -> Self {
        let ropes: Vec<(Vec<DVec3>, Vec<DVec3>)> = (0..cable.ropes()).filter_map(|r| cable.rope(r)).map(|v| (v.nodes(), v.node_velocities())).collect();
        Self::of_nodes(ropes.iter().map(|(p, v)| (&p[..], &v[..])))
    }

    /// The extent of ropes given by their nodes (m) and the nodes'
    /// velocities (m/s).
    fn of_nodes<'n>(ropes: impl IntoIterator<Item = (&'n [DVec3], &'n [DVec3])>) -> Self {
        let mut e = CableExtent { lo: DVec3::INFINITY, hi: DVec3::NEG_INFINITY, fastest: 0.0 };
        for (nodes, velocities) in ropes {
            for p in nodes {
                (e.lo, e.hi) = (e.lo.min(*p), e.hi.max(*p));
            }
            e.fastest = velocities.iter().map(|v| v.length()).fold(e.fastest, f64::max);
        }
        e
    }
}

impl<'a> BodyShapes<'a> {
    /// The non-sensor colliders of `rb`.
    pub fn of(rb: &rp::RigidBody, colliders: &'a rp::ColliderSet) -> Self {
        let colliders = rb
            .colliders()
            .iter()
            .filter_map(|h| colliders.get(*h))
            .filter(|c| !c.is_sensor())
            .map(|c| {
                let (t, r) = offset(c);
                (c, t, r)
            })
            .collect();
        BodyShapes { colliders }
    }
}

/// Contacts between the bodies a cable carries and a free body (a crate
/// resting on a payload, a ball on a plank hung on ropes), as pairs solved
/// in the cable's island with the free body's own chain (`chain_a` the
/// cable, `chain_b`/`link_b` the free body at pose `(origin, rotation)`
/// moving at up to `speed` m/s): each touch point ([`touch_points`]) of
/// the free body's colliders within the speculative reach over `h` s of
/// a carried body's collider, against its nearest surface point, and each
/// of the carried body's touch points against the free body's colliders;
/// steel on steel ([`body_law`], the lighter body's mass), the colliders'
/// combined friction. A carried body that the free body strikes (one of
/// its touch points closing faster than `strike`'s speed, m/s, unless the
/// island held the two together or rapier met their strike at the last
/// step, `strike`'s list; the step's start gives two frame steps of
/// gravity, its passes `None`) is
/// left to rapier, whose restitution the strike keeps
/// (`reweigh_strikes`), as are the carried bodies in `leave` (struck at
/// the step's start). Rapier meets a carried body as a free body of its
/// own mass, one step behind the cable: a 20 kg ball resting on a 10 kg
/// plank hung on two steel ropes sank 11 cm into it, and a 60 kg ball
/// went through (2026-11-29). Returns the pairs, how fast they may close
/// (m/s), and the carried bodies touched and struck ([`CarriedPairs`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn carried_pairs(
    cable: &Cable,
    carried: &[CarriedLink],
    chain_a: usize,
    (bodies, colliders): (&rp::RigidBodySet, &rp::ColliderSet),
    (free_mass, shapes): (f64, &BodyShapes<'_>),
    (origin, rotation): (DVec3, DMat3),
    (velocity, angular_velocity, com): (DVec3, DVec3, DVec3),
    speed: f64,
    (chain_b, link_b): (usize, usize),
    (h, strike): (f64, Option<(f64, &[rp::RigidBodyHandle])>),
    leave: &[rp::RigidBodyHandle],
) -> CarriedPairs {
    let gravity = cable.model.chain.gravity.length();
    let mut pairs = Vec::new();
    let (mut touched, mut struck) = (Vec::new(), Vec::new());
    let mut approach = 0.0f64;
    // (collider, its pose in the world, its box)
    fn placed<'c>(list: &BodyShapes<'c>, o: DVec3, r: DMat3) -> Vec<(&'c rp::Collider, DVec3, DMat3, (DVec3, DVec3))> {
        list.colliders.iter().map(|&(c, lt, lr)| (c, o + r * lt, r * lr, placed_aabb(c, o + r * lt, r * lr))).collect()
    }
    let free = placed(shapes, origin, rotation);
    for c in carried.iter().filter(|c| !leave.contains(&c.body)) {
        let Some(rb) = bodies.get(c.body) else {
            continue;
        };
        let Ok(law) = body_law(free_mass.min(c.mass)) else {
            continue;
        };
        let (p, r, v, w) = cable.model.body_state(&c.place);
        let mine_shapes = BodyShapes::of(rb, colliders);
        let mine = placed(&mine_shapes, p, r);
        let closing = speed + v.length() + w.length() * body_extent(rb, colliders);
        let reach = 2.0 * h * closing + h * h * gravity + 0.01;
        let pad = DVec3::splat(reach);
        let to_link = |q: DVec3| c.place.origin + c.place.rotation * q;
        let before = pairs.len();
        // (Whether a touch point closes fast.)
        let mut fast = false;
        // How fast a carried point and a free one close along `n` (from
        // the free point to the carried one): a strike, closing faster than
        // `strike`, is rapier's (its restitution); bodies the island held
        // together stay the island's however fast the cable jerks the
        // carried one (a crate on a pallet a hook snatches up).
        let centre = origin + rotation * com;
        let closing_at = |on_carried: DVec3, on_free: DVec3, n: DVec3| {
            let vc = v + w.cross(on_carried - p);
            let vf = velocity + angular_velocity.cross(on_free - centre);
            -(vc - vf).dot(n)
        };
        for &(mc, mo, mr, (mlo, mhi)) in &mine {
            for &(fc, fo, fr, (flo, fhi)) in &free {
                if !colliders_touch(mc, fc) || (mlo - pad).cmpgt(fhi).any() || (mhi + pad).cmplt(flo).any() {
                    continue;
                }
                let mu = combine(mc.friction() as f64, fc.friction() as f64, mc.friction_combine_rule(), fc.friction_combine_rule());
                approach = approach.max(closing);
                // The free body's touch points on the carried collider, and
                // the carried body's on the free one: each a pair of the
                // carried link's point (first) and the free body's, the
                // normal from the free one to the carried one.
                for carried_touches in [false, true] {
                    let ((tc, to, tr), (sc, so, sr)) = if carried_touches { ((mc, mo, mr), (fc, fo, fr)) } else { ((fc, fo, fr), (mc, mo, mr)) };
                    let ((tlt, tlr), (slt, slr)) = (offset(tc), offset(sc));
                    for (q, radius) in touch_points(tc.shape()) {
                        let at = to + tr * q;
                        let Some((s, normal, d)) = nearest(sc.shape(), sr.transpose() * (at - so)) else {
                            continue;
                        };
                        if d - radius > reach {
                            continue;
                        }
                        // (Outward from the touched surface.)
                        let out = sr * normal;
                        let (on_carried, on_free, n) = if carried_touches { (at, so + sr * s, out) } else { (so + sr * s, at, -out) };
                        fast |= strike.is_some_and(|(s, resting)| !resting.contains(&c.body) && closing_at(on_carried, on_free, n) > s);
                        let (point_a, point_b) = if carried_touches { (tlt + tlr * q, slt + slr * s) } else { (slt + slr * s, tlt + tlr * q) };
                        let element = PairContact::new(n, radius, law);
                        pairs.push(RopePair {
                            cable_a: chain_a,
                            link_a: c.place.link,
                            point_a: to_link(point_a),
                            cable_b: chain_b,
                            link_b,
                            point_b,
                            element,
                            mu,
                        });
                    }
                }
            }
        }
        if fast {
            pairs.truncate(before);
            struck.push(c.body);
        } else if pairs.len() > before {
            touched.push(c.body);
        }
    }
    CarriedPairs { pairs, approach, touched, struck }
}

/// The world box (min, max corners, m) of `collider`'s shape placed at
/// `origin` turned by `rotation`.
fn placed_aabb(collider: &rp::Collider, origin: DVec3, rotation: DMat3) -> (DVec3, DVec3) {
    let pose = rp::Pose::from_parts(origin.as_vec3(), glam::DQuat::from_mat3(&rotation).normalize().as_quat());
    let aabb = collider.shape().compute_aabb(&pose);
    (aabb.mins.as_dvec3(), aabb.maxs.as_dvec3())
}

/// What [`carried_pairs`] found.
pub(crate) struct CarriedPairs {
    /// The pairs.
    pub pairs: Vec<RopePair>,
    /// How fast they may close, m/s.
    pub approach: f64,
    /// The carried bodies they touch.
    pub touched: Vec<rp::RigidBodyHandle>,
    /// The carried bodies the free body strikes (left to rapier).
    pub struck: Vec<rp::RigidBodyHandle>,
}

/// The contacts of `cable`'s rope nodes (chain `chain_a` of a forest) with
/// a free body (chain `chain_b`, its body link `link_b`) at the pose
/// `(origin, rotation)` moving at `speed` (m/s, a bound on its surface's
/// speed): each node not held, within the speculative reach of a
/// collider (its own and the body's motion over `h`, plus the rope's
/// radius and gravity's fall), gets a [`PairContact`] between it and the
/// nearest point of the collider's surface (a material point of the body),
/// the surface's outward normal frozen for the step; so does an element's
/// interior point nearer to the collider than both its nodes. Returns the
/// pairs and how fast they may close (m/s).
#[allow(clippy::too_many_arguments)]
pub(crate) fn body_pairs(
    (cable, extent): (&Cable, &CableExtent),
    contact: &CableContact,
    chain_a: usize,
    body: &BodyShapes<'_>,
    (origin, rotation): (DVec3, DMat3),
    speed: f64,
    chain_b: usize,
    link_b: usize,
    h: f64,
) -> (Vec<RopePair>, f64) {
    let radius = 0.5 * cable.model.diameter;
    let gravity = cable.model.chain.gravity.length();
    let mut pairs = Vec::new();
    let mut approach: f64 = 0.0;
    let aabb_at = |collider: &rp::Collider, lt: DVec3, lr: DMat3| placed_aabb(collider, origin + rotation * lt, rotation * lr);
    // The whole cable's box, padded by its fastest node's reach, first
    // (each rope's own test below is within it: the same collider boxes,
    // a smaller box and pad).
    let pad = DVec3::splat(radius + 2.0 * h * (extent.fastest + speed) + h * h * gravity);
    let near = |&&(collider, lt, lr): &&(&rp::Collider, DVec3, DMat3)| {
        let (lo, hi) = aabb_at(collider, lt, lr);
        !((extent.lo - pad).cmpgt(hi).any() || (extent.hi + pad).cmplt(lo).any())
    };
    if !body.colliders.iter().any(|c| near(&c)) {
        return (pairs, approach);
    }
    for rope in 0..cable.ropes() {
        let Some(view) = cable.rope(rope) else {
            continue;
        };
        let (nodes, velocities) = (view.nodes(), view.node_velocities());
        let element_length = view.layout().element_length;
        let n = nodes.len().saturating_sub(1);
        let (held_first, held_last) = held_ends(cable, &view);
        // The whole rope's box, padded by the farthest reach: most bodies
        // are nowhere near a rope.
        let fastest = velocities.iter().map(|v| v.length()).fold(0.0, f64::max);
        let pad = DVec3::splat(radius + 2.0 * h * (fastest + speed) + h * h * gravity);
        let (rope_lo, rope_hi) = nodes.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, u), p| (l.min(*p), u.max(*p)));
        for &(collider, lt, lr) in body.colliders.iter().filter(|(c, _, _)| contact.touches(c)) {
            let (co, cr) = (origin + rotation * lt, rotation * lr);
            let mu = combine(contact.friction, collider.friction() as f64, rp::CoefficientCombineRule::Average, collider.friction_combine_rule());
            let (lo, hi) = aabb_at(collider, lt, lr);
            if (rope_lo - pad).cmpgt(hi).any() || (rope_hi + pad).cmplt(lo).any() {
                continue;
            }
            for k in (0..=n).filter(|&k| !((k == 0 && held_first) || (k == n && held_last))) {
                let reach = radius + 2.0 * h * (velocities[k].length() + speed) + h * h * gravity;
                let p = nodes[k];
                if (p + DVec3::splat(reach)).cmplt(lo).any() || (p - DVec3::splat(reach)).cmpgt(hi).any() {
                    continue;
                }
                approach = approach.max(velocities[k].length() + speed);
                let Some((q, normal, d)) = nearest(collider.shape(), cr.transpose() * (p - co)) else {
                    continue;
                };
                if d - radius > reach {
                    continue;
                }
                let Some((link_a, point_a)) = cable.rope_point(rope, k as f64 * element_length) else {
                    continue;
                };
                let element = PairContact::new(cr * normal, radius, contact.law);
                pairs.push(RopePair { cable_a: chain_a, link_a, point_a, cable_b: chain_b, link_b, point_b: lt + lr * q, element, mu });
            }
            // Element interiors nearer than both their nodes (a ball
            // between two nodes; the distance to a convex shape is convex
            // along the element): the nearest point, by a ternary search.
            for i in 0..n {
                let (a, b) = (cr.transpose() * (nodes[i] - co), cr.transpose() * (nodes[i + 1] - co));
                let reach = radius + 2.0 * h * (velocities[i].length().max(velocities[i + 1].length()) + speed) + h * h * gravity;
                let (wa, wb) = (nodes[i], nodes[i + 1]);
                if (wa.min(wb) - DVec3::splat(reach)).cmpgt(hi).any() || (wa.max(wb) + DVec3::splat(reach)).cmplt(lo).any() {
                    continue;
                }
                let dist = |f: f64| nearest(collider.shape(), a.lerp(b, f)).map_or(f64::INFINITY, |hit| hit.2);
                let f = convex_min(dist, 0.0, 1.0, 30);
                let d = dist(f);
                if !(f > 1e-3 && f < 1.0 - 1e-3 && d < dist(0.0).min(dist(1.0)) - 1e-3 * radius && d - radius <= reach) {
                    continue;
                }
                let Some((q, normal, _)) = nearest(collider.shape(), a.lerp(b, f)) else {
                    continue;
                };
                let Some((link_a, point_a)) = cable.rope_point(rope, (i as f64 + f) * element_length) else {
                    continue;
                };
                let element = PairContact::new(cr * normal, radius, contact.law);
                pairs.push(RopePair { cable_a: chain_a, link_a, point_a, cable_b: chain_b, link_b, point_b: lt + lr * q, element, mu });
            }
        }
    }
    (pairs, approach)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cable::{RopeBuilder, RopeSection, RopeStart};
    use crate::integrate::Scheme;

    /// A free 20 mm steel rope of `n` elements along `path`, at rest.
    fn free_rope(length: f64, n: usize, path: Vec<DVec3>) -> Cable {
        let section = RopeSection { linear_density: 1.6, ea: 2e7, ei: 50.0, ei2: 50.0, gj: 35.0, min_breaking_load: 0.0 };
        let model = RopeBuilder::new(length, n, section, 0.02).start(RopeStart::Free).path(path).build().expect("rope");
        Cable::new(model, Scheme::default()).expect("cable")
    }

    /// An arc of radius `radius` (m) turning by `turn` (rad) in the x–y
    /// plane, as one path point per element.
    fn arc(radius: f64, turn: f64, n: usize) -> Vec<DVec3> {
        (0..=n).map(|k| radius * DVec3::new((turn * k as f64 / n as f64).sin(), 1.0 - (turn * k as f64 / n as f64).cos(), 0.0)).collect()
    }

    /// The self-contact search is skipped only where it finds nothing: a
    /// straight rope and an arc turning by 0.8π skip it (and the search
    /// itself finds no pair and no approach there); an arc turning by more
    /// than π (a hairpin whose legs lie 5 cm apart, and a whole turn) does
    /// not skip it, and the search finds the legs of a hairpin laid
    /// pressed together.
    #[test]
    fn a_rope_too_little_bent_to_touch_itself_skips_the_search_and_the_search_agrees() {
        let contact = CableContact::steel(0.02, 0.16).expect("law");
        let h = 1.0 / 60.0;
        let straight = free_rope(10.0, 100, vec![DVec3::ZERO, DVec3::new(10.0, 0.0, 0.0)]);
        let bent = free_rope(0.8 * std::f64::consts::PI * 2.0, 100, arc(2.0, 0.8 * std::f64::consts::PI, 100));
        for (name, cable) in [("straight", &straight), ("0.8π arc", &bent)] {
            assert!(cannot_touch_itself(cable, &[], h), "{name}: the search should be skipped");
            let (pairs, approach) = rope_pairs(&[(cable, &contact)], &[], h, true);
            assert!(pairs.is_empty() && approach[0] == 0.0, "{name}: the search found {} pairs, approach {}", pairs.len(), approach[0]);
        }
        for (radius, turn) in [(0.025, 1.05 * std::f64::consts::PI), (0.5, 2.0 * std::f64::consts::PI)] {
            let length = radius * turn;
            let cable = free_rope(length, 40, arc(radius, turn, 40));
            assert!(!cannot_touch_itself(&cable, &[], h), "turning by {turn} rad at r = {radius} m: the search should run");
        }
        // A hairpin: two 1 m legs 1.98 cm apart (centres: pressed 0.2 mm
        // into each other), joined by a half circle.
        let r = 0.0099;
        let mut path: Vec<DVec3> = (0..=20).map(|k| DVec3::new(-1.0 + 0.05 * k as f64, 0.0, 0.0)).collect();
        path.extend((1..20).map(|k| {
            let a = std::f64::consts::PI * k as f64 / 20.0;
            DVec3::new(r * a.sin(), r * (1.0 - a.cos()), 0.0)
        }));
        path.extend((0..=20).map(|k| DVec3::new(-0.05 * k as f64, 2.0 * r, 0.0)));
        let length = 2.0 + std::f64::consts::PI * r;
        let hairpin = free_rope(length, path.len() - 1, path);
        assert!(!cannot_touch_itself(&hairpin, &[], h));
        let (pairs, _) = rope_pairs(&[(&hairpin, &contact)], &[], h, true);
        assert!(!pairs.is_empty(), "the hairpin's legs touch");
    }

    /// The nearest point on a cuboid: a face's own normal; at an edge or a
    /// corner the direction from the nearest point to the query point (a
    /// plane that supports the box there), not parry's mean of the faces.
    #[test]
    fn an_edge_or_a_corner_pushes_along_the_nearest_direction_and_a_face_along_its_normal() {
        let cuboid = rp::SharedShape::cuboid(0.025, 2.0, 5.0);
        // Straight above the top face.
        let (q, n, d) = nearest(&*cuboid, DVec3::new(0.01, 2.3, 0.0)).unwrap();
        assert!((n - DVec3::Y).length() < 1e-12 && (q.y - 2.0).abs() < 1e-6 && (d - 0.3).abs() < 1e-6, "face: {q} {n} {d}");
        // Above, just beyond the top-right edge (x = 0.025): the edge is
        // nearest, 10 mm away almost straight down.
        let p = DVec3::new(0.026, 2.01, 0.0);
        let (q, n, d) = nearest(&*cuboid, p).unwrap();
        let expected = (p - q).normalize();
        assert!((q - DVec3::new(0.025, 2.0, 0.0)).length() < 1e-6, "edge point {q}");
        assert!((n - expected).length() < 1e-12 && n.y > 0.99, "edge normal {n} (parry's diagonal would be 0.707)");
        assert!((d - (p - q).length()).abs() < 1e-12, "edge distance {d}");
        // Beyond a corner.
        let p = DVec3::new(0.03, 2.02, 5.01);
        let (q, n, _) = nearest(&*cuboid, p).unwrap();
        assert!((q - DVec3::new(0.025, 2.0, 5.0)).length() < 1e-6 && (n - (p - q).normalize()).length() < 1e-12, "corner: {q} {n}");
        // Inside, nearest to the right face: that face's normal.
        let (_, n, d) = nearest(&*cuboid, DVec3::new(0.02, 0.0, 0.0)).unwrap();
        assert!((n - DVec3::X).length() < 1e-12 && (d + 0.005).abs() < 1e-6, "inside: {n} {d}");
    }

    /// The rope's broad phase keeps every element whose padded box
    /// overlaps a query box, as the exact per-element test finds them
    /// (so the contacts found do not change), on a random rope far from
    /// the origin (where `f32` rounds by 2e-3 m) against random boxes,
    /// some overlapping an element's box by less than that rounding, and
    /// against boxes padded the exact test's way (one sum of two pads)
    /// that touch an element's box to the last bit; and it searches under
    /// a tenth of the element tests a search of every element makes.
    #[test]
    fn the_broad_phase_keeps_every_element_the_exact_test_keeps() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let far = DVec3::new(3.0e4, -2.0e4, 1.0e4);
        let mut nodes = vec![far];
        for _ in 0..203 {
            let last = *nodes.last().unwrap();
            nodes.push(last + DVec3::new(0.3 + 0.1 * rnd(), 0.2 * rnd() - 0.1, 0.2 * rnd() - 0.1));
        }
        let pads: Vec<f64> = (0..203).map(|_| 0.01 + 0.05 * rnd()).collect();
        let broad = RopeBroadPhase::new(&nodes, |i| pads[i]);
        let element_box = |i: usize| (nodes[i].min(nodes[i + 1]) - DVec3::splat(pads[i]), nodes[i].max(nodes[i + 1]) + DVec3::splat(pads[i]));
        let (mut kept, mut searched) = (0, 0);
        for q in 0..400 {
            // A box beside a random element, touching it from outside by
            // 0 to 2 mm, or overlapping it.
            let i = (rnd() * 203.0) as usize;
            let (lo, hi) = element_box(i);
            let gap = if q % 2 == 0 { 2e-3 * rnd() } else { -0.05 * rnd() };
            let size = DVec3::splat(0.05 + 0.5 * rnd());
            let (qlo, qhi) = (DVec3::new(hi.x + gap, lo.y, lo.z), DVec3::new(hi.x + gap, lo.y, lo.z) + size);
            let exact: Vec<usize> = (0..203)
                .filter(|&k| {
                    let (l, h) = element_box(k);
                    !(l.cmpgt(qhi).any() || h.cmplt(qlo).any())
                })
                .collect();
            let near = broad.elements_near(qlo, qhi);
            assert!(exact.iter().all(|k| near.contains(k)), "query {q}: exact {exact:?}, broad phase {near:?}");
            assert!(near.windows(2).all(|w| w[0] < w[1]), "in order");
            kept += exact.len();
            searched += near.len();
        }
        println!("exact {kept}, searched {searched} of {} element tests", 400 * 203);
        assert!(searched < 400 * 203 / 10, "the broad phase searched {searched} elements");
        // One element far out, and boxes overlapping its padded box by
        // less than `f32`'s rounding there, on each side: never dropped.
        let one = [far, far + DVec3::new(0.3, 0.01, -0.02)];
        let single = RopeBroadPhase::new(&one, |_| 0.013);
        let (lo, hi) = (one[0].min(one[1]) - DVec3::splat(0.013), one[0].max(one[1]) + DVec3::splat(0.013));
        for q in 0..600 {
            let (axis, beyond) = (q % 3, q % 6 < 3);
            let overlap = 1e-3 * rnd();
            let (mut qlo, mut qhi) = (lo, hi);
            if beyond {
                qlo[axis] = hi[axis] - overlap;
                qhi[axis] = qlo[axis] + 0.1;
            } else {
                qhi[axis] = lo[axis] + overlap;
                qlo[axis] = qhi[axis] - 0.1;
            }
            assert_eq!(single.elements_near(qlo, qhi), vec![0], "box {q} overlapping by {overlap} m on axis {axis}");
        }
        // The exact test's padding (the element's pad and the obstacle's
        // in one sum) against the broad phase's (each box its own pad),
        // for boxes that touch: kept whenever the exact test keeps them.
        for q in 0..2000 {
            let i = (rnd() * 203.0) as usize;
            let own = 0.1 * rnd();
            let (a, b) = (nodes[i], nodes[i + 1]);
            let pad = DVec3::splat(pads[i] + own);
            let (ex_lo, ex_hi) = (a.min(b) - pad, a.max(b) + pad);
            // An obstacle box whose low corner is the exact box's high one.
            let (clo, chi) = (ex_hi, ex_hi + DVec3::splat(0.2));
            let exact = !((ex_lo).cmpgt(chi).any() || (ex_hi).cmplt(clo).any());
            let near = broad.elements_near(clo - DVec3::splat(own), chi + DVec3::splat(own));
            assert!(!exact || near.contains(&i), "touching box {q}: element {i} dropped");
        }
        // A rope whose boxes are not finite searches every element.
        let mut bad = nodes.clone();
        bad[7].x = f64::NAN;
        assert_eq!(RopeBroadPhase::new(&bad, |_| 0.0).elements_near(far, far).len(), 203);
    }
}
