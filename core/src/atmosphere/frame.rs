//! What a frame's pixels share ([`AtmosphereFrame`]): the view's
//! directions, the eye's fogged sky by sine and the fog's rate by height,
//! and the grid of cells at whose corners a pixel's sine and ray length
//! are worked out, blended between them for the pixels inside
//! ([`PixelGrid`]).

use super::*;

/// What a frame's pixels share: the view's directions in Q20 and the eye.
/// A pixel's direction is below 2^7 in size (the widest field of view
/// and the tallest image), so its components and their steps fit 32 bits.
#[derive(Debug, Clone)]
pub struct AtmosphereFrame {
    pub(super) base: [i32; 3],
    pub(super) per_column: [i32; 3],
    pub(super) per_row: [i32; 3],
    pub(super) top_row: i32,
    /// The eye's height, Q16.
    pub(super) eye_q16: i64,
    /// The sky as this eye sees it through the fog, by sine: entry `i`
    /// at sine `i/1024` (see [`SKY_FINE_STEPS`]); and what the fog leaves
    /// of the sky at each entry of [`PreparedAtmosphere`]'s gradient (in
    /// 1/256; for the sun's disc and glow, which go on before the fog).
    pub(super) sky: [Rgb; SKY_FINE_STEPS + 1],
    pub(super) sky_weights: [u16; SKY_STEPS + 1],
    /// The fog's halvings a voxel of path (Q31) at the mean density from
    /// the eye to the middle of each voxel of height: a path's length
    /// times it is the halvings along it.
    pub(super) rate: [u32; HEIGHT_VOXELS as usize + 1],
    pub(super) grid: PixelGrid,
}

/// What a pixel needs of its direction, at the corners of square cells of
/// `2^bits` pixels (corner `(i, j)` at column `i·2^bits`, row `j·2^bits`
/// from the bottom), blended between the corners for the pixels inside.
#[derive(Debug, Clone)]
pub(super) struct PixelGrid {
    pub(super) bits: u32,
    /// The sine of the elevation, Q20 (below the horizon negative).
    pub(super) sine: [[i32; GRID_CORNERS]; GRID_CORNERS],
    /// The reciprocal (Q16) of the unit direction's larger of its vertical
    /// component and its larger horizontal one: a ray's length over its
    /// height drop, or over its distance along its major axis.
    pub(super) reciprocal: [[i32; GRID_CORNERS]; GRID_CORNERS],
    /// Per cell, [`CELL_VERTICAL`], [`CELL_MIXED`] and [`CELL_SUN`].
    pub(super) cells: [[u8; GRID_CELLS]; GRID_CELLS],
}

/// The cell's rays are steeper than 45°: their length is over the height
/// drop.
pub(super) const CELL_VERTICAL: u8 = 1;
/// The corners disagree on the ray's largest component (vertical or which
/// horizontal axis), where the reciprocal has a kink: the pixels take
/// their own direction.
pub(super) const CELL_MIXED: u8 = 2;
/// The cell may reach into the sun's glow: its sky pixels take their own
/// direction.
const CELL_SUN: u8 = 4;

