//! The binary pyramid: coarser levels of the terrain, and conservative
//! height bounds for the hierarchical first hit (Cohen-Or §2).
//!
//! # Levels
//! Level 0 is the terrain itself. Grid point `i` of level `l` sits at world
//! coordinate `i·2^l`, so every grid line of a coarser level is a grid line
//! of every finer one and a ray that doubles its step at an even step stays
//! on the coarser grid. A level has `ceil((side − 1) / 2^l) + 1` points per
//! side, so it always covers the whole map; maps of any size are handled (a
//! side that is not `2^n + 1` gets coarse points up to `2^l − 1` voxels past
//! the far edge, filtered from the clamped edge, which no ray samples because
//! rays are clipped to the level-0 map). Levels go up until both sides are 2.
//!
//! # Filter
//! Colors: each coarse point is the tent filter (`[1 2 1] / 4` along each
//! axis, so `1/16 … 4/16` in 2-D) of the finer level centered on it, the
//! filter that keeps a vertex-aligned grid unbiased (a box filter over the
//! four children would shift every level by half a fine voxel). A pixel
//! then shows the average color of the voxels it covers.
//!
//! Heights decide silhouettes and occlusion. The caster interpolates a
//! coarse level linearly between its points, and a chord between two
//! points runs below every ridge and above every valley between them: a
//! coarse level made of the terrain's own points
//! ([`HeightFilter::Subsample`]) sinks the far ridges, and with them the
//! silhouettes. The default ([`HeightFilter::Wavelet`]) is the low-pass of
//! the LeGall 5/3 wavelet (JPEG 2000's lossless filter), `[−1 2 6 2 −1] / 8`
//! along each axis: it keeps a plane, and where the surface curves down (a
//! ridge) it lifts a coarse point, where it curves up (a valley) it lowers
//! one, by about what the chords beside the point miss. On a parabola
//! `a·x²/2` (x in fine voxels) it moves a point by `−a/4`, where the
//! chords' least-squares fit moves it by `−a/3`, subsampling by `0` and the
//! tent mean by `+a/4`, the wrong way. It is kept within the lowest and
//! highest of the 25 points it weighs, so it rings past no cliff, and a
//! crest or a trough that is itself a coarse point stays where subsampling
//! puts it.
//! [`HeightFilter::Mean`] (the tent filter) lowers every peak and raises
//! every valley toward the local mean; [`HeightFilter::Max`] (the largest
//! of the nine) raises and thickens all far terrain. Measured against the
//! exact reference, the wavelet is the closest of the four on most views
//! and subsampling next; the README's accuracy table prints all four.
//!
//! # Bounds
//! Bound cell `(i, j)` of level `b ≥ 1` covers the closed square
//! `[i·2^b, (i+1)·2^b]²` and holds a height no lower than any point of
//! levels `0..=b` in it, so a skip over the cell cannot miss a hit on any of
//! those levels (or on a blend of two of them). The first hit never tests a
//! cell below the level the caster samples there.
//!
//! Storage is the caller's: [`pyramid_points`] and [`pyramid_cells`] are
//! `const fn`s, so a board can size `static` buffers at compile time (or put
//! a pyramid built on the host in flash and wrap it with [`Pyramid::new`]).

use crate::color::Rgb;
use crate::config::{MAX_LEVEL, MAX_MAP_SIDE};
use crate::roughness::RoughnessSum;
use crate::surface::{Extent, Surface};
use crate::terrain::Terrain;
use core::fmt;
use heapless::Vec;

/// Levels a pyramid can hold, level 0 included.
pub const MAX_LEVELS: usize = MAX_LEVEL as usize + 1;

/// How coarse heights are made from finer ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HeightFilter {
    /// The LeGall 5/3 wavelet's low-pass of the 5 × 5 finer points around
    /// it (`[−1 2 6 2 −1] / 8` along each axis), kept within their lowest
    /// and highest: its chords fit the finer surface better than the
    /// points themselves do. Closest to the terrain's silhouettes
    /// (measured: see the module notes).
    #[default]
    Wavelet,
    /// The finer point at the coarse point's own position: every level
    /// passes through points of the terrain itself.
    Subsample,
    /// The tent-weighted mean of the nine finer points around it.
    Mean,
    /// The largest of the nine finer points around it.
    Max,
}

impl HeightFilter {
    /// Every filter, the default first.
    pub const ALL: [Self; 4] = [Self::Wavelet, Self::Subsample, Self::Mean, Self::Max];
}

/// Points per side of level `level` of a map side `side` (0 for level 0 of
/// a degenerate side).
pub const fn level_side(side: u32, level: u32) -> u32 {
    if side < 2 || level > 31 {
        return side;
    }
    let span = (side - 1) as u64;
    let step = 1u64 << level;
    span.div_ceil(step) as u32 + 1
}

/// Number of levels of a `width × depth` map's pyramid, level 0 included
/// (1 for a map with no coarser level, such as 2 × 2).
pub const fn level_count(width: u32, depth: u32) -> usize {
    let mut levels = 1;
    while level_side(width, levels as u32 - 1) > 2 || level_side(depth, levels as u32 - 1) > 2 {
        levels += 1;
    }
    levels
}

