//! What the caster reads: a stack of grids (the pyramid's levels) and their
//! height bounds, whether borrowed whole ([`crate::Pyramid`]) or paged in
//! tiles ([`crate::tiles::TiledSurface`]).
//!
//! The caster addresses a grid point of level `l` by a linear index
//! `y·stride + x`, with `stride` the grid's own (a borrowed level's width,
//! or a power of two for tiles, so a tile lookup is a shift and a mask). It
//! is monomorphized for each surface: rendering from a [`crate::Pyramid`]
//! compiles to the same slice indexing as before the trait existed.

use crate::color::Rgb;

/// The size of level 0 and its highest height: what clipping a ray to the
/// map needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Extent {
    /// Grid points along x.
    pub width: u32,
    /// Grid points along y.
    pub depth: u32,
    /// The highest height (U12.4) anywhere on any level: rays above it can
    /// no longer hit.
    pub max_height: u16,
    /// Whether the map's edges are the terrain's own: then a ray that
    /// leaves the map between its level's grid lines tests its last sample
    /// inside on level 0, so that the terrain's edge keeps its silhouette.
    /// False for a window cut out of a larger terrain, whose edges are not
    /// the terrain's.
    pub real_edges: bool,
}

/// One level's grid points, addressed by linear index.
pub trait Grid: Copy {
    /// Index change from one row (y) to the next.
    fn stride(&self) -> isize;
    /// The height (U12.4) at `index`; `None` outside the grid.
    fn height(&self, index: isize) -> Option<u16>;
    /// The color at `index`; `None` outside the grid.
    fn color(&self, index: isize) -> Option<Rgb>;
    /// This grid, for reads mostly near index `index`: a grid paged in
    /// tiles resolves that point's tile once, so that reads inside it skip
    /// the tile directory. Reads anywhere are still served, with the same
    /// values.
    #[inline(always)]
    fn near(self, index: isize) -> Self {
        let _ = index;
        self
    }
    /// The heights at `index` and `index + across`, both or `None`: the two
    /// ends of the grid-line cell a step tests. A grid that pays per lookup
    /// (a tile cache) can find both in one.
    #[inline(always)]
    fn height_pair(&self, index: isize, across: isize) -> Option<(u16, u16)> {
        Some((self.height(index)?, self.height(index + across)?))
    }
    /// The colors at `index` and `index + across`, both or `None` (see
    /// [`Grid::height_pair`]).
    #[inline(always)]
    fn color_pair(&self, index: isize, across: isize) -> Option<(Rgb, Rgb)> {
        Some((self.color(index)?, self.color(index + across)?))
    }
    /// [`Grid::color_pair`] where a ray crosses the surface at height `z`
    /// (Q16): what an object standing at a point shows at that height
    /// ([`crate::WithSticks`]); the grid's own colors by default.
    #[inline(always)]
    fn color_pair_at(&self, index: isize, across: isize, z: i32) -> Option<(Rgb, Rgb)> {
        let _ = z;
        self.color_pair(index, across)
    }
    /// Whether an object stands at `index` or `index + across` as high as
    /// `z` (Q16) or higher: a crossing at `z` next to it is on its wall
    /// ([`crate::StickLayer::pair`]). Never, by default.
    #[inline(always)]
    fn stands(&self, index: isize, across: isize, z: i32) -> bool {
        let _ = (index, across, z);
        false
    }
    /// [`Grid::color`] at height `z` (Q16), as [`Grid::color_pair_at`].
    #[inline(always)]
    fn color_at(&self, index: isize, z: i32) -> Option<Rgb> {
        let _ = z;
        self.color(index)
    }
    /// Whether anything on this grid can be seen through (complex sticks,
    /// [`crate::StickTable::with_alphas`]): if not, every color
    /// [`Grid::seen_pair_at`] gives is opaque. Never, by default.
    #[inline(always)]
    fn sees_through(&self) -> bool {
        false
    }
    /// Whether a ray crossing the grid line between `index` and `index +
    /// across` may see through what stands there (a complex stick at
    /// either point, [`crate::StickTable::first_complex`]): if not, the
    /// colors there are opaque and shaded as [`Grid::color_pair_at`]'s.
    /// Never, by default.
    #[inline(always)]
    fn may_see_through(&self, index: isize, across: isize) -> bool {
        let _ = (index, across);
        false
    }
    /// [`Grid::color_pair_at`], each color with its opacity (255 opaque),
    /// for a ray that sees through the sticks of the points `lowered`
    /// says: such a point is plain terrain at its [`Grid::ground`].
    /// Opaque, by default, where nothing can be seen through.
    #[inline(always)]
    fn seen_pair_at(
        &self,
        index: isize,
        across: isize,
        z: i32,
        lowered: (bool, bool),
    ) -> Option<((Rgb, u8), (Rgb, u8))> {
        let _ = lowered;
        let (c0, c1) = self.color_pair_at(index, across, z)?;
        Some(((c0, u8::MAX), (c1, u8::MAX)))
    }
    /// The height (U12.4) of the ground at `index`, under any object
    /// standing there: what a ray that sees through the object meets.
    /// [`Grid::height`], by default.
    #[inline(always)]
    fn ground(&self, index: isize) -> Option<u16> {
        self.height(index)
    }
}

