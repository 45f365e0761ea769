//! The exponential atmosphere: `ρ = ρ0 exp(−(h − h0)/H)` from the row of Vallado's table
//! (Fundamentals of Astrodynamics and Applications, 4th ed., Table 8-4) with the largest
//! base altitude `h0 <= h`, with `h = |r| − R_E` (a spherical Earth, as the table's use
//! assumes). Above 1000 km the last row continues; below 0 km the first row does.

use crate::R_EARTH;

/// `(h0 km, ρ0 kg/m³, H km)`, Vallado Table 8-4.
const TABLE: [(f64, f64, f64); 28] = [
    (0.0, 1.225, 7.249),
    (25.0, 3.899e-2, 6.349),
    (30.0, 1.774e-2, 6.682),
    (40.0, 3.972e-3, 7.554),
    (50.0, 1.057e-3, 8.382),
    (60.0, 3.206e-4, 7.714),
    (70.0, 8.770e-5, 6.549),
    (80.0, 1.905e-5, 5.799),
    (90.0, 3.396e-6, 5.382),
    (100.0, 5.297e-7, 5.877),
    (110.0, 9.661e-8, 7.263),
    (120.0, 2.438e-8, 9.473),
    (130.0, 8.484e-9, 12.636),
    (140.0, 3.845e-9, 16.149),
    (150.0, 2.070e-9, 22.523),
    (180.0, 5.464e-10, 29.740),
    (200.0, 2.789e-10, 37.105),
    (250.0, 7.248e-11, 45.546),
    (300.0, 2.418e-11, 53.628),
    (350.0, 9.518e-12, 53.298),
    (400.0, 3.725e-12, 58.515),
    (450.0, 1.585e-12, 60.828),
    (500.0, 6.967e-13, 63.822),
    (600.0, 1.454e-13, 71.835),
    (700.0, 3.614e-14, 88.667),
    (800.0, 1.170e-14, 124.64),
    (900.0, 5.245e-15, 181.05),
    (1000.0, 3.019e-15, 268.00),
];

/// The density (kg/m³) at altitude `h` (m) above the equatorial radius.
///
/// ```
/// use satsim_environment::atmosphere::density_at_altitude;
/// assert_eq!(density_at_altitude(500e3), 6.967e-13);
/// ```
pub fn density_at_altitude(h: f64) -> f64 {
    let km = h / 1000.0;
    let row = TABLE
        .iter()
        .rev()
        .find(|(h0, _, _)| *h0 <= km)
        .unwrap_or(&TABLE[0]);
    let (h0, rho0, scale) = *row;
    rho0 * (-(km - h0) / scale).exp()
}

/// The density (kg/m³) at distance `r` (m) from the Earth's centre.
pub fn density(r: f64) -> f64 {
    density_at_altitude(r - R_EARTH)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_row_starts_at_its_base_density_and_falls_by_e_over_its_scale_height() {
        for (h0, rho0, scale) in TABLE {
            assert_eq!(density_at_altitude(h0 * 1000.0), rho0);
            let r = density_at_altitude((h0 + scale) * 1000.0);
            // Within the row (or the next row takes over: then not checked).
            let next = TABLE
                .iter()
                .find(|(h, _, _)| *h > h0)
                .map_or(f64::MAX, |x| x.0);
            if h0 + scale < next {
                assert!((r / rho0 - (-1.0f64).exp()).abs() < 1e-12, "row {h0}");
            }
        }
        // Continuous to within the table's rounding at each boundary (a few percent).
        for w in TABLE.windows(2) {
            let below = w[0].1 * (-(w[1].0 - w[0].0) / w[0].2).exp();
            assert!(
                (below / w[1].1 - 1.0).abs() < 0.06,
                "at {} km: {below} vs {}",
                w[1].0,
                w[1].1
            );
        }
        assert!(density(R_EARTH + 2000e3) < 3.019e-15 && density(R_EARTH + 2000e3) > 0.0);
    }
}
