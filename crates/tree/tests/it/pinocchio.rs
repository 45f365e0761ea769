//! Every Pinocchio fixture case (`tests/fixtures/pinocchio/NAME.{model.toml,state.json}`),
//! read through `satsim_tree::io`, against `NAME.expected.json`: mass matrix, bias, ABA
//! acceleration, CRBA + Cholesky acceleration and kinetic energy, each entry within
//! `TOL * max(1, max |expected|)` of that quantity (see the fixtures' README), `TOL = 1e-13`.
//!
//! Measured (2026-11, Pinocchio 4.1.0 fixtures): the worst entry over all seven cases is
//! 1.9e-15 of its scale (`tree_free`, ABA acceleration); most are below 1e-15. `TOL` leaves a
//! factor of 50 for other compilers and instruction sets (FMA), and is tight enough that a
//! wrong sign or a dropped term anywhere (errors of order 1e-3 and more) fails.

use satsim_tree::aba::aba;
use satsim_tree::cholesky::crba_cholesky;
use satsim_tree::io::{read_model, read_state};
use satsim_tree::{Data, ForwardDynamics, Input, Method, bias, crba, kinetic_energy};
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Expected {
    dof: usize,
    mass_matrix: Vec<Vec<f64>>,
    bias: Vec<f64>,
    acceleration: Vec<f64>,
    kinetic_energy: f64,
}

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/pinocchio")
}

fn cases() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(fixtures())
        .expect("fixture directory")
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            name.strip_suffix(".expected.json").map(str::to_owned)
        })
        .collect();
    names.sort();
    names
}

/// Relative tolerance of every comparison (see the module documentation).
const TOL: f64 = 1e-13;

/// Asserts `|got - exp| <= TOL * max(1, max |exp|)` entry by entry.
fn check(case: &str, what: &str, got: &[f64], exp: &[f64]) {
    assert_eq!(got.len(), exp.len(), "{case}: {what}: length");
    let scale = exp.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (i, (g, e)) in got.iter().zip(exp).enumerate() {
        assert!(
            (g - e).abs() <= TOL * scale,
            "{case}: {what}[{i}]: got {g:e}, expected {e:e} (scale {scale:e})"
        );
    }
}

#[test]
fn fixture_cases_are_present() {
    let names = cases();
    for required in [
        "chain_fixed",
        "satellite",
        "satellite_rotated",
        "single_body_free",
        "tree_free",
        "tree_free_big",
        "wheel",
    ] {
        assert!(
            names.iter().any(|n| n == required),
            "missing case {required}"
        );
    }
}

#[test]
fn against_pinocchio() {
    for case in cases() {
        let dir = fixtures();
        let model = read_model(dir.join(format!("{case}.model.toml")))
            .unwrap_or_else(|e| panic!("{case}: {e}"));
        let state = read_state(dir.join(format!("{case}.state.json")), &model)
            .unwrap_or_else(|e| panic!("{case}: {e}"));
        let text = std::fs::read_to_string(dir.join(format!("{case}.expected.json"))).unwrap();
        let exp: Expected = serde_json::from_str(&text).unwrap();
        let n = model.nv();
        assert_eq!(exp.dof, n, "{case}: dof");

        let mut data = Data::new(&model);
        let m = crba(&model, &mut data, &state.q).unwrap();
        let m_rows: Vec<f64> = (0..n)
            .flat_map(|i| (0..n).map(move |j| m[(i, j)]))
            .collect();
        let exp_rows: Vec<f64> = exp.mass_matrix.iter().flatten().copied().collect();
        check(&case, "mass_matrix", &m_rows, &exp_rows);

        let b = bias(&model, &mut data, &state.q, &state.v, None).unwrap();
        check(&case, "bias", b.as_slice(), &exp.bias);

        let a = aba(&model, &mut data, &state.q, &state.v, &state.tau, None).unwrap();
        check(&case, "aba acceleration", a.as_slice(), &exp.acceleration);

        let a = crba_cholesky(&model, &mut data, &state.q, &state.v, &state.tau, None).unwrap();
        check(
            &case,
            "crba_cholesky acceleration",
            a.as_slice(),
            &exp.acceleration,
        );

        // The entry, both methods (bit for bit the functions above: checked here too).
        let input = Input::new(&state.q, &state.v, &state.tau);
        for (method, what) in [
            (Method::Aba, "ForwardDynamics (ABA) acceleration"),
            (Method::CrbaCholesky, "ForwardDynamics (CRBA) acceleration"),
        ] {
            let mut ddq = vec![0.0; n];
            ForwardDynamics::new(&model)
                .with_method(method)
                .solve(&model, &mut data, input, &mut ddq)
                .unwrap();
            check(&case, what, &ddq, &exp.acceleration);
        }

        let ke = kinetic_energy(&model, &mut data, &state.q, &state.v).unwrap();
        check(&case, "kinetic_energy", &[ke], &[exp.kinetic_energy]);
    }
}
