//! [`Simulation::run_lanes`]: several runs of one scene on one core, their dynamics solved
//! together in the SIMD lanes of the preprint layout's unrolled kernel.
//!
//! The runs advance in lockstep ([`satsim_integrate::lanes`]: fixed-step RK4, each stage's
//! right-hand sides of all the runs of a batch at once). Each right-hand side is split where
//! the dynamics are solved (`rhs.rs`): every run's effects run on their own
//! ([`Simulation::rhs_forces`]), then one call of the kernel over lanes
//! ([`UnrolledAba::gather`]) solves all of them, then each run books its power
//! ([`Simulation::rhs_power`]). Lane `k` of the kernel computes exactly what run `k`'s own
//! kernel computes (`satsim-satellite`'s bit-for-bit test), so a run gives the same rows,
//! bit for bit, in a batch or alone.
//!
//! The lanes' kernel is taken only where every run of the stage takes it with the same
//! branches: the same lock mask (that the kernel accepts), wrenches on all or none, kernels
//! that gather (one layout). Otherwise, and where the lanes part ways at a pivot
//! ([`DynamicsError::LanesPart`](satsim_tree::DynamicsError::LanesPart)), each run solves
//! its own dynamics, as alone. A run whose step holds an event locates it alone (the
//! integrator's driver), and a finished run's place goes to the next run at once.

use super::Simulation;
use super::run::{RunError, Shared, SimCell, deliver, outcome};
use satsim_integrate::lanes::{Batch, Lane, LaneRun, Runs, StepEnd, integrate_lanes};
use satsim_integrate::{IntegrateError, Options, Output, Stats, SystemError};
use satsim_satellite::kernel::{Instructions, Locks, UnrolledAba};
use satsim_tree::real::F64x;
use satsim_tree::spatial::Force;
use std::cell::{Ref, RefCell, RefMut};
use std::ops::ControlFlow;
use std::rc::Rc;

/// Where a run of [`Simulation::run_lanes`] writes its rows.
pub trait RowSink {
    /// What a refused row is.
    type Error;
    /// An output row (see [`Simulation::columns`]), as [`Simulation::run`]'s sink gets it.
    fn row(&mut self, t: f64, row: &[f64]) -> Result<(), Self::Error>;
}

/// A run for [`Simulation::run_lanes`]: the simulation from its initial state to `t_end`,
/// rows at `output` into `sink`.
pub struct LaneJob<K> {
    /// The run's simulation.
    pub sim: Simulation,
    /// End time.
    pub t_end: f64,
    /// Output times.
    pub output: Output,
    /// Where its rows go.
    pub sink: K,
}

/// The runs of [`Simulation::run_lanes`]: where they come from and where they end.
pub trait LaneJobs {
    /// Where a run writes its rows.
    type Sink: RowSink;
    /// The next run, `None` when there is none left.
    fn next(&mut self) -> Option<LaneJob<Self::Sink>>;
    /// A run is over, with what [`Simulation::run`] would have returned for it. Runs end in
    /// any order.
    #[allow(clippy::type_complexity)]
    fn done(
        &mut self,
        sim: Simulation,
        sink: Self::Sink,
        result: Result<Stats, RunError<<Self::Sink as RowSink>::Error>>,
    );
}

impl Simulation {
    /// How many runs [`Simulation::run_lanes`] puts in one batch on this CPU: one vector
    /// register per value of the kernel, [`Instructions::lanes`] of the widest it has (8 on
    /// x86-64 with AVX-512, 4 with AVX2, else 2; `benches/lanes.rs` in `satsim-satellite`
    /// measures each), capped by `SATSIM_INSTRUCTIONS` ([`Instructions::ENV`]).
    pub fn lane_width() -> usize {
        Instructions::detected().lanes()
    }

    /// Whether this simulation's dynamics, now, go to a kernel that gathers into lanes
    /// (the preprint layout's unrolled kernel, rigid, with a lock mask it takes): what
    /// [`Simulation::run_lanes`] speeds up.
    pub fn takes_lanes(&self) -> bool {
        kernel_call(self).is_some()
    }

