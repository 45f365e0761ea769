//! `[orbit] gravity` and `third_body` (contract section 17): the scene keys, their refusals at
//! their lines, and what `satsim environment` reports.

use satsim_environment::gravity::{HarmonicField, MU_MOON, MU_SUN, egm2008};
use satsim_environment::moon::moon_position;
use satsim_environment::sun::sun_position;
use satsim_environment::{Vec3, parse_epoch};
use satsim_spacecraft::effects::orbit::{J2_EARTH, MU_EARTH, R_EARTH};
use satsim_tools::environment::environment;
use satsim_tools::scene::Scene;
use std::path::Path;

const EPOCH: &str = "2026-03-20T12:00:00 UTC";

/// A one-body scene; `orbit` is the `[orbit]` table's extra lines (line 9 on), `epoch` on line 1
/// or a comment.
fn text(epoch: bool, orbit: &str) -> String {
    format!(
        "{}\nduration = 10.0\n[model]\n[[model.body]]\nname = \"bus\"\nmass = 100.0\ninertia = [[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 10.0]]\n[orbit]\naltitude = 500e3\ninclination_deg = 51.6\n{orbit}\n",
        if epoch {
            format!("epoch = \"{EPOCH}\"")
        } else {
            "# no epoch".into()
        }
    )
}

fn read(epoch: bool, orbit: &str) -> Result<Scene, String> {
    Scene::parse(&text(epoch, orbit), Path::new("orbit.toml")).map_err(|e| e.to_string())
}

/// The refusal of `orbit` (on line 11) at line `line`, containing `words`.
fn refused(epoch: bool, orbit: &str, line: usize, words: &str) {
    let e = read(epoch, orbit)
        .err()
        .unwrap_or_else(|| panic!("accepted: {orbit}"));
    assert!(
        e.contains(&format!("orbit.toml:{line}:")) && e.contains(words),
        "{orbit}: {e}"
    );
}

#[test]
fn environment_reports_the_harmonic_gravity_at_the_position() {
    let s = read(
        true,
        "gravity = { model = \"egm2008\", degree = 20, order = 20 }",
    )
    .unwrap();
    let env = environment(&s, 0.0).unwrap();
    let (r, _) = env.orbit.unwrap();
    let field = HarmonicField::new(egm2008().unwrap(), 20, 20).unwrap();
    let expected = field.acceleration_gcrf(parse_epoch(EPOCH).unwrap(), 0.0, &r);
    assert_eq!(env.gravity.unwrap(), expected);
    assert!(env.moon.is_none() && env.third_body.is_none());
    // Later in the run, too (the Earth has turned).
    let later = environment(&s, 10.0).unwrap();
    let (r, _) = later.orbit.unwrap();
    let expected = field.acceleration_gcrf(parse_epoch(EPOCH).unwrap(), 10.0, &r);
    assert_eq!(later.gravity.unwrap(), expected);
}

#[test]
fn point_and_j2_are_today_s_models_under_either_key() {
    let j2 = |r: Vec3| {
        let r2 = r.norm_squared();
        let z2 = r.z * r.z / r2;
        let k = -1.5 * J2_EARTH * MU_EARTH * R_EARTH * R_EARTH / (r2 * r2 * r2.sqrt());
        -MU_EARTH / (r2 * r2.sqrt()) * r
            + k * Vec3::new(
                r.x * (1.0 - 5.0 * z2),
                r.y * (1.0 - 5.0 * z2),
                r.z * (3.0 - 5.0 * z2),
            )
    };
    for (orbit, with_j2) in [
        ("", false),
        ("model = \"kepler\"", false),
        ("gravity = \"point\"", false),
        ("gravity = { model = \"point\" }", false),
        ("model = \"kepler\"\ngravity = \"point\"", false),
        ("model = \"j2\"", true),
        ("gravity = \"j2\"", true),
        ("model = \"j2\"\ngravity = { model = \"j2\" }", true),
    ] {
        let env = environment(&read(false, orbit).unwrap(), 0.0).unwrap();
        let (r, _) = env.orbit.unwrap();
        let expected = if with_j2 {
            j2(r)
        } else {
            -MU_EARTH / r.norm().powi(3) * r
        };
        assert!(
            (env.gravity.unwrap() - expected).norm() < 1e-15 * expected.norm(),
            "{orbit}"
        );
    }
}

