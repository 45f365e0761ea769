//! A campaign's runs several per core ([`Simulation::run_lanes`]): each worker thread takes
//! the next runs from a shared queue, [`Simulation::lane_width`] at a time, their dynamics
//! solved together in SIMD lanes. Every run's record is bit for bit the one it has alone
//! ([`Campaign::run_one_until`]): a run whose drawn scene integrates with other options
//! than the nominal scene's, or whose scene cannot be built, is handled alone.

use super::{Campaign, Collect, RunRecord, catch_panic};
use satsim_integrate::{Method, Options, Output as Times, Stats};
use satsim_spacecraft::simulation::{LaneJob, LaneJobs, RunError, Simulation};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

/// Whether the campaign's runs go in lanes: fixed-step RK4, and the nominal scene's dynamics
/// are the kernel's that gathers into lanes.
pub(crate) fn applies(campaign: &Campaign) -> bool {
    campaign.nominal.options.method == Method::Rk4
        && campaign
            .nominal
            .simulation()
            .is_ok_and(|sim| sim.takes_lanes())
}

/// One worker: runs `todo[next..]` as the queue hands them out, each record to `emit`
/// (which says whether to go on), until the queue is empty, `stop` turns true or `emit`
/// says stop.
pub(crate) fn work(
    campaign: &Campaign,
    queue: &Queue<'_>,
    stop: &(dyn Fn() -> bool + Sync),
    emit: &mut dyn FnMut(RunRecord) -> bool,
) {
    let mut jobs = Jobs {
        campaign,
        options: campaign.nominal.options.clone(),
        queue,
        stop,
        emit,
        going: true,
        in_flight: Vec::new(),
    };
    let options = jobs.options.clone();
    let ran = catch_panic(|| {
        Simulation::run_lanes(&options, &mut jobs);
        Ok(())
    });
    if ran.is_err() {
        // A bug inside a batch: its runs still under way are run again one by one, each to
        // its own record (its own panic message included).
        for k in std::mem::take(&mut jobs.in_flight) {
            if let Some(r) = campaign.run_one_until(k, stop) {
                jobs.going &= (jobs.emit)(r);
            }
        }
    }
}

/// The runs to make, shared by the workers, and what they count.
pub(crate) struct Queue<'q> {
    /// The runs.
    pub todo: &'q [u64],
    /// The next to hand out.
    pub next: &'q AtomicUsize,
    /// Right-hand sides of the runs made in batches, and of those the ones solved in lanes.
    pub counts: &'q [AtomicU64; 2],
}

/// The queue as [`LaneJobs`].
struct Jobs<'c, 'e> {
    campaign: &'c Campaign,
    options: Options,
    queue: &'c Queue<'c>,
    stop: &'c (dyn Fn() -> bool + Sync),
    emit: &'e mut dyn FnMut(RunRecord) -> bool,
    going: bool,
    /// The runs handed out and not yet done.
    in_flight: Vec<u64>,
}

/// A run of a batch: its rows' reduction, its drawn values.
pub(crate) struct Sink<'c> {
    collect: Collect<'c>,
    values: Vec<f64>,
}

impl satsim_spacecraft::simulation::RowSink for Sink<'_> {
    type Error = String;
    fn row(&mut self, t: f64, row: &[f64]) -> Result<(), String> {
        self.collect.row(t, row)
    }
}

impl<'c> LaneJobs for Jobs<'c, '_> {
    type Sink = Sink<'c>;

    fn next(&mut self) -> Option<LaneJob<Sink<'c>>> {
        while self.going && !(self.stop)() {
            let q = self.queue;
            let &k = q.todo.get(q.next.fetch_add(1, Ordering::Relaxed))?;
            let values = self.campaign.draw(k);
            let prepared = catch_panic(|| self.campaign.prepare(k, &values));
            match prepared {
                Ok((scene, sim)) if scene.options == self.options => {
                    self.in_flight.push(k);
                    return Some(LaneJob {
                        t_end: sim.t0() + scene.duration,
                        output: Times::Interval(scene.every),
                        sim,
                        sink: Sink {
                            collect: Collect::new(self.campaign, k, self.stop),
                            values,
                        },
                    });
                }
                // Dispersed integrator options: this run alone.
                Ok(_) => {
                    if let Some(r) = self.campaign.run_one_until(k, self.stop) {
                        self.going &= (self.emit)(r);
                    }
                }
                Err(why) => self.going &= (self.emit)(RunRecord::failed(k, values, why)),
            }
        }
        None
    }

    fn done(&mut self, sim: Simulation, sink: Sink<'c>, result: Result<Stats, RunError<String>>) {
        let log = sim.run_log();
        let [rhs, in_lanes] = &self.queue.counts;
        rhs.fetch_add(log.rhs_evals(), Ordering::Relaxed);
        in_lanes.fetch_add(log.lane_rhs(), Ordering::Relaxed);
        let k = sink.collect.k;
        self.in_flight.retain(|&f| f != k);
        let mut sink = sink;
        sink.collect.take_peaks(&sim);
        if let Some(r) = sink.collect.record(sink.values, result) {
            self.going &= (self.emit)(r);
        }
    }
}
