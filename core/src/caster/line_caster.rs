//! The per-line caster on the pyramid: what is the same for every ray of
//! an image line is set up once for the line, and a ray differs from the
//! one before it by its slope.
//!
//! - **Once a frame**: the surface's level grids, the level plan (where
//!   height levels and color levels begin, by the pixel-to-voxel ratio and
//!   the terrain fit) and the sky.
//! - **Once a line**: its vertical plane ([`Plane`]), the index steps of
//!   each level's grid, and the level schedule along the major axis: level
//!   `l` begins at the first sample of its grid (an even step of level
//!   `l − 1`, Cohen-Or §2) at or past `2^(l−1)` times the reach: the
//!   depth where a voxel gets narrower than a pixel, along the major axis.
//!   That distance depends on a ray's major-axis component, which changes
//!   along the line, so a line is cast in stretches of rays whose
//!   components are within a third of each other, scheduled once a
//!   stretch (see [`LineCaster::line`]). Every ray of a stretch steps on
//!   the same levels at the same samples.
//! - **Once a ray**: its slope (one division) and its height where the ray
//!   before it hit. It resumes there: it is no lower than that ray at any
//!   sample, and both step on the same levels, so it is above the surface
//!   wherever that ray was (Cohen-Or Figure 7). The heights of the hit
//!   sample and of the sample before it are at hand. A line's first ray
//!   skips through the pyramid's height bounds to where it may hit.
//! - **Once a step**: the two heights across the minor grid line of the
//!   step's level, blended by shift and mask, compared with the ray.
//! - **Once a hit**: the crossing placed between the last sample above and
//!   the hit by their clearances (one division). Near the eye its color is
//!   level 0's, both grid lines' blended by the subvoxel weights; past the
//!   ray's color reach (or on a coarse height level) it comes from the two
//!   levels the pixel's footprint brackets, blended by depth
//!   ([`mod@super::footprint_color`]'s levels, the soft transition).
//! - **Sky** above a line's last hit is written without rays.
//!
//! [`super::render`] takes this path for [`Coherence::AcrossLevels`] with
//! one ray a pixel (the defaults; either shading); at single
//! resolution its image is the one [`Coherence::Exact`] gives, bit for bit.
//!
//! [`Coherence::AcrossLevels`]: super::Coherence::AcrossLevels
//! [`Coherence::Exact`]: super::Coherence::Exact

use super::first_hit::first_hit;
use super::footprint_color::{color_level, levels_color, narrower_side};
use super::ray_caster::{Allowances, Unlimited};
use super::walk::{along_weight, lerp, line_color};
use super::{
    crossing_fraction, sky, Coherence, Frame, HeightPath, RenderOptions, Shading, VerticalSamples,
};
use crate::color::Rgb;
use crate::config::{COORD_FRAC_BITS, HEIGHT_FRAC_BITS, HEIGHT_WEIGHT_BITS, MAX_WALK_LEVEL};
use crate::divide::div_ceil;
use crate::probe::Probe;
use crate::surface::{Extent, Grid, Surface};
use crate::view::lines::{Line, LinePixels, OwnedPixels};
use crate::view::lod::LodPlan;
use crate::view::plane::{slope_quotient, Plane, DIRECTION_WORD_SHIFT};
use crate::view::words::saturate;
use crate::{LinePlane, Sample, Sink, View};

mod see_through;

use see_through::NearHit;
pub use see_through::{MAX_SEE_THROUGH, SEE_THROUGH_REACH};

/// Heights are U12.4; the walk compares them in Q16.
const HEIGHT_TO_Q16: u32 = COORD_FRAC_BITS - HEIGHT_FRAC_BITS;
const ONE: i64 = 1 << COORD_FRAC_BITS;
/// Levels a walk may step on: 0 to `MAX_WALK_LEVEL`.
const LEVELS: usize = MAX_WALK_LEVEL as usize + 1;

/// Whether [`super::render`] renders `options` with the line caster.
pub(crate) fn takes(options: &RenderOptions) -> bool {
    options.coherence == Coherence::AcrossLevels && options.vertical_samples == VerticalSamples::One
}

/// What every line of a frame shares.
pub(crate) struct LineCaster<'s, 'v, T: Surface + ?Sized + 's> {
    surface: &'s T,
    /// Each level's grid and row stride (level 0's past the surface's top,
    /// never stepped on).
    grids: [T::Grid<'s>; LEVELS],
    strides: [isize; LEVELS],
    view: &'v View,
    extent: Extent,
    /// The highest height, Q16: a rising ray above it sees the sky.
    highest: i64,
    plan: LodPlan,
    /// A line's first ray skips through the pyramid's height bounds.
    first_hit: bool,
    /// Each hit takes its nearest voxel's color ([`Shading::Nearest`]).
    nearest: bool,
    /// Each ray reads heights on its own path ([`HeightPath::Ray`]).
    own_path: bool,
    sky: Sample,
}

/// One line's walk through the grids.
struct LineWalk {
    plane: Plane,
    /// `plane.delta0`, in [0, 2^16).
    delta0: i32,
    /// `plane.minor_max` (below 2^31).
    minor_max: i32,
    /// The line's samples inside the map: `first..=last` (a map side is
    /// below 2^15 samples: the walk's positions are 32-bit, the word of
    /// the cores it runs on).
    first: i32,
    last: i32,
    /// `begins[l]`: the first sample of level `l`; `i32::MAX` past the
    /// line's last level.
    begins: [i32; LEVELS + 1],
    /// `ends[l]`: the last sample a step on level `l` may reach (before
    /// the next level begins, and inside the map).
    ends: [i32; LEVELS],
    /// Index change per major grid line and across a minor grid line, on
    /// each level.
    major_stride: [isize; LEVELS],
    across: [isize; LEVELS],
    /// Index change of one step on each level (a major grid line of the
    /// level, forward or back), and the minor coordinate's (Q16).
    step: [isize; LEVELS],
    minor_step: [i32; LEVELS],
}

impl LineWalk {
    /// Minor coordinate `minor` moved `aside` (Q16) across the line, kept
    /// inside the map (`Plane::minor_max`): minor coordinates are below
    /// 2^31 in Q16; their sum may not be, and saturates.
    #[inline(always)]
    fn aside(&self, minor: i32, aside: i32) -> i32 {
        let moved = minor.saturating_add(aside);
        // Inside is the rule: one unsigned compare finds it, where
        // `i32::clamp` is a call on the board.
        if moved as u32 <= self.minor_max as u32 {
            moved
        } else if moved < 0 {
            0
        } else {
            self.minor_max
        }
    }
}

