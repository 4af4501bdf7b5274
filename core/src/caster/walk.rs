//! The per-step loop: Cohen-Or's Figure 7, integer only, on any level.
//!
//! One step at level 0: fetch the two heights across the minor grid line,
//! blend them by the subvoxel weight (shift and mask of the minor
//! coordinate), compare with the ray height, advance by the fixed-point
//! increments. At level `l ≥ 1` the step is `2^l` voxels with the increments
//! doubled `l` times, and the grid and weight are the same shift by `l` more
//! bits. (Colors, not heights, are blended with the level below when a hit
//! is shaded: morphing heights too would sample the finer level on the
//! coarser grid lines only and lose every feature between them.) No
//! division, no float; the only branches are the
//! hit test, the end of the clipped ray, the level switch, and the `get`
//! that turns an impossible out-of-map index into an exit instead of a
//! panic.

use crate::color::Rgb;
use crate::config::{COORD_FRAC_BITS, HEIGHT_WEIGHT_BITS, WEIGHT_BITS};
#[cfg(test)]
use crate::probe::NoProbe;
use crate::probe::Probe;
use crate::surface::{Grid, Surface};
use crate::view::ray::{Cursor, Ray};

/// Everything a step on one level needs, fixed while the ray stays there.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Stage<G> {
    level: u8,
    here: G,
    /// Index change across a minor grid line.
    minor_stride: isize,
    /// Index change per step, here and on the level below (two of its grid
    /// lines per step).
    step: isize,
    /// Increments of one step of `2^level` voxels, Q16.
    dminor: i32,
    dz: i32,
}

/// Index strides of a level's grid for a ray: (per major grid line, across
/// a minor grid line).
fn strides(row: isize, x_major: bool) -> (isize, isize) {
    if x_major {
        (1, row)
    } else {
        (row, 1)
    }
}

