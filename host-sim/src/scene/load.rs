//! Height and color maps from files.
//!
//! Heights: 8- or 16-bit grayscale PNG (any PNG is converted to luma), or an
//! SRTM `.hgt` tile (square, big-endian `i16` meters; voids, −32768, become
//! 0). Colors: RGB, RGBA, gray or palette PNG.

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
    let image = open_image(path, "height map")?;
    let (w, h) = (image.width(), image.height());
    let values: Vec<f32> = match image {
        DynamicImage::ImageLuma8(_)
        | DynamicImage::ImageLumaA8(_)
        | DynamicImage::ImageRgb8(_)
        | DynamicImage::ImageRgba8(_) => image
            .to_luma8()
            .into_raw()
            .into_iter()
            .map(f32::from)
            .collect(),
        _ => image
            .to_luma16()
            .into_raw()
            .into_iter()
            .map(f32::from)
            .collect(),
    };
    Ok((w, h, values.into_iter().map(|v| v * scale).collect()))
}

fn load_hgt(path: &Path, scale: f32) -> Result<(u32, u32, Vec<f32>)> {
    let bytes = std::fs::read(path)
        .map_err(|e| Error::new(format!("cannot read height map {}: {e}", path.display())))?;
    let samples = bytes.len() / 2;
    let side = (samples as f64).sqrt() as usize;
    if bytes.len() % 2 != 0 || side * side != samples || side < 2 {
        return Err(Error::new(format!(
            "{} is not an SRTM .hgt tile: {} bytes is not a square grid of 16-bit samples",
            path.display(),
            bytes.len()
        )));
    }
    let heights = bytes
        .chunks_exact(2)
        .map(|b| match i16::from_be_bytes([b[0], b[1]]) {
            i16::MIN => 0.0,
            v => f32::from(v) * scale,
        })
        .collect();
    Ok((side as u32, side as u32, heights))
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
    let image = open_image(path, "color map")?.to_rgb8();
    let (cw, cd) = image.dimensions();
    if (cw, cd) == (width, depth) {
        return Ok(image.pixels().map(|p| p.0).collect());
    }
    if cw < 2 || cd < 2 {
        return Err(Error::new(format!(
            "color map {} is {cw}x{cd}: too small to stretch over a {width}x{depth} height map",
            path.display()
        )));
    }
    let sx = f64::from(cw - 1) / f64::from(width - 1);
    let sy = f64::from(cd - 1) / f64::from(depth - 1);
    let pixel = |x: i64, y: i64| {
        let p = image.get_pixel(
            x.clamp(0, i64::from(cw) - 1) as u32,
            y.clamp(0, i64::from(cd) - 1) as u32,
        );
        [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]
    };
    let mut out = Vec::with_capacity(width as usize * depth as usize);
    for gy in 0..depth {
        for gx in 0..width {
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
    }
    Ok(out)
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
