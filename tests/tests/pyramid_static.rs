//! Pyramids built into static storage sized at compile time by the
//! kernel's `const fn`s, as a board would declare them: 1024² and 4096².

use std::sync::Mutex;
use terracast::{pyramid_cells, pyramid_points, HeightFilter, Pyramid, Terrain};

const SMALL: u32 = 1024;
const LARGE: u32 = 4096;

static SMALL_HEIGHTS: Mutex<[u16; pyramid_points(SMALL, SMALL)]> =
    Mutex::new([0; pyramid_points(SMALL, SMALL)]);
static SMALL_COLORS: Mutex<[[u8; 3]; pyramid_points(SMALL, SMALL)]> =
    Mutex::new([[0; 3]; pyramid_points(SMALL, SMALL)]);
static SMALL_BOUNDS: Mutex<[u16; pyramid_cells(SMALL, SMALL)]> =
    Mutex::new([0; pyramid_cells(SMALL, SMALL)]);
static LARGE_HEIGHTS: Mutex<[u16; pyramid_points(LARGE, LARGE)]> =
    Mutex::new([0; pyramid_points(LARGE, LARGE)]);
static LARGE_COLORS: Mutex<[[u8; 3]; pyramid_points(LARGE, LARGE)]> =
    Mutex::new([[0; 3]; pyramid_points(LARGE, LARGE)]);
static LARGE_BOUNDS: Mutex<[u16; pyramid_cells(LARGE, LARGE)]> =
    Mutex::new([0; pyramid_cells(LARGE, LARGE)]);

fn check(side: u32, heights: &mut [u16], colors: &mut [[u8; 3]], bounds: &mut [u16]) {
    let n = (side * side) as usize;
    // A ramp up to 1000 voxels with one 4000-voxel spike.
    let mut base: Vec<u16> = (0..n)
        .map(|i| {
            Terrain::quantize_height((i % side as usize) as f32 * 1000.0 / side as f32).unwrap()
        })
        .collect();
    base[n / 2 + side as usize / 3] = Terrain::quantize_height(4000.0).unwrap();
    let base_colors = vec![[10, 200, 30]; n];
    let terrain = Terrain::new(side, side, &base, &base_colors).unwrap();
    Pyramid::build(&terrain, HeightFilter::default(), heights, colors, bounds).unwrap();
    let pyramid = Pyramid::new(terrain, heights, colors, bounds).unwrap();
    let top = pyramid.level(pyramid.levels() - 1).unwrap();
    assert_eq!((top.width(), top.depth()), (2, 2));
    assert_eq!(pyramid.levels() as u32, side.ilog2() + 1);
    // Colors of a uniform map stay uniform on every level.
    for l in 0..pyramid.levels() {
        assert!(pyramid
            .level(l)
            .unwrap()
            .colors()
            .iter()
            .all(|&c| c == [10, 200, 30]));
    }
    // The spike survives in the bounds of every level, though the mean
    // spreads it thin.
    let spike = Terrain::quantize_height(4000.0).unwrap();
    assert!(bounds.iter().filter(|&&b| b == spike).count() >= pyramid.levels() - 1);
    let level1 = pyramid.level(1).unwrap();
    assert!(level1.heights().iter().all(|&h| h < spike));
}

#[test]
fn pyramids_build_in_static_storage() {
    check(
        SMALL,
        &mut *SMALL_HEIGHTS.lock().unwrap(),
        &mut *SMALL_COLORS.lock().unwrap(),
        &mut *SMALL_BOUNDS.lock().unwrap(),
    );
    check(
        LARGE,
        &mut *LARGE_HEIGHTS.lock().unwrap(),
        &mut *LARGE_COLORS.lock().unwrap(),
        &mut *LARGE_BOUNDS.lock().unwrap(),
    );
    // Cohen-Or's "a third more" for the levels (heights and colors), and
    // two bytes for each of a third as many bound cells: 7/15 in all.
    let side = LARGE as f64;
    let points = terracast::pyramid_points(LARGE, LARGE) as f64 / (side * side);
    assert!((0.333..0.336).contains(&points), "{points}");
    let ratio = terracast::pyramid_bytes(LARGE, LARGE) as f64 / (side * side * 5.0);
    assert!((0.465..0.47).contains(&ratio), "{ratio}");
}
