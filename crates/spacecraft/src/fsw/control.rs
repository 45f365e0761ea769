//! [`Pid`]: the attitude control law of `[fsw.control] kind = "pid"` and its allocation to the
//! reaction wheels (contract section 16).
//!
//! At each control sample (period `T`), with the estimate `q̂` (body to inertial), the
//! estimated rate `ω̂` (the gyro's reading less the estimated bias, body axes) and the
//! reference `q_r`, `ω_r` ([`super::Guidance`], `ω_r` in the reference's axes):
//!
//! ```text
//! e   = log(q_r* ⊗ q̂)                     rotation vector (rad), the shorter way round
//! ω_r,b = R(q̂)ᵀ R(q_r) ω_r                the reference rate in the estimated body axes
//! I  ← clamp(I + e T, ±u_max / ki)         per axis (anti-windup; no clamp where ki = 0)
//! u   = −kp∘e − ki∘I − kd∘(ω̂ − ω_r,b) + ω̂ × (J ω̂)     wanted torque on the body (N m)
//! τ   = −s A⁺ u,  s = min(1, min_j τ_max,j / |(A⁺ u)_j|)   motor torques on the wheels
//! ```
//!
//! `∘` is the per-axis product (the gains are 3-vectors), `J` the optional `inertia` (the
//! gyroscopic feed-forward is left out without it). The wheels apply `−Σ τ_j a_j` to the
//! body: `A = [a_1 … a_k]` holds the wheel axes (body axes), `A⁺` its pseudo-inverse (least
//! squares, the smallest torques), as `[effects.attitude_control]` allocates. `s` scales the
//! whole vector down when a wheel would exceed its `max_torque`, keeping the torque's
//! direction. `u_max` on axis `i` is the largest torque the wheels make about it,
//! `min_j τ_max,j / |A⁺_ji|`. The commands are held until the next sample (zero-order hold);
//! the wheels then apply their own torque and speed limits and their friction.

use super::mekf::log_rotation;
use nalgebra::{DMatrix, Matrix3, UnitQuaternion, Vector3};

/// Whether `j` is a feed-forward inertia [`Pid::new`] takes (kg m², body axes): finite,
/// symmetric and positive definite (a rigid body's, or near enough: a negative diagonal
/// would turn the feed-forward `ω × (J ω)` against the motion).
pub fn inertia_is_valid(j: &[[f64; 3]; 3]) -> bool {
    let m = Matrix3::from_fn(|r, c| j[r][c]);
    m.iter().all(|x| x.is_finite()) && m == m.transpose() && m.cholesky().is_some()
}

/// A least-squares allocation of a body vector `v` over unit axes `a_j` within per-axis
/// limits: `x = s A⁺ v`, `A = [a_1 … a_k]`, `A⁺` its pseudo-inverse (the smallest `x` with
/// `A x = v` when the axes span `v`), `s = min(1, min_j max_j / |(A⁺ v)_j|)` so that the
/// whole vector scales down, keeping its direction, when one entry would exceed its limit.
/// The wheels' torques and the torquers' dipoles are allocated this way.
#[derive(Clone, Debug, PartialEq)]
pub struct Allocation {
    /// `A⁺` (k × 3).
    pinv: DMatrix<f64>,
    /// Each axis' limit, in the same order.
    max: Vec<f64>,
}

