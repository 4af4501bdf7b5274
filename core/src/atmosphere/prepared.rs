//! An [`Atmosphere`] in fixed point ([`PreparedAtmosphere`]): its tables,
//! a frame's tables made from them, and a pixel's color: the sky with the
//! sun over it, and a hit through the fog.

use super::*;

/// An [`Atmosphere`] in fixed point, ready for frames.
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedAtmosphere {
    pub(super) sky: [Rgb; SKY_STEPS + 1],
    pub(super) sun: Option<SunTable>,
    pub(super) fog: Option<FogTable>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SunTable {
    /// Unit vector, Q20; the disc's and the glow's sin² of their radius,
    /// Q40.
    pub(super) direction: [i64; 3],
    pub(super) disc: i64,
    pub(super) glow: i64,
    /// The cosine of the glow's radius, Q40, less a margin for the unit
    /// vector's rounding.
    pub(super) glow_cosine: i64,
    /// The glow's radius.
    pub(super) glow_radians: f64,
    pub(super) color: Rgb,
}

#[derive(Debug, Clone, PartialEq)]
pub(super) struct FogTable {
    pub(super) fog: Fog,
    /// The fog's color weighted for a blend toward another color that
    /// keeps `i`/256 of it ([`Lanes::weighted`] by `256 − i`), by `i`.
    pub(super) toward_fog: [Lanes; 257],
    /// Halvings a voxel at ground density, Q32 (below 1: the visibility
    /// is at least 8 voxels).
    pub(super) halvings_q32: u32,
    /// `F` (Q8 voxels) and the density (Q16) every 4 voxels of height.
    pub(super) column: [u32; HEIGHT_STEPS + 1],
    pub(super) density: [u32; HEIGHT_STEPS + 1],
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
        let rate_every_step: [u32; HEIGHT_STEPS + 1] = core::array::from_fn(|i| match &self.fog {
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
        // At the middle of every voxel, linear between the steps, so that a
        // hit reads its rate without a blend, by its whole voxels.
        let rate = core::array::from_fn(|i| {
            let q8 = ((i as u32) << Q8) + (1 << (Q8 - 1));
            between(&rate_every_step, q8.min(HEIGHT_VOXELS << Q8))
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
    pub(super) fn sky_pixel(
        &self,
        frame: &AtmosphereFrame,
        cell: &mut SkyCell,
        x: u32,
        y: u32,
    ) -> Rgb {
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
        // The rate at the middle of the voxel of the hit's height (held
        // past the table's top); below 2^31, so the halvings (Q8,
        // rounded) fit a word: one 32 × 32-bit product.
        let voxel = (sample.elevation >> COORD_FRAC_BITS).clamp(0, HEIGHT_VOXELS as i32);
        let rate = frame.rate[voxel as usize];
        let halvings_q8 = (u64::from(distance_q8) * u64::from(rate) + (1 << 30)) >> 31;
        let weight = left_after(halvings_q8 as u32);
        // `weight` is at most 256: held there, so that no bound is checked.
        let weight = weight.min(256);
        table.toward_fog[weight as usize]
            .plus_weighted(Lanes::of(sample.color), weight)
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
        // Sky and a hit without fog decided here, not by `color`: that is
        // out of line and takes the sample by reference, which makes every
        // hit of the caster's loop work out and store its elevation.
        if sample.is_sky() {
            return self.sky_pixel(frame, &mut SkyCell::default(), x, y);
        }
        let Some(table) = self.fog.as_ref() else {
            return sample.color;
        };
        // A ray with no run (straight down) has no major-axis distance:
        // its length is its height change.
        let vertical = slope.unsigned_abs() >= MAX_SLOPE_Q16;
        let distance_q8 = if vertical {
            drop(frame, sample) >> (COORD_FRAC_BITS - Q8)
        } else {
            let length = line.ray_length(slope);
            word((u64::from(sample.distance) * u64::from(length)) >> (16 + 16 - Q8))
        };
        self.fogged(frame, table, sample, distance_q8)
    }

    /// The sky along `d` (Q20, `unit` its unit direction), through the
    /// fog: the frame's fogged gradient by the sine of the elevation,
    /// blended between neighbouring entries, and near the sun its disc and
    /// glow over the gradient, then the fog.
    pub(super) fn sky_color(&self, frame: &AtmosphereFrame, d: [i32; 3], unit: &Unit) -> Rgb {
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

impl SunTable {
    /// Whether unit direction `e` (Q20) is within the glow's reach: one
    /// dot product, so that most of the sky skips the rest. The glow is
    /// at most 90° wide, so that is in the sun's half of the sky too.
    fn near(&self, e: [i64; 3]) -> bool {
        self.cosine(e) > self.glow_cosine.max(0)
    }

    /// The cosine (Q40) of the angle between unit direction `e` (Q20)
    /// and the sun's.
    pub(super) fn cosine(&self, e: [i64; 3]) -> i64 {
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
    pub(super) fn transmitted(&self, column_q8: u64) -> u32 {
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
