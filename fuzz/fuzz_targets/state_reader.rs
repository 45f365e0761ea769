//! Any text given as a state file for the preprint satellite gives a state or a `FileError`,
//! never a panic; a state that loads runs ABA to a result or a `DynamicsError`.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;
use std::sync::OnceLock;

static MODEL: OnceLock<satsim_tree::Model> = OnceLock::new();

fuzz_target!(|bytes: &[u8]| {
    let model = MODEL.get_or_init(|| {
        satsim_tree::parse_model(
            include_str!("../../examples/satellite.toml"),
            Path::new("satellite.toml"),
        )
        .expect("the example model loads")
        .0
    });
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    let Ok(state) = satsim_tree::parse_state(text, Path::new("fuzz.json"), model) else {
        return;
    };
    let mut data = satsim_tree::Data::new(model);
    let _ = satsim_tree::aba::aba(model, &mut data, &state.q, &state.v, &state.tau, None);
});
