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
//! [`render_level_columns_lean`] is the column caster written lean: a
//! column's walk in single words (a ray's height from where it resumes
//! one long product, then an add a step), a ray above the highest terrain
//! skipping the samples it cannot hit at, its colors written straight
//! into the frame. The same frame, and what a level pixel of this design
//! costs on a 32-bit core.
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
//!
//! [`render_pixel_path_lean`] is the tabled path written lean: every value
//! of a ray in a word, its slope and drift from one reciprocal of its run,
//! its hit shaded without a depth or an elevation, its color written
//! straight into the frame. What is left is what the design's pixel
//! costs: the table, the ray's set-up, four texels and three blends (one
//! texel under nearest shading).

use super::walk::lerp;
use super::{crossing_fraction, sky, RenderOptions, Shading};
use crate::color::Rgb;
use crate::config::{COORD_FRAC_BITS, HEIGHT_FRAC_BITS, MAX_RAY_SLOPE, WEIGHT_BITS};
use crate::divide::div_trunc;
use crate::view::lines::{Line, LinePixels, Owned, RayWords, TableError};
use crate::view::plane::{slope_quotient, Plane};
use crate::view::words::saturate;
use crate::{Sample, Sink, Terrain, View};
use core::fmt;

/// Why [`render_level_columns`] cannot render a view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColumnsError {
    /// The view is pitched or rolled: its image columns are not the
    /// images of vertical planes.
    NotLevel,
    /// The frame holds fewer pixels than the view has.
    FrameTooSmall,
}

impl fmt::Display for ColumnsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NotLevel => "the column caster renders level views (pitch 0, roll 0) only",
            Self::FrameTooSmall => "the frame holds fewer pixels than the view",
        })
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

