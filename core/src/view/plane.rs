//! A line's vertical plane and a ray's slope in it: what every ray of an
//! image line shares (the plane's grid lines, its start and minor
//! increment), and the one division a ray adds (its slope, from its
//! direction's words).

use super::ray::RayKey;
use super::words::{bound, saturate};
use super::View;
use crate::config::{COORD_FRAC_BITS, MAX_RAY_SLOPE};
use crate::divide::{div_ceil, div_floor, div_trunc};
use crate::surface::Extent;

const ONE: i64 = 1 << COORD_FRAC_BITS;

/// What every ray of an image line shares: its vertical plane. The
/// horizontal direction (which grid lines the rays cross, their minor
/// slope) and so where their samples lie and which of them are in the map.
/// Sharing it bit for bit puts the rays of a line in one plane, sample for
/// sample, and leaves a ray only its slope to set up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Plane {
    pub key: RayKey,
    /// Minor-axis increment per major-axis step, Q16 (within ±1).
    pub dminor: i64,
    /// Major-axis grid coordinate of sample 0, the distance to it, and the
    /// minor coordinate there (see [`Ray`](super::ray::Ray)).
    pub major0: i64,
    pub delta0: i64,
    pub minor0: i64,
    /// Samples inside the map: `first..=last` (`first` may be −1).
    pub first: i64,
    pub last: i64,
    /// Largest minor coordinate whose neighbour across the grid line is in
    /// the map, Q16.
    pub minor_max: i64,
    /// `across_minor − dminor·across_major` (see [`Plane::with_across`]);
    /// 0 until set.
    across: i64,
}

impl Plane {
    /// The plane of direction `d` (I32F32 bits) from `view`'s eye over
    /// a map of `extent`.
    pub fn new(view: &View, extent: &Extent, d: &[i64; 3]) -> Self {
        let x_major = d[0].abs() >= d[1].abs();
        let (d_major, d_minor) = if x_major { (d[0], d[1]) } else { (d[1], d[0]) };
        let forward = d_major >= 0;
        let run = d_major.abs();
        // Directions are I32F32 below 2^10 in magnitude (a line's far-edge
        // point lies within a few image sizes), so `<< 16` cannot overflow;
        // |d_minor| <= run keeps the minor slope within ±1.
        let dminor = if run == 0 {
            0
        } else {
            div_trunc(d_minor << COORD_FRAC_BITS, run)
        };

        let [ex, ey, _] = view.eye.map(|v| v.to_bits());
        let (e_major, e_minor) = if x_major { (ex, ey) } else { (ey, ex) };
        let (major0, delta0) = if forward {
            let m = (e_major + ONE - 1) >> COORD_FRAC_BITS;
            (m, (m << COORD_FRAC_BITS) - e_major)
        } else {
            let m = e_major >> COORD_FRAC_BITS;
            (m, e_major - (m << COORD_FRAC_BITS))
        };
        let minor0 = e_minor + ((delta0 * dminor) >> COORD_FRAC_BITS);

        let (major_len, minor_len) = if x_major {
            (extent.width, extent.depth)
        } else {
            (extent.depth, extent.width)
        };
        // Samples inside the map: 0 <= major <= len-1 and 0 <= minor < len-1,
        // so that the neighbour across the minor grid line exists too.
        let (mut first, mut last) = (-1i64, i64::MAX);
        let major_last = i64::from(major_len) - 1;
        let (lo, hi) = if forward {
            (-major0, major_last - major0)
        } else {
            (major0 - major_last, major0)
        };
        first = first.max(lo);
        last = last.min(hi);
        let minor_max = ((i64::from(minor_len) - 1) << COORD_FRAC_BITS) - 1;
        match dminor.signum() {
            1 => {
                first = first.max(div_ceil(-minor0, dminor));
                last = last.min(div_floor(minor_max - minor0, dminor));
            }
            -1 => {
                first = first.max(div_ceil(minor_max - minor0, dminor));
                last = last.min(div_floor(-minor0, dminor));
            }
            _ if (0..=minor_max).contains(&minor0) => {}
            _ => last = first - 1,
        }
        Self {
            key: RayKey { x_major, forward },
            dminor,
            major0,
            delta0,
            minor0,
            first,
            last,
            minor_max,
            across: 0,
        }
    }

