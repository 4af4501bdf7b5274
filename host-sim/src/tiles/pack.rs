//! `terracast-sim pack`: height and color maps to a `.tiles` file, one row
//! at a time, so an input larger than memory can be packed.
//!
//! The pyramid is built as the rows stream in, with the kernel's filter
//! and bounds ([`terracast::Pyramid::build`]) to the bit: a coarse row is
//! made as soon as the three finer rows under it have arrived, a bound row
//! as soon as the coarse row after it has, and a strip of tiles is written
//! as soon as its rows and bounds are complete. Memory is a few strips of
//! [`TILE`] rows a level, whatever the map's size.
//!
//! PNG maps stream row by row, GeoTIFF heights a strip (or a row of
//! tiles) at a time ([`TiffHeightRows`]) and SRTM `.hgt` tiles row by
//! row; voids are filled as the rows pass ([`VoidFill`]: each void as soon
//! as the row after it arrives), to the bit as `render` fills them.
//! GeoTIFF photos placed by their georeference stream with the rows they
//! color ([`StreamedPhoto`]: a window of each photo's rows, draped row by
//! row, its texels kept and cut into photo tiles as they come), and so
//! does one PNG or TIFF color map stretched over the map, whatever its
//! size ([`Stretching`]). A color map in another image format is loaded
//! whole, as `render` loads it ([`load_scene_files`]), and the rows
//! packed from memory. A photo finer than the height grid is packed at its own
//! resolution, its fine levels cut into photo tiles
//! ([`terracast::tiles::cut_photo_tile`]).

use super::file::{Header, TilesWriter, MAX_PHOTOS, MAX_STICKS};
use super::TILE;
use crate::error::{Error, Result};
use crate::objects::placing::ScenePlan;
use crate::outputs::Outputs;
use crate::scene::geotiff::PhotoRowSource;
use crate::scene::geotiff::{is_tiff, TiffHeightRows};
use crate::scene::geotiff::{Drape, PhotoWindow};
use crate::scene::voids::VoidFill;
use crate::scene::{
    block_means, hgt_height, hgt_side, load_scene_files, not_a_height_map, placements,
    refuse_mostly_void, report_filled, terrain_color, value_noise, HeightBands, PlacedPhoto, Scene,
    Stretch, StretchedPhoto,
};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use terracast::roughness::RoughnessSum;
use terracast::tiles::{
    cut_photo_tile, cut_stick_points, cut_tile, photo_tiles, PhotoKey, PhotoTile, Tile, TileKey,
    World,
};
use terracast::wavelet_row;
use terracast::{Detail, DetailArea, HeightFilter, Rgb, StickTable, Terrain};

/// What to pack.
#[derive(Debug, Clone)]
pub struct PackInput {
    /// Height map: 8/16-bit grayscale PNG, SRTM `.hgt` or GeoTIFF.
    pub height: PathBuf,
    /// Color maps, as `render` drapes them: none (heights colored by
    /// height and slope, as `render` colors them), one PNG of the same size
    /// (8-bit RGB, RGBA, gray or palette; streamed with a PNG height map),
    /// or photos: GeoTIFFs over a GeoTIFF height map placed by their
    /// georeference, each over the ones before (read whole, see the
    /// module's notes), or one photo stretched over the map.
    pub colors: Vec<PathBuf>,
    /// World height of one height-map unit, in voxels.
    pub height_scale: f32,
    /// How coarse heights are made.
    pub filter: HeightFilter,
    /// Seed of the coloring's texture (when there is no color map), and
    /// of the objects' planting.
    pub seed: u64,
    /// Plant a wood and a village on the map by a rule seeded with
    /// `seed`, as `render --objects` plants them.
    pub objects: bool,
    /// Stand the objects of this scene file on the map (as `render
    /// --place`).
    pub place: Option<PathBuf>,
}

/// What `pack` wrote.
#[derive(Debug, Clone)]
pub struct PackSummary {
    /// Level-0 size.
    pub width: u32,
    /// Level-0 size.
    pub depth: u32,
    /// Levels written.
    pub levels: u8,
    /// Tiles written.
    pub tiles: u64,
    /// Photo tiles written: the texels of photos finer than the height
    /// grid, at their own resolution.
    pub photo_tiles: u64,
    /// File size in bytes.
    pub bytes: u64,
    /// Most rows (of points and of bounds, all levels) held at once: the
    /// streaming's memory, whatever the input's height.
    pub rows_held_at_most: usize,
    /// Void samples filled (streamed; a map loaded whole says so as it
    /// loads).
    pub voids: u64,
    /// Most rows the void fill held at once: those from the top of the
    /// tallest void not yet filled (streamed).
    pub void_rows_held_at_most: usize,
    /// Most rows of a photo held at once (photos streamed).
    pub photo_rows_held_at_most: usize,
    /// Whether the input's rows were read as they were packed (else it
    /// was loaded whole first: a color map in another image format, or
    /// objects to stand on the map).
    pub streamed: bool,
    /// What stands on the map, in one line (as `render --objects`
    /// reports it), when objects were planted or placed.
    pub objects: Option<String>,
}

