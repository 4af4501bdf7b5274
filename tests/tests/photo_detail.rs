//! Photos finer than the height grid, kept at their own resolution, on
//! near views against the exact reference (which samples the photos'
//! texels): the kernel reading the texels (`WithDetail`) against the same
//! kernel with the photos reduced to the height grid (the mean of each
//! point's texels, which is also what the pyramid filters on).
//!
//! - Comanche's C3 (1024²) stretched over D3 (512²): 2 texels a spacing.
//! - Swellendam: its two 2.5 m aerial photos placed by their georeference
//!   over the 90 m SRTM grid: 32 texels a spacing, each over the points
//!   it covers.

use std::time::Instant;
use terracast::{Camera, RenderOptions};
use terracast_sim::metrics::psnr;
use terracast_sim::reference::Reference;
use terracast_sim::scene::{derived_height_scale, load_scene_files, KernelScene, Scene};
use terracast_tests::{
    comanche, data_dir, kernel_render, near_photo_views, reference_view, swellendam_files, NearView,
};

const SIZE: (u32, u32) = (640, 360);

/// The best time of `render` in milliseconds, the two kernels' renders
/// taking turns five times.
fn best_ms_of_each(kernels: &[KernelScene; 2], camera: &Camera) -> [f64; 2] {
    let options = RenderOptions::default();
    let mut times = [f64::INFINITY; 2];
    for _ in 0..5 {
        for (time, kernel) in times.iter_mut().zip(kernels) {
            let start = Instant::now();
            kernel_render(kernel, camera, SIZE, &options);
            *time = time.min(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    times
}

/// Prints a table row for each of `views` of `scene` (the kernel with its
/// photos' texels and with them reduced) and holds the texels to a higher
/// PSNR on every view.
fn texels_against_reduced(name: &str, scene: &Scene, views: &[NearView]) {
    assert!(!scene.details.is_empty(), "{name}: a photo is kept finer");
    let reduced = Scene {
        details: Vec::new(),
        ..scene.clone()
    };
    let kernels: [KernelScene; 2] = [scene.to_kernel().unwrap(), reduced.to_kernel().unwrap()];
    let reference = Reference::new(scene);
    let options = RenderOptions::default();
    for &([x, y], above, yaw, pitch) in views {
        let ground = scene.height_at(f64::from(x), f64::from(y)) as f32;
        let camera = Camera::looking([x, y, ground + above], yaw, pitch);
        let truth = reference_view(&reference, &camera, SIZE);
        let scores = kernels.each_ref().map(|kernel| {
            let (frame, _) = kernel_render(kernel, &camera, SIZE, &options);
            psnr(&frame.colors, &truth.colors)
        });
        let times = best_ms_of_each(&kernels, &camera);
        println!(
            "| {name} | {x:.0}, {y:.0}, {:.1} | {yaw:.0}° | {pitch:.0}° | {:.2}, {:.1} | {:.2}, {:.1} | {:+.2} dB |",
            ground + above,
            scores[0],
            times[0],
            scores[1],
            times[1],
            scores[0] - scores[1]
        );
        assert!(
            scores[0] > scores[1],
            "{name} at {x}, {y}: {:.2} dB with the photo's texels, {:.2} dB reduced",
            scores[0],
            scores[1]
        );
    }
}

#[test]
fn photos_kept_finer_than_the_grid_win_on_every_near_view() {
    let Some(data) = data_dir("photos_kept_finer_than_the_grid_win_on_every_near_view") else {
        return;
    };
    println!("| map | eye | yaw | pitch | photo's own resolution: dB, ms | reduced to the grid: dB, ms | gain |");
    println!("|---|---|---|---|---|---|---|");

    let c3 = comanche(&data, "3", "3");
    let detail = &c3.details[0];
    assert_eq!((detail.shift, detail.size), (1, [512, 512]));
    texels_against_reduced(
        "C3/D3",
        &c3,
        &[
            ([300.0, 200.0], 30.0, 60.0, 35.0),
            ([120.0, 380.0], 45.0, 300.0, 25.0),
            ([400.0, 420.0], 25.0, 200.0, 45.0),
            ([250.0, 60.0], 50.0, 100.0, 20.0),
            ([60.0, 150.0], 40.0, 10.0, 30.0),
        ],
    );

    let (height, photos) = swellendam_files(&data);
    let (scale, _) = derived_height_scale(&height).unwrap().unwrap();
    let swellendam = load_scene_files(&height, &photos, scale, 1).unwrap();
    assert_eq!(swellendam.details.len(), 2);
    assert!(swellendam.details.iter().all(|d| d.shift == 5));
    texels_against_reduced("Swellendam", &swellendam, &near_photo_views(&swellendam));
}