    /// Runs every job of `jobs`, [`Simulation::lane_width`] at a time with their dynamics in
    /// lanes (see the module documentation), each with `options`, and hands each outcome to
    /// [`LaneJobs::done`]: bit for bit what [`Simulation::run`] gives that run alone, its rows
    /// included. With an adaptive method the runs go one after the other.
    pub fn run_lanes<J: LaneJobs>(options: &Options, jobs: &mut J) {
        Self::run_lanes_with(options, Self::lane_width(), jobs)
    }

    /// [`Simulation::run_lanes`] with `width` runs per batch (2, 4 or 8; 1 runs them one
    /// after the other).
    pub fn run_lanes_with<J: LaneJobs>(options: &Options, width: usize, jobs: &mut J) {
        let mut runs = Adapter {
            jobs,
            options: options.clone(),
        };
        match width {
            0 | 1 => integrate_lanes(options, 1, &mut Lanes::<2>::default(), &mut runs),
            2 | 3 => integrate_lanes(options, 2, &mut Lanes::<2>::default(), &mut runs),
            4..=7 => integrate_lanes(options, 4, &mut Lanes::<4>::default(), &mut runs),
            _ => integrate_lanes(options, 8, &mut Lanes::<8>::default(), &mut runs),
        }
    }
}

/// A run of a batch: its simulation, shared by its system and its observer.
struct Running<K: RowSink> {
    sim: Simulation,
    sink: K,
    columns: Vec<String>,
    row: Vec<f64>,
    failure: Option<RunError<K::Error>>,
}

type Cell<K> = Rc<RefCell<Running<K>>>;
type Observer<'k> = Box<dyn FnMut(f64, &[f64]) -> ControlFlow<()> + 'k>;

impl<K: RowSink> SimCell for Cell<K> {
    fn sim(&self) -> Ref<'_, Simulation> {
        Ref::map(self.borrow(), |r| &r.sim)
    }
    fn sim_mut(&self) -> RefMut<'_, Simulation> {
        RefMut::map(self.borrow_mut(), |r| &mut r.sim)
    }
}

/// [`LaneJobs`] as the integrator's [`Runs`].
struct Adapter<'j, J> {
    jobs: &'j mut J,
    /// The runs' options (their method and step, for the message of a failed run).
    options: Options,
}

impl<'j, J: LaneJobs> Runs<Shared<Cell<J::Sink>>, Observer<'j>> for Adapter<'j, J>
where
    J::Sink: 'j,
{
    fn next(&mut self) -> Option<LaneRun<Shared<Cell<J::Sink>>, Observer<'j>>> {
        let mut job = self.jobs.next()?;
        // A simulation that has run starts again as `Simulation::run` does, or its job fails.
        while let Err(source) = job
            .sim
            .takes(&self.options)
            .and_then(|()| job.sim.restart())
        {
            let t = job.sim.t0;
            let e = RunError::Integrate(IntegrateError::System { t, source });
            self.jobs.done(job.sim, job.sink, Err(e));
            job = self.jobs.next()?;
        }
        let (t0, x0, columns) = (job.sim.t0, job.sim.x0.clone(), job.sim.columns());
        let cell = Rc::new(RefCell::new(Running {
            sim: job.sim,
            sink: job.sink,
            columns,
            row: Vec::new(),
            failure: None,
        }));
        let seen = Rc::clone(&cell);
        let observer: Observer<'j> = Box::new(move |t, x| {
            let mut r = seen.borrow_mut();
            let r = &mut *r;
            match deliver(&mut r.sim, &r.columns, &mut r.row, t, x, &mut |t, row| {
                r.sink.row(t, row)
            }) {
                Ok(()) => ControlFlow::Continue(()),
                Err(f) => {
                    r.failure = Some(f);
                    ControlFlow::Break(())
                }
            }
        });
        Some(LaneRun {
            system: Shared(cell),
            t0,
            x0,
            t_end: job.t_end,
            output: job.output,
            observer,
        })
    }

    fn done(
        &mut self,
        system: Shared<Cell<J::Sink>>,
        observer: Observer<'j>,
        result: Result<Stats, IntegrateError>,
    ) {
        drop(observer);
        let Ok(run) = Rc::try_unwrap(system.0) else {
            unreachable!("the observer, the cell's only other owner, is dropped")
        };
        let run = run.into_inner();
        let result = outcome(result, run.failure, &run.sim, &self.options);
        self.jobs.done(run.sim, run.sink, result);
    }
}