/// Packs `input` into `out`, calling `progress(rows done, rows)` now and
/// then.
///
/// `out` must not be one of the inputs (nor a link to one): that is
/// refused before anything is written. The heights are checked against the
/// kernel's range in a first pass, before the file is begun; the file is
/// written beside `out` and renamed into place when complete, so a pack
/// that fails (a truncated color map, say) leaves nothing behind.
pub fn pack(
    input: &PackInput,
    out: &Path,
    progress: &mut dyn FnMut(u32, u32),
) -> Result<PackSummary> {
    if !input.height_scale.is_finite() || input.height_scale <= 0.0 {
        return Err(Error::new(format!(
            "--height-scale must be a positive number, got {}",
            input.height_scale
        )));
    }
    let mut outputs = Outputs::new();
    outputs.input("--height", &input.height);
    for color in &input.colors {
        outputs.input("--color", color);
    }
    if let Some(path) = &input.place {
        outputs.input("--place", path);
        for view in ScenePlan::view_paths(path) {
            outputs.input("--place", &view);
        }
    }
    let out_id = outputs.output("--out", out)?;
    if input.objects || input.place.is_some() {
        let summary = pack_with_objects(input, outputs.temporary(out_id), progress)?;
        outputs.commit()?;
        return Ok(summary);
    }
    // Heights stream (PNG, GeoTIFF, `.hgt`, voids and all) alone, with
    // GeoTIFF photos placed by their georeference, or with one PNG or TIFF
    // color map stretched over the map as `render` stretches it; anything
    // else (several photos not placed, another image format) is loaded
    // whole, as `render` loads it.
    let placed = placements(&input.height, &input.colors)?;
    let stretched = match (&placed, input.colors.as_slice()) {
        (None, [one]) => is_tiff(one) || is_png(one),
        _ => false,
    };
    let streams = input.colors.is_empty() || placed.is_some() || stretched;
    let load_whole = || -> Result<Arc<Scene>> {
        let scene = load_scene_files(&input.height, &input.colors, input.height_scale, input.seed)?;
        Ok(Arc::new(scene))
    };
    let loaded = if streams { None } else { Some(load_whole()?) };
    let mut heights = match &loaded {
        Some(scene) => HeightRows::loaded(scene),
        None => HeightRows::open(&input.height, input.height_scale)?,
    };
    let (width, depth) = heights.size();
    // The whole range first: a height the kernel cannot hold is reported
    // before any tile is written, and colors by height need the range too.
    let bands = height_range(&input.height, &mut heights, depth)?;
    let (voids, void_rows_held_at_most) = heights.voids();
    if voids > 0 {
        report_filled(&input.height, voids, u64::from(width) * u64::from(depth));
    }
    heights.rewind()?;
    let world = world_of(width, depth)?;
    // (Streamed, the color maps are photos placed by their georeference,
    // or one map stretched over the whole.)
    let mut colors = match (&loaded, &placed, input.colors.first()) {
        (Some(scene), _, _) => Colors::Loaded(scene.clone()),
        (None, Some((grid_at, photos_at)), _) => {
            let mut photos = Vec::new();
            for (path, at) in input.colors.iter().zip(photos_at) {
                let window = PhotoWindow::open(path)?;
                let placed = PlacedPhoto::new(window.dimensions(), at, grid_at, (width, depth));
                // Photo tiles number the photos kept finer, in order.
                let kept = photos
                    .iter()
                    .filter(|p: &&StreamedPhoto| p.detail.is_some());
                let index = kept.count() as u8;
                let detail =
                    placed.map(|placed| (placed, FineLevels::new(index, &area_of(&placed))));
                photos.push(StreamedPhoto {
                    path: path.clone(),
                    window,
                    drape: Drape::new(grid_at, at),
                    detail,
                    covered: 0,
                    pixels_a_spacing: grid_at.pixel[0] / at.pixel[0],
                    rows_held_at_most: 0,
                });
            }
            Colors::Placed {
                by_height: ByHeight::new(bands, input.seed),
                photos,
            }
        }
        (None, None, Some(path)) => {
            let window = if is_tiff(path) {
                PhotoWindow::open(path)?
            } else {
                PhotoWindow::over(Box::new(ColorRows::open(path)?))
            };
            let size = window.dimensions();
            let photo = StretchedPhoto::new(size, (width, depth));
            let how = match photo {
                Some(photo) => {
                    let area =
                        DetailArea::new([0, 0], [width, depth], photo.shift, World::MAX_SIDE)
                            .expect(
                                "a photo detail's shift and size are within the kernel's limits",
                            );
                    Stretching::Detail(photo, FineLevels::new(0, &area))
                }
                None => Stretching::Colors(Stretch::new(size, path, (width, depth))?),
            };
            Colors::Stretched {
                window,
                how: Box::new(how),
            }
        }
        (None, None, None) => Colors::ByHeight(ByHeight::new(bands, input.seed)),
    };
    let header = Header::new(world, input.filter);
    // Photos finer than the grid keep their texels in photo tiles: a
    // scene loaded whole has them in memory, photos streamed cut them as
    // their rows pass.
    let photos = loaded
        .as_ref()
        .map_or_else(Vec::new, |scene| kernel_photos(scene));
    let areas: Vec<DetailArea> = match &colors {
        Colors::Placed { photos, .. } => photos
            .iter()
            .filter_map(|photo| photo.detail.as_ref().map(|(_, levels)| levels.area))
            .collect(),
        Colors::Stretched { how, .. } => match how.as_ref() {
            Stretching::Detail(_, levels) => vec![levels.area],
            Stretching::Colors(_) => Vec::new(),
        },
        _ => photos.iter().map(|(area, _)| *area).collect(),
    };
    if areas.len() as u64 > MAX_PHOTOS {
        return Err(Error::new(format!(
            "{} photos are finer than the height grid: a packed file holds at most {MAX_PHOTOS}",
            areas.len()
        )));
    }
    let mut writer = TilesWriter::create(outputs.temporary(out_id), header, areas)?;
    let mut photo_tiles = write_photos(&mut writer, &photos)?;
    drop(photos);
    let mut builder = Builder::new(world, input.filter, writer);
    let mut max_height = 0u16;
    // Measured on the rows a pyramid of the same map measures.
    let mut roughness = RoughnessSum::default();
    let mut held: Option<Vec<u16>> = None;
    for y in 0..depth {
        let row = heights.next()?;
        let quantized = row
            .iter()
            .enumerate()
            .map(|(x, &h)| {
                Terrain::quantize_height(h).ok_or_else(|| {
                    Error::new(format!(
                        "height {h} at grid point ({x}, {y}) is outside the kernel's range 0..={} voxels (adjust --height-scale)",
                        Terrain::MAX_HEIGHT
                    ))
                })
            })
            .collect::<Result<Vec<u16>>>()?;
        max_height = max_height.max(quantized.iter().copied().max().unwrap_or(0));
        roughness.add_row_at(y, &quantized);
        // Colors by height lag a row (they need the row after): the row
        // they color now is the one held back.
        let row_colors = colors.row(y, row)?;
        for (key, tile) in colors.photo_tiles() {
            builder.writer.write_photo(key, &tile)?;
            photo_tiles += 1;
        }
        match (row_colors, held.take()) {
            (Some(row_colors), Some(previous)) => {
                builder.push(0, y - 1, previous, row_colors)?;
                held = Some(quantized);
            }
            (Some(row_colors), None) => builder.push(0, y, quantized, row_colors)?,
            (None, _) => held = Some(quantized),
        }
        if y % 64 == 0 || y + 1 == depth {
            progress(y + 1, depth);
        }
    }
    if let (Some(last), Some(row_colors)) = (held.take(), colors.finish(depth)?) {
        builder.push(0, depth - 1, last, row_colors)?;
    }
    for (key, tile) in colors.photo_tiles() {
        builder.writer.write_photo(key, &tile)?;
        photo_tiles += 1;
    }
    let photo_rows_held_at_most = colors.photos_placed(&input.height, (width, depth))?;
    let rows_held_at_most = builder.rows_held_at_most;
    builder.finish(max_height, roughness.roughness())?;
    let bytes = std::fs::metadata(outputs.temporary(out_id)).map_or(0, |m| m.len());
    outputs.commit()?;
    Ok(PackSummary {
        width,
        depth,
        levels: header.levels,
        tiles: header.tiles,
        photo_tiles,
        bytes,
        rows_held_at_most,
        voids,
        void_rows_held_at_most,
        photo_rows_held_at_most,
        streamed: loaded.is_none(),
        objects: None,
    })
}

