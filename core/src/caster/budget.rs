//! Frames that spend a fixed budget.
//!
//! A deterministic image generator never varies its frame time (Cosman &
//! Grange): the frame's time is fixed and its quality adapts. Cohen-Or
//! tuned the pixel-to-voxel ratio "as a tool to tune the quality of the
//! image as the frame generation rate is guaranteed". The [`Governor`]
//! does it per frame, in a budget of [`Prices`]: every pixel, line, ray,
//! step and color fetch the frame makes has its price (a board's
//! instructions, a modeled machine's cycles, or steps alone), so sky,
//! shading and steps are all paid for.
//!
//! 1. **Base pass.** Every line at the level bias (the pixel-to-voxel
//!    ratio of [`Resolution::Multi`]) the frames before suggest, one ray a
//!    pixel, by the line caster (a line set up once, a ray its slope; the
//!    per-ray path for `options.vertical_samples` above one or the other
//!    coherence settings), priced at the governor's base prices
//!    ([`Governor::with_base_prices`]).
//!    - *Correction*: once half the rays are cast, if the cost so far
//!      projects past the budget, the remaining lines are rendered at the
//!      coarsest bias: coarser, rather than late.
//!    - *Guarantee*: before each ray the budget left, less every later
//!      ray's set-up and shading, is turned into an allowance `n` of at
//!      most `4n + 2` steps (a ray cut short is shaded where it stopped);
//!      with fewer than six steps' worth left a pixel repeats the ray
//!      before it on its line.
//! 2. **Refinement.** What the base pass left is spent on lines rendered
//!    again on the per-ray path with two rays a pixel, four where the
//!    pixel's footprint is long ([`crate::render_by_footprint`]'s rule, at
//!    least two), in bit-reversed line order so that the refined lines
//!    spread over the image. A line starts only while a line's and a
//!    pixel's most cost are left, and stops at the pixel that would not
//!    fit: its other pixels keep the rays they had. When every line is refined and budget is
//!    left (views of mostly sky, where a refined line is cheap), a second
//!    round renders the lines again with each pixel's rays doubled (4 or
//!    8).
//! 3. **Next frame.** The base pass is steered to take a half to three
//!    quarters of the budget, which leaves the refinement room to fill it:
//!    the next frame's bias goes coarser with the base pass's cost over
//!    three quarters (at least twice after a frame that went coarse or ran
//!    dry), and finer by an eighth a frame under a half.
//!
//! A frame never costs more than its budget or [`Governor::least_cost`],
//! whichever is more (tested over 10 000 frames of a flight that keeps
//! changing). Everything is integer arithmetic on counts: the same flight
//! and budget give the same images and costs on every machine. Several
//! governors can render one frame between them on as many cores, each a
//! [`LineShare`] of its lines within its own budget
//! ([`Governor::render_share`]).
//!
//! ```
//! use terracast::{render, Camera, CountingProbe, Framebuffer, Governor, Pyramid, RenderOptions, Terrain, View};
//!
//! let heights: [u16; 64] = core::array::from_fn(|i| ((i % 8) * (i / 8)) as u16 * 8);
//! let terrain = Terrain::new(8, 8, &heights, &[[90, 140, 60]; 64])?;
//! let pyramid = Pyramid::flat(terrain);
//! let view = View::new(&Camera::looking([1.0, 1.0, 40.0], 45.0, 30.0), 16, 12)?;
//! let mut pixels = [[0u8; 3]; 16 * 12];
//! let mut governor = Governor::on_board(600_000);
//! for _ in 0..3 {
//!     let mut frame = Framebuffer::new(&mut pixels, 16, 12)?;
//!     let cost = governor.render(&pyramid, &view, &RenderOptions::default(), &mut frame, &mut CountingProbe::default());
//!     assert!(cost.cost <= cost.budget);
//! }
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

use super::line_caster::{self, LineCaster};
use super::ray_caster::{Allowances, RayCaster, REFINED_MOST_LOG2};
use super::{RenderOptions, Resolution};
use crate::probe::{CountingProbe, Probe, MAX_COLOR_FETCHES_A_RAY};
use crate::sink::Sink;
use crate::surface::Surface;
use crate::view::View;
use core::cell::Cell;
use fixed::types::U8F8;

/// The price of each thing a frame does, in the budget's unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Prices {
    /// Writing a pixel (a refined pixel is written again).
    pub per_pixel: u32,
    /// Writing a pixel in the base pass instead, where every line of the
    /// view runs straight along its axis ([`View::lines_are_straight`]: a
    /// level view's columns): the line caster steps those pixels a row at
    /// a time, without the ownership test a pixel of any other line takes.
    pub per_straight_pixel: u32,
    /// Setting up an image line.
    pub per_line: u32,
    /// Setting up a ray.
    pub per_ray: u32,
    /// A traversal step or a bound test ([`Probe::visit`], [`Probe::bound`]).
    pub per_step: u32,
    /// A color fetch ([`Probe::color`]).
    pub per_color: u32,
    /// More for a color fetch that is a square of four texels blended by
    /// a far hit's footprint ([`Probe::color_square`]): the footprint's
    /// level, its crossing point and the bilinear blend.
    pub per_color_square: u32,
    /// A hit and its shading ([`Probe::hit`]).
    pub per_hit: u32,
    /// A hit's shading, more for each level above level 0 it is on.
    pub per_hit_level: u32,
}

impl Prices {
    /// Steps alone: a budget in steps.
    pub const STEPS: Self = Self {
        per_pixel: 0,
        per_straight_pixel: 0,
        per_line: 0,
        per_ray: 0,
        per_step: 1,
        per_color: 0,
        per_color_square: 0,
        per_hit: 0,
        per_hit_level: 0,
    };

    /// The board's (Cortex-M7) instructions in the refinement, which sets
    /// every ray up in full (the per-ray path); [`Governor::on_board`]
    /// prices the base pass at [`Prices::BOARD_LINES`]. Both are the
    /// least-squares prices that `scripts/board-check` prints for its
    /// governed frames on the built-in map and on a real one together
    /// (`prices fitted to these frames and ...'s`: the board's counts of
    /// its runs at 3000, 2000 and 1200 instructions a pixel against their
    /// work, the two passes' apart, a step's price held at 53, as these
    /// frames take too few steps to tell it apart), raised by 4 %: enough
    /// that the board's count stays under the budget on both maps, and
    /// little enough that the built-in map's frames spend nine tenths of
    /// their budgets. The fit prices no refined ray apart from its hit
    /// (the two move together): a hit's price is both. A hit's price
    /// grows with its level; a far hit's color squares (its footprint's
    /// levels, blended bilinearly, at one price in both passes) cost more
    /// than a near hit's grid-line colors, and a refined line's set-up on
    /// the per-ray path has a price of its own: without those two counts
    /// the fit is off the two maps' counts by up to 12 % (the real map's
    /// level views hit far more often, and refine fewer and longer
    /// lines). A level view's base
    /// pass writes straight pixels, stepped without the ownership test:
    /// priced apart from the others, the fit leaves them no price of
    /// their own (what they cost goes with their rays).
    pub const BOARD: Self = Self {
        per_pixel: 107,
        per_straight_pixel: 0,
        per_line: 16646,
        per_ray: 0,
        per_step: 53,
        per_color: 0,
        per_color_square: 174,
        per_hit: 1803,
        per_hit_level: 276,
    };

