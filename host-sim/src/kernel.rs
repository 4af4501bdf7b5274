//! Runs the fixed-point kernel on the host and converts what it reports.

use crate::camera::{length, ContractCamera};
use crate::error::{Error, Result};
use crate::frame::{Frame, LevelStats, RenderStats};
use crate::scene::KernelScene;
use std::time::Instant;
use terracast::{
    render, render_by_footprint, Camera, Coherence, CountingProbe, FrameCost, Governor, NoProbe,
    PreparedAtmosphere, Prices, Probe, RenderOptions, Rgb, Sample, Sink, Surface, View, WithDetail,
    WithSticks,
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
    /// a pixel (`terracast::Governor::on_board`, from a bias of 1):
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
                let mut governor = Governor::on_board(budget);
                return Some(governor.render(surface, view, options, sink, probe));
            }
        }
        None
    }
}

/// This machine's prices for the [`Governor`], in picoseconds: the
/// least-squares fit, no price below 0, of `frames`' measured times (ns)
/// to their work, for images of `image_pixels` pixels. The base pass (the
/// line caster) and the refinement (the per-ray path) are priced apart,
/// as the board's are ([`Governor::on_board`]): the base pass's lines,
/// rays and hit levels (a ray of the line caster is a hit: it casts none
/// into the sky but the one a line leaves the terrain with), the
/// refinement's pixels rendered again (their rays' blend), rays, hits and
/// hit levels, a step alike in both, and apart from them every pixel's
/// first write, a constant of the image's size that no choice of the
/// governor's changes. A color fetch's cost goes with its hit's: its price
/// is 0. The frames should span the work the governor will spend on
/// (several budgets and views): the board's prices count instructions,
/// and this machine's caches and branch predictors do not price the same
/// things alike.
pub fn fitted_prices(frames: &[(FrameCost, f64)], image_pixels: u64) -> Result<FittedPrices> {
    // The prices fitted: as many frames at least.
    const FITTED: usize = 9;
    let rows: Vec<([f64; FITTED], f64)> = frames
        .iter()
        .map(|(cost, ns)| {
            let (base, refined) = (&cost.base_work, cost.refined_work());
            (
                [
                    image_pixels,
                    base.lines,
                    base.rays,
                    base.hit_levels,
                    refined.pixels,
                    refined.rays,
                    refined.hits,
                    refined.hit_levels,
                    cost.work.steps,
                ]
                .map(|n| n as f64),
                ns * 1000.0,
            )
        })
        .collect();
    let apart = || {
        Error::new(format!(
            "the {} timed frames do not tell a pixel's, a ray's, a step's and a hit's costs apart: time frames of more views and budgets",
            frames.len()
        ))
    };
    // (A price the frames cannot tell apart from the others is held at 0.)
    if rows.len() < FITTED {
        return Err(apart());
    }
    let fit = crate::fit::non_negative_least_squares(&rows).ok_or_else(apart)?;
    let [first_write, line, base_ray, base_level, pixel, ray, hit, level, step] =
        fit.map(|p| p.round().clamp(0.0, f64::from(u32::MAX)) as u32);
    Ok(FittedPrices {
        // Every pixel's first write is apart, a straight one's too: no
        // count here tells them apart (what a level frame's pixels save
        // goes to its other counts).
        base: Prices {
            per_pixel: 0,
            per_straight_pixel: 0,
            per_line: line,
            per_ray: base_ray,
            per_step: step,
            per_color: 0,
            per_color_square: 0,
            per_hit: 0,
            per_hit_level: base_level,
        },
        prices: Prices {
            per_pixel: pixel,
            // The refinement writes no straight pixel.
            per_straight_pixel: pixel,
            per_line: 0,
            per_ray: ray,
            per_step: step,
            per_color: 0,
            per_color_square: 0,
            per_hit: hit,
            per_hit_level: level,
        },
        first_write,
        image_pixels,
    })
}

/// Prices fitted to this machine's times ([`fitted_prices`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FittedPrices {
    /// The base pass's prices (ps; a pixel's first write is apart).
    pub base: Prices,
    /// The refinement's prices (ps).
    pub prices: Prices,
    /// A pixel's first write (ps), outside the governor's prices.
    pub first_write: u32,
    /// The image size the prices were fitted for.
    pub image_pixels: u64,
}

impl FittedPrices {
    /// A governor at these prices whose frames take `ns` (the first
    /// writes' constant set aside from its budget), and that budget.
    pub fn governor(&self, ns: f64) -> Governor {
        let first_writes = f64::from(self.first_write) * self.image_pixels as f64;
        let budget = (ns * 1000.0 - first_writes).max(0.0) as u64;
        Governor::new(budget, self.prices).with_base_prices(self.base)
    }

