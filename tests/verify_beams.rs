//! Beam behaviour of the rope model against closed forms and published
//! references: the 45° bend under an out-of-plane tip load (verification
//! cases §1c, bending–torsion coupling), its objectivity under a rigid
//! rotation of the whole problem, the cable with a mid-span point load
//! (§11c), the O(1/N²) convergence of the Mattiasson cantilever (§1a), and
//! the linearized natural frequencies of §4 (cantilever and free–free,
//! bending, axial, torsion, rigid-body modes).

use bevy_rapier_cable::cable::*;
use glam::{DMat3, DVec3};
use std::f64::consts::PI;

fn section(mu: f64, ea: f64, ei: f64, gj: f64) -> RopeSection {
    RopeSection { linear_density: mu, ea, ei, ei2: ei, gj, min_breaking_load: 0.0 }
}

fn fixed(rot: DMat3, p: DVec3) -> BaseMotion {
    BaseMotion::Fixed(BaseState::fixed(rot, p))
}

// ---------------------------------------------------------------------------
// §1c 45° bend (Bathe–Bolourchi)
// ---------------------------------------------------------------------------

/// The 45° bend: R = 100, arc in the x–z plane from the origin tangent to +z
/// curving to +x, EI = GJ = 8.333e5, EA = 1e7, kGA = 4.1667e6, clamped at
/// the origin, stress-free in its curved shape
/// (`RopeBuilder::stress_free_shape`), dead tip force P·(+y) applied in `increments`
/// equal steps. The whole problem (base, path, load) is rotated by `rot`.
/// Returns the tip displacement (rotated back) at every increment.
fn bend45(n: usize, gj_factor: f64, increments: usize, p_max: f64, rot: DMat3) -> Vec<(f64, DVec3)> {
    let (mut m, initial) = bend45_model(n, gj_factor, rot);
    let mut q = m.q0.clone();
    let mut out = Vec::new();
    for k in 1..=increments {
        let p = p_max * k as f64 / increments as f64;
        m.chain.loads_mut()[0].force = rot * DVec3::new(0.0, p, 0.0);
        m.chain.solve_static(0.0, &mut q, 1e-10, 400).unwrap();
        out.push((p, rot.transpose() * (m.nodes()[n] - initial)));
    }
    out
}

/// The 45° bend model of [`bend45`] with a zero tip load (`chain.loads()[0]`)
/// and its initial tip position.
fn bend45_model(n: usize, gj_factor: f64, rot: DMat3) -> (RopeModel, DVec3) {
    let r = 100.0;
    let length = r * PI / 4.0;
    let ei = 1e7 / 12.0;
    let gj = 5e6 / 6.0 * gj_factor;
    let kga = 5.0 / 6.0 * 5e6;
    // Nodes on the arc at equal angles: equal chords, so the resampling
    // keeps them exactly.
    let path: Vec<DVec3> = (0..=n)
        .map(|k| {
            let phi = PI / 4.0 * k as f64 / n as f64;
            rot * DVec3::new(r - r * phi.cos(), 0.0, r * phi.sin())
        })
        .collect();
    // Statics do not depend on the mass; μ is small (solve_static once
    // stalled on this 78.5 m beam with μ = 1 kg/m; fixed, see
    // `solve_static_stalls_on_soft_long_cantilever`).
    let mut m = RopeBuilder::new(length, n, section(1e-3, 1e7, ei, gj), 1.0)
        .shear_stiffness(kga)
        .path(path)
        .start(RopeStart::Clamped(fixed(rot, DVec3::ZERO)))
        .end(RopeEnd::Free)
        .gravity(DVec3::ZERO)
        .stress_free_shape(true)
        .build()
        .unwrap();
    let initial = m.nodes()[n];
    let expected = rot * DVec3::new(r - r * (PI / 4.0).cos(), 0.0, r * (PI / 4.0).sin());
    assert!(initial.distance(expected) < 1e-9, "initial tip {initial:?}");
    let tip = m.layout.element_link(n - 1);
    let le = m.layout.element_length;
    m.chain.loads_mut().push(LinkLoad { link: tip, force: DVec3::ZERO, local_point: DVec3::new(le, 0.0, 0.0), moment: DVec3::ZERO });
    (m, initial)
}

/// Internal forces by statics: on the 45° bend at P = 600 (tip rotated by
/// about 0.5 rad out of plane, bending and torsion mixed at every joint),
/// each element joint must carry the tip force `F` and its moment about
/// the joint, `(x_tip − x_i) × F`, whatever the deflection. The reported
/// tension/shear are `F` in the element frame, the reported bending and
/// torsion the moment in it. (The earlier report, each Euler angle's
/// linear spring `k (q − q₀)`, was off by up to 1 050 N·m, 3.5 % of the
/// largest moment here: it ignores the coupling of the three angles.)
#[test]
fn bend45_internal_forces_match_statics() {
    let n = 16;
    let rot = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let (mut m, _) = bend45_model(n, 1.0, rot);
    let mut q = m.q0.clone();
    for k in 1..=10 {
        m.chain.loads_mut()[0].force = rot * DVec3::new(0.0, 60.0 * k as f64, 0.0);
        m.chain.solve_static(0.0, &mut q, 1e-10, 400).unwrap();
    }
    let force = m.chain.loads()[0].force;
    let v = vec![0.0; q.len()];
    let nodes = m.nodes();
    let tip = nodes[n];
    let (mut worst_f, mut worst_m, mut largest_m): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for (i, &node) in nodes[..n].iter().enumerate() {
        let e = m.element_forces(i, &q, &v).expect("element");
        let r = m.chain.link_rotation(m.layout.element_link(i)).unwrap();
        let f_local = r.transpose() * force;
        let m_local = r.transpose() * (tip - node).cross(force);
        let got_f = DVec3::new(e.tension, e.shear[0], e.shear[1]);
        let got_m = DVec3::new(e.torsion, e.bending[1], e.bending[0]);
        worst_f = worst_f.max(got_f.distance(f_local));
        worst_m = worst_m.max(got_m.distance(m_local));
        largest_m = largest_m.max(m_local.length());
        if i == 0 || i == n / 2 {
            println!("joint {i}: moment {got_m:.4?} N·m, statics {m_local:.4?} N·m; force {got_f:.5?} N, statics {f_local:.5?} N");
        }
    }
    println!("largest force error {worst_f:.2e} N (|F| = 600 N), largest moment error {worst_m:.2e} N·m (largest moment {largest_m:.1} N·m)");
    assert!(worst_f < 1e-6 * force.length(), "force error {worst_f}");
    assert!(worst_m < 1e-6 * largest_m, "moment error {worst_m}");
}

