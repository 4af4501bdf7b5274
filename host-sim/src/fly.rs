//! A flight at a steady display rate (Cohen-Or §4): frames rendered within
//! a fixed budget at the rendering rate, and every display frame between
//! them warped from the last rendered one toward the display-time camera.
//!
//! Time is the modeled machine's ([`Machine`]): a frame of `r` rays, `c`
//! color fetches and `s` steps takes `r·per_ray + c·per_color + s·per_step`
//! cycles, spread over the workers (the line pool keeps them within a few
//! lines of each other, see `sim`). The budget is the rendering period's
//! cycles on the workers, and the kernel's [`Governor`] spends it at those
//! prices ([`terracast::Prices`]): every frame costs at most the budget and the
//! governor fills what its base pass leaves with refined lines, so renders
//! take the same time and start on a fixed cadence:
//!
//! - render `j ≥ 1` starts at `(j − 1)·T`, is done by `j·T`, and is made for
//!   the first display time at or after `j·T`, from the path's camera then;
//!   render 0 is made before the flight starts, for time 0;
//! - display frame `k` (at `k/rate`) shows the last render done by then:
//!   as rendered if it was made for that time, else warped to that time's
//!   camera ([`Warp`]).
//!
//! Frames are rendered with margins ([`with_margin`]), so that a warp
//! rarely reaches outside them.

use crate::error::{Error, Result};
use crate::metrics::psnr;
use crate::scene::{KernelScene, Scene};
use crate::sim::Machine;
use terracast::{
    control_points, with_margin, Camera, CountingProbe, FrameCost, Framebuffer, Governor,
    PreparedAtmosphere, RenderOptions, Rgb, Sample, Surface, View, Warp, WithDetail, WithSticks,
};

/// A camera path: keyframes in time, linearly interpolated.
#[derive(Debug, Clone, PartialEq)]
pub struct Path {
    keys: Vec<Key>,
}

/// One keyframe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Key {
    /// Seconds from the start.
    pub time: f64,
    /// Eye, voxels.
    pub eye: [f32; 3],
    /// Heading, pitch and bank, degrees.
    pub yaw: f32,
    /// See `yaw`.
    pub pitch: f32,
    /// See `yaw`.
    pub roll: f32,
}

impl Path {
    /// A path through `keys`, which must be at least one and in
    /// increasing time.
    pub fn new(keys: Vec<Key>) -> Result<Self> {
        if keys.is_empty() {
            return Err(Error::new("a path needs at least one keyframe"));
        }
        if keys.windows(2).any(|w| w[1].time <= w[0].time) {
            return Err(Error::new("path keyframes must be in increasing time"));
        }
        Ok(Self { keys })
    }

    /// Reads a path file: one keyframe a line, `t x y z yaw pitch [roll]`
    /// (seconds, voxels, degrees; roll 0 when left out), `#` starts a
    /// comment.
    pub fn parse(text: &str) -> Result<Self> {
        let mut keys = Vec::new();
        for (number, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let values: Vec<f64> = line
                .split_whitespace()
                .map(str::parse::<f64>)
                .collect::<std::result::Result<_, _>>()
                .ok()
                .filter(|v: &Vec<f64>| {
                    (6..=7).contains(&v.len()) && v.iter().all(|x| x.is_finite())
                })
                .ok_or_else(|| {
                    Error::new(format!(
                        "path line {}: expected 't x y z yaw pitch [roll]', got '{line}'",
                        number + 1
                    ))
                })?;
            keys.push(Key {
                time: values[0],
                eye: [values[1] as f32, values[2] as f32, values[3] as f32],
                yaw: values[4] as f32,
                pitch: values[5] as f32,
                roll: values.get(6).copied().unwrap_or(0.0) as f32,
            });
        }
        Self::new(keys)
    }

