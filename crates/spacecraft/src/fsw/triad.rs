//! [`triad`]: the attitude from two vector observations (the TRIAD algorithm), and
//! [`triad_covariance`], the covariance of its error; the safe mode's initial estimate for
//! the [`Mekf`](crate::fsw::Mekf) updated with the same kind of vectors
//! ([`Mekf::update_vector`](crate::fsw::Mekf::update_vector)).
//!
//! # Conventions
//!
//! - Body vectors `b1`, `b2` (a Sun sensor's Sun direction, a magnetometer's field, …) are
//!   measured in the body's axes; `r1`, `r2` are the same directions in the inertial frame
//!   from on-board models (the Sun's ephemeris, a geomagnetic field model). Only directions
//!   matter: the inputs are normalised, so a field in tesla and a unit vector can be mixed.
//! - The result `q` is a Hamilton unit quaternion, **body to inertial**, as the
//!   [`Mekf`](crate::fsw::Mekf)'s and the star tracker's: `R(q) b_i ≈ r_i`.
//! - Its error `δθ` (rad, body axes) is the [`Mekf`](crate::fsw::Mekf)'s:
//!   `q_true = q ⊗ exp(δθ/2)`.
//! - Vector noise (Shuster's measurement model, the [`SunSensor`](crate::sensors::SunSensor)'s
//!   noise): the measured unit vector is the true one turned by a small random rotation
//!   `n ~ N(0, σ² I)` about the body's axes, `b_meas = b + n × b`, an error of covariance
//!   `σ² (I − b bᵀ)`: `σ` (rad) is the 1σ angular error about each axis across `b`. A
//!   magnetometer's additive white noise of `σ_B` (T) per axis on a field of magnitude `|B|`
//!   is, to first order, this with `σ = σ_B/|B|`.
//!
//! # TRIAD
//!
//! With `t1 = b1/|b1|`, `t2 = (b1 × b2)/|b1 × b2|`, `t3 = t1 × t2` and `s1`, `s2`, `s3` the
//! same of `r1`, `r2`:
//!
//! ```text
//! R(q) = [s1 s2 s3] [t1 t2 t3]ᵀ
//! ```
//!
//! so that `R(q) t1 = s1`: the primary `b1` is mapped exactly onto `r1`, and the secondary
//! only fixes the rotation about it (the plane of `b2` onto the plane of `r2`). Put the more
//! accurate vector first (the Sun sensor's, usually).
//!
//! A pair is refused when the sine of the angle between its two vectors is below
//! [`TRIAD_MIN_SIN`] (`1e-3`, 0.057°): that guards the construction against degenerate
//! geometry only; the accuracy near it is very poor (the error about `b1` has the 1σ
//! `σ2/sin θ`, see below), so check [`triad_covariance`] to decide whether an attitude is
//! good enough.
//!
//! # Covariance (Shuster & Oh 1981)
//!
//! Shuster & Oh, *Three-axis attitude determination from vector observations*, J. Guidance
//! and Control 4(1), 1981: for unit `b1`, `b2` with the noises above (`σ1` the primary's,
//! `σ2` the secondary's, independent), the covariance of `δθ` in body axes is, to first order,
//!
//! ```text
//! P = σ1² I + |b1 × b2|⁻² [ (σ2² − σ1²) b1 b1ᵀ + σ1² (b1 · b2)(b1 b2ᵀ + b2 b1ᵀ) ]
//! ```
//!
//! In the frame `e1 = b1`, `e2 = b1 × b2/sin θ`, `e3 = e1 × e2` (`b2 = cos θ e1 − sin θ e3`):
//! across `b1` (`e2`, `e3`) the error is the primary's, variance `σ1²`; about `b1` it is the
//! turn of the plane's normal, `δθ_1 = (c (n2₃ − n1₃) + s n2₁)/s` (`c`, `s` the cosine and
//! sine of `θ`, `nᵢⱼ` the noise rotations' components), of variance `(σ2² + c² σ1²)/s²`
//! and covariance `−c σ1²/s` with `δθ_3`. This is what the formula above says.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// The smallest sine of the angle between the two vectors of a pair (body or reference) that
/// [`triad`] accepts: `1e-3` (0.057°).
pub const TRIAD_MIN_SIN: f64 = 1e-3;

