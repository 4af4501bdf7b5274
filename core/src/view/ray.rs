//! Per-ray set-up: direction, major axis, fixed-point increments, clipping,
//! and the schedule of pyramid levels along the ray.
//!
//! Integer arithmetic only (one division per increment, per ray, as in
//! Cohen-Or's Figure 7). A ray samples the terrain on the grid lines of its
//! major axis: sample `k` lies on grid line `major0 + k·sign` at distance
//! `delta0 + k` voxels from the eye along that axis. Clipping bounds `k` so
//! that every sample the caster visits is inside the map and every
//! fixed-point value stays in range.
//!
//! # Levels along a ray
//! Level `l ≥ 1` begins where a voxel of level `l − 1` gets narrower than a
//! pixel: at depth `2^(l−1)·D1`, `D1 = focal / pixel_to_voxel`. On a ray of
//! major-axis component `|d_major|` (the forward component is 1) that is the
//! major-axis distance `2^(l−1)·reach`, `reach = D1·|d_major|`. The ray
//! switches at the first sample past that distance whose grid line is a
//! line of level `l` (the even-step rule, Figure 8), so it visits sample `k`
//! at level `l` only when `major(k)` is a multiple of `2^l`, and steps there
//! by `2^l`, with doubled increments.
//!
//! Colors have a schedule of their own (`Ray::color_reach`, by the ratio
//! as given; see `caster::footprint_color`), blended between levels by
//! depth, so they do not jump where the heights switch.

use super::lod::{Lod, LodPlan};
use super::plane::{slope_quotient, to_word, Plane};
use super::words::{clamp_in_place, narrow, saturate};
use super::View;
use crate::config::{COORD_FRAC_BITS, HEIGHT_FRAC_BITS, MAX_WALK_LEVEL};
use crate::divide::{div_ceil, div_floor};
use crate::surface::{Extent, Surface};
use fixed::types::I16F16;

/// Which family of grid lines a ray steps across. Two rays with the same key
/// number their samples identically, so one can resume where the other hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RayKey {
    pub x_major: bool,
    pub forward: bool,
}

/// One ray, ready to traverse.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ray {
    pub key: RayKey,
    /// Major-axis grid coordinate of sample 0.
    major0: i64,
    /// Distance from the eye to sample 0 along the major axis, Q16 in [0, 1).
    delta0: i64,
    /// Minor coordinate and height at sample 0, Q16.
    minor0: i64,
    z0: i64,
    /// Per-step (level 0) increments of the minor coordinate and height.
    pub dminor: I16F16,
    pub dz: I16F16,
    /// First sample inside the map; may be −1 (one step behind the eye),
    /// which only the hit refinement reads.
    pub first: i32,
    /// First sample the traversal visits.
    pub start: i32,
    /// Last sample where a hit is possible.
    pub end: i32,
    /// `end` is where the ray leaves a map with real edges (not where it
    /// rises above the highest terrain or sinks below 0).
    edge_end: bool,
    /// Largest minor coordinate inside the map, Q16.
    pub minor_max: i32,
    /// Minor-coordinate drift per major step of the pixel center's own ray
    /// from this one, Q16 (see [`Plane::drift`]); colors are looked up
    /// that far aside.
    pub color_drift: i32,
    pub lod: Lod,
    /// Major-axis distance where colors begin to come from level 1, Q16
    /// (`i64::MAX` at single resolution): level `l` is blended in from
    /// `reach << (l − 1)`. Colors have their own schedule, by the ratio as
    /// given: a coarse level's heights are off by the terrain's detail,
    /// which the terrain fit keeps in check by moving the height levels
    /// out; its colors are the same photo, low-passed, which is what a
    /// pixel as wide as a voxel of that level should show.
    pub color_reach: i64,
    /// The highest level colors may come from: the frame's, whatever this
    /// ray's heights may use.
    pub color_top: u8,
    /// The level schedule, worked out once per ray because the caster asks
    /// for it several times a ray: `begins[l]` is the first sample of level
    /// `l` (`begins[0] = first`), known for `l < known`, which covers every
    /// level up to the one in effect at `end`. Samples past that are
    /// scheduled on demand (only the coherence proof asks about them). A
    /// ray that ends before level 1 can begin has no levels at all
    /// (`lod.top` is 0), at any sample.
    begins: [i32; LEVEL_SLOTS],
    known: u8,
}

