//! Out-of-core terrain: the terrain and each pyramid level cut into square
//! tiles, a cache of a fixed number of tile slots, the tiles a view needs,
//! and a surface the caster renders from the cache (Cohen-Or §3.2).
//!
//! ```
//! use terracast::tiles::{
//!     footprint, FootprintView, Tile, TileCache, TileError, TileKey, TileSource, TiledSurface, World,
//! };
//! use terracast::{render, Camera, CountingProbe, Framebuffer, RenderOptions, View};
//!
//! /// A flat green world, 256 voxels a side, made on demand.
//! struct Flat;
//! impl TileSource<16> for Flat {
//!     fn world(&self) -> World {
//!         World::new(256, 256, 0).unwrap()
//!     }
//!     fn load(&mut self, _key: TileKey, tile: &mut Tile<16>) -> Result<usize, TileError> {
//!         *tile = Tile { colors: [[[40, 160, 40]; 16]; 16], ..Tile::EMPTY };
//!         Ok(Tile::<16>::BYTES)
//!     }
//! }
//!
//! let mut slots = [Tile::<16>::EMPTY; 256];
//! let mut cache = TileCache::<16, 256>::new(Flat.world(), &mut slots);
//! let camera = Camera::looking([128.0, 20.0, 30.0], 90.0, 20.0);
//! // The tiles the frame needs, loaded before it is drawn (a flight loads
//! // the next frame's during this one: see `prefetch`).
//! let mut needed = heapless::Vec::<TileKey, 256>::new();
//! let frame = FootprintView { camera, width: 32, height: 24, pixel_to_voxel: 1.0, widen_deg: 0.0 };
//! footprint::<16, 256>(&Flat.world(), &frame, &mut needed)?;
//! cache.begin_frame();
//! for key in &needed {
//!     cache.require(*key, &mut Flat)?;
//! }
//! let surface = TiledSurface::around(&cache, camera.eye);
//! let view = View::new(&surface.local(&camera), 32, 24)?;
//! let mut pixels = [[0u8; 3]; 32 * 24];
//! render(&surface, &view, &RenderOptions::default(), &mut Framebuffer::new(&mut pixels, 32, 24)?, &mut CountingProbe::default());
//! assert_eq!(pixels[32 * 23 + 16], [40, 160, 40]);
//! assert_eq!(surface.degraded_samples(), 0);
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

mod cache;
mod footprint;
mod surface;

pub use cache::{CacheStats, Payload, PhotoCache, TileCache};
pub use footprint::{
    footprint, footprint_under, photo_footprint, window_origin, FootprintFull, FootprintView,
    WINDOW_SIDE, WINDOW_TOP,
};
pub use surface::{TiledGrid, TiledSurface};

use crate::color::Rgb;
use crate::detail::{Detail, DetailArea};
use crate::pyramid::level_side;
use crate::sticks::{StickLayer, StickTable};
use core::fmt;

/// The size of a whole tiled terrain, which may be far larger than any map
/// the caster addresses at once (a [`TiledSurface`] shows a window of it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct World {
    /// Grid points along x of level 0.
    pub width: u32,
    /// Grid points along y of level 0.
    pub depth: u32,
    /// The highest height (U12.4) on any level.
    pub max_height: u16,
    /// Level 0's roughness ([`crate::roughness`]); 0 when unknown.
    pub roughness: u8,
}

impl World {
    /// Largest world side: 2^30 grid points.
    pub const MAX_SIDE: u32 = 1 << 30;

    /// A world of `width × depth` points; `None` for a side below 2 or
    /// above [`World::MAX_SIDE`].
    pub const fn new(width: u32, depth: u32, max_height: u16) -> Option<Self> {
        if width < 2 || depth < 2 || width > Self::MAX_SIDE || depth > Self::MAX_SIDE {
            return None;
        }
        Some(Self {
            width,
            depth,
            max_height,
            roughness: 0,
        })
    }

    /// The same world with level 0's roughness known.
    pub const fn with_roughness(self, roughness: u8) -> Self {
        Self { roughness, ..self }
    }

    /// Number of levels, level 0 included: up to both sides being 2, as a
    /// [`crate::Pyramid`] of the same map.
    pub const fn levels(&self) -> u8 {
        let mut levels = 1u32;
        while level_side(self.width, levels - 1) > 2 || level_side(self.depth, levels - 1) > 2 {
            levels += 1;
        }
        levels as u8
    }

    /// Points per side of level `level`: `(along x, along y)`.
    pub const fn level_size(&self, level: u8) -> (u32, u32) {
        (
            level_side(self.width, level as u32),
            level_side(self.depth, level as u32),
        )
    }

