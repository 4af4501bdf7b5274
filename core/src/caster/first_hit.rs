//! The hierarchical first hit (Cohen-Or §2, after Cohen & Shaked \[5\]): the
//! first ray of an image line cannot resume from a ray before it, so it goes
//! top-down through the pyramid's height bounds instead of voxel by voxel.
//!
//! On bound level `b` the ray tests the segment up to its next grid line of
//! that level (at most `2^b` voxels) against the bound of the cells the
//! segment crosses (at most two, since the minor slope is at most one). If
//! the segment's lower end is
//! above the bound, no level's surface can be hit there and the ray skips
//! the whole segment, then climbs a level whenever it stands on a coarser
//! grid line. Otherwise it descends, and hands the sample over to the walk
//! below level 1 or below the level the walk steps on there (a bound covers
//! the levels up to its own, not the coarser ones). The cost is logarithmic
//! in the distance to the hit.

use crate::config::{COORD_FRAC_BITS, HEIGHT_WEIGHT_BITS, MAX_WALK_LEVEL};
use crate::probe::Probe;
use crate::surface::Surface;
use crate::view::ray::Ray;

/// The first sample in `from..=end` where `ray` may hit any level of
/// `surface` (every sample before it is above every level's surface), or
/// `None` when it cannot hit there. After `tests` rounds (each at most two
/// bound tests) it stops and hands over the sample it has proven up to.
pub(crate) fn first_hit<T: Surface + ?Sized, P: Probe>(
    surface: &T,
    ray: &Ray,
    from: i32,
    end: i32,
    mut tests: u32,
    probe: &mut P,
) -> Option<i32> {
    let top = surface.top().min(MAX_WALK_LEVEL as u8);
    let mut level = top;
    let mut k = from;
    loop {
        if k > end {
            return None;
        }
        if level == 0 || tests == 0 {
            return Some(k);
        }
        tests -= 1;
        // The segment to the next grid line of this level lies in one
        // column (or row) of its cells.
        let next = ray.align_up(k.saturating_add(1), level);
        if next > end {
            level -= 1;
            continue;
        }
        if level < ray.level_at(next) {
            // The walk steps on a coarser level here, which this level's
            // bounds do not cover: hand over.
            return Some(k);
        }
        let major = ray.major_at(k);
        let major_cell = if ray.key.forward {
            major >> level
        } else {
            (major - 1) >> level
        };
        let (minor_a, z_a) = ray.position(k);
        let (minor_b, z_b) = ray.position(next);
        let shift = COORD_FRAC_BITS + u32::from(level);
        let (lo, hi) = (minor_a.min(minor_b) >> shift, minor_a.max(minor_b) >> shift);
        let mut bound = 0u16;
        for minor_cell in lo..=hi.min(lo + 1) {
            let (x, y) = if ray.key.x_major {
                (major_cell, minor_cell)
            } else {
                (minor_cell, major_cell)
            };
            let b = surface.bound(level, x, y);
            if let Some((_, cell)) = b {
                probe.bound(level, cell);
            }
            // A cell outside the map or not known proves nothing: assume
            // the worst.
            bound = bound.max(b.map_or(u16::MAX, |(b, _)| b));
        }
        if hi > lo + 1 {
            // Cannot happen with a minor slope of at most one; never skip.
            bound = u16::MAX;
        }
        let lowest = z_a.min(z_b);
        if lowest > i64::from(bound) << HEIGHT_WEIGHT_BITS {
            k = next;
            while level < top && ray.on_level_grid(k, level + 1) {
                level += 1;
            }
        } else {
            level -= 1;
        }
    }
}
