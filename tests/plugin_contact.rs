//! Contact in a Bevy app (issue 12): a rope against a bevy_rapier collider,
//! read from `CableState::contact_force`.

#[path = "common/plugin_app.rs"]
mod plugin_app;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::plugin::*;

/// A free 10 m steel rope (20 mm) dropped 1 mm onto a fixed ground box, as
/// a Bevy user spawns it: after 3 s at 1/60 s `CableState::contact_force`
/// reads its weight ρ g L = 156.96 N within 1e-5 (f32), its nodes lie on
/// the ground (the radius above it within 1e-5 m), and with `contacts(false)`
/// the same rope falls through the ground.
#[test]
fn a_rope_dropped_on_the_ground_rests_on_it_and_reports_its_weight() {
    let run = |contacts: bool| {
        let mut app = plugin_app::headless_app(1.0 / 60.0);
        let w = app.world_mut();
        w.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, -0.5, 0.0), Collider::cuboid(20.0, 0.5, 20.0)));
        let path = [Vec3::new(-5.0, 0.011, 0.0), Vec3::new(5.0, 0.011, 0.0)];
        let rope = w
            .spawn(CableDescriptor::new(10.0).material(RopeMaterial::steel_6x36_iwrc(0.02)).segments(20).start(CableAnchor::Free).path(path).contacts(contacts))
            .id();
        for _ in 0..(3 * 60) {
            app.update();
        }
        let st = app.world().get::<CableState>(rope).unwrap().clone();
        let low = st.nodes.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        (st.contact_force, low)
    };
    let weight = 1.6 * 10.0 * 9.81;
    let (force, low) = run(true);
    let (_, fallen) = run(false);
    println!("contact force {force:.4} N vs {weight:.4} N; lowest node {low:.6} m; without contacts {fallen:.2} m");
    assert!((force as f64 / weight - 1.0).abs() < 1e-5, "contact force {force}");
    assert!((low - 0.01).abs() < 1e-5, "lowest node {low}");
    assert!(fallen < -10.0, "without contacts the rope fell to {fallen}");
}
