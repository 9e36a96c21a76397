//! Static equilibria of ropes against closed forms (verification-cases §1a,
//! §1b, §2a/2b and the hanging rope with a payload).

use bevy_rapier_cable::cable::*;
use glam::{DMat3, DVec3};

fn section(mu: f64, ea: f64, ei: f64, gj: f64) -> RopeSection {
    RopeSection { linear_density: mu, ea, ei, ei2: ei, gj, min_breaking_load: 0.0 }
}

fn fixed_at(p: DVec3) -> BaseMotion {
    BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, p))
}

/// Hanging rope with a payload: top tension = total weight (exact), and
/// elongation = m g L/EA + μ g L²/(2 EA) (continuum) — the discrete chain
/// adds exactly μ g L L_e/(2 EA) (each joint carries its whole element).
#[test]
fn hanging_rope_with_payload_elongation_and_top_tension() {
    let (l, n, mu, ea, m) = (20.0, 100, 1.6, 2e7, 1000.0);
    let g = 9.81;
    let body = LumpedBody::sphere(m, 0.3, DVec3::new(0.0, -l - 0.3, 0.0));
    let mut model = RopeBuilder::new(l, n, section(mu, ea, 50.0, 35.0), 0.02)
        .start(RopeStart::Pinned(fixed_at(DVec3::ZERO)))
        .end(RopeEnd::Body { body, anchor: DVec3::new(0.0, 0.3, 0.0), clamp: false })
        .build()
        .unwrap();
    let mut q = model.q0.clone();
    let iters = model.chain.solve_static(0.0, &mut q, 1e-12, 100).unwrap();
    let zero = vec![0.0; q.len()];
    let top = model.tension(0, &q, &zero);
    let exact_top = (m + mu * l) * g;
    let nodes = model.nodes();
    let stretched: f64 = nodes.windows(2).map(|w| w[0].distance(w[1])).sum();
    let elong = stretched - l;
    let exact = m * g * l / ea + mu * g * l * l / (2.0 * ea);
    let discrete = exact + mu * g * l * (l / n as f64) / (2.0 * ea);
    println!("iterations {iters}; top tension {top} (exact {exact_top}); elongation {elong} (continuum {exact}, discrete {discrete})");
    assert!((top - exact_top).abs() / exact_top < 1e-9);
    assert!((elong - discrete).abs() / discrete < 1e-7, "elongation {elong} vs discrete {discrete}");
    assert!((elong - exact).abs() / exact < 2e-4, "elongation {elong} vs continuum {exact}");
}

/// A clamped cantilever along +x with `n` elements, EI = 1, L = 1.
fn cantilever(n: usize) -> RopeModel {
    RopeBuilder::new(1.0, n, section(1e-3, 1e7, 1.0, 1.0), 0.01)
        .shear_stiffness(1e7)
        .path(vec![DVec3::ZERO, DVec3::X])
        .start(RopeStart::Clamped(fixed_at(DVec3::ZERO)))
        .gravity(DVec3::ZERO)
        .build()
        .unwrap()
}

/// Loads the tip with a dead force and/or moment in `steps` increments and
/// returns the tip position and the tip tangent.
fn load_tip(model: &mut RopeModel, force: DVec3, moment: DVec3, steps: usize) -> (DVec3, DVec3) {
    let tip = model.layout.element_link(model.layout.elements - 1);
    let le = model.layout.element_length;
    model.chain.loads_mut().push(LinkLoad { link: tip, force: DVec3::ZERO, local_point: DVec3::new(le, 0.0, 0.0), moment: DVec3::ZERO });
    let mut q = model.q0.clone();
    for k in 1..=steps {
        let f = k as f64 / steps as f64;
        let ld = model.chain.loads_mut().last_mut().unwrap();
        ld.force = force * f;
        ld.moment = moment * f;
        model.chain.solve_static(0.0, &mut q, 1e-13, 200).unwrap();
    }
    let nodes = model.nodes();
    let tangent = model.chain.link_rotation(tip).unwrap().x_axis;
    (nodes[nodes.len() - 1], tangent)
}

