//! Complex sticks (Cohen-Or §2): a hit on texels less than opaque
//! ([`crate::StickTable::with_alphas`]) is blended with what a **secondary
//! ray** sees through them.
//!
//! The secondary ray is the same ray, continued from its hit sample over
//! the surface with the see-through points it hit lowered to their ground
//! ([`Grid::ground`]): a leaf at a crown's edge lets through what is behind
//! its stick. It walks level 0 on its own path (its drift aside of the
//! line) and is shaded as a near hit is: both grid lines' colors and
//! opacities at the crossing, blended by the subvoxel and along weights.
//! A hit it makes on see-through texels casts the next, up to
//! [`MAX_SEE_THROUGH`] a pixel; the colors are composited front to back,
//! each by its opacity. A secondary ray that rises above the highest
//! terrain or leaves the map sees the sky; one that finds nothing within
//! [`SEE_THROUGH_REACH`] samples leaves the texels before it opaque.
//!
//! The caster shades a hit here only where a complex stick stands on a
//! grid line it is shaded from ([`Grid::may_see_through`]); it shades
//! every other hit as an opaque one, at no cost for the opacities.
//!
//! Only near hits on level 0 see through: past the color reach and on the
//! coarser levels the pyramid's filtered colors stand for the objects, so
//! small cavities are filled there and cost no ray. The primary ray's
//! coherence is untouched: every primary ray stops at a stick's surface,
//! as with opaque sticks, so the next ray of the line resumes there.

use super::{LineCaster, LineWalk, HEIGHT_TO_Q16};
use crate::caster::crossing_fraction;
use crate::caster::walk::lerp;
use crate::color::Rgb;
use crate::config::{COORD_FRAC_BITS, HEIGHT_WEIGHT_BITS, WEIGHT_BITS};
use crate::probe::Probe;
use crate::surface::{Grid, Surface};
use crate::view::words::saturate;

/// Secondary rays a pixel may cast through see-through texels.
pub const MAX_SEE_THROUGH: usize = 2;
/// Samples of level 0 a secondary ray walks before it gives up, leaving
/// the texels in front of it opaque.
pub const SEE_THROUGH_REACH: i32 = 256;
/// Points a pixel's rays lower: the two of each of the two grid lines a
/// hit is shaded from, for the primary ray and each secondary one.
const MAX_LOWERED: usize = 4 * (MAX_SEE_THROUGH + 1);

/// A near hit on level 0, as [`LineCaster::see_through`] takes it.
#[derive(Clone, Copy)]
pub(super) struct NearHit {
    /// Its sample, that sample's major grid line's index and the line's
    /// minor coordinate there (Q16).
    pub k: i32,
    pub index: isize,
    pub minor: i32,
    /// The ray's height at the sample (Q16), its change a sample, and its
    /// colors' drift aside of the line ([`super::HitRay`]).
    pub z: i64,
    pub dz: i32,
    pub drift: i32,
    /// The crossing's height (Q16), and how far (of 256) it is from the
    /// sample before to the hit: 256 where it is shaded from the hit's
    /// grid line alone.
    pub elevation: i32,
    pub t: u32,
}

/// The points lowered to their ground, for a pixel's secondary rays.
struct Lowered {
    points: [isize; MAX_LOWERED],
    count: usize,
}

impl Lowered {
    fn holds(&self, index: isize) -> bool {
        self.points[..self.count].contains(&index)
    }

    fn add(&mut self, index: isize) {
        if self.count < MAX_LOWERED && !self.holds(index) {
            self.points[self.count] = index;
            self.count += 1;
        }
    }
}

/// One grid line's shading at a crossing: its blended color and opacity,
/// and its first point.
struct LineShade {
    color: Rgb,
    alpha: u32,
    cell: isize,
    /// The opacities of its two points.
    alphas: (u8, u8),
    /// Which of them a secondary ray sees through (plain ground to it).
    lowered: (bool, bool),
}

