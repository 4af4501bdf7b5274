//! Sky, sun and layered fog: what a ray sees on its way to the terrain or
//! past it, in fixed point.
//!
//! The model (every formula here is also written out in floating point,
//! [`Atmosphere::exact`], which the host's reference renders with):
//!
//! - **Sky**: a gradient from the horizon color to the zenith color by the
//!   sine `s` of the ray's elevation, weighted `1 − (1 − s)²` (rays below
//!   the horizon take the horizon color). Cheap per sky pixel: a table
//!   of 257 colors by sine, blended between neighbours.
//! - **Sun**: a disc of the sun's color within `disc_deg` of its direction
//!   and a glow out to `glow_deg`, blending the sky toward the sun's color
//!   by `½·g²`, `g = 1 − sin²θ / sin²θ_glow` (`θ` the angle to the sun).
//! - **Fog** of a density that is the ground layer's up to a `ceiling`
//!   and halves every `halving` voxels above it (or stays: uniform fog).
//!   The optical depth along a ray is integrated in closed form: through
//!   heights `a` to `b` over a length `L` it is `L·(F(b) − F(a))/(b − a)`
//!   times the ground density, `F` the density's integral over height
//!   (`L·density` where `b ≈ a`), and to the sky `(F(∞) − F(a)) / s`. A
//!   color keeps `2^−τ` of itself (`τ` in halvings) and takes the fog's
//!   color for the rest. The ground density is set by the visibility: the
//!   distance at which ground fog leaves 2 % of a color.
//!
//! A frame gets its atmosphere through [`AtmosphereSink`], which wraps any
//! [`Sink`]: each finished pixel's direction comes from the [`View`], its
//! hit's distance and height from its [`Sample`]. What depends on the eye
//! is tabled once a frame (the fogged sky by sine, the mean density from
//! the eye to each height), and so is what a pixel needs of its direction:
//! the sine of its elevation and how much longer its ray is than the
//! distance a [`Sample`] holds, at the corners of a grid of 64 cells a
//! side or fewer ([`PixelGrid`]), blended between them for the pixels
//! inside: both are near enough linear across a cell to stay within a
//! part in 512. The cells where they are not (the sun's glow, and where
//! the ray's largest component changes axis) take each pixel's direction
//! instead. A pixel then takes multiplies, table lookups and one blend: no
//! float, no division, no square root.
//!
//! ```
//! use terracast::{Atmosphere, Camera, Framebuffer, NoProbe, Pyramid, RenderOptions, Terrain, View, render};
//! let (heights, colors) = ([0u16; 64], [[90, 140, 60]; 64]);
//! let pyramid = Pyramid::flat(Terrain::new(8, 8, &heights, &colors).unwrap());
//! let view = View::new(&Camera::looking([4.0, 0.0, 3.0], 90.0, 5.0), 32, 24).unwrap();
//! let air = Atmosphere::FLIGHT.prepare().unwrap();
//! let mut pixels = [[0u8; 3]; 32 * 24];
//! let mut frame = Framebuffer::new(&mut pixels, 32, 24).unwrap();
//! render(&pyramid, &view, &RenderOptions::default(), &mut air.sink(&view, &mut frame), &mut NoProbe);
//! // The top row is sky: the gradient, no longer the flat sky color.
//! assert_ne!(pixels[0], RenderOptions::default().sky);
//! ```

use crate::caster::walk::{lerp, Lanes};
use crate::color::Rgb;
use crate::config::MAX_RAY_SLOPE;
use crate::config::{COORD_FRAC_BITS, HEIGHT_FRAC_BITS};
use crate::divide::div_trunc;
use crate::sink::{put_sky_row, LinePlane, Sample, Sink, SKY_RUN};
use crate::view::View;
use core::fmt;

/// What fog of the ground layer's density leaves of a color at the
/// visibility distance: 2 % (the meteorological visibility).
pub const VISIBILITY_CONTRAST: f64 = 0.02;
/// The glow's strength at the disc's edge: half the way to the sun's color.
const GLOW_STRENGTH_Q8: u32 = 128;
/// Sky colors by the sine of the elevation: entry `i` at sine `i/256`.
const SKY_STEPS: usize = 256;
/// A frame's fogged sky by the sine of the elevation, for a sky pixel to
/// read without a blend: entry `i` at sine `i/1024`, its nearest (four
/// entries to a step of [`SKY_STEPS`], blended between its two ends).
const SKY_FINE_BITS: u32 = 10;
const SKY_FINE_STEPS: usize = 1 << SKY_FINE_BITS;
/// Fog tables by height: an entry every 4 voxels from 0 to 4096 (heights
/// are U12.4, below 4096).
const HEIGHT_STEP_BITS: u32 = 2;
const HEIGHT_STEPS: usize = 4096 >> HEIGHT_STEP_BITS;
/// What fog leaves of a color (in 1/256, rounded) after `i/256`
/// halvings: `256 · 2^−i/256`, from a table without a blend between its
/// entries (neighbours differ by at most one 256th). Past 10 halvings
/// nothing is left.
const TRANSMITTED_HALVINGS: usize = 10;
static TRANSMITTED: [u16; (TRANSMITTED_HALVINGS << 8) + 1] = {
    // `2^−1/256`: each entry the one before it times that.
    const STEP: f64 = 0.997_296_056_085_470_1;
    let mut table = [0u16; (TRANSMITTED_HALVINGS << 8) + 1];
    let mut left = 256.0;
    let mut i = 0;
    while i < table.len() {
        table[i] = (left + 0.5) as u16;
        left *= STEP;
        i += 1;
    }
    table
};
/// Fixed-point formats: directions Q20, heights and lengths Q8.
const DIR_BITS: u32 = 20;
const Q8: u32 = 8;
/// A frame's [`PixelGrid`]: corners a side at most. A cell then spans at
/// most a 64th of the field of view (under 2.5°), over which a pixel's
/// sine and reciprocal are near enough linear.
const GRID_CORNERS: usize = 65;
const GRID_CELLS: usize = GRID_CORNERS - 1;

/// A sun in the sky.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sun {
    /// Its heading, from +x toward +y (as a camera's yaw), degrees.
    pub azimuth_deg: f32,
    /// Its height above the horizon, degrees.
    pub elevation_deg: f32,
    /// The disc's color.
    pub color: Rgb,
    /// The disc's angular radius, degrees.
    pub disc_deg: f32,
    /// The glow's angular radius, degrees (at least the disc's).
    pub glow_deg: f32,
}

impl Sun {
    /// The unit vector toward the sun.
    pub fn direction(&self) -> [f64; 3] {
        let (azimuth, elevation) = (
            f64::from(self.azimuth_deg).to_radians(),
            f64::from(self.elevation_deg).to_radians(),
        );
        let horizontal = libm::cos(elevation);
        [
            horizontal * libm::cos(azimuth),
            horizontal * libm::sin(azimuth),
            libm::sin(elevation),
        ]
    }
}

/// Fog: the ground layer's density up to a ceiling, thinning above it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fog {
    /// The fog's color.
    pub color: Rgb,
    /// The distance, voxels, at which fog of the ground layer's density
    /// leaves 2 % of a color ([`VISIBILITY_CONTRAST`]); at least 8.
    pub visibility: f32,
    /// The ground layer's top, voxels (at least 0).
    pub ceiling: f32,
    /// Above the ceiling the density halves every `halving` voxels;
    /// `None`: it does not fall (uniform fog, which hides the sky too).
    pub halving: Option<f32>,
}

impl Fog {
    /// The density at height `h`, relative to the ground layer's.
    pub fn density(&self, h: f64) -> f64 {
        let ceiling = f64::from(self.ceiling);
        match self.halving {
            Some(halving) if h > ceiling => libm::exp2(-(h - ceiling) / f64::from(halving)),
            _ => 1.0,
        }
    }

    /// The density's integral over height from 0 to `h` (`F`; negative
    /// below 0), voxels.
    pub fn column(&self, h: f64) -> f64 {
        let ceiling = f64::from(self.ceiling);
        match self.halving {
            Some(halving) if h > ceiling => {
                let halving = f64::from(halving);
                ceiling + halving / core::f64::consts::LN_2 * (1.0 - self.density(h))
            }
            _ => h,
        }
    }

    /// `F(∞)`: the whole column, `None` for uniform fog.
    pub fn column_to_infinity(&self) -> Option<f64> {
        self.halving
            .map(|halving| f64::from(self.ceiling) + f64::from(halving) / core::f64::consts::LN_2)
    }

    /// Halvings of a color a voxel of ground-density fog takes.
    pub fn halvings_per_voxel(&self) -> f64 {
        -libm::log2(VISIBILITY_CONTRAST) / f64::from(self.visibility)
    }

    /// The distance (voxels) from an eye at height `eye` beyond which a
    /// hit at or below `highest` keeps less than a 512th of its color (half
    /// an 8-bit level): the path there never rises above the higher of
    /// the two, so its density is never below the density there. Terrain
    /// farther than this shows as fog: a renderer may stop its rays there
    /// and a tile cache leave the tiles beyond it unloaded.
    pub fn opaque_distance(&self, eye: f64, highest: f64) -> f64 {
        let thinnest = self.density(eye.max(highest));
        9.0 / (self.halvings_per_voxel() * thinnest)
    }

    /// What a straight path of `length` voxels from height `a` to height
    /// `b` leaves of a color (exact).
    pub fn transmittance(&self, length: f64, a: f64, b: f64) -> f64 {
        let mean = if (b - a).abs() < 1e-9 {
            self.density(0.5 * (a + b))
        } else {
            (self.column(b) - self.column(a)) / (b - a)
        };
        libm::exp2(-self.halvings_per_voxel() * length * mean)
    }

    /// What the path from height `a` up to the sky at elevation sine `s`
    /// leaves of the sky's color (exact): nothing at or below the horizon,
    /// nor through uniform fog.
    pub fn transmittance_to_sky(&self, a: f64, s: f64) -> f64 {
        match self.column_to_infinity() {
            Some(all) if s > 0.0 => {
                libm::exp2(-self.halvings_per_voxel() * (all - self.column(a)) / s)
            }
            _ => 0.0,
        }
    }
}