/// Sum over levels 1 and up of `(points a row − less)·(points a column −
/// less)`: points with `less = 0`, cells with `less = 1`.
const fn sum_over_levels(width: u32, depth: u32, less: usize) -> usize {
    let mut total = 0;
    let mut level = 1;
    while level < level_count(width, depth) {
        let (w, d) = (
            level_side(width, level as u32),
            level_side(depth, level as u32),
        );
        total += (w as usize - less) * (d as usize - less);
        level += 1;
    }
    total
}

/// Grid points in the coarser levels (1 and up) of a `width × depth` map:
/// the length of the height and of the color storage.
pub const fn pyramid_points(width: u32, depth: u32) -> usize {
    sum_over_levels(width, depth, 0)
}

/// Bound cells in levels 1 and up: the length of the bound storage.
pub const fn pyramid_cells(width: u32, depth: u32) -> usize {
    sum_over_levels(width, depth, 1)
}

/// Bytes of pyramid storage a `width × depth` map needs (U12.4 heights,
/// RGB colors and U12.4 bounds), on top of the map itself.
pub const fn pyramid_bytes(width: u32, depth: u32) -> usize {
    pyramid_points(width, depth) * (2 + 3) + pyramid_cells(width, depth) * 2
}

/// Why a pyramid could not be built or wrapped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PyramidError {
    /// The height storage is shorter than [`pyramid_points`].
    HeightStorage {
        /// Elements needed.
        needed: usize,
    },
    /// The color storage is shorter than [`pyramid_points`].
    ColorStorage {
        /// Elements needed.
        needed: usize,
    },
    /// The bound storage is shorter than [`pyramid_cells`].
    BoundStorage {
        /// Elements needed.
        needed: usize,
    },
}

impl fmt::Display for PyramidError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (what, needed) = match self {
            Self::HeightStorage { needed } => ("height", needed),
            Self::ColorStorage { needed } => ("color", needed),
            Self::BoundStorage { needed } => ("bound", needed),
        };
        write!(
            f,
            "pyramid {what} storage too small: {needed} elements needed"
        )
    }
}

impl core::error::Error for PyramidError {}

/// A terrain and its coarser levels, borrowed from the caller.
#[derive(Debug, Clone)]
pub struct Pyramid<'a> {
    levels: Vec<Terrain<'a>, MAX_LEVELS>,
    /// `bounds[b - 1]`: the bound cells of level `b`.
    bounds: Vec<&'a [u16], MAX_LEVELS>,
    /// Level 0's roughness ([`crate::roughness`]), measured when the
    /// coarser levels were added; 0 for a flat pyramid.
    roughness: u8,
}

impl<'a> Pyramid<'a> {
    /// A pyramid of one level: single-resolution rendering, no first-hit
    /// acceleration, no storage.
    pub fn flat(terrain: Terrain<'a>) -> Self {
        let mut levels = Vec::new();
        // Capacity is at least one: this cannot fail.
        let _ = levels.push(terrain);
        Self {
            levels,
            bounds: Vec::new(),
            roughness: 0,
        }
    }

    /// Wraps storage that [`Pyramid::build`] filled for this terrain (on
    /// this machine or another: a board can keep it in flash). Longer
    /// storage is fine; only the prefix is used. Measures the terrain's
    /// roughness (a pass over a quarter of its rows; see
    /// [`Pyramid::with_roughness`] to skip it when it is known).
    pub fn new(
        terrain: Terrain<'a>,
        heights: &'a [u16],
        colors: &'a [Rgb],
        bounds: &'a [u16],
    ) -> Result<Self, PyramidError> {
        let mut pyramid = Self::with_roughness(terrain, heights, colors, bounds, 0)?;
        if pyramid.levels.len() > 1 {
            let mut sum = RoughnessSum::default();
            sum.add_grid(terrain.heights(), terrain.width() as usize);
            pyramid.roughness = sum.roughness();
        }
        Ok(pyramid)
    }

    /// [`Pyramid::new`] with the roughness given, not measured: the value
    /// an earlier [`Pyramid::roughness`] of the same terrain returned (a
    /// host that wraps its storage for every frame keeps it), or one
    /// stored with the pyramid.
    pub fn with_roughness(
        terrain: Terrain<'a>,
        heights: &'a [u16],
        colors: &'a [Rgb],
        bounds: &'a [u16],
        roughness: u8,
    ) -> Result<Self, PyramidError> {
        let (width, depth) = (terrain.width(), terrain.depth());
        check_storage(width, depth, heights.len(), colors.len(), bounds.len())?;
        let mut pyramid = Self::flat(terrain);
        let (mut heights, mut colors, mut bounds) = (heights, colors, bounds);
        for level in 1..level_count(width, depth) as u32 {
            let (w, d) = (level_side(width, level), level_side(depth, level));
            let points = w as usize * d as usize;
            let cells = (w as usize - 1) * (d as usize - 1);
            let (h, h_rest) = heights.split_at(points);
            let (c, c_rest) = colors.split_at(points);
            let (b, b_rest) = bounds.split_at(cells);
            (heights, colors, bounds) = (h_rest, c_rest, b_rest);
            // Coarse levels never exceed the base's highest height.
            let coarse = Terrain::with_bounds(w, d, h, c, terrain.max_height());
            // Capacities hold every level a map of MAX_MAP_SIDE can have.
            let _ = pyramid.levels.push(coarse);
            let _ = pyramid.bounds.push(b);
        }
        if pyramid.levels.len() > 1 {
            pyramid.roughness = roughness;
        }
        Ok(pyramid)
    }