/// verification-cases §1a: Mattiasson's large-deflection cantilever.
#[test]
fn cantilever_tip_load_mattiasson() {
    let table = [(1.0, 0.05643, 0.30172, 0.46135), (5.0, 0.38763, 0.71379, 1.21537), (10.0, 0.55500, 0.81061, 1.43029)];
    for n in [20, 40] {
        for &(alpha, u_ref, w_ref, th_ref) in &table {
            let mut m = cantilever(n);
            let (tip, t) = load_tip(&mut m, DVec3::new(0.0, -alpha, 0.0), DVec3::ZERO, 10);
            let (u, w, th) = (1.0 - tip.x, -tip.y, (-t.y).atan2(t.x));
            let (eu, ew, et) = ((u - u_ref) / u_ref, (w - w_ref) / w_ref, (th - th_ref) / th_ref);
            println!("N={n} α={alpha}: u/L {u:.5} ({eu:+.2e}), w/L {w:.5} ({ew:+.2e}), θ {th:.5} ({et:+.2e}), z {:.1e}", tip.z);
            let tol = if n == 20 { 2e-3 } else { 6e-4 };
            assert!(ew.abs() < tol && eu.abs() < 3.0 * tol && et.abs() < tol, "N={n} α={alpha}");
            assert!(tip.z.abs() < 1e-9);
        }
    }
}

/// verification-cases §1b: a tip moment rolls the beam into a circle; in 3D
/// (moment about y), up to a full circle, independent of the load steps.
#[test]
fn cantilever_end_moment_rolls_into_circle() {
    let pi = std::f64::consts::PI;
    for phi in [0.5 * pi, pi, 2.0 * pi] {
        let mut tips = Vec::new();
        for steps in [10, 20, 40] {
            let mut m = cantilever(20);
            // Moment about −y bends the beam toward +z: x = sin φ/φ, z = (1 − cos φ)/φ.
            let (tip, _) = load_tip(&mut m, DVec3::ZERO, DVec3::new(0.0, -phi, 0.0), steps);
            tips.push(tip);
        }
        let exact = DVec3::new(phi.sin() / phi, 0.0, (1.0 - phi.cos()) / phi);
        let err = tips[0].distance(exact);
        let spread = tips[0].distance(tips[1]).max(tips[0].distance(tips[2]));
        println!("φ = {phi:.4}: tip {:?} exact {:?} |err| {err:.2e}, load-step spread {spread:.1e}", tips[0], exact);
        assert!(err < 1e-3, "tip error {err}");
        assert!(spread < 1e-9, "path dependence {spread}");
    }
}

/// verification-cases §2b: elastic catenary between level supports,
/// l = 100 m, L0 = 102 m, w = 10 N/m.
#[test]
fn elastic_catenary_level_supports() {
    let g = 9.81;
    let rows = [
        (102.0, 1e9, 1447.630, 1534.839, 8.72098),
        (102.0, 1e6, 1396.061, 1486.300, 9.03686),
        // L0 < span: only an extensible rope can span it (taut, small sag).
        (99.9, 1e7, 12619.389, 12629.270, 0.98942),
    ];
    for (l0, ea, h_ref, t_ref, sag_ref) in rows {
        let n = 100;
        let end = DVec3::new(100.0, 0.0, 0.0);
        // Initial guess: a parabola of the rope's length, or the straight
        // (pre-strained) chord when the rope is shorter than the span.
        let path = if l0 > 100.0 { parabola_of_length(100.0, l0) } else { vec![DVec3::ZERO, end] };
        let mut m = RopeBuilder::new(l0, n, section(10.0 / g, ea, 1e-3, 1e-3), 0.02)
            .path(path)
            .start(RopeStart::Pinned(fixed_at(DVec3::ZERO)))
            .end(RopeEnd::Pinned(BaseMotion::point(end)))
            .gravity(DVec3::new(0.0, -g, 0.0))
            .build()
            .unwrap();
        let mut q = m.q0.clone();
        m.chain.solve_static(0.0, &mut q, 1e-9, 300).unwrap();
        let zero = vec![0.0; q.len()];
        let nodes = m.nodes();
        let t_end = m.tension(0, &q, &zero);
        let t_mid = m.tension(n / 2, &q, &zero);
        let sag = -nodes[n / 2].y;
        let (eh, et, es) = ((t_mid - h_ref) / h_ref, (t_end - t_ref) / t_ref, (sag - sag_ref) / sag_ref);
        println!("L0={l0} EA={ea:e}: H {t_mid:.3} ({eh:+.2e}), T_end {t_end:.3} ({et:+.2e}), sag {sag:.5} ({es:+.2e}), tip gap {:.1e}", nodes[n].distance(end));
        assert!(eh.abs() < 1e-3 && et.abs() < 1e-3 && es.abs() < 1e-3);
    }
}