    /// Sets how the plane's rays drift sideways when their direction moves
    /// by `across` (I32F32 bits, the step to the next pixel across the
    /// line): see [`Plane::drift`].
    pub fn with_across(mut self, across: &[i64; 3]) -> Self {
        let (major, minor) = if self.key.x_major { (0, 1) } else { (1, 0) };
        let sign = if self.key.forward { 1 } else { -1 };
        // |across| < 2^40 and |dminor| <= 2^16: no overflow.
        self.across = (across[minor] << COORD_FRAC_BITS) - self.dminor * across[major] * sign;
        self
    }

    /// How much faster (Q16 per major step) the minor coordinate of a ray
    /// along `d` would grow if `d` moved by `offset` (Q16) steps across the
    /// line: `(across_minor − dminor·across_major) / run`. A pixel's ray goes
    /// through its line, up to half a pixel beside the pixel's center; this
    /// is how far the center's own ray would drift from it, which the color
    /// lookup makes up for.
    #[inline]
    pub fn drift(&self, d: &[i64; 3], offset: i64) -> i64 {
        self.drift_of(if self.key.x_major { d[0] } else { d[1] }, offset)
    }

    /// [`Plane::drift_of`] from the ray's run as a word (its major-axis
    /// component toward the plane's direction, shifted right by
    /// [`DIRECTION_WORD_SHIFT`]), for a direction with no bits below its
    /// word (a line's): the same drift, in 32-bit words but the across
    /// step's shift.
    #[inline]
    pub fn drift_of_word(&self, run: i32, offset: i64) -> i64 {
        if run <= 0 || offset == 0 || self.across == 0 {
            return 0;
        }
        // As `drift_of`: the run to 24 bits, the across step alike.
        let shift = (32 - run.leading_zeros()).saturating_sub(24 - DIRECTION_WORD_SHIFT);
        let run = if shift <= DIRECTION_WORD_SHIFT {
            run << (DIRECTION_WORD_SHIFT - shift)
        } else {
            run >> (shift - DIRECTION_WORD_SHIFT)
        };
        let across = bound(self.across >> shift, 1 << 30) as i32;
        let per_pixel = across / run.max(1);
        bound(
            (i64::from(per_pixel) * i64::from(offset as i32)) >> COORD_FRAC_BITS,
            1 << 14,
        )
    }

    /// [`Plane::drift_of_word`] with the across step shifted into the
    /// divide's range instead of bounded to it: the drift of the pixel
    /// center's own ray in full. The bounded one saturates on many lines
    /// at usual image widths (the across step shifted as far as the run is
    /// often above 2^30), which the colors of a line's rays are measured
    /// with; a ray that reads heights on its own path takes this one.
    #[inline]
    pub fn full_drift_of_word(&self, run: i32, offset: i64) -> i64 {
        if run <= 0 || offset == 0 || self.across == 0 {
            return 0;
        }
        // The run to 24 bits, or further where the across step needs it
        // to fit the 32-bit divide.
        let across_bits = 64 - self.across.unsigned_abs().leading_zeros();
        let shift = (32 - run.leading_zeros())
            .saturating_sub(24 - DIRECTION_WORD_SHIFT)
            .max(across_bits.saturating_sub(30));
        let run = if shift <= DIRECTION_WORD_SHIFT {
            run << (DIRECTION_WORD_SHIFT - shift)
        } else {
            run >> (shift - DIRECTION_WORD_SHIFT)
        };
        let across = bound(self.across >> shift, 1 << 30) as i32;
        let per_pixel = across / run.max(1);
        bound(
            (i64::from(per_pixel) * i64::from(offset as i32)) >> COORD_FRAC_BITS,
            1 << 14,
        )
    }

    /// The drift's numerator, `across_minor − dminor·across_major`
    /// ([`Plane::drift`]): what every ray of the plane divides by its run.
    #[inline]
    pub fn across(&self) -> i64 {
        self.across
    }

    /// [`Plane::drift`] from the direction's major-axis component alone.
    #[inline]
    pub fn drift_of(&self, major: i64, offset: i64) -> i64 {
        let run = if self.key.forward { major } else { -major };
        if run <= 0 || offset == 0 || self.across == 0 {
            return 0;
        }
        // A color lookup needs no more than 24 bits of this: drop the low
        // bits of both until they fit the core's 32-bit divide (and the
        // product its 32 × 32-bit multiply: |offset| <= 2^15).
        let shift = (64 - run.leading_zeros()).saturating_sub(24);
        let across = bound(self.across >> shift, 1 << 30) as i32;
        let per_pixel = across / ((run >> shift) as i32).max(1);
        bound(
            (i64::from(per_pixel) * i64::from(offset as i32)) >> COORD_FRAC_BITS,
            1 << 14,
        )
    }
}

