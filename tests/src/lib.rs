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

/// The Swellendam set in the shared data folder `data`: its SRTM heights
/// (float32 GeoTIFF, degrees) and its two 2.5 m photos.
pub fn swellendam_files(data: &Path) -> (PathBuf, [PathBuf; 2]) {
    let dir = data.join("swellendam");
    (
        dir.join("srtm_41_19_4326.tif"),
        [
            dir.join("3320D_2010_315_RGB_LATLNG.tif"),
            dir.join("3420B_2010_328_RGB_LATLNG.tif"),
        ],
    )
}

/// A near view: the point it is over, its height above the ground there,
/// yaw and pitch (degrees).
pub type NearView = ([f32; 2], f32, f32, f32);

/// Two near views over each photo kept finer than `scene`'s grid: from
/// its middle along its long side, 3 voxels up, and from past its first
/// corner, 5 up.
pub fn near_photo_views(scene: &Scene) -> Vec<NearView> {
    let mut views = Vec::new();
    for detail in &scene.details {
        let [ox, oy] = detail.origin.map(|v| v as f32);
        let [w, d] = detail.size.map(|v| v as f32);
        let (cx, cy) = (ox + w / 2.0, oy + d / 2.0);
        let along = if d >= w { 90.0 } else { 0.0 };
        views.push(([cx, cy], 3.0, along, 30.0));
        views.push(([ox + 2.0, oy + 2.0], 5.0, 45.0, 40.0));
    }
    views
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

/// A float32 GeoTIFF of `samples` (`w` × `d`) stored in `tile` × `tile`
/// tiles (a multiple of 16; the tiles past the edges padded with 0),
/// georeferenced by `at`: how GDAL writes a tiled or cloud-optimized
/// elevation model, uncompressed, in memory. (The `tiff` crate writes
/// strips only, so the file is laid out here.)
pub fn tiled_float_tiff(
    (w, d): (u32, u32),
    samples: &[f32],
    tile: u32,
    at: Georeference,
) -> Vec<u8> {
    const SHORT: u16 = 3;
    const LONG: u16 = 4;
    const DOUBLE: u16 = 12;
    let (across, down) = (w.div_ceil(tile), d.div_ceil(tile));
    let tiles = (across * down) as usize;
    let tile_bytes = (tile * tile * 4) as usize;
    // Header, then the directory, then its values too long for an
    // entry, then the tiles.
    let mut entries: Vec<(u16, u16, Vec<u8>)> = vec![
        (256, LONG, w.to_le_bytes().to_vec()),
        (257, LONG, d.to_le_bytes().to_vec()),
        (258, SHORT, 32u16.to_le_bytes().to_vec()),
        (259, SHORT, 1u16.to_le_bytes().to_vec()),
        (262, SHORT, 1u16.to_le_bytes().to_vec()),
        (277, SHORT, 1u16.to_le_bytes().to_vec()),
        (284, SHORT, 1u16.to_le_bytes().to_vec()),
        (322, LONG, tile.to_le_bytes().to_vec()),
        (323, LONG, tile.to_le_bytes().to_vec()),
        // The tiles' offsets: placeholders, filled in below.
        (324, LONG, vec![0; tiles * 4]),
        (
            325,
            LONG,
            (0..tiles)
                .flat_map(|_| (tile_bytes as u32).to_le_bytes())
                .collect(),
        ),
        (339, SHORT, 3u16.to_le_bytes().to_vec()),
        (
            33550,
            DOUBLE,
            [at.pixel, at.pixel, 0.0]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
        ),
        (
            33922,
            DOUBLE,
            [0.0, 0.0, 0.0, at.origin[0], at.origin[1], 0.0]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
        ),
    ];
    if at.geographic {
        // One key: GTModelTypeGeoKey (1024) = 2, geographic.
        let keys: [u16; 8] = [1, 1, 0, 1, 1024, 0, 1, 2];
        entries.push((
            34735,
            SHORT,
            keys.iter().flat_map(|k| k.to_le_bytes()).collect(),
        ));
    }
    let size_of = |kind: u16| match kind {
        SHORT => 2,
        LONG => 4,
        _ => 8,
    };
    let directory = 8 + 2 + entries.len() * 12 + 4;
    let values: usize = entries
        .iter()
        .map(|(_, _, v)| if v.len() > 4 { v.len() } else { 0 })
        .sum();
    let first_tile = directory + values;
    let offsets: Vec<u8> = (0..tiles)
        .flat_map(|i| ((first_tile + i * tile_bytes) as u32).to_le_bytes())
        .collect();
    entries[9].2 = offsets;
    let mut out = b"II".to_vec();
    out.extend(42u16.to_le_bytes());
    out.extend(8u32.to_le_bytes());
    out.extend((entries.len() as u16).to_le_bytes());
    let mut extra: Vec<u8> = Vec::new();
    for (tag, kind, value) in &entries {
        out.extend(tag.to_le_bytes());
        out.extend(kind.to_le_bytes());
        out.extend(((value.len() / size_of(*kind)) as u32).to_le_bytes());
        if value.len() <= 4 {
            let mut inline = value.clone();
            inline.resize(4, 0);
            out.extend(inline);
        } else {
            out.extend(((directory + extra.len()) as u32).to_le_bytes());
            extra.extend(value);
        }
    }
    out.extend(0u32.to_le_bytes());
    out.extend(extra);
    assert_eq!(out.len(), first_tile);
    for ty in 0..down {
        for tx in 0..across {
            for y in ty * tile..(ty + 1) * tile {
                for x in tx * tile..(tx + 1) * tile {
                    let v = if x < w && y < d {
                        samples[(y * w + x) as usize]
                    } else {
                        0.0
                    };
                    out.extend(v.to_le_bytes());
                }
            }
        }
    }
    out
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
