//! Forward dynamics by the mass matrix: `M q̈ = τ − C`, with `M` from CRBA, `C` from RNEA and
//! a Cholesky solve (Featherstone §6.1). The second, independent path beside ABA
//! ([`crate::Method::CrbaCholesky`] of [`crate::ForwardDynamics`], which calls it).
//!
//! Small systems use the in-place factorisation of [`crate::llt`] (no allocation, no
//! dispatch); from [`crate::llt::FAER_MIN_DOF`] degrees of freedom on, faer's blocked
//! Cholesky takes over.

use crate::crba::mass_matrix;
use crate::data::Data;
use crate::error::DynamicsError;
use crate::llt::{llt_in_place, llt_solve_in_place};
use crate::model::Model;
use crate::rnea::bias;
use crate::spatial::Force;
use faer::Par;
use faer::dyn_stack::MemStack;
use faer::linalg::cholesky::llt::factor::{LltError, LltRegularization, cholesky_in_place};
use nalgebra::DVector;

/// Forward dynamics by CRBA + RNEA + Cholesky, into `data.ddq` (conventions of
/// [`crate::aba::aba`]).
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, ModelBuilder, aba::aba, cholesky::crba_cholesky};
/// use satsim_tree::spatial::{Mat3, Vec3};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 4.0, Mat3::from_diagonal(&Vec3::new(1.0, 2.0, 3.0))).with_com(Vec3::x()))
///     .build()?;
/// let mut data = Data::new(&model);
/// let (q, v, tau) = (model.neutral(), [0.1, 0.2, 0.3, 0.0, 1.0, 0.0], [0.0, 0.0, 6.0, 8.0, 0.0, 0.0]);
/// let by_crba = crba_cholesky(&model, &mut data, &q, &v, &tau, None)?.clone();
/// let by_aba = aba(&model, &mut data, &q, &v, &tau, None)?;
/// assert!((by_crba - by_aba).norm() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn crba_cholesky<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    solve(model, data, q, v, tau, fext, None)
}

/// [`crba_cholesky`], and with `locked` (one entry per hinge, as [`crate::aba::aba_hybrid`]
/// takes it) hybrid dynamics by the mass matrix: a locked hinge's acceleration is zero and
/// the others solve `M_ff q̈_f = τ_f − C_f`, the principal block of the free coordinates
/// (factored as `M` with the locked rows and columns made those of the identity and their
/// right-hand sides zero: the free pivots are then `M_ff`'s, in the same order).
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
    locked: Option<&[bool]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    crate::kinematics::check_len("tau", tau.len(), model.nv())?;
    if let Some(l) = locked {
        crate::kinematics::check_len("locked", l.len(), model.n_hinges())?;
    }
    bias(model, data, q, v, fext)?; // also computes `data.xup` for q
    mass_matrix(model, data);
    for (r, t) in tau.iter().enumerate() {
        data.ddq[r] = t - data.bias[r];
    }
    let nb = model.base_nv();
    // Coordinate `r` is a locked hinge's.
    let held = |r: usize| locked.is_some_and(|l| r >= nb && l[r - nb]);
    if locked.is_some() {
        for r in 0..model.nv() {
            if held(r) {
                data.ddq[r] = 0.0;
            }
        }
    }
    let n = model.nv();
    match &mut data.faer {
        Some(work) => {
            for j in 0..n {
                for i in j..n {
                    work.l[(i, j)] = data.mass_matrix[(i, j)];
                }
                work.rhs[(j, 0)] = data.ddq[j];
            }
            if locked.is_some() {
                for j in (0..n).filter(|&j| held(j)) {
                    for i in j..n {
                        work.l[(i, j)] = if i == j { 1.0 } else { 0.0 };
                    }
                    for k in 0..j {
                        work.l[(j, k)] = 0.0;
                    }
                }
            }
            let stack = MemStack::new(&mut work.stack);
            cholesky_in_place(
                work.l.as_mut(),
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map_err(|LltError::NonPositivePivot { index }| {
                DynamicsError::NotPositiveDefinite {
                    index,
                    pivot: f64::NAN,
                }
            })?;
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                work.l.as_ref(),
                work.rhs.as_mut(),
                Par::Seq,
            );
            faer::linalg::triangular_solve::solve_upper_triangular_in_place(
                work.l.as_ref().transpose(),
                work.rhs.as_mut(),
                Par::Seq,
            );
            for j in 0..n {
                data.ddq[j] = work.rhs[(j, 0)];
            }
        }
        None => {
            data.chol.copy_from(&data.mass_matrix);
            if locked.is_some() {
                for j in (0..n).filter(|&j| held(j)) {
                    data.chol.row_mut(j).fill(0.0);
                    data.chol.column_mut(j).fill(0.0);
                    data.chol[(j, j)] = 1.0;
                }
            }
            llt_in_place(&mut data.chol)?;
            llt_solve_in_place(&data.chol, &mut data.ddq);
        }
    }
    Ok(&data.ddq)
}
