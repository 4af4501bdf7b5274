//! The per-ray path: the settings the line caster does not take
//! ([`Coherence::Off`] and [`Coherence::Exact`], several rays a pixel, a
//! frame budget) set every ray up in full: its
//! direction, its clip against the map and its level schedule. The rays of
//! a line lie in one vertical plane and share their horizontal direction
//! bit for bit, so each ray can start at the sample where the ray before it
//! hit ([`resume_at`]).
//!
//! [`Coherence::Off`]: super::Coherence::Off
//! [`Coherence::Exact`]: super::Coherence::Exact

use super::first_hit::first_hit;
use super::footprint_color::{detail_color, footprint_color};
use super::line_caster::Fetches;
use super::walk::{lerp, walk, Recent, Stage, Walk};
use super::{crossing_fraction, sky, Frame, RenderOptions, Shading};
use crate::probe::Probe;
use crate::sink::{Sample, Sink};
use crate::surface::Surface;
use crate::view::lines::Line;
use crate::view::lod::Lod;
use crate::view::plane::Plane;
use crate::view::ray::{Clip, Cursor, Ray, RayKey};
use crate::view::View;

/// How many steps each ray of a line may take, asked before each ray:
/// `u32::MAX` for no limit, `n` for at most `4n + 2` steps (the ray is cut
/// short past that), 0 for none at all (the pixel repeats the line's
/// previous one).
pub(crate) trait Allowances {
    /// What the line caster counts a ray's height fetches with
    /// ([`Fetches::for_allowance`]).
    type Fetches: Fetches;
    /// Whether any ray may be limited: `false` (the plain render) compiles
    /// the line caster's step counting out.
    const LIMITED: bool = <Self::Fetches as Fetches>::LIMITED;
    fn next(&mut self) -> u32;
    /// Whether the line's next pixel is rendered: `false` ends the line,
    /// its remaining pixels left as the sink has them (a frame's
    /// refinement stops where its budget does).
    #[inline(always)]
    fn pixel(&mut self) -> bool {
        true
    }
}

/// No limit: the plain render.
pub(crate) struct Unlimited;

impl Allowances for Unlimited {
    type Fetches = Unlimited;
    #[inline(always)]
    fn next(&mut self) -> u32 {
        u32::MAX
    }
}

/// The per-ray path for one frame: what its lines share (the surface, the
/// view, the settings and what they plan for the frame). Every ray is set
/// up in full: its direction, its clip against the map, its level
/// schedule; coherence lets it start where the ray before it hit.
pub(crate) struct RayCaster<'s, 'v, T: Surface + ?Sized> {
    surface: &'s T,
    view: &'v View,
    options: &'v RenderOptions,
    frame: Frame,
}

impl<'s, 'v, T: Surface + ?Sized> RayCaster<'s, 'v, T> {
    pub fn new(surface: &'s T, view: &'v View, options: &'v RenderOptions) -> Self {
        Self {
            surface,
            view,
            options,
            frame: Frame::new(surface, view, options),
        }
    }

    /// Renders image line `line` with `options.vertical_samples` rays a
    /// pixel, each within the steps `allowances` gives it.
    pub fn line<S: Sink, P: Probe, A: Allowances>(
        &self,
        line: u32,
        sink: &mut S,
        probe: &mut P,
        allowances: &mut A,
    ) {
        let rays = FixedRays(self.options.vertical_samples.log2());
        self.line_rays(line, sink, probe, allowances, rays);
    }

    /// Renders image line `line` with rays by footprint, unlimited (see
    /// [`super::render_by_footprint`]).
    pub fn line_by_footprint<S: Sink, P: Probe>(&self, line: u32, sink: &mut S, probe: &mut P) {
        let rays = RaysByFootprint::new(self.view, self.options, 0);
        self.line_rays(line, sink, probe, &mut Unlimited, rays);
    }

