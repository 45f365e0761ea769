//! Sensors (contract sections 13 and 17): gyros, star trackers, Sun sensors, magnetometers,
//! coarse Sun sensors and GPS receivers, each fixed to a body of the tree and sampled on its
//! own clock, with seeded noise.
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
//! - [`Magnetometer`]: the geomagnetic field in the body's axes (T), plus white noise;
//! - [`CoarseSun`]: one photodiode's cosine response to the Sun within its field of view,
//!   with the Earth's albedo if asked, plus white noise;
//! - [`Gps`]: the centre of mass's position and velocity in the GCRF, plus white noise.
//!
//! Every sensor but the GPS receiver may have a [`Misalignment`] of its axes from its
//! body's (it then reads in its own axes) and a quantisation step ([`mounting`]); a gyro a
//! scale factor error; a star tracker exclusion angles ([`star_tracker::Exclusion`]), which
//! give it a validity. "Body axes" below means the sensor's axes when it is misaligned.
//!
//! Output columns: `<name>_x`, `<name>_y`, `<name>_z` (star tracker `<name>_q_w` …
//! `<name>_q_z`; coarse Sun sensor `<name>` alone; GPS `<name>_x` … `<name>_z`,
//! `<name>_vx` … `<name>_vz`), each holding the reading last taken, then, for a star tracker
//! with exclusion angles, `<name>_valid` (1 when the reading was taken at the last sample,
//! 0 when it was excluded and the reading is the last valid one held). A row at a sample
//! instant holds the reading taken there (the one the sample will latch, from the same
//! state). [`Effect::measure`] gives `(name, reading)` per sensor in the same order, and
//! after a star tracker with exclusion angles `(<name>_valid, [1 or 0])`: a one-value
//! entry's column is its name.
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

pub mod coarse_sun;
pub mod gps;
pub mod gyro;
pub mod magnetometer;
pub mod mounting;
pub mod star_tracker;
pub mod sun_sensor;

pub use coarse_sun::CoarseSun;
pub use gps::Gps;
pub use gyro::Gyro;
pub use magnetometer::Magnetometer;
pub use mounting::Misalignment;
pub use star_tracker::StarTracker;
pub use sun_sensor::SunSensor;

use crate::effects::faults::{FaultKind, Schedule, show};
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

/// What a sensor on one body sees at a sample: the attitude and rate of its frame (the
/// body's, or the body's turned by the sensor's [`Misalignment`]) and the orbit.
pub struct Pose<'a> {
    /// Time (s).
    pub t: f64,
    /// The frame's attitude, frame to inertial (the state's quaternion for the root body
    /// without misalignment; `q ⊗ q_R` with one).
    pub attitude: UnitQuaternion<f64>,
    /// The frame's inertial angular velocity, its own axes (rad/s).
    pub omega: Vec3,
    /// The body's rotation matrix (body to inertial), for a body other than the root.
    rotation: Option<&'a Mat3>,
    /// The sensor's misalignment from the body, if any.
    mount: Option<&'a Misalignment>,
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
                mount: None,
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
                mount: None,
                orbit: ctx.orbit,
            }
        }
    }
    /// The pose of the frame turned from the body's by `mount` (the same pose without).
    pub fn mounted(mut self, mount: Option<&'a Misalignment>) -> Self {
        if let Some(m) = mount {
            self.attitude *= m.rotation();
            self.omega = m.to_sensor(&self.omega);
            self.mount = Some(m);
        }
        self
    }
    /// An inertial vector in the frame's axes (for the root body without misalignment,
    /// exactly as the effects rotate into bus axes; with one, the body's axes then `Rᵀ`).
    pub fn to_body(&self, v: &Vec3) -> Vec3 {
        match (self.rotation, self.mount) {
            // The frame's attitude: the body's, or the misaligned frame's.
            (None, _) => self.attitude.inverse_transform_vector(v),
            (Some(r), None) => r.tr_mul(v),
            (Some(r), Some(m)) => m.to_sensor(&r.tr_mul(v)),
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
    /// A coarse Sun sensor.
    CoarseSun(CoarseSun),
    /// A GPS receiver.
    Gps(Gps),
}

impl Kind {
    /// The reading's length (3; 4 for a quaternion, 1 for a coarse Sun sensor, 6 for a
    /// GPS receiver's position and velocity).
    pub fn width(&self) -> usize {
        match self {
            Kind::StarTracker(_) => 4,
            Kind::CoarseSun(_) => 1,
            Kind::Gps(_) => 6,
            _ => 3,
        }
    }
    /// The column suffixes.
    fn suffixes(&self) -> &'static [&'static str] {
        match self {
            Kind::StarTracker(_) => &["_q_w", "_q_x", "_q_y", "_q_z"],
            Kind::CoarseSun(_) => &[""],
            Kind::Gps(_) => &["_x", "_y", "_z", "_vx", "_vy", "_vz"],
            _ => &["_x", "_y", "_z"],
        }
    }
    /// Whether its readings have a validity (a star tracker with exclusion angles).
    pub fn has_validity(&self) -> bool {
        matches!(
            self,
            Kind::StarTracker(StarTracker {
                exclusion: Some(_),
                ..
            })
        )
    }
    /// The scene's name of the kind (`gyro`, …).
    pub fn name(&self) -> &'static str {
        match self {
            Kind::Gyro(_) => "gyro",
            Kind::StarTracker(_) => "star_tracker",
            Kind::SunSensor(_) => "sun_sensor",
            Kind::Magnetometer(_) => "magnetometer",
            Kind::CoarseSun(_) => "coarse_sun",
            Kind::Gps(_) => "gps",
        }
    }
    /// The reading into `out[..width]`, and whether it is valid.
    fn read(
        &self,
        pose: &Pose,
        period: f64,
        d: &mut Draws,
        out: &mut [f64; 6],
    ) -> Result<bool, String> {
        match self {
            Kind::Gyro(g) => g.read(pose, period, d, out),
            Kind::StarTracker(s) => return s.read(pose, d, out),
            Kind::SunSensor(s) => s.read(pose, d, out)?,
            Kind::Magnetometer(m) => m.read(pose, d, out)?,
            Kind::CoarseSun(c) => c.read(pose, d, out)?,
            Kind::Gps(g) => g.read(pose, d, out)?,
        }
        Ok(true)
    }
}

