//! Which tiles a frame needs: the projection of the image frame on the
//! terrain, level by level (Cohen-Or §3.2), and the window of the world the
//! caster addresses.
//!
//! A level-`l` tile is needed where the caster can read it: its heights and
//! colors where rays step on level `l` or blend with it, and its bounds
//! wherever the first hit may test them, which is anywhere nearer than
//! where level `l + 1` ends, since the colors of level `l + 1` are blended
//! with those of level `l` there. So the footprint of level `l` is the
//! view's frustum (widened by `widen_deg` each side for prefetch), cut by
//! the slab of terrain heights, out to a depth of `D₁·2^(l+1)` (`D₁` the
//! depth where level 1 begins: focal length in pixels over the
//! pixel-to-voxel ratio), with a margin of two level-`l` cells and an
//! eighth of the depth.
//! The top level reaches to the window's edge. On a world with real edges
//! (one that fits the window), level 0 also covers the edges in view: a
//! ray leaving the map tests its last sample there on level 0. Rays too
//! steep to double
//! their step stay on low levels at any depth: under the eye, each level
//! also covers the cone of those rays. A tile is tested as the box
//! of its cells (one cell wider each side, for the cells across tile
//! edges) against the frustum's planes: conservative, never missing a
//! tile a ray reads. Float math, once a frame.

use super::cache::ceiling_tiles;
use super::{PhotoKey, TileKey, World};
use crate::detail::DetailArea;
use crate::view::Camera;
use glam::DVec3;
use heapless::Vec;

/// Points per side of the window of the world a [`super::TiledSurface`]
/// addresses: `2^14 + 1`, so every level's row fits a power-of-two stride.
pub const WINDOW_SIDE: u32 = (1 << 14) + 1;

/// Highest level of a window placed inside a larger world: the window's
/// origin is a multiple of `2^WINDOW_TOP` so its levels line up with the
/// world's. The eye sits within `2^(WINDOW_TOP − 1)` of the window's
/// center, so a view reaches at least 7680 voxels each way.
pub const WINDOW_TOP: u8 = 10;

/// The window's origin (level-0 world point) for an eye at `eye`, and its
/// highest level. A world that fits the window is its own window, with all
/// its levels.
pub fn window_origin(world: &World, eye: [f32; 3]) -> ([u32; 2], u8) {
    let fits = world.width <= WINDOW_SIDE && world.depth <= WINDOW_SIDE;
    if fits {
        return ([0, 0], world.levels() - 1);
    }
    let align = 1u32 << WINDOW_TOP;
    let place = |eye: f32, side: u32| -> u32 {
        if side <= WINDOW_SIDE {
            return 0;
        }
        let centered = f64::from(eye) - f64::from(WINDOW_SIDE / 2);
        let aligned = libm::floor(centered / f64::from(align) + 0.5) * f64::from(align);
        let last = f64::from((side - WINDOW_SIDE) / align * align);
        // NaN clamps to 0 too.
        aligned.clamp(0.0, last) as u32
    };
    let origin = [place(eye[0], world.width), place(eye[1], world.depth)];
    (origin, WINDOW_TOP.min(world.levels() - 1))
}

/// The footprint did not fit the list it was collected in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FootprintFull;

impl core::fmt::Display for FootprintFull {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("footprint has more tiles than its list holds")
    }
}

impl core::error::Error for FootprintFull {}

/// The frame a footprint is made for.
#[derive(Debug, Clone, Copy)]
pub struct FootprintView {
    /// The camera, in world coordinates.
    pub camera: Camera,
    /// Image size in pixels.
    pub width: u32,
    /// Image size in pixels.
    pub height: u32,
    /// The level bias the frame renders at: its pixel-to-voxel ratio as
    /// the caster uses it ([`crate::RenderOptions::level_bias`], which
    /// takes the terrain fit in).
    pub pixel_to_voxel: f32,
    /// Degrees added to each side of the field of view: 0 for the frame
    /// itself, more for an extended footprint to prefetch.
    pub widen_deg: f32,
}

