//! Running the `terracast-sim` binary from integration tests.

use std::path::Path;
use std::process::Command;

/// Runs `terracast-sim` with `args`: (exit code, stdout, stderr).
pub fn sim(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_terracast-sim"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Writes a 16 x 16 height map (a gentle slope) and color map (a red ramp).
// Each test crate includes this module; not all of them make maps.
#[allow(dead_code)]
pub fn write_small_maps(height: &Path, color: &Path) {
    image::GrayImage::from_fn(16, 16, |x, y| image::Luma([(x * 3 + y) as u8]))
        .save(height)
        .unwrap();
    image::RgbImage::from_fn(16, 16, |x, _| image::Rgb([x as u8 * 10, 100, 50]))
        .save(color)
        .unwrap();
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}
