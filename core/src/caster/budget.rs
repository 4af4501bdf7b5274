//! Frames that keep a step budget.
//!
//! A deterministic image generator never varies its frame time (Cosman &
//! Grange); Cohen-Or tuned the pixel-to-voxel ratio by hand to get there.
//! The [`Governor`] does it per frame:
//!
//! 1. **Prediction.** It renders with the level bias (the pixel-to-voxel
//!    ratio of [`Resolution::Multi`]) that the frames before suggest: up
//!    fast when a frame took more than three quarters of the budget, down
//!    slowly when it took less than half.
//! 2. **Correction.** Once a quarter of the frame's rays are cast, if the
//!    steps so far project past the budget, the frame's remaining lines are
//!    rendered at the coarsest bias: coarser, rather than late.
//! 3. **Guarantee.** Before each ray the budget left is turned into an
//!    allowance `n` with `4n + 2` no more than what is left (a ray cut short
//!    is shaded where it stopped); with fewer than six steps left a pixel
//!    repeats the ray before it on its line. So a frame never takes more
//!    steps than its budget, whatever the terrain (tested over 10 000
//!    frames).
//!
//! Everything is integer arithmetic on step counts: the same flight gives
//! the same choices on every machine.
//!
//! ```
//! use terracast::{render, Camera, CountingProbe, Framebuffer, Governor, Pyramid, RenderOptions, Terrain, View};
//!
//! let heights: [u16; 64] = core::array::from_fn(|i| ((i % 8) * (i / 8)) as u16 * 8);
//! let terrain = Terrain::new(8, 8, &heights, &[[90, 140, 60]; 64])?;
//! let pyramid = Pyramid::flat(terrain);
//! let view = View::new(&Camera::looking([1.0, 1.0, 40.0], 45.0, 30.0), 16, 12)?;
//! let mut pixels = [[0u8; 3]; 16 * 12];
//! let mut governor = Governor::new(100);
//! for _ in 0..3 {
//!     let mut frame = Framebuffer::new(&mut pixels, 16, 12)?;
//!     let cost = governor.render(&pyramid, &view, &RenderOptions::default(), &mut frame, &mut CountingProbe::default());
//!     assert!(cost.steps <= cost.budget);
//! }
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

use super::ray_caster::{Allowances, RayCaster};
use super::{RenderOptions, Resolution};
use crate::probe::Probe;
use crate::sink::Sink;
use crate::surface::Surface;
use crate::view::View;
use core::cell::Cell;
use fixed::types::U8F8;

/// What a budgeted frame did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameCost {
    /// Steps taken: walk steps and bound tests, as a probe counts them.
    pub steps: u64,
    /// The frame's budget; `steps` never exceeds it.
    pub budget: u64,
    /// The level bias (pixel-to-voxel ratio) the frame began with.
    pub level_bias: U8F8,
    /// Lines finished at the coarsest bias ([`Governor::MAX_BIAS`])
    /// because the frame was heading past its budget.
    pub coarse_lines: u32,
    /// Rays that found no budget left and repeat the ray before them.
    pub filled_rays: u32,
}

/// A per-frame step budget and the level bias that keeps it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Governor {
    budget: u64,
    /// The level bias for the next frame, U8.8 bits.
    bias: u16,
}

impl Governor {
    /// The finest level bias the governor uses: a voxel a quarter pixel wide.
    pub const MIN_BIAS: U8F8 = U8F8::from_bits(64);
    /// The coarsest: a voxel 64 pixels wide.
    pub const MAX_BIAS: U8F8 = U8F8::from_bits(64 << 8);

    /// A governor for frames of at most `budget_steps` steps, starting at a
    /// bias of 1.
    pub const fn new(budget_steps: u64) -> Self {
        Self {
            budget: budget_steps,
            bias: 1 << 8,
        }
    }

    /// Steps a frame may take.
    pub fn budget(&self) -> u64 {
        self.budget
    }

    /// The level bias the next frame starts with.
    pub fn level_bias(&self) -> U8F8 {
        U8F8::from_bits(self.bias)
    }

