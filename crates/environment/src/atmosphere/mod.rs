//! The air's density (kg/m³) at a place and a time, for drag: two models.
//!
//! - [`exponential`]: Vallado's exponential table at the altitude over a spherical Earth, no
//!   date needed (the default);
//! - [`nrlmsise`]: NRLMSISE-00 (Picone et al. 2002) at the geodetic latitude, longitude and
//!   altitude in the Earth-fixed frame, at the date, with the solar flux and geomagnetic
//!   activity given as constants or read from a space-weather file ([`space_weather`]);
//!   [`nrlmsise::MsisTrack`] holds it on a lattice along a run, since one evaluation costs
//!   about as much as the rest of a right-hand side.

pub mod exponential;
pub mod nrlmsise;
pub mod space_weather;

pub use exponential::{density, density_at_altitude};
