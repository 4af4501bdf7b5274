//! The built-in scene: fractal terrain with photo-like coloring, so every
//! command works on a machine with no data. Deterministic from its seed.

use super::Scene;
use terracast::Rgb;

/// A `side` × `side` fractal terrain: ridged mountains over rolling fBm,
/// a flat lake below the water line, colored by height and slope.
pub fn procedural(side: u32, seed: u64) -> Scene {
    let side = side.max(2);
    let n = side as usize;
    let mut heights = vec![0.0f32; n * n];
    let scale = 1.0 / 256.0;
    for y in 0..n {
        for x in 0..n {
            let (fx, fy) = (x as f64 * scale, y as f64 * scale);
            let hills = fbm(fx, fy, seed, 7, 0.5);
            let ridges = ridged(fx * 0.7 + 3.1, fy * 0.7 - 1.7, seed ^ 0x9e37_79b9, 6);
            let mask = smoothstep(0.35, 0.75, value_noise(fx * 0.35, fy * 0.35, seed ^ 0x51ed));
            let h = 70.0 * hills + 160.0 * ridges * mask;
            heights[y * n + x] = h.max(WATER_LEVEL) as f32;
        }
    }
    let colors = color_by_height_and_slope(side, side, &heights, seed);
    Scene::new(side, side, heights, colors).expect("procedural scene is well-formed")
}

pub(crate) const WATER_LEVEL: f64 = 22.0;

/// Colors a height field like an aerial photograph: water, sand, grass,
/// forest, rock and snow by relative height and slope, with per-voxel
/// texture and sun shading baked in (as Comanche's color maps are).
pub fn color_by_height_and_slope(width: u32, depth: u32, heights: &[f32], seed: u64) -> Vec<Rgb> {
    let (w, d) = (width as usize, depth as usize);
    let mut bands = HeightBands::default();
    heights.iter().for_each(|&h| bands.add(h));
    let at = |x: usize, y: usize| f64::from(heights[y.min(d - 1) * w + x.min(w - 1)]);
    let mut colors = Vec::with_capacity(w * d);
    for y in 0..d {
        for x in 0..w {
            let gx = (at(x + 1, y) - at(x.saturating_sub(1), y)) * 0.5;
            let gy = (at(x, y + 1) - at(x, y.saturating_sub(1))) * 0.5;
            let grain = value_noise(x as f64 * 0.5, y as f64 * 0.5, seed ^ 0xabc) - 0.5;
            colors.push(terrain_color(
                [x as f64, y as f64],
                at(x, y),
                [gx, gy],
                bands,
                grain,
                seed,
            ));
        }
    }
    colors
}

/// A map's own height range, and its water: a flat surface at its lowest
/// height covering at least [`HeightBands::WATER_SHARE`] of the map (the
/// built-in scene's lake, a coast's sea at 0 m). Colors are banded by these,
/// not by fixed heights, so a map colors the same at any height scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeightBands {
    /// Lowest height.
    pub lo: f64,
    /// Highest height.
    pub hi: f64,
    /// Points at the lowest height.
    pub at_lo: u64,
    /// Points seen.
    pub points: u64,
}

impl Default for HeightBands {
    fn default() -> Self {
        Self {
            lo: f64::MAX,
            hi: f64::MIN,
            at_lo: 0,
            points: 0,
        }
    }
}

impl HeightBands {
    /// Share of the map a flat lowest surface must cover to be water.
    pub const WATER_SHARE: f64 = 0.01;
    /// Most height the shore's sand rises above the water, in voxels; on a
    /// map of little relief, a fiftieth of its range instead.
    const SAND_VOXELS: f64 = 2.5;

    /// The bands of a map whose water level is known (the built-in scene's
    /// lake) and whose heights reach `hi`.
    pub fn with_water(water: f64, hi: f64) -> Self {
        Self {
            lo: water,
            hi,
            at_lo: 1,
            points: 1,
        }
    }

    /// Takes one more height into the range.
    pub fn add(&mut self, h: f32) {
        let h = f64::from(h);
        if h < self.lo {
            (self.lo, self.at_lo) = (h, 0);
        }
        if h == self.lo {
            self.at_lo += 1;
        }
        self.hi = self.hi.max(h);
        self.points += 1;
    }

    /// The water level, if the map has water.
    pub fn water(&self) -> Option<f64> {
        (self.at_lo as f64 >= Self::WATER_SHARE * self.points as f64).then_some(self.lo)
    }

    fn span(&self) -> f64 {
        (self.hi - self.lo).max(1e-6)
    }