/// A sagging parabola between (0,0,0) and (span,0,0) whose polyline length
/// is `length` (the initial guess a user would draw).
fn parabola_of_length(span: f64, length: f64) -> Vec<DVec3> {
    let pts = |d: f64| -> Vec<DVec3> {
        (0..=400)
            .map(|k| {
                let x = span * k as f64 / 400.0;
                DVec3::new(x, -4.0 * d * x * (span - x) / (span * span), 0.0)
            })
            .collect()
    };
    let len = |p: &[DVec3]| p.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>();
    let (mut lo, mut hi) = (0.0, span);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if len(&pts(mid)) < length {
            lo = mid
        } else {
            hi = mid
        }
    }
    pts(0.5 * (lo + hi))
}

/// The implicit spring that pins a rope's end (`end_stiffness_factor` f
/// times an element's `EA/L_e`) is in series with the last element, whose
/// axial spring is stiffened to `f/(f − 1)·EA/L_e`: the rope keeps its
/// axial compliance exactly. A 10 m steel rope (40 elements) pinned 10.01 m
/// apart, no gravity, carries `T = EA δ / L` in every element (closed form
/// of a stretched bar) from its first state and after a second of steps,
/// and its end node sits short of the pin by the anchor's stretch
/// `T / (f EA/L_e)`. Before the compensation the anchor added `1/(f N)` of
/// the rope's compliance: at f = 1000 the tension was 2.5e-5 low, at f = 2
/// 1.2 % low.
#[test]
fn an_end_anchor_in_series_with_the_last_element_keeps_the_ropes_compliance() {
    let s = preset("steel_wire_rope_6x36_iwrc", 0.016).unwrap();
    let (l, span, n) = (10.0, 10.01, 40);
    let t_exact = s.ea * (span - l) / l;
    for f in [2.0, 10.0, 1000.0] {
        let pin = DVec3::new(span, 0.0, 0.0);
        let model = RopeBuilder::new(l, n, s, 0.016)
            .path(vec![DVec3::ZERO, pin])
            .end(RopeEnd::Pinned(fixed_at(pin)))
            .end_stiffness_factor(f)
            .gravity(DVec3::ZERO)
            .damping(0.01)
            .build()
            .unwrap();
        let mut cable = Cable::new(model, bevy_rapier_cable::integrate::Scheme::default()).unwrap();
        for step in [0, 60] {
            for _ in 0..step {
                cable.step(1.0 / 60.0).unwrap();
            }
            let worst = (0..n).map(|i| (cable.element_forces(i).unwrap().tension - t_exact).abs() / t_exact).fold(0.0f64, f64::max);
            let gap = pin.x - cable.nodes()[n].x;
            let gap_exact = t_exact / (f * s.ea / (l / n as f64));
            eprintln!(
                "f = {f}, after {step} steps: tensions within {worst:.1e} of EA·δ/L = {t_exact:.2} N; end node {gap:.4e} m short of the pin ({gap_exact:.4e})"
            );
            assert!(worst < 1e-9, "f = {f}: tension off by {worst:e} of EA·δ/L");
            assert!((gap - gap_exact).abs() < 1e-9 * gap_exact.max(1e-6) + 1e-13, "f = {f}: end node {gap:e} m short of the pin, expected {gap_exact:e}");
        }
    }
}
