//! Sensors (contract section 13): gyros, star trackers, Sun sensors and magnetometers, each
//! fixed to a body of the tree and sampled on its own clock, with seeded noise.
//!
//! The set of a scene's sensors is one effect, [`Sensors`], that applies nothing: each sensor
//! samples on its own [`Sampling`] clock (`t = 0, period, 2 period, …`, the first sample at
//! the start), a time stop of the integrator, and holds its reading until its next sample.
//! Because it only observes ([`Effect::observes_only`]), a sample does not restart the
//! integrator: with periods that are whole numbers of a fixed step, a run's other columns are
//! bit for bit those of the run without sensors. A period that is not a whole number of steps
//! shortens the steps that cross a sample instant (a time stop), which changes the
//! trajectory within the method's error. Body poses are computed at the samples only (no
//! work in the right-hand side).
//!
//! - [`Gyro`]: the body's inertial angular velocity in its axes, plus a bias that does a
//!   random walk, plus white noise;
//! - [`StarTracker`]: the body's attitude quaternion `[w, x, y, z]` (body to inertial) times
//!   a small random rotation about the body's axes, sign chosen so that `w >= 0`;
//! - [`SunSensor`]: the unit vector from the spacecraft to the Sun in the body's axes; zeros
//!   in umbra (lit fraction 0; any visible part of the Sun's disk gives the unit vector);
//! - [`Magnetometer`]: the geomagnetic field in the body's axes (T), plus white noise.
//!
//! Output columns: `<name>_x`, `<name>_y`, `<name>_z` (star tracker `<name>_q_w` …
//! `<name>_q_z`), each holding the reading last taken. A row at a sample instant holds the
//! reading taken there (the one the sample will latch, from the same state).
//!
//! Flight software: the set may host a scene's `[fsw]` blocks ([`Sensors::set_fsw`],
//! [`crate::fsw::Onboard`]), which run at a sample instant right after the sensors sampled,
//! on the readings just taken. With a control among them the set commands the wheels (or
//! the torquers, or the thrusters: [`Effect::thrust_commands`]), with `[fsw.bdot]` or
//! `[fsw.momentum]` the magnetic torquers, and no longer only observes.
//!
//! Noise: one ChaCha12 stream per sensor (its index in the set) from the set's seed
//! ([`Noise`]), and a fixed block of that stream per sample, so that a sensor's readings
//! depend on the seed, its index and its sample count only, not on the other sensors or on
//! when the rows are written.

pub mod gyro;
pub mod magnetometer;
pub mod star_tracker;
pub mod sun_sensor;

pub use gyro::Gyro;
pub use magnetometer::Magnetometer;
pub use star_tracker::StarTracker;
pub use sun_sensor::SunSensor;

use crate::effects::{Context, Effect, Forces, Links, Needs, OrbitState, Sampling};
use crate::fsw::Onboard;
use chacha20::ChaCha12Rng;
use nalgebra::UnitQuaternion;
use rand_core::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use satsim_integrate::{SystemError, stop_due};
use satsim_tree::spatial::{Mat3, Vec3};

/// ChaCha blocks (16 words each) of a sensor's stream reserved for one sample: far more
/// than the few normal draws a sample takes, so that sample `k` starts at block `256 k`.
const BLOCKS_PER_SAMPLE: u64 = 256;

/// A sensor's noise source: the ChaCha12 stream `stream` of the key `seed` (its first 8
/// bytes, little-endian, as the campaign's `run_rng`), block `256 k` onwards for sample `k`.
///
/// ```
/// use satsim_spacecraft::sensors::Noise;
/// let (a, b) = (Noise::new(7, 0), Noise::new(7, 1));
/// let x = a.sample(3).normal(1.0);
/// assert_eq!(x, a.sample(3).normal(1.0)); // a sample's draws are fixed
/// assert_ne!(x, b.sample(3).normal(1.0)); // each sensor has its own stream
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Noise {
    seed: u64,
    stream: u64,
}

impl Noise {
    /// Stream `stream` of `seed`.
    pub fn new(seed: u64, stream: u64) -> Self {
        Self { seed, stream }
    }
    /// The draws of sample `k` (a generator keyed and positioned afresh; no allocation).
    pub fn sample(&self, k: u64) -> Draws {
        let mut key = [0u8; 32];
        key[..8].copy_from_slice(&self.seed.to_le_bytes());
        let mut rng = ChaCha12Rng::from_seed(key);
        rng.set_stream(self.stream);
        rng.set_block_pos(k.wrapping_mul(BLOCKS_PER_SAMPLE));
        Draws(rng)
    }
}

