//! The interactive viewer's parts that need no window (`terracast-sim
//! view` opens the window, see `cli/view.rs`): how held keys move the
//! camera, the ground it stays above, frames rendered by the line pool on
//! the host's cores straight into window pixels, the wall-clock governor's
//! options, the on-screen line, the `render` command line that reproduces
//! a view, and the flown path in `fly`'s path format.

use crate::error::{Error, Result};
use crate::fly::Key;
use crate::kernel::PixelRays;
#[cfg(feature = "window")]
use embedded_graphics::mono_font::{ascii::FONT_6X10, MonoTextStyle};
#[cfg(feature = "window")]
use embedded_graphics::pixelcolor::Rgb888;
#[cfg(feature = "window")]
use embedded_graphics::prelude::*;
#[cfg(feature = "window")]
use embedded_graphics::primitives::{PrimitiveStyle, Rectangle};
#[cfg(feature = "window")]
use embedded_graphics::text::{Baseline, Text};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Instant;
use terracast::config::{MAX_EYE_HEIGHT, PITCH_RANGE_DEG};
use terracast::{
    render_line, render_line_by_footprint, AtmosphereFrame, Camera, Coherence, CountingProbe,
    FrameCost, Governor, Grid, HeightPath, LinePlane, LinePool, LineShade, LineShare,
    PreparedAtmosphere, Prices, Probe, RenderOptions, Resolution, Sample, Shading, Sink, SkyCell,
    Surface, View, Wait, U8F8,
};

/// How far above the ground the eye stays, voxels.
pub const GROUND_CLEARANCE: f32 = 2.0;
/// Degrees a second the arrow keys and Q/E turn, pitch and bank.
pub const TURN_DEG_PER_S: f32 = 60.0;
/// Degrees the view turns for a pixel of mouse drag.
pub const DRAG_DEG_PER_PIXEL: f32 = 0.2;

/// What the held keys ask for, each −1, 0 or 1: forward, right, up, and
/// turning right, looking down, banking right.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Motion {
    /// W (+1) and S (−1).
    pub forward: f32,
    /// D (+1) and A (−1).
    pub right: f32,
    /// R (+1) and F (−1).
    pub up: f32,
    /// → (+1) and ← (−1): heading.
    pub turn: f32,
    /// ↓ (+1, looks down) and ↑ (−1).
    pub pitch: f32,
    /// E (+1, right wing down) and Q (−1).
    pub bank: f32,
}

impl Motion {
    /// Whether any key moves the camera.
    pub fn is_still(&self) -> bool {
        *self == Self::default()
    }
}

/// Moves `camera` by `motion` for `seconds` at `speed` voxels a second:
/// forward and sideways along the ground (the heading's horizontal
/// directions, whatever the pitch), up and down along z; heading, pitch and
/// bank at [`TURN_DEG_PER_S`]. Then [`keep_in_range`].
pub fn fly_step(camera: &mut Camera, motion: &Motion, speed: f32, seconds: f32) {
    let yaw = camera.yaw_deg.to_radians();
    let (forward, right) = ([yaw.cos(), yaw.sin()], [-yaw.sin(), yaw.cos()]);
    let distance = speed * seconds;
    for axis in 0..2 {
        camera.eye[axis] +=
            distance * (motion.forward * forward[axis] + motion.right * right[axis]);
    }
    camera.eye[2] += distance * motion.up;
    let turn = TURN_DEG_PER_S * seconds;
    turn_by(
        camera,
        motion.turn * turn,
        motion.pitch * turn,
        motion.bank * turn,
    );
}

/// Turns `camera` by the given degrees of heading, pitch and bank, within
/// the kernel's ranges ([`keep_in_range`]).
pub fn turn_by(camera: &mut Camera, yaw: f32, pitch: f32, roll: f32) {
    camera.yaw_deg += yaw;
    camera.pitch_deg += pitch;
    camera.roll_deg += roll;
    keep_in_range(camera);
}

/// Heading in [0°, 360°), bank in [−180°, 180°) and pitch within the
/// kernel's range: the ranges `fly`'s paths come back in, so a recorded
/// camera replays as it was.
pub fn keep_in_range(camera: &mut Camera) {
    camera.yaw_deg = camera.yaw_deg.rem_euclid(360.0);
    camera.roll_deg = (camera.roll_deg + 180.0).rem_euclid(360.0) - 180.0;
    camera.pitch_deg = camera.pitch_deg.clamp(PITCH_RANGE_DEG.0, PITCH_RANGE_DEG.1);
}

/// The highest of the four level-0 heights around `(x, y)` (voxels, the
/// surface's own coordinates), or `None` off the surface.
pub fn ground_under<T: Surface + ?Sized>(surface: &T, x: f32, y: f32) -> Option<f32> {
    let extent = surface.extent();
    if !(x >= 0.0 && y >= 0.0) {
        return None;
    }
    let (x, y) = (x as u32, y as u32);
    if x >= extent.width || y >= extent.depth {
        return None;
    }
    let grid = surface.base();
    let stride = grid.stride();
    let corner = y as isize * stride + x as isize;
    let (right, below) = (
        isize::from(x + 1 < extent.width),
        if y + 1 < extent.depth { stride } else { 0 },
    );
    [0, right, below, below + right]
        .into_iter()
        .filter_map(|offset| grid.height(corner + offset))
        .max()
        .map(|h| f32::from(h) / 16.0)
}

/// Keeps the eye inside the map (`width` × `depth` voxels) and between
/// [`GROUND_CLEARANCE`] above `ground` and the kernel's highest eye.
pub fn keep_above(camera: &mut Camera, width: u32, depth: u32, ground: Option<f32>) {
    camera.eye[0] = camera.eye[0].clamp(0.0, width.saturating_sub(1) as f32);
    camera.eye[1] = camera.eye[1].clamp(0.0, depth.saturating_sub(1) as f32);
    let floor = ground.map_or(0.0, |g| g + GROUND_CLEARANCE);
    camera.eye[2] = camera.eye[2].clamp(floor, MAX_EYE_HEIGHT.max(floor));
}

/// The kernel settings the viewer toggles (the ones the chart compares),
/// and whether its governor is on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// The kernel's options; the governor replaces the pixel-to-voxel
    /// ratio of a multi-resolution render with its level bias.
    pub options: RenderOptions,
    /// One ray a pixel, or as many as its footprint needs.
    pub rays: PixelRays,
    /// What holds the frame time.
    pub governor: WindowGovernor,
    /// The resolution the resolution key switches to next (so that a
    /// pixel-to-voxel ratio given at the start comes back).
    other_resolution: Resolution,
}

