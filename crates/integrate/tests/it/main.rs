//! The integrators' tests: one binary (one link), one module per subject; `common` holds the test problems.

mod carry;
mod common;
mod convergence;
mod dense_events;
mod first_step;
mod hairer_reference;
mod properties;
mod quadratures;
mod short_rebounds;
mod simultaneous_events;
mod stiff_errors;
mod time_stops;
