//! Where finished pixels go.

use crate::color::Rgb;
use core::fmt;

/// What a ray saw: a color and how far away along the ray's major axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sample {
    /// Pixel color.
    pub color: Rgb,
    /// Distance from the eye to the hit, measured along the ray's major axis
    /// (x or y, whichever the ray moves along faster), in U16.16 voxels;
    /// [`Sample::SKY`] when the ray saw sky. Multiply by `|d| / |d_major|`
    /// for the Euclidean distance.
    pub distance: u32,
    /// Height of the hit point, I16.16 voxels (0 for sky). With `distance`
    /// it fixes the hit on the ray; for steep rays it is the better
    /// conditioned of the two.
    pub elevation: i32,
}

impl Sample {
    /// The distance of a ray that saw sky.
    pub const SKY: u32 = u32::MAX;

    /// A ray that saw sky in `color`.
    #[inline(always)]
    pub const fn sky(color: Rgb) -> Self {
        Self {
            color,
            distance: Self::SKY,
            elevation: 0,
        }
    }

    /// Whether the ray saw sky.
    pub fn is_sky(&self) -> bool {
        self.distance == Self::SKY
    }
}

/// Receives finished pixels, each once, line by line through the
/// vertical's vanishing point (see [`View::lines`](crate::View::lines)):
/// at pitch 0 each column bottom to top, under pitch in no row or column
/// order. A sink that needs columns (a display) takes them from a
/// [`Framebuffer`].
///
/// The line caster also says which vertical plane a line's rays share
/// ([`Sink::line`]) and the slope in it of each ray that hits
/// ([`Sink::put_ray`]): a sink that shades by the ray's direction (the
/// atmosphere's fog) takes it from there instead of working it out from
/// the pixel's position. Sky, and other renderers' pixels, come through
/// [`Sink::put`].
///
/// A sink that holds the sky before the render ([`SkyFirst`],
/// [`PreparedAtmosphere::sink_over_sky`](crate::PreparedAtmosphere::sink_over_sky))
/// says so ([`Sink::sky_is_drawn`]); the line caster then leaves the sky
/// above each line's last hit out, so such a sink receives only some of
/// its sky pixels from the renderer.
pub trait Sink {
    /// Pixel `(x, y)` (y = 0 at the top) is finished. Out-of-range pixels are
    /// the sink's to discard; they must never panic.
    fn put(&mut self, x: u32, y: u32, sample: Sample);

    /// The rays put after this (until the next call) lie in `plane`.
    #[inline]
    fn line(&mut self, plane: &LinePlane) {
        let _ = plane;
    }

    /// As [`Sink::put`], for a ray of the current line's plane whose height
    /// changes by `slope` (Q16) a unit of distance along the plane's major
    /// axis; a ray with no run along it (straight up or down) has
    /// [`MAX_RAY_SLOPE`](crate::config::MAX_RAY_SLOPE) in size.
    #[inline(always)]
    fn put_ray(&mut self, x: u32, y: u32, sample: Sample, slope: i32) {
        let _ = slope;
        self.put(x, y, sample);
    }

    /// Pixels `x` to `x + colors.len() − 1` of row `y` saw sky, in
    /// `colors`: a run along a row, as a sink that draws the sky first
    /// puts it ([`SkyFirst`],
    /// [`PreparedAtmosphere::sink_over_sky`](crate::PreparedAtmosphere::sink_over_sky)).
    /// Each as [`Sink::put`] of a sky sample (elevation 0) unless the sink
    /// stores a run faster.
    #[inline]
    fn put_sky_run(&mut self, x: u32, y: u32, colors: &[Rgb]) {
        for (column, &color) in (x..).zip(colors) {
            self.put(column, y, Sample::sky(color));
        }
    }

    /// Whether this sink holds every pixel's sky already, so that a
    /// renderer need not put the sky (it may: a sky pixel put is then
    /// dropped). The line caster then leaves the pixels above a line's
    /// last hit unwalked.
    #[inline(always)]
    fn sky_is_drawn(&self) -> bool {
        false
    }
}

impl<S: Sink + ?Sized> Sink for &mut S {
    #[inline]
    fn put(&mut self, x: u32, y: u32, sample: Sample) {
        (**self).put(x, y, sample);
    }

    #[inline]
    fn line(&mut self, plane: &LinePlane) {
        (**self).line(plane);
    }

    #[inline(always)]
    fn put_ray(&mut self, x: u32, y: u32, sample: Sample, slope: i32) {
        (**self).put_ray(x, y, sample, slope);
    }

    #[inline(always)]
    fn sky_is_drawn(&self) -> bool {
        (**self).sky_is_drawn()
    }

    #[inline]
    fn put_sky_run(&mut self, x: u32, y: u32, colors: &[Rgb]) {
        (**self).put_sky_run(x, y, colors);
    }
}