fn at(run: &[(f64, DVec3)], p: f64) -> DVec3 {
    run.iter().find(|(pk, _)| (pk - p).abs() < 1e-9).unwrap().1
}

const BEND45_TABLE: [(f64, DVec3); 2] = [(300.0, DVec3::new(-7.045, 40.192, -11.932)), (600.0, DVec3::new(-13.605, 53.475, -23.561))];

/// §1c: tip displacement at P = 300 and 600 vs the Kirchhoff rod "with EA,
/// kGA" column. Measured: the error falls as O(1/N) (not O(1/N²)), so the
/// §1c bar (0.5 % of |Δ| with 8–16 elements) is met only from N ≈ 64
/// (see `bend45_meets_section_1c_tolerance_with_16_elements`, ignored, and
/// the report: the Euler-angle strain measure of the joints). Asserted here:
/// first-order convergence, the Richardson extrapolation 2Δ(128) − Δ(64)
/// within 0.1 % of the Kirchhoff solution (the model converges to the right
/// answer), 8/10/20 load increments agree, and the GJ × 100 guard (torsion effectively rigid) is far off.
#[test]
fn bend45_out_of_plane_tip_load() {
    let ns = [8, 16, 32, 64, 128];
    let runs: Vec<Vec<(f64, DVec3)>> = ns.iter().map(|&n| bend45(n, 1.0, 10, 600.0, DMat3::IDENTITY)).collect();
    for (p, reference) in BEND45_TABLE {
        let mut errs = Vec::new();
        for (k, &n) in ns.iter().enumerate() {
            let d = at(&runs[k], p);
            let err = d.distance(reference) / reference.length();
            println!(
                "N={n} P={p}: Δ = ({:.3}, {:.3}, {:.3}) vs ({:.3}, {:.3}, {:.3}): |error| {:.3} % of |Δ|",
                d.x,
                d.y,
                d.z,
                reference.x,
                reference.y,
                reference.z,
                100.0 * err
            );
            errs.push(err);
        }
        for k in 1..ns.len() - 1 {
            let ratio = errs[k] / errs[k + 1];
            println!("  P={p}: error ratio N={} / N={}: {ratio:.2}", ns[k], ns[k + 1]);
            // Second order until the error reaches the table's own rounding.
            if errs[k + 1] > 2e-4 {
                assert!((3.4..4.6).contains(&ratio), "P={p}: convergence ratio {ratio}");
            }
        }
        let extrapolated = (4.0 * at(&runs[4], p) - at(&runs[3], p)) / 3.0;
        let e_extra = extrapolated.distance(reference) / reference.length();
        println!(
            "  P={p}: Richardson (4Δ(128) − Δ(64))/3 = ({:.3}, {:.3}, {:.3}): |error| {:.3} % of |Δ|",
            extrapolated.x,
            extrapolated.y,
            extrapolated.z,
            100.0 * e_extra
        );
        assert!(e_extra < 1e-3, "P={p}: extrapolated error {e_extra}");
        assert!(errs[1] < 5e-3 && errs[2] < 5e-3, "P={p}: N = 16, 32 outside 0.5 %");
    }
    // Path independence: 8, 10, 20 load increments (N = 16).
    let finals: Vec<DVec3> = [8, 10, 20].iter().map(|&inc| bend45(16, 1.0, inc, 600.0, DMat3::IDENTITY).last().unwrap().1).collect();
    let spread = finals.iter().map(|d| d.distance(finals[0])).fold(0.0, f64::max);
    println!("N=16, P=600 with 8/10/20 increments: spread {spread:.2e} (|Δ| {:.3})", finals[0].length());
    assert!(spread < 1e-6 * finals[0].length(), "path dependence {spread}");
    // Guard: without torsional compliance the bend is much stiffer.
    for n in [16, 128] {
        let stiff = bend45(n, 100.0, 10, 600.0, DMat3::IDENTITY);
        for (p, reference) in BEND45_TABLE {
            let d = at(&stiff, p);
            let err = d.distance(reference) / reference.length();
            println!("guard GJ×100, N={n} P={p}: Δ = ({:.3}, {:.3}, {:.3}): |error| {:.2} % of |Δ|", d.x, d.y, d.z, 100.0 * err);
            assert!(err > 0.02, "the torsion guard does not separate: {err}");
        }
    }
}

