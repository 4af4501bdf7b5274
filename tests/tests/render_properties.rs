//! The render path under random input: random terrains (flat, spiky,
//! cliffs of 4000, one-voxel ridges, all at the highest height, noise),
//! random cameras over the whole range `View::new` takes (eye anywhere
//! within the config's limits, below the surface and far outside the map;
//! every yaw; pitch −89° to 90°; roll −180° to 180°; fields of view 1° to
//! 160°; images 1 × 1 up to 64 × 64, one in a hundred up to 512 × 512),
//! terrains 2 to 96 a side (one in forty up to 1024), every kernel setting,
//! and the governor with budgets down to 0.
//!
//! Held on every render: no panic; every pixel written exactly once; a
//! sky sample has the sky's color, and a hit lies no higher than the
//! terrain's highest point (to the crossing's precision, see
//! `Checked::top`; a frame the governor starves shades its cut rays where
//! they stopped); a budgeted frame takes no more steps than its budget.
//!
//! Seeded (ChaCha from a fixed seed for each of [`SHARDS`] shards, which
//! run on all the cores; each terrain's cameras from its own seed), so a
//! failure repeats on any machine; `PROPTEST_CASES` sets the number of
//! terrains (800 by default) for a longer or shorter run. Each terrain is
//! rendered from [`CAMERAS_A_CASE`] cameras with every setting on the
//! pyramid and on level 0 alone, with rays by footprint and with the
//! governor, and turned level by the two column casters (the per-line
//! design's bound renderers; the lean one's frame is the other's, bit for
//! bit): the default run renders about 1.43 million views (it prints
//! the count and the time).

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use terracast::config::{
    HFOV_RANGE_DEG, MAX_EYE_COORD, MAX_EYE_HEIGHT, PITCH_RANGE_DEG, ROLL_RANGE_DEG,
};
use terracast::{
    level_count, pyramid_cells, pyramid_points, render, render_by_footprint, render_level_columns,
    render_level_columns_lean, Camera, Coherence, CountingProbe, Framebuffer, Governor,
    HeightFilter, HeightPath, NoProbe, Pyramid, RenderOptions, Resolution, Rgb, Sample, Shading,
    Sink, Terrain, VerticalSamples, View, ViewError, U8F8,
};

/// Terrains a default run draws: about a million views, a minute or two
/// in release mode on the 2-core development machine.
const CASES: u32 = 800;
/// Cameras each terrain is rendered from.
const CAMERAS_A_CASE: usize = 40;

/// A sink that counts the writes to each pixel and checks each sample.
struct Checked {
    width: u32,
    writes: Vec<u8>,
    bad_samples: u32,
    /// The first wrong write, described.
    first_bad: Option<String>,
    /// The highest a hit may be (I16.16): the terrain's top, 8 voxels, and
    /// 1/16 of the eye's height over the top. A crossing is placed to 1/256
    /// of the span between the samples either side, which a first-hit skip
    /// or a coarse level and a steep ray can make tall; a wrapped or
    /// garbage height is far past this.
    top: i64,
    /// The sky's color, where a pixel is one ray (more rays blend a
    /// pixel that is mostly sky toward the terrain's color).
    sky: Option<Rgb>,
    /// The most times a pixel may be written: once, or three times where
    /// a budget's refinement renders lines again (in its two rounds).
    most_writes: u8,
}

impl Checked {
    fn new(width: u32, height: u32, (highest, eye_z): (u16, f32), one_ray: bool) -> Self {
        let top = (i64::from(highest) << 12) + (8 << 16);
        let above = ((f64::from(eye_z) * 65536.0) as i64 - top).max(0);
        Self {
            width,
            writes: vec![0; (width * height) as usize],
            bad_samples: 0,
            first_bad: None,
            top: top + above / 16,
            sky: one_ray.then_some(RenderOptions::default().sky),
            most_writes: 1,
        }
    }

    /// Every pixel written once (at least once and at most
    /// `most_writes`) and every sample sane.
    fn verdict(&self) -> Result<(), String> {
        if let Some(at) = self
            .writes
            .iter()
            .position(|&n| n == 0 || n > self.most_writes)
        {
            let (x, y) = (at as u32 % self.width, at as u32 / self.width);
            return Err(format!(
                "pixel ({x}, {y}) written {} times",
                self.writes[at]
            ));
        }
        if self.bad_samples > 0 {
            return Err(format!(
                "{} samples off the image, skies of another color or hits above the terrain, first {}",
                self.bad_samples,
                self.first_bad.as_deref().unwrap_or("")
            ));
        }
        Ok(())
    }
}

