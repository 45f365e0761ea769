//! ODE integrators (being written).
