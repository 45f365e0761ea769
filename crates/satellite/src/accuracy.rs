//! Work-precision measurements: what accuracy costs in time.
//!
//! A [`Sweep`] runs a [`Scene`] with every integrator over a range of tolerances (and the
//! fixed-step RK4 over a range of steps), measures each run's error against a reference
//! solution and its cost (wall time, minimum over several repeats, and right-hand-side
//! evaluations from [`Stats`]), and collects the points into a [`Report`] that renders as
//! CSV, a log-log SVG diagram and a markdown table.
//!
//! # Reference
//!
//! The reference is the same scene integrated by DOP853 at `rtol = atol = 1e-13`
//! ([`Sweep::reference`]). DOP853's own points are measured against a reference computed by
//! a *different* method ([`Sweep::cross_reference`], DP5(4) at `1e-13`; Radau IIA is not
//! used because at that tolerance its Newton iteration fails on the deployment scene's
//! stick-slip wheels), so that a method
//! is never judged against itself. The difference between the two references is reported as
//! the *floor*: errors below it are not measurable.
//!
//! # Error
//!
//! At each saved time `t_i` (the scene's output times) the run and the reference are
//! compared by ([`ErrorMetrics`]):
//!
//! - the bus attitude error: the rotation angle of `q_ref⁻¹ ⊗ q` (rad),
//! - the hinge angle errors `|φ_k − φ_ref,k|` (rad),
//! - the rate errors: bus angular velocity components and hinge rates (rad/s),
//!
//! and `e_i` is the largest of them. A point's error is `e` at the final time, and its RMS
//! over the saved times is reported too. Angles and rates are mixed on purpose: a
//! flight-dynamics requirement is usually "attitude to X rad and rates to Y rad/s", and the
//! largest of the two is what a tolerance must deliver.
//!
//! # Cost
//!
//! The wall time of one [`satsim_integrate::integrate`] call (the simulation is built
//! beforehand and outputs are copied into a preallocated list), minimum over
//! [`Sweep::repeats`] runs, and the right-hand-side evaluations it made (finite-difference
//! Jacobians included).
//!
//! ```
//! use satsim_satellite::accuracy::attitude_angle;
//! // A rotation by 0.3 rad about z against the identity.
//! let (s, c) = (0.15f64.sin(), 0.15f64.cos());
//! let e = attitude_angle(&[1.0, 0.0, 0.0, 0.0], &[c, 0.0, 0.0, s]);
//! assert!((e - 0.3).abs() < 1e-15);
//! ```

use crate::scene::Scene;
use crate::simulation::StateLayout;
use satsim_integrate::{Method, Options, Output, Stats};
use std::fmt::Write as _;
use std::ops::ControlFlow;
use std::time::Instant;

/// One setting of one method: a tolerance (adaptive methods) or a step (RK4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    /// `rtol = tol`, `atol = tol * atol_scale`.
    Tolerance(f64),
    /// Fixed step (s).
    Step(f64),
}

impl Setting {
    /// `tol=1e-6` or `h=0.01`.
    pub fn label(&self) -> String {
        match self {
            Setting::Tolerance(t) => format!("tol={t:e}"),
            Setting::Step(h) => format!("h={h}"),
        }
    }
}

/// What to run.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// Methods, in the order they are reported.
    pub methods: Vec<Method>,
    /// Tolerances of the adaptive methods (`rtol`; `atol = rtol * atol_scale`).
    pub tolerances: Vec<f64>,
    /// Steps of the fixed-step RK4 (s).
    pub rk4_steps: Vec<f64>,
    /// `atol / rtol`.
    pub atol_scale: f64,
    /// Timed runs per point; the minimum wall time is reported.
    pub repeats: usize,
    /// The reference for every method but itself: `(method, tolerance)`.
    pub reference: (Method, f64),
    /// The reference for [`Sweep::reference`]'s own method.
    pub cross_reference: (Method, f64),
}

