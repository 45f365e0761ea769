//! [`Slew`]: shapes a guidance reference so that it moves towards its target within a rate and
//! an acceleration limit (`[fsw.guidance] max_rate`, `max_acceleration`; contract section 16).
//!
//! # What it does
//!
//! The shaper holds the shaped attitude *relative to the target*,
//! `q_e = q_t* ⊗ q_s` (shaped to target; `q_s`, `q_t` body to inertial), and the relative
//! angular velocity `w` of the shaped frame with respect to the target frame (the shaped
//! frame's angular velocity minus the target's, shaped axes, rad/s). At each
//! [`step`](Slew::step) of `dt` seconds it
//!
//! 1. takes the error `e = log(q_e)` (rotation vector, the shorter way round, `θ = |e| ≤ π`);
//! 2. asks for the relative rate `w* = −ê · min(max_rate, U(θ))` along the error's axis,
//!    where `U(θ)` is the largest speed from which steps whose speed falls by
//!    `max_acceleration · dt` each reach the target without passing it (the discrete braking
//!    curve: `U ≈ √(2 a θ) − a dt/2` far out, `U = θ/dt` within `a dt²`; with an infinite
//!    acceleration `U = θ/dt`);
//! 3. moves `w` towards `w*` by at most `max_acceleration · dt` (the vector change, clamped
//!    in norm);
//! 4. turns the relative attitude by the new rate held over the step,
//!    `q_e ← q_e ⊗ exp(w dt)`;
//! 5. returns `q_s = q_t ⊗ q_e` with the *current* target.
//!
//! # What is bounded
//!
//! The motion of the shaped reference **relative to the target**: with `w_k` the relative
//! rate held over step `k` (the shaper's [`relative_rate`](Slew::relative_rate)),
//!
//! - `|w_k| ≤ max(max_rate, |w_0|)`, `w_0` the relative rate at the last reset: from rest, or
//!   from any rate within the limit, the relative rate never exceeds `max_rate`; a faster start
//!   is brought down towards it;
//! - `|w_k − w_(k−1)| ≤ max_acceleration · dt_k`;
//! - the relative attitude turns by exactly `|w_k| dt_k` during the step.
//!
//! The shaped reference's own rate is the target's rate plus `w_k`: a moving target (nadir,
//! a target on the ground) is followed at its own rate, and the limits apply to the slew on
//! top of it. The motion is about the error's axis (an eigenaxis slew relative to the target)
//! when it starts from rest or with a rate along that axis; a transverse starting rate decays
//! by `max_acceleration · dt` per step. From rest the error falls monotonically to zero (the
//! braking curve never lets a step pass the target) and reaches it to rounding in finite
//! time, about `θ/max_rate + max_rate/max_acceleration` for a large slew; it then stays there
//! (the relative rate is zero) without chattering.
//!
//! # The shaped reference
//!
//! `attitude = q_t ⊗ q_e`; `rate = C ω_t + w` (`C` target to shaped axes, `ω_t` the target's
//! rate); `acceleration = C ω̇_t − w × C ω_t + ẇ`, `ẇ = (w_k − w_(k−1))/dt_k` (the
//! derivative of the rate's components in the shaped axes, the same convention as
//! [`Reference`]).
//!
//! # Starting
//!
//! A shaper that has never been [`reset`](Slew::reset) starts at the first target exactly (zero
//! relative rate). After [`reset`](Slew::reset)`(attitude, rate)` (the spacecraft's attitude
//! and body rate now, e.g. at a mode switch), the next step is taken at that same instant: it
//! returns the given attitude and rate (expressed relative to the target it is given) without
//! advancing, and the steps after it advance by their `dt`.
//!
//! ```
//! use nalgebra::{UnitQuaternion, Vector3};
//! use satsim_spacecraft::fsw::{Guidance, Slew};
//! let mut slew = Slew::new(0.02, 1e-3).unwrap();
//! slew.reset(UnitQuaternion::identity(), Vector3::zeros());
//! let target = Guidance::Inertial(UnitQuaternion::from_euler_angles(0.0, 0.0, 1.0))
//!     .reference_at(0.0, None)
//!     .unwrap();
//! let first = slew.step(&target, 0.1);
//! assert_eq!(first.attitude, UnitQuaternion::identity());
//! let mut last = first;
//! for _ in 0..1000 {
//!     let r = slew.step(&target, 0.1);
//!     assert!(r.rate.norm() <= 0.02 * (1.0 + 1e-12));
//!     assert!((r.rate - last.rate).norm() <= 1e-3 * 0.1 * (1.0 + 1e-12));
//!     last = r;
//! }
//! // 1 rad at 0.02 rad/s, 20 s to speed up and slow down: done within 100 s.
//! assert!((last.attitude.inverse() * target.attitude).imag().norm() < 1e-12);
//! ```