/// How a secondary ray ends.
enum Through {
    /// At or below the surface at sample `k`, `below` under it there;
    /// `above` over it at the sample before, where it was.
    Hit {
        k: i32,
        above: Option<i32>,
        below: i32,
    },
    /// It rose above the highest terrain or left the map.
    Sky,
    /// Nothing within [`SEE_THROUGH_REACH`] samples.
    Lost,
}

impl<T: Surface + ?Sized> LineCaster<'_, '_, T> {
    /// The color of `hit`: both grid lines' colors and opacities at the
    /// crossing, composited with what the secondary rays see through it
    /// where it is less than opaque ([`LineCaster::see_behind`]). Out of
    /// line: the caster takes it only for a crossing by a complex stick.
    #[inline(never)]
    pub(super) fn see_through<P: Probe>(
        &self,
        walk: &LineWalk,
        hit: &NearHit,
        probe: &mut P,
    ) -> Rgb {
        let mut lowered = Lowered {
            points: [0; MAX_LOWERED],
            count: 0,
        };
        let crossing = (hit.k, hit.t, hit.elevation);
        let (color, alpha) =
            self.shade_crossing::<false, _>(walk, hit, crossing, &mut lowered, probe);
        if alpha >= 255 {
            return color;
        }
        self.see_behind(walk, hit, (color, alpha), lowered, probe)
    }

    /// `hit`'s color and opacity (less than opaque) composited with what
    /// the secondary rays see through it, the points it sees through in
    /// `lowered`.
    #[inline(never)]
    fn see_behind<P: Probe>(
        &self,
        walk: &LineWalk,
        hit: &NearHit,
        (mut color, mut alpha): (Rgb, u32),
        mut lowered: Lowered,
        probe: &mut P,
    ) -> Rgb {
        // Front to back: each layer's color and opacity.
        let mut layers = [([0u8; 3], 0u32); MAX_SEE_THROUGH];
        let (mut count, mut from) = (0, hit.k);
        let behind = loop {
            if alpha >= 255 || count == MAX_SEE_THROUGH {
                break color;
            }
            layers[count] = (color, alpha);
            count += 1;
            probe.secondary_ray();
            match self.through(walk, hit, from, &lowered, probe) {
                Through::Sky => break self.sky.color,
                Through::Lost => {
                    // Nothing behind: the last layer shows as it is.
                    count -= 1;
                    break layers[count].0;
                }
                Through::Hit { k, above, below } => {
                    let t = above.map_or(256, |above| crossing_fraction(above, below));
                    let elevation = saturate(
                        ray_height(hit, k) - ((i64::from(256 - t) * i64::from(hit.dz)) >> 8),
                    );
                    (color, alpha) = self.shade_crossing::<true, _>(
                        walk,
                        hit,
                        (k, t, elevation),
                        &mut lowered,
                        probe,
                    );
                    from = k;
                }
            }
        };
        layers[..count]
            .iter()
            .rev()
            .fold(behind, |behind, &(color, alpha)| {
                lerp(behind, color, alpha + (alpha >> 7))
            })
    }

    /// Adds the points of `line` (on `walk`'s level 0) that are less than
    /// opaque to `lowered`.
    fn lower(walk: &LineWalk, line: &LineShade, lowered: &mut Lowered) {
        if line.alphas.0 < u8::MAX {
            lowered.add(line.cell);
        }
        if line.alphas.1 < u8::MAX {
            lowered.add(line.cell + walk.across[0]);
        }
    }

