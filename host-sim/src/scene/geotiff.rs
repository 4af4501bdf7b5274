//! GeoTIFF rasters (the `tiff` crate): heights in any integer or float
//! sample format with their no-data value (the GDAL_NODATA tag; for int16
//! without it, SRTM's −32768), photos in 8-bit gray, RGB or RGBA, and the
//! georeference of either (ModelPixelScale with ModelTiepoint, or an
//! unrotated ModelTransformation; geographic or projected by the
//! GeoKeyDirectory's model type).

use crate::error::{Error, Result};
use image::RgbImage;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;
use terracast::Rgb;
use tiff::decoder::{Decoder, DecodingResult};
use tiff::tags::Tag;
use tiff::ColorType;

/// Where a raster lies: the model coordinates of its top-left corner and
/// the size of a pixel (x east, y south, both positive).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoRef {
    /// Model x and y of the top-left pixel's outer corner.
    pub origin: [f64; 2],
    /// Pixel width and height in model units.
    pub pixel: [f64; 2],
    /// Longitude and latitude in degrees (EPSG:4326 and the like), rather
    /// than a projection's linear units.
    pub geographic: bool,
    /// Meters a linear unit of a projected raster (1, or a foot's).
    pub meters_per_unit: f64,
}

/// Meters along a degree of latitude (and of longitude at the equator).
const METERS_PER_DEGREE: f64 = 111_132.0;

impl GeoRef {
    /// Where pixel position `[x, y]` of this raster (fractional, pixel
    /// centers at whole numbers) falls among `other`'s pixels, in the same
    /// terms: model x runs east, model y north, rows south.
    pub fn pixel_in(&self, other: &GeoRef, [x, y]: [f64; 2]) -> [f64; 2] {
        [
            (self.origin[0] + (x + 0.5) * self.pixel[0] - other.origin[0]) / other.pixel[0] - 0.5,
            (other.origin[1] - self.origin[1] + (y + 0.5) * self.pixel[1]) / other.pixel[1] - 0.5,
        ]
    }

    /// Meters between samples east-west and north-south; a geographic
    /// raster's east-west spacing is taken at its middle latitude.
    pub fn spacing_m(&self, height: u32) -> (f64, f64) {
        if self.geographic {
            let middle = self.origin[1] - self.pixel[1] * f64::from(height) / 2.0;
            let east = self.pixel[0] * METERS_PER_DEGREE * middle.to_radians().cos();
            (east, self.pixel[1] * METERS_PER_DEGREE)
        } else {
            (
                self.pixel[0] * self.meters_per_unit,
                self.pixel[1] * self.meters_per_unit,
            )
        }
    }

    /// The height scale that puts heights in meters into voxels of the
    /// grid's spacing (the mean of the two directions), and one line
    /// saying so.
    pub fn height_scale(&self, height: u32) -> (f32, String) {
        let (east, north) = self.spacing_m(height);
        let voxel = (east + north) / 2.0;
        let how = if self.geographic {
            let middle = self.origin[1] - self.pixel[1] * f64::from(height) / 2.0;
            format!(
                "{:.6}° samples at latitude {middle:.2} are {east:.1} m east-west and {north:.1} m north-south",
                self.pixel[1]
            )
        } else {
            format!("samples are {east:.2} m east-west and {north:.2} m north-south")
        };
        (
            (1.0 / voxel) as f32,
            format!("height scale 1/{voxel:.2}: {how}; --height-scale overrides"),
        )
    }
}

fn open(path: &Path, what: &str) -> Result<Decoder<BufReader<File>>> {
    let mut file = File::open(path)
        .map_err(|e| Error::new(format!("cannot open {what} {}: {e}", path.display())))?;
    let length = file.metadata().map(|m| m.len()).unwrap_or(0);
    check_first_directory(&mut file, length)
        .and_then(|()| file.seek(SeekFrom::Start(0)).map(|_| ()))
        .map_err(|e| Error::new(format!("cannot read {what} {}: {e}", path.display())))?;
    let decoder = Decoder::new(BufReader::new(file))
        .map_err(|e| Error::new(format!("cannot read {what} {}: {e}", path.display())))?;
    // A tile is decoded whole, padding and all, before its samples are
    // cut out: one far larger than the file can hold (a damaged tile
    // size) is refused before it is allocated. Real tiles (GDAL's 256 or
    // 512 a side) are far below this.
    if decoder.get_chunk_type() == tiff::decoder::ChunkType::Tile {
        let (width, height) = decoder.chunk_dimensions();
        let bytes = u64::from(width) * u64::from(height) * 8;
        // (The decoder divides by a tile's sides.)
        if bytes == 0 || bytes > 16 * length + (16 << 20) {
            return Err(failed(
                path,
                what,
                format!("{width} x {height} tiles in a {length}-byte file"),
            ));
        }
    }
    Ok(decoder)
}