/// Packs `input`'s maps with objects standing on them into `out`: loaded
/// whole (the planting needs the whole map, and so do the coarser
/// levels' object heights), planted or placed as `render` stands them,
/// and cut into tiles from the kernel's pyramid
/// ([`terracast::Pyramid::build_with_sticks`]). Level 0's tiles name
/// their points' sticks and the file carries the stick table
/// ([`terracast::tiles::cut_stick_points`]). As in `render`, a photo
/// finer than the grid is kept at the grid's resolution under objects.
fn pack_with_objects(
    input: &PackInput,
    out: &Path,
    progress: &mut dyn FnMut(u32, u32),
) -> Result<PackSummary> {
    let mut scene = load_scene_files(&input.height, &input.colors, input.height_scale, input.seed)?;
    let plan = input.place.as_deref().map(ScenePlan::read).transpose()?;
    let planted = scene.add_objects(plan.as_ref(), input.objects.then_some(input.seed))?;
    let kernel = scene.to_kernel_with(input.filter)?;
    let pyramid = kernel.pyramid()?;
    let layer = kernel.sticks()?;
    let table = layer.map_or(StickTable::EMPTY, |layer| layer.table());
    if table.sticks().len() as u64 > MAX_STICKS {
        return Err(Error::new(format!(
            "{} distinct sticks stand on the map: a packed file holds at most {MAX_STICKS}",
            table.sticks().len()
        )));
    }
    let (width, depth) = (scene.width, scene.depth);
    let world = world_of(width, depth)?;
    let header = Header::new(world, input.filter);
    let mut writer = TilesWriter::create(out, header, Vec::new())?;
    let mut tile = Box::new(Tile::<TILE>::EMPTY);
    for level in 0..header.levels {
        let (columns, rows) = world.tiles(level, TILE as u32);
        for y in 0..rows {
            for x in 0..columns {
                let key = TileKey { level, x, y };
                cut_tile(&pyramid, key, &mut tile);
                if let Some(layer) = &layer {
                    cut_stick_points(layer, (width, depth), key, &mut tile);
                }
                writer.write(key, &tile)?;
            }
            if level == 0 {
                progress(((y + 1) * TILE as u32).min(depth), depth);
            }
        }
    }
    let max_height = terracast::Surface::extent(&pyramid).max_height;
    writer.finish(max_height, pyramid.roughness(), &table)?;
    Ok(PackSummary {
        width,
        depth,
        levels: header.levels,
        tiles: header.tiles,
        photo_tiles: 0,
        bytes: std::fs::metadata(out).map_or(0, |m| m.len()),
        rows_held_at_most: depth as usize,
        voids: 0,
        void_rows_held_at_most: 0,
        photo_rows_held_at_most: 0,
        streamed: false,
        objects: Some(planted),
    })
}

/// The world of a `width` × `depth` height map; a map too small to be
/// one is refused in one line.
fn world_of(width: u32, depth: u32) -> Result<World> {
    World::new(width, depth, 0).ok_or_else(|| {
        Error::new(format!(
            "height map is {width}x{depth}: it needs at least 2x2 points"
        ))
    })
}

/// The photos of `scene` kept finer than its grid, as the kernel holds
/// them: where each lies, and all its fine levels' texels.
fn kernel_photos(scene: &Scene) -> Vec<(DetailArea, Vec<Rgb>)> {
    scene
        .details
        .iter()
        .map(|detail| {
            let area = DetailArea::new(detail.origin, detail.size, detail.shift, World::MAX_SIDE)
                .expect("a photo detail's shift and size are within the kernel's limits");
            (area, detail.kernel_levels())
        })
        .collect()
}

/// Cuts every tile of every fine level of `photos` and writes it; returns
/// the tiles written.
fn write_photos(writer: &mut TilesWriter, photos: &[(DetailArea, Vec<Rgb>)]) -> Result<u64> {
    let mut tile = Box::new(PhotoTile::<TILE>::EMPTY);
    let mut written = 0;
    for (photo, (area, levels)) in photos.iter().enumerate() {
        let detail = Detail::new(area.origin(), area.size(), area.shift(), levels)
            .map_err(|e| Error::new(format!("photo {photo}: {e}")))?;
        for level in 0..=area.shift() {
            let (columns, rows) = photo_tiles(area, level, TILE as u32);
            for y in 0..rows {
                for x in 0..columns {
                    let key = PhotoKey {
                        photo: photo as u8,
                        level: level as u8,
                        x,
                        y,
                    };
                    if cut_photo_tile(&detail, key, &mut tile) {
                        writer.write_photo(key, &tile)?;
                        written += 1;
                    }
                }
            }
        }
    }
    Ok(written)
}

/// Whether `path` is a PNG (by its first bytes).
fn is_png(path: &Path) -> bool {
    let mut magic = [0u8; 8];
    File::open(path).is_ok_and(|mut f| f.read_exact(&mut magic).is_ok())
        && magic == *b"\x89PNG\r\n\x1a\n"
}

/// The lowest and highest height of the map (voids filled), refusing the
/// first one outside the kernel's range (with its grid point).
fn height_range(path: &Path, rows: &mut HeightRows, depth: u32) -> Result<HeightBands> {
    let mut bands = HeightBands::default();
    for y in 0..depth {
        for (x, &h) in rows.next()?.iter().enumerate() {
            if Terrain::quantize_height(h).is_none() {
                return Err(Error::new(format!(
                    "height map {}: height {h} at grid point ({x}, {y}) is outside the kernel's range 0..={} voxels (adjust --height-scale)",
                    path.display(),
                    Terrain::MAX_HEIGHT
                )));
            }
            bands.add(h);
        }
    }
    Ok(bands)
}

