#![no_main]
//! GeoTIFF heights (any sample format, no-data, voids filled), photos and
//! the georeference, read from whatever bytes come.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("terracast-fuzz-tif-{}", std::process::id()));
    if std::fs::create_dir_all(&dir).is_err() {
        return;
    }
    let path = dir.join("input.tif");
    if std::fs::write(&path, data).is_ok() {
        let _ = terracast_sim::scene::derived_height_scale(&path);
        let _ = terracast_sim::scene::load_heights(&path, 1.0);
        let _ = terracast_sim::scene::load_colors(&path, 8, 8);
    }
});