    /// The shading of the grid line of level 0 at sample `k` of `hit`'s
    /// line, `aside` (Q16) across it, at height `z` (Q16); for a
    /// `SECONDARY` ray, the points in `lowered` plain terrain at their
    /// ground (a primary ray has lowered none: it skips the test).
    #[inline(always)]
    fn line_shade<const SECONDARY: bool, P: Probe>(
        &self,
        walk: &LineWalk,
        hit: &NearHit,
        (k, aside, z): (i32, i32, i32),
        lowered: &Lowered,
        probe: &mut P,
    ) -> LineShade {
        let (index, minor) = Self::sample_at(walk, hit, k, aside);
        let across = walk.across[0];
        let cell = index + (minor >> COORD_FRAC_BITS) as isize * across;
        let weight = ((minor >> (COORD_FRAC_BITS - WEIGHT_BITS)) & ((1 << WEIGHT_BITS) - 1)) as u32;
        probe.color(0, cell as usize);
        let lowered = if SECONDARY {
            (lowered.holds(cell), lowered.holds(cell + across))
        } else {
            (false, false)
        };
        match self.grids[0].seen_pair_at(cell, across, z, lowered) {
            Some(((c0, a0), (c1, a1))) => {
                let (color, alpha) = mix((c0, u32::from(a0)), (c1, u32::from(a1)), weight);
                LineShade {
                    color,
                    alpha,
                    cell,
                    alphas: (a0, a1),
                    lowered,
                }
            }
            None => LineShade {
                color: self.sky.color,
                alpha: 255,
                cell,
                alphas: (u8::MAX, u8::MAX),
                lowered,
            },
        }
    }

    /// The index of sample `k`'s major grid line on level 0 and the line's
    /// minor coordinate there (Q16), `hit`'s line stepped from its sample.
    fn on_line(walk: &LineWalk, hit: &NearHit, k: i32) -> (isize, i32) {
        let steps = k - hit.k;
        let index = hit.index + steps as isize * walk.step[0];
        let minor = hit
            .minor
            .saturating_add(steps.saturating_mul(walk.minor_step[0]));
        (index, minor)
    }

    /// [`LineCaster::on_line`], its minor coordinate moved `aside` (Q16)
    /// across the line.
    fn sample_at(walk: &LineWalk, hit: &NearHit, k: i32, aside: i32) -> (isize, i32) {
        let (index, minor) = Self::on_line(walk, hit, k);
        (index, walk.aside(minor, aside))
    }

    /// The ray's clearance (Q16) at height `z` (Q16) over the blended
    /// height where it is at `(index, minor)` (a major grid line of level
    /// 0 and a minor coordinate, Q16), the points in `lowered` (if any
    /// may be on this grid line) at their ground; `None` outside the map.
    #[inline(always)]
    fn clearance<P: Probe>(
        &self,
        walk: &LineWalk,
        (index, minor, z): (isize, i32, i64),
        lowered: Option<&Lowered>,
        probe: &mut P,
    ) -> Option<i32> {
        let across = walk.across[0];
        let cell = index + (minor >> COORD_FRAC_BITS) as isize * across;
        let grid = &self.grids[0];
        let (mut h0, mut h1) = grid.height_pair(cell, across)?;
        if let Some(lowered) = lowered {
            if lowered.holds(cell) {
                h0 = grid.ground(cell)?;
            }
            if lowered.holds(cell + across) {
                h1 = grid.ground(cell + across)?;
            }
        }
        probe.visit(0, cell as usize);
        let (h0, h1) = (i32::from(h0), i32::from(h1));
        let weight =
            (minor >> (COORD_FRAC_BITS - HEIGHT_WEIGHT_BITS)) & ((1 << HEIGHT_WEIGHT_BITS) - 1);
        let ground = (h0 << HEIGHT_TO_Q16) + (h1 - h0) * weight;
        Some(saturate(z - i64::from(ground)))
    }

