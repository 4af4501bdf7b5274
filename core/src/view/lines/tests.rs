//! Every pixel on exactly one line, at every pitch and roll; the stepped
//! and the tabled pixels against the exact test; a line's rays in one
//! vertical plane.

use super::*;
use crate::view::Camera;
use std::vec;

fn view(pitch: f32, yaw: f32, size: (u32, u32), hfov: f32) -> View {
    rolled(pitch, 0.0, yaw, size, hfov)
}

fn rolled(pitch: f32, roll: f32, yaw: f32, size: (u32, u32), hfov: f32) -> View {
    let camera = Camera {
        eye: [10.0, 20.0, 30.0],
        yaw_deg: yaw,
        pitch_deg: pitch,
        roll_deg: roll,
        hfov_deg: hfov,
    };
    View::new(&camera, size.0, size.1).unwrap()
}

/// Every roll the ownership test is held to: every 7.5° both ways,
/// with ±90° and 180°.
fn rolls() -> impl Iterator<Item = f32> {
    (-24..=24).map(|i| i as f32 * 7.5)
}

/// How many times each pixel is owned, over every line of the view.
fn ownership(view: &View) -> vec::Vec<u32> {
    let (w, h) = (view.width(), view.height());
    let mut owned = vec![0u32; (w * h) as usize];
    for index in 0..view.lines() {
        let line = view.line(index).unwrap();
        for p in line.pixels(h) {
            owned[(p.y * w + p.x) as usize] += 1;
        }
    }
    owned
}

#[test]
fn every_pixel_belongs_to_exactly_one_line() {
    for pitch in [
        -89.0, -45.0, -3.0, 0.0, 0.001, 2.0, 15.0, 30.0, 45.0, 60.0, 66.0, 75.0, 89.9, 90.0,
    ] {
        for size in [(64, 48), (63, 47), (1, 9), (9, 1), (31, 80)] {
            for hfov in [30.0, 60.0, 120.0] {
                let view = view(pitch, 25.0, size, hfov);
                let owned = ownership(&view);
                assert!(
                    owned.iter().all(|&n| n == 1),
                    "pitch {pitch} size {size:?} hfov {hfov}: {:?}",
                    owned
                        .iter()
                        .enumerate()
                        .filter(|(_, &n)| n != 1)
                        .take(5)
                        .collect::<vec::Vec<_>>()
                );
            }
        }
    }
}

#[test]
fn a_straight_line_steps_the_pixels_its_ownership_test_gives() {
    // Straight: level views' columns (upright or upside down), and
    // their rows rolled ±90°; every other view's lines step their
    // window.
    let mut straight_views = 0;
    for roll in rolls() {
        for pitch in [-45.0, -3.0, 0.0, 2.0, 90.0] {
            for size in [(32, 21), (40, 30), (1, 9), (9, 1)] {
                let view = rolled(pitch, roll, 25.0, size, 70.0);
                let level = pitch == 0.0 && roll % 90.0 == 0.0;
                straight_views += usize::from(level);
                // What a frame budget prices the view's pixels by.
                assert_eq!(
                    view.lines_are_straight(),
                    level,
                    "roll {roll} pitch {pitch}"
                );
                for index in 0..view.lines() {
                    let line = view.line(index).unwrap();
                    let stepped = line.pixels(size.1);
                    let Some(straight) = stepped.straightened() else {
                        assert!(!level || stepped.clone().next().is_none());
                        continue;
                    };
                    assert!(level, "roll {roll} pitch {pitch}: line {index} straight");
                    // The same pixels, directions and offsets, in the
                    // same order.
                    assert_eq!(
                        straight.clone().collect::<vec::Vec<_>>(),
                        stepped.clone().collect::<vec::Vec<_>>(),
                        "roll {roll} size {size:?} line {index}"
                    );
                    // And the same positions left once two rays are
                    // cast (the sky above a line's last hit).
                    let (mut a, mut b) = (straight, stepped.clone());
                    a.nth(1);
                    b.nth(1);
                    let mut positions = (vec::Vec::new(), vec::Vec::new());
                    a.for_each_position(|x, y| positions.0.push((x, y)));
                    b.for_each_position(|x, y| positions.1.push((x, y)));
                    assert_eq!(positions.0, positions.1);
                    assert_eq!(positions.0.len(), stepped.count().saturating_sub(2));
                }
            }
        }
    }
    assert_eq!(straight_views, 5 * 4);
}

