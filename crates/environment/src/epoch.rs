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

/// The first year of the dates a run may cover (1 January 00:00 UTC).
pub const FIRST_YEAR: f64 = 1900.0;
/// The year at whose start the dates a run may cover end.
pub const END_YEAR: f64 = 2100.0;

/// Refuses a run from `epoch` lasting `duration` seconds that leaves [`FIRST_YEAR`] to
/// [`END_YEAR`]: the span over which the Sun's series is checked against ERFA's epv00
/// ephemeris (`tests/it/sun.rs`, 0.5 arcsecond; epv00 itself covers 1900-2100). Outside it the
/// truncated series and the IAU-1976 precession drift without bound (year 100000 puts the
/// Sun at 2.4 AU), so a date there is almost always a typing error.
///
/// ```
/// use satsim_environment::{epoch::check_span, parse_epoch};
/// assert!(check_span(parse_epoch("2026-03-20T12:00:00 UTC").unwrap(), 86_400.0).is_ok());
/// let far = parse_epoch("9999-01-01T00:00:00 UTC").unwrap();
/// assert!(check_span(far, 0.0).unwrap_err().contains("1900 to 2100"));
/// let late = parse_epoch("2099-12-31T00:00:00 UTC").unwrap();
/// assert!(check_span(late, 2.0 * 86_400.0).unwrap_err().contains("ends"));
/// ```
pub fn check_span(epoch: Epoch, duration: f64) -> Result<(), String> {
    let why = "the years the Sun's position is checked for (against ERFA's epv00 ephemeris)";
    let start = decimal_year(epoch, 0.0);
    if !(FIRST_YEAR..END_YEAR).contains(&start) {
        return Err(format!(
            "{epoch} (year {start:.3}) is outside {FIRST_YEAR:.0} to {END_YEAR:.0}, {why}"
        ));
    }
    let end = decimal_year(epoch, duration);
    if !(FIRST_YEAR..END_YEAR).contains(&end) {
        return Err(format!(
            "the run from {epoch} ends in year {end:.3}, after {END_YEAR:.0}: dates must stay within {FIRST_YEAR:.0} to {END_YEAR:.0}, {why}"
        ));
    }
    Ok(())
}

/// `epoch + t` seconds (SI seconds, the run's time), as a TAI epoch.
pub fn at(epoch: Epoch, t: f64) -> Epoch {
    // Added in TAI: hifitime adds to a UTC epoch in UTC's count, which skips leap seconds.
    epoch.to_time_scale(TimeScale::TAI) + Duration::from_seconds(t)
}

/// Seconds in a day.
const DAY: f64 = 86_400.0;
/// hifitime's TAI seconds (from 1900-01-01T00:00:00 TAI) at J2000.0, 2000-01-01T12:00:00 TT
/// = TAI + 32.184 s.
const J2000_TAI_SECONDS: f64 = 36_524.5 * DAY - 32.184;
/// hifitime's UTC seconds (86 400 a day, leap seconds left out, from 1900-01-01T00:00:00 UTC)
/// at J2000 noon UTC: 36 524.5 days.
const J2000_UTC_SECONDS: f64 = 36_524.5 * DAY;

// These run at every right-hand side of an ODE: each converts the epoch once (no calendar
// dates built per call, which cost hifitime ~0.3 µs each).

/// Julian centuries of TT from J2000.0 (2000-01-01T12:00:00 TT) to `epoch + t`: the time
/// argument of the Sun's series and of precession.
pub fn centuries_tt(epoch: Epoch, t: f64) -> f64 {
    // Elapsed SI seconds, counted in TAI (leap seconds included). Not `to_tt_since_j2k`:
    // from a UTC epoch hifitime 4.3 leaves out the leap seconds since J2000 there.
    (epoch.to_tai_seconds() - J2000_TAI_SECONDS + t) / (36_525.0 * DAY)
}

/// Days of UT1 (= UTC) from J2000.0 (2000-01-01T12:00:00 UT1) to `epoch + t`: the argument of
/// the Earth's rotation angle. UT1 is the epoch's UTC plus the `t` SI seconds elapsed: it runs
/// on through a leap second within a run, as UT1 does.
pub fn days_ut1(epoch: Epoch, t: f64) -> f64 {
    // UTC seconds (leap seconds left out, as UT1 leaves them out) from the UTC J2000 noon.
    (epoch.to_utc_seconds() - J2000_UTC_SECONDS + t) / DAY
}

/// The day (from 1900-01-01, UTC) on which `year` begins, in the Gregorian calendar.
fn new_year_day(year: i64) -> i64 {
    let leaps = |y: i64| y.div_euclid(4) - y.div_euclid(100) + y.div_euclid(400);
    365 * (year - 1900) + leaps(year - 1) - leaps(1899)
}

