//! Inputs the fuzz targets once crashed on (`fuzz/regressions/<target>/`), replayed in CI
//! through the same steps as the targets: each must give a result or an error, never a
//! panic.
//!
//! - `scene_reader/frictionless_wheel_with_stops.toml`: a wheel without friction (no events)
//!   next to hinge stops (events) indexed past the wheels' empty event slice.

use satsim::integrate::{Output, System};
use satsim::tools::scene::Scene;
use std::path::Path;

fn inputs(target: &str) -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/regressions")
        .join(target);
    let mut out: Vec<(String, String)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| {
            let bytes = std::fs::read(&p).unwrap();
            (
                p.display().to_string(),
                String::from_utf8_lossy(&bytes).into_owned(),
            )
        })
        .collect();
    out.sort();
    out
}

/// The `scene_reader` fuzz target's steps.
fn scene_reader(text: &str) {
    let Ok(scene) = Scene::parse(text, Path::new("/nonexistent/fuzz.toml")) else {
        return;
    };
    let Ok(mut sim) = scene.simulation() else {
        return;
    };
    let x0 = sim.x0().to_vec();
    let mut dx = vec![0.0; x0.len()];
    let _ = sim.rhs(0.0, &x0, &mut dx);
    let mut g = vec![0.0; sim.n_events()];
    let _ = sim.events(0.0, &x0, &mut g);
    let mut row = Vec::new();
    let _ = sim.row(0.0, &x0, &mut row);
    let options = scene.options.clone().with_max_steps(20);
    let t_end = sim.t0() + scene.duration.min(1.0);
    let _ = sim.run(&options, t_end, &Output::Steps, |_, _| Ok::<(), ()>(()));
}

#[test]
fn scene_reader_regressions() {
    let inputs = inputs("scene_reader");
    assert!(!inputs.is_empty());
    for (name, text) in inputs {
        println!("{name}");
        scene_reader(&text);
    }
}