/// Renders a level `view` of `terrain` as [`render_level_columns`] does,
/// in words throughout, its colors written straight into `frame`
/// (row-major, y = 0 at the top; at least a pixel each): the column
/// caster written lean. A ray's height is a word from where it resumes
/// (one long product a ray, then an add a step), a step's heights and
/// its compare are words, and its hit is shaded with no depth or
/// elevation made. A ray above the terrain's highest point skips the
/// samples it cannot hit at (one division). Its frame is
/// [`render_level_columns`]'s bit for bit (tested). A measurement, not
/// the kernel: never inlined, so that its count does not hang on its
/// caller's code.
#[inline(never)]
pub fn render_level_columns_lean(
    terrain: &Terrain<'_>,
    view: &View,
    options: &RenderOptions,
    frame: &mut [Rgb],
) -> Result<(), ColumnsError> {
    if view.per_row[0].to_bits() != 0 || view.per_row[1].to_bits() != 0 {
        return Err(ColumnsError::NotLevel);
    }
    let frame = frame
        .get_mut(..view.width() as usize * view.height() as usize)
        .ok_or(ColumnsError::FrameTooSmall)?;
    let columns = FrameCaster::new(terrain, view, options);
    for column in 0..view.width() {
        columns.lean_column(column, frame);
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
    for (index, pixels) in table.owned_lines() {
        let Some((line, plane, walk)) = lines.set_up(index) else {
            continue;
        };
        let owned = pixels
            .iter()
            .map(|&p| line.owned_at((p & 0xFFFF) as i32, (p >> 16) as i32, top_row));
        lines.pixels_unwalked(&line, owned, &plane, &walk, sink);
    }
    Ok(())
}

/// Renders `view` of `terrain` as [`render_pixel_path_tabled`] does, in
/// words throughout, its colors written straight into `frame` (row-major,
/// y = 0 at the top; at least a pixel each): the per-pixel path written
/// lean (see the module's notes). A ray's run and rise are multiply-adds
/// on words and its offset from its line one long product, where the
/// other paths carry them in 64-bit words; its slope and color drift come
/// from one reciprocal of its run (one divide, where they divide twice);
/// its hit is shaded from values in words, with no depth or elevation
/// made. Its frame is the tabled path's to the rounding of the slope, the
/// drift and the offset (tested). With `options.shading`
/// [`Shading::Nearest`] a hit takes the one voxel nearest to where it is
/// looked up instead of four texels and three blends (and no crossing):
/// the path under the kernel's nearest shading. A measurement, not an
/// image of the terrain. Never inlined, so that its count does not hang
/// on its caller's code.
#[inline(never)]
pub fn render_pixel_path_lean(
    terrain: &Terrain<'_>,
    view: &View,
    options: &RenderOptions,
    (line_of, order, starts): (&mut [u16], &mut [u32], &mut [u32]),
    frame: &mut [Rgb],
) -> Result<(), TableError> {
    let width = view.width() as usize;
    let frame = frame
        .get_mut(..width * view.height() as usize)
        .ok_or(TableError::TooSmall)?;
    let table = view.tabulate_pixels(line_of, order, starts)?;
    let lines = FrameCaster::new(terrain, view, options);
    let eye_z = view.eye[2].to_bits();
    for (index, pixels) in table.owned_lines() {
        let Some((line, plane, walk)) = lines.set_up(index) else {
            continue;
        };
        let words = line.words(if plane.key.x_major { 0 } else { 1 }, view.height());
        let ray_of = |p: u32| words.ray((p & 0xFFFF) as i32, (p >> 16) as i32);
        let mut put = |ray: &RayWords, color: Rgb| {
            if let Some(pixel) = frame.get_mut(ray.y as usize * width + ray.x as usize) {
                *pixel = color;
            }
        };
        if walk.first > walk.last {
            for &p in pixels {
                put(&ray_of(p), lines.sky.color);
            }
            continue;
        }
        let at = LeanAt::new(&lines.start(&plane, &walk), &walk, &plane, eye_z);
        let across = Across::of(plane.across());
        let forward = plane.key.forward;
        if options.shading == Shading::Nearest {
            lean_pixels(pixels, &ray_of, forward, &across, |ray, dz, drift| {
                put(&ray, lines.lean_nearest(&at, dz, drift));
            });
        } else {
            lean_pixels(pixels, &ray_of, forward, &across, |ray, dz, drift| {
                put(&ray, lines.lean_color(&at, dz, drift));
            });
        }
    }
    Ok(())
}

/// Each of a line's tabled `pixels`, its ray set up in words: its words
/// (`ray_of`), its slope (Q16) and its color drift, from one reciprocal of
/// its run (toward the line's direction, `forward`), handed to `shade`.
#[inline(always)]
fn lean_pixels(
    pixels: &[u32],
    ray_of: &impl Fn(u32) -> RayWords,
    forward: bool,
    across: &Across,
    mut shade: impl FnMut(RayWords, i32, i32),
) {
    for &p in pixels {
        let ray = ray_of(p);
        let run = if forward {
            ray.major
        } else {
            ray.major.wrapping_neg()
        }
        .max(0) as u32;
        let reciprocal = Reciprocal::of_word(run);
        let dz = reciprocal.slope(ray.up);
        let drift = across.drift(reciprocal, ray.offset);
        shade(ray, dz, drift);
    }
}

/// A ray's run (its direction's major-axis component toward its plane's
/// direction, as a word) as a reciprocal, `1/run ≈ inverse · 2^shift /
/// 2^48`: the run's 16 leading bits divided into 2^32 once. A ray's slope
/// and its color drift both divide by its run; with this they multiply
/// (a 32 × 32-bit product each) and shift. A run of 0 (a vertical ray)
/// has none: `inverse` 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Reciprocal {
    inverse: u32,
    shift: i32,
}

impl Reciprocal {
    #[inline(always)]
    fn of_word(run: u32) -> Self {
        if run == 0 {
            return Self {
                inverse: 0,
                shift: 0,
            };
        }
        // run = leading · 2^(16 − shift), leading in [2^15, 2^16).
        let shift = run.leading_zeros();
        Self {
            inverse: u32::MAX / ((run << shift) >> 16),
            shift: shift as i32,
        }
    }

    /// `up / run` in Q16 (`up` a word), within `MAX_RAY_SLOPE`, as
    /// `slope_quotient` (to 2^−14 of it): `up`'s leading bits times the
    /// inverse, shifted. A vertical ray takes the steepest slope.
    #[inline(always)]
    fn slope(&self, up: i32) -> i32 {
        const MAX: u32 = (MAX_RAY_SLOPE as u32) << COORD_FRAC_BITS;
        let size = up.unsigned_abs();
        let magnitude = if self.inverse == 0 {
            MAX
        } else if size == 0 {
            0
        } else {
            let leading_zeros = size.leading_zeros();
            // In [2^15, 2^17): up's leading bits times the inverse.
            let high = ((u64::from(size << leading_zeros) * u64::from(self.inverse)) >> 32) as u32;
            // up · 2^16 / run = high · 2^(shift − leading zeros).
            let exponent = self.shift - leading_zeros as i32;
            if exponent >= 0 {
                if exponent >= 14 || high > MAX >> exponent {
                    MAX
                } else {
                    high << exponent
                }
            } else {
                high.checked_shr(exponent.unsigned_abs()).unwrap_or(0)
            }
        };
        if up < 0 {
            -(magnitude as i32)
        } else {
            magnitude as i32
        }
    }
}

