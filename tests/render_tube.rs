//! The render plugin (feature `render`) headless: `MinimalPlugins`,
//! `AssetPlugin` and `MeshPlugin`, no window and no GPU. The tube mesh
//! around a rope's nodes, its fixed topology, the interpolation between
//! fixed steps, degenerate ropes, colours by tension, despawning, and
//! cables of the real plugin (sling legs included).

use bevy::mesh::{Indices, MeshPlugin, VertexAttributeValues};
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::plugin::render::*;
use bevy_rapier_cable::plugin::*;
use std::time::Duration;

const STEP: Duration = Duration::from_millis(100);

/// The render plugin alone, on hand-made `CableState`s: a fixed step of
/// 100 ms, and 100 ms of time per `update()` unless a test says otherwise.
fn render_app() -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), MeshPlugin, CableRenderPlugin::default()));
    app.insert_resource(Time::<Fixed>::from_duration(STEP));
    app.insert_resource(TimeUpdateStrategy::ManualDuration(STEP));
    app.finish();
    app.cleanup();
    app
}

fn state(nodes: Vec<Vec3>) -> CableState {
    let tensions = vec![1000.0; nodes.len().saturating_sub(1)];
    CableState { nodes, tensions, ..default() }
}

/// A bent rope: 9 nodes on a quarter circle of radius 2 m, then a kink.
fn bent_nodes() -> Vec<Vec3> {
    let mut v: Vec<Vec3> = (0..7).map(|i| i as f32 * std::f32::consts::FRAC_PI_2 / 6.0).map(|a| Vec3::new(2.0 * a.sin(), 2.0 * a.cos(), 0.1 * a)).collect();
    v.push(Vec3::new(2.5, 0.2, 0.8));
    v.push(Vec3::new(2.6, -0.9, 1.5));
    v
}

/// Updates until the cable's render history holds `nodes` as its current
/// fixed step (at most 5 frames).
fn until_recorded(app: &mut App, cable: Entity, nodes: &[Vec3]) {
    for _ in 0..5 {
        app.update();
        if app.world().get::<CableRenderNodes>(cable).is_some_and(|h| h.current == nodes) {
            return;
        }
    }
    panic!("the fixed step never recorded the nodes");
}

/// Spawns a hand-made cable (`extra`: its look, a descriptor, ...) on
/// `nodes` and updates until it is drawn.
fn drawn_cable(app: &mut App, nodes: &[Vec3], extra: impl Bundle) -> Entity {
    let cable = app.world_mut().spawn((state(nodes.to_vec()), extra)).id();
    until_recorded(app, cable, nodes);
    app.update();
    cable
}

fn tube(app: &App, cable: Entity) -> CableTube {
    app.world().get::<CableTube>(cable).expect("the cable has a tube").clone()
}

fn mesh(app: &App, cable: Entity) -> Mesh {
    let t = tube(app, cable);
    app.world().resource::<Assets<Mesh>>().get(t.mesh()).expect("the tube's mesh asset").clone()
}

fn f3(mesh: &Mesh, attribute: bevy::mesh::MeshVertexAttribute) -> Vec<Vec3> {
    match mesh.attribute(attribute) {
        Some(VertexAttributeValues::Float32x3(v)) => v.iter().map(|a| Vec3::from_array(*a)).collect(),
        other => panic!("{attribute:?}: {other:?}"),
    }
}

fn colors(mesh: &Mesh) -> Vec<[f32; 4]> {
    match mesh.attribute(Mesh::ATTRIBUTE_COLOR) {
        Some(VertexAttributeValues::Float32x4(v)) => v.clone(),
        other => panic!("colours: {other:?}"),
    }
}

fn indices(mesh: &Mesh) -> Vec<u32> {
    match mesh.indices() {
        Some(Indices::U32(i)) => i.clone(),
        other => panic!("indices: {other:?}"),
    }
}

/// The tangent the tube is built around, computed here independently: the
/// bisector of the unit directions of a node's elements.
fn tangent(nodes: &[Vec3], i: usize) -> Vec3 {
    let dir = |k: usize| (nodes[k + 1] - nodes[k]).normalize();
    match i {
        0 => dir(0),
        _ if i == nodes.len() - 1 => dir(i - 1),
        _ => (dir(i - 1) + dir(i)).normalize(),
    }
}

