//! The cost of one call of the per-step functions, measured with `std::time::Instant`:
//! `cargo run --release -p satsim-environment --example per_call_cost`.

use satsim_environment::magnetic::{FieldModel, GeoField};
use satsim_environment::shadow::{ShadowModel, shadow_fraction};
use satsim_environment::sun::sun_position;
use satsim_environment::{Vec3, parse_epoch};
use std::hint::black_box;
use std::time::Instant;

/// Nanoseconds per call of `f` over `n` calls, each at a different time/position.
fn per_call(name: &str, n: usize, mut f: impl FnMut(f64) -> f64) {
    let start = Instant::now();
    let mut acc = 0.0;
    for k in 0..n {
        acc += f(black_box(k as f64 * 0.7));
    }
    let ns = start.elapsed().as_nanos() as f64 / n as f64;
    println!("{name:<28} {ns:8.1} ns/call   (checksum {acc:.3e})");
}

fn main() -> Result<(), String> {
    let epoch = parse_epoch("2026-03-20T12:00:00 UTC")?;
    let igrf = GeoField::new(FieldModel::Igrf14, epoch)?;
    let dipole = GeoField::new(FieldModel::Dipole, epoch)?;
    let sun = sun_position(epoch, 0.0);
    let orbit = |t: f64| {
        let u = t * 1.1e-3;
        Vec3::new(u.cos(), u.sin() * 0.8, u.sin() * 0.6) * 6.9e6
    };
    let n = 200_000;
    per_call("centuries_tt", n, |t| {
        satsim_environment::epoch::centuries_tt(epoch, t)
    });
    per_call("days_ut1", n, |t| {
        satsim_environment::epoch::days_ut1(epoch, t)
    });
    per_call("decimal_year", n, |t| {
        satsim_environment::epoch::decimal_year(epoch, t)
    });
    per_call("gcrf_to_itrf", n, |t| {
        satsim_environment::earth::gcrf_to_itrf(epoch, t).matrix()[0]
    });
    per_call("sun_position", n, |t| sun_position(epoch, t).x);
    per_call("shadow_fraction conical", n, |t| {
        shadow_fraction(ShadowModel::Conical, &orbit(t), &sun)
    });
    per_call("shadow_fraction cylindrical", n, |t| {
        shadow_fraction(ShadowModel::Cylindrical, &orbit(t), &sun)
    });
    per_call("field_gcrf igrf14", n, |t| igrf.field_gcrf(t, &orbit(t)).x);
    per_call("field_gcrf dipole", n, |t| {
        dipole.field_gcrf(t, &orbit(t)).x
    });
    per_call("field_itrf igrf14", n, |t| igrf.field_itrf(t, &orbit(t)).x);
    Ok(())
}