    /// The board's instructions in the base pass, which takes the line
    /// caster (a line set up once, a ray its slope), fitted with
    /// [`Prices::BOARD`]. The line caster casts no ray into the sky but
    /// the one a line leaves the terrain with: a ray's price is its hit's
    /// too.
    pub const BOARD_LINES: Self = Self {
        per_pixel: 107,
        per_straight_pixel: 0,
        per_line: 0,
        per_ray: 830,
        per_step: 53,
        per_color: 0,
        per_color_square: 174,
        per_hit: 0,
        per_hit_level: 0,
    };

    /// What `work` costs at these prices.
    pub fn of(&self, work: &FrameWork) -> u64 {
        work.pixels.saturating_sub(work.straight_pixels) * u64::from(self.per_pixel)
            + work.straight_pixels * u64::from(self.per_straight_pixel)
            + work.lines * u64::from(self.per_line)
            + work.rays * u64::from(self.per_ray)
            + work.steps * u64::from(self.per_step)
            + work.colors * u64::from(self.per_color)
            + work.color_squares * u64::from(self.per_color_square)
            + work.hits * u64::from(self.per_hit)
            + work.hit_levels * u64::from(self.per_hit_level)
    }

    /// The most a ray's shading can cost on a surface whose top level is
    /// `top`: its color fetches and its hit.
    const fn shading_most(&self, top: u8) -> u64 {
        MAX_COLOR_FETCHES_A_RAY as u64 * (self.per_color as u64 + self.per_color_square as u64)
            + self.per_hit as u64
            + top as u64 * self.per_hit_level as u64
    }
}

/// What a frame did, counted as it is priced.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FrameWork {
    /// Pixels written (a refined pixel twice).
    pub pixels: u64,
    /// Image lines set up (a refined line twice).
    pub lines: u64,
    /// Rays set up.
    pub rays: u64,
    /// Traversal steps and bound tests.
    pub steps: u64,
    /// Color fetches.
    pub colors: u64,
    /// Of `colors`, the squares of four texels a far hit's footprint
    /// blends.
    pub color_squares: u64,
    /// Hits.
    pub hits: u64,
    /// The hits' levels, summed.
    pub hit_levels: u64,
    /// Of `pixels`, those the base pass wrote on lines that run straight
    /// along their axis ([`View::lines_are_straight`]).
    pub straight_pixels: u64,
}

impl FrameWork {
    /// What a frame of `pixels` pixels, each written once, and `lines`
    /// image lines did, as `probe` counted it: its rays, steps, color
    /// fetches and hits (the probe counts each level's hits apart), none of
    /// its pixels counted straight.
    pub fn counted(probe: &CountingProbe, pixels: u64, lines: u64) -> Self {
        Self {
            pixels,
            lines,
            rays: probe.rays,
            steps: probe.steps,
            colors: probe.color_fetches,
            color_squares: probe.color_squares,
            hits: probe.hits_by_level.iter().sum(),
            hit_levels: (0u64..)
                .zip(probe.hits_by_level)
                .map(|(level, hits)| level * hits)
                .sum(),
            straight_pixels: 0,
        }
    }
}

/// What a budgeted frame did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameCost {
    /// The frame's cost at the governor's [`Prices`]: `prices.of(&work)`.
    pub cost: u64,
    /// What it did.
    pub work: FrameWork,
    /// The frame's budget; `cost` exceeds it only when the budget is
    /// below [`Governor::least_cost`].
    pub budget: u64,
    /// Of `cost`, the base pass's (every line once).
    pub base_cost: u64,
    /// Of `work`, the base pass's, priced at the governor's base prices
    /// ([`Governor::with_base_prices`]); the rest at its prices.
    pub base_work: FrameWork,
    /// The level bias (pixel-to-voxel ratio) the frame was rendered at.
    pub level_bias: U8F8,
    /// Lines finished at the coarsest bias ([`Governor::MAX_BIAS`], or
    /// [`Governor::with_bias_range`]'s)
    /// because the frame was heading past its budget.
    pub coarse_lines: u32,
    /// Lines rendered again with more rays (some of them in part) from
    /// what the base pass left; a line the second round renders again
    /// counts twice.
    pub refined_lines: u32,
    /// Rays that found no budget left and repeat the ray before them.
    pub filled_rays: u32,
}

impl FrameCost {
    /// Of `work`, the refinement's: what the frame did after its base pass.
    pub fn refined_work(&self) -> FrameWork {
        let (all, base) = (&self.work, &self.base_work);
        FrameWork {
            pixels: all.pixels - base.pixels,
            lines: all.lines - base.lines,
            rays: all.rays - base.rays,
            steps: all.steps - base.steps,
            colors: all.colors - base.colors,
            color_squares: all.color_squares - base.color_squares,
            hits: all.hits - base.hits,
            hit_levels: all.hit_levels - base.hit_levels,
            straight_pixels: all.straight_pixels - base.straight_pixels,
        }
    }
}

/// A per-frame budget, the prices it is spent at, and the level bias that
/// keeps it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Governor {
    budget: u64,
    /// The base pass's prices, and the refinement's.
    base_prices: Prices,
    prices: Prices,
    /// The level bias for the next frame, and the finest and coarsest it
    /// may take (a frame heading past its budget finishes at the
    /// coarsest), U8.8 bits.
    bias: u16,
    finest: u16,
    coarsest: u16,
}

impl Governor {
    /// The finest level bias the governor uses: a voxel a quarter pixel wide.
    pub const MIN_BIAS: U8F8 = U8F8::from_bits(64);
    /// The coarsest: a voxel 64 pixels wide.
    pub const MAX_BIAS: U8F8 = U8F8::from_bits(64 << 8);

    /// A governor for frames that cost at most `budget` at `prices`,
    /// starting at a bias of 1.
    pub const fn new(budget: u64, prices: Prices) -> Self {
        Self {
            budget,
            base_prices: prices,
            prices,
            bias: 1 << 8,
            finest: Self::MIN_BIAS.to_bits(),
            coarsest: Self::MAX_BIAS.to_bits(),
        }
    }

