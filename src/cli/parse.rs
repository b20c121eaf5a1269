//! Parsers of flag values (durations, image sizes, pass ranges) for clap's `value_parser`.
//!
//! Each returns a message that clap prints after "invalid value 'X' for '--flag'".

use std::time::Duration;

use photonix::limits::{
    fmt_number, printable, MAX_DEPTH, MAX_DURATION_SECONDS, MAX_EXPOSURE, MAX_GATHER_RAYS, MAX_IMAGE_SIDE, MAX_PASSES,
    MAX_PHOTON_PATHS, MAX_PIXELS, MAX_SCENE_VALUE, MAX_SPP, MAX_TARGET_ERROR, MIN_DURATION_SECONDS,
};

/// `90s`, `2m`, `1.5h`, `250ms`, `1e3s` or a number of seconds, from 1 ms to 365 days.
pub fn parse_duration(s: &str) -> Result<Duration, String> {
    let t = s.trim();
    // The unit is the trailing letters; an exponent (`1e3s`) is part of the number.
    let split = t.trim_end_matches(|c: char| c.is_ascii_alphabetic()).len();
    let (number, unit) = t.split_at(split);
    let (number, unit) = match (number.is_empty(), unit) {
        // `1e3` with no unit: the `e3` belongs to the number.
        (false, u) if u.starts_with('e') && !u.contains(|c: char| c != 'e') => (t, "s"),
        (_, "") => (t, "s"),
        (_, u) => (number, u),
    };
    let shown = printable(s);
    let scale = match unit {
        "ms" => 1e-3,
        "s" => 1.0,
        "m" | "min" => 60.0,
        "h" => 3600.0,
        _ => {
            let unit = printable(unit);
            return Err(format!("`{shown}` has an unknown unit `{unit}`; use ms, s, m or h (e.g. 90s)"));
        }
    };
    let value: f64 = number.trim().parse().map_err(|_| format!("`{shown}` is not a duration such as 90s or 2m"))?;
    let seconds = value * scale;
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(format!("`{shown}` is not a positive duration; give e.g. 90s"));
    }
    if !(MIN_DURATION_SECONDS..=MAX_DURATION_SECONDS).contains(&seconds) {
        return Err(format!(
            "`{shown}` is {} s; give a duration from 1ms to 365 days ({}h)",
            fmt_number(seconds),
            MAX_DURATION_SECONDS / 3600.0
        ));
    }
    Ok(Duration::from_secs_f64(seconds))
}

/// `A..B` with A < B <= `MAX_PASSES`: passes A, A+1, ..., B-1.
pub fn parse_pass_range(s: &str) -> Result<(u32, u32), String> {
    let bad = || {
        format!("`{}` is not a pass range A..B of whole numbers with A < B <= {MAX_PASSES} (e.g. 0..32)", printable(s))
    };
    let (a, b) = s.split_once("..").ok_or_else(bad)?;
    let (a, b): (u32, u32) = (a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?);
    if a >= b || b > MAX_PASSES {
        return Err(bad());
    }
    Ok((a, b))
}

/// `WIDTHxHEIGHT` (or `X`), each from 1 to `MAX_IMAGE_SIDE`, at most `MAX_PIXELS` in all.
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let shown = printable(s);
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("`{shown}` is not WIDTHxHEIGHT (e.g. 640x480)"))?;
    let parse = |v: &str| v.trim().parse::<u32>().ok().filter(|&n| n > 0 && n <= MAX_IMAGE_SIDE);
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) if w as u64 * h as u64 <= MAX_PIXELS => Ok((w, h)),
        (Some(_), Some(_)) => Err(format!("`{shown}` has more than {MAX_PIXELS} pixels (16384x16384); render less")),
        _ => Err(format!("`{shown}` is not WIDTHxHEIGHT with sizes from 1 to {MAX_IMAGE_SIDE} (e.g. 640x480)")),
    }
}

/// A whole number in `min..=max`; `what` names it in the message ("samples per pixel").
pub fn parse_whole(s: &str, min: u32, max: u32, what: &str) -> Result<u32, String> {
    let t = s.trim();
    let digits = t.strip_prefix(['-', '+']).unwrap_or(t);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("`{}` is not a whole number; give {what} from {min} to {max}", printable(s)));
    }
    // Beyond i128 is out of range as surely as beyond `max`.
    let value = t.parse::<i128>().ok().filter(|v| (min as i128..=max as i128).contains(v));
    value
        .map(|v| v as u32)
        .ok_or_else(|| format!("`{}` is out of range; give {what} from {min} to {max}", printable(s)))
}

/// A finite number in `min..=max` (`min` excluded when `open_min`); `what` names it.
fn parse_real(s: &str, min: f64, open_min: bool, max: f64, what: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("`{}` is not a number; give {what}", printable(s)))?;
    let above_min = if open_min { v > min } else { v >= min };
    if !(v.is_finite() && above_min && v <= max) {
        let low = if open_min { "above" } else { "from" };
        return Err(format!(
            "`{}` is out of range; give {what}, {low} {} to {}",
            printable(s),
            fmt_number(min),
            fmt_number(max)
        ));
    }
    Ok(v)
}

pub fn parse_spp(s: &str) -> Result<u32, String> {
    parse_whole(s, 1, MAX_SPP, "samples per pixel")
}