/// Decimal year of `epoch + t` (UTC, calendar): the year plus the fraction of it elapsed, the
/// argument of the geomagnetic model's coefficients (IGRF's models stand at 1900.0, 1905.0,
/// …: 1 January, 00:00). A leap second counts as the next day's first.
pub fn decimal_year(epoch: Epoch, t: f64) -> f64 {
    let days = (epoch.to_utc_seconds() + t) / DAY;
    if days.is_nan() || days.abs() >= 1e11 {
        // NaN, infinite or past any calendar: no year to find (and no overflow on the way).
        return 1900.0 + days / 365.2425;
    }
    let mut year = 1900 + (days / 365.2425).floor() as i64;
    while (new_year_day(year) as f64) > days {
        year -= 1;
    }
    while (new_year_day(year + 1) as f64) <= days {
        year += 1;
    }
    let (start, end) = (new_year_day(year) as f64, new_year_day(year + 1) as f64);
    year as f64 + (days - start) / (end - start)
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

    #[test]
    fn a_time_past_any_calendar_gives_no_panic() {
        let e = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
        assert!(decimal_year(e, f64::NAN).is_nan());
        assert_eq!(decimal_year(e, f64::INFINITY), f64::INFINITY);
        assert!(decimal_year(e, -1e300) < -1e290);
    }

    #[test]
    fn runs_outside_1900_to_2100_are_refused() {
        let e = |t: &str| parse_epoch(t).unwrap();
        assert!(check_span(e("1900-01-01T00:00:00 UTC"), 0.0).is_ok());
        assert!(check_span(e("2099-12-31T23:59:00 UTC"), 59.0).is_ok());
        for far in [
            "0001-01-01T00:00:00 UTC",
            "1899-12-31T23:59:59 UTC",
            "2100-01-01T00:00:00 UTC",
            "9999-01-01T00:00:00 UTC",
            "100000-01-01T00:00:00 UTC",
        ] {
            let m = check_span(e(far), 0.0).unwrap_err();
            assert!(m.contains("is outside 1900 to 2100"), "{far}: {m}");
        }
        let m = check_span(e("2099-12-31T23:59:00 UTC"), 61.0).unwrap_err();
        assert!(m.contains("ends in year 2100.000, after 2100"), "{m}");
        // Not finite: refused, no panic.
        assert!(check_span(e("2026-01-01T00:00:00 UTC"), f64::INFINITY).is_err());
    }

    #[test]
    fn at_counts_leap_seconds() {
        // 2016-12-31 had a leap second: 23:59:59 UTC plus 2 s is 00:00:00 UTC.
        let e = parse_epoch("2016-12-31T23:59:59 UTC").unwrap();
        let next = parse_epoch("2017-01-01T00:00:00 UTC").unwrap();
        assert_eq!((at(e, 2.0) - next).to_seconds(), 0.0);
    }

    #[test]
    fn one_instant_written_in_two_scales_has_one_time_argument() {
        // 2026-03-20T12:00:00 UTC is 12:01:09.184 TT (TAI − UTC = 37 s since 2017): the
        // leap seconds since J2000 (5) are elapsed time.
        let utc = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
        let tt = parse_epoch("2026-03-20T12:01:09.184 TT").unwrap();
        assert_eq!(centuries_tt(utc, 0.0), centuries_tt(tt, 0.0));
        // 9575 days of UTC from J2000 noon UTC, plus the 64.184 s J2000 TT is ahead of it
        // and the 5 leap seconds.
        let expected = (9575.0 * 86_400.0 + 64.184 + 5.0) / (36_525.0 * 86_400.0);
        assert!((centuries_tt(utc, 0.0) - expected).abs() < 1e-16);
        assert!((days_ut1(utc, 0.0) - 9575.0).abs() < 1e-12);
    }

    #[test]
    fn the_fast_time_arguments_agree_with_hifitimes_calendar() {
        // The arguments as hifitime's calendar gives them: the dates built, then subtracted.
        let j2000_tt = Epoch::from_gregorian_hms(2000, 1, 1, 12, 0, 0, TimeScale::TT);
        let j2000_utc = Epoch::from_gregorian_hms(2000, 1, 1, 12, 0, 0, TimeScale::UTC);
        for text in [
            "1900-01-01T00:00:00 UTC",
            "1951-07-04T03:17:00 UTC",
            "1972-06-30T23:50:00 UTC",
            "2000-02-29T12:00:00 TT",
            "2016-12-31T23:59:59 UTC",
            "2024-12-31T18:00:00 GPST",
            "2026-03-20T12:00:00 UTC",
            "2049-12-31T23:59:00 TAI",
        ] {
            let e = parse_epoch(text).unwrap();
            for t in [0.0, 1234.5, 40.0 * 86_400.0] {
                let later = at(e, t);
                // In TT: `utc_epoch - tt_epoch` would count UTC's seconds, leap seconds left out.
                let c = (later.to_time_scale(TimeScale::TT) - j2000_tt).to_seconds()
                    / (36_525.0 * 86_400.0);
                assert!(
                    (centuries_tt(e, t) - c).abs() < 1e-15,
                    "{text} {t}: {} vs {c}",
                    centuries_tt(e, t)
                );
                // UT1 runs on through a leap second, UTC's calendar does not: they part by
                // the leap seconds within the run.
                let leaps = |x: Epoch| x.to_tai_seconds() - x.to_utc_seconds();
                let leapt = (leaps(later) - leaps(e)) / 86_400.0;
                let d = (later.to_utc_seconds() - j2000_utc.to_utc_seconds()) / 86_400.0;
                let gap = days_ut1(e, t) - d;
                assert!((gap - leapt).abs() < 1e-10, "{text} {t}: {gap} days");
                let year = later.to_gregorian_utc().0;
                let start = Epoch::from_gregorian_utc_at_midnight(year, 1, 1);
                let end = Epoch::from_gregorian_utc_at_midnight(year + 1, 1, 1);
                let y = f64::from(year) + (later - start).to_seconds() / (end - start).to_seconds();
                // Within the leap seconds of that year (1 s in 3e7).
                assert!(
                    (decimal_year(e, t) - y).abs() < 1e-7,
                    "{text} {t}: {} vs {y}",
                    decimal_year(e, t)
                );
            }
        }
    }
}