impl<G: Grid> Stage<G> {
    /// The stage of `level` for `ray` (level 0 if the surface lacks it).
    #[inline]
    pub fn new<'s, T>(surface: &'s T, ray: &Ray, level: u8) -> Self
    where
        T: Surface<Grid<'s> = G> + ?Sized,
    {
        let level = level.min(surface.top());
        let here = surface.grid(level).unwrap_or_else(|| surface.base());
        let sign = if ray.key.forward { 1 } else { -1 };
        let (major_stride, minor_stride) = strides(here.stride(), ray.key.x_major);
        Self {
            level,
            here,
            minor_stride,
            step: sign * major_stride,
            dminor: ray.dminor.to_bits() << level,
            dz: ray.dz.to_bits() << level,
        }
    }

    /// This stage, its grid resolved for reads near `at` ([`Grid::near`]).
    #[inline(always)]
    pub fn near(mut self, at: &Cursor) -> Self {
        self.here = self
            .here
            .near(index(at.base, self.minor_stride, at.minor, self.level));
        self
    }

    /// This stage when it is `level`'s (a walk's, at hand), else a new one.
    #[inline]
    pub fn on_level<'s, T>(self, surface: &'s T, ray: &Ray, level: u8) -> Self
    where
        T: Surface<Grid<'s> = G> + ?Sized,
    {
        if self.level == level {
            self
        } else {
            Self::new(surface, ray, level)
        }
    }

    /// Samples per step.
    #[inline(always)]
    pub fn stride(&self) -> i32 {
        1 << self.level
    }

    /// How far the ray is above the surface at a sample (Q16; ≤ 0 is a
    /// hit), and the voxel of this level fetched. `None` only for an index
    /// outside the map.
    #[cfg(test)]
    pub fn clearance(&self, at: &Cursor) -> Option<(usize, i32)> {
        let (cell, clearance) = self.clearance_recent(at, &Recent::default(), &mut NoProbe)?;
        Some((cell.index as usize, clearance))
    }

    /// The two heights across the grid line starting at `index`: from
    /// `recent` when it holds that cell (no fetch, no step: Figure 7's inner
    /// loop compares the next ray with the heights it already has), else
    /// fetched and reported. `None` only for an index outside the map.
    #[inline(always)]
    fn cell<P: Probe>(&self, index: isize, recent: Option<&Recent>, probe: &mut P) -> Option<Cell> {
        if let Some(cell) = recent.and_then(|r| r.find(self.level, index, self.minor_stride)) {
            return Some(cell);
        }
        let (h0, h1) = self.here.height_pair(index, self.minor_stride)?;
        probe.visit(self.level, index as usize);
        Some(Cell {
            level: self.level,
            index,
            across: self.minor_stride,
            h0: i32::from(h0),
            h1: i32::from(h1),
        })
    }

    /// How far a ray at height `z` is above a cell's surface at minor
    /// coordinate `minor` (Q16): the two heights blended by a 12-bit weight
    /// (U12.4 lands exactly on I16F16).
    #[inline(always)]
    fn clearance_in(&self, cell: &Cell, minor: i32, z: i32) -> i32 {
        let weight_shift = COORD_FRAC_BITS - HEIGHT_WEIGHT_BITS + u32::from(self.level);
        let weight = (minor >> weight_shift) & ((1 << HEIGHT_WEIGHT_BITS) - 1);
        z.saturating_sub((cell.h0 << HEIGHT_WEIGHT_BITS) + (cell.h1 - cell.h0) * weight)
    }

    /// The clearance at a sample and its cell, read from `recent` when it
    /// holds the cell (see [`Stage::cell`]).
    pub fn clearance_recent<P: Probe>(
        &self,
        at: &Cursor,
        recent: &Recent,
        probe: &mut P,
    ) -> Option<(Cell, i32)> {
        let index = index(at.base, self.minor_stride, at.minor, self.level);
        let cell = self.cell(index, Some(recent), probe)?;
        Some((cell, self.clearance_in(&cell, at.minor, at.z)))
    }

    /// The index of the first voxel of the grid line a sample is on.
    #[inline(always)]
    pub fn line_start(&self, at: &Cursor) -> isize {
        index(at.base, self.minor_stride, at.minor, self.level)
    }

    /// Where the ray crosses at height `z` (Q16), `t`/256 of the way from
    /// the sample `before` (on `before_stage`) to the hit sample `hit` on
    /// this stage: the hit's weight against the sample before
    /// ([`along_weight`], on level 0; `t` elsewhere).
    #[inline(always)]
    pub fn along_weight(
        &self,
        before_stage: &Self,
        (before, hit): (&Cursor, &Cursor),
        z: i32,
        t: u32,
    ) -> u32 {
        if self.level != 0 || before_stage.level != 0 {
            return t;
        }
        along_weight(
            &self.here,
            (self.line_start(before), self.line_start(hit)),
            self.minor_stride,
            z,
            t,
        )
    }

    /// The color of the voxel nearest a sample, on this level alone.
    pub fn nearest_color<P: Probe>(&self, at: &Cursor, z: i32, probe: &mut P) -> Option<Rgb> {
        let i = index(at.base, self.minor_stride, at.minor, self.level);
        let half = 1 << (COORD_FRAC_BITS - 1 + u32::from(self.level));
        let nearest = if at.minor & ((half << 1) - 1) < half {
            i
        } else {
            i + self.minor_stride
        };
        probe.color(self.level, i as usize);
        self.here.color_at(nearest, z)
    }

    /// The color where a sample's grid line is crossed: two voxels of this
    /// level blended by the subvoxel weight. (Past the color reach, hits
    /// take the levels their footprint brackets instead:
    /// `caster::footprint_color`.)
    ///
    /// Reported to `probe` once a color was found: a lookup that finds
    /// none leaves the caller to try another, uncounted.
    pub fn color<P: Probe>(&self, at: &Cursor, z: i32, probe: &mut P) -> Option<Rgb> {
        let color = line_color(
            &self.here,
            at.base,
            self.minor_stride,
            at.minor,
            self.level,
            z,
        )?;
        probe.color(
            self.level,
            index(at.base, self.minor_stride, at.minor, self.level) as usize,
        );
        Some(color)
    }
}

/// The index of a sample's grid-line start on level `level`.
#[inline(always)]
fn index(base: isize, minor_stride: isize, minor: i32, level: u8) -> isize {
    base + (minor >> (COORD_FRAC_BITS + u32::from(level))) as isize * minor_stride
}

/// The two heights across a grid line on one level, as fetched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Cell {
    level: u8,
    index: isize,
    /// Index change to the second height (which grid line family).
    across: isize,
    h0: i32,
    h1: i32,
}

/// The last two cells a line's rays hit or retraced to: the next ray
/// tests them again.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Recent {
    cells: [Option<Cell>; 2],
}

impl Recent {
    fn find(&self, level: u8, index: isize, across: isize) -> Option<Cell> {
        self.cells
            .iter()
            .flatten()
            .find(|c| c.level == level && c.index == index && c.across == across)
            .copied()
    }

    /// Remembers a cell: a hit's, or a retrace's.
    pub fn add(&mut self, cell: Cell) {
        self.cells = [Some(cell), self.cells[0]];
    }
}