impl Settings {
    /// The settings a window starts with.
    pub fn new(options: RenderOptions, rays: PixelRays, governor: WindowGovernor) -> Self {
        let other_resolution = match options.resolution {
            Resolution::Single => Resolution::Multi {
                pixel_to_voxel: U8F8::ONE,
            },
            Resolution::Multi { .. } => Resolution::Single,
        };
        Self {
            options,
            rays,
            governor,
            other_resolution,
        }
    }

    /// Subvoxel or nearest shading (from level-0 colors: to nearest).
    pub fn toggle_shading(&mut self) {
        self.options.shading = match self.options.shading {
            Shading::Subvoxel | Shading::LevelZero => Shading::Nearest,
            Shading::Nearest => Shading::Subvoxel,
        };
    }

    /// The pyramid's levels, or level 0 only.
    pub fn toggle_resolution(&mut self) {
        core::mem::swap(&mut self.options.resolution, &mut self.other_resolution);
    }

    /// One ray a pixel, or rays by footprint.
    pub fn toggle_rays(&mut self) {
        self.rays = match self.rays {
            PixelRays::Fixed => PixelRays::ByFootprint,
            PixelRays::ByFootprint | PixelRays::Governed(_) => PixelRays::Fixed,
        };
    }

    /// Across levels, exact, off, and round again.
    pub fn next_coherence(&mut self) {
        self.options.coherence = match self.options.coherence {
            Coherence::AcrossLevels => Coherence::Exact,
            Coherence::Exact => Coherence::Off,
            Coherence::Off => Coherence::AcrossLevels,
        };
    }

    /// The settings in a few words, for the on-screen line.
    pub fn describe(&self) -> String {
        let options = &self.options;
        let resolution = match options.resolution {
            Resolution::Single => "single".to_string(),
            Resolution::Multi { pixel_to_voxel } => format!("multi {pixel_to_voxel}"),
        };
        format!(
            "{} | {resolution} | {} | {}",
            match options.shading {
                Shading::Subvoxel => "subvoxel",
                Shading::Nearest => "nearest",
                Shading::LevelZero => "level-zero colors",
            },
            match self.rays {
                PixelRays::Fixed => "1 ray",
                PixelRays::ByFootprint => "rays by footprint",
                PixelRays::Governed(_) => "1 ray (a budget is a whole frame's)",
            },
            coherence_name(options.coherence),
        )
    }
}

/// What holds the window's frame time (`--governor`, the G key).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WindowGovernor {
    /// The size alone ([`ScaleGovernor`]): every frame as the settings
    /// say, rendered smaller when it would be late. The default: on the
    /// development machine it renders twice the pixels [`Self::Cost`] does
    /// at the same display rate and misses no more display frames
    /// (`docs/viewer.md`).
    #[value(alias = "on")]
    Size,
    /// The kernel's [`Governor`], one a worker, within a budget that stands
    /// for a share of the display frame ([`FrameBudget`]), with the size
    /// from the base pass ([`ScaleGovernor`]): the frame's cost holds, its
    /// quality adapts.
    Cost,
    /// Every frame at the window's size, as the settings say.
    Off,
}

impl WindowGovernor {
    /// The next one the G key switches to.
    pub fn next(self) -> Self {
        match self {
            Self::Size => Self::Cost,
            Self::Cost => Self::Off,
            Self::Off => Self::Size,
        }
    }

    /// Its `--governor` name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Cost => "cost",
            Self::Size => "size",
            Self::Off => "off",
        }
    }
}

/// Holds a window's frame time by the size its frames are rendered at:
/// when a render would be late the image is rendered smaller and enlarged
/// to the window, and when there is time it grows back to the window's
/// size. A render's time is nearly proportional to its pixels, so the
/// scale of each side moves by the square root of the time's ratio to the
/// target (three quarters of a display frame), by at most 2× a frame; a
/// frame under half the display frame grows the image by an eighth of its
/// pixels. Between the two the scale holds, so that it does not hunt.
///
/// (The pixel-to-voxel ratio is not the knob: a coarser ratio takes fewer
/// steps but no less time on the host, because more hits take the dearer
/// footprint colors; `docs/viewer.md` has the measurement.)
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaleGovernor {
    period: f64,
    scale: f32,
}

impl ScaleGovernor {
    /// The most a side is divided by.
    pub const MAX_SCALE: f32 = 4.0;

    /// A governor for display frames of `period` seconds, at full size.
    pub fn new(period: f64) -> Self {
        Self { period, scale: 1.0 }
    }

    /// A display frame, seconds.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// What each side of the window is divided by: 1 to
    /// [`ScaleGovernor::MAX_SCALE`].
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// The size to render a `window`-sized frame at.
    pub fn render_size(&self, window: (u32, u32)) -> (u32, u32) {
        let side = |n: u32| ((n as f32 / self.scale).round() as u32).clamp(1, n.max(1));
        (side(window.0), side(window.1))
    }

    /// Chooses the next frame's scale from this one's render time.
    pub fn adapt(&mut self, seconds: f64) {
        let target = 0.75 * self.period;
        if seconds > target {
            self.scale *= (seconds / target).min(4.0).sqrt() as f32;
        } else if seconds < 0.5 * self.period {
            self.scale *= (7.0f32 / 8.0).sqrt();
        }
        self.scale = self.scale.clamp(1.0, Self::MAX_SCALE);
    }
}

/// `--coherence`'s name for `coherence`.
fn coherence_name(coherence: Coherence) -> &'static str {
    match coherence {
        Coherence::Off => "off",
        Coherence::Exact => "exact",
        Coherence::AcrossLevels => "across-levels",
    }
}

/// A frame's pixels as the window takes them (`0x00RRGGBB`), written by
/// any number of workers at once.
#[derive(Debug)]
pub struct Pixels {
    width: u32,
    height: u32,
    words: Vec<AtomicU32>,
}

