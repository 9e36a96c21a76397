//! Collision groups (issue 12, a game's filtering of contacts): a rope
//! touches a collider, another rope or a body only where rapier's groups
//! test passes, both ways, as a bevy_rapier collider would. Each filtered
//! case is checked against the same scene with the default groups, and a
//! filtered fall against the closed form of free fall.

#[path = "common/plugin_app.rs"]
mod plugin_app;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::plugin::*;

const G: f32 = 9.81;
const H: f32 = 1.0 / 60.0;

use plugin_app::free_rope_laid_level as free_rope;

fn lowest(app: &App, rope: Entity) -> f32 {
    app.world().get::<CableState>(rope).unwrap().nodes.iter().map(|p| p.y).fold(f32::INFINITY, f32::min)
}

fn highest(app: &App, rope: Entity) -> f32 {
    app.world().get::<CableState>(rope).unwrap().nodes.iter().map(|p| p.y).fold(f32::NEG_INFINITY, f32::max)
}

/// A free rope laid 1 mm above a fixed 10 cm plate (top at y = 0), 30
/// frames at 1/60 s, with the rope's and the plate's groups as given: the
/// rope's lowest and highest node then, the contact force, and the
/// cable's time (s; the cable steps from the frame after its spawn).
fn rope_over_plate(rope_groups: Option<CollisionGroups>, plate: (Option<CollisionGroups>, Option<SolverGroups>)) -> (f32, f32, f32, f64) {
    let mut app = plugin_app::headless_app(H);
    let w = app.world_mut();
    let mut p = w.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, -0.05, 0.0), Collider::cuboid(5.0, 0.05, 5.0)));
    if let Some(g) = plate.0 {
        p.insert(g);
    }
    if let Some(g) = plate.1 {
        p.insert(g);
    }
    let mut d = free_rope(0.011, 0.0);
    if let Some(g) = rope_groups {
        d = d.collision_groups(g);
    }
    let rope = w.spawn(d).id();
    let errors = plugin_app::errors_over(&mut app, 30);
    assert!(errors.is_empty(), "{errors:?}");
    let st = app.world().get::<CableState>(rope).unwrap();
    (lowest(&app, rope), highest(&app, rope), st.contact_force, st.time)
}

/// A rope whose groups and a plate's keep them apart passes through the
/// plate in free fall: at the cable's time t every node is ½ g t² below
/// where it was laid (generalized-α is exact for a constant acceleration;
/// within 1e-5 m, the f32 readout), with no contact force. Each way of
/// keeping them apart is tried: the rope's filter leaves out the plate's
/// group; the plate's filter leaves out the rope's group; the plate's
/// solver groups leave out the rope's. (A rope in every group, the
/// default, like a bevy_rapier collider without `CollisionGroups`, meets
/// every filter that is not empty.) With the default groups, and with
/// groups that overlap, the same rope rests on the plate (its lowest node
/// one radius above it) carrying its weight ρ g L = 47.088 N.
#[test]
fn a_rope_passes_through_a_collider_its_groups_leave_out_and_rests_on_one_they_meet() {
    let laid = 0.011;
    let weight = 1.6 * 3.0 * G;
    let rope_only_1 = CollisionGroups::new(Group::GROUP_1, Group::GROUP_1);
    let apart = [
        ("the rope's filter", Some(rope_only_1), (Some(CollisionGroups::new(Group::GROUP_2, Group::ALL)), None)),
        ("the plate's filter", Some(CollisionGroups::new(Group::GROUP_3, Group::ALL)), (Some(CollisionGroups::new(Group::GROUP_2, Group::GROUP_2)), None)),
        ("the plate's solver groups", Some(CollisionGroups::new(Group::GROUP_1, Group::ALL)), (None, Some(SolverGroups::new(Group::GROUP_2, Group::GROUP_2)))),
    ];
    for (what, rope, plate) in apart {
        let (low, high, force, t) = rope_over_plate(rope, plate);
        let fall = 0.5 * G * (t * t) as f32;
        println!("kept apart by {what} (t = {t:.4} s): nodes at {low:.6} … {high:.6} m (free fall: {:.6} m); contact force {force} N", laid - fall);
        assert!((low - (laid - fall)).abs() < 1e-5 && (high - (laid - fall)).abs() < 1e-5, "{what}: nodes at {low} … {high} m, free fall to {} m", laid - fall);
        assert_eq!(force, 0.0, "{what}");
    }
    let meet = [
        ("the default groups", None, (None, None)),
        (
            "overlapping groups",
            Some(CollisionGroups::new(Group::GROUP_1 | Group::GROUP_2, Group::GROUP_2)),
            (Some(CollisionGroups::new(Group::GROUP_2, Group::GROUP_1)), None),
        ),
    ];
    for (what, rope, plate) in meet {
        let (low, high, force, _) = rope_over_plate(rope, plate);
        println!("{what}: nodes at {low:.6} … {high:.6} m; contact force {force:.4} N (weight {weight:.4} N)");
        assert!((low - 0.01).abs() < 1e-5 && (high - 0.01).abs() < 1e-5, "{what}: nodes at {low} … {high} m");
        assert!((force / weight - 1.0).abs() < 1e-3, "{what}: contact force {force} N against the weight {weight} N");
    }
}

