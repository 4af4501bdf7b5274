//! The per-line design at its smallest: level 0 only, subvoxel shading,
//! level views only (pitch 0), whose image lines are the columns. It is
//! the speed bound the kernel's line caster (`line_caster.rs`, the same
//! design on the pyramid at any pitch) is measured against (`cargo bench
//! -p terracast-sim --bench kernel`, group `per-line bound`):
//!
//! - **Once a column**: its vertical plane ([`Plane`]: major axis,
//!   direction, minor slope, the samples inside the map), its bottom ray's
//!   slope and the slope's change a row.
//! - **Once a ray**: its slope (a multiply-add) and its height where the
//!   ray below it hit (a multiply). It resumes there: it is no lower than
//!   that ray at any sample, so it is above the surface before it (Cohen-Or
//!   §2, Figure 7), and the blended heights of the hit sample and the one
//!   before are already at hand.
//! - **Once a step**: the two heights across the minor grid line, blended
//!   by shift and mask, compared with the ray's height.
//! - **Once a hit**: the crossing placed by the clearances (one division),
//!   and both grid lines' colors blended there by the subvoxel weights.
//! - **Sky** above a column's last hit is one span, written without rays.
//!
//! Its images differ from the kernel's single-resolution ones only by
//! rounding (it steps the slope instead of dividing it; at pitch 0 no ray
//! is beside its pixel's center, so there is no color drift), so a pixel
//! costs what the algorithm costs. Under pitch a ray's slope is a ratio,
//! one division a ray: the line caster's.
//!
//! [`render_pixel_lines`] is the same design under any pitch and roll:
//! the kernel's image lines (through the vertical's vanishing point), a
//! ray's slope one division (`slope_quotient`, from its pixel center's
//! words), a ray lower than the one before starting again from the line's
//! first sample, and the color looked up where the pixel center's own ray
//! would cross (`Plane::drift`). What it leaves out of the kernel's line
//! caster is the pyramid (levels, stretches, far colors) and the first
//! hit: it is the bound for the kernel's pitched frames.
//!
//! [`render_pixel_path`] is the same again without the walk: every pixel
//! of every line owned, its ray's slope and color drift worked out and its
//! hit shaded (the crossing's division, both grid lines' colors) at the
//! line's first sample in the map, as if the ray hit there. It takes no
//! step, and writes sky only on a line that never enters the map: what
//! the per-pixel path costs a terrain pixel before any step, the floor
//! under a pitched frame of this design.
//!
//! [`render_pixel_path_tabled`] is that path with each line's pixels read
//! from a table of the frame's pixel ownership, built once a frame into
//! caller storage by a pass over the image's rows and a counting sort by
//! line, instead of each line stepping its rows' ownership test: the same
//! frame, and what the pixel costs when its line is looked up rather than
//! stepped to ([`tabulate_pixel_ownership`] builds the table alone, to
//! count it apart).

use super::walk::lerp;
use super::{crossing_fraction, sky, RenderOptions};
use crate::color::Rgb;
use crate::config::{COORD_FRAC_BITS, HEIGHT_FRAC_BITS, MAX_RAY_SLOPE, WEIGHT_BITS};
use crate::divide::div_trunc;
use crate::view::lines::{Line, Owned, OwnedPixels, TableError};
use crate::view::plane::{slope_quotient, Plane};
use crate::{Sample, Sink, Terrain, View};
use core::fmt;

/// Why [`render_level_columns`] cannot render a view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColumnsError {
    /// The view is pitched or rolled: its image columns are not the
    /// images of vertical planes.
    NotLevel,
}

impl fmt::Display for ColumnsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("the column caster renders level views (pitch 0, roll 0) only")
    }
}

impl core::error::Error for ColumnsError {}

/// Heights are U12.4; the walk compares them in Q16 (`HEIGHT_WEIGHT_BITS`).
const HEIGHT_TO_Q16: u32 = COORD_FRAC_BITS - HEIGHT_FRAC_BITS;

