//! The built-in flight software's blocks, callable from Python on arrays (contract section
//! 16): `satsim.fsw.Mekf` wraps [`Mekf`], the same code a scene's `[fsw.estimator]` runs;
//! `NativeGuidance`, `NativeSlew` and `NativePid` wrap [`Guidance`], [`Slew`] and [`Pid`]
//! (`[fsw.guidance]`, `[fsw.control]`), and the functions TRIAD and the magnetic laws.
//! Bad input is a `satsim.SatsimError` (a `ValueError`) with the Rust message.

use crate::err;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use numpy::{PyArray2, PyArrayMethods, ToPyArray};
use pyo3::prelude::*;
use satsim_environment::parse_epoch;
use satsim_spacecraft::effects::OrbitState;
use satsim_spacecraft::fsw::estimator::MIN_SIGMA;
use satsim_spacecraft::fsw::{
    Guidance, GyroModel, Mekf, MekfParams, Pid, Reference, Slew, attitude_error, bdot_dipole,
    gyro_mean, momentum_dipole, triad, triad_covariance,
};
use satsim_tree::error::Num;
use satsim_tree::io::near_unit_quaternion;

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
    /// Propagates over `dt` with the gyro reading `omega` held; an error (the filter as it
    /// was) where the result is not finite (a rate of 1e200 rad/s).
    fn propagate(&mut self, omega: [f64; 3], dt: f64) -> PyResult<()> {
        let mut next = self.inner.clone();
        next.propagate(omega, dt).map_err(err)?;
        let finite = next.attitude().iter().all(|x| x.is_finite())
            && next.bias().iter().all(|x| x.is_finite())
            && next.covariance().iter().flatten().all(|x| x.is_finite());
        if !finite {
            return Err(err(format!(
                "propagating with omega {omega:?} over dt {dt} gives a non-finite attitude or covariance"
            )));
        }
        self.inner = next;
        Ok(())
    }
    /// A star tracker's reading `q` with its 1-sigma `sigma` (rad) about the body's axes,
    /// each floored at [`MIN_SIGMA`] as a scene's estimator floors them.
    fn update_attitude(&mut self, q: [f64; 4], sigma: [f64; 3]) -> PyResult<()> {
        let mut floored = [0.0; 3];
        for (f, s) in floored.iter_mut().zip(sigma) {
            *f = floored_sigma(s).ok_or_else(|| {
                err(format!(
                    "sigma must be finite numbers >= 0 (rad), not {sigma:?}"
                ))
            })?;
        }
        self.inner.update_attitude(q, floored).map_err(err)
    }
    /// A direction measured in the body's axes, `body`, and its inertial direction
    /// `reference` (any units; both normalised), 1-sigma `sigma` (rad) across it, floored at
    /// [`MIN_SIGMA`] as a scene's estimator floors a Sun sensor's and a magnetometer's.
    fn update_vector(&mut self, body: [f64; 3], reference: [f64; 3], sigma: f64) -> PyResult<()> {
        let floored = floored_sigma(sigma).ok_or_else(|| {
            err(format!(
                "sigma must be a finite number >= 0 (rad), not {sigma}"
            ))
        })?;
        self.inner
            .update_vector(body, reference, floored)
            .map_err(err)
    }
    /// Sets the attitude block of the covariance (rad², body axes), its correlation with the
    /// bias to zero; an error (the filter as it was) unless symmetric positive definite.
    fn set_attitude_covariance(&mut self, p: [[f64; 3]; 3]) -> PyResult<()> {
        let m = Matrix3::from_fn(|r, c| p[r][c]);
        self.inner = self
            .inner
            .clone()
            .with_attitude_covariance(m)
            .map_err(err)?;
        Ok(())
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

/// The rotation vector `δθ` (rad) with `q_true = q_est ⊗ exp(δθ/2)`; the quaternions of any
/// non-zero norm (a quantised star tracker's reading compared with the truth), an error for
/// a zero or non-finite one (for which [`attitude_error`] gives NaN).
#[pyfunction(name = "attitude_error")]
pub(crate) fn attitude_error_py(q_est: [f64; 4], q_true: [f64; 4]) -> PyResult<[f64; 3]> {
    let q_est = nonzero_quaternion("q_est", q_est)?;
    let q_true = nonzero_quaternion("q_true", q_true)?;
    Ok(attitude_error(q_est, q_true))
}

// ---------------------------------------------------------------------------------------
// Helpers: checked conversions from Python's numbers.

/// An update's 1-sigma (rad) floored at [`MIN_SIGMA`], as a scene's estimator floors its
/// sensors' (a sigma near zero leaves the innovation covariance singular once the updates
/// have shrunk the covariance, or destroys it); `None` unless finite and `>= 0`, checked
/// before the floor, which would turn a NaN or a negative sigma into `MIN_SIGMA`.
fn floored_sigma(s: f64) -> Option<f64> {
    (s.is_finite() && s >= 0.0).then(|| s.max(MIN_SIGMA))
}

/// A magnetic law's gain: a finite number > 0, as `[fsw.bdot]` and `[fsw.momentum]` take.
fn positive_gain(gain: f64) -> PyResult<()> {
    if gain.is_finite() && gain > 0.0 {
        Ok(())
    } else {
        Err(err(format!("gain must be a finite number > 0, not {gain}")))
    }
}

fn finite<const N: usize>(name: &str, v: [f64; N]) -> PyResult<[f64; N]> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        Err(err(format!("{name} must be finite, not {v:?}")))
    }
}

