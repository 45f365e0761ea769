//! The unrolled kernel over lanes of runs against one run at a time: the preprint satellite
//! with its three wheels, four (eight) runs with their own panel masses and states, each
//! batch solved by the `f64` kernel per run and by the kernel over `F64x<2>`, `F64x<4>`
//! and `F64x<8>` lanes, both capped to each instruction set the CPU has (the baseline
//! target's SSE2, AVX2, AVX-512: [`Instructions`]; lanes have the instances of their own
//! register size only, so a cap without one is marked with the instance that ran), with hinge angles anywhere
//! (±3 rad) and small (±0.7 rad). Throughput per run is what a campaign gains (its runs are
//! independent); `cargo bench -p satsim-satellite --bench lanes [-- ROUNDS]`. The results are equal bit for
//! bit (checked here before timing, and by the kernel's tests). Not criterion: on a shared
//! machine whose speed drifts, the ways alternate in short rounds and the per-round
//! ratios are what is reported.

use satsim_satellite::kernel::{Instructions, Locks, UnrolledAba};
use satsim_tree::real::{F64x, Real};
use satsim_tree::samples::{SplitMix, push_wheels, random_q};
use satsim_tree::{Model, read_model};
use std::hint::black_box;
use std::time::Instant;

/// `n` models of the satellite with wheels, panel 2 and 3 masses dispersed by ±10 %.
fn models(n: usize) -> Vec<Model> {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/satellite.toml");
    let nominal = read_model(&path).expect("the example model");
    let mut rng = SplitMix(3);
    (0..n)
        .map(|_| {
            let mut b = nominal.to_builder();
            for body in [4, 5] {
                let scale = rng.range(0.9, 1.1);
                b.bodies_mut()[body].mass *= scale;
                b.bodies_mut()[body].inertia *= scale;
            }
            push_wheels(&mut b, "bus");
            b.build().expect("a valid model")
        })
        .collect()
}

type Run = (Vec<f64>, Vec<f64>, Vec<f64>);

/// A random state per model: hinge angles in `[-3, 3)` rad scaled by `hinges / 3` (so
/// `hinges = 3.0` leaves `random_q`'s), rates and torques as they come.
fn states(models: &[Model], hinges: f64) -> Vec<Run> {
    let mut rng = SplitMix(17);
    models
        .iter()
        .map(|m| {
            let mut q = random_q(m, &mut rng, 1.0);
            for x in &mut q[m.base_nq()..] {
                *x *= hinges / 3.0;
            }
            let v = (0..m.nv()).map(|_| rng.range(-0.5, 0.5)).collect();
            let tau = (0..m.nv()).map(|_| rng.range(-1.0, 1.0)).collect();
            (q, v, tau)
        })
        .collect()
}

fn pack<const N: usize>(runs: &[Run], part: fn(&Run) -> &Vec<f64>) -> Vec<F64x<N>> {
    (0..part(&runs[0]).len())
        .map(|i| F64x(std::array::from_fn(|k| part(&runs[k])[i])))
        .collect()
}

/// Nanoseconds per run of `f` (which solves `runs` runs), over `iters` calls.
fn per_run(iters: u32, runs: usize, mut f: impl FnMut()) -> f64 {
    let t = Instant::now();
    for _ in 0..iters {
        f();
    }
    t.elapsed().as_nanos() as f64 / f64::from(iters) / runs as f64
}

fn median(mut xs: Vec<f64>) -> f64 {
    xs.sort_by(f64::total_cmp);
    xs[xs.len() / 2]
}

