//! The caster: each image line through the vertical's vanishing point,
//! one ray after another by rising elevation (see [`crate::View::lines`]).
//!
//! With the default settings [`render`] and [`render_line`] take the line
//! caster (`line_caster.rs`): a line is set up once and a ray is its slope.
//! The other settings set every ray up in full, as described below.
//!
//! The rays of a line lie in one vertical plane and share their horizontal
//! direction bit for bit, so each ray can start at the sample where the ray
//! before it hit (Cohen-Or §2): it is no lower than that ray at any sample,
//! and the surface below that ray is the surface below it ([`resume_at`]).
//! With levels, the ray before may have stepped on other levels than this
//! one near a switch; [`Coherence::Exact`] casts such a ray from the eye,
//! so the image equals the image with every ray cast from the eye, bit for
//! bit (tested), and [`Coherence::AcrossLevels`] resumes it anyway. Under
//! AcrossLevels, a ray that would resume past its own last sample (the ray
//! below it left the terrain) is sky after its slope and clip alone. A
//! resumed ray that starts below the
//! surface retraces backwards to the last sample above it (Qu et al. §4);
//! the hit is refined between that sample and the first one below by the
//! ratio of their clearances. Near the eye the color is level 0's, blended
//! across both grid lines; farther out it comes from the levels the pixel's
//! footprint brackets, on a schedule of its own ([`mod@footprint_color`]).

mod budget;
mod first_hit;
mod footprint_color;
mod line_caster;
mod per_line;
pub(crate) mod walk;

pub use budget::{FrameCost, Governor};
pub use per_line::{render_level_columns, ColumnsError};

use crate::probe::Probe;
use crate::roughness::terrain_fit;
use crate::sink::{Sample, Sink};
use crate::surface::Surface;
use crate::view::lines::Line;
use crate::view::ray::{Clip, Cursor, Lod, LodPlan, Plane, Ray, RayKey};
use crate::view::View;
use crate::{color::Rgb, config::DEFAULT_SKY};
use first_hit::first_hit;
use fixed::types::U8F8;
use footprint_color::footprint_color;
use walk::{lerp, walk, Recent, Stage, Walk};

/// How each ray of an image line may use the ray before it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coherence {
    /// Every ray is cast from the eye: the slow baseline.
    Off,
    /// A ray starts where the ray before it hit when both step on the same
    /// levels (always at single resolution): the image equals
    /// [`Coherence::Off`]'s bit for bit. On the pyramid the rays of a line
    /// switch levels at different samples, so under pitch most are cast
    /// from the eye.
    Exact,
    /// The line caster's (`caster/line_caster.rs`), with one ray a pixel
    /// and subvoxel shading: the rays of a stretch of a line share one
    /// level schedule, its least ray's, so every ray resumes where the ray
    /// before it hit; a ray switches levels up to a quarter nearer than
    /// its own depth says, and a new stretch starts where the stretch
    /// before left off, whose surface may differ from this one's by a
    /// level (the bound measured in the coherence tests). With more rays
    /// a pixel or nearest shading: as [`Coherence::Exact`], and across
    /// different level schedules too. At single resolution, the image of
    /// [`Coherence::Exact`] bit for bit.
    AcrossLevels,
}

impl Coherence {
    /// The default: [`Coherence::AcrossLevels`].
    pub const DEFAULT: Self = Self::AcrossLevels;
}

/// Which levels of the pyramid the caster steps on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resolution {
    /// Level 0 only, however far the ray goes (the baseline that aliases
    /// in the distance and costs more the farther it sees).
    Single,
    /// Every level the pyramid has (Cohen-Or §2): a ray moves up a level,
    /// at an even step, where a voxel of its level gets narrower than
    /// `1 / pixel_to_voxel` pixels, and blends the colors of adjacent
    /// levels by depth so the switch is invisible. A higher ratio
    /// switches sooner: fewer steps, a blurrier far field. With
    /// [`RenderOptions::terrain_fit`] the ratio is scaled down on rugged
    /// terrain first.
    Multi {
        /// The pixel-to-voxel ratio (1 = switch where a voxel is one pixel
        /// wide).
        pixel_to_voxel: U8F8,
    },
}

impl Resolution {
    /// [`Resolution::Multi`] at a pixel-to-voxel ratio of 1.
    pub const DEFAULT: Self = Self::Multi {
        pixel_to_voxel: U8F8::ONE,
    };
}

/// How many rays each pixel gets, spread along its image line (Cohen-Or
/// §2.1: at shallow pitch a pixel's footprint is long and thin, and one ray
/// undersamples it). They share the line's coherence, so they add rays, not
/// voxels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VerticalSamples {
    /// One ray through the pixel center.
    One,
    /// Two rays a half pixel apart.
    Two,
    /// Four rays.
    Four,
    /// Eight rays.
    Eight,
}

impl VerticalSamples {
    /// Rays per pixel.
    pub fn count(self) -> u32 {
        1 << self.log2()
    }
    fn log2(self) -> u32 {
        match self {
            Self::One => 0,
            Self::Two => 1,
            Self::Four => 2,
            Self::Eight => 3,
        }
    }
}

/// How a hit is colored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shading {
    /// The two voxels across the grid line blended by the fraction of the
    /// minor coordinate (a shift and a mask), on the grid lines before and
    /// after the crossing, blended by where it lies; past the color reach,
    /// bilinear on the two levels the pixel's footprint brackets, blended
    /// by depth (the soft transition; see `footprint_color`).
    Subvoxel,
    /// The voxel nearest the hit sample, on its level: no blend. Cheaper
    /// and blockier: the baseline the subvoxel weights are measured
    /// against.
    Nearest,
}