/// What a ray's hit needs of the ray beyond its walk.
#[derive(Clone, Copy)]
struct HitRay {
    /// Height change a sample, Q16 (within `MAX_RAY_SLOPE` samples, below
    /// 2^29).
    dz: i32,
    /// Major-axis distance (Q16) where its colors leave level 0.
    color_reach: i64,
    /// Its colors' sideways drift (see [`Plane::drift`]; within 2^14).
    drift: i32,
}

/// What a far hit's color needs of the hit (see [`LineCaster::far_color`]).
struct Far {
    span: i32,
    above: Option<(i32, i32)>,
    below: i32,
    back: i32,
    distance: i32,
    drift: i32,
    color_reach: i64,
}

/// Where a line's walk is: a sample, its level and its blended height, and
/// the sample visited before it and its height (on its own level).
#[derive(Clone, Copy)]
struct At {
    k: i32,
    level: u8,
    /// The index of the sample's major grid line on its level, and its
    /// minor coordinate (Q16, world voxels, inside the map: below 2^31).
    index: isize,
    minor: i32,
    /// Q16; heights are U12.4, so below 2^28.
    height: i32,
    before_k: i32,
    before: Option<i32>,
}

impl At {
    /// Its sample: `(k, index, minor, level)`.
    fn here(&self) -> (i32, isize, i32, u8) {
        (self.k, self.index, self.minor, self.level)
    }

    /// The sample before it, where its height is known and was a step on
    /// the same level (the one its crossing is placed with).
    fn sample_before(&self, walk: &LineWalk) -> Option<(i32, isize, i32, u8)> {
        let l = usize::from(self.level);
        (self.before.is_some() && self.k - self.before_k == 1 << self.level).then(|| {
            (
                self.before_k,
                self.index - walk.step[l],
                self.minor - walk.minor_step[l],
                self.level,
            )
        })
    }
}

impl<'s, 'v, T: Surface + ?Sized> LineCaster<'s, 'v, T> {
    pub fn new(surface: &'s T, view: &'v View, options: &RenderOptions) -> Self {
        let frame = Frame::new(surface, view, options);
        let extent = surface.extent();
        let grids =
            core::array::from_fn(|l| surface.grid(l as u8).unwrap_or_else(|| surface.base()));
        let strides = core::array::from_fn(|l| surface.stride(l as u8).unwrap_or(1));
        Self {
            surface,
            grids,
            strides,
            view,
            extent,
            highest: i64::from(extent.max_height) << HEIGHT_TO_Q16,
            plan: frame.lod,
            first_hit: frame.first_hit,
            nearest: options.shading == Shading::Nearest,
            own_path: options.height_path == HeightPath::Ray,
            sky: sky(options),
        }
    }

    /// The walk of `line`'s rays: its plane and the index steps of each
    /// level's grid, with no levels scheduled yet (see
    /// [`LineCaster::schedule`]).
    fn line_walk(&self, line: &Line) -> LineWalk {
        let view = self.view;
        let plane = Plane::new(view, &self.extent, &line.reference).with_across(&view.across(line));
        // `Plane` keeps its samples inside the map, whose side is below 2^15.
        let (first, last) = (plane.first.max(0) as i32, plane.last as i32);
        let mut begins = [i32::MAX; LEVELS + 1];
        begins[0] = first;
        let x_major = plane.key.x_major;
        let major_stride = core::array::from_fn(|l| if x_major { 1 } else { self.strides[l] });
        let across = core::array::from_fn(|l| if x_major { self.strides[l] } else { 1 });
        let sign = if plane.key.forward { 1 } else { -1 };
        let step = major_stride.map(|stride| sign * stride);
        // |dminor| <= 2^16 and levels go to 14: within 2^30.
        let minor_step = core::array::from_fn(|l| (plane.dminor << l) as i32);
        LineWalk {
            ends: [last; LEVELS],
            delta0: plane.delta0 as i32,
            minor_max: plane.minor_max as i32,
            plane,
            first,
            last,
            begins,
            major_stride,
            across,
            step,
            minor_step,
        }
    }

    /// Schedules `walk`'s levels for a ray whose direction's major-axis
    /// component is `run`: level `l` begins at the first sample
    /// of its grid at or past `2^(l−1)` times the reach of `run`, and at
    /// or past level `l − 1`'s beginning (an even step of that level).
    #[inline(never)]
    fn schedule(&self, walk: &mut LineWalk, run: i64) {
        let plane = &walk.plane;
        // (The plan's top is the surface's, at most `MAX_WALK_LEVEL`.)
        let top = usize::from(self.plan.top);
        let reach = self.plan.height_reach(run);
        let mut level = 1;
        // Levels begin in order, each at or past the one below: the first
        // that begins past the line's last sample ends the schedule.
        while level <= top {
            let threshold = ((reach << (level - 1)) - plane.delta0 + ONE - 1) >> COORD_FRAC_BITS;
            let from = threshold.max(i64::from(walk.begins[level - 1]));
            let k = align_up(plane, from, level as u32);
            if k > i64::from(walk.last) {
                break;
            }
            walk.begins[level] = k as i32;
            level += 1;
        }
        walk.begins[level..].fill(i32::MAX);
        for (end, begins) in walk.ends.iter_mut().zip(&walk.begins[1..]) {
            *end = (begins - 1).min(walk.last);
        }
    }

    /// Renders image line `index` into `sink`.
    ///
    /// On the pyramid the line is walked in stretches whose rays' major-axis
    /// components lie within a third of the stretch's least (along a line
    /// they change steadily; at steep pitch by a large factor): a stretch
    /// schedules its levels for its least component, so each of its rays
    /// switches levels no farther than its own depth says, and no nearer
    /// than three quarters of that. A level is never read past where the
    /// ray's own schedule leaves it, so a tile footprint
    /// ([`crate::tiles::footprint`]), which holds every level from the
    /// eye out, holds what the stretch reads. A line's first ray walks
    /// from the eye, through the height bounds; a stretch's first ray
    /// starts where the stretch before left off; the others resume.
    pub fn line<S: Sink, P: Probe>(&self, index: u32, sink: &mut S, probe: &mut P) {
        self.line_within(index, sink, probe, &mut Unlimited);
    }

