//! The column caster: each image column bottom to top, one ray after another.
//!
//! With vertical ray coherence on, each ray starts at the sample where the
//! ray below it hit (Cohen-Or §2). Under a pitched pinhole camera the rays of
//! a column are not in one vertical plane: the upper ray drifts sideways as
//! well as rising, and may pass over ground the lower ray never saw. The
//! caster keeps coherence exact anyway:
//!
//! * a ray that rises faster (per step) than the terrain's steepest
//!   neighbour difference can climb across its sideways drift is above the
//!   surface wherever the ray below it was, except within a few steps of the
//!   eye where fixed-point rounding dominates; those few are walked, then
//!   the ray jumps to the lower ray's hit ([`resume_plan`]);
//! * any other ray is cast from the eye.
//!
//! So the image with coherence equals the image with every ray cast from
//! the eye, bit for bit (tested). A resumed ray that starts below the
//! surface retraces backwards to the last sample above it (Qu et al. §4);
//! the hit is refined between that sample and the first one below by the
//! ratio of their clearances, and the color blended across both grid lines.

pub(crate) mod walk;

use crate::config::{COORD_FRAC_BITS, HEIGHT_FRAC_BITS, HEIGHT_WEIGHT_BITS, WEIGHT_BITS};
use crate::probe::Probe;
use crate::sink::{Sample, Sink};
use crate::terrain::Terrain;
use crate::view::ray::{Cursor, Ray, RayKey, Strides};
use crate::view::View;
use crate::{config::DEFAULT_SKY, Rgb};
use walk::{clearance, locate, walk, Walk};

/// How each ray of a column may use the ray below it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coherence {
    /// Every ray is cast from the eye: the slow baseline.
    Off,
    /// A ray skips ahead only where the terrain's steepest neighbour
    /// difference could not have hidden a hit from it: the image equals
    /// [`Coherence::Off`]'s bit for bit.
    Exact,
    /// As [`Coherence::Exact`], assuming terrain no steeper than `slope`
    /// (U12.4 height units per voxel). Faster under pitch; where the real
    /// terrain is steeper, a ray may miss a ridge the ray below it passed
    /// over (the bound measured in the coherence tests).
    Bounded {
        /// Assumed steepest neighbour difference, U12.4 (16 = one voxel
        /// of height per voxel).
        slope: u16,
    },
}

impl Coherence {
    /// The default: [`Coherence::Bounded`] at a slope of 2 (about 63°).
    pub const DEFAULT: Self = Self::Bounded { slope: 32 };
}

/// Settings of the caster.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderOptions {
    /// Vertical ray coherence: each ray resumes where the ray below it hit.
    pub coherence: Coherence,
    /// Color of rays that leave the terrain.
    pub sky: Rgb,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            coherence: Coherence::DEFAULT,
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

/// What the last cast ray of a column established: it was above the surface
/// at every sample in `start..k`.
#[derive(Debug, Clone, Copy)]
struct Anchor {
    key: RayKey,
    start: i32,
    k: i32,
    dminor: i32,
    dz: i32,
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
    // The slope bound the resume proof assumes; `None` casts every ray from
    // the eye.
    let slope = match options.coherence {
        Coherence::Off => None,
        Coherence::Exact => Some(terrain.max_step()),
        Coherence::Bounded { slope } => Some(slope.min(terrain.max_step())),
    };
    let mut anchor: Option<Anchor> = None;
    let top_row = view.height() - 1;
    for row in 0..view.height() {
        probe.ray();
        let ray = view.ray(terrain, column, row);
        let sample = if ray.start > ray.end {
            sky(options)
        } else {
            let plan = anchor
                .zip(slope)
                .and_then(|(a, slope)| resume_plan(&a, &ray, slope));
            let (sample, clear_until) = cast(terrain, &ray, plan, options, probe);
            anchor = Some(Anchor {
                key: ray.key,
                start: ray.start,
                k: clear_until,
                dminor: ray.dminor.to_bits(),
                dz: ray.dz.to_bits(),
            });
            sample
        };
        sink.put(column, top_row - row, sample);
    }
}

