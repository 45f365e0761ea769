//! Per-call cost of forward dynamics with flexible panels (issue 27's target: the modal model
//! at least 10x faster than a rigid chain of the same accuracy). Four models of the preprint
//! satellite (examples/satellite.toml):
//! - `rigid`: the file as is, through [`ForwardDynamics`] (ABA);
//! - `modal`: each panel half rigid (10 kg) and half a beam clamped at its inboard edge
//!   (`root = (0, −0.5, 0)`, along y, bending along z, L = 1 m, EI = 500 N m², ρA = 10 kg/m,
//!   3 modes, stiffening on): the flexible ABA, and the flexible CRBA + bias + dense Cholesky;
//! - `chain40`, `chain80`: each beam a chain of 40 (80) rigid segments with hinge springs (the discretisation
//!   of tests/it/flexible.rs, which gives the first two frequencies within 1 % at N = 40 after
//!   extrapolation), the next panel hinged at the last segment's tip: the rigid ABA.
//!
//! `cargo bench -p satsim-tree --bench flexible`; the numbers are in the theory page
//! "Flexible bodies", section "Cost".

use criterion::{Criterion, criterion_group, criterion_main};
use satsim_tree::flexible::{self, Beam, FlexData, FlexModel, Flexible, Modes};
use satsim_tree::llt::{llt_in_place, llt_solve_in_place};
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::*;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

const PANELS: [&str; 3] = ["panel1", "panel2", "panel3"];
/// The panel beams: length (m), `EI` (N m²), `ρA` (kg/m).
const L: f64 = 1.0;
const EI: f64 = 500.0;
const RHO_A: f64 = 10.0;

fn satellite() -> Model {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/satellite.toml");
    read_model(&path).expect("examples/satellite.toml loads")
}

/// The satellite with each panel's rigid part halved (the beam carries the other half).
fn halved_panels() -> ModelBuilder {
    let mut b = satellite().to_builder();
    for body in b.bodies_mut() {
        if PANELS.contains(&body.name.as_str()) {
            body.mass *= 0.5;
            body.inertia *= 0.5;
        }
    }
    b
}

fn modal() -> FlexModel {
    let flex: Vec<Flexible> = PANELS
        .iter()
        .map(|p| Flexible {
            body: p.to_string(),
            modes: Modes::Beam(Beam {
                root: Vec3::new(0.0, -0.5, 0.0),
                axis: Vec3::y(),
                bend: Vec3::z(),
                length: L,
                ei: EI,
                rho_a: RHO_A,
                modes: 3,
            }),
            damping: 0.0,
            stiffening: true,
        })
        .collect();
    FlexModel::build(halved_panels(), &flex).expect("the flexible satellite is valid")
}

/// Each beam as `n` rigid segments (a thin rod each, framed at its inboard hinge) from the
/// panel's root; the next panel's hinge moves to the last segment's tip.
fn chain(n: usize) -> Model {
    let mut b = halved_panels();
    let l = L / n as f64;
    let m = RHO_A * l;
    let j = m * l * l / 12.0;
    for p in PANELS {
        let mut prev = p.to_string();
        for s in 0..n {
            let name = format!("{p}_s{s}");
            b.push_body(
                Body::new(name.clone(), m, Mat3::from_diagonal(&Vec3::new(j, 0.0, j)))
                    .with_com(Vec3::new(0.0, 0.5 * l, 0.0)),
            );
            let at = if s == 0 {
                Vec3::new(0.0, -0.5, 0.0)
            } else {
                Vec3::new(0.0, l, 0.0)
            };
            b.push_hinge(
                Hinge::revolute(format!("{name}_h"), prev.clone(), name.clone(), Vec3::x()).at(at),
            );
            prev = name;
        }
        for h in b.hinges_mut() {
            if h.parent == p && PANELS.contains(&h.child.as_str()) {
                h.parent = prev.clone();
                h.at = Vec3::new(0.0, l, 0.0);
            }
        }
    }
    b.build().expect("the chain satellite is valid")
}

/// A state away from symmetry: hinge angles `0.1 + 0.01 k`, small rates and torques, the
/// elastic coordinates included.
fn state(nq: usize, nv: usize, base_nq: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut q = vec![0.0; nq];
    q[0] = 1.0;
    for (k, x) in q[base_nq..].iter_mut().enumerate() {
        *x = 0.1 + 0.01 * k as f64;
    }
    let v = (0..nv).map(|k| 0.01 * (1.0 + k as f64).sin()).collect();
    let tau = (0..nv).map(|k| 0.1 * (2.0 + k as f64).cos()).collect();
    (q, v, tau)
}

fn flexible(c: &mut Criterion) {
    let mut group = c.benchmark_group("flexible_satellite");

    let rigid = satellite();
    let (q, v, tau) = state(rigid.nq(), rigid.nv(), rigid.base_nq());
    let fd = ForwardDynamics::new(&rigid);
    let mut data = Data::new(&rigid);
    let mut ddq = vec![0.0; rigid.nv()];
    group.bench_function(format!("rigid_aba/{}", rigid.nv()), |b| {
        b.iter(|| {
            let input = Input::new(black_box(&q), black_box(&v), black_box(&tau));
            fd.solve(&rigid, &mut data, input, &mut ddq).unwrap();
        })
    });

    let model = modal();
    let (mut q, v, tau) = state(model.nq(), model.nv(), model.rigid().base_nq());
    // Small deflections (the linear model's range): η of a few mm·√kg.
    for x in &mut q[model.rigid().nq()..] {
        *x *= 0.01;
    }
    let mut data = FlexData::new(&model);
    group.bench_function(format!("modal_aba/{}", model.nv()), |b| {
        b.iter(|| {
            flexible::aba(
                &model,
                &mut data,
                black_box(&q),
                black_box(&v),
                black_box(&tau),
                None,
            )
            .unwrap();
        })
    });
    let mut rhs = nalgebra::DVector::zeros(model.nv());
    group.bench_function(format!("modal_crba_cholesky/{}", model.nv()), |b| {
        b.iter(|| {
            flexible::bias(&model, &mut data, black_box(&q), black_box(&v), None).unwrap();
            for (r, (t, b)) in rhs.iter_mut().zip(tau.iter().zip(data.bias.iter())) {
                *r = t - b;
            }
            flexible::crba(&model, &mut data, black_box(&q)).unwrap();
            llt_in_place(&mut data.mass_matrix).unwrap();
            llt_solve_in_place(&data.mass_matrix, &mut rhs);
        })
    });

    for n in [40, 80] {
        let chain = chain(n);
        let (q, v, tau) = state(chain.nq(), chain.nv(), chain.base_nq());
        let fd = ForwardDynamics::new(&chain);
        let mut data = Data::new(&chain);
        let mut ddq = vec![0.0; chain.nv()];
        group.bench_function(format!("chain{n}_aba/{}", chain.nv()), |b| {
            b.iter(|| {
                let input = Input::new(black_box(&q), black_box(&v), black_box(&tau));
                fd.solve(&chain, &mut data, input, &mut ddq).unwrap();
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    targets = flexible
}
criterion_main!(benches);
