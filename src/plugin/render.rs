//! Drawing cables (feature `render`): every rope as a smooth lit tube mesh,
//! its nodes interpolated between fixed steps, and optional gizmos (nodes,
//! contacts with their forces, element frames).
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_rapier3d::prelude::*;
//! use bevy_rapier_cable::plugin::render::*;
//! use bevy_rapier_cable::plugin::*;
//! App::new()
//!     .add_plugins((
//!         DefaultPlugins,
//!         RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(),
//!         CablePlugin::default(),
//!         CableRenderPlugin::default().with_gizmos(true),
//!     ))
//!     .run();
//! ```
//!
//! ## What it does
//! * **Which cables.** Every entity with a [`CableState`] (a cable with its
//!   own [`CableSim`](super::CableSim), and a rope solved in another cable's
//!   chain, [`CableRopeOf`](super::CableRopeOf): a sling leg) that has a
//!   [`CableRender`]. The plugin inserts `CableRender::default()` on each
//!   new [`CableState`] that has none
//!   ([`CableRenderPlugin::with_auto_insert`], on by default); insert your
//!   own `CableRender` with the descriptor to choose. Removing the
//!   component removes the tube (and it is not inserted again).
//! * **The tube.** A separate entity ([`CableTube::entity`], with
//!   [`CableTubeOf`]) with a `Mesh3d` (`TriangleList`, one ring of
//!   [`CableRender::sides`] vertices per node, and a flat cap closing each
//!   end, [`tube_vertex_count`]; indices built once) and the
//!   shared [`CableTubeMaterial`] (a `StandardMaterial`, base colour white:
//!   the colour is in the vertex colours). Each frame the positions,
//!   normals and colours are rewritten in place in the same mesh asset
//!   (so its `Aabb` follows through Bevy's `calculate_bounds`). The
//!   topology is rebuilt only when the node count or the number of sides
//!   changes. Replace the tube entity's `MeshMaterial3d` to change the
//!   look.
//! * **Frames.** The ring at node `i` is centred on it, perpendicular to
//!   the node's tangent: the bisector of the unit directions of its two
//!   elements (the element's direction at the ends). The rings' reference
//!   direction is carried along the rope by parallel transport (the
//!   smallest rotation from one tangent to the next), and from one frame to
//!   the next, so the tube neither flips nor twists. An element of zero
//!   length (coincident nodes) takes its neighbour's direction; a rope whose
//!   nodes all coincide is drawn along +Y. Nodes that are not finite leave
//!   the last drawn mesh unchanged.
//! * **Interpolation.** At every fixed step ([`CableRenderSystems::Record`],
//!   in `FixedPostUpdate`) the previous and the current [`CableState`] nodes
//!   and tensions are kept in [`CableRenderNodes`]; in `Update` they are
//!   blended by `Time<Fixed>::overstep_fraction()`, so a rope moves
//!   smoothly at any frame rate, one fixed step behind the physics (as
//!   bevy_rapier's `TransformInterpolation`). With cables stepped outside
//!   the fixed loop (`CablePlugin::in_schedule(PostUpdate)`), switch it off
//!   with [`CableRenderPlugin::with_interpolation`]`(false)`: the last state
//!   is drawn as it is.
//! * **Despawning.** A cable entity despawned, its [`CableState`] removed
//!   (the plugin does that when the cable stops existing, e.g. its carried
//!   body was despawned) or its [`CableRender`] removed: the tube entity is
//!   despawned and its mesh freed.
//! * **Gizmos.** With Bevy's `GizmoPlugin` (in `DefaultPlugins`), the
//!   [`CableGizmos`] config group draws the interpolated centreline, a
//!   small sphere at every node, the contact points with an arrow of each
//!   contact's force, and (as an option) each element's frame. Off by default
//!   ([`CableRenderPlugin::with_gizmos`]); toggle it at run time through
//!   `GizmoConfigStore`.
//!
//! Without Bevy's `PbrPlugin` (headless tests: `MinimalPlugins`,
//! `AssetPlugin`, `MeshPlugin`) the tubes are built and updated without a
//! material.

