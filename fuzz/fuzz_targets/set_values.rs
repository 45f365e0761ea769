//! Any `--set KEY=VALUE` texts applied to a scene give a scene (or a campaign) or a
//! `FileError`, never a panic. The input's first line picks the scene (even length:
//! `fuzz/scenes/wing.toml` with a `[campaign]` table, its model in a file beside it; odd:
//! `examples/scenes/tumbling.toml`, an inline model); each further line is one `--set`
//! argument, parsed by `Override::parse` (a line it refuses is left out, as the command line
//! would refuse it). `Scene::read_with` (`satsim run`) and, for the campaign scene,
//! `Campaign::read_with` (`satsim campaign`) read the scene file with the overrides, which
//! `overridden_text` applies to its text; a scene that reads builds its simulation and
//! evaluates its right-hand side once.
//!
//! `--set model=...` and `--set initial=...` are left out: a path there could name
//! `/dev/zero`, which the reader would read forever.
#![no_main]
use libfuzzer_sys::fuzz_target;
use satsim_integrate::System;
use satsim_tools::campaign::Campaign;
use satsim_tools::scene::Scene;
use satsim_tools::scene_keys::Override;
use std::path::PathBuf;
use std::sync::OnceLock;

const CAMPAIGN: &str = "
[campaign]
runs = 4
seed = 7
[[campaign.disperse]]
key = \"effects.hinge_springs.stiffness\"
index = 0
scale = { sigma = 0.1 }
[[campaign.disperse]]
key = \"initial.hinges.angle\"
normal = { sigma = 0.02 }
";

/// The two scene files, written once into a temporary folder (the model file beside them).
fn paths() -> &'static [PathBuf; 2] {
    static PATHS: OnceLock<[PathBuf; 2]> = OnceLock::new();
    PATHS.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("satsim-fuzz-set-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("wing.model.toml"),
            include_str!("../scenes/wing.model.toml"),
        )
        .unwrap();
        let wing = dir.join("wing.toml");
        std::fs::write(
            &wing,
            format!("{}{CAMPAIGN}", include_str!("../scenes/wing.toml")),
        )
        .unwrap();
        let tumbling = dir.join("tumbling.toml");
        std::fs::write(
            &tumbling,
            include_str!("../../examples/scenes/tumbling.toml"),
        )
        .unwrap();
        [wing, tumbling]
    })
}

fuzz_target!(|bytes: &[u8]| {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    let mut lines = text.lines();
    let pick = lines.next().map_or(0, |l| l.len() % 2);
    let overrides: Vec<Override> = lines
        .take(16)
        .filter_map(|l| Override::parse(l).ok())
        .filter(|o| o.key != "model" && o.key != "initial")
        .collect();
    let path = &paths()[pick];
    if let Ok(scene) = Scene::read_with(path, &overrides)
        && let Ok(mut sim) = scene.simulation()
    {
        let x0 = sim.x0().to_vec();
        let mut dx = vec![0.0; x0.len()];
        let _ = sim.rhs(0.0, &x0, &mut dx);
    }
    if pick == 0 {
        let _ = Campaign::read_with(path, &overrides);
    }
});