/// Height rows, scaled, top row first: streamed from a PNG, a GeoTIFF or
/// an `.hgt` through the void fill, or from a scene loaded whole.
enum HeightRows {
    Streamed {
        raw: Box<RawRows>,
        path: PathBuf,
        fill: Box<VoidFill>,
        /// Rows given to the fill, of `size`.
        pushed: u32,
        size: (u32, u32),
        row: Vec<f32>,
        scale: f32,
    },
    Loaded {
        scene: Arc<Scene>,
        /// The next row.
        y: usize,
    },
}

/// A height map's rows as the file holds them (NaN for no data).
enum RawRows {
    Tiff(Box<TiffHeightRows>),
    Png {
        reader: Box<png::Reader<BufReader<File>>>,
        wide: bool,
        channels: usize,
        row: Vec<f32>,
    },
    Hgt {
        file: BufReader<File>,
        bytes: Vec<u8>,
        row: Vec<f32>,
    },
}

impl RawRows {
    fn open(path: &Path) -> Result<(Self, (u32, u32))> {
        let fail = |e: &dyn std::fmt::Display| {
            Error::new(format!("cannot read height map {}: {e}", path.display()))
        };
        if is_tiff(path) {
            let rows = TiffHeightRows::open(path)?;
            let size = rows.size();
            return Ok((Self::Tiff(Box::new(rows)), size));
        }
        if is_hgt(path) {
            let file = File::open(path).map_err(|e| fail(&e))?;
            let length = file.metadata().map_err(|e| fail(&e))?.len();
            let side = hgt_side(path, length)?;
            let raw = Self::Hgt {
                file: BufReader::new(file),
                bytes: vec![0; 2 * side as usize],
                row: vec![0.0; side as usize],
            };
            return Ok((raw, (side, side)));
        }
        let file = File::open(path).map_err(|e| fail(&e))?;
        let file = require_png(file, path, "height map")?;
        let mut decoder = png::Decoder::new(BufReader::new(file));
        decoder.set_transformations(png::Transformations::IDENTITY);
        let reader = decoder.read_info().map_err(|e| fail(&e))?;
        let info = reader.info();
        let channels = match info.color_type {
            png::ColorType::Grayscale => 1,
            png::ColorType::GrayscaleAlpha => 2,
            other => return Err(not_a_height_map(path, &format!("{other:?}"))),
        };
        let wide = match info.bit_depth {
            png::BitDepth::Eight => false,
            png::BitDepth::Sixteen => true,
            other => return Err(not_a_height_map(path, &format!("{other:?}-bit"))),
        };
        let size = (info.width, info.height);
        let raw = Self::Png {
            reader: Box::new(reader),
            wide,
            channels,
            row: vec![0.0; size.0 as usize],
        };
        Ok((raw, size))
    }

    fn next(&mut self, path: &Path) -> Result<&[f32]> {
        let early = || Error::new(format!("height map {} ends early", path.display()));
        match self {
            Self::Tiff(rows) => rows.next_row(),
            Self::Png {
                reader,
                wide,
                channels,
                row,
            } => {
                let data = reader
                    .next_row()
                    .map_err(|e| Error::new(format!("height map {}: {e}", path.display())))?
                    .ok_or_else(early)?;
                let step = *channels * if *wide { 2 } else { 1 };
                for (v, px) in row.iter_mut().zip(data.data().chunks_exact(step)) {
                    *v = if *wide {
                        f32::from(u16::from_be_bytes([px[0], px[1]]))
                    } else {
                        f32::from(px[0])
                    };
                }
                Ok(row)
            }
            Self::Hgt { file, bytes, row } => {
                file.read_exact(bytes).map_err(|_| early())?;
                for (v, b) in row.iter_mut().zip(bytes.chunks_exact(2)) {
                    *v = hgt_height([b[0], b[1]]);
                }
                Ok(row)
            }
        }
    }
}

impl HeightRows {
    fn loaded(scene: &Arc<Scene>) -> Self {
        Self::Loaded {
            scene: scene.clone(),
            y: 0,
        }
    }

    fn open(path: &Path, scale: f32) -> Result<Self> {
        let (raw, size) = RawRows::open(path)?;
        Ok(Self::Streamed {
            raw: Box::new(raw),
            path: path.to_owned(),
            fill: Box::new(VoidFill::new(size.0 as usize)),
            pushed: 0,
            size,
            row: vec![0.0; size.0 as usize],
            scale,
        })
    }

    fn size(&self) -> (u32, u32) {
        match self {
            Self::Streamed { size, .. } => *size,
            Self::Loaded { scene, .. } => (scene.width, scene.depth),
        }
    }

    /// Void samples filled so far (those of the rows given out, and of
    /// the ones the fill holds), and the most rows the fill held at once.
    fn voids(&self) -> (u64, usize) {
        match self {
            Self::Streamed { fill, .. } => (fill.voids(), fill.rows_held_at_most()),
            Self::Loaded { .. } => (0, 0),
        }
    }

    /// Back to the first row.
    fn rewind(&mut self) -> Result<()> {
        match self {
            Self::Streamed { path, scale, .. } => *self = Self::open(&path.clone(), *scale)?,
            Self::Loaded { y, .. } => *y = 0,
        }
        Ok(())
    }

    fn next(&mut self) -> Result<&[f32]> {
        match self {
            Self::Streamed {
                raw,
                path,
                fill,
                pushed,
                size,
                row,
                scale,
            } => {
                // Voids are filled before the scale, as a map loaded whole.
                let filled = loop {
                    if let Some(filled) = fill.pop() {
                        break filled;
                    }
                    if *pushed == size.1 {
                        fill.finish();
                        break fill.pop().ok_or_else(|| {
                            Error::new(format!(
                                "height map {}: a void with no valid height around it",
                                path.display()
                            ))
                        })?;
                    }
                    fill.push(raw.next(path)?);
                    *pushed += 1;
                    refuse_mostly_void(path, fill.voids(), u64::from(size.0) * u64::from(size.1))?;
                };
                for (v, h) in row.iter_mut().zip(filled) {
                    *v = h * *scale;
                }
                Ok(row)
            }
            Self::Loaded { scene, y } => {
                let width = scene.width as usize;
                let row = scene
                    .heights
                    .get(*y * width..(*y + 1) * width)
                    .ok_or_else(|| Error::new("height rows read past the map's last"))?;
                *y += 1;
                Ok(row)
            }
        }
    }
}

