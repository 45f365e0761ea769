//! A scene's epoch: t = 0 as a date, and the time arguments the series of this crate take.
//!
//! An epoch is written as hifitime reads it, `"2026-03-20T12:00:00 UTC"`, with the time scale
//! last: UTC, TAI, TT or GPST (no scale: UTC). UT1 is taken equal to UTC.

pub use hifitime::Epoch;
use hifitime::{Duration, TimeScale};
use std::str::FromStr;

/// The epoch written in `text`, or a message saying what is wrong with it.
///
/// ```
/// use satsim_environment::parse_epoch;
/// let e = parse_epoch("2000-01-01T12:00:00 TT").unwrap();
/// assert_eq!(satsim_environment::epoch::centuries_tt(e, 0.0), 0.0);
/// assert!(parse_epoch("2026-13-40").is_err());
/// ```
pub fn parse_epoch(text: &str) -> Result<Epoch, String> {
    let scales = ["UTC", "TAI", "TT", "GPST"];
    let trimmed = text.trim();
    if let Some(last) = trimmed.rsplit(' ').next().filter(|_| trimmed.contains(' '))
        && !scales.contains(&last)
    {
        return Err(format!(
            "`{text}`: unknown time scale `{last}` (expected UTC, TAI, TT or GPST, e.g. \"2026-03-20T12:00:00 UTC\")"
        ));
    }
    Epoch::from_str(trimmed).map_err(|e| {
        format!("`{text}` is not a date ({e}); write e.g. \"2026-03-20T12:00:00 UTC\"")
    })
}

/// `epoch + t` seconds (SI seconds, the run's time).
pub fn at(epoch: Epoch, t: f64) -> Epoch {
    epoch + Duration::from_seconds(t)
}

/// Julian centuries of TT from J2000.0 (2000-01-01T12:00:00 TT) to `epoch + t`: the time
/// argument of the Sun's series and of precession.
pub fn centuries_tt(epoch: Epoch, t: f64) -> f64 {
    // Elapsed SI seconds (the same in every scale but UTC), exact in hifitime's integers.
    let j2000 = Epoch::from_gregorian_hms(2000, 1, 1, 12, 0, 0, TimeScale::TT);
    ((epoch - j2000).to_seconds() + t) / (36_525.0 * 86_400.0)
}

/// Days of UT1 (= UTC) from J2000.0 (2000-01-01T12:00:00 UT1) to `epoch + t`: the argument of
/// the Earth's rotation angle.
pub fn days_ut1(epoch: Epoch, t: f64) -> f64 {
    // UTC seconds (leap seconds left out, as UT1 leaves them out) from the UTC J2000 noon.
    let j2000 = Epoch::from_gregorian_hms(2000, 1, 1, 12, 0, 0, TimeScale::UTC);
    (epoch.to_utc_seconds() - j2000.to_utc_seconds() + t) / 86_400.0
}

/// Decimal year of `epoch + t` (UTC, calendar): the year plus the fraction of it elapsed, the
/// argument of the geomagnetic model's coefficients (IGRF's models stand at 1900.0, 1905.0,
/// …: 1 January, 00:00).
pub fn decimal_year(epoch: Epoch, t: f64) -> f64 {
    let e = at(epoch, t);
    let year = e.to_gregorian_utc().0;
    let start = Epoch::from_gregorian_utc_at_midnight(year, 1, 1);
    let end = Epoch::from_gregorian_utc_at_midnight(year + 1, 1, 1);
    f64::from(year) + (e - start).to_seconds() / (end - start).to_seconds()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scale_the_contract_names_is_read_and_others_are_refused() {
        let tt = parse_epoch("2026-03-20T12:00:00 TT").unwrap();
        let utc = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
        let tai = parse_epoch("2026-03-20T12:00:00 TAI").unwrap();
        let gps = parse_epoch("2026-03-20T12:00:00 GPST").unwrap();
        // TT = TAI + 32.184 s; TAI = UTC + 37 s (leap seconds since 2017); GPST = TAI - 19 s.
        let s = |a: Epoch, b: Epoch| (a - b).to_seconds();
        assert!((s(utc, tt) - 69.184).abs() < 1e-9, "{}", s(utc, tt));
        assert!((s(tai, tt) - 32.184).abs() < 1e-9);
        assert!((s(gps, tt) - 51.184).abs() < 1e-9);
        assert_eq!(parse_epoch("2026-03-20T12:00:00").unwrap(), utc);
        for bad in [
            "2026-03-20T12:00:00 UT1X",
            "tomorrow",
            "",
            "2026-02-30T00:00:00 UTC",
        ] {
            assert!(parse_epoch(bad).is_err(), "{bad} was accepted");
        }
    }

    #[test]
    fn time_arguments_count_from_j2000() {
        let e = parse_epoch("2000-01-01T12:00:00 TT").unwrap();
        assert_eq!(centuries_tt(e, 36_525.0 * 86_400.0), 1.0);
        // UTC - TT at J2000 was -64.184 s.
        let d = days_ut1(e, 0.0);
        assert!((d * 86_400.0 + 64.184).abs() < 1e-6, "{}", d * 86_400.0);
        // J2000 is 2000-01-01T11:58:55.816 UTC: 0.4993 days into a leap year.
        let expected = 2000.0 + (0.5 - 64.184 / 86_400.0) / 366.0;
        assert!((decimal_year(e, 0.0) - expected).abs() < 1e-12);
        let new_year = parse_epoch("2026-01-01T00:00:00 UTC").unwrap();
        assert_eq!(decimal_year(new_year, 0.0), 2026.0);
        assert!((decimal_year(new_year, 365.0 * 43_200.0) - 2026.5).abs() < 1e-12);
    }
}
