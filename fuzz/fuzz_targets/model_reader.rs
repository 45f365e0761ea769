//! Any text given as a model file must give a model or a `FileError`, never a panic; and a
//! model that builds must run every algorithm to a result or a `DynamicsError`.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|bytes: &[u8]| {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    let Ok((model, _)) = satsim_tree::parse_model(text, Path::new("fuzz.toml")) else {
        return;
    };
    if model.n_bodies() > 64 {
        return;
    }
    let mut data = satsim_tree::Data::new(&model);
    let q = model.neutral();
    let v = vec![0.1; model.nv()];
    let tau = vec![0.1; model.nv()];
    let _ = satsim_tree::crba(&model, &mut data, &q);
    let _ = satsim_tree::rnea(&model, &mut data, &q, &v, &tau, None);
    let _ = satsim_tree::aba::aba(&model, &mut data, &q, &v, &tau, None);
    let _ = satsim_tree::cholesky::crba_cholesky(&model, &mut data, &q, &v, &tau, None);
    let _ = satsim_tree::kinetic_energy(&model, &mut data, &q, &v);
});