/// Whether `path` names an SRTM `.hgt` tile.
fn is_hgt(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("hgt"))
}

/// `file`, rewound, when it starts with PNG's signature; otherwise an
/// error that says what it is instead.
fn require_png(mut file: File, path: &Path, what: &str) -> Result<File> {
    use std::io::{Seek, SeekFrom};
    let mut magic = [0u8; 8];
    let read = file.read(&mut magic).unwrap_or(0);
    if read == 8 && magic == *b"\x89PNG\r\n\x1a\n" {
        file.seek(SeekFrom::Start(0))
            .map_err(|e| Error::new(format!("cannot read {what} {}: {e}", path.display())))?;
        return Ok(file);
    }
    let is_tiff = magic.starts_with(b"II*\0") || magic.starts_with(b"MM\0*");
    Err(Error::new(format!(
        "{what} {} is {}: pack reads PNG, SRTM .hgt (heights) and GeoTIFF (.tif) maps",
        path.display(),
        if is_tiff {
            "a TIFF without a .tif name"
        } else {
            "not a PNG file"
        }
    )))
}

/// Color rows of a PNG, expanded to RGB.
struct ColorRows {
    reader: png::Reader<BufReader<File>>,
    path: PathBuf,
    size: (u32, u32),
    channels: usize,
}

impl ColorRows {
    fn open(path: &Path) -> Result<Self> {
        let fail = |e: &dyn std::fmt::Display| {
            Error::new(format!("cannot read color map {}: {e}", path.display()))
        };
        let file = File::open(path).map_err(|e| fail(&e))?;
        let file = require_png(file, path, "color map")?;
        let mut decoder = png::Decoder::new(BufReader::new(file));
        decoder.set_transformations(png::Transformations::EXPAND);
        let reader = decoder.read_info().map_err(|e| fail(&e))?;
        let (color, depth) = reader.output_color_type();
        if depth != png::BitDepth::Eight {
            return Err(Error::new(format!(
                "{}: pack reads 8-bit color PNGs",
                path.display()
            )));
        }
        let size = (reader.info().width, reader.info().height);
        Ok(Self {
            reader,
            path: path.to_owned(),
            size,
            channels: color.samples(),
        })
    }

    fn next(&mut self) -> Result<Vec<Rgb>> {
        let channels = self.channels;
        let row = self
            .reader
            .next_row()
            .map_err(|e| Error::new(format!("color map {}: {e}", self.path.display())))?
            .ok_or_else(|| Error::new(format!("color map {} ends early", self.path.display())))?;
        Ok(row
            .data()
            .chunks_exact(channels)
            .map(|p| {
                if channels >= 3 {
                    [p[0], p[1], p[2]]
                } else {
                    [p[0]; 3]
                }
            })
            .collect())
    }
}

impl PhotoRowSource for ColorRows {
    fn size(&self) -> (u32, u32) {
        self.size
    }
    fn read_row(&mut self) -> Result<Vec<Rgb>> {
        self.next()
    }
}

/// Where each row's colors come from.
enum Colors {
    /// One color map stretched over the map as `render` stretches it, a
    /// window of its rows at a time.
    Stretched {
        window: PhotoWindow,
        how: Box<Stretching>,
    },
    /// The colors of a scene loaded whole.
    Loaded(Arc<Scene>),
    /// Colored by height and slope, as `render` colors a height map alone.
    ByHeight(ByHeight),
    /// Colored by height and slope, and the photos draped over that as
    /// `render` places them, a row at a time.
    Placed {
        by_height: ByHeight,
        photos: Vec<StreamedPhoto>,
    },
}

/// How a color map is stretched over the map: kept finer than the grid
/// (its texels into photo tiles, the grid's colors their means), or
/// filtered to the grid.
enum Stretching {
    Detail(StretchedPhoto, FineLevels),
    Colors(Stretch),
}

/// Colored by height and slope, as `render` colors a height map alone:
/// a row is colored when the row after it has arrived.
struct ByHeight {
    range: HeightBands,
    /// The last three height rows (rows y − 2 to y).
    window: Vec<Vec<f32>>,
    seed: u64,
}

impl ByHeight {
    fn new(range: HeightBands, seed: u64) -> Self {
        Self {
            range,
            window: Vec::new(),
            seed,
        }
    }

    /// Row `y − 1`'s colors, now that row `y` has arrived (`None` for the
    /// first row).
    fn row(&mut self, y: u32, heights: &[f32]) -> Option<Vec<Rgb>> {
        self.window.push(heights.to_vec());
        if self.window.len() > 3 {
            self.window.remove(0);
        }
        if y == 0 {
            return None;
        }
        // Rows y − 2 (if any), y − 1 and y: color row y − 1.
        let n = self.window.len();
        let (here, below) = (&self.window[n - 2], &self.window[n - 1]);
        let above = if n >= 3 { &self.window[n - 3] } else { here };
        Some(color_row(
            y - 1,
            [above, here, below],
            self.range,
            self.seed,
        ))
    }

    /// The last row's colors, once every row has arrived.
    fn finish(&mut self, depth: u32) -> Option<Vec<Rgb>> {
        let n = self.window.len();
        let here = self.window.last()?;
        let above = if n >= 2 { &self.window[n - 2] } else { here };
        Some(color_row(
            depth - 1,
            [above, here, here],
            self.range,
            self.seed,
        ))
    }
}

impl Colors {
    /// The colors of a row ready now: row `y`'s from a map, or row
    /// `y − 1`'s by height (`None` for the first row).
    fn row(&mut self, y: u32, heights: &[f32]) -> Result<Option<Vec<Rgb>>> {
        match self {
            Self::Stretched { window, how } => match how.as_mut() {
                Stretching::Detail(photo, levels) => {
                    let (low, high) = photo.photo_rows(y);
                    window.hold(low, high)?;
                    let texels = photo.texel_rows(y, window);
                    // `2^shift` rows of texels, `2^shift` a grid point.
                    let row = texels.len() >> photo.shift;
                    for texel_row in texels.chunks_exact(row) {
                        levels.push(0, texel_row.to_vec());
                    }
                    let points = (row >> photo.shift) as u32;
                    Ok(Some(block_means(&texels, photo.shift, points)))
                }
                Stretching::Colors(stretch) => {
                    let (low, high) = stretch.image_rows(y);
                    window.hold(low, high)?;
                    Ok(Some(stretch.row(y, window)))
                }
            },
            Self::Loaded(scene) => {
                let width = scene.width as usize;
                let at = y as usize * width;
                let row = scene
                    .colors
                    .get(at..at + width)
                    .ok_or_else(|| Error::new("color rows read past the map's last"))?;
                Ok(Some(row.to_vec()))
            }
            Self::ByHeight(by_height) => Ok(by_height.row(y, heights)),
            Self::Placed { by_height, photos } => match by_height.row(y, heights) {
                Some(mut colors) => {
                    for photo in photos.iter_mut() {
                        photo.drape(y - 1, &mut colors)?;
                    }
                    Ok(Some(colors))
                }
                None => Ok(None),
            },
        }
    }

