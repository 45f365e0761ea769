//! The estimator block of `[fsw]` (contract section 16): a [`Mekf`] wired to a gyro and to
//! what aids it, clocked by the gyro's samples.
//!
//! # Kinds
//!
//! - **`"mekf"`** ([`Aiding::StarTrackers`]): the MEKF on the gyro and one or more star
//!   trackers (attitude updates). A tracker's sample that its exclusion angles flagged
//!   invalid ([`Sensor::valid`]) is skipped: no update, as if it had not sampled.
//! - **`"sun_mag"`**, the safe mode's ([`Aiding::SunMag`]): the same MEKF updated with two
//!   directions instead, the Sun sensor's Sun direction and the magnetometer's field, against
//!   the on-board models of both at the orbit's position (the Sun's ephemeris of the Sun
//!   sensor's epoch, the magnetometer's field model: the scene's). It starts from the
//!   TRIAD attitude of the two directions (the Sun the primary) at the first gyro sample
//!   where both are read (the Sun lit) and are not nearly parallel
//!   ([`TRIAD_MIN_SIN`](super::triad::TRIAD_MIN_SIN)), with TRIAD's covariance
//!   ([`triad_covariance`]) and bias 0, σ_bias as given;
//!   before that it has no estimate. In eclipse it goes
//!   on the gyro and the field alone: the attitude about the field is then unobservable and
//!   its σ grows, until the Sun comes back.
//!
//! # Timing
//!
//! The estimator runs at each gyro sample `t_k`: it propagates the estimate from `t_{k−1}`
//! with the mean of the gyro's readings at `t_{k−1}` and `t_k` ([`gyro_mean`], the
//! trapezoidal rule), then updates it with each aiding sensor that sampled at `t_k` (in the
//! order listed). The gyro reads the rate at its sample instants: holding one reading over
//! the period would err by `α T²/2` per sample under an angular acceleration `α` (1.5 mrad
//! at 1 Hz for a bus braking at 3e-3 rad/s²), far beyond what a Sun sensor and a
//! magnetometer correct in a few samples; the mean errs by `j T³/12` for a jerk `j`. The
//! filter's process noise is the held reading's ([`GyroModel::Sampled`]): the mean's noise
//! has half its variance per period, correlated from one period to the next, with the
//! same random walk over many (so the filter is, if anything, cautious). The first gyro sample where it can
//! start initialises it (at a star tracker's reading taken there, or at TRIAD), bias 0, covariance
//! `diag(σ_att², σ_bias²)` (no truth), then updates as above. The estimate held between
//! samples is the one of the last sample (after its updates).

use super::mekf::{GyroModel, Mekf, MekfParams};
use super::triad::{triad, triad_covariance};
use crate::effects::OrbitState;
use crate::sensors::{Kind, Sensor};
use nalgebra::Vector3;

/// The least angular 1σ (rad) an estimator's update takes (about 0.2 arcsecond, far below
/// any star tracker's, Sun sensor's or magnetometer's), so that a noiseless sensor's update
/// stays well posed.
pub const MIN_SIGMA: f64 = 1e-6;

/// What aids the gyro.
#[derive(Clone, Debug, PartialEq)]
pub enum Aiding {
    /// Star trackers (indices in the sensor set) and their 1σ noise about the body's x, y, z
    /// (rad), in update order; each update floors them at [`MIN_SIGMA`].
    StarTrackers(Vec<(usize, [f64; 3])>),
    /// A Sun sensor and a magnetometer (indices in the sensor set) and their noise for the
    /// filter's updates. The field's direction has the angular 1σ `field_noise / |B|` of
    /// each reading `B`. Both angular sigmas are floored at [`MIN_SIGMA`] so that an update
    /// stays well posed with noiseless sensors.
    SunMag {
        /// The Sun sensor.
        sun_sensor: usize,
        /// The magnetometer.
        magnetometer: usize,
        /// 1σ of the Sun direction about each axis across it (rad).
        sigma_sun: f64,
        /// 1σ of the magnetometer's noise on each axis (T).
        field_noise: f64,
    },
}

impl Aiding {
    /// The sensors it reads (indices in the set), in update order.
    fn sensors(&self) -> Vec<usize> {
        match self {
            Aiding::StarTrackers(st) => st.iter().map(|s| s.0).collect(),
            Aiding::SunMag {
                sun_sensor,
                magnetometer,
                ..
            } => vec![*sun_sensor, *magnetometer],
        }
    }
}

