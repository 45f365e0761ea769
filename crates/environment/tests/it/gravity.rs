//! The spherical-harmonic field against an independent evaluation: the potential's gradient
//! in spherical coordinates, with unnormalised Legendre functions from Legendre's recursion
//! and their φ-derivatives from `dP_nm/dφ = P_n(m+1) − m tan φ P_nm`, normalised afterwards
//! (a different formulation, normalisation and set of recursions from the Cunningham one).
//! And the third bodies' formula.

use satsim_environment::gravity::{
    Coefficients, HarmonicField, MAX_DEGREE, MU_MOON, MU_SUN, egm2008, third_body_acceleration,
};
use satsim_environment::{MU_EARTH, R_EARTH, Vec3, parse_epoch};

/// The normalisation `N_nm = sqrt((2 − δ_m0)(2n + 1)(n − m)!/(n + m)!)`.
fn norm(n: usize, m: usize) -> f64 {
    let mut ratio = 1.0; // (n − m)!/(n + m)!
    for k in (n - m + 1)..=(n + m) {
        ratio /= k as f64;
    }
    let d = if m == 0 { 1.0 } else { 2.0 };
    (d * (2 * n + 1) as f64 * ratio).sqrt()
}

/// The acceleration by the direct sum: `∇U` in spherical coordinates, without the central
/// term's `n = 0` (returned separately: (harmonics, central)).
fn direct(c: &Coefficients, degree: usize, order: usize, r: &Vec3) -> (Vec3, Vec3) {
    let rn = r.norm();
    let (sphi, cphi) = (r.z / rn, (r.x * r.x + r.y * r.y).sqrt() / rn);
    let lam = r.y.atan2(r.x);
    let tphi = sphi / cphi;
    // Unnormalised P_nm(sin φ), n, m up to degree + 1.
    let top = degree + 1;
    let mut p = vec![vec![0.0f64; top + 2]; top + 1];
    p[0][0] = 1.0;
    for m in 0..=top {
        if m > 0 {
            p[m][m] = (2 * m - 1) as f64 * cphi * p[m - 1][m - 1];
        }
        for n in (m + 1)..=top {
            let a = (2 * n - 1) as f64 * sphi * p[n - 1][m];
            let b = if n >= m + 2 {
                (n + m - 1) as f64 * p[n - 2][m]
            } else {
                0.0
            };
            p[n][m] = (a - b) / (n - m) as f64;
        }
    }
    let (mut dr, mut dphi, mut dlam) = (0.0, 0.0, 0.0);
    for (n, pn) in p.iter().enumerate().take(degree + 1).skip(2) {
        let q = (c.radius / rn).powi(n as i32);
        for m in 0..=n.min(order) {
            let (cc, ss) = c.get(n, m);
            let (sm, cm) = (m as f64 * lam).sin_cos();
            let nn = norm(n, m);
            let pbar = nn * pn[m];
            let dpbar = nn * (pn[m + 1] - m as f64 * tphi * pn[m]);
            let trig = cc * cm + ss * sm;
            dr -= (n + 1) as f64 * q * pbar * trig;
            dphi += q * dpbar * trig;
            dlam += q * pbar * m as f64 * (-cc * sm + ss * cm);
        }
    }
    let gm = c.gm;
    let (dr, dphi, dlam) = (gm / (rn * rn) * dr, gm / rn * dphi, gm / rn * dlam);
    let (sl, cl) = lam.sin_cos();
    let e_r = Vec3::new(cphi * cl, cphi * sl, sphi);
    let e_phi = Vec3::new(-sphi * cl, -sphi * sl, cphi);
    let e_lam = Vec3::new(-sl, cl, 0.0);
    let harmonics = dr * e_r + dphi / rn * e_phi + dlam / (rn * cphi) * e_lam;
    (harmonics, -gm / (rn * rn * rn) * r)
}