/// The random numbers of one sample ([`Noise::sample`]).
pub struct Draws(ChaCha12Rng);

impl Draws {
    /// A normal number of mean 0 and standard deviation `std` (exactly 0 when `std` is 0).
    pub fn normal(&mut self, std: f64) -> f64 {
        let z: f64 = StandardNormal.sample(&mut self.0);
        std * z
    }
    /// Three independent normal numbers of standard deviations `std`.
    pub fn vec3(&mut self, std: [f64; 3]) -> Vec3 {
        let x = self.normal(std[0]);
        let y = self.normal(std[1]);
        let z = self.normal(std[2]);
        Vec3::new(x, y, z)
    }
}

/// What a sensor on one body sees at a sample: the body's attitude and rate and the orbit.
pub struct Pose<'a> {
    /// Time (s).
    pub t: f64,
    /// The body's attitude, body to inertial (the state's quaternion for the root).
    pub attitude: UnitQuaternion<f64>,
    /// The body's inertial angular velocity, its own axes (rad/s).
    pub omega: Vec3,
    /// The body's rotation matrix (body to inertial), for a body other than the root.
    rotation: Option<&'a Mat3>,
    /// The orbit of the centre of mass, when the scene has one.
    pub orbit: Option<OrbitState>,
}

impl<'a> Pose<'a> {
    /// Body `body`'s pose in `ctx` (the poses of bodies other than the root must be current).
    pub fn of(ctx: &'a Context, body: usize) -> Self {
        if body == 0 {
            Self {
                t: ctx.t,
                attitude: ctx.attitude,
                omega: ctx.omega,
                rotation: None,
                orbit: ctx.orbit,
            }
        } else {
            let rot = &ctx.data.rotation[body];
            Self {
                t: ctx.t,
                attitude: UnitQuaternion::from_rotation_matrix(
                    &nalgebra::Rotation3::from_matrix_unchecked(*rot),
                ),
                omega: ctx.data.v[body].ang,
                rotation: Some(rot),
                orbit: ctx.orbit,
            }
        }
    }
    /// An inertial vector in the body's axes (for the root, exactly as the effects rotate
    /// into bus axes).
    pub fn to_body(&self, v: &Vec3) -> Vec3 {
        match self.rotation {
            None => self.attitude.inverse_transform_vector(v),
            Some(r) => r.tr_mul(v),
        }
    }
}

/// What a sensor measures, with its parameters and its own state (a gyro's bias).
#[derive(Clone, Debug)]
pub enum Kind {
    /// A rate gyro.
    Gyro(Gyro),
    /// A star tracker.
    StarTracker(StarTracker),
    /// A Sun sensor.
    SunSensor(SunSensor),
    /// A magnetometer.
    Magnetometer(Magnetometer),
}

impl Kind {
    /// The reading's length (3, or 4 for a quaternion).
    pub fn width(&self) -> usize {
        match self {
            Kind::StarTracker(_) => 4,
            _ => 3,
        }
    }
    /// The column suffixes.
    fn suffixes(&self) -> &'static [&'static str] {
        match self {
            Kind::StarTracker(_) => &["_q_w", "_q_x", "_q_y", "_q_z"],
            _ => &["_x", "_y", "_z"],
        }
    }
    /// The scene's name of the kind (`gyro`, …).
    pub fn name(&self) -> &'static str {
        match self {
            Kind::Gyro(_) => "gyro",
            Kind::StarTracker(_) => "star_tracker",
            Kind::SunSensor(_) => "sun_sensor",
            Kind::Magnetometer(_) => "magnetometer",
        }
    }
    fn read(
        &self,
        pose: &Pose,
        period: f64,
        d: &mut Draws,
        out: &mut [f64; 4],
    ) -> Result<(), String> {
        match self {
            Kind::Gyro(g) => g.read(pose, period, d, out),
            Kind::StarTracker(s) => s.read(pose, d, out),
            Kind::SunSensor(s) => s.read(pose, d, out)?,
            Kind::Magnetometer(m) => m.read(pose, d, out)?,
        }
        Ok(())
    }
}

