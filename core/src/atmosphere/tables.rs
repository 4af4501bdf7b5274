//! The fixed-point lookups the atmosphere shares: what fog leaves of a
//! color after a number of halvings, linear lookups in the tables by height
//! and by sine, a ray's length over its run or its drop, and unit vectors
//! and reciprocals without a division.

use super::*;

/// What fog leaves of a color (in 1/256, rounded) after `i/256`
/// halvings: `256 · 2^−i/256`, from a table without a blend between its
/// entries (neighbours differ by at most one 256th). Past 10 halvings
/// nothing is left.
const TRANSMITTED_HALVINGS: usize = 10;
static TRANSMITTED: [u16; (TRANSMITTED_HALVINGS << 8) + 1] = {
    // `2^−1/256`: each entry the one before it times that.
    const STEP: f64 = 0.997_296_056_085_470_1;
    let mut table = [0u16; (TRANSMITTED_HALVINGS << 8) + 1];
    let mut left = 256.0;
    let mut i = 0;
    while i < table.len() {
        table[i] = (left + 0.5) as u16;
        left *= STEP;
        i += 1;
    }
    table
};

/// What fog leaves of a color (in 1/256) after `halvings_q8` halvings
/// (Q8).
#[inline(always)]
pub(super) fn left_after(halvings_q8: u32) -> u32 {
    match TRANSMITTED.get(halvings_q8 as usize) {
        Some(&left) => u32::from(left),
        None => 0,
    }
}

/// `v` within a word, held at the largest.
#[inline(always)]
pub(super) fn word(v: u64) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

/// `table` (an entry every 4 voxels of height, each below 2^31, so a
/// step between two fits a word) at height `h` (Q8), linear between
/// entries, held past the last: one 32 × 32-bit product. The fog's
/// tables by height and the frame's rate table.
#[inline(always)]
pub(super) fn between(table: &[u32; HEIGHT_STEPS + 1], h: u32) -> u32 {
    let step_q8 = HEIGHT_STEP_BITS + Q8;
    let at = (h >> step_q8) as usize;
    match (table.get(at), table.get(at + 1)) {
        (Some(&low), Some(&high)) => {
            let step = high.wrapping_sub(low) as i32;
            let fraction = (h & ((1 << step_q8) - 1)) as i32;
            low.wrapping_add(((i64::from(step) * i64::from(fraction)) >> step_q8) as u32)
        }
        _ => table[HEIGHT_STEPS],
    }
}

/// Where the sky's tables by sine hold elevation sine `sine` (Q20, in
/// [0, 1]): the entry below it and the fraction (in 1/256) to the next.
#[inline(always)]
pub(super) fn sky_entry(sine: i64) -> (usize, u32) {
    let at = (sine >> (DIR_BITS - 8)) as usize;
    (at, ((sine >> (DIR_BITS - 16)) & 0xFF) as u32)
}

/// `table` at entry `at` blended `fraction`/256 toward the next.
#[inline(always)]
pub(super) fn sky_between(table: &[Rgb; SKY_STEPS + 1], at: usize, fraction: u32) -> Rgb {
    match table.get(at + 1) {
        Some(&next) => lerp(table[at.min(SKY_STEPS)], next, fraction),
        None => table[SKY_STEPS],
    }
}

/// The frame's fogged sky gradient at elevation sine `up` (Q20; below
/// the horizon, the horizon's): its entry nearest `up`.
#[inline(always)]
pub(super) fn fogged_sky(sky: &[Rgb; SKY_FINE_STEPS + 1], up: i64) -> Rgb {
    let half = 1 << (DIR_BITS - SKY_FINE_BITS - 1);
    let at = ((up.clamp(0, 1 << DIR_BITS) + half) >> (DIR_BITS - SKY_FINE_BITS)) as usize;
    sky[at.min(SKY_FINE_STEPS)]
}

/// How far below (or above) the eye `sample`'s hit is, Q16, within a
/// word.
#[inline(always)]
pub(super) fn drop(frame: &AtmosphereFrame, sample: &Sample) -> u32 {
    let drop = (frame.eye_q16 - i64::from(sample.elevation)).unsigned_abs();
    drop.min(u64::from(u32::MAX)) as u32
}

