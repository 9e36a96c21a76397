//! Issue 10, item 8: a chain the next issues can change. Its description is
//! reached through accessors, its size changes only through the topology
//! API (`Chain::insert_joints` / `remove_joints`, `State::insert` /
//! `remove`, `Integrator::reset_history`), and a bad index is an error,
//! never a panic.
//!
//! The reference for the topology API is the rope built directly: a rope of
//! N elements grown by one element in the middle must be the rope of N + 1
//! elements, bit for bit, in its description, its residual and 1 s of
//! motion; shrunk again it must be the N-element rope.

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::{IntegrateError, Integrator, Scheme, SecondOrderSystem, State, SystemError};
use glam::{DMat3, DVec3};
use std::sync::Arc;

const LE: f64 = 0.5;
const H: f64 = 1.0 / 60.0;

/// `n` elements of 0.5 m of steel rope (1.6 kg/m, EA 2e7 N), pinned at the
/// origin and laid straight at 17° from the vertical, a 50 kg ball on a
/// ball joint at the end: it swings when released.
fn rope(n: usize) -> RopeModel {
    let section = RopeSection { linear_density: 1.6, ea: 2e7, ei: 50.0, ei2: 50.0, gj: 35.0, min_breaking_load: 0.0 };
    let length = LE * n as f64;
    let dir = DVec3::new(0.3, -1.0, 0.0).normalize();
    RopeBuilder::new(length, n, section, 0.02)
        .path(vec![DVec3::ZERO, dir * length])
        .start(RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, DVec3::ZERO))))
        .end(RopeEnd::Body { body: LumpedBody::sphere(50.0, 0.2, dir * (length + 0.2)), anchor: -dir * 0.2, clamp: false })
        .build()
        .expect("rope")
}

fn residual(chain: &mut Chain, q: &[f64], v: &[f64]) -> Vec<f64> {
    let mut r = vec![0.0; q.len()];
    chain.residual_into(0.0, q, v, &vec![0.0; q.len()], &mut r).expect("residual");
    r
}

/// Element 1 of the 11-element rope (sub-joints 6..12) inserted into the
/// 10-element rope before its element 1, with its rotation spring and its
/// coordinates: the 11-element rope, bit for bit.
fn grown() -> (Chain, Vec<f64>) {
    let (small, big) = (rope(10), rope(11));
    let mut chain = small.chain.clone();
    chain.insert_joints(6, big.chain.joints()[6..12].to_vec()).expect("insert");
    let spring = big.chain.rotation_springs().iter().find(|r| r.first == 6).copied().expect("element 1's rotation spring");
    let k = chain.rotation_springs().partition_point(|r| r.first < 6);
    chain.rotation_springs_mut().insert(k, spring);
    let mut q = small.q0.clone();
    let mut state = State { t: 0.0, q: q.clone(), v: vec![0.0; q.len()], a: vec![0.0; q.len()], a_hat: vec![0.0; q.len()] };
    state.insert(6, &big.q0[6..12], &[0.0; 6]).expect("state insert");
    q.clone_from(&state.q);
    (chain, q)
}

#[test]
fn a_rope_grown_by_one_element_is_the_longer_rope_bit_for_bit() {
    let big = rope(11);
    let (mut chain, q) = grown();
    assert_eq!(chain.joints(), big.chain.joints());
    assert_eq!(chain.joint_forces().len(), big.chain.len());
    // The coordinates agree to the builder's round-off in laying each rope
    // from its path (a few 1e-16 m of axial stretch); both runs start from
    // the longer rope's own.
    assert!(q.iter().zip(&big.q0).all(|(a, b)| (a - b).abs() < 1e-15));
    let q = big.q0.clone();
    let mut big_chain = big.chain.clone();
    let v = vec![0.0; q.len()];
    assert_eq!(residual(&mut chain, &q, &v), residual(&mut big_chain, &q, &v));

    // One second of swing from release: the same bits, step after step (no
    // stale layout, branch or integrator history in the grown chain).
    let mut a = State::new(&mut chain, 0.0, q.clone(), v.clone()).expect("state");
    let mut b = State::new(&mut big_chain, 0.0, q, v).expect("state");
    let (mut ia, mut ib) = (Integrator::new(Scheme::default()), Integrator::new(Scheme::default()));
    for _ in 0..60 {
        ia.step(&mut chain, &mut a, H).expect("grown chain step");
        ib.step(&mut big_chain, &mut b, H).expect("built chain step");
        assert_eq!((&a.q, &a.v), (&b.q, &b.v), "t = {}", a.t);
    }
    let moved = chain.link_point(chain.len() - 1, DVec3::ZERO).unwrap().distance(big.chain.link_point(big.chain.len() - 1, DVec3::ZERO).unwrap());
    assert!(moved > 0.1, "the payload moved {moved} m in 1 s: the comparison would be empty");
}