/// Refuses a TIFF (`length` bytes) whose first directory declares more
/// values for a tag than the file holds. The decoder makes room for a
/// tag's values, a few dozen bytes each, before it reads them: a damaged
/// count would have it allocate many times the file. A file too short or
/// not a TIFF is left to the decoder to name.
fn check_first_directory(file: &mut File, length: u64) -> std::io::Result<()> {
    // Whether `buffer` was filled: a file that ends first is the
    // decoder's to name.
    let fill = |file: &mut File, buffer: &mut [u8]| match file.read_exact(buffer) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => Ok(false),
        Err(e) => Err(e),
    };
    let mut header = [0u8; 16];
    if !fill(file, &mut header[..8])? {
        return Ok(());
    }
    let little = &header[..2] == b"II";
    let number = |bytes: &[u8]| {
        // Up to 8 bytes in the file's byte order.
        let mut value = 0u64;
        for i in 0..bytes.len() {
            let byte = if little {
                bytes[bytes.len() - 1 - i]
            } else {
                bytes[i]
            };
            value = (value << 8) | u64::from(byte);
        }
        value
    };
    // Classic TIFF: a 2-byte entry count and 12-byte entries with 4-byte
    // value counts; BigTIFF: 8, 20 and 8.
    let (big, directory) = match number(&header[2..4]) {
        42 => (false, number(&header[4..8])),
        43 if fill(file, &mut header[8..16])? => (true, number(&header[8..16])),
        _ => return Ok(()),
    };
    let (count_bytes, entry_bytes, values_bytes) = if big { (8, 20, 8) } else { (2, 12, 4) };
    let mut count = [0u8; 8];
    file.seek(SeekFrom::Start(directory))?;
    if !fill(file, &mut count[..count_bytes])? {
        return Ok(());
    }
    let mut entry = [0u8; 20];
    for _ in 0..number(&count[..count_bytes]).min(length / entry_bytes as u64) {
        if !fill(file, &mut entry[..entry_bytes])? {
            return Ok(());
        }
        let size: u64 = match number(&entry[2..4]) {
            1 | 2 | 6 | 7 => 1,
            3 | 8 => 2,
            4 | 9 | 11 | 13 => 4,
            _ => 8,
        };
        let values = number(&entry[4..4 + values_bytes]);
        // At least two bytes a value: the decoder's room for them stays
        // within 16 times the file.
        if values.saturating_mul(size.max(2)) > length {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "tag {} declares {values} values, more than the file holds",
                    number(&entry[..2])
                ),
            ));
        }
    }
    Ok(())
}

fn failed(path: &Path, what: &str, e: impl std::fmt::Display) -> Error {
    Error::new(format!("cannot decode {what} {}: {e}", path.display()))
}

/// The raster's georeference, or `None` (with what is missing) when it has
/// none or only a rotated one.
fn georef(decoder: &mut Decoder<BufReader<File>>) -> std::result::Result<GeoRef, &'static str> {
    let doubles = |decoder: &mut Decoder<BufReader<File>>, tag| {
        decoder
            .find_tag(tag)
            .ok()
            .flatten()
            .and_then(|v| v.into_f64_vec().ok())
    };
    let scale = doubles(decoder, Tag::ModelPixelScaleTag);
    let tiepoint = doubles(decoder, Tag::ModelTiepointTag);
    let transformation = doubles(decoder, Tag::ModelTransformationTag);
    let (origin, pixel) = match (scale, tiepoint, transformation) {
        (Some(s), Some(t), _) if s.len() >= 2 && t.len() >= 6 => {
            ([t[3] - t[0] * s[0], t[4] + t[1] * s[1]], [s[0], s[1]])
        }
        (_, _, Some(m)) if m.len() >= 16 => {
            if m[1] != 0.0 || m[4] != 0.0 {
                return Err("its ModelTransformation rotates it");
            }
            ([m[3], m[7]], [m[0], -m[5]])
        }
        _ => return Err("it has no ModelPixelScale and ModelTiepoint"),
    };
    let positive = pixel[0] > 0.0 && pixel[1] > 0.0;
    if !(positive && origin.iter().all(|v| v.is_finite())) {
        return Err("its pixel scale is not positive");
    }
    // GeoKeyDirectory: a header of four shorts, then keys of four
    // (id, location, count, value). 1024 is the model type (1 projected,
    // 2 geographic), 3076 the projection's linear unit (EPSG unit codes).
    let keys = decoder
        .find_tag(Tag::GeoKeyDirectoryTag)
        .ok()
        .flatten()
        .and_then(|v| v.into_u16_vec().ok())
        .unwrap_or_default();
    let key = |id: u16| {
        keys.get(4..)
            .unwrap_or(&[])
            .chunks_exact(4)
            .find(|k| k[0] == id && k[1] == 0)
            .map(|k| k[3])
    };
    let geographic = match key(1024) {
        Some(model) => model == 2,
        // No keys: degrees if it looks like degrees.
        None => origin[0].abs() <= 180.0 && origin[1].abs() <= 90.0 && pixel[0] < 0.1,
    };
    let meters_per_unit = match key(3076) {
        Some(9002) => 0.3048,
        Some(9003) => 1200.0 / 3937.0,
        _ => 1.0,
    };
    Ok(GeoRef {
        origin,
        pixel,
        geographic,
        meters_per_unit,
    })
}

