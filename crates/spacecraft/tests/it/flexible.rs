//! Flexible panels in a simulation: the preprint satellite with its three panels as beams
//! (cli-contract section 14), checked by conservation laws, the energy budget, momentum across
//! an impact and the rigid limit.

use satsim_integrate::{Method, Options, Output};
use satsim_satellite::{Deployment, PreprintParams, build_model};
use satsim_spacecraft::effects::{
    HingeSprings, HingeStop, HingeStops, ReactionWheels, StopAction, Wheel,
};
use satsim_spacecraft::simulation::{Simulation, attitude_norm_error};
use satsim_tree::flexible::{Beam, FlexModel, Flexible, Modes};
use satsim_tree::spatial::Vec3;
use satsim_tree::{Model, State};

/// The preprint satellite with each panel a beam along its y axis from its root hinge
/// (y = −0.5) to the next panel's (y = +0.5), bending along z (out of the panel's plane).
fn flexible_satellite(ei: f64, damping: f64) -> FlexModel {
    let model = build_model(&PreprintParams::default()).unwrap();
    let beam = Beam {
        root: Vec3::new(0.0, -0.5, 0.0),
        axis: Vec3::y(),
        bend: Vec3::z(),
        length: 1.0,
        ei,
        rho_a: 5.0,
        modes: 3,
    };
    let flex: Vec<Flexible> = ["panel1", "panel2", "panel3"]
        .iter()
        .map(|p| Flexible {
            body: p.to_string(),
            modes: Modes::Beam(beam.clone()),
            damping,
            stiffening: true,
        })
        .collect();
    FlexModel::build(model.to_builder(), &flex).unwrap()
}

fn moving_state(model: &Model) -> State {
    let mut s = State::rest(model);
    s.q[7..12].copy_from_slice(&Deployment::HalfDeployed.angles());
    s.q[7] = 0.2;
    s.v[..6].copy_from_slice(&[0.02, -0.03, 0.01, 0.01, 0.0, -0.02]);
    s.v[6..11].copy_from_slice(&[0.05, -0.04, 0.03, 0.2, -0.1]);
    s
}

/// `state` with the root's velocity shifted so that the linear momentum is zero (the root's
/// attitude is the identity in these states). Only then is the angular momentum about the
/// centre of mass conserved: the model is linear in the deformation, and the point that
/// moves with `p / M` is not the (undeformed) centre of mass `h` is taken about.
fn balanced(f: &FlexModel, mut state: State, eta: &[f64], etadot: &[f64]) -> State {
    let mut s = Simulation::builder(f.rigid().clone())
        .flexible(f.clone())
        .initial(state.clone())
        .elastic(eta.to_vec(), etadot.to_vec())
        .build()
        .unwrap();
    let x0 = s.x0().to_vec();
    let p = s.diagnostics(0.0, &x0).unwrap().p;
    let mass = f.rigid().total_mass();
    for k in 0..3 {
        state.v[3 + k] -= p[k] / mass;
    }
    state
}

fn sim(f: &FlexModel, eta: f64) -> Simulation {
    let m = f.n_elastic();
    let eta: Vec<f64> = (0..m).map(|e| eta / (1 + e % 3) as f64).collect();
    let state = balanced(f, moving_state(f.rigid()), &eta, &vec![0.0; m]);
    Simulation::builder(f.rigid().clone())
        .flexible(f.clone())
        .initial(state)
        .elastic(eta, vec![0.0; m])
        .build()
        .unwrap()
}

fn dp54(rtol: f64) -> Options {
    Options::new(Method::Dp54)
        .with_tolerances(rtol, rtol * 1e-3)
        .with_max_steps(10_000_000)
}

fn end_state(sim: &mut Simulation, opts: &Options, t_end: f64) -> Vec<f64> {
    let x0 = sim.x0().to_vec();
    let mut last = x0.clone();
    satsim_integrate::integrate(
        sim,
        opts,
        0.0,
        &x0,
        t_end,
        &Output::Times(vec![t_end]),
        |_, x| {
            last = x.to_vec();
            std::ops::ControlFlow::Continue(())
        },
    )
    .unwrap();
    last
}

fn column(sim: &Simulation, name: &str) -> usize {
    sim.columns()
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name}"))
}