    /// A governor for frames that cost at most `budget` of the board's
    /// instructions: the base pass at [`Prices::BOARD_LINES`], the
    /// refinement at [`Prices::BOARD`].
    pub const fn on_board(budget: u64) -> Self {
        Self::new(budget, Prices::BOARD).with_base_prices(Prices::BOARD_LINES)
    }

    /// This governor with the base pass priced at `base`: where one event
    /// costs a different amount in the base pass, which takes the line
    /// caster when the options allow it (one ray a pixel, the default
    /// coherence), than in the refinement, which sets every ray up in
    /// full (a board's instructions; a modeled machine whose costs are
    /// per event prices both alike).
    pub const fn with_base_prices(self, base: Prices) -> Self {
        Self {
            base_prices: base,
            ..self
        }
    }

    /// What a frame may cost.
    pub fn budget(&self) -> u64 {
        self.budget
    }

    /// The prices the refinement is spent at.
    pub fn prices(&self) -> Prices {
        self.prices
    }

    /// The prices the base pass is spent at.
    pub fn base_prices(&self) -> Prices {
        self.base_prices
    }

    /// The level bias the next frame starts with.
    pub fn level_bias(&self) -> U8F8 {
        U8F8::from_bits(self.bias)
    }

    /// This governor with its level bias within `finest..=coarsest`
    /// (itself within [`Governor::MIN_BIAS`] and [`Governor::MAX_BIAS`]):
    /// for a caller with a better way to spend or save time than the
    /// levels (a window can render more or fewer pixels), which wants them
    /// kept near the pixel's footprint.
    pub fn with_bias_range(self, finest: U8F8, coarsest: U8F8) -> Self {
        let clamp = |bias: U8F8| bias.clamp(Self::MIN_BIAS, Self::MAX_BIAS).to_bits();
        let (finest, coarsest) = (clamp(finest), clamp(coarsest));
        let coarsest = coarsest.max(finest);
        Self {
            finest,
            coarsest,
            bias: self.bias.clamp(finest, coarsest),
            ..self
        }
    }

    /// This governor with a budget of `budget` from the next frame on (its
    /// level bias kept): for a caller whose budget follows a clock.
    pub const fn with_budget(self, budget: u64) -> Self {
        Self { budget, ..self }
    }

    /// The least a frame of `view` costs, whatever the budget: every pixel
    /// written, every line and every ray (`options.vertical_samples` a
    /// pixel) set up. A budget below it is overrun by up to the
    /// difference; one that also covers every ray's shading
    /// ([`MAX_COLOR_FETCHES_A_RAY`]) and a few steps a ray renders every
    /// ray.
    pub fn least_cost(&self, view: &View, options: &RenderOptions) -> u64 {
        self.least_share_cost(view, options, &LineShare::all(view))
    }

    /// The least `share` of a frame of `view` costs (see
    /// [`Governor::least_cost`]).
    pub fn least_share_cost(&self, view: &View, options: &RenderOptions, share: &LineShare) -> u64 {
        let prices = &self.base_prices;
        let pixels = share.pixels;
        let per_pixel = if straight_base_pass(view, options) {
            prices.per_straight_pixel
        } else {
            prices.per_pixel
        };
        pixels * u64::from(per_pixel)
            + u64::from(share.line_count(view)) * u64::from(prices.per_line)
            + pixels * u64::from(options.vertical_samples.count()) * u64::from(prices.per_ray)
    }

    /// Renders `view` within the budget (with `options`, its resolution
    /// replaced by the pyramid's levels at the governor's bias), then
    /// chooses the next frame's bias from this frame's base pass.
    pub fn render<T: Surface + ?Sized, S: Sink, P: Probe>(
        &mut self,
        surface: &T,
        view: &View,
        options: &RenderOptions,
        sink: &mut S,
        probe: &mut P,
    ) -> FrameCost {
        self.render_share(surface, view, options, &LineShare::all(view), sink, probe)
    }

    /// Renders `share` of `view`'s lines within the budget, as
    /// [`Governor::render`] renders them all: several governors, each with
    /// its share of a frame's budget, render a frame between them on as
    /// many cores, each share within its own budget, the same images and
    /// costs whatever order they run in.
    pub fn render_share<T: Surface + ?Sized, S: Sink, P: Probe>(
        &mut self,
        surface: &T,
        view: &View,
        options: &RenderOptions,
        share: &LineShare,
        sink: &mut S,
        probe: &mut P,
    ) -> FrameCost {
        let bias = self.bias;
        let at = |bits: u16| RenderOptions {
            resolution: Resolution::Multi {
                pixel_to_voxel: U8F8::from_bits(bits),
            },
            ..*options
        };
        let (fine, coarse) = (at(bias), at(self.coarsest));
        let fine_caster = RayCaster::new(surface, view, &fine);
        let pixels = share.pixels;
        // Every pixel is written and every line set up once.
        let meter = Meter::new(self.base_prices, surface.top());
        if straight_base_pass(view, options) {
            meter.add_straight_pixels(pixels);
        } else {
            meter.add_pixels(pixels);
        }
        meter.add_lines(u64::from(share.line_count(view)));
        let budget = self.budget;
        let mut metered = Metered {
            inner: probe,
            meter: &meter,
        };
        let mut base = BaseAllowances {
            meter: &meter,
            budget,
            rays_total: pixels * u64::from(options.vertical_samples.count()),
            filled: 0,
        };
        let coarse_lines = if line_caster::takes(options) {
            let (fine_lines, coarse_lines) = (
                LineCaster::new(surface, view, &fine),
                LineCaster::new(surface, view, &coarse),
            );
            base_pass(view, share, &mut base, |line, coarse, base| {
                metered.line(line);
                let caster = if coarse { &coarse_lines } else { &fine_lines };
                caster.line_within(line, sink, &mut metered, base);
            })
        } else {
            let coarse_caster = RayCaster::new(surface, view, &coarse);
            base_pass(view, share, &mut base, |line, coarse, base| {
                metered.line(line);
                let caster = if coarse { &coarse_caster } else { &fine_caster };
                caster.line(line, sink, &mut metered, base);
            })
        };
        let (base_cost, base_work) = (meter.cost(), meter.work());
        meter.price_from_here(self.prices, surface.top());
        let mut refined_lines = 0;
        let mut refine = RefineAllowances {
            meter: &meter,
            budget,
            filled: 0,
            most_rays: 0,
        };
        if base.filled == 0 {
            'rounds: for round in 1..=REFINE_ROUNDS {
                refine.most_rays = 1 << (round + 1).min(REFINED_MOST_LOG2);
                let line_most = u64::from(self.prices.per_line) + refine.pixel_most();
                for line in BitReversed::new(share.line_count(view)).map(|j| share.line(j)) {
                    if budget.saturating_sub(meter.cost()) < line_most {
                        break 'rounds;
                    }
                    meter.add_lines(1);
                    refined_lines += 1;
                    metered.line(line);
                    fine_caster.line_refined(line, round, sink, &mut metered, &mut refine);
                }
            }
        }
        let cost = FrameCost {
            cost: meter.cost(),
            work: meter.work(),
            budget,
            base_cost,
            base_work,
            level_bias: U8F8::from_bits(bias),
            coarse_lines,
            refined_lines,
            filled_rays: base.filled + refine.filled,
        };
        self.bias = next_bias(bias, &cost).clamp(self.finest, self.coarsest);
        cost
    }
}

