//! Out-of-core terrain: packed files render as their PNGs do, bit for bit;
//! a flight over 64 GiB of procedural terrain pages through a 28 MiB cache
//! with no frame drawn short of a tile after the first; damaged files,
//! failing and slow sources never stop a frame, and over a thousand frames
//! from a source that fails, stalls and hands back damaged tiles at random
//! no damaged tile is ever drawn.

use std::path::{Path, PathBuf};
use std::time::Duration;
use terracast::tiles::{
    cut_photo_tile, cut_stick_points, cut_tile, photo_tiles as photo_tiles_of, PhotoKey, PhotoTile,
    Tile, TileError, TileKey, TileSource, World,
};
use terracast::{Camera, HeightFilter, RenderOptions};
use terracast_sim::kernel::{render_kernel, PixelRays};
use terracast_sim::scene::{load_scene_files, procedural, Scene};
use terracast_sim::tiles::{
    pack, page_flight, render_tiled, PackInput, PageOptions, ProceduralSource, TilesFile, TILE,
};
use terracast_tests::{georeferenced_tiff, tiled_float_tiff, Georeference};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("terracast-tiles-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn pack_input(height: &Path, colors: &[&Path], scale: f32, filter: HeightFilter) -> PackInput {
    PackInput {
        height: height.to_path_buf(),
        colors: colors.iter().map(|c| c.to_path_buf()).collect(),
        height_scale: scale,
        filter,
        seed: 1,
        objects: false,
        place: None,
    }
}

/// A 203 x 150 crop of the built-in scene as a 16-bit height PNG (1/16
/// voxel a unit) and an RGB color PNG.
fn odd_sized_maps() -> (PathBuf, PathBuf) {
    let scene = procedural(256, 3);
    let (w, d) = (203u32, 150u32);
    let mut heights = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::new(w, d);
    let mut colors = image::RgbImage::new(w, d);
    for y in 0..d {
        for x in 0..w {
            let h = scene.height(x as usize, y as usize);
            heights.put_pixel(x, y, image::Luma([(h * 16.0).round() as u16]));
            colors.put_pixel(x, y, image::Rgb(scene.colors[(y * 256 + x) as usize]));
        }
    }
    let (hp, cp) = (temp("odd-h.png"), temp("odd-c.png"));
    heights.save(&hp).unwrap();
    colors.save(&cp).unwrap();
    (hp, cp)
}

fn views(w: f32, d: f32, top: f32) -> Vec<Camera> {
    [
        ([w * 0.5, d * 0.1, top + 20.0], 90.0, 15.0),
        ([-30.0, d * 0.5, top + 60.0], 10.0, 30.0),
        ([w * 0.3, d * 0.8, top * 0.6], 250.0, 4.0),
        ([w * 0.5, d * 0.5, top + 300.0], 0.0, 90.0),
    ]
    .into_iter()
    .map(|(eye, yaw_deg, pitch_deg)| Camera::looking(eye, yaw_deg, pitch_deg))
    .collect()
}

/// Checks that `file` holds the photos of `kernel` kept finer than its
/// grid, every photo tile as the photo in memory cuts it; returns the
/// photo tiles.
fn photo_tiles_as_in_memory(
    file: &mut TilesFile,
    kernel: &terracast_sim::scene::KernelScene,
    name: &str,
) -> u64 {
    let details = kernel.details().unwrap();
    assert_eq!(
        file.photos(),
        details.iter().map(|d| d.area()).collect::<Vec<_>>(),
        "{name}"
    );
    let (mut from_file, mut cut) = (
        Box::new(PhotoTile::<TILE>::EMPTY),
        Box::new(PhotoTile::EMPTY),
    );
    let mut photo_tiles = 0;
    for (photo, detail) in details.iter().enumerate() {
        for level in 0..=detail.shift() {
            let (tx, ty) = photo_tiles_of(&detail.area(), level, TILE as u32);
            for y in 0..ty {
                for x in 0..tx {
                    let key = PhotoKey {
                        photo: photo as u8,
                        level: level as u8,
                        x,
                        y,
                    };
                    file.load_photo(key, &mut from_file).unwrap();
                    assert!(cut_photo_tile(detail, key, &mut cut));
                    assert!(from_file == cut, "{name}: photo tile {key:?} differs");
                    photo_tiles += 1;
                }
            }
        }
    }
    photo_tiles
}

/// Checks that every tile of `file` is as `pyramid` cuts it (with
/// `layer`'s points in level 0's tiles, when the map has objects); returns
/// the tiles.
fn tiles_as_cut(
    file: &mut TilesFile,
    pyramid: &terracast::Pyramid<'_>,
    layer: Option<&terracast::StickLayer<'_>>,
    name: &str,
) -> u64 {
    let world = file.world();
    let (mut from_file, mut cut) = (Box::new(Tile::<TILE>::EMPTY), Box::new(Tile::EMPTY));
    let mut tiles = 0;
    for level in 0..world.levels() {
        let (tx, ty) = world.tiles(level, TILE as u32);
        for y in 0..ty {
            for x in 0..tx {
                let key = TileKey { level, x, y };
                file.load(key, &mut from_file).unwrap();
                assert!(cut_tile(pyramid, key, &mut cut));
                if let Some(layer) = layer {
                    cut_stick_points(layer, (world.width, world.depth), key, &mut cut);
                }
                assert!(
                    from_file == cut,
                    "{name}: tile {key:?} differs from the pyramid's"
                );
                tiles += 1;
            }
        }
    }
    tiles
}

