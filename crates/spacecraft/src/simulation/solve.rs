//! The dynamics stage's two solves, `q̈` of the tree and `[q̈; η̈]` of the flexible tree:
//! the right-hand side (`rhs.rs`) runs them with the hinges locked now, the hold torques
//! (`hold.rs`) with other locks. Apart from both so that each imports this, not the other.

use super::data::FlexWork;
use super::model::SimModel;
use satsim_tree::flexible::{self, FlexModel};
use satsim_tree::spatial::Force;
use satsim_tree::{Data, DynamicsError, Input};

/// The flexible tree's accelerations `[q̈; η̈]` for the rigid generalised forces `tau` (the
/// modes take none from the effects), hybrid with `locked`. `current`: the work's first
/// pass is this state's (the flexible kinematics or an earlier solve ran on it), so the ABA
/// reuses it (bit for bit the same result).
pub(super) fn flexible_dynamics<'w>(
    model: &FlexModel,
    work: &'w mut FlexWork,
    tau: &[f64],
    elastic: &[f64],
    fext: Option<&[Force]>,
    locked: Option<&[bool]>,
    current: bool,
) -> Result<&'w [f64], DynamicsError> {
    work.tau[..tau.len()].copy_from_slice(tau);
    // The loads' generalised forces on the modes (empty: none).
    if !elastic.is_empty() {
        work.tau[tau.len()..].copy_from_slice(elastic);
    }
    let FlexWork {
        data, q, v, tau, ..
    } = work;
    let ddq = match (locked, current) {
        (Some(l), false) => flexible::aba_hybrid(model, data, q, v, tau, fext, l)?,
        (Some(l), true) => flexible::aba_hybrid_with_kinematics(model, data, q, v, tau, fext, l)?,
        (None, false) => flexible::aba(model, data, q, v, tau, fext)?,
        (None, true) => flexible::aba_with_kinematics(model, data, q, v, tau, fext)?,
    };
    Ok(ddq.as_slice())
}

/// The generalised forces that give the flexible tree the rigid accelerations `ddq` and the
/// elastic `eta_ddot`: RNEA on the first pass that the dynamics just solved on this state left
/// in `work` (the hold torques, and the locked hinges' power).
pub(super) fn flexible_forces<'w>(
    model: &FlexModel,
    work: &'w mut FlexWork,
    ddq: &[f64],
    eta_ddot: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'w [f64], DynamicsError> {
    let nv = ddq.len();
    work.a[..nv].copy_from_slice(ddq);
    work.a[nv..].copy_from_slice(eta_ddot);
    let FlexWork { data, q, v, a, .. } = work;
    Ok(flexible::rnea_with_kinematics(model, data, q, v, a, fext)?.as_slice())
}

/// `q̈` into `ddq`: the one place the dynamics are solved, through the model's
/// [`ForwardDynamics`](satsim_tree::ForwardDynamics) (chosen once: the layout's unrolled
/// kernel where it takes the lock mask, else the generic ABA, hybrid when hinges are locked,
/// reusing the transforms when they are current; bit for bit the algorithm it calls).
pub(super) fn forward_dynamics(
    m: &SimModel,
    data: &mut Data,
    input: Input,
    ddq: &mut [f64],
) -> Result<(), DynamicsError> {
    m.fd.solve(&m.tree, data, input, ddq)
}
