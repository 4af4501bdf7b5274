//! The frame-budget governor: over 10 000 frames of varied flights (pitch 2°
//! to 90°, fast turns, low passes over cliffs) no frame costs more than its
//! budget at the board's prices, most spend nearly all of it, and the same
//! flight gives the same choices twice.

use terracast::{
    Camera, CountingProbe, FrameCost, Governor, RenderOptions, Sample, Sink, Surface, View,
};
use terracast_sim::scene::{procedural, KernelScene, Scene};

const SIZE: (u32, u32) = (96, 72);
const FRAMES: usize = 10_000;

struct Discard;

impl Sink for Discard {
    fn put(&mut self, _: u32, _: u32, _: Sample) {}
}

/// The procedural scene with cliffs: every fourth band of 16 voxels raised
/// by 220.
fn cliffs() -> Scene {
    let mut scene: Scene = procedural(256, 4);
    let side = scene.width;
    for (i, h) in scene.heights.iter_mut().enumerate() {
        if (i as u32 % side / 16) % 4 == 1 {
            *h += 220.0;
        }
    }
    scene
}

/// Frame `i` of a flight that keeps changing: pitch sweeping 2° to 90° and
/// back, turns of up to 40° a frame, and every other stretch of 500 frames
/// flown 4 to 14 voxels above the ground, over the cliffs' edges.
fn camera(scene: &Scene, i: usize) -> Camera {
    let t = i as f32;
    let pitch = 2.0 + 88.0 * (0.5 - 0.5 * (t * 0.013).cos());
    let yaw = (t * 17.0 + 40.0 * (t * 0.07).sin() * t.sqrt().min(8.0)) % 360.0;
    let (x, y) = (
        128.0 + 110.0 * (t * 0.004).sin(),
        128.0 + 110.0 * (t * 0.0031).cos(),
    );
    let ground = scene.heights[y as usize * scene.width as usize + x as usize];
    let low = (i / 500) % 2 == 1;
    let z = if low {
        ground + 4.0 + 10.0 * (t * 0.05).sin().abs()
    } else {
        ground + 150.0
    };
    Camera::looking([x, y, z], yaw, pitch)
}

/// Each frame's cost and its view's line count.
fn fly(scene: &Scene, kernel: &KernelScene, budget: u64) -> Vec<(FrameCost, u32)> {
    let pyramid = kernel.pyramid().expect("pyramid");
    let mut governor = Governor::on_board(budget);
    (0..FRAMES)
        .map(|i| governed(&mut governor, &pyramid, &camera(scene, i)))
        .collect()
}

/// One frame of `camera` by `governor`: its cost and its view's line count.
fn governed(governor: &mut Governor, surface: &impl Surface, camera: &Camera) -> (FrameCost, u32) {
    let view = View::new(camera, SIZE.0, SIZE.1).expect("view");
    let cost = governor.render(
        surface,
        &view,
        &RenderOptions::default(),
        &mut Discard,
        &mut CountingProbe::default(),
    );
    (cost, view.lines())
}

/// Flies at `per_pixel` of the board's instructions a pixel, prints what
/// the governor did, checks that no frame went over (and with `repeat`,
/// that the same flight repeats); returns the frames.
fn fly_within(
    scene: &Scene,
    kernel: &KernelScene,
    per_pixel: u64,
    repeat: bool,
) -> Vec<(FrameCost, u32)> {
    let budget = u64::from(SIZE.0 * SIZE.1) * per_pixel;
    let frames = fly(scene, kernel, budget);
    let costs: Vec<&FrameCost> = frames.iter().map(|(c, _)| c).collect();
    let over: Vec<usize> = (0..FRAMES).filter(|&i| costs[i].cost > budget).collect();
    let coarse = costs.iter().filter(|c| c.coarse_lines > 0).count();
    let filled = costs.iter().filter(|c| c.filled_rays > 0).count();
    let share = |c: &FrameCost| c.cost as f64 / budget as f64;
    let mean = costs.iter().map(|c| share(c)).sum::<f64>() / FRAMES as f64;
    let full = costs.iter().filter(|c| share(c) >= 0.9).count();
    let biases: Vec<f64> = costs.iter().map(|c| c.level_bias.to_num::<f64>()).collect();
    println!(
        "{FRAMES} frames of {}x{}, budget {per_pixel} a pixel at the board's prices: mean {:.1} % \
         of it, {full} frames at 90 % or more, least {:.1} %, most {:.1} %; frames finished \
         coarser: {coarse}; frames with repeated pixels: {filled}; level bias {:.2} to {:.2}",
        SIZE.0,
        SIZE.1,
        100.0 * mean,
        100.0 * costs.iter().map(|c| share(c)).fold(f64::INFINITY, f64::min),
        100.0 * costs.iter().map(|c| share(c)).fold(0.0, f64::max),
        biases.iter().cloned().fold(f64::INFINITY, f64::min),
        biases.iter().cloned().fold(0.0, f64::max),
    );
    assert!(over.is_empty(), "frames over budget: {over:?}");
    // Deterministic: the same flight, the same choices.
    assert!(
        !repeat || fly(scene, kernel, budget) == frames,
        "a second flight chose otherwise"
    );
    frames
}