/// Packs the maps with `filter`, then checks every tile against the pyramid
/// in memory and every view against the render from the maps.
fn packed_equals_maps(
    height: &Path,
    colors: &[&Path],
    scale: f32,
    filter: HeightFilter,
    name: &str,
) {
    let out = temp(name);
    let input = pack_input(height, colors, scale, filter);
    let summary = pack(&input, &out, &mut |_, _| {}).unwrap();
    let scene = load_scene_files(height, &input.colors, scale, 1).unwrap();
    let kernel = scene.to_kernel_with(filter).unwrap();
    let pyramid = kernel.pyramid().unwrap();
    let mut file = TilesFile::open(&out).unwrap();
    let world = file.world();
    assert_eq!((world.width, world.depth), (scene.width, scene.depth));
    // The packer measured the roughness on the rows the pyramid does.
    assert_eq!(world.roughness, pyramid.roughness(), "{name}");
    let tiles = tiles_as_cut(&mut file, &pyramid, None, name);
    assert_eq!(tiles, summary.tiles);
    // A photo finer than the grid is packed at its own resolution: every
    // photo tile as the kernel's detail in memory cuts it.
    let photo_tiles = photo_tiles_as_in_memory(&mut file, &kernel, name);
    assert_eq!(photo_tiles, summary.photo_tiles);
    let top = scene.max_height();
    for camera in views(scene.width as f32, scene.depth as f32, top) {
        let options = RenderOptions::default();
        let (from_maps, _) = render_kernel(&kernel, &camera, 96, 72, &options).unwrap();
        let (from_tiles, _, tiled) =
            render_tiled(&mut file, &camera, 96, 72, &options, PixelRays::Fixed).unwrap();
        assert!(from_maps.colors == from_tiles.colors, "{name}: {camera:?}");
        assert_eq!(
            (tiled.misses, tiled.photo_misses, tiled.degraded_samples),
            (0, 0, 0),
            "{name}: {camera:?}"
        );
        assert!(tiled.resident_bytes > 0 && tiled.tiles_loaded as usize == tiled.footprint_tiles);
    }
    println!(
        "{name}: {}x{}, {} levels, {} tiles and {} photo tiles, {} bytes, {filter:?} heights: every tile and view identical",
        summary.width, summary.depth, summary.levels, summary.tiles, summary.photo_tiles, summary.bytes
    );
}

#[test]
fn packed_files_render_as_their_maps_bit_for_bit() {
    let (height, color) = odd_sized_maps();
    // Every height filter: the pack streams each with its own code.
    for filter in HeightFilter::ALL {
        packed_equals_maps(&height, &[&color], 1.0 / 16.0, filter, "odd.tiles");
    }
    // Without a color map, colored by height and slope as `render` does.
    let default = HeightFilter::default();
    packed_equals_maps(&height, &[], 1.0 / 16.0, default, "odd-gray.tiles");
    // A color map twice as fine: kept at its own resolution as `render`
    // keeps it, in photo tiles, and the grid's colors the mean of each
    // point's texels; loaded whole.
    let fine = temp("odd-c2.png");
    let odd = image::open(&color).unwrap().to_rgb8();
    image::imageops::resize(&odd, 406, 300, image::imageops::FilterType::Nearest)
        .save(&fine)
        .unwrap();
    packed_equals_maps(&height, &[&fine], 1.0 / 16.0, default, "odd-fine.tiles");
    let summary = pack(
        &pack_input(&height, &[&fine], 1.0 / 16.0, default),
        &temp("odd-fine-again.tiles"),
        &mut |_, _| {},
    )
    .unwrap();
    assert!(summary.streamed);
    // A color map coarser than the grid: stretched bilinear, streamed.
    let coarse = temp("odd-c-half.png");
    image::imageops::resize(&odd, 101, 75, image::imageops::FilterType::Triangle)
        .save(&coarse)
        .unwrap();
    packed_equals_maps(&height, &[&coarse], 1.0 / 16.0, default, "odd-coarse.tiles");
    if let Some(data) = terracast_tests::data_dir("the Comanche and SRTM packs") {
        let comanche = data.join("comanche");
        packed_equals_maps(
            &comanche.join("D7.png"),
            &[&comanche.join("C7W.png")],
            1.0,
            default,
            "c7w.tiles",
        );
        packed_equals_maps(
            &data.join("srtm/N44W072_3arcsec.hgt"),
            &[],
            1.0 / 8.0,
            default,
            "srtm.tiles",
        );
    }
}

