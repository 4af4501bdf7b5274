//! A photo finer than the height grid (Cohen-Or: "full resolution of both
//! the digital terrain model and the corresponding aerial photograph need
//! to be employed").
//!
//! A [`Detail`] holds a color grid `2^shift` times finer than level 0 over
//! a rectangle of the map, and its own coarser levels down to level 0's
//! spacing: fine level `f` has `2^(shift − f)` texels a voxel, each the
//! mean of the `2^f × 2^f` texels of fine level 0 it covers, so its level
//! `shift` is the height grid's level 0 colors over the rectangle (the
//! caller fills level 0's colors as that mean, as a photo reduced to the
//! height grid is). A texel of fine level 0 covers `1/2^shift` of a voxel
//! on each side, and a grid point's color is the mean of the `2^shift ×
//! 2^shift` texels around it.
//!
//! [`WithDetail`] lends a surface with details (several photos, each
//! over its own rectangle) to the caster. A hit
//! nearer than the color reach (where a voxel of level 0 is wider than the
//! pixel's footprint) takes its color from the two fine levels whose
//! texels bracket the footprint, bilinear in each and blended by depth,
//! the soft transition the pyramid's levels make farther out
//! ([`mod@crate::caster`]'s footprint colors). Outside the rectangle, and
//! with `Shading::Nearest`, the hit takes level 0's colors as without a
//! detail.
//!
//! ```
//! use terracast::{detail_points, render, Camera, Detail, Framebuffer, NoProbe, Pyramid, RenderOptions, Terrain, View, WithDetail};
//!
//! // A flat 8 x 8 map, its photo 4 times finer: stripes a quarter of a
//! // voxel wide, which level 0 (their mean) shows as one gray.
//! let heights = [16u16; 64];
//! let colors = [[128, 128, 128]; 64];
//! let terrain = Terrain::new(8, 8, &heights, &colors)?;
//! const SHIFT: u32 = 2;
//! let mut texels = [[0u8; 3]; detail_points(8, 8, SHIFT)];
//! for (i, texel) in texels.iter_mut().take(32 * 32).enumerate() {
//!     *texel = if i % 2 == 0 { [255, 255, 255] } else { [0, 0, 0] };
//! }
//! let detail = Detail::build([0, 0], [8, 8], SHIFT, &mut texels)?;
//!
//! let pyramid = Pyramid::flat(terrain);
//! let details = [detail];
//! let surface = WithDetail::new(&pyramid, &details);
//! let view = View::new(&Camera::looking([4.0, -1.0, 3.0], 90.0, 60.0), 64, 48)?;
//! let mut pixels = [[0u8; 3]; 64 * 48];
//! render(&surface, &view, &RenderOptions::default(), &mut Framebuffer::new(&mut pixels, 64, 48)?, &mut NoProbe);
//! // Near the eye the stripes show: pixels far from level 0's gray.
//! assert!(pixels.iter().any(|c| c[0] > 200) && pixels.iter().any(|c| c[0] < 50));
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

use crate::caster::walk::lerp;
use crate::color::Rgb;
use crate::config::{COORD_FRAC_BITS, MAX_DETAIL_SHIFT, MAX_MAP_SIDE, WEIGHT_BITS};
use crate::surface::{Extent, Surface};
use core::fmt;

/// Texels of a [`Detail`] over a `width` × `depth` rectangle of grid
/// points `2^shift` times finer, all its levels: the storage
/// [`Detail::build`] takes.
/// `usize::MAX` where that does not fit a `usize` (no storage is that
/// long, so such a detail is refused).
pub const fn detail_points(width: u32, depth: u32, shift: u32) -> usize {
    if shift > MAX_DETAIL_SHIFT {
        return usize::MAX;
    }
    let (mut total, mut level) = (0u64, 0u32);
    while level <= shift {
        let side = 1u64 << (shift - level);
        total += width as u64 * side * depth as u64 * side;
        level += 1;
    }
    if total > usize::MAX as u64 {
        usize::MAX
    } else {
        total as usize
    }
}

