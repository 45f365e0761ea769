//! # satsim-satellite: the Keldysh preprint 2015-26 satellite on the `satsim-tree` engine
//!
//! The Keldysh Institute preprint 2015-26 (Ovchinnikov, Chang, Mirer, Tkachev, Roldugin,
//! *Dynamical model of a satellite with controllable solar array*): its layout (a bus, a
//! 3-DOF gimbal hinge made of three 1-DOF hinges through two massless links, three panels)
//! configured on the generic engine, and the printed closed-form equations of motion (19)
//! cross-checked against it.
//!
//! - [`params`]: the preprint's parameters ([`PreprintParams`], with a realistic default) and
//!   [`build_model`], which lays them out as a [`satsim_tree::Model`];
//! - [`layout`]: [`recognise`] finds the preprint's layout in any model (or says what is
//!   wrong) and reads its parameters back;
//! - [`table2`](mod@table2): the rotation chain of Table 2 (`B_i`, `D_i`);
//! - [`closed_form`]: every printed symbol of `S` and `N` (equation (19)) as a function,
//!   printed and corrected where the text is wrong;
//! - [`engine`]: `S` and `N` from the engine (Schur complement over the root's linear
//!   velocity: the centre-of-mass translation eliminated);
//! - [`checks`]: the other formulas the project takes from the preprint (centre of mass (13),
//!   gravity-gradient torque, quaternion equation (20), the gravity force approximation,
//!   equations (5)-(10));
//! - [`compare`]: what `satsim preprint` prints.

// Two `unsafe` blocks: the lane kernel's calls of its AVX-512 and AVX2 instances, where the
// CPU has those instructions (`kernel.rs`, each with its safety comment).
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod checks;
pub mod closed_form;
pub mod engine;
pub mod instructions;
pub mod kernel;
pub mod layout;
pub mod params;
pub mod table2;
pub mod variant;

pub use closed_form::{K, PreprintState, Symbols, Variant};
pub use engine::{n_tree, s_tree};
pub use layout::{Layout, LayoutError, recognise};
pub use params::{Deployment, PreprintParams, build_model};
pub use table2::{Table2, table2};

use nalgebra::{DMatrix, DVector};
use satsim_tree::spatial::Vec3;
use satsim_tree::{Data, DynamicsError, Model};
use thiserror::Error;

/// Why [`compare`] could not run.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PreprintError {
    /// The model does not have the preprint's layout.
    #[error("the model does not have the preprint's layout: {0}")]
    Layout(#[from] LayoutError),
    /// A state vector has the wrong length.
    #[error("{what}: expected {expected} entries for the preprint's layout, got {got}")]
    Dimension {
        /// `q`, `v` or `tau`.
        what: &'static str,
        /// The length needed.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A state entry is not finite.
    #[error("{what}[{index}] is not finite")]
    NonFinite {
        /// `q`, `v` or `tau`.
        what: &'static str,
        /// The entry.
        index: usize,
    },
    /// A generalised force on the free base: the preprint's equations have none.
    #[error(
        "tau on the free base must be zero (the preprint has no external force or torque on the bus), found {0:?}"
    )]
    BaseForce([f64; 6]),
    /// The engine failed (e.g. a massless tree: the linear block of the mass matrix is
    /// singular).
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// A result overflowed: the state's rates or torques (or the model's masses) are too
    /// large or too small for `f64`. `what` names the quantity (`S_tree`, `N_closed_form`…).
    #[error(
        "{what} is not finite: the computation overflowed (rates, torques or masses too extreme for f64)"
    )]
    Overflow {
        /// The quantity.
        what: &'static str,
    },
}

/// What `satsim preprint` prints: `S` and `N` of equation (19) from the corrected closed form
/// and from the engine, rows `(ω1 x, y, z in bus axes, hinges 1..5)`.
#[derive(Clone, Debug, PartialEq)]
pub struct PreprintReport {
    /// `S` from the closed form (errata corrected), 8x8.
    pub s_closed_form: DMatrix<f64>,
    /// `N` from the closed form (errata corrected), 8.
    pub n_closed_form: DVector<f64>,
    /// `S` from the engine (Schur complement of the mass matrix), 8x8.
    pub s_tree: DMatrix<f64>,
    /// `N` from the engine (RNEA bias, reduced the same way), 8.
    pub n_tree: DVector<f64>,
    /// Largest absolute entry of `S_closed_form − S_tree` and `N_closed_form − N_tree`.
    pub max_abs_difference: f64,
}

