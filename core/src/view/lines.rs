//! Image lines through the vertical vanishing point: the caster's unit of
//! work.
//!
//! Vertical ray coherence needs rays in one vertical plane (Cohen-Or §2).
//! Under a pitched camera an image column is not one: its rays drift
//! sideways as they rise, and at steep pitch a column even crosses the
//! nadir. The images of vertical planes are the lines through the vanishing
//! point `V` of the vertical (the nadir's image when looking down, the
//! zenith's when looking up; at pitch 0 it is at infinity and the lines are
//! the columns). So the caster works along those lines, as Qu et al. (§5)
//! work along pixel lines for roll.
//!
//! # Which line owns which pixel
//! Lines through `V` split the image into up to four sectors by the two
//! diagonals through `V`: above and below `V` the lines are steeper than 45°
//! and step row by row; left and right of it they step column by column. In
//! a sector, line `K` is the one through `V` and the point at cross
//! coordinate `K` on the sector's far edge (the top row for the sector above
//! `V`, the left column for the sector left of it, and so on). Lines are one
//! pixel apart on the far edge and closer everywhere else, so each pixel is
//! within half a pixel of the line nearest it, which owns it, and a line
//! owns at most one pixel a row (or column). Ownership is decided by exact
//! integer comparisons in Q8 pixel coordinates, so every pixel of the image
//! belongs to exactly one line of one sector (tested).
//!
//! A pixel's ray takes the horizontal direction of its line's point at the
//! pixel's row (or column), at most half a pixel from the pixel's center,
//! and all rays of a line share it, bit for bit: each ray of a line can
//! resume where the ray before it hit, with no sideways drift. Its vertical
//! component is the center's own ([`Line::up_word`]). At pitch 0 every ray
//! goes through its pixel's center, as before.
//!
//! # Order along a line
//! Rays go by rising elevation: away from `V` when it is the nadir, toward
//! it when it is the zenith. At pitch 0 that is each column bottom to top.

use super::plane::DIRECTION_WORD_SHIFT;
use super::View;
use crate::config::COORD_FRAC_BITS;
use crate::divide::{div_ceil, div_floor, div_trunc};

/// Fractional bits of image-plane positions in the ownership tests.
const IMG_FRAC: u32 = 8;
/// A direction component (I32F32 bits) rounded to the nearest multiple
/// of its word's unit (see [`DIRECTION_WORD_SHIFT`]).
fn to_word_multiple(v: i64) -> i64 {
    let half = 1 << (DIRECTION_WORD_SHIFT - 1);
    (v + half) & !((1 << DIRECTION_WORD_SHIFT) - 1)
}
const IMG_ONE: i64 = 1 << IMG_FRAC;

/// Farthest the vanishing point may lie from the image before the lines
/// are taken as parallel (the columns), in pixels. At that distance a line
/// leans by less than a sixth of a pixel over an 8192-pixel image, and all
/// positions stay inside `i64` in the tests below.
const FAR_VANISHING_POINT: f64 = (1u64 << 20) as f64;

/// The most lines any view of a `width × height` image has: the size a
/// [`LinePool`](crate::LinePool) needs a frame. A frame has about `width`
/// lines at shallow pitch, up to about twice its perimeter straight down,
/// and rolled with the vanishing point just off a corner, where the lines
/// fan out across two sectors, up to about four times `width + height`
/// (tested over every pitch, roll and field of view).
pub const fn max_lines(width: u32, height: u32) -> u32 {
    6 * (width + height) + 64
}

/// One sector of the image and its family of lines.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Sector {
    /// Lines step along rows (the sectors above and below `V`: the axis
    /// coordinate `s` is the row counted from the bottom, the cross
    /// coordinate `t` the column), or along columns (`s` the column, `t`
    /// the row from the bottom).
    pub along_rows: bool,
    /// `V`'s axis and cross coordinates, Q8; `None` when `V` is at infinity
    /// and the lines are parallel (the columns, or slanted under roll).
    vanishing: Option<(i64, i64)>,
    /// Parallel lines' cross coordinate change a unit of axis, Q32 (within
    /// ±1; 0 for the columns and for lines through `V`).
    lean: i64,
    /// Axis coordinate of the far edge, where line `K` crosses at `t = K`.
    s_ref: i32,
    /// The sector's axis positions, in the order rays are cast: `first`
    /// to `last` by `step` (±1).
    first: i32,
    last: i32,
    pub step: i32,
    /// Its lines, `K` from `k_first` to `k_first + lines − 1`.
    k_first: i32,
    lines: u32,
    /// Pixels along the cross coordinate (the image width or height).
    cross_len: i32,
}

/// Every sector of a view: up to four, in a fixed order.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Lines {
    sectors: [Option<Sector>; 4],
}

impl Lines {
    /// The sectors of a `width × height` image whose camera looks `pitch`
    /// radians down, with `tangent = tan(hfov / 2)`, and rolls by `roll`
    /// radians; `pixels` are the frame's pixel directions. Float set-up,
    /// once a frame; everything per pixel is integer.
    pub fn new(
        width: u32,
        height: u32,
        pitch: f64,
        tangent: f64,
        roll: f64,
        pixels: &PixelDirections,
    ) -> Self {
        let (w, h) = (f64::from(width), f64::from(height));
        let vanishing = if roll == 0.0 {
            // Pixel (c, j), j rows from the bottom, looks along
            // f + r·tan·((2c+1)/w − 1) + u·tan·((2j+1−h)/w); its horizontal
            // part vanishes at c = (w−1)/2 and cos p + sin p·tan·(2j+1−h)/w = 0.
            let cot = libm::cos(pitch) / libm::sin(pitch);
            ((w - 1.0) * 0.5, (h - 1.0 - cot * w / tangent) * 0.5)
        } else {
            pixels.vertical()
        };
        let (c_v, j_v) = vanishing;
        // How far off the image `V` is (unrolled, as it always was measured).
        let far = if roll == 0.0 {
            j_v.abs()
        } else {
            (c_v - (w - 1.0) * 0.5)
                .abs()
                .max((j_v - (h - 1.0) * 0.5).abs())
        };
        if !c_v.is_finite() || !j_v.is_finite() || far > FAR_VANISHING_POINT {
            let parallel = if roll == 0.0 {
                // The columns, bottom to top.
                Sector {
                    along_rows: true,
                    vanishing: None,
                    lean: 0,
                    s_ref: height as i32 - 1,
                    first: 0,
                    last: height as i32 - 1,
                    step: 1,
                    k_first: 0,
                    lines: width,
                    cross_len: width as i32,
                }
            } else {
                parallel_sector(width as i32, height as i32, pixels)
            };
            return Self {
                sectors: [Some(parallel), None, None, None],
            };
        }
        let (u_v, v_v) =
            off_pixel_centers((c_v * IMG_ONE as f64) as i64, (j_v * IMG_ONE as f64) as i64);
        let nadir = pitch > 0.0;
        let (wi, hi) = (width as i32, height as i32);
        // (along rows, s_V, t_V, s_ref, the sector's axis range, away from V)
        let candidates = [
            (true, v_v, u_v, hi - 1, floor_q8(v_v) + 1, hi - 1, 1),
            (true, v_v, u_v, 0, 0, ceil_q8(v_v) - 1, -1),
            (false, u_v, v_v, wi - 1, floor_q8(u_v) + 1, wi - 1, 1),
            (false, u_v, v_v, 0, 0, ceil_q8(u_v) - 1, -1),
        ];
        let mut sectors = [None; 4];
        for (slot, (along_rows, s_v, t_v, s_ref, lo, hi_s, away)) in
            sectors.iter_mut().zip(candidates)
        {
            let (axis_len, cross_len) = if along_rows { (hi, wi) } else { (wi, hi) };
            let (lo, hi_s) = (lo.max(0), hi_s.min(axis_len - 1));
            if lo > hi_s {
                continue;
            }
            let Some((k_first, lines)) = line_range(s_v, t_v, s_ref, (lo, hi_s), cross_len) else {
                continue;
            };
            // Rising elevation: away from the nadir, toward the zenith.
            let step = if nadir { away } else { -away };
            let (first, last) = if step > 0 { (lo, hi_s) } else { (hi_s, lo) };
            *slot = Some(Sector {
                along_rows,
                vanishing: Some((s_v, t_v)),
                lean: 0,
                s_ref,
                first,
                last,
                step,
                k_first,
                lines,
                cross_len,
            });
        }
        Self { sectors }
    }

    /// Lines in the frame.
    pub fn count(&self) -> u32 {
        self.sectors.iter().flatten().map(|s| s.lines).sum()
    }

    /// Whether every line runs straight along its axis: parallel lines
    /// with no lean (a level view's columns, upright or upside down, and
    /// its rows rolled ±90°), each owning the same pixel on every row.
    pub fn straight(&self) -> bool {
        self.sectors
            .iter()
            .flatten()
            .all(|s| s.vanishing.is_none() && s.lean == 0)
    }

    /// Line number `index` (`0..count()`): its sector and `K`.
    pub fn get(&self, mut index: u32) -> Option<(Sector, i32)> {
        for sector in self.sectors.iter().flatten() {
            if index < sector.lines {
                return Some((*sector, sector.k_first + index as i32));
            }
            index -= sector.lines;
        }
        None
    }
}

/// A frame's pixel directions: pixel (0, 0)'s (the bottom-left one) and
/// their change a column and a row (world axes, any common scale).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PixelDirections {
    pub corner: [f64; 3],
    pub per_column: [f64; 3],
    pub per_row: [f64; 3],
}

impl PixelDirections {
    /// The image position (column, row from the bottom) whose direction is
    /// vertical: where both horizontal components vanish. Not finite when
    /// the image of the vertical is at infinity.
    fn vertical(&self) -> (f64, f64) {
        let (b, c, r) = (self.corner, self.per_column, self.per_row);
        let det = c[0] * r[1] - c[1] * r[0];
        (
            (b[1] * r[0] - b[0] * r[1]) / det,
            (b[0] * c[1] - b[1] * c[0]) / det,
        )
    }
}

