//! The plugin's components as a Bevy user reads them (issue 11): builder
//! constructors with defaults and a typed material, `Reflect`
//! registration, and entity references that survive a remapping
//! (`MapEntities`: scenes, cloning into another world).

#[path = "common/plugin_app.rs"]
mod plugin_app;

use bevy::ecs::entity::EntityHashMap;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::{preset, RopeMaterial};
use bevy_rapier_cable::integrate::Scheme;
use bevy_rapier_cable::plugin::*;

/// The builder's defaults are the documented ones, and each method sets
/// what it names, with Bevy's f32 and `Vec3` at the boundary.
#[test]
fn the_builder_has_documented_defaults_and_sets_what_it_names() {
    let d = CableDescriptor::new(12.0);
    assert_eq!(d.length, 12.0);
    assert_eq!(d.segments, 24, "one element per 0.5 m");
    assert_eq!(CableDescriptor::default_segments(0.3), 4);
    assert_eq!(CableDescriptor::default_segments(1000.0), 100);
    assert_eq!(d.material, RopeMaterial::steel_6x36_iwrc(0.02));
    assert_eq!(d.material.section(), preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap());
    assert_eq!((d.start.clone(), d.end.clone()), (CableAnchor::world(Vec3::ZERO), CableAnchor::Free));
    assert!(d.tension_only && d.damping == 0.0 && d.static_start.is_none() && d.loads.is_empty() && !d.stress_free);
    let body = Entity::from_raw_u32(7).unwrap();
    let d = d
        .segments(30)
        .material(RopeMaterial::polyester(0.03))
        .start(CableAnchor::world_clamped(Vec3::Y))
        .end(CableAnchor::body(body, Vec3::Y * 0.5))
        .path([Vec3::Y, Vec3::ZERO])
        .stress_free(true)
        .damping(0.25)
        .tension_only(false)
        .scheme(Scheme::Newmark { beta: 0.25, gamma: 0.5 })
        .static_start(5)
        .point_load(6.0, Vec3::new(0.0, -100.0, 0.0));
    assert_eq!(d.segments, 30);
    assert_eq!(d.material.diameter(), 0.03);
    assert_eq!(d.start, CableAnchor::World { point: Vec3::Y, clamp: true });
    assert_eq!(d.end, CableAnchor::Body { entity: body, anchor: Vec3::Y * 0.5, clamp: false });
    assert_eq!(d.path.as_deref(), Some(&[Vec3::Y, Vec3::ZERO][..]));
    assert!(d.stress_free);
    assert_eq!((d.damping, d.tension_only, d.static_start), (0.25, false, Some(5)));
    assert_eq!(d.loads[0].s, 6.0);
    assert_eq!(d.loads[0].force.y, -100.0);
}

/// A newcomer's rope with the builder alone: a 500 kg ball on 8 m of
/// 20 mm steel wire rope hangs where the closed form puts it, the rope's
/// stretch m g L/EA (with the rope's own weight below the mid-point) and
/// the tension at the top m g + μ g L.
#[test]
fn a_payload_hung_with_the_builder_sits_at_the_static_stretch() {
    let mut app = plugin_app::headless_app(1.0 / 60.0);
    let (l, r, m) = (8.0f32, 0.25f32, 500.0f32);
    let payload = app.world_mut().spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, -(l + r), 0.0), Collider::ball(r), ColliderMassProperties::Mass(m))).id();
    let cable = app
        .world_mut()
        .spawn(CableDescriptor::new(l).material(RopeMaterial::steel_6x36_iwrc(0.02)).end(CableAnchor::body(payload, Vec3::Y * r)).damping(0.01).static_start(1))
        .id();
    for _ in 0..120 {
        app.update();
    }
    let sec = RopeMaterial::steel_6x36_iwrc(0.02).section();
    let (g, lf, mf) = (9.81, l as f64, m as f64);
    let stretch = (mf * g + 0.5 * sec.linear_density * g * lf) * lf / sec.ea;
    let y = app.world().get::<Transform>(payload).unwrap().translation.y as f64;
    let state = app.world().get::<CableState>(cable).unwrap();
    let top = state.tensions[0] as f64;
    let top_ref = mf * g + sec.linear_density * g * lf;
    println!("payload at {y:.6} m (closed form {:.6} m); top tension {top:.1} N ({top_ref:.1} N)", -(lf + r as f64) - stretch);
    assert!((y + lf + r as f64 + stretch).abs() < 0.05 * stretch + 1e-5, "payload at {y}");
    assert!((top / top_ref - 1.0).abs() < 0.01, "top tension {top} vs {top_ref}");
}

