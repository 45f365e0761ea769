//! The per-call algorithms allocate nothing once `Data` exists (Pinocchio's Model/Data rule).

use satsim_testkit::alloc::allocations;
use satsim_tree::aba::aba;
use satsim_tree::cholesky::crba_cholesky;
use satsim_tree::samples::{chain, random_tree, random_tree_with_rotors};
use satsim_tree::*;

#[test]
fn per_call_algorithms_do_not_allocate() {
    // One small model (in-house Cholesky), one with gyrostat rotors (ABA's gyrostat form)
    // and one large enough for faer's path.
    // And a 3-DOF gimbal through massless links with a wheel on its tip (ABA's multi-axis
    // chain form with a gyrostat).
    let i = spatial::Mat3::identity();
    // The bus, the gimbal's two massless links and the panel, with a wheel on `wheel_on`.
    let gimbal_with_wheel = |wheel_on: &str| {
        ModelBuilder::new(BaseKind::Free)
            .body(Body::new("bus", 500.0, i * 40.0))
            .body(Body::massless("l1"))
            .body(Body::massless("l2"))
            .body(Body::new("panel", 20.0, i * 2.0))
            .body(Body::new(
                "wheel",
                1.0,
                spatial::Mat3::from_diagonal(&spatial::Vec3::new(0.1, 0.1, 0.2)),
            ))
            .hinge(Hinge::revolute("h1", "bus", "l1", spatial::Vec3::z()).at(spatial::Vec3::y()))
            .hinge(Hinge::revolute("h2", "l1", "l2", spatial::Vec3::x()))
            .hinge(
                Hinge::revolute("h3", "l2", "panel", spatial::Vec3::y())
                    .child_at(-spatial::Vec3::y()),
            )
            .hinge(Hinge::revolute("w", wheel_on, "wheel", spatial::Vec3::z()))
    };
    let gimbal = gimbal_with_wheel("panel").build().unwrap();
    assert_eq!((gimbal.chains().len(), gimbal.gyrostats().len()), (1, 1));
    // The preprint's layout (`satsim-satellite`'s unrolled kernel, whose own test this is
    // there): the gimbal with a second panel below the first and the wheel on the bus.
    let layout = gimbal_with_wheel("bus")
        .body(Body::new("panel2", 20.0, i * 2.0).with_com(spatial::Vec3::y()))
        .hinge(Hinge::revolute("h4", "panel", "panel2", spatial::Vec3::x()).at(spatial::Vec3::y()))
        .build()
        .unwrap();
    for model in [
        gimbal,
        layout,
        random_tree(12, BaseKind::Free, true, 5),
        random_tree_with_rotors(8, BaseKind::Free, true, 3, 5),
        chain(80, BaseKind::Free),
    ] {
        let mut data = Data::new(&model);
        let q = model.neutral();
        let v = vec![0.1; model.nv()];
        let tau = vec![0.2; model.nv()];
        let fext =
            vec![spatial::Force::new(spatial::Vec3::x(), spatial::Vec3::y()); model.n_bodies()];
        // Every other hinge locked (hybrid dynamics, by ABA and by the mass matrix).
        let locked: Vec<bool> = (0..model.n_hinges()).map(|h| h % 2 == 0).collect();
        let by_aba = ForwardDynamics::new(&model);
        let by_crba = ForwardDynamics::new(&model).with_method(Method::CrbaCholesky);
        let mut ddq = vec![0.0; model.nv()];
        // One warm-up round: faer initialises process-wide state (its kernel dispatch) on its
        // first call. Every later call must allocate nothing.
        let mut before = 0;
        for round in 0..4 {
            if round == 1 {
                before = allocations();
            }
            forward_kinematics(&model, &mut data, &q, &v).unwrap();
            crba(&model, &mut data, &q).unwrap();
            rnea(&model, &mut data, &q, &v, &tau, Some(&fext)).unwrap();
            bias(&model, &mut data, &q, &v, None).unwrap();
            aba(&model, &mut data, &q, &v, &tau, Some(&fext)).unwrap();
            aba(&model, &mut data, &q, &v, &tau, None).unwrap();
            crba_cholesky(&model, &mut data, &q, &v, &tau, None).unwrap();
            // The entry, in each of its forms.
            for fd in [&by_aba, &by_crba] {
                for l in [None, Some(locked.as_slice())] {
                    for f in [None, Some(fext.as_slice())] {
                        forward_kinematics(&model, &mut data, &q, &v).unwrap();
                        for xup in [true, false] {
                            let input = Input::new(&q, &v, &tau).fext(f).locked(l).xup_current(xup);
                            fd.solve(&model, &mut data, input, &mut ddq).unwrap();
                        }
                    }
                }
            }
            kinetic_energy(&model, &mut data, &q, &v).unwrap();
            momentum(&model, &data);
        }
        let after = allocations();
        assert_eq!(
            after - before,
            0,
            "{} allocations in the per-call algorithms ({} DOF)",
            after - before,
            model.nv()
        );
    }
}