    /// Renders image line `index` as [`LineCaster::line`] does, each ray
    /// within the steps `allowances` gives it (see [`Allowances`]): a ray
    /// given `n` takes at most `4n + 2` (at most `2n` bound tests of the
    /// first hit, the rest stepping; one cut short is shaded at the
    /// sample where it stopped), a ray given none repeats the pixel
    /// before it.
    pub fn line_within<S: Sink, P: Probe, A: Allowances>(
        &self,
        index: u32,
        sink: &mut S,
        probe: &mut P,
        allowances: &mut A,
    ) {
        // Most lines of a rolled or steep view's outer sectors miss the
        // image: neither the line, its plane nor its rays are set up.
        if self.view.line_misses_image(index) {
            return;
        }
        let Some(line) = self.view.line(index) else {
            return;
        };
        let pixels = line.pixels(self.view.height());
        if pixels.no_rows_left() {
            return;
        }
        let a = allowances;
        match (self.nearest, self.own_path) {
            (false, false) => {
                self.cast_line_pixels::<_, _, _, false, false>(&line, pixels, sink, probe, a)
            }
            (true, false) => {
                self.cast_line_pixels::<_, _, _, true, false>(&line, pixels, sink, probe, a)
            }
            (false, true) => {
                self.cast_line_pixels::<_, _, _, false, true>(&line, pixels, sink, probe, a)
            }
            (true, true) => {
                self.cast_line_pixels::<_, _, _, true, true>(&line, pixels, sink, probe, a)
            }
        }
    }

    /// [`LineCaster::cast`] with the line's pixels stepped the cheapest
    /// way they allow: a row at a time where the line runs straight along
    /// the axis (a level view's columns), else with the pixel window in
    /// 32-bit words where the line's values fit.
    #[inline(always)]
    fn cast_line_pixels<
        S: Sink,
        P: Probe,
        A: Allowances,
        const NEAREST: bool,
        const OWN_PATH: bool,
    >(
        &self,
        line: &Line,
        pixels: OwnedPixels,
        sink: &mut S,
        probe: &mut P,
        allowances: &mut A,
    ) {
        let a = allowances;
        if let Some(px) = pixels.straightened() {
            // Pixels centered on their line (a level view's columns): each
            // ray's own path is the line's, and the line's walk reads it.
            if px.centered() {
                return self.cast::<_, _, _, _, NEAREST, false>(line, px, sink, probe, a);
            }
            return self.cast::<_, _, _, _, NEAREST, OWN_PATH>(line, px, sink, probe, a);
        }
        match pixels.narrowed() {
            Ok(px) => self.cast::<_, _, _, _, NEAREST, OWN_PATH>(line, px, sink, probe, a),
            Err(px) => self.cast::<_, _, _, _, NEAREST, OWN_PATH>(line, px, sink, probe, a),
        }
    }

    /// Casts `line`'s rays through `pixels`, its pixels, into `sink`; with
    /// `OWN_PATH` each ray reads heights on its own path.
    /// Out of line: the loop's state then has the registers to itself.
    #[inline(never)]
    fn cast<
        L: LinePixels,
        S: Sink,
        P: Probe,
        A: Allowances,
        const NEAREST: bool,
        const OWN_PATH: bool,
    >(
        &self,
        line: &Line,
        mut pixels: L,
        sink: &mut S,
        probe: &mut P,
        allowances: &mut A,
    ) {
        let view = self.view;
        let mut walk = self.line_walk(line);
        let levels = self.plan.top > 0;
        let [first_run, last_run] = line
            .end_directions()
            .map(|d| View::slope(&d, &walk.plane).1);
        let mut at: Option<At> = None;
        // The major-axis components the stretch's levels hold: from its
        // least, which they are scheduled by, to a third more.
        let (mut stretch_run, mut stretch_most) = (0, -1);
        let mut previous_dz = i32::MIN;
        // On its own path: the drift `at`'s heights were read with.
        let mut read_drift = 0;
        // The direction's major-axis component, which a ray's set-up needs
        // with its center's vertical one.
        let axis = [if walk.plane.key.x_major { 0 } else { 1 }];
        // Under a limit: the pixel a ray with no steps left repeats.
        let mut previous = self.sky;
        sink.line(&LinePlane {
            // Within ±1 (`Plane::dminor`).
            dminor: walk.plane.dminor as i32,
        });
        if walk.first <= walk.last {
            for pixel in pixels.by_ref() {
                probe.ray();
                // Height fetches left to this ray's start and climb (its
                // first hit's bound tests are `allowance` rounds).
                let allowance = allowances.next();
                if A::LIMITED && allowance == 0 {
                    sink.put(pixel.x, pixel.y, previous);
                    continue;
                }
                let mut fetches = A::Fetches::for_allowance(allowance);
                // The direction's words: exactly `Line::pixel_direction`'s
                // components shifted, so the slope, the run and the drift
                // are `View::slope`'s and `Plane::drift`'s.
                let [major] = line.direction_words(pixel.along, axis);
                let up = line.up_word(&pixel);
                let run_word = if walk.plane.key.forward {
                    major
                } else {
                    -major
                }
                .max(0);
                let dz = i64::from(slope_quotient(up, run_word as u32));
                let run = i64::from(run_word) << DIRECTION_WORD_SHIFT;
                // Within `MAX_RAY_SLOPE` samples a sample, below 2^29.
                let dz = dz as i32;
                // A ray lower than the one before (directions are linear
                // along the line, so only next to the vanishing point,
                // where a ray's horizontal part rounds to nothing) cannot
                // resume where it hit. A ray outside the
                // stretch's levels starts a stretch where the stretch
                // before left off: it is above that stretch's surface
                // wherever the stretch's last ray was (the approximation
                // `AcrossLevels` makes: the surfaces differ where the levels
                // do).
                let mut resume_from = None;
                if dz < previous_dz {
                    at = None;
                } else if levels && !(stretch_run <= run && run <= stretch_most) {
                    resume_from = at.map(|at| at.before_k);
                    at = None;
                }
                previous_dz = dz;
                let dz = i64::from(dz);
                // How far aside of the line this ray reads heights: its
                // drift (within 2^14, `Plane::drift_of`) on its own path.
                let height_drift = if OWN_PATH {
                    walk.plane.full_drift_of_word(run_word, pixel.offset) as i32
                } else {
                    0
                };
                let z0 = view.eye[2].to_bits() + ((walk.plane.delta0 * dz) >> COORD_FRAC_BITS);
                // A ray resuming where the ray before it hit (not one just
                // started) reads that sample again on its own path, unless
                // the ray before drifted as far (a level view's rays do not
                // drift at all).
                let read_again = OWN_PATH && at.is_some() && height_drift != read_drift;
                read_drift = height_drift;
                if at.is_none() {
                    if levels {
                        // Along the line the component rises (or falls)
                        // steadily: this ray's is the stretch's least (or
                        // largest, and the least is a quarter less, or the
                        // line's last).
                        stretch_run = if last_run > first_run {
                            run
                        } else {
                            last_run.max(run - run / 4).min(run)
                        };
                        stretch_most = stretch_run + stretch_run / 3;
                        self.schedule(&mut walk, stretch_run);
                    }
                    at = resume_from
                        .or_else(|| {
                            let d = line.pixel_direction(&pixel);
                            self.clear_until(&walk, &d, allowance, probe)
                        })
                        .and_then(|from| {
                            self.start::<_, OWN_PATH>(&walk, from, z0, dz, height_drift, probe)
                        });
                    fetches.take();
                }
                let hit = at.as_mut().and_then(|at| {
                    // Resuming where the ray before it hit, a ray that
                    // drifts otherwise compares with that sample's height
                    // read again on its own path.
                    let resumed_at = at.k;
                    if read_again {
                        at.height =
                            self.height_at::<P, true>(&walk, at.here(), height_drift, probe)?;
                    }
                    let z = self.climb::<_, _, OWN_PATH>(
                        &walk,
                        at,
                        (z0, dz),
                        height_drift,
                        &mut fetches,
                        probe,
                    )?;
                    // Hit where it resumed, the ray places its crossing
                    // with the sample before too, read again on its own
                    // path; a ray that stepped read that sample itself.
                    if read_again && at.k == resumed_at {
                        if let Some(before) = at.sample_before(&walk) {
                            let height =
                                self.height_at::<P, true>(&walk, before, height_drift, probe)?;
                            at.before = Some(height);
                        }
                    }
                    let ray = HitRay {
                        dz: dz as i32,
                        color_reach: self.plan.color_reach(run),
                        // Within 2^14 (`Plane::drift_of`).
                        drift: if OWN_PATH {
                            height_drift
                        } else {
                            walk.plane.drift_of_word(run_word, pixel.offset) as i32
                        },
                    };
                    Some(self.hit::<P, NEAREST>(&walk, at, z, &ray, probe))
                });
                match hit {
                    Some(sample) => {
                        if A::LIMITED {
                            previous = sample;
                        }
                        sink.put_ray(pixel.x, pixel.y, sample, dz as i32)
                    }
                    None => {
                        // It left the terrain: so does every ray after it.
                        sink.put(pixel.x, pixel.y, self.sky);
                        break;
                    }
                }
            }
        }
        // The sky above the line's last hit: no rays (and no pixels to
        // put where the sink has the sky already).
        if !sink.sky_is_drawn() {
            pixels.for_each_position(|x, y| sink.put(x, y, self.sky));
        }
    }