use super::{CableDescriptor, CableState};
use bevy::asset::RenderAssetUsages;
use bevy::gizmos::config::{GizmoConfig, GizmoConfigGroup};
use bevy::gizmos::{AppGizmoBuilder, GizmoPlugin};
use bevy::mesh::{Indices, Mesh3d, PrimitiveTopology, VertexAttributeValues};
use bevy::pbr::{MeshMaterial3d, StandardMaterial};
use bevy::prelude::*;

/// Draws cables as tube meshes (see the [module docs](self)). Add it after
/// [`CablePlugin`](super::CablePlugin); it needs Bevy's `AssetPlugin` and
/// `MeshPlugin` (both in `DefaultPlugins`).
#[derive(Debug, Clone)]
pub struct CableRenderPlugin {
    auto_insert: bool,
    interpolate: bool,
    gizmos: bool,
}

impl Default for CableRenderPlugin {
    /// Auto-insert on, interpolation on, gizmos off.
    fn default() -> Self {
        CableRenderPlugin { auto_insert: true, interpolate: true, gizmos: false }
    }
}

impl CableRenderPlugin {
    /// `true` (default): every new [`CableState`] without a [`CableRender`]
    /// gets `CableRender::default()`. `false`: only cables you give a
    /// `CableRender` are drawn.
    pub fn with_auto_insert(mut self, auto_insert: bool) -> Self {
        self.auto_insert = auto_insert;
        self
    }

    /// `true` (default): nodes blended between the last two fixed steps by
    /// `Time<Fixed>::overstep_fraction()`; `false`: the last [`CableState`]
    /// drawn as it is (cables stepped outside the fixed loop).
    pub fn with_interpolation(mut self, interpolate: bool) -> Self {
        self.interpolate = interpolate;
        self
    }

    /// Enables the [`CableGizmos`] group at start-up (default `false`;
    /// needs Bevy's `GizmoPlugin`).
    pub fn with_gizmos(mut self, enabled: bool) -> Self {
        self.gizmos = enabled;
        self
    }
}

/// System sets of the render plugin.
#[derive(SystemSet, Debug, Hash, PartialEq, Eq, Clone, Copy)]
pub enum CableRenderSystems {
    /// `FixedPostUpdate`: keeps the last two [`CableState`]s.
    Record,
    /// `Update`: blends them into [`CableRenderNodes::drawn`].
    Interpolate,
    /// `Update`, after `Interpolate`: builds and rewrites the tube meshes.
    Mesh,
    /// `Update`, after `Mesh`: the [`CableGizmos`].
    Gizmos,
}

/// How a cable is drawn. Put it on a cable entity (the one with the
/// [`CableDescriptor`]); with [`CableRenderPlugin::with_auto_insert`] (the
/// default) every cable gets `CableRender::default()`.
///
/// ```
/// use bevy::prelude::*;
/// use bevy_rapier_cable::plugin::render::CableRender;
/// // A thick orange rope, red at 20 kN.
/// let look = CableRender { radius: Some(0.03), color: Color::srgb(1.0, 0.5, 0.1), color_by_tension: Some(20_000.0), ..default() };
/// assert_eq!(look.sides, 12);
/// ```
#[derive(Component, Debug, Clone, PartialEq, Reflect)]
#[reflect(Component, Debug, Default, PartialEq)]
#[require(CableRenderNodes)]
pub struct CableRender {
    /// Vertices around the tube (at least 3; fewer are drawn as 3). Default 12.
    pub sides: u32,
    /// Tube radius, m. `None` (default): half the rope's diameter
    /// ([`CableDescriptor::material`]), or 10 mm on an entity without a
    /// descriptor.
    pub radius: Option<f32>,
    /// Colour of the rope (vertex colours), default steel grey.
    pub color: Color,
    /// `Some(max)`: colour each ring by the tension there, N, from blue
    /// (0 N or slack) through green and yellow to red (`max` N and more)
    /// instead of [`CableRender::color`]. `None` by default.
    pub color_by_tension: Option<f32>,
}

