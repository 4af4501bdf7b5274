//! The baselines the kernel is measured against, each an honest
//! single-threaded implementation of its method on the same scene and the
//! same contract camera:
//!
//! - [`voxel_space`]: the Comanche "Voxel Space" algorithm as published by
//!   Sebastian Macke: depth slices front to back, each a line across the
//!   field of view, projected column by column into a y-buffer, the slice
//!   spacing growing with distance. **It cannot pitch:** its pitch is a
//!   shift of the horizon line, not a rotation, so it agrees with a true
//!   camera only at pitch 0.
//! - [`march`]: a naive per-pixel float ray march with a fixed step, the
//!   bilinear surface sampled at each step, no refinement.

use crate::camera::{length, ContractCamera};
use crate::frame::{Frame, RenderStats};
use crate::scene::Scene;
use std::time::Instant;
use terracast::{Camera, Rgb};

/// Voxel Space's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoxelSpaceOptions {
    /// Growth of the slice spacing each slice (the published demo: 0.005;
    /// the first slice is 1 voxel from the eye, 1 voxel after the last).
    pub spacing_growth: f64,
    /// Sky color.
    pub sky: Rgb,
}

/// Renders with Voxel Space. The horizon sits where the contract camera
/// puts it (`tan(pitch)` focal lengths above the image center); slices are
/// perpendicular to the heading and span the horizontal field of view.
pub fn voxel_space(
    scene: &Scene,
    camera: &Camera,
    width: u32,
    height: u32,
    options: &VoxelSpaceOptions,
) -> (Frame, RenderStats) {
    voxel_space_touching(scene, camera, width, height, options, &mut |_| {})
}

/// [`voxel_space`], calling `touch` with the index of every voxel it reads
/// (a no-op closure compiles away).
pub fn voxel_space_touching(
    scene: &Scene,
    camera: &Camera,
    width: u32,
    height: u32,
    options: &VoxelSpaceOptions,
    touch: &mut impl FnMut(usize),
) -> (Frame, RenderStats) {
    let started = Instant::now();
    let mut frame = Frame::new(width, height);
    frame.colors.fill(options.sky);
    let (w, h) = (width as usize, height as usize);
    let (sin_yaw, cos_yaw) = f64::from(camera.yaw_deg).to_radians().sin_cos();
    let tangent = (f64::from(camera.hfov_deg).to_radians() / 2.0).tan();
    let focal = f64::from(width) / (2.0 * tangent);
    let horizon = f64::from(height) / 2.0 - f64::from(camera.pitch_deg).to_radians().tan() * focal;
    let [ex, ey, ez] = camera.eye.map(f64::from);
    let (map_w, map_d) = (scene.width as usize, scene.depth as usize);
    // Nothing lies farther than the map's far corner.
    let far = [
        (0.0, 0.0),
        (map_w as f64, 0.0),
        (0.0, map_d as f64),
        (map_w as f64, map_d as f64),
    ]
    .iter()
    .map(|&(x, y)| (x - ex).hypot(y - ey))
    .fold(0.0, f64::max);
    // The top of each column's drawn part, and its slope factor for depth.
    let mut y_buffer = vec![h as f64; w];
    let spread: Vec<f64> = (0..w)
        .map(|i| (2.0 * (i as f64 + 0.5) / width as f64 - 1.0) * tangent)
        .collect();
    let mut samples = 0u64;
    let (mut z, mut dz) = (1.0f64, 1.0f64);
    while z < far {
        // The slice: from the left edge of the view to the right, z ahead.
        let (cx, cy) = (ex + z * cos_yaw, ey + z * sin_yaw);
        let (rx, ry) = (-sin_yaw * z, cos_yaw * z);
        // Screen rows per unit of height at this slice, once a slice (as
        // in Macke's code: one division a slice, not one a sample).
        let rows_per_height = focal / z;
        for (i, &a) in spread.iter().enumerate() {
            let (x, y) = (cx + a * rx, cy + a * ry);
            if x < 0.0 || y < 0.0 || x >= map_w as f64 || y >= map_d as f64 {
                continue;
            }
            samples += 1;
            let voxel = y as usize * map_w + x as usize;
            touch(voxel);
            let top = horizon + (ez - f64::from(scene.heights[voxel])) * rows_per_height;
            let bottom = y_buffer[i];
            if top < bottom {
                let first = top.max(0.0).ceil() as usize;
                let last = bottom.min(h as f64).ceil() as usize;
                let distance =
                    (z * (1.0 + a * a).sqrt()).hypot(ez - f64::from(scene.heights[voxel])) as f32;
                for row in first..last {
                    frame.colors[row * w + i] = scene.colors[voxel];
                    frame.depth[row * w + i] = distance;
                }
                y_buffer[i] = top;
            }
        }
        z += dz;
        dz += options.spacing_growth;
    }
    let stats = RenderStats {
        method: "voxelspace",
        pixels: (w * h) as u64,
        rays: w as u64,
        steps: samples,
        resident_bytes: scene_bytes(scene),
        render_ns: started.elapsed().as_nanos() as u64,
        levels: None,
    };
    (frame, stats)
}