    /// Where a walk from the eye starts for a ray whose height at sample 0
    /// is `z0` (Q16), `dz` a sample, known to clear the surface before
    /// sample `from`: the last sample of its level's grid before `from`
    /// and before it sinks below the highest terrain, with nothing known
    /// before it. The samples before it are above the terrain, and so
    /// outside the slab a tile footprint loads. `None`
    /// when the ray never comes down to the terrain or the map has no
    /// height there.
    #[inline(never)]
    fn start<P: Probe, const OWN_PATH: bool>(
        &self,
        walk: &LineWalk,
        from: i32,
        z0: i64,
        dz: i64,
        drift: i32,
        probe: &mut P,
    ) -> Option<At> {
        let mut k = from.max(walk.first);
        if z0 + i64::from(k) * dz > self.highest {
            if dz >= 0 {
                return None;
            }
            // The first sample at or below the top, less one.
            let below_top = div_ceil(z0 - self.highest, -dz) - 1;
            if below_top > i64::from(walk.last) {
                return None;
            }
            k = k.max(below_top as i32);
        }
        let mut level = 0;
        while walk.begins[level + 1] <= k {
            level += 1;
        }
        let k = align_down(&walk.plane, i64::from(k), level as u32) as i32;
        let level = level as u8;
        let (index, minor) = self.position(walk, k, level);
        Some(At {
            k,
            level,
            index,
            minor,
            height: self.height_at::<P, OWN_PATH>(walk, (k, index, minor, level), drift, probe)?,
            before_k: k,
            before: None,
        })
    }

    /// The sample before which the ray along `d` clears every level of
    /// the surface, by the hierarchical first hit through the pyramid's
    /// height bounds (the line's first sample without them); `None` when
    /// it cannot hit at all. Its bounds cover every level, so the skip
    /// holds whatever levels the walk steps on. After `tests` rounds of
    /// bound tests (see [`first_hit`]) it stops where it has proven.
    #[inline(never)]
    fn clear_until<P: Probe>(
        &self,
        walk: &LineWalk,
        d: &[i64; 3],
        tests: u32,
        probe: &mut P,
    ) -> Option<i32> {
        if !self.first_hit {
            return Some(walk.first);
        }
        let (view, plane) = (self.view, &walk.plane);
        let clip = view.clip(&self.extent, d, plane);
        if clip.start > clip.end {
            return None;
        }
        let mut ray = view.ray_with(&self.extent, &self.plan, plane, &clip);
        ray.schedule();
        let k = first_hit(self.surface, &ray, ray.start, ray.end, tests, probe)?;
        Some(k - 1)
    }

    /// Where sample `k` of `walk` is on `level`: the index of its major
    /// grid line there, and its minor coordinate (Q16, world voxels).
    #[inline(always)]
    fn position(&self, walk: &LineWalk, k: i32, level: u8) -> (isize, i32) {
        let plane = &walk.plane;
        let k = i64::from(k);
        let major = if plane.key.forward {
            plane.major0 + k
        } else {
            plane.major0 - k
        };
        let index = (major >> level) as isize * walk.major_stride[usize::from(level)];
        // Inside the map, below 2^31 (`Plane::minor_max`).
        (index, (plane.minor0 + k * plane.dminor) as i32)
    }

    /// How far (Q16) a ray drifting `drift` reads heights aside of the
    /// line at sample `k`: its drift times the sample's distance, as its
    /// colors are looked up (`LineCaster::hit`).
    #[inline(always)]
    fn aside_at(walk: &LineWalk, k: i32, drift: i32) -> i32 {
        aside_at_distance(walk.delta0, k, drift)
    }

    /// [`LineCaster::height`] at sample `k`, at `minor` on the line or,
    /// with `OWN_PATH`, on the path of a ray drifting `drift`.
    #[inline(always)]
    fn height_at<P: Probe, const OWN_PATH: bool>(
        &self,
        walk: &LineWalk,
        (k, index, minor, level): (i32, isize, i32, u8),
        drift: i32,
        probe: &mut P,
    ) -> Option<i32> {
        let minor = if OWN_PATH {
            walk.aside(minor, Self::aside_at(walk, k, drift))
        } else {
            minor
        };
        self.height(walk, index, minor, level, probe)
    }

