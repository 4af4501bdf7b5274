//! Files a render writes: PNG image, PFM depth, JSON stats.

use crate::error::{Error, Result};
use crate::frame::{Frame, RenderStats};
use std::io::Write;
use std::path::Path;

/// Writes the frame's colors as an 8-bit RGB PNG.
pub fn write_png(path: &Path, frame: &Frame) -> Result<()> {
    let raw: Vec<u8> = frame.colors.iter().flatten().copied().collect();
    let image = image::RgbImage::from_raw(frame.width, frame.height, raw)
        .ok_or_else(|| Error::new("frame buffer does not match its size"))?;
    image
        .save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| Error::new(format!("cannot write {}: {e}", path.display())))
}

/// Writes depth as a grayscale little-endian PFM, rows bottom to top.
pub fn write_pfm(path: &Path, frame: &Frame) -> Result<()> {
    let mut bytes = format!("Pf\n{} {}\n-1.0\n", frame.width, frame.height).into_bytes();
    for row in frame.depth.chunks(frame.width as usize).rev() {
        for v in row {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    write_file(path, &bytes)
}

/// Reads a PFM written by [`write_pfm`]: `(width, height, row-major depth
/// with y = 0 at the top)`.
pub fn read_pfm(bytes: &[u8]) -> Result<(u32, u32, Vec<f32>)> {
    let bad = || Error::new("not a grayscale little-endian PFM");
    let mut fields = Vec::new();
    let mut at = 0;
    while fields.len() < 4 {
        while bytes.get(at).is_some_and(u8::is_ascii_whitespace) {
            at += 1;
        }
        let start = at;
        while bytes.get(at).is_some_and(|b| !b.is_ascii_whitespace()) {
            at += 1;
        }
        fields.push(std::str::from_utf8(&bytes[start..at]).map_err(|_| bad())?);
    }
    let (w, h): (u32, u32) = (
        fields[1].parse().map_err(|_| bad())?,
        fields[2].parse().map_err(|_| bad())?,
    );
    if fields[0] != "Pf" || fields[3] != "-1.0" {
        return Err(bad());
    }
    let data = bytes.get(at + 1..).ok_or_else(bad)?;
    if data.len() != w as usize * h as usize * 4 {
        return Err(bad());
    }
    let values: Vec<f32> = data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let depth = values.chunks(w as usize).rev().flatten().copied().collect();
    Ok((w, h, depth))
}

/// The `--stats` object.
pub fn stats_json(
    stats: &RenderStats,
    width: u32,
    height: u32,
    sky_pixels: usize,
) -> serde_json::Value {
    let mut value = serde_json::json!({
        "method": stats.method,
        "width": width,
        "height": height,
        "pixels": stats.pixels,
        "rays": stats.rays,
        "steps": stats.steps,
        "steps_per_pixel": stats.steps as f64 / stats.pixels.max(1) as f64,
        "sky_pixels": sky_pixels,
        "resident_bytes": stats.resident_bytes,
        "render_ns": stats.render_ns,
    });
    if let Some(levels) = &stats.levels {
        value["bound_tests"] = levels.bound_tests.into();
        value["color_fetches"] = levels.color_fetches.into();
        value["secondary_rays"] = levels.secondary_rays.into();
        value["terrain_roughness"] = (f64::from(levels.roughness) / 64.0).into();
        value["terrain_fit"] = (f64::from(levels.terrain_fit) / 65536.0).into();
        if let Some(cost) = &levels.governed {
            value["budget"] = serde_json::json!({
                "budget": cost.budget,
                "cost": cost.cost,
                "base_cost": cost.base_cost,
                "level_bias": cost.level_bias.to_num::<f64>(),
                "coarse_lines": cost.coarse_lines,
                "refined_lines": cost.refined_lines,
                "filled_rays": cost.filled_rays,
            });
        }
        value["levels"] = serde_json::json!({
            "steps": &levels.steps[..levels.levels],
            "hits": &levels.hits[..levels.levels],
        });
    }
    value
}

/// Writes JSON (`--stats`, a report), pretty, with a final newline.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::new(e.to_string()))?;
    write_file(path, format!("{text}\n").as_bytes())
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    let write = || -> std::io::Result<()> {
        let mut file = std::fs::File::create(path)?;
        file.write_all(bytes)?;
        file.sync_all()
    };
    write().map_err(|e| Error::new(format!("cannot write {}: {e}", path.display())))
}
