//! [`Onboard`]: a scene's built-in flight software (`[fsw]`, contract section 16), the
//! estimator, guidance and control blocks and the magnetic block (B-dot or momentum
//! dumping) wired to the scene's sensors.
//!
//! # Reading the sensors at the instant they sample
//!
//! The blocks live inside the scene's [`Sensors`](crate::sensors::Sensors) effect
//! ([`Sensors::set_fsw`](crate::sensors::Sensors::set_fsw)): at a sample
//! instant that effect first takes every sensor sample due, then runs the blocks on the
//! readings just taken — the same values the sensors' columns and `measure()` show, noise
//! included — so the flight software never sees the truth and never reads a reading one
//! sample late, whatever order the effects run in. Without `[fsw]` the sensors do exactly what
//! they did (no block, no cost).
//!
//! # Timing (zero-order hold)
//!
//! - **Estimator** ([`EstimatorSpec`], a [`Mekf`] with [`GyroModel::Sampled`]): runs at each
//!   gyro sample `t_k` (its period is the gyro's): it propagates the estimate from `t_{k−1}`
//!   with the gyro reading taken there, held over the period, then updates it with the
//!   reading of each star tracker that sampled at `t_k` (in the order listed). So the filter
//!   does, in turn, update at `t_k`, propagate over `[t_k, t_{k+1}]` with the reading of
//!   `t_k`, update at `t_{k+1}`, …, exactly as a standalone [`Mekf`] driven by the same
//!   readings. The first gyro sample initialises it at the first star tracker's reading,
//!   bias 0, covariance `diag(σ_att², σ_bias²)` (no truth), then updates as above. The
//!   estimate held between samples is the one of the last sample (after its updates).
//! - **Guidance**: evaluated at the control's samples (without a control, at the
//!   estimator's), from the orbit; held in between.
//! - **Control**: at its own samples (`t = 0, period, …`); the estimate it reads is the last
//!   one, turned on to the control instant by the gyro's rate less the estimated bias when
//!   the instant lies between gyro samples. Its wheel commands are held in between.
//!
//! A row written at a sample instant holds what that sample latches (the sensors' readings
//! taken there, the estimate after its update), as the sensors' columns do.
//!
//! # Columns
//!
//! With an estimator: `est_q_w..z` (the estimate, body to inertial, `w >= 0`),
//! `est_bias_x..z` (rad/s), `est_sigma_x..z` (1σ of the attitude error about the body's
//! axes, rad), `est_error` (rad: the angle between the estimate and the true attitude of
//! the estimator's body — a diagnostic, the only place the truth is read). With guidance:
//! `ref_q_w..z`, `ref_omega_x..z` (rad/s, the reference's axes) and `pointing_error` (rad:
//! the angle between the true attitude and the reference). With `[fsw.bdot]` or
//! `[fsw.momentum]` ([`crate::fsw::magnetic`], run at its magnetometer's samples, after the
//! other blocks): `fsw_dipole_x..z` (A m², body axes: the dipole commanded, before the
//! torquers clamp it).

use super::control::Pid;
use super::guidance::{Guidance, Reference};
use super::magnetic::{DipoleBlock, DipoleSpec};
use super::mekf::log_rotation;
use super::mekf::{GyroModel, Mekf, MekfParams};
use crate::effects::{Context, Forces, Links, Needs, OrbitState, Sampling};
use crate::sensors::{Pose, Sensor};
use nalgebra::{UnitQuaternion, Vector3};
use satsim_integrate::{SystemError, stop_due};

/// The estimator's wiring: which sensors it reads (indices in the
/// [`Sensors`](crate::sensors::Sensors) set) and its
/// filter's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimatorSpec {
    /// The gyro (index in the sensor set).
    pub gyro: usize,
    /// The gyro's period (s): the filter's propagation step.
    pub period: f64,
    /// The star trackers (indices in the sensor set) and their 1σ noise about the body's
    /// x, y, z (rad), in update order.
    pub star_trackers: Vec<(usize, [f64; 3])>,
    /// The body whose attitude it estimates (the gyro's, and the trackers').
    pub body: usize,
    /// The filter's noises and initial sigmas.
    pub params: MekfParams,
}

/// The filter between samples: what a row at a sample instant recomputes from a copy.
#[derive(Clone, Debug, PartialEq)]
struct Estimate {
    /// `None` before the first gyro sample.
    filter: Option<Mekf>,
    /// The gyro reading of the last sample (rad/s), held over the next period.
    gyro: [f64; 3],
    /// The time of the last sample (s).
    t: f64,
}