impl Default for CableRender {
    fn default() -> Self {
        CableRender { sides: 12, radius: None, color: Color::srgb(0.55, 0.56, 0.58), color_by_tension: None }
    }
}

/// The nodes a cable is drawn with, world, m, refreshed by the render
/// plugin (required by [`CableRender`]). Read [`CableRenderNodes::drawn`] to
/// attach something to the rope as it is drawn (a hook model, a label).
#[derive(Component, Debug, Clone, Default, PartialEq, Reflect)]
#[reflect(Component, Debug, Default, PartialEq)]
pub struct CableRenderNodes {
    /// The nodes at the fixed step before the last one, m.
    pub previous: Vec<Vec3>,
    /// The nodes at the last fixed step, m.
    pub current: Vec<Vec3>,
    /// The nodes drawn this frame: `previous` blended towards `current` by
    /// the overstep fraction, m.
    pub drawn: Vec<Vec3>,
    /// Element tensions at the fixed step before the last one, N.
    pub previous_tensions: Vec<f32>,
    /// Element tensions at the last fixed step, N.
    pub current_tensions: Vec<f32>,
    /// Element tensions drawn this frame (blended as the nodes), N.
    pub drawn_tensions: Vec<f32>,
    /// The blend factor of this frame (0: `previous`, 1: `current`).
    pub fraction: f32,
}

/// On a cable entity: its tube (put by the render plugin).
#[derive(Component, Debug, Clone, Reflect)]
#[reflect(Component, Debug)]
pub struct CableTube {
    entity: Entity,
    mesh: Handle<Mesh>,
    sides: usize,
    rings: usize,
    /// The first ring's reference direction, carried from frame to frame.
    normal: Vec3,
}

impl CableTube {
    /// The tube's entity (with `Mesh3d`, `MeshMaterial3d` and [`CableTubeOf`]).
    pub fn entity(&self) -> Entity {
        self.entity
    }

    /// The tube's mesh asset.
    pub fn mesh(&self) -> &Handle<Mesh> {
        &self.mesh
    }

    /// Vertices around the tube.
    pub fn sides(&self) -> usize {
        self.sides
    }

    /// Rings along the tube (one per node).
    pub fn rings(&self) -> usize {
        self.rings
    }
}

/// On a tube entity: the cable entity it draws.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, Reflect)]
#[reflect(Component, Debug, PartialEq)]
pub struct CableTubeOf(pub Entity);

/// The material of new tubes (with Bevy's `PbrPlugin`): a white, fairly
/// metallic `StandardMaterial` (the colour comes from the vertex colours).
/// Edit the asset to change every rope's look.
#[derive(Resource, Debug, Clone, Reflect)]
#[reflect(Resource, Debug)]
pub struct CableTubeMaterial(pub Handle<StandardMaterial>);

/// Settings of the running render plugin.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Reflect)]
#[reflect(Resource, Debug, PartialEq)]
pub struct CableRenderSettings {
    /// Blend between fixed steps ([`CableRenderPlugin::with_interpolation`]).
    pub interpolate: bool,
}