/// Settings of the caster.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RenderOptions {
    /// Vertical ray coherence: each ray resumes where the ray before it on
    /// its image line hit.
    pub coherence: Coherence,
    /// Single resolution or the pyramid's levels.
    pub resolution: Resolution,
    /// Rays cast from the eye (the first of each image line, and any ray that
    /// cannot resume) skip through the pyramid's height bounds.
    pub hierarchical_first_hit: bool,
    /// Rays per pixel, spread along the pixel's image line.
    pub vertical_samples: VerticalSamples,
    /// How hits are colored.
    pub shading: Shading,
    /// On the pyramid, scale the pixel-to-voxel ratio the height levels
    /// switch by down by the terrain's roughness
    /// ([`crate::roughness::terrain_fit`]), so that a coarse level's
    /// silhouettes are within an eighth of a pixel (RMS) where it begins. Colors
    /// switch by the ratio as given. No effect on smooth maps, nor on surfaces whose roughness
    /// is unknown.
    pub terrain_fit: bool,
    /// Color of rays that leave the terrain.
    pub sky: Rgb,
}

impl RenderOptions {
    /// The pixel-to-voxel ratio the caster switches levels by on a surface
    /// of `roughness` ([`crate::Surface::roughness`]): the one set, scaled
    /// by the terrain fit when it is on; 1 at single resolution. A tile
    /// footprint ([`crate::tiles::FootprintView`]) takes this one.
    pub fn level_bias(&self, roughness: u8) -> f32 {
        match self.resolution {
            Resolution::Single => 1.0,
            Resolution::Multi { pixel_to_voxel } => {
                pixel_to_voxel.to_num::<f32>() * self.fit_for(roughness) as f32 / 65536.0
            }
        }
    }

    /// The factor (Q16, at most 1) the ratio is scaled by on a surface of
    /// `roughness`: [`crate::roughness::terrain_fit`] when the fit is on
    /// and the pyramid in use, else 1.
    pub fn fit_for(&self, roughness: u8) -> u32 {
        match self.resolution {
            Resolution::Multi { .. } if self.terrain_fit => terrain_fit(roughness),
            _ => 1 << 16,
        }
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            coherence: Coherence::DEFAULT,
            resolution: Resolution::DEFAULT,
            hierarchical_first_hit: true,
            vertical_samples: VerticalSamples::One,
            shading: Shading::Subvoxel,
            terrain_fit: true,
            sky: DEFAULT_SKY,
        }
    }
}

/// What every line of a frame shares.
#[derive(Debug, Clone, Copy)]
struct Frame {
    lod: LodPlan,
    /// Rays may resume where the ray before hit.
    resume: bool,
    /// Resume only between rays with equal level schedules.
    same_schedule: bool,
    first_hit: bool,
    /// Once a ray of a line sees the sky, so does every ray after it:
    /// each is no lower at any sample than the one before (see
    /// [`resume_at`]; the pixels' directions step linearly along the line,
    /// so their slopes rise with it, by rounding too), so it clears the
    /// surface wherever that one did. Exact where the rays step on the
    /// same levels (single resolution); across levels the approximation
    /// [`Coherence::AcrossLevels`] makes when it resumes. Off for
    /// [`Coherence::Off`], and for [`Coherence::Exact`] on the pyramid.
    sky_above_sky: bool,
}

impl Frame {
    fn new<T: Surface + ?Sized>(surface: &T, view: &View, options: &RenderOptions) -> Self {
        let lod = match options.resolution {
            Resolution::Single => LodPlan::SINGLE,
            Resolution::Multi { pixel_to_voxel } => LodPlan::new(
                view,
                pixel_to_voxel.to_bits(),
                options.fit_for(surface.roughness()),
                surface.top(),
            ),
        };
        let (resume, same_schedule) = match options.coherence {
            Coherence::Off => (false, false),
            Coherence::Exact => (true, true),
            Coherence::AcrossLevels => (true, false),
        };
        let single = matches!(options.resolution, Resolution::Single);
        Self {
            lod,
            resume,
            same_schedule,
            first_hit: options.hierarchical_first_hit && surface.has_bounds(),
            sky_above_sky: resume && (single || !same_schedule),
        }
    }
}

/// Renders every image line of the view into `sink`: the whole frame.
pub fn render<T: Surface + ?Sized, S: Sink, P: Probe>(
    surface: &T,
    view: &View,
    options: &RenderOptions,
    sink: &mut S,
    probe: &mut P,
) {
    if line_caster::takes(options) {
        let caster = line_caster::LineCaster::new(surface, view, options);
        for line in 0..view.lines() {
            caster.line(line, sink, probe);
        }
        return;
    }
    let frame = Frame::new(surface, view, options);
    for line in 0..view.lines() {
        line_with(
            surface,
            view,
            options,
            &frame,
            line,
            sink,
            probe,
            &mut Unlimited,
        );
    }
}

/// Renders as [`render`] does, with one, two or four rays a pixel: as many
/// as its footprint needs (Cohen-Or §2.1 supersamples the elongated
/// footprints; [`VerticalSamples`] gives every pixel the same count).
/// A pixel's count is judged by the pixel before it on its image line:
/// the length along the line of that pixel's footprint (the spacing of the
/// two hits before it) against the larger of a voxel and the pixel's
/// width there, rounded to 1, 2 or 4 at 1.5 and 3. Grazing ground gets
/// four rays, slopes facing the eye, steep views and terrain within a
/// voxel of a pixel one. `options.vertical_samples` is not used.
///
/// A function of its own, not a [`VerticalSamples`] setting, so that a
/// build that never calls it (a board's) keeps the one line loop it has:
/// a second copy of that loop in the same build changes how the compiler
/// inlines the caster, which cost the board's default render 90 to 290
/// instructions a pixel when measured.
pub fn render_by_footprint<T: Surface + ?Sized, S: Sink, P: Probe>(
    surface: &T,
    view: &View,
    options: &RenderOptions,
    sink: &mut S,
    probe: &mut P,
) {
    let frame = Frame::new(surface, view, options);
    for line in 0..view.lines() {
        footprint_line(surface, view, options, &frame, line, sink, probe);
    }
}

