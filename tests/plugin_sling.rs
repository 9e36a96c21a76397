//! Issue 10 item 2 in the plugin: a payload on two ropes (a two-leg sling)
//! spawned as a Bevy user would, two `CableDescriptor`s ending on the same
//! dynamic body. The plugin solves both ropes and the body as one implicit
//! island: the first cable carries the body (`CableSim`), the second is a
//! limb grafted onto it (`CableRopeOf`, its own `CableState`).

#[path = "common/irvine.rs"]
mod irvine;
#[path = "common/plugin_app.rs"]
mod plugin_app;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier_cable::cable::preset;
use bevy_rapier_cable::cable::RopeMaterial;
use bevy_rapier_cable::plugin::*;
use irvine::irvine_leg;

const DT: f32 = 1.0 / 60.0;
const G: f64 = 9.81;
const M: f64 = 1000.0;

/// A 1 t ball (radius 0.3 m, legs attached at its centre) at (0, −8, 0) on
/// two 10 m legs of 20 mm steel wire rope from (∓6, 0, 0), N = 10 each,
/// damped (τ = 0.05 s), built. Returns (payload, leg a, leg b).
fn sling(app: &mut App) -> (Entity, Entity, Entity) {
    let w = app.world_mut();
    let payload =
        w.spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, -8.0, 0.0), Collider::ball(0.3), ColliderMassProperties::Mass(M as f32), Velocity::zero())).id();
    let section = preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap();
    let mut leg = |x: f32| {
        let mut d = CableDescriptor::from_section(
            10.0,
            10,
            RopeMaterial::custom(section, 0.02),
            CableAnchor::World { point: Vec3::new(x, 0.0, 0.0), clamp: false },
            CableAnchor::Body { entity: payload, anchor: Vec3::ZERO, clamp: false },
        );
        d.damping = 0.05;
        w.spawn(d).id()
    };
    let (a, b) = (leg(-6.0), leg(6.0));
    for _ in 0..2 {
        app.update();
    }
    let failed: Vec<String> = app.world().resource::<Messages<CableError>>().iter_current_update_messages().map(|m| m.message.clone()).collect();
    assert!(failed.is_empty(), "{failed:?}");
    (payload, a, b)
}

fn position(app: &App, e: Entity) -> Vec3 {
    app.world().get::<Transform>(e).unwrap().translation
}

