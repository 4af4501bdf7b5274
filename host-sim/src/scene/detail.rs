//! A photo kept finer than the height grid: the host side of the kernel's
//! [`terracast::Detail`].
//!
//! A photo of `cw × cd` pixels over a `w × d` height grid, `r` pixels a
//! grid spacing (the smaller of `cw/w` and `cd/d`), is kept at `2^s` texels
//! a spacing, `2^s` the smallest power of two at or above `r` and at most
//! 32: resampled up (bilinear between the photo's pixels) where `r` is not
//! a power of two, so that no pixel of the photo is lost, and down (each
//! texel the mean of the pixels it covers) only past 32.
//!
//! A photo stretched over the map ([`PhotoDetail::from_photo`]) covers its
//! voxels, pixel by area: pixel `(i, j)` is the square around `((i + ½)·w/cw
//! − ½, (j + ½)·d/cd − ½)`. A GeoTIFF photo placed by its georeference
//! ([`PhotoDetail::placed`]) covers the rectangle of the grid points whose
//! centers it covers. Either way the height grid's colors there are the
//! mean of each point's `2^s × 2^s` texels, the colors the pyramid filters
//! on, so that the fine levels and level 0 agree where the caster passes
//! from one to the other.

use super::geotiff::{GeoRef, PhotoPixels};
use image::RgbImage;
use terracast::config::MAX_DETAIL_SHIFT;
use terracast::{detail_points, Detail, Rgb};

/// A photo finer than the height grid over the map (see the module).
#[derive(Debug, Clone)]
pub struct PhotoDetail {
    /// Texels a grid spacing on each side: `2^shift`.
    pub shift: u32,
    /// The first grid point the texels cover.
    pub origin: [u32; 2],
    /// Grid points along x and y the texels cover.
    pub size: [u32; 2],
    /// The texels, row by row, `size[0]·2^shift` a row.
    pub texels: Vec<Rgb>,
}

/// Pixels a grid spacing below which a photo is not kept finer than the
/// height grid: at 1.5 or less, a texel a spacing loses little.
const LEAST_RATIO: f64 = 1.5;

/// The shift of the power of two at or above `ratio` pixels a grid
/// spacing, 1 to [`MAX_DETAIL_SHIFT`].
fn shift_for(ratio: f64) -> u32 {
    (ratio.log2() - 1e-9)
        .ceil()
        .clamp(1.0, f64::from(MAX_DETAIL_SHIFT)) as u32
}

