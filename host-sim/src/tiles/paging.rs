//! Rendering through the kernel's tile cache: one view (`render
//! --terrain`), and a flight that pages tiles the way Cohen-Or's master
//! did (§3.2): each frame is drawn from what is resident when it starts,
//! and while it is drawn the loader fetches, within a budget of tiles a
//! frame, first the tiles it lacked, then the next frame's, then an
//! extended footprint ahead along the turn.

use super::{new_slots, SLOTS, TILE};
use crate::error::{Error, Result};
use crate::frame::{Frame, RenderStats};
use crate::kernel::{render_surface, render_surface_in, PixelRays};
use serde::Serialize;
use terracast::tiles::{
    footprint_under, photo_footprint, FootprintView, Payload, PhotoCache, PhotoKey, PhotoTile,
    Tile, TileCache, TileKey, TileSource, TiledSurface,
};
use terracast::{Camera, DetailArea, PreparedAtmosphere, RenderOptions};

/// Footprint list capacity: far more than a 32 MiB cache holds.
const FOOTPRINT: usize = 16_384;

type Keys = heapless::Vec<TileKey, FOOTPRINT>;
type PhotoKeys = heapless::Vec<PhotoKey, FOOTPRINT>;

/// Photo tile slots of the host's photo cache (12 KiB each: 24 MiB at
/// most), for a source with photos finer than its height grid.
pub const PHOTO_SLOTS: usize = 2048;

/// A source's photos paged through a photo cache of `M` slots: where
/// they lie, the tiles the frame needs, and the cache.
struct PhotoPager<'s, const M: usize> {
    cache: PhotoCache<'s, TILE, M>,
    areas: Vec<DetailArea>,
    needed: Box<PhotoKeys>,
}

impl<'s, const M: usize> PhotoPager<'s, M> {
    fn new<S: TileSource<TILE>>(source: &S, slots: &'s mut [PhotoTile<TILE>; M]) -> Self {
        Self {
            cache: PhotoCache::new(source.world(), slots),
            areas: source.photos().to_vec(),
            needed: Box::new(PhotoKeys::new()),
        }
    }

    /// Adds the photo tiles `camera` needs to `keys`, by fine level
    /// (coarse ones last: fetched first, from the end).
    fn collect(
        &self,
        camera: &Camera,
        size: (u32, u32),
        bias: f32,
        widen_deg: f32,
        keys: &mut PhotoKeys,
    ) -> Result<()> {
        let view = footprint_view(camera, size, bias, widen_deg);
        photo_footprint::<TILE, FOOTPRINT>(&self.cache.world(), &self.areas, &view, keys)
            .map_err(|e| Error::new(format!("photo footprint: {e}")))?;
        keys.sort_by_key(|k| k.level);
        Ok(())
    }

    /// Replaces the photo tiles the frame needs with `camera`'s.
    fn collect_needed(&mut self, camera: &Camera, size: (u32, u32), bias: f32) -> Result<()> {
        let mut needed = std::mem::take(&mut self.needed);
        needed.clear();
        let collected = self.collect(camera, size, bias, 0.0, &mut needed);
        self.needed = needed;
        collected
    }

    /// Loads `camera`'s photo tiles (coarse fine levels first, so that
    /// the finest are the ones left out when the cache is full); returns
    /// those that could not be loaded.
    fn load_view<S: TileSource<TILE>>(
        &mut self,
        source: &mut S,
        camera: &Camera,
        size: (u32, u32),
        bias: f32,
    ) -> Result<usize> {
        self.collect_needed(camera, size, bias)?;
        let needed = std::mem::take(&mut self.needed);
        let misses = needed
            .iter()
            .rev()
            .filter(|key| self.cache.require(**key, source).is_err())
            .count();
        self.needed = needed;
        Ok(misses)
    }
}

/// The host photo cache's slots, on the heap.
pub fn new_photo_slots() -> Box<[PhotoTile<TILE>; PHOTO_SLOTS]> {
    let slots = vec![PhotoTile::<TILE>::EMPTY; PHOTO_SLOTS].into_boxed_slice();
    // The length is PHOTO_SLOTS by construction.
    slots.try_into().unwrap_or_else(|_| unreachable!())
}

