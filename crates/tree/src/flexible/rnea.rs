//! Inverse dynamics of a tree with flexible bodies (RNEA extended by the modal equations).

use super::data::{FlexData, check_state, velocities};
use super::model::FlexModel;
use crate::error::DynamicsError;
use crate::kinematics::{base_motion, check_len};
use crate::model::BaseKind;
use crate::spatial::Force;
use nalgebra::DVector;

/// The generalised forces `τ = M(q) a + b(q, v)` into `data.tau`, `b` the velocity products,
/// the modal stiffness `ωₖ² ηₖ` and damping `2 ζ ωₖ η̇ₖ`, less `Jᵀ fext` (`fext` as in
/// [`crate::rnea()`], one per body, on the body's frame). A mode's entry is the modal force
/// that must act on it. Outward: each body's `aᵢ = Xupᵢ a_λ + Gᵢ η̈_λ + Sᵢ φ̈ᵢ + cᵢ`, its
/// frame force `fᵢ = I aᵢ + P η̈ᵢ + vᵢ ×* (I vᵢ + P η̇ᵢ)` and its own modal forces
/// `Pᵀ aᵢ + η̈ᵢ + D η̇ᵢ + K ηᵢ`; inward: `τ_hinge = Sᵀ fᵢ`, `f_λ += Xupᵀ fᵢ`, and a
/// flexible parent's modes take `Gᵢᵀ fᵢ`.
pub fn rnea<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    inverse(model, data, q, v, a, fext, false)
}

/// As [`rnea()`], reusing the first pass in `data`, which must be that of this `q` and `v`
/// (see [`super::aba_with_kinematics`]): the torques that hold locked hinges, after the
/// forward dynamics on the same state.
pub fn rnea_with_kinematics<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    inverse(model, data, q, v, a, fext, true)
}

fn inverse<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    fext: Option<&[Force]>,
    first_pass_current: bool,
) -> Result<&'d DVector<f64>, DynamicsError> {
    check_state(model, q, v)?;
    check_len("a", a.len(), model.nv())?;
    let rigid = &model.rigid;
    if let Some(f) = fext {
        check_len("fext", f.len(), rigid.n_bodies())?;
    }
    if !first_pass_current {
        velocities(model, data, q, v);
    }
    let (nq, nv) = (rigid.nq(), rigid.nv());
    let n = rigid.n_bodies();
    data.a[0] = base_motion(rigid, a);
    for i in 0..n {
        if let Some(joint) = &rigid.joints[i] {
            let p = rigid.parent[i].expect("parent");
            let mut ai = data.xup[i].apply_motion(&data.a[p]) + joint.s * a[joint.dof] + data.c[i];
            let (op, mp) = (model.offset[p], model.modes[p]);
            for (k, g) in data.g[data.g_offset[i]..][..mp].iter().enumerate() {
                ai += *g * a[nv + op + k];
            }
            data.a[i] = ai;
        }
        let inertia = &data.inertia[i];
        let (o, m) = (model.offset[i], model.modes[i]);
        let vi = data.v[i];
        let mut h = inertia.mul_motion(&vi);
        let mut f = inertia.mul_motion(&data.a[i]);
        for k in 0..m {
            let pk = model.momentum_at(i, q, k);
            h += pk * v[nv + o + k];
            f += pk * a[nv + o + k];
            data.tau[nv + o + k] = data.a[i].dot(&pk)
                + a[nv + o + k]
                + model.damping[o + k] * v[nv + o + k]
                + model.stiffness[o + k] * q[nq + o + k];
        }
        data.f[i] = f + vi.cross_force(&h);
        let modal = &mut data.tau.as_mut_slice()[nv + o..nv + o + m];
        model.add_stiffening(i, q, v, &vi, &mut data.f[i], modal);
        if let Some(fe) = fext {
            data.f[i] -= fe[i];
        }
    }
    for i in (1..n).rev() {
        let joint = rigid.joints[i].as_ref().expect("joint");
        let fi = data.f[i];
        data.tau[joint.dof] = joint.s.dot(&fi) + joint.armature() * a[joint.dof];
        let p = rigid.parent[i].expect("parent");
        let (op, mp) = (model.offset[p], model.modes[p]);
        for (k, g) in data.g[data.g_offset[i]..][..mp].iter().enumerate() {
            data.tau[nv + op + k] += g.dot(&fi);
        }
        let fp = data.xup[i].inv_apply_force(&fi);
        data.f[p] += fp;
    }
    if rigid.base == BaseKind::Free {
        let f0 = data.f[0];
        for (r, x) in [f0.ang.x, f0.ang.y, f0.ang.z, f0.lin.x, f0.lin.y, f0.lin.z]
            .into_iter()
            .enumerate()
        {
            data.tau[r] = x;
        }
    }
    Ok(&data.tau)
}