impl Pixels {
    /// A black frame.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            words: (0..width as usize * height as usize)
                .map(|_| AtomicU32::new(0))
                .collect(),
        }
    }

    /// Width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Copies the frame into `out` (row-major, `0x00RRGGBB`, `size`),
    /// enlarged to it by repeating pixels where it is larger.
    pub fn enlarge_to(&self, out: &mut [u32], size: (u32, u32)) {
        let (w, h) = (self.width as usize, self.height as usize);
        let (out_w, out_h) = (size.0 as usize, size.1 as usize);
        for (y, row) in out.chunks_mut(out_w.max(1)).take(out_h).enumerate() {
            let from = (y * h / out_h.max(1)).min(h.saturating_sub(1)) * w;
            for (x, word) in row.iter_mut().enumerate() {
                let at = from + (x * w / out_w.max(1)).min(w.saturating_sub(1));
                *word = self.words.get(at).map_or(0, |p| p.load(Ordering::Relaxed));
            }
        }
    }

    /// Row-major RGB.
    pub fn rgb(&self) -> Vec<u8> {
        self.words
            .iter()
            .flat_map(|w| {
                let w = w.load(Ordering::Relaxed);
                [(w >> 16) as u8, (w >> 8) as u8, w as u8]
            })
            .collect()
    }
}

/// A worker's sink into [`Pixels`], with the atmosphere over each pixel
/// where there is one, as [`terracast::AtmosphereSink`] gives it (a line
/// caster's hits by their ray's slope in the line's plane).
struct PixelSink<'a> {
    pixels: &'a Pixels,
    atmosphere: Option<(&'a PreparedAtmosphere, AtmosphereFrame)>,
    /// The shade of the line being cast ([`Sink::line`]).
    line: LineShade,
    /// The last sky pixel's cell of the frame's grid.
    sky: SkyCell,
}

impl<'a> PixelSink<'a> {
    /// A sink into `pixels` for one frame of `view`, under `atmosphere`.
    fn new(pixels: &'a Pixels, atmosphere: Option<&'a PreparedAtmosphere>, view: &View) -> Self {
        Self {
            pixels,
            atmosphere: atmosphere.map(|air| (air, air.frame(view))),
            line: LineShade::default(),
            sky: SkyCell::default(),
        }
    }

    #[inline]
    fn store(&self, x: u32, y: u32, color: terracast::Rgb) {
        let [r, g, b] = color.map(u32::from);
        if let Some(word) = self
            .pixels
            .words
            .get(y as usize * self.pixels.width as usize + x as usize)
        {
            word.store(r << 16 | g << 8 | b, Ordering::Relaxed);
        }
    }
}

impl Sink for PixelSink<'_> {
    #[inline]
    fn put(&mut self, x: u32, y: u32, sample: Sample) {
        let color = match &self.atmosphere {
            Some((air, frame)) => air.pixel_color(frame, &mut self.sky, x, y, &sample),
            None => sample.color,
        };
        self.store(x, y, color);
    }

    #[inline]
    fn line(&mut self, plane: &LinePlane) {
        self.line = LineShade::new(plane);
    }

    #[inline]
    fn put_ray(&mut self, x: u32, y: u32, sample: Sample, slope: i32) {
        let color = match &self.atmosphere {
            Some((air, frame)) => air.ray_color(frame, &self.line, (x, y), &sample, slope),
            None => sample.color,
        };
        self.store(x, y, color);
    }
}

/// Renders `view` into `pixels` (its size) with `threads` workers taking
/// lines from one [`LinePool`], with `atmosphere` over it where given;
/// returns the frame's steps (walk steps and bound tests). The image is
/// [`terracast::render`]'s (or [`terracast::render_by_footprint`]'s), bit
/// for bit.
pub fn render_pool<T: Surface + Sync + ?Sized>(
    surface: &T,
    view: &View,
    (options, atmosphere): (&RenderOptions, Option<&PreparedAtmosphere>),
    rays: PixelRays,
    threads: usize,
    pixels: &Pixels,
) -> u64 {
    let pool = LinePool::new(view.lines(), 1);
    pool.publish(0);
    let worker = || {
        let mut probe = CountingProbe::default();
        let mut sink = PixelSink::new(pixels, atmosphere, view);
        loop {
            match pool.take() {
                Ok(task) => render_one(
                    surface, view, options, rays, task.line, &mut sink, &mut probe,
                ),
                Err(Wait::NotPublished { .. }) => std::thread::yield_now(),
                Err(Wait::Finished) => break,
            }
        }
        probe.steps + probe.bound_tests
    };
    std::thread::scope(|scope| {
        let others: Vec<_> = (1..threads.max(1)).map(|_| scope.spawn(worker)).collect();
        let mine = worker();
        mine + others
            .into_iter()
            .map(|w| w.join().unwrap_or(0))
            .sum::<u64>()
    })
}

/// Renders `view` into `pixels` (its size) within a budget: one worker a
/// governor of `governors`, each rendering its [`LineShare`] of the lines
/// (every `governors.len()`th) within its own budget, with `atmosphere`
/// over it where given. Returns the frame's steps and what each share
/// cost and took. The image depends on the governors (their budgets,
/// prices and biases), never on how the workers' turns fall.
pub fn render_governed<T: Surface + Sync + ?Sized>(
    surface: &T,
    view: &View,
    (options, atmosphere): (&RenderOptions, Option<&PreparedAtmosphere>),
    governors: &mut [Governor],
    pixels: &Pixels,
) -> (u64, Vec<GovernedShare>) {
    let count = governors.len() as u32;
    let worker = |(index, governor): (u32, &mut Governor)| {
        let began = Instant::now();
        let mut sink = PixelSink::new(pixels, atmosphere, view);
        let share = LineShare::new(view, index, count)?;
        let mut probe = ShareProbe {
            steps: 0,
            lines: 0,
            base_lines: share.line_count(view),
            began,
            base_seconds: None,
        };
        let cost = governor.render_share(surface, view, options, &share, &mut sink, &mut probe);
        let seconds = began.elapsed().as_secs_f64();
        Some((
            probe.steps,
            GovernedShare {
                cost,
                seconds,
                base_seconds: probe.base_seconds.unwrap_or(seconds),
            },
        ))
    };
    let results: Vec<_> = std::thread::scope(|scope| {
        let mut shares = (0..count).zip(governors.iter_mut());
        let mine = shares.next();
        let others: Vec<_> = shares
            .map(|share| scope.spawn(move || worker(share)))
            .collect();
        let mut results = vec![mine.and_then(worker)];
        results.extend(others.into_iter().map(|w| w.join().ok().flatten()));
        results
    });
    let steps = results.iter().flatten().map(|(steps, _)| steps).sum();
    (
        steps,
        results
            .into_iter()
            .flatten()
            .map(|(_, share)| share)
            .collect(),
    )
}

