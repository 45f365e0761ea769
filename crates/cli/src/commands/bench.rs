//! `satsim bench --model MODEL.toml [--state STATE.json] [--calls N]` (contract section 5):
//! the per-call cost of `crba`, `rnea`, `aba` and `crba_cholesky` on one model and state,
//! and of `aba_unrolled` ([`UnrolledAba`], the same forward dynamics written out for the
//! preprint's layout) where the model has that layout (the key is absent otherwise).
//!
//! For each algorithm: a warm-up, then [`REPETITIONS`] repetitions of `calls` calls; each
//! repetition gives the mean time per call, and the figure printed is their median. Without
//! `--calls`, a short calibration picks a round number of calls that makes the whole
//! benchmark take about [`TARGET_SECONDS`].

use super::{CliError, Output, at_least_one, to_json};
use satsim_satellite::kernel::UnrolledAba;
use satsim_tree::aba::aba;
use satsim_tree::cholesky::crba_cholesky;
use satsim_tree::io::{State, read_state};
use satsim_tree::{Data, Model, crba, rnea};
use serde::Serialize;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// The flags of `satsim bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model file (TOML, cli-contract section 1)
    #[arg(long, value_name = "MODEL.toml")]
    pub model: PathBuf,
    /// The state to time the algorithms at (JSON, cli-contract section 2) [default: zero
    /// angles, small non-zero rates, no torque]
    #[arg(long, value_name = "STATE.json")]
    pub state: Option<PathBuf>,
    /// Calls per timed repetition (7 repetitions, the median printed) [default: calibrated
    /// so that the whole benchmark takes about 1.5 s]
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    pub calls: Option<usize>,
}

/// The printed object.
#[derive(Serialize)]
struct Json {
    dof: usize,
    calls: usize,
    repetitions: usize,
    ns_per_call: NsPerCall,
}

/// Median ns per call of each algorithm.
#[derive(Serialize)]
struct NsPerCall {
    crba: f64,
    rnea: f64,
    aba: f64,
    crba_cholesky: f64,
    /// Only for models with the layout of [`UnrolledAba`].
    #[serde(skip_serializing_if = "Option::is_none")]
    aba_unrolled: Option<f64>,
}

/// One timed algorithm: a call on the workspace.
type Timed<'a> = Box<dyn FnMut(&mut Data) + 'a>;

/// Timed repetitions per algorithm.
pub const REPETITIONS: usize = 7;

/// Approximate wall time of a benchmark without `--calls` (s).
pub const TARGET_SECONDS: f64 = 1.5;

/// The default state: neutral configuration (identity attitude, zero angles) with small
/// non-zero velocities and no torque.
pub fn default_state(model: &Model) -> State {
    let mut s = State::rest(model);
    let nb = model.base_nv();
    if nb == 6 {
        s.v[..6].copy_from_slice(&[0.01, -0.02, 0.015, 0.001, 0.002, -0.001]);
    }
    for (k, v) in s.v[nb..].iter_mut().enumerate() {
        *v = 0.01 * (1.0 + (k % 3) as f64) * if k % 2 == 0 { 1.0 } else { -1.0 };
    }
    s
}