/// The torques that hold locked gyrostat rotors, in closed form: for each hinge `k` asked
/// for in `which` (one entry per hinge, as [`crate::gyrostat_torques`]), `τₖ = J (a · α_λ +
/// q̈ₖ) + armature q̈ₖ − a · n_ext`, `α_λ` the carrier's angular acceleration that the forward
/// dynamics on this state (its accelerations `a`, `[q̈; η̈]`) just left in `data.a`
/// ([`super::aba_with_kinematics`], [`super::aba_hybrid_with_kinematics`]), `n_ext` the
/// couple of `fext` on the rotor. RNEA's to round-off (a balanced rotor's velocity products
/// have no part along its axis), without its passes over the tree. `Ok(None)` where a hinge
/// asked for is not a rotor that the model folds into its rigid carrier: RNEA then
/// ([`rnea_with_kinematics`]).
pub fn gyrostat_torques<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    a: &[f64],
    fext: Option<&[Force]>,
    which: &[bool],
) -> Result<Option<&'d DVector<f64>>, DynamicsError> {
    closed_form(model, data, a, fext, which, false)
}

/// As [`gyrostat_torques`], with no forward dynamics run on this state: the accelerations
/// `a` (`[q̈; η̈]`) come from elsewhere (an integrator's slope), and the carriers'
/// accelerations from them where every rotor asked for rides the base, body 0, whose
/// acceleration is `a`'s first six entries (zero on a fixed base). `Ok(None)`, with nothing
/// written, where a rotor asked for rides another body or a hinge asked for is not a folded
/// rotor: RNEA then ([`rnea()`]).
pub fn gyrostat_torques_on_base<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    a: &[f64],
    fext: Option<&[Force]>,
    which: &[bool],
) -> Result<Option<&'d DVector<f64>>, DynamicsError> {
    closed_form(model, data, a, fext, which, true)
}

/// The two above: the carriers' angular accelerations from the solve's `data.a`, or
/// (`on_base`) the base's from `a`.
fn closed_form<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    a: &[f64],
    fext: Option<&[Force]>,
    which: &[bool],
    on_base: bool,
) -> Result<Option<&'d DVector<f64>>, DynamicsError> {
    let rigid = &model.rigid;
    let nb = rigid.base_nv();
    check_len("a", a.len(), model.nv())?;
    check_len("which", which.len(), rigid.nv() - nb)?;
    if let Some(f) = fext {
        check_len("fext", f.len(), rigid.n_bodies())?;
    }
    let asked = |i: usize| rigid.joints[i].as_ref().is_some_and(|j| which[j.dof - nb]);
    if (1..rigid.n_bodies()).any(|i| asked(i) && !(model.fold_rotors && rigid.is_gyrostat[i]))
        || on_base
            && rigid
                .gyrostats
                .iter()
                .any(|g| asked(g.body) && g.parent != 0)
    {
        return Ok(None);
    }
    // The base's angular acceleration, made once, where the slope gives it.
    let base = on_base.then(|| base_motion(rigid, a).ang);
    for g in &rigid.gyrostats {
        let joint = rigid.joints[g.body].as_ref().expect("joint");
        if which[joint.dof - nb] {
            let n_ext = fext.map_or(0.0, |f| joint.s.dot(&f[g.body]));
            let qdd = a[joint.dof];
            let alpha = base.as_ref().unwrap_or(&data.a[g.parent].ang);
            data.tau[joint.dof] =
                g.axial * (g.axis.dot(alpha) + qdd) + joint.armature() * qdd - n_ext;
        }
    }
    Ok(Some(&data.tau))
}

/// The bias forces `b(q, v)` (RNEA at zero acceleration) into `data.bias`.
pub fn bias<'d>(
    model: &FlexModel,
    data: &'d mut FlexData,
    q: &[f64],
    v: &[f64],
    fext: Option<&[Force]>,
) -> Result<&'d DVector<f64>, DynamicsError> {
    data.ddq.fill(0.0);
    let zero = std::mem::take(&mut data.ddq);
    let result = rnea(model, data, q, v, zero.as_slice(), fext).map(|_| ());
    data.ddq = zero;
    result?;
    data.bias.copy_from(&data.tau);
    Ok(&data.bias)
}
