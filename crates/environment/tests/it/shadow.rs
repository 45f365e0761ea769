//! The Earth's shadow over circular orbits, against the shadow's geometry worked here apart
//! from the models: the cylinder's entry and exit angles in closed form, and the penumbra's
//! and umbra's cones (the lines tangent to both the Sun and the Earth).

use satsim_environment::shadow::{R_SUN, ShadowModel, shadow_fraction};
use satsim_environment::{AU, R_EARTH, Vec3};
use std::f64::consts::PI;

const R_ORBIT: f64 = R_EARTH + 500e3;

/// The Sun at 1 AU, `beta` (rad) out of the orbit's plane (the xy plane), towards +x.
fn sun(beta: f64) -> Vec3 {
    Vec3::new(beta.cos(), 0.0, beta.sin()) * AU
}

/// The satellite at argument `u` (rad) on the circular orbit.
fn sat(u: f64) -> Vec3 {
    Vec3::new(u.cos(), u.sin(), 0.0) * R_ORBIT
}

/// The `u` in [lo, hi] where `pred` turns, by bisection (pred(lo) != pred(hi)).
fn turn(mut lo: f64, mut hi: f64, pred: impl Fn(f64) -> bool) -> f64 {
    let at_lo = pred(lo);
    assert_ne!(at_lo, pred(hi));
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if pred(mid) == at_lo {
            lo = mid
        } else {
            hi = mid
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn the_cylinder_is_entered_and_left_where_the_geometry_says() {
    for beta in [0.0f64, 0.3, 0.6] {
        let s = sun(beta);
        let nu = |u: f64| shadow_fraction(ShadowModel::Cylindrical, &sat(u), &s);
        // Behind the Earth and within R_E of the axis: cos u < 0 and
        // r² (1 − cos²β cos²u) < R_E², so u = π ± u0 with cos u0 = sqrt(1 − R_E²/r²) / cos β.
        let u0 = ((1.0 - (R_EARTH / R_ORBIT).powi(2)).sqrt() / beta.cos()).acos();
        let entry = turn(PI / 2.0, PI, |u| nu(u) == 1.0);
        let exit = turn(PI, 1.5 * PI, |u| nu(u) == 1.0);
        println!(
            "beta {beta}: entry {entry:.12} vs {:.12}, exit {exit:.12} vs {:.12}",
            PI - u0,
            PI + u0
        );
        assert!((entry - (PI - u0)).abs() < 1e-12, "{entry} vs {}", PI - u0);
        assert!((exit - (PI + u0)).abs() < 1e-12, "{exit} vs {}", PI + u0);
        // All or nothing, and nothing else along the orbit.
        let samples: Vec<f64> = (0..10_000).map(|k| nu(2.0 * PI * k as f64 / 1e4)).collect();
        assert!(samples.iter().all(|&x| x == 0.0 || x == 1.0));
        let dark = samples.iter().filter(|&&x| x == 0.0).count() as f64 / 1e4;
        assert!((dark - u0 / PI).abs() < 2e-4, "{dark} vs {}", u0 / PI);
    }
    // No shadow where the Sun is too far out of the plane (cos u0 > 1).
    let s = sun(1.4);
    assert!((0..1000).all(|k| shadow_fraction(
        ShadowModel::Cylindrical,
        &sat(k as f64 * 0.00628),
        &s
    ) == 1.0));
}

/// The perpendicular distance of `r` from the shadow's axis and its distance behind the
/// Earth's centre along it.
fn axis_coords(r: &Vec3, r_sun: &Vec3) -> (f64, f64) {
    let s = r_sun.normalize();
    let behind = -r.dot(&s);
    ((r + s * behind).norm(), behind)
}

/// The penumbra's outer cone and the umbra's cone at `behind` metres behind the Earth:
/// their radii, from the vertices of the lines tangent to both spheres (the penumbra's
/// between the bodies at d R_E / (R_S + R_E) sunward, the umbra's behind the Earth at
/// d R_E / (R_S − R_E)), sin α = R_E / (vertex distance), radius = (distance from the vertex)
/// tan α.
fn cones(behind: f64, d: f64) -> (f64, f64) {
    let (xp, xu) = (
        d * R_EARTH / (R_SUN + R_EARTH),
        d * R_EARTH / (R_SUN - R_EARTH),
    );
    let (ap, au) = ((R_EARTH / xp).asin(), (R_EARTH / xu).asin());
    ((behind + xp) * ap.tan(), (xu - behind) * au.tan())
}

#[test]
fn the_conical_shadow_is_continuous_monotone_and_bounded_by_the_cones() {
    for beta in [0.0f64, 0.5] {
        let s = sun(beta);
        let nu = |u: f64| shadow_fraction(ShadowModel::Conical, &sat(u), &s);
        assert_eq!(nu(0.0), 1.0);
        assert_eq!(nu(PI), 0.0);
        // The cones' crossings, found on the geometry alone.
        let cone = |u: f64, outer: bool| {
            let (rho, behind) = axis_coords(&sat(u), &s);
            let (p, um) = cones(behind, s.norm());
            behind > 0.0 && rho < if outer { p } else { um }
        };
        let pen_in = turn(PI / 2.0, PI, |u| cone(u, true));
        let umb_in = turn(PI / 2.0, PI, |u| cone(u, false));
        let umb_out = turn(PI, 1.5 * PI, |u| cone(u, false));
        let pen_out = turn(PI, 1.5 * PI, |u| cone(u, true));
        // The model's: where ν leaves 1 and reaches 0.
        let in1 = turn(PI / 2.0, PI, |u| nu(u) < 1.0);
        let in0 = turn(PI / 2.0, PI, |u| nu(u) > 0.0);
        let out0 = turn(PI, 1.5 * PI, |u| nu(u) > 0.0);
        let out1 = turn(PI, 1.5 * PI, |u| nu(u) < 1.0);
        let period = 2.0 * PI * (R_ORBIT.powi(3) / satsim_environment::MU_EARTH).sqrt();
        let secs = |du: f64| du / (2.0 * PI) * period;
        println!(
            "beta {beta}: penumbra {:.4} s (cones {:.4} s), umbra {:.2} s (cones {:.2} s)",
            secs(in0 - in1),
            secs(umb_in - pen_in),
            secs(out0 - in0),
            secs(umb_out - umb_in)
        );
        // The disks touch exactly when the satellite is on a cone: the same instants.
        for (model, geometry) in [
            (in1, pen_in),
            (in0, umb_in),
            (out0, umb_out),
            (out1, pen_out),
        ] {
            assert!(
                secs((model - geometry).abs()) < 1e-6,
                "{model} vs {geometry}"
            );
        }

        // Continuous and monotone through the penumbra: with N samples a step of the orbit
        // moves ν by at most (4/π) × step / penumbra (the fastest change, at mid-penumbra,
        // is 4/π times the mean); 5% more for the Sun's disk crossing the Earth's limb at a
        // rate that varies a little over the penumbra.
        let n = 200_000;
        let step = 2.0 * PI / n as f64;
        let bound = 4.0 / PI * step / (in0 - in1) * 1.05;
        let values: Vec<f64> = (0..=n).map(|k| nu(k as f64 * step)).collect();
        let mut worst = 0.0f64;
        for (k, w) in values.windows(2).enumerate() {
            worst = worst.max((w[1] - w[0]).abs());
            let u = k as f64 * step;
            if u > in1 && u + step < in0 {
                assert!(w[1] <= w[0], "ν rises entering the shadow at u = {u}");
            }
            if u > out0 && u + step < out1 {
                assert!(w[1] >= w[0], "ν falls leaving the shadow at u = {u}");
            }
        }
        println!("beta {beta}: largest step {worst:.4} (bound {bound:.4})");
        assert!(worst <= bound, "{worst} > {bound}");

        // At the cylinder's edge about half the Sun shows: the edge lies midway between
        // the cones to within x R_E / d (a few hundred metres of a ~60 km penumbra).
        let edge = turn(PI / 2.0, PI, |u| {
            shadow_fraction(ShadowModel::Cylindrical, &sat(u), &s) == 1.0
        });
        let half = nu(edge);
        println!("beta {beta}: ν at the cylinder's edge {half:.4}");
        assert!((half - 0.5).abs() < 0.02, "{half}");
    }
}

#[test]
fn beyond_the_umbra_the_earth_is_a_ring_inside_the_sun() {
    // The umbra ends d R_E / (R_S − R_E) ≈ 1.38e9 m behind the Earth; at 3e9 m on the axis
    // the Earth's disk lies wholly inside the Sun's.
    let s = sun(0.0);
    let r = Vec3::new(-3e9, 0.0, 0.0);
    let (a, b) = ((R_SUN / (AU + 3e9)).asin(), (R_EARTH / 3e9).asin());
    let nu = shadow_fraction(ShadowModel::Conical, &r, &s);
    assert!((nu - (1.0 - (b / a).powi(2))).abs() < 1e-12, "{nu}");
    // And it joins the umbra and the full Sun continuously along the axis and across it.
    let mut last = shadow_fraction(ShadowModel::Conical, &Vec3::new(-1e9, 0.0, 0.0), &s);
    for k in 1..=4000 {
        let x = -1e9 - k as f64 * 1e6;
        let v = shadow_fraction(ShadowModel::Conical, &Vec3::new(x, 0.0, 0.0), &s);
        assert!(
            (v - last).abs() < 2e-3 && v >= last,
            "{x}: {v} after {last}"
        );
        last = v;
    }
}

#[test]
fn models_by_name_none_and_bad_positions() {
    for m in [
        ShadowModel::Conical,
        ShadowModel::Cylindrical,
        ShadowModel::None,
    ] {
        assert_eq!(ShadowModel::from_name(m.name()), Some(m));
    }
    assert_eq!(ShadowModel::from_name("penumbral"), None);
    assert_eq!(ShadowModel::default(), ShadowModel::Conical);
    let s = sun(0.0);
    let behind = Vec3::new(-R_ORBIT, 0.0, 0.0);
    assert_eq!(shadow_fraction(ShadowModel::None, &behind, &s), 1.0);
    // Inside the Earth: no Sun. NaN in, NaN out (no panic).
    let inside = Vec3::new(1e6, 0.0, 0.0);
    assert_eq!(shadow_fraction(ShadowModel::Conical, &inside, &s), 0.0);
    assert_eq!(shadow_fraction(ShadowModel::Cylindrical, &inside, &s), 0.0);
    let nan = Vec3::new(f64::NAN, 0.0, 7e6);
    assert!(shadow_fraction(ShadowModel::Conical, &nan, &s).is_nan());
    assert!(shadow_fraction(ShadowModel::Cylindrical, &nan, &s).is_nan());
}
