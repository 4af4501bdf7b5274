//! Rolled views against the exact reference on real terrain (Comanche
//! maps), 640 × 360, hfov 60°, default settings: C7W/D7 and C1W/D1, rolls
//! 0° to 180° at pitches 0°, 10° and 45°. The table it prints is in
//! docs/figures.md.
//!
//! A rolled camera's image lines are still the images of vertical planes:
//! lines through the vertical's vanishing point, or, with the camera level,
//! parallel lines slanted by the roll. A pixel's ray takes its center's
//! elevation but its line's horizontal direction, up to half a pixel
//! beside the center, as under pitch: a level
//! view rolled by 15° or 30° loses up to 2.8 dB against the same view
//! unrolled (whose lines are the columns, through every pixel center) and
//! lands where a view pitched by half a degree does; at 45°, 90° and 180°
//! the lines meet the pixel centers again. A rolled frame shows other
//! terrain than its twin (a 640 × 360 frame turned on its side, corners
//! of sky swapped for ground), so its PSNR and steps move with what it
//! sees as well. Held here: sky agreement at least 99.9 %, every rolled
//! view within 3 dB of its roll-0 twin and within 1.4 times its steps a
//! pixel. Rolled 180° at pitch 0 the lines are the columns again: the
//! same PSNR and steps as unrolled.
//!
//! The last columns are the same view with the line caster reading heights
//! on each ray's own path (`HeightPath::Ray`) instead of its line's plane,
//! and one exact ray a pixel through the pixel's center (the reference at
//! one ray a pixel) against the same reference: what any renderer of one
//! ray a pixel scores there, and how much of a rolled view's loss against
//! its twin is the roll's own, not the kernel's. Held here too: level, the
//! kernel on its rays' own paths loses to the roll at most 0.6 dB more
//! than one exact ray does. (Pitched 45°, one exact ray aliases where the
//! kernel's levels filter: it scores 3.2 to 7.5 dB above the kernel and swings
//! with what the roll shows, so it bounds nothing there.)

use terracast::{Camera, Coherence, HeightPath, RenderOptions, Resolution};
use terracast_sim::metrics::{psnr, sky_agreement};
use terracast_sim::reference::{Reference, ReferenceOptions};
use terracast_tests::{comanche, data_dir, kernel_render, kernel_view, reference_view};

const SIZE: (u32, u32) = (640, 360);
const ROLLS: [f32; 7] = [0.0, 15.0, 30.0, 45.0, 90.0, 135.0, 180.0];
const PITCHES: [f32; 3] = [0.0, 10.0, 45.0];

#[test]
fn rolled_views_match_the_reference_as_level_ones_do() {
    let Some(data) = data_dir("rolled_views_match_the_reference_as_level_ones_do") else {
        return;
    };
    let mut failures = Vec::new();
    println!("| map | pitch | roll | PSNR dB | − roll 0 | sky agreement | steps/pixel | heights on the ray's path: PSNR dB | − roll 0 | one exact ray: PSNR dB | − roll 0 |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let one_ray = ReferenceOptions {
        supersample: 1,
        ..ReferenceOptions::default()
    };
    let ray_path = RenderOptions {
        height_path: HeightPath::Ray,
        ..RenderOptions::default()
    };
    for (color, height, eye, yaw) in [
        ("7W", "7", [300.0, 700.0, 170.0], 20.0),
        ("1W", "1", [200.0, 300.0, 160.0], 45.0),
    ] {
        let scene = comanche(&data, color, height);
        let kernel = scene.to_kernel().unwrap();
        let reference = Reference::new(&scene);
        for pitch in PITCHES {
            let (mut level, mut level_steps) = (None, None);
            let (mut level_ray, mut level_exact) = (None, None);
            for roll in ROLLS {
                let camera = Camera {
                    roll_deg: roll,
                    ..Camera::looking(eye, yaw, pitch)
                };
                let r = reference_view(&reference, &camera, SIZE);
                let (k, stats) = kernel_view(
                    &kernel,
                    &camera,
                    SIZE,
                    Coherence::DEFAULT,
                    Resolution::DEFAULT,
                );
                let p = psnr(&k.colors, &r.colors);
                let (on_ray_path, _) = kernel_render(&kernel, &camera, SIZE, &ray_path);
                let p_ray = psnr(&on_ray_path.colors, &r.colors);
                let exact = reference.render(&camera, SIZE.0, SIZE.1, &one_ray).0;
                let p_exact = psnr(&exact.colors, &r.colors);
                let level_ray = *level_ray.get_or_insert(p_ray);
                let level_exact = *level_exact.get_or_insert(p_exact);
                let agree = sky_agreement(&k.depth, &r.depth);
                let steps = stats.steps as f64 / f64::from(SIZE.0 * SIZE.1);
                let level = *level.get_or_insert(p);
                println!(
                    "| C{color}/D{height} | {pitch}° | {roll}° | {p:.2} | {:+.2} | {:.3} % | {steps:.2} | {p_ray:.2} | {:+.2} | {p_exact:.2} | {:+.2} |",
                    p - level,
                    agree * 100.0,
                    p_ray - level_ray,
                    p_exact - level_exact,
                );
                let level_steps = *level_steps.get_or_insert(steps);
                // Turned over, a level view's lines are its columns again,
                // top to bottom: the same image but for the rounding of
                // each line's directions to words, which starts at the
                // other end of the column (`Line::direction_words`).
                let upside_down = pitch == 0.0 && roll == 180.0;
                // Level, one exact ray a pixel is the bound: on its own
                // path the kernel loses to the roll at most 0.6 dB more
                // than that ray does (on the line's plane, up to 1.8 dB).
                let beyond_exact = (p_exact - level_exact) - (p_ray - level_ray);
                if p < level - 3.0
                    || (pitch == 0.0 && beyond_exact > 0.6)
                    || agree < 0.999
                    || steps > 1.4 * level_steps
                    || (upside_down
                        && ((p - level).abs() > 0.02
                            || (steps - level_steps).abs() > 0.005 * level_steps))
                {
                    failures.push(format!(
                        "C{color}/D{height} pitch {pitch} roll {roll}: {p:.2} dB (roll 0: {level:.2}), sky {:.3} %, {steps:.2} steps/px, on the ray's path {beyond_exact:.2} dB more lost than one exact ray",
                        agree * 100.0
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