/// Renders image line `line` as [`render_by_footprint`] renders it: a pool
/// of workers that hands out lines ([`render_line`]) gets the same image
/// from this as the whole frame gives.
pub fn render_line_by_footprint<T: Surface + ?Sized, S: Sink, P: Probe>(
    surface: &T,
    view: &View,
    options: &RenderOptions,
    line: u32,
    sink: &mut S,
    probe: &mut P,
) {
    let frame = Frame::new(surface, view, options);
    footprint_line(surface, view, options, &frame, line, sink, probe);
}

/// One line with rays by footprint, unlimited.
fn footprint_line<T: Surface + ?Sized, S: Sink, P: Probe>(
    surface: &T,
    view: &View,
    options: &RenderOptions,
    frame: &Frame,
    line: u32,
    sink: &mut S,
    probe: &mut P,
) {
    let rays = RaysByFootprint::new(view, options);
    line_rays(
        surface,
        view,
        options,
        frame,
        line,
        sink,
        probe,
        &mut Unlimited,
        rays,
    );
}

/// How many steps each ray of a line may take, asked before each ray:
/// `u32::MAX` for no limit, `n` for at most `4n + 2` steps (the ray is cut
/// short past that), 0 for none at all (the pixel repeats the line's
/// previous one).
pub(crate) trait Allowances {
    fn next(&mut self) -> u32;
}

/// No limit: the plain render.
struct Unlimited;

impl Allowances for Unlimited {
    #[inline(always)]
    fn next(&mut self) -> u32 {
        u32::MAX
    }
}

/// What the last cast ray of a column established: it was above the surface
/// at every sample in `start..k`.
#[derive(Debug, Clone, Copy)]
struct Anchor {
    key: RayKey,
    /// `None` for a ray whose schedule was not worked out: one that resumed
    /// past its end, which only [`Coherence::AcrossLevels`] lets a ray do
    /// without it (see [`Anchor::clears_all_of`]).
    lod: Option<Lod>,
    start: i32,
    k: i32,
    dminor: i32,
    dz: i32,
}

/// Renders image line `line` (`0..view.lines()`; a line past the last
/// renders nothing). Lines are independent and together cover every pixel
/// once: a pool may hand them to any number of workers.
pub fn render_line<T: Surface + ?Sized, S: Sink, P: Probe>(
    surface: &T,
    view: &View,
    options: &RenderOptions,
    line: u32,
    sink: &mut S,
    probe: &mut P,
) {
    if line_caster::takes(options) {
        line_caster::LineCaster::new(surface, view, options).line(line, sink, probe);
        return;
    }
    let frame = Frame::new(surface, view, options);
    line_with(
        surface,
        view,
        options,
        &frame,
        line,
        sink,
        probe,
        &mut Unlimited,
    );
}

/// Renders a line with `options.vertical_samples` rays a pixel.
#[allow(clippy::too_many_arguments)]
fn line_with<T: Surface + ?Sized, S: Sink, P: Probe, A: Allowances>(
    surface: &T,
    view: &View,
    options: &RenderOptions,
    frame: &Frame,
    line: u32,
    sink: &mut S,
    probe: &mut P,
    allowances: &mut A,
) {
    let rays = FixedRays(options.vertical_samples.log2());
    line_rays(
        surface, view, options, frame, line, sink, probe, allowances, rays,
    );
}

/// How many rays each pixel of a line gets.
trait RaysPerPixel {
    /// A line begins.
    fn start(&mut self, line: &Line) {
        let _ = line;
    }
    /// log2 of the rays the next pixel gets.
    fn log2(&self) -> u32;
    /// The pixel just rendered: its center ray's sample, and its row.
    fn rendered(&mut self, center: &Sample, row: i32) {
        let _ = (center, row);
    }
}

/// The same count for every pixel, as log2.
struct FixedRays(u32);

impl RaysPerPixel for FixedRays {
    #[inline(always)]
    fn log2(&self) -> u32 {
        self.0
    }
}

/// [`render_by_footprint`]'s counts: by the footprint of the pixel before.
/// One for each line (the line loop takes it by value).
struct RaysByFootprint {
    /// The hits of the two pixels before on the line, older first, and
    /// their rows (near the vanishing point a line skips rows).
    before: [(Sample, i32); 2],
    eye_z: i64,
    focal: i64,
    /// The line's pixel spacing (`Line::pixel_spacing_q16`).
    spacing: u64,
}

impl RaysByFootprint {
    fn new(view: &View, options: &RenderOptions) -> Self {
        Self {
            before: [(sky(options), 0); 2],
            eye_z: view.eye[2].to_bits(),
            focal: view.focal,
            spacing: 1 << 16,
        }
    }
}

impl RaysPerPixel for RaysByFootprint {
    fn start(&mut self, line: &Line) {
        self.spacing = line.pixel_spacing_q16();
    }
    fn log2(&self) -> u32 {
        let [(older, older_row), (newer, newer_row)] = &self.before;
        let rows = u64::from(older_row.abs_diff(*newer_row).max(1));
        footprint_rays_log2([older, newer], self.eye_z, self.focal, self.spacing * rows)
    }
    fn rendered(&mut self, center: &Sample, row: i32) {
        self.before = [self.before[1], (*center, row)];
    }
}

/// log2 of the most rays [`render_by_footprint`] gives a pixel.
const FOOTPRINT_MOST_LOG2: u32 = 2;

