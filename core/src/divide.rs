//! Integer division for the per-ray set-up, exact and cheap on 32-bit
//! cores.
//!
//! A Cortex-M divides 32 bits by 32 bits in hardware, but a 64-bit `/` is a
//! library call of well over a hundred instructions. The ray set-up divides
//! 64-bit fixed-point values whose quotients are small (a slope, a level
//! weight), so on 32-bit cores [`div_trunc`] takes the hardware path: one
//! divide when both operands fit 32 bits, and otherwise, when the quotient
//! does, two and a correction (Knuth's algorithm D with 16-bit
//! digits, as in Hacker's Delight §9-4 and §9-5).
//! The quotient is always the one `i64` division gives, so frames do not
//! depend on which path ran. 64-bit cores divide in hardware and use `/`.

/// `a / b`, truncated, as `i64` division does (`b ≠ 0`); through 32-bit
/// divides on 32-bit cores.
#[inline]
pub(crate) fn div_trunc(a: i64, b: i64) -> i64 {
    if cfg!(target_pointer_width = "64") {
        return a / b;
    }
    narrow_div_trunc(a, b)
}

/// [`div_trunc`] through 32-bit divides (any target: the tests run it on
/// the host). Operands that fit 32 bits take the one hardware divide
/// inline; wider ones call [`wide_div_trunc`].
#[inline]
fn narrow_div_trunc(a: i64, b: i64) -> i64 {
    if let (Ok(a), Ok(b)) = (i32::try_from(a), i32::try_from(b)) {
        if b != 0 && !(a == i32::MIN && b == -1) {
            return i64::from(a / b);
        }
    }
    wide_div_trunc(a, b)
}

/// [`narrow_div_trunc`] for operands past 32 bits. Not inlined: its body
/// inlined into every caller cost the board a few instructions a pixel
/// more than the call (board-check, 1947 against 1944 when measured).
#[inline(never)]
fn wide_div_trunc(a: i64, b: i64) -> i64 {
    let negative = (a < 0) != (b < 0);
    match quotient_below_2_32(a.unsigned_abs(), b.unsigned_abs()) {
        // q < 2^32, so neither sign overflows.
        Some(q) if negative => -i64::from(q),
        Some(q) => i64::from(q),
        None => a / b,
    }
}

/// `a / b` rounded down (`b ≠ 0`).
#[inline]
pub(crate) fn div_floor(a: i64, b: i64) -> i64 {
    let q = div_trunc(a, b);
    if q * b != a && ((a < 0) != (b < 0)) {
        q - 1
    } else {
        q
    }
}

/// `a / b` rounded up (`b ≠ 0`).
#[inline]
pub(crate) fn div_ceil(a: i64, b: i64) -> i64 {
    -div_floor(-a, b)
}

/// `⌊n / d⌋` when it is below 2^32 (`d ≠ 0`), from 32-bit divides only;
/// `None` when it is not. Written in 32-bit halves: a 64-bit shift is
/// several instructions on a 32-bit core.
#[inline]
fn quotient_below_2_32(n: u64, d: u64) -> Option<u32> {
    let (n_hi, n_lo) = ((n >> 32) as u32, n as u32);
    let (d_hi, d_lo) = ((d >> 32) as u32, d as u32);
    if d_hi == 0 {
        return (d_lo != 0 && n_hi < d_lo).then(|| divide_by_word(n_hi, n_lo, d_lo));
    }
    // Hacker's Delight §9-5: divide half of n by the top 32 bits of the
    // normalized divisor; the estimate, scaled back, is the quotient or one
    // more, which one multiply tells apart. d ≥ 2^32, so the quotient is
    // below 2^32, and half of n is below `top << 32` (top ≥ 2^31).
    let shift = d_hi.leading_zeros();
    let top = if shift == 0 {
        d_hi
    } else {
        (d_hi << shift) | (d_lo >> (32 - shift))
    };
    let estimate = divide_by_word(n_hi >> 1, (n_lo >> 1) | (n_hi << 31), top);
    // (estimate << shift) >> 31, in one word.
    let mut q = (estimate >> (31 - shift)).saturating_sub(1);
    if n - u64::from(q) * d >= d {
        q += 1;
    }
    Some(q)
}