/// Renders a level `view` of `terrain` (level 0, subvoxel shading, the sky
/// of `options`) column by column into `sink`.
pub fn render_level_columns<S: Sink>(
    terrain: &Terrain<'_>,
    view: &View,
    options: &RenderOptions,
    sink: &mut S,
) -> Result<(), ColumnsError> {
    if view.per_row[0].to_bits() != 0 || view.per_row[1].to_bits() != 0 {
        return Err(ColumnsError::NotLevel);
    }
    let columns = FrameCaster::new(terrain, view, options);
    for column in 0..view.width() {
        columns.column(column, sink);
    }
    Ok(())
}

/// Renders `view` of `terrain` (level 0, subvoxel shading with the color
/// drift, the sky of `options`) line by line, along the kernel's image
/// lines, into `sink`: the per-line design at its smallest under pitch
/// and roll (see the module's notes).
pub fn render_pixel_lines<S: Sink>(
    terrain: &Terrain<'_>,
    view: &View,
    options: &RenderOptions,
    sink: &mut S,
) {
    let lines = FrameCaster::new(terrain, view, options);
    for index in 0..view.lines() {
        lines.line(index, sink);
    }
}

/// Renders `view` of `terrain` as [`render_pixel_lines`] does, every ray
/// shaded where its line enters the map instead of where it hits (no step,
/// no sky): the per-pixel path alone (see the module's notes). A
/// measurement, not an image of the terrain.
pub fn render_pixel_path<S: Sink>(
    terrain: &Terrain<'_>,
    view: &View,
    options: &RenderOptions,
    sink: &mut S,
) {
    let lines = FrameCaster::new(terrain, view, options);
    for index in 0..view.lines() {
        lines.line_unwalked(index, sink);
    }
}

/// Renders `view` of `terrain` as [`render_pixel_path`] does, each line's
/// pixels from a table of the frame's pixel ownership built first into
/// caller storage (`line_of` and `order` a pixel each, `starts` a line
/// each plus one: [`View::lines`]) instead of each line stepping its
/// rows: the same image, and what the per-pixel path costs with its
/// ownership found once a frame (see the module's notes). A measurement,
/// not an image of the terrain.
pub fn render_pixel_path_tabled<S: Sink>(
    terrain: &Terrain<'_>,
    view: &View,
    options: &RenderOptions,
    (line_of, order, starts): (&mut [u16], &mut [u32], &mut [u32]),
    sink: &mut S,
) -> Result<(), TableError> {
    let table = view.tabulate_pixels(line_of, order, starts)?;
    let lines = FrameCaster::new(terrain, view, options);
    let top_row = view.height() as i32 - 1;
    for (index, ends) in table.starts.windows(2).enumerate() {
        let Some(pixels) = table.order.get(ends[0] as usize..ends[1] as usize) else {
            continue;
        };
        // A line that owns no pixel is never set up.
        if pixels.is_empty() {
            continue;
        }
        let Some((line, _, plane, walk)) = lines.set_up(index as u32) else {
            continue;
        };
        let owned = pixels
            .iter()
            .map(|&p| line.owned_at((p & 0xFFFF) as i32, (p >> 16) as i32, top_row));
        lines.pixels_unwalked(&line, owned, &plane, &walk, sink);
    }
    Ok(())
}

/// The table [`render_pixel_path_tabled`] builds, alone (a measurement).
pub fn tabulate_pixel_ownership(
    view: &View,
    (line_of, order, starts): (&mut [u16], &mut [u32], &mut [u32]),
) -> Result<(), TableError> {
    view.tabulate_pixels(line_of, order, starts).map(|_| ())
}

/// What every column or line of a frame shares: the terrain, the view and
/// the sky.
struct FrameCaster<'t, 'v> {
    heights: &'t [u16],
    colors: &'t [Rgb],
    width: isize,
    top: i64,
    view: &'v View,
    extent: crate::Extent,
    sky: Sample,
}

/// A column's walk: where its current sample is, and the blended height
/// of that sample and of the one before it.
#[derive(Clone, Copy)]
struct At {
    k: i64,
    index: isize,
    minor: i64,
    height: i64,
    before: i64,
}