impl Sweep {
    /// The full sweep: tolerances `1e-3 … 1e-12` (one per decade), RK4 steps
    /// `every · 2^-k` for `k = 3 … 11` (steps that divide the output interval, so no step is
    /// shortened), 3 repeats, references at `1e-13`.
    pub fn full(scene: &Scene) -> Self {
        Self {
            methods: Method::ALL.to_vec(),
            tolerances: (3..=12).map(|k| 10f64.powi(-k)).collect(),
            rk4_steps: (3..=11).map(|k| scene.every * 0.5f64.powi(k)).collect(),
            atol_scale: 1.0,
            repeats: 3,
            reference: (Method::Dop853, 1e-13),
            cross_reference: (Method::Dp54, 1e-13),
        }
    }

    /// A small sweep for tests and smoke runs: two tolerances, two RK4 steps, one repeat,
    /// references at `1e-12`.
    pub fn quick(scene: &Scene) -> Self {
        Self {
            tolerances: vec![1e-4, 1e-7],
            rk4_steps: vec![scene.every / 8.0, scene.every / 32.0],
            repeats: 1,
            reference: (Method::Dop853, 1e-12),
            cross_reference: (Method::Dp54, 1e-12),
            ..Self::full(scene)
        }
    }

    /// Every `(method, setting)` of the sweep, in report order.
    pub fn settings(&self) -> Vec<(Method, Setting)> {
        let mut out = Vec::new();
        for &m in &self.methods {
            if m == Method::Rk4 {
                out.extend(self.rk4_steps.iter().map(|&h| (m, Setting::Step(h))));
            } else {
                out.extend(self.tolerances.iter().map(|&t| (m, Setting::Tolerance(t))));
            }
        }
        out
    }

    /// The integrator options of one setting, from the scene's (its step limits and
    /// `max_steps` are kept; its first step is not).
    pub fn options(&self, scene: &Scene, method: Method, setting: Setting) -> Options {
        let mut o = scene.options.clone();
        o.method = method;
        o.h0 = None;
        o.fixed_step = None;
        match setting {
            Setting::Tolerance(t) => o.with_tolerances(t, t * self.atol_scale),
            Setting::Step(h) => o.with_fixed_step(h),
        }
    }
}

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

/// The rotation angle (rad, in `[0, π]`) of `q_ref⁻¹ ⊗ q` for Hamilton quaternions
/// `[w, x, y, z]` (normalised here, so a slightly denormalised input is fine).
pub fn attitude_angle(q_ref: &[f64], q: &[f64]) -> f64 {
    let (a, b) = (q_ref, q);
    // conj(a) ⊗ b
    let w = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    let x = a[0] * b[1] - a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
    let y = a[0] * b[2] + a[1] * b[3] - a[2] * b[0] - a[3] * b[1];
    let z = a[0] * b[3] - a[1] * b[2] + a[2] * b[1] - a[3] * b[0];
    let v = (x * x + y * y + z * z).sqrt();
    2.0 * v.atan2(w.abs())
}

/// Errors of one state against a reference state at the same time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StateError {
    /// Bus attitude error (rad); 0 for a fixed base.
    pub attitude: f64,
    /// Largest hinge angle error (rad).
    pub angles: f64,
    /// Largest bus angular velocity component or hinge rate error (rad/s).
    pub rates: f64,
}