/// `N` runs with hinge angles within `±hinges` rad: one at a time, then in lanes on each of
/// `sets` (instruction sets). The ways alternate in short rounds (this machine's speed drifts
/// by tens of per cent from one second to the next); the medians of the per-round figures
/// and ratios.
fn lanes<const N: usize>(rounds: usize, hinges: f64, sets: &[Instructions]) {
    let models = models(N);
    let kernels: Vec<UnrolledAba> = models
        .iter()
        .map(|m| UnrolledAba::new(m).unwrap())
        .collect();
    let batch = UnrolledAba::<F64x<N>>::gather(std::array::from_fn(|k| &kernels[k])).unwrap();
    let batches: Vec<UnrolledAba<F64x<N>>> = sets
        .iter()
        .map(|&i| batch.clone().instructions(i))
        .collect();
    let runs = states(&models, hinges);
    let nv = models[0].nv();
    let (q, v, tau) = (
        pack::<N>(&runs, |r| &r.0),
        pack::<N>(&runs, |r| &r.1),
        pack::<N>(&runs, |r| &r.2),
    );
    let mut ddq = vec![F64x::<N>::splat(0.0); nv];
    let mut one = vec![0.0; nv];
    for lanes in &batches {
        lanes
            .aba_hybrid_with_forces_into(&q, &v, &tau, None, Locks::NONE, &mut ddq)
            .unwrap();
        for (k, (kernel, (q, v, tau))) in kernels.iter().zip(&runs).enumerate() {
            kernel
                .aba_hybrid_with_forces_into(q, v, tau, None, Locks::NONE, &mut one)
                .unwrap();
            assert!(
                ddq.iter()
                    .zip(&one)
                    .all(|(l, x)| l.lane(k).to_bits() == x.to_bits())
            );
        }
    }
    // One at a time on each instruction set (the first, the baseline's, is the reference).
    let singles: Vec<Vec<UnrolledAba>> = sets
        .iter()
        .map(|&i| kernels.iter().map(|k| k.clone().instructions(i)).collect())
        .collect();
    let iters = (200_000 / N) as u32;
    let mut figures = vec![vec![]; 2 * sets.len()];
    for _ in 0..rounds {
        for (f, kernels) in figures.iter_mut().zip(&singles) {
            f.push(per_run(iters, N, || {
                for (kernel, (q, v, tau)) in kernels.iter().zip(&runs) {
                    kernel
                        .aba_hybrid_with_forces_into(
                            black_box(q),
                            v,
                            tau,
                            None,
                            Locks::NONE,
                            &mut one,
                        )
                        .unwrap();
                    black_box(&one);
                }
            }));
        }
        for (f, lanes) in figures[sets.len()..].iter_mut().zip(&batches) {
            f.push(per_run(iters, N, || {
                lanes
                    .aba_hybrid_with_forces_into(
                        black_box(&q),
                        &v,
                        &tau,
                        None,
                        Locks::NONE,
                        &mut ddq,
                    )
                    .unwrap();
                black_box(&ddq);
            }));
        }
    }
    let ratio = |i: usize| {
        median(
            figures[0]
                .iter()
                .zip(&figures[i])
                .map(|(a, b)| a / b)
                .collect(),
        )
    };
    let mut line = format!(
        "{N} runs, ±{hinges} rad | {:.0}",
        median(figures[0].clone())
    );
    for (i, f) in figures.iter().enumerate().skip(1) {
        // A width has the instances of its own register size only (`UnrolledAba::instance`):
        // under a cap it has no instance for, the lanes run on a narrower one, named.
        let on = match i.checked_sub(sets.len()) {
            Some(j) if batches[j].instance() != sets[j] => format!(", {}", batches[j].instance()),
            _ => String::new(),
        };
        line += &format!(" | {:.0} ({:.2}x{on})", median(f.clone()), ratio(i));
    }
    println!("{line}");
}

fn main() {
    // `cargo bench` passes `--bench`; any other argument is the number of rounds.
    let rounds = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(15);
    let widest = Instructions::detected();
    let sets: Vec<Instructions> = [
        Instructions::Baseline,
        Instructions::Avx2,
        Instructions::Avx512,
    ]
    .into_iter()
    .filter(|&i| i <= widest)
    .collect();
    println!(
        "ns per run of the kernel (medians of {rounds} alternating rounds; this CPU's widest \
         instructions: {widest:?})"
    );
    let head: String = sets
        .iter()
        .skip(1)
        .map(|i| format!(" | one at a time, {i:?} (speed-up)"))
        .chain(sets.iter().map(|i| format!(" | lanes, {i:?} (speed-up)")))
        .collect();
    println!("runs, hinge angles | one at a time, Baseline{head}");
    // Hinge angles anywhere (±3 rad: most beyond π/4, where `sin_cos` reduces its argument)
    // and small (±0.7 rad, all within π/4, as typical of a campaign).
    for hinges in [3.0, 0.7] {
        lanes::<2>(rounds, hinges, &sets);
        lanes::<4>(rounds, hinges, &sets);
        lanes::<8>(rounds, hinges, &sets);
    }
}