#[test]
fn a_grown_rope_shrunk_again_is_the_shorter_rope_and_a_running_state_follows() {
    let small = rope(10);
    let (mut chain, q) = grown();
    // The rotation spring on sub-joints 6..=8 must go first.
    let err = chain.remove_joints(6..12).expect_err("a rotation spring is in the way");
    assert!(err.to_string().contains("rotation spring 0 uses sub-joints 6..=8"), "{err}");
    assert_eq!(chain.len(), rope(11).chain.len(), "a refused removal changed the chain");
    chain.rotation_springs_mut().retain(|r| r.first != 6);
    let removed = chain.remove_joints(6..12).expect("remove");
    assert_eq!(removed.len(), 6);
    assert_eq!(chain.joints(), small.chain.joints());
    assert_eq!(chain.rotation_springs(), small.chain.rotation_springs());

    // A running state shrinks with it: remove the coordinates, recompute
    // the acceleration, reset the integrator, and step on.
    let mut grown_chain = grown().0;
    let mut state = State::new(&mut grown_chain, 0.0, q.clone(), vec![0.0; q.len()]).expect("state");
    let mut integrator = Integrator::new(Scheme::default());
    for _ in 0..10 {
        integrator.step(&mut grown_chain, &mut state, H).expect("step");
    }
    state.remove(6..12).expect("state remove");
    assert!(matches!(state.remove(0..999), Err(IntegrateError::IndexOutOfRange { .. })));
    state.recompute_acceleration(&mut chain).expect("acceleration");
    integrator.reset_history();
    for _ in 0..30 {
        integrator.step(&mut chain, &mut state, H).expect("step after shrinking");
    }
    assert!(state.is_finite());
}

#[test]
fn everything_that_names_a_sub_joint_moves_with_it() {
    let mut chain = rope(10).chain.clone();
    let n = chain.len();
    let tip = n - 1;
    chain.loads_mut().push(LinkLoad { link: tip, force: DVec3::X, local_point: DVec3::ZERO, moment: DVec3::ZERO });
    chain.loads_mut().push(LinkLoad { link: 5, force: DVec3::Y, local_point: DVec3::ZERO, moment: DVec3::ZERO });
    let spring = Arc::new(PointSpring { target: DVec3::ZERO, stiffness: 10.0, damping: 0.0 });
    chain.forces_mut().push(AttachedForce { link: 23, local_point: DVec3::ZERO, element: spring });
    chain.set_joint_force(30, 7.0).expect("drive");
    let springs: Vec<usize> = chain.rotation_springs().iter().map(|r| r.first).collect();
    let extra = chain.joints()[6..12].to_vec();
    chain.insert_joints(12, extra).expect("insert");
    assert_eq!(chain.len(), n + 6);
    assert_eq!(chain.loads().iter().map(|l| l.link).collect::<Vec<_>>(), vec![tip + 6, 5]);
    assert_eq!(chain.forces()[0].link, 29);
    assert_eq!((chain.joint_force(36), chain.joint_force(30)), (Some(7.0), Some(0.0)));
    let moved: Vec<usize> = chain.rotation_springs().iter().map(|r| r.first).collect();
    let expect: Vec<usize> = springs.iter().map(|&f| if f >= 12 { f + 6 } else { f }).collect();
    assert_eq!(moved, expect);
    // Refusals name what is in the way, and change nothing.
    let before = chain.joints().to_vec();
    let err = chain.insert_joints(7, vec![chain.joints()[0].clone()]).expect_err("inside a rotation spring");
    assert!(err.to_string().contains("inside rotation spring 0 (sub-joints 6..=8)"), "{err}");
    let err = chain.remove_joints(27..31).expect_err("a force element is there");
    assert!(err.to_string().contains("force element 0 acts on link 29"), "{err}");
    let err = chain.insert_joints(999, vec![]).expect_err("past the end");
    assert!(matches!(err, ChainError::Index { index: 999, .. }), "{err}");
    assert_eq!(chain.joints(), &before[..]);
    // The grown chain evaluates (every per-sub-joint array grew with it).
    let q = vec![0.0; chain.len()];
    residual(&mut chain, &q, &q);
}