/// The odd-sized maps' heights (1/16 voxel a unit) as a square SRTM
/// `.hgt` (big-endian i16) with a 9 × 7 void (−32768) in its middle.
fn hgt_with_a_void() -> PathBuf {
    let scene = procedural(256, 3);
    let side = 97usize;
    let bytes: Vec<u8> = (0..side * side)
        .flat_map(|i| {
            let (x, y) = (i % side, i / side);
            let void = (40..49).contains(&x) && (45..52).contains(&y);
            let h = if void {
                i16::MIN
            } else {
                (scene.height(x, y) * 16.0).round() as i16
            };
            h.to_be_bytes()
        })
        .collect();
    let path = temp("void.hgt");
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn an_hgt_with_voids_packs_as_render_loads_it() {
    // The void is filled as `render` fills it: no pit down to height 0.
    let hgt = hgt_with_a_void();
    packed_equals_maps(&hgt, &[], 1.0 / 16.0, HeightFilter::default(), "void.tiles");
    // Streamed, the fill holding the void's rows and one each side.
    let summary = pack(
        &pack_input(&hgt, &[], 1.0 / 16.0, HeightFilter::default()),
        &temp("void-again.tiles"),
        &mut |_, _| {},
    )
    .unwrap();
    assert!(summary.streamed);
    assert_eq!((summary.voids, summary.void_rows_held_at_most), (63, 9));
    // A tile more void than not is refused in one line, and nothing is
    // written.
    let mostly = temp("mostly-void.hgt");
    let side = 50usize;
    let samples: Vec<u8> = (0..side * side)
        .flat_map(|i| if i % 3 == 0 { 100i16 } else { i16::MIN }.to_be_bytes())
        .collect();
    std::fs::write(&mostly, samples).unwrap();
    let out = temp("mostly-void.tiles");
    let e = pack(
        &pack_input(&mostly, &[], 1.0, HeightFilter::default()),
        &out,
        &mut |_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("mostly void") && !e.contains('\n'), "{e}");
    assert!(!out.exists());
    let scene = load_scene_files(&hgt, &[], 1.0 / 16.0, 1).unwrap();
    let lowest = |points: &mut dyn Iterator<Item = (usize, usize)>| {
        points
            .map(|(x, y)| scene.height(x, y))
            .fold(f32::MAX, f32::min)
    };
    let rim = lowest(
        &mut (39..=49)
            .flat_map(|x| (44..=52).map(move |y| (x, y)))
            .filter(|&(x, y)| x == 39 || x == 49 || y == 44 || y == 52),
    );
    let filled = lowest(&mut (40..49).flat_map(|x| (45..52).map(move |y| (x, y))));
    assert!(
        filled >= rim && rim > 0.0,
        "a pit: {filled} inside a rim at {rim}"
    );
}

/// The odd-sized maps' size, and their heights as floats (voxels).
const ODD_SIZE: (u32, u32) = (203, 150);

fn odd_sized_float_heights(scene: &Scene) -> Vec<f32> {
    let (w, d) = ODD_SIZE;
    (0..w * d)
        .map(|i| scene.height((i % w) as usize, (i / w) as usize))
        .collect()
}

#[test]
fn geotiff_heights_and_photo_pack_as_render_loads_them() {
    use tiff::encoder::{colortype, TiffEncoder};
    // The odd-sized maps as a float32 TIFF of heights (no georeference:
    // read with a note) and an RGB TIFF photo.
    let (scene, (w, d)) = (procedural(256, 3), ODD_SIZE);
    let heights = odd_sized_float_heights(&scene);
    let colors: Vec<u8> = (0..w * d)
        .flat_map(|i| scene.colors[((i / w) * 256 + i % w) as usize])
        .collect();
    let (height, photo) = (temp("odd-h.tif"), temp("odd-c.tif"));
    let mut encoder = TiffEncoder::new(std::fs::File::create(&height).unwrap()).unwrap();
    encoder
        .write_image::<colortype::Gray32Float>(w, d, &heights)
        .unwrap();
    let mut encoder = TiffEncoder::new(std::fs::File::create(&photo).unwrap()).unwrap();
    encoder
        .write_image::<colortype::RGB8>(w, d, &colors)
        .unwrap();
    packed_equals_maps(
        &height,
        &[&photo],
        1.0,
        HeightFilter::default(),
        "odd-tif.tiles",
    );
}

/// A georeferenced GeoTIFF (geographic, `pixel` degrees a pixel, its
/// top-left corner at `origin`) of `samples`, written to `name`.
fn geotiff<C: tiff::encoder::colortype::ColorType>(
    name: &str,
    size: (u32, u32),
    samples: &[C::Inner],
    origin: [f64; 2],
    pixel: f64,
) -> PathBuf
where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let at = Georeference {
        origin,
        pixel,
        geographic: true,
    };
    let path = temp(name);
    std::fs::write(&path, georeferenced_tiff::<C>(size, samples, at, None)).unwrap();
    path
}

#[test]
fn several_photos_pack_as_render_drapes_them() {
    use tiff::encoder::colortype;
    // The odd-sized heights over 0.001° a sample from (20°, −34°), and two
    // photos at twice that resolution: one over the west half, one over a
    // band across the middle, which lies over the first where they meet.
    let (scene, (w, d)) = (procedural(256, 3), ODD_SIZE);
    let heights = odd_sized_float_heights(&scene);
    let grid =
        geotiff::<colortype::Gray32Float>("geo-h.tif", (w, d), &heights, [20.0, -34.0], 0.001);
    let photo = |name: &str, (pw, pd): (u32, u32), origin: [f64; 2], tint: u8| {
        let pixels: Vec<u8> = (0..pw * pd)
            .flat_map(|i| {
                let c = scene.colors[(((i / pw) / 2) * 256 + (i % pw) / 2) as usize];
                [c[0] / 2 + tint, c[1], c[2]]
            })
            .collect();
        geotiff::<colortype::RGB8>(name, (pw, pd), &pixels, origin, 0.0005)
    };
    let west = photo("geo-west.tif", (200, 300), [20.0, -34.0], 0);
    let band = photo("geo-band.tif", (300, 80), [20.05, -34.05], 120);
    packed_equals_maps(
        &grid,
        &[&west, &band],
        1.0,
        HeightFilter::default(),
        "two-photos.tiles",
    );
    // Streamed: a few rows of each photo at a time.
    let summary = pack(
        &pack_input(&grid, &[&west, &band], 1.0, HeightFilter::default()),
        &temp("two-photos-again.tiles"),
        &mut |_, _| {},
    )
    .unwrap();
    assert!(summary.streamed);
    assert!(
        summary.photo_rows_held_at_most < 20,
        "{}",
        summary.photo_rows_held_at_most
    );
    // Both photos are on the packed terrain, the band over the west one
    // where they overlap, and the terrain neither covers is colored by
    // height.
    let draped = load_scene_files(&grid, &[west.clone(), band.clone()], 1.0, 1).unwrap();
    let alone = load_scene_files(&grid, &[west], 1.0, 1).unwrap();
    let by_height = load_scene_files(&grid, &[], 1.0, 1).unwrap();
    let at = |x: usize, y: usize| y * w as usize + x;
    assert_eq!(draped.colors[at(10, 10)], alone.colors[at(10, 10)]);
    assert_ne!(draped.colors[at(10, 10)], by_height.colors[at(10, 10)]);
    assert_ne!(draped.colors[at(60, 60)], alone.colors[at(60, 60)]);
    assert_eq!(draped.colors[at(190, 10)], by_height.colors[at(190, 10)]);
}

