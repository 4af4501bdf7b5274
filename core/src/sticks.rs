//! 3D objects on the terrain as sticks (Cohen-Or §2): runs of voxels
//! standing on the terrain at grid points, colored by a texture up their
//! height.
//!
//! A stick raises the height field at its grid point: the terrain's
//! heights a caster steps on are the sticks' tops, so a ray meets a stick
//! as it meets the terrain, vertical ray coherence stays exact (a point's
//! column is solid from the ground to its top) and the pyramid, its height
//! bounds and the first hit see objects with no change. What a stick
//! changes is the color: a ray that hits it "climbs onto the stick and
//! maps back the stick texture", the texel at the height where the ray
//! crosses the surface.
//!
//! A [`StickLayer`] holds, in caller storage, an index a grid point of
//! level 0 (0 for plain terrain) into a shared table of [`Stick`]s, and
//! their texels: replicated objects (the trees of a wood) share sticks. A
//! stick's base is its point's height less its own: it stands on the
//! terrain wherever it is placed. [`WithSticks`] lends a surface with the
//! layer on its level 0 to the caster. A tiled terrain keeps its points'
//! values in its level-0 tiles and lends the [`StickTable`] alone
//! ([`crate::tiles::TiledSurface::with_sticks`]).
//!
//! A **uniform** stick is one texel (one color at every height, as a
//! terrain voxel); a **textured** stick has a texel a voxel of its height,
//! bottom up. Coarser levels take the colors the pyramid filtered from
//! level 0's, where a stick's point holds its top texel.
//!
//! ```
//! use terracast::{render, Camera, Framebuffer, NoProbe, Pyramid, RenderOptions, Stick, StickLayer, Terrain, View, WithSticks};
//!
//! // A flat 8 x 8 map with a stick 4 voxels tall at point (4, 4): red at
//! // the bottom, white above. The height there is the stick's top.
//! let mut heights = [16u16; 64];
//! heights[4 * 8 + 4] = 16 + 4 * 16;
//! let colors = [[0, 120, 0]; 64];
//! let terrain = Terrain::new(8, 8, &heights, &colors)?;
//! let mut points = [0u16; 64];
//! points[4 * 8 + 4] = 1;
//! let sticks = [Stick { first: 0, texels: 4, height: 4 * 16 }];
//! let texels = [[200, 0, 0], [200, 0, 0], [255, 255, 255], [255, 255, 255]];
//! let layer = StickLayer::new(&terrain, &points, &sticks, &texels)?;
//!
//! let pyramid = Pyramid::flat(terrain);
//! let surface = WithSticks::new(&pyramid, layer);
//! let view = View::new(&Camera::looking([0.5, 4.0, 2.0], 0.0, 0.0), 16, 12)?;
//! let mut pixels = [[0u8; 3]; 16 * 12];
//! render(&surface, &view, &RenderOptions::default(), &mut Framebuffer::new(&mut pixels, 16, 12)?, &mut NoProbe);
//! assert!(pixels.iter().any(|&c| c[0] > 150 && c[1] < 100)); // the red foot shows
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

use crate::color::Rgb;
use crate::config::{COORD_FRAC_BITS, HEIGHT_FRAC_BITS};
use crate::pyramid::{level_count, level_side, MAX_LEVELS};
use crate::surface::{Grid, Surface};
use crate::terrain::Terrain;
use core::fmt;

/// Heights are U12.4; a ray's height is Q16.
const HEIGHT_TO_Q16: u32 = COORD_FRAC_BITS - HEIGHT_FRAC_BITS;

/// One stick of a [`StickLayer`]'s table.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stick {
    /// Its texels are the layer's `texels[first..first + texels]`, bottom
    /// up, one a voxel of height (the last one also above that).
    pub first: u32,
    /// How many: 1 for a uniform stick.
    pub texels: u16,
    /// Its height above its base, U12.4 like the terrain's.
    pub height: u16,
}

impl Stick {
    /// Whether it is **complex**: a texel of it less than opaque in
    /// `alphas` (one a texel of its table, or none: every texel opaque).
    pub fn is_complex(&self, alphas: &[u8]) -> bool {
        let first = self.first as usize;
        alphas
            .get(first..first + usize::from(self.texels))
            .is_some_and(|a| a.iter().any(|&a| a < u8::MAX))
    }

    /// Where in the texel table its texel at height `z` (Q16) lies, on a
    /// point whose height is `top` (U12.4): the voxels above its base,
    /// within its texels.
    #[inline(always)]
    fn texel_at(&self, top: u16, z: i32) -> usize {
        let base = i32::from(top - self.height.min(top)) << HEIGHT_TO_Q16;
        // As compares: `i32::clamp` is a call on the board.
        let texel = (z.saturating_sub(base) >> COORD_FRAC_BITS)
            .min(i32::from(self.texels) - 1)
            .max(0);
        self.first as usize + texel as usize
    }
}

