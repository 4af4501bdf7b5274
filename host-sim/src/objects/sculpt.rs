//! Objects sculpted from three photographs, as Cohen-Or et al. (§5) make
//! theirs: start from a solid box and clear every voxel that a background
//! pixel's ray passes through in any of the views; the voxels left take
//! their colors by projecting back into the views.
//!
//! The three views are orthographic, one pixel a voxel:
//!
//! - **front**: seen from −y looking toward +y; its columns are x (left to
//!   right), its rows z (the bottom row on the ground);
//! - **side**: seen from +x looking toward −x; its columns are y, its rows z;
//! - **top**: seen from above; its columns are x, its rows y (the top row
//!   the largest y).
//!
//! So the front is as wide as the top, the side as wide as the top is
//! tall, and the front and the side are equally tall. A pixel is
//! background where it is transparent (alpha below half) or, when a key
//! color is given, of exactly that color.
//!
//! The kernel's sticks stand from the ground to their tops, so a column of
//! the carved box becomes a stick as high as its highest voxel left: a
//! voxel under an overhang is filled (cavities and see-through voxels are
//! complex sticks, which the kernel does not have). A voxel's color comes
//! from the view that sees it: the top view for a stick's top voxel, the
//! front view for one with a lower column beside it along y (the back
//! takes the front's colors too, as it is not photographed), the side
//! view for one with a lower column beside it along x; a voxel that none
//! of them sees takes whichever of the front or the side has a foreground
//! pixel over it.

use super::{Column, Shape};
use image::RgbaImage;
use std::fmt;
use terracast::Rgb;

/// Why three views could not be sculpted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SculptError {
    /// The views' sizes do not agree (front as wide as top, side as wide as
    /// top is tall, front and side equally tall).
    Sizes {
        /// The front's width × height.
        front: (u32, u32),
        /// The side's.
        side: (u32, u32),
        /// The top's.
        top: (u32, u32),
    },
    /// A view is larger than an object may be.
    TooLarge(u32),
    /// No voxel is left: the views' silhouettes do not overlap.
    Empty,
}

impl fmt::Display for SculptError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Sizes { front, side, top } => write!(
                f,
                "the views' sizes do not agree: front {}x{}, side {}x{}, top {}x{} \
                 (the front must be as wide as the top, the side as wide as the top is tall, \
                 and the front and the side equally tall)",
                front.0, front.1, side.0, side.1, top.0, top.1
            ),
            Self::TooLarge(side) => write!(
                f,
                "a view is {side} pixels across; an object is at most {} voxels a side",
                Sculpture::MAX_SIDE
            ),
            Self::Empty => f.write_str("no voxel is left: the views' silhouettes do not overlap"),
        }
    }
}

impl std::error::Error for SculptError {}

/// Three views of an object and which of their pixels are background.
pub struct Sculpture<'a> {
    /// Seen from −y.
    pub front: &'a RgbaImage,
    /// Seen from +x.
    pub side: &'a RgbaImage,
    /// Seen from above.
    pub top: &'a RgbaImage,
    /// A color that is background besides transparent pixels.
    pub background: Option<Rgb>,
}

