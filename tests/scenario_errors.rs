//! Scenario files: every class of bad input gives an error with the right
//! line, column and message; a complete file parses with the right values;
//! random corruption never panics.

use bevy_rapier_cable::scenario::{parse, BodyKind, CableEnd, CableSide, Component, Drive, JointKind, Motion, ProbeTarget, Quantity, ScenarioError, Shape};
use glam::{DQuat, DVec3, EulerRot};

/// A small valid file; tests break one line of it. Line numbers:
/// 11 `position`, 13 `[[cable]]`, 15 `length`, 16 `segments`, 19 `ea`, 23 `end`.
const BASE: &str = r#"[simulation]
duration = 1
dt = 0.01

[[body]]
name = "hook"
type = "dynamic"
shape = "ball"
radius = 0.2
mass = 10
position = [0, -5, 0]

[[cable]]
name = "rope"
length = 5
segments = 10
diameter = 0.01
linear_density = 0.5
ea = 1e6
ei = 1
gj = 1
start = { world = [0, 0, 0] }
end = { body = "hook" }
"#;

fn err(src: &str) -> ScenarioError {
    match parse(src, "bad.toml") {
        Ok(_) => panic!("expected an error for:\n{src}"),
        Err(e) => e,
    }
}

/// Assert position and a phrase of the message; print the rendering on failure.
fn check(src: &str, line: usize, col: usize, phrase: &str) -> ScenarioError {
    let e = err(src);
    let shown = e.to_string();
    assert_eq!((e.line, e.col), (line, col), "wrong position:\n{shown}");
    assert!(e.message.contains(phrase), "message lacks {phrase:?}:\n{shown}");
    assert!(shown.contains(&format!("bad.toml:{line}:{col}")), "{shown}");
    e
}

fn replace(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "BASE lacks {from:?}");
    BASE.replacen(from, to, 1)
}

/// A body's `restitution` is a coefficient from 0 to 1: outside, or not a
/// number, it is refused where it stands.
#[test]
fn restitution_out_of_range_is_refused() {
    check(&replace("mass = 10", "mass = 10\nrestitution = 1.5"), 11, 15, "`restitution` must be between 0 and 1, found 1.5");
    check(&replace("mass = 10", "mass = 10\nrestitution = -0.1"), 11, 15, "`restitution` must be between 0 and 1");
    check(&replace("mass = 10", "mass = 10\nrestitution = nan"), 11, 15, "`restitution` must be a finite number");
    let s = parse(&replace("mass = 10", "mass = 10\nrestitution = 0.7"), "ok.toml").unwrap();
    assert_eq!(s.bodies[0].restitution, 0.7);
}

/// `collision_groups` lists group numbers 1 to 32 (an extension); a
/// number outside is refused where it stands, an unknown key by name, and
/// a list left out means every group.
#[test]
fn collision_groups_are_group_numbers_from_1_to_32() {
    check(
        &replace("mass = 10", "mass = 10\ncollision_groups = { memberships = [0] }"),
        11,
        37,
        "`collision_groups.memberships` lists group 0; groups are numbered 1 to 32",
    );
    check(&replace("gj = 1", "gj = 1\ncollision_groups = { filter = [1, 33] }"), 22, 35, "`collision_groups.filter` lists group 33");
    check(&replace("gj = 1", "gj = 1\ncollision_groups = { filters = [1] }"), 22, 22, "unknown field `filters`");
    let s = parse(&replace("mass = 10", "mass = 10\ncollision_groups = { memberships = [1, 32], filter = [2] }"), "ok.toml").unwrap();
    assert_eq!((s.bodies[0].collision_groups.memberships, s.bodies[0].collision_groups.filter), (1 | 1 << 31, 2));
    assert_eq!((s.cables[0].collision_groups.memberships, s.cables[0].collision_groups.filter), (u32::MAX, u32::MAX));
}

#[test]
fn base_is_valid() {
    let s = parse(BASE, "base.toml").unwrap();
    assert_eq!(s.cables[0].path, vec![DVec3::ZERO, DVec3::new(0.0, -5.0, 0.0)]);
}

#[test]
fn negative_or_zero_length() {
    check(&replace("length = 5", "length = -2"), 15, 10, "`length` must be greater than 0 m, found -2");
    check(&replace("length = 5", "length = 0"), 15, 10, "`length` must be greater than 0");
}

#[test]
fn zero_segments() {
    let e = check(&replace("segments = 10", "segments = 0"), 16, 12, "`segments` must be between 1 and 100000, found 0");
    assert!(e.to_string().contains("16 | segments = 0\n   |            ^"), "{e}");
}

#[test]
fn nan_value() {
    check(&replace("ea = 1e6", "ea = nan"), 19, 6, "`ea` must be a finite number, found NaN");
}

#[test]
fn infinite_value() {
    check(&replace("diameter = 0.01", "diameter = inf"), 17, 12, "`diameter` must be a finite number");
    check(&replace("[0, -5, 0]", "[0, -inf, 0]"), 11, 16, "`position` must be a finite number");
}

