//! Item 4 of issue 3: every other formula the project takes from the preprint, each checked
//! by an independent computation: Table 2, the centre of mass (13), the gravity-gradient
//! torque, the quaternion equation (20), the gravity force approximation, and the Newton-Euler
//! equations (5)-(10) with (2), (3) and (16) from which (19) is derived.

use crate::common;

use common::{Rng, random_model, random_state, realistic};
use nalgebra::{Quaternion, UnitQuaternion, Vector4};
use satsim_satellite::checks::*;
use satsim_satellite::*;
use satsim_tree::aba::aba;
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{Data, Model, center_of_mass, forward_kinematics, forward_kinematics_acc};

/// Rotation of each model body relative to the bus, from the engine.
fn relative(data: &Data, i: usize) -> Mat3 {
    data.rotation[0].transpose() * data.rotation[i]
}

#[test]
fn table2_rotation_chain() {
    let mut worst = [0.0f64; 2];
    for seed in 0..200u64 {
        let mut rng = Rng(seed);
        let model = random_model(&mut rng);
        let (q, v, _) = random_state(&mut rng, 1.0);
        let layout = recognise(&model).unwrap();
        let mut data = Data::new(&model);
        forward_kinematics(&model, &mut data, &q, &v).unwrap();
        let phi = [q[7], q[8], q[9], q[10], q[11]];
        let [_, l1, l2, p1, p2, p3] = layout.bodies;
        for (k, variant) in [Variant::Printed, Variant::Corrected]
            .into_iter()
            .enumerate()
        {
            let t = table2(&layout.params, &phi, variant);
            // Rows whose frame is a model body frame.
            let rows_ok = [(t.p1, l1), (t.p2, l2), (t.o2, p1), (t.o4, p3)]
                .iter()
                .map(|(m, b)| (m - relative(&data, *b)).amax())
                .fold(0.0, f64::max);
            assert!(rows_ok < 1e-12, "{variant:?}: {rows_ok:e}");
            // Hinge frames: P_k is the parent turned by φ_k about e_k.
            let p4 = relative(&data, p1) * table2::rot(&layout.params.e[3], phi[3]);
            assert!((t.p4 - p4).amax() < 1e-12);
            worst[k] = worst[k].max((t.o3 - relative(&data, p2)).amax());
        }
    }
    println!(
        "Table 2 O3 row: printed max error {:.3}, corrected {:.2e}",
        worst[0], worst[1]
    );
    assert!(worst[0] > 0.5 && worst[1] < 1e-12);
}

/// (13) against the engine's centre of mass, with body centres of mass off the body frames.
#[test]
fn centre_of_mass_eq13() {
    for seed in 0..200u64 {
        let mut rng = Rng(seed);
        let model = random_model(&mut rng);
        let (q, v, tau) = random_state(&mut rng, 1.0);
        let layout = recognise(&model).unwrap();
        let mut data = Data::new(&model);
        forward_kinematics(&model, &mut data, &q, &v).unwrap();
        let r_o = center_of_mass(&model, &data);
        let bus = &model.bodies()[0];
        let r_o1 = data.position[0] + data.rotation[0] * bus.com();
        let sy = Symbols::new(&layout.params, &state_from_engine(&q, &v, &tau).unwrap());
        let by_13 = r_o + data.rotation[0] * bus_offset_eq13(&sy);
        assert!((by_13 - r_o1).norm() < 1e-11 * (1.0 + r_o.norm()), "{seed}");
        // (12): r_O2 = r_O1 + a1 + c2, etc.
        let com = |b: usize| data.position[b] + data.rotation[b] * model.bodies()[b].com();
        let r = data.rotation[0];
        assert!(
            (com(layout.body(2).unwrap()) - (r_o1 + r * sy.d_12())).norm()
                < 1e-11 * (1.0 + r_o.norm())
        );
        assert!(
            (com(layout.body(4).unwrap()) - (r_o1 + r * sy.d_14())).norm()
                < 1e-11 * (1.0 + r_o.norm())
        );
    }
}

