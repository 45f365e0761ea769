//! [`Simulation::run_lanes_with`]: runs of the deployment campaign in batches of 2, 3 and 8
//! give each run's rows, outcome and counters bit for bit as [`Simulation::run`] alone does,
//! and most of their dynamics are solved in lanes, the event functions' right-hand sides at
//! the steps' ends included.

use crate::common::example;
use satsim_integrate::{Output, Stats};
use satsim_spacecraft::simulation::{LaneJob, LaneJobs, RowSink, RunError, Simulation};
use satsim_tools::campaign::Campaign;
use satsim_tools::scene::Scene;

/// Each row's time and entries, as bits.
#[derive(Default)]
struct Rows(Vec<u64>);

impl RowSink for Rows {
    type Error = String;
    fn row(&mut self, t: f64, row: &[f64]) -> Result<(), String> {
        self.0.push(t.to_bits());
        self.0.extend(row.iter().map(|v| v.to_bits()));
        Ok(())
    }
}

/// A run's outcome (as text), rows, right-hand sides and events.
type Outcome = (String, Vec<u64>, u64, usize);

fn outcome(sim: &Simulation, rows: Rows, result: Result<Stats, RunError<String>>) -> Outcome {
    let result = format!("{:?}", result.map(|s| (s.t_final, s.x_final, s.events)));
    (result, rows.0, sim.rhs_evals(), sim.event_log().len())
}

struct Jobs {
    scenes: Vec<Scene>,
    next: usize,
    done: Vec<Option<(Outcome, u64, u64)>>,
}

impl LaneJobs for Jobs {
    type Sink = Rows;
    fn next(&mut self) -> Option<LaneJob<Rows>> {
        let scene = self.scenes.get(self.next)?;
        self.next += 1;
        let sim = scene.simulation().unwrap();
        Some(LaneJob {
            t_end: sim.t0() + scene.duration,
            output: Output::Interval(scene.every),
            sim,
            sink: Rows::default(),
        })
    }
    fn done(&mut self, sim: Simulation, rows: Rows, result: Result<Stats, RunError<String>>) {
        // Which run: the first not done with this run's initial state.
        let k = (0..self.scenes.len())
            .find(|&k| {
                self.done[k].is_none() && self.scenes[k].simulation().unwrap().x0() == sim.x0()
            })
            .expect("a run handed out");
        let (lanes, ahead) = (sim.run_log().lane_rhs(), sim.run_log().lane_ahead());
        self.done[k] = Some((outcome(&sim, rows, result), lanes, ahead));
    }
}

#[test]
fn runs_in_lanes_are_the_runs_alone() {
    let path = example("scenes/deploy_campaign.toml");
    let campaign = Campaign::read(&path).unwrap();
    let scenes: Vec<Scene> = (0..7)
        .map(|k| {
            let text = campaign.run_text(k, &campaign.draw(k));
            let mut scene = Scene::parse(&text, &path).unwrap();
            scene.duration = 25.0;
            scene
        })
        .collect();
    let options = scenes[0].options.clone();
    let alone: Vec<Outcome> = scenes
        .iter()
        .map(|scene| {
            let mut sim = scene.simulation().unwrap();
            let mut rows = Rows::default();
            let result = sim.run(
                &scene.options,
                sim.t0() + scene.duration,
                &Output::Interval(scene.every),
                |t, row| rows.row(t, row),
            );
            outcome(&sim, rows, result)
        })
        .collect();
    // The runs latch their panels: events, and lock masks that differ between runs.
    assert!(
        alone.iter().all(|o| o.3 >= 2),
        "{:?}",
        alone.iter().map(|o| o.3).collect::<Vec<_>>()
    );
    for width in [2, 3, 8] {
        let mut jobs = Jobs {
            scenes: scenes.clone(),
            next: 0,
            done: vec![None; scenes.len()],
        };
        Simulation::run_lanes_with(&options, width, &mut jobs);
        let (mut in_lanes, mut ahead) = (0, 0);
        for (k, (a, b)) in alone.iter().zip(&jobs.done).enumerate() {
            let (b, lanes, lane_ahead) = b.as_ref().expect("every run ends");
            ahead += lane_ahead;
            assert_eq!(a.0, b.0, "run {k}, width {width}: outcome");
            assert!(a.1 == b.1, "run {k}, width {width}: rows differ");
            assert_eq!((a.2, a.3), (b.2, b.3), "run {k}, width {width}: counters");
            in_lanes += lanes;
        }
        let rhs: u64 = alone.iter().map(|a| a.2).sum();
        assert!(
            in_lanes * 2 > rhs,
            "width {width}: {in_lanes} of {rhs} in lanes"
        );
        // The wheels stick from the start, so the event functions evaluate the right-hand
        // side at (nearly) every step's end, a quarter of the evaluations: most of those in
        // lanes too (not where a lone run is left in its batch, as at the end).
        assert!(
            ahead * 8 > rhs,
            "width {width}: {ahead} of {rhs} evaluated ahead in lanes"
        );
    }
}