    /// Walks `hit`'s ray on from sample `from` over the surface with
    /// `lowered`'s points at their ground, to its next hit. Its position
    /// steps by adds: its drift aside grows by the drift a sample. The
    /// points lowered are on the grid lines of the hits before, none past
    /// sample `from`'s: the samples after it need no test of them.
    fn through<P: Probe>(
        &self,
        walk: &LineWalk,
        hit: &NearHit,
        from: i32,
        lowered: &Lowered,
        probe: &mut P,
    ) -> Through {
        let start = from - 1;
        let (mut aside, mut z) = (
            Self::aside_at(walk, start, hit.drift),
            ray_height(hit, start),
        );
        let (mut index, mut minor) = Self::on_line(walk, hit, start);
        let at = |index, minor, aside, z| (index, walk.aside(minor, aside), z);
        let mut above = if start >= walk.first {
            self.clearance(walk, at(index, minor, aside, z), Some(lowered), probe)
                .filter(|&c| c > 0)
        } else {
            None
        };
        let end = walk.last.min(from.saturating_add(SEE_THROUGH_REACH));
        let dz = i64::from(hit.dz);
        for k in from..=end {
            index += walk.step[0];
            minor = minor.saturating_add(walk.minor_step[0]);
            aside = aside.saturating_add(hit.drift);
            z += dz;
            if dz >= 0 && z > self.highest {
                return Through::Sky;
            }
            let lowered = (k == from).then_some(lowered);
            let Some(below) = self.clearance(walk, at(index, minor, aside, z), lowered, probe)
            else {
                return Through::Sky;
            };
            if below <= 0 {
                return Through::Hit { k, above, below };
            }
            above = Some(below);
        }
        if end == walk.last {
            Through::Sky
        } else {
            Through::Lost
        }
    }

    /// The color and opacity where `hit`'s ray crosses the surface `t`/256
    /// of the way from sample `k − 1` to `k`, at height `elevation` (Q16):
    /// both grid lines' blended by the along weight (the hit's line's alone
    /// where `t` is 256), as a `SECONDARY` ray or the primary sees it.
    /// Where the crossing is less than opaque, its points less than opaque
    /// join `lowered`.
    #[inline(always)]
    fn shade_crossing<const SECONDARY: bool, P: Probe>(
        &self,
        walk: &LineWalk,
        hit: &NearHit,
        (k, t, elevation): (i32, u32, i32),
        lowered: &mut Lowered,
        probe: &mut P,
    ) -> (Rgb, u32) {
        let aside = Self::aside_at(walk, k, hit.drift);
        let on_hit =
            self.line_shade::<SECONDARY, _>(walk, hit, (k, aside, elevation), lowered, probe);
        if t >= 256 {
            if on_hit.alpha < 255 {
                Self::lower(walk, &on_hit, lowered);
            }
            return (on_hit.color, on_hit.alpha);
        }
        let before = self.line_shade::<SECONDARY, _>(
            walk,
            hit,
            (k - 1, aside - hit.drift, elevation),
            lowered,
            probe,
        );
        // Where an object stands on one grid line and not on the other, the
        // crossing is on its wall (`walk::along_weight`); a point lowered by
        // the rays before stands no more.
        let (grid, across) = (&self.grids[0], walk.across[0]);
        let stands = |line: &LineShade| {
            if !SECONDARY {
                return grid.stands(line.cell, across, elevation);
            }
            let (cell, (lowered0, lowered1)) = (line.cell, line.lowered);
            (!lowered0 && grid.stands(cell, 0, elevation))
                || (!lowered1 && grid.stands(cell + across, 0, elevation))
        };
        let t = match (stands(&before), stands(&on_hit)) {
            (false, true) => 256,
            (true, false) => 0,
            _ => t,
        };
        let (color, alpha) = mix(
            (before.color, before.alpha),
            (on_hit.color, on_hit.alpha),
            t,
        );
        // Only a crossing less than opaque lets a secondary ray on.
        if alpha < 255 {
            Self::lower(walk, &on_hit, lowered);
            Self::lower(walk, &before, lowered);
        }
        (color, alpha)
    }
}

/// The height (Q16) of `hit`'s ray at sample `k`.
fn ray_height(hit: &NearHit, k: i32) -> i64 {
    hit.z + i64::from(k - hit.k) * i64::from(hit.dz)
}