/// The attitude `q` (body to inertial) from two body-frame measurements `b1` (the primary,
/// mapped exactly: `R(q) b1/|b1| = r1/|r1|`) and `b2`, and their inertial references `r1`,
/// `r2` (module documentation). The vectors need not be unit vectors.
///
/// An error when a vector is zero or not finite, or when the two vectors of a pair make an
/// angle whose sine is below [`TRIAD_MIN_SIN`].
///
/// ```
/// use nalgebra::{UnitQuaternion, Vector3};
/// use satsim_spacecraft::fsw::triad;
/// let q = UnitQuaternion::from_euler_angles(0.3, -0.7, 2.0);  // the truth, body to inertial
/// let sun = Vector3::new(1.0, 0.2, -0.1);                     // inertial references
/// let field = Vector3::new(-1.0e-5, 2.5e-5, 1.2e-5);          // (T: only directions count)
/// let (b_sun, b_field) = (q.inverse_transform_vector(&sun), q.inverse_transform_vector(&field));
/// let est = triad(&b_sun, &b_field, &sun, &field).unwrap();
/// assert!(est.angle_to(&q) < 1e-14);
/// assert!(triad(&b_sun, &(b_sun * 2.0), &sun, &field).is_err()); // parallel
/// ```
pub fn triad(
    b1: &Vector3<f64>,
    b2: &Vector3<f64>,
    r1: &Vector3<f64>,
    r2: &Vector3<f64>,
) -> Result<UnitQuaternion<f64>, String> {
    let body = frame(b1, b2, "body")?;
    let reference = frame(r1, r2, "reference")?;
    let m = reference * body.transpose();
    Ok(UnitQuaternion::from_rotation_matrix(
        &Rotation3::from_matrix_unchecked(m),
    ))
}

/// The covariance (rad², body axes) of [`triad`]'s attitude error `δθ` (`q_true = q ⊗
/// exp(δθ/2)`) for the body vectors `b1` (primary) and `b2` (need not be unit vectors) of
/// 1σ angular noises `sigma1` and `sigma2` (rad, about each axis across the vector; module
/// documentation), Shuster & Oh (1981):
///
/// ```text
/// P = σ1² I + |b1 × b2|⁻² [ (σ2² − σ1²) b1 b1ᵀ + σ1² (b1 · b2)(b1 b2ᵀ + b2 b1ᵀ) ]
/// ```
///
/// (`b1`, `b2` normalised). First order in the noises; the entries are not finite for a
/// zero or parallel pair (which [`triad`] refuses).
pub fn triad_covariance(
    b1: &Vector3<f64>,
    b2: &Vector3<f64>,
    sigma1: f64,
    sigma2: f64,
) -> Matrix3<f64> {
    let (u1, u2) = (b1 / b1.norm(), b2 / b2.norm());
    let (v1, v2) = (sigma1 * sigma1, sigma2 * sigma2);
    let s2 = u1.cross(&u2).norm_squared();
    let c = u1.dot(&u2);
    let outer = u1 * u2.transpose();
    Matrix3::identity() * v1
        + (u1 * u1.transpose() * (v2 - v1) + (outer + outer.transpose()) * (v1 * c)) / s2
}

