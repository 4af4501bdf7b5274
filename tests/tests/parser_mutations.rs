//! The project's own readers fed damaged files: a valid file of each kind,
//! then random damage (bit flips, truncation, a chunk copied over another,
//! a 32-bit word set to a huge count or offset). Held for every damaged
//! file: no panic; the reader accepts or refuses it with its error; and
//! no single allocation while it reads is larger than the file's size
//! could justify (16 × its bytes and 16 MiB: a short file stating a huge
//! size must be refused before anything that size is allocated).
//!
//! Readers: the board scene file and the display wire capture, the camera
//! path file, the machine description (TOML), the tiled terrain (`.tiles`:
//! header, directory and every tile's record), SRTM `.hgt`, PNG and
//! GeoTIFF height maps and TIFF photos. Not coverage-guided (each case is a random mutation of one valid
//! file); seeded, so a failure repeats; `PROPTEST_CASES` sets the cases a
//! reader.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::{Path, PathBuf};
use terracast::tiles::{Tile, TileKey, TileSource};
use terracast_sim::board::{board_views, write_scene, SceneFile};
use terracast_sim::fly::Path as FlyPath;
use terracast_sim::scene::{load_heights, procedural};
use terracast_sim::sim::Machine;
use terracast_sim::tiles::{pack, PackInput, TilesFile, TILE};

/// The largest single allocation made on this thread while armed.
struct Tracking;

