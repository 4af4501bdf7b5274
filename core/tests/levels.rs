//! The pyramid in the caster: switching levels never skips a hit, and the
//! accelerations (hierarchical first hit, exact coherence) never change the
//! image, at single resolution or on the pyramid.

use terracast::{
    pyramid_cells, pyramid_points, render, Camera, Coherence, CountingProbe, Framebuffer,
    HeightFilter, Pyramid, RenderOptions, Resolution, Terrain, View, U8F8,
};

/// Owns a terrain's storage and its pyramid's.
struct Map {
    side: u32,
    heights: Vec<u16>,
    colors: Vec<[u8; 3]>,
    coarse: (Vec<u16>, Vec<[u8; 3]>, Vec<u16>),
}

impl Map {
    fn new(side: u32, height: impl Fn(u32, u32) -> f32) -> Self {
        let n = (side * side) as usize;
        let heights: Vec<u16> = (0..n as u32)
            .map(|i| Terrain::quantize_height(height(i % side, i / side)).unwrap())
            .collect();
        let colors = (0..n as u32)
            .map(|i| [(i % side * 7 % 256) as u8, (i / side * 3 % 256) as u8, 90])
            .collect();
        let points = pyramid_points(side, side);
        let mut map = Self {
            side,
            heights,
            colors,
            coarse: (
                vec![0; points],
                vec![[0; 3]; points],
                vec![0; pyramid_cells(side, side)],
            ),
        };
        let terrain = Terrain::new(side, side, &map.heights, &map.colors).unwrap();
        let (h, c, b) = &mut map.coarse;
        Pyramid::build(&terrain, HeightFilter::default(), h, c, b).unwrap();
        map
    }

    fn pyramid(&self) -> Pyramid<'_> {
        let terrain = Terrain::new(self.side, self.side, &self.heights, &self.colors).unwrap();
        let (h, c, b) = &self.coarse;
        Pyramid::new(terrain, h, c, b).unwrap()
    }
}

/// Colors and major-axis distances of a render.
fn frame(
    pyramid: &Pyramid<'_>,
    camera: &Camera,
    size: (u32, u32),
    options: &RenderOptions,
) -> (Vec<[u8; 3]>, Vec<u32>, CountingProbe) {
    let n = (size.0 * size.1) as usize;
    let (mut colors, mut distances) = (vec![[0; 3]; n], vec![0; n]);
    let mut fb = Framebuffer::with_distances(&mut colors, &mut distances, size.0, size.1).unwrap();
    let view = View::new(camera, size.0, size.1).unwrap();
    let mut probe = CountingProbe::default();
    render(pyramid, &view, options, &mut fb, &mut probe);
    (colors, distances, probe)
}

fn rough(x: u32, y: u32) -> f32 {
    let (x, y) = (x as f32, y as f32);
    40.0 + 25.0 * (x * 0.05).sin() * (y * 0.037).cos() + 8.0 * ((x * 0.31 + y * 0.17).sin())
}

#[test]
fn first_hit_and_exact_coherence_leave_the_image_unchanged() {
    let map = Map::new(257, rough);
    let pyramid = map.pyramid();
    let cameras = [
        ([5.0, 128.0, 90.0], 0.0, 4.0),
        ([250.0, 20.0, 120.0], 135.0, 25.0),
        ([128.0, 128.0, 160.0], 250.0, 60.0),
        ([60.0, 200.0, 140.0], 300.0, 90.0),
    ];
    for (eye, yaw, pitch) in cameras {
        let camera = Camera::looking(eye, yaw, pitch);
        for resolution in [
            Resolution::Single,
            Resolution::Multi {
                pixel_to_voxel: U8F8::from_num(2),
            },
        ] {
            let options = |coherence, first_hit| RenderOptions {
                coherence,
                resolution,
                hierarchical_first_hit: first_hit,
                ..RenderOptions::default()
            };
            let (base_colors, base_distances, base) =
                frame(&pyramid, &camera, (96, 64), &options(Coherence::Off, false));
            for (coherence, first_hit) in [
                (Coherence::Off, true),
                (Coherence::Exact, false),
                (Coherence::Exact, true),
            ] {
                let (colors, distances, probe) =
                    frame(&pyramid, &camera, (96, 64), &options(coherence, first_hit));
                let case = format!("{camera:?} {resolution:?} {coherence:?} first hit {first_hit}");
                assert_eq!(distances, base_distances, "{case}");
                assert_eq!(colors, base_colors, "{case}");
                assert!(probe.steps <= base.steps, "{case}: more steps");
                if first_hit {
                    assert!(probe.steps < base.steps, "{case}: no steps saved");
                }
            }
        }
    }
}

