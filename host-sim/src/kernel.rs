//! Runs the fixed-point kernel on the host and converts what it reports.

use crate::camera::{length, ContractCamera};
use crate::error::{Error, Result};
use crate::frame::{Frame, LevelStats, RenderStats};
use crate::scene::KernelScene;
use std::time::Instant;
use terracast::{
    render, render_by_footprint, Camera, Coherence, CountingProbe, FrameCost, FrameWork, Governor,
    PreparedAtmosphere, Prices, Probe, RenderOptions, Sample, Sink, Surface, View, WithSticks,
};

/// How many rays each pixel gets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelRays {
    /// The options' `vertical_samples`, every pixel alike
    /// (`terracast::render`).
    Fixed,
    /// One, two or four, as many as the pixel's footprint needs
    /// (`terracast::render_by_footprint`).
    ByFootprint,
    /// One frame within a budget of this many of the board's instructions
    /// a pixel (`terracast::Governor` at `Prices::BOARD`, from a bias of 1):
    /// one ray a pixel, and two or four on the lines the budget refines.
    Governed(u64),
}

impl PixelRays {
    /// Renders `view` of `surface` with the kernel entry point these rays
    /// a pixel name; a governed frame's cost.
    pub fn render<T: Surface + ?Sized, S: Sink, P: Probe>(
        self,
        surface: &T,
        view: &View,
        options: &RenderOptions,
        sink: &mut S,
        probe: &mut P,
    ) -> Option<FrameCost> {
        match self {
            Self::Fixed => render(surface, view, options, sink, probe),
            Self::ByFootprint => render_by_footprint(surface, view, options, sink, probe),
            Self::Governed(per_pixel) => {
                let pixels = u64::from(view.width()) * u64::from(view.height());
                let budget = pixels.saturating_mul(per_pixel);
                let mut governor = Governor::new(budget, Prices::BOARD);
                return Some(governor.render(surface, view, options, sink, probe));
            }
        }
        None
    }
}

/// This machine's prices for the [`Governor`], in picoseconds: the
/// least-squares fit, no price below 0, of `frames`' measured times (ns)
/// to their work, for images of `image_pixels` pixels. Fitted are a pixel
/// rendered again by the refinement (its rays' blend), a ray, a step, a
/// hit and a hit level, and apart from them every pixel's first write, a
/// constant of the image's size that no choice of the governor's changes.
/// `per_pixel` is the refined pixel's price, so the frames' priced costs
/// all carry the same constant beside their time. A line's and a color
/// fetch's costs go with the rays' and the hits' (a line's rays are set up
/// with it; a hit fetches its colors): their prices are 0. The frames
/// should span the work the governor will spend on (several budgets and
/// views): the board's prices count instructions, and this machine's
/// caches and branch predictors do not price the same things alike.
pub fn fitted_prices(frames: &[(FrameWork, f64)], image_pixels: u64) -> Result<FittedPrices> {
    let rows: Vec<([f64; 6], f64)> = frames
        .iter()
        .map(|(w, ns)| {
            (
                [
                    image_pixels,
                    w.pixels.saturating_sub(image_pixels),
                    w.rays,
                    w.steps,
                    w.hits,
                    w.hit_levels,
                ]
                .map(|n| n as f64),
                ns * 1000.0,
            )
        })
        .collect();
    let fit = crate::fit::non_negative_least_squares(&rows).ok_or_else(|| {
        Error::new(format!(
            "the {} timed frames do not tell a pixel's, a ray's, a step's and a hit's costs apart: time frames of more views and budgets",
            frames.len()
        ))
    })?;
    let [first_write, per_pixel, per_ray, per_step, per_hit, per_hit_level] =
        fit.map(|p| p.round().clamp(0.0, f64::from(u32::MAX)) as u32);
    Ok(FittedPrices {
        prices: Prices {
            per_pixel,
            per_line: 0,
            per_ray,
            per_step,
            per_color: 0,
            per_hit,
            per_hit_level,
        },
        first_write,
        image_pixels,
    })
}

/// Prices fitted to this machine's times ([`fitted_prices`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FittedPrices {
    /// The governor's prices (ps).
    pub prices: Prices,
    /// A pixel's first write (ps), outside the governor's prices.
    pub first_write: u32,
    /// The image size the prices were fitted for.
    pub image_pixels: u64,
}