/// A quaternion `[w, x, y, z]` of any non-zero norm, as the MEKF takes a star tracker's
/// (a quantised reading is not of unit norm); an error when not finite or zero.
fn nonzero_quaternion(name: &str, q: [f64; 4]) -> PyResult<[f64; 4]> {
    let q = finite(name, q)?;
    if q.iter().all(|x| *x == 0.0) {
        return Err(err(format!(
            "{name} must be a non-zero quaternion [w, x, y, z]"
        )));
    }
    Ok(q)
}

/// A quaternion `[w, x, y, z]` the user gives a block (a guidance law's attitude or offset,
/// the slew's and the controller's attitudes), by a scene's rule ([`near_unit_quaternion`]):
/// within 1e-3 of unit norm normalised, with a `UserWarning` when more than rounding off;
/// refused beyond, so that a quaternion off by a factor is not silently taken for another.
fn written_quaternion(py: Python<'_>, name: &str, q: [f64; 4]) -> PyResult<UnitQuaternion<f64>> {
    let q = finite(name, q)?;
    let ([w, x, y, z], off) = near_unit_quaternion(q).map_err(|m| err(format!("{name}: {m}")))?;
    if let Some(n) = off {
        let message = format!("{name}: quaternion norm {} is not 1; normalised", Num(n));
        let message = std::ffi::CString::new(message).expect("no NUL in the message");
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &message,
            2,
        )?;
    }
    Ok(UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z)))
}

/// `[w, x, y, z]` with `w >= 0`.
fn wxyz(q: &UnitQuaternion<f64>) -> [f64; 4] {
    let c = q.quaternion();
    let s = if c.w < 0.0 { -1.0 } else { 1.0 };
    [s * c.w, s * c.i, s * c.j, s * c.k]
}

fn vector(name: &str, v: [f64; 3]) -> PyResult<Vector3<f64>> {
    Ok(Vector3::from(finite(name, v)?))
}

fn matrix3<'py>(py: Python<'py>, m: &Matrix3<f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    // nalgebra is column-major: copy by rows.
    let flat: Vec<f64> = (0..3)
        .flat_map(|r| (0..3).map(move |c| m[(r, c)]))
        .collect();
    flat.to_pyarray(py).reshape([3, 3])
}

type RefTuple = ([f64; 4], [f64; 3], [f64; 3]);

fn reference_tuple(r: &Reference) -> RefTuple {
    (wxyz(&r.attitude), r.rate.into(), r.acceleration.into())
}

// ---------------------------------------------------------------------------------------
// TRIAD and the small functions.