/// `M_iG = −3 μ/r³ E × I E` as printed has the wrong sign: a brute-force sum over point
/// masses (exact inverse-square gravity) gives `+3`.
#[test]
fn gravity_gradient_sign() {
    let mut rng = Rng(42);
    let mut worst = [0.0f64; 2];
    for _ in 0..100 {
        let mass = rng.uniform(1.0, 1000.0);
        let inertia = rng.inertia(mass, 1.0);
        let r = rng.uniform(6.6e6, 4.2e7);
        let e = rng.unit();
        let centre = e * r;
        let points = point_masses(mass, &inertia);
        // The point masses reproduce the body.
        let pm = point_masses(mass, &inertia);
        let i_pm: Mat3 = pm
            .iter()
            .map(|(m, p)| (Mat3::identity() * p.norm_squared() - p * p.transpose()) * *m)
            .sum();
        assert!((i_pm - inertia).amax() < 1e-9 * inertia.amax());
        let exact = point_mass_torque(MU_EARTH, &centre, &points);
        for (k, v) in [Variant::Printed, Variant::Corrected]
            .into_iter()
            .enumerate()
        {
            // Either sense of the local vertical gives the same torque.
            let m_g = gravity_gradient_torque(v, MU_EARTH, r, &e, &inertia);
            let m_g2 = gravity_gradient_torque(v, MU_EARTH, r, &-e, &inertia);
            assert!((m_g - m_g2).norm() <= 1e-15 * m_g.norm());
            worst[k] = worst[k].max((m_g - exact).norm() / exact.norm());
        }
    }
    println!(
        "M_iG vs point masses: printed (-3) relative error {:.3}, corrected (+3) {:.2e}",
        worst[0], worst[1]
    );
    assert!(
        (worst[0] - 2.0).abs() < 1e-3,
        "printed is exactly the opposite"
    );
    assert!(worst[1] < 1e-5, "corrected agrees to O(size / r)");
    assert!(worst[1] > 0.0);
}

/// (20): `q̇ = ½ Ω q` with the printed `Ω` is the Hamilton kinematics of a SCALAR-LAST
/// quaternion of the bus-to-inertial rotation with `ω` in bus axes, i.e. nalgebra's
/// `UnitQuaternion::coords` order `[i, j, k, w]` of the state's `attitude`.
#[test]
fn quaternion_equation_20() {
    let mut rng = Rng(3);
    for _ in 0..20 {
        let q0 = rng.rotation();
        let w = rng.vec3(1.0);
        let t_end = 2.0;
        // RK4 on the preprint's equation from the preprint's quaternion.
        let f = |q: &Vector4<f64>| omega_matrix(&w) * q * 0.5;
        let mut q = paper_quaternion(&q0);
        let n = 2000;
        let h = t_end / n as f64;
        for _ in 0..n {
            let k1 = f(&q);
            let k2 = f(&(q + k1 * (h / 2.0)));
            let k3 = f(&(q + k2 * (h / 2.0)));
            let k4 = f(&(q + k3 * h));
            q += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        }
        // Exact: R(t) = R0 exp(t [ω×]) for ω in body axes.
        let exact = q0 * UnitQuaternion::from_scaled_axis(w * t_end);
        let exact_inertial = UnitQuaternion::from_scaled_axis(w * t_end) * q0;
        let same = |a: &Vector4<f64>, b: &Vector4<f64>| (a - b).amax().min((a + b).amax());
        assert!(
            same(&q, &exact.coords) < 1e-11,
            "{}",
            same(&q, &exact.coords)
        );
        // Not the inertial-axes reading, not a scalar-first reading.
        assert!(same(&q, &exact_inertial.coords) > 1e-3);
        let mut qf = Vector4::new(q0.w, q0.i, q0.j, q0.k);
        for _ in 0..n {
            let k1 = f(&qf);
            let k2 = f(&(qf + k1 * (h / 2.0)));
            let k3 = f(&(qf + k2 * (h / 2.0)));
            let k4 = f(&(qf + k3 * h));
            qf += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        }
        let as_first = Vector4::new(exact.w, exact.i, exact.j, exact.k);
        assert!(same(&qf, &as_first) > 1e-3);
        // The attitude matrix of the scalar-last (JPL) quaternion maps inertial to bus axes.
        let a = attitude_matrix(&paper_quaternion(&q0));
        assert!((a - q0.to_rotation_matrix().into_inner().transpose()).amax() < 1e-14);
        // And the round trip into nalgebra.
        let p = paper_quaternion(&q0);
        let back = UnitQuaternion::from_quaternion(Quaternion::new(p[3], p[0], p[1], p[2]));
        assert!(back.angle_to(&q0) < 1e-14);
    }
}

/// Bodies of a model as `(m_i, I_i inertial, ρ_i = r_Oi − r_O inertial)`.
fn bodies_about_com(model: &Model, data: &Data) -> Vec<(f64, Mat3, Vec3)> {
    let c = center_of_mass(model, data);
    model
        .bodies()
        .iter()
        .enumerate()
        .filter(|(_, b)| b.mass() > 0.0)
        .map(|(i, b)| {
            let r = data.rotation[i];
            (
                b.mass(),
                r * b.inertia_com() * r.transpose(),
                data.position[i] + r * b.com() - c,
            )
        })
        .collect()
}