/// Two colors with their opacities (of 255) blended `t`/256 of the way
/// from the first to the second, the colors weighted by their opacities
/// (as premultiplied colors blend): a clear texel lends its color nothing
/// to what is seen through it. Inline where the opacities are equal
/// (most crossings: opaque), out of line where they differ.
#[inline(always)]
fn mix((c0, a0): (Rgb, u32), (c1, a1): (Rgb, u32), t: u32) -> (Rgb, u32) {
    let t = t.min(256);
    let alpha = blend(a0, a1, t);
    if a0 == a1 {
        return (lerp(c0, c1, t), alpha);
    }
    (mix_unequal((c0, a0), (c1, a1), t), alpha)
}

/// [`mix`]'s color where the opacities differ.
#[inline(never)]
fn mix_unequal((c0, a0): (Rgb, u32), (c1, a1): (Rgb, u32), t: u32) -> Rgb {
    let (w0, w1) = (a0 * (256 - t), a1 * t);
    if w0 + w1 == 0 {
        return lerp(c0, c1, t);
    }
    // The second color's share of what is opaque, of 256.
    let share = (w1 * 256 + (w0 + w1) / 2) / (w0 + w1);
    lerp(c0, c1, share)
}

/// `a` blended toward `b` by `t`/256, rounded.
fn blend(a: u32, b: u32, t: u32) -> u32 {
    let t = t.min(256);
    (a * (256 - t) + b * t + 128) >> 8
}

#[cfg(test)]
mod tests {
    use crate::{
        render, Camera, Framebuffer, NoProbe, Pyramid, RenderOptions, Rgb, Stick, StickLayer,
        Terrain, View, WithSticks,
    };
    use std::vec;
    use std::vec::Vec;

    const SIDE: u32 = 32;
    const GROUND: u16 = 2 << 4;
    const GRASS: Rgb = [40, 120, 40];
    const FRONT: Rgb = [250, 0, 0];
    const BACK: Rgb = [0, 0, 250];
    const TALL: u16 = 6 * 16;

    /// A flat map with a hedge two points thick across x = 20 and 21 (rows
    /// 4 to 27), six voxels tall: the front row's stick red at opacity
    /// `front` (texel alphas given, or none), the back row's blue; seen
    /// from x = 2, looking along x.
    fn hedge(alphas: Option<[u8; 2]>) -> Vec<Rgb> {
        hedge_from(Camera::looking([2.0, 16.0, 5.0], 0.0, 0.0), alphas)
    }

    /// [`hedge`], seen by `camera`.
    fn hedge_from(camera: Camera, alphas: Option<[u8; 2]>) -> Vec<Rgb> {
        hedge_in_order(camera, alphas, true)
    }

    /// [`hedge_from`], the front row's stick first in the stick table or
    /// (`front_first` false) second.
    fn hedge_in_order(camera: Camera, alphas: Option<[u8; 2]>, front_first: bool) -> Vec<Rgb> {
        let n = (SIDE * SIDE) as usize;
        // The ground under the hedge stays grass: what a ray that sees
        // through the front row meets at its foot.
        let (mut heights, colors, mut points) = (vec![GROUND; n], vec![GRASS; n], vec![0; n]);
        let (front, back) = if front_first { (1, 2) } else { (2, 1) };
        for y in 4..28 {
            for (x, stick) in [(20, front), (21, back)] {
                let i = y * SIDE as usize + x;
                heights[i] += TALL;
                points[i] = stick;
            }
        }
        let terrain = Terrain::new(SIDE, SIDE, &heights, &colors).unwrap();
        let sticks = [
            Stick {
                first: 0,
                texels: 1,
                height: TALL,
            },
            Stick {
                first: 1,
                texels: 1,
                height: TALL,
            },
        ];
        let (texels, opacities) = match (front_first, alphas.unwrap_or_default()) {
            (true, opacities) => ([FRONT, BACK], opacities),
            (false, [a, b]) => ([BACK, FRONT], [b, a]),
        };
        let layer = StickLayer::new(&terrain, &points, &sticks, &texels).unwrap();
        let layer = match alphas {
            Some(_) => layer.with_alphas(&opacities).unwrap(),
            None => layer,
        };
        let pyramid = Pyramid::flat(terrain);
        let view = View::new(&camera, 48, 36).unwrap();
        let mut pixels = vec![[0; 3]; 48 * 36];
        let mut frame = Framebuffer::new(&mut pixels, 48, 36).unwrap();
        let surface = WithSticks::new(&pyramid, layer);
        render(
            &surface,
            &view,
            &RenderOptions::default(),
            &mut frame,
            &mut NoProbe,
        );
        pixels
    }