impl Sink for Checked {
    fn put(&mut self, x: u32, y: u32, sample: Sample) {
        let inside = match self.writes.get_mut((y * self.width + x) as usize) {
            Some(n) if x < self.width => {
                *n = n.saturating_add(1);
                true
            }
            _ => false,
        };
        let sane = if sample.is_sky() {
            self.sky.is_none_or(|sky| sample.color == sky)
        } else {
            i64::from(sample.elevation) <= self.top
        };
        if !inside || !sane {
            self.bad_samples += 1;
            self.first_bad
                .get_or_insert_with(|| format!("({x}, {y}): {sample:?}"));
        }
    }
}

/// The kinds of terrain where casters are known to break.
#[derive(Debug, Clone, Copy)]
enum Shape {
    Flat(u16),
    Spikes,
    Cliff,
    Ridges,
    AllHighest,
    Noise,
}

fn heights(shape: Shape, width: u32, depth: u32, seed: u64) -> Vec<u16> {
    let highest = u16::MAX;
    (0..depth)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let hash = ((u64::from(x) * 0x9E37_79B9) ^ (u64::from(y) * 0x85EB_CA6B) ^ seed)
                .wrapping_mul(0xC2B2_AE35);
            match shape {
                Shape::Flat(h) => h,
                Shape::Spikes => {
                    if hash % 7 == 0 {
                        highest
                    } else {
                        0
                    }
                }
                // 4000 voxels, U12.4.
                Shape::Cliff => {
                    if x < width / 2 {
                        16
                    } else {
                        4000 * 16
                    }
                }
                Shape::Ridges => {
                    if x % 4 == 0 {
                        800
                    } else {
                        0
                    }
                }
                Shape::AllHighest => highest,
                Shape::Noise => (hash >> 20) as u16 & highest,
            }
        })
        .collect()
}

fn shape() -> impl Strategy<Value = Shape> {
    prop_oneof![
        any::<u16>().prop_map(Shape::Flat),
        Just(Shape::Spikes),
        Just(Shape::Cliff),
        Just(Shape::Ridges),
        Just(Shape::AllHighest),
        Just(Shape::Noise),
    ]
}

/// A terrain: its shape, size (2 to 96 a side, and one in forty up to
/// 1024) and a seed.
fn terrain() -> impl Strategy<Value = (Shape, u32, u32, u64)> {
    let side = || prop_oneof![39 => 2u32..=96, 1 => 97u32..=1024];
    (shape(), side(), side(), any::<u64>())
}

/// A camera anywhere `View::new` takes one, and an image size; a few
/// draws outside the ranges check that they are refused, not rendered.
fn camera(rng: &mut TestRng, side: f32) -> (Camera, u32, u32) {
    let mut between = |lo: f32, hi: f32| lo + (hi - lo) * (rng.next_u32() as f32 / u32::MAX as f32);
    let eye = if between(0.0, 1.0) < 0.7 {
        // Over the map or near it: where the pictures are.
        [
            between(-side, 2.0 * side),
            between(-side, 2.0 * side),
            between(-50.0, 4500.0),
        ]
    } else {
        [
            between(-MAX_EYE_COORD, MAX_EYE_COORD),
            between(-MAX_EYE_COORD, MAX_EYE_COORD),
            between(-MAX_EYE_HEIGHT, MAX_EYE_HEIGHT),
        ]
    };
    let camera = Camera {
        eye,
        yaw_deg: between(-360.0, 360.0),
        pitch_deg: between(PITCH_RANGE_DEG.0, PITCH_RANGE_DEG.1),
        roll_deg: if between(0.0, 1.0) < 0.3 {
            0.0
        } else {
            between(ROLL_RANGE_DEG.0, ROLL_RANGE_DEG.1)
        },
        hfov_deg: between(HFOV_RANGE_DEG.0, HFOV_RANGE_DEG.1),
    };
    // Mostly small images; one camera in a hundred up to 512 a side.
    let most = if rng.next_u32() % 100 == 0 { 512 } else { 64 };
    let size = |rng: &mut TestRng| 1 + rng.next_u32() % most;
    let (width, height) = (size(rng), size(rng));
    (camera, width, height)
}

