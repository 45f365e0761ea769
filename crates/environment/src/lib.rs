//! The spacecraft's world: what surrounds an orbit at a date, as pure functions of time and
//! position. No state, no allocation; the effects that load the spacecraft
//! (`satsim_spacecraft::effects::{solar_radiation, drag, magnetic}`) call them.
//!
//! # Conventions
//!
//! - **Frames.** The inertial frame is the GCRF: Earth-centred, axes those of the J2000 mean
//!   equator and equinox to the precision of these models. The Earth-fixed frame (ITRF, for
//!   the field and the turning atmosphere) is reached by [`earth`]'s rotation.
//! - **Time.** An [`Epoch`] (hifitime) is t = 0 of a scene; a time `t` (s) of a run is the
//!   epoch plus `t` SI seconds. UT1 is taken equal to UTC: |UT1 − UTC| < 0.9 s, so the Earth's
//!   rotation angle is off by at most 0.0038 degrees.
//! - **Units.** SI throughout: metres, seconds, kilograms, tesla.
//!
//! # Files
//!
//! - `epoch.rs`: reading an epoch, and the time arguments the series take;
//! - `atmosphere/`: the exponential atmosphere (Vallado's table) and NRLMSISE-00 (the
//!   `nrlmsise00` crate) with its space-weather file and the lattice a run reads it through;
//! - `sun.rs`: the Sun's position (truncated VSOP87, Meeus);
//! - `shadow.rs`: the Earth's shadow, conical or cylindrical (Montenbruck & Gill 3.4.2);
//! - `earth_radiation.rs`: the Earth's reflected sunlight (albedo) and emitted infrared on a
//!   plate, and the view factor from a plate to a sphere;
//! - `earth.rs`: GCRF to ITRF (IAU-1976 precession, IAU-82 GMST) and the Earth's spin;
//! - `moon.rs`: the Moon's position (truncated ELP-2000/82, Meeus chapter 47);
//! - `gravity.rs`: the Earth's spherical-harmonic gravity (EGM2008 to degree and order 70,
//!   the coefficients in `data/egm2008_70.gfc`) and the third bodies' point-mass
//!   perturbations;
//! - `magnetic/`: the geomagnetic field, IGRF-14 (`igrf.rs`, the coefficients in
//!   `data/igrf14coeffs.txt`) or its tilted dipole (`dipole.rs`);
//! - `lattice.rs`: an Earth-fixed lattice a run reads a smooth field through (the gravity
//!   harmonics beyond J2, IGRF-14), each node a function of its indices only;
//! - `earth_radiation.rs` also holds the table of the cap's moments a run reads.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod atmosphere;
pub mod earth;
pub mod earth_radiation;
pub mod epoch;
pub mod gravity;
pub mod lattice;
pub mod magnetic;
pub mod moon;
pub mod shadow;
pub mod sun;
pub mod track;

pub use epoch::{Epoch, parse_epoch};

/// A 3-vector (m, m/s, T: see each function).
pub type Vec3 = nalgebra::Vector3<f64>;

/// The Earth's equatorial radius (m, WGS-84).
pub const R_EARTH: f64 = 6_378_137.0;
/// The Earth's gravitational parameter μ (m³/s²).
pub const MU_EARTH: f64 = 3.986004418e14;
/// The Earth's rotation rate (rad/s).
pub const OMEGA_EARTH: f64 = 7.292115e-5;
/// The astronomical unit (m, IAU 2012).
pub const AU: f64 = 149_597_870_700.0;
/// Solar radiation pressure at 1 AU (N/m²): the solar flux over the speed of light.
pub const SOLAR_PRESSURE_1AU: f64 = 4.56e-6;
