//! The Earth-fixed lattice under the gravity harmonics and IGRF-14: its error against the
//! exact models along low orbits (500 km, inclined 51.6° and polar, every 0.5 s for one
//! orbit), the results' independence of the order of the calls, and (ignored tests, timings
//! and tables) the numbers the modules' pages give:
//! `cargo test -p satsim-environment --release --test it -- --ignored --nocapture lattice_`.

use satsim_environment::earth::gcrf_to_itrf;
use satsim_environment::gravity::{HarmonicField, HarmonicLattice, LATTICE_DEG, egm2008};
use satsim_environment::magnetic::{self, FieldModel, GeoField};
use satsim_environment::{Epoch, MU_EARTH, R_EARTH, Vec3, parse_epoch};
use std::sync::Arc;
use std::time::Instant;

const EPOCH: &str = "2026-03-20T12:00:00 UTC";

fn epoch() -> Epoch {
    parse_epoch(EPOCH).unwrap()
}

/// One orbit of a circular orbit at `alt` (m), inclined `incl_deg`, every 0.5 s: the times
/// and the Earth-fixed positions (m).
fn track(alt: f64, incl_deg: f64) -> Vec<(f64, Vec3)> {
    track_every(alt, incl_deg, 0.5)
}

/// [`track`] every `dt` (s).
fn track_every(alt: f64, incl_deg: f64, dt: f64) -> Vec<(f64, Vec3)> {
    let a = R_EARTH + alt;
    let n = (MU_EARTH / a.powi(3)).sqrt();
    let (i, raan) = (incl_deg.to_radians(), 0.7f64);
    let p = Vec3::new(raan.cos(), raan.sin(), 0.0);
    let q = Vec3::new(-raan.sin() * i.cos(), raan.cos() * i.cos(), i.sin());
    let steps = (std::f64::consts::TAU / n / dt).ceil() as usize;
    (0..=steps)
        .map(|k| {
            let t = k as f64 * dt;
            let (s, c) = (n * t).sin_cos();
            (t, gcrf_to_itrf(epoch(), t) * (a * (c * p + s * q)))
        })
        .collect()
}