/// Every component and resource of the plugin is in the type registry, the
/// descriptor as a reflected component.
#[test]
fn components_and_resources_are_reflect_registered() {
    let app = plugin_app::headless_app(1.0 / 60.0);
    let registry = app.world().resource::<AppTypeRegistry>().read();
    use std::any::TypeId;
    for (name, id) in [
        ("CableDescriptor", TypeId::of::<CableDescriptor>()),
        ("CableSim", TypeId::of::<CableSim>()),
        ("CableState", TypeId::of::<CableState>()),
        ("CableRopeOf", TypeId::of::<CableRopeOf>()),
        ("CableExact", TypeId::of::<CableExact>()),
        ("BodyExact", TypeId::of::<BodyExact>()),
    ] {
        let reg = registry.get(id).unwrap_or_else(|| panic!("{name} not registered"));
        assert!(reg.data::<ReflectComponent>().is_some(), "{name} not reflected as a component");
    }
    assert!(registry.get(TypeId::of::<CableSettings>()).and_then(|r| r.data::<ReflectResource>()).is_some());
    assert!(registry.get(TypeId::of::<CableError>()).is_some());
    // A reflected descriptor reads back its fields by name.
    let d = CableDescriptor::new(5.0);
    let field = d.reflect_ref().as_struct().unwrap().field("length").unwrap().try_downcast_ref::<f64>().copied();
    assert_eq!(field, Some(5.0));
}

/// The body entities a descriptor names are remapped with the component
/// (what a scene load or a clone into another world does), so a cable
/// spawned from a scene hangs on the scene's bodies, not on stale ids.
#[test]
fn body_anchors_are_remapped_with_the_descriptor() {
    let (a, b, a2, b2) =
        (Entity::from_raw_u32(1).unwrap(), Entity::from_raw_u32(2).unwrap(), Entity::from_raw_u32(11).unwrap(), Entity::from_raw_u32(12).unwrap());
    let mut d = CableDescriptor::new(3.0).start(CableAnchor::body_clamped(a, Vec3::ZERO)).end(CableAnchor::body(b, Vec3::Y));
    let mut map: EntityHashMap<Entity> = EntityHashMap::default();
    map.insert(a, a2);
    map.insert(b, b2);
    <CableDescriptor as Component>::map_entities(&mut d, &mut map);
    assert_eq!(d.start, CableAnchor::body_clamped(a2, Vec3::ZERO));
    assert_eq!(d.end, CableAnchor::body(b2, Vec3::Y));
    // A world anchor has no entity to map.
    let mut w = CableDescriptor::new(3.0);
    <CableDescriptor as Component>::map_entities(&mut w, &mut map);
    assert_eq!(w.start, CableAnchor::world(Vec3::ZERO));
}

/// A second rope spawned later on a body a cable already carries is
/// refused as a configuration error that names the carrying cable's entity
/// (not the core's index) and says how to hang the body on both.
#[test]
fn a_later_rope_on_a_carried_body_names_the_carrying_cable() {
    let mut app = plugin_app::headless_app(1.0 / 60.0);
    let payload =
        app.world_mut().spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, -5.3, 0.0), Collider::ball(0.3), ColliderMassProperties::Mass(200.0))).id();
    let first = app.world_mut().spawn(CableDescriptor::new(5.0).end(CableAnchor::body(payload, Vec3::Y * 0.3))).id();
    for _ in 0..3 {
        app.update();
    }
    let second = app.world_mut().spawn(CableDescriptor::new(5.0).start(CableAnchor::world(Vec3::X * 3.0)).end(CableAnchor::body(payload, Vec3::Y * 0.3))).id();
    let errors = plugin_app::errors_over(&mut app, 2);
    println!("{}", errors.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"));
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert_eq!((errors[0].entity, errors[0].kind), (second, CableErrorKind::Configuration));
    assert!(errors[0].message.contains(&format!("cable {first} already carries")) && errors[0].message.contains("same frame"), "{}", errors[0]);
    assert!(!app.world().get::<CableSim>(first).unwrap().failed, "the first cable runs on");
}