/// The fewest photo slots a cache takes (its directory needs two), for a
/// source without photos, which never uses them.
fn no_photo_slots() -> Box<[PhotoTile<TILE>; 2]> {
    Box::new([PhotoTile::<TILE>::EMPTY, PhotoTile::<TILE>::EMPTY])
}

/// What a render through the cache did, besides the image.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct TiledRender {
    /// Tiles in the frame's footprint.
    pub footprint_tiles: usize,
    /// Of the resident tiles, those the frame read.
    pub touched_tiles: usize,
    /// Terrain bytes resident when the frame was drawn: tiles, photo
    /// tiles and the stick table.
    pub resident_bytes: u64,
    /// Tiles loaded for the frame.
    pub tiles_loaded: u64,
    /// Footprint tiles that could not be loaded (failed, rejected, or no
    /// room): drawn from a coarser level.
    pub misses: usize,
    /// Of those, tiles rejected for a bad checksum.
    pub rejected: u64,
    /// Samples read from a coarser level than the caster asked for.
    pub degraded_samples: u32,
    /// Bytes the source read.
    pub bytes_read: u64,
    /// Photo tiles in the frame's footprint (photos finer than the height
    /// grid, at their own resolution).
    pub photo_tiles: usize,
    /// Photo tiles loaded for the frame.
    pub photo_tiles_loaded: u64,
    /// Photo tiles of the footprint that could not be loaded: drawn from
    /// a coarser fine level, or the height grid's colors.
    pub photo_misses: usize,
}

/// The frame a footprint is made for: `camera` at `size`, its level
/// bias, widened by `widen_deg` a side.
fn footprint_view(camera: &Camera, size: (u32, u32), bias: f32, widen_deg: f32) -> FootprintView {
    FootprintView {
        camera: *camera,
        width: size.0,
        height: size.1,
        pixel_to_voxel: bias,
        widen_deg,
    }
}

/// Adds the footprint of `camera` to `keys`, cut to the terrain height
/// the coarser tiles resident in `cache` show.
fn collect(
    cache: &TileCache<'_, TILE, SLOTS>,
    camera: &Camera,
    size: (u32, u32),
    bias: f32,
    widen_deg: f32,
    keys: &mut Keys,
) -> Result<u8> {
    let ceiling = |key| cache.ceiling(key);
    let view = footprint_view(camera, size, bias, widen_deg);
    footprint_under::<TILE, FOOTPRINT>(&cache.world(), &view, &ceiling, keys)
        .map_err(|e| Error::new(format!("view footprint: {e}")))
}

/// Loads the view's footprint level by level from the top, each level's
/// cut by the bounds of the one above, loaded just before; leaves the
/// footprint in `needed` and returns the tiles that could not be loaded.
/// If the cache cannot hold everything, the fine tiles are the ones left
/// out, and coarse ones stand in for them.
fn load_view<S: TileSource<TILE>>(
    cache: &mut TileCache<'_, TILE, SLOTS>,
    source: &mut S,
    camera: &Camera,
    size: (u32, u32),
    bias: f32,
    needed: &mut Keys,
) -> Result<usize> {
    let mut misses = 0;
    let mut level = collect(cache, camera, size, bias, 0.0, needed)?;
    loop {
        needed.clear();
        collect(cache, camera, size, bias, 0.0, needed)?;
        for key in needed.iter().filter(|k| k.level == level) {
            if cache.require(*key, source).is_err() {
                misses += 1;
            }
        }
        if level == 0 {
            return Ok(misses);
        }
        level -= 1;
    }
}

/// `camera` in the window's coordinates, refused in one line when the eye
/// is too far from the terrain for the caster's coordinates.
fn local_camera<const M: usize>(
    surface: &TiledSurface<'_, '_, TILE, SLOTS, M>,
    camera: &Camera,
) -> Result<Camera> {
    let local = surface.local(camera);
    let limit = terracast::config::MAX_EYE_COORD;
    if local.eye[0].abs() > limit || local.eye[1].abs() > limit {
        return Err(Error::new(format!(
            "eye ({}, {}) is too far from the terrain: it must be within {limit} voxels of the window the view is drawn from (origin {:?})",
            camera.eye[0],
            camera.eye[1],
            surface.origin()
        )));
    }
    Ok(local)
}

