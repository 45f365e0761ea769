//! Dense Cholesky helpers shared by the mass-matrix algorithms: an in-place `L Lᵀ`
//! factorisation and solve for small systems (no allocation, no dispatch), and faer's
//! buffers for large ones ([`FaerWork`], from [`FAER_MIN_DOF`] degrees of freedom on).
//!
//! [`crate::Data`] owns the buffers ([`crate::Data::faer`], [`crate::Data::chol`]);
//! [`crate::cholesky::crba_cholesky`] and [`crate::impulse::hinge_impulse`] use them. This
//! module depends on neither, so that `data.rs` and `cholesky.rs` both import it and not
//! each other.

use crate::error::DynamicsError;
use faer::Mat;
use faer::Par;
use faer::dyn_stack::MemBuffer;
use faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch;
use nalgebra::{DMatrix, DVector};

/// From this many degrees of freedom on, the factorisation uses faer. Measured: with the
/// in-house factorisation [`crate::cholesky::crba_cholesky`] is faster up to about 45 DOF,
/// faer is faster from about 55-65 DOF on, and in between they are level within the noise
/// (chains and binary trees; docs/src/engineering/algorithms.md, "Dense Cholesky below 48 DOF").
pub const FAER_MIN_DOF: usize = 48;

/// faer's buffers, allocated once for large models.
pub struct FaerWork {
    pub(crate) l: Mat<f64>,
    pub(crate) rhs: Mat<f64>,
    pub(crate) stack: MemBuffer,
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
    /// Buffers for `n` degrees of freedom. [`crate::Data::new`] sets `Data::faer` from
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
