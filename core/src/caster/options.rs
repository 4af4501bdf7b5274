//! What a render may be asked to do: the settings of [`super::render`].

use crate::config::DEFAULT_SKY;
use crate::roughness::terrain_fit;
use crate::Rgb;
use fixed::types::U8F8;

/// How each ray of an image line may use the ray before it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coherence {
    /// Every ray is cast from the eye: the slow baseline.
    Off,
    /// A ray starts where the ray before it hit when both step on the same
    /// levels (always at single resolution): the image equals
    /// [`Coherence::Off`]'s bit for bit. On the pyramid the rays of a line
    /// switch levels at different samples, so under pitch most are cast
    /// from the eye.
    Exact,
    /// The line caster's (`caster/line_caster.rs`), with one ray a pixel
    /// (either shading): the rays of a stretch of a line share one
    /// level schedule, its least ray's, so every ray resumes where the ray
    /// before it hit; a ray switches levels up to a quarter nearer than
    /// its own depth says, and a new stretch starts where the stretch
    /// before left off, whose surface may differ from this one's by a
    /// level (the bound measured in the coherence tests). With more rays
    /// a pixel: as [`Coherence::Exact`], and across
    /// different level schedules too. At single resolution, the image of
    /// [`Coherence::Exact`] bit for bit.
    AcrossLevels,
}

impl Coherence {
    /// The default: [`Coherence::AcrossLevels`].
    pub const DEFAULT: Self = Self::AcrossLevels;
}

/// Which levels of the pyramid the caster steps on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resolution {
    /// Level 0 only, however far the ray goes (the baseline that aliases
    /// in the distance and costs more the farther it sees).
    Single,
    /// Every level the pyramid has (Cohen-Or §2): a ray moves up a level,
    /// at an even step, where a voxel of its level gets narrower than
    /// `1 / pixel_to_voxel` pixels, and blends the colors of adjacent
    /// levels by depth so the switch is invisible. A higher ratio
    /// switches sooner: fewer steps, a blurrier far field. With
    /// [`RenderOptions::terrain_fit`] the ratio is scaled down on rugged
    /// terrain first.
    Multi {
        /// The pixel-to-voxel ratio (1 = switch where a voxel is one pixel
        /// wide).
        pixel_to_voxel: U8F8,
    },
}

impl Resolution {
    /// [`Resolution::Multi`] at a pixel-to-voxel ratio of 1.
    pub const DEFAULT: Self = Self::Multi {
        pixel_to_voxel: U8F8::ONE,
    };
}

/// How many rays each pixel gets, spread along its image line (Cohen-Or
/// §2.1: at shallow pitch a pixel's footprint is long and thin, and one ray
/// undersamples it). They share the line's coherence, so they add rays, not
/// voxels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VerticalSamples {
    /// One ray through the pixel center.
    One,
    /// Two rays a half pixel apart.
    Two,
    /// Four rays.
    Four,
    /// Eight rays.
    Eight,
}

impl VerticalSamples {
    /// Rays per pixel.
    pub fn count(self) -> u32 {
        1 << self.log2()
    }
    pub(crate) fn log2(self) -> u32 {
        match self {
            Self::One => 0,
            Self::Two => 1,
            Self::Four => 2,
            Self::Eight => 3,
        }
    }
}

/// How a hit is colored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shading {
    /// The two voxels across the grid line blended by the fraction of the
    /// minor coordinate (a shift and a mask), on the grid lines before and
    /// after the crossing, blended by where it lies; past the color reach,
    /// bilinear on the two levels the pixel's footprint brackets, blended
    /// by depth (the soft transition; see `footprint_color`).
    Subvoxel,
    /// The voxel nearest the hit sample, on its level: no blend. Cheaper
    /// and blockier: the baseline the subvoxel weights are measured
    /// against.
    Nearest,
    /// As [`Shading::Subvoxel`], but a hit on level 0 takes level 0's
    /// colors at any depth: no footprint colors past the color reach (a
    /// hit on a coarse height level still takes its level's). The
    /// baseline the footprint colors are measured against: far terrain
    /// aliases, and the host saves their bilinear squares.
    LevelZero,
}