/// The tiles of `camera`'s footprint at `size` (as a render through the
/// cache loads them), and how many of them lie wholly farther than
/// `distance` voxels from the eye (horizontally, so farther along any
/// ray): what a renderer that stops its rays there would not need (fog's
/// opaque distance, `terracast::Fog::opaque_distance`).
pub fn footprint_beyond<S: TileSource<TILE>>(
    source: &mut S,
    camera: &Camera,
    size: (u32, u32),
    options: &RenderOptions,
    distance: f64,
) -> Result<(usize, usize)> {
    let world = source.world();
    let mut slots = new_slots();
    let mut cache = TileCache::<TILE, SLOTS>::new(world, &mut slots);
    let mut needed = Box::new(Keys::new());
    cache.begin_frame();
    load_view(
        &mut cache,
        source,
        camera,
        size,
        options.level_bias(world.roughness),
        &mut needed,
    )?;
    let [x, y, _] = camera.eye.map(f64::from);
    let beyond = needed
        .iter()
        .filter(|key| {
            // The tile's points, in voxels: `TILE` a side, `2^level` apart.
            let spacing = f64::from(1u32 << key.level);
            let side = TILE as f64 * spacing;
            let (x0, y0) = (f64::from(key.x) * side, f64::from(key.y) * side);
            let (x1, y1) = (x0 + side - spacing, y0 + side - spacing);
            let dx = (x0 - x).max(x - x1).max(0.0);
            let dy = (y0 - y).max(y - y1).max(0.0);
            dx.hypot(dy) > distance
        })
        .count();
    Ok((needed.len(), beyond))
}

/// Renders one view of `source` (camera in world coordinates) through a
/// cache of [`SLOTS`] tiles, loading the view's footprint first.
pub fn render_tiled<S: TileSource<TILE>>(
    source: &mut S,
    camera: &Camera,
    width: u32,
    height: u32,
    options: &RenderOptions,
    rays: PixelRays,
) -> Result<(Frame, RenderStats, TiledRender)> {
    render_tiled_in(source, camera, (width, height), options, rays, None)
}

/// [`render_tiled`] with `atmosphere` over the frame (when given).
pub fn render_tiled_in<S: TileSource<TILE>>(
    source: &mut S,
    camera: &Camera,
    size: (u32, u32),
    options: &RenderOptions,
    rays: PixelRays,
    atmosphere: Option<&PreparedAtmosphere>,
) -> Result<(Frame, RenderStats, TiledRender)> {
    // The photo cache's slots are a type parameter: one slot when there
    // are no photos.
    if source.photos().is_empty() {
        let mut slots = no_photo_slots();
        render_tiled_with(source, camera, size, options, rays, atmosphere, &mut slots)
    } else {
        let mut slots = new_photo_slots();
        render_tiled_with(source, camera, size, options, rays, atmosphere, &mut slots)
    }
}

fn render_tiled_with<S: TileSource<TILE>, const M: usize>(
    source: &mut S,
    camera: &Camera,
    (width, height): (u32, u32),
    options: &RenderOptions,
    rays: PixelRays,
    atmosphere: Option<&PreparedAtmosphere>,
    photo_slots: &mut [PhotoTile<TILE>; M],
) -> Result<(Frame, RenderStats, TiledRender)> {
    let world = source.world();
    let mut slots = new_slots();
    let mut cache = TileCache::<TILE, SLOTS>::new(world, &mut slots);
    let mut needed = Box::new(Keys::new());
    cache.begin_frame();
    let bias = options.level_bias(world.roughness);
    let misses = load_view(
        &mut cache,
        source,
        camera,
        (width, height),
        bias,
        &mut needed,
    )?;
    let mut photos = PhotoPager::new(source, photo_slots);
    photos.cache.begin_frame();
    let photo_misses = photos.load_view(source, camera, (width, height), bias)?;
    let sticks = source.sticks();
    let surface = TiledSurface::around(&cache, camera.eye)
        .with_photos(&photos.cache, &photos.areas)
        .with_sticks(sticks);
    let (frame, mut stats) = render_surface_in(
        &surface,
        &local_camera(&surface, camera)?,
        (width, height),
        options,
        rays,
        atmosphere,
    )?;
    // The stick table is held whole, beside the tiles.
    let resident_bytes =
        (cache.resident_bytes() + photos.cache.resident_bytes() + sticks.bytes()) as u64;
    stats.resident_bytes = resident_bytes;
    let (cache_stats, photo_stats) = (cache.stats(), photos.cache.stats());
    let tiled = TiledRender {
        footprint_tiles: needed.len(),
        touched_tiles: surface.touched_tiles(),
        resident_bytes,
        tiles_loaded: cache_stats.loads,
        misses,
        rejected: cache_stats.rejected + photo_stats.rejected,
        degraded_samples: surface.degraded_samples(),
        bytes_read: cache_stats.bytes_read + photo_stats.bytes_read,
        photo_tiles: photos.needed.len(),
        photo_tiles_loaded: photo_stats.loads,
        photo_misses,
    };
    Ok((frame, stats, tiled))
}