/// `⌊(n_hi·2^32 + n_lo) / d⌋` for `n_hi < d` (so the quotient fits 32
/// bits): Hacker's Delight's `divlu`, two 32-by-16-bit digit divisions
/// after normalizing `d`, each estimate corrected by at most two, all in
/// 32-bit words.
#[inline]
fn divide_by_word(n_hi: u32, n_lo: u32, d: u32) -> u32 {
    const DIGIT: u32 = 1 << 16;
    if n_hi == 0 {
        return n_lo / d;
    }
    let shift = d.leading_zeros();
    let d = d << shift;
    let (d1, d0) = (d >> 16, d & 0xFFFF);
    // The dividend shifted with d; its top word stays below d.
    let upper = if shift == 0 {
        n_hi
    } else {
        (n_hi << shift) | (n_lo >> (32 - shift))
    };
    let lower = n_lo << shift;
    let (n1, n0) = (lower >> 16, lower & 0xFFFF);
    // One 16-bit digit of the quotient of `upper·2^16 + next` (d1 ≥ 2^15,
    // so the first estimate is below 2^17). Each product and sum below
    // fits a word: q < 2^16 once past the first test, and rest < 2^16
    // while the loop runs.
    let digit = |upper: u32, next: u32| {
        let mut q = upper / d1;
        let mut rest = upper - q * d1;
        while q >= DIGIT || q * d0 > (rest << 16) + next {
            q -= 1;
            rest += d1;
            if rest >= DIGIT {
                break;
            }
        }
        q
    };
    let q1 = digit(upper, n1);
    // The remainder so far, which fits a word (wrapping arithmetic on
    // purpose: the high bits cancel).
    let middle = (upper << 16)
        .wrapping_add(n1)
        .wrapping_sub(q1.wrapping_mul(d));
    let q0 = digit(middle, n0);
    (q1 << 16) | q0
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Values at the edges of every width the paths choose between.
    fn edges() -> std::vec::Vec<i64> {
        let mut values = std::vec![0, 1, -1, 7, -7, 65_535, 65_536, 65_537];
        for bits in [15, 16, 31, 32, 33, 40, 47, 48, 62] {
            let p = 1i64 << bits;
            values.extend([p - 1, p, p + 1, -p - 1, -p, -p + 1]);
        }
        values.extend([i64::MAX, i64::MIN, i64::MIN + 1]);
        values
    }

    #[test]
    fn narrow_division_equals_wide_division_at_every_edge() {
        for a in edges() {
            for b in edges().into_iter().filter(|&b| b != 0) {
                if a == i64::MIN && b == -1 {
                    continue;
                }
                assert_eq!(narrow_div_trunc(a, b), a / b, "{a} / {b}");
                assert_eq!(div_trunc(a, b), a / b, "{a} / {b}");
            }
        }
    }

    #[test]
    fn a_quotient_from_2_32_up_is_left_to_wide_division() {
        assert_eq!(quotient_below_2_32(1 << 32, 1), None);
        assert_eq!(quotient_below_2_32(u64::MAX, 0xFFFF_FFFF), None);
        assert_eq!(
            quotient_below_2_32(u64::MAX, 1 << 32),
            Some(u32::MAX),
            "the largest quotient of a divisor of 33 bits"
        );
        assert_eq!(quotient_below_2_32(5, 0), None);
    }

    /// Quotients whose 16-bit digits are at their edges, over divisors whose
    /// low half is large against their high half: where each digit's first
    /// estimate is too large and the correction loop must run.
    #[test]
    fn digit_estimates_that_need_correcting_are_corrected() {
        let divisors = [
            0x0000_8001u32,
            0x0001_FFFF,
            0x0002_FFFF,
            0x8000_FFFF,
            0x8000_8000,
            0xFFFF_FFFF,
            0x7FFF_FFFF,
            0x1234_FFFF,
            3,
        ];
        let digits = [0u64, 1, 0x7FFF, 0x8000, 0xFFFE, 0xFFFF];
        for d in divisors {
            for hi in digits {
                for lo in digits {
                    let q = (hi << 16) | lo;
                    for r in [0, 1, u64::from(d) / 2, u64::from(d) - 1] {
                        let n = q * u64::from(d) + r;
                        assert_eq!(
                            u64::from(divide_by_word((n >> 32) as u32, n as u32, d)),
                            q,
                            "{n} / {d}"
                        );
                        // The same digits over a divisor of 33 to 52 bits,
                        // where the quotient's product fits.
                        let wide = u64::from(d) << 20 | 0xF_FFFF;
                        if let Some(n) = q.checked_mul(wide).and_then(|p| p.checked_add(r)) {
                            assert_eq!(
                                quotient_below_2_32(n, wide),
                                Some(q as u32),
                                "{n} / {wide}"
                            );
                        }
                    }
                }
            }
        }
    }

    proptest! {
        /// The slope's shape: a Q16-shifted direction component over a
        /// run of up to 42 bits.
        #[test]
        fn per_ray_quotients_are_exact(n in -(1i64 << 58)..(1i64 << 58), d in 1i64..(1i64 << 42)) {
            prop_assert_eq!(narrow_div_trunc(n, d), n / d);
            prop_assert_eq!(narrow_div_trunc(n, -d), n / -d);
        }

        #[test]
        fn any_quotient_is_exact(n: i64, d: i64) {
            prop_assume!(d != 0 && !(n == i64::MIN && d == -1));
            prop_assert_eq!(narrow_div_trunc(n, d), n / d);
        }

        /// Remainders of 0 and d − 1 over divisors past 32 bits: where the
        /// scaled estimate is one short and the multiply must add it.
        #[test]
        fn wide_divisors_at_remainder_edges(q in 0u64..(1 << 23), d in (1u64 << 32)..(1 << 40), last: bool) {
            // With the bits below its top 32 cleared, the divisor is its own
            // estimate, which then comes out one short.
            let below_top = (64 - d.leading_zeros()).saturating_sub(32);
            for d in [d, d >> below_top << below_top] {
                let n = q * d + if last { d - 1 } else { 0 };
                prop_assert_eq!(quotient_below_2_32(n, d), Some(q as u32));
            }
        }

        #[test]
        fn word_divisors_are_exact(n: u64, d in 1u32..) {
            prop_assume!((n >> 32) < u64::from(d));
            prop_assert_eq!(u64::from(divide_by_word((n >> 32) as u32, n as u32, d)), n / u64::from(d));
        }

        #[test]
        fn floor_and_ceil_round_toward_the_infinities(a: i64, b: i64) {
            prop_assume!(b != 0 && a != i64::MIN && a != i64::MAX);
            let (q, r) = (a.div_euclid(b), a.rem_euclid(b));
            let floor = if r != 0 && b < 0 { q - 1 } else { q };
            prop_assert_eq!(div_floor(a, b), floor);
            prop_assert_eq!(div_ceil(a, b), -div_floor(-a, b));
        }
    }

    #[test]
    fn floor_and_ceil_division_round_toward_infinities() {
        assert_eq!(div_floor(7, 2), 3);
        assert_eq!(div_floor(-7, 2), -4);
        assert_eq!(div_floor(7, -2), -4);
        assert_eq!(div_ceil(7, 2), 4);
        assert_eq!(div_ceil(-7, 2), -3);
        assert_eq!(div_ceil(-8, -2), 4);
    }
}
