//! A procedural tile source for terrains far larger than any disk: every
//! tile of every level is computed from its coordinates alone.
//!
//! Heights are fractal value noise: octaves of wavelength 16384 down to
//! 4 voxels, amplitudes falling by 0.66 an octave (about 2960 voxels in all).
//! Level `l` keeps the octaves of wavelength `4·2^l` and up: the finer ones
//! average out over its `2^l`-voxel spacing, as the pyramid's filter would
//! make them. Its bounds add to the highest corner what the kept octaves
//! can rise within a cell (value noise with quintic steps rises at most
//! 1.875 a wavelength) and the whole amplitude of the dropped ones, so a
//! skip over them never misses a finer level's surface.

use super::TILE;
use crate::error::{Error, Result};
use crate::scene::{terrain_color, value_noise, HeightBands, WATER_LEVEL};
use terracast::tiles::{Tile, TileError, TileKey, TileSource, World};

const OCTAVES: usize = 13;
const LONGEST: f64 = 16_384.0;
const FIRST_AMPLITUDE: f64 = 1000.0;
const GAIN: f64 = 0.66;

/// Tiles of a fractal terrain `side` voxels a side, made on demand.
#[derive(Debug, Clone)]
pub struct ProceduralSource {
    world: World,
    seed: u64,
}

impl ProceduralSource {
    /// A `side` × `side` terrain (2 to 2^30 points a side).
    pub fn new(side: u32, seed: u64) -> Result<Self> {
        let total: f64 = (0..OCTAVES).map(amplitude).sum();
        let max_height = terracast::Terrain::quantize_height((WATER_LEVEL + total) as f32)
            .ok_or_else(|| Error::new("procedural terrain too high for the kernel"))?;
        let world = World::new(side, side, max_height).ok_or_else(|| {
            Error::new(format!(
                "procedural:{side}: SIZE must be between 2 and {} voxels",
                World::MAX_SIDE
            ))
        })?;
        Ok(Self { world, seed })
    }

    /// Terrain bytes it stands for at 4 bytes a voxel, as Cohen-Or counted.
    pub fn virtual_bytes(&self) -> u64 {
        u64::from(self.world.width) * u64::from(self.world.depth) * 4
    }

    /// Octaves level `level` keeps.
    fn kept(level: u8) -> usize {
        let spacing = f64::from(1u32 << level.min(30));
        (0..OCTAVES)
            .take_while(|&o| wavelength(o) >= 4.0 * spacing)
            .count()
    }

    /// Height at world point `(x, y)` with the first `octaves` octaves.
    fn height(&self, x: f64, y: f64, octaves: usize) -> f64 {
        let mut h = WATER_LEVEL;
        for o in 0..octaves {
            let lambda = wavelength(o);
            let seed = self.seed.wrapping_add(o as u64 * 7919);
            h += amplitude(o) * value_noise(x / lambda, y / lambda, seed);
        }
        h
    }
}

fn wavelength(octave: usize) -> f64 {
    LONGEST / f64::from(1u32 << octave)
}

fn amplitude(octave: usize) -> f64 {
    FIRST_AMPLITUDE * GAIN.powi(octave as i32)
}

impl TileSource<TILE> for ProceduralSource {
    fn world(&self) -> World {
        self.world
    }