/// How a line's walk moves through the grid.
struct Walk {
    /// Index step to the neighbour across the minor grid line.
    across: isize,
    /// Index step of one sample along the major axis, and of one grid line
    /// of the major axis.
    step: isize,
    major_stride: isize,
    /// The line's samples inside the map: `first..=last`.
    first: i64,
    last: i64,
}

impl Walk {
    /// The walk of `plane`'s rays over a map `width` points wide.
    fn new(plane: &Plane, width: isize) -> Self {
        let (major_stride, across) = if plane.key.x_major {
            (1, width)
        } else {
            (width, 1)
        };
        Self {
            across,
            step: if plane.key.forward {
                major_stride
            } else {
                -major_stride
            },
            major_stride,
            first: plane.first.max(0),
            last: plane.last,
        }
    }
}

impl<'t, 'v> FrameCaster<'t, 'v> {
    fn new(terrain: &Terrain<'t>, view: &'v View, options: &RenderOptions) -> Self {
        Self {
            heights: terrain.heights(),
            colors: terrain.colors(),
            width: terrain.width() as isize,
            top: i64::from(terrain.max_height()) << HEIGHT_TO_Q16,
            view,
            extent: terrain.extent(),
            sky: sky(options),
        }
    }

    /// Height (Q16) at minor coordinate `minor` (Q16) of the grid line
    /// starting at `index`, the neighbour `across` away.
    #[inline(always)]
    fn height(&self, index: isize, across: isize, minor: i64) -> i64 {
        let i = (index + across * (minor >> COORD_FRAC_BITS) as isize) as usize;
        let (h0, h1) = (self.heights[i], self.heights[i + across as usize]);
        let weight = (minor as i32 & 0xFFFF) >> HEIGHT_FRAC_BITS;
        i64::from((i32::from(h0) << HEIGHT_TO_Q16) + (i32::from(h1) - i32::from(h0)) * weight)
    }

    /// The color at minor coordinate `minor` (Q16) of the grid line
    /// starting at `index`, looked up `aside` (Q16) across the line and
    /// kept inside the map.
    #[inline(always)]
    fn color_aside(
        &self,
        index: isize,
        across: isize,
        minor: i64,
        aside: i64,
        plane: &Plane,
    ) -> Rgb {
        // As the line caster keeps it inside: one unsigned compare for the
        // rule, where `clamp` is a call on the board.
        let moved = minor + aside;
        let inside = if moved as u64 <= plane.minor_max as u64 {
            moved
        } else if moved < 0 {
            0
        } else {
            plane.minor_max
        };
        self.color(index, across, inside)
    }

    #[inline(always)]
    fn color(&self, index: isize, across: isize, minor: i64) -> Rgb {
        let i = (index + across * (minor >> COORD_FRAC_BITS) as isize) as usize;
        let weight = (minor >> (COORD_FRAC_BITS - WEIGHT_BITS)) as u32 & 0xFF;
        lerp(self.colors[i], self.colors[i + across as usize], weight)
    }