    /// Level 0's roughness ([`RoughnessSum::roughness`]): how far the
    /// coarse levels scale the pixel-to-voxel ratio down (see
    /// [`crate::roughness`]). Measured by [`Pyramid::new`], 0 for a flat
    /// pyramid.
    #[inline]
    pub fn roughness(&self) -> u8 {
        self.roughness
    }

    /// Fills `heights`, `colors` and `bounds` with the coarser levels of
    /// `terrain` and their height bounds. Needs [`pyramid_points`] heights
    /// and colors and [`pyramid_cells`] bounds; allocates nothing.
    pub fn build(
        terrain: &Terrain<'_>,
        filter: HeightFilter,
        heights: &mut [u16],
        colors: &mut [Rgb],
        bounds: &mut [u16],
    ) -> Result<(), PyramidError> {
        Self::build_with_sticks(terrain, filter, None, heights, colors, bounds)
    }

    /// [`Pyramid::build`] for a terrain with objects standing on it
    /// (`sticks`, if any): each coarser level's heights are raised to the
    /// tops of the sticks nearest its points before the bounds are made,
    /// so a far object keeps its silhouette (Cohen-Or's coarse heights as
    /// the maximum over the finer sticks); colors are filtered as the
    /// terrain's.
    pub fn build_with_sticks(
        terrain: &Terrain<'_>,
        filter: HeightFilter,
        sticks: Option<&crate::StickLayer<'_>>,
        heights: &mut [u16],
        colors: &mut [Rgb],
        bounds: &mut [u16],
    ) -> Result<(), PyramidError> {
        let (width, depth) = (terrain.width(), terrain.depth());
        check_storage(width, depth, heights.len(), colors.len(), bounds.len())?;
        build_levels(terrain, filter, heights, colors);
        if let Some(sticks) = sticks {
            sticks.raise_coarse(terrain, heights);
        }
        build_bounds(terrain, heights, bounds);
        Ok(())
    }

    /// Number of levels, level 0 included.
    #[inline]
    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    /// The highest level (0 for a flat pyramid).
    #[inline]
    pub fn top(&self) -> u8 {
        (self.levels.len() - 1) as u8
    }

    /// Level `level`, if the pyramid has it.
    #[inline]
    pub fn level(&self, level: usize) -> Option<&Terrain<'a>> {
        self.levels.get(level)
    }

    /// Level 0: the terrain itself.
    #[inline]
    pub fn base(&self) -> &Terrain<'a> {
        // A pyramid always holds level 0.
        &self.levels[0]
    }

    /// The bound cells of level `level` (1 and up), if there are any.
    pub(crate) fn bounds(&self, level: usize) -> Option<&'a [u16]> {
        level
            .checked_sub(1)
            .and_then(|i| self.bounds.get(i))
            .copied()
    }

    /// Whether the hierarchical first hit can be used.
    #[inline]
    pub fn has_bounds(&self) -> bool {
        !self.bounds.is_empty()
    }

    /// Bytes of terrain the pyramid lends the caster: every level and the
    /// bounds.
    pub fn bytes(&self) -> usize {
        self.levels.iter().map(Terrain::bytes).sum::<usize>()
            + self
                .bounds
                .iter()
                .map(|b| core::mem::size_of_val(*b))
                .sum::<usize>()
    }
}

impl<'a> Surface for Pyramid<'a> {
    type Grid<'s>
        = Terrain<'s>
    where
        Self: 's;

    #[inline(always)]
    fn grid(&self, level: u8) -> Option<Terrain<'_>> {
        self.levels.get(usize::from(level)).copied()
    }
    #[inline(always)]
    fn base(&self) -> Terrain<'_> {
        *Pyramid::base(self)
    }
    #[inline(always)]
    fn roughness(&self) -> u8 {
        self.roughness
    }
    #[inline(always)]
    fn stride(&self, level: u8) -> Option<isize> {
        // Read through the reference: a copy of the level's slices would
        // cost more than the width.
        self.levels
            .get(usize::from(level))
            .map(|t| t.width() as isize)
    }
    #[inline(always)]
    fn top(&self) -> u8 {
        Pyramid::top(self)
    }
    #[inline]
    fn extent(&self) -> Extent {
        self.base().extent()
    }
    #[inline]
    fn has_bounds(&self) -> bool {
        Pyramid::has_bounds(self)
    }
    #[inline]
    fn bound(&self, level: u8, x: i64, y: i64) -> Option<(u16, usize)> {
        let base = self.base();
        let cells_x = i64::from(level_side(base.width(), u32::from(level))) - 1;
        let cells_y = i64::from(level_side(base.depth(), u32::from(level))) - 1;
        if !(0..cells_x).contains(&x) || !(0..cells_y).contains(&y) {
            return None;
        }
        let cell = (y * cells_x + x) as usize;
        let bound = self.bounds(usize::from(level))?.get(cell).copied()?;
        Some((bound, cell))
    }
}