#[test]
fn unknown_body_name() {
    check(&replace(r#"body = "hook""#, r#"body = "hok""#), 23, 16, "unknown body `hok` (known bodies: `hook`");
}

#[test]
fn path_end_does_not_match_attachment() {
    let src = format!("{BASE}path = [[0, 0, 0], [0, -4, 0]]\n");
    let e = check(&src, 24, 20, "does not coincide with the `end` attachment point");
    assert!(e.message.contains("[0, -4, 0]") && e.message.contains("[0, -5, 0]"), "{e}");
    let src = format!("{BASE}path = [[0, 0.5, 0], [0, -5, 0]]\n");
    let e = check(&src, 24, 9, "the first point of `path` [0, 0.5, 0]");
    assert!(e.message.contains("`start` attachment point [0, 0, 0]"), "{e}");
}

#[test]
fn unknown_integrator_lists_valid_names() {
    let e = check(&replace("dt = 0.01\n", "dt = 0.01\nintegrator = \"rk5\"\n"), 4, 14, "unknown integrator `rk5`");
    for name in ["euler", "rk4", "newmark", "wilson_theta", "hht", "generalized_alpha", "linearly_implicit"] {
        assert!(e.message.contains(&format!("`{name}`")), "{e}");
    }
}

#[test]
fn integrator_parameter_out_of_range() {
    let src = replace("dt = 0.01\n", "dt = 0.01\nintegrator = \"generalized_alpha\"\nrho_inf = 1.5\n");
    check(&src, 5, 11, "`rho_inf` must be between 0 and 1, found 1.5");
    let src = replace("dt = 0.01\n", "dt = 0.01\nintegrator = \"hht\"\nalpha = 0.1\n");
    check(&src, 5, 9, "`alpha` must be between -0.333333 and 0");
    let src = replace("dt = 0.01\n", "dt = 0.01\nintegrator = \"newmark\"\ngamma = 0.4\n");
    check(&src, 5, 9, "`gamma` must be at least 0.5");
    // A parameter of another scheme is not silently ignored.
    let src = replace("dt = 0.01\n", "dt = 0.01\nintegrator = \"newmark\"\ntheta = 1.4\n");
    check(&src, 5, 9, "`theta` is a parameter of the `wilson_theta` integrator");
}

#[test]
fn misspelt_field() {
    check(&replace("length = 5", "lenght = 5"), 15, 1, "unknown field `lenght`");
    check(&replace("[[cable]]", "[[cables]]"), 13, 3, "unknown field `cables`");
    check(&replace("{ world = [0, 0, 0] }", "{ wrold = [0, 0, 0] }"), 22, 11, "unknown field `wrold`");
}

#[test]
fn wrong_type() {
    check(&replace("mass = 10", "mass = \"heavy\""), 10, 8, "invalid type: string \"heavy\", expected f64");
    check(&replace("segments = 10", "segments = 2.5"), 16, 12, "invalid type: floating point");
}

#[test]
fn unit_mismatch() {
    // A quaternion where XYZ Euler degrees are expected.
    let src = replace("position = [0, -5, 0]\n", "position = [0, -5, 0]\nrotation = [0, 0, 0, 1]\n");
    check(&src, 12, 12, "`rotation` must have 3 components [x, y, z] (degrees), found 4");
    // A velocity table point that is not [t, v].
    let joint = "\n[[joint]]\nname = \"j\"\ntype = \"prismatic\"\nbody1 = \"world\"\nbody2 = \"hook\"\naxis = [0, 1, 0]\ndrive = { velocity = [[0, 0], [1, 0.5, 2]], max_force = 100 }\n";
    let src = format!("{BASE}{joint}");
    check(&src, 31, 31, "`velocity` must be a list of points [[t, v], ...] (s, m/s); point 2 has 3 elements");
}

#[test]
fn duplicate_names() {
    let src = format!(
        "{BASE}\n[[cable]]\nname = \"rope\"\nlength = 1\nsegments = 1\ndiameter = 0.01\nmaterial = \"fibre_rope_polyester\"\nstart = {{ world = [1, 0, 0] }}\n"
    );
    check(&src, 26, 8, "duplicate cable name `rope` (first defined at line 14)");
}

#[test]
fn probe_with_two_targets() {
    let src = format!("{BASE}\n[[probe]]\nname = \"p\"\nbody = \"hook\"\ncable = \"rope\"\nquantity = \"position\"\n");
    check(&src, 28, 9, "has several targets (`body` and `cable`)");
    let src = format!("{BASE}\n[[probe]]\nname = \"p\"\nquantity = \"position\"\n");
    check(&src, 25, 1, "needs exactly one target");
}

#[test]
fn probe_quantity_invalid_for_target() {
    let src = format!("{BASE}\n[[probe]]\nname = \"p\"\ncable = \"rope\"\nquantity = \"rotation\"\n");
    let e = check(&src, 28, 12, "quantity `rotation` is not available for a cable probe");
    assert!(e.message.contains("`tension`") && e.message.contains("`contact_force`"), "{e}");
}

#[test]
fn world_is_not_a_body_name() {
    check(&replace("name = \"hook\"", "name = \"world\""), 6, 8, "`world` is reserved");
}

#[test]
fn toml_syntax_error() {
    check(&replace("[[cable]]", "[[cable]"), 13, 9, "TOML syntax error");
    check(&replace("ea = 1e6", "ea = 1e6 2"), 19, 6, "TOML syntax error");
}

#[test]
fn missing_material_or_field() {
    check(&replace("ei = 1\n", ""), 13, 1, "missing field `ei` (give it, or a `material` preset)");
    let e = check(&replace("linear_density = 0.5", "material = \"unobtainium\""), 18, 12, "unknown material `unobtainium`");
    assert!(e.message.contains("`steel_wire_rope_6x36_iwrc`"), "{e}");
}

#[test]
fn rendering_points_at_the_column() {
    let e = err(&replace("length = 5", "length = -2"));
    assert_eq!(
        e.to_string(),
        "error: cable `rope`: `length` must be greater than 0 m, found -2\n  --> bad.toml:15:10\n   |\n15 | length = -2\n   |          ^^"
    );
}

/// The complete example of docs/scenario.md: every section and every field.
fn docs_example() -> &'static str {
    let doc = include_str!("../docs/scenario.md");
    let start = doc.find("```toml\n").map_or(0, |i| i + 8);
    let end = doc[start..].find("```").map_or(doc.len(), |i| start + i);
    &doc[start..end]
}

#[test]
fn docs_example_parses_with_every_field() {
    let s = parse(docs_example(), "scenario.md").unwrap_or_else(|e| panic!("{e}"));
    let sim = &s.simulation;
    assert_eq!((sim.duration, sim.substeps, sim.output_interval), (20.0, Some(2), 0.05));
    approx::assert_relative_eq!(sim.dt, 1.0 / 60.0);
    assert_eq!(sim.gravity, DVec3::new(0.0, -9.81, 0.0));
    assert_eq!((sim.integrator.name.as_str(), sim.integrator.rho_inf), ("generalized_alpha", Some(0.0)));

    let env = &s.environment;
    assert_eq!((env.air_density, env.water_surface, env.water_density), (1.225, Some(-2.0), 1025.0));
    assert_eq!((env.wind, env.current), (DVec3::new(8.0, 0.0, 0.0), DVec3::new(0.3, 0.0, 0.0)));

    let quay = s.body("quay").unwrap();
    assert_eq!((quay.kind, quay.mass, quay.friction), (BodyKind::Fixed, None, 0.6));
    assert_eq!(quay.shape, Shape::Cuboid { half_extents: DVec3::new(20.0, 1.0, 20.0) });
    assert!(quay.location.line > 1 && quay.location.col == 1);
    let jib = s.body("jib").unwrap();
    assert_eq!(jib.shape, Shape::Capsule { radius: 0.3, half_height: 8.0 });
    // Rz(90°) turns the capsule axis (local y) to world -x.
    assert!(jib.rotation.mul_vec3(DVec3::Y).abs_diff_eq(-DVec3::X, 1e-12));
    let trolley = s.body("trolley").unwrap();
    let Some(Motion::Sine { amplitude, period, phase }) = trolley.motion.clone() else { panic!() };
    assert_eq!((amplitude, period, phase), (DVec3::new(2.0, 0.0, 0.0), 12.0, 0.0));
    approx::assert_relative_eq!(trolley.position_at(3.0).x, 14.0);
    let v = trolley.motion.as_ref().unwrap().velocity_at(0.0);
    approx::assert_relative_eq!(v.x, 2.0 * std::f64::consts::TAU / 12.0);
    let barge = s.body("barge").unwrap();
    assert_eq!(barge.position, DVec3::new(14.0, -2.0, 0.0));
    let m = barge.motion.as_ref().unwrap();
    assert_eq!(m.position_at(5.0, DVec3::ZERO), DVec3::new(14.0, -2.0, 1.5));
    assert_eq!(m.position_at(99.0, DVec3::ZERO), DVec3::new(16.0, -2.0, 3.0));
    assert_eq!(m.velocity_at(15.0), DVec3::new(0.2, 0.0, 0.0));
    assert_eq!(m.velocity_at(25.0), DVec3::ZERO);
    let hook = s.body("hook").unwrap();
    assert_eq!((hook.kind, hook.mass), (BodyKind::Dynamic, Some(500.0)));
    assert_eq!(hook.shape, Shape::Cylinder { radius: 0.35, half_height: 0.4 });
    let q = DQuat::from_euler(EulerRot::XYZ, 0.0, 90f64.to_radians(), 0.0);
    assert!(hook.rotation.dot(q) > 1.0 - 1e-12);
    assert_eq!(hook.linear_velocity, DVec3::new(0.5, 0.0, 0.0));
    approx::assert_relative_eq!(hook.angular_velocity.y, 10f64.to_radians());
    assert_eq!((hook.wind_area, hook.wind_coefficient, hook.friction), (0.6, 1.2, 0.4));
    assert_eq!(s.body("shackle").unwrap().shape, Shape::Ball { radius: 0.1 });

    let slew = &s.joints[0];
    assert_eq!((slew.kind, slew.body1.as_str(), slew.body2.as_str()), (JointKind::Revolute, "world", "jib"));
    assert_eq!((slew.anchor1, slew.axis), (DVec3::new(0.0, 30.0, 0.0), Some(DVec3::Y)));
    let lim = slew.limits.unwrap();
    approx::assert_relative_eq!(lim[0], -std::f64::consts::FRAC_PI_4);
    let Some(Drive::Velocity { velocity, max_force }) = &slew.drive else { panic!() };
    assert_eq!(*max_force, 2e6);
    approx::assert_relative_eq!(velocity.value_at(2.5), 1.5f64.to_radians());
    approx::assert_relative_eq!(velocity.value_at(99.0), 0.0);
    let balance = &s.joints[1];
    assert_eq!((balance.kind, balance.limits), (JointKind::Prismatic, Some([-1.0, 4.0])));
    let Some(Drive::Force { force }) = &balance.drive else { panic!() };
    assert_eq!((force.value_at(-1.0), force.value_at(1.0), force.value_at(9.0)), (0.0, 2500.0, 5000.0));
    assert_eq!((s.joints[2].kind, s.joints[2].axis), (JointKind::Spherical, None));
    assert_eq!(s.joints[3].kind, JointKind::Fixed);

    let hoist = s.cable("hoist").unwrap();
    let steel = bevy_rapier_cable::cable::preset("steel_wire_rope_6x36_iwrc", 0.02).unwrap();
    assert_eq!((hoist.length, hoist.segments, hoist.diameter), (18.8, 40, 0.02));
    assert_eq!((hoist.linear_density, hoist.ea, hoist.gj), (steel.linear_density, steel.ea, steel.gj));
    assert_eq!((hoist.ei, hoist.ei2, hoist.shear_stiffness), (40.0, 45.0, Some(1e8)));
    assert_eq!((hoist.damping, hoist.friction, hoist.drag_normal, hoist.drag_tangential, hoist.added_mass), (0.002, 0.2, 1.1, 0.01, 0.9));
    assert_eq!(hoist.material.as_deref(), Some("steel_wire_rope_6x36_iwrc"));
    // Default path: the trolley point to the hook point.
    assert_eq!(hoist.path, vec![DVec3::new(12.0, 29.2, 0.0), DVec3::new(12.0, 10.4, 0.0)]);
    approx::assert_relative_eq!(hoist.path_length(), hoist.length, epsilon = 1e-9);
    assert!(matches!(&hoist.end, CableEnd::Body { body, clamp: true, .. } if body == "hook"));
    assert!(hoist.contacts);
    let tag = s.cable("tagline").unwrap();
    assert_eq!((tag.linear_density, tag.ea, tag.ei, tag.ei2, tag.gj), (0.09, 1.2e6, 0.02, 0.02, 0.01));
    assert_eq!((&tag.end, tag.path.len(), tag.contacts), (&CableEnd::Free, 3, false));
    // Extensions: point loads, stress-free shape, static start, spin.
    assert_eq!(tag.loads.len(), 2);
    assert_eq!((tag.loads[0].s, tag.loads[0].force, tag.loads[0].moment), (6.0, DVec3::new(0.0, -50.0, 0.0), DVec3::ZERO));
    assert_eq!((tag.loads[1].s, tag.loads[1].force, tag.loads[1].moment), (3.0, DVec3::new(20.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 1.5)));
    assert!(!tag.stress_free && hoist.loads.is_empty());
    assert_eq!((sim.statics, sim.static_load_steps), (true, 5));
    let radar = s.body("radar").unwrap();
    let Some(Motion::Spin { axis, rate }) = &radar.motion else { panic!("{:?}", radar.motion) };
    assert_eq!((*axis, rate.points.len()), (DVec3::Y, 3));
    approx::assert_relative_eq!(rate.value_at(10.0), 36f64.to_radians());
    let hose = s.cable("hose").unwrap();
    assert!(hose.stress_free);
    assert_eq!(hose.start, CableEnd::Free);
    assert_eq!(hose.end, CableEnd::World { point: DVec3::new(-5.0, 4.0, 0.0), clamp: true });
    let fibre = bevy_rapier_cable::cable::preset("fibre_rope_polyester", 0.1).unwrap();
    assert_eq!((hose.linear_density, hose.ea), (6.0, fibre.ea));

    let w = &s.winches[0];
    assert_eq!((w.cable.as_str(), w.at, w.brake), ("hoist", CableSide::Start, true));
    assert_eq!((w.drum_radius, w.drum_inertia, w.max_torque), (0.4, 25.0, 3e4));
    assert_eq!((w.min_length, w.max_length, w.speed.value_at(3.0)), (Some(2.0), Some(28.0), -0.25));

    assert_eq!(s.probes[1].component, Some(Component::Y));
    assert_eq!(s.probes[2].target, ProbeTarget::Cable("hoist".into()));
    assert_eq!((s.probes[2].quantity, s.probes[2].s), (Quantity::Tension, Some(0.25)));
    assert_eq!((s.probes[5].quantity, s.probes[5].component), (Quantity::Force, Some(Component::Norm)));
    assert_eq!(s.probes[8].target, ProbeTarget::System);
    let expected = [
        "hook.x",
        "hook.y",
        "hook.z",
        "hook_height",
        "rope_tension_top",
        "rope_out",
        "slew_angle",
        "swivel_force",
        "tagline_tip_speed",
        "hose_length",
        "energy",
    ];
    assert_eq!(s.columns(), expected);
    // The column list at the end of the page matches.
    let listed = include_str!("../docs/scenario.md").split("writes the columns `").nth(1).unwrap_or("");
    let listed: String = listed.split('`').next().unwrap_or("").split_whitespace().collect();
    assert_eq!(listed, format!("time,{}", expected.join(",")));
}

#[test]
fn every_integrator_and_parameter_is_accepted() {
    let cases: &[(&str, &str)] = &[
        ("euler", ""),
        ("symplectic_euler", ""),
        ("improved_euler", ""),
        ("rk4", ""),
        ("linear_acceleration", ""),
        ("newmark", "beta = 0.3\ngamma = 0.6"),
        ("wilson_theta", "theta = 1.4"),
        ("hht", "alpha = -0.1"),
        ("generalized_alpha", "rho_inf = 0.5"),
        ("linearly_implicit", "w = 0.55"),
    ];
    for (name, params) in cases {
        let src = replace("dt = 0.01\n", &format!("dt = 0.01\nintegrator = \"{name}\"\n{params}\n"));
        let i = parse(&src, "i.toml").unwrap_or_else(|e| panic!("{e}")).simulation.integrator;
        assert_eq!(i.name, *name);
        let given = [i.beta, i.gamma, i.theta, i.alpha, i.rho_inf, i.w];
        let expected = match *name {
            "newmark" => [Some(0.3), Some(0.6), None, None, None, None],
            "wilson_theta" => [None, None, Some(1.4), None, None, None],
            "hht" => [None, None, None, Some(-0.1), None, None],
            "generalized_alpha" => [None, None, None, None, Some(0.5), None],
            "linearly_implicit" => [None, None, None, None, None, Some(0.55)],
            _ => [None; 6],
        };
        assert_eq!(given, expected, "{name}");
    }
}

#[test]
fn defaults_are_right() {
    let s = parse(BASE, "base.toml").unwrap();
    let sim = &s.simulation;
    assert_eq!((sim.substeps, sim.output_interval, sim.gravity), (None, 0.01, DVec3::new(0.0, -9.81, 0.0)));
    assert_eq!(sim.integrator.name, "generalized_alpha");
    assert_eq!(sim.integrator.rho_inf, Some(0.0));
    assert_eq!((sim.statics, sim.static_load_steps), (false, 10));
    assert!(s.cables[0].loads.is_empty() && !s.cables[0].stress_free);
    let env = &s.environment;
    assert_eq!((env.air_density, env.wind, env.water_surface, env.water_density, env.current), (1.225, DVec3::ZERO, None, 1025.0, DVec3::ZERO));
    let b = &s.bodies[0];
    assert_eq!((b.rotation, b.linear_velocity, b.angular_velocity), (DQuat::IDENTITY, DVec3::ZERO, DVec3::ZERO));
    assert_eq!((b.friction, b.restitution, b.wind_area, b.wind_coefficient, b.motion.is_none()), (0.5, 0.0, 0.0, 0.0, true));
    let c = &s.cables[0];
    assert_eq!((c.damping, c.friction, c.drag_normal, c.drag_tangential, c.added_mass), (0.0, 0.3, 1.2, 0.008, 1.0));
    assert_eq!((c.ei2, c.shear_stiffness, c.contacts, c.material.is_none()), (1.0, None, true, true));
    assert_eq!(c.end, CableEnd::Body { body: "hook".into(), anchor: DVec3::ZERO, clamp: false });
    // Free end: straight down from the start, of the cable's length.
    let s = parse(&replace("end = { body = \"hook\" }\n", ""), "free.toml").unwrap();
    assert_eq!(s.cables[0].path, vec![DVec3::ZERO, DVec3::new(0.0, -5.0, 0.0)]);
}

#[test]
fn random_corruption_never_panics() {
    let mut state: u64 = 0x2545_F491_4F6C_DD1D;
    let mut next = move || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) as usize
    };
    const GARBAGE: &[&str] = &[
        "\"",
        "[",
        "]",
        "{",
        "}",
        "=",
        ",",
        "\n",
        "#",
        "nan",
        "-inf",
        "1e999",
        "0",
        "-1",
        "x",
        "é",
        "[[",
        "'''",
        "\"world\"",
        "true",
        "1979-05-27",
        "\\u00e9",
        ".",
        "9999999999999999999999",
        "e300",
        "e-300",
        "1e308",
        "-1e308",
        "-",
        "000",
    ];
    // FUZZ_ITERS=200000 for a longer run.
    let iters: usize = std::env::var("FUZZ_ITERS").ok().and_then(|s| s.parse().ok()).unwrap_or(2000);
    let mut errors = 0;
    for i in 0..iters {
        let mut chars: Vec<char> = if i % 2 == 0 { docs_example() } else { BASE }.chars().collect();
        for _ in 0..1 + next() % 3 {
            let at = next() % (chars.len() + 1);
            if next() % 2 == 0 && at < chars.len() {
                chars.remove(at);
            } else {
                let g = GARBAGE[next() % GARBAGE.len()];
                for (k, c) in g.chars().enumerate() {
                    chars.insert(at + k, c);
                }
            }
        }
        let src: String = chars.into_iter().collect();
        if let Err(e) = parse(&src, "fuzz.toml") {
            errors += 1;
            let shown = e.to_string();
            assert!(shown.starts_with("error: "), "{shown}");
            assert!(e.line >= 1 && e.col >= 1, "no position:\n{shown}");
        }
    }
    assert!(errors > iters / 4, "only {errors} of {iters} mutations were rejected");
}
#[test]
fn deeply_nested_input_is_an_error_not_a_stack_overflow() {
    let n = 100_000;
    let src = format!(
        "{BASE}\n[[body]]\nname='k'\ntype='kinematic'\nshape='ball'\nradius=1\nmotion = {{ type = 'table', points = {}{} }}\n",
        "[".repeat(n),
        "]".repeat(n)
    );
    let e = check(&src, 30, 116, "TOML syntax error");
    assert!(e.to_string().len() < 400, "the long line is cut around the column:\n{e}");
}

