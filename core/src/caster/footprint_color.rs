//! A hit's color by the pixel's footprint on the terrain: trilinear, from
//! the two levels whose voxels bracket the footprint, whatever level the
//! ray stepped on.
//!
//! Heights and colors want different levels. A coarse level's heights are
//! off from the terrain by its detail, which the terrain fit keeps small by
//! moving the height levels out ([`crate::roughness`]); its colors are the
//! photo low-passed, which is what a pixel as wide as one of its voxels
//! should show. So colors take their own schedule, by the pixel-to-voxel
//! ratio as given ([`Ray::color_reach`]): level `l` is blended in from
//! where a voxel of level `l − 1` gets narrower than the pixel, and is all
//! there where a voxel of level `l` does (Cohen-Or's soft transition, by
//! depth). Before, colors came from the height level, so on rugged maps,
//! where the fit keeps level 0 out to thousands of voxels, they aliased
//! there as single resolution does.
//!
//! The footprint is the pixel's narrower side. Across the ray a pixel at
//! major-axis depth `D` is about `D / focal` voxels wide; along it,
//! `1 / σ` of that, with `σ` the surface's slope against the ray's
//! (height change per voxel between the samples either side of the
//! crossing). Ground seen at a grazing angle (`σ < 1`) is long along the
//! ray and its width decides; a slope facing the eye (`σ > 1`) is short
//! along the ray, and a level picked by its width alone would blur the
//! slope's colors over many rows of pixels. By the narrower side nothing
//! the pixel resolves is blurred.

use super::fraction_256;
use super::walk::Lanes;
use crate::config::{COORD_FRAC_BITS, WEIGHT_BITS};
use crate::probe::Probe;
use crate::surface::{Grid, Surface};
use crate::view::ray::{Cursor, Ray};
use crate::Rgb;

/// The color of a hit from the levels its footprint brackets, or `None`
/// where level 0 alone is fine enough (the caller then blends level 0's
/// grid lines, as before the ray reached `color_reach`) and where a lookup
/// finds no color.
///
/// `hit` is the first sample at or below the surface (clearance `below`);
/// `above`, when known, the visited sample before it and its clearance,
/// and `f`/256 how far between the two the crossing lies. Colors never come
/// from a level finer than the one below `hit`'s own: the ray read that
/// one at this depth already, so a surface paged in tiles has it.
#[inline(never)]
pub(crate) fn footprint_color<T: Surface + ?Sized, P: Probe>(
    surface: &T,
    ray: &Ray,
    hit: &Cursor,
    below: i32,
    above: Option<(i32, i32)>,
    f: u32,
    probe: &mut P,
) -> Option<Rgb> {
    let (k, distance, steps) = crossing_along(ray, hit, above, f);
    // Near the eye (and at single resolution: `color_reach` is i64::MAX)
    // level 0 alone, unless the ray stepped on a coarser level.
    if distance < ray.color_reach && hit.level == 0 {
        return None;
    }
    let width = narrower_side(distance, steps, above, below);
    let (level, t) = match color_level(width, ray.color_reach, ray.color_top) {
        Some((level, t)) if level >= hit.level => (level, t),
        _ if hit.level > 0 => (hit.level, 0),
        _ => return None,
    };
    levels_color(surface, level, t, ray.color_point(k, distance), probe)
}

/// The color of a hit on level 0 nearer than the color reach from the
/// photos finer than level 0 ([`crate::Detail::color_for`]), by the pixel's
/// footprint as [`footprint_color`] finds it; `None` outside their
/// rectangles and on a coarser level.
#[inline(never)]
pub(crate) fn detail_color<T: Surface + ?Sized, P: Probe>(
    surface: &T,
    ray: &Ray,
    hit: &Cursor,
    below: i32,
    above: Option<(i32, i32)>,
    f: u32,
    probe: &mut P,
) -> Option<Rgb> {
    if hit.level > 0 {
        return None;
    }
    let (k, distance, steps) = crossing_along(ray, hit, above, f);
    let width = narrower_side(distance, steps, above, below);
    let color = surface.detail_color(ray.color_point(k, distance), width, ray.color_reach)?;
    probe.color(0, hit.base as usize);
    Some(color)
}