impl StateError {
    /// `x` against `x_ref`.
    pub fn of(layout: &StateLayout, x_ref: &[f64], x: &[f64]) -> Self {
        let max_diff = |r: std::ops::Range<usize>| {
            r.map(|i| (x[i] - x_ref[i]).abs()).fold(0.0, |m: f64, d| {
                if d.is_nan() { f64::NAN } else { m.max(d) }
            })
        };
        let attitude = if layout.free {
            let a = layout.attitude.clone();
            attitude_angle(&x_ref[a.clone()], &x[a])
        } else {
            0.0
        };
        Self {
            attitude,
            angles: max_diff(layout.angles.clone()),
            rates: max_diff(layout.omega.clone()).max(max_diff(layout.rates.clone())),
        }
    }
    /// The largest of the three (NaN if any is NaN).
    pub fn max(&self) -> f64 {
        let v = [self.attitude, self.angles, self.rates];
        if v.iter().any(|e| e.is_nan()) {
            return f64::NAN;
        }
        v.into_iter().fold(0.0, f64::max)
    }
}

/// The error of a run against a reference, see the module documentation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorMetrics {
    /// The three errors at the final time.
    pub at_end: StateError,
    /// `max` of [`ErrorMetrics::at_end`]: the headline error.
    pub final_max: f64,
    /// RMS over the saved times of the per-time largest error.
    pub rms: f64,
    /// Largest per-time error over the saved times.
    pub max_over_time: f64,
}

/// Compares two trajectories saved at the same times. Every metric returned is finite (an
/// overflowing difference is an error).
pub fn compare(
    layout: &StateLayout,
    reference: &Trajectory,
    run: &Trajectory,
) -> Result<ErrorMetrics, String> {
    if reference.times.len() != run.times.len()
        || reference
            .times
            .iter()
            .zip(&run.times)
            .any(|(a, b)| (a - b).abs() > 1e-9 * a.abs().max(1.0))
    {
        return Err(format!(
            "saved times differ ({} against {} rows)",
            run.times.len(),
            reference.times.len()
        ));
    }
    let Some((last_ref, last)) = reference.states.last().zip(run.states.last()) else {
        return Err("no saved state".into());
    };
    let at_end = StateError::of(layout, last_ref, last);
    let mut sum = 0.0;
    let mut worst: f64 = 0.0;
    for (a, b) in reference.states.iter().zip(&run.states) {
        let e = StateError::of(layout, a, b).max();
        sum += e * e;
        worst = if e.is_nan() { f64::NAN } else { worst.max(e) };
    }
    let m = ErrorMetrics {
        at_end,
        final_max: at_end.max(),
        rms: (sum / run.states.len() as f64).sqrt(),
        max_over_time: worst,
    };
    // A non-finite error is never reported as a measurement.
    if [m.final_max, m.rms, m.max_over_time]
        .iter()
        .all(|e| e.is_finite())
    {
        Ok(m)
    } else {
        Err("the error against the reference is not finite (the states overflow)".into())
    }
}

/// A measured point.
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// Errors against the reference.
    pub errors: ErrorMetrics,
    /// Wall time (s), minimum over the repeats.
    pub seconds: f64,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
    /// Accepted steps.
    pub steps: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Located events.
    pub events: usize,
}

/// One point of the diagram: a method at a setting, measured or failed.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// The method.
    pub method: Method,
    /// Its tolerance or step.
    pub setting: Setting,
    /// The measurement, or why the run failed.
    pub result: Result<Measured, String>,
}

impl Point {
    /// The measurement, if the run succeeded with a finite error.
    pub fn ok(&self) -> Option<&Measured> {
        self.result
            .as_ref()
            .ok()
            .filter(|m| m.errors.final_max.is_finite())
    }
}

/// A reference run's description.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceRun {
    /// The method.
    pub method: Method,
    /// Its tolerance.
    pub tol: f64,
    /// Wall time of one run (s).
    pub seconds: f64,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
    /// Accepted steps.
    pub steps: usize,
}

/// The outcome of a [`Sweep`].
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// The scene file.
    pub scene: String,
    /// Duration (s) and output interval (s) of the scene.
    pub duration: f64,
    /// Seconds between saved states.
    pub every: f64,
    /// State components.
    pub state_len: usize,
    /// The sweep.
    pub sweep: Sweep,
    /// The main reference.
    pub reference: ReferenceRun,
    /// The reference for the main reference's method.
    pub cross_reference: ReferenceRun,
    /// The two references against each other: the floor of measurable error.
    pub floor: ErrorMetrics,
    /// The points, in sweep order.
    pub points: Vec<Point>,
}