    /// Renders `view` within the budget (with `options`, its resolution
    /// replaced by the pyramid's levels at the governor's bias), then
    /// chooses the next frame's bias from this frame's steps.
    pub fn render<T: Surface + ?Sized, S: Sink, P: Probe>(
        &mut self,
        surface: &T,
        view: &View,
        options: &RenderOptions,
        sink: &mut S,
        probe: &mut P,
    ) -> FrameCost {
        let bias = self.bias;
        let coarse_bias = Self::MAX_BIAS.to_bits();
        let at = |bits: u16| RenderOptions {
            resolution: Resolution::Multi {
                pixel_to_voxel: U8F8::from_bits(bits),
            },
            ..*options
        };
        let (fine, coarse) = (at(bias), at(coarse_bias));
        let (fine_caster, coarse_caster) = (
            RayCaster::new(surface, view, &fine),
            RayCaster::new(surface, view, &coarse),
        );
        let rays_total = u64::from(view.width())
            * u64::from(view.height())
            * u64::from(options.vertical_samples.count());
        let meter = Meter::default();
        let mut metered = Metered {
            inner: probe,
            meter: &meter,
        };
        let mut allowances = Budget {
            meter: &meter,
            budget: self.budget,
            filled: 0,
        };
        let mut coarse_lines = 0;
        for line in 0..view.lines() {
            // Projected past the budget: the rest goes coarser.
            let (rays, steps) = (meter.rays.get(), meter.steps.get());
            let heading_over = coarse_lines > 0
                || (rays >= rays_total / 4
                    && u128::from(steps) * u128::from(rays_total)
                        > u128::from(self.budget) * u128::from(rays));
            let caster = if heading_over {
                coarse_lines += 1;
                &coarse_caster
            } else {
                &fine_caster
            };
            caster.line(line, sink, &mut metered, &mut allowances);
        }
        let cost = FrameCost {
            steps: meter.steps.get(),
            budget: self.budget,
            level_bias: U8F8::from_bits(bias),
            coarse_lines,
            filled_rays: allowances.filled,
        };
        self.bias = next_bias(bias, &cost);
        cost
    }
}

/// The next frame's bias. Over three quarters of the budget, scale it by
/// the steps over that target (at most ×4 a frame: the steps fall about
/// inversely with the bias); at least double it after a frame that went
/// coarse or ran dry; under half the budget, refine it by an eighth a
/// frame, so that a quiet stretch does not swing it back too fast.
fn next_bias(bias: u16, cost: &FrameCost) -> u16 {
    let target = (cost.budget - cost.budget / 4).max(1);
    let bias64 = u64::from(bias);
    let mut next = if cost.steps > target {
        (bias64 * cost.steps / target).min(bias64 * 4)
    } else if cost.steps < cost.budget / 2 {
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

/// Rays and steps so far in a frame.
#[derive(Debug, Default)]
struct Meter {
    rays: Cell<u64>,
    steps: Cell<u64>,
}

/// A probe that counts into a [`Meter`] and passes every event on.
struct Metered<'a, P> {
    inner: &'a mut P,
    meter: &'a Meter,
}

impl<P: Probe> Probe for Metered<'_, P> {
    #[inline(always)]
    fn visit(&mut self, level: u8, voxel: usize) {
        self.meter.steps.set(self.meter.steps.get() + 1);
        self.inner.visit(level, voxel);
    }
    #[inline(always)]
    fn bound(&mut self, level: u8, cell: usize) {
        self.meter.steps.set(self.meter.steps.get() + 1);
        self.inner.bound(level, cell);
    }
    #[inline(always)]
    fn color(&mut self, level: u8, voxel: usize) {
        self.inner.color(level, voxel);
    }
    #[inline(always)]
    fn color_square(&mut self, level: u8, corner: usize) {
        self.inner.color_square(level, corner);
    }
    #[inline(always)]
    fn hit(&mut self, level: u8) {
        self.inner.hit(level);
    }
    #[inline(always)]
    fn ray(&mut self) {
        self.meter.rays.set(self.meter.rays.get() + 1);
        self.inner.ray();
    }
}

/// Each ray's allowance from the budget left: a ray with allowance `n`
/// takes at most `4n + 2` steps.
struct Budget<'a> {
    meter: &'a Meter,
    budget: u64,
    filled: u32,
}

impl Allowances for Budget<'_> {
    fn next(&mut self) -> u32 {
        let left = self.budget.saturating_sub(self.meter.steps.get());
        if left < 6 {
            self.filled += 1;
            return 0;
        }
        ((left - 2) / 4).min(u64::from(u32::MAX - 1)) as u32
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
                for allowance in [1, 2, 3, 5, 8, 40] {
                    let mut probe = PerRay::default();
                    for line in 0..view.lines() {
                        caster.line(line, &mut Discard, &mut probe, &mut Fixed(allowance));
                        probe.ray();
                    }
                    assert!(
                        probe.most() <= 4 * u64::from(allowance) + 2,
                        "eye {eye:?} pitch {pitch} yaw {yaw} allowance {allowance}: {}",
                        probe.most()
                    );
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
    }

    fn cost(steps: u64, coarse_lines: u32) -> FrameCost {
        FrameCost {
            steps,
            budget: 1000,
            level_bias: U8F8::ONE,
            coarse_lines,
            filled_rays: 0,
        }
    }

    #[test]
    fn the_bias_follows_the_steps_within_its_limits() {
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
}
