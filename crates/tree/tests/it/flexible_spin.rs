//! A flexible body on a turning or accelerating frame (issue 53, item 1): the axial load of
//! the frame's own acceleration in the geometric stiffness. A cantilever on a spinning hub at
//! radius `R` has the same frequencies whether it is rooted off-axis in the hub body or is its
//! own body on a hinge at radius `R` (the rotating-cantilever problem of Wright et al. 1982 and
//! Yoo & Shin 1998); a frame accelerating along the beam softens it by `a J₀`; and a spinning
//! free spacecraft with off-axis hinged beams conserves its energy.

use crate::flexible::energies_and_momenta;
use nalgebra::{DMatrix, Quaternion, SymmetricEigen, UnitQuaternion};
use satsim_tree::flexible::beam::{PANELS, POINTS, gauss_legendre, integrate};
use satsim_tree::flexible::{self, Beam, FlexData, FlexModel, Flexible, Modes};
use satsim_tree::spatial::{Force, Mat3, Vec3};
use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder};

/// The unit beam (L = EI = ρA = 1) along x, bending along `bend`, from `root`.
fn unit_beam(root: Vec3, bend: Vec3, modes: usize) -> Beam {
    Beam {
        root,
        axis: Vec3::x(),
        bend,
        length: 1.0,
        ei: 1.0,
        rho_a: 1.0,
        modes,
    }
}

fn stiffened(body: &str, beam: Beam) -> Flexible {
    Flexible {
        body: body.into(),
        modes: Modes::Beam(beam),
        damping: 0.0,
        stiffening: true,
    }
}

/// A 10 kg hub on a hinge about z (`spin`) on a fixed base.
fn spinning_hub() -> ModelBuilder {
    ModelBuilder::new(BaseKind::Fixed)
        .body(Body::new("ground", 0.0, Mat3::zeros()))
        .body(Body::new("hub", 10.0, Mat3::identity() * 5.0))
        .hinge(Hinge::revolute("spin", "ground", "hub", Vec3::z()))
}

/// A hub spinning about z on a fixed base carrying the unit beam at radius `r`: rooted
/// off-axis in the hub itself (`hinged` false) or as its own body on a hinge about z at
/// `(r, 0, 0)` (`hinged` true, the way arrays are built).
fn hub(r: f64, bend: Vec3, modes: usize, hinged: bool) -> FlexModel {
    let b = spinning_hub();
    if hinged {
        let b = b
            .body(Body::new("beam", 0.0, Mat3::zeros()))
            .hinge(Hinge::revolute("lag", "hub", "beam", Vec3::z()).at(Vec3::new(r, 0.0, 0.0)));
        FlexModel::build(
            b,
            &[stiffened("beam", unit_beam(Vec3::zeros(), bend, modes))],
        )
    } else {
        FlexModel::build(
            b,
            &[stiffened(
                "hub",
                unit_beam(Vec3::new(r, 0.0, 0.0), bend, modes),
            )],
        )
    }
    .unwrap()
}

/// `−∂η̈/∂η` on the hub spinning steadily at `spin`, every hinge locked (held at its rate),
/// by central differences of the hybrid ABA (the modal equations are linear there, and free
/// of `η̇`: checked): `M⁻¹K`, the modal stiffness over the modal mass.
fn modal_stiffness(model: &FlexModel, spin: f64) -> DMatrix<f64> {
    let (nq, nv, m) = (model.rigid().nq(), model.rigid().nv(), model.n_elastic());
    let mut data = FlexData::new(model);
    let locked = vec![true; model.rigid().n_hinges()];
    let tau = vec![0.0; model.nv()];
    let mut eval = |eta: &[f64], etad: &[f64]| -> Vec<f64> {
        let mut q = model.neutral();
        q[nq..].copy_from_slice(eta);
        let mut v = vec![0.0; model.nv()];
        v[0] = spin;
        v[nv..].copy_from_slice(etad);
        let a = flexible::aba_hybrid(model, &mut data, &q, &v, &tau, None, &locked).unwrap();
        a.as_slice()[nv..].to_vec()
    };
    let zero = vec![0.0; m];
    let d = 1e-6;
    let mut k = DMatrix::zeros(m, m);
    for j in 0..m {
        let mut e = zero.clone();
        e[j] = d;
        let plus = eval(&e, &zero);
        e[j] = -d;
        let minus = eval(&e, &zero);
        for i in 0..m {
            k[(i, j)] = -(plus[i] - minus[i]) / (2.0 * d);
        }
        // No gyroscopic coupling of the modes at a locked steady spin.
        let mut ed = zero.clone();
        ed[j] = d;
        let g = eval(&zero, &ed);
        assert!(g.iter().all(|x| x.abs() < 1e-9), "{g:?}");
    }
    k
}

/// The beam's frequencies (rad/s, ascending) on the hub spinning steadily at `spin`
/// ([`modal_stiffness`], symmetric: the beam's modes alone have unit modal mass).
fn spinning_frequencies(model: &FlexModel, spin: f64) -> Vec<f64> {
    let k = modal_stiffness(model, spin);
    let asym = (&k - k.transpose()).amax();
    assert!(
        asym < 1e-6 * k.amax(),
        "modal stiffness not symmetric: {asym:e}"
    );
    let k = (&k + k.transpose()) * 0.5;
    let mut w: Vec<f64> = SymmetricEigen::new(k)
        .eigenvalues
        .iter()
        .map(|l| l.sqrt())
        .collect();
    w.sort_by(|a, b| a.partial_cmp(b).unwrap());
    w
}