    fn column<S: Sink>(&self, column: u32, sink: &mut S) {
        let view = self.view;
        let (height_px, c) = (view.height(), i64::from(column));
        let d = [0, 1, 2].map(|a| view.base[a].to_bits() + c * view.per_column[a].to_bits());
        let plane = Plane::new(view, &self.extent, &d);
        let run = if plane.key.x_major { d[0] } else { d[1] }.abs();
        let walk = Walk::new(&plane, self.width);
        let put =
            |sink: &mut S, row: u32, sample: Sample| sink.put(column, height_px - 1 - row, sample);
        if walk.first > walk.last || run == 0 {
            (0..height_px).for_each(|row| put(sink, row, self.sky));
            return;
        }
        // The bottom ray's slope and its change a row, both Q32: the
        // direction's height is I32F32 below 2^36, so the bottom slope is
        // divided in Q24 and widened; a row's change is below 2^26.
        let max_slope = i64::from(MAX_RAY_SLOPE) << COORD_FRAC_BITS;
        let slope0 = div_trunc(d[2] << 24, run) << 8;
        let per_row = div_trunc(view.per_row[2].to_bits() << 32, run);
        let eye_z = view.eye[2].to_bits();

        let mut at = self.start(&plane, &walk);
        for row in 0..height_px {
            let dz = ((slope0 + i64::from(row) * per_row) >> 16).clamp(-max_slope, max_slope);
            let z0 = eye_z + ((plane.delta0 * dz) >> COORD_FRAC_BITS);
            let z = z0 + at.k * dz;
            let Some(z) = self.climb(&mut at, z, dz, &walk, &plane) else {
                // Left the map or rose above the highest terrain: so do
                // all the rays above it.
                (row..height_px).for_each(|row| put(sink, row, self.sky));
                return;
            };
            put(sink, row, self.hit(&at, z, dz, 0, &walk, &plane));
        }
    }

    /// Image line `index` set up: the line, its pixels, its plane and how
    /// its walk moves; `None` for a line that owns no pixel. The line's
    /// rays cross the map when `walk.first <= walk.last`.
    #[inline(always)]
    fn set_up(&self, index: u32) -> Option<(Line, OwnedPixels, Plane, Walk)> {
        let view = self.view;
        if view.line_misses_image(index) {
            return None;
        }
        let line = view.line(index)?;
        let pixels = line.pixels(view.height());
        let plane =
            Plane::new(view, &self.extent, &line.reference).with_across(&view.across(&line));
        let walk = Walk::new(&plane, self.width);
        Some((line, pixels, plane, walk))
    }

    /// The ray of `pixel` on `line`: its run along the major axis (a
    /// word) and its height change a sample (Q16), one division.
    #[inline(always)]
    fn ray(line: &Line, plane: &Plane, pixel: &Owned) -> (i32, i64) {
        let axis = [if plane.key.x_major { 0 } else { 1 }];
        let [major] = line.direction_words(pixel.along, axis);
        let run = if plane.key.forward { major } else { -major }.max(0);
        (
            run,
            i64::from(slope_quotient(line.up_word(pixel), run as u32)),
        )
    }

    /// Renders image line `index` (see [`render_pixel_lines`]).
    fn line<S: Sink>(&self, index: u32, sink: &mut S) {
        let Some((line, mut pixels, plane, walk)) = self.set_up(index) else {
            return;
        };
        if walk.first <= walk.last {
            let eye_z = self.view.eye[2].to_bits();
            let (mut at, mut previous_dz) = (None, i64::MIN);
            for pixel in pixels.by_ref() {
                let (run, dz) = Self::ray(&line, &plane, &pixel);
                // Lower than the ray before (next to the vanishing point):
                // from the line's first sample again.
                if dz < previous_dz {
                    at = None;
                }
                previous_dz = dz;
                let at = at.get_or_insert_with(|| self.start(&plane, &walk));
                let z = eye_z + ((plane.delta0 * dz) >> COORD_FRAC_BITS) + at.k * dz;
                let Some(z) = self.climb(at, z, dz, &walk, &plane) else {
                    sink.put(pixel.x, pixel.y, self.sky);
                    break;
                };
                let drift = plane.drift_of_word(run, pixel.offset);
                sink.put(pixel.x, pixel.y, self.hit(at, z, dz, drift, &walk, &plane));
            }
        }
        // The sky above the line's last hit.
        pixels.for_each_position(|x, y| sink.put(x, y, self.sky));
    }

    /// Renders image line `index` as [`FrameCaster::line`] does, each ray
    /// shaded at the line's first sample (see [`render_pixel_path`]).
    fn line_unwalked<S: Sink>(&self, index: u32, sink: &mut S) {
        let Some((line, pixels, plane, walk)) = self.set_up(index) else {
            return;
        };
        self.pixels_unwalked(&line, pixels, &plane, &walk, sink);
    }