/// The batch's right-hand sides, the dynamics in `N` lanes: the gathered kernel of the runs
/// it last saw (by their models' serial numbers; `None` where they do not gather, so that
/// they are not tried again at every stage) and the lanes' inputs and outputs.
#[derive(Default)]
struct Lanes<const N: usize> {
    kernel: Option<(Option<UnrolledAba<F64x<N>>>, [u64; N])>,
    q: Vec<F64x<N>>,
    v: Vec<F64x<N>>,
    tau: Vec<F64x<N>>,
    fext: Vec<Force<F64x<N>>>,
    ddq: Vec<F64x<N>>,
}

/// A place's run, `(t, x)`, `dx` and result ([`Place::parts`]).
type Parts<'p, K> = (
    &'p Cell<K>,
    f64,
    &'p [f64],
    &'p mut [f64],
    &'p mut Result<(), SystemError>,
);

/// A right-hand side for [`Lanes::evaluate`]: a stage's lane, or a step's end
/// ([`Batch::step_ends`]).
trait Place<K: RowSink> {
    /// The run, `(t, x)`, where `dx` goes and the result; `None` for a place left empty.
    fn parts(&mut self) -> Option<Parts<'_, K>>;
}

impl<K: RowSink> Place<K> for Lane<'_, Shared<Cell<K>>> {
    #[inline(always)]
    fn parts(&mut self) -> Option<Parts<'_, K>> {
        Some((
            &self.system.0,
            self.t,
            self.x,
            &mut *self.dx,
            &mut self.result,
        ))
    }
}

/// A step's end whose event functions will evaluate the right-hand side there
/// ([`Simulation::evaluates_ahead`]): evaluated in lanes, into the run's kept slope.
struct Ending<'a, K: RowSink> {
    cell: Option<&'a Cell<K>>,
    t: f64,
    x: &'a [f64],
    dx: Vec<f64>,
    result: Result<(), SystemError>,
}

impl<K: RowSink> Place<K> for Ending<'_, K> {
    #[inline(always)]
    fn parts(&mut self) -> Option<Parts<'_, K>> {
        Some((self.cell?, self.t, self.x, &mut self.dx, &mut self.result))
    }
}