#[test]
fn swellendams_photos_pack_at_their_own_resolution_and_page_as_a_near_view_needs() {
    let Some(data) = terracast_tests::data_dir("swellendams_photos_pack_at_their_own_resolution")
    else {
        return;
    };
    let (height, photos) = terracast_tests::swellendam_files(&data);
    let (scale, _) = terracast_sim::scene::derived_height_scale(&height)
        .unwrap()
        .unwrap();
    let out = temp("swellendam.tiles");
    let input = PackInput {
        height: height.clone(),
        colors: photos.to_vec(),
        height_scale: scale,
        filter: HeightFilter::default(),
        seed: 1,
        objects: false,
        place: None,
    };
    let summary = pack(&input, &out, &mut |_, _| {}).unwrap();
    let scene = load_scene_files(&height, &photos, scale, 1).unwrap();
    let kernel = scene.to_kernel().unwrap();
    let in_memory: usize = kernel.details().unwrap().iter().map(|d| d.bytes()).sum();
    let mut file = TilesFile::open(&out).unwrap();
    assert_eq!(file.photos().len(), 2);
    // Streamed, a band of each photo's rows at a time, into the tiles the
    // photos loaded whole cut.
    assert!(summary.streamed);
    assert_eq!(
        photo_tiles_as_in_memory(&mut file, &kernel, "swellendam"),
        summary.photo_tiles
    );
    println!(
        "Swellendam packed, streamed: {} tiles and {} photo tiles, {:.1} MiB, holding at most {} rows of a photo; the photos' fine levels {:.1} MiB in memory",
        summary.tiles,
        summary.photo_tiles,
        summary.bytes as f64 / 1048576.0,
        summary.photo_rows_held_at_most,
        in_memory as f64 / 1048576.0
    );
    // Near views over each photo (as the photo-detail accuracy test's):
    // from the file through the caches as from the scene in memory, with
    // a small part of the photos resident.
    {
        for ([x, y], above, yaw, pitch) in terracast_tests::near_photo_views(&scene) {
            let ground = scene.height_at(f64::from(x), f64::from(y)) as f32;
            let camera = Camera::looking([x, y, ground + above], yaw, pitch);
            let options = RenderOptions::default();
            let (from_memory, _) = render_kernel(&kernel, &camera, 320, 240, &options).unwrap();
            let (from_tiles, _, tiled) =
                render_tiled(&mut file, &camera, 320, 240, &options, PixelRays::Fixed).unwrap();
            let photo_bytes = tiled.photo_tiles * PhotoTile::<TILE>::BYTES;
            println!(
                "  eye {x:.0}, {y:.0}, {:.1}: {} photo tiles resident ({:.1} MiB), {} degraded samples",
                ground + above,
                tiled.photo_tiles,
                photo_bytes as f64 / 1048576.0,
                tiled.degraded_samples
            );
            assert_eq!(tiled.photo_misses, 0, "{camera:?}");
            assert!(from_memory.colors == from_tiles.colors, "{camera:?}");
            assert!(
                (tiled.photo_tiles as u64) < summary.photo_tiles,
                "{camera:?}: every photo tile"
            );
        }
    }
}

#[test]
fn geotiff_heights_stream_into_a_pack_and_a_void_is_filled_as_render_fills_it() {
    use tiff::encoder::colortype;
    // The odd-sized heights as a georeferenced float32 GeoTIFF, no photo:
    // packed strip by strip.
    let (scene, (w, d)) = (procedural(256, 3), ODD_SIZE);
    let mut heights = odd_sized_float_heights(&scene);
    let grid =
        geotiff::<colortype::Gray32Float>("stream-h.tif", (w, d), &heights, [20.0, -34.0], 0.001);
    packed_equals_maps(
        &grid,
        &[],
        1.0,
        HeightFilter::default(),
        "geotiff-streamed.tiles",
    );
    // A block of no data: filled from its neighbours as the rows pass, to
    // the bit as `render` fills it loading the map whole.
    for y in 40..50 {
        for x in 60..75 {
            heights[(y * w + x) as usize] = f32::NAN;
        }
    }
    let voids =
        geotiff::<colortype::Gray32Float>("void-h.tif", (w, d), &heights, [20.0, -34.0], 0.001);
    packed_equals_maps(
        &voids,
        &[],
        1.0,
        HeightFilter::default(),
        "geotiff-voids.tiles",
    );
    // Tall, it holds a few strips of rows, not the map.
    let (tw, td) = (96u32, 3000u32);
    let tall: Vec<f32> = (0..tw * td)
        .map(|i| ((i % tw) * 7 + (i / tw) * 13) as f32 % 900.0)
        .collect();
    let path =
        geotiff::<colortype::Gray32Float>("stream-tall.tif", (tw, td), &tall, [20.0, -34.0], 0.001);
    let summary = pack(
        &pack_input(&path, &[], 1.0, HeightFilter::default()),
        &temp("stream-tall.tiles"),
        &mut |_, _| {},
    )
    .unwrap();
    assert!(summary.streamed);
    let held = summary.rows_held_at_most;
    assert!(held < 3000 / 3, "{held} rows held of 3000");
    // The map with voids streamed, the fill holding the block's rows and
    // the row each side of it.
    let summary = pack(
        &pack_input(&voids, &[], 1.0, HeightFilter::default()),
        &temp("void-again.tiles"),
        &mut |_, _| {},
    )
    .unwrap();
    assert!(summary.streamed);
    assert_eq!(summary.voids, 150);
    assert!(
        summary.void_rows_held_at_most <= 12,
        "{}",
        summary.void_rows_held_at_most
    );
    // Tall, with a void every 40 rows (a few points each, and one as wide
    // as the map): the fill holds a few rows, not the map.
    let mut holed = tall.clone();
    for y in (20..td).step_by(40) {
        let wide = y % 400 == 20;
        for x in 0..tw {
            if wide || (x + y) % 37 < 3 {
                holed[(y * tw + x) as usize] = f32::NAN;
            }
        }
    }
    let path =
        geotiff::<colortype::Gray32Float>("holed-tall.tif", (tw, td), &holed, [20.0, -34.0], 0.001);
    packed_equals_maps(&path, &[], 1.0, HeightFilter::default(), "holed-tall.tiles");
    let summary = pack(
        &pack_input(&path, &[], 1.0, HeightFilter::default()),
        &temp("holed-tall-again.tiles"),
        &mut |_, _| {},
    )
    .unwrap();
    assert!(summary.streamed && summary.voids > 0);
    assert!(
        summary.void_rows_held_at_most <= 3,
        "{}",
        summary.void_rows_held_at_most
    );
    assert!(summary.rows_held_at_most < 3000 / 3);
}

