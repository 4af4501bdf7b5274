//! Sky, sun and fog: the kernel's fixed-point atmosphere against the
//! reference's exact one.
//!
//! * On two views of the built-in scene, one with the sun in view, the
//!   kernel with the flight's atmosphere scores within 0.5 dB of the same
//!   view without it (each against the reference rendered the same way),
//!   and sees sky where it did before. The same on the accuracy views of
//!   real terrain (Comanche C1W/D1, C7W/D7 and C14/D14) is checked in
//!   `accuracy.rs`, which shares its reference frames.
//! * What fog's opaque distance would spare a tiled terrain's footprint.

use terracast::tiles::TileSource;
use terracast::{Atmosphere, Camera, Fog, RenderOptions, Sun};
use terracast_sim::frame::Frame;
use terracast_sim::kernel::{render_kernel_in, PixelRays};
use terracast_sim::reference::{Reference, ReferenceOptions};
use terracast_sim::scene::{procedural, Scene};
use terracast_sim::tiles::{footprint_beyond, ProceduralSource};
use terracast_tests::atmosphere_against_reference;

/// The kernel's frame of `camera`, with `air` or without.
fn kernel(scene: &Scene, camera: &Camera, size: (u32, u32), air: Option<Atmosphere>) -> Frame {
    let prepared = air.map(|air| air.prepare().unwrap());
    let kernel = scene.to_kernel().unwrap();
    render_kernel_in(
        &kernel,
        camera,
        size,
        &RenderOptions::default(),
        PixelRays::Fixed,
        prepared.as_ref(),
    )
    .unwrap()
    .0
}

/// The reference's frames of `camera` without the atmosphere and with
/// `air`, from one pass over the rays (`Reference::render_each`).
fn references(scene: &Scene, camera: &Camera, size: (u32, u32), air: Atmosphere) -> [Frame; 2] {
    let clear = ReferenceOptions::default();
    let hazy = ReferenceOptions {
        atmosphere: Some(air),
        ..clear
    };
    let (frames, _) = Reference::new(scene).render_each(
        camera,
        size.0,
        size.1,
        clear.supersample,
        &[clear.coloring(), hazy.coloring()],
    );
    let [r, fr]: [Frame; 2] = frames.try_into().unwrap();
    [r, fr]
}

/// PSNR with the atmosphere and without, and the sky agreement with it;
/// records a failure when the atmosphere costs more than 0.5 dB.
fn compare(
    name: &str,
    scene: &Scene,
    camera: &Camera,
    size: (u32, u32),
    air: Atmosphere,
    failures: &mut Vec<String>,
) -> f64 {
    let (k, fk) = (
        kernel(scene, camera, size, None),
        kernel(scene, camera, size, Some(air)),
    );
    let [r, fr] = references(scene, camera, size, air);
    let (clear, hazy, agree) = atmosphere_against_reference(name, [&k, &fk], [&r, &fr]);
    if hazy < clear - 0.5 {
        failures.push(format!(
            "{name}: {hazy:.2} dB with it, {clear:.2} dB without"
        ));
    }
    if agree < 0.995 {
        failures.push(format!("{name}: sky agreement {agree}"));
    }
    hazy - clear
}

#[test]
fn the_atmosphere_keeps_the_kernel_within_half_a_decibel_on_the_built_in_scene() {
    let scene = procedural(512, 1);
    let mut failures = Vec::new();
    let eye = [256.0, 20.0, scene.max_height() + 30.0];
    let level = Camera::looking(eye, 90.0, 6.0);
    compare(
        "level",
        &scene,
        &level,
        (240, 135),
        Atmosphere::FLIGHT,
        &mut failures,
    );
    // Toward a low sun, with a little sky above the ridges.
    let mut toward_sun = Atmosphere::FLIGHT;
    toward_sun.sun = toward_sun.sun.map(|sun| Sun {
        azimuth_deg: 95.0,
        elevation_deg: 4.0,
        ..sun
    });
    let up = Camera::looking(eye, 90.0, -2.0);
    compare(
        "toward the sun",
        &scene,
        &up,
        (240, 135),
        toward_sun,
        &mut failures,
    );
    assert!(failures.is_empty(), "{failures:?}");
}

/// What fog's opaque distance spares a tiled terrain: the footprint tiles
/// wholly beyond it, on the procedural 131072² world from `page`'s eye
/// (over the world's middle, 100 voxels above its highest point) at
/// pitch 20° (`page`'s start) and 5°, 320 × 240, hfov 60°.
#[test]
fn fog_spares_the_footprint_beyond_its_opaque_distance() {
    let mut source = ProceduralSource::new(131_072, 1).unwrap();
    let world = source.world();
    let highest = f64::from(world.max_height) / 16.0;
    let eye = [65_536.0, 65_536.0, highest as f32 + 100.0];
    let flight = Atmosphere::FLIGHT.fog.unwrap();
    let fogs = [
        ("the flight's layered fog", flight),
        (
            "uniform fog, visibility 2500",
            Fog {
                halving: None,
                ..flight
            },
        ),
        (
            "uniform fog, visibility 800",
            Fog {
                halving: None,
                visibility: 800.0,
                ..flight
            },
        ),
    ];
    let mut spared = Vec::new();
    for pitch in [20.0, 5.0] {
        let camera = Camera::looking(eye, 0.0, pitch);
        for (name, fog) in fogs {
            let far = fog.opaque_distance(f64::from(eye[2]), highest);
            let (all, beyond) = footprint_beyond(
                &mut source,
                &camera,
                (320, 240),
                &RenderOptions::default(),
                far,
            )
            .unwrap();
            println!(
                "pitch {pitch:>4}: {name}: opaque past {far:.0} voxels; {beyond} of {all} footprint tiles ({:.1} %) lie beyond",
                100.0 * beyond as f64 / all as f64
            );
            spared.push(beyond);
        }
    }
    // The flight's layer is below this eye: its fog is thin where the
    // eye looks from, and it spares nothing; dense uniform fog spares
    // the far footprint.
    assert_eq!(spared[0], 0);
    assert!(spared[5] > 0, "{spared:?}");
}
