//! Slings: one payload on several ropes, solved as one tree-shaped chain
//! (issue 10, item 2). The payload hangs on leg 0; the other legs are
//! grafted onto it as limbs whose far ends are pinned to the world by
//! implicit anchor springs.

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::Scheme;
use glam::{DMat3, DVec3};

#[path = "common/irvine.rs"]
mod irvine;
use irvine::irvine_leg;

const G: f64 = 9.81;

fn steel20() -> RopeSection {
    preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap()
}

/// A payload of `mass` (a 0.3 m sphere whose centre is the attachment
/// point) at `apex`, on straight legs from each of `anchors`, `n` elements
/// each.
fn sling(anchors: &[DVec3], apex: DVec3, mass: f64, n: usize, section: RopeSection, damping: f64) -> Cable {
    let body = LumpedBody::sphere(mass, 0.3, apex);
    let leg0 = anchors[0].distance(apex);
    let mut model = RopeBuilder::new(leg0, n, section, 0.02)
        .damping(damping)
        .start(RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, anchors[0]))))
        .path(vec![anchors[0], apex])
        .end(RopeEnd::Body { body, anchor: DVec3::ZERO, clamp: false })
        .build()
        .unwrap();
    let at = model.layout.end_body.unwrap();
    for &a in &anchors[1..] {
        let leg = RopeBuilder::new(a.distance(apex), n, section, 0.02)
            .damping(damping)
            .start(RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, apex))))
            .path(vec![apex, a])
            .end(RopeEnd::Pinned(BaseMotion::point(a)))
            .build()
            .unwrap();
        model.graft(leg, &at, true).unwrap();
    }

    Cable::new(model, Scheme::default()).unwrap()
}

/// Statics of a symmetric two-leg sling (legs 10 m, anchors 12 m apart,
/// 1 t on 20 mm steel rope, N = 20 per leg) against the elastic catenary
/// of one leg: apex depth, the tension at each leg's top (leg 0: its first
/// element joint; leg 1, grafted reversed: its end spring) and at the
/// element joint next to the apex (arc length L_e above it).
#[test]
fn two_leg_sling_statics_match_the_elastic_catenary_of_a_leg() {
    let s = steel20();
    let w = s.linear_density * G;
    let (m, n) = (1000.0, 20);
    let anchors = [DVec3::new(-6.0, 0.0, 0.0), DVec3::new(6.0, 0.0, 0.0)];
    let mut cable = sling(&anchors, DVec3::new(0.0, -8.0, 0.0), m, n, s, 0.0);
    cable.solve_static(1, 1e-10, 2000).unwrap();
    let v0 = m * G / 2.0;
    let (depth, h) = irvine_leg(10.0, w, s.ea, 6.0, v0);
    let body = cable.model.layout.end_body.unwrap();
    let y = cable.model.body_state(&body).0.y;
    let err_depth = (-y - depth) / depth;
    eprintln!("depth {} (Irvine {depth}) {err_depth:e}", -y);
    assert!(err_depth.abs() < 1e-6, "apex depth {} vs {depth}", -y);
    let le = 10.0 / n as f64;
    let (t_top, t_low) = (h.hypot(v0 + w * 10.0), h.hypot(v0 + w * le));
    assert_eq!(cable.ropes(), 2);
    for (part, anchor) in anchors.iter().enumerate() {
        let rope = cable.rope(part).unwrap();
        let (top, low) = (rope.tension_at(0.0), rope.tension_at(rope.length()));
        let (e_top, e_low) = ((top - t_top) / t_top, (low - t_low) / t_low);
        eprintln!("leg {part}: top {top} ({t_top}) {e_top:e}, next to the apex {low} ({t_low}) {e_low:e}");
        assert!(e_top.abs() < 1e-5 && e_low.abs() < 1e-5, "leg {part}: tensions {top}, {low} vs {t_top}, {t_low}");
        // Node 0 of every leg is its top anchor (the user's start), node N the apex.
        let nodes = rope.nodes();
        let apex = cable.model.body_state(&body).0;
        // (Leg 1's top is an end spring 1000 times stiffer than an element.)
        assert!(nodes[0].distance(*anchor) < 1e-6 && nodes[n].distance(apex) < 1e-12, "leg {part} runs from its anchor to the apex");
    }
    assert!(cable.rope(2).is_none());
}