    /// The last row's colors (by height, and the photos over them), once
    /// every row has arrived.
    fn finish(&mut self, depth: u32) -> Result<Option<Vec<Rgb>>> {
        match self {
            Self::Stretched { how, .. } => {
                if let Stretching::Detail(_, levels) = how.as_mut() {
                    levels.finish();
                }
                Ok(None)
            }
            Self::Loaded(_) => Ok(None),
            Self::ByHeight(by_height) => Ok(by_height.finish(depth)),
            Self::Placed { by_height, photos } => {
                let Some(mut colors) = by_height.finish(depth) else {
                    return Ok(None);
                };
                for photo in photos.iter_mut() {
                    photo.drape(depth - 1, &mut colors)?;
                    photo.finish();
                }
                Ok(Some(colors))
            }
        }
    }

    /// After the last row: refuses a photo streamed over none of the
    /// terrain, says on one line how much each covers (as `render` does),
    /// and returns the most photo rows held at once.
    fn photos_placed(&self, height: &Path, (width, depth): (u32, u32)) -> Result<usize> {
        let Self::Placed { photos, .. } = self else {
            return Ok(0);
        };
        for photo in photos {
            if photo.covered == 0 {
                return Err(Error::new(format!(
                    "photo {} does not overlap height map {}",
                    photo.path.display(),
                    height.display()
                )));
            }
            eprintln!(
                "{}: covers {:.1} % of the terrain, {:.1} photo pixels a grid spacing",
                photo.path.display(),
                100.0 * photo.covered as f64 / (f64::from(width) * f64::from(depth)),
                photo.pixels_a_spacing
            );
        }
        Ok(photos
            .iter()
            .map(|p| p.rows_held_at_most)
            .max()
            .unwrap_or(0))
    }

    /// Photo tiles complete so far, to be written.
    fn photo_tiles(&mut self) -> Vec<(PhotoKey, Box<PhotoTile<TILE>>)> {
        match self {
            Self::Stretched { how, .. } => match how.as_mut() {
                Stretching::Detail(_, levels) => std::mem::take(&mut levels.done),
                Stretching::Colors(_) => Vec::new(),
            },
            Self::Placed { photos, .. } => photos
                .iter_mut()
                .filter_map(|photo| photo.detail.as_mut())
                .flat_map(|(_, levels)| std::mem::take(&mut levels.done))
                .collect(),
            _ => Vec::new(),
        }
    }
}

/// A GeoTIFF photo streamed over the grid's rows as they are colored:
/// draped as `render` drapes it, and where it is finer than the grid kept
/// at its own resolution, its fine levels cut into photo tiles as their
/// rows complete.
struct StreamedPhoto {
    path: PathBuf,
    window: PhotoWindow,
    drape: Drape,
    /// Where it is kept finer than the grid, and its fine levels.
    detail: Option<(PlacedPhoto, FineLevels)>,
    /// Grid points it covers.
    covered: u64,
    /// Its pixels a grid spacing (east-west).
    pixels_a_spacing: f64,
    /// Most photo rows held at once.
    rows_held_at_most: usize,
}

/// The kernel's place of a photo kept finer than the grid.
fn area_of(placed: &PlacedPhoto) -> DetailArea {
    DetailArea::new(placed.origin, placed.size, placed.shift, World::MAX_SIDE)
        .expect("a photo detail's shift and size are within the kernel's limits")
}

impl StreamedPhoto {
    /// Drapes the photo over grid row `gy` (`colors`), and keeps its
    /// texels there.
    fn drape(&mut self, gy: u32, colors: &mut [Rgb]) -> Result<()> {
        let (mut low, mut high) = self.drape.rows(gy);
        let detail = self
            .detail
            .as_mut()
            .filter(|(placed, _)| placed.covers_row(gy));
        if let Some((placed, _)) = &detail {
            let (a, b) = placed.photo_rows(gy);
            (low, high) = (low.min(a), high.max(b));
        }
        self.window.hold(low, high)?;
        self.rows_held_at_most = self.rows_held_at_most.max(self.window.rows_held());
        self.covered += self.drape.row(colors, gy, &self.window) as u64;
        if let Some((placed, levels)) = detail {
            // The grid's colors there are the mean of each point's texels.
            let texels = placed.texel_rows(gy, colors, &self.window);
            let means = block_means(&texels, placed.shift, placed.size[0]);
            colors[placed.origin[0] as usize..][..means.len()].copy_from_slice(&means);
            for row in texels.chunks_exact((placed.size[0] << placed.shift) as usize) {
                levels.push(0, row.to_vec());
            }
        }
        Ok(())
    }

    fn finish(&mut self) {
        if let Some((_, levels)) = &mut self.detail {
            levels.finish();
        }
    }
}

/// A photo's fine levels built as fine level 0's rows arrive (each row of
/// a level the rounded mean of two of the one below, as
/// [`terracast::Detail::build_levels`]), and cut into photo tiles a strip
/// of `TILE` rows at a time (as [`terracast::tiles::cut_photo_tile`]).
struct FineLevels {
    photo: u8,
    /// Where the photo lies.
    area: DetailArea,
    /// Each level's texels a row and rows, its strip's rows so far, its
    /// next strip, and a row waiting for the next to make a coarser one.
    levels: Vec<FineLevel>,
    /// Tiles cut, not written yet.
    done: Vec<(PhotoKey, Box<PhotoTile<TILE>>)>,
}

struct FineLevel {
    size: (usize, usize),
    rows: Vec<Vec<Rgb>>,
    received: usize,
    strip: u32,
    waiting: Option<Vec<Rgb>>,
}