/// The georeference of the TIFF at `path` (its tags alone are read), or
/// why it has none.
pub fn read_georef(path: &Path) -> Result<std::result::Result<GeoRef, &'static str>> {
    let mut decoder = open(path, "GeoTIFF")?;
    Ok(georef(&mut decoder))
}

/// The height scale the georeference of the height map at `path` gives
/// and the line saying so ([`GeoRef::height_scale`]), from its tags and
/// size alone; or why it has no georeference.
pub fn height_scale(path: &Path) -> Result<std::result::Result<(f32, String), &'static str>> {
    let mut decoder = open(path, "height map")?;
    let (_, rows) = decoder
        .dimensions()
        .map_err(|e| failed(path, "height map", e))?;
    Ok(georef(&mut decoder).map(|georef| georef.height_scale(rows)))
}

/// A photo's pixels as draping reads them: a photo in memory, or a
/// window of its rows streamed from its file ([`PhotoWindow`]).
pub trait PhotoPixels {
    /// Pixels a row, and rows.
    fn dimensions(&self) -> (u32, u32);
    /// Pixel `(x, y)`, inside the photo.
    fn pixel(&self, x: u32, y: u32) -> Rgb;
}

impl PhotoPixels for RgbImage {
    fn dimensions(&self) -> (u32, u32) {
        RgbImage::dimensions(self)
    }
    fn pixel(&self, x: u32, y: u32) -> Rgb {
        self.get_pixel(x, y).0
    }
}

/// A photo's rows read from its file in order, top row first: a TIFF
/// ([`TiffPhotoRows`]) or a PNG.
pub trait PhotoRowSource {
    /// Pixels a row, and rows.
    fn size(&self) -> (u32, u32);
    /// The next row.
    fn read_row(&mut self) -> Result<Vec<Rgb>>;
}

impl PhotoRowSource for TiffPhotoRows {
    fn size(&self) -> (u32, u32) {
        TiffRows::size(self)
    }
    fn read_row(&mut self) -> Result<Vec<Rgb>> {
        self.next_row().map(<[Rgb]>::to_vec)
    }
}

/// The rows of a photo streamed from its file that draping the grid's
/// current row reads ([`PhotoWindow::hold`]): the grid's rows come in
/// order, and the photo rows they need move down with them.
pub struct PhotoWindow {
    rows: Box<dyn PhotoRowSource>,
    size: (u32, u32),
    /// The rows held, from `first`, and the next row to read.
    lines: std::collections::VecDeque<Vec<Rgb>>,
    first: u32,
    next: u32,
}

impl PhotoWindow {
    /// The TIFF photo at `path`, no row read yet.
    pub fn open(path: &Path) -> Result<Self> {
        Ok(Self::over(Box::new(TiffPhotoRows::open_photo(path)?)))
    }

    /// The photo `rows` reads, no row read yet.
    pub fn over(rows: Box<dyn PhotoRowSource>) -> Self {
        Self {
            size: rows.size(),
            rows,
            lines: std::collections::VecDeque::new(),
            first: 0,
            next: 0,
        }
    }

    /// Holds photo rows `low..=high` (clamped into the photo), dropping
    /// those above: rows are read in order, once each.
    pub fn hold(&mut self, low: i64, high: i64) -> Result<()> {
        let last = i64::from(self.size.1) - 1;
        let (low, high) = (low.clamp(0, last) as u32, high.clamp(0, last) as u32);
        while self.first < low && !self.lines.is_empty() {
            self.lines.pop_front();
            self.first += 1;
        }
        if self.lines.is_empty() {
            // Rows above `low` that were never held are skipped.
            while self.next < low {
                self.rows.read_row()?;
                self.next += 1;
            }
            self.first = self.next;
        }
        while self.next <= high {
            self.lines.push_back(self.rows.read_row()?);
            self.next += 1;
        }
        Ok(())
    }

    /// Rows held now.
    pub fn rows_held(&self) -> usize {
        self.lines.len()
    }

    /// The photo's pixels a row, and rows.
    pub fn dimensions(&self) -> (u32, u32) {
        self.size
    }
}

impl PhotoPixels for PhotoWindow {
    fn dimensions(&self) -> (u32, u32) {
        self.size
    }
    fn pixel(&self, x: u32, y: u32) -> Rgb {
        // (Draping holds every row it reads first: `hold`.)
        let at = (y.saturating_sub(self.first) as usize).min(self.lines.len().saturating_sub(1));
        self.lines
            .get(at)
            .and_then(|line| line.get(x as usize))
            .copied()
            .unwrap_or([0; 3])
    }
}

