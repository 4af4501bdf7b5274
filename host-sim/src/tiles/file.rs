//! The tiled terrain file (`.tiles`): every pyramid level cut into tiles of
//! [`TILE`]² points, each with a CRC-32, so a reader fetches any tile with
//! one seek and checks it.
//!
//! Layout, little-endian:
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `TCTILES\0` |
//! | 4 | format version ([`FORMAT_VERSION`]) |
//! | 4 | tile side in points |
//! | 4, 4 | width, depth of level 0 in points |
//! | 4 | levels |
//! | 2 | highest height, U12.4 |
//! | 1 | height filter: 0 mean, 1 max, 2 subsample, 3 wavelet |
//! | 1 | roughness of level 0 (`terracast::roughness`), 0 if unknown |
//! | 8 | tile count |
//! | 4 | CRC-32 of the 40 bytes before it |
//! | 4 × count | CRC-32 of each tile record |
//! | record × count | tile records |
//! | 4 | photo count (version 2) |
//! | 20 × photos | each photo's first grid point (x, y), grid points (x, y), texels a voxel as a shift |
//! | 4 | CRC-32 of the photo count and table |
//! | 4 × photo tiles | CRC-32 of each photo tile record |
//! | photo record × photo tiles | photo tile records |
//! | 4, 4 | stick count, texel count (version 3) |
//! | 4 | opacity count: 0, or the texel count (version 4) |
//! | 8 × sticks | each stick's first texel (`u32`), texel count and height (U12.4, `u16` each) |
//! | 3 × texels | the sticks' texels (RGB) |
//! | opacities | each texel's opacity, 255 opaque (version 4; none where all are) |
//! | 4 | CRC-32 of the stick section before it |
//!
//! Tiles are ordered by level, then row, then column. A record is the
//! tile's heights (`u16`, row by row), colors (RGB), and cell bounds
//! (`u16`; on level 0, each point's stick, 0 where none stands, 1 for the
//! stick table's first): see [`terracast::tiles::Tile`]. Photo tiles (photos finer than
//! the height grid, [`terracast::tiles::PhotoTile`]) are ordered by photo,
//! then fine level (the photo's texels first), then row, then column; a
//! record is the tile's texels (RGB). A version-1 file is read as one
//! without photos, a version-2 file as one without objects, a version-3
//! file as one whose objects are opaque.

use super::TILE;
use crate::error::{Error, Result};
use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use terracast::tiles::{
    photo_tiles, PhotoKey, PhotoTile, Tile, TileError, TileKey, TileSource, World,
};
use terracast::{DetailArea, HeightFilter, Rgb, Stick, StickTable};

/// The format version this build writes (it reads versions 1 to 3 too).
pub const FORMAT_VERSION: u32 = 4;

const MAGIC: &[u8; 8] = b"TCTILES\0";
const HEADER_BYTES: u64 = 44;
/// Bytes of one tile record.
pub(crate) const RECORD_BYTES: usize = TILE * TILE * 7;
/// Bytes of one photo tile record.
const PHOTO_RECORD_BYTES: usize = TILE * TILE * 3;
/// Bytes of a photo's entry in the photo table.
const PHOTO_ENTRY_BYTES: usize = 20;
/// Photos a file holds at most (a [`PhotoKey`] names one in a byte).
pub(crate) const MAX_PHOTOS: u64 = 256;
/// Sticks a file holds at most (a level-0 point names one in 16 bits).
pub(crate) const MAX_STICKS: u64 = u16::MAX as u64;
/// Bytes of a stick's entry in the stick table.
const STICK_ENTRY_BYTES: usize = 8;

/// The header's byte for a height filter.
fn filter_code(filter: HeightFilter) -> u8 {
    match filter {
        HeightFilter::Mean => 0,
        HeightFilter::Max => 1,
        HeightFilter::Subsample => 2,
        HeightFilter::Wavelet => 3,
    }
}

/// The height filter a header's byte names, if any.
fn filter_from_code(code: u8) -> Option<HeightFilter> {
    match code {
        0 => Some(HeightFilter::Mean),
        1 => Some(HeightFilter::Max),
        2 => Some(HeightFilter::Subsample),
        3 => Some(HeightFilter::Wavelet),
        _ => None,
    }
}

/// What the header says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Header {
    pub world: World,
    pub levels: u8,
    pub filter: HeightFilter,
    pub tiles: u64,
}