/// The §1c bar as stated (0.5 % of |Δ| with 16 and 32 elements). (Failed
/// at 1.12 % / 0.62 % with one spring per Euler angle; passes with the
/// objective rotation-vector law.)
#[test]
fn bend45_meets_section_1c_tolerance_with_16_elements() {
    for n in [16, 32] {
        let run = bend45(n, 1.0, 10, 600.0, DMat3::IDENTITY);
        for (p, reference) in BEND45_TABLE {
            let err = at(&run, p).distance(reference) / reference.length();
            println!("N={n} P={p}: |error| {:.3} % of |Δ|", 100.0 * err);
            assert!(err < 5e-3, "N={n} P={p}: {err}");
        }
    }
}

/// Objectivity: rotating the whole problem (base, path, load) about the
/// world y axis — the builder's frame helper axis, so every element frame
/// turns with it and the coordinates are unchanged — gives the same tip
/// displacement (rotated back) to solver tolerance: the kinematics, loads
/// and solver are objective. (An arbitrary rotation, which also changes the
/// element frames' twist reference: `bend45_is_objective_under_arbitrary_rotation`.)
#[test]
fn bend45_objectivity_under_rigid_rotation() {
    let plain = bend45(16, 1.0, 10, 600.0, DMat3::IDENTITY);
    let about_y = bend45(16, 1.0, 10, 600.0, DMat3::from_rotation_y(1.0));
    let worst = plain.iter().zip(&about_y).map(|(a, b)| a.1.distance(b.1)).fold(0.0, f64::max);
    println!("rotation 1 rad about y (frames rotate with the problem): largest tip-displacement difference over the load path {worst:.2e}");
    assert!(worst < 1e-7 * plain.last().unwrap().1.length(), "not objective: {worst}");
}

/// Strict objectivity under an arbitrary rotation at N = 16 (difference
/// below 1e-6 |Δ|): the strain measure does not depend on the element
/// frames' twist reference. (Failed at 1.1 % with one spring per Euler
/// angle; exact with the rotation-vector law.)
#[test]
fn bend45_is_objective_under_arbitrary_rotation() {
    let plain = bend45(16, 1.0, 10, 600.0, DMat3::IDENTITY);
    let rot = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let turned = bend45(16, 1.0, 10, 600.0, rot);
    let worst = plain.iter().zip(&turned).map(|(a, b)| a.1.distance(b.1)).fold(0.0, f64::max);
    println!("largest tip-displacement difference {worst:.3e}");
    assert!(worst < 1e-6 * plain.last().unwrap().1.length(), "not objective: {worst}");
}

/// Convergence order of a straight cantilever (L = 1, EI = EI2 = 1,
/// GJ = 0.7) under dead tip loads: planar bending (F_y = −3) converges as
/// O(1/N²) (successive-difference ratio 4), but as soon as two rotation
/// components meet at the joints — a tip torque M_x = 0.5 with F_y = −3, or
/// biaxial bending F_y = −2 with M_y = 1.5 — the ratio stays 4 with the
/// objective rotation-vector law (it dropped to 2, O(1/N), with one spring
/// per Euler angle). No closed form is needed: |x(N) − x(2N)| /
/// |x(2N) − x(4N)| gives the order.
#[test]
fn straight_cantilever_convergence_order_2d_vs_3d() {
    let cant = |n: usize, force: DVec3, moment: DVec3| -> DVec3 {
        let mut m = RopeBuilder::new(1.0, n, RopeSection { linear_density: 1e-3, ea: 1e7, ei: 1.0, ei2: 1.0, gj: 0.7, min_breaking_load: 0.0 }, 0.01)
            .shear_stiffness(1e7)
            .path(vec![DVec3::ZERO, DVec3::X])
            .start(RopeStart::Clamped(fixed(DMat3::IDENTITY, DVec3::ZERO)))
            .gravity(DVec3::ZERO)
            .build()
            .unwrap();
        let tip = m.layout.element_link(n - 1);
        let le = m.layout.element_length;
        m.chain.loads_mut().push(LinkLoad { link: tip, force: DVec3::ZERO, local_point: DVec3::new(le, 0.0, 0.0), moment: DVec3::ZERO });
        let mut q = m.q0.clone();
        for k in 1..=20 {
            let f = k as f64 / 20.0;
            m.chain.loads_mut()[0].force = force * f;
            m.chain.loads_mut()[0].moment = moment * f;
            m.chain.solve_static(0.0, &mut q, 1e-13, 300).unwrap();
        }
        m.nodes()[n]
    };
    let cases = [
        ("planar F_y = −3", DVec3::new(0.0, -3.0, 0.0), DVec3::ZERO, 4.0),
        ("F_y = −3 + torque M_x = 0.5", DVec3::new(0.0, -3.0, 0.0), DVec3::new(0.5, 0.0, 0.0), 4.0),
        ("biaxial F_y = −2, M_y = 1.5", DVec3::new(0.0, -2.0, 0.0), DVec3::new(0.0, 1.5, 0.0), 4.0),
    ];
    for (name, force, moment, expected) in cases {
        let tips: Vec<DVec3> = [10, 20, 40, 80].iter().map(|&n| cant(n, force, moment)).collect();
        let d: Vec<f64> = tips.windows(2).map(|w| w[0].distance(w[1])).collect();
        let ratios: Vec<f64> = d.windows(2).map(|w| w[0] / w[1]).collect();
        println!(
            "{name}: tip N=80 ({:.5}, {:.5}, {:.5}); |x(N) − x(2N)| for N = 10, 20, 40: {:.2e}, {:.2e}, {:.2e}; ratios {:.2}, {:.2} (order {})",
            tips[3].x,
            tips[3].y,
            tips[3].z,
            d[0],
            d[1],
            d[2],
            ratios[0],
            ratios[1],
            if expected > 3.0 { 2 } else { 1 }
        );
        assert!((ratios[1] - expected).abs() < 0.15 * expected, "{name}: ratio {}", ratios[1]);
    }
}

