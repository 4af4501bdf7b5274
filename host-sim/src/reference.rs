//! The exact reference renderer, against which every accuracy figure is
//! measured: the first intersection of each ray with the bilinear surface
//! (solved analytically per cell), bilinear color at the hit, pixels
//! supersampled on a regular grid (box filter).
//!
//! Acceleration: a max-height mipmap over the cells. A ray skips a node
//! whenever it stays above the node's highest point over the node's extent,
//! climbs a level after a skip and descends where it cannot skip, so a ray
//! costs about log(n) node visits per empty stretch.

use crate::camera::{length, ContractCamera};
use crate::frame::{Frame, RenderStats};
use crate::scene::Scene;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;
use terracast::{Atmosphere, Camera, Rgb};

/// The exact renderer for one scene.
#[derive(Debug)]
pub struct Reference<'s> {
    scene: &'s Scene,
    /// `levels[l]` holds the highest height of each 2^l × 2^l block of cells.
    levels: Vec<MaxLevel>,
}

#[derive(Debug)]
struct MaxLevel {
    width: usize,
    depth: usize,
    max: Vec<f32>,
}

/// Where a ray first meets the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceHit {
    /// Ray parameter: the hit is at `origin + t·direction`.
    pub t: f64,
    /// World x and y of the hit.
    pub x: f64,
    /// World y of the hit.
    pub y: f64,
}

/// Settings of the reference.
#[derive(Debug, Clone, Copy)]
pub struct ReferenceOptions {
    /// Rays per pixel side: `n × n` rays a pixel.
    pub supersample: u32,
    /// Color of rays that miss.
    pub sky: Rgb,
    /// Sky, sun and fog, exact (`Atmosphere::exact`), over every ray's
    /// color; `sky` is unused with it.
    pub atmosphere: Option<Atmosphere>,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        Self {
            supersample: 4,
            sky: terracast::config::DEFAULT_SKY,
            atmosphere: None,
        }
    }
}

impl ReferenceOptions {
    /// How these options color a ray: their sky and atmosphere.
    pub fn coloring(&self) -> ReferenceColoring {
        ReferenceColoring {
            sky: self.sky,
            atmosphere: self.atmosphere,
        }
    }
}

/// How the reference colors a ray it has found the hit of (see
/// [`Reference::render_each`]): the part of [`ReferenceOptions`] that does
/// not change which rays are cast.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceColoring {
    /// Color of rays that miss.
    pub sky: Rgb,
    /// Sky, sun and fog, exact, over every ray's color; `sky` is unused
    /// with it.
    pub atmosphere: Option<Atmosphere>,
}