/// Every vertex of ring `i` is at `radius` from drawn node `i`, its normal
/// is unit, points from the node to the vertex and is perpendicular to the
/// node's tangent; every triangle faces outwards (counter-clockwise seen
/// from outside, Bevy's front face).
fn check_tube(mesh: &Mesh, nodes: &[Vec3], sides: usize, radius: f32) {
    let p = f3(mesh, Mesh::ATTRIBUTE_POSITION);
    let n = f3(mesh, Mesh::ATTRIBUTE_NORMAL);
    assert_eq!(p.len(), tube_vertex_count(nodes.len(), sides));
    for (i, node) in nodes.iter().enumerate() {
        let t = tangent(nodes, i);
        for j in 0..sides {
            let k = i * sides + j;
            let r = p[k] - *node;
            assert!((r.length() - radius).abs() < 1e-5 * radius.max(1.0), "ring {i} vertex {j}: {} m from the node, radius {radius}", r.length());
            assert!((n[k].length() - 1.0).abs() < 1e-5, "ring {i} vertex {j}: normal length {}", n[k].length());
            assert!(n[k].dot(t).abs() < 1e-5, "ring {i} vertex {j}: normal·tangent = {}", n[k].dot(t));
            assert!((r / radius - n[k]).length() < 1e-4, "ring {i} vertex {j}: the normal does not point at the vertex");
        }
    }
    for tri in indices(mesh).chunks(3) {
        let [a, b, c] = [p[tri[0] as usize], p[tri[1] as usize], p[tri[2] as usize]];
        let face = (b - a).cross(c - a);
        let outward = n[tri[0] as usize] + n[tri[1] as usize] + n[tri[2] as usize];
        assert!(face.dot(outward) > 0.0, "triangle {tri:?} faces inwards");
    }
}

#[test]
fn tube_vertices_ring_the_drawn_nodes_at_the_radius_with_normals_across_the_tangent() {
    let mut app = render_app();
    let nodes = bent_nodes();
    let cable = drawn_cable(&mut app, &nodes, CableRender { sides: 8, radius: Some(0.05), ..default() });
    let t = tube(&app, cable);
    assert_eq!((t.rings(), t.sides()), (nodes.len(), 8));
    assert_eq!(app.world().get::<CableTubeOf>(t.entity()), Some(&CableTubeOf(cable)));
    assert_eq!(app.world().get::<CableRenderNodes>(cable).unwrap().drawn, nodes);
    check_tube(&mesh(&app, cable), &nodes, 8, 0.05);
    assert_eq!(indices(&mesh(&app, cable)).len(), (nodes.len() - 1) * 8 * 6 + 2 * 8 * 3);
}

#[test]
fn default_radius_is_half_the_rope_diameter() {
    let mut app = render_app();
    let nodes = bent_nodes();
    let descriptor = CableDescriptor::new(5.0).material(RopeMaterial::steel_6x36_iwrc(0.032));
    let cable = drawn_cable(&mut app, &nodes, descriptor);
    assert_eq!(app.world().get::<CableRender>(cable), Some(&CableRender::default()), "inserted with the defaults");
    check_tube(&mesh(&app, cable), &nodes, 12, 0.016);
}

