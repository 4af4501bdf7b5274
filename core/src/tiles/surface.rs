//! The caster's view of a tile cache: a window of the world around the eye,
//! read through the cache, with coarser tiles standing in for missing ones.

use super::footprint::{window_origin, WINDOW_SIDE};
use super::{PhotoCache, PhotoKey, PhotoTile, Tile, TileCache, TileKey, World};
use crate::color::Rgb;
use crate::config::COORD_FRAC_BITS;
use crate::detail::DetailArea;
use crate::sticks::StickTable;
use crate::surface::{Extent, Grid, Surface};
use crate::Camera;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// log2 of the row stride of level 0 in a window: every level's grid fits
/// its stride (`2^(15 − l)` ≥ the window's `2^(14 − l) + 1` points), and
/// indices stay below 2^30.
const STRIDE_LOG2: u32 = 15;

/// A window of [`WINDOW_SIDE`] points a side of a tiled world, placed
/// around the eye, that the caster renders from a [`TileCache`].
///
/// The caster works in window coordinates: render with the camera from
/// [`TiledSurface::local`]. A sample whose tile is not resident reads the
/// best resident coarser level there (and is counted in
/// [`TiledSurface::degraded_samples`]); with none, the ray ends there.
/// Renders from a world that fits the window are the same, bit for bit, as
/// from a [`crate::Pyramid`] of the same levels; with photos finer than
/// level 0 paged through a [`PhotoCache`] ([`TiledSurface::with_photos`],
/// `M` its slots), as from a [`crate::WithDetail`] of the same photos;
/// with objects ([`TiledSurface::with_sticks`]), as from a
/// [`crate::WithSticks`] of the same sticks.
#[derive(Debug)]
pub struct TiledSurface<'c, 'a, const T: usize, const N: usize, const M: usize = 0> {
    cache: &'c TileCache<'a, T, N>,
    /// The photos' tiles and where each photo lies (world coordinates).
    photos: Option<(&'c PhotoCache<'a, T, M>, &'c [DetailArea])>,
    /// The stick table that level 0's tiles name their points' sticks in.
    sticks: Option<StickTable<'c>>,
    origin: [u32; 2],
    extent: Extent,
    top: u8,
    world_levels: u8,
    degraded: AtomicU32,
    /// Which slots the frame has read.
    touched: [AtomicBool; N],
}

impl<'c, 'a, const T: usize, const N: usize> TiledSurface<'c, 'a, T, N> {
    /// The window around `eye` (world coordinates; only x and y are used).
    pub fn around(cache: &'c TileCache<'a, T, N>, eye: [f32; 3]) -> Self {
        let world = cache.world();
        let (origin, top) = window_origin(&world, eye);
        Self {
            cache,
            origin,
            extent: Extent {
                width: (world.width - origin[0]).min(WINDOW_SIDE),
                depth: (world.depth - origin[1]).min(WINDOW_SIDE),
                max_height: world.max_height,
                real_edges: world.width <= WINDOW_SIDE && world.depth <= WINDOW_SIDE,
            },
            top,
            world_levels: world.levels(),
            degraded: AtomicU32::new(0),
            touched: core::array::from_fn(|_| AtomicBool::new(false)),
            photos: None,
            sticks: None,
        }
    }

    /// This window with the photos over `areas` (world coordinates: a
    /// source's [`super::TileSource::photos`]) read through `cache`: a
    /// hit nearer than its color reach takes their colors, as from a
    /// [`crate::WithDetail`]. A texel whose tile is not resident reads
    /// the next coarser fine level whose tiles are (and is counted in
    /// [`TiledSurface::degraded_samples`]); with none, the hit takes
    /// level 0's colors.
    pub fn with_photos<const M: usize>(
        self,
        cache: &'c PhotoCache<'a, T, M>,
        areas: &'c [DetailArea],
    ) -> TiledSurface<'c, 'a, T, N, M> {
        TiledSurface {
            cache: self.cache,
            photos: Some((cache, areas)),
            sticks: self.sticks,
            origin: self.origin,
            extent: self.extent,
            top: self.top,
            world_levels: self.world_levels,
            degraded: self.degraded,
            touched: self.touched,
        }
    }
}

impl<'c, 'a, const T: usize, const N: usize, const M: usize> TiledSurface<'c, 'a, T, N, M> {
    /// This window with objects standing on level 0: each level-0 tile
    /// holds its points' values in `table` (a source's
    /// [`super::TileSource::sticks`]) where other levels hold their cell
    /// bounds, and a hit on a stick takes its texel at the crossing's
    /// height, as through a [`crate::WithSticks`]. A point whose level-0
    /// tile is not resident (its sample read from a coarser tile) is plain
    /// terrain. An empty table leaves the window as it is.
    pub fn with_sticks(mut self, table: StickTable<'c>) -> Self {
        self.sticks = (!table.is_empty()).then_some(table);
        self
    }

