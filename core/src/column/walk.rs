//! The per-step loop: Cohen-Or's Figure 7, integer only.
//!
//! One step: fetch the two heights across the minor grid line, blend them by
//! the subvoxel weight (shift and mask of the minor coordinate), compare with
//! the ray height, advance by the fixed-point increments. No division, no
//! float; the only branches are the hit test, the end of the clipped ray, and
//! the `get` that turns an impossible out-of-map index into an exit instead
//! of a panic.

use crate::config::{COORD_FRAC_BITS, HEIGHT_WEIGHT_BITS};
use crate::probe::Probe;
use crate::view::ray::{Cursor, Ray, Strides};

/// The voxel index of a sample's grid-line start and its subvoxel weight of
/// `bits` bits (shift and mask of the minor coordinate).
#[inline(always)]
pub(crate) fn locate(at: &Cursor, strides: &Strides, bits: u32) -> (isize, i32) {
    let minor = at.minor.to_bits();
    let index = at.base + (minor >> COORD_FRAC_BITS) as isize * strides.minor;
    (
        index,
        (minor >> (COORD_FRAC_BITS - bits)) & ((1 << bits) - 1),
    )
}

/// How far the ray is above the surface at a sample (Q16; ≤ 0 is a hit),
/// and the voxel fetched. `None` only for an index outside the map.
#[inline(always)]
pub(crate) fn clearance(heights: &[u16], at: &Cursor, strides: &Strides) -> Option<(usize, i32)> {
    let (index, weight) = locate(at, strides, HEIGHT_WEIGHT_BITS);
    let h0 = i32::from(*heights.get(index as usize)?);
    let h1 = i32::from(*heights.get((index + strides.minor) as usize)?);
    // U12.4 height times a 12-bit weight is exactly I16F16.
    let surface = (h0 << HEIGHT_WEIGHT_BITS) + (h1 - h0) * weight;
    Some((index as usize, at.z.to_bits().saturating_sub(surface)))
}

/// The outcome of a walk along one ray.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Walk {
    /// The ray is at or below the surface at `at`. `above` is the clearance
    /// of the sample before it, when the walk visited that sample.
    Hit {
        at: Cursor,
        clearance: i32,
        above: Option<i32>,
    },
    /// The ray reached its end above the surface: it was above at every
    /// sample it visited, up to `last`.
    Exit { last: i32 },
}

/// Walks from `at` along the ray until a hit or sample `end`.
#[inline]
pub(crate) fn walk<P: Probe>(
    heights: &[u16],
    ray: &Ray,
    strides: &Strides,
    mut at: Cursor,
    end: i32,
    probe: &mut P,
) -> Walk {
    let mut above = None;
    loop {
        let Some((voxel, clearance)) = clearance(heights, &at, strides) else {
            return Walk::Exit { last: at.k - 1 };
        };
        probe.visit(voxel);
        if clearance <= 0 {
            return Walk::Hit {
                at,
                clearance,
                above,
            };
        }
        if at.k >= end {
            return Walk::Exit { last: at.k };
        }
        above = Some(clearance);
        at.advance(ray, strides);
    }
}
