//! The fixed-point format at its extremes: the largest map side
//! (`MAX_MAP_SIDE` = 32767) and the farthest eye (`MAX_EYE_COORD` = 32000
//! voxels outside the map), in both major axes and both directions.
//!
//! Stated precision: the I16F16 slopes are truncated to 2⁻¹⁶ per step, so
//! after n steps a ray's height is off by at most n·2⁻¹⁶ voxels (≤ 1 voxel
//! after 64 767 steps). On a flat plane seen at a grazing 0.6° that is a
//! relative depth error of at most 1.5 %, and it must not wrap, smear or
//! panic anywhere.

use terracast::config::{MAX_EYE_COORD, MAX_MAP_SIDE};
use terracast::{
    render, Camera, Coherence, CountingProbe, Framebuffer, Pyramid, RenderOptions, Sample, Terrain,
    TerrainError, View,
};

const PLANE: f64 = 100.0;

/// Renders a flat plane at height 100 on a `w` × `d` map and checks every
/// hit's distance against the analytic one.
fn check_plane(w: u32, d: u32, eye: [f32; 3], yaw: f32) -> (usize, f64) {
    let n = w as usize * d as usize;
    let heights = vec![Terrain::quantize_height(PLANE as f32).unwrap(); n];
    let colors = vec![[50, 120, 60]; n];
    let terrain = Terrain::new(w, d, &heights, &colors).unwrap();
    let camera = Camera {
        eye,
        yaw_deg: yaw,
        pitch_deg: 0.67,
        roll_deg: 0.0,
        hfov_deg: 1.0,
    };
    let (iw, ih) = (31, 31);
    let view = View::new(&camera, iw, ih).unwrap();
    let mut pixels = vec![[0u8; 3]; (iw * ih) as usize];
    let mut distances = vec![0u32; (iw * ih) as usize];
    let mut frame = Framebuffer::with_distances(&mut pixels, &mut distances, iw, ih).unwrap();
    let options = RenderOptions {
        coherence: Coherence::Exact,
        ..RenderOptions::default()
    };
    render(
        &Pyramid::flat(terrain),
        &view,
        &options,
        &mut frame,
        &mut CountingProbe::default(),
    );

    let (mut hits, mut worst) = (0, 0.0f64);
    let (yaw, pitch) = (f64::from(yaw).to_radians(), 0.67f64.to_radians());
    let t = (0.5f64.to_radians()).tan();
    for py in 0..ih {
        let x = 15u32; // middle column: the ray lies in the vertical plane of the yaw
        let b =
            (1.0 - 2.0 * (f64::from(py) + 0.5) / f64::from(ih)) * t * f64::from(ih) / f64::from(iw);
        // Angle below the horizon of this row's ray.
        let below = pitch - b.atan();
        let index = (py * iw + x) as usize;
        let along = (f64::from(eye[2]) - PLANE) / below.tan(); // horizontal distance to the plane
        let (hx, hy) = (
            f64::from(eye[0]) + along * yaw.cos(),
            f64::from(eye[1]) + along * yaw.sin(),
        );
        let inside = below > 0.0
            && (0.0..=f64::from(w - 1)).contains(&hx)
            && (0.0..=f64::from(d - 1)).contains(&hy);
        let got = distances[index];
        if !inside {
            // Distances along the major axis from the eye to the map's near
            // and far edges.
            let (e, len, sign) = if yaw.cos().abs() > 0.5 {
                (f64::from(eye[0]), f64::from(w - 1), yaw.cos().signum())
            } else {
                (f64::from(eye[1]), f64::from(d - 1), yaw.sin().signum())
            };
            let (to0, to_end) = (-e * sign, (len - e) * sign);
            let (near, far) = (to0.min(to_end).max(0.0), to0.max(to_end));
            let major_expected = along * yaw.cos().abs().max(yaw.sin().abs());
            if below <= 0.0 || major_expected > far * 1.02 {
                // Rising, or meeting the plane beyond the map: sky.
                assert_eq!(got, Sample::SKY, "row {py}: hit where there is no terrain");
            } else if major_expected < near {
                // Enters the map already below the plane: hit at the near edge.
                let major = f64::from(got) / 65536.0;
                assert!(
                    (major - near).abs() <= 1.0,
                    "row {py}: hit at {major}, near edge at {near}"
                );
            }
            continue;
        }
        assert_ne!(
            got,
            Sample::SKY,
            "row {py}: missed the plane {along:.0} voxels away"
        );
        assert_eq!(pixels[index], [50, 120, 60], "row {py}: garbage color");
        let major = f64::from(got) / 65536.0;
        let major_expected = along * yaw.cos().abs().max(yaw.sin().abs());
        let error = (major - major_expected).abs() / major_expected;
        worst = worst.max(error);
        hits += 1;
    }
    (hits, worst)
}

#[test]
fn largest_map_and_farthest_eye_in_every_direction() {
    let side = MAX_MAP_SIDE;
    let far = MAX_EYE_COORD;
    // x-major forward (from 32000 voxels outside the map) and backward
    // (from the far end) along a 32767 x 4 strip; y-major likewise.
    let cases = [
        (side, 4, [-far, 1.5, 600.0], 0.0),
        (side, 4, [far, 1.5, 300.0], 180.0),
        (4, side, [1.5, -far, 600.0], 90.0),
        (4, side, [1.5, far, 300.0], 270.0),
    ];
    for (w, d, eye, yaw) in cases {
        let (hits, worst) = check_plane(w, d, eye, yaw);
        println!(
            "{w}x{d} eye {eye:?} yaw {yaw}: {hits} hits, worst relative depth error {:.4} %",
            worst * 100.0
        );
        assert!(hits >= 8, "too few rows hit the plane");
        assert!(
            worst < 0.015,
            "relative depth error {worst} above the stated 1.5 %"
        );
    }
}

#[test]
fn map_sides_beyond_the_format_are_refused() {
    let h = [0u16; 4];
    let c = [[0u8; 3]; 4];
    assert_eq!(
        Terrain::new(MAX_MAP_SIDE + 1, 2, &h, &c).unwrap_err(),
        TerrainError::TooLarge
    );
    let eye = Camera {
        eye: [MAX_EYE_COORD * 1.01, 0.0, 0.0],
        ..Camera::default()
    };
    assert!(View::new(&eye, 4, 4).is_err());
}