/// A plane's drift numerator ([`Plane::across`]) as its sign and its size
/// `lead · 2^shift` (`lead` its 32 leading bits), once a line.
#[derive(Debug, Clone, Copy)]
struct Across {
    negative: bool,
    lead: u32,
    shift: i32,
}

impl Across {
    fn of(across: i64) -> Self {
        let size = across.unsigned_abs();
        let leading = size.leading_zeros();
        Self {
            negative: across < 0,
            lead: size.checked_shl(leading).map_or(0, |v| (v >> 32) as u32),
            shift: 32 - leading as i32,
        }
    }

    /// The drift ([`Plane::drift`], to 2^−13 of it) of a ray whose run is
    /// `run`, `offset` (Q16, within ±2^15) steps across the line, within
    /// ±2^14: `across · offset / (run · 2^24)`, the leading bits times the
    /// reciprocal, times the offset, in words.
    #[inline(always)]
    fn drift(&self, run: Reciprocal, offset: i32) -> i32 {
        const LIMIT: u32 = 1 << 14;
        if run.inverse == 0 || offset == 0 {
            return 0;
        }
        // lead · inverse / 2^33 is below 2^16: its product with the offset
        // fits a word.
        let high = ((u64::from(self.lead) * u64::from(run.inverse)) >> 33) as u32;
        let product = high * offset.unsigned_abs().min(1 << 15);
        let exponent = self.shift + run.shift - 39;
        let size = if exponent >= 0 {
            if exponent >= 31 || product > LIMIT >> exponent {
                LIMIT
            } else {
                product << exponent
            }
        } else {
            product
                .checked_shr(exponent.unsigned_abs())
                .unwrap_or(0)
                .min(LIMIT)
        };
        if self.negative != (offset < 0) {
            -(size as i32)
        } else {
            size as i32
        }
    }
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

/// A column's walk as [`FrameCaster::lean_column`] keeps it, in words:
/// the current sample, its grid line's start, its minor coordinate (Q16)
/// and its blended height (Q16), and the height of the sample before
/// (none where the walk started or skipped to this sample).
struct LeanColumnAt {
    k: i32,
    index: isize,
    minor: i32,
    height: i32,
    before: Option<i32>,
}

/// The line's first sample as the lean path shades every ray there
/// ([`FrameCaster::lean_color`]), in words: where its two grid lines'
/// colors are, how far it is, the heights either side of the crossing.
struct LeanAt {
    /// The eye's height and the sample's distance (Q16).
    eye_z: i32,
    delta0: i32,
    distance: i32,
    k: i32,
    /// The hit's and the sample before's grid-line starts and minor
    /// coordinates (Q16), and the step across the minor grid line.
    index: usize,
    minor: i32,
    before_index: usize,
    before_minor: i32,
    across: usize,
    minor_max: i32,
    /// The blended heights at the sample and before it (Q16).
    height: i32,
    before: i32,
}

impl LeanAt {
    /// `at`, the first sample of `walk` on `plane` (inside the map: its
    /// values fit words), as if the sample before stood a voxel above the
    /// surface (every ray takes the crossing's division).
    fn new(at: &At, walk: &Walk, plane: &Plane, eye_z: i64) -> Self {
        Self {
            eye_z: eye_z as i32,
            delta0: plane.delta0 as i32,
            distance: (plane.delta0 + (at.k << COORD_FRAC_BITS)) as i32,
            k: at.k as i32,
            index: at.index as usize,
            minor: at.minor as i32,
            before_index: (at.index - walk.step) as usize,
            before_minor: (at.minor - plane.dminor) as i32,
            across: walk.across as usize,
            minor_max: plane.minor_max as i32,
            height: at.height as i32,
            before: at.height as i32 + (1 << COORD_FRAC_BITS),
        }
    }