/// What one share of a governed frame cost, and how long it and its base
/// pass took.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GovernedShare {
    /// The governor's account of the share.
    pub cost: FrameCost,
    /// Seconds the share took.
    pub seconds: f64,
    /// Of them, its base pass's.
    pub base_seconds: f64,
}

/// Counts a governed share's steps and times its base pass: the base pass
/// reports each of the share's lines once, then the refinement starts
/// with the next line report.
struct ShareProbe {
    steps: u64,
    lines: u32,
    base_lines: u32,
    began: Instant,
    base_seconds: Option<f64>,
}

impl Probe for ShareProbe {
    #[inline(always)]
    fn visit(&mut self, _: u8, _: usize) {
        self.steps += 1;
    }
    #[inline(always)]
    fn bound(&mut self, _: u8, _: usize) {
        self.steps += 1;
    }
    fn line(&mut self, _: u32) {
        self.lines += 1;
        if self.lines == self.base_lines + 1 {
            self.base_seconds = Some(self.began.elapsed().as_secs_f64());
        }
    }
}

/// The window's frame budget: a display frame's time turned into the
/// kernel's cost by the seconds a unit of cost has taken in the frames so
/// far, shared among the workers' governors. Each governor spends its
/// share, so a frame's time holds while its quality (level bias, refined
/// lines) adapts to the view.
///
/// The prices are the board's ([`Governor::on_board`]), the base pass's
/// scaled by what it takes on this host against the refinement (timed
/// apart in every frame): the board's line caster costs a larger part of
/// the per-ray path than the host's does.
///
/// On the host a coarser level saves little time (a frame's cost is
/// mostly its rays' set-up and shading), and a finer one buys less than
/// more pixels do, so the governors' bias stays within
/// [`FrameBudget::BIAS_RANGE`] and the window's [`ScaleGovernor`] renders
/// fewer pixels when the base pass takes more than
/// [`FrameBudget::BASE_SHARE_MOST`] of the budget, and more when it takes
/// under two thirds of that ([`FrameBudget::seconds_for_size`]): more
/// pixels first, then more rays.
#[derive(Debug, Clone)]
pub struct FrameBudget {
    period: f64,
    governors: Vec<Governor>,
    /// Seconds a unit of a share's cost took, smoothed over the frames.
    seconds_per_unit: Option<f64>,
    /// The base pass's prices against the board's.
    base_scale: f64,
}

impl FrameBudget {
    /// The share of a display frame a render is given: the rest is margin
    /// for the host's other work (the window's own drawing, a page of
    /// tiles, the display server on the same cores).
    pub const SHARE_OF_PERIOD: f64 = 0.6;
    /// The most of the budget a base pass may take before the size
    /// shrinks; under two thirds of it the size grows.
    pub const BASE_SHARE_MOST: f64 = 0.9;
    /// A first frame's budget a pixel, before any frame has been timed.
    pub const FIRST_PER_PIXEL: u64 = 1000;
    /// The level biases the governors take: from a voxel a pixel wide to
    /// one two pixels wide.
    pub const BIAS_RANGE: (U8F8, U8F8) = (U8F8::ONE, U8F8::from_bits(2 << 8));

    /// A budget for display frames of `period` seconds, rendered by
    /// `workers` governors.
    pub fn new(period: f64, workers: usize) -> Self {
        Self {
            period,
            governors: vec![
                Governor::on_board(0)
                    .with_bias_range(Self::BIAS_RANGE.0, Self::BIAS_RANGE.1);
                workers.max(1)
            ],
            seconds_per_unit: None,
            base_scale: 1.0,
        }
    }

    /// The governors, each with its share of the next frame's budget
    /// (`pixels` a frame) and the prices learnt so far: to hand to
    /// [`render_governed`].
    pub fn governors(&mut self, pixels: u64) -> &mut [Governor] {
        let workers = self.governors.len() as u64;
        let share = match self.seconds_per_unit {
            Some(rate) => (Self::SHARE_OF_PERIOD * self.period / rate).round() as u64,
            None => Self::FIRST_PER_PIXEL * pixels / workers,
        };
        let base_prices = self.base_prices();
        for governor in &mut self.governors {
            *governor = governor.with_budget(share).with_base_prices(base_prices);
        }
        &mut self.governors
    }

    /// The base pass's prices: the board's, scaled.
    pub fn base_prices(&self) -> Prices {
        let scale = |price: u32| (f64::from(price) * self.base_scale).round() as u32;
        let board = Prices::BOARD_LINES;
        Prices {
            per_pixel: scale(board.per_pixel),
            per_straight_pixel: scale(board.per_straight_pixel),
            per_line: scale(board.per_line),
            per_ray: scale(board.per_ray),
            per_step: scale(board.per_step),
            per_color: scale(board.per_color),
            per_color_square: scale(board.per_color_square),
            per_hit: scale(board.per_hit),
            per_hit_level: scale(board.per_hit_level),
        }
    }

    /// Learns from a frame that took `seconds` in `shares`: the workers run
    /// at once, so the dearest share sets the time; the base passes' and
    /// the refinements' seconds a unit set the base pass's prices.
    pub fn adapt(&mut self, seconds: f64, shares: &[GovernedShare]) {
        let dearest = shares.iter().map(|s| s.cost.cost).max().unwrap_or(0);
        if dearest == 0 || seconds <= 0.0 {
            return;
        }
        // Halfway to the new frame's figures: one slow frame (a page of
        // tiles, another process) does not halve the next one's budget,
        // and the budget does not swing from frame to frame.
        let halfway = |old: f64, new: f64| 0.5 * (old + new);
        let rate = seconds / dearest as f64;
        self.seconds_per_unit = Some(self.seconds_per_unit.map_or(rate, |r| halfway(r, rate)));
        let sum = |f: &dyn Fn(&GovernedShare) -> f64| shares.iter().map(f).sum::<f64>();
        let (base_seconds, base_cost) =
            (sum(&|s| s.base_seconds), sum(&|s| s.cost.base_cost as f64));
        let refined_seconds = sum(&|s| s.seconds - s.base_seconds);
        let refined_cost = sum(&|s| (s.cost.cost - s.cost.base_cost) as f64);
        // Only a refinement of some size tells its rate.
        if refined_cost > 0.1 * sum(&|s| s.cost.cost as f64)
            && refined_seconds > 0.0
            && base_cost > 0.0
        {
            let ratio = (base_seconds / base_cost) / (refined_seconds / refined_cost);
            self.base_scale =
                halfway(self.base_scale, self.base_scale * ratio).clamp(1.0 / 16.0, 4.0);
        }
    }