/// The image of vertical planes when `V` is at infinity (the camera level,
/// rolled): parallel lines along the image direction in which a pixel's
/// horizontal direction does not change, stepping along rows where they
/// are steeper than 45° and along columns otherwise (Qu et al. §5, there
/// by Bresenham; here by the same stepped ownership test as lines through
/// `V`). Rays go by rising elevation.
fn parallel_sector(width: i32, height: i32, pixels: &PixelDirections) -> Sector {
    let (c, r) = (pixels.per_column, pixels.per_row);
    // (dc, dj) with c_h·dc + r_h·dj = 0 on the better-conditioned
    // horizontal axis (the other agrees: the determinant is about 0).
    let i = if c[0].abs() + r[0].abs() >= c[1].abs() + r[1].abs() {
        0
    } else {
        1
    };
    let (mut dc, mut dj) = (r[i], -c[i]);
    if c[2] * dc + r[2] * dj < 0.0 {
        (dc, dj) = (-dc, -dj);
    }
    let along_rows = dj.abs() >= dc.abs();
    let (axis, cross, axis_len, cross_len) = if along_rows {
        (dj, dc, height, width)
    } else {
        (dc, dj, width, height)
    };
    let lean = (cross / axis).clamp(-1.0, 1.0);
    let step = if axis > 0.0 { 1 } else { -1 };
    let s_ref = axis_len - 1;
    // Line K crosses row s at K + lean·(s − s_ref): the lines that reach
    // the image are those between its corners' K, with one to spare.
    let spread = lean.abs() * f64::from(axis_len - 1);
    let k_first = -(libm::ceil(spread) as i32) - 1;
    let k_last = cross_len + libm::ceil(spread) as i32;
    let (first, last) = if step > 0 {
        (0, axis_len - 1)
    } else {
        (axis_len - 1, 0)
    };
    Sector {
        along_rows,
        vanishing: None,
        lean: (lean * (1u64 << 32) as f64) as i64,
        s_ref,
        first,
        last,
        step,
        k_first,
        lines: (k_last - k_first + 1) as u32,
        cross_len,
    }
}

/// `V` (Q8 column and row from the bottom) moved by a few 1/256 of a pixel
/// where needed, so that every pixel lies strictly inside one sector: off
/// every pixel's row and column, and off every diagonal through a pixel
/// center. Unrolled, `V` is on the image's middle column or half a pixel
/// beside it (a multiple of one half): then it only has to leave the half
/// rows, as it always has.
fn off_pixel_centers(mut u_v: i64, mut v_v: i64) -> (i64, i64) {
    if u_v.rem_euclid(IMG_ONE / 2) == 0 {
        if v_v.rem_euclid(IMG_ONE / 2) == 0 {
            v_v += 1;
        }
        return (u_v, v_v);
    }
    for _ in 0..8 {
        let on_a_line = u_v.rem_euclid(IMG_ONE) == 0 || v_v.rem_euclid(IMG_ONE) == 0;
        let on_a_diagonal =
            (u_v - v_v).rem_euclid(IMG_ONE) == 0 || (u_v + v_v).rem_euclid(IMG_ONE) == 0;
        if !on_a_line && !on_a_diagonal {
            break;
        }
        if u_v.rem_euclid(IMG_ONE) == 0 {
            u_v += 1;
        }
        v_v += 1;
    }
    (u_v, v_v)
}

fn floor_q8(v: i64) -> i32 {
    (v >> IMG_FRAC).clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
}

fn ceil_q8(v: i64) -> i32 {
    ((v + IMG_ONE - 1) >> IMG_FRAC).clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
}

/// The lines `K` that may own a pixel of a sector, with a margin (a line
/// that owns none costs a few comparisons): `(first K, count)`.
fn line_range(
    s_v: i64,
    t_v: i64,
    s_ref: i32,
    (lo, hi): (i32, i32),
    cross_len: i32,
) -> Option<(i32, u32)> {
    let q = |v: i64| v as f64 / IMG_ONE as f64;
    let (s_v, t_v) = (q(s_v), q(t_v));
    let b = (f64::from(s_ref) - s_v).abs();
    // A pixel (t, s) belongs to line K = t_V + (t − t_V)·b/a, a = |s − s_V|;
    // for fixed s that grows with t, and along each edge of the sector's
    // pixels it is monotone in s, so its extremes are at the axis ends.
    let (mut k_min, mut k_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut ends_without_pixels = 0;
    for s in [lo, hi] {
        let a = (f64::from(s) - s_v).abs();
        let t_lo = (t_v - a).max(0.0);
        let t_hi = (t_v + a).min(f64::from(cross_len - 1));
        if t_lo > t_hi {
            ends_without_pixels += 1;
            // No pixel at this end: the sector's pixels start on its edges.
            k_min = k_min.min(t_v - b);
            k_max = k_max.max(t_v + b);
            continue;
        }
        for t in [t_lo, t_hi] {
            let k = t_v + (t - t_v) * b / a.max(1e-9);
            k_min = k_min.min(k);
            k_max = k_max.max(k);
        }
    }
    // The cone widens steadily along the axis: if it misses the image at
    // both ends, it misses every row between.
    if ends_without_pixels == 2 {
        return None;
    }
    let (k_min, k_max) = (k_min.max(t_v - b), k_max.min(t_v + b));
    if k_min > k_max {
        return None;
    }
    // A line that owns a pixel crosses the far edge within a few image
    // sizes of it; the clamp is a guard that keeps every direction and
    // product in range, not a limit that is ever reached.
    let limit = 4 * i64::from(cross_len + (hi - lo + 1).max(s_ref.abs() + 1)) + 64;
    let first = (libm::floor(k_min) as i64 - 2).clamp(-limit, limit) as i32;
    let last = (libm::ceil(k_max) as i64 + 2).clamp(-limit, limit) as i32;
    if first > last {
        return None;
    }
    Some((first, (last - first + 1) as u32))
}

/// A line of a frame, set up to walk its pixels.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Line {
    pub sector: Sector,
    pub k: i32,
    /// Direction of the line's far-edge point (I32F32): every ray of the
    /// line takes its horizontal direction from it.
    pub reference: [i64; 3],
    /// The direction's change a unit of axis coordinate along the line
    /// (I32F32): a pixel's ray steps to the next row's by one add.
    per_axis: [i64; 3],
    /// The vertical component of the direction's step to the next pixel
    /// across the line (I32F32): a pixel's ray takes its center's
    /// elevation from it ([`Line::up_word`]).
    across_up: i64,
    /// Cross coordinate per unit of axis, Q32 (`(K − t_V) / (s_ref − s_V)`).
    slope: i64,
    /// The ownership test's per-line terms (see `Line::owns`), Q8:
    /// `|s_ref − s_V|`, and `K − ½ − t_V`.
    far: i64,
    nearest_from: i64,
}

/// A line's per-ray set-up in 32-bit words: from a pixel's coordinates
/// its image position, its ray's run and rise, and its offset from the
/// line, by multiply-adds on single words (one 32 × 32 → 64-bit product
/// for the offset and one for the rise beside the line). The same
/// quantities as [`Line::owned_at`], [`Line::direction_words`] and
/// [`Line::up_word`], rounded to words: what the lean per-pixel path
/// (`render_pixel_path_lean`) costs a ray.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LineWords {
    /// The direction's major-axis and vertical components at the far edge,
    /// and their change a row (or column), as words.
    major: [i32; 2],
    up: [i32; 2],
    /// The vertical component's step across the line, in 2^16 direction
    /// bits.
    across_up: i32,
    /// The line's point on the far edge's row (cross coordinate `K`,
    /// Q16), its cross coordinate's change a row (Q24: within ±1), and
    /// that row.
    t_far: i32,
    lean: i32,
    s_ref: i32,
    along_rows: bool,
    top_row: i32,
}

/// A pixel's ray in words (see [`LineWords::ray`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct RayWords {
    /// Image position, y = 0 at the top.
    pub x: u32,
    pub y: u32,
    /// The direction's major-axis component and its vertical component
    /// through the pixel's center, as words.
    pub major: i32,
    pub up: i32,
    /// The pixel's center less its line's point, Q16 pixels.
    pub offset: i32,
}

impl LineWords {
    /// The ray of the pixel at cross coordinate `t`, axis coordinate `s`.
    #[inline(always)]
    pub(crate) fn ray(&self, t: i32, s: i32) -> RayWords {
        let (x, y) = image_position(self.along_rows, self.top_row, t, s);
        let along = s - self.s_ref;
        // Q24 lean times rows from the far edge: one long product. (From
        // the far edge, not from a vanishing point far off the image, the
        // lean's rounding moves the point by under 2^−11 pixel.)
        let point = self
            .t_far
            .wrapping_add(((i64::from(self.lean) * i64::from(along)) >> 8) as i32);
        let offset = (t << COORD_FRAC_BITS).wrapping_sub(point);
        let beside = (i64::from(self.across_up) * i64::from(offset)) >> DIRECTION_WORD_SHIFT;
        RayWords {
            x,
            y,
            major: self.major[0].wrapping_add(self.major[1].wrapping_mul(along)),
            up: self.up[0]
                .wrapping_add(self.up[1].wrapping_mul(along))
                .wrapping_add(beside as i32),
            offset,
        }
    }
}

/// A pixel a line owns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Owned {
    /// Image position, y = 0 at the top (the sink's coordinates).
    pub x: u32,
    pub y: u32,
    /// Axis coordinate of the pixel.
    pub s: i32,
    /// Axis coordinate of the pixel less the far edge's (`s − s_ref`): the
    /// ray's direction is the line's reference plus this many axis steps
    /// ([`Line::direction`]).
    pub along: i32,
    /// The pixel's center less its line's point there, along the cross
    /// coordinate, Q16 pixels (within ±1/2).
    pub offset: i64,
}