/// TRIAD: the attitude `[w, x, y, z]` (body to inertial, `w >= 0`) with `R b1 ∥ r1` exactly.
#[pyfunction(name = "triad")]
pub(crate) fn triad_py(
    b1: [f64; 3],
    b2: [f64; 3],
    r1: [f64; 3],
    r2: [f64; 3],
) -> PyResult<[f64; 4]> {
    let q = triad(&b1.into(), &b2.into(), &r1.into(), &r2.into()).map_err(err)?;
    Ok(wxyz(&q))
}

/// TRIAD's attitude-error covariance (rad², body axes), Shuster & Oh (1981).
#[pyfunction(name = "triad_covariance")]
pub(crate) fn triad_covariance_py<'py>(
    py: Python<'py>,
    b1: [f64; 3],
    b2: [f64; 3],
    sigma1: f64,
    sigma2: f64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    for (name, s) in [("sigma1", sigma1), ("sigma2", sigma2)] {
        if !(s.is_finite() && s >= 0.0) {
            return Err(err(format!("{name} must be a finite number >= 0, not {s}")));
        }
    }
    let (b1, b2) = (Vector3::from(b1), Vector3::from(b2));
    // The same refusals as TRIAD's (zero, non-finite or parallel vectors): the pair checked
    // against itself as the reference.
    triad(&b1, &b2, &b1, &b2).map_err(err)?;
    matrix3(py, &triad_covariance(&b1, &b2, sigma1, sigma2))
}

/// The trapezoidal mean of two gyro readings (rad/s).
#[pyfunction(name = "gyro_mean")]
pub(crate) fn gyro_mean_py(before: [f64; 3], after: [f64; 3]) -> PyResult<[f64; 3]> {
    let (before, after) = (finite("before", before)?, finite("after", after)?);
    Ok(gyro_mean(&before, &after))
}

/// `−k (b − b_prev) / dt` (A m²).
#[pyfunction(name = "bdot_dipole")]
pub(crate) fn bdot_dipole_py(
    gain: f64,
    b_prev: [f64; 3],
    b: [f64; 3],
    dt: f64,
) -> PyResult<[f64; 3]> {
    positive_gain(gain)?;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(err(format!("dt must be a finite number > 0, not {dt}")));
    }
    let (bp, b) = (vector("b_prev", b_prev)?, vector("b", b)?);
    Ok(bdot_dipole(gain, &bp, &b, dt).into())
}

/// `k (h × b) / |b|²` (A m²), zero where `b` is zero.
#[pyfunction(name = "momentum_dipole")]
pub(crate) fn momentum_dipole_py(gain: f64, h: [f64; 3], b: [f64; 3]) -> PyResult<[f64; 3]> {
    positive_gain(gain)?;
    let (h, b) = (vector("h", h)?, vector("b", b)?);
    Ok(momentum_dipole(gain, &h, &b).into())
}

// ---------------------------------------------------------------------------------------
// Guidance.

/// A guidance law ([`Guidance`]).
#[pyclass(module = "satsim._satsim", name = "NativeGuidance", frozen)]
pub(crate) struct NativeGuidance {
    inner: Guidance,
}