/// Some of a frame's lines, for one of several governors that render a
/// frame between them (one a core): the lines whose index is `index`
/// modulo `count`, and how many pixels they own. Neighbouring lines see
/// nearly the same ground, so each share of an interleaved frame costs
/// about the same.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LineShare {
    index: u32,
    count: u32,
    pixels: u64,
}

impl LineShare {
    /// Every line of `view`.
    pub fn all(view: &View) -> Self {
        Self {
            index: 0,
            count: 1,
            pixels: u64::from(view.width()) * u64::from(view.height()),
        }
    }

    /// Share `index` of `count` of `view`'s lines; `None` unless `index <
    /// count`. Counts the pixels the share's lines own (a governor sets
    /// their rays' set-up aside before it casts any): one pass of the
    /// ownership test over the share's lines, a few instructions a pixel.
    pub fn new(view: &View, index: u32, count: u32) -> Option<Self> {
        if index >= count {
            return None;
        }
        let pixels = (index..view.lines())
            .step_by(count as usize)
            .map(|line| view.line_pixels(line).count() as u64)
            .sum();
        Some(Self {
            index,
            count,
            pixels,
        })
    }

    /// The pixels this share's lines own.
    pub fn pixels(&self) -> u64 {
        self.pixels
    }

    /// How many of `view`'s lines this share holds.
    pub fn line_count(&self, view: &View) -> u32 {
        view.lines().saturating_sub(self.index).div_ceil(self.count)
    }

    /// The share's `j`th line's index in the frame.
    fn line(&self, j: u32) -> u32 {
        self.index + j * self.count
    }
}

/// Whether the base pass steps every pixel of `view` a row at a time: the
/// line caster takes `options` and every line runs straight.
fn straight_base_pass(view: &View, options: &RenderOptions) -> bool {
    line_caster::takes(options) && view.lines_are_straight()
}

/// The base pass: every line of `share` of `view` by `cast_line(line, coarse,
/// allowances)`, at the governor's bias until, once half the rays are
/// cast, the cost so far projects past the budget; from there on at the
/// coarsest (`coarse`). Returns the lines rendered coarse.
fn base_pass(
    view: &View,
    share: &LineShare,
    base: &mut BaseAllowances<'_>,
    mut cast_line: impl FnMut(u32, bool, &mut BaseAllowances<'_>),
) -> u32 {
    let meter = base.meter;
    let (budget, rays_total) = (base.budget, base.rays_total);
    let fixed = meter.cost();
    let mut coarse_lines = 0;
    for line in (0..share.line_count(view)).map(|j| share.line(j)) {
        // Projected past the budget: the rest goes coarser.
        let rays = meter.rays.get();
        let heading_over = coarse_lines > 0
            || (rays >= rays_total / 2
                && u128::from(meter.cost() - fixed) * u128::from(rays_total)
                    > u128::from(budget.saturating_sub(fixed)) * u128::from(rays));
        if heading_over {
            coarse_lines += 1;
        }
        cast_line(line, heading_over, base);
    }
    coarse_lines
}

/// The next frame's bias, from this frame's base pass: over three
/// quarters of the budget, scaled by its cost over that target (at most ×4
/// a frame: the steps fall about inversely with the bias); at least
/// doubled after a frame that went coarse or ran dry; under half the
/// budget, refined by an eighth a frame, so that a quiet stretch does not
/// swing it back too fast.
fn next_bias(bias: u16, cost: &FrameCost) -> u16 {
    let target = (cost.budget - cost.budget / 4).max(1);
    let bias64 = u64::from(bias);
    let base = cost.base_cost;
    let mut next = if base > target {
        (u128::from(bias64) * u128::from(base) / u128::from(target)).min(u128::from(bias64 * 4))
            as u64
    } else if base < cost.budget / 2 {
        bias64 - bias64 / 8
    } else {
        bias64
    };
    if cost.coarse_lines > 0 || cost.filled_rays > 0 {
        next = next.max(bias64 * 2);
    }
    next.clamp(
        u64::from(Governor::MIN_BIAS.to_bits()),
        u64::from(Governor::MAX_BIAS.to_bits()),
    ) as u16
}

/// What a frame has done so far, and what it has cost: each event is
/// counted and its price added as it happens (the base pass's events at
/// the base prices, the refinement's at its own), so that the cost left
/// before each ray is one read.
#[derive(Debug)]
struct Meter {
    prices: Cell<Prices>,
    cost: Cell<u64>,
    pixels: Cell<u64>,
    lines: Cell<u64>,
    rays: Cell<u64>,
    steps: Cell<u64>,
    colors: Cell<u64>,
    color_squares: Cell<u64>,
    hits: Cell<u64>,
    hit_levels: Cell<u64>,
    straight_pixels: Cell<u64>,
    /// The most a ray's shading costs (see [`Prices::shading_most`]).
    shading_most: Cell<u64>,
}

impl Meter {
    /// A meter at `prices` with nothing counted, for a frame over a
    /// surface whose top level is `top`.
    fn new(prices: Prices, top: u8) -> Self {
        Self {
            prices: Cell::new(prices),
            cost: Cell::new(0),
            pixels: Cell::new(0),
            lines: Cell::new(0),
            rays: Cell::new(0),
            steps: Cell::new(0),
            colors: Cell::new(0),
            color_squares: Cell::new(0),
            hits: Cell::new(0),
            hit_levels: Cell::new(0),
            straight_pixels: Cell::new(0),
            shading_most: Cell::new(prices.shading_most(top)),
        }
    }

    /// Prices the work from here on at `prices` (the refinement's).
    fn price_from_here(&self, prices: Prices, top: u8) {
        self.prices.set(prices);
        self.shading_most.set(prices.shading_most(top));
    }

    /// Counts `n` more in `count`, at `price` each.
    #[inline(always)]
    fn add(&self, count: &Cell<u64>, n: u64, price: u32) {
        count.set(count.get() + n);
        self.cost.set(self.cost.get() + n * u64::from(price));
    }

    fn add_pixels(&self, n: u64) {
        self.add(&self.pixels, n, self.prices.get().per_pixel);
    }

    /// Counts `n` pixels that are straight ones too, at their own price.
    fn add_straight_pixels(&self, n: u64) {
        self.pixels.set(self.pixels.get() + n);
        self.add(
            &self.straight_pixels,
            n,
            self.prices.get().per_straight_pixel,
        );
    }

    fn add_lines(&self, n: u64) {
        self.add(&self.lines, n, self.prices.get().per_line);
    }

    fn work(&self) -> FrameWork {
        FrameWork {
            pixels: self.pixels.get(),
            lines: self.lines.get(),
            rays: self.rays.get(),
            steps: self.steps.get(),
            colors: self.colors.get(),
            color_squares: self.color_squares.get(),
            hits: self.hits.get(),
            hit_levels: self.hit_levels.get(),
            straight_pixels: self.straight_pixels.get(),
        }
    }

    #[inline(always)]
    fn cost(&self) -> u64 {
        self.cost.get()
    }

    #[inline(always)]
    fn left(&self, budget: u64) -> u64 {
        budget.saturating_sub(self.cost())
    }

    /// The allowance a ray gets from `left` (what is left for its steps
    /// once its shading and every later ray are set aside): at most
    /// `4n + 2` steps, none with fewer than six steps' worth left.
    #[inline]
    fn allowance(&self, left: u64, filled: &mut u32) -> u32 {
        let per_step = self.prices.get().per_step;
        // Steps at no price: as many as the ray can take, while anything
        // is left. A frame's budget is below 2^32 on a board: one 32-bit
        // divide, where a 64-bit one is a library call.
        let steps = if per_step == 0 {
            if left == 0 {
                0
            } else {
                u64::MAX
            }
        } else if let Ok(left) = u32::try_from(left) {
            u64::from(left / per_step)
        } else {
            left / u64::from(per_step)
        };
        if steps < 6 {
            *filled += 1;
            return 0;
        }
        ((steps - 2) / 4).min(u64::from(u32::MAX - 1)) as u32
    }
}

/// A probe that counts into a [`Meter`] and passes every event on.
struct Metered<'a, P> {
    inner: &'a mut P,
    meter: &'a Meter,
}

