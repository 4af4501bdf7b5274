//! Values brought into machine words: clamps and saturations written so
//! that the common case (the value already in range) is one compare on a
//! 32-bit core.

/// A sample number as a ray keeps it: far outside any map, but in range of
/// every sum the caster forms with it.
#[inline]
pub(crate) fn narrow(v: i64) -> i32 {
    bound(v, 1 << 20) as i32
}

/// `v` clamped to `low..=high` (`low ≤ high`, `high − low` within
/// `i64`). `i64::clamp` is a call on the board (its bounds check stops it
/// inlining). Values within the range are the rule: one unsigned compare
/// of `v − low` finds them, as in [`bound`], where `max` and `min` compare
/// against both ends.
#[inline(always)]
pub(crate) fn clamp_in_place(v: i64, low: i64, high: i64) -> i64 {
    if (v.wrapping_sub(low) as u64) <= (high.wrapping_sub(low)) as u64 {
        v
    } else if v < low {
        low
    } else {
        high
    }
}

/// `v` clamped to `-limit..=limit` (`0 ≤ limit < 2^62`), in place. Values
/// within the limit are the rule: one unsigned compare of `v + limit`
/// finds them, where a clamp compares against both ends (on 32-bit cores
/// each a 64-bit compare).
#[inline(always)]
pub(crate) fn bound(v: i64, limit: i64) -> i64 {
    if (v.wrapping_add(limit) as u64) <= (2 * limit) as u64 {
        v
    } else if v < 0 {
        -limit
    } else {
        limit
    }
}

/// `v` saturated into `i32`. Values that fit are the rule: on 32-bit cores
/// testing for that compares one word, where a clamp compares two 64-bit
/// bounds.
#[inline]
pub(crate) fn saturate(v: i64) -> i32 {
    let low = v as i32;
    if i64::from(low) == v {
        low
    } else if v < 0 {
        i32::MIN
    } else {
        i32::MAX
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saturate_equals_a_clamp_to_i32() {
        let edges = [
            i64::from(i32::MAX),
            i64::from(i32::MIN),
            1 << 32,
            -(1 << 32),
        ];
        for v in
            edges
                .into_iter()
                .flat_map(|e| [e - 1, e, e + 1])
                .chain([0, -1, i64::MIN, i64::MAX])
        {
            let clamped = v.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
            assert_eq!(saturate(v), clamped, "{v}");
        }
    }

    #[test]
    fn bound_equals_a_clamp() {
        for limit in [0, 1, 1 << 14, 1 << 20, 1 << 29, (1 << 62) - 1] {
            let edges = [0, limit, -limit, 2 * limit, -2 * limit, i64::MIN, i64::MAX];
            for v in edges
                .into_iter()
                .flat_map(|e| [e.saturating_sub(1), e, e.saturating_add(1)])
            {
                assert_eq!(bound(v, limit), v.clamp(-limit, limit), "{v} {limit}");
            }
        }
    }

    #[test]
    fn clamp_in_place_equals_a_clamp() {
        // The ranges the caster clamps to (a reach, a minor coordinate),
        // an empty one and one across 0.
        for (low, high) in [(1, 1 << 40), (0, 0), (0, i64::from(i32::MAX)), (-5, 5)] {
            let edges = [0, low, high, i64::MIN, i64::MAX, -high];
            for v in edges
                .into_iter()
                .flat_map(|e| [e.saturating_sub(1), e, e.saturating_add(1)])
            {
                assert_eq!(
                    clamp_in_place(v, low, high),
                    v.clamp(low, high),
                    "{v} {low} {high}"
                );
            }
        }
    }
}