impl PixelGrid {
    /// The grid of a `width` × `height` image whose pixel `(column, row)`
    /// looks along `direction(column, row)` (Q20), the sun (if any) along
    /// `sun`.
    pub(super) fn new(
        width: u32,
        height: u32,
        direction: impl Fn(i32, i32) -> [i32; 3],
        sun: Option<&SunTable>,
    ) -> Self {
        // The smallest cells (a power of two pixels) that cover the image
        // in 64 a side: 8 pixels at 320 × 240, 1 at 64 × 48 (as many
        // corners as pixels: each pixel's own direction, in effect).
        let mut bits = 0;
        while ((width.max(height) - 1) >> bits) as usize >= GRID_CELLS {
            bits += 1;
        }
        let mut grid = Self {
            bits,
            sine: [[0; GRID_CORNERS]; GRID_CORNERS],
            reciprocal: [[0; GRID_CORNERS]; GRID_CORNERS],
            cells: [[0; GRID_CELLS]; GRID_CELLS],
        };
        let corners = |side: u32| ((side - 1) >> bits) as usize + 2;
        let (columns, rows) = (corners(width), corners(height));
        // Which component is largest at each corner (0 vertical, 1 x, 2
        // y), and the sun's cosine there (Q40).
        let mut largest = [[0u8; GRID_CORNERS]; GRID_CORNERS];
        let mut sun_cosine = [[i64::MIN; GRID_CORNERS]; GRID_CORNERS];
        for j in 0..rows {
            for i in 0..columns {
                let d = direction((i << bits) as i32, (j << bits) as i32);
                let unit = Unit::new(d);
                grid.sine[j][i] = unit.of(d[2]) as i32;
                let (axis, component) = largest_component(d);
                largest[j][i] = axis;
                grid.reciprocal[j][i] = reciprocal_q16(unit.of_size(component)) as i32;
                if let Some(sun) = sun {
                    sun_cosine[j][i] = sun.cosine(d.map(|c| unit.of(c)));
                }
            }
        }
        // A pixel's direction lies between its cell's corners', so within
        // a cell's diagonal of the nearest corner; the cell at the image's
        // center subtends the most. Half as much again, for the rounding.
        let near_sun = sun.map(|sun| {
            let center = |offset: usize| {
                let c = ((width / 2) >> bits) as usize + offset;
                let r = ((height / 2) >> bits) as usize + offset;
                direction((c << bits) as i32, (r << bits) as i32).map(f64::from)
            };
            let (a, b) = (center(0), center(1));
            let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
            let length = |v: [f64; 3]| libm::sqrt(v.iter().map(|c| c * c).sum::<f64>());
            let diagonal = libm::acos((dot / (length(a) * length(b))).clamp(-1.0, 1.0));
            let reach = (sun.glow_radians + 1.5 * diagonal).min(core::f64::consts::PI);
            to_fixed(libm::cos(reach), 2 * DIR_BITS) - (1 << 26)
        });
        for j in 0..rows - 1 {
            for i in 0..columns - 1 {
                let four = [(j, i), (j, i + 1), (j + 1, i), (j + 1, i + 1)];
                let axis = largest[j][i];
                let mut cell = if axis == 0 { CELL_VERTICAL } else { 0 };
                if four.iter().any(|&(r, c)| largest[r][c] != axis) {
                    cell |= CELL_MIXED;
                }
                if near_sun.is_some_and(|near| four.iter().any(|&(r, c)| sun_cosine[r][c] > near)) {
                    cell |= CELL_SUN;
                }
                grid.cells[j][i] = cell;
            }
        }
        grid
    }

    /// The cell of pixel `(column, row)` (row from the bottom): its flags,
    /// and where the pixel lies in it.
    #[inline(always)]
    pub(super) fn cell(&self, column: i32, row: i32) -> (u8, Corner) {
        let (i, j) = ((column >> self.bits) as usize, (row >> self.bits) as usize);
        let mask = (1 << self.bits) - 1;
        let flags = match self.cells.get(j).and_then(|cells| cells.get(i)) {
            Some(&flags) => flags,
            // (Every pixel of the image has a cell.)
            None => CELL_MIXED | CELL_SUN,
        };
        let corner = Corner {
            i,
            j,
            x: column & mask,
            y: row & mask,
        };
        (flags, corner)
    }

    /// `table` at `corner`'s pixel, blended between the cell's corners.
    #[inline(always)]
    pub(super) fn blend(&self, table: &[[i32; GRID_CORNERS]; GRID_CORNERS], at: &Corner) -> i32 {
        let (low, high) = (&table[at.j], &table[at.j + 1]);
        let corners = [low[at.i], low[at.i + 1], high[at.i], high[at.i + 1]];
        self.blend_corners(&corners, at.x, at.y)
    }

    /// A value at pixel `(x, y)` of a cell (from its lower left corner)
    /// blended between the values at its `corners` (lower left, lower
    /// right, upper left, upper right).
    #[inline(always)]
    pub(super) fn blend_corners(&self, corners: &[i32; 4], x: i32, y: i32) -> i32 {
        let (left, right) = self.edges_at(corners, y);
        left + (((right - left) * x) >> self.bits)
    }

