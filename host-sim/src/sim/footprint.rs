//! The master's footprint: the tiles a frame may read, found from the view
//! alone (Cohen-Or §3.2: "the master draws the rectangular frame of the
//! image footprint on the terrain").
//!
//! The footprint is the horizontal wedge of the field of view, out to where
//! the top row's ray reaches the ground (or to the map's edge when it looks
//! at or above the horizon), widened to the whole circle when the view
//! includes the nadir. A tile is in it when one of nine points spread over
//! the tile, or the eye, lies in the wedge. Tiles of every level are
//! listed; the kernel may read any of them, and anything it reads outside
//! the footprint is a critical load at render time.

use super::trace::TileKey;
use terracast::{level_side, Camera};

/// The footprint's tiles, and how many tiles were tested.
pub fn footprint_tiles(
    camera: &Camera,
    size: (u32, u32),
    map: (u32, u32),
    levels: usize,
    tile_side: u32,
) -> (Vec<TileKey>, u64) {
    let wedge = Wedge::new(camera, size, map);
    let mut tiles = Vec::new();
    let mut tested = 0;
    for level in 0..levels {
        let (w, d) = (
            level_side(map.0, level as u32),
            level_side(map.1, level as u32),
        );
        let scale = f64::from(1u32 << level.min(31));
        let side = f64::from(tile_side) * scale;
        for ty in 0..d.div_ceil(tile_side) {
            for tx in 0..w.div_ceil(tile_side) {
                tested += 1;
                let (x0, y0) = (f64::from(tx) * side, f64::from(ty) * side);
                if wedge.touches(x0, y0, side) {
                    tiles.push(TileKey {
                        level: level as u8,
                        x: tx,
                        y: ty,
                    });
                }
            }
        }
    }
    (tiles, tested)
}

struct Wedge {
    eye: (f64, f64),
    /// Unit heading.
    heading: (f64, f64),
    /// Cosine of the half angle; -1 for the whole circle.
    cos_half: f64,
    far: f64,
}

impl Wedge {
    fn new(camera: &Camera, size: (u32, u32), map: (u32, u32)) -> Self {
        let [ex, ey, ez] = camera.eye.map(f64::from);
        let yaw = f64::from(camera.yaw_deg).to_radians();
        let (sin_p, cos_p) = f64::from(camera.pitch_deg).to_radians().sin_cos();
        // Image-plane half extents at unit depth (the view contract's
        // direction f + a·r + b·u, |a| <= ta, |b| <= tb).
        let ta = (f64::from(camera.hfov_deg).to_radians() / 2.0).tan();
        let tb = ta * f64::from(size.1) / f64::from(size.0);
        // A corner ray's horizontal part: forward cos p + b·sin p, sideways
        // a; its height change: b·cos p − sin p.
        let forward_bottom = cos_p - tb * sin_p;
        let forward_top = cos_p + tb * sin_p;
        let diagonal = f64::from(map.0).hypot(f64::from(map.1)) + ex.abs() + ey.abs();
        // Nothing past where the top corners reach the ground can be hit.
        let descent = sin_p - tb * cos_p;
        let far = if descent > 1e-9 {
            (ez.max(0.0) * forward_top.hypot(ta) / descent).min(diagonal)
        } else {
            diagonal
        };
        // The widest horizontal angle is a bottom corner's; a view whose
        // bottom rows lean back past the vertical sees every direction.
        let cos_half = if forward_bottom <= 1e-9 {
            -1.0
        } else {
            let widest = ta.atan2(forward_bottom).max(ta.atan2(forward_top));
            widest.cos()
        };
        Self {
            eye: (ex, ey),
            heading: (yaw.cos(), yaw.sin()),
            cos_half,
            far,
        }
    }

    fn contains(&self, x: f64, y: f64) -> bool {
        let (dx, dy) = (x - self.eye.0, y - self.eye.1);
        let distance = dx.hypot(dy);
        if distance > self.far {
            return false;
        }
        distance < 1e-9 || (dx * self.heading.0 + dy * self.heading.1) >= self.cos_half * distance
    }

    /// Whether the tile `[x0, x0 + side]²` meets the wedge.
    fn touches(&self, x0: f64, y0: f64, side: f64) -> bool {
        let (ex, ey) = self.eye;
        if (x0..=x0 + side).contains(&ex) && (y0..=y0 + side).contains(&ey) {
            return true;
        }
        (0..3).any(|i| {
            (0..3).any(|j| {
                let x = x0 + side * f64::from(i) / 2.0;
                let y = y0 + side * f64::from(j) / 2.0;
                self.contains(x, y)
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(pitch: f32) -> Camera {
        Camera::looking([512.0, 100.0, 300.0], 90.0, pitch)
    }

    #[test]
    fn steeper_views_have_smaller_footprints_in_front_of_the_eye() {
        let count = |pitch| footprint_tiles(&camera(pitch), (640, 480), (1024, 1024), 1, 64).0;
        let (shallow, steep) = (count(10.0), count(60.0));
        assert!(
            steep.len() < shallow.len(),
            "{} {}",
            steep.len(),
            shallow.len()
        );
        // The eye's own tile is always in; a tile behind the eye is not.
        for tiles in [&shallow, &steep] {
            assert!(tiles.contains(&TileKey {
                level: 0,
                x: 8,
                y: 1
            }));
            assert!(!tiles.contains(&TileKey {
                level: 0,
                x: 8,
                y: 0
            }));
        }
        assert!(!steep.contains(&TileKey {
            level: 0,
            x: 8,
            y: 15
        }));
        assert!(shallow.contains(&TileKey {
            level: 0,
            x: 8,
            y: 15
        }));
    }

    #[test]
    fn straight_down_covers_the_circle_around_the_eye() {
        let (tiles, tested) = footprint_tiles(&camera(90.0), (640, 480), (1024, 1024), 2, 64);
        let level1 = u64::from(level_side(1024, 1).div_ceil(64));
        assert_eq!(tested, 16 * 16 + level1 * level1);
        // Behind the eye too.
        assert!(tiles.contains(&TileKey {
            level: 0,
            x: 8,
            y: 0
        }));
        assert!(tiles.contains(&TileKey {
            level: 1,
            x: 4,
            y: 0
        }));
    }
}