    /// The built-in scenic path over `scene`: in from its south edge over
    /// the middle, a long turn east and back west, dipping toward the
    /// ground and looking down on the way, about 100 voxels a second at a
    /// 1024-voxel scale, banking into its turns (the right wing down while
    /// the heading falls, the left while it rises). It looks across the
    /// map all the way: terrain fills the view out to 0.3 of the map's
    /// side.
    pub fn scenic(scene: &Scene) -> Self {
        let (w, d) = (scene.width as f32, scene.depth as f32);
        let s = w.min(d) / 1024.0;
        let top = scene.max_height();
        let at = |x: f32, y: f32| [w * x, d * y];
        let keys = [
            (0.0, at(0.50, 0.06), top + 40.0 * s, 90.0, 10.0, 0.0),
            (2.0, at(0.52, 0.25), top + 10.0 * s, 80.0, 14.0, 5.0),
            (4.0, at(0.60, 0.42), top - 20.0 * s, 55.0, 22.0, 12.0),
            (6.0, at(0.70, 0.50), top + 5.0 * s, 40.0, 35.0, -10.0),
            (8.0, at(0.74, 0.64), top + 60.0 * s, 100.0, 55.0, -25.0),
            (10.0, at(0.66, 0.72), top + 30.0 * s, 160.0, 18.0, -20.0),
            (12.0, at(0.52, 0.68), top + 15.0 * s, 210.0, 8.0, 0.0),
        ];
        Self {
            keys: keys
                .into_iter()
                .map(|(time, [x, y], z, yaw, pitch, roll)| Key {
                    time,
                    eye: [x, y, z],
                    yaw,
                    pitch,
                    roll,
                })
                .collect(),
        }
    }

    /// The same path with every keyframe's roll 0.
    pub fn level(mut self) -> Self {
        for key in &mut self.keys {
            key.roll = 0.0;
        }
        self
    }

    /// Seconds from the first keyframe to the last.
    pub fn duration(&self) -> f64 {
        self.keys.last().map_or(0.0, |k| k.time) - self.keys.first().map_or(0.0, |k| k.time)
    }

    /// The camera at time `t` (held at the ends), with `hfov` degrees of
    /// horizontal field of view.
    pub fn camera(&self, t: f64, hfov: f32) -> Camera {
        // The keyframes around `t`, the same one at either end.
        let i = self.keys.partition_point(|k| k.time <= t);
        let last = self.keys.len() - 1;
        let (a, b) = (
            self.keys[i.saturating_sub(1).min(last)],
            self.keys[i.min(last)],
        );
        let f = if b.time > a.time {
            ((t - a.time) / (b.time - a.time)) as f32
        } else {
            0.0
        };
        let lerp = |x: f32, y: f32| x + (y - x) * f;
        // Turn and bank the short way round.
        let short = |from: f32, to: f32| ((to - from + 540.0) % 360.0) - 180.0;
        let roll = a.roll + short(a.roll, b.roll) * f;
        Camera {
            eye: core::array::from_fn(|i| lerp(a.eye[i], b.eye[i])),
            yaw_deg: (a.yaw + short(a.yaw, b.yaw) * f).rem_euclid(360.0),
            pitch_deg: lerp(a.pitch, b.pitch),
            // Within −180° to 180°, as the kernel takes it.
            roll_deg: roll - 360.0 * ((roll + 180.0) / 360.0).floor(),
            hfov_deg: hfov,
        }
    }
}

/// How to fly.
#[derive(Debug, Clone, PartialEq)]
pub struct FlyOptions {
    /// Display frames.
    pub frames: u32,
    /// Display rate, frames a second.
    pub display_hz: f64,
    /// Rendering rate the budget is made for, frames a second.
    pub render_hz: f64,
    /// Display image size.
    pub size: (u32, u32),
    /// Horizontal field of view of the display, degrees.
    pub hfov: f32,
    /// How much wider and taller than the display frames are rendered.
    pub margin: f32,
    /// Also render each warped frame's true view and compare.
    pub measure_warp: bool,
    /// The kernel's settings (the governor moves their level bias).
    pub render: RenderOptions,
    /// Sky, sun and fog over every render (the warped frames carry it).
    pub atmosphere: Option<PreparedAtmosphere>,
}

impl Default for FlyOptions {
    fn default() -> Self {
        Self {
            frames: 150,
            display_hz: 30.0,
            render_hz: 10.0,
            size: (200, 150),
            hfov: 60.0,
            margin: 1.2,
            measure_warp: true,
            render: RenderOptions::default(),
            atmosphere: None,
        }
    }
}

