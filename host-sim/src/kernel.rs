//! Runs the fixed-point kernel on the host and converts what it reports.

use crate::camera::{length, ContractCamera};
use crate::error::{Error, Result};
use crate::frame::{Frame, LevelStats, RenderStats};
use crate::scene::KernelScene;
use std::time::Instant;
use terracast::{
    render, render_by_footprint, Camera, Coherence, CountingProbe, FrameCost, Governor,
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