/// log2 of the rays [`render_by_footprint`] gives a pixel, from the hits
/// of the two pixels before it on its line, `older` first, seen from eye
/// height `eye_z` (I16.16); the line's pixels are `spacing` pixels apart
/// (Q16, `Line::pixel_spacing_q16`, times the rows between the two). The
/// hits' spacing (the larger of their distances' and their heights'
/// differences) over `spacing` is a pixel's footprint length along the
/// line. Over the larger of a voxel (colors are interpolated between
/// voxels, so a footprint within one needs no more rays) and the pixel's
/// width (its depth over `focal`; the depth is the larger of the
/// major-axis distance and the height below the eye, within √2 of the
/// Euclidean one either way), it is how many rays the footprint needs:
/// rounded to 1, 2 or 4 at 1.5 and 3. A sky pixel before gives one ray.
fn footprint_rays_log2([older, newer]: [&Sample; 2], eye_z: i64, focal: i64, spacing: u64) -> u32 {
    if older.is_sky() || newer.is_sky() {
        return 0;
    }
    let length = u128::from(
        older
            .distance
            .abs_diff(newer.distance)
            .max(older.elevation.abs_diff(newer.elevation)),
    );
    let depth = u128::from(newer.distance).max(u128::from(
        (eye_z - i64::from(newer.elevation)).unsigned_abs(),
    ));
    // `length / spacing / max(1, width) ≥ half_rays / 2`, without
    // dividing: width is `depth · 2^16 / focal` (U16.16).
    let spacing = u128::from(spacing);
    let needs = |half_rays: u128| {
        2 * length >= half_rays * spacing
            && 2 * length * focal.unsigned_abs() as u128 >= half_rays * depth * spacing
    };
    if needs(6) {
        FOOTPRINT_MOST_LOG2
    } else if needs(3) {
        1
    } else {
        0
    }
}

/// Renders a line with the rays a pixel `rays_per_pixel` gives.
#[allow(clippy::too_many_arguments)]
fn line_rays<T: Surface + ?Sized, S: Sink, P: Probe, A: Allowances, R: RaysPerPixel>(
    surface: &T,
    view: &View,
    options: &RenderOptions,
    frame: &Frame,
    line: u32,
    sink: &mut S,
    probe: &mut P,
    allowances: &mut A,
    mut rays_per_pixel: R,
) {
    let Some(line) = view.line(line) else {
        return;
    };
    rays_per_pixel.start(&line);
    let extent = surface.extent();
    let plane = Plane::new(view, &extent, &line.reference).with_across(&view.across(&line));
    let mut anchor: Option<Anchor> = None;
    let mut previous: Option<Sample> = None;
    let mut recent = Recent::default();
    // Sub-rays go by rising elevation too: the way the line is walked.
    let step = i64::from(line.sector.step);
    // Set once a ray of the line sees the sky (see `Frame::sky_above_sky`):
    // the rest of the line is sky, written without rays.
    let mut sky_from_here = false;
    for pixel in line.pixels(view.height()) {
        if sky_from_here {
            let sky = sky(options);
            rays_per_pixel.rendered(&sky, pixel.s);
            sink.put(pixel.x, pixel.y, sky);
            continue;
        }
        let log2 = rays_per_pixel.log2();
        let samples = 1i64 << log2;
        let mut sum = [0u32; 3];
        let mut center = sky(options);
        for sub in 0..samples {
            // Sub-ray centers, in sixteenths of a pixel from the pixel center.
            let offset = (((2 * sub + 1 - samples) * 8) >> log2) * step;
            if sky_from_here {
                let sky = sky(options);
                for (s, v) in sum.iter_mut().zip(sky.color) {
                    *s += u32::from(v);
                }
                if sub == samples / 2 {
                    center = sky;
                }
                continue;
            }
            probe.ray();
            let d = if offset == 0 {
                line.direction(pixel.along)
            } else {
                View::direction_beside(&line, &pixel, offset)
            };
            let clip = view.clip(&extent, &d, &plane);
            let allowance = allowances.next();
            let sample = if clip.start > clip.end {
                sky_from_here = frame.sky_above_sky;
                sky(options)
            } else if allowance == 0 {
                // No step left in the budget: repeat the ray before.
                previous.unwrap_or_else(|| sky(options))
            } else if let Some(a) =
                anchor.filter(|a| frame.resume && a.clears_all_of(&clip, frame.same_schedule))
            {
                // It would resume past its own end (the ray below left the
                // terrain): sky, and no more of its set-up is needed.
                anchor = Some(Anchor {
                    lod: None,
                    start: clip.start,
                    k: clip.end + 1,
                    dz: clip.dz as i32,
                    ..a
                });
                sky_from_here = frame.sky_above_sky;
                sky(options)
            } else {
                let mut ray = view.ray_with(&extent, &frame.lod, &plane, &clip);
                ray.color_drift = plane.drift(&d, pixel.offset) as i32;
                ray.schedule();
                let resume = anchor
                    .filter(|_| frame.resume)
                    .and_then(|a| resume_at(&a, &ray, frame.same_schedule));
                let (sample, clear_until) = cast(
                    surface,
                    &ray,
                    resume,
                    frame.first_hit,
                    allowance,
                    options,
                    &mut recent,
                    probe,
                );
                anchor = Some(Anchor {
                    key: ray.key,
                    lod: Some(ray.lod),
                    start: ray.start,
                    k: clear_until,
                    dminor: ray.dminor.to_bits(),
                    dz: ray.dz.to_bits(),
                });
                // `cast` gives the sky only to a ray that left the terrain
                // (one cut short by its allowance is shaded where it stopped).
                sky_from_here = frame.sky_above_sky && sample.is_sky();
                sample
            };
            previous = Some(sample);
            for (s, v) in sum.iter_mut().zip(sample.color) {
                *s += u32::from(v);
            }
            if sub == samples / 2 {
                center = sample;
            }
        }
        let color = sum.map(|s| ((s + (1 << log2 >> 1)) >> log2) as u8);
        rays_per_pixel.rendered(&center, pixel.s);
        sink.put(pixel.x, pixel.y, Sample { color, ..center });
    }
}

