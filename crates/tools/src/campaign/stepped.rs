//! Runs stepped by the user's flight software (contract section 15): run `k` of a campaign
//! with a controller called at the control instants `t0 + i · period`.
//!
//! [`Campaign::run_stepped`] draws run `k`'s values and sensor seed exactly as
//! [`Campaign::run_one`] does, builds the drawn scene as a [`SceneStepper`] (what
//! `satsim.Simulation` steps), and at each control instant calls `control(t, stepper)`
//! (the Python binding calls the user's `step(t, measure(), row())` there and sets the
//! inputs it returns), then advances to the next instant (the last piece ends at the
//! scene's end). The rows are reduced to the same record as a run of the built-in
//! controllers (as [`Campaign::run_one`] reduces them): a controller that sets no input
//! gives the row `satsim campaign` gives, bit for bit where stepping in pieces reproduces a
//! run (a fixed-step integrator, `period` a whole number of steps:
//! [`SceneStepper::advance`]).
//!
//! A controller that fails (raises, returns an unknown input or a non-finite value) fails
//! its run only, with a message naming the run, the time and the cause.

use super::{Campaign, Collect, RunRecord, catch_panic};
use crate::api::Trajectory;
use crate::stepping::SceneStepper;
use satsim_integrate::DecimalGrid;
use satsim_tree::error::{Count, Num};

/// Why a control instant did not go on.
#[derive(Debug)]
pub enum Tick {
    /// The controller failed: the run is failed with this cause.
    Failed(String),
    /// The caller stopped the campaign (Ctrl-C): the run is left out, to be made again.
    Stopped,
}

/// A run made by [`Campaign::run_stepped`].
#[derive(Debug)]
pub struct Stepped {
    /// Its record (`metrics` empty: the caller computes them from `trajectory`).
    pub record: RunRecord,
    /// Its rows, for the user's metrics; `None` for a failed run.
    pub trajectory: Option<Trajectory>,
}

impl Stepped {
    /// How `campaign.json` names the flight software of a stepped campaign: the factory,
    /// the period and the metrics function, so that a folder is resumed and merged only
    /// with the same.
    pub fn identity(factory: &str, period: f64, metrics: Option<&str>) -> String {
        match metrics {
            Some(m) => format!("{factory} every {period} s, metrics {m}"),
            None => format!("{factory} every {period} s"),
        }
    }
}

impl Campaign {
    /// Whether `period` can step the nominal scene: a finite number > 0 whose control
    /// instants over the scene's `duration` are within [`Campaign::max_rows`] (as the
    /// sensors' samples are), so that a slip (`1e-9`) is refused before any run.
    pub fn check_period(&self, period: f64) -> Result<(), String> {
        if !(period > 0.0 && period.is_finite()) {
            return Err(format!(
                "the period must be a finite number > 0 (s), got {period}"
            ));
        }
        let instants = (self.nominal.duration / period).ceil();
        if instants > self.max_rows() as f64 {
            return Err(format!(
                "a period of {} s makes {} control instants in the scene's {} s, more than the limit of {} (`max_rows`): the smallest period allowed is {} s",
                Num(period),
                Count(instants),
                Num(self.nominal.duration),
                self.max_rows(),
                self.nominal.duration / self.max_rows() as f64
            ));
        }
        Ok(())
    }