    /// Tiles of side `tile` per side of level `level`.
    pub const fn tiles(&self, level: u8, tile: u32) -> (u32, u32) {
        let (w, d) = self.level_size(level);
        (w.div_ceil(tile), d.div_ceil(tile))
    }

    /// Whether `key` names a tile of this world.
    pub fn contains(&self, key: TileKey, tile: u32) -> bool {
        let (tx, ty) = self.tiles(key.level, tile);
        key.level < self.levels() && key.x < tx && key.y < ty
    }
}

/// A tile: level, and column and row among that level's tiles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TileKey {
    /// Pyramid level (0 is the terrain itself).
    pub level: u8,
    /// Tile column: the tile holds level points `x·T .. x·T + T`.
    pub x: u32,
    /// Tile row.
    pub y: u32,
}

/// One tile of `T × T` grid points of a level: heights, colors and, on
/// levels 1 and up, the height bound of the cell to the +x, +y of each point
/// (see [`crate::Pyramid`]'s notes); on level 0, each point's stick in the
/// source's stick table ([`TileSource::sticks`], 0 for plain terrain, as a
/// [`crate::StickLayer`]'s points). Points past the level's far edge hold
/// the edge's values.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tile<const T: usize> {
    /// Heights, U12.4, `[row][column]`.
    pub heights: [[u16; T]; T],
    /// Colors, `[row][column]`.
    pub colors: [[Rgb; T]; T],
    /// Cell bounds, U12.4, `[row][column]`; on level 0, the points'
    /// sticks (zero where none stand).
    pub bounds: [[u16; T]; T],
}

impl<const T: usize> Tile<T> {
    /// A tile of zeros.
    pub const EMPTY: Self = Self {
        heights: [[0; T]; T],
        colors: [[[0; 3]; T]; T],
        bounds: [[0; T]; T],
    };
    /// Bytes of terrain a tile holds (heights, colors and bounds).
    pub const BYTES: usize = T * T * (2 + 3 + 2);
}

/// A tile of a photo finer than level 0 ([`crate::Detail`]): the photo's
/// place among the source's ([`TileSource::photos`]), its fine level, and
/// the tile's column and row among that level's tiles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PhotoKey {
    /// Which photo.
    pub photo: u8,
    /// Fine level: 0 is the photo's own texels, each next one the mean of
    /// four of the one before, up to the level of a texel a voxel.
    pub level: u8,
    /// Tile column: the tile holds texels `x·T .. x·T + T` of the level.
    pub x: u32,
    /// Tile row.
    pub y: u32,
}

/// One tile of `T × T` texels of a photo's fine level. Texels past the
/// level's far edge hold the edge's.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PhotoTile<const T: usize> {
    /// Texels, `[row][column]`.
    pub texels: [[Rgb; T]; T],
}

impl<const T: usize> PhotoTile<T> {
    /// A tile of black texels.
    pub const EMPTY: Self = Self {
        texels: [[[0; 3]; T]; T],
    };
    /// Bytes of texels a tile holds.
    pub const BYTES: usize = T * T * 3;
}

/// The tiles of side `T` of fine level `level` of a photo over `area`:
/// columns and rows.
pub fn photo_tiles(area: &DetailArea, level: u32, tile: u32) -> (u32, u32) {
    let (w, d) = area.level_size(level);
    let tiles = |n: usize| {
        (n as u64)
            .div_ceil(u64::from(tile))
            .min(u64::from(u32::MAX)) as u32
    };
    (tiles(w), tiles(d))
}

/// Fills `tile` with photo tile `key`'s texels of `detail` (the key's
/// photo): a source for a photo already in memory, and the definition of
/// what a packed file's photo tiles must hold. False (and `tile`
/// untouched) when the detail has no such tile.
pub fn cut_photo_tile<const T: usize>(
    detail: &Detail<'_>,
    key: PhotoKey,
    tile: &mut PhotoTile<T>,
) -> bool {
    let level = u32::from(key.level);
    if level > detail.shift() {
        return false;
    }
    let (w, d) = detail.area().level_size(level);
    let (x0, y0) = (key.x as usize * T, key.y as usize * T);
    if x0 >= w || y0 >= d {
        return false;
    }
    let texels = detail.level(level);
    for (j, row) in tile.texels.iter_mut().enumerate() {
        let y = (y0 + j).min(d - 1);
        for (i, texel) in row.iter_mut().enumerate() {
            let x = (x0 + i).min(w - 1);
            *texel = texels.get(y * w + x).copied().unwrap_or([0; 3]);
        }
    }
    true
}