    /// `pixels` of `line` rendered as [`FrameCaster::line_unwalked`]
    /// renders a line's.
    #[inline(always)]
    fn pixels_unwalked<S: Sink>(
        &self,
        line: &Line,
        pixels: impl Iterator<Item = Owned>,
        plane: &Plane,
        walk: &Walk,
        sink: &mut S,
    ) {
        if walk.first > walk.last {
            pixels.for_each(|pixel| sink.put(pixel.x, pixel.y, self.sky));
            return;
        }
        let eye_z = self.view.eye[2].to_bits();
        // The first sample, as if the sample before it stood a voxel
        // above the surface: every hit takes the crossing's division.
        let mut at = self.start(plane, walk);
        at.before = at.height + (1 << COORD_FRAC_BITS);
        for pixel in pixels {
            let (run, dz) = Self::ray(line, plane, &pixel);
            let z = eye_z + ((plane.delta0 * dz) >> COORD_FRAC_BITS) + at.k * dz;
            let drift = plane.drift_of_word(run, pixel.offset);
            sink.put(pixel.x, pixel.y, self.hit(&at, z, dz, drift, walk, plane));
        }
    }

    /// The walk's first sample inside the map, with nothing known before it.
    #[inline(always)]
    fn start(&self, plane: &Plane, walk: &Walk) -> At {
        let first = walk.first;
        let major = plane.major0 + if plane.key.forward { first } else { -first };
        let index = major as isize * walk.major_stride;
        let minor = plane.minor0 + first * plane.dminor;
        At {
            k: first,
            index,
            minor,
            height: self.height(index, walk.across, minor),
            before: i64::MAX,
        }
    }

    /// Climbs to a ray at height `z` (Q16) at `at`, `dz` a step (Cohen-Or's
    /// Figure 7): from the sample where the ray below hit, steps while
    /// above the surface. Returns the ray's height at its hit, or `None`
    /// when it leaves the map or rises above the highest terrain (and so
    /// does every ray of the line above it).
    #[inline(always)]
    fn climb(&self, at: &mut At, mut z: i64, dz: i64, walk: &Walk, plane: &Plane) -> Option<i64> {
        while z > at.height {
            if at.k == walk.last || (dz >= 0 && z > self.top) {
                return None;
            }
            at.before = at.height;
            at.k += 1;
            at.index += walk.step;
            at.minor += plane.dminor;
            at.height = self.height(at.index, walk.across, at.minor);
            z += dz;
        }
        Some(z)
    }

    /// The sample of a ray at height `z` (Q16) at `at`, below the surface
    /// there and above it at the sample before (when there is one), its
    /// colors looked up `drift` (Q16 a unit of distance) aside.
    #[inline(always)]
    fn hit(&self, at: &At, z: i64, dz: i64, drift: i64, walk: &Walk, plane: &Plane) -> Sample {
        let (across, step) = (walk.across, walk.step);
        let distance = plane.delta0 + (at.k << COORD_FRAC_BITS);
        let aside = (drift * distance) >> COORD_FRAC_BITS;
        let on_hit_line = if drift == 0 {
            self.color(at.index, across, at.minor)
        } else {
            self.color_aside(at.index, across, at.minor, aside, plane)
        };
        if at.before == i64::MAX {
            return Sample {
                color: on_hit_line,
                distance: distance.clamp(0, i64::from(Sample::SKY - 1)) as u32,
                elevation: z as i32,
            };
        }
        let above = (z - dz - at.before) as i32;
        let below = (z - at.height) as i32;
        let t = crossing_fraction(above, below);
        let before_minor = at.minor - plane.dminor;
        let before = if drift == 0 {
            self.color(at.index - step, across, before_minor)
        } else {
            self.color_aside(at.index - step, across, before_minor, aside - drift, plane)
        };
        let back = i64::from(256 - t);
        Sample {
            color: lerp(before, on_hit_line, t),
            distance: (distance - (back << 8)).clamp(0, i64::from(Sample::SKY - 1)) as u32,
            elevation: (z - ((back * dz) >> 8)) as i32,
        }
    }
}