/// Runs the sweep on `scene`. `progress` is told what is being run.
pub fn sweep(
    scene: &Scene,
    sweep: &Sweep,
    mut progress: impl FnMut(&str),
) -> Result<Report, String> {
    let layout = scene
        .simulation()
        .map_err(|e| e.to_string())?
        .layout()
        .clone();
    let reference_run = |(method, tol): (Method, f64), progress: &mut dyn FnMut(&str)| {
        progress(&format!("reference {method} tol={tol:e}"));
        let opts = sweep.options(scene, method, Setting::Tolerance(tol));
        let tr =
            run(scene, &opts).map_err(|e| format!("reference run {method} at {tol:e}: {e}"))?;
        let info = ReferenceRun {
            method,
            tol,
            seconds: tr.seconds,
            rhs_evals: tr.stats.rhs_evals,
            steps: tr.stats.steps_accepted,
        };
        Ok::<_, String>((tr, info))
    };
    let (ref_main, ref_info) = reference_run(sweep.reference, &mut progress)?;
    let (ref_cross, cross_info) = reference_run(sweep.cross_reference, &mut progress)?;
    let floor = compare(&layout, &ref_main, &ref_cross)?;
    let mut points = Vec::new();
    for (method, setting) in sweep.settings() {
        progress(&format!("{method} {}", setting.label()));
        let reference = if method == sweep.reference.0 {
            &ref_cross
        } else {
            &ref_main
        };
        let opts = sweep.options(scene, method, setting);
        let mut best: Option<Trajectory> = None;
        let mut failure = None;
        for _ in 0..sweep.repeats.max(1) {
            match run(scene, &opts) {
                Ok(tr) => {
                    if best.as_ref().is_none_or(|b| tr.seconds < b.seconds) {
                        best = Some(tr);
                    }
                }
                Err(e) => {
                    failure = Some(e);
                    break;
                }
            }
        }
        let result = match (failure, best) {
            (Some(e), _) => Err(e),
            (None, None) => Err("no run".into()),
            (None, Some(tr)) => compare(&layout, reference, &tr).map(|errors| Measured {
                errors,
                seconds: tr.seconds,
                rhs_evals: tr.stats.rhs_evals,
                steps: tr.stats.steps_accepted,
                rejected: tr.stats.steps_rejected,
                events: tr.stats.events.len(),
            }),
        };
        points.push(Point {
            method,
            setting,
            result,
        });
    }
    Ok(Report {
        scene: scene.path.display().to_string(),
        duration: scene.duration,
        every: scene.every,
        state_len: layout.len,
        sweep: sweep.clone(),
        reference: ref_info,
        cross_reference: cross_info,
        floor,
        points,
    })
}

/// The cost axis of a diagram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cost {
    /// Wall time (s).
    Seconds,
    /// Right-hand-side evaluations.
    RhsEvals,
}

impl Cost {
    fn of(self, m: &Measured) -> f64 {
        match self {
            Cost::Seconds => m.seconds,
            Cost::RhsEvals => m.rhs_evals as f64,
        }
    }
    fn label(self) -> &'static str {
        match self {
            Cost::Seconds => "wall time (s, min of repeats)",
            Cost::RhsEvals => "right-hand-side evaluations",
        }
    }
}

/// The display name of a method.
pub fn method_label(m: Method) -> &'static str {
    match m {
        Method::Rk4 => "RK4 (fixed step)",
        Method::Dp54 => "DP5(4)",
        Method::Dop853 => "DOP853",
        Method::Radau5 => "Radau IIA (5)",
    }
}