/// A four-leg sling (anchors on a 12 m square, legs 10 m, 1 t, N = 10)
/// released from the unstretched legs, damped (τ = 0.05 s), settles at the
/// apex depth of the elastic catenary at 1/60 s with the defaults. Newton
/// needs many iterations here (two or more loops closed through the
/// payload, see docs/verification.md).
#[test]
fn four_leg_sling_settles_at_the_catenary_depth() {
    let s = steel20();
    let w = s.linear_density * G;
    let anchors = [DVec3::new(-6.0, 0.0, -6.0), DVec3::new(6.0, 0.0, -6.0), DVec3::new(6.0, 0.0, 6.0), DVec3::new(-6.0, 0.0, 6.0)];
    let span = 72f64.sqrt();
    let mut cable = sling(&anchors, DVec3::new(0.0, -(100.0 - span * span).sqrt(), 0.0), 1000.0, 10, s, 0.05);
    let body = cable.model.layout.end_body.unwrap();
    while cable.time() < 3.0 {
        cable.step(1.0 / 60.0).unwrap();
    }
    let (depth, _) = irvine_leg(10.0, w, s.ea, span, 1000.0 * G / 4.0);
    let (p, _, v, _) = cable.model.body_state(&body);
    let err = (-p.y - depth) / depth;
    eprintln!(
        "four legs: depth {} (Irvine {depth}) {err:e}, |v| {}, {} Newton its/step",
        -p.y,
        v.length(),
        cable.total_stats.newton_iterations as f64 / cable.steps as f64
    );
    // (The damped bounce is not over at 3 s: |v| ≈ 0.01 m/s.)
    assert!(err.abs() < 1e-4 && p.x.abs() < 1e-5 && p.z.abs() < 1e-5, "apex {p} vs depth {depth}");
}

/// The two-leg sling swings out of its plane about the line through the
/// anchors: ω² = (g/d)(M + m_r/2)/(M + m_r/3) for straight legs of total
/// mass m_r (d: the apex depth below that line), at the frame step with
/// the defaults. Also: the tension stays at its static value to first order.
#[test]
fn two_leg_sling_swings_about_the_anchor_line_at_the_frame_step() {
    let s = steel20();
    let anchors = [DVec3::new(-6.0, 0.0, 0.0), DVec3::new(6.0, 0.0, 0.0)];
    let m = 1000.0;
    let apex = DVec3::new(0.0, -8.0, 0.0);
    let mut cable = sling(&anchors, apex, m, 10, s, 0.0);
    cable.solve_static(1, 1e-10, 2000).unwrap();
    let body = cable.model.layout.end_body.unwrap();
    let d = -cable.model.body_state(&body).0.y;
    // Kick the payload sideways: 0.1 m/s (about 0.65° of swing).
    let lv = LinkVelocity { link: body.link, point: body.origin, linear: DVec3::new(0.0, 0.0, 0.1), angular: DVec3::ZERO };
    cable.set_link_velocities(&[lv]).unwrap();
    let m_r = 2.0 * 10.0 * s.linear_density;
    let omega = (G / d * (m + m_r / 2.0) / (m + m_r / 3.0)).sqrt();
    let period = 2.0 * std::f64::consts::PI / omega;
    let h = 1.0 / 60.0;
    let (mut last_z, mut crossings) = (0.0f64, Vec::new());
    let t0 = cable.rope(0).unwrap().tension_at(0.0);
    let mut worst_t: f64 = 0.0;
    while cable.time() < 4.2 * period {
        cable.step(h).unwrap();
        let z = cable.model.body_state(&body).0.z;
        if last_z > 0.0 && z <= 0.0 {
            // Linear interpolation of the downward zero crossing.
            crossings.push(cable.time() - h * z / (z - last_z));
        }
        last_z = z;
        worst_t = worst_t.max((cable.rope(1).unwrap().tension_at(0.0) - t0).abs() / t0);
    }
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let err = (measured - period) / period;
    eprintln!(
        "period {measured} (closed form {period}) {err:e}; tension drift {worst_t:e}; {} Newton its/step",
        cable.total_stats.newton_iterations as f64 / cable.steps as f64
    );
    assert!(err.abs() < 1e-3, "sling swing period {measured} vs {period}");
    assert!(worst_t < 1e-3, "tension changed by {worst_t:e} of its static value");
}