/// A terrain and its coarser levels, as the caster reads them.
pub trait Surface {
    /// A level's grid, cheap to make (the caster makes one per level a ray
    /// steps on).
    type Grid<'s>: Grid
    where
        Self: 's;
    /// Level `level`, if the surface has it.
    fn grid(&self, level: u8) -> Option<Self::Grid<'_>>;
    /// Level 0, which every surface has.
    fn base(&self) -> Self::Grid<'_>;
    /// Level 0's roughness ([`crate::roughness::RoughnessSum::roughness`]),
    /// which scales the pixel-to-voxel ratio down on rugged terrain; 0
    /// when unknown (the ratio is then used as given).
    #[inline(always)]
    fn roughness(&self) -> u8 {
        0
    }
    /// Level `level`'s row stride ([`Grid::stride`]), if the surface has
    /// the level: what locating a sample needs, without making the grid.
    #[inline(always)]
    fn stride(&self, level: u8) -> Option<isize> {
        self.grid(level).map(|grid| grid.stride())
    }
    /// The highest level (0 for a single resolution).
    fn top(&self) -> u8;
    /// Level 0's size and the highest height.
    fn extent(&self) -> Extent;
    /// Whether [`Surface::bound`] answers (the hierarchical first hit needs
    /// it).
    fn has_bounds(&self) -> bool;
    /// The height bound (U12.4) of cell `(x, y)` of level `level ≥ 1` (the
    /// square between grid points `(x, y)` and `(x + 1, y + 1)`): no point
    /// of levels `0..=level` in the cell is higher. With it, an index of
    /// the cell for the probe. `None` when unknown: the caller must assume
    /// the worst.
    fn bound(&self, level: u8, x: i64, y: i64) -> Option<(u16, usize)>;
    /// Whether photos finer than level 0 lie over part of the map
    /// ([`crate::WithDetail`], [`crate::tiles::TiledSurface::with_photos`]);
    /// none by default.
    #[inline(always)]
    fn has_details(&self) -> bool {
        false
    }
    /// The color a hit nearer than the color reach takes from the photos
    /// finer than level 0 at world point `point` (Q16) for a footprint
    /// `width` on a ray whose colors reach level 1 at `reach`
    /// ([`crate::DetailArea::color_for_with`]); `None` outside them.
    #[inline(always)]
    fn detail_color(&self, point: [i64; 2], width: i64, reach: i64) -> Option<Rgb> {
        let _ = (point, width, reach);
        None
    }
}

/// The [`Surface`] methods of a wrapper that lends field `$inner`'s
/// levels, bounds and extent as they are ([`crate::WithSticks`],
/// [`crate::WithDetail`]: what they change is what a hit sees).
macro_rules! lend_surface {
    ($inner:ident) => {
        #[inline(always)]
        fn roughness(&self) -> u8 {
            self.$inner.roughness()
        }
        #[inline(always)]
        fn stride(&self, level: u8) -> Option<isize> {
            self.$inner.stride(level)
        }
        #[inline(always)]
        fn top(&self) -> u8 {
            self.$inner.top()
        }
        #[inline]
        fn extent(&self) -> $crate::surface::Extent {
            self.$inner.extent()
        }
        #[inline]
        fn has_bounds(&self) -> bool {
            self.$inner.has_bounds()
        }
        #[inline]
        fn bound(&self, level: u8, x: i64, y: i64) -> Option<(u16, usize)> {
            self.$inner.bound(level, x, y)
        }
    };
}
pub(crate) use lend_surface;
