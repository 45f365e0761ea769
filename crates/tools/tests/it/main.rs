//! The tools' tests (scenes, runs, campaigns' lanes, linearisation, output): one binary (one
//! link), one module per subject.

mod common;
mod earth_radiation;
mod edges;
mod energy_budget;
mod environment;
mod event_slopes;
mod faults;
mod flexible_loads;
mod flexible_scene;
mod fsw;
mod jacobian_update;
mod lanes;
mod linearize;
mod mounting;
mod orbit_gravity;
mod orbital_start;
mod plots;
mod roll_pitch_yaw;
mod scene;
mod sensors;
mod simulation_passes;
mod simultaneous_stops;
mod step_limit;
mod stepping;
mod thrusters;
mod wheel_release;
mod wheel_speed_limit;

// `edges` counts the allocations of output rows and whole runs (per thread: the other tests
// run in parallel threads).
#[global_allocator]
static GLOBAL: satsim_testkit::alloc::Counting = satsim_testkit::alloc::Counting;
