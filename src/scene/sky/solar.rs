//! Where the sun is: the NOAA solar-position algorithm (after Meeus, "Astronomical Algorithms"),
//! good to about 0.01 degree between the years 1800 and 2100 and usable well beyond. Elevations are
//! geometric (no atmospheric refraction), azimuths clockwise from north.

/// A civil date and time at a UTC offset, as a scene file gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DateTime {
    pub year: i32,
    pub month: u32,
    pub day: u32,
    /// Hours, minutes and seconds of local time, seconds may have a fraction.
    pub hour: u32,
    pub minute: u32,
    pub second: f64,
    /// Hours east of UTC (Berlin in winter +1, New York -5), -14 to +14.
    pub utc_offset_hours: f64,
}

fn is_leap(year: i32) -> bool {
    (year % 4 == 0 && year % 100 != 0) || year % 400 == 0
}

fn days_in_month(year: i32, month: u32) -> u32 {
    match month {
        1 | 3 | 5 | 7 | 8 | 10 | 12 => 31,
        4 | 6 | 9 | 11 => 30,
        2 if is_leap(year) => 29,
        _ => 28,
    }
}

/// `YYYY-MM-DD`, a real day of the proleptic Gregorian calendar (years 1 to 9999).
pub fn parse_date(text: &str) -> Result<(i32, u32, u32), String> {
    let parts: Vec<&str> = text.split('-').collect();
    let number = |s: &str| s.parse::<u32>().ok().filter(|_| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()));
    let (Some(y), Some(m), Some(d)) = (
        parts.first().and_then(|s| number(s)),
        parts.get(1).and_then(|s| number(s)),
        parts.get(2).and_then(|s| number(s)),
    ) else {
        return Err(format!("\"{text}\" is not a date; write it as YYYY-MM-DD, e.g. \"2026-06-21\""));
    };
    if parts.len() != 3 || !(1..=9999).contains(&y) {
        return Err(format!("\"{text}\" is not a date; write it as YYYY-MM-DD with a year from 1 to 9999"));
    }
    let year = y as i32;
    if !(1..=12).contains(&m) {
        return Err(format!("\"{text}\" has month {m}; months run from 1 to 12"));
    }
    if !(1..=days_in_month(year, m)).contains(&d) {
        return Err(format!("\"{text}\" has day {d}, but that month has {} days", days_in_month(year, m)));
    }
    Ok((year, m, d))
}

/// `HH:MM` or `HH:MM:SS` (seconds may have a fraction), 00:00 to 23:59:59.
pub fn parse_time(text: &str) -> Result<(u32, u32, f64), String> {
    let bad = || format!("\"{text}\" is not a time of day; write it as HH:MM or HH:MM:SS, e.g. \"14:30\"");
    let parts: Vec<&str> = text.split(':').collect();
    if !(2..=3).contains(&parts.len()) {
        return Err(bad());
    }
    let whole = |s: &str| s.parse::<u32>().ok().filter(|_| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()));
    let (Some(h), Some(m)) = (whole(parts[0]), whole(parts[1])) else {
        return Err(bad());
    };
    let s = match parts.get(2) {
        Some(s) => s
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && s.bytes().all(|b| b.is_ascii_digit() || b == b'.'))
            .ok_or_else(bad)?,
        None => 0.0,
    };
    if h > 23 || m > 59 || s >= 60.0 {
        return Err(format!("\"{text}\" is past the end of a day; hours run 0-23, minutes and seconds 0-59"));
    }
    Ok((h, m, s))
}

/// Julian day (days since noon UTC, 1 January 4713 BC) of `t`.
pub fn julian_day(t: &DateTime) -> f64 {
    let (mut y, mut m) = (t.year as i64, t.month as i64);
    if m <= 2 {
        y -= 1;
        m += 12;
    }
    let a = y.div_euclid(100);
    let b = 2 - a + a.div_euclid(4);
    let day_fraction = (t.hour as f64 + t.minute as f64 / 60.0 + t.second / 3600.0 - t.utc_offset_hours) / 24.0;
    (365.25 * (y + 4716) as f64).floor() + (30.6001 * (m + 1) as f64).floor() + t.day as f64 + b as f64 - 1524.5
        + day_fraction
}

