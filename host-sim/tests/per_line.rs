//! The per-line designs render what setting every ray up in full renders at
//! single resolution: the column caster (the design at its smallest) on
//! level views, as accurately against the exact reference (it refuses a
//! pitched one); the pixel-line caster (the design at its smallest under
//! pitch and roll) and the line caster, the kernel's default, at any pose
//! bit for bit (`Coherence::Exact` is the full set-up).

use terracast::{
    render_level_columns, render_level_columns_lean, render_pixel_lines, Camera, Coherence,
    ColumnsError, RenderOptions, Resolution, Rgb, Shading, Terrain, View,
};
use terracast_sim::camera::ContractCamera;
use terracast_sim::kernel::{render_kernel_with, PixelRays, SampleBuffer};
use terracast_sim::metrics::psnr;
use terracast_sim::reference::{Reference, ReferenceOptions};
use terracast_sim::scene::{procedural, KernelScene, Scene};

const SIZE: (u32, u32) = (160, 120);

fn colors(buffer: &SampleBuffer) -> Vec<Rgb> {
    buffer.samples.iter().map(|s| s.color).collect()
}

/// The kernel at single resolution (the line caster).
fn single() -> RenderOptions {
    RenderOptions {
        resolution: Resolution::Single,
        ..RenderOptions::default()
    }
}

/// How an image of `camera` compares with the kernel's single-resolution
/// render (checked to show terrain of more than one color) and with the
/// exact reference.
struct Compared {
    against_kernel_db: f64,
    against_reference_db: f64,
    kernel_against_reference_db: f64,
    identical: bool,
}

fn compare(scene: &Scene, kernel_scene: &KernelScene, camera: &Camera, image: &[Rgb]) -> Compared {
    let (kernel, _) = render_kernel_with(
        kernel_scene,
        camera,
        SIZE.0,
        SIZE.1,
        &single(),
        PixelRays::Fixed,
    )
    .unwrap();
    assert!(
        kernel.sky_pixels() < kernel.depth.len(),
        "{camera:?} sees no terrain"
    );
    assert!(
        kernel.colors.iter().any(|c| *c != kernel.colors[0]),
        "{camera:?}: one color"
    );
    let (reference, _) =
        Reference::new(scene).render(camera, SIZE.0, SIZE.1, &ReferenceOptions::default());
    let compared = Compared {
        against_kernel_db: psnr(image, &kernel.colors),
        against_reference_db: psnr(image, &reference.colors),
        kernel_against_reference_db: psnr(&kernel.colors, &reference.colors),
        identical: image == kernel.colors.as_slice(),
    };
    println!(
        "yaw {} pitch {}: {:.2} dB from the kernel; {:.2} dB against the reference, the kernel's {:.2}",
        camera.yaw_deg,
        camera.pitch_deg,
        compared.against_kernel_db,
        compared.against_reference_db,
        compared.kernel_against_reference_db
    );
    compared
}