    /// The height (Q16) at this sample of a ray of slope `dz` (Q16 a
    /// sample), in a word: what its walk resumes with.
    #[inline(always)]
    fn ray_height(&self, dz: i32) -> i32 {
        self.eye_z
            .wrapping_add(((i64::from(self.delta0) * i64::from(dz)) >> COORD_FRAC_BITS) as i32)
            .wrapping_add(self.k.wrapping_mul(dz))
    }

    /// How far aside (Q16) a ray drifting `drift` looks its colors up at
    /// this sample: the drift times the sample's distance.
    #[inline(always)]
    fn aside(&self, drift: i32) -> i32 {
        ((i64::from(drift) * i64::from(self.distance)) >> COORD_FRAC_BITS) as i32
    }

    /// Minor coordinate `minor` (Q16) kept inside the map.
    #[inline(always)]
    fn inside(&self, minor: i32) -> i32 {
        if minor as u32 <= self.minor_max as u32 {
            minor
        } else if minor < 0 {
            0
        } else {
            self.minor_max
        }
    }
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

    /// Renders `column` of a level view as [`FrameCaster::column`] does,
    /// in words, into `frame` (see [`render_level_columns_lean`]).
    #[inline(always)]
    fn lean_column(&self, column: u32, frame: &mut [Rgb]) {
        let view = self.view;
        let (height_px, c) = (view.height(), i64::from(column));
        let width = view.width() as usize;
        let d = [0, 1, 2].map(|a| view.base[a].to_bits() + c * view.per_column[a].to_bits());
        let plane = Plane::new(view, &self.extent, &d);
        let run = if plane.key.x_major { d[0] } else { d[1] }.abs();
        let walk = Walk::new(&plane, self.width);
        // The column's pixels, bottom row first: `rows` of them from
        // `pixel` up, a row `width` before the one under it.
        let (mut pixel, mut rows) = (
            (height_px as usize).saturating_sub(1) * width + column as usize,
            height_px,
        );
        let mut put = |pixel: usize, color: Rgb| {
            if let Some(slot) = frame.get_mut(pixel) {
                *slot = color;
            }
        };
        if walk.first <= walk.last && run != 0 {
            // The slopes as `column` steps them (Q32), so that every ray's
            // slope and height are its.
            let max_slope = i64::from(MAX_RAY_SLOPE) << COORD_FRAC_BITS;
            let mut slope = div_trunc(d[2] << 24, run) << 8;
            let per_row = div_trunc(view.per_row[2].to_bits() << 32, run);
            let eye_z = view.eye[2].to_bits();
            // At most 2^28 (4096 voxels in Q16): a ray at or under it,
            // stepping by a slope of at most 2^29, keeps its height in a word.
            let top = self.top as i32;
            let (dminor, step, across) = (plane.dminor as i32, walk.step, walk.across);
            let last = walk.last as i32;
            let start = self.start(&plane, &walk);
            let mut at = LeanColumnAt {
                k: start.k as i32,
                index: start.index,
                minor: start.minor as i32,
                height: start.height as i32,
                before: None,
            };
            while rows > 0 {
                let dz_wide = (slope >> 16).clamp(-max_slope, max_slope);
                slope += per_row;
                let dz = dz_wide as i32;
                let mut z_wide = eye_z
                    + ((plane.delta0 * dz_wide) >> COORD_FRAC_BITS)
                    + i64::from(at.k) * dz_wide;
                if z_wide > i64::from(top) {
                    if dz >= 0 {
                        // It rises above the highest terrain: so do all the
                        // rays above it.
                        break;
                    }
                    // It cannot hit while above the highest terrain: on to the
                    // last sample where it still is (the walk from there reads
                    // what a walk over these samples would have).
                    let skip =
                        ((z_wide - i64::from(top) - 1) / -dz_wide).min(i64::from(last - at.k));
                    if skip > 0 {
                        let skip = skip as i32;
                        at.k += skip;
                        at.index += skip as isize * step;
                        at.minor += skip * dminor;
                        at.height = self.lean_height(at.index, across, at.minor);
                        at.before = None;
                        z_wide += i64::from(skip) * dz_wide;
                    }
                }
                // At or under the highest terrain, or under the surface here.
                // The first compare is the wide sum's (a ray out of a word's
                // reach below is under the surface, whatever its low word);
                // the climb and the shading take the low word, as the wide
                // sums' low words are all they read.
                let mut z = z_wide as i32;
                if z_wide > i64::from(at.height) {
                    let hit = loop {
                        if at.k == last || (dz >= 0 && z > top) {
                            break false;
                        }
                        at.before = Some(at.height);
                        at.k += 1;
                        at.index += step;
                        at.minor += dminor;
                        at.height = self.lean_height(at.index, across, at.minor);
                        z += dz;
                        if z <= at.height {
                            break true;
                        }
                    };
                    if !hit {
                        break;
                    }
                }
                let on_hit = self.lean_color_at(at.index, across, at.minor);
                put(
                    pixel,
                    match at.before {
                        None => on_hit,
                        Some(before) => {
                            let above = z.wrapping_sub(dz).wrapping_sub(before);
                            let below = z.wrapping_sub(at.height);
                            let behind =
                                self.lean_color_at(at.index - step, across, at.minor - dminor);
                            lerp(behind, on_hit, crossing_fraction(above, below))
                        }
                    },
                );
                pixel = pixel.wrapping_sub(width);
                rows -= 1;
            }
        }
        // The sky above the column's last hit (the whole column where it
        // never enters the map).
        for row in 0..rows as usize {
            put(pixel.wrapping_sub(row * width), self.sky.color);
        }
    }