/// A tiled terrain drawn frame after frame through one cache that stays
/// resident between frames (the interactive viewer's): each frame loads
/// what its footprint lacks, then renders from the window around the eye,
/// with the source's photos finer than its grid through a photo cache.
pub struct TiledViewer<'s, S: TileSource<TILE>> {
    source: S,
    cache: TileCache<'s, TILE, SLOTS>,
    photos: PhotoPager<'s, PHOTO_SLOTS>,
    needed: Box<Keys>,
}

impl<'s, S: TileSource<TILE>> TiledViewer<'s, S> {
    /// A viewer of `source` whose cache lives in `slots`, and its photo
    /// cache in `photo_slots` ([`new_photo_slots`]).
    pub fn new(
        source: S,
        slots: &'s mut [Tile<TILE>; SLOTS],
        photo_slots: &'s mut [PhotoTile<TILE>; PHOTO_SLOTS],
    ) -> Self {
        let cache = TileCache::new(source.world(), slots);
        let photos = PhotoPager::new(&source, photo_slots);
        Self {
            source,
            cache,
            photos,
            needed: Box::new(Keys::new()),
        }
    }

    /// The terrain's extent.
    pub fn world(&self) -> terracast::tiles::World {
        self.source.world()
    }

    /// The ground under `eye` (world coordinates), from the tiles
    /// resident now ([`crate::viewer::ground_under`]).
    pub fn ground_under(&self, eye: [f32; 3]) -> Option<f32> {
        let surface = TiledSurface::around(&self.cache, eye);
        let local = surface.local(&Camera::looking(eye, 0.0, 0.0)).eye;
        crate::viewer::ground_under(&surface, local[0], local[1])
    }

    /// Loads `camera`'s footprint (world coordinates) at `size` with
    /// `options`, then calls `draw` with the window around the eye and the
    /// camera in its coordinates. Returns what `draw` returns and the
    /// footprint tiles (and photo tiles) that could not be loaded.
    pub fn frame<R>(
        &mut self,
        camera: &Camera,
        size: (u32, u32),
        options: &RenderOptions,
        draw: impl FnOnce(&TiledSurface<'_, 's, TILE, SLOTS, PHOTO_SLOTS>, &Camera) -> R,
    ) -> Result<(R, usize)> {
        self.cache.begin_frame();
        self.photos.cache.begin_frame();
        self.needed.clear();
        let bias = options.level_bias(self.source.world().roughness);
        let misses = load_view(
            &mut self.cache,
            &mut self.source,
            camera,
            size,
            bias,
            &mut self.needed,
        )?;
        let photo_misses = self
            .photos
            .load_view(&mut self.source, camera, size, bias)?;
        let surface = TiledSurface::around(&self.cache, camera.eye)
            .with_photos(&self.photos.cache, &self.photos.areas)
            .with_sticks(self.source.sticks());
        let local = local_camera(&surface, camera)?;
        Ok((draw(&surface, &local), misses + photo_misses))
    }
}