/// Why a [`Detail`] cannot be made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DetailError {
    /// The shift is 0 or above [`MAX_DETAIL_SHIFT`].
    Shift,
    /// The rectangle is empty or reaches past [`MAX_MAP_SIDE`].
    Rectangle,
    /// The storage is not [`detail_points`] long.
    StorageLength,
    /// The rectangle reaches past the surface's map.
    OutsideMap,
}

impl fmt::Display for DetailError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Shift => "a detail is 2 to 32 times finer than the height grid (shift 1 to 5)",
            Self::Rectangle => "a detail's rectangle is empty or larger than a map",
            Self::StorageLength => {
                "a detail's storage is not detail_points(width, depth, shift) long"
            }
            Self::OutsideMap => "a detail's rectangle reaches past the map",
        })
    }
}

impl core::error::Error for DetailError {}

/// Where a [`Detail`] lies and how fine it is: a rectangle of grid points
/// of level 0 and its texels a voxel, without the texels. A detail held in
/// memory ([`Detail`]) and one paged through a tile cache
/// ([`crate::tiles::TiledSurface::with_photos`]) look their colors up the
/// same way, through this.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DetailArea {
    /// Fine level 0's texels a voxel on each side: `2^shift`.
    shift: u8,
    /// The rectangle's first grid point.
    origin: [u32; 2],
    /// Its grid points on each axis.
    size: [u32; 2],
}

impl DetailArea {
    /// The area of `size` grid points from `origin`, `2^shift` times
    /// finer than level 0, on a map up to `max_side` points a side.
    pub fn new(
        origin: [u32; 2],
        size: [u32; 2],
        shift: u32,
        max_side: u32,
    ) -> Result<Self, DetailError> {
        if shift == 0 || shift > MAX_DETAIL_SHIFT {
            return Err(DetailError::Shift);
        }
        let past =
            |axis: usize| u64::from(origin[axis]) + u64::from(size[axis]) > u64::from(max_side);
        if size.contains(&0) || past(0) || past(1) {
            return Err(DetailError::Rectangle);
        }
        Ok(Self {
            shift: shift as u8,
            origin,
            size,
        })
    }

    /// Fine level 0's texels a voxel on each side, as a shift.
    pub fn shift(&self) -> u32 {
        u32::from(self.shift)
    }

    /// The rectangle's first grid point.
    pub fn origin(&self) -> [u32; 2] {
        self.origin
    }

    /// The rectangle's grid points on each axis.
    pub fn size(&self) -> [u32; 2] {
        self.size
    }

    /// Fine level `level`'s texels a row and rows.
    pub fn level_size(&self, level: u32) -> (usize, usize) {
        level_size(self.size, self.shift(), level.min(self.shift()))
    }

    /// Fine level `level`'s color at world point `point` (Q16 voxels),
    /// its texel `(x, y)` from `texel`: the four texels around the point
    /// blended by the point's fraction of their spacing (the last row and
    /// column repeat past the rectangle's edge); `None` outside the
    /// rectangle, or where `texel` has none.
    #[inline]
    pub fn color_with(
        &self,
        level: u32,
        point: [i64; 2],
        texel: impl Fn(usize, usize) -> Option<Rgb>,
    ) -> Option<Rgb> {
        let shift = self.shift();
        let level = level.min(shift);
        let finer = shift - level;
        let (w, d) = level_size(self.size, shift, level);
        // The texel whose center is at fine coordinate `i` lies at world
        // `origin + (i + ½)/2^finer − ½`: the point's coordinate in texels
        // of this level (Q16), half a texel in.
        let half_in = ((1i64 << finer) - 1) << (COORD_FRAC_BITS - 1);
        let mut cell = [0usize; 2];
        let mut weight = [0u32; 2];
        for axis in 0..2 {
            let from_origin = point[axis] - (i64::from(self.origin[axis]) << COORD_FRAC_BITS);
            let fine = (from_origin << finer) + half_in;
            let limit = [w, d][axis] as i64;
            // Outside the rectangle's voxels (half a texel of this level
            // past its first and last centers): not this detail's.
            let half = 1 << (COORD_FRAC_BITS - 1);
            if fine < -half || fine >= (limit << COORD_FRAC_BITS) - half {
                return None;
            }
            let fine = fine.max(0);
            let whole = (fine >> COORD_FRAC_BITS) as usize;
            cell[axis] = whole.min(limit as usize - 1);
            weight[axis] = if whole + 1 < limit as usize {
                ((fine >> (COORD_FRAC_BITS - WEIGHT_BITS)) & ((1 << WEIGHT_BITS) - 1)) as u32
            } else {
                0
            };
        }
        let (x, y) = (cell[0], cell[1]);
        let (x1, y1) = ((x + 1).min(w - 1), (y + 1).min(d - 1));
        Some(lerp(
            lerp(texel(x, y)?, texel(x1, y)?, weight[0]),
            lerp(texel(x, y1)?, texel(x1, y1)?, weight[0]),
            weight[1],
        ))
    }