/// The reference, from the continuum equation of the rotating cantilever alone,
/// `EI u'''' − (N u')' − s ρA Ω² u = ρA ω² u`, `N(x) = ρA Ω² (R (L − x) + (L² − x²)/2)`
/// (`s = 1` bending in the plane of rotation, 0 across it), by Galerkin on `m` cantilever
/// modes with the integrals at twice the engine's panels: its first two frequencies.
fn continuum_frequencies(m: usize, spin: f64, r: f64, chordwise: bool) -> [f64; 2] {
    let bm = unit_beam(Vec3::zeros(), Vec3::z(), m);
    let modes = bm.cantilever_modes();
    let rule = gauss_legendre(POINTS);
    let l = bm.length;
    let s = if chordwise { 1.0 } else { 0.0 };
    let k = DMatrix::from_fn(m, m, |i, j| {
        let n = bm.rho_a
            * spin
            * spin
            * integrate(l, 2 * PANELS, &rule, |x| {
                (r * (l - x) + 0.5 * (l * l - x * x)) * modes[i].shape(x)[1] * modes[j].shape(x)[1]
            });
        let own = if i == j {
            bm.omega(i + 1).powi(2) - s * spin * spin
        } else {
            0.0
        };
        own + n
    });
    let mut w: Vec<f64> = SymmetricEigen::new(k)
        .eigenvalues
        .iter()
        .map(|l| l.sqrt())
        .collect();
    w.sort_by(|a, b| a.partial_cmp(b).unwrap());
    [w[0], w[1]]
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs())
}

// 1. The hub radius. With L = EI = ρA = 1 the frequencies are the dimensionless ones of the
// tables, and the spin rate is γ = Ω √(ρA L⁴ / EI). Before the frame's acceleration entered
// the geometric stiffness, the hinged beam lost the hub radius: 4.7974 at γ = 3, R/L = 1
// (the R = 0 value), against 6.0818.
#[test]
fn hub_radius_is_kept_in_both_geometries() {
    // Wright et al. (1982) / Yoo & Shin (1998), first flapwise: (γ, R/L, ω); the chordwise
    // ones of this model (Euler-Bernoulli, inextensible) are √(ω² − γ²).
    let literature = [(3.0, 0.0, 4.7973), (3.0, 1.0, 6.0818), (10.0, 0.0, 11.2023)];
    let modes = 6;
    for spin in [3.0, 10.0] {
        for r in [0.0, 0.5, 1.0] {
            for (bend, chordwise, name) in [
                (Vec3::z(), false, "flapwise"),
                (Vec3::y(), true, "chordwise"),
            ] {
                let rooted = spinning_frequencies(&hub(r, bend, modes, false), spin);
                let hinged = spinning_frequencies(&hub(r, bend, modes, true), spin);
                let reference = continuum_frequencies(12, spin, r, chordwise);
                println!(
                    "γ = {spin}, R/L = {r}, {name}: rooted {:.5} {:.5}, hinged {:.5} {:.5}, continuum (12 modes) {:.5} {:.5}",
                    rooted[0], rooted[1], hinged[0], hinged[1], reference[0], reference[1]
                );
                for k in 0..2 {
                    assert!(
                        rel(rooted[k], hinged[k]) < 1e-6,
                        "{name} mode {}: rooted {} hinged {}",
                        k + 1,
                        rooted[k],
                        hinged[k]
                    );
                    // 6 modes against the 12-mode Galerkin: converged to 1e-3.
                    assert!(
                        rel(hinged[k], reference[k]) < 1e-3,
                        "{name} mode {}: {} vs {}",
                        k + 1,
                        hinged[k],
                        reference[k]
                    );
                }
                for &(g, rr, w) in &literature {
                    if g == spin && rr == r {
                        let expected = if chordwise { (w * w - g * g).sqrt() } else { w };
                        println!("  literature {expected:.5}");
                        assert!(
                            rel(hinged[0], expected) < 0.01,
                            "{} vs {expected}",
                            hinged[0]
                        );
                        assert!(
                            rel(rooted[0], expected) < 0.01,
                            "{} vs {expected}",
                            rooted[0]
                        );
                    }
                }
            }
        }
    }
}

// 1b. The classic table of the rotating cantilever without hub radius (Hodges & Rutkowski,
// AIAA J. 19(11), 1981, Table 1; Wright et al. 1982): the first two flapwise frequencies for
// γ = 0 … 10, and the chordwise ones of this (Euler-Bernoulli, inextensible) model,
// √(ω² − γ²), in both geometries, within 1 % (6e-4 measured, the worst a chordwise one).
#[test]
fn rotating_cantilever_matches_the_literature_table() {
    let table = [
        (0.0, 3.5160, 22.0345),
        (1.0, 3.6817, 22.1810),
        (2.0, 4.1373, 22.6149),
        (3.0, 4.7973, 23.3203),
        (4.0, 5.5850, 24.2733),
        (5.0, 6.4495, 25.4461),
        (6.0, 7.3604, 26.8091),
        (7.0, 8.2996, 28.3341),
        (8.0, 9.2568, 29.9954),
        (9.0, 10.2257, 31.7705),
        (10.0, 11.2023, 33.6404),
    ];
    let mut worst: f64 = 0.0;
    for hinged in [false, true] {
        for (bend, chordwise) in [(Vec3::z(), false), (Vec3::y(), true)] {
            let model = hub(0.0, bend, 6, hinged);
            for &(g, w1, w2) in &table {
                let w = spinning_frequencies(&model, g);
                for (k, lit) in [w1, w2].into_iter().enumerate() {
                    let expected = if chordwise {
                        (lit * lit - g * g).sqrt()
                    } else {
                        lit
                    };
                    let e = rel(w[k], expected);
                    worst = worst.max(e);
                    assert!(
                        e < 0.01,
                        "γ = {g}, mode {}, hinged {hinged}, chordwise {chordwise}: {} vs {expected}",
                        k + 1,
                        w[k]
                    );
                }
            }
        }
    }
    println!("worst relative difference from the table: {worst:e}");
}