/// Released from straight legs at the frame step with the defaults, the
/// sling settles on the elastic catenary of a leg carrying half the
/// payload's weight: the payload's depth and each leg's tension at its
/// anchor (`CableState::tensions[0]`, both legs from their own start).
/// Then an `ExternalImpulse` across the sling's plane swings it about the
/// anchor line with the closed-form period ω² = (g/d)(M + m_r/2)/(M + m_r/3)
/// (m_r: the legs' mass), the legs' tension staying at its static value.
#[test]
fn two_leg_sling_in_the_plugin_hangs_on_the_catenary_and_swings() {
    let mut app = plugin_app::headless_app(DT);
    let (payload, a, b) = sling(&mut app);
    // One leg carries the payload, the other is grafted onto it.
    let (carrier, grafted) = if app.world().get::<CableSim>(a).is_some() { (a, b) } else { (b, a) };
    assert!(app.world().get::<CableSim>(carrier).is_some() && app.world().get::<CableSim>(grafted).is_none());
    assert_eq!(app.world().get::<CableRopeOf>(grafted), Some(&CableRopeOf { cable: carrier, rope: 1 }));
    assert!(app.world().get::<RigidBody>(payload) == Some(&RigidBody::Dynamic), "the payload stays a dynamic rapier body");
    for _ in 0..480 {
        app.update();
    }
    let s = preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap();
    let w = s.linear_density * G;
    let (depth, h) = irvine_leg(10.0, w, s.ea, 6.0, M * G / 2.0);
    let t_top = h.hypot(M * G / 2.0 + w * 10.0);
    let p = position(&app, payload);
    let d = -p.y as f64;
    let e = |x: f64, r: f64| (x - r) / r;
    let (ta, tb) = (app.world().get::<CableState>(a).unwrap().tensions[0] as f64, app.world().get::<CableState>(b).unwrap().tensions[0] as f64);
    println!("depth {d:.6} (Irvine {depth:.6}) {:+.1e}; tops {ta:.2} / {tb:.2} (Irvine {t_top:.2}) {:+.1e} / {:+.1e}", e(d, depth), e(ta, t_top), e(tb, t_top));
    assert!(e(d, depth).abs() < 2e-5 && p.x.abs() < 1e-4 && p.z.abs() < 1e-4, "payload at {p}");
    assert!(e(ta, t_top).abs() < 2e-3 && e(tb, t_top).abs() < 2e-3, "top tensions {ta}, {tb} vs {t_top}");
    // Both legs' states run from their anchor to the payload.
    for (leg, x) in [(a, -6.0), (b, 6.0)] {
        let nodes = &app.world().get::<CableState>(leg).unwrap().nodes;
        assert!(nodes[0].distance(Vec3::new(x, 0.0, 0.0)) < 1e-3 && nodes[10].distance(p) < 1e-3, "leg nodes {nodes:?}");
    }
    // Kick across the plane: 100 N·s on 1 t (0.1 m/s).
    app.world_mut().entity_mut(payload).insert(ExternalImpulse { impulse: Vec3::new(0.0, 0.0, 100.0), torque_impulse: Vec3::ZERO });
    let m_r = 2.0 * 10.0 * s.linear_density;
    let period = 2.0 * std::f64::consts::PI / (G / d * (M + m_r / 2.0) / (M + m_r / 3.0)).sqrt();
    let (mut last_z, mut crossings, mut peak, mut t) = (0.0f64, Vec::new(), 0.0f64, 0.0);
    while t < 4.2 * period {
        app.update();
        t += DT as f64;
        let z = position(&app, payload).z as f64;
        peak = peak.max(z.abs());
        if last_z > 0.0 && z <= 0.0 {
            crossings.push(t - DT as f64 * z / (z - last_z));
        }
        last_z = z;
    }
    assert!(!app.world().get::<CableSim>(carrier).unwrap().failed);
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    // The swing mode's share of the impulse: J/(M + m_r/3), amplitude v/ω.
    // Not a verification: from this released (not static) start the kick
    // step needs Newton's sub-step fallback (a loop closed by a stiff
    // anchor spring, docs/verification.md "Slings") and the amplitude comes
    // out 1.5 % low; from the static start (tests/sling.rs) it is 2e-4.
    // Checked here only as "the impulse reached the island".
    let amp = 100.0 / (M + m_r / 3.0) / (2.0 * std::f64::consts::PI / period);
    println!("period {measured:.5} (closed form {period:.5}) {:+.1e}; amplitude {peak:.5} ({amp:.5}) {:+.1e}", e(measured, period), e(peak, amp));
    assert!(e(measured, period).abs() < 2e-4, "period {measured} vs {period}");
    assert!(e(peak, amp).abs() < 0.05, "amplitude {peak} vs {amp}");
}

/// A loop through two dynamic bodies (a box on a rope from the world and on
/// a rope from a block, the block on a rope from the world) is refused at
/// creation: every cable of the island gets a `CableError` message, the
/// first naming both bodies, and none is built.
#[test]
fn a_loop_through_two_dynamic_bodies_is_refused_by_name() {
    let mut app = plugin_app::headless_app(DT);
    let w = app.world_mut();
    let body = |w: &mut World, y: f32, x: f32| {
        w.spawn((RigidBody::Dynamic, Transform::from_xyz(x, y, 0.0), Collider::ball(0.2), ColliderMassProperties::Mass(50.0))).id()
    };
    let (boxed, block) = (body(w, -8.0, 0.0), body(w, -3.0, 6.0));
    let section = preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap();
    let cable = |w: &mut World, start: CableAnchor, end: CableAnchor, len: f64| {
        w.spawn(CableDescriptor::from_section(len, 4, RopeMaterial::custom(section, 0.02), start, end)).id()
    };
    let at = |entity| CableAnchor::Body { entity, anchor: Vec3::ZERO, clamp: false };
    let world = |x: f32| CableAnchor::World { point: Vec3::new(x, 0.0, 0.0), clamp: false };
    let cables = [cable(w, world(-6.0), at(boxed), 10.0), cable(w, at(block), at(boxed), 7.9), cable(w, world(6.0), at(block), 3.0)];
    let mut messages = Vec::new();
    for _ in 0..2 {
        app.update();
        messages.extend(app.world().resource::<Messages<CableError>>().iter_current_update_messages().map(|m| (m.entity, m.message.clone())));
    }
    println!("{messages:#?}");
    for c in cables {
        assert!(messages.iter().any(|(e, _)| *e == c), "cable {c} reported");
        assert!(app.world().get::<CableSim>(c).is_none() && app.world().get::<CableRopeOf>(c).is_none());
    }
    let (b, k) = (boxed.to_string(), block.to_string());
    assert!(messages.iter().any(|(_, m)| m.contains(&b) && m.contains(&k) && m.contains("loop through two dynamic bodies")), "{messages:?}");
}

