//! The column caster: each image column bottom to top, one ray after another.
//!
//! With vertical ray coherence on, each ray starts at the sample where the
//! ray below it hit (Cohen-Or §2). Under a pitched pinhole camera the rays of
//! a column are not in one vertical plane, so a resumed ray may start past
//! its own hit: it then retraces backwards to the last sample above the
//! surface (Qu et al. §4). The hit is refined between that sample and the
//! first one below by the ratio of their clearances, and the color is
//! blended across both grid lines.

pub(crate) mod walk;

use crate::probe::Probe;
use crate::sink::{Sample, Sink};
use crate::terrain::Terrain;
use crate::view::ray::{Cursor, Ray, RayKey, Strides};
use crate::view::View;
use crate::{Rgb, config::DEFAULT_SKY};
use walk::{clearance, locate, walk, Walk};

/// Settings of the caster.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderOptions {
    /// Vertical ray coherence: each ray resumes where the ray below it hit.
    /// Off, every ray is cast from the eye (the slow, exact baseline).
    pub coherence: bool,
    /// Color of rays that leave the terrain.
    pub sky: Rgb,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            coherence: true,
            sky: DEFAULT_SKY,
        }
    }
}

/// Renders every column of the view into `sink`.
pub fn render<S: Sink, P: Probe>(
    terrain: &Terrain<'_>,
    view: &View,
    options: &RenderOptions,
    sink: &mut S,
    probe: &mut P,
) {
    for column in 0..view.width() {
        render_column(terrain, view, options, column, sink, probe);
    }
}

/// Renders one image column, bottom to top. Columns are independent: a
/// column pool may hand them to any number of workers.
pub fn render_column<S: Sink, P: Probe>(
    terrain: &Terrain<'_>,
    view: &View,
    options: &RenderOptions,
    column: u32,
    sink: &mut S,
    probe: &mut P,
) {
    let mut resume: Option<(RayKey, i32)> = None;
    let top_row = view.height() - 1;
    for row in 0..view.height() {
        probe.ray();
        let ray = view.ray(terrain, column, row);
        let sample = if ray.start > ray.end {
            sky(options)
        } else {
            let from = match resume {
                Some((key, k)) if options.coherence && key == ray.key => k.clamp(ray.start, ray.end),
                _ => ray.start,
            };
            let (sample, reached) = cast(terrain, &ray, from, options, probe);
            resume = Some((ray.key, reached));
            sample
        };
        sink.put(column, top_row - row, sample);
    }
}

fn sky(options: &RenderOptions) -> Sample {
    Sample {
        color: options.sky,
        distance: Sample::SKY,
        elevation: 0,
    }
}

/// Casts one ray from sample `from`; returns what it saw and the sample it
/// stopped at (where the next ray of the column resumes).
fn cast<P: Probe>(
    terrain: &Terrain<'_>,
    ray: &Ray,
    from: i32,
    options: &RenderOptions,
    probe: &mut P,
) -> (Sample, i32) {
    let heights = terrain.heights();
    let strides = ray.strides(terrain.width());
    let start = ray.cursor(from, &strides);
    match walk(heights, ray, &strides, start, probe) {
        Walk::Exit { last } => (sky(options), last),
        Walk::Hit { at, clearance, above: Some(above) } => {
            (shade(terrain, ray, &strides, at, clearance, Some(above), options, probe), at.k)
        }
        Walk::Hit { at, clearance, above: None } => {
            let (at, clearance, above) = retrace(heights, ray, &strides, at, clearance, probe);
            (shade(terrain, ray, &strides, at, clearance, above, options, probe), at.k)
        }
    }
}

/// The first visited sample was already below the surface: step back while
/// the sample before is below too (never before the ray's start), and report
/// the clearance of the sample above, if there is one in the map.
fn retrace<P: Probe>(
    heights: &[u16],
    ray: &Ray,
    strides: &Strides,
    mut at: Cursor,
    mut below: i32,
    probe: &mut P,
) -> (Cursor, i32, Option<i32>) {
    while at.k > ray.first {
        let before = ray.cursor(at.k - 1, strides);
        let Some((voxel, c)) = clearance(heights, &before, strides) else {
            break;
        };
        probe.visit(voxel);
        if c > 0 {
            return (at, below, Some(c));
        }
        if before.k < ray.start {
            break;
        }
        at = before;
        below = c;
    }
    (at, below, None)
}

