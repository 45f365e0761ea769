//! Output rows: the column names, one row of values, the energies and momenta.

use super::Simulation;
use super::hold::Hold;
use satsim_integrate::SystemError;
use satsim_tree::energy_and_momentum;
use satsim_tree::flexible;
use satsim_tree::spatial::Vec3;

impl Simulation {
    /// Output column names: `t`, attitude, rates, hinge angles and rates, the elastic
    /// coordinates `eta_<body>_<k>`, their rates `etadot_<body>_<k>` and each beam's tip
    /// deflection `tip_<body>` (m, along its `bend`), the effects' columns, energies and
    /// angular momentum.
    pub fn columns(&self) -> Vec<String> {
        let mut c: Vec<String> = [
            "t", "q_w", "q_x", "q_y", "q_z", "omega_x", "omega_y", "omega_z",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        for name in &self.model.tree.hinge_names()[..self.model.n_user] {
            c.push(format!("angle_{name}"));
        }
        for name in &self.model.tree.hinge_names()[..self.model.n_user] {
            c.push(format!("rate_{name}"));
        }
        let elastic = self.elastic_names();
        c.extend(elastic.iter().map(|n| format!("eta_{n}")));
        c.extend(elastic.iter().map(|n| format!("etadot_{n}")));
        if let Some(f) = &self.model.flex {
            for i in 0..f.rigid().n_bodies() {
                if f.beam(i).is_some() {
                    c.push(format!("tip_{}", f.rigid().bodies()[i].name()));
                }
            }
        }
        for e in &self.effects {
            if !e.rotors().is_empty() {
                c.extend(e.state_names());
            }
            c.extend(e.output_columns());
        }
        c.extend(
            [
                "kinetic_energy",
                "potential_energy",
                "total_energy",
                "h_x",
                "h_y",
                "h_z",
                "h_norm",
            ]
            .iter()
            .map(|s| s.to_string()),
        );
        if !self.model.work.is_empty() {
            c.extend(
                ["work_actuators", "energy_dissipated", "energy_budget"]
                    .iter()
                    .map(|s| s.to_string()),
            );
        }
        c
    }

    /// One output row at `(t, x)` (see [`Simulation::columns`]).
    /// A state of the wrong length is an error.
    pub fn row(&mut self, t: f64, x: &[f64], row: &mut Vec<f64>) -> Result<(), SystemError> {
        self.check_len(x.len(), "row")?;
        row.clear();
        self.prepare_row(t, x)?;
        row.push(t);
        let l = &self.model.layout;
        if l.free {
            row.extend_from_slice(&x[l.attitude.clone()]);
            row.extend_from_slice(&x[l.omega.clone()]);
        } else {
            row.extend_from_slice(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        }
        row.extend_from_slice(&x[l.angles.clone()]);
        row.extend_from_slice(&x[l.rates.clone()]);
        row.extend_from_slice(&x[l.eta.clone()]);
        row.extend_from_slice(&x[l.etadot.clone()]);
        if let (Some(f), Some(w)) = (&self.model.flex, &self.data.flex) {
            // `prepare` unpacked this state.
            row.extend((0..f.rigid().n_bodies()).filter_map(|i| f.tip_deflection(i, &w.q)));
        }
        let d = self.diagnostics_prepared(t, x, Some(row))?;
        row.push(d.kinetic);
        row.push(d.potential);
        row.push(d.kinetic + d.potential);
        row.extend_from_slice(d.h.as_slice());
        row.push(d.h.norm());
        if !self.model.work.is_empty() {
            let (work, lost) = (x[self.model.work.start], x[self.model.work.start + 1]);
            let budget = d.kinetic + d.potential - work + lost;
            row.push(work);
            row.push(lost);
            row.push(budget);
            self.data
                .budget
                .see(budget, [d.kinetic, d.potential, work, lost]);
        }
        Ok(())
    }

    /// Energies and momenta at `(t, x)`.
    pub fn diagnostics(&mut self, t: f64, x: &[f64]) -> Result<Diagnostics, SystemError> {
        self.check_len(x.len(), "diagnostics")?;
        self.prepare_row(t, x)?;
        self.diagnostics_prepared(t, x, None)
    }

    /// What a row reads prepared: [`Self::prepare`] with kinematics, less the effects'
    /// `apply` where none of them reads in its output or potential what `apply` kept
    /// ([`crate::effects::Effect::row_reads_apply`]): a row takes no forces, and that pass
    /// was a fifth of the springs' every-step rows.
    fn prepare_row(&mut self, t: f64, x: &[f64]) -> Result<(), SystemError> {
        if self.effects.iter().any(|e| e.row_reads_apply()) {
            return self.prepare(t, x, true);
        }
        self.unpack(x);
        self.kinematics(true)?;
        self.hold_torques_after_effects(true, Hold::None)
    }

    pub(super) fn diagnostics_prepared(
        &mut self,
        t: f64,
        x: &[f64],
        row: Option<&mut Vec<f64>>,
    ) -> Result<Diagnostics, SystemError> {
        // `prepare` ran kinematics on this state.
        let d = &mut self.data;
        let (kinetic, strain, p, h) = match (&self.model.flex, &mut d.flex) {
            (Some(f), Some(w)) => {
                // The first pass is the kinematics' on this state.
                flexible::energy_and_momentum(f, &w.data, &d.tree, &w.q, &w.v)
            }
            _ => {
                // The energy and momenta in one pass (bit for bit the separate functions').
                let (kinetic, p, h) = energy_and_momentum(&self.model.tree, &d.tree, &d.v);
                (kinetic, 0.0, p, h)
            }
        };
        let rotor_effect = self.model.rotor_effect;
        let potential = self.with_context(t, x, true, |ctx, hooks| {
            let mut potential = 0.0;
            for (e, r) in hooks.effects.iter().zip(hooks.own) {
                potential += e.potential_energy(ctx, &x[r.clone()]);
            }
            if let Some(row) = row {
                for (i, (e, r)) in hooks.effects.iter().zip(hooks.own).enumerate() {
                    // The wheel speeds (no call to `rotors()`, which allocates).
                    if rotor_effect == Some(i) {
                        row.extend_from_slice(&x[r.clone()]);
                    }
                    e.output(ctx, &x[r.clone()], row);
                }
            }
            potential
        });
        Ok(Diagnostics {
            kinetic,
            potential: potential + strain,
            h,
            p,
        })
    }
}

/// Energies (J) and momenta (inertial axes) of the tree, wheels included.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diagnostics {
    /// Kinetic energy (relative to the centre-of-mass frame when there is an orbit).
    pub kinetic: f64,
    /// Potential energy of the effects (springs, gravity gradient) and the flexible bodies'
    /// strain energy `½ Σ ωₖ² ηₖ²`.
    pub potential: f64,
    /// Angular momentum about the centre of mass (N m s).
    pub h: Vec3,
    /// Linear momentum (N s).
    pub p: Vec3,
}