/// Why a [`StickLayer`] cannot be made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StickError {
    /// The points are not one a grid point of the terrain.
    PointsLength,
    /// A point's index is past the stick table.
    UnknownStick {
        /// The grid point.
        point: usize,
    },
    /// A stick has no texels, or texels past the texel table.
    Texels {
        /// The stick (its index in the table).
        stick: usize,
    },
    /// A stick is taller than the height of its point.
    BelowGround {
        /// The grid point.
        point: usize,
    },
    /// The opacities are neither none nor one a texel.
    AlphasLength,
}

impl fmt::Display for StickError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::PointsLength => f.write_str("stick points must be one a grid point of the terrain"),
            Self::UnknownStick { point } => {
                write!(f, "grid point {point} names a stick past the stick table")
            }
            Self::Texels { stick } => {
                write!(f, "stick {stick} has no texels or texels past the texel table")
            }
            Self::BelowGround { point } => write!(
                f,
                "the stick at grid point {point} is taller than the height there (its base would be below 0)"
            ),
            Self::AlphasLength => {
                f.write_str("stick texel opacities must be none or one a texel")
            }
        }
    }
}

impl core::error::Error for StickError {}

/// The sticks of a [`StickLayer`] (or of a tiled terrain's level-0 tiles,
/// [`crate::tiles::TiledSurface::with_sticks`]) and their texels, shared
/// by every grid point that holds one: point value `i` names
/// `sticks[i − 1]`, 0 plain terrain. Checked when it is made: every
/// stick's texels lie inside the texel table.
#[derive(Debug, Clone, Copy)]
pub struct StickTable<'a> {
    sticks: &'a [Stick],
    texels: &'a [Rgb],
    /// Each texel's opacity (255 opaque), or none: every texel opaque.
    alphas: &'a [u8],
    /// The smallest point value whose stick is complex (a texel less than
    /// opaque): a point below it shows only opaque texels
    /// ([`StickTable::first_complex`]).
    first_complex: u16,
}