#[test]
fn a_geotiff_stored_in_tiles_streams_into_a_pack_a_row_of_tiles_at_a_time() {
    // The odd-sized heights (203 x 150) in 16 x 16 tiles, the last
    // column and row of tiles cut by the edges: packed tile for tile as
    // `render` loads the file, streamed.
    let (scene, (w, d)) = (procedural(256, 3), ODD_SIZE);
    let heights = odd_sized_float_heights(&scene);
    let at = Georeference {
        origin: [20.0, -34.0],
        pixel: 0.001,
        geographic: true,
    };
    let path = temp("tiled-h.tif");
    std::fs::write(&path, tiled_float_tiff((w, d), &heights, 16, at)).unwrap();
    let decoder = tiff::decoder::Decoder::new(std::fs::File::open(&path).unwrap()).unwrap();
    assert_eq!(decoder.get_chunk_type(), tiff::decoder::ChunkType::Tile);
    packed_equals_maps(
        &path,
        &[],
        1.0,
        HeightFilter::default(),
        "geotiff-tiled.tiles",
    );
    let summary = pack(
        &pack_input(&path, &[], 1.0, HeightFilter::default()),
        &temp("geotiff-tiled-again.tiles"),
        &mut |_, _| {},
    )
    .unwrap();
    assert!(summary.streamed);
    // Row by row, each row is the file's.
    let mut rows = terracast_sim::scene::geotiff::TiffHeightRows::open(&path).unwrap();
    for y in 0..d as usize {
        let row = rows.next_row().unwrap();
        assert_eq!(
            row,
            &heights[y * w as usize..(y + 1) * w as usize],
            "row {y}"
        );
    }
    assert!(rows.next_row().is_err());
    // Tiles of length 0 (the directory's ninth entry, TileLength): refused
    // in a line naming the file, by the streaming reader and by `render`'s.
    let mut zero = tiled_float_tiff((w, d), &heights, 16, at);
    assert_eq!(&zero[10 + 8 * 12..10 + 8 * 12 + 2], &323u16.to_le_bytes());
    zero[10 + 8 * 12 + 8..10 + 8 * 12 + 12].copy_from_slice(&0u32.to_le_bytes());
    let path = temp("tiled-zero-h.tif");
    std::fs::write(&path, zero).unwrap();
    let e = terracast_sim::scene::geotiff::TiffHeightRows::open(&path)
        .unwrap_err()
        .to_string();
    assert!(e.contains("tiled-zero-h.tif") && !e.contains('\n'), "{e}");
    assert!(terracast_sim::scene::load_heights(&path, 1.0).is_err());
}

#[test]
fn pack_holds_a_few_strips_of_rows_however_tall_the_map() {
    // 96 x 300 and 96 x 3000: at most a strip of rows and one of bounds a
    // level (12 levels at 3000 rows), far fewer than the map's rows.
    let held = |depth: u32| {
        let mut heights = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::new(96, depth);
        for (x, y, p) in heights.enumerate_pixels_mut() {
            *p = image::Luma([((x * 7 + y * 13) % 900) as u16 * 16]);
        }
        let path = temp(&format!("tall-{depth}.png"));
        heights.save(&path).unwrap();
        let out = temp(&format!("tall-{depth}.tiles"));
        pack(
            &pack_input(&path, &[], 1.0 / 16.0, HeightFilter::default()),
            &out,
            &mut |_, _| {},
        )
        .unwrap()
        .rows_held_at_most
    };
    let (short, tall) = (held(300), held(3000));
    println!("rows held at most: {short} for 300 rows, {tall} for 3000");
    let levels = World::new(96, 3000, 0).unwrap().levels() as usize;
    assert!(tall <= levels * 2 * (TILE + 4), "{short} then {tall}");
    assert!(tall < 3000 / 3, "{tall} rows held of 3000");
}

/// A map packed with objects (`pack --objects`) renders from its tiles as
/// `render --objects` draws it from the maps, bit for bit: every tile as
/// the pyramid with the objects' heights cuts it, level 0's tiles naming
/// the points' sticks, the file carrying the stick table; views from afar
/// and among the objects.
#[test]
fn objects_pack_into_tiles_and_render_as_from_the_maps() {
    let (height, color) = odd_sized_maps();
    let out = temp("objects.tiles");
    let input = PackInput {
        objects: true,
        ..pack_input(&height, &[&color], 1.0 / 16.0, HeightFilter::default())
    };
    let summary = pack(&input, &out, &mut |_, _| {}).unwrap();
    let mut scene = load_scene_files(&height, &input.colors, 1.0 / 16.0, 1).unwrap();
    let planted = scene.plant_objects(1);
    assert_eq!(summary.objects.as_deref(), Some(planted.as_str()));
    let kernel = scene.to_kernel().unwrap();
    let pyramid = kernel.pyramid().unwrap();
    let layer = kernel.sticks().unwrap().unwrap();
    let mut file = TilesFile::open(&out).unwrap();
    let table = file.sticks();
    assert!(!table.is_empty(), "{planted}");
    assert_eq!(table.sticks(), layer.table().sticks());
    assert_eq!(table.texels(), layer.table().texels());
    let world = file.world();
    assert_eq!(world.roughness, pyramid.roughness());
    assert_eq!(
        tiles_as_cut(&mut file, &pyramid, Some(&layer), "objects"),
        summary.tiles
    );
    // The wood's boundary trees see through their leaves: the file keeps
    // the opacities.
    assert!(file.sticks().sees_through());
    assert_eq!(file.sticks().alphas(), objects_alphas(&scene));
    // Its complex sticks after the opaque ones, as the planting ordered
    // them: a hit on an opaque one reads no opacity.
    let first_complex = file.sticks().first_complex();
    assert_eq!(first_complex, layer.table().first_complex());
    assert!(
        usize::from(first_complex) > 1
            && usize::from(first_complex) <= layer.table().sticks().len()
    );
    // Among the objects: low over the first stick, looking along +x.
    let objects = scene.objects.as_ref().unwrap();
    let first = objects.points.iter().position(|&p| p != 0).unwrap();
    let (x, y) = (first % scene.width as usize, first / scene.width as usize);
    let ground = scene.height(x, y);
    let mut cameras = views(scene.width as f32, scene.depth as f32, scene.max_height());
    cameras.push(Camera::looking(
        [x as f32 - 12.0, y as f32 + 0.5, ground + 2.0],
        0.0,
        5.0,
    ));
    let options = RenderOptions::default();
    for camera in cameras {
        let (from_maps, _) = render_kernel(&kernel, &camera, 96, 72, &options).unwrap();
        let (from_tiles, _, tiled) =
            render_tiled(&mut file, &camera, 96, 72, &options, PixelRays::Fixed).unwrap();
        assert!(from_maps.colors == from_tiles.colors, "{camera:?}");
        assert_eq!((tiled.misses, tiled.degraded_samples), (0, 0), "{camera:?}");
    }
    println!(
        "{planted}: {} tiles, {} bytes, every tile and view identical",
        summary.tiles, summary.bytes
    );
}