/// A frame's sky, sun and fog, as a user sets them (see the module).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Atmosphere {
    /// The sky's color at the horizon (and below it).
    pub horizon: Rgb,
    /// The sky's color straight up.
    pub zenith: Rgb,
    /// A sun, if any.
    pub sun: Option<Sun>,
    /// Fog, if any.
    pub fog: Option<Fog>,
}

/// Why an atmosphere could not be prepared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AtmosphereError {
    /// A number is NaN or infinite.
    NotFinite,
    /// The sun is below the horizon or its disc and glow are out of order.
    Sun,
    /// The fog's visibility is under 8 voxels, its ceiling below 0 or its
    /// halving height not positive.
    Fog,
}

impl fmt::Display for AtmosphereError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NotFinite => "atmosphere value is NaN or infinite",
            Self::Sun => "sun needs elevation 0 to 90 degrees and 0 < disc <= glow <= 90 degrees",
            Self::Fog => "fog needs visibility >= 8 voxels, ceiling >= 0 and halving height > 0",
        })
    }
}

impl core::error::Error for AtmosphereError {}

impl Atmosphere {
    /// The flight's atmosphere: a blue gradient, a sun in the south-west
    /// at 35°, and haze in a ground layer 30 voxels deep, halving every
    /// 45 voxels above it, with 2500 voxels' visibility.
    pub const FLIGHT: Self = Self {
        horizon: [196, 214, 230],
        zenith: [62, 110, 190],
        sun: Some(Sun {
            azimuth_deg: 225.0,
            elevation_deg: 35.0,
            color: [255, 246, 220],
            disc_deg: 0.6,
            glow_deg: 12.0,
        }),
        fog: Some(Fog {
            color: [196, 210, 222],
            visibility: 2500.0,
            ceiling: 30.0,
            halving: Some(45.0),
        }),
    };

    /// The sky's color (no fog) along the unit direction `e`, exact.
    pub fn sky_exact(&self, e: [f64; 3]) -> [f64; 3] {
        let gradient = sky_weight(e[2]);
        let (horizon, zenith) = (self.horizon.map(f64::from), self.zenith.map(f64::from));
        let sky = core::array::from_fn(|i| horizon[i] + (zenith[i] - horizon[i]) * gradient);
        let Some(sun) = &self.sun else {
            return sky;
        };
        let s = sun.direction();
        let dot = e[0] * s[0] + e[1] * s[1] + e[2] * s[2];
        let cross = [
            e[1] * s[2] - e[2] * s[1],
            e[2] * s[0] - e[0] * s[2],
            e[0] * s[1] - e[1] * s[0],
        ];
        let q = cross.iter().map(|c| c * c).sum::<f64>();
        let color = sun.color.map(f64::from);
        let (disc, glow) = (sine_squared(sun.disc_deg), sine_squared(sun.glow_deg));
        if dot <= 0.0 || q >= glow {
            sky
        } else if q <= disc {
            color
        } else {
            let g = 1.0 - q / glow;
            let t = f64::from(GLOW_STRENGTH_Q8) / 256.0 * g * g;
            core::array::from_fn(|i| sky[i] + (color[i] - sky[i]) * t)
        }
    }

    /// What a ray from an eye at height `eye_z` along direction `d` shows,
    /// exact: `color` seen through the fog at `hit` (the hit's distance
    /// from the eye and its height), or the sky where there is no hit.
    /// The reference renders with this.
    pub fn exact(
        &self,
        d: [f64; 3],
        eye_z: f64,
        hit: Option<(f64, f64)>,
        color: [f64; 3],
    ) -> [f64; 3] {
        let length = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        let e = d.map(|v| v / length);
        let (seen, transmittance) = match hit {
            Some((distance, height)) => (
                color,
                self.fog
                    .map_or(1.0, |fog| fog.transmittance(distance, eye_z, height)),
            ),
            None => (
                self.sky_exact(e),
                self.fog
                    .map_or(1.0, |fog| fog.transmittance_to_sky(eye_z, e[2])),
            ),
        };
        let fog = self.fog.map_or([0; 3], |fog| fog.color).map(f64::from);
        core::array::from_fn(|i| fog[i] + (seen[i] - fog[i]) * transmittance)
    }

    /// Checks the settings and builds the fixed-point tables (once; a
    /// frame then needs only [`PreparedAtmosphere::sink`]).
    pub fn prepare(&self) -> Result<PreparedAtmosphere, AtmosphereError> {
        if let Some(sun) = &self.sun {
            let numbers = [
                sun.azimuth_deg,
                sun.elevation_deg,
                sun.disc_deg,
                sun.glow_deg,
            ];
            if numbers.iter().any(|v| !v.is_finite()) {
                return Err(AtmosphereError::NotFinite);
            }
            let in_order =
                sun.disc_deg > 0.0 && sun.disc_deg <= sun.glow_deg && sun.glow_deg <= 90.0;
            if !((0.0..=90.0).contains(&sun.elevation_deg) && in_order) {
                return Err(AtmosphereError::Sun);
            }
        }
        if let Some(fog) = &self.fog {
            let numbers = [fog.visibility, fog.ceiling, fog.halving.unwrap_or(1.0)];
            if numbers.iter().any(|v| !v.is_finite()) {
                return Err(AtmosphereError::NotFinite);
            }
            if fog.visibility < 8.0 || fog.ceiling < 0.0 || fog.halving.is_some_and(|h| h <= 0.0) {
                return Err(AtmosphereError::Fog);
            }
        }
        let (horizon, zenith) = (self.horizon.map(f64::from), self.zenith.map(f64::from));
        let sky = core::array::from_fn(|i| {
            let w = sky_weight(i as f64 / SKY_STEPS as f64);
            core::array::from_fn(|c| round_channel(horizon[c] + (zenith[c] - horizon[c]) * w))
        });
        let sun = self.sun.map(|sun| SunTable {
            direction: sun.direction().map(|v| to_fixed(v, DIR_BITS)),
            disc: to_fixed(sine_squared(sun.disc_deg), 2 * DIR_BITS),
            glow: to_fixed(sine_squared(sun.glow_deg), 2 * DIR_BITS).max(1),
            glow_cosine: to_fixed(
                libm::cos(f64::from(sun.glow_deg).to_radians()),
                2 * DIR_BITS,
            ) - (1 << 26),
            glow_radians: f64::from(sun.glow_deg).to_radians(),
            color: sun.color,
        });
        let fog = self.fog.map(|fog| FogTable {
            fog,
            color_lanes: Lanes::of(fog.color),
            halvings_q32: to_fixed(fog.halvings_per_voxel(), 32) as u32,
            column: core::array::from_fn(|i| {
                to_fixed(fog.column((i << HEIGHT_STEP_BITS) as f64), Q8) as u32
            }),
            density: core::array::from_fn(|i| {
                to_fixed(fog.density((i << HEIGHT_STEP_BITS) as f64), 16) as u32
            }),
        });
        Ok(PreparedAtmosphere { sky, sun, fog })
    }
}

/// The gradient's weight of the zenith color at elevation sine `s`.
fn sky_weight(s: f64) -> f64 {
    let below = 1.0 - s.clamp(0.0, 1.0);
    1.0 - below * below
}

fn sine_squared(deg: f32) -> f64 {
    let s = libm::sin(f64::from(deg).to_radians());
    s * s
}

fn to_fixed(v: f64, bits: u32) -> i64 {
    libm::round(v * (1u64 << bits) as f64) as i64
}

fn round_channel(v: f64) -> u8 {
    libm::round(v).clamp(0.0, 255.0) as u8
}