/// One sensor: its name, body, clock, noise stream and the reading last taken.
#[derive(Clone, Debug)]
pub struct Sensor {
    name: String,
    body: usize,
    clock: Sampling,
    noise: Noise,
    taken: u64,
    reading: [f64; 4],
    kind: Kind,
}

impl Sensor {
    /// A sensor called `name` on body `body` (index in the model's bodies) sampling every
    /// `period` seconds; `None` unless `period` is finite and > 0. Its noise stream is set
    /// when it joins a [`Sensors`] set.
    pub fn new(name: impl Into<String>, body: usize, period: f64, kind: Kind) -> Option<Self> {
        Some(Self {
            name: name.into(),
            body,
            clock: Sampling::new(period)?,
            noise: Noise::new(0, 0),
            taken: 0,
            reading: [0.0; 4],
            kind,
        })
    }
    /// Its name (the columns' prefix).
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Its body (index in the model's bodies).
    pub fn body(&self) -> usize {
        self.body
    }
    /// Its period (s).
    pub fn period(&self) -> f64 {
        self.clock.period()
    }
    /// What it measures.
    pub fn kind(&self) -> &Kind {
        &self.kind
    }
    /// Its output columns.
    pub fn columns(&self) -> Vec<String> {
        let n = &self.name;
        self.kind
            .suffixes()
            .iter()
            .map(|s| format!("{n}{s}"))
            .collect()
    }
    /// How many samples it took.
    pub fn samples_taken(&self) -> u64 {
        self.taken
    }
    /// The reading last taken (zeros before the first).
    pub fn last_reading(&self) -> &[f64] {
        &self.reading[..self.kind.width()]
    }
    /// Its next sample instant (`-∞` before the first).
    pub fn next_sample(&self) -> f64 {
        self.clock.next()
    }
    /// The reading at `ctx`: the one taken there when a sample is due (not yet latched),
    /// else the one last taken (NaN where it cannot be read). Only the first
    /// [`Kind::width`] values count.
    pub fn reading_at(&self, ctx: &Context) -> [f64; 4] {
        self.current(ctx)
    }
    /// The reading of the next sample at `ctx` (the state it would sample), into `out`.
    fn pending(&self, ctx: &Context, out: &mut [f64; 4]) -> Result<(), String> {
        let mut d = self.noise.sample(self.taken);
        self.kind
            .read(&Pose::of(ctx, self.body), self.period(), &mut d, out)
    }
    /// Takes the sample due at `ctx.t`: the reading, then the state's step (a gyro's bias
    /// walk), from the same draws.
    fn take(&mut self, ctx: &Context) -> Result<(), SystemError> {
        let mut d = self.noise.sample(self.taken);
        let mut r = [0.0; 4];
        self.kind
            .read(&Pose::of(ctx, self.body), self.period(), &mut d, &mut r)
            .map_err(|m| SystemError::new(format!("sensor `{}`: {m}", self.name)))?;
        if let Kind::Gyro(g) = &mut self.kind {
            g.walk(self.clock.period(), &mut d);
        }
        self.reading = r;
        self.taken += 1;
        self.clock.taken(ctx.t);
        Ok(())
    }
    /// The reading at `ctx`: the one taken there when a sample is due (not yet latched),
    /// else the one last taken. NaN where it cannot be read (no orbit).
    fn current(&self, ctx: &Context) -> [f64; 4] {
        if stop_due(ctx.t, self.clock.next()) {
            let mut r = [0.0; 4];
            match self.pending(ctx, &mut r) {
                Ok(()) => r,
                Err(_) => [f64::NAN; 4],
            }
        } else {
            self.reading
        }
    }
}

/// A sensor's reading by name, as [`Sensors::readings`] gives it.
pub type Reading = (String, Vec<f64>);

/// A scene's sensors: one effect that applies nothing (see the module documentation).
///
/// ```
/// use satsim_spacecraft::sensors::{Gyro, Kind, Sensor, Sensors};
/// use satsim_tree::spatial::Vec3;
/// let mut set = Sensors::new(1);
/// let gyro = Gyro::new(1e-5, 0.0, Vec3::zeros());
/// set.push(Sensor::new("gyro", 0, 0.1, Kind::Gyro(gyro)).unwrap());
/// assert_eq!(set.columns(), ["gyro_x", "gyro_y", "gyro_z"]);
/// ```
#[derive(Clone, Debug)]
pub struct Sensors {
    seed: u64,
    sensors: Vec<Sensor>,
    /// The flight software that reads these sensors (`[fsw]`), if any.
    fsw: Option<Box<Onboard>>,
}

impl Sensors {
    /// An empty set whose noise comes from `seed`.
    pub fn new(seed: u64) -> Self {
        Self {
            seed,
            sensors: Vec::new(),
            fsw: None,
        }
    }
    /// Hosts the flight software `fsw`, whose blocks read these sensors (the indices of its
    /// specs are indices into [`Sensors::sensors`]): it runs at each sample instant after
    /// the sensors sampled (see [`crate::fsw::onboard`]).
    pub fn set_fsw(&mut self, fsw: Onboard) {
        self.fsw = Some(Box::new(fsw));
    }
    /// The flight software it hosts.
    pub fn fsw(&self) -> Option<&Onboard> {
        self.fsw.as_deref()
    }
    /// Adds a sensor; its noise is stream `i` of the seed, `i` its index in the set.
    pub fn push(&mut self, mut s: Sensor) {
        s.noise = Noise::new(self.seed, self.sensors.len() as u64);
        self.sensors.push(s);
    }
    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }
    /// Draws the noise from `seed` instead (before a run: readings already taken stay).
    pub fn set_seed(&mut self, seed: u64) {
        self.seed = seed;
        for (i, s) in self.sensors.iter_mut().enumerate() {
            s.noise = Noise::new(seed, i as u64);
        }
    }
    /// The sensors, in the scene's order.
    pub fn sensors(&self) -> &[Sensor] {
        &self.sensors
    }
    /// Every sensor's columns, in order.
    pub fn columns(&self) -> Vec<String> {
        self.sensors.iter().flat_map(|s| s.columns()).collect()
    }
    /// Each sensor's reading at `ctx` (the one a sample due there takes, else the last).
    pub fn readings(&self, ctx: &Context) -> Vec<Reading> {
        self.sensors
            .iter()
            .map(|s| {
                let w = s.kind.width();
                (s.name.clone(), s.current(ctx)[..w].to_vec())
            })
            .collect()
    }
}

