//! One timed run of a scene: the states at its output times ([`Trajectory`], [`run`]).

use crate::scene::Scene;
use satsim_integrate::{Options, Output, Stats};
use std::ops::ControlFlow;
use std::time::Instant;

/// The states at the saved times of one run.
#[derive(Clone, Debug)]
pub struct Trajectory {
    /// Saved times (the scene's output times).
    pub times: Vec<f64>,
    /// The state at each saved time.
    pub states: Vec<Vec<f64>>,
    /// The integrator's counters.
    pub stats: Stats,
    /// Wall time of the integration (s).
    pub seconds: f64,
}

/// Integrates `scene` once with `options`, saving the state at the scene's output times.
/// Fails when the integrator fails or the run stops before the scene's duration.
pub fn run(scene: &Scene, options: &Options) -> Result<Trajectory, String> {
    let mut sim = scene.simulation().map_err(|e| e.to_string())?;
    let (t0, t_end) = (sim.t0(), sim.t0() + scene.duration);
    let x0 = sim.x0().to_vec();
    let n_out = (scene.duration / scene.every).ceil() as usize + 2;
    let mut times = Vec::with_capacity(n_out);
    let mut states = Vec::with_capacity(n_out);
    let started = Instant::now();
    let stats = satsim_integrate::integrate(
        &mut sim,
        options,
        t0,
        &x0,
        t_end,
        &Output::Interval(scene.every),
        |t, x| {
            times.push(t);
            states.push(x.to_vec());
            ControlFlow::Continue(())
        },
    )
    .map_err(|e| e.to_string())?;
    let seconds = started.elapsed().as_secs_f64();
    if stats.t_final < t_end {
        return Err(format!(
            "stopped at t = {} s ({:?})",
            stats.t_final, stats.stop
        ));
    }
    Ok(Trajectory {
        times,
        states,
        stats,
        seconds,
    })
}
