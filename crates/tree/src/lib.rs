//! # satsim-tree: a generic recursive multibody engine
//!
//! Trees of rigid bodies joined by revolute hinges, with a free-floating or fixed root, after
//! Featherstone's *Rigid Body Dynamics Algorithms*. It knows nothing about spacecraft.
//!
//! - [`ModelBuilder`] builds an immutable, validated [`Model`]; [`Data`] is its reusable
//!   workspace: the per-call algorithms below allocate nothing.
//! - Forward dynamics has one entry, [`ForwardDynamics`]: made once per model (the method,
//!   ABA or CRBA + Cholesky, and an optional specialised [`Kernel`]), it solves each call
//!   ([`Input`]: external forces, locked hinges, transforms already current) by the form of
//!   the algorithm that fits it, bit for bit that algorithm's result.
//! - One file per algorithm, each the algorithm's page: [`forward_kinematics`], [`crba()`]
//!   (mass matrix), [`rnea()`] (inverse dynamics, [`bias`]), [`aba`] (O(n) forward dynamics,
//!   the default method), [`cholesky`] (forward dynamics through the mass matrix, with the
//!   dense factorisation of [`llt`]), [`kinetic_energy`], [`center_of_mass`], [`momentum`].
//!   [`kernel_parts`] holds the engine's pieces a specialised kernel needs.
//! - [`facet`]: the flat one-sided [`Facet`]s of a body's surface (area, normal, centroid,
//!   optical and drag coefficients) that the surface-force models read; data only, no
//!   algorithm of the tree reads them.
//! - [`io`] reads the model TOML and state JSON files of the command-line contract (cargo
//!   feature `files`, on by default; `default-features = false` builds the engine without
//!   serde, serde_json and toml).
//!
//! Conventions: SI units; spatial vectors angular-then-linear, in body coordinates about the
//! body frame's origin ([`spatial`]); quaternions are Hamilton `[w, x, y, z]`; a hinge torque
//! acts on the child and reacts on the parent. See [`model`] for the coordinates `q` and `v`.
//!
//! ```
//! use satsim_tree::{BaseKind, Body, Data, ForwardDynamics, Hinge, Input, ModelBuilder};
//! use satsim_tree::spatial::{Mat3, Vec3};
//! let model = ModelBuilder::new(BaseKind::Free)
//!     .body(Body::new("bus", 500.0, Mat3::identity() * 40.0))
//!     .body(Body::new("panel", 20.0, Mat3::from_diagonal(&Vec3::new(1.7, 6.7, 8.3))))
//!     .hinge(Hinge::revolute("h", "bus", "panel", Vec3::x()).at(Vec3::y()).child_at(Vec3::new(0.0, -1.0, 0.0)))
//!     .build()?;
//! let fd = ForwardDynamics::new(&model); // once per model
//! let mut data = Data::new(&model);
//! let (q, v) = (model.neutral(), vec![0.0; model.nv()]);
//! let mut tau = vec![0.0; model.nv()];
//! tau[6] = 1.0; // 1 N m on the hinge
//! let mut ddq = vec![0.0; model.nv()];
//! fd.solve(&model, &mut data, Input::new(&q, &v, &tau), &mut ddq)?;
//! assert!(ddq[6] > 0.0 && ddq[0] < 0.0); // the panel turns one way, the bus the other
//! // The hinge locked: hybrid dynamics, the hinge torque held by the lock.
//! fd.solve(&model, &mut data, Input::new(&q, &v, &tau).locked(Some(&[true])), &mut ddq)?;
//! assert!(ddq.iter().all(|&a| a == 0.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
// `unsafe` only to call the instances compiled for AVX2 where the CPU has it (`wide.rs`),
// each call with its safety comment.
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod aba;
mod axis;
pub mod cholesky;
pub mod crba;
pub mod data;
pub mod energy;
pub mod error;
pub mod facet;
pub mod flexible;
pub mod forward_dynamics;
pub mod impulse;
#[cfg(feature = "files")]
pub mod io;
pub mod kernel_parts;
pub mod kinematics;
pub mod llt;
pub mod model;
pub mod real;
pub mod rnea;
pub mod samples;
mod shape;
pub mod spatial;
mod wide;

pub use crba::crba;
pub use data::Data;
pub use energy::{
    center_of_mass, energy_and_momentum, kinetic_energy, kinetic_energy_after_kinematics, momentum,
};
pub use error::{DynamicsError, ModelError};
pub use facet::{Facet, facets_of_box};
pub use forward_dynamics::{ForwardDynamics, Input, Kernel, Method};
#[cfg(feature = "files")]
pub use io::{
    FileError, ModelFile, State, StateFile, parse_flex_model, parse_model, parse_state,
    read_flex_model, read_model, read_state,
};
pub use kinematics::{
    base_pose, forward_kinematics, forward_kinematics_acc, forward_poses, forward_poses_of,
    update_transforms,
};
pub use model::{
    BaseKind, Body, BodyInfo, BoxShape, Chain, Gyrostat, Hinge, Joint, Model, ModelBuilder,
};
pub use rnea::{bias, gyrostat_torques, rnea, rnea_for};
