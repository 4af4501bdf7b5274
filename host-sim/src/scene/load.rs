//! Height and color maps from files.
//!
//! Heights: 8- or 16-bit grayscale PNG (any PNG is converted to luma), an
//! SRTM `.hgt` tile (square, big-endian `i16` meters), or a single-band
//! GeoTIFF ([`super::geotiff`]). Voids (an `.hgt`'s −32768, a GeoTIFF's
//! no-data value) are filled from their neighbours ([`fill_voids`]), and
//! one line says how many. Colors: RGB, RGBA, gray or palette PNG, or an
//! 8-bit gray, RGB or RGBA TIFF.

use crate::error::{Error, Result};
use image::{DynamicImage, ImageReader};
use std::path::Path;
use terracast::Rgb;

/// Loads a height map: `(width, depth, heights)` with heights = value × scale.
pub fn load_heights(path: &Path, scale: f32) -> Result<(u32, u32, Vec<f32>)> {
    if !scale.is_finite() || scale <= 0.0 {
        return Err(Error::new(format!(
            "--height-scale must be a positive number, got {scale}"
        )));
    }
    let is_hgt = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("hgt"));
    if is_hgt {
        return load_hgt(path, scale);
    }
    if super::geotiff::is_tiff(path) {
        let mut raster = super::geotiff::read_heights(path)?;
        fill_voids(path, raster.width, raster.depth, &mut raster.values)?;
        let heights = raster.values.into_iter().map(|v| v * scale).collect();
        return Ok((raster.width, raster.depth, heights));
    }
    let image = open_image(path, "height map")?;
    let (w, h) = (image.width(), image.height());
    let values: Vec<f32> = match image {
        DynamicImage::ImageLuma8(_) | DynamicImage::ImageLumaA8(_) => image
            .to_luma8()
            .into_raw()
            .into_iter()
            .map(f32::from)
            .collect(),
        DynamicImage::ImageLuma16(_) | DynamicImage::ImageLumaA16(_) => image
            .to_luma16()
            .into_raw()
            .into_iter()
            .map(f32::from)
            .collect(),
        other => return Err(not_a_height_map(path, &format!("{:?}", other.color()))),
    };
    Ok((w, h, values.into_iter().map(|v| v * scale).collect()))
}

/// The one refusal of a height map that is not grayscale (`kind` says what
/// it is): every command that reads heights says the same.
pub fn not_a_height_map(path: &Path, kind: &str) -> Error {
    Error::new(format!(
        "height map {} is {kind}: a height map is an 8- or 16-bit grayscale PNG or an SRTM .hgt (convert a color image to grayscale first)",
        path.display()
    ))
}

/// The side of an SRTM `.hgt` tile of `bytes` bytes (a square grid of
/// big-endian 16-bit samples), or why it is not one.
pub fn hgt_side(path: &Path, bytes: u64) -> Result<u32> {
    let samples = bytes / 2;
    let side = (samples as f64).sqrt() as u64;
    if bytes % 2 != 0 || side * side != samples || side < 2 || side > u64::from(u32::MAX) {
        return Err(Error::new(format!(
            "{} is not an SRTM .hgt tile: {bytes} bytes is not a square grid of 16-bit samples",
            path.display(),
        )));
    }
    Ok(side as u32)
}

/// An `.hgt` sample's height: its big-endian value, NaN for a void
/// (−32768).
pub fn hgt_height(sample: [u8; 2]) -> f32 {
    match i16::from_be_bytes(sample) {
        i16::MIN => f32::NAN,
        v => f32::from(v),
    }
}

fn load_hgt(path: &Path, scale: f32) -> Result<(u32, u32, Vec<f32>)> {
    let bytes = std::fs::read(path)
        .map_err(|e| Error::new(format!("cannot read height map {}: {e}", path.display())))?;
    let side = hgt_side(path, bytes.len() as u64)? as usize;
    let mut heights: Vec<f32> = bytes
        .chunks_exact(2)
        .map(|b| hgt_height([b[0], b[1]]))
        .collect();
    fill_voids(path, side as u32, side as u32, &mut heights)?;
    Ok((
        side as u32,
        side as u32,
        heights.into_iter().map(|h| h * scale).collect(),
    ))
}

