//! [`Gyro`]: a rate gyro, the body's inertial angular velocity in its axes plus a bias and
//! white noise.
//!
//! Reading `k` (at `t_k`): `ω(t_k) + b_k + w_k`, with `w_k ~ N(0, noise_density / √period)`
//! per axis (rad/s; `noise_density` in rad/s/√Hz) and the bias `b_0 = bias`, then
//! `b_{k+1} = b_k + N(0, bias_walk · √period)` per axis (`bias_walk` in rad/s²/√Hz): the
//! angle random walk and the rate random walk of a gyro's Allan variance.
//!
//! With a scale factor error `s` (a scalar for the three axes, or one per axis) the rate is
//! read as `(1 + s) ∘ ω` (per axis): reading `(1 + s) ∘ ω + b_k + w_k`. `ω`, the bias and
//! the noise are in the sensor's axes (the body's, turned by its
//! [misalignment](super::mounting)).

use super::{Draws, Pose};
use satsim_tree::spatial::Vec3;

/// A rate gyro's noise parameters and its current bias.
#[derive(Clone, Debug, PartialEq)]
pub struct Gyro {
    /// White noise density (rad/s/√Hz).
    pub noise_density: f64,
    /// Bias random walk (rad/s²/√Hz).
    pub bias_walk: f64,
    /// The bias of the next reading (rad/s, sensor axes): the initial one until the first.
    pub bias: Vec3,
    /// The scale factor error `s` per axis (relative: the rate read is `(1 + s) ∘ ω`);
    /// `None`: none (the reading is bit for bit that of a gyro without one).
    pub scale_factor: Option<Vec3>,
}

impl Gyro {
    /// A gyro of white noise `noise_density` (rad/s/√Hz), bias random walk `bias_walk`
    /// (rad/s²/√Hz) and initial bias `bias` (rad/s).
    pub fn new(noise_density: f64, bias_walk: f64, bias: Vec3) -> Self {
        Self {
            noise_density,
            bias_walk,
            bias,
            scale_factor: None,
        }
    }
    /// The same gyro with the scale factor error `s` per axis (relative).
    pub fn with_scale_factor(mut self, s: Vec3) -> Self {
        self.scale_factor = Some(s);
        self
    }
    /// The per-sample standard deviation of the white noise at `period` (rad/s).
    pub fn white_std(&self, period: f64) -> f64 {
        self.noise_density / period.sqrt()
    }
    /// The per-sample standard deviation of the bias step at `period` (rad/s).
    pub fn walk_std(&self, period: f64) -> f64 {
        self.bias_walk * period.sqrt()
    }
    /// The reading (the white noise drawn first).
    pub(super) fn read(&self, pose: &Pose, period: f64, d: &mut Draws, out: &mut [f64; 6]) {
        let s = self.white_std(period);
        let omega = match &self.scale_factor {
            None => pose.omega,
            Some(k) => k.add_scalar(1.0).component_mul(&pose.omega),
        };
        let r = omega + self.bias + d.vec3([s; 3]);
        out[..3].copy_from_slice(r.as_slice());
    }
    /// The bias step after a reading (drawn after its white noise).
    pub(super) fn walk(&mut self, period: f64, d: &mut Draws) {
        let s = self.walk_std(period);
        self.bias += d.vec3([s; 3]);
    }
}