#[test]
fn topology_never_changes_while_the_rope_moves() {
    let mut app = render_app();
    let nodes = bent_nodes();
    let cable = drawn_cable(&mut app, &nodes, CableRender { sides: 6, radius: Some(0.02), ..default() });
    let (t0, m0) = (tube(&app, cable), mesh(&app, cable));
    for frame in 1..=20 {
        let moved: Vec<Vec3> =
            nodes.iter().enumerate().map(|(i, p)| *p + Vec3::new(0.1 * frame as f32 * i as f32, 0.03 * frame as f32, -0.02 * (frame * i) as f32)).collect();
        app.world_mut().get_mut::<CableState>(cable).unwrap().nodes = moved.clone();
        app.update();
        let (t, m) = (tube(&app, cable), mesh(&app, cable));
        assert_eq!((t.entity(), t.mesh().id()), (t0.entity(), t0.mesh().id()), "frame {frame}: the same tube entity and mesh asset");
        assert_eq!(m.count_vertices(), m0.count_vertices(), "frame {frame}");
        assert_eq!(indices(&m), indices(&m0), "frame {frame}: indices changed");
        let drawn = app.world().get::<CableRenderNodes>(cable).unwrap().drawn.clone();
        check_tube(&m, &drawn, 6, 0.02);
    }
    assert_ne!(f3(&mesh(&app, cable), Mesh::ATTRIBUTE_POSITION), f3(&m0, Mesh::ATTRIBUTE_POSITION), "the positions were rewritten");
    assert_eq!(app.world().resource::<Assets<Mesh>>().len(), 1, "no mesh leaked");
}

/// Ring centres (the mean of a ring's vertices) of the tube.
fn ring_centres(mesh: &Mesh, sides: usize) -> Vec<Vec3> {
    let p = f3(mesh, Mesh::ATTRIBUTE_POSITION);
    // The rings, without the caps' vertices after them.
    p[..p.len() - 2 * (sides + 1)].chunks(sides).map(|r| r.iter().sum::<Vec3>() / sides as f32).collect()
}

fn close(a: &[Vec3], b: &[Vec3], tol: f32) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (*x - *y).length() < tol)
}

#[test]
fn nodes_are_interpolated_between_fixed_steps_by_the_overstep() {
    let mut app = render_app();
    let a = bent_nodes();
    let b: Vec<Vec3> = a.iter().enumerate().map(|(i, p)| *p + Vec3::new(0.4, -0.2 * i as f32, 0.3)).collect();
    let mid: Vec<Vec3> = a.iter().zip(&b).map(|(p, q)| (*p + *q) / 2.0).collect();
    let cable = app.world_mut().spawn((state(a.clone()), CableRender { sides: 8, radius: Some(0.05), ..default() })).id();
    until_recorded(&mut app, cable, &a);
    // One fixed step to state b, at the step boundary: overstep 0, `a` drawn.
    app.world_mut().get_mut::<CableState>(cable).unwrap().nodes = b.clone();
    app.update();
    let h = app.world().get::<CableRenderNodes>(cable).unwrap().clone();
    assert_eq!((&h.previous, &h.current), (&a, &b));
    assert_eq!(h.fraction, 0.0);
    assert!(close(&h.drawn, &a, 1e-6), "overstep 0: the previous step's nodes");
    assert!(close(&ring_centres(&mesh(&app, cable), 8), &a, 1e-5), "the tube follows");
    // Half a step later (no fixed step): midway.
    app.insert_resource(TimeUpdateStrategy::ManualDuration(STEP / 2));
    app.update();
    let h = app.world().get::<CableRenderNodes>(cable).unwrap().clone();
    assert!((h.fraction - 0.5).abs() < 1e-6, "fraction {}", h.fraction);
    assert!(close(&h.drawn, &mid, 1e-5), "overstep 0.5: midway");
    assert!(close(&ring_centres(&mesh(&app, cable), 8), &mid, 1e-5));
    check_tube(&mesh(&app, cable), &h.drawn, 8, 0.05);
    // A whole step of overstep (the instant before the next fixed step): `b`.
    app.world_mut().resource_mut::<Time<Fixed>>().accumulate_overstep(STEP / 2);
    app.world_mut().run_schedule(Update);
    let h = app.world().get::<CableRenderNodes>(cable).unwrap().clone();
    assert!((h.fraction - 1.0).abs() < 1e-6);
    assert!(close(&h.drawn, &b, 1e-5), "overstep 1: the current step's nodes");
    assert!(close(&ring_centres(&mesh(&app, cable), 8), &b, 1e-5));
}