fn check_storage(
    width: u32,
    depth: u32,
    heights: usize,
    colors: usize,
    bounds: usize,
) -> Result<(), PyramidError> {
    debug_assert!(width <= MAX_MAP_SIDE && depth <= MAX_MAP_SIDE);
    let points = pyramid_points(width, depth);
    let cells = pyramid_cells(width, depth);
    if heights < points {
        return Err(PyramidError::HeightStorage { needed: points });
    }
    if colors < points {
        return Err(PyramidError::ColorStorage { needed: points });
    }
    if bounds < cells {
        return Err(PyramidError::BoundStorage { needed: cells });
    }
    Ok(())
}

/// Fills `heights` and `colors` (sized as [`check_storage`] checked) with
/// the coarser levels of `terrain`, each from the one below.
fn build_levels(
    terrain: &Terrain<'_>,
    filter: HeightFilter,
    heights: &mut [u16],
    colors: &mut [Rgb],
) {
    let (width, depth) = (terrain.width(), terrain.depth());
    let levels = level_count(width, depth) as u32;
    // Mean (or max) levels, each from the one below.
    let mut offset = 0;
    for level in 1..levels {
        let (w, d) = (level_side(width, level), level_side(depth, level));
        let points = w as usize * d as usize;
        let (done, rest) = heights.split_at_mut(offset);
        let (done_c, rest_c) = colors.split_at_mut(offset);
        let (fine_h, fine_c, fw, fd): (&[u16], &[Rgb], u32, u32) = if level == 1 {
            (terrain.heights(), terrain.colors(), width, depth)
        } else {
            let (fw, fd) = (level_side(width, level - 1), level_side(depth, level - 1));
            let fine = fw as usize * fd as usize;
            (&done[offset - fine..], &done_c[offset - fine..], fw, fd)
        };
        let coarse = Grid { width: w, depth: d };
        let fine = Grid {
            width: fw,
            depth: fd,
        };
        downsample(
            fine,
            fine_h,
            fine_c,
            coarse,
            &mut rest[..points],
            &mut rest_c[..points],
            filter,
        );
        offset += points;
    }
}

#[derive(Debug, Clone, Copy)]
struct Grid {
    width: u32,
    depth: u32,
}

/// Builds one coarser level: each coarse point `(x, y)` sits on the finer
/// point `(2x, 2y)`. Colors are the tent-filtered mean of the 3 × 3 finer
/// points around it (weights 1 2 1 / 2 4 2 / 1 2 1, sum 16), heights per
/// `filter`. Neighbours past the map's edge repeat the edge.
///
/// Runs once at boot on a board, so it is written for a 32-bit core: the
/// tent is separable, and the clamped neighbours are worked out once a row
/// and once a column in word arithmetic.
fn downsample(
    fine: Grid,
    fine_h: &[u16],
    fine_c: &[Rgb],
    coarse: Grid,
    out_h: &mut [u16],
    out_c: &mut [Rgb],
    filter: HeightFilter,
) {
    let (fw, fd) = (fine.width as usize, fine.depth as usize);
    // The finer neighbours of coarse coordinate `v` (`2v − 2` to `2v + 2`),
    // clamped into `0..side`. The tents use the middle three.
    let taps = |v: usize, side: usize| -> [usize; 5] {
        let last = side.saturating_sub(1);
        core::array::from_fn(|i| (2 * v + i).saturating_sub(2).min(last))
    };
    for y in 0..coarse.depth as usize {
        // The finer rows, sliced once a coarse row.
        let rows = taps(y, fd);
        let color_rows = middle(rows).map(|r| fine_c.get(r * fw..(r + 1) * fw).unwrap_or(&[]));
        let wide_height_rows = rows.map(|r| fine_h.get(r * fw..(r + 1) * fw).unwrap_or(&[]));
        let height_rows = middle(wide_height_rows);
        let (out_row, width) = (y * coarse.width as usize, coarse.width as usize);
        if filter == HeightFilter::Wavelet {
            if let Some(out) = out_h.get_mut(out_row..out_row + width) {
                wavelet_row(wide_height_rows, fw, out);
            }
        }
        for x in 0..width {
            let columns = middle(taps(x, fw));
            let mut c_sum = [0u32; 3];
            for (row, row_weight) in color_rows.iter().zip([1u32, 2, 1]) {
                for (&column, weight) in columns.iter().zip([1u32, 2, 1]) {
                    let c = row.get(column).copied().unwrap_or([0; 3]);
                    for (s, v) in c_sum.iter_mut().zip(c) {
                        *s += row_weight * weight * u32::from(v);
                    }
                }
            }
            let height = |row: usize, column: usize| {
                height_rows[row].get(columns[column]).copied().unwrap_or(0)
            };
            let h = match filter {
                // The whole row was made above.
                HeightFilter::Wavelet => None,
                HeightFilter::Subsample => Some(height(1, 1)),
                HeightFilter::Mean => {
                    let mut sum = 0u32;
                    for (row, row_weight) in [1u32, 2, 1].into_iter().enumerate() {
                        for (column, weight) in [1u32, 2, 1].into_iter().enumerate() {
                            sum += row_weight * weight * u32::from(height(row, column));
                        }
                    }
                    Some(((sum + 8) >> 4) as u16)
                }
                HeightFilter::Max => (0..9).map(|t| height(t / 3, t % 3)).max(),
            };
            if let (Some(out_h), Some(h)) = (out_h.get_mut(out_row + x), h) {
                *out_h = h;
            }
            if let Some(out_c) = out_c.get_mut(out_row + x) {
                *out_c = c_sum.map(|s| ((s + 8) >> 4) as u8);
            }
        }
    }
}