/// Gizmos of the cables: the centreline and the nodes, as drawn
/// (interpolated), and the last fixed step's contacts (points and forces)
/// and element frames. A Bevy `GizmoConfigGroup`: enable it with
/// [`CableRenderPlugin::with_gizmos`] or at run time,
/// `store.config_mut::<CableGizmos>().0.enabled = true` on
/// `ResMut<GizmoConfigStore>`.
#[derive(Debug, Clone, Reflect, GizmoConfigGroup)]
#[reflect(Debug, Default)]
pub struct CableGizmos {
    /// Draw the centreline (a line strip through the nodes).
    pub centerline: bool,
    /// Draw a sphere at every node.
    pub nodes: bool,
    /// Node sphere radius, m.
    pub node_radius: f32,
    /// Gizmo colour.
    pub color: Color,
    /// Draw each element's frame ([`CableState::frames`], at the element's
    /// middle as drawn): x (along the element) red, y green, z blue.
    /// Default `false`.
    pub frames: bool,
    /// Length of a frame's axes, m.
    pub frame_length: f32,
    /// Draw the contacts ([`CableState::contacts`]): a sphere at each
    /// contact point and an arrow of the force on the rope. Default `true`.
    pub contacts: bool,
    /// Arrow length per newton of contact force, m/N (default 1e-3: 1 kN
    /// is drawn 1 m long).
    pub force_scale: f32,
    /// Colour of the contact gizmos.
    pub contact_color: Color,
}

impl Default for CableGizmos {
    fn default() -> Self {
        CableGizmos {
            centerline: true,
            nodes: true,
            node_radius: 0.03,
            color: Color::srgb(1.0, 0.85, 0.1),
            frames: false,
            frame_length: 0.1,
            contacts: true,
            force_scale: 1e-3,
            contact_color: Color::srgb(1.0, 0.2, 0.8),
        }
    }
}

impl Plugin for CableRenderPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<CableRender>()
            .register_type::<CableRenderNodes>()
            .register_type::<CableTube>()
            .register_type::<CableTubeOf>()
            .register_type::<CableTubeMaterial>()
            .register_type::<CableRenderSettings>()
            .register_type::<CableGizmos>();
        app.insert_resource(CableRenderSettings { interpolate: self.interpolate });
        app.configure_sets(Update, (CableRenderSystems::Interpolate, CableRenderSystems::Mesh, CableRenderSystems::Gizmos).chain());
        app.add_systems(FixedPostUpdate, record.in_set(CableRenderSystems::Record));
        if self.auto_insert {
            app.add_systems(Update, auto_insert.before(CableRenderSystems::Interpolate));
        }
        app.add_systems(Update, interpolate.in_set(CableRenderSystems::Interpolate));
        app.add_systems(Update, (build_tubes, update_tubes).chain().in_set(CableRenderSystems::Mesh));
        app.add_observer(drop_tube_with_state).add_observer(drop_tube_with_render);
    }

    fn finish(&self, app: &mut App) {
        let world = app.world_mut();
        let steel = StandardMaterial { base_color: Color::WHITE, metallic: 0.7, perceptual_roughness: 0.35, ..default() };
        if let Some(material) = world.get_resource_mut::<Assets<StandardMaterial>>().map(|mut m| m.add(steel)) {
            world.insert_resource(CableTubeMaterial(material));
        }
        if !world.contains_resource::<Assets<Mesh>>() {
            log::error!("CableRenderPlugin needs Bevy's AssetPlugin and MeshPlugin (in DefaultPlugins): no cable tube will be drawn");
        }
        if app.is_plugin_added::<GizmoPlugin>() {
            app.insert_gizmo_config(CableGizmos::default(), GizmoConfig { enabled: self.gizmos, ..default() });
            app.add_systems(Update, draw_gizmos.in_set(CableRenderSystems::Gizmos));
        }
    }
}

/// New cables get the default look.
fn auto_insert(mut commands: Commands, new: Query<Entity, (Added<CableState>, Without<CableRender>)>) {
    for entity in &new {
        commands.entity(entity).try_insert(CableRender::default());
    }
}