/// How to fly through a tiled terrain.
#[derive(Debug, Clone)]
pub struct PageOptions {
    /// Image size.
    pub size: (u32, u32),
    /// Frames to fly.
    pub frames: u32,
    /// Frames a second.
    pub fps: f32,
    /// Heading change, degrees a second (Cohen-Or's test: one field of view
    /// a second).
    pub turn_deg_per_s: f32,
    /// Ground speed, voxels a second.
    pub speed: f32,
    /// Start: eye position (world), heading, pitch, field of view.
    pub start: Camera,
    /// Tiles the loader may fetch during one frame (the disk's share).
    pub load_budget: u32,
    /// Fetch the next frame's footprint and the extended one ahead; off,
    /// the loader only fetches what the frame just lacked.
    pub prefetch: bool,
    /// How far ahead the extended footprint looks, seconds.
    pub lead_s: f32,
    /// Kernel options.
    pub options: RenderOptions,
    /// A keyframed path to fly instead of the turn (`fly`'s format; its
    /// field of view is `start`'s).
    pub path: Option<crate::fly::Path>,
}

/// One frame of a paged flight.
#[derive(Debug, Clone, Serialize)]
pub struct PagedFrame {
    /// Frame number.
    pub frame: u32,
    /// Tiles the frame's view may need (the conservative footprint the
    /// loader works from).
    pub footprint_tiles: usize,
    /// Tiles the frame actually read.
    pub touched_tiles: usize,
    /// Of those, tiles not resident when it was drawn (drawn from a
    /// coarser level instead).
    pub missing_tiles: usize,
    /// Photo tiles the frame's view may need (photos finer than the
    /// height grid).
    pub photo_footprint_tiles: usize,
    /// Of those, photo tiles not resident when it was drawn (drawn from
    /// a coarser fine level, or the grid's colors).
    pub photo_missing_tiles: usize,
    /// Samples the frame read from a coarser level than asked for.
    pub degraded_samples: u32,
    /// Tiles loaded while this frame was drawn (the first frame: before).
    pub loads: u64,
    /// Bytes the source read for them.
    pub bytes_read: u64,
    /// Tiles the cache rejected for a bad checksum while this frame was
    /// drawn (they stay missing and are drawn from a coarser level).
    pub rejected: u64,
    /// Terrain bytes resident when the frame was drawn: tiles, photo
    /// tiles and the stick table.
    pub resident_bytes: u64,
    /// Bytes of the frame's own footprint.
    pub footprint_bytes: u64,
    /// Steps per pixel.
    pub steps_per_pixel: f64,
}

/// A paged flight's frames and summary.
#[derive(Debug, Clone, Serialize)]
pub struct PageReport {
    /// Side of the world along x.
    pub world_width: u32,
    /// Side of the world along y.
    pub world_depth: u32,
    /// Cache capacity in bytes.
    pub cache_bytes: u64,
    /// Every frame.
    pub frames: Vec<PagedFrame>,
    /// Tiles rejected for a bad checksum over the flight.
    pub rejected: u64,
}

impl PageReport {
    /// Frames after the first drawn with a footprint tile missing.
    pub fn frames_missing_after_first(&self) -> usize {
        self.frames
            .iter()
            .skip(1)
            .filter(|f| f.missing_tiles > 0)
            .count()
    }

    /// Resident bytes over the frame's footprint bytes: mean and largest,
    /// after the first frame.
    pub fn resident_ratio(&self) -> (f64, f64) {
        let ratios: Vec<f64> = self
            .frames
            .iter()
            .skip(1)
            .map(|f| f.resident_bytes as f64 / f.footprint_bytes.max(1) as f64)
            .collect();
        let mean = ratios.iter().sum::<f64>() / ratios.len().max(1) as f64;
        (mean, ratios.iter().copied().fold(0.0, f64::max))
    }

    /// Resident bytes over the bytes of the tiles the frame read: mean and
    /// largest, after the first frame.
    pub fn resident_over_touched(&self) -> (f64, f64) {
        let ratios: Vec<f64> = self
            .frames
            .iter()
            .skip(1)
            .map(|f| {
                f.resident_bytes as f64 / (f.touched_tiles.max(1) * Tile::<TILE>::BYTES) as f64
            })
            .collect();
        let mean = ratios.iter().sum::<f64>() / ratios.len().max(1) as f64;
        (mean, ratios.iter().copied().fold(0.0, f64::max))
    }

    /// Loads per frame after the first: mean and largest.
    pub fn loads_per_frame(&self) -> (f64, u64) {
        let loads: Vec<u64> = self.frames.iter().skip(1).map(|f| f.loads).collect();
        let mean = loads.iter().sum::<u64>() as f64 / loads.len().max(1) as f64;
        (mean, loads.iter().copied().max().unwrap_or(0))
    }
}

