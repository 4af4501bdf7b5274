//! The caster: each image line through the vertical's vanishing point,
//! one ray after another by rising elevation (see [`crate::View::lines`]).
//!
//! - `options.rs`: what a render may be asked to do ([`RenderOptions`]).
//! - `line_caster.rs`: the default coherence's path with one ray a pixel,
//!   in either shading. A line is set up once and a ray is its slope; it
//!   resumes where the ray before it hit.
//! - `ray_caster.rs`: every other setting's path ([`Coherence::Off`],
//!   [`Coherence::Exact`], several rays a pixel, a frame budget). Every ray is set up in full, and may start where the ray
//!   before it hit. [`Coherence::Exact`] casts a ray whose levels differ
//!   from the ray before's from the eye, so the image equals the image with
//!   every ray cast from the eye, bit for bit (tested).
//! - `walk.rs`: the per-step loop, a level's heights and colors;
//!   `first_hit.rs`: the skip through the pyramid's height bounds;
//!   `footprint_color.rs`: colors past the color reach, from the levels the
//!   pixel's footprint brackets, blended by depth (the soft transition);
//!   `budget.rs`: the frame-time governor; `per_line.rs`: the per-line
//!   design at its smallest, the bound the line caster is measured against.
//!
//! Both paths refine a hit between the last sample above the surface and
//! the first one below by the ratio of their clearances, and color it near
//! the eye with level 0's grid lines, blended across both by the subvoxel
//! weights.

mod budget;
mod first_hit;
mod footprint_color;
mod line_caster;
mod options;
mod per_line;
mod ray_caster;
pub(crate) mod walk;

pub use budget::{FrameCost, FrameWork, Governor, LineShare, Prices};
pub use options::{Coherence, HeightPath, RenderOptions, Resolution, Shading, VerticalSamples};
pub use per_line::{
    render_level_columns, render_level_columns_lean, render_pixel_lines, render_pixel_path,
    render_pixel_path_lean, render_pixel_path_tabled, tabulate_pixel_ownership, ColumnsError,
};