/// The opacities of `scene`'s planted objects the kernel takes.
fn objects_alphas(scene: &Scene) -> &[u8] {
    scene.objects.as_ref().unwrap().see_through_alphas()
}

/// The bytes of a `.tiles` file with the header's version set to
/// `version` and its checksum made again (the file's sections of later
/// versions cut off by the caller).
fn as_version(bytes: &[u8], version: u8) -> Vec<u8> {
    let mut older = bytes.to_vec();
    older[8] = version;
    let header_crc = crc32fast::hash(&older[..40]);
    older[40..44].copy_from_slice(&header_crc.to_le_bytes());
    older
}

#[test]
fn damaged_and_foreign_files_are_refused_and_bad_tiles_rejected() {
    let (height, color) = odd_sized_maps();
    let out = temp("damaged.tiles");
    pack(
        &pack_input(&height, &[&color], 1.0 / 16.0, HeightFilter::default()),
        &out,
        &mut |_, _| {},
    )
    .unwrap();
    let bytes = std::fs::read(&out).unwrap();

    // Truncated: refused on opening, in one line.
    let truncated = temp("truncated.tiles");
    std::fs::write(&truncated, &bytes[..bytes.len() - 100]).unwrap();
    let e = TilesFile::open(&truncated).unwrap_err().to_string();
    assert!(e.contains("truncated") && !e.contains('\n'), "{e}");
    // Foreign: a PNG is not a tiled file.
    let e = TilesFile::open(&color).unwrap_err().to_string();
    assert!(e.contains("not a terracast tiled terrain file"), "{e}");
    // Another version.
    let mut newer = bytes.clone();
    newer[8] = 9;
    let versioned = temp("newer.tiles");
    std::fs::write(&versioned, &newer).unwrap();
    let e = TilesFile::open(&versioned).unwrap_err().to_string();
    assert!(e.contains("format version 9"), "{e}");
    // A version-2 file (no stick section) reads as one without objects.
    let stick_section = 16;
    let old = temp("version-2.tiles");
    std::fs::write(&old, as_version(&bytes[..bytes.len() - stick_section], 2)).unwrap();
    assert!(TilesFile::open(&old).unwrap().sticks().is_empty());
    // A version-3 file: its stick section without the opacity count.
    let mut section = vec![0u8; 8];
    section.extend_from_slice(&crc32fast::hash(&section).to_le_bytes());
    let mut version_3 = as_version(&bytes[..bytes.len() - stick_section], 3);
    version_3.extend_from_slice(&section);
    let old = temp("version-3.tiles");
    std::fs::write(&old, version_3).unwrap();
    let version_3 = TilesFile::open(&old).unwrap();
    assert!(version_3.sticks().is_empty() && version_3.sticks().alphas().is_empty());
    // A damaged stick table, and one cut short: refused in one line.
    let mut table = bytes.clone();
    let at = bytes.len() - 3;
    table[at] ^= 0x01;
    let damaged_sticks = temp("stick-table.tiles");
    std::fs::write(&damaged_sticks, &table).unwrap();
    let e = TilesFile::open(&damaged_sticks).unwrap_err().to_string();
    assert!(e.contains("stick table") && !e.contains('\n'), "{e}");
    std::fs::write(&damaged_sticks, &bytes[..bytes.len() - 2]).unwrap();
    let e = TilesFile::open(&damaged_sticks).unwrap_err().to_string();
    assert!(e.contains("truncated") && !e.contains('\n'), "{e}");
    // A level-0 point naming a stick the file's table does not hold (its
    // tile's checksum made to match): that tile is rejected.
    let mut unknown = bytes.clone();
    let tiles = u64::from_le_bytes(bytes[32..40].try_into().unwrap()) as usize;
    let first_record = 44 + 4 * tiles;
    let stick_of_first_point = first_record + TILE * TILE * 5;
    unknown[stick_of_first_point] = 1;
    let record = &unknown[first_record..first_record + TILE * TILE * 7];
    let crc = crc32fast::hash(record);
    unknown[44..48].copy_from_slice(&crc.to_le_bytes());
    let named = temp("unknown-stick.tiles");
    std::fs::write(&named, &unknown).unwrap();
    let mut file = TilesFile::open(&named).unwrap();
    let mut tile = Box::new(Tile::<TILE>::EMPTY);
    let first = TileKey {
        level: 0,
        x: 0,
        y: 0,
    };
    assert_eq!(file.load(first, &mut tile), Err(TileError::Checksum));
    // A version-1 file (no photo section) reads as one without photos.
    let tiles_end = bytes.len() - stick_section - 8;
    let old = temp("older.tiles");
    std::fs::write(&old, as_version(&bytes[..tiles_end], 1)).unwrap();
    assert!(TilesFile::open(&old).unwrap().photos().is_empty());
    // A damaged photo table, and one cut short: refused in one line.
    let mut table = bytes.clone();
    table[tiles_end] ^= 0x01;
    let damaged_table = temp("photo-table.tiles");
    std::fs::write(&damaged_table, &table).unwrap();
    let e = TilesFile::open(&damaged_table).unwrap_err().to_string();
    assert!(e.contains("photo") && !e.contains('\n'), "{e}");
    std::fs::write(&damaged_table, &bytes[..tiles_end + 2]).unwrap();
    let e = TilesFile::open(&damaged_table).unwrap_err().to_string();
    assert!(e.contains("truncated") && !e.contains('\n'), "{e}");

    // One byte of the first level-0 tile's record flipped: that tile is
    // rejected, reported, and drawn from level 1; the frame completes.
    let mut corrupt = bytes.clone();
    let first_record =
        corrupt.len() - (corrupt.len() - 44) / (4 + TILE * TILE * 7) * (TILE * TILE * 7);
    corrupt[first_record + 10] ^= 0xff;
    let damaged = temp("corrupt.tiles");
    std::fs::write(&damaged, &corrupt).unwrap();
    let mut file = TilesFile::open(&damaged).unwrap();
    let mut tile = Box::new(Tile::<TILE>::EMPTY);
    let key = TileKey {
        level: 0,
        x: 0,
        y: 0,
    };
    assert_eq!(file.load(key, &mut tile), Err(TileError::Checksum));
    let camera = Camera::looking([30.0, -20.0, 60.0], 80.0, 25.0);
    let (frame, _, tiled) = render_tiled(
        &mut file,
        &camera,
        96,
        72,
        &RenderOptions::default(),
        PixelRays::Fixed,
    )
    .unwrap();
    assert_eq!((tiled.misses, tiled.rejected), (1, 1));
    assert!(tiled.degraded_samples > 0);
    assert!(frame
        .colors
        .iter()
        .any(|c| *c != terracast::config::DEFAULT_SKY));
}