    fn sand(&self) -> f64 {
        Self::SAND_VOXELS.min(self.span() / 50.0)
    }
}

/// The color of one grid point at `at` (voxels) of height `h`, with height
/// gradient `[gx, gy]` (per voxel), on terrain of height `bands`, with
/// per-voxel texture `grain` (−0.5 to 0.5; 0 for a coarse level, where it
/// averages out).
pub(crate) fn terrain_color(
    at: [f64; 2],
    h: f64,
    [gx, gy]: [f64; 2],
    bands: HeightBands,
    grain: f64,
    seed: u64,
) -> Rgb {
    let (lo, span) = (bands.lo, bands.span());
    let water = bands.water();
    let is_water = water.is_some_and(|w| h <= w + 0.01);
    let is_sand = water.is_some_and(|w| h < w + bands.sand());
    let sun = normalize([-0.5, -0.35, 0.8]);
    let slope = (gx * gx + gy * gy).sqrt();
    let normal = normalize([-gx, -gy, 1.0]);
    let light = 0.5 + 0.6 * dot(normal, sun).max(0.0);
    let rel = (h - lo) / span;
    let patch = fbm(at[0] / 40.0, at[1] / 40.0, seed ^ 0xf00d, 4, 0.55);
    let base: [f64; 3] = if is_water {
        let depth_tint = 0.8 + 0.4 * patch;
        [40.0 * depth_tint, 80.0 * depth_tint, 110.0 * depth_tint]
    } else if is_sand {
        [196.0, 180.0, 130.0]
    } else if slope > 1.3 || (rel > 0.62 && slope > 0.6) {
        [120.0 + 30.0 * patch, 108.0 + 20.0 * patch, 96.0]
    } else if rel > 0.8 {
        [235.0, 238.0, 242.0]
    } else if patch > 0.55 {
        [44.0, 78.0 + 20.0 * patch, 36.0]
    } else {
        [92.0 + 40.0 * patch, 128.0 + 30.0 * patch, 58.0]
    };
    let shade = if is_water { 1.0 } else { light };
    base.map(|c| (c * shade * (1.0 + 0.18 * grain)).round().clamp(0.0, 255.0) as u8)
}

fn hash(x: i64, y: i64, seed: u64) -> f64 {
    let mut h = seed
        ^ (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 29;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

pub(crate) fn value_noise(x: f64, y: f64, seed: u64) -> f64 {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (ix, iy) = (x0 as i64, y0 as i64);
    let (u, v) = (quintic(fx), quintic(fy));
    let a = hash(ix, iy, seed);
    let b = hash(ix + 1, iy, seed);
    let c = hash(ix, iy + 1, seed);
    let d = hash(ix + 1, iy + 1, seed);
    (a * (1.0 - u) + b * u) * (1.0 - v) + (c * (1.0 - u) + d * u) * v
}

pub(crate) fn fbm(x: f64, y: f64, seed: u64, octaves: u32, gain: f64) -> f64 {
    let (mut sum, mut amp, mut freq, mut norm) = (0.0, 1.0, 1.0, 0.0);
    for o in 0..octaves {
        sum += amp * value_noise(x * freq, y * freq, seed.wrapping_add(u64::from(o) * 7919));
        norm += amp;
        amp *= gain;
        freq *= 2.03;
    }
    sum / norm
}

fn ridged(x: f64, y: f64, seed: u64, octaves: u32) -> f64 {
    let (mut sum, mut amp, mut freq, mut norm, mut weight) = (0.0, 1.0, 1.0, 0.0, 1.0);
    for o in 0..octaves {
        let n = 1.0
            - (2.0
                * value_noise(
                    x * freq,
                    y * freq,
                    seed.wrapping_add(u64::from(o) * 104_729),
                )
                - 1.0)
                .abs();
        let r = n * n * weight;
        weight = (r * 1.5).clamp(0.0, 1.0);
        sum += amp * r;
        norm += amp;
        amp *= 0.5;
        freq *= 2.1;
    }
    sum / norm
}

fn quintic(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let l = dot(v, v).sqrt();
    v.map(|c| c / l)
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_deterministic_and_in_kernel_range() {
        let a = procedural(64, 7);
        let b = procedural(64, 7);
        assert_eq!(a.heights, b.heights);
        assert_eq!(a.colors, b.colors);
        assert_ne!(a.heights, procedural(64, 8).heights);
        assert!(a.heights.iter().all(|&h| (0.0..=400.0).contains(&h)));
        assert!(a.to_kernel().is_ok());
    }
}