    /// The time (ns) these prices predict for a frame that `cost` says
    /// was rendered at them (or at any prices: its work is repriced).
    pub fn time_ns(&self, cost: &FrameCost) -> f64 {
        let priced = self.base.of(&cost.base_work) + self.prices.of(&cost.refined_work());
        (priced as f64 + f64::from(self.first_write) * self.image_pixels as f64) / 1000.0
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
        let sky = Sample::sky([0; 3]);
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

    #[inline]
    fn put_sky_run(&mut self, x: u32, y: u32, colors: &[Rgb]) {
        let Some(run) = terracast::row_run(self.width, self.height, x, y, colors.len()) else {
            return;
        };
        for (sample, &color) in self.samples[run].iter_mut().zip(colors) {
            *sample = Sample::sky(color);
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
    let details = scene.details()?;
    let (frame, mut stats) = match scene.sticks()? {
        Some(sticks) => {
            let surface = WithSticks::new(&pyramid, sticks);
            let (frame, mut stats) =
                render_surface_in(&surface, camera, size, options, rays, atmosphere)?;
            stats.resident_bytes = sticks.bytes() as u64;
            (frame, stats)
        }
        None if !details.is_empty() => {
            let surface = WithDetail::new(&pyramid, &details);
            let (frame, mut stats) =
                render_surface_in(&surface, camera, size, options, rays, atmosphere)?;
            stats.resident_bytes = details.iter().map(|d| d.bytes() as u64).sum();
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

/// The time (ns) of one render of `scene` as a user's render runs: with
/// no probe, into the host's sample buffer (which the depth comes from),
/// the surface set up outside the time as [`render_kernel_in`] sets it up.
/// [`render_kernel_in`] counts the kernel's work with a probe, which costs
/// the host time a user's render does not spend: a speed compared with
/// another method's takes this time instead.
pub fn time_kernel(
    scene: &KernelScene,
    camera: &Camera,
    (width, height): (u32, u32),
    options: &RenderOptions,
    rays: PixelRays,
) -> Result<u64> {
    let view =
        View::new(camera, width, height).map_err(|e| Error::new(format!("bad view: {e}")))?;
    let pyramid = scene.pyramid_for(options)?;
    let details = scene.details()?;
    let mut buffer = SampleBuffer::new(width, height);
    let buffer = &mut buffer;
    Ok(match scene.sticks()? {
        Some(sticks) => time_surface(
            &WithSticks::new(&pyramid, sticks),
            &view,
            options,
            rays,
            buffer,
        ),
        None if !details.is_empty() => time_surface(
            &WithDetail::new(&pyramid, &details),
            &view,
            options,
            rays,
            buffer,
        ),
        None => time_surface(&pyramid, &view, options, rays, buffer),
    })
}

/// The time (ns) of one render of `surface` into `buffer`, no probe.
fn time_surface<T: Surface + ?Sized>(
    surface: &T,
    view: &View,
    options: &RenderOptions,
    rays: PixelRays,
    buffer: &mut SampleBuffer,
) -> u64 {
    let started = Instant::now();
    rays.render(surface, view, options, buffer, &mut NoProbe);
    started.elapsed().as_nanos() as u64
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
            secondary_rays: probe.secondary_rays,
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
    use terracast::{FrameWork, U8F8};

    fn work(pixels: u64, rays: u64, steps: u64, hits: u64, hit_levels: u64) -> FrameWork {
        FrameWork {
            pixels,
            lines: 600,
            rays,
            steps,
            colors: 2 * hits,
            color_squares: 0,
            hits,
            hit_levels,
            straight_pixels: 0,
        }
    }

    #[test]
    fn prices_fitted_to_timed_frames_are_the_ones_that_timed_them() {
        // Frames of 1000 pixels timed at 3 ns a pixel's first write and
        // 2.5 a step; in the base pass 5 a line, 20 a ray and 4 a hit
        // level; in the refinement 9 a pixel, 40 a ray, 60 a hit and 15 a
        // hit level: the fit finds those prices in picoseconds.
        let mut seed = 7u64;
        let mut next = |most: u64| {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (seed >> 33) % most + 1
        };
        let frames: Vec<(FrameCost, f64)> = (0..14)
            .map(|_| {
                let base = FrameWork {
                    lines: next(400),
                    ..work(1000, next(1000), next(5000), next(900), next(300))
                };
                let refined = work(next(2000), next(2000), next(9000), next(1900), next(900));
                let all = FrameWork {
                    pixels: base.pixels + refined.pixels,
                    lines: base.lines + refined.lines,
                    rays: base.rays + refined.rays,
                    steps: base.steps + refined.steps,
                    colors: base.colors + refined.colors,
                    color_squares: base.color_squares + refined.color_squares,
                    hits: base.hits + refined.hits,
                    hit_levels: base.hit_levels + refined.hit_levels,
                    straight_pixels: 0,
                };
                let ns = 3.0 * 1000.0
                    + 2.5 * all.steps as f64
                    + 5.0 * base.lines as f64
                    + 20.0 * base.rays as f64
                    + 4.0 * base.hit_levels as f64
                    + 9.0 * refined.pixels as f64
                    + 40.0 * refined.rays as f64
                    + 60.0 * refined.hits as f64
                    + 15.0 * refined.hit_levels as f64;
                let cost = FrameCost {
                    cost: 0,
                    work: all,
                    budget: 0,
                    base_cost: 0,
                    base_work: base,
                    level_bias: U8F8::ONE,
                    coarse_lines: 0,
                    refined_lines: 0,
                    filled_rays: 0,
                };
                (cost, ns)
            })
            .collect();
        let fitted = fitted_prices(&frames, 1000).unwrap();
        let (base, prices) = (fitted.base, fitted.prices);
        assert_eq!(fitted.first_write, 3000);
        for (cost, ns) in &frames {
            assert!((fitted.time_ns(cost) - ns).abs() < 1e-3, "{cost:?}");
        }
        assert_eq!(
            [
                base.per_line,
                base.per_ray,
                base.per_hit_level,
                base.per_step
            ],
            [5000, 20000, 4000, 2500]
        );
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
        // A governor for a frame time sets the first writes aside.
        assert_eq!(fitted.governor(10_000.0).budget(), 7_000_000);
        // One frame cannot tell five prices apart: a one-line error.
        let error = fitted_prices(&frames[..1], 1000).unwrap_err().to_string();
        assert!(
            error.contains("do not tell") && !error.contains('\n'),
            "{error}"
        );
    }

    #[test]
    fn a_kernel_render_is_timed_without_its_probe() {
        // The time of the render `render_kernel_with` counts, on each
        // surface the scene may lend (plain, with objects); a view the
        // kernel cannot take is a one-line error, as the render's is.
        let camera = Camera::looking([20.0, 30.0, 120.0], 50.0, 10.0);
        let options = RenderOptions::default();
        let plain = crate::scene::procedural(128, 3).to_kernel().unwrap();
        let mut objects = crate::scene::procedural(128, 3);
        objects.plant_objects(5);
        let objects = objects.to_kernel().unwrap();
        assert!(objects.sticks().unwrap().is_some());
        for scene in [&plain, &objects] {
            let time = time_kernel(scene, &camera, (64, 48), &options, PixelRays::Fixed).unwrap();
            assert!(time > 0);
        }
        let error = time_kernel(&plain, &camera, (0, 48), &options, PixelRays::Fixed)
            .unwrap_err()
            .to_string();
        let rendered = render_kernel(&plain, &camera, 0, 48, &options)
            .unwrap_err()
            .to_string();
        assert!(error == rendered && !error.contains('\n'), "{error}");
    }

    #[test]
    fn the_sky_drawn_first_gives_the_same_samples() {
        // The host's sample buffer takes the sky drawn first as runs of a
        // row (`Sink::put_sky_run`): every sample, color, distance and
        // elevation, as the atmosphere put pixel by pixel gives it, looking
        // up and down, and down past the map's edge (where rows below the
        // horizon, drawn as its one color, show sky).
        let scene = crate::scene::procedural(256, 3).to_kernel().unwrap();
        let pyramid = scene.pyramid_for(&RenderOptions::default()).unwrap();
        let air = terracast::Atmosphere::FLIGHT.prepare().unwrap();
        for (yaw, pitch) in [(50.0, -5.0), (50.0, 2.0), (50.0, 30.0), (230.0, 25.0)] {
            let camera = Camera::looking([20.0, 30.0, 200.0], yaw, pitch);
            let view = View::new(&camera, 203, 117).unwrap();
            let options = RenderOptions::default();
            let render_into = |mut sink: &mut dyn Sink| {
                render(
                    &pyramid,
                    &view,
                    &options,
                    &mut sink,
                    &mut terracast::NoProbe,
                );
            };
            let mut pixel_by_pixel = SampleBuffer::new(203, 117);
            render_into(&mut air.sink(&view, &mut pixel_by_pixel));
            let mut drawn_first = SampleBuffer::new(203, 117);
            render_into(&mut air.sink_over_sky(&view, &mut drawn_first));
            let (pixel_by_pixel, drawn_first) = (pixel_by_pixel.samples, drawn_first.samples);
            assert!(pixel_by_pixel == drawn_first, "yaw {yaw}, pitch {pitch}");
        }
    }
}