/// A weighted sum of heights, with the lowest and highest of them.
#[derive(Debug, Clone, Copy)]
struct ColumnStats {
    sum: i32,
    lowest: i32,
    highest: i32,
}

impl ColumnStats {
    const EMPTY: Self = Self {
        sum: 0,
        lowest: i32::MAX,
        highest: i32::MIN,
    };

    fn add(&mut self, weight: i32, height: u16) {
        let h = i32::from(height);
        self.sum += weight * h;
        self.lowest = self.lowest.min(h);
        self.highest = self.highest.max(h);
    }

    /// Adds `other`'s sum times `weight`, and its range.
    fn add_weighted(&mut self, weight: i32, other: &Self) {
        self.sum += weight * other.sum;
        self.lowest = self.lowest.min(other.lowest);
        self.highest = self.highest.max(other.highest);
    }
}

/// The middle three of five taps: a tent's, of the wavelet's.
fn middle<T: Copy>(five: [T; 5]) -> [T; 3] {
    [five[1], five[2], five[3]]
}

/// The LeGall 5/3 wavelet's low-pass along each axis ([`HeightFilter::Wavelet`]).
const WAVELET_LOW_PASS: [i32; 5] = [-1, 2, 6, 2, -1];

/// One coarse row of [`HeightFilter::Wavelet`] heights, `out.len()` points,
/// from the five finer rows `2y − 2` to `2y + 2` (clamped into the map, as
/// [`Pyramid::build`] and a streaming packer both have them) of a level
/// `fine_width` points wide. A point a row lacks reads as 0.
///
/// Each finer column's five rows are summed once: the window of five
/// columns moves two a coarse point, so three carry over.
pub fn wavelet_row(rows: [&[u16]; 5], fine_width: usize, out: &mut [u16]) {
    let last = fine_width.saturating_sub(1);
    let column = |c: usize| {
        let mut stats = ColumnStats::EMPTY;
        for (row, weight) in rows.iter().zip(WAVELET_LOW_PASS) {
            stats.add(weight, row.get(c.min(last)).copied().unwrap_or(0));
        }
        stats
    };
    // Columns 2x − 2 to 2x + 2: past the first point, the first three are
    // the point before's last three (the same finer columns, clamped
    // alike).
    let mut window = [0, 0, 0, 1, 2].map(column);
    for (x, out) in out.iter_mut().enumerate() {
        if x > 0 {
            window = [
                window[2],
                window[3],
                window[4],
                column(2 * x + 1),
                column(2 * x + 2),
            ];
        }
        // In words: at most 12 · 12 · 65535 in size.
        let mut all = ColumnStats::EMPTY;
        for (stats, weight) in window.iter().zip(WAVELET_LOW_PASS) {
            all.add_weighted(weight, stats);
        }
        *out = wavelet_height(all.sum, all.lowest, all.highest);
    }
}

/// A [`HeightFilter::Wavelet`] height from the [`WAVELET_LOW_PASS`]-weighted sum
/// of its 5 × 5 finer points (weights summing to 64) and their lowest and
/// highest: rounded, and kept within them, so that no coarse point rings
/// past a cliff's top or foot or leaves the terrain's range. (`lowest` is
/// taken to be at most `highest`; if not, `highest` wins.)
#[inline]
fn wavelet_height(weighted_sum: i32, lowest: i32, highest: i32) -> u16 {
    ((weighted_sum + 32) >> 6)
        .max(lowest)
        .min(highest)
        .clamp(0, i32::from(u16::MAX)) as u16
}

