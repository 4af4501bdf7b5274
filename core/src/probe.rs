//! What the caster touches, reported as it happens.
//!
//! The simulator turns these events into time and traffic; tests count them.
//! Every method has an empty default body, so [`NoProbe`] compiles to nothing.

use crate::pyramid::MAX_LEVELS;

/// Receives the caster's memory events.
pub trait Probe {
    /// One traversal step on pyramid level `level`: the heights of voxel
    /// `voxel` of that level and of its neighbour across the minor grid line
    /// were fetched and compared with the ray.
    #[inline(always)]
    fn visit(&mut self, level: u8, voxel: usize) {
        let _ = (level, voxel);
    }
    /// One step of the hierarchical first hit: the height bound of cell
    /// `cell` of level `level` was compared with the ray.
    #[inline(always)]
    fn bound(&mut self, level: u8, cell: usize) {
        let _ = (level, cell);
    }
    /// The colors of voxel `voxel` of level `level` and its minor-axis
    /// neighbour were fetched to shade a pixel. With
    /// [`Probe::color_square`], at most [`MAX_COLOR_FETCHES_A_RAY`] a ray.
    #[inline(always)]
    fn color(&mut self, level: u8, voxel: usize) {
        let _ = (level, voxel);
    }
    /// Past the color reach, the four colors of the grid square whose
    /// first corner is voxel `corner` of level `level` (it and the next
    /// voxel on its row and on the row after) were fetched to shade a
    /// pixel. One color fetch as [`Probe::color`] is, and by default
    /// reported as one: a probe that counts bytes or memory traffic
    /// tells the two apart.
    #[inline(always)]
    fn color_square(&mut self, level: u8, corner: usize) {
        self.color(level, corner);
    }
    /// A ray hit the terrain on level `level`.
    #[inline(always)]
    fn hit(&mut self, level: u8) {
        let _ = level;
    }
    /// A ray was set up (one per pixel, or per vertical subsample).
    #[inline(always)]
    fn ray(&mut self) {}
    /// A secondary ray was cast through texels less than opaque (complex
    /// sticks, [`crate::StickTable::with_alphas`]): at most
    /// [`crate::MAX_SEE_THROUGH`] a pixel. Its steps are reported as
    /// [`Probe::visit`]s on level 0, its hit's colors as
    /// [`Probe::color`]s (beyond [`MAX_COLOR_FETCHES_A_RAY`]).
    #[inline(always)]
    fn secondary_ray(&mut self) {}
    /// A frame's render starts image line `index`: the events up to the
    /// next call are that line's. [`crate::render`],
    /// [`crate::render_by_footprint`] and [`crate::Governor::render`]
    /// report each line they render, the governor's refinement rounds
    /// each line again; a one-line render ([`crate::render_line`]) does
    /// not.
    #[inline(always)]
    fn line(&mut self, index: u32) {
        let _ = index;
    }
}

/// The most color fetches ([`Probe::color`], [`Probe::color_square`]) the
/// caster makes for one ray:
/// a hit is shaded from its own grid line and the one before it (near the
/// eye) or from two levels around the crossing (farther out), a ray cut
/// short from the grid line under it, and a sky ray from none. (A fetch
/// that finds no color, outside the map, is not reported.) A cost model
/// can reserve this much shading a ray before the frame is rendered.
pub const MAX_COLOR_FETCHES_A_RAY: u32 = 2;

/// The probe that observes nothing and costs nothing.
#[derive(Debug, Default, Clone, Copy)]
pub struct NoProbe;

impl Probe for NoProbe {}

/// Counts events: steps, color fetches, rays, and steps and hits by level.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct CountingProbe {
    /// Traversal steps: walk steps plus first-hit bound tests.
    pub steps: u64,
    /// Of `steps`, the first-hit bound tests.
    pub bound_tests: u64,
    /// Color fetches (one per shaded grid-line sample).
    pub color_fetches: u64,
    /// Of `color_fetches`, the squares of four texels a far hit's
    /// footprint blends ([`Probe::color_square`]).
    pub color_squares: u64,
    /// Rays set up.
    pub rays: u64,
    /// Secondary rays cast through texels less than opaque.
    pub secondary_rays: u64,
    /// Walk steps on each pyramid level.
    pub steps_by_level: [u64; MAX_LEVELS],
    /// Rays that hit on each pyramid level.
    pub hits_by_level: [u64; MAX_LEVELS],
}

/// Adds one to slot `level` (the last slot for anything higher).
#[inline(always)]
fn count(slots: &mut [u64; MAX_LEVELS], level: u8) {
    slots[usize::from(level).min(MAX_LEVELS - 1)] += 1;
}

impl Probe for CountingProbe {
    #[inline(always)]
    fn visit(&mut self, level: u8, _voxel: usize) {
        self.steps += 1;
        count(&mut self.steps_by_level, level);
    }
    #[inline(always)]
    fn bound(&mut self, _level: u8, _cell: usize) {
        self.steps += 1;
        self.bound_tests += 1;
    }
    #[inline(always)]
    fn color(&mut self, _level: u8, _voxel: usize) {
        self.color_fetches += 1;
    }
    #[inline(always)]
    fn color_square(&mut self, _level: u8, _corner: usize) {
        self.color_fetches += 1;
        self.color_squares += 1;
    }
    #[inline(always)]
    fn hit(&mut self, level: u8) {
        count(&mut self.hits_by_level, level);
    }
    #[inline(always)]
    fn ray(&mut self) {
        self.rays += 1;
    }
    #[inline(always)]
    fn secondary_ray(&mut self) {
        self.secondary_rays += 1;
    }
}
