//! What several of the tools' test modules build: the example files' paths and the tables of
//! small models written into scene text.
#![allow(dead_code)] // each module uses its own subset

use std::path::PathBuf;

/// A file of the repository's `examples/` folder: `example("scenes/deploy.toml")`.
pub fn example(path: &str) -> PathBuf {
    satsim_testkit::root().join("examples").join(path)
}

/// A `[[model.body]]` table: `name`, `mass` (kg) and a diagonal inertia about its centre
/// (kg m²).
pub fn body(name: &str, mass: f64, inertia: [f64; 3]) -> String {
    let [x, y, z] = inertia;
    format!(
        "[[model.body]]\nname = \"{name}\"\nmass = {mass:?}\n\
         inertia = [[{x:?}, 0.0, 0.0], [0.0, {y:?}, 0.0], [0.0, 0.0, {z:?}]]\n"
    )
}

/// A `[[model.hinge]]` table: `name` about z from `parent` to `child`, at `at` m along the
/// parent's x, the child's origin `child_at` m along its own x from the hinge when given.
pub fn z_hinge(name: &str, parent: &str, child: &str, at: f64, child_at: Option<f64>) -> String {
    let child_at = child_at.map_or(String::new(), |c| format!("child_at = [{c:?}, 0.0, 0.0]\n"));
    format!(
        "[[model.hinge]]\nname = \"{name}\"\nparent = \"{parent}\"\nchild = \"{child}\"\n\
         axis = [0.0, 0.0, 1.0]\nat = [{at:?}, 0.0, 0.0]\n{child_at}"
    )
}

/// The `[model]` of a panel (mass `m`, inertia `j` about its centre on every axis, centre `d`
/// from the hinge) on a fixed base, on hinge `h` about z at (0.5, 0, 0): `I θ̈ = τ` with
/// `I = j + m d²`.
pub fn fixed_panel_model(m: f64, j: f64, d: f64) -> String {
    format!(
        "[model]\nbase = {{ kind = \"fixed\" }}\n{}{}{}",
        body("base", 10.0, [1.0; 3]),
        body("panel", m, [j; 3]),
        z_hinge("h", "base", "panel", 0.5, Some(-d))
    )
}
