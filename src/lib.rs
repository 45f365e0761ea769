//! satsim: attitude dynamics of hinged spacecraft.
//!
//! This facade re-exports the workspace crates:
//! - [`tree`]: the generic recursive multibody engine (CRBA, RNEA, ABA);
//! - [`satellite`]: the Keldysh preprint's layout, effects, scenes and runs;
//! - [`integrate`]: ODE integrators and event location.
#![warn(missing_docs)]

pub use satsim_integrate as integrate;
pub use satsim_satellite as satellite;
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
