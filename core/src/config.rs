//! Number formats and limits of the kernel, in one place.
//!
//! Every range check the kernel makes at set-up comes from these constants,
//! and every overflow argument in the per-step loop rests on them. The README
//! has a table of them.

/// Fractional bits of the per-step fixed-point values: the minor coordinate,
/// the ray height and their increments are `I16F16` (range ±32768, step
/// 1/65536 voxel).
pub const COORD_FRAC_BITS: u32 = 16;

/// Fractional bits of a stored height: heights are unsigned U12.4 in a `u16`
/// (0 to 4095.9375 voxels in steps of 1/16).
pub const HEIGHT_FRAC_BITS: u32 = 4;

/// Bits of a color weight: the fraction of the minor coordinate, taken by
/// shift and mask, in 1/256 of a voxel.
pub const WEIGHT_BITS: u32 = 8;

/// Bits of the weight that blends the two heights across a grid line in the
/// hit test. With U12.4 heights, 12 bits land the blend exactly on I16F16,
/// and `(h1 − h0)·w` stays inside `i32`.
pub const HEIGHT_WEIGHT_BITS: u32 = COORD_FRAC_BITS - HEIGHT_FRAC_BITS;

/// Largest map side in voxels. The minor coordinate must stay inside
/// `I16F16`, and a voxel index must fit a 32-bit `usize`.
pub const MAX_MAP_SIDE: u32 = 32_767;

/// Largest |x| and |y| of the eye, in voxels (the eye may be outside the map).
pub const MAX_EYE_COORD: f32 = 32_000.0;

/// Largest |z| of the eye, in voxels. With [`MAX_RAY_SLOPE`] and the largest
/// height this keeps every ray height inside `I16F16`.
pub const MAX_EYE_HEIGHT: f32 = 16_000.0;

/// Steepest ray slope, in height units per major-axis step. Steeper rays
/// (within 0.007° of vertical) are clamped to it; they hit within two steps.
pub const MAX_RAY_SLOPE: i32 = 8_192;

/// Highest level a pyramid can have: a map of [`MAX_MAP_SIDE`] has levels
/// 0 to 15.
pub const MAX_LEVEL: u32 = 15;

/// Highest level the caster steps on. A step there is `2^14` voxels, which
/// keeps the doubled minor increment inside `I16F16`; rays steeper than
/// `2^(13 − l)` (height units per voxel) stop doubling before level `l` so
/// their height increment stays in range too.
pub const MAX_WALK_LEVEL: u32 = 14;

/// Finest photo detail over the height grid, as a shift: a
/// [`crate::Detail`] is 2 to `2^MAX_DETAIL_SHIFT` (32) times finer than
/// level 0 on each side.
pub const MAX_DETAIL_SHIFT: u32 = 5;

/// Largest image side in pixels.
pub const MAX_IMAGE_SIDE: u32 = 8_192;

/// Narrowest and widest horizontal field of view, in degrees.
pub const HFOV_RANGE_DEG: (f32, f32) = (1.0, 160.0);

/// Largest vertical half-angle tangent (`tan(hfov/2) · H / W`). Bounds the ray
/// direction vectors so their fixed-point forms cannot overflow.
pub const MAX_VERTICAL_TANGENT: f32 = 64.0;

/// Pitch range in degrees: −89 (looking up) to +90 (straight down).
pub const PITCH_RANGE_DEG: (f32, f32) = (-89.0, 90.0);

/// Roll range in degrees (−180 and 180 are the same bank, upside down).
pub const ROLL_RANGE_DEG: (f32, f32) = (-180.0, 180.0);

/// Default sky color of the view contract.
pub const DEFAULT_SKY: crate::color::Rgb = [135, 185, 235];

/// Default full horizontal field of view of the view contract, degrees.
pub const DEFAULT_HFOV_DEG: f32 = 60.0;