/// Appends to `out` the tiles (of side `T`) `view` needs; sorted, without
/// duplicates (with what `out` held before). Returns the window's highest
/// level. [`FootprintFull`] when `out` ran out of room (it then holds a
/// part of the footprint).
pub fn footprint<const T: usize, const F: usize>(
    world: &World,
    view: &FootprintView,
    out: &mut Vec<TileKey, F>,
) -> Result<u8, FootprintFull> {
    footprint_under::<T, F>(world, view, &|_| None, out)
}

/// [`footprint`], with each tile's box only as high as `ceiling` says the
/// terrain there is (U12.4; `None`: the world's highest height). With
/// [`super::TileCache::ceiling`], the coarser tiles already resident cut
/// the finer levels' footprint down to the terrain the view can see.
pub fn footprint_under<const T: usize, const F: usize>(
    world: &World,
    view: &FootprintView,
    ceiling: &dyn Fn(TileKey) -> Option<u16>,
    out: &mut Vec<TileKey, F>,
) -> Result<u8, FootprintFull> {
    let camera = &view.camera;
    let (origin, top) = window_origin(world, camera.eye);
    let Frustum {
        eye,
        forward,
        planes,
        level1,
        top_z,
        corner,
    } = Frustum::of(view, world);
    let window = [
        origin[0],
        origin[1],
        origin[0] + WINDOW_SIDE.min(world.width - origin[0]),
        origin[1] + WINDOW_SIDE.min(world.depth - origin[1]),
    ];
    let mut full = false;
    for level in 0..=top {
        let cell = f64::from(1u32 << level);
        let far = if level == top {
            f64::INFINITY
        } else {
            // Level `l` is stepped on out to `D₁·2^l` and blended with
            // level `l + 1`'s colors out to twice that.
            level1 * cell * 2.0 * 1.125 + 2.0 * cell
        };
        // Rays steeper than 2^(12 − l) (height per major-axis step) never
        // double past level l (their height increment would overflow), so
        // level l is read at any depth inside the cone of those rays
        // under the eye: horizontal radius below Δz·√2·2^(l − 12).
        let cone = libm::fabs(eye.z) * 1.5 * libm::exp2(f64::from(level) - 12.0) + 2.0 * cell;
        let reach = (far * corner).max(cone);
        // Level points of the window, then tiles, within reach of the eye.
        let lo = |e: f64, w: u32| -> u32 {
            let v = ((e - reach) / cell).max(f64::from(w >> level)).max(0.0);
            (v as u32) / T as u32
        };
        let hi = |e: f64, w: u32, size: u32| -> u32 {
            let last_point = (w.div_ceil(1 << level)).min(size - 1);
            let v = ((e + reach) / cell + 1.0)
                .min(f64::from(last_point))
                .max(0.0);
            (v as u32) / T as u32
        };
        let (size_x, size_y) = world.level_size(level);
        let (x0, x1) = (lo(eye.x, window[0]), hi(eye.x, window[2], size_x));
        let (y0, y1) = (lo(eye.y, window[1]), hi(eye.y, window[3], size_y));
        for ty in y0..=y1 {
            for tx in x0..=x1 {
                let span = T as f64 * cell;
                let bx = [f64::from(tx) * span - cell, f64::from(tx + 1) * span + cell];
                let by = [f64::from(ty) * span - cell, f64::from(ty + 1) * span + cell];
                let near_nadir = {
                    let dx = (bx[0] - eye.x).max(eye.x - bx[1]).max(0.0);
                    let dy = (by[0] - eye.y).max(eye.y - by[1]).max(0.0);
                    libm::sqrt(dx * dx + dy * dy) <= cone
                };
                let depth_limit = if near_nadir { f64::INFINITY } else { far };
                let key = TileKey {
                    level,
                    x: tx,
                    y: ty,
                };
                let in_view = |top: f64| {
                    box_in_frustum(eye, forward, &planes, depth_limit, bx, by, [0.0, top])
                };
                if !in_view(top_z) {
                    continue;
                }
                let roof = ceiling(key);
                // A footprint holds the tiles its cut relies on (whether
                // the cut keeps this tile or not), so that the next
                // frame's is cut the same way.
                if roof.is_some() {
                    for parent in ceiling_tiles::<T>(world, key) {
                        if out.push(parent).is_err() {
                            full = true;
                        }
                    }
                }
                if roof.is_some_and(|c| !in_view(f64::from(c) / 16.0)) {
                    continue;
                }
                if out.push(key).is_err() {
                    full = true;
                }
            }
        }
    }
    // A world that fits the window has real edges: rays leaving it test
    // their last sample on level 0 there, at any distance.
    if world.width <= WINDOW_SIDE && world.depth <= WINDOW_SIDE {
        let t = T as u32;
        let (w, d) = (world.width, world.depth);
        let (tiles_x, tiles_y) = world.tiles(0, t);
        let edge_columns = [0, 1.min(w - 1) / t, (w - 2) / t, (w - 1) / t];
        let edge_rows = [0, 1.min(d - 1) / t, (d - 2) / t, (d - 1) / t];
        for ty in 0..tiles_y {
            for tx in 0..tiles_x {
                if !(edge_columns.contains(&tx) || edge_rows.contains(&ty)) {
                    continue;
                }
                let span = f64::from(t);
                let bx = [f64::from(tx) * span - 1.0, f64::from(tx + 1) * span + 1.0];
                let by = [f64::from(ty) * span - 1.0, f64::from(ty + 1) * span + 1.0];
                let in_view =
                    box_in_frustum(eye, forward, &planes, f64::INFINITY, bx, by, [0.0, top_z]);
                if in_view
                    && out
                        .push(TileKey {
                            level: 0,
                            x: tx,
                            y: ty,
                        })
                        .is_err()
                {
                    full = true;
                }
            }
        }
    }
    sort_and_dedup(out, full).map(|()| top)
}