/// Two colors across a grid line blended by the subvoxel weight: at minor
/// coordinate `minor` (Q16, world voxels) of level `level`'s grid line
/// starting at `base`, the neighbour `minor_stride` away, where the ray
/// crosses the surface at height `z` (Q16; see [`Grid::color_pair_at`]).
#[inline]
pub(crate) fn line_color<G: Grid>(
    grid: &G,
    base: isize,
    minor_stride: isize,
    minor: i32,
    level: u8,
    z: i32,
) -> Option<Rgb> {
    let i = index(base, minor_stride, minor, level);
    let weight =
        (minor >> (COORD_FRAC_BITS - WEIGHT_BITS + u32::from(level))) & ((1 << WEIGHT_BITS) - 1);
    let (c0, c1) = grid.color_pair_at(i, minor_stride, z)?;
    Some(lerp(c0, c1, weight as u32))
}

/// The weight (of 256) a hit's color takes against the color at the
/// sample before it, where the ray crosses the surface `t`/256 of the way
/// between them at height `z` (Q16): `t`, but where an object stands on
/// one of the two grid lines and not on the other, the crossing is on its
/// wall, whose color is that line's alone (see [`Grid::stands`]).
#[inline(always)]
pub(crate) fn along_weight<G: Grid>(
    grid: &G,
    (before, hit): (isize, isize),
    across: isize,
    z: i32,
    t: u32,
) -> u32 {
    match (grid.stands(before, across, z), grid.stands(hit, across, z)) {
        (false, true) => 256,
        (true, false) => 0,
        _ => t,
    }
}

/// Blends `a` toward `b` by `t`/256 (`WEIGHT_BITS` = 8).
#[inline]
pub(crate) fn lerp(a: Rgb, b: Rgb, t: u32) -> Rgb {
    Lanes::of(a).lerp(Lanes::of(b), t).rgb()
}

/// A color in 16-bit lanes, as [`lerp`] blends it: a chain of blends (a
/// bilinear square, two levels' squares) stays in lanes and unpacks once.
/// A lane's sum in a blend is at most 255 · 256 + 128 < 2^16, so no carry
/// crosses lanes, and every channel is rounded as on its own.
///
/// On a 64-bit machine the three channels share one word, so a blend is
/// two products; on a 32-bit one red and blue share a word and green has
/// its own, since a 64-bit product there costs two (the one-word lanes
/// take the board's views from 594 to 606 instructions a pixel,
/// `scripts/board-bound`). The results are the same bit for bit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Lanes(LaneWord);

/// Red, green and blue in lanes 0, 1 and 2 of one word.
#[cfg(target_pointer_width = "64")]
type LaneWord = u64;
/// Red and blue in lanes 1 and 0 of the first word, green in the second.
#[cfg(not(target_pointer_width = "64"))]
type LaneWord = (u32, u32);

#[cfg(target_pointer_width = "64")]
impl Lanes {
    const HALF: u64 = 0x0080_0080_0080;
    const MASK: u64 = 0x00FF_00FF_00FF;

    #[inline(always)]
    pub(crate) fn of(c: Rgb) -> Self {
        Self(u64::from(c[0]) | (u64::from(c[1]) << 16) | (u64::from(c[2]) << 32))
    }

    /// Blends toward `other` by `t`/256.
    #[inline(always)]
    pub(crate) fn lerp(self, other: Self, t: u32) -> Self {
        let t = u64::from(t.min(256));
        Self(((self.0 * (256 - t) + other.0 * t + Self::HALF) >> 8) & Self::MASK)
    }

    /// The part of [`Lanes::lerp`] from `self` that does not depend on the
    /// other color: `self` by `weight` (at most 256), with the blend's
    /// rounding. A color blended toward many others by a table of weights
    /// (the fog's) keeps it for every weight.
    #[inline(always)]
    pub(crate) fn weighted(self, weight: u32) -> Self {
        Self(self.0 * u64::from(weight) + Self::HALF)
    }

    /// The blend [`Lanes::lerp`] gives from a color to `other` by `t`
    /// (at most 256), `self` that color [`Lanes::weighted`] by `256 − t`:
    /// one product.
    #[inline(always)]
    pub(crate) fn plus_weighted(self, other: Self, t: u32) -> Self {
        Self(((self.0 + other.0 * u64::from(t)) >> 8) & Self::MASK)
    }

    #[inline(always)]
    pub(crate) fn rgb(self) -> Rgb {
        [self.0 as u8, (self.0 >> 16) as u8, (self.0 >> 32) as u8]
    }
}

#[cfg(not(target_pointer_width = "64"))]
impl Lanes {
    #[inline(always)]
    pub(crate) fn of(c: Rgb) -> Self {
        Self(((u32::from(c[0]) << 16) | u32::from(c[2]), u32::from(c[1])))
    }