/// Levels a ray may use: 0 to `MAX_WALK_LEVEL`.
const LEVEL_SLOTS: usize = MAX_WALK_LEVEL as usize + 1;

/// Where sample `k` of a ray is, on its level.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cursor {
    pub k: i32,
    pub level: u8,
    /// Index of the level's grid-line start (`floor(minor) = 0`) in the
    /// level's grid.
    pub base: isize,
    /// Minor coordinate (world voxels) and height, Q16.
    pub minor: i32,
    pub z: i32,
}

impl View {
    /// The height change per major-axis step (Q16) of direction `d` in
    /// `plane`, and the run: `d`'s major component (I32F32 bits).
    #[inline]
    pub(crate) fn slope(d: &[i64; 3], plane: &Plane) -> (i64, i64) {
        Self::slope_of(if plane.key.x_major { d[0] } else { d[1] }, d[2], plane)
    }

    /// [`View::slope`] from the direction's major-axis and vertical
    /// components alone.
    #[inline]
    pub(crate) fn slope_of(d_major: i64, d_up: i64, plane: &Plane) -> (i64, i64) {
        let forward = plane.key.forward;
        // Within rounding of the vanishing point the sign may disagree: that
        // ray is vertical.
        let run = if forward { d_major } else { -d_major }.max(0);
        (
            i64::from(slope_quotient(to_word(d_up), to_word(run) as u32)),
            run,
        )
    }

    /// The slope of direction `d` (I32F32 bits) in `plane` and the samples
    /// where a ray along it can hit: the part of a ray's set-up that tells
    /// whether it needs the rest (see [`View::ray_with`]).
    #[inline]
    pub(crate) fn clip(&self, extent: &Extent, d: &[i64; 3], plane: &Plane) -> Clip {
        let (dz, run) = Self::slope(d, plane);
        let (first, last) = (plane.first, plane.last);
        let z0 = self.eye[2].to_bits() + ((plane.delta0 * dz) >> COORD_FRAC_BITS);
        let start = first.max(0);
        // A hit needs the ray at or below the highest height; a falling ray
        // is certainly below the surface once its height is <= 0.
        let top = i64::from(extent.max_height) << (COORD_FRAC_BITS - HEIGHT_FRAC_BITS);
        let end = match dz.signum() {
            1 => last.min(div_floor(top - z0, dz)),
            0 if z0 > top => start - 1,
            0 => last,
            _ => last.min(start.max(div_ceil(z0, -dz))),
        };
        Clip {
            dz,
            run,
            z0,
            wide_end: end,
            start: narrow(start),
            end: narrow(end),
        }
    }

    /// Sets up the ray clipped by [`View::clip`]: everything the walk
    /// needs. Its level schedule is worked out on demand until the caller
    /// calls [`Ray::schedule`], in its own storage: scheduling here, before
    /// the return, made the board copy the ray's 144 bytes every ray
    /// (about 100 instructions a pixel).
    #[inline]
    pub(crate) fn ray_with(
        &self,
        extent: &Extent,
        plan: &LodPlan,
        plane: &Plane,
        clip: &Clip,
    ) -> Ray {
        let Plane {
            key,
            dminor,
            major0,
            delta0,
            minor0,
            first,
            last,
            minor_max,
            ..
        } = *plane;
        let Clip {
            dz,
            run,
            z0,
            wide_end: end,
            start,
            end: narrow_end,
        } = *clip;
        let edge_end = extent.real_edges && end == last;
        Ray {
            key,
            major0,
            delta0,
            minor0,
            z0,
            dminor: I16F16::from_bits(dminor as i32),
            dz: I16F16::from_bits(dz as i32),
            first: narrow(first),
            start,
            end: narrow_end,
            edge_end,
            minor_max: minor_max.clamp(0, i64::from(i32::MAX)) as i32,
            color_drift: 0,
            lod: Lod::new(plan, run, dz, delta0, end),
            color_reach: plan.color_reach(run),
            color_top: plan.top,
            begins: [i32::MAX; LEVEL_SLOTS],
            known: 1,
        }
    }
}