impl<'a> StickTable<'a> {
    /// No sticks.
    pub const EMPTY: StickTable<'static> = StickTable {
        sticks: &[],
        texels: &[],
        alphas: &[],
        first_complex: u16::MAX,
    };

    /// The table of `sticks` and their `texels`.
    pub fn new(sticks: &'a [Stick], texels: &'a [Rgb]) -> Result<Self, StickError> {
        for (stick, s) in sticks.iter().enumerate() {
            let end = s.first as usize + usize::from(s.texels);
            if s.texels == 0 || end > texels.len() {
                return Err(StickError::Texels { stick });
            }
        }
        Ok(Self {
            sticks,
            texels,
            alphas: &[],
            first_complex: u16::MAX,
        })
    }

    /// This table with each texel's opacity, `alphas[i]` texel `i`'s (255
    /// opaque, 0 clear): its sticks are **complex** (Cohen-Or §2) where a
    /// texel is less than opaque, and a ray that meets one sees through
    /// it ([`Grid::seen_pair_at`]). None (an empty slice) keeps every
    /// texel opaque. Put the complex sticks after the opaque ones in the
    /// table: a hit on a stick before the first complex one is shaded as an
    /// opaque one is, with no opacity to look up
    /// ([`StickTable::first_complex`]).
    pub fn with_alphas(self, alphas: &'a [u8]) -> Result<Self, StickError> {
        if !alphas.is_empty() && alphas.len() != self.texels.len() {
            return Err(StickError::AlphasLength);
        }
        let first_complex = self
            .sticks
            .iter()
            .position(|s| s.is_complex(alphas))
            .map_or(u16::MAX, |i| u16::try_from(i + 1).unwrap_or(u16::MAX));
        Ok(Self {
            alphas,
            first_complex,
            ..self
        })
    }

    /// The smallest point value whose stick is complex (`u16::MAX` where
    /// none is): every point whose value is below it is plain terrain or
    /// an opaque stick.
    pub fn first_complex(&self) -> u16 {
        self.first_complex
    }

    /// Whether a point whose value is `point` holds a stick that may be
    /// less than opaque somewhere (a complex stick, or one after it).
    #[inline(always)]
    pub(crate) fn may_see_through(&self, point: u16) -> bool {
        point >= self.first_complex
    }

    /// The texels' opacities: none where every texel is opaque.
    pub fn alphas(&self) -> &'a [u8] {
        self.alphas
    }

    /// Whether a texel is less than opaque.
    pub fn sees_through(&self) -> bool {
        self.alphas.iter().any(|&a| a < u8::MAX)
    }

    /// The sticks.
    pub fn sticks(&self) -> &'a [Stick] {
        self.sticks
    }

    /// Their texels.
    pub fn texels(&self) -> &'a [Rgb] {
        self.texels
    }

    /// Whether the table holds no stick.
    pub fn is_empty(&self) -> bool {
        self.sticks.is_empty()
    }

    /// Bytes of the table: its sticks, texels and opacities.
    pub fn bytes(&self) -> usize {
        core::mem::size_of_val(self.sticks)
            + core::mem::size_of_val(self.texels)
            + self.alphas.len()
    }

    /// The texel at height `z` (Q16) of the stick a grid point whose value
    /// is `point` and whose height is `top` (U12.4) holds; `None` for
    /// plain terrain (0) or a value past the table.
    #[inline]
    pub(crate) fn texel(&self, point: u16, top: u16, z: i32) -> Option<Rgb> {
        let stick = self.sticks.get(usize::from(point.checked_sub(1)?))?;
        self.texels.get(stick.texel_at(top, z)).copied()
    }

    /// The colors at two neighbouring grid points (heights `tops`, U12.4,
    /// colors `terrain`) where a ray crosses the surface between them at
    /// height `z` (Q16), given each point's stick texel there (`None`
    /// where no stick stands; see [`StickLayer::pair`]).
    /// The same choice for any value of a texel (its color, its opacity).
    #[inline(always)]
    fn pair_of<V: Copy>(
        texels: (Option<V>, Option<V>),
        tops: (u16, u16),
        z: i32,
        terrain: (V, V),
    ) -> (V, V) {
        let (first, second) = texels;
        let above = |top: u16| z > i32::from(top) << HEIGHT_TO_Q16;
        let c0 = match (first, second) {
            (Some(c), _) => c,
            (None, Some(c)) if above(tops.0) => c,
            _ => terrain.0,
        };
        let c1 = match (second, first) {
            (Some(c), _) => c,
            (None, Some(c)) if above(tops.1) => c,
            _ => terrain.1,
        };
        (c0, c1)
    }

    /// [`StickLayer::pair`] of two points whose values are `points`.
    #[inline]
    pub(crate) fn pair(
        &self,
        points: (u16, u16),
        tops: (u16, u16),
        z: i32,
        terrain: (Rgb, Rgb),
    ) -> (Rgb, Rgb) {
        let texels = (
            self.texel(points.0, tops.0, z),
            self.texel(points.1, tops.1, z),
        );
        Self::pair_of(texels, tops, z, terrain)
    }

    /// The texel at height `z` (Q16) of the stick a point whose value is
    /// `point` and whose height is `top` (U12.4) holds, and its opacity
    /// (255 where the table has none); `None` for plain terrain.
    #[inline]
    fn seen(&self, point: u16, top: u16, z: i32) -> Option<(Rgb, u8)> {
        let stick = self.sticks.get(usize::from(point.checked_sub(1)?))?;
        let texel = stick.texel_at(top, z);
        let alpha = self.alphas.get(texel).copied().unwrap_or(u8::MAX);
        Some((*self.texels.get(texel)?, alpha))
    }

    /// [`StickTable::pair`] with each color's opacity: a texel's, or
    /// opaque terrain. A point `lowered` (a secondary ray sees through
    /// its stick) is plain terrain at its ground: it shows no texel of its
    /// own and is no wall.
    #[inline]
    pub(crate) fn seen_pair(
        &self,
        points: (u16, u16),
        tops: (u16, u16),
        z: i32,
        terrain: (Rgb, Rgb),
        lowered: (bool, bool),
    ) -> ((Rgb, u8), (Rgb, u8)) {
        let seen_at = |point: u16, top: u16, lowered: bool| {
            if lowered {
                (None, self.ground(point, top))
            } else {
                (self.seen(point, top, z), top)
            }
        };
        let (seen0, top0) = seen_at(points.0, tops.0, lowered.0);
        let (seen1, top1) = seen_at(points.1, tops.1, lowered.1);
        Self::pair_of(
            (seen0, seen1),
            (top0, top1),
            z,
            ((terrain.0, u8::MAX), (terrain.1, u8::MAX)),
        )
    }

    /// The ground's height (U12.4) under a point whose value is `point`
    /// and whose height is `top`: its stick's base, or `top` for plain
    /// terrain.
    #[inline]
    pub(crate) fn ground(&self, point: u16, top: u16) -> u16 {
        match point
            .checked_sub(1)
            .and_then(|i| self.sticks.get(usize::from(i)))
        {
            Some(stick) => top - stick.height.min(top),
            None => top,
        }
    }

    /// Whether a stick on a point whose height is `top` (U12.4) stands as
    /// high as `z` (Q16) or higher: a crossing at `z` beside it is on its
    /// wall ([`Grid::stands`]).
    #[inline(always)]
    pub(crate) fn reaches(top: u16, z: i32) -> bool {
        i32::from(top) << HEIGHT_TO_Q16 >= z
    }
}

/// Sticks on level 0 of a terrain: an index a grid point into the stick
/// table (0 for plain terrain, `i` for `sticks[i − 1]`), in caller storage.
#[derive(Debug, Clone, Copy)]
pub struct StickLayer<'a> {
    points: &'a [u16],
    sticks: &'a [Stick],
    texels: &'a [Rgb],
    alphas: &'a [u8],
    first_complex: u16,
    /// Whether [`StickLayer::raise_coarse`] raises the coarse levels by
    /// the complex sticks too (fills their cavities there).
    fills_cavities: bool,
}

