//! The cost of one acceleration of the harmonic field (EGM2008) at several degrees, of the
//! GCRF evaluation (with the Earth's rotation), of the Moon's series and of a third body's
//! pull, measured with `std::time::Instant`:
//! `cargo run --release -p satsim-environment --example gravity_cost`.

use satsim_environment::gravity::{HarmonicField, MU_MOON, egm2008, third_body_acceleration};
use satsim_environment::moon::moon_position;
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
    println!("{name:<34} {ns:9.1} ns/call   (checksum {acc:.3e})");
}

fn main() -> Result<(), String> {
    let epoch = parse_epoch("2026-03-20T12:00:00 UTC")?;
    let egm = egm2008()?;
    let orbit = |t: f64| {
        let u = t * 1.1e-3;
        Vec3::new(u.cos(), u.sin() * 0.8, u.sin() * 0.6) * 6.9e6
    };
    let n = 100_000;
    for (degree, order) in [(2, 0), (4, 4), (8, 8), (20, 20), (40, 40), (70, 70)] {
        let f = HarmonicField::new(egm, degree, order)?;
        per_call(
            &format!("harmonics {degree}x{order} (Earth-fixed)"),
            n,
            |t| f.acceleration(&orbit(t)).x,
        );
    }
    let f = HarmonicField::new(egm, 20, 20)?;
    per_call("harmonics 20x20 from GCRF", n, |t| {
        f.acceleration_gcrf(epoch, t, &orbit(t)).x
    });
    per_call("moon_position (series)", n, |t| moon_position(epoch, t).x);
    let moon = moon_position(epoch, 0.0);
    per_call("third_body_acceleration", n, |t| {
        third_body_acceleration(MU_MOON, &moon, &orbit(t)).x
    });
    Ok(())
}