/// The estimator's wiring: which sensors it reads (indices in the
/// [`Sensors`](crate::sensors::Sensors) set) and its filter's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimatorSpec {
    /// The gyro (index in the sensor set).
    pub gyro: usize,
    /// The gyro's period (s): the filter's propagation step.
    pub period: f64,
    /// What aids the gyro.
    pub aiding: Aiding,
    /// The body whose attitude it estimates (the gyro's, and the aiding sensors').
    pub body: usize,
    /// The filter's noises and initial sigmas.
    pub params: MekfParams,
}

/// An estimator running: the filter as of its last sample.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Estimator {
    pub(crate) spec: EstimatorSpec,
    /// `None` before the first sample that could start it.
    pub(crate) filter: Option<Mekf>,
    /// The gyro reading of the last sample (rad/s), held over the next period.
    pub(crate) gyro: [f64; 3],
    /// The time of the last sample (s).
    pub(crate) t: f64,
    /// The aiding sensors (indices in the set), in update order.
    aids: Vec<usize>,
    /// Samples taken by the gyro and by each aiding sensor, as last seen.
    seen_gyro: u64,
    seen: Vec<u64>,
}

impl Estimator {
    pub(crate) fn new(spec: EstimatorSpec) -> Self {
        let aids = spec.aiding.sensors();
        Self {
            seen: vec![0; aids.len()],
            aids,
            spec,
            filter: None,
            gyro: [0.0; 3],
            t: f64::NEG_INFINITY,
            seen_gyro: 0,
        }
    }

    /// Starts afresh (no estimate) from the sensors' samples so far: it initialises at the
    /// next gyro sample.
    pub(crate) fn reset(&mut self, sensors: &[Sensor]) {
        self.filter = None;
        self.gyro = [0.0; 3];
        self.t = f64::NEG_INFINITY;
        self.seen_gyro = sensors[self.spec.gyro].samples_taken();
        for (s, &i) in self.seen.iter_mut().zip(&self.aids) {
            *s = sensors[i].samples_taken();
        }
    }

    /// The estimated rate (rad/s, body axes): the gyro's last reading less the bias.
    pub(crate) fn rate(&self) -> Option<Vector3<f64>> {
        self.filter
            .as_ref()
            .map(|f| Vector3::from(f.rate(self.gyro)))
    }

    /// Runs after the sensors sampled at `t`: a new gyro sample steps the filter. Whether it
    /// did.
    pub(crate) fn sample(
        &mut self,
        t: f64,
        sensors: &[Sensor],
        orbit: Option<&OrbitState>,
    ) -> Result<bool, String> {
        let g = &sensors[self.spec.gyro];
        if g.samples_taken() <= self.seen_gyro {
            return Ok(false);
        }
        self.seen_gyro = g.samples_taken();
        let gyro = vector(g.last_reading());
        // An aiding sensor's reading counts when it sampled now (since the last look) and
        // the reading is valid (not a star tracker's excluded one, which holds an old one).
        let fresh: Vec<Option<&[f64]>> = self
            .aids
            .iter()
            .zip(&self.seen)
            .map(|(&i, &seen)| {
                (sensors[i].samples_taken() > seen && sensors[i].valid())
                    .then(|| sensors[i].last_reading())
            })
            .collect();
        let result = self.step(t, gyro, &fresh, sensors, orbit);
        for (s, &i) in self.seen.iter_mut().zip(&self.aids) {
            *s = sensors[i].samples_taken();
        }
        result.map(|()| true)
    }