impl<const N: usize, K: RowSink> Batch<Shared<Cell<K>>> for Lanes<N> {
    fn rhs(&mut self, lanes: &mut [Lane<'_, Shared<Cell<K>>>]) {
        self.evaluate(lanes);
    }

    /// The right-hand sides that the runs' event functions are about to evaluate at their
    /// steps' ends (`ahead.rs`), evaluated here together: the dynamics in lanes where the
    /// event functions would have solved them one run at a time.
    fn step_ends(&mut self, ends: &mut [StepEnd<'_, Shared<Cell<K>>>]) {
        if ends.len() > N || ends.iter().filter(|e| e.events).count() < 2 {
            return;
        }
        let mut places: [Ending<'_, K>; N] = std::array::from_fn(|_| Ending {
            cell: None,
            t: 0.0,
            x: &[],
            dx: Vec::new(),
            result: Ok(()),
        });
        let mut count = 0;
        for (e, p) in ends.iter_mut().zip(&mut places) {
            let mut sim = e.system.0.sim_mut();
            if e.events && sim.evaluates_ahead(e.x) {
                p.dx = sim.take_ahead_slope();
                (p.cell, p.t, p.x) = (Some(&e.system.0), e.t, e.x);
                count += 1;
            }
        }
        if count < 2 {
            // One run alone: its event functions evaluate it, as without lanes.
            for p in places.iter_mut().filter(|p| p.cell.is_some()) {
                let dx = std::mem::take(&mut p.dx);
                p.cell.expect("a run").sim_mut().return_ahead_slope(dx);
            }
            return;
        }
        self.evaluate(&mut places);
        for p in places.iter_mut() {
            if let Some(cell) = p.cell {
                let result = std::mem::replace(&mut p.result, Ok(()));
                let dx = std::mem::take(&mut p.dx);
                cell.sim_mut().keep_ahead(p.t, p.x, dx, result);
            }
        }
    }
}

impl<const N: usize> Lanes<N> {
    /// Every place's right-hand side: each run's effects on their own, the dynamics of all
    /// of them by one call of the lanes' kernel where they take it alike ([`Self::solve`]),
    /// else each run's own; then each run's power.
    fn evaluate<K: RowSink, P: Place<K>>(&mut self, places: &mut [P]) {
        let mut kin = [false; N];
        // The places whose slope their event functions evaluated already (`ahead.rs`), and
        // the empty ones: not evaluated.
        let mut ahead = [false; N];
        let mut ready = true;
        for ((p, kin), ahead) in places.iter_mut().zip(&mut kin).zip(&mut ahead) {
            let Some((cell, t, x, dx, result)) = p.parts() else {
                *ahead = true;
                continue;
            };
            let mut sim = cell.sim_mut();
            if sim.reuse_ahead(t, x, dx) {
                *ahead = true;
                continue;
            }
            match sim.rhs_forces(t, x, dx) {
                Ok(k) => *kin = k,
                Err(e) => {
                    *result = Err(e);
                    ready = false;
                }
            }
        }
        if ahead[..places.len().min(N)].iter().all(|&a| a) {
            return;
        }
        let solved = ready && self.solve(places, &ahead);
        for ((p, &kin), &ahead) in places.iter_mut().zip(&kin).zip(&ahead) {
            let Some((cell, _, x, dx, result)) = p.parts() else {
                continue;
            };
            if result.is_err() || ahead {
                continue;
            }
            let mut sim = cell.sim_mut();
            let dynamics = if solved {
                Ok(())
            } else {
                sim.dynamics(kin, dx)
            };
            *result = dynamics.and_then(|()| sim.rhs_power(x, dx));
        }
    }