#[test]
fn a_bad_index_is_an_error_that_names_it_not_a_panic() {
    let model = rope(4);
    let mut chain = model.chain.clone();
    let n = chain.len();
    assert!(matches!(chain.set_joint_force(n, 1.0), Err(ChainError::Index { index, len, .. }) if index == n && len == n));
    assert_eq!(chain.joint_force(n), None);
    assert!(chain.joint(n).is_none() && chain.joint_mut(n).is_none());
    assert!(chain.link_point(n, DVec3::ZERO).is_none() && chain.link_rotation(n).is_none() && chain.joint_point(n).is_none());
    assert!(chain.link_point_velocity(n, DVec3::ZERO).is_none() && chain.link_velocity(n).is_none() && chain.joint_point_velocity(n).is_none());
    assert!(model.element_forces(3, &model.q0, &vec![0.0; n]).is_some() && model.element_forces(4, &model.q0, &vec![0.0; n]).is_none());

    let q = model.q0.clone();
    let zeros = vec![0.0; n];
    let mut r = vec![0.0; n];
    chain.loads_mut().push(LinkLoad { link: 999, force: DVec3::X, local_point: DVec3::ZERO, moment: DVec3::ZERO });
    match chain.residual_into(0.0, &q, &zeros, &zeros, &mut r) {
        Err(SystemError::Model(m)) => assert!(m.contains(&format!("load 0 refers to sub-joint 999, but the chain has {n} sub-joints")), "{m}"),
        other => panic!("expected a model error, got {other:?}"),
    }
    chain.loads_mut().clear();
    chain.residual_into(0.0, &q, &zeros, &zeros, &mut r).expect("valid again");

    // Through a cable: the step fails with the reason and changes nothing.
    let mut cable = Cable::new(model, Scheme::default()).expect("cable");
    let spring = Arc::new(PointSpring { target: DVec3::ZERO, stiffness: 1.0, damping: 0.0 });
    cable.model.chain.forces_mut().push(AttachedForce { link: 40, local_point: DVec3::ZERO, element: spring });
    assert!(cable.element_forces(4).is_none() && cable.rope(0).expect("main rope").element_forces(4).is_none());
    assert!(cable.element_forces(3).is_some());
    let before = cable.state.clone();
    let err = cable.step(H).expect_err("a force element past the chain's end");
    assert!(err.to_string().contains("force element 0 refers to sub-joint 40"), "{err}");
    assert_eq!((cable.state.t, &cable.state.q), (before.t, &before.q));
    assert_eq!(cable.model.chain.dof(), n);
}

/// Base motion as data: a sampled base and a sampled anchor target are
/// refreshed by their source id, print as data, and a cloned chain keeps
/// its own (before, a follower's closure shared one locked sample between
/// the clone and the original).
#[test]
fn sampled_motion_is_data_that_a_clone_does_not_share() {
    let sample = |source: usize, x: f64| SampledMotion {
        source,
        t0: 0.0,
        rotation: DMat3::IDENTITY,
        position: DVec3::new(x, 0.0, 0.0),
        velocity: DVec3::new(1.0, 0.0, 0.0),
        angular_velocity: DVec3::ZERO,
        acceleration: DVec3::new(0.0, 2.0, 0.0),
    };
    let section = RopeSection { linear_density: 1.6, ea: 2e7, ei: 50.0, ei2: 50.0, gj: 35.0, min_breaking_load: 0.0 };
    let model = RopeBuilder::new(2.0, 4, section, 0.02)
        .start(RopeStart::Pinned(BaseMotion::Sampled(sample(7, 0.0))))
        .path(vec![DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0)])
        .end(RopeEnd::Pinned(BaseMotion::Sampled(sample(8, 2.0))))
        .build()
        .expect("rope");
    let mut original = model.chain.clone();
    let mut copy = model.chain.clone();
    // Extrapolated with constant acceleration: x + v t, ½ a t².
    let s = original.base.at(0.5);
    assert_eq!((s.position, s.velocity), (DVec3::new(0.5, 0.25, 0.0), DVec3::new(1.0, 1.0, 0.0)));
    assert_eq!(copy.set_sampled(sample(7, 3.0)), 1);
    assert_eq!(copy.set_sampled(sample(8, 5.0)), 1);
    assert_eq!(copy.set_sampled(sample(9, 5.0)), 0);
    assert_eq!(copy.base.at(0.0).position.x, 3.0);
    assert_eq!(copy.anchors()[0].target.at(0.0).position.x, 5.0);
    assert_eq!(original.base.at(0.0).position.x, 0.0, "the clone's refresh moved the original's base");
    assert_eq!(original.anchors()[0].target.at(0.0).position.x, 2.0, "the clone's refresh moved the original's anchor");
    assert!(format!("{:?}", original.base).starts_with("Sampled(SampledMotion { source: 7"));
    assert_eq!(original.set_sampled(sample(8, 2.0)), 1);
}