    /// The world point at window point (0, 0).
    pub fn origin(&self) -> [u32; 2] {
        self.origin
    }

    /// `camera` moved into window coordinates.
    pub fn local(&self, camera: &Camera) -> Camera {
        let [x, y, z] = camera.eye;
        Camera {
            eye: [x - self.origin[0] as f32, y - self.origin[1] as f32, z],
            ..*camera
        }
    }

    /// Samples read from a coarser level than asked for since the surface
    /// was made.
    pub fn degraded_samples(&self) -> u32 {
        self.degraded.load(Ordering::Relaxed)
    }

    /// Tiles the caster has read through this surface: the frame's own
    /// footprint, exactly.
    pub fn touched_tiles(&self) -> usize {
        self.touched
            .iter()
            .filter(|t| t.load(Ordering::Relaxed))
            .count()
    }

    /// The world of the cache.
    fn world(&self) -> World {
        self.cache.world()
    }

    #[inline(always)]
    fn touch(&self, slot: usize) {
        if let Some(flag) = self.touched.get(slot) {
            flag.store(true, Ordering::Relaxed);
        }
    }

    /// The resident tile holding world point `(x, y)` of `level`, or the
    /// best resident coarser one, with the point's place in it.
    #[inline]
    fn point(&self, level: u8, x: u32, y: u32) -> Option<(&Tile<T>, usize, usize)> {
        let (tile, coarser) = self.locate(level, x, y, 1)?;
        let (row, column) = Self::place(x >> coarser, y >> coarser);
        Some((tile, row, column))
    }

    /// The resident tile holding world point `(x, y)` of `level`, or the
    /// best resident coarser one, and how many levels coarser it is. Counts
    /// `samples` degraded samples when it is coarser.
    #[inline]
    fn locate(&self, level: u8, x: u32, y: u32, samples: u32) -> Option<(&Tile<T>, u8)> {
        let shift = T.trailing_zeros();
        let (mut level_at, mut x, mut y) = (level, x, y);
        loop {
            let key = TileKey {
                level: level_at,
                x: x >> shift,
                y: y >> shift,
            };
            if let Some((slot, tile)) = self.cache.lookup(&key) {
                self.touch(slot);
                if level_at != level {
                    self.degraded.fetch_add(samples, Ordering::Relaxed);
                }
                return Some((tile, level_at - level));
            }
            if level_at + 1 >= self.world_levels {
                return None;
            }
            level_at += 1;
            x >>= 1;
            y >>= 1;
        }
    }

    /// Fine level `level`'s color of photo `photo` over `area` at world
    /// point `point` (Q16), its texels from `cache`; where one of them is
    /// not resident, the next coarser fine level's, counted as degraded.
    fn photo_color(
        &self,
        cache: &PhotoCache<'_, T, M>,
        photo: u8,
        area: &DetailArea,
        level: u32,
        point: [i64; 2],
    ) -> Option<Rgb> {
        let shift = T.trailing_zeros();
        let mask = T - 1;
        (level..=area.shift()).find_map(|at| {
            // The four texels of a color nearly always share a tile: one
            // directory lookup for them.
            let last = core::cell::Cell::new(None);
            let color = area.color_with(at, point, |x, y| {
                let (tx, ty) = ((x >> shift) as u32, (y >> shift) as u32);
                let tile = match last.get() {
                    Some((at_x, at_y, tile)) if (at_x, at_y) == (tx, ty) => tile,
                    _ => {
                        let key = PhotoKey {
                            photo,
                            level: at as u8,
                            x: tx,
                            y: ty,
                        };
                        let tile: &PhotoTile<T> = cache.get(&key)?;
                        last.set(Some((tx, ty, tile)));
                        tile
                    }
                };
                Some(tile.texels[y & mask][x & mask])
            });
            if color.is_some() && at != level {
                self.degraded.fetch_add(1, Ordering::Relaxed);
            }
            color
        })
    }