/// How a photo lying at `photo_at` drapes over a grid lying at `grid_at`
/// (pixel-is-area: a sample stands for its pixel's center): a grid
/// point's footprint is a box as wide as the grid's spacing, at most 64
/// photo pixels a side.
#[derive(Debug, Clone, Copy)]
pub struct Drape {
    grid_at: GeoRef,
    photo_at: GeoRef,
    /// Photo pixels each side of a point's center its footprint reaches.
    reach: [f64; 2],
}

impl Drape {
    /// `photo_at`'s photo over `grid_at`'s grid.
    pub fn new(grid_at: &GeoRef, photo_at: &GeoRef) -> Self {
        Self {
            grid_at: *grid_at,
            photo_at: *photo_at,
            reach: [0, 1].map(|i| (grid_at.pixel[i] / photo_at.pixel[i] / 2.0).clamp(0.5, 32.0)),
        }
    }

    /// Grid row `gy`'s center in photo rows.
    fn v(&self, gy: u32) -> f64 {
        let my = self.grid_at.origin[1] - (f64::from(gy) + 0.5) * self.grid_at.pixel[1];
        (self.photo_at.origin[1] - my) / self.photo_at.pixel[1] - 0.5
    }

    /// The photo rows draping grid row `gy` reads.
    pub fn rows(&self, gy: u32) -> (i64, i64) {
        let v = self.v(gy);
        (
            (v - self.reach[1]).ceil() as i64,
            (v + self.reach[1]).floor() as i64,
        )
    }

    /// Drapes `photo` over grid row `gy` (`colors`, its points' colors):
    /// each point the photo covers takes the mean of the photo's pixels
    /// over the point's footprint, and the others keep their colors.
    /// Returns the points covered.
    pub fn row(&self, colors: &mut [Rgb], gy: u32, photo: &impl PhotoPixels) -> usize {
        let (pw, ph) = photo.dimensions();
        let (pw, ph) = (i64::from(pw), i64::from(ph));
        let v = self.v(gy);
        if v < -0.5 || v > ph as f64 - 0.5 {
            return 0;
        }
        let (y0, y1) = self.rows(gy);
        let mut covered = 0;
        for (gx, color) in colors.iter_mut().enumerate() {
            let mx = self.grid_at.origin[0] + (gx as f64 + 0.5) * self.grid_at.pixel[0];
            let u = (mx - self.photo_at.origin[0]) / self.photo_at.pixel[0] - 0.5;
            if u < -0.5 || u > pw as f64 - 0.5 {
                continue;
            }
            let (x0, x1) = (
                (u - self.reach[0]).ceil() as i64,
                (u + self.reach[0]).floor() as i64,
            );
            let (mut sum, mut n) = ([0u64; 3], 0u64);
            for y in y0.max(0)..=y1.min(ph - 1) {
                for x in x0.max(0)..=x1.min(pw - 1) {
                    let p = photo.pixel(x as u32, y as u32);
                    (0..3).for_each(|i| sum[i] += u64::from(p[i]));
                    n += 1;
                }
            }
            if n == 0 {
                continue;
            }
            *color = sum.map(|c| ((c + n / 2) / n) as u8);
            covered += 1;
        }
        covered
    }
}

/// Drapes `photo`, which lies at `photo_at`, over the grid of `width` ×
/// `depth` points lying at `grid_at`, row by row ([`Drape::row`]).
/// Returns the points covered.
pub fn drape(
    colors: &mut [Rgb],
    (width, depth): (u32, u32),
    grid_at: &GeoRef,
    photo: &RgbImage,
    photo_at: &GeoRef,
) -> usize {
    let drape = Drape::new(grid_at, photo_at);
    colors
        .chunks_exact_mut(width as usize)
        .take(depth as usize)
        .enumerate()
        .map(|(gy, row)| drape.row(row, gy as u32, photo))
        .sum()
}

/// A height raster: row-major values, NaN where it has no data.
#[derive(Debug, Clone)]
pub struct HeightRaster {
    /// Samples a row.
    pub width: u32,
    /// Rows.
    pub depth: u32,
    /// Heights in the file's units, top row first; NaN for no data.
    pub values: Vec<f32>,
    /// Where it lies, or why that is unknown.
    pub georef: std::result::Result<GeoRef, &'static str>,
}

/// Reads the heights of a single-band GeoTIFF.
pub fn read_heights(path: &Path) -> Result<HeightRaster> {
    let what = "height map";
    let (mut decoder, (width, depth), no_data) = open_heights(path)?;
    let georef = georef(&mut decoder);
    let image = decoder.read_image().map_err(|e| failed(path, what, e))?;
    let values = heights_of(image, no_data, path)?;
    if values.len() != width as usize * depth as usize {
        return Err(failed(path, what, "fewer samples than its size"));
    }
    Ok(HeightRaster {
        width,
        depth,
        values,
        georef,
    })
}