/// A ray's slope and the samples where it can hit (see [`View::clip`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Clip {
    /// Height change per major-axis step, Q16.
    pub dz: i64,
    /// The direction's major-axis component (I32F32 bits).
    run: i64,
    /// Height at sample 0, Q16.
    z0: i64,
    /// `end` before narrowing.
    wide_end: i64,
    /// First sample the traversal visits and last where a hit is
    /// possible, as [`Ray::start`] and [`Ray::end`] will have them: no
    /// hit at all when `start > end`.
    pub start: i32,
    pub end: i32,
}

impl Ray {
    /// Works out `begins` for every level up to the first that begins past
    /// the end (or the top), so that the caster need not work them out
    /// each time it asks. Without it the answers are the same.
    pub(crate) fn schedule(&mut self) {
        // Entries from `known` on are never read.
        self.begins[0] = self.first;
        let top = usize::from(self.lod.top).min(LEVEL_SLOTS - 1);
        let mut level = 1;
        while level <= top && self.begins[level - 1] <= self.end {
            self.begins[level] = self.switch_sample(level as u8, self.begins[level - 1]);
            level += 1;
        }
        self.known = level as u8;
    }

    /// Major-axis grid coordinate of sample `k`.
    #[inline]
    pub fn major_at(&self, k: i32) -> i64 {
        if self.key.forward {
            self.major0 + i64::from(k)
        } else {
            self.major0 - i64::from(k)
        }
    }

    /// Whether sample `k` lies on a grid line of `level`.
    pub fn on_level_grid(&self, k: i32, level: u8) -> bool {
        self.major_at(k) & ((1 << level) - 1) == 0
    }

    /// The first sample at or after `k` on a grid line of `level`.
    #[inline]
    pub fn align_up(&self, k: i32, level: u8) -> i32 {
        let mask = (1i64 << level) - 1;
        let m = self.major_at(k);
        let to = if self.key.forward {
            ((m + mask) & !mask) - self.major0
        } else {
            self.major0 - (m & !mask)
        };
        to.min(i64::from(i32::MAX)) as i32
    }

    /// The first sample at the distance where `level` begins, or beyond.
    #[inline]
    fn threshold(&self, level: u8) -> i32 {
        saturate(self.lod.first_sample_of(level, self.delta0))
    }

    /// Where a ray at level `level − 1`, at sample `k` (on or past that
    /// level's first sample), switches to `level`: the first sample of
    /// `level`'s grid at or past both `k` and the level's distance.
    #[inline]
    pub fn switch_sample(&self, level: u8, k: i32) -> i32 {
        self.align_up(k.max(self.threshold(level)), level)
    }

    /// The first sample of the level after `level`, seen from sample `k` of
    /// `level` (`i32::MAX` at the top level).
    #[inline]
    pub fn next_switch(&self, level: u8, k: i32) -> i32 {
        if level >= self.lod.top {
            return i32::MAX;
        }
        let l = usize::from(level);
        if l + 1 < usize::from(self.known) {
            // On the schedule, `switch_sample` gives the next level's first
            // sample; off it (a cursor moved to another level), work it out.
            let (begins, next) = (self.begins[l], self.begins[l + 1]);
            if begins <= k && k < next {
                return next;
            }
        }
        self.switch_sample(level + 1, k)
    }

