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
//! A pixel's ray goes through the point of its line at the pixel's row (or
//! column), at most half a pixel from the pixel's center, and all rays of a
//! line share one horizontal direction, bit for bit: each ray of a line can
//! resume where the ray before it hit, with no sideways drift. At pitch 0
//! every ray goes through its pixel's center, as before.
//!
//! # Order along a line
//! Rays go by rising elevation: away from `V` when it is the nadir, toward
//! it when it is the zenith. At pitch 0 that is each column bottom to top.

use super::View;
use crate::config::COORD_FRAC_BITS;
use crate::divide::{div_ceil, div_trunc};

/// Fractional bits of image-plane positions in the ownership tests.
const IMG_FRAC: u32 = 8;
const IMG_ONE: i64 = 1 << IMG_FRAC;

/// Farthest the vanishing point may lie from the image before the lines
/// are taken as parallel (the columns), in pixels. At that distance a line
/// leans by less than a sixth of a pixel over an 8192-pixel image, and all
/// positions stay inside `i64` in the tests below.
const FAR_VANISHING_POINT: f64 = (1u64 << 20) as f64;

/// The most lines any view of a `width × height` image has: the size a
/// [`LinePool`](crate::LinePool) needs a frame. A frame has about `width`
/// lines at shallow pitch and up to about twice its perimeter straight down.
pub const fn max_lines(width: u32, height: u32) -> u32 {
    3 * width + 2 * height + 32
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
    /// and the lines are parallel (the columns).
    vanishing: Option<(i64, i64)>,
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
    /// radians down, with `tangent = tan(hfov / 2)`. Float set-up, once a
    /// frame; everything per pixel is integer.
    pub fn new(width: u32, height: u32, pitch: f64, tangent: f64) -> Self {
        let (w, h) = (f64::from(width), f64::from(height));
        // Pixel (c, j), j rows from the bottom, looks along
        // f + r·tan·((2c+1)/w − 1) + u·tan·((2j+1−h)/w); its horizontal part
        // vanishes at c = (w−1)/2 and cos p + sin p·tan·(2j+1−h)/w = 0.
        let u_v = i64::from(width - 1) << (IMG_FRAC - 1);
        let cot = libm::cos(pitch) / libm::sin(pitch);
        let j_v = (h - 1.0 - cot * w / tangent) * 0.5;
        let parallel = Sector {
            along_rows: true,
            vanishing: None,
            s_ref: height as i32 - 1,
            first: 0,
            last: height as i32 - 1,
            step: 1,
            k_first: 0,
            lines: width,
            cross_len: width as i32,
        };
        if !j_v.is_finite() || j_v.abs() > FAR_VANISHING_POINT {
            return Self {
                sectors: [Some(parallel), None, None, None],
            };
        }
        let mut v_v = (j_v * IMG_ONE as f64) as i64;
        // Keep V off every pixel center, half pixel and diagonal through a
        // pixel center: with `u_v` a multiple of one half, that makes every
        // pixel strictly inside one sector.
        if v_v.rem_euclid(IMG_ONE / 2) == 0 {
            v_v += 1;
        }
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
    for s in [lo, hi] {
        let a = (f64::from(s) - s_v).abs();
        let t_lo = (t_v - a).max(0.0);
        let t_hi = (t_v + a).min(f64::from(cross_len - 1));
        if t_lo > t_hi {
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
    /// Cross coordinate per unit of axis, Q32 (`(K − t_V) / (s_ref − s_V)`).
    slope: i64,
    /// The ownership test's per-line terms (see [`Line::owns`]), Q8:
    /// `|s_ref − s_V|`, and `K ∓ ½ − t_V`.
    far: i64,
    nearest_from: i64,
    nearest_to: i64,
    /// The row skip's terms (see [`OwnedPixels::holds_no_pixel`]): rows
    /// nearer the vanishing point than `skip_within` (Q8, `far / 2`; 0 for
    /// no skip) are tested, with `2^30 / far` rounded up.
    skip_within: u32,
    inverse_far: u32,
}

/// The most a line's point ([`Line::cross_at`], Q16) is off the exact
/// line: the slope's truncation and the shift's, with room to spare.
const CROSS_ERROR_Q16: i64 = 4;

/// A pixel a line owns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Owned {
    /// Image position, y = 0 at the top (the sink's coordinates).
    pub x: u32,
    pub y: u32,
    /// Axis coordinate of the pixel.
    pub s: i32,
    /// The pixel's center less its line's point there, along the cross
    /// coordinate, Q16 pixels (within ±1/2).
    pub offset: i64,
    /// The line's point there: its cross coordinate, Q16.
    pub cross: i64,
}

impl View {
    /// Lines in this frame: the units a caster or a pool hands out.
    pub fn lines(&self) -> u32 {
        self.lines.count()
    }

    /// Line `index`, or `None` past the last.
    pub(crate) fn line(&self, index: u32) -> Option<Line> {
        let (sector, k) = self.lines.get(index)?;
        let (t, s) = (i64::from(k), i64::from(sector.s_ref));
        let (u, v) = if sector.along_rows { (t, s) } else { (s, t) };
        let reference = core::array::from_fn(|i| {
            self.base[i].to_bits()
                + self.per_column[i].to_bits() * u
                + self.per_row[i].to_bits() * v
        });
        let slope = match sector.vanishing {
            None => 0,
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
        let (s_v, t_v) = sector.vanishing.unwrap_or((0, 0));
        let k_t = (i64::from(k) << IMG_FRAC) - t_v;
        let far = ((i64::from(sector.s_ref) << IMG_FRAC) - s_v).abs();
        // Both under 2^31: one 32-bit divide on a 32-bit core.
        let (skip_within, inverse_far) = match sector.vanishing {
            Some(_) if (1..1 << 30).contains(&far) => {
                ((far / 2) as u32, div_ceil(1 << 30, far) as u32)
            }
            _ => (0, 0),
        };
        Some(Line {
            sector,
            k,
            reference,
            slope,
            far,
            nearest_from: k_t - IMG_ONE / 2,
            nearest_to: k_t + IMG_ONE / 2,
            skip_within,
            inverse_far,
        })
    }

    /// The direction through the point of `line` at axis coordinate `s`
    /// plus `offset16` sixteenths (I32F32 bits).
    #[inline]
    pub(crate) fn direction_on(&self, line: &Line, s: i32, offset16: i64) -> [i64; 3] {
        let s_q16 = (i64::from(s) << COORD_FRAC_BITS) + (offset16 << (COORD_FRAC_BITS - 4));
        self.direction_at(line, s_q16, line.cross_at(s_q16))
    }

    /// The direction through the pixel `pixel` of `line` looks along: the
    /// line's point at its axis coordinate, worked out when it was found.
    #[inline]
    pub(crate) fn direction_of(&self, line: &Line, pixel: &Owned) -> [i64; 3] {
        self.direction_at(line, i64::from(pixel.s) << COORD_FRAC_BITS, pixel.cross)
    }

    /// The direction through image-plane point (`s_q16`, `t_q16`): axis
    /// and cross coordinates of `line`'s sector, Q16.
    #[inline]
    fn direction_at(&self, line: &Line, s_q16: i64, t_q16: i64) -> [i64; 3] {
        let (u, v) = if line.sector.along_rows {
            (t_q16, s_q16)
        } else {
            (s_q16, t_q16)
        };
        core::array::from_fn(|i| {
            self.base[i].to_bits()
                + scale(self.per_column[i].to_bits(), u)
                + scale(self.per_row[i].to_bits(), v)
        })
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

/// `v · q / 2^16` for a Q16 `q`, split so that neither product overflows:
/// `v` is a direction step (below 2^40 in I32F32 bits) and `|q|` below 2^30.
#[inline]
fn scale(v: i64, q: i64) -> i64 {
    v * (q >> COORD_FRAC_BITS) + ((v * (q & ((1 << COORD_FRAC_BITS) - 1))) >> COORD_FRAC_BITS)
}

impl Line {
    /// How far apart (in pixels, Q16) the centers of two of the line's
    /// pixels on neighbouring rows are: `√(1 + slope²)`, from 1 for a line
    /// along the axis to √2 on the diagonals.
    pub(crate) fn pixel_spacing_q16(&self) -> u64 {
        // Slope to Q16 (at most about 1 inside the sector), squared to Q32.
        let slope = (self.slope >> 16).unsigned_abs().min(1 << 20);
        ((1u64 << 32) + slope * slope).isqrt()
    }

    /// The line's cross coordinate at axis coordinate `s_q16` (Q16 both).
    #[inline]
    fn cross_at(&self, s_q16: i64) -> i64 {
        match self.sector.vanishing {
            None => i64::from(self.k) << COORD_FRAC_BITS,
            Some((s_v, t_v)) => {
                // Q32 slope times Q8 distance, to Q16.
                let ds = (s_q16 >> (COORD_FRAC_BITS - IMG_FRAC)) - s_v;
                (t_v << (COORD_FRAC_BITS - IMG_FRAC))
                    + ((self.slope * ds) >> (32 + IMG_FRAC - COORD_FRAC_BITS))
            }
        }
    }

    /// Whether the pixel at cross coordinate `t`, axis coordinate `s`, is
    /// this line's: inside the image and the sector, and nearer this line
    /// than any other of the sector. Exact integer arithmetic, so the lines
    /// of a sector share out its pixels with none left over or repeated.
    #[inline]
    fn owns(&self, t: i32, s: i32) -> bool {
        if !(0..self.sector.cross_len).contains(&t) {
            return false;
        }
        let Some((s_v, t_v)) = self.sector.vanishing else {
            return t == self.k;
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
        inside && self.nearest_from * a <= dt * b && dt * b < self.nearest_to * a
    }

    /// The pixels this line owns, in the order their rays are cast.
    pub fn pixels(&self, height: u32) -> OwnedPixels {
        OwnedPixels {
            line: *self,
            s: self.sector.first,
            entered: false,
            top_row: height as i32 - 1,
        }
    }
}

/// Iterator over a line's pixels (see [`Line::pixels`]).
#[derive(Debug, Clone)]
pub(crate) struct OwnedPixels {
    line: Line,
    s: i32,
    entered: bool,
    top_row: i32,
}

impl OwnedPixels {
    /// Whether row `s` holds none of the line's pixels, by one product:
    /// a pixel the line owns lies within its share of the row, `a / far`
    /// pixels wide and centered on the line's point `t_q16` (`a` the row's
    /// distance from the vanishing point; [`Line::owns`]). So if even the
    /// pixel `nearest` to the point lies outside, no pixel does. Near the
    /// vanishing point the lines are closer than a pixel and most rows hold
    /// none, so this spares them the exact test; it never rejects a row
    /// the exact test would not (the share is rounded up, the point's
    /// error allowed for). Rows where the share is half a pixel or more
    /// mostly hold a pixel and go straight to the exact test.
    #[inline(always)]
    fn holds_no_pixel(&self, s: i32, t_q16: i64, nearest: i32) -> bool {
        let Some((s_v, _)) = self.line.sector.vanishing else {
            return false;
        };
        let a = ((i64::from(s) << IMG_FRAC) - s_v).unsigned_abs();
        if a >= u64::from(self.line.skip_within) {
            return false;
        }
        // Half the share, Q16: 2^15 · a / far, rounded up (a < 2^29: one
        // 32 × 32-bit product).
        let half_share = ((a * u64::from(self.line.inverse_far)) >> 15) as i64 + 1;
        let miss = ((i64::from(nearest) << COORD_FRAC_BITS) - t_q16).abs();
        miss > half_share + CROSS_ERROR_Q16
    }
}

impl Iterator for OwnedPixels {
    type Item = Owned;

    fn next(&mut self) -> Option<Owned> {
        let sector = self.line.sector;
        let end = sector.last + sector.step;
        let limit = i64::from(sector.cross_len) << COORD_FRAC_BITS;
        while self.s != end {
            let s = self.s;
            self.s += sector.step;
            let t_q16 = self.line.cross_at(i64::from(s) << COORD_FRAC_BITS);
            // More than a pixel outside the image: no pixel of this row is
            // the line's. The line runs straight, so once it has been
            // inside and leaves, it is done.
            if t_q16 < -(1 << COORD_FRAC_BITS) || t_q16 > limit {
                if self.entered {
                    self.s = end;
                }
                continue;
            }
            self.entered = true;
            // The owned pixel is within half a pixel of the line, so it is
            // the nearest one or (by rounding) a neighbour.
            let nearest = ((t_q16 + (1 << (COORD_FRAC_BITS - 1))) >> COORD_FRAC_BITS) as i32;
            if self.holds_no_pixel(s, t_q16, nearest) {
                continue;
            }
            let other = if t_q16 >= i64::from(nearest) << COORD_FRAC_BITS {
                nearest + 1
            } else {
                nearest - 1
            };
            if let Some(t) = [nearest, other].into_iter().find(|&t| self.line.owns(t, s)) {
                let (x, row) = if sector.along_rows { (t, s) } else { (s, t) };
                return Some(Owned {
                    x: x as u32,
                    y: (self.top_row - row) as u32,
                    s,
                    offset: (i64::from(t) << COORD_FRAC_BITS) - t_q16,
                    cross: t_q16,
                });
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::Camera;
    use std::vec;

    fn view(pitch: f32, yaw: f32, size: (u32, u32), hfov: f32) -> View {
        let camera = Camera {
            eye: [10.0, 20.0, 30.0],
            yaw_deg: yaw,
            pitch_deg: pitch,
            hfov_deg: hfov,
            ..Camera::default()
        };
        View::new(&camera, size.0, size.1).unwrap()
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
    fn the_row_skip_passes_every_row_that_holds_a_pixel_of_the_line() {
        for (pitch, size) in [
            (30.0, (64, 48)),
            (60.0, (63, 47)),
            (89.9, (64, 48)),
            (90.0, (640, 480)),
        ] {
            let view = view(pitch, 25.0, size, 60.0);
            let (mut rows, mut skipped) = (0u32, 0u32);
            for index in 0..view.lines() {
                let line = view.line(index).unwrap();
                let pixels = line.pixels(size.1);
                let sector = line.sector;
                let mut s = sector.first;
                while s != sector.last + sector.step {
                    let t_q16 = line.cross_at(i64::from(s) << COORD_FRAC_BITS);
                    let nearest =
                        ((t_q16 + (1 << (COORD_FRAC_BITS - 1))) >> COORD_FRAC_BITS) as i32;
                    let holds = (nearest - 1..=nearest + 1).any(|t| line.owns(t, s));
                    if pixels.holds_no_pixel(s, t_q16, nearest) {
                        assert!(!holds, "pitch {pitch}: line {index} row {s} skipped");
                        skipped += 1;
                    }
                    rows += 1;
                    s += sector.step;
                }
            }
            // Straight down, most of a line's rows near the center are
            // another line's: the skip spares their exact test.
            if pitch == 90.0 {
                assert!(skipped * 3 > rows, "{skipped} of {rows} rows skipped");
            }
        }
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
                for tenth in -890..=900 {
                    let pitch = tenth as f32 / 10.0;
                    let Ok(view) = View::new(
                        &Camera {
                            pitch_deg: pitch,
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
                        "{size:?} hfov {hfov} pitch {pitch}: {}",
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
    fn a_pixels_direction_is_its_lines_direction_at_the_pixel() {
        // The caster takes a one-ray pixel's direction from the point the
        // pixel iterator found, not by working it out again.
        for pitch in [0.0, 10.0, 45.0, 90.0, -60.0] {
            let view = view(pitch, 33.0, (40, 30), 70.0);
            for index in 0..view.lines() {
                let line = view.line(index).unwrap();
                for p in line.pixels(30) {
                    assert_eq!(
                        view.direction_of(&line, &p),
                        view.direction_on(&line, p.s, 0),
                        "pitch {pitch} line {index} pixel {p:?}"
                    );
                }
            }
        }
    }
}