/// An [`Atmosphere`] in fixed point, ready for frames.
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedAtmosphere {
    sky: [Rgb; SKY_STEPS + 1],
    sun: Option<SunTable>,
    fog: Option<FogTable>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct SunTable {
    /// Unit vector, Q20; the disc's and the glow's sin² of their radius,
    /// Q40.
    direction: [i64; 3],
    disc: i64,
    glow: i64,
    /// The cosine of the glow's radius, Q40, less a margin for the unit
    /// vector's rounding.
    glow_cosine: i64,
    /// The glow's radius.
    glow_radians: f64,
    color: Rgb,
}

#[derive(Debug, Clone, PartialEq)]
struct FogTable {
    fog: Fog,
    /// The fog's color as a blend takes it.
    color_lanes: Lanes,
    /// Halvings a voxel at ground density, Q32 (below 1: the visibility
    /// is at least 8 voxels).
    halvings_q32: u32,
    /// `F` (Q8 voxels) and the density (Q16) every 4 voxels of height.
    column: [u32; HEIGHT_STEPS + 1],
    density: [u32; HEIGHT_STEPS + 1],
}

/// What a frame's pixels share: the view's directions in Q20 and the eye.
/// A pixel's direction is below 2^7 in size (the widest field of view
/// and the tallest image), so its components and their steps fit 32 bits.
#[derive(Debug, Clone)]
pub struct AtmosphereFrame {
    base: [i32; 3],
    per_column: [i32; 3],
    per_row: [i32; 3],
    top_row: i32,
    /// The eye's height, Q16.
    eye_q16: i64,
    /// The sky as this eye sees it through the fog, by sine: entry `i`
    /// at sine `i/1024` (see [`SKY_FINE_STEPS`]); and what the fog leaves
    /// of the sky at each entry of [`PreparedAtmosphere`]'s gradient (in
    /// 1/256; for the sun's disc and glow, which go on before the fog).
    sky: [Rgb; SKY_FINE_STEPS + 1],
    sky_weights: [u16; SKY_STEPS + 1],
    /// The fog's halvings a voxel of path (Q31) at the mean density from
    /// the eye to each height of the fog's tables: a path's length times
    /// it is the halvings along it.
    rate: [u32; HEIGHT_STEPS + 1],
    grid: PixelGrid,
}

/// What a pixel needs of its direction, at the corners of square cells of
/// `2^bits` pixels (corner `(i, j)` at column `i·2^bits`, row `j·2^bits`
/// from the bottom), blended between the corners for the pixels inside.
#[derive(Debug, Clone)]
struct PixelGrid {
    bits: u32,
    /// The sine of the elevation, Q20 (below the horizon negative).
    sine: [[i32; GRID_CORNERS]; GRID_CORNERS],
    /// The reciprocal (Q16) of the unit direction's larger of its vertical
    /// component and its larger horizontal one: a ray's length over its
    /// height drop, or over its distance along its major axis.
    reciprocal: [[i32; GRID_CORNERS]; GRID_CORNERS],
    /// Per cell, [`CELL_VERTICAL`], [`CELL_MIXED`] and [`CELL_SUN`].
    cells: [[u8; GRID_CELLS]; GRID_CELLS],
}

/// The cell's rays are steeper than 45°: their length is over the height
/// drop.
const CELL_VERTICAL: u8 = 1;
/// The corners disagree on the ray's largest component (vertical or which
/// horizontal axis), where the reciprocal has a kink: the pixels take
/// their own direction.
const CELL_MIXED: u8 = 2;
/// The cell may reach into the sun's glow: its sky pixels take their own
/// direction.
const CELL_SUN: u8 = 4;

impl PixelGrid {
    /// The grid of a `width` × `height` image whose pixel `(column, row)`
    /// looks along `direction(column, row)` (Q20), the sun (if any) along
    /// `sun`.
    fn new(
        width: u32,
        height: u32,
        direction: impl Fn(i32, i32) -> [i32; 3],
        sun: Option<&SunTable>,
    ) -> Self {
        // The smallest cells (a power of two pixels) that cover the image
        // in 64 a side: 8 pixels at 320 × 240, 1 at 64 × 48 (as many
        // corners as pixels: each pixel's own direction, in effect).
        let mut bits = 0;
        while ((width.max(height) - 1) >> bits) as usize >= GRID_CELLS {
            bits += 1;
        }
        let mut grid = Self {
            bits,
            sine: [[0; GRID_CORNERS]; GRID_CORNERS],
            reciprocal: [[0; GRID_CORNERS]; GRID_CORNERS],
            cells: [[0; GRID_CELLS]; GRID_CELLS],
        };
        let corners = |side: u32| ((side - 1) >> bits) as usize + 2;
        let (columns, rows) = (corners(width), corners(height));
        // Which component is largest at each corner (0 vertical, 1 x, 2
        // y), and the sun's cosine there (Q40).
        let mut largest = [[0u8; GRID_CORNERS]; GRID_CORNERS];
        let mut sun_cosine = [[i64::MIN; GRID_CORNERS]; GRID_CORNERS];
        for j in 0..rows {
            for i in 0..columns {
                let d = direction((i << bits) as i32, (j << bits) as i32);
                let unit = Unit::new(d);
                grid.sine[j][i] = unit.of(d[2]) as i32;
                let (axis, component) = largest_component(d);
                largest[j][i] = axis;
                grid.reciprocal[j][i] = reciprocal_q16(unit.of_size(component)) as i32;
                if let Some(sun) = sun {
                    sun_cosine[j][i] = sun.cosine(d.map(|c| unit.of(c)));
                }
            }
        }
        // A pixel's direction lies between its cell's corners', so within
        // a cell's diagonal of the nearest corner; the cell at the image's
        // center subtends the most. Half as much again, for the rounding.
        let near_sun = sun.map(|sun| {
            let center = |offset: usize| {
                let c = ((width / 2) >> bits) as usize + offset;
                let r = ((height / 2) >> bits) as usize + offset;
                direction((c << bits) as i32, (r << bits) as i32).map(f64::from)
            };
            let (a, b) = (center(0), center(1));
            let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
            let length = |v: [f64; 3]| libm::sqrt(v.iter().map(|c| c * c).sum::<f64>());
            let diagonal = libm::acos((dot / (length(a) * length(b))).clamp(-1.0, 1.0));
            let reach = (sun.glow_radians + 1.5 * diagonal).min(core::f64::consts::PI);
            to_fixed(libm::cos(reach), 2 * DIR_BITS) - (1 << 26)
        });
        for j in 0..rows - 1 {
            for i in 0..columns - 1 {
                let four = [(j, i), (j, i + 1), (j + 1, i), (j + 1, i + 1)];
                let axis = largest[j][i];
                let mut cell = if axis == 0 { CELL_VERTICAL } else { 0 };
                if four.iter().any(|&(r, c)| largest[r][c] != axis) {
                    cell |= CELL_MIXED;
                }
                if near_sun.is_some_and(|near| four.iter().any(|&(r, c)| sun_cosine[r][c] > near)) {
                    cell |= CELL_SUN;
                }
                grid.cells[j][i] = cell;
            }
        }
        grid
    }

    /// The cell of pixel `(column, row)` (row from the bottom): its flags,
    /// and where the pixel lies in it.
    #[inline(always)]
    fn cell(&self, column: i32, row: i32) -> (u8, Corner) {
        let (i, j) = ((column >> self.bits) as usize, (row >> self.bits) as usize);
        let mask = (1 << self.bits) - 1;
        let flags = match self.cells.get(j).and_then(|cells| cells.get(i)) {
            Some(&flags) => flags,
            // (Every pixel of the image has a cell.)
            None => CELL_MIXED | CELL_SUN,
        };
        let corner = Corner {
            i,
            j,
            x: column & mask,
            y: row & mask,
        };
        (flags, corner)
    }

    /// `table` at `corner`'s pixel, blended between the cell's corners.
    #[inline(always)]
    fn blend(&self, table: &[[i32; GRID_CORNERS]; GRID_CORNERS], at: &Corner) -> i32 {
        let (low, high) = (&table[at.j], &table[at.j + 1]);
        let corners = [low[at.i], low[at.i + 1], high[at.i], high[at.i + 1]];
        self.blend_corners(&corners, at.x, at.y)
    }

    /// A value at pixel `(x, y)` of a cell (from its lower left corner)
    /// blended between the values at its `corners` (lower left, lower
    /// right, upper left, upper right).
    #[inline(always)]
    fn blend_corners(&self, corners: &[i32; 4], x: i32, y: i32) -> i32 {
        let (left, right) = self.edges_at(corners, y);
        left + (((right - left) * x) >> self.bits)
    }

    /// The values on a cell's left and right edges at row `y` of it
    /// (from its bottom), blended between its `corners` (as
    /// [`PixelGrid::blend_corners`]): along a row of the cell, a pixel's
    /// value is the blend of these two, so a row of pixels steps it by
    /// one add a pixel ([`PreparedAtmosphere::sink_over_sky`]).
    #[inline(always)]
    fn edges_at(&self, corners: &[i32; 4], y: i32) -> (i32, i32) {
        let [low_left, low_right, high_left, high_right] = *corners;
        (
            low_left + (((high_left - low_left) * y) >> self.bits),
            low_right + (((high_right - low_right) * y) >> self.bits),
        )
    }

    /// What a sky pixel of cell `(i, j)` needs ([`SkyCell`]).
    fn sky_cell(&self, i: i32, j: i32) -> SkyCell {
        let (column, row) = (i as usize, j as usize);
        let flags = self.cells.get(row).and_then(|cells| cells.get(column));
        match flags {
            Some(&flags) if flags & CELL_SUN == 0 => {
                let (low, high) = (&self.sine[row], &self.sine[row + 1]);
                SkyCell {
                    i,
                    j,
                    own_direction: false,
                    sine: [low[column], low[column + 1], high[column], high[column + 1]],
                }
            }
            // Near the sun, or (no pixel of the image is) outside the grid.
            _ => SkyCell {
                i,
                j,
                own_direction: true,
                sine: [0; 4],
            },
        }
    }
}

/// What a sink keeps from one sky pixel to the next
/// ([`PreparedAtmosphere::pixel_color`]): the last one's cell of the frame's
/// grid and the sines at its corners. It belongs to one
/// [`AtmosphereFrame`]: start each frame from `SkyCell::default()`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SkyCell {
    i: i32,
    j: i32,
    /// Its pixels take their own direction: it may reach the sun's glow.
    own_direction: bool,
    sine: [i32; 4],
}

impl SkyCell {
    /// Whether every pixel of the cell looks at or below the horizon, away
    /// from the sun: their sines, blended between the corners', are then
    /// at most 0 (a blend's rounding stays within its ends), and their sky
    /// is the horizon's color.
    fn below_horizon(&self) -> bool {
        !self.own_direction && self.sine.iter().all(|&sine| sine <= 0)
    }
}

impl Default for SkyCell {
    /// No cell yet.
    fn default() -> Self {
        Self {
            i: -1,
            j: -1,
            own_direction: true,
            sine: [0; 4],
        }
    }
}

/// A pixel's place in its [`PixelGrid`] cell: the cell's lower-left
/// corner, and the pixel's offset from it.
#[derive(Debug, Clone, Copy)]
struct Corner {
    i: usize,
    j: usize,
    x: i32,
    y: i32,
}

impl PreparedAtmosphere {
    /// What `view`'s pixels share.
    pub fn frame(&self, view: &View) -> AtmosphereFrame {
        let q20 = |v: [fixed::types::I32F32; 3]| v.map(|c| (c.to_bits() >> (32 - DIR_BITS)) as i32);
        let eye_q16 = view.eye[2].to_bits();
        let eye = eye_q16 as f64 / f64::from(1u32 << COORD_FRAC_BITS);
        let (eye_column, sky_column) = match &self.fog {
            Some(table) => {
                let here = table.fog.column(eye);
                (
                    to_fixed(here, Q8),
                    table
                        .fog
                        .column_to_infinity()
                        .map(|all| to_fixed((all - here).max(0.0), Q8)),
                )
            }
            None => (0, None),
        };
        let sky_weights: [u16; SKY_STEPS + 1] = core::array::from_fn(|i| match &self.fog {
            None => 256,
            Some(table) => match sky_column {
                // Sine i/256, Q20.
                Some(column) if i > 0 => {
                    // Once a frame: a plain division.
                    let over_sine = div_trunc(column << DIR_BITS, (i as i64) << 12);
                    table.transmitted(over_sine as u64) as u16
                }
                _ => 0,
            },
        });
        let fog_color = self.fog.as_ref().map_or([0; 3], |table| table.fog.color);
        let fogged: [Lanes; SKY_STEPS + 1] = core::array::from_fn(|i| {
            Lanes::of(lerp(fog_color, self.sky[i], u32::from(sky_weights[i])))
        });
        let fine_per_step = SKY_FINE_STEPS / SKY_STEPS;
        let sky = core::array::from_fn(|i| {
            let (at, part) = (i / fine_per_step, i % fine_per_step);
            let next = fogged[(at + 1).min(SKY_STEPS)];
            fogged[at]
                .lerp(next, (part * 256 / fine_per_step) as u32)
                .rgb()
        });
        // The mean density from the eye to each height of the table:
        // `(F(b) − F(a)) / (b − a)`, the density midway within a voxel of
        // the eye's height.
        let eye_q8 = eye_q16 >> (COORD_FRAC_BITS - Q8);
        let rate = core::array::from_fn(|i| match &self.fog {
            None => 0,
            Some(table) => {
                let height = (i as i64) << (HEIGHT_STEP_BITS + Q8);
                let rise = height - eye_q8;
                let mean_q16 = if rise.abs() < 1 << Q8 {
                    table.density_at((height + eye_q8) / 2)
                } else {
                    let columns = table.column_at(height) - eye_column;
                    div_trunc(columns << 16, rise).clamp(0, 1 << 16)
                };
                // Below 2^31: the halvings a voxel are below 1.
                ((mean_q16 as u64 * u64::from(table.halvings_q32)) >> 17) as u32
            }
        });
        let (base, per_column, per_row) = (q20(view.base), q20(view.per_column), q20(view.per_row));
        let grid = PixelGrid::new(
            view.width(),
            view.height(),
            |column, row| direction(&base, &per_column, &per_row, column, row),
            self.sun.as_ref(),
        );
        AtmosphereFrame {
            sky,
            sky_weights,
            rate,
            base,
            per_column,
            per_row,
            top_row: view.height() as i32 - 1,
            eye_q16,
            grid,
        }
    }

