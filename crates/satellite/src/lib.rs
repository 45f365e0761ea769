//! # satsim-satellite: the Keldysh preprint 2015-26 satellite on the `satsim-tree` engine
//!
//! [`preprint`] configures the preprint's layout (a bus, a 3-DOF gimbal hinge made of three
//! 1-DOF hinges through two massless links, three panels) on the generic engine and
//! cross-checks the printed closed-form equations of motion (19) against it.
#![warn(missing_docs)]

pub mod accuracy;
pub mod api;
pub mod campaign;
pub mod effects;
pub mod linearize;
pub mod modes;
pub mod output;
pub mod preprint;
pub mod scene;
pub mod scene_keys;
pub mod simulation;
pub mod view;