/// `FixedPostUpdate`: shift the history by one fixed step.
fn record(mut cables: Query<(&CableState, &mut CableRenderNodes)>) {
    for (state, mut h) in &mut cables {
        if state.nodes.len() < 2 {
            continue;
        }
        let h = &mut *h;
        if h.current.len() == state.nodes.len() && h.current_tensions.len() == state.tensions.len() {
            std::mem::swap(&mut h.previous, &mut h.current);
            std::mem::swap(&mut h.previous_tensions, &mut h.current_tensions);
            h.current.clone_from(&state.nodes);
            h.current_tensions.clone_from(&state.tensions);
        } else {
            // First step seen, or the rope changed its node count: no history.
            h.previous.clone_from(&state.nodes);
            h.current.clone_from(&state.nodes);
            h.previous_tensions.clone_from(&state.tensions);
            h.current_tensions.clone_from(&state.tensions);
        }
    }
}

/// `Update`: blend the last two fixed steps by the overstep fraction.
/// `CableRenderNodes` is marked changed only when what is drawn changed
/// (a rope at rest is not re-uploaded).
fn interpolate(settings: Res<CableRenderSettings>, time: Res<Time<Fixed>>, mut cables: Query<(&CableState, &mut CableRenderNodes)>) {
    let a = time.overstep_fraction();
    let a = if a.is_finite() { a.clamp(0.0, 1.0) } else { 1.0 };
    for (state, mut h) in &mut cables {
        let n = h.bypass_change_detection();
        let history =
            settings.interpolate && n.current.len() >= 2 && n.previous.len() == n.current.len() && n.previous_tensions.len() == n.current_tensions.len();
        let changed = if history {
            n.fraction = a;
            assign(&mut n.drawn, n.previous.iter().zip(&n.current).map(|(p, c)| p.lerp(*c, a)))
                | assign(&mut n.drawn_tensions, n.previous_tensions.iter().zip(&n.current_tensions).map(|(p, c)| p + (c - p) * a))
        } else {
            // No fixed step recorded yet (or interpolation off): the state as it is.
            n.fraction = 1.0;
            assign(&mut n.drawn, state.nodes.iter().copied()) | assign(&mut n.drawn_tensions, state.tensions.iter().copied())
        };
        if changed {
            h.set_changed();
        }
    }
}

/// Overwrites `dst` with `src`; whether anything changed.
fn assign<T: Copy + PartialEq>(dst: &mut Vec<T>, src: impl Iterator<Item = T>) -> bool {
    let mut changed = false;
    let mut len = 0;
    for (k, v) in src.enumerate() {
        len = k + 1;
        match dst.get_mut(k) {
            Some(d) if *d == v => {}
            Some(d) => {
                *d = v;
                changed = true;
            }
            None => {
                dst.push(v);
                changed = true;
            }
        }
    }
    if dst.len() != len {
        dst.truncate(len);
        changed = true;
    }
    changed
}

/// The tube radius of a cable, m.
fn radius_of(render: &CableRender, descriptor: Option<&CableDescriptor>) -> f32 {
    let r = render.radius.unwrap_or_else(|| descriptor.map_or(0.01, |d| (0.5 * d.material.diameter()) as f32));
    if r.is_finite() && r > 0.0 {
        r
    } else {
        0.01
    }
}

type TubeQuery<'a> = (Entity, &'a CableRender, &'a CableRenderNodes, Option<&'a CableDescriptor>, Option<&'a mut CableTube>);

/// Cables whose drawing changed this frame.
type Redrawn = (With<CableState>, Or<(Changed<CableRenderNodes>, Changed<CableRender>)>);