/// Points: a low orbit, a geostationary one, near the poles, over the equator, high
/// latitudes south.
fn points() -> Vec<Vec3> {
    let at = |rad: f64, lat: f64, lon: f64| {
        let (lat, lon) = (lat.to_radians(), lon.to_radians());
        Vec3::new(lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin()) * rad
    };
    vec![
        at(6_778e3, 23.4, 51.7),
        at(6_878e3, -0.3, -120.0),
        at(7_178e3, 89.9, 10.0),
        at(6_678e3, -89.7, 200.0),
        at(6_900e3, 63.0, -45.0),
        at(42_164e3, 0.05, 75.0),
        at(26_560e3, -55.0, 160.0),
    ]
}

#[test]
fn the_harmonic_acceleration_equals_the_direct_sum_to_1e_12() {
    let egm = egm2008().unwrap();
    let (mut worst_total, mut worst_harm) = (0.0f64, 0.0f64);
    for (degree, order) in [(20, 20), (70, 70), (30, 12), (2, 0), (8, 8)] {
        let field = HarmonicField::new(egm, degree, order).unwrap();
        for r in points() {
            let (harm, central) = direct(egm, degree, order, &r);
            let total = harm + central;
            let got = field.acceleration(&r);
            let e_total = (got - total).norm() / total.norm();
            let e_harm = (field.harmonics(&r) - harm).norm() / harm.norm();
            worst_total = worst_total.max(e_total);
            worst_harm = worst_harm.max(e_harm);
            assert!(
                e_total < 1e-12,
                "{degree}x{order} at {r:?}: total off by {e_total:e}"
            );
            assert!(
                e_harm < 1e-12,
                "{degree}x{order} at {r:?}: harmonics off by {e_harm:e}"
            );
        }
    }
    println!(
        "worst relative difference: total acceleration {worst_total:.1e}, harmonic part alone {worst_harm:.1e}"
    );
}

#[test]
fn degree_2_order_0_alone_is_the_j2_acceleration() {
    // The J2 formula of satsim's orbit (Vallado eq. 8-30), with J2 = −√5 C̄20.
    let j2 = 1.08262668e-3;
    let c = Coefficients::from_fn("j2", MU_EARTH, R_EARTH, 2, |n, m| {
        if (n, m) == (2, 0) {
            (-j2 / 5f64.sqrt(), 0.0)
        } else {
            (0.0, 0.0)
        }
    });
    let field = HarmonicField::new(&c, 2, 0).unwrap();
    let mut worst = 0.0f64;
    for r in points() {
        let r2 = r.norm_squared();
        let rn = r2.sqrt();
        let z2 = r.z * r.z / r2;
        let k = -1.5 * j2 * MU_EARTH * R_EARTH * R_EARTH / (r2 * r2 * rn);
        let expected = -MU_EARTH / (r2 * rn) * r
            + k * Vec3::new(
                r.x * (1.0 - 5.0 * z2),
                r.y * (1.0 - 5.0 * z2),
                r.z * (3.0 - 5.0 * z2),
            );
        let e = (field.acceleration(&r) - expected).norm() / expected.norm();
        worst = worst.max(e);
        assert!(e < 1e-12, "{r:?}: {e:e}");
    }
    println!("degree 2 order 0 against the J2 formula: worst {worst:.1e} relative");
}

#[test]
fn the_shipped_coefficients_are_egm2008() {
    let egm = egm2008().unwrap();
    assert_eq!(egm.max_degree, MAX_DEGREE);
    assert_eq!((egm.gm, egm.radius), (3.986004415e14, 6_378_136.3));
    // Spot values from the published file: C̄20, C̄22/S̄22, the last row.
    assert_eq!(egm.get(2, 0), (-0.484165143790815e-03, 0.0));
    assert_eq!(
        egm.get(2, 2),
        (0.243938357328313e-05, -0.140027370385934e-05)
    );
    assert_eq!(
        egm.get(70, 70),
        (0.298214665798648e-09, -0.140484139457899e-09)
    );
    // The field at a low orbit: 8.7 m/s², the harmonics a thousandth of it (J2).
    let f = HarmonicField::new(egm, 70, 70).unwrap();
    let r = Vec3::new(6_778e3, 0.0, 0.0);
    let h = f.harmonics(&r).norm() / f.central(&r).norm();
    assert!((1.0e-3..2.0e-3).contains(&h), "{h}");
}