    /// The level in effect at sample `k`.
    #[inline]
    pub fn level_at(&self, k: i32) -> u8 {
        let (mut level, mut begins) = (0u8, self.first);
        // The levels worked out at set-up first.
        while level < self.lod.top && level + 1 < self.known {
            let next = self.begins[usize::from(level) + 1];
            if next > k {
                return level;
            }
            level += 1;
            begins = next;
        }
        while level < self.lod.top {
            let next = self.switch_sample(level + 1, begins);
            if next > k {
                break;
            }
            level += 1;
            begins = next;
        }
        level
    }

    /// Whether `k` is the ray's end sample and lies between the grid lines
    /// of its level: a walk tests it anyway, so that a ray that ends inside
    /// the map (below the ground, or at its edge) cannot step over its last
    /// hit. Where the ray leaves a map with real edges it is tested on
    /// level 0 (the edge keeps its silhouette); elsewhere on its level,
    /// against the grid line at or before it, so that a frame reads each
    /// level only out to that level's distance, and level 0 along the map's
    /// edges, which is what a tile footprint holds.
    #[inline]
    fn is_extra_end(&self, k: i32) -> bool {
        k == self.end && !self.on_level_grid(k, self.level_at(k))
    }

    /// The first sample at or after `k` that a walk from the eye visits.
    pub fn next_visited(&self, k: i32) -> i32 {
        let on_grid = self.align_up(k, self.level_at(k));
        if on_grid > self.end && k <= self.end {
            self.end
        } else {
            on_grid
        }
    }

    /// The sample a walk from the eye visits just before sample `k` (which
    /// it must visit itself).
    #[inline]
    pub fn previous_visited(&self, k: i32) -> i32 {
        if k <= self.first {
            return k - 1;
        }
        if self.is_extra_end(k) {
            // The last grid line of its level before it.
            let level = self.level_at(k);
            let up = self.align_up(k, level);
            return up - (1 << level);
        }
        k - (1 << self.level_at(k - 1))
    }

    /// The position of sample `k` on its level, computed directly (not by
    /// stepping), so a resumed ray sees exactly the values it would have
    /// reached by walking.
    #[inline]
    pub fn cursor<T: Surface + ?Sized>(&self, surface: &T, k: i32) -> Cursor {
        let level = if self.edge_end && self.is_extra_end(k) {
            0
        } else {
            self.level_at(k)
        };
        self.cursor_on(surface, k, level)
    }

    /// The position of sample `k` before `hit` (a sample this ray visited,
    /// `k < hit.k`), as [`Ray::cursor`] has it. Levels never fall along a
    /// ray, so behind a hit on level 0 (other than one tested on level 0
    /// only for being the ray's end at a map edge) it is on level 0 too,
    /// and its level need not be worked out: most hits are shaded this way.
    #[inline]
    pub fn cursor_before<T: Surface + ?Sized>(&self, surface: &T, hit: &Cursor, k: i32) -> Cursor {
        if hit.level == 0 && !(self.edge_end && hit.k == self.end) {
            self.cursor_on(surface, k, 0)
        } else {
            self.cursor(surface, k)
        }
    }

    /// The position of sample `k` on `level`, whatever the schedule says.
    #[inline]
    fn cursor_on<T: Surface + ?Sized>(&self, surface: &T, k: i32, level: u8) -> Cursor {
        let major = self.major_at(k);
        let stride = if self.key.x_major {
            1
        } else {
            surface.stride(level).unwrap_or(1)
        };
        let k64 = i64::from(k);
        // Inside [first, end] both values are in range by construction;
        // saturating keeps an out-of-range request harmless (it reads as
        // far below the surface, or as outside the map).
        Cursor {
            k,
            level,
            base: (major >> level) as isize * stride,
            minor: saturate(self.minor0 + k64 * i64::from(self.dminor.to_bits())),
            z: saturate(self.z0 + k64 * i64::from(self.dz.to_bits())),
        }
    }

