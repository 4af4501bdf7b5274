//! A line's pixels one after another: [`OwnedPixels`] steps the exact
//! ownership test row by row by adds, [`StraightPixels`] walks a
//! level view's columns; both are [`LinePixels`].

use super::*;

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
pub(super) fn image_position(along_rows: bool, top_row: i32, t: i32, s: i32) -> (u32, u32) {
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
    pub(super) along_rows: bool,
    /// The row next looked at, the row past the last, and the step.
    pub(super) s: i32,
    pub(super) end: i32,
    pub(super) step: i32,
    /// The far edge's row (`along` counts from it) and the image's top row
    /// (`y` counts from it), along the axis; pixels across.
    pub(super) s_ref: i32,
    pub(super) top_row: i32,
    pub(super) cross_len: i32,
    /// The window on row `s` starts at `(K − ½ − t_V)·a` and is `a` wide
    /// (Q16, `a` times one pixel): its start's change a row, its width
    /// and the width's change a row.
    from_step: W,
    pub(super) width: W,
    width_step: W,
    /// The window's start moves toward larger `t` from row to row (or
    /// stays), so the candidate only ever rises; else it only falls.
    rising: bool,
    /// The candidate pixel `t`, how far `(t − t_V)·b` is past the window's
    /// start on row `s` (Q16), and its change a pixel, `b`.
    pub(super) t: i32,
    gap: W,
    b_step: W,
    /// `t_V` (Q8) where a pixel may lie outside the sector's cone (only
    /// the lines at its edges); `None` where none can.
    pub(super) cone: Option<i64>,
    /// The line's point on row `s` less `t_V`, Q40 (the Q32 slope times the
    /// row's Q8 distance from `V`), its change a row, and `t_V` in Q16.
    pub(super) point: i64,
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
    pub(super) fn new(line: &Line, height: u32) -> Self {
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
    pub(super) along_rows: bool,
    /// The cross coordinate the line keeps to (the column along rows, the
    /// row from the bottom along columns); the axis coordinate steps.
    pub(super) t: i32,
    /// The axis position next, the one past the last, and the step.
    pub(super) s: i32,
    pub(super) end: i32,
    pub(super) step: i32,
    pub(super) s_ref: i32,
    pub(super) top_row: i32,
    /// Every pixel's center less the line's point (Q16): the same on
    /// every row.
    pub(super) offset: i64,
}

impl StraightPixels {
    /// Whether every pixel's center lies on the line: then its ray's
    /// horizontal direction is the line's own, and it drifts nowhere.
    #[inline(always)]
    pub(crate) fn centered(&self) -> bool {
        self.offset == 0
    }

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
