//! `[orbit]`: the orbit of the centre of mass, by elements or by position and velocity
//! (inertial frame, SI units; angles in degrees in the file), and the fields it moves in.
//!
//! The Earth's field is `model` (`"kepler"`, the default, or `"j2"`, as before) or `gravity`
//! (contract section 17), which replaces it: `"point"` is `model = "kepler"`, `"j2"` is
//! `model = "j2"` (with `j2`, `mu`, `radius` as before), and `"egm2008"` or
//! `{ model = "egm2008", degree = N, order = M, lattice_deg = D }` the spherical harmonics to
//! degree N (default 20, at most 70) and order M (default N, at most N), all but their
//! central term and J2 read through an Earth-fixed lattice of D degrees (default
//! [`LATTICE_DEG`], at most [`MAX_LATTICE_DEG`]; 0: the series at every call), with EGM2008's
//! own GM and radius (GM also becomes the orbit's `mu`: the elements' conversion and the
//! gravity-gradient torque use it). Both keys may be given only when they say the same;
//! with `"egm2008"`, `model`, `mu` and `j2` would be ignored and are refused (`radius` stays
//! the altitude's reference). `third_body = ["sun", "moon"]` adds their point-mass
//! perturbations. The harmonics and the third bodies need the scene's `epoch`; each
//! refusal names the line of the key at fault.

use super::file::OrbitFile;
use super::parse::Parser;
use satsim_environment::Epoch;
use satsim_environment::gravity::{HarmonicField, LATTICE_DEG, MAX_DEGREE, egm2008};
use satsim_spacecraft::effects::{Elements, Orbit, OrbitModel, ThirdBodies};
use satsim_tree::error::Num;
use satsim_tree::io::FileError;
use satsim_tree::spatial::Vec3;
use std::sync::Arc;
use toml::Spanned;

/// The lowest orbit altitude a scene accepts (m): below it the atmosphere ends an orbit
/// within hours, and a smaller number is almost always kilometres written as metres.
pub const MIN_ALTITUDE: f64 = 100e3;

/// The largest lattice spacing `orbit.gravity.lattice_deg` accepts (degrees): at 10 degrees
/// the interpolation's error in low orbit is already as large as the degree 21 to 30 terms a
/// 20x20 field leaves out.
pub const MAX_LATTICE_DEG: f64 = 10.0;