    /// Where to look up the color of `at`: its minor coordinate moved by the
    /// color drift over the distance to it, kept inside the map.
    #[inline]
    pub fn color_cursor(&self, at: &Cursor) -> Cursor {
        if self.color_drift == 0 {
            return *at;
        }
        let aside = (i64::from(self.color_drift) * self.distance(at.k)) >> COORD_FRAC_BITS;
        let minor = clamp_in_place(i64::from(at.minor) + aside, 0, i64::from(self.minor_max));
        Cursor {
            minor: minor as i32,
            ..*at
        }
    }

    /// The distance from the eye along the major axis, Q16, of the point
    /// `k`/256 samples from sample 0 (never negative).
    #[inline]
    pub fn distance_q8(&self, k: i64) -> i64 {
        (self.delta0 + (k << (COORD_FRAC_BITS - 8))).max(0)
    }

    /// The world position (x, y), Q16, of the point `k`/256 samples from
    /// sample 0, `distance` ([`Ray::distance_q8`]) from the eye, its minor
    /// coordinate moved by the color drift as [`Ray::color_cursor`] moves
    /// it: where a crossing's color is looked up.
    #[inline]
    pub fn color_point(&self, k: i64, distance: i64) -> [i64; 2] {
        let along = k << (COORD_FRAC_BITS - 8);
        let major =
            (self.major0 << COORD_FRAC_BITS) + if self.key.forward { along } else { -along };
        let mut minor = self.minor0 + ((k * i64::from(self.dminor.to_bits())) >> 8);
        if self.color_drift != 0 {
            minor += (i64::from(self.color_drift) * distance) >> COORD_FRAC_BITS;
        }
        let minor = clamp_in_place(minor, 0, i64::from(self.minor_max));
        if self.key.x_major {
            [major, minor]
        } else {
            [minor, major]
        }
    }

    /// Minor coordinate and height at sample `k`, Q16, without narrowing.
    #[inline]
    pub fn position(&self, k: i32) -> (i64, i64) {
        let k = i64::from(k);
        (
            self.minor0 + k * i64::from(self.dminor.to_bits()),
            self.z0 + k * i64::from(self.dz.to_bits()),
        )
    }

    /// Distance from the eye along the major axis to sample `k`, Q16, never
    /// negative.
    #[inline]
    pub fn distance(&self, k: i32) -> i64 {
        (self.delta0 + (i64::from(k) << COORD_FRAC_BITS)).max(0)
    }
}