#[test]
fn no_frame_exceeds_its_budget_and_the_choices_repeat() {
    let scene = cliffs();
    let kernel = scene.to_kernel().expect("scene");
    // Below what the steep views' base pass costs at a bias of 1 (about
    // 1400 of the board's instructions a pixel, more from the eye and
    // over the cliffs): the governor must coarsen.
    let tight = fly_within(&scene, &kernel, 1200, true);
    assert!(
        tight
            .iter()
            .any(|(c, _)| c.level_bias.to_num::<f64>() > 1.0),
        "the bias never moved"
    );
    // Room to spare: the refinement spends it, unless both its rounds
    // refined every line of the frame (a frame of sky has nothing to buy).
    let loose = fly_within(&scene, &kernel, 3000, false);
    let budget = u64::from(SIZE.0 * SIZE.1) * 3000;
    let unspent: Vec<usize> = (0..FRAMES)
        .filter(|&i| {
            let (cost, lines) = &loose[i];
            cost.cost * 10 < budget * 9 && cost.refined_lines < 2 * *lines
        })
        .collect();
    assert!(
        unspent.is_empty(),
        "{} frames left over a tenth of the budget with lines not refined twice: {:?}",
        unspent.len(),
        &unspent[..unspent.len().min(20)]
    );
}

/// A view that swings from 2° to 90° pitch and back, twice, over 400
/// frames: the governor's level bias follows it without oscillating (it
/// turns from coarser to finer or back a few times a swing, never frame
/// after frame), and every frame spends the budget or has refined every
/// line.
#[test]
fn the_bias_follows_a_swinging_view_without_oscillating() {
    let scene = cliffs();
    let kernel = scene.to_kernel().expect("scene");
    let pyramid = kernel.pyramid().expect("pyramid");
    // Tight: the steep views' base pass costs about this much at a bias
    // of 1, so the bias must follow the swing.
    let per_pixel = 1400;
    let budget = u64::from(SIZE.0 * SIZE.1) * per_pixel;
    let mut governor = Governor::on_board(budget);
    let frames = 400;
    let mut biases = Vec::new();
    let mut unspent = Vec::new();
    for i in 0..frames {
        let t = i as f32 / 200.0 * std::f32::consts::TAU;
        let pitch = 2.0 + 88.0 * (0.5 - 0.5 * t.cos());
        let camera = Camera::looking([40.0, 60.0, 420.0], 35.0, pitch);
        let (cost, lines) = governed(&mut governor, &pyramid, &camera);
        assert!(cost.cost <= budget, "frame {i}: {cost:?}");
        if cost.cost * 10 < budget * 9 && cost.refined_lines < 2 * lines {
            unspent.push(i);
        }
        biases.push(cost.level_bias.to_bits());
    }
    // Where the bias turns: a rise after a fall, or a fall after a rise.
    let moves: Vec<i32> = biases
        .windows(2)
        .map(|w| (i32::from(w[1]) - i32::from(w[0])).signum())
        .filter(|&m| m != 0)
        .collect();
    let turns = moves.windows(2).filter(|m| m[0] != m[1]).count();
    println!(
        "{frames} frames swinging 2° to 90° and back twice, budget {per_pixel} a pixel: bias {:.2} to {:.2}, {} changes, {turns} turns; {} frames left a tenth unspent",
        f64::from(*biases.iter().min().unwrap_or(&0)) / 256.0,
        f64::from(*biases.iter().max().unwrap_or(&0)) / 256.0,
        moves.len(),
        unspent.len()
    );
    assert!(
        unspent.is_empty(),
        "frames that left budget unspent: {unspent:?}"
    );
    assert!(
        (2..=8).contains(&turns),
        "the bias turned {turns} times: {biases:?}"
    );
}