/// Each camera `cameras` places over the built-in scene (256², seed 3),
/// rendered by `renderer` at single resolution into a sample buffer, and
/// compared with the kernel's render.
fn compare_each(
    cameras: impl Fn(&Scene) -> Vec<Camera>,
    renderer: impl Fn(&Terrain<'_>, &View, &RenderOptions, &mut SampleBuffer),
) -> Vec<(Camera, Compared)> {
    let scene = procedural(256, 3);
    let kernel_scene = scene.to_kernel().unwrap();
    let terrain = kernel_scene.terrain().unwrap();
    cameras(&scene)
        .into_iter()
        .map(|camera| {
            let view = View::new(&camera, SIZE.0, SIZE.1).unwrap();
            let mut image = SampleBuffer::new(SIZE.0, SIZE.1);
            renderer(&terrain, &view, &single(), &mut image);
            let compared = compare(&scene, &kernel_scene, &camera, &colors(&image));
            (camera, compared)
        })
        .collect()
}

/// Level views of `scene`: along each axis both ways, diagonals, from
/// outside the map, near the ground and above its highest point.
fn level_cameras(scene: &Scene) -> Vec<Camera> {
    let top = scene.max_height();
    vec![
        Camera::looking([128.0, 5.0, top * 0.7], 90.0, 0.0),
        Camera::looking([5.0, 128.0, top + 20.0], 0.0, 0.0),
        Camera::looking([250.0, 128.0, top * 0.6], 180.0, 0.0),
        Camera::looking([128.0, 250.0, top + 5.0], 270.0, 0.0),
        Camera::looking([-40.0, -40.0, top * 0.8], 45.0, 0.0),
        Camera::looking([200.0, 30.0, top * 0.5], 135.0, 0.0),
    ]
}

#[test]
fn level_views_match_the_kernel_at_single_resolution() {
    let columns =
        |terrain: &Terrain<'_>, view: &View, options: &RenderOptions, image: &mut SampleBuffer| {
            render_level_columns(terrain, view, options, image).unwrap()
        };
    for (camera, compared) in compare_each(level_cameras, columns) {
        assert!(compared.against_kernel_db > 38.0, "{camera:?}");
        assert!(
            compared.against_reference_db >= compared.kernel_against_reference_db - 0.3,
            "{camera:?}"
        );
    }
}

#[test]
fn the_lean_column_caster_draws_the_column_casters_frame() {
    // The level views, and one more from outside the map above its
    // highest point: rays that start above it, which the lean caster
    // skips along; odd and even sizes.
    let scene = procedural(256, 3);
    let kernel_scene = scene.to_kernel().unwrap();
    let terrain = kernel_scene.terrain().unwrap();
    let mut cameras = level_cameras(&scene);
    cameras.push(Camera::looking(
        [-100.0, 128.0, scene.max_height() + 10.0],
        0.0,
        0.0,
    ));
    // Both casters' frames of `camera` over `terrain`.
    let frames = |terrain: &Terrain<'_>, camera: &Camera, (width, height): (u32, u32)| {
        let view = View::new(camera, width, height).unwrap();
        let mut columns = SampleBuffer::new(width, height);
        render_level_columns(terrain, &view, &single(), &mut columns).unwrap();
        let mut lean = vec![[1, 2, 3]; (width * height) as usize];
        render_level_columns_lean(terrain, &view, &single(), &mut lean).unwrap();
        (colors(&columns), lean)
    };
    for camera in &cameras {
        for size in [SIZE, (97, 61)] {
            let (expected, lean) = frames(&terrain, camera, size);
            assert!(
                expected.iter().any(|&c| c != single().sky) && expected.contains(&single().sky),
                "{camera:?}: the frame shows terrain and sky"
            );
            assert!(lean == expected, "{camera:?} at {size:?}");
        }
    }
    // A wall as high as the map's highest point across a flat map, seen
    // from just above its top: the rays that graze it skip to just before
    // it, and one sample too far would pass it.
    let (side, wall) = (64usize, 40u16 << 4);
    let heights: Vec<u16> = (0..side * side)
        .map(|i| {
            if (30..33).contains(&(i / side)) {
                wall
            } else {
                0
            }
        })
        .collect();
    let checker: Vec<Rgb> = (0..side * side)
        .map(|i| [(i * 37 % 256) as u8, (i * 11 % 256) as u8, 90])
        .collect();
    let walled = Terrain::new(side as u32, side as u32, &heights, &checker).unwrap();
    for eye_z in [40.2, 41.5, 47.0] {
        let camera = Camera::looking([32.0, 2.0, eye_z], 90.0, 0.0);
        let (expected, lean) = frames(&walled, &camera, (64, 48));
        assert!(lean == expected, "the wall from {eye_z}");
    }
    let view = View::new(&cameras[0], 16, 12).unwrap();
    assert_eq!(
        render_level_columns_lean(&terrain, &view, &single(), &mut [[0; 3]; 191]),
        Err(ColumnsError::FrameTooSmall)
    );
    let pitched = View::new(&Camera::looking([32.0, 2.0, 80.0], 90.0, 10.0), 16, 12).unwrap();
    assert_eq!(
        render_level_columns_lean(&terrain, &pitched, &single(), &mut [[0; 3]; 192]),
        Err(ColumnsError::NotLevel)
    );
}