impl Sculpture<'_> {
    /// The largest side of a view in pixels (an object's voxels a side).
    pub const MAX_SIDE: u32 = 512;

    /// The object the views carve out of a solid box, its anchor at the
    /// footprint's lower corner (x and y 0).
    pub fn carve(&self) -> Result<Shape, SculptError> {
        let (wide, deep, tall) = (self.top.width(), self.top.height(), self.front.height());
        if self.front.width() != wide || self.side.width() != deep || self.side.height() != tall {
            return Err(SculptError::Sizes {
                front: self.front.dimensions(),
                side: self.side.dimensions(),
                top: self.top.dimensions(),
            });
        }
        if let Some(&side) = [wide, deep, tall].iter().find(|&&s| s > Self::MAX_SIDE) {
            return Err(SculptError::TooLarge(side));
        }
        // Each column's height: its highest voxel that every view keeps.
        let heights: Vec<u32> = (0..deep)
            .flat_map(|y| (0..wide).map(move |x| (x, y)))
            .map(|(x, y)| {
                if !self.on_top(x, y) {
                    return 0;
                }
                (0..tall)
                    .rev()
                    .find(|&z| self.on_front(x, z) && self.on_side(y, z))
                    .map_or(0, |z| z + 1)
            })
            .collect();
        let height = |x: i64, y: i64| -> u32 {
            if (0..i64::from(wide)).contains(&x) && (0..i64::from(deep)).contains(&y) {
                heights[(y * i64::from(wide) + x) as usize]
            } else {
                0
            }
        };
        let mut columns = Vec::new();
        for y in 0..deep {
            for x in 0..wide {
                let top = height(x.into(), y.into());
                if top == 0 {
                    continue;
                }
                let (xi, yi) = (i64::from(x), i64::from(y));
                let texels = (0..top)
                    .map(|z| {
                        let front = self.front_color(x, z);
                        let side = self.side_color(y, z);
                        let along_y = height(xi, yi - 1) <= z || height(xi, yi + 1) <= z;
                        let along_x = height(xi - 1, yi) <= z || height(xi + 1, yi) <= z;
                        let seen = if z + 1 == top {
                            self.top_color(x, y)
                        } else if along_y {
                            front
                        } else if along_x {
                            side
                        } else {
                            None
                        };
                        seen.or(front)
                            .or(side)
                            .or(self.top_color(x, y))
                            .unwrap_or([0; 3])
                    })
                    .collect();
                columns.push(Column {
                    dx: x as i32,
                    dy: y as i32,
                    height: top as u16,
                    texels,
                    alphas: Vec::new(),
                });
            }
        }
        if columns.is_empty() {
            return Err(SculptError::Empty);
        }
        Ok(Shape { columns })
    }

    /// A pixel's color, `None` for background.
    fn pixel(&self, image: &RgbaImage, column: u32, row: u32) -> Option<Rgb> {
        let [r, g, b, a] = image.get_pixel(column, row).0;
        let color = [r, g, b];
        (a >= 128 && Some(color) != self.background).then_some(color)
    }

    fn front_color(&self, x: u32, z: u32) -> Option<Rgb> {
        self.pixel(self.front, x, self.front.height() - 1 - z)
    }

    fn side_color(&self, y: u32, z: u32) -> Option<Rgb> {
        self.pixel(self.side, y, self.side.height() - 1 - z)
    }

    fn top_color(&self, x: u32, y: u32) -> Option<Rgb> {
        self.pixel(self.top, x, self.top.height() - 1 - y)
    }

    fn on_front(&self, x: u32, z: u32) -> bool {
        self.front_color(x, z).is_some()
    }

    fn on_side(&self, y: u32, z: u32) -> bool {
        self.side_color(y, z).is_some()
    }

    fn on_top(&self, x: u32, y: u32) -> bool {
        self.top_color(x, y).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgba;

    const WALL: Rgb = [200, 190, 170];
    const GABLE: Rgb = [150, 120, 90];
    const ROOF: Rgb = [170, 60, 45];
    const SKY: [u8; 4] = [255, 255, 255, 255];

    /// A known solid: per column (x, y) of a `wide` × `deep` footprint its
    /// height (0 outside it).
    struct Solid {
        wide: u32,
        deep: u32,
        tall: u32,
        height: Box<dyn Fn(u32, u32) -> u32>,
    }

    impl Solid {
        /// A box 14 × 9 with walls 6 high under a roof rising 4 more to a
        /// ridge along x.
        fn barn() -> Self {
            Self {
                wide: 14,
                deep: 9,
                tall: 10,
                height: Box::new(|_, y| {
                    let from_ridge = (f64::from(y) - 4.0).abs() / 4.0;
                    6 + (4.0 * (1.0 - from_ridge)).round() as u32
                }),
            }
        }

        /// An upright cylinder of radius 5.5 about (5.5, 5.5), 9 high.
        fn cylinder() -> Self {
            Self {
                wide: 12,
                deep: 12,
                tall: 9,
                height: Box::new(|x, y| {
                    let (dx, dy) = (f64::from(x) - 5.5, f64::from(y) - 5.5);
                    if dx * dx + dy * dy <= 5.5 * 5.5 {
                        9
                    } else {
                        0
                    }
                }),
            }
        }

        fn at(&self, x: u32, y: u32) -> u32 {
            (self.height)(x, y)
        }

        /// Its three views, photographed: the front's walls `WALL`, the
        /// side's `GABLE`, the top `ROOF`, on a white background.
        fn views(&self) -> [RgbaImage; 3] {
            let mut front = RgbaImage::from_pixel(self.wide, self.tall, Rgba(SKY));
            let mut side = RgbaImage::from_pixel(self.deep, self.tall, Rgba(SKY));
            let mut top = RgbaImage::from_pixel(self.wide, self.deep, Rgba(SKY));
            for y in 0..self.deep {
                for x in 0..self.wide {
                    let h = self.at(x, y);
                    if h == 0 {
                        continue;
                    }
                    top.put_pixel(x, self.deep - 1 - y, Rgba([ROOF[0], ROOF[1], ROOF[2], 255]));
                    for z in 0..h {
                        let row = self.tall - 1 - z;
                        front.put_pixel(x, row, Rgba([WALL[0], WALL[1], WALL[2], 255]));
                        side.put_pixel(y, row, Rgba([GABLE[0], GABLE[1], GABLE[2], 255]));
                    }
                }
            }
            [front, side, top]
        }
    }

    /// Carves `front`, `side` and `top` with `background`.
    fn carve_views(
        [front, side, top]: [&RgbaImage; 3],
        background: Option<Rgb>,
    ) -> Result<Shape, SculptError> {
        Sculpture {
            front,
            side,
            top,
            background,
        }
        .carve()
    }

    fn carve(solid: &Solid) -> Shape {
        let [front, side, top] = solid.views();
        carve_views([&front, &side, &top], Some([255, 255, 255])).unwrap()
    }

    #[test]
    fn three_views_of_a_known_solid_give_it_back_within_a_voxel() {
        for solid in [Solid::barn(), Solid::cylinder()] {
            let shape = carve(&solid);
            let mut footprint = 0;
            for y in 0..solid.deep {
                for x in 0..solid.wide {
                    let carved = shape
                        .columns
                        .iter()
                        .find(|c| (c.dx, c.dy) == (x as i32, y as i32))
                        .map_or(0, |c| u32::from(c.height));
                    let truth = solid.at(x, y);
                    assert!(
                        carved.abs_diff(truth) <= 1,
                        "({x}, {y}): carved {carved}, truth {truth}"
                    );
                    assert_eq!(carved > 0, truth > 0, "({x}, {y}) in the footprint");
                    footprint += usize::from(truth > 0);
                }
            }
            assert_eq!(shape.columns.len(), footprint);
        }
    }

    #[test]
    fn faces_take_the_colors_of_the_views_that_see_them() {
        let shape = carve(&Solid::barn());
        let column = |x: i32, y: i32| {
            shape
                .columns
                .iter()
                .find(|c| (c.dx, c.dy) == (x, y))
                .unwrap()
        };
        // The front wall (y 0), low down: the front view's color.
        assert_eq!(column(5, 0).texels[1], WALL);
        // The gable end (x 0), low down, away from the front and back:
        // the side view's.
        assert_eq!(column(0, 4).texels[2], GABLE);
        // Every top voxel: the top view's.
        assert!(shape
            .columns
            .iter()
            .all(|c| *c.texels.last().unwrap() == ROOF));
        // A texel a voxel of its height.
        assert!(shape
            .columns
            .iter()
            .all(|c| c.texels.len() == usize::from(c.height)));
    }

    #[test]
    fn transparent_pixels_are_background_and_bad_views_are_refused() {
        let [front, side, top] = Solid::cylinder().views();
        // Without a key color, a white background is foreground: the box
        // is not carved at all.
        let uncarved = carve_views([&front, &side, &top], None).unwrap();
        assert_eq!(uncarved.columns.len(), 12 * 12);
        // Transparent pixels are background with no key color.
        let clear = |image: &RgbaImage| {
            let mut image = image.clone();
            image
                .pixels_mut()
                .filter(|p| p.0 == SKY)
                .for_each(|p| p.0[3] = 0);
            image
        };
        let (front, side, top) = (clear(&front), clear(&side), clear(&top));
        let carved = carve_views([&front, &side, &top], None).unwrap();
        assert_eq!(carved, carve(&Solid::cylinder()));

        let small = RgbaImage::new(3, 9);
        let wrong = carve_views([&small, &side, &top], None).unwrap_err();
        assert!(matches!(wrong, SculptError::Sizes { .. }), "{wrong}");
        assert!(wrong.to_string().contains("front 3x9"), "{wrong}");

        let empty = RgbaImage::new(12, 9);
        let nothing = carve_views([&empty, &side, &top], None).unwrap_err();
        assert_eq!(nothing, SculptError::Empty);
    }
}