/// Creates a tube for a drawn cable without one, or a new one when the node
/// count or the number of sides changed.
fn build_tubes(
    mut commands: Commands,
    meshes: Option<ResMut<Assets<Mesh>>>,
    material: Option<Res<CableTubeMaterial>>,
    cables: Query<TubeQuery, With<CableState>>,
) {
    let Some(mut meshes) = meshes else { return };
    for (entity, render, nodes, descriptor, tube) in &cables {
        let rings = nodes.drawn.len();
        let sides = render.sides.max(3) as usize;
        if rings < 2 || tube.as_ref().is_some_and(|t| t.rings == rings && t.sides == sides) {
            continue;
        }
        if let Some(old) = &tube {
            commands.entity(old.entity).try_despawn();
        }
        let mut mesh = tube_mesh(rings, sides);
        let mut normal = Vec3::ZERO;
        write_tube(&mut mesh, render, radius_of(render, descriptor), &nodes.drawn, &nodes.drawn_tensions, &mut normal);
        let handle = meshes.add(mesh);
        let mut e = commands.spawn((Name::new("cable tube"), CableTubeOf(entity), Mesh3d(handle.clone()), Transform::IDENTITY));
        if let Some(m) = &material {
            e.insert(MeshMaterial3d(m.0.clone()));
        }
        let tube_entity = e.id();
        commands.entity(entity).try_insert(CableTube { entity: tube_entity, mesh: handle, sides, rings, normal });
    }
}

/// Rewrites the tubes' positions, normals and colours in place.
fn update_tubes(meshes: Option<ResMut<Assets<Mesh>>>, mut cables: Query<TubeQuery, Redrawn>) {
    let Some(mut meshes) = meshes else { return };
    for (_, render, nodes, descriptor, tube) in &mut cables {
        let Some(mut tube) = tube else { continue };
        if tube.rings != nodes.drawn.len() || tube.sides != render.sides.max(3) as usize {
            continue; // rebuilt next frame
        }
        let Some(mut mesh) = meshes.get_mut(&tube.mesh) else { continue };
        write_tube(&mut mesh, render, radius_of(render, descriptor), &nodes.drawn, &nodes.drawn_tensions, &mut tube.normal);
    }
}

/// Vertices of a tube of `rings` × `sides` with its two end caps: the
/// rings (ring `i` from `i * sides`), then each cap's centre followed by
/// its own ring of `sides` vertices (the start cap at `rings * sides`, the
/// end cap `sides + 1` after it), whose normals are along the rope.
pub fn tube_vertex_count(rings: usize, sides: usize) -> usize {
    rings * sides + 2 * (sides + 1)
}

/// A tube of `rings` × `sides` vertices and its end caps
/// ([`tube_vertex_count`]; positions, normals, colours to be written) and
/// its triangles (outward, counter-clockwise).
fn tube_mesh(rings: usize, sides: usize) -> Mesh {
    let n = tube_vertex_count(rings, sides);
    let mut indices = Vec::with_capacity((rings - 1) * sides * 6 + 2 * sides * 3);
    for i in 0..rings - 1 {
        for j in 0..sides {
            let a = (i * sides + j) as u32;
            let b = (i * sides + (j + 1) % sides) as u32;
            let c = ((i + 1) * sides + j) as u32;
            let d = ((i + 1) * sides + (j + 1) % sides) as u32;
            indices.extend_from_slice(&[a, b, c, b, d, c]);
        }
    }
    // The caps: fans around their centres. The ring turns positively about
    // the tangent, so the end cap (facing +tangent) takes j, j + 1 and the
    // start cap (facing −tangent) j + 1, j.
    let (start, end) = (rings * sides, rings * sides + sides + 1);
    for j in 0..sides {
        let k = (j + 1) % sides;
        indices.extend_from_slice(&[start as u32, (start + 1 + k) as u32, (start + 1 + j) as u32]);
        indices.extend_from_slice(&[end as u32, (end + 1 + j) as u32, (end + 1 + k) as u32]);
    }
    Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::MAIN_WORLD | RenderAssetUsages::RENDER_WORLD)
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, vec![[0.0f32; 3]; n])
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, vec![[0.0f32, 1.0, 0.0]; n])
        .with_inserted_attribute(Mesh::ATTRIBUTE_COLOR, vec![[1.0f32; 4]; n])
        .with_inserted_indices(Indices::U32(indices))
}

