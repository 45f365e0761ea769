//! Cost of linearising a scene and of its eigen-analysis, on the default deployment scene
//! (the preprint's satellite with an orbit, gravity gradient, springs, stops, three wheels
//! with friction and an attitude controller: 28 states, 8 inputs) and on the springs-only
//! `deployment_modes` scene (19 states, 5 inputs).
//!
//! `cargo bench -p satsim-satellite --bench linearize`

use criterion::{Criterion, criterion_group, criterion_main};
use satsim_tools::linearize::linearize;
use satsim_tools::modes::{modes, modes_of};
use satsim_tools::scene::Scene;
use std::hint::black_box;
use std::path::Path;

fn scene(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/scenes")
        .join(format!("{name}.toml"));
    Scene::read(&path).expect("example scene")
}

fn bench(c: &mut Criterion) {
    for name in ["deploy", "deployment_modes"] {
        let s = scene(name);
        c.bench_function(&format!("linearize/{name}"), |b| {
            b.iter(|| linearize(black_box(&s)).expect("linearises"))
        });
        let lin = linearize(&s).expect("linearises");
        c.bench_function(&format!("eigen/{name}"), |b| {
            b.iter(|| modes_of(black_box(&lin)).expect("modes"))
        });
        c.bench_function(&format!("modes/{name}"), |b| {
            b.iter(|| modes(black_box(&s)).expect("modes"))
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