    /// What the window's [`ScaleGovernor`] is to hold after a frame that
    /// took `seconds` in `shares`, as if it were a render time (which it
    /// holds between a half and three quarters of a display frame): the
    /// slowest base pass (every line once, one ray a pixel) against the
    /// time the budget stands for, scaled so that the size shrinks when
    /// the base pass takes over [`FrameBudget::BASE_SHARE_MOST`] of it and
    /// grows when it takes under two thirds of that; at least a display
    /// frame when a share went coarse or repeated rays (its base pass did
    /// not fit), and the frame's own time when it was late.
    pub fn seconds_for_size(&self, seconds: f64, shares: &[GovernedShare]) -> f64 {
        let slowest = shares.iter().map(|s| s.base_seconds).fold(0.0, f64::max);
        let base_share = slowest / (Self::SHARE_OF_PERIOD * self.period);
        let mut held = self.period * 0.75 * base_share / Self::BASE_SHARE_MOST;
        if shares
            .iter()
            .any(|s| s.cost.coarse_lines > 0 || s.cost.filled_rays > 0)
        {
            held = held.max(self.period);
        }
        if seconds > self.period {
            held = held.max(seconds);
        }
        held
    }
}

fn render_one<T: Surface + ?Sized, S: Sink, P: Probe>(
    surface: &T,
    view: &View,
    options: &RenderOptions,
    rays: PixelRays,
    line: u32,
    sink: &mut S,
    probe: &mut P,
) {
    match rays {
        // A budget is spent over a whole frame, not line by line: the
        // window holds its time by the size it renders at instead.
        PixelRays::Fixed | PixelRays::Governed(_) => {
            render_line(surface, view, options, line, sink, probe)
        }
        PixelRays::ByFootprint => {
            render_line_by_footprint(surface, view, options, line, sink, probe)
        }
    }
}

/// Draws `text` on a dark band across the top of `frame` (row-major
/// `0x00RRGGBB`, `width` wide).
#[cfg(feature = "window")]
pub fn draw_line_of_text(frame: &mut [u32], width: u32, text: &str) {
    let height = (frame.len() / width.max(1) as usize) as u32;
    let mut target = Framebuffer32 {
        words: frame,
        width,
        height,
    };
    let band = Rectangle::new(Point::zero(), Size::new(width, OVERLAY_ROWS));
    // Drawing into a framebuffer cannot fail (pixels outside are skipped).
    let _ = band
        .into_styled(PrimitiveStyle::with_fill(Rgb888::new(0, 0, 0)))
        .draw(&mut target);
    let style = MonoTextStyle::new(&FONT_6X10, Rgb888::new(255, 255, 160));
    let _ = Text::with_baseline(text, Point::new(3, 1), style, Baseline::Top).draw(&mut target);
}

/// Rows the on-screen line covers.
#[cfg(feature = "window")]
pub const OVERLAY_ROWS: u32 = 12;

/// Window pixels as an embedded-graphics target.
#[cfg(feature = "window")]
struct Framebuffer32<'a> {
    words: &'a mut [u32],
    width: u32,
    height: u32,
}

#[cfg(feature = "window")]
impl OriginDimensions for Framebuffer32<'_> {
    fn size(&self) -> Size {
        Size::new(self.width, self.height)
    }
}

#[cfg(feature = "window")]
impl DrawTarget for Framebuffer32<'_> {
    type Color = Rgb888;
    type Error = core::convert::Infallible;

    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb888>>>(
        &mut self,
        pixels: I,
    ) -> core::result::Result<(), Self::Error> {
        for Pixel(at, color) in pixels {
            let (Ok(x), Ok(y)) = (u32::try_from(at.x), u32::try_from(at.y)) else {
                continue;
            };
            if x < self.width && y < self.height {
                self.words[(y * self.width + x) as usize] =
                    u32::from(color.r()) << 16 | u32::from(color.g()) << 8 | u32::from(color.b());
            }
        }
        Ok(())
    }
}

