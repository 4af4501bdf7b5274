//! Sun shading baked into a terrain's colors before its pyramid is built:
//! relief by the slope, and cast shadows. Done once a scene, so a pixel
//! pays nothing for it; the pyramid's coarser colors filter the shaded
//! ones.
//!
//! - **Relief**: Lambert's cosine between the surface normal (central
//!   differences of the heights) and the sun, with an ambient share,
//!   scaled so that level ground in the sun keeps its color: slopes
//!   facing the sun brighten, slopes facing away darken to the ambient
//!   share.
//! - **Shadows**: a point that terrain between it and the sun rises above
//!   (along the sun's azimuth, at its elevation) takes the ambient share
//!   only. One sweep along lines of the sun's azimuth finds them all, each
//!   point visited once (the grid point nearest the line at each step).

use crate::color::Rgb;
use core::fmt;

/// The light a terrain is shaded by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relief {
    /// The sun's heading, from +x toward +y, degrees.
    pub sun_azimuth_deg: f32,
    /// The sun's height above the horizon, degrees (above 0, at most 90).
    pub sun_elevation_deg: f32,
    /// The share of light that reaches every point (0 to 1).
    pub ambient: f32,
    /// Whether the terrain casts shadows.
    pub shadows: bool,
}

/// Why a terrain could not be shaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReliefError {
    /// The colors are not `width ×` the rows, the rows run past the map,
    /// or the map is under 2 × 2.
    Size,
    /// The sun is not above the horizon (0 < elevation <= 90°), or a
    /// number is not finite.
    Sun,
    /// The ambient share is outside 0 to 1.
    Ambient,
}

impl fmt::Display for ReliefError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Size => "relief shading needs a map of at least 2 x 2 with a color a point",
            Self::Sun => {
                "relief shading needs a sun above the horizon (0 < elevation <= 90 degrees)"
            }
            Self::Ambient => "relief shading needs an ambient share from 0 to 1",
        })
    }
}

impl core::error::Error for ReliefError {}

