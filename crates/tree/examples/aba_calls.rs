//! 100 000 forward-dynamics calls on the preprint satellite with the peer orbit's wheels, by
//! the generic ABA called directly (`generic`) or through the entry, [`ForwardDynamics`]
//! (`entry`), without external forces or (second argument `forces`) with a wrench on every
//! body: the program to count instructions per call with callgrind (`valgrind
//! --tool=callgrind target/release/examples/aba_calls entry`, then `callgrind_annotate
//! --inclusive=yes`). `cargo run --release -p satsim-tree --example aba_calls --
//! generic|entry [forces]`. (The preprint layout's unrolled kernel is `satsim-satellite`'s.)

use satsim_tree::*;
use std::hint::black_box;
use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let which = std::env::args().nth(1).unwrap_or_else(|| "entry".into());
    let forces = std::env::args().nth(2).is_some_and(|a| a == "forces");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/satellite.toml");
    let mut b = read_model(&path)?.to_builder();
    samples::push_wheels(&mut b, "bus");
    let model = b.build()?;
    let fd = ForwardDynamics::new(&model);
    let mut ddq = vec![0.0; model.nv()];
    let mut data = Data::new(&model);
    let mut q = model.neutral();
    q[7..12].copy_from_slice(&[0.1, 0.2, 0.3, 1.2, -1.0]);
    let mut v: Vec<f64> = (0..model.nv())
        .map(|k| 0.01 * (1.0 + k as f64).sin())
        .collect();
    let tau: Vec<f64> = (0..model.nv())
        .map(|k| 0.1 * (2.0 + k as f64).cos())
        .collect();
    // Gravity-gradient-like wrenches: small, different on every body.
    let wrenches: Vec<spatial::Force> = (0..model.n_bodies())
        .map(|i| {
            let x = i as f64;
            spatial::Force::new(
                spatial::Vec3::new(x.sin(), x.cos(), 0.5) * 1e-4,
                spatial::Vec3::new(0.3, -x.sin(), x.cos()) * 1e-3,
            )
        })
        .collect();
    let fext = forces.then_some(wrenches.as_slice());
    let mut sum = 0.0;
    for _ in 0..100_000 {
        let x = match which.as_str() {
            "generic" => aba::aba(&model, &mut data, black_box(&q), &v, black_box(&tau), fext)?[10],
            _ => {
                let input = Input::new(black_box(&q), &v, black_box(&tau)).fext(fext);
                fd.solve(&model, &mut data, input, &mut ddq)?;
                ddq[10]
            }
        };
        sum += x;
        v[0] += 0.0 * x;
    }
    println!("{which}{}: {sum}", if forces { " with forces" } else { "" });
    Ok(())
}