/// Quotes `word` for a POSIX shell when it needs it.
pub fn shell_word(word: &str) -> String {
    let plain = !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./:,=+@%".contains(c));
    if plain {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

/// The `terracast-sim render` arguments (after `render`) that draw
/// `camera` at `size` with `options` and `rays` on the terrain that
/// `terrain` names (its flags, as the viewer was given them): the view the
/// window showed, bit for bit.
pub fn render_arguments(
    terrain: &[String],
    camera: &Camera,
    size: (u32, u32),
    options: &RenderOptions,
    rays: PixelRays,
    out: &str,
) -> Vec<String> {
    let mut args: Vec<String> = terrain.to_vec();
    let [x, y, z] = camera.eye;
    args.extend([
        format!("--eye={x},{y},{z}"),
        format!("--yaw={}", camera.yaw_deg),
        format!("--pitch={}", camera.pitch_deg),
        format!("--roll={}", camera.roll_deg),
        format!("--hfov={}", camera.hfov_deg),
        format!("--size={}x{}", size.0, size.1),
    ]);
    let [r, g, b] = options.sky;
    args.push(format!("--sky={r},{g},{b}"));
    args.push(format!("--coherence={}", coherence_name(options.coherence)));
    match options.resolution {
        Resolution::Single => args.push("--resolution=single".into()),
        Resolution::Multi { pixel_to_voxel } => {
            args.push("--resolution=multi".into());
            // U8.8: its decimal expansion is exact within 8 digits.
            args.push(format!(
                "--pixel-to-voxel={}",
                f64::from(pixel_to_voxel.to_bits()) / 256.0
            ));
        }
    }
    args.push(format!(
        "--terrain-fit={}",
        if options.terrain_fit { "on" } else { "off" }
    ));
    args.push(format!(
        "--first-hit={}",
        if options.hierarchical_first_hit {
            "hierarchical"
        } else {
            "walk"
        }
    ));
    args.push(format!(
        "--vertical-samples={}",
        match rays {
            PixelRays::ByFootprint => "footprint".to_string(),
            PixelRays::Fixed => options.vertical_samples.count().to_string(),
            PixelRays::Governed(_) => "1".to_string(),
        }
    ));
    if let PixelRays::Governed(per_pixel) = rays {
        args.push(format!("--budget={per_pixel}"));
    }
    args.push(format!(
        "--shading={}",
        match options.shading {
            Shading::Subvoxel => "subvoxel",
            Shading::Nearest => "nearest",
            Shading::LevelZero => "level-zero",
        }
    ));
    args.push(format!(
        "--height-path={}",
        match options.height_path {
            HeightPath::Line => "line",
            HeightPath::Ray => "ray",
        }
    ));
    args.push(format!("--out={out}"));
    args
}

/// The flown path, as `fly` reads it: a keyframe whenever the camera
/// changed (and the last camera before it moved again, so a pause stays a
/// pause when replayed).
#[derive(Debug, Default)]
pub struct Recorder {
    keys: Vec<Key>,
    /// The camera last seen, and when, if it is not a keyframe yet.
    held: Option<Key>,
}

impl Recorder {
    /// Notes the camera at `seconds` from the start (increasing).
    pub fn note(&mut self, seconds: f64, camera: &Camera) {
        let key = Key {
            time: seconds,
            eye: camera.eye,
            yaw: camera.yaw_deg,
            pitch: camera.pitch_deg,
            roll: camera.roll_deg,
        };
        if self.keys.last().is_some_and(|last| seconds <= last.time) {
            return;
        }
        let same = |a: &Key, b: &Key| {
            a.eye == b.eye && a.yaw == b.yaw && a.pitch == b.pitch && a.roll == b.roll
        };
        match self.keys.last() {
            Some(last) if same(last, &key) => self.held = Some(key),
            _ => {
                if let Some(held) = self.held.take() {
                    self.keys.push(held);
                }
                self.keys.push(key);
            }
        }
    }

    /// The keyframes so far, with the camera held last.
    pub fn keys(&self) -> Vec<Key> {
        self.keys.iter().chain(&self.held).copied().collect()
    }

    /// The path file's text: `t x y z yaw pitch roll` a line, each value
    /// written so that it reads back to the same number.
    pub fn path_text(&self) -> String {
        let mut text = String::from("# t x y z yaw pitch roll, recorded by terracast-sim view\n");
        for key in self.keys() {
            let [x, y, z] = key.eye.map(f64::from);
            text.push_str(&format!(
                "{} {x} {y} {z} {} {} {}\n",
                key.time,
                f64::from(key.yaw),
                f64::from(key.pitch),
                f64::from(key.roll)
            ));
        }
        text
    }
}

/// A frame's figures for the on-screen line.
#[derive(Debug, Clone, Copy)]
pub struct FrameFigures {
    /// Seconds the render took.
    pub seconds: f64,
    /// Pixels rendered.
    pub pixels: u64,
    /// Steps taken.
    pub steps: u64,
    /// How the governors spent the frame's budget, when they rendered it.
    pub governed: Option<Governed>,
}

/// What a frame's governors did, over their shares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Governed {
    /// The frame's budget a pixel, in the board's instructions.
    pub budget_per_pixel: f64,
    /// What the frame cost a pixel, at the same prices.
    pub cost_per_pixel: f64,
    /// The level biases the shares were rendered at, least and most.
    pub bias: (f32, f32),
    /// Lines rendered again with more rays, over all shares.
    pub refined_lines: u32,
}

impl Governed {
    /// The figures of `shares` for a frame of `pixels`.
    pub fn of(shares: &[GovernedShare], pixels: u64) -> Self {
        let costs = || shares.iter().map(|s| &s.cost);
        let pixels = pixels.max(1) as f64;
        let biases = costs().map(|c| c.level_bias.to_num::<f32>());
        Self {
            budget_per_pixel: costs().map(|c| c.budget).sum::<u64>() as f64 / pixels,
            cost_per_pixel: costs().map(|c| c.cost).sum::<u64>() as f64 / pixels,
            bias: (
                biases.clone().fold(f32::INFINITY, f32::min),
                biases.fold(0.0, f32::max),
            ),
            refined_lines: costs().map(|c| c.refined_lines).sum(),
        }
    }
}

impl FrameFigures {
    /// "12.3 ms  40.1 Mpx/s  2.31 steps/px", and for a governed frame
    /// "  budget 2400/px  bias 0.50  310 lines refined".
    pub fn describe(&self) -> String {
        let pixels = self.pixels.max(1) as f64;
        let mut text = format!(
            "{:.1} ms  {:.1} Mpx/s  {:.2} steps/px",
            self.seconds * 1e3,
            pixels / self.seconds.max(1e-9) / 1e6,
            self.steps as f64 / pixels
        );
        if let Some(g) = &self.governed {
            text += &format!(
                "  budget {:.0}/px  bias {:.2}  {} lines refined",
                g.budget_per_pixel, g.bias.1, g.refined_lines
            );
        }
        text
    }
}

/// The camera in a few words, for the on-screen line.
pub fn describe_camera(camera: &Camera) -> String {
    let [x, y, z] = camera.eye;
    format!(
        "eye {x:.0},{y:.0},{z:.0} yaw {:.0} pitch {:.0} roll {:.0}",
        camera.yaw_deg, camera.pitch_deg, camera.roll_deg
    )
}

/// `--threads`: 1 or more, or the host's cores when not given.
pub fn threads_or_cores(threads: Option<usize>) -> Result<usize> {
    match threads {
        Some(0) => Err(Error::new("--threads must be at least 1")),
        Some(n) => Ok(n),
        None => Ok(std::thread::available_parallelism().map_or(1, |n| n.get())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fly::Path;
    use terracast::{FrameWork, Framebuffer, NoProbe, Prices};

    #[test]
    fn the_pool_renders_into_window_pixels_what_render_does() {
        let scene = crate::scene::procedural(128, 3).to_kernel().unwrap();
        let pyramid = scene.pyramid().unwrap();
        let view = View::new(
            &Camera {
                roll_deg: 20.0,
                ..Camera::looking([64.0, 5.0, 110.0], 90.0, 15.0)
            },
            80,
            50,
        )
        .unwrap();
        let options = RenderOptions::default();
        for rays in [PixelRays::Fixed, PixelRays::ByFootprint] {
            let mut colors = vec![[0u8; 3]; 80 * 50];
            let mut frame = Framebuffer::new(&mut colors, 80, 50).unwrap();
            rays.render(&pyramid, &view, &options, &mut frame, &mut NoProbe);
            for threads in [1, 3] {
                let pixels = Pixels::new(80, 50);
                let steps = render_pool(&pyramid, &view, (&options, None), rays, threads, &pixels);
                assert!(steps > 0);
                assert_eq!(pixels.rgb(), colors.concat(), "{rays:?}, {threads} threads");
            }
        }
    }

    #[test]
    fn governed_shares_draw_the_governors_frame_each_within_its_budget() {
        let scene = crate::scene::procedural(128, 3).to_kernel().unwrap();
        let pyramid = scene.pyramid().unwrap();
        let view = View::new(&Camera::looking([64.0, 5.0, 110.0], 90.0, 25.0), 80, 50).unwrap();
        let options = RenderOptions::default();
        // Without a limit every line ends refined twice, whoever renders
        // it: the shares draw one governor's frame.
        let mut colors = vec![[0u8; 3]; 80 * 50];
        let mut frame = Framebuffer::new(&mut colors, 80, 50).unwrap();
        Governor::new(u64::MAX / 8, Prices::BOARD).render(
            &pyramid,
            &view,
            &options,
            &mut frame,
            &mut NoProbe,
        );
        let pixels = Pixels::new(80, 50);
        let mut unlimited = [Governor::new(u64::MAX / 8, Prices::BOARD); 3];
        render_governed(&pyramid, &view, (&options, None), &mut unlimited, &pixels);
        assert_eq!(pixels.rgb(), colors.concat());
        // Within a budget: each share keeps its own, and the same governors
        // draw the same frame again.
        let mut images = Vec::new();
        for _ in 0..2 {
            let mut budget = FrameBudget::new(1.0 / 60.0, 3);
            let governors = budget.governors(80 * 50);
            assert_eq!(
                governors[0].budget(),
                FrameBudget::FIRST_PER_PIXEL * 80 * 50 / 3
            );
            let pixels = Pixels::new(80, 50);
            let (steps, costs) =
                render_governed(&pyramid, &view, (&options, None), governors, &pixels);
            assert!(steps > 0 && costs.len() == 3);
            assert!(
                costs
                    .iter()
                    .all(|s| s.cost.cost <= s.cost.budget && s.base_seconds <= s.seconds),
                "{costs:?}"
            );
            images.push(pixels.rgb());
        }
        assert_eq!(images[0], images[1]);
    }

    #[test]
    fn the_frame_budget_follows_the_time_a_unit_of_cost_takes() {
        let mut budget = FrameBudget::new(0.016, 2);
        let share = |cost: u64, base_cost: u64, seconds: f64, base_seconds: f64| GovernedShare {
            cost: FrameCost {
                cost,
                work: FrameWork::default(),
                budget: cost,
                base_cost,
                base_work: FrameWork::default(),
                level_bias: U8F8::ONE,
                coarse_lines: 0,
                refined_lines: 0,
                filled_rays: 0,
            },
            seconds,
            base_seconds,
        };
        // A frame of 0.008 s whose dearer share cost 1 000 000: 8 ns a
        // unit, and the next share is its share of the period at it.
        // Its base pass took a unit a third of the refinement's time: the
        // base prices go a half of the way there.
        budget.adapt(
            0.008,
            &[
                share(1_000_000, 500_000, 0.008, 0.002),
                share(800_000, 400_000, 0.0064, 0.0016),
            ],
        );
        let at = |seconds_a_unit: f64| {
            (FrameBudget::SHARE_OF_PERIOD * 0.016 / seconds_a_unit).round() as u64
        };
        assert_eq!(budget.governors(1000)[0].budget(), at(8e-9));
        // The board's base prices at two thirds.
        let two_thirds = (f64::from(Prices::BOARD_LINES.per_ray) * 2.0 / 3.0).round() as u32;
        assert_eq!(budget.base_prices().per_ray, two_thirds);
        assert_eq!(
            budget.governors(1000)[1].base_prices(),
            budget.base_prices()
        );
        // A slower frame moves the rate halfway: 12 ns a unit. A frame
        // with too little refinement to time leaves the prices alone.
        budget.adapt(0.016, &[share(1_000_000, 950_000, 0.016, 0.015)]);
        assert_eq!(budget.governors(1000)[0].budget(), at(12e-9));
        assert_eq!(budget.base_prices().per_ray, two_thirds);
        // The size follows the slowest base pass against the time the
        // budget stands for: at the most it may take of it, three quarters
        // of a display frame; a share that went coarse, or a late frame,
        // shrinks it.
        let most = FrameBudget::BASE_SHARE_MOST * FrameBudget::SHARE_OF_PERIOD * 0.016;
        let shares = [share(10, 5, 0.012, 0.003), share(10, 5, 0.012, most)];
        assert!((budget.seconds_for_size(0.012, &shares) - 0.012).abs() < 1e-12);
        let mut coarse = share(10, 5, 0.012, 0.003);
        coarse.cost.coarse_lines = 3;
        assert_eq!(budget.seconds_for_size(0.012, &[coarse]), 0.016);
        assert_eq!(budget.seconds_for_size(0.020, &shares), 0.020);
        // A frame with no cost to learn from changes nothing.
        budget.adapt(0.016, &[]);
        assert_eq!(budget.governors(1000)[0].budget(), at(12e-9));
    }

    #[test]
    fn keys_move_along_the_heading_and_turn_within_the_kernels_ranges() {
        let mut camera = Camera::looking([100.0, 100.0, 50.0], 90.0, 10.0);
        let forward = Motion {
            forward: 1.0,
            ..Motion::default()
        };
        fly_step(&mut camera, &forward, 10.0, 0.5);
        assert!((camera.eye[0] - 100.0).abs() < 1e-4 && (camera.eye[1] - 105.0).abs() < 1e-4);
        // Right of a heading of 90° (toward +y) is −x, as the view
        // contract's right vector says.
        let right = Motion {
            right: 1.0,
            ..Motion::default()
        };
        fly_step(&mut camera, &right, 10.0, 1.0);
        assert!((camera.eye[0] - 90.0).abs() < 1e-4);
        turn_by(&mut camera, 300.0, -200.0, 190.0);
        assert_eq!(camera.yaw_deg, 30.0);
        assert_eq!(camera.pitch_deg, PITCH_RANGE_DEG.0);
        assert_eq!(camera.roll_deg, -170.0);
        assert!(View::new(&camera, 64, 48).is_ok());
    }

    #[test]
    fn the_eye_stays_above_the_ground_and_on_the_map() {
        let scene = crate::scene::procedural(64, 2).to_kernel().unwrap();
        let pyramid = scene.pyramid().unwrap();
        let ground = ground_under(&pyramid, 10.5, 20.5).unwrap();
        let highest = (10..=11)
            .flat_map(|x| (20..=21).map(move |y| (x, y)))
            .map(|(x, y)| f32::from(pyramid.base().height(y * 64 + x).unwrap()) / 16.0)
            .fold(0.0, f32::max);
        assert_eq!(ground, highest);
        let mut camera = Camera::looking([10.5, 20.5, -30.0], 0.0, 0.0);
        keep_above(&mut camera, 64, 64, Some(ground));
        assert_eq!(camera.eye[2], ground + GROUND_CLEARANCE);
        camera.eye = [-5.0, 99.0, 1e9];
        keep_above(&mut camera, 64, 64, ground_under(&pyramid, -5.0, 99.0));
        assert_eq!(camera.eye, [0.0, 63.0, MAX_EYE_HEIGHT]);
        assert!(ground_under(&pyramid, 63.9, 63.9).is_some());
        assert_eq!(ground_under(&pyramid, 64.0, 0.0), None);
    }

    #[test]
    fn a_recorded_flight_replays_with_the_same_camera_at_every_keyframe() {
        let mut recorder = Recorder::default();
        let mut camera = Camera::looking([100.1, 200.2, 51.7], 359.9, -3.3);
        let mut t = 0.0;
        let mut expected = Vec::new();
        for step in 0..40 {
            t += 1.0 / 61.0;
            let motion = Motion {
                forward: if step < 20 { 1.0 } else { 0.0 },
                turn: if step % 3 == 0 { -1.0 } else { 0.0 },
                bank: if step < 30 { 1.0 } else { 0.0 },
                ..Motion::default()
            };
            if step >= 35 {
                // Still: the last camera is held, not repeated.
            } else {
                fly_step(&mut camera, &motion, 37.3, 1.0 / 61.0);
            }
            recorder.note(t, &camera);
            expected.push((t, camera));
        }
        let path = Path::parse(&recorder.path_text()).unwrap();
        let keys = recorder.keys();
        assert!(keys.len() < expected.len());
        for (t, camera) in expected {
            assert_eq!(path.camera(t, camera.hfov_deg), camera, "at {t} s");
        }
    }

    #[test]
    fn the_governor_shrinks_late_frames_and_grows_them_back_when_there_is_time() {
        let mut governor = ScaleGovernor::new(0.016);
        assert_eq!(governor.render_size((960, 540)), (960, 540));
        // Twice the target (three quarters of the frame): half the pixels.
        governor.adapt(0.024);
        assert!((governor.scale() - 2f32.sqrt()).abs() < 1e-6);
        assert_eq!(governor.render_size((960, 540)), (679, 382));
        // Far over: at most twice as small a side a frame, at most 4.
        governor.adapt(1.0);
        assert!((governor.scale() - 2.0 * 2f32.sqrt()).abs() < 1e-5);
        governor.adapt(1.0);
        assert_eq!(governor.scale(), ScaleGovernor::MAX_SCALE);
        // Between half and three quarters: it holds.
        governor.adapt(0.010);
        assert_eq!(governor.scale(), ScaleGovernor::MAX_SCALE);
        // Time to spare: an eighth more pixels a frame, up to the window.
        governor.adapt(0.001);
        assert!((governor.scale().powi(2) - 16.0 * 7.0 / 8.0).abs() < 1e-4);
        for _ in 0..40 {
            governor.adapt(0.001);
        }
        assert_eq!(governor.scale(), 1.0);
        assert_eq!(governor.render_size((3, 1)), (3, 1));
    }

    #[test]
    fn a_smaller_frame_is_enlarged_to_the_window_by_repeating_pixels() {
        let pixels = Pixels::new(2, 2);
        for (i, word) in pixels.words.iter().enumerate() {
            word.store(i as u32 + 1, Ordering::Relaxed);
        }
        let mut out = vec![0; 5 * 3];
        pixels.enlarge_to(&mut out, (5, 3));
        assert_eq!(out, [1, 1, 1, 2, 2, 1, 1, 1, 2, 2, 3, 3, 3, 4, 4]);
        let mut same = vec![0; 4];
        pixels.enlarge_to(&mut same, (2, 2));
        assert_eq!(same, [1, 2, 3, 4]);
    }

    #[test]
    fn the_render_command_names_every_setting_the_window_used() {
        let given = Resolution::Multi {
            pixel_to_voxel: U8F8::from_bits(300),
        };
        let options = RenderOptions {
            resolution: given,
            ..RenderOptions::default()
        };
        let mut settings = Settings::new(options, PixelRays::ByFootprint, WindowGovernor::Cost);
        settings.toggle_shading();
        // Single resolution and back: the ratio given comes back.
        settings.toggle_resolution();
        assert_eq!(settings.options.resolution, Resolution::Single);
        settings.toggle_resolution();
        assert_eq!(settings.options.resolution, given);
        let options = settings.options;
        let camera = Camera::looking([1.5, 2.25, 3.0], 10.0, 20.0);
        let args = render_arguments(
            &["--height".into(), "my map.png".into()],
            &camera,
            (960, 540),
            &options,
            settings.rays,
            "view 1.png",
        );
        let line = args
            .iter()
            .map(|a| shell_word(a))
            .collect::<Vec<_>>()
            .join(" ");
        assert!(line.starts_with("--height 'my map.png' --eye=1.5,2.25,3 --yaw=10 --pitch=20"));
        assert!(line.contains("--pixel-to-voxel=1.171875"));
        assert!(line.contains("--shading=nearest"));
        assert!(line.contains("--vertical-samples=footprint"));
        assert!(line.ends_with("'--out=view 1.png'"));
        assert_eq!(shell_word("it's"), r"'it'\''s'");
    }
}