// ---------------------------------------------------------------------------
// §11c mid-span point load
// ---------------------------------------------------------------------------

/// Closed form of the crate's constitutive law (engineering strain on the
/// unstretched length): half-length a, unstretched half-length a₀,
/// T = EA(s/a₀ − 1), P = 2Td/s, s = √(a² + d²). Solved for d by bisection.
fn midspan_closed_form(a: f64, a0: f64, ea: f64, p: f64) -> (f64, f64) {
    let f = |d: f64| {
        let s = (a * a + d * d).sqrt();
        2.0 * ea * (s / a0 - 1.0) * d / s - p
    };
    let (mut lo, mut hi) = (0.0, a);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    let d = 0.5 * (lo + hi);
    (d, ea * ((a * a + d * d).sqrt() / a0 - 1.0))
}

/// §11c: L = 10 m between pins 10 m apart, EA = 1e6 N, point load P at
/// mid-span (a node), pretension T₀ from a shortened rope. Table rows and
/// tolerance 0.5 %; also against the crate's own strain measure (tight).
#[test]
fn cable_midspan_point_load() {
    let (l, ea, n) = (10.0, 1e6, 20);
    let rows = [(0.0, 1000.0, 0.501252, 5012.51), (0.0, 100.0, 0.232204, 1077.80), (1e4, 1000.0, 0.226905, 11029.19)];
    for (t0, p, d_ref, t_ref) in rows {
        let l0 = l / (1.0 + t0 / ea);
        let end = DVec3::new(l, 0.0, 0.0);
        let mut m = RopeBuilder::new(l0, n, section(1.0, ea, 1e-3, 1e-3), 0.01)
            .path(vec![DVec3::ZERO, end])
            .start(RopeStart::Pinned(fixed(DMat3::IDENTITY, DVec3::ZERO)))
            .end(RopeEnd::Pinned(BaseMotion::point(end)))
            .gravity(DVec3::ZERO)
            .build()
            .unwrap();
        let le = m.layout.element_length;
        // Node n/2 is the outboard end of element n/2 − 1.
        m.chain.loads_mut().push(LinkLoad {
            link: m.layout.element_link(n / 2 - 1),
            force: DVec3::ZERO,
            local_point: DVec3::new(le, 0.0, 0.0),
            moment: DVec3::ZERO,
        });
        let mut q = m.q0.clone();
        let steps = 10;
        for k in 1..=steps {
            m.chain.loads_mut()[0].force = DVec3::new(0.0, -p * k as f64 / steps as f64, 0.0);
            if let Err(e) = m.chain.solve_static(0.0, &mut q, 1e-10, 500) {
                panic!("T0={t0} P={p}: {e}");
            }
        }
        let zero = vec![0.0; q.len()];
        let d = -m.nodes()[n / 2].y;
        let t = m.tension(0, &q, &zero);
        let t_mid = m.tension(n / 2, &q, &zero);
        let (d_own, t_own) = midspan_closed_form(0.5 * l, 0.5 * l0, ea, p);
        let (ed, et) = (d / d_ref - 1.0, t / t_ref - 1.0);
        println!(
            "T0={t0} P={p}: d {d:.6} m ({ed:+.2e} vs {d_ref}), T {t:.2} N ({et:+.2e} vs {t_ref}), T at mid-span {t_mid:.2}; own strain measure: d {d_own:.6} ({:+.1e}), T {t_own:.2} ({:+.1e})",
            d / d_own - 1.0,
            t / t_own - 1.0
        );
        assert!(ed.abs() < 5e-3 && et.abs() < 5e-3, "T0={t0} P={p}");
        assert!((d / d_own - 1.0).abs() < 2e-4 && (t / t_own - 1.0).abs() < 2e-4, "T0={t0} P={p}: vs own closed form");
    }
}

// ---------------------------------------------------------------------------
// §1a convergence with N
// ---------------------------------------------------------------------------

