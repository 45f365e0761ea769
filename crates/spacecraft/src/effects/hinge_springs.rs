//! Hinge spring-dampers (preprint section 2): `M_ui = −δ_i ψ_i − λ_i (φ_i − φ_ref,i)` on each
//! of the model's hinges, in file order. Potential energy `Σ ½ λ_i (φ_i − φ_ref,i)²`; the
//! dampers dissipate `Σ δ_i ψ_i²` (W).

use super::{Context, Effect, Forces, Power, SceneEffect, Section};
use satsim_integrate::SystemError;
use satsim_tree::io::FileError;
use serde::Deserialize;
use toml::Spanned;

/// The spring-damper effect; one entry per model hinge, file order.
#[derive(Clone, Debug, PartialEq)]
pub struct HingeSprings {
    /// Stiffness λ_i (N m/rad).
    pub stiffness: Vec<f64>,
    /// Damping δ_i (N m s/rad).
    pub damping: Vec<f64>,
    /// Reference angle φ_ref,i (rad).
    pub reference: Vec<f64>,
}

impl HingeSprings {
    /// Springs with the given stiffness, no damping, zero reference.
    pub fn new(stiffness: Vec<f64>) -> Self {
        let n = stiffness.len();
        Self {
            stiffness,
            damping: vec![0.0; n],
            reference: vec![0.0; n],
        }
    }
}

impl Effect for HingeSprings {
    fn name(&self) -> &str {
        "hinge_springs"
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        // Zipped rather than indexed: no bounds check per hinge (the lengths are the
        // model's hinge count, checked when the scene was read).
        let hinges = forces
            .hinge_torque
            .iter_mut()
            .zip(ctx.angles)
            .zip(ctx.rates);
        let gains = self
            .stiffness
            .iter()
            .zip(&self.damping)
            .zip(&self.reference);
        for (((tau, phi), psi), ((lambda, delta), phi_ref)) in hinges.zip(gains) {
            *tau += -delta * psi - lambda * (phi - phi_ref);
        }
        Ok(())
    }
    /// The springs are conservative (their work is the potential's change); the dampers
    /// dissipate `Σ δ_i ψ_i²`.
    fn power(&self, ctx: &Context, _own: &[f64], _applied: f64) -> Power {
        // Zipped, as in `apply` (the same terms in the same order).
        Power::dissipated(
            self.damping
                .iter()
                .zip(ctx.rates)
                .map(|(delta, psi)| delta * psi * psi)
                .sum(),
        )
    }
    fn potential_energy(&self, ctx: &Context, _own: &[f64]) -> f64 {
        self.stiffness
            .iter()
            .zip(&self.reference)
            .zip(ctx.angles)
            .map(|((lambda, phi_ref), phi)| {
                let d = phi - phi_ref;
                0.5 * lambda * d * d
            })
            .sum()
    }
    /// Its potential reads the angles only, and it has no output columns.
    fn row_reads_apply(&self) -> bool {
        false
    }
}

/// `[effects.hinge_springs]` (contract section 7).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringsFile {
    /// N m/rad, one per hinge, file order.
    pub stiffness: Spanned<Vec<f64>>,
    /// N m s/rad (default zeros).
    #[serde(default)]
    pub damping: Option<Spanned<Vec<f64>>>,
    /// rad (default zeros).
    #[serde(default)]
    pub reference: Option<Spanned<Vec<f64>>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

impl SceneEffect for HingeSprings {
    const SECTION: &'static str = "hinge_springs";
    type File = SpringsFile;
    fn from_section(s: SpringsFile, section: &Section) -> Result<Self, FileError> {
        let n = section.model().n_hinges();
        let stiffness =
            section.per_hinge_non_negative(&s.stiffness, "effects.hinge_springs.stiffness")?;
        let damping = match &s.damping {
            Some(d) => section.per_hinge_non_negative(d, "effects.hinge_springs.damping")?,
            None => vec![0.0; n],
        };
        let reference = match &s.reference {
            Some(r) => {
                let v = section.per_hinge(r, "effects.hinge_springs.reference")?;
                for &a in &v {
                    section.check_angle(r.span(), "effects.hinge_springs.reference", a);
                }
                v
            }
            None => vec![0.0; n],
        };
        Ok(HingeSprings {
            stiffness,
            damping,
            reference,
        })
    }
}