impl FittedPrices {
    /// The time (ns) these prices predict for a frame that did `work`.
    pub fn time_ns(&self, work: &FrameWork) -> f64 {
        let first_writes = self.image_pixels;
        let priced = self.prices.of(work) as f64
            - f64::from(self.prices.per_pixel) * first_writes as f64
            + f64::from(self.first_write) * first_writes as f64;
        priced / 1000.0
    }
}

/// A sink that keeps every sample of the frame.
#[derive(Debug)]
pub struct SampleBuffer {
    width: u32,
    height: u32,
    /// Row-major samples, y = 0 at the top.
    pub samples: Vec<Sample>,
}

impl SampleBuffer {
    /// A buffer of sky samples.
    pub fn new(width: u32, height: u32) -> Self {
        let sky = Sample {
            color: [0; 3],
            distance: Sample::SKY,
            elevation: 0,
        };
        Self {
            width,
            height,
            samples: vec![sky; width as usize * height as usize],
        }
    }
}

impl Sink for SampleBuffer {
    #[inline]
    fn put(&mut self, x: u32, y: u32, sample: Sample) {
        if x < self.width && y < self.height {
            self.samples[y as usize * self.width as usize + x as usize] = sample;
        }
    }
}

/// Renders with the kernel; the Euclidean depth of each pixel comes from
/// the kernel's hit (major-axis distance or height, whichever the ray's
/// direction conditions better).
pub fn render_kernel(
    scene: &KernelScene,
    camera: &Camera,
    width: u32,
    height: u32,
    options: &RenderOptions,
) -> Result<(Frame, RenderStats)> {
    render_kernel_with(scene, camera, width, height, options, PixelRays::Fixed)
}

/// [`render_kernel`] with `rays` rays a pixel.
pub fn render_kernel_with(
    scene: &KernelScene,
    camera: &Camera,
    width: u32,
    height: u32,
    options: &RenderOptions,
    rays: PixelRays,
) -> Result<(Frame, RenderStats)> {
    render_kernel_in(scene, camera, (width, height), options, rays, None)
}

/// [`render_kernel_with`] with `atmosphere` over the frame (when given).
pub fn render_kernel_in(
    scene: &KernelScene,
    camera: &Camera,
    (width, height): (u32, u32),
    options: &RenderOptions,
    rays: PixelRays,
    atmosphere: Option<&PreparedAtmosphere>,
) -> Result<(Frame, RenderStats)> {
    let pyramid = scene.pyramid_for(options)?;
    let size = (width, height);
    let (frame, mut stats) = match scene.sticks()? {
        Some(sticks) => {
            let surface = WithSticks::new(&pyramid, sticks);
            let (frame, mut stats) =
                render_surface_in(&surface, camera, size, options, rays, atmosphere)?;
            stats.resident_bytes = sticks.bytes() as u64;
            (frame, stats)
        }
        None => render_surface_in(&pyramid, camera, size, options, rays, atmosphere)?,
    };
    stats.resident_bytes += pyramid.bytes() as u64;
    if let Some(levels) = &mut stats.levels {
        levels.levels = pyramid.levels();
    }
    Ok((frame, stats))
}

/// Renders `surface` with the kernel (the camera in the surface's
/// coordinates). The stats' resident bytes are left 0 for the caller.
pub fn render_surface<T: Surface + ?Sized>(
    surface: &T,
    camera: &Camera,
    width: u32,
    height: u32,
    options: &RenderOptions,
) -> Result<(Frame, RenderStats)> {
    render_surface_with(surface, camera, width, height, options, PixelRays::Fixed)
}

/// [`render_surface`] with `rays` rays a pixel.
pub fn render_surface_with<T: Surface + ?Sized>(
    surface: &T,
    camera: &Camera,
    width: u32,
    height: u32,
    options: &RenderOptions,
    rays: PixelRays,
) -> Result<(Frame, RenderStats)> {
    render_surface_in(surface, camera, (width, height), options, rays, None)
}