impl Allocation {
    /// Over these unit axes (body axes) with these limits (`∞` for none).
    pub fn new(axes: &[Vector3<f64>], max: &[f64]) -> Self {
        let k = axes.len();
        let pinv = if k == 0 {
            DMatrix::zeros(0, 3)
        } else {
            DMatrix::from_fn(3, k, |r, c| axes[c][r])
                .pseudo_inverse(1e-12)
                .unwrap_or_else(|_| DMatrix::zeros(k, 3))
        };
        Self {
            pinv,
            max: max.to_vec(),
        }
    }
    /// The largest `|v_i|` about each body axis `i` within the limits.
    pub fn capability(&self) -> Vector3<f64> {
        Vector3::from_fn(|i, _| {
            (0..self.pinv.nrows()).fold(f64::INFINITY, |m, j| {
                let a = self.pinv[(j, i)].abs();
                if a == 0.0 { m } else { m.min(self.max[j] / a) }
            })
        })
    }
    /// `x = s A⁺ v` into `out` (one entry per axis).
    pub fn solve(&self, v: &Vector3<f64>, out: &mut [f64]) {
        let mut scale: f64 = 1.0;
        for (j, c) in out.iter_mut().enumerate() {
            let row = self.pinv.row(j);
            *c = row[0] * v.x + row[1] * v.y + row[2] * v.z;
            let m = self.max[j];
            if c.abs() > m {
                scale = scale.min(m / c.abs());
            }
        }
        if scale < 1.0 {
            out.iter_mut().for_each(|c| *c *= scale);
        }
    }
    /// Number of axes.
    pub fn len(&self) -> usize {
        self.pinv.nrows()
    }
    /// Whether it has no axes.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The PID's gains and state, and the wheel allocation.
#[derive(Clone, Debug, PartialEq)]
pub struct Pid {
    /// Proportional gains (N m/rad), body axes.
    pub kp: Vector3<f64>,
    /// Integral gains (N m/(rad s)).
    pub ki: Vector3<f64>,
    /// Derivative gains (N m s/rad).
    pub kd: Vector3<f64>,
    /// The inertia of the feed-forward `ω̂ × (J ω̂)` (kg m², body axes), if any.
    pub inertia: Option<Matrix3<f64>>,
    /// `∫ e dt` (rad s).
    integral: Vector3<f64>,
    /// The wheels' torques.
    allocation: Allocation,
    /// The largest torque about each body axis (N m).
    capability: Vector3<f64>,
}

impl Pid {
    /// A law of these gains, with no wheels yet ([`Pid::allocate`]).
    pub fn new(kp: [f64; 3], ki: [f64; 3], kd: [f64; 3], inertia: Option<[[f64; 3]; 3]>) -> Self {
        Self {
            kp: kp.into(),
            ki: ki.into(),
            kd: kd.into(),
            inertia: inertia.map(|m| Matrix3::from_fn(|r, c| m[r][c])),
            integral: Vector3::zeros(),
            allocation: Allocation::new(&[], &[]),
            capability: Vector3::repeat(f64::INFINITY),
        }
    }

    /// Sets the wheels: unit axes (body axes) and torque limits (N m, `∞` for none).
    pub fn allocate(&mut self, axes: &[Vector3<f64>], max_torque: &[f64]) {
        self.allocation = Allocation::new(axes, max_torque);
        self.capability = self.allocation.capability();
    }

    /// Sets the largest torque about each body axis (N m, the integral's clamp) where the
    /// actuator is not the wheels ([`Pid::allocate`] works it out for them).
    pub fn set_capability(&mut self, capability: [f64; 3]) {
        self.capability = capability.into();
    }

    /// Starts afresh: the integral back to zero.
    pub fn reset(&mut self) {
        self.integral = Vector3::zeros();
    }

    /// The largest torque the wheels make about each body axis (N m).
    pub fn capability(&self) -> [f64; 3] {
        self.capability.into()
    }

    /// `∫ e dt` so far (rad s).
    pub fn integral(&self) -> [f64; 3] {
        self.integral.into()
    }

    /// One sample: the wanted body torque `u` (N m, body axes) from the estimate `q_est`
    /// and rate `omega_est` (body axes), the reference `q_ref` and rate `omega_ref` (its own
    /// axes), over the sample period `dt` (the integral's step).
    pub fn torque(
        &mut self,
        q_est: &UnitQuaternion<f64>,
        omega_est: &Vector3<f64>,
        q_ref: &UnitQuaternion<f64>,
        omega_ref: &Vector3<f64>,
        dt: f64,
    ) -> Vector3<f64> {
        let e = log_rotation(&(q_ref.inverse() * q_est));
        let w_ref = q_est.inverse_transform_vector(&q_ref.transform_vector(omega_ref));
        self.integral += e * dt;
        for i in 0..3 {
            if self.ki[i] > 0.0 && self.capability[i].is_finite() {
                let lim = self.capability[i] / self.ki[i];
                self.integral[i] = self.integral[i].clamp(-lim, lim);
            }
        }
        let mut u = -self.kp.component_mul(&e)
            - self.ki.component_mul(&self.integral)
            - self.kd.component_mul(&(omega_est - w_ref));
        if let Some(j) = &self.inertia {
            u += omega_est.cross(&(j * omega_est));
        }
        u
    }