#[derive(Clone, Debug, PartialEq)]
struct Estimator {
    spec: EstimatorSpec,
    state: Estimate,
    /// Samples taken by the gyro and by each tracker, as last seen.
    seen_gyro: u64,
    seen: Vec<u64>,
}

impl Estimator {
    /// One filter step at `t` on the gyro reading `gyro` and the trackers' readings
    /// (`reading(k)`: tracker `k`'s reading when it sampled at `t`).
    fn step(
        spec: &EstimatorSpec,
        state: &mut Estimate,
        t: f64,
        gyro: [f64; 3],
        reading: impl Fn(usize) -> Option<[f64; 4]>,
    ) -> Result<(), String> {
        let f = match &mut state.filter {
            Some(f) => {
                f.propagate(state.gyro, spec.period)?;
                f
            }
            None => {
                let q0 = (0..spec.star_trackers.len())
                    .find_map(&reading)
                    .ok_or("no star tracker reading at the first gyro sample to start from")?;
                state.filter.insert(
                    Mekf::new(spec.params, q0, [0.0; 3])?.with_gyro_model(GyroModel::Sampled),
                )
            }
        };
        for (k, (_, sigma)) in spec.star_trackers.iter().enumerate() {
            if let Some(q) = reading(k) {
                f.update_attitude(q, *sigma)?;
            }
        }
        state.gyro = gyro;
        state.t = t;
        Ok(())
    }
}

/// Where the control's commands go and how it is timed.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlSpec {
    /// The law.
    pub pid: Pid,
    /// Sample period (s).
    pub period: f64,
    /// The wheels it commands: rotor names (`wheel_<name>`) and `max_torque` (N m).
    pub wheels: Vec<(String, f64)>,
}

#[derive(Clone, Debug, PartialEq)]
struct Control {
    pid: Pid,
    clock: Sampling,
    wheels: Vec<(String, f64)>,
    /// Rotor index (tree order, after the model's hinges) of each wheel, from `connect`.
    rotor: Vec<usize>,
    /// The motor commands held (one per rotor of the tree).
    held: Vec<f64>,
    /// The commands of the wheels, in `wheels` order (room for one sample's).
    scratch: Vec<f64>,
    /// The body torque wanted at the last sample (N m, body axes).
    torque: Vector3<f64>,
}

/// A scene's flight software: see the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct Onboard {
    estimator: Option<Estimator>,
    guidance: Option<(Guidance, Option<Reference>)>,
    control: Option<Control>,
    /// `[fsw.bdot]` or `[fsw.momentum]`.
    magnetic: Option<DipoleBlock>,
}

impl Onboard {
    /// Blocks: an estimator, a guidance law (it needs the estimator: its clock and the body
    /// it points), a control (it needs both). `None` when a block lacks what it needs.
    pub fn new(
        estimator: Option<EstimatorSpec>,
        guidance: Option<Guidance>,
        control: Option<ControlSpec>,
    ) -> Option<Self> {
        if (guidance.is_some() && estimator.is_none()) || (control.is_some() && guidance.is_none())
        {
            return None;
        }
        let control = match control {
            Some(c) => Some(Control {
                pid: c.pid,
                clock: Sampling::new(c.period)?,
                wheels: c.wheels,
                rotor: Vec::new(),
                held: Vec::new(),
                scratch: Vec::new(),
                torque: Vector3::zeros(),
            }),
            None => None,
        };
        Some(Self {
            estimator: estimator.map(|spec| Estimator {
                seen: vec![0; spec.star_trackers.len()],
                spec,
                state: Estimate {
                    filter: None,
                    gyro: [0.0; 3],
                    t: f64::NEG_INFINITY,
                },
                seen_gyro: 0,
            }),
            guidance: guidance.map(|g| (g, None)),
            control,
            magnetic: None,
        })
    }

    /// Adds a magnetic block (`[fsw.bdot]` or `[fsw.momentum]`, see
    /// [`crate::fsw::magnetic`]): it reads its magnetometer and commands the torquers.
    pub fn with_magnetic(mut self, spec: DipoleSpec) -> Self {
        self.magnetic = Some(DipoleBlock::new(spec));
        self
    }