/// Why a tile did not arrive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TileError {
    /// The source has no such tile.
    Missing,
    /// Reading it failed.
    Io,
    /// It arrived, but its checksum does not match: rejected.
    Checksum,
    /// Every slot holds a tile pinned by the frame being rendered.
    CacheFull,
}

impl fmt::Display for TileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Missing => "no such tile in the source",
            Self::Io => "tile read failed",
            Self::Checksum => "tile checksum mismatch: tile rejected",
            Self::CacheFull => "every cache slot is pinned by the current frame",
        })
    }
}

impl core::error::Error for TileError {}

/// Where tiles come from: a file, a generator, a network. A load may be
/// slow and may fail; the cache never lets either stop a frame.
pub trait TileSource<const T: usize> {
    /// The whole terrain's size.
    fn world(&self) -> World;
    /// Fills `tile` with tile `key`; returns the bytes read to do it.
    /// On an error `tile`'s contents are unspecified (the cache drops it).
    fn load(&mut self, key: TileKey, tile: &mut Tile<T>) -> Result<usize, TileError>;
    /// The photos finer than level 0 the source has tiles of, in the
    /// order they lie over each other (the last on top); none by default.
    fn photos(&self) -> &[DetailArea] {
        &[]
    }
    /// Fills `tile` with photo tile `key` ([`PhotoKey`]), as
    /// [`TileSource::load`] does a pyramid tile.
    fn load_photo(&mut self, key: PhotoKey, tile: &mut PhotoTile<T>) -> Result<usize, TileError> {
        let _ = (key, tile);
        Err(TileError::Missing)
    }
    /// The stick table level 0's tiles name their points' sticks in
    /// ([`Tile::bounds`], [`TiledSurface::with_sticks`]); none by default.
    fn sticks(&self) -> StickTable<'_> {
        StickTable::EMPTY
    }
}

/// Fills `tile` with tile `key` of `pyramid`: a source for a map already in
/// memory, and the definition of what a packed file's tiles must hold.
/// False (and `tile` untouched) when the pyramid has no such tile.
pub fn cut_tile<const T: usize>(
    pyramid: &crate::Pyramid<'_>,
    key: TileKey,
    tile: &mut Tile<T>,
) -> bool {
    let Some(grid) = pyramid.level(usize::from(key.level)) else {
        return false;
    };
    let (w, d) = (grid.width(), grid.depth());
    let (x0, y0) = (key.x as usize * T, key.y as usize * T);
    if x0 >= w as usize || y0 >= d as usize {
        return false;
    }
    let bounds = pyramid.bounds(usize::from(key.level));
    for (j, ((heights, colors), cell_bounds)) in tile
        .heights
        .iter_mut()
        .zip(tile.colors.iter_mut())
        .zip(tile.bounds.iter_mut())
        .enumerate()
    {
        let y = (y0 + j).min(d as usize - 1);
        for i in 0..T {
            let x = (x0 + i).min(w as usize - 1);
            let at = y * w as usize + x;
            heights[i] = grid.heights().get(at).copied().unwrap_or(0);
            colors[i] = grid.colors().get(at).copied().unwrap_or([0; 3]);
            let (cx, cy) = ((x0 + i).min(w as usize - 2), (y0 + j).min(d as usize - 2));
            cell_bounds[i] = bounds
                .and_then(|b| b.get(cy * (w as usize - 1) + cx).copied())
                .unwrap_or(0);
        }
    }
    true
}