#[test]
fn every_pixel_belongs_to_exactly_one_line_at_every_roll() {
    for roll in rolls() {
        for pitch in [-89.0, -45.0, 0.0, 2.0, 30.0, 60.0, 90.0] {
            for size in [(32, 21), (40, 30)] {
                for hfov in [30.0, 70.0, 120.0] {
                    let view = rolled(pitch, roll, 25.0, size, hfov);
                    let owned = ownership(&view);
                    let wrong = owned.iter().filter(|&&n| n != 1).count();
                    assert_eq!(
                        wrong, 0,
                        "roll {roll} pitch {pitch} size {size:?} hfov {hfov}"
                    );
                }
            }
        }
    }
}

#[test]
fn a_rolled_lines_rays_share_one_vertical_plane_and_rise_along_it() {
    for roll in rolls() {
        for pitch in [-45.0, 0.0, 2.0, 30.0, 90.0] {
            let view = rolled(pitch, roll, 25.0, (48, 36), 70.0);
            for index in 0..view.lines() {
                let line = view.line(index).unwrap();
                let rays: vec::Vec<[f64; 3]> = line
                    .pixels(36)
                    .map(|p| line.direction(p.along).map(|v| v as f64 / 4294967296.0))
                    .collect();
                let (Some(first), Some(last)) = (rays.first(), rays.last()) else {
                    continue;
                };
                // The last ray leaves the first one's vertical plane by
                // far less than a pixel: its sideways part against its
                // length, in pixels (a pixel is |per_column| radians).
                let length = |d: &[f64; 3]| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let across = (first[0] * last[1] - first[1] * last[0]).abs()
                    / first[0].hypot(first[1]).max(1e-12);
                let pixel = length(&view.per_column.map(|v| v.to_num::<f64>()));
                let off = across / length(last) / pixel;
                // (0.076 at most, straight down, rolled or not: `V` is
                // placed to 1/256 of a pixel.)
                assert!(
                    off < 0.1,
                    "roll {roll} pitch {pitch} line {index}: {off} pixel"
                );
                // Elevation rises (or holds) ray by ray.
                let elevation = |d: &[f64; 3]| d[2].atan2(d[0].hypot(d[1]));
                for pair in rays.windows(2) {
                    assert!(
                        elevation(&pair[1]) >= elevation(&pair[0]) - 1e-9,
                        "roll {roll} pitch {pitch} line {index}"
                    );
                }
            }
        }
    }
}

#[test]
fn a_lines_direction_words_are_its_directions_shifted_and_give_the_same_slope_and_drift() {
    use crate::view::plane::Plane;
    for (pitch, roll, size) in [
        (12.0, 0.0, (320, 240)),
        (90.0, 0.0, (64, 48)),
        (-45.0, 0.0, (40, 90)),
        (20.0, 30.0, (64, 48)),
        (0.0, 0.0, (33, 17)),
    ] {
        let view = rolled(pitch, roll, 25.0, size, 60.0);
        let extent = crate::surface::Extent {
            width: 512,
            depth: 512,
            max_height: 100,
            real_edges: true,
        };
        for index in 0..view.lines() {
            let line = view.line(index).unwrap();
            let plane =
                Plane::new(&view, &extent, &line.reference).with_across(&view.across(&line));
            let (major, up) = if plane.key.x_major { (0, 2) } else { (1, 2) };
            for pixel in line.pixels(size.1) {
                let d = line.direction(pixel.along);
                let words = line.direction_words(pixel.along, [major, up]);
                assert_eq!(words.map(i64::from), [d[major] >> 8, d[up] >> 8]);
                assert_eq!(words.map(|w| i64::from(w) << 8), [d[major], d[up]]);
                let run = if plane.key.forward {
                    words[0]
                } else {
                    -words[0]
                }
                .max(0);
                assert_eq!(
                    plane.drift_of_word(run, pixel.offset),
                    plane.drift(&d, pixel.offset),
                    "pitch {pitch} roll {roll} line {index}"
                );
            }
        }
    }
}