/// A TIFF decoder over a file.
type FileDecoder = Decoder<BufReader<File>>;

/// A single-band GeoTIFF of heights, opened: its decoder, its size and
/// its no-data value.
fn open_heights(path: &Path) -> Result<(FileDecoder, (u32, u32), Option<f64>)> {
    let what = "height map";
    let mut decoder = open(path, what)?;
    let size = decoder.dimensions().map_err(|e| failed(path, what, e))?;
    let color = decoder.colortype().map_err(|e| failed(path, what, e))?;
    if !matches!(color, ColorType::Gray(_)) {
        return Err(Error::new(format!(
            "height map {} is a {color:?} TIFF: a height map has one band of samples",
            path.display()
        )));
    }
    let no_data: Option<f64> = decoder
        .find_tag(Tag::GdalNodata)
        .ok()
        .flatten()
        .and_then(|v| v.into_string().ok())
        .and_then(|s| s.trim().trim_end_matches('\0').parse().ok());
    Ok((decoder, size, no_data))
}

/// Decoded height samples as `f32`, NaN where there is no data (the
/// file's no-data value, for int16 without one SRTM's −32768, and
/// infinities).
fn heights_of(samples: DecodingResult, no_data: Option<f64>, path: &Path) -> Result<Vec<f32>> {
    let mut values: Vec<f32> = match samples {
        DecodingResult::U8(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::U32(v) => v.into_iter().map(|x| x as f32).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f32::from).collect(),
        DecodingResult::I16(v) => v
            .into_iter()
            .map(|x| match (x, no_data) {
                // SRTM's void, where the file names no other.
                (i16::MIN, None) => f32::NAN,
                _ => f32::from(x),
            })
            .collect(),
        DecodingResult::I32(v) => v.into_iter().map(|x| x as f32).collect(),
        DecodingResult::F32(v) => v,
        DecodingResult::F64(v) => v.into_iter().map(|x| x as f32).collect(),
        other => {
            return Err(Error::new(format!(
                "height map {} has {} samples: GeoTIFF heights are 8-, 16- or 32-bit integers or 32- or 64-bit floats",
                path.display(),
                sample_kind(&other)
            )))
        }
    };
    let no_data = no_data.map(|v| v as f32);
    for v in &mut values {
        // Values no height can be (infinities) are no data too.
        if Some(*v) == no_data || v.is_infinite() {
            *v = f32::NAN;
        }
    }
    Ok(values)
}

/// A TIFF's rows, top row first, decoded a strip at a time, or for a file
/// stored in tiles a row of tiles at a time: what `pack` streams, in
/// memory a strip's (or a tile's) rows, whatever the file's size. Each
/// pixel is a `T`: a height ([`TiffHeightRows`]) or a photo's color
/// ([`TiffPhotoRows`]).
pub struct TiffRows<T> {
    decoder: FileDecoder,
    path: std::path::PathBuf,
    what: &'static str,
    size: (u32, u32),
    /// A chunk's samples as pixels.
    pixels: ChunkPixels<T>,
    /// What a pixel a tile does not cover holds until one does.
    blank: T,
    /// Tiles across and each tile's width, for a file stored in tiles.
    tiles: Option<(u32, u32)>,
    /// The current strip's (or row of tiles') rows, `size.0` pixels
    /// each, and its first row.
    strip: Vec<T>,
    strip_first: u32,
    /// The next row, and the next strip (or row of tiles) to decode.
    next: u32,
    next_strip: u32,
}

/// A decoded chunk's samples as a [`TiffRows`]'s pixels (the file's path
/// for errors).
type ChunkPixels<T> = Box<dyn Fn(DecodingResult, &Path) -> Result<Vec<T>>>;

/// A single-band GeoTIFF's heights row by row ([`TiffRows`]), in the
/// file's units, NaN for no data.
pub type TiffHeightRows = TiffRows<f32>;

/// A photo's rows ([`TiffRows`]), its pixels as RGB.
pub type TiffPhotoRows = TiffRows<Rgb>;

impl<T> std::fmt::Debug for TiffRows<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TiffRows")
            .field("path", &self.path)
            .field("size", &self.size)
            .field("next", &self.next)
            .finish_non_exhaustive()
    }
}

impl TiffRows<f32> {
    /// Opens the heights at `path`, stored in strips or in tiles.
    pub fn open(path: &Path) -> Result<Self> {
        let (decoder, size, no_data) = open_heights(path)?;
        let pixels = Box::new(move |samples, path: &Path| heights_of(samples, no_data, path));
        Ok(TiffRows::over(
            decoder,
            path,
            "height map",
            size,
            pixels,
            f32::NAN,
        ))
    }
}