    fn load(
        &mut self,
        key: TileKey,
        tile: &mut Tile<TILE>,
    ) -> std::result::Result<usize, TileError> {
        if !self.world.contains(key, TILE as u32) {
            return Err(TileError::Missing);
        }
        let spacing = f64::from(1u32 << key.level.min(30));
        let octaves = Self::kept(key.level);
        let (size_x, size_y) = self.world.level_size(key.level);
        // Heights on the tile's points and one ring around (for slopes and
        // the last cells' far corners).
        const SIDE: usize = TILE + 2;
        let mut grid = vec![0.0f64; SIDE * SIDE];
        let (x0, y0) = (
            i64::from(key.x) * TILE as i64 - 1,
            i64::from(key.y) * TILE as i64 - 1,
        );
        for j in 0..SIDE {
            for i in 0..SIDE {
                // Points past the level's edge repeat the edge, as the
                // pyramid's do.
                let px = (x0 + i as i64).clamp(0, i64::from(size_x) - 1) as f64;
                let py = (y0 + j as i64).clamp(0, i64::from(size_y) - 1) as f64;
                grid[j * SIDE + i] = self.height(px * spacing, py * spacing, octaves);
            }
        }
        let dropped: f64 = (octaves..OCTAVES).map(amplitude).sum();
        let rise: f64 = (0..octaves)
            .map(|o| amplitude(o) * (1.875 * spacing / wavelength(o)).min(1.0))
            .sum();
        let range = HeightBands::with_water(WATER_LEVEL, f64::from(self.world.max_height) / 16.0);
        let quantize = |h: f64| (h * 16.0).round().clamp(0.0, f64::from(u16::MAX)) as u16;
        for j in 0..TILE {
            for i in 0..TILE {
                // Point (i + di, j + dj) of the tile, di and dj in -1..=1.
                let at = |di: usize, dj: usize| grid[(j + dj) * SIDE + i + di];
                let h = at(1, 1);
                let gx = (at(2, 1) - at(0, 1)) / (2.0 * spacing);
                let gy = (at(1, 2) - at(1, 0)) / (2.0 * spacing);
                let (wx, wy) = (
                    (x0 + 1 + i as i64) as f64 * spacing,
                    (y0 + 1 + j as i64) as f64 * spacing,
                );
                let grain = if key.level == 0 {
                    value_noise(wx * 0.5, wy * 0.5, self.seed ^ 0xabc) - 0.5
                } else {
                    0.0
                };
                tile.heights[j][i] = quantize(h);
                tile.colors[j][i] = terrain_color([wx, wy], h, [gx, gy], range, grain, self.seed);
                let corners = h.max(at(2, 1)).max(at(1, 2)).max(at(2, 2));
                tile.bounds[j][i] = if key.level == 0 {
                    0
                } else {
                    // Rounded up: a bound is never below what it bounds.
                    ((corners + rise + dropped) * 16.0)
                        .ceil()
                        .min(f64::from(u16::MAX)) as u16
                };
            }
        }
        Ok(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_are_deterministic_and_bounds_cover_the_finer_levels() {
        let mut source = ProceduralSource::new(131_072, 7).unwrap();
        assert_eq!(source.virtual_bytes(), 64 << 30);
        let mut a = Box::new(Tile::<TILE>::EMPTY);
        let mut b = Box::new(Tile::<TILE>::EMPTY);
        let key = TileKey {
            level: 3,
            x: 100,
            y: 57,
        };
        source.load(key, &mut a).unwrap();
        source.load(key, &mut b).unwrap();
        assert_eq!(a, b);
        // Every level-0 and level-2 point under a level-3 cell is below
        // its bound.
        let mut fine = Box::new(Tile::<TILE>::EMPTY);
        for level in [0u8, 2] {
            let scale = 1u32 << (3 - level);
            // The fine tile under the coarse tile's cells (0..8, 0..8).
            let fine_key = TileKey {
                level,
                x: key.x * scale,
                y: key.y * scale,
            };
            source.load(fine_key, &mut fine).unwrap();
            for cj in 0..8 {
                for ci in 0..8 {
                    let bound = a.bounds[cj][ci];
                    for j in cj * scale as usize..=((cj + 1) * scale as usize).min(TILE - 1) {
                        for i in ci * scale as usize..=((ci + 1) * scale as usize).min(TILE - 1) {
                            assert!(fine.heights[j][i] <= bound, "level {level} ({i}, {j})");
                        }
                    }
                }
            }
        }
        assert!(source.world().max_height > 16 * 1000);
        assert!(ProceduralSource::new(1, 7).is_err());
    }
}