/// Colors a hit: the two voxels across the grid line blended by the subvoxel
/// weight, on the hit's grid line and (when known) on the one before,
/// blended by where between them the ray crossed the surface.
#[allow(clippy::too_many_arguments)]
fn shade<P: Probe>(
    terrain: &Terrain<'_>,
    ray: &Ray,
    strides: &Strides,
    hit: Cursor,
    below: i32,
    above: Option<i32>,
    options: &RenderOptions,
    probe: &mut P,
) -> Sample {
    let colors = terrain.colors();
    let Some(on_hit_line) = line_color(colors, &hit, strides, probe) else {
        return sky(options);
    };
    let (color, distance, back) = match above {
        Some(above) => {
            let t = crossing_fraction(above, below);
            let before = ray.cursor(hit.k - 1, strides);
            let color = match line_color(colors, &before, strides, probe) {
                Some(on_line_before) => lerp(on_line_before, on_hit_line, t),
                None => on_hit_line,
            };
            let back = i64::from(256 - t);
            (color, ray.distance(hit.k) - (back << 8), back)
        }
        None => (on_hit_line, ray.distance(hit.k), 0),
    };
    // The crossing lies `back`/256 of a step before the hit sample.
    let elevation = i64::from(hit.z.to_bits()) - ((back * i64::from(ray.dz.to_bits())) >> 8);
    Sample {
        color,
        distance: distance.clamp(0, i64::from(Sample::SKY - 1)) as u32,
        elevation: elevation.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32,
    }
}

/// The color where a sample's grid line is crossed: two voxels blended by
/// the subvoxel weight.
#[inline]
fn line_color<P: Probe>(colors: &[Rgb], at: &Cursor, strides: &Strides, probe: &mut P) -> Option<Rgb> {
    let (index, weight) = locate(at, strides);
    let c0 = *colors.get(index as usize)?;
    let c1 = *colors.get((index + strides.minor) as usize)?;
    probe.color(index as usize);
    Some(lerp(c0, c1, weight as u32))
}

/// Where between a sample above the surface (clearance `above` > 0) and the
/// next one below (`below` ≤ 0) the ray crosses it, in 1/256 of a step.
/// One division a pixel, outside the per-step loop.
fn crossing_fraction(above: i32, below: i32) -> u32 {
    let num = above.unsigned_abs();
    let den = num + below.unsigned_abs();
    let shift = (32 - den.leading_zeros()).saturating_sub(24);
    ((num >> shift) << 8) / (den >> shift).max(1)
}

/// Blends `a` toward `b` by `t`/256.
#[inline]
fn lerp(a: Rgb, b: Rgb, t: u32) -> Rgb {
    let t = t.min(256);
    core::array::from_fn(|i| ((u32::from(a[i]) * (256 - t) + u32::from(b[i]) * t + 128) >> 8) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_fraction_is_proportional_and_bounded() {
        assert_eq!(crossing_fraction(1, 0), 256);
        assert_eq!(crossing_fraction(1, -1), 128);
        assert_eq!(crossing_fraction(3 << 16, -(1 << 16)), 192);
        assert_eq!(crossing_fraction(i32::MAX, i32::MIN), 127);
        assert!(crossing_fraction(1, i32::MIN) <= 1);
    }

    #[test]
    fn lerp_hits_both_ends() {
        assert_eq!(lerp([0, 100, 255], [255, 0, 255], 0), [0, 100, 255]);
        assert_eq!(lerp([0, 100, 255], [255, 0, 255], 256), [255, 0, 255]);
        assert_eq!(lerp([0, 0, 0], [255, 255, 255], 128), [128, 128, 128]);
    }
}