// ---------------------------------------------------------------------------
// Extensions: point loads, statics, stress-free shape, spinning bodies
// ---------------------------------------------------------------------------

/// 1-based line and column of the last occurrence of `needle` in `src`.
fn last(src: &str, needle: &str) -> (usize, usize) {
    let at = src.rfind(needle).unwrap_or_else(|| panic!("{needle:?} not in the source"));
    let line = src[..at].matches('\n').count() + 1;
    let col = src[..at].rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// `BASE` with `extra` appended to the `[[cable]]` table, checked to fail at
/// the last occurrence of `marker` with `phrase`.
fn cable_err(extra: &str, marker: &str, phrase: &str) -> ScenarioError {
    let src = format!("{BASE}{extra}\n");
    let (line, col) = last(&src, marker);
    check(&src, line, col, phrase)
}

#[test]
fn point_loads_are_validated() {
    cable_err("loads = [{ s = nan, force = [0, 1, 0] }]", "nan", "cable `rope`: load 1: `s` must be a finite number, found NaN");
    cable_err("loads = [{ s = -1, force = [0, 1, 0] }]", "-1", "load 1: `s` must be at least 0 m, found -1");
    cable_err("loads = [{ s = 5, force = [0, 1, 0] }, { s = 6, force = [0, 1, 0] }]", "6,", "load 2: `s` must be at most the cable's `length` 5 m, found 6");
    cable_err("loads = [{ s = 2, force = [0, 1] }]", "[0, 1]", "load 1: `force` must have 3 components [x, y, z] (N), found 2");
    cable_err("loads = [{ s = 2, force = [0, inf, 0] }]", "inf", "load 1: `force` must be a finite number");
    cable_err("loads = [{ s = 2, force = [0, 1, 0], moment = [nan, 0, 0] }]", "nan", "load 1: `moment` must be a finite number");
    cable_err("loads = [{ s = 2, force = \"up\" }]", "\"up\"", "invalid type: string \"up\"");
    cable_err("loads = [{ s = \"end\", force = [0, 1, 0] }]", "\"end\"", "invalid type: string \"end\"");
    cable_err("loads = [{ s = 2, force = [0, 1, 0], torque = [0, 0, 1] }]", "torque", "unknown field `torque`");
    cable_err("loads = [{ s = 2 }]", "{ s = 2 }", "missing field `force`");
    cable_err("loads = { s = 2, force = [0, 1, 0] }", "{ s = 2", "invalid type");
}

#[test]
fn point_loads_parse() {
    let src = format!("{BASE}loads = [{{ s = 5, force = [0, -100, 0] }}, {{ s = 2.5, force = [1, 0, 0], moment = [0, 0, 3] }}]\n");
    let s = parse(&src, "loads.toml").unwrap_or_else(|e| panic!("{e}"));
    let l = &s.cables[0].loads;
    assert_eq!(l.len(), 2);
    assert_eq!((l[0].s, l[0].force, l[0].moment), (5.0, DVec3::new(0.0, -100.0, 0.0), DVec3::ZERO));
    assert_eq!((l[1].s, l[1].force, l[1].moment), (2.5, DVec3::X, DVec3::new(0.0, 0.0, 3.0)));
    let base = parse(BASE, "base.toml").unwrap();
    assert!(base.cables[0].loads.is_empty() && !base.cables[0].stress_free);
}

#[test]
fn stress_free_is_a_boolean() {
    cable_err("stress_free = 1", "1", "invalid type: integer `1`, expected a boolean");
    let s = parse(&format!("{BASE}stress_free = true\n"), "sf.toml").unwrap();
    assert!(s.cables[0].stress_free);
}

#[test]
fn tension_only_is_a_boolean_that_defaults_to_true() {
    cable_err("tension_only = \"no\"", "\"no\"", "invalid type: string \"no\", expected a boolean");
    assert!(parse(BASE, "base.toml").unwrap().cables[0].tension_only);
    let s = parse(&format!("{BASE}tension_only = false\n"), "rod.toml").unwrap();
    assert!(!s.cables[0].tension_only);
}

#[test]
fn statics_fields_are_validated() {
    let with = |sim: &str| replace("dt = 0.01\n", &format!("dt = 0.01\n{sim}\n"));
    check(&with("statics = \"yes\""), 4, 11, "invalid type: string \"yes\", expected a boolean");
    check(&with("statics = true\nstatic_load_steps = 0"), 5, 21, "`static_load_steps` must be between 1 and 10000, found 0");
    check(&with("statics = true\nstatic_load_steps = -3"), 5, 21, "found -3");
    check(&with("statics = true\nstatic_load_steps = 2.5"), 5, 21, "invalid type: floating point");
    check(&with("static_load_steps = 5"), 4, 21, "`static_load_steps` only applies with `statics = true`");
    check(&with("statics = false\nstatic_load_steps = 5"), 5, 21, "only applies with `statics = true`");
    let s = parse(&with("statics = true"), "s.toml").unwrap();
    assert_eq!((s.simulation.statics, s.simulation.static_load_steps), (true, 10));
    let s = parse(&with("statics = true\nstatic_load_steps = 4"), "s.toml").unwrap();
    assert_eq!((s.simulation.statics, s.simulation.static_load_steps), (true, 4));
    let s = parse(BASE, "base.toml").unwrap();
    assert!(!s.simulation.statics);
}

/// `BASE` plus a kinematic body `hub` with the given `motion`.
fn hub(motion: &str) -> String {
    format!("{BASE}\n[[body]]\nname = \"hub\"\ntype = \"kinematic\"\nshape = \"ball\"\nradius = 0.1\nposition = [1, 2, 3]\nmotion = {motion}\n")
}

fn hub_err(motion: &str, marker: &str, phrase: &str) -> ScenarioError {
    let src = hub(motion);
    let (line, col) = last(&src, marker);
    check(&src, line, col, phrase)
}

#[test]
fn spin_motion_is_validated() {
    hub_err("{ type = \"spin\", axis = [0, 0, 0], rate = [[0, 10]] }", "[0, 0, 0]", "body `hub`: motion: `axis` must be a nonzero direction, found [0, 0, 0]");
    hub_err("{ type = \"spin\", axis = [0, nan, 1], rate = [[0, 10]] }", "nan", "motion: `axis` must be a finite number");
    hub_err("{ type = \"spin\", axis = [0, 1], rate = [[0, 10]] }", "[0, 1]", "`axis` must have 3 components");
    hub_err("{ type = \"spin\", axis = [0, 1, 0] }", "{ type", "motion: missing field `rate` (required for a spin)");
    hub_err("{ type = \"spin\", rate = [[0, 10]] }", "{ type", "motion: missing field `axis` (required for a spin)");
    hub_err(
        "{ type = \"spin\", axis = [0, 1, 0], rate = [[0, 0], [2, 10], [1, 20]] }",
        "1, 20",
        "times in `rate` must be strictly increasing; point 3 has t = 1 after t = 2",
    );
    hub_err("{ type = \"spin\", axis = [0, 1, 0], rate = [[0, 0], [1, nan]] }", "nan", "`rate`: the rate must be a finite number, found NaN");
    hub_err("{ type = \"spin\", axis = [0, 1, 0], rate = [[0, \"fast\"]] }", "\"fast\"", "`rate`: the rate must be a number, found a string");
    hub_err("{ type = \"spin\", axis = [0, 1, 0], rate = 30 }", "30", "`rate` must be a list of points [[t, rate], ...] (s, deg/s); found a number");
    hub_err("{ type = \"spin\", axis = [0, 1, 0], rate = [] }", "[]", "found an empty list");
    hub_err("{ type = \"spin\", axis = [0, 1, 0], rate = [[0, 1]], period = 2 }", "2 }", "`period` does not apply to a `spin` motion");
    hub_err("{ type = \"sine\", amplitude = [1, 0, 0], period = 2, axis = [0, 1, 0] }", "[0, 1, 0]", "`axis` does not apply to a `sine` motion");
    hub_err("{ type = \"table\", points = [[0, [1, 2, 3]]], rate = [[0, 1]] }", "[[0, 1]]", "`rate` does not apply to a `table` motion");
    hub_err(
        "{ type = \"spinning\", axis = [0, 1, 0], rate = [[0, 1]] }",
        "\"spinning\"",
        "unknown motion type `spinning`; expected one of `sine`, `table`, `spin`",
    );
}

#[test]
fn spin_motion_parses_in_radians_with_a_unit_axis() {
    let s = parse(&hub("{ type = \"spin\", axis = [0, 2, 0], rate = [[0, 0], [2, 90], [4, 90]] }"), "spin.toml").unwrap_or_else(|e| panic!("{e}"));
    let b = s.body("hub").unwrap();
    let Some(Motion::Spin { axis, rate }) = &b.motion else { panic!("{:?}", b.motion) };
    assert_eq!(*axis, DVec3::Y);
    let half_pi = std::f64::consts::FRAC_PI_2;
    assert_eq!(rate.points, vec![(0.0, 0.0), (2.0, half_pi), (4.0, half_pi)]);
    let m = b.motion.as_ref().unwrap();
    // Angle: ∫ rate = π/2 (ramp) + π (constant) at t = 4, then π/2 per s.
    for (t, angle) in [(0.0, 0.0), (1.0, half_pi / 4.0), (2.0, half_pi), (4.0, 1.5 * std::f64::consts::PI), (5.0, 2.0 * std::f64::consts::PI)] {
        let q = m.rotation_at(t);
        let expect = DQuat::from_rotation_y(angle);
        assert!(q.dot(expect).abs() > 1.0 - 1e-14, "t = {t}: {q:?} vs {expect:?}");
    }
    assert_eq!(m.angular_velocity_at(1.0), DVec3::new(0.0, half_pi / 2.0, 0.0));
    assert_eq!(m.angular_acceleration_at(1.0), DVec3::new(0.0, half_pi / 2.0, 0.0));
    // At a breakpoint: the mean of the slopes on either side; outside: 0.
    assert_eq!(m.angular_acceleration_at(2.0), DVec3::new(0.0, half_pi / 4.0, 0.0));
    assert_eq!(m.angular_acceleration_at(5.0), DVec3::ZERO);
    // Position stays; orientation = spin · rotation.
    assert_eq!(b.position_at(3.0), DVec3::new(1.0, 2.0, 3.0));
    assert!(b.rotation_at(2.0).dot(DQuat::from_rotation_y(half_pi)).abs() > 1.0 - 1e-14);
    let _ = EulerRot::XYZ;
}

/// What `sim::World` (rapier bodies and joints) still refuses, with the
/// file position.
#[cfg(feature = "sim")]
mod world_refusals {
    use bevy_rapier_cable::scenario::parse;
    use bevy_rapier_cable::sim::{SimError, World};

    const BEAM: &str = r#"[simulation]
duration = 1.0
dt = 0.01

[[body]]
name = "beam"
type = "dynamic"
shape = "cuboid"
half_extents = [1.0, 0.1, 0.1]
mass = 500.0
position = [1.0, 0.0, 0.0]

[[joint]]
name = "hinge"
type = "revolute"
body1 = "world"
body2 = "beam"
anchor1 = [0.0, 0.0, 0.0]
anchor2 = [-1.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
"#;

    fn world_err(src: &str) -> (SimError, String) {
        let sc = parse(src, "bad.toml").unwrap_or_else(|e| panic!("{e}"));
        let e = World::new(sc).expect_err("World::new should refuse this");
        let shown = e.to_string();
        (e, shown)
    }

    #[test]
    fn joint_anchors_that_do_not_meet() {
        let src = BEAM.replace("anchor2 = [-1.0, 0.0, 0.0]", "anchor2 = [-0.9, 0.0, 0.0]");
        let (e, shown) = world_err(&src);
        assert!(matches!(e, SimError::Invalid { .. }), "{shown}");
        assert!(shown.starts_with("bad.toml:13:1:") && shown.contains("must be the same point"), "{shown}");
    }

    #[test]
    fn force_probe_on_an_undriven_rapier_joint() {
        let src = format!("{BEAM}\n[[probe]]\nname = \"f\"\njoint = \"hinge\"\nquantity = \"force\"\n");
        let (e, shown) = world_err(&src);
        assert!(matches!(e, SimError::Unsupported { .. }), "{shown}");
        assert!(shown.starts_with("bad.toml:22:1:") && shown.contains("has no `drive`") && shown.contains("not supported yet"), "{shown}");
        // With a drive the force probe is the drive's.
        let driven = src.replace("axis = [0.0, 0.0, 1.0]", "axis = [0.0, 0.0, 1.0]\ndrive = { force = [[0.0, 10.0]] }");
        World::new(parse(&driven, "ok.toml").unwrap()).unwrap_or_else(|e| panic!("{e}"));
    }

    #[test]
    fn clamped_end_on_a_rapier_body() {
        let cable = "\n[[cable]]\nname = \"stay\"\nlength = 3.0\nsegments = 4\ndiameter = 0.02\nlinear_density = 1.0\nea = 1e6\nei = 1.0\ngj = 1.0\nstart = { world = [2.0, 3.0, 0.0] }\nend = { body = \"beam\", anchor = [1.0, 0.0, 0.0], clamp = true }\n";
        let (e, shown) = world_err(&format!("{BEAM}{cable}"));
        assert!(matches!(e, SimError::Unsupported { .. }), "{shown}");
        assert!(shown.starts_with("bad.toml:22:1:") && shown.contains("clamped to body `beam`"), "{shown}");
        // Pinned, it runs.
        let ok = format!("{BEAM}{}", cable.replace(", clamp = true", ""));
        World::new(parse(&ok, "ok.toml").unwrap()).unwrap_or_else(|e| panic!("{e}"));
    }

    /// What used to be refused now builds: a free dynamic body, a cable
    /// starting on a free dynamic body, a body between two cables, joints
    /// between dynamic bodies.
    #[test]
    fn formerly_refused_layouts_build() {
        let src = r#"[simulation]
duration = 1.0
dt = 0.01

[[body]]
name = "rock"
type = "dynamic"
shape = "ball"
radius = 0.2
mass = 5.0
position = [5.0, 1.0, 0.0]

[[body]]
name = "hook"
type = "dynamic"
shape = "ball"
radius = 0.1
mass = 50.0
position = [0.0, -2.0, 0.0]

[[body]]
name = "load"
type = "dynamic"
shape = "cuboid"
half_extents = [0.2, 0.2, 0.2]
mass = 200.0
position = [0.0, -4.2, 0.0]

[[body]]
name = "arm"
type = "dynamic"
shape = "capsule"
radius = 0.05
half_height = 0.3
mass = 2.0
position = [0.0, -4.7, 0.0]

[[joint]]
name = "wrist"
type = "spherical"
body1 = "load"
body2 = "arm"
anchor1 = [0.0, -0.2, 0.0]
anchor2 = [0.0, 0.3, 0.0]

[[cable]]
name = "upper"
length = 2.0
segments = 4
diameter = 0.02
linear_density = 1.0
ea = 1e5
ei = 1.0
gj = 1.0
start = { world = [0.0, 0.0, 0.0] }
end = { body = "hook" }

[[cable]]
name = "lower"
length = 2.0
segments = 4
diameter = 0.02
linear_density = 1.0
ea = 1e5
ei = 1.0
gj = 1.0
start = { body = "hook" }
end = { body = "load", anchor = [0.0, 0.2, 0.0] }
"#;
        let mut w = World::new(parse(src, "ok.toml").unwrap()).unwrap_or_else(|e| panic!("{e}"));
        for _ in 0..10 {
            w.step().unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

/// Sizes and run lengths that cannot be run are refused before anything is
/// allocated or stepped, naming the field and the limit: 2³¹ segments
/// aborted on a 51 GB allocation, `dt = 1e-12` hung.
#[test]
fn huge_sizes_and_endless_runs_are_refused() {
    check(&replace("segments = 10", "segments = 2147483648"), 16, 12, "`segments` must be between 1 and 100000, found 2147483648");
    check(&replace("segments = 10", "segments = 100001"), 16, 12, "between 1 and 100000");
    parse(&replace("segments = 10", "segments = 100000"), "ok.toml").expect("the largest size is accepted");
    let e = check(&replace("dt = 0.01", "dt = 1e-12"), 3, 6, "`dt` = 1e-12 s gives 1000000000000 steps over `duration` = 1 s");
    assert!(e.message.contains("at most 100000000 can be run"), "{e}");
    let e = check(&replace("dt = 0.01", "dt = 1e-7\nsubsteps = 20"), 3, 6, "with `substeps` = 20");
    assert!(e.message.contains("200000000 steps"), "{e}");
    parse(&replace("dt = 0.01", "dt = 1e-8"), "ok.toml").expect("10⁸ steps are accepted");
}

/// An `output_interval` just below `dt` is refused with values that can be
/// told apart (they used to print as 0.016667 and 0.016667).
#[test]
fn output_interval_refusal_shows_distinguishable_values() {
    let src = replace("dt = 0.01", "dt = 0.016666666666666666\noutput_interval = 0.01666666666666666");
    let e = check(&src, 4, 19, "must be at least `dt` = 0.016666666666666666 s, found 0.01666666666666666 s");
    println!("{e}");
}

/// A cable's `end_stiffness` (a multiple of `EA/L_e`) must be positive
/// and finite: 0, a negative value or NaN is refused with its name, unit
/// and place; a valid one reaches the cable.
#[test]
fn end_stiffness_out_of_range_is_refused() {
    let with = |v: &str| replace("segments = 10", &format!("segments = 10\nend_stiffness = {v}"));
    check(&with("0"), 17, 17, "`end_stiffness` must be greater than 0 (multiple of EA/L_e), found 0");
    check(&with("-2"), 17, 17, "`end_stiffness` must be greater than 0");
    check(&with("nan"), 17, 17, "`end_stiffness`");
    let sc = parse(&with("2.5"), "ok.toml").unwrap();
    assert_eq!(sc.cables[0].end_stiffness, 2.5);
    let sc = parse(BASE, "ok.toml").unwrap();
    assert_eq!(sc.cables[0].end_stiffness, bevy_rapier_cable::cable::END_STIFFNESS_FACTOR);
}