    /// The blended height (Q16) at the point of `level`'s major grid line
    /// `index` at minor coordinate `minor`: the two heights across the
    /// level's minor grid line, weighted by the minor coordinate's fraction
    /// of the level's spacing. `None` outside the level's grid.
    #[inline(always)]
    fn height<P: Probe>(
        &self,
        walk: &LineWalk,
        index: isize,
        minor: i32,
        level: u8,
        probe: &mut P,
    ) -> Option<i32> {
        let (l, shift) = (usize::from(level), u32::from(level));
        let across = walk.across[l];
        let index = index + (minor >> (COORD_FRAC_BITS + shift)) as isize * across;
        let (h0, h1) = self.grids[l].height_pair(index, across)?;
        probe.visit(level, index as usize);
        let weight_shift = COORD_FRAC_BITS - HEIGHT_WEIGHT_BITS + shift;
        let weight = (minor >> weight_shift) & ((1 << HEIGHT_WEIGHT_BITS) - 1);
        Some((i32::from(h0) << HEIGHT_TO_Q16) + (i32::from(h1) - i32::from(h0)) * weight)
    }

    /// Climbs to a ray whose height at sample 0 is `z0` (Q16), `dz` a
    /// sample: from `at`, where the ray before hit, steps on the line's
    /// schedule while above the surface (with `OWN_PATH`, reading heights
    /// on the path of a ray drifting `drift`; at `at` itself it compares
    /// with the height the ray before read). Returns the ray's height at its
    /// hit, or `None` when it leaves the map or rises above the highest
    /// terrain (and so does every ray of the line after it).
    ///
    /// Each height fetched takes one of `fetches`; with none
    /// left the ray stops at the sample it is on, above the surface, and
    /// is shaded there as if it hit (the next ray, higher, climbs on from
    /// it: the surface is below both there).
    #[inline(always)]
    fn climb<P: Probe, F: Fetches, const OWN_PATH: bool>(
        &self,
        walk: &LineWalk,
        at: &mut At,
        (z0, dz): (i64, i64),
        drift: i32,
        fetches: &mut F,
        probe: &mut P,
    ) -> Option<i64> {
        let mut z = z0 + i64::from(at.k) * dz;
        if z <= i64::from(at.height) {
            return Some(z);
        }
        // A rising ray above the highest terrain never comes down to it.
        let rising = dz >= 0;
        if rising && z > self.highest {
            return None;
        }
        let mut here = *at;
        loop {
            // Along this level while its grid lines last: the level's
            // steps in locals.
            let level = here.level;
            let l = usize::from(level);
            let (end, step, minor_step) = (walk.ends[l], walk.step[l], walk.minor_step[l]);
            let (stride, z_step) = (1 << level, dz << level);
            let (mut k, mut index, mut minor, mut height) =
                (here.k, here.index, here.minor, here.height);
            // The ray's own path: aside of the line by the drift times the
            // distance, one product where a level's run begins and an add
            // a step (the product of the drift and a whole number of
            // samples is exact).
            let (mut aside, aside_step) = if OWN_PATH {
                (Self::aside_at(walk, k, drift), drift << level)
            } else {
                (0, 0)
            };
            // As far as the fetches left reach (no limit: the level's end).
            let (from, run_end) = (k, fetches.run_end(k, stride, end));
            while k + stride <= run_end {
                let before = height;
                k += stride;
                index += step;
                minor += minor_step;
                z += z_step;
                let read_at = if OWN_PATH {
                    aside += aside_step;
                    walk.aside(minor, aside)
                } else {
                    minor
                };
                height = self.height(walk, index, read_at, level, probe)?;
                if z <= i64::from(height) {
                    *at = At {
                        k,
                        level,
                        index,
                        minor,
                        height,
                        before_k: k - stride,
                        before: Some(before),
                    };
                    return Some(z);
                }
                if rising && z > self.highest {
                    return None;
                }
            }
            if F::LIMITED {
                fetches.ran(from, k, level);
                if k + stride <= end {
                    return Some(stopped(at, level, (k, index, minor, height), z));
                }
            }
            if k >= walk.last {
                return None;
            }
            if F::LIMITED && !fetches.take() {
                return Some(stopped(at, level, (k, index, minor, height), z));
            }
            // The next level's first grid line, or the map's last sample.
            let next = k + stride;
            let level = if next > walk.last {
                // The map ends between this level's grid lines: its last
                // sample is tested, on level 0 where the map's edge is the
                // terrain's (the edge keeps its silhouette), else against
                // this level's grid line at or before it (a window of a
                // larger world holds level 0 no farther than its schedule
                // needs).
                if self.extent.real_edges {
                    0
                } else {
                    level
                }
            } else {
                level + 1
            };
            let next = next.min(walk.last);
            let (index, minor) = self.position(walk, next, level);
            z = z0 + i64::from(next) * dz;
            here = At {
                k: next,
                level,
                index,
                minor,
                height: self.height_at::<P, OWN_PATH>(
                    walk,
                    (next, index, minor, level),
                    drift,
                    probe,
                )?,
                before_k: k,
                before: Some(height),
            };
            if z <= i64::from(here.height) {
                *at = here;
                return Some(z);
            }
            if rising && z > self.highest {
                return None;
            }
        }
    }