#[test]
fn interpolation_off_draws_the_last_state() {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), MeshPlugin, CableRenderPlugin::default().with_interpolation(false)));
    app.insert_resource(Time::<Fixed>::from_duration(STEP));
    app.insert_resource(TimeUpdateStrategy::ManualDuration(STEP / 2));
    app.finish();
    app.cleanup();
    let a = bent_nodes();
    let cable = app.world_mut().spawn(state(a.clone())).id();
    for _ in 0..4 {
        app.update();
    }
    let b: Vec<Vec3> = a.iter().map(|p| *p + Vec3::X).collect();
    app.world_mut().get_mut::<CableState>(cable).unwrap().nodes = b.clone();
    app.update();
    assert_eq!(app.world().get::<CableRenderNodes>(cable).unwrap().drawn, b);
}

#[test]
fn straight_vertical_and_coincident_nodes_give_finite_vertices() {
    let vertical: Vec<Vec3> = (0..11).map(|i| Vec3::new(1.0, -(i as f32), 2.0)).collect();
    let mut coincident = vertical.clone();
    coincident[4] = coincident[5];
    let mut leading = vertical.clone();
    leading[1] = leading[0];
    leading[2] = leading[0];
    let mut folded = vertical.clone(); // a rope folded back onto itself at node 5
    for i in 6..11 {
        folded[i] = folded[10 - i];
    }
    let cases = [
        ("vertical", vertical),
        ("two coincident nodes", coincident),
        ("coincident at the start", leading),
        ("folded", folded),
        ("all at one point", vec![Vec3::ONE; 6]),
    ];
    for (name, nodes) in cases {
        let mut app = render_app();
        let cable = drawn_cable(&mut app, &nodes, CableRender { sides: 7, radius: Some(0.03), ..default() });
        let m = mesh(&app, cable);
        let (p, n) = (f3(&m, Mesh::ATTRIBUTE_POSITION), f3(&m, Mesh::ATTRIBUTE_NORMAL));
        assert_eq!(p.len(), tube_vertex_count(nodes.len(), 7), "{name}");
        assert!(p.iter().chain(&n).all(|v| v.is_finite()), "{name}: a vertex is not finite");
        assert!(n.iter().all(|v| (v.length() - 1.0).abs() < 1e-5), "{name}: a normal is not unit");
        for (i, ring) in p[..nodes.len() * 7].chunks(7).enumerate() {
            assert!(ring.iter().all(|v| ((*v - nodes[i]).length() - 0.03).abs() < 1e-5), "{name}: ring {i} off the radius");
        }
        if name == "vertical" {
            check_tube(&m, &nodes, 7, 0.03);
        }
    }
}

#[test]
fn non_finite_nodes_keep_the_last_mesh() {
    let mut app = render_app();
    let nodes = bent_nodes();
    let cable = drawn_cable(&mut app, &nodes, ());
    let before = f3(&mesh(&app, cable), Mesh::ATTRIBUTE_POSITION);
    let mut bad = nodes.clone();
    bad[3] = Vec3::NAN;
    app.world_mut().get_mut::<CableState>(cable).unwrap().nodes = bad;
    for _ in 0..3 {
        app.update();
    }
    assert_eq!(f3(&mesh(&app, cable), Mesh::ATTRIBUTE_POSITION), before);
}

#[test]
fn color_by_tension_runs_from_blue_to_red() {
    let mut app = render_app();
    let nodes: Vec<Vec3> = (0..5).map(|i| Vec3::new(0.0, -(i as f32), 0.0)).collect();
    let mut s = state(nodes.clone());
    s.tensions = vec![0.0, 0.0, 20_000.0, 20_000.0];
    let cable = app.world_mut().spawn((s, CableRender { sides: 4, color_by_tension: Some(10_000.0), ..default() })).id();
    until_recorded(&mut app, cable, &nodes);
    app.update();
    let c = colors(&mesh(&app, cable));
    let rgb = |k: usize| Vec3::new(c[k][0], c[k][1], c[k][2]);
    let (top, bottom) = (rgb(0), rgb(4 * 4));
    assert!(top.z > 0.5 && top.x < 0.05 && top.y < 0.05, "slack: blue, {top}");
    assert!(bottom.x > 0.5 && bottom.y < 0.05 && bottom.z < 0.05, "over the maximum: red, {bottom}");
    // The plain colour otherwise.
    app.world_mut().get_mut::<CableRender>(cable).unwrap().color_by_tension = None;
    app.update();
    let grey = LinearRgba::from(CableRender::default().color).to_f32_array();
    assert!(colors(&mesh(&app, cable)).iter().all(|x| *x == grey));
}