/// Whether a display frame is a fresh render or a warp.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Rendered for this display time.
    Rendered,
    /// The last render, warped to this display time's camera.
    Warped,
}

/// One display frame of the report.
#[derive(Debug, Clone, PartialEq)]
pub struct DisplayFrame {
    /// Display time, seconds.
    pub time: f64,
    /// Rendered or warped.
    pub kind: Kind,
    /// The render it shows: its number, cost (cycles), steps, budget
    /// (cycles) and level bias.
    pub render: usize,
    /// See `render`.
    pub cost: u64,
    /// See `render`.
    pub steps: u64,
    /// See `render`.
    pub budget: u64,
    /// See `render`.
    pub level_bias: f64,
    /// Lines the render finished at the coarsest bias, and rays that found
    /// no budget left (see [`terracast::FrameCost`]).
    pub coarse_lines: u32,
    /// See `coarse_lines`.
    pub filled_rays: u32,
    /// Modeled time the render took, milliseconds.
    pub render_ms: f64,
    /// Whether the frame was ready at its display time.
    pub deadline_met: bool,
    /// PSNR against a true render at this display time's camera (warped
    /// frames, when measured).
    pub warp_psnr: Option<f64>,
}

/// A flight: its frames and the report.
#[derive(Debug, Clone)]
pub struct Flight {
    /// Display frames, row-major colors of the display size.
    pub images: Vec<Vec<Rgb>>,
    /// One record per display frame.
    pub frames: Vec<DisplayFrame>,
    /// Cycles a render may take.
    pub budget: u64,
}

impl Flight {
    /// The report as JSON: `{"frames": [...], ...}`.
    pub fn report_json(&self, options: &FlyOptions) -> serde_json::Value {
        let warped: Vec<f64> = self.frames.iter().filter_map(|f| f.warp_psnr).collect();
        let finite: Vec<f64> = warped.iter().copied().filter(|p| p.is_finite()).collect();
        let mean = (!finite.is_empty()).then(|| finite.iter().sum::<f64>() / finite.len() as f64);
        let worst = warped.iter().copied().reduce(f64::min);
        serde_json::json!({
            "display_hz": options.display_hz,
            "render_hz": options.render_hz,
            "size": [options.size.0, options.size.1],
            "budget": self.budget,
            "deadlines_met": self.frames.iter().filter(|f| f.deadline_met).count(),
            "warp_psnr": { "mean": mean, "worst": worst.map(finite_or_null) },
            "frames": self.frames.iter().map(|f| serde_json::json!({
                "time": f.time,
                "kind": match f.kind { Kind::Rendered => "rendered", Kind::Warped => "warped" },
                "render": f.render,
                "cost": f.cost,
                "steps": f.steps,
                "budget": f.budget,
                "level_bias": f.level_bias,
                "coarse_lines": f.coarse_lines,
                "filled_rays": f.filled_rays,
                "render_ms": f.render_ms,
                "deadline_met": f.deadline_met,
                "warp_psnr": f.warp_psnr.map(finite_or_null),
            })).collect::<Vec<_>>(),
        })
    }
}

fn finite_or_null(v: f64) -> serde_json::Value {
    if v.is_finite() {
        serde_json::json!(v)
    } else {
        serde_json::Value::Null
    }
}

/// One render: its camera, frame and cost.
struct Render {
    camera: Camera,
    size: (u32, u32),
    time: f64,
    done: f64,
    colors: Vec<Rgb>,
    points: [terracast::ControlPoint; 9],
    cost: u64,
    steps: u64,
    level_bias: f64,
    coarse_lines: u32,
    filled_rays: u32,
    millis: f64,
}

/// One frame of `surface` within `governor`'s budget, through the
/// flight's atmosphere when it has one.
fn governed<T: Surface + ?Sized>(
    governor: &mut Governor,
    surface: &T,
    view: &View,
    options: &FlyOptions,
    frame: &mut Framebuffer,
    counts: &mut CountingProbe,
) -> FrameCost {
    match &options.atmosphere {
        Some(air) => governor.render(
            surface,
            view,
            &options.render,
            &mut air.sink(view, frame),
            counts,
        ),
        None => governor.render(surface, view, &options.render, frame, counts),
    }
}