    /// The sample of `ray` at height `z` (Q16) at `at`, below the surface
    /// there and above it at the sample before (when there is one).
    ///
    /// In 32-bit words where the values allow: a hit's distance is below
    /// 2^31 (inside the map), a clearance saturates.
    #[inline(always)]
    fn hit<P: Probe, const NEAREST: bool>(
        &self,
        walk: &LineWalk,
        at: &At,
        z: i64,
        ray: &HitRay,
        probe: &mut P,
    ) -> Sample {
        probe.hit(at.level);
        let HitRay {
            dz,
            color_reach,
            drift,
        } = *ray;
        let span = at.k - at.before_k;
        // The crossing, `t`/256 of the way from the sample before to the
        // hit, and the clearances either side.
        // Clearances and the elevation saturate: a ray that reaches the
        // map far below the terrain (an eye far off the map) hits at its
        // first sample thousands of voxels down.
        let below = saturate(z - i64::from(at.height));
        let above = match at.before {
            Some(before) if span > 0 => Some(saturate(
                z - i64::from(dz) * i64::from(span) - i64::from(before),
            )),
            _ => None,
        };
        let t = above.map_or(256, |above| crossing_fraction(above, below));
        // How far back from the hit the crossing is, in 1/256 of a sample.
        let back = (256 - t) as i32 * span;
        // Inside the map: below 2^31 (`delta0` < 1, `k` < 2^15).
        let hit_distance = walk.delta0 + (at.k << COORD_FRAC_BITS);
        // A crossing behind the eye (a ray that starts inside the terrain)
        // is the eye itself: distance 0, and the ray's height there.
        let distance = (hit_distance - (back << 8)).max(0);
        // The crossing's height, where an object standing on the hit's
        // grid points is seen; worked out where it is used (on a plain
        // terrain only the sample takes it).
        let elevation = || {
            saturate(z - ((i64::from(hit_distance - distance) * i64::from(dz)) >> COORD_FRAC_BITS))
        };
        let sample = |color| Sample {
            color,
            distance: distance as u32,
            elevation: elevation(),
        };
        if NEAREST {
            let aside = ((i64::from(drift) * i64::from(hit_distance)) >> COORD_FRAC_BITS) as i32;
            return match self.nearest_color(walk, at, aside, elevation(), probe) {
                Some(color) => sample(color),
                None => self.sky,
            };
        }
        if i64::from(distance) >= color_reach || at.level > 0 {
            let above = above.map(|above| (at.before_k, above));
            let far = Far {
                span,
                above,
                below,
                back,
                distance,
                drift,
                color_reach,
            };
            if let Some(color) = self.far_color(walk, at, &far, probe) {
                return sample(color);
            }
        }
        // Level 0's grid lines at the hit and the sample before, blended
        // at the crossing, looked up `drift` aside: the drift times the
        // distance, which is one sample less at the sample before.
        let aside = ((i64::from(drift) * i64::from(hit_distance)) >> COORD_FRAC_BITS) as i32;
        if at.level > 0 {
            // A coarse hit whose footprint found no color (at the map's
            // edge): its own level's grid line.
            return sample(self.coarse_color(walk, at, aside, elevation(), probe));
        }
        if self.surface.has_details() {
            let far = Far {
                span,
                above: above.map(|above| (at.before_k, above)),
                below,
                back,
                distance,
                drift,
                color_reach,
            };
            if let Some(color) = self.detail_color(walk, at, &far, probe) {
                return sample(color);
            }
        }
        // A crossing by a complex stick is shaded with its opacities, and
        // seen through where it is less than opaque (out of line: few hits
        // are on one). The test compiles out for a grid that has none.
        let near = |t| NearHit {
            k: at.k,
            index: at.index,
            minor: at.minor,
            z,
            dz,
            drift,
            elevation: elevation(),
            t,
        };
        let (grid, across) = (&self.grids[0], walk.across[0]);
        let (on_hit, hit_cell) =
            self.line_color(walk, 0, (at.index, at.minor), aside, elevation(), probe);
        let color = if above.is_some() && t < 256 {
            let (before, before_cell) = self.line_color(
                walk,
                0,
                (at.index - walk.step[0], at.minor - walk.minor_step[0]),
                aside - drift,
                elevation(),
                probe,
            );
            if grid.sees_through()
                && (grid.may_see_through(before_cell, across)
                    || grid.may_see_through(hit_cell, across))
            {
                return sample(self.see_through(walk, &near(t), probe));
            }
            let cells = (before_cell, hit_cell);
            let t = along_weight(grid, cells, across, elevation(), t);
            lerp(before, on_hit, t)
        } else {
            if grid.sees_through() && grid.may_see_through(hit_cell, across) {
                return sample(self.see_through(walk, &near(256), probe));
            }
            on_hit
        };
        sample(color)
    }

    /// The color of a hit past its color reach or on a coarse level: from
    /// the two levels its footprint brackets, blended by depth
    /// ([`mod@super::footprint_color`]'s levels, the soft transition), or
    /// its own coarse level's; `None` where it takes level 0's grid lines.
    /// Out of line: most hits are near and fine.
    #[inline(never)]
    fn far_color<P: Probe>(
        &self,
        walk: &LineWalk,
        at: &At,
        far: &Far,
        probe: &mut P,
    ) -> Option<Rgb> {
        let distance = i64::from(far.distance);
        let width = narrower_side(distance, far.span, far.above, far.below);
        let (level, t) = match color_level(width, far.color_reach, self.plan.top) {
            Some((level, t)) if level >= at.level => (level, t),
            _ if at.level > 0 => (at.level, 0),
            _ => return None,
        };
        // The crossing, in 1/256 of a sample.
        let crossing = (i64::from(at.k) << 8) - i64::from(far.back);
        self.footprint(walk, crossing, far, (level, t), probe)
    }

    /// The color of a near hit from the photos finer than level 0, by its
    /// footprint ([`crate::Detail::color_for`]); `None` outside their
    /// rectangles and where level 0 is fine enough. Out of line: only a
    /// surface with a detail takes it.
    #[inline(never)]
    fn detail_color<P: Probe>(
        &self,
        walk: &LineWalk,
        at: &At,
        near: &Far,
        probe: &mut P,
    ) -> Option<Rgb> {
        let distance = i64::from(near.distance);
        let width = narrower_side(distance, near.span, near.above, near.below);
        let crossing = (i64::from(at.k) << 8) - i64::from(near.back);
        let point = crossing_point(walk, crossing, near);
        let color = self.surface.detail_color(point, width, near.color_reach)?;
        probe.color(0, at.index as usize);
        Some(color)
    }

    /// The color of `level` where the sample on its major grid line
    /// `index` at minor coordinate `minor` crosses its minor grid line,
    /// looked up `aside` (Q16) across the line, the ray at height `z`: the
    /// two voxels across the line blended by the subvoxel weight (the
    /// sky's color where the map has none); and the index of the first of
    /// the two (where an object may stand, [`Grid::stands`]).
    #[inline(always)]
    fn line_color<P: Probe>(
        &self,
        walk: &LineWalk,
        level: u8,
        (index, mut minor): (isize, i32),
        aside: i32,
        z: i32,
        probe: &mut P,
    ) -> (Rgb, isize) {
        if aside != 0 {
            minor = walk.aside(minor, aside);
        }
        let (l, across) = (usize::from(level), walk.across[usize::from(level)]);
        let color = line_color(&self.grids[l], index, across, minor, level, z);
        let cell = index + (minor >> (COORD_FRAC_BITS + u32::from(level))) as isize * across;
        probe.color(level, cell as usize);
        (color.unwrap_or(self.sky.color), cell)
    }