impl Effect for Sensors {
    fn name(&self) -> &str {
        "sensors"
    }
    fn needs(&self) -> Needs {
        self.fsw.as_ref().map_or_else(Needs::default, |f| f.needs())
    }
    fn observes_only(&self) -> bool {
        self.fsw.as_ref().is_none_or(|f| {
            !f.commands_rotors() && !f.commands_dipoles() && !f.commands_thrusters()
        })
    }
    fn commands_thrusters(&self) -> bool {
        self.fsw.as_ref().is_some_and(|f| f.commands_thrusters())
    }
    fn thrust_commands(&self) -> &[f64] {
        self.fsw.as_ref().map_or(&[], |f| f.thrust_commands())
    }
    fn commands_rotors(&self) -> bool {
        self.fsw.as_ref().is_some_and(|f| f.commands_rotors())
    }
    fn commands_dipoles(&self) -> bool {
        self.fsw.as_ref().is_some_and(|f| f.commands_dipoles())
    }
    fn before(&self) -> &[&str] {
        let thrusters = self.commands_thrusters();
        match (self.commands_rotors(), self.commands_dipoles()) {
            (true, true) if thrusters => &["reaction_wheels", "magnetic", "thrusters"],
            (true, false) if thrusters => &["reaction_wheels", "thrusters"],
            (false, true) if thrusters => &["magnetic", "thrusters"],
            (false, false) if thrusters => &["thrusters"],
            (true, true) => &["reaction_wheels", "magnetic"],
            (true, false) => &["reaction_wheels"],
            (false, true) => &["magnetic"],
            (false, false) => &[],
        }
    }
    fn connect(&mut self, links: &Links) {
        if let Some(f) = &mut self.fsw {
            f.connect(links);
        }
    }
    fn sample_reads_kinematics(&self) -> bool {
        self.sensors.iter().any(|s| s.body != 0)
    }
    fn next_sample(&self) -> f64 {
        let fsw = self.fsw.as_ref().map_or(f64::INFINITY, |f| f.next_sample());
        self.sensors.iter().fold(fsw, |m, s| m.min(s.clock.next()))
    }
    fn sample(&mut self, ctx: &Context) -> Result<(), SystemError> {
        for s in &mut self.sensors {
            if stop_due(ctx.t, s.clock.next()) {
                s.take(ctx)?;
            }
        }
        if let Some(f) = &mut self.fsw {
            f.sample(ctx, &self.sensors)?;
        }
        Ok(())
    }
    fn apply(
        &mut self,
        _ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        if let Some(f) = &self.fsw {
            f.apply(forces);
        }
        Ok(())
    }
    fn output_columns(&self) -> Vec<String> {
        let mut c = self.columns();
        if let Some(f) = &self.fsw {
            c.extend(f.columns());
        }
        c
    }
    fn output(&self, ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        for s in &self.sensors {
            row.extend_from_slice(&s.current(ctx)[..s.kind.width()]);
        }
        if let Some(f) = &self.fsw {
            if stop_due(ctx.t, self.next_sample()) {
                // What the sample here latches: worked out on a copy.
                let mut copy = self.clone();
                match copy.sample(ctx) {
                    Ok(()) => copy.fsw.as_ref().expect("cloned").output(ctx, row),
                    // The sample itself fails there and ends the run with its error.
                    Err(_) => f.output(ctx, row),
                }
            } else {
                f.output(ctx, row);
            }
        }
    }
    fn drain_sample_log(&mut self, out: &mut Vec<String>) {
        if let Some(f) = &mut self.fsw {
            f.drain_log(out);
        }
    }
    fn measure(&self, ctx: &Context, out: &mut Vec<Reading>) {
        out.extend(self.readings(ctx));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(attitude: UnitQuaternion<f64>, omega: Vec3) -> Pose<'static> {
        Pose {
            t: 0.0,
            attitude,
            omega,
            rotation: None,
            orbit: None,
        }
    }