    /// The values on a cell's left and right edges at row `y` of it
    /// (from its bottom), blended between its `corners` (as
    /// [`PixelGrid::blend_corners`]): along a row of the cell, a pixel's
    /// value is the blend of these two, so a row of pixels steps it by
    /// one add a pixel ([`PreparedAtmosphere::sink_over_sky`]).
    #[inline(always)]
    pub(super) fn edges_at(&self, corners: &[i32; 4], y: i32) -> (i32, i32) {
        let [low_left, low_right, high_left, high_right] = *corners;
        (
            low_left + (((high_left - low_left) * y) >> self.bits),
            low_right + (((high_right - low_right) * y) >> self.bits),
        )
    }

    /// What a sky pixel of cell `(i, j)` needs ([`SkyCell`]).
    pub(super) fn sky_cell(&self, i: i32, j: i32) -> SkyCell {
        let (column, row) = (i as usize, j as usize);
        let flags = self.cells.get(row).and_then(|cells| cells.get(column));
        match flags {
            Some(&flags) if flags & CELL_SUN == 0 => {
                let (low, high) = (&self.sine[row], &self.sine[row + 1]);
                SkyCell {
                    i,
                    j,
                    own_direction: false,
                    sine: [low[column], low[column + 1], high[column], high[column + 1]],
                }
            }
            // Near the sun, or (no pixel of the image is) outside the grid.
            _ => SkyCell {
                i,
                j,
                own_direction: true,
                sine: [0; 4],
            },
        }
    }
}

/// What a sink keeps from one sky pixel to the next
/// ([`PreparedAtmosphere::pixel_color`]): the last one's cell of the frame's
/// grid and the sines at its corners. It belongs to one
/// [`AtmosphereFrame`]: start each frame from `SkyCell::default()`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SkyCell {
    pub(super) i: i32,
    pub(super) j: i32,
    /// Its pixels take their own direction: it may reach the sun's glow.
    pub(super) own_direction: bool,
    pub(super) sine: [i32; 4],
}

impl SkyCell {
    /// Whether every pixel of the cell looks at or below the horizon, away
    /// from the sun: their sines, blended between the corners', are then
    /// at most 0 (a blend's rounding stays within its ends), and their sky
    /// is the horizon's color.
    pub(super) fn below_horizon(&self) -> bool {
        !self.own_direction && self.sine.iter().all(|&sine| sine <= 0)
    }
}

impl Default for SkyCell {
    /// No cell yet.
    fn default() -> Self {
        Self {
            i: -1,
            j: -1,
            own_direction: true,
            sine: [0; 4],
        }
    }
}

/// A pixel's place in its [`PixelGrid`] cell: the cell's lower-left
/// corner, and the pixel's offset from it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Corner {
    pub(super) i: usize,
    pub(super) j: usize,
    pub(super) x: i32,
    pub(super) y: i32,
}

/// Pixel `(column, row)`'s direction (row from the bottom; Q20) from the
/// frame's first pixel's and its steps: each product is one 32 × 32-bit
/// multiply, and the sum fits 32 bits.
#[inline(always)]
pub(super) fn direction(
    base: &[i32; 3],
    per_column: &[i32; 3],
    per_row: &[i32; 3],
    column: i32,
    row: i32,
) -> [i32; 3] {
    core::array::from_fn(|i| {
        (i64::from(base[i])
            + i64::from(column) * i64::from(per_column[i])
            + i64::from(row) * i64::from(per_row[i])) as i32
    })
}

/// Direction `d`'s largest component by size, vertical first (0, else 1
/// for x, 2 for y, x on a tie between them; the horizontal one on a tie
/// with the vertical), and that size.
#[inline(always)]
pub(super) fn largest_component(d: [i32; 3]) -> (u8, u32) {
    let [x, y, z] = d.map(i32::unsigned_abs);
    if z > x.max(y) {
        (0, z)
    } else if x >= y {
        (1, x)
    } else {
        (2, y)
    }
}
