//! What any sensor's reading may add to the ideal one: a [`Misalignment`] of its axes and a
//! [`quantize`]d output.
//!
//! **Misalignment** `r = [rx, ry, rz]` (rad) is a rotation vector: the sensor's axes are the
//! body's turned by `R = exp([r]×)` (the rotation of angle `|r|` about `r / |r|`), so that
//! sensor axis `i` is `R e_i` in body axes. A body-axis vector `v` reads `Rᵀ v` in the
//! sensor's axes; the sensor's frame has the attitude `q ⊗ q_R` (sensor to inertial), `q`
//! the body's (body to inertial) and `q_R` the quaternion of `R` (sensor to body). A sensor
//! reads every quantity in its own (misaligned) axes: the reading of the ideal sensor whose
//! body were the sensor's frame. Without a misalignment (the key absent) the sensor's axes
//! are the body's and no rotation is applied: the readings are bit for bit those of a
//! sensor without the key.
//!
//! **Quantisation** `step > 0`: each value of the reading is rounded to the nearest multiple
//! of `step`, `step · round(x / step)` (halves away from zero), after everything else (the
//! noise included): the output of an analogue-to-digital converter.

use nalgebra::UnitQuaternion;
use satsim_tree::spatial::{Mat3, Vec3};

/// A fixed rotation of a sensor's axes from its body's (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Misalignment {
    /// The rotation vector `r` (rad, body axes).
    pub angles: Vec3,
    /// `q_R`, sensor to body.
    rotation: UnitQuaternion<f64>,
    /// `R`, sensor to body (columns: the sensor's axes in body axes).
    matrix: Mat3,
}

impl Misalignment {
    /// The rotation of vector `angles` (rad): angle `|angles|` about `angles / |angles|`.
    pub fn new(angles: Vec3) -> Self {
        let rotation = UnitQuaternion::from_scaled_axis(angles);
        Self {
            angles,
            matrix: rotation.to_rotation_matrix().into_inner(),
            rotation,
        }
    }
    /// `q_R`, the quaternion of the sensor's frame relative to the body's (sensor to body).
    pub fn rotation(&self) -> &UnitQuaternion<f64> {
        &self.rotation
    }
    /// `R`, sensor to body.
    pub fn matrix(&self) -> &Mat3 {
        &self.matrix
    }
    /// A body-axis vector in the sensor's axes, `Rᵀ v`.
    pub fn to_sensor(&self, v: &Vec3) -> Vec3 {
        self.matrix.tr_mul(v)
    }
    /// A sensor-axis vector in the body's axes, `R v`.
    pub fn to_body(&self, v: &Vec3) -> Vec3 {
        self.matrix * v
    }
}

/// `x` rounded to the nearest multiple of `step` (`step · round(x / step)`, halves away from
/// zero).
///
/// ```
/// use satsim_spacecraft::sensors::mounting::quantize;
/// assert_eq!(quantize(0.26, 0.5), 0.5);
/// assert_eq!(quantize(-0.74, 0.5), -0.5);
/// assert_eq!(quantize(7.0, 2.0), 8.0); // 3.5 steps: away from zero
/// ```
pub fn quantize(x: f64, step: f64) -> f64 {
    (x / step).round() * step
}
