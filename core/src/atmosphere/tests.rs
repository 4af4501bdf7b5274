//! The fixed-point atmosphere against its exact model, a line caster's
//! rays against it, the sky drawn first against pixel by pixel, and the
//! settings it refuses.

use super::sink::inverse_q20;
use super::*;
use crate::Camera;

fn view() -> View {
    View::new(&Camera::looking([100.0, 50.0, 80.0], 30.0, 8.0), 96, 64).unwrap()
}

fn exact_color(air: &Atmosphere, view: &View, x: u32, y: u32, sample: &Sample) -> [f64; 3] {
    let row = i64::from(view.height()) - 1 - i64::from(y);
    let d: [f64; 3] = core::array::from_fn(|i| {
        (view.base[i].to_bits()
            + i64::from(x) * view.per_column[i].to_bits()
            + row * view.per_row[i].to_bits()) as f64
            / 2f64.powi(32)
    });
    let eye = view.eye[2].to_num::<f64>();
    let hit = (!sample.is_sky()).then(|| {
        let major = d[0].abs().max(d[1].abs());
        let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        (
            f64::from(sample.distance) / 65536.0 * length / major,
            f64::from(sample.elevation) / 65536.0,
        )
    });
    air.exact(d, eye, hit, sample.color.map(f64::from))
}

#[test]
fn a_sky_pixel_from_its_cached_cell_is_the_pixels_own_color() {
    // Down the columns and back up, as a line caster's sky comes, and
    // along the rows, each sky pixel's color from the cell kept from
    // the pixel before is `color`'s, with the sun's glow in view (its
    // cells take their own direction) and without it.
    let view = view();
    let sky = Sample::sky([200, 60, 20]);
    let toward_the_sun = Atmosphere {
        sun: Atmosphere::FLIGHT.sun.map(|sun| Sun {
            azimuth_deg: 34.0,
            elevation_deg: 3.0,
            ..sun
        }),
        ..Atmosphere::FLIGHT
    };
    for air in [Atmosphere::FLIGHT, toward_the_sun] {
        let prepared = air.prepare().unwrap();
        let frame = prepared.frame(&view);
        let mut own = 0;
        let columns =
            (0..96).flat_map(|x| (0..64).map(move |y| (x, if x % 2 == 0 { y } else { 63 - y })));
        let rows = (0..64).flat_map(|y| (0..96).map(move |x| (x, y)));
        for order in [columns.collect::<std::vec::Vec<_>>(), rows.collect()] {
            let mut cell = SkyCell::default();
            for (x, y) in order {
                let cached = prepared.pixel_color(&frame, &mut cell, x, y, &sky);
                assert_eq!(cached, prepared.color(&frame, x, y, &sky), "({x}, {y})");
                own += usize::from(cell.own_direction);
            }
        }
        assert_eq!(
            own > 0,
            air.sun.unwrap().azimuth_deg == 34.0,
            "cells near the sun"
        );
    }
}

#[test]
fn fixed_point_matches_the_exact_model_within_two_levels() {
    let view = view();
    let mut hazy = Atmosphere::FLIGHT;
    // The sun in view, so its disc and glow are tested too.
    hazy.sun = hazy.sun.map(|sun| Sun {
        azimuth_deg: 34.0,
        elevation_deg: 3.0,
        ..sun
    });
    let clear = Atmosphere { fog: None, ..hazy };
    for air in [hazy, clear] {
        let prepared = air.prepare().unwrap();
        let frame = prepared.frame(&view);
        let mut worst = 0.0f64;
        let mut sun_pixels = 0;
        for y in 0..64 {
            for x in 0..96 {
                let samples = [
                    Sample::sky([200, 60, 20]),
                    Sample {
                        color: [200, 60, 20],
                        distance: (x * 97 + y * 13 + 1) << 14,
                        elevation: ((x as i32 * 5) % 90) << 16,
                    },
                ];
                for sample in samples {
                    let kernel = prepared.color(&frame, x, y, &sample);
                    let exact = exact_color(&air, &view, x, y, &sample);
                    if sample.is_sky() && kernel == air.sun.unwrap().color {
                        sun_pixels += 1;
                    }
                    for c in 0..3 {
                        worst = worst.max((f64::from(kernel[c]) - exact[c]).abs());
                    }
                }
            }
        }
        assert!(
            air.fog.is_some() || sun_pixels > 0,
            "the sun's disc is in view"
        );
        assert!(worst <= 2.0, "worst channel difference {worst}");
    }
}