/// A procedural source that fails every `every`-th load with an I/O error,
/// and may sleep on each load.
struct Flaky {
    inner: ProceduralSource,
    every: u32,
    loads: u32,
    delay: Duration,
}

impl TileSource<TILE> for Flaky {
    fn world(&self) -> World {
        self.inner.world()
    }
    fn load(&mut self, key: TileKey, tile: &mut Tile<TILE>) -> Result<usize, TileError> {
        self.loads += 1;
        std::thread::sleep(self.delay);
        if self.every > 0 && self.loads % self.every == 0 {
            return Err(TileError::Io);
        }
        self.inner.load(key, tile)
    }
}

fn flight(frames: u32, prefetch: bool) -> PageOptions {
    PageOptions {
        size: (320, 240),
        frames,
        fps: 30.0,
        turn_deg_per_s: 60.0,
        speed: 300.0,
        start: Camera {
            eye: [65_536.0, 65_536.0, 2_500.0],
            pitch_deg: 20.0,
            ..Camera::default()
        },
        load_budget: 81,
        prefetch,
        lead_s: 0.25,
        options: RenderOptions::default(),
        path: None,
    }
}

#[test]
fn a_flight_over_64_gib_pages_through_a_fixed_cache_without_missing_a_tile() {
    let mut source = ProceduralSource::new(131_072, 1).unwrap();
    assert!(source.virtual_bytes() >= 64 << 30);
    // 1.5 s turning one field of view (60 degrees) a second.
    let report = page_flight(&mut source, &flight(45, true), &mut |_, _| Ok(())).unwrap();
    let (mean_loads, most_loads) = report.loads_per_frame();
    let (mean_ratio, most_ratio) = report.resident_ratio();
    println!(
        "64 GiB flight, cache {} MiB: first frame {} loads; after it {} frames short of a tile, loads a frame mean {mean_loads:.1} most {most_loads}, resident / footprint mean {mean_ratio:.2} most {most_ratio:.2}",
        report.cache_bytes >> 20,
        report.frames[0].loads,
        report.frames_missing_after_first()
    );
    assert_eq!(report.frames_missing_after_first(), 0);
    assert!(report.frames.iter().all(|f| f.degraded_samples == 0));
    assert!(most_loads <= 81 && mean_loads > 0.0);
    assert!(most_ratio <= 2.0, "resident {most_ratio:.2}x the footprint");
    assert!(report.cache_bytes <= 32 << 20);

    // Without prefetch the same flight is drawn short of tiles: the
    // extended footprint is what keeps it whole.
    let mut source = ProceduralSource::new(131_072, 1).unwrap();
    let bare = page_flight(&mut source, &flight(10, false), &mut |_, _| Ok(())).unwrap();
    assert!(bare.frames_missing_after_first() > 0);
}

#[test]
fn failing_and_slow_sources_never_stop_a_frame_and_change_nothing_but_time() {
    let run = |every: u32, delay_ms: u64| {
        let mut source = Flaky {
            inner: ProceduralSource::new(131_072, 1).unwrap(),
            every,
            loads: 0,
            delay: Duration::from_millis(delay_ms),
        };
        let mut images = Vec::new();
        let report = page_flight(&mut source, &flight(6, true), &mut |image, _| {
            images.push(image.colors.clone());
            Ok(())
        })
        .unwrap();
        (report, images)
    };
    let (fast, fast_images) = run(0, 0);
    // A slow source (1 ms a tile) gives the same frames and records: the
    // loader's budget is in tiles, not in wall time.
    let (slow, slow_images) = run(0, 1);
    assert!(fast_images == slow_images);
    assert_eq!(
        serde_json::to_string(&fast.frames).unwrap(),
        serde_json::to_string(&slow.frames).unwrap()
    );
    // One load in seven fails: every frame is still drawn, the failures
    // show as missing tiles drawn from coarser levels.
    let (flaky, flaky_images) = run(7, 0);
    assert_eq!(flaky_images.len(), 6);
    assert!(flaky.frames.iter().map(|f| f.missing_tiles).sum::<usize>() > 0);
    assert!(flaky_images
        .iter()
        .all(|i| i.iter().any(|c| *c != terracast::config::DEFAULT_SKY)));
}

/// A source that misbehaves at random (seeded): fails to read, hands back
/// a damaged record (filled with a poison color and refused, as a file's
/// checksum refuses it), or stalls.
struct Chaotic {
    inner: ProceduralSource,
    state: u64,
    stalls: u32,
}