#[test]
fn the_narrow_window_steps_the_same_pixels_as_the_wide_one() {
    // Every line of views at every kind of pitch, roll and size, up to
    // one whose vanishing point is too far for a narrow window.
    let mut narrow_lines = 0;
    let mut wide_only = 0;
    for (pitch, roll, size) in [
        (12.0, 0.0, (320, 240)),
        (2.0, 0.0, (320, 240)),
        (0.5, 0.0, (1280, 720)),
        (45.0, 0.0, (63, 47)),
        (90.0, 0.0, (160, 120)),
        (-45.0, 0.0, (40, 90)),
        (20.0, 30.0, (64, 48)),
        (0.0, 30.0, (40, 30)),
    ] {
        let view = rolled(pitch, roll, 25.0, size, 60.0);
        for index in 0..view.lines() {
            let line = view.line(index).unwrap();
            let Ok(narrow) = line.pixels(size.1).narrowed() else {
                wide_only += 1;
                continue;
            };
            narrow_lines += 1;
            let wide: vec::Vec<Owned> = line.pixels(size.1).collect();
            let stepped: vec::Vec<Owned> = narrow.collect();
            assert_eq!(stepped, wide, "pitch {pitch} roll {roll} line {index}");
        }
    }
    assert!(
        narrow_lines > 1000 && wide_only > 100,
        "{narrow_lines} {wide_only}"
    );
}

#[test]
fn the_stepped_pixels_are_the_exact_tests_pixels() {
    // Every row of every line: the pixel the iterator gives (if any)
    // is the one pixel of the row `Line::owns` accepts.
    for (pitch, roll, size) in [
        (0.0, 0.0, (16, 8)),
        (30.0, 0.0, (64, 48)),
        (60.0, 0.0, (63, 47)),
        (89.9, 0.0, (64, 48)),
        (90.0, 0.0, (160, 120)),
        (-45.0, 0.0, (40, 90)),
        (0.0, 30.0, (40, 30)),
        (0.0, 60.0, (41, 31)),
        (0.0, -135.0, (40, 30)),
        (20.0, 30.0, (64, 48)),
        (45.0, -100.0, (63, 47)),
        (90.0, 45.0, (80, 60)),
        (-30.0, 170.0, (40, 90)),
    ] {
        let view = rolled(pitch, roll, 25.0, size, 60.0);
        for index in 0..view.lines() {
            let line = view.line(index).unwrap();
            let sector = line.sector;
            let mut exact = vec::Vec::new();
            let mut s = sector.first;
            while s != sector.last + sector.step {
                let owned: vec::Vec<i32> = (-2..sector.cross_len + 2)
                    .filter(|&t| line.owns(t, s))
                    .collect();
                assert!(
                    owned.len() <= 1,
                    "pitch {pitch} roll {roll} line {index} row {s}"
                );
                exact.extend(owned.into_iter().map(|t| (t, s)));
                s += sector.step;
            }
            let stepped: vec::Vec<(i32, i32)> = line
                .pixels(size.1)
                .map(|p| {
                    let row = size.1 as i32 - 1 - p.y as i32;
                    let t = if sector.along_rows { p.x as i32 } else { row };
                    (t, p.s)
                })
                .collect();
            assert_eq!(stepped, exact, "pitch {pitch} roll {roll} line {index}");
        }
    }
}

#[test]
fn the_tabled_pixels_are_the_stepped_pixels_line_by_line() {
    // Every line's pixels from the frame's table, in order, with the
    // same image position, axis coordinate and offset from the line.
    let mut compared = 0;
    for roll in [0.0, 7.5, 30.0, -60.0, 90.0, 135.0, 180.0] {
        for pitch in [-89.0, -45.0, 0.0, 2.0, 12.0, 45.0, 89.9, 90.0] {
            for (size, hfov) in [((64, 48), 60.0), ((63, 47), 120.0), ((9, 31), 30.0)] {
                let view = rolled(pitch, roll, 25.0, size, hfov);
                let pixels = (size.0 * size.1) as usize;
                let mut line_of = vec![0u16; pixels];
                let mut order = vec![0u32; pixels];
                let mut starts = vec![0u32; view.lines() as usize + 1];
                let table = view
                    .tabulate_pixels(&mut line_of, &mut order, &mut starts)
                    .unwrap();
                assert_eq!(table.order.len(), pixels);
                for index in 0..view.lines() {
                    let range = table.starts[index as usize] as usize
                        ..table.starts[index as usize + 1] as usize;
                    let Some(line) = view.line(index) else {
                        assert!(range.is_empty());
                        continue;
                    };
                    let tabled: vec::Vec<Owned> = table.order[range]
                        .iter()
                        .map(|&p| {
                            line.owned_at((p & 0xFFFF) as i32, (p >> 16) as i32, size.1 as i32 - 1)
                        })
                        .collect();
                    let stepped: vec::Vec<Owned> = line.pixels(size.1).collect();
                    assert_eq!(
                        tabled, stepped,
                        "roll {roll} pitch {pitch} size {size:?} line {index}"
                    );
                    compared += tabled.len();
                }
            }
        }
    }
    assert!(compared > 100_000, "{compared} pixels compared");
    // Too little storage is an error, not a panic.
    let view = view(30.0, 25.0, (16, 8), 60.0);
    let (mut line_of, mut order) = ([0u16; 128], [0u32; 127]);
    let mut starts = vec![0u32; view.lines() as usize + 1];
    assert_eq!(
        view.tabulate_pixels(&mut line_of, &mut order, &mut starts)
            .err(),
        Some(TableError::TooSmall)
    );
}