/// The orthonormal triad `[t1 t2 t3]` (columns) of the pair `a`, `b` (`t1 = a/|a|`,
/// `t2 = a × b/|a × b|`, `t3 = t1 × t2`), or an error naming `which` pair.
fn frame(a: &Vector3<f64>, b: &Vector3<f64>, which: &str) -> Result<Matrix3<f64>, String> {
    let unit = |v: &Vector3<f64>, name: &str| {
        let n = v.norm();
        if v.iter().all(|c| c.is_finite()) && n > 0.0 && n.is_finite() {
            Ok(v / n)
        } else {
            Err(format!(
                "the {which} {name} vector must be finite and non-zero, not {:?}",
                <[f64; 3]>::from(*v)
            ))
        }
    };
    let (t1, u2) = (unit(a, "primary")?, unit(b, "secondary")?);
    let cross = t1.cross(&u2);
    let sin = cross.norm();
    if sin < TRIAD_MIN_SIN {
        return Err(format!(
            "the {which} vectors are (nearly) parallel: the sine of their angle is {sin:e}, \
             below {TRIAD_MIN_SIN:e}"
        ));
    }
    let t2 = cross / sin;
    let t3 = t1.cross(&t2);
    Ok(Matrix3::from_columns(&[t1, t2, t3]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fsw::mekf::log_rotation;
    use crate::sensors::Noise;

    /// A random unit quaternion and two random vectors from `noise`'s sample `k`.
    fn random_case(noise: Noise, k: u64) -> (UnitQuaternion<f64>, Vector3<f64>, Vector3<f64>) {
        let mut d = noise.sample(k);
        let q = UnitQuaternion::from_scaled_axis(d.vec3([2.0; 3]));
        (q, d.vec3([1.0; 3]), d.vec3([1.0; 3]))
    }

    /// **Noiseless TRIAD is exact**: 1000 random attitudes and reference pairs (the second
    /// scaled by 3e-5, a field in tesla; pairs with a sine below 0.05 skipped), the angle
    /// between the truth and the estimate below 1e-14 rad; and the primary with the
    /// secondary swapped gives the same attitude.
    #[test]
    fn noiseless_triad_is_exact() {
        let noise = Noise::new(11, 0);
        let mut worst: f64 = 0.0;
        let mut done = 0;
        for k in 0..1000 {
            let (q, r1, r2) = random_case(noise, k);
            let r2 = r2 * 3e-5;
            if r1.normalize().cross(&r2.normalize()).norm() < 0.05 {
                continue;
            }
            let (b1, b2) = (
                q.inverse_transform_vector(&r1),
                q.inverse_transform_vector(&r2),
            );
            for est in [
                triad(&b1, &b2, &r1, &r2).unwrap(),
                triad(&b2, &b1, &r2, &r1).unwrap(),
            ] {
                let err = est.angle_to(&q);
                worst = worst.max(err);
                assert!(err < 1e-14, "case {k}: {err:e}");
            }
            done += 1;
        }
        assert!(done > 950, "{done}");
        println!("{done} cases, worst angle {worst:e} rad");
    }

    /// **The primary is mapped exactly** (to rounding, 1e-15) with noisy measurements
    /// (0.01 rad on the primary, 0.05 rad on the secondary), and the secondary only into the
    /// plane of the references: `R(q) (b1 × b2)` is along `r1 × r2`.
    #[test]
    fn the_primary_is_mapped_exactly() {
        let noise = Noise::new(12, 0);
        for k in 0..200 {
            let (q, r1, r2) = random_case(noise, k);
            if r1.normalize().cross(&r2.normalize()).norm() < 0.05 {
                continue;
            }
            let mut d = noise.sample(10_000 + k);
            let b1 = UnitQuaternion::from_scaled_axis(d.vec3([0.01; 3]))
                * q.inverse_transform_vector(&r1);
            let b2 = UnitQuaternion::from_scaled_axis(d.vec3([0.05; 3]))
                * q.inverse_transform_vector(&r2);
            let est = triad(&b1, &b2, &r1, &r2).unwrap();
            let mapped = est * b1.normalize();
            assert!((mapped - r1.normalize()).norm() < 1e-15, "case {k}");
            let normal = est * b1.cross(&b2).normalize();
            assert!(
                (normal - r1.cross(&r2).normalize()).norm() < 1e-15,
                "case {k}"
            );
            // and the estimate is not the truth (the noise went somewhere).
            assert!(est.angle_to(&q) > 1e-4);
        }
    }

    /// **Degenerate pairs are errors**: a zero, non-finite or parallel (or anti-parallel)
    /// vector in either pair; a sine of 2e-3 passes and 5e-4 does not.
    #[test]
    fn degenerate_pairs_are_errors() {
        let x = Vector3::x();
        let y = Vector3::y();
        let z0 = Vector3::zeros();
        let nan = Vector3::new(f64::NAN, 0.0, 1.0);
        let inf = Vector3::new(0.0, f64::INFINITY, 1.0);
        let huge = Vector3::new(1e200, 1e200, 1e200); // norm overflows
        for bad in [z0, nan, inf, huge] {
            for args in [
                (bad, y, x, y),
                (x, bad, x, y),
                (x, y, bad, y),
                (x, y, x, bad),
            ] {
                let e = triad(&args.0, &args.1, &args.2, &args.3).unwrap_err();
                assert!(e.contains("finite and non-zero"), "{e}");
            }
        }
        let near = |s: f64| Vector3::new((1.0 - s * s).sqrt(), s, 0.0);
        for par in [x * 3.0, -x, near(5e-4)] {
            let e = triad(&x, &par, &x, &y).unwrap_err();
            assert!(e.contains("body vectors are (nearly) parallel"), "{e}");
            let e = triad(&x, &y, &x, &par).unwrap_err();
            assert!(e.contains("reference vectors are (nearly) parallel"), "{e}");
        }
        assert!(triad(&x, &near(2e-3), &x, &near(2e-3)).is_ok());
    }

    /// **The covariance is Shuster & Oh's.** A Monte Carlo of 4000 draws: vectors 60° apart
    /// (in a tilted plane), the primary turned by a random rotation of 1σ 1e-3 rad about each
    /// axis, the secondary of 4e-3 rad; the sample covariance `C` of the error `δθ`
    /// (`q = q̂ ⊗ exp(δθ/2)`):
    ///
    /// - its trace is within 10 % of the formula's `P`;
    /// - in the frame of the vectors (`e1 = b1`, `e2` their normal, `e3 = e1 × e2`) each
    ///   entry is within 4.5 standard errors (`√((P_ii P_jj + P_ij²)/N)`) of `P`'s: across
    ///   the primary the variances are `σ1²`, about it `(σ2² + cos²θ σ1²)/sin²θ`, and the
    ///   `(e1, e3)` covariance is `−cos θ σ1²/sin θ` (8 standard errors from 0);
    /// - the formula with `σ1` and `σ2` swapped fails the trace check, and the formula without
    ///   its `(b1 · b2)` term fails the entry check: the test tells them apart.
    #[test]
    fn the_covariance_is_shuster_and_ohs() {
        let (s1, s2) = (1e-3, 4e-3);
        let q = UnitQuaternion::from_euler_angles(0.4, 1.1, -0.6);
        let r1 = Vector3::new(1.0, 2.0, -0.5);
        let axis = r1.cross(&Vector3::new(0.3, -1.0, 2.0)).normalize();
        let r2 = UnitQuaternion::from_scaled_axis(axis * 60f64.to_radians()) * r1 * 0.7;
        let (b1, b2) = (
            q.inverse_transform_vector(&r1),
            q.inverse_transform_vector(&r2),
        );
        let p = triad_covariance(&b1, &b2, s1, s2);
        let noise = Noise::new(13, 0);
        let n = 4000;
        let mut c = Matrix3::zeros();
        for k in 0..n {
            let mut d = noise.sample(k);
            let m1 = UnitQuaternion::from_scaled_axis(d.vec3([s1; 3])) * b1;
            let m2 = UnitQuaternion::from_scaled_axis(d.vec3([s2; 3])) * b2;
            let est = triad(&m1, &m2, &r1, &r2).unwrap();
            let e = log_rotation(&(est.inverse() * q));
            c += e * e.transpose() / n as f64;
        }
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        let e1 = b1.normalize();
        let e2 = b1.cross(&b2).normalize();
        let e3 = e1.cross(&e2);
        let frame = Matrix3::from_columns(&[e1, e2, e3]);
        let in_frame = |m: &Matrix3<f64>| frame.transpose() * m * frame;
        // The largest |C − P| entry in the frame, in standard errors.
        let worst = |p: &Matrix3<f64>| {
            let (cf, pf) = (in_frame(&c), in_frame(p));
            let mut w: f64 = 0.0;
            for i in 0..3 {
                for j in 0..3 {
                    let se = ((pf[(i, i)] * pf[(j, j)] + pf[(i, j)].powi(2)) / n as f64).sqrt();
                    w = w.max((cf[(i, j)] - pf[(i, j)]).abs() / se);
                }
            }
            w
        };
        println!(
            "formula (vector frame) {:.4e}\nsample {:.4e}\nworst entry {:.2} standard errors",
            in_frame(&p),
            in_frame(&c),
            worst(&p)
        );
        assert!(
            rel(c.trace(), p.trace()) < 0.1,
            "{} vs {}",
            c.trace(),
            p.trace()
        );
        assert!(worst(&p) < 4.5, "{}", worst(&p));
        let th = 60f64.to_radians();
        let pf = in_frame(&p);
        let about = (s2 * s2 + th.cos().powi(2) * s1 * s1) / th.sin().powi(2);
        assert!(rel(pf[(0, 0)], about) < 1e-12);
        assert!(rel(pf[(1, 1)], s1 * s1) < 1e-12 && rel(pf[(2, 2)], s1 * s1) < 1e-12);
        assert!(rel(pf[(0, 2)], -th.cos() * s1 * s1 / th.sin()) < 1e-12);
        assert!(pf[(0, 1)].abs() < 1e-20 && pf[(1, 2)].abs() < 1e-20);

        let swapped = triad_covariance(&b1, &b2, s2, s1);
        assert!(rel(c.trace(), swapped.trace()) > 0.1);
        let u = e1 * b2.normalize().transpose();
        let dropped = p - (u + u.transpose()) * (s1 * s1 * th.cos() / th.sin().powi(2));
        assert!(worst(&dropped) > 4.5, "{}", worst(&dropped));
        // Scaling the vectors changes nothing.
        let scaled = triad_covariance(&(b1 * 7.0), &(b2 * 3e-5), s1, s2);
        assert!((scaled - p).abs().max() < 1e-18);
    }
}
