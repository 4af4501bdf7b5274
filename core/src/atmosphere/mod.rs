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

mod frame;
mod prepared;
mod sink;
mod tables;
#[cfg(test)]
mod tests;

use frame::*;
pub use frame::{AtmosphereFrame, SkyCell};
pub use prepared::PreparedAtmosphere;
use prepared::*;
pub use sink::{AtmosphereSink, LineShade};
use tables::*;

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
/// are U12.4, below 4096); a frame's rate, an entry every voxel.
const HEIGHT_STEP_BITS: u32 = 2;
const HEIGHT_VOXELS: u32 = 4096;
const HEIGHT_STEPS: usize = (HEIGHT_VOXELS >> HEIGHT_STEP_BITS) as usize;
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

    /// This atmosphere without its fog: what the fog's cost is measured
    /// against (fog on against off).
    pub const fn without_fog(self) -> Self {
        Self { fog: None, ..self }
    }

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
            toward_fog: core::array::from_fn(|left| {
                Lanes::of(fog.color).weighted(256 - left as u32)
            }),
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

// Heights in samples are I16.16; the tables' are U12.4 voxels' range.
const _: () = assert!(HEIGHT_FRAC_BITS <= Q8);
