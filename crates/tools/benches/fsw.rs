//! What the built-in flight software costs (contract section 16's target: the full
//! `adcs_full.toml` loop at most 25 % more per simulated second than the same scene with
//! the truth-based controller): one orbit (5680 s) of `examples/scenes/adcs_full.toml`
//!
//! - `fsw`: as written — B-dot, then the Sun and field estimator with Sun pointing, then the
//!   star tracker MEKF, nadir guidance, the PID on the wheels and momentum dumping, all on
//!   the sensors at 1 Hz;
//! - `truth`: the same scene with `[fsw]` replaced by the truth-based
//!   `[effects.attitude_control]` (the orbital frame, a PD at 1 Hz on the true attitude and
//!   rate, on the same wheels), the sensors still sampling;
//! - `no_control`: the same scene without either (the sensors sampling, nothing commanded).
//!
//! Each is a whole run in memory (`run_scene`, rows every 10 s). RK4 at a fixed 0.5 s with
//! the 1 Hz samples on its grid: the three take the same steps, so the ratios are the
//! blocks' own cost per simulated second.
//!
//! `cargo bench -p satsim-tools --bench fsw`

use criterion::{Criterion, criterion_group, criterion_main};
use satsim_tools::api::run_scene;
use satsim_tools::scene::Scene;
use std::path::Path;

fn scene(variant: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes/adcs_full.toml");
    let text = std::fs::read_to_string(&path).expect("the example");
    let before_fsw = &text[..text.find("[fsw.bdot]").expect("an [fsw] table")];
    let text = match variant {
        "fsw" => text.clone(),
        "truth" => format!(
            "{before_fsw}[effects.attitude_control]\ntarget = \"orbital\"\nkp = 0.4\nkd = 8.0\nperiod = 1.0\n"
        ),
        _ => before_fsw.to_string(),
    };
    let mut s = Scene::parse(&text, &path).expect("the bench scene");
    s.duration = 5680.0;
    s
}

fn one_orbit(c: &mut Criterion) {
    let mut g = c.benchmark_group("adcs_full_one_orbit");
    g.sample_size(20);
    for variant in ["fsw", "truth", "no_control"] {
        let s = scene(variant);
        g.bench_function(variant, |b| {
            b.iter(|| run_scene(&s, || false).expect("the run"));
        });
    }
    g.finish();
}

criterion_group!(benches, one_orbit);
criterion_main!(benches);