    /// The color at world point `point` (Q16) for a footprint `width` (a
    /// depth, Q16) on a ray whose colors reach level 1 at `reach`, from
    /// `color` (fine level, point → its color, as [`DetailArea::color_with`]):
    /// fine level 0 alone under `reach / 2^shift`, then each next fine
    /// level blended in as a texel of the one before gets narrower than
    /// the footprint, as the pyramid's levels are past `reach`; `None`
    /// outside the rectangle or at or past the reach (where level 0 and
    /// the pyramid take over).
    #[inline]
    pub fn color_for_with(
        &self,
        point: [i64; 2],
        width: i64,
        reach: i64,
        color: impl Fn(u32, [i64; 2]) -> Option<Rgb>,
    ) -> Option<Rgb> {
        if width >= reach {
            return None;
        }
        let shift = self.shift();
        // Fine level f is all there at `reach >> (shift − f)`.
        let mut level = 0;
        while level < shift && width >= reach >> (shift - level) {
            level += 1;
        }
        if level == 0 {
            return color(0, point);
        }
        let begins = reach >> (shift - level + 1);
        let span = (reach >> (shift - level)) - begins;
        let t = if span > 0 {
            (((width - begins) << WEIGHT_BITS) / span).clamp(0, 1 << WEIGHT_BITS) as u32
        } else {
            1 << WEIGHT_BITS
        };
        let finer = color(level - 1, point)?;
        let coarser = color(level, point)?;
        Some(lerp(finer, coarser, t))
    }

    /// How far (in the unit of `reach`, the depth where colors reach
    /// level 1) fine level `level` is read: [`DetailArea::color_for_with`]
    /// blends fine levels `f − 1` and `f` for footprints narrower than
    /// `reach >> (shift − f)`, so fine level `f` is read for footprints
    /// narrower than `reach >> (shift − f − 1)`, and the last two out to
    /// `reach`. What a tile cache's footprint of the detail needs.
    pub fn reaches(&self, level: u32, reach: f64) -> f64 {
        let shift = self.shift();
        reach / f64::from(1u32 << shift.saturating_sub(level.min(shift) + 1))
    }

    /// Whether the rectangle lies inside a map of `extent`.
    fn fits(&self, extent: &Extent) -> bool {
        let end = |axis: usize| u64::from(self.origin[axis]) + u64::from(self.size[axis]);
        end(0) <= u64::from(extent.width) && end(1) <= u64::from(extent.depth)
    }
}

/// A color grid finer than level 0 over a rectangle of the map, and its
/// levels (see the module).
#[derive(Debug, Clone, Copy)]
pub struct Detail<'a> {
    /// Where it lies.
    area: DetailArea,
    /// Fine levels 0 to `shift`, one after the other, row by row.
    texels: &'a [Rgb],
}