/// [`render_surface_with`] with `atmosphere` over the frame (when given):
/// the kernel's fixed-point sky and fog, pixel by pixel as the kernel
/// finishes them, inside the render's time.
pub fn render_surface_in<T: Surface + ?Sized>(
    surface: &T,
    camera: &Camera,
    (width, height): (u32, u32),
    options: &RenderOptions,
    rays: PixelRays,
    atmosphere: Option<&PreparedAtmosphere>,
) -> Result<(Frame, RenderStats)> {
    let view =
        View::new(camera, width, height).map_err(|e| Error::new(format!("bad view: {e}")))?;
    let mut buffer = SampleBuffer::new(width, height);
    let mut probe = CountingProbe::default();
    let started = Instant::now();
    let governed = match atmosphere {
        Some(air) => rays.render(
            surface,
            &view,
            options,
            &mut air.sink(&view, &mut buffer),
            &mut probe,
        ),
        None => rays.render(surface, &view, options, &mut buffer, &mut probe),
    };
    let render_ns = started.elapsed().as_nanos() as u64;

    let rays = ContractCamera::new(camera, width, height);
    let mut frame = Frame::new(width, height);
    for (i, sample) in buffer.samples.iter().enumerate() {
        frame.colors[i] = sample.color;
        if sample.is_sky() {
            continue;
        }
        let (px, py) = ((i % width as usize) as f64, (i / width as usize) as f64);
        let d = rays.direction(px + 0.5, py + 0.5);
        let major = d[0].abs().max(d[1].abs());
        let per_unit = length(d);
        const ONE: f64 = 65536.0;
        frame.depth[i] = if major >= d[2].abs() {
            f64::from(sample.distance) / ONE * per_unit / major
        } else {
            (rays.eye[2] - f64::from(sample.elevation) / ONE).abs() * per_unit / d[2].abs()
        } as f32;
    }
    let pixels = u64::from(width) * u64::from(height);
    let stats = RenderStats {
        method: match options.coherence {
            Coherence::Off => "kernel-no-coherence",
            Coherence::Exact => "kernel-exact-coherence",
            Coherence::AcrossLevels => "kernel",
        },
        pixels,
        rays: probe.rays,
        steps: probe.steps,
        resident_bytes: 0,
        render_ns,
        levels: Some(LevelStats {
            levels: usize::from(surface.top()) + 1,
            steps: probe.steps_by_level,
            hits: probe.hits_by_level,
            bound_tests: probe.bound_tests,
            color_fetches: probe.color_fetches,
            roughness: surface.roughness(),
            terrain_fit: options.fit_for(surface.roughness()),
            governed,
        }),
    };
    Ok((frame, stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn work(pixels: u64, rays: u64, steps: u64, hits: u64, hit_levels: u64) -> FrameWork {
        FrameWork {
            pixels,
            lines: 600,
            rays,
            steps,
            colors: 2 * hits,
            hits,
            hit_levels,
        }
    }

    #[test]
    fn prices_fitted_to_timed_frames_are_the_ones_that_timed_them() {
        // Frames of 1000 pixels timed at 3 ns a pixel's first write, 9 a
        // refined pixel, 40 a ray, 2.5 a step, 60 a hit and 15 a hit
        // level: the fit finds those prices in picoseconds.
        let frames: Vec<_> = [
            work(1000, 1000, 9000, 900, 100),
            work(1000, 2000, 15000, 1900, 900),
            work(2000, 2000, 30000, 1000, 0),
            work(2000, 4000, 11000, 3900, 2000),
            work(1500, 1500, 20000, 1500, 700),
            work(3000, 5000, 41000, 4000, 1500),
            work(1200, 2500, 12000, 2400, 300),
        ]
        .into_iter()
        .map(|w| {
            let ns = 3.0 * 1000.0
                + 9.0 * (w.pixels - 1000) as f64
                + 40.0 * w.rays as f64
                + 2.5 * w.steps as f64
                + 60.0 * w.hits as f64
                + 15.0 * w.hit_levels as f64;
            (w, ns)
        })
        .collect();
        let fitted = fitted_prices(&frames, 1000).unwrap();
        let prices = fitted.prices;
        assert_eq!(fitted.first_write, 3000);
        for (work, ns) in &frames {
            assert!((fitted.time_ns(work) - ns).abs() < 1e-6, "{work:?}");
        }
        assert_eq!(
            [
                prices.per_pixel,
                prices.per_ray,
                prices.per_step,
                prices.per_hit,
                prices.per_hit_level
            ],
            [9000, 40000, 2500, 60000, 15000]
        );
        assert_eq!((prices.per_line, prices.per_color), (0, 0));
        // One frame cannot tell five prices apart: a one-line error.
        let error = fitted_prices(&frames[..1], 1000).unwrap_err().to_string();
        assert!(
            error.contains("do not tell") && !error.contains('\n'),
            "{error}"
        );
    }
}