/// The march's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarchOptions {
    /// Step length along the ray, in voxels.
    pub step: f64,
    /// Sky color.
    pub sky: Rgb,
}

/// Renders with a fixed-step march: one ray through each pixel center,
/// stepping `step` voxels until the ray is at or below the bilinear surface
/// (the hit), leaves the map, or rises above the highest terrain.
pub fn march(
    scene: &Scene,
    camera: &Camera,
    width: u32,
    height: u32,
    options: &MarchOptions,
) -> (Frame, RenderStats) {
    march_touching(scene, camera, width, height, options, &mut |_| {})
}

/// [`march`], calling `touch` with the index of the lower-left corner of
/// every cell it samples (the sample reads the cell's four corners).
pub fn march_touching(
    scene: &Scene,
    camera: &Camera,
    width: u32,
    height: u32,
    options: &MarchOptions,
    touch: &mut impl FnMut(usize),
) -> (Frame, RenderStats) {
    let started = Instant::now();
    let rays = ContractCamera::new(camera, width, height);
    let mut frame = Frame::new(width, height);
    let top = f64::from(scene.max_height());
    let (map_w, map_d) = (f64::from(scene.width - 1), f64::from(scene.depth - 1));
    let mut samples = 0u64;
    for py in 0..height {
        for px in 0..width {
            let d = rays.direction(f64::from(px) + 0.5, f64::from(py) + 0.5);
            let n = length(d);
            let step: [f64; 3] = core::array::from_fn(|k| d[k] / n * options.step);
            let mut p = rays.eye;
            let mut t = 0.0;
            let index = (py * width + px) as usize;
            frame.colors[index] = options.sky;
            loop {
                let inside = (0.0..=map_w).contains(&p[0]) && (0.0..=map_d).contains(&p[1]);
                if inside {
                    samples += 1;
                    let (i, j, _, _) = scene.cell_at(p[0], p[1]);
                    touch(j * scene.width as usize + i);
                    if p[2] <= scene.height_at(p[0], p[1]) {
                        let color = scene.color_at(p[0], p[1]);
                        frame.colors[index] = color.map(|v| v.round().clamp(0.0, 255.0) as u8);
                        frame.depth[index] = t as f32;
                        break;
                    }
                } else if moving_away(p, step, map_w, map_d) {
                    break;
                }
                if p[2] > top && step[2] >= 0.0 {
                    break;
                }
                p = core::array::from_fn(|k| p[k] + step[k]);
                t += options.step;
            }
        }
    }
    let stats = RenderStats {
        method: "march",
        pixels: u64::from(width) * u64::from(height),
        rays: u64::from(width) * u64::from(height),
        steps: samples,
        resident_bytes: scene_bytes(scene),
        render_ns: started.elapsed().as_nanos() as u64,
        levels: None,
    };
    (frame, stats)
}

