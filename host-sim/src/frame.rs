//! A rendered image with its per-pixel depth and the render's statistics.

use terracast::{Rgb, MAX_LEVELS};

/// An image and the Euclidean depth of each pixel's center ray.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major colors, y = 0 at the top.
    pub colors: Vec<Rgb>,
    /// Row-major distances from the eye in voxels; +inf where the ray saw sky.
    pub depth: Vec<f32>,
}

impl Frame {
    /// A black frame with infinite depth.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            colors: vec![[0; 3]; n],
            depth: vec![f32::INFINITY; n],
        }
    }

    /// Pixels whose ray saw sky.
    pub fn sky_pixels(&self) -> usize {
        self.depth.iter().filter(|d| d.is_infinite()).count()
    }
}

/// What only a kernel render counts: steps and hits per pyramid level,
/// first-hit bound tests, and color fetches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LevelStats {
    /// Levels the pyramid had (entries past it are zero).
    pub levels: usize,
    /// Walk steps on each level.
    pub steps: [u64; MAX_LEVELS],
    /// Rays that hit on each level.
    pub hits: [u64; MAX_LEVELS],
    /// First-hit bound tests (counted in the render's steps too).
    pub bound_tests: u64,
    /// Color fetches of the shading (a terrain ray makes one or two; the
    /// board's cost fit charges each).
    pub color_fetches: u64,
    /// Secondary rays cast through see-through texels (complex sticks).
    pub secondary_rays: u64,
    /// The surface's roughness (`terracast::roughness`, 1/64 units).
    pub roughness: u8,
    /// The factor the terrain fit scaled the pixel-to-voxel ratio by, Q16
    /// (1 when it was off, or at single resolution).
    pub terrain_fit: u32,
    /// A frame rendered within a budget (`render --budget`): what the
    /// governor did.
    pub governed: Option<terracast::FrameCost>,
}

/// What a render cost, for `--stats`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderStats {
    /// Renderer name.
    pub method: &'static str,
    /// Pixels rendered.
    pub pixels: u64,
    /// Rays cast.
    pub rays: u64,
    /// Voxel visits of the traversal (for the reference: mipmap nodes).
    pub steps: u64,
    /// Terrain bytes the renderer held for the frame.
    pub resident_bytes: u64,
    /// Time of the render call alone.
    pub render_ns: u64,
    /// Kernel renders: steps and hits by pyramid level.
    pub levels: Option<LevelStats>,
}