/// Two free ropes crossing at right angles, the upper one laid 5 cm above
/// the lower, which lies on the ground: with groups that keep the two
/// ropes apart the upper one falls through the lower onto the ground (its
/// lowest node one radius up), and with the default groups it comes to
/// rest across the lower one (its crossing node one diameter higher).
#[test]
fn a_rope_falls_through_another_rope_its_groups_leave_out() {
    let run_pair = |groups: Option<(CollisionGroups, CollisionGroups)>| {
        let mut app = plugin_app::headless_app(H);
        let w = app.world_mut();
        w.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, -0.5, 0.0), Collider::cuboid(5.0, 0.5, 5.0)));
        let mut lower = free_rope(0.0101, 0.0).damping(0.01);
        let mut upper = CableDescriptor::new(3.0)
            .material(RopeMaterial::steel_6x36_iwrc(0.02))
            .segments(30)
            .start(CableAnchor::Free)
            .path([Vec3::new(0.0, 0.06, -1.5), Vec3::new(0.0, 0.06, 1.5)])
            .damping(0.01);
        if let Some((a, b)) = groups {
            lower = lower.collision_groups(a);
            upper = upper.collision_groups(b);
        }
        w.spawn(lower);
        let upper = w.spawn(upper).id();
        let errors = plugin_app::errors_over(&mut app, 90);
        assert!(errors.is_empty(), "{errors:?}");
        (lowest(&app, upper), highest(&app, upper))
    };
    let apart = Some((CollisionGroups::new(Group::GROUP_1, Group::ALL), CollisionGroups::new(Group::GROUP_2, Group::GROUP_2 | Group::GROUP_3)));
    let (low, high) = run_pair(apart);
    println!("kept apart: the upper rope lies at {low:.5} … {high:.5} m");
    assert!((low - 0.01).abs() < 1e-4 && (high - 0.01).abs() < 1e-4, "kept apart, the upper rope should lie on the ground: {low} … {high} m");
    let (low, high) = run_pair(None);
    println!("default groups: the upper rope lies at {low:.5} … {high:.5} m");
    assert!((high - 0.03).abs() < 1e-3, "across the lower rope the upper one should rest a diameter up: highest node {high} m");
}

