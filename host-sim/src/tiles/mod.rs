//! Out-of-core terrain on the host: the tiled terrain file and `pack`, the
//! procedural source for huge terrains, and rendering and flying through
//! the kernel's tile cache.
//!
//! The host uses one cache shape: tiles of [`TILE`]² points (28 KiB each)
//! in [`SLOTS`] slots, 28 MiB of terrain at most; and, for photos finer
//! than the height grid, photo tiles of [`TILE`]² texels (12 KiB each) in
//! [`PHOTO_SLOTS`] slots, 24 MiB at most.

mod file;
mod pack;
mod paging;
mod procedural;

pub use file::{TilesFile, FORMAT_VERSION};
pub use pack::{pack, PackInput, PackSummary};
pub use paging::{
    footprint_beyond, new_photo_slots, page_flight, render_tiled, render_tiled_in, PageOptions,
    PageReport, PagedFrame, TiledRender, TiledViewer, PHOTO_SLOTS,
};
pub use procedural::ProceduralSource;

use crate::error::{Error, Result};
use std::path::Path;
use terracast::tiles::{PhotoKey, PhotoTile, Tile, TileError, TileKey, TileSource, World};
use terracast::{DetailArea, StickTable};

/// Points per tile side on the host.
pub const TILE: usize = 64;
/// Tile slots of the host's cache.
pub const SLOTS: usize = 1024;

/// A tile source chosen on the command line: `procedural:SIZE` or a
/// `.tiles` file.
#[derive(Debug)]
pub enum Terrain {
    /// Generated from coordinates.
    Procedural(ProceduralSource),
    /// Read from a packed file.
    File(TilesFile),
}

impl Terrain {
    /// Parses `procedural:SIZE` (SIZE the side in voxels, 2 to 2^30), or
    /// opens a `.tiles` file.
    pub fn open(spec: &str, seed: u64) -> Result<Self> {
        if let Some(size) = spec.strip_prefix("procedural:") {
            let side: u32 = size.parse().map_err(|_| {
                Error::new(format!(
                    "--terrain {spec}: SIZE must be a whole number of voxels, as in procedural:131072"
                ))
            })?;
            return ProceduralSource::new(side, seed).map(Self::Procedural);
        }
        TilesFile::open(Path::new(spec)).map(Self::File)
    }
}

impl TileSource<TILE> for Terrain {
    fn world(&self) -> World {
        match self {
            Self::Procedural(s) => s.world(),
            Self::File(s) => s.world(),
        }
    }
    fn photos(&self) -> &[DetailArea] {
        match self {
            Self::Procedural(_) => &[],
            Self::File(s) => s.photos(),
        }
    }
    fn load_photo(
        &mut self,
        key: PhotoKey,
        tile: &mut PhotoTile<TILE>,
    ) -> std::result::Result<usize, TileError> {
        match self {
            Self::Procedural(_) => Err(TileError::Missing),
            Self::File(s) => s.load_photo(key, tile),
        }
    }
    fn load(
        &mut self,
        key: TileKey,
        tile: &mut Tile<TILE>,
    ) -> std::result::Result<usize, TileError> {
        match self {
            Self::Procedural(s) => s.load(key, tile),
            Self::File(s) => s.load(key, tile),
        }
    }
    fn sticks(&self) -> StickTable<'_> {
        match self {
            Self::Procedural(_) => StickTable::EMPTY,
            Self::File(s) => s.sticks(),
        }
    }
}

/// The host cache's slots, on the heap.
pub fn new_slots() -> Box<[Tile<TILE>; SLOTS]> {
    let slots = vec![Tile::<TILE>::EMPTY; SLOTS].into_boxed_slice();
    // The length is SLOTS by construction.
    slots.try_into().unwrap_or_else(|_| unreachable!())
}
