//! Per-call cost of the engine's algorithms: the preprint satellite (11 DOF; with the peer
//! orbit's three wheels, 14 DOF) and chains and binary trees of 10, 100 and 1000 bodies;
//! `forward_dynamics`: ABA through the entry, [`ForwardDynamics::solve`] (the same call plus
//! the copy into the caller's `q̈`). The preprint layout's unrolled kernel is
//! `satsim-satellite`'s (`satsim bench` times it as `aba_unrolled`).
//! `cargo bench -p satsim-tree --bench algorithms`.
//! Results and the scaling slopes are in docs/src/engineering/algorithms.md.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use satsim_tree::aba::aba;
use satsim_tree::cholesky::crba_cholesky;
use satsim_tree::samples::{binary_tree, chain};
use satsim_tree::*;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

fn satellite() -> Model {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/satellite.toml");
    read_model(&path).expect("examples/satellite.toml loads")
}

/// The preprint satellite with the peer orbit's three reaction wheels on the bus
/// (benches/peers/orbit.toml), as `satsim-satellite` adds them: 2 kg rotors about x, y, z at
/// 0.3 m, axial inertia 0.1 kg m².
fn satellite_with_wheels() -> Model {
    let mut b = satellite().to_builder();
    for (k, name) in ["x", "y", "z"].into_iter().enumerate() {
        let axis = spatial::Vec3::ith(k, 1.0);
        let aat = axis * axis.transpose();
        let inertia = aat * 0.1 + (spatial::Mat3::identity() - aat) * 0.05;
        b.push_body(Body::new(name, 2.0, inertia));
        b.push_hinge(Hinge::revolute(name, "bus", name, axis).at(axis * 0.3));
    }
    b.build().expect("the satellite with wheels is valid")
}

fn bench_model(c: &mut Criterion, label: &str, model: &Model) {
    let mut data = Data::new(model);
    let mut q = model.neutral();
    for (k, x) in q[model.base_nq()..].iter_mut().enumerate() {
        *x = 0.1 + 0.01 * k as f64;
    }
    let v: Vec<f64> = (0..model.nv())
        .map(|k| 0.01 * (1.0 + k as f64).sin())
        .collect();
    let tau: Vec<f64> = (0..model.nv())
        .map(|k| 0.1 * (2.0 + k as f64).cos())
        .collect();
    let mut group = c.benchmark_group(label);
    if model.nv() > 500 {
        group.sample_size(10);
    }
    group.bench_function(BenchmarkId::new("crba", model.nv()), |b| {
        b.iter(|| {
            crba(model, &mut data, black_box(&q)).unwrap();
        })
    });
    group.bench_function(BenchmarkId::new("rnea", model.nv()), |b| {
        b.iter(|| {
            rnea(
                model,
                &mut data,
                black_box(&q),
                black_box(&v),
                black_box(&tau),
                None,
            )
            .unwrap();
        })
    });
    group.bench_function(BenchmarkId::new("aba", model.nv()), |b| {
        b.iter(|| {
            aba(
                model,
                &mut data,
                black_box(&q),
                black_box(&v),
                black_box(&tau),
                None,
            )
            .unwrap();
        })
    });
    // The entry: the same ABA, its result copied into the caller's vector.
    let fd = ForwardDynamics::new(model);
    let mut ddq = vec![0.0; model.nv()];
    group.bench_function(BenchmarkId::new("forward_dynamics", model.nv()), |b| {
        b.iter(|| {
            let input = Input::new(black_box(&q), black_box(&v), black_box(&tau));
            fd.solve(model, &mut data, input, &mut ddq).unwrap();
        })
    });
    // The same calls made a chain: each call's base rate depends on the previous call's last
    // acceleration (`+ 0 · q̈`, which the compiler must keep), so no call can start before
    // the one before it ends, as in a simulation (each RK4 stage needs the last). The
    // difference to `aba` is the time the processor overlapped independent calls: how much
    // of a call is its dependency chain (latency) rather than its instructions (throughput).
    group.bench_function(BenchmarkId::new("aba_dependent", model.nv()), |b| {
        let mut v = v.clone();
        let (v0, last) = (v[0], model.nv() - 1);
        b.iter(|| {
            let ddq = aba(model, &mut data, black_box(&q), &v, black_box(&tau), None).unwrap();
            v[0] = v0 + 0.0 * ddq[last];
        })
    });
    group.bench_function(BenchmarkId::new("crba_cholesky", model.nv()), |b| {
        b.iter(|| {
            crba_cholesky(
                model,
                &mut data,
                black_box(&q),
                black_box(&v),
                black_box(&tau),
                None,
            )
            .unwrap();
        })
    });
    group.finish();
}

fn algorithms(c: &mut Criterion) {
    bench_model(c, "satellite", &satellite());
    bench_model(c, "satellite_wheels", &satellite_with_wheels());
    for n in [10, 100, 1000] {
        bench_model(c, &format!("chain{n}"), &chain(n, BaseKind::Free));
        bench_model(c, &format!("binary{n}"), &binary_tree(n, BaseKind::Free));
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    targets = algorithms
}
criterion_main!(benches);