/// `photo` at pixel coordinate `[u, v]` (centers at whole numbers, the
/// edge pixels repeated past it) for a texel `pixels` wide: bilinear
/// where a texel is at most a pixel, else the mean of the pixels within
/// it.
fn sample(photo: &impl PhotoPixels, [u, v]: [f64; 2], pixels: [f64; 2]) -> Rgb {
    let (w, h) = photo.dimensions();
    let (w, h) = (i64::from(w), i64::from(h));
    let pixel = |x: i64, y: i64| -> [f64; 3] {
        photo
            .pixel(x.clamp(0, w - 1) as u32, y.clamp(0, h - 1) as u32)
            .map(f64::from)
    };
    let color = if pixels[0] > 1.0 || pixels[1] > 1.0 {
        let half = pixels.map(|p| p / 2.0);
        let (x0, x1) = (
            (u - half[0] + 0.5).floor() as i64,
            (u + half[0] - 0.5).ceil() as i64,
        );
        let (y0, y1) = (
            (v - half[1] + 0.5).floor() as i64,
            (v + half[1] - 0.5).ceil() as i64,
        );
        let (mut sum, mut n) = ([0.0; 3], 0.0);
        for y in y0..=y1.max(y0) {
            for x in x0..=x1.max(x0) {
                let p = pixel(x, y);
                (0..3).for_each(|c| sum[c] += p[c]);
                n += 1.0;
            }
        }
        sum.map(|s| s / n)
    } else {
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = (u - x0, v - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let corners = [
            pixel(x0, y0),
            pixel(x0 + 1, y0),
            pixel(x0, y0 + 1),
            pixel(x0 + 1, y0 + 1),
        ];
        super::bilinear(corners, fx, fy)
    };
    color.map(|v| v.round().clamp(0.0, 255.0) as u8)
}

impl PhotoDetail {
    /// `photo` over a `width` × `depth` height grid, kept finer when it
    /// has more than 1.5 pixels a grid spacing on both axes; `None` when
    /// it has fewer.
    pub fn from_photo(photo: &RgbImage, width: u32, depth: u32) -> Option<Self> {
        let stretched = StretchedPhoto::new(photo.dimensions(), (width, depth))?;
        let texels = (0..depth)
            .flat_map(|gy| stretched.texel_rows(gy, photo))
            .collect();
        Some(Self {
            shift: stretched.shift,
            origin: [0, 0],
            size: [width, depth],
            texels,
        })
    }

    /// `photo`, lying at `photo_at`, over the grid of `width` × `depth`
    /// points lying at `grid_at`, kept finer where it has more than 1.5
    /// pixels a grid spacing ([`PlacedPhoto`], row by row). `None` when
    /// the photo is not finer or covers no point's center.
    pub fn placed(
        photo: &RgbImage,
        photo_at: &GeoRef,
        grid_at: &GeoRef,
        (width, depth): (u32, u32),
        colors: &[Rgb],
    ) -> Option<Self> {
        let placed = PlacedPhoto::new(photo.dimensions(), photo_at, grid_at, (width, depth))?;
        let rows = placed.origin[1]..placed.origin[1] + placed.size[1];
        let texels = rows
            .flat_map(|gy| {
                let row = &colors[(gy * width) as usize..][..width as usize];
                placed.texel_rows(gy, row, photo)
            })
            .collect();
        Some(Self {
            shift: placed.shift,
            origin: placed.origin,
            size: placed.size,
            texels,
        })
    }

    /// Writes the mean of each of its grid points' texels into `colors`
    /// (the grid's, `width` a row) over its rectangle.
    pub fn reduce_into(&self, colors: &mut [Rgb], width: u32) {
        let w = self.size[0] as usize;
        for (i, mean) in self.grid_colors().into_iter().enumerate() {
            let (x, y) = (
                self.origin[0] as usize + i % w,
                self.origin[1] as usize + i / w,
            );
            colors[y * width as usize + x] = mean;
        }
    }

    /// Texels a row.
    fn row(&self) -> usize {
        (self.size[0] << self.shift) as usize
    }

    /// The height grid's colors: each point the rounded mean of its
    /// `2^shift × 2^shift` texels (as the kernel's coarsest fine level).
    pub fn grid_colors(&self) -> Vec<Rgb> {
        let band = self.row() << self.shift;
        self.texels
            .chunks_exact(band)
            .flat_map(|texels| block_means(texels, self.shift, self.size[0]))
            .collect()
    }

    /// The bilinear color at world point `(x, y)` (voxels), from the
    /// texels around it (the last row and column repeat at the edge);
    /// `None` outside the voxels of its rectangle (as the kernel's
    /// `Detail::color`).
    pub fn color_at(&self, x: f64, y: f64) -> Option<[f64; 3]> {
        let scale = f64::from(1u32 << self.shift);
        let (tw, td) = (self.row(), self.texels.len() / self.row());
        let at = |v: f64, origin: u32, n: usize| -> Option<(usize, usize, f64)> {
            let t = (v - f64::from(origin) + 0.5) * scale - 0.5;
            if t < -0.5 || t >= n as f64 - 0.5 {
                return None;
            }
            let t = t.clamp(0.0, (n - 1) as f64);
            let i = (t.floor() as usize).min(n - 1);
            Some((i, (i + 1).min(n - 1), t - i as f64))
        };
        let (x0, x1, fx) = at(x, self.origin[0], tw)?;
        let (y0, y1, fy) = at(y, self.origin[1], td)?;
        let texel = |x: usize, y: usize| self.texels[y * tw + x].map(f64::from);
        Some(super::bilinear(
            [texel(x0, y0), texel(x1, y0), texel(x0, y1), texel(x1, y1)],
            fx,
            fy,
        ))
    }

    /// The texels of all the kernel's fine levels, level 0 (these) first
    /// and the coarser ones built ([`Detail::build_levels`]).
    pub fn kernel_levels(&self) -> Vec<Rgb> {
        let mut levels = vec![[0; 3]; detail_points(self.size[0], self.size[1], self.shift)];
        levels[..self.texels.len()].copy_from_slice(&self.texels);
        Detail::build_levels(self.size, self.shift, &mut levels)
            .expect("a photo detail's shift and size are within the kernel's limits");
        levels
    }

    /// Bytes of its texels.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(self.texels.as_slice())
    }
}