impl View {
    /// Lines in this frame: the units a caster or a pool hands out.
    pub fn lines(&self) -> u32 {
        self.lines.count()
    }

    /// Whether every image line runs straight along its axis (a level
    /// view's columns, upright or upside down, and its rows rolled ±90°):
    /// a caster steps such a line's pixels a row at a time, with no
    /// ownership test (`OwnedPixels::straightened`), and a frame
    /// budget prices its pixels apart ([`crate::Prices::per_straight_pixel`]).
    pub fn lines_are_straight(&self) -> bool {
        self.lines.straight()
    }

    /// The pixels (x, y; y = 0 at the top) of image line `index`, in the
    /// order the caster casts them: their rays lie in the line's vertical
    /// plane (to within half a pixel), and along it each ray reaches the
    /// ground farther from the eye than the one before. Another ray caster
    /// gets vertical coherence at any pitch and roll from this order; none
    /// past the last line.
    pub fn line_pixels(&self, index: u32) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.line(index)
            .into_iter()
            .flat_map(move |line| line.pixels(self.height()).map(|p| (p.x, p.y)))
    }

    /// Line `index`, or `None` past the last.
    pub(crate) fn line(&self, index: u32) -> Option<Line> {
        let (sector, k) = self.lines.get(index)?;
        let (t, s) = (i64::from(k), i64::from(sector.s_ref));
        let (u, v) = if sector.along_rows { (t, s) } else { (s, t) };
        // Both the reference and the step along the line keep no bits
        // below a word's (`DIRECTION_WORD_SHIFT`), rounded to the nearest:
        // every ray's direction is then a word times 2^8, its words a
        // 32-bit multiply-add.
        let reference = core::array::from_fn(|i| {
            to_word_multiple(
                self.base[i].to_bits()
                    + self.per_column[i].to_bits() * u
                    + self.per_row[i].to_bits() * v,
            )
        });
        let slope = match sector.vanishing {
            None => sector.lean,
            Some((s_v, t_v)) => {
                // |K − t_V| stays below 2^17 pixels and |s_ref − s_V| above
                // 2^−8: no overflow, and the quotient is at most 1 in size
                // inside the sector's cone (or a little past it at the margin).
                let num = ((i64::from(k) << IMG_FRAC) - t_v) << 32;
                let den = (i64::from(sector.s_ref) << IMG_FRAC) - s_v;
                if den == 0 {
                    0
                } else {
                    div_trunc(num, den)
                }
            }
        };
        // Along the line the cross coordinate moves `slope` a unit of axis:
        // the direction moves by the axis step plus `slope` cross steps
        // (once a line, in 128 bits: a step is below 2^41, the slope 2^34).
        let (axis_step, cross_step) = if sector.along_rows {
            (&self.per_row, &self.per_column)
        } else {
            (&self.per_column, &self.per_row)
        };
        let per_axis = core::array::from_fn(|i| {
            let cross = (i128::from(cross_step[i].to_bits()) * i128::from(slope)) >> 32;
            to_word_multiple(axis_step[i].to_bits() + cross as i64)
        });
        let (s_v, t_v) = sector.vanishing.unwrap_or((0, 0));
        let k_t = (i64::from(k) << IMG_FRAC) - t_v;
        let far = ((i64::from(sector.s_ref) << IMG_FRAC) - s_v).abs();
        Some(Line {
            sector,
            k,
            reference,
            per_axis,
            across_up: cross_step[2].to_bits(),
            slope,
            far,
            nearest_from: k_t - IMG_ONE / 2,
        })
    }

    /// Whether line `index` certainly owns no pixel, told without setting
    /// the line up (no division): its point stays on one side outside the
    /// image over its sector's rows and two more each way, so
    /// [`Line::pixels`] would find no row within half a pixel of the
    /// image. A line this does not rule out may still own none.
    pub(crate) fn line_misses_image(&self, index: u32) -> bool {
        let Some((sector, k)) = self.lines.get(index) else {
            return true;
        };
        // The line's cross coordinate t at axis coordinate s (Q8 both):
        // (t − t_A)·den = num·(s − s_A), through its anchor A.
        let (s_a, t_a, num, den) = match sector.vanishing {
            None => (
                i128::from(sector.s_ref) << IMG_FRAC,
                i128::from(k) << IMG_FRAC,
                i128::from(sector.lean),
                1i128 << 32,
            ),
            Some((s_v, t_v)) => (
                i128::from(s_v),
                i128::from(t_v),
                (i128::from(k) << IMG_FRAC) - i128::from(t_v),
                (i128::from(sector.s_ref) << IMG_FRAC) - i128::from(s_v),
            ),
        };
        let (num, den) = if den < 0 { (-num, -den) } else { (num, den) };
        if den == 0 {
            return false;
        }
        let low = i128::from(-IMG_ONE / 2);
        let high = (i128::from(sector.cross_len) << IMG_FRAC) - i128::from(IMG_ONE / 2);
        // −1 below the image, 1 above it, 0 within, at axis coordinate s.
        let side = |s: i32| {
            let across = num * ((i128::from(s) << IMG_FRAC) - s_a);
            if across < (low - t_a) * den {
                -1
            } else if across > (high - t_a) * den {
                1
            } else {
                0
            }
        };
        let (from, to) = (sector.first.min(sector.last), sector.first.max(sector.last));
        let ends = side(from - 2);
        ends != 0 && ends == side(to + 2)
    }

    /// The direction `offset16` sixteenths of a pixel along `line` from
    /// `pixel`'s ([`Line::pixel_direction`]; a sub-ray's; I32F32 bits).
    #[inline]
    pub(crate) fn direction_beside(line: &Line, pixel: &Owned, offset16: i64) -> [i64; 3] {
        let direction = line.pixel_direction(pixel);
        core::array::from_fn(|i| direction[i] + ((line.per_axis[i] * offset16) >> 4))
    }
}

impl View {
    /// The direction step from one pixel to the next across `line` (a
    /// column for the sectors above and below the vanishing point, a row
    /// for the others), I32F32 bits.
    pub(crate) fn across(&self, line: &Line) -> [i64; 3] {
        let step = if line.sector.along_rows {
            &self.per_column
        } else {
            &self.per_row
        };
        step.map(|v| v.to_bits())
    }
}

impl Line {
    /// The direction through the line's point `along` axis steps past the
    /// far edge (I32F32 bits): every component is linear along the line.
    #[inline]
    pub(crate) fn direction(&self, along: i32) -> [i64; 3] {
        self.direction_component(along, [0, 1, 2])
    }

    /// Components `which` of [`Line::direction`] as words (the direction
    /// shifted right by [`DIRECTION_WORD_SHIFT`], exactly: the line's
    /// directions have no lower bits), by 32-bit multiply-adds. Every
    /// direction the view's limits allow fits a word.
    #[inline(always)]
    pub(crate) fn direction_words<const N: usize>(
        &self,
        along: i32,
        which: [usize; N],
    ) -> [i32; N] {
        which.map(|i| {
            let reference = (self.reference[i] >> DIRECTION_WORD_SHIFT) as i32;
            let per_axis = (self.per_axis[i] >> DIRECTION_WORD_SHIFT) as i32;
            // Wrapping: the sum fits a word, whatever its parts do.
            reference.wrapping_add(per_axis.wrapping_mul(along))
        })
    }

    /// The ray of `pixel`: its line's horizontal direction at the pixel
    /// (the line's vertical plane), with the vertical component of the
    /// direction through the pixel's center ([`Line::up_word`]); I32F32
    /// bits, none below a word's.
    #[inline]
    pub(crate) fn pixel_direction(&self, pixel: &Owned) -> [i64; 3] {
        let mut direction = self.direction(pixel.along);
        direction[2] = i64::from(self.up_word(pixel)) << DIRECTION_WORD_SHIFT;
        direction
    }

    /// The vertical component of the direction through `pixel`'s center,
    /// as a word: the line's at the pixel plus the step across the line
    /// times the pixel's offset from it. A pixel lies up to half a pixel
    /// beside its line; where the line is slanted in the image (a rolled
    /// view) that is up to half a pixel too high or too low, which at a
    /// grazing angle moves the hit far. The ray keeps its line's plane
    /// (its horizontal direction is the line's, and its color lookup makes
    /// up the sideways part, see [`super::plane::Plane::drift`]) and takes
    /// its pixel center's elevation.
    #[inline(always)]
    pub(crate) fn up_word(&self, pixel: &Owned) -> i32 {
        let [up] = self.direction_words(pixel.along, [2]);
        // |across_up| < 2^40 and |offset| <= 2^15: the product fits; the
        // change is under a pixel's step, a fraction of a word.
        let beside = (self.across_up * pixel.offset) >> (COORD_FRAC_BITS + DIRECTION_WORD_SHIFT);
        up.wrapping_add(beside as i32)
    }

    /// The line's per-ray set-up in 32-bit words (see [`LineWords`]), the
    /// direction's major-axis component taken from component `axis`.
    pub(crate) fn words(&self, axis: usize, height: u32) -> LineWords {
        let word = |v: i64| (v >> DIRECTION_WORD_SHIFT) as i32;
        LineWords {
            major: [word(self.reference[axis]), word(self.per_axis[axis])],
            up: [word(self.reference[2]), word(self.per_axis[2])],
            // Below 2^24: |across_up| < 2^40.
            across_up: (self.across_up >> COORD_FRAC_BITS) as i32,
            // Line K goes through the far edge's point K.
            t_far: self.k << COORD_FRAC_BITS,
            // Within ±1 a row inside the sector: Q32 to Q24.
            lean: (self.slope >> 8) as i32,
            s_ref: self.sector.s_ref,
            along_rows: self.sector.along_rows,
            top_row: height as i32 - 1,
        }
    }

    /// Components `which` of [`Line::direction`], and only those.
    #[inline(always)]
    pub(crate) fn direction_component<const N: usize>(
        &self,
        along: i32,
        which: [usize; N],
    ) -> [i64; N] {
        which.map(|i| self.reference[i] + self.per_axis[i] * i64::from(along))
    }