pub fn parse_passes(s: &str) -> Result<u32, String> {
    parse_whole(s, 1, MAX_PASSES, "a pass count")
}

pub fn parse_seed(s: &str) -> Result<u32, String> {
    parse_whole(s, 0, u32::MAX, "a seed")
}

pub fn parse_depth(s: &str) -> Result<u32, String> {
    parse_whole(s, 1, MAX_DEPTH, "a path depth")
}

pub fn parse_photons(s: &str) -> Result<u32, String> {
    parse_whole(s, 1, MAX_PHOTON_PATHS, "photon paths (or --no-photons)")
}

pub fn parse_gather_rays(s: &str) -> Result<u32, String> {
    parse_whole(s, 0, MAX_GATHER_RAYS, "final-gather rays")
}

/// Stops: 2^EXPOSURE scales the radiance.
pub fn parse_exposure(s: &str) -> Result<f32, String> {
    let e = MAX_EXPOSURE as f64;
    parse_real(s, -e, false, e, "an exposure in stops").map(|v| v as f32)
}

/// A lookup radius in scene units.
pub fn parse_radius(s: &str) -> Result<f32, String> {
    let r = parse_real(s, 0.0, true, MAX_SCENE_VALUE, "a positive radius in scene units")?;
    // Positive in f64 but zero in f32 (1e-50) is as bad as zero.
    if (r as f32) <= 0.0 {
        return Err(format!("`{}` is too small; give a positive radius in scene units", printable(s)));
    }
    Ok(r as f32)
}

/// A relMSE to stop at.
pub fn parse_target_error(s: &str) -> Result<f64, String> {
    parse_real(s, 0.0, true, MAX_TARGET_ERROR, "a relMSE such as 0.01")
}

/// `--integrator`: one of [`Integrator::NAMES`], or `auto` (None: the one
/// `Scene::set_integrator` lets `auto_integrator` pick).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntegratorArg(pub Option<photonix::scene::Integrator>);

pub fn parse_integrator(s: &str) -> Result<IntegratorArg, String> {
    if s == photonix::scene::Integrator::AUTO {
        return Ok(IntegratorArg(None));
    }
    photonix::scene::Integrator::from_name(s).map(|i| IntegratorArg(Some(i))).ok_or_else(|| {
        let names: Vec<&str> = photonix::scene::Integrator::NAMES.iter().map(|(n, _)| *n).collect();
        format!("unknown integrator `{s}`; use one of {}, auto", names.join(", "))
    })
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
    fn durations_read_exponents_and_stay_in_range() {
        assert_eq!(parse_duration("1e3s"), Ok(Duration::from_secs(1000)));
        assert_eq!(parse_duration("1e3"), Ok(Duration::from_secs(1000)));
        assert_eq!(parse_duration("2.5e-1m"), Ok(Duration::from_secs(15)));
        // Too large for a Duration, or merely absurd: refused with the range, never a panic.
        for s in ["1e30s", "1e30", "1e300h", "100000000000000000000000h", "366d", "9000h", "0.1ms"] {
            let e = parse_duration(s).unwrap_err();
            assert!(e.contains("from 1ms to 365 days") || e.contains("unknown unit"), "{s}: {e}");
        }
    }

    #[test]
    fn pass_ranges_are_half_open_and_non_empty() {
        assert_eq!(parse_pass_range("0..32"), Ok((0, 32)));
        assert_eq!(parse_pass_range(" 4 .. 5 "), Ok((4, 5)));
        for s in ["3..3", "3..1", "0..", "..4", "0-4", "-1..4", "a..b", "0..1000001", "0..4294967295"] {
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
        assert!(parse_resolution("65536x65536").unwrap_err().contains("more than 268435456 pixels"));
        assert_eq!(parse_resolution("16384x16384"), Ok((16384, 16384)));
    }

    #[test]
    fn whole_numbers_name_their_range() {
        assert_eq!(parse_spp("16"), Ok(16));
        assert_eq!(parse_seed("4294967295"), Ok(u32::MAX));
        for (s, piece) in [
            ("0", "out of range; give samples per pixel from 1 to 4096"),
            ("4097", "out of range"),
            ("-1", "out of range"),
            ("99999999999999999999999999999999999999999", "out of range"),
            ("1e3", "not a whole number"),
            ("", "not a whole number"),
        ] {
            let e = parse_spp(s).unwrap_err();
            assert!(e.contains(piece), "{s}: {e}");
        }
        assert!(parse_seed("4294967296").unwrap_err().contains("from 0 to 4294967295"));
        assert!(parse_photons("1000000001").unwrap_err().contains("from 1 to 1000000000"));
    }

    #[test]
    fn real_numbers_refuse_nan_infinity_and_extremes() {
        assert_eq!(parse_exposure("-2.5"), Ok(-2.5));
        for s in ["nan", "NaN", "inf", "-inf", "65", "1e30"] {
            let e = parse_exposure(s).unwrap_err();
            assert!(e.contains("from -64 to 64"), "{s}: {e}");
        }
        assert_eq!(parse_radius("0.5"), Ok(0.5));
        for s in ["0", "-1", "nan", "inf", "1e10", "1e-50"] {
            assert!(parse_radius(s).is_err(), "{s}");
        }
        assert!(parse_target_error("0").is_err());
        assert!(parse_target_error("1e300").unwrap_err().contains("1000"));
    }
}