#[test]
fn at_pitch_zero_the_lines_are_the_columns_bottom_to_top() {
    let view = view(0.0, 40.0, (16, 8), 60.0);
    assert_eq!(view.lines(), 16);
    for column in 0..16 {
        let line = view.line(column).unwrap();
        let pixels: vec::Vec<(u32, u32)> = line.pixels(8).map(|p| (p.x, p.y)).collect();
        let expected: vec::Vec<(u32, u32)> = (0..8).rev().map(|y| (column, y)).collect();
        assert_eq!(pixels, expected);
    }
}

#[test]
fn a_line_ruled_out_of_the_image_owns_no_pixel() {
    // Rolled, steep and level views: every line `line_misses_image`
    // rules out owns no pixel, and it rules out four in five of the
    // lines that own none (the rest cross the image outside their
    // sector).
    let (mut ruled_out, mut empty) = (0, 0);
    for roll in rolls() {
        for pitch in [-45.0, 0.0, 20.0, 60.0, 90.0] {
            for (size, hfov) in [((320, 240), 60.0), ((101, 67), 110.0)] {
                let view = rolled(pitch, roll, 30.0, size, hfov);
                for index in 0..view.lines() {
                    let owns = view.line_pixels(index).count();
                    if view.line_misses_image(index) {
                        assert_eq!(owns, 0, "pitch {pitch} roll {roll} line {index}");
                        ruled_out += 1;
                    }
                    empty += usize::from(owns == 0);
                }
            }
        }
    }
    assert!(
        ruled_out * 5 >= empty * 4,
        "{ruled_out} of {empty} empty lines ruled out"
    );
}

#[test]
fn straight_down_the_lines_fan_out_from_the_center() {
    let view = view(90.0, 0.0, (64, 48), 60.0);
    let center = (31.5f64, 23.5f64);
    let mut last_distance = vec::Vec::new();
    for index in 0..view.lines() {
        let line = view.line(index).unwrap();
        let mut previous = -1.0f64;
        for p in line.pixels(48) {
            let (dx, dy) = (f64::from(p.x) - center.0, f64::from(p.y) - center.1);
            let distance = (dx * dx + dy * dy).sqrt();
            // Away from the nadir, pixel by pixel.
            assert!(
                distance > previous - 0.75,
                "line {index}: {distance} after {previous}"
            );
            previous = distance;
        }
        last_distance.push(previous);
    }
    assert!(view.lines() > 64 && view.lines() <= max_lines(64, 48));
}

#[test]
fn no_view_has_more_lines_than_max_lines() {
    let mut most = 0.0f64;
    for size in [(64, 48), (48, 64), (1, 9), (9, 1), (200, 20), (20, 200)] {
        for hfov in [1.0, 30.0, 60.0, 120.0, 160.0] {
            for (tenth, roll) in (-890..=900)
                .map(|t| (t, 0.0))
                .chain((-89..=90).flat_map(|p| rolls().map(move |r| (p * 10, r))))
            {
                let pitch = tenth as f32 / 10.0;
                let Ok(view) = View::new(
                    &Camera {
                        pitch_deg: pitch,
                        roll_deg: roll,
                        hfov_deg: hfov,
                        ..Camera::default()
                    },
                    size.0,
                    size.1,
                ) else {
                    continue;
                };
                let bound = max_lines(size.0, size.1);
                assert!(
                    view.lines() <= bound,
                    "{size:?} hfov {hfov} pitch {pitch} roll {roll}: {}",
                    view.lines()
                );
                most = most.max(f64::from(view.lines()) / f64::from(bound));
            }
        }
    }
    assert!(most > 0.5, "the bound is not wildly loose: {most}");
}