/// The vertical plane a line's rays share (see [`Sink::line`]), as far
/// as a sink needs it: along it, a unit of distance along the major axis
/// (x or y, whichever the plane runs along faster) moves `dminor` along
/// the other.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinePlane {
    /// Minor-axis change a unit of major-axis distance, Q16 (within ±1).
    pub dminor: i32,
}

/// A sink that stores its pixels (a frame buffer), with every pixel's sky
/// put into it first ([`SkyFirst::new`]): a renderer's sky pixels are then
/// dropped, and the line caster leaves the pixels above each line's last
/// hit unwalked ([`Sink::sky_is_drawn`]). The same frame as the sink's
/// own, for a render that puts each pixel once ([`crate::render`]; a
/// governor's refined line may put sky where its base pass put terrain).
/// [`PreparedAtmosphere::sink_over_sky`](crate::PreparedAtmosphere::sink_over_sky)
/// does the same under the atmosphere's sky.
#[derive(Debug)]
pub struct SkyFirst<S> {
    sink: S,
}

impl<S: Sink> SkyFirst<S> {
    /// `sink`, a `width` × `height` frame, with every pixel put as sky of
    /// color `sky` (the render's `RenderOptions::sky`), a row at a time
    /// in runs ([`Sink::put_sky_run`]).
    pub fn new(mut sink: S, width: u32, height: u32, sky: Rgb) -> Self {
        let run = [sky; SKY_RUN];
        for y in 0..height {
            put_sky_row(&mut sink, width, y, &run);
        }
        Self { sink }
    }
}

impl<S: Sink> Sink for SkyFirst<S> {
    #[inline(always)]
    fn put(&mut self, x: u32, y: u32, sample: Sample) {
        if !sample.is_sky() {
            self.sink.put(x, y, sample);
        }
    }

    #[inline]
    fn line(&mut self, plane: &LinePlane) {
        self.sink.line(plane);
    }

    #[inline(always)]
    fn put_ray(&mut self, x: u32, y: u32, sample: Sample, slope: i32) {
        self.sink.put_ray(x, y, sample, slope);
    }

    #[inline(always)]
    fn sky_is_drawn(&self) -> bool {
        true
    }
}

/// The most pixels of a row a sink that draws the sky first puts at once
/// ([`Sink::put_sky_run`]).
pub(crate) const SKY_RUN: usize = 64;

/// Puts row `y` of a `width`-pixel frame as sky, every pixel of it
/// colored as `run`'s, in runs of [`SKY_RUN`].
pub(crate) fn put_sky_row<S: Sink + ?Sized>(
    sink: &mut S,
    width: u32,
    y: u32,
    run: &[Rgb; SKY_RUN],
) {
    for x in (0..width).step_by(SKY_RUN) {
        sink.put_sky_run(x, y, &run[..(width - x).min(SKY_RUN as u32) as usize]);
    }
}

/// Where a run of `pixels` pixels from `(x, y)` along a row lies in a
/// row-major `width` × `height` buffer: its indices, cut at the row's end;
/// `None` where `(x, y)` is outside. For a sink's
/// [`Sink::put_sky_run`].
#[inline]
pub fn row_run(
    width: u32,
    height: u32,
    x: u32,
    y: u32,
    pixels: usize,
) -> Option<core::ops::Range<usize>> {
    if x >= width || y >= height {
        return None;
    }
    let start = y as usize * width as usize + x as usize;
    Some(start..start + pixels.min((width - x) as usize))
}

/// A caller-provided framebuffer: a color per pixel, optionally a distance
/// per pixel, row-major with y = 0 at the top.
#[derive(Debug)]
pub struct Framebuffer<'a> {
    colors: &'a mut [Rgb],
    distances: Option<&'a mut [u32]>,
    width: u32,
    height: u32,
}

/// Why a framebuffer could not be made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FramebufferError {
    /// A buffer is shorter than width × height.
    TooSmall,
}

impl fmt::Display for FramebufferError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("framebuffer is smaller than width x height")
    }
}

impl core::error::Error for FramebufferError {}

impl<'a> Framebuffer<'a> {
    /// A color-only framebuffer.
    pub fn new(colors: &'a mut [Rgb], width: u32, height: u32) -> Result<Self, FramebufferError> {
        if colors.len() < width as usize * height as usize {
            return Err(FramebufferError::TooSmall);
        }
        Ok(Self {
            colors,
            distances: None,
            width,
            height,
        })
    }

    /// A framebuffer that also keeps each pixel's [`Sample::distance`].
    pub fn with_distances(
        colors: &'a mut [Rgb],
        distances: &'a mut [u32],
        width: u32,
        height: u32,
    ) -> Result<Self, FramebufferError> {
        if distances.len() < width as usize * height as usize {
            return Err(FramebufferError::TooSmall);
        }
        let mut fb = Self::new(colors, width, height)?;
        fb.distances = Some(distances);
        Ok(fb)
    }
}