/// Whether a point outside the map is moving farther out on some axis.
fn moving_away(p: [f64; 3], step: [f64; 3], map_w: f64, map_d: f64) -> bool {
    (p[0] < 0.0 && step[0] <= 0.0)
        || (p[0] > map_w && step[0] >= 0.0)
        || (p[1] < 0.0 && step[1] <= 0.0)
        || (p[1] > map_d && step[1] >= 0.0)
}

/// Bytes of the scene as the baselines hold it (f32 height and RGB color).
fn scene_bytes(scene: &Scene) -> u64 {
    (scene.heights.len() * (4 + 3)) as u64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::psnr;
    use crate::reference::{Reference, ReferenceOptions};

    fn scene() -> Scene {
        crate::scene::procedural(256, 4)
    }

    fn camera(pitch: f32) -> Camera {
        Camera::looking([128.0, 20.0, 170.0], 90.0, pitch)
    }

    fn reference(scene: &Scene, camera: &Camera) -> Frame {
        let options = ReferenceOptions {
            supersample: 2,
            sky: terracast::config::DEFAULT_SKY,
            ..ReferenceOptions::default()
        };
        Reference::new(scene).render(camera, 96, 64, &options).0
    }

    #[test]
    fn both_baselines_resemble_the_reference_at_pitch_zero() {
        let scene = scene();
        let cam = camera(0.0);
        let exact = reference(&scene, &cam);
        let sky = terracast::config::DEFAULT_SKY;
        let (vs, vs_stats) = voxel_space(
            &scene,
            &cam,
            96,
            64,
            &VoxelSpaceOptions {
                spacing_growth: 0.005,
                sky,
            },
        );
        let (mr, mr_stats) = march(&scene, &cam, 96, 64, &MarchOptions { step: 0.25, sky });
        let (vs_db, mr_db) = (
            psnr(&vs.colors, &exact.colors),
            psnr(&mr.colors, &exact.colors),
        );
        assert!(vs_db > 15.0, "voxel space {vs_db} dB");
        assert!(mr_db > 20.0, "march {mr_db} dB");
        assert!(vs_stats.steps > 0 && mr_stats.steps > 0);
        assert_eq!((vs_stats.method, mr_stats.method), ("voxelspace", "march"));
        // Infinite depth only where the color is the sky's; never NaN.
        for frame in [&vs, &mr] {
            for (c, d) in frame.colors.iter().zip(&frame.depth) {
                assert!(d.is_infinite() == (*c == sky) || d.is_finite(), "{c:?} {d}");
                assert!(!d.is_nan());
            }
        }
    }

    #[test]
    fn a_finer_march_is_closer_to_the_reference() {
        let scene = scene();
        let cam = camera(20.0);
        let exact = reference(&scene, &cam);
        let sky = terracast::config::DEFAULT_SKY;
        let coarse = march(&scene, &cam, 96, 64, &MarchOptions { step: 4.0, sky }).0;
        let fine = march(&scene, &cam, 96, 64, &MarchOptions { step: 0.25, sky }).0;
        assert!(psnr(&fine.colors, &exact.colors) > psnr(&coarse.colors, &exact.colors));
    }

    #[test]
    fn voxel_space_pitch_is_a_horizon_shift_not_a_rotation() {
        // Looking down 30°, a true camera sees the ground below the eye at
        // the bottom of the image; Voxel Space only slides the picture up, so
        // it falls far from the reference there.
        let scene = scene();
        let sky = terracast::config::DEFAULT_SKY;
        let options = VoxelSpaceOptions {
            spacing_growth: 0.005,
            sky,
        };
        let level = psnr(
            &voxel_space(&scene, &camera(0.0), 96, 64, &options).0.colors,
            &reference(&scene, &camera(0.0)).colors,
        );
        let pitched = psnr(
            &voxel_space(&scene, &camera(30.0), 96, 64, &options)
                .0
                .colors,
            &reference(&scene, &camera(30.0)).colors,
        );
        assert!(
            pitched < level,
            "pitch 30: {pitched} dB, pitch 0: {level} dB"
        );
    }
}
