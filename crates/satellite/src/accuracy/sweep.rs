//! What to measure ([`Sweep`], [`Setting`]) and the measuring loop ([`sweep()`]).

use super::metrics::compare;
use super::report::{Measured, Point, ReferenceRun, Report};
use super::trajectory::{Trajectory, run};
use crate::scene::Scene;
use satsim_integrate::{Method, Options};

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