/// Fills the voids (NaN) of a `width` × `depth` height grid from their
/// valid neighbours ([`super::voids`]: ring by ring from the edges of each
/// void inward, each point the mean of its known neighbours, so no filled
/// height lies below the lowest valid height around its void). Says on
/// one line how many were filled; refuses a grid that is mostly void.
/// Returns the count.
pub fn fill_voids(path: &Path, width: u32, depth: u32, heights: &mut [f32]) -> Result<usize> {
    let voids = heights.iter().filter(|h| h.is_nan()).count();
    if voids == 0 {
        return Ok(0);
    }
    refuse_mostly_void(path, voids as u64, heights.len() as u64)?;
    let cells = width as usize * depth as usize;
    let grid = heights.get_mut(..cells).unwrap_or_default();
    let (filled, _) = super::voids::VoidFill::fill_grid(width as usize, grid);
    grid.copy_from_slice(&filled);
    report_filled(path, voids as u64, heights.len() as u64);
    Ok(voids)
}

/// Refuses a height map with more void samples than valid ones.
pub fn refuse_mostly_void(path: &Path, voids: u64, total: u64) -> Result<()> {
    if voids * 2 > total {
        return Err(Error::new(format!(
            "height map {} is mostly void: {voids} of its {total} samples have no data",
            path.display()
        )));
    }
    Ok(())
}

/// Says on one line how many void samples were filled.
pub fn report_filled(path: &Path, voids: u64, total: u64) {
    eprintln!(
        "{}: filled {voids} void samples ({:.1} %) from their neighbours",
        path.display(),
        100.0 * voids as f64 / total as f64
    );
}

/// Loads a color map and fits it to a `width` × `depth` height grid.
///
/// Same size: color pixel (i, j) is the color of grid point (i, j). Other
/// sizes: the color image is stretched over the same world extent with its
/// corner pixel centers on the corner grid points, i.e. grid point (x, y)
/// takes the color image at `(x·(Cw−1)/(W−1), y·(Cd−1)/(D−1))`, averaged over
/// the grid spacing when the image is finer (box filter) and bilinear when
/// it is coarser.
pub fn load_colors(path: &Path, width: u32, depth: u32) -> Result<Vec<Rgb>> {
    stretch_colors(&read_color_map(path)?, path, width, depth)
}

/// The photo or color map at `path` (PNG or any format `image` reads, or a
/// GeoTIFF).
pub fn read_color_map(path: &Path) -> Result<image::RgbImage> {
    if super::geotiff::is_tiff(path) {
        super::geotiff::read_photo(path)
    } else {
        Ok(open_image(path, "color map")?.to_rgb8())
    }
}

/// `image` (read from `path`) stretched over a `width` × `depth` height
/// grid, its corners on the grid's (see [`load_colors`]).
pub fn stretch_colors(
    image: &image::RgbImage,
    path: &Path,
    width: u32,
    depth: u32,
) -> Result<Vec<Rgb>> {
    let stretch = Stretch::new(image.dimensions(), path, (width, depth))?;
    Ok((0..depth).flat_map(|gy| stretch.row(gy, image)).collect())
}

/// A color map stretched over a height grid, a grid row at a time (see
/// [`load_colors`]).
#[derive(Debug, Clone, Copy)]
pub struct Stretch {
    image: (u32, u32),
    width: u32,
    /// Color pixels a grid spacing, corner to corner.
    scale: [f64; 2],
}

impl Stretch {
    /// A `image`-sized color map (read from `path`) over a `width` ×
    /// `depth` grid; refused when it is too small to stretch.
    pub fn new(image: (u32, u32), path: &Path, (width, depth): (u32, u32)) -> Result<Self> {
        let (cw, cd) = image;
        if (cw, cd) != (width, depth) && (cw < 2 || cd < 2) {
            return Err(Error::new(format!(
                "color map {} is {cw}x{cd}: too small to stretch over a {width}x{depth} height map",
                path.display()
            )));
        }
        Ok(Self {
            image,
            width,
            scale: [
                f64::from(cw.saturating_sub(1)) / f64::from(width - 1),
                f64::from(cd.saturating_sub(1)) / f64::from(depth - 1),
            ],
        })
    }

    /// The color rows [`Stretch::row`] reads for grid row `gy`.
    pub fn image_rows(&self, gy: u32) -> (i64, i64) {
        let cy = f64::from(gy) * self.scale[1];
        let reach = (self.scale[1] / 2.0).max(0.5) + 1.0;
        ((cy - reach).floor() as i64, (cy + reach).ceil() as i64)
    }

