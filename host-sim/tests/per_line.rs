//! The per-line casters (the design at its smallest) render what the kernel
//! renders at single resolution, as accurately against the exact
//! reference: the column caster on level views (it refuses a pitched one),
//! the line caster at any pitch (bit for bit on these views).

use terracast::{
    render_level0_lines, render_level_columns, Camera, ColumnsError, RenderOptions, Resolution,
    Rgb, View,
};
use terracast_sim::kernel::{render_kernel_with, PixelRays, SampleBuffer};
use terracast_sim::metrics::psnr;
use terracast_sim::reference::{Reference, ReferenceOptions};
use terracast_sim::scene::procedural;

const SIZE: (u32, u32) = (160, 120);

fn colors(buffer: &SampleBuffer) -> Vec<Rgb> {
    buffer.samples.iter().map(|s| s.color).collect()
}

#[test]
fn level_views_match_the_kernel_at_single_resolution() {
    let scene = procedural(256, 3);
    let kernel_scene = scene.to_kernel().unwrap();
    let terrain = kernel_scene.terrain().unwrap();
    let single = RenderOptions {
        resolution: Resolution::Single,
        ..RenderOptions::default()
    };
    let top = scene.max_height();
    // Along each axis both ways, diagonals, from outside the map, near the
    // ground and high above it.
    let cameras = [
        Camera::looking([128.0, 5.0, top * 0.7], 90.0, 0.0),
        Camera::looking([5.0, 128.0, top + 20.0], 0.0, 0.0),
        Camera::looking([250.0, 128.0, top * 0.6], 180.0, 0.0),
        Camera::looking([128.0, 250.0, top + 5.0], 270.0, 0.0),
        Camera::looking([-40.0, -40.0, top * 0.8], 45.0, 0.0),
        Camera::looking([200.0, 30.0, top * 0.5], 135.0, 0.0),
    ];
    for camera in cameras {
        let view = View::new(&camera, SIZE.0, SIZE.1).unwrap();
        let mut columns = SampleBuffer::new(SIZE.0, SIZE.1);
        render_level_columns(&terrain, &view, &single, &mut columns).unwrap();
        let (kernel, _) = render_kernel_with(
            &kernel_scene,
            &camera,
            SIZE.0,
            SIZE.1,
            &single,
            PixelRays::Fixed,
        )
        .unwrap();
        let (reference, _) =
            Reference::new(&scene).render(&camera, SIZE.0, SIZE.1, &ReferenceOptions::default());
        let terrain_pixels = kernel.sky_pixels() < kernel.depth.len();
        assert!(terrain_pixels, "{camera:?} sees no terrain");
        let columns = colors(&columns);
        let against_kernel = psnr(&columns, &kernel.colors);
        let (mine, kernels) = (
            psnr(&columns, &reference.colors),
            psnr(&kernel.colors, &reference.colors),
        );
        println!(
            "{camera:?}: columns vs kernel {against_kernel:.2} dB; vs reference {mine:.2} against the kernel's {kernels:.2}"
        );
        assert!(
            against_kernel > 38.0,
            "{against_kernel:.2} dB from the kernel"
        );
        assert!(
            mine >= kernels - 0.3,
            "{mine:.2} dB against the kernel's {kernels:.2}"
        );
    }
}

#[test]
fn a_pitched_view_is_refused() {
    let scene = procedural(64, 1);
    let kernel_scene = scene.to_kernel().unwrap();
    let terrain = kernel_scene.terrain().unwrap();
    let view = View::new(&Camera::looking([32.0, 2.0, 80.0], 90.0, 10.0), 16, 12).unwrap();
    let mut buffer = SampleBuffer::new(16, 12);
    assert_eq!(
        render_level_columns(&terrain, &view, &RenderOptions::default(), &mut buffer),
        Err(ColumnsError::NotLevel)
    );
}

#[test]
fn the_line_caster_matches_the_kernel_at_single_resolution_at_every_pitch() {
    let scene = procedural(256, 5);
    let kernel_scene = scene.to_kernel().unwrap();
    let terrain = kernel_scene.terrain().unwrap();
    let single = RenderOptions {
        resolution: Resolution::Single,
        ..RenderOptions::default()
    };
    let top = scene.max_height();
    for (eye, yaw, pitch) in [
        ([128.0, 10.0, scene.height(128, 10) + 30.0], 90.0, 0.0),
        ([128.0, 10.0, top + 20.0], 80.0, 10.0),
        ([30.0, 40.0, top + 40.0], 30.0, 30.0),
        ([200.0, 200.0, top + 60.0], 225.0, 60.0),
        ([128.0, 128.0, top + 80.0], 10.0, 90.0),
        ([128.0, 20.0, scene.height(128, 20) + 8.0], 95.0, -20.0),
    ] {
        let camera = Camera::looking(eye, yaw, pitch);
        let view = View::new(&camera, SIZE.0, SIZE.1).unwrap();
        let mut lines = SampleBuffer::new(SIZE.0, SIZE.1);
        render_level0_lines(&terrain, &view, &single, &mut lines);
        let (kernel, _) = render_kernel_with(
            &kernel_scene,
            &camera,
            SIZE.0,
            SIZE.1,
            &single,
            PixelRays::Fixed,
        )
        .unwrap();
        // Terrain, and more than one color of it.
        assert!(
            kernel.sky_pixels() < kernel.depth.len(),
            "pitch {pitch} sees no terrain"
        );
        assert!(
            kernel.colors.iter().any(|c| *c != kernel.colors[0]),
            "pitch {pitch}: one color"
        );
        let (reference, _) =
            Reference::new(&scene).render(&camera, SIZE.0, SIZE.1, &ReferenceOptions::default());
        let lines = colors(&lines);
        let against_kernel = psnr(&lines, &kernel.colors);
        let (mine, kernels) = (
            psnr(&lines, &reference.colors),
            psnr(&kernel.colors, &reference.colors),
        );
        println!(
            "pitch {pitch}: lines vs kernel {against_kernel:.2} dB; vs reference {mine:.2} against the kernel's {kernels:.2}"
        );
        // The same walk, the same crossing, the same color drift: the
        // kernel's single-resolution image, bit for bit.
        assert!(
            lines == kernel.colors,
            "pitch {pitch}: {against_kernel:.2} dB from the kernel"
        );
        assert!(
            mine >= kernels - 0.3,
            "pitch {pitch}: {mine:.2} dB against the kernel's {kernels:.2}"
        );
    }
}
