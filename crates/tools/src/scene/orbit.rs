//! `[orbit]`: the orbit of the centre of mass, by elements or by position and velocity
//! (inertial frame, SI units; angles in degrees in the file).

use super::file::OrbitFile;
use super::parse::Parser;
use satsim_spacecraft::effects::{Elements, Orbit, OrbitModel};
use satsim_tree::error::Num;
use satsim_tree::io::FileError;
use satsim_tree::spatial::Vec3;
use toml::Spanned;

/// The lowest orbit altitude a scene accepts (m): below it the atmosphere ends an orbit
/// within hours, and a smaller number is almost always kilometres written as metres.
pub const MIN_ALTITUDE: f64 = 100e3;

impl Parser<'_> {
    pub(super) fn orbit(&self, o: &Spanned<OrbitFile>) -> Result<Orbit, FileError> {
        let span = Some(o.span());
        let f = o.get_ref();
        let model = match f.model.as_ref().map(|m| (m.get_ref().as_str(), m.span())) {
            None | Some(("kepler", _)) => OrbitModel::Kepler,
            Some(("j2", _)) => OrbitModel::J2,
            Some((other, s)) => {
                return Err(self.error(
                    Some(s),
                    format!(
                        "`orbit.model`: unknown value `{other}`, expected \"kepler\" or \"j2\""
                    ),
                ));
            }
        };
        let vec = |v: Option<[f64; 3]>, k: usize| v.map(|v| v[k]);
        self.check_numbers(
            o.span(),
            "orbit.",
            &[
                ("inclination_deg", f.inclination_deg, false),
                ("raan_deg", f.raan_deg, false),
                ("arg_periapsis_deg", f.arg_periapsis_deg, false),
                ("true_anomaly_deg", f.true_anomaly_deg, false),
                ("j2", f.j2, false),
                ("position", vec(f.position, 0), false),
                ("position", vec(f.position, 1), false),
                ("position", vec(f.position, 2), false),
                ("velocity", vec(f.velocity, 0), false),
                ("velocity", vec(f.velocity, 1), false),
                ("velocity", vec(f.velocity, 2), false),
            ],
        )?;
        if let Some(i) = f.inclination_deg
            && !(0.0..=180.0).contains(&i)
        {
            return Err(self.error(
                Some(o.span()),
                format!(
                    "`orbit.inclination_deg` is {} deg: an inclination lies in [0, 180] deg",
                    Num(i)
                ),
            ));
        }
        for (key, v) in [("mu", f.mu), ("radius", f.radius)] {
            if let Some(v) = v
                && !(v > 0.0 && v.is_finite())
            {
                return Err(self.error(
                    Some(o.span()),
                    format!("`orbit.{key}` must be a finite number > 0, got {}", Num(v)),
                ));
            }
        }
        let mut orbit = Orbit::new(model, Vec3::zeros(), Vec3::zeros());
        if let Some(mu) = f.mu {
            orbit.mu = mu;
        }
        if let Some(j2) = f.j2 {
            orbit.j2 = j2;
        }
        if let Some(r) = f.radius {
            orbit.radius = r;
        }
        let has_elements = f.altitude.is_some() || f.semi_major_axis.is_some();
        match (has_elements, f.position, f.velocity) {
            (false, Some(r), Some(v)) => {
                orbit.r0 = Vec3::from(r);
                orbit.v0 = Vec3::from(v);
                if orbit.r0.norm().is_nan() || orbit.r0.norm() <= orbit.radius * 0.5 {
                    return Err(self.error(span, "`orbit.position` is inside the Earth"));
                }
                let h = orbit.r0.norm() - orbit.radius;
                if h < MIN_ALTITUDE {
                    return Err(self.error(
                        span,
                        format!(
                            "`orbit.position` is {h:.0} m above `radius`, below 100 km (no orbit lasts there); positions are in metres (7e6, not 7000)"
                        ),
                    ));
                }
                // Without angular momentum there is no orbital plane: the local orbital
                // frame (and every column or law that uses it) is undefined. Round-off of
                // the cross product is ~1e-16 of |r||v|, far below this.
                let momentum = orbit.r0.cross(&orbit.v0).norm();
                if momentum <= 1e-10 * orbit.r0.norm() * orbit.v0.norm() {
                    return Err(self.error(
                        span,
                        format!(
                            "the orbit is degenerate: `orbit.velocity` is {}, so the angular momentum r × v is zero and there is no orbital plane; give a velocity with a component across the position (a circular orbit's is sqrt(mu / |r|) = {:.0} m/s, at right angles to it)",
                            if orbit.v0.norm() == 0.0 {
                                "zero"
                            } else {
                                "parallel to `orbit.position` (a radial orbit)"
                            },
                            (orbit.mu / orbit.r0.norm()).sqrt()
                        ),
                    ));
                }
            }
            (true, None, None) => {
                let a = match (&f.altitude, &f.semi_major_axis) {
                    (Some(h), None) => {
                        let v = self.positive(h, "orbit.altitude")?;
                        if v < MIN_ALTITUDE {
                            return Err(self.error(
                                Some(h.span()),
                                format!(
                                    "`orbit.altitude` is {v} m, below 100 km (no orbit lasts there); altitudes are in metres: for {v} km write `altitude = {v}e3`"
                                ),
                            ));
                        }
                        orbit.radius + v
                    }
                    (None, Some(a)) => self.positive(a, "orbit.semi_major_axis")?,
                    _ => {
                        return Err(self.error(
                            span,
                            "give `orbit.altitude` or `orbit.semi_major_axis`, not both",
                        ));
                    }
                };
                let e = match &f.eccentricity {
                    Some(e) => {
                        let v = self.non_negative(e, "orbit.eccentricity")?;
                        if v >= 1.0 {
                            return Err(
                                self.error(Some(e.span()), "`orbit.eccentricity` must be < 1")
                            );
                        }
                        v
                    }
                    None => 0.0,
                };
                let el = Elements {
                    a,
                    e,
                    i: f.inclination_deg.unwrap_or(0.0).to_radians(),
                    raan: f.raan_deg.unwrap_or(0.0).to_radians(),
                    argp: f.arg_periapsis_deg.unwrap_or(0.0).to_radians(),
                    nu: f.true_anomaly_deg.unwrap_or(0.0).to_radians(),
                };
                if a * (1.0 - e) < orbit.radius {
                    return Err(self.error(
                        span,
                        format!(
                            "the orbit's periapsis ({:.0} m) is inside the Earth",
                            a * (1.0 - e)
                        ),
                    ));
                }
                let hp = a * (1.0 - e) - orbit.radius;
                if hp < MIN_ALTITUDE {
                    return Err(self.error(
                        span,
                        format!(
                            "the orbit's periapsis altitude ({hp:.0} m) is below 100 km (no orbit lasts there); lengths are in metres (`semi_major_axis = 6878e3` for 500 km)"
                        ),
                    ));
                }
                let (r, v) = el.to_cartesian(orbit.mu);
                orbit.r0 = r;
                orbit.v0 = v;
            }
            _ => {
                return Err(self.error(span, "[orbit] needs either `altitude` or `semi_major_axis` (with optional elements), or both `position` and `velocity`"));
            }
        }
        Ok(orbit)
    }
}