/// The elastica θ'' = −α cos θ, θ(0) = 0, θ'(1) = 0 by shooting (RK4, 4000
/// steps, bisection on θ'(0)): returns (u/L, w/L, θ_tip).
fn elastica(alpha: f64) -> (f64, f64, f64) {
    let run = |k0: f64| {
        let steps = 4000;
        let h = 1.0 / steps as f64;
        let f = |y: [f64; 4]| [y[1], -alpha * y[0].cos(), y[0].cos(), y[0].sin()];
        let mut y = [0.0, k0, 0.0, 0.0];
        for _ in 0..steps {
            let add = |a: [f64; 4], b: [f64; 4], s: f64| [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2], a[3] + s * b[3]];
            let k1 = f(y);
            let k2 = f(add(y, k1, 0.5 * h));
            let k3 = f(add(y, k2, 0.5 * h));
            let k4 = f(add(y, k3, h));
            for i in 0..4 {
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        y
    };
    let (mut lo, mut hi) = (0.0, alpha);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if run(mid)[1] < 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    let y = run(0.5 * (lo + hi));
    (1.0 - y[2], y[3], y[0])
}

/// The clamped cantilever of tests/statics.rs (L = 1, EI = 1, EA = GA = 1e7).
fn cantilever(n: usize) -> RopeModel {
    RopeBuilder::new(1.0, n, section(1e-3, 1e7, 1.0, 1.0), 0.01)
        .shear_stiffness(1e7)
        .path(vec![DVec3::ZERO, DVec3::X])
        .start(RopeStart::Clamped(fixed(DMat3::IDENTITY, DVec3::ZERO)))
        .gravity(DVec3::ZERO)
        .build()
        .unwrap()
}

/// §1a: w/L of the Mattiasson cantilever at α = 5 for N = 10, 20, 40, 80:
/// error ratios between doublings ≈ 4 (second order), against a shooting
/// solution of the elastica accurate to ~1e-12.
#[test]
fn mattiasson_convergence_in_n() {
    let alpha = 5.0;
    let (u_ref, w_ref, th_ref) = elastica(alpha);
    println!("elastica α=5 by shooting: u/L {u_ref:.8}, w/L {w_ref:.8}, θ {th_ref:.8} (table 0.38763, 0.71379, 1.21537)");
    assert!((u_ref - 0.38763).abs() < 6e-6 && (w_ref - 0.71379).abs() < 6e-6 && (th_ref - 1.21537).abs() < 6e-6);
    let mut errs = Vec::new();
    for n in [10, 20, 40, 80] {
        let mut m = cantilever(n);
        let tip = m.layout.element_link(n - 1);
        let le = m.layout.element_length;
        m.chain.loads_mut().push(LinkLoad { link: tip, force: DVec3::ZERO, local_point: DVec3::new(le, 0.0, 0.0), moment: DVec3::ZERO });
        let mut q = m.q0.clone();
        for k in 1..=10 {
            m.chain.loads_mut()[0].force = DVec3::new(0.0, -alpha * k as f64 / 10.0, 0.0);
            m.chain.solve_static(0.0, &mut q, 1e-13, 300).unwrap();
        }
        let w = -m.nodes()[n].y;
        let ew = w / w_ref - 1.0;
        println!("N={n}: w/L {w:.7}, error {ew:+.3e}");
        errs.push(ew);
    }
    for k in 0..errs.len() - 1 {
        let ratio = errs[k] / errs[k + 1];
        println!("error ratio N={} / N={}: {ratio:.3}", 10 << k, 20 << k);
        assert!((3.6..4.4).contains(&ratio), "not second order: {ratio}");
    }
}

// ---------------------------------------------------------------------------
// §4 natural frequencies of the linearized model
// ---------------------------------------------------------------------------

/// Joint-space mass matrix at `q` (v = 0): column i is r(q, 0, e_i) −
/// r(q, 0, 0), exact because the residual is linear in the acceleration.
fn mass_matrix(chain: &mut Chain, q: &[f64]) -> Vec<Vec<f64>> {
    let n = q.len();
    let zero = vec![0.0; n];
    let mut r0 = vec![0.0; n];
    chain.residual_into(0.0, q, &zero, &zero, &mut r0).unwrap();
    let mut m = vec![vec![0.0; n]; n];
    let mut a = vec![0.0; n];
    let mut r = vec![0.0; n];
    for i in 0..n {
        a[i] = 1.0;
        chain.residual_into(0.0, q, &zero, &a, &mut r).unwrap();
        a[i] = 0.0;
        for k in 0..n {
            m[k][i] = r[k] - r0[k];
        }
    }
    m
}

/// Eigenvalues of a symmetric matrix by cyclic Jacobi rotations.
fn jacobi_eigenvalues(mut a: Vec<Vec<f64>>) -> Vec<f64> {
    let n = a.len();
    for _ in 0..100 {
        let off: f64 = (0..n).flat_map(|p| (0..n).filter(move |&q| q != p).map(move |q| (p, q))).map(|(p, q)| a[p][q] * a[p][q]).sum();
        let diag: f64 = (0..n).map(|p| a[p][p] * a[p][p]).sum();
        if off <= 1e-32 * diag {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p][q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                let t = if theta == 0.0 { 1.0 } else { theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt()) };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (upper, lower) = a.split_at_mut(q);
                for (row_p, row_q) in upper[p].iter_mut().zip(lower[0].iter_mut()) {
                    let (apk, aqk) = (*row_p, *row_q);
                    *row_p = c * apk - s * aqk;
                    *row_q = s * apk + c * aqk;
                }
            }
        }
    }
    (0..n).map(|i| a[i][i]).collect()
}

/// Natural frequencies (rad/s, ascending) of `K x = ω² M x` with K =
/// diag(k) > 0 and M symmetric positive semi-definite: the eigenvalues
/// μ = 1/ω² of K^{-1/2} M K^{-1/2} (the largest μ, i.e. the lowest modes,
/// are the most accurate). `idx` selects a subset of coordinates.
fn frequencies(m: &[Vec<f64>], k: &[f64], idx: &[usize]) -> Vec<f64> {
    let a: Vec<Vec<f64>> = idx.iter().map(|&i| idx.iter().map(|&j| m[i][j] / (k[i] * k[j]).sqrt()).collect()).collect();
    let mut w: Vec<f64> = jacobi_eigenvalues(a).into_iter().filter(|&mu| mu > 0.0).map(|mu| 1.0 / mu.sqrt()).collect();
    w.sort_by(|a, b| a.partial_cmp(b).unwrap());
    w
}