/// The sample a ray may start at instead of the eye: where the anchor (the
/// ray cast before it on its line) hit, or `None` to cast it from the eye.
///
/// The rays of a line share their plane bit for bit, so at sample `i`
/// both are at the same major and minor coordinates and read the same
/// heights there. Their heights are `z0 + i·dz`, with `z0` the eye height
/// plus `delta0·dz` rounded down (`delta0` the same for both): a ray whose
/// `dz` is no smaller has a `z0` no smaller and is no lower at any sample
/// `i >= 0`. So wherever the anchor was above the surface, this ray is too,
/// on the same levels. With `same_schedule`, rays on other levels are cast
/// from the eye.
fn resume_at(anchor: &Anchor, ray: &Ray, same_schedule: bool) -> Option<i32> {
    let same_plane = anchor.key == ray.key && anchor.dminor == ray.dminor.to_bits();
    if !same_plane || ray.dz.to_bits() < anchor.dz || (same_schedule && anchor.lod != Some(ray.lod))
    {
        return None;
    }
    (anchor.start < anchor.k).then_some(anchor.k)
}

impl Anchor {
    /// Whether the next ray of the line, clipped to `clip`, would resume
    /// (see [`resume_at`]) past its last sample, so that its walk is empty
    /// and it sees the sky whatever the rest of its set-up. Its plane is
    /// the anchor's (the line's). Rays compared by schedule are left to
    /// the full set-up.
    #[inline]
    fn clears_all_of(&self, clip: &Clip, same_schedule: bool) -> bool {
        !same_schedule && clip.dz >= i64::from(self.dz) && self.start < self.k && self.k > clip.end
    }
}

fn sky(options: &RenderOptions) -> Sample {
    Sample {
        color: options.sky,
        distance: Sample::SKY,
        elevation: 0,
    }
}

/// Casts one ray: from the eye, or from `resume` (see [`resume_at`]). With
/// `first_hit_on`, a walk from the eye skips through the pyramid's bounds
/// first. Within `allowance` (see [`Allowances`]) the ray takes at most
/// `4n + 2` steps; a ray cut short is shaded where it stopped. Returns what
/// it saw and the sample up to which it is known to be above the surface
/// (its hit, or one past its last).
#[allow(clippy::too_many_arguments)]
fn cast<T: Surface + ?Sized, P: Probe>(
    surface: &T,
    ray: &Ray,
    resume: Option<i32>,
    first_hit_on: bool,
    allowance: u32,
    options: &RenderOptions,
    recent: &mut Recent,
    probe: &mut P,
) -> (Sample, i32) {
    // Walks `from..=end`, at most `allowance` samples (and the ray's end).
    let walk_at = |from: i32, recent: &mut Recent, probe: &mut P| {
        let end = if allowance == u32::MAX {
            ray.end
        } else {
            // (An allowance past i32::MAX is no limit on any ray.)
            let allowance = i32::try_from(allowance).unwrap_or(i32::MAX);
            ray.end.min(from.saturating_add(allowance - 1))
        };
        if from > end {
            Walk::Exit { last: end }
        } else {
            walk(surface, ray, ray.cursor(surface, from), end, recent, probe)
        }
    };
    let outcome = match resume {
        Some(resume) => walk_at(ray.next_visited(resume), recent, probe),
        None if first_hit_on => match first_hit(surface, ray, ray.start, ray.end, allowance, probe)
        {
            Some(k) => walk_at(ray.next_visited(k), recent, probe),
            None => Walk::Exit { last: ray.end },
        },
        None => walk_at(ray.start, recent, probe),
    };
    match outcome {
        Walk::Exit { last } if allowance != u32::MAX && last < ray.end && last >= ray.first => {
            // Cut short by the allowance: the color under the ray there.
            (shade_above(surface, ray, last, options, probe), last + 1)
        }
        Walk::Exit { last } => (sky(options), last + 1),
        Walk::Hit {
            at,
            clearance,
            above,
            stage,
        } => {
            // A first sample already below: find the one above it.
            let (at, clearance, above) = match above {
                Some(_) => (at, clearance, above),
                None => retrace(surface, ray, at, clearance, allowance, recent, probe),
            };
            (
                shade(surface, ray, stage, at, clearance, above, options, probe),
                at.k,
            )
        }
    }
}

/// The color of the surface under sample `k` of a ray cut short above it.
fn shade_above<T: Surface + ?Sized, P: Probe>(
    surface: &T,
    ray: &Ray,
    k: i32,
    options: &RenderOptions,
    probe: &mut P,
) -> Sample {
    let at = ray.cursor(surface, k);
    // Colored as a hit there would be: by the footprint past the color
    // reach (at the sample itself; there is no crossing), else level 0's
    // grid line.
    let color = footprint_color(surface, ray, &at, 0, None, 0, probe)
        .or_else(|| Stage::new(surface, ray, at.level).color(&ray.color_cursor(&at), probe));
    match color {
        Some(color) => Sample {
            color,
            distance: ray.distance(k).clamp(0, i64::from(Sample::SKY - 1)) as u32,
            elevation: at.z,
        },
        None => sky(options),
    }
}

/// The first visited sample was already below the surface: step back along
/// the samples a walk from the eye visits while the one before is below
/// too (never before the ray's start), and report the sample above and its
/// clearance, if there is one in the map.
fn retrace<T: Surface + ?Sized, P: Probe>(
    surface: &T,
    ray: &Ray,
    mut at: Cursor,
    mut below: i32,
    mut allowance: u32,
    recent: &mut Recent,
    probe: &mut P,
) -> (Cursor, i32, Option<(i32, i32)>) {
    while at.k > ray.first && allowance > 0 {
        allowance -= 1;
        let before = ray.cursor(surface, ray.previous_visited(at.k));
        let stage = Stage::new(surface, ray, before.level);
        let Some((cell, c)) = stage.clearance_recent(&before, recent, probe) else {
            break;
        };
        recent.add(cell);
        if c > 0 {
            return (at, below, Some((before.k, c)));
        }
        if before.k < ray.start {
            break;
        }
        at = before;
        below = c;
    }
    (at, below, None)
}