impl TiffRows<Rgb> {
    /// Opens the photo at `path` (8-bit gray, RGB or RGBA, alpha dropped),
    /// stored in strips or in tiles.
    pub fn open_photo(path: &Path) -> Result<Self> {
        let what = "color map";
        let (decoder, size, channels) = open_photo(path)?;
        let pixels = Box::new(move |samples, path: &Path| {
            let DecodingResult::U8(bytes) = samples else {
                return Err(failed(path, what, "its samples are not bytes"));
            };
            Ok(rgb_of(&bytes, channels).collect())
        });
        Ok(TiffRows::over(decoder, path, what, size, pixels, [0; 3]))
    }
}

impl<T: Copy> TiffRows<T> {
    fn over(
        decoder: FileDecoder,
        path: &Path,
        what: &'static str,
        size: (u32, u32),
        pixels: ChunkPixels<T>,
        blank: T,
    ) -> Self {
        let tiles = match decoder.get_chunk_type() {
            tiff::decoder::ChunkType::Strip => None,
            // (`open` refused tiles with a side of 0.)
            tiff::decoder::ChunkType::Tile => {
                let (width, _) = decoder.chunk_dimensions();
                Some((size.0.div_ceil(width.max(1)), width))
            }
        };
        Self {
            decoder,
            path: path.to_owned(),
            what,
            size,
            pixels,
            blank,
            tiles,
            strip: Vec::new(),
            strip_first: 0,
            next: 0,
            next_strip: 0,
        }
    }

    /// Pixels a row and rows.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The next row.
    pub fn next_row(&mut self) -> Result<&[T]> {
        let what = self.what;
        let width = self.size.0 as usize;
        if self.next >= self.size.1 {
            return Err(failed(&self.path, what, "read past its last row"));
        }
        if (self.next - self.strip_first + 1) as usize * width > self.strip.len() {
            self.strip = match self.tiles {
                None => {
                    let samples = self
                        .decoder
                        .read_chunk(self.next_strip)
                        .map_err(|e| failed(&self.path, what, e))?;
                    (self.pixels)(samples, &self.path)?
                }
                Some((across, tile_width)) => self.tile_row(self.next_strip, across, tile_width)?,
            };
            if self.strip.is_empty() || self.strip.len() % width != 0 {
                return Err(failed(&self.path, what, "a strip of part of a row"));
            }
            self.strip_first = self.next;
            self.next_strip += 1;
        }
        let at = (self.next - self.strip_first) as usize * width;
        self.next += 1;
        Ok(&self.strip[at..at + width])
    }

    /// Row `row` of the file's tiles (`across` of them, `tile_width`
    /// pixels wide, the last cut at the image's edge) as whole image rows.
    fn tile_row(&mut self, row: u32, across: u32, tile_width: u32) -> Result<Vec<T>> {
        let what = self.what;
        let width = self.size.0 as usize;
        let count = self
            .decoder
            .tile_count()
            .map_err(|e| failed(&self.path, what, e))?;
        // The row's tiles are all in the file before its rows are made.
        if row.saturating_add(1).saturating_mul(across) > count {
            return Err(failed(&self.path, what, "fewer tiles than its size"));
        }
        let mut rows = Vec::new();
        for column in 0..across {
            let index = row
                .checked_mul(across)
                .and_then(|i| i.checked_add(column))
                .filter(|&i| i < count)
                .ok_or_else(|| failed(&self.path, what, "fewer tiles than its size"))?;
            let (data_width, data_height) = self.decoder.chunk_data_dimensions(index);
            let samples = self
                .decoder
                .read_chunk(index)
                .map_err(|e| failed(&self.path, what, e))?;
            let tile = (self.pixels)(samples, &self.path)?;
            let (data_width, data_height) = (data_width as usize, data_height as usize);
            let x = (column * tile_width) as usize;
            if rows.is_empty() {
                rows = vec![self.blank; data_height * width];
            }
            if tile.len() < data_width * data_height
                || x + data_width > width
                || rows.len() != data_height * width
            {
                return Err(failed(
                    &self.path,
                    what,
                    "a tile of another size than its row's",
                ));
            }
            for (line, pixels) in rows
                .chunks_exact_mut(width)
                .zip(tile.chunks_exact(data_width))
            {
                line[x..x + data_width].copy_from_slice(pixels);
            }
        }
        Ok(rows)
    }
}

fn sample_kind(result: &DecodingResult) -> &'static str {
    match result {
        DecodingResult::U64(_) => "64-bit integer",
        DecodingResult::I64(_) => "64-bit signed integer",
        DecodingResult::F16(_) => "16-bit float",
        _ => "unsupported",
    }
}