impl<'a> Detail<'a> {
    /// The detail whose fine level 0 the caller has written at the start
    /// of `texels` (`size[0]·2^shift` texels a row, `size[1]·2^shift`
    /// rows) over the `size` grid points from `origin`: builds its coarser
    /// levels into the rest of `texels` ([`Detail::build_levels`]), and
    /// borrows them.
    pub fn build(
        origin: [u32; 2],
        size: [u32; 2],
        shift: u32,
        texels: &'a mut [Rgb],
    ) -> Result<Self, DetailError> {
        Self::build_levels(size, shift, texels)?;
        Self::new(origin, size, shift, texels)
    }

    /// Builds the coarser fine levels of a detail of `size` grid points
    /// `2^shift` times finer into `texels` (of [`detail_points`]), whose
    /// start holds fine level 0: each texel the rounded mean of the four
    /// below it.
    pub fn build_levels(size: [u32; 2], shift: u32, texels: &mut [Rgb]) -> Result<(), DetailError> {
        check(size, shift, texels.len())?;
        let mut start = 0;
        for level in 0..shift {
            let (w, d) = level_size(size, shift, level);
            let (finer, coarser) = texels[start..].split_at_mut(w * d);
            for y in 0..d / 2 {
                for x in 0..w / 2 {
                    let at = |dx: usize, dy: usize| finer[(2 * y + dy) * w + 2 * x + dx];
                    let quad = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
                    coarser[y * (w / 2) + x] = core::array::from_fn(|c| {
                        let sum: u32 = quad.iter().map(|t| u32::from(t[c])).sum();
                        ((sum + 2) / 4) as u8
                    });
                }
            }
            start += w * d;
        }
        Ok(())
    }

    /// The detail of `size` grid points from `origin`, `2^shift` times
    /// finer, whose levels [`Detail::build_levels`] built into `texels`.
    pub fn new(
        origin: [u32; 2],
        size: [u32; 2],
        shift: u32,
        texels: &'a [Rgb],
    ) -> Result<Self, DetailError> {
        check(size, shift, texels.len())?;
        let area = DetailArea::new(origin, size, shift, MAX_MAP_SIDE)?;
        Ok(Self { area, texels })
    }

    /// Where it lies and how fine it is.
    pub fn area(&self) -> DetailArea {
        self.area
    }

    /// Bytes of its texels, all levels.
    pub fn bytes(&self) -> usize {
        core::mem::size_of_val(self.texels)
    }

    /// Fine level 0's texels a voxel on each side, as a shift.
    pub fn shift(&self) -> u32 {
        self.area.shift()
    }

    /// Fine level `level`'s texels, row by row ([`DetailArea::level_size`]).
    pub fn level(&self, level: u32) -> &'a [Rgb] {
        let level = level.min(self.shift());
        let start = (0..level)
            .map(|l| {
                let (w, d) = self.area.level_size(l);
                w * d
            })
            .sum::<usize>();
        let (w, d) = self.area.level_size(level);
        self.texels.get(start..start + w * d).unwrap_or(&[])
    }

    /// Fine level `level`'s color at world point `point` (Q16 voxels):
    /// its four texels around the point blended by the point's fraction
    /// of their spacing (the last row and column repeat past the
    /// rectangle's edge); `None` outside the rectangle.
    #[inline]
    pub fn color(&self, level: u32, point: [i64; 2]) -> Option<Rgb> {
        let texels = self.level(level);
        let (w, _) = self.area.level_size(level);
        self.area
            .color_with(level, point, |x, y| texels.get(y * w + x).copied())
    }

    /// The color at world point `point` (Q16) for a footprint `width` (a
    /// depth, Q16) on a ray whose colors reach level 1 at `reach`
    /// ([`DetailArea::color_for_with`] over this detail's texels).
    #[inline]
    pub fn color_for(&self, point: [i64; 2], width: i64, reach: i64) -> Option<Rgb> {
        self.area
            .color_for_with(point, width, reach, |level, point| self.color(level, point))
    }
}