    /// The wheels' motor commands (N m, one per wheel, into `out`) for the body torque `u`,
    /// scaled down as a whole when one would exceed its limit.
    pub fn commands(&self, u: &Vector3<f64>, out: &mut [f64]) {
        // The wheels apply −Σ τ_j a_j to the body.
        self.allocation.solve(&-u, out);
    }

    /// Number of wheels allocated to.
    pub fn n_wheels(&self) -> usize {
        self.allocation.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axes() -> Vec<Vector3<f64>> {
        vec![Vector3::x(), Vector3::y(), Vector3::z()]
    }

    #[test]
    fn the_law_pushes_back_against_the_error_and_the_rate() {
        let mut pid = Pid::new([2.0; 3], [0.0; 3], [10.0; 3], None);
        pid.allocate(&axes(), &[1.0; 3]);
        let q = UnitQuaternion::from_scaled_axis(Vector3::new(0.01, 0.0, 0.0));
        let w = Vector3::new(0.0, 0.002, 0.0);
        let u = pid.torque(&q, &w, &UnitQuaternion::identity(), &Vector3::zeros(), 0.1);
        assert!((u - Vector3::new(-0.02, -0.02, 0.0)).norm() < 1e-15, "{u}");
        // Orthogonal wheels: each gets minus the torque about its axis.
        let mut c = [0.0; 3];
        pid.commands(&u, &mut c);
        assert!((c[0] - 0.02).abs() < 1e-15 && (c[1] - 0.02).abs() < 1e-15 && c[2] == 0.0);
    }

    #[test]
    fn a_saturated_wheel_scales_the_whole_vector_down() {
        let mut pid = Pid::new([1.0; 3], [0.0; 3], [0.0; 3], None);
        pid.allocate(&axes(), &[0.5, 1.0, 1.0]);
        let mut c = [0.0; 3];
        pid.commands(&Vector3::new(1.0, 0.5, 0.0), &mut c);
        assert_eq!(c, [-0.5, -0.25, 0.0]);
    }

    #[test]
    fn the_integral_is_clamped_to_the_wheels_capability() {
        let mut pid = Pid::new([0.0; 3], [0.1; 3], [0.0; 3], None);
        pid.allocate(&axes(), &[0.2; 3]);
        assert_eq!(pid.capability(), [0.2; 3]);
        let q = UnitQuaternion::from_scaled_axis(Vector3::new(0.5, 0.0, 0.0));
        for _ in 0..1000 {
            pid.torque(
                &q,
                &Vector3::zeros(),
                &UnitQuaternion::identity(),
                &Vector3::zeros(),
                1.0,
            );
        }
        assert!(
            (pid.integral()[0] - 2.0).abs() < 1e-12,
            "{:?}",
            pid.integral()
        );
    }

    #[test]
    fn the_feed_forward_cancels_the_gyroscopic_torque() {
        let j = [[10.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 30.0]];
        let mut pid = Pid::new([0.0; 3], [0.0; 3], [0.0; 3], Some(j));
        let w = Vector3::new(0.1, 0.2, 0.3);
        let u = pid.torque(
            &UnitQuaternion::identity(),
            &w,
            &UnitQuaternion::identity(),
            &w,
            0.1,
        );
        let jm = Matrix3::from_diagonal(&Vector3::new(10.0, 20.0, 30.0));
        assert_eq!(u, w.cross(&(jm * w)));
    }

    #[test]
    fn four_wheels_share_by_least_squares() {
        let s = 1.0 / 3f64.sqrt();
        let mut ax = axes();
        ax.push(Vector3::new(s, s, s));
        let mut pid = Pid::new([0.0; 3], [0.0; 3], [0.0; 3], None);
        pid.allocate(&ax, &[f64::INFINITY; 4]);
        let u = Vector3::new(0.1, -0.2, 0.05);
        let mut c = [0.0; 4];
        pid.commands(&u, &mut c);
        // The bus receives −Σ τ_j a_j = u.
        let got: Vector3<f64> = ax.iter().zip(c).map(|(a, t)| -a * t).sum();
        assert!((got - u).norm() < 1e-14, "{got}");
    }
}