    /// The dipole the magnetic block holds (body axes, A m²), if there is one.
    pub fn dipole(&self) -> Option<[f64; 3]> {
        self.magnetic.as_ref().map(|m| m.dipole().into())
    }
    /// Whether a magnetic block commands the torquers.
    pub fn commands_dipoles(&self) -> bool {
        self.magnetic.is_some()
    }

    /// The filter as of the last estimator sample (`None` before the first).
    pub fn filter(&self) -> Option<&Mekf> {
        self.estimator.as_ref()?.state.filter.as_ref()
    }
    /// The reference held since the last guidance sample.
    pub fn reference(&self) -> Option<Reference> {
        self.guidance.as_ref()?.1
    }
    /// The body torque the control wanted at its last sample (N m, body axes).
    pub fn control_torque(&self) -> Option<[f64; 3]> {
        self.control.as_ref().map(|c| c.torque.into())
    }
    /// Whether a control commands the wheels.
    pub fn commands_rotors(&self) -> bool {
        self.control.is_some()
    }
    /// What the blocks need of the scene.
    pub fn needs(&self) -> Needs {
        Needs {
            orbit: self.guidance.as_ref().is_some_and(|g| g.0.needs_orbit()),
            rotors: self.control.is_some(),
            free_base: self.control.is_some(),
            ..Needs::default()
        }
    }
    /// The next control sample (`∞` without a control; the estimator runs on the gyro's
    /// samples).
    pub fn next_sample(&self) -> f64 {
        self.control
            .as_ref()
            .map_or(f64::INFINITY, |c| c.clock.next())
    }
    /// The wheels' axes and rotor indices from the simulation.
    pub fn connect(&mut self, links: &Links) {
        if let Some(c) = &mut self.control {
            let mut axes = Vec::new();
            let mut limits = Vec::new();
            c.rotor.clear();
            for (name, max) in &c.wheels {
                if let Some(j) = links.rotors.iter().position(|r| &r.name == name) {
                    c.rotor.push(j);
                    axes.push(links.rotors[j].axis);
                    limits.push(*max);
                }
            }
            c.pid.allocate(&axes, &limits);
            c.held = vec![0.0; links.rotors.len()];
            c.scratch = vec![0.0; c.rotor.len()];
        }
        if let Some(m) = &mut self.magnetic {
            m.connect(links);
        }
    }

    /// Runs the blocks due at `ctx.t`, after the sensors took their samples there.
    pub fn sample(&mut self, ctx: &Context, sensors: &[Sensor]) -> Result<(), SystemError> {
        let t = ctx.t;
        let mut estimated = false;
        if let Some(Estimator {
            spec,
            state,
            seen_gyro,
            seen,
        }) = &mut self.estimator
        {
            let g = &sensors[spec.gyro];
            if g.samples_taken() > *seen_gyro {
                *seen_gyro = g.samples_taken();
                // A tracker's reading counts when it sampled now (since the last look).
                let reading = |k: usize| {
                    let s = &sensors[spec.star_trackers[k].0];
                    (s.samples_taken() > seen[k]).then(|| quaternion(s.last_reading()))
                };
                let gyro = vector(g.last_reading());
                Estimator::step(spec, state, t, gyro, reading)
                    .map_err(|m| SystemError::new(format!("fsw.estimator at t = {t} s: {m}")))?;
                for (k, (i, _)) in spec.star_trackers.iter().enumerate() {
                    seen[k] = sensors[*i].samples_taken();
                }
                estimated = true;
            }
        }
        let control_due = self
            .control
            .as_ref()
            .is_some_and(|c| stop_due(t, c.clock.next()));
        if let Some((law, held)) = &mut self.guidance
            && (control_due || (self.control.is_none() && estimated))
        {
            *held = Some(
                law.reference(ctx.orbit.as_ref())
                    .map_err(|m| SystemError::new(format!("fsw.guidance: {m}")))?,
            );
        }
        if let Some(c) = &mut self.control
            && control_due
        {
            let e = self.estimator.as_ref().expect("a control has an estimator");
            let r = self
                .guidance
                .as_ref()
                .and_then(|g| g.1)
                .expect("a control has a guidance, evaluated above");
            let f = e.state.filter.as_ref().ok_or_else(|| {
                SystemError::new(format!(
                    "fsw.control at t = {t} s: the estimator has no estimate yet"
                ))
            })?;
            let omega = Vector3::from(f.rate(e.state.gyro));
            let ahead = t - e.state.t;
            let q = if ahead > 0.0 {
                f.unit_attitude() * UnitQuaternion::from_scaled_axis(omega * ahead)
            } else {
                f.unit_attitude()
            };
            c.torque = c
                .pid
                .torque(&q, &omega, &r.attitude, &r.rate, c.clock.period());
            c.pid.commands(&c.torque, &mut c.scratch);
            c.held.fill(0.0);
            for (&rotor, &cmd) in c.rotor.iter().zip(&c.scratch) {
                c.held[rotor] = cmd;
            }
            c.clock.taken(t);
        }
        if let Some(m) = &mut self.magnetic {
            m.sample(sensors, ctx.rotor_rates);
        }
        Ok(())
    }