impl FineLevels {
    fn new(photo: u8, area: &DetailArea) -> Self {
        Self {
            photo,
            area: *area,
            levels: (0..=area.shift())
                .map(|level| FineLevel {
                    size: area.level_size(level),
                    rows: Vec::new(),
                    received: 0,
                    strip: 0,
                    waiting: None,
                })
                .collect(),
            done: Vec::new(),
        }
    }

    fn push(&mut self, level: usize, row: Vec<Rgb>) {
        let coarser = level + 1 < self.levels.len();
        let l = &mut self.levels[level];
        l.received += 1;
        let pair = if coarser {
            match l.waiting.take() {
                Some(first) => Some(
                    (0..row.len() / 2)
                        .map(|x| {
                            let quad = [first[2 * x], first[2 * x + 1], row[2 * x], row[2 * x + 1]];
                            core::array::from_fn(|c| {
                                let sum: u32 = quad.iter().map(|t| u32::from(t[c])).sum();
                                ((sum + 2) / 4) as u8
                            })
                        })
                        .collect::<Vec<Rgb>>(),
                ),
                None => {
                    l.waiting = Some(row.clone());
                    None
                }
            }
        } else {
            None
        };
        l.rows.push(row);
        if l.rows.len() == TILE || l.received == l.size.1 {
            self.cut_strip(level);
        }
        if let Some(pair) = pair {
            self.push(level + 1, pair);
        }
    }

    /// Cuts level `level`'s strip into tiles.
    fn cut_strip(&mut self, level: usize) {
        let l = &mut self.levels[level];
        let (width, rows) = (l.size.0, std::mem::take(&mut l.rows));
        for x in 0..width.div_ceil(TILE) {
            let mut tile = Box::new(PhotoTile::<TILE>::EMPTY);
            for (j, line) in tile.texels.iter_mut().enumerate() {
                let row = &rows[j.min(rows.len() - 1)];
                for (i, texel) in line.iter_mut().enumerate() {
                    *texel = row[(x * TILE + i).min(width - 1)];
                }
            }
            let key = PhotoKey {
                photo: self.photo,
                level: level as u8,
                x: x as u32,
                y: l.strip,
            };
            self.done.push((key, tile));
        }
        l.strip += 1;
    }

    /// Cuts what is left (every level's strips end with its last row).
    fn finish(&mut self) {
        for level in 0..self.levels.len() {
            if !self.levels[level].rows.is_empty() {
                self.cut_strip(level);
            }
        }
    }
}

/// Colors of row `y` from rows `y − 1`, `y`, `y + 1` (edges repeated), as
/// [`crate::scene::color_by_height_and_slope`] colors them.
fn color_row(
    y: u32,
    [above, here, below]: [&Vec<f32>; 3],
    range: HeightBands,
    seed: u64,
) -> Vec<Rgb> {
    let w = here.len();
    (0..w)
        .map(|x| {
            let at = |row: &Vec<f32>, x: usize| f64::from(row[x.min(w - 1)]);
            let gx = (at(here, x + 1) - at(here, x.saturating_sub(1))) * 0.5;
            let gy = (at(below, x) - at(above, x)) * 0.5;
            let grain = value_noise(x as f64 * 0.5, f64::from(y) * 0.5, seed ^ 0xabc) - 0.5;
            terrain_color(
                [x as f64, f64::from(y)],
                at(here, x),
                [gx, gy],
                range,
                grain,
                seed,
            )
        })
        .collect()
}

/// Tent weights of the 3 × 3 finer points around a coarse point (sum 16),
/// as the kernel's pyramid.
const TENT: [[u32; 3]; 3] = [[1, 2, 1], [2, 4, 2], [1, 2, 1]];

/// One level as it streams: its recent rows and bound rows.
struct Level {
    level: u8,
    width: u32,
    depth: u32,
    points: BTreeMap<u32, (Vec<u16>, Vec<Rgb>)>,
    bounds: BTreeMap<u32, Vec<u16>>,
    /// Point rows received, bound rows made, coarse rows made from this
    /// level, tile strips written.
    received: u32,
    bounded: u32,
    coarsened: u32,
    strips: u32,
}

struct Builder {
    levels: Vec<Level>,
    filter: HeightFilter,
    writer: TilesWriter,
    tile: Box<Tile<TILE>>,
    rows_held_at_most: usize,
}

impl Builder {
    fn new(world: World, filter: HeightFilter, writer: TilesWriter) -> Self {
        let levels = (0..world.levels())
            .map(|level| {
                let (width, depth) = world.level_size(level);
                Level {
                    level,
                    width,
                    depth,
                    points: BTreeMap::new(),
                    bounds: BTreeMap::new(),
                    received: 0,
                    bounded: 0,
                    coarsened: 0,
                    strips: 0,
                }
            })
            .collect();
        Self {
            levels,
            filter,
            writer,
            tile: Box::new(Tile::EMPTY),
            rows_held_at_most: 0,
        }
    }

    /// Row `y` of `level` has arrived.
    fn push(&mut self, level: usize, y: u32, heights: Vec<u16>, colors: Vec<Rgb>) -> Result<()> {
        {
            let l = &mut self.levels[level];
            l.points.insert(y, (heights, colors));
            l.received = y + 1;
        }
        if level >= 1 {
            while self.levels[level].bounded + 1 < self.levels[level].received {
                let j = self.levels[level].bounded;
                let row = self.bound_row(level, j);
                let l = &mut self.levels[level];
                l.bounds.insert(j, row);
                l.bounded += 1;
            }
        }
        self.write_ready_strips(level)?;
        if level + 1 < self.levels.len() {
            loop {
                let (fine, coarse) = (&self.levels[level], &self.levels[level + 1]);
                let y = fine.coarsened;
                if y >= coarse.depth {
                    break;
                }
                let needs = (2 * y + 2).min(fine.depth - 1);
                if needs >= fine.received {
                    break;
                }
                let (h, c) = self.coarse_row(level, y);
                self.levels[level].coarsened += 1;
                self.push(level + 1, y, h, c)?;
            }
        }
        self.forget(level);
        let held = self
            .levels
            .iter()
            .map(|l| l.points.len() + l.bounds.len())
            .sum();
        self.rows_held_at_most = self.rows_held_at_most.max(held);
        Ok(())
    }

