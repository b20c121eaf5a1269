//! Parsers of flag values (durations, image sizes, pass ranges) for clap's `value_parser`.
//!
//! Each returns a message that clap prints after "invalid value 'X' for '--flag'".

use std::time::Duration;

/// `90s`, `2m`, `1.5h`, `250ms` or a number of seconds; must be positive.
pub fn parse_duration(s: &str) -> Result<Duration, String> {
    let t = s.trim();
    let (number, unit) = match t.find(|c: char| c.is_ascii_alphabetic()) {
        Some(i) => t.split_at(i),
        None => (t, "s"),
    };
    let scale = match unit {
        "ms" => 1e-3,
        "s" => 1.0,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        _ => return Err(format!("`{s}` has an unknown unit `{unit}`; use ms, s, m or h (e.g. 90s)")),
    };
    let value: f64 = number.trim().parse().map_err(|_| format!("`{s}` is not a duration such as 90s or 2m"))?;
    let seconds = value * scale;
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(format!("`{s}` is not a positive duration; give e.g. 90s"));
    }
    Ok(Duration::from_secs_f64(seconds))
}

/// `A..B` with A < B: passes A, A+1, ..., B-1.
pub fn parse_pass_range(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}` is not a pass range A..B of whole numbers with A < B (e.g. 0..32)");
    let (a, b) = s.split_once("..").ok_or_else(bad)?;
    let (a, b): (u32, u32) = (a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?);
    if a >= b {
        return Err(bad());
    }
    Ok((a, b))
}

/// `WIDTHxHEIGHT` (or `X`), each from 1 to 65536.
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("`{s}` is not WIDTHxHEIGHT (e.g. 640x480)"))?;
    let parse = |v: &str| v.trim().parse::<u32>().ok().filter(|&n| n > 0 && n <= 65536);
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("`{s}` is not WIDTHxHEIGHT with sizes from 1 to 65536 (e.g. 640x480)")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_take_each_unit_and_default_to_seconds() {
        assert_eq!(parse_duration("90s"), Ok(Duration::from_secs(90)));
        assert_eq!(parse_duration("90"), Ok(Duration::from_secs(90)));
        assert_eq!(parse_duration(" 2m "), Ok(Duration::from_secs(120)));
        assert_eq!(parse_duration("2min"), Ok(Duration::from_secs(120)));
        assert_eq!(parse_duration("1.5h"), Ok(Duration::from_secs(5400)));
        assert_eq!(parse_duration("250ms"), Ok(Duration::from_millis(250)));
    }

    #[test]
    fn durations_refuse_unknown_units_and_non_positive_values() {
        assert!(parse_duration("5x").unwrap_err().contains("unknown unit `x`"));
        assert!(parse_duration("fast").unwrap_err().contains("unknown unit `fast`"));
        assert!(parse_duration("s").unwrap_err().contains("is not a duration"));
        for s in ["0s", "-1s", "inf", "NaN"] {
            assert!(parse_duration(s).is_err(), "{s} was accepted");
        }
    }

    #[test]
    fn pass_ranges_are_half_open_and_non_empty() {
        assert_eq!(parse_pass_range("0..32"), Ok((0, 32)));
        assert_eq!(parse_pass_range(" 4 .. 5 "), Ok((4, 5)));
        for s in ["3..3", "3..1", "0..", "..4", "0-4", "-1..4", "a..b"] {
            let e = parse_pass_range(s).unwrap_err();
            assert!(e.contains("is not a pass range A..B"), "{s}: {e}");
        }
    }

    #[test]
    fn resolutions_are_two_sizes_from_1_to_65536() {
        assert_eq!(parse_resolution("640x480"), Ok((640, 480)));
        assert_eq!(parse_resolution("1X65536"), Ok((1, 65536)));
        assert!(parse_resolution("640").unwrap_err().contains("is not WIDTHxHEIGHT (e.g. 640x480)"));
        for s in ["0x3", "3x0", "65537x1", "-1x4", "axb"] {
            let e = parse_resolution(s).unwrap_err();
            assert!(e.contains("with sizes from 1 to 65536"), "{s}: {e}");
        }
    }
}