/// One sensor: its name, body, mounting, clock, noise stream and the reading last taken.
#[derive(Clone, Debug)]
pub struct Sensor {
    name: String,
    body: usize,
    clock: Sampling,
    noise: Noise,
    taken: u64,
    /// The last valid reading (zeros before the first).
    reading: [f64; 6],
    /// Whether the last sample's reading was valid (true before the first).
    valid: bool,
    mount: Option<Misalignment>,
    quantization: Option<f64>,
    kind: Kind,
    /// The time of its `sensor_stuck` fault (`∞`: none): readings from then on are held.
    stuck_from: f64,
    /// The time of its `sensor_bias` fault (`∞`: none), and the bias (its units).
    bias_from: f64,
    bias: [f64; 6],
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
            reading: [0.0; 6],
            valid: true,
            mount: None,
            quantization: None,
            kind,
            stuck_from: f64::INFINITY,
            bias_from: f64::INFINITY,
            bias: [0.0; 6],
        })
    }
    /// The same sensor with its axes turned from its body's by `misalignment` (see
    /// [`mounting`]).
    pub fn with_misalignment(mut self, misalignment: Misalignment) -> Self {
        self.mount = Some(misalignment);
        self
    }
    /// The same sensor with its readings rounded to multiples of `step`; `None` unless `step`
    /// is finite and > 0.
    pub fn with_quantization(mut self, step: f64) -> Option<Self> {
        (step.is_finite() && step > 0.0).then(|| {
            self.quantization = Some(step);
            self
        })
    }
    /// Its misalignment, if any.
    pub fn misalignment(&self) -> Option<&Misalignment> {
        self.mount.as_ref()
    }
    /// Its quantisation step, if any.
    pub fn quantization(&self) -> Option<f64> {
        self.quantization
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
    /// Its output columns (then `<name>_valid` for a star tracker with exclusion angles).
    pub fn columns(&self) -> Vec<String> {
        let n = &self.name;
        let mut c: Vec<String> = self
            .kind
            .suffixes()
            .iter()
            .map(|s| format!("{n}{s}"))
            .collect();
        if self.kind.has_validity() {
            c.push(format!("{n}_valid"));
        }
        c
    }
    /// How many samples it took.
    pub fn samples_taken(&self) -> u64 {
        self.taken
    }
    /// The reading last taken (zeros before the first); for a star tracker with exclusion
    /// angles, the last valid one.
    pub fn last_reading(&self) -> &[f64] {
        &self.reading[..self.kind.width()]
    }
    /// Whether the last sample's reading was valid: false when a star tracker's exclusion
    /// angles excluded it (its [`Sensor::last_reading`] is then an older one); true for a
    /// sensor without validity, and before the first sample.
    pub fn valid(&self) -> bool {
        self.valid
    }
    /// Its next sample instant (`-∞` before the first).
    pub fn next_sample(&self) -> f64 {
        self.clock.next()
    }
    /// The reading at `ctx` and its validity (1 or 0): the one taken there when a sample is
    /// due (not yet latched), else the one last taken (NaN where it cannot be read). Only
    /// the first [`Kind::width`] values count.
    pub fn reading_at(&self, ctx: &Context) -> ([f64; 6], f64) {
        self.current(ctx)
    }
    /// The reading of a sample with the draws `d` (misalignment and quantisation applied),
    /// into `out`, and whether it is valid.
    fn read(&self, ctx: &Context, d: &mut Draws, out: &mut [f64; 6]) -> Result<bool, String> {
        let pose = Pose::of(ctx, self.body).mounted(self.mount.as_ref());
        let valid = self.kind.read(&pose, self.period(), d, out)?;
        if let Some(step) = self.quantization {
            for v in &mut out[..self.kind.width()] {
                *v = mounting::quantize(*v, step);
            }
        }
        Ok(valid)
    }
    /// Takes the sample due at `ctx.t`: the reading, then the state's step (a gyro's bias
    /// walk), from the same draws. An invalid reading is not kept (the last valid one is).
    fn take(&mut self, ctx: &Context) -> Result<(), SystemError> {
        let mut d = self.noise.sample(self.taken);
        let mut r = [0.0; 6];
        let valid = self
            .read(ctx, &mut d, &mut r)
            .map_err(|m| SystemError::new(format!("sensor `{}`: {m}", self.name)))?;
        if let Kind::Gyro(g) = &mut self.kind {
            g.walk(self.clock.period(), &mut d);
        }
        // Stuck: the reading and its validity stay those last taken before the fault.
        if !self.stuck(ctx.t) {
            self.biased(ctx.t, &mut r);
            if valid {
                self.reading = r;
            }
            self.valid = valid;
        }
        self.taken += 1;
        self.clock.taken(ctx.t);
        Ok(())
    }
    /// The reading at `ctx` and its validity: the one taken there when a sample is due (not
    /// yet latched), else the one last taken. NaN where it cannot be read (no orbit).
    fn current(&self, ctx: &Context) -> ([f64; 6], f64) {
        let flag = |v: bool| if v { 1.0 } else { 0.0 };
        if stop_due(ctx.t, self.clock.next()) && !self.stuck(ctx.t) {
            let mut r = [0.0; 6];
            match self.read(ctx, &mut self.noise.sample(self.taken), &mut r) {
                Ok(true) => {
                    self.biased(ctx.t, &mut r);
                    (r, 1.0)
                }
                Ok(false) => (self.reading, 0.0),
                Err(_) => ([f64::NAN; 6], f64::NAN),
            }
        } else {
            (self.reading, flag(self.valid))
        }
    }
    /// Whether a sample at `t` holds the reading last taken (a `sensor_stuck` fault at or
    /// before `t`).
    fn stuck(&self, t: f64) -> bool {
        stop_due(t, self.stuck_from)
    }
    /// Adds the `sensor_bias` fault's bias to the reading `r` of a sample at `t` (after the
    /// quantisation: the bias is the reading's error) when the fault is at or before `t`.
    fn biased(&self, t: f64, r: &mut [f64; 6]) {
        if stop_due(t, self.bias_from) {
            let w = self.kind.width();
            for (v, b) in r[..w].iter_mut().zip(&self.bias[..w]) {
                *v += b;
            }
        }
    }
    /// Latches `reading` as a sample's (kept when `valid`), as [`Sensor::take`] does: for
    /// the flight software's tests, which have no simulation to sample.
    #[cfg(test)]
    pub(crate) fn latch(&mut self, reading: &[f64], valid: bool) {
        if valid {
            self.reading[..reading.len()].copy_from_slice(reading);
        }
        self.valid = valid;
        self.taken += 1;
    }
    /// Appends its entries of [`Sensors::readings`] to `out`.
    fn entries(&self, ctx: &Context, out: &mut Vec<Reading>) {
        let (r, valid) = self.current(ctx);
        out.push((self.name.clone(), r[..self.kind.width()].to_vec()));
        if self.kind.has_validity() {
            out.push((format!("{}_valid", self.name), vec![valid]));
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
    /// The sensors' faults, each a time stop at which it is logged (a sensor applies its
    /// own by time: [`Sensor::stuck`], [`Sensor::biased`]).
    faults: Schedule,
    /// Faults happened and not yet logged.
    said: Vec<String>,
}

impl Sensors {
    /// An empty set whose noise comes from `seed`.
    pub fn new(seed: u64) -> Self {
        Self {
            seed,
            sensors: Vec::new(),
            fsw: None,
            faults: Schedule::default(),
            said: Vec::new(),
        }
    }
    /// Adds the fault `kind` on sensor `target` (index in [`Sensors::sensors`]) at `at` (s,
    /// finite, >= 0): a `sensor_stuck` or a `sensor_bias` whose bias has one value per
    /// component of the sensor's reading. Refused, with the reason, otherwise, or when the
    /// sensor already has a fault of that kind.
    pub fn add_fault(&mut self, at: f64, target: usize, kind: FaultKind) -> Result<(), String> {
        let s = self
            .sensors
            .get_mut(target)
            .ok_or_else(|| format!("no sensor {target}"))?;
        if !(at.is_finite() && at >= 0.0) {
            return Err(format!("`at` must be a finite time >= 0 (s), got {at}"));
        }
        let twice = |k: &str| format!("sensor `{}` has two `{k}` faults", s.name);
        match &kind {
            FaultKind::SensorStuck if s.stuck_from.is_finite() => return Err(twice(kind.name())),
            FaultKind::SensorStuck => s.stuck_from = at,
            FaultKind::SensorBias(_) if s.bias_from.is_finite() => {
                return Err(twice(kind.name()));
            }
            FaultKind::SensorBias(b) => {
                let w = s.kind.width();
                if b.len() != w || !b.iter().all(|v| v.is_finite()) {
                    return Err(format!(
                        "a `sensor_bias` of {} `{}` needs {} finite number{} (one per component of its reading, its units), got {}",
                        s.kind.name(),
                        s.name,
                        w,
                        if w == 1 { "" } else { "s" },
                        show(b)
                    ));
                }
                s.bias[..w].copy_from_slice(b);
                s.bias_from = at;
            }
            other => return Err(format!("a sensor cannot have a `{}` fault", other.name())),
        }
        self.faults.push(at, target, kind);
        Ok(())
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
    /// Each sensor's reading at `ctx` (the one a sample due there takes, else the last),
    /// followed for a star tracker with exclusion angles by `(<name>_valid, [1 or 0])`.
    pub fn readings(&self, ctx: &Context) -> Vec<Reading> {
        let mut out = Vec::with_capacity(self.sensors.len());
        for s in &self.sensors {
            s.entries(ctx, &mut out);
        }
        out
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
        let own = self.faults.next().min(fsw);
        self.sensors.iter().fold(own, |m, s| m.min(s.clock.next()))
    }
    fn sample(&mut self, ctx: &Context) -> Result<(), SystemError> {
        // A fault's stop logs it (before a sample at the same time, which it affects).
        while let Some(k) = self.faults.take_due(ctx.t) {
            let f = &self.faults.list()[k];
            let s = &self.sensors[f.target];
            self.said.push(match &f.kind {
                FaultKind::SensorBias(b) => {
                    format!("fault: sensor `{}` biased by {}", s.name, show(&b[..]))
                }
                _ => format!(
                    "fault: sensor `{}` stuck (reading held at {})",
                    s.name,
                    show(s.last_reading())
                ),
            });
        }
        // The sensors and the flight software sample on their clocks only.
        let fsw_due = self
            .fsw
            .as_ref()
            .is_some_and(|f| stop_due(ctx.t, f.next_sample()));
        if !fsw_due && !self.sensors.iter().any(|s| stop_due(ctx.t, s.clock.next())) {
            return Ok(());
        }
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
            let (r, valid) = s.current(ctx);
            row.extend_from_slice(&r[..s.kind.width()]);
            if s.kind.has_validity() {
                row.push(valid);
            }
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
        out.append(&mut self.said);
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
            mount: None,
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
        let mut out = [0.0; 6];
        let valid = st
            .read(
                &pose(q, Vec3::zeros()),
                &mut Noise::new(1, 0).sample(0),
                &mut out,
            )
            .unwrap();
        assert!(valid);
        assert_eq!(out[..4], [0.5, -0.5, 0.5, -0.5]);
    }

    #[test]
    fn a_gyro_reads_rate_plus_bias_and_its_bias_walks_by_the_stated_step() {
        let mut g = Gyro::new(0.0, 1e-3, Vec3::new(1e-3, 0.0, 0.0));
        let omega = Vec3::new(0.1, 0.2, 0.3);
        let mut out = [0.0; 6];
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

    #[test]
    fn a_sensor_fault_is_a_stop_and_is_refused_when_it_does_not_fit_its_sensor() {
        let mut set = Sensors::new(1);
        let gyro = Gyro::new(0.0, 0.0, Vec3::zeros());
        set.push(Sensor::new("g", 0, 0.1, Kind::Gyro(gyro)).unwrap());
        let st = StarTracker::from_arcsec([0.0; 3]);
        set.push(Sensor::new("st", 0, 0.1, Kind::StarTracker(st)).unwrap());
        let bias = |v: &[f64]| FaultKind::SensorBias(v.to_vec());
        assert!(set.add_fault(0.25, 0, bias(&[1.0, 2.0, 3.0])).is_ok());
        assert!(set.add_fault(0.35, 1, FaultKind::SensorStuck).is_ok());
        // The sensors' clocks start at -∞; past the first samples, the faults are stops.
        for s in &mut set.sensors {
            s.clock.taken(0.2);
        }
        assert_eq!(set.next_sample(), 0.25);
        assert!(set.sensors[1].stuck(0.35) && !set.sensors[1].stuck(0.3));
        let mut r = [0.0; 6];
        set.sensors[0].biased(0.2, &mut r);
        assert_eq!(r, [0.0; 6]);
        set.sensors[0].biased(0.25, &mut r);
        assert_eq!(r, [1.0, 2.0, 3.0, 0.0, 0.0, 0.0]);
        let refused = |set: &mut Sensors, at, j, kind| set.add_fault(at, j, kind).unwrap_err();
        let e = refused(&mut set, 1.0, 1, bias(&[1.0, 2.0, 3.0]));
        assert!(
            e.contains("star_tracker `st` needs 4 finite numbers"),
            "{e}"
        );
        assert!(refused(&mut set, 1.0, 1, bias(&[f64::NAN; 4])).contains("finite"));
        assert!(set.add_fault(1.0, 1, bias(&[0.0; 4])).is_ok());
        assert!(refused(&mut set, 2.0, 1, bias(&[0.0; 4])).contains("two `sensor_bias`"));
        assert!(refused(&mut set, 1.0, 1, FaultKind::SensorStuck).contains("two"));
        assert!(refused(&mut set, -1.0, 0, FaultKind::SensorStuck).contains(">= 0"));
        assert!(refused(&mut set, 1.0, 0, FaultKind::WheelOff).contains("cannot"));
    }

    // ---- Misalignment, scale factor, exclusion, coarse Sun sensor (contract section 17).

    use super::star_tracker::Exclusion;
    use crate::effects::OrbitState;
    use satsim_environment::shadow::ShadowModel;
    use satsim_environment::sun::sun_position;
    use satsim_environment::{Epoch, R_EARTH, parse_epoch};
    use std::f64::consts::{FRAC_PI_2, PI};

    fn epoch() -> Epoch {
        parse_epoch("2026-03-20T12:00:00 UTC").unwrap()
    }

    /// A pose at `r` (m, inertial) on a circular-ish orbit, attitude `q`, no rate.
    fn pose_at(q: UnitQuaternion<f64>, r: Vec3) -> Pose<'static> {
        Pose {
            orbit: Some(OrbitState {
                r,
                v: Vec3::new(0.0, 7600.0, 0.0),
                mu: 3.986004418e14,
            }),
            ..pose(q, Vec3::zeros())
        }
    }

    /// Rodrigues' formula, independently of nalgebra's quaternions: the rotation of vector `r`.
    fn rodrigues(r: Vec3) -> Mat3 {
        let angle = r.norm();
        let k = r / angle;
        let kx = Mat3::new(0.0, -k.z, k.y, k.z, 0.0, -k.x, -k.y, k.x, 0.0);
        Mat3::identity() * angle.cos() + k * k.transpose() * (1.0 - angle.cos()) + kx * angle.sin()
    }

    fn close(a: &[f64], b: &[f64], tol: f64) {
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= tol, "{a:?} against {b:?}");
        }
    }

    #[test]
    fn a_misaligned_sensor_reads_in_its_turned_axes() {
        let omega = Vec3::new(0.1, 0.2, 0.3);
        let q = UnitQuaternion::from_scaled_axis(Vec3::new(0.3, -0.2, 0.5));
        let g = Kind::Gyro(Gyro::new(0.0, 0.0, Vec3::zeros()));
        let read = |m: &Misalignment, p: Pose| {
            let mut out = [0.0; 6];
            let p = p.mounted(Some(m));
            g.read(&p, 0.1, &mut Noise::new(1, 0).sample(0), &mut out)
                .unwrap();
            Vec3::new(out[0], out[1], out[2])
        };
        // A quarter turn about z: the sensor's x is the body's y, its y the body's −x.
        let quarter = Misalignment::new(Vec3::new(0.0, 0.0, FRAC_PI_2));
        let r = read(&quarter, pose(q, omega));
        close(r.as_slice(), &[0.2, -0.1, 0.3], 1e-16);
        // Any rotation: Rᵀ ω with R from Rodrigues' formula.
        let v = Vec3::new(0.01, -0.02, 0.03);
        let m = Misalignment::new(v);
        let want = rodrigues(v).transpose() * omega;
        close(read(&m, pose(q, omega)).as_slice(), want.as_slice(), 1e-16);
        // Inertial vectors too (a magnetometer's or a Sun sensor's), on the root body and on
        // another body (its rotation matrix): Rᵀ of the body-axis vector.
        let b = Vec3::new(2e-5, -1e-5, 3e-5);
        let body = q.inverse_transform_vector(&b);
        let want = rodrigues(v).transpose() * body;
        let root = pose(q, omega).mounted(Some(&m));
        close(root.to_body(&b).as_slice(), want.as_slice(), 1e-20);
        let rot = q.to_rotation_matrix().into_inner();
        let other = Pose {
            rotation: Some(&rot),
            ..pose(q, omega)
        }
        .mounted(Some(&m));
        close(other.to_body(&b).as_slice(), want.as_slice(), 1e-20);
        // A star tracker: the attitude of the turned frame, q ⊗ q_R.
        let st = StarTracker::from_arcsec([0.0; 3]);
        let mut out = [0.0; 6];
        let id = UnitQuaternion::identity();
        st.read(
            &pose(id, omega).mounted(Some(&quarter)),
            &mut Noise::new(1, 0).sample(0),
            &mut out,
        )
        .unwrap();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        close(&out[..4], &[h, 0.0, 0.0, h], 2.3e-16);
        // The frame's +z (the boresight) in inertial axes is R e_z turned by q.
        let p = pose(q, omega).mounted(Some(&m));
        let bore = p.attitude * Vec3::z();
        let want = q * (rodrigues(v) * Vec3::z());
        close(bore.as_slice(), want.as_slice(), 1e-15);
    }

    #[test]
    fn a_gyros_scale_factor_multiplies_each_axis_of_the_rate() {
        let omega = Vec3::new(0.1, -0.2, 0.3);
        let bias = Vec3::new(1e-3, 2e-3, -1e-3);
        for s in [Vec3::repeat(0.01), Vec3::new(0.01, -0.02, 0.5)] {
            let g = Gyro::new(0.0, 0.0, bias).with_scale_factor(s);
            let mut out = [0.0; 6];
            let mut d = Noise::new(1, 0).sample(0);
            g.read(
                &pose(UnitQuaternion::identity(), omega),
                0.1,
                &mut d,
                &mut out,
            );
            for a in 0..3 {
                let want = (1.0 + s[a]) * omega[a] + bias[a];
                assert_eq!(out[a].to_bits(), want.to_bits(), "axis {a}");
            }
        }
    }

    #[test]
    fn a_star_trackers_exclusion_flags_the_sun_and_the_earths_limb() {
        let e = epoch();
        let sun = sun_position(e, 0.0);
        let s = sun.normalize();
        // On the orbit a quarter turn from the Sun's direction, 500 km up.
        let r = s.cross(&Vec3::z()).normalize() * (R_EARTH + 500e3);
        let to_sun = (sun - r).normalize();
        let both = Exclusion {
            sun: Some((30f64.to_radians(), e)),
            earth: Some(20f64.to_radians()),
        };
        assert!(!both.clear(&to_sun, 0.0, &r));
        // 40° from the Sun, turned away from the Earth: valid.
        let away = to_sun.cross(&r).normalize();
        let turn = |axis: Vec3, deg: f64, v: Vec3| {
            UnitQuaternion::from_scaled_axis(axis * deg.to_radians()) * v
        };
        let forty = turn(away, 40.0, to_sun);
        assert!(forty.dot(&r) > 0.0, "turned away from the Earth");
        assert!(both.clear(&forty, 0.0, &r));
        // 29.9° from the Sun: excluded; 30.1°: valid.
        assert!(!both.clear(&turn(away, 29.9, to_sun), 0.0, &r));
        assert!(both.clear(&turn(away, 30.1, to_sun), 0.0, &r));
        // The Earth's limb: nadir + angular radius + 20°, from either side of it.
        let earth = Exclusion {
            sun: None,
            earth: Some(20f64.to_radians()),
        };
        let nadir = -r.normalize();
        let rho = (R_EARTH / r.norm()).asin().to_degrees();
        let side = nadir.cross(&Vec3::z()).normalize();
        for sign in [1.0, -1.0] {
            assert!(!earth.clear(&turn(side, sign * (rho + 19.9), nadir), 0.0, &r));
            assert!(earth.clear(&turn(side, sign * (rho + 20.1), nadir), 0.0, &r));
        }
        assert!(!earth.clear(&nadir, 0.0, &r));
        // A tracker with exclusion needs the orbit; on the Sun it reads, flagged invalid.
        let st = StarTracker::from_arcsec([0.0; 3]).with_exclusion(both);
        let q = UnitQuaternion::rotation_between(&Vec3::z(), &to_sun).unwrap();
        let mut out = [0.0; 6];
        let d = &mut Noise::new(1, 0).sample(0);
        assert!(!st.read(&pose_at(q, r), d, &mut out).unwrap());
        assert!(st.read(&pose(q, Vec3::zeros()), d, &mut out).is_err());
        let q40 = UnitQuaternion::rotation_between(&Vec3::z(), &forty).unwrap();
        assert!(st.read(&pose_at(q40, r), d, &mut out).unwrap());
    }

    fn coarse(normal: Vec3, fov_deg: f64, albedo: bool) -> CoarseSun {
        CoarseSun {
            epoch: epoch(),
            shadow: ShadowModel::Conical,
            normal,
            fov: fov_deg.to_radians(),
            scale: 2.0,
            noise: 0.0,
            albedo,
        }
    }

    fn read_coarse(c: &CoarseSun, p: &Pose) -> f64 {
        let mut out = [0.0; 6];
        c.read(p, &mut Noise::new(1, 0).sample(0), &mut out)
            .unwrap();
        out[0]
    }

    #[test]
    fn a_coarse_sun_sensor_follows_the_cosine_within_its_field_of_view_and_reads_zero_in_umbra() {
        let sun = sun_position(epoch(), 0.0);
        let s = sun.normalize();
        let r = s.cross(&Vec3::z()).normalize() * (R_EARTH + 500e3);
        let to_sun = (sun - r).normalize();
        let id = UnitQuaternion::identity();
        let side = to_sun.cross(&Vec3::z()).normalize();
        for deg in [0.0, 30.0, 60.0, 85.0] {
            let n = UnitQuaternion::from_scaled_axis(side * f64::to_radians(deg)) * to_sun;
            let got = read_coarse(&coarse(n, 90.0, false), &pose_at(id, r));
            let want = 2.0 * n.dot(&to_sun);
            assert!((got - want).abs() < 1e-15, "{deg}°: {got} against {want}");
            assert!((got - 2.0 * f64::to_radians(deg).cos()).abs() < 1e-12);
            // Outside a 20° field of view: 0 (inside it at 0°).
            let narrow = read_coarse(&coarse(n, 20.0, false), &pose_at(id, r));
            assert_eq!(narrow, if deg == 0.0 { got } else { 0.0 }, "{deg}°");
        }
        // Facing away from the Sun: 0.
        assert_eq!(
            read_coarse(&coarse(-to_sun, 90.0, false), &pose_at(id, r)),
            0.0
        );
        // In the Earth's shadow (behind the Earth from the Sun): 0.
        let behind = -s * (R_EARTH + 500e3);
        let to_sun = (sun - behind).normalize();
        assert_eq!(
            read_coarse(&coarse(to_sun, 90.0, false), &pose_at(id, behind)),
            0.0
        );
        // The body's attitude turns the Sun into body axes.
        let q = UnitQuaternion::from_scaled_axis(Vec3::new(0.2, 0.4, -0.1));
        let n = Vec3::new(0.0, 0.6, 0.8);
        let want = 2.0 * n.dot(&q.inverse_transform_vector(&(sun - r).normalize()));
        assert!(want > 0.0);
        let got = read_coarse(&coarse(n, 90.0, false), &pose_at(q, r));
        assert!((got - want).abs() < 1e-15, "{got} against {want}");
    }

    #[test]
    fn the_albedo_of_a_photodiode_facing_nadir_under_the_sun_is_albedo_times_r_over_r_squared() {
        // At the sub-solar point, facing the Earth: the Sun behind the photodiode.
        let s = sun_position(epoch(), 0.0).normalize();
        for h in [400e3, 800e3, 20_000e3] {
            let r = s * (R_EARTH + h);
            let id = UnitQuaternion::identity();
            let got = read_coarse(&coarse(-s, 90.0, true), &pose_at(id, r));
            let want = 2.0 * 0.3 * (R_EARTH / (R_EARTH + h)).powi(2);
            assert!(
                (got / want - 1.0).abs() < 1e-14,
                "{h}: {got} against {want}"
            );
            // Without albedo: nothing.
            assert_eq!(read_coarse(&coarse(-s, 90.0, false), &pose_at(id, r)), 0.0);
            // Over the night side: nothing either.
            assert_eq!(read_coarse(&coarse(s, 90.0, true), &pose_at(id, -r)), 0.0);
        }
    }

    #[test]
    fn the_view_factor_of_a_sphere_matches_a_quadrature_at_every_tilt() {
        // A unit sphere at the origin, the plate at (0, 0, h), its normal at β from −z.
        let quadrature = |cos_beta: f64, h: f64| {
            let sin_beta = (1.0 - cos_beta * cos_beta).sqrt();
            let n = Vec3::new(sin_beta, 0.0, -cos_beta);
            let p = Vec3::new(0.0, 0.0, h);
            let cap = (1.0 / h).acos();
            let (na, nphi) = (1500, 1500);
            let (da, dphi) = (cap / na as f64, 2.0 * PI / nphi as f64);
            let mut sum = 0.0;
            for i in 0..na {
                let a = (i as f64 + 0.5) * da;
                let (sa, ca) = a.sin_cos();
                for j in 0..nphi {
                    let (sp, cp) = ((j as f64 + 0.5) * dphi).sin_cos();
                    let x = Vec3::new(sa * cp, sa * sp, ca);
                    let d = x - p;
                    let s2 = d.norm_squared();
                    let c1 = n.dot(&d);
                    let c2 = -x.dot(&d);
                    if c1 > 0.0 && c2 > 0.0 {
                        sum += c1 * c2 / (s2 * s2) * sa;
                    }
                }
            }
            sum * da * dphi / PI
        };
        for h in [1.1f64, 1.5, 3.0] {
            let cut = (1.0 / h).acos().to_degrees();
            for deg in [
                0.0,
                0.5 * (90.0 - cut),
                90.0 - cut,
                60.0,
                90.0,
                90.0 + 0.5 * cut,
            ] {
                let c = f64::to_radians(deg).cos();
                let f = coarse_sun::sphere_view_factor(c, h);
                let q = quadrature(c, h);
                assert!(
                    (f - q).abs() < 2e-3 * q + 1e-6,
                    "h {h}, {deg}°: {f} against {q}"
                );
            }
            assert_eq!(coarse_sun::sphere_view_factor(1.0, h), 1.0 / (h * h));
            assert_eq!(coarse_sun::sphere_view_factor(-1.0 / h, h), 0.0);
            // Continuous where the horizon starts to cut the sphere.
            let edge = 1.0 / h;
            let inside = coarse_sun::sphere_view_factor(edge + 1e-9, h);
            let outside = coarse_sun::sphere_view_factor(edge - 1e-9, h);
            assert!((inside - outside).abs() < 1e-6, "{inside} {outside}");
        }
    }
}