impl Parser<'_> {
    pub(super) fn orbit(&self, o: &Spanned<OrbitFile>) -> Result<Orbit, FileError> {
        let span = Some(o.span());
        let f = o.get_ref();
        let (model, harmonics, lattice_deg) = self.gravity(f)?;
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
        if let Some(field) = harmonics {
            orbit.mu = field.gm;
            orbit.harmonics = Some(Arc::new(field));
            orbit.lattice_deg = lattice_deg;
        }
        orbit.third_bodies = self.third_bodies(f)?;
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

    /// The Earth's field from `model` and `gravity`: the model, and the harmonic field and
    /// its lattice's spacing (degrees) when `gravity` asks for one.
    fn gravity(
        &self,
        f: &OrbitFile,
    ) -> Result<(OrbitModel, Option<HarmonicField>, f64), FileError> {
        let model = match f.model.as_ref().map(|m| (m.get_ref().as_str(), m.span())) {
            None => None,
            Some(("kepler", _)) => Some(OrbitModel::Kepler),
            Some(("j2", _)) => Some(OrbitModel::J2),
            Some((other, s)) => {
                return Err(self.error(
                    Some(s),
                    format!(
                        "`orbit.model`: unknown value `{other}`, expected \"kepler\" or \"j2\""
                    ),
                ));
            }
        };
        let Some(g) = &f.gravity else {
            return Ok((model.unwrap_or_default(), None, LATTICE_DEG));
        };
        let at = |m: String| self.error(Some(g.span()), m);
        // The name, and the degree and order when given.
        let (name, degree, order, lattice) = match g.get_ref() {
            toml::Value::String(s) => (s.clone(), None, None, None),
            toml::Value::Table(t) => {
                if let Some(k) = t
                    .keys()
                    .find(|k| !["model", "degree", "order", "lattice_deg"].contains(&k.as_str()))
                {
                    return Err(at(format!(
                        "`orbit.gravity.{k}`: unknown key, expected `model`, `degree`, `order` or `lattice_deg`"
                    )));
                }
                let name = match t.get("model") {
                    Some(toml::Value::String(s)) => s.clone(),
                    _ => {
                        return Err(at(
                            "`orbit.gravity` needs `model = \"point\" | \"j2\" | \"egm2008\"`"
                                .into(),
                        ));
                    }
                };
                let int = |key: &str| match t.get(key) {
                    None => Ok(None),
                    Some(toml::Value::Integer(n)) => Ok(Some(*n)),
                    Some(_) => Err(at(format!(
                        "`orbit.gravity.{key}` must be a whole number (e.g. `{key} = 20`)"
                    ))),
                };
                let lattice = match t.get("lattice_deg") {
                    None => None,
                    Some(toml::Value::Float(x)) => Some(*x),
                    Some(toml::Value::Integer(n)) => Some(*n as f64),
                    Some(_) => {
                        return Err(at(
                            "`orbit.gravity.lattice_deg` must be a number of degrees (e.g. `lattice_deg = 1.0`)".into(),
                        ));
                    }
                };
                (name, int("degree")?, int("order")?, lattice)
            }
            _ => {
                return Err(at(
                    "`orbit.gravity` must be \"point\", \"j2\", \"egm2008\" or a table `{ model = \"egm2008\", degree = 20, order = 20 }`".into(),
                ));
            }
        };
        let chosen = match name.as_str() {
            "point" => Some(OrbitModel::Kepler),
            "j2" => Some(OrbitModel::J2),
            "egm2008" => None,
            other => {
                return Err(at(format!(
                    "`orbit.gravity`: unknown model `{other}`, expected \"point\", \"j2\" or \"egm2008\""
                )));
            }
        };
        if let Some(chosen) = chosen {
            if degree.is_some() || order.is_some() || lattice.is_some() {
                return Err(at(format!(
                    "`orbit.gravity`: `degree`, `order` and `lattice_deg` belong to \"egm2008\", not to \"{name}\""
                )));
            }
            if let Some(m) = model
                && m != chosen
            {
                return Err(at(format!(
                    "`orbit.gravity = \"{name}\"` contradicts `orbit.model = \"{}\"`: give one of them (`gravity` replaces `model`)",
                    if m == OrbitModel::J2 { "j2" } else { "kepler" }
                )));
            }
            if chosen == OrbitModel::Kepler && f.j2.is_some() {
                return Err(at(
                    "`orbit.j2` is given but `orbit.gravity = \"point\"` has no J2 term".into(),
                ));
            }
            return Ok((chosen, None, LATTICE_DEG));
        }
        if model.is_some() {
            return Err(at(
                "`orbit.gravity = \"egm2008\"` replaces `orbit.model`: leave `model` out".into(),
            ));
        }
        for (key, given) in [("j2", f.j2.is_some()), ("mu", f.mu.is_some())] {
            if given {
                return Err(at(format!(
                    "`orbit.{key}` is given but `orbit.gravity = \"egm2008\"` uses the model's own {}: leave `{key}` out",
                    if key == "mu" {
                        "GM (3.986004415e14 m^3/s^2)"
                    } else {
                        "coefficients"
                    }
                )));
            }
        }
        let degree = degree.unwrap_or(20);
        let order = order.unwrap_or(degree);
        if !(2..=MAX_DEGREE as i64).contains(&degree) {
            return Err(at(format!(
                "`orbit.gravity.degree` is {degree}: EGM2008 is shipped to degree {MAX_DEGREE}, and the harmonics start at 2"
            )));
        }
        if !(0..=degree).contains(&order) {
            return Err(at(format!(
                "`orbit.gravity.order` is {order}: the order lies from 0 to the degree ({degree})"
            )));
        }
        let lattice = lattice.unwrap_or(LATTICE_DEG);
        if !(0.0..=MAX_LATTICE_DEG).contains(&lattice) {
            return Err(at(format!(
                "`orbit.gravity.lattice_deg` is {}: the lattice's spacing lies from 0 (the series at every call) to {MAX_LATTICE_DEG} degrees",
                Num(lattice)
            )));
        }
        let field = egm2008()
            .and_then(|c| HarmonicField::new(c, degree as usize, order as usize))
            .map_err(|e| at(format!("`orbit.gravity`: {e}")))?;
        Ok((OrbitModel::Kepler, Some(field), lattice))
    }

    /// `third_body = ["sun", "moon"]`.
    fn third_bodies(&self, f: &OrbitFile) -> Result<ThirdBodies, FileError> {
        let mut bodies = ThirdBodies::default();
        for b in f.third_body.iter().flat_map(|l| l.get_ref()) {
            let slot = match b.get_ref().as_str() {
                "sun" => &mut bodies.sun,
                "moon" => &mut bodies.moon,
                other => {
                    return Err(self.error(
                        Some(b.span()),
                        format!(
                            "`orbit.third_body`: unknown body `{other}`, expected \"sun\" or \"moon\""
                        ),
                    ));
                }
            };
            if *slot {
                return Err(self.error(
                    Some(b.span()),
                    format!("`orbit.third_body`: `{}` is listed twice", b.get_ref()),
                ));
            }
            *slot = true;
        }
        Ok(bodies)
    }

    /// Gives the orbit the scene's `epoch`, which the harmonic field (the Earth's
    /// orientation) and the third bodies (their positions) need: without one, an error at
    /// the key that needs it.
    pub(super) fn orbit_epoch(
        &self,
        o: &Spanned<OrbitFile>,
        orbit: &mut Orbit,
        epoch: Option<Epoch>,
    ) -> Result<(), FileError> {
        orbit.epoch = epoch;
        if epoch.is_some() {
            return Ok(());
        }
        let f = o.get_ref();
        let need = |span: std::ops::Range<usize>, what: &str| {
            Err(self.error(
                Some(span),
                format!(
                    "{what} needs the scene's `epoch` (t = 0 as a date, e.g. `epoch = \"2026-03-20T12:00:00 UTC\"` at the top of the file)"
                ),
            ))
        };
        if let (Some(_), Some(g)) = (&orbit.harmonics, &f.gravity) {
            return need(
                g.span(),
                "`orbit.gravity = \"egm2008\"` turns the field with the Earth: it",
            );
        }
        if let (true, Some(t)) = (orbit.third_bodies.any(), &f.third_body) {
            return need(
                t.span(),
                "`orbit.third_body` places the Sun and the Moon by date: it",
            );
        }
        Ok(())
    }
}