#[test]
fn bad_degrees_and_orders_are_refused() {
    let egm = egm2008().unwrap();
    let e = HarmonicField::new(egm, 71, 10).unwrap_err();
    assert!(e.contains("degree 71") && e.contains("70 at most"), "{e}");
    let e = HarmonicField::new(egm, 10, 11).unwrap_err();
    assert!(e.contains("order 11") && e.contains("degree 10"), "{e}");
}

#[test]
fn the_field_turns_with_the_earth() {
    // In GCRF the same inertial point sees the field of a different longitude 6 h later:
    // the harmonic part changes, the central part does not; and the rotation is undone
    // exactly (ITRF round trip).
    let egm = egm2008().unwrap();
    let f = HarmonicField::new(egm, 20, 20).unwrap();
    let epoch = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    let r = Vec3::new(5_000e3, 4_000e3, 2_500e3);
    let a0 = f.acceleration_gcrf(epoch, 0.0, &r);
    let a6 = f.acceleration_gcrf(epoch, 21_600.0, &r);
    let rot = satsim_environment::earth::gcrf_to_itrf(epoch, 0.0);
    let expected = rot.inverse() * f.acceleration(&(rot * r));
    assert!((a0 - expected).norm() < 1e-15 * a0.norm());
    let change = (a6 - a0).norm();
    assert!(change > 1e-6 && change < 1e-3, "{change:e}");
}

#[test]
fn the_third_body_acceleration_is_the_difference_of_the_pulls() {
    let sun = Vec3::new(1.2e11, -8.0e10, -3.5e10);
    let moon = Vec3::new(-2.1e8, 3.0e8, 1.1e8);
    for r in points() {
        for (mu, b) in [(MU_SUN, sun), (MU_MOON, moon)] {
            let d = b - r;
            let formula = mu * (d / d.norm().powi(3) - b / b.norm().powi(3));
            let got = third_body_acceleration(mu, &b, &r);
            // The formula loses ~|b|/|r| digits to cancellation: 1e-11 for the Sun.
            assert!(
                (got - formula).norm() < 1e-9 * formula.norm(),
                "{r:?}: {got:?} vs {formula:?}"
            );
        }
    }
}

#[test]
fn the_sun_perturbs_a_geostationary_orbit_by_about_5e_6() {
    // The solar tide at GEO: between μ☉ r/d³ (across) and 2 μ☉ r/d³ (along the line),
    // 1.7e-6 to 3.5e-6 m/s²; the Moon's is about 2.2 times as large (up to 1.1e-5 at perigee).
    let epoch = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    let sun = satsim_environment::sun::sun_position(epoch, 0.0);
    let moon = satsim_environment::moon::moon_position(epoch, 0.0);
    let mut worst_sun: f64 = 0.0;
    let mut worst_moon: f64 = 0.0;
    for k in 0..24 {
        let u = (k as f64 * 15.0).to_radians();
        let r = Vec3::new(u.cos(), u.sin(), 0.0) * 42_164e3;
        let s = third_body_acceleration(MU_SUN, &sun, &r).norm();
        let m = third_body_acceleration(MU_MOON, &moon, &r).norm();
        assert!((1.5e-6..4.0e-6).contains(&s), "Sun {s:e}");
        assert!((3.0e-6..1.2e-5).contains(&m), "Moon {m:e}");
        worst_sun = worst_sun.max(s);
        worst_moon = worst_moon.max(m);
    }
    println!(
        "GEO: the Sun's perturbation up to {worst_sun:.2e} m/s², the Moon's up to {worst_moon:.2e}"
    );
}