use super::guidance::Reference;
use super::mekf::log_rotation;
use nalgebra::{UnitQuaternion, Vector3};

/// A slew shaper (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slew {
    max_rate: f64,
    max_acceleration: f64,
    state: State,
}

/// Where the shaper stands.
#[derive(Clone, Copy, Debug, PartialEq)]
enum State {
    /// Never reset and never stepped: starts at the first target.
    Fresh,
    /// Reset to this attitude (body to inertial) and body rate, at the instant of the next
    /// step.
    Reset {
        attitude: UnitQuaternion<f64>,
        rate: Vector3<f64>,
    },
    /// After a step: the attitude relative to the target (`q_t* ⊗ q_s`), the relative rate
    /// and its derivative over the last step (shaped axes).
    Relative {
        error: UnitQuaternion<f64>,
        rate: Vector3<f64>,
        acceleration: Vector3<f64>,
    },
}

impl Slew {
    /// A shaper within `max_rate` (rad/s) and `max_acceleration` (rad/s²) relative to its
    /// target. Each must be > 0 and not NaN; one of them may be infinite (no limit on it), not
    /// both.
    pub fn new(max_rate: f64, max_acceleration: f64) -> Result<Self, String> {
        for (name, x) in [
            ("max_rate", max_rate),
            ("max_acceleration", max_acceleration),
        ] {
            if x.is_nan() || x <= 0.0 {
                return Err(format!("fsw.guidance: {name} must be > 0 (got {x})"));
            }
        }
        if max_rate.is_infinite() && max_acceleration.is_infinite() {
            return Err(
                "fsw.guidance: max_rate and max_acceleration cannot both be unlimited".into(),
            );
        }
        Ok(Self {
            max_rate,
            max_acceleration,
            state: State::Fresh,
        })
    }

    /// The rate limit (rad/s).
    pub fn max_rate(&self) -> f64 {
        self.max_rate
    }
    /// The acceleration limit (rad/s²).
    pub fn max_acceleration(&self) -> f64 {
        self.max_acceleration
    }

    /// Starts again from `attitude` (body to inertial) turning at `rate` (body axes, rad/s):
    /// the spacecraft's state now. The next [`step`](Slew::step) is taken at this instant
    /// and returns them. A state that is not finite makes the shaper start at the next target
    /// instead, as one never reset.
    pub fn reset(&mut self, attitude: UnitQuaternion<f64>, rate: Vector3<f64>) {
        let finite = attitude
            .coords
            .iter()
            .chain(rate.iter())
            .all(|x| x.is_finite());
        self.state = if finite {
            State::Reset { attitude, rate }
        } else {
            State::Fresh
        };
    }

    /// The relative rate held over the last step (shaped axes, rad/s), `None` before the first
    /// step.
    pub fn relative_rate(&self) -> Option<Vector3<f64>> {
        match self.state {
            State::Relative { rate, .. } => Some(rate),
            _ => None,
        }
    }

    /// The angle (rad) between the shaped reference and the target at the last step, `None`
    /// before the first step.
    pub fn remaining_angle(&self) -> Option<f64> {
        match self.state {
            State::Relative { error, .. } => Some(log_rotation(&error).norm()),
            _ => None,
        }
    }

