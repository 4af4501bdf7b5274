//! The kernel against the exact reference on real terrain (Comanche maps),
//! 640 × 360, hfov 60°, eyes over the map, yaws in all four quadrants,
//! pitch 0°–45°. Thresholds from the foundation issue:
//! PSNR ≥ 32 dB, sky/terrain agreement ≥ 99.5 %, median relative depth
//! error ≤ 0.5 %, on every view.

use terracast::Coherence;
use terracast_sim::metrics::{median_relative_depth_error, psnr, sky_agreement};
use terracast_sim::reference::Reference;
use terracast_tests::{camera, comanche, kernel_view, reference_view};

const SIZE: (u32, u32) = (640, 360);

/// (eye, yaw, pitch) per view; yaws cover all four quadrants, and both
/// x-major and y-major rays.
const VIEWS: [([f32; 3], f32, f32); 4] = [
    ([200.0, 300.0, 140.0], 20.0, 0.0),
    ([800.0, 250.0, 150.0], 110.0, 15.0),
    ([760.0, 820.0, 170.0], 200.0, 30.0),
    ([300.0, 700.0, 220.0], 300.0, 45.0),
];

#[test]
fn kernel_matches_reference_on_comanche_maps() {
    let mut failures = Vec::new();
    for (color, height) in [("1W", "1"), ("7W", "7"), ("14", "14")] {
        let scene = comanche(color, height);
        let kernel = scene.to_kernel().unwrap();
        let reference = Reference::new(&scene);
        for (eye, yaw, pitch) in VIEWS {
            let cam = camera(eye, yaw, pitch);
            let (k, _) = kernel_view(&kernel, &cam, SIZE, Coherence::DEFAULT);
            let r = reference_view(&reference, &cam, SIZE);
            let p = psnr(&k.colors, &r.colors);
            let agree = sky_agreement(&k.depth, &r.depth);
            let depth = median_relative_depth_error(&k.depth, &r.depth).unwrap_or(0.0);
            println!(
                "C{color}/D{height} eye {eye:?} yaw {yaw:>5} pitch {pitch:>4}: PSNR {p:6.2} dB, sky agreement {:7.3} %, median depth error {:.3} %",
                agree * 100.0,
                depth * 100.0
            );
            if p < 32.0 || agree < 0.995 || depth > 0.005 {
                failures.push(format!("C{color}/D{height} yaw {yaw} pitch {pitch}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "views below the accuracy bar: {failures:?}"
    );
}