/// The unit tangent at every node: the bisector of the unit directions of
/// the node's elements (the element's direction at the ends). Elements of
/// zero length take their neighbour's direction; all of zero length give +Y.
pub fn node_tangents(nodes: &[Vec3]) -> Vec<Vec3> {
    let mut seg: Vec<Option<Vec3>> = nodes.windows(2).map(|w| (w[1] - w[0]).try_normalize()).collect();
    // Fill zero-length elements forwards, then the leading ones backwards.
    let mut last = None;
    for s in seg.iter_mut() {
        match s {
            Some(d) => last = Some(*d),
            None => *s = last,
        }
    }
    let first = seg.iter().flatten().next().copied().unwrap_or(Vec3::Y);
    let seg: Vec<Vec3> = seg.into_iter().map(|s| s.unwrap_or(first)).collect();
    (0..nodes.len())
        .map(|i| match (i.checked_sub(1).and_then(|k| seg.get(k)), seg.get(i)) {
            (Some(a), Some(b)) => (*a + *b).try_normalize().unwrap_or(*b),
            (Some(a), None) => *a,
            (None, Some(b)) => *b,
            (None, None) => Vec3::Y,
        })
        .collect()
}

/// A ring's colour: the rope's, or the tension map.
fn ring_color(render: &CableRender, tensions: &[f32], i: usize) -> [f32; 4] {
    let color = match render.color_by_tension {
        Some(max) if max.is_finite() && max > 0.0 && !tensions.is_empty() => {
            let k = tensions.len();
            let t = 0.5 * (tensions[i.saturating_sub(1).min(k - 1)] + tensions[i.min(k - 1)]);
            let f = if t.is_finite() { (t / max).clamp(0.0, 1.0) } else { 0.0 };
            Color::hsl(240.0 * (1.0 - f), 0.85, 0.5)
        }
        _ => render.color,
    };
    LinearRgba::from(color).to_f32_array()
}

/// Writes the tube's vertices around `nodes` (parallel-transport frames
/// from `normal`, the previous frame's first reference direction, updated).
fn write_tube(mesh: &mut Mesh, render: &CableRender, radius: f32, nodes: &[Vec3], tensions: &[f32], normal: &mut Vec3) {
    if nodes.len() < 2 || nodes.iter().any(|p| !p.is_finite()) {
        return;
    }
    let sides = render.sides.max(3) as usize;
    let rings = nodes.len();
    let n = tube_vertex_count(rings, sides);
    let tangents = node_tangents(nodes);
    let t0 = tangents[0];
    let mut nrm = (*normal - t0 * normal.dot(t0)).try_normalize().unwrap_or_else(|| t0.any_orthonormal_vector());
    *normal = nrm;
    let (sin, cos): (Vec<f32>, Vec<f32>) = (0..sides).map(|j| (std::f32::consts::TAU * j as f32 / sides as f32).sin_cos()).unzip();
    let mut positions = Vec::with_capacity(n);
    let mut normals = Vec::with_capacity(n);
    let mut colors = Vec::with_capacity(n);
    for (i, (p, t)) in nodes.iter().zip(&tangents).enumerate() {
        if i > 0 {
            let carried = Quat::from_rotation_arc(tangents[i - 1], *t) * nrm;
            nrm = (carried - *t * carried.dot(*t)).try_normalize().unwrap_or_else(|| t.any_orthonormal_vector());
        }
        let b = t.cross(nrm);
        let c = ring_color(render, tensions, i);
        for j in 0..sides {
            let d = nrm * cos[j] + b * sin[j];
            positions.push((*p + d * radius).to_array());
            normals.push(d.to_array());
            colors.push(c);
        }
    }
    // The caps: a copy of the first and last rings around their nodes, with
    // normals along the rope (out of the tube).
    for (ring, outward) in [(0, -tangents[0]), (rings - 1, tangents[rings - 1])] {
        positions.push(nodes[ring].to_array());
        normals.push(outward.to_array());
        colors.push(colors[ring * sides]);
        for j in 0..sides {
            positions.push(positions[ring * sides + j]);
            normals.push(outward.to_array());
            colors.push(colors[ring * sides]);
        }
    }
    set_attribute(mesh, Mesh::ATTRIBUTE_POSITION, positions);
    set_attribute(mesh, Mesh::ATTRIBUTE_NORMAL, normals);
    set_attribute(mesh, Mesh::ATTRIBUTE_COLOR, colors);
}

