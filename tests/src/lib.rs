//! Shared helpers of the terracast integration tests: where the real data
//! lives, loading a Comanche pair, and rendering kernel and reference views.

use std::path::PathBuf;
use terracast::{Camera, Coherence, RenderOptions, Resolution};
use terracast_sim::frame::{Frame, RenderStats};
use terracast_sim::kernel::render_kernel;
use terracast_sim::reference::{Reference, ReferenceOptions};
use terracast_sim::scene::{load_pair, KernelScene, Scene};

/// The shared data folder: `$TERRACAST_DATA`, or `../shared/data` beside the
/// repository. The tests that need it fail with a clear message if it is
/// missing: the accuracy figures are meaningless without real terrain.
pub fn data_dir() -> PathBuf {
    let dir = std::env::var_os("TERRACAST_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data"));
    assert!(
        dir.join("comanche").is_dir(),
        "real terrain not found at {}: set TERRACAST_DATA to the shared data folder",
        dir.display()
    );
    dir
}

/// Loads Comanche color map `C{color}.png` over height map `D{height}.png`.
pub fn comanche(color: &str, height: &str) -> Scene {
    let dir = data_dir().join("comanche");
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
