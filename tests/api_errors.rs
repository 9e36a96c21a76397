//! Bad input through the Rust API gets a typed error naming what is wrong;
//! nothing panics (the scenario-file errors are in `scenario_errors.rs`).

use bevy_rapier_cable::cable::*;
use bevy_rapier_cable::integrate::Scheme;
use glam::{DMat3, DVec3};

fn section() -> RopeSection {
    RopeSection { linear_density: 1.6, ea: 2e7, ei: 50.0, ei2: 50.0, gj: 35.0, min_breaking_load: 0.0 }
}

fn pinned() -> RopeStart {
    RopeStart::Pinned(BaseMotion::Fixed(BaseState::fixed(DMat3::IDENTITY, DVec3::ZERO)))
}

fn name_of(e: RopeError) -> String {
    match e {
        RopeError::InvalidParameter { name, .. } => name.to_string(),
        other => other.to_string(),
    }
}

#[test]
fn rope_builder_rejects_bad_parameters_by_name() {
    let base = || RopeBuilder::new(20.0, 10, section(), 0.02).start(pinned());
    let cases: Vec<(RopeBuilder, &str)> = vec![
        (RopeBuilder::new(0.0, 10, section(), 0.02).start(pinned()), "length"),
        (RopeBuilder::new(-1.0, 10, section(), 0.02).start(pinned()), "length"),
        (RopeBuilder::new(20.0, 0, section(), 0.02).start(pinned()), "segments"),
        // A huge size is refused before anything is allocated (2³¹ elements
        // asked for 51 GB and aborted).
        (RopeBuilder::new(20.0, bevy_rapier_cable::cable::MAX_SEGMENTS + 1, section(), 0.02).start(pinned()), "segments"),
        (RopeBuilder::new(20.0, 1 << 31, section(), 0.02).start(pinned()), "segments"),
        (RopeBuilder::new(20.0, 10, RopeSection { ea: f64::NAN, ..section() }, 0.02).start(pinned()), "ea"),
        (RopeBuilder::new(20.0, 10, RopeSection { ei: -1.0, ..section() }, 0.02).start(pinned()), "ei"),
        (RopeBuilder::new(20.0, 10, section(), f64::INFINITY).start(pinned()), "diameter"),
        (base().damping(-0.1), "damping"),
        (base().shear_stiffness(0.0), "shear_stiffness"),
        (base().gravity(DVec3::new(0.0, f64::NAN, 0.0)), "gravity"),
        (base().end_stiffness_factor(f64::NAN), "end_stiffness_factor"),
        (base().end_stiffness_factor(0.0), "end_stiffness_factor"),
        (base().end(RopeEnd::Body { body: LumpedBody::sphere(-5.0, 0.3, DVec3::new(0.0, -20.3, 0.0)), anchor: DVec3::Y * 0.3, clamp: false }), "end body"),
        (base().end(RopeEnd::Body { body: LumpedBody::sphere(f64::NAN, 0.3, DVec3::new(0.0, -20.3, 0.0)), anchor: DVec3::Y * 0.3, clamp: false }), "end body"),
    ];
    for (builder, expected) in cases {
        let err = builder.build().expect_err(expected);
        println!("{err}");
        assert_eq!(name_of(err), expected);
    }
}

#[test]
fn rope_builder_rejects_bad_paths() {
    for (path, what) in [
        (vec![DVec3::ZERO], "at least 2 points"),
        (vec![DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 0.0)], "non-finite"),
        (vec![DVec3::ZERO, DVec3::ZERO], "zero length"),
        (vec![DVec3::new(5.0, 0.0, 0.0), DVec3::new(5.0, -20.0, 0.0)], "start anchor"),
    ] {
        let err = RopeBuilder::new(20.0, 10, section(), 0.02).start(pinned()).path(path).build().unwrap_err();
        println!("{err}");
        assert!(matches!(err, RopeError::InvalidPath(_)) && err.to_string().contains(what), "{err}");
    }
}

#[test]
fn set_link_velocities_rejects_bad_targets() {
    let body = LumpedBody::sphere(1000.0, 0.3, DVec3::new(0.0, -20.3, 0.0));
    let model = RopeBuilder::new(20.0, 10, section(), 0.02).start(pinned()).end(RopeEnd::Body { body, anchor: DVec3::Y * 0.3, clamp: false }).build().unwrap();
    let mut c = Cable::new(model, Scheme::default()).unwrap();
    let n = c.state.q.len();
    let ok = LinkVelocity { link: n - 1, point: DVec3::ZERO, linear: DVec3::X, angular: DVec3::ZERO };
    for (bad, what) in [
        (LinkVelocity { link: n, ..ok }, "links"),
        (LinkVelocity { linear: DVec3::new(f64::NAN, 0.0, 0.0), ..ok }, "non-finite"),
        (LinkVelocity { point: DVec3::splat(f64::INFINITY), ..ok }, "non-finite"),
    ] {
        let err = c.set_link_velocities(&[bad]).unwrap_err();
        println!("{err}");
        assert!(matches!(err, CableError::Velocity { .. }) && err.to_string().contains(what), "{err}");
    }
    // A pinned end cannot move: a velocity at the start's first link point
    // that would move the pin is refused, and the state is left as it was.
    let before = c.state.v.clone();
    let err = c.set_link_velocities(&[LinkVelocity { link: 0, point: DVec3::ZERO, linear: DVec3::X, angular: DVec3::ZERO }]).unwrap_err();
    println!("{err}");
    assert!(err.to_string().contains("cannot make"), "{err}");
    assert_eq!(c.state.v, before);
}

/// `Cable::set_gravity` refuses a vector that is not finite, by name, and
/// keeps the gravity it had; a finite one is taken.
#[test]
fn set_gravity_rejects_a_vector_that_is_not_finite() {
    let model = RopeBuilder::new(20.0, 10, section(), 0.02).start(pinned()).build().unwrap();
    let mut c = Cable::new(model, Scheme::default()).unwrap();
    let g = c.gravity();
    for bad in [DVec3::new(f64::NAN, -9.81, 0.0), DVec3::new(0.0, f64::NEG_INFINITY, 0.0)] {
        let err = c.set_gravity(bad).unwrap_err();
        println!("{err}");
        assert!(matches!(err, CableError::Gravity { .. }) && err.to_string().contains("gravity") && err.to_string().contains("not finite"), "{err}");
        assert_eq!(c.gravity(), g);
    }
    c.set_gravity(DVec3::new(0.0, -1.62, 0.0)).unwrap();
    assert_eq!(c.gravity(), DVec3::new(0.0, -1.62, 0.0));
}