/// Every setting the kernel has, each a render.
fn settings() -> Vec<RenderOptions> {
    let multi = |bits| Resolution::Multi {
        pixel_to_voxel: U8F8::from_bits(bits),
    };
    let mut all = Vec::new();
    for coherence in [Coherence::Off, Coherence::Exact, Coherence::AcrossLevels] {
        for resolution in [Resolution::Single, multi(256), multi(64), multi(1024)] {
            all.push(RenderOptions {
                coherence,
                resolution,
                ..RenderOptions::default()
            });
        }
    }
    for vertical_samples in [VerticalSamples::Two, VerticalSamples::Eight] {
        all.push(RenderOptions {
            vertical_samples,
            ..RenderOptions::default()
        });
    }
    for shading in [Shading::Nearest, Shading::LevelZero] {
        all.push(RenderOptions {
            shading,
            ..RenderOptions::default()
        });
    }
    all.push(RenderOptions {
        hierarchical_first_hit: false,
        terrain_fit: false,
        ..RenderOptions::default()
    });
    for resolution in [Resolution::Single, multi(256)] {
        for shading in [Shading::Subvoxel, Shading::Nearest] {
            all.push(RenderOptions {
                resolution,
                shading,
                height_path: HeightPath::Ray,
                ..RenderOptions::default()
            });
        }
    }
    all
}

/// Renders one terrain from many cameras with every setting, the
/// governor and rays by footprint; the first broken property, if any.
fn check_terrain(
    (shape, width, depth, seed): (Shape, u32, u32, u64),
    rendered: &mut u64,
) -> Result<(), String> {
    // The cameras follow from the case, so a failing case repeats alone.
    let mut seed_bytes = [0u8; 32];
    seed_bytes[..8].copy_from_slice(&seed.to_le_bytes());
    let rng = &mut TestRng::from_seed(RngAlgorithm::ChaCha, &seed_bytes);
    let heights = heights(shape, width, depth, seed);
    let colors: Vec<Rgb> = (0..heights.len())
        .map(|i| [(i * 7) as u8, (i * 13) as u8, (i * 29) as u8])
        .collect();
    let terrain = Terrain::new(width, depth, &heights, &colors).map_err(|e| e.to_string())?;
    let mut level_heights = vec![0u16; pyramid_points(width, depth)];
    let mut level_colors = vec![[0u8; 3]; pyramid_points(width, depth)];
    let mut bounds = vec![0u16; pyramid_cells(width, depth)];
    Pyramid::build(
        &terrain,
        HeightFilter::default(),
        &mut level_heights,
        &mut level_colors,
        &mut bounds,
    )
    .map_err(|e| e.to_string())?;
    let pyramid =
        Pyramid::new(terrain, &level_heights, &level_colors, &bounds).map_err(|e| e.to_string())?;
    let flat = Pyramid::flat(terrain);
    let highest = heights.iter().copied().max().unwrap_or(0);
    let settings = settings();
    let levels = level_count(width, depth);
    for _ in 0..CAMERAS_A_CASE {
        let (camera, w, h) = camera(rng, width.max(depth) as f32);
        let view = match View::new(&camera, w, h) {
            Ok(view) => view,
            // Too tall an image for a wide field of view: refused, rightly.
            Err(ViewError::AspectOutOfRange) => continue,
            Err(e) => return Err(format!("{camera:?} {w}x{h} refused: {e}")),
        };
        let context = |what: &str, why: String| {
            format!(
                "{what}: {why}; {shape:?} {width}x{depth} ({levels} levels), {camera:?}, {w}x{h}"
            )
        };
        for options in &settings {
            let one_ray = options.vertical_samples == VerticalSamples::One;
            for surface in [&pyramid, &flat] {
                let mut sink = Checked::new(w, h, (highest, camera.eye[2]), one_ray);
                render(surface, &view, options, &mut sink, &mut NoProbe);
                sink.verdict()
                    .map_err(|why| context(&format!("{options:?}"), why))?;
                *rendered += 1;
            }
        }
        let mut sink = Checked::new(w, h, (highest, camera.eye[2]), false);
        render_by_footprint(
            &pyramid,
            &view,
            &RenderOptions::default(),
            &mut sink,
            &mut NoProbe,
        );
        sink.verdict()
            .map_err(|why| context("rays by footprint", why))?;
        // Up to 4500 of the board's instructions a pixel, down to none.
        let budget = u64::from(rng.next_u32() % 4) * u64::from(rng.next_u32() % (w * h * 1500 + 1));
        let mut governor = Governor::on_board(budget);
        // A ray the budget cuts short is shaded where it stopped, in the
        // air: no height check here.
        // Refined lines are written again, with two to eight rays a pixel.
        let mut sink = Checked {
            most_writes: 3,
            ..Checked::new(w, h, (u16::MAX, f32::MAX), false)
        };
        let mut probe = CountingProbe::default();
        let cost = governor.render(
            &pyramid,
            &view,
            &RenderOptions::default(),
            &mut sink,
            &mut probe,
        );
        sink.verdict()
            .map_err(|why| context(&format!("budget {budget}"), why))?;
        if cost.cost > budget.max(governor.least_cost(&view, &RenderOptions::default())) {
            return Err(context(
                "governor",
                format!("cost {} over a budget of {budget}", cost.cost),
            ));
        }
        *rendered += 2;
        // The column casters, on the camera turned level: every pixel
        // once, and the lean one's frame the plain one's.
        if let Ok(view) = View::new(&camera.turned_level(), w, h) {
            let single = RenderOptions {
                resolution: Resolution::Single,
                ..RenderOptions::default()
            };
            let mut sink = Checked::new(w, h, (highest, camera.eye[2]), true);
            render_level_columns(&terrain, &view, &single, &mut sink)
                .map_err(|e| context("columns", e.to_string()))?;
            sink.verdict().map_err(|why| context("columns", why))?;
            let mut colors = vec![[0u8; 3]; (w * h) as usize];
            let mut frame = Framebuffer::new(&mut colors, w, h).map_err(|e| e.to_string())?;
            render_level_columns(&terrain, &view, &single, &mut frame)
                .map_err(|e| context("columns", e.to_string()))?;
            let mut lean = vec![[1u8, 2, 3]; (w * h) as usize];
            render_level_columns_lean(&terrain, &view, &single, &mut lean)
                .map_err(|e| context("lean columns", e.to_string()))?;
            if lean != colors {
                return Err(context(
                    "lean columns",
                    "a frame unlike the columns'".into(),
                ));
            }
            *rendered += 3;
        }
    }
    Ok(())
}