    /// Grid row `gy`'s colors.
    pub fn row(&self, gy: u32, image: &impl super::geotiff::PhotoPixels) -> Vec<Rgb> {
        let (cw, cd) = self.image;
        if self.scale == [1.0, 1.0] {
            // The same size: a pixel a point.
            return (0..cw).map(|x| image.pixel(x, gy)).collect();
        }
        let [sx, sy] = self.scale;
        let pixel = |x: i64, y: i64| {
            let p = image.pixel(
                x.clamp(0, i64::from(cw) - 1) as u32,
                y.clamp(0, i64::from(cd) - 1) as u32,
            );
            [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]
        };
        let mut out = Vec::with_capacity(self.width as usize);
        for gx in 0..self.width {
            let (cx, cy) = (f64::from(gx) * sx, f64::from(gy) * sy);
            let color = if sx > 1.0 || sy > 1.0 {
                // Box filter: every color pixel within half a grid spacing.
                let (rx, ry) = ((sx / 2.0).max(0.5), (sy / 2.0).max(0.5));
                let (x0, x1) = ((cx - rx).ceil() as i64, (cx + rx).floor() as i64);
                let (y0, y1) = ((cy - ry).ceil() as i64, (cy + ry).floor() as i64);
                let mut sum = [0.0; 3];
                let mut n = 0.0;
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let p = pixel(x, y);
                        (0..3).for_each(|i| sum[i] += p[i]);
                        n += 1.0;
                    }
                }
                sum.map(|s| s / n)
            } else {
                let (x0, y0) = (cx.floor(), cy.floor());
                let (fx, fy) = (cx - x0, cy - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let (a, b, c, d) = (
                    pixel(x0, y0),
                    pixel(x0 + 1, y0),
                    pixel(x0, y0 + 1),
                    pixel(x0 + 1, y0 + 1),
                );
                core::array::from_fn(|i| {
                    (a[i] * (1.0 - fx) + b[i] * fx) * (1.0 - fy)
                        + (c[i] * (1.0 - fx) + d[i] * fx) * fy
                })
            };
            out.push(color.map(|v| v.round().clamp(0.0, 255.0) as u8));
        }
        out
    }
}

fn open_image(path: &Path, what: &str) -> Result<DynamicImage> {
    let reader = ImageReader::open(path)
        .map_err(|e| Error::new(format!("cannot open {what} {}: {e}", path.display())))?
        .with_guessed_format()
        .map_err(|e| Error::new(format!("cannot read {what} {}: {e}", path.display())))?;
    reader
        .decode()
        .map_err(|e| Error::new(format!("cannot decode {what} {}: {e}", path.display())))
}

/// The height scale a map's own georeference gives (an SRTM `.hgt`'s
/// grid spacing, a GeoTIFF's pixel size) and one line saying what it
/// chose; `None` for a map without one (a PNG, a TIFF without a
/// georeference, which also gets a line).
pub fn derived_height_scale(path: &Path) -> Result<Option<(f32, String)>> {
    if let Some(spacing) = hgt_spacing(path)? {
        return Ok(Some((spacing.height_scale(), spacing.describe())));
    }
    if !super::geotiff::is_tiff(path) {
        return Ok(None);
    }
    Ok(match super::geotiff::height_scale(path)? {
        Ok(scale) => Some(scale),
        Err(why) => {
            eprintln!(
                "{} is not georeferenced ({why}): its heights are taken as voxels (--height-scale to change)",
                path.display()
            );
            None
        }
    })
}

/// Meters along one arc-second of latitude (and of longitude at the
/// equator).
const METERS_PER_ARC_SECOND: f64 = 30.87;

/// The ground spacing of an SRTM `.hgt` tile's grid, from its sample count
/// and the latitude in its name (`N44W072…`: the tile's south edge).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HgtSpacing {
    /// Arc-seconds between samples: 3600 / (side − 1).
    pub arc_seconds: f64,
    /// Latitude of the tile's middle in degrees, when the name gives it.
    pub latitude: Option<f64>,
    /// Meters between samples east-west.
    pub east_m: f64,
    /// Meters between samples north-south.
    pub north_m: f64,
}

impl HgtSpacing {
    /// Meters one voxel spans: the mean of the two spacings (the kernel's
    /// voxels are square; the tile's are not, away from the equator).
    pub fn meters_per_voxel(&self) -> f64 {
        0.5 * (self.east_m + self.north_m)
    }

    /// The height scale that puts meters into voxels.
    pub fn height_scale(&self) -> f32 {
        (1.0 / self.meters_per_voxel()) as f32
    }

    /// One line saying what was chosen and why.
    pub fn describe(&self) -> String {
        let at = match self.latitude {
            Some(lat) => format!("at latitude {lat:.1}"),
            None => "at the equator (no latitude in the file name)".to_owned(),
        };
        format!(
            "height scale 1/{:.1}: {} arc-second samples {at} are {:.1} m east-west and {:.1} m north-south; --height-scale overrides",
            self.meters_per_voxel(),
            self.arc_seconds,
            self.east_m,
            self.north_m
        )
    }
}