/// The steel rod of §4 (d = 10 mm, L = 1 m, E = 210 GPa, ν = 0.3,
/// ρ = 7850 kg/m³), clamped at x = 0, free at x = L, `n` elements. Shear
/// made rigid (GA = 1e4·EA) so the Euler–Bernoulli limit applies.
fn steel_rod(n: usize, diameter_for_inertia: f64, start: RopeStart) -> RopeModel {
    let (e, nu, rho, d) = (210e9, 0.3, 7850.0, 0.01);
    let area = PI * d * d / 4.0;
    let i = PI * d.powi(4) / 64.0;
    let g = e / (2.0 * (1.0 + nu));
    let sec = section(rho * area, e * area, e * i, g * 2.0 * i);
    RopeBuilder::new(1.0, n, sec, diameter_for_inertia)
        .tension_only(false) // a rod: K = diag(k) needs the linear axial law
        .shear_stiffness(1e4 * e * area)
        .path(vec![DVec3::ZERO, DVec3::X])
        .start(start)
        .gravity(DVec3::ZERO)
        .build()
        .unwrap()
}

/// §4 cantilever, linearized about the straight stress-free state (no
/// gravity, no load: K = diag(joint stiffnesses) exactly, the geometric
/// stiffness vanishes): bending modes 1–3 against the continuum
/// (βₙL)² √(EI/ρA L⁴) and against the §4 table of rigid-segment chain errors
/// (springs EI/Δ, 2EI/Δ at the clamp, segment mass and inertia — exactly
/// this model); y/z pairs degenerate; axial modes against the exact
/// spring–mass chain; first torsion mode against 801.9 Hz.
#[test]
fn cantilever_natural_frequencies() {
    let beta_l: [f64; 3] = [1.875104, 4.694091, 7.854757];
    // §4 table (percent), with half a unit of its last printed digit.
    let table = [
        (10, [(-0.46, 0.006), (-1.56, 0.006), (-2.6, 0.06)]),
        (20, [(-0.12, 0.006), (-0.40, 0.006), (-0.65, 0.006)]),
        (40, [(-0.03, 0.006), (-0.10, 0.006), (-0.16, 0.006)]),
    ];
    let (ei, rho_a) = steel_ei_rho_a();
    assert!((ei / 103.0835 - 1.0).abs() < 1e-6 && (rho_a / 0.616538 - 1.0).abs() < 1e-6);
    for (n, table_err) in table {
        // Bending: section rotary inertia off (tiny diameter), as in
        // Euler–Bernoulli; the segments keep their own μL_e³/12.
        let mut model = steel_rod(n, 1e-5, RopeStart::Clamped(fixed(DMat3::IDENTITY, DVec3::ZERO)));
        let q = model.q0.clone();
        let dof = q.len();
        let m = mass_matrix(&mut model.chain, &q);
        let asym = (0..dof).flat_map(|i| (0..dof).map(move |j| (i, j))).map(|(i, j)| (m[i][j] - m[j][i]).abs()).fold(0.0, f64::max);
        let k: Vec<f64> = model.chain.joints().iter().map(|j| j.stiffness).collect();
        // K = diag(k): central differences of the residual in q.
        let kmax = k.iter().cloned().fold(0.0, f64::max);
        let zero = vec![0.0; dof];
        let (mut rp, mut rm) = (vec![0.0; dof], vec![0.0; dof]);
        let mut k_dev: f64 = 0.0;
        for i in 0..dof {
            let dq = 1e-7;
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[i] += dq;
            qm[i] -= dq;
            model.chain.residual_into(0.0, &qp, &zero, &zero, &mut rp).unwrap();
            model.chain.residual_into(0.0, &qm, &zero, &zero, &mut rm).unwrap();
            for j in 0..dof {
                let kij = (rp[j] - rm[j]) / (2.0 * dq);
                let expect = if i == j { k[i] } else { 0.0 };
                k_dev = k_dev.max((kij - expect).abs() / kmax);
            }
        }
        assert!(k_dev < 1e-9, "K is not diag(k): {k_dev}");
        let all: Vec<usize> = (0..dof).collect();
        let w = frequencies(&m, &k, &all);
        let mut line = format!("N={n} (|M − Mᵀ| ≤ {asym:.1e}, |K − diag k| ≤ {k_dev:.0e}·k_max):");
        for mode in 0..3 {
            let (a, b) = (w[2 * mode], w[2 * mode + 1]);
            let exact = beta_l[mode].powi(2) * (ei / rho_a).sqrt();
            let err = 100.0 * (a / exact - 1.0);
            let (t_err, t_tol) = table_err[mode];
            line += &format!(" f{} {:.4} Hz ({err:+.3} %, §4 table {t_err:+.2} %, pair split {:.0e})", mode + 1, a / (2.0 * PI), (b / a - 1.0).abs());
            assert!((b / a - 1.0).abs() < 1e-9, "y/z pair not degenerate");
            assert!((err - t_err).abs() < t_tol, "N={n} mode {}: {err} % vs table {t_err} %", mode + 1);
        }
        println!("{line}");
        assert!(asym < 1e-12 * m[0][0].abs().max(1.0));
    }
    // Axial and torsion with the real 10 mm section (the blocks decouple
    // from bending in the straight state).
    let n = 20;
    let mut model = steel_rod(n, 0.01, RopeStart::Clamped(fixed(DMat3::IDENTITY, DVec3::ZERO)));
    let q = model.q0.clone();
    let lay = model.layout;
    let m = mass_matrix(&mut model.chain, &q);
    let k: Vec<f64> = model.chain.joints().iter().map(|j| j.stiffness).collect();
    let axial: Vec<usize> = (0..n).map(|i| lay.dof(i, 3)).collect();
    let torsion: Vec<usize> = (0..n).map(|i| lay.dof(i, 2)).collect();
    let kind = |j: usize| (j - lay.first) % 6;
    let mut coupling: f64 = 0.0;
    for &i in axial.iter().chain(&torsion) {
        for (j, mij) in m[i].iter().enumerate().skip(lay.first) {
            if kind(j) != kind(i) {
                coupling = coupling.max(mij.abs());
            }
        }
    }
    let wa = frequencies(&m, &k, &axial);
    let wt = frequencies(&m, &k, &torsion);
    // Fixed–free chain of N masses μL_e and N springs EA/L_e:
    // ω_j = 2√(k/m)·sin((2j − 1)π / (2(2N + 1))).
    let (ea, mu) = (210e9 * PI * 1e-4 / 4.0, 7850.0 * PI * 1e-4 / 4.0);
    let le = 1.0 / n as f64;
    let chain_axial = |j: usize| 2.0 * (ea / le / (mu * le)).sqrt() * (((2 * j - 1) as f64) * PI / (2.0 * (2 * n + 1) as f64)).sin();
    for j in 1..=3 {
        let err = wa[j - 1] / chain_axial(j) - 1.0;
        println!(
            "axial mode {j}, N={n}: {:.3} Hz vs spring–mass chain {:.3} Hz ({err:+.1e}); continuum {:.3} Hz",
            wa[j - 1] / (2.0 * PI),
            chain_axial(j) / (2.0 * PI),
            (2 * j - 1) as f64 * 1293.05
        );
        assert!(err.abs() < 1e-10);
    }
    // The axial compliance of each element sits at its inboard joint, so in
    // axial motion each element's mass rides on the node outboard of its
    // spring: the fixed–free chain above, whose ω₁ is low by ≈ 1/(2N + 1)
    // (first order in 1/N), unlike bending and torsion (second order).
    let e_axial = wa[0] / (2.0 * PI) / 1293.05 - 1.0;
    let first_order = 2.0 * n as f64 / (2 * n + 1) as f64 - 1.0;
    let e_torsion = wt[0] / (2.0 * PI) / 801.9 - 1.0;
    println!("axial f1 vs continuum 1293.05 Hz: {e_axial:+.3e} (−1/(2N+1) = {first_order:+.3e}); torsion f1 {:.2} Hz vs 801.9 Hz: {e_torsion:+.2e}; largest M coupling of axial/torsion to other DOF types {coupling:.1e}", wt[0] / (2.0 * PI));
    assert!(coupling < 1e-12);
    assert!((e_axial - first_order).abs() < 2e-3, "axial f1 {e_axial}");
    assert!(e_torsion.abs() < 1e-3, "torsion f1 {e_torsion}");
}

