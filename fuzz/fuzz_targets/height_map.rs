#![no_main]
//! Height maps: a PNG, read by the loader `render`, `fly` and `pack` use
//! (the `image` crate underneath).
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("terracast-fuzz-{}.png", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = terracast_sim::scene::load_heights(&path, 1.0);
    }
});