    /// A sink that gives each pixel of `view` this atmosphere and passes
    /// it on to `sink`, each pixel once, as the renderer puts it.
    pub fn sink<'a, S: Sink>(&'a self, view: &View, sink: S) -> AtmosphereSink<'a, S> {
        self.sink_of(view, sink)
    }

    /// An [`AtmosphereSink`] of `view` into `sink`, nothing put yet.
    fn sink_of<'a, S: Sink, const SKY_DRAWN: bool>(
        &'a self,
        view: &View,
        sink: S,
    ) -> AtmosphereSink<'a, S, SKY_DRAWN> {
        AtmosphereSink {
            air: self,
            frame: self.frame(view),
            line: LineShade::default(),
            sky: SkyCell::default(),
            sink,
        }
    }

    /// [`PreparedAtmosphere::sink`] for a `sink` that stores its pixels (a
    /// frame buffer), with the sky drawn into it first: the same frame,
    /// cheaper. A sky pixel's color depends on the pixel alone, so the sky
    /// is put row by row along each cell of the frame's grid, its sine
    /// stepped by one add a pixel, and below the horizon (where the sky is
    /// the horizon's color) as one color; the renderer's sky pixels are
    /// then not put again, and the line caster does not walk the pixels
    /// above a line's last hit at all ([`Sink::sky_is_drawn`]). So `sink`
    /// receives the terrain's pixels twice, the sky first: only for a
    /// sink that keeps the last color put (not one that streams its
    /// pixels out), and only for a render that puts each pixel once
    /// ([`crate::render`]: a governor's refined line may put sky where its
    /// base pass put terrain).
    pub fn sink_over_sky<'a, S: Sink>(
        &'a self,
        view: &View,
        sink: S,
    ) -> AtmosphereSink<'a, S, true> {
        let mut hazy = self.sink_of(view, sink);
        hazy.draw_sky(view.width(), view.height());
        hazy
    }

    /// [`PreparedAtmosphere::color`] of pixel `(x, y)` of `frame` whose
    /// ray saw `sample`, for a sink that keeps `sky` from one pixel to the
    /// next: a sky pixel from the cell kept from the sky pixel before it
    /// ([`SkyCell`]). The same color as [`PreparedAtmosphere::color`]'s.
    #[inline(always)]
    pub fn pixel_color(
        &self,
        frame: &AtmosphereFrame,
        sky: &mut SkyCell,
        x: u32,
        y: u32,
        sample: &Sample,
    ) -> Rgb {
        if sample.is_sky() {
            self.sky_pixel(frame, sky, x, y)
        } else {
            self.color(frame, x, y, sample)
        }
    }

    /// The sky's color at pixel `(x, y)` of `frame`, `cell` kept from the
    /// sky pixel before it: the sky above a line's last hit comes pixel
    /// after pixel along the line, mostly within one cell of the frame's
    /// grid, whose corners are read once. Near the sun (and outside the
    /// grid) from the pixel's own direction. The one way a sky pixel is
    /// colored: [`PreparedAtmosphere::color`] calls it with a new cell.
    #[inline(always)]
    fn sky_pixel(&self, frame: &AtmosphereFrame, cell: &mut SkyCell, x: u32, y: u32) -> Rgb {
        let grid = &frame.grid;
        let (column, row) = (x as i32, frame.top_row - y as i32);
        let (i, j) = (column >> grid.bits, row >> grid.bits);
        if (i, j) != (cell.i, cell.j) {
            *cell = grid.sky_cell(i, j);
        }
        if cell.own_direction {
            let d = direction(&frame.base, &frame.per_column, &frame.per_row, column, row);
            return self.sky_color(frame, d, &Unit::new(d));
        }
        let mask = (1 << grid.bits) - 1;
        let sine = grid.blend_corners(&cell.sine, column & mask, row & mask);
        fogged_sky(&frame.sky, i64::from(sine))
    }

    /// The color of pixel `(x, y)` (y = 0 at the top) of `frame` whose ray
    /// saw `sample`: the sky's (gradient, sun, fog to the sky) where it saw
    /// sky, else the sample's color through the fog to its hit.
    pub fn color(&self, frame: &AtmosphereFrame, x: u32, y: u32, sample: &Sample) -> Rgb {
        let fog = self.fog.as_ref();
        if fog.is_none() && !sample.is_sky() {
            return sample.color;
        }
        let (column, row) = (x as i32, frame.top_row - y as i32);
        let pixel_direction = || {
            let d = direction(&frame.base, &frame.per_column, &frame.per_row, column, row);
            (d, Unit::new(d))
        };
        let grid = &frame.grid;
        let (cell, at) = grid.cell(column, row);
        let Some(table) = fog.filter(|_| !sample.is_sky()) else {
            return self.sky_pixel(frame, &mut SkyCell::default(), x, y);
        };
        // The hit's distance from the eye: its major-axis distance or its
        // height below the eye, whichever the direction conditions better,
        // over that component of the unit direction (at least 1/√3: the
        // larger of the two is the largest of the three).
        let (vertical, reciprocal) = if cell & CELL_MIXED == 0 {
            (
                cell & CELL_VERTICAL != 0,
                grid.blend(&grid.reciprocal, &at) as u32,
            )
        } else {
            let (d, unit) = pixel_direction();
            let (axis, component) = largest_component(d);
            (axis == 0, reciprocal_q16(unit.of_size(component)))
        };
        let along = if vertical {
            drop(frame, sample)
        } else {
            sample.distance
        };
        let distance_q8 = word((u64::from(along) * u64::from(reciprocal)) >> (16 + 16 - Q8));
        self.fogged(frame, table, sample, distance_q8)
    }

    /// `sample`'s color through `table`'s fog over the `distance_q8`
    /// (Q8 voxels) from the eye to its hit: the distance times the rate
    /// at the hit's height (the mean density from the eye to there) is
    /// the halvings along the path.
    #[inline(always)]
    fn fogged(
        &self,
        frame: &AtmosphereFrame,
        table: &FogTable,
        sample: &Sample,
        distance_q8: u32,
    ) -> Rgb {
        // In words: the height is below 2^20 (Q8); the rate below 2^31,
        // so the halvings (Q8, rounded) fit a word: one 32 × 32-bit
        // product.
        let height_q8 = (sample.elevation >> (COORD_FRAC_BITS - Q8)).max(0) as u32;
        let rate = between(&frame.rate, height_q8);
        let halvings_q8 = (u64::from(distance_q8) * u64::from(rate) + (1 << 30)) >> 31;
        let weight = left_after(halvings_q8 as u32);
        table
            .color_lanes
            .lerp(Lanes::of(sample.color), weight)
            .rgb()
    }

    /// The color of pixel `(x, y)` whose ray saw `sample`, as
    /// [`PreparedAtmosphere::color`]; a hit's fog from the ray's slope in
    /// its line's plane (see [`Sink::put_ray`]) instead of the pixel's
    /// position: the ray's length a unit of major-axis distance is that
    /// of `(m, slope)`, `m` the plane's horizontal length a unit of
    /// major-axis distance, from a table by `slope/m`.
    #[inline(always)]
    pub fn ray_color(
        &self,
        frame: &AtmosphereFrame,
        line: &LineShade,
        (x, y): (u32, u32),
        sample: &Sample,
        slope: i32,
    ) -> Rgb {
        let Some(table) = self.fog.as_ref().filter(|_| !sample.is_sky()) else {
            return self.color(frame, x, y, sample);
        };
        // A ray with no run (straight down) has no major-axis distance:
        // its length is its height change.
        let vertical = slope.unsigned_abs() >= MAX_SLOPE_Q16;
        let distance_q8 = if vertical {
            drop(frame, sample) >> (COORD_FRAC_BITS - Q8)
        } else {
            // The ray's length a unit of major-axis distance, Q16:
            // `m·√(1 + u²)`, `u` the slope over `m` (Q16, below 2^30), or
            // for a steep ray `|slope|·√(1 + 1/u²)`.
            let u = ((u64::from(slope.unsigned_abs()) * u64::from(line.inverse_m)) >> 20) as u32;
            let length = if u < 1 << 16 {
                let at = ((u + (1 << 5)) >> 6) as usize;
                let stretch = STRETCH_FINE.get(at).map_or(0, |&s| u32::from(s)) + (1 << 16);
                (u64::from(line.m) * u64::from(stretch)) >> 16
            } else {
                (u64::from(slope.unsigned_abs()) * StretchEntry::steep(u).of_table(&STRETCH_HIGH))
                    >> 16
            };
            word((u64::from(sample.distance) * length) >> (16 + 16 - Q8))
        };
        self.fogged(frame, table, sample, distance_q8)
    }

    /// The sky along `d` (Q20, `unit` its unit direction), through the
    /// fog: the frame's fogged gradient by the sine of the elevation,
    /// blended between neighbouring entries, and near the sun its disc and
    /// glow over the gradient, then the fog.
    fn sky_color(&self, frame: &AtmosphereFrame, d: [i32; 3], unit: &Unit) -> Rgb {
        let up = unit.of(d[2]);
        let Some(sun) = &self.sun else {
            return fogged_sky(&frame.sky, up);
        };
        let e = [unit.of(d[0]), unit.of(d[1]), up];
        if !sun.near(e) {
            return fogged_sky(&frame.sky, up);
        }
        let sine = up.clamp(0, 1 << DIR_BITS);
        let (at, fraction) = sky_entry(sine);
        let color = sun.over(sky_between(&self.sky, at, fraction), e);
        let Some(table) = &self.fog else {
            return color;
        };
        let weights = &frame.sky_weights;
        let low = u32::from(weights[at.min(SKY_STEPS)]);
        let high = u32::from(weights[(at + 1).min(SKY_STEPS)]);
        let weight = low + (((high - low.min(high)) * fraction) >> 8);
        lerp(table.fog.color, color, weight)
    }
}