/// A frame's frustum as the footprints test tiles against it.
struct Frustum {
    eye: DVec3,
    forward: DVec3,
    /// Inside where every normal's dot with (point − eye) is >= 0.
    planes: Vec<DVec3, 4>,
    /// The depth where level 1 begins (and colors reach level 1, or
    /// farther: the terrain fit only moves the heights' farther).
    level1: f64,
    /// The world's highest height, voxels.
    top_z: f64,
    /// A point at depth d in the frustum is at most `d·corner` from the eye.
    corner: f64,
}

impl Frustum {
    fn of(view: &FootprintView, world: &World) -> Self {
        let FootprintView {
            camera,
            width,
            height,
            pixel_to_voxel,
            widen_deg,
        } = *view;
        let [forward, right, up] = camera.axes();
        let eye = DVec3::new(
            f64::from(camera.eye[0]),
            f64::from(camera.eye[1]),
            f64::from(camera.eye[2]),
        );
        let half = f64::from(camera.hfov_deg).to_radians() / 2.0;
        let tan_v = libm::tan(half) * f64::from(height.max(1)) / f64::from(width.max(1));
        let widened = half + f64::from(widen_deg.max(0.0)).to_radians();
        let mut planes: Vec<DVec3, 4> = Vec::new();
        let tan_h = if widened < core::f64::consts::FRAC_PI_2 - 1e-6 {
            let tan_h = libm::tan(widened);
            let _ = planes.push(forward * tan_h - right);
            let _ = planes.push(forward * tan_h + right);
            tan_h
        } else {
            f64::INFINITY
        };
        let _ = planes.push(forward * tan_v - up);
        let _ = planes.push(forward * tan_v + up);
        let focal = f64::from(width.max(1)) / (2.0 * libm::tan(half));
        Self {
            eye,
            forward,
            planes,
            level1: focal / f64::from(pixel_to_voxel).max(1.0 / 256.0),
            top_z: f64::from(world.max_height) / 16.0,
            corner: libm::sqrt(1.0 + tan_h * tan_h + tan_v * tan_v),
        }
    }

    /// Whether the box `bx × by`, from the ground to the highest height,
    /// may meet the frustum no deeper than `far`.
    fn holds(&self, far: f64, bx: [f64; 2], by: [f64; 2]) -> bool {
        box_in_frustum(
            self.eye,
            self.forward,
            &self.planes,
            far,
            bx,
            by,
            [0.0, self.top_z],
        )
    }
}