/// Overwrites an attribute in place when it is there with the same length,
/// else inserts it.
fn set_attribute<const K: usize>(mesh: &mut Mesh, attribute: bevy::mesh::MeshVertexAttribute, values: Vec<[f32; K]>)
where
    VertexAttributeValues: From<Vec<[f32; K]>>,
{
    let done = match mesh.try_attribute_mut(attribute) {
        Ok(VertexAttributeValues::Float32x3(v)) if K == 3 && v.len() == values.len() => {
            for (dst, src) in v.iter_mut().zip(&values) {
                dst.copy_from_slice(src);
            }
            true
        }
        Ok(VertexAttributeValues::Float32x4(v)) if K == 4 && v.len() == values.len() => {
            for (dst, src) in v.iter_mut().zip(&values) {
                dst.copy_from_slice(src);
            }
            true
        }
        _ => false,
    };
    if !done {
        // Absent, another layout, or (never with MAIN_WORLD usage) extracted.
        let _ = mesh.try_insert_attribute(attribute, values);
    }
}

/// A cable lost its state (despawned, or removed by the cable plugin): its tube goes.
fn drop_tube_with_state(remove: On<Remove, CableState>, mut commands: Commands, tubes: Query<&CableTube>) {
    drop_tube(remove.entity, &mut commands, &tubes);
}

/// A cable is no longer drawn: its tube goes.
fn drop_tube_with_render(remove: On<Remove, CableRender>, mut commands: Commands, tubes: Query<&CableTube>) {
    drop_tube(remove.entity, &mut commands, &tubes);
}

fn drop_tube(cable: Entity, commands: &mut Commands, tubes: &Query<&CableTube>) {
    if let Ok(tube) = tubes.get(cable) {
        commands.entity(tube.entity).try_despawn();
        commands.entity(cable).try_remove::<CableTube>();
    }
}

/// The [`CableGizmos`]: centreline and nodes as drawn; element frames and
/// contacts of the last fixed step.
fn draw_gizmos(mut gizmos: Gizmos<CableGizmos>, cables: Query<(&CableRenderNodes, Option<&CableState>)>) {
    if !gizmos.config.enabled {
        return;
    }
    let ext = gizmos.config_ext.clone();
    for (nodes, state) in &cables {
        if ext.centerline {
            gizmos.linestrip(nodes.drawn.iter().copied(), ext.color);
        }
        if ext.nodes {
            for p in &nodes.drawn {
                gizmos.sphere(Isometry3d::from_translation(*p), ext.node_radius, ext.color);
            }
        }
        let Some(state) = state else {
            continue;
        };
        if ext.frames {
            let axes = [(Vec3::X, Color::srgb(0.9, 0.1, 0.1)), (Vec3::Y, Color::srgb(0.1, 0.8, 0.1)), (Vec3::Z, Color::srgb(0.1, 0.3, 0.95))];
            for (frame, ends) in state.frames.iter().zip(nodes.drawn.windows(2)) {
                let middle = 0.5 * (ends[0] + ends[1]);
                for (axis, color) in axes {
                    gizmos.line(middle, middle + *frame * axis * ext.frame_length, color);
                }
            }
        }
        if ext.contacts {
            for &(point, force) in &state.contacts {
                gizmos.sphere(Isometry3d::from_translation(point), 0.5 * ext.node_radius, ext.contact_color);
                gizmos.arrow(point, point + force * ext.force_scale, ext.contact_color);
            }
        }
    }
}