    /// Renders image line `line` again, finer, each ray within
    /// `allowances`, which may end the line early. Round 1: rays by
    /// footprint, at least two a pixel (2 or 4); round 2 and later: the
    /// same doubled `round − 1` times (round 2: 4 or 8 rays), at most
    /// [`REFINED_MOST_LOG2`].
    pub fn line_refined<S: Sink, P: Probe, A: Allowances>(
        &self,
        line: u32,
        round: u32,
        sink: &mut S,
        probe: &mut P,
        allowances: &mut A,
    ) {
        let doubled = round
            .saturating_sub(1)
            .min(REFINED_MOST_LOG2 - FOOTPRINT_MOST_LOG2);
        let mut rays = RaysByFootprint::new(self.view, self.options, 1 + doubled);
        rays.doubled = doubled;
        self.line_rays(line, sink, probe, allowances, rays);
    }

    /// Renders a line with the rays a pixel `rays_per_pixel` gives.
    fn line_rays<S: Sink, P: Probe, A: Allowances, R: RaysPerPixel>(
        &self,
        line: u32,
        sink: &mut S,
        probe: &mut P,
        allowances: &mut A,
        mut rays_per_pixel: R,
    ) {
        let (surface, view, options, frame) = (self.surface, self.view, self.options, &self.frame);
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
            if !allowances.pixel() {
                return;
            }
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
                    line.pixel_direction(&pixel)
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
                    let (sample, clear_until) =
                        self.cast(&ray, resume, allowance, &mut recent, probe);
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

    /// Casts one ray: from the eye, or from `resume` (see [`resume_at`]). With
    /// the frame's first hit on, a walk from the eye skips through the pyramid's bounds
    /// first. Within `allowance` (see [`Allowances`]) the ray takes at most
    /// `4n + 2` steps; a ray cut short is shaded where it stopped. Returns what
    /// it saw and the sample up to which it is known to be above the surface
    /// (its hit, or one past its last).
    fn cast<P: Probe>(
        &self,
        ray: &Ray,
        resume: Option<i32>,
        allowance: u32,
        recent: &mut Recent,
        probe: &mut P,
    ) -> (Sample, i32) {
        let (surface, options) = (self.surface, self.options);
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
            None if self.frame.first_hit => {
                match first_hit(surface, ray, ray.start, ray.end, allowance, probe) {
                    Some(k) => walk_at(ray.next_visited(k), recent, probe),
                    None => Walk::Exit { last: ray.end },
                }
            }
            None => walk_at(ray.start, recent, probe),
        };
        match outcome {
            Walk::Exit { last } if allowance != u32::MAX && last < ray.end && last >= ray.first => {
                // Cut short by the allowance: the color under the ray there.
                (self.shade_above(ray, last, probe), last + 1)
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
                    None => self.retrace(ray, at, clearance, allowance, recent, probe),
                };
                (self.shade(ray, stage, at, clearance, above, probe), at.k)
            }
        }
    }

    /// The color of the surface under sample `k` of a ray cut short above it.
    fn shade_above<P: Probe>(&self, ray: &Ray, k: i32, probe: &mut P) -> Sample {
        let surface = self.surface;
        let at = ray.cursor(surface, k);
        // Colored as a hit there would be: by the footprint past the color
        // reach (at the sample itself; there is no crossing), else level 0's
        // grid line.
        let color = footprint_color(surface, ray, &at, 0, None, 0, probe).or_else(|| {
            Stage::new(surface, ray, at.level).color(&ray.color_cursor(&at), at.z, probe)
        });
        match color {
            Some(color) => Sample {
                color,
                distance: ray.distance(k).clamp(0, i64::from(Sample::SKY - 1)) as u32,
                elevation: at.z,
            },
            None => sky(self.options),
        }
    }

    /// The first visited sample was already below the surface: step back along
    /// the samples a walk from the eye visits while the one before is below
    /// too (never before the ray's start), and report the sample above and its
    /// clearance, if there is one in the map.
    fn retrace<P: Probe>(
        &self,
        ray: &Ray,
        mut at: Cursor,
        mut below: i32,
        mut allowance: u32,
        recent: &mut Recent,
        probe: &mut P,
    ) -> (Cursor, i32, Option<(i32, i32)>) {
        let surface = self.surface;
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
    fn shade<P: Probe>(
        &self,
        ray: &Ray,
        walked: Stage<T::Grid<'s>>,
        hit: Cursor,
        below: i32,
        above: Option<(i32, i32)>,
        probe: &mut P,
    ) -> Sample {
        let (surface, options) = (self.surface, self.options);
        let (position, before) = crossing(ray, &hit, below, above);
        // The walk's last stage, unless a retrace left its level.
        let stage = walked.on_level(surface, ray, hit.level);
        let color = if options.shading == Shading::Nearest {
            stage.nearest_color(&ray.color_cursor(&hit), position.elevation, probe)
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
            let far = far.or_else(|| {
                if !surface.has_details() {
                    return None;
                }
                let f = before.map_or(0, |(_, f)| f);
                detail_color(surface, ray, &hit, below, above, f, probe)
            });
            far.or_else(|| {
                // Level 0 is fine enough: its colors on the hit's grid line and
                // (when known) the one before, blended by where the ray crossed.
                let z = position.elevation;
                let hit_cursor = ray.color_cursor(&hit);
                let on_hit_line = stage
                    .color(&hit_cursor, z, probe)
                    .or_else(|| stage.color(&hit, z, probe))?;
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
                let before_cursor = ray.color_cursor(&before);
                Some(match before_stage.color(&before_cursor, z, probe) {
                    Some(on_line_before) => {
                        let cursors = (&before_cursor, &hit_cursor);
                        let f = stage.along_weight(before_stage, cursors, z, f);
                        lerp(on_line_before, on_hit_line, f)
                    }
                    None => on_hit_line,
                })
            })
        };
        let Some(color) = color else {
            return sky(options);
        };
        probe.hit(hit.level);
        Sample { color, ..position }
    }
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

/// [`super::render_by_footprint`]'s counts: by the footprint of the pixel before.
/// One for each line (the line loop takes it by value).
struct RaysByFootprint {
    /// The hits of the two pixels before on the line, older first, and
    /// their rows (near the vanishing point a line skips rows).
    before: [(Sample, i32); 2],
    eye_z: i64,
    focal: i64,
    /// The line's pixel spacing (`Line::pixel_spacing_q16`).
    spacing: u64,
    /// log2 of the fewest rays a pixel gets.
    least_log2: u32,
    /// Added to the footprint's log2: each pixel's rays doubled this many
    /// times (the governor's later refinement rounds).
    doubled: u32,
}

impl RaysByFootprint {
    fn new(view: &View, options: &RenderOptions, least_log2: u32) -> Self {
        Self {
            before: [(sky(options), 0); 2],
            eye_z: view.eye[2].to_bits(),
            focal: view.focal,
            spacing: 1 << 16,
            least_log2,
            doubled: 0,
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
        (footprint_rays_log2([older, newer], self.eye_z, self.focal, self.spacing * rows)
            + self.doubled)
            .max(self.least_log2)
    }
    fn rendered(&mut self, center: &Sample, row: i32) {
        self.before = [self.before[1], (*center, row)];
    }
}

/// log2 of the most rays [`super::render_by_footprint`] gives a pixel.
const FOOTPRINT_MOST_LOG2: u32 = 2;

/// log2 of the most rays a refined pixel gets ([`RayCaster::line_refined`]).
pub(super) const REFINED_MOST_LOG2: u32 = 3;

/// log2 of the rays [`super::render_by_footprint`] gives a pixel, from the hits
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
pub(super) fn footprint_rays_log2(
    [older, newer]: [&Sample; 2],
    eye_z: i64,
    focal: i64,
    spacing: u64,
) -> u32 {
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

/// What the last cast ray of a column established: it was above the surface
/// at every sample in `start..k`.
#[derive(Debug, Clone, Copy)]
struct Anchor {
    key: RayKey,
    /// `None` for a ray whose schedule was not worked out: one that resumed
    /// past its end, which only [`super::Coherence::AcrossLevels`] lets a ray do
    /// without it (see [`Anchor::clears_all_of`]).
    lod: Option<Lod>,
    start: i32,
    k: i32,
    dminor: i32,
    dz: i32,
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