/// Two bodies in series (a hook block and the payload on a rope below it):
/// the lower rope is grafted onto the hook block with the payload as its
/// end body ([`RopeModel::graft`] with [`RopeEnd::Body`]), one chain, one
/// implicit solve. Weightless light ropes (`tension_only(false)`, 0.01 kg/m
/// against 10 kg bodies): along the line the two bodies and two ropes are
/// the two-mass, two-spring system `M ẍ + K x = 0`, `K = [[k₁ + k₂, −k₂],
/// [−k₂, k₂]]`, `k = EA/L`. Started in each mode shape (every element of a
/// rope stretched alike), each moves at its own frequency,
/// `ω² = eig(M⁻¹K)`, and stays in its shape.
#[test]
fn two_bodies_in_series_oscillate_at_the_two_mass_two_spring_frequencies() {
    let sec = RopeSection { linear_density: 0.01, ea: 1e5, ei: 1e-3, ei2: 1e-3, gj: 1e-3, min_breaking_load: 0.0 };
    let (m1, m2, l1, l2, n) = (10.0, 20.0, 2.0, 1.0, 10);
    let (k1, k2) = (sec.ea / l1, sec.ea / l2);
    let hook = DVec3::new(l1, 0.0, 0.0);
    let payload = DVec3::new(l1 + l2, 0.0, 0.0);
    let rope = |len: f64, a: DVec3, b: DVec3| RopeBuilder::new(len, n, sec, 0.01).tension_only(false).gravity(DVec3::ZERO).path(vec![a, b]);
    let mut model = rope(l1, DVec3::ZERO, hook)
        .start(RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, DVec3::ZERO))))
        .end(RopeEnd::Body { body: LumpedBody::sphere(m1, 0.1, hook), anchor: DVec3::ZERO, clamp: false })
        .build()
        .unwrap();
    let at = model.layout.end_body.unwrap();
    let lower = rope(l2, hook, payload)
        .start(RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, hook))))
        .end(RopeEnd::Body { body: LumpedBody::sphere(m2, 0.1, payload), anchor: DVec3::ZERO, clamp: false })
        .build()
        .unwrap();
    let part = model.graft(lower, &at, false).unwrap();
    let below = model.parts[part - 1].layout.end_body.expect("the limb keeps its end body");
    // (k₁ + k₂ − ω² m₁)(k₂ − ω² m₂) = k₂²
    let (a, b, c) = (m1 * m2, -(m1 * k2 + m2 * (k1 + k2)), k1 * k2);
    let disc = (b * b - 4.0 * a * c).sqrt();
    for (mode, omega2) in [(-b - disc) / (2.0 * a), (-b + disc) / (2.0 * a)].into_iter().enumerate() {
        // Mode shape: x₂/x₁ = k₂/(k₂ − ω² m₂).
        let (x1, x2) = (1e-4, 1e-4 * k2 / (k2 - omega2 * m2));
        let mut cable = Cable::new(model.clone(), Scheme::default()).unwrap();
        let (upper, lower) = (cable.model.layout, cable.model.parts[part - 1].layout);
        for i in 0..n {
            cable.state.q[upper.dof(i, 3)] += x1 / n as f64;
            cable.state.q[lower.dof(i, 3)] += (x2 - x1) / n as f64;
        }
        cable.state.recompute_acceleration(&mut cable.model.chain).unwrap();
        cable.refresh();
        let x = |c: &Cable| (c.model.body_state(&at).0.x - l1, c.model.body_state(&below).0.x - l1 - l2);
        let start = x(&cable);
        let period = 2.0 * std::f64::consts::PI / omega2.sqrt();
        let h = period / 400.0;
        let (mut last, mut crossings, mut off_shape) = (start.0, Vec::new(), 0.0f64);
        while cable.time() < 5.2 * period {
            cable.step(h).unwrap();
            let (a1, a2) = x(&cable);
            if last > 0.0 && a1 <= 0.0 {
                crossings.push(cable.time() - h * a1 / (a1 - last));
            }
            last = a1;
            // Distance from the mode shape, as a fraction of the amplitude.
            off_shape = off_shape.max((a2 - a1 * x2 / x1).abs() / x2.abs().max(x1));
        }
        let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        let err = measured / period - 1.0;
        eprintln!(
            "mode {mode}: start ({:.3e}, {:.3e}) m, period {measured:.6e} s against {period:.6e} s ({err:+.2e}), off its shape by {off_shape:.2e}",
            start.0, start.1
        );
        assert!((start.0 - x1).abs() < 1e-6 * x1 && (start.1 - x2).abs() < 1e-6 * x1, "started at {start:?}");
        assert!(err.abs() < 1e-3, "mode {mode}: period {measured} against {period}");
        assert!(off_shape < 2e-2, "mode {mode} left its shape by {off_shape}");
    }
}