/// The sun seen from a place: degrees.
#[derive(Clone, Copy, Debug)]
pub struct SunPosition {
    /// Above the horizon (geometric, no refraction), -90 to 90.
    pub elevation: f64,
    /// Clockwise from north, 0 to 360.
    pub azimuth: f64,
    /// Declination and apparent ecliptic longitude, for checks against an almanac.
    pub declination: f64,
    pub ecliptic_longitude: f64,
}

/// The sun's position at `t` seen from `latitude` (north positive) and `longitude` (east
/// positive), degrees.
pub fn sun_position(t: &DateTime, latitude: f64, longitude: f64) -> SunPosition {
    let jd = julian_day(t);
    let c = (jd - 2451545.0) / 36525.0; // Julian centuries since J2000.0
    let rad = f64::to_radians;
    let geom_mean_long = (280.46646 + c * (36000.76983 + c * 0.0003032)).rem_euclid(360.0);
    let geom_mean_anom = 357.52911 + c * (35999.05029 - 0.0001537 * c);
    let eccent = 0.016708634 - c * (0.000042037 + 0.0000001267 * c);
    let m = rad(geom_mean_anom);
    let centre = m.sin() * (1.914602 - c * (0.004817 + 0.000014 * c))
        + (2.0 * m).sin() * (0.019993 - 0.000101 * c)
        + (3.0 * m).sin() * 0.000289;
    let true_long = geom_mean_long + centre;
    let omega = rad(125.04 - 1934.136 * c);
    let apparent_long = true_long - 0.00569 - 0.00478 * omega.sin();
    let mean_obliq = 23.0 + (26.0 + (21.448 - c * (46.815 + c * (0.00059 - c * 0.001813))) / 60.0) / 60.0;
    let obliq = rad(mean_obliq + 0.00256 * omega.cos());
    let declination = (obliq.sin() * rad(apparent_long).sin()).asin();
    let y = (obliq / 2.0).tan().powi(2);
    let l0 = rad(geom_mean_long);
    let eq_of_time_min = 4.0
        * (y * (2.0 * l0).sin() - 2.0 * eccent * m.sin() + 4.0 * eccent * y * m.sin() * (2.0 * l0).cos()
            - 0.5 * y * y * (4.0 * l0).sin()
            - 1.25 * eccent * eccent * (2.0 * m).sin())
        .to_degrees();
    let utc_minutes = (t.hour as f64 - t.utc_offset_hours) * 60.0 + t.minute as f64 + t.second / 60.0;
    let true_solar_min = (utc_minutes + eq_of_time_min + 4.0 * longitude).rem_euclid(1440.0);
    let hour_angle = rad(true_solar_min / 4.0 - 180.0);
    let lat = rad(latitude);
    let cos_zenith =
        (lat.sin() * declination.sin() + lat.cos() * declination.cos() * hour_angle.cos()).clamp(-1.0, 1.0);
    let zenith = cos_zenith.acos();
    // Azimuth clockwise from north: atan2 of the east and north components.
    let east = -declination.cos() * hour_angle.sin();
    let north = declination.sin() * lat.cos() - declination.cos() * lat.sin() * hour_angle.cos();
    SunPosition {
        elevation: 90.0 - zenith.to_degrees(),
        azimuth: east.atan2(north).to_degrees().rem_euclid(360.0),
        declination: declination.to_degrees(),
        ecliptic_longitude: apparent_long.rem_euclid(360.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(date: &str, time: &str, utc_offset_hours: f64) -> DateTime {
        let (year, month, day) = parse_date(date).unwrap();
        let (hour, minute, second) = parse_time(time).unwrap();
        DateTime { year, month, day, hour, minute, second, utc_offset_hours }
    }

    #[test]
    fn reda_and_andreas_example() {
        // The worked example of NREL's Solar Position Algorithm (Reda & Andreas 2004, table A4.1):
        // 17 October 2003, 12:30:30 at UTC-7, 39.742476 N 105.1786 W: topocentric zenith
        // 50.11162 degrees (with 0.0163 of refraction at 820 mbar, 11 C) and azimuth 194.34024.
        let p = sun_position(&at("2003-10-17", "12:30:30", -7.0), 39.742476, -105.1786);
        let zenith = 90.0 - p.elevation;
        assert!((zenith - (50.11162 + 0.0163)).abs() < 0.02, "zenith {zenith}");
        assert!((p.azimuth - 194.34024).abs() < 0.02, "azimuth {}", p.azimuth);
    }

    #[test]
    fn equinoxes_and_solstices_of_2024() {
        // USNO/IMCCE times: March equinox 20 Mar 03:06 UTC, June solstice 20 Jun 20:51,
        // September equinox 22 Sep 12:44, December solstice 21 Dec 09:21; obliquity 23.436.
        for (date, time, longitude, declination) in [
            ("2024-03-20", "03:06", 0.0, 0.0),
            ("2024-06-20", "20:51", 90.0, 23.436),
            ("2024-09-22", "12:44", 180.0, 0.0),
            ("2024-12-21", "09:21", 270.0, -23.436),
        ] {
            let p = sun_position(&at(date, time, 0.0), 0.0, 0.0);
            let dl = (p.ecliptic_longitude - longitude + 180.0).rem_euclid(360.0) - 180.0;
            assert!(dl.abs() < 0.01, "{date}: ecliptic longitude {}", p.ecliptic_longitude);
            assert!((p.declination - declination).abs() < 0.01, "{date}: declination {}", p.declination);
        }
    }

    #[test]
    fn noon_and_local_time() {
        // At Greenwich on the June solstice the sun culminates due south at 90 - 51.48 + 23.44
        // degrees, a couple of minutes after 12:00 UTC (equation of time -1.8 min).
        let p = sun_position(&at("2024-06-20", "13:01:45", 1.0), 51.4779, 0.0);
        assert!((p.elevation - (90.0 - 51.4779 + 23.436)).abs() < 0.02, "elevation {}", p.elevation);
        assert!((p.azimuth - 180.0).abs() < 0.2, "azimuth {}", p.azimuth);
        // The same instant written in another time zone is the same sun.
        let q = sun_position(&at("2024-06-20", "07:01:45", -5.0), 51.4779, 0.0);
        assert!((p.elevation - q.elevation).abs() < 1e-9 && (p.azimuth - q.azimuth).abs() < 1e-9);
        // Morning sun is in the east, evening sun in the west.
        assert!((45.0..135.0).contains(&sun_position(&at("2024-06-20", "06:00", 1.0), 51.4779, 0.0).azimuth));
        assert!((225.0..315.0).contains(&sun_position(&at("2024-06-20", "19:00", 1.0), 51.4779, 0.0).azimuth));
    }

    #[test]
    fn impossible_dates_and_times_are_refused() {
        assert!(parse_date("2023-02-29").unwrap_err().contains("28 days"));
        assert!(parse_date("2024-02-29").is_ok());
        assert!(parse_date("2024-13-01").unwrap_err().contains("month 13"));
        assert!(parse_date("2024-04-31").unwrap_err().contains("30 days"));
        assert!(parse_date("21/06/2024").is_err());
        assert!(parse_date("2024-6").is_err());
        assert!(parse_date("0-01-01").is_err());
        assert!(parse_time("24:00").unwrap_err().contains("past the end"));
        assert!(parse_time("12:60").is_err());
        assert!(parse_time("noon").is_err());
        assert!(parse_time("-1:30").is_err());
        assert_eq!(parse_time("07:05:30.5"), Ok((7, 5, 30.5)));
    }
}