/// §4 free–free: the rope cannot start free, so the test builds one: three
/// world-axis prismatic sub-joints (massless, no stiffness) are put in front
/// of a pinned rope whose first joint's bending and torsion springs are
/// removed — a floating beam. With K = diag(k) having exactly six zero
/// entries (the floating coordinates), the six rigid-body modes are exact
/// zeros, and the flexible modes follow from the Schur complement
/// M_ee − M_eb M_bb⁻¹ M_be. Also checked: any finite rigid motion of the
/// floating coordinates leaves the residual (internal forces) at zero.
#[test]
fn free_free_natural_frequencies_and_rigid_modes() {
    let beta_l: [f64; 3] = [4.730041, 7.853205, 10.995608];
    let (ei, rho_a) = steel_ei_rho_a();
    let mut prev: Option<[f64; 3]> = None;
    for n in [10, 20, 40] {
        let model = steel_rod(n, 1e-5, RopeStart::Pinned(fixed(DMat3::IDENTITY, DVec3::ZERO)));
        let lay = model.layout;
        let src = &model.chain;
        let free = |axis: DVec3| SubJoint::free(JointKind::Prismatic, axis);
        let mut joints = vec![free(DVec3::X), free(DVec3::Y), free(DVec3::Z)];
        joints.extend(src.joints().iter().cloned());
        let first = 3 + lay.first;
        joints[first + 2].stiffness = 0.0; // torsion of the first joint
        let mut chain = Chain::new(joints, src.base.clone(), DVec3::ZERO, src.origin);
        let mut q = vec![0.0; 3];
        q.extend(model.q0.iter());
        let dof = q.len();
        let k: Vec<f64> = chain.joints().iter().map(|j| j.stiffness).collect();
        let base: Vec<usize> = vec![0, 1, 2, first, first + 1, first + 2];
        assert!(base.iter().all(|&b| k[b] == 0.0));
        assert_eq!(k.iter().filter(|&&x| x == 0.0).count(), 6, "exactly six floating coordinates");
        // Rigid motions leave the residual (elastic and inertial loads) zero.
        let mut qr = q.clone();
        for (b, v) in base.iter().zip([0.3, -0.7, 1.1, 0.4, -0.9, 2.0]) {
            qr[*b] += v;
        }
        let zero = vec![0.0; dof];
        let mut r = vec![0.0; dof];
        let mut r0 = vec![0.0; dof];
        chain.residual_into(0.0, &q, &zero, &zero, &mut r0).unwrap();
        chain.residual_into(0.0, &qr, &zero, &zero, &mut r).unwrap();
        let rigid_res = r.iter().zip(&r0).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(rigid_res < 1e-12, "rigid motion loads the beam: {rigid_res}");
        // Schur complement on the floating coordinates.
        let m = mass_matrix(&mut chain, &q);
        let elastic: Vec<usize> = (0..dof).filter(|i| !base.contains(i)).collect();
        let mbb: Vec<Vec<f64>> = base.iter().map(|&i| base.iter().map(|&j| m[i][j]).collect()).collect();
        let inv = invert(&mbb);
        let mut schur = m.clone();
        for &i in &elastic {
            for &j in &elastic {
                let mut s = 0.0;
                for (a, &bi) in base.iter().enumerate() {
                    for (b, &bj) in base.iter().enumerate() {
                        s += m[i][bi] * inv[a][b] * m[bj][j];
                    }
                }
                schur[i][j] = m[i][j] - s;
            }
        }
        let w = frequencies(&schur, &k, &elastic);
        let mut line = format!("free–free N={n}: 6 rigid modes exactly 0 (residual change after a finite rigid motion {rigid_res:.0e});");
        let mut errs = [0.0; 3];
        for mode in 0..3 {
            let (a, b) = (w[2 * mode], w[2 * mode + 1]);
            let exact = beta_l[mode].powi(2) * (ei / rho_a).sqrt();
            errs[mode] = a / exact - 1.0;
            line += &format!(" f{} {:.4} Hz ({:+.2e}, pair split {:.0e})", mode + 1, a / (2.0 * PI), errs[mode], (b / a - 1.0).abs());
            assert!((b / a - 1.0).abs() < 1e-9);
        }
        println!("{line}");
        // Much faster than the cantilever (−0.46 %, −1.56 %, −2.6 % at
        // N = 10): ≤ 0.2 % at N = 10 and shrinking by ≥ 8× per doubling
        // until the 7-digit βL table is reached.
        for (mode, err) in errs.iter().enumerate() {
            assert!(err.abs() < 2e-3 / ((n / 10) * (n / 10) * (n / 10)) as f64 + 1e-6, "free–free mode {} error {}", mode + 1, err);
        }
        if let Some(p) = prev {
            println!("  error ratios vs N/2: {:.1}, {:.1}, {:.1}", p[0] / errs[0], p[1] / errs[1], p[2] / errs[2]);
        }
        prev = Some(errs);
    }
}

