//! The one place a flag's value is checked: every numeric flag of every
//! command parses through [`number`] (or a parser built on it) with its
//! range, so a bad value is refused before any work, by clap, with the
//! flag and the value named and the same exit code everywhere.
//!
//! Numeric flags also take `allow_hyphen_values`, so that `-30` and `-inf`
//! reach the parser as values (and are refused there with the range) rather
//! than being read as flags.

use std::fmt::Display;
use std::str::FromStr;
use terracast::config::{HFOV_RANGE_DEG, MAX_IMAGE_SIDE, PITCH_RANGE_DEG, ROLL_RANGE_DEG};
use terracast::Rgb;

/// A parser for a number from `low` to `high` inclusive: NaN, infinities,
/// and values that overflow the type (`1e308` as an `f32`) are outside
/// every range.
pub(crate) fn number<T>(
    low: T,
    high: T,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
{
    // NaN fails both comparisons.
    ranged(
        move |v: &T| *v >= low && *v <= high,
        format!("must be a number from {low} to {high}"),
    )
}

/// Like [`number`], for a value that must be above `low` (a rate, a
/// scale) and at most `high`.
pub(crate) fn positive<T>(
    low_exclusive: T,
    high: T,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
{
    ranged(
        move |v: &T| *v > low_exclusive && *v <= high,
        format!("must be a number above {low_exclusive} and at most {high}"),
    )
}

/// A parser that takes the values `within` accepts, and otherwise says
/// `range`.
fn ranged<T: FromStr>(
    within: impl Fn(&T) -> bool + Clone + Send + Sync + 'static,
    range: String,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static {
    move |text: &str| match text.trim().parse::<T>() {
        Ok(value) if within(&value) => Ok(value),
        // Parsed but outside `within`: dropped, the message says why.
        _ => Err(range.clone()),
    }
}

/// `--hfov`: the kernel's field-of-view range.
pub(crate) fn hfov(text: &str) -> Result<f32, String> {
    number(HFOV_RANGE_DEG.0, HFOV_RANGE_DEG.1)(text)
}

/// `--pitch`: the kernel's pitch range.
pub(crate) fn pitch(text: &str) -> Result<f32, String> {
    number(PITCH_RANGE_DEG.0, PITCH_RANGE_DEG.1)(text)
}

/// `--yaw`: an angle in degrees, one turn either way.
pub(crate) fn angle(text: &str) -> Result<f32, String> {
    number(-360.0, 360.0)(text)
}

/// `--roll`: a bank in degrees, half a turn either way.
pub(crate) fn roll(text: &str) -> Result<f32, String> {
    number(ROLL_RANGE_DEG.0, ROLL_RANGE_DEG.1)(text)
}

/// `--seed`: any 64-bit value.
pub(crate) fn seed(text: &str) -> Result<u64, String> {
    number(0, u64::MAX)(text)
}

/// Largest eye coordinate a flag takes; the kernel's own limit (smaller, and
/// relative to the window on tiled terrain) is checked with the view.
const MAX_EYE_FLAG: f32 = 1.0e7;

/// `--eye X,Y,Z`: three finite numbers.
pub(crate) fn triple(text: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("expected X,Y,Z, got '{text}'"));
    }
    let mut out = [0.0; 3];
    for (o, p) in out.iter_mut().zip(parts) {
        *o = number(-MAX_EYE_FLAG, MAX_EYE_FLAG)(p).map_err(|e| format!("'{}' {e}", p.trim()))?;
    }
    Ok(out)
}

/// `--size WxH`: 1 to the kernel's largest image side each way.
pub(crate) fn size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got '{text}'"))?;
    let side = number(1, MAX_IMAGE_SIDE);
    let w = side(w).map_err(|e| format!("width '{}' {e}", w.trim()))?;
    let h = side(h).map_err(|e| format!("height '{}' {e}", h.trim()))?;
    Ok((w, h))
}

/// `--sky R,G,B`: three values 0 to 255.
pub(crate) fn rgb(text: &str) -> Result<Rgb, String> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("expected R,G,B, got '{text}'"));
    }
    let mut out = [0u8; 3];
    for (o, p) in out.iter_mut().zip(parts) {
        *o = number(0, 255)(p).map_err(|e| format!("'{}' {e}", p.trim()))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_outside_their_range_are_refused_with_the_range() {
        let fov = |t: &str| hfov(t);
        for bad in ["nan", "NaN", "inf", "-inf", "1e308", "-1", "0", "179", "x"] {
            let message = fov(bad).unwrap_err();
            assert!(message.contains("from 1 to 160"), "{bad}: {message}");
        }
        assert_eq!(fov("60"), Ok(60.0));
        assert_eq!(number(1u32, 10)("10"), Ok(10));
        assert!(number(1u32, 10)("-1").is_err());
        assert!(positive(0.0f64, 10.0)("0").is_err());
        assert_eq!(positive(0.0f64, 10.0)("0.5"), Ok(0.5));
        assert_eq!(seed("18446744073709551615"), Ok(u64::MAX));
    }

    #[test]
    fn lists_check_every_part() {
        assert_eq!(triple("1, -2.5,3"), Ok([1.0, -2.5, 3.0]));
        assert!(triple("1,nan,3").unwrap_err().contains("'nan'"));
        assert!(triple("1,2").is_err());
        assert_eq!(size("640x360"), Ok((640, 360)));
        assert!(size("0x360").unwrap_err().contains("width '0'"));
        assert!(size("640x9000").is_err());
        assert_eq!(rgb("1,2,255"), Ok([1, 2, 255]));
        assert!(rgb("1,2,256").is_err());
    }
}
