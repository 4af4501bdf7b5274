//! Bakes the board scene into the firmware and puts `memory.x` on the
//! linker's path.
//!
//! The scene comes from `TERRACAST_BOARD_SCENE` (a file written by
//! `terracast-sim board scene`), by default `../target/board/scene.tcb`.
//! Its header fixes the sizes of the firmware's static buffers.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let manifest =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));

    let memory = manifest.join("../memory.x");
    fs::copy(&memory, out.join("memory.x")).expect("copy memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory.display());

    println!("cargo:rerun-if-env-changed=TERRACAST_BOARD_SCENE");
    let scene = env::var_os("TERRACAST_BOARD_SCENE")
        .map(PathBuf::from)
        .unwrap_or_else(|| manifest.join("../target/board/scene.tcb"));
    println!("cargo:rerun-if-changed={}", scene.display());
    let bytes = fs::read(&scene).unwrap_or_else(|e| {
        panic!(
            "cannot read the board scene {}: {e}; write it with `terracast-sim board scene --out {}` (scripts/board-check does)",
            scene.display(),
            scene.display()
        )
    });
    let header = terracast_board::scene::Header::decode(&bytes)
        .unwrap_or_else(|e| panic!("{}: {e}", scene.display()));
    // Objects may follow the colors; the firmware checks them at boot.
    if bytes.len() < header.file_bytes() {
        panic!(
            "{}: {} bytes, but its header says at least {}",
            scene.display(),
            bytes.len(),
            header.file_bytes()
        );
    }
    let scene_path = fs::canonicalize(&scene).expect("scene path");
    let generated = format!(
        "/// Map width of the baked-in scene.\n\
         pub const MAP_WIDTH: u32 = {};\n\
         /// Map depth of the baked-in scene.\n\
         pub const MAP_DEPTH: u32 = {};\n\
         /// Image width of the scene's views.\n\
         pub const IMAGE_WIDTH: u32 = {};\n\
         /// Image height of the scene's views.\n\
         pub const IMAGE_HEIGHT: u32 = {};\n\
         /// The scene file, aligned so that its heights can be read in place.\n\
         pub static SCENE: &Aligned<[u8]> = &Aligned(*include_bytes!({:?}));\n",
        header.map_width, header.map_depth, header.image_width, header.image_height, scene_path
    );
    fs::write(out.join("scene.rs"), generated).expect("write scene.rs");
}