    /// The color of the voxel of the hit's level nearest to where the hit
    /// sample crosses its minor grid line, looked up `aside` (Q16) across
    /// the line (as `Stage::nearest_color` finds it); `None` where the map
    /// has none. Out of line: the default shading never takes it.
    #[inline(never)]
    fn nearest_color<P: Probe>(
        &self,
        walk: &LineWalk,
        at: &At,
        aside: i32,
        z: i32,
        probe: &mut P,
    ) -> Option<Rgb> {
        let minor = if aside == 0 {
            at.minor
        } else {
            walk.aside(at.minor, aside)
        };
        let (l, shift) = (usize::from(at.level), u32::from(at.level));
        let across = walk.across[l];
        let cell = at.index + (minor >> (COORD_FRAC_BITS + shift)) as isize * across;
        let half = 1 << (COORD_FRAC_BITS - 1 + shift);
        let nearest = if minor & ((half << 1) - 1) < half {
            cell
        } else {
            cell + across
        };
        probe.color(at.level, cell as usize);
        self.grids[l].color_at(nearest, z)
    }

    /// [`LineCaster::line_color`] on a coarse hit's own level. Out of line:
    /// rare (a coarse hit whose footprint found no color).
    #[inline(never)]
    fn coarse_color<P: Probe>(
        &self,
        walk: &LineWalk,
        at: &At,
        aside: i32,
        z: i32,
        probe: &mut P,
    ) -> Rgb {
        self.line_color(walk, at.level, (at.index, at.minor), aside, z, probe)
            .0
    }

    /// The color at the crossing `crossing`/256 samples along the line,
    /// the far hit's distance (Q16) from the eye, looked up its drift aside
    /// (as `Ray::color_point` places it), from levels `level − 1` and
    /// `level` blended by `t`/256; `None` where neither has a color.
    #[inline(never)]
    fn footprint<P: Probe>(
        &self,
        walk: &LineWalk,
        crossing: i64,
        far: &Far,
        (level, t): (u8, u32),
        probe: &mut P,
    ) -> Option<Rgb> {
        let point = crossing_point(walk, crossing, far);
        levels_color(self.surface, level, t, point, probe)
    }
}

/// The world point (Q16) of the crossing `crossing`/256 samples along
/// `walk`'s line, the hit's distance (Q16) from the eye, looked up its
/// drift aside (as `Ray::color_point` places it).
#[inline(always)]
fn crossing_point(walk: &LineWalk, crossing: i64, far: &Far) -> [i64; 2] {
    let (distance, drift) = (i64::from(far.distance), i64::from(far.drift));
    let plane = &walk.plane;
    let along = crossing << (COORD_FRAC_BITS - 8);
    let major = (plane.major0 << COORD_FRAC_BITS) + if plane.key.forward { along } else { -along };
    let minor =
        plane.minor0 + ((crossing * plane.dminor) >> 8) + ((drift * distance) >> COORD_FRAC_BITS);
    let minor = minor.clamp(0, plane.minor_max);
    if plane.key.x_major {
        [major, minor]
    } else {
        [minor, major]
    }
}

/// A count of height fetches a ray may still make (the line caster's
/// climb counts them in runs of steps, so that its loop is the plain
/// render's).
pub(crate) trait Fetches {
    /// Whether there is a limit: `false` compiles the counting out.
    const LIMITED: bool;
    /// The fetches of a ray given `allowance` (see [`Allowances`]): at
    /// most `2n + 2` for `n` (with at most `2n` bound tests of its first
    /// hit, `4n + 2` steps in all).
    fn for_allowance(allowance: u32) -> Self;
    /// Where a run of steps of `stride` samples from sample `k` must stop
    /// before passing `end` to stay within the count.
    fn run_end(&self, k: i32, stride: i32, end: i32) -> i32;
    /// Counts the steps of a run from sample `from` to `to` on `level`.
    fn ran(&mut self, from: i32, to: i32, level: u8);
    /// Takes one: `false` when none is left.
    fn take(&mut self) -> bool;
}

/// Any number of fetches.
impl Fetches for Unlimited {
    const LIMITED: bool = false;
    #[inline(always)]
    fn for_allowance(_allowance: u32) -> Self {
        Unlimited
    }
    #[inline(always)]
    fn run_end(&self, _k: i32, _stride: i32, end: i32) -> i32 {
        end
    }
    #[inline(always)]
    fn ran(&mut self, _from: i32, _to: i32, _level: u8) {}
    #[inline(always)]
    fn take(&mut self) -> bool {
        true
    }
}

impl Fetches for u32 {
    const LIMITED: bool = true;
    #[inline(always)]
    fn for_allowance(allowance: u32) -> Self {
        allowance.saturating_mul(2).saturating_add(2)
    }
    #[inline(always)]
    fn run_end(&self, k: i32, stride: i32, end: i32) -> i32 {
        let steps = i32::try_from(*self).unwrap_or(i32::MAX);
        end.min(k.saturating_add(stride.saturating_mul(steps)))
    }
    #[inline(always)]
    fn ran(&mut self, from: i32, to: i32, level: u8) {
        *self = self.saturating_sub(((to - from) >> level) as u32);
    }
    #[inline(always)]
    fn take(&mut self) -> bool {
        let left = *self > 0;
        *self = self.saturating_sub(1);
        left
    }
}

/// Stops a ray that has no fetch left where it is, at sample `k` of
/// `level` (with its index, minor coordinate and height), the ray at
/// height `z` there: it is shaded there as if it hit. Out of line and
/// cold: the plain render never takes it, and its body inlined into the
/// climb changes how the compiler lays the plain render out (10
/// instructions a pixel more on the board when measured).
#[cold]
#[inline(never)]
fn stopped(
    at: &mut At,
    level: u8,
    (k, index, minor, height): (i32, isize, i32, i32),
    z: i64,
) -> i64 {
    *at = At {
        k,
        level,
        index,
        minor,
        height,
        before_k: k,
        before: None,
    };
    z
}

/// How far (Q16) a ray drifting `drift` (Q16 a unit of distance, within
/// ±2^14) is aside of its line at sample `k` (in `0..2^15`) of a line whose
/// sample 0 lies `delta0` (Q16, below 2^16) from the eye: `drift · (delta0
/// + k·2^16) / 2^16`, rounded down. The whole samples' part is exact, so it
/// is the sample 0 part rounded plus `drift · k`, all in words.
#[inline(always)]
fn aside_at_distance(delta0: i32, k: i32, drift: i32) -> i32 {
    ((drift * delta0) >> COORD_FRAC_BITS) + drift * k
}

fn align_down(plane: &Plane, k: i64, level: u32) -> i64 {
    let mask = (1i64 << level) - 1;
    if plane.key.forward {
        ((plane.major0 + k) & !mask) - plane.major0
    } else {
        let m = plane.major0 - k;
        plane.major0 - ((m + mask) & !mask)
    }
}