/// `F_i ≈ −μ m_i r_O / r_O³` drops terms of the same order as the gravity-gradient torques it
/// keeps: quantified on the realistic satellite at 7000 km.
#[test]
fn gravity_force_approximation_budget() {
    let r = 7.0e6;
    let mut rng = Rng(11);
    let mut worst_split = 0.0f64;
    for d in Deployment::ALL {
        let (model, q, v, _) = realistic(d, 1.0);
        let mut data = Data::new(&model);
        forward_kinematics(&model, &mut data, &q, &v).unwrap();
        let bodies = bodies_about_com(&model, &data);
        // A generic direction of the local vertical, and the peaks over many directions.
        let (mut peak_kept, mut peak_dropped, mut peak_exact) = (0.0f64, 0.0f64, 0.0f64);
        let mut shown = None;
        for k in 0..2000 {
            let e = if k == 0 {
                Vec3::new(1.0, 1.0, 1.0).normalize()
            } else {
                rng.unit()
            };
            let b = gravity_budget(MU_EARTH, &(e * r), &bodies);
            peak_kept = peak_kept.max(b.kept.norm());
            peak_dropped = peak_dropped.max(b.dropped.norm());
            peak_exact = peak_exact.max(b.exact.norm());
            if k == 0 {
                shown = Some(b);
            }
        }
        let mut rng2 = Rng(12);
        for _ in 0..200 {
            let b = gravity_budget(MU_EARTH, &(rng2.unit() * r), &bodies);
            worst_split = worst_split.max((b.kept + b.dropped - b.exact).norm() / peak_exact);
        }
        let b = shown.unwrap();
        println!(
            "{d:?}: E = (1,1,1)/sqrt3, r = 7000 km: kept |sum M_iG| = {:.3e} N m, dropped = {:.3e} N m, exact = {:.3e} N m, dropped/kept = {:.3}, |kept - exact|/|exact| = {:.3}",
            b.kept.norm(),
            b.dropped.norm(),
            b.exact.norm(),
            b.dropped.norm() / b.kept.norm(),
            (b.kept - b.exact).norm() / b.exact.norm(),
        );
        println!(
            "{d:?}: peaks over 2000 directions: kept {peak_kept:.3e} N m, dropped {peak_dropped:.3e} N m, exact {peak_exact:.3e} N m, dropped/kept {:.3}",
            peak_dropped / peak_kept
        );
        assert!(peak_dropped / peak_kept > 0.1, "same order");
        // The relative size of the dropped force itself: 3|ρ_i|/r.
        let rho_max = bodies.iter().map(|(_, _, p)| p.norm()).fold(0.0, f64::max);
        println!(
            "{d:?}: max |rho_i| = {rho_max:.3} m, dropped force / kept force <= 3 rho/r = {:.2e}",
            3.0 * rho_max / r
        );
    }
    assert!(
        worst_split < 1e-5,
        "kept + dropped = exact to O(size/r): {worst_split:e}"
    );
}

