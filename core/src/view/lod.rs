//! The frame's level-of-detail plan and a ray's level schedule: where
//! each pyramid level begins along a ray (Cohen-Or §2: a level begins
//! where a voxel of the level below gets narrower than a pixel, at an even
//! step of that level).

use super::words::clamp_in_place;
use super::View;
use crate::config::{COORD_FRAC_BITS, MAX_WALK_LEVEL};

const ONE: i64 = 1 << COORD_FRAC_BITS;

/// The frame's level-of-detail set-up.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LodPlan {
    /// Depth where level 1 begins, Q16 voxels.
    pub(in crate::view) level1_depth: i64,
    /// Highest level the frame may use.
    pub top: u8,
    /// Depth where colors begin to come from level 1, Q16: the ratio as
    /// given, not scaled by the terrain fit (colors have no height error
    /// to keep small; see [`Ray::color_reach`](super::ray::Ray::color_reach)).
    pub(in crate::view) color_level1_depth: i64,
}

impl LodPlan {
    /// Levels up to `top`, switching by `pixel_to_voxel` (U8.8; 0 counts as
    /// 1/256) scaled by `fit` (Q16, at most 1; see
    /// [`crate::roughness::terrain_fit`]; colors switch by the ratio
    /// alone).
    pub fn new(view: &View, pixel_to_voxel: u16, fit: u32, top: u8) -> Self {
        let pixel_to_voxel = i64::from(pixel_to_voxel.max(1));
        let ratio = pixel_to_voxel * i64::from(fit.clamp(1, 1 << 16));
        Self {
            level1_depth: (view.focal << 24) / ratio,
            top: top.min(MAX_WALK_LEVEL as u8),
            color_level1_depth: (view.focal << 8) / pixel_to_voxel,
        }
    }

    /// This plan with colors that never leave level 0 by depth
    /// ([`crate::Shading::LevelZero`]).
    pub fn without_far_colors(self) -> Self {
        Self {
            color_level1_depth: i64::MAX,
            ..self
        }
    }

    /// The major-axis distance (Q16) where level 1's heights begin for a
    /// ray whose direction's major-axis component is `run` (I32F32 bits):
    /// the depth where they begin times `run`.
    pub fn height_reach(&self, run: i64) -> i64 {
        clamp_in_place(
            (self.level1_depth.min(1 << 40) * (run >> 16)) >> 16,
            1,
            1 << 40,
        )
    }

    /// The major-axis distance (Q16) where colors begin to come from level
    /// 1 for a ray of major-axis component `run` (see [`Ray::color_reach`](super::ray::Ray::color_reach)).
    #[inline]
    pub fn color_reach(&self, run: i64) -> i64 {
        match self.color_level1_depth {
            i64::MAX => i64::MAX,
            depth => clamp_in_place((depth.min(1 << 40) * (run >> 16)) >> 16, 1, 1 << 40),
        }
    }

    /// One level only.
    pub const SINGLE: Self = Self {
        level1_depth: i64::MAX,
        top: 0,
        color_level1_depth: i64::MAX,
    };
}

/// A ray's level schedule. Two rays with equal `Lod` (and key) visit the
/// same samples at the same levels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Lod {
    /// Major-axis distance where level 1 begins, Q16 (level `l` begins at
    /// `reach << (l − 1)`).
    pub(in crate::view) reach: i64,
    /// Highest level this ray uses.
    pub top: u8,
}

impl Lod {
    /// The schedule of a ray of major-axis component `run` and height
    /// increment `dz` whose sample 0 is `delta0` from the eye and whose last
    /// sample is `end`.
    pub(crate) fn new(plan: &LodPlan, run: i64, dz: i64, delta0: i64, end: i64) -> Self {
        const SINGLE: Lod = Lod {
            reach: i64::MAX,
            top: 0,
        };
        // Doubling must keep the height increment inside I16F16 with room
        // for the height itself: |dz|·2^l <= 2^29.
        let mut top = plan.top;
        while top > 0 && (dz.abs() << top) > 1 << 29 {
            top -= 1;
        }
        if top == 0 {
            return SINGLE;
        }
        // reach = D1·|d_major|: Q16 times Q32 (taken as Q16), in range for
        // every depth and direction View accepts.
        let reach = plan.height_reach(run);
        // A ray that ends before level 1 can begin steps on level 0 only:
        // it needs no schedule. It samples exactly as with the levels it
        // never reaches.
        if first_sample_from(reach, delta0) > end {
            return SINGLE;
        }
        Self { reach, top }
    }

    /// The first sample at or past the major-axis distance where level
    /// `level` (at least 1) begins, for sample 0 at `delta0` (Q16).
    #[inline]
    pub(crate) fn first_sample_of(&self, level: u8, delta0: i64) -> i64 {
        first_sample_from(self.reach << (level - 1), delta0)
    }
}

/// The first sample at or past major-axis distance `distance` (Q16) on a
/// ray whose sample 0 is `delta0` (Q16) from the eye.
#[inline]
fn first_sample_from(distance: i64, delta0: i64) -> i64 {
    (distance - delta0 + ONE - 1) >> COORD_FRAC_BITS
}