impl PreprintReport {
    /// The JSON object of cli-contract section 4: keys `S_closed_form`, `N_closed_form`,
    /// `S_tree`, `N_tree` (matrices as arrays of rows), `max_abs_difference`.
    pub fn to_json(&self) -> serde_json::Value {
        let rows = |m: &DMatrix<f64>| -> Vec<Vec<f64>> {
            (0..m.nrows())
                .map(|i| m.row(i).iter().copied().collect())
                .collect()
        };
        let vec = |v: &DVector<f64>| -> Vec<f64> { v.iter().copied().collect() };
        serde_json::json!({
            "S_closed_form": rows(&self.s_closed_form),
            "N_closed_form": vec(&self.n_closed_form),
            "S_tree": rows(&self.s_tree),
            "N_tree": vec(&self.n_tree),
            "max_abs_difference": self.max_abs_difference,
        })
    }
}

fn check(what: &'static str, x: &[f64], expected: usize) -> Result<(), PreprintError> {
    if x.len() != expected {
        return Err(PreprintError::Dimension {
            what,
            expected,
            got: x.len(),
        });
    }
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(PreprintError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// The preprint state at engine coordinates `q, v, tau` of a model with the preprint's layout
/// (hinges 1..5 are the model's hinges in file order), with no external couples. `q` needs
/// 12 entries, `v` and `tau` 11 each: shorter slices are a [`PreprintError::Dimension`].
pub fn state_from_engine(
    q: &[f64],
    v: &[f64],
    tau: &[f64],
) -> Result<PreprintState, PreprintError> {
    for (what, x, expected) in [("q", q, 12), ("v", v, 11), ("tau", tau, 11)] {
        if x.len() < expected {
            return Err(PreprintError::Dimension {
                what,
                expected,
                got: x.len(),
            });
        }
    }
    let five = |s: &[f64]| -> [f64; 5] { [s[0], s[1], s[2], s[3], s[4]] };
    Ok(PreprintState {
        phi: five(&q[7..12]),
        omega1: Vec3::new(v[0], v[1], v[2]),
        psi: five(&v[6..11]),
        m_u: five(&tau[6..11]),
        m_ext: [Vec3::zeros(); 4],
    })
}

/// `Err(Overflow { what })` unless every entry of `x` is finite.
fn finite<'a>(
    what: &'static str,
    x: impl IntoIterator<Item = &'a f64>,
) -> Result<(), PreprintError> {
    if x.into_iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(PreprintError::Overflow { what })
    }
}

/// `satsim preprint`: `S` and `N` of equation (19) from the corrected closed form and from
/// the engine, for a model with the preprint's layout at engine coordinates `q`
/// (`[attitude w x y z, position, φ1..φ5]`), `v` (`[ω1, root origin velocity, ψ1..ψ5]`) and
/// `tau` (zero on the base, `M_u1..M_u5` on the hinges). No external torques.
///
/// Every number of the report is finite: a result that overflows is
/// [`PreprintError::Overflow`] naming it, a massless tree a [`PreprintError::Dynamics`].
///
/// ```
/// use satsim_satellite::{build_model, compare, PreprintParams};
/// let model = build_model(&PreprintParams::default())?;
/// let mut q = model.neutral();
/// q[10] = 1.2; // φ4
/// let v = [0.001, -0.002, 0.0015, 0.0, 0.0, 0.0, 0.01, 0.02, -0.01, 0.05, -0.04];
/// let tau = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -0.5, 0.4];
/// let report = compare(&model, &q, &v, &tau)?;
/// assert!(report.max_abs_difference < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn compare(
    model: &Model,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
) -> Result<PreprintReport, PreprintError> {
    let layout = recognise(model)?;
    check("q", q, model.nq())?;
    check("v", v, model.nv())?;
    check("tau", tau, model.nv())?;
    if tau[..6].iter().any(|&t| t != 0.0) {
        return Err(PreprintError::BaseForce([
            tau[0], tau[1], tau[2], tau[3], tau[4], tau[5],
        ]));
    }
    let symbols = Symbols::new(&layout.params, &state_from_engine(q, v, tau)?);
    let s_cf = symbols.S();
    let n_cf = symbols.N(Variant::Corrected);
    let s_closed_form = DMatrix::from_fn(8, 8, |i, j| s_cf[(i, j)]);
    let n_closed_form = DVector::from_fn(8, |i, _| n_cf[i]);
    let mut data = Data::new(model);
    let s_tree = s_tree(model, &mut data, q)?;
    let n_tree = n_tree(model, &mut data, q, v, tau, None)?;
    // Every result finite (`amax` would skip a NaN), so the difference means something.
    finite("S_closed_form", s_closed_form.iter())?;
    finite("N_closed_form", n_closed_form.iter())?;
    finite("S_tree", s_tree.iter())?;
    finite("N_tree", n_tree.iter())?;
    let max_abs_difference = (&s_closed_form - &s_tree)
        .amax()
        .max((&n_closed_form - &n_tree).amax());
    finite("max_abs_difference", [&max_abs_difference])?;
    Ok(PreprintReport {
        s_closed_form,
        n_closed_form,
        s_tree,
        n_tree,
        max_abs_difference,
    })
}
