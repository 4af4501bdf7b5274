//! A frame's pixel ownership as a table ([`PixelTable`]): every pixel's
//! line found in a pass over each sector's rows, then the pixels sorted
//! line by line in caller storage, for the tabled per-pixel path
//! ([`crate::render_pixel_path_tabled`]).

use super::*;

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
