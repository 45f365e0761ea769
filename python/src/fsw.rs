//! The built-in flight software's blocks, callable from Python on arrays (contract section
//! 16): `satsim.fsw.Mekf` wraps [`Mekf`], the same code a scene's `[fsw.estimator]` runs.

use crate::err;
use numpy::{PyArray2, PyArrayMethods, ToPyArray};
use pyo3::prelude::*;
use satsim_spacecraft::fsw::{GyroModel, Mekf, MekfParams, attitude_error};

/// The attitude and gyro-bias MEKF ([`Mekf`]).
#[pyclass(module = "satsim._satsim", name = "NativeMekf")]
pub(crate) struct NativeMekf {
    inner: Mekf,
}

#[pymethods]
impl NativeMekf {
    /// `sigma_v` (rad/s/√Hz), `sigma_u` (rad/s²/√Hz), the initial 1-sigmas, the initial
    /// attitude `[w, x, y, z]` and bias; `sampled`: satsim's sampled-gyro noise model.
    #[new]
    #[pyo3(signature = (sigma_v, sigma_u, sigma_attitude, sigma_bias, q0, bias0, sampled=false))]
    fn new(
        sigma_v: f64,
        sigma_u: f64,
        sigma_attitude: f64,
        sigma_bias: f64,
        q0: [f64; 4],
        bias0: [f64; 3],
        sampled: bool,
    ) -> PyResult<Self> {
        let params = MekfParams {
            sigma_v,
            sigma_u,
            sigma_attitude,
            sigma_bias,
        };
        let model = if sampled {
            GyroModel::Sampled
        } else {
            GyroModel::Continuous
        };
        let inner = Mekf::new(params, q0, bias0)
            .map_err(err)?
            .with_gyro_model(model);
        Ok(Self { inner })
    }
    /// Propagates over `dt` with the gyro reading `omega` held.
    fn propagate(&mut self, omega: [f64; 3], dt: f64) -> PyResult<()> {
        self.inner.propagate(omega, dt).map_err(err)
    }
    /// A star tracker's reading `q` with its 1-sigma `sigma` (rad) about the body's axes.
    fn update_attitude(&mut self, q: [f64; 4], sigma: [f64; 3]) -> PyResult<()> {
        self.inner.update_attitude(q, sigma).map_err(err)
    }
    /// The attitude estimate `[w, x, y, z]`, `w >= 0`.
    #[getter]
    fn attitude(&self) -> [f64; 4] {
        self.inner.attitude()
    }
    /// The bias estimate (rad/s).
    #[getter]
    fn bias(&self) -> [f64; 3] {
        self.inner.bias()
    }
    /// The attitude's 1-sigma about the body's axes (rad).
    #[getter]
    fn sigma_attitude(&self) -> [f64; 3] {
        self.inner.sigma_attitude()
    }
    /// The bias's 1-sigma (rad/s).
    #[getter]
    fn sigma_bias(&self) -> [f64; 3] {
        self.inner.sigma_bias()
    }
    /// The covariance of `[attitude error; bias error]` (6 × 6).
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let c = self.inner.covariance();
        let flat: Vec<f64> = c.iter().flatten().copied().collect();
        flat.to_pyarray(py).reshape([6, 6])
    }
    /// The rate estimate `omega - bias` (rad/s).
    fn rate(&self, omega: [f64; 3]) -> [f64; 3] {
        self.inner.rate(omega)
    }
}

/// The rotation vector `δθ` (rad) with `q_true = q_est ⊗ exp(δθ/2)`.
#[pyfunction(name = "attitude_error")]
pub(crate) fn attitude_error_py(q_est: [f64; 4], q_true: [f64; 4]) -> [f64; 3] {
    attitude_error(q_est, q_true)
}