/// The cheapest way a method reaches a final error: see [`Report::to_reach`].
#[derive(Clone, Debug, PartialEq)]
pub struct Reach {
    /// The cheapest measured point at or below the target.
    pub cheapest: Option<(Setting, Measured)>,
    /// The cost at the target by log-log interpolation between the two measured points
    /// (in order of increasing cost) that bracket it; `None` when no pair brackets it.
    pub interpolated: Option<f64>,
}

impl Report {
    /// The measured points of `method`, in order of increasing wall time.
    pub fn measured(&self, method: Method) -> Vec<(Setting, &Measured)> {
        let mut v: Vec<(Setting, &Measured)> = self
            .points
            .iter()
            .filter(|p| p.method == method)
            .filter_map(|p| p.ok().map(|m| (p.setting, m)))
            .collect();
        v.sort_by(|a, b| a.1.seconds.total_cmp(&b.1.seconds));
        v
    }

    /// What it costs `method` to reach a final error `target`.
    pub fn to_reach(&self, method: Method, target: f64, cost: Cost) -> Reach {
        let mut pts = self.measured(method);
        pts.sort_by(|a, b| cost.of(a.1).total_cmp(&cost.of(b.1)));
        let cheapest = pts
            .iter()
            .find(|(_, m)| m.errors.final_max <= target)
            .map(|(s, m)| (*s, (*m).clone()));
        let interpolated = pts.windows(2).find_map(|w| {
            let (e0, e1) = (w[0].1.errors.final_max, w[1].1.errors.final_max);
            let (c0, c1) = (cost.of(w[0].1), cost.of(w[1].1));
            if e0 > target && e1 <= target && e0 > 0.0 && e1 > 0.0 && c0 > 0.0 && c1 > 0.0 {
                let s = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
                Some((c0.ln() + s * (c1.ln() - c0.ln())).exp())
            } else {
                None
            }
        });
        Reach {
            cheapest,
            interpolated,
        }
    }

    /// The point of `method` at tolerance `tol`, if measured.
    pub fn at_tolerance(&self, method: Method, tol: f64) -> Option<&Measured> {
        self.points
            .iter()
            .find(|p| {
                p.method == method
                    && matches!(p.setting, Setting::Tolerance(t) if (t - tol).abs() <= 1e-12 * tol)
            })
            .and_then(|p| p.result.as_ref().ok())
    }

    /// The points as CSV: one row per point, failed runs with empty numbers and the reason.
    pub fn csv(&self) -> String {
        let mut s = String::from(
            "method,tolerance,step,status,seconds,rhs_evals,steps,rejected,events,\
             err_final,err_rms,err_max_over_time,err_attitude_final,err_angles_final,err_rates_final\n",
        );
        for p in &self.points {
            let (tol, step) = match p.setting {
                Setting::Tolerance(t) => (format!("{t:e}"), String::new()),
                Setting::Step(h) => (String::new(), format!("{h}")),
            };
            match &p.result {
                Ok(m) => {
                    let e = &m.errors;
                    let _ = writeln!(
                        s,
                        "{},{tol},{step},ok,{:e},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e}",
                        p.method,
                        m.seconds,
                        m.rhs_evals,
                        m.steps,
                        m.rejected,
                        m.events,
                        e.final_max,
                        e.rms,
                        e.max_over_time,
                        e.at_end.attitude,
                        e.at_end.angles,
                        e.at_end.rates
                    );
                }
                Err(why) => {
                    let why = why.replace([',', '\n', '"'], " ");
                    let _ = writeln!(s, "{},{tol},{step},failed: {why},,,,,,,,,,,", p.method);
                }
            }
        }
        s
    }