#[test]
fn a_wall_at_a_level_switch_is_never_skipped() {
    // Flat ground with an 8-voxel-thick wall from x = wall; the eye looks
    // along +x just above the ground, so the wall is the first thing each
    // ray meets. Walls at every position around where levels 1 and 2
    // begin (even and odd grid lines) must be hit at their face, within
    // the filter's spread of a coarse voxel, however the switch falls.
    let focal = 32.0 / (2.0 * 30f64.to_radians().tan()); // 32 px wide, hfov 60°
    for wall in 20u32..130 {
        let map = Map::new(160, |x, _| {
            if (wall..wall + 8).contains(&x) {
                60.0
            } else {
                0.0
            }
        });
        let pyramid = map.pyramid();
        let camera = Camera {
            eye: [0.5, 80.0, 6.0],
            ..Camera::default()
        };
        // The wall makes the map rough: the terrain fit would keep the
        // switch out of the frame.
        let options = RenderOptions {
            coherence: Coherence::Exact,
            terrain_fit: false,
            ..RenderOptions::default()
        };
        let (_, distances, probe) = frame(&pyramid, &camera, (32, 24), &options);
        if f64::from(wall) > 2.0 * focal {
            assert!(probe.steps_by_level[1] > 0 && probe.steps_by_level[2] > 0);
        }
        // The middle column, the rows at and above the horizon: rays that
        // rise gently and meet the wall below its top.
        for row in 6..12 {
            let d = f64::from(distances[row * 32 + 16]) / 65536.0;
            let expected = f64::from(wall) - 0.5;
            assert!(
                // Level l (voxels of 2^l) starts at 2^(l−1)·focal.
                (d - expected).abs() <= (2.0 * f64::from(wall) / focal).max(2.0),
                "wall at {wall} (level 1 from {focal:.0}): row {row} hit at {d:.2}"
            );
        }
    }
}

/// The terrain fit: on a rugged map the pyramid's height levels begin
/// farther out by the fit's factor, exactly as a ratio scaled by hand would
/// place them (colors keep the ratio as given); on a smooth map nothing
/// changes.
#[test]
fn the_terrain_fit_scales_the_ratio_on_rugged_maps_only() {
    let camera = Camera::looking([5.0, 128.0, 70.0], 10.0, 8.0);
    let fit_off = |resolution| RenderOptions {
        resolution,
        terrain_fit: false,
        ..RenderOptions::default()
    };
    // Ridges one voxel high on every other grid line, on a gentle slope:
    // each point is a voxel off the line between its neighbours, so the
    // roughness is 1 voxel per voxel (64/64) and the fit an eighth.
    let rugged = Map::new(257, |x, y| 20.0 + (x % 2) as f32 + 0.3 * y as f32);
    let pyramid = rugged.pyramid();
    let roughness = pyramid.roughness();
    assert_eq!(roughness, 64);
    let fit = terracast::roughness::terrain_fit(roughness);
    assert_eq!(fit, 1 << 13);
    let (fitted, fitted_depths, fitted_probe) =
        frame(&pyramid, &camera, (96, 64), &RenderOptions::default());
    let (given, _, given_probe) = frame(&pyramid, &camera, (96, 64), &fit_off(Resolution::DEFAULT));
    let eighth = Resolution::Multi {
        pixel_to_voxel: U8F8::from_num(0.125),
    };
    let (scaled, scaled_depths, scaled_probe) =
        frame(&pyramid, &camera, (96, 64), &fit_off(eighth));
    assert!(
        fitted_depths == scaled_depths && fitted_probe.steps == scaled_probe.steps,
        "the fit's heights are not the ratio scaled by it"
    );
    assert!(fitted != scaled, "the fit moved the color levels too");
    // Wrapped with its roughness known, the pyramid renders the same; with
    // 0 (unknown) the ratio is used as given.
    let terrain = Terrain::new(257, 257, &rugged.heights, &rugged.colors).unwrap();
    let (h, c, b) = &rugged.coarse;
    let known = Pyramid::with_roughness(terrain, h, c, b, roughness).unwrap();
    let unknown = Pyramid::with_roughness(terrain, h, c, b, 0).unwrap();
    let options = RenderOptions::default();
    assert!(frame(&known, &camera, (96, 64), &options).0 == fitted);
    assert!(frame(&unknown, &camera, (96, 64), &options).0 == given);
    assert!(fitted != given);
    // Levels begin later: more level-0 steps, fewer on the coarse levels.
    assert!(fitted_probe.steps_by_level[0] > given_probe.steps_by_level[0]);
    assert!(
        fitted_probe.steps_by_level[1..].iter().sum::<u64>()
            < given_probe.steps_by_level[1..].iter().sum::<u64>()
    );
    assert_eq!(
        RenderOptions::default().level_bias(roughness),
        fit as f32 / 65536.0
    );

    let smooth = Map::new(257, |x, y| 40.0 + 0.2 * x as f32 + 0.1 * y as f32);
    let pyramid = smooth.pyramid();
    assert_eq!(
        terracast::roughness::terrain_fit(pyramid.roughness()),
        1 << 16
    );
    let (fitted, _, _) = frame(&pyramid, &camera, (96, 64), &RenderOptions::default());
    let (given, _, _) = frame(&pyramid, &camera, (96, 64), &fit_off(Resolution::DEFAULT));
    assert!(fitted == given);
}
