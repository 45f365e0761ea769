//! Impulse response: the jump in generalised velocity caused by a unit impulse on one hinge,
//! `Δv = M⁻¹ e_k` (Featherstone §11.3). Used to resolve hinge-stop impacts: a stop that must
//! change hinge `k`'s rate by `Δφ̇` applies the impulse `λ = Δφ̇ / (M⁻¹)_kk`, which conserves
//! the system's momentum because it acts between the hinge's two bodies.

use crate::crba::crba;
use crate::data::Data;
use crate::error::DynamicsError;
use crate::llt::{llt_in_place, llt_solve_in_place};
use crate::model::Model;
use nalgebra::DVector;

/// `M(q)⁻¹ e_k` for hinge `k` (order of addition), into `data.ddq` (overwritten).
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder, impulse::hinge_impulse, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 100.0, Mat3::identity() * 10.0))
///     .body(Body::new("panel", 1.0, Mat3::identity()))
///     .hinge(Hinge::revolute("h", "bus", "panel", Vec3::z()))
///     .build()?;
/// let mut data = Data::new(&model);
/// let dv = hinge_impulse(&model, &mut data, &model.neutral(), 0)?;
/// // The panel spins up and the bus counter-rotates: no net angular momentum is created.
/// assert!(dv[6] > 0.0 && dv[2] < 0.0 && (10.0 * dv[2] + 1.0 * (dv[2] + dv[6])).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn hinge_impulse<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
    k: usize,
) -> Result<&'d DVector<f64>, DynamicsError> {
    if k >= model.n_hinges() {
        return Err(DynamicsError::Dimension {
            what: "hinge index",
            expected: model.n_hinges(),
            got: k,
        });
    }
    crba(model, data, q)?;
    data.chol.copy_from(&data.mass_matrix);
    llt_in_place(&mut data.chol)?;
    data.ddq.fill(0.0);
    data.ddq[model.base_nv() + k] = 1.0;
    llt_solve_in_place(&data.chol, &mut data.ddq);
    Ok(&data.ddq)
}