    /// Row and column of point `(x, y)` of a level inside its tile.
    #[inline(always)]
    fn place(x: u32, y: u32) -> (usize, usize) {
        let mask = T as u32 - 1;
        ((y & mask) as usize, (x & mask) as usize)
    }

    /// The places of points `a` and `b` of `level` when both lie in one
    /// tile (one lookup for both); `None` when they do not, or when that
    /// tile and every coarser one is missing.
    #[inline]
    fn pair_in_one_tile(
        &self,
        level: u8,
        a: (u32, u32),
        b: (u32, u32),
    ) -> Option<(&Tile<T>, [(usize, usize); 2])> {
        let shift = T.trailing_zeros();
        if a.0 >> shift != b.0 >> shift || a.1 >> shift != b.1 >> shift {
            return None;
        }
        let (tile, coarser) = self.locate(level, a.0, a.1, 2)?;
        let place = |(x, y): (u32, u32)| Self::place(x >> coarser, y >> coarser);
        Some((tile, [place(a), place(b)]))
    }
}

/// One level of a [`TiledSurface`].
#[derive(Debug, Clone, Copy)]
pub struct TiledGrid<'s, 'c, 'a, const T: usize, const N: usize, const M: usize = 0> {
    surface: &'s TiledSurface<'c, 'a, T, N, M>,
    level: u8,
    /// log2 of the row stride.
    shift: u32,
    /// The window's origin on this level.
    origin: [u32; 2],
    /// Points of the world's level.
    size: (u32, u32),
    /// A resident tile of this level resolved ahead, and its tile column
    /// and row: reads inside it skip the directory.
    near: Option<(&'s Tile<T>, u32, u32)>,
    /// On level 0, the stick table its tiles' points name.
    sticks: Option<StickTable<'s>>,
}

/// A grid-line cell where a stick stands: the stick table, its two
/// points' stick values and their heights.
type SticksOnPair<'s> = (StickTable<'s>, (u16, u16), (u16, u16));

impl<'s, const T: usize, const N: usize, const M: usize> TiledGrid<'s, '_, '_, T, N, M> {
    /// The tile resolved ahead ([`Grid::near`]), if it holds world point
    /// `(x, y)`.
    #[inline(always)]
    fn near_tile(&self, (x, y): (u32, u32)) -> Option<&'s Tile<T>> {
        let shift = T.trailing_zeros();
        let (tile, tx, ty) = self.near?;
        (x >> shift == tx && y >> shift == ty).then_some(tile)
    }

    /// World point of window index `index`, if inside the world.
    #[inline(always)]
    fn at(&self, index: isize) -> Option<(u32, u32)> {
        if index < 0 {
            return None;
        }
        let index = index as usize;
        let x = (index & ((1 << self.shift) - 1)) as u32 + self.origin[0];
        let y = (index >> self.shift) as u32 + self.origin[1];
        (x < self.size.0 && y < self.size.1).then_some((x, y))
    }

    /// The stick value of level-0 point `index` (its tile's bounds slot):
    /// 0 where the point's own tile is not resident.
    #[inline(always)]
    fn stick_point(&self, index: isize) -> u16 {
        let Some((x, y)) = self.at(index) else {
            return 0;
        };
        let (row, column) = TiledSurface::<T, N, M>::place(x, y);
        if let Some(tile) = self.near_tile((x, y)) {
            return tile.bounds[row][column];
        }
        let shift = T.trailing_zeros();
        let key = TileKey {
            level: 0,
            x: x >> shift,
            y: y >> shift,
        };
        match self.surface.cache.lookup(&key) {
            Some((slot, tile)) => {
                self.surface.touch(slot);
                tile.bounds[row][column]
            }
            None => 0,
        }
    }

    /// Where a stick stands at level-0 point `index` or `index + across`:
    /// the stick table, the two points' values and their heights.
    #[inline(always)]
    fn sticks_on_pair(&self, index: isize, across: isize) -> Option<SticksOnPair<'s>> {
        let table = self.sticks?;
        let points = (self.stick_point(index), self.stick_point(index + across));
        if points == (0, 0) {
            return None;
        }
        Some((table, points, self.height_pair(index, across)?))
    }

    /// `field` (a tile's heights or colors at a row and column) of the
    /// point at window index `index`.
    #[inline(always)]
    fn read<V>(&self, index: isize, field: impl Fn(&Tile<T>, usize, usize) -> V) -> Option<V> {
        let (x, y) = self.at(index)?;
        if let Some(tile) = self.near_tile((x, y)) {
            let (row, column) = TiledSurface::<T, N, M>::place(x, y);
            return Some(field(tile, row, column));
        }
        let (tile, row, column) = self.surface.point(self.level, x, y)?;
        Some(field(tile, row, column))
    }

    /// `field` of the points at `index` and `index + across`: one cache
    /// lookup when they share a tile (nearly always: a tile is 64 points a
    /// side), else one each.
    #[inline(always)]
    fn read_pair<V>(
        &self,
        index: isize,
        across: isize,
        field: impl Fn(&Tile<T>, usize, usize) -> V,
    ) -> Option<(V, V)> {
        let (a, b) = (self.at(index)?, self.at(index + across)?);
        if let (Some(tile), Some(_)) = (self.near_tile(a), self.near_tile(b)) {
            let (r0, c0) = TiledSurface::<T, N, M>::place(a.0, a.1);
            let (r1, c1) = TiledSurface::<T, N, M>::place(b.0, b.1);
            return Some((field(tile, r0, c0), field(tile, r1, c1)));
        }
        match self.surface.pair_in_one_tile(self.level, a, b) {
            Some((tile, [(r0, c0), (r1, c1)])) => Some((field(tile, r0, c0), field(tile, r1, c1))),
            None => Some((
                self.read(index, &field)?,
                self.read(index + across, &field)?,
            )),
        }
    }
}