/// Appends to `out` the photo tiles (of side `T`) of the photos over
/// `areas` (a source's [`super::TileSource::photos`], in world
/// coordinates) that `view` needs; sorted, without duplicates (with what
/// `out` held before). Of each photo's fine level, the tiles in the
/// frustum nearer than the depth to which the level is read
/// ([`DetailArea::reaches`], from the depth where colors reach level 1),
/// with the margin the pyramid's levels get; and, at any depth, those
/// within twice that of the eye horizontally, and no farther than the
/// eye is high: a steep ray's footprint is narrower than its depth (the
/// clearances change by its own slope), so under the eye a fine level is
/// read out to about its reach from the nadir, however high the eye, by
/// rays that drop more than they run. A hit on a surface steeper than its ray
/// reads a fine level farther out still (a cliff's footprint is narrower
/// on the map than its depth): there a missing tile reads the next
/// coarser fine level, and is counted as a degraded sample.
pub fn photo_footprint<const T: usize, const F: usize>(
    world: &World,
    areas: &[DetailArea],
    view: &FootprintView,
    out: &mut Vec<PhotoKey, F>,
) -> Result<(), FootprintFull> {
    let frustum = Frustum::of(view, world);
    let eye = frustum.eye;
    let mut full = false;
    for (photo, area) in areas.iter().enumerate().take(usize::from(u8::MAX) + 1) {
        for level in 0..=area.shift() {
            // Texels a voxel on this level; texel i's center lies at
            // world `origin − ½ + (i + ½)/scale`.
            let scale = f64::from(1u32 << (area.shift() - level));
            let far = area.reaches(level, frustum.level1) * 1.125 + 2.0;
            let nadir = (2.0 * far).min(eye.z.max(0.0));
            let reach = (far * frustum.corner).max(nadir);
            let (w, d) = area.level_size(level);
            let origin = area.origin().map(|o| f64::from(o) - 0.5);
            // Tiles whose texels lie within reach of the eye, each way.
            let span = |e: f64, o: f64, n: usize| -> Option<(u32, u32)> {
                let lo = ((e - reach - o) * scale - 1.0).max(0.0);
                let hi = ((e + reach - o) * scale + 1.0).min(n as f64 - 1.0);
                (lo <= hi).then(|| (lo as u32 / T as u32, hi as u32 / T as u32))
            };
            let (Some((x0, x1)), Some((y0, y1))) =
                (span(eye.x, origin[0], w), span(eye.y, origin[1], d))
            else {
                continue;
            };
            let side = T as f64 / scale;
            for ty in y0..=y1 {
                for tx in x0..=x1 {
                    // The tile's texels and one more each side (a color
                    // blends a texel with its neighbour).
                    let bx = [
                        origin[0] + f64::from(tx) * side - 1.0 / scale,
                        origin[0] + f64::from(tx + 1) * side + 1.0 / scale,
                    ];
                    let by = [
                        origin[1] + f64::from(ty) * side - 1.0 / scale,
                        origin[1] + f64::from(ty + 1) * side + 1.0 / scale,
                    ];
                    let (dx, dy) = (
                        (bx[0] - eye.x).max(eye.x - bx[1]).max(0.0),
                        (by[0] - eye.y).max(eye.y - by[1]).max(0.0),
                    );
                    let depth_limit = if libm::sqrt(dx * dx + dy * dy) <= nadir {
                        f64::INFINITY
                    } else {
                        far
                    };
                    if !frustum.holds(depth_limit, bx, by) {
                        continue;
                    }
                    let key = PhotoKey {
                        photo: photo as u8,
                        level: level as u8,
                        x: tx,
                        y: ty,
                    };
                    if out.push(key).is_err() {
                        full = true;
                    }
                }
            }
        }
    }
    sort_and_dedup(out, full)
}

/// Sorts `keys` and drops repeats; [`FootprintFull`] when some did not
/// fit (`full`).
fn sort_and_dedup<K: Ord + Copy, const F: usize>(
    keys: &mut Vec<K, F>,
    full: bool,
) -> Result<(), FootprintFull> {
    keys.sort_unstable();
    let mut kept = 0;
    for i in 0..keys.len() {
        if kept == 0 || keys[i] != keys[kept - 1] {
            keys[kept] = keys[i];
            kept += 1;
        }
    }
    keys.truncate(kept);
    if full {
        Err(FootprintFull)
    } else {
        Ok(())
    }
}

