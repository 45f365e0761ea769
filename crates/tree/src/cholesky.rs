//! Forward dynamics by the mass matrix: `M q̈ = τ − C`, with `M` from CRBA, `C` from RNEA and
//! a Cholesky solve (Featherstone §6.1). The second, independent path beside ABA.
//!
//! Small systems use an in-place factorisation written here (no allocation, no dispatch);
//! from [`FAER_MIN_DOF`] degrees of freedom on, faer's blocked Cholesky takes over.

use crate::crba::mass_matrix;
use crate::data::Data;
use crate::error::DynamicsError;
use crate::model::Model;
use crate::rnea::bias;
use crate::spatial::Force;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{
    LltError, LltRegularization, cholesky_in_place, cholesky_in_place_scratch,
};
use faer::{Mat, Par};
use nalgebra::{DMatrix, DVector};

/// From this many degrees of freedom on, the factorisation uses faer. Measured: with the
/// in-house factorisation `crba_cholesky` is faster up to about 45 DOF, faer is faster from
/// about 55-65 DOF on, and in between they are level within the noise (chains and binary
/// trees; docs/src/results/performance.md, "Cholesky crossover").
pub const FAER_MIN_DOF: usize = 48;

/// faer's buffers, allocated once for large models.
pub struct FaerWork {
    l: Mat<f64>,
    rhs: Mat<f64>,
    stack: MemBuffer,
}

impl std::fmt::Debug for FaerWork {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "FaerWork({} dof)", self.l.nrows())
    }
}

impl Clone for FaerWork {
    fn clone(&self) -> Self {
        FaerWork::new(self.l.nrows())
    }
}

impl FaerWork {
    /// Buffers for `n` degrees of freedom. [`Data::new`] sets `Data::faer` from
    /// [`FAER_MIN_DOF`]; setting it to `Some(FaerWork::new(nv))` or `None` by hand forces either
    /// factorisation (how the crossover was measured).
    pub fn new(n: usize) -> Self {
        let req = cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default());
        Self {
            l: Mat::zeros(n, n),
            rhs: Mat::zeros(n, 1),
            stack: MemBuffer::new(req),
        }
    }
}

/// Forward dynamics by CRBA + RNEA + Cholesky, into `data.ddq` (conventions of [`crate::aba()`]).
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, ModelBuilder, aba, crba_cholesky, spatial::{Mat3, Vec3}};
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
    crate::kinematics::check_len("tau", tau.len(), model.nv())?;
    bias(model, data, q, v, fext)?; // also computes `data.xup` for q
    mass_matrix(model, data);
    for (r, t) in tau.iter().enumerate() {
        data.ddq[r] = t - data.bias[r];
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
            llt_in_place(&mut data.chol)?;
            llt_solve_in_place(&data.chol, &mut data.ddq);
        }
    }
    Ok(&data.ddq)
}

/// In-place Cholesky `A = L Lᵀ` on the lower triangle (the upper is left untouched).
pub fn llt_in_place(a: &mut DMatrix<f64>) -> Result<(), DynamicsError> {
    let n = a.nrows();
    for j in 0..n {
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= a[(j, k)] * a[(j, k)];
        }
        if d.is_nan() || d <= 0.0 {
            return Err(DynamicsError::NotPositiveDefinite { index: j, pivot: d });
        }
        let ljj = d.sqrt();
        a[(j, j)] = ljj;
        for i in j + 1..n {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= a[(i, k)] * a[(j, k)];
            }
            a[(i, j)] = s / ljj;
        }
    }
    Ok(())
}

/// Solves `L Lᵀ x = b` in place, `L` from [`llt_in_place`].
pub fn llt_solve_in_place(l: &DMatrix<f64>, b: &mut DVector<f64>) {
    let n = l.nrows();
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[(i, k)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[(k, i)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
}