    /// How far apart (in pixels, Q16) the centers of two of the line's
    /// pixels on neighbouring rows are: `√(1 + slope²)`, from 1 for a line
    /// along the axis to √2 on the diagonals.
    pub(crate) fn pixel_spacing_q16(&self) -> u64 {
        // Slope to Q16 (at most about 1 inside the sector), squared to Q32.
        let slope = (self.slope >> 16).unsigned_abs().min(1 << 20);
        ((1u64 << 32) + slope * slope).isqrt()
    }

    /// The line's cross coordinate at axis coordinate `s_q16` (Q16 both):
    /// the point [`OwnedPixels`] steps along, bit for bit.
    #[cfg(test)]
    fn cross_at(&self, s_q16: i64) -> i64 {
        let (s_v, t_v) = self.anchor();
        // Q32 slope times Q8 distance, to Q16.
        let ds = (s_q16 >> (COORD_FRAC_BITS - IMG_FRAC)) - s_v;
        (t_v << (COORD_FRAC_BITS - IMG_FRAC))
            + ((self.slope * ds) >> (32 + IMG_FRAC - COORD_FRAC_BITS))
    }

    /// Whether the pixel at cross coordinate `t`, axis coordinate `s`, is
    /// this line's: inside the image and the sector, and nearer this line
    /// than any other of the sector. Exact integer arithmetic, so the lines
    /// of a sector share out its pixels with none left over or repeated.
    /// [`OwnedPixels`] steps this test along the line.
    #[cfg(test)]
    fn owns(&self, t: i32, s: i32) -> bool {
        if !(0..self.sector.cross_len).contains(&t) {
            return false;
        }
        let Some((s_v, t_v)) = self.sector.vanishing else {
            // Parallel lines: t within half a pixel of K + lean·(s − s_ref),
            // the lower end in (all Q32).
            let gap = (i64::from(t - self.k) << 32) - self.slope * i64::from(s - self.sector.s_ref);
            return (-(1 << 31)..1 << 31).contains(&gap);
        };
        let a = ((i64::from(s) << IMG_FRAC) - s_v).abs();
        let b = self.far;
        let dt = (i64::from(t) << IMG_FRAC) - t_v;
        // Rows belong to the sectors above and below V on the diagonals
        // (which `Lines::new` keeps off pixel centers anyway).
        let inside = if self.sector.along_rows {
            dt.abs() <= a
        } else {
            dt.abs() < a
        };
        // Nearest line: (K − ½ − t_V)·a <= (t − t_V)·b < (K + ½ − t_V)·a.
        let nearest_to = self.nearest_from + IMG_ONE;
        inside && self.nearest_from * a <= dt * b && dt * b < nearest_to * a
    }

    /// A point the line goes through (axis and cross coordinates, Q8): `V`,
    /// or for parallel lines the far edge's point, `(s_ref, K)`.
    fn anchor(&self) -> (i64, i64) {
        let sector = &self.sector;
        sector.vanishing.unwrap_or((
            i64::from(sector.s_ref) << IMG_FRAC,
            i64::from(self.k) << IMG_FRAC,
        ))
    }

    /// The rows (axis coordinates) where the line's point is within half
    /// a pixel of the image, with a row to spare at each end, in the
    /// order rays are cast: `first` up to `end` (exclusive; `first == end`
    /// for none). A pixel the line owns is within half a pixel of its
    /// point, so no other row holds one.
    fn rows_in_image(&self) -> (i32, i32) {
        let sector = &self.sector;
        let (first, last, step) = (sector.first, sector.last, sector.step);
        let (s_v, t_v) = self.anchor();
        let (low, high) = (
            -IMG_ONE / 2,
            (i64::from(sector.cross_len) << IMG_FRAC) - IMG_ONE / 2,
        );
        if self.slope == 0 {
            return if (low..=high).contains(&t_v) {
                (first, last + step)
            } else {
                (first, first)
            };
        }
        // Where the point crosses the two edges: s = s_V + (t − t_V)/slope
        // (`V` standing for the anchor)
        // (Q8; the Q32 slope is at least 2^−32, the quotient clamps).
        let s_at = |t: i64| s_v + div_trunc((t - t_v) << 32, self.slope);
        let (a, b) = (s_at(low), s_at(high));
        let (lo, hi) = (floor_q8(a.min(b)) - 1, ceil_q8(a.max(b)) + 1);
        let (lo, hi) = (lo.max(first.min(last)), hi.min(first.max(last)));
        if lo > hi {
            return (first, first);
        }
        if step > 0 {
            (lo, hi + 1)
        } else {
            (hi, lo - 1)
        }
    }

    /// The directions through the line's points on the first and the last
    /// of the rows where it may own pixels (its reference direction twice
    /// when it has none): along the line a direction's components change
    /// linearly, so these bound them.
    pub(crate) fn end_directions(&self) -> [[i64; 3]; 2] {
        let (first, end) = self.rows_in_image();
        if first == end {
            return [self.reference; 2];
        }
        [first, end - self.sector.step].map(|s| self.direction(s - self.sector.s_ref))
    }

    /// The pixels this line owns, in the order their rays are cast.
    pub fn pixels(&self, height: u32) -> OwnedPixels {
        OwnedPixels::new(self, height)
    }
}

/// Why a frame's pixel ownership cannot be tabled
/// ([`crate::render_pixel_path_tabled`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableError {
    /// The storage holds fewer entries than the frame has pixels (or
    /// lines, plus one), or the frame has more lines than the table's
    /// 16-bit line numbers name (possible from about 5 000 pixels a
    /// side: [`crate::max_lines`]).
    TooSmall,
}

impl core::fmt::Display for TableError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("the pixel table holds fewer entries than the frame needs")
    }
}

impl core::error::Error for TableError {}

/// Which line owns each pixel of a frame, found once a frame by a pass
/// over each sector's rows, not by each line stepping its own rows:
/// line `i`'s pixels are `order[starts[i]..starts[i + 1]]`, in the order
/// its rays are cast, each packed as cross coordinate `t` (low 16 bits)
/// and axis coordinate `s` (high 16 bits). Exactly the pixels
/// [`Line::pixels`] gives each line (tested).
pub(crate) struct PixelTable<'a> {
    pub order: &'a [u32],
    pub starts: &'a [u32],
}

impl<'a> PixelTable<'a> {
    /// Each line that owns a pixel, by index, with its pixels (packed as
    /// in `order`): a line that owns none need not be set up.
    pub(crate) fn owned_lines(&self) -> impl Iterator<Item = (u32, &'a [u32])> + '_ {
        self.starts
            .windows(2)
            .enumerate()
            .filter_map(|(index, ends)| {
                let pixels = self.order.get(ends[0] as usize..ends[1] as usize)?;
                (!pixels.is_empty()).then_some((index as u32, pixels))
            })
    }
}

impl View {
    /// Tables the frame's pixel ownership into caller storage: `line_of`
    /// (a pixel each: its line, in the scan's order), `order` (a pixel
    /// each) and `starts` (a line each, plus one) (see [`PixelTable`]).
    ///
    /// On row `s` of a sector through `V`, pixel `t` belongs to line `K =
    /// ⌊((t − t_V)·b + (½ + t_V)·a) / a⌋` (`a = |s − s_V|`, `b` the far
    /// edge's; the nearest line, as `Line::owns` decides it), so along a
    /// row `K` steps by `b/a` a pixel: a quotient and a remainder, two
    /// divisions a row and a few adds a pixel. Parallel lines shift by
    /// their lean a row. A counting sort by line then puts each line's
    /// pixels together, in the order of the scan, which is the order its
    /// rays are cast.
    pub(crate) fn tabulate_pixels<'a>(
        &self,
        line_of: &mut [u16],
        order: &'a mut [u32],
        starts: &'a mut [u32],
    ) -> Result<PixelTable<'a>, TableError> {
        let pixels = self.width() as usize * self.height() as usize;
        let lines = self.lines() as usize;
        if line_of.len() < pixels
            || order.len() < pixels
            || starts.len() < lines + 1
            || lines >= usize::from(NO_LINE)
        {
            return Err(TableError::TooSmall);
        }
        let starts = &mut starts[..lines + 1];
        starts.fill(0);
        // Each pixel's line in scan order, and each line's count.
        let mut scanned = 0;
        self.scan_rows(|sector, base, s, (t_lo, t_hi)| {
            let n = (t_hi - t_lo + 1) as usize;
            let Some(row) = line_of.get_mut(scanned..scanned + n) else {
                return;
            };
            scanned += n;
            let (count, k_first) = (i64::from(sector.lines), i64::from(sector.k_first));
            let mut note = |slot: &mut u16, k: i64| {
                let line = k - k_first;
                *slot = if (0..count).contains(&line) {
                    let line = base + line as u32;
                    if let Some(n) = starts.get_mut(line as usize + 1) {
                        *n += 1;
                    }
                    line as u16
                } else {
                    NO_LINE
                };
            };
            match sector.vanishing {
                None => {
                    // Line K holds t within half a pixel of
                    // K + lean·(s − s_ref), the lower end in (Q32).
                    let lean = sector.lean * i64::from(s - sector.s_ref);
                    let shift = (lean + (1 << 31)) >> 32;
                    for (slot, t) in row.iter_mut().zip(i64::from(t_lo)..) {
                        note(slot, t - shift);
                    }
                }
                Some((s_v, t_v)) => {
                    let a = ((i64::from(s) << IMG_FRAC) - s_v).abs();
                    let b = ((i64::from(sector.s_ref) << IMG_FRAC) - s_v).abs();
                    let denominator = a << IMG_FRAC;
                    let numerator =
                        ((i64::from(t_lo) << IMG_FRAC) - t_v) * b + (IMG_ONE / 2 + t_v) * a;
                    let mut k = div_floor(numerator, denominator);
                    let mut rest = numerator - k * denominator;
                    let per_pixel = b << IMG_FRAC;
                    let k_step = div_floor(per_pixel, denominator);
                    let rest_step = per_pixel - k_step * denominator;
                    for slot in row.iter_mut() {
                        note(slot, k);
                        k += k_step;
                        rest += rest_step;
                        if rest >= denominator {
                            k += 1;
                            rest -= denominator;
                        }
                    }
                }
            }
        });
        for i in 1..starts.len() {
            starts[i] += starts[i - 1];
        }
        // Place them: `starts[i]` runs to line i's end as it fills...
        let mut scanned = 0;
        self.scan_rows(|_, _, s, (t_lo, t_hi)| {
            let n = (t_hi - t_lo + 1) as usize;
            let Some(row) = line_of.get(scanned..scanned + n) else {
                return;
            };
            scanned += n;
            for (&line, t) in row.iter().zip(t_lo..) {
                // (`NO_LINE` is past every line: such a pixel is skipped.)
                let Some(next) = starts.get_mut(usize::from(line)) else {
                    continue;
                };
                if let Some(slot) = order.get_mut(*next as usize) {
                    *slot = (t as u32 & 0xFFFF) | ((s as u32) << 16);
                }
                *next += 1;
            }
        });
        // ... and back to its start.
        starts.copy_within(0..lines, 1);
        starts[0] = 0;
        let owned = starts[lines] as usize;
        Ok(PixelTable {
            order: &order[..owned.min(pixels)],
            starts,
        })
    }

    /// Calls `row(sector, base, s, (t_lo, t_hi))` for every row `s` of
    /// every sector that has pixels, `t_lo..=t_hi` those pixels (inside
    /// the image and the sector's cone), `base` the sector's first line
    /// index: sector by sector, each sector's rows in the order its rays
    /// are cast.
    fn scan_rows(&self, mut row: impl FnMut(&Sector, u32, i32, (i32, i32))) {
        let mut base = 0u32;
        for sector in self.lines.sectors.iter().flatten() {
            let mut s = sector.first;
            loop {
                let range = match sector.vanishing {
                    None => Some((0, sector.cross_len - 1)),
                    Some((s_v, t_v)) => {
                        let a = ((i64::from(s) << IMG_FRAC) - s_v).abs();
                        // The sector's cone, |t − t_V| <= a (< a left and
                        // right of V), inside the image.
                        let (low, high) = (t_v - a, t_v + a);
                        let (t_lo, t_hi) = if sector.along_rows {
                            (div_ceil(low, IMG_ONE), div_floor(high, IMG_ONE))
                        } else {
                            (div_floor(low, IMG_ONE) + 1, div_ceil(high, IMG_ONE) - 1)
                        };
                        let (t_lo, t_hi) = (t_lo.max(0), t_hi.min(i64::from(sector.cross_len) - 1));
                        (t_lo <= t_hi && a > 0).then_some((t_lo as i32, t_hi as i32))
                    }
                };
                if let Some(range) = range {
                    row(sector, base, s, range);
                }
                if s == sector.last {
                    break;
                }
                s += sector.step;
            }
            base += sector.lines;
        }
    }
}