/// The first sample at or after `k` on a grid line of `level` (major
/// coordinate a multiple of `2^level`).
fn align_up(plane: &Plane, k: i64, level: u32) -> i64 {
    let mask = (1i64 << level) - 1;
    if plane.key.forward {
        let m = plane.major0 + k;
        ((m + mask) & !mask) - plane.major0
    } else {
        let m = plane.major0 - k;
        plane.major0 - (m & !mask)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every sample a line's rays put, in order.
    #[derive(Default)]
    struct Recorded(Vec<(u32, u32, Sample)>);

    impl Sink for Recorded {
        fn put(&mut self, x: u32, y: u32, sample: Sample) {
            self.0.push((x, y, sample));
        }
    }

    /// `cast_line_pixels` walks a line whose pixels are centered on it on
    /// the line even when each ray reads heights on its own path: a
    /// centered ray's path is the line's, so the two walks must put the
    /// same samples. This holds them to it on level views (columns, rolled
    /// upside down) and on views rolled ±90° (rows).
    #[test]
    fn a_centered_lines_rays_read_their_own_paths_on_the_line() {
        use crate::{Camera, NoProbe, Pyramid, Terrain};
        let (heights, colors) = crate::test_scenes::hills(48, 48);
        let terrain = Terrain::new(48, 48, &heights, &colors).unwrap();
        let pyramid = Pyramid::flat(terrain);
        let options = RenderOptions {
            height_path: HeightPath::Ray,
            ..RenderOptions::default()
        };
        for (yaw, roll) in [
            (30.0, 0.0),
            (200.0, 0.0),
            (75.0, 180.0),
            (10.0, 90.0),
            (300.0, -90.0),
        ] {
            let camera = Camera {
                roll_deg: roll,
                ..Camera::looking([3.0, 5.0, 70.0], yaw, 0.0)
            };
            let view = View::new(&camera, 41, 30).unwrap();
            let caster = LineCaster::new(&pyramid, &view, &options);
            let mut centered = 0;
            for index in 0..view.lines() {
                let Some(line) = view.line(index) else {
                    continue;
                };
                let Some(pixels) = line.pixels(view.height()).straightened() else {
                    continue;
                };
                if !pixels.centered() {
                    continue;
                }
                centered += 1;
                let (mut own, mut on_line) = (Recorded::default(), Recorded::default());
                let a = &mut Unlimited;
                caster.cast::<_, _, _, _, false, true>(
                    &line,
                    pixels.clone(),
                    &mut own,
                    &mut NoProbe,
                    a,
                );
                caster.cast::<_, _, _, _, false, false>(
                    &line,
                    pixels,
                    &mut on_line,
                    &mut NoProbe,
                    a,
                );
                assert!(!own.0.is_empty(), "yaw {yaw} roll {roll} line {index}");
                assert!(own.0 == on_line.0, "yaw {yaw} roll {roll} line {index}");
            }
            assert!(centered > 0, "yaw {yaw} roll {roll}: no centered line");
        }
    }

    /// A walk on each ray's own path starts on it: the height a ray's walk
    /// starts with (`LineCaster::start`, which a line's first ray and
    /// every stretch's first ray take) is the terrain's at the line's
    /// minor coordinate moved by the ray's drift times the sample's
    /// distance. On a ramp across the lines, worked out apart in `f64`.
    #[test]
    fn an_own_path_walk_starts_on_the_rays_path() {
        use crate::{Camera, NoProbe, Pyramid, Terrain};
        // Four voxels of height a voxel of y (U12.4), the same along x.
        let side = 64u32;
        let heights: Vec<u16> = (0..side * side).map(|i| (i / side * 64) as u16).collect();
        let colors = vec![[0u8; 3]; heights.len()];
        let terrain = Terrain::new(side, side, &heights, &colors).unwrap();
        let pyramid = Pyramid::flat(terrain);
        let options = RenderOptions {
            height_path: HeightPath::Ray,
            ..RenderOptions::default()
        };
        let camera = Camera::looking([2.0, 30.0, 300.0], 0.0, 20.0);
        let view = View::new(&camera, 40, 30).unwrap();
        let caster = LineCaster::new(&pyramid, &view, &options);
        let mut checked = 0;
        for index in 0..view.lines() {
            let Some(line) = view.line(index) else {
                continue;
            };
            let walk = caster.line_walk(&line);
            if walk.first > walk.last || !walk.plane.key.x_major {
                continue;
            }
            for drift in [-3000, -700, 0, 900, 4000] {
                for from in [walk.first, (walk.first + walk.last) / 2, walk.last] {
                    // A ray at height 0: below the terrain's top from the
                    // eye on, so it starts where it is asked to.
                    let Some(at) = caster.start::<_, true>(&walk, from, 0, 0, drift, &mut NoProbe)
                    else {
                        continue;
                    };
                    let one = f64::from(1 << COORD_FRAC_BITS);
                    let distance = (f64::from(walk.delta0) + f64::from(at.k) * one) / one;
                    let minor = f64::from(at.minor) / one + f64::from(drift) / one * distance;
                    let expected = 4.0 * minor.clamp(0.0, f64::from(side - 1));
                    let got = f64::from(at.height) / one;
                    assert!(
                        (got - expected).abs() < 0.01,
                        "line {index}, drift {drift}, sample {}: height {got}, on the ray's path {expected}",
                        at.k
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 100, "{checked} starts checked");
    }

    #[test]
    fn the_aside_in_words_is_the_product_of_the_drift_and_the_distance() {
        let distance_product = |delta0: i32, k: i32, drift: i32| {
            ((i64::from(drift) * (i64::from(delta0) + (i64::from(k) << COORD_FRAC_BITS)))
                >> COORD_FRAC_BITS) as i32
        };
        let limit = 1 << 14;
        let drifts = [
            -limit,
            -limit + 1,
            -12345,
            -257,
            -1,
            0,
            1,
            3,
            255,
            9999,
            limit - 1,
            limit,
        ];
        let ks = [0, 1, 2, 7, 1000, 20_000, (1 << 15) - 1];
        let deltas = [0, 1, 0x7FFF, 0x8000, 0xABCD, 0xFFFF];
        for drift in drifts {
            for k in ks {
                for delta0 in deltas {
                    assert_eq!(
                        aside_at_distance(delta0, k, drift),
                        distance_product(delta0, k, drift),
                        "delta0 {delta0}, k {k}, drift {drift}"
                    );
                }
            }
        }
    }
}