/// Where a ray may skip to: `(last prefix sample to walk, sample to resume
/// at)`, or `None` to cast it from the eye.
///
/// Let the anchor ray be above the surface at samples `start..k`. At sample
/// `i`, at distance `s ≥ i` from the eye, this ray is higher by at least
/// `s·rise − 1` (Q16 bits) and sideways by at most `s·drift + 1`, and the
/// sampled surface (heights blended by a 12-bit weight, so positions are
/// quantized to 16 Q16 bits) can be higher there by at most
/// `L/16 · (s·drift + 17)`, with `L`
/// the slope bound in U12.4 per voxel. So this ray is above wherever
/// `s·(rise − L·drift/16) > 1 + 17·L/16`: everywhere past a short prefix.
fn resume_plan(anchor: &Anchor, ray: &Ray, slope: u16) -> Option<(i32, i32)> {
    if anchor.key != ray.key {
        return None;
    }
    let steep = i64::from(slope);
    let rise = i64::from(ray.dz.to_bits()) - i64::from(anchor.dz);
    let drift = (i64::from(ray.dminor.to_bits()) - i64::from(anchor.dminor)).abs();
    let unit = 1i64 << HEIGHT_FRAC_BITS;
    let margin = rise - (steep * drift + unit - 1) / unit;
    if margin <= 0 {
        return None;
    }
    let quantum = 1i64 << (COORD_FRAC_BITS - HEIGHT_WEIGHT_BITS);
    let slack = 1 + ((quantum + 1) * steep + unit - 1) / unit;
    let unsafe_samples = (slack / margin).min(i64::from(i32::MAX)) as i32;
    let prefix_end = unsafe_samples.max(anchor.start - 1);
    (prefix_end + 1 < anchor.k).then_some((prefix_end, anchor.k))
}

fn sky(options: &RenderOptions) -> Sample {
    Sample {
        color: options.sky,
        distance: Sample::SKY,
        elevation: 0,
    }
}

/// Casts one ray: from its start, or (with a plan) through a prefix and then
/// from the resume sample. Returns what it saw and the sample up to which
/// it is known to be above the surface (its hit, or one past its last).
fn cast<P: Probe>(
    terrain: &Terrain<'_>,
    ray: &Ray,
    plan: Option<(i32, i32)>,
    options: &RenderOptions,
    probe: &mut P,
) -> (Sample, i32) {
    let heights = terrain.heights();
    let strides = ray.strides(terrain.width());
    // With a plan, walk only the prefix the proof does not cover first.
    let first_end = plan.map_or(ray.end, |(prefix_end, _)| prefix_end.min(ray.end));
    let mut outcome = if first_end >= ray.start {
        walk(
            heights,
            ray,
            &strides,
            ray.cursor(ray.start, &strides),
            first_end,
            probe,
        )
    } else {
        Walk::Exit {
            last: ray.start - 1,
        }
    };
    if let (Some((_, resume)), Walk::Exit { last }) = (plan, outcome) {
        if last < ray.end {
            let from = resume.clamp(last + 1, ray.end);
            outcome = walk(
                heights,
                ray,
                &strides,
                ray.cursor(from, &strides),
                ray.end,
                probe,
            );
        }
    }
    match outcome {
        Walk::Exit { last } => (sky(options), last + 1),
        Walk::Hit {
            at,
            clearance,
            above: Some(above),
        } => (
            shade(
                terrain,
                ray,
                &strides,
                at,
                clearance,
                Some(above),
                options,
                probe,
            ),
            at.k,
        ),
        Walk::Hit {
            at,
            clearance,
            above: None,
        } => {
            let (at, clearance, above) = retrace(heights, ray, &strides, at, clearance, probe);
            (
                shade(terrain, ray, &strides, at, clearance, above, options, probe),
                at.k,
            )
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
fn line_color<P: Probe>(
    colors: &[Rgb],
    at: &Cursor,
    strides: &Strides,
    probe: &mut P,
) -> Option<Rgb> {
    let (index, weight) = locate(at, strides, WEIGHT_BITS);
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
