#![no_main]
//! Color maps: a PNG stretched over a 16 × 16 height grid, as `render`,
//! `fly` and `pack` load it.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path =
        std::env::temp_dir().join(format!("terracast-fuzz-{}-color.png", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = terracast_sim::scene::load_colors(&path, 16, 16);
    }
});