/// Where a hit's crossing is, `f`/256 of the way from the sample before
/// (`above`'s, when known) to `hit`: in 1/256 of a sample along the ray,
/// its distance (Q16), and the samples between the two.
#[inline(always)]
fn crossing_along(ray: &Ray, hit: &Cursor, above: Option<(i32, i32)>, f: u32) -> (i64, i64, i32) {
    let before = above.map_or(hit.k, |(k, _)| k);
    let k = (i64::from(before) << 8) + i64::from(hit.k - before) * i64::from(f);
    (k, ray.distance_q8(k), hit.k - before)
}

/// The color at world point `point` (Q16) of levels `level − 1` and
/// `level` blended by `t`/256 (see [`color_level`]); `None` where neither
/// has a color.
pub(super) fn levels_color<T: Surface + ?Sized, P: Probe>(
    surface: &T,
    level: u8,
    t: u32,
    point: [i64; 2],
    probe: &mut P,
) -> Option<Rgb> {
    // Weight 0 or 1 reads one level only. A level that finds no color (at
    // the map's edge) leaves the other's: once a fetch is reported, the
    // caller must not make two more (`MAX_COLOR_FETCHES_A_RAY`). The
    // blends stay in lanes until the last.
    let finer = (t < 1 << WEIGHT_BITS)
        .then(|| bilinear(surface, level - 1, point, probe))
        .flatten();
    let coarser = (t > 0)
        .then(|| bilinear(surface, level, point, probe))
        .flatten();
    match (finer, coarser) {
        (Some(finer), Some(coarser)) => Some(finer.lerp(coarser, t).rgb()),
        (Some(color), None) | (None, Some(color)) => Some(color.rgb()),
        (None, None) => None,
    }
}

/// The footprint's narrower side as a depth, Q16: `distance` across the
/// ray, or `distance / σ` on a surface steeper than the ray by `σ > 1`
/// (the clearances change by `σ` voxels a voxel between the two samples
/// `steps` apart).
#[inline]
pub(super) fn narrower_side(
    distance: i64,
    steps: i32,
    above: Option<(i32, i32)>,
    below: i32,
) -> i64 {
    let Some((_, above)) = above else {
        return distance;
    };
    let run = u64::from(steps.max(1).unsigned_abs()) << COORD_FRAC_BITS;
    let rise = (i64::from(above) - i64::from(below)).unsigned_abs();
    if rise <= run {
        return distance;
    }
    // `distance · run / rise` by a 32-bit division: `run / rise` (below 1)
    // to 16 bits, with both brought under 2^16 first.
    let shift = (64 - rise.leading_zeros()).saturating_sub(16);
    let ratio = (((run >> shift) as u32) << 16) / ((rise >> shift) as u32).max(1);
    distance.saturating_mul(i64::from(ratio)) >> 16
}

/// The level pair and blend for a footprint `width` (a depth, Q16) on a ray
/// whose colors reach level 1 at `reach`: `(l, t)` blends level `l − 1`
/// into level `l` by `t`/256, from 0 at `reach << (l − 1)` to 1 at
/// `reach << l`; past level `top`'s end, `(top, 256)`. `None` before
/// `reach` (level 0 alone) and when there is no level 1.
#[inline]
pub(super) fn color_level(width: i64, reach: i64, top: u8) -> Option<(u8, u32)> {
    if width < reach || top == 0 {
        return None;
    }
    let (mut level, mut begins) = (1u8, reach);
    while width >= begins << 1 {
        if level == top {
            return Some((top, 1 << WEIGHT_BITS));
        }
        level += 1;
        begins <<= 1;
    }
    Some((level, fraction(width - begins, begins)))
}

/// `num / den` in 1/256 (`0 ≤ num < den`), both brought under 2^32 for
/// the caster's 32-bit [`fraction_256`].
#[inline]
fn fraction(num: i64, den: i64) -> u32 {
    let shift = (64 - den.leading_zeros()).saturating_sub(32);
    fraction_256((num >> shift) as u32, (den >> shift) as u32)
}