use crate::probe::Probe;
use crate::sink::{Sample, Sink};
use crate::surface::Surface;
use crate::view::lod::LodPlan;
use crate::view::View;
pub use line_caster::{MAX_SEE_THROUGH, SEE_THROUGH_REACH};
use ray_caster::{RayCaster, Unlimited};

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
    /// `ray_caster::resume_at`; the pixels' directions step linearly along the line,
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
        let lod = match options.shading {
            Shading::LevelZero => lod.without_far_colors(),
            Shading::Subvoxel | Shading::Nearest => lod,
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
            probe.line(line);
            caster.line(line, sink, probe);
        }
        return;
    }
    let caster = RayCaster::new(surface, view, options);
    for line in 0..view.lines() {
        probe.line(line);
        caster.line(line, sink, probe, &mut Unlimited);
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
    let caster = RayCaster::new(surface, view, options);
    for line in 0..view.lines() {
        probe.line(line);
        caster.line_by_footprint(line, sink, probe);
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
    RayCaster::new(surface, view, options).line_by_footprint(line, sink, probe);
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
    RayCaster::new(surface, view, options).line(line, sink, probe, &mut Unlimited);
}

fn sky(options: &RenderOptions) -> Sample {
    Sample::sky(options.sky)
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
    use super::footprint_color::footprint_color;
    use super::walk::lerp;
    use super::*;
    use crate::config::DEFAULT_SKY;
    use crate::{Framebuffer, Pyramid, Rgb};

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

    /// `Shading::LevelZero` keeps a hit on level 0 in level 0's colors at
    /// any depth, where the default takes the coarse levels' past the
    /// color reach; nearer hits are shaded alike.
    #[test]
    fn level_zero_shading_keeps_far_hits_in_level_0s_colors() {
        use crate::pyramid::{pyramid_cells, pyramid_points};
        use crate::{Camera, Terrain};
        use std::vec;
        // Flat; level 0 red and blue stripes, the coarse levels (their
        // storage filled by hand) green. The map is said to be rough, so
        // the terrain fit keeps the heights on level 0 past the map, while
        // colors switch by the ratio (4: level 1 from 14 voxels out).
        let heights = vec![0u16; 64 * 64];
        let colors: vec::Vec<Rgb> = (0..64 * 64)
            .map(|i| if i % 2 == 0 { [255, 0, 0] } else { [0, 0, 255] })
            .collect();
        let terrain = Terrain::new(64, 64, &heights, &colors).unwrap();
        let n = pyramid_points(64, 64);
        let (ph, pc, pb) = (
            vec![0; n],
            vec![[0, 255, 0]; n],
            vec![0; pyramid_cells(64, 64)],
        );
        let pyramid = Pyramid::with_roughness(terrain, &ph, &pc, &pb, u8::MAX).unwrap();
        let view = View::new(&Camera::looking([0.5, 30.2, 3.0], 0.0, 0.0), 64, 48).unwrap();
        let image = |shading| {
            let mut pixels = [[0u8; 3]; 64 * 48];
            let mut frame = Framebuffer::new(&mut pixels, 64, 48).unwrap();
            let options = RenderOptions {
                resolution: Resolution::Multi {
                    pixel_to_voxel: crate::U8F8::from_num(4),
                },
                shading,
                ..RenderOptions::default()
            };
            render(&pyramid, &view, &options, &mut frame, &mut crate::NoProbe);
            pixels
        };
        let (footprint, level_zero) = (image(Shading::Subvoxel), image(Shading::LevelZero));
        let terrain = |p: &Rgb| *p != DEFAULT_SKY;
        let green = |p: &Rgb| terrain(p) && p[1] > 0;
        assert!(footprint.iter().any(green), "no far hit");
        assert!(!level_zero.iter().any(green));
        let mut near = 0;
        for (a, b) in footprint.iter().zip(&level_zero) {
            if terrain(a) && !green(a) {
                assert_eq!(a, b);
                near += 1;
            }
        }
        assert!(near > 0);
        // The same hits: the same pixels are terrain.
        assert!(footprint
            .iter()
            .zip(&level_zero)
            .all(|(a, b)| terrain(a) == terrain(b)));
    }

    /// Nearest shading goes the line caster's way too: at single
    /// resolution its image is the one every ray set up in full gives,
    /// bit for bit, rolled or not.
    #[test]
    fn the_line_caster_shades_nearest_as_the_per_ray_path_does() {
        use crate::{Camera, Terrain};
        let heights: [u16; 1024] =
            core::array::from_fn(|i| ((i % 32 * 7 + i / 32 * 3) % 20) as u16 * 16);
        let colors: [Rgb; 1024] = core::array::from_fn(|i| [(i % 256) as u8, (i / 4) as u8, 90]);
        let terrain = Terrain::new(32, 32, &heights, &colors).unwrap();
        let pyramid = Pyramid::flat(terrain);
        for (eye, yaw, pitch, roll) in [
            ([-6.0, 16.0, 22.0], 0.0, 3.0, 0.0),
            ([2.0, 3.0, 25.0], 45.0, 20.0, 30.0),
            ([40.0, 30.0, 24.0], 200.0, 0.0, -15.0),
            ([16.0, 16.0, 30.0], 300.0, 60.0, 135.0),
        ] {
            let camera = Camera {
                roll_deg: roll,
                ..Camera::looking(eye, yaw, pitch)
            };
            let view = View::new(&camera, 24, 18).unwrap();
            let image = |coherence| {
                let options = RenderOptions {
                    coherence,
                    shading: Shading::Nearest,
                    ..RenderOptions::default()
                };
                small_image(&pyramid, &view, options)
            };
            let lines = image(Coherence::AcrossLevels);
            assert!(lines.iter().any(|p| *p != DEFAULT_SKY), "{eye:?}: only sky");
            assert!(lines == image(Coherence::Exact), "{eye:?}");
            // Nearest: every terrain pixel is one voxel's color.
            assert!(
                lines
                    .iter()
                    .all(|p| *p == DEFAULT_SKY || colors.contains(p)),
                "{eye:?}"
            );
        }
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