/// Refused when `shift` or `size` is out of range, or `len` is not the
/// storage they need.
fn check(size: [u32; 2], shift: u32, len: usize) -> Result<(), DetailError> {
    DetailArea::new([0, 0], size, shift, MAX_MAP_SIDE)?;
    if len != detail_points(size[0], size[1], shift) {
        return Err(DetailError::StorageLength);
    }
    Ok(())
}

/// Fine level `level`'s texels a row and rows, over `size` grid points
/// `2^shift` finer.
fn level_size(size: [u32; 2], shift: u32, level: u32) -> (usize, usize) {
    let side = 1usize << (shift - level);
    (size[0] as usize * side, size[1] as usize * side)
}

/// A surface with [`Detail`]s over its level 0 (see the module): where
/// their rectangles overlap, the later one's.
#[derive(Debug, Clone, Copy)]
pub struct WithDetail<'s, T: ?Sized> {
    surface: &'s T,
    details: &'s [Detail<'s>],
}

impl<'s, T: Surface + ?Sized> WithDetail<'s, T> {
    /// `surface` with `details` over its level 0.
    pub fn new(surface: &'s T, details: &'s [Detail<'s>]) -> Self {
        Self { surface, details }
    }

    /// [`WithDetail::new`], refused when a detail's rectangle reaches
    /// past the surface's map.
    pub fn checked(surface: &'s T, details: &'s [Detail<'s>]) -> Result<Self, DetailError> {
        let extent = surface.extent();
        if !details.iter().all(|detail| detail.area.fits(&extent)) {
            return Err(DetailError::OutsideMap);
        }
        Ok(Self::new(surface, details))
    }
}

/// The color of [`Detail::color_for`] from the last of `details` that
/// holds `point`.
#[inline]
pub(crate) fn details_color(
    details: &[Detail<'_>],
    point: [i64; 2],
    width: i64,
    reach: i64,
) -> Option<Rgb> {
    details
        .iter()
        .rev()
        .find_map(|detail| detail.color_for(point, width, reach))
}

impl<'s, T: Surface + ?Sized> Surface for WithDetail<'s, T> {
    type Grid<'g>
        = T::Grid<'g>
    where
        Self: 'g;

    #[inline(always)]
    fn grid(&self, level: u8) -> Option<Self::Grid<'_>> {
        self.surface.grid(level)
    }
    #[inline(always)]
    fn base(&self) -> Self::Grid<'_> {
        self.surface.base()
    }
    crate::surface::lend_surface!(surface);
    #[inline(always)]
    fn has_details(&self) -> bool {
        !self.details.is_empty()
    }
    #[inline]
    fn detail_color(&self, point: [i64; 2], width: i64, reach: i64) -> Option<Rgb> {
        details_color(self.details, point, width, reach)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ONE: i64 = 1 << COORD_FRAC_BITS;

    /// A 2 × 2-point detail 4 times finer whose fine level 0 is `texel`
    /// of its coordinates.
    fn detail_of(texel: impl Fn(usize, usize) -> Rgb) -> ([u32; 2], Vec<Rgb>) {
        let size = [2, 2];
        let mut texels = vec![[0; 3]; detail_points(2, 2, 2)];
        for y in 0..8 {
            for x in 0..8 {
                texels[y * 8 + x] = texel(x, y);
            }
        }
        (size, texels)
    }

    #[test]
    fn each_level_is_the_mean_of_the_one_below_and_the_last_is_a_voxel_a_texel() {
        let (size, mut texels) = detail_of(|x, y| [(x * 30) as u8, (y * 30) as u8, 7]);
        let detail = Detail::build([0, 0], size, 2, &mut texels).unwrap();
        // Level 2: one texel a grid point, the mean of the 4 x 4 around it.
        let mean = |x0: usize, y0: usize| -> Rgb {
            let sum = |f: &dyn Fn(usize, usize) -> usize| -> usize {
                (0..4)
                    .flat_map(|y| (0..4).map(move |x| (x, y)))
                    .map(|(x, y)| f(x0 + x, y0 + y))
                    .sum()
            };
            [
                (sum(&|x, _| x * 30) as f64 / 16.0).round() as u8,
                (sum(&|_, y| y * 30) as f64 / 16.0).round() as u8,
                7,
            ]
        };
        assert_eq!(detail.color(2, [0, 0]), Some(mean(0, 0)));
        assert_eq!(detail.color(2, [ONE, ONE]), Some(mean(4, 4)));
        // Level 0 at a texel's center is that texel.
        let center = |i: i64| (i * ONE + ONE / 2) / 4 - ONE / 2;
        assert_eq!(detail.color(0, [center(5), center(2)]), Some([150, 60, 7]));
        // Halfway between two texels, their mean.
        assert_eq!(
            detail.color(0, [center(5) + ONE / 8, center(2)]),
            Some([165, 60, 7])
        );
        // Outside the rectangle's voxels: none.
        assert_eq!(detail.color(0, [-ONE, 0]), None);
        assert_eq!(detail.color(0, [2 * ONE, 0]), None);
    }

    #[test]
    fn the_footprint_picks_the_fine_levels_and_blends_between_them() {
        let (size, mut texels) = detail_of(|x, _| if x % 2 == 0 { [255; 3] } else { [0; 3] });
        let detail = Detail::build([0, 0], size, 2, &mut texels).unwrap();
        let reach = 64 * ONE;
        let point = [(ONE / 2) / 4 - ONE / 2 + ONE / 2, ONE / 2];
        // A footprint under a fine texel: the stripes themselves.
        let stripe = detail.color_for(point, reach / 8, reach).unwrap();
        assert!(stripe[0] == 255 || stripe[0] == 0, "{stripe:?}");
        // A footprint near a voxel: the stripes' mean.
        let gray = detail.color_for(point, reach - 1, reach).unwrap();
        assert!((120..=135).contains(&gray[0]), "{gray:?}");
        // At the reach, level 0's colors take over.
        assert_eq!(detail.color_for(point, reach, reach), None);
        // Between, the contrast falls steadily with the footprint.
        let contrast = |w: i64| {
            let c = detail.color_for(point, w, reach).unwrap()[0];
            (i32::from(c) - 128).abs()
        };
        let widths = [
            reach / 8,
            reach / 4 + reach / 16,
            reach / 2,
            reach / 2 + reach / 4,
        ];
        assert!(
            widths.windows(2).all(|w| contrast(w[0]) >= contrast(w[1])),
            "{:?}",
            widths.map(contrast)
        );
    }

    /// A rolling 32 × 32 map, a checkered photo 4 times finer over its
    /// middle 16 × 16 points, and the map's colors its mean there.
    struct Hills {
        heights: Vec<u16>,
        colors: Vec<Rgb>,
        texels: Vec<Rgb>,
    }

    const SIDE: u32 = 32;

    fn hills() -> Hills {
        let n = SIDE as usize;
        let heights = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64, (i / n) as f64);
                ((3.0 + (x * 0.4).sin() * 1.5 + (y * 0.3).cos()) * 16.0) as u16
            })
            .collect();
        let texel = |x: usize, y: usize| -> Rgb {
            if (x / 2 + y / 3) % 2 == 0 {
                [250, 40, (x * 7) as u8]
            } else {
                [20, 200, (y * 7) as u8]
            }
        };
        let mut texels = vec![[0; 3]; detail_points(16, 16, 2)];
        for y in 0..64 {
            for x in 0..64 {
                texels[y * 64 + x] = texel(x, y);
            }
        }
        let mut colors = vec![[90, 110, 60]; n * n];
        for y in 0..16 {
            for x in 0..16 {
                colors[(y + 8) * n + x + 8] = core::array::from_fn(|c| {
                    let sum: u32 = (0..16)
                        .map(|i| u32::from(texel(4 * x + i % 4, 4 * y + i / 4)[c]))
                        .sum();
                    ((sum + 8) / 16) as u8
                });
            }
        }
        Hills {
            heights,
            colors,
            texels,
        }
    }

    fn render_hills(
        camera: &crate::Camera,
        options: &crate::RenderOptions,
        with_detail: bool,
    ) -> Vec<Rgb> {
        let mut map = hills();
        let terrain = crate::Terrain::new(SIDE, SIDE, &map.heights, &map.colors).unwrap();
        let points = crate::pyramid_points(SIDE, SIDE);
        let (mut coarse_heights, mut coarse_colors) = (vec![0; points], vec![[0; 3]; points]);
        let mut bounds = vec![0; crate::pyramid_cells(SIDE, SIDE)];
        crate::Pyramid::build(
            &terrain,
            crate::HeightFilter::default(),
            &mut coarse_heights,
            &mut coarse_colors,
            &mut bounds,
        )
        .unwrap();
        let pyramid =
            crate::Pyramid::new(terrain, &coarse_heights, &coarse_colors, &bounds).unwrap();
        let view = crate::View::new(camera, 48, 36).unwrap();
        let mut pixels = vec![[0u8; 3]; 48 * 36];
        let mut frame = crate::Framebuffer::new(&mut pixels, 48, 36).unwrap();
        let details = [Detail::build([8, 8], [16, 16], 2, &mut map.texels).unwrap()];
        if with_detail {
            let surface = WithDetail::checked(&pyramid, &details).unwrap();
            crate::render(&surface, &view, options, &mut frame, &mut crate::NoProbe);
        } else {
            crate::render(&pyramid, &view, options, &mut frame, &mut crate::NoProbe);
        }
        pixels
    }

    #[test]
    fn exact_coherence_is_off_bit_for_bit_with_a_detail_and_the_line_caster_too() {
        use crate::{Camera, Coherence, RenderOptions, Resolution};
        for camera in [
            Camera::looking([16.0, 2.0, 9.0], 90.0, 25.0),
            Camera::looking([4.0, 5.0, 12.0], 40.0, 45.0),
            Camera::looking([16.0, 16.0, 20.0], 10.0, 90.0),
        ] {
            for resolution in [Resolution::Single, Resolution::DEFAULT] {
                let at = |coherence| RenderOptions {
                    coherence,
                    resolution,
                    ..RenderOptions::default()
                };
                let off = render_hills(&camera, &at(Coherence::Off), true);
                assert_eq!(
                    off,
                    render_hills(&camera, &at(Coherence::Exact), true),
                    "{camera:?}"
                );
                if resolution == Resolution::Single {
                    assert_eq!(
                        off,
                        render_hills(&camera, &at(Coherence::AcrossLevels), true),
                        "{camera:?}"
                    );
                }
                // And the photo's detail shows.
                assert_ne!(
                    off,
                    render_hills(&camera, &at(Coherence::Off), false),
                    "{camera:?}"
                );
            }
        }
    }

    #[test]
    fn bad_details_are_refused() {
        let mut texels = vec![[0; 3]; detail_points(2, 2, 2)];
        assert_eq!(
            Detail::build([0, 0], [2, 2], 0, &mut texels).unwrap_err(),
            DetailError::Shift
        );
        assert_eq!(
            Detail::build([0, 0], [2, 2], 6, &mut texels).unwrap_err(),
            DetailError::Shift
        );
        assert_eq!(
            Detail::build([0, 0], [0, 2], 2, &mut texels).unwrap_err(),
            DetailError::Rectangle
        );
        assert_eq!(
            Detail::build([0, 0], [2, 2], 1, &mut texels).unwrap_err(),
            DetailError::StorageLength
        );
        let details = [Detail::build([1, 0], [2, 2], 2, &mut texels).unwrap()];
        let heights = [0u16; 4];
        let colors = [[0u8; 3]; 4];
        let terrain = crate::Terrain::new(2, 2, &heights, &colors).unwrap();
        let pyramid = crate::Pyramid::flat(terrain);
        assert_eq!(
            WithDetail::checked(&pyramid, &details).unwrap_err(),
            DetailError::OutsideMap
        );
        assert!(DetailError::Shift.to_string().contains("2 to 32 times"));
    }
}
