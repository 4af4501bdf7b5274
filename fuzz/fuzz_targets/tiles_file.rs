#![no_main]
//! The tiled terrain file: its header and checksum table on open, then
//! every tile record of the first levels.
use libfuzzer_sys::fuzz_target;
use terracast::tiles::{Tile, TileKey, TileSource};
use terracast_sim::tiles::{TilesFile, TILE};

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("terracast-fuzz-{}.tiles", std::process::id()));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(mut file) = TilesFile::open(&path) {
        let world = file.world();
        let mut tile = Box::new(Tile::<TILE>::EMPTY);
        for level in 0..world.levels() {
            let (across, down) = world.tiles(level, TILE as u32);
            for y in 0..down.min(4) {
                for x in 0..across.min(4) {
                    let _ = file.load(TileKey { level, x, y }, &mut tile);
                }
            }
        }
    }
});