/// Runs the command.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let model_path = &args.model;
    let calls = args.calls;
    let model = super::read_rigid_model(model_path, "bench")?;
    let state_path = args.state.as_ref();
    let state = match state_path {
        Some(p) => read_state(p, &model)?,
        None => default_state(&model),
    };
    let where_ = state_path.unwrap_or(model_path).display();
    let n = model.nv();
    let mut data = Data::new(&model);
    // RNEA's accelerations: small, non-zero.
    let acc: Vec<f64> = (0..n).map(|i| 1e-3 * (1.0 + i as f64)).collect();
    let (q, v, tau) = (&state.q, &state.v, &state.tau);

    // Check every algorithm once: the timed loops ignore results.
    let err = |e: satsim_tree::DynamicsError| CliError::Other(format!("{where_}: {e}"));
    // A state whose dynamics overflow is refused: the timings would be of NaN arithmetic.
    let finite = |what: &str, x: &[f64]| {
        if x.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(CliError::Other(format!(
                "{where_}: the {what} of this state is not finite (the computation overflows)"
            )))
        }
    };
    let m: Vec<f64> = crba(&model, &mut data, q)
        .map_err(err)?
        .iter()
        .copied()
        .collect();
    finite("mass matrix (crba)", &m)?;
    let b = rnea(&model, &mut data, q, v, &acc, None)
        .map_err(err)?
        .as_slice()
        .to_vec();
    finite("inverse dynamics (rnea)", &b)?;
    let a = aba(&model, &mut data, q, v, tau, None)
        .map_err(err)?
        .as_slice()
        .to_vec();
    finite("forward dynamics (aba)", &a)?;
    let c = crba_cholesky(&model, &mut data, q, v, tau, None)
        .map_err(err)?
        .as_slice()
        .to_vec();
    finite("forward dynamics (crba_cholesky)", &c)?;
    let unrolled = UnrolledAba::new(&model);
    if let Some(k) = &unrolled {
        let u = k
            .aba(&mut data, q, v, tau)
            .map_err(err)?
            .as_slice()
            .to_vec();
        finite("forward dynamics (aba_unrolled)", &u)?;
    }

    let mut algorithms: Vec<(&str, Timed<'_>)> = vec![
        (
            "crba",
            Box::new(|d: &mut Data| {
                let _ = black_box(crba(black_box(&model), d, black_box(q)).is_ok());
            }),
        ),
        (
            "rnea",
            Box::new(|d: &mut Data| {
                let _ = black_box(
                    rnea(
                        black_box(&model),
                        d,
                        black_box(q),
                        black_box(v),
                        black_box(&acc),
                        None,
                    )
                    .is_ok(),
                );
            }),
        ),
        (
            "aba",
            Box::new(|d: &mut Data| {
                let _ = black_box(
                    aba(
                        black_box(&model),
                        d,
                        black_box(q),
                        black_box(v),
                        black_box(tau),
                        None,
                    )
                    .is_ok(),
                );
            }),
        ),
        (
            "crba_cholesky",
            Box::new(|d: &mut Data| {
                let _ = black_box(
                    crba_cholesky(
                        black_box(&model),
                        d,
                        black_box(q),
                        black_box(v),
                        black_box(tau),
                        None,
                    )
                    .is_ok(),
                );
            }),
        ),
    ];
    if let Some(k) = &unrolled {
        algorithms.push((
            "aba_unrolled",
            Box::new(move |d: &mut Data| {
                let _ = black_box(k.aba(d, black_box(q), black_box(v), black_box(tau)).is_ok());
            }),
        ));
    }

    let calls = match calls {
        Some(c) => c,
        None => {
            // Calibrate: the cost of one call of each, from ~20 ms of calls each.
            let mut total = 0.0;
            for (_, f) in algorithms.iter_mut() {
                total += mean_ns(f, &mut data, Duration::from_millis(20));
            }
            // Warm-up of one repetition plus REPETITIONS timed ones, for all of them.
            let per_call_all = total * 1e-9 * (REPETITIONS + 1) as f64;
            round_down((TARGET_SECONDS / per_call_all).max(100.0) as usize)
        }
    };

    // Medians in the order of `algorithms`: crba, rnea, aba, crba_cholesky[, aba_unrolled].
    let mut medians = vec![0.0; algorithms.len()];
    for ((_, f), median) in algorithms.iter_mut().zip(&mut medians) {
        for _ in 0..calls {
            f(&mut data);
        }
        let mut means: Vec<f64> = (0..REPETITIONS)
            .map(|_| {
                let t = Instant::now();
                for _ in 0..calls {
                    f(&mut data);
                }
                t.elapsed().as_nanos() as f64 / calls as f64
            })
            .collect();
        means.sort_by(f64::total_cmp);
        *median = means[REPETITIONS / 2];
    }
    to_json(&Json {
        dof: n,
        calls,
        repetitions: REPETITIONS,
        ns_per_call: NsPerCall {
            crba: medians[0],
            rnea: medians[1],
            aba: medians[2],
            crba_cholesky: medians[3],
            aba_unrolled: medians.get(4).copied(),
        },
    })
}

/// Mean ns per call of `f`, calling it for about `budget`.
fn mean_ns(f: &mut Timed<'_>, data: &mut Data, budget: Duration) -> f64 {
    let start = Instant::now();
    let mut calls = 0u64;
    while start.elapsed() < budget {
        for _ in 0..64 {
            f(data);
        }
        calls += 64;
    }
    start.elapsed().as_nanos() as f64 / calls as f64
}

/// The largest of 1, 2, 5 times a power of ten not above `n` (at least 1).
fn round_down(n: usize) -> usize {
    let mut p = 1usize;
    while p * 10 <= n {
        p *= 10;
    }
    [5 * p, 2 * p, p].into_iter().find(|&c| c <= n).unwrap_or(1)
}

#[cfg(test)]
mod tests {
    use super::round_down;

    #[test]
    fn round_numbers() {
        assert_eq!(round_down(1), 1);
        assert_eq!(round_down(7), 5);
        assert_eq!(round_down(199_999), 100_000);
        assert_eq!(round_down(250_000), 200_000);
        assert_eq!(round_down(999), 500);
    }
}