/// The rounded mean of each of `points` blocks of `2^shift × 2^shift`
/// texels side by side in `texels` (`2^shift` rows of `points << shift`):
/// a row of grid points' colors from their texels.
pub fn block_means(texels: &[Rgb], shift: u32, points: u32) -> Vec<Rgb> {
    let side = 1usize << shift;
    let row = (points as usize) << shift;
    let n = (side * side) as u32;
    (0..points as usize)
        .map(|x| {
            core::array::from_fn(|c| {
                let sum: u32 = (0..side * side)
                    .map(|k| u32::from(texels[(k / side) * row + x * side + k % side][c]))
                    .sum();
                ((sum + n / 2) / n) as u8
            })
        })
        .collect()
}

/// A photo stretched over the whole map and kept finer than the grid
/// (see [`PhotoDetail::from_photo`]), its texels made a grid row at a
/// time: the photo's pixels cover the map's voxels by area, `2^shift`
/// texels a grid spacing, each texel the photo at its center.
#[derive(Debug, Clone, Copy)]
pub struct StretchedPhoto {
    /// Texels a grid spacing on each side: `2^shift`.
    pub shift: u32,
    /// The grid's points along x.
    width: u32,
    /// Photo pixels a texel on each axis.
    pixels_a_texel: [f64; 2],
}

impl StretchedPhoto {
    /// A photo of `photo_size` pixels over a `width` × `depth` grid, kept
    /// finer when it has more than 1.5 pixels a grid spacing on both
    /// axes; `None` when it has fewer.
    pub fn new(photo_size: (u32, u32), (width, depth): (u32, u32)) -> Option<Self> {
        let (cw, cd) = photo_size;
        let ratio = (f64::from(cw) / f64::from(width)).min(f64::from(cd) / f64::from(depth));
        if ratio <= LEAST_RATIO {
            return None;
        }
        let shift = shift_for(ratio);
        let (tw, td) = (width << shift, depth << shift);
        Some(Self {
            shift,
            width,
            pixels_a_texel: [f64::from(cw) / f64::from(tw), f64::from(cd) / f64::from(td)],
        })
    }

    /// The photo rows [`StretchedPhoto::texel_rows`] reads for grid row
    /// `gy`.
    pub fn photo_rows(&self, gy: u32) -> (i64, i64) {
        let sy = self.pixels_a_texel[1];
        let side = f64::from(1u32 << self.shift);
        let first = f64::from(gy) * side;
        let (a, b) = ((first + 0.5) * sy - 0.5, (first + side - 0.5) * sy - 0.5);
        let margin = sy / 2.0 + 2.0;
        ((a - margin).floor() as i64, (b + margin).ceil() as i64)
    }

    /// The `2^shift` texel rows of grid row `gy`, `width << shift`
    /// texels each, one after the other.
    pub fn texel_rows(&self, gy: u32, photo: &impl PhotoPixels) -> Vec<Rgb> {
        let [sx, sy] = self.pixels_a_texel;
        let (side, tw) = (1u32 << self.shift, self.width << self.shift);
        let mut texels = Vec::with_capacity((side * tw) as usize);
        for ty in gy * side..(gy + 1) * side {
            // The texel's center in photo pixels.
            let v = (f64::from(ty) + 0.5) * sy - 0.5;
            for tx in 0..tw {
                let u = (f64::from(tx) + 0.5) * sx - 0.5;
                texels.push(sample(photo, [u, v], [sx, sy]));
            }
        }
        texels
    }
}