    /// Blends toward `other` by `t`/256.
    #[inline(always)]
    pub(crate) fn lerp(self, other: Self, t: u32) -> Self {
        let t = t.min(256);
        let (Self((red_blue, green)), Self((other_red_blue, other_green))) = (self, other);
        Self((
            ((red_blue * (256 - t) + other_red_blue * t + 0x0080_0080) >> 8) & 0x00FF_00FF,
            (green * (256 - t) + other_green * t + 128) >> 8,
        ))
    }

    /// The part of [`Lanes::lerp`] from `self` that does not depend on the
    /// other color: `self` by `weight` (at most 256), with the blend's
    /// rounding. A color blended toward many others by a table of weights
    /// (the fog's) keeps it for every weight.
    #[inline(always)]
    pub(crate) fn weighted(self, weight: u32) -> Self {
        let Self((red_blue, green)) = self;
        Self((red_blue * weight + 0x0080_0080, green * weight + 128))
    }

    /// The blend [`Lanes::lerp`] gives from a color to `other` by `t`
    /// (at most 256), `self` that color [`Lanes::weighted`] by `256 − t`:
    /// a product a word.
    #[inline(always)]
    pub(crate) fn plus_weighted(self, other: Self, t: u32) -> Self {
        let (Self((red_blue, green)), Self((other_red_blue, other_green))) = (self, other);
        Self((
            ((red_blue + other_red_blue * t) >> 8) & 0x00FF_00FF,
            (green + other_green * t) >> 8,
        ))
    }

    #[inline(always)]
    pub(crate) fn rgb(self) -> Rgb {
        let Self((red_blue, green)) = self;
        [(red_blue >> 16) as u8, green as u8, red_blue as u8]
    }
}

/// The outcome of a walk along one ray.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Walk<G> {
    /// The ray is at or below the surface at `at`, found on `stage`.
    /// `above` is the visited sample before it and its clearance, when the
    /// walk visited it.
    Hit {
        at: Cursor,
        clearance: i32,
        above: Option<(i32, i32)>,
        stage: Stage<G>,
    },
    /// The ray stopped above the surface: it was above at every sample it
    /// visited, up to `last`.
    Exit { last: i32 },
}

/// Walks from `at` along the ray, switching levels on schedule, until a hit
/// or the last visited sample not past `end`. The first sample is tested
/// against the `recent` cells; a hit's cell is left there for the next ray.
#[inline]
pub(crate) fn walk<'s, T: Surface + ?Sized, P: Probe>(
    surface: &'s T,
    ray: &Ray,
    mut at: Cursor,
    end: i32,
    recent: &mut Recent,
    probe: &mut P,
) -> Walk<T::Grid<'s>> {
    let mut last: Option<(i32, i32)> = None;
    let mut first = Some(&*recent);
    loop {
        let stage = Stage::new(surface, ray, at.level).near(&at);
        let switch = ray.next_switch(at.level, at.k);
        match stage.steps(at, end, switch, first.take(), &mut last, probe) {
            Run::Hit {
                k,
                base,
                minor,
                z,
                clearance,
                cell,
            } => {
                recent.add(cell);
                // The loop's values are the cursor: stepping lands on the
                // directly computed positions, on every level (tested
                // below).
                let at = Cursor {
                    k,
                    level: stage.level,
                    base,
                    minor,
                    z,
                };
                return Walk::Hit {
                    at,
                    clearance,
                    above: last,
                    stage,
                };
            }
            Run::Missing => {
                return Walk::Exit {
                    last: last.map_or(at.k - 1, |l| l.0),
                }
            }
            Run::Above => {}
        }
        // The run ended above the surface: the next sample begins the next
        // level, or is the ray's end between this level's lines.
        let Some((k, _)) = last else {
            return Walk::Exit { last: at.k - 1 };
        };
        let next = k + stage.stride();
        let next = if next <= end {
            next
        } else if k < end && end == ray.end {
            end
        } else {
            return Walk::Exit { last: k };
        };
        at = ray.cursor(surface, next);
    }
}

/// How a run of steps on one level ended.
enum Run {
    /// At sample `k` (loop values `base`, `minor`, `z`), in `cell`.
    Hit {
        k: i32,
        base: isize,
        minor: i32,
        z: i32,
        clearance: i32,
        cell: Cell,
    },
    /// Above the surface at its last sample, the one before the next
    /// level's first or the end.
    Above,
    /// An index outside the map (impossible for a clipped ray).
    Missing,
}