/// Writes `layer`'s points into level-0 tile `key` (cut by [`cut_tile`]
/// from the pyramid whose level 0 the layer stands on, `width` × `depth`
/// points): a tile's points name their sticks where coarser levels hold
/// bounds. Nothing for a tile of another level.
pub fn cut_stick_points<const T: usize>(
    layer: &StickLayer<'_>,
    (width, depth): (u32, u32),
    key: TileKey,
    tile: &mut Tile<T>,
) {
    if key.level != 0 || width == 0 || depth == 0 {
        return;
    }
    let (x0, y0) = (key.x as usize * T, key.y as usize * T);
    for (j, row) in tile.bounds.iter_mut().enumerate() {
        let y = (y0 + j).min(depth as usize - 1);
        for (i, point) in row.iter_mut().enumerate() {
            let x = (x0 + i).min(width as usize - 1);
            *point = layer.point(y * width as usize + x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::Grid;
    use crate::test_scenes::hills;
    use crate::{
        pyramid_cells, pyramid_points, render, Camera, CountingProbe, Framebuffer, HeightFilter,
        NoProbe, Pyramid, RenderOptions, Surface, Terrain, View,
    };
    use std::vec;

    /// Tiles cut from a pyramid in memory.
    struct Cut<'p>(&'p Pyramid<'p>);

    impl TileSource<16> for Cut<'_> {
        fn world(&self) -> World {
            let e = crate::Surface::extent(self.0);
            World::new(e.width, e.depth, e.max_height)
                .unwrap()
                .with_roughness(self.0.roughness())
        }
        fn load(&mut self, key: TileKey, tile: &mut Tile<16>) -> Result<usize, TileError> {
            cut_tile(self.0, key, tile)
                .then_some(Tile::<16>::BYTES)
                .ok_or(TileError::Missing)
        }
    }

    /// A map and the storage of its pyramid.
    struct Built {
        size: (u32, u32),
        heights: vec::Vec<u16>,
        colors: vec::Vec<Rgb>,
        coarse: (vec::Vec<u16>, vec::Vec<Rgb>, vec::Vec<u16>),
    }

    impl Built {
        fn hills(w: u32, d: u32) -> Self {
            let (heights, colors) = hills(w, d);
            let terrain = Terrain::new(w, d, &heights, &colors).unwrap();
            let n = pyramid_points(w, d);
            let (mut ph, mut pc) = (vec![0u16; n], vec![[0u8; 3]; n]);
            let mut pb = vec![0u16; pyramid_cells(w, d)];
            Pyramid::build(&terrain, HeightFilter::default(), &mut ph, &mut pc, &mut pb).unwrap();
            Self {
                size: (w, d),
                heights,
                colors,
                coarse: (ph, pc, pb),
            }
        }

        fn pyramid(&self) -> Pyramid<'_> {
            let (w, d) = self.size;
            let terrain = Terrain::new(w, d, &self.heights, &self.colors).unwrap();
            let (ph, pc, pb) = &self.coarse;
            Pyramid::new(terrain, ph, pc, pb).unwrap()
        }
    }

    /// A 64 x 48 frame from `camera` over `world` with `options`.
    fn frame_64x48(camera: Camera, world: &World, options: &RenderOptions) -> FootprintView {
        FootprintView {
            camera,
            width: 64,
            height: 48,
            pixel_to_voxel: options.level_bias(world.roughness),
            widen_deg: 0.0,
        }
    }

    /// Loads the footprint of a 64 × 48 frame from `camera` with
    /// `options` into `cache`, as the frame's.
    fn load_frame<S: TileSource<16>>(
        cache: &mut TileCache<'_, 16, 256>,
        source: &mut S,
        camera: Camera,
        options: &RenderOptions,
    ) {
        let mut needed = heapless::Vec::<TileKey, 512>::new();
        let frame = frame_64x48(camera, &source.world(), options);
        footprint::<16, 512>(&source.world(), &frame, &mut needed).unwrap();
        cache.begin_frame();
        for key in &needed {
            cache.require(*key, source).unwrap();
        }
    }

    #[test]
    fn rendering_from_tiles_equals_rendering_from_the_pyramid() {
        let built = Built::hills(203, 150);
        let pyramid = built.pyramid();
        let mut source = Cut(&pyramid);
        let mut slots = vec![Tile::<16>::EMPTY; 256].into_boxed_slice();
        let slots: &mut [Tile<16>; 256] = (&mut slots[..]).try_into().unwrap();
        let mut cache = TileCache::<16, 256>::new(source.world(), slots);
        for (eye, yaw, pitch) in [
            ([-20.0, 75.0, 90.0], 0.0, 15.0),
            ([100.0, 75.0, 60.0], 200.0, 40.0),
            ([10.0, 10.0, 70.0], 45.0, 3.0),
            ([100.0, 70.0, 300.0], 10.0, 90.0),
        ] {
            let camera = Camera::looking(eye, yaw, pitch);
            let options = RenderOptions::default();
            load_frame(&mut cache, &mut source, camera, &options);
            let surface = TiledSurface::around(&cache, camera.eye);
            assert_eq!(surface.origin(), [0, 0]);
            let view = View::new(&surface.local(&camera), 64, 48).unwrap();
            let draw = |s: &dyn Fn(&mut Framebuffer<'_>, &mut CountingProbe)| {
                let mut pixels = vec![[0u8; 3]; 64 * 48];
                let mut probe = CountingProbe::default();
                s(
                    &mut Framebuffer::new(&mut pixels, 64, 48).unwrap(),
                    &mut probe,
                );
                (pixels, probe.steps)
            };
            let from_tiles = draw(&|f, p| render(&surface, &view, &options, f, p));
            let from_pyramid = draw(&|f, p| render(&pyramid, &view, &options, f, p));
            let differ = from_tiles
                .0
                .iter()
                .zip(&from_pyramid.0)
                .filter(|(a, b)| a != b)
                .count();
            assert!(
                from_tiles == from_pyramid,
                "{camera:?}: {differ} pixels differ, steps {} and {}, degraded {}",
                from_tiles.1,
                from_pyramid.1,
                surface.degraded_samples()
            );
            // The footprint held every tile the frame read.
            assert_eq!(surface.degraded_samples(), 0, "{camera:?}");
        }
    }

    /// Tiles cut from a pyramid with objects, their level-0 tiles naming
    /// the layer's sticks.
    struct CutWithSticks<'p> {
        pyramid: &'p Pyramid<'p>,
        layer: StickLayer<'p>,
    }

    impl TileSource<16> for CutWithSticks<'_> {
        fn world(&self) -> World {
            Cut(self.pyramid).world()
        }
        fn load(&mut self, key: TileKey, tile: &mut Tile<16>) -> Result<usize, TileError> {
            if !cut_tile(self.pyramid, key, tile) {
                return Err(TileError::Missing);
            }
            let base = self.pyramid.base();
            cut_stick_points(&self.layer, (base.width(), base.depth()), key, tile);
            Ok(Tile::<16>::BYTES)
        }
        fn sticks(&self) -> StickTable<'_> {
            self.layer.table()
        }
    }

    #[test]
    fn rendering_objects_from_tiles_equals_rendering_them_from_memory() {
        use crate::{Stick, WithSticks};
        let (w, d) = (203, 150);
        let (mut heights, mut colors) = hills(w, d);
        // Posts every 9 points and a wall two points thick: sticks five
        // voxels tall, a texel a voxel, bottom up.
        let bands: vec::Vec<Rgb> = (0..5).map(|i| [250, 50 * i as u8, 0]).collect();
        let sticks = [Stick {
            first: 0,
            texels: 5,
            height: 5 * 16,
        }];
        let mut points = vec![0u16; (w * d) as usize];
        for y in 0..d {
            for x in 0..w {
                if (x % 9 == 4 && y % 9 == 4) || ((60..62).contains(&x) && (20..120).contains(&y)) {
                    let i = (y * w + x) as usize;
                    heights[i] += 5 * 16;
                    colors[i] = bands[4];
                    points[i] = 1;
                }
            }
        }
        let terrain = Terrain::new(w, d, &heights, &colors).unwrap();
        let layer = StickLayer::new(&terrain, &points, &sticks, &bands).unwrap();
        let n = pyramid_points(w, d);
        let (mut ph, mut pc) = (vec![0u16; n], vec![[0u8; 3]; n]);
        let mut pb = vec![0u16; pyramid_cells(w, d)];
        Pyramid::build_with_sticks(
            &terrain,
            HeightFilter::default(),
            Some(&layer),
            &mut ph,
            &mut pc,
            &mut pb,
        )
        .unwrap();
        let pyramid = Pyramid::new(terrain, &ph, &pc, &pb).unwrap();
        let in_memory = WithSticks::new(&pyramid, layer);
        let mut source = CutWithSticks {
            pyramid: &pyramid,
            layer,
        };
        let mut slots = vec![Tile::<16>::EMPTY; 256].into_boxed_slice();
        let slots: &mut [Tile<16>; 256] = (&mut slots[..]).try_into().unwrap();
        let mut cache = TileCache::<16, 256>::new(source.world(), slots);
        for (eye, yaw, pitch) in [
            ([30.0, 70.0, 60.0], 0.0, 10.0),
            ([100.0, 75.0, 60.0], 200.0, 40.0),
            ([10.0, 10.0, 70.0], 45.0, 3.0),
            ([100.0, 70.0, 300.0], 10.0, 90.0),
        ] {
            let camera = Camera::looking(eye, yaw, pitch);
            let options = RenderOptions::default();
            load_frame(&mut cache, &mut source, camera, &options);
            let table = source.sticks();
            let tiled = TiledSurface::around(&cache, camera.eye).with_sticks(table);
            let bare = TiledSurface::around(&cache, camera.eye);
            let view = View::new(&tiled.local(&camera), 64, 48).unwrap();
            let draw = |s: &dyn Fn(&mut Framebuffer<'_>)| {
                let mut pixels = vec![[0u8; 3]; 64 * 48];
                s(&mut Framebuffer::new(&mut pixels, 64, 48).unwrap());
                pixels
            };
            let from_tiles = draw(&|f| render(&tiled, &view, &options, f, &mut NoProbe));
            let from_memory = draw(&|f| render(&in_memory, &view, &options, f, &mut NoProbe));
            let without_table = draw(&|f| render(&bare, &view, &options, f, &mut NoProbe));
            let differ = from_tiles
                .iter()
                .zip(&from_memory)
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(differ, 0, "{camera:?}: pixels differ");
            assert_eq!(tiled.degraded_samples(), 0, "{camera:?}");
            // The sticks' texels show: without the table the posts and the
            // wall are their top color all the way down.
            assert_ne!(from_tiles, without_table, "{camera:?}");
        }
    }

    /// Tiles and photo tiles cut from a pyramid and photos in memory.
    struct CutWithPhotos<'p> {
        pyramid: &'p Pyramid<'p>,
        details: &'p [Detail<'p>],
        areas: vec::Vec<DetailArea>,
    }

    impl TileSource<16> for CutWithPhotos<'_> {
        fn world(&self) -> World {
            Cut(self.pyramid).world()
        }
        fn load(&mut self, key: TileKey, tile: &mut Tile<16>) -> Result<usize, TileError> {
            Cut(self.pyramid).load(key, tile)
        }
        fn photos(&self) -> &[DetailArea] {
            &self.areas
        }
        fn load_photo(
            &mut self,
            key: PhotoKey,
            tile: &mut PhotoTile<16>,
        ) -> Result<usize, TileError> {
            let detail = self
                .details
                .get(usize::from(key.photo))
                .ok_or(TileError::Missing)?;
            cut_photo_tile(detail, key, tile)
                .then_some(PhotoTile::<16>::BYTES)
                .ok_or(TileError::Missing)
        }
    }

    /// Fine level 0 of a photo `2^shift` times finer over `size` points:
    /// stripes and checks no level of the map shows.
    fn photo_texels(size: [u32; 2], shift: u32) -> vec::Vec<Rgb> {
        let mut texels = vec![[0u8; 3]; crate::detail_points(size[0], size[1], shift)];
        let row = (size[0] << shift) as usize;
        for (i, texel) in texels
            .iter_mut()
            .take(row * (size[1] << shift) as usize)
            .enumerate()
        {
            let (x, y) = (i % row, i / row);
            *texel = if (x / 3 + y / 2) % 2 == 0 {
                [230, (x * 5) as u8, 40]
            } else {
                [30, 90, (y * 7) as u8]
            };
        }
        texels
    }

    #[test]
    fn photos_paged_through_a_cache_render_as_photos_in_memory() {
        let built = Built::hills(203, 150);
        let pyramid = built.pyramid();
        // Two photos, the second partly over the first.
        let (mut first, mut second) = (photo_texels([60, 50], 2), photo_texels([40, 40], 3));
        let details = [
            Detail::build([40, 30], [60, 50], 2, &mut first).unwrap(),
            Detail::build([80, 60], [40, 40], 3, &mut second).unwrap(),
        ];
        let mut source = CutWithPhotos {
            pyramid: &pyramid,
            details: &details,
            areas: details.iter().map(Detail::area).collect(),
        };
        let in_memory = crate::WithDetail::checked(&pyramid, &details).unwrap();
        let mut slots = vec![Tile::<16>::EMPTY; 256].into_boxed_slice();
        let slots: &mut [Tile<16>; 256] = (&mut slots[..]).try_into().unwrap();
        let mut photo_slots = vec![PhotoTile::<16>::EMPTY; 1024].into_boxed_slice();
        let photo_slots: &mut [PhotoTile<16>; 1024] = (&mut photo_slots[..]).try_into().unwrap();
        let mut cache = TileCache::<16, 256>::new(source.world(), slots);
        let mut photo_cache = PhotoCache::<16, 1024>::new(source.world(), photo_slots);
        for (eye, yaw, pitch) in [
            ([70.0, 20.0, 70.0], 90.0, 30.0),
            ([100.0, 40.0, 80.0], 100.0, 45.0),
            ([60.0, 90.0, 60.0], 0.0, 20.0),
            ([95.0, 75.0, 120.0], 10.0, 90.0),
        ] {
            let camera = Camera::looking(eye, yaw, pitch);
            let options = RenderOptions::default();
            let frame = frame_64x48(camera, &source.world(), &options);
            let mut needed = heapless::Vec::<TileKey, 512>::new();
            footprint::<16, 512>(&source.world(), &frame, &mut needed).unwrap();
            let mut photos = heapless::Vec::<PhotoKey, 1024>::new();
            photo_footprint::<16, 1024>(&source.world(), source.photos(), &frame, &mut photos)
                .unwrap();
            assert!(!photos.is_empty(), "{camera:?}");
            cache.begin_frame();
            photo_cache.begin_frame();
            for key in &needed {
                cache.require(*key, &mut source).unwrap();
            }
            for key in &photos {
                photo_cache.require(*key, &mut source).unwrap();
            }
            let areas = source.areas.clone();
            let surface =
                TiledSurface::around(&cache, camera.eye).with_photos(&photo_cache, &areas);
            let view = View::new(&surface.local(&camera), 64, 48).unwrap();
            let draw = |s: &dyn Fn(&mut Framebuffer<'_>)| {
                let mut pixels = vec![[0u8; 3]; 64 * 48];
                s(&mut Framebuffer::new(&mut pixels, 64, 48).unwrap());
                pixels
            };
            let from_tiles = draw(&|f| render(&surface, &view, &options, f, &mut NoProbe));
            let from_memory = draw(&|f| render(&in_memory, &view, &options, f, &mut NoProbe));
            let bare = draw(&|f| render(&pyramid, &view, &options, f, &mut NoProbe));
            assert_eq!(surface.degraded_samples(), 0, "{camera:?}");
            assert!(from_tiles == from_memory, "{camera:?}");
            // The photos show: the view is not the map's own colors.
            assert!(from_tiles != bare, "{camera:?}");
        }
    }

    #[test]
    fn a_missing_photo_tile_reads_the_next_coarser_fine_level() {
        let built = Built::hills(64, 64);
        let pyramid = built.pyramid();
        let mut texels = photo_texels([32, 32], 2);
        let details = [Detail::build([16, 16], [32, 32], 2, &mut texels).unwrap()];
        let mut source = CutWithPhotos {
            pyramid: &pyramid,
            details: &details,
            areas: details.iter().map(Detail::area).collect(),
        };
        let mut slots = vec![Tile::<16>::EMPTY; 64].into_boxed_slice();
        let cache = all_but_one_tile(&pyramid, (&mut slots[..]).try_into().unwrap());
        let mut photo_slots = vec![PhotoTile::<16>::EMPTY; 128].into_boxed_slice();
        let photo_slots: &mut [PhotoTile<16>; 128] = (&mut photo_slots[..]).try_into().unwrap();
        let mut photo_cache = PhotoCache::<16, 128>::new(source.world(), photo_slots);
        photo_cache.begin_frame();
        // Fine level 0 (128 x 128 texels: 8 x 8 tiles) but its first
        // tile, and every tile of levels 1 and 2.
        for (level, tiles) in [(0u8, 8u32), (1, 4), (2, 2)] {
            for y in 0..tiles {
                for x in 0..tiles {
                    if (level, x, y) != (0, 0, 0) {
                        let key = PhotoKey {
                            photo: 0,
                            level,
                            x,
                            y,
                        };
                        photo_cache.require(key, &mut source).unwrap();
                    }
                }
            }
        }
        let areas = source.areas.clone();
        let surface = TiledSurface::around(&cache, [0.0; 3]).with_photos(&photo_cache, &areas);
        let one = 1i64 << 16;
        let reach = 64 * one;
        // A footprint that reads fine level 0 alone, in its missing first
        // tile (texels 0..16 are points 16 to 20): fine level 1's color
        // instead, counted.
        let point = [17 * one + one / 3, 18 * one];
        let before = surface.degraded_samples();
        let level1 = details[0].color(1, point);
        assert_eq!(surface.detail_color(point, reach / 16, reach), level1);
        assert!(surface.degraded_samples() > before);
        // In a resident tile, fine level 0's own, not counted.
        let point = [30 * one + one / 3, 40 * one];
        let before = surface.degraded_samples();
        assert_eq!(
            surface.detail_color(point, reach / 16, reach),
            details[0].color(0, point)
        );
        assert_eq!(surface.degraded_samples(), before);
        // Outside the photo: none.
        assert_eq!(
            surface.detail_color([2 * one, 2 * one], reach / 16, reach),
            None
        );
    }

    /// The tiles of a 64 x 64 map's levels 0 and 1, but for level 0's
    /// tile (1, 1), resident in `slots`.
    fn all_but_one_tile<'a>(
        pyramid: &Pyramid<'_>,
        slots: &'a mut [Tile<16>; 64],
    ) -> TileCache<'a, 16, 64> {
        let mut source = Cut(pyramid);
        let mut cache = TileCache::<16, 64>::new(source.world(), slots);
        cache.begin_frame();
        // Level 1 whole (33 x 33 points: tiles 0..=2), level 0 without tile (1, 1).
        for y in 0..3 {
            for x in 0..3 {
                cache
                    .require(TileKey { level: 1, x, y }, &mut source)
                    .unwrap();
            }
        }
        for y in 0..4 {
            for x in 0..4 {
                if (x, y) != (1, 1) {
                    cache
                        .require(TileKey { level: 0, x, y }, &mut source)
                        .unwrap();
                }
            }
        }
        cache
    }

    #[test]
    fn a_missing_tile_reads_the_coarser_level_and_is_counted() {
        let built = Built::hills(64, 64);
        let pyramid = built.pyramid();
        let (heights, ph) = (&built.heights, &built.coarse.0);
        let mut slots = vec![Tile::<16>::EMPTY; 64].into_boxed_slice();
        let cache = all_but_one_tile(&pyramid, (&mut slots[..]).try_into().unwrap());
        let surface = TiledSurface::around(&cache, [0.0; 3]);
        let level0 = crate::Surface::grid(&surface, 0).unwrap();
        let stride = level0.stride();
        // Point (20, 24) is in the missing tile: it reads level 1's (10, 12).
        let at = 24 * stride + 20;
        assert_eq!(level0.height(at), Some(ph[12 * 33 + 10]));
        assert_eq!(surface.degraded_samples(), 1);
        // Point (40, 24) is resident.
        assert_eq!(level0.height(24 * stride + 40), Some(heights[24 * 64 + 40]));
        assert_eq!(surface.degraded_samples(), 1);
        // Outside the world: nothing.
        assert_eq!(level0.height(24 * stride + 64), None);
        assert_eq!(level0.height(-1), None);

        // A pair reads what its two points read, and counts the same
        // degraded samples, whether it takes one lookup or two: both points
        // in the missing tile, across its borders (tiles are 16 points a
        // side), both resident, and one point outside the world.
        let row = 24 * stride;
        for (at, across) in [
            (row + 20, 1),
            (row + 20, stride),
            (row + 15, 1),
            (row + 31, 1),
            (23 * stride + 40, stride),
            (row + 40, 1),
            (row + 63, 1),
        ] {
            let before = surface.degraded_samples();
            let heights = level0.height(at).zip(level0.height(at + across));
            let colors = level0.color(at).zip(level0.color(at + across));
            let counted = surface.degraded_samples() - before;
            assert_eq!(level0.height_pair(at, across), heights, "{at} {across}");
            assert_eq!(level0.color_pair(at, across), colors, "{at} {across}");
            assert_eq!(
                surface.degraded_samples() - before,
                2 * counted,
                "{at} {across}"
            );
        }
    }
    /// A grid resolved near a point (the walk resolves its stage's grid
    /// near where it begins) reads what the plain grid reads, at every
    /// point and pair, inside the resolved tile, across its borders, in
    /// the missing tile and outside the world, and counts the same
    /// degraded samples.
    #[test]
    fn a_grid_resolved_near_a_point_reads_what_the_plain_grid_reads() {
        let built = Built::hills(64, 64);
        let pyramid = built.pyramid();
        let mut slots = vec![Tile::<16>::EMPTY; 64].into_boxed_slice();
        let cache = all_but_one_tile(&pyramid, (&mut slots[..]).try_into().unwrap());
        let surface = TiledSurface::around(&cache, [0.0; 3]);
        for level in [0, 1] {
            let plain = crate::Surface::grid(&surface, level).unwrap();
            let stride = plain.stride();
            let side = if level == 0 { 64 } else { 33 };
            // In tile (0, 0), in tile (2, 1), in the missing tile (1, 1)
            // (level 0), on the world's last point, outside it.
            for (x, y) in [(3, 5), (40, 20), (20, 24), (side - 1, side - 1), (side, 0)] {
                let near = plain.near(y * stride + x);
                for index in
                    (-2..side + 2).flat_map(|y| (-2..side + 2).map(move |x| y * stride + x))
                {
                    for across in [1, stride] {
                        let before = surface.degraded_samples();
                        let expected = (
                            plain.height(index),
                            plain.color(index),
                            plain.height_pair(index, across),
                            plain.color_pair(index, across),
                        );
                        let plain_counted = surface.degraded_samples() - before;
                        let got = (
                            near.height(index),
                            near.color(index),
                            near.height_pair(index, across),
                            near.color_pair(index, across),
                        );
                        assert_eq!(got, expected, "level {level} near ({x}, {y}) index {index}");
                        assert_eq!(
                            surface.degraded_samples() - before - plain_counted,
                            plain_counted,
                            "level {level} near ({x}, {y}) index {index}"
                        );
                    }
                }
            }
        }
    }
}