/// The run's terrains are drawn in this many shards, each from its own
/// seed, so that the shards run on all the cores while the terrains drawn
/// stay the same on every machine.
const SHARDS: u8 = 4;

#[test]
fn every_render_writes_every_pixel_once_and_keeps_its_budget() {
    let cases: u32 = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(CASES);
    let started = std::time::Instant::now();
    let next_shard = std::sync::atomic::AtomicU8::new(0);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    // Each thread takes the next shard until none is left; every shard
    // reports its views and its first failure.
    let outcomes: Vec<(u64, Option<String>)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads.min(usize::from(SHARDS)))
            .map(|_| {
                scope.spawn(|| {
                    let mut outcomes = Vec::new();
                    loop {
                        let shard = next_shard.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        if shard >= SHARDS {
                            return outcomes;
                        }
                        // The cases split as evenly as they go.
                        let shard_cases =
                            (cases + u32::from(SHARDS - 1 - shard)) / u32::from(SHARDS);
                        outcomes.push(run_shard(shard, shard_cases));
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|worker| worker.join().expect("a shard's thread panicked"))
            .collect()
    });
    let rendered: u64 = outcomes.iter().map(|(views, _)| views).sum();
    println!(
        "{rendered} views rendered over {cases} terrains in {:.1} s",
        started.elapsed().as_secs_f64()
    );
    let failures: Vec<&String> = outcomes.iter().filter_map(|(_, e)| e.as_ref()).collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Draws `cases` terrains from shard `shard`'s seed and checks each: the
/// views rendered and the first failure (proptest's shrunk case).
fn run_shard(shard: u8, cases: u32) -> (u64, Option<String>) {
    let config = Config {
        cases,
        failure_persistence: None,
        rng_algorithm: RngAlgorithm::ChaCha,
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(
        config,
        TestRng::from_seed(RngAlgorithm::ChaCha, &[7 + shard; 32]),
    );
    let rendered = std::cell::Cell::new(0u64);
    let result = runner.run(&terrain(), |case| {
        let mut count = rendered.get();
        let outcome = check_terrain(case, &mut count);
        rendered.set(count);
        outcome.map_err(TestCaseError::fail)
    });
    (
        rendered.get(),
        result.err().map(|e| format!("shard {shard}: {e}")),
    )
}
