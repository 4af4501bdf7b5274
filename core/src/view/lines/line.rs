//! One image line ([`Line`]): its sector and its point, the horizontal
//! direction its rays share and each ray's vertical component, the
//! direction words a ray's slope and drift are worked out from, and
//! which pixels it owns by the exact test.

use super::*;

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
    pub(super) per_axis: [i64; 3],
    /// The vertical component of the direction's step to the next pixel
    /// across the line (I32F32): a pixel's ray takes its center's
    /// elevation from it ([`Line::up_word`]).
    pub(super) across_up: i64,
    /// Cross coordinate per unit of axis, Q32 (`(K − t_V) / (s_ref − s_V)`).
    pub(super) slope: i64,
    /// The ownership test's per-line terms (see `Line::owns`), Q8:
    /// `|s_ref − s_V|`, and `K − ½ − t_V`.
    pub(super) far: i64,
    pub(super) nearest_from: i64,
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
    pub(super) major: [i32; 2],
    pub(super) up: [i32; 2],
    /// The vertical component's step across the line, in 2^16 direction
    /// bits.
    pub(super) across_up: i32,
    /// The line's point on the far edge's row (cross coordinate `K`,
    /// Q16), its cross coordinate's change a row (Q24: within ±1), and
    /// that row.
    t_far: i32,
    pub(super) lean: i32,
    pub(super) s_ref: i32,
    pub(super) along_rows: bool,
    pub(super) top_row: i32,
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
    /// up the sideways part, see [`crate::view::plane::Plane::drift`]) and takes
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
    pub(super) fn cross_at(&self, s_q16: i64) -> i64 {
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
    pub(super) fn owns(&self, t: i32, s: i32) -> bool {
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
    pub(super) fn anchor(&self) -> (i64, i64) {
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
    pub(super) fn rows_in_image(&self) -> (i32, i32) {
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