/// EI (N·m²) and ρA (kg/m) of the §4 steel rod, unrounded.
fn steel_ei_rho_a() -> (f64, f64) {
    let d: f64 = 0.01;
    (210e9 * PI * d.powi(4) / 64.0, 7850.0 * PI * d * d / 4.0)
}

/// Inverse of a small matrix by Gauss–Jordan with partial pivoting.
fn invert(a: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = a.len();
    let mut m: Vec<Vec<f64>> = a
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let mut r = row.clone();
            r.extend((0..n).map(|j| if i == j { 1.0 } else { 0.0 }));
            r
        })
        .collect();
    for c in 0..n {
        let p = (c..n).max_by(|&x, &y| m[x][c].abs().partial_cmp(&m[y][c].abs()).unwrap()).unwrap();
        m.swap(c, p);
        let d = m[c][c];
        assert!(d.abs() > 0.0, "singular");
        for v in m[c].iter_mut() {
            *v /= d;
        }
        for r in 0..n {
            if r != c {
                let f = m[r][c];
                if f != 0.0 {
                    let row_c = m[c].clone();
                    for (x, y) in m[r].iter_mut().zip(&row_c) {
                        *x -= f * y;
                    }
                }
            }
        }
    }
    m.into_iter().map(|r| r[n..].to_vec()).collect()
}

/// Regression test for a former `Chain::solve_static` scale problem (fixed
/// here): a straight clamped cantilever L = 78.54 m, EI = 8.33e5
/// N·m², μ = 1 kg/m, dead tip load 60 N (α = PL²/EI = 0.44, a mild case)
/// does not converge in 300 iterations — the max-norm residual creeps up
/// (4439 → 4846 N·m) while the pseudo-time factor c drops to its 1e-6 s²
/// floor. The same beam with μ ≤ 0.1 kg/m converges in 5–7 iterations to
/// the same (mass-independent) answer. Cause was the pseudo-time control
/// (c cut whenever ‖r‖∞ grew); it now grows c unless a step needs the
/// rotation limit. Regression test.
#[test]
fn solve_static_stalls_on_soft_long_cantilever() {
    let length = 100.0 * PI / 4.0;
    let ei = 1e7 / 12.0;
    let mut m = RopeBuilder::new(length, 16, section(1.0, 1e7, ei, ei), 1.0)
        .shear_stiffness(5.0 / 6.0 * 5e6)
        .path(vec![DVec3::ZERO, DVec3::X * length])
        .start(RopeStart::Clamped(fixed(DMat3::IDENTITY, DVec3::ZERO)))
        .gravity(DVec3::ZERO)
        .build()
        .unwrap();
    let tip = m.layout.element_link(15);
    let le = m.layout.element_length;
    m.chain.loads_mut().push(LinkLoad { link: tip, force: DVec3::new(0.0, 60.0, 0.0), local_point: DVec3::new(le, 0.0, 0.0), moment: DVec3::ZERO });
    let mut q = m.q0.clone();
    let result = m.chain.solve_static(0.0, &mut q, 1e-10, 300);
    println!("{result:?}, tip {:?}", m.nodes()[16]);
    assert!(result.is_ok(), "solve_static: {result:?}");
}