/// Flies `path` over `scene` on `machine`; `progress` is called after each
/// display frame with its number.
pub fn fly(
    kernel: &KernelScene,
    path: &Path,
    machine: &Machine,
    options: &FlyOptions,
    mut progress: impl FnMut(u32),
) -> Result<Flight> {
    let rate_ok = |v: f64| v.is_finite() && v > 0.0 && v <= 1000.0;
    if !rate_ok(options.display_hz) || !rate_ok(options.render_hz) {
        return Err(Error::new(
            "display and render rates must be between 0 and 1000 Hz",
        ));
    }
    if options.render_hz > options.display_hz {
        return Err(Error::new("the render rate cannot exceed the display rate"));
    }
    let pyramid = kernel.pyramid_for(&options.render)?;
    let sticks = kernel.sticks()?;
    let details = kernel.details()?;
    let first = path.camera(0.0, options.hfov);
    let (_, render_size) = with_margin(&first, options.size, options.margin);
    // The budget: the rendering period's cycles on the workers, spent at
    // the machine's prices.
    let cycles_per_s = machine.worker_cycles(1.0);
    let period_cycles = cycles_per_s / options.render_hz;
    let prices = machine.compute_prices()?;
    let budget = period_cycles.floor().max(0.0) as u64;
    let mut governor = Governor::new(budget, prices);
    let first_view = View::new(
        &with_margin(&first, options.size, options.margin).0,
        render_size.0,
        render_size.1,
    )
    .map_err(|e| Error::new(format!("bad camera at the start of the path: {e}")))?;
    let rays = u64::from(render_size.0) * u64::from(render_size.1);
    let least = crate::sim::least_frame_cost(&governor, &first_view, &options.render);
    if budget < least {
        return Err(Error::new(format!(
            "the machine cannot render {}x{} (with margins) at {} Hz: {} processors at {} MHz give {:.0} cycles a pixel, and a frame needs at least {:.0}; use a smaller --size, a lower --render-hz or more --processors",
            render_size.0,
            render_size.1,
            options.render_hz,
            machine.processors,
            machine.clock_mhz,
            budget as f64 / rays as f64,
            least as f64 / rays as f64,
        )));
    }
    let period = 1.0 / options.render_hz;
    let slot = 1.0 / options.display_hz;
    let render = |governor: &mut Governor, time: f64, start: f64| -> Result<Render> {
        let display = path.camera(time, options.hfov);
        let (camera, size) = with_margin(&display, options.size, options.margin);
        let view = View::new(&camera, size.0, size.1)
            .map_err(|e| Error::new(format!("bad camera on the path at {time:.2} s: {e}")))?;
        let n = size.0 as usize * size.1 as usize;
        let (mut colors, mut distances) = (vec![[0u8; 3]; n], vec![Sample::SKY; n]);
        let mut frame = Framebuffer::with_distances(&mut colors, &mut distances, size.0, size.1)
            .map_err(|e| Error::new(e.to_string()))?;
        let mut counts = CountingProbe::default();
        let cost = match sticks {
            Some(layer) => governed(
                governor,
                &WithSticks::new(&pyramid, layer),
                &view,
                options,
                &mut frame,
                &mut counts,
            ),
            None if !details.is_empty() => governed(
                governor,
                &WithDetail::new(&pyramid, &details),
                &view,
                options,
                &mut frame,
                &mut counts,
            ),
            None => governed(governor, &pyramid, &view, options, &mut frame, &mut counts),
        };
        // The governor's prices are the machine's cycles.
        let seconds = cost.cost as f64 / cycles_per_s;
        let points = control_points(&camera, size, |x, y| {
            let i = y as usize * size.0 as usize + x as usize;
            let distance = *distances.get(i)?;
            Some(Sample {
                color: colors[i],
                distance,
                elevation: 0,
            })
        });
        Ok(Render {
            camera,
            size,
            time,
            done: start + seconds,
            colors,
            points,
            cost: cost.cost,
            steps: cost.work.steps,
            level_bias: cost.level_bias.to_num(),
            coarse_lines: cost.coarse_lines,
            filled_rays: cost.filled_rays,
            millis: seconds * 1e3,
        })
    };

    let mut renders = vec![render(&mut governor, 0.0, -period)?];
    let mut images = Vec::with_capacity(options.frames as usize);
    let mut frames = Vec::with_capacity(options.frames as usize);
    let display_pixels = options.size.0 as usize * options.size.1 as usize;
    for k in 0..options.frames {
        let time = f64::from(k) * slot;
        // Start every render whose turn has come by now: render j starts at
        // (j - 1)·T, for the first display time at or after j·T.
        while (renders.len() - 1) as f64 * period <= time {
            let j = renders.len() as f64;
            let target = (j * period / slot - 1e-9).ceil() * slot;
            let next = render(&mut governor, target, (j - 1.0) * period)?;
            renders.push(next);
        }
        let (index, source) = renders
            .iter()
            .enumerate()
            .rev()
            .find(|(_, r)| r.done <= time + 1e-12)
            .unwrap_or((0, &renders[0]));
        let display = path.camera(time, options.hfov);
        let kind = if (source.time - time).abs() < 1e-9 {
            Kind::Rendered
        } else {
            Kind::Warped
        };
        let mut image = vec![[0u8; 3]; display_pixels];
        let source_size = source.size;
        match Warp::fit(
            &source.camera,
            source_size,
            &display,
            options.size,
            &source.points,
        ) {
            Ok(warp) => warp.apply(&source.colors, source_size, &mut image, options.size),
            Err(_) => {
                // Too far to warp: the middle of the render, unwarped.
                let (ox, oy) = (
                    (source_size.0 - options.size.0) / 2,
                    (source_size.1 - options.size.1) / 2,
                );
                for (y, row) in image.chunks_exact_mut(options.size.0 as usize).enumerate() {
                    let from = (y + oy as usize) * source_size.0 as usize + ox as usize;
                    row.copy_from_slice(&source.colors[from..from + options.size.0 as usize]);
                }
            }
        }
        let warp_psnr = (kind == Kind::Warped && options.measure_warp)
            .then(|| {
                true_view(kernel, &display, options.size, options).map(|truth| psnr(&image, &truth))
            })
            .transpose()?;
        frames.push(DisplayFrame {
            time,
            kind,
            render: index,
            cost: source.cost,
            steps: source.steps,
            budget,
            level_bias: source.level_bias,
            coarse_lines: source.coarse_lines,
            filled_rays: source.filled_rays,
            render_ms: source.millis,
            deadline_met: source.done <= time + 1e-12,
            warp_psnr,
        });
        images.push(image);
        progress(k + 1);
    }
    Ok(Flight {
        images,
        frames,
        budget,
    })
}

