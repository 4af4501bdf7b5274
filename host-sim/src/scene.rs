//! Terrain on the host: loaded from files or generated, in world units.
//!
//! A [`Scene`] keeps heights as `f32` voxels (value × height scale) for the
//! exact reference, and converts them once to the kernel's U12.4 form.

mod load;
mod procedural;

pub use load::{load_colors, load_heights};
pub use procedural::{color_by_height_and_slope, procedural};

use crate::error::{Error, Result};
use terracast::{Rgb, Terrain};

/// A height field and its colors, one per grid point, row-major.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Grid points along x.
    pub width: u32,
    /// Grid points along y.
    pub depth: u32,
    /// Height of each grid point in voxels.
    pub heights: Vec<f32>,
    /// Color of each grid point.
    pub colors: Vec<Rgb>,
}

/// A scene in the kernel's storage format; lends a [`Terrain`].
#[derive(Debug, Clone)]
pub struct KernelScene {
    width: u32,
    depth: u32,
    heights: Vec<u16>,
    colors: Vec<Rgb>,
}

/// Loads a height map and its color map (colored by height and slope when
/// `color` is `None`) into a checked scene.
pub fn load_pair(
    height: &std::path::Path,
    color: Option<&std::path::Path>,
    scale: f32,
    seed: u64,
) -> Result<Scene> {
    let (w, d, heights) = load_heights(height, scale)?;
    let colors = match color {
        Some(c) => load_colors(c, w, d)?,
        None => color_by_height_and_slope(w, d, &heights, seed),
    };
    Scene::new(w, d, heights, colors)
}

impl Scene {
    /// Checks that the sizes agree and every height is finite.
    pub fn new(width: u32, depth: u32, heights: Vec<f32>, colors: Vec<Rgb>) -> Result<Self> {
        let cells = width as usize * depth as usize;
        if width < 2 || depth < 2 {
            return Err(Error::new(format!(
                "terrain is {width}x{depth}: it needs at least 2x2 grid points"
            )));
        }
        if heights.len() != cells || colors.len() != cells {
            return Err(Error::new("height and color grids differ in size"));
        }
        if let Some(i) = heights.iter().position(|h| !h.is_finite()) {
            return Err(Error::new(format!(
                "height at grid point ({}, {}) is not a finite number",
                i % width as usize,
                i / width as usize
            )));
        }
        Ok(Self {
            width,
            depth,
            heights,
            colors,
        })
    }

    /// Height of grid point (x, y).
    pub fn height(&self, x: usize, y: usize) -> f32 {
        self.heights[y * self.width as usize + x]
    }

    /// Highest height in voxels.
    pub fn max_height(&self) -> f32 {
        self.heights.iter().copied().fold(f32::MIN, f32::max)
    }

    /// Converts to the kernel's format: heights rounded to 1/16 voxel.
    pub fn to_kernel(&self) -> Result<KernelScene> {
        let heights = self
            .heights
            .iter()
            .enumerate()
            .map(|(i, &h)| {
                Terrain::quantize_height(h).ok_or_else(|| {
                    Error::new(format!(
                        "height {h} at grid point ({}, {}) is outside the kernel's range 0..={} voxels (adjust --height-scale)",
                        i % self.width as usize,
                        i / self.width as usize,
                        Terrain::MAX_HEIGHT
                    ))
                })
            })
            .collect::<Result<Vec<u16>>>()?;
        let scene = KernelScene {
            width: self.width,
            depth: self.depth,
            heights,
            colors: self.colors.clone(),
        };
        scene.terrain()?;
        Ok(scene)
    }
}

impl KernelScene {
    /// The kernel's borrowed view of this scene.
    pub fn terrain(&self) -> Result<Terrain<'_>> {
        Terrain::new(self.width, self.depth, &self.heights, &self.colors)
            .map_err(|e| Error::new(format!("terrain rejected by the kernel: {e}")))
    }
}