/// A 100 kg crate (0.4 m cube) on a 3 m rope from a fixed point 3 m above
/// the ground's top, laid so that it hangs 0.5 m into the ground: with the
/// default groups it stands on the ground and the rope is slack; with
/// groups that keep the crate (and its rope) and the ground apart it hangs
/// through the ground on its rope, whose top tension then carries the crate and the
/// rope (m g + ρ g L = 1 032.8 N, within 1e-3) and its centre is 0.5 m
/// down (within 1 mm: the rope stretches by 0.15 mm).
#[test]
fn a_carried_crate_meets_the_ground_only_if_their_groups_meet() {
    let run_crate = |crate_groups: Option<CollisionGroups>| {
        let mut app = plugin_app::headless_app(H);
        let w = app.world_mut();
        w.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, -0.5, 0.0), Collider::cuboid(5.0, 0.5, 5.0), CollisionGroups::new(Group::GROUP_2, Group::ALL)));
        let mut c = w.spawn((
            RigidBody::Dynamic,
            Transform::from_xyz(0.0, 0.2, 0.0),
            Collider::cuboid(0.2, 0.2, 0.2),
            ColliderMassProperties::Mass(100.0),
            Velocity::zero(),
            Damping { linear_damping: 2.0, angular_damping: 2.0 },
        ));
        if let Some(g) = crate_groups {
            c.insert(g);
        }
        let c = c.id();
        let rope = CableDescriptor::new(3.3).material(RopeMaterial::steel_6x36_iwrc(0.02)).segments(20).damping(0.01);
        let rope = crate_groups.map_or(rope.clone(), |g| rope.collision_groups(g));
        let rope = w.spawn(rope.start(CableAnchor::world(Vec3::new(0.0, 3.0, 0.0))).end(CableAnchor::body(c, Vec3::Y * 0.2))).id();
        let errors = plugin_app::errors_over(&mut app, 240);
        assert!(errors.is_empty(), "{errors:?}");
        let y = app.world().get::<Transform>(c).unwrap().translation.y;
        let top = app.world().get::<CableState>(rope).unwrap().tensions[0];
        (y, top)
    };
    let (y, top) = run_crate(None);
    println!("default groups: crate centre at {y:.4} m, top tension {top:.1} N");
    assert!((y - 0.2).abs() < 2e-3 && top < 50.0, "the crate should stand on the ground, its rope slack: centre {y} m, top tension {top} N");
    let (y, top) = run_crate(Some(CollisionGroups::new(Group::GROUP_1, Group::GROUP_1)));
    let carried = 100.0 * G + 1.6 * 3.3 * G;
    println!("kept apart: crate centre at {y:.4} m, top tension {top:.1} N (m g + ρ g L = {carried:.1} N)");
    assert!((y + 0.5).abs() < 1e-3, "kept apart, the crate should hang through the ground: centre {y} m");
    assert!((top / carried - 1.0).abs() < 1e-3, "top tension {top} N against {carried} N");
}

/// A 5 kg ball dropped from 1 m onto a taut rope between two posts: with
/// the default groups it lands on the rope and stays above it; with groups
/// that keep the ball and the rope apart it falls past the rope as rapier
/// moves it (below the rope after 0.6 s) and the rope moves exactly as it
/// does in the same scene without the ball.
#[test]
fn a_ball_falls_through_a_rope_its_groups_leave_out() {
    let run_ball = |ball: Option<Option<CollisionGroups>>| {
        let mut app = plugin_app::headless_app(H);
        let w = app.world_mut();
        let ball = ball.map(|groups| {
            let mut b =
                w.spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, 1.0, 0.0), Collider::ball(0.1), ColliderMassProperties::Mass(5.0), Velocity::zero()));
            if let Some(g) = groups {
                b.insert(g);
            }
            b.id()
        });
        let rope = w
            .spawn(
                CableDescriptor::new(3.0)
                    .material(RopeMaterial::steel_6x36_iwrc(0.02))
                    .segments(30)
                    .damping(0.01)
                    .start(CableAnchor::world(Vec3::new(-1.5, 0.0, 0.0)))
                    .end(CableAnchor::world(Vec3::new(1.5, 0.0, 0.0)))
                    .collision_groups(CollisionGroups::new(Group::GROUP_1, Group::GROUP_1)),
            )
            .id();
        let errors = plugin_app::errors_over(&mut app, 36);
        assert!(errors.is_empty(), "{errors:?}");
        (ball.map_or(f32::NAN, |b| app.world().get::<Transform>(b).unwrap().translation.y), lowest(&app, rope))
    };
    let (_, alone) = run_ball(None);
    let (y, rope_low) = run_ball(Some(None));
    println!("default groups: ball centre at {y:.4} m, rope's lowest node {rope_low:.4} m");
    assert!(y > rope_low + 0.1 && rope_low < -1e-3, "the ball should rest on the rope, pushing it down: ball {y} m, rope {rope_low} m");
    let (y, rope_low) = run_ball(Some(Some(CollisionGroups::new(Group::GROUP_2, Group::ALL))));
    println!("kept apart: ball centre at {y:.4} m, rope's lowest node {rope_low:.6} m (without a ball: {alone:.6} m)");
    assert!(y < -0.5, "the ball should fall past the rope: ball {y} m");
    assert_eq!(rope_low, alone, "the rope should move as with no ball at all");
}