/// Whether the box `bx × by × bz` may meet the frustum of planes `planes`
/// through `eye`, no deeper than `far` along `forward`.
fn box_in_frustum(
    eye: DVec3,
    forward: DVec3,
    planes: &[DVec3],
    far: f64,
    bx: [f64; 2],
    by: [f64; 2],
    bz: [f64; 2],
) -> bool {
    let corners = || (0..8).map(move |i| DVec3::new(bx[i & 1], by[(i >> 1) & 1], bz[i >> 2]) - eye);
    // Nearer than `far` somewhere, in front of the eye somewhere.
    let nearest = corners()
        .map(|c| c.dot(forward))
        .fold(f64::INFINITY, f64::min);
    if nearest > far {
        return false;
    }
    planes.iter().all(|n| corners().any(|c| c.dot(*n) >= 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(camera: Camera, widen_deg: f32) -> FootprintView {
        FootprintView {
            camera,
            width: 320,
            height: 240,
            pixel_to_voxel: 1.0,
            widen_deg,
        }
    }

    fn world(side: u32) -> World {
        World::new(side, side, 200 * 16).unwrap()
    }

    #[test]
    fn a_world_that_fits_is_its_own_window() {
        let w = world(1024);
        assert_eq!(window_origin(&w, [500.0, 20.0, 90.0]), ([0, 0], 10));
    }

    #[test]
    fn a_large_world_gets_an_aligned_window_around_the_eye() {
        let w = world(131_072);
        for eye in [9000.0f32, 40_000.5, 65_536.0, 131_000.0, -50.0] {
            let ([ox, oy], top) = window_origin(&w, [eye, eye, 100.0]);
            assert_eq!(top, WINDOW_TOP);
            assert_eq!((ox % 1024, ox), (0, oy));
            assert!(ox + WINDOW_SIDE <= 131_072);
            let inside = eye.clamp(0.0, 131_071.0) - ox as f32;
            let far_enough = (7680.0..=8704.0).contains(&inside);
            let at_an_edge = ox == 0 || ox == (131_072 - WINDOW_SIDE) / 1024 * 1024;
            assert!(far_enough || at_an_edge, "{eye}: origin {ox}");
        }
    }

    #[test]
    fn the_footprint_is_in_front_of_the_eye_and_coarsens_with_distance() {
        let w = world(8192);
        let camera = Camera::looking([4000.0, 4000.0, 300.0], 0.0, 10.0);
        let mut keys = Vec::<TileKey, 4096>::new();
        let top = footprint::<64, 4096>(&w, &frame(camera, 0.0), &mut keys).unwrap();
        assert_eq!(top, 13);
        // Level 0 tiles lie ahead (+x) of the eye, near it, but for the far
        // edge of the map in view (the world fits a window: real edges).
        let (near, edge): (std::vec::Vec<&TileKey>, std::vec::Vec<&TileKey>) = keys
            .iter()
            .filter(|k| k.level == 0)
            .partition(|k| k.x < 127 && k.y > 0 && k.y < 127);
        assert!(edge.iter().any(|k| k.x == 127 && k.y == 4000 / 64));
        assert!(edge.iter().all(|k| k.x == 127), "{edge:?}");
        let level0 = near;
        assert!(!level0.is_empty());
        for k in &level0 {
            assert!(k.x * 64 + 64 >= 3990, "{k:?} behind the eye");
            assert!(k.x * 64 <= 4000 + 800, "{k:?} too far for level 0");
        }
        // Every level has some tiles, and fewer than a thousand.
        for level in 0..=top {
            let n = keys.iter().filter(|k| k.level == level).count();
            assert!((1..1000).contains(&n), "level {level}: {n}");
        }
        // Sorted and without duplicates.
        assert!(keys.windows(2).all(|p| p[0] < p[1]));
        // Widening only adds tiles.
        let mut wide = Vec::<TileKey, 4096>::new();
        footprint::<64, 4096>(&w, &frame(camera, 30.0), &mut wide).unwrap();
        assert!(keys.iter().all(|k| wide.contains(k)) && wide.len() > keys.len());
        // A list too short says so.
        let mut short = Vec::<TileKey, 8>::new();
        assert_eq!(
            footprint::<64, 8>(&w, &frame(camera, 0.0), &mut short),
            Err(FootprintFull)
        );
    }
}