impl<P: Probe> Probe for Metered<'_, P> {
    #[inline(always)]
    fn visit(&mut self, level: u8, voxel: usize) {
        let meter = self.meter;
        meter.add(&meter.steps, 1, meter.prices.get().per_step);
        self.inner.visit(level, voxel);
    }
    #[inline(always)]
    fn bound(&mut self, level: u8, cell: usize) {
        let meter = self.meter;
        meter.add(&meter.steps, 1, meter.prices.get().per_step);
        self.inner.bound(level, cell);
    }
    #[inline(always)]
    fn color(&mut self, level: u8, voxel: usize) {
        let meter = self.meter;
        meter.add(&meter.colors, 1, meter.prices.get().per_color);
        self.inner.color(level, voxel);
    }
    #[inline(always)]
    fn color_square(&mut self, level: u8, corner: usize) {
        let meter = self.meter;
        let prices = meter.prices.get();
        meter.add(&meter.colors, 1, prices.per_color);
        meter.add(&meter.color_squares, 1, prices.per_color_square);
        self.inner.color_square(level, corner);
    }
    #[inline(always)]
    fn hit(&mut self, level: u8) {
        let meter = self.meter;
        let prices = meter.prices.get();
        meter.add(&meter.hits, 1, prices.per_hit);
        meter.add(&meter.hit_levels, u64::from(level), prices.per_hit_level);
        self.inner.hit(level);
    }
    #[inline(always)]
    fn ray(&mut self) {
        let meter = self.meter;
        meter.add(&meter.rays, 1, meter.prices.get().per_ray);
        self.inner.ray();
    }
    /// A secondary ray costs the frame as a ray does.
    #[inline(always)]
    fn secondary_ray(&mut self) {
        let meter = self.meter;
        meter.add(&meter.rays, 1, meter.prices.get().per_ray);
        self.inner.secondary_ray();
    }
    #[inline(always)]
    fn line(&mut self, index: u32) {
        self.inner.line(index);
    }
}

/// The base pass's allowances: each ray's from the budget left once its
/// own shading and every later ray's set-up are set aside.
struct BaseAllowances<'a> {
    meter: &'a Meter,
    budget: u64,
    rays_total: u64,
    filled: u32,
}

impl Allowances for BaseAllowances<'_> {
    type Fetches = u32;
    fn next(&mut self) -> u32 {
        let meter = self.meter;
        let prices = meter.prices.get();
        // This ray's set-up is counted; its shading and the later rays'
        // set-up are not (a later ray that finds no budget is not shaded).
        let later = self.rays_total.saturating_sub(meter.rays.get()) * u64::from(prices.per_ray)
            + meter.shading_most.get();
        meter.allowance(
            meter.left(self.budget).saturating_sub(later),
            &mut self.filled,
        )
    }
}

/// The refinement's allowances: a pixel is rendered again only while its
/// most cost (the round's most rays with their shading and six steps
/// each, and its write) is left; each ray's steps from what is left once
/// its shading and the pixel's other rays' set-up are set aside.
struct RefineAllowances<'a> {
    meter: &'a Meter,
    budget: u64,
    filled: u32,
    /// The most rays a pixel of this round gets.
    most_rays: u64,
}

/// Refinement rounds: every line with rays by footprint (2 or 4 a
/// pixel), then every line again with them doubled (4 or 8), while the
/// budget lasts. The second round spends what the first leaves on views
/// whose lines are cheap to refine (mostly sky, few steps a ray).
const REFINE_ROUNDS: u32 = 2;

impl RefineAllowances<'_> {
    fn pixel_most(&self) -> u64 {
        let meter = self.meter;
        let prices = meter.prices.get();
        self.most_rays
            * (u64::from(prices.per_ray)
                + meter.shading_most.get()
                + 6 * u64::from(prices.per_step))
            + u64::from(prices.per_pixel)
    }
}

impl Allowances for RefineAllowances<'_> {
    type Fetches = u32;
    fn next(&mut self) -> u32 {
        let meter = self.meter;
        let prices = meter.prices.get();
        let later = (self.most_rays - 1) * u64::from(prices.per_ray) + meter.shading_most.get();
        meter.allowance(
            meter.left(self.budget).saturating_sub(later),
            &mut self.filled,
        )
    }

    fn pixel(&mut self) -> bool {
        if self.meter.left(self.budget) < self.pixel_most() {
            return false;
        }
        let meter = self.meter;
        meter.add_pixels(1);
        true
    }
}

/// `0..count` in bit-reversed order (0, half, a quarter, three quarters,
/// …): every prefix spreads evenly over the range.
struct BitReversed {
    next: u64,
    bits: u32,
    count: u32,
}

