//! What a campaign warns of after its runs, from `runs.csv`'s rows (so that a resumed or
//! merged folder warns alike): runs bent beyond their modal model, runs whose energy budget
//! drifted, runs whose steps a stability limit held. `satsim campaign`'s words, and Python's
//! `satsim.campaign`'s.

/// The warning after a campaign whose `beyond` of its `ok` finished runs bent a body past
/// [`SMALL_DEFLECTION`](satsim_tree::flexible::SMALL_DEFLECTION) of its length
/// ([`Finished::beyond`](super::Finished::beyond)): `satsim campaign`'s and Python's `satsim.campaign`'s.
pub fn beyond_warning(beyond: u64, ok: u64) -> String {
    format!(
        "{beyond} of the {ok} finished runs bent a flexible body past a tenth of its length at some step (a beam's tip, or a modes file's node for its distance from the body's frame): beyond what its modal model holds (a few per cent of the length), so those runs' results from then on are not the structure's (`peak_deflection_<body>` in runs.csv, the largest over every step as a fraction of the length; `satsim run` of a run's scene says when)"
    )
}

/// Whether the finished run whose statistics are `row` (named by `names`: `runs.csv`'s
/// columns after `message`) moved its energy budget by more than
/// [`BUDGET_DRIFT`](satsim_spacecraft::simulation::BUDGET_DRIFT) of its largest term over
/// its output rows: `max_energy_budget − min_energy_budget` against the largest `min_` or
/// `max_` of `kinetic_energy`, `potential_energy`, `work_actuators` and
/// `energy_dissipated`, the test `satsim run` applies to its one run
/// ([`budget_drifted`](satsim_spacecraft::simulation::budget_drifted)). `false` without an
/// energy budget.
pub fn budget_drifted_row(names: &[String], row: &[f64]) -> bool {
    let at = |name: &str| names.iter().position(|n| n == name).map(|i| row[i]);
    let (Some(min), Some(max)) = (at("min_energy_budget"), at("max_energy_budget")) else {
        return false;
    };
    let scale = [
        "kinetic_energy",
        "potential_energy",
        "work_actuators",
        "energy_dissipated",
    ]
    .iter()
    .flat_map(|t| [at(&format!("min_{t}")), at(&format!("max_{t}"))])
    .flatten()
    .fold(0.0, |s: f64, x| s.max(x.abs()));
    satsim_spacecraft::simulation::budget_drifted(max - min, scale)
}

/// The column of `runs.csv` after the statistics (and the beams' peaks): 1 where the run's
/// steps were held by its explicit method's stability limit ([`RunStats::held`](super::RunStats::held)), else 0.
pub const HELD_COLUMN: &str = "stability_held";

/// The warning after a campaign whose `held` of its `ok` finished runs had their steps held by
/// their explicit method's stability limit ([`Finished::held`](super::Finished::held)): `satsim campaign`'s and
/// Python's `satsim.campaign`'s.
pub fn held_warning(held: u64, ok: u64) -> String {
    format!(
        "{held} of the {ok} finished runs took steps held by their explicit method's stability limit on the scene's fastest motion, not by the tolerance (`{HELD_COLUMN}` in runs.csv): `integrator.method = \"radau5\"` (implicit) steps over that motion, with `elastic_error = false` where a flexible body's own ringing need not be resolved (`satsim run` of the scene names the motion and its limit)"
    )
}

/// The warning after a campaign whose `drifted` of its `ok` finished runs moved their energy
/// budget beyond what the integration should leave ([`Finished::drifted`](super::Finished::drifted)): `satsim
/// campaign`'s and Python's `satsim.campaign`'s.
pub fn budget_warning(drifted: u64, ok: u64) -> String {
    format!(
        "{drifted} of the {ok} finished runs moved their energy budget by more than {:.0} % of its largest term (`max_energy_budget` − `min_energy_budget` in runs.csv): along the exact motion it is constant, so those runs carry the integration's error, not the structure's behaviour: a fixed step near a fast mode's stability limit damps that mode, or the tolerance is too loose (`satsim run` of a run's scene says how much)",
        100.0 * satsim_spacecraft::simulation::BUDGET_DRIFT
    )
}