impl<'a> StickLayer<'a> {
    /// The layer of `points` (one a grid point of `terrain`, row by row)
    /// over `terrain`, whose heights are the sticks' tops where they stand.
    /// Checked once here, so that a lookup cannot fail.
    pub fn new(
        terrain: &Terrain<'_>,
        points: &'a [u16],
        sticks: &'a [Stick],
        texels: &'a [Rgb],
    ) -> Result<Self, StickError> {
        if points.len() != terrain.heights().len() {
            return Err(StickError::PointsLength);
        }
        StickTable::new(sticks, texels)?;
        for (point, (&index, &height)) in points.iter().zip(terrain.heights()).enumerate() {
            if index == 0 {
                continue;
            }
            let stick = sticks
                .get(usize::from(index) - 1)
                .ok_or(StickError::UnknownStick { point })?;
            if stick.height > height {
                return Err(StickError::BelowGround { point });
            }
        }
        Ok(Self {
            points,
            sticks,
            texels,
            alphas: &[],
            first_complex: u16::MAX,
            fills_cavities: true,
        })
    }

    /// This layer with each texel's opacity ([`StickTable::with_alphas`]).
    pub fn with_alphas(self, alphas: &'a [u8]) -> Result<Self, StickError> {
        let table = self.table().with_alphas(alphas)?;
        Ok(Self {
            alphas: table.alphas,
            first_complex: table.first_complex,
            ..self
        })
    }

    /// This layer, raising the coarse levels
    /// ([`crate::Pyramid::build_with_sticks`]) by its opaque sticks only
    /// (those before the table's first complex one: all of them, where the
    /// complex sticks come last): a complex stick is filtered with the
    /// ground around it there, as the terrain is, so the cavities of its
    /// see-through texels are not filled on the coarse levels (Cohen-Or
    /// fills them, the default; this measures what filling them does).
    pub fn with_cavities_open(self) -> Self {
        Self {
            fills_cavities: false,
            ..self
        }
    }

    /// The stick table.
    pub fn table(&self) -> StickTable<'a> {
        StickTable {
            sticks: self.sticks,
            texels: self.texels,
            alphas: self.alphas,
            first_complex: self.first_complex,
        }
    }

    /// Whether grid point `index` holds a stick that may be less than
    /// opaque somewhere ([`StickTable::first_complex`]).
    #[inline(always)]
    pub fn may_see_through(&self, index: isize) -> bool {
        self.point(index as usize) >= self.first_complex
    }

    /// The value of grid point `index` of level 0 (row by row): 0 for
    /// plain terrain, `i` for the table's stick `i − 1`.
    #[inline(always)]
    pub fn point(&self, index: usize) -> u16 {
        self.points.get(index).copied().unwrap_or(0)
    }

    /// The color at grid point `index` of level 0, whose height is
    /// `top` (U12.4), at height `z` (Q16): its stick's texel there, or
    /// `None` where no stick stands.
    #[inline]
    pub fn texel(&self, index: isize, top: u16, z: i32) -> Option<Rgb> {
        // Its own lookup rather than `StickTable::texel`'s: the board's
        // render compiles a few instructions a pixel shorter so.
        let point = *self.points.get(index as usize)?;
        let stick = self.sticks.get(usize::from(point.checked_sub(1)?))?;
        self.texels.get(stick.texel_at(top, z)).copied()
    }

    /// The colors at two neighbouring grid points (`index` and `index +
    /// across`, heights `tops` U12.4, colors `terrain`) where a ray
    /// crosses the surface between them at height `z` (Q16). A stick's
    /// point shows its texel at `z`. Between a stick and a lower point the
    /// surface rises over one grid spacing, where a stick of voxels has a
    /// wall: a crossing above the lower point's top is on that wall, and
    /// both ends take the stick's texel, so the wall is not blended with
    /// the ground beside it.
    #[inline]
    pub fn pair(
        &self,
        index: isize,
        across: isize,
        tops: (u16, u16),
        z: i32,
        terrain: (Rgb, Rgb),
    ) -> (Rgb, Rgb) {
        let texels = (
            self.texel(index, tops.0, z),
            self.texel(index + across, tops.1, z),
        );
        StickTable::pair_of(texels, tops, z, terrain)
    }

    /// Whether grid point `index` holds a stick.
    #[inline(always)]
    pub fn holds(&self, index: isize) -> bool {
        self.points.get(index as usize).is_some_and(|&p| p != 0)
    }

    /// Bytes of the layer: its points, sticks and texels.
    pub fn bytes(&self) -> usize {
        core::mem::size_of_val(self.points) + self.table().bytes()
    }

    /// Raises the coarser levels' heights (`coarse`: levels 1 and up of
    /// `terrain`'s pyramid, laid out as [`Pyramid::build`] fills them) to
    /// the top of every stick nearest each of their points, so that a
    /// coarse level keeps an object's silhouette rather than filtering it
    /// down with the ground around it. Visits each stick once a level.
    /// A complex stick raises them only where the layer fills cavities
    /// ([`StickLayer::with_cavities_open`]).
    ///
    /// [`Pyramid::build`]: crate::Pyramid::build
    pub(crate) fn raise_coarse(&self, terrain: &Terrain<'_>, coarse: &mut [u16]) {
        let (width, depth) = (terrain.width(), terrain.depth());
        let levels = level_count(width, depth);
        // Each coarser level's width and where it starts in `coarse`, once.
        let mut layout = [(0usize, 0usize, 0usize); MAX_LEVELS];
        let mut offset = 0;
        for (level, slot) in layout.iter_mut().enumerate().take(levels).skip(1) {
            let (w, d) = (
                level_side(width, level as u32) as usize,
                level_side(depth, level as u32) as usize,
            );
            *slot = (offset, w, d);
            offset += w * d;
        }
        let row = width as usize;
        let raises = |point: u16| point != 0 && (self.fills_cavities || point < self.first_complex);
        for (index, (&point, &top)) in self.points.iter().zip(terrain.heights()).enumerate() {
            if !raises(point) {
                continue;
            }
            let (x, y) = (index % row, index / row);
            for (level, &(offset, w, d)) in layout.iter().enumerate().take(levels).skip(1) {
                // The nearest point of the level: it sits on level 0's
                // point 2^level times its own coordinates.
                let half = 1 << (level - 1);
                let (cx, cy) = (
                    ((x + half) >> level).min(w - 1),
                    ((y + half) >> level).min(d - 1),
                );
                if let Some(h) = coarse.get_mut(offset + cy * w + cx) {
                    *h = (*h).max(top);
                }
            }
        }
    }
}