/// What fog leaves of a color (in 1/256) after `halvings_q8` halvings
/// (Q8).
#[inline(always)]
fn left_after(halvings_q8: u32) -> u32 {
    match TRANSMITTED.get(halvings_q8 as usize) {
        Some(&left) => u32::from(left),
        None => 0,
    }
}

/// `v` within a word, held at the largest.
#[inline(always)]
fn word(v: u64) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

/// `table` (an entry every 4 voxels of height, each below 2^31, so a
/// step between two fits a word) at height `h` (Q8), linear between
/// entries, held past the last: one 32 × 32-bit product. The fog's
/// tables by height and the frame's rate table.
#[inline(always)]
fn between(table: &[u32; HEIGHT_STEPS + 1], h: u32) -> u32 {
    let step_q8 = HEIGHT_STEP_BITS + Q8;
    let at = (h >> step_q8) as usize;
    match (table.get(at), table.get(at + 1)) {
        (Some(&low), Some(&high)) => {
            let step = high.wrapping_sub(low) as i32;
            let fraction = (h & ((1 << step_q8) - 1)) as i32;
            low.wrapping_add(((i64::from(step) * i64::from(fraction)) >> step_q8) as u32)
        }
        _ => table[HEIGHT_STEPS],
    }
}

/// Pixel `(column, row)`'s direction (row from the bottom; Q20) from the
/// frame's first pixel's and its steps: each product is one 32 × 32-bit
/// multiply, and the sum fits 32 bits.
#[inline(always)]
fn direction(
    base: &[i32; 3],
    per_column: &[i32; 3],
    per_row: &[i32; 3],
    column: i32,
    row: i32,
) -> [i32; 3] {
    core::array::from_fn(|i| {
        (i64::from(base[i])
            + i64::from(column) * i64::from(per_column[i])
            + i64::from(row) * i64::from(per_row[i])) as i32
    })
}

/// Direction `d`'s largest component by size, vertical first (0, else 1
/// for x, 2 for y, x on a tie between them; the horizontal one on a tie
/// with the vertical), and that size.
#[inline(always)]
fn largest_component(d: [i32; 3]) -> (u8, u32) {
    let [x, y, z] = d.map(i32::unsigned_abs);
    if z > x.max(y) {
        (0, z)
    } else if x >= y {
        (1, x)
    } else {
        (2, y)
    }
}

/// Where the sky's tables by sine hold elevation sine `sine` (Q20, in
/// [0, 1]): the entry below it and the fraction (in 1/256) to the next.
#[inline(always)]
fn sky_entry(sine: i64) -> (usize, u32) {
    let at = (sine >> (DIR_BITS - 8)) as usize;
    (at, ((sine >> (DIR_BITS - 16)) & 0xFF) as u32)
}

/// `table` at entry `at` blended `fraction`/256 toward the next.
#[inline(always)]
fn sky_between(table: &[Rgb; SKY_STEPS + 1], at: usize, fraction: u32) -> Rgb {
    match table.get(at + 1) {
        Some(&next) => lerp(table[at.min(SKY_STEPS)], next, fraction),
        None => table[SKY_STEPS],
    }
}

/// The frame's fogged sky gradient at elevation sine `up` (Q20; below
/// the horizon, the horizon's): its entry nearest `up`.
#[inline(always)]
fn fogged_sky(sky: &[Rgb; SKY_FINE_STEPS + 1], up: i64) -> Rgb {
    let half = 1 << (DIR_BITS - SKY_FINE_BITS - 1);
    let at = ((up.clamp(0, 1 << DIR_BITS) + half) >> (DIR_BITS - SKY_FINE_BITS)) as usize;
    sky[at.min(SKY_FINE_STEPS)]
}

/// How far below (or above) the eye `sample`'s hit is, Q16, within a
/// word.
#[inline(always)]
fn drop(frame: &AtmosphereFrame, sample: &Sample) -> u32 {
    let drop = (frame.eye_q16 - i64::from(sample.elevation)).unsigned_abs();
    drop.min(u64::from(u32::MAX)) as u32
}

/// A ray's slope at and past which it has no run along the major axis.
const MAX_SLOPE_Q16: u32 = (MAX_RAY_SLOPE as u32) << COORD_FRAC_BITS;

/// `√(1 + u²)` (Q16) for `u` = `i/256`, `i` in 0..=256: a ray's length
/// over its horizontal length, `u` its slope over its line's `m`, where
/// that is below 1.
const STRETCH_LOW: [u32; 257] = {
    let mut table = [0u32; 257];
    let mut i = 0;
    while i < 257 {
        table[i] = ((65536 + (i * i) as u64) << 16).isqrt() as u32;
        i += 1;
    }
    table
};

/// `√(1 + 1/u²)` (Q16) for `u = 2^e·(1 + k/32)`, at entry `32e + k`
/// (`e` in 0..8, the last entry `u = 256`): a ray's length over its
/// height change, where its slope is `u` times its line's `m`, 1 or more.
/// Past 256 it is 1 within 2^−17.
const STRETCH_HIGH: [u32; 257] = {
    let mut table = [0u32; 257];
    let mut i = 0;
    while i < 257 {
        let (e, k) = ((i / 32) as u32, (i % 32) as u64);
        // 1/u² = 2^−2e · 32² / (32 + k)², in Q32.
        let inverse_squared = (1u64 << (42 - 2 * e)) / ((32 + k) * (32 + k));
        table[i] = ((1u64 << 32) + inverse_squared).isqrt() as u32;
        i += 1;
    }
    table
};

/// `√(1 + u²) − 1` (Q16) for `u = i/1024`, `i` in 0..=1024: a ray's
/// length over its horizontal length, as [`STRETCH_LOW`], at the entry
/// nearest its `u`, without a blend (neighbours differ by under 2^−10 of
/// the length).
const STRETCH_FINE: [u16; 1025] = {
    let mut table = [0u16; 1025];
    let mut i = 0;
    while i < 1025 {
        let root = ((1u64 << 52) + (((i * i) as u64) << 32)).isqrt();
        table[i] = ((root - (1 << 26) + (1 << 9)) >> 10) as u16;
        i += 1;
    }
    table
};

/// Where a `u` lies in a table by `u` ([`STRETCH_LOW`] below 1,
/// [`STRETCH_HIGH`] from 1): the entry below it and the fraction (in
/// 1/256) to the next.
#[derive(Clone, Copy)]
struct StretchEntry {
    at: usize,
    fraction: i32,
}

impl StretchEntry {
    /// The entry of `u` (Q16, 1 or more) in [`STRETCH_HIGH`].
    #[inline(always)]
    fn steep(u: u32) -> Self {
        let top = 31 - u.leading_zeros();
        if top >= 16 + 8 {
            // 256 or more: the last entry.
            return Self {
                at: 256,
                fraction: 0,
            };
        }
        Self {
            at: ((top - 16) * 32 + ((u >> (top - 5)) & 31)) as usize,
            fraction: ((u >> (top - 13)) & 0xFF) as i32,
        }
    }

    /// `table` here, blended between its entries.
    #[inline(always)]
    fn of_table(&self, table: &[u32; 257]) -> u64 {
        let low = table[self.at.min(256)] as i32;
        let high = table[(self.at + 1).min(256)] as i32;
        // Entries below 2^21, steps below 2^17: within a word.
        (low + (((high - low) * self.fraction) >> 8)) as u64
    }
}

/// Scales a direction (Q20, at least 1 and below 2^7 long) to unit
/// length without a division: its squared length's top 32 bits brought
/// into [2^30, 2^32) by an even shift, and `1/√` of that from a table by
/// its top 9 bits, blended by the next 16 (within a part in 2^16).
struct Unit {
    /// `1/√u` (Q30, `u` the normalized squared length in [1/4, 1)) and
    /// the shift that turns a component times it into Q20.
    inverse: i64,
    shift: u32,
}

impl Unit {
    fn new(d: [i32; 3]) -> Self {
        let squared: u64 = d
            .iter()
            .map(|&v| (i64::from(v) * i64::from(v)) as u64)
            .sum();
        // At least 2^40 (|d| >= 1): the bits dropped are below a part in 2^16.
        let top = (squared.clamp(1 << 40, (1 << 56) - 1) >> 24) as u32;
        let half_shift = top.leading_zeros() / 2;
        let m = top << (2 * half_shift);
        let at = (m >> 23) as usize - 128;
        let fraction = u64::from((m >> 7) & 0xFFFF);
        let (low, high) = (
            u64::from(INVERSE_ROOTS[at]),
            u64::from(INVERSE_ROOTS[at + 1]),
        );
        // |d| = √u · 2^(8 − half_shift) in units of 2^20: a component c
        // (Q20) over it is c · (1/√u) · 2^(half_shift − 8), Q20.
        Self {
            inverse: (low - (((low - high) * fraction) >> 16)) as i64,
            shift: 30 + 8 - half_shift,
        }
    }

    /// Component `c` of the direction, of the unit direction (Q20).
    fn of(&self, c: i32) -> i64 {
        (i64::from(c) * self.inverse) >> self.shift
    }

    /// `c` as [`Unit::of`] for a component's size.
    fn of_size(&self, c: u32) -> u32 {
        ((u64::from(c) * self.inverse as u64) >> self.shift) as u32
    }
}