    /// The dynamics of every place by one call of the lanes' kernel, after their effects:
    /// `false` (nothing written) where the runs do not all take it alike, or where the lanes
    /// part ways; then each run solves its own.
    /// The places `ahead` (their slope kept already, or empty) are not solved: the inputs of
    /// a run there (whatever its last pass left) or of the first run only fill their lanes,
    /// and their results are not written.
    fn solve<K: RowSink, P: Place<K>>(&mut self, places: &mut [P], ahead: &[bool; N]) -> bool {
        if places.len() < 2 || places.len() > N {
            return false;
        }
        // The runs' simulations (no allocation: a stage is a few microseconds).
        let mut sims: [Option<Ref<'_, Running<K>>>; N] = std::array::from_fn(|_| None);
        for (s, p) in sims.iter_mut().zip(places.iter_mut()) {
            *s = p.parts().map(|(cell, ..)| cell.borrow());
        }
        let Some(first) = sims.iter().position(Option::is_some) else {
            return false;
        };
        let lane = |k: usize| {
            sims[k]
                .as_ref()
                .unwrap_or_else(|| sims[first].as_ref().expect("a run"))
        };
        let Some((first_kernel, locks, loaded)) = kernel_call(&lane(first).sim) else {
            return false;
        };
        let mut serials = [lane(first).sim.model.serial; N];
        for (k, r) in sims
            .iter()
            .enumerate()
            .skip(first + 1)
            .filter_map(|(k, r)| Some((k, r.as_ref()?)))
        {
            match kernel_call(&r.sim) {
                Some((_, l, w)) if (l, w) == (locks, loaded) => serials[k] = r.sim.model.serial,
                _ => return false,
            }
        }
        if self.kernel.as_ref().is_none_or(|(_, s)| *s != serials) {
            let kernels: [&UnrolledAba; N] = std::array::from_fn(|k| {
                sims[k]
                    .as_ref()
                    .and_then(|r| kernel_call(&r.sim))
                    .map_or(first_kernel, |c| c.0)
            });
            self.kernel = Some((UnrolledAba::gather(kernels), serials));
        }
        let Some((Some(kernel), _)) = &self.kernel else {
            return false;
        };
        // The inputs, lane `k` run `k`'s (the lanes past the runs repeat the first run).
        let d0 = &lane(first).sim.data;
        let (nq, nv, nb) = (d0.q.len(), d0.v.len(), d0.forces.body_wrench.len());
        let zero = F64x([0.0; N]);
        self.q.resize(nq, zero);
        self.v.resize(nv, zero);
        self.tau.resize(nv, zero);
        self.ddq.resize(nv, zero);
        let zero_force = Force::new(
            nalgebra::Vector3::repeat(zero),
            nalgebra::Vector3::repeat(zero),
        );
        self.fext.resize(if loaded { nb } else { 0 }, zero_force);
        let data = |k: usize| &lane(k).sim.data;
        pack(&mut self.q, std::array::from_fn(|k| &data(k).q[..]));
        pack(&mut self.v, std::array::from_fn(|k| &data(k).v[..]));
        pack(&mut self.tau, std::array::from_fn(|k| &data(k).tau[..]));
        for (b, a) in self.fext.iter_mut().enumerate() {
            let w: [&Force; N] = std::array::from_fn(|k| &data(k).forces.body_wrench[b]);
            for i in 0..3 {
                a.ang[i] = F64x(w.map(|w| w.ang[i]));
                a.lin[i] = F64x(w.map(|w| w.lin[i]));
            }
        }
        let fext = loaded.then_some(self.fext.as_slice());
        if kernel
            .aba_hybrid_with_forces_into(&self.q, &self.v, &self.tau, fext, locks, &mut self.ddq)
            .is_err()
        {
            return false;
        }
        drop(sims);
        for (k, p) in places.iter_mut().enumerate() {
            if ahead[k] {
                continue;
            }
            let Some((cell, _, _, dx, _)) = p.parts() else {
                continue;
            };
            let mut sim = cell.sim_mut();
            sim.log.lane_rhs += 1;
            match sim.model.velocity_at {
                Some(s) => {
                    for (d, a) in dx[s..s + nv].iter_mut().zip(&self.ddq) {
                        *d = a.0[k];
                    }
                }
                None => {
                    for (d, a) in sim.data.ddq.iter_mut().zip(&self.ddq) {
                        *d = a.0[k];
                    }
                    sim.pack_accelerations(dx);
                }
            }
        }
        true
    }
}

/// `dst[i]`'s lane `k` = `src[k][i]`: one value of the lanes built whole (stored at once,
/// so that the kernel's wide loads find it; lane by lane, four narrow stores would each be
/// waited for). Out of line: alone, the compiler transposes two values of each run at a
/// time in registers; inlined into `solve`, it loaded and stored each value on its own.
#[inline(never)]
fn pack<const N: usize>(dst: &mut [F64x<N>], src: [&[f64]; N]) {
    let n = dst.len();
    let src = src.map(|s| &s[..n]);
    for (i, d) in dst.iter_mut().enumerate() {
        *d = F64x(std::array::from_fn(|k| src[k][i]));
    }
}

/// How `sim`'s dynamics call, now, goes to its unrolled kernel: the kernel, the lock mask
/// in its form, whether wrenches are applied; `None` where it does not (a flexible tree, no
/// kernel, a lock mask the kernel leaves to the generic algorithm).
fn kernel_call(sim: &Simulation) -> Option<(&UnrolledAba, Locks, bool)> {
    let (m, d) = (&sim.model, &sim.data);
    if m.flex.is_some() {
        return None;
    }
    let kernel = m.fd.kernel()?.as_any()?.downcast_ref::<UnrolledAba>()?;
    let locks = match d.n_locked {
        0 => Locks::NONE,
        _ => kernel.locks(&d.locked)?,
    };
    Some((kernel, locks, d.forces.has_wrench))
}