/// Equations (5)-(10) (about `O1`, absolute accelerations, no gravity) hold on the engine's
/// motion; the printed (3) (duplicated body-3 term) and (2) (`e3` for `e4` at `δφ4`) and the
/// printed (16) (`φ̇` for `φ̈`) do not.
#[test]
fn newton_euler_equations_5_to_10_and_16() {
    let mut worst = [[0.0f64; 2]; 4];
    for seed in 0..100u64 {
        let mut rng = Rng(seed + 500);
        let model = random_model(&mut rng);
        let (q, v, tau) = random_state(&mut rng, 1.0);
        let layout = recognise(&model).unwrap();
        let mut data = Data::new(&model);
        let a = aba(&model, &mut data, &q, &v, &tau, None).unwrap().clone();
        forward_kinematics_acc(&model, &mut data, &q, &v, a.as_slice()).unwrap();
        // Inertial quantities of the preprint's bodies 1..4.
        let b = [1, 2, 3, 4].map(|i| layout.body(i).unwrap());
        let rot = |i: usize| data.rotation[b[i]];
        let com = |i: usize| *model.bodies()[b[i]].com();
        let mass = |i: usize| model.bodies()[b[i]].mass();
        let w = |i: usize| rot(i) * data.v[b[i]].ang;
        let wd = |i: usize| rot(i) * data.a[b[i]].ang;
        let r_o = |i: usize| data.position[b[i]] + rot(i) * com(i);
        let acc = |i: usize| {
            let (vv, aa, c) = (data.v[b[i]], data.a[b[i]], com(i));
            rot(i)
                * (aa.lin
                    + vv.ang.cross(&vv.lin)
                    + aa.ang.cross(&c)
                    + vv.ang.cross(&vv.ang.cross(&c)))
        };
        let kdot = |i: usize| {
            let ii = rot(i) * model.bodies()[b[i]].inertia_com() * rot(i).transpose();
            ii * wd(i) + w(i).cross(&(ii * w(i)))
        };
        let hinge_point = |k: usize| {
            let c = model.hinge_body()[k];
            let p = model.parent()[c].unwrap();
            data.position[p] + data.rotation[p] * model.joint(c).unwrap().at()
        };
        let axis = |k: usize| {
            let c = model.hinge_body()[k];
            let p = model.parent()[c].unwrap();
            data.rotation[p] * model.joint(c).unwrap().axis()
        };
        let f = |i: usize| acc(i) * mass(i); // m_i r̈_Oi − F_i with F_i = 0
        let (p1, p4, p5) = (hinge_point(0), hinge_point(3), hinge_point(4));
        let scale = (0..4)
            .map(|i| kdot(i).norm() + f(i).norm() * 3.0)
            .fold(1.0, f64::max);
        // (5), corrected, and the δθ1 coefficient of the printed (3).
        let sum_k: Vec3 = (0..4).map(kdot).sum();
        let arm = |i: usize| r_o(i) - r_o(0); // d_{1,i}
        let eq5 = sum_k + arm(1).cross(&f(1)) + arm(2).cross(&f(2)) + arm(3).cross(&f(3));
        let eq3 = sum_k + arm(1).cross(&f(1)) + arm(2).cross(&f(2)) + arm(2).cross(&f(2));
        worst[0][0] = worst[0][0].max(eq3.norm() / scale);
        worst[0][1] = worst[0][1].max(eq5.norm() / scale);
        // (6)-(8): moments about P1 of bodies 2..4 on e1, e2, e3.
        let about = |p: Vec3, from: usize| -> Vec3 {
            (from..4).map(|i| kdot(i) + (r_o(i) - p).cross(&f(i))).sum()
        };
        for k in 0..3 {
            let r = (about(p1, 1).dot(&axis(k)) - tau[6 + k]).abs() / scale;
            worst[1][1] = worst[1][1].max(r);
        }
        // (9) and (10); and (9) from the printed (2), whose body-3 bracket has e3 at δφ4.
        let eq9 = about(p4, 2).dot(&axis(3)) - tau[9];
        let eq10 = about(p5, 3).dot(&axis(4)) - tau[10];
        worst[1][1] = worst[1][1].max(eq9.abs().max(eq10.abs()) / scale);
        let body3 = kdot(2) + (r_o(2) - p4).cross(&f(2));
        let body4 = kdot(3) + (r_o(3) - p4).cross(&f(3));
        let eq9_printed2 = body3.dot(&axis(2)) + body4.dot(&axis(3)) - tau[9];
        worst[2][0] = worst[2][0].max(eq9_printed2.abs() / scale);
        worst[2][1] = worst[2][1].max(eq9.abs() / scale);
        // (16): ω̇2 = ω̇1 + e1ψ̇1 + ω1×e1ψ1 + e2ψ̇2 + (ω1+e1ψ1)×e2ψ2 + e3ψ̇3 + (…)×e3ψ3;
        // printed with e_kψ_k (φ̇) where e_kψ̇_k (φ̈) is meant.
        let (e1, e2, e3) = (axis(0), axis(1), axis(2));
        let (s1, s2, s3) = (v[6], v[7], v[8]);
        let (d1, d2, d3) = (a[6], a[7], a[8]);
        let w1 = w(0);
        let gyro = w1.cross(&(e1 * s1))
            + (w1 + e1 * s1).cross(&(e2 * s2))
            + (w1 + e1 * s1 + e2 * s2).cross(&(e3 * s3));
        let w2d = wd(0) + e1 * d1 + e2 * d2 + e3 * d3 + gyro;
        let w2d_printed = wd(0) + e1 * s1 + e2 * s2 + e3 * s3 + gyro;
        let ws = wd(1).norm().max(1.0);
        worst[3][0] = worst[3][0].max((w2d_printed - wd(1)).norm() / ws);
        worst[3][1] = worst[3][1].max((w2d - wd(1)).norm() / ws);
    }
    println!(
        "(3)/(5) rotation equation: printed {:.3e}, corrected {:.2e}",
        worst[0][0], worst[0][1]
    );
    println!("(6)-(10) hinge equations: {:.2e}", worst[1][1]);
    println!(
        "(2) body-3 axis at dphi4: printed {:.3e}, corrected {:.2e}",
        worst[2][0], worst[2][1]
    );
    println!(
        "(16) omega2 dot: printed {:.3e}, corrected {:.2e}",
        worst[3][0], worst[3][1]
    );
    for (k, w) in worst.iter().enumerate() {
        assert!(w[1] < 1e-11, "{k}: {w:?}");
        if k != 1 {
            assert!(w[0] > 1e-2, "{k}: {w:?}");
        }
    }
}