#[cfg(test)]
impl View {
    /// The ray through the center of pixel column `column`, `row16`
    /// sixteenths of a pixel above the bottom row's center, with its own
    /// plane (for tests of the ray itself).
    pub(crate) fn pixel_ray(
        &self,
        extent: &Extent,
        plan: &LodPlan,
        column: u32,
        row16: i64,
    ) -> Ray {
        let d: [i64; 3] = core::array::from_fn(|i| {
            self.base[i].to_bits()
                + self.per_column[i].to_bits() * i64::from(column)
                + ((self.per_row[i].to_bits() * row16) >> 4)
        });
        let plane = Plane::new(self, extent, &d);
        let mut ray = self.ray_with(extent, plan, &plane, &self.clip(extent, &d, &plane));
        ray.schedule();
        ray
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::caster::walk::Stage;
    use crate::view::Camera;
    use crate::{Pyramid, Terrain};

    fn flat(side: u32, height: u16) -> (std::vec::Vec<u16>, std::vec::Vec<[u8; 3]>) {
        let n = (side * side) as usize;
        (std::vec![height; n], std::vec![[0; 3]; n])
    }

    #[test]
    fn samples_inside_the_clip_range_are_inside_the_map() {
        let (h, c) = flat(16, 0);
        let terrain = Terrain::new(16, 16, &h, &c).unwrap();
        let pyramid = Pyramid::flat(terrain);
        for yaw in [0.0, 37.0, 90.0, 150.0, 200.0, 271.0, 333.0] {
            let cam = Camera::looking([-5.5, 7.25, 20.0], yaw, 10.0);
            let view = View::new(&cam, 32, 8).unwrap();
            for col in 0..32 {
                for row in 0..8 {
                    let ray = view.pixel_ray(&terrain.extent(), &LodPlan::SINGLE, col, row * 16);
                    let stage = Stage::new(&pyramid, &ray, 0);
                    for k in ray.first..=ray.end {
                        let cur = ray.cursor(&pyramid, k);
                        assert!(stage.clearance(&cur).is_some(), "yaw {yaw} k {k}");
                    }
                }
            }
        }
    }

    /// A ray over a long map with levels 0 to 4, switching at `reach`.
    /// A level ray across a 64-voxel map that runs to the map's far edge
    /// (the terrain, above the eye, keeps it from ending early).
    fn ray_with_levels(forward: bool, eye_x: f32) -> Ray {
        let (h, c) = flat(64, 1000);
        let terrain = Terrain::new(64, 64, &h, &c).unwrap();
        let cam = Camera {
            eye: [eye_x, 31.5, 3.0],
            yaw_deg: if forward { 0.0 } else { 180.0 },
            ..Camera::default()
        };
        let view = View::new(&cam, 64, 1).unwrap();
        let plan = LodPlan {
            level1_depth: 3 << 16,
            top: 4,
            color_level1_depth: i64::MAX,
        };
        view.pixel_ray(&terrain.extent(), &plan, 32, 0)
    }

    #[test]
    fn a_scheduled_and_an_unscheduled_ray_give_the_on_demand_levels() {
        for (forward, eye_x) in [(true, 0.3), (true, 5.0), (false, 63.2), (false, 50.0)] {
            let mut ray = ray_with_levels(forward, eye_x);
            for end in [ray.first - 1, ray.first, 3, 9, 17, 30, 61] {
                ray.end = end;
                ray.schedule();
                // As `View::ray_with` returns it, before its schedule.
                let unscheduled = Ray { known: 1, ..ray };
                // On demand: each level's first sample from the one before.
                let on_demand = |k: i32| {
                    let (mut level, mut begins) = (0u8, ray.first);
                    while level < ray.lod.top {
                        let next = ray.switch_sample(level + 1, begins);
                        if next > k {
                            break;
                        }
                        level += 1;
                        begins = next;
                    }
                    level
                };
                for k in ray.first - 2..80 {
                    let level = ray.level_at(k);
                    assert_eq!(level, on_demand(k), "end {end} k {k}");
                    assert_eq!(unscheduled.level_at(k), level, "end {end} k {k}");
                    for l in 0..ray.lod.top {
                        let next = ray.switch_sample(l + 1, k);
                        assert_eq!(ray.next_switch(l, k), next, "end {end} k {k} level {l}");
                        assert_eq!(
                            unscheduled.next_switch(l, k),
                            next,
                            "end {end} k {k} level {l}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_ray_that_ends_before_level_one_has_no_schedule() {
        // Looking 30° down from 3 voxels over flat ground at height 0, the
        // ray is at the ground about 5 voxels out, before level 1 begins at
        // 20: no level, no weight.
        let (h, c) = flat(64, 0);
        let terrain = Terrain::new(64, 64, &h, &c).unwrap();
        let cam = Camera {
            eye: [0.3, 31.5, 3.0],
            pitch_deg: 30.0,
            ..Camera::default()
        };
        let view = View::new(&cam, 64, 1).unwrap();
        let plan = LodPlan {
            level1_depth: 20 << 16,
            top: 4,
            color_level1_depth: i64::MAX,
        };
        let short = view.pixel_ray(&terrain.extent(), &plan, 32, 0);
        assert!((3..=8).contains(&short.end), "end {}", short.end);
        assert_eq!((short.lod.top, short.lod.reach), (0, i64::MAX));
        assert!((short.first..=short.end).all(|k| short.level_at(k) == 0));
        // A ray with room to run keeps its levels.
        let long = ray_with_levels(true, 0.3);
        assert_eq!(long.lod.top, 4);
        assert!(long.lod.reach < i64::MAX);
    }

    /// `cursor_before` skips working out the level behind a level-0 hit;
    /// it must locate every visited sample as `cursor` does, on every
    /// level, along both axes, at the map's edge and away from it.
    #[test]
    fn the_sample_before_a_hit_is_where_the_schedule_puts_it() {
        use crate::pyramid::{pyramid_cells, pyramid_points};
        let (h, c) = flat(64, 1000);
        let terrain = Terrain::new(64, 64, &h, &c).unwrap();
        let n = pyramid_points(64, 64);
        let (ph, pc) = (std::vec![0; n], std::vec![[0; 3]; n]);
        let pb = std::vec![0; pyramid_cells(64, 64)];
        let pyramid = Pyramid::new(terrain, &ph, &pc, &pb).unwrap();
        let plan = LodPlan {
            level1_depth: 3 << 16,
            top: 4,
            color_level1_depth: i64::MAX,
        };
        let same = |a: &Cursor, b: &Cursor| {
            (a.k, a.level, a.base, a.minor, a.z) == (b.k, b.level, b.base, b.minor, b.z)
        };
        for (eye, yaw) in [
            ([0.3, 31.5], 0.0),
            ([31.5, 0.3], 90.0),
            ([63.2, 20.0], 190.0),
        ] {
            let cam = Camera::looking([eye[0], eye[1], 3.0], yaw, 0.0);
            let view = View::new(&cam, 64, 1).unwrap();
            let full = view.pixel_ray(&terrain.extent(), &plan, 32, 0);
            for (end, edge_end) in [(full.end, true), (full.end, false), (40, false), (9, false)] {
                let mut ray = Ray {
                    end,
                    edge_end,
                    ..full
                };
                ray.schedule();
                let mut k = ray.start;
                let mut checked = 0;
                while k <= ray.end {
                    let hit = ray.cursor(&pyramid, k);
                    let before = ray.previous_visited(k);
                    if before >= ray.start {
                        let expected = ray.cursor(&pyramid, before);
                        let found = ray.cursor_before(&pyramid, &hit, before);
                        assert!(same(&found, &expected), "yaw {yaw} end {end} k {k}");
                        checked += 1;
                    }
                    k = if k == ray.end {
                        k + 1
                    } else {
                        ray.next_visited(k + 1)
                    };
                }
                assert!(checked > 4, "yaw {yaw} end {end}: {checked} samples");
            }
        }
    }

    #[test]
    fn levels_switch_only_on_coarser_grid_lines() {
        for (forward, eye_x) in [(true, 0.3), (true, 5.0), (false, 63.2), (false, 50.0)] {
            let ray = ray_with_levels(forward, eye_x);
            let mut k = ray.start;
            let mut level = 0;
            let mut visited = std::vec::Vec::new();
            while k <= 60 {
                let now = ray.level_at(k);
                assert!(now >= level, "levels never go back down");
                if now > level {
                    // The even-step rule: the first sample of a level is on
                    // its grid, and the ray got there on the finer one.
                    assert!(ray.on_level_grid(k, now), "{forward} {eye_x} k {k}");
                    assert_eq!(now, level + 1, "one level at a time");
                    level = now;
                }
                visited.push(k);
                assert!(ray.on_level_grid(k, level));
                assert_eq!(ray.next_visited(k), k);
                // Increments double with the level.
                let next = k + (1 << level);
                if next <= 60 && ray.level_at(next) >= level {
                    assert_eq!(ray.previous_visited(next), k);
                }
                k = next;
            }
            assert_eq!(level, 4, "reached the top level");
            // Distances where levels begin grow by two each level.
            let begins: std::vec::Vec<i64> = (1..=4u8)
                .map(|l| ray.distance(ray.switch_sample(l, ray.threshold(l))))
                .collect();
            for pair in begins.windows(2) {
                assert!(pair[1] >= 2 * pair[0] - (16 << 16), "{begins:?}");
            }
        }
    }
}