#[test]
fn despawning_or_stopping_a_cable_removes_its_tube() {
    let mut app = render_app();
    let nodes = bent_nodes();
    let a = app.world_mut().spawn(state(nodes.clone())).id();
    let b = app.world_mut().spawn(state(nodes.clone())).id();
    let c = app.world_mut().spawn(state(nodes.clone())).id();
    until_recorded(&mut app, a, &nodes);
    app.update();
    // The tube entities and mesh ids (not the handles: they would keep the meshes).
    let tubes: Vec<(Entity, AssetId<Mesh>)> = [a, b, c].iter().map(|e| tube(&app, *e)).map(|t| (t.entity(), t.mesh().id())).collect();
    assert_eq!(app.world().resource::<Assets<Mesh>>().len(), 3);
    // Despawned; its state removed (as the cable plugin does for a cable it
    // removes); its `CableRender` removed.
    app.world_mut().despawn(a);
    app.world_mut().entity_mut(b).remove::<CableState>();
    app.world_mut().entity_mut(c).remove::<CableRender>();
    for _ in 0..3 {
        app.update();
    }
    for (entity, mesh) in &tubes {
        assert!(app.world().get_entity(*entity).is_err(), "the tube entity is gone");
        assert!(app.world().resource::<Assets<Mesh>>().get(*mesh).is_none(), "the mesh is freed");
    }
    assert!(app.world().get::<CableTube>(b).is_none() && app.world().get::<CableTube>(c).is_none());
    assert_eq!(app.world().resource::<Assets<Mesh>>().len(), 0, "no mesh left");
    assert!(app.world().get::<CableRender>(c).is_none(), "a removed CableRender is not inserted again");
}

/// The real plugins: a payload on a two-leg sling (one leg carries it,
/// the other is a limb of its chain) and a single rope; each rope gets a
/// tube around its own nodes; despawning the payload removes the cables
/// and their tubes.
#[test]
fn cables_of_the_plugin_and_sling_legs_are_drawn() {
    let dt = 1.0 / 60.0;
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        TransformPlugin,
        AssetPlugin::default(),
        MeshPlugin,
        RapierPhysicsPlugin::<NoUserData>::default().in_fixed_schedule(),
        CablePlugin::default(),
        CableRenderPlugin::default(),
    ));
    app.insert_resource(Time::<Fixed>::from_seconds(dt));
    app.insert_resource(TimestepMode::Fixed { dt: dt as f32, substeps: 1 });
    app.insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    app.finish();
    app.cleanup();
    let w = app.world_mut();
    let payload = w.spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, -8.0, 0.0), Collider::ball(0.3), ColliderMassProperties::Mass(1000.0))).id();
    let leg = |x: f32| {
        CableDescriptor::new(10.0)
            .segments(10)
            .material(RopeMaterial::steel_6x36_iwrc(0.02))
            .damping(0.05)
            .start(CableAnchor::world(Vec3::new(x, 0.0, 0.0)))
            .end(CableAnchor::body(payload, Vec3::ZERO))
    };
    let (la, lb) = (w.spawn(leg(-6.0)).id(), w.spawn(leg(6.0)).id());
    let single = w.spawn(CableDescriptor::new(4.0).segments(8).start(CableAnchor::world(Vec3::new(10.0, 0.0, 0.0)))).id();
    for _ in 0..30 {
        app.update();
    }
    let limb = if app.world().get::<CableRopeOf>(la).is_some() { la } else { lb };
    assert!(app.world().get::<CableRopeOf>(limb).is_some(), "one leg is a limb of the other's chain");
    for (cable, rings) in [(la, 11), (lb, 11), (single, 9)] {
        let t = tube(&app, cable);
        assert_eq!(t.rings(), rings);
        let drawn = app.world().get::<CableRenderNodes>(cable).unwrap().drawn.clone();
        let state = app.world().get::<CableState>(cable).unwrap().nodes.clone();
        assert!(close(&drawn, &state, 0.05), "drawn within a step of the state");
        check_tube(&mesh(&app, cable), &drawn, 12, 0.01);
    }
    let tubes: Vec<Entity> = [la, lb].iter().map(|e| tube(&app, *e).entity()).collect();
    app.world_mut().despawn(payload);
    for _ in 0..3 {
        app.update();
    }
    for t in tubes {
        assert!(app.world().get_entity(t).is_err(), "the legs' tubes are gone with their cables");
    }
    assert!(app.world().get::<CableTube>(single).is_some(), "the other cable keeps its tube");
}