/// A newcomer's sling laid slack, with the defaults (no damping), as
/// `scenarios::an_undamped_sling_laid_slack_from_one_hook_never_gains_energy`
/// through `cablesim`: a 500 kg crate (cuboid collider 1 × 0.6 × 1 m) on
/// two 3.2 m legs of 16 mm steel rope from one fixed hook body to the
/// middles of its top edges (0.55 m of slack each), over a ground, pushed
/// across with an `ExternalImpulse` of 300 N·s at 1.5 s; 2.5 s at 1/60 s.
/// No `CableError`; the crate drops onto its legs, bounces, and never
/// rises above where it was let go (before 2026-11-28 the legs whipping
/// into each other threw it 8 m up and the cable stopped at 0.55 s); the
/// push moves it across at the momentum it gives, within what the legs
/// take in the frame.
#[test]
fn an_undamped_sling_laid_slack_in_the_plugin_bounces_without_gaining_energy() {
    let mut app = plugin_app::headless_app(DT);
    let w = app.world_mut();
    w.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, -2.5, 0.0), Collider::cuboid(20.0, 0.5, 20.0)));
    let hook = w.spawn((RigidBody::Fixed, Transform::from_xyz(0.0, 3.0, 0.0), Collider::ball(0.1))).id();
    let crate_ = w
        .spawn((
            RigidBody::Dynamic,
            Collider::cuboid(0.5, 0.3, 0.5),
            ColliderMassProperties::Mass(500.0),
            Transform::from_xyz(0.0, 0.0, 0.0),
            Velocity::zero(),
            ExternalImpulse::default(),
        ))
        .id();
    let rope = RopeMaterial::steel_6x36_iwrc(0.016);
    for x in [-0.5, 0.5] {
        w.spawn(
            CableDescriptor::new(3.2)
                .material(rope)
                .segments(16)
                .start(CableAnchor::body(hook, Vec3::Y * -0.1))
                .end(CableAnchor::body(crate_, Vec3::new(x, 0.3, 0.0))),
        );
    }
    let (mut highest, mut lowest) = (f32::NEG_INFINITY, f32::INFINITY);
    let mut after_push = Vec3::ZERO;
    for frame in 1..=150 {
        if frame == 90 {
            app.world_mut().get_mut::<ExternalImpulse>(crate_).unwrap().impulse = Vec3::Z * 300.0;
        }
        app.update();
        let errors = plugin_app::cable_errors(&mut app);
        assert!(errors.is_empty(), "frame {frame}: {errors:?}");
        let y = position(&app, crate_).y;
        if frame > 1 {
            highest = highest.max(y);
        }
        lowest = lowest.min(y);
        if frame == 90 {
            after_push = app.world().get::<Velocity>(crate_).unwrap().linear;
        }
    }
    println!("crate between {lowest:.4} and {highest:.4} m; velocity after the push {after_push:?} (300 N·s / 500 kg = 0.6 m/s across)");
    assert!(highest < 0.01, "the crate rose to {highest} m");
    assert!(lowest > -0.7, "the crate fell to {lowest} m: the legs would have to stretch");
    assert!(after_push.z > 0.3 && after_push.z < 0.61, "the push gave {} m/s across", after_push.z);
}