    /// The middle column's pixels, bottom up.
    fn middle_column(pixels: &[Rgb]) -> Vec<Rgb> {
        (0..36).rev().map(|y| pixels[y * 48 + 24]).collect()
    }

    #[test]
    fn opaque_texels_render_as_without_opacities() {
        assert_eq!(hedge(Some([255, 255])), hedge(None));
    }

    #[test]
    fn the_stick_tables_order_does_not_change_the_image() {
        // Front first, every stick from the first complex one on: every
        // hit is shaded with its opacities. Back first (opaque before
        // complex, as `StickTable::with_alphas` asks), a hit on the back
        // row alone is shaded as an opaque one.
        for alphas in [[0, 255], [128, 255], [128, 64]] {
            for (eye, yaw, pitch) in [
                ([2.0, 16.0, 5.0], 0.0, 0.0),
                ([10.0, 2.0, 9.0], 35.0, -10.0),
                ([2.0, 9.0, 12.0], 20.0, -20.0),
            ] {
                let camera = Camera::looking(eye, yaw, pitch);
                assert_eq!(
                    hedge_in_order(camera, Some(alphas), true),
                    hedge_in_order(camera, Some(alphas), false),
                    "{alphas:?} {eye:?}"
                );
            }
        }
    }

    #[test]
    fn a_clear_front_row_shows_the_row_behind_it() {
        let opaque = middle_column(&hedge(None));
        assert!(opaque.contains(&FRONT), "{opaque:?}");
        assert!(!opaque.contains(&BACK), "{opaque:?}");
        let clear = middle_column(&hedge(Some([0, 255])));
        assert!(clear.contains(&BACK), "{clear:?}");
        // From any side, no pixel shows any of the clear row's red: a
        // point seen through is plain ground to the secondary rays, and a
        // clear texel lends its color nothing where it is blended with an
        // opaque one. (The grass, the blue row and the sky, blended in any
        // way, have less red than green.)
        for eye in [
            [2.0, 16.0, 5.0],
            [2.0, 9.0, 12.0],
            [10.0, 16.0, 20.0],
            [10.0, 2.0, 9.0],
        ] {
            for yaw in [0.0, 20.0, 35.0, -25.0] {
                for pitch in [0.0, -10.0, -20.0, -30.0, -45.0] {
                    let frame = hedge_from(Camera::looking(eye, yaw, pitch), Some([0, 255]));
                    let reddened = frame.iter().filter(|c| c[0] > c[1]).count();
                    assert_eq!(reddened, 0, "{eye:?} yaw {yaw} pitch {pitch}");
                }
            }
        }
    }

    #[test]
    fn a_half_clear_front_row_blends_with_the_row_behind_it() {
        let column = middle_column(&hedge(Some([128, 255])));
        let halves = column
            .iter()
            .filter(|c| (120..=135).contains(&c[0]) && (115..=130).contains(&c[2]))
            .count();
        assert!(halves >= 6, "{column:?}");
        assert!(
            !column.contains(&FRONT) && !column.contains(&BACK),
            "{column:?}"
        );
    }
}
