//! Shared by the tree crate's integration tests.

use satsim_tree::{Model, parse_model};
use std::path::Path;

/// The preprint satellite (`examples/satellite.toml`), with `armature` (kg m²) on the three
/// gimbal hinges when it is positive (the opt-in regularisation of a gimbal lock).
pub fn satellite(armature: f64) -> Model {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/satellite.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let (_, mut file) = parse_model(&text, &path).unwrap();
    if armature > 0.0 {
        for h in file.hinge.iter_mut().take(3) {
            h.get_mut().armature = Some(toml::Spanned::new(0..0, armature));
        }
    }
    file.build().unwrap()
}