/// A ray's slope at and past which it has no run along the major axis.
pub(super) const MAX_SLOPE_Q16: u32 = (MAX_RAY_SLOPE as u32) << COORD_FRAC_BITS;

/// `√(1 + u²) − 1` (Q16) for `u = i/1024`, `i` in 0..=1024: a line's
/// plane's horizontal length a unit of major-axis distance (`u` its minor
/// slope), and a ray's length over its horizontal length (`u` its slope
/// over its line's `m`) or, for a ray steeper than that, over its height
/// change (`u` the run over the rise). A ray takes the entry nearest its
/// `u`, without a blend (neighbours differ by under 2^−10 of the length).
pub(super) const STRETCH_FINE: [u16; 1025] = {
    let mut table = [0u16; 1025];
    let mut i = 0;
    while i < 1025 {
        let root = ((1u64 << 52) + (((i * i) as u64) << 32)).isqrt();
        table[i] = ((root - (1 << 26) + (1 << 9)) >> 10) as u16;
        i += 1;
    }
    table
};

/// Scales a direction (Q20, at least 1 and below 2^7 long) to unit
/// length without a division: its squared length's top 32 bits brought
/// into [2^30, 2^32) by an even shift, and `1/√` of that from a table by
/// its top 9 bits, blended by the next 16 (within a part in 2^16).
pub(super) struct Unit {
    /// `1/√u` (Q30, `u` the normalized squared length in [1/4, 1)) and
    /// the shift that turns a component times it into Q20.
    inverse: i64,
    shift: u32,
}

impl Unit {
    pub(super) fn new(d: [i32; 3]) -> Self {
        let squared: u64 = d
            .iter()
            .map(|&v| (i64::from(v) * i64::from(v)) as u64)
            .sum();
        // At least 2^40 (|d| >= 1): the bits dropped are below a part in 2^16.
        let top = (squared.clamp(1 << 40, (1 << 56) - 1) >> 24) as u32;
        let half_shift = top.leading_zeros() / 2;
        let m = top << (2 * half_shift);
        let at = (m >> 23) as usize - 128;
        let fraction = u64::from((m >> 7) & 0xFFFF);
        let (low, high) = (
            u64::from(INVERSE_ROOTS[at]),
            u64::from(INVERSE_ROOTS[at + 1]),
        );
        // |d| = √u · 2^(8 − half_shift) in units of 2^20: a component c
        // (Q20) over it is c · (1/√u) · 2^(half_shift − 8), Q20.
        Self {
            inverse: (low - (((low - high) * fraction) >> 16)) as i64,
            shift: 30 + 8 - half_shift,
        }
    }

    /// Component `c` of the direction, of the unit direction (Q20).
    pub(super) fn of(&self, c: i32) -> i64 {
        (i64::from(c) * self.inverse) >> self.shift
    }

    /// `c` as [`Unit::of`] for a component's size.
    pub(super) fn of_size(&self, c: u32) -> u32 {
        ((u64::from(c) * self.inverse as u64) >> self.shift) as u32
    }
}

/// `1/√(i/512)` in Q30 for `i` in 128..=512: `√(2^69 / i)`.
const INVERSE_ROOTS: [u32; 385] = {
    let mut roots = [0u32; 385];
    let mut i = 0;
    while i < 385 {
        roots[i] = ((1u128 << 69) / (i as u128 + 128)).isqrt() as u32;
        i += 1;
    }
    roots
};

/// `1/x` in Q16 for `x` (Q20) from 1/2 to 1 (a unit direction's largest
/// component is at least 1/√3), from a table by its top 8 bits below
/// 1, blended by the next 12.
pub(super) fn reciprocal_q16(x: u32) -> u32 {
    let x = x.clamp(1 << (DIR_BITS - 1), 1 << DIR_BITS);
    let at = (x >> 12) as usize - 128;
    let fraction = x & 0xFFF;
    let (low, high) = (RECIPROCALS[at], RECIPROCALS[(at + 1).min(128)]);
    low - (((low - high) * fraction) >> 12)
}

/// `256 / (i + 128)` in Q16 for `i` in 0..=128.
const RECIPROCALS: [u32; 129] = {
    let mut reciprocals = [0u32; 129];
    let mut i = 0;
    while i < 129 {
        reciprocals[i] = (1 << 24) / (i as u32 + 128);
        i += 1;
    }
    reciprocals
};
