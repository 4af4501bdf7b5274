//! Shared helpers of the terracast integration tests: where the real data
//! lives, loading a Comanche pair, and rendering kernel and reference views.

use std::io::Write;
use std::path::{Path, PathBuf};
use terracast::{Camera, Coherence, RenderOptions, Resolution};
use terracast_sim::frame::{Frame, RenderStats};
use terracast_sim::kernel::render_kernel;
use terracast_sim::reference::{Reference, ReferenceOptions};
use terracast_sim::scene::{load_pair, KernelScene, Scene};

/// The shared data folder that `$TERRACAST_DATA` names, for the tests that
/// need real terrain. Without the variable (a fresh clone) the test named
/// `test` is skipped: this says so on one line, past the test harness's
/// capture, and returns `None`. A variable that names a folder without the
/// data fails the test: CI sets it, and there a missing folder must not
/// pass quietly.
pub fn data_dir(test: &str) -> Option<PathBuf> {
    let Some(dir) = std::env::var_os("TERRACAST_DATA").map(PathBuf::from) else {
        // Straight to the terminal: the harness captures `println!`.
        let _ = writeln!(
            std::io::stderr(),
            "skipped {test}: no real terrain (set TERRACAST_DATA to the shared data folder)"
        );
        return None;
    };
    assert!(
        dir.join("comanche").is_dir(),
        "TERRACAST_DATA is {}, which holds no comanche folder",
        dir.display()
    );
    Some(dir)
}

/// Loads Comanche color map `C{color}.png` over height map `D{height}.png`
/// from the shared data folder `data`.
pub fn comanche(data: &Path, color: &str, height: &str) -> Scene {
    let dir = data.join("comanche");
    let (h, c) = (
        dir.join(format!("D{height}.png")),
        dir.join(format!("C{color}.png")),
    );
    load_pair(&h, Some(&c), 1.0, 0).expect("Comanche maps")
}

/// Renders with the kernel at the given coherence and resolution.
pub fn kernel_view(
    scene: &KernelScene,
    cam: &Camera,
    size: (u32, u32),
    coherence: Coherence,
    resolution: Resolution,
) -> (Frame, RenderStats) {
    let options = RenderOptions {
        coherence,
        resolution,
        ..RenderOptions::default()
    };
    kernel_render(scene, cam, size, &options)
}

/// Renders with the kernel at any options.
pub fn kernel_render(
    scene: &KernelScene,
    cam: &Camera,
    size: (u32, u32),
    options: &RenderOptions,
) -> (Frame, RenderStats) {
    render_kernel(scene, cam, size.0, size.1, options).expect("kernel render")
}

/// Renders the exact reference at 4 × 4 rays a pixel.
pub fn reference_view(reference: &Reference<'_>, cam: &Camera, size: (u32, u32)) -> Frame {
    reference
        .render(cam, size.0, size.1, &ReferenceOptions::default())
        .0
}
