//! The terrain: borrowed height and color slices of one grid.

use crate::color::Rgb;
use crate::config::{HEIGHT_FRAC_BITS, MAX_MAP_SIDE};
use crate::surface::{Extent, Grid};
use core::fmt;

/// A height field with a color per grid point, borrowed from the caller.
///
/// Grid point `(x, y)` is element `y * width + x` of both slices. Heights are
/// unsigned U12.4 fixed point (see [`Terrain::quantize_height`]).
#[derive(Debug, Clone, Copy)]
pub struct Terrain<'a> {
    heights: &'a [u16],
    colors: &'a [Rgb],
    width: u32,
    depth: u32,
    max_height: u16,
}

/// Why a terrain was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TerrainError {
    /// A side is smaller than 2 grid points: there is no surface to sample.
    TooSmall,
    /// A side is larger than [`MAX_MAP_SIDE`].
    TooLarge,
    /// The height slice is not `width * depth` long.
    HeightsLength,
    /// The color slice is not `width * depth` long.
    ColorsLength,
}

impl fmt::Display for TerrainError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::TooSmall => "terrain must be at least 2 x 2 grid points",
            Self::TooLarge => "terrain side exceeds the kernel's largest map side (32767)",
            Self::HeightsLength => "height slice length is not width x depth",
            Self::ColorsLength => "color slice length is not width x depth",
        })
    }
}

impl core::error::Error for TerrainError {}

impl<'a> Terrain<'a> {
    /// Checks the dimensions once; past this, every access is in range or
    /// handled without a panic.
    pub fn new(
        width: u32,
        depth: u32,
        heights: &'a [u16],
        colors: &'a [Rgb],
    ) -> Result<Self, TerrainError> {
        if width < 2 || depth < 2 {
            return Err(TerrainError::TooSmall);
        }
        if width > MAX_MAP_SIDE || depth > MAX_MAP_SIDE {
            return Err(TerrainError::TooLarge);
        }
        let cells = width as usize * depth as usize;
        if heights.len() != cells {
            return Err(TerrainError::HeightsLength);
        }
        if colors.len() != cells {
            return Err(TerrainError::ColorsLength);
        }
        let max_height = heights.iter().copied().max().unwrap_or(0);
        Ok(Self::with_bounds(width, depth, heights, colors, max_height))
    }

    /// A terrain whose highest height is already known (checked by
    /// [`Terrain::new`], or a pyramid level, bounded by the level below:
    /// see [`crate::Pyramid::new`]).
    pub(crate) fn with_bounds(
        width: u32,
        depth: u32,
        heights: &'a [u16],
        colors: &'a [Rgb],
        max_height: u16,
    ) -> Self {
        Self {
            heights,
            colors,
            width,
            depth,
            max_height,
        }
    }

    /// Converts a height in voxels to the stored U12.4 form, rounding to the
    /// nearest 1/16. `None` for NaN, negative heights and heights above
    /// [`Terrain::MAX_HEIGHT`].
    pub fn quantize_height(height: f32) -> Option<u16> {
        let scaled = height * (1u32 << HEIGHT_FRAC_BITS) as f32;
        if scaled.is_nan() || !(0.0..=u16::MAX as f32).contains(&scaled) {
            return None;
        }
        Some((scaled + 0.5) as u16)
    }

    /// The highest height the kernel can store, in voxels.
    pub const MAX_HEIGHT: f32 = u16::MAX as f32 / (1u32 << HEIGHT_FRAC_BITS) as f32;

    /// Grid points along x.
    #[inline]
    pub fn width(&self) -> u32 {
        self.width
    }
    /// Grid points along y.
    #[inline]
    pub fn depth(&self) -> u32 {
        self.depth
    }
    /// The stored heights (U12.4).
    #[inline]
    pub fn heights(&self) -> &'a [u16] {
        self.heights
    }
    /// The colors.
    #[inline]
    pub fn colors(&self) -> &'a [Rgb] {
        self.colors
    }
    /// The highest stored height (U12.4): rays above it can no longer hit.
    #[inline]
    pub fn max_height(&self) -> u16 {
        self.max_height
    }
    /// The size and highest height, for clipping rays.
    #[inline]
    pub fn extent(&self) -> Extent {
        Extent {
            width: self.width,
            depth: self.depth,
            max_height: self.max_height,
            real_edges: true,
        }
    }
    /// Bytes of terrain this view of the data covers (heights and colors).
    pub fn bytes(&self) -> usize {
        core::mem::size_of_val(self.heights) + core::mem::size_of_val(self.colors)
    }
}

impl Grid for Terrain<'_> {
    #[inline(always)]
    fn stride(&self) -> isize {
        self.width as isize
    }
    #[inline(always)]
    fn height(&self, index: isize) -> Option<u16> {
        self.heights.get(index as usize).copied()
    }
    #[inline(always)]
    fn color(&self, index: isize) -> Option<Rgb> {
        self.colors.get(index as usize).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_dimensions() {
        let h = [0u16; 4];
        let c = [[0u8; 3]; 4];
        assert_eq!(
            Terrain::new(1, 4, &h, &c).unwrap_err(),
            TerrainError::TooSmall
        );
        assert_eq!(
            Terrain::new(2, 3, &h, &c).unwrap_err(),
            TerrainError::HeightsLength
        );
        assert_eq!(
            Terrain::new(2, 2, &h, &c[..3]).unwrap_err(),
            TerrainError::ColorsLength
        );
        assert_eq!(
            Terrain::new(40_000, 2, &h, &c).unwrap_err(),
            TerrainError::TooLarge
        );
        assert!(Terrain::new(2, 2, &h, &c).is_ok());
    }

    #[test]
    fn quantizes_heights_to_sixteenths() {
        assert_eq!(Terrain::quantize_height(0.0), Some(0));
        assert_eq!(Terrain::quantize_height(1.5), Some(24));
        assert_eq!(
            Terrain::quantize_height(Terrain::MAX_HEIGHT),
            Some(u16::MAX)
        );
        assert_eq!(Terrain::quantize_height(4096.0), None);
        assert_eq!(Terrain::quantize_height(-0.5), None);
        assert_eq!(Terrain::quantize_height(f32::NAN), None);
    }
}