#[test]
fn pixel_lines_match_the_kernel_at_single_resolution_at_any_pose() {
    // Level, grazing, steep, straight down, looking up, rolled (its lines
    // slanted, and through a vanishing point inside the image), from
    // outside the map.
    let cameras = |scene: &Scene| {
        let top = scene.max_height();
        vec![
            Camera::looking([128.0, 5.0, top * 0.7], 90.0, 0.0),
            Camera::looking([5.0, 128.0, top * 0.8], 10.0, 2.0),
            Camera::looking([30.0, 40.0, top + 40.0], 30.0, 30.0),
            Camera::looking([200.0, 200.0, top + 60.0], 225.0, 60.0),
            Camera::looking([128.0, 128.0, top + 80.0], 10.0, 90.0),
            Camera::looking([128.0, 20.0, scene.height(128, 20) + 4.0], 95.0, -5.0),
            Camera {
                roll_deg: 30.0,
                ..Camera::looking([40.0, 60.0, top + 30.0], 50.0, 20.0)
            },
            Camera {
                roll_deg: -15.0,
                ..Camera::looking([200.0, 30.0, top * 0.8], 135.0, 0.0)
            },
            Camera {
                roll_deg: 120.0,
                ..Camera::looking([128.0, 128.0, top + 60.0], 0.0, 75.0)
            },
            Camera::looking([-40.0, -40.0, top * 0.8], 45.0, 15.0),
        ]
    };
    // The same lines, slopes, walk, crossing and color drift as the line
    // caster at single resolution, which skips to where a ray can hit
    // where this walks from the line's first sample: its image.
    for (camera, compared) in compare_each(cameras, render_pixel_lines) {
        assert!(compared.identical, "{camera:?}: not the kernel's image");
    }
}

/// Counts each pixel's writes.
struct Writes {
    width: u32,
    count: Vec<u32>,
}

impl terracast::Sink for Writes {
    fn put(&mut self, x: u32, y: u32, _: terracast::Sample) {
        self.count[(y * self.width + x) as usize] += 1;
    }
}

#[test]
fn the_per_pixel_path_alone_writes_every_pixel_once() {
    let scene = procedural(128, 2);
    let kernel_scene = scene.to_kernel().unwrap();
    let terrain = kernel_scene.terrain().unwrap();
    let top = scene.max_height();
    for camera in [
        Camera::looking([64.0, 64.0, top + 40.0], 30.0, 90.0),
        Camera {
            roll_deg: 30.0,
            ..Camera::looking([20.0, 30.0, top + 20.0], 50.0, 20.0)
        },
    ] {
        let view = View::new(&camera, 63, 47).unwrap();
        let mut writes = Writes {
            width: 63,
            count: vec![0; 63 * 47],
        };
        terracast::render_pixel_path(&terrain, &view, &single(), &mut writes);
        assert!(writes.count.iter().all(|&n| n == 1), "{camera:?}");
        // Straight down over the map: every pixel a shaded terrain pixel.
        let mut buffer = SampleBuffer::new(63, 47);
        terracast::render_pixel_path(&terrain, &view, &single(), &mut buffer);
        if camera.pitch_deg == 90.0 {
            assert!(!buffer.samples.iter().any(|s| s.is_sky()), "{camera:?}");
        }
    }
}