    #[test]
    fn a_samples_draws_are_standard_normal_and_depend_on_its_index_alone() {
        let noise = Noise::new(42, 3);
        let z: Vec<f64> = (0..10_000).map(|k| noise.sample(k).normal(2.0)).collect();
        let n = z.len() as f64;
        let mean = z.iter().sum::<f64>() / n;
        let var = z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        assert!(mean.abs() < 4.0 * 2.0 / n.sqrt(), "mean {mean}");
        assert!((var.sqrt() / 2.0 - 1.0).abs() < 0.03, "std {}", var.sqrt());
        // Sample 7's draws whatever was drawn before; another seed or stream, other draws.
        let mut d = noise.sample(7);
        let first = d.normal(1.0);
        assert_eq!(noise.sample(7).normal(1.0), first);
        assert_ne!(Noise::new(43, 3).sample(7).normal(1.0), first);
        assert_ne!(Noise::new(42, 4).sample(7).normal(1.0), first);
        assert_eq!(noise.sample(7).normal(0.0), 0.0);
    }

    #[test]
    fn a_star_tracker_without_noise_gives_the_attitude_with_w_non_negative() {
        let st = StarTracker::from_arcsec([0.0; 3]);
        let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(-0.5, 0.5, -0.5, 0.5));
        let mut out = [0.0; 4];
        st.read(
            &pose(q, Vec3::zeros()),
            &mut Noise::new(1, 0).sample(0),
            &mut out,
        );
        assert_eq!(out, [0.5, -0.5, 0.5, -0.5]);
    }

    #[test]
    fn a_gyro_reads_rate_plus_bias_and_its_bias_walks_by_the_stated_step() {
        let mut g = Gyro::new(0.0, 1e-3, Vec3::new(1e-3, 0.0, 0.0));
        let omega = Vec3::new(0.1, 0.2, 0.3);
        let mut out = [0.0; 4];
        let noise = Noise::new(5, 0);
        let mut d = noise.sample(0);
        g.read(
            &pose(UnitQuaternion::identity(), omega),
            0.25,
            &mut d,
            &mut out,
        );
        assert_eq!(&out[..3], (omega + Vec3::new(1e-3, 0.0, 0.0)).as_slice());
        let b0 = g.bias;
        g.walk(0.25, &mut d);
        // The step is the sample's next three draws, scaled by bias_walk √period.
        let mut again = noise.sample(0);
        again.vec3([0.0; 3]);
        let step = again.vec3([1e-3 * 0.5; 3]);
        assert_eq!(g.bias, b0 + step);
        assert_eq!(g.white_std(0.25), 0.0);
        assert_eq!(Gyro::new(1e-4, 0.0, Vec3::zeros()).white_std(0.25), 2e-4);
    }
}