    /// [`FrameCaster::height`] in a word.
    #[inline(always)]
    fn lean_height(&self, index: isize, across: isize, minor: i32) -> i32 {
        let i =
            index.wrapping_add(across.wrapping_mul((minor >> COORD_FRAC_BITS) as isize)) as usize;
        let (h0, h1) = match (
            self.heights.get(i),
            self.heights.get(i.wrapping_add(across as usize)),
        ) {
            (Some(&h0), Some(&h1)) => (i32::from(h0), i32::from(h1)),
            _ => (0, 0),
        };
        let weight = (minor & 0xFFFF) >> HEIGHT_FRAC_BITS;
        (h0 << HEIGHT_TO_Q16) + (h1 - h0) * weight
    }

    /// [`FrameCaster::color`] with the minor coordinate in a word, and off
    /// the map (wrapping indices included) the sky's color.
    #[inline(always)]
    fn lean_color_at(&self, index: isize, across: isize, minor: i32) -> Rgb {
        let i =
            index.wrapping_add(across.wrapping_mul((minor >> COORD_FRAC_BITS) as isize)) as usize;
        let weight = (minor >> (COORD_FRAC_BITS - WEIGHT_BITS)) as u32 & 0xFF;
        match (
            self.colors.get(i),
            self.colors.get(i.wrapping_add(across as usize)),
        ) {
            (Some(&a), Some(&b)) => lerp(a, b, weight),
            _ => self.sky.color,
        }
    }

