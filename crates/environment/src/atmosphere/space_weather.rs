//! The solar flux and geomagnetic activity NRLMSISE-00 reads, from CelesTrak's space-weather
//! CSV (`SW-All.csv`: one row a day, UTC, with a header naming the columns).
//!
//! The columns read, by their header names (the others are ignored, in any order):
//! `DATE` (`YYYY-MM-DD`), `F10.7_OBS` (the observed 10.7 cm flux, sfu, at the Earth's
//! distance from the Sun, as the model wants it), `F10.7_OBS_CENTER81` (its 81-day mean
//! centred on the day), `AP_AVG` (the daily Ap) and `AP1` … `AP8` (the 3-hour ap of
//! 00-03 h, …, 21-24 h UTC).
//!
//! At a time of day `d`, [`SpaceWeather::drivers`] gives what the model's storm-time mode
//! (its switch 9 = −1) takes:
//!
//! - `f107`: the F10.7 of the **previous** day, `d − 1`;
//! - `f107a`: the 81-day centred mean of day `d`;
//! - `ap[0]`: the daily Ap of day `d`; `ap[1]`: the 3-hour ap of the interval holding the
//!   time; `ap[2]`, `ap[3]`, `ap[4]`: those of 3, 6 and 9 hours before; `ap[5]`: the mean of
//!   the eight intervals from 12 to 33 hours before; `ap[6]`: the mean of the eight from 36 to
//!   57 hours before (intervals counted back across midnights: a time of day `d` reads the
//!   days `d − 3` to `d`).
//!
//! Rows are checked where they are read: a file whose later rows (CelesTrak's monthly
//! predictions) leave the 3-hour columns empty serves every day it does fill, and a day the
//! run needs that is absent or has a column that is not a number is an error naming the
//! file and the date or line ([`SpaceWeather::check_days`]).

use std::path::{Path, PathBuf};

/// Seconds in a day.
const DAY: f64 = 86_400.0;

/// The columns read from a day's row.
const COLUMNS: [&str; 11] = [
    "F10.7_OBS",
    "F10.7_OBS_CENTER81",
    "AP_AVG",
    "AP1",
    "AP2",
    "AP3",
    "AP4",
    "AP5",
    "AP6",
    "AP7",
    "AP8",
];

/// One day's row: its line in the file and the values of [`COLUMNS`], or why one is not a
/// number.
#[derive(Clone, Debug)]
struct Row {
    line: usize,
    values: Result<[f64; 11], String>,
}

/// A space-weather file's days, by their date.
#[derive(Clone, Debug)]
pub struct SpaceWeather {
    path: PathBuf,
    /// The day number (from 1900-01-01) of `days[0]`.
    first: i64,
    /// One entry a day from `first`; `None` where the file has no row for the date.
    days: Vec<Option<Row>>,
}

/// What NRLMSISE-00 reads of the space weather at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drivers {
    /// The previous day's observed F10.7 (sfu).
    pub f107: f64,
    /// The 81-day mean of the observed F10.7 centred on the day (sfu).
    pub f107a: f64,
    /// The Ap history, in the order the module's page gives.
    pub ap: [f64; 7],
}

/// The day number (from 1900-01-01, proleptic Gregorian) of `year-month-day`.
pub fn day_number(year: i64, month: i64, day: i64) -> i64 {
    // Howard Hinnant's days_from_civil, shifted from 1970-01-01 to 1900-01-01.
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (month + 9) % 12;
    let doy = (153 * mp + 2) / 5 + day - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468 + 25_567
}

/// The date `(year, month, day)` of day number `n` (from 1900-01-01).
pub fn date_of(n: i64) -> (i64, i64, i64) {
    // Hinnant's civil_from_days.
    let z = n - 25_567 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    (yoe + era * 400 + i64::from(month <= 2), month, day)
}

/// Day number `n` written `YYYY-MM-DD`.
pub fn date_text(n: i64) -> String {
    let (y, m, d) = date_of(n);
    format!("{y:04}-{m:02}-{d:02}")
}

/// `YYYY-MM-DD` as a day number, or `None`.
fn parse_date(s: &str) -> Option<i64> {
    let mut parts = s.trim().split('-');
    let y: i64 = parts.next()?.parse().ok()?;
    let m: i64 = parts.next()?.parse().ok()?;
    let d: i64 = parts.next()?.parse().ok()?;
    if parts.next().is_some() || !(1..=12).contains(&m) || d < 1 {
        return None;
    }
    let n = day_number(y, m, d);
    // A day past the month's end (2026-02-30) comes back as another date.
    (date_of(n) == (y, m, d)).then_some(n)
}

/// The day number and the UTC seconds into that day at UTC seconds `s` from 1900-01-01
/// (86 400 a day: a leap second counts as the next day's first).
pub fn day_and_seconds(s: f64) -> (i64, f64) {
    let day = (s / DAY).floor();
    (day as i64, s - day * DAY)
}