/// Reads a photo: 8-bit gray, gray with alpha, RGB or RGBA (alpha is
/// dropped).
pub fn read_photo(path: &Path) -> Result<RgbImage> {
    let what = "color map";
    let (mut decoder, (width, height), channels) = open_photo(path)?;
    let DecodingResult::U8(bytes) = decoder.read_image().map_err(|e| failed(path, what, e))? else {
        return Err(failed(path, what, "its samples are not bytes"));
    };
    let pixels = width as usize * height as usize;
    if bytes.len() < pixels * channels {
        return Err(failed(path, what, "fewer samples than its size"));
    }
    let rgb: Vec<u8> = rgb_of(&bytes, channels).take(pixels).flatten().collect();
    RgbImage::from_raw(width, height, rgb).ok_or_else(|| failed(path, what, "bad size"))
}

/// A photo's decoder, its size and its samples a pixel (1 to 4), refused
/// in one line unless 8-bit gray, RGB or RGBA.
fn open_photo(path: &Path) -> Result<(FileDecoder, (u32, u32), usize)> {
    let what = "color map";
    let mut decoder = open(path, what)?;
    let size = decoder.dimensions().map_err(|e| failed(path, what, e))?;
    let color = decoder.colortype().map_err(|e| failed(path, what, e))?;
    let channels = match color {
        ColorType::Gray(8) => 1,
        ColorType::GrayA(8) => 2,
        ColorType::RGB(8) => 3,
        ColorType::RGBA(8) => 4,
        other => {
            return Err(Error::new(format!(
                "color map {} is a {other:?} TIFF: a photo is 8-bit gray, RGB or RGBA",
                path.display()
            )))
        }
    };
    Ok((decoder, size, channels))
}

/// 8-bit samples, `channels` a pixel, as RGB (gray repeated, alpha
/// dropped).
fn rgb_of(bytes: &[u8], channels: usize) -> impl Iterator<Item = Rgb> + '_ {
    bytes.chunks_exact(channels).map(move |p| match channels {
        1 | 2 => [p[0]; 3],
        _ => [p[0], p[1], p[2]],
    })
}