/// A pixel no line of its sector owns, in the table's scan (none does:
/// tested).
const NO_LINE: u16 = u16::MAX;

impl Line {
    /// Pixel `(t, s)` as this line owns it (see [`OwnedPixels`]), in an
    /// image whose top row is `top_row`.
    #[inline(always)]
    pub(crate) fn owned_at(&self, t: i32, s: i32, top_row: i32) -> Owned {
        let (x, y) = image_position(self.sector.along_rows, top_row, t, s);
        let (s_v, t_v) = self.anchor();
        // As `OwnedPixels` steps it: the Q32 slope times the row's Q8
        // distance from the anchor, Q40.
        let point = self.slope * ((i64::from(s) << IMG_FRAC) - s_v);
        Owned {
            x,
            y,
            s,
            along: s - self.sector.s_ref,
            offset: offset_from_point(t, t_v << (COORD_FRAC_BITS - IMG_FRAC), point),
        }
    }
}

/// The image position (x, y from the top) of the pixel at cross
/// coordinate `t`, axis coordinate `s`, on a line that steps along rows
/// (`s` the row from the bottom) or along columns, in an image whose top
/// row is `top_row`.
#[inline(always)]
fn image_position(along_rows: bool, top_row: i32, t: i32, s: i32) -> (u32, u32) {
    let (x, row) = if along_rows { (t, s) } else { (s, t) };
    (x as u32, (top_row - row) as u32)
}

/// A pixel's center at cross coordinate `t` less its line's point on the
/// pixel's row, Q16: `point` is that point less `t_V` (Q40), `t_v_q16` is
/// `t_V` (Q16).
#[inline(always)]
fn offset_from_point(t: i32, t_v_q16: i64, point: i64) -> i64 {
    (i64::from(t) << COORD_FRAC_BITS) - (t_v_q16 + (point >> (32 + IMG_FRAC - COORD_FRAC_BITS)))
}

/// Iterator over a line's pixels (see [`Line::pixels`]): the ownership
/// test of `Line::owns` stepped row by row by adds.
///
/// On row `s` the line owns pixel `t` when `(K − ½ − t_V)·a ≤ (t − t_V)·b <
/// (K + ½ − t_V)·a` (`a` the row's distance from the vanishing point, `b`
/// the far edge's) and `t` is inside the image and the sector. The window's
/// start moves by a constant a row and its width, `a`, too; `(t − t_V)·b`
/// moves by `b` a pixel. The window is at most a pixel wide (`a ≤ b`), so
/// the candidate `t`, the smallest at or past its start, is the only pixel
/// the row can give the line, and it moves by about the line's slope a
/// row. Near the vanishing point the lines are closer than a pixel and
/// most rows give a line none: such a row costs a few adds and compares.
/// The direction and the offset are worked out for the pixels owned only.
#[derive(Debug, Clone)]
pub(crate) struct OwnedPixels<W: WindowWord = i64> {
    along_rows: bool,
    /// The row next looked at, the row past the last, and the step.
    s: i32,
    end: i32,
    step: i32,
    /// The far edge's row (`along` counts from it) and the image's top row
    /// (`y` counts from it), along the axis; pixels across.
    s_ref: i32,
    top_row: i32,
    cross_len: i32,
    /// The window on row `s` starts at `(K − ½ − t_V)·a` and is `a` wide
    /// (Q16, `a` times one pixel): its start's change a row, its width
    /// and the width's change a row.
    from_step: W,
    width: W,
    width_step: W,
    /// The window's start moves toward larger `t` from row to row (or
    /// stays), so the candidate only ever rises; else it only falls.
    rising: bool,
    /// The candidate pixel `t`, how far `(t − t_V)·b` is past the window's
    /// start on row `s` (Q16), and its change a pixel, `b`.
    t: i32,
    gap: W,
    b_step: W,
    /// `t_V` (Q8) where a pixel may lie outside the sector's cone (only
    /// the lines at its edges); `None` where none can.
    cone: Option<i64>,
    /// The line's point on row `s` less `t_V`, Q40 (the Q32 slope times the
    /// row's Q8 distance from `V`), its change a row, and `t_V` in Q16.
    point: i64,
    point_step: i64,
    t_v_q16: i64,
}

/// The integer an [`OwnedPixels`] window steps in: `i64` always fits;
/// `i32` fits most lines through a vanishing point within a few thousand
/// pixels of the image, and halves the work of a row on 32-bit cores.
pub(crate) trait WindowWord:
    Copy
    + Ord
    + core::fmt::Debug
    + core::ops::AddAssign
    + core::ops::SubAssign
    + core::ops::Shr<u32, Output = Self>
{
    const ZERO: Self;
    fn widen(self) -> i64;
}

impl WindowWord for i64 {
    const ZERO: Self = 0;
    #[inline(always)]
    fn widen(self) -> i64 {
        self
    }
}

impl WindowWord for i32 {
    const ZERO: Self = 0;
    #[inline(always)]
    fn widen(self) -> i64 {
        i64::from(self)
    }
}

impl OwnedPixels {
    /// These pixels with the window in 32-bit words, when its values fit
    /// them all the way along the line (the candidate's distance past the
    /// window, within a pixel step and a row's change of the window; the
    /// window's width at both ends); else `Err` with these pixels back.
    pub(crate) fn narrowed(self) -> Result<OwnedPixels<i32>, Self> {
        let wide = self;
        // (Parallel lines' window is a pixel in Q32: never narrow.)
        const LIMIT: i64 = 1 << 30;
        let rows = i64::from((wide.end - wide.s).abs());
        let last_width = wide.width + wide.width_step * rows;
        let fits = wide.b_step + wide.from_step.abs() < LIMIT
            && wide.gap.abs() < LIMIT
            && wide.width.abs().max(last_width.abs()) < LIMIT
            && wide.width_step.abs() < LIMIT;
        if !fits {
            return Err(wide);
        }
        Ok(OwnedPixels {
            along_rows: wide.along_rows,
            s: wide.s,
            end: wide.end,
            step: wide.step,
            s_ref: wide.s_ref,
            top_row: wide.top_row,
            cross_len: wide.cross_len,
            from_step: wide.from_step as i32,
            width: wide.width as i32,
            width_step: wide.width_step as i32,
            rising: wide.rising,
            t: wide.t,
            gap: wide.gap as i32,
            b_step: wide.b_step as i32,
            cone: wide.cone,
            point: wide.point,
            point_step: wide.point_step,
            t_v_q16: wide.t_v_q16,
        })
    }
}