/// Colors a hit: the color where the hit sample's grid line is crossed and
/// (when known) where the previous visited sample's is, blended by where
/// between them the ray crossed the surface.
#[allow(clippy::too_many_arguments)]
fn shade<'s, T: Surface + ?Sized, P: Probe>(
    surface: &'s T,
    ray: &Ray,
    walked: Stage<T::Grid<'s>>,
    hit: Cursor,
    below: i32,
    above: Option<(i32, i32)>,
    options: &RenderOptions,
    probe: &mut P,
) -> Sample {
    let (position, before) = crossing(ray, &hit, below, above);
    // The walk's last stage, unless a retrace left its level.
    let stage = walked.on_level(surface, ray, hit.level);
    let color = if options.shading == Shading::Nearest {
        stage.nearest_color(&ray.color_cursor(&hit), probe)
    } else {
        // Most hits are near the eye, on level 0 (the crossing is no
        // farther than the hit sample): their colors need no coarse level,
        // and the far hits' work (not inlined) stays out of their way.
        let near = hit.level == 0 && ray.distance(hit.k) < ray.color_reach;
        let far = if near {
            None
        } else {
            let f = before.map_or(0, |(_, f)| f);
            footprint_color(surface, ray, &hit, below, above, f, probe)
        };
        far.or_else(|| {
            // Level 0 is fine enough: its colors on the hit's grid line and
            // (when known) the one before, blended by where the ray crossed.
            let on_hit_line = stage
                .color(&ray.color_cursor(&hit), probe)
                .or_else(|| stage.color(&hit, probe))?;
            let Some((k, f)) = before else {
                return Some(on_hit_line);
            };
            let before = ray.cursor_before(surface, &hit, k);
            // Mostly on the hit's level: its stage is at hand.
            let other_level;
            let before_stage = if before.level == hit.level {
                &stage
            } else {
                other_level = Stage::new(surface, ray, before.level);
                &other_level
            };
            Some(
                match before_stage.color(&ray.color_cursor(&before), probe) {
                    Some(on_line_before) => lerp(on_line_before, on_hit_line, f),
                    None => on_hit_line,
                },
            )
        })
    };
    let Some(color) = color else {
        return sky(options);
    };
    probe.hit(hit.level);
    Sample { color, ..position }
}

/// Where a ray crossed the surface: the distance and height of the hit,
/// moved back from the hit sample toward the visited sample before it (when
/// known) by the ratio of their clearances; and that sample with the
/// crossing's weight toward the hit (1/256 of the step). Colorless.
fn crossing(
    ray: &Ray,
    hit: &Cursor,
    below: i32,
    above: Option<(i32, i32)>,
) -> (Sample, Option<(i32, u32)>) {
    let (back, step, before) = match above {
        Some((before, above)) => {
            let t = crossing_fraction(above, below);
            (
                i64::from(256 - t),
                i64::from(hit.k - before),
                Some((before, t)),
            )
        }
        None => (0, 1, None),
    };
    let hit_distance = ray.distance(hit.k);
    // A crossing behind the eye (a ray that starts inside the terrain,
    // retraced past where it began) is the eye itself: distance 0, and the
    // ray's height there.
    let distance = (hit_distance - ((back * step) << 8)).max(0);
    let elevation =
        i64::from(hit.z) - (((hit_distance - distance) * i64::from(ray.dz.to_bits())) >> 16);
    (
        Sample {
            color: [0; 3],
            distance: distance.clamp(0, i64::from(Sample::SKY - 1)) as u32,
            elevation: elevation.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32,
        },
        before,
    )
}

/// Where between a sample above the surface (clearance `above` > 0) and the
/// next one below (`below` ≤ 0) the ray crosses it, in 1/256 of a step.
/// One division a pixel, outside the per-step loop.
fn crossing_fraction(above: i32, below: i32) -> u32 {
    let num = above.unsigned_abs();
    fraction_256(num, num + below.unsigned_abs())
}