/// Whether `path` names a TIFF by its extension.
pub fn is_tiff(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("tif") || e.eq_ignore_ascii_case("tiff"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use tiff::encoder::{colortype, TiffEncoder};

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("terracast-geotiff-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    /// Writes a 4 × 3 one-band TIFF of `C` samples with `tags` (tag,
    /// doubles) and an optional GDAL_NODATA string.
    fn write<C: colortype::ColorType>(
        name: &str,
        data: &[C::Inner],
        tags: &[(Tag, &[f64])],
        no_data: Option<&str>,
    ) -> std::path::PathBuf
    where
        [C::Inner]: tiff::encoder::TiffValue,
    {
        let path = temp(name);
        let mut encoder = TiffEncoder::new(File::create(&path).unwrap()).unwrap();
        let mut image = encoder.new_image::<C>(4, 3).unwrap();
        for &(tag, values) in tags {
            image.encoder().write_tag(tag, values).unwrap();
        }
        if let Some(text) = no_data {
            image.encoder().write_tag(Tag::GdalNodata, text).unwrap();
        }
        image.write_data(data).unwrap();
        path
    }

    const GEOGRAPHIC: [(Tag, &[f64]); 2] = [
        (Tag::ModelPixelScaleTag, &[0.001, 0.001, 0.0]),
        (Tag::ModelTiepointTag, &[0.0, 0.0, 0.0, 20.0, -34.0, 0.0]),
    ];

    #[test]
    fn heights_of_every_sample_format_with_their_no_data() {
        let int16 = write::<colortype::GrayI16>(
            "i16.tif",
            &[10, 20, i16::MIN, 40, 50, 60, 70, 80, 90, 100, 110, -5],
            &GEOGRAPHIC,
            None,
        );
        let raster = read_heights(&int16).unwrap();
        assert_eq!((raster.width, raster.depth), (4, 3));
        assert!(raster.values[2].is_nan(), "SRTM's void");
        assert_eq!(raster.values[11], -5.0);
        let float = write::<colortype::Gray32Float>(
            "f32.tif",
            &[
                1.5, -9999.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0,
            ],
            &GEOGRAPHIC,
            Some("-9999"),
        );
        let raster = read_heights(&float).unwrap();
        assert_eq!(raster.values[0], 1.5);
        assert!(raster.values[1].is_nan(), "GDAL_NODATA");
        let unsigned = write::<colortype::Gray16>("u16.tif", &[7; 12], &[], None);
        let raster = read_heights(&unsigned).unwrap();
        assert_eq!(raster.values, vec![7.0; 12]);
        assert_eq!(
            raster.georef,
            Err("it has no ModelPixelScale and ModelTiepoint")
        );
    }

    #[test]
    fn a_georeference_gives_the_height_scale_in_meters() {
        let path = write::<colortype::Gray16>("geo.tif", &[0; 12], &GEOGRAPHIC, None);
        let georef = read_heights(&path).unwrap().georef.unwrap();
        assert!(georef.geographic);
        assert_eq!(georef.origin, [20.0, -34.0]);
        // 0.001° of latitude is 111.1 m; of longitude at 34°S, 92.1 m.
        let (east, north) = georef.spacing_m(3);
        assert!(
            (north - 111.132).abs() < 0.01 && (east - 92.13).abs() < 0.05,
            "{east} {north}"
        );
        let (scale, why) = georef.height_scale(3);
        assert!((1.0 / scale - 101.63).abs() < 0.05, "{scale}");
        assert!(why.contains("latitude -34.00"), "{why}");
        // Projected, in meters: the pixel size is the spacing.
        let projected = write::<colortype::Gray16>(
            "utm.tif",
            &[0; 12],
            &[
                (Tag::ModelPixelScaleTag, &[2.0, 2.0, 0.0]),
                (
                    Tag::ModelTiepointTag,
                    &[0.0, 0.0, 0.0, 500_000.0, 3_800_000.0, 0.0],
                ),
            ],
            None,
        );
        let georef = read_heights(&projected).unwrap().georef.unwrap();
        assert!(!georef.geographic);
        assert_eq!(georef.height_scale(3).0, 0.5);
    }

    /// A 4 × 2 RGB photo at `origin` (degrees), 0.0005° pixels.
    fn photo_at(name: &str, origin: [f64; 2]) -> std::path::PathBuf {
        let path = temp(name);
        let mut encoder = TiffEncoder::new(File::create(&path).unwrap()).unwrap();
        let mut image = encoder.new_image::<colortype::RGB8>(4, 2).unwrap();
        let scale: &[f64] = &[0.0005, 0.0005, 0.0];
        let tiepoint: &[f64] = &[0.0, 0.0, 0.0, origin[0], origin[1], 0.0];
        image
            .encoder()
            .write_tag(Tag::ModelPixelScaleTag, scale)
            .unwrap();
        image
            .encoder()
            .write_tag(Tag::ModelTiepointTag, tiepoint)
            .unwrap();
        image.write_data(&[250u8; 24]).unwrap();
        path
    }

    #[test]
    fn photos_lie_where_their_georeference_puts_them() {
        // Heights: 4 × 3 samples of 0.001° from (20, −34).
        let heights = write::<colortype::Gray16>("grid.tif", &[5; 12], &GEOGRAPHIC, None);
        // A photo over the grid's top-left corner, 0.002° by 0.001°: the
        // two points whose centers (0.0005° and 0.0015° in) it covers.
        let corner = photo_at("corner.tif", [20.0, -34.0]);
        let scene = crate::scene::load_scene_files(&heights, &[corner], 1.0, 1).unwrap();
        let bright = |c: &terracast::Rgb| *c == [250; 3];
        let covered: Vec<bool> = scene.colors.iter().map(bright).collect();
        assert_eq!(
            covered,
            [true, true, false, false, false, false, false, false, false, false, false, false]
        );
        // Far away: refused in one line.
        let far = photo_at("far.tif", [30.0, -10.0]);
        let e = crate::scene::load_scene_files(&heights, std::slice::from_ref(&far), 1.0, 1)
            .unwrap_err();
        assert!(e.to_string().contains("does not overlap"), "{e}");
        // Several photos over a height map without a georeference.
        let plain = write::<colortype::Gray16>("plain.tif", &[5; 12], &[], None);
        let e = crate::scene::load_scene_files(&plain, &[far.clone(), far], 1.0, 1).unwrap_err();
        assert!(e.to_string().contains("several --color photos"), "{e}");
    }

    #[test]
    fn photos_and_bad_files_are_read_or_refused_in_one_line() {
        let path = temp("rgba.tif");
        let mut encoder = TiffEncoder::new(File::create(&path).unwrap()).unwrap();
        let rgba: Vec<u8> = (0..4 * 3).flat_map(|i| [i as u8, 100, 200, 0]).collect();
        encoder
            .write_image::<colortype::RGBA8>(4, 3, &rgba)
            .unwrap();
        let photo = read_photo(&path).unwrap();
        assert_eq!(photo.dimensions(), (4, 3));
        assert_eq!(photo.get_pixel(3, 2).0, [11, 100, 200]);
        // A photo as heights, heights as a photo, 16-bit RGB: refused.
        let e = read_heights(&path).unwrap_err().to_string();
        assert!(e.contains("one band"), "{e}");
        let heights = write::<colortype::Gray32Float>("h.tif", &[0.0; 12], &[], None);
        assert!(read_photo(&heights)
            .unwrap_err()
            .to_string()
            .contains("8-bit"));
        // Truncated: an error, not a panic.
        let bytes = std::fs::read(&path).unwrap();
        let cut = temp("cut.tif");
        for keep in [0, 8, 40, bytes.len() / 2, bytes.len() - 1] {
            std::fs::write(&cut, &bytes[..keep]).unwrap();
            let e = read_photo(&cut).unwrap_err().to_string();
            assert!(e.contains("cut.tif") && !e.contains('\n'), "{e}");
        }
    }
}