#[test]
fn a_line_casters_rays_match_the_exact_model_within_two_levels() {
    // Rendered through the line caster, which gives the sink each
    // ray's slope in its line's plane: every pixel, sky and terrain,
    // within two levels of the exact model along the pixel's own
    // direction (the terrain one color, so the model needs only the
    // hit). Level, pitched up and down, rolled, straight down.
    use crate::{render, Framebuffer, NoProbe, Pyramid, RenderOptions, Terrain};
    const SIDE: usize = 96;
    let heights: std::vec::Vec<u16> = (0..SIDE * SIDE)
        .map(|i| {
            let (x, y) = ((i % SIDE) as f64, (i / SIDE) as f64);
            ((20.0 + 12.0 * (x * 0.21).sin() * (y * 0.17).cos()) * 16.0) as u16
        })
        .collect();
    let colors = std::vec![[200u8, 60, 20]; SIDE * SIDE];
    let terrain = Terrain::new(SIDE as u32, SIDE as u32, &heights, &colors).unwrap();
    let pyramid = Pyramid::flat(terrain);
    let mut air = Atmosphere::FLIGHT;
    air.fog = air.fog.map(|fog| Fog {
        visibility: 60.0,
        ..fog
    });
    // The sun low in the north-east, in view of the first cameras.
    air.sun = air.sun.map(|sun| Sun {
        azimuth_deg: 60.0,
        elevation_deg: 4.0,
        ..sun
    });
    let clear = Atmosphere { fog: None, ..air };
    let (mut suns, mut skies) = (0, 0);
    let cameras = [
        Camera::looking([10.0, 10.0, 40.0], 45.0, 0.0),
        Camera::looking([10.0, 10.0, 40.0], 45.0, 12.0),
        Camera::looking([10.0, 80.0, 30.0], 20.0, -10.0),
        Camera {
            roll_deg: 30.0,
            ..Camera::looking([10.0, 10.0, 40.0], 50.0, 8.0)
        },
        Camera::looking([48.0, 48.0, 90.0], 0.0, 90.0),
    ];
    for (air, camera) in [air, clear]
        .into_iter()
        .flat_map(|air| cameras.map(|camera| (air, camera)))
    {
        let prepared = air.prepare().unwrap();
        let view = View::new(&camera, 80, 60).unwrap();
        let mut hazy = std::vec![[0u8; 3]; 80 * 60];
        let options = RenderOptions::default();
        let mut frame = Framebuffer::new(&mut hazy, 80, 60).unwrap();
        render(
            &pyramid,
            &view,
            &options,
            &mut prepared.sink(&view, &mut frame),
            &mut NoProbe,
        );
        // The sky drawn first gives the same frame, at this size (cells
        // of 2 pixels) and at sizes with cells of 8 and a part cell at
        // the image's right and top edges.
        for (width, height) in [(80, 60), (320, 240), (331, 187)] {
            let view = View::new(&camera, width, height).unwrap();
            let frames = [false, true].map(|first| {
                let mut pixels = std::vec![[0u8; 3]; (width * height) as usize];
                let mut frame = Framebuffer::new(&mut pixels, width, height).unwrap();
                let mut plain;
                let mut over_sky;
                let mut sink: &mut dyn Sink = if first {
                    over_sky = prepared.sink_over_sky(&view, &mut frame);
                    &mut over_sky
                } else {
                    plain = prepared.sink(&view, &mut frame);
                    &mut plain
                };
                // Only the sink that drew the sky says so: a streaming
                // sink's frame must get every sky pixel from the render.
                assert_eq!(sink.sky_is_drawn(), first);
                render(&pyramid, &view, &options, &mut sink, &mut NoProbe);
                pixels
            });
            assert!(
                frames[0] == frames[1],
                "{camera:?} at {width} x {height}: the sky drawn first changes the frame"
            );
        }
        // The elevations, from a capture of the samples.
        let mut samples = std::vec![None; 80 * 60];
        struct Capture<'a>(&'a mut [Option<Sample>]);
        impl Sink for Capture<'_> {
            fn put(&mut self, x: u32, y: u32, sample: Sample) {
                self.0[(y * 80 + x) as usize] = Some(sample);
            }
        }
        render(
            &pyramid,
            &view,
            &options,
            &mut Capture(&mut samples),
            &mut NoProbe,
        );
        let (mut worst, mut sky, mut sun) = (0.0f64, 0, 0);
        for (i, sample) in samples.iter().enumerate() {
            let sample = sample.unwrap();
            sky += usize::from(sample.is_sky());
            sun += usize::from(hazy[i] == air.sun.unwrap().color);
            let (x, y) = ((i % 80) as u32, (i / 80) as u32);
            let exact = exact_color(&air, &view, x, y, &sample);
            for c in 0..3 {
                worst = worst.max((f64::from(hazy[i][c]) - exact[c]).abs());
            }
        }
        assert!(worst <= 2.0, "{camera:?}: worst channel difference {worst}");
        assert!(sky < 80 * 60, "{camera:?} sees terrain");
        suns += sun;
        skies += sky;
    }
    assert!(
        suns > 0 && skies > 80 * 60,
        "the sky and the sun's disc are in view"
    );
}