    /// Run `k` stepped by `control` every `period` seconds (finite, > 0): see the module
    /// documentation. `None` when `control` stopped it ([`Tick::Stopped`]).
    pub fn run_stepped(
        &self,
        k: u64,
        period: f64,
        control: &mut dyn FnMut(f64, &mut SceneStepper) -> Result<(), Tick>,
    ) -> Option<Stepped> {
        let values = self.draw(k);
        let mut stopped = false;
        let outcome = catch_panic(|| {
            self.check_period(period)?;
            let scene = self.drawn_scene(k, &values)?;
            let mut s = SceneStepper::new(&scene, None, "").map_err(|e| e.to_string())?;
            s.set_max_rows(self.max_rows());
            if s.columns() != self.columns {
                return Err(
                    "the drawn scene's trajectory columns differ from the nominal scene's".into(),
                );
            }
            let t0 = s.t();
            let t_end = s.stepping().output_grid().t_end;
            // An instant within round-off of the end is the end (no sliver of a step).
            let slack = 1e-9 * period;
            // The instants as decimals, as the fixed step's grid and the rows are.
            let instants = DecimalGrid::new(t0, period);
            let mut i = 0u64;
            while s.t() < t_end {
                let t = s.t();
                match control(t, &mut s) {
                    Ok(()) => {}
                    Err(Tick::Failed(why)) => return Err(format!("run {k} at t = {t} s: {why}")),
                    Err(Tick::Stopped) => {
                        stopped = true;
                        return Err("stopped".into());
                    }
                }
                i += 1;
                let mut next = instants.point(i as f64);
                if next > t_end - slack {
                    next = t_end;
                }
                if next <= s.t() {
                    continue; // below the time's resolution here: the next instant
                }
                s.advance_to(next)
                    .map_err(|e| format!("at t = {t} s: {e}"))?;
            }
            Ok((
                s.trajectory().clone(),
                super::peaks(s.stepping().simulation()),
                s.stepping().steps(),
            ))
        });
        if stopped {
            return None;
        }
        Some(match outcome {
            Ok((trajectory, peaks, steps)) => {
                let mut c = Collect::new(self, k, &|| false);
                c.stats.peaks = peaks;
                // A control period longer than the stability limit leaves the integrator's
                // steps to it.
                c.stats.held = self.stability_held(&steps);
                let width = trajectory.columns.len();
                for row in trajectory.values.chunks_exact(width) {
                    // Rows from the stepper are finite (it refuses any that is not).
                    use satsim_spacecraft::simulation::RowSink;
                    let _ = c.row(row[0], row);
                }
                let record = c.into_record(values);
                let trajectory = record.outcome.is_ok().then_some(trajectory);
                Stepped { record, trajectory }
            }
            Err(why) => Stepped {
                record: RunRecord::failed(k, values, why),
                trajectory: None,
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A controller that sets no input gives the record of the run alone, bit for bit, with
    /// the control instants at `t0 + i · period` and the last piece ending at the end.
    #[test]
    fn stepping_without_inputs_is_the_run_bit_for_bit() {
        let c = super::super::tests::short_example(2.0, 4);
        for k in 0..c.runs {
            let mut instants = Vec::new();
            let s = c
                .run_stepped(k, 0.3, &mut |t, _| {
                    instants.push(t);
                    Ok(())
                })
                .unwrap();
            let alone = c.run_one(k);
            assert_eq!(c.csv_row(&s.record), c.csv_row(&alone), "run {k}");
            assert_eq!(c.trace_lines(&s.record), c.trace_lines(&alone), "run {k}");
            // On the RK4 grid (0.01 s): `0.9`, where `3.0 * 0.3` is 0.8999999999999999.
            assert_eq!(instants.len(), 7, "run {k}");
            for (i, t) in instants.iter().enumerate() {
                assert!((t - i as f64 * 0.3).abs() < 1e-12, "run {k}: {instants:?}");
            }
            let rows = s.trajectory.unwrap();
            assert_eq!(rows.values[rows.values.len() - rows.columns.len()], 2.0);
        }
    }

    /// A controller's failure fails its run, named with the time; a stop leaves it out;
    /// an input is applied (the run differs from the run alone).
    #[test]
    fn a_failing_controller_fails_its_run_and_inputs_act() {
        let c = super::super::tests::short_example(2.0, 4);
        let s = c
            .run_stepped(1, 0.1, &mut |t, _| {
                if t > 0.25 {
                    Err(Tick::Failed("the controller raised ValueError: x".into()))
                } else {
                    Ok(())
                }
            })
            .unwrap();
        assert_eq!(
            s.record.outcome.unwrap_err(),
            "run 1 at t = 0.3 s: the controller raised ValueError: x"
        );
        assert!(s.trajectory.is_none());
        assert!(
            c.run_stepped(1, 0.1, &mut |_, _| Err(Tick::Stopped))
                .is_none()
        );
        let pushed = c
            .run_stepped(0, 0.1, &mut |_, s| {
                s.set_inputs(&[("wheel_x", 0.01)])
                    .map_err(|e| Tick::Failed(e.to_string()))
            })
            .unwrap();
        assert_ne!(c.csv_row(&pushed.record), c.csv_row(&c.run_one(0)));
        let bad = c
            .run_stepped(0, 0.1, &mut |_, s| {
                s.set_inputs(&[("wheel_q", 0.01)])
                    .map_err(|e| Tick::Failed(e.to_string()))
            })
            .unwrap();
        assert!(bad.record.outcome.unwrap_err().contains("wheel_q"));
        assert!(
            c.check_period(1e-9)
                .unwrap_err()
                .contains("control instants")
        );
        assert!(c.check_period(f64::NAN).is_err());
    }

    /// A run stepped by flight software under DP5(4) is held by the stiff hinge's modes
    /// where its control period leaves the integrator steps to take (1 s), as the same run
    /// of the built-in controllers is; a period below the limit (about 7 ms) is what sets
    /// the steps, and the run is not held.
    #[test]
    fn a_stepped_run_is_held_where_its_period_leaves_the_steps_to_the_integrator() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/scenes/stiff_hinge.toml");
        let text = std::fs::read_to_string(&path)
            .unwrap()
            .replace("duration = 100.0", "duration = 10.0")
            .replace("method = \"radau5\"", "method = \"dp54\"")
            + "[campaign]\nruns = 1\nseed = 7\n";
        let c = Campaign::parse(&text, &path).unwrap();
        assert!(c.run_one(0).outcome.unwrap().held);
        let held = |period: f64| {
            let s = c.run_stepped(0, period, &mut |_, _| Ok(())).unwrap();
            s.record.outcome.unwrap().held
        };
        assert!(held(1.0));
        assert!(!held(6e-3));
    }
}