impl<'s> Reference<'s> {
    /// Builds the max-height mipmap.
    pub fn new(scene: &'s Scene) -> Self {
        let (cw, cd) = (scene.width as usize - 1, scene.depth as usize - 1);
        let mut base = Vec::with_capacity(cw * cd);
        for j in 0..cd {
            for i in 0..cw {
                let h = scene
                    .height(i, j)
                    .max(scene.height(i + 1, j))
                    .max(scene.height(i, j + 1))
                    .max(scene.height(i + 1, j + 1));
                base.push(h);
            }
        }
        let mut levels = vec![MaxLevel {
            width: cw,
            depth: cd,
            max: base,
        }];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.depth > 1) {
            let (w, d) = (last.width.div_ceil(2), last.depth.div_ceil(2));
            let mut max = vec![f32::MIN; w * d];
            for j in 0..last.depth {
                for i in 0..last.width {
                    let m = &mut max[(j / 2) * w + i / 2];
                    *m = m.max(last.max[j * last.width + i]);
                }
            }
            levels.push(MaxLevel {
                width: w,
                depth: d,
                max,
            });
        }
        Self { scene, levels }
    }

    /// The first point where the ray `origin + t·direction`, t ≥ 0, is at or
    /// below the bilinear surface inside the map; `None` if it never is.
    /// `visits` counts the mipmap nodes the search looked at.
    pub fn intersect(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        visits: &mut u64,
    ) -> Option<SurfaceHit> {
        self.intersect_past(origin, dir, (0.0, &[]), visits)
    }

    /// [`Reference::intersect`] from ray parameter `from` on, over the
    /// surface with the grid points in `lowered` at their ground (under
    /// their sticks): the ray a see-through texel lets on.
    fn intersect_past(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        (from, lowered): (f64, &[usize]),
        visits: &mut u64,
    ) -> Option<SurfaceHit> {
        let extent = [
            f64::from(self.scene.width - 1),
            f64::from(self.scene.depth - 1),
        ];
        let (mut t, mut t_end) = (from, f64::INFINITY);
        for axis in 0..2 {
            if dir[axis] == 0.0 {
                if origin[axis] < 0.0 || origin[axis] > extent[axis] {
                    return None;
                }
            } else {
                let a = (0.0 - origin[axis]) / dir[axis];
                let b = (extent[axis] - origin[axis]) / dir[axis];
                t = t.max(a.min(b));
                t_end = t_end.min(a.max(b));
            }
        }
        let top = self.levels.len() - 1;
        let mut level = top;
        while t <= t_end {
            *visits += 1;
            let node = &self.levels[level];
            let size = (1u64 << level) as f64;
            let index = |axis: usize, count: usize| {
                let q = (origin[axis] + t * dir[axis]) / size;
                let i = if dir[axis] < 0.0 {
                    q.ceil() - 1.0
                } else {
                    q.floor()
                };
                (i.max(0.0) as usize).min(count - 1)
            };
            let (nx, ny) = (index(0, node.width), index(1, node.depth));
            let exit_along = |axis: usize, n: usize| {
                let lo = n as f64 * size;
                let hi = (lo + size).min(extent[axis]);
                if dir[axis] > 0.0 {
                    (hi - origin[axis]) / dir[axis]
                } else if dir[axis] < 0.0 {
                    (lo - origin[axis]) / dir[axis]
                } else {
                    f64::INFINITY
                }
            };
            let t_exit = exit_along(0, nx).min(exit_along(1, ny)).min(t_end);
            let lowest = (origin[2] + t * dir[2]).min(origin[2] + t_exit * dir[2]);
            let step_past = |t_exit: f64| t_exit + 1e-9 * (1.0 + t_exit.abs());
            if lowest > f64::from(node.max[ny * node.width + nx]) {
                t = step_past(t_exit);
                level = (level + 1).min(top);
            } else if level > 0 {
                level -= 1;
            } else if let Some(hit) = self.cell_hit((nx, ny, lowered), origin, dir, t, t_exit) {
                return Some(hit);
            } else {
                t = step_past(t_exit);
                level = 1.min(top);
            }
        }
        None
    }

    /// Solves ray against the bilinear patch of cell (i, j) for t in [ta, tb]:
    /// along the ray the patch height is quadratic in t.
    fn cell_hit(
        &self,
        (i, j, lowered): (usize, usize, &[usize]),
        o: [f64; 3],
        d: [f64; 3],
        ta: f64,
        tb: f64,
    ) -> Option<SurfaceHit> {
        let s = self.scene;
        let height = |a: usize, b: usize| {
            let top = f64::from(s.height(a, b));
            let index = b * s.width as usize + a;
            match &s.objects {
                Some(objects) if lowered.contains(&index) => objects.ground(index, top),
                _ => top,
            }
        };
        let h00 = height(i, j);
        let h10 = height(i + 1, j);
        let h01 = height(i, j + 1);
        let h11 = height(i + 1, j + 1);
        let (b, c, dd) = (h10 - h00, h01 - h00, h00 - h10 - h01 + h11);
        let u0 = o[0] + ta * d[0] - i as f64;
        let v0 = o[1] + ta * d[1] - j as f64;
        let za = o[2] + ta * d[2];
        let qa = -dd * d[0] * d[1];
        let qb = d[2] - b * d[0] - c * d[1] - dd * (u0 * d[1] + v0 * d[0]);
        let qc = za - h00 - b * u0 - c * v0 - dd * u0 * v0;
        let span = tb - ta;
        let root = if qc <= 0.0 {
            Some(0.0)
        } else {
            smallest_root_in(qa, qb, qc, span)
        }?;
        let t = ta + root;
        Some(SurfaceHit {
            t,
            x: o[0] + t * d[0],
            y: o[1] + t * d[1],
        })
    }

    /// Bilinear color of the grid at world (x, y).
    pub fn color_at(&self, x: f64, y: f64) -> [f64; 3] {
        self.scene.color_at(x, y)
    }

    /// Renders a view: colors from `n × n` rays a pixel, depth from the ray
    /// through the pixel center. Uses every available core.
    pub fn render(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        options: &ReferenceOptions,
    ) -> (Frame, RenderStats) {
        let (mut frames, stats) = self.render_each(
            camera,
            width,
            height,
            options.supersample,
            &[options.coloring()],
        );
        (frames.remove(0), stats)
    }

    /// Renders a view once for each of `colorings` (`supersample` rays a
    /// pixel side for all), finding each
    /// ray's hit once for all of them: the frames are each
    /// [`Reference::render`]'s with that coloring, and the stats are one
    /// render's.
    pub fn render_each(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        supersample: u32,
        colorings: &[ReferenceColoring],
    ) -> (Vec<Frame>, RenderStats) {
        let rays = ContractCamera::new(camera, width, height);
        let n = supersample.max(1);
        let visits = AtomicU64::new(0);
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(height as usize);
        let started = Instant::now();
        // Each row: its index, its colors under each coloring, its depths.
        type Row = (u32, Vec<Vec<Rgb>>, Vec<f32>);
        let mut rows: Vec<Row> = std::thread::scope(|scope| {
            let workers: Vec<_> = (0..threads)
                .map(|worker| {
                    let visits = &visits;
                    scope.spawn(move || {
                        let mut done = Vec::new();
                        let mut count = 0u64;
                        for py in (worker as u32..height).step_by(threads) {
                            let mut colors =
                                vec![Vec::with_capacity(width as usize); colorings.len()];
                            let mut depths = Vec::with_capacity(width as usize);
                            for px in 0..width {
                                let mut sums = vec![[0.0f64; 3]; colorings.len()];
                                for sy in 0..n {
                                    for sx in 0..n {
                                        let dir = rays.direction(
                                            f64::from(px) + (f64::from(sx) + 0.5) / f64::from(n),
                                            f64::from(py) + (f64::from(sy) + 0.5) / f64::from(n),
                                        );
                                        let hit = self.intersect(rays.eye, dir, &mut count);
                                        for (sum, coloring) in sums.iter_mut().zip(colorings) {
                                            let c = self.ray_color(rays.eye, dir, hit, coloring);
                                            (0..3).for_each(|k| sum[k] += c[k]);
                                        }
                                    }
                                }
                                let samples = f64::from(n * n);
                                for (colors, sum) in colors.iter_mut().zip(&sums) {
                                    colors.push(
                                        sum.map(|s| (s / samples).round().clamp(0.0, 255.0) as u8),
                                    );
                                }
                                let center =
                                    rays.direction(f64::from(px) + 0.5, f64::from(py) + 0.5);
                                let depth = self
                                    .intersect(rays.eye, center, &mut count)
                                    .map_or(f32::INFINITY, |hit| (hit.t * length(center)) as f32);
                                depths.push(depth);
                            }
                            done.push((py, colors, depths));
                        }
                        visits.fetch_add(count, Ordering::Relaxed);
                        done
                    })
                })
                .collect();
            workers
                .into_iter()
                .flat_map(|w| w.join().expect("reference worker"))
                .collect()
        });
        let render_ns = started.elapsed().as_nanos() as u64;
        rows.sort_by_key(|r| r.0);
        let mut frames = vec![Frame::new(width, height); colorings.len()];
        for (py, colors, depths) in rows {
            let at = py as usize * width as usize;
            for (frame, colors) in frames.iter_mut().zip(colors) {
                frame.colors[at..at + width as usize].copy_from_slice(&colors);
                frame.depth[at..at + width as usize].copy_from_slice(&depths);
            }
        }
        let pixels = u64::from(width) * u64::from(height);
        let stats = RenderStats {
            method: "reference",
            pixels,
            rays: pixels * u64::from(n * n + 1),
            steps: visits.into_inner(),
            resident_bytes: (self.scene.heights.len() * 4
                + self.scene.colors.len() * 3
                + self.levels.iter().map(|l| l.max.len() * 4).sum::<usize>())
                as u64,
            render_ns,
            levels: None,
        };
        (frames, stats)
    }

    /// What a ray from `eye` along `dir` that meets the
    /// surface at `hit` (or nowhere) shows under `coloring`'s sky and
    /// atmosphere.
    fn ray_color(
        &self,
        eye: [f64; 3],
        dir: [f64; 3],
        hit: Option<SurfaceHit>,
        coloring: &ReferenceColoring,
    ) -> [f64; 3] {
        let eye_z = eye[2];
        let sky = coloring.sky.map(f64::from);
        let hit_color = |hit: SurfaceHit| self.seen_through(eye, dir, hit, sky);
        match &coloring.atmosphere {
            None => hit.map_or(sky, hit_color),
            Some(air) => {
                let at = hit.map(|hit| (hit.t * length(dir), eye_z + hit.t * dir[2]));
                air.exact(dir, eye_z, at, hit.map_or([0.0; 3], hit_color))
            }
        }
    }

    /// The color a ray from `eye` along `dir` sees at
    /// `hit`: where the texels there are less than opaque, composited in
    /// order with what the ray meets through them (the points it saw
    /// through lowered to their ground), up to [`SEE_THROUGH_LAYERS`]
    /// layers; `sky` where it meets nothing more.
    fn seen_through(
        &self,
        eye: [f64; 3],
        dir: [f64; 3],
        hit: SurfaceHit,
        sky: [f64; 3],
    ) -> [f64; 3] {
        let mut layers = Vec::new();
        let mut lowered = Vec::new();
        let mut at = Some(hit);
        let mut behind = sky;
        while let Some(hit) = at {
            let z = eye[2] + hit.t * dir[2];
            let (color, alpha, clear) = self.scene.seen_at_height(hit.x, hit.y, z, &lowered);
            if alpha >= 1.0 || layers.len() == SEE_THROUGH_LAYERS {
                behind = color;
                break;
            }
            layers.push((color, alpha));
            lowered.extend(clear);
            at = self.intersect_past(eye, dir, (hit.t, &lowered), &mut 0);
        }
        layers.iter().rev().fold(behind, |behind, (color, alpha)| {
            std::array::from_fn(|k| color[k] * alpha + behind[k] * (1.0 - alpha))
        })
    }
}