    /// A log-log SVG diagram: final error against `cost`, one line per method, with the
    /// references' floor as a dashed line.
    pub fn svg(&self, cost: Cost) -> String {
        let series: Vec<(String, Vec<(f64, f64)>)> = self
            .sweep
            .methods
            .iter()
            .map(|&m| {
                let mut pts: Vec<(f64, f64)> = self
                    .measured(m)
                    .iter()
                    .map(|(_, x)| (cost.of(x), x.errors.final_max))
                    .filter(|(c, e)| *c > 0.0 && *e > 0.0)
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                (method_label(m).to_owned(), pts)
            })
            .collect();
        let floor = (self.floor.final_max > 0.0).then_some(self.floor.final_max);
        let name = std::path::Path::new(&self.scene)
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.scene.clone());
        loglog_plot(
            &format!("Work-precision: {name}"),
            cost.label(),
            "error at the final time (rad, rad/s)",
            &series,
            floor,
        )
    }

    /// A markdown summary: references, floor, and one table row per point.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# Work-precision: `{}`\n", self.scene);
        let _ = writeln!(
            s,
            "Duration {} s, states saved every {} s, {} state components. Wall times are the \
             minimum of {} run(s).\n",
            self.duration,
            self.every,
            self.state_len,
            self.sweep.repeats.max(1)
        );
        for (what, r) in [
            ("Reference", &self.reference),
            (
                "Cross-reference (for its own method)",
                &self.cross_reference,
            ),
        ] {
            let _ = writeln!(
                s,
                "- {what}: {} at tol {:e}: {} steps, {} rhs evaluations, {:.3} s",
                method_label(r.method),
                r.tol,
                r.steps,
                r.rhs_evals,
                r.seconds
            );
        }
        let _ = writeln!(
            s,
            "- Floor (the two references against each other): final error {:.2e}, RMS {:.2e}\n",
            self.floor.final_max, self.floor.rms
        );
        let target = 1e-8;
        let _ = writeln!(
            s,
            "## Cost of a final error of {target:.0e}\n\n\
             | method | cheapest run at or below it | its error | its wall time (s) | its rhs evals | wall time interpolated at {target:.0e} (s) |\n\
             | --- | --- | ---: | ---: | ---: | ---: |"
        );
        for &m in &self.sweep.methods {
            let r = self.to_reach(m, target, Cost::Seconds);
            let interp = r
                .interpolated
                .map(fmt_seconds)
                .unwrap_or_else(|| "-".into());
            match r.cheapest {
                Some((setting, x)) => {
                    let _ = writeln!(
                        s,
                        "| {} | {} | {:.2e} | {} | {} | {interp} |",
                        method_label(m),
                        setting.label(),
                        x.errors.final_max,
                        fmt_seconds(x.seconds),
                        x.rhs_evals
                    );
                }
                None => {
                    let _ = writeln!(s, "| {} | not reached | | | | {interp} |", method_label(m));
                }
            }
        }
        let tol = 1e-6;
        let _ = writeln!(
            s,
            "\n## At tolerance {tol:.0e}\n\n\
             | method | final error | rhs evals | steps (rejected) | wall time (s) |\n\
             | --- | ---: | ---: | ---: | ---: |"
        );
        for &m in &self.sweep.methods {
            if let Some(x) = self.at_tolerance(m, tol) {
                let _ = writeln!(
                    s,
                    "| {} | {:.2e} | {} | {} ({}) | {} |",
                    method_label(m),
                    x.errors.final_max,
                    x.rhs_evals,
                    x.steps,
                    x.rejected,
                    fmt_seconds(x.seconds)
                );
            }
        }
        s.push_str("\n## All points\n\n");
        s.push_str(
            "| method | setting | final error | RMS error | attitude (rad) | hinge angles (rad) | rates (rad/s) | wall time (s) | rhs evals | steps (rejected) |\n\
             | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
        );
        for p in &self.points {
            let setting = match p.setting {
                Setting::Tolerance(t) => format!("tol {t:.0e}"),
                Setting::Step(h) => format!("h = {h} s"),
            };
            match &p.result {
                Ok(m) => {
                    let e = &m.errors;
                    let _ = writeln!(
                        s,
                        "| {} | {setting} | {:.2e} | {:.2e} | {:.1e} | {:.1e} | {:.1e} | {} | {} | {} ({}) |",
                        method_label(p.method),
                        e.final_max,
                        e.rms,
                        e.at_end.attitude,
                        e.at_end.angles,
                        e.at_end.rates,
                        fmt_seconds(m.seconds),
                        m.rhs_evals,
                        m.steps,
                        m.rejected
                    );
                }
                Err(why) => {
                    let why = why.replace('|', "/");
                    let _ = writeln!(
                        s,
                        "| {} | {setting} | failed: {why} | | | | | | | |",
                        method_label(p.method)
                    );
                }
            }
        }
        s
    }
}