#[pymethods]
impl NativeGuidance {
    #[staticmethod]
    fn inertial(py: Python<'_>, q: [f64; 4]) -> PyResult<Self> {
        Ok(Self {
            inner: Guidance::Inertial(written_quaternion(py, "q", q)?),
        })
    }
    #[staticmethod]
    fn nadir(py: Python<'_>, offset: [f64; 4]) -> PyResult<Self> {
        Ok(Self {
            inner: Guidance::Nadir(written_quaternion(py, "offset", offset)?),
        })
    }
    #[staticmethod]
    fn sun(axis: [f64; 3], secondary: [f64; 3], epoch: &str) -> PyResult<Self> {
        let epoch = parse_epoch(epoch).map_err(|m| err(format!("epoch: {m}")))?;
        Ok(Self {
            inner: Guidance::sun(axis.into(), secondary.into(), epoch).map_err(err)?,
        })
    }
    #[staticmethod]
    fn target(
        latitude_deg: f64,
        longitude_deg: f64,
        altitude: f64,
        axis: [f64; 3],
        secondary: [f64; 3],
        epoch: &str,
    ) -> PyResult<Self> {
        let epoch = parse_epoch(epoch).map_err(|m| err(format!("epoch: {m}")))?;
        Ok(Self {
            inner: Guidance::target(
                latitude_deg,
                longitude_deg,
                altitude,
                axis.into(),
                secondary.into(),
                epoch,
            )
            .map_err(err)?,
        })
    }
    /// Whether the law needs the orbit (`r`, `v`).
    #[getter]
    fn needs_orbit(&self) -> bool {
        self.inner.needs_orbit()
    }
    /// The law's kind: "inertial", "nadir", "sun" or "target".
    #[getter]
    fn kind(&self) -> &'static str {
        match self.inner {
            Guidance::Inertial(_) => "inertial",
            Guidance::Nadir(_) => "nadir",
            Guidance::Sun { .. } => "sun",
            Guidance::Target { .. } => "target",
        }
    }
    /// `(attitude [w, x, y, z], rate, acceleration)` at `t` (s from the epoch) where the
    /// orbit is `r`, `v` (GCRF, m, m/s), `mu` (m³/s²).
    #[pyo3(signature = (t, r=None, v=None, mu=3.986004418e14))]
    fn reference(
        &self,
        t: f64,
        r: Option<[f64; 3]>,
        v: Option<[f64; 3]>,
        mu: f64,
    ) -> PyResult<RefTuple> {
        if !t.is_finite() {
            return Err(err(format!("t must be finite, not {t}")));
        }
        let orbit = match (r, v) {
            (Some(r), Some(v)) => {
                let (r, v) = (vector("r", r)?, vector("v", v)?);
                // The orbital frame is along r and across r × v: neither may vanish.
                if self.inner.needs_orbit() {
                    if r.norm() == 0.0 {
                        return Err(err("r is zero: the orbit's position fixes the frame"));
                    }
                    if r.cross(&v).norm() <= 1e-12 * r.norm() * v.norm() || v.norm() == 0.0 {
                        return Err(err(format!(
                            "v {:?} is zero or parallel to r {:?}: the orbit normal r × v is undefined",
                            <[f64; 3]>::from(v),
                            <[f64; 3]>::from(r)
                        )));
                    }
                }
                Some(OrbitState { r, v, mu })
            }
            (None, None) => None,
            _ => return Err(err("give both r and v, or neither")),
        };
        let reference = self.inner.reference_at(t, orbit.as_ref()).map_err(err)?;
        Ok(reference_tuple(&reference))
    }
}

// ---------------------------------------------------------------------------------------
// Slew.

/// The slew shaper ([`Slew`]).
#[pyclass(module = "satsim._satsim", name = "NativeSlew")]
pub(crate) struct NativeSlew {
    inner: Slew,
}

#[pymethods]
impl NativeSlew {
    #[new]
    fn new(max_rate: f64, max_acceleration: f64) -> PyResult<Self> {
        Ok(Self {
            inner: Slew::new(max_rate, max_acceleration).map_err(err)?,
        })
    }
    fn reset(&mut self, py: Python<'_>, attitude: [f64; 4], rate: [f64; 3]) -> PyResult<()> {
        let q = written_quaternion(py, "attitude", attitude)?;
        let w = vector("the rate", rate)?;
        self.inner.reset(q, w);
        Ok(())
    }
    fn step(
        &mut self,
        py: Python<'_>,
        attitude: [f64; 4],
        rate: [f64; 3],
        acceleration: [f64; 3],
        dt: f64,
    ) -> PyResult<RefTuple> {
        let target = Reference {
            attitude: written_quaternion(py, "the reference's attitude", attitude)?,
            rate: vector("the reference's rate", rate)?,
            acceleration: vector("the reference's acceleration", acceleration)?,
        };
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(err(format!("dt must be a finite number >= 0, not {dt}")));
        }
        Ok(reference_tuple(&self.inner.step(&target, dt)))
    }
    #[getter]
    fn max_rate(&self) -> f64 {
        self.inner.max_rate()
    }
    #[getter]
    fn max_acceleration(&self) -> f64 {
        self.inner.max_acceleration()
    }
    #[getter]
    fn relative_rate(&self) -> Option<[f64; 3]> {
        self.inner.relative_rate().map(Into::into)
    }
    #[getter]
    fn remaining_angle(&self) -> Option<f64> {
        self.inner.remaining_angle()
    }
}

