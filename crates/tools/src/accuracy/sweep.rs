//! The measuring loop ([`sweep()`]) over a [`Sweep`].

use super::metrics::compare;
use super::report::{Measured, Point, ReferenceRun, Report};
use super::spec::{Setting, Sweep};
use super::trajectory::{Trajectory, run};
use crate::scene::Scene;
use crate::scene::step_limit::rk4_stable_step;
use satsim_integrate::Method;

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
    // The references count every state in their error, the elastic coordinates too, whatever
    // the runs measured against them do (`integrator.elastic_error`).
    let full = Scene {
        elastic_error: true,
        ..scene.clone()
    };
    let reference_run = |(method, tol): (Method, f64), progress: &mut dyn FnMut(&str)| {
        progress(&format!("reference {method} tol={tol:e}"));
        let opts = sweep.options(&full, method, Setting::Tolerance(tol));
        let tr =
            run(&full, &opts).map_err(|e| format!("reference run {method} at {tol:e}: {e}"))?;
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
        // `elastic_error = false` is Radau IIA's (the scene reader refuses it with an
        // explicit method, whose steps would go past the modes' stability limit): the other
        // methods count the elastic coordinates, as the references do.
        let scene = if method == Method::Radau5 {
            scene
        } else {
            &full
        };
        let opts = sweep.options(scene, method, setting);
        let mut best: Option<Trajectory> = None;
        let mut failure = None;
        // A fixed step beyond RK4's stability limit for the scene's modes and hinge gains is
        // not run: they would grow without bound (the scene reader refuses such a step
        // likewise).
        if let (Some(h), Some((stable, what))) = (opts.fixed_step, rk4_stable_step(scene))
            && method == Method::Rk4
            && h > stable
        {
            points.push(Point {
                method,
                setting,
                result: Err(format!(
                    "not run: h = {h} s is beyond rk4's stability limit for {what} (largest stable step {stable:.3e} s)"
                )),
            });
            continue;
        }
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