/// Where a photo placed by its georeference is kept finer than the grid
/// (see [`PhotoDetail::placed`]), and how its texels are made, a grid
/// row at a time: over the grid points whose centers it covers, at the
/// power of two at or above its pixels a spacing (at most 32), each texel
/// the photo at its center (bilinear, or past 32 the mean of the pixels it
/// covers), a texel past the photo's edge its grid point's color.
#[derive(Debug, Clone, Copy)]
pub struct PlacedPhoto {
    /// Texels a grid spacing on each side: `2^shift`.
    pub shift: u32,
    /// The first grid point the texels cover.
    pub origin: [u32; 2],
    /// Grid points along x and y the texels cover.
    pub size: [u32; 2],
    photo_at: GeoRef,
    grid_at: GeoRef,
    /// The photo's pixels a row, and rows.
    photo_size: (u32, u32),
    /// Photo pixels a texel on each axis.
    pixels_a_texel: [f64; 2],
}

impl PlacedPhoto {
    /// A photo of `photo_size` pixels lying at `photo_at` over the grid of
    /// `width` × `depth` points lying at `grid_at` (both pixel-is-area, as
    /// [`super::geotiff::drape`] places them); `None` when the photo is
    /// not finer than the grid or covers no point's center.
    pub fn new(
        photo_size: (u32, u32),
        photo_at: &GeoRef,
        grid_at: &GeoRef,
        (width, depth): (u32, u32),
    ) -> Option<Self> {
        let ratio =
            (grid_at.pixel[0] / photo_at.pixel[0]).min(grid_at.pixel[1] / photo_at.pixel[1]);
        if ratio.is_nan() || ratio <= LEAST_RATIO {
            return None;
        }
        let shift = shift_for(ratio);
        let (pw, ph) = (f64::from(photo_size.0), f64::from(photo_size.1));
        let x_of = |u: f64| photo_at.pixel_in(grid_at, [u, 0.0])[0];
        let y_of = |v: f64| photo_at.pixel_in(grid_at, [0.0, v])[1];
        let span = |low: f64, high: f64, n: u32| -> Option<(u32, u32)> {
            let first = low.ceil().max(0.0);
            let last = high.floor().min(f64::from(n) - 1.0);
            (first <= last).then_some((first as u32, last as u32))
        };
        let (x0, x1) = span(x_of(-0.5), x_of(pw - 0.5), width)?;
        let (y0, y1) = span(y_of(-0.5), y_of(ph - 0.5), depth)?;
        let scale = f64::from(1u32 << shift);
        Some(Self {
            shift,
            origin: [x0, y0],
            size: [x1 - x0 + 1, y1 - y0 + 1],
            photo_at: *photo_at,
            grid_at: *grid_at,
            photo_size,
            pixels_a_texel: [0, 1].map(|i| grid_at.pixel[i] / scale / photo_at.pixel[i]),
        })
    }

    /// Whether grid row `gy` has texels.
    pub fn covers_row(&self, gy: u32) -> bool {
        (self.origin[1]..self.origin[1] + self.size[1]).contains(&gy)
    }

    /// The photo rows [`PlacedPhoto::texel_rows`] reads for grid row `gy`.
    pub fn photo_rows(&self, gy: u32) -> (i64, i64) {
        let v_of = |y: f64| self.grid_at.pixel_in(&self.photo_at, [0.0, y])[1];
        let (a, b) = (v_of(f64::from(gy) - 0.5), v_of(f64::from(gy) + 0.5));
        let margin = self.pixels_a_texel[1] / 2.0 + 2.0;
        (
            (a.min(b) - margin).floor() as i64,
            (a.max(b) + margin).ceil() as i64,
        )
    }