/// A surface with sticks on its level 0 (see the module).
#[derive(Debug, Clone, Copy)]
pub struct WithSticks<'s, T: ?Sized> {
    surface: &'s T,
    layer: StickLayer<'s>,
}

impl<'s, T: Surface + ?Sized> WithSticks<'s, T> {
    /// `surface` with `layer` on its level 0 (made over that level).
    pub fn new(surface: &'s T, layer: StickLayer<'s>) -> Self {
        Self { surface, layer }
    }
}

/// A level's grid of a [`WithSticks`]: level 0's colors come from the
/// sticks where they stand.
#[derive(Debug, Clone, Copy)]
pub struct StickGrid<'s, G> {
    grid: G,
    layer: Option<StickLayer<'s>>,
}

impl<G: Grid> Grid for StickGrid<'_, G> {
    #[inline(always)]
    fn stride(&self) -> isize {
        self.grid.stride()
    }
    #[inline(always)]
    fn height(&self, index: isize) -> Option<u16> {
        self.grid.height(index)
    }
    #[inline(always)]
    fn color(&self, index: isize) -> Option<Rgb> {
        self.grid.color(index)
    }
    #[inline(always)]
    fn near(self, index: isize) -> Self {
        Self {
            grid: self.grid.near(index),
            layer: self.layer,
        }
    }
    #[inline(always)]
    fn height_pair(&self, index: isize, across: isize) -> Option<(u16, u16)> {
        self.grid.height_pair(index, across)
    }
    #[inline(always)]
    fn color_pair(&self, index: isize, across: isize) -> Option<(Rgb, Rgb)> {
        self.grid.color_pair(index, across)
    }
    #[inline]
    fn color_pair_at(&self, index: isize, across: isize, z: i32) -> Option<(Rgb, Rgb)> {
        let (c0, c1) = self.grid.color_pair(index, across)?;
        match &self.layer {
            // Most points hold no stick: their colors as they are.
            Some(layer) if layer.holds(index) || layer.holds(index + across) => {
                let tops = self.grid.height_pair(index, across)?;
                Some(layer.pair(index, across, tops, z, (c0, c1)))
            }
            _ => Some((c0, c1)),
        }
    }
    #[inline]
    fn stands(&self, index: isize, across: isize, z: i32) -> bool {
        let Some(layer) = &self.layer else {
            return false;
        };
        let stands_at = |i: isize| {
            layer.holds(i)
                && self
                    .grid
                    .height(i)
                    .is_some_and(|top| StickTable::reaches(top, z))
        };
        stands_at(index) || stands_at(index + across)
    }
    #[inline]
    fn color_at(&self, index: isize, z: i32) -> Option<Rgb> {
        let color = self.grid.color(index)?;
        let Some(layer) = &self.layer else {
            return Some(color);
        };
        Some(
            layer
                .texel(index, self.grid.height(index)?, z)
                .unwrap_or(color),
        )
    }
    #[inline]
    fn sees_through(&self) -> bool {
        self.layer.is_some_and(|layer| !layer.alphas.is_empty())
    }
    #[inline(always)]
    fn may_see_through(&self, index: isize, across: isize) -> bool {
        self.layer.is_some_and(|layer| {
            layer.may_see_through(index) || layer.may_see_through(index + across)
        })
    }
    #[inline(always)]
    fn seen_pair_at(
        &self,
        index: isize,
        across: isize,
        z: i32,
        lowered: (bool, bool),
    ) -> Option<((Rgb, u8), (Rgb, u8))> {
        let (c0, c1) = self.grid.color_pair(index, across)?;
        match &self.layer {
            Some(layer) if layer.holds(index) || layer.holds(index + across) => {
                let tops = self.grid.height_pair(index, across)?;
                let points = (
                    layer.point(index as usize),
                    layer.point((index + across) as usize),
                );
                Some(layer.table().seen_pair(points, tops, z, (c0, c1), lowered))
            }
            _ => Some(((c0, u8::MAX), (c1, u8::MAX))),
        }
    }
    #[inline]
    fn ground(&self, index: isize) -> Option<u16> {
        let top = self.grid.height(index)?;
        Some(match &self.layer {
            Some(layer) => layer.table().ground(layer.point(index as usize), top),
            None => top,
        })
    }
}