/// A newcomer's crane through the plugin, with the defaults (no damping):
/// a kinematic (velocity-based) jib at 12 m swung ±1.5 m along x (4 s
/// period, its `Velocity` written every frame), a 200 kg hook ball on 8 m
/// of 16 mm steel rope laid 0.2 m slack, a 1 t crate on 1.8 m below it
/// given 0.5 m/s across. Both ropes and the two bodies are one island on
/// the jib's sampled motion. It runs 1.2 s without a `CableError` (before
/// 2026-11-28, eighth session, it stopped at 0.83 s: "Newton did not
/// converge" at every split; the moving jib's work is now counted in the
/// energy check, so the tangent's fallback is tried at every split, and a
/// finest-split sub-step that fails is cut further), and the crate stays
/// where stretched ropes would put it at most (a 1 % strain of both:
/// above 1.10 m).
#[test]
fn an_undamped_hook_and_crate_under_a_swinging_jib_run_in_the_plugin() {
    let mut app = plugin_app::headless_app(DT);
    let w = app.world_mut();
    let jib = w.spawn((RigidBody::KinematicVelocityBased, Transform::from_xyz(0.0, 12.0, 0.0), Collider::cuboid(0.5, 0.2, 0.5), Velocity::zero())).id();
    let hook =
        w.spawn((RigidBody::Dynamic, Collider::ball(0.2), ColliderMassProperties::Mass(200.0), Transform::from_xyz(0.0, 3.8, 0.0), Velocity::zero())).id();
    let crate_ = w
        .spawn((
            RigidBody::Dynamic,
            Collider::cuboid(0.6, 0.4, 0.6),
            ColliderMassProperties::Mass(1000.0),
            Transform::from_xyz(0.0, 1.4, 0.0),
            Velocity::linear(Vec3::Z * 0.5),
        ))
        .id();
    let rope = RopeMaterial::steel_6x36_iwrc(0.016);
    w.spawn(CableDescriptor::new(8.0).material(rope).segments(32).start(CableAnchor::body(jib, Vec3::Y * -0.2)).end(CableAnchor::body(hook, Vec3::Y * 0.2)));
    w.spawn(CableDescriptor::new(1.8).material(rope).segments(8).start(CableAnchor::body(hook, Vec3::Y * -0.2)).end(CableAnchor::body(crate_, Vec3::Y * 0.4)));
    let omega = std::f32::consts::TAU / 4.0;
    let (mut lowest, mut farthest) = (f32::INFINITY, 0.0f32);
    for frame in 0..72 {
        let t = frame as f32 * DT;
        app.world_mut().get_mut::<Velocity>(jib).unwrap().linear = Vec3::X * 1.5 * omega * (omega * t).cos();
        app.update();
        let errors = plugin_app::cable_errors(&mut app);
        assert!(errors.is_empty(), "frame {frame}: {errors:?}");
        let p = position(&app, crate_);
        lowest = lowest.min(p.y);
        farthest = farthest.max(p.x.abs());
    }
    let jib_x = position(&app, jib).x;
    println!("1.2 s: jib at x = {jib_x:.3} m; crate lowest {lowest:.4} m, farthest {farthest:.3} m along x");
    assert!(jib_x > 1.0, "the jib did not move: {jib_x}");
    assert!(lowest > 1.10, "the crate fell to {lowest} m: the ropes would have to stretch");
}

/// A rope with both ends on one dynamic body (a handle on a crate) is
/// refused at creation by name, with what to do instead; the body stays a
/// rapier body and falls.
#[test]
fn a_rope_from_a_body_to_itself_is_refused_by_name() {
    let mut app = plugin_app::headless_app(DT);
    let w = app.world_mut();
    let crate_ = w.spawn((RigidBody::Dynamic, Transform::from_xyz(0.0, 2.0, 0.0), Collider::cuboid(0.5, 0.5, 0.5), ColliderMassProperties::Mass(50.0))).id();
    let section = preset("steel_wire_rope_6x36_iwrc", 0.012).unwrap();
    let handle = w
        .spawn(
            CableDescriptor::from_section(
                1.6,
                8,
                RopeMaterial::custom(section, 0.012),
                CableAnchor::body(crate_, Vec3::new(-0.4, 0.5, 0.0)),
                CableAnchor::body(crate_, Vec3::new(0.4, 0.5, 0.0)),
            )
            .path([Vec3::new(-0.4, 2.5, 0.0), Vec3::new(-0.4, 3.1, 0.0), Vec3::new(0.4, 3.1, 0.0), Vec3::new(0.4, 2.5, 0.0)]),
        )
        .id();
    let errors = plugin_app::errors_over(&mut app, 30);
    println!("{errors:#?}");
    assert_eq!(errors.iter().map(|e| (e.entity, e.kind)).collect::<Vec<_>>(), vec![(handle, CableErrorKind::Configuration)], "{errors:?}");
    let m = &errors[0].message;
    assert!(m.contains(&format!("{crate_} to itself")) && m.contains("two-leg sling"), "{m}");
    assert!(app.world().get::<CableSim>(handle).is_none());
    let v = app.world().get::<Velocity>(crate_).map_or(0.0, |v| v.linear.y);
    let y = app.world().get::<Transform>(crate_).unwrap().translation.y;
    assert!(y < 1.0, "the crate falls as a rapier body: y = {y} (velocity {v})");
}