    /// Coarse row `y` of level `level + 1`, from level `level`: as the
    /// kernel's `Pyramid::build`.
    fn coarse_row(&self, level: usize, y: u32) -> (Vec<u16>, Vec<Rgb>) {
        let fine = &self.levels[level];
        let width = self.levels[level + 1].width;
        // Finer rows 2y − 2 to 2y + 2 (the wavelet's); the tents use the
        // middle three.
        let rows: [&(Vec<u16>, Vec<Rgb>); 5] = core::array::from_fn(|dy| {
            let r = (2 * i64::from(y) + dy as i64 - 2).clamp(0, i64::from(fine.depth) - 1);
            &fine.points[&(r as u32)]
        });
        let column =
            |x: u32, dx: i64| (2 * i64::from(x) + dx).clamp(0, i64::from(fine.width) - 1) as usize;
        let mut wavelet = Vec::new();
        if self.filter == HeightFilter::Wavelet {
            wavelet = vec![0; width as usize];
            wavelet_row(
                rows.map(|r| r.0.as_slice()),
                fine.width as usize,
                &mut wavelet,
            );
        }
        let mut heights = Vec::with_capacity(width as usize);
        let mut colors = Vec::with_capacity(width as usize);
        for x in 0..width {
            let (mut h_sum, mut h_max) = (0u32, 0u16);
            let mut c_sum = [0u32; 3];
            for (row, weights) in rows[1..4].iter().zip(TENT) {
                for (dx, w) in weights.into_iter().enumerate() {
                    let fx = column(x, dx as i64 - 1);
                    let (h, c) = (row.0[fx], row.1[fx]);
                    h_sum += w * u32::from(h);
                    h_max = h_max.max(h);
                    for (s, v) in c_sum.iter_mut().zip(c) {
                        *s += w * u32::from(v);
                    }
                }
            }
            let center = (2 * x).min(fine.width - 1) as usize;
            heights.push(match self.filter {
                HeightFilter::Subsample => rows[2].0[center],
                HeightFilter::Mean => ((h_sum + 8) >> 4) as u16,
                HeightFilter::Max => h_max,
                HeightFilter::Wavelet => wavelet[x as usize],
            });
            colors.push(c_sum.map(|s| ((s + 8) >> 4) as u8));
        }
        (heights, colors)
    }

    /// Bound row `j` of `level` (≥ 1): as the kernel's `build_bounds`.
    fn bound_row(&self, level: usize, j: u32) -> Vec<u16> {
        let here = &self.levels[level];
        let child = &self.levels[level - 1];
        let cells = here.width - 1;
        let (row0, row1) = (&here.points[&j].0, &here.points[&(j + 1)].0);
        (0..cells)
            .map(|i| {
                let (i0, i1) = (i as usize, i as usize + 1);
                let mut b = row0[i0].max(row0[i1]).max(row1[i0]).max(row1[i1]);
                if level == 1 {
                    for y in 2 * j..=(2 * j + 2).min(child.depth - 1) {
                        let row = &child.points[&y].0;
                        for x in 2 * i..=(2 * i + 2).min(child.width - 1) {
                            b = b.max(row[x as usize]);
                        }
                    }
                } else {
                    let (ccw, ccd) = (child.width - 1, child.depth - 1);
                    for y in 2 * j..(2 * j + 2).min(ccd) {
                        let row = &child.bounds[&y];
                        for x in 2 * i..(2 * i + 2).min(ccw) {
                            b = b.max(row[x as usize]);
                        }
                    }
                }
                b
            })
            .collect()
    }

    /// Writes every strip of tiles of `level` whose rows (and bounds) are
    /// all known.
    fn write_ready_strips(&mut self, level: usize) -> Result<()> {
        loop {
            let l = &self.levels[level];
            let first = l.strips * TILE as u32;
            if first >= l.depth {
                return Ok(());
            }
            let last_point = (first + TILE as u32 - 1).min(l.depth - 1);
            let last_bound = (first + TILE as u32 - 1).min(l.depth - 2);
            let points_ready = last_point < l.received;
            let bounds_ready = level == 0 || last_bound < l.bounded;
            if !(points_ready && bounds_ready) {
                return Ok(());
            }
            let strip = l.strips;
            let tiles_x = l.width.div_ceil(TILE as u32);
            for tx in 0..tiles_x {
                self.fill_tile(level, tx, strip);
                let key = TileKey {
                    level: level as u8,
                    x: tx,
                    y: strip,
                };
                self.writer.write(key, &self.tile)?;
            }
            self.levels[level].strips += 1;
        }
    }

    fn fill_tile(&mut self, level: usize, tx: u32, ty: u32) {
        let l = &self.levels[level];
        let tile = &mut self.tile;
        for j in 0..TILE {
            let y = (ty as usize * TILE + j).min(l.depth as usize - 1) as u32;
            let by = (ty as usize * TILE + j).min(l.depth as usize - 2) as u32;
            let (heights, colors) = &l.points[&y];
            let bounds = l.bounds.get(&by);
            for i in 0..TILE {
                let x = (tx as usize * TILE + i).min(l.width as usize - 1);
                let bx = (tx as usize * TILE + i).min(l.width as usize - 2);
                tile.heights[j][i] = heights[x];
                tile.colors[j][i] = colors[x];
                tile.bounds[j][i] = if level == 0 {
                    0
                } else {
                    bounds.map_or(0, |b| b[bx])
                };
            }
        }
    }

    /// Drops the rows of `level` nothing will read again.
    fn forget(&mut self, level: usize) {
        let coarser = self.levels.get(level + 1).map(|c| c.bounded);
        let l = &mut self.levels[level];
        // Rows still read: the strip being gathered, the coarse filter
        // (2y − 2 up), this level's next bound row (levels 1 and up), and
        // the next level's bounds (level 0's points, other levels' bounds:
        // 2j up).
        let mut keep = l.strips * TILE as u32;
        if let Some(child_bounded) = coarser {
            keep = keep
                .min((2 * l.coarsened).saturating_sub(2))
                .min(child_bounded.saturating_mul(2));
        }
        if level > 0 {
            keep = keep.min(l.bounded);
        }
        let keep = keep.saturating_sub(2);
        l.points = l.points.split_off(&keep);
        l.bounds = l.bounds.split_off(&keep);
    }

    fn finish(self, max_height: u16, roughness: u8) -> Result<()> {
        for level in &self.levels {
            if level.strips * (TILE as u32) < level.depth {
                return Err(Error::new(format!(
                    "pack: level {} incomplete ({} of {} rows)",
                    level.level, level.received, level.depth
                )));
            }
        }
        self.writer
            .finish(max_height, roughness, &StickTable::EMPTY)
    }
}
