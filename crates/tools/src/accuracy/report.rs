//! The measured points and their renderings: CSV, the work-precision diagrams, the markdown
//! table ([`Report`]).

use super::metrics::ErrorMetrics;
use super::plot::loglog_plot;
use super::spec::{Setting, Sweep};
use satsim_integrate::Method;
use std::fmt::Write as _;

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