impl Header {
    pub fn new(world: World, filter: HeightFilter) -> Self {
        let levels = world.levels();
        let tiles = (0..levels)
            .map(|l| {
                let (x, y) = world.tiles(l, TILE as u32);
                u64::from(x) * u64::from(y)
            })
            .sum();
        Self {
            world,
            levels,
            filter,
            tiles,
        }
    }

    fn bytes(&self) -> [u8; HEADER_BYTES as usize] {
        let mut b = [0u8; HEADER_BYTES as usize];
        b[0..8].copy_from_slice(MAGIC);
        b[8..12].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
        b[12..16].copy_from_slice(&(TILE as u32).to_le_bytes());
        b[16..20].copy_from_slice(&self.world.width.to_le_bytes());
        b[20..24].copy_from_slice(&self.world.depth.to_le_bytes());
        b[24..28].copy_from_slice(&u32::from(self.levels).to_le_bytes());
        b[28..30].copy_from_slice(&self.world.max_height.to_le_bytes());
        b[30] = filter_code(self.filter);
        b[31] = self.world.roughness;
        b[32..40].copy_from_slice(&self.tiles.to_le_bytes());
        let crc = crc32fast::hash(&b[..40]);
        b[40..44].copy_from_slice(&crc.to_le_bytes());
        b
    }

    /// Index of a tile among all the file's tiles.
    pub fn index(&self, key: TileKey) -> Option<u64> {
        if key.level >= self.levels {
            return None;
        }
        let before: u64 = (0..key.level)
            .map(|l| {
                let (x, y) = self.world.tiles(l, TILE as u32);
                u64::from(x) * u64::from(y)
            })
            .sum();
        let (tx, ty) = self.world.tiles(key.level, TILE as u32);
        (key.x < tx && key.y < ty)
            .then(|| before + u64::from(key.y) * u64::from(tx) + u64::from(key.x))
    }

    fn record_offset(&self, index: u64) -> u64 {
        HEADER_BYTES + 4 * self.tiles + index * RECORD_BYTES as u64
    }

    fn file_bytes(&self) -> u64 {
        self.record_offset(self.tiles)
    }
}

/// The photo section of a file: where each photo lies and where its
/// tiles are.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Photos {
    pub areas: Vec<DetailArea>,
    /// Each photo's and fine level's first tile among the photo tiles.
    firsts: Vec<Vec<u64>>,
    /// Photo tiles in all.
    pub tiles: u64,
}

impl Photos {
    pub fn new(areas: Vec<DetailArea>) -> Self {
        let mut tiles = 0u64;
        let firsts = areas
            .iter()
            .map(|area| {
                (0..=area.shift())
                    .map(|level| {
                        let first = tiles;
                        let (x, y) = photo_tiles(area, level, TILE as u32);
                        tiles += u64::from(x) * u64::from(y);
                        first
                    })
                    .collect()
            })
            .collect();
        Self {
            areas,
            firsts,
            tiles,
        }
    }

    /// Index of a photo tile among the file's photo tiles.
    pub fn index(&self, key: PhotoKey) -> Option<u64> {
        let area = self.areas.get(usize::from(key.photo))?;
        let first = *self.firsts[usize::from(key.photo)].get(usize::from(key.level))?;
        let (tx, ty) = photo_tiles(area, u32::from(key.level), TILE as u32);
        (key.x < tx && key.y < ty)
            .then(|| first + u64::from(key.y) * u64::from(tx) + u64::from(key.x))
    }

    /// Bytes of the photo count and table.
    fn table_bytes(&self) -> u64 {
        4 + (PHOTO_ENTRY_BYTES * self.areas.len()) as u64
    }

    /// The photo count and table, and their CRC-32.
    fn table(&self) -> Vec<u8> {
        let mut b = (self.areas.len() as u32).to_le_bytes().to_vec();
        for area in &self.areas {
            for v in [area.origin(), area.size()].concat() {
                b.extend_from_slice(&v.to_le_bytes());
            }
            b.extend_from_slice(&area.shift().to_le_bytes());
        }
        let crc = crc32fast::hash(&b);
        b.extend_from_slice(&crc.to_le_bytes());
        b
    }

    /// Offset of photo tile record `index`, the section starting at `start`.
    fn record_offset(&self, start: u64, index: u64) -> u64 {
        start + self.table_bytes() + 4 + 4 * self.tiles + index * PHOTO_RECORD_BYTES as u64
    }

    /// Bytes of the section.
    fn bytes(&self) -> u64 {
        self.record_offset(0, self.tiles)
    }
}

