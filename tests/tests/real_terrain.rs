//! Real terrain as it comes (`../shared/data`): GeoTIFF heights in
//! geographic and projected coordinates, photos placed by their
//! georeference over part of the terrain, and SRTM voids filled without
//! pits.

use std::path::PathBuf;
use terracast::Camera;
use terracast_sim::kernel::render_kernel;
use terracast_sim::scene::geotiff::{read_georef, read_heights, read_photo};
use terracast_sim::scene::{derived_height_scale, load_heights, load_scene_files};
use terracast_tests::data_dir;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("terracast-real-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn swellendam_renders_with_its_photos_where_they_lie() {
    let Some(data) = data_dir("swellendam_renders_with_its_photos_where_they_lie") else {
        return;
    };
    let (height, photos) = terracast_tests::swellendam_files(&data);
    let (scale, why) = derived_height_scale(&height).unwrap().unwrap();
    assert!(why.contains("latitude -34"), "{why}");
    // 90 m samples: a meter is about a 85th of a voxel.
    assert!((1.0 / scale - 85.0).abs() < 2.0, "{scale}");
    let with = load_scene_files(&height, &photos, scale, 1).unwrap();
    let without = load_scene_files(&height, &[], scale, 1).unwrap();
    // Above the second photo's middle, looking down: its colors, not the
    // height-and-slope colors around it.
    let grid = read_georef(&height).unwrap().unwrap();
    let photo = read_georef(&photos[1]).unwrap().unwrap();
    let (pw, ph) = read_photo(&photos[1]).unwrap().dimensions();
    let middle = [
        photo.origin[0] + photo.pixel[0] * f64::from(pw) / 2.0,
        photo.origin[1] - photo.pixel[1] * f64::from(ph) / 2.0,
    ];
    let (x, y) = (
        ((middle[0] - grid.origin[0]) / grid.pixel[0]) as f32,
        ((grid.origin[1] - middle[1]) / grid.pixel[1]) as f32,
    );
    let ground = with.height(x as usize, y as usize);
    let camera = Camera::looking([x, y, ground + 12.0], 90.0, 80.0);
    let render = |scene: &terracast_sim::scene::Scene| {
        render_kernel(
            &scene.to_kernel().unwrap(),
            &camera,
            64,
            48,
            &Default::default(),
        )
        .unwrap()
        .0
    };
    let (photo_view, plain_view) = (render(&with), render(&without));
    let differing = photo_view
        .colors
        .iter()
        .zip(&plain_view.colors)
        .filter(|(a, b)| a != b)
        .count();
    assert!(differing * 10 > 64 * 48 * 9, "{differing} pixels differ");
    // Outside the photos the terrain keeps its height-and-slope colors.
    assert_eq!(with.colors[0], without.colors[0]);
}

#[test]
fn fort_bragg_float_heights_are_projected_meters() {
    let Some(data) = data_dir("fort_bragg_float_heights_are_projected_meters") else {
        return;
    };
    let height = data.join("fortbragg").join("elevation_2012_1m.tif");
    let raster = read_heights(&height).unwrap();
    assert_eq!((raster.width, raster.depth), (450, 450));
    assert!(raster.values.iter().all(|v| v.is_finite()));
    let georef = raster.georef.unwrap();
    assert!(!georef.geographic);
    let (scale, _) = derived_height_scale(&height).unwrap().unwrap();
    assert!((scale - 1.0).abs() < 1e-3, "1 m samples: {scale}");
    let photo = data.join("fortbragg").join("naip_2012_rgb_1m.png");
    let scene = load_scene_files(&height, &[photo], scale, 1).unwrap();
    assert_eq!((scene.width, scene.depth), (450, 450));
}

#[test]
fn srtm_voids_are_filled_without_pits_and_counted() {
    let Some(data) = data_dir("srtm_voids_are_filled_without_pits_and_counted") else {
        return;
    };
    let source = data.join("srtm").join("N44W072_3arcsec.hgt");
    let mut bytes = std::fs::read(&source).unwrap();
    let side = 1201usize;
    // A 40 × 30 void in the mountains.
    let (x0, y0, w, h) = (600usize, 500usize, 40usize, 30usize);
    for y in y0..y0 + h {
        for x in x0..x0 + w {
            let i = 2 * (y * side + x);
            bytes[i..i + 2].copy_from_slice(&i16::MIN.to_be_bytes());
        }
    }
    let holed = temp("N44W072.hgt");
    std::fs::write(&holed, &bytes).unwrap();
    let (_, _, heights) = load_heights(&holed, 1.0).unwrap();
    let at = |x: usize, y: usize| heights[y * side + x];
    let ring_low = (y0 - 1..=y0 + h)
        .flat_map(|y| (x0 - 1..=x0 + w).map(move |x| (x, y)))
        .filter(|&(x, y)| x == x0 - 1 || x == x0 + w || y == y0 - 1 || y == y0 + h)
        .map(|(x, y)| at(x, y))
        .fold(f32::MAX, f32::min);
    let block_low = (y0..y0 + h)
        .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
        .map(|(x, y)| at(x, y))
        .fold(f32::MAX, f32::min);
    assert!(block_low >= ring_low, "a pit: {block_low} below {ring_low}");
    assert!(heights.iter().all(|h| h.is_finite() && *h > 0.0));
}
