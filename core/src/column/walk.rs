//! The per-step loop: Cohen-Or's Figure 7, integer only.
//!
//! One step: fetch the two heights across the minor grid line, blend them by
//! the subvoxel weight (shift and mask of the minor coordinate), compare with
//! the ray height, advance by the fixed-point increments. No division, no
//! float; the only branches are the hit test, the end of the clipped ray, and
//! the `get` that turns an impossible out-of-map index into an exit instead
//! of a panic.

use crate::config::{COORD_FRAC_BITS, HEIGHT_FRAC_BITS, WEIGHT_BITS};
use crate::probe::Probe;
use crate::view::ray::{Cursor, Ray, Strides};

/// Bit shift from a blended height (U12.4 times a weight in 1/256) to Q16.
const BLEND_TO_COORD: u32 = COORD_FRAC_BITS - WEIGHT_BITS - HEIGHT_FRAC_BITS;
const WEIGHT_MASK: i32 = (1 << WEIGHT_BITS) - 1;

/// The voxel index of a sample's grid-line start and its subvoxel weight.
#[inline(always)]
pub(crate) fn locate(at: &Cursor, strides: &Strides) -> (isize, i32) {
    let bits = at.minor.to_bits();
    let index = at.base + (bits >> COORD_FRAC_BITS) as isize * strides.minor;
    (index, (bits >> (COORD_FRAC_BITS - WEIGHT_BITS)) & WEIGHT_MASK)
}

/// How far the ray is above the surface at a sample (Q16; ≤ 0 is a hit),
/// and the voxel fetched. `None` only for an index outside the map.
#[inline(always)]
pub(crate) fn clearance(heights: &[u16], at: &Cursor, strides: &Strides) -> Option<(usize, i32)> {
    let (index, weight) = locate(at, strides);
    let h0 = i32::from(*heights.get(index as usize)?);
    let h1 = i32::from(*heights.get((index + strides.minor) as usize)?);
    let surface = ((h0 << WEIGHT_BITS) + (h1 - h0) * weight) << BLEND_TO_COORD;
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
    /// The ray left the map, or rose above the highest terrain, after
    /// sample `last`.
    Exit { last: i32 },
}

/// Walks from `at` along the ray until a hit or the ray's end.
#[inline]
pub(crate) fn walk<P: Probe>(
    heights: &[u16],
    ray: &Ray,
    strides: &Strides,
    mut at: Cursor,
    probe: &mut P,
) -> Walk {
    let mut above = None;
    loop {
        let Some((voxel, clearance)) = clearance(heights, &at, strides) else {
            return Walk::Exit { last: at.k };
        };
        probe.visit(voxel);
        if clearance <= 0 {
            return Walk::Hit { at, clearance, above };
        }
        if at.k >= ray.end {
            return Walk::Exit { last: at.k };
        }
        above = Some(clearance);
        at.advance(ray, strides);
    }
}