impl SpaceWeather {
    /// Reads the file at `path`; the error names the file (and the line, for a line that is
    /// not a row of the table).
    pub fn read(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            format!(
                "space-weather file {}: cannot be read ({e})",
                path.display()
            )
        })?;
        Self::parse(&text, path)
    }

    /// Reads `text`, the contents of the file at `path` (which errors name).
    pub fn parse(text: &str, path: &Path) -> Result<Self, String> {
        let at = |line: usize, m: String| format!("{}:{line}: {m}", path.display());
        let mut lines = text.lines().enumerate().map(|(k, l)| (k + 1, l));
        let (_, header) = lines
            .by_ref()
            .find(|(_, l)| !l.trim().is_empty())
            .ok_or_else(|| format!("space-weather file {}: empty", path.display()))?;
        let names: Vec<&str> = header.split(',').map(str::trim).collect();
        let column = |name: &str| {
            names.iter().position(|n| *n == name).ok_or_else(|| {
                format!(
                    "{}:1: no column `{name}` in the header (a CelesTrak space-weather CSV has DATE, F10.7_OBS, F10.7_OBS_CENTER81, AP_AVG, AP1 … AP8)",
                    path.display()
                )
            })
        };
        let date_col = column("DATE")?;
        let cols = COLUMNS
            .iter()
            .map(|c| column(c))
            .collect::<Result<Vec<_>, _>>()?;
        let mut rows: Vec<(i64, Row)> = Vec::new();
        for (line, l) in lines {
            if l.trim().is_empty() {
                continue;
            }
            let fields: Vec<&str> = l.split(',').map(str::trim).collect();
            let field = |k: usize| fields.get(k).copied().unwrap_or("");
            let date = parse_date(field(date_col)).ok_or_else(|| {
                at(
                    line,
                    format!("`DATE` is `{}`, not a date YYYY-MM-DD", field(date_col)),
                )
            })?;
            let values = (|| {
                let mut v = [0.0; 11];
                for (k, (&c, name)) in cols.iter().zip(COLUMNS).enumerate() {
                    let s = field(c);
                    v[k] = s
                        .parse::<f64>()
                        .ok()
                        .filter(|x| x.is_finite() && *x >= 0.0)
                        .ok_or_else(|| {
                            at(line, format!("column `{name}` is `{s}`, not a number >= 0"))
                        })?;
                }
                Ok(v)
            })();
            rows.push((date, Row { line, values }));
        }
        let first = rows.iter().map(|r| r.0).min().unwrap_or(0);
        let last = rows.iter().map(|r| r.0).max().unwrap_or(-1);
        let mut days: Vec<Option<Row>> = vec![None; (last - first + 1).max(0) as usize];
        for (date, row) in rows {
            let slot = &mut days[(date - first) as usize];
            if let Some(before) = slot {
                return Err(at(
                    row.line,
                    format!(
                        "a second row for {} (the first is at line {})",
                        date_text(date),
                        before.line
                    ),
                ));
            }
            *slot = Some(row);
        }
        Ok(Self {
            path: path.to_path_buf(),
            first,
            days,
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Day `n`'s values; the error names the file and the date, or the line.
    fn day(&self, n: i64) -> Result<&[f64; 11], String> {
        let row = usize::try_from(n - self.first)
            .ok()
            .and_then(|k| self.days.get(k))
            .and_then(Option::as_ref)
            .ok_or_else(|| {
                format!(
                    "space-weather file {}: no row for {}",
                    self.path.display(),
                    date_text(n)
                )
            })?;
        row.values.as_ref().map_err(Clone::clone)
    }

    /// Every day the drivers of days `first` to `last` read (from three days before `first`,
    /// for the Ap history) is in the file with numbers in its columns; else the error names
    /// the file and the first date missing, or the line of the first bad row.
    pub fn check_days(&self, first: i64, last: i64) -> Result<(), String> {
        for n in first - 3..=last {
            self.day(n)?;
        }
        Ok(())
    }

    /// The drivers at `s` UTC seconds from 1900-01-01 (see the module's page); the error
    /// names the file and the date missing.
    pub fn drivers(&self, s: f64) -> Result<Drivers, String> {
        let (d, sec) = day_and_seconds(s);
        let today = self.day(d)?;
        let f107 = self.day(d - 1)?[0];
        // The 3-hour interval counted from day 0's first: a leap second stays in the last.
        let now = d * 8 + ((sec / 10_800.0).floor() as i64).clamp(0, 7);
        let ap3 = |m: i64| -> Result<f64, String> {
            Ok(self.day(m.div_euclid(8))?[3 + m.rem_euclid(8) as usize])
        };
        let mean8 = |from: i64| -> Result<f64, String> {
            let mut sum = 0.0;
            for m in from - 7..=from {
                sum += ap3(m)?;
            }
            Ok(sum / 8.0)
        };
        Ok(Drivers {
            f107,
            f107a: today[1],
            ap: [
                today[2],
                ap3(now)?,
                ap3(now - 1)?,
                ap3(now - 2)?,
                ap3(now - 3)?,
                mean8(now - 4)?,
                mean8(now - 12)?,
            ],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn day_numbers_count_from_1900_and_round_trip_through_dates() {
        assert_eq!(day_number(1900, 1, 1), 0);
        assert_eq!(day_number(1900, 3, 1), 59, "1900 is not a leap year");
        assert_eq!(day_number(2000, 1, 1), 36_524);
        for n in [-1000, 0, 59, 36_524, 36_584, 46_000, 73_000] {
            let (y, m, d) = date_of(n);
            assert_eq!(day_number(y, m, d), n);
        }
        assert_eq!(date_text(day_number(2024, 2, 29)), "2024-02-29");
        assert_eq!(parse_date("2026-02-30"), None);
        assert_eq!(parse_date("2026-02-28"), Some(day_number(2026, 2, 28)));
        assert_eq!(parse_date("2026/02/28"), None);
    }
}
