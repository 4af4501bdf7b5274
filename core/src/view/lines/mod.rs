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

mod line;
mod pixels;
mod table;
#[cfg(test)]
mod tests;

pub(crate) use line::{Line, Owned, RayWords};
use pixels::*;
pub(crate) use pixels::{LinePixels, OwnedPixels};
pub use table::TableError;

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