/// The grid spacing of an `.hgt` height map, or `None` for any other file.
pub fn hgt_spacing(path: &Path) -> Result<Option<HgtSpacing>> {
    let is_hgt = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("hgt"));
    if !is_hgt {
        return Ok(None);
    }
    let length = std::fs::metadata(path)
        .map_err(|e| Error::new(format!("cannot read height map {}: {e}", path.display())))?
        .len();
    let side = ((length / 2) as f64).sqrt().round();
    if side < 2.0 {
        return Ok(None);
    }
    let arc_seconds = 3600.0 / (side - 1.0);
    let latitude = path
        .file_name()
        .and_then(|n| n.to_str())
        .and_then(latitude_from_name);
    let north_m = arc_seconds * METERS_PER_ARC_SECOND;
    let east_m = north_m * latitude.unwrap_or(0.0).to_radians().cos();
    Ok(Some(HgtSpacing {
        arc_seconds,
        latitude,
        east_m,
        north_m,
    }))
}

/// The middle latitude of a tile named `N44…` or `S34…` (SRTM names a
/// tile by its south-west corner).
fn latitude_from_name(name: &str) -> Option<f64> {
    let sign = match name.as_bytes().first()? {
        b'N' | b'n' => 1.0,
        b'S' | b's' => -1.0,
        _ => return None,
    };
    let digits: String = name[1..].chars().take_while(char::is_ascii_digit).collect();
    let south_edge = sign * digits.parse::<f64>().ok()?;
    (digits.len() == 2 && south_edge.abs() < 90.0).then_some(south_edge + 0.5)
}

#[cfg(test)]
mod tests {
    #[test]
    fn voids_are_filled_from_their_neighbours_without_pits() {
        // A 6 × 5 slope with a 3 × 2 hole and a void at a corner.
        let (w, d) = (6u32, 5u32);
        let mut heights: Vec<f32> = (0..w * d).map(|i| (i % w * 10 + i / w) as f32).collect();
        for (x, y) in [(2, 1), (3, 1), (4, 1), (2, 2), (3, 2), (4, 2), (0, 0)] {
            heights[(y * w + x) as usize] = f32::NAN;
        }
        let filled = fill_voids(Path::new("slope.tif"), w, d, &mut heights).unwrap();
        assert_eq!(filled, 7);
        assert!(heights.iter().all(|h| h.is_finite()));
        // Inside the hole's ring of known heights: no pit, no peak.
        let ring = [
            (1, 0),
            (2, 0),
            (3, 0),
            (4, 0),
            (5, 0),
            (1, 1),
            (5, 1),
            (1, 2),
            (5, 2),
        ]
        .into_iter()
        .chain([(1, 3), (2, 3), (3, 3), (4, 3), (5, 3)])
        .map(|(x, y)| heights[y * w as usize + x]);
        let (low, high) = ring.fold((f32::MAX, f32::MIN), |(a, b), h| (a.min(h), b.max(h)));
        for (x, y) in [(2, 1), (3, 1), (4, 1), (2, 2), (3, 2), (4, 2)] {
            let h = heights[y * w as usize + x];
            assert!((low..=high).contains(&h), "{h} outside {low}..{high}");
        }
        // No voids: nothing to do. Mostly void: refused in one line.
        assert_eq!(fill_voids(Path::new("x"), w, d, &mut heights).unwrap(), 0);
        let mut holes = vec![f32::NAN; 30];
        holes[0] = 1.0;
        let e = fill_voids(Path::new("void.tif"), w, d, &mut holes).unwrap_err();
        assert!(e.to_string().contains("mostly void: 29 of its 30"), "{e}");
    }

    use super::*;

    #[test]
    fn an_srtm_tile_gets_its_grid_spacing_by_latitude() {
        assert_eq!(latitude_from_name("N44W072_3arcsec.hgt"), Some(44.5));
        assert_eq!(latitude_from_name("S34E020.hgt"), Some(-33.5));
        assert_eq!(latitude_from_name("tile.hgt"), None);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("N60E010.hgt");
        std::fs::write(&path, vec![0u8; 1201 * 1201 * 2]).unwrap();
        let spacing = hgt_spacing(&path).unwrap().unwrap();
        assert_eq!(spacing.arc_seconds, 3.0);
        assert!((spacing.north_m - 92.61).abs() < 0.01);
        // cos 60.5° ≈ 0.492.
        assert!((spacing.east_m / spacing.north_m - 0.4924).abs() < 0.001);
        assert!(spacing.describe().contains("latitude 60.5"));
        assert_eq!(hgt_spacing(Path::new("h.png")).unwrap(), None);
    }
}