impl OwnedPixels {
    fn new(line: &Line, height: u32) -> Self {
        let sector = line.sector;
        let (first, end) = line.rows_in_image();
        let first = i64::from(first);
        let (s_v, t_v) = line.anchor();
        // The candidate starts at the line's point on the first row.
        let point = line.slope * ((first << IMG_FRAC) - s_v);
        let t = (((t_v << 32) + point) >> 40).clamp(-(1 << 24), 1 << 24) as i32;
        let (gap, from_step, width, width_step, b_step, cone) = match sector.vanishing {
            Some(_) => {
                let ds = (first << IMG_FRAC) - s_v;
                let (a, a_step) = (ds.abs(), ds.signum() * i64::from(sector.step) * IMG_ONE);
                let (b, nearest_from) = (line.far, line.nearest_from);
                // An owned pixel is within (|K − t_V| + ½)·a/b of t_V: inside
                // the cone `|t − t_V| < a` whenever |K − t_V| + ½ < b.
                let k_t = nearest_from + IMG_ONE / 2;
                let cone = (k_t.abs() + IMG_ONE / 2 >= b).then_some(t_v);
                (
                    ((i64::from(t) << IMG_FRAC) - t_v) * b - nearest_from * a,
                    nearest_from * a_step,
                    IMG_ONE * a,
                    IMG_ONE * a_step,
                    IMG_ONE * b,
                    cone,
                )
            }
            None => {
                // Parallel lines own a pixel a row: line K's window on row s
                // starts at K − ½ + lean·(s − s_ref) and is a pixel wide
                // (Q32), so the lines share every row out exactly.
                let from = (i64::from(line.k) << 32) - (1 << 31)
                    + line.slope * (first - i64::from(sector.s_ref));
                let one = 1 << 32;
                let lean_step = line.slope * i64::from(sector.step);
                ((i64::from(t) << 32) - from, lean_step, one, 0, one, None)
            }
        };
        let mut pixels = Self {
            along_rows: sector.along_rows,
            s: first as i32,
            end,
            step: sector.step,
            s_ref: sector.s_ref,
            top_row: height as i32 - 1,
            cross_len: sector.cross_len,
            from_step,
            width,
            width_step,
            rising: from_step >= 0,
            t,
            gap,
            b_step,
            cone,
            point,
            point_step: line.slope * (i64::from(sector.step) << IMG_FRAC),
            t_v_q16: t_v << (COORD_FRAC_BITS - IMG_FRAC),
        };
        // The smallest t at or past the first row's window start; from
        // there on the candidate moves one way only.
        while pixels.gap < 0 {
            pixels.t += 1;
            pixels.gap += pixels.b_step;
        }
        while pixels.gap >= pixels.b_step {
            pixels.t -= 1;
            pixels.gap -= pixels.b_step;
        }
        pixels
    }

    /// These pixels as [`StraightPixels`] where the line runs straight
    /// along the axis (parallel lines with no lean: a level view's
    /// columns, a view rolled ±90°'s rows) and owns a pixel on its first
    /// row: its window neither moves nor widens, so every row's test has
    /// the first row's outcome and the line owns pixel `t` on every row.
    pub(crate) fn straightened(&self) -> Option<StraightPixels> {
        let straight = self.from_step == 0
            && self.width_step == 0
            && self.point_step == 0
            && self.cone.is_none()
            && self.gap < self.width
            && (self.t as u32) < self.cross_len as u32;
        if !straight {
            return None;
        }
        Some(StraightPixels {
            along_rows: self.along_rows,
            t: self.t,
            s: self.s,
            end: self.end,
            step: self.step,
            s_ref: self.s_ref,
            top_row: self.top_row,
            offset: offset_from_point(self.t, self.t_v_q16, self.point),
        })
    }
}

impl<W: WindowWord> OwnedPixels<W> {
    /// Whether no row is left to look at: then no pixel is either (a line
    /// whose point never comes within half a pixel of the image has none
    /// to begin with).
    #[inline]
    pub(crate) fn no_rows_left(&self) -> bool {
        self.s == self.end
    }

    /// The next pixel's cross and axis coordinates, and the line's point
    /// on its row (see `point`).
    #[inline(always)]
    fn advance(&mut self) -> Option<(i32, i32, i64)> {
        while self.s != self.end {
            let (s, width, point) = (self.s, self.width, self.point);
            self.s += self.step;
            self.width += self.width_step;
            self.point += self.point_step;
            // The smallest t at or past the window's start.
            if self.rising {
                while self.gap < W::ZERO {
                    self.t += 1;
                    self.gap += self.b_step;
                }
            } else {
                while self.gap >= self.b_step {
                    self.t -= 1;
                    self.gap -= self.b_step;
                }
            }
            let (t, gap) = (self.t, self.gap);
            self.gap -= self.from_step;
            if gap >= width || t as u32 >= self.cross_len as u32 {
                continue;
            }
            // Inside the sector: |t − t_V| <= a (< a for the sectors left
            // and right of V), Q8.
            if let Some(t_v) = self.cone {
                let (dt, a) = (
                    ((i64::from(t) << IMG_FRAC) - t_v).abs(),
                    (width >> IMG_FRAC).widen(),
                );
                if dt > a || (dt == a && !self.along_rows) {
                    continue;
                }
            }
            return Some((t, s, point));
        }
        None
    }

    /// The image position (x, y from the top) of the pixel at cross
    /// coordinate `t`, axis coordinate `s`.
    #[inline(always)]
    fn image_position(&self, t: i32, s: i32) -> (u32, u32) {
        image_position(self.along_rows, self.top_row, t, s)
    }
}

impl<W: WindowWord> Iterator for OwnedPixels<W> {
    type Item = Owned;

    #[inline(always)]
    fn next(&mut self) -> Option<Owned> {
        let (t, s, point) = self.advance()?;
        let (x, y) = self.image_position(t, s);
        Some(Owned {
            x,
            y,
            s,
            along: s - self.s_ref,
            offset: offset_from_point(t, self.t_v_q16, point),
        })
    }
}

/// A line's pixels, as a caster walks them: each owned pixel in the
/// order its rays are cast ([`Iterator`]), and the positions of those left
/// when its rays stop.
pub(crate) trait LinePixels: Iterator<Item = Owned> {
    /// Calls `put` with the image position (x, y from the top) of each
    /// pixel left: what a caster needs of the pixels it fills without
    /// rays (the sky above a line's last hit).
    fn for_each_position(self, put: impl FnMut(u32, u32));
}

impl<W: WindowWord> LinePixels for OwnedPixels<W> {
    #[inline]
    fn for_each_position(mut self, mut put: impl FnMut(u32, u32)) {
        while let Some((t, s, _)) = self.advance() {
            let (x, y) = self.image_position(t, s);
            put(x, y);
        }
    }
}

/// The pixels of a line that runs straight along the axis and owns one on
/// every row ([`OwnedPixels::straightened`]): a row at a time, with no
/// ownership test.
#[derive(Debug, Clone)]
pub(crate) struct StraightPixels {
    along_rows: bool,
    /// The cross coordinate the line keeps to (the column along rows, the
    /// row from the bottom along columns); the axis coordinate steps.
    t: i32,
    /// The axis position next, the one past the last, and the step.
    s: i32,
    end: i32,
    step: i32,
    s_ref: i32,
    top_row: i32,
    /// Every pixel's center less the line's point (Q16): the same on
    /// every row.
    offset: i64,
}

impl StraightPixels {
    /// The image position (x, y from the top) of the pixel at axis
    /// coordinate `s`.
    #[inline(always)]
    fn image_position(&self, s: i32) -> (u32, u32) {
        image_position(self.along_rows, self.top_row, self.t, s)
    }
}

impl Iterator for StraightPixels {
    type Item = Owned;

    #[inline(always)]
    fn next(&mut self) -> Option<Owned> {
        if self.s == self.end {
            return None;
        }
        let s = self.s;
        self.s += self.step;
        let (x, y) = self.image_position(s);
        Some(Owned {
            x,
            y,
            s,
            along: s - self.s_ref,
            offset: self.offset,
        })
    }
}