/// The end caps: each a fan around its end node, a copy of the end ring
/// with normals along the rope, out of the tube; with them the tube is a
/// closed, consistently oriented surface (every edge, by position, is in
/// exactly two triangles, once in each direction). Moving the rope moves
/// the caps in the same mesh, indices unchanged.
#[test]
fn end_caps_close_the_tube_and_follow_the_rope() {
    let mut app = render_app();
    let nodes = bent_nodes();
    let sides = 9;
    let cable = drawn_cable(&mut app, &nodes, CableRender { sides: sides as u32, radius: Some(0.05), ..default() });
    let check_caps = |m: &Mesh, nodes: &[Vec3]| {
        let (p, n) = (f3(m, Mesh::ATTRIBUTE_POSITION), f3(m, Mesh::ATTRIBUTE_NORMAL));
        let rings = nodes.len();
        let last = rings - 1;
        for (centre, ring, outward) in [(rings * sides, 0, -tangent(nodes, 0)), (rings * sides + sides + 1, last, tangent(nodes, last))] {
            assert!((p[centre] - nodes[ring]).length() < 1e-6, "cap centre {} on node {ring} {}", p[centre], nodes[ring]);
            for j in 0..=sides {
                assert!((n[centre + j] - outward).length() < 1e-5, "cap of ring {ring}: normal {} not {outward}", n[centre + j]);
            }
            for j in 0..sides {
                assert_eq!(p[centre + 1 + j], p[ring * sides + j], "cap of ring {ring}: vertex {j} off the ring");
            }
        }
        check_tube(m, nodes, sides, 0.05);
        // Closed and consistently oriented, edges keyed by position.
        let key = |v: Vec3| (v * 1e4).round().as_ivec3().to_array();
        let mut edges = std::collections::HashMap::new();
        for tri in indices(m).chunks(3) {
            for (a, b) in [(tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])] {
                *edges.entry((key(p[a as usize]), key(p[b as usize]))).or_insert(0) += 1;
            }
        }
        for ((a, b), count) in &edges {
            assert_eq!(*count, 1, "edge {a:?} → {b:?} used {count} times in one direction");
            assert_eq!(edges.get(&(*b, *a)), Some(&1), "edge {a:?} → {b:?} has no opposite: the tube is open");
        }
    };
    let m0 = mesh(&app, cable);
    check_caps(&m0, &nodes);
    let id = tube(&app, cable).mesh().id();
    // Move the rope: same mesh, same indices, caps on the new ends.
    let moved: Vec<Vec3> = nodes.iter().enumerate().map(|(i, p)| *p + Vec3::new(0.3, 0.1 * i as f32, -0.2)).collect();
    app.world_mut().get_mut::<CableState>(cable).unwrap().nodes = moved.clone();
    until_recorded(&mut app, cable, &moved);
    // Past the interpolation: the drawn nodes are the moved ones.
    app.world_mut().get_mut::<CableState>(cable).unwrap().nodes = moved.clone();
    for _ in 0..3 {
        app.update();
    }
    let drawn = app.world().get::<CableRenderNodes>(cable).unwrap().drawn.clone();
    assert!(close(&drawn, &moved, 1e-6), "the moved nodes are drawn");
    assert_eq!(tube(&app, cable).mesh().id(), id, "the same mesh asset");
    let m1 = mesh(&app, cable);
    assert_eq!(indices(&m1), indices(&m0), "the topology is fixed");
    check_caps(&m1, &moved);
}