#[test]
fn the_state_and_columns_carry_the_elastic_coordinates() {
    let f = flexible_satellite(50.0, 0.0);
    let mut s = sim(&f, 0.01);
    let l = s.layout().clone();
    assert_eq!((l.eta.len(), l.etadot.len()), (9, 9));
    assert_eq!(l.eta.start, l.rates.end, "η right after the hinge rates");
    let cols = s.columns();
    let (e, d, t) = (
        column(&s, "eta_panel1_1"),
        column(&s, "etadot_panel3_3"),
        column(&s, "tip_panel2"),
    );
    assert!(e < d && d < t && t < column(&s, "kinetic_energy"));
    assert_eq!(column(&s, "rate_h5") + 1, e);
    let x0 = s.x0().to_vec();
    let mut row = Vec::new();
    s.row(0.0, &x0, &mut row).unwrap();
    assert_eq!(row.len(), cols.len());
    assert_eq!(row[e], 0.01);
    assert_eq!(row[column(&s, "eta_panel1_2")], 0.005);
    // The tip deflection is the modes' sum at the tip, by the tree's own function.
    let mut q = f.neutral();
    let nq = f.rigid().nq();
    q[nq..].copy_from_slice(&x0[l.eta.clone()]);
    let i = f.rigid().body_index("panel2").unwrap();
    assert_eq!(row[t], f.tip_deflection(i, &q).unwrap());
    assert!(row[t].abs() > 1e-3, "a deflected tip: {}", row[t]);
    // The strain energy is potential: half the modal stiffness times η².
    let strain: f64 = f
        .stiffness()
        .iter()
        .zip(&x0[l.eta.clone()])
        .map(|(k, e)| 0.5 * k * e * e)
        .sum();
    assert!((row[column(&s, "potential_energy")] - strain).abs() <= 1e-12 * strain);
    // Wrong lengths are an error, not a panic.
    let bad = Simulation::builder(f.rigid().clone())
        .flexible(f.clone())
        .elastic(vec![0.0; 2], vec![0.0; 9])
        .build();
    assert!(
        bad.err()
            .unwrap()
            .to_string()
            .contains("eta and etadot of length 9")
    );
}

#[test]
fn torque_free_flexible_satellite_conserves_energy_and_momentum() {
    let f = flexible_satellite(50.0, 0.0);
    let mut s = sim(&f, 0.02);
    let x0 = s.x0().to_vec();
    // The drifts are the integration's: they fall tenfold with each decade of the tolerance
    // (|Δp| 2.0e-8, 1.3e-9, 8.8e-11, 8.5e-12 from 1e-10 to 1e-13; the strips stiffened by the
    // panels they carry ring faster than they did, and 1e-11 no longer keeps |Δp| below 1e-9).
    let x1 = end_state(&mut s, &dp54(1e-12), 20.0);
    let (d0, d1) = (
        s.diagnostics(0.0, &x0).unwrap(),
        s.diagnostics(20.0, &x1).unwrap(),
    );
    let (e0, e1) = (d0.kinetic + d0.potential, d1.kinetic + d1.potential);
    assert!(
        d0.potential > 0.1 * d0.kinetic,
        "the beams store energy: {d0:?}"
    );
    let de = (e1 - e0).abs() / e0;
    let dh = (d1.h - d0.h).norm() / d0.h.norm();
    let dp = (d1.p - d0.p).norm();
    eprintln!("relative drift: energy {de:.2e}, angular momentum {dh:.2e}, |Δp| {dp:.2e}");
    assert!(
        de < 1e-8 && dh < 1e-8 && dp < 1e-9,
        "energy {de}, momentum {dh}, p {dp}"
    );
    assert!(attitude_norm_error(s.layout(), &x1) < 1e-12);
    // The modes moved: energy went back and forth between the beams and the rigid motion.
    let l = s.layout();
    assert!(
        x1[l.eta.clone()]
            .iter()
            .zip(&x0[l.eta.clone()])
            .any(|(a, b)| (a - b).abs() > 1e-3)
    );
}

#[test]
fn modal_damping_is_booked_as_dissipated_energy() {
    let f = flexible_satellite(50.0, 0.05);
    let mut s = Simulation::builder(f.rigid().clone())
        .flexible(f.clone())
        .initial(moving_state(f.rigid()))
        .elastic(vec![0.02; 9], vec![0.0; 9])
        .effect(HingeSprings::new(vec![30.0, 30.0, 30.0, 2.0, 3.0]))
        .build()
        .unwrap();
    let x0 = s.x0().to_vec();
    let x1 = end_state(&mut s, &dp54(1e-11), 10.0);
    let (mut r0, mut r1) = (Vec::new(), Vec::new());
    s.row(0.0, &x0, &mut r0).unwrap();
    s.row(10.0, &x1, &mut r1).unwrap();
    let (te, lost, budget) = (
        column(&s, "total_energy"),
        column(&s, "energy_dissipated"),
        column(&s, "energy_budget"),
    );
    eprintln!("T+V {} -> {}, dissipated {}", r0[te], r1[te], r1[lost]);
    assert!(
        r1[lost] > 0.3 * (r0[te] - r1[te]) && r1[lost] > 1e-3 * r0[te],
        "damping works"
    );
    assert!(
        (r1[budget] - r0[budget]).abs() < 1e-8 * r0[te],
        "budget {} -> {}",
        r0[budget],
        r1[budget]
    );
}