    /// One filter step at `t` on the gyro reading `gyro` and the aiding sensors' fresh
    /// readings (`fresh[k]`: aid `k`'s reading when it sampled at `t`).
    fn step(
        &mut self,
        t: f64,
        gyro: [f64; 3],
        fresh: &[Option<&[f64]>],
        sensors: &[Sensor],
        orbit: Option<&OrbitState>,
    ) -> Result<(), String> {
        let spec = &self.spec;
        if let Some(f) = &mut self.filter {
            f.propagate(gyro_mean(&self.gyro, &gyro), spec.period)?;
        }
        match &spec.aiding {
            Aiding::StarTrackers(trackers) => {
                if self.filter.is_none() {
                    let Some(q0) = fresh.iter().find_map(|r| r.map(quaternion)) else {
                        // Not yet: it starts at a gyro sample where a star tracker sampled.
                        self.gyro = gyro;
                        self.t = t;
                        return Ok(());
                    };
                    self.filter = Some(
                        Mekf::new(spec.params, q0, [0.0; 3])?.with_gyro_model(GyroModel::Sampled),
                    );
                }
                let f = self.filter.as_mut().expect("started above");
                for ((_, sigma), r) in trackers.iter().zip(fresh) {
                    if let Some(r) = r {
                        f.update_attitude(quaternion(r), sigma.map(|s| s.max(MIN_SIGMA)))?;
                    }
                }
            }
            Aiding::SunMag {
                sun_sensor,
                magnetometer,
                sigma_sun,
                field_noise,
            } => {
                let orbit =
                    orbit.ok_or("the Sun and field estimator needs an orbit (an [orbit] table)")?;
                // The Sun sensor reads zeros in umbra: no direction then.
                let sun = fresh[0]
                    .map(vector)
                    .filter(|s| s.iter().any(|x| *x != 0.0))
                    .map(|s| {
                        (
                            Vector3::from(s),
                            sun_reference(&sensors[*sun_sensor], t, orbit),
                        )
                    });
                let field = fresh[1].map(|b| {
                    (
                        Vector3::from(vector(b)),
                        field_reference(&sensors[*magnetometer], t, orbit),
                    )
                });
                if self.filter.is_none() {
                    let (Some((s_b, s_i)), Some((b_b, b_i))) = (&sun, &field) else {
                        // Not yet: both directions are needed to start.
                        self.gyro = gyro;
                        self.t = t;
                        return Ok(());
                    };
                    let s_i = s_i.as_ref().map_err(String::clone)?;
                    let b_i = b_i.as_ref().map_err(String::clone)?;
                    // Nearly parallel directions fix no attitude: wait for the next sample.
                    let Ok(q0) = triad(s_b, b_b, s_i, b_i) else {
                        self.gyro = gyro;
                        self.t = t;
                        return Ok(());
                    };
                    let q = q0.quaternion();
                    // The attitude's covariance is TRIAD's (Shuster and Oh 1981) for the
                    // two readings' noise.
                    let p0 = triad_covariance(
                        s_b,
                        b_b,
                        sigma_sun.max(MIN_SIGMA),
                        (field_noise / b_b.norm()).max(MIN_SIGMA),
                    );
                    self.filter = Some(
                        Mekf::new(spec.params, [q.w, q.i, q.j, q.k], [0.0; 3])?
                            .with_gyro_model(GyroModel::Sampled)
                            .with_attitude_covariance(p0)?,
                    );
                }
                let f = self.filter.as_mut().expect("started above");
                if let Some((s_b, s_i)) = sun {
                    f.update_vector(s_b.into(), s_i?.into(), sigma_sun.max(MIN_SIGMA))?;
                }
                if let Some((b_b, b_i)) = field {
                    let sigma = (field_noise / b_b.norm()).max(MIN_SIGMA);
                    f.update_vector(b_b.into(), b_i?.into(), sigma)?;
                }
            }
        }
        self.gyro = gyro;
        self.t = t;
        Ok(())
    }
}

/// The on-board Sun direction (inertial, unit) at `t` from the orbit's position: the Sun
/// sensor's ephemeris.
fn sun_reference(s: &Sensor, t: f64, orbit: &OrbitState) -> Result<Vector3<f64>, String> {
    let Kind::SunSensor(sun) = s.kind() else {
        return Err(format!("sensor `{}` is not a Sun sensor", s.name()));
    };
    Ok((satsim_environment::sun::sun_position(sun.epoch, t) - orbit.r).normalize())
}

/// The on-board field (inertial, T) at `t` at the orbit's position: the magnetometer's model.
fn field_reference(s: &Sensor, t: f64, orbit: &OrbitState) -> Result<Vector3<f64>, String> {
    let Kind::Magnetometer(m) = s.kind() else {
        return Err(format!("sensor `{}` is not a magnetometer", s.name()));
    };
    Ok(m.field.field_gcrf(t, &orbit.r))
}

/// The rate the filter propagates with over a gyro period: the mean of the readings at its
/// two ends (the trapezoidal rule).
pub fn gyro_mean(before: &[f64; 3], after: &[f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| 0.5 * (before[i] + after[i]))
}