impl<G: Grid> Stage<G> {
    /// The per-step loop on this level, from `at` (not yet tested) up to
    /// the last sample before `switch` and not past `end`; `last` follows
    /// the last sample found above the surface. The first sample is read
    /// from `first` when it holds its cell. Only four values change per
    /// step; the caller rebuilds the full cursor at the exits.
    #[inline(always)]
    fn steps<P: Probe>(
        &self,
        at: Cursor,
        end: i32,
        switch: i32,
        mut first: Option<&Recent>,
        last: &mut Option<(i32, i32)>,
        probe: &mut P,
    ) -> Run {
        let (mut k, mut base, mut minor, mut z) = (at.k, at.base, at.minor, at.z);
        let stride = self.stride();
        // Step on while the next sample is before the switch and the end.
        let stop = end.min(switch.saturating_sub(1)).saturating_sub(stride);
        let mut above = *last;
        loop {
            let index = index(base, self.minor_stride, minor, self.level);
            let Some(cell) = self.cell(index, first.take(), probe) else {
                *last = above;
                return Run::Missing;
            };
            let clearance = self.clearance_in(&cell, minor, z);
            if clearance <= 0 {
                *last = above;
                return Run::Hit {
                    k,
                    base,
                    minor,
                    z,
                    clearance,
                    cell,
                };
            }
            above = Some((k, clearance));
            if k > stop {
                *last = above;
                return Run::Above;
            }
            k += stride;
            base += self.step;
            minor = minor.wrapping_add(self.dminor);
            z = z.wrapping_add(self.dz);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pyramid::{pyramid_cells, pyramid_points, Pyramid};
    use crate::terrain::Terrain;
    use crate::view::lod::LodPlan;
    use crate::view::{Camera, View};
    use std::vec;

    /// A blend from a color weighted once for its weight is the blend
    /// `lerp` gives, at every weight up to 256.
    #[test]
    fn a_blend_from_a_weighted_color_is_lerps_blend() {
        let colors: [Rgb; 4] = [[0, 0, 0], [255, 255, 255], [17, 200, 93], [254, 1, 128]];
        for a in colors {
            for b in colors {
                for t in 0..=256 {
                    let (a, b) = (Lanes::of(a), Lanes::of(b));
                    assert_eq!(
                        a.weighted(256 - t).plus_weighted(b, t),
                        a.lerp(b, t),
                        "{a:?} {b:?} {t}"
                    );
                }
            }
        }
    }

    /// The loop's four increments on every level are exactly the difference
    /// between the directly computed positions of successive samples: the
    /// increments double with the level and never drift.
    #[test]
    fn loop_increments_double_and_land_on_the_direct_positions() {
        let (h, c) = (vec![0u16; 64 * 64], vec![[0u8; 3]; 64 * 64]);
        let terrain = Terrain::new(64, 64, &h, &c).unwrap();
        let n = pyramid_points(64, 64);
        let (ph, pc, pb) = (vec![0; n], vec![[0; 3]; n], vec![0; pyramid_cells(64, 64)]);
        let pyramid = Pyramid::new(terrain, &ph, &pc, &pb).unwrap();
        for yaw in [0.0, 25.0, 110.0, 200.0, 300.0] {
            let camera = Camera {
                eye: [31.7, 30.2, 3.0],
                yaw_deg: yaw,
                ..Camera::default()
            };
            let view = View::new(&camera, 64, 8).unwrap();
            // Level 1 begins 14 voxels out (pixel-to-voxel ratio 4).
            let plan = LodPlan::new(&view, 4 << 8, 1 << 16, pyramid.top());
            for column in [0, 20, 63] {
                let ray = view.pixel_ray(&terrain.extent(), &plan, column, 48);
                let mut levels_seen = 0u8;
                let mut k = ray.start;
                loop {
                    let at = ray.cursor(&pyramid, k);
                    let stage = Stage::new(&pyramid, &ray, at.level);
                    levels_seen |= 1 << at.level;
                    if k + stage.stride() > ray.end {
                        break;
                    }
                    let next = ray.cursor(&pyramid, k + stage.stride());
                    if next.level == at.level {
                        assert_eq!(stage.dminor, ray.dminor.to_bits() << at.level);
                        assert_eq!(
                            (next.base - at.base, next.minor - at.minor, next.z - at.z),
                            (stage.step, stage.dminor, stage.dz),
                            "yaw {yaw} column {column} k {k} level {}",
                            at.level
                        );
                    }
                    k = next.k;
                }
                assert!(
                    levels_seen & 0b110 != 0,
                    "yaw {yaw}: no coarse level reached"
                );
            }
        }
    }
}