    /// The `2^shift` texel rows of grid row `gy` (one of those it
    /// covers), `size[0] << shift` texels each, one after the other;
    /// `colors` is the grid row's colors (a texel past the photo's edge
    /// takes its point's).
    pub fn texel_rows(&self, gy: u32, colors: &[Rgb], photo: &impl PhotoPixels) -> Vec<Rgb> {
        let scale = f64::from(1u32 << self.shift);
        let (pw, ph) = (f64::from(self.photo_size.0), f64::from(self.photo_size.1));
        let u_of = |x: f64| self.grid_at.pixel_in(&self.photo_at, [x, 0.0])[0];
        let v_of = |y: f64| self.grid_at.pixel_in(&self.photo_at, [0.0, y])[1];
        let [x0, y0] = self.origin;
        let (side, tw) = (1u32 << self.shift, self.size[0] << self.shift);
        let mut texels = Vec::with_capacity((side * tw) as usize);
        for ty in (gy - y0) * side..(gy - y0 + 1) * side {
            let y = f64::from(y0) + (f64::from(ty) + 0.5) / scale - 0.5;
            let v = v_of(y);
            for tx in 0..tw {
                let x = f64::from(x0) + (f64::from(tx) + 0.5) / scale - 0.5;
                let u = u_of(x);
                if u < -0.5 || u > pw - 0.5 || v < -0.5 || v > ph - 0.5 {
                    texels.push(colors[x.round() as usize]);
                } else {
                    texels.push(sample(photo, [u, v], self.pixels_a_texel));
                }
            }
        }
        texels
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_photo_twice_the_grid_is_kept_pixel_for_pixel_and_the_grid_is_its_mean() {
        let photo = RgbImage::from_fn(8, 6, |x, y| image::Rgb([(x * 30) as u8, (y * 40) as u8, 9]));
        let detail = PhotoDetail::from_photo(&photo, 4, 3).unwrap();
        assert_eq!((detail.shift, detail.size), (1, [4, 3]));
        assert_eq!(
            detail.texels,
            photo.pixels().map(|p| p.0).collect::<Vec<_>>()
        );
        let grid = detail.grid_colors();
        // Point (1, 2): pixels 2..4 by 4..6.
        assert_eq!(grid[2 * 4 + 1], [75, 180, 9]);
        // A texel's center is that pixel; a grid point the mean around it.
        assert_eq!(
            detail
                .color_at(0.25, 0.75)
                .unwrap()
                .map(|v| v.round() as u8),
            [30, 80, 9]
        );
        assert_eq!(
            detail.color_at(1.0, 2.0).unwrap().map(|v| v.round() as u8),
            [75, 180, 9]
        );
    }

    #[test]
    fn the_power_of_two_is_the_one_at_or_above_the_photos_and_at_most_32() {
        let shift_for = |cw: u32| {
            let photo = RgbImage::new(cw, cw);
            PhotoDetail::from_photo(&photo, 4, 4).map(|d| d.shift)
        };
        assert_eq!(shift_for(4), None);
        assert_eq!(shift_for(6), None);
        assert_eq!(shift_for(7), Some(1));
        assert_eq!(shift_for(12), Some(2));
        assert_eq!(shift_for(16), Some(2));
        assert_eq!(shift_for(17), Some(3));
        assert_eq!(shift_for(4 * 35), Some(5));
        // Resampled down past 32: a uniform photo stays uniform.
        let photo = RgbImage::from_pixel(4 * 35, 4 * 35, image::Rgb([10, 20, 30]));
        let detail = PhotoDetail::from_photo(&photo, 4, 4).unwrap();
        assert_eq!(detail.texels.len(), 128 * 128);
        assert!(detail.texels.iter().all(|&t| t == [10, 20, 30]));
    }

    #[test]
    fn the_kernels_levels_start_with_the_texels_and_end_with_the_grids_colors() {
        let photo = RgbImage::from_fn(16, 16, |x, y| {
            image::Rgb([(x * 15) as u8, (y * 15) as u8, ((x + y) * 7) as u8])
        });
        let detail = PhotoDetail::from_photo(&photo, 4, 4).unwrap();
        let levels = detail.kernel_levels();
        assert_eq!(&levels[..256], detail.texels.as_slice());
        let grid = detail.grid_colors();
        // The last level, a texel a point: within rounding of the mean.
        for (kernel, host) in levels[levels.len() - 16..].iter().zip(&grid) {
            for c in 0..3 {
                assert!(kernel[c].abs_diff(host[c]) <= 1, "{kernel:?} {host:?}");
            }
        }
    }
}