/// The poses the tabled paths are checked at over a map whose highest
/// point is `top`: level, pitched up to straight down (the least pitch
/// with its vanishing point thousands of pixels off the image), rolled,
/// and up.
fn table_cameras(top: f32) -> impl Iterator<Item = Camera> {
    [
        (0.0, 0.0, 30.0),
        (0.05, 0.0, 15.0),
        (2.0, 0.0, 70.0),
        (12.0, 0.0, 200.0),
        (45.0, 0.0, 10.0),
        (90.0, 0.0, 0.0),
        (20.0, 30.0, 120.0),
        (0.0, -15.0, 300.0),
        (-30.0, 0.0, 45.0),
    ]
    .into_iter()
    .map(move |(pitch, roll, yaw)| Camera {
        pitch_deg: pitch,
        roll_deg: roll,
        ..Camera::looking([30.0, 40.0, top + 25.0], yaw, pitch)
    })
}

#[test]
fn the_tabled_per_pixel_paths_draw_the_stepped_ones_frame() {
    let scene = procedural(128, 2);
    let kernel_scene = scene.to_kernel().unwrap();
    let terrain = kernel_scene.terrain().unwrap();
    let top = scene.max_height();
    let (width, height) = (80u32, 61u32);
    let pixels = (width * height) as usize;
    for camera in table_cameras(top) {
        let view = View::new(&camera, width, height).unwrap();
        let mut stepped = SampleBuffer::new(width, height);
        terracast::render_pixel_path(&terrain, &view, &single(), &mut stepped);
        let (mut line_of, mut order) = (vec![0u16; pixels], vec![0u32; pixels]);
        let mut starts = vec![0u32; view.lines() as usize + 1];
        let mut tabled = SampleBuffer::new(width, height);
        let mut writes = Writes {
            width,
            count: vec![0; pixels],
        };
        for sink in [&mut tabled as &mut dyn terracast::Sink, &mut writes] {
            terracast::render_pixel_path_tabled(
                &terrain,
                &view,
                &single(),
                (&mut line_of, &mut order, &mut starts),
                &mut &mut *sink,
            )
            .unwrap();
        }
        assert!(writes.count.iter().all(|&n| n == 1), "{camera:?}");
        assert!(
            tabled.samples == stepped.samples,
            "{camera:?}: not the stepped frame"
        );
        // Written lean: the same frame but for the rounding of the slope,
        // the drift and the offset. A color no pixel has shows any pixel
        // left unwritten.
        let mut lean = vec![[1, 2, 3]; pixels];
        terracast::render_pixel_path_lean(
            &terrain,
            &view,
            &single(),
            (&mut line_of, &mut order, &mut starts),
            &mut lean,
        )
        .unwrap();
        let tabled = colors(&tabled);
        assert!(
            !lean.contains(&[1, 2, 3]),
            "{camera:?}: a pixel left unwritten"
        );
        let close = lean
            .iter()
            .zip(&tabled)
            .filter(|(a, b)| a.iter().zip(b.iter()).all(|(a, b)| a.abs_diff(*b) <= 4))
            .count();
        let db = psnr(&lean, &tabled);
        println!("{camera:?}: lean against tabled {db:.2} dB, {close} of {pixels} within 4 levels");
        assert!(
            close * 100 >= pixels * 99 && db > 40.0,
            "{camera:?}: {close} of {pixels} pixels within 4 levels, {db:.2} dB"
        );
    }
    // Storage short of a line, a frame short of a pixel: refused.
    let view = View::new(&Camera::looking([30.0, 40.0, top], 0.0, 30.0), 16, 8).unwrap();
    let (mut line_of, mut order) = ([0u16; 128], [0u32; 128]);
    let mut starts = vec![0u32; view.lines() as usize];
    let refused = terracast::render_pixel_path_tabled(
        &terrain,
        &view,
        &single(),
        (&mut line_of, &mut order, &mut starts),
        &mut SampleBuffer::new(16, 8),
    );
    assert_eq!(refused, Err(terracast::TableError::TooSmall));
    let mut starts = vec![0u32; view.lines() as usize + 1];
    let refused = terracast::render_pixel_path_lean(
        &terrain,
        &view,
        &single(),
        (&mut line_of, &mut order, &mut starts),
        &mut [[0; 3]; 127],
    );
    assert_eq!(refused, Err(terracast::TableError::TooSmall));
}