impl LinePixels for StraightPixels {
    #[inline]
    fn for_each_position(mut self, mut put: impl FnMut(u32, u32)) {
        while self.s != self.end {
            let (x, y) = self.image_position(self.s);
            put(x, y);
            self.s += self.step;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::Camera;
    use std::vec;

    fn view(pitch: f32, yaw: f32, size: (u32, u32), hfov: f32) -> View {
        rolled(pitch, 0.0, yaw, size, hfov)
    }

    fn rolled(pitch: f32, roll: f32, yaw: f32, size: (u32, u32), hfov: f32) -> View {
        let camera = Camera {
            eye: [10.0, 20.0, 30.0],
            yaw_deg: yaw,
            pitch_deg: pitch,
            roll_deg: roll,
            hfov_deg: hfov,
        };
        View::new(&camera, size.0, size.1).unwrap()
    }

    /// Every roll the ownership test is held to: every 7.5° both ways,
    /// with ±90° and 180°.
    fn rolls() -> impl Iterator<Item = f32> {
        (-24..=24).map(|i| i as f32 * 7.5)
    }

    /// How many times each pixel is owned, over every line of the view.
    fn ownership(view: &View) -> vec::Vec<u32> {
        let (w, h) = (view.width(), view.height());
        let mut owned = vec![0u32; (w * h) as usize];
        for index in 0..view.lines() {
            let line = view.line(index).unwrap();
            for p in line.pixels(h) {
                owned[(p.y * w + p.x) as usize] += 1;
            }
        }
        owned
    }

    #[test]
    fn every_pixel_belongs_to_exactly_one_line() {
        for pitch in [
            -89.0, -45.0, -3.0, 0.0, 0.001, 2.0, 15.0, 30.0, 45.0, 60.0, 66.0, 75.0, 89.9, 90.0,
        ] {
            for size in [(64, 48), (63, 47), (1, 9), (9, 1), (31, 80)] {
                for hfov in [30.0, 60.0, 120.0] {
                    let view = view(pitch, 25.0, size, hfov);
                    let owned = ownership(&view);
                    assert!(
                        owned.iter().all(|&n| n == 1),
                        "pitch {pitch} size {size:?} hfov {hfov}: {:?}",
                        owned
                            .iter()
                            .enumerate()
                            .filter(|(_, &n)| n != 1)
                            .take(5)
                            .collect::<vec::Vec<_>>()
                    );
                }
            }
        }
    }

    #[test]
    fn a_straight_line_steps_the_pixels_its_ownership_test_gives() {
        // Straight: level views' columns (upright or upside down), and
        // their rows rolled ±90°; every other view's lines step their
        // window.
        let mut straight_views = 0;
        for roll in rolls() {
            for pitch in [-45.0, -3.0, 0.0, 2.0, 90.0] {
                for size in [(32, 21), (40, 30), (1, 9), (9, 1)] {
                    let view = rolled(pitch, roll, 25.0, size, 70.0);
                    let level = pitch == 0.0 && roll % 90.0 == 0.0;
                    straight_views += usize::from(level);
                    // What a frame budget prices the view's pixels by.
                    assert_eq!(
                        view.lines_are_straight(),
                        level,
                        "roll {roll} pitch {pitch}"
                    );
                    for index in 0..view.lines() {
                        let line = view.line(index).unwrap();
                        let stepped = line.pixels(size.1);
                        let Some(straight) = stepped.straightened() else {
                            assert!(!level || stepped.clone().next().is_none());
                            continue;
                        };
                        assert!(level, "roll {roll} pitch {pitch}: line {index} straight");
                        // The same pixels, directions and offsets, in the
                        // same order.
                        assert_eq!(
                            straight.clone().collect::<vec::Vec<_>>(),
                            stepped.clone().collect::<vec::Vec<_>>(),
                            "roll {roll} size {size:?} line {index}"
                        );
                        // And the same positions left once two rays are
                        // cast (the sky above a line's last hit).
                        let (mut a, mut b) = (straight, stepped.clone());
                        a.nth(1);
                        b.nth(1);
                        let mut positions = (vec::Vec::new(), vec::Vec::new());
                        a.for_each_position(|x, y| positions.0.push((x, y)));
                        b.for_each_position(|x, y| positions.1.push((x, y)));
                        assert_eq!(positions.0, positions.1);
                        assert_eq!(positions.0.len(), stepped.count().saturating_sub(2));
                    }
                }
            }
        }
        assert_eq!(straight_views, 5 * 4);
    }

    #[test]
    fn every_pixel_belongs_to_exactly_one_line_at_every_roll() {
        for roll in rolls() {
            for pitch in [-89.0, -45.0, 0.0, 2.0, 30.0, 60.0, 90.0] {
                for size in [(32, 21), (40, 30)] {
                    for hfov in [30.0, 70.0, 120.0] {
                        let view = rolled(pitch, roll, 25.0, size, hfov);
                        let owned = ownership(&view);
                        let wrong = owned.iter().filter(|&&n| n != 1).count();
                        assert_eq!(
                            wrong, 0,
                            "roll {roll} pitch {pitch} size {size:?} hfov {hfov}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_rolled_lines_rays_share_one_vertical_plane_and_rise_along_it() {
        for roll in rolls() {
            for pitch in [-45.0, 0.0, 2.0, 30.0, 90.0] {
                let view = rolled(pitch, roll, 25.0, (48, 36), 70.0);
                for index in 0..view.lines() {
                    let line = view.line(index).unwrap();
                    let rays: vec::Vec<[f64; 3]> = line
                        .pixels(36)
                        .map(|p| line.direction(p.along).map(|v| v as f64 / 4294967296.0))
                        .collect();
                    let (Some(first), Some(last)) = (rays.first(), rays.last()) else {
                        continue;
                    };
                    // The last ray leaves the first one's vertical plane by
                    // far less than a pixel: its sideways part against its
                    // length, in pixels (a pixel is |per_column| radians).
                    let length = |d: &[f64; 3]| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    let across = (first[0] * last[1] - first[1] * last[0]).abs()
                        / first[0].hypot(first[1]).max(1e-12);
                    let pixel = length(&view.per_column.map(|v| v.to_num::<f64>()));
                    let off = across / length(last) / pixel;
                    // (0.076 at most, straight down, rolled or not: `V` is
                    // placed to 1/256 of a pixel.)
                    assert!(
                        off < 0.1,
                        "roll {roll} pitch {pitch} line {index}: {off} pixel"
                    );
                    // Elevation rises (or holds) ray by ray.
                    let elevation = |d: &[f64; 3]| d[2].atan2(d[0].hypot(d[1]));
                    for pair in rays.windows(2) {
                        assert!(
                            elevation(&pair[1]) >= elevation(&pair[0]) - 1e-9,
                            "roll {roll} pitch {pitch} line {index}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_lines_direction_words_are_its_directions_shifted_and_give_the_same_slope_and_drift() {
        use crate::view::plane::Plane;
        for (pitch, roll, size) in [
            (12.0, 0.0, (320, 240)),
            (90.0, 0.0, (64, 48)),
            (-45.0, 0.0, (40, 90)),
            (20.0, 30.0, (64, 48)),
            (0.0, 0.0, (33, 17)),
        ] {
            let view = rolled(pitch, roll, 25.0, size, 60.0);
            let extent = crate::surface::Extent {
                width: 512,
                depth: 512,
                max_height: 100,
                real_edges: true,
            };
            for index in 0..view.lines() {
                let line = view.line(index).unwrap();
                let plane =
                    Plane::new(&view, &extent, &line.reference).with_across(&view.across(&line));
                let (major, up) = if plane.key.x_major { (0, 2) } else { (1, 2) };
                for pixel in line.pixels(size.1) {
                    let d = line.direction(pixel.along);
                    let words = line.direction_words(pixel.along, [major, up]);
                    assert_eq!(words.map(i64::from), [d[major] >> 8, d[up] >> 8]);
                    assert_eq!(words.map(|w| i64::from(w) << 8), [d[major], d[up]]);
                    let run = if plane.key.forward {
                        words[0]
                    } else {
                        -words[0]
                    }
                    .max(0);
                    assert_eq!(
                        plane.drift_of_word(run, pixel.offset),
                        plane.drift(&d, pixel.offset),
                        "pitch {pitch} roll {roll} line {index}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_narrow_window_steps_the_same_pixels_as_the_wide_one() {
        // Every line of views at every kind of pitch, roll and size, up to
        // one whose vanishing point is too far for a narrow window.
        let mut narrow_lines = 0;
        let mut wide_only = 0;
        for (pitch, roll, size) in [
            (12.0, 0.0, (320, 240)),
            (2.0, 0.0, (320, 240)),
            (0.5, 0.0, (1280, 720)),
            (45.0, 0.0, (63, 47)),
            (90.0, 0.0, (160, 120)),
            (-45.0, 0.0, (40, 90)),
            (20.0, 30.0, (64, 48)),
            (0.0, 30.0, (40, 30)),
        ] {
            let view = rolled(pitch, roll, 25.0, size, 60.0);
            for index in 0..view.lines() {
                let line = view.line(index).unwrap();
                let Ok(narrow) = line.pixels(size.1).narrowed() else {
                    wide_only += 1;
                    continue;
                };
                narrow_lines += 1;
                let wide: vec::Vec<Owned> = line.pixels(size.1).collect();
                let stepped: vec::Vec<Owned> = narrow.collect();
                assert_eq!(stepped, wide, "pitch {pitch} roll {roll} line {index}");
            }
        }
        assert!(
            narrow_lines > 1000 && wide_only > 100,
            "{narrow_lines} {wide_only}"
        );
    }

    #[test]
    fn the_stepped_pixels_are_the_exact_tests_pixels() {
        // Every row of every line: the pixel the iterator gives (if any)
        // is the one pixel of the row `Line::owns` accepts.
        for (pitch, roll, size) in [
            (0.0, 0.0, (16, 8)),
            (30.0, 0.0, (64, 48)),
            (60.0, 0.0, (63, 47)),
            (89.9, 0.0, (64, 48)),
            (90.0, 0.0, (160, 120)),
            (-45.0, 0.0, (40, 90)),
            (0.0, 30.0, (40, 30)),
            (0.0, 60.0, (41, 31)),
            (0.0, -135.0, (40, 30)),
            (20.0, 30.0, (64, 48)),
            (45.0, -100.0, (63, 47)),
            (90.0, 45.0, (80, 60)),
            (-30.0, 170.0, (40, 90)),
        ] {
            let view = rolled(pitch, roll, 25.0, size, 60.0);
            for index in 0..view.lines() {
                let line = view.line(index).unwrap();
                let sector = line.sector;
                let mut exact = vec::Vec::new();
                let mut s = sector.first;
                while s != sector.last + sector.step {
                    let owned: vec::Vec<i32> = (-2..sector.cross_len + 2)
                        .filter(|&t| line.owns(t, s))
                        .collect();
                    assert!(
                        owned.len() <= 1,
                        "pitch {pitch} roll {roll} line {index} row {s}"
                    );
                    exact.extend(owned.into_iter().map(|t| (t, s)));
                    s += sector.step;
                }
                let stepped: vec::Vec<(i32, i32)> = line
                    .pixels(size.1)
                    .map(|p| {
                        let row = size.1 as i32 - 1 - p.y as i32;
                        let t = if sector.along_rows { p.x as i32 } else { row };
                        (t, p.s)
                    })
                    .collect();
                assert_eq!(stepped, exact, "pitch {pitch} roll {roll} line {index}");
            }
        }
    }

    #[test]
    fn the_tabled_pixels_are_the_stepped_pixels_line_by_line() {
        // Every line's pixels from the frame's table, in order, with the
        // same image position, axis coordinate and offset from the line.
        let mut compared = 0;
        for roll in [0.0, 7.5, 30.0, -60.0, 90.0, 135.0, 180.0] {
            for pitch in [-89.0, -45.0, 0.0, 2.0, 12.0, 45.0, 89.9, 90.0] {
                for (size, hfov) in [((64, 48), 60.0), ((63, 47), 120.0), ((9, 31), 30.0)] {
                    let view = rolled(pitch, roll, 25.0, size, hfov);
                    let pixels = (size.0 * size.1) as usize;
                    let mut line_of = vec![0u16; pixels];
                    let mut order = vec![0u32; pixels];
                    let mut starts = vec![0u32; view.lines() as usize + 1];
                    let table = view
                        .tabulate_pixels(&mut line_of, &mut order, &mut starts)
                        .unwrap();
                    assert_eq!(table.order.len(), pixels);
                    for index in 0..view.lines() {
                        let range = table.starts[index as usize] as usize
                            ..table.starts[index as usize + 1] as usize;
                        let Some(line) = view.line(index) else {
                            assert!(range.is_empty());
                            continue;
                        };
                        let tabled: vec::Vec<Owned> = table.order[range]
                            .iter()
                            .map(|&p| {
                                line.owned_at(
                                    (p & 0xFFFF) as i32,
                                    (p >> 16) as i32,
                                    size.1 as i32 - 1,
                                )
                            })
                            .collect();
                        let stepped: vec::Vec<Owned> = line.pixels(size.1).collect();
                        assert_eq!(
                            tabled, stepped,
                            "roll {roll} pitch {pitch} size {size:?} line {index}"
                        );
                        compared += tabled.len();
                    }
                }
            }
        }
        assert!(compared > 100_000, "{compared} pixels compared");
        // Too little storage is an error, not a panic.
        let view = view(30.0, 25.0, (16, 8), 60.0);
        let (mut line_of, mut order) = ([0u16; 128], [0u32; 127]);
        let mut starts = vec![0u32; view.lines() as usize + 1];
        assert_eq!(
            view.tabulate_pixels(&mut line_of, &mut order, &mut starts)
                .err(),
            Some(TableError::TooSmall)
        );
    }

    #[test]
    fn at_pitch_zero_the_lines_are_the_columns_bottom_to_top() {
        let view = view(0.0, 40.0, (16, 8), 60.0);
        assert_eq!(view.lines(), 16);
        for column in 0..16 {
            let line = view.line(column).unwrap();
            let pixels: vec::Vec<(u32, u32)> = line.pixels(8).map(|p| (p.x, p.y)).collect();
            let expected: vec::Vec<(u32, u32)> = (0..8).rev().map(|y| (column, y)).collect();
            assert_eq!(pixels, expected);
        }
    }

    #[test]
    fn a_line_ruled_out_of_the_image_owns_no_pixel() {
        // Rolled, steep and level views: every line `line_misses_image`
        // rules out owns no pixel, and it rules out four in five of the
        // lines that own none (the rest cross the image outside their
        // sector).
        let (mut ruled_out, mut empty) = (0, 0);
        for roll in rolls() {
            for pitch in [-45.0, 0.0, 20.0, 60.0, 90.0] {
                for (size, hfov) in [((320, 240), 60.0), ((101, 67), 110.0)] {
                    let view = rolled(pitch, roll, 30.0, size, hfov);
                    for index in 0..view.lines() {
                        let owns = view.line_pixels(index).count();
                        if view.line_misses_image(index) {
                            assert_eq!(owns, 0, "pitch {pitch} roll {roll} line {index}");
                            ruled_out += 1;
                        }
                        empty += usize::from(owns == 0);
                    }
                }
            }
        }
        assert!(
            ruled_out * 5 >= empty * 4,
            "{ruled_out} of {empty} empty lines ruled out"
        );
    }

    #[test]
    fn straight_down_the_lines_fan_out_from_the_center() {
        let view = view(90.0, 0.0, (64, 48), 60.0);
        let center = (31.5f64, 23.5f64);
        let mut last_distance = vec::Vec::new();
        for index in 0..view.lines() {
            let line = view.line(index).unwrap();
            let mut previous = -1.0f64;
            for p in line.pixels(48) {
                let (dx, dy) = (f64::from(p.x) - center.0, f64::from(p.y) - center.1);
                let distance = (dx * dx + dy * dy).sqrt();
                // Away from the nadir, pixel by pixel.
                assert!(
                    distance > previous - 0.75,
                    "line {index}: {distance} after {previous}"
                );
                previous = distance;
            }
            last_distance.push(previous);
        }
        assert!(view.lines() > 64 && view.lines() <= max_lines(64, 48));
    }

    #[test]
    fn no_view_has_more_lines_than_max_lines() {
        let mut most = 0.0f64;
        for size in [(64, 48), (48, 64), (1, 9), (9, 1), (200, 20), (20, 200)] {
            for hfov in [1.0, 30.0, 60.0, 120.0, 160.0] {
                for (tenth, roll) in (-890..=900)
                    .map(|t| (t, 0.0))
                    .chain((-89..=90).flat_map(|p| rolls().map(move |r| (p * 10, r))))
                {
                    let pitch = tenth as f32 / 10.0;
                    let Ok(view) = View::new(
                        &Camera {
                            pitch_deg: pitch,
                            roll_deg: roll,
                            hfov_deg: hfov,
                            ..Camera::default()
                        },
                        size.0,
                        size.1,
                    ) else {
                        continue;
                    };
                    let bound = max_lines(size.0, size.1);
                    assert!(
                        view.lines() <= bound,
                        "{size:?} hfov {hfov} pitch {pitch} roll {roll}: {}",
                        view.lines()
                    );
                    most = most.max(f64::from(view.lines()) / f64::from(bound));
                }
            }
        }
        assert!(most > 0.5, "the bound is not wildly loose: {most}");
    }

    #[test]
    fn a_rays_point_is_within_half_a_pixel_of_its_pixel_center() {
        for pitch in [10.0, 45.0, 80.0, 90.0, -60.0] {
            let view = view(pitch, 10.0, (40, 30), 70.0);
            for index in 0..view.lines() {
                let line = view.line(index).unwrap();
                for p in line.pixels(30) {
                    let t = line.cross_at(i64::from(p.s) << COORD_FRAC_BITS) as f64 / 65536.0;
                    let own = if line.sector.along_rows {
                        p.x
                    } else {
                        29 - p.y
                    };
                    assert!(
                        (t - f64::from(own)).abs() <= 0.5 + 1e-3,
                        "pitch {pitch}: {t} for {own}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_pixels_ray_rises_as_its_centers_direction_does() {
        // Rolled, the lines are slanted and a pixel lies up to half a pixel
        // beside its line, above or below it: its ray takes the vertical
        // component of the direction through its center (to the word),
        // where its line's point would be off by up to half the step
        // across the line's.
        let q32 = |v: i64| v as f64 / 4294967296.0;
        for (pitch, roll) in [
            (0.0, 15.0),
            (0.0, 30.0),
            (10.0, 15.0),
            (45.0, -30.0),
            (20.0, 135.0),
        ] {
            let view = rolled(pitch, roll, 33.0, (200, 150), 70.0);
            let (mut worst, mut line_worst) = (0.0f64, 0.0f64);
            for index in 0..view.lines() {
                let line = view.line(index).unwrap();
                for p in line.pixels(150) {
                    let (x, row) = (f64::from(p.x), f64::from(149 - p.y));
                    let center = q32(view.base[2].to_bits())
                        + q32(view.per_column[2].to_bits()) * x
                        + q32(view.per_row[2].to_bits()) * row;
                    let ray = line.pixel_direction(&p);
                    worst = worst.max((q32(ray[2]) - center).abs());
                    line_worst = line_worst.max((q32(line.direction(p.along)[2]) - center).abs());
                    // The horizontal direction is the line's: its plane.
                    assert_eq!(ray[..2], line.direction(p.along)[..2]);
                }
            }
            // A word is 2^−24; the line's own steps add a few of them.
            assert!(worst < 1e-5, "pitch {pitch} roll {roll}: {worst}");
            assert!(
                line_worst > 20.0 * worst,
                "pitch {pitch} roll {roll}: {line_worst} against {worst}"
            );
        }
    }

    #[test]
    fn a_pixels_direction_is_its_lines_direction_at_the_pixel() {
        // The iterator steps the direction by adds; it stays within
        // rounding of the direction through the line's point, worked out
        // from the view's vectors in floating point.
        for pitch in [0.0, 10.0, 45.0, 90.0, -60.0] {
            let view = view(pitch, 33.0, (400, 300), 70.0);
            let q32 = |v: i64| v as f64 / 4294967296.0;
            let mut worst = 0.0f64;
            for index in 0..view.lines() {
                let line = view.line(index).unwrap();
                for p in line.pixels(300) {
                    let point = line.cross_at(i64::from(p.s) << COORD_FRAC_BITS) as f64 / 65536.0;
                    let (u, v) = if line.sector.along_rows {
                        (point, f64::from(p.s))
                    } else {
                        (f64::from(p.s), point)
                    };
                    for (i, component) in line.direction(p.along).into_iter().enumerate() {
                        let exact = q32(view.base[i].to_bits())
                            + q32(view.per_column[i].to_bits()) * u
                            + q32(view.per_row[i].to_bits()) * v;
                        worst = worst.max((q32(component) - exact).abs());
                    }
                    if pitch == 0.0 {
                        assert_eq!(p.offset, 0);
                    }
                }
            }
            // A ray's direction is about 1 long. A line's step along it is
            // rounded to 2^-25 (a word's unit, to the nearest), so 300 rows
            // along it is within 2^-16: the relative precision of a slope
            // (`slope_quotient`, 2^-15).
            assert!(worst < 1.0 / 65536.0, "pitch {pitch}: {worst}");
        }
    }

    #[test]
    fn a_sector_whose_cone_misses_the_image_has_no_lines() {
        // At 12° down the vanishing point is far below the image: the
        // sectors left and right of it hold no pixel, and only the sector
        // above it has lines (one a column, and a few that end in a
        // corner).
        let view = view(12.0, 0.0, (320, 240), 60.0);
        assert!(view.lines() < 400, "{} lines", view.lines());
        assert!((0..view.lines()).all(|i| view.line(i).unwrap().sector.along_rows));
    }
}
