//! satsim: attitude dynamics of hinged spacecraft.
//!
//! This facade re-exports the workspace crates:
//! - [`tree`]: the generic recursive multibody engine (CRBA, RNEA, ABA);
//! - [`integrate`]: ODE integrators and event location;
//! - [`environment`]: the spacecraft's world (epoch, Sun and shadow, atmosphere, the Earth's
//!   rotation and magnetic field);
//! - [`satellite`]: the Keldysh preprint's layout and its closed-form equations, checked;
//! - [`spacecraft`]: the spacecraft engine (effects, the simulation and its right-hand side);
//! - [`tools`]: scene files, campaigns, accuracy sweeps, linearisation and modes, output, the
//!   3-D view.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub use satsim_environment as environment;
pub use satsim_integrate as integrate;
pub use satsim_satellite as satellite;
pub use satsim_spacecraft as spacecraft;
pub use satsim_tools as tools;
pub use satsim_tree as tree;

/// The Rust snippets of the book (docs/src) run as doc tests, so the guide cannot drift
/// from the code.
#[cfg(doctest)]
mod book {
    #[doc = include_str!("../docs/src/guide/building-a-tree.md")]
    struct BuildingATree;
    #[doc = include_str!("../docs/src/theory/floating-base.md")]
    struct FloatingBase;
    #[doc = include_str!("../docs/src/guide/adding-an-effect.md")]
    struct AddingAnEffect;
}
