//! Any text given as the `[campaign]` section of a campaign scene gives a campaign or a
//! `FileError`, never a panic. The fuzzed text follows the small scene `fuzz/scenes/wing.toml`
//! (its model file `wing.model.toml` beside it in a temporary folder) and is read by
//! `Campaign::parse`, which `Campaign::read_with` (`satsim campaign`) calls on the file's
//! text. A campaign that reads gives its `runs.csv` header, its scene digest, the draws of
//! its first run and that run's scene text, read back as a scene whose simulation is built
//! (or says why not), as `satsim campaign` does for each run.
//!
//! The fuzzed text comes after the scene's last table, so it cannot set the top-level
//! `model` or `initial` to a path (which could name `/dev/zero`).
#![no_main]
use libfuzzer_sys::fuzz_target;
use satsim_tools::campaign::Campaign;
use satsim_tools::scene::Scene;
use std::path::PathBuf;
use std::sync::OnceLock;

const SCENE: &str = include_str!("../scenes/wing.toml");
const MODEL: &str = include_str!("../scenes/wing.model.toml");

/// The scene file's path (its model file written beside it, once).
fn path() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("satsim-fuzz-campaign-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("wing.model.toml"), MODEL).unwrap();
        dir.join("wing.toml")
    })
}

fuzz_target!(|bytes: &[u8]| {
    let Ok(section) = std::str::from_utf8(bytes) else {
        return;
    };
    let path = path();
    let Ok(campaign) = Campaign::parse(&format!("{SCENE}\n{section}"), path) else {
        return;
    };
    let _ = campaign.header();
    let _ = campaign.scene_digest();
    let values = campaign.draw(0);
    let text = campaign.scene_text(&values);
    if let Ok(scene) = Scene::parse(&text, path) {
        let _ = scene.simulation();
    }
});
