//! The atmosphere on the host: relief shading baked into a scene's colors,
//! and the exact sky and fog over the frames of renderers other than the
//! kernel (which has its own, in fixed point: `terracast::AtmosphereSink`)
//! and the reference (which applies it ray by ray).

use crate::camera::{length, ContractCamera};
use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::scene::Scene;
use terracast::{shade_relief, Atmosphere, Camera, Relief};

/// Shades `scene`'s colors by its relief under `relief`'s sun, before any
/// renderer (or the kernel's pyramid) reads them; returns the points in
/// shadow.
pub fn shade_scene(scene: &mut Scene, relief: &Relief) -> Result<usize> {
    let (width, heights) = (scene.width as usize, &scene.heights);
    shade_relief(
        scene.width,
        scene.depth,
        |i, j| heights[j as usize * width + i as usize],
        &mut scene.colors,
        relief,
    )
    .map_err(|e| Error::new(e.to_string()))
}

/// Puts `atmosphere` over a finished frame of `camera`, pixel by pixel
/// from its center ray and depth: for renderers that keep a depth a pixel
/// (Voxel Space, the march, the volume methods).
pub fn apply_exact(frame: &mut Frame, camera: &Camera, atmosphere: &Atmosphere) {
    let rays = ContractCamera::new(camera, frame.width, frame.height);
    let eye = rays.eye[2];
    for (i, (color, &depth)) in frame.colors.iter_mut().zip(&frame.depth).enumerate() {
        let (x, y) = (i % frame.width as usize, i / frame.width as usize);
        let d = rays.direction(x as f64 + 0.5, y as f64 + 0.5);
        let hit = depth
            .is_finite()
            .then(|| (f64::from(depth), eye + f64::from(depth) * d[2] / length(d)));
        let seen = atmosphere.exact(d, eye, hit, color.map(f64::from));
        *color = seen.map(|c| c.round().clamp(0.0, 255.0) as u8);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_atmosphere_over_a_frame_turns_sky_into_the_gradient() {
        let mut frame = Frame::new(8, 6);
        frame.colors.fill([1, 2, 3]);
        let camera = Camera::looking([0.0, 0.0, 50.0], 0.0, -30.0);
        let air = Atmosphere {
            fog: None,
            sun: None,
            ..Atmosphere::FLIGHT
        };
        apply_exact(&mut frame, &camera, &air);
        // Looking 30° up: every pixel is sky, bluer at the top.
        assert!(frame.colors.iter().all(|&c| c != [1, 2, 3]));
        assert!(
            frame.colors[0][2] < frame.colors[5 * 8][2]
                || frame.colors[0][0] < frame.colors[5 * 8][0]
        );
    }
}