/// Where a ray of the line caster reads the terrain's heights.
///
/// A line's rays share one vertical plane, the image of its pixel line,
/// and a pixel's center lies up to half a pixel beside the line (under
/// pitch or roll). Its colors are always looked up where its own ray
/// crosses (the line's minor coordinate moved by the
/// ray's drift times its distance); its heights, by this.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeightPath {
    /// On the line's plane: every ray of a line steps on the same
    /// heights, so a ray resumes exactly where the ray below it hit
    /// (Cohen-Or's vertical coherence), and at single resolution the
    /// image is [`Coherence::Exact`]'s bit for bit.
    Line,
    /// On the ray's own path: each height fetch is moved across the line
    /// by the ray's drift (in full, where the colors' is bounded) times its
    /// distance, stepped with the walk (an add a step), and a ray that
    /// resumes where the ray below it hit reads that sample and the one
    /// before it again on its own path. A silhouette then lies where the
    /// pixel's own ray sees it, not up to half a pixel aside; the price is
    /// exactness of the coherence (a resumed ray takes it that it clears
    /// the surface before that sample, as the ray below did on its path),
    /// two fetches a resumed ray and a few instructions a step. The line
    /// caster's only ([`Coherence::AcrossLevels`] with one ray a pixel);
    /// the per-ray settings walk the line's plane.
    Ray,
}

impl HeightPath {
    /// The default: [`HeightPath::Line`].
    pub const DEFAULT: Self = Self::Line;
}

/// Settings of the caster.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderOptions {
    /// Vertical ray coherence: each ray resumes where the ray before it on
    /// its image line hit.
    pub coherence: Coherence,
    /// Single resolution or the pyramid's levels.
    pub resolution: Resolution,
    /// Rays cast from the eye (the first of each image line, and any ray that
    /// cannot resume) skip through the pyramid's height bounds.
    pub hierarchical_first_hit: bool,
    /// Rays per pixel, spread along the pixel's image line.
    pub vertical_samples: VerticalSamples,
    /// How hits are colored.
    pub shading: Shading,
    /// On the pyramid, scale the pixel-to-voxel ratio the height levels
    /// switch by down by the terrain's roughness
    /// ([`crate::roughness::terrain_fit`]), so that a coarse level's
    /// silhouettes are within an eighth of a pixel (RMS) where it begins. Colors
    /// switch by the ratio as given. No effect on smooth maps, nor on surfaces whose roughness
    /// is unknown.
    pub terrain_fit: bool,
    /// Where the line caster's rays read heights.
    pub height_path: HeightPath,
    /// Color of rays that leave the terrain.
    pub sky: Rgb,
}

impl RenderOptions {
    /// The pixel-to-voxel ratio the caster switches levels by on a surface
    /// of `roughness` ([`crate::Surface::roughness`]): the one set, scaled
    /// by the terrain fit when it is on; 1 at single resolution. A tile
    /// footprint ([`crate::tiles::FootprintView`]) takes this one.
    pub fn level_bias(&self, roughness: u8) -> f32 {
        match self.resolution {
            Resolution::Single => 1.0,
            Resolution::Multi { pixel_to_voxel } => {
                pixel_to_voxel.to_num::<f32>() * self.fit_for(roughness) as f32 / 65536.0
            }
        }
    }

    /// The factor (Q16, at most 1) the ratio is scaled by on a surface of
    /// `roughness`: [`crate::roughness::terrain_fit`] when the fit is on
    /// and the pyramid in use, else 1.
    pub fn fit_for(&self, roughness: u8) -> u32 {
        match self.resolution {
            Resolution::Multi { .. } if self.terrain_fit => terrain_fit(roughness),
            _ => 1 << 16,
        }
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            coherence: Coherence::DEFAULT,
            resolution: Resolution::DEFAULT,
            hierarchical_first_hit: true,
            vertical_samples: VerticalSamples::One,
            shading: Shading::Subvoxel,
            terrain_fit: true,
            height_path: HeightPath::DEFAULT,
            sky: DEFAULT_SKY,
        }
    }
}
