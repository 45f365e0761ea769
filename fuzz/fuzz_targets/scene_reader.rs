//! Any text given as a scene file gives a scene or a `FileError`, never a panic; a scene that
//! reads builds its simulation (or says why not), and the simulation evaluates its
//! right-hand side, events and output row and takes a few integration steps, each to a
//! result or an error.
//!
//! Only inline models and states are followed: a scene naming a file (`model = "..."`, a
//! flexible body's `modes_file = "..."`) could name `/dev/zero`, which the reader would read
//! forever. Scenes whose sampled laws (sensors, discrete controllers, thrusters) would take
//! more samples than a run may are refused by `check_rows`, as `satsim run` refuses them.
//!
//! Seed corpora: `corpus_seed/scene_reader` (the examples), and one per section of the
//! environment and the hardware (`scene_sensors`, `scene_thrusters`, `scene_flexible`,
//! `scene_environment`), each run for 10^6 executions.
#![no_main]
use libfuzzer_sys::fuzz_target;
use satsim_integrate::{Output, System};
use satsim_tools::scene::Scene;
use std::path::Path;

fuzz_target!(|bytes: &[u8]| {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    if let Ok(table) = text.parse::<toml::Table>()
        && (table.get("model").is_some_and(|m| m.is_str())
            || table.get("initial").is_some_and(|m| m.is_str())
            || names_a_file(&toml::Value::Table(table)))
    {
        return;
    }
    let Ok(scene) = Scene::parse(text, Path::new("/nonexistent/fuzz.toml")) else {
        return;
    };
    if scene.check_rows(100_000).is_err() {
        return;
    }
    if scene.model.n_bodies() > 64
        || scene
            .effects
            .get::<satsim_spacecraft::effects::ReactionWheels>()
            .is_some_and(|w| w.wheels.len() > 16)
    {
        return;
    }
    let Ok(mut sim) = scene.simulation() else {
        return;
    };
    let x0 = sim.x0().to_vec();
    let mut dx = vec![0.0; x0.len()];
    let mut x = x0.clone();
    for k in 0..3 {
        if sim.rhs(0.0, &x, &mut dx).is_err() {
            break;
        }
        for (xi, di) in x.iter_mut().zip(&dx) {
            *xi += 1e-3 * (k + 1) as f64 * di;
        }
        sim.project(&mut x);
    }
    let mut g = vec![0.0; sim.n_events()];
    let _ = sim.events(0.0, &x0, &mut g);
    let mut row = Vec::new();
    let _ = sim.row(0.0, &x0, &mut row);
    // A few steps of the scene's own integrator.
    let options = scene.options.clone().with_max_steps(20);
    let t_end = sim.t0() + scene.duration.min(1.0);
    let _ = sim.run(&options, t_end, &Output::Steps, |_, _| Ok::<(), ()>(()));
});

/// Whether any table holds a `modes_file` (a path the reader would follow).
fn names_a_file(v: &toml::Value) -> bool {
    match v {
        toml::Value::Table(t) => t
            .iter()
            .any(|(k, v)| k == "modes_file" || names_a_file(v)),
        toml::Value::Array(a) => a.iter().any(names_a_file),
        _ => false,
    }
}