// ---------------------------------------------------------------------------------------
// PID.

/// The attitude PID and its wheel allocation ([`Pid`]).
#[pyclass(module = "satsim._satsim", name = "NativePid")]
pub(crate) struct NativePid {
    inner: Pid,
}

#[pymethods]
impl NativePid {
    #[new]
    #[pyo3(signature = (kp, ki, kd, inertia=None))]
    fn new(
        kp: [f64; 3],
        ki: [f64; 3],
        kd: [f64; 3],
        inertia: Option<[[f64; 3]; 3]>,
    ) -> PyResult<Self> {
        for (name, k) in [("kp", kp), ("ki", ki), ("kd", kd)] {
            if !k.iter().all(|x| x.is_finite() && *x >= 0.0) {
                return Err(err(format!(
                    "{name} must be finite numbers >= 0, not {k:?}"
                )));
            }
        }
        if let Some(j) = inertia
            && !satsim_spacecraft::fsw::inertia_is_valid(&j)
        {
            return Err(err(format!(
                "the inertia must be a symmetric positive definite 3 x 3 matrix of finite numbers (kg m², body axes), not {j:?}"
            )));
        }
        Ok(Self {
            inner: Pid::new(kp, ki, kd, inertia),
        })
    }
    fn allocate(&mut self, axes: Vec<[f64; 3]>, max_torque: Vec<f64>) -> PyResult<()> {
        if axes.len() != max_torque.len() {
            return Err(err(format!(
                "{} wheel axes but {} max_torque values",
                axes.len(),
                max_torque.len()
            )));
        }
        let mut unit = Vec::with_capacity(axes.len());
        for (i, a) in axes.iter().enumerate() {
            let v = vector(&format!("wheel axis {i}"), *a)?;
            let n = v.norm();
            if n == 0.0 {
                return Err(err(format!("wheel axis {i} is zero")));
            }
            unit.push(v / n);
        }
        for (i, m) in max_torque.iter().enumerate() {
            if m.is_nan() || *m <= 0.0 {
                return Err(err(format!(
                    "max_torque of wheel {i} must be > 0 (inf for none), not {m}"
                )));
            }
        }
        self.inner.allocate(&unit, &max_torque);
        Ok(())
    }
    fn reset(&mut self) {
        self.inner.reset();
    }
    fn torque(
        &mut self,
        py: Python<'_>,
        q_est: [f64; 4],
        w_est: [f64; 3],
        q_ref: [f64; 4],
        w_ref: [f64; 3],
        dt: f64,
    ) -> PyResult<[f64; 3]> {
        let qe = written_quaternion(py, "q_est", q_est)?;
        let we = vector("w_est", w_est)?;
        let qr = written_quaternion(py, "q_ref", q_ref)?;
        let wr = vector("w_ref", w_ref)?;
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(err(format!("dt must be a finite number >= 0, not {dt}")));
        }
        Ok(self.inner.torque(&qe, &we, &qr, &wr, dt).into())
    }
    fn commands(&self, u: [f64; 3]) -> PyResult<Vec<f64>> {
        let u = vector("u", u)?;
        let mut out = vec![0.0; self.inner.n_wheels()];
        self.inner.commands(&u, &mut out);
        Ok(out)
    }
    #[getter]
    fn capability(&self) -> [f64; 3] {
        self.inner.capability()
    }
    #[getter]
    fn integral(&self) -> [f64; 3] {
        self.inner.integral()
    }
    #[getter]
    fn n_wheels(&self) -> usize {
        self.inner.n_wheels()
    }
}