    /// The shaped reference at the instant of `target` (the target reference there), `dt`
    /// seconds after the previous step (see the module page). A `dt` that is not finite and
    /// > 0 advances nothing (the shaped reference is carried along with the target).
    pub fn step(&mut self, target: &Reference, dt: f64) -> Reference {
        let (error, rate, acceleration) = match self.state {
            State::Fresh => {
                self.state = State::Relative {
                    error: UnitQuaternion::identity(),
                    rate: Vector3::zeros(),
                    acceleration: Vector3::zeros(),
                };
                return *target;
            }
            State::Reset { attitude, rate } => {
                let error = target.attitude.inverse() * attitude;
                let c_rate = error.inverse_transform_vector(&target.rate);
                let w = rate - c_rate;
                self.state = State::Relative {
                    error,
                    rate: w,
                    acceleration: Vector3::zeros(),
                };
                return Reference {
                    attitude,
                    rate,
                    acceleration: error.inverse_transform_vector(&target.acceleration)
                        - w.cross(&c_rate),
                };
            }
            State::Relative {
                error,
                rate,
                acceleration,
            } => {
                if dt.is_finite() && dt > 0.0 {
                    self.advance(error, rate, dt)
                } else {
                    (error, rate, acceleration)
                }
            }
        };
        self.state = State::Relative {
            error,
            rate,
            acceleration,
        };
        let c_rate = error.inverse_transform_vector(&target.rate);
        Reference {
            attitude: target.attitude * error,
            rate: c_rate + rate,
            acceleration: error.inverse_transform_vector(&target.acceleration)
                - rate.cross(&c_rate)
                + acceleration,
        }
    }

    /// One step of the law from the relative attitude `error` and rate `w`: the new relative
    /// attitude, rate and the rate's change per second.
    fn advance(
        &self,
        error: UnitQuaternion<f64>,
        w: Vector3<f64>,
        dt: f64,
    ) -> (UnitQuaternion<f64>, Vector3<f64>, Vector3<f64>) {
        let e = log_rotation(&error);
        let theta = e.norm();
        let desired = if theta > 0.0 {
            let speed = self
                .max_rate
                .min(braking_speed(theta, self.max_acceleration, dt));
            e * (-speed / theta)
        } else {
            Vector3::zeros()
        };
        let mut change = desired - w;
        let limit = self.max_acceleration * dt;
        let n = change.norm();
        if n > limit {
            change *= limit / n;
        }
        let w_new = w + change;
        let mut q = error * UnitQuaternion::from_scaled_axis(w_new * dt);
        q.renormalize();
        (q, w_new, change / dt)
    }
}