impl<'s, T: Surface + ?Sized> Surface for WithSticks<'s, T> {
    type Grid<'g>
        = StickGrid<'g, T::Grid<'g>>
    where
        Self: 'g;

    #[inline(always)]
    fn grid(&self, level: u8) -> Option<Self::Grid<'_>> {
        Some(StickGrid {
            grid: self.surface.grid(level)?,
            layer: (level == 0).then_some(self.layer),
        })
    }
    #[inline(always)]
    fn base(&self) -> Self::Grid<'_> {
        StickGrid {
            grid: self.surface.base(),
            layer: Some(self.layer),
        }
    }
    crate::surface::lend_surface!(surface);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_complex_stick_is_found_by_its_texels_opacities() {
        let stick = |first| Stick {
            first,
            texels: 2,
            height: 2 << HEIGHT_FRAC_BITS,
        };
        let sticks = [stick(0), stick(2), stick(4)];
        let texels = [[9; 3]; 6];
        let table = StickTable::new(&sticks, &texels).unwrap();
        assert_eq!(table.first_complex(), u16::MAX);
        let opaque = table.with_alphas(&[255; 6]).unwrap();
        assert_eq!(opaque.first_complex(), u16::MAX);
        // The second stick's top texel is less than opaque: point value 2.
        let second = table.with_alphas(&[255, 255, 255, 254, 0, 255]).unwrap();
        assert_eq!(second.first_complex(), 2);
        assert!(!second.may_see_through(0) && !second.may_see_through(1));
        assert!(second.may_see_through(2) && second.may_see_through(3));
    }
    use crate::{
        pyramid_cells, pyramid_points, render, Camera, Coherence, Framebuffer, HeightFilter,
        NoProbe, Pyramid, RenderOptions, Resolution, View,
    };
    use std::vec;
    use std::vec::Vec;

    const SIDE: u32 = 32;
    const GROUND: u16 = 2 << HEIGHT_FRAC_BITS;
    const GRASS: Rgb = [40, 120, 40];
    /// A wall's texels, one a voxel, bottom up.
    const BANDS: [Rgb; 6] = [
        [250, 0, 0],
        [0, 0, 250],
        [250, 250, 0],
        [0, 250, 250],
        [250, 0, 250],
        [255, 255, 255],
    ];

    /// A flat map with a wall of sticks six voxels tall and two points
    /// thick at x = 20 and 21 (rows 4 to 27), and a lone uniform stick at
    /// (10, 8).
    struct Walled {
        heights: Vec<u16>,
        colors: Vec<Rgb>,
        points: Vec<u16>,
    }

    fn walled() -> Walled {
        let n = (SIDE * SIDE) as usize;
        let (mut heights, mut colors, mut points) = (vec![GROUND; n], vec![GRASS; n], vec![0; n]);
        let tall = BANDS.len() as u16 * 16;
        for y in 4..28 {
            for x in [20, 21] {
                let i = y * SIDE as usize + x;
                heights[i] += tall;
                points[i] = 1;
                colors[i] = BANDS[BANDS.len() - 1];
            }
        }
        let lone = 8 * SIDE as usize + 10;
        heights[lone] += 3 * 16;
        points[lone] = 2;
        colors[lone] = [90, 60, 30];
        Walled {
            heights,
            colors,
            points,
        }
    }

    const STICKS: [Stick; 2] = [
        Stick {
            first: 0,
            texels: 6,
            height: 6 * 16,
        },
        Stick {
            first: 6,
            texels: 1,
            height: 3 * 16,
        },
    ];

    fn texels() -> Vec<Rgb> {
        let mut texels = BANDS.to_vec();
        texels.push([90, 60, 30]);
        texels
    }

    /// Renders `camera` over the walled map, with the sticks or without,
    /// at `options`: colors and hit distances.
    fn render_walled(
        camera: &Camera,
        options: &RenderOptions,
        with_sticks: bool,
    ) -> (Vec<Rgb>, Vec<u32>) {
        let map = walled();
        let terrain = Terrain::new(SIDE, SIDE, &map.heights, &map.colors).unwrap();
        let texels = texels();
        let layer = StickLayer::new(&terrain, &map.points, &STICKS, &texels).unwrap();
        let pyramid = Pyramid::flat(terrain);
        let view = View::new(camera, 48, 36).unwrap();
        let (mut colors, mut distances) = (vec![[0; 3]; 48 * 36], vec![0; 48 * 36]);
        let mut frame = Framebuffer::with_distances(&mut colors, &mut distances, 48, 36).unwrap();
        if with_sticks {
            render(
                &WithSticks::new(&pyramid, layer),
                &view,
                options,
                &mut frame,
                &mut NoProbe,
            );
        } else {
            render(&pyramid, &view, options, &mut frame, &mut NoProbe);
        }
        (colors, distances)
    }

    fn facing_the_wall() -> Camera {
        Camera::looking([2.0, 16.0, 5.0], 0.0, 0.0)
    }

    #[test]
    fn a_wall_shows_its_texels_by_height_and_none_of_the_ground() {
        let options = RenderOptions {
            resolution: Resolution::Single,
            ..RenderOptions::default()
        };
        let (colors, distances) = render_walled(&facing_the_wall(), &options, true);
        // The middle column looks straight at the wall: from the bottom up
        // it meets the ground, then each band of the wall in order.
        let column: Vec<Rgb> = (0..36).rev().map(|y| colors[y * 48 + 24]).collect();
        let on_wall: Vec<usize> = column
            .iter()
            .filter_map(|c| BANDS.iter().position(|b| b == c))
            .collect();
        assert!(on_wall.len() >= 8, "{column:?}");
        assert!(on_wall.windows(2).all(|w| w[0] <= w[1]), "{on_wall:?}");
        assert!(
            on_wall.contains(&0) && on_wall.contains(&(BANDS.len() - 1)),
            "{on_wall:?}"
        );
        // Every pixel that hit the wall (17 to 18 voxels away along x) is
        // one of its bands: the wall's side is not blended with the grass
        // beside it.
        for (color, distance) in colors.iter().zip(&distances) {
            let voxels = *distance >> 16;
            if (17..19).contains(&voxels) {
                assert!(
                    BANDS.contains(color) || *color == GRASS,
                    "{color:?} at {voxels}"
                );
            }
        }
    }

    #[test]
    fn no_ray_passes_through_the_wall() {
        for camera in [
            facing_the_wall(),
            Camera::looking([2.0, 16.0, 9.0], 15.0, 10.0),
            Camera::looking([3.0, 5.0, 4.0], 40.0, -5.0),
        ] {
            for options in [
                RenderOptions::default(),
                RenderOptions {
                    resolution: Resolution::Single,
                    ..RenderOptions::default()
                },
            ] {
                let view = View::new(&camera, 48, 36).unwrap();
                let (_, distances) = render_walled(&camera, &options, true);
                let eye = camera.eye.map(f64::from);
                let wall_top = f64::from(GROUND + STICKS[0].height) / 16.0;
                for y in 0..36u32 {
                    for x in 0..48u32 {
                        // The pixel's ray meets the plane x = 20.5 inside
                        // the wall (clear of its ends and top, which slope
                        // over a grid spacing): its hit is no farther than
                        // there. (Two points thick, the wall is solid: a
                        // ray's samples are less than a grid spacing apart
                        // across it, so one lands on it. A lone stick is
                        // seen as the surface through its point, a spike.)
                        let row = i64::from(35 - y);
                        let d: [f64; 3] = core::array::from_fn(|i| {
                            (view.base[i].to_bits()
                                + view.per_column[i].to_bits() * i64::from(x)
                                + view.per_row[i].to_bits() * row)
                                as f64
                        });
                        if d[0] <= 0.0 {
                            continue;
                        }
                        let t = (20.5 - eye[0]) / d[0];
                        let at = [eye[1] + t * d[1], eye[2] + t * d[2]];
                        if !(6.0..25.0).contains(&at[0]) || !(2.5..wall_top - 1.5).contains(&at[1])
                        {
                            continue;
                        }
                        let distance = f64::from(distances[(y * 48 + x) as usize]) / 65536.0;
                        let along_major = t * d[0].abs().max(d[1].abs());
                        assert!(
                            distance <= along_major + 1.0,
                            "{camera:?} pixel ({x}, {y}): hit at {distance}, the wall at {along_major}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn exact_coherence_is_off_bit_for_bit_with_sticks_and_the_line_caster_too() {
        for camera in [
            facing_the_wall(),
            Camera::looking([2.0, 16.0, 9.0], 15.0, 10.0),
            Camera::looking([16.0, 16.0, 30.0], 30.0, 70.0),
        ] {
            let at = |coherence| RenderOptions {
                coherence,
                resolution: Resolution::Single,
                ..RenderOptions::default()
            };
            let off = render_walled(&camera, &at(Coherence::Off), true);
            assert_eq!(
                off,
                render_walled(&camera, &at(Coherence::Exact), true),
                "{camera:?}"
            );
            assert_eq!(
                off,
                render_walled(&camera, &at(Coherence::AcrossLevels), true),
                "{camera:?}"
            );
            // And the sticks change the image.
            assert_ne!(
                off.0,
                render_walled(&camera, &at(Coherence::Off), false).0,
                "{camera:?}"
            );
        }
    }

    #[test]
    fn coarse_levels_keep_the_sticks_tops() {
        let map = walled();
        let terrain = Terrain::new(SIDE, SIDE, &map.heights, &map.colors).unwrap();
        let texels = texels();
        let layer = StickLayer::new(&terrain, &map.points, &STICKS, &texels).unwrap();
        let build = |sticks: Option<&StickLayer<'_>>| {
            let (points, cells) = (pyramid_points(SIDE, SIDE), pyramid_cells(SIDE, SIDE));
            let (mut heights, mut colors, mut bounds) =
                (vec![0; points], vec![[0; 3]; points], vec![0; cells]);
            Pyramid::build_with_sticks(
                &terrain,
                HeightFilter::default(),
                sticks,
                &mut heights,
                &mut colors,
                &mut bounds,
            )
            .unwrap();
            (heights, colors, bounds)
        };
        let (filtered, filtered_colors, _) = build(None);
        let (raised, raised_colors, raised_bounds) = build(Some(&layer));
        let pyramid = Pyramid::new(terrain, &raised, &raised_colors, &raised_bounds).unwrap();
        let wall_top = GROUND + 6 * 16;
        let lone_top = GROUND + 3 * 16;
        for level in 1..pyramid.levels() {
            let grid = pyramid.level(level).unwrap();
            let at = |x: usize, y: usize| {
                let (w, shift) = (grid.width() as usize, level);
                let half = 1 << (shift - 1);
                let (cx, cy) = ((x + half) >> shift, (y + half) >> shift);
                grid.heights()[cy.min(w - 1) * w + cx.min(w - 1)]
            };
            // The point nearest a stick stands as high as its top, on
            // every level; the ground far from them is left alone.
            assert_eq!(at(20, 16), wall_top, "level {level}");
            assert!(at(10, 8) >= lone_top, "level {level}");
        }
        // Filtered, the sticks sink into the ground around them: raising
        // only ever lifts a point, and lifts some.
        assert!(filtered.iter().zip(&raised).all(|(f, r)| f <= r));
        assert_ne!(filtered, raised);
        // Colors are filtered either way.
        assert_eq!(filtered_colors, raised_colors);
        // Cavities open, a complex stick raises nothing and an opaque one
        // raises as before.
        let (see_through, opaque) = (vec![128; texels.len()], vec![255; texels.len()]);
        let open = |alphas| layer.with_alphas(alphas).unwrap().with_cavities_open();
        assert_eq!(build(Some(&open(&see_through))).0, filtered);
        assert_eq!(build(Some(&open(&opaque))).0, raised);
        let filled = layer.with_alphas(&see_through).unwrap();
        assert_eq!(build(Some(&filled)).0, raised);
        // And the raised pyramid renders: the first hit's bounds hold the
        // raised heights, so a ray through the bounds sees what the walk
        // alone sees.
        let view = View::new(&Camera::looking([2.0, 16.0, 9.0], 15.0, 10.0), 48, 36).unwrap();
        let frame = |hierarchical_first_hit| {
            let mut colors = vec![[0; 3]; 48 * 36];
            let mut frame = Framebuffer::new(&mut colors, 48, 36).unwrap();
            let options = RenderOptions {
                hierarchical_first_hit,
                ..RenderOptions::default()
            };
            render(
                &WithSticks::new(&pyramid, layer),
                &view,
                &options,
                &mut frame,
                &mut NoProbe,
            );
            colors
        };
        assert_eq!(frame(true), frame(false));
    }

    #[test]
    fn a_bad_layer_is_refused() {
        let map = walled();
        let terrain = Terrain::new(SIDE, SIDE, &map.heights, &map.colors).unwrap();
        let texels = texels();
        assert_eq!(
            StickLayer::new(&terrain, &map.points[1..], &STICKS, &texels).unwrap_err(),
            StickError::PointsLength
        );
        assert_eq!(
            StickLayer::new(&terrain, &map.points, &STICKS[..1], &texels).unwrap_err(),
            StickError::UnknownStick {
                point: 8 * SIDE as usize + 10
            }
        );
        assert_eq!(
            StickLayer::new(&terrain, &map.points, &STICKS, &texels[..6]).unwrap_err(),
            StickError::Texels { stick: 1 }
        );
        let mut tall = STICKS;
        tall[1].height = GROUND + 3 * 16 + 1;
        let error = StickLayer::new(&terrain, &map.points, &tall, &texels).unwrap_err();
        assert_eq!(
            error,
            StickError::BelowGround {
                point: 8 * SIDE as usize + 10
            }
        );
        assert!(error.to_string().contains("taller than the height"));
    }
}
