//! The unrolled kernel behind the engine's one forward-dynamics entry: a
//! [`ForwardDynamics`] with [`UnrolledAba`] attached gives, bit for bit, the kernel's own
//! result where the kernel takes the lock mask and the generic ABA's elsewhere, `accepts`
//! says which, and the per-call path allocates nothing. (The kernel against the generic ABA,
//! to round-off, is tested in `kernel.rs` itself.)

use satsim_satellite::kernel::UnrolledAba;
use satsim_testkit::alloc::allocations;
use satsim_tree::aba::{aba, aba_hybrid, aba_hybrid_with_kinematics, aba_with_kinematics};
use satsim_tree::samples::{SplitMix, push_wheels, random_q};
use satsim_tree::spatial::Force;
use satsim_tree::{Data, ForwardDynamics, Input, Kernel, Model, forward_kinematics, read_model};
use std::path::Path;

/// The preprint satellite (`examples/satellite.toml`) with the peer orbit's three wheels.
fn satellite_with_wheels() -> Model {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/satellite.toml");
    let mut b = read_model(&path).unwrap().to_builder();
    push_wheels(&mut b, "bus");
    b.build().unwrap()
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

/// Every lock mask of the satellite's 8 hinges, with and without wrenches, with and without
/// current transforms: the entry gives the kernel's `_into` result bit for bit where
/// `accepts` (no gimbal hinge locked), else the generic function's bit for bit.
#[test]
fn the_entry_gives_the_kernels_or_the_generic_result_bit_for_bit() {
    let model = satellite_with_wheels();
    let kernel = UnrolledAba::new(&model).expect("the preprint's layout");
    let fd = ForwardDynamics::new(&model).with_kernel(Box::new(kernel.clone()));
    let mut rng = SplitMix(21);
    let (mut data, mut old) = (Data::new(&model), Data::new(&model));
    let (mut taken, mut generic) = (0, 0);
    for mask in 0..1u32 << model.n_hinges() {
        let locked: Vec<bool> = (0..model.n_hinges()).map(|h| mask >> h & 1 == 1).collect();
        let q = random_q(&model, &mut rng, 2.0);
        let v: Vec<f64> = (0..model.nv()).map(|_| rng.range(-1.0, 1.0)).collect();
        let tau: Vec<f64> = (0..model.nv()).map(|_| rng.range(-1.0, 1.0)).collect();
        let fext: Vec<Force> = (0..model.n_bodies())
            .map(|_| Force::new(rng.vec3(1.0), rng.vec3(1.0)))
            .collect();
        let gimbal_locked = locked[..3].iter().any(|&l| l);
        let mask = (mask != 0).then_some(locked.as_slice());
        assert_eq!(fd.uses_kernel(mask), !gimbal_locked, "{locked:?}");
        assert_eq!(kernel.accepts(mask), !gimbal_locked);
        for f in [None, Some(fext.as_slice())] {
            for xup in [false, true] {
                if xup {
                    forward_kinematics(&model, &mut data, &q, &v).unwrap();
                    forward_kinematics(&model, &mut old, &q, &v).unwrap();
                }
                let input = Input::new(&q, &v, &tau)
                    .fext(f)
                    .locked(mask)
                    .xup_current(xup);
                let mut ddq = vec![f64::NAN; model.nv()];
                let got = fd.solve(&model, &mut data, input, &mut ddq);
                let mut expected = vec![f64::NAN; model.nv()];
                let was = if gimbal_locked {
                    generic += 1;
                    let l = mask.unwrap();
                    let r = if xup {
                        aba_hybrid_with_kinematics(&model, &mut old, &q, &v, &tau, f, l)
                    } else {
                        aba_hybrid(&model, &mut old, &q, &v, &tau, f, l)
                    };
                    r.map(|a| expected.copy_from_slice(a.as_slice()))
                } else {
                    taken += 1;
                    let locks = match mask {
                        None => satsim_satellite::kernel::Locks::NONE,
                        Some(l) => kernel.locks(l).unwrap(),
                    };
                    kernel.aba_hybrid_with_forces_into(&q, &v, &tau, f, locks, &mut expected)
                };
                assert_eq!(got, was, "{locked:?}");
                if got.is_ok() {
                    assert_eq!(
                        bits(&ddq),
                        bits(&expected),
                        "{locked:?} fext {}",
                        f.is_some()
                    );
                }
            }
        }
    }
    assert_eq!((taken, generic), (32 * 4, 224 * 4));
    // Nothing locked without a kernel: the plain generic ABA, bit for bit.
    let plain = ForwardDynamics::new(&model);
    let q = random_q(&model, &mut rng, 2.0);
    let (v, tau) = (vec![0.1; model.nv()], vec![0.2; model.nv()]);
    let mut ddq = vec![0.0; model.nv()];
    plain
        .solve(&model, &mut data, Input::new(&q, &v, &tau), &mut ddq)
        .unwrap();
    assert_eq!(
        bits(&ddq),
        bits(
            aba(&model, &mut old, &q, &v, &tau, None)
                .unwrap()
                .as_slice()
        )
    );
    forward_kinematics(&model, &mut data, &q, &v).unwrap();
    let input = Input::new(&q, &v, &tau).xup_current(true);
    plain.solve(&model, &mut data, input, &mut ddq).unwrap();
    forward_kinematics(&model, &mut old, &q, &v).unwrap();
    let a = aba_with_kinematics(&model, &mut old, &q, &v, &tau, None).unwrap();
    assert_eq!(bits(&ddq), bits(a.as_slice()));
}

/// The kernel writes only `ddq`: a caller's forward kinematics in `data` stays as it was.
#[test]
fn the_kernel_leaves_data_alone() {
    let model = satellite_with_wheels();
    let fd = ForwardDynamics::new(&model).with_kernel(Box::new(UnrolledAba::new(&model).unwrap()));
    let mut data = Data::new(&model);
    let mut rng = SplitMix(4);
    let q = random_q(&model, &mut rng, 2.0);
    let (v, tau) = (vec![0.1; model.nv()], vec![0.2; model.nv()]);
    forward_kinematics(&model, &mut data, &q, &v).unwrap();
    let (xup, vel, ddq_before) = (data.xup.clone(), data.v.clone(), data.ddq.clone());
    let mut ddq = vec![0.0; model.nv()];
    let input = Input::new(&q, &v, &tau).xup_current(true);
    fd.solve(&model, &mut data, input, &mut ddq).unwrap();
    assert_eq!((data.xup, data.v, data.ddq), (xup, vel, ddq_before));
}

/// The entry with the kernel attached allocates nothing per call, in each of its forms
/// (kernel, kernel with locks, the generic hybrid form for a locked gimbal hinge).
#[test]
fn the_entry_with_the_kernel_does_not_allocate() {
    let model = satellite_with_wheels();
    let fd = ForwardDynamics::new(&model).with_kernel(Box::new(UnrolledAba::new(&model).unwrap()));
    let mut data = Data::new(&model);
    let mut q = model.neutral();
    q[7..12].copy_from_slice(&[0.1, 0.2, 0.3, 1.2, -1.0]);
    let (v, tau) = (vec![0.1; model.nv()], vec![0.2; model.nv()]);
    let fext = vec![Force::zero(); model.n_bodies()];
    let wheels_held: Vec<bool> = (0..model.n_hinges()).map(|h| h >= 5).collect();
    let gimbal_held: Vec<bool> = (0..model.n_hinges()).map(|h| h == 1).collect();
    let mut ddq = vec![0.0; model.nv()];
    let mut before = 0;
    for round in 0..3 {
        if round == 1 {
            before = allocations();
        }
        for l in [
            None,
            Some(wheels_held.as_slice()),
            Some(gimbal_held.as_slice()),
        ] {
            for f in [None, Some(fext.as_slice())] {
                let input = Input::new(&q, &v, &tau).fext(f).locked(l);
                fd.solve(&model, &mut data, input, &mut ddq).unwrap();
            }
        }
    }
    assert_eq!(allocations() - before, 0);
}