/// Fills the bound cells of every level (see the module notes):
/// `B_1(c)` is the largest of the level-0 and level-1 points in the closed
/// cell, and `B_l(c)` the largest of its four children's bounds and its own
/// level-`l` corners. So `B_l(c)` is no lower than any point of levels
/// `0..=l` in `c`, and no surface of those levels (nor a blend of two of
/// them) rises above it there.
fn build_bounds(terrain: &Terrain<'_>, coarse_heights: &[u16], bounds: &mut [u16]) {
    let (width, depth) = (terrain.width(), terrain.depth());
    let levels = level_count(width, depth) as u32;
    let (mut points_at, mut cells_at) = (0usize, 0usize);
    let mut children_at = 0usize;
    for level in 1..levels {
        let g = Grid {
            width: level_side(width, level),
            depth: level_side(depth, level),
        };
        let (cw, cd) = (g.width - 1, g.depth - 1);
        let points = &coarse_heights[points_at..points_at + (g.width * g.depth) as usize];
        let (lower, upper) = bounds.split_at_mut(cells_at);
        let children = &lower[children_at..];
        let cells = &mut upper[..(cw * cd) as usize];
        let child_grid = Grid {
            width: level_side(width, level - 1),
            depth: level_side(depth, level - 1),
        };
        // Every index below is inside its grid (cells stop one short of
        // each side), so none is clamped; a missing point would read as the
        // highest, which keeps the bound conservative.
        let point = |at: u32| points.get(at as usize).copied().unwrap_or(u16::MAX);
        for j in 0..cd {
            for i in 0..cw {
                let (top, bottom) = (j * g.width + i, (j + 1) * g.width + i);
                let mut b = point(top)
                    .max(point(top + 1))
                    .max(point(bottom))
                    .max(point(bottom + 1));
                if level == 1 {
                    let finest = terrain.heights();
                    let (x0, x1) = (2 * i as usize, (2 * i + 2).min(width - 1) as usize);
                    for y in 2 * j..(2 * j + 3).min(depth) {
                        let row = (y * width) as usize;
                        let taps = finest.get(row + x0..=row + x1).unwrap_or(&[u16::MAX]);
                        b = taps.iter().fold(b, |b, &h| b.max(h));
                    }
                } else {
                    let (ccw, ccd) = (child_grid.width - 1, child_grid.depth - 1);
                    for y in 2 * j..(2 * j + 2).min(ccd) {
                        for x in 2 * i..(2 * i + 2).min(ccw) {
                            let child = children.get((y * ccw + x) as usize);
                            b = b.max(child.copied().unwrap_or(u16::MAX));
                        }
                    }
                }
                if let Some(slot) = cells.get_mut((j * cw + i) as usize) {
                    *slot = b;
                }
            }
        }
        children_at = cells_at;
        points_at += (g.width * g.depth) as usize;
        cells_at += (cw * cd) as usize;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec;
    use std::vec::Vec as StdVec;

    #[test]
    fn level_sides_cover_the_map() {
        assert_eq!(level_side(1024, 0), 1024);
        assert_eq!(level_side(1024, 1), 513);
        assert_eq!(level_side(1025, 1), 513);
        assert_eq!(level_side(1024, 10), 2);
        assert_eq!(level_count(1024, 1024), 11);
        assert_eq!(level_count(2, 2), 1);
        assert_eq!(level_count(3, 2), 2);
        assert_eq!(level_count(MAX_MAP_SIDE, MAX_MAP_SIDE), 16);
        assert!(level_count(MAX_MAP_SIDE, 2) <= MAX_LEVELS);
        // Every level's last point reaches the far edge of the map.
        for side in [2u32, 3, 5, 100, 1000, 1024, 4097] {
            for level in 0..level_count(side, side) as u32 {
                assert!((level_side(side, level) - 1) << level >= side - 1);
            }
        }
        // About a third of the map again, as Cohen-Or's "a third more".
        let extra = pyramid_points(1025, 1025) as f64 / (1025.0 * 1025.0);
        assert!((extra - 1.0 / 3.0).abs() < 0.01, "{extra}");
    }

    fn map(side: u32, f: impl Fn(u32, u32) -> u16) -> (StdVec<u16>, StdVec<Rgb>) {
        let h = (0..side * side).map(|i| f(i % side, i / side)).collect();
        let c = (0..side * side).map(|i| [(i % 251) as u8, 0, 0]).collect();
        (h, c)
    }

    fn built(side: u32, h: &[u16], c: &[Rgb], filter: HeightFilter) -> [StdVec<u16>; 2] {
        let t = Terrain::new(side, side, h, c).unwrap();
        let mut ph = vec![0; pyramid_points(side, side)];
        let mut pc = vec![[0; 3]; pyramid_points(side, side)];
        let mut pb = vec![0; pyramid_cells(side, side)];
        Pyramid::build(&t, filter, &mut ph, &mut pc, &mut pb).unwrap();
        [ph, pb]
    }

    #[test]
    fn subsample_and_mean_keep_a_plane_and_max_keeps_a_peak() {
        // A tilted plane stays the same plane under both.
        let (h, c) = map(9, |x, _| x as u16 * 16);
        for filter in [HeightFilter::Subsample, HeightFilter::Mean] {
            let [ph, _] = built(9, &h, &c, filter);
            // Level 1 is 5 x 5; point (2, y) sits at world x = 4.
            assert_eq!(ph[2], 4 * 16);
            assert_eq!(ph[5 + 3], 6 * 16);
        }
        // A one-voxel peak on an even point: subsample and max keep it,
        // the mean spreads it.
        let (h, c) = map(9, |x, y| if (x, y) == (4, 4) { 160 } else { 0 });
        let [sub, _] = built(9, &h, &c, HeightFilter::Subsample);
        let [mean, _] = built(9, &h, &c, HeightFilter::Mean);
        let [max, _] = built(9, &h, &c, HeightFilter::Max);
        assert_eq!(sub[2 * 5 + 2], 160);
        assert_eq!(mean[2 * 5 + 2], 40);
        assert_eq!(max[2 * 5 + 2], 160);
        // On an odd point only the max keeps it; subsample steps over it
        // (the bounds still hold it, see below).
        let (h, c) = map(9, |x, y| if (x, y) == (3, 4) { 160 } else { 0 });
        let [sub, _] = built(9, &h, &c, HeightFilter::Subsample);
        let [max, _] = built(9, &h, &c, HeightFilter::Max);
        assert!(sub[..25].iter().all(|&v| v == 0));
        assert_eq!(max[2 * 5 + 1], 160);
    }

    #[test]
    fn the_wavelet_moves_points_of_a_parabola_by_a_quarter_of_its_curvature() {
        // Heights 2·x² (U12.4): curvature a = 4. Level-1 point x sits at
        // fine 2x. Away from the vertex the wavelet moves it by −a/4 = −1,
        // the tent by +1, subsampling not at all (module notes).
        let (h, c) = map(17, |x, _| 2 * (x * x) as u16);
        let at = |filter, x: usize| built(17, &h, &c, filter)[0][9 * 4 + x];
        for x in 2..=6 {
            let fine = 2 * (2 * x * 2 * x) as u16;
            assert_eq!(at(HeightFilter::Wavelet, x), fine - 1, "x = {x}");
            assert_eq!(at(HeightFilter::Subsample, x), fine);
            assert_eq!(at(HeightFilter::Mean, x), fine + 1);
        }
        // The vertex is the lowest of its 25 points: kept there.
        assert_eq!(at(HeightFilter::Wavelet, 0), 0);
        // A cliff: kept within the points around it, no ringing.
        let (h, c) = map(17, |x, _| if x < 7 { 0 } else { 3200 });
        let [wavelet, _] = built(17, &h, &c, HeightFilter::Wavelet);
        assert!(wavelet[..81].iter().all(|&v| v <= 3200));
        assert_eq!(wavelet[9 * 4 + 2], 0, "foot of the cliff, below 25 zeros");
        assert_eq!(wavelet[9 * 4 + 5], 3200);
    }

    #[test]
    fn the_wavelet_chords_fit_a_rough_map_closer_than_its_own_points() {
        // What the caster samples on level 1: heights along its grid lines,
        // linear between coarse points. Squared error against level 0 at
        // every fine point on the lines, over a rough map: waves of every
        // wavelength down to 2.2 voxels, in all directions, amplitude in
        // proportion to wavelength as terrain's roughly is.
        let side = 65u32;
        let (h, c) = map(side, |x, y| {
            let (x, y) = (x as f32, y as f32);
            let waves: f32 = (1..=24)
                .map(|k| {
                    let k = k as f32;
                    let (dx, dy) = ((k * 2.4).cos(), (k * 2.4).sin());
                    (800.0 / k) * (k * 0.12 * (x * dx + y * dy) + k * k).sin()
                })
                .sum();
            (3000.0 + waves) as u16
        });
        let error = |filter| {
            let [ph, _] = built(side, &h, &c, filter);
            let coarse = |x: u32, y: u32| f64::from(ph[(y * 33 + x) as usize]);
            let mut sum = 0.0;
            for a in (0..side).step_by(2) {
                for b in 0..side - 1 {
                    let (b0, t) = (b / 2, f64::from(b % 2) / 2.0);
                    // Along x on row a, and along y on column a.
                    let along_x = coarse(b0, a / 2) * (1.0 - t) + coarse(b0 + 1, a / 2) * t;
                    let along_y = coarse(a / 2, b0) * (1.0 - t) + coarse(a / 2, b0 + 1) * t;
                    sum += (along_x - f64::from(h[(a * side + b) as usize])).powi(2);
                    sum += (along_y - f64::from(h[(b * side + a) as usize])).powi(2);
                }
            }
            sum
        };
        let (wavelet, subsample, mean) = (
            error(HeightFilter::Wavelet),
            error(HeightFilter::Subsample),
            error(HeightFilter::Mean),
        );
        assert!(wavelet < 0.95 * subsample, "{wavelet} against {subsample}");
        assert!(subsample < mean, "{subsample} against {mean}");
    }

    #[test]
    fn every_level_is_its_definition_on_any_map_shape() {
        // Each coarse point from the finer points around it, edges
        // repeated: the tent mean of the 3 x 3 for colors, heights by the
        // filter (the wavelet's from the 5 x 5).
        for (w, d) in [(2u32, 2u32), (3, 2), (5, 8), (17, 12), (12, 17)] {
            let h: StdVec<u16> = (0..w * d)
                .map(|i| ((i * 37 + i / w * 91) % 53) as u16 * 7)
                .collect();
            let c: StdVec<Rgb> = (0..w * d)
                .map(|i| [(i * 13 % 256) as u8, (i * 7 % 256) as u8, (i % 256) as u8])
                .collect();
            for filter in HeightFilter::ALL {
                let t = Terrain::new(w, d, &h, &c).unwrap();
                let n = pyramid_points(w, d);
                let (mut ph, mut pc) = (vec![0; n], vec![[0; 3]; n]);
                let mut pb = vec![0; pyramid_cells(w, d)];
                Pyramid::build(&t, filter, &mut ph, &mut pc, &mut pb).unwrap();
                let p = Pyramid::new(t, &ph, &pc, &pb).unwrap();
                for l in 1..p.levels() {
                    let (fine, coarse) = (p.level(l - 1).unwrap(), p.level(l).unwrap());
                    let at = |x: i64, y: i64| {
                        let x = x.clamp(0, i64::from(fine.width()) - 1);
                        let y = y.clamp(0, i64::from(fine.depth()) - 1);
                        (y * i64::from(fine.width()) + x) as usize
                    };
                    for y in 0..i64::from(coarse.depth()) {
                        for x in 0..i64::from(coarse.width()) {
                            // (tent weight, height, color) of the 3 x 3 taps.
                            let taps: StdVec<(u32, u16, Rgb)> = (0..9i64)
                                .map(|t| {
                                    let (dx, dy) = (t % 3 - 1, t / 3 - 1);
                                    let weight = ((2 - dx.abs()) * (2 - dy.abs())) as u32;
                                    let i = at(2 * x + dx, 2 * y + dy);
                                    (weight, fine.heights()[i], fine.colors()[i])
                                })
                                .collect();
                            let tent = |value: &dyn Fn(&(u32, u16, Rgb)) -> u32| {
                                (taps.iter().map(|tap| tap.0 * value(tap)).sum::<u32>() + 8) >> 4
                            };
                            let want_h = match filter {
                                HeightFilter::Wavelet => {
                                    let mut sum = 0i32;
                                    let mut range = (i32::MAX, 0);
                                    for t in 0..25i64 {
                                        let (dx, dy) = (t % 5 - 2, t / 5 - 2);
                                        let i = at(2 * x + dx, 2 * y + dy);
                                        let v = i32::from(fine.heights()[i]);
                                        let weight = WAVELET_LOW_PASS[(dx + 2) as usize]
                                            * WAVELET_LOW_PASS[(dy + 2) as usize];
                                        sum += weight * v;
                                        range = (range.0.min(v), range.1.max(v));
                                    }
                                    ((sum + 32).div_euclid(64)).clamp(range.0, range.1) as u16
                                }
                                HeightFilter::Subsample => taps[4].1,
                                HeightFilter::Mean => tent(&|tap| u32::from(tap.1)) as u16,
                                HeightFilter::Max => taps.iter().map(|tap| tap.1).max().unwrap(),
                            };
                            let want_c: [u8; 3] =
                                core::array::from_fn(|k| tent(&|tap| u32::from(tap.2[k])) as u8);
                            let i = (y * i64::from(coarse.width()) + x) as usize;
                            assert_eq!(
                                coarse.heights()[i],
                                want_h,
                                "{w}x{d} {filter:?} level {l} ({x}, {y})"
                            );
                            assert_eq!(coarse.colors()[i], want_c, "{w}x{d} level {l} ({x}, {y})");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn bounds_cover_every_level_surface() {
        let (h, c) = map(17, |x, y| ((x * 37 + y * 91) % 53) as u16 * 7);
        for filter in HeightFilter::ALL {
            let t = Terrain::new(17, 17, &h, &c).unwrap();
            let n = pyramid_points(17, 17);
            let (mut ph, mut pc) = (vec![0; n], vec![[0; 3]; n]);
            let mut pb = vec![0; pyramid_cells(17, 17)];
            Pyramid::build(&t, filter, &mut ph, &mut pc, &mut pb).unwrap();
            let p = Pyramid::new(t, &ph, &pc, &pb).unwrap();
            // For every bound cell, every grid point of levels up to the
            // cell's own inside it is below.
            for b in 1..p.levels() {
                let bounds = p.bounds(b).unwrap();
                let cw = level_side(17, b as u32) - 1;
                for (ci, &bound) in bounds.iter().enumerate() {
                    let mut tight = false;
                    let (i, j) = (ci as u32 % cw, ci as u32 / cw);
                    let (x0, y0, x1, y1) = (i << b, j << b, (i + 1) << b, (j + 1) << b);
                    for l in 0..=b {
                        let lv = p.level(l).unwrap();
                        let step = 1u32 << l;
                        let (gx0, gy0) = (x0 / step, y0 / step);
                        let (gx1, gy1) = (x1 / step, y1 / step);
                        for gy in gy0..=gy1.min(lv.depth() - 1) {
                            for gx in gx0..=gx1.min(lv.width() - 1) {
                                let v = lv.heights()[(gy * lv.width() + gx) as usize];
                                assert!(v <= bound, "{filter:?} level {l} bound {b} cell {ci}");
                                tight |= v == bound;
                            }
                        }
                    }
                    assert!(
                        tight,
                        "{filter:?} bound {b} cell {ci} is looser than its points"
                    );
                }
            }
        }
    }

    #[test]
    fn refuses_short_storage() {
        let (h, c) = map(9, |_, _| 0);
        let t = Terrain::new(9, 9, &h, &c).unwrap();
        let n = pyramid_points(9, 9);
        let (ph, pc, pb) = (vec![0; n], vec![[0; 3]; n], vec![0; pyramid_cells(9, 9)]);
        assert_eq!(
            Pyramid::new(t, &ph[1..], &pc, &pb).unwrap_err(),
            PyramidError::HeightStorage { needed: n }
        );
        assert!(Pyramid::new(t, &ph, &pc[1..], &pb).is_err());
        assert!(Pyramid::new(t, &ph, &pc, &pb[1..]).is_err());
        assert_eq!(Pyramid::new(t, &ph, &pc, &pb).unwrap().levels(), 4);
        assert_eq!(Pyramid::flat(t).levels(), 1);
    }
}