thread_local! {
    static ARMED: Cell<bool> = const { Cell::new(false) };
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Tracking {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

fn note(size: usize) {
    // `try_with`: the thread may be tearing its locals down.
    let _ = ARMED.try_with(|armed| {
        if armed.get() {
            let _ = LARGEST.try_with(|largest| largest.set(largest.get().max(size)));
        }
    });
}

#[global_allocator]
static ALLOCATOR: Tracking = Tracking;

/// Runs `read`, returning the largest single allocation it made.
fn largest_allocation(read: impl FnOnce()) -> usize {
    LARGEST.with(|l| l.set(0));
    ARMED.with(|a| a.set(true));
    read();
    ARMED.with(|a| a.set(false));
    LARGEST.with(|l| l.get())
}

/// One piece of damage, its positions taken modulo the file's length.
#[derive(Debug, Clone)]
enum Damage {
    Flip { at: usize, bit: u8 },
    Truncate { keep: usize },
    Splice { from: usize, to: usize, len: usize },
    Word { at: usize, value: u32 },
}

fn damage() -> impl Strategy<Value = Damage> {
    let huge = prop_oneof![
        Just(u32::MAX),
        Just(0x7FFF_FFFF),
        Just(0x8000_0000),
        Just(0x0001_0000),
        Just(0),
        any::<u32>(),
    ];
    prop_oneof![
        4 => (any::<usize>(), 0u8..8).prop_map(|(at, bit)| Damage::Flip { at, bit }),
        1 => any::<usize>().prop_map(|keep| Damage::Truncate { keep }),
        1 => (any::<usize>(), any::<usize>(), 1usize..64)
            .prop_map(|(from, to, len)| Damage::Splice { from, to, len }),
        2 => (any::<usize>(), huge).prop_map(|(at, value)| Damage::Word { at, value }),
    ]
}

fn apply(bytes: &[u8], damages: &[Damage], header: usize) -> Vec<u8> {
    let mut out = bytes.to_vec();
    for damage in damages {
        if out.is_empty() {
            break;
        }
        // Half the damage lands in the first `header` bytes, where the
        // sizes and offsets are.
        let at = |i: usize, len: usize| {
            if i % 2 == 0 {
                (i / 2) % header.min(len).max(1)
            } else {
                (i / 2) % len
            }
        };
        match *damage {
            Damage::Flip { at: i, bit } => {
                let i = at(i, out.len());
                out[i] ^= 1 << bit;
            }
            Damage::Truncate { keep } => out.truncate(keep % (out.len() + 1)),
            Damage::Splice { from, to, len } => {
                let (from, to) = (at(from, out.len()), at(to, out.len()));
                let len = len.min(out.len() - from).min(out.len() - to);
                let chunk = out[from..from + len].to_vec();
                out[to..to + len].copy_from_slice(&chunk);
            }
            Damage::Word { at: i, value } => {
                let i = at(i, out.len().saturating_sub(3).max(1));
                for (k, b) in value.to_le_bytes().into_iter().enumerate() {
                    if let Some(slot) = out.get_mut(i + k) {
                        *slot = b;
                    }
                }
            }
        }
    }
    out
}

fn work_dir(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("terracast-mutations-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Damages `valid` in `cases` ways (or `PROPTEST_CASES`) and hands each
/// result to `read`, with a path holding it named `file_name`; fails on a
/// panic or an allocation past the bound.
fn mutate(
    name: &str,
    file_name: &str,
    (valid, header): (&[u8], usize),
    cases: u32,
    read: impl Fn(&[u8], &Path) -> bool,
) {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(cases);
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    let seed: [u8; 32] = core::array::from_fn(|i| name.as_bytes().get(i).copied().unwrap_or(1));
    let mut runner =
        TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed));
    let dir = work_dir(name);
    let file = dir.join(file_name);
    let (accepted, ran, most) = (Cell::new(0u32), Cell::new(0u32), Cell::new(0usize));
    let result = runner.run(&prop::collection::vec(damage(), 1..6), |damages| {
        let bytes = apply(valid, &damages, header);
        std::fs::write(&file, &bytes).unwrap();
        let mut ok = false;
        let largest = largest_allocation(|| ok = read(&bytes, &file));
        ran.set(ran.get() + 1);
        accepted.set(accepted.get() + u32::from(ok));
        most.set(most.get().max(largest));
        let bound = 16 * bytes.len() + (16 << 20);
        prop_assert!(
            largest <= bound,
            "{name}: a {}-byte file made a {largest}-byte allocation",
            bytes.len()
        );
        Ok(())
    });
    let _ = std::fs::remove_dir_all(&dir);
    println!(
        "| {name} | {} bytes | {} | {} | {} | {} KiB |",
        valid.len(),
        ran.get(),
        accepted.get(),
        ran.get() - accepted.get(),
        most.get() / 1024
    );
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
}

#[test]
fn board_scene_files_and_wire_captures() {
    let dir = work_dir("board-valid");
    let scene_path = dir.join("scene.tcb");
    let scene = procedural(32, 3);
    let views = board_views(32, scene.max_height());
    write_scene(&scene_path, &scene, (16, 12), &views[..2]).unwrap();
    let valid = std::fs::read(&scene_path).unwrap();
    mutate("board scene", "scene.tcb", (&valid, 256), 300, |_, path| {
        SceneFile::read(path).is_ok()
    });
    let wire = SceneFile::read(&scene_path)
        .unwrap()
        .render(terracast::HeightPath::Line)
        .unwrap()
        .0[0]
        .wire
        .clone();
    mutate("wire capture", "wire.bin", (&wire, 64), 300, |bytes, _| {
        let mut image = vec![0u16; 16 * 12];
        terracast_board::wire::decode(bytes, &mut image, 16, 12).is_ok()
    });
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn path_files_and_machine_descriptions() {
    let path = b"# t x y z yaw pitch [roll]\n0 10 20 100 90 10\n2 30 40 90 120 20 15\n4.5 50 60 80 200 45 -30\n";
    mutate("path file", "path.txt", (path, 64), 300, |bytes, _| {
        FlyPath::parse(&String::from_utf8_lossy(bytes)).is_ok()
    });
    let machine = b"processors = 16\nclock_mhz = 40.0\n[cycles]\nper_ray = 689\nper_step = 262\n[global_memory]\ncards = 4\nbanks_per_card = 4\n[tiles]\nside = 64\n[disk]\nmb_per_s = 35.0\n";
    mutate(
        "machine description",
        "machine.toml",
        (machine, 64),
        300,
        |bytes, _| Machine::from_toml(&String::from_utf8_lossy(bytes)).is_ok(),
    );
}

#[test]
fn tiled_terrain_files() {
    let dir = work_dir("tiles-valid");
    let height = dir.join("heights.png");
    let heights: Vec<u16> = (0..96 * 80u32)
        .map(|i| ((i * 37) % 4000) as u16 * 16)
        .collect();
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(96, 80, heights)
        .unwrap()
        .save(&height)
        .unwrap();
    let tiles = dir.join("terrain.tiles");
    let input = PackInput {
        height: height.clone(),
        colors: Vec::new(),
        height_scale: 1.0 / 16.0,
        filter: Default::default(),
        seed: 1,
        objects: false,
        place: None,
    };
    pack(&input, &tiles, &mut |_, _| {}).unwrap();
    let valid = std::fs::read(&tiles).unwrap();
    mutate(".tiles", "terrain.tiles", (&valid, 512), 300, |_, path| {
        let Ok(mut file) = TilesFile::open(path) else {
            return false;
        };
        let world = file.world();
        let mut tile = Box::new(Tile::<TILE>::EMPTY);
        for level in 0..world.levels() {
            let (across, down) = world.tiles(level, TILE as u32);
            for y in 0..down.min(4) {
                for x in 0..across.min(4) {
                    let _ = file.load(TileKey { level, x, y }, &mut tile);
                }
            }
        }
        true
    });
    let valid_png = std::fs::read(&height).unwrap();
    mutate(
        "height PNG",
        "heights.png",
        (&valid_png, 64),
        300,
        |_, path| load_heights(path, 1.0).is_ok(),
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn srtm_height_files() {
    let dir = work_dir("hgt-valid");
    // A 3-arc-second tile is 1201 × 1201 big-endian i16; a void or two.
    let samples: Vec<u8> = (0..1201 * 1201u32)
        .flat_map(|i| {
            let h: i16 = if i % 9973 == 0 {
                -32768
            } else {
                (i % 3000) as i16
            };
            h.to_be_bytes()
        })
        .collect();
    // Each case writes and reads 2.9 MB: fewer of them.
    mutate(".hgt", "N44W072.hgt", (&samples, 4096), 40, |_, path| {
        load_heights(path, 1.0).is_ok()
    });
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn geotiff_height_and_photo_files() {
    use terracast_tests::{georeferenced_tiff, tiled_float_tiff, Georeference};
    use tiff::encoder::colortype;
    // A 64 × 64 int16 GeoTIFF with its georeference, a no-data value and a
    // void, as an SRTM export comes.
    let heights: Vec<i16> = (0..64 * 64)
        .map(|i| {
            if i % 613 == 0 {
                -9999
            } else {
                (i % 900) as i16
            }
        })
        .collect();
    let at = Georeference {
        origin: [20.0, -34.0],
        pixel: 0.001,
        geographic: false,
    };
    let valid = georeferenced_tiff::<colortype::GrayI16>((64, 64), &heights, at, Some("-9999"));
    mutate("GeoTIFF", "h.tif", (&valid, 512), 400, |_, path| {
        let heights = load_heights(path, 1.0).is_ok();
        let photo = terracast_sim::scene::load_colors(path, 8, 8).is_ok();
        // And strip by strip, as `pack` streams it.
        heights || photo || streams(path)
    });
    // Float heights stored in 16 x 16 tiles, streamed a row of tiles at a
    // time.
    let floats: Vec<f32> = heights.iter().map(|&h| f32::from(h)).collect();
    let tiled = tiled_float_tiff((64, 64), &floats, 16, at);
    mutate("tiled GeoTIFF", "t.tif", (&tiled, 512), 200, |_, path| {
        load_heights(path, 1.0).is_ok() || streams(path)
    });
}

/// Whether `path` reads as heights row by row, as `pack` streams them.
fn streams(path: &Path) -> bool {
    terracast_sim::scene::geotiff::TiffHeightRows::open(path)
        .ok()
        .is_some_and(|mut rows| {
            let depth = rows.size().1;
            (0..depth).all(|_| rows.next_row().is_ok())
        })
}