#[test]
fn the_grid_gives_each_pixel_its_own_directions_sine_and_length() {
    // Level, steep, straight down, rolled, wide and narrow, small and
    // large images: wherever a cell is blended (not marked for each
    // pixel's own direction), the blend is within a part in 1024 of
    // the pixel's own sine (a quarter of a step of the sky's table by
    // sine) and a part in 512 of its reciprocal (which moves the fog's
    // weight by under a fifth of a color level: `e^−1` of 255 times
    // the relative error, at most).
    let cameras = [
        (
            Camera::looking([100.0, 50.0, 80.0], 30.0, 0.0),
            60.0,
            (320, 240),
        ),
        (
            Camera::looking([100.0, 50.0, 80.0], 200.0, 12.0),
            90.0,
            (96, 64),
        ),
        (
            Camera::looking([10.0, 50.0, 800.0], 45.0, 60.0),
            120.0,
            (1024, 768),
        ),
        (
            Camera::looking([10.0, 50.0, 800.0], 0.0, 90.0),
            60.0,
            (333, 211),
        ),
        (
            Camera::looking([10.0, 50.0, 80.0], 0.0, -30.0),
            30.0,
            (640, 360),
        ),
        (
            Camera {
                roll_deg: 35.0,
                ..Camera::looking([10.0, 50.0, 80.0], 70.0, 20.0)
            },
            60.0,
            (320, 240),
        ),
    ];
    let air = Atmosphere::FLIGHT.prepare().unwrap();
    let (mut blended, mut own) = (0, 0);
    for (camera, hfov_deg, (width, height)) in cameras {
        let view = View::new(&Camera { hfov_deg, ..camera }, width, height).unwrap();
        let frame = air.frame(&view);
        let grid = &frame.grid;
        for row in 0..height as i32 {
            for column in 0..width as i32 {
                let (cell, at) = grid.cell(column, row);
                if cell & CELL_MIXED != 0 {
                    own += 1;
                    continue;
                }
                blended += 1;
                let d = direction(&frame.base, &frame.per_column, &frame.per_row, column, row);
                let unit = Unit::new(d);
                let sine = unit.of(d[2]) as i32;
                let got = grid.blend(&grid.sine, &at);
                assert!(
                    (got - sine).abs() <= 1 << (DIR_BITS - 10),
                    "{camera:?} ({column}, {row}): sine {got} against {sine}"
                );
                let [x, y, z] = d.map(i32::unsigned_abs);
                assert_eq!(cell & CELL_VERTICAL != 0, z > x.max(y));
                let reciprocal = reciprocal_q16(unit.of_size(x.max(y).max(z))) as i32;
                let got = grid.blend(&grid.reciprocal, &at);
                assert!(
                    (got - reciprocal).abs() <= reciprocal >> 9,
                    "{camera:?} ({column}, {row}): reciprocal {got} against {reciprocal}"
                );
            }
        }
    }
    // Nearly every pixel is blended.
    assert!(
        own * 20 < blended,
        "{own} pixels take their own direction, {blended} blended"
    );
}

#[test]
fn fog_fades_smoothly_with_distance_without_bands() {
    // A level ray at the ground layer's height, one sixteenth of a
    // voxel farther each time, out to four visibilities: what the fog
    // leaves never rises and never drops by more than one 256th at
    // once (the 8-bit blend's own step), so no band shows.
    let air = Atmosphere::FLIGHT.prepare().unwrap();
    let table = air.fog.as_ref().unwrap();
    let mut before = 256;
    let mut seen = 0;
    for step in 0..(4 * 2500 * 16) {
        let column_q8 = step * 16;
        let weight = table.transmitted(column_q8);
        assert!(weight <= before, "rises at {step}");
        assert!(
            before - weight <= 1,
            "a band at {step}: {before} to {weight}"
        );
        before = weight;
        seen |= 1 << (weight.min(255) / 32);
    }
    assert_eq!(seen, 0xFF, "runs the whole range");
    // At the visibility distance 2 % is left: 5 of 256.
    let at_visibility = table.transmitted(2500 << 8);
    assert!((4..=6).contains(&at_visibility), "{at_visibility}");
}