/// A packed terrain file opened for reading: a [`TileSource`].
#[derive(Debug)]
pub struct TilesFile {
    path: PathBuf,
    file: File,
    header: Header,
    checksums: Vec<u32>,
    record: Vec<u8>,
    photos: Photos,
    photo_checksums: Vec<u32>,
    /// The objects' sticks, their texels and the texels' opacities (none
    /// before version 3; no opacities before version 4).
    sticks: Box<Sticks>,
}

impl TilesFile {
    /// Opens and checks a `.tiles` file: refuses a foreign file, another
    /// version or tile size, a damaged header, and a truncated file.
    pub fn open(path: &Path) -> Result<Self> {
        let fail = |what: &str| Error::new(format!("{}: {what}", path.display()));
        let mut file = File::open(path).map_err(|e| {
            Error::new(format!("cannot open tiled terrain {}: {e}", path.display()))
        })?;
        let mut b = [0u8; HEADER_BYTES as usize];
        let length = file.metadata().map(|m| m.len()).unwrap_or(0);
        if length < HEADER_BYTES {
            return Err(fail(
                "not a terracast tiled terrain file (too short for a header)",
            ));
        }
        file.read_exact(&mut b)
            .map_err(|e| fail(&format!("cannot read header: {e}")))?;
        if &b[0..8] != MAGIC {
            return Err(fail("not a terracast tiled terrain file (bad magic)"));
        }
        let u32_at = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        let version = u32_at(8);
        if !(1..=FORMAT_VERSION).contains(&version) {
            return Err(fail(&format!(
                "format version {version}, this build reads versions 1 to {FORMAT_VERSION}"
            )));
        }
        if crc32fast::hash(&b[..40]) != u32_at(40) {
            return Err(fail("header checksum mismatch: the file is damaged"));
        }
        if u32_at(12) != TILE as u32 {
            return Err(fail(&format!(
                "tiles of {} points a side, this build uses {TILE}",
                u32_at(12)
            )));
        }
        let max_height = u16::from_le_bytes([b[28], b[29]]);
        let world = World::new(u32_at(16), u32_at(20), max_height)
            .ok_or_else(|| fail("impossible map size in the header"))?
            .with_roughness(b[31]);
        let filter = filter_from_code(b[30])
            .ok_or_else(|| fail(&format!("unknown height filter {} in the header", b[30])))?;
        let header = Header::new(world, filter);
        let tiles = u64::from_le_bytes(b[32..40].try_into().unwrap_or_default());
        if tiles != header.tiles || u32_at(24) != u32::from(header.levels) {
            return Err(fail("header's tile count does not match its map size"));
        }
        if length < header.file_bytes() {
            return Err(fail(&format!(
                "truncated: {length} bytes, the header promises {}",
                header.file_bytes()
            )));
        }
        let mut table = vec![0u8; 4 * header.tiles as usize];
        file.read_exact(&mut table)
            .map_err(|e| fail(&format!("cannot read the checksum table: {e}")))?;
        let checksums = words(&table);
        let (photos, photo_checksums) = if version == 1 {
            (Photos::default(), Vec::new())
        } else {
            read_photos(&mut file, header.file_bytes(), length).map_err(|e| fail(&e))?
        };
        let sticks = Box::new(if version < 3 {
            Sticks::default()
        } else {
            let start = header.file_bytes() + photos.bytes();
            read_sticks(&mut file, (start, length), version).map_err(|e| fail(&e))?
        });
        Ok(Self {
            path: path.to_path_buf(),
            file,
            header,
            checksums,
            record: vec![0; RECORD_BYTES],
            photos,
            photo_checksums,
            sticks,
        })
    }

