//! A linear field over a flexible body's deformed mass ([`FlexModel::linear_field`]): the
//! gravity gradient's tidal field distributed over a beam. Its generalised forces and its
//! wrench are the gradients of its potential (so the energy budget closes), and its
//! generalised forces are the continuum's: the lateral load over the length, the deflected
//! mass's own, and the geometric stiffness of the field's axial load.

use satsim_tree::flexible::{Beam, FlexModel, Flexible, Modes};
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{BaseKind, Body, ModelBuilder};

const MODES: usize = 4;

/// A stiffened beam (2 m, EI 50, ρA 3) on a 20 kg body, rooted off the origin, tilted in
/// the body, bending along `bend`.
fn beam() -> Beam {
    beam_of(MODES)
}

/// [`beam`] with `modes` modes.
fn beam_of(modes: usize) -> Beam {
    let axis = Vec3::new(1.0, 0.4, -0.2).normalize();
    let bend = axis.cross(&Vec3::new(0.3, -0.2, 1.0)).normalize();
    Beam {
        root: Vec3::new(0.3, -0.2, 0.5),
        axis,
        bend,
        length: 2.0,
        ei: 50.0,
        rho_a: 3.0,
        modes,
    }
}

fn model(stiffening: bool) -> FlexModel {
    model_of(beam(), stiffening)
}

fn model_of(beam: Beam, stiffening: bool) -> FlexModel {
    let inertia = Mat3::new(4.0, 0.2, 0.1, 0.2, 5.0, -0.3, 0.1, -0.3, 6.0);
    let b = ModelBuilder::new(BaseKind::Free)
        .body(Body::new("panel", 20.0, inertia).with_com(Vec3::new(0.1, 0.05, -0.02)));
    FlexModel::build(
        b,
        &[Flexible {
            body: "panel".into(),
            modes: Modes::Beam(beam),
            damping: 0.0,
            stiffening,
        }],
    )
    .unwrap()
}

/// The tidal field `k (3 e eᵀ − 1)` (body axes).
fn tidal(k: f64, e: Vec3) -> Mat3 {
    let e = e.normalize();
    (e * e.transpose() * 3.0 - Mat3::identity()) * k
}

const ETA: [f64; MODES] = [0.08, -0.03, 0.01, 0.004];

/// The generalised forces and the wrench are `−∂V/∂η`, `−∂V/∂ρ` and `−∂V/∂θ` (a small turn
/// of the body in the field: the field `RᵀTR` and `Rᵀρ` in its axes), by central
/// differences.
#[test]
fn the_fields_forces_are_the_gradients_of_its_potential() {
    let m = model(true);
    let t = tidal(1.3e-3, Vec3::new(0.2, -0.7, 0.6));
    let rho = Vec3::new(0.4, 1.1, -0.6);
    let mut q = vec![0.0; MODES];
    let load = m.linear_field(0, &ETA, &t, &rho, &mut q);
    assert_eq!(load.potential, m.field_potential(0, &ETA, &t, &rho));
    let h = 1e-5;
    for k in 0..MODES {
        let (mut up, mut down) = (ETA, ETA);
        up[k] += h;
        down[k] -= h;
        let fd = -(m.field_potential(0, &up, &t, &rho) - m.field_potential(0, &down, &t, &rho))
            / (2.0 * h);
        println!("Q{k} {:e}, −∂V/∂η {fd:e}", q[k]);
        assert!((q[k] - fd).abs() < 1e-8 * q.iter().map(|x| x.abs()).fold(0.0, f64::max));
    }
    let scale = load.wrench.lin.norm() + load.wrench.ang.norm();
    for d in 0..3 {
        let e = Vec3::ith(d, h);
        let fd = -(m.field_potential(0, &ETA, &t, &(rho + e))
            - m.field_potential(0, &ETA, &t, &(rho - e)))
            / (2.0 * h);
        assert!((load.wrench.lin[d] - fd).abs() < 1e-8 * scale, "F{d}");
        let turned = |s: f64| {
            let r = nalgebra::Rotation3::new(e * s).into_inner();
            m.field_potential(0, &ETA, &(r.transpose() * t * r), &(r.transpose() * rho))
        };
        let fd = -(turned(1.0) - turned(-1.0)) / (2.0 * h);
        println!("N{d} {:e}, −∂V/∂θ {fd:e}", load.wrench.ang[d]);
        assert!((load.wrench.ang[d] - fd).abs() < 1e-8 * scale, "N{d}");
    }
    // Without stiffening the inertia is the undeformed one: no load on the modes.
    let mut q = vec![0.0; MODES];
    model(false).linear_field(0, &ETA, &t, &rho, &mut q);
    assert_eq!(q, [0.0; MODES]);
}