#[test]
fn a_rays_point_is_within_half_a_pixel_of_its_pixel_center() {
    for pitch in [10.0, 45.0, 80.0, 90.0, -60.0] {
        let view = view(pitch, 10.0, (40, 30), 70.0);
        for index in 0..view.lines() {
            let line = view.line(index).unwrap();
            for p in line.pixels(30) {
                let t = line.cross_at(i64::from(p.s) << COORD_FRAC_BITS) as f64 / 65536.0;
                let own = if line.sector.along_rows {
                    p.x
                } else {
                    29 - p.y
                };
                assert!(
                    (t - f64::from(own)).abs() <= 0.5 + 1e-3,
                    "pitch {pitch}: {t} for {own}"
                );
            }
        }
    }
}

#[test]
fn a_pixels_ray_rises_as_its_centers_direction_does() {
    // Rolled, the lines are slanted and a pixel lies up to half a pixel
    // beside its line, above or below it: its ray takes the vertical
    // component of the direction through its center (to the word),
    // where its line's point would be off by up to half the step
    // across the line's.
    let q32 = |v: i64| v as f64 / 4294967296.0;
    for (pitch, roll) in [
        (0.0, 15.0),
        (0.0, 30.0),
        (10.0, 15.0),
        (45.0, -30.0),
        (20.0, 135.0),
    ] {
        let view = rolled(pitch, roll, 33.0, (200, 150), 70.0);
        let (mut worst, mut line_worst) = (0.0f64, 0.0f64);
        for index in 0..view.lines() {
            let line = view.line(index).unwrap();
            for p in line.pixels(150) {
                let (x, row) = (f64::from(p.x), f64::from(149 - p.y));
                let center = q32(view.base[2].to_bits())
                    + q32(view.per_column[2].to_bits()) * x
                    + q32(view.per_row[2].to_bits()) * row;
                let ray = line.pixel_direction(&p);
                worst = worst.max((q32(ray[2]) - center).abs());
                line_worst = line_worst.max((q32(line.direction(p.along)[2]) - center).abs());
                // The horizontal direction is the line's: its plane.
                assert_eq!(ray[..2], line.direction(p.along)[..2]);
            }
        }
        // A word is 2^−24; the line's own steps add a few of them.
        assert!(worst < 1e-5, "pitch {pitch} roll {roll}: {worst}");
        assert!(
            line_worst > 20.0 * worst,
            "pitch {pitch} roll {roll}: {line_worst} against {worst}"
        );
    }
}

#[test]
fn a_pixels_direction_is_its_lines_direction_at_the_pixel() {
    // The iterator steps the direction by adds; it stays within
    // rounding of the direction through the line's point, worked out
    // from the view's vectors in floating point.
    for pitch in [0.0, 10.0, 45.0, 90.0, -60.0] {
        let view = view(pitch, 33.0, (400, 300), 70.0);
        let q32 = |v: i64| v as f64 / 4294967296.0;
        let mut worst = 0.0f64;
        for index in 0..view.lines() {
            let line = view.line(index).unwrap();
            for p in line.pixels(300) {
                let point = line.cross_at(i64::from(p.s) << COORD_FRAC_BITS) as f64 / 65536.0;
                let (u, v) = if line.sector.along_rows {
                    (point, f64::from(p.s))
                } else {
                    (f64::from(p.s), point)
                };
                for (i, component) in line.direction(p.along).into_iter().enumerate() {
                    let exact = q32(view.base[i].to_bits())
                        + q32(view.per_column[i].to_bits()) * u
                        + q32(view.per_row[i].to_bits()) * v;
                    worst = worst.max((q32(component) - exact).abs());
                }
                if pitch == 0.0 {
                    assert_eq!(p.offset, 0);
                }
            }
        }
        // A ray's direction is about 1 long. A line's step along it is
        // rounded to 2^-25 (a word's unit, to the nearest), so 300 rows
        // along it is within 2^-16: the relative precision of a slope
        // (`slope_quotient`, 2^-15).
        assert!(worst < 1.0 / 65536.0, "pitch {pitch}: {worst}");
    }
}

#[test]
fn a_sector_whose_cone_misses_the_image_has_no_lines() {
    // At 12° down the vanishing point is far below the image: the
    // sectors left and right of it hold no pixel, and only the sector
    // above it has lines (one a column, and a few that end in a
    // corner).
    let view = view(12.0, 0.0, (320, 240), 60.0);
    assert!(view.lines() < 400, "{} lines", view.lines());
    assert!((0..view.lines()).all(|i| view.line(i).unwrap().sector.along_rows));
}