/// The kernel's render of `camera` at `size`, no budget: what a warped
/// frame is measured against.
fn true_view(
    kernel: &KernelScene,
    camera: &Camera,
    size: (u32, u32),
    options: &FlyOptions,
) -> Result<Vec<Rgb>> {
    let (frame, _) = crate::kernel::render_kernel_in(
        kernel,
        camera,
        size,
        &options.render,
        crate::kernel::PixelRays::Fixed,
        options.atmosphere.as_ref(),
    )?;
    Ok(frame.colors)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scenic_path_looks_across_the_map_all_the_way() {
        let scene = crate::scene::procedural(256, 1);
        let path = Path::scenic(&scene);
        let side = 256.0f32;
        // The display's field (60°) widened by fly's default margin (1.2).
        let half_field = 36.0f32;
        for k in 0..=120 {
            let t = path.duration() * f64::from(k) / 120.0;
            let camera = path.camera(t, 60.0);
            for turn in [-half_field, 0.0, half_field] {
                let heading = (camera.yaw_deg + turn).to_radians();
                let reach = side * 0.3;
                let [x, y] = [
                    camera.eye[0] + reach * heading.cos(),
                    camera.eye[1] + reach * heading.sin(),
                ];
                assert!(
                    (0.0..=side).contains(&x) && (0.0..=side).contains(&y),
                    "at {t:.1} s the view at {turn}° leaves the map within 0.3 of its side"
                );
            }
        }
    }

    #[test]
    fn paths_interpolate_and_turn_the_short_way() {
        let path =
            Path::parse("# t x y z yaw pitch\n0 0 0 100 350 10\n2 20 0 100 10 30 # end\n").unwrap();
        let mid = path.camera(1.0, 60.0);
        assert_eq!(mid.eye, [10.0, 0.0, 100.0]);
        assert!((mid.yaw_deg - 0.0).abs() < 1e-4 || (mid.yaw_deg - 360.0).abs() < 1e-4);
        assert_eq!(mid.pitch_deg, 20.0);
        // Held at the ends.
        assert_eq!(path.camera(-1.0, 60.0).eye, [0.0, 0.0, 100.0]);
        assert_eq!(path.camera(5.0, 60.0).eye, [20.0, 0.0, 100.0]);
        assert!((path.duration() - 2.0).abs() < 1e-12);
        assert_eq!(mid.roll_deg, 0.0);
        // A seventh column banks, also the short way round.
        let banked = Path::parse("0 0 0 100 0 0 170\n2 0 0 100 0 0 -150").unwrap();
        assert_eq!(banked.camera(0.0, 60.0).roll_deg, 170.0);
        assert!((banked.camera(1.0, 60.0).roll_deg - (-170.0)).abs() < 1e-3);
        let bad_lines = ["0 1 2 3 4 5 6 7", "0 1 2 3 4 5 inf"];
        for bad in ["", "0 1 2 3 4", "0 1 2 3 4 x", "1 0 0 0 0 0\n0 0 0 0 0 0"]
            .into_iter()
            .chain(bad_lines)
        {
            assert!(Path::parse(bad).is_err(), "{bad:?}");
        }
    }

    /// The budget sets aside `MAX_COLOR_FETCHES_A_RAY` a ray: no ray may
    /// make more, whatever the setting, and a hit makes that many.
    #[test]
    fn no_ray_makes_more_color_fetches_than_the_budget_sets_aside() {
        use terracast::{Coherence, Resolution, Shading};
        let scene = crate::scene::procedural(128, 5);
        let kernel = scene.to_kernel().unwrap();
        let top = scene.max_height();
        let settings = [
            RenderOptions::default(),
            RenderOptions {
                resolution: Resolution::Single,
                ..RenderOptions::default()
            },
            RenderOptions {
                coherence: Coherence::Off,
                ..RenderOptions::default()
            },
            RenderOptions {
                shading: Shading::Nearest,
                ..RenderOptions::default()
            },
        ];
        let mut most = 0.0f64;
        for options in settings {
            let pyramid = kernel.pyramid_for(&options).unwrap();
            // Over the map, from outside, straight down, steep and low: sky,
            // terrain and map edges.
            for (eye, yaw, pitch) in [
                ([64.0, 10.0, top + 5.0], 90.0, 10.0),
                ([-30.0, 64.0, top + 20.0], 0.0, 20.0),
                ([64.0, 64.0, top + 40.0], 0.0, 90.0),
                ([20.0, 20.0, top + 10.0], 45.0, 35.0),
                ([64.0, 64.0, top + 2.0], 200.0, 0.0),
            ] {
                let camera = Camera::looking(eye, yaw, pitch);
                let view = View::new(&camera, 64, 48).unwrap();
                let mut colors = vec![[0u8; 3]; 64 * 48];
                let mut frame = Framebuffer::new(&mut colors, 64, 48).unwrap();
                let mut counts = CountingProbe::default();
                terracast::render(&pyramid, &view, &options, &mut frame, &mut counts);
                let per_ray = counts.color_fetches as f64 / counts.rays as f64;
                assert!(
                    counts.color_fetches
                        <= u64::from(terracast::MAX_COLOR_FETCHES_A_RAY) * counts.rays,
                    "{options:?} {eye:?}: {per_ray} a ray"
                );
                most = most.max(per_ray);
            }
        }
        // Straight down every ray hits: nearly two fetches a ray.
        assert!(most > 1.9, "the bound is not tight: {most}");
    }
}