impl<const T: usize, const N: usize, const M: usize> Grid for TiledGrid<'_, '_, '_, T, N, M> {
    #[inline(always)]
    fn stride(&self) -> isize {
        1 << self.shift
    }
    #[inline]
    fn near(mut self, index: isize) -> Self {
        if let Some((x, y)) = self.at(index) {
            let shift = T.trailing_zeros();
            let key = TileKey {
                level: self.level,
                x: x >> shift,
                y: y >> shift,
            };
            if let Some((slot, tile)) = self.surface.cache.lookup(&key) {
                self.surface.touch(slot);
                self.near = Some((tile, key.x, key.y));
            }
        }
        self
    }
    #[inline]
    fn height(&self, index: isize) -> Option<u16> {
        self.read(index, |tile, row, column| tile.heights[row][column])
    }
    #[inline]
    fn color(&self, index: isize) -> Option<Rgb> {
        self.read(index, |tile, row, column| tile.colors[row][column])
    }
    #[inline]
    fn height_pair(&self, index: isize, across: isize) -> Option<(u16, u16)> {
        self.read_pair(index, across, |tile, row, column| tile.heights[row][column])
    }
    #[inline]
    fn color_pair(&self, index: isize, across: isize) -> Option<(Rgb, Rgb)> {
        self.read_pair(index, across, |tile, row, column| tile.colors[row][column])
    }
    #[inline]
    fn color_pair_at(&self, index: isize, across: isize, z: i32) -> Option<(Rgb, Rgb)> {
        let colors = self.color_pair(index, across)?;
        Some(match self.sticks_on_pair(index, across) {
            Some((table, points, tops)) => table.pair(points, tops, z, colors),
            None => colors,
        })
    }
    #[inline]
    fn stands(&self, index: isize, across: isize, z: i32) -> bool {
        if self.sticks.is_none() {
            return false;
        }
        let stands_at = |i: isize| {
            self.stick_point(i) != 0
                && self
                    .height(i)
                    .is_some_and(|top| StickTable::reaches(top, z))
        };
        stands_at(index) || stands_at(index + across)
    }
    #[inline]
    fn color_at(&self, index: isize, z: i32) -> Option<Rgb> {
        let color = self.color(index)?;
        let Some(table) = &self.sticks else {
            return Some(color);
        };
        let point = self.stick_point(index);
        if point == 0 {
            return Some(color);
        }
        Some(table.texel(point, self.height(index)?, z).unwrap_or(color))
    }
    #[inline]
    fn sees_through(&self) -> bool {
        self.sticks.is_some_and(|table| !table.alphas().is_empty())
    }
    #[inline]
    fn may_see_through(&self, index: isize, across: isize) -> bool {
        self.sticks.is_some_and(|table| {
            table.may_see_through(self.stick_point(index))
                || table.may_see_through(self.stick_point(index + across))
        })
    }
    #[inline]
    fn seen_pair_at(
        &self,
        index: isize,
        across: isize,
        z: i32,
        lowered: (bool, bool),
    ) -> Option<((Rgb, u8), (Rgb, u8))> {
        let colors = self.color_pair(index, across)?;
        Some(match self.sticks_on_pair(index, across) {
            Some((table, points, tops)) => table.seen_pair(points, tops, z, colors, lowered),
            None => ((colors.0, u8::MAX), (colors.1, u8::MAX)),
        })
    }
    #[inline]
    fn ground(&self, index: isize) -> Option<u16> {
        let top = self.height(index)?;
        Some(match &self.sticks {
            Some(table) => table.ground(self.stick_point(index), top),
            None => top,
        })
    }
}