    /// Image line `index` set up: the line, its plane and how its walk
    /// moves; `None` for a line that owns no pixel. The line's rays cross
    /// the map when `walk.first <= walk.last`. (Its pixels, stepped, are
    /// `line.pixels(height)`: a tabled path has them already.)
    #[inline(always)]
    fn set_up(&self, index: u32) -> Option<(Line, Plane, Walk)> {
        let view = self.view;
        if view.line_misses_image(index) {
            return None;
        }
        let line = view.line(index)?;
        let plane =
            Plane::new(view, &self.extent, &line.reference).with_across(&view.across(&line));
        let walk = Walk::new(&plane, self.width);
        Some((line, plane, walk))
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
        let Some((line, plane, walk)) = self.set_up(index) else {
            return;
        };
        let mut pixels = line.pixels(self.view.height());
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
        let Some((line, plane, walk)) = self.set_up(index) else {
            return;
        };
        let pixels = line.pixels(self.view.height());
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

    /// The color [`FrameCaster::hit`] gives a ray with slope `dz` (Q16) and
    /// drift `drift` (Q16 a unit of distance) at `at`, in words (its
    /// heights wrap as the wide sums' low words do): no sample, depth or
    /// elevation made.
    #[inline(always)]
    fn lean_color(&self, at: &LeanAt, dz: i32, drift: i32) -> Rgb {
        let z = at.ray_height(dz);
        let aside = at.aside(drift);
        let on_hit = self.lean_texels(at, at.index, at.minor.wrapping_add(aside));
        let before = self.lean_texels(
            at,
            at.before_index,
            at.before_minor.wrapping_add(aside.wrapping_sub(drift)),
        );
        let above = z.wrapping_sub(dz).wrapping_sub(at.before);
        let below = z.wrapping_sub(at.height);
        lerp(before, on_hit, crossing_fraction(above, below))
    }

    /// [`FrameCaster::lean_color`] for [`Shading::Nearest`]: the voxel
    /// nearest to where the hit sample, looked up `drift` aside, crosses
    /// its minor grid line, as the kernel's nearest shading takes it. The
    /// ray's height at the sample (what its walk resumes with) is worked
    /// out as for the blend, and kept from the optimizer: the walk needs
    /// it, and the nearest color does not.
    #[inline(always)]
    fn lean_nearest(&self, at: &LeanAt, dz: i32, drift: i32) -> Rgb {
        core::hint::black_box(at.ray_height(dz));
        let minor = at.inside(at.minor.wrapping_add(at.aside(drift)));
        let cell = at
            .index
            .wrapping_add(at.across.wrapping_mul((minor >> COORD_FRAC_BITS) as usize));
        let half = 1 << (COORD_FRAC_BITS - 1);
        let nearest = if minor & ((half << 1) - 1) < half {
            cell
        } else {
            cell.wrapping_add(at.across)
        };
        self.colors.get(nearest).copied().unwrap_or(self.sky.color)
    }

    /// The two voxels across the minor grid line at `minor` (Q16, kept
    /// inside the map) of the grid line starting at `index`, blended by
    /// the subvoxel weight.
    #[inline(always)]
    fn lean_texels(&self, at: &LeanAt, index: usize, minor: i32) -> Rgb {
        let minor = at.inside(minor);
        // The sample before the first may lie off the map (an index below
        // 0, as a huge one), which the lookup's `get` then refuses.
        self.lean_color_at(index as isize, at.across as isize, minor)
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
                elevation: saturate(z),
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
            // Saturated: an eye far under the surface starts its rays
            // below a word's reach.
            elevation: saturate(z - ((back * dz) >> 8)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::plane::DIRECTION_WORD_SHIFT;
    use crate::{Camera, Extent};
    use proptest::prelude::*;

    #[test]
    fn the_lean_slope_is_within_its_precision_of_the_exact_quotient() {
        let max = f64::from(MAX_RAY_SLOPE) * 65536.0;
        proptest!(|(up in any::<i32>(), run in 0u32..=i32::MAX as u32)| {
            let exact = if run == 0 {
                max.copysign(f64::from(up))
            } else {
                (f64::from(up) * 65536.0 / f64::from(run)).clamp(-max, max)
            };
            let got = f64::from(Reciprocal::of_word(run).slope(up));
            // The run's and up's 16 leading bits, and the product's.
            prop_assert!(
                (got - exact).abs() <= exact.abs() * 2f64.powi(-14) + 2.0,
                "{up} / {run}: {got} against {exact}"
            );
        });
    }

    #[test]
    fn the_lean_drift_is_within_its_precision_of_the_exact_quotient() {
        let extent = Extent {
            width: 64,
            depth: 64,
            max_height: 0,
            real_edges: true,
        };
        let view = View::new(&Camera::looking([20.0, 20.0, 10.0], 30.0, 10.0), 64, 48).unwrap();
        let base = Plane::new(&view, &extent, &[1 << 32, 1 << 31, 0]);
        // Across steps of the sizes a view's pixels make, runs of words
        // from 2^8 to 2^30, offsets within half a pixel.
        proptest!(|(across in -(1i64 << 38)..1 << 38, run in 1u32 << 8..1 << 30, offset in -(1i32 << 15)..=1 << 15)| {
            let plane = base.with_across(&[0, across, 0]);
            let exact = (plane.across() as f64 * f64::from(offset)
                / (f64::from(run) * 2f64.powi(16 + DIRECTION_WORD_SHIFT as i32)))
            .clamp(-16384.0, 16384.0);
            let got = f64::from(Across::of(plane.across()).drift(Reciprocal::of_word(run), offset));
            // 2^−13 of the quotient, and a unit of its last place.
            prop_assert!(
                (got - exact).abs() <= exact.abs() * 2f64.powi(-13) + 1.0,
                "{across} {run} {offset}: {got} against {exact}"
            );
        });
    }
}
