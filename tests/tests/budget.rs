//! The frame-budget governor: over 10 000 frames of varied flights (pitch 2°
//! to 90°, fast turns, low passes over cliffs) no frame takes more steps than
//! its budget, and the same flight gives the same choices twice.

use terracast::{Camera, CountingProbe, FrameCost, Governor, RenderOptions, Sample, Sink, View};
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

fn fly(scene: &Scene, kernel: &KernelScene, budget: u64) -> Vec<FrameCost> {
    let pyramid = kernel.pyramid().expect("pyramid");
    let mut governor = Governor::new(budget);
    (0..FRAMES)
        .map(|i| {
            let view = View::new(&camera(scene, i), SIZE.0, SIZE.1).expect("view");
            governor.render(
                &pyramid,
                &view,
                &RenderOptions::default(),
                &mut Discard,
                &mut CountingProbe::default(),
            )
        })
        .collect()
}

#[test]
fn no_frame_exceeds_its_budget_and_the_choices_repeat() {
    let scene = cliffs();
    let kernel = scene.to_kernel().expect("scene");
    // A step and a half a pixel: the default renders these views at 0.6 to
    // 1.6 steps a pixel, more from the eye and over the cliffs.
    let budget = u64::from(SIZE.0 * SIZE.1) * 3 / 2;
    let costs = fly(&scene, &kernel, budget);
    let over: Vec<usize> = (0..FRAMES).filter(|&i| costs[i].steps > budget).collect();
    let coarse = costs.iter().filter(|c| c.coarse_lines > 0).count();
    let filled = costs.iter().filter(|c| c.filled_rays > 0).count();
    let mean_steps = costs.iter().map(|c| c.steps).sum::<u64>() as f64 / FRAMES as f64;
    let biases: Vec<f64> = costs.iter().map(|c| c.level_bias.to_num::<f64>()).collect();
    println!(
        "{FRAMES} frames of {}x{}, budget {budget} steps: mean {mean_steps:.0} ({:.0} %), max {}; \
         frames finished coarser: {coarse}; frames with repeated pixels: {filled}; \
         level bias {:.2} to {:.2}",
        SIZE.0,
        SIZE.1,
        100.0 * mean_steps / budget as f64,
        costs.iter().map(|c| c.steps).max().unwrap_or(0),
        biases.iter().cloned().fold(f64::INFINITY, f64::min),
        biases.iter().cloned().fold(0.0, f64::max),
    );
    assert!(over.is_empty(), "frames over budget: {over:?}");
    // The flight does push the governor: some frames need a coarser bias.
    assert!(biases.iter().any(|&b| b > 1.0), "the bias never moved");
    // Deterministic: the same flight, the same choices.
    assert_eq!(fly(&scene, &kernel, budget), costs);
}