    /// The height filter the file's levels were built with.
    pub fn filter(&self) -> HeightFilter {
        self.header.filter
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Little-endian words.
fn words(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Reads the photo section starting at `start` of a file `length` bytes
/// long; why not, in words, when it is damaged or cut short.
fn read_photos(
    file: &mut File,
    start: u64,
    length: u64,
) -> std::result::Result<(Photos, Vec<u32>), String> {
    let cut = |what: &str| format!("truncated: the photo section's {what} is missing");
    if length < start + 4 {
        return Err(cut("count"));
    }
    let mut count = [0u8; 4];
    file.seek(SeekFrom::Start(start))
        .and_then(|_| file.read_exact(&mut count))
        .map_err(|e| format!("cannot read the photo count: {e}"))?;
    let count = u64::from(u32::from_le_bytes(count));
    if count > MAX_PHOTOS {
        return Err(format!(
            "the photo table lists {count} photos, a file holds at most {MAX_PHOTOS}: the file is damaged"
        ));
    }
    let table_bytes = 4 + PHOTO_ENTRY_BYTES as u64 * count + 4;
    if length < start + table_bytes {
        return Err(cut("table"));
    }
    let mut table = vec![0u8; table_bytes as usize];
    file.seek(SeekFrom::Start(start))
        .and_then(|_| file.read_exact(&mut table))
        .map_err(|e| format!("cannot read the photo table: {e}"))?;
    let (entries, crc) = table.split_at(table.len() - 4);
    if crc32fast::hash(entries) != words(crc)[0] {
        return Err("photo table checksum mismatch: the file is damaged".into());
    }
    let areas = entries[4..]
        .chunks_exact(PHOTO_ENTRY_BYTES)
        .map(|entry| {
            let v = words(entry);
            DetailArea::new([v[0], v[1]], [v[2], v[3]], v[4], World::MAX_SIDE)
                .map_err(|e| format!("photo table: {e}"))
        })
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let photos = Photos::new(areas);
    if length < start + photos.bytes() {
        return Err(format!(
            "truncated: {length} bytes, the photo table promises {}",
            start + photos.bytes()
        ));
    }
    let mut sums = vec![0u8; 4 * photos.tiles as usize];
    file.read_exact(&mut sums)
        .map_err(|e| format!("cannot read the photo checksums: {e}"))?;
    Ok((photos, words(&sums)))
}

/// A file's objects: sticks, texels, opacities (none where all opaque).
#[derive(Debug, Default)]
struct Sticks {
    sticks: Vec<Stick>,
    texels: Vec<Rgb>,
    alphas: Vec<u8>,
}

/// The stick section's bytes for `table`.
fn stick_section(table: &StickTable<'_>) -> Vec<u8> {
    let (sticks, texels, alphas) = (table.sticks(), table.texels(), table.alphas());
    let mut b =
        Vec::with_capacity(16 + STICK_ENTRY_BYTES * sticks.len() + 3 * texels.len() + alphas.len());
    b.extend_from_slice(&(sticks.len() as u32).to_le_bytes());
    b.extend_from_slice(&(texels.len() as u32).to_le_bytes());
    b.extend_from_slice(&(alphas.len() as u32).to_le_bytes());
    for stick in sticks {
        b.extend_from_slice(&stick.first.to_le_bytes());
        b.extend_from_slice(&stick.texels.to_le_bytes());
        b.extend_from_slice(&stick.height.to_le_bytes());
    }
    texels.iter().for_each(|c| b.extend_from_slice(c));
    b.extend_from_slice(alphas);
    let crc = crc32fast::hash(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

/// Reads the stick section starting at `start` of a file `length` bytes
/// long, of format `version`; why not, in words, when it is damaged or
/// cut short.
fn read_sticks(
    file: &mut File,
    (start, length): (u64, u64),
    version: u32,
) -> std::result::Result<Sticks, String> {
    let cut = || "truncated: the stick table is missing or cut short".to_string();
    // Version 3 has no opacity count.
    let counted = if version >= 4 { 12 } else { 8 };
    if length < start + counted {
        return Err(cut());
    }
    let mut counts = [0u8; 12];
    file.seek(SeekFrom::Start(start))
        .and_then(|_| file.read_exact(&mut counts[..counted as usize]))
        .map_err(|e| format!("cannot read the stick table: {e}"))?;
    let [count, texel_count, alpha_count] = [0, 1, 2].map(|i| u64::from(words(&counts)[i]));
    if count > MAX_STICKS {
        return Err(format!(
            "the stick table lists {count} sticks, a file holds at most {MAX_STICKS}: the file is damaged"
        ));
    }
    if alpha_count != 0 && alpha_count != texel_count {
        return Err(format!(
            "the stick table lists {alpha_count} opacities for {texel_count} texels: the file is damaged"
        ));
    }
    let bytes = counted + STICK_ENTRY_BYTES as u64 * count + 3 * texel_count + alpha_count + 4;
    if length < start + bytes {
        return Err(cut());
    }
    let mut section = vec![0u8; bytes as usize];
    file.seek(SeekFrom::Start(start))
        .and_then(|_| file.read_exact(&mut section))
        .map_err(|e| format!("cannot read the stick table: {e}"))?;
    let (entries, crc) = section.split_at(section.len() - 4);
    if crc32fast::hash(entries) != words(crc)[0] {
        return Err("stick table checksum mismatch: the file is damaged".into());
    }
    let (table, rest) = entries[counted as usize..].split_at(STICK_ENTRY_BYTES * count as usize);
    let (texels, alphas) = rest.split_at(3 * texel_count as usize);
    let sticks: Vec<Stick> = table
        .chunks_exact(STICK_ENTRY_BYTES)
        .map(|e| Stick {
            first: u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
            texels: u16::from_le_bytes([e[4], e[5]]),
            height: u16::from_le_bytes([e[6], e[7]]),
        })
        .collect();
    let texels: Vec<Rgb> = texels.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    StickTable::new(&sticks, &texels)
        .and_then(|table| table.with_alphas(alphas))
        .map_err(|e| format!("stick table: {e}"))?;
    Ok(Sticks {
        sticks,
        texels,
        alphas: alphas.to_vec(),
    })
}

impl TileSource<TILE> for TilesFile {
    fn world(&self) -> World {
        self.header.world
    }

    fn load(
        &mut self,
        key: TileKey,
        tile: &mut Tile<TILE>,
    ) -> std::result::Result<usize, TileError> {
        let index = self.header.index(key).ok_or(TileError::Missing)?;
        let offset = self.header.record_offset(index);
        self.file
            .seek(SeekFrom::Start(offset))
            .and_then(|_| self.file.read_exact(&mut self.record))
            .map_err(|_| TileError::Io)?;
        if crc32fast::hash(&self.record) != self.checksums[index as usize] {
            return Err(TileError::Checksum);
        }
        decode(&self.record, tile);
        // A level-0 point naming a stick past the file's table is damage
        // the checksum did not catch: rejected as a damaged tile is.
        let sticks = self.sticks.sticks.len();
        if key.level == 0
            && tile
                .bounds
                .iter()
                .flatten()
                .any(|&p| usize::from(p) > sticks)
        {
            return Err(TileError::Checksum);
        }
        Ok(RECORD_BYTES)
    }

    fn photos(&self) -> &[DetailArea] {
        &self.photos.areas
    }

    fn load_photo(
        &mut self,
        key: PhotoKey,
        tile: &mut PhotoTile<TILE>,
    ) -> std::result::Result<usize, TileError> {
        let index = self.photos.index(key).ok_or(TileError::Missing)?;
        let offset = self.photos.record_offset(self.header.file_bytes(), index);
        let record = &mut self.record[..PHOTO_RECORD_BYTES];
        self.file
            .seek(SeekFrom::Start(offset))
            .and_then(|_| self.file.read_exact(record))
            .map_err(|_| TileError::Io)?;
        if crc32fast::hash(record) != self.photo_checksums[index as usize] {
            return Err(TileError::Checksum);
        }
        for (texel, c) in tile.texels.iter_mut().flatten().zip(record.chunks_exact(3)) {
            *texel = [c[0], c[1], c[2]];
        }
        Ok(PHOTO_RECORD_BYTES)
    }

    fn sticks(&self) -> StickTable<'_> {
        // Checked when the file was opened.
        let Sticks {
            sticks,
            texels,
            alphas,
        } = &*self.sticks;
        StickTable::new(sticks, texels)
            .and_then(|table| table.with_alphas(alphas))
            .unwrap_or(StickTable::EMPTY)
    }
}

pub(crate) fn encode(tile: &Tile<TILE>, out: &mut Vec<u8>) {
    out.clear();
    for row in &tile.heights {
        row.iter()
            .for_each(|h| out.extend_from_slice(&h.to_le_bytes()));
    }
    for row in &tile.colors {
        row.iter().for_each(|c| out.extend_from_slice(c));
    }
    for row in &tile.bounds {
        row.iter()
            .for_each(|h| out.extend_from_slice(&h.to_le_bytes()));
    }
}

fn decode(record: &[u8], tile: &mut Tile<TILE>) {
    let (heights, rest) = record.split_at(TILE * TILE * 2);
    let (colors, bounds) = rest.split_at(TILE * TILE * 3);
    let points = heights.chunks_exact(2).zip(bounds.chunks_exact(2));
    for (i, ((h, b), c)) in points.zip(colors.chunks_exact(3)).enumerate() {
        let (row, column) = (i / TILE, i % TILE);
        tile.heights[row][column] = u16::from_le_bytes([h[0], h[1]]);
        tile.bounds[row][column] = u16::from_le_bytes([b[0], b[1]]);
        tile.colors[row][column] = [c[0], c[1], c[2]];
    }
}

/// Writes a `.tiles` file tile by tile, in any order.
pub(crate) struct TilesWriter {
    file: BufWriter<File>,
    header: Header,
    checksums: Vec<u32>,
    record: Vec<u8>,
    position: u64,
    photos: Photos,
    photo_checksums: Vec<u32>,
}

impl TilesWriter {
    /// A file of `header`'s tiles and of the tiles of the photos over
    /// `photos`.
    pub fn create(path: &Path, header: Header, photos: Vec<DetailArea>) -> Result<Self> {
        let fail = |e: std::io::Error| Error::new(format!("cannot write {}: {e}", path.display()));
        let photos = Photos::new(photos);
        let file = File::create(path).map_err(fail)?;
        file.set_len(header.file_bytes() + photos.bytes())
            .map_err(fail)?;
        Ok(Self {
            file: BufWriter::with_capacity(1 << 20, file),
            header,
            checksums: vec![0; header.tiles as usize],
            record: Vec::with_capacity(RECORD_BYTES),
            position: u64::MAX,
            photo_checksums: vec![0; photos.tiles as usize],
            photos,
        })
    }

    /// Writes `bytes` at `offset`, seeking only when the last write did
    /// not end there.
    fn write_at(&mut self, offset: u64, bytes: &[u8]) -> Result<()> {
        let io = |e: std::io::Error| Error::new(format!("cannot write tile: {e}"));
        if offset != self.position {
            self.file.seek(SeekFrom::Start(offset)).map_err(io)?;
        }
        self.file.write_all(bytes).map_err(io)?;
        self.position = offset + bytes.len() as u64;
        Ok(())
    }

    /// Writes photo tile `key`.
    pub fn write_photo(&mut self, key: PhotoKey, tile: &PhotoTile<TILE>) -> Result<()> {
        let index = self.photos.index(key).ok_or_else(|| {
            Error::new(format!("photo tile {key:?} is outside the packed photos"))
        })?;
        let mut record = std::mem::take(&mut self.record);
        record.clear();
        tile.texels
            .iter()
            .flatten()
            .for_each(|c| record.extend_from_slice(c));
        self.photo_checksums[index as usize] = crc32fast::hash(&record);
        let offset = self.photos.record_offset(self.header.file_bytes(), index);
        let written = self.write_at(offset, &record);
        self.record = record;
        written
    }

    pub fn write(&mut self, key: TileKey, tile: &Tile<TILE>) -> Result<()> {
        let index = self
            .header
            .index(key)
            .ok_or_else(|| Error::new(format!("tile {key:?} is outside the packed map")))?;
        let mut record = std::mem::take(&mut self.record);
        encode(tile, &mut record);
        self.checksums[index as usize] = crc32fast::hash(&record);
        let written = self.write_at(self.header.record_offset(index), &record);
        self.record = record;
        written
    }

    /// Writes the header (with the final highest height), the checksums
    /// and `sticks`, the table level 0's tiles name their points' sticks
    /// in (empty without objects).
    pub fn finish(mut self, max_height: u16, roughness: u8, sticks: &StickTable<'_>) -> Result<()> {
        let io = |e: std::io::Error| Error::new(format!("cannot finish the tiled file: {e}"));
        self.header.world.max_height = max_height;
        self.header.world.roughness = roughness;
        self.file.seek(SeekFrom::Start(0)).map_err(io)?;
        self.file.write_all(&self.header.bytes()).map_err(io)?;
        for c in &self.checksums {
            self.file.write_all(&c.to_le_bytes()).map_err(io)?;
        }
        self.file
            .seek(SeekFrom::Start(self.header.file_bytes()))
            .map_err(io)?;
        self.file.write_all(&self.photos.table()).map_err(io)?;
        for c in &self.photo_checksums {
            self.file.write_all(&c.to_le_bytes()).map_err(io)?;
        }
        self.file
            .seek(SeekFrom::Start(
                self.header.file_bytes() + self.photos.bytes(),
            ))
            .map_err(io)?;
        self.file.write_all(&stick_section(sticks)).map_err(io)?;
        self.file.flush().map_err(io)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_height_filter_has_its_own_header_byte() {
        for filter in HeightFilter::ALL {
            assert_eq!(filter_from_code(filter_code(filter)), Some(filter));
        }
        // Files packed before the wavelet keep their bytes.
        assert_eq!(filter_code(HeightFilter::Subsample), 2);
        assert_eq!(filter_from_code(4), None);
    }
}