/// The generalised forces are `−∂V/∂η` for every mode count: those the flexible algorithms
/// have instances for (1 to 4) and the general code beyond.
#[test]
fn the_modal_forces_are_the_gradient_for_every_mode_count() {
    let t = tidal(1.3e-3, Vec3::new(0.2, -0.7, 0.6));
    let rho = Vec3::new(0.4, 1.1, -0.6);
    let all = [0.08, -0.03, 0.01, 0.004, -0.002, 0.001, 0.0005];
    for modes in 1..=all.len() {
        let m = model_of(beam_of(modes), true);
        let eta = &all[..modes];
        let mut q = vec![0.0; modes];
        m.linear_field(0, eta, &t, &rho, &mut q);
        let largest = q.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let h = 1e-5;
        for k in 0..modes {
            let (mut up, mut down) = (eta.to_vec(), eta.to_vec());
            up[k] += h;
            down[k] -= h;
            let fd = -(m.field_potential(0, &up, &t, &rho) - m.field_potential(0, &down, &t, &rho))
                / (2.0 * h);
            assert!(
                (q[k] - fd).abs() < 1e-8 * largest,
                "{modes} modes: Q{k} {:e}, −∂V/∂η {fd:e}",
                q[k]
            );
        }
    }
}

/// Against the continuum, by Simpson's rule on the beam's own mode shapes: the field at a
/// section `x` is `T (ρ + r₀ + x a + b w)`, so
/// `Qₖ = ∫ ρA φₖ bᵀT(ρ + r₀ + x a) dx + (bᵀT b) ηₖ − Σⱼ ηⱼ ∫ N φₖ' φⱼ' dx`, with the axial
/// load `N(x) = ρA ∫ₓᴸ aᵀT (ρ + r₀ + ξ a) dξ`. A beam hanging along the local vertical from its
/// root is in tension and stiffens; across it, compressed, it softens.
#[test]
fn the_fields_modal_forces_are_the_continuums() {
    let m = model(true);
    let bm = beam();
    let shapes = bm.cantilever_modes();
    let (a, b, r0, l) = (bm.axis, bm.bend, bm.root, bm.length);
    let simpson = |f: &dyn Fn(f64) -> f64| {
        let n = 2000;
        let h = l / n as f64;
        (0..=n)
            .map(|j| {
                let c = if j == 0 || j == n {
                    1.0
                } else if j % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                c * f(j as f64 * h)
            })
            .sum::<f64>()
            * h
            / 3.0
    };
    for (name, e, rho) in [
        (
            "tilted",
            Vec3::new(0.2, -0.7, 0.6),
            Vec3::new(0.4, 1.1, -0.6),
        ),
        ("along the vertical", a, Vec3::zeros()),
        ("across", b, Vec3::zeros()),
    ] {
        let k = 1.3e-3;
        let t = tidal(k, e);
        let mut q = vec![0.0; MODES];
        m.linear_field(0, &ETA, &t, &rho, &mut q);
        let base = rho + r0;
        let n_axial = |x: f64| {
            bm.rho_a * ((l - x) * a.dot(&(t * base)) + 0.5 * (l * l - x * x) * a.dot(&(t * a)))
        };
        let mut worst: f64 = 0.0;
        for kk in 0..MODES {
            let lateral =
                simpson(&|x| bm.rho_a * shapes[kk].shape(x)[0] * b.dot(&(t * (base + a * x))));
            let own = b.dot(&(t * b)) * ETA[kk];
            let geometric: f64 = (0..MODES)
                .map(|j| {
                    ETA[j]
                        * simpson(&|x| n_axial(x) * shapes[kk].shape(x)[1] * shapes[j].shape(x)[1])
                })
                .sum();
            let continuum = lateral + own - geometric;
            println!("{name}: Q{kk} {:e}, continuum {continuum:e}", q[kk]);
            worst = worst.max((q[kk] - continuum).abs());
        }
        let scale = q.iter().map(|x| x.abs()).fold(0.0, f64::max);
        assert!(worst < 1e-7 * scale, "{name}: {worst:e} of {scale:e}");
    }
    // Hanging along the vertical from the field's centre, the first mode stiffens by the
    // tension's share less the deflected mass's own: `k (2 J₁ + 2 (a·r₀) J₀ + 1)`, row 1.
    let k = 1.3e-3;
    let t = tidal(k, a);
    let (mut q0, mut q1) = (vec![0.0; MODES], vec![0.0; MODES]);
    let mut one = [0.0; MODES];
    one[0] = 1e-3;
    m.linear_field(0, &[0.0; MODES], &t, &Vec3::zeros(), &mut q0);
    m.linear_field(0, &one, &t, &Vec3::zeros(), &mut q1);
    let stiffening = -(q1[0] - q0[0]) / 1e-3;
    let s = bm.stiffening_integrals();
    let expected = k * (2.0 * s.j1[0] + 2.0 * a.dot(&r0) * s.j0[0] + 1.0);
    println!(
        "along the vertical: mode 1 stiffens by {stiffening:e} 1/s², k (2 J₁ + 2 (a·r₀) J₀ + 1) = {expected:e}"
    );
    assert!((stiffening - expected).abs() < 1e-9 * expected);
    assert!(stiffening > k);
}