// 2. Thrust along the beam: a free bus pushed along the beam's axis (towards its tip) at
// `a` compresses it, `N(x) = −ρA a (L − x)`, so the first mode's stiffness falls by `a J₀₁₁`
// (one mode, the bus heavy enough that the beam's momentum does not move it). Pushed the
// other way the beam is in tension and stiffens by as much.
#[test]
fn thrust_along_the_beam_softens_it_by_a_j0() {
    let beam = Beam {
        root: Vec3::new(0.5, 0.0, 0.0),
        axis: Vec3::x(),
        bend: Vec3::z(),
        length: 2.0,
        ei: 500.0,
        rho_a: 5.0,
        modes: 1,
    };
    let j0 = beam.stiffening().j0[0];
    let w0 = beam.omega(1);
    let mass = 1e7;
    let model = FlexModel::build(
        ModelBuilder::new(BaseKind::Free).body(Body::new("bus", mass, Mat3::identity() * mass)),
        &[stiffened("bus", beam)],
    )
    .unwrap();
    let mut data = FlexData::new(&model);
    let total = model.rigid().bodies()[0].mass();
    // The modal stiffness at rest: ω₀² raised by the bus's small share of the beam's
    // momentum (|P|²/I ~ 3e-6), the baseline the acceleration's load shifts.
    let mut base = 0.0;
    for accel in [0.0, 1.0, -1.0, 20.0] {
        // The applied force (RNEA's `fext`) at the frame origin, on the line of the centre
        // of mass: the bus and the beam's frame accelerate at `accel` along +x.
        let fext = [Force::new(Vec3::zeros(), Vec3::x() * (accel * total))];
        let mut acc = |eta: f64| {
            let mut q = model.neutral();
            q[7] = eta;
            let v = vec![0.0; model.nv()];
            flexible::aba(&model, &mut data, &q, &v, &[0.0; 7], Some(&fext)).unwrap()[6]
        };
        let d = 1e-6;
        let k = -(acc(d) - acc(-d)) / (2.0 * d);
        if accel == 0.0 {
            base = k;
            println!("at rest: ω² {k:.6}, ω₀² {:.6}", w0 * w0);
            assert!(rel(k, w0 * w0) < 1e-5);
            continue;
        }
        let coefficient = (base - k) / (accel * j0);
        println!(
            "frame acceleration {accel} m/s² along the beam: ω² {k:.6}, (ω²(0) − ω²)/(a J₀) = {coefficient:.8}"
        );
        assert!((coefficient - 1.0).abs() < 2e-5, "{coefficient}");
    }
}

/// `[q̇; v̇]` of a free-base flexible model (quaternion `q̇ = ½ q ⊗ [0; ω]`, `ṗ = R v`).
fn derivative(model: &FlexModel, data: &mut FlexData, x: &[f64], dx: &mut [f64]) {
    let (nq, nv) = (model.nq(), model.nv());
    let (q, v) = x.split_at(nq);
    let att = Quaternion::new(q[0], q[1], q[2], q[3]);
    let qd = att * Quaternion::new(0.0, v[0], v[1], v[2]) * 0.5;
    dx[..4].copy_from_slice(&[qd.w, qd.i, qd.j, qd.k]);
    let pd = UnitQuaternion::from_quaternion(att) * Vec3::new(v[3], v[4], v[5]);
    dx[4..7].copy_from_slice(pd.as_slice());
    dx[7..nq].copy_from_slice(&v[6..]);
    let a = flexible::aba(model, data, q, v, &vec![0.0; nv], None).unwrap();
    dx[nq..].copy_from_slice(a.as_slice());
}

