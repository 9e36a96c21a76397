//! External point and distributed loads on a rope (the API later issues use
//! for contact, wind and water), checked by global equilibrium.

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::Scheme;
use glam::{DMat3, DVec3};

fn hanging(m: f64) -> Cable {
    let sec = RopeSection { linear_density: 1.6, ea: 2e7, ei: 50.0, ei2: 50.0, gj: 35.0, min_breaking_load: 0.0 };
    let body = LumpedBody::sphere(m, 0.3, DVec3::new(0.0, -20.3, 0.0));
    let model = RopeBuilder::new(20.0, 40, sec, 0.02)
        .start(RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, DVec3::ZERO))))
        .end(RopeEnd::Body { body, anchor: DVec3::new(0.0, 0.3, 0.0), clamp: false })
        .build()
        .unwrap();
    Cable::new(model, Scheme::default()).unwrap()
}

fn settle(c: &mut Cable) {
    let mut q = c.state.q.clone();
    c.model.chain.solve_static(0.0, &mut q, 1e-10, 200).unwrap();
    c.state.q = q;
    c.state.v.iter_mut().for_each(|v| *v = 0.0);
    c.refresh();
}

/// A uniform horizontal load q (N/m) on a hanging rope with a payload: the
/// top reaction is (q L, (m + μL) g) whatever the deflected shape.
#[test]
fn uniform_side_load_top_tension_by_equilibrium() {
    let (m, mu, l, g, q) = (1000.0, 1.6, 20.0, 9.81, 150.0);
    let mut c = hanging(m);
    c.add_distributed_load(|_, _, _| DVec3::new(q, 0.0, 0.0));
    settle(&mut c);
    // The pin reaction is the joint's axial force and shear force together.
    let f = c.element_forces(0).expect("element");
    let top = (f.tension.powi(2) + f.shear[0].powi(2) + f.shear[1].powi(2)).sqrt();
    let exact = ((q * l).powi(2) + ((m + mu * l) * g).powi(2)).sqrt();
    let tip = c.nodes()[40];
    println!("top reaction {top:.3} N vs {exact:.3} N (axial {:.3} N);", f.tension);
    println!(" tip moved to x = {:.3} m", tip.x);
    assert!((top - exact).abs() / exact < 1e-9);
    assert!(tip.x > 1.0, "the load must deflect the rope");
}

/// An upward distributed load μg cancels the rope's weight: the top tension
/// is the payload weight alone; a point load at the tip adds to it.
#[test]
fn distributed_load_cancels_weight_and_point_load_adds() {
    let (m, mu, g) = (1000.0, 1.6, 9.81);
    let mut c = hanging(m);
    c.add_distributed_load(|_, _, _| DVec3::new(0.0, mu * g, 0.0));
    settle(&mut c);
    let t1 = c.tension_at(0.0);
    assert!((t1 - m * g).abs() / (m * g) < 1e-9, "{t1}");
    c.add_point_load(10.0, DVec3::new(0.0, -500.0, 0.0));
    settle(&mut c);
    let (t_top, t_bottom) = (c.tension_at(0.0), c.tension_at(19.0));
    println!("top {t_top:.4} N, below the point load {t_bottom:.4} N");
    assert!((t_top - (m * g + 500.0)).abs() < 1e-6 * t_top);
    assert!((t_bottom - m * g).abs() < 1e-6 * t_bottom);
    c.clear_loads();
    settle(&mut c);
    assert!((c.tension_at(0.0) - (m + mu * 20.0) * g).abs() < 1e-6 * m * g);
}

/// The layout of the per-link scratch is rebuilt whenever the loaded links
/// change: loads on links {0, 40} then on {1, 9} (which a hashed layout
/// key confused) give the residual of a chain built with {1, 9} from the
/// start, bit for bit.
#[test]
fn moving_loads_to_other_links_rebuilds_the_layout() {
    let c = hanging(1000.0);
    let load = |link: usize| LinkLoad { link, force: DVec3::new(120.0, -40.0, 7.0), local_point: DVec3::new(0.01, 0.0, 0.0), moment: DVec3::ZERO };
    let (q, v, a) = (c.state.q.clone(), c.state.v.clone(), c.state.a.clone());
    let n = q.len();
    let mut moved = c.model.chain.clone();
    let mut r = vec![0.0; n];
    *moved.loads_mut() = vec![load(0), load(40)];
    moved.residual_into(0.0, &q, &v, &a, &mut r).unwrap();
    *moved.loads_mut() = vec![load(1), load(9)];
    let mut r_moved = vec![0.0; n];
    moved.residual_into(0.0, &q, &v, &a, &mut r_moved).unwrap();
    let mut fresh = c.model.chain.clone();
    *fresh.loads_mut() = vec![load(1), load(9)];
    let mut r_fresh = vec![0.0; n];
    fresh.residual_into(0.0, &q, &v, &a, &mut r_fresh).unwrap();
    assert_eq!(r_moved, r_fresh);
    assert_ne!(r, r_fresh);
}