/// Seconds with 3 significant digits.
pub fn fmt_seconds(x: f64) -> String {
    if x >= 100.0 {
        format!("{x:.0}")
    } else if x >= 1e-3 {
        let digits = (2 - x.log10().floor() as i32).max(0) as usize;
        format!("{x:.digits$}")
    } else {
        format!("{x:.2e}")
    }
}

/// A log-log SVG line plot (the shared [`crate::output::Figure`] writer): decade grid and
/// labels, one polyline with markers per series, an optional dashed horizontal line labelled
/// "reference floor".
pub fn loglog_plot(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[(String, Vec<(f64, f64)>)],
    floor: Option<f64>,
) -> String {
    use crate::output::{Axis, Figure};
    let xs = series.iter().flat_map(|s| s.1.iter().map(|p| p.0));
    let ys = series.iter().flat_map(|s| s.1.iter().map(|p| p.1));
    let mut f = Figure::new(
        title,
        Axis::log10(xlabel, xs),
        Axis::log10(ylabel, ys.chain(floor)),
    );
    if let Some(floor) = floor {
        f.reference(floor, "reference floor");
    }
    for (k, (label, points)) in series.iter().enumerate() {
        f.curve(label, points.iter().copied(), k);
        f.markers(points.iter().copied(), k);
    }
    f.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{UnitQuaternion, Vector3};

    #[test]
    fn attitude_angle_of_a_rotation_is_its_angle() {
        let base = UnitQuaternion::from_euler_angles(0.3, -1.1, 2.0);
        for (axis, angle) in [
            (Vector3::new(1.0, 2.0, -0.5), 1e-9),
            (Vector3::new(0.0, 0.0, 1.0), 0.25),
            (Vector3::new(-3.0, 1.0, 1.0), 3.0),
        ] {
            let d = UnitQuaternion::from_scaled_axis(axis.normalize() * angle);
            let q = base * d;
            let c = |u: UnitQuaternion<f64>| [u.w, u.i, u.j, u.k];
            let e = attitude_angle(&c(base), &c(q));
            assert!((e - angle).abs() < 1e-15 + 1e-13 * angle, "{e} vs {angle}");
            // q and −q are the same attitude.
            let neg = c(q).map(|v| -v);
            assert!((attitude_angle(&c(base), &neg) - angle).abs() < 1e-15 + 1e-13 * angle);
            // The error is the same measured in either order.
            assert!((attitude_angle(&c(q), &c(base)) - angle).abs() < 1e-15 + 1e-13 * angle);
        }
    }

    fn layout_free_2() -> StateLayout {
        // q (4), angles (2), ω (3), v (3), rates (2)
        StateLayout {
            free: true,
            n_hinges: 2,
            attitude: 0..4,
            angles: 4..6,
            omega: 6..9,
            velocity: 9..12,
            rates: 12..14,
            effects: vec![],
            len: 14,
        }
    }

    fn traj(times: &[f64], states: Vec<Vec<f64>>) -> Trajectory {
        Trajectory {
            times: times.to_vec(),
            states,
            stats: Stats {
                rhs_evals: 0,
                steps_accepted: 0,
                steps_rejected: 0,
                jacobian_evals: 0,
                lu_decompositions: 0,
                events: vec![],
                t_final: *times.last().unwrap(),
                x_final: vec![],
                stop: satsim_integrate::StopReason::Finished,
            },
            seconds: 0.0,
        }
    }

    #[test]
    fn metrics_on_a_synthetic_case() {
        let l = layout_free_2();
        let mut x = vec![0.0; 14];
        x[0] = 1.0;
        let reference = traj(&[0.0, 1.0], vec![x.clone(), x.clone()]);
        // At t = 1: rotated by 2e-6 rad, hinge angle off by 3e-7, velocity (not compared)
        // off by 1, bus rate off by 4e-6 (the largest), hinge rate off by 1e-6.
        let mut y = x.clone();
        let (s, c) = (1e-6f64.sin(), 1e-6f64.cos());
        y[..4].copy_from_slice(&[c, 0.0, s, 0.0]);
        y[5] = 3e-7;
        y[10] = 1.0;
        y[7] = -4e-6;
        y[13] = 1e-6;
        let run = traj(&[0.0, 1.0], vec![x.clone(), y]);
        let m = compare(&l, &reference, &run).unwrap();
        assert!((m.at_end.attitude - 2e-6).abs() < 1e-18);
        assert_eq!(m.at_end.angles, 3e-7);
        assert_eq!(m.at_end.rates, 4e-6);
        assert_eq!(m.final_max, 4e-6);
        assert_eq!(m.max_over_time, 4e-6);
        // RMS over the two saved times: sqrt((0 + (4e-6)²) / 2).
        assert!((m.rms - 4e-6 / 2f64.sqrt()).abs() < 1e-20);
        // Mismatched saved times are an error.
        let short = traj(&[0.0], vec![x]);
        assert!(compare(&l, &reference, &short).is_err());
    }

    #[test]
    fn reach_interpolates_in_log_log() {
        let m = |e: f64, t: f64| Measured {
            errors: ErrorMetrics {
                final_max: e,
                ..Default::default()
            },
            seconds: t,
            rhs_evals: (t * 1e6) as usize,
            steps: 1,
            rejected: 0,
            events: 0,
        };
        let p = |tol: f64, e: f64, t: f64| Point {
            method: Method::Dp54,
            setting: Setting::Tolerance(tol),
            result: Ok(m(e, t)),
        };
        let report = Report {
            scene: "x".into(),
            duration: 1.0,
            every: 1.0,
            state_len: 1,
            sweep: Sweep {
                methods: vec![Method::Dp54],
                tolerances: vec![],
                rk4_steps: vec![],
                atol_scale: 1.0,
                repeats: 1,
                reference: (Method::Dop853, 1e-13),
                cross_reference: (Method::Dp54, 1e-13),
            },
            reference: ReferenceRun {
                method: Method::Dop853,
                tol: 1e-13,
                seconds: 0.0,
                rhs_evals: 0,
                steps: 0,
            },
            cross_reference: ReferenceRun {
                method: Method::Dp54,
                tol: 1e-13,
                seconds: 0.0,
                rhs_evals: 0,
                steps: 0,
            },
            floor: ErrorMetrics::default(),
            points: vec![p(1e-4, 1e-6, 0.01), p(1e-6, 1e-10, 0.1)],
        };
        let r = report.to_reach(Method::Dp54, 1e-8, Cost::Seconds);
        assert!((r.interpolated.unwrap() - 10f64.powf(-1.5)).abs() < 1e-12);
        assert_eq!(r.cheapest.unwrap().0, Setting::Tolerance(1e-6));
        let svg = report.svg(Cost::Seconds);
        assert!(svg.starts_with("<svg") && svg.contains("polyline") && svg.contains("DP5(4)"));
        assert_eq!(report.csv().lines().count(), 3);
        assert!(report.markdown().contains("| DP5(4) | tol 1e-6 |"));
    }
}
