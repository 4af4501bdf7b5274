#![no_main]
//! SRTM `.hgt` tiles. The reader refuses any size but a square grid, so
//! the input is repeated to fill a 3-arc-second tile (1201 × 1201
//! big-endian samples, voids included) and also read at its own size.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("terracast-fuzz-hgt-{}", std::process::id()));
    if std::fs::create_dir_all(&dir).is_err() {
        return;
    }
    let path = dir.join("N44W072.hgt");
    let full: Vec<u8> = data.iter().copied().cycle().take(1201 * 1201 * 2).collect();
    for bytes in [data, &full[..]] {
        if std::fs::write(&path, bytes).is_ok() {
            let _ = terracast_sim::scene::load_heights(&path, 1.0);
        }
    }
});