/// The color at world point `point` (Q16) on `level`: its four grid points
/// blended by the point's fraction of the level's spacing on each axis,
/// in lanes. Reported to `probe` as one color fetch, of a square.
#[inline(always)]
fn bilinear<T: Surface + ?Sized, P: Probe>(
    surface: &T,
    level: u8,
    point: [i64; 2],
    probe: &mut P,
) -> Option<Lanes> {
    let grid = surface.grid(level)?;
    let shift = COORD_FRAC_BITS + u32::from(level);
    let cell = point.map(|v| v >> shift);
    let weight = point.map(|v| ((v >> (shift - WEIGHT_BITS)) & ((1 << WEIGHT_BITS) - 1)) as u32);
    let index = cell[1] as isize * grid.stride() + cell[0] as isize;
    let grid = grid.near(index);
    // A neighbour of weight 0 is not read: a point on the map's last row
    // or column has none there.
    let across = isize::from(weight[0] != 0);
    let (c00, c10) = grid.color_pair(index, across)?;
    let row = Lanes::of(c00).lerp(Lanes::of(c10), weight[0]);
    let square = if weight[1] == 0 {
        row
    } else {
        let (c01, c11) = grid.color_pair(index + grid.stride(), across)?;
        row.lerp(Lanes::of(c01).lerp(Lanes::of(c11), weight[0]), weight[1])
    };
    probe.color_square(level, index as usize);
    Some(square)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ONE: i64 = 1 << COORD_FRAC_BITS;

    #[test]
    fn levels_begin_at_doublings_of_the_reach_and_blend_between() {
        let reach = 500 * ONE;
        assert_eq!(color_level(499 * ONE, reach, 6), None);
        assert_eq!(color_level(500 * ONE, reach, 6), Some((1, 0)));
        assert_eq!(color_level(750 * ONE, reach, 6), Some((1, 128)));
        assert_eq!(color_level(1000 * ONE, reach, 6), Some((2, 0)));
        assert_eq!(color_level(3000 * ONE, reach, 6), Some((3, 128)));
        // Past the top level's end: all of the top level.
        assert_eq!(color_level(500 * 64 * ONE, reach, 6), Some((6, 256)));
        assert_eq!(color_level(1500 * ONE, reach, 1), Some((1, 256)));
        // No levels: level 0 at any depth.
        assert_eq!(color_level(i64::MAX / 4, reach, 0), None);
    }

    #[test]
    fn a_slope_facing_the_eye_narrows_the_footprint_and_ground_does_not() {
        let distance = 2000 * ONE;
        const ONE_I32: i32 = 1 << COORD_FRAC_BITS;
        // Ground below a grazing ray: the clearance falls by a tenth of a
        // voxel a voxel.
        assert_eq!(
            narrower_side(distance, 4, Some((0, 4 * ONE_I32 / 10)), 0),
            distance
        );
        // A slope four times steeper than the ray's, over a step of two.
        assert_eq!(
            narrower_side(distance, 2, Some((0, 5 * ONE_I32)), -3 * ONE_I32),
            distance / 4
        );
        // Unknown before: the width across.
        assert_eq!(narrower_side(distance, 1, None, -ONE_I32), distance);
    }

    #[test]
    fn bilinear_reads_the_maps_last_row_and_column_without_a_neighbour_past_them() {
        use crate::{NoProbe, Pyramid, Terrain};
        let heights = [0u16; 16];
        let colors: [Rgb; 16] = core::array::from_fn(|i| [(i * 10) as u8, 0, 0]);
        let terrain = Terrain::new(4, 4, &heights, &colors).unwrap();
        let pyramid = Pyramid::flat(terrain);
        let at = |x: i64, y: i64| bilinear(&pyramid, 0, [x, y], &mut NoProbe).map(|c| c.rgb()[0]);
        // The far corner, the last column and the last row: grid points.
        assert_eq!(at(3 * ONE, 3 * ONE), Some(150));
        assert_eq!(at(3 * ONE, ONE), Some(70));
        assert_eq!(at(ONE, 3 * ONE), Some(130));
        // Halfway along the last row: its two points blended.
        assert_eq!(at(ONE + ONE / 2, 3 * ONE), Some(135));
        // Past the last row: no color.
        assert_eq!(at(ONE, 3 * ONE + ONE / 2), None);
    }

    #[test]
    fn fraction_is_exact_on_halves_and_never_reaches_past_one() {
        assert_eq!(fraction(1, 2), 128);
        assert_eq!(fraction(0, 1 << 40), 0);
        assert_eq!(fraction((1 << 40) - 1, 1 << 40), 255);
        assert_eq!(fraction(3 << 50, 4 << 50), 192);
    }
}
