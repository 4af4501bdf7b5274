//! The atmosphere as a [`Sink`] ([`AtmosphereSink`]): it wraps any sink
//! and gives each pixel its sky or its fog as the renderer puts it, or
//! draws the sky first; and what a line's plane gives its rays' fog
//! ([`LineShade`]).

use super::*;

/// A [`Sink`] that gives each pixel its atmosphere (see
/// [`PreparedAtmosphere::color`]) and passes it on. `SKY_DRAWN`: every
/// pixel's sky is in `sink` already
/// ([`PreparedAtmosphere::sink_over_sky`]); a constant, so that the line
/// caster compiled for it leaves out the walk over the sky's pixels.
#[derive(Debug)]
pub struct AtmosphereSink<'a, S, const SKY_DRAWN: bool = false> {
    pub(super) air: &'a PreparedAtmosphere,
    pub(super) frame: AtmosphereFrame,
    pub(super) line: LineShade,
    pub(super) sky: SkyCell,
    pub(super) sink: S,
}

impl<S: Sink, const SKY_DRAWN: bool> AtmosphereSink<'_, S, SKY_DRAWN> {
    /// Puts the sky into every pixel, a row at a time in runs of up to
    /// [`SKY_RUN`] pixels, the sine stepped along each cell of the frame's
    /// grid; near the sun each pixel from its own direction; a cell below
    /// the horizon, and a whole row of them, as the horizon's one color.
    pub(super) fn draw_sky(&mut self, width: u32, height: u32) {
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
    pub(super) m: u32,
    pub(super) inverse_m: u32,
}

impl LineShade {
    /// The shade of `plane`'s rays.
    pub fn new(plane: &LinePlane) -> Self {
        // `√(1 + u²)` from the stretch table (`u = |dminor|` ≤ 1, Q16:
        // 64 to an entry), blended between its entries, and its
        // reciprocal by two 32-bit divides: a square root and a 64-bit
        // division a line are library calls on a 32-bit core, about 19
        // instructions a pixel on the board's steep views.
        let u = plane.dminor.unsigned_abs().min(1 << 16);
        let at = (u >> 6) as usize;
        let entry = |i: usize| u32::from(STRETCH_FINE[i.min(1024)]);
        // The table rises: the step is not negative.
        let m = (1 << 16) + entry(at) + (((entry(at + 1) - entry(at)) * (u & 63)) >> 6);
        Self {
            m,
            inverse_m: inverse_q20(m),
        }
    }

    /// The length (Q16) a unit of major-axis distance of the ray of this
    /// line's plane whose height changes by `slope` (Q16, below 2^29) a
    /// unit: `√(m² + slope²)`, within a word (below 2^30). For a ray
    /// shallower than the plane's diagonal `m·√(1 + u²)`, `u` the slope
    /// over `m` (Q16, below 1), else `|slope|·√(1 + v²)`, `v` the other
    /// way round, by one 32-bit divide: both from the same table, at the
    /// entry nearest `u` or `v` (no blend, no branch on the octave).
    #[inline(always)]
    pub(super) fn ray_length(&self, slope: i32) -> u32 {
        let rise = slope.unsigned_abs();
        let (scale, at) = if rise < self.m {
            let u = ((u64::from(rise) * u64::from(self.inverse_m)) >> 20) as u32;
            (self.m, (u + (1 << 5)) >> 6)
        } else {
            // `m < 2^17` and `rise < 2^29`: the sum is within a word;
            // `rise ≥ m`, so the quotient is at most 1024.
            (
                rise,
                ((self.m << 10) + (rise >> 1))
                    .checked_div(rise)
                    .unwrap_or(0),
            )
        };
        let stretch = STRETCH_FINE.get(at as usize).map_or(0, |&s| u32::from(s)) + (1 << 16);
        ((u64::from(scale) * u64::from(stretch)) >> 16) as u32
    }
}

/// `⌊2^36 / m⌋` (`1/m` in Q20 for `m` in Q16, `m ≥ 2^16`) by two 32-bit
/// divides: `2^32 = q·m + r + 1` with `q = ⌊(2^32 − 1)/m⌋`, so
/// `2^36 / m = 16q + 16(r + 1)/m`.
pub(super) fn inverse_q20(m: u32) -> u32 {
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