/// `num / den` in 1/256 (`num ≤ den`): one 32-bit division, of both
/// brought under 2^24 so that the numerator's 8 extra bits fit.
#[inline]
fn fraction_256(num: u32, den: u32) -> u32 {
    let shift = (32 - den.leading_zeros()).saturating_sub(24);
    ((num >> shift) << 8) / (den >> shift).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Framebuffer, Pyramid};

    /// A 24 × 18 render at single resolution with `options` otherwise.
    fn small_image(pyramid: &Pyramid, view: &View, options: RenderOptions) -> [Rgb; 24 * 18] {
        let mut pixels = [[0u8; 3]; 24 * 18];
        let mut frame = Framebuffer::new(&mut pixels, 24, 18).unwrap();
        let options = RenderOptions {
            resolution: Resolution::Single,
            ..options
        };
        render(pyramid, view, &options, &mut frame, &mut crate::NoProbe);
        pixels
    }

    #[test]
    fn elongated_footprints_get_more_rays_and_short_ones_one() {
        const VOXEL: u32 = 1 << 16;
        const ONE: u64 = 1 << 16;
        let focal = 500i64 << 16;
        // The eye 10 voxels above the ground.
        let eye_z = 10i64 << 16;
        let at = |distance: u32, height: i32| Sample {
            color: [0; 3],
            distance,
            elevation: height << 16,
        };
        let log2 =
            |older: Sample, newer: Sample| footprint_rays_log2([&older, &newer], eye_z, focal, ONE);
        // Ground 1000 voxels out, a pixel 2 wide there: its hits 8 apart
        // are four widths long, 5 apart 2.5, 2 apart one.
        assert_eq!(log2(at(1000 * VOXEL, 0), at(1008 * VOXEL, 0)), 2);
        assert_eq!(log2(at(1000 * VOXEL, 0), at(1005 * VOXEL, 0)), 1);
        assert_eq!(log2(at(1000 * VOXEL, 0), at(1002 * VOXEL, 0)), 0);
        // Near the eye a footprint within a voxel needs one ray, however
        // thin it is (colors are interpolated between voxels).
        assert_eq!(log2(at(50 * VOXEL, 0), at(50 * VOXEL + VOXEL / 2, 0)), 0);
        assert_eq!(log2(at(50 * VOXEL, 0), at(54 * VOXEL, 0)), 2);
        // A slope facing the eye: hits at nearly one distance, and heights
        // a pixel's width apart.
        assert_eq!(log2(at(1000 * VOXEL, 0), at(1000 * VOXEL + 100, 2)), 0);
        // Straight down from 1000 voxels up: hits 2 apart near the nadir
        // are as long as a pixel is wide there.
        let high = 1000i64 << 16;
        let down = footprint_rays_log2([&at(VOXEL, 0), &at(3 * VOXEL, 0)], high, focal, ONE);
        assert_eq!(down, 0);
        // On a diagonal line the pixels are √2 apart: hits 8 apart 1000
        // voxels out are 2.8 widths a pixel.
        let diagonal = 92682; // √2, Q16
        let hits = [&at(1000 * VOXEL, 0), &at(1008 * VOXEL, 0)];
        assert_eq!(footprint_rays_log2(hits, eye_z, focal, diagonal), 1);
        // After sky, or on the line's first pixels: one ray.
        let sky = Sample {
            distance: Sample::SKY,
            ..at(0, 0)
        };
        assert_eq!(log2(sky, at(1000 * VOXEL, 0)), 0);
        assert_eq!(log2(at(1000 * VOXEL, 0), sky), 0);
    }

    /// Each pixel of [`render_by_footprint`] is the pixel one, two or four
    /// rays give: more where the ground is seen at a grazing angle, one
    /// looking straight down.
    #[test]
    fn by_footprint_each_pixel_takes_one_two_or_four_rays() {
        use crate::{Camera, CountingProbe, Terrain};
        use std::vec;
        // Flat, in 3-voxel stripes of black and white across y.
        let (w, d) = (64u32, 64u32);
        let heights = vec![0u16; (w * d) as usize];
        let colors: vec::Vec<Rgb> = (0..w * d)
            .map(|i| [((i / w) / 3 % 2 * 255) as u8; 3])
            .collect();
        let terrain = Terrain::new(w, d, &heights, &colors).unwrap();
        let pyramid = Pyramid::flat(terrain);
        // `None`: by footprint.
        let render_with = |camera: &Camera, vertical_samples: Option<VerticalSamples>| {
            let view = View::new(camera, 32, 24).unwrap();
            let mut pixels = [[0u8; 3]; 32 * 24];
            let mut frame = Framebuffer::new(&mut pixels, 32, 24).unwrap();
            let mut probe = CountingProbe::default();
            match vertical_samples {
                Some(vertical_samples) => {
                    let options = RenderOptions {
                        vertical_samples,
                        ..RenderOptions::default()
                    };
                    render(&pyramid, &view, &options, &mut frame, &mut probe)
                }
                None => render_by_footprint(
                    &pyramid,
                    &view,
                    &RenderOptions::default(),
                    &mut frame,
                    &mut probe,
                ),
            }
            (pixels, probe.rays)
        };
        let grazing = Camera::looking([32.0, 1.0, 6.0], 90.0, 8.0);
        let (by_footprint, rays) = render_with(&grazing, None);
        let fixed = [
            VerticalSamples::One,
            VerticalSamples::Two,
            VerticalSamples::Four,
        ]
        .map(|v| render_with(&grazing, Some(v)).0);
        for (i, color) in by_footprint.iter().enumerate() {
            assert!(fixed.iter().any(|f| f[i] == *color), "pixel {i}");
        }
        let four_alone = (0..by_footprint.len())
            .filter(|&i| by_footprint[i] == fixed[2][i] && by_footprint[i] != fixed[0][i])
            .count();
        assert!(four_alone > 20, "{four_alone} pixels took four rays");
        assert!(rays > 32 * 24 && rays < 4 * 32 * 24, "{rays} rays");
        // Straight down every footprint is about as long as it is wide.
        let down = Camera::looking([32.0, 32.0, 40.0], 90.0, 90.0);
        let (by_footprint, rays) = render_with(&down, None);
        assert_eq!(rays, 32 * 24);
        assert_eq!(
            by_footprint,
            render_with(&down, Some(VerticalSamples::One)).0
        );
    }

    #[test]
    fn crossing_fraction_is_proportional_and_bounded() {
        assert_eq!(crossing_fraction(1, 0), 256);
        assert_eq!(crossing_fraction(1, -1), 128);
        assert_eq!(crossing_fraction(3 << 16, -(1 << 16)), 192);
        assert_eq!(crossing_fraction(i32::MAX, i32::MIN), 127);
        assert!(crossing_fraction(1, i32::MIN) <= 1);
    }

    #[test]
    fn nearest_shading_shows_only_voxel_colors_and_subvoxel_blends_them() {
        use crate::{Camera, Terrain};
        // A flat 16 x 16 map of black and white stripes across x.
        let heights = [0u16; 256];
        let colors: [Rgb; 256] = core::array::from_fn(|i| [(i % 2 * 255) as u8; 3]);
        let terrain = Terrain::new(16, 16, &heights, &colors).unwrap();
        let pyramid = Pyramid::flat(terrain);
        let camera = Camera::looking([1.3, 2.1, 6.0], 70.0, 40.0);
        let view = View::new(&camera, 24, 18).unwrap();
        let shaded = |shading| {
            let options = RenderOptions {
                shading,
                ..RenderOptions::default()
            };
            small_image(&pyramid, &view, options)
        };
        let terrain_pixels = |p: [Rgb; 432]| {
            p.into_iter()
                .filter(|c| *c != DEFAULT_SKY)
                .collect::<std::vec::Vec<_>>()
        };
        let nearest = terrain_pixels(shaded(Shading::Nearest));
        assert!(!nearest.is_empty());
        assert!(
            nearest.iter().all(|c| *c == [0; 3] || *c == [255; 3]),
            "{nearest:?}"
        );
        let subvoxel = terrain_pixels(shaded(Shading::Subvoxel));
        assert!(subvoxel.iter().any(|c| c[0] > 20 && c[0] < 235));
    }

    /// Colors follow the pixel's footprint, not the level the heights are
    /// stepped on: with the height levels pushed past the map (a small
    /// terrain fit), a far hit on level 0 is shaded from the coarse
    /// levels, blended in from the color reach on.
    #[test]
    fn far_hits_take_the_footprints_colors_while_heights_stay_on_level_0() {
        use crate::pyramid::{pyramid_cells, pyramid_points};
        use crate::{Camera, Terrain};
        use std::vec;
        // Flat; level 0 black with white on every odd x, the coarse levels
        // (their storage filled by hand) gray.
        let heights = vec![0u16; 64 * 64];
        let colors: vec::Vec<Rgb> = (0..64 * 64).map(|i| [(i % 2 * 255) as u8; 3]).collect();
        let terrain = Terrain::new(64, 64, &heights, &colors).unwrap();
        let n = pyramid_points(64, 64);
        let (ph, pc, pb) = (
            vec![0; n],
            vec![[128; 3]; n],
            vec![0; pyramid_cells(64, 64)],
        );
        let pyramid = Pyramid::new(terrain, &ph, &pc, &pb).unwrap();
        let view = View::new(&Camera::looking([0.5, 30.2, 3.0], 0.0, 0.0), 64, 8).unwrap();
        // Colors reach level 1 14 voxels out (ratio 4); heights 16 times
        // farther, past the map.
        let plan = LodPlan::new(&view, 4 << 8, 1 << 12, pyramid.top());
        let ray = view.pixel_ray(&terrain.extent(), &plan, 32, 48);
        let (mut near, mut blended, mut far) = (0, 0, 0);
        for k in ray.start..=ray.end {
            let hit = ray.cursor(&pyramid, k);
            assert_eq!(hit.level, 0);
            let color = footprint_color(&pyramid, &ray, &hit, -1, None, 0, &mut crate::NoProbe);
            let distance = ray.distance(k);
            if distance < ray.color_reach {
                assert_eq!(color, None, "level 0 alone, at sample {k}");
                near += 1;
            } else if distance >= 2 * ray.color_reach {
                assert_eq!(color, Some([128; 3]), "coarse levels only, at sample {k}");
                far += 1;
            } else {
                let [r, g, b] = color.unwrap();
                assert!(r == g && g == b && r != 0 && r != 128 && r != 255, "{r}");
                blended += 1;
            }
        }
        assert!(near > 0 && blended > 0 && far > 0, "{near} {blended} {far}");
    }

    #[test]
    fn rays_above_a_line_that_left_the_terrain_see_the_same_sky_without_their_set_up() {
        use crate::{Camera, Terrain};
        // Ridges across a 32 x 32 map, seen from low and far: most lines
        // leave the terrain part way up. At single resolution every ray's
        // schedule is the same, so Exact resumes exactly where AcrossLevels
        // does; only AcrossLevels skips the set-up of rays that would
        // resume past their end.
        let heights: [u16; 1024] = core::array::from_fn(|i| ((i % 32 * 7) % 20) as u16 * 16);
        let colors: [Rgb; 1024] = core::array::from_fn(|i| [(i % 256) as u8, (i / 4) as u8, 90]);
        let terrain = Terrain::new(32, 32, &heights, &colors).unwrap();
        let pyramid = Pyramid::flat(terrain);
        for (eye, yaw, pitch) in [
            ([-6.0, 16.0, 22.0], 0.0, 3.0),
            ([2.0, 3.0, 25.0], 45.0, 20.0),
            ([40.0, 30.0, 24.0], 200.0, -5.0),
            ([16.0, 16.0, 30.0], 300.0, 40.0),
        ] {
            let camera = Camera::looking(eye, yaw, pitch);
            let view = View::new(&camera, 24, 18).unwrap();
            let image = |coherence| {
                let options = RenderOptions {
                    coherence,
                    ..RenderOptions::default()
                };
                small_image(&pyramid, &view, options)
            };
            let skipping = image(Coherence::AcrossLevels);
            assert!(skipping.contains(&DEFAULT_SKY), "{eye:?}: no sky");
            assert!(
                skipping.iter().any(|p| *p != DEFAULT_SKY),
                "{eye:?}: only sky"
            );
            assert!(skipping == image(Coherence::Exact), "{eye:?}");
            assert!(skipping == image(Coherence::Off), "{eye:?}");
        }
    }

    #[test]
    fn lerp_hits_both_ends() {
        assert_eq!(lerp([0, 100, 255], [255, 0, 255], 0), [0, 100, 255]);
        assert_eq!(lerp([0, 100, 255], [255, 0, 255], 256), [255, 0, 255]);
        assert_eq!(lerp([0, 0, 0], [255, 255, 255], 128), [128, 128, 128]);
    }

    /// Two channels share a word in `lerp`: each must still round exactly
    /// as on its own, whatever its neighbours hold.
    #[test]
    fn lerp_rounds_each_channel_as_on_its_own() {
        let alone = |a: u8, b: u8, t: u32| {
            let t = t.min(256);
            ((u32::from(a) * (256 - t) + u32::from(b) * t + 128) >> 8) as u8
        };
        for x in 0..=255u8 {
            for y in 0..=255u8 {
                let (a, b) = ([x, !x, x], [y, y, !y]);
                for t in (0..=256).chain([300, u32::MAX]) {
                    let expected: Rgb = core::array::from_fn(|i| alone(a[i], b[i], t));
                    assert_eq!(lerp(a, b, t), expected, "{a:?} {b:?} {t}");
                }
            }
        }
    }
}