/// Direction components (I32F32 bits) are below 2^38 (the view's limits
/// keep a pixel's direction under 2^6 in size): shifted right by this
/// they fit a word with room, keeping over 20 bits of every direction a
/// view has. A line's directions have no bits below it
/// ([`super::lines::Line::direction_words`]).
pub(crate) const DIRECTION_WORD_SHIFT: u32 = 8;

/// A direction component (I32F32 bits) to a word (see
/// [`DIRECTION_WORD_SHIFT`]).
#[inline(always)]
pub(crate) fn to_word(v: i64) -> i32 {
    saturate(v >> DIRECTION_WORD_SHIFT)
}

/// `v` brought to its 16 leading bits: the right shift and the result.
#[inline(always)]
fn leading_16(v: u32) -> (u32, u32) {
    let shift = (32 - v.leading_zeros()).saturating_sub(16);
    (shift, v >> shift)
}

/// A ray's slope, `up / run` in Q16 for direction components `up` and
/// `run` ≥ 0 in words (see [`to_word`]), within `MAX_RAY_SLOPE`: from the
/// run's 16 leading bits and one 32-bit divide. That is a relative
/// precision of 2^−15, which moves a ray by under a fiftieth of a voxel at
/// a depth of a thousand samples, in a few instructions on 32-bit cores,
/// where a 64-bit quotient calls a library routine. A vertical ray (a run
/// of 0) takes the steepest slope.
#[inline(always)]
pub(crate) fn slope_quotient(up: i32, run: u32) -> i32 {
    const MAX: u32 = (MAX_RAY_SLOPE as u32) << COORD_FRAC_BITS;
    let magnitude = if run == 0 {
        MAX
    } else {
        let (run_shift, run) = leading_16(run);
        // The numerator keeps as many of the 16 fraction bits as fit.
        let up = up.unsigned_abs();
        let fraction = up.leading_zeros().min(COORD_FRAC_BITS);
        let quotient = (up << fraction) / run;
        // up·2^16 / run = quotient · 2^(16 − fraction − run_shift).
        let right = fraction + run_shift;
        if right >= COORD_FRAC_BITS {
            (quotient >> (right - COORD_FRAC_BITS)).min(MAX)
        } else {
            let left = COORD_FRAC_BITS - right;
            if quotient > MAX >> left {
                MAX
            } else {
                quotient << left
            }
        }
    };
    if up < 0 {
        -(magnitude as i32)
    } else {
        magnitude as i32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact slope, `up·2^16 / run` bounded by `MAX_RAY_SLOPE`.
    fn exact_slope(up: i32, run: u32) -> f64 {
        let max = f64::from(MAX_RAY_SLOPE) * 65536.0;
        if run == 0 {
            return max.copysign(f64::from(up));
        }
        (f64::from(up) * 65536.0 / f64::from(run)).clamp(-max, max)
    }

    #[test]
    fn a_slope_is_within_its_precision_of_the_exact_quotient() {
        use proptest::prelude::*;
        let check = |up: i32, run: u32| {
            let exact = exact_slope(up, run);
            let got = f64::from(slope_quotient(up, run));
            // 2^−15 of the quotient (the run's 16 leading bits, truncated)
            // with room, and two units of its last place.
            let tolerance = exact.abs() * 2f64.powi(-14) + 2.0;
            assert!(
                (got - exact).abs() <= tolerance,
                "{up} / {run}: {got} against {exact}"
            );
        };
        let edges = [
            0,
            1,
            2,
            255,
            1 << 15,
            (1 << 16) - 1,
            1 << 16,
            1 << 24,
            i32::MAX as u32,
        ];
        for run in edges {
            for up in [
                0,
                1,
                -1,
                1 << 20,
                -(1 << 20),
                i32::MAX,
                i32::MIN + 1,
                i32::MIN,
            ] {
                check(up, run);
            }
        }
        proptest!(|(up in any::<i32>(), run in 0u32..=i32::MAX as u32)| check(up, run));
        // Words of directions the views make (2^20 to 2^30 in size).
        proptest!(|(up in -(1i32 << 30)..1 << 30, run in 1u32 << 20..1 << 30)| check(up, run));
    }

    #[test]
    fn slopes_rise_with_up_and_fall_with_run() {
        use proptest::prelude::*;
        proptest!(|(up in -(1i32 << 28)..1 << 28, run in 1u32..1 << 30, more in 0i32..1 << 10)| {
            prop_assert!(slope_quotient(up + more, run) >= slope_quotient(up, run));
            if up >= 0 {
                prop_assert!(slope_quotient(up, run + more as u32) <= slope_quotient(up, run));
            }
        });
    }
}