/// A color the procedural terrain never has: a damaged tile's.
const POISON: terracast::Rgb = [255, 0, 255];

impl Chaotic {
    fn roll(&mut self) -> u64 {
        // xorshift64*: deterministic, no dependency.
        self.state ^= self.state >> 12;
        self.state ^= self.state << 25;
        self.state ^= self.state >> 27;
        self.state.wrapping_mul(0x2545_F491_4F6C_DD1D) % 100
    }
}

impl TileSource<TILE> for Chaotic {
    fn world(&self) -> World {
        self.inner.world()
    }
    fn load(&mut self, key: TileKey, tile: &mut Tile<TILE>) -> Result<usize, TileError> {
        match self.roll() {
            0..=7 => Err(TileError::Io),
            8..=15 => {
                self.inner.load(key, tile)?;
                tile.colors = [[POISON; TILE]; TILE];
                Err(TileError::Checksum)
            }
            16..=20 => {
                self.stalls += 1;
                std::thread::sleep(Duration::from_micros(200));
                self.inner.load(key, tile)
            }
            _ => self.inner.load(key, tile),
        }
    }
}

#[test]
fn a_thousand_frames_from_a_misbehaving_source_are_all_drawn_none_with_a_bad_tile() {
    let options = PageOptions {
        size: (96, 72),
        ..flight(1000, true)
    };
    let run = |chaotic: bool| {
        let mut source = Chaotic {
            inner: ProceduralSource::new(131_072, 1).unwrap(),
            state: 0x9E37_79B9_7F4A_7C15,
            stalls: 0,
        };
        let mut drawn = 0u32;
        let mut poisoned = 0usize;
        let report = if chaotic {
            page_flight(&mut source, &options, &mut |image, _| {
                drawn += 1;
                poisoned += image.colors.iter().filter(|c| **c == POISON).count();
                Ok(())
            })
        } else {
            page_flight(&mut source.inner, &options, &mut |image, _| {
                drawn += 1;
                poisoned += image.colors.iter().filter(|c| **c == POISON).count();
                Ok(())
            })
        }
        .unwrap();
        (report, drawn, poisoned, source.stalls)
    };
    let (clean, clean_drawn, clean_poison, _) = run(false);
    let (chaos, drawn, poisoned, stalls) = run(true);
    let failed: u64 = chaos.rejected;
    let missing: usize = chaos.frames.iter().map(|f| f.missing_tiles).sum();
    let steady = |r: &terracast_sim::tiles::PageReport| {
        r.frames[900..]
            .iter()
            .map(|f| f.resident_bytes)
            .max()
            .unwrap_or(0)
    };
    println!(
        "1000 frames: {drawn} drawn; {failed} tiles refused as damaged, {stalls} stalls, {missing} tile-draws from coarser levels; resident at the end {} KiB (clean flight {} KiB, cache {} KiB)",
        steady(&chaos) >> 10,
        steady(&clean) >> 10,
        chaos.cache_bytes >> 10
    );
    assert_eq!((clean_drawn, drawn), (1000, 1000));
    // The poison color is the damaged tiles' alone, and none is shown.
    assert_eq!(clean_poison, 0);
    assert_eq!(poisoned, 0, "a damaged tile was drawn");
    assert!(failed > 0 && stalls > 0 && missing > 0);
    // The loader's budget holds every frame after the first (which loads
    // its footprint before it is drawn), and the cache neither grows past
    // its slots nor loses them: over the last hundred frames the resident
    // bytes stay within 5 % of the clean flight's (the tiles refused and
    // retried make the two caches hold slightly different tiles).
    assert!(chaos.frames[1..]
        .iter()
        .all(|f| f.loads <= u64::from(options.load_budget)));
    assert!(chaos
        .frames
        .iter()
        .all(|f| f.resident_bytes <= chaos.cache_bytes));
    let (ended, clean_ended) = (steady(&chaos) as f64, steady(&clean) as f64);
    assert!(
        (ended - clean_ended).abs() <= 0.05 * clean_ended,
        "resident {ended} against {clean_ended}"
    );
}

/// The window's tiled terrain (`terracast-sim view --terrain`): one cache
/// kept resident from frame to frame, frames rendered by the line pool on
/// several threads, draws each view as a render through a fresh cache
/// does, and knows the ground under the eye.
#[test]
fn a_resident_cache_on_many_threads_draws_what_a_fresh_one_does() {
    use terracast::View;
    use terracast_sim::tiles::{new_photo_slots, new_slots, TiledViewer};
    use terracast_sim::viewer::{render_pool, Pixels};
    let source = || ProceduralSource::new(8192, 5).unwrap();
    let (mut slots, mut photo_slots) = (new_slots(), new_photo_slots());
    let mut viewer = TiledViewer::new(source(), &mut slots, &mut photo_slots);
    let options = RenderOptions::default();
    let size = (96, 72);
    let top = f32::from(source().world().max_height) / 16.0;
    for step in 0..6 {
        let camera = Camera::looking(
            [4000.0 + 40.0 * step as f32, 3000.0, top + 50.0],
            30.0 + 10.0 * step as f32,
            15.0,
        );
        let pixels = Pixels::new(size.0, size.1);
        let (_, misses) = viewer
            .frame(&camera, size, &options, |surface, local| {
                let view = View::new(local, size.0, size.1).unwrap();
                render_pool(
                    surface,
                    &view,
                    (&options, None),
                    PixelRays::Fixed,
                    3,
                    &pixels,
                )
            })
            .unwrap();
        assert_eq!(misses, 0);
        let (fresh, _, _) = render_tiled(
            &mut source(),
            &camera,
            size.0,
            size.1,
            &options,
            PixelRays::Fixed,
        )
        .unwrap();
        assert_eq!(pixels.rgb(), fresh.colors.concat(), "frame {step}");
        let ground = viewer
            .ground_under(camera.eye)
            .expect("the ground under the eye is resident");
        assert!(ground > 0.0 && ground <= top, "{ground}");
    }
}