#[test]
fn spinning_wheels_on_a_flexible_satellite_conserve_momentum() {
    let f = flexible_satellite(50.0, 0.0);
    let wheels = (0..3)
        .map(|j| {
            let mut w = Wheel::new(format!("w{j}"), Vec3::ith(j, 1.0), 0.05);
            w.speed = 50.0 * (j as f64 + 1.0);
            w
        })
        .collect();
    let mut s = Simulation::builder(f.rigid().clone())
        .flexible(f.clone())
        .initial(balanced(&f, moving_state(f.rigid()), &[0.01; 9], &[0.0; 9]))
        .elastic(vec![0.01; 9], vec![0.0; 9])
        .effect(ReactionWheels::new(wheels))
        .build()
        .unwrap();
    assert_eq!(
        s.model().n_bodies(),
        f.rigid().n_bodies() + 3,
        "rotors appended"
    );
    let x0 = s.x0().to_vec();
    let x1 = end_state(&mut s, &dp54(1e-11), 10.0);
    let (d0, d1) = (
        s.diagnostics(0.0, &x0).unwrap(),
        s.diagnostics(10.0, &x1).unwrap(),
    );
    let dh = (d1.h - d0.h).norm() / d0.h.norm();
    let de = ((d1.kinetic + d1.potential) - (d0.kinetic + d0.potential)).abs()
        / (d0.kinetic + d0.potential);
    assert!(dh < 1e-8 && de < 1e-8, "momentum {dh}, energy {de}");
}

#[test]
fn a_latching_panel_conserves_momentum_and_books_the_impact() {
    let f = flexible_satellite(50.0, 0.0);
    let mut state = State::rest(f.rigid());
    state.q[10] = 1.0; // h4
    state.v[9] = -0.5; // heading for the stop at 0
    state.v[..3].copy_from_slice(&[0.01, 0.02, -0.01]);
    let mut s = Simulation::builder(f.rigid().clone())
        .flexible(f.clone())
        .initial(balanced(&f, state, &[0.0; 9], &[0.0; 9]))
        .effect(HingeStops::new(vec![HingeStop {
            hinge: 3,
            lower: Some(0.0),
            upper: None,
            action: StopAction::Latch,
            min_rebound_rate: 1e-3,
        }]))
        .build()
        .unwrap();
    let x0 = s.x0().to_vec();
    let x1 = end_state(&mut s, &dp54(1e-10), 6.0);
    assert_eq!(s.event_log().len(), 1, "{:?}", s.event_log());
    let l = s.layout().clone();
    assert!(x1[l.angles.start + 3].abs() < 1e-8 && x1[l.rates.start + 3] == 0.0);
    let (mut r0, mut r1) = (Vec::new(), Vec::new());
    s.row(0.0, &x0, &mut r0).unwrap();
    s.row(6.0, &x1, &mut r1).unwrap();
    let h = |r: &[f64]| {
        Vec3::new(
            r[column(&s, "h_x")],
            r[column(&s, "h_y")],
            r[column(&s, "h_z")],
        )
    };
    assert!(
        (h(&r1) - h(&r0)).norm() < 1e-8 * h(&r0).norm(),
        "{} {}",
        h(&r0),
        h(&r1)
    );
    let (budget, lost, te) = (
        column(&s, "energy_budget"),
        column(&s, "energy_dissipated"),
        column(&s, "total_energy"),
    );
    eprintln!("T+V {}, lost at the latch {}", r0[te], r1[lost]);
    assert!(
        r1[lost] > 1e-3 * r0[te],
        "the plastic impact loses energy: {} of {}",
        r1[lost],
        r0[te]
    );
    assert!(
        (r1[budget] - r0[budget]).abs() < 1e-7 * r0[te],
        "{} {}",
        r0[budget],
        r1[budget]
    );
    // The latch rings the panels: their modes carry energy afterwards.
    assert!(x1[l.etadot.clone()].iter().any(|v| v.abs() > 1e-4));
}

/// Largest difference of the hinge angles after 3 s between the flexible satellite with
/// stiffness `ei` and the rigid satellite of the same masses.
fn distance_from_rigid(ei: f64) -> f64 {
    let f = flexible_satellite(ei, 0.0);
    let mut flex = Simulation::builder(f.rigid().clone())
        .flexible(f.clone())
        .initial(moving_state(f.rigid()))
        .build()
        .unwrap();
    let mut rigid = Simulation::builder(f.rigid().clone())
        .initial(moving_state(f.rigid()))
        .build()
        .unwrap();
    let opts = dp54(1e-10);
    let (a, b) = (
        end_state(&mut flex, &opts, 3.0),
        end_state(&mut rigid, &opts, 3.0),
    );
    let (la, lb) = (flex.layout().clone(), rigid.layout().clone());
    la.angles
        .clone()
        .zip(lb.angles.clone())
        .map(|(i, j)| (a[i] - b[j]).abs())
        .fold(0.0, f64::max)
}

#[test]
fn stiff_panels_tend_to_the_rigid_satellite() {
    // The quasi-static deflection, and so the difference, falls as 1/EI.
    let (soft, stiff) = (distance_from_rigid(2e3), distance_from_rigid(2e4));
    eprintln!("max angle difference: EI 2e3 {soft:.3e}, EI 2e4 {stiff:.3e}");
    assert!(soft < 1e-3 && soft > 1e-7, "{soft}");
    assert!(stiff < soft / 5.0 && stiff > soft / 20.0, "{soft} {stiff}");
}