/// Dormand-Prince 5(4) with error control (relative and absolute `tol`) from 0 to `t_end`;
/// calls `each` after every accepted step. Returns the number of steps.
fn dopri(
    model: &FlexModel,
    x: &mut [f64],
    t_end: f64,
    tol: f64,
    mut each: impl FnMut(&[f64]),
) -> usize {
    const A: [[f64; 6]; 7] = [
        [0.0; 6],
        [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
        [
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
            0.0,
            0.0,
        ],
        [
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
            0.0,
        ],
        [
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
        ],
    ];
    const E: [f64; 7] = [
        71.0 / 57600.0,
        0.0,
        -71.0 / 16695.0,
        71.0 / 1920.0,
        -17253.0 / 339200.0,
        22.0 / 525.0,
        -1.0 / 40.0,
    ];
    let n = x.len();
    let mut data = FlexData::new(model);
    let mut k = vec![vec![0.0; n]; 7];
    let mut y = vec![0.0; n];
    let (mut t, mut h, mut steps) = (0.0, 1e-3_f64, 0);
    derivative(model, &mut data, x, &mut k[0]);
    while t < t_end {
        h = h.min(t_end - t);
        for s in 1..7 {
            for i in 0..n {
                y[i] = x[i] + h * (0..s).map(|j| A[s][j] * k[j][i]).sum::<f64>();
            }
            let rest = &mut k[s];
            derivative(model, &mut data, &y, rest);
        }
        // y is the 5th-order solution (the 7th stage's argument, FSAL).
        let mut err: f64 = 0.0;
        for i in 0..n {
            let e = h * (0..7).map(|j| E[j] * k[j][i]).sum::<f64>();
            let sc = tol * (1.0 + x[i].abs().max(y[i].abs()));
            err = err.max((e / sc).abs());
        }
        if err <= 1.0 {
            t += h;
            x.copy_from_slice(&y);
            k.swap(0, 6);
            steps += 1;
            each(x);
        }
        h *= (0.9 * err.max(1e-10).powf(-0.2)).clamp(0.2, 5.0);
    }
    steps
}

/// The largest relative changes of the energy and of the linear and angular momenta (about
/// the centre of mass at the deformation) over `duration` s of DP5(4) at 1e-12 from `x`,
/// `each` seeing every step's state.
struct Drifts {
    energy: f64,
    linear: f64,
    angular: f64,
    /// The linear momentum at the start.
    p0: Vec3,
    steps: usize,
}

fn drifts(model: &FlexModel, x: &mut [f64], duration: f64, mut each: impl FnMut(&[f64])) -> Drifts {
    let nq = model.nq();
    let mut data = FlexData::new(model);
    let mut rigid = Data::new(model.rigid());
    let mut conserved = |x: &[f64]| {
        let (q, v) = x.split_at(nq);
        let (t, u, p, h) = energies_and_momenta(model, &mut data, &mut rigid, q, v);
        (t + u, p, h)
    };
    let (e0, p0, h0) = conserved(x);
    let (mut energy, mut linear, mut angular) = (0.0_f64, 0.0_f64, 0.0_f64);
    let steps = dopri(model, x, duration, 1e-12, |s| {
        let (e, p, h) = conserved(s);
        energy = energy.max(rel(e, e0));
        linear = linear.max((p - p0).norm() / p0.norm());
        angular = angular.max((h - h0).norm() / h0.norm());
        each(s);
    });
    Drifts {
        energy,
        linear,
        angular,
        p0,
        steps,
    }
}

// 3. Energy: a free bus spinning at 2 rad/s with two beams on hinges off its axis (one
// bending across the spin, one in its plane), deflected, hinges swinging: every new term
// (the foreshortening's first moment and momentum, the frame's velocity in the geometric
// stiffness) is in play; the Lagrangian keeps T + V over 20 s to the integrator's accuracy.
#[test]
fn spinning_bus_with_off_axis_hinged_beams_conserves_energy() {
    let beam = |axis: Vec3, bend: Vec3| Beam {
        root: Vec3::zeros(),
        axis,
        bend,
        length: 2.0,
        ei: 500.0,
        rho_a: 5.0,
        modes: 3,
    };
    let model = FlexModel::build(
        ModelBuilder::new(BaseKind::Free)
            .body(Body::new(
                "bus",
                50.0,
                Mat3::from_diagonal(&Vec3::new(8.0, 9.0, 10.0)),
            ))
            .body(Body::new("flap", 0.0, Mat3::zeros()))
            .body(Body::new("lag", 0.0, Mat3::zeros()))
            .hinge(Hinge::revolute("h1", "bus", "flap", Vec3::y()).at(Vec3::new(0.6, 0.1, 0.0)))
            .hinge(Hinge::revolute("h2", "bus", "lag", Vec3::z()).at(Vec3::new(-0.2, -0.6, 0.05))),
        &[
            stiffened("flap", beam(Vec3::x(), Vec3::z())),
            stiffened("lag", beam(-Vec3::y(), Vec3::x())),
        ],
    )
    .unwrap();
    let (nq, nv) = (model.nq(), model.nv());
    let mut x = vec![0.0; nq + nv];
    x[..nq].copy_from_slice(&model.neutral());
    // Spin about z, a wobble, drift; hinge rates; modes deflected and moving.
    let v0 = [
        0.05, -0.03, 2.0, 0.1, 0.0, -0.05, 0.3, -0.2, 0.05, -0.1, 0.2, -0.05, 0.1, 0.02,
    ];
    x[nq..].copy_from_slice(&v0[..nv]);
    x[7] = 0.1;
    x[8] = -0.2;
    x[9] = 0.02;
    x[10] = -0.004;
    x[12] = -0.015;
    x[13] = 0.003;
    let mut moved = 0.0_f64;
    let d = drifts(&model, &mut x, 20.0, |s| moved = moved.max(s[12].abs()));
    let (worst, dp, dh, p0) = (d.energy, d.linear, d.angular, d.p0);
    println!(
        "over 20 s, DP5(4) at 1e-12 ({} steps): energy drift {worst:e}, linear momentum {dp:e} (|p| {:.4}), angular momentum about the centre of mass {dh:e}",
        d.steps,
        p0.norm()
    );
    assert!(worst < 1e-8, "relative energy drift {worst:e}");
    assert!(dp < 1e-8 && dh < 1e-8, "momentum drift {dp:e} {dh:e}");
    assert!(p0.norm() > 1.0, "the linear momentum is not zero");
    assert!(moved > 0.01, "the in-plane beam bent: {moved}");
}

/// Kane, Ryan and Banerjee's hub rate profile (as in `flexible_dynamics.rs`): `(θ, Ω, Ω̇)`.
fn spin_profile(t: f64, rate: f64, ts: f64) -> (f64, f64, f64) {
    let w = 2.0 * std::f64::consts::PI / ts;
    if t < ts {
        let c = rate / ts;
        (
            c * (0.5 * t * t + ((w * t).cos() - 1.0) / (w * w)),
            c * (t - (w * t).sin() / w),
            c * (1.0 - (w * t).cos()),
        )
    } else {
        (rate * (t - 0.5 * ts), rate, 0.0)
    }
}

/// Their beam (L = 10 m, ρA = 1.2 kg/m, EI = 14 000 N m²) along x from `root`, bending in
/// the plane of rotation along y (the direction the hub moves it).
fn krb_beam(root: Vec3) -> Beam {
    Beam {
        root,
        axis: Vec3::x(),
        bend: Vec3::y(),
        length: 10.0,
        ei: 14_000.0,
        rho_a: 1.2,
        modes: 4,
    }
}

/// The spin-up with every hinge's motion prescribed (the hub's by the profile, a lag hinge
/// held at 0): `M_ee η̈ = −(RNEA's modal forces at [Ω̇, 0…])`, RK4 at `h` to `t_end`; the
/// tip deflection of body `body` every `every` steps.
fn prescribed_spin_up(
    model: &FlexModel,
    body: usize,
    h: f64,
    t_end: f64,
    every: usize,
) -> Vec<(f64, f64)> {
    let (nh, m) = (model.rigid().nv(), model.n_elastic());
    let mut data = FlexData::new(model);
    let (mut q, mut v, mut a) = (model.neutral(), vec![0.0; nh + m], vec![0.0; nh + m]);
    let mut f = |t: f64, x: &[f64], dx: &mut [f64]| {
        let (theta, rate, accel) = spin_profile(t, 6.0, 15.0);
        q[0] = theta;
        v[0] = rate;
        a[0] = accel;
        q[nh..].copy_from_slice(&x[..m]);
        v[nh..].copy_from_slice(&x[m..]);
        let tau = flexible::rnea(model, &mut data, &q, &v, &a, None).unwrap();
        let mut rhs = nalgebra::DVector::from_fn(m, |k, _| -tau[nh + k]);
        let mm = flexible::crba(model, &mut data, &q).unwrap();
        let mee = mm.view((nh, nh), (m, m)).into_owned();
        mee.cholesky().unwrap().solve_mut(&mut rhs);
        dx[..m].copy_from_slice(&x[m..]);
        dx[m..].copy_from_slice(rhs.as_slice());
    };
    let n = 2 * m;
    let mut x = vec![0.0; n];
    let (mut k1, mut k2, mut k3, mut k4, mut y) = (
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
    );
    let mut out = Vec::new();
    let mut qq = model.neutral();
    let steps = (t_end / h).round() as usize;
    for s in 0..steps {
        let t = s as f64 * h;
        f(t, &x, &mut k1);
        for i in 0..n {
            y[i] = x[i] + 0.5 * h * k1[i];
        }
        f(t + 0.5 * h, &y, &mut k2);
        for i in 0..n {
            y[i] = x[i] + 0.5 * h * k2[i];
        }
        f(t + 0.5 * h, &y, &mut k3);
        for i in 0..n {
            y[i] = x[i] + h * k3[i];
        }
        f(t + h, &y, &mut k4);
        for i in 0..n {
            x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        if (s + 1) % every == 0 {
            qq[nh..].copy_from_slice(&x[..m]);
            out.push(((s + 1) as f64 * h, model.tip_deflection(body, &qq).unwrap()));
        }
    }
    out
}

/// The quasi-static tip lag of the spin-up with hub radius `r`, from the continuum equation
/// in the hub frame projected on the 4 modes: `ρA (ü + Ω̇ (r + x) − Ω² u) + EI u'''' −
/// (N u')' = 0`, `N = ρA Ω² (r_n (L − x) + (L² − x²)/2)` (`r_n = r`; `r_n = 0` is the axial
/// load without the hub radius).
fn quasi_static_lag(r: f64, r_n: f64, t: f64) -> f64 {
    let bm = krb_beam(Vec3::zeros());
    let (_, rate, accel) = spin_profile(t, 6.0, 15.0);
    let modes = bm.cantilever_modes();
    let rule = gauss_legendre(POINTS);
    let (l, ra, m) = (bm.length, bm.rho_a, bm.modes);
    let k = DMatrix::from_fn(m, m, |i, j| {
        let n = ra
            * integrate(l, 2 * PANELS, &rule, |x| {
                (r_n * (l - x) + 0.5 * (l * l - x * x))
                    * modes[i].shape(x)[1]
                    * modes[j].shape(x)[1]
            });
        let own = if i == j {
            bm.omega(i + 1).powi(2) - rate * rate
        } else {
            0.0
        };
        own + rate * rate * n
    });
    let load = nalgebra::DVector::from_fn(m, |i, _| {
        -accel * ra * integrate(l, 2 * PANELS, &rule, |x| (r + x) * modes[i].shape(x)[0])
    });
    let eta = k.lu().solve(&load).unwrap();
    (0..m).map(|i| modes[i].shape(l)[0] * eta[i]).sum()
}

// 4. The spin-up of Kane, Ryan and Banerjee's beam at a hub radius of 2 m: rooted off-axis
// in the hub, or its own body on a (held) hinge there, the same response, and the
// continuum's quasi-static lag with the radius (the tangential load Ω̇ (R + x), the
// stiffening Ω² (R J₀ + J₁)).
#[test]
fn spin_up_is_the_same_rooted_or_hinged_off_axis() {
    let r = 2.0;
    let ground = || {
        ModelBuilder::new(BaseKind::Fixed)
            .body(Body::new("ground", 0.0, Mat3::zeros()))
            .body(Body::new("hub", 10.0, Mat3::identity() * 5.0))
            .hinge(Hinge::revolute("spin", "ground", "hub", Vec3::z()))
    };
    let rooted = FlexModel::build(
        ground(),
        &[stiffened("hub", krb_beam(Vec3::new(r, 0.0, 0.0)))],
    )
    .unwrap();
    let hinged = FlexModel::build(
        ground()
            .body(Body::new("beam", 0.0, Mat3::zeros()))
            .hinge(Hinge::revolute("lag", "hub", "beam", Vec3::z()).at(Vec3::new(r, 0.0, 0.0))),
        &[stiffened("beam", krb_beam(Vec3::zeros()))],
    )
    .unwrap();
    let a = prescribed_spin_up(&rooted, 1, 2e-3, 20.0, 25);
    let b = prescribed_spin_up(&hinged, 2, 2e-3, 20.0, 25);
    let peak = a.iter().fold(0.0_f64, |p, s| p.max(s.1.abs()));
    let diff = a
        .iter()
        .zip(&b)
        .fold(0.0_f64, |d, (x, y)| d.max((x.1 - y.1).abs()));
    let at = |run: &[(f64, f64)], t: f64| run.iter().find(|s| (s.0 - t).abs() < 1e-9).unwrap().1;
    let (lag, qs) = (at(&b, 7.5), quasi_static_lag(r, r, 7.5));
    let (qs0, lost) = (
        quasi_static_lag(0.0, 0.0, 7.5),
        quasi_static_lag(r, 0.0, 7.5),
    );
    println!(
        "spin-up at R = {r} m: peak lag {peak:.5} m, rooted vs hinged {diff:e} m; at 7.5 s {lag:.5} m, quasi-static {qs:.5} m (R = 0: {qs0:.5} m; the radius's axial load lost: {lost:.5} m)"
    );
    assert!(diff < 1e-9 * peak, "{diff:e}");
    assert!(rel(lag, qs) < 0.01, "{lag} vs {qs}");
    assert!(
        rel(lost, qs) > 0.1,
        "the radius's axial load matters: {lost} vs {qs}"
    );
    let after = b
        .iter()
        .filter(|s| s.0 >= 16.0)
        .fold(0.0_f64, |p, s| p.max(s.1.abs()));
    assert!(after < 0.01, "{after}");
}

// 5. The deflection's first-order inertia (issue 53, item 2): a beam spun about an axis
// tilted from its normal feels the transverse component of the centrifugal field,
// `−ρA Ω² sin θ cos θ x` along its bend (a linearly growing load), plus the axial
// `Ω² cos² θ` stiffening and the `Ω² sin² θ` softening of its own deflection. The hub's hinge
// is held at the rate `Ω` (locked); the static deflection is where the modes' accelerations
// vanish. Without the first-order inertia the beam would not bend at all.
#[test]
fn tilted_spin_bends_the_beam_by_its_centrifugal_load() {
    let theta: f64 = 0.5;
    let spin_axis = Vec3::new(theta.sin(), 0.0, theta.cos());
    let (l, ei, rho_a) = (2.0, 500.0, 5.0);
    let modes = 6;
    let model = FlexModel::build(
        ModelBuilder::new(BaseKind::Fixed)
            .body(Body::new("ground", 0.0, Mat3::zeros()))
            .body(Body::new("hub", 10.0, Mat3::identity() * 5.0))
            .hinge(Hinge::revolute("spin", "ground", "hub", spin_axis)),
        &[stiffened(
            "hub",
            Beam {
                root: Vec3::zeros(),
                axis: Vec3::x(),
                bend: Vec3::z(),
                length: l,
                ei,
                rho_a,
                modes,
            },
        )],
    )
    .unwrap();
    let bm = model.beam(1).unwrap().clone();
    let mut data = FlexData::new(&model);
    let mut static_tip = |spin: f64| {
        let mut acc = |eta: &[f64]| {
            let mut q = model.neutral();
            q[1..].copy_from_slice(eta);
            let mut v = vec![0.0; model.nv()];
            v[0] = spin;
            let a = flexible::aba_hybrid(
                &model,
                &mut data,
                &q,
                &v,
                &vec![0.0; model.nv()],
                None,
                &[true],
            )
            .unwrap();
            nalgebra::DVector::from_column_slice(&a.as_slice()[1..])
        };
        let f = acc(&vec![0.0; modes]);
        let d = 1e-6;
        let k = DMatrix::from_fn(modes, modes, |i, j| {
            let mut e = vec![0.0; modes];
            e[j] = d;
            let p = acc(&e);
            e[j] = -d;
            -(p[i] - acc(&e)[i]) / (2.0 * d)
        });
        let eta = k.lu().solve(&f).unwrap();
        let mut q = model.neutral();
        q[1..].copy_from_slice(eta.as_slice());
        model.tip_deflection(1, &q).unwrap()
    };
    // Slow: the cantilever under q(x) = q₀ x / L, tip 11 q₀ L⁴ / (120 EI).
    let slow = 0.05;
    let q0 = -rho_a * slow * slow * theta.sin() * theta.cos() * l;
    let closed = 11.0 * q0 * l.powi(4) / (120.0 * ei);
    let tip = static_tip(slow);
    println!("tilted spin at {slow} rad/s: static tip {tip:e} m, closed form {closed:e} m");
    assert!(rel(tip, closed) < 1e-3, "{tip} vs {closed}");
    // Fast: against the continuum by Galerkin on 12 modes,
    // (diag(ω²) + Ω² (cos² θ J₁ − sin² θ)) η = −Ω² sin θ cos θ S₂.
    let fast = 4.0;
    let m = 12;
    let reference = {
        let b12 = Beam {
            modes: m,
            ..bm.clone()
        };
        let shapes = b12.cantilever_modes();
        let rule = gauss_legendre(POINTS);
        let (s, c) = theta.sin_cos();
        let k = DMatrix::from_fn(m, m, |i, j| {
            let j1 = rho_a
                * integrate(l, 2 * PANELS, &rule, |x| {
                    0.5 * (l * l - x * x) * shapes[i].shape(x)[1] * shapes[j].shape(x)[1]
                });
            let own = if i == j {
                b12.omega(i + 1).powi(2) - fast * fast * s * s
            } else {
                0.0
            };
            own + fast * fast * c * c * j1
        });
        let load = nalgebra::DVector::from_fn(m, |i, _| {
            -fast
                * fast
                * s
                * c
                * rho_a
                * integrate(l, 2 * PANELS, &rule, |x| x * shapes[i].shape(x)[0])
        });
        let eta = k.lu().solve(&load).unwrap();
        (0..m).map(|i| shapes[i].shape(l)[0] * eta[i]).sum::<f64>()
    };
    let tip = static_tip(fast);
    println!(
        "tilted spin at {fast} rad/s: static tip {tip:.6} m, continuum (12 modes) {reference:.6} m"
    );
    assert!(rel(tip, reference) < 1e-3, "{tip} vs {reference}");
}

/// The frequencies (rad/s, ascending, below `below`) of a free body spinning steadily at
/// `spin` about z: without external forces the body-frame velocity, the hinge angles and
/// the modes evolve free of the pose, so `z = [v; x; ẋ]` (`x` the hinge angles or modes
/// kept) is linearised by central differences of `accel(q_x, v) → [v̇; ẍ]` about
/// `v = [0, 0, spin, 0, 0, 0]`, `x = 0`; the positive imaginary parts of the eigenvalues.
fn free_spin_frequencies(
    n: usize,
    spin: f64,
    below: f64,
    mut accel: impl FnMut(&[f64], &[f64]) -> Vec<f64>,
) -> Vec<f64> {
    let dim = 6 + 2 * n;
    let mut z0 = vec![0.0; dim];
    z0[2] = spin;
    let mut rhs = |z: &[f64]| -> Vec<f64> {
        let (v, rest) = z.split_at(6);
        let (x, xd) = rest.split_at(n);
        let mut vv = v.to_vec();
        vv.extend_from_slice(xd);
        let a = accel(x, &vv);
        let mut out = a[..6].to_vec();
        out.extend_from_slice(xd);
        out.extend_from_slice(&a[6..]);
        out
    };
    let d = 1e-6;
    let mut jac = DMatrix::zeros(dim, dim);
    for j in 0..dim {
        let mut z = z0.clone();
        z[j] += d;
        let p = rhs(&z);
        z[j] -= 2.0 * d;
        let m = rhs(&z);
        for i in 0..dim {
            jac[(i, j)] = (p[i] - m[i]) / (2.0 * d);
        }
    }
    let mut w: Vec<f64> = jac
        .complex_eigenvalues()
        .iter()
        .map(|e| e.im)
        .filter(|&im| im > 1e-6 && im < below)
        .collect();
    w.sort_by(|a, b| a.partial_cmp(b).unwrap());
    w
}

/// The bus of the spinning checks: 50 kg, its major axis z.
fn spin_bus(b: ModelBuilder) -> ModelBuilder {
    b.body(Body::new(
        "bus",
        50.0,
        Mat3::from_diagonal(&Vec3::new(4.0, 3.0, 6.0)),
    ))
}

/// The modal model: the bus and two contract beams (6 modes) on hinges about x at
/// `(0, ±offset, 0)`, along ±y, bending along z; frequencies of the hinges locked.
fn modal_spin_frequencies(offset: f64, spin: f64, below: f64) -> Vec<f64> {
    let beam = |dir: f64| Beam {
        root: Vec3::zeros(),
        axis: Vec3::y() * dir,
        bend: Vec3::z(),
        length: 2.0,
        ei: 500.0,
        rho_a: 5.0,
        modes: 6,
    };
    let model = FlexModel::build(
        spin_bus(ModelBuilder::new(BaseKind::Free))
            .body(Body::new("p", 0.0, Mat3::zeros()))
            .body(Body::new("q", 0.0, Mat3::zeros()))
            .hinge(Hinge::revolute("hp", "bus", "p", Vec3::x()).at(Vec3::new(0.0, offset, 0.0)))
            .hinge(Hinge::revolute("hq", "bus", "q", Vec3::x()).at(Vec3::new(0.0, -offset, 0.0))),
        &[stiffened("p", beam(1.0)), stiffened("q", beam(-1.0))],
    )
    .unwrap();
    let (nq, nv, m) = (model.rigid().nq(), model.rigid().nv(), model.n_elastic());
    let mut data = FlexData::new(&model);
    free_spin_frequencies(m, spin, below, |x, vv| {
        let mut q = model.neutral();
        q[nq..].copy_from_slice(x);
        let mut v = vec![0.0; model.nv()];
        v[..6].copy_from_slice(&vv[..6]);
        v[nv..].copy_from_slice(&vv[6..]);
        let a = flexible::aba_hybrid(
            &model,
            &mut data,
            &q,
            &v,
            &vec![0.0; model.nv()],
            None,
            &[true, true],
        )
        .unwrap();
        let mut out = a.as_slice()[..6].to_vec();
        out.extend_from_slice(&a.as_slice()[nv..]);
        out
    })
}

/// The rigid-chain model: each beam as `n` segments with hinge springs `EI / (L / n)`, the
/// first at `(0, ±offset, 0)`.
fn chain_spin_frequencies(n: usize, offset: f64, spin: f64, below: f64) -> Vec<f64> {
    let (ds, rho_a, k) = (2.0 / n as f64, 5.0, 500.0 / (2.0 / n as f64));
    let mut b = spin_bus(ModelBuilder::new(BaseKind::Free));
    for (dir, tag) in [(1.0, "p"), (-1.0, "q")] {
        let m = rho_a * ds;
        let j = m * ds * ds / 12.0;
        let mut prev = "bus".to_string();
        for s in 0..n {
            let name = format!("{tag}{s}");
            b.push_body(
                Body::new(name.clone(), m, Mat3::from_diagonal(&Vec3::new(j, 0.0, j)))
                    .with_com(Vec3::new(0.0, dir * 0.5 * ds, 0.0)),
            );
            let at = if s == 0 { offset } else { ds };
            b.push_hinge(
                Hinge::revolute(format!("h{name}"), prev.clone(), name.clone(), Vec3::x())
                    .at(Vec3::new(0.0, dir * at, 0.0)),
            );
            prev = name;
        }
    }
    let model = b.build().unwrap();
    let mut data = satsim_tree::Data::new(&model);
    let nh = 2 * n;
    free_spin_frequencies(nh, spin, below, |x, vv| {
        let mut q = model.neutral();
        q[7..].copy_from_slice(x);
        let tau: Vec<f64> = (0..6)
            .map(|_| 0.0)
            .chain(x.iter().map(|a| -k * a))
            .collect();
        satsim_tree::aba::aba(&model, &mut data, &q, vv, &tau, None)
            .unwrap()
            .as_slice()
            .to_vec()
    })
}

// 6. A spinning free spacecraft's coupled modes (issue 53): a 50 kg bus with two contract
// beams (2 m, EI 500 N m², ρA 5 kg/m) along ±y on locked hinges, bending along z, spinning
// about z at 1 and 3 rad/s, hinges at the bus centre and 0.5 m off it: every frequency below
// 12 Hz (the elastic ones and the spinning body's own) against rigid chains of 40 and 80
// segments extrapolated (2 f₈₀ − f₄₀). The antisymmetric flapwise mode rocks the bus; its
// deflection's first-order inertia is the dynamic imbalance the spin acts through.
#[test]
fn spinning_free_spacecraft_modes_match_rigid_chains() {
    let below = 2.0 * std::f64::consts::PI * 12.0;
    let mut worst: f64 = 0.0;
    for offset in [0.0, 0.5] {
        for spin in [1.0, 3.0] {
            let modal = modal_spin_frequencies(offset, spin, below);
            let c40 = chain_spin_frequencies(40, offset, spin, below);
            let c80 = chain_spin_frequencies(80, offset, spin, below);
            assert_eq!(modal.len(), c40.len(), "{modal:?} {c40:?}");
            assert_eq!(c40.len(), c80.len());
            let ext: Vec<f64> = c40.iter().zip(&c80).map(|(a, b)| 2.0 * b - a).collect();
            let hz = |w: &[f64]| {
                w.iter()
                    .map(|x| format!("{:.4}", x / (2.0 * std::f64::consts::PI)))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            println!(
                "offset {offset} m, spin {spin} rad/s (Hz): modal {}; chains extrapolated {}; N = 80 {}",
                hz(&modal),
                hz(&ext),
                hz(&c80)
            );
            for (a, b) in modal.iter().zip(&ext) {
                worst = worst.max(rel(*a, *b));
                assert!(rel(*a, *b) < 0.01, "{a} vs {b}");
            }
        }
    }
    println!("worst relative difference {worst:e}");
}

/// The hub of [`hub`] with the unit beam rooted in it at radius `r` and a point body of
/// mass `tip` on a hinge about z at the beam's tip.
fn hub_with_tip_mass(r: f64, bend: Vec3, modes: usize, tip: f64) -> FlexModel {
    let b = spinning_hub()
        .body(Body::new("tip", tip, Mat3::zeros()))
        .hinge(Hinge::revolute("end", "hub", "tip", Vec3::z()).at(Vec3::new(r + 1.0, 0.0, 0.0)));
    let beam = unit_beam(Vec3::new(r, 0.0, 0.0), bend, modes);
    FlexModel::build(b, &[stiffened("hub", beam)]).unwrap()
}

/// [`spinning_frequencies`] where the modal mass is not the identity (a body carried by the
/// beam): the eigenvalues of [`modal_stiffness`]'s `M⁻¹K`, real and positive for a stable
/// spin.
fn carrying_frequencies(model: &FlexModel, spin: f64) -> Vec<f64> {
    let mut w: Vec<f64> = modal_stiffness(model, spin)
        .complex_eigenvalues()
        .iter()
        .map(|l| {
            assert!(l.im.abs() < 1e-6 * l.re.abs() && l.re > 0.0, "{l}");
            l.re.sqrt()
        })
        .collect();
    w.sort_by(|a, b| a.partial_cmp(b).unwrap());
    w
}

// 6. A load the beam carries: a tip mass pulled outwards by its centrifugal force puts the
// beam in tension `M Ω² (R + L)` along its whole length, which stiffens it by
// `M Ω² (R + L) ∫₀ᴸ φ'φ'ᵀ` (the tip drawn in by the foreshortening does work against the
// pull), and adds `M φ(L) φ(L)ᵀ` to the modal mass (and, bending in the plane of rotation,
// the tip's own centrifugal softening `−M Ω² φ(L) φ(L)ᵀ`). The reference is the continuum's
// Galerkin on the same cantilever modes, so the frequencies agree to the differences' round-off;
// without the tip's tension the flapwise frequency is 20 % low at M = 5, Ω = 5.
#[test]
fn a_tip_mass_stiffens_a_spinning_beam_by_its_pull() {
    let m = 4;
    for (r, spin, tip) in [(0.0, 5.0, 5.0), (1.0, 3.0, 2.0)] {
        for chordwise in [false, true] {
            let bend = if chordwise { Vec3::y() } else { Vec3::z() };
            let got = carrying_frequencies(&hub_with_tip_mass(r, bend, m, tip), spin);
            let bm = unit_beam(Vec3::zeros(), Vec3::z(), m);
            let modes = bm.cantilever_modes();
            let rule = gauss_legendre(POINTS);
            let (l, s) = (bm.length, if chordwise { 1.0 } else { 0.0 });
            let w2 = spin * spin;
            let tension = tip * w2 * (r + l);
            let k = DMatrix::from_fn(m, m, |i, j| {
                let (a, b) = (&modes[i], &modes[j]);
                let slopes = |x: f64| a.shape(x)[1] * b.shape(x)[1];
                let own = bm.rho_a
                    * w2
                    * integrate(l, 2 * PANELS, &rule, |x| {
                        (r * (l - x) + 0.5 * (l * l - x * x)) * slopes(x)
                    });
                let pull = tension * integrate(l, 2 * PANELS, &rule, slopes);
                let diag = if i == j {
                    bm.omega(i + 1).powi(2) - s * w2
                } else {
                    0.0
                };
                diag + own + pull - s * tip * w2 * a.shape(l)[0] * b.shape(l)[0]
            });
            let mass = DMatrix::from_fn(m, m, |i, j| {
                let d = if i == j { 1.0 } else { 0.0 };
                d + tip * modes[i].shape(l)[0] * modes[j].shape(l)[0]
            });
            // K v = ω² M v through M = L Lᵀ.
            let lo = mass.cholesky().unwrap().l();
            let li = lo.clone().try_inverse().unwrap();
            let a = &li * k * li.transpose();
            let mut expected: Vec<f64> = SymmetricEigen::new((&a + a.transpose()) * 0.5)
                .eigenvalues
                .iter()
                .map(|l| l.sqrt())
                .collect();
            expected.sort_by(|a, b| a.partial_cmp(b).unwrap());
            for (g, e) in got.iter().zip(&expected) {
                assert!(
                    rel(*g, *e) < 1e-6,
                    "r = {r}, spin {spin}, tip {tip}, chordwise {chordwise}: {got:?} vs {expected:?}"
                );
            }
        }
    }
}

// 7. Energy and momentum with a body hung on a stiffened beam: the foreshortening moves the
// node, so the body's kinetic energy and the node's velocity product carry it; a free bus
// spinning at 2 rad/s, a beam on a hinge off its axis, a 3 kg body swinging on the beam's
// tip, all deflected and moving: T + V and the momenta kept over 10 s to the integrator's
// accuracy.
#[test]
fn a_body_on_a_spinning_stiffened_beam_conserves_energy_and_momentum() {
    let model = FlexModel::build(
        ModelBuilder::new(BaseKind::Free)
            .body(Body::new(
                "bus",
                50.0,
                Mat3::from_diagonal(&Vec3::new(8.0, 9.0, 10.0)),
            ))
            .body(Body::new("flap", 0.0, Mat3::zeros()))
            .body(Body::new(
                "tip",
                3.0,
                Mat3::from_diagonal(&Vec3::new(0.05, 0.08, 0.1)),
            ))
            .hinge(Hinge::revolute("h1", "bus", "flap", Vec3::y()).at(Vec3::new(0.6, 0.1, 0.0)))
            .hinge(
                Hinge::revolute("h2", "flap", "tip", Vec3::x())
                    .at(Vec3::new(2.0, 0.0, 0.0))
                    .child_at(Vec3::new(-0.1, 0.05, 0.2)),
            ),
        &[stiffened(
            "flap",
            Beam {
                root: Vec3::zeros(),
                axis: Vec3::x(),
                bend: Vec3::z(),
                length: 2.0,
                ei: 500.0,
                rho_a: 5.0,
                modes: 3,
            },
        )],
    )
    .unwrap();
    let (nq, nv) = (model.nq(), model.nv());
    let mut x = vec![0.0; nq + nv];
    x[..nq].copy_from_slice(&model.neutral());
    let v0 = [
        0.05, -0.03, 2.0, 0.1, 0.0, -0.05, 0.3, -0.4, 0.1, -0.2, 0.05,
    ];
    x[nq..].copy_from_slice(&v0[..nv]);
    x[7] = 0.1;
    x[8] = 0.3;
    x[9] = 0.03;
    x[10] = -0.004;
    let d = drifts(&model, &mut x, 10.0, |_| {});
    let (worst, dp, dh) = (d.energy, d.linear, d.angular);
    println!(
        "over 10 s ({} steps): energy {worst:e}, momenta {dp:e} {dh:e}",
        d.steps
    );
    assert!(worst < 1e-8, "relative energy drift {worst:e}");
    assert!(dp < 1e-8 && dh < 1e-8, "momentum drift {dp:e} {dh:e}");
}