    /// Writes the held wheel commands and adds the held torquer commands.
    pub fn apply(&self, forces: &mut Forces) {
        if let Some(c) = &self.control {
            for (out, held) in forces.rotor_command.iter_mut().zip(&c.held) {
                *out = *held;
            }
        }
        if let Some(m) = &self.magnetic {
            m.apply(forces);
        }
    }

    /// The output columns (see the module documentation).
    pub fn columns(&self) -> Vec<String> {
        let mut c = Vec::new();
        let add = |c: &mut Vec<String>, p: &str, s: &[&str]| {
            c.extend(s.iter().map(|s| format!("{p}_{s}")));
        };
        if self.estimator.is_some() {
            add(&mut c, "est_q", &["w", "x", "y", "z"]);
            add(&mut c, "est_bias", &["x", "y", "z"]);
            add(&mut c, "est_sigma", &["x", "y", "z"]);
            c.push("est_error".into());
        }
        if self.guidance.is_some() {
            add(&mut c, "ref_q", &["w", "x", "y", "z"]);
            add(&mut c, "ref_omega", &["x", "y", "z"]);
            c.push("pointing_error".into());
        }
        if self.magnetic.is_some() {
            add(&mut c, "fsw_dipole", &["x", "y", "z"]);
        }
        c
    }

    /// The columns' values at `ctx`: at a sample instant, what the sample there latches
    /// (worked out on a copy, from the readings the sensors take there); else what is held.
    pub fn output(&self, ctx: &Context, sensors: &[Sensor], row: &mut Vec<f64>) {
        self.output_estimate(ctx, sensors, row);
        if let Some(m) = &self.magnetic {
            row.extend_from_slice(m.dipole_at(ctx, sensors).as_slice());
        }
    }

    /// The estimator's and the guidance's columns.
    fn output_estimate(&self, ctx: &Context, sensors: &[Sensor], row: &mut Vec<f64>) {
        let t = ctx.t;
        let Some(e) = &self.estimator else {
            return;
        };
        let truth = Pose::of(ctx, e.spec.body).attitude;
        let gyro_due = stop_due(t, sensors[e.spec.gyro].next_sample());
        let pending;
        let state = if gyro_due {
            let mut s = e.state.clone();
            let reading = |k: usize| {
                let st = &sensors[e.spec.star_trackers[k].0];
                stop_due(t, st.next_sample()).then(|| quaternion(&st.reading_at(ctx)))
            };
            let gyro = vector(&sensors[e.spec.gyro].reading_at(ctx));
            pending = Estimator::step(&e.spec, &mut s, t, gyro, reading)
                .ok()
                .map(|_| s);
            pending.as_ref()
        } else {
            Some(&e.state)
        };
        match state.and_then(|s| s.filter.as_ref()) {
            Some(f) => {
                row.extend_from_slice(&f.attitude());
                row.extend_from_slice(&f.bias());
                row.extend_from_slice(&f.sigma_attitude());
                row.push(log_rotation(&(f.unit_attitude().inverse() * truth)).norm());
            }
            None => row.extend_from_slice(&[f64::NAN; 11]),
        }
        let Some((law, held)) = &self.guidance else {
            return;
        };
        let due = match &self.control {
            Some(c) => stop_due(t, c.clock.next()),
            None => gyro_due,
        };
        let r = if due {
            law.reference(ctx.orbit.as_ref()).ok()
        } else {
            *held
        };
        match r {
            Some(r) => {
                let q = r.attitude.quaternion();
                let s = if q.w < 0.0 { -1.0 } else { 1.0 };
                row.extend_from_slice(&[s * q.w, s * q.i, s * q.j, s * q.k]);
                row.extend_from_slice(r.rate.as_slice());
                row.push(log_rotation(&(r.attitude.inverse() * truth)).norm());
            }
            None => row.extend_from_slice(&[f64::NAN; 8]),
        }
    }