/// The camera `t` seconds into the flight: turning at a steady rate,
/// moving along its heading.
pub fn flight_camera(options: &PageOptions, t: f32) -> Camera {
    if let Some(path) = &options.path {
        return path.camera(f64::from(t), options.start.hfov_deg);
    }
    let start = &options.start;
    let turn = options.turn_deg_per_s.to_radians();
    let yaw0 = start.yaw_deg.to_radians();
    // Position: the integral of the heading over time.
    let (dx, dy) = if turn.abs() < 1e-6 {
        (yaw0.cos() * t, yaw0.sin() * t)
    } else {
        (
            ((yaw0 + turn * t).sin() - yaw0.sin()) / turn,
            (yaw0.cos() - (yaw0 + turn * t).cos()) / turn,
        )
    };
    Camera {
        eye: [
            start.eye[0] + options.speed * dx,
            start.eye[1] + options.speed * dy,
            start.eye[2],
        ],
        yaw_deg: start.yaw_deg + options.turn_deg_per_s * t,
        ..*start
    }
}

/// Flies `options.frames` frames over `source` through a cache of
/// [`SLOTS`] tiles (and, for a source with photos finer than its grid,
/// a photo cache of [`PHOTO_SLOTS`]); `each_frame` gets every frame's
/// image and record.
pub fn page_flight<S: TileSource<TILE>>(
    source: &mut S,
    options: &PageOptions,
    each_frame: &mut dyn FnMut(&Frame, &PagedFrame) -> Result<()>,
) -> Result<PageReport> {
    if source.photos().is_empty() {
        page_flight_with(source, options, each_frame, &mut no_photo_slots())
    } else {
        page_flight_with(source, options, each_frame, &mut new_photo_slots())
    }
}

/// Makes `keys` resident in `cache` (pinned, or prefetched), from the
/// last (the coarsest, for keys by level), as many as `budget` loads
/// allow; resident ones are pinned whatever the budget.
fn fetch<S: TileSource<TILE>, P: Payload<TILE>, const N: usize>(
    cache: &mut TileCache<'_, TILE, N, P>,
    source: &mut S,
    keys: &[P::Key],
    pin: bool,
    budget: &mut u32,
) {
    for key in keys.iter().rev() {
        if cache.contains(key) {
            if pin {
                cache.pin(*key);
            }
            continue;
        }
        if *budget == 0 {
            continue;
        }
        *budget -= 1;
        let _ = if pin {
            cache.require(*key, source)
        } else {
            cache.prefetch(*key, source)
        };
    }
}