/// The two test orbits, 500 km high.
fn orbits() -> [(&'static str, Vec<(f64, Vec3)>); 2] {
    [
        ("51.6 deg", track(500e3, 51.6)),
        ("polar", track(500e3, 90.0)),
    ]
}

/// EGM2008 to degree and order `n`.
fn egm(n: usize) -> Arc<HarmonicField> {
    Arc::new(HarmonicField::new(egm2008().unwrap(), n, n).unwrap())
}

/// The largest and the RMS norm of `f` over `points`.
fn max_rms(points: &[(f64, Vec3)], mut f: impl FnMut(f64, &Vec3) -> f64) -> (f64, f64) {
    let (mut max, mut sum) = (0.0f64, 0.0);
    for (t, r) in points {
        let e = f(*t, r);
        max = max.max(e);
        sum += e * e;
    }
    (max, (sum / points.len() as f64).sqrt())
}

/// The largest error (m/s²) of the 20x20 harmonics on a lattice of `deg` against the series.
fn gravity_error(points: &[(f64, Vec3)], deg: f64) -> (f64, f64) {
    let field = egm(20);
    let mut l = HarmonicLattice::new(field.clone(), deg).unwrap();
    max_rms(points, |_, r| (l.harmonics(r) - field.harmonics(r)).norm())
}

/// The largest error (nT) of IGRF-14 on a lattice of `deg` against the model, and the largest
/// relative error.
fn igrf_error(points: &[(f64, Vec3)], deg: f64) -> (f64, f64) {
    let exact = GeoField::new(FieldModel::Igrf14, epoch()).unwrap();
    let lattice = exact.clone().with_lattice(deg);
    let (mut nt, mut rel) = (0.0f64, 0.0f64);
    for (t, r) in points {
        let b = exact.field_itrf(*t, r);
        let e = (lattice.field_itrf(*t, r) - b).norm();
        nt = nt.max(e * 1e9);
        rel = rel.max(e / b.norm());
    }
    (nt, rel)
}

#[test]
fn the_gravity_lattice_is_within_its_documented_error_and_below_the_truncation() {
    let (field, f30) = (egm(20), egm(30));
    for (name, points) in orbits() {
        let (worst, _) = gravity_error(&points, LATTICE_DEG);
        // The module's page: 8e-7 m/s² at 1 degree.
        assert!(worst < 1.0e-6, "{name}: {worst:e} m/s²");
        // A tenth of what degrees 21 to 30 (left out by 20x20) give at the worst point.
        let (trunc, _) = max_rms(&points, |_, r| {
            (f30.harmonics(r) - field.harmonics(r)).norm()
        });
        assert!(worst < 0.1 * trunc, "{name}: {worst:e} vs {trunc:e}");
        // And it is an interpolation, not a copy of the series: coarser is worse.
        let (coarse, _) = gravity_error(&points, 4.0);
        assert!(coarse > 4.0 * worst, "{name}: {coarse:e} vs {worst:e}");
    }
    // In the GCRF, with the central term and J2 exact, the same error.
    let mut l = HarmonicLattice::new(field.clone(), LATTICE_DEG).unwrap();
    let r = Vec3::new(3.0e6, -5.0e6, 3.5e6);
    let e = (l.acceleration_gcrf(epoch(), 100.0, &r) - field.acceleration_gcrf(epoch(), 100.0, &r))
        .norm();
    assert!(e < 1.0e-6, "{e:e}");
}

#[test]
fn the_igrf_lattice_is_within_its_documented_error() {
    for (name, points) in orbits() {
        let (nt, rel) = igrf_error(&points, magnetic::LATTICE_DEG);
        // The module's page: 11 nT, 4.3e-4 of the field, at 1 degree.
        assert!(nt < 12.0 && rel < 5e-4, "{name}: {nt} nT, {rel:e}");
        let (coarse, _) = igrf_error(&points, 8.0);
        assert!(coarse > 4.0 * nt, "{name}: {coarse} vs {nt}");
    }
}

#[test]
fn the_lattices_are_exact_in_time_and_finite_at_the_poles() {
    // The Gauss coefficients are linear in time over 2025-2030: a lattice keyed by the model
    // keeps them so; a year later at the same place, the lattice moves as the model does.
    let exact = GeoField::new(FieldModel::Igrf14, epoch()).unwrap();
    let lattice = exact.clone().with_lattice(magnetic::LATTICE_DEG);
    let r = Vec3::new(4.0e6, 3.0e6, 4.2e6);
    let year = 365.25 * 86_400.0;
    let moved = lattice.field_itrf(year, &r) - lattice.field_itrf(0.0, &r);
    let model = exact.field_itrf(year, &r) - exact.field_itrf(0.0, &r);
    assert!(
        (moved - model).norm() < 1e-2 * model.norm(),
        "{moved} {model}"
    );
    assert!(model.norm() > 10e-9, "{model}");
    // At and about the poles.
    let field = egm(20);
    let mut g = HarmonicLattice::new(field.clone(), LATTICE_DEG).unwrap();
    for z in [6.9e6, -6.9e6] {
        for off in [0.0, 1e-3, 2e3] {
            let r = Vec3::new(off, -0.5 * off, z);
            let a = g.harmonics(&r);
            assert!((a - field.harmonics(&r)).norm() < 1e-6, "{r}: {a}");
            let b = lattice.field_itrf(0.0, &r);
            assert!((b - exact.field_itrf(0.0, &r)).norm() < 12e-9, "{r}: {b}");
        }
    }
    // 0 degrees is the model at every call.
    let off = exact.clone().with_lattice(0.0);
    assert_eq!(off.lattice_deg(), 0.0);
    assert_eq!(off.field_itrf(5.0, &r), exact.field_itrf(5.0, &r));
    assert!(HarmonicLattice::new(field, 0.0).is_none());
}

#[test]
fn the_lattices_give_the_same_bits_in_any_call_order() {
    let points = track(500e3, 51.6);
    let field = egm(20);
    let mut forward = HarmonicLattice::new(field.clone(), LATTICE_DEG).unwrap();
    let ahead: Vec<Vec3> = points.iter().map(|(_, r)| forward.harmonics(r)).collect();
    let mut backward = HarmonicLattice::new(field.clone(), LATTICE_DEG).unwrap();
    for ((_, r), a) in points.iter().zip(&ahead).rev() {
        assert_eq!(backward.harmonics(r), *a);
    }
    // Strided, as an integrator's stages and redone steps jump about.
    let mut strided = HarmonicLattice::new(field, LATTICE_DEG).unwrap();
    for k in (0..points.len())
        .step_by(7)
        .chain((0..points.len()).step_by(3))
    {
        assert_eq!(strided.harmonics(&points[k].1), ahead[k]);
    }
    let exact = GeoField::new(FieldModel::Igrf14, epoch()).unwrap();
    let one = exact.clone().with_lattice(magnetic::LATTICE_DEG);
    let first: Vec<Vec3> = points.iter().map(|(t, r)| one.field_itrf(*t, r)).collect();
    let other = exact.with_lattice(magnetic::LATTICE_DEG);
    for ((t, r), b) in points.iter().zip(&first).rev() {
        assert_eq!(other.field_itrf(*t, r), *b);
    }
    // A clone made mid-run reads the same.
    let copy = one.clone();
    assert_eq!(copy.field_itrf(points[5].0, &points[5].1), first[5]);
}

/// The error table of the modules' pages.
#[test]
#[ignore = "a table, not a check"]
fn lattice_error() {
    let (field, f30) = (egm(20), egm(30));
    for (name, points) in orbits() {
        let (trunc, trunc_rms) = max_rms(&points, |_, r| {
            (f30.harmonics(r) - field.harmonics(r)).norm()
        });
        // What the lattice holds: the harmonics less J2.
        let j2 = HarmonicField::new(egm2008().unwrap(), 2, 0).unwrap();
        let (beyond_j2, _) = max_rms(&points, |_, r| {
            (field.harmonics(r) - j2.harmonics(r)).norm()
        });
        println!(
            "{name}: the 20x20 harmonics less J2 up to {beyond_j2:.3e} m/s²; degrees 21-30: max {trunc:.3e}, rms {trunc_rms:.3e} m/s²"
        );
        for deg in [0.5, 1.0, 2.0, 3.0] {
            let (max, rms) = gravity_error(&points, deg);
            println!("  gravity lattice {deg} deg: max {max:.3e}, rms {rms:.3e} m/s²");
        }
        for deg in [1.0, 2.0, 3.0, 4.0] {
            let (nt, rel) = igrf_error(&points, deg);
            println!("  igrf lattice {deg} deg: max {nt:.3} nT, {rel:.2e} of the field");
        }
    }
}

/// The cost table of the modules' pages: a call every `dt` along the orbit, warm cache.
#[test]
#[ignore = "a timing, not a check"]
fn lattice_cost() {
    let field = egm(20);
    let exact = GeoField::new(FieldModel::Igrf14, epoch()).unwrap();
    for dt in [0.5, 0.1] {
        cost_every(&field, &exact, dt);
    }
}

/// [`lattice_cost`] with a call every `dt` (s).
fn cost_every(field: &Arc<HarmonicField>, exact: &GeoField, dt: f64) {
    let points = track_every(500e3, 51.6, dt);
    let n = points.len();
    let time = |f: &mut dyn FnMut(f64, &Vec3) -> Vec3| {
        let mut sum = Vec3::zeros();
        // Warm-up pass, then ten timed.
        for (t, r) in &points {
            sum += f(*t, r);
        }
        let start = Instant::now();
        for _ in 0..10 {
            for (t, r) in &points {
                sum += f(*t, r);
            }
        }
        std::hint::black_box(sum);
        start.elapsed().as_secs_f64() / (10 * points.len()) as f64 * 1e9
    };
    let series = time(&mut |_, r| field.harmonics(r));
    let rotation = time(&mut |t, _| gcrf_to_itrf(epoch(), t) * Vec3::x());
    for deg in [0.5, 1.0, 2.0, 3.0] {
        // A fresh lattice each pass: its fills are in the time, amortised over the orbit.
        let per = time(&mut {
            let mut l = HarmonicLattice::new(field.clone(), deg).unwrap();
            let mut k = 0;
            move |_, r| {
                k += 1;
                if k % n == 0 {
                    l = HarmonicLattice::new(field.clone(), deg).unwrap();
                }
                l.harmonics(r)
            }
        });
        let mut l = HarmonicLattice::new(field.clone(), deg).unwrap();
        for (_, r) in &points {
            l.harmonics(r);
        }
        println!(
            "gravity 20x20 every {dt} s: series {series:.0} ns a call; lattice {deg} deg {per:.0} ns a call, {} node evaluations an orbit of {} calls",
            l.lattice().evaluations(),
            points.len(),
        );
    }
    let model = time(&mut |t, r| exact.field_itrf(t, r));
    println!("gcrf_to_itrf: {rotation:.0} ns a call");
    for deg in [1.0, 2.0, 3.0, 4.0] {
        let per = time(&mut {
            let mut g = exact.clone().with_lattice(deg);
            let mut k = 0;
            move |t, r| {
                k += 1;
                if k % n == 0 {
                    g = exact.clone().with_lattice(deg);
                }
                g.field_itrf(t, r)
            }
        });
        let g = exact.clone().with_lattice(deg);
        for (t, r) in &points {
            g.field_itrf(*t, r);
        }
        println!(
            "igrf14 every {dt} s: model {model:.0} ns a call; lattice {deg} deg {per:.0} ns a call, {} node evaluations an orbit",
            g.lattice_evaluations()
        );
    }
}
