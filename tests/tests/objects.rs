//! 3D objects as sticks (the built-in scene's wood and village) against
//! the exact reference, which intersects the same raised surface and
//! colors a hit by the same stick texels.
//!
//! On views of the built-in scene with its objects planted (from afar,
//! into the wood, over the village, grazing along the trees), the table
//! this prints (docs/objects.md) gives the kernel at its defaults against
//! the reference (4 × 4 rays a pixel), the reference's own single ray a
//! pixel against it (what one ray a pixel can reach on this much fine
//! detail), the same views without objects, and the steps a pixel both
//! ways, the secondary rays a pixel the wood's see-through leaves cast,
//! and the kernel reading heights on each ray's own path
//! (`HeightPath::Ray`). Held here, as guards against a regression (issue
//! 32 asks for 35 dB, which one exact ray a pixel does not reach on this
//! much fine detail, and 99.9 %): sky agreement at least 99.8 % (99.9 %
//! on each ray's path), the kernel at least 23 dB and within 6.5 dB of
//! the single exact ray.

use terracast::{Camera, HeightFilter, HeightPath, RenderOptions, Resolution, U8F8};
use terracast_sim::kernel::render_kernel;
use terracast_sim::metrics::{psnr, sky_agreement};
use terracast_sim::objects::showcase_views;
use terracast_sim::reference::{Reference, ReferenceOptions};
use terracast_sim::scene::{procedural, ObjectHeights, Scene};

const SIZE: (u32, u32) = (640, 360);

/// A view's scores against the reference.
struct Score {
    /// The kernel's PSNR, its sky agreement, its steps a pixel and its
    /// secondary rays a pixel (through see-through leaves).
    db: f64,
    sky: f64,
    steps: f64,
    secondary: f64,
    /// The reference's single ray a pixel's PSNR.
    one_ray_db: f64,
    /// The kernel reading heights on each ray's path: PSNR, sky agreement.
    ray_path: (f64, f64),
}

fn score(scene: &Scene, camera: &Camera) -> Score {
    let kernel = scene.to_kernel().unwrap();
    let (k, stats) =
        render_kernel(&kernel, camera, SIZE.0, SIZE.1, &RenderOptions::default()).unwrap();
    let ray_path = RenderOptions {
        height_path: HeightPath::Ray,
        ..RenderOptions::default()
    };
    let (on_ray_path, _) = render_kernel(&kernel, camera, SIZE.0, SIZE.1, &ray_path).unwrap();
    let reference = Reference::new(scene);
    let (r, _) = reference.render(camera, SIZE.0, SIZE.1, &ReferenceOptions::default());
    let one_ray = ReferenceOptions {
        supersample: 1,
        ..ReferenceOptions::default()
    };
    let (r1, _) = reference.render(camera, SIZE.0, SIZE.1, &one_ray);
    Score {
        db: psnr(&k.colors, &r.colors),
        sky: sky_agreement(&k.depth, &r.depth),
        steps: stats.steps as f64 / f64::from(SIZE.0 * SIZE.1),
        secondary: stats.levels.as_ref().map_or(0, |l| l.secondary_rays) as f64
            / f64::from(SIZE.0 * SIZE.1),
        one_ray_db: psnr(&r1.colors, &r.colors),
        ray_path: (
            psnr(&on_ray_path.colors, &r.colors),
            sky_agreement(&on_ray_path.depth, &r.depth),
        ),
    }
}