impl BitReversed {
    fn new(count: u32) -> Self {
        Self {
            next: 0,
            bits: count
                .checked_next_power_of_two()
                .map_or(32, u32::trailing_zeros),
            count,
        }
    }
}

impl Iterator for BitReversed {
    type Item = u32;
    fn next(&mut self) -> Option<u32> {
        while self.next < 1u64 << self.bits {
            let i = self.next as u32;
            self.next += 1;
            let reversed = if self.bits == 0 {
                0
            } else {
                i.reverse_bits() >> (32 - self.bits)
            };
            if reversed < self.count {
                return Some(reversed);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{pyramid_cells, pyramid_points, Camera, HeightFilter, Pyramid, Terrain};
    use std::vec;

    /// The same allowance for every ray.
    struct Fixed(u32);

    impl Allowances for Fixed {
        type Fetches = u32;
        fn next(&mut self) -> u32 {
            self.0
        }
    }

    /// The most steps any one ray took.
    #[derive(Default)]
    struct PerRay {
        current: u64,
        most: u64,
    }

    impl PerRay {
        fn most(&self) -> u64 {
            self.most.max(self.current)
        }
    }

    impl Probe for PerRay {
        fn visit(&mut self, _: u8, _: usize) {
            self.current += 1;
        }
        fn bound(&mut self, _: u8, _: usize) {
            self.current += 1;
        }
        fn ray(&mut self) {
            self.most = self.most.max(self.current);
            self.current = 0;
        }
    }

    struct Discard;

    impl Sink for Discard {
        fn put(&mut self, _: u32, _: u32, _: crate::Sample) {}
    }

    /// The coarser levels and bounds of `terrain`, built: the storage a
    /// pyramid over it borrows.
    fn pyramid_storage(
        terrain: &Terrain,
    ) -> (vec::Vec<u16>, vec::Vec<crate::color::Rgb>, vec::Vec<u16>) {
        let (side_x, side_y) = (terrain.width(), terrain.depth());
        let points = pyramid_points(side_x, side_y);
        let (mut h, mut c) = (vec![0u16; points], vec![[0u8; 3]; points]);
        let mut b = vec![0u16; pyramid_cells(side_x, side_y)];
        Pyramid::build(terrain, HeightFilter::default(), &mut h, &mut c, &mut b).unwrap();
        (h, c, b)
    }

    #[test]
    fn a_ray_with_allowance_n_takes_at_most_4n_plus_2_steps() {
        // Rough terrain with cliffs: heights jump by up to 200 voxels.
        let side = 64u32;
        let n = (side * side) as usize;
        let heights: vec::Vec<u16> = (0..n as u32)
            .map(|i| {
                let (x, y) = (i % side, i / side);
                let cliff = if (x / 8 + y / 8) % 3 == 0 { 200 } else { 0 };
                ((x * 7 + y * 13) % 17 + cliff) as u16 * 16
            })
            .collect();
        let colors = vec![[80u8, 120, 60]; n];
        let terrain = Terrain::new(side, side, &heights, &colors).unwrap();
        let (h, c, b) = pyramid_storage(&terrain);
        let pyramid = Pyramid::new(terrain, &h, &c, &b).unwrap();
        let options = RenderOptions::default();
        for (eye, pitch) in [
            ([-10.0, 5.0, 230.0], 5.0),
            ([30.0, 30.0, 400.0], 60.0),
            ([2.0, 60.0, 205.0], 0.0),
            ([32.0, 32.0, 300.0], 90.0),
        ] {
            for yaw in [0.0, 37.0, 135.0, 290.0] {
                let camera = Camera::looking(eye, yaw, pitch);
                let view = View::new(&camera, 24, 18).unwrap();
                let caster = RayCaster::new(&pyramid, &view, &options);
                // The base pass's caster too.
                let lines = LineCaster::new(&pyramid, &view, &options);
                for allowance in [1, 2, 3, 5, 8, 40] {
                    let (mut probe, mut line_probe) = (PerRay::default(), PerRay::default());
                    for line in 0..view.lines() {
                        caster.line(line, &mut Discard, &mut probe, &mut Fixed(allowance));
                        probe.ray();
                        let limit = &mut Fixed(allowance);
                        lines.line_within(line, &mut Discard, &mut line_probe, limit);
                        line_probe.ray();
                    }
                    for (caster, probe) in [("per ray", probe), ("line", line_probe)] {
                        assert!(
                            probe.most() <= 4 * u64::from(allowance) + 2,
                            "{caster} caster, eye {eye:?} pitch {pitch} yaw {yaw} allowance {allowance}: {}",
                            probe.most()
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn an_allowance_past_i32_max_is_no_limit() {
        // Hills under a low, shallow eye: long rays, sky above them.
        let side = 64u32;
        let heights: vec::Vec<u16> = (0..side * side)
            .map(|i| ((i % side * 5 + i / side * 3) % 40) as u16 * 16)
            .collect();
        let colors: vec::Vec<crate::color::Rgb> = (0..side * side)
            .map(|i| [(i % 251) as u8, (i % 97) as u8, 60])
            .collect();
        let terrain = Terrain::new(side, side, &heights, &colors).unwrap();
        let (h, c, b) = pyramid_storage(&terrain);
        let pyramid = Pyramid::new(terrain, &h, &c, &b).unwrap();
        let options = RenderOptions::default();
        let camera = Camera::looking([3.0, 5.0, 50.0], 40.0, 4.0);
        let view = View::new(&camera, 32, 24).unwrap();
        let caster = RayCaster::new(&pyramid, &view, &options);
        // u32::MAX is what the plain render's allowances give: no limit.
        let render_with = |allowance: u32| {
            let mut pixels = [[0u8; 3]; 32 * 24];
            let mut sink = crate::Framebuffer::new(&mut pixels, 32, 24).unwrap();
            for line in 0..view.lines() {
                let mut probe = crate::NoProbe;
                caster.line(line, &mut sink, &mut probe, &mut Fixed(allowance));
            }
            pixels
        };
        let unlimited = render_with(u32::MAX);
        assert!(unlimited.contains(&options.sky));
        assert!(unlimited.iter().any(|p| *p != options.sky));
        for allowance in [i32::MAX as u32, i32::MAX as u32 + 1, u32::MAX - 1] {
            assert!(render_with(allowance) == unlimited, "allowance {allowance}");
        }
        // The line caster alike, against its plain render.
        let lines = LineCaster::new(&pyramid, &view, &options);
        let render_lines_with = |allowance: Option<u32>| {
            let mut pixels = [[0u8; 3]; 32 * 24];
            let mut sink = crate::Framebuffer::new(&mut pixels, 32, 24).unwrap();
            for line in 0..view.lines() {
                let mut probe = crate::NoProbe;
                match allowance {
                    Some(a) => lines.line_within(line, &mut sink, &mut probe, &mut Fixed(a)),
                    None => lines.line(line, &mut sink, &mut probe),
                }
            }
            pixels
        };
        let plain = render_lines_with(None);
        for allowance in [i32::MAX as u32, u32::MAX - 1, u32::MAX] {
            assert!(
                render_lines_with(Some(allowance)) == plain,
                "line caster, allowance {allowance}"
            );
        }
        // With no steps at all, every pixel repeats the one before it:
        // the sky's.
        assert!(render_lines_with(Some(0)).iter().all(|p| *p == options.sky));
    }

    fn cost(base_cost: u64, coarse_lines: u32) -> FrameCost {
        FrameCost {
            cost: base_cost,
            work: FrameWork::default(),
            budget: 1000,
            base_cost,
            base_work: FrameWork::default(),
            level_bias: U8F8::ONE,
            coarse_lines,
            refined_lines: 0,
            filled_rays: 0,
        }
    }

    #[test]
    fn the_bias_follows_the_base_pass_within_its_limits() {
        // Between half and three quarters of the budget: unchanged.
        assert_eq!(next_bias(256, &cost(750, 0)), 256);
        assert_eq!(next_bias(256, &cost(600, 0)), 256);
        // Twice the target: twice as coarse.
        assert_eq!(next_bias(256, &cost(1500, 0)), 512);
        // Far over: at most four times.
        assert_eq!(next_bias(256, &cost(100_000, 0)), 1024);
        // Under half: an eighth finer a frame, never below the finest.
        assert_eq!(next_bias(256, &cost(10, 0)), 224);
        assert_eq!(next_bias(64, &cost(10, 0)), 64);
        // A frame that had to go coarse doubles it at least.
        assert_eq!(next_bias(256, &cost(750, 3)), 512);
        // Never past the coarsest.
        assert_eq!(next_bias(64 << 8, &cost(5000, 1)), 64 << 8);
    }

    #[test]
    fn bit_reversed_order_visits_each_line_once_spread_out() {
        for count in [0u32, 1, 2, 3, 7, 8, 9, 100, 1023, 1025] {
            let order: vec::Vec<u32> = BitReversed::new(count).collect();
            let mut sorted = order.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..count).collect::<vec::Vec<_>>(), "{count}");
        }
        let first: vec::Vec<u32> = BitReversed::new(8).take(4).collect();
        assert_eq!(first, [0, 4, 2, 6]);
    }

    /// Calls `test` with a pyramid over [`hills`].
    fn on_hills(test: impl FnOnce(&Pyramid<'_>)) {
        let (heights, colors) = hills();
        let terrain = Terrain::new(64, 64, &heights, &colors).unwrap();
        let (h, c, b) = pyramid_storage(&terrain);
        test(&Pyramid::new(terrain, &h, &c, &b).unwrap());
    }

    /// A flat-ish scene and a view of it, seen from `pitch`.
    fn hills() -> (vec::Vec<u16>, vec::Vec<crate::color::Rgb>) {
        let side = 64u32;
        let heights = (0..side * side)
            .map(|i| ((i % side * 5 + i / side * 3) % 40) as u16 * 16)
            .collect();
        let colors = (0..side * side)
            .map(|i| [(i % 251) as u8, (i % 97) as u8, 60])
            .collect();
        (heights, colors)
    }

    /// Each pixel's last color, and how many times it was written.
    struct Recorded {
        width: u32,
        colors: vec::Vec<crate::color::Rgb>,
        writes: vec::Vec<u32>,
    }

    impl Recorded {
        fn new(view: &View) -> Self {
            let pixels = (view.width() * view.height()) as usize;
            Self {
                width: view.width(),
                colors: vec![[0; 3]; pixels],
                writes: vec![0; pixels],
            }
        }
    }

    impl Sink for Recorded {
        fn put(&mut self, x: u32, y: u32, sample: crate::Sample) {
            let at = (y * self.width + x) as usize;
            self.colors[at] = sample.color;
            self.writes[at] += 1;
        }
    }

    #[test]
    fn a_bias_range_holds_the_levels_whatever_the_budget() {
        on_hills(|pyramid| {
            let options = RenderOptions::default();
            let view = View::new(&Camera::looking([3.0, 5.0, 80.0], 40.0, 20.0), 32, 24).unwrap();
            let budget = Governor::on_board(0).least_cost(&view, &options);
            let two = U8F8::from_num(2);
            let mut free = Governor::on_board(budget);
            let mut held = Governor::on_board(budget).with_bias_range(U8F8::ONE, two);
            for _ in 0..6 {
                for governor in [&mut free, &mut held] {
                    let cost = governor.render(
                        pyramid,
                        &view,
                        &options,
                        &mut Discard,
                        &mut crate::NoProbe,
                    );
                    assert!(cost.cost <= budget.max(governor.least_cost(&view, &options)));
                }
                assert!(held.level_bias() <= two);
            }
            assert!(free.level_bias() > two, "{:?}", free.level_bias());
            // A budget to spare: the bias goes no finer than the range.
            let mut free = Governor::on_board(budget * 20);
            let mut held = Governor::on_board(budget * 20).with_bias_range(U8F8::ONE, two);
            for _ in 0..12 {
                for governor in [&mut free, &mut held] {
                    governor.render(pyramid, &view, &options, &mut Discard, &mut crate::NoProbe);
                }
                assert!(held.level_bias() >= U8F8::ONE);
            }
            assert!(free.level_bias() < U8F8::ONE, "{:?}", free.level_bias());
            // Past the limits, the limits.
            let finest = Governor::on_board(1).with_bias_range(U8F8::ZERO, U8F8::ZERO);
            assert_eq!(finest.level_bias(), Governor::MIN_BIAS);
        });
    }

    #[test]
    fn shares_of_a_frame_each_keep_their_budget_and_together_draw_it() {
        on_hills(|pyramid| {
            let options = RenderOptions::default();
            for pitch in [5.0, 30.0, 90.0] {
                let view =
                    View::new(&Camera::looking([3.0, 5.0, 80.0], 40.0, pitch), 33, 24).unwrap();
                assert!(LineShare::new(&view, 3, 3).is_none());
                let shares: vec::Vec<LineShare> = (0..3)
                    .map(|i| LineShare::new(&view, i, 3).unwrap())
                    .collect();
                let all = LineShare::all(&view);
                assert_eq!(
                    shares.iter().map(LineShare::pixels).sum::<u64>(),
                    all.pixels()
                );
                assert_eq!(
                    shares.iter().map(|s| s.line_count(&view)).sum::<u32>(),
                    view.lines()
                );
                // Without a limit, every line ends refined twice whoever
                // renders it: the shares draw the whole frame's image.
                let mut whole = Recorded::new(&view);
                Governor::new(u64::MAX / 4, Prices::BOARD).render(
                    pyramid,
                    &view,
                    &options,
                    &mut whole,
                    &mut crate::NoProbe,
                );
                let mut together = Recorded::new(&view);
                for share in shares.iter().rev() {
                    Governor::new(u64::MAX / 4, Prices::BOARD).render_share(
                        pyramid,
                        &view,
                        &options,
                        share,
                        &mut together,
                        &mut crate::NoProbe,
                    );
                }
                assert!(together.colors == whole.colors, "pitch {pitch}");
                assert!(together.writes == whole.writes, "pitch {pitch}");
                // Each share within its own budget, every pixel written, the
                // same cost and image again on a second run.
                let least: u64 = shares
                    .iter()
                    .map(|s| Governor::on_board(0).least_share_cost(&view, &options, s))
                    .sum();
                assert_eq!(least, Governor::on_board(0).least_cost(&view, &options));
                let mut runs = vec::Vec::new();
                for _ in 0..2 {
                    let mut frame = Recorded::new(&view);
                    let mut costs = vec::Vec::new();
                    for share in &shares {
                        let budget =
                            2 * Governor::on_board(0).least_share_cost(&view, &options, share);
                        let cost = Governor::on_board(budget).render_share(
                            pyramid,
                            &view,
                            &options,
                            share,
                            &mut frame,
                            &mut crate::NoProbe,
                        );
                        assert!(cost.cost <= budget, "pitch {pitch}: {cost:?}");
                        assert_eq!(
                            cost.work.lines,
                            u64::from(share.line_count(&view) + cost.refined_lines)
                        );
                        costs.push(cost);
                    }
                    assert!(frame.writes.iter().all(|&n| n >= 1), "pitch {pitch}");
                    runs.push((frame.colors, costs));
                }
                assert!(runs[0] == runs[1], "pitch {pitch}");
            }
        });
    }

    #[test]
    fn a_far_hits_color_squares_are_counted_and_priced_apart() {
        // A square is a color fetch too: its price is on top.
        let mut probe = crate::CountingProbe::default();
        probe.color(0, 7);
        probe.color_square(1, 3);
        probe.color_square(2, 1);
        assert_eq!((probe.color_fetches, probe.color_squares), (3, 2));
        let work = FrameWork::counted(&probe, 0, 0);
        let prices = Prices {
            per_color: 3,
            per_color_square: 10,
            ..Prices::STEPS
        };
        assert_eq!(prices.of(&work), 3 * 3 + 2 * 10);
    }

    #[test]
    fn a_frame_spends_its_budget_and_never_more() {
        on_hills(|pyramid| {
            let options = RenderOptions::default();
            for pitch in [0.0, 5.0, 30.0, 90.0] {
                let view =
                    View::new(&Camera::looking([3.0, 5.0, 80.0], 40.0, pitch), 32, 24).unwrap();
                // A level view's base pass writes straight pixels.
                let straight = if pitch == 0.0 { 32 * 24 } else { 0 };
                // The least a frame costs: every pixel written (a level
                // view's at the straight price), line and ray set up.
                let least_work = FrameWork {
                    pixels: 32 * 24,
                    lines: u64::from(view.lines()),
                    rays: 32 * 24,
                    straight_pixels: straight,
                    ..FrameWork::default()
                };
                assert_eq!(
                    Governor::on_board(0).least_cost(&view, &options),
                    Prices::BOARD_LINES.of(&least_work),
                    "pitch {pitch}"
                );
                let mut probe = crate::CountingProbe::default();
                let mut plain = Governor::new(u64::MAX / 4, Prices::BOARD);
                let unlimited = plain.render(pyramid, &view, &options, &mut Discard, &mut probe);
                assert!(unlimited.filled_rays == 0 && unlimited.coarse_lines == 0);
                // Without a limit, both rounds refine every line.
                assert_eq!(unlimited.refined_lines, 2 * view.lines(), "pitch {pitch}");
                let mut refined_twice = false;
                for share in [1u64, 3, 5, 8, 13] {
                    // From the base pass's cost up: the refinement fills it.
                    let budget =
                        plain.least_cost(&view, &options) + unlimited.base_cost * share / 2;
                    let mut governor = Governor::new(budget, Prices::BOARD);
                    let mut probe = crate::CountingProbe::default();
                    let cost = governor.render(pyramid, &view, &options, &mut Discard, &mut probe);
                    assert!(cost.cost <= budget, "pitch {pitch}: {cost:?}");
                    assert!(
                        cost.refined_lines > 0 || share == 1,
                        "pitch {pitch}: {cost:?}"
                    );
                    assert_eq!(cost.work.steps, probe.steps);
                    assert_eq!(cost.cost, Prices::BOARD.of(&cost.work));
                    // The meter counts what the probe does; a refined pixel
                    // is written and a refined line set up again.
                    let counted = FrameWork::counted(
                        &probe,
                        cost.work.pixels,
                        u64::from(view.lines()) + u64::from(cost.refined_lines),
                    );
                    let counted = FrameWork {
                        straight_pixels: straight,
                        ..counted
                    };
                    assert_eq!(counted, cost.work, "pitch {pitch} share {share}");
                    let lines = u64::from(view.lines());
                    if cost.base_cost * 2 < budget {
                        // Unless both rounds refined every line, the budget is
                        // spent to within a line's and a pixel's most cost of
                        // the round it stopped in.
                        let refined = u64::from(cost.refined_lines);
                        let pixel_most = RefineAllowances {
                            meter: &Meter::new(Prices::BOARD, pyramid.top()),
                            budget,
                            filled: 0,
                            most_rays: if refined >= lines { 8 } else { 4 },
                        }
                        .pixel_most();
                        assert!(
                            cost.cost + pixel_most + u64::from(Prices::BOARD.per_line) >= budget
                                || refined == 2 * lines,
                            "pitch {pitch} share {share}: {cost:?}"
                        );
                    }
                    refined_twice |= u64::from(cost.refined_lines) > lines;
                }
                assert!(
                    refined_twice,
                    "pitch {pitch}: no budget reached the second round"
                );
                // On the board's two prices: the base pass at its own, the
                // refinement at the per-ray path's, within the budget.
                let budget = 3 * Governor::on_board(0).least_cost(&view, &options);
                let cost = Governor::on_board(budget).render(
                    pyramid,
                    &view,
                    &options,
                    &mut Discard,
                    &mut crate::NoProbe,
                );
                assert!(cost.refined_lines > 0 && cost.cost <= budget, "{cost:?}");
                assert_eq!(cost.base_cost, Prices::BOARD_LINES.of(&cost.base_work));
                assert_eq!(
                    cost.cost,
                    cost.base_cost + Prices::BOARD.of(&cost.refined_work())
                );
            }
        });
    }
}