/// Layers of see-through texels the reference composites a ray through
/// (more than the kernel's [`terracast::MAX_SEE_THROUGH`] secondary rays:
/// the reference's is the exact picture).
pub const SEE_THROUGH_LAYERS: usize = 8;

/// The smallest root of `a·s² + b·s + c` in `[0, span]`, given `c > 0`.
fn smallest_root_in(a: f64, b: f64, c: f64, span: f64) -> Option<f64> {
    let scale = a.abs().max(b.abs()).max(c.abs());
    let in_span = |s: f64| (0.0..=span).contains(&s).then_some(s);
    if a.abs() <= 1e-12 * scale {
        return if b < 0.0 { in_span(-c / b) } else { None };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let (r1, r2) = (q / a, if q != 0.0 { c / q } else { f64::INFINITY });
    let (lo, hi) = (r1.min(r2), r1.max(r2));
    in_span(lo).or_else(|| in_span(hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smallest_root_picks_the_first_crossing() {
        // (s-1)(s-3) = s² - 4s + 3
        assert_eq!(smallest_root_in(1.0, -4.0, 3.0, 10.0), Some(1.0));
        assert_eq!(smallest_root_in(1.0, -4.0, 3.0, 0.5), None);
        assert_eq!(smallest_root_in(0.0, -2.0, 1.0, 1.0), Some(0.5));
        assert_eq!(smallest_root_in(1.0, 0.0, 1.0, 10.0), None);
    }

    /// The center pixel of a view along x, from x = 2 at height 5, of
    /// [`hedge_seen_by`]'s hedge.
    fn through_a_hedge(front: u8) -> Rgb {
        let camera = Camera::looking([2.0, 16.0, 5.0], 0.0, 0.0);
        hedge_seen_by(camera, 9, front)[4 * 9 + 4]
    }

    /// A `side` × `side` view by `camera` of a flat map with a hedge two
    /// points thick across x = 20 and 21 (rows 4 to 27), six voxels tall
    /// on ground two high: the front row red at opacity `front`, the back
    /// row blue and opaque, grass under both.
    fn hedge_seen_by(camera: Camera, side: u32, front: u8) -> Vec<Rgb> {
        const SIDE: u32 = 32;
        let n = (SIDE * SIDE) as usize;
        let grass = [40, 120, 40];
        let mut scene = Scene::new(SIDE, SIDE, vec![2.0; n], vec![grass; n]).unwrap();
        let mut objects = crate::objects::Objects::empty(n);
        objects.sticks = (0..2)
            .map(|first| terracast::Stick {
                first,
                texels: 1,
                height: 6 * 16,
            })
            .collect();
        objects.texels = vec![[250, 0, 0], [0, 0, 250]];
        objects.alphas = vec![front, u8::MAX];
        for y in 4..28 {
            for (x, stick) in [(20, 1), (21, 2)] {
                let i = y * SIDE as usize + x;
                objects.points[i] = stick;
                scene.heights[i] += 6.0;
            }
        }
        scene.objects = Some(objects);
        let reference = Reference::new(&scene);
        let options = ReferenceOptions {
            supersample: 1,
            ..ReferenceOptions::default()
        };
        reference.render(&camera, side, side, &options).0.colors
    }

    #[test]
    fn texels_seen_through_blend_by_their_opacity_with_what_is_behind() {
        assert_eq!(through_a_hedge(u8::MAX), [250, 0, 0]);
        // Clear: the blue row behind, and none of the red in front.
        assert_eq!(through_a_hedge(0), [0, 0, 250]);
        let half = through_a_hedge(128);
        assert!(
            (124..=127).contains(&half[0]) && half[1] == 0 && (123..=126).contains(&half[2]),
            "{half:?}"
        );
        // From any side, a clear row shows none of its red: its points are
        // plain ground to the rays through it, and a clear texel lends its
        // color nothing where it is blended with an opaque one. (The grass,
        // the blue row and the sky, blended in any way, have less red than
        // green.)
        for eye in [[2.0, 9.0, 12.0], [10.0, 16.0, 20.0], [10.0, 2.0, 9.0]] {
            for (yaw, pitch) in [(0.0, -10.0), (20.0, 0.0), (35.0, -20.0), (-25.0, -30.0)] {
                let frame = hedge_seen_by(Camera::looking(eye, yaw, pitch), 32, 0);
                let reddened = frame.iter().filter(|c| c[0] > c[1]).count();
                assert_eq!(reddened, 0, "{eye:?} yaw {yaw} pitch {pitch}");
            }
        }
    }

    #[test]
    fn one_pass_for_several_colorings_renders_each_as_alone() {
        let scene = crate::scene::procedural(64, 2);
        let reference = Reference::new(&scene);
        let camera = Camera::looking([8.0, 8.0, scene.max_height() + 6.0], 45.0, 4.0);
        let clear = ReferenceOptions {
            supersample: 2,
            sky: [10, 20, 30],
            ..ReferenceOptions::default()
        };
        let hazy = ReferenceOptions {
            atmosphere: Some(Atmosphere::FLIGHT),
            ..clear
        };
        let (frames, _) =
            reference.render_each(&camera, 24, 16, 2, &[clear.coloring(), hazy.coloring()]);
        assert_eq!(frames.len(), 2);
        assert_ne!(frames[0].colors, frames[1].colors);
        for (frame, options) in frames.iter().zip([clear, hazy]) {
            let (alone, _) = reference.render(&camera, 24, 16, &options);
            assert_eq!(frame, &alone);
        }
    }
}