#[test]
fn what_fog_leaves_is_a_blend_weight_from_all_to_nothing() {
    // Every halving count, in the table and past it, gives a weight from
    // all of the color (256) to none: the blend holds the weight at 256
    // only so that its lookup in `FogTable::toward_fog` needs no bound
    // check, and a larger weight there would leave the color unfogged.
    assert_eq!(left_after(0), 256);
    assert!((0..=u32::from(u16::MAX)).all(|halvings| left_after(halvings) <= 256));
    assert_eq!(left_after(u32::MAX), 0);
}

#[test]
fn the_sky_gradient_has_no_bands_from_horizon_to_zenith() {
    let air = Atmosphere {
        fog: None,
        sun: None,
        ..Atmosphere::FLIGHT
    }
    .prepare()
    .unwrap();
    let frame = air.frame(&view());
    let level = [1 << DIR_BITS, 0, 0];
    let mut before = air.sky_color(&frame, level, &Unit::new(level));
    assert_eq!(before, Atmosphere::FLIGHT.horizon);
    for step in 1..=4096 {
        let angle = f64::from(step) / 4096.0 * core::f64::consts::FRAC_PI_2;
        let d = [angle.cos(), 0.0, angle.sin()].map(|v| (v * f64::from(1 << DIR_BITS)) as i32);
        let color = air.sky_color(&frame, d, &Unit::new(d));
        for c in 0..3 {
            assert!(color[c].abs_diff(before[c]) <= 1, "a band at {step}");
        }
        before = color;
    }
    assert!(before
        .iter()
        .zip(Atmosphere::FLIGHT.zenith)
        .all(|(a, b)| a.abs_diff(b) <= 1));
}

#[test]
fn uniform_fog_hides_the_sky_and_layered_fog_does_not() {
    let view = view();
    let sky = Sample::sky([0; 3]);
    let fog = Atmosphere::FLIGHT.fog.unwrap();
    let uniform = Atmosphere {
        fog: Some(Fog {
            halving: None,
            ..fog
        }),
        sun: None,
        ..Atmosphere::FLIGHT
    };
    let prepared = uniform.prepare().unwrap();
    assert_eq!(
        prepared.color(&prepared.frame(&view), 40, 0, &sky),
        fog.color
    );
    let layered = Atmosphere {
        sun: None,
        ..Atmosphere::FLIGHT
    }
    .prepare()
    .unwrap();
    let top = layered.color(&layered.frame(&view), 40, 0, &sky);
    assert_ne!(top, fog.color);
}

#[test]
fn the_sink_changes_colors_only() {
    let view = view();
    let air = Atmosphere::FLIGHT.prepare().unwrap();
    let mut got = None;
    struct Keep<'a>(&'a mut Option<Sample>);
    impl Sink for Keep<'_> {
        fn put(&mut self, _: u32, _: u32, sample: Sample) {
            *self.0 = Some(sample);
        }
    }
    let hit = Sample {
        color: [10, 200, 30],
        distance: 900 << 16,
        elevation: 20 << 16,
    };
    air.sink(&view, Keep(&mut got)).put(3, 50, hit);
    let got = got.unwrap();
    assert_eq!((got.distance, got.elevation), (hit.distance, hit.elevation));
    assert_ne!(got.color, hit.color, "900 voxels of haze show");
}

#[test]
fn a_lines_shade_is_its_planes_length_and_its_reciprocal() {
    // m = √(1 + dminor²) within two units of Q16 (a part in 2^15) at
    // every minor slope the caster gives (within ±1), and 1/m exactly
    // ⌊2^36 / m⌋.
    for dminor in (-(1 << 16)..=1 << 16)
        .step_by(7)
        .chain([1 << 16, -(1 << 16)])
    {
        let shade = LineShade::new(&LinePlane { dminor });
        let exact = (1.0 + (f64::from(dminor) / 65536.0).powi(2)).sqrt() * 65536.0;
        assert!(
            (f64::from(shade.m) - exact).abs() <= 2.0,
            "dminor {dminor}: m {} against {exact}",
            shade.m
        );
        assert_eq!(
            u64::from(shade.inverse_m),
            (1u64 << 36) / u64::from(shade.m)
        );
    }
    assert_eq!(inverse_q20(1 << 16), 1 << 20);
}