impl Sink for Framebuffer<'_> {
    #[inline]
    fn put_sky_run(&mut self, x: u32, y: u32, colors: &[Rgb]) {
        let Some(run) = row_run(self.width, self.height, x, y, colors.len()) else {
            return;
        };
        let length = run.len();
        if let Some(pixels) = self.colors.get_mut(run.clone()) {
            pixels.copy_from_slice(&colors[..length]);
        }
        if let Some(distances) = self.distances.as_deref_mut().and_then(|d| d.get_mut(run)) {
            distances.fill(Sample::SKY);
        }
    }

    #[inline]
    fn put(&mut self, x: u32, y: u32, sample: Sample) {
        if x >= self.width || y >= self.height {
            return;
        }
        let index = y as usize * self.width as usize + x as usize;
        if let Some(pixel) = self.colors.get_mut(index) {
            *pixel = sample.color;
        }
        if let Some(d) = self.distances.as_deref_mut().and_then(|d| d.get_mut(index)) {
            *d = sample.distance;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sky_put_first_gives_the_same_frame() {
        // Colors and distances, looking up, level, down, rolled and
        // straight down, at a size with runs cut at the row's end.
        use crate::{render, Camera, NoProbe, Pyramid, RenderOptions, Terrain, View};
        const SIDE: usize = 64;
        let heights: std::vec::Vec<u16> = (0..SIDE * SIDE)
            .map(|i| ((20 + (i * 7919 % 13)) * 16) as u16)
            .collect();
        let colors: std::vec::Vec<Rgb> = (0..SIDE * SIDE).map(|i| [i as u8, 90, 30]).collect();
        let terrain = Terrain::new(SIDE as u32, SIDE as u32, &heights, &colors).unwrap();
        let pyramid = Pyramid::flat(terrain);
        let options = RenderOptions::default();
        let (width, height) = (131, 77);
        let pixels = (width * height) as usize;
        for camera in [
            Camera::looking([5.0, 5.0, 40.0], 45.0, -10.0),
            Camera::looking([5.0, 5.0, 40.0], 45.0, 0.0),
            Camera::looking([5.0, 5.0, 40.0], 45.0, 20.0),
            Camera {
                roll_deg: 40.0,
                ..Camera::looking([5.0, 60.0, 35.0], -30.0, 5.0)
            },
            Camera::looking([32.0, 32.0, 90.0], 0.0, 90.0),
        ] {
            let view = View::new(&camera, width, height).unwrap();
            let frames = [false, true].map(|first| {
                let (mut colors, mut distances) = (std::vec![[0; 3]; pixels], std::vec![0; pixels]);
                let mut frame =
                    Framebuffer::with_distances(&mut colors, &mut distances, width, height)
                        .unwrap();
                if first {
                    let mut sky_first = SkyFirst::new(&mut frame, width, height, options.sky);
                    render(&pyramid, &view, &options, &mut sky_first, &mut NoProbe);
                } else {
                    render(&pyramid, &view, &options, &mut frame, &mut NoProbe);
                }
                (colors, distances)
            });
            let sky = frames[0].1.iter().filter(|&&d| d == Sample::SKY).count();
            assert!(frames[0] == frames[1], "{camera:?}: {sky} sky pixels");
        }
    }

    #[test]
    fn a_sky_run_is_cut_at_its_rows_end_and_dropped_outside() {
        assert_eq!(row_run(4, 3, 1, 2, 2), Some(9..11));
        assert_eq!(row_run(4, 3, 2, 1, 9), Some(6..8));
        assert_eq!(row_run(4, 3, 4, 0, 1), None);
        assert_eq!(row_run(4, 3, 0, 3, 1), None);
        // A frame buffer takes the run's colors and the sky's distance.
        let (mut colors, mut distances) = ([[0u8; 3]; 12], [0u32; 12]);
        let mut frame = Framebuffer::with_distances(&mut colors, &mut distances, 4, 3).unwrap();
        frame.put_sky_run(2, 1, &[[1, 2, 3], [4, 5, 6], [7, 8, 9]]);
        assert_eq!(colors[5..9], [[0; 3], [1, 2, 3], [4, 5, 6], [0; 3]]);
        assert_eq!(distances[5..9], [0, Sample::SKY, Sample::SKY, 0]);
    }

    #[test]
    fn out_of_range_pixels_are_discarded() {
        let mut colors = [[0u8; 3]; 6];
        let mut fb = Framebuffer::new(&mut colors, 3, 2).unwrap();
        let s = Sample {
            color: [9, 9, 9],
            distance: 5,
            elevation: 0,
        };
        fb.put(3, 0, s);
        fb.put(0, 2, s);
        fb.put(u32::MAX, u32::MAX, s);
        fb.put(2, 1, s);
        assert_eq!(colors, [[0; 3], [0; 3], [0; 3], [0; 3], [0; 3], [9, 9, 9]]);
        assert_eq!(
            Framebuffer::new(&mut [[0; 3]; 5], 3, 2).unwrap_err(),
            FramebufferError::TooSmall
        );
    }
}