#[test]
fn the_lean_path_under_nearest_shading_takes_the_voxel_nearest_the_pixels_ray() {
    // Colors that name their voxel: red twice its row, green twice its
    // column. A blend of two voxels can be odd; one voxel's color never is.
    let mut scene = procedural(128, 2);
    let side = scene.width as usize;
    for (i, color) in scene.colors.iter_mut().enumerate() {
        *color = [(2 * (i / side)) as u8, (2 * (i % side)) as u8, 0];
    }
    let kernel_scene = scene.to_kernel().unwrap();
    let terrain = kernel_scene.terrain().unwrap();
    let (width, height) = (80u32, 61u32);
    let pixels = (width * height) as usize;
    let nearest = RenderOptions {
        shading: Shading::Nearest,
        ..single()
    };
    // From off the map's west edge, looking east: every line's first
    // sample, where the path shades, is on one of the map's first two
    // columns, and the voxel it takes is the one nearest to where the
    // pixel's own ray crosses that column.
    let eye = [-30.0, 64.0, scene.max_height() + 25.0];
    let cameras = [
        (0.0, 0.0, 0.0),
        (10.0, 0.0, 10.0),
        (10.0, 30.0, -10.0),
        (5.0, -60.0, 5.0),
    ]
    .map(|(pitch, roll, yaw)| Camera {
        roll_deg: roll,
        ..Camera::looking(eye, yaw, pitch)
    });
    for camera in cameras {
        let view = View::new(&camera, width, height).unwrap();
        let (mut line_of, mut order) = (vec![0u16; pixels], vec![0u32; pixels]);
        let mut starts = vec![0u32; view.lines() as usize + 1];
        let mut frame = vec![[1, 2, 3]; pixels];
        terracast::render_pixel_path_lean(
            &terrain,
            &view,
            &nearest,
            (&mut line_of, &mut order, &mut starts),
            &mut frame,
        )
        .unwrap();
        // Rounded to the nearest row: half a row off at most (and the
        // drift's and the words' rounding).
        let rays = ContractCamera::new(&camera, width, height);
        for (i, color) in frame.iter().enumerate() {
            let (px, py) = ((i % width as usize) as f64, (i / width as usize) as f64);
            assert!(
                color[0] % 2 == 0 && color[1] <= 2,
                "{camera:?}: pixel {i} {color:?} is no voxel of the first columns"
            );
            // Where the pixel's ray crosses the voxel's column.
            let column = f64::from(color[1] / 2);
            let d = rays.direction(px + 0.5, py + 0.5);
            let crossing = f64::from(eye[1]) + d[1] / d[0] * (column - f64::from(eye[0]));
            assert!(
                (f64::from(color[0] / 2) - crossing).abs() <= 0.51,
                "{camera:?}: pixel {i} takes row {}, its ray crosses at {crossing:.3}",
                color[0] / 2
            );
        }
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
fn the_line_caster_renders_exacts_image_at_single_resolution_at_every_pitch() {
    let scene = procedural(256, 5);
    let kernel_scene = scene.to_kernel().unwrap();
    // Every ray set up in full and resumed only where exact.
    let exact = RenderOptions {
        coherence: Coherence::Exact,
        ..single()
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
        let (full, _) = render_kernel_with(
            &kernel_scene,
            &camera,
            SIZE.0,
            SIZE.1,
            &exact,
            PixelRays::Fixed,
        )
        .unwrap();
        // The same walk, the same crossing, the same color drift: the line
        // caster's image (the default's at single resolution), bit for bit.
        let compared = compare(&scene, &kernel_scene, &camera, &full.colors);
        assert!(
            compared.identical,
            "pitch {pitch}: not the line caster's image"
        );
    }
}