fn page_flight_with<S: TileSource<TILE>, const M: usize>(
    source: &mut S,
    options: &PageOptions,
    each_frame: &mut dyn FnMut(&Frame, &PagedFrame) -> Result<()>,
    photo_slots: &mut [PhotoTile<TILE>; M],
) -> Result<PageReport> {
    if !(options.fps > 0.0 && options.fps.is_finite()) {
        return Err(Error::new("--fps must be a positive number"));
    }
    let world = source.world();
    let bias = options.options.level_bias(world.roughness);
    let mut slots = new_slots();
    let mut cache = TileCache::<TILE, SLOTS>::new(world, &mut slots);
    let mut photos = PhotoPager::new(source, photo_slots);
    let (mut needed, mut ahead) = (Box::new(Keys::new()), Box::new(Keys::new()));
    let mut photos_ahead = Box::new(PhotoKeys::new());
    let mut frames = Vec::new();
    let period = 1.0 / options.fps;
    for frame in 0..options.frames {
        let t = frame as f32 * period;
        let camera = flight_camera(options, t);
        let (before, photos_before) = (cache.stats(), photos.cache.stats());
        cache.begin_frame();
        photos.cache.begin_frame();
        needed.clear();
        if frame == 0 {
            // The first frame waits for its tiles.
            load_view(&mut cache, source, &camera, options.size, bias, &mut needed)?;
            photos.load_view(source, &camera, options.size, bias)?;
        } else {
            collect(&cache, &camera, options.size, bias, 0.0, &mut needed)?;
            photos.collect_needed(&camera, options.size, bias)?;
        }
        let missing: Vec<TileKey> = needed.iter().filter(|k| !cache.pin(**k)).copied().collect();
        let photos_missing: Vec<PhotoKey> = photos
            .needed
            .iter()
            .filter(|k| !photos.cache.pin(**k))
            .copied()
            .collect();
        let sticks = source.sticks();
        let surface = TiledSurface::around(&cache, camera.eye)
            .with_photos(&photos.cache, &photos.areas)
            .with_sticks(sticks);
        let (image, stats) = render_surface(
            &surface,
            &local_camera(&surface, &camera)?,
            options.size.0,
            options.size.1,
            &options.options,
        )?;
        let degraded = surface.degraded_samples();
        let touched = surface.touched_tiles();
        let resident =
            (cache.resident_bytes() + photos.cache.resident_bytes() + sticks.bytes()) as u64;

        // While the frame is drawn: what it lacked, then (with prefetch)
        // the next frame's footprint, pinned so that nothing evicts it
        // before that frame, then the extended one ahead, coarse levels
        // first within each (a photo tile counts as a load, as a tile
        // does). The first frame waits for all of it.
        let mut budget = if frame == 0 {
            u32::MAX
        } else {
            options.load_budget
        };
        fetch(&mut cache, source, &missing, true, &mut budget);
        fetch(
            &mut photos.cache,
            source,
            &photos_missing,
            true,
            &mut budget,
        );
        ahead.clear();
        photos_ahead.clear();
        if options.prefetch {
            let next = flight_camera(options, (frame + 1) as f32 * period);
            collect(&cache, &next, options.size, bias, 0.0, &mut ahead)?;
            fetch(&mut cache, source, &ahead, true, &mut budget);
            photos.collect(&next, options.size, bias, 0.0, &mut photos_ahead)?;
            fetch(&mut photos.cache, source, &photos_ahead, true, &mut budget);
            let lead = options.lead_s.max(period);
            let widen = options.turn_deg_per_s.abs() * lead / 2.0;
            let later = flight_camera(options, t + lead);
            collect(&cache, &later, options.size, bias, widen, &mut ahead)?;
            let mut by_level: Vec<TileKey> = ahead.to_vec();
            by_level.sort_by_key(|k| k.level);
            fetch(&mut cache, source, &by_level, false, &mut budget);
            photos.collect(&later, options.size, bias, widen, &mut photos_ahead)?;
            fetch(&mut photos.cache, source, &photos_ahead, false, &mut budget);
            // Hold no more than this view and the next ones need.
            cache.retain(|k| ahead.binary_search(k).is_ok());
            photos_ahead.sort_unstable();
            photos
                .cache
                .retain(|k| photos_ahead.binary_search(k).is_ok());
        } else {
            cache.retain(|k| needed.binary_search(k).is_ok());
            let mut kept = photos.needed.to_vec();
            kept.sort_unstable();
            photos.cache.retain(|k| kept.binary_search(k).is_ok());
        }
        let (end, photos_end) = (cache.stats(), photos.cache.stats());
        let record = PagedFrame {
            frame,
            footprint_tiles: needed.len(),
            touched_tiles: touched,
            missing_tiles: missing.len(),
            photo_footprint_tiles: photos.needed.len(),
            photo_missing_tiles: photos_missing.len(),
            degraded_samples: degraded,
            loads: end.loads - before.loads + photos_end.loads - photos_before.loads,
            bytes_read: end.bytes_read - before.bytes_read + photos_end.bytes_read
                - photos_before.bytes_read,
            rejected: end.rejected - before.rejected + photos_end.rejected - photos_before.rejected,
            resident_bytes: resident,
            footprint_bytes: (needed.len() * Tile::<TILE>::BYTES
                + photos.needed.len() * PhotoTile::<TILE>::BYTES)
                as u64,
            steps_per_pixel: stats.steps as f64 / stats.pixels.max(1) as f64,
        };
        each_frame(&image, &record)?;
        frames.push(record);
    }
    Ok(PageReport {
        world_width: world.width,
        world_depth: world.depth,
        cache_bytes: (SLOTS * Tile::<TILE>::BYTES
            + if photos.areas.is_empty() {
                0
            } else {
                M * PhotoTile::<TILE>::BYTES
            }) as u64,
        rejected: frames.iter().map(|f| f.rejected).sum(),
        frames,
    })
}