/// Shades `colors` (row-major, `width × depth`) by the relief of the
/// heights `height(i, j)` (voxels) under `relief`'s sun; returns how many
/// points lie in shadow.
///
/// ```
/// use terracast::{shade_relief, Relief};
/// // A ridge along y: its east face (+x) toward a sun in the east.
/// let height = |i: u32, _j: u32| 8.0 - (i as f32 - 4.0).abs() * 2.0;
/// let mut colors = [[100u8; 3]; 81];
/// let sun = Relief { sun_azimuth_deg: 0.0, sun_elevation_deg: 30.0, ambient: 0.3, shadows: true };
/// shade_relief(9, 9, height, &mut colors, &sun).unwrap();
/// assert!(colors[4 * 9 + 6][0] > 100 && colors[4 * 9 + 2][0] < 100);
/// ```
pub fn shade_relief(
    width: u32,
    depth: u32,
    height: impl Fn(u32, u32) -> f32,
    colors: &mut [Rgb],
    relief: &Relief,
) -> Result<usize, ReliefError> {
    if width < 2 || depth < 2 || colors.len() != width as usize * depth as usize {
        return Err(ReliefError::Size);
    }
    let (azimuth, elevation) = (relief.sun_azimuth_deg, relief.sun_elevation_deg);
    if !(azimuth.is_finite() && elevation > 0.0 && elevation <= 90.0) {
        return Err(ReliefError::Sun);
    }
    if !(0.0..=1.0).contains(&relief.ambient) {
        return Err(ReliefError::Ambient);
    }
    let (azimuth, elevation) = (azimuth.to_radians(), elevation.to_radians());
    let sun = [
        libm::cosf(elevation) * libm::cosf(azimuth),
        libm::cosf(elevation) * libm::sinf(azimuth),
        libm::sinf(elevation),
    ];
    let ambient = relief.ambient;
    // Level ground in the sun keeps its color.
    let level = ambient + (1.0 - ambient) * sun[2];
    let at = |i: i64, j: i64| {
        height(
            i.clamp(0, i64::from(width) - 1) as u32,
            j.clamp(0, i64::from(depth) - 1) as u32,
        )
    };
    let mut shadowed = 0;
    let mut shade = |i: u32, j: u32, in_shadow: bool| {
        let (x, y) = (i64::from(i), i64::from(j));
        let dx = 0.5 * (at(x + 1, y) - at(x - 1, y));
        let dy = 0.5 * (at(x, y + 1) - at(x, y - 1));
        let normal_length = libm::sqrtf(dx * dx + dy * dy + 1.0);
        let lambert = ((-dx * sun[0] - dy * sun[1] + sun[2]) / normal_length).max(0.0);
        let lit = if in_shadow {
            shadowed += 1;
            0.0
        } else {
            lambert
        };
        let factor = (ambient + (1.0 - ambient) * lit) / level;
        let color = &mut colors[j as usize * width as usize + i as usize];
        *color = color.map(|c| libm::roundf(f32::from(c) * factor).clamp(0.0, 255.0) as u8);
    };
    if !relief.shadows || elevation >= core::f32::consts::FRAC_PI_2 {
        for j in 0..depth {
            for i in 0..width {
                shade(i, j, false);
            }
        }
        return Ok(shadowed);
    }
    // Shadows by one sweep: lines along the sun's azimuth, one grid
    // point a step along the axis nearer that azimuth (the point nearest
    // the line across it), walked away from the sun. The shadow's top
    // falls by the sun's slope a step and rises to the terrain wherever
    // the terrain is higher; a point under it is in shadow. Every point
    // lies on exactly one line: linear in the map.
    let toward = [libm::cosf(azimuth), libm::sinf(azimuth)];
    let x_major = toward[0].abs() >= toward[1].abs();
    let (along, across) = if x_major {
        (width, depth)
    } else {
        (depth, width)
    };
    let (sun_along, sun_across) = if x_major {
        (toward[0], toward[1])
    } else {
        (toward[1], toward[0])
    };
    // Away from the sun: one point a step along, `lean` across.
    let step = if sun_along > 0.0 { -1i64 } else { 1 };
    let first = if step > 0 { 0 } else { i64::from(along) - 1 };
    let lean = -sun_across / sun_along.abs().max(f32::MIN_POSITIVE);
    let drop = libm::tanf(elevation) * libm::sqrtf(1.0 + lean * lean);
    let offset = |k: i64| libm::roundf(k as f32 * lean) as i64;
    let last_offset = offset(i64::from(along) - 1);
    let (low, high) = (last_offset.min(0), last_offset.max(0));
    let point = |a: i64, cross: i64| {
        let (a, cross) = (a as u32, cross as u32);
        if x_major {
            (a, cross)
        } else {
            (cross, a)
        }
    };
    let last_across = i64::from(across) - 1;
    for line in -high..i64::from(across) - low {
        let mut top = f32::NEG_INFINITY;
        for k in 0..i64::from(along) {
            top -= drop;
            let a = first + k * step;
            // The terrain on the line itself, between the two points
            // across it; the nearer of them takes the line's shadow.
            let on_line = (line as f32 + k as f32 * lean).clamp(0.0, last_across as f32);
            let below = libm::floorf(on_line) as i64;
            let (i0, j0) = point(a, below);
            let (i1, j1) = point(a, (below + 1).min(last_across));
            let (h0, h1) = (height(i0, j0), height(i1, j1));
            let here = h0 + (h1 - h0) * (on_line - below as f32);
            let cross = line + offset(k);
            if (0..=last_across).contains(&cross) {
                let (i, j) = point(a, cross);
                shade(i, j, top > here + 0.01);
            }
            top = top.max(here);
        }
    }
    Ok(shadowed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_ground_in_the_sun_keeps_its_color() {
        let mut colors = [[120u8, 80, 40]; 64];
        let relief = Relief {
            sun_azimuth_deg: 40.0,
            sun_elevation_deg: 25.0,
            ambient: 0.25,
            shadows: true,
        };
        let shadowed = shade_relief(8, 8, |_, _| 5.0, &mut colors, &relief).unwrap();
        assert_eq!(shadowed, 0);
        assert!(colors.iter().all(|&c| c == [120, 80, 40]));
    }

    #[test]
    fn a_wall_shadows_the_ground_behind_it_from_the_sun() {
        // A wall 10 voxels high along x = 10 on a 32 × 8 plain; the sun in
        // the east (+x) at 45°: the ten points west of the wall are in its
        // shadow, the plain east of it is lit.
        let height = |i: u32, _j: u32| if i == 10 { 10.0 } else { 0.0 };
        let mut colors = [[200u8; 3]; 32 * 8];
        let relief = Relief {
            sun_azimuth_deg: 0.0,
            sun_elevation_deg: 45.0,
            ambient: 0.2,
            shadows: true,
        };
        shade_relief(32, 8, height, &mut colors, &relief).unwrap();
        let row = &colors[3 * 32..4 * 32];
        assert!(row[2..9].iter().all(|c| c[0] < 100), "{row:?}");
        assert!(row[12..].iter().all(|c| c[0] == 200), "{row:?}");
        let without = Relief {
            shadows: false,
            ..relief
        };
        let mut unshadowed = [[200u8; 3]; 32 * 8];
        assert_eq!(
            shade_relief(32, 8, height, &mut unshadowed, &without),
            Ok(0)
        );
        assert_eq!(unshadowed[3 * 32 + 4], [200; 3]);
    }

    #[test]
    fn the_sweep_shades_every_point_once_at_every_azimuth() {
        // A plane rising toward +x and +y: every point faces a sun above
        // it from those sides, so every point brightens; a point the sweep
        // missed would keep its color, one shaded twice would brighten more.
        let plane = |i: u32, j: u32| 0.3 * i as f32 + 0.2 * j as f32;
        for azimuth in [180.0, 200.0, 225.0, 250.0, 270.0, 235.5] {
            for (width, depth) in [(17, 9), (9, 23), (2, 2)] {
                let relief = Relief {
                    sun_azimuth_deg: azimuth,
                    sun_elevation_deg: 60.0,
                    ambient: 0.3,
                    shadows: true,
                };
                let mut colors = vec![[100u8; 3]; width * depth];
                let (w, d) = (width as u32, depth as u32);
                assert_eq!(shade_relief(w, d, plane, &mut colors, &relief), Ok(0));
                // Central differences halve at the edges: the inside is
                // one shade, and every point brightens.
                let inside = colors[width + 1];
                assert!(
                    colors.iter().all(|c| c[0] > 100),
                    "{azimuth} {width}x{depth}"
                );
                for j in 1..depth.saturating_sub(1) {
                    for i in 1..width - 1 {
                        assert_eq!(colors[j * width + i], inside, "{azimuth} {width}x{depth}");
                    }
                }
            }
        }
    }

    #[test]
    fn the_sweep_agrees_with_a_march_toward_the_sun_but_on_shadow_edges() {
        // Rough terrain (bumps 9 voxels high, 10 to 30 apart, the sun at
        // 20°: shadow edges everywhere); a point is in shadow when a march
        // toward the sun (a tenth of a voxel a step, heights bilinear)
        // passes below the terrain.
        let (width, depth) = (48u32, 40u32);
        let height = |i: u32, j: u32| {
            let (x, y) = (i as f32, j as f32);
            6.0 * libm::sinf(x * 0.31) * libm::cosf(y * 0.23) + 3.0 * libm::sinf((x + y) * 0.7)
        };
        let bilinear = |x: f32, y: f32| {
            let (i, j) = (libm::floorf(x) as u32, libm::floorf(y) as u32);
            let (fx, fy) = (x - i as f32, y - j as f32);
            let (i1, j1) = ((i + 1).min(width - 1), (j + 1).min(depth - 1));
            let near = height(i, j) + (height(i1, j) - height(i, j)) * fx;
            let far = height(i, j1) + (height(i1, j1) - height(i, j1)) * fx;
            near + (far - near) * fy
        };
        for azimuth in [10.0f32, 75.0, 150.0, 240.0, 315.0] {
            let relief = Relief {
                sun_azimuth_deg: azimuth,
                sun_elevation_deg: 20.0,
                ambient: 0.0,
                shadows: true,
            };
            let mut colors = vec![[200u8; 3]; (width * depth) as usize];
            shade_relief(width, depth, height, &mut colors, &relief).unwrap();
            let (a, e) = (azimuth.to_radians(), 20f32.to_radians());
            let (mut agree, mut total) = (0, 0);
            for j in 0..depth {
                for i in 0..width {
                    let (mut x, mut y, mut z) = (i as f32, j as f32, height(i, j) + 0.01);
                    let mut marched = false;
                    loop {
                        x += 0.1 * libm::cosf(a);
                        y += 0.1 * libm::sinf(a);
                        z += 0.1 * libm::tanf(e);
                        if x < 0.0
                            || y < 0.0
                            || x > (width - 1) as f32
                            || y > (depth - 1) as f32
                            || z > 9.5
                        {
                            break;
                        }
                        if bilinear(x, y) > z {
                            marched = true;
                            break;
                        }
                    }
                    // With no ambient light a point in shadow is black.
                    let swept = colors[(j * width + i) as usize] == [0; 3];
                    agree += usize::from(swept == marched);
                    total += 1;
                }
            }
            // The sweep takes a point's shadow from the line nearest it,
            // so shadow edges move by up to a voxel across the sun (here
            // 87 to 91 % of the points agree, the rest on the edges).
            let share = agree as f64 / total as f64;
            println!("azimuth {azimuth}: {:.1} % agree", 100.0 * share);
            assert!(
                share >= 0.85,
                "azimuth {azimuth}: {:.1} % agree",
                100.0 * share
            );
        }
    }

    #[test]
    fn bad_input_is_refused() {
        let relief = Relief {
            sun_azimuth_deg: 0.0,
            sun_elevation_deg: 45.0,
            ambient: 0.2,
            shadows: false,
        };
        let mut colors = [[0u8; 3]; 4];
        assert_eq!(
            shade_relief(3, 3, |_, _| 0.0, &mut colors, &relief),
            Err(ReliefError::Size)
        );
        let below = Relief {
            sun_elevation_deg: 0.0,
            ..relief
        };
        assert_eq!(
            shade_relief(2, 2, |_, _| 0.0, &mut colors, &below),
            Err(ReliefError::Sun)
        );
        let dark = Relief {
            ambient: 1.5,
            ..relief
        };
        assert_eq!(
            shade_relief(2, 2, |_, _| 0.0, &mut colors, &dark),
            Err(ReliefError::Ambient)
        );
    }
}