#[test]
fn a_rays_length_is_within_a_part_in_2_to_the_11_at_every_slope() {
    // `√(m² + slope²)` for planes from along an axis to the diagonal, and
    // slopes from level to the steepest with a run, both signs: the
    // shallow and the steep branch, and both sides of where they meet.
    let mut worst: f64 = 0.0;
    for dminor in [0, 1 << 14, 27_000, 1 << 16] {
        let shade = LineShade::new(&LinePlane { dminor });
        let m = f64::from(shade.m);
        let slopes = (0..4000)
            .map(|i| (f64::from(i) / 4000.0).powi(4) * f64::from(MAX_SLOPE_Q16 - 1))
            .map(|s| s as i32)
            .chain([shade.m as i32 - 1, shade.m as i32, shade.m as i32 + 1]);
        for slope in slopes.flat_map(|s| [s, -s]) {
            let exact = (m * m + f64::from(slope).powi(2)).sqrt();
            let error = (f64::from(shade.ray_length(slope)) - exact).abs() / exact;
            worst = worst.max(error);
            assert!(
                error < 1.0 / 2048.0,
                "dminor {dminor} slope {slope}: {} against {exact}",
                shade.ray_length(slope)
            );
        }
    }
    println!("a ray's length: worst {worst:.2e}");
}

#[test]
fn unit_directions_and_reciprocals_are_within_a_part_in_2_to_the_14() {
    // Directions from length 1 to 100, every way.
    for step in 0..20_000 {
        let t = f64::from(step);
        let length = 1.0 + 99.0 * (t * 0.618).fract().powi(3);
        let (a, b) = (t * 0.37, t * 0.11);
        let true_unit = [a.cos() * b.cos(), a.sin() * b.cos(), b.sin()];
        let d = true_unit.map(|v| (v * length * f64::from(1 << DIR_BITS)).round() as i32);
        let exact = {
            let n = d.map(f64::from);
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            n.map(|v| v / len * f64::from(1 << DIR_BITS))
        };
        let unit = Unit::new(d);
        for i in 0..3 {
            let got = unit.of(d[i]) as f64;
            assert!(
                (got - exact[i]).abs() <= 1.0 + f64::from(1 << 6),
                "{d:?}: {got} against {}",
                exact[i]
            );
        }
    }
    for x in (1 << 19..=1 << 20).step_by(37) {
        let exact = f64::from(1u32 << 16) * f64::from(1u32 << 20) / f64::from(x);
        let got = f64::from(reciprocal_q16(x));
        assert!(
            (got - exact).abs() <= exact / f64::from(1 << 14),
            "1/{x}: {got} against {exact}"
        );
    }
}

#[test]
fn past_the_opaque_distance_no_hit_below_the_highest_shows() {
    for fog in [
        Atmosphere::FLIGHT.fog.unwrap(),
        Fog {
            halving: None,
            ..Atmosphere::FLIGHT.fog.unwrap()
        },
    ] {
        for (eye, highest) in [(10.0, 5.0), (200.0, 180.0), (50.0, 300.0), (400.0, 20.0)] {
            let far = fog.opaque_distance(eye, highest);
            for hit in [0.0, highest / 3.0, highest] {
                // Along the path, or farther.
                for length in [far, far * 1.5] {
                    let kept = fog.transmittance(length, eye, hit);
                    assert!(
                        kept <= 1.0 / 512.0 + 1e-12,
                        "{fog:?} {eye} {highest} {hit}: {kept}"
                    );
                }
            }
            // And no sooner than it must: a level path at the higher
            // of the two keeps exactly a 512th there.
            let top = f64::max(eye, highest);
            let kept = fog.transmittance(far, top, top);
            assert!((kept * 512.0 - 1.0).abs() < 1e-9, "{kept}");
        }
    }
    // Uniform fog of visibility 2500: about 4000 voxels.
    let uniform = Fog {
        halving: None,
        visibility: 2500.0,
        ..Atmosphere::FLIGHT.fog.unwrap()
    };
    assert!((uniform.opaque_distance(100.0, 50.0) - 3986.6).abs() < 0.1);
}

#[test]
fn bad_settings_are_refused() {
    let mut air = Atmosphere::FLIGHT;
    air.fog = air.fog.map(|fog| Fog {
        visibility: 2.0,
        ..fog
    });
    assert_eq!(air.prepare().unwrap_err(), AtmosphereError::Fog);
    let mut air = Atmosphere::FLIGHT;
    air.sun = air.sun.map(|sun| Sun {
        disc_deg: 20.0,
        ..sun
    });
    assert_eq!(air.prepare().unwrap_err(), AtmosphereError::Sun);
    let mut air = Atmosphere::FLIGHT;
    air.sun = air.sun.map(|sun| Sun {
        azimuth_deg: f32::NAN,
        ..sun
    });
    assert_eq!(air.prepare().unwrap_err(), AtmosphereError::NotFinite);
}