/// `1/√(i/512)` in Q30 for `i` in 128..=512: `√(2^69 / i)`.
const INVERSE_ROOTS: [u32; 385] = {
    let mut roots = [0u32; 385];
    let mut i = 0;
    while i < 385 {
        roots[i] = ((1u128 << 69) / (i as u128 + 128)).isqrt() as u32;
        i += 1;
    }
    roots
};

/// `1/x` in Q16 for `x` (Q20) from 1/2 to 1 (a unit direction's largest
/// component is at least 1/√3), from a table by its top 8 bits below
/// 1, blended by the next 12.
fn reciprocal_q16(x: u32) -> u32 {
    let x = x.clamp(1 << (DIR_BITS - 1), 1 << DIR_BITS);
    let at = (x >> 12) as usize - 128;
    let fraction = x & 0xFFF;
    let (low, high) = (RECIPROCALS[at], RECIPROCALS[(at + 1).min(128)]);
    low - (((low - high) * fraction) >> 12)
}

/// `256 / (i + 128)` in Q16 for `i` in 0..=128.
const RECIPROCALS: [u32; 129] = {
    let mut reciprocals = [0u32; 129];
    let mut i = 0;
    while i < 129 {
        reciprocals[i] = (1 << 24) / (i as u32 + 128);
        i += 1;
    }
    reciprocals
};

impl SunTable {
    /// Whether unit direction `e` (Q20) is within the glow's reach: one
    /// dot product, so that most of the sky skips the rest. The glow is
    /// at most 90° wide, so that is in the sun's half of the sky too.
    fn near(&self, e: [i64; 3]) -> bool {
        self.cosine(e) > self.glow_cosine.max(0)
    }

    /// The cosine (Q40) of the angle between unit direction `e` (Q20)
    /// and the sun's.
    fn cosine(&self, e: [i64; 3]) -> i64 {
        let s = self.direction;
        e[0] * s[0] + e[1] * s[1] + e[2] * s[2]
    }

    /// The sky `color` along unit direction `e` (Q20, [`SunTable::near`]
    /// the sun) with the sun's disc and glow over it.
    fn over(&self, color: Rgb, e: [i64; 3]) -> Rgb {
        let s = self.direction;
        let cross = [
            (e[1] * s[2] - e[2] * s[1]) >> DIR_BITS,
            (e[2] * s[0] - e[0] * s[2]) >> DIR_BITS,
            (e[0] * s[1] - e[1] * s[0]) >> DIR_BITS,
        ];
        let sine_squared: i64 = cross.iter().map(|c| c * c).sum();
        if sine_squared >= self.glow {
            color
        } else if sine_squared <= self.disc {
            self.color
        } else {
            let g = div_trunc((self.glow - sine_squared) << 8, self.glow) as u32;
            lerp(color, self.color, (g * g * GLOW_STRENGTH_Q8) >> 16)
        }
    }
}

impl FogTable {
    /// What the fog leaves of a color over `column_q8` voxels at ground
    /// density, in 1/256.
    fn transmitted(&self, column_q8: u64) -> u32 {
        // Both below 2^32: one 32 × 32-bit product, the halvings Q8
        // rounded.
        let column = u64::from(word(column_q8));
        left_after(word(
            (column * u64::from(self.halvings_q32) + (1 << 31)) >> 32,
        ))
    }

    /// `F` at height `h` (both Q8 voxels), linear between the table's
    /// entries; below 0 the ground layer's density goes on (`F(h) = h`).
    fn column_at(&self, h: i64) -> i64 {
        if h <= 0 {
            return h;
        }
        i64::from(between(&self.column, h.min(i64::from(u32::MAX)) as u32))
    }

    /// The density (Q16) at height `h` (Q8 voxels): the ground layer's
    /// below 0.
    fn density_at(&self, h: i64) -> i64 {
        i64::from(between(
            &self.density,
            h.clamp(0, i64::from(u32::MAX)) as u32,
        ))
    }
}

/// A [`Sink`] that gives each pixel its atmosphere (see
/// [`PreparedAtmosphere::color`]) and passes it on. `SKY_DRAWN`: every
/// pixel's sky is in `sink` already
/// ([`PreparedAtmosphere::sink_over_sky`]); a constant, so that the line
/// caster compiled for it leaves out the walk over the sky's pixels.
#[derive(Debug)]
pub struct AtmosphereSink<'a, S, const SKY_DRAWN: bool = false> {
    air: &'a PreparedAtmosphere,
    frame: AtmosphereFrame,
    line: LineShade,
    sky: SkyCell,
    sink: S,
}

impl<S: Sink, const SKY_DRAWN: bool> AtmosphereSink<'_, S, SKY_DRAWN> {
    /// Puts the sky into every pixel, a row at a time in runs of up to
    /// [`SKY_RUN`] pixels, the sine stepped along each cell of the frame's
    /// grid; near the sun each pixel from its own direction; a cell below
    /// the horizon, and a whole row of them, as the horizon's one color.
    fn draw_sky(&mut self, width: u32, height: u32) {
        let bits = self.frame.grid.bits;
        let side = 1u32 << bits;
        let cells = width.div_ceil(side);
        let mut run = [[0u8; 3]; SKY_RUN];
        let horizon = [self.frame.sky[0]; SKY_RUN];
        // The last row of cells seen, and whether all its cells lie below
        // the horizon.
        let mut row_of_cells = (i32::MIN, false);
        for image_y in 0..height {
            let row = self.frame.top_row - image_y as i32;
            let (j, y) = (row >> bits, row & ((1 << bits) - 1));
            if row_of_cells.0 != j {
                let below =
                    (0..cells).all(|i| self.frame.grid.sky_cell(i as i32, j).below_horizon());
                row_of_cells = (j, below);
            }
            if row_of_cells.1 {
                // A row that is the horizon's color: runs of it.
                put_sky_row(&mut self.sink, width, image_y, &horizon);
                continue;
            }
            // The run's first pixel, and how much of it is filled.
            let (mut run_x, mut filled) = (0, 0);
            for i in 0..cells {
                let column0 = i << bits;
                let mut cell = self.frame.grid.sky_cell(i as i32, j);
                // Along the cell's row the sine is the blend of its edges
                // there: one add a pixel.
                let (left, right) = self.frame.grid.edges_at(&cell.sine, y);
                let (mut along, step) = (0, right - left);
                let (mut done, pixels) = (0, side.min(width - column0) as usize);
                while done < pixels {
                    let take = (pixels - done).min(SKY_RUN - filled);
                    let slots = &mut run[filled..filled + take];
                    if cell.below_horizon() {
                        slots.fill(self.frame.sky[0]);
                    } else if cell.own_direction {
                        for (column, slot) in (column0 + done as u32..).zip(slots) {
                            *slot = self.air.sky_pixel(&self.frame, &mut cell, column, image_y);
                        }
                    } else {
                        for slot in slots {
                            *slot = fogged_sky(&self.frame.sky, i64::from(left + (along >> bits)));
                            along += step;
                        }
                    }
                    (done, filled) = (done + take, filled + take);
                    if filled == SKY_RUN {
                        self.sink.put_sky_run(run_x, image_y, &run);
                        (run_x, filled) = (run_x + SKY_RUN as u32, 0);
                    }
                }
            }
            self.sink.put_sky_run(run_x, image_y, &run[..filled]);
        }
    }
}

impl<S: Sink, const SKY_DRAWN: bool> Sink for AtmosphereSink<'_, S, SKY_DRAWN> {
    #[inline(always)]
    fn sky_is_drawn(&self) -> bool {
        SKY_DRAWN
    }

    // Inlined: the sky above a line's last hit comes through it pixel
    // after pixel, and a call a pixel costs more than its color.
    #[inline(always)]
    fn put(&mut self, x: u32, y: u32, sample: Sample) {
        if SKY_DRAWN && sample.is_sky() {
            return;
        }
        let color = self
            .air
            .pixel_color(&self.frame, &mut self.sky, x, y, &sample);
        self.sink.put(x, y, Sample { color, ..sample });
    }

    #[inline]
    fn line(&mut self, plane: &LinePlane) {
        self.line = LineShade::new(plane);
    }

    #[inline(always)]
    fn put_ray(&mut self, x: u32, y: u32, sample: Sample, slope: i32) {
        let color = self
            .air
            .ray_color(&self.frame, &self.line, (x, y), &sample, slope);
        self.sink.put(x, y, Sample { color, ..sample });
    }
}

/// What the atmosphere needs of a line's vertical plane (see
/// [`Sink::line`]): the plane's horizontal length a unit of major-axis
/// distance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LineShade {
    /// `m = √(1 + dminor²)`, Q16 (from 1 to √2), and `1/m`, Q20.
    m: u32,
    inverse_m: u32,
}

impl LineShade {
    /// The shade of `plane`'s rays.
    pub fn new(plane: &LinePlane) -> Self {
        // `√(1 + u²)` from the stretch table (`u = |dminor|` ≤ 1), and its
        // reciprocal by two 32-bit divides: a square root and a 64-bit
        // division a line are library calls on a 32-bit core, about 19
        // instructions a pixel on the board's steep views.
        let u = plane.dminor.unsigned_abs().min(1 << 16);
        let entry = StretchEntry {
            at: (u >> 8) as usize,
            fraction: (u & 0xFF) as i32,
        };
        let m = entry.of_table(&STRETCH_LOW) as u32;
        Self {
            m,
            inverse_m: inverse_q20(m),
        }
    }
}

/// `⌊2^36 / m⌋` (`1/m` in Q20 for `m` in Q16, `m ≥ 2^16`) by two 32-bit
/// divides: `2^32 = q·m + r + 1` with `q = ⌊(2^32 − 1)/m⌋`, so
/// `2^36 / m = 16q + 16(r + 1)/m`.
fn inverse_q20(m: u32) -> u32 {
    let m = m.max(1 << 16);
    let q = u32::MAX / m;
    let r = u32::MAX - q * m;
    16 * q + 16 * (r + 1) / m
}

impl Default for LineShade {
    /// A plane along a grid axis (what a sink holds before its first
    /// line).
    fn default() -> Self {
        Self::new(&LinePlane { dminor: 0 })
    }
}