    /// The reference of the guidance law at an orbit (for checks against it).
    pub fn reference_at(&self, orbit: Option<&OrbitState>) -> Option<Reference> {
        self.guidance.as_ref()?.0.reference(orbit).ok()
    }
}

fn quaternion(r: &[f64]) -> [f64; 4] {
    [r[0], r[1], r[2], r[3]]
}

fn vector(r: &[f64]) -> [f64; 3] {
    [r[0], r[1], r[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> EstimatorSpec {
        EstimatorSpec {
            gyro: 0,
            period: 0.1,
            star_trackers: vec![(1, [1e-5; 3])],
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
    fn a_block_without_what_it_reads_is_refused_and_the_columns_follow_the_blocks() {
        let inertial = Guidance::Inertial(UnitQuaternion::identity());
        assert!(Onboard::new(None, Some(inertial), None).is_none());
        let control = ControlSpec {
            pid: Pid::new([1.0; 3], [0.0; 3], [1.0; 3], None),
            period: 0.1,
            wheels: vec![("wheel_x".into(), 1.0)],
        };
        assert!(Onboard::new(Some(spec()), None, Some(control.clone())).is_none());
        let est = Onboard::new(Some(spec()), None, None).unwrap();
        assert_eq!(est.columns().len(), 11);
        assert!(!est.commands_rotors() && est.next_sample() == f64::INFINITY);
        let all = Onboard::new(Some(spec()), Some(inertial), Some(control)).unwrap();
        assert_eq!(all.columns().len(), 19);
        assert!(all.commands_rotors() && all.needs().rotors && !all.needs().orbit);
        assert_eq!(all.next_sample(), f64::NEG_INFINITY);
    }

    #[test]
    fn a_magnetic_block_adds_the_dipole_columns_and_has_the_sensors_command_the_torquers() {
        use crate::effects::Effect;
        use crate::fsw::{DipoleLaw, DipoleSpec};
        let spec = DipoleSpec {
            law: DipoleLaw::Bdot { gain: 1e6 },
            magnetometer: 0,
            period: 1.0,
            every: 1,
            wheels: Vec::new(),
        };
        let b = Onboard::new(None, None, None).unwrap().with_magnetic(spec);
        assert_eq!(
            b.columns(),
            ["fsw_dipole_x", "fsw_dipole_y", "fsw_dipole_z"]
        );
        assert!(b.commands_dipoles() && !b.commands_rotors());
        assert_eq!(b.dipole(), Some([0.0; 3]));
        let mut set = crate::sensors::Sensors::new(1);
        assert!(set.observes_only() && !set.commands_dipoles());
        set.set_fsw(b);
        assert!(!set.observes_only() && set.commands_dipoles());
        assert_eq!(set.before(), ["magnetic"]);
    }

    #[test]
    fn the_first_step_starts_at_the_first_tracker_reading_then_updates_with_it() {
        let spec = spec();
        let mut state = Estimate {
            filter: None,
            gyro: [0.0; 3],
            t: f64::NEG_INFINITY,
        };
        let q = [0.6, 0.8, 0.0, 0.0];
        Estimator::step(&spec, &mut state, 0.0, [1e-3, 0.0, 0.0], |_| Some(q)).unwrap();
        let mut want = Mekf::new(spec.params, q, [0.0; 3])
            .unwrap()
            .with_gyro_model(GyroModel::Sampled);
        want.update_attitude(q, [1e-5; 3]).unwrap();
        assert_eq!(state.filter.as_ref(), Some(&want));
        // The next: propagate with the held reading, then update.
        Estimator::step(&spec, &mut state, 0.1, [0.0; 3], |_| Some(q)).unwrap();
        want.propagate([1e-3, 0.0, 0.0], 0.1).unwrap();
        want.update_attitude(q, [1e-5; 3]).unwrap();
        assert_eq!(state.filter.as_ref(), Some(&want));
        // No tracker reading at the first sample: an error.
        let mut empty = Estimate {
            filter: None,
            gyro: [0.0; 3],
            t: 0.0,
        };
        assert!(Estimator::step(&spec, &mut empty, 0.0, [0.0; 3], |_| None).is_err());
    }
}
