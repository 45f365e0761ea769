//! The composite-rigid-body algorithm (Featherstone §6.2): the joint-space mass matrix.

use crate::data::Data;
use crate::error::DynamicsError;
use crate::kinematics::update_transforms;
use crate::model::{BaseKind, Model};

/// Computes the mass matrix `M(q)` into `data.mass_matrix` (full, symmetric) and returns it.
///
/// For a free base the first six rows and columns belong to the root's spatial velocity
/// `[ω; v]` in root-body axes; the rest follow the hinges' order of addition.
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, ModelBuilder, crba, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 2.0, Mat3::identity() * 3.0))
///     .build()?;
/// let mut data = Data::new(&model);
/// let m = crba(&model, &mut data, &model.neutral())?;
/// assert_eq!((m[(0, 0)], m[(5, 5)]), (3.0, 2.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn crba<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &[f64],
) -> Result<&'d nalgebra::DMatrix<f64>, DynamicsError> {
    update_transforms(model, data, q)?;
    mass_matrix(model, data);
    Ok(&data.mass_matrix)
}

/// CRBA proper, from the transforms already in `data.xup` (so that forward dynamics by the
/// mass matrix computes them once).
pub(crate) fn mass_matrix(model: &Model, data: &mut Data) {
    let n = model.n_bodies();
    for i in 0..n {
        data.ic[i] = model.bodies[i].inertia;
    }
    for i in (1..n).rev() {
        let p = model.parent[i].expect("parent");
        // Hinges about coordinate axes by their fast path (planar similarities).
        let moved = match &model.coord_axis[i] {
            Some(a) => a.rigid_inv_transform(&data.ic[i], &data.xup[i]),
            None => data.ic[i].inv_transform(&data.xup[i]),
        };
        data.ic[p] += moved;
    }
    let m = &mut data.mass_matrix;
    for i in 1..n {
        let ji = model.joints[i].as_ref().expect("joint");
        let mut f = data.ic[i].mul_motion(&ji.s);
        m[(ji.dof, ji.dof)] = ji.s.dot(&f) + ji.armature;
        let mut j = i;
        while let Some(p) = model.parent[j] {
            f = match &model.coord_axis[j] {
                Some(a) => a.inv_apply_force(&data.xup[j], &f),
                None => data.xup[j].inv_apply_force(&f),
            };
            j = p;
            match &model.joints[j] {
                Some(jj) => {
                    let hij = jj.s.dot(&f);
                    m[(ji.dof, jj.dof)] = hij;
                    m[(jj.dof, ji.dof)] = hij;
                }
                None if model.base == BaseKind::Free => {
                    let col = [f.ang.x, f.ang.y, f.ang.z, f.lin.x, f.lin.y, f.lin.z];
                    for (r, x) in col.into_iter().enumerate() {
                        m[(r, ji.dof)] = x;
                        m[(ji.dof, r)] = x;
                    }
                }
                None => {}
            }
        }
    }
    // Entries between hinges on different branches are never written: they are zero from
    // `Data::new`, and every call writes exactly the same (ancestor, descendant) pattern.
    if model.base == BaseKind::Free {
        let m6 = data.ic[0].to_matrix();
        m.fixed_view_mut::<6, 6>(0, 0).copy_from(&m6);
    }
}
