//! Shared helpers of the terracast integration tests: where the real data
//! lives, loading a Comanche pair, rendering kernel and reference views,
//! and writing georeferenced GeoTIFFs.

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

/// The kernel's frames without and with an atmosphere (`[k, fk]`) against
/// the reference's rendered the same ways (`[r, fr]`): the PSNR without it,
/// the PSNR with it and the sky agreement with it, printed as one line
/// after `name`. Panics when the atmosphere left the kernel's frame as it
/// was.
pub fn atmosphere_against_reference(
    name: &str,
    [k, fk]: [&Frame; 2],
    [r, fr]: [&Frame; 2],
) -> (f64, f64, f64) {
    use terracast_sim::metrics::{psnr, sky_agreement};
    let (without, with) = (psnr(&k.colors, &r.colors), psnr(&fk.colors, &fr.colors));
    let agree = sky_agreement(&fk.depth, &fr.depth);
    println!(
        "{name}: PSNR {without:6.2} dB without the atmosphere, {with:6.2} dB with it ({:+.2} dB), sky agreement {:.3} %",
        with - without,
        agree * 100.0
    );
    assert_ne!(k.colors, fk.colors, "{name}: the atmosphere shows");
    (without, with, agree)
}

/// Where a [`georeferenced_tiff`] lies: its top-left corner (ModelTiepoint)
/// and its pixel size (ModelPixelScale), in degrees when `geographic` (a
/// GeoKeyDirectory says so), else in meters.
#[derive(Debug, Clone, Copy)]
pub struct Georeference {
    pub origin: [f64; 2],
    pub pixel: f64,
    pub geographic: bool,
}

/// A GeoTIFF of `samples` (`w` × `d` of color type `C`), georeferenced by
/// `at`, with GDAL_NODATA `nodata` when given: what GDAL writes for an
/// elevation model or a photo, in memory.
pub fn georeferenced_tiff<C: tiff::encoder::colortype::ColorType>(
    (w, d): (u32, u32),
    samples: &[C::Inner],
    at: Georeference,
    nodata: Option<&str>,
) -> Vec<u8>
where
    [C::Inner]: tiff::encoder::TiffValue,
{
    use tiff::tags::Tag;
    let mut bytes = std::io::Cursor::new(Vec::new());
    {
        let mut encoder = tiff::encoder::TiffEncoder::new(&mut bytes).unwrap();
        let mut image = encoder.new_image::<C>(w, d).unwrap();
        let scale: &[f64] = &[at.pixel, at.pixel, 0.0];
        let tiepoint: &[f64] = &[0.0, 0.0, 0.0, at.origin[0], at.origin[1], 0.0];
        let encoder = image.encoder();
        encoder.write_tag(Tag::ModelPixelScaleTag, scale).unwrap();
        encoder.write_tag(Tag::ModelTiepointTag, tiepoint).unwrap();
        if at.geographic {
            // One key: GTModelTypeGeoKey (1024) = 2, geographic.
            let keys: &[u16] = &[1, 1, 0, 1, 1024, 0, 1, 2];
            encoder.write_tag(Tag::GeoKeyDirectoryTag, keys).unwrap();
        }
        if let Some(nodata) = nodata {
            encoder.write_tag(Tag::GdalNodata, nodata).unwrap();
        }
        image.write_data(samples).unwrap();
    }
    bytes.into_inner()
}