#[test]
fn objects_render_as_the_reference_sees_them() {
    let bare = procedural(1024, 1);
    let mut planted = bare.clone();
    println!("{}", planted.plant_objects(1));
    let views = showcase_views(&bare);
    println!("| view | kernel dB | one exact ray a pixel dB | sky agreement | without objects: kernel dB | steps/px | without objects | secondary rays/px | heights on the ray's path: dB | sky agreement |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut failures = Vec::new();
    for (name, camera) in views {
        let with = score(&planted, &camera);
        let without = score(&bare, &camera);
        let (p, one_ray, agree) = (with.db, with.one_ray_db, with.sky);
        println!(
            "| {name} | {p:.2} | {one_ray:.2} | {:.3} % | {:.2} | {:.2} | {:.2} | {:.3} | {:.2} | {:.3} % |",
            agree * 100.0,
            without.db,
            with.steps,
            without.steps,
            with.secondary,
            with.ray_path.0,
            with.ray_path.1 * 100.0
        );
        // Read on each ray's own path, tree tops stand where the pixel's
        // own ray sees them: issue 32's 99.9 %.
        // The wood's boundary trees have see-through leaves: rays see
        // through them on every view that shows trees near.
        if p < 23.0
            || p < one_ray - 6.5
            || agree < 0.998
            || with.ray_path.1 < 0.999
            || with.secondary <= 0.0
        {
            failures.push(format!(
                "{name}: {p:.2} dB (one exact ray {one_ray:.2}), sky {:.3} %",
                agree * 100.0
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The pyramid's coarser levels with the objects' heights raised to their
/// tallest sticks (the default) against filtered with the ground, where
/// coarse levels are what a ray sees: 200 × 150 at a pixel-to-voxel ratio
/// of 8 (as far as the flight's governor goes), the showcase views and two
/// from beyond the map's edge. Prints the table in docs/objects.md; holds
/// that the raised levels keep at least as much of the silhouettes (sky
/// agreement over all views) and lose at most 0.3 dB on any view.
#[test]
fn coarse_levels_keep_the_objects_silhouettes() {
    let bare = procedural(1024, 1);
    let mut planted = bare.clone();
    planted.plant_objects(1);
    let mut views = showcase_views(&bare).to_vec();
    views.push((
        "from beyond the edge",
        Camera::looking([512.0, -300.0, 320.0], 90.0, 8.0),
    ));
    views.push((
        "from beyond the corner",
        Camera::looking([100.0, -100.0, 600.0], 45.0, 25.0),
    ));
    let (width, height) = (200, 150);
    let coarse = RenderOptions {
        resolution: Resolution::Multi {
            pixel_to_voxel: U8F8::from_num(8),
        },
        ..RenderOptions::default()
    };
    let reference = Reference::new(&planted);
    let kernels = [
        ObjectHeights::Max,
        ObjectHeights::Filtered,
        ObjectHeights::CavitiesOpen,
    ]
    .map(|heights| {
        planted
            .to_kernel_with_object_heights(HeightFilter::default(), heights)
            .unwrap()
    });
    // Cavities open: the boundary trees' see-through crowns raise no
    // coarse point, so some coarse points stand lower than raised.
    let coarse_heights = |k: usize| {
        kernels[k]
            .pyramid()
            .unwrap()
            .level(1)
            .unwrap()
            .heights()
            .to_vec()
    };
    let (raised, open) = (coarse_heights(0), coarse_heights(2));
    assert!(raised.iter().zip(&open).all(|(r, o)| o <= r));
    assert!(raised.iter().zip(&open).any(|(r, o)| o < r));
    println!(
        "| view | raised: kernel dB | sky agreement | steps/px | filtered: kernel dB | sky agreement | cavities open: kernel dB | sky agreement | steps/px |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let (mut raised_sky, mut filtered_sky, mut failures) = (0.0, 0.0, Vec::new());
    let pixels = f64::from(width * height);
    for (name, camera) in views {
        let (r, _) = reference.render(&camera, width, height, &ReferenceOptions::default());
        let [(p, agree, steps), (p0, agree0, _), (p_open, agree_open, steps_open)] =
            kernels.each_ref().map(|kernel| {
                let (k, stats) = render_kernel(kernel, &camera, width, height, &coarse).unwrap();
                (
                    psnr(&k.colors, &r.colors),
                    sky_agreement(&k.depth, &r.depth),
                    stats.steps as f64 / pixels,
                )
            });
        println!(
            "| {name} | {p:.2} | {:.3} % | {steps:.2} | {p0:.2} | {:.3} % | {p_open:.2} | {:.3} % | {steps_open:.2} |",
            agree * 100.0,
            agree0 * 100.0,
            agree_open * 100.0
        );
        raised_sky += agree;
        filtered_sky += agree0;
        if p < p0 - 0.3 {
            failures.push(format!("{name}: raised {p:.2} dB, filtered {p0:.2} dB"));
        }
    }
    assert!(
        raised_sky >= filtered_sky,
        "sky agreement raised {raised_sky:.4}, filtered {filtered_sky:.4} (sums over the views)"
    );
    assert!(failures.is_empty(), "{failures:#?}");
}