// Heights in samples are I16.16; the tables' are U12.4 voxels' range.
const _: () = assert!(HEIGHT_FRAC_BITS <= Q8);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Camera;

    fn view() -> View {
        View::new(&Camera::looking([100.0, 50.0, 80.0], 30.0, 8.0), 96, 64).unwrap()
    }

    fn exact_color(air: &Atmosphere, view: &View, x: u32, y: u32, sample: &Sample) -> [f64; 3] {
        let row = i64::from(view.height()) - 1 - i64::from(y);
        let d: [f64; 3] = core::array::from_fn(|i| {
            (view.base[i].to_bits()
                + i64::from(x) * view.per_column[i].to_bits()
                + row * view.per_row[i].to_bits()) as f64
                / 2f64.powi(32)
        });
        let eye = view.eye[2].to_num::<f64>();
        let hit = (!sample.is_sky()).then(|| {
            let major = d[0].abs().max(d[1].abs());
            let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            (
                f64::from(sample.distance) / 65536.0 * length / major,
                f64::from(sample.elevation) / 65536.0,
            )
        });
        air.exact(d, eye, hit, sample.color.map(f64::from))
    }

    #[test]
    fn a_sky_pixel_from_its_cached_cell_is_the_pixels_own_color() {
        // Down the columns and back up, as a line caster's sky comes, and
        // along the rows, each sky pixel's color from the cell kept from
        // the pixel before is `color`'s, with the sun's glow in view (its
        // cells take their own direction) and without it.
        let view = view();
        let sky = Sample::sky([200, 60, 20]);
        let toward_the_sun = Atmosphere {
            sun: Atmosphere::FLIGHT.sun.map(|sun| Sun {
                azimuth_deg: 34.0,
                elevation_deg: 3.0,
                ..sun
            }),
            ..Atmosphere::FLIGHT
        };
        for air in [Atmosphere::FLIGHT, toward_the_sun] {
            let prepared = air.prepare().unwrap();
            let frame = prepared.frame(&view);
            let mut own = 0;
            let columns = (0..96)
                .flat_map(|x| (0..64).map(move |y| (x, if x % 2 == 0 { y } else { 63 - y })));
            let rows = (0..64).flat_map(|y| (0..96).map(move |x| (x, y)));
            for order in [columns.collect::<std::vec::Vec<_>>(), rows.collect()] {
                let mut cell = SkyCell::default();
                for (x, y) in order {
                    let cached = prepared.pixel_color(&frame, &mut cell, x, y, &sky);
                    assert_eq!(cached, prepared.color(&frame, x, y, &sky), "({x}, {y})");
                    own += usize::from(cell.own_direction);
                }
            }
            assert_eq!(
                own > 0,
                air.sun.unwrap().azimuth_deg == 34.0,
                "cells near the sun"
            );
        }
    }

    #[test]
    fn fixed_point_matches_the_exact_model_within_two_levels() {
        let view = view();
        let mut hazy = Atmosphere::FLIGHT;
        // The sun in view, so its disc and glow are tested too.
        hazy.sun = hazy.sun.map(|sun| Sun {
            azimuth_deg: 34.0,
            elevation_deg: 3.0,
            ..sun
        });
        let clear = Atmosphere { fog: None, ..hazy };
        for air in [hazy, clear] {
            let prepared = air.prepare().unwrap();
            let frame = prepared.frame(&view);
            let mut worst = 0.0f64;
            let mut sun_pixels = 0;
            for y in 0..64 {
                for x in 0..96 {
                    let samples = [
                        Sample::sky([200, 60, 20]),
                        Sample {
                            color: [200, 60, 20],
                            distance: (x * 97 + y * 13 + 1) << 14,
                            elevation: ((x as i32 * 5) % 90) << 16,
                        },
                    ];
                    for sample in samples {
                        let kernel = prepared.color(&frame, x, y, &sample);
                        let exact = exact_color(&air, &view, x, y, &sample);
                        if sample.is_sky() && kernel == air.sun.unwrap().color {
                            sun_pixels += 1;
                        }
                        for c in 0..3 {
                            worst = worst.max((f64::from(kernel[c]) - exact[c]).abs());
                        }
                    }
                }
            }
            assert!(
                air.fog.is_some() || sun_pixels > 0,
                "the sun's disc is in view"
            );
            assert!(worst <= 2.0, "worst channel difference {worst}");
        }
    }

    #[test]
    fn a_line_casters_rays_match_the_exact_model_within_two_levels() {
        // Rendered through the line caster, which gives the sink each
        // ray's slope in its line's plane: every pixel, sky and terrain,
        // within two levels of the exact model along the pixel's own
        // direction (the terrain one color, so the model needs only the
        // hit). Level, pitched up and down, rolled, straight down.
        use crate::{render, Framebuffer, NoProbe, Pyramid, RenderOptions, Terrain};
        const SIDE: usize = 96;
        let heights: std::vec::Vec<u16> = (0..SIDE * SIDE)
            .map(|i| {
                let (x, y) = ((i % SIDE) as f64, (i / SIDE) as f64);
                ((20.0 + 12.0 * (x * 0.21).sin() * (y * 0.17).cos()) * 16.0) as u16
            })
            .collect();
        let colors = std::vec![[200u8, 60, 20]; SIDE * SIDE];
        let terrain = Terrain::new(SIDE as u32, SIDE as u32, &heights, &colors).unwrap();
        let pyramid = Pyramid::flat(terrain);
        let mut air = Atmosphere::FLIGHT;
        air.fog = air.fog.map(|fog| Fog {
            visibility: 60.0,
            ..fog
        });
        // The sun low in the north-east, in view of the first cameras.
        air.sun = air.sun.map(|sun| Sun {
            azimuth_deg: 60.0,
            elevation_deg: 4.0,
            ..sun
        });
        let clear = Atmosphere { fog: None, ..air };
        let (mut suns, mut skies) = (0, 0);
        let cameras = [
            Camera::looking([10.0, 10.0, 40.0], 45.0, 0.0),
            Camera::looking([10.0, 10.0, 40.0], 45.0, 12.0),
            Camera::looking([10.0, 80.0, 30.0], 20.0, -10.0),
            Camera {
                roll_deg: 30.0,
                ..Camera::looking([10.0, 10.0, 40.0], 50.0, 8.0)
            },
            Camera::looking([48.0, 48.0, 90.0], 0.0, 90.0),
        ];
        for (air, camera) in [air, clear]
            .into_iter()
            .flat_map(|air| cameras.map(|camera| (air, camera)))
        {
            let prepared = air.prepare().unwrap();
            let view = View::new(&camera, 80, 60).unwrap();
            let mut hazy = std::vec![[0u8; 3]; 80 * 60];
            let options = RenderOptions::default();
            let mut frame = Framebuffer::new(&mut hazy, 80, 60).unwrap();
            render(
                &pyramid,
                &view,
                &options,
                &mut prepared.sink(&view, &mut frame),
                &mut NoProbe,
            );
            // The sky drawn first gives the same frame, at this size (cells
            // of 2 pixels) and at sizes with cells of 8 and a part cell at
            // the image's right and top edges.
            for (width, height) in [(80, 60), (320, 240), (331, 187)] {
                let view = View::new(&camera, width, height).unwrap();
                let frames = [false, true].map(|first| {
                    let mut pixels = std::vec![[0u8; 3]; (width * height) as usize];
                    let mut frame = Framebuffer::new(&mut pixels, width, height).unwrap();
                    let mut plain;
                    let mut over_sky;
                    let mut sink: &mut dyn Sink = if first {
                        over_sky = prepared.sink_over_sky(&view, &mut frame);
                        &mut over_sky
                    } else {
                        plain = prepared.sink(&view, &mut frame);
                        &mut plain
                    };
                    // Only the sink that drew the sky says so: a streaming
                    // sink's frame must get every sky pixel from the render.
                    assert_eq!(sink.sky_is_drawn(), first);
                    render(&pyramid, &view, &options, &mut sink, &mut NoProbe);
                    pixels
                });
                assert!(
                    frames[0] == frames[1],
                    "{camera:?} at {width} x {height}: the sky drawn first changes the frame"
                );
            }
            // The elevations, from a capture of the samples.
            let mut samples = std::vec![None; 80 * 60];
            struct Capture<'a>(&'a mut [Option<Sample>]);
            impl Sink for Capture<'_> {
                fn put(&mut self, x: u32, y: u32, sample: Sample) {
                    self.0[(y * 80 + x) as usize] = Some(sample);
                }
            }
            render(
                &pyramid,
                &view,
                &options,
                &mut Capture(&mut samples),
                &mut NoProbe,
            );
            let (mut worst, mut sky, mut sun) = (0.0f64, 0, 0);
            for (i, sample) in samples.iter().enumerate() {
                let sample = sample.unwrap();
                sky += usize::from(sample.is_sky());
                sun += usize::from(hazy[i] == air.sun.unwrap().color);
                let (x, y) = ((i % 80) as u32, (i / 80) as u32);
                let exact = exact_color(&air, &view, x, y, &sample);
                for c in 0..3 {
                    worst = worst.max((f64::from(hazy[i][c]) - exact[c]).abs());
                }
            }
            assert!(worst <= 2.0, "{camera:?}: worst channel difference {worst}");
            assert!(sky < 80 * 60, "{camera:?} sees terrain");
            suns += sun;
            skies += sky;
        }
        assert!(
            suns > 0 && skies > 80 * 60,
            "the sky and the sun's disc are in view"
        );
    }

    #[test]
    fn the_grid_gives_each_pixel_its_own_directions_sine_and_length() {
        // Level, steep, straight down, rolled, wide and narrow, small and
        // large images: wherever a cell is blended (not marked for each
        // pixel's own direction), the blend is within a part in 1024 of
        // the pixel's own sine (a quarter of a step of the sky's table by
        // sine) and a part in 512 of its reciprocal (which moves the fog's
        // weight by under a fifth of a color level: `e^−1` of 255 times
        // the relative error, at most).
        let cameras = [
            (
                Camera::looking([100.0, 50.0, 80.0], 30.0, 0.0),
                60.0,
                (320, 240),
            ),
            (
                Camera::looking([100.0, 50.0, 80.0], 200.0, 12.0),
                90.0,
                (96, 64),
            ),
            (
                Camera::looking([10.0, 50.0, 800.0], 45.0, 60.0),
                120.0,
                (1024, 768),
            ),
            (
                Camera::looking([10.0, 50.0, 800.0], 0.0, 90.0),
                60.0,
                (333, 211),
            ),
            (
                Camera::looking([10.0, 50.0, 80.0], 0.0, -30.0),
                30.0,
                (640, 360),
            ),
            (
                Camera {
                    roll_deg: 35.0,
                    ..Camera::looking([10.0, 50.0, 80.0], 70.0, 20.0)
                },
                60.0,
                (320, 240),
            ),
        ];
        let air = Atmosphere::FLIGHT.prepare().unwrap();
        let (mut blended, mut own) = (0, 0);
        for (camera, hfov_deg, (width, height)) in cameras {
            let view = View::new(&Camera { hfov_deg, ..camera }, width, height).unwrap();
            let frame = air.frame(&view);
            let grid = &frame.grid;
            for row in 0..height as i32 {
                for column in 0..width as i32 {
                    let (cell, at) = grid.cell(column, row);
                    if cell & CELL_MIXED != 0 {
                        own += 1;
                        continue;
                    }
                    blended += 1;
                    let d = direction(&frame.base, &frame.per_column, &frame.per_row, column, row);
                    let unit = Unit::new(d);
                    let sine = unit.of(d[2]) as i32;
                    let got = grid.blend(&grid.sine, &at);
                    assert!(
                        (got - sine).abs() <= 1 << (DIR_BITS - 10),
                        "{camera:?} ({column}, {row}): sine {got} against {sine}"
                    );
                    let [x, y, z] = d.map(i32::unsigned_abs);
                    assert_eq!(cell & CELL_VERTICAL != 0, z > x.max(y));
                    let reciprocal = reciprocal_q16(unit.of_size(x.max(y).max(z))) as i32;
                    let got = grid.blend(&grid.reciprocal, &at);
                    assert!(
                        (got - reciprocal).abs() <= reciprocal >> 9,
                        "{camera:?} ({column}, {row}): reciprocal {got} against {reciprocal}"
                    );
                }
            }
        }
        // Nearly every pixel is blended.
        assert!(
            own * 20 < blended,
            "{own} pixels take their own direction, {blended} blended"
        );
    }

    #[test]
    fn fog_fades_smoothly_with_distance_without_bands() {
        // A level ray at the ground layer's height, one sixteenth of a
        // voxel farther each time, out to four visibilities: what the fog
        // leaves never rises and never drops by more than one 256th at
        // once (the 8-bit blend's own step), so no band shows.
        let air = Atmosphere::FLIGHT.prepare().unwrap();
        let table = air.fog.as_ref().unwrap();
        let mut before = 256;
        let mut seen = 0;
        for step in 0..(4 * 2500 * 16) {
            let column_q8 = step * 16;
            let weight = table.transmitted(column_q8);
            assert!(weight <= before, "rises at {step}");
            assert!(
                before - weight <= 1,
                "a band at {step}: {before} to {weight}"
            );
            before = weight;
            seen |= 1 << (weight.min(255) / 32);
        }
        assert_eq!(seen, 0xFF, "runs the whole range");
        // At the visibility distance 2 % is left: 5 of 256.
        let at_visibility = table.transmitted(2500 << 8);
        assert!((4..=6).contains(&at_visibility), "{at_visibility}");
    }

    #[test]
    fn the_sky_gradient_has_no_bands_from_horizon_to_zenith() {
        let air = Atmosphere {
            fog: None,
            sun: None,
            ..Atmosphere::FLIGHT
        }
        .prepare()
        .unwrap();
        let frame = air.frame(&view());
        let level = [1 << DIR_BITS, 0, 0];
        let mut before = air.sky_color(&frame, level, &Unit::new(level));
        assert_eq!(before, Atmosphere::FLIGHT.horizon);
        for step in 1..=4096 {
            let angle = f64::from(step) / 4096.0 * core::f64::consts::FRAC_PI_2;
            let d = [angle.cos(), 0.0, angle.sin()].map(|v| (v * f64::from(1 << DIR_BITS)) as i32);
            let color = air.sky_color(&frame, d, &Unit::new(d));
            for c in 0..3 {
                assert!(color[c].abs_diff(before[c]) <= 1, "a band at {step}");
            }
            before = color;
        }
        assert!(before
            .iter()
            .zip(Atmosphere::FLIGHT.zenith)
            .all(|(a, b)| a.abs_diff(b) <= 1));
    }

    #[test]
    fn uniform_fog_hides_the_sky_and_layered_fog_does_not() {
        let view = view();
        let sky = Sample::sky([0; 3]);
        let fog = Atmosphere::FLIGHT.fog.unwrap();
        let uniform = Atmosphere {
            fog: Some(Fog {
                halving: None,
                ..fog
            }),
            sun: None,
            ..Atmosphere::FLIGHT
        };
        let prepared = uniform.prepare().unwrap();
        assert_eq!(
            prepared.color(&prepared.frame(&view), 40, 0, &sky),
            fog.color
        );
        let layered = Atmosphere {
            sun: None,
            ..Atmosphere::FLIGHT
        }
        .prepare()
        .unwrap();
        let top = layered.color(&layered.frame(&view), 40, 0, &sky);
        assert_ne!(top, fog.color);
    }

    #[test]
    fn the_sink_changes_colors_only() {
        let view = view();
        let air = Atmosphere::FLIGHT.prepare().unwrap();
        let mut got = None;
        struct Keep<'a>(&'a mut Option<Sample>);
        impl Sink for Keep<'_> {
            fn put(&mut self, _: u32, _: u32, sample: Sample) {
                *self.0 = Some(sample);
            }
        }
        let hit = Sample {
            color: [10, 200, 30],
            distance: 900 << 16,
            elevation: 20 << 16,
        };
        air.sink(&view, Keep(&mut got)).put(3, 50, hit);
        let got = got.unwrap();
        assert_eq!((got.distance, got.elevation), (hit.distance, hit.elevation));
        assert_ne!(got.color, hit.color, "900 voxels of haze show");
    }

    #[test]
    fn a_lines_shade_is_its_planes_length_and_its_reciprocal() {
        // m = √(1 + dminor²) within two units of Q16 (a part in 2^15) at
        // every minor slope the caster gives (within ±1), and 1/m exactly
        // ⌊2^36 / m⌋.
        for dminor in (-(1 << 16)..=1 << 16)
            .step_by(7)
            .chain([1 << 16, -(1 << 16)])
        {
            let shade = LineShade::new(&LinePlane { dminor });
            let exact = (1.0 + (f64::from(dminor) / 65536.0).powi(2)).sqrt() * 65536.0;
            assert!(
                (f64::from(shade.m) - exact).abs() <= 2.0,
                "dminor {dminor}: m {} against {exact}",
                shade.m
            );
            assert_eq!(
                u64::from(shade.inverse_m),
                (1u64 << 36) / u64::from(shade.m)
            );
        }
        assert_eq!(inverse_q20(1 << 16), 1 << 20);
    }

    #[test]
    fn unit_directions_and_reciprocals_are_within_a_part_in_2_to_the_14() {
        // Directions from length 1 to 100, every way.
        for step in 0..20_000 {
            let t = f64::from(step);
            let length = 1.0 + 99.0 * (t * 0.618).fract().powi(3);
            let (a, b) = (t * 0.37, t * 0.11);
            let true_unit = [a.cos() * b.cos(), a.sin() * b.cos(), b.sin()];
            let d = true_unit.map(|v| (v * length * f64::from(1 << DIR_BITS)).round() as i32);
            let exact = {
                let n = d.map(f64::from);
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                n.map(|v| v / len * f64::from(1 << DIR_BITS))
            };
            let unit = Unit::new(d);
            for i in 0..3 {
                let got = unit.of(d[i]) as f64;
                assert!(
                    (got - exact[i]).abs() <= 1.0 + f64::from(1 << 6),
                    "{d:?}: {got} against {}",
                    exact[i]
                );
            }
        }
        for x in (1 << 19..=1 << 20).step_by(37) {
            let exact = f64::from(1u32 << 16) * f64::from(1u32 << 20) / f64::from(x);
            let got = f64::from(reciprocal_q16(x));
            assert!(
                (got - exact).abs() <= exact / f64::from(1 << 14),
                "1/{x}: {got} against {exact}"
            );
        }
    }

    #[test]
    fn past_the_opaque_distance_no_hit_below_the_highest_shows() {
        for fog in [
            Atmosphere::FLIGHT.fog.unwrap(),
            Fog {
                halving: None,
                ..Atmosphere::FLIGHT.fog.unwrap()
            },
        ] {
            for (eye, highest) in [(10.0, 5.0), (200.0, 180.0), (50.0, 300.0), (400.0, 20.0)] {
                let far = fog.opaque_distance(eye, highest);
                for hit in [0.0, highest / 3.0, highest] {
                    // Along the path, or farther.
                    for length in [far, far * 1.5] {
                        let kept = fog.transmittance(length, eye, hit);
                        assert!(
                            kept <= 1.0 / 512.0 + 1e-12,
                            "{fog:?} {eye} {highest} {hit}: {kept}"
                        );
                    }
                }
                // And no sooner than it must: a level path at the higher
                // of the two keeps exactly a 512th there.
                let top = f64::max(eye, highest);
                let kept = fog.transmittance(far, top, top);
                assert!((kept * 512.0 - 1.0).abs() < 1e-9, "{kept}");
            }
        }
        // Uniform fog of visibility 2500: about 4000 voxels.
        let uniform = Fog {
            halving: None,
            visibility: 2500.0,
            ..Atmosphere::FLIGHT.fog.unwrap()
        };
        assert!((uniform.opaque_distance(100.0, 50.0) - 3986.6).abs() < 0.1);
    }

    #[test]
    fn bad_settings_are_refused() {
        let mut air = Atmosphere::FLIGHT;
        air.fog = air.fog.map(|fog| Fog {
            visibility: 2.0,
            ..fog
        });
        assert_eq!(air.prepare().unwrap_err(), AtmosphereError::Fog);
        let mut air = Atmosphere::FLIGHT;
        air.sun = air.sun.map(|sun| Sun {
            disc_deg: 20.0,
            ..sun
        });
        assert_eq!(air.prepare().unwrap_err(), AtmosphereError::Sun);
        let mut air = Atmosphere::FLIGHT;
        air.sun = air.sun.map(|sun| Sun {
            azimuth_deg: f32::NAN,
            ..sun
        });
        assert_eq!(air.prepare().unwrap_err(), AtmosphereError::NotFinite);
    }
}