#[test]
fn environment_reports_the_moon_and_the_third_bodies_pull() {
    let s = read(true, "third_body = [\"sun\", \"moon\"]").unwrap();
    let env = environment(&s, 0.0).unwrap();
    let (r, _) = env.orbit.unwrap();
    let epoch = parse_epoch(EPOCH).unwrap();
    let (sun, moon) = (sun_position(epoch, 0.0), moon_position(epoch, 0.0));
    assert!((env.moon.unwrap() - moon).norm() < 1e-6);
    let tide = |mu: f64, b: Vec3| mu * ((b - r) / (b - r).norm().powi(3) - b / b.norm().powi(3));
    let formula = tide(MU_SUN, sun) + tide(MU_MOON, moon);
    let got = env.third_body.unwrap();
    assert!(
        (got - formula).norm() < 1e-6 * formula.norm(),
        "{got:?} {formula:?}"
    );
    // A low orbit feels ~1e-6 m/s² from the Moon and half that from the Sun.
    assert!((1e-7..3e-6).contains(&got.norm()), "{got:?}");
    // The Sun only: no `moon`.
    let env = environment(&read(true, "third_body = [\"sun\"]").unwrap(), 0.0).unwrap();
    assert!(env.moon.is_none());
    assert!((env.third_body.unwrap() - tide(MU_SUN, sun)).norm() < 1e-6 * tide(MU_SUN, sun).norm());
}

#[test]
fn bad_gravity_and_third_bodies_are_refused_at_their_line() {
    refused(true, "gravity = \"egm2009\"", 11, "unknown model `egm2009`");
    refused(
        true,
        "gravity = { model = \"egm2008\", degree = 71 }",
        11,
        "shipped to degree 70",
    );
    refused(
        true,
        "gravity = { model = \"egm2008\", degree = 10, order = 12 }",
        11,
        "from 0 to the degree (10)",
    );
    refused(
        true,
        "gravity = { model = \"egm2008\", degree = 1 }",
        11,
        "start at 2",
    );
    refused(
        true,
        "gravity = { model = \"egm2008\", degree = 2.5 }",
        11,
        "whole number",
    );
    refused(
        true,
        "gravity = { model = \"egm2008\", degre = 20 }",
        11,
        "unknown key",
    );
    refused(
        true,
        "gravity = { model = \"egm2008\", lattice_deg = 11.0 }",
        11,
        "orbit.gravity.lattice_deg",
    );
    refused(
        true,
        "gravity = { model = \"egm2008\", lattice_deg = -0.5 }",
        11,
        "orbit.gravity.lattice_deg",
    );
    refused(
        true,
        "gravity = { model = \"egm2008\", lattice_deg = \"fine\" }",
        11,
        "must be a number of degrees",
    );
    refused(
        true,
        "gravity = { model = \"point\", lattice_deg = 1.0 }",
        11,
        "belong to \"egm2008\"",
    );
    refused(
        true,
        "gravity = { model = \"j2\", degree = 4 }",
        11,
        "belong to \"egm2008\"",
    );
    refused(
        false,
        "gravity = { model = \"egm2008\", degree = 20, order = 20 }",
        11,
        "`epoch`",
    );
    refused(
        true,
        "model = \"j2\"\ngravity = \"point\"",
        12,
        "contradicts `orbit.model = \"j2\"`",
    );
    refused(
        true,
        "model = \"j2\"\ngravity = \"egm2008\"",
        12,
        "leave `model` out",
    );
    refused(true, "j2 = 1e-3\ngravity = \"egm2008\"", 12, "`orbit.j2`");
    refused(true, "mu = 4e14\ngravity = \"egm2008\"", 12, "`orbit.mu`");
    refused(
        true,
        "third_body = [\"sun\", \"mars\"]",
        11,
        "unknown body `mars`",
    );
    refused(true, "third_body = [\"moon\", \"moon\"]", 11, "twice");
    refused(false, "third_body = [\"moon\"]", 11, "`epoch`");
    refused(true, "model = \"egm2008\"", 11, "unknown value `egm2008`");
}

#[test]
fn the_defaults_are_degree_20_and_order_equal_to_degree() {
    let s = read(true, "gravity = \"egm2008\"").unwrap();
    let o = s
        .effects
        .get::<satsim_spacecraft::effects::Orbit>()
        .unwrap();
    let f = o.harmonics.as_ref().unwrap();
    assert_eq!((f.degree, f.order), (20, 20));
    assert_eq!(o.mu, 3.986004415e14);
    let s = read(true, "gravity = { model = \"egm2008\", degree = 8 }").unwrap();
    let o = s
        .effects
        .get::<satsim_spacecraft::effects::Orbit>()
        .unwrap();
    let f = o.harmonics.as_ref().unwrap();
    assert_eq!((f.degree, f.order), (8, 8));
}