fn quaternion(r: &[f64]) -> [f64; 4] {
    [r[0], r[1], r[2], r[3]]
}

fn vector(r: &[f64]) -> [f64; 3] {
    [r[0], r[1], r[2]]
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A gyro (sensor 0) and a star tracker (sensor 1) at 10 Hz.
    pub(crate) fn spec() -> EstimatorSpec {
        EstimatorSpec {
            gyro: 0,
            period: 0.1,
            aiding: Aiding::StarTrackers(vec![(1, [1e-5; 3])]),
            body: 0,
            params: MekfParams {
                sigma_v: 1e-5,
                sigma_u: 1e-7,
                sigma_attitude: 0.01,
                sigma_bias: 1e-4,
            },
        }
    }

    #[test]
    fn the_first_step_starts_at_the_first_tracker_reading_then_updates_with_it() {
        let spec = spec();
        let mut e = Estimator::new(spec.clone());
        let q = [0.6, 0.8, 0.0, 0.0];
        e.step(0.0, [1e-3, 0.0, 0.0], &[Some(&q)], &[], None)
            .unwrap();
        let mut want = Mekf::new(spec.params, q, [0.0; 3])
            .unwrap()
            .with_gyro_model(GyroModel::Sampled);
        want.update_attitude(q, [1e-5; 3]).unwrap();
        assert_eq!(e.filter.as_ref(), Some(&want));
        // The next: propagate with the mean of the two readings, then update.
        e.step(0.1, [0.0; 3], &[Some(&q)], &[], None).unwrap();
        want.propagate([5e-4, 0.0, 0.0], 0.1).unwrap();
        want.update_attitude(q, [1e-5; 3]).unwrap();
        assert_eq!(e.filter.as_ref(), Some(&want));
        // No tracker reading at the first sample: no estimate yet, and no error.
        let mut empty = Estimator::new(spec);
        empty.step(0.0, [0.0; 3], &[None], &[], None).unwrap();
        assert!(empty.filter.is_none());
    }

    #[test]
    fn a_star_tracker_reading_flagged_invalid_does_not_update_the_filter() {
        use crate::sensors::star_tracker::Exclusion;
        use crate::sensors::{Gyro, StarTracker};
        let spec = spec();
        let gyro = Gyro::new(1e-5, 1e-7, nalgebra::Vector3::zeros());
        let tracker = StarTracker::from_arcsec([2.0; 3]).with_exclusion(Exclusion {
            sun: None,
            earth: Some(0.3),
        });
        let mut sensors = vec![
            Sensor::new("gyro", 0, 0.1, Kind::Gyro(gyro)).unwrap(),
            Sensor::new("st", 0, 0.1, Kind::StarTracker(tracker)).unwrap(),
        ];
        let q = [0.6, 0.8, 0.0, 0.0];
        let w = [1e-3, 0.0, 0.0];
        let mut e = Estimator::new(spec.clone());
        // Excluded at the first sample: nothing to start from.
        sensors[0].latch(&w, true);
        sensors[1].latch(&q, false);
        assert!(e.sample(0.0, &sensors, None).unwrap());
        assert!(e.filter.is_none());
        // Valid at the next: it starts there, and updates.
        sensors[0].latch(&w, true);
        sensors[1].latch(&q, true);
        assert!(e.sample(0.1, &sensors, None).unwrap());
        let mut want = Mekf::new(spec.params, q, [0.0; 3])
            .unwrap()
            .with_gyro_model(GyroModel::Sampled);
        want.update_attitude(q, [1e-5; 3]).unwrap();
        assert_eq!(e.filter.as_ref(), Some(&want));
        // Excluded again, holding a valid reading: propagation only, no update.
        sensors[0].latch(&w, true);
        sensors[1].latch(&[0.0, 1.0, 0.0, 0.0], false);
        assert_eq!(sensors[1].last_reading(), q);
        assert!(e.sample(0.2, &sensors, None).unwrap());
        want.propagate(w, 0.1).unwrap();
        assert_eq!(e.filter.as_ref(), Some(&want));
        // The same sample valid would have updated it.
        let mut updated = want.clone();
        updated.update_attitude(q, [1e-5; 3]).unwrap();
        assert_ne!(updated, want);
    }
}