/// The largest speed `u` (rad/s) from which steps of `dt` whose speeds fall by `a dt` each
/// (`u`, `u − a dt`, …, down to 0) cover at most `theta`: `dt Σ_j (u − j a dt)⁺ ≤ θ`. With
/// `c = a dt²`, `y = θ/c` and `m` the largest integer with `m (m + 1)/2 ≤ y`,
/// `u = a dt (y/(m + 1) + m/2)`; `θ/dt` for an infinite `a`.
fn braking_speed(theta: f64, a: f64, dt: f64) -> f64 {
    if a.is_infinite() {
        return theta / dt;
    }
    let y = theta / (a * dt * dt);
    if !y.is_finite() {
        return f64::INFINITY;
    }
    let tri = |m: f64| m * (m + 1.0) / 2.0;
    let mut m = ((-1.0 + (1.0 + 8.0 * y).sqrt()) / 2.0).floor().max(0.0);
    for _ in 0..4 {
        if m > 0.0 && tri(m) > y {
            m -= 1.0;
        } else if tri(m + 1.0) <= y {
            m += 1.0;
        } else {
            break;
        }
    }
    a * dt * (y / (m + 1.0) + m / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::OrbitState;
    use crate::fsw::Guidance;
    use nalgebra::Rotation3;
    use satsim_environment::MU_EARTH;

    fn angle(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
        log_rotation(&(a.inverse() * b)).norm()
    }

    /// The relative rate of a shaped reference with respect to its target (shaped axes),
    /// from the two references alone.
    fn relative(shaped: &Reference, target: &Reference) -> Vector3<f64> {
        let error = target.attitude.inverse() * shaped.attitude;
        shaped.rate - error.inverse_transform_vector(&target.rate)
    }

    /// Runs `slew` after the targets `targets(k)` at steps of `dt`, checking the bounds at each
    /// step; the last `settle` steps must all be within `tol` of the target. Returns the shaped
    /// references.
    fn run(
        slew: &mut Slew,
        targets: impl Fn(usize) -> Reference,
        dt: f64,
        steps: usize,
        settle: usize,
        tol: f64,
    ) -> Vec<Reference> {
        let (rmax, amax) = (slew.max_rate(), slew.max_acceleration());
        let mut out: Vec<Reference> = Vec::new();
        let mut last: Option<(Reference, Reference)> = None;
        for k in 0..steps {
            let target = targets(k);
            let shaped = slew.step(&target, dt);
            assert!(shaped.attitude.coords.iter().all(|x| x.is_finite()));
            let w = relative(&shaped, &target);
            assert!(
                w.norm() <= rmax * (1.0 + 1e-12),
                "step {k}: |w| = {}",
                w.norm()
            );
            if let Some((ps, pt)) = last {
                let w0 = relative(&ps, &pt);
                assert!(
                    (w - w0).norm() <= amax * dt * (1.0 + 1e-9),
                    "step {k}: |dw| = {} > {}",
                    (w - w0).norm(),
                    amax * dt
                );
                // The relative attitude turns by |w| dt, no more.
                let (e0, e1) = (
                    pt.attitude.inverse() * ps.attitude,
                    target.attitude.inverse() * shaped.attitude,
                );
                assert!(angle(&e0, &e1) <= rmax * dt * (1.0 + 1e-9) + 1e-14);
            }
            if k + settle >= steps {
                assert!(
                    angle(&shaped.attitude, &target.attitude) < tol,
                    "step {k}: {}",
                    angle(&shaped.attitude, &target.attitude)
                );
                assert!(w.norm() < 1e-12, "step {k}: settled |w| = {}", w.norm());
            }
            last = Some((shaped, target));
            out.push(shaped);
        }
        out
    }

    fn inertial(q: UnitQuaternion<f64>) -> Reference {
        Guidance::Inertial(q).reference_at(0.0, None).unwrap()
    }

    #[test]
    fn a_quarter_turn_within_the_limits_about_one_axis() {
        let mut slew = Slew::new(0.02, 1e-3).unwrap();
        let start = UnitQuaternion::from_euler_angles(0.2, -0.4, 1.0);
        slew.reset(start, Vector3::zeros());
        let axis = Vector3::new(1.0, 2.0, -0.5).normalize();
        let target = inertial(start * UnitQuaternion::from_scaled_axis(axis * 90f64.to_radians()));
        // π/2 at 0.02 rad/s: 78.5 s cruising plus 20 s; 150 s of margin, settled over 50 s.
        let out = run(&mut slew, |_| target, 0.1, 2000, 500, 1e-12);
        assert_eq!(out[0].attitude, start);
        // Eigenaxis: every shaped attitude lies on the rotation from the start about `axis`.
        for r in &out {
            let turned = log_rotation(&(start.inverse() * r.attitude));
            assert!(turned.cross(&axis).norm() < 1e-12);
        }
        // The cruise reaches the limit and the whole slew takes about the time said.
        let peak = out.iter().map(|r| r.rate.norm()).fold(0.0, f64::max);
        assert!((peak - 0.02).abs() < 1e-12);
        let done = out
            .iter()
            .position(|r| angle(&r.attitude, &target.attitude) < 1e-9)
            .unwrap();
        let ideal = 90f64.to_radians() / 0.02 + 0.02 / 1e-3;
        assert!((done as f64 * 0.1 - ideal).abs() < 1.0, "{done}");
        // The shaped acceleration is the rate's step change over dt.
        for w in out.windows(2) {
            assert!((w[1].acceleration - (w[1].rate - w[0].rate) / 0.1).norm() < 1e-12);
        }
    }

    #[test]
    fn half_turns_and_a_fresh_shaper() {
        for deg in [179.9, 180.0] {
            let mut slew = Slew::new(0.05, 2e-3).unwrap();
            slew.reset(UnitQuaternion::identity(), Vector3::zeros());
            let target = inertial(UnitQuaternion::from_scaled_axis(
                Vector3::new(0.0, 0.6, 0.8) * f64::to_radians(deg),
            ));
            run(&mut slew, |_| target, 0.25, 1200, 300, 1e-12);
        }
        // Never reset: the first target exactly, and it follows the target from there.
        let mut slew = Slew::new(0.05, 2e-3).unwrap();
        let t0 = inertial(UnitQuaternion::from_euler_angles(1.0, 0.5, -2.0));
        assert_eq!(slew.step(&t0, 0.1), t0);
        assert_eq!(slew.remaining_angle(), Some(0.0));
        let t1 = inertial(UnitQuaternion::identity());
        let first = slew.step(&t1, 0.1);
        assert!(first.rate.norm() <= 2e-3 * 0.1 * (1.0 + 1e-12));
        // The limits are checked.
        assert!(Slew::new(0.0, 1.0).is_err());
        assert!(Slew::new(f64::NAN, 1.0).is_err());
        assert!(Slew::new(1.0, -1.0).is_err());
        assert!(Slew::new(f64::INFINITY, f64::INFINITY).is_err());
        // One unlimited: rate only (reached in one step when the error allows), or
        // acceleration only.
        let mut slew = Slew::new(f64::INFINITY, 1e-3).unwrap();
        slew.reset(UnitQuaternion::identity(), Vector3::zeros());
        let target = inertial(UnitQuaternion::from_scaled_axis(Vector3::x() * 2.0));
        run(&mut slew, |_| target, 0.1, 1500, 200, 1e-12);
        let mut slew = Slew::new(0.1, f64::INFINITY).unwrap();
        slew.reset(UnitQuaternion::identity(), Vector3::zeros());
        run(&mut slew, |_| target, 0.1, 300, 50, 1e-12);
    }

    /// An eccentric inclined orbit carried `t` seconds by RK4 (1/8 s steps from its start).
    fn orbit_at(t: f64) -> OrbitState {
        let (rp, e) = (6.9e6, 0.05);
        let r = Vector3::new(rp, 0.0, 0.0);
        let v = Vector3::new(0.0, 0.6, 0.8) * (MU_EARTH * (1.0 + e) / rp).sqrt();
        let f = |r: &Vector3<f64>| -MU_EARTH * r / r.norm().powi(3);
        let n = (t * 8.0).round() as usize;
        let h = if n == 0 { 0.0 } else { t / n as f64 };
        let (mut r, mut v) = (r, v);
        for _ in 0..n {
            let (k1r, k1v) = (v, f(&r));
            let (k2r, k2v) = (v + h / 2.0 * k1v, f(&(r + h / 2.0 * k1r)));
            let (k3r, k3v) = (v + h / 2.0 * k2v, f(&(r + h / 2.0 * k2r)));
            let (k4r, k4v) = (v + h * k3v, f(&(r + h * k3r)));
            r += h / 6.0 * (k1r + 2.0 * k2r + 2.0 * k3r + k4r);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        OrbitState { r, v, mu: MU_EARTH }
    }

    #[test]
    fn follows_a_moving_nadir_target_and_restarts_mid_slew() {
        let dt = 0.5;
        let steps = 1200;
        let orbits: Vec<OrbitState> = {
            let mut o = vec![orbit_at(0.0)];
            for _ in 1..steps {
                let last = *o.last().unwrap();
                // Carry the previous state dt further (4 RK4 substeps).
                let f = |r: &Vector3<f64>| -MU_EARTH * r / r.norm().powi(3);
                let (mut r, mut v) = (last.r, last.v);
                let h = dt / 4.0;
                for _ in 0..4 {
                    let (k1r, k1v) = (v, f(&r));
                    let (k2r, k2v) = (v + h / 2.0 * k1v, f(&(r + h / 2.0 * k1r)));
                    let (k3r, k3v) = (v + h / 2.0 * k2v, f(&(r + h / 2.0 * k2r)));
                    let (k4r, k4v) = (v + h * k3v, f(&(r + h * k3r)));
                    r += h / 6.0 * (k1r + 2.0 * k2r + 2.0 * k3r + k4r);
                    v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
                }
                o.push(OrbitState { r, v, mu: MU_EARTH });
            }
            o
        };
        assert!((orbits[8].r - orbit_at(4.0).r).norm() < 1e-6);
        let law = Guidance::Nadir(UnitQuaternion::identity());
        let targets = |k: usize| law.reference_at(0.0, Some(&orbits[k])).unwrap();
        // From an attitude far from nadir, turning slowly (within the limit).
        let mut slew = Slew::new(0.01, 5e-4).unwrap();
        let start = UnitQuaternion::from_euler_angles(2.0, -0.7, 0.3);
        let w0 = Vector3::new(0.003, -0.002, 0.004);
        slew.reset(start, w0);
        let out = run(&mut slew, targets, dt, steps, 200, 1e-9);
        // The first step is the reset state itself.
        assert_eq!(out[0].attitude, start);
        assert!((out[0].rate - w0).norm() < 1e-15);
        // The shaped acceleration includes the target's and the transport term: compare with
        // the change of the rate's components over the steps while slewing.
        for k in 1..400 {
            let fd = (out[k + 1].rate - out[k].rate) / dt;
            // The acceleration reported for step k+1 is the relative change plus the target's
            // own, to first order in dt.
            assert!(
                (fd - out[k + 1].acceleration).norm() < 2e-3 * 5e-4 + 1e-6,
                "{k}"
            );
        }

        // Restart mid-slew at another state: the next step returns it, then converges.
        let mut slew = Slew::new(0.01, 5e-4).unwrap();
        slew.reset(start, Vector3::zeros());
        for k in 0..100 {
            slew.step(&targets(k), dt);
        }
        assert!(slew.remaining_angle().unwrap() > 0.1);
        let restart = UnitQuaternion::from_euler_angles(-1.0, 0.4, 2.5);
        let w1 = Vector3::new(-0.004, 0.001, 0.0);
        slew.reset(restart, w1);
        let first = slew.step(&targets(100), dt);
        assert!(angle(&first.attitude, &restart) < 1e-15);
        assert!((first.rate - w1).norm() < 1e-15);
        run(&mut slew, |k| targets(k + 101), dt, steps - 101, 200, 1e-9);
        // A non-finite reset starts at the next target.
        slew.reset(restart, Vector3::new(f64::NAN, 0.0, 0.0));
        assert_eq!(slew.step(&targets(5), dt), targets(5));
    }

    #[test]
    fn a_fast_transverse_start_is_brought_within_the_limit() {
        let mut slew = Slew::new(0.02, 1e-3).unwrap();
        let w0 = Vector3::new(0.0, 0.05, 0.0);
        slew.reset(UnitQuaternion::identity(), w0);
        let target = inertial(UnitQuaternion::from_scaled_axis(Vector3::x() * 1.0));
        let dt = 0.1;
        let mut last = slew.step(&target, dt);
        let mut norms = vec![last.rate.norm()];
        for _ in 0..3000 {
            let r = slew.step(&target, dt);
            assert!((r.rate - last.rate).norm() <= 1e-3 * dt * (1.0 + 1e-12));
            assert!(r.rate.norm() <= w0.norm() * (1.0 + 1e-12));
            norms.push(r.rate.norm());
            last = r;
        }
        // Above the limit the relative rate only falls.
        for w in norms.windows(2) {
            if w[0] > 0.02 {
                assert!(w[1] <= w[0] * (1.0 + 1e-12));
            }
        }
        assert!(angle(&last.attitude, &target.attitude) < 1e-12);
        assert!(last.rate.norm() < 1e-12);
        let _ = Rotation3::<f64>::identity();
    }

    #[test]
    fn the_braking_curve_is_the_largest_safe_speed() {
        let (a, dt) = (1e-3, 0.1);
        for theta in [0.0, 1e-9, 5e-6, 1e-5, 1e-4, 3e-3, 0.1, 1.0, 3.0] {
            let u = braking_speed(theta, a, dt);
            let cover = |u: f64| {
                (0..1_000_000)
                    .map(|j| (u - j as f64 * a * dt).max(0.0))
                    .take_while(|&x| x > 0.0)
                    .sum::<f64>()
                    * dt
            };
            assert!(cover(u) <= theta * (1.0 + 1e-12) + 1e-18, "{theta}");
            assert!(cover(u * (1.0 + 1e-9) + 1e-15) > theta, "{theta}");
            assert!(
                (u - ((2.0 * a * theta).sqrt() - a * dt / 2.0)).abs() <= a * dt || theta < 1e-4
            );
        }
        assert!((braking_speed(0.3, f64::INFINITY, 0.1) - 3.0).abs() < 1e-15);
    }
}