impl<'c, 'a, const T: usize, const N: usize, const M: usize> Surface
    for TiledSurface<'c, 'a, T, N, M>
{
    type Grid<'s>
        = TiledGrid<'s, 'c, 'a, T, N, M>
    where
        Self: 's;

    #[inline]
    fn grid(&self, level: u8) -> Option<Self::Grid<'_>> {
        (level <= self.top).then(|| TiledGrid {
            surface: self,
            level,
            shift: STRIDE_LOG2 - u32::from(level),
            origin: self.origin.map(|o| o >> level),
            size: self.world().level_size(level),
            near: None,
            sticks: self.sticks.filter(|_| level == 0),
        })
    }
    #[inline]
    fn base(&self) -> Self::Grid<'_> {
        TiledGrid {
            surface: self,
            level: 0,
            shift: STRIDE_LOG2,
            origin: self.origin,
            size: (self.world().width, self.world().depth),
            near: None,
            sticks: self.sticks,
        }
    }
    fn top(&self) -> u8 {
        self.top
    }
    fn extent(&self) -> Extent {
        self.extent
    }
    fn has_bounds(&self) -> bool {
        self.top > 0
    }
    fn roughness(&self) -> u8 {
        self.world().roughness
    }
    #[inline]
    fn bound(&self, level: u8, x: i64, y: i64) -> Option<(u16, usize)> {
        if level == 0 || level > self.top || x < 0 || y < 0 {
            return None;
        }
        let (w, d) = self.world().level_size(level);
        let wx = u32::try_from(x)
            .ok()?
            .checked_add(self.origin[0] >> level)?;
        let wy = u32::try_from(y)
            .ok()?
            .checked_add(self.origin[1] >> level)?;
        if wx + 1 >= w || wy + 1 >= d {
            return None;
        }
        let shift = T.trailing_zeros();
        let mask = T as u32 - 1;
        let key = TileKey {
            level,
            x: wx >> shift,
            y: wy >> shift,
        };
        // A missing bound proves nothing: the caller assumes the worst.
        let (slot, tile) = self.cache.lookup(&key)?;
        self.touch(slot);
        let bound = tile.bounds[(wy & mask) as usize][(wx & mask) as usize];
        let stride_log2 = STRIDE_LOG2 - u32::from(level);
        Some((bound, ((y as usize) << stride_log2) + x as usize))
    }
    #[inline]
    fn has_details(&self) -> bool {
        self.photos.is_some_and(|(_, areas)| !areas.is_empty())
    }
    #[inline]
    fn detail_color(&self, point: [i64; 2], width: i64, reach: i64) -> Option<Rgb> {
        let (cache, areas) = self.photos?;
        let origin = self.origin.map(|o| i64::from(o) << COORD_FRAC_BITS);
        let point = [point[0] + origin[0], point[1] + origin[1]];
        areas.iter().enumerate().rev().find_map(|(photo, area)| {
            area.color_for_with(point, width, reach, |level, point| {
                self.photo_color(cache, photo as u8, area, level, point)
            })
        })
    }
}
